//! # The seed's own gap: material 1's two c3, diagnosed
//!
//! What it shows: the seed paper needed two
//! parameter sets for material 1 (Table II: x_force with c3 = 29.7 MPa s for the
//! force, x_shape with c3 = 1.50 MPa s for the final shape). Here synthetic
//! material-1 trials in the seed's protocol (Table I: 58 x 59.5 x 12 mm, 2D plane
//! stress with the thickness, glued plates, 0.2 mm/s to 5.774 mm, 182.06 s hold,
//! release, recovery to 400 s) are made with a chosen cause behind that symptom,
//! and the diagnosis is run on them.
//!
//! Run: `cargo run --release -p wagashi-workspace-tests --example seed_gap`
//! (`-- --quick` stops before the swap study, `-- --no-symptom` skips step 2,
//! `-- --swap-only` runs steps 1 and 4). The generator runs on 5 mm elements and
//! fixed 0.25 s steps, the diagnoser on 10 mm elements and adaptive steps.
//! Step 3 (the whole library) took 130 s (load about 4; on fixed
//! 0.5 s steps 2214 s at load 12), each swap diagnosis minutes.
//! `-- --no-symptom --quick` runs steps 1 and 3 only; `-- --fixed-steps` runs
//! the diagnoser on fixed 0.5 s steps instead of adaptive ones.
//! `-- --truth stress-thinning,bingham-dashpot` matches and swaps only those
//! causes (same noise draws as the full run); `-- --designs long-hold` runs
//! the swap study on the hold-and-speed campaign plus a 728 s hold
//! (`seed_gap::HOLD_SPEED_LONG_DESIGN`) instead of the default `seed,hold-speed`;
//! `-- --help` lists the flags.
//!
//! Steps:
//! 1. every kappa > 1 candidate (diagnosis-details.md §1: plastic-slider,
//!    bingham-dashpot, stress-thinning, dual-viscosity) is matched to Table II:
//!    its truth's parameters are fitted so that it gives x_force's force and keep
//!    shape and x_shape's final shape (`seed_gap::match_table_ii`); the best
//!    match is the chosen cause;
//! 2. the symptom: the seed's own three-step procedure (`wagashi fit`'s `seed`)
//!    on the chosen cause's trials in the seed's protocol gives c3 from the force
//!    and c3 from the final shape; kappa is their ratio;
//! 3. the diagnosis of a campaign that varies hold and speed: WHERE, the verdict,
//!    and the fit with the named effect, per cell, in noise units;
//! 4. the swap study: each candidate as the true cause, on the seed's protocol
//!    only (two replicates) and on the hold-and-speed campaign (or the designs
//!    of `--designs`); each truth's end-of-hold force and final set per trial
//!    are printed first.

use std::collections::BTreeMap;
use std::time::Instant;

use calibrate::diagnosis::{cells, diagnose, Diagnosis, DiagnosisOptions, Model};
use calibrate::procedure::{self, Procedure, ProcedureOptions};
use calibrate::seed_gap::*;
use calibrate::trial::Campaign;
use fem_core::effects::EffectId;
use wagashi_io::{Bundle, MaterialSpec};

/// Element sizes [mm]: the diagnoser's, and the generator's (half).
const SIZE_MM: f64 = 10.0;
const TRUTH_SIZE_MM: f64 = 5.0;
/// Element size of the Table II matching [mm] (the matched truth then runs at `TRUTH_SIZE_MM`).
const MATCH_SIZE_MM: f64 = 5.0;
const SEED: u64 = 20_261_122;
/// The diagnoser's fixed step with `--fixed-steps` [s] (the generator's is
/// 0.25 s), for comparison with the adaptive steps.
const DIAGNOSER_DT_S: f64 = 0.5;

const CANDIDATES: [EffectId; 4] =
    [EffectId::PlasticSlider, EffectId::BinghamDashpot, EffectId::StressThinning, EffectId::DualViscosity];

fn options() -> DiagnosisOptions {
    DiagnosisOptions {
        starts: 1,
        seed: 1,
        bootstrap: 300,
        size_mm: Some(SIZE_MM),
        marker_sigma_mm: NoiseModel::SEED.marker_sigma_mm,
        // Adaptive steps (the engine's slider converges in the very short step
        // adaptive control takes right after the release); `--fixed-steps`:
        // the diagnoser on fixed 0.5 s steps.
        fixed_dt_s: if std::env::args().any(|a| a == "--fixed-steps") { Some(DIAGNOSER_DT_S) } else { None },
        ..DiagnosisOptions::default()
    }
}

fn run_diagnosis(bundles: &[Bundle], start: &BTreeMap<String, MaterialSpec>) -> Diagnosis {
    diagnose(bundles, &[], start, &options(), &|_, _, _| {}).expect("diagnosis")
}

/// The swap study's diagnosis: the four kappa > 1 candidates only (the question
/// is whether they are told apart; the whole library's cost is section 3's).
fn run_swap_diagnosis(bundles: &[Bundle], start: &BTreeMap<String, MaterialSpec>) -> Diagnosis {
    let options = DiagnosisOptions { effects: Some(CANDIDATES.iter().map(|&e| e.into()).collect()), ..options() };
    diagnose(bundles, &[], start, &options, &|_, _, _| {}).expect("diagnosis")
}

fn print_where(d: &Diagnosis) {
    println!("  WHERE (baseline residuals; cells flagged at Holm 1e-3):");
    println!("  | cell | n | RMS [noise] | T_c | p | flagged |");
    println!("  |---|---|---|---|---|---|");
    for c in &d.where_cells {
        println!(
            "  | {} | {} | {:.2} | {:.1} | {:.1e} | {} |",
            c.label(),
            c.n,
            c.rms_noise_units,
            c.statistic,
            c.p_value,
            if c.flagged { "yes" } else { "" }
        );
    }
}

fn print_candidates(d: &Diagnosis) {
    match d.peak_stress_mpa {
        Some(s) => println!("  peak nominal stress {s:.4e} MPa (the stress-valued references follow it)"),
        None => println!("  peak nominal stress unknown: the registry's static references"),
    }
    println!("  | candidate | LM | LR | crit | eligible | C | remaining flagged | parameters |");
    println!("  |---|---|---|---|---|---|---|---|");
    for c in &d.candidates {
        let p: Vec<String> = c.parameters.iter().map(|p| format!("{} = {:.3e}", p.key, p.value)).collect();
        println!(
            "  | {} | {:.1} | {:.1} | {:.1} | {} | {:.1} | {} | {} |",
            c.effect,
            c.score_statistic,
            c.lr,
            c.lr_critical,
            c.eligible,
            c.combined,
            c.remaining_flagged.len(),
            p.join(", ")
        );
    }
    for (e, why) in &d.not_evaluated {
        println!("  not evaluated: {e}: {why}");
    }
}

/// Per-cell RMS of the baseline and of the named effect's refit (one parameter set).
fn print_closure(bundles: &[Bundle], start: &BTreeMap<String, MaterialSpec>, d: &Diagnosis) {
    let Some(id) = d.verdict.effects.first() else { return };
    let c = d.candidate(*id).expect("named candidates are evaluated");
    let o = options();
    let campaign = Campaign::new(bundles, start, o.size_mm, false).expect("campaign");
    let mut model =
        Model::new(bundles, &campaign.materials, campaign.unknowns.clone(), o.size_mm, false, o.marker_sigma_mm)
            .expect("model");
    model.settings.fixed_dt_s = o.fixed_dt_s;
    // Every parameter of the effect: the fitted strength ones, the nuisance ones
    // (the slider's hardening) at their registry defaults, as the refit ran them.
    let mut values = id.null_values();
    for p in &c.parameters {
        if let Some((_, i)) = EffectId::from_key(p.key) {
            values[i] = p.value;
        }
    }
    let (r1, _) = model.residuals(&c.theta, Some((*id, &values)), None).expect("refit residuals");
    let theta0 = &d.baseline.values;
    let (r0, _) = model.residuals(theta0, None, None).expect("baseline residuals");
    let segments = cells::segments(&model);
    let w0 = cells::where_table(&segments, &r0, o.alpha_where);
    let w1 = cells::where_table(&segments, &r1, o.alpha_where);
    println!(
        "  One parameter set with {id}: {}",
        c.parameters.iter().map(|p| format!("{} = {:.4e}", p.key, p.value)).collect::<Vec<_>>().join(", ")
    );
    println!(
        "  and {}",
        d.baseline.labels.iter().zip(&c.theta).map(|(l, v)| format!("{l} = {v:.4}")).collect::<Vec<_>>().join(", ")
    );
    println!("  | cell | RMS baseline | RMS with {id} | flagged after |");
    println!("  |---|---|---|---|");
    for (a, b) in w0.iter().zip(&w1) {
        println!(
            "  | {} | {:.2} | {:.2} | {} |",
            a.label(),
            a.rms_noise_units,
            b.rms_noise_units,
            if b.flagged { "yes" } else { "" }
        );
    }
}

/// The swap study's designs (`--designs`).
const DESIGNS: [&str; 3] = ["seed", "hold-speed", "long-hold"];

const HELP: &str = "seed_gap: the seed's own gap, diagnosed (module docs)
  --quick          stop after step 3 (no swap study)
  --no-symptom     skip step 2 (the seed's three steps)
  --swap-only      steps 1 and 4 only
  --fixed-steps    the diagnoser on fixed 0.5 s steps (default: adaptive)
  --truth IDS      the true causes to match and swap, comma-separated among
                   plastic-slider, bingham-dashpot, stress-thinning, dual-viscosity (default: all four)
  --designs NAMES  the swap study's campaigns, comma-separated among
                   seed (two replicates of the seed's trial), hold-speed (4 trials: 0.2 and 0.8 mm/s,
                   45 and 182 s holds), long-hold (hold-speed plus 0.2 mm/s with a 728 s hold)
                   (default: seed,hold-speed)";

/// The value after `flag` on the command line.
fn flag_value(flag: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1).cloned())
}

/// Per trial of a measured campaign: the mean force over the last 10 s of the
/// hold and the final set of the top markers (measured, noise included): the
/// signatures that hold time and speed separate.
fn print_signature(effect: EffectId, design: &str, bundles: &[Bundle]) {
    let cells: Vec<String> = bundles
        .iter()
        .map(|b| {
            let release = b.experiment.protocol.release_s;
            let f: Vec<f64> = b
                .force
                .as_ref()
                .map(|f| f.samples.iter().filter(|s| s.t_s > release - 10.0 && s.t_s <= release).map(|s| s.force_n))
                .into_iter()
                .flatten()
                .collect();
            let hold_force = f.iter().sum::<f64>() / f.len().max(1) as f64;
            let tops: Vec<f64> = MARKERS
                .iter()
                .zip(&b.markers)
                .filter(|(m, _)| m[1] > 2.0 / 3.0)
                .filter_map(|(m, s)| {
                    s.samples.last().map(|p| p.position_mm[1] - m[1] * calibrate::seed_gap::SIZE_MM[1])
                })
                .collect();
            let set = tops.iter().sum::<f64>() / tops.len().max(1) as f64;
            format!("{}: end-of-hold force {:.1} mN, final set {:.2} mm", b.experiment.name, 1e3 * hold_force, set)
        })
        .collect();
    println!("- {effect} truth, {design}: {}", cells.join("; "));
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    if std::env::args().any(|a| a == "--help" || a == "-h") {
        println!("{HELP}");
        return;
    }
    let truths: Vec<EffectId> = match flag_value("--truth") {
        None => CANDIDATES.to_vec(),
        Some(list) => list
            .split(',')
            .map(|id| {
                CANDIDATES.into_iter().find(|e| e.id() == id).unwrap_or_else(|| {
                    eprintln!("--truth: {id} is not one of the four kappa > 1 causes");
                    std::process::exit(2)
                })
            })
            .collect(),
    };
    let swap_designs: Vec<String> = match flag_value("--designs") {
        None => vec!["seed".to_string(), "hold-speed".to_string()],
        Some(list) => list.split(',').map(str::to_string).collect(),
    };
    if let Some(d) = swap_designs.iter().find(|d| !DESIGNS.contains(&d.as_str())) {
        eprintln!("--designs: {d} is not one of {}", DESIGNS.join(", "));
        std::process::exit(2);
    }
    let mut designs = vec!["seed".to_string(), "hold-speed".to_string()];
    designs.extend(swap_designs.iter().filter(|d| !designs.contains(d)).cloned().collect::<Vec<_>>());
    let noise = NoiseModel::SEED;
    let start = x_force_start();

    println!("## 1. Matching each kappa > 1 cause to Table II (seed protocol, {MATCH_SIZE_MM} mm elements)\n");
    println!("| cause | truth | force RMS vs x_force [5 mN] | keep RMS vs x_force [0.05 mm] | final RMS vs x_shape [0.05 mm] | set [mm] (x_shape) |");
    println!("|---|---|---|---|---|---|");
    let match_noise = NoiseModel { force_sigma_n: 0.02, ..noise };
    let mut matches = Vec::new();
    for (k, e) in CANDIDATES.into_iter().enumerate().filter(|(_, e)| truths.contains(e)) {
        let t0 = Instant::now();
        let m = match_table_ii(e, MATCH_SIZE_MM, &match_noise).expect("match");
        println!(
            "| {e} | {} | {:.2} | {:.2} | {:.2} | {:.2} ({:.2}) |",
            m.truth.describe(),
            m.force_rms * match_noise.force_sigma_n / noise.force_sigma_n,
            m.keep_rms,
            m.final_rms,
            m.set_mm[0],
            m.set_mm[1]
        );
        eprintln!("  matched {e} in {:.0} s ({})", t0.elapsed().as_secs_f64(), m.stop);
        matches.push((k, e, m));
    }
    // The campaigns of every matched truth on every design asked for (the seed's
    // protocol and hold and speed always, for steps 2 and 3). A truth the engine
    // cannot run on every trial cannot be the chosen cause. Seeds by the cause's
    // place in the library of four, so a subset (`--truth`) draws the same noise;
    // the extended hold design shares the hold-and-speed seed, so its first four
    // trials are those of the hold-and-speed campaign, bit for bit.
    let mut campaigns = Vec::new();
    for (k, e, m) in &matches {
        let seed = SEED + 10 * *k as u64;
        let mut by_design = Vec::new();
        for d in &designs {
            let (trials, s): (&[SeedTrial], u64) = match d.as_str() {
                "seed" => (&SEED_ONLY_DESIGN, seed),
                "hold-speed" => (&HOLD_SPEED_DESIGN, seed + 1),
                _ => (&HOLD_SPEED_LONG_DESIGN, seed + 1),
            };
            let c = campaign(trials, &m.truth, TRUTH_SIZE_MM, &noise, s);
            match &c {
                Err(err) => println!("- {e}: the {d} campaign cannot be generated: {err}"),
                Ok(bundles) => print_signature(*e, d, bundles),
            }
            by_design.push((d.clone(), c));
        }
        campaigns.push((*e, m.clone(), by_design));
    }
    let design_of = |c: &[(String, Result<Vec<Bundle>, GenerateError>)], name: &str| {
        c.iter().find(|d| d.0 == name).and_then(|d| d.1.as_ref().ok()).cloned()
    };
    let score = |m: &TableIiMatch| m.force_rms.powi(2) + m.final_rms.powi(2) + m.keep_rms.powi(2);
    let best = matches.iter().min_by(|a, b| score(&a.2).total_cmp(&score(&b.2))).map(|m| m.1).unwrap();
    let (cause, chosen, a, b) = campaigns
        .iter()
        .filter_map(|c| Some((c.0, c.1.clone(), design_of(&c.2, "seed")?, design_of(&c.2, "hold-speed")?)))
        .min_by(|x, y| score(&x.1).total_cmp(&score(&y.1)))
        .expect("a cause that runs");
    println!("\nBest match to Table II: {best}. Chosen cause (best match that the engine runs on every trial): {cause}: {}\n", chosen.truth.describe());
    let swap_only = std::env::args().any(|a| a == "--swap-only");
    let skip_symptom = swap_only || std::env::args().any(|a| a == "--no-symptom");
    if !skip_symptom {
        println!("## 2. The symptom: the seed's three steps on the seed's protocol\n");
        let c = Campaign::new(&a, &start, Some(SIZE_MM), false).expect("campaign");
        let report =
            procedure::run(&c, Procedure::Seed, &ProcedureOptions { starts: 1, ..Default::default() }, &|_, _, _| {})
                .expect("seed procedure");
        for (name, set) in &report.sets {
            println!(
                "- x_{name}: {}",
                set.iter().map(|e| format!("{} = {:.4}", e.key, e.value)).collect::<Vec<_>>().join(", ")
            );
        }
        let c3 = |name: &str| {
            report
                .sets
                .iter()
                .find(|s| s.0 == name)
                .and_then(|s| s.1.iter().find(|e| e.key == "c3_MPa_s"))
                .map(|e| e.value)
                .unwrap()
        };
        println!(
            "- kappa = c3_force / c3_shape = {:.2} / {:.3} = {:.1} (Table II: 29.719 / 1.4951 = {:.1})\n",
            c3("force"),
            c3("shape"),
            c3("force") / c3("shape"),
            X_FORCE[4] / X_SHAPE_C3
        );
        for s in &report.steps {
            println!("  step {}: RMS {:.2} noise units ({})", s.name, s.rms, s.stop);
        }
    }
    if !swap_only {
        println!("\n## 3. Diagnosis: hold and speed varied ({} trials)\n", HOLD_SPEED_DESIGN.len());
        for bundle in &b {
            let f: Vec<(f64, f64)> =
                bundle.force.as_ref().unwrap().samples.iter().map(|s| (s.t_s, s.force_n)).collect();
            let release = bundle.experiment.protocol.release_s;
            let after: Vec<f64> = f.iter().filter(|s| s.0 > release + 5.0).map(|s| s.1).collect();
            let mean = after.iter().sum::<f64>() / after.len() as f64;
            let sd = (after.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / after.len() as f64).sqrt();
            println!(
            "  {}: force noise by the difference method {:.2} mN (generator: {:.1} mN, lag-1 {}); after release: mean {:.2} mN, sd {:.2} mN",
            bundle.experiment.name,
            1e3 * calibrate::trial::force_noise(&f),
            1e3 * noise.force_sigma_n,
            noise.force_rho,
            1e3 * mean,
            1e3 * sd
        );
        }
        let t0 = Instant::now();
        let d = run_diagnosis(&b, &start);
        eprintln!("  diagnosed in {:.0} s", t0.elapsed().as_secs_f64());
        print_where(&d);
        println!("\n  verdict: {} — {}\n", d.verdict.label, d.verdict.sentence);
        print_candidates(&d);
        println!();
        print_closure(&b, &start, &d);
        for w in &d.warnings {
            println!("  warning: {w}");
        }
        if quick {
            return;
        }
    }

    println!("\n## 4. Swap study\n");
    println!("Candidates: the four kappa > 1 explanations.\n");
    let mut rows = Vec::new();
    for (e, _, by_design) in &campaigns {
        let mut cells = Vec::new();
        for (name, c) in by_design.iter().filter(|d| swap_designs.contains(&d.0)) {
            println!("\n{e} as the true cause, design {name}:");
            let cell = match c {
                Ok(bundles) => {
                    let t0 = Instant::now();
                    let d = run_swap_diagnosis(bundles, &start);
                    eprintln!("  {e} on {name} ({:.0} s): {}", t0.elapsed().as_secs_f64(), d.verdict.sentence);
                    println!("  verdict: {} — {}", d.verdict.label, d.verdict.sentence);
                    print_candidates(&d);
                    format!(
                        "{} ({})",
                        d.verdict.label,
                        d.verdict.effects.iter().map(|e| e.id()).collect::<Vec<_>>().join(", ")
                    )
                }
                Err(_) => "not generated (the truth does not run)".to_string(),
            };
            cells.push(cell);
        }
        rows.push(format!("| {e} | {} |", cells.join(" | ")));
    }
    println!("\n| true cause | {} |", swap_designs.join(" | "));
    println!("|---|{}", "---|".repeat(swap_designs.len()));
    for r in rows {
        println!("{r}");
    }
}
