//! `wagashi import`: the real binary on the shared measured data
//! (`<workspace>/../shared/data`, never copied into the repository; a test that
//! reads it skips without it, see `tests/support/data.rs`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

use wagashi_io::bundle::{MaterialSpec, Model};
use wagashi_io::{read_bundle_with, Bundle};

mod common;

use common::{assert_one_line_error, assert_success, shared_data_path, skip_without_shared_data, stderr, wagashi_in};

// ---- the shared data

/// `<workspace>/../shared/data/real/SUB` (the test has checked that the folder
/// is there), or a failure that says what is missing.
fn data(sub: &str) -> PathBuf {
    let root = shared_data_path();
    let path = root.join("real").join(sub);
    assert!(
        path.is_file(),
        "this test reads the measured data in {} (the shared data folder beside the workspace, \
         <workspace>/../shared/data; see its README.md), and {} is missing",
        root.display(),
        path.display()
    );
    path.canonicalize().unwrap()
}

fn fungi(k: usize) -> PathBuf {
    data(&format!("fungi-steak/double-compression-slowest-inplane-{k}.txt"))
}

fn gel() -> PathBuf {
    data("cmc-gel/sampleGel.tab")
}

/// Reads the bundle with a placeholder material in place of the import's
/// model-only table (which `--model none` leaves out).
fn read_back(dir: &Path) -> Bundle {
    let materials = BTreeMap::from([("sample".to_string(), MaterialSpec::new(Model::Elastic))]);
    read_bundle_with(dir, &materials).unwrap_or_else(|e| panic!("{}: does not read back: {e}", dir.display()))
}

/// `[extra.import] KEY` as a number.
fn fact(bundle: &Bundle, key: &str) -> f64 {
    let extra = bundle.experiment.extra.as_ref().expect("[extra]");
    let v = &extra["import"][key];
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64)).unwrap_or_else(|| panic!("{key} = {v}"))
}

/// The rows of a TA rheometer file, parsed here independently of wagashi-io:
/// (time s, normal force N, gap um).
fn raw_rheometer(path: &Path) -> Vec<(f64, f64, f64)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split('\t').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, f, g) = (col("Time (s)"), col("Normal force (N)"), col("Gap (um)"));
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            (c[t].parse().unwrap(), c[f].parse().unwrap(), c[g].parse().unwrap())
        })
        .collect()
}

fn import(cwd: &Path, kind: &str, files: &[&Path], out: &Path, extra: &[&str]) -> Output {
    let mut args: Vec<std::ffi::OsString> = vec!["import".into(), kind.into()];
    args.extend(files.iter().map(|f| f.as_os_str().to_os_string()));
    args.extend(["-o".into(), out.as_os_str().to_os_string()]);
    args.extend(extra.iter().map(Into::into));
    wagashi_in(cwd, args)
}

#[test]
fn fungi_steak_specimen_1() {
    if skip_without_shared_data("the fungi-steak records") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let input = fungi(1);
    let before = std::fs::read(&input).unwrap();
    let o = import(dir.path(), "rheometer", &[&input], Path::new("out"), &["--cylinder-radius-mm", "4"]);
    assert_success(&o);
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("double-compression-slowest-inplane-1.txt: touch at ") && err.contains("waypoints"), "{err}");

    let out = dir.path().join("out/double-compression-slowest-inplane-1");
    let bundle = read_back(&out);
    let e = &bundle.experiment;
    assert_eq!(e.name, "double-compression-slowest-inplane-1");
    assert_eq!(e.specimen.radius_mm, Some(4.0));

    // The height: the gap at first touch, 8 to 9.5 mm (README of the data).
    let height = e.specimen.height_mm.unwrap();
    assert!((8.0..=9.5).contains(&height), "height {height} mm");

    // The raw file, read here: the gap at the touch time is the height, and the
    // largest force minus the tare is the bundle's peak.
    let raw = raw_rheometer(&input);
    let touch_s = fact(&bundle, "touch_raw_s");
    let at_touch = raw.iter().find(|r| r.0 == touch_s).expect("the touch time is a row's time");
    assert!((at_touch.2 / 1000.0 - height).abs() < 1e-12, "gap {} um, height {height} mm", at_touch.2);
    let raw_peak = raw.iter().map(|r| r.1).fold(f64::MIN, f64::max);
    let tare = fact(&bundle, "tare_N");
    let force = &bundle.force.as_ref().unwrap().samples;
    let peak = force.iter().map(|s| s.force_n).fold(f64::MIN, f64::max);
    assert!((peak - (raw_peak - tare)).abs() < 1e-12, "peak {peak} N, raw {raw_peak} N, tare {tare} N");
    assert!((fact(&bundle, "peak_force_N") - peak).abs() < 1e-12);
    assert!((1.85..2.0).contains(&raw_peak), "raw peak {raw_peak} N");
    assert!(tare.abs() < 0.05 && fact(&bundle, "noise_sigma_N") < 0.01, "tare {tare}");

    // The speed read from the gap: the ramp of specimen 1 runs at 0.225 mm/s
    // (the data's README says "about 0.2"); check it independently: the gap's
    // fall over the loading between 1 and 4 mm of travel, divided by its duration.
    let speed = fact(&bundle, "speed_mm_s");
    let gap0 = at_touch.2;
    let first = raw.iter().find(|r| gap0 - r.2 >= 1000.0).unwrap();
    let last = raw.iter().find(|r| gap0 - r.2 >= 4000.0).unwrap();
    let independent = (first.2 - last.2) / 1000.0 / (last.0 - first.0);
    assert!((speed / independent - 1.0).abs() < 0.01, "speed {speed} vs {independent} mm/s");
    assert!((0.18..=0.25).contains(&speed), "speed {speed} mm/s: about 0.2");

    // The protocol: from [0, 0], increasing, released before the end of the stroke.
    let p = &e.protocol;
    assert_eq!(p.waypoints[0], [0.0, 0.0]);
    assert!(p.waypoints.windows(2).all(|w| w[1][0] > w[0][0]));
    let max_d = p.waypoints.iter().map(|w| w[1]).fold(0.0, f64::max);
    assert!((max_d - 4.5).abs() < 0.1, "compressed {max_d} mm (about 50 %)");
    assert!(p.release_s > fact(&bundle, "peak_force_s") && p.release_s < p.end_s, "{p:?}");
    assert_eq!(force[0].t_s, 0.0);
    assert_eq!(force.last().unwrap().t_s, p.end_s);
    assert_eq!(e.data.as_ref().unwrap().force_tared, Some(true));

    // summary.json, and the input untouched.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["import"]["height_mm"].as_f64(), Some(height));
    assert_eq!(std::fs::read(&input).unwrap(), before);
}

#[test]
fn three_fungi_specimens_in_one_run_and_their_second_strokes() {
    if skip_without_shared_data("the fungi-steak records") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let files = [fungi(1), fungi(2), fungi(3)];
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let o = import(dir.path(), "rheometer", &refs, Path::new("out"), &["--cylinder-radius-mm", "4", "--every", "4"]);
    assert_success(&o);
    assert_eq!(stderr(&o).lines().count(), 3, "{}", stderr(&o));
    let o2 = import(dir.path(), "rheometer", &refs, Path::new("out2"), &["--cylinder-radius-mm", "4", "--stroke", "2"]);
    assert_success(&o2);
    for k in 1..=3 {
        let name = format!("double-compression-slowest-inplane-{k}");
        let one = read_back(&dir.path().join("out").join(&name));
        let two = read_back(&dir.path().join("out2").join(&name));
        let h = one.experiment.specimen.height_mm.unwrap();
        assert!((8.0..=9.5).contains(&h), "specimen {k}: height {h} mm");
        // Stroke 2 starts where stroke 1 ends, on the same clock, and peaks 0-20 % lower.
        let (p1, p2) = (&one.experiment.protocol, &two.experiment.protocol);
        assert!((p2.waypoints[0][0] - p1.end_s).abs() < 1e-9, "specimen {k}");
        assert_eq!(fact(&one, "touch_raw_s"), fact(&two, "touch_raw_s"));
        let (f1, f2) = (fact(&one, "peak_force_N"), fact(&two, "peak_force_N"));
        assert!(f2 < f1 && f2 > 0.8 * f1, "specimen {k}: peaks {f1} and {f2} N");
        assert!(fact(&two, "second_touch_s") > p1.end_s);
    }
}

#[test]
fn cmc_gel_on_the_exponent() {
    if skip_without_shared_data("the CMC gel record") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let args = ["--cylinder-radius-mm", "2.5", "--start-height-mm", "2.5"];
    let o = import(dir.path(), "exponent", &[&gel()], Path::new("out"), &args);
    assert_success(&o);
    let bundle = read_back(&dir.path().join("out/sampleGel"));
    let e = &bundle.experiment;
    // The probe touches the gel about a third of the way down (0.5-1 mm), the peak
    // is about 18 g.
    let h = e.specimen.height_mm.unwrap();
    assert!((1.5..2.0).contains(&h), "height {h} mm");
    let peak = fact(&bundle, "peak_force_N");
    assert!((peak / 9.80665e-3 - 18.0).abs() < 0.5, "peak {peak} N");
    assert!((fact(&bundle, "speed_mm_s") - 0.01).abs() < 1e-4);
    assert_eq!(e.extra.as_ref().unwrap()["import"]["source_test"].as_str(), Some("gel2_I_2_5mm3"));

    // Without a height the Exponent import is a usage error.
    let o = import(dir.path(), "exponent", &[&gel()], Path::new("out2"), &["--cylinder-radius-mm", "2.5"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!dir.path().join("out2").exists());
}

#[test]
fn an_existing_output_is_replaced_only_with_force() {
    if skip_without_shared_data("the fungi-steak records") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let args = ["--cylinder-radius-mm", "4"];
    assert_success(&import(dir.path(), "rheometer", &[&fungi(2)], Path::new("out"), &args));
    let line = assert_one_line_error(&import(dir.path(), "rheometer", &[&fungi(2)], Path::new("out"), &args));
    assert!(line.contains("exists (a previous wagashi output); pass --force"), "{line}");
    let forced =
        import(dir.path(), "rheometer", &[&fungi(2)], Path::new("out"), &["--cylinder-radius-mm", "4", "--force"]);
    assert_success(&forced);
    // A folder that is not a wagashi output is never replaced.
    let other = dir.path().join("mine/double-compression-slowest-inplane-2");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "keep").unwrap();
    let o = import(dir.path(), "rheometer", &[&fungi(2)], Path::new("mine"), &["--cylinder-radius-mm", "4", "--force"]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("refusing to overwrite"), "{line}");
    assert_eq!(std::fs::read_to_string(other.join("notes.txt")).unwrap(), "keep");
}

#[test]
fn a_bad_file_writes_nothing_and_names_its_line() {
    if skip_without_shared_data("the fungi-steak and CMC gel records") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // The gel file read as a rheometer file: wrong header.
    let o = import(dir.path(), "rheometer", &[&fungi(1), &gel()], Path::new("out"), &["--cylinder-radius-mm", "4"]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("sampleGel.tab:1: header: wrong header"), "{line}");
    assert!(!dir.path().join("out").exists(), "nothing is written");
    // A garbled copy: a non-numeric cell.
    let text = std::fs::read_to_string(fungi(3)).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines[99] = "12.5\t0\t0\t0\tabc\t9000\t";
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let line = assert_one_line_error(&import(
        dir.path(),
        "rheometer",
        &[&bad],
        Path::new("out"),
        &["--cylinder-radius-mm", "4"],
    ));
    assert!(line.ends_with("bad.txt:100: Normal force (N): not a number: \"abc\""), "{line}");
    // Only the rest before the plate moves (2.8 s; specimen 1's holds a spike of
    // 7 sigma): no contact.
    for k in [1, 3] {
        let text = std::fs::read_to_string(fungi(k)).unwrap();
        let rest: Vec<&str> = text.lines().take(700).collect();
        let quiet = dir.path().join(format!("quiet{k}.txt"));
        std::fs::write(&quiet, rest.join("\n")).unwrap();
        let o = import(dir.path(), "rheometer", &[&quiet], Path::new("out"), &["--cylinder-radius-mm", "4"]);
        let line = assert_one_line_error(&o);
        assert!(
            line.contains(&format!("quiet{k}.txt:")) && line.contains("Normal force (N): no contact found"),
            "{line}"
        );
    }
    assert!(!dir.path().join("out").exists());
}

#[test]
fn help_shows_an_example_with_the_shared_data() {
    let dir = tempfile::tempdir().unwrap();
    for args in [&["import", "--help"][..], &["import", "rheometer", "--help"], &["import", "exponent", "--help"]] {
        let o = wagashi_in(dir.path(), args);
        assert_success(&o);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("../shared/data/real/fungi-steak/") && text.contains("--cylinder-radius-mm"), "{text}");
    }
}
