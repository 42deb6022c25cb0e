//! The sim-to-real gap diagnosis (diagnosis.md; diagnosis-details.md §5): where
//! the gap lies, which unmodelled effect of the library causes it, and how far
//! it shrinks once that effect is added.
//!
//! [`diagnose`] runs, on calibration bundles (and optional validation bundles):
//!
//! 1. **Baseline calibration** (step 1): the unknown material parameters and
//!    the per-sample scales `b` by multi-start Levenberg-Marquardt
//!    ([`crate::multistart()`]) on the whitened force and marker residuals of
//!    every trial ([`model::Model`]) plus the scales' prior rows, exact Jacobians
//!    from the engine's sensitivities.
//!
//!    **Per-sample scales** (diagnosis-details.md §5.0, `b_k ~ N(0, Omega)`):
//!    every trial (sample) has a log-scale on all its modulus unknowns and one
//!    on all its viscosity unknowns, with the Gaussian prior
//!    `Omega = omega^2 I`, `omega` = [`DiagnosisOptions::sample_scale_sd`]
//!    (default 0.1, the upper end of the 3 to 10 % scatter of soft-food
//!    specimens; no replicate set is required to estimate it). The objective is
//!    `Phi = 1/2 |r|^2 + 1/2 sum b^2 / omega^2`, and every LR is a difference of
//!    `Phi`. Why a prior and not free scales: an effect that acts as a
//!    trial-level drift of the moduli or viscosities (ageing, the run order)
//!    would be unidentifiable against free per-trial scales; with the prior it
//!    stays identifiable, at the price that it is partly absorbed (its
//!    `lambda_eff` counts only what survives the scales, diagnosis-details.md
//!    §7.4). The scales also absorb what acts on a trial as a stiffness scale:
//!    geometry errors and most of the coarse mesh's stiffness error. Held-out
//!    trials are still anchored on their own two scales ([`heldout`]).
//!
//!    **Noise model** ([`model::force_noise_model`]). Force: AR(1) with the
//!    marginal sigma and the lag-1 correlation of the no-contact segments
//!    (pre-contact and recovery, each detrended by a line, so an offset or a
//!    drift does not enter), the residuals and the Jacobian whitened by the
//!    Prais-Winsten transform, so that chi-square units and LR tests are
//!    calibrated (with white weights, AR(1) noise of rho = 0.5 inflates the
//!    chi-square of a smooth gap about threefold); with fewer than
//!    [`model::MIN_QUIET_SAMPLES`] no-contact samples, the difference-method
//!    sigma and white noise. Markers: `marker_sigma_mm`, and a marker's
//!    coordinates whitened together for the error of its measured initial
//!    position, which every later residual shares ([`model::whiten_markers`]).
//! 2. **Numerical-error budget** (step 0). *Mesh*: every trial is also run on a
//!    mesh of half the element size, at the start values and again at the fit
//!    (then a polish of the fit); the difference `d` of the predictions is added
//!    to the coarse model's as a fixed correction (a first-order multi-fidelity
//!    correction: the coarse model's dependence on the parameters, the fine
//!    model's level). Reported: `mesh_chi2 = |d|^2` and the part the unknowns
//!    and scales cannot absorb, `|(I - P_theta,b) d|^2`, the gap that the coarse
//!    mesh alone would have shown. Measured in the blind check (blind.rs): the
//!    null misfit fell from 333 to 626 noise units to about 1. *Time steps*:
//!    the trials are run again on their own step ends with every step halved;
//!    the difference `e_num` in noise units gives `chi2_num = |e_num|^2` and, per
//!    candidate, `LM_num = (J~^T e)^T (J~^T J~)^-1 (J~^T e)` (how much of it
//!    could pass for the candidate's signature). Above 1 each is a warning:
//!    `numerical` is not a verdict label. The three-mesh GCI of
//!    diagnosis-details.md §5.1 is not run (a quarter-size mesh costs 16 coarse
//!    runs per trial in 2D); the remaining error of the corrected model is what
//!    the blind check measures against its quarter-size generator.
//! 3. **WHERE** (step 2, [`cells`]): phase x channel x region cells, Legendre
//!    smooth test, Holm at `alpha_where` (1e-3).
//! 4. **WHICH** (step 3, [`which`]): for every candidate of the campaign's
//!    library ([`library`]: on network materials the network's components, on
//!    chain materials the effects that [`EffectId::implemented`] says the
//!    engine simulates; others are listed as not evaluated), in parallel (rayon; the result does not depend on the
//!    number of threads): score test with projection and the one-sided rule;
//!    refit with fallback to the null (the secant references and the refit's
//!    extra starts of stress-valued parameters, a yield stress, a threshold, a
//!    critical stress, a strength, follow the calibration trials' peak nominal
//!    stress, [`model::peak_stress_mpa`] and `fem_core::effects::StressScale`,
//!    so that a threshold below the registry's static reference is still
//!    crossed); `LR = 2 (Phi0 - Phi_j)` against the
//!    chi-bar-square with Holm over the candidates at `alpha_which` (0.01) and
//!    the Bonferroni critical value reported; held-out non-inferiority
//!    (`Delta_ho > -2 SE`, the SE of a paired block bootstrap,
//!    [`HeldOut::non_inferior`]); ranking `C_j = LR_j + Delta_ho_j - 2 d_j`.
//! 5. **HOW FAR** (step 4, [`heldout`]): gap closure on smooth-projected
//!    held-out residuals with a 90 % paired-bootstrap interval (fixed seed).
//!
//! **Nuisance parameters.** The score test and the first refit fit an effect's
//! strength parameters only; its nuisance parameters (the slider's hardening
//! `H`, the thinning exponent `m`, the adhesion opening `delta_c`) stay at their
//! registry defaults, since at the null they have no effect to estimate (the
//! Davies problem, diagnosis-details.md §4.2). When that refit is significant
//! on its own (chi-bar-square at `alpha_which`), a second refit frees them
//! ([`Candidate::with_nuisance`], [`which::refine_nuisance`], from the first
//! refit's point) and is kept when it lowers the objective; the LR is then
//! referred to the chi-bar-square of every fitted effect parameter (more
//! conservative). Measured on the seed's gap (VALIDATION.md): a slider truth
//! with `H` = 9.14e-3 MPa against the default 0.01 left four cells flagged at
//! 1.4 to 4 noise units with `H` fixed; with the same truth at `H` = 0.01 every
//! cell fell to about 1 and the verdict was the plain `plastic-slider`.
//!
//! **Verdict.** A gap is present when a WHERE cell is flagged or a candidate's
//! LR is significant. Then: no eligible candidate gives `unexplained`; else
//! the best `C_j` is named, as `tie` (with the runner-up and the experiment
//! that separates them, diagnosis-details.md §4.3 and §5.7) when
//! `C_1 - C_2 < 2 SE` or when the two refits change the residuals in nearly
//! the same way (cosine > 0.9; either condition alone, as §5.4 writes it:
//! [`is_tie`]), and as `partial: <id>` when a cell stays
//! flagged after its refit. No gap: `none`. Eligible means significant and
//! non-inferior on held-out data, `Delta_ho > -2 SE` with the SE of the same
//! paired block bootstrap on the held-out residuals ([`HeldOut::non_inferior`];
//! a whole-segment bootstrap would let a candidate that makes the held-out
//! trials far worse pass). The tie rule's SE is that of a paired block
//! bootstrap (diagnosis-details.md §5.4, "over trials and blocks"): blocks of
//! `round(n^(1/3))` whitened samples redrawn inside every segment, stratified
//! by trial and segment, around the segment's smooth trend, on the calibration
//! and the held-out residuals ([`heldout::block_se`], whose module docs say
//! why). Redrawing whole segments ([`TieBootstrap::Segments`], an option)
//! does not serve: when the lead sits in one separating trial, that SE is
//! about the lead itself, so such a lead is always a tie.
//! [`Verdict::tie_test`] reports the margin and both SEs. (Tried on the
//! development seeds and not kept: ranking by `LR - 2d`, the calibration SE alone and a cosine
//! of 0.95; on seed 101 it turned one correct attribution into a tie and
//! resolved none.)
//!
//! **Composable verdicts** (forward selection, [`SelectionStep`]). When the
//! verdict names a candidate that is eligible and improves the held-out
//! prediction (a positive held-out gain), it joins the model at its fitted
//! values ([`Model::included`]) and the next step tests the candidates left
//! against that baseline by the same rules (score, refit, LR with Holm over
//! the step's candidates, held-out veto, ranking, tie rule). Before each step
//! the candidates named earlier are refitted beside the newest, one sweep of
//! block coordinate descent, each with the unknowns, the others held: a value
//! fitted alone may have absorbed part of the next candidate's signature
//! (measured in the tests: a force offset fitted before the compliance left
//! cells flagged until it was refitted beside it). The selection stops when a
//! step names nothing that improves the held-out prediction, at a tie, or at
//! [`DiagnosisOptions::max_components`] (3). The verdict then names the set,
//! `a + b` (`partial: a + b` when a WHERE cell stays flagged on the baseline
//! that holds them all), and its sentence gives each later step's LR and gap
//! closure of what the step's baseline left, with the interval. Two of the
//! chain's material-point effects never join one model (its inelastic loop
//! runs one); the network's components compose with each other and with the
//! load-path effects.
//!
//! **Not done here** (reported, not hidden): an estimate of `Omega` from
//! replicates (it is fixed by `sample_scale_sd`), replicate ANOVA, the
//! simulator-free checks and the parameter-inconsistency map; the forward
//! selection's joint refit is one coordinate-descent sweep, not a joint
//! fit of every named candidate; the held-out refits are one Gauss-Newton step of case deletion
//! rather than full refits ([`heldout`]); the mesh budget is a two-level
//! correction, not a three-mesh GCI.
//!
//! The API is in-process: the blind self-check ([`blind`]) generates synthetic
//! campaigns as [`wagashi_io::Bundle`]s in memory, calls [`diagnose`] and scores
//! the verdicts.

pub mod blind;
pub mod cells;
pub mod heldout;
pub mod library;
pub mod model;
pub mod stats;
pub mod which;

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use fem_core::effects::EffectId;
pub use library::{CandidateId, Component};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use wagashi_io::{Bundle, MaterialSpec};

pub use cells::Cell;
pub use heldout::{HeldOut, TieBootstrap};
pub use model::{Candidate, Model, ObsChannel, Phase, Region};

use crate::lsq::{EvalError, FitError, Options};
use crate::multistart::{multistart, MultiStartOptions};
use crate::trial::{Campaign, CampaignError};
use stats::{chibar2_sf, critical_value, holm};

/// Why a diagnosis could not be run.
#[derive(Debug, thiserror::Error)]
pub enum DiagnosisError {
    /// A bundle could not be turned into a press problem.
    #[error(transparent)]
    Bundle(#[from] wagashi_io::BundleError),
    /// The trials could not be set up for fitting.
    #[error(transparent)]
    Campaign(#[from] CampaignError),
    /// The baseline calibration could not be run.
    #[error("baseline calibration: {0}")]
    Fit(#[from] FitError),
    /// A simulation at the baseline failed.
    #[error("simulation at the baseline fit: {0}")]
    Simulation(#[from] EvalError),
    /// Something about the input, in words.
    #[error("{0}")]
    Input(String),
}

/// Settings of a diagnosis.
#[derive(Debug, Clone)]
pub struct DiagnosisOptions {
    /// Latin hypercube starts of the baseline calibration besides the start values.
    pub starts: usize,
    /// Seed of the starts and of the bootstrap.
    pub seed: u64,
    /// The candidates to evaluate (`None`: the whole library).
    pub effects: Option<Vec<CandidateId>>,
    /// Family-wise level of the WHERE cells (Holm).
    pub alpha_where: f64,
    /// Family-wise level of the candidates' LR tests (Holm).
    pub alpha_which: f64,
    /// Bootstrap resamples.
    pub bootstrap: usize,
    /// Element size [mm] (default: each bundle's).
    pub size_mm: Option<f64>,
    /// Cylinders by their axisymmetric section.
    pub axisymmetric: bool,
    /// Marker noise [mm].
    pub marker_sigma_mm: f64,
    /// Levenberg-Marquardt settings (baseline and refits).
    pub lsq: Options,
    /// Prior standard deviation `omega` of the per-sample (per-trial) log-scales
    /// on the moduli and on the viscosities (0: no scales; module docs).
    pub sample_scale_sd: f64,
    /// Correct the predictions by a run on a mesh of half the element size
    /// (module docs, step 0).
    pub mesh_correction: bool,
    /// Fixed time steps [s] for every simulation instead of the adaptive control
    /// (`None`, the default: adaptive). For effects the engine does not run on
    /// some adaptive step sequences (the slider right after a release; see
    /// `crate::seed_gap`).
    pub fixed_dt_s: Option<f64>,
    /// How the tie rule's SE of `C_1 - C_2` is resampled (module docs,
    /// "Verdict"; default: blocks inside segments).
    pub tie_bootstrap: TieBootstrap,
    /// The most candidates the forward selection names (module docs,
    /// "Composable verdicts"; 1: the single-candidate diagnosis).
    pub max_components: usize,
}

impl Default for DiagnosisOptions {
    fn default() -> Self {
        Self {
            starts: 4,
            seed: 1,
            effects: None,
            alpha_where: 1e-3,
            alpha_which: 0.01,
            bootstrap: 1000,
            size_mm: None,
            axisymmetric: false,
            marker_sigma_mm: 0.05,
            lsq: Options { max_iterations: 60, ..Options::default() },
            sample_scale_sd: 0.1,
            mesh_correction: true,
            fixed_dt_s: None,
            tie_bootstrap: TieBootstrap::Blocks,
            max_components: 3,
        }
    }
}

/// The stage a progress report is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The baseline calibration's starts.
    Calibration,
    /// The candidates.
    Candidates,
}

/// Progress: stage, done, total (called from worker threads).
pub type ProgressFn<'a> = &'a (dyn Fn(Stage, usize, usize) + Sync);

/// The baseline fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Baseline {
    /// The unknowns' labels (`material.key`).
    pub labels: Vec<String>,
    /// Their fitted values.
    pub values: Vec<f64>,
    /// `1/2 |r|^2`.
    pub objective: f64,
    /// RMS residual [noise units].
    pub rms_noise_units: f64,
    /// Residuals.
    pub num_residuals: usize,
    /// Why the best start stopped.
    pub stop: String,
}

/// The numerical-error budget (step 0).
#[derive(Debug, Clone, PartialEq)]
pub struct NumericalError {
    /// What was refined.
    pub refinement: String,
    /// `|e_num|^2` [noise units squared].
    pub chi2: f64,
    /// RMS of `e_num` [noise units].
    pub rms_noise_units: f64,
    /// Largest `|e_num|` [noise units].
    pub max_abs_noise_units: f64,
    /// `LM_num` per evaluated candidate.
    pub per_candidate: Vec<(CandidateId, f64)>,
    /// The mesh correction at the fit, `|d|^2` [noise units squared, whitened]
    /// (0 without; module docs, step 0).
    pub mesh_chi2: f64,
    /// The part of `|d|^2` the unknowns and the sample scales cannot absorb,
    /// `|(I - P_theta,b) d|^2`: what the gap would have been made of without it.
    pub mesh_chi2_unabsorbed: f64,
}

/// A fitted effect parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedParameter {
    /// The bundle key.
    pub key: &'static str,
    /// The symbol.
    pub name: &'static str,
    /// The unit.
    pub unit: &'static str,
    /// The fitted value (the null when the refit fell back).
    pub value: f64,
    /// The null value.
    pub null: f64,
}

/// One evaluated candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateReport {
    /// The effect.
    pub effect: CandidateId,
    /// `d_j`.
    pub dim: usize,
    /// Score (LM) statistic after the one-sided rule.
    pub score_statistic: f64,
    /// Its p-value.
    pub score_p_value: f64,
    /// Expected parameter change per strength parameter (solver coordinates).
    pub epc: Vec<f64>,
    /// `2 (Phi0 - Phi_j)`, >= 0.
    pub lr: f64,
    /// Its p-value (chi-bar-square for one-sided nulls).
    pub p_value: f64,
    /// The Bonferroni critical value of the LR over the evaluated candidates.
    pub lr_critical: f64,
    /// Holm-significant at `alpha_which`.
    pub significant: bool,
    /// Held-out comparison (None with a single trial and no validation).
    pub heldout: Option<HeldOut>,
    /// Significant and non-inferior on held-out data.
    pub eligible: bool,
    /// `C_j = LR_j + Delta_ho_j - 2 d_j`.
    pub combined: f64,
    /// The fitted effect parameters.
    pub parameters: Vec<FittedParameter>,
    /// The unknowns refitted with the effect.
    pub theta: Vec<f64>,
    /// WHERE cells still flagged after the refit.
    pub remaining_flagged: Vec<String>,
    /// `LM_num` of this candidate.
    pub lm_num: f64,
    /// Refit starts.
    pub refit_starts: usize,
    /// Whether the refit fell back to the null.
    pub fell_back: bool,
    /// Refit starts that failed, in words.
    pub refit_errors: Vec<String>,
}

/// The decision.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// `<effect id>`, `tie`, `partial: <effect id>`, `unexplained` or `none`.
    pub label: String,
    /// The effects named.
    pub effects: Vec<CandidateId>,
    /// One sentence.
    pub sentence: String,
    /// For `tie` (and as advice otherwise): the experiment that would separate the leaders.
    pub separating_experiment: Option<String>,
    /// For `partial`: the cells still flagged.
    pub remaining_cells: Vec<String>,
    /// The tie rule's numbers, when two candidates were eligible.
    pub tie_test: Option<TieTest>,
}

/// One step of the forward selection (module docs, "Composable verdicts").
#[derive(Debug, Clone, PartialEq)]
pub struct SelectionStep {
    /// The candidates in the step's baseline (named by the earlier steps, at
    /// their fitted values).
    pub included: Vec<CandidateId>,
    /// The step's verdict label on the candidates left (as [`Verdict::label`]).
    pub label: String,
    /// The WHERE cells still flagged after the step's verdict (as
    /// [`Verdict::remaining_cells`]).
    pub remaining_cells: Vec<String>,
    /// The candidate the step adds (`None`: the selection stops here).
    pub named: Option<CandidateId>,
    /// The step's baseline objective `Phi0` (the earlier steps' candidates
    /// included, the unknowns refitted).
    pub baseline_objective: f64,
    /// The WHERE cells flagged on the step's baseline.
    pub flagged: Vec<String>,
    /// The named candidate's LR against the step's baseline (0 without one).
    pub lr: f64,
    /// Its p-value (1 without one).
    pub p_value: f64,
    /// Its held-out comparison against the step's baseline (the gap closure
    /// `G` of what the step's baseline leaves, with its 90 % interval).
    pub heldout: Option<HeldOut>,
    /// The step's candidate reports (the first step's are also
    /// [`Diagnosis::candidates`]).
    pub candidates: Vec<CandidateReport>,
}

/// The tie rule between the two best eligible candidates (module docs, "Verdict").
#[derive(Debug, Clone, PartialEq)]
pub struct TieTest {
    /// The runner-up.
    pub runner_up: CandidateId,
    /// `C_1 - C_2`.
    pub margin: f64,
    /// The standard error of the margin the rule used ([`DiagnosisOptions::tie_bootstrap`]).
    pub se: f64,
    /// The block bootstrap's SE (calibration and held-out, [`heldout::block_se`]).
    pub se_blocks: f64,
    /// The whole-segment bootstrap's SE ([`heldout::segment_se`]), for comparison.
    pub se_segments: f64,
    /// The cosine of the two refits' residual changes.
    pub cosine: f64,
}

/// Measured and simulated force of one trial, before and after the named effect.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceCurves {
    /// The trial.
    pub trial: String,
    /// `(t_s, phase)` per sample.
    pub times: Vec<(f64, Phase)>,
    /// Measured [N].
    pub measured: Vec<f64>,
    /// Baseline [N].
    pub baseline: Vec<f64>,
    /// With the named effect [N] (the baseline when none is named).
    pub with_effect: Vec<f64>,
}

/// One marker's places at one photograph [mm], in the model's coordinates (x,
/// y; z in 3D; r, y in the axisymmetric section), mesh correction included.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerPlaces {
    /// The marker's index in its bundle.
    pub marker: usize,
    /// Measured.
    pub measured: Vec<f64>,
    /// The calibrated baseline.
    pub baseline: Vec<f64>,
    /// With the named effect (the baseline when none is named).
    pub with_effect: Vec<f64>,
}

/// Marker positions of one calibration trial at one photograph, measured and
/// simulated before and after the named effect: the specimen's shape.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerShapes {
    /// The trial.
    pub trial: String,
    /// The photograph's time [s].
    pub t_s: f64,
    /// Its phase.
    pub phase: Phase,
    /// Per marker.
    pub markers: Vec<MarkerPlaces>,
}

/// A diagnosis.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosis {
    /// Calibration trials.
    pub trials: Vec<String>,
    /// Validation trials.
    pub validation_trials: Vec<String>,
    /// How held-out residuals were made.
    pub heldout_method: String,
    /// Step 1.
    pub baseline: Baseline,
    /// Step 0.
    pub numerical_error: NumericalError,
    /// Step 2 on the baseline residuals.
    pub where_cells: Vec<Cell>,
    /// Step 3 and 4, in registry order.
    pub candidates: Vec<CandidateReport>,
    /// Candidates not evaluated, and why.
    pub not_evaluated: Vec<(CandidateId, String)>,
    /// The decision (the forward selection's: every named step).
    pub verdict: Verdict,
    /// The forward selection, one entry per step (module docs, "Composable
    /// verdicts"); the first is the single-candidate diagnosis.
    pub selection: Vec<SelectionStep>,
    /// Warnings in words.
    pub warnings: Vec<String>,
    /// Forces for the report, per calibration trial (the fits' predictions).
    pub curves: Vec<ForceCurves>,
    /// Forces for the report, per validation trial (none without
    /// `validation`): the held-out predictions of the baseline and of the model
    /// with the named set, each trial anchored on its two sample scales as the
    /// gap closure is measured.
    pub validation_curves: Vec<ForceCurves>,
    /// Per calibration trial, the marker shapes at the last photograph of the
    /// hold and of the recovery (none without markers).
    pub shapes: Vec<MarkerShapes>,
    /// The force noise model per calibration trial: (trial, sigma [N], lag-1 correlation).
    pub force_noise: Vec<(String, f64, f64)>,
    /// The calibration trials' peak nominal stress [MPa] that the stress-valued
    /// effect references follow ([`model::peak_stress_mpa`]; `None`: the
    /// registry's static references).
    pub peak_stress_mpa: Option<f64>,
}

impl Diagnosis {
    /// The candidate report of `effect`, if evaluated.
    pub fn candidate(&self, effect: impl Into<CandidateId>) -> Option<&CandidateReport> {
        let effect = effect.into();
        self.candidates.iter().find(|c| c.effect == effect)
    }
}

/// Work of one candidate, kept for the decision.
struct Evaluated {
    report: CandidateReport,
    residuals: Vec<f64>,
    heldout: Option<Vec<f64>>,
    /// Every parameter's fitted value (registry order), for the next step.
    values: Vec<f64>,
}

/// Step ends with every step halved.
fn halved(steps: &[Vec<f64>]) -> Vec<Vec<f64>> {
    steps
        .iter()
        .map(|ends| {
            let mut out = Vec::with_capacity(2 * ends.len());
            let mut prev = 0.0;
            for &t in ends {
                out.push(0.5 * (prev + t));
                out.push(t);
                prev = t;
            }
            out
        })
        .collect()
}

/// Validation residuals at `theta` (and the candidate at `u`), each trial anchored
/// on its sample scales.
fn validation_heldout(
    vm: &Model,
    theta: &[f64],
    candidate: Option<(&Candidate, &[f64])>,
) -> Result<Vec<f64>, EvalError> {
    let kinds = vm.scale_kind();
    // Validation trials carry no fitted scales: anchoring re-estimates them.
    let theta = &theta[..vm.unknowns.len()];
    let p = theta.len();
    let parts: Vec<Vec<f64>> = (0..vm.num_trials())
        .into_par_iter()
        .map(|k| {
            let (r, cols) = vm.trial_jacobian(k, theta, candidate, true)?;
            let j = DMatrix::from_fn(r.len(), p, |i, c| cols[c][i]);
            Ok(heldout::anchor(&DVector::from_vec(r), &j, theta, &kinds).iter().copied().collect())
        })
        .collect::<Result<_, EvalError>>()?;
    Ok(parts.concat())
}

/// The diagnoser's model of `bundles` on `campaign`'s materials and unknowns,
/// with `options`' element size times `refinement` (0.5: step 0's half-size
/// run), formulation, marker noise and fixed steps.
pub(super) fn diagnosis_model(
    bundles: &[Bundle],
    campaign: &Campaign,
    options: &DiagnosisOptions,
    refinement: f64,
) -> Result<Model, DiagnosisError> {
    let mut model = Model::with_refinement(
        bundles,
        &campaign.materials,
        campaign.unknowns.clone(),
        options.size_mm,
        options.axisymmetric,
        options.marker_sigma_mm,
        refinement,
    )?;
    model.settings.fixed_dt_s = options.fixed_dt_s;
    Ok(model)
}

/// Whether every material of the model is a network (the library of
/// [`library::library_for`]).
fn all_networks(model: &Model) -> bool {
    !model.table.is_empty() && model.table.values().all(|m| m.model == wagashi_io::bundle::Model::Network)
}

/// Why a candidate is not evaluated, if it is not.
fn not_evaluable(model: &Model, candidate: CandidateId) -> Option<String> {
    let networks = all_networks(model);
    match candidate {
        CandidateId::Effect(effect) => {
            if !effect.implemented() {
                Some("not implemented in the engine yet".into())
            } else if model.bundles_set(effect) {
                Some("set in the bundles' [effects]: part of the baseline".into())
            } else if effect == EffectId::Ageing && !model.has_age() {
                Some("no trial gives the covariate age_h, through which ageing acts".into())
            } else if networks && effect.hook() == fem_core::effects::HookPoint::MaterialPoint {
                Some("a material-point effect of the seed's chain; the materials are networks, whose components are tested instead".into())
            } else {
                None
            }
        }
        CandidateId::Component(c) => {
            if !networks {
                return Some(
                    "a component of the network model; the materials are not all networks (model = \"network\")".into(),
                );
            }
            model.table.iter().find_map(|(name, spec)| match spec.to_network() {
                Ok(net) => c.not_applicable(&net).map(|why| format!("material {name}: {why}")),
                Err(_) => None,
            })
        }
    }
}

/// Runs the diagnosis (module docs) on `calibration` bundles, with optional
/// `validation` bundles, materials `start` (as `wagashi fit --materials`).
pub fn diagnose(
    calibration: &[Bundle],
    validation: &[Bundle],
    start: &BTreeMap<String, MaterialSpec>,
    options: &DiagnosisOptions,
    progress: ProgressFn<'_>,
) -> Result<Diagnosis, DiagnosisError> {
    for b in calibration.iter().chain(validation) {
        if b.force.is_none() && b.markers.is_empty() {
            return Err(DiagnosisError::Input(format!(
                "{}: has no measured data ([data] force or markers): nothing to diagnose",
                b.experiment_file().display()
            )));
        }
    }
    let campaign = Campaign::new(calibration, start, options.size_mm, options.axisymmetric)?;
    if campaign.unknowns.is_empty() {
        return Err(DiagnosisError::Input(
            "every material parameter is given: nothing to calibrate (give a material only its model, or free \
             parameters with --materials)"
                .into(),
        ));
    }
    let mut model = diagnosis_model(calibration, &campaign, options, 1.0)?;
    model.sample_scale_sd = options.sample_scale_sd.max(0.0);
    let mut fine =
        if options.mesh_correction { Some(diagnosis_model(calibration, &campaign, options, 0.5)?) } else { None };
    let vmodel = if validation.is_empty() { None } else { Some(diagnosis_model(validation, &campaign, options, 1.0)?) };
    let mut warnings = Vec::new();

    // Step 1: the baseline (on the mesh-corrected model: the correction at the
    // start values, then at the fit and a polish).
    let mut x0 = campaign.values();
    x0.resize(model.num_theta(), 0.0);
    if let Some(f) = fine.as_mut() {
        model.set_mesh_correction(f, &x0)?;
    }
    let ms_options = MultiStartOptions { num_starts: options.starts, seed: options.seed, fit: options.lsq.clone() };
    let report_start = |done: usize, total: usize| progress(Stage::Calibration, done, total);
    let mut base = {
        let problem = model::Fitting { model: &model, candidate: None };
        let ms = multistart(&problem, &problem.specs(), &x0, &ms_options, Some(&report_start))?;
        ms.best().clone()
    };
    let mut mesh_d = Vec::new();
    if let Some(f) = fine.as_mut() {
        mesh_d = model.set_mesh_correction(f, &base.x)?;
        let problem = model::Fitting { model: &model, candidate: None };
        base = crate::lsq::levenberg_marquardt(&problem, &problem.specs(), &base.x, &options.lsq)?;
    }
    if !base.stop.converged() {
        warnings.push(format!("the baseline calibration did not converge ({})", base.stop));
    }
    let theta = base.x.clone();
    let r0 = base.residuals.clone();
    let j0 = base.jacobian.clone();
    let phi0 = base.objective;
    let n = model.num_residuals();
    let baseline = Baseline {
        labels: model.unknowns.iter().map(|u| u.label()).chain(model.scale_labels()).collect(),
        values: theta.clone(),
        objective: phi0,
        rms_noise_units: (2.0 * phi0 / n as f64).sqrt(),
        num_residuals: n,
        stop: base.stop.to_string(),
    };

    // Step 0 at the fit: halved steps on the frozen discretisation.
    let (r_adaptive, steps) = model.residuals(&theta, None, None)?;
    let (r_frozen, _) = model.residuals(&theta, None, Some(&steps))?;
    let (r_half, _) = model.residuals(&theta, None, Some(&halved(&steps)))?;
    let e_num: Vec<f64> = r_half.iter().zip(&r_frozen).map(|(a, b)| a - b).collect();
    let chi2_num: f64 = e_num.iter().map(|e| e * e).sum();

    // Step 2.
    let segments = cells::segments(&model);
    let where_cells = cells::where_table(&segments, &r0, options.alpha_where);

    // Held-out residuals of the baseline.
    let kinds = model.scale_kind();
    let (ho_segments, h0, heldout_method) = match &vmodel {
        Some(vm) => (
            cells::segments(vm),
            Some(validation_heldout(vm, &theta, None)?),
            "validation trials at the calibrated parameters, each anchored on its two sample scales".to_string(),
        ),
        None => (
            segments.clone(),
            heldout::leave_one_out(&r0, &j0, &model.offsets, &theta, &kinds),
            "leave one calibration trial out (one Gauss-Newton step of case deletion), each anchored on its two \
             sample scales"
                .to_string(),
        ),
    };
    if h0.is_none() {
        warnings.push("one calibration trial and no --validate: no held-out check and no gap closure".into());
    }
    let samples = heldout::resamples(ho_segments.len(), options.bootstrap, options.seed);

    // Step 3.
    let library: Vec<CandidateId> =
        options.effects.clone().unwrap_or_else(|| library::library_for(all_networks(&model)));
    let mut not_evaluated = Vec::new();
    let mut to_evaluate = Vec::new();
    for effect in CandidateId::all().into_iter().filter(|e| library.contains(e)) {
        match not_evaluable(&model, effect) {
            Some(why) => not_evaluated.push((effect, why)),
            None => to_evaluate.push(effect),
        }
    }
    let peak_stress_mpa = model::peak_stress_mpa(calibration);
    let at = AtBaseline {
        peak_stress_mpa,
        theta: &theta,
        r0: &r0,
        j0: &j0,
        phi0,
        steps: &steps,
        r_frozen: &r_frozen,
        r_adaptive: &r_adaptive,
        e_num: &e_num,
    };
    let done = AtomicUsize::new(0);
    let total = to_evaluate.len();
    progress(Stage::Candidates, 0, total);
    let results: Vec<Result<Evaluated, String>> = to_evaluate
        .par_iter()
        .map(|&effect| {
            let out = evaluate(&model, vmodel.as_ref(), effect, &at, &segments, options);
            progress(Stage::Candidates, done.fetch_add(1, Ordering::Relaxed) + 1, total);
            out.map_err(|e| error_chain(&e))
        })
        .collect();
    let mut evaluated = Vec::new();
    for (effect, r) in to_evaluate.iter().zip(results) {
        match r {
            Ok(e) => evaluated.push(e),
            Err(why) => not_evaluated.push((*effect, format!("failed: {why}"))),
        }
    }
    not_evaluated.sort_by_key(|(e, _)| *e);

    // Multiplicity, held-out, ranking.
    rank(&mut evaluated, h0.as_deref(), &ho_segments, &samples, options);

    let (mesh_chi2, mesh_chi2_unabsorbed) = if mesh_d.is_empty() {
        (0.0, 0.0)
    } else {
        let mut d = mesh_d.clone();
        d.resize(r0.len(), 0.0);
        let q = heldout::range_basis(&j0.columns(0, theta.len()).into_owned());
        let dv = DVector::from_vec(d);
        (dv.norm_squared(), heldout::project_out(&q, &dv).norm_squared())
    };
    let numerical_error = NumericalError {
        refinement: if mesh_d.is_empty() {
            "time steps halved (every step of the baseline's adaptive sequence split in two); mesh not refined".into()
        } else {
            "mesh: predictions corrected by a run on half the element size (at the start values, then at the fit); \
             time steps halved (every step of the baseline's adaptive sequence split in two)"
                .into()
        },
        mesh_chi2,
        mesh_chi2_unabsorbed,
        chi2: chi2_num,
        rms_noise_units: (chi2_num / n.max(1) as f64).sqrt(),
        max_abs_noise_units: e_num.iter().map(|e| e.abs()).fold(0.0, f64::max),
        per_candidate: evaluated.iter().map(|e| (e.report.effect, e.report.lm_num)).collect(),
    };
    if mesh_chi2_unabsorbed > 1.0 {
        warnings.push(format!(
            "numerical: the mesh alone would leave {mesh_chi2_unabsorbed:.3e} noise units squared that the parameters \
             cannot absorb; the predictions are corrected by a half-size run (step 0), whose own remaining error is \
             not estimated"
        ));
    }
    if chi2_num > 1.0 {
        warnings.push(format!(
            "numerical: the time discretisation error is chi2_num = {chi2_num:.3e} noise units squared (> 1); \
             tighten the step tolerance before trusting small effects"
        ));
    }
    for e in &evaluated {
        if e.report.lm_num > 1.0 {
            warnings.push(format!(
                "numerical: LM_num = {:.3e} > 1 for {}: the discretisation error resembles its signature",
                e.report.lm_num, e.report.effect
            ));
        }
    }

    let mut verdict = decide(&where_cells, &evaluated, &r0, h0.as_deref(), &segments, &ho_segments, options);
    // A verdict says what it could not test: candidates whose runs failed on these
    // trials (e.g. effects the engine does not run with contact tools) are named.
    let failed: Vec<&str> =
        not_evaluated.iter().filter(|(_, why)| why.starts_with("failed: ")).map(|(e, _)| e.id()).collect();
    if !failed.is_empty() && verdict.label != "none" {
        verdict.sentence.push_str(&format!(
            " Not tested, their runs failed on these trials: {} (see not_evaluated).",
            failed.join(", ")
        ));
    }
    let named = verdict.effects.first().and_then(|id| evaluated.iter().find(|e| e.report.effect == *id));
    let mut after = named.map_or(r0.clone(), |e| e.residuals.clone());
    let mut after_heldout = named.and_then(|e| e.heldout.clone());

    // The forward selection (module docs, "Composable verdicts").
    let mut selection = vec![selection_step(Vec::new(), &where_cells, &verdict, &evaluated, phi0)];
    if options.max_components > 1 && selection[0].named.is_some() {
        let ctx = SelectionContext {
            to_evaluate: &to_evaluate,
            peak_stress_mpa,
            e_num: &e_num,
            segments: &segments,
            ho_segments: &ho_segments,
            samples: &samples,
        };
        let mut vmodel = vmodel.clone();
        let (more, last, notes) =
            forward_selection(&mut model, &mut vmodel, (&verdict, &evaluated), &ctx, options, progress);
        model.included.clear();
        warnings.extend(notes);
        selection.extend(more);
        if let Some((r, h)) = last {
            after = r;
            after_heldout = h;
        }
        compose_verdict(&mut verdict, &selection);
    }
    let curves = force_curves(&model, &r0, &after);
    let validation_curves = match (&vmodel, &h0) {
        (Some(vm), Some(h0)) => force_curves(vm, h0, after_heldout.as_deref().unwrap_or(h0)),
        _ => Vec::new(),
    };
    let shapes = marker_shapes(&model, &r0, &after);
    Ok(Diagnosis {
        trials: model.trial_names(),
        validation_trials: vmodel.as_ref().map(Model::trial_names).unwrap_or_default(),
        heldout_method,
        baseline,
        numerical_error,
        where_cells,
        candidates: evaluated.into_iter().map(|e| e.report).collect(),
        not_evaluated,
        verdict,
        selection,
        warnings,
        curves,
        validation_curves,
        shapes,
        force_noise: model.trials.iter().map(|t| (t.name.clone(), t.force_sigma_n, t.force_rho)).collect(),
        peak_stress_mpa,
    })
}

/// An error and its sources, joined with `: `, each once (a source the line
/// already holds, printed by its wrapper's own message, is not repeated).
fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut source = e.source();
    while let Some(inner) = source {
        let message = inner.to_string();
        if !s.contains(&message) {
            s.push_str(": ");
            s.push_str(&message);
        }
        source = inner.source();
    }
    s
}

/// Steps 3 and 4 of one candidate (module docs).
/// What every candidate starts from: the baseline fit and its runs.
#[derive(Clone, Copy)]
struct AtBaseline<'a> {
    /// The stress level of the candidates' references ([`model::peak_stress_mpa`]).
    peak_stress_mpa: Option<f64>,
    theta: &'a [f64],
    r0: &'a [f64],
    j0: &'a DMatrix<f64>,
    phi0: f64,
    steps: &'a [Vec<f64>],
    r_frozen: &'a [f64],
    r_adaptive: &'a [f64],
    e_num: &'a [f64],
}

fn evaluate(
    model: &Model,
    vmodel: Option<&Model>,
    effect: CandidateId,
    at: &AtBaseline<'_>,
    segments: &[cells::Segment],
    options: &DiagnosisOptions,
) -> Result<Evaluated, EvalError> {
    let AtBaseline { peak_stress_mpa, theta, r0, j0, phi0, steps, r_frozen, r_adaptive, e_num } = *at;
    let candidate = Candidate::at_stress(effect, peak_stress_mpa);
    let columns = which::effect_columns(model, theta, &candidate, steps, r_frozen, r_adaptive)?;
    let score = which::score(&candidate, &columns, r0, j0);
    let lm_num = which::absorbed(&score.projected, e_num);
    let mut refit = which::refit(model, &candidate, theta, &score.epc, phi0, &options.lsq);
    // A significant strength fit frees the effect's nuisance parameters (module
    // docs, "Nuisance parameters"): kept when it lowers the objective.
    let mut candidate = candidate;
    if let Some(f) = &refit.fit {
        let lr = 2.0 * (phi0 - f.objective);
        let q = candidate.coords.iter().filter(|c| c.one_sided()).count();
        if Candidate::has_nuisance(effect) && chibar2_sf(lr, candidate.dim(), q) < options.alpha_which {
            let extended = Candidate::with_nuisance(effect, peak_stress_mpa);
            match which::refine_nuisance(model, &extended, &f.x, f.objective, &options.lsq) {
                Ok(Some(better)) => {
                    refit.fit = Some(better);
                    candidate = extended;
                }
                Ok(None) => {}
                Err(e) => refit.errors.push(format!("with its nuisance parameters freed: {e}")),
            }
        }
    }
    let p = theta.len();
    let (theta1, u1, r1, objective, fell_back) = match &refit.fit {
        Some(f) => (f.x[..p].to_vec(), f.x[p..].to_vec(), f.residuals.clone(), f.objective, false),
        None => (theta.to_vec(), candidate.null(), r0.to_vec(), phi0, true),
    };
    let lr = (2.0 * (phi0 - objective)).max(0.0);
    let d = candidate.dim();
    let q = candidate.coords.iter().filter(|c| c.one_sided()).count();
    let p_value = chibar2_sf(lr, d, q);
    let kinds = model.scale_kind();
    let heldout = match (vmodel, &refit.fit) {
        (Some(vm), Some(_)) => Some(validation_heldout(vm, &theta1, Some((&candidate, &u1)))?),
        (Some(vm), None) => Some(validation_heldout(vm, theta, None)?),
        (None, Some(f)) => heldout::leave_one_out(&r1, &f.jacobian, &model.offsets, &theta1, &kinds),
        (None, None) => heldout::leave_one_out(r0, j0, &model.offsets, theta, &kinds),
    };
    let remaining_flagged = cells::where_table(segments, &r1, options.alpha_where)
        .into_iter()
        .filter(|c| c.flagged)
        .map(|c| c.label())
        .collect();
    let values = candidate.values(&u1);
    let parameters = candidate
        .coords
        .iter()
        .map(|c| FittedParameter {
            key: c.spec.key,
            name: c.spec.name,
            unit: c.spec.unit,
            value: values[c.index],
            null: c.spec.null,
        })
        .collect();
    let report = CandidateReport {
        effect,
        dim: d,
        score_statistic: score.statistic,
        score_p_value: score.p_value,
        epc: score.epc.clone(),
        lr,
        p_value,
        lr_critical: f64::NAN,
        significant: false,
        heldout: None,
        eligible: false,
        combined: f64::NAN,
        parameters,
        theta: theta1,
        remaining_flagged,
        lm_num,
        refit_starts: refit.starts,
        fell_back,
        refit_errors: refit.errors,
    };
    Ok(Evaluated { report, residuals: r1, heldout, values })
}

/// Multiplicity, held-out comparison and ranking of one step's candidates
/// (module docs, step 3): Holm at `alpha_which`, the Bonferroni critical value,
/// the held-out gain against the step's baseline `h0`, eligibility and `C_j`.
fn rank(
    evaluated: &mut [Evaluated],
    h0: Option<&[f64]>,
    ho_segments: &[cells::Segment],
    samples: &[Vec<usize>],
    options: &DiagnosisOptions,
) {
    let m = evaluated.len().max(1);
    let p_values: Vec<f64> = evaluated.iter().map(|e| e.report.p_value).collect();
    let significant = holm(&p_values, options.alpha_which);
    for (e, sig) in evaluated.iter_mut().zip(significant) {
        let d = e.report.dim;
        let q = Candidate::new(e.report.effect).coords.iter().filter(|c| c.one_sided()).count();
        e.report.lr_critical = critical_value(options.alpha_which / m as f64, |x| chibar2_sf(x, d, q));
        e.report.significant = sig;
        e.report.heldout = match (h0, &e.heldout) {
            (Some(a), Some(b)) => Some(heldout::compare(ho_segments, a, b, samples)),
            _ => None,
        };
        let gain = e.report.heldout.as_ref().map_or(0.0, |h| h.gain);
        e.report.eligible = sig && e.report.heldout.as_ref().is_none_or(HeldOut::non_inferior);
        e.report.combined = e.report.lr + gain - 2.0 * d as f64;
    }
}

/// The candidate a step names for the next one, if any: the verdict's first
/// candidate when it is not a tie, is eligible and improves the held-out
/// prediction (module docs, "Composable verdicts").
fn step_named<'a>(verdict: &Verdict, evaluated: &'a [Evaluated]) -> Option<&'a Evaluated> {
    if verdict.label == "tie" {
        return None;
    }
    let id = *verdict.effects.first()?;
    let e = evaluated.iter().find(|e| e.report.effect == id)?;
    let improves = e.report.heldout.as_ref().is_none_or(|h| h.gain > 0.0);
    (e.report.eligible && improves).then_some(e)
}

/// Whether `candidate` can join the candidates `included`: the chain's
/// material-point effects act one at a time on its inelastic loop.
fn composable(candidate: CandidateId, included: &[CandidateId]) -> bool {
    let chain_point =
        |c: &CandidateId| c.effect().is_some_and(|e| e.hook() == fem_core::effects::HookPoint::MaterialPoint);
    if included.contains(&candidate) {
        return false;
    }
    !(chain_point(&candidate) && included.iter().any(chain_point))
}

/// A step's entry from its verdict and candidates.
fn selection_step(
    included: Vec<CandidateId>,
    where_cells: &[Cell],
    verdict: &Verdict,
    evaluated: &[Evaluated],
    baseline_objective: f64,
) -> SelectionStep {
    let named = step_named(verdict, evaluated);
    SelectionStep {
        included,
        label: verdict.label.clone(),
        remaining_cells: verdict.remaining_cells.clone(),
        named: named.map(|e| e.report.effect),
        baseline_objective,
        flagged: where_cells.iter().filter(|c| c.flagged).map(Cell::label).collect(),
        lr: named.map_or(0.0, |e| e.report.lr),
        p_value: named.map_or(1.0, |e| e.report.p_value),
        heldout: named.and_then(|e| e.report.heldout.clone()),
        candidates: evaluated.iter().map(|e| e.report.clone()).collect(),
    }
}

/// The residuals and held-out residuals (none without a held-out check) with a
/// step's named candidate.
type NamedResiduals = (Vec<f64>, Option<Vec<f64>>);

/// A later step, what it names for the next (candidate, values, unknowns) and
/// the residuals with its named candidate.
type StepOutcome = (SelectionStep, Option<(CandidateId, Vec<f64>, Vec<f64>)>, Option<NamedResiduals>);

/// What the forward selection's later steps share with the first.
struct SelectionContext<'a> {
    to_evaluate: &'a [CandidateId],
    peak_stress_mpa: Option<f64>,
    e_num: &'a [f64],
    segments: &'a [cells::Segment],
    ho_segments: &'a [cells::Segment],
    samples: &'a [Vec<usize>],
}

/// The forward selection's steps after the first (module docs, "Composable
/// verdicts"): while the last step names a candidate and fewer than
/// `max_components` are named, the candidate joins the model at its fitted
/// values, the earlier candidates are refitted beside it (one sweep of block
/// coordinate descent, each with the unknowns), the unknowns are refitted, and
/// the candidates left are tested against that baseline by the first step's
/// rules. Returns the
/// new steps, the residuals and held-out residuals with the last named
/// candidate (for the report's "after" curves) and warnings.
fn forward_selection(
    model: &mut Model,
    vmodel: &mut Option<Model>,
    first: (&Verdict, &[Evaluated]),
    ctx: &SelectionContext<'_>,
    options: &DiagnosisOptions,
    progress: ProgressFn<'_>,
) -> (Vec<SelectionStep>, Option<NamedResiduals>, Vec<String>) {
    let mut steps = Vec::new();
    let mut warnings = Vec::new();
    let mut next = step_named(first.0, first.1).map(|e| (e.report.effect, e.values.clone(), e.report.theta.clone()));
    let mut last = step_named(first.0, first.1).map(|e| (e.residuals.clone(), e.heldout.clone()));
    let kinds = model.scale_kind();
    while let Some((id, values, start)) = next.take() {
        if model.included.len() + 1 >= options.max_components {
            break;
        }
        model.included.push((id, values));
        // The earlier candidates' values were fitted before the newest joined:
        // one sweep of block coordinate descent refits each with the unknowns,
        // the others held (the newest was just refitted with the unknowns).
        let mut start = start;
        for j in 0..model.included.len() - 1 {
            let (cj, current) = model.included.remove(j);
            let mut cand = Candidate::at_stress(cj, ctx.peak_stress_mpa);
            cand.defaults = current.clone();
            let mut x0 = start.clone();
            x0.extend(cand.coords.iter().map(|c| match (c.inverse, current[c.index]) {
                (true, v) if v.is_infinite() => 0.0,
                (true, v) => 1.0 / v,
                (false, v) => v,
            }));
            let mut lsq = options.lsq.clone();
            if !cj.has_sensitivities() {
                lsq.jacobian_with_trial = false;
            }
            let problem = model::Fitting { model, candidate: Some(&cand) };
            let p = start.len();
            let refit = crate::lsq::levenberg_marquardt(&problem, &problem.specs(), &x0, &lsq);
            let values = match refit {
                Ok(f) => {
                    start = f.x[..p].to_vec();
                    cand.values(&f.x[p..])
                }
                Err(e) => {
                    warnings.push(format!(
                        "forward selection: refitting {cj} beside the others failed: {}",
                        error_chain(&e)
                    ));
                    current
                }
            };
            model.included.insert(j, (cj, values));
        }
        if let Some(vm) = vmodel.as_mut() {
            vm.included = model.included.clone();
        }
        let included: Vec<CandidateId> = model.included.iter().map(|(c, _)| *c).collect();
        let names = included.iter().map(|c| c.id()).collect::<Vec<_>>().join(" + ");
        let step = (|| -> Result<StepOutcome, String> {
            let problem = model::Fitting { model, candidate: None };
            let fit = crate::lsq::levenberg_marquardt(&problem, &problem.specs(), &start, &options.lsq)
                .map_err(|e| error_chain(&e))?;
            let theta = fit.x.clone();
            let (r_adaptive, steps_t) = model.residuals(&theta, None, None).map_err(|e| error_chain(&e))?;
            let (r_frozen, _) = model.residuals(&theta, None, Some(&steps_t)).map_err(|e| error_chain(&e))?;
            let where_cells = cells::where_table(ctx.segments, &fit.residuals, options.alpha_where);
            let h0 = match vmodel.as_ref() {
                Some(vm) => Some(validation_heldout(vm, &theta, None).map_err(|e| error_chain(&e))?),
                None => heldout::leave_one_out(&fit.residuals, &fit.jacobian, &model.offsets, &theta, &kinds),
            };
            let at = AtBaseline {
                peak_stress_mpa: ctx.peak_stress_mpa,
                theta: &theta,
                r0: &fit.residuals,
                j0: &fit.jacobian,
                phi0: fit.objective,
                steps: &steps_t,
                r_frozen: &r_frozen,
                r_adaptive: &r_adaptive,
                e_num: ctx.e_num,
            };
            let remaining: Vec<CandidateId> =
                ctx.to_evaluate.iter().copied().filter(|c| composable(*c, &included)).collect();
            let done = AtomicUsize::new(0);
            progress(Stage::Candidates, 0, remaining.len());
            let m: &Model = model;
            let mut evaluated: Vec<Evaluated> = remaining
                .par_iter()
                .map(|&c| {
                    let out = evaluate(m, vmodel.as_ref(), c, &at, ctx.segments, options);
                    progress(Stage::Candidates, done.fetch_add(1, Ordering::Relaxed) + 1, remaining.len());
                    out
                })
                .collect::<Vec<_>>()
                .into_iter()
                .filter_map(Result::ok)
                .collect();
            rank(&mut evaluated, h0.as_deref(), ctx.ho_segments, ctx.samples, options);
            let verdict =
                decide(&where_cells, &evaluated, &fit.residuals, h0.as_deref(), ctx.segments, ctx.ho_segments, options);
            let step = selection_step(included.clone(), &where_cells, &verdict, &evaluated, fit.objective);
            let named = step_named(&verdict, &evaluated);
            Ok((
                step,
                named.map(|e| (e.report.effect, e.values.clone(), e.report.theta.clone())),
                named.map(|e| (e.residuals.clone(), e.heldout.clone())),
            ))
        })();
        match step {
            Ok((step, n, residuals)) => {
                steps.push(step);
                if residuals.is_some() {
                    last = residuals;
                }
                next = n;
            }
            Err(why) => {
                warnings.push(format!("forward selection: the step with {names} included failed: {why}"));
                break;
            }
        }
    }
    (steps, last, warnings)
}

/// The verdict of the forward selection (module docs, "Composable
/// verdicts"): with two or more named steps, the label names the set (`a + b`,
/// `partial: a + b` when a cell stays flagged with the whole set) and the
/// sentence says what each later step added; with one, the first step's
/// verdict, its sentence saying why the selection stopped.
fn compose_verdict(verdict: &mut Verdict, selection: &[SelectionStep]) {
    let named: Vec<&SelectionStep> = selection.iter().filter(|s| s.named.is_some()).collect();
    let mut sentence = String::new();
    for s in selection.iter().skip(1) {
        let with = s.included.iter().map(|c| c.id()).collect::<Vec<_>>().join(" + ");
        match (s.named, &s.heldout) {
            (Some(c), Some(h)) => sentence.push_str(&format!(
                " With {with} included, {c} is named next (LR {:.1}; it closes {:.2} [{:.2}, {:.2}] of the held-out gap \
                 that remains).",
                s.lr, h.closure, h.closure_ci90[0], h.closure_ci90[1]
            )),
            (Some(c), None) => sentence.push_str(&format!(" With {with} included, {c} is named next (LR {:.1}).", s.lr)),
            (None, _) => sentence.push_str(&format!(
                " With {with} included, no further candidate is named and improves the held-out prediction (step \
                 verdict: {}).",
                s.label
            )),
        }
    }
    if named.len() >= 2 {
        let ids: Vec<CandidateId> = named.iter().filter_map(|s| s.named).collect();
        let set = ids.iter().map(|c| c.id()).collect::<Vec<_>>().join(" + ");
        // What stays flagged with the whole set: the WHERE cells of the step
        // after the last named one (its baseline holds them all, refitted
        // together), else the last named step's own remaining cells.
        let remaining = match selection.last() {
            Some(s) if s.named.is_none() => s.flagged.clone(),
            _ => named.last().expect("two named steps").remaining_cells.clone(),
        };
        verdict.label = if remaining.is_empty() { set } else { format!("partial: {set}") };
        verdict.effects = ids;
        verdict.remaining_cells = remaining;
    }
    verdict.sentence.push_str(&sentence);
}

fn decide(
    where_cells: &[Cell],
    evaluated: &[Evaluated],
    r0: &[f64],
    h0: Option<&[f64]>,
    segments: &[cells::Segment],
    ho_segments: &[cells::Segment],
    options: &DiagnosisOptions,
) -> Verdict {
    let flagged: Vec<String> = where_cells.iter().filter(|c| c.flagged).map(Cell::label).collect();
    let gap = !flagged.is_empty() || evaluated.iter().any(|e| e.report.significant);
    if !gap {
        return Verdict {
            label: "none".into(),
            effects: Vec::new(),
            sentence: "No gap: no WHERE cell is flagged and no candidate's likelihood ratio is significant; the \
                       baseline fits the trials within the noise."
                .into(),
            separating_experiment: None,
            remaining_cells: Vec::new(),
            tie_test: None,
        };
    }
    let mut eligible: Vec<&Evaluated> = evaluated.iter().filter(|e| e.report.eligible).collect();
    eligible
        .sort_by(|a, b| b.report.combined.total_cmp(&a.report.combined).then(a.report.effect.cmp(&b.report.effect)));
    let Some(best) = eligible.first() else {
        return Verdict {
            label: "unexplained".into(),
            effects: Vec::new(),
            sentence: format!(
                "A gap is present ({}) but no candidate of the library explains it significantly and holds up on \
                 held-out data: unexplained, possibly out of the library.",
                if flagged.is_empty() { "significant candidate tests".to_string() } else { flagged.join(", ") }
            ),
            separating_experiment: None,
            remaining_cells: flagged,
            tie_test: None,
        };
    };
    let id = best.report.effect;
    let mut tie_test = None;
    if let Some(second) = eligible.get(1) {
        let samples = heldout::resamples(segments.len(), options.bootstrap, options.seed ^ 0x71e);
        let mut seg2 = heldout::segment_se(segments, &best.residuals, &second.residuals, &samples).powi(2);
        let mut block2 = heldout::block_se(segments, &best.residuals, &second.residuals).powi(2);
        if let (Some(_), Some(h1), Some(h2)) = (h0, &best.heldout, &second.heldout) {
            let s2 = heldout::resamples(ho_segments.len(), options.bootstrap, options.seed ^ 0x71e);
            seg2 += heldout::segment_se(ho_segments, h1, h2, &s2).powi(2);
            block2 += heldout::block_se(ho_segments, h1, h2).powi(2);
        }
        let se2 = match options.tie_bootstrap {
            TieBootstrap::Blocks => block2,
            TieBootstrap::Segments => seg2,
        };
        let d1: Vec<f64> = r0.iter().zip(&best.residuals).map(|(a, b)| a - b).collect();
        let d2: Vec<f64> = r0.iter().zip(&second.residuals).map(|(a, b)| a - b).collect();
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let cos = stats::dot(&d1, &d2) / (norm(&d1) * norm(&d2)).max(1e-300);
        let margin = best.report.combined - second.report.combined;
        tie_test = Some(TieTest {
            runner_up: second.report.effect,
            margin,
            se: se2.sqrt(),
            se_blocks: block2.sqrt(),
            se_segments: seg2.sqrt(),
            cosine: cos,
        });
        if is_tie(margin, se2.sqrt(), cos) {
            let other = second.report.effect;
            let experiment = separating_experiment(id, other);
            return Verdict {
                label: "tie".into(),
                effects: vec![id, other],
                sentence: format!(
                    "A gap is present; {id} and {other} explain it about equally (C = {:.1} vs {:.1}, margin {:.1} \
                     against 2 SE = {:.1}; cosine of their corrections {:.2}): a tie. {experiment}",
                    best.report.combined,
                    second.report.combined,
                    margin,
                    2.0 * se2.sqrt(),
                    cos
                ),
                separating_experiment: Some(experiment),
                remaining_cells: best.report.remaining_flagged.clone(),
                tie_test: tie_test.clone(),
            };
        }
    }
    if !best.report.remaining_flagged.is_empty() {
        return Verdict {
            label: format!("partial: {id}"),
            effects: vec![id],
            sentence: format!(
                "{id} explains part of the gap (LR = {:.1}) but cells stay flagged after it is added: {}.",
                best.report.lr,
                best.report.remaining_flagged.join(", ")
            ),
            separating_experiment: None,
            remaining_cells: best.report.remaining_flagged.clone(),
            tie_test: tie_test.clone(),
        };
    }
    let closure = best
        .report
        .heldout
        .as_ref()
        .map(|h| {
            format!(
                "; on held-out data it closes G = {:.2} [{:.2}, {:.2}] of the gap",
                h.closure, h.closure_ci90[0], h.closure_ci90[1]
            )
        })
        .unwrap_or_default();
    Verdict {
        label: id.id().to_string(),
        effects: vec![id],
        sentence: format!("The gap is caused by {id} ({}): LR = {:.1}{closure}.", id.description(), best.report.lr),
        separating_experiment: None,
        remaining_cells: Vec::new(),
        tie_test,
    }
}

/// The cosine above which two candidates' corrections count as collinear
/// (diagnosis-details.md §5.4.4).
pub const TIE_COSINE: f64 = 0.9;

/// The tie rule between the two best eligible candidates, as
/// diagnosis-details.md §5.4.4 writes it: "if C_(1) - C_(2) < 2 SE_C, or
/// cos(J~_1, J~_2) > 0.9, report both and propose the discriminating
/// experiment". Either condition alone makes a tie: a margin within its SE
/// band (the data do not separate the two), or collinear corrections however
/// large the margin (the two signatures are the same to within 1 - cos^2 of
/// their energy, so the part that decides between them is small next to what
/// either explains, and the separating experiment is what §5.7 prescribes).
/// `cosine` is that of the two refits' residual changes `r0 - r_j`: for a
/// one-parameter candidate in a model linear in its parameters the change is
/// the projection of `r0` on `J~_j`, so its cosine is `cos(J~_1, J~_2)` up to
/// sign, and it extends to multi-parameter candidates (the fitted directions)
/// and to non-linear refits. The rule follows the document (unit test
/// `collinear_corrections_tie_even_with_a_large_margin`);
/// requiring the margin within its SE band for collinear pairs as well would
/// depart from §5.4.
pub fn is_tie(margin: f64, se: f64, cosine: f64) -> bool {
    margin < 2.0 * se || cosine > TIE_COSINE
}

/// What data separates `effect` from others (diagnosis-details.md §4.2, last column).
pub fn discriminator(candidate: CandidateId) -> &'static str {
    let effect = match candidate {
        CandidateId::Effect(e) => e,
        CandidateId::Component(c) => return component_discriminator(c),
    };
    match effect {
        EffectId::PlasticSlider => {
            "trials at two hold times and two speeds (the permanent set of a slider does not change)"
        }
        EffectId::BinghamDashpot => "a long hold, at least 5x the c3 relaxation time (the force settles on a plateau)",
        EffectId::StressThinning => "two strain levels (normalised relaxation curves that do not overlay)",
        EffectId::DualViscosity => "a longer post-release observation (the gap grows with recovery time)",
        EffectId::StrainStiffening => "two strain levels at one aspect ratio",
        EffectId::FiniteStrain => "two strain levels, 10 % and 20 %",
        EffectId::PlateFriction => "lubricated against dry plates, or two aspect ratios r/h (friction grows with r/h)",
        EffectId::Adhesion => "the force during withdrawal (a negative force) and another plate material",
        EffectId::MachineCompliance => "a rigid-block run, or the camera height against the commanded displacement",
        EffectId::Gravity => "the shape tracked after release (a slump that continues) and a taller specimen",
        EffectId::ForceOffset => "force recorded for 5 s or more before contact and after separation",
        EffectId::Ageing => "the time since preparation logged, with the run order randomised",
    }
}

/// What data separates a network component from others.
fn component_discriminator(component: Component) -> &'static str {
    match component {
        Component::Stiffening => "two strain levels at one aspect ratio (the tangent stiffness grows with strain)",
        Component::PlasticSet => {
            "the height after a long rest following the release (a permanent set does not recover)"
        }
        Component::Mullins => "a third stroke to the same depth after a rest (softening stays, relaxation recovers)",
        Component::ExtraViscous => "a hold at least 10x longer than the longest relaxation time",
        Component::PowerLawFlow => "holds at two strain levels (normalised relaxation curves that do not overlay)",
        Component::LoadingUnloadingViscosity => "a longer post-release observation (the gap grows with recovery time)",
    }
}

/// The experiment that separates two confusable effects (§4.3), or both discriminators.
pub fn separating_experiment(a: CandidateId, b: CandidateId) -> String {
    use EffectId::*;
    let pair = |x: EffectId, y: EffectId| {
        let (x, y) = (CandidateId::Effect(x), CandidateId::Effect(y));
        (a == x && b == y) || (a == y && b == x)
    };
    let set_or_softening = [Component::PlasticSet, Component::Mullins].map(CandidateId::Component);
    let specific = if set_or_softening.contains(&a) && set_or_softening.contains(&b) {
        Some("Reload a specimen after a rest of 10x its longest relaxation time: a permanent set stays (the height does not come back), Mullins softening lets the height come back but keeps the second stroke's force low.")
    } else if pair(Gravity, ForceOffset) {
        Some("Record the force with nothing on the sensor and before contact, and track markers after release: an offset moves no material, gravity slumps it.")
    } else if pair(MachineCompliance, StrainStiffening) || pair(MachineCompliance, PlateFriction) {
        Some("Run a rigid block (compliance alone deflects), or compare the camera height with the commanded displacement.")
    } else if pair(StrainStiffening, FiniteStrain)
        || pair(StrainStiffening, PlateFriction)
        || pair(FiniteStrain, PlateFriction)
    {
        Some("Vary the aspect ratio and lubricate the plates (only friction responds), and watch the bulge (friction barrels).")
    } else if pair(PlasticSlider, StressThinning)
        || pair(PlasticSlider, DualViscosity)
        || pair(StressThinning, DualViscosity)
    {
        Some("Vary the hold time (a slider's set does not change), overlay normalised relaxation at two strain levels (thinning), follow the post-release time course (dual viscosity).")
    } else if pair(BinghamDashpot, StressThinning) {
        Some("Hold at least 5x the c3 relaxation time: a plateau means a threshold, decay toward zero means thinning.")
    } else if pair(PlasticSlider, Gravity) {
        Some("Follow the height after release (gravity keeps slumping, a slider does not) and compare top and bottom widths.")
    } else if pair(Gravity, DualViscosity) {
        Some("Look for top/bottom asymmetry and a dependence on the height (gravity) against a release-phase force change (dual viscosity).")
    } else {
        None
    };
    match specific {
        Some(s) => s.to_string(),
        None => format!("To separate them: for {a}, {}; for {b}, {}.", discriminator(a), discriminator(b)),
    }
}

/// Measured and simulated force curves from the residuals (no extra simulation).
fn force_curves(model: &Model, r0: &[f64], r1: &[f64]) -> Vec<ForceCurves> {
    model
        .trials
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let start = model.offsets[k];
            let sigma = t.force_sigma_n;
            let nf = t.force.len();
            let mut base = r0[start..start + nf].to_vec();
            let mut with = r1[start..start + nf].to_vec();
            model::unwhiten(&mut base, t.force_rho);
            model::unwhiten(&mut with, t.force_rho);
            let times = t.force.iter().enumerate().map(|(i, f)| (f.0, model.observations[start + i].phase)).collect();
            ForceCurves {
                trial: t.name.clone(),
                times,
                measured: t.force.iter().map(|f| f.1).collect(),
                baseline: t.force.iter().enumerate().map(|(i, f)| f.1 + sigma * base[i]).collect(),
                with_effect: t.force.iter().enumerate().map(|(i, f)| f.1 + sigma * with[i]).collect(),
            }
        })
        .collect()
}

/// Marker shapes from the residuals (no extra simulation): per trial, the
/// last photograph of each phase that has one.
fn marker_shapes(model: &Model, r0: &[f64], r1: &[f64]) -> Vec<MarkerShapes> {
    let mut out = Vec::new();
    for (k, t) in model.trials.iter().enumerate() {
        let before = model.marker_samples(k, r0);
        let after = model.marker_samples(k, r1);
        for phase in Phase::ALL {
            let Some(t_last) = before.iter().filter(|s| s.phase == phase).map(|s| s.t_s).reduce(f64::max) else {
                continue;
            };
            let markers = before
                .iter()
                .zip(&after)
                .filter(|(b, _)| b.phase == phase && b.t_s == t_last)
                .map(|(b, a)| MarkerPlaces {
                    marker: b.marker,
                    measured: b.measured.clone(),
                    baseline: b.simulated.clone(),
                    with_effect: a.simulated.clone(),
                })
                .collect();
            out.push(MarkerShapes { trial: t.name.clone(), t_s: t_last, phase, markers });
        }
    }
    out
}

#[cfg(test)]
mod tests;
