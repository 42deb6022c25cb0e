//! Atomic outputs: a reader never sees a half-written file or folder.
//!
//! - [`write_atomic`]: a file is written to a temporary file in the same folder,
//!   flushed to disk, then renamed over the target (a rename within one file
//!   system is atomic).
//! - [`AtomicDir`]: an output folder is built as a hidden sibling temporary folder
//!   `.NAME.tmp-PID-*` and put in place by [`AtomicDir::commit`], which writes its
//!   manifest ([`MANIFEST_FILE`]: the files wagashi wrote); dropped without a
//!   commit, the temporary folder is removed, and one a killed run left is
//!   removed by the next run on the same target ([`remove_stale_temporaries`],
//!   which also removes the temporary files of a killed [`write_atomic`]). An existing target is replaced
//!   only when it is empty or is a previous wagashi output holding only the files
//!   its manifest lists ([`is_previous_output`]); only those files are removed, and
//!   links are never followed.
//! - [`written_by_wagashi`]: whether an existing file carries a wagashi writer's
//!   mark, and so may be replaced without the user's `--force`.
//! - [`remove_pending_for_exit`]: what an interrupt handler calls to remove the
//!   temporaries of this process before it exits.

mod atomic_dir;
mod manifest;
mod pending;
mod write_atomic;
mod written_by;

pub use atomic_dir::{is_previous_output, remove_stale_temporaries, AtomicDir, OUTPUT_MARKER_FILE};
pub use manifest::{Manifest, MANIFEST_FILE, MANIFEST_FORMAT};
pub use pending::remove_pending_for_exit;
pub use write_atomic::write_atomic;
pub use written_by::written_by_wagashi;
