//! Real data end to end (issue: parameter identification, "Real data"): import the
//! fungi-steak double compressions (../shared/data/real/fungi-steak), fit the
//! five-element model to specimen 1's first stroke with the axisymmetric model, and
//! predict specimens 2 and 3. The test asserts that the pipeline runs and that its
//! numbers are finite and self-consistent; the numbers themselves (how badly a
//! linear model fits a 50 % compression) are printed and recorded in VALIDATION.md.

mod common;

use std::path::PathBuf;

use common::*;

fn fungi() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/real/fungi-steak");
    assert!(
        dir.is_dir(),
        "{} is missing: this test reads the shared measured data beside the checkout (../shared/data)",
        dir.display()
    );
    dir
}

fn summary_rms(dir: &std::path::Path) -> (f64, f64) {
    let s = read_summary(dir);
    let text = s.to_string();
    let rms = s["force_rms_diff_N"].as_f64().unwrap_or_else(|| panic!("no rms in {text}"));
    let peak = s["peak_force_N"].as_f64().unwrap_or_else(|| panic!("no peak in {text}"));
    (rms, peak)
}

#[test]
fn fungi_steak_first_stroke_fits_and_predicts_the_other_specimens() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let files: Vec<String> = (1..=3)
        .map(|i| fungi().join(format!("double-compression-slowest-inplane-{i}.txt")).display().to_string())
        .collect();
    let mut args = vec!["import", "rheometer"];
    args.extend(files.iter().map(String::as_str));
    args.extend(["--cylinder-radius-mm", "4", "-o", "bundles"]);
    assert_success(&wagashi_in(cwd, &args));
    // The import gives the material by its model only (five-element): all unknown.
    let fit = wagashi_in(cwd, ["fit", "bundles/double-compression-slowest-inplane-1", "--axisymmetric", "-o", "fit"]);
    assert_success(&fit);
    println!("{}", stdout(&fit));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("fit/fit.json")).unwrap()).unwrap();
    for key in ["E1_MPa", "E2_MPa", "c1_MPa_s", "c2_MPa_s", "c3_MPa_s"] {
        let v = json["sets"]["force"]["sample"][key]["value"].as_f64().unwrap();
        assert!(v.is_finite() && v > 0.0, "{key} = {v}");
    }
    // The keep and final steps have no marker data: skipped, and said so.
    let steps = json["steps"].as_array().unwrap();
    assert!(steps.iter().any(|s| s["name"] == "keep-shape" && s["skipped"].is_string()), "{json}");
    for i in 1..=3 {
        let out = format!("pred{i}");
        let o = wagashi_in(
            cwd,
            [
                "press",
                &format!("bundles/double-compression-slowest-inplane-{i}"),
                "--materials",
                "fit/materials.toml",
                "--axisymmetric",
                "-o",
                &out,
            ],
        );
        assert_success(&o);
        let (rms, peak) = summary_rms(&cwd.join(&out));
        println!("specimen {i}: simulated peak {peak:.4} N, force rms vs measured {rms:.4} N");
        assert!(rms.is_finite() && rms > 0.0 && peak.is_finite() && peak > 0.0);
    }
}
