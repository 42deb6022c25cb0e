//! `wagashi press` on a network material: the example bundle by its
//! axisymmetric section and in 3D, the output read back as a trial, and a
//! refusal naming both sides.

mod common;

use common::*;

#[test]
fn the_network_example_runs_and_its_output_reads_back() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = example("network/gel-cylinder");
    let before = contents(&bundle);
    let out = tmp.path().join("gel");
    let o = press_in(tmp.path(), &bundle, &out, &["--axisymmetric"]);
    assert_success(&o);
    assert_eq!(contents(&bundle), before, "the input bundle changed");
    let summary = read_summary(&out);
    assert_eq!(summary["formulation"].as_str(), Some("axisymmetric"));
    let peak = summary["peak_force_N"].as_f64().unwrap();
    // A neo-Hookean-like solid of E = 0.03 MPa plus networks, 40 % down on a
    // 10 mm radius: between the equilibrium network's small-strain force
    // (0.03 * 0.4 * pi * 100 = 3.8 N) and ten times it.
    assert!(peak > 3.8 && peak < 38.0, "peak {peak}");
    // The softening equilibrium network keeps a set after the release; the
    // viscous networks relax: a final height loss between 0 and the push.
    let final_loss = summary["final_height_loss_mm"].as_f64().unwrap();
    assert!(final_loss > 0.0 && final_loss < 4.0, "final height loss {final_loss}");
    // The output's experiment.toml holds the network: pressing it again compares
    // the force sample by sample and finds the same curve.
    let again = tmp.path().join("again");
    let o = press_in(tmp.path(), &out, &again, &["--axisymmetric"]);
    assert_success(&o);
    let rms = read_summary(&again)["force_rms_diff_N"].as_f64().unwrap();
    assert!(rms < 1e-9 * peak, "rms {rms}");
}

#[test]
fn a_network_in_plane_stress_is_refused_naming_both() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example("network/gel-cylinder").join("experiment.toml")).unwrap();
    let text = text.replace("dimension = 3", "dimension = 2").replace(
        "shape = \"cylinder\"\nradius_mm = 10.0\nheight_mm = 10.0",
        "shape = \"block\"\nsize_mm = [20.0, 10.0, 10.0]",
    );
    let bundle = write_files(&tmp.path().join("plane"), &[("experiment.toml", &text)]);
    let o = press_in(tmp.path(), &bundle, &tmp.path().join("out"), &[]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("network") && line.contains("plane stress"), "{line}");
}

/// `--fbar` on the example (poisson 0.45, frictionless plates: a homogeneous
/// deformation, where F-bar patches are exact): the same peak force to 1e-8,
/// and the note on locking only without it. On a chain material it is refused
/// in one line naming both.
#[test]
fn fbar_runs_the_network_example_and_is_refused_for_a_chain() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = example("network/gel-cylinder");
    let plain = press_in(tmp.path(), &bundle, &tmp.path().join("plain"), &["--axisymmetric"]);
    assert_success(&plain);
    assert!(stdout(&plain).contains("--fbar removes that"), "{}", stdout(&plain));
    let patched = press_in(tmp.path(), &bundle, &tmp.path().join("fbar"), &["--axisymmetric", "--fbar"]);
    assert_success(&patched);
    assert!(!stdout(&patched).contains("--fbar removes that"), "{}", stdout(&patched));
    let peak = |dir: &str| read_summary(&tmp.path().join(dir))["peak_force_N"].as_f64().unwrap();
    let (a, b) = (peak("plain"), peak("fbar"));
    assert!((a - b).abs() <= 1e-8 * a, "peaks {a} and {b}");

    let chain = example("paper/mat1");
    let o = press_in(tmp.path(), &chain, &tmp.path().join("chain"), &["--fbar"]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("F-bar") && line.contains("network"), "{line}");
}
