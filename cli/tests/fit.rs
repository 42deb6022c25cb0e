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
    // One push: a misfit but no texture profile, and no note about one.
    let trial = &fit["trials"][0];
    assert!(trial.get("tpa").is_none(), "{trial}");
    assert!(trial["misfit"]["force_rms_noise_units"].is_number() && trial["misfit"]["marker_rms_mm"].is_number());
    assert!(!stdout(&o).contains("texture profile"), "{}", stdout(&o));
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

/// Writes a short 2D trial (push 2 mm in 10 s, hold to 30 s, recover to 60 s) of a
/// 30 mm block, uniform (`layers` empty: `material`) or layered, with the true
/// materials of the seed's Table II and side markers at the keep (25 s) and final
/// (60 s) times.
fn short_trial(dir: &Path, name: &str, material: &str, layers: &[&str]) {
    std::fs::create_dir_all(dir).unwrap();
    let mut specimen = String::new();
    if layers.is_empty() {
        specimen.push_str(&format!("material = \"{material}\"\n"));
    }
    for layer in layers {
        specimen.push_str(&format!("[[specimen.layers]]\nmaterial = \"{layer}\"\nthickness_mm = 10.0\n"));
    }
    let toml = format!(
        "format = \"wagashi-experiment/1\"\nname = \"{name}\"\ndimension = 2\n\n[specimen]\nshape = \"block\"\n\
size_mm = [30.0, 30.0, 10.0]\n{specimen}\n\
[materials.mat1]\nmodel = \"five-element\"\npoisson = 0.3746\nE1_MPa = 0.0349\nE2_MPa = 0.0221\nc1_MPa_s = 0.0071\n\
c2_MPa_s = 0.1869\nc3_MPa_s = 29.719\n\n\
[materials.mat2]\nmodel = \"five-element\"\npoisson = 0.3353\nE1_MPa = 0.0454\nE2_MPa = 0.0141\nc1_MPa_s = 0.0115\n\
c2_MPa_s = 0.1991\nc3_MPa_s = 13.370\n\n\
[data]\nmarkers = \"markers.csv\"\n\n\
[protocol]\ntool = \"plate\"\ntool_contact = \"glued\"\nsupport = \"glued\"\n\
waypoints = [[0.0, 0.0], [10.0, 2.0], [30.0, 2.0]]\nrelease_s = 30.0\nend_s = 60.0\n"
    );
    std::fs::write(dir.join("experiment.toml"), toml).unwrap();
    let mut csv = String::from("marker,t_s,x_mm,y_mm\n");
    for (marker, x, y) in [("a", 30.0, 5.0), ("b", 30.0, 15.0), ("c", 30.0, 25.0), ("d", 15.0, 30.0)] {
        for t in ["0.0", "25", "60"] {
            csv.push_str(&format!("{marker},{t},{x},{y}\n"));
        }
    }
    std::fs::write(dir.join("markers.csv"), csv).unwrap();
}

/// Several trials at once, sharing materials (the seed's validation, small): a
/// uniform mat1 trial, a uniform mat2 trial and a layered mat1/mat2/mat1 trial,
/// simulated by `wagashi press`, fitted together from other start values. The two
/// materials are two sets of unknowns, whatever the number of trials and layers
/// that use them; the outputs carry every key per material, and materials.toml
/// runs the layered trial again.
#[test]
fn fits_uniform_and_layered_trials_together() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let trials = [("u1", "mat1", vec![]), ("u2", "mat2", vec![]), ("l121", "", vec!["mat1", "mat2", "mat1"])];
    std::fs::create_dir_all(cwd.join("measured")).unwrap();
    for (name, material, layers) in &trials {
        short_trial(&cwd.join("in").join(name), name, material, layers);
        let input = format!("in/{name}");
        let output = format!("measured/{name}");
        assert_success(&wagashi_in(cwd, ["press", input.as_str(), "-o", output.as_str(), "--size-mm", "5"]));
    }
    let start = format!("{START}\n{}", START.replace("mat1", "mat2"));
    std::fs::write(cwd.join("start.toml"), start).unwrap();
    let truth = [
        ("mat1", [("poisson", 0.3746), ("E1_MPa", 0.0349), ("E2_MPa", 0.0221), ("c1_MPa_s", 0.0071)]),
        ("mat2", [("poisson", 0.3353), ("E1_MPa", 0.0454), ("E2_MPa", 0.0141), ("c1_MPa_s", 0.0115)]),
    ];
    let bundles = ["measured/u1", "measured/u2", "measured/l121"];
    for (procedure, sets) in [("seed", vec!["force", "shape"]), ("joint", vec!["joint"])] {
        let out = format!("fit-{procedure}");
        let mut args = vec!["fit"];
        args.extend(bundles);
        args.extend(["--materials", "start.toml", "--size-mm", "5", "--procedure", procedure, "-o", out.as_str()]);
        assert_success(&wagashi_in(cwd, args));
        let fit: serde_json::Value =
            serde_json::from_slice(&std::fs::read(cwd.join(&out).join("fit.json")).unwrap()).unwrap();
        for key in ["objective", "iterations", "simulations"] {
            assert!(fit[key].is_number(), "{procedure}: {key} missing: {fit}");
        }
        for set in &sets {
            for (material, values) in &truth {
                for key in ["poisson", "E1_MPa", "E2_MPa", "c1_MPa_s", "c2_MPa_s", "c3_MPa_s"] {
                    let entry = &fit["sets"][set][material][key];
                    let v = entry["value"].as_f64().unwrap_or_else(|| panic!("sets.{set}.{material}.{key}: {fit}"));
                    let ci = entry["ci95"].as_array().unwrap_or_else(|| panic!("{procedure} {set}: {entry}"));
                    let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
                    assert!(lo <= v && v <= hi, "{procedure} sets.{set}.{material}.{key}: {entry}");
                }
                // Same mesh, noise-free data: the well-determined parameters come back.
                for (key, value) in values {
                    let v = fit["sets"][set][material][key]["value"].as_f64().unwrap();
                    assert!(
                        (v - value).abs() < 1e-2 * value,
                        "{procedure} sets.{set}.{material}.{key} = {v} vs {value}"
                    );
                }
            }
        }
        // materials.toml runs the layered trial with the fitted materials.
        let materials = format!("{out}/materials.toml");
        let again = format!("again-{procedure}");
        let o = wagashi_in(
            cwd,
            ["press", "in/l121", "--materials", materials.as_str(), "--size-mm", "5", "-o", again.as_str()],
        );
        assert_success(&o);
    }
}

/// A double compression whose plate leaves the specimen and touches it again
/// (a contact tool, which has no forward sensitivities): simulated on the
/// cylinder's axisymmetric section, then fitted back with E1 and c3 unknown. The
/// Jacobian comes from forward differences on the run's frozen step ends, so
/// the fit returns both to 1e-4 (measured: 5 digits), and the output reads
/// back as a fit.
#[test]
fn fits_a_double_compression_with_a_contact_plate_back() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let o = press_in(
        cwd,
        &example("paper/double-compression"),
        &cwd.join("measured"),
        &["--axisymmetric", "--size-mm", "2.5"],
    );
    assert_success(&o);
    let bundle = cwd.join("measured/experiment.toml");
    let text = std::fs::read_to_string(&bundle).unwrap();
    let out = fit_e1_and_c3_back(cwd, &bundle, &text);
    check_texture_misfit_and_intervals(cwd, &out);
}

/// What the double compression's fit reports beside its values: the measured
/// and simulated texture profiles (the measured hardness is the largest sample
/// of `measured/force.csv` before the split; fitted to its own simulated data,
/// the simulated profile matches the measured one), the per-trial misfit
/// (consistent in N, noise units and share of the peak, and small), and
/// intervals as ranges with no relative width above 100 %.
fn check_texture_misfit_and_intervals(cwd: &Path, out: &str) {
    let fit: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("fit/fit.json")).unwrap()).unwrap();
    let trial = &fit["trials"][0];
    let (measured, simulated) = (&trial["tpa"]["measured"], &trial["tpa"]["simulated"]);
    let split = measured["split_s"].as_f64().unwrap_or_else(|| panic!("no tpa in {trial}"));
    let force = read_force_csv(&cwd.join("measured/force.csv"));
    let peak = force.iter().filter(|&&(t, _)| t < split).map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    // The misfit's peak: every sample's largest magnitude (the protocol ends at 40 s).
    let largest = force.iter().filter(|&&(t, _)| t > 0.0 && t <= 40.0).map(|p| p.1.abs()).fold(0.0, f64::max);
    assert_eq!(measured["hardness_N"].as_f64().unwrap(), peak, "{measured}");
    for key in ["hardness_N", "cohesiveness", "springiness", "resilience"] {
        let (m, s) = (measured[key].as_f64().unwrap(), simulated[key].as_f64().unwrap());
        assert!(m > 0.0 && (s / m - 1.0).abs() < 1e-3, "{key}: measured {m}, simulated {s}");
    }
    assert!(out.contains("texture profile, measured / simulated:"), "{out}");
    let name = trial["name"].as_str().unwrap();
    let row = out.lines().find(|l| l.trim_start().starts_with(&format!("{name} "))).unwrap_or_else(|| panic!("{out}"));
    assert_eq!(row.matches(" / ").count(), 4, "{row}");
    // The misfit, per trial.
    let misfit = &trial["misfit"];
    let [rms, units, share, peak_n] =
        ["force_rms_N", "force_rms_noise_units", "force_rms_share_of_peak", "force_peak_N"]
            .map(|k| misfit[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {misfit}")));
    assert!((units * trial["force_sigma_N"].as_f64().unwrap() / rms - 1.0).abs() < 1e-12, "{misfit}");
    assert!((share * peak_n / rms - 1.0).abs() < 1e-12, "{misfit}");
    assert_eq!(peak_n, largest, "{misfit}");
    assert!(share < 1e-3, "a fit to its own simulated data misses by {share} of the peak");
    let line = out
        .lines()
        .skip_while(|l| *l != "misfit of the fitted simulation, per trial:")
        .nth(1)
        .unwrap_or_else(|| panic!("no misfit lines: {out}"));
    assert!(line.starts_with(&format!("  {name}: force rms ")), "{line}");
    // The printed numbers (four digits) are the JSON's.
    let printed = |before: &str| -> f64 {
        let head = &line[..line.find(before).unwrap_or_else(|| panic!("no {before:?} in {line}"))];
        head.rsplit(' ').next().unwrap().parse().unwrap()
    };
    assert!((printed(" noise units") / units - 1.0).abs() < 1e-3, "{line}");
    assert!((printed(" % of its peak") / (100.0 * share) - 1.0).abs() < 1e-3, "{line}");
    // Intervals: ranges, and no percentage above 100 (nor an infinite one).
    let sets = out.lines().skip_while(|l| !l.starts_with("set ")).take_while(|l| !l.starts_with("misfit"));
    for l in sets.filter(|l| l.starts_with("  ")) {
        assert!(l.contains(" [") && l.contains("]"), "{l}");
    }
    assert!(!out.contains("inf %"), "{out}");
    for (i, _) in out.match_indices(" %") {
        let number = out[..i].rsplit([' ', '(', '[']).next().unwrap();
        if let Ok(p) = number.parse::<f64>() {
            assert!(p <= 100.0, "a percentage above 100: {}", &out[i.saturating_sub(80)..i + 2]);
        }
    }
}

/// The same double compression with a plastic slider in series
/// (`plastic_yield_stress_MPa`, a material-point effect, which runs with contact
/// tools): simulated, then fitted back with E1 and c3 unknown and the slider in
/// place. Both return to 1e-4, as without the slider.
#[test]
fn fits_a_double_compression_with_a_contact_plate_and_a_plastic_slider_back() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let source = example("paper/double-compression/experiment.toml");
    let text = std::fs::read_to_string(source).unwrap();
    std::fs::create_dir_all(cwd.join("truth")).unwrap();
    let with_slider = format!("{text}\n[effects]\nplastic_yield_stress_MPa = 0.002\nplastic_hardening_MPa = 0.01\n");
    std::fs::write(cwd.join("truth/experiment.toml"), with_slider).unwrap();
    let o = press_in(cwd, &cwd.join("truth"), &cwd.join("measured"), &["--axisymmetric", "--size-mm", "2.5"]);
    assert_success(&o);
    let bundle = cwd.join("measured/experiment.toml");
    let text = std::fs::read_to_string(&bundle).unwrap();
    assert!(text.contains("plastic_yield_stress_MPa = 0.002"), "{text}");
    fit_e1_and_c3_back(cwd, &bundle, &text);
}

/// Removes E1 and c3 from the simulated bundle `measured` (its text `text`
/// holds the truth's values), fits them back with the joint procedure and
/// checks both return to 1e-4 of the truth (E1 = 0.0349 MPa, c3 = 29.719 MPa s).
/// Returns the fit's stdout.
fn fit_e1_and_c3_back(cwd: &Path, bundle: &Path, text: &str) -> String {
    assert!(text.contains("E1_MPa = 0.0349\n") && text.contains("c3_MPa_s = 29.719\n"), "{text}");
    std::fs::write(bundle, text.replace("E1_MPa = 0.0349\n", "").replace("c3_MPa_s = 29.719\n", "")).unwrap();
    let o =
        wagashi_in(cwd, ["fit", "measured", "--axisymmetric", "--size-mm", "2.5", "--procedure", "joint", "-o", "fit"]);
    assert_success(&o);
    let fit: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("fit/fit.json")).unwrap()).unwrap();
    for (key, truth) in [("E1_MPa", 0.0349), ("c3_MPa_s", 29.719)] {
        let v = fit["sets"]["joint"]["mat1"][key]["value"].as_f64().unwrap_or_else(|| panic!("{fit}"));
        assert!((v / truth - 1.0).abs() < 1e-4, "{key} = {v} vs {truth}");
    }
    stdout(&o)
}
