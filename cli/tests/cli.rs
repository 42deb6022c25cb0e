//! The command line itself: help, version, and refusals that do not depend on
//! the bundle's content (a missing bundle, output folders that must not be touched).

mod common;

use common::*;

#[test]
fn help_of_every_command_has_an_example() {
    let tmp = tempfile::tempdir().unwrap();
    for args in [&["--help"][..], &["help"], &["press", "--help"], &["demo", "--help"], &["help", "press"]] {
        let o = wagashi_in(tmp.path(), args);
        assert_success(&o);
        assert!(stdout(&o).contains("Example"), "{args:?}:\n{}", stdout(&o));
    }
    let press = stdout(&wagashi_in(tmp.path(), ["press", "--help"]));
    for flag in ["--size-mm", "--integrator", "--rtol", "--dt", "--materials", "--output-dt", "--pvd", "--force"] {
        assert!(press.contains(flag), "press --help lacks {flag}");
    }
}

#[test]
fn version_is_printed() {
    let tmp = tempfile::tempdir().unwrap();
    let o = wagashi_in(tmp.path(), ["--version"]);
    assert_success(&o);
    assert_eq!(stdout(&o).trim(), format!("wagashi {}", env!("CARGO_PKG_VERSION")));
}

#[test]
fn a_missing_bundle_is_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let o = wagashi_in(tmp.path(), ["press", "no/such/bundle", "-o", "out"]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("no/such/bundle"), "{line}");
    assert!(!tmp.path().join("out").exists());
}

#[test]
fn a_bundle_may_be_named_by_its_experiment_toml() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = example("paper/mat2/experiment.toml");
    let out = tmp.path().join("out");
    let o = wagashi_in(
        tmp.path(),
        ["press".as_ref(), toml.as_os_str(), "-o".as_ref(), out.as_os_str(), "--size-mm".as_ref(), "25".as_ref()],
    );
    assert_success(&o);
    check_output(&out, 3);
}

#[test]
fn bad_flag_values_are_refused_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = example("paper/mat1");
    for (flag, value) in [
        ("--size-mm", "0"),
        ("--size-mm", "-3"),
        ("--rtol", "nan"),
        ("--dt", "x"),
        ("--output-dt", "0"),
        ("--pvd", "0"),
        ("--integrator", "euler"),
    ] {
        let o = wagashi_in(
            tmp.path(),
            ["press".as_ref(), bundle.as_os_str(), "-o".as_ref(), "out".as_ref(), flag.as_ref(), value.as_ref()],
        );
        assert_eq!(o.status.code(), Some(2), "{flag} {value}: {}", stderr(&o));
        assert!(stderr(&o).contains(flag), "{flag} {value}: {}", stderr(&o));
    }
    assert!(!tmp.path().join("out").exists());
}

/// An existing folder that is not a wagashi output is never touched, --force or not.
#[test]
fn a_foreign_output_folder_is_refused_untouched() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("precious");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("thesis.tex"), "months of work").unwrap();
    let before_parent: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    for force in [false, true] {
        let o = wagashi_in(tmp.path(), press_args("paper/mat1", &out, force));
        let line = assert_one_line_error(&o);
        assert!(line.contains("refusing to overwrite") && line.contains("precious"), "{line}");
        assert_eq!(contents(&out), [("thesis.tex".into(), b"months of work".to_vec())].into_iter().collect());
        let parent: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(parent, before_parent, "nothing new beside the folder");
    }
    // A plain file is not replaced either.
    let file = tmp.path().join("file.txt");
    std::fs::write(&file, "x").unwrap();
    let o =
        wagashi_in(tmp.path(), ["press".as_ref(), example("paper/mat1").as_os_str(), "-o".as_ref(), file.as_os_str()]);
    assert_one_line_error(&o);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
}

/// A previous wagashi output is replaced only with --force.
#[test]
fn a_previous_output_needs_force() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let run = |force: bool| wagashi_in(tmp.path(), press_args("paper/mat1-2d", &out, force));
    assert_success(&run(false));
    let first = contents(&out);
    let line = assert_one_line_error(&run(false));
    assert!(line.contains("--force"), "{line}");
    assert_eq!(contents(&out), first);
    assert_success(&run(true));
    check_output(&out, 2);
}

/// The output may not be the input bundle, lie inside it or contain it.
#[test]
fn the_output_may_not_overlap_the_input() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = tmp.path().join("trial");
    copy_dir(&example("paper/mat1-2d"), &bundle);
    let before = contents(&bundle);
    for out in [bundle.clone(), bundle.join("results"), tmp.path().to_path_buf()] {
        let o = wagashi_in(
            tmp.path(),
            ["press".as_ref(), bundle.as_os_str(), "-o".as_ref(), out.as_os_str(), "--force".as_ref()],
        );
        let line = assert_one_line_error(&o);
        assert!(line.contains("input bundle"), "{line}");
        assert_eq!(contents(&bundle), before);
    }
}

/// `press EXAMPLE -o OUT --size-mm 20 [--force]`.
fn press_args(example_name: &str, out: &std::path::Path, force: bool) -> Vec<std::ffi::OsString> {
    let mut args = vec![
        "press".into(),
        example(example_name).into_os_string(),
        "-o".into(),
        out.as_os_str().to_owned(),
        "--size-mm".into(),
        "20".into(),
    ];
    if force {
        args.push("--force".into());
    }
    args
}
