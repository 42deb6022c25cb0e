//! The temporary files and folders this process is writing, for an interrupt
//! handler to remove before the process exits.
//!
//! [`crate::AtomicDir`] and [`crate::write_atomic`] register their temporaries
//! here while they exist; [`crate::AtomicDir::commit`] holds the lock while it
//! moves folders, so a handler never removes a folder half moved.

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The registry (a panic elsewhere while it was held leaves it usable).
pub(crate) fn lock() -> MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// For an interrupt handler about to exit the process: waits for a folder move
/// in progress to finish, removes every temporary file and folder this process
/// is writing, and keeps the registry locked so that nothing is committed or
/// created afterwards. Returns what was removed. Call it only right before
/// exiting: every later write of an output blocks.
pub fn remove_pending_for_exit() -> Vec<PathBuf> {
    let registry = lock();
    let removed = registry.clone();
    for path in removed.iter() {
        // A writer may add a file while the folder is removed: try again a few times.
        for _ in 0..5 {
            let gone = match std::fs::symlink_metadata(path) {
                Err(_) => true,
                Ok(m) if m.is_dir() => std::fs::remove_dir_all(path).is_ok(),
                Ok(_) => std::fs::remove_file(path).is_ok(),
            };
            if gone {
                break;
            }
        }
    }
    std::mem::forget(registry);
    removed
}
