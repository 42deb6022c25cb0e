//! `wagashi press` end to end: the real binary on the repository's example
//! bundles, in a temporary folder, at a coarse element size so that the suite
//! stays fast.

mod common;

use common::*;

/// Every Table I bundle (and the 2D one) runs and writes a complete output; the
/// input bundle is left unchanged.
#[test]
fn every_paper_bundle_runs() {
    let tmp = tempfile::tempdir().unwrap();
    for name in PAPER_BUNDLES {
        let bundle = example(&format!("paper/{name}"));
        let before = contents(&bundle);
        let out = tmp.path().join(name);
        let o = press_in(tmp.path(), &bundle, &out, &["--size-mm", "10"]);
        assert_success(&o);
        assert_eq!(contents(&bundle), before, "{name}: the input bundle changed");
        let dimension = if name.ends_with("-2d") { 2 } else { 3 };
        let summary = check_output(&out, dimension);
        assert_eq!(summary["name"].as_str(), Some(name));
        assert_eq!(summary["size_mm"].as_f64(), Some(10.0));
        assert_eq!(summary["integrator"].as_str(), Some("implicit"));
        assert!(summary["force_rms_diff_N"].is_null(), "nothing measured");
        assert_eq!(summary["final_time_s"].as_f64(), Some(400.0));
        // No measured force: the default 0.1 s grid from 0 to end_s.
        let force = read_force_csv(&out.join("force.csv"));
        assert_eq!(force.len(), 4001);
        assert_eq!((force[0].0, force[4000].0), (0.0, 400.0));
        // The glued plate holds the top face at the push displacement (0.2 t_p).
        let keep_loss = summary["keep_height_loss_mm"].as_f64().unwrap();
        assert!(keep_loss > 5.7 && keep_loss < 9.9, "{name}: keep height loss {keep_loss}");
        let final_loss = summary["final_height_loss_mm"].as_f64().unwrap();
        assert!(final_loss > 0.0 && final_loss < keep_loss, "{name}: final height loss {final_loss}");
        let text = stdout(&o);
        for needle in ["peak force", "force at end of hold", "final height loss", "elements", out.to_str().unwrap()] {
            assert!(text.contains(needle), "{name}: stdout lacks {needle:?}:\n{text}");
        }
        // The output is itself a bundle: no markers here, so no markers.csv.
        assert!(!out.join("markers.csv").exists());
        check_stress_strain(&bundle, &out);
    }
}

/// `stress_strain.csv` against the bundle: the force of `force.csv` over the
/// block's `W T`, and the plate's travel over `H`, at every sample until
/// `release_s`, with the push's end at the waypoint's strain.
fn check_stress_strain(bundle: &std::path::Path, out: &std::path::Path) {
    let experiment: toml::Table =
        toml::from_str(&std::fs::read_to_string(bundle.join("experiment.toml")).unwrap()).unwrap();
    let size: Vec<f64> =
        experiment["specimen"]["size_mm"].as_array().unwrap().iter().map(|v| v.as_float().unwrap()).collect();
    let protocol = &experiment["protocol"];
    let release_s = protocol["release_s"].as_float().unwrap();
    let waypoints = protocol["waypoints"].as_array().unwrap();
    let push = waypoints[1].as_array().unwrap();
    let (push_s, push_mm) = (push[0].as_float().unwrap(), push[1].as_float().unwrap());
    let force = read_force_csv(&out.join("force.csv"));
    let text = std::fs::read_to_string(out.join("stress_strain.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_s,strain,stress_kPa"));
    let rows: Vec<[f64; 3]> = lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(rows.len(), force.iter().filter(|f| f.0 <= release_s).count());
    for (row, f) in rows.iter().zip(&force) {
        assert_eq!(row[0], f.0);
        let want = 1e3 * f.1 / (size[0] * size[2]);
        assert!((row[2] - want).abs() <= 1e-12 * want.abs().max(1e-9), "stress {} against {want}", row[2]);
        if row[0] <= push_s {
            let strain = push_mm * row[0] / push_s / size[1];
            assert!((row[1] - strain).abs() < 1e-12, "strain {} against {strain} at {} s", row[1], row[0]);
        } else {
            assert!((row[1] - push_mm / size[1]).abs() < 1e-12, "held strain {}", row[1]);
        }
    }
}

/// The default element size is a quarter of the smallest dimension.
#[test]
fn the_default_size_is_a_quarter_of_the_smallest_dimension() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &example("paper/mat1-2d"), &out, &[]);
    assert_success(&o);
    let summary = check_output(&out, 2);
    assert_eq!(summary["size_mm"].as_f64(), Some(3.0)); // min(58, 59.5, 12) / 4
    assert!(stdout(&o).contains("3 mm elements (default: a quarter of the smallest dimension)"), "{}", stdout(&o));
}

/// Markers given at t = 0 come back, simulated, in markers.csv.
#[test]
fn markers_are_written_at_their_measured_times() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = example("markers-demo");
    let before = contents(&bundle);
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &bundle, &out, &["--size-mm", "10"]);
    assert_success(&o);
    assert_eq!(contents(&bundle), before);
    let summary = check_output(&out, 3);
    assert_eq!(summary["markers"].as_u64(), Some(9));
    let written = std::fs::read_to_string(out.join("markers.csv")).unwrap();
    let given = std::fs::read_to_string(bundle.join("markers.csv")).unwrap();
    let rows = |text: &str| -> Vec<(String, Vec<f64>)> {
        text.lines()
            .skip(1)
            .map(|l| {
                let mut cells = l.split(',');
                let name = cells.next().unwrap().to_string();
                (name, cells.map(|c| c.parse().unwrap()).collect())
            })
            .collect()
    };
    assert_eq!(written.lines().next(), Some("marker,t_s,x_mm,y_mm,z_mm"));
    let (w, g) = (rows(&written), rows(&given));
    assert_eq!(w.len(), g.len());
    for ((wn, wv), (gn, gv)) in w.iter().zip(&g) {
        assert_eq!(wn, gn);
        // At t = 0 the simulated position is the initial one (to rounding).
        assert!(wv.iter().zip(gv).all(|(a, b)| (a - b).abs() <= 1e-9 * b.abs().max(1.0)), "{wn}: {wv:?} vs {gv:?}");
    }
}

/// A simulated output reads back as a measured bundle; simulating it again with
/// the same settings reproduces its force (the comparison is reported).
#[test]
fn an_output_reads_back_as_a_measured_bundle() {
    let tmp = tempfile::tempdir().unwrap();
    let first = tmp.path().join("first");
    let args = ["--size-mm", "10", "--output-dt", "2"];
    let o = press_in(tmp.path(), &example("paper/mat2"), &first, &args);
    assert_success(&o);
    let before = contents(&first);
    let second = tmp.path().join("second");
    let o = press_in(tmp.path(), &first, &second, &args);
    assert_success(&o);
    assert_eq!(contents(&first), before, "the input (a previous output) changed");
    let summary = check_output(&second, 3);
    assert_eq!(summary["name"].as_str(), Some("mat2-sim"));
    assert_eq!(summary["measured_force_samples"].as_u64(), Some(201));
    // The same mesh, materials and steps: the same force, to rounding.
    let peak = summary["peak_force_N"].as_f64().unwrap();
    let rms = summary["force_rms_diff_N"].as_f64().unwrap();
    let max = summary["force_max_abs_diff_N"].as_f64().unwrap();
    assert!(rms <= max && max <= 1e-9 * peak, "rms {rms}, max {max}, peak {peak}");
    // Sampled at the measured times.
    let times =
        |dir: &std::path::Path| read_force_csv(&dir.join("force.csv")).into_iter().map(|s| s.0).collect::<Vec<_>>();
    assert_eq!(times(&second), times(&first));
    assert!(stdout(&o).contains("simulated - measured"), "{}", stdout(&o));
    let svg = std::fs::read_to_string(second.join("force.svg")).unwrap();
    assert!(svg.contains("measured") && svg.contains("simulated"));
}

/// `--materials` replaces the bundle's materials: the seed's x_shape set (a
/// smaller c3) leaves less of the push in the final shape.
#[test]
fn a_materials_file_replaces_the_bundle_materials() {
    let tmp = tempfile::tempdir().unwrap();
    let run = |out: &str, extra: &[&str]| {
        let out = tmp.path().join(out);
        let args = [&["--size-mm", "10"], extra].concat();
        let o = press_in(tmp.path(), &example("paper/mat1-2d"), &out, &args);
        assert_success(&o);
        check_output(&out, 2)
    };
    let x_shape = example("paper/x-shape.toml");
    let force = run("force", &[]);
    let shape = run("shape", &["--materials", x_shape.to_str().unwrap()]);
    let loss = |s: &serde_json::Value| s["final_height_loss_mm"].as_f64().unwrap();
    // A smaller series dashpot c3 keeps more of the push after release.
    assert!(loss(&shape) > loss(&force), "x_shape {} vs x_force {}", loss(&shape), loss(&force));
    // The written bundle holds the materials it was simulated with.
    let written = std::fs::read_to_string(tmp.path().join("shape/experiment.toml")).unwrap();
    assert!(written.contains("c3_MPa_s = 1.4951"), "{written}");
}

/// `--pvd N` writes N + 1 shapes and a collection that names them.
#[test]
fn pvd_writes_a_time_series() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &example("paper/mat3"), &out, &["--size-mm", "10", "--pvd", "4"]);
    assert_success(&o);
    let summary = check_output(&out, 3);
    let (nodes, cells) = (summary["nodes"].as_u64().unwrap(), summary["cells"].as_u64().unwrap());
    let pvd = std::fs::read_to_string(out.join("shapes.pvd")).unwrap();
    let doc = roxmltree::Document::parse(&pvd).unwrap();
    let sets: Vec<(f64, String)> = doc
        .descendants()
        .filter(|n| n.has_tag_name("DataSet"))
        .map(|n| (n.attribute("timestep").unwrap().parse().unwrap(), n.attribute("file").unwrap().to_string()))
        .collect();
    let times: Vec<f64> = sets.iter().map(|s| s.0).collect();
    assert_eq!(times, [0.0, 100.0, 200.0, 300.0, 400.0]);
    for (_, file) in &sets {
        check_vtu(&out.join(file), nodes, cells, 10);
    }
}

/// The other integrators run through the same path (dynamic on a coarse 2D mesh).
#[test]
fn the_dynamic_integrator_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &example("paper/mat1-2d"), &out, &["--size-mm", "15", "--integrator", "dynamic"]);
    assert_success(&o);
    let summary = check_output(&out, 2);
    assert_eq!(summary["integrator"].as_str(), Some("dynamic"));
}

/// A fixed step: every step (except those landing on a kink) has that size.
#[test]
fn a_fixed_step_is_used() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &example("paper/mat1-2d"), &out, &["--size-mm", "15", "--dt", "5"]);
    assert_success(&o);
    let summary = check_output(&out, 2);
    assert_eq!(summary["dt_s"].as_f64(), Some(5.0));
    let steps = std::fs::read_to_string(out.join("steps.csv")).unwrap();
    let dts: Vec<f64> = steps.lines().skip(1).map(|l| l.split(',').nth(1).unwrap().parse().unwrap()).collect();
    assert!(dts.iter().all(|&dt| dt <= 5.0 * (1.0 + 1e-12)), "{dts:?}");
    assert!(dts.iter().filter(|&&dt| (dt - 5.0).abs() < 1e-9).count() > dts.len() / 2, "{dts:?}");
}

/// Measured force past `end_s`: nothing is simulated there, so `force.csv`
/// stops at `end_s` (no held value written after it) and the comparison uses
/// the samples up to it; the run says how many it left out.
#[test]
fn measured_force_after_the_end_is_left_out() {
    let tmp = tempfile::tempdir().unwrap();
    let toml = mat1_experiment!(
        "past-end",
        3,
        "shape = \"block\"\nsize_mm = [10.0, 10.0, 10.0]\n",
        "tool_contact = \"glued\"\nsupport = \"glued\"\nwaypoints = [[0.0, 0.0], [2.0, 0.2]]\nrelease_s = 2.0\nend_s = 4.0\n\n[data]\nforce = \"force.csv\"\n"
    );
    let force = "t_s,force_N\n0.0,0.0\n1.0,0.01\n2.0,0.02\n3.0,0.0\n4.0,0.0\n5.0,0.0\n6.0,0.0\n";
    let bundle = write_files(&tmp.path().join("trial"), &[("experiment.toml", toml), ("force.csv", force)]);
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &bundle, &out, &["--size-mm", "5"]);
    assert_success(&o);
    let times: Vec<f64> = read_force_csv(&out.join("force.csv")).into_iter().map(|s| s.0).collect();
    assert_eq!(times, vec![0.0, 1.0, 2.0, 3.0, 4.0]);
    assert_eq!(read_summary(&out)["measured_force_samples"].as_u64(), Some(5));
    assert!(
        stdout(&o).contains("note: 2 measured force samples after end_s = 4 s are left out (not simulated)"),
        "{}",
        stdout(&o)
    );
}
