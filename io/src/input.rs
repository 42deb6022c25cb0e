//! Reading input files: regular files only, and no larger than
//! [`MAX_INPUT_BYTES`].
//!
//! Every reader of the crate (bundles, CSV series, materials, surfaces and
//! their glTF buffers, TetGen and Gmsh meshes, texture-analyser exports, VTU
//! shapes) reads through [`read`] or [`read_to_string`], so that a name that
//! leads to a device (`/dev/zero`), a FIFO or a folder is refused before it is
//! opened, and a file too large to be an input is refused instead of filling
//! the memory. The refusals are `std::io::Error`s (kind `InvalidInput`) whose
//! text says why; each reader puts the file's name in front, as for any other
//! read error (`force.csv: cannot read: not a regular file (a character device)`).
//!
//! [`inside`] tells whether a name given in an input (a bundle's data file, a
//! glTF buffer's URI) stays inside the input's folder.

use std::io::{self, Read};
use std::path::{Component, Path};

/// The largest input file the readers take: 2 GiB (a surface scan of tens of
/// millions of triangles, a day of 1 kHz texture-analyser rows).
pub const MAX_INPUT_BYTES: u64 = 2 << 30;

/// The content of the regular file `path` (symlinks followed), at most
/// [`MAX_INPUT_BYTES`] long.
pub fn read(path: impl AsRef<Path>) -> io::Result<Vec<u8>> {
    read_capped(path.as_ref(), MAX_INPUT_BYTES)
}

/// [`read`] as UTF-8 text.
pub fn read_to_string(path: impl AsRef<Path>) -> io::Result<String> {
    String::from_utf8(read(path)?).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        io::Error::new(io::ErrorKind::InvalidData, format!("line {line}: not valid UTF-8 text"))
    })
}

/// [`read`] with the limit `max_bytes`.
pub(crate) fn read_capped(path: &Path, max_bytes: u64) -> io::Result<Vec<u8>> {
    // Judged before opening: opening a FIFO blocks until someone writes to it.
    regular(&std::fs::metadata(path)?)?;
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    regular(&meta)?;
    let too_large = |size: u64| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{size} bytes or more, larger than the {max_bytes} bytes an input file may have"),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // One byte more than allowed tells a file that grew (or reports size 0, as
    // /proc's do) past the limit.
    file.take(max_bytes + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

/// Whether the file `name`, relative to the folder `dir`, lies inside it: `name`
/// is not absolute, no `..` of it climbs above `dir`, and, when the file
/// exists, its canonical path (symlinks followed) is inside the canonical
/// `dir`. A file that does not exist is judged by its name alone.
pub(crate) fn inside(dir: &Path, name: &str) -> bool {
    let relative = Path::new(name);
    let mut depth = 0usize;
    for c in relative.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => return false,
            Component::CurDir => {}
            Component::ParentDir => match depth.checked_sub(1) {
                Some(d) => depth = d,
                None => return false,
            },
            Component::Normal(_) => depth += 1,
        }
    }
    match (dir.canonicalize(), dir.join(relative).canonicalize()) {
        (Ok(folder), Ok(file)) => file.starts_with(folder),
        // Not there (or the folder is not): the name alone decides.
        _ => true,
    }
}

/// `Ok` for a regular file; otherwise the refusal, naming what it is.
fn regular(meta: &std::fs::Metadata) -> io::Result<()> {
    let kind = meta.file_type();
    if kind.is_file() {
        return Ok(());
    }
    let what = if kind.is_dir() {
        "a folder"
    } else {
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if kind.is_fifo() {
                "a FIFO"
            } else if kind.is_char_device() {
                "a character device"
            } else if kind.is_block_device() {
                "a block device"
            } else if kind.is_socket() {
                "a socket"
            } else {
                "a special file"
            }
        }
        #[cfg(not(unix))]
        {
            "a special file"
        }
    };
    Err(io::Error::new(io::ErrorKind::InvalidInput, format!("not a regular file ({what})")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_files_are_read_up_to_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        std::fs::write(&path, "one\ntwo\n").unwrap();
        assert_eq!(read(&path).unwrap(), b"one\ntwo\n");
        assert_eq!(read_to_string(&path).unwrap(), "one\ntwo\n");
        assert_eq!(read_capped(&path, 8).unwrap().len(), 8);
        let err = read_capped(&path, 7).unwrap_err();
        assert_eq!(err.to_string(), "8 bytes or more, larger than the 7 bytes an input file may have");
        std::fs::write(&path, b"ok\n\xff\n").unwrap();
        assert_eq!(read_to_string(&path).unwrap_err().to_string(), "line 2: not valid UTF-8 text");
        let err = read(dir.path()).unwrap_err();
        assert_eq!(err.to_string(), "not a regular file (a folder)");
    }

    #[cfg(unix)]
    #[test]
    fn devices_and_fifos_are_refused_without_reading() {
        let err = read("/dev/zero").unwrap_err();
        assert_eq!(err.to_string(), "not a regular file (a character device)");
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            // Would block forever if it were opened.
            assert_eq!(read(&fifo).unwrap_err().to_string(), "not a regular file (a FIFO)");
        }
        // /proc files say size 0 and hold more: the limit still holds.
        if Path::new("/proc/self/status").is_file() {
            assert!(read_capped(Path::new("/proc/self/status"), 4).is_err());
        }
    }
}
