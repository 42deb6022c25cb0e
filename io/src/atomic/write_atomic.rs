use std::io::Write;
use std::path::Path;

use crate::error::WriteError;

/// Writes `bytes` to `path` atomically: into a temporary file in the same folder
/// (`.NAME.tmp-PID-*`, so that the next run can tell a killed run's from a live
/// one's: [`super::remove_stale_temporaries`]), synced, then renamed over `path`.
/// The folder must exist. The file gets the mode any new file gets (`0666` less
/// the umask: normally `0644`), not the owner-only mode of a temporary file.
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), WriteError> {
    let path = path.as_ref();
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let io = |e: std::io::Error| WriteError::io(path, e);
    let prefix = format!(".{name}.tmp-{}-", std::process::id());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = {
        let mut registry = super::pending::lock();
        let tmp = builder.tempfile_in(parent).map_err(io)?;
        registry.push(tmp.path().to_path_buf());
        tmp
    };
    let temp_path = tmp.path().to_path_buf();
    let written = (|| {
        tmp.write_all(bytes).map_err(io)?;
        tmp.as_file().sync_all().map_err(io)?;
        tmp.persist(path).map_err(|e| io(e.error))?;
        Ok(())
    })();
    super::pending::lock().retain(|p| p != &temp_path);
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        write_atomic(&path, b"one").unwrap();
        write_atomic(&path, b"two").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.txt")]);
    }

    /// Outputs are for colleagues too: the mode of any new file (0666 less the
    /// umask), as `std::fs::write` gives it, not a temporary file's 0600.
    #[cfg(unix)]
    #[test]
    fn files_get_the_umasks_mode() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        std::fs::write(dir.path().join("plain.txt"), b"x").unwrap();
        write_atomic(dir.path().join("a.txt"), b"x").unwrap();
        assert_eq!(mode(&dir.path().join("a.txt")), mode(&dir.path().join("plain.txt")));
    }

    #[test]
    fn a_missing_folder_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no/such/a.txt");
        let err = write_atomic(&path, b"x").unwrap_err();
        assert!(err.to_string().contains("no/such/a.txt: cannot write"), "{err}");
    }
}
