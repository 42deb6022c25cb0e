//! `wagashi diagnose` end to end: three 2D trials at different speeds and holds
//! are simulated by `wagashi press` with a machine compliance the diagnosis is
//! not told about, given deterministic force noise, and diagnosed (also with one
//! trial held out by `--validate`); the reports are laid out in headless
//! Chromium with no clipped label (`tests/browser/harness.rs` says when that
//! runs: always on CI); bad input is refused in one line.

mod common;
#[path = "../../tests/browser/harness.rs"]
mod harness;

use std::path::Path;

use common::*;

/// (push [s], hold [s]) of the three trials; push depth 1.5 mm, 15 s of recovery.
const DESIGN: [(f64, f64); 3] = [(5.0, 10.0), (10.0, 20.0), (2.5, 5.0)];

fn experiment(name: &str, push: f64, hold: f64, material: &str, tail: &str) -> String {
    let release = push + hold;
    let end = release + 15.0;
    format!(
        r#"format = "wagashi-experiment/1"
name = "{name}"
dimension = 2

[specimen]
shape = "block"
size_mm = [20.0, 15.0, 10.0]
density_g_cm3 = 1.1
material = "gel"

[materials.gel]
model = "three-element"
poisson = 0.3
{material}
[protocol]
tool = "plate"
tool_contact = "frictionless"
support = "glued"
waypoints = [[0.0, 0.0], [{push}, 1.5], [{release}, 1.5]]
release_s = {release}
end_s = {end}
{tail}"#
    )
}

/// A standard normal deviate stream (xorshift64* and Box-Muller): the test's own
/// deterministic noise.
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn gaussian(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// Simulates the three trials with `effects` and writes the measured bundles
/// `meas0..2` (material by model and Poisson's ratio only, no effect, force
/// with noise of 3 mN) and `mark0..2` (the same with three markers).
fn campaign(cwd: &Path, effects: &str) {
    let mut noise = Noise(0x5eed_1234_abcd);
    for (k, &(push, hold)) in DESIGN.iter().enumerate() {
        let truth = cwd.join(format!("truth{k}"));
        std::fs::create_dir_all(&truth).unwrap();
        let material = "E1_MPa = 0.05\nc1_MPa_s = 0.05\nc3_MPa_s = 5.0\n";
        // Three markers on the free side and the top, photographed late in the
        // hold and twice in the recovery; the truth's run gives their places.
        let release = push + hold;
        let mut markers = String::from("marker,t_s,x_mm,y_mm\n");
        for (name, x, y) in [("side-low", 20.0, 4.0), ("side-high", 20.0, 11.0), ("top", 6.0, 15.0)] {
            for t in [0.0, release - 1.0, release + 5.0, release + 15.0] {
                markers.push_str(&format!("{name},{t},{x},{y}\n"));
            }
        }
        std::fs::write(truth.join("markers.csv"), markers).unwrap();
        let tail = format!("{effects}\n[data]\nmarkers = \"markers.csv\"\n");
        std::fs::write(truth.join("experiment.toml"), experiment("t", push, hold, material, &tail)).unwrap();
        let sim = format!("sim{k}");
        assert_success(&wagashi_in(
            cwd,
            ["press", &format!("truth{k}"), "-o", &sim, "--size-mm", "5", "--output-dt", "0.1"],
        ));
        let force = read_force_csv(&cwd.join(&sim).join("force.csv"));
        let meas = cwd.join(format!("meas{k}"));
        std::fs::create_dir_all(&meas).unwrap();
        let mut csv = String::from("t_s,force_N\n");
        for (t, f) in force {
            csv.push_str(&format!("{t},{}\n", f + 3e-3 * noise.gaussian()));
        }
        std::fs::write(meas.join("force.csv"), &csv).unwrap();
        let text = experiment(&format!("trial{k}"), push, hold, "", "\n[data]\nforce = \"force.csv\"\n");
        std::fs::write(meas.join("experiment.toml"), text).unwrap();
        // The same trial with the markers too (noise-free).
        let mark = cwd.join(format!("mark{k}"));
        std::fs::create_dir_all(&mark).unwrap();
        std::fs::write(mark.join("force.csv"), &csv).unwrap();
        std::fs::copy(cwd.join(&sim).join("markers.csv"), mark.join("markers.csv")).unwrap();
        let tail = "\n[data]\nforce = \"force.csv\"\nmarkers = \"markers.csv\"\n";
        std::fs::write(mark.join("experiment.toml"), experiment(&format!("trial{k}"), push, hold, "", tail)).unwrap();
    }
}

/// The withheld compliance (0.2 mm/N) is named with label = its id and fitted
/// back within 10 %; every required field of diagnosis.json is there; the
/// inputs are not modified.
#[test]
fn a_withheld_machine_compliance_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    campaign(cwd, "\n[effects]\nmachine_compliance_mm_per_N = 0.2\n");
    let before = contents(&cwd.join("meas0"));
    let o = wagashi_in(
        cwd,
        ["diagnose", "--calibrate", "meas0", "meas1", "meas2", "--size-mm", "5", "--starts", "1", "-o", "diag"],
    );
    assert_success(&o);
    assert_eq!(contents(&cwd.join("meas0")), before, "the input bundle was modified");
    let d: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cwd.join("diag/diagnosis.json")).unwrap()).unwrap();
    assert_eq!(d["verdict"]["label"], "machine-compliance", "{:#}", d["verdict"]);
    assert_eq!(d["verdict"]["effects"], serde_json::json!(["machine-compliance"]));
    let c = &d["candidates"]["machine-compliance"];
    let k = c["parameters"]["machine_compliance_mm_per_N"]["value"].as_f64().unwrap();
    assert!((k - 0.2).abs() < 0.02, "1/k_m = {k}");
    for key in ["score_statistic", "lr", "p_value", "heldout_gain"] {
        assert!(c[key].is_number(), "candidates.machine-compliance.{key}: {c:#}");
    }
    let g = &c["gap_closure"];
    let (lo, v, hi) = (g["ci90"][0].as_f64().unwrap(), g["value"].as_f64().unwrap(), g["ci90"][1].as_f64().unwrap());
    assert!(lo <= v && v <= hi && v > 0.8, "{g:#}");
    let cells = d["where"].as_array().unwrap();
    assert!(!cells.is_empty());
    for cell in cells {
        for key in ["phase", "channel", "region", "rms_noise_units", "p_value", "flagged"] {
            assert!(!cell[key].is_null(), "where entry lacks {key}: {cell}");
        }
    }
    assert!(cells.iter().any(|c| c["flagged"] == true), "a gap this size flags a cell");
    assert!(d["numerical_error"]["chi2_noise_units"].is_number());
    // The campaign's stress level: the largest measured force over the 20 x 10 mm top face.
    let peak = (0..3)
        .flat_map(|k| read_force_csv(&cwd.join(format!("meas{k}/force.csv"))))
        .map(|(_, f)| f)
        .fold(f64::MIN, f64::max);
    let sigma = d["peak_stress_MPa"].as_f64().unwrap();
    assert!((sigma - peak / 200.0).abs() < 1e-9 * sigma, "{sigma} MPa against {peak} N / 200 mm^2");
    // Effects the engine does not simulate are listed, not evaluated.
    assert!(d["not_evaluated"]["plastic-slider"].is_string() || d["candidates"]["plastic-slider"].is_object());
    assert!(stdout(&o).contains("verdict: machine-compliance"), "{}", stdout(&o));
    // The report: one self-contained, well-formed page naming the verdict.
    let html = std::fs::read_to_string(cwd.join("diag/report.html")).unwrap();
    assert!(
        html.contains("machine-compliance") && html.contains("<svg") && !html.contains("http://www.w3.org/1999/xlink")
    );
    assert!(!html.contains("<script") && !html.contains("src=\"http"), "no network");
    roxmltree::Document::parse(html.trim_start_matches("<!DOCTYPE html>")).expect("report.html is well-formed");
    assert!(d["marker_shapes"].as_array().unwrap().is_empty() && !html.contains("Marker shapes"), "no markers");

    // With markers: the same verdict, and the marker shapes before and after
    // (per trial, the last photograph of the hold and of the recovery). The
    // measured places are the truth's (noise-free); in the hold, where the
    // compliance acts, the named effect brings the simulated markers at least
    // twice as close to them as the baseline does.
    let o = wagashi_in(
        cwd,
        ["diagnose", "--calibrate", "mark0", "mark1", "mark2", "--size-mm", "5", "--starts", "1", "-o", "diag-m"],
    );
    assert_success(&o);
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cwd.join("diag-m/diagnosis.json")).unwrap()).unwrap();
    assert_eq!(m["verdict"]["label"], "machine-compliance", "{:#}", m["verdict"]);
    let html = std::fs::read_to_string(cwd.join("diag-m/report.html")).unwrap();
    assert!(html.contains("Marker shapes"), "the report shows the marker shapes");
    roxmltree::Document::parse(html.trim_start_matches("<!DOCTYPE html>")).expect("report.html is well-formed");
    let shapes = m["marker_shapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 2 * DESIGN.len(), "{shapes:#?}");
    let rms = |s: &serde_json::Value, key: &str| {
        let m = s["markers"].as_array().unwrap();
        let sum: f64 = m
            .iter()
            .map(|e| {
                let (a, b) = (e[key].as_array().unwrap(), e["measured_mm"].as_array().unwrap());
                a.iter().zip(b).map(|(x, y)| (x.as_f64().unwrap() - y.as_f64().unwrap()).powi(2)).sum::<f64>()
            })
            .sum();
        (sum / m.len() as f64).sqrt()
    };
    for s in shapes.iter().filter(|s| s["phase"] == "hold") {
        assert_eq!(s["markers"].as_array().unwrap().len(), 3);
        let (before, after) = (rms(s, "baseline_mm"), rms(s, "with_effect_mm"));
        assert!(after < 0.5 * before, "{}: RMS {before} mm before, {after} mm after", s["trial"]);
    }

    // Calibrated on two trials and validated on the third: the same verdict, the
    // gap closure measured on the held-out trial, the validation trial named.
    let o = wagashi_in(
        cwd,
        [
            "diagnose",
            "--calibrate",
            "meas0",
            "meas1",
            "--validate",
            "meas2",
            "--size-mm",
            "5",
            "--starts",
            "1",
            "-o",
            "diag-v",
        ],
    );
    assert_success(&o);
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cwd.join("diag-v/diagnosis.json")).unwrap()).unwrap();
    assert_eq!(v["verdict"]["label"], "machine-compliance", "{:#}", v["verdict"]);
    assert_eq!(v["validation_trials"], serde_json::json!(["trial2"]));
    let g = v["candidates"]["machine-compliance"]["gap_closure"]["value"].as_f64().unwrap();
    assert!(g > 0.8, "G on the validation trial = {g}");
    // No label is clipped in any of the three reports, laid out by Chromium.
    let pages = ["diag", "diag-m", "diag-v"].map(|d| cwd.join(d).join("report.html"));
    assert_report_layout(&pages.iter().map(|p| p.as_path()).collect::<Vec<_>>(), cwd);
    // The report draws the validation trial too: every trial's force against
    // time, before and after, on axes with ticks and units.
    let html = std::fs::read_to_string(cwd.join("diag-v/report.html")).unwrap();
    let doc =
        roxmltree::Document::parse(html.trim_start_matches("<!DOCTYPE html>")).expect("report.html is well-formed");
    assert!(html.contains("trial2 (validation)"), "the validation trial's curves are in the report");
    assert_eq!(html.matches("time [s]").count(), 3, "one force plot per trial, each with its time axis");
    assert_eq!(html.matches("force [N]").count(), 3, "one force plot per trial, each with its force axis");
    // Its held-out prediction with the named effect (blue) lies closer to the
    // measured force (grey) than the baseline's (red): RMS distance in the
    // plot's pixels, at least halved (G > 0.8 above).
    let heading = doc
        .descendants()
        .find(|n| n.has_tag_name("h3") && n.text() == Some("trial2 (validation)"))
        .expect("the validation trial's heading");
    let svg = heading.next_sibling_element().filter(|n| n.has_tag_name("svg")).expect("its plot");
    let curve = |colour: &str| -> Vec<(f64, f64)> {
        let line = svg
            .children()
            .find(|n| n.has_tag_name("polyline") && n.attribute("stroke") == Some(colour))
            .unwrap_or_else(|| panic!("no {colour} curve"));
        line.attribute("points")
            .unwrap()
            .split(' ')
            .map(|p| {
                let (x, y) = p.split_once(',').unwrap();
                (x.parse().unwrap(), y.parse().unwrap())
            })
            .collect()
    };
    let (measured, baseline, with) = (curve("#999"), curve("#c0392b"), curve("#2471a3"));
    let rms = |a: &[(f64, f64)]| {
        assert_eq!(a.len(), measured.len());
        (a.iter().zip(&measured).map(|(p, q)| (p.1 - q.1).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
    };
    let (before, after) = (rms(&baseline), rms(&with));
    assert!(
        after < 0.5 * before,
        "validation trial: {before:.2} px from the measured force before, {after:.2} px after"
    );
}

/// Lays `pages` out in headless Chromium and asserts that every SVG label lies
/// inside its SVG and overlaps no other, and that no table cell's content
/// overflows it (skipped with a note when the browser is missing, except on CI).
/// A control page in `scratch` with one defect of each kind shows that the
/// check finds them.
fn assert_report_layout(pages: &[&Path], scratch: &Path) {
    let control = scratch.join("layout-control.html");
    std::fs::write(
        &control,
        r#"<!DOCTYPE html><html><body><svg xmlns="http://www.w3.org/2000/svg" width="200" height="60"><text x="150" y="30" font-size="12">clipped at the right</text><text x="10" y="30" font-size="12">one</text><text x="14" y="34" font-size="12">two</text></svg><table><tr><td style="max-width:30px;overflow:hidden">overflowing-cell-content</td></tr></table></body></html>"#,
    )
    .unwrap();
    let mut all = pages.to_vec();
    all.push(&control);
    let Some(report) = harness::layout(&all) else { return };
    let (reports, control) = report["pages"].as_array().unwrap().split_at(pages.len());
    let found: Vec<&str> = control[0]["defects"].as_array().unwrap().iter().map(|d| d.as_str().unwrap()).collect();
    for kind in ["clipped: ", "overlap: ", "overflow: "] {
        assert_eq!(found.iter().filter(|d| d.starts_with(kind)).count(), 1, "control page, {kind}{found:#?}");
    }
    let mut defects = Vec::new();
    for page in reports {
        let (svgs, texts) = (page["svgs"].as_u64().unwrap(), page["texts"].as_u64().unwrap());
        assert!(svgs >= 2 && texts >= 10, "nothing laid out: {page:#}");
        for d in page["defects"].as_array().unwrap() {
            defects.push(format!("{}: {}", page["file"].as_str().unwrap(), d.as_str().unwrap()));
        }
    }
    assert!(defects.is_empty(), "{} layout defects:\n{}", defects.len(), defects.join("\n"));
}

/// Bad input: an unknown effect id, a bundle without data, an existing output;
/// each refused in one line, with no output folder left behind.
#[test]
fn bad_input_is_refused_in_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    std::fs::create_dir_all(cwd.join("nodata")).unwrap();
    std::fs::write(
        cwd.join("nodata/experiment.toml"),
        experiment("n", 5.0, 10.0, "E1_MPa = 0.05\nc1_MPa_s = 0.05\nc3_MPa_s = 5.0\n", ""),
    )
    .unwrap();
    let line = assert_one_line_error(&wagashi_in(
        cwd,
        ["diagnose", "--calibrate", "nodata", "--effects", "gravity,warp-drive", "-o", "out"],
    ));
    assert!(line.contains("warp-drive") && line.contains("--effects"), "{line}");
    let line = assert_one_line_error(&wagashi_in(cwd, ["diagnose", "--calibrate", "nodata", "-o", "out"]));
    assert!(line.contains("nodata") && line.contains("no measured data"), "{line}");
    let line = assert_one_line_error(&wagashi_in(cwd, ["diagnose", "--calibrate", "missing", "-o", "out"]));
    assert!(line.contains("missing"), "{line}");
    assert!(!cwd.join("out").exists());
}

/// `--blind`: one synthetic campaign (seed 7, two candidates to keep it short)
/// is generated, diagnosed and scored; blind.json has the campaign's record,
/// the scores, the targets and the confusion matrix, and stdout the table.
/// Conflicting or missing arguments are refused by clap (status 2) with
/// nothing written.
#[test]
fn blind_self_check_writes_blind_json() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let o =
        wagashi_in(cwd, ["diagnose", "--blind", "1", "--seed", "7", "--effects", "force-offset,gravity", "-o", "b"]);
    assert_success(&o);
    let b: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("b/blind.json")).unwrap()).unwrap();
    let campaigns = b["campaigns"].as_array().unwrap();
    assert_eq!(campaigns.len(), 1);
    let c = &campaigns[0];
    for key in ["truth", "kind", "lambda_target", "verdict", "column", "top1", "variability", "force_rho", "seconds"] {
        assert!(!c[key].is_null(), "campaign lacks {key}: {c:#}");
    }
    let v = c["variability"].as_f64().unwrap();
    assert!((0.03..=0.10).contains(&v), "variability {v}");
    for r in c["force_rho"].as_array().unwrap() {
        assert!((0.3..=0.7).contains(&r.as_f64().unwrap()));
    }
    if c["kind"] != "null" {
        let (target, eff) = (c["lambda_target"].as_f64().unwrap(), c["lambda_eff"].as_f64().unwrap());
        assert!(c["strength_reached"] == false || (eff / target - 1.0).abs() < 0.2, "{c:#}");
    }
    let s = &b["summary"];
    assert_eq!(s["targets"].as_array().unwrap().len(), 5);
    let row = &s["confusion"][c["truth"].as_str().unwrap()];
    assert_eq!(row[c["column"].as_str().unwrap()], 1, "{s:#}");
    let text = stdout(&o);
    assert!(text.contains("confusion matrix") && text.contains("targets of the diagnosis:"), "{text}");

    let o = wagashi_in(cwd, ["diagnose", "--blind", "2", "--calibrate", "x", "-o", "c"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--calibrate"), "{}", stderr(&o));
    let o = wagashi_in(cwd, ["diagnose", "--blind", "0", "-o", "c"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let o = wagashi_in(cwd, ["diagnose", "-o", "c"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!cwd.join("c").exists());
}
