/// The marks wagashi's writers put near the start of a file: the comment line of
/// TetGen files and Gmsh's `$Comments` section (`written by wagashi`), the XML
/// comment of VTU files (`written by wagashi-io`), the version key of JSON reports.
const MARKS: [&str; 2] = ["written by wagashi", "\"wagashi_version\""];

/// How far into a file the marks are looked for [bytes].
const HEAD_BYTES: u64 = 4096;

/// Whether the regular file at `path` is one wagashi wrote (it carries one of
/// wagashi's marks in its first 4 KiB): such a file may be replaced by a later
/// run; any other existing file needs the user's `--force`. A link, a folder or
/// an unreadable file is not wagashi's.
pub fn written_by_wagashi(path: &std::path::Path) -> bool {
    use std::io::Read;
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return false;
    };
    if !meta.file_type().is_file() {
        return false;
    }
    let mut head = Vec::new();
    let read = std::fs::File::open(path).and_then(|f| f.take(HEAD_BYTES).read_to_end(&mut head));
    if read.is_err() {
        return false;
    }
    let text = String::from_utf8_lossy(&head);
    MARKS.iter().any(|m| text.contains(m))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_files_with_a_mark_are_wagashis() {
        let dir = tempfile::tempdir().unwrap();
        let file = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            p
        };
        assert!(written_by_wagashi(&file("a.node", "# written by wagashi: points [mm]\n3 3 0 0\n")));
        assert!(written_by_wagashi(&file("r.json", "{\n  \"wagashi_version\": \"0.1.0\"\n}\n")));
        assert!(!written_by_wagashi(&file("b.node", "# my own mesh\n3 3 0 0\n")));
        assert!(!written_by_wagashi(&dir.path().join("missing.node")));
        assert!(!written_by_wagashi(dir.path()));
    }
}
