//! AtomicDir: built aside, renamed into place on commit, removed when dropped.

use std::path::Path;

use wagashi_io::{write_atomic, AtomicDir, WriteError};

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn commit_moves_the_folder_into_place() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("deep/out");
    let out = AtomicDir::new(&target).unwrap();
    assert_ne!(out.path(), target.as_path());
    assert_eq!(out.path().parent(), target.parent());
    write_atomic(out.path().join("summary.json"), b"{}").unwrap();
    assert!(!target.exists());
    assert_eq!(out.commit().unwrap(), target);
    assert_eq!(entries(&target), vec!["summary.json"]);
    // No temporary folder is left beside it.
    assert_eq!(entries(&root.path().join("deep")), vec!["out"]);
}

#[test]
fn drop_without_commit_removes_the_temporary_folder() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("out");
    {
        let out = AtomicDir::new(&target).unwrap();
        write_atomic(out.path().join("a.csv"), b"x").unwrap();
        assert!(out.path().exists());
    }
    assert!(!target.exists());
    assert!(entries(root.path()).is_empty());
}

#[test]
fn refuses_to_overwrite_a_folder_that_is_not_a_wagashi_output() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("photos");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("holiday.jpg"), b"precious").unwrap();
    let err = AtomicDir::new(&target).unwrap_err();
    assert!(matches!(err, WriteError::RefuseOverwrite { .. }));
    assert_eq!(
        err.to_string(),
        format!("refusing to overwrite {}: it exists and is not a wagashi output", target.display())
    );
    assert_eq!(std::fs::read(target.join("holiday.jpg")).unwrap(), b"precious");
    assert_eq!(entries(root.path()), vec!["photos"]);
}

#[test]
fn refuses_a_folder_that_became_foreign_before_the_commit() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("out");
    let out = AtomicDir::new(&target).unwrap();
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("notes.txt"), b"mine").unwrap();
    assert!(matches!(out.commit(), Err(WriteError::RefuseOverwrite { .. })));
    assert_eq!(entries(&target), vec!["notes.txt"]);
    assert_eq!(entries(root.path()), vec!["out"]);
}

#[test]
fn refuses_to_replace_a_file() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("out");
    std::fs::write(&target, b"a file").unwrap();
    assert!(matches!(AtomicDir::new(&target), Err(WriteError::RefuseOverwrite { .. })));
}

#[test]
fn replaces_a_previous_output_and_an_empty_folder() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("out");
    std::fs::create_dir(&target).unwrap();
    // Empty: replaced.
    let out = AtomicDir::new(&target).unwrap();
    write_atomic(out.path().join("summary.json"), b"1").unwrap();
    write_atomic(out.path().join("old.csv"), b"old").unwrap();
    out.commit().unwrap();
    // A previous output (has summary.json): replaced whole, old files gone.
    let out = AtomicDir::new(&target).unwrap();
    write_atomic(out.path().join("summary.json"), b"2").unwrap();
    out.commit().unwrap();
    assert_eq!(entries(&target), vec!["summary.json"]);
    assert_eq!(std::fs::read(target.join("summary.json")).unwrap(), b"2");
    assert_eq!(entries(root.path()), vec!["out"]);
}
