use std::path::{Path, PathBuf};

use super::manifest::Manifest;
use super::pending;
use crate::error::WriteError;

/// The file that commands write last into an output folder (its summary).
pub const OUTPUT_MARKER_FILE: &str = "summary.json";

/// An output folder built aside and renamed into place on [`commit`](Self::commit).
///
/// ```
/// # fn main() -> Result<(), wagashi_io::WriteError> {
/// # let root = tempfile::tempdir().unwrap();
/// let target = root.path().join("out");
/// let out = wagashi_io::AtomicDir::new(&target)?;
/// wagashi_io::write_atomic(out.path().join("summary.json"), b"{}")?;
/// assert!(!target.exists()); // nothing is visible before the commit
/// out.commit()?;
/// assert!(target.join("summary.json").exists());
/// assert!(target.join(wagashi_io::atomic::MANIFEST_FILE).exists());
/// # Ok(()) }
/// ```
#[derive(Debug)]
pub struct AtomicDir {
    target: PathBuf,
    /// The temporary folder; `None` once committed.
    temp: Option<PathBuf>,
    /// Temporary folders of interrupted runs on the same target, removed by [`AtomicDir::new`].
    stale_removed: Vec<PathBuf>,
}

/// Whether `target` holds a previous wagashi output: a real folder (not a link)
/// holding a manifest wagashi wrote ([`MANIFEST_FILE`]).
pub fn is_previous_output(target: &Path) -> bool {
    std::fs::symlink_metadata(target).is_ok_and(|m| m.is_dir()) && Manifest::read(target).is_some()
}

/// What replacing `target` takes: `Ok(None)` when it is absent or an empty
/// folder, `Ok(Some(manifest))` for a previous wagashi output all of whose
/// entries its manifest lists; any other file, link or folder is refused.
fn check_replaceable(target: &Path) -> Result<Option<Manifest>, WriteError> {
    let meta = match std::fs::symlink_metadata(target) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(WriteError::io(target, e)),
    };
    let refuse = || WriteError::RefuseOverwrite { dir: target.to_path_buf() };
    if !meta.is_dir() {
        return Err(refuse());
    }
    let mut entries = std::fs::read_dir(target).map_err(|e| WriteError::io(target, e))?;
    if entries.next().is_none() {
        return Ok(None);
    }
    let manifest = Manifest::read(target).ok_or_else(refuse)?;
    if let Some(entry) = manifest.first_unlisted(target)? {
        return Err(WriteError::RefuseUnlisted { dir: target.to_path_buf(), entry });
    }
    Ok(Some(manifest))
}

fn parent_of(target: &Path) -> &Path {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

fn name_of(target: &Path) -> String {
    target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into())
}

/// The prefix of this process's hidden siblings of `target` (`kind`: `tmp` or
/// `old`): `.NAME.KIND-PID-`, so that a later run can tell a dead run's from a
/// live one's.
fn sibling_prefix(target: &Path, kind: &str) -> String {
    format!(".{}.{kind}-{}-", name_of(target), std::process::id())
}

/// Removes the hidden temporaries `.NAME.tmp-PID-*` and `.NAME.old-PID-*`
/// beside `target` whose process PID no longer runs (killed runs): the
/// folders of [`AtomicDir`] and the files of [`super::write_atomic`] (regular
/// files only; a link is left alone). Returns what it removed. Where running
/// processes cannot be listed (no `/proc`), nothing is removed.
pub fn remove_stale_temporaries(target: &Path) -> Vec<PathBuf> {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return Vec::new();
    }
    let Ok(entries) = std::fs::read_dir(parent_of(target)) else {
        return Vec::new();
    };
    let name = name_of(target);
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let file_name = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = [".tmp-", ".old-"].iter().find_map(|kind| file_name.strip_prefix(&format!(".{name}{kind}")))
        else {
            continue;
        };
        let Some(pid) = rest.split_once('-').and_then(|(pid, _)| pid.parse::<u32>().ok()) else {
            continue;
        };
        if proc.join(pid.to_string()).exists() {
            continue;
        }
        let gone = match entry.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(entry.path()).is_ok(),
            Ok(t) if t.is_file() => std::fs::remove_file(entry.path()).is_ok(),
            _ => false,
        };
        if gone {
            removed.push(entry.path());
        }
    }
    removed
}

/// Swaps the folders `a` and `b` in one step (Linux `renameat2` with
/// `RENAME_EXCHANGE`); `Ok(false)` where the system or the file system cannot.
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<bool> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    let c = |p: &Path| CString::new(p.as_os_str().as_bytes()).map_err(std::io::Error::other);
    let (a, b) = (c(a)?, c(b)?);
    // SAFETY: both paths are NUL-terminated strings that outlive the call; the
    // system call reads them and touches no memory of ours.
    let rc = unsafe {
        libc::syscall(
            libc::SYS_renameat2,
            libc::AT_FDCWD,
            a.as_ptr(),
            libc::AT_FDCWD,
            b.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if rc == 0 {
        return Ok(true);
    }
    let err = std::io::Error::last_os_error();
    match err.raw_os_error() {
        Some(libc::ENOSYS | libc::EINVAL | libc::ENOTSUP) => Ok(false),
        _ => Err(err),
    }
}

#[cfg(not(target_os = "linux"))]
fn exchange(_a: &Path, _b: &Path) -> std::io::Result<bool> {
    Ok(false)
}

impl AtomicDir {
    /// Starts building `target`: checks that it may be replaced (absent, an
    /// empty folder, or a previous wagashi output holding only the files its
    /// manifest lists), creates its parent folders, removes the temporary
    /// folders that killed runs left beside it ([`stale_removed`](Self::stale_removed)),
    /// and creates a hidden temporary sibling to write into.
    pub fn new(target: impl AsRef<Path>) -> Result<Self, WriteError> {
        let target = target.as_ref().to_path_buf();
        check_replaceable(&target)?;
        let parent = parent_of(&target);
        std::fs::create_dir_all(parent).map_err(|e| WriteError::io(parent, e))?;
        let stale_removed = remove_stale_temporaries(&target);
        let temp = {
            let mut registry = pending::lock();
            let temp = tempfile::Builder::new()
                .prefix(&sibling_prefix(&target, "tmp"))
                .tempdir_in(parent)
                .map_err(|e| WriteError::io(&target, e))?
                .keep();
            registry.push(temp.clone());
            temp
        };
        Ok(Self { target, temp: Some(temp), stale_removed })
    }

    /// The folder to write into (the temporary one until the commit).
    pub fn path(&self) -> &Path {
        self.temp.as_deref().unwrap_or(&self.target)
    }

    /// The folder this will become.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The temporary folders of interrupted runs on the same target that
    /// [`new`](Self::new) removed.
    pub fn stale_removed(&self) -> &[PathBuf] {
        &self.stale_removed
    }

    /// Writes the manifest of what the temporary folder holds and puts the
    /// folder in place: swapped with a previous output in one step where the
    /// system can (else the old output moved aside first and put back if the
    /// move fails), whose listed files are then removed and nothing else.
    /// Returns the target.
    pub fn commit(mut self) -> Result<PathBuf, WriteError> {
        let Some(temp) = self.temp.clone() else {
            return Ok(self.target.clone());
        };
        Manifest::of_folder(&temp)?.write(&temp)?;
        // No interrupt handler removes anything while the folders move.
        let mut registry = pending::lock();
        let old = check_replaceable(&self.target)?;
        let io = |e: std::io::Error| WriteError::io(&self.target, e);
        let exists = std::fs::symlink_metadata(&self.target).is_ok();
        let previous = if !exists {
            std::fs::rename(&temp, &self.target).map_err(io)?;
            None
        } else if exchange(&temp, &self.target).map_err(io)? {
            // The old output now sits in the temporary folder.
            Some(temp.clone())
        } else {
            let aside = parent_of(&self.target).join(format!(
                "{}{}",
                sibling_prefix(&self.target, "old"),
                temp.file_name().unwrap_or_default().to_string_lossy().rsplit('-').next().unwrap_or("x")
            ));
            std::fs::rename(&self.target, &aside).map_err(io)?;
            if let Err(e) = std::fs::rename(&temp, &self.target) {
                let _ = std::fs::rename(&aside, &self.target);
                return Err(io(e));
            }
            Some(aside)
        };
        registry.retain(|p| p != &temp);
        self.temp = None;
        drop(registry);
        if let Some(previous) = previous {
            let gone = match &old {
                Some(manifest) => manifest.remove_listed(&previous)?,
                // An empty folder.
                None => std::fs::remove_dir(&previous).is_ok(),
            };
            if !gone {
                // Something not listed appeared while the run went on: keep it,
                // beside the target, under a name no later run removes.
                let kept =
                    parent_of(&self.target).join(format!(".{}.kept-{}", name_of(&self.target), std::process::id()));
                let _ = std::fs::rename(&previous, kept);
            }
        }
        Ok(self.target.clone())
    }
}

impl Drop for AtomicDir {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            let mut registry = pending::lock();
            let _ = std::fs::remove_dir_all(&temp);
            registry.retain(|p| p != &temp);
        }
    }
}
