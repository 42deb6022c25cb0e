//! `wagashi demo` end to end.

mod common;

use common::*;

#[test]
fn the_demo_runs_and_writes_the_press_output() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("demo");
    let o = wagashi_in(tmp.path(), ["demo".as_ref(), "-o".as_ref(), out.as_os_str()]);
    assert_success(&o);
    let summary = check_output(&out, 3);
    assert_eq!(summary["name"].as_str(), Some("mat1"));
    assert_eq!(summary["size_mm"].as_f64(), Some(3.0));
    assert_eq!(summary["cells"].as_u64(), Some(9600)); // 20 x 20 x 4 hexahedra, 6 tetrahedra each
    assert_eq!(summary["keep_time_s"].as_f64(), Some(210.93));
    let text = stdout(&o);
    for needle in ["peak force", "force at end of hold", "final height loss", "ParaView", "browser", "force.svg"] {
        assert!(text.contains(needle), "stdout lacks {needle:?}:\n{text}");
    }
    // Run again: the previous demo output is replaced.
    let o = wagashi_in(tmp.path(), ["demo".as_ref(), "-o".as_ref(), out.as_os_str()]);
    assert_success(&o);
    check_output(&out, 3);
}

/// Without -o the demo writes `demo-out` in the current folder.
#[test]
fn the_demo_writes_demo_out_by_default() {
    let tmp = tempfile::tempdir().unwrap();
    let o = wagashi_in(tmp.path(), ["demo"]);
    assert_success(&o);
    check_output(&tmp.path().join("demo-out"), 3);
}

/// The demo never replaces a folder that is not a wagashi output.
#[test]
fn the_demo_refuses_a_foreign_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mine");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "keep me").unwrap();
    let o = wagashi_in(tmp.path(), ["demo".as_ref(), "-o".as_ref(), out.as_os_str()]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("refusing to overwrite") && line.contains("mine"), "{line}");
    assert_eq!(std::fs::read_to_string(out.join("notes.txt")).unwrap(), "keep me");
}
