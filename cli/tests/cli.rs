//! The command line itself: help, version, and refusals that do not depend on
//! the bundle's content (a missing bundle, output folders that must not be touched).

mod common;

use std::path::Path;

use common::*;

#[test]
fn help_of_every_command_has_an_example() {
    let tmp = tempfile::tempdir().unwrap();
    for args in
        [&["--help"][..], &["help"], &["press", "--help"], &["demo", "--help"], &["help", "press"], &["tpa", "--help"]]
    {
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

/// The largest force of `rows` before `t_end` [N] and its time.
fn peak_before(rows: &[(f64, f64)], t_end: f64) -> (f64, f64) {
    rows.iter().filter(|r| r.0 < t_end).fold((f64::NAN, f64::NEG_INFINITY), |p, r| if r.1 > p.1 { *r } else { p })
}

/// `wagashi press` on the double-compression example writes `tpa.json`, and
/// `wagashi tpa` on that output agrees with it and with its own `force.csv`:
/// the hardness is the largest force before the split, the second stroke's
/// peak the largest after it, the ratios lie where a viscoelastic solid puts
/// them, and `-o` writes the table and the plot.
#[test]
fn tpa_of_a_simulated_double_compression() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let bundle = example("paper/double-compression");
    assert_success(&press_in(cwd, &bundle, Path::new("dc"), &["--axisymmetric", "--size-mm", "2"]));
    let written: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cwd.join("dc/tpa.json")).expect("press writes tpa.json")).unwrap();
    // The shapes at each stroke's peak (the plate deepest, 10 s and 27.5 s) and
    // after it, with the summary's figures: the first stroke's set recovers
    // partly before the second, which compresses it again.
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cwd.join("dc/summary.json")).unwrap()).unwrap();
    let strokes = summary["strokes"].as_array().expect("summary.json lists the strokes");
    assert_eq!(strokes.len(), 2);
    let at = |i: usize, key: &str| strokes[i][key].as_f64().unwrap();
    assert_eq!((at(0, "peak_t_s"), at(1, "peak_t_s")), (10.0, 27.5));
    for (i, stroke) in strokes.iter().enumerate() {
        assert!(at(i, "peak_height_loss_mm") > at(i, "after_height_loss_mm").max(0.0), "{stroke}");
        for shape in ["peak", "after"] {
            assert!(cwd.join(format!("dc/stroke{}-{shape}.vtu", i + 1)).is_file());
        }
    }
    let o = wagashi_in(cwd, ["tpa", "dc", "--json", "-o", "tpa"]);
    assert_success(&o);
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let rows = json.as_array().unwrap();
    assert_eq!(rows.len(), 1);
    let tpa = &rows[0];
    assert_eq!(tpa["input"], "dc");
    let get = |v: &serde_json::Value, key: &str| v[key].as_f64().unwrap_or_else(|| panic!("no {key} in {v}"));
    // press analyses the force it writes; tpa reads it back (shortest round-trip text).
    for key in ["hardness_N", "cohesiveness", "springiness", "resilience", "gumminess_N", "chewiness_N", "split_s"] {
        let (a, b) = (get(tpa, key), get(&written, key));
        assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0), "{key}: tpa {a} vs press {b}");
    }
    let force = read_force_csv(&cwd.join("dc/force.csv"));
    let split = get(tpa, "split_s");
    // The plate leaves the specimen at 10.5 s and comes back from 15 s on.
    assert!(split > 10.0 && split < 27.5, "split {split}");
    let (t1, f1) = peak_before(&force, split);
    let (t2, f2) = peak_before(&force.iter().filter(|r| r.0 >= split).copied().collect::<Vec<_>>(), f64::INFINITY);
    // serde_json reads a float back to within a unit in the last place.
    let same = |a: f64, b: f64, what: &str| assert!((a - b).abs() <= 1e-14 * b.abs(), "{what}: {a} vs {b}");
    same(get(tpa, "hardness_N"), f1, "hardness");
    same(get(&tpa["strokes"][0], "peak_s"), t1, "peak 1 time");
    same(get(&tpa["strokes"][1], "peak_N"), f2, "peak 2");
    same(get(&tpa["strokes"][1], "peak_s"), t2, "peak 2 time");
    // Peaks where the plate is deepest (10 s and 27.5 s).
    assert!((t1 - 10.0).abs() < 0.5 && (t2 - 27.5).abs() < 0.5, "peaks at {t1} and {t2} s");
    let (cohesiveness, springiness, resilience) =
        (get(tpa, "cohesiveness"), get(tpa, "springiness"), get(tpa, "resilience"));
    // The areas by a trapezoid rule of their own on force.csv (the force is
    // positive from touch to end, so F+ = F), linear between the rows.
    let interpolate = |t: f64| {
        let i = force.partition_point(|r| r.0 < t).clamp(1, force.len() - 1);
        let (a, b) = (force[i - 1], force[i]);
        a.1 + (t - a.0) / (b.0 - a.0) * (b.1 - a.1)
    };
    let integral = |from: f64, to: f64| {
        let mut points = vec![(from, interpolate(from))];
        points.extend(force.iter().copied().filter(|r| r.0 > from && r.0 < to));
        points.push((to, interpolate(to)));
        points.windows(2).map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0)).sum::<f64>()
    };
    let mut areas = Vec::new();
    for k in 0..2 {
        let stroke = &tpa["strokes"][k];
        let (touch, peak, end) = (get(stroke, "touch_s"), get(stroke, "peak_s"), get(stroke, "end_s"));
        assert!(
            (interpolate(touch) - 0.1).abs() <= 1e-9,
            "stroke {k}: touch at {touch} s, force {}",
            interpolate(touch)
        );
        assert!((interpolate(end) - 0.1).abs() <= 1e-9, "stroke {k}: end at {end} s, force {}", interpolate(end));
        for (from, to, key) in [(touch, peak, "area_to_peak_N_s"), (peak, end, "area_after_peak_N_s")] {
            let (mine, theirs) = (integral(from, to), get(stroke, key));
            assert!((mine - theirs).abs() <= 1e-9 * theirs, "stroke {k} {key}: {mine} vs {theirs}");
            areas.push(mine);
        }
    }
    assert!((cohesiveness - (areas[2] + areas[3]) / (areas[0] + areas[1])).abs() <= 1e-9, "{areas:?}");
    assert!((resilience - areas[1] / areas[0]).abs() <= 1e-9, "{areas:?}");
    // The residual deformation shortens stroke 2: less area and a later touch.
    assert!(cohesiveness > 0.3 && cohesiveness < 1.0, "cohesiveness {cohesiveness}");
    assert!(springiness > 0.3 && springiness < 1.0, "springiness {springiness}");
    // The plate rises in 0.5 s, far faster than the specimen recovers.
    assert!(resilience > 0.0 && resilience < 0.2, "resilience {resilience}");
    assert!((get(tpa, "gumminess_N") - f1 * cohesiveness).abs() <= 1e-12 * f1);
    assert!((get(tpa, "chewiness_N") - f1 * cohesiveness * springiness).abs() <= 1e-12 * f1);
    let csv = std::fs::read_to_string(cwd.join("tpa/tpa.csv")).unwrap();
    assert!(csv.starts_with("input,hardness_N,cohesiveness,springiness,resilience,gumminess_N,chewiness_N,"), "{csv}");
    assert_eq!(csv.lines().count(), 2);
    let svg = std::fs::read_to_string(cwd.join("tpa/tpa.svg")).unwrap();
    assert!(svg.contains("time [s]") && svg.contains("force [N]") && svg.contains("A4"), "tpa.svg lacks labels");
    read_summary_marker(&cwd.join("tpa"));
    // Again without --force: refused, nothing changes.
    let before = contents(&cwd.join("tpa"));
    let again = wagashi_in(cwd, ["tpa", "dc", "-o", "tpa"]);
    assert!(assert_one_line_error(&again).contains("--force"));
    assert_eq!(contents(&cwd.join("tpa")), before);
}

fn read_summary_marker(dir: &Path) {
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["command"], "tpa", "{s}");
}

/// A record with one compression, or none above the threshold, is one line
/// naming the file and the line; the output folder is not created.
#[test]
fn tpa_refuses_a_single_compression_and_no_contact() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let triangle: String = (0..=100)
        .map(|i| {
            let t = i as f64 * 0.2;
            format!("{t},{}\n", if t < 10.0 { 0.2 * t } else { (4.0 - 0.4 * (t - 10.0)).max(0.0) })
        })
        .collect();
    write_files(&cwd.join("one"), &[("force.csv", &format!("t_s,force_N\n{triangle}"))]);
    let line = assert_one_line_error(&wagashi_in(cwd, ["tpa", "one", "-o", "out"]));
    assert!(line.contains("one/force.csv:") && line.contains("force_N: no second stroke"), "{line}");
    write_files(&cwd.join("flat"), &[("force.csv", "t_s,force_N\n0,0\n1,0.05\n2,0.02\n")]);
    let line = assert_one_line_error(&wagashi_in(cwd, ["tpa", "flat", "--threshold-N", "0.1"]));
    assert!(line.contains("flat/force.csv:3: force_N: no contact"), "{line}");
    assert!(!cwd.join("out").exists());
}

/// The fungi-steak double compression (a rheometer export, read as `wagashi
/// import` reads it): the hardness is the record's first-stroke peak above its
/// tare (the mean force of the first 2 s, before the plate touches; the
/// detected tare is the mean of a longer quiet segment, within 2 mN of it at
/// this noise), at the record's own peak sample.
#[test]
fn tpa_of_the_shared_fungi_double_compression() {
    if skip_without_shared_data("the fungi-steak double compressions") {
        return;
    }
    let file = shared_data_path().join("real/fungi-steak/double-compression-slowest-inplane-1.txt");
    let tmp = tempfile::tempdir().unwrap();
    let o = wagashi_in(tmp.path(), [std::ffi::OsStr::new("tpa"), file.as_os_str(), "--json".as_ref()]);
    assert_success(&o);
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let tpa = &json[0];
    let get = |v: &serde_json::Value, key: &str| v[key].as_f64().unwrap_or_else(|| panic!("no {key} in {v}"));
    // Time (s) is column 1 and Normal force (N) column 5 of the export.
    let text = std::fs::read_to_string(&file).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    assert_eq!((header[0], header[4]), ("Time (s)", "Normal force (N)"));
    let rows: Vec<(f64, f64)> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            (c[0].trim().parse().unwrap(), c[4].trim().parse().unwrap())
        })
        .collect();
    let quiet: Vec<f64> = rows.iter().filter(|r| r.0 < 2.0).map(|r| r.1).collect();
    let tare = quiet.iter().sum::<f64>() / quiet.len() as f64;
    let (t_peak, peak) = peak_before(&rows, get(tpa, "split_s"));
    let hardness = get(tpa, "hardness_N");
    println!("fungi 1: hardness {hardness:.4} N, record's first-stroke peak {peak:.4} N above a tare of {tare:.4} N");
    assert!((hardness - (peak - tare)).abs() <= 2e-3, "hardness {hardness} vs {peak} - {tare}");
    assert!((get(&tpa["strokes"][0], "peak_s") - t_peak).abs() <= 1e-12 * t_peak, "peak at {t_peak} s");
    for key in ["cohesiveness", "springiness", "resilience"] {
        let v = get(tpa, key);
        assert!(v > 0.0 && v < 1.0, "{key} = {v}");
    }
}
