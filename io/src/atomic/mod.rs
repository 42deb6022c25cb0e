//! Atomic outputs: a reader never sees a half-written file or folder.
//!
//! - [`write_atomic`]: a file is written to a temporary file in the same folder,
//!   flushed to disk, then renamed over the target (a rename within one file
//!   system is atomic).
//! - [`AtomicDir`]: an output folder is built as a hidden sibling temporary folder
//!   and renamed into place by [`AtomicDir::commit`]; dropped without a commit, the
//!   temporary folder is removed. An existing target is replaced only when it is
//!   empty or holds a `summary.json` (a previous wagashi output).

mod atomic_dir;
mod write_atomic;

pub use atomic_dir::{AtomicDir, OUTPUT_MARKER_FILE};
pub use write_atomic::write_atomic;
