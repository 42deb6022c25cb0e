//! End-to-end tests of the diagnosis on small synthetic campaigns: three 2D
//! trials (a 20 x 15 x 10 mm block of a three-element material, plane stress,
//! glued floor, frictionless plate) at different speeds and holds, simulated by
//! the engine with the truth's effect, sampled at 10 Hz with deterministic
//! Gaussian noise, and diagnosed without being told the effect.

use std::collections::BTreeMap;

use fem_core::effects::EffectId;
use fem_core::press::{simulate_any, Settings};
use wagashi_io::{read_bundle_from_str, Bundle, ForceSample, ForceSeries};

use super::*;
use crate::rng::SplitMix64;

/// (push duration [s], hold [s]) of the three trials; push depth 1.5 mm.
const DESIGN: [(f64, f64); 3] = [(5.0, 10.0), (10.0, 20.0), (2.5, 5.0)];
const END_AFTER_RELEASE_S: f64 = 15.0;

fn experiment(name: &str, push_s: f64, hold_s: f64, material: &str, effects: &str) -> String {
    let release = push_s + hold_s;
    let end = release + END_AFTER_RELEASE_S;
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
waypoints = [[0.0, 0.0], [{push_s}, 1.5], [{release}, 1.5]]
release_s = {release}
end_s = {end}
{effects}"#
    )
}

const TRUTH: &str = "E1_MPa = 0.05\nc1_MPa_s = 0.05\nc3_MPa_s = 5.0\n";

/// The campaign: trials simulated with `effects` (an `[effects]` table or ""),
/// force noise `sigma_n` from `seed`; the returned bundles give the material by
/// its model and Poisson's ratio only, and no effect.
pub(super) fn campaign(effects: &str, sigma_n: f64, seed: u64) -> Vec<Bundle> {
    campaign_of(TRUTH, effects, sigma_n, seed, &Settings::default())
}

/// [`campaign`] of the material `truth` (its `[materials.gel]` keys) simulated
/// with `settings`.
fn campaign_of(truth: &str, effects: &str, sigma_n: f64, seed: u64, settings: &Settings) -> Vec<Bundle> {
    campaign_on(&DESIGN, truth, effects, sigma_n, seed, settings)
}

/// [`campaign_of`] on the trials `design` ((push duration [s], hold [s]) each).
fn campaign_on(
    design: &[(f64, f64)],
    truth: &str,
    effects: &str,
    sigma_n: f64,
    seed: u64,
    settings: &Settings,
) -> Vec<Bundle> {
    let text = |name: &str, push: f64, hold: f64, measured: bool| {
        if measured {
            experiment(name, push, hold, "", "")
        } else {
            experiment(name, push, hold, truth, effects)
        }
    };
    campaign_from(design, &text, sigma_n, seed, settings)
}

/// The campaign of the trials `design`, each trial's experiment text from
/// `text(name, push_s, hold_s, measured)`: the truth's (`measured` false),
/// simulated with `settings` and sampled at 10 Hz with force noise `sigma_n`
/// from `seed`, and the measured bundle's (`measured` true), which carries
/// the samples.
fn campaign_from(
    design: &[(f64, f64)],
    text: &dyn Fn(&str, f64, f64, bool) -> String,
    sigma_n: f64,
    seed: u64,
    settings: &Settings,
) -> Vec<Bundle> {
    let mut rng = SplitMix64::new(seed);
    design
        .iter()
        .enumerate()
        .map(|(k, &(push, hold))| {
            let name = format!("trial{k}");
            let truth = read_bundle_from_str("/nonexistent", &text(&name, push, hold, false), &BTreeMap::new())
                .expect("a valid truth");
            let problem = truth.to_press(5.0).expect("a press problem");
            let result = simulate_any(&problem, settings, &mut |_| {}).expect("the truth runs");
            let end = truth.experiment.protocol.end_s;
            let samples = (0..=(end * 10.0).round() as usize)
                .map(|i| {
                    let t = i as f64 * 0.1;
                    ForceSample { t_s: t, force_n: result.bottom_force_at(t) + sigma_n * rng.next_gaussian() }
                })
                .collect();
            let mut measured = read_bundle_from_str("/nonexistent", &text(&name, push, hold, true), &BTreeMap::new())
                .expect("a valid measured bundle");
            measured.force = Some(ForceSeries { samples });
            measured
        })
        .collect()
}

pub(super) fn options(effects: &[EffectId]) -> DiagnosisOptions {
    DiagnosisOptions {
        starts: 1,
        effects: Some(effects.iter().map(|&e| e.into()).collect()),
        bootstrap: 300,
        size_mm: Some(5.0),
        ..DiagnosisOptions::default()
    }
}

/// A withheld force offset and drift (about -7 and +20 noise units over a
/// trial) is named, with the fitted offset and drift near the truth, and the
/// gap it leaves localised in the force cells where nothing touches.
#[test]
fn a_withheld_force_drift_is_named() {
    let bundles = campaign("[effects]\nforce_offset_N = -0.02\nforce_drift_N_per_s = 0.002\n", 3e-3, 11);
    let d = diagnose(&bundles, &[], &BTreeMap::new(), &options(&EffectId::ALL), &|_, _, _| {}).unwrap();
    assert_eq!(d.verdict.label, "force-offset", "{:#?}\n{:#?}", d.verdict, d.candidates);
    let c = d.candidate(EffectId::ForceOffset).unwrap();
    assert!((c.parameters[0].value + 0.02).abs() < 0.004, "{:?}", c.parameters);
    assert!((c.parameters[1].value - 0.002).abs() < 0.0004, "{:?}", c.parameters);
    assert!(d.where_cells.iter().any(|w| w.flagged && w.phase == Phase::Recovery), "{:#?}", d.where_cells);
    let h = c.heldout.as_ref().unwrap();
    assert!(h.closure > 0.8 && h.closure_ci90[0] <= h.closure && h.closure <= h.closure_ci90[1], "{h:?}");
    // The engine's not-implemented effects are listed, not evaluated.
    assert!(
        d.not_evaluated.iter().any(|(e, _)| *e == EffectId::PlasticSlider) || EffectId::PlasticSlider.implemented()
    );
}

/// A slider far below the registry's static reference (sigma_y = 0.5 kPa
/// against 10 kPa; the soft gel's peak nominal stress is about 0.9 kPa, so the
/// static secant and the static refit starts, yield stresses of 3.3 kPa and up,
/// never yield anywhere and its score is exactly 0) is seen once its reference
/// follows the campaign's stress level (`Candidate::at_stress`): a positive
/// score, a significant refit that ranks first and names it, and the fitted
/// yield stress within 5 % of the truth. Fixed 0.25 s steps in the truth and
/// the diagnoser (`DiagnosisOptions::fixed_dt_s`: written when the engine's
/// slider did not converge on some adaptive steps right after a release, fixed
/// since; kept, as the figures below were measured with them).
///
/// Measured: score 251, LR 261, sigma_y 0.5024 kPa, verdict `plastic-slider`;
/// with the static references (the code before the change) the score and the
/// LR were exactly 0 (the refit stayed at sigma_y = 10 MPa, no yield), the
/// Bingham threshold's score too, and the verdict was a `tie`. The 5 %: the
/// diagnoser's 5 mm mesh is corrected by a 2.5 mm run while the truth ran on
/// the 5 mm mesh, so the corrected model is not the generator (the correction
/// moves the stress at the glued corners, where yield starts), and with force
/// only the yield stress trades off against the chain's parameters along the
/// push's knee; 1 mN noise on a 0.17 N peak alone moves it far less.
#[test]
fn a_weak_slider_below_the_static_reference_is_seen() {
    const SOFT: &str = "E1_MPa = 0.01\nc1_MPa_s = 0.01\nc3_MPa_s = 1.0\n";
    let sigma_y = 5e-4;
    let fixed = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let effects = format!("[effects]\nplastic_yield_stress_MPa = {sigma_y}\n");
    let bundles = campaign_of(SOFT, &effects, 1e-3, 16, &fixed);
    let library =
        [EffectId::PlasticSlider, EffectId::BinghamDashpot, EffectId::StressThinning, EffectId::DualViscosity];
    let opts = DiagnosisOptions { fixed_dt_s: Some(0.25), ..options(&library) };
    let d = diagnose(&bundles, &[], &BTreeMap::new(), &opts, &|_, _, _| {}).unwrap();
    let peak = d.peak_stress_mpa.expect("a block with a measured force");
    eprintln!("peak {peak:.3e} MPa; verdict {}", d.verdict.label);
    for c in &d.candidates {
        eprintln!(
            "{}: LM {:.3e} LR {:.3e} C {:.3e} fell back {} {:?}",
            c.effect, c.score_statistic, c.lr, c.combined, c.fell_back, c.parameters
        );
    }
    // Far below the static reference (every static start: 3.3 kPa and up),
    // above the truth's yield stress.
    assert!(peak > sigma_y && peak < 0.3 * EffectId::PlasticSlider.params()[0].reference, "{peak}");
    let slider = d.candidate(EffectId::PlasticSlider).unwrap();
    assert!(slider.score_statistic > 0.0, "{slider:#?}");
    assert!(slider.significant && !slider.fell_back, "{slider:#?}");
    let best = d.candidates.iter().max_by(|a, b| a.combined.total_cmp(&b.combined)).unwrap();
    assert_eq!(best.effect, EffectId::PlasticSlider, "{:#?}", d.candidates);
    assert!(d.verdict.effects.first().is_some_and(|e| *e == EffectId::PlasticSlider), "{:#?}", d.verdict);
    let fitted = slider.parameters[0].value;
    assert!((fitted / sigma_y - 1.0).abs() < 0.05, "sigma_y = {fitted}");
}

/// No effect: `none`.
#[test]
fn a_null_campaign_gives_none() {
    let bundles = campaign("", 3e-3, 12);
    let d = diagnose(&bundles, &[], &BTreeMap::new(), &options(&EffectId::ALL), &|_, _, _| {}).unwrap();
    assert_eq!(d.verdict.label, "none", "{:#?}\n{:#?}\n{:#?}", d.verdict, d.where_cells, d.candidates);
    assert!(d.where_cells.iter().all(|c| !c.flagged));
    assert!(d.candidates.iter().all(|c| !c.significant));
    assert!(d.numerical_error.chi2.is_finite());
}

/// A withheld machine compliance (0.2 mm/N: the plate gives way by about 13 %
/// of its stroke at the peak force) is named.
#[test]
fn a_withheld_machine_compliance_is_named() {
    let bundles = campaign("[effects]\nmachine_compliance_mm_per_N = 0.2\n", 3e-3, 13);
    let d = diagnose(&bundles, &[], &BTreeMap::new(), &options(&EffectId::ALL), &|_, _, _| {}).unwrap();
    assert_eq!(d.verdict.label, "machine-compliance", "{:#?}\n{:#?}", d.verdict, d.candidates);
    let k = d.candidate(EffectId::MachineCompliance).unwrap().parameters[0].value;
    assert!((k - 0.2).abs() < 0.02, "1/k_m = {k}");
}

/// The whole diagnosis (fits, bootstrap intervals, verdict) is the same bit for
/// bit on one thread and on three.
#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    let bundles = campaign("[effects]\nforce_offset_N = 0.01\n", 3e-3, 14);
    let opts = options(&[EffectId::ForceOffset, EffectId::Gravity, EffectId::MachineCompliance]);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| diagnose(&bundles, &[], &BTreeMap::new(), &opts, &|_, _, _| {}).unwrap())
    };
    let (one, three) = (run(1), run(3));
    assert_eq!(one, three);
    assert!(one.candidate(EffectId::ForceOffset).unwrap().heldout.is_some());
}

/// The blind generator is a function of the seed: the measured bundles (force
/// and marker samples, bit for bit) and the realised strength are the same on
/// one thread and on three.
#[test]
fn the_blind_generator_does_not_depend_on_the_number_of_threads() {
    use super::blind::{default_options, generate, Case, Scatter, Truth};
    let case = Case { truth: Truth::InLibrary(EffectId::ForceOffset), lambda: 30.0 };
    let opts = default_options(1);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| generate(&case, 77, &Scatter::ISSUE, &opts).unwrap())
    };
    let (one, three) = (run(1), run(3));
    assert_eq!(one.lambda_eff.to_bits(), three.lambda_eff.to_bits());
    assert_eq!(one.strength, three.strength);
    for (a, b) in one.bundles.iter().zip(&three.bundles) {
        assert_eq!(a.force, b.force);
        assert_eq!(a.markers, b.markers);
    }
    assert!(one.reached && (one.lambda_eff / 30.0 - 1.0).abs() < 0.2, "{one:?}");
}

/// A Mullins-type damage campaign (out of library: the engine's damage law on
/// the truth, [`super::blind::OutOfLibrary::MullinsDamage`]) is generated at its
/// target strength: lambda_eff within 20 % of 100 (the strength calibration's
/// acceptance), reached, with `d_inf = 0.1 a` inside the law's bounds and the
/// characteristic strain recorded.
#[test]
fn a_mullins_campaign_is_generated_at_its_strength() {
    use super::blind::{
        default_options, generate, Case, OutOfLibrary, Scatter, Truth, MULLINS_D_INF_PER_AMPLITUDE, MULLINS_STRAIN_C,
    };
    let case = Case { truth: Truth::OutOfLibrary(OutOfLibrary::MullinsDamage), lambda: 100.0 };
    let g = generate(&case, 78, &Scatter::ISSUE, &default_options(1)).unwrap();
    eprintln!("{:?}: lambda_eff {:.1} (raw {:.1}, null {:.1})", g.strength, g.lambda_eff, g.lambda_raw, g.lambda_null);
    assert!(g.reached && (g.lambda_eff / 100.0 - 1.0).abs() < 0.2, "{:?} {}", g.strength, g.lambda_eff);
    assert_eq!(g.strength.len(), 2);
    let (key, d_inf) = &g.strength[0];
    assert_eq!(key, "mullins_d_inf");
    assert!(*d_inf > 0.0 && *d_inf <= fem_core::material::MAX_DAMAGE, "{d_inf}");
    assert_eq!(*d_inf, g.amplitude * MULLINS_D_INF_PER_AMPLITUDE);
    assert_eq!(g.strength[1], ("mullins_strain_c".to_string(), MULLINS_STRAIN_C));
    assert_eq!(g.bundles.len(), super::blind::DESIGN.len());
}

/// The frozen blind CI set (seed 20261121, never used while tuning; the
/// development seeds are 101 to 104, see blind.rs): eight campaigns with ideal
/// samples ([`super::blind::Scatter::IDEAL`], so that its figures in
/// BENCHMARKS.md compare like with like). Checks that every campaign is
/// generated at its strength (lambda_eff within 20 % of its target), that the
/// scores add up, and the diagnosis's targets that hold on this set
/// ([`HOLDING`]); the others are printed with their values and reported as
/// misses (not asserted, not loosened).
///
/// Measured, with the tie rule's SE by blocks inside segments
/// (`heldout::block_se`) and the held-out veto's SE by blocks
/// ([`HeldOut::non_inferior`]): eight verdicts (`none`, `tie` force-offset /
/// gravity, `machine-compliance`, `tie`, `none`, `tie`, `ageing`,
/// `dual-viscosity`): top-1 at lambda >= 30 2/5 (a miss), nulls 0/2,
/// out-of-library 0/1 (a miss), closure error 0.149; no tie of this set is
/// called on the cosine alone (the three ties have margins of 10.0, 2.1 and
/// 5.5 against 2 SE of 13.2, 10.7 and 21.9). 208.8 s wall, 40.0 s user CPU at
/// load about 15. By whole segments ageing at lambda 100 is a `tie` (margin
/// 109.4 against 2 SE = 126.2; 2 SE = 42.6 by blocks) and top-1 at lambda >=
/// 30 is 1/5.
///
/// The closure error of the one scoreable campaign (machine-compliance at
/// lambda 100) is over the 0.10 target, so that target is not in [`HOLDING`]:
/// it is 0.149 with the force noise's AR(1) estimate free of its detrending
/// bias (`model::ar1_estimate`), 0.063 with the biased estimate, every verdict
/// of this set the same. The unbiased estimate is kept for what it does on
/// development seed 101 (same campaigns, biased against unbiased): false
/// attribution on nulls 2/7 against 0/7, top-1 at lambda >= 30 3/8 against
/// 4/8, a poroelastic case a wrong `machine-compliance` against `none`, median
/// closure error 0.058 over one case against 0.101 over two.
///
/// The design with the separating trials (a hold of five relaxation times,
/// 25 % strain, 5 s before contact; blind.rs, "The separating trials, tried
/// and not kept") was run on this set once (`calibrate-* frozen_blind_ci_set
/// --nocapture`, commit 7dac917, load about 25) and failed this test's own
/// check that every campaign is generated at its strength: `ageing` at lambda
/// 100 did not land within 20 % in its 12 evaluations. The six campaigns
/// before it came out `none`, `force-offset`, `machine-compliance`, `none`
/// (thinning at 30), `none`, `bingham-dashpot`, 58 to 175 s each. That design
/// was not kept, so the assertions are those of the four-trial design.
#[test]
fn frozen_blind_ci_set() {
    use super::blind::{default_options, run_blind, summarise, Case, OutOfLibrary, Scatter, Truth};
    const HOLDING: &[&str] = &["false attribution on null campaigns"];
    let inlib = |e, lambda| Case { truth: Truth::InLibrary(e), lambda };
    let cases = [
        Case { truth: Truth::Null, lambda: 0.0 },
        inlib(EffectId::ForceOffset, 100.0),
        inlib(EffectId::MachineCompliance, 100.0),
        inlib(EffectId::StressThinning, 30.0),
        Case { truth: Truth::Null, lambda: 0.0 },
        inlib(EffectId::BinghamDashpot, 30.0),
        inlib(EffectId::Ageing, 100.0),
        Case { truth: Truth::OutOfLibrary(OutOfLibrary::BroadSpectrum), lambda: 100.0 },
    ];
    let (outcomes, failures) =
        run_blind(&cases, 20_261_121, &Scatter::IDEAL, &default_options(20_261_121), &|_, _, _| {});
    assert!(failures.is_empty(), "{failures:#?}");
    assert_eq!(outcomes.len(), cases.len());
    for o in &outcomes {
        let g = &o.generated;
        if o.case.lambda > 0.0 {
            assert!(g.reached && (g.lambda_eff / o.case.lambda - 1.0).abs() < 0.2, "{} {:?}", o.index, g.strength);
        } else {
            assert_eq!(g.lambda_eff, 0.0);
        }
        eprintln!(
            "{} {} @ {}: lambda_eff {:.1} (null misfit {:.1}, peak stress {:.2e} MPa) -> {} ({:.1} s + {:.1} s) \
             tie test {}",
            o.index,
            o.case.truth.name(),
            o.case.lambda,
            g.lambda_eff,
            g.lambda_null,
            model::peak_stress_mpa(&g.bundles).unwrap_or(f64::NAN),
            o.label,
            o.generate_s,
            o.diagnose_s,
            o.tie_test.as_ref().map_or("-".to_string(), |t| format!(
                "vs {}: margin {:.1}, 2 SE blocks {:.1}, 2 SE segments {:.1}, cosine {:.2}",
                t.runner_up,
                t.margin,
                2.0 * t.se_blocks,
                2.0 * t.se_segments,
                t.cosine
            ))
        );
    }
    let s = summarise(&outcomes);
    let counted: usize = s.confusion.values().flat_map(|row| row.values()).sum();
    assert_eq!(counted, cases.len());
    assert_eq!(s.false_attribution.total, 2);
    assert_eq!(s.out_of_library_flagged.total, 1);
    assert_eq!(s.top1_by_lambda.values().map(|r| r.total).sum::<usize>(), 5);
    for t in &s.targets {
        eprintln!("{} {} {}: {:.3} over {} -> {}", t.metric, t.relation, t.threshold, t.value, t.cases, t.holds);
        if HOLDING.contains(&t.metric) {
            assert!(t.holds, "{t:?}");
        }
    }
}

/// The per-sample scales' Jacobian columns (built from the unknowns' columns,
/// `sum theta_i dr/dtheta_i` per trial and kind) agree with central differences
/// of the residuals within 1e-3 of the column norm, and their prior rows are
/// `b / omega`.
#[test]
fn per_sample_scale_columns_match_finite_differences() {
    use crate::lsq::LeastSquares;
    let bundles = campaign("", 3e-3, 15);
    let c = crate::trial::Campaign::new(&bundles, &BTreeMap::new(), Some(5.0), false).unwrap();
    let mut model = Model::new(&bundles, &c.materials, c.unknowns.clone(), Some(5.0), false, 0.05).unwrap();
    model.sample_scale_sd = 0.1;
    let p = model.unknowns.len();
    assert_eq!(model.num_scales(), 2 * bundles.len());
    let mut x = c.values();
    x.resize(model.num_theta(), 0.0);
    for (m, b) in x[p..].iter_mut().enumerate() {
        *b = 0.02 * (m as f64 - 2.5);
    }
    let problem = model::Fitting { model: &model, candidate: None };
    let e = problem.evaluate(&x, true).unwrap();
    let j = e.jacobian.unwrap();
    let n_obs = model.num_residuals();
    assert_eq!(e.residuals.len(), n_obs + model.num_scales());
    for m in 0..model.num_scales() {
        assert!((e.residuals[n_obs + m] - x[p + m] / 0.1).abs() < 1e-12);
        let h = 1e-4;
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[p + m] += h;
        xm[p + m] -= h;
        let rp = problem.evaluate(&xp, false).unwrap().residuals;
        let rm = problem.evaluate(&xm, false).unwrap().residuals;
        let fd: Vec<f64> = rp.iter().zip(&rm).map(|(a, b)| (a - b) / (2.0 * h)).collect();
        let col: Vec<f64> = (0..fd.len()).map(|i| j[(i, p + m)]).collect();
        let norm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
        let err = col.iter().zip(&fd).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        assert!(norm > 0.0 && err < 1e-3 * norm, "scale {m}: |J - FD| = {err:e}, |J| = {norm:e}");
    }
}

/// Stress thinning against a Bingham threshold (diagnosis-details.md §4.3, E2
/// against E3), the swap study's confusable pair (VALIDATION.md, "The swap
/// study"), on a Cross-thinning truth (m = 1) whose critical stress is an
/// eighth of the campaign's peak stress (1/sigma_c = 1600 1/MPa; peak 5.8
/// kPa), force only, truth and diagnoser on fixed 0.25 s steps.
///
/// *Short holds* (the three trials of [`DESIGN`], holds of 5 to 20 s): over the
/// stresses they visit a threshold dashpot mimics thinning, and the verdict is
/// a `tie` (measured: thinning's LR 83.4 against Bingham's 74.8, cosine of the
/// corrections 0.95).
///
/// *With a long hold* (the same three plus a 150 s hold at the middle speed):
/// the stress relaxes to a few sigma_c, where thinning keeps decaying and a
/// threshold stops. The refits tell them apart: thinning's recovers the truth
/// (measured 1/sigma_c = 1602, m = 0.996 with the exponent freed) and leaves no
/// cell flagged, Bingham's leaves the push and hold force flagged and its LR
/// is lower (2.931e4 against 3.833e4; measured 1/sigma_c 1603); its held-out
/// prediction is worse than the baseline's (closure -30) where thinning's
/// closes the gap (1.00). The verdict is `stress-thinning`: the margin of C
/// (8.47e5) against 2 SE = 3.2e4 of the block bootstrap inside segments
/// (`heldout::block_se`). A bootstrap over whole segments would make it a
/// `tie` (2 SE = 1.6e6), because with force only the whole difference sits in
/// one segment (the long trial's hold), which a bootstrap over segments reads
/// as spread (VALIDATION.md). The short design stays a `tie` through the
/// cosine (0.95; margin 77.7 against 2 SE = 7.2). With a step control that
/// follows the displacements alone, the diagnoser's adaptive steps gave the
/// same campaign 1/sigma_c = 2669 and the recovery force flagged: the
/// displacements barely move in a hold, so hold steps grew to a twentieth of
/// the trial and the Cross law's first-order flow (fem_core::effects,
/// "Accuracy") drifted. The step control checks the inelastic strains too
/// (`fem_core::press::Settings::flow_rtol`); this small campaign was not
/// re-measured on adaptive steps with it.
#[test]
fn a_long_hold_tells_thinning_from_a_threshold_in_the_refits() {
    let effects = "[effects]\nthinning_inverse_stress_1_per_MPa = 1600.0\n";
    let library = [EffectId::BinghamDashpot, EffectId::StressThinning];
    let fixed = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let opts = DiagnosisOptions { fixed_dt_s: Some(0.25), ..options(&library) };
    let run = |design: &[(f64, f64)]| {
        let bundles = campaign_on(design, TRUTH, effects, 3e-3, 17, &fixed);
        let d = diagnose(&bundles, &[], &BTreeMap::new(), &opts, &|_, _, _| {}).unwrap();
        eprintln!("verdict {}: {} {:?}", d.verdict.label, d.verdict.sentence, d.verdict.tie_test);
        for c in &d.candidates {
            eprintln!(
                "  {}: LR {:.4e} C {:.4e} flagged {:?} {:?} held-out {:?}",
                c.effect, c.lr, c.combined, c.remaining_flagged, c.parameters, c.heldout
            );
        }
        d
    };
    let short = run(&DESIGN);
    assert_eq!(short.verdict.label, "tie", "{:#?}", short.verdict);
    let mut design = DESIGN.to_vec();
    design.push((5.0, 150.0));
    let long = run(&design);
    let thinning = long.candidate(EffectId::StressThinning).unwrap();
    let bingham = long.candidate(EffectId::BinghamDashpot).unwrap();
    assert!(thinning.significant && thinning.remaining_flagged.is_empty(), "{thinning:#?}");
    assert!((thinning.parameters[0].value / 1600.0 - 1.0).abs() < 0.02, "{:?}", thinning.parameters);
    assert!(!bingham.remaining_flagged.is_empty(), "{bingham:#?}");
    assert!(thinning.lr > bingham.lr + 1e3, "{} vs {}", thinning.lr, bingham.lr);
    let (ht, hb) = (thinning.heldout.as_ref().unwrap(), bingham.heldout.as_ref().unwrap());
    assert!(ht.closure > 0.9 && hb.closure < 0.0, "{ht:?} {hb:?}");
    assert_eq!(long.verdict.label, "stress-thinning", "{:#?}", long.verdict);
}

/// The tie rule on constructed inputs (diagnosis-details.md §5.4.4, [`is_tie`]).
mod tie_rule {
    use super::*;
    use crate::diagnosis::cells::Segment;
    use crate::diagnosis::stats::legendre_basis;

    /// Four trials, each a push (60 samples), hold (300) and recovery (200) force segment.
    fn segments() -> (Vec<Segment>, usize) {
        let mut out = Vec::new();
        let mut next = 0;
        for trial in 0..4 {
            for (phase, n) in [(Phase::Push, 60), (Phase::Hold, 300), (Phase::Recovery, 200)] {
                let times: Vec<f64> = (0..n).map(|i| i as f64).collect();
                let indices = (next..next + n).collect();
                next += n;
                out.push(Segment {
                    cell: (phase, ObsChannel::Force, Region::All),
                    trial,
                    indices,
                    basis: legendre_basis(&times, 3),
                });
            }
        }
        (out, next)
    }

    /// A unit-norm smooth signature: a decay over every hold segment (`a`)
    /// or a ramp over every recovery segment (`b`), orthogonal to each other.
    fn signature(segments: &[Segment], n: usize, phase: Phase) -> Vec<f64> {
        let mut v = vec![0.0; n];
        for s in segments.iter().filter(|s| s.cell.0 == phase) {
            let len = s.indices.len() as f64;
            for (k, &i) in s.indices.iter().enumerate() {
                let x = k as f64 / len;
                v[i] = if phase == Phase::Hold { (-3.0 * x).exp() } else { x };
            }
        }
        let norm = stats::dot(&v, &v).sqrt();
        v.iter().map(|x| x / norm).collect()
    }

    /// `r` minus its projection on `column` (a one-parameter refit of a model
    /// linear in its parameter).
    fn refit(r: &[f64], column: &[f64]) -> Vec<f64> {
        let c = stats::dot(r, column) / stats::dot(column, column);
        r.iter().zip(column).map(|(x, y)| x - c * y).collect()
    }

    fn evaluated(effect: EffectId, r0: &[f64], residuals: Vec<f64>) -> Evaluated {
        let lr = stats::dot(r0, r0) - stats::dot(&residuals, &residuals);
        let report = CandidateReport {
            effect: effect.into(),
            dim: 1,
            score_statistic: lr,
            score_p_value: 0.0,
            epc: vec![1.0],
            lr,
            p_value: 0.0,
            lr_critical: 11.2,
            significant: true,
            heldout: None,
            eligible: true,
            combined: lr - 2.0,
            parameters: Vec::new(),
            theta: Vec::new(),
            remaining_flagged: Vec::new(),
            lm_num: 0.0,
            refit_starts: 1,
            fell_back: false,
            refit_errors: Vec::new(),
        };
        Evaluated { report, residuals, heldout: None, values: Vec::new() }
    }

    /// The truth is `gravity`, its signature `a` at strength `lambda` (noise
    /// units squared) on white noise; the runner-up `force-offset` has the
    /// column `cos a + sin b` (`b` orthogonal to `a`). Returns the verdict.
    fn verdict(lambda: f64, cosine: f64, seed: u64) -> Verdict {
        let (segments, n) = segments();
        let a = signature(&segments, n, Phase::Hold);
        let b = signature(&segments, n, Phase::Recovery);
        let sine = (1.0 - cosine * cosine).sqrt();
        let column: Vec<f64> = a.iter().zip(&b).map(|(x, y)| cosine * x + sine * y).collect();
        let mut rng = SplitMix64::new(seed);
        let r0: Vec<f64> = a.iter().map(|x| lambda.sqrt() * x + rng.next_gaussian()).collect();
        let evaluated = [
            evaluated(EffectId::Gravity, &r0, refit(&r0, &a)),
            evaluated(EffectId::ForceOffset, &r0, refit(&r0, &column)),
        ];
        decide(&[], &evaluated, &r0, None, &segments, &segments, &options(&EffectId::ALL))
    }

    /// Collinear corrections (cosine 0.95) with a margin far outside its SE
    /// band, as `gravity` against `force-offset` at lambda = 100 in a blind
    /// campaign with the separating trials (margin 2942 against 2 SE = 233,
    /// cosine 0.93). The document's rule is
    /// "margin < 2 SE, **or** cosine > 0.9": a tie, with both named. Measured:
    /// margin 297.9 against SE 33.4 (8.9 SE), cosine 0.950. Asserted: the
    /// margin over 6 SE (the large-margin premise), the cosine over 0.9, and
    /// the label `tie`.
    #[test]
    fn collinear_corrections_tie_even_with_a_large_margin() {
        let v = verdict(3000.0, 0.95, 3);
        let t = v.tie_test.clone().unwrap();
        eprintln!("{t:?}");
        assert!(t.margin > 6.0 * t.se && t.cosine > TIE_COSINE, "{t:?}");
        assert_eq!(v.label, "tie", "{v:?}");
        assert_eq!(v.effects, vec![EffectId::Gravity, EffectId::ForceOffset]);
    }

    /// The same strength with corrections at cosine 0.6: the margin is outside
    /// its SE band and the signatures are not collinear, so the leader is
    /// named. Measured: margin 1871.4 against 2 SE = 172.9, cosine 0.600.
    #[test]
    fn a_large_margin_between_distinct_corrections_names_the_leader() {
        let v = verdict(3000.0, 0.6, 3);
        let t = v.tie_test.clone().unwrap();
        eprintln!("{t:?}");
        assert!(t.margin > 2.0 * t.se && t.cosine < TIE_COSINE, "{t:?}");
        assert_eq!(v.label, "gravity", "{v:?}");
    }

    /// Orthogonal corrections that explain equal parts: the residual is noise
    /// plus `a + b` at 40 noise units squared each, so the margin is noise
    /// (`N(0, 4 * 80)` about 0). Over 50 seeds the rule gives a tie in at
    /// least 45 (nominal 95 % two-sided: the leader is the better of the two);
    /// measured 47/50.
    #[test]
    fn a_margin_within_its_se_band_ties() {
        let (segments, n) = segments();
        let a = signature(&segments, n, Phase::Hold);
        let b = signature(&segments, n, Phase::Recovery);
        let mut ties = 0;
        for seed in 0..50 {
            let mut rng = SplitMix64::new(100 + seed);
            let r0: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 40f64.sqrt() * (x + y) + rng.next_gaussian()).collect();
            let evaluated = [
                evaluated(EffectId::Gravity, &r0, refit(&r0, &a)),
                evaluated(EffectId::ForceOffset, &r0, refit(&r0, &b)),
            ];
            let v = decide(&[], &evaluated, &r0, None, &segments, &segments, &options(&EffectId::ALL));
            let t = v.tie_test.unwrap();
            assert!(t.cosine.abs() < 0.5, "{t:?}");
            ties += usize::from(v.label == "tie");
        }
        eprintln!("ties {ties}/50");
        assert!(ties >= 45, "ties {ties}/50");
    }
}

/// [`experiment`] in plane strain with the material a network of the
/// sub-tables `tables` (`[materials.gel.equilibrium]` and the parts, their keys
/// given or absent).
fn network_experiment(name: &str, push_s: f64, hold_s: f64, tables: &str) -> String {
    experiment(name, push_s, hold_s, tables, "")
        .replace("model = \"three-element\"", "model = \"network\"")
        .replace("material = \"gel\"", "material = \"gel\"\nplane = \"strain\"")
}

/// A network campaign on [`DESIGN`]: trials simulated with the material
/// `truth` (sub-tables), force noise `sigma_n` from `seed`; the returned
/// bundles give the material as `skeleton` (its absent keys are the unknowns).
fn network_campaign(truth: &str, skeleton: &str, sigma_n: f64, seed: u64) -> Vec<Bundle> {
    let text = |name: &str, push: f64, hold: f64, measured: bool| {
        network_experiment(name, push, hold, if measured { skeleton } else { truth })
    };
    campaign_from(&DESIGN, &text, sigma_n, seed, &Settings::default())
}

const NETWORK_BASE: &str = "[materials.gel.equilibrium]\nenergy = \"neo-hookean\"\nE_MPa = 0.02\n\
    [[materials.gel.viscous]]\nE_MPa = 0.05\ntau_s = 2.0\n";
const NETWORK_SKELETON: &str = "[materials.gel.equilibrium]\nenergy = \"neo-hookean\"\n[[materials.gel.viscous]]\n";

/// A network campaign whose truth holds a second viscous network (a 20 s
/// relaxation beside the baseline's 2 s) is diagnosed with the network's
/// components (the library of an all-network campaign): `extra-viscous-network`
/// is named first, with its freed relaxation time near one of the truth's two
/// (which network takes which time is arbitrary); the same campaign without it
/// names nothing. The truth runs on the diagnoser's own
/// 5 mm mesh, so the mesh correction is off (it would be zero to round-off).
///
/// Measured: LR 71.1, E 0.0500 MPa and tau 1.999 s (truth 0.05 MPa, 2 s: the
/// baseline's network took the 20 s time), verdict `extra-viscous-network`
/// with no cell left flagged; the null campaign's baseline recovers the truth
/// to 0.05 % and every LR is below 4e-4. The network's unknowns have no
/// engine sensitivities; their columns are differences (with empty columns
/// the baseline would stay at its start and the null campaign name the extra
/// network).
#[test]
fn a_withheld_viscous_network_is_named_and_a_null_network_campaign_gives_none() {
    let truth = format!("{NETWORK_BASE}[[materials.gel.viscous]]\nE_MPa = 0.03\ntau_s = 20.0\n");
    let bundles = network_campaign(&truth, NETWORK_SKELETON, 1e-3, 21);
    let library = [Component::Stiffening, Component::PlasticSet, Component::ExtraViscous];
    let opts = DiagnosisOptions {
        effects: Some(library.map(CandidateId::Component).to_vec()),
        mesh_correction: false,
        ..options(&[])
    };
    let d = diagnose(&bundles, &[], &BTreeMap::new(), &opts, &|_, _, _| {}).unwrap();
    for c in &d.candidates {
        eprintln!("{}: LM {:.3e} LR {:.3e} C {:.3e} {:?}", c.effect, c.score_statistic, c.lr, c.combined, c.parameters);
    }
    eprintln!("verdict {}; remaining {:?}", d.verdict.label, d.verdict.remaining_cells);
    assert!(
        d.verdict.effects.first().is_some_and(|e| *e == CandidateId::Component(Component::ExtraViscous)),
        "{:#?}",
        d.verdict
    );
    let c = d.candidate(Component::ExtraViscous).unwrap();
    let tau = c.parameters.iter().find(|p| p.key == "tau_s").unwrap().value;
    assert!((tau / 20.0 - 1.0).abs() < 0.2 || (tau / 2.0 - 1.0).abs() < 0.2, "tau = {tau}");

    let null = network_campaign(NETWORK_BASE, NETWORK_SKELETON, 1e-3, 22);
    let d0 = diagnose(&null, &[], &BTreeMap::new(), &opts, &|_, _, _| {}).unwrap();
    eprintln!(
        "null baseline {:?} {:?} rms {} stop {}",
        d0.baseline.labels, d0.baseline.values, d0.baseline.rms_noise_units, d0.baseline.stop
    );
    for c in &d0.candidates {
        eprintln!(
            "null {}: LM {:.3e} LR {:.3e} C {:.3e} {:?}",
            c.effect, c.score_statistic, c.lr, c.combined, c.parameters
        );
    }
    assert_eq!(d0.verdict.label, "none", "{:#?}\n{:#?}", d0.verdict, d0.candidates);
}

/// Forward selection: a campaign whose truth holds two effects the baseline
/// lacks, a force offset and drift and a machine compliance (each named alone
/// by the tests above), is diagnosed as the set of both, one step each, and
/// the selection stops at a third step that names nothing.
///
/// Measured: step 1 names force-offset (LR 5.6e4; cells stay flagged), step
/// 2, with it included, machine-compliance (LR 6.1e3, 1/k_m = 0.195 mm/N,
/// closing 0.99 [0.96, 1.00] of the held-out gap left), step 3 `none` (gravity
/// LR 0.02): the verdict `force-offset + machine-compliance`. Without the
/// sweep that refits force-offset beside the compliance, its step-1 offset
/// (-0.0222 N against -0.02) left cells flagged and step 3 `unexplained`.
#[test]
fn two_withheld_effects_are_named_as_a_set_by_forward_selection() {
    let effects = "[effects]\nforce_offset_N = -0.02\nforce_drift_N_per_s = 0.002\nmachine_compliance_mm_per_N = 0.2\n";
    let bundles = campaign(effects, 3e-3, 17);
    let library = [EffectId::ForceOffset, EffectId::MachineCompliance, EffectId::Gravity];
    let d = diagnose(&bundles, &[], &BTreeMap::new(), &options(&library), &|_, _, _| {}).unwrap();
    for s in &d.selection {
        eprintln!("step with {:?}: {} named {:?} LR {:.3e}", s.included, s.label, s.named, s.lr);
        for c in &s.candidates {
            eprintln!("  {}: LR {:.3e} eligible {} {:?}", c.effect, c.lr, c.eligible, c.parameters);
        }
    }
    eprintln!("verdict {}: {}", d.verdict.label, d.verdict.sentence);
    let mut named = d.verdict.effects.clone();
    named.sort();
    let want: Vec<CandidateId> = [EffectId::MachineCompliance, EffectId::ForceOffset].map(CandidateId::Effect).to_vec();
    assert_eq!(named, want, "{:#?}", d.verdict);
    assert_eq!(d.selection.len(), 3, "{:#?}", d.selection);
    assert_eq!(d.selection[1].included.len(), 1);
    assert_eq!(d.selection[2].named, None);
    assert_eq!(d.verdict.label, "force-offset + machine-compliance");
    assert!(d.verdict.remaining_cells.is_empty());
    let compliance = d.selection[1].candidates.iter().find(|c| c.effect == EffectId::MachineCompliance).unwrap();
    assert!((compliance.parameters[0].value - 0.2).abs() < 0.02, "{:?}", compliance.parameters);
}
