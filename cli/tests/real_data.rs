//! Real data end to end (issue: parameter identification, "Real data"): import the
//! fungi-steak double compressions (../shared/data/real/fungi-steak), fit the
//! five-element model to specimen 1's first stroke with the axisymmetric model, and
//! predict specimens 2 and 3. The test asserts that the pipeline runs and that its
//! numbers are finite and self-consistent; the numbers themselves (how badly a
//! linear model fits a 50 % compression) are printed and recorded in VALIDATION.md.
//!
//! The second stroke: the whole double compression (`--stroke all`) imported with
//! frictionless plates, so that the plate following the measured gap is a contact
//! tool that leaves the specimen and touches it again, run with the parameters
//! fitted to specimen 1's first stroke. Its errors are measured per stroke, split
//! at the measured second touch.
//!
//! Without the shared data folder the tests skip (`tests/support/data.rs`).

mod common;

use std::path::PathBuf;

use common::*;

/// The fungi-steak records (the test has checked that the shared data folder is there).
fn fungi() -> PathBuf {
    let dir = shared_data_path().join("real/fungi-steak");
    assert!(dir.is_dir(), "{} is missing from the shared data folder", dir.display());
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
    if skip_without_shared_data("the fungi-steak records") {
        return;
    }
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

    // The second stroke, predicted for every specimen.
    let mut args = vec!["import", "rheometer"];
    args.extend(files.iter().map(String::as_str));
    args.extend(["--cylinder-radius-mm", "4", "--stroke", "all", "--contact", "frictionless", "-o", "whole"]);
    assert_success(&wagashi_in(cwd, &args));
    for i in 1..=3 {
        let bundle = cwd.join(format!("whole/double-compression-slowest-inplane-{i}"));
        let out = format!("second{i}");
        let input = bundle.to_str().unwrap();
        let o = wagashi_in(cwd, ["press", input, "--materials", "fit/materials.toml", "--axisymmetric", "-o", &out]);
        assert_success(&o);
        // A contact run: the plate is a tool with its own track.
        assert!(cwd.join(&out).join("tools.csv").is_file(), "specimen {i}: no contact tool in the run");
        let facts = read_json(&bundle.join("summary.json"));
        let second_touch = facts["import"]["second_touch_s"].as_f64().expect("two strokes found");
        let threshold = facts["import"]["touch_threshold_N"].as_f64().unwrap();
        let measured = read_force_csv(&bundle.join("force.csv"));
        let simulated = read_force_csv(&cwd.join(&out).join("force.csv"));
        assert_eq!(measured.len(), simulated.len(), "specimen {i}: the run is sampled at the measured times");
        for (m, s) in measured.iter().zip(&simulated) {
            assert_eq!(m.0, s.0, "specimen {i}: sample times differ");
        }
        let strokes = [
            stroke_errors(&measured, &simulated, |t| t < second_touch),
            stroke_errors(&measured, &simulated, |t| t >= second_touch),
        ];
        // The simulated plate leaves the specimen between the strokes and touches
        // it again: the force drops below the touch threshold after the first
        // peak and rises above it later.
        // (The measured curve's own second touch is the importer's, which asks the
        // force to stay above the threshold; the simulated curve has no noise.)
        let sim_touch = second_touch_of(&simulated, threshold).expect("the simulated plate touches again");
        for (k, e) in strokes.iter().enumerate() {
            println!(
                "specimen {i}, stroke {}: measured peak {:.4} N, simulated {:.4} N ({:+.1} %), rms {:.4} N ({:.1} % of \
                 the measured peak)",
                k + 1,
                e.measured_peak,
                e.simulated_peak,
                100.0 * (e.simulated_peak / e.measured_peak - 1.0),
                e.rms,
                100.0 * e.rms / e.measured_peak
            );
            assert!(e.rms.is_finite() && e.rms > 0.0 && e.simulated_peak > 0.0 && e.measured_peak > 0.0);
        }
        println!(
            "specimen {i}: second touch measured at {second_touch:.2} s, simulated at {sim_touch:.2} s; stroke 2 \
             peak / stroke 1 peak measured {:.3}, simulated {:.3}",
            strokes[1].measured_peak / strokes[0].measured_peak,
            strokes[1].simulated_peak / strokes[0].simulated_peak
        );
        assert!(sim_touch > strokes_peak_time(&simulated), "specimen {i}: touched again at {sim_touch} s");
    }
}

/// The network model on the whole double compressions (issue: network model,
/// verification 7): imported with `--model network --stroke all` (the default
/// structure, frictionless contact plates), fitted jointly to the three records on
/// the axisymmetric section, and each record run with the fitted material.
///
/// Asserted per record, the targets: after one stiffness scale per
/// record the force RMS is at most 5 % of the measured peak, and the
/// second-stroke retention (stroke 2 peak over stroke 1 peak, split at the
/// measured second touch) is within 0.05 of the measured one. Measured: 2.0,
/// 4.6 and 2.8 % (scales 1.256, 0.761, 0.702); retention 0.925, 0.912, 0.922
/// against 0.918, 0.922, 0.926 (VALIDATION.md).
#[test]
fn fungi_steak_network_fit_of_the_whole_double_compressions_meets_the_targets() {
    if skip_without_shared_data("the fungi-steak records") {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let files: Vec<String> = (1..=3)
        .map(|i| fungi().join(format!("double-compression-slowest-inplane-{i}.txt")).display().to_string())
        .collect();
    let mut args = vec!["import", "rheometer"];
    args.extend(files.iter().map(String::as_str));
    args.extend(["--cylinder-radius-mm", "4", "--model", "network", "--stroke", "all", "-o", "net"]);
    assert_success(&wagashi_in(cwd, &args));
    let bundles: Vec<String> = (1..=3).map(|i| format!("net/double-compression-slowest-inplane-{i}")).collect();
    let mut args = vec!["fit"];
    args.extend(bundles.iter().map(String::as_str));
    args.extend(["--procedure", "joint", "--axisymmetric", "-o", "fit"]);
    let fit = wagashi_in(cwd, &args);
    assert_success(&fit);
    println!("{}", stdout(&fit));
    // Both passes report the misfit in the records' own noise units: the
    // second pass's rescaled channels do not make it 1 by construction.
    let json = read_json(&cwd.join("fit/fit.json"));
    let rms: Vec<f64> =
        json["steps"].as_array().unwrap().iter().map(|s| s["rms_noise_units"].as_f64().unwrap()).collect();
    assert_eq!(rms.len(), 2, "{json}");
    assert!(rms[0] > 5.0 && (rms[1] / rms[0] - 1.0).abs() < 0.5, "rms of the two passes: {rms:?}");
    for (i, bundle) in bundles.iter().enumerate() {
        let out = format!("run{}", i + 1);
        assert_success(&wagashi_in(
            cwd,
            ["press", bundle, "--materials", "fit/materials.toml", "--axisymmetric", "-o", &out],
        ));
        let facts = read_json(&cwd.join(bundle).join("summary.json"));
        let second_touch = facts["import"]["second_touch_s"].as_f64().expect("two strokes found");
        let measured = read_force_csv(&cwd.join(bundle).join("force.csv"));
        let simulated = read_force_csv(&cwd.join(&out).join("force.csv"));
        assert_eq!(measured.len(), simulated.len());
        let peak = measured.iter().fold(0.0f64, |p, m| p.max(m.1.abs()));
        let scale = measured.iter().zip(&simulated).map(|(m, s)| m.1 * s.1).sum::<f64>()
            / simulated.iter().map(|s| s.1 * s.1).sum::<f64>();
        let rms = (measured.iter().zip(&simulated).map(|(m, s)| (m.1 - scale * s.1).powi(2)).sum::<f64>()
            / measured.len() as f64)
            .sqrt()
            / peak;
        let strokes = [
            stroke_errors(&measured, &simulated, |t| t < second_touch),
            stroke_errors(&measured, &simulated, |t| t >= second_touch),
        ];
        let retention = |e: &[StrokeErrors; 2], simulated: bool| {
            if simulated {
                e[1].simulated_peak / e[0].simulated_peak
            } else {
                e[1].measured_peak / e[0].measured_peak
            }
        };
        let (measured_f2f1, simulated_f2f1) = (retention(&strokes, false), retention(&strokes, true));
        println!(
            "specimen {}: force rms {:.1} % of the peak after the scale {scale:.3}; F2/F1 measured {measured_f2f1:.3}, \
             simulated {simulated_f2f1:.3}",
            i + 1,
            100.0 * rms
        );
        assert!(rms <= 0.05, "specimen {}: rms {:.1} % of the peak after one scale", i + 1, 100.0 * rms);
        assert!(
            (simulated_f2f1 - measured_f2f1).abs() <= 0.05,
            "specimen {}: retention {simulated_f2f1:.3} against {measured_f2f1:.3}",
            i + 1
        );
    }
}

fn read_json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// A stroke's peaks and RMS force error over the samples whose time passes `inside`.
struct StrokeErrors {
    measured_peak: f64,
    simulated_peak: f64,
    rms: f64,
}

fn stroke_errors(measured: &[(f64, f64)], simulated: &[(f64, f64)], inside: impl Fn(f64) -> bool) -> StrokeErrors {
    let (mut mp, mut sp, mut sum, mut n) = (f64::MIN, f64::MIN, 0.0, 0usize);
    for (m, s) in measured.iter().zip(simulated).filter(|(m, _)| inside(m.0)) {
        mp = mp.max(m.1);
        sp = sp.max(s.1);
        sum += (s.1 - m.1).powi(2);
        n += 1;
    }
    assert!(n > 0, "an empty stroke");
    StrokeErrors { measured_peak: mp, simulated_peak: sp, rms: (sum / n as f64).sqrt() }
}

/// The time of the first stroke's peak: the largest force in the test's first half.
fn strokes_peak_time(force: &[(f64, f64)]) -> f64 {
    let half = force.last().map_or(0.0, |p| p.0 / 2.0);
    force.iter().filter(|p| p.0 < half).max_by(|a, b| a.1.total_cmp(&b.1)).map_or(0.0, |p| p.0)
}

/// The time a noise-free force rises above `threshold` again after falling below
/// it following the first stroke's peak.
fn second_touch_of(force: &[(f64, f64)], threshold: f64) -> Option<f64> {
    let peak = strokes_peak_time(force);
    let apart = force.iter().position(|p| p.0 > peak && p.1 < threshold)?;
    force[apart..].iter().find(|p| p.1 > threshold).map(|p| p.0)
}

/// The gap diagnosis on the real data (issue: gap diagnosis, "Real data"):
/// calibrated on specimen 1's first stroke, validated on specimen 2's first
/// stroke and on its whole double compression, whose plate is a contact tool.
/// Contact runs have no sensitivities, so the held-out check anchors that trial
/// on finite differences. The material-point effect strain-stiffening runs on
/// that trial thanks to the contact fixed point on the operator scaled to the
/// stiffest tangent (`fem_core::press` inelastic module, "Stiffer tangents") and
/// pairs in contact starting each step on their tool; without them it diverges
/// (step 24, t = 2.47 s).
///
/// Asserted: the three candidates evaluated, with finite held-out gap
/// closures. strain-stiffening is significant on the calibration trial but
/// makes the held-out trials worse beyond noise, so the non-inferiority veto
/// (diagnosis-details.md §5.4: `Delta_ho > -2 SE`, the SE of the paired block
/// bootstrap) takes it out, force-offset likewise, and the verdict is
/// `unexplained`. Measured: strain-stiffening LR 1.51e5, held-out gain -5.57e5
/// against SE 1.19e5 (-4.7 SE; the whole-segment SE of 8.32e5 would keep it
/// eligible, the verdict then `partial: strain-stiffening` with G = -0.35);
/// force-offset gain -7.70e7
/// against SE 5.53e5. finite-strain (full Green-Lagrange kinematics blended in
/// by `lambda_g`, its score a secant at `lambda_g` = 1/2 because the runs at 1
/// invert on this stroke) is not significant: the score's expected change
/// points to `lambda_g < 0` (LM 0 by the one-sided rule), the refit stays at
/// `lambda_g` = 0 and LR 1.1 against its critical value 7.36. Asserted: its
/// LR under the critical value and the fitted `lambda_g` below 0.05.
#[test]
fn fungi_steak_diagnosis_validates_on_a_double_compression() {
    if skip_without_shared_data("the fungi-steak records") {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let files: Vec<String> = (1..=2)
        .map(|i| fungi().join(format!("double-compression-slowest-inplane-{i}.txt")).display().to_string())
        .collect();
    for (out, extra) in [("first", vec![]), ("all", vec!["--stroke", "all", "--contact", "frictionless"])] {
        let mut args = vec!["import", "rheometer"];
        args.extend(files.iter().map(String::as_str));
        args.extend(["--cylinder-radius-mm", "4", "-o", out]);
        args.extend(extra);
        assert_success(&wagashi_in(cwd, &args));
    }
    let o = wagashi_in(
        cwd,
        [
            "diagnose",
            "--calibrate",
            "first/double-compression-slowest-inplane-1",
            "--validate",
            "first/double-compression-slowest-inplane-2",
            "all/double-compression-slowest-inplane-2",
            "--axisymmetric",
            "--effects",
            "strain-stiffening,force-offset,finite-strain",
            "-o",
            "diag",
        ],
    );
    assert_success(&o);
    println!("{}", stdout(&o));
    let d = read_json(&cwd.join("diag/diagnosis.json"));
    assert_eq!(d["validation_trials"].as_array().map(Vec::len), Some(2), "{d}");
    for effect in ["force-offset", "strain-stiffening", "finite-strain"] {
        let g = d["candidates"][effect]["gap_closure"]["value"].as_f64();
        assert!(g.is_some_and(f64::is_finite), "{effect}'s held-out gap closure: {d}");
        assert!(d["not_evaluated"].get(effect).is_none(), "{effect} not evaluated: {}", d["not_evaluated"]);
    }
    let num = |effect: &str, key: &str| d["candidates"][effect][key].as_f64().unwrap();
    for effect in ["force-offset", "strain-stiffening"] {
        assert_eq!(d["candidates"][effect]["significant"], true, "{effect}: {}", d["candidates"][effect]);
        assert!(
            num(effect, "heldout_gain") < -2.0 * num(effect, "heldout_gain_se"),
            "{effect}: {}",
            d["candidates"][effect]
        );
        assert_eq!(d["candidates"][effect]["eligible"], false, "{effect}: {}", d["candidates"][effect]);
    }
    assert_eq!(d["verdict"]["label"], "unexplained", "{}", d["verdict"]);
    let finite = &d["candidates"]["finite-strain"];
    assert!(num("finite-strain", "lr") < num("finite-strain", "lr_critical"), "{finite}");
    let lambda_g = finite["parameters"]["finite_strain"]["value"].as_f64().unwrap();
    assert!((0.0..0.05).contains(&lambda_g), "{finite}");
}
