//! `wagashi fit` end to end: a trial simulated by `wagashi press` (2D, with markers
//! at keep and final times) is fitted back from other start values.

mod common;

use std::path::Path;

use common::*;

/// Writes the seed's 2D material 1 trial with markers on the free side at the keep
/// (150 s, release) and final (300 s, end) times into `dir`.
fn trial_with_markers(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    let toml = std::fs::read_to_string(example("paper/mat1-2d").join("experiment.toml")).unwrap();
    let toml = toml.replace("[protocol]", "[data]\nmarkers = \"markers.csv\"\n\n[protocol]");
    std::fs::write(dir.join("experiment.toml"), toml).unwrap();
    let mut csv = String::from("marker,t_s,x_mm,y_mm\n");
    for (name, x, y) in [("a", 58.0, 14.875), ("b", 58.0, 29.75), ("c", 58.0, 44.625), ("d", 29.0, 59.5)] {
        for t in ["0.0", "150", "210.93", "300", "400"] {
            csv.push_str(&format!("{name},{t},{x},{y}\n"));
        }
    }
    std::fs::write(dir.join("markers.csv"), csv).unwrap();
}

const START: &str = "[materials.mat1]
model = \"five-element\"
poisson = 0.3
E1_MPa = 0.05
E2_MPa = 0.03
c1_MPa_s = 0.01
c2_MPa_s = 0.5
c3_MPa_s = 50.0
";

#[test]
fn fits_a_simulated_trial_back_and_writes_every_output() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    trial_with_markers(&cwd.join("in"));
    assert_success(&wagashi_in(cwd, ["press", "in", "-o", "measured", "--size-mm", "6"]));
    std::fs::write(cwd.join("start.toml"), START).unwrap();
    let before = contents(&cwd.join("measured"));
    let o = wagashi_in(cwd, ["fit", "measured", "--materials", "start.toml", "--size-mm", "6", "-o", "fit"]);
    assert_success(&o);
    assert_eq!(contents(&cwd.join("measured")), before, "the input bundle was modified");
    for f in ["fit.json", "materials.toml", "fit.svg", "shapes.svg", "summary.json"] {
        assert!(cwd.join("fit").join(f).is_file(), "{f} missing");
    }
    let fit: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("fit/fit.json")).unwrap()).unwrap();
    // Same mesh, same data: the seed's three steps recover Table II (the data are
    // noise-free; only the adaptive steps differ between the runs' parameters).
    let truth =
        [("poisson", 0.3746), ("E1_MPa", 0.0349), ("E2_MPa", 0.0221), ("c1_MPa_s", 0.0071), ("c2_MPa_s", 0.1869)];
    for set in ["force", "shape"] {
        for (key, value) in truth {
            let entry = &fit["sets"][set]["mat1"][key];
            let v = entry["value"].as_f64().unwrap_or_else(|| panic!("sets.{set}.mat1.{key}: {fit}"));
            assert!((v - value).abs() < 5e-3 * value, "sets.{set}.mat1.{key} = {v}, expected {value}");
            let ci = entry["ci95"].as_array().unwrap();
            assert!(ci[0].as_f64().unwrap() <= v && v <= ci[1].as_f64().unwrap(), "{key}: {entry}");
        }
    }
    let c3 = fit["sets"]["force"]["mat1"]["c3_MPa_s"]["value"].as_f64().unwrap();
    assert!((c3 - 29.719).abs() < 5e-3 * 29.719, "c3 = {c3}");
    for key in ["objective", "iterations", "simulations"] {
        assert!(fit[key].is_number(), "{key} missing: {fit}");
    }
    // materials.toml loads with --materials.
    let o = wagashi_in(cwd, ["press", "in", "--materials", "fit/materials.toml", "--size-mm", "6", "-o", "again"]);
    assert_success(&o);
    // The joint procedure: one set, with profile likelihoods of nu and c3.
    let o = wagashi_in(
        cwd,
        ["fit", "measured", "--materials", "start.toml", "--size-mm", "6", "--procedure", "joint", "-o", "joint"],
    );
    assert_success(&o);
    let joint: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("joint/fit.json")).unwrap()).unwrap();
    let nu = joint["sets"]["joint"]["mat1"]["poisson"]["value"].as_f64().unwrap();
    assert!((nu - 0.3746).abs() < 5e-3 * 0.3746, "joint nu = {nu}");
    let last = joint["steps"].as_array().unwrap().last().unwrap().clone();
    let profiled: Vec<&str> =
        last["profiles"].as_array().unwrap().iter().map(|p| p["parameter"].as_str().unwrap()).collect();
    assert_eq!(profiled, ["mat1.poisson", "mat1.c3_MPa_s"], "{last}");
    for p in last["profiles"].as_array().unwrap() {
        let ci: Vec<f64> = p["ci95"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        let v = joint["sets"]["joint"]["mat1"][p["parameter"].as_str().unwrap().trim_start_matches("mat1.")]["value"]
            .as_f64()
            .unwrap();
        assert!(ci[0] <= v && v <= ci[1], "profile interval {ci:?} misses the estimate {v}");
    }
    // The output folder is not replaced without --force.
    let o = wagashi_in(cwd, ["fit", "measured", "--materials", "start.toml", "--size-mm", "6", "-o", "fit"]);
    assert!(assert_one_line_error(&o).contains("--force"));
}

#[test]
fn refuses_trials_with_nothing_to_fit() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    // No measured data.
    let o = wagashi_in(cwd, ["fit", example("paper/mat1-2d").to_str().unwrap(), "-o", "out"]);
    assert!(assert_one_line_error(&o).contains("no measured data"), "{}", stderr(&o));
    // Every parameter given.
    trial_with_markers(&cwd.join("in"));
    assert_success(&wagashi_in(cwd, ["press", "in", "-o", "measured", "--size-mm", "12"]));
    let o = wagashi_in(cwd, ["fit", "measured", "-o", "out"]);
    assert!(assert_one_line_error(&o).contains("nothing to fit"), "{}", stderr(&o));
    assert!(!cwd.join("out").exists(), "a refused fit left an output folder");
}
