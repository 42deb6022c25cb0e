//! The manifest of an output folder: the file that tells a folder wagashi wrote
//! from any other, and which of its files wagashi may remove.
//!
//! `wagashi-manifest.json` holds a format key and the files the output holds,
//! relative to the folder, `/`-separated, sorted:
//!
//! ```json
//! {"format": "wagashi-output/1", "files": ["force.csv", "shapes/shape-0000.vtu", "summary.json"]}
//! ```
//!
//! [`crate::AtomicDir`] writes it into every folder it commits. A folder is a
//! previous wagashi output only when it holds this file as a regular file (a
//! symbolic link is not trusted) with this format key; replacing it removes the
//! listed files and nothing else, never following a symbolic link.

use std::path::{Component, Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::WriteError;

/// The manifest's file name in an output folder.
pub const MANIFEST_FILE: &str = "wagashi-manifest.json";

/// The manifest's format key.
pub const MANIFEST_FORMAT: &str = "wagashi-output/1";

/// The largest manifest read [bytes] (a real one lists a few thousand names).
const MAX_MANIFEST_BYTES: u64 = 16 << 20;

/// What `wagashi-manifest.json` holds.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// [`MANIFEST_FORMAT`].
    pub format: String,
    /// The files written, relative to the folder, `/`-separated (the manifest
    /// itself not included).
    pub files: Vec<String>,
}

impl Manifest {
    /// The manifest of the files under `dir` (regular files and links, not
    /// followed; the manifest itself left out), sorted.
    pub fn of_folder(dir: &Path) -> Result<Self, WriteError> {
        let mut files = Vec::new();
        walk(dir, dir, &mut files)?;
        files.retain(|f| f != MANIFEST_FILE);
        files.sort();
        Ok(Self { format: MANIFEST_FORMAT.to_string(), files })
    }

    /// The manifest of the folder `dir`: `None` when it holds no manifest that
    /// wagashi wrote (absent, a link, not a regular file, too large, not JSON, another
    /// format key, or a listed name that leaves the folder).
    pub fn read(dir: &Path) -> Option<Self> {
        let path = dir.join(MANIFEST_FILE);
        let meta = std::fs::symlink_metadata(&path).ok()?;
        if !meta.file_type().is_file() || meta.len() > MAX_MANIFEST_BYTES {
            return None;
        }
        let text = std::fs::read_to_string(&path).ok()?;
        let mut manifest: Manifest = serde_json::from_str(&text).ok()?;
        manifest.files.sort();
        (manifest.format == MANIFEST_FORMAT && manifest.files.iter().all(|f| is_plain_relative(f))).then_some(manifest)
    }

    /// Writes the manifest into `dir` (a folder not yet visible: a plain write).
    pub(crate) fn write(&self, dir: &Path) -> Result<(), WriteError> {
        let path = dir.join(MANIFEST_FILE);
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| WriteError::BadInput { path: path.clone(), cause: e.to_string() })?;
        std::fs::write(&path, text + "\n").map_err(|e| WriteError::io(&path, e))
    }

    /// The first entry under `dir` (relative, `/`-separated) that is neither
    /// listed, nor the manifest, nor a folder holding only listed entries;
    /// `None` when `dir` holds only what wagashi wrote.
    pub fn first_unlisted(&self, dir: &Path) -> Result<Option<String>, WriteError> {
        let mut found = Vec::new();
        walk(dir, dir, &mut found)?;
        Ok(found.into_iter().find(|f| f != MANIFEST_FILE && self.files.binary_search(f).is_err()))
    }

    /// Removes the listed files and the manifest from `dir`, then the folders
    /// left empty, `dir` last. Links are removed, never followed; anything not
    /// listed stays (and keeps its folders). Returns whether `dir` is gone.
    pub fn remove_listed(&self, dir: &Path) -> Result<bool, WriteError> {
        for name in self.files.iter().map(String::as_str).chain([MANIFEST_FILE]) {
            if !is_plain_relative(name) {
                continue;
            }
            let path = dir.join(name);
            match std::fs::symlink_metadata(&path) {
                Ok(meta) if !meta.is_dir() => std::fs::remove_file(&path).map_err(|e| WriteError::io(&path, e))?,
                _ => {}
            }
        }
        remove_empty_folders(dir)
    }
}

/// Whether `name` is a relative path that stays inside its folder: no root, no
/// `..`, not empty.
fn is_plain_relative(name: &str) -> bool {
    let path = Path::new(name);
    !name.is_empty() && path.components().all(|c| matches!(c, Component::Normal(_)))
}

/// The files (anything but a real folder) under `dir`, relative to `root`,
/// `/`-separated; links are listed, not followed.
fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) -> Result<(), WriteError> {
    for entry in std::fs::read_dir(dir).map_err(|e| WriteError::io(dir, e))? {
        let entry = entry.map_err(|e| WriteError::io(dir, e))?;
        let path = entry.path();
        let kind = entry.file_type().map_err(|e| WriteError::io(&path, e))?;
        if kind.is_dir() {
            walk(root, &path, out)?;
        } else {
            out.push(relative_name(root, &path));
        }
    }
    Ok(())
}

fn relative_name(root: &Path, path: &Path) -> String {
    let relative: PathBuf = path.strip_prefix(root).unwrap_or(path).to_path_buf();
    relative.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/")
}

/// Removes the empty folders under `dir` (real folders only), deepest first,
/// then `dir` itself when it is empty; returns whether `dir` is gone.
fn remove_empty_folders(dir: &Path) -> Result<bool, WriteError> {
    let mut empty = true;
    for entry in std::fs::read_dir(dir).map_err(|e| WriteError::io(dir, e))? {
        let entry = entry.map_err(|e| WriteError::io(dir, e))?;
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if !(is_dir && remove_empty_folders(&entry.path())?) {
            empty = false;
        }
    }
    if empty {
        std::fs::remove_dir(dir).map_err(|e| WriteError::io(dir, e))?;
    }
    Ok(empty)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listed_names_stay_inside_the_folder() {
        assert!(is_plain_relative("a.csv"));
        assert!(is_plain_relative("shapes/shape-0000.vtu"));
        for bad in ["", "/etc/passwd", "../x", "a/../../x", "./a"] {
            assert!(!is_plain_relative(bad), "{bad}");
        }
    }

    #[test]
    fn a_manifest_round_trips_and_lists_nested_files() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("shapes")).unwrap();
        std::fs::write(dir.path().join("shapes/a.vtu"), b"x").unwrap();
        std::fs::write(dir.path().join("b.csv"), b"x").unwrap();
        let m = Manifest::of_folder(dir.path()).unwrap();
        assert_eq!(m.files, vec!["b.csv", "shapes/a.vtu"]);
        m.write(dir.path()).unwrap();
        assert_eq!(Manifest::read(dir.path()), Some(m.clone()));
        assert_eq!(m.first_unlisted(dir.path()).unwrap(), None);
        std::fs::write(dir.path().join("shapes/mine.txt"), b"x").unwrap();
        assert_eq!(m.first_unlisted(dir.path()).unwrap().as_deref(), Some("shapes/mine.txt"));
        // Removal keeps what is not listed, and its folder.
        assert!(!m.remove_listed(dir.path()).unwrap());
        assert!(dir.path().join("shapes/mine.txt").is_file());
        assert!(!dir.path().join("b.csv").exists());
    }

    #[test]
    fn another_format_or_an_escaping_name_is_no_manifest() {
        let dir = tempfile::tempdir().unwrap();
        let write = |text: &str| std::fs::write(dir.path().join(MANIFEST_FILE), text).unwrap();
        write(r#"{"format": "something-else", "files": []}"#);
        assert_eq!(Manifest::read(dir.path()), None);
        write(r#"{"format": "wagashi-output/1", "files": ["../victim.txt"]}"#);
        assert_eq!(Manifest::read(dir.path()), None);
        write(r#"{"format": "wagashi-output/1", "files": ["a"]}"#);
        assert!(Manifest::read(dir.path()).is_some());
    }
}
