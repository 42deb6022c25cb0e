//! AtomicDir: built aside, renamed into place on commit, removed when dropped;
//! a previous output is replaced only through its manifest.

use std::path::Path;

use wagashi_io::atomic::{is_previous_output, MANIFEST_FILE};
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
    assert_eq!(entries(&target), vec!["summary.json", MANIFEST_FILE]);
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(target.join(MANIFEST_FILE)).unwrap()).unwrap();
    assert_eq!(manifest, serde_json::json!({"format": "wagashi-output/1", "files": ["summary.json"]}));
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
        format!(
            "refusing to overwrite {}: it exists and is not a wagashi output (no wagashi manifest)",
            target.display()
        )
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
    // A previous output (its manifest lists every file): replaced whole, old files gone.
    assert!(is_previous_output(&target));
    let out = AtomicDir::new(&target).unwrap();
    write_atomic(out.path().join("summary.json"), b"2").unwrap();
    out.commit().unwrap();
    assert_eq!(entries(&target), vec!["summary.json", MANIFEST_FILE]);
    assert_eq!(std::fs::read(target.join("summary.json")).unwrap(), b"2");
    assert_eq!(entries(root.path()), vec!["out"]);
}

/// A folder that merely holds a `summary.json`, or a manifest that is a link,
/// is not a wagashi output: refused, untouched.
#[test]
fn a_summary_or_a_linked_manifest_is_not_trusted() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("out");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("summary.json"), b"{}").unwrap();
    std::fs::write(target.join("data.csv"), b"mine").unwrap();
    assert!(!is_previous_output(&target));
    assert!(matches!(AtomicDir::new(&target), Err(WriteError::RefuseOverwrite { .. })));
    #[cfg(unix)]
    {
        let real = root.path().join("elsewhere.json");
        std::fs::write(&real, br#"{"format": "wagashi-output/1", "files": ["data.csv", "summary.json"]}"#).unwrap();
        std::os::unix::fs::symlink(&real, target.join(MANIFEST_FILE)).unwrap();
        assert!(!is_previous_output(&target));
        assert!(matches!(AtomicDir::new(&target), Err(WriteError::RefuseOverwrite { .. })));
    }
    assert_eq!(std::fs::read(target.join("data.csv")).unwrap(), b"mine");
}

/// A file the user put into a previous output is not the manifest's: the
/// replacement is refused, naming it, and nothing is removed.
#[test]
fn an_unlisted_file_in_a_previous_output_is_kept_and_refused() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("out");
    let out = AtomicDir::new(&target).unwrap();
    write_atomic(out.path().join("summary.json"), b"1").unwrap();
    out.commit().unwrap();
    std::fs::write(target.join("notes.txt"), b"mine").unwrap();
    let err = AtomicDir::new(&target).unwrap_err();
    assert!(matches!(err, WriteError::RefuseUnlisted { ref entry, .. } if entry == "notes.txt"), "{err}");
    assert!(err.to_string().contains("notes.txt is not a file wagashi wrote"), "{err}");
    assert_eq!(entries(&target), vec!["notes.txt", "summary.json", MANIFEST_FILE]);
    assert_eq!(entries(root.path()), vec!["out"]);
}

/// Replacing an output removes a link it holds, never what the link points to.
#[cfg(unix)]
#[test]
fn replacing_never_follows_a_link() {
    let root = tempfile::tempdir().unwrap();
    let victim = root.path().join("victim");
    std::fs::create_dir(&victim).unwrap();
    std::fs::write(victim.join("keep.txt"), b"precious").unwrap();
    let target = root.path().join("out");
    let out = AtomicDir::new(&target).unwrap();
    std::os::unix::fs::symlink(&victim, out.path().join("shapes")).unwrap();
    write_atomic(out.path().join("summary.json"), b"1").unwrap();
    out.commit().unwrap();
    let out = AtomicDir::new(&target).unwrap();
    write_atomic(out.path().join("summary.json"), b"2").unwrap();
    out.commit().unwrap();
    assert_eq!(entries(&target), vec!["summary.json", MANIFEST_FILE]);
    assert_eq!(std::fs::read(victim.join("keep.txt")).unwrap(), b"precious");
    assert_eq!(entries(root.path()), vec!["out", "victim"]);
}

/// A killed run's temporary folder (`.NAME.tmp-PID-*`, PID no longer running)
/// is removed by the next run on the same target, which says so; a running
/// process's is kept.
#[cfg(target_os = "linux")]
#[test]
fn a_killed_runs_temporary_folder_is_removed_by_the_next_run() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("out");
    // Above Linux's largest process id (2^22): no process has it.
    let stale = root.path().join(".out.tmp-4999999-abc123");
    std::fs::create_dir_all(stale.join("shapes")).unwrap();
    std::fs::write(stale.join("shapes/part.vtu"), b"partial").unwrap();
    let live = root.path().join(format!(".out.tmp-{}-zzz999", std::process::id()));
    std::fs::create_dir(&live).unwrap();
    let other = root.path().join(".other.tmp-4999999-abc123");
    std::fs::create_dir(&other).unwrap();
    let out = AtomicDir::new(&target).unwrap();
    assert_eq!(out.stale_removed(), std::slice::from_ref(&stale));
    assert!(!stale.exists() && live.exists() && other.exists());
    drop(out);
    std::fs::remove_dir(&live).unwrap();
    assert_eq!(entries(root.path()), vec![".other.tmp-4999999-abc123"]);
}

/// A killed single-file write leaves `.NAME.tmp-PID-*` beside the file: the
/// next run on the same file removes it (a dead PID only; a live process's,
/// another file's, and a link of that name are left alone).
#[cfg(target_os = "linux")]
#[test]
fn a_killed_single_file_writes_temporary_is_removed_by_the_next_run() {
    let root = tempfile::tempdir().unwrap();
    let target = root.path().join("x.vtu");
    let stale = root.path().join(".x.vtu.tmp-4999999-Ab3dE9");
    std::fs::write(&stale, b"partial").unwrap();
    let live = root.path().join(format!(".x.vtu.tmp-{}-zzz999", std::process::id()));
    std::fs::write(&live, b"being written").unwrap();
    let other = root.path().join(".y.vtu.tmp-4999999-Ab3dE9");
    std::fs::write(&other, b"partial").unwrap();
    let link = root.path().join(".x.vtu.tmp-4999998-Ab3dE9");
    std::os::unix::fs::symlink(&other, &link).unwrap();
    let removed = wagashi_io::atomic::remove_stale_temporaries(&target);
    assert_eq!(removed, vec![stale.clone()]);
    assert!(!stale.exists() && live.exists() && other.exists());
    assert!(std::fs::symlink_metadata(&link).is_ok());
    assert!(wagashi_io::atomic::remove_stale_temporaries(&target).is_empty());
}
