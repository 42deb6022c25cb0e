use std::path::{Path, PathBuf};

use crate::error::WriteError;

/// The file whose presence marks a folder as a previous wagashi output.
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
/// # Ok(()) }
/// ```
#[derive(Debug)]
pub struct AtomicDir {
    target: PathBuf,
    /// The temporary folder; `None` once committed.
    temp: Option<PathBuf>,
}

/// Whether `target` may be replaced: absent, an empty folder, or a folder holding
/// [`OUTPUT_MARKER_FILE`].
fn check_replaceable(target: &Path) -> Result<(), WriteError> {
    let meta = match std::fs::symlink_metadata(target) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(WriteError::io(target, e)),
    };
    let refuse = || WriteError::RefuseOverwrite { dir: target.to_path_buf() };
    if !meta.is_dir() {
        return Err(refuse());
    }
    let mut entries = std::fs::read_dir(target).map_err(|e| WriteError::io(target, e))?;
    if entries.next().is_none() || target.join(OUTPUT_MARKER_FILE).is_file() {
        Ok(())
    } else {
        Err(refuse())
    }
}

fn parent_of(target: &Path) -> &Path {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

impl AtomicDir {
    /// Starts building `target`: checks that it may be replaced, creates its
    /// parent folders, and creates a hidden temporary sibling to write into.
    pub fn new(target: impl AsRef<Path>) -> Result<Self, WriteError> {
        let target = target.as_ref().to_path_buf();
        check_replaceable(&target)?;
        let parent = parent_of(&target);
        std::fs::create_dir_all(parent).map_err(|e| WriteError::io(parent, e))?;
        let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
        let temp = tempfile::Builder::new()
            .prefix(&format!(".{name}.tmp-"))
            .tempdir_in(parent)
            .map_err(|e| WriteError::io(&target, e))?
            .keep();
        Ok(Self { target, temp: Some(temp) })
    }

    /// The folder to write into (the temporary one until the commit).
    pub fn path(&self) -> &Path {
        self.temp.as_deref().unwrap_or(&self.target)
    }

    /// The folder this will become.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Renames the temporary folder into place, replacing an empty or previous
    /// wagashi output folder; returns the target.
    pub fn commit(mut self) -> Result<PathBuf, WriteError> {
        let Some(temp) = self.temp.clone() else {
            return Ok(self.target.clone());
        };
        check_replaceable(&self.target)?;
        let io = |e: std::io::Error| WriteError::io(&self.target, e);
        if std::fs::symlink_metadata(&self.target).is_ok() {
            // Move the old output aside first, so the rename below never meets it;
            // put it back if that rename fails.
            let aside = tempfile::Builder::new()
                .prefix(&format!(".{}.old-", self.target.file_name().unwrap_or_default().to_string_lossy()))
                .tempdir_in(parent_of(&self.target))
                .map_err(io)?
                .keep();
            std::fs::remove_dir(&aside).map_err(io)?;
            std::fs::rename(&self.target, &aside).map_err(io)?;
            if let Err(e) = std::fs::rename(&temp, &self.target) {
                let _ = std::fs::rename(&aside, &self.target);
                return Err(io(e));
            }
            self.temp = None;
            // The new output is in place; the old one is removed as well as can be
            // (a leftover hidden `.NAME.old-*` folder is harmless).
            let _ = std::fs::remove_dir_all(&aside);
        } else {
            std::fs::rename(&temp, &self.target).map_err(io)?;
            self.temp = None;
        }
        Ok(self.target.clone())
    }
}

impl Drop for AtomicDir {
    fn drop(&mut self) {
        if let Some(temp) = self.temp.take() {
            let _ = std::fs::remove_dir_all(temp);
        }
    }
}
