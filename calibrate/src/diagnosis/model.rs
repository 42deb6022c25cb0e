//! The diagnoser's model of a campaign: every trial as a press problem that runs
//! with any values of the unknowns and any candidate effect, and the layout of
//! its noise-weighted residuals (which trial, channel, phase, region and time each
//! one belongs to).
//!
//! The observations are those of [`crate::trial`]: the force at the bundle's
//! samples (`t > 0`, at most [`crate::trial::MAX_FORCE_SAMPLES`] per trial by a
//! uniform stride, noise by the difference method) and the marker coordinates
//! during the hold and after the release (noise `marker_sigma_mm`). Marker
//! coordinates are split into two channels: `height` (the vertical coordinate y)
//! and `width` (x, and z in 3D; r in the axisymmetric section), each in the
//! region (top, middle, bottom third of the specimen) of the marker's initial
//! height.
//!
//! **Jacobians.** The columns of the unknowns come from the engine's forward
//! sensitivities when the trial's effects allow them
//! (`Effects::check_sensitivities`), otherwise, and for every effect parameter,
//! from forward differences on a *frozen* discretisation: the run at the point
//! is replayed on its own step ends (`Settings::step_ends_s`), and so are the
//! perturbed runs, so the adaptive step choice does not enter the difference
//! (diagnosis-details.md §5.1.3). Relative steps: 1e-6 for the unknowns, 1e-3 of
//! the coordinate's scale for an effect parameter. Contact effects are not
//! replayed (a contact step that does not settle may not be subdivided on a
//! replay); their differences come from adaptive runs, whose step choice moves
//! the force by about the step tolerance, so the steps are larger there (2e-2
//! relative for the unknowns, 5e-2 of the scale for the effect).
//!
//! **Effect coordinates.** An effect parameter with a finite null is fitted as
//! itself; one with an infinite null (a yield stress never reached) as its
//! inverse `u = 1/phi` (null `u = 0`), so that the null is a bound the secant
//! score and the refit can start from. Each coordinate carries its secant
//! reference, the registry's or, for a stress-valued parameter, a fraction of
//! the campaign's peak nominal stress ([`Candidate::at_stress`],
//! [`peak_stress_mpa`]). A one-sided coordinate within 1e-4 of
//! its reference distance from the null ([`DEADBAND`]) runs as the null: the
//! effect of such values is far below any noise, and a refit creeping toward the
//! null would otherwise spend runs on friction coefficients of order 1e-7 (the
//! engine's friction contact settles there too: the diagnosis tests give the
//! same verdicts without the band).

use std::collections::BTreeMap;

use fem_core::effects::{Effects, ParamSpec};
use fem_core::material::Material;
use fem_core::press::{
    simulate_any, simulate_any_with_sensitivities, AnyPress, PressResult, SensitivityParameter, Settings,
};
use nalgebra::DMatrix;
use rayon::prelude::*;
use wagashi_io::bundle::{Shape, Tool};
use wagashi_io::{Bundle, MaterialSpec};

use crate::lsq::{EvalError, Evaluation, LeastSquares, ParameterSpec};
use crate::trial::{measured_force, model_position, region_names, sensitivity_parameter, set_parameter, Unknown};

use super::library::CandidateId;
use super::DiagnosisError;

/// A phase of a trial (diagnosis.md, step 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Phase {
    /// Before the tool first pushes.
    PreContact,
    /// The tool moves down.
    Push,
    /// The tool stands still in contact.
    Hold,
    /// The tool moves up before it lets go.
    Release,
    /// After the release time: the specimen recovers.
    Recovery,
}

impl Phase {
    /// Every phase in time order.
    pub const ALL: [Phase; 5] = [Phase::PreContact, Phase::Push, Phase::Hold, Phase::Release, Phase::Recovery];

    /// The name in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Phase::PreContact => "pre-contact",
            Phase::Push => "push",
            Phase::Hold => "hold",
            Phase::Release => "release",
            Phase::Recovery => "recovery",
        }
    }
}

/// A measured channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ObsChannel {
    /// The bottom force.
    Force,
    /// Vertical marker coordinates.
    Height,
    /// Lateral marker coordinates.
    Width,
}

impl ObsChannel {
    /// The name in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            ObsChannel::Force => "force",
            ObsChannel::Height => "height",
            ObsChannel::Width => "width",
        }
    }
}

/// A region of the specimen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Region {
    /// The whole specimen (the force).
    All,
    /// Upper third (by the marker's initial height).
    Top,
    /// Middle third.
    Middle,
    /// Lower third.
    Bottom,
}

impl Region {
    /// The name in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Region::All => "all",
            Region::Top => "top",
            Region::Middle => "middle",
            Region::Bottom => "bottom",
        }
    }
}

/// What one residual is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// The trial's index.
    pub trial: usize,
    /// Time [s].
    pub t_s: f64,
    /// Its phase.
    pub phase: Phase,
    /// Its channel.
    pub channel: ObsChannel,
    /// Its region.
    pub region: Region,
    /// A series key within the trial: 0 for the force, `1 + marker * 3 + component` for a marker coordinate.
    pub series: usize,
}

/// The dead band of one-sided coordinates, relative to the distance from the
/// null to the reference (module docs).
pub const DEADBAND: f64 = 1e-4;

/// One strength parameter of a candidate, as the solver sees it (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coord {
    /// The registry's specification.
    pub spec: ParamSpec,
    /// The parameter's index in [`CandidateId::params`].
    pub index: usize,
    /// Fitted as `1/phi` (infinite null).
    pub inverse: bool,
    /// The secant reference value of the parameter (not the coordinate): the
    /// registry's, scaled to the campaign's stress level for stress-valued
    /// parameters ([`Candidate::at_stress`]).
    pub reference: f64,
}

impl Coord {
    /// The coordinate of the null.
    pub fn null(&self) -> f64 {
        if self.inverse {
            0.0
        } else {
            self.spec.null
        }
    }

    /// The coordinate of the secant reference.
    pub fn reference(&self) -> f64 {
        if self.inverse {
            1.0 / self.reference
        } else {
            self.reference
        }
    }

    /// Bounds of the coordinate.
    pub fn bounds(&self) -> [f64; 2] {
        if self.inverse {
            let [lo, hi] = self.spec.bounds;
            [1.0 / hi, if lo > 0.0 { 1.0 / lo } else { f64::INFINITY }]
        } else {
            self.spec.bounds
        }
    }

    /// The parameter's value at coordinate `u`.
    pub fn value(&self, u: f64) -> f64 {
        if self.inverse {
            if u == 0.0 {
                f64::INFINITY
            } else {
                1.0 / u
            }
        } else {
            u
        }
    }

    /// The scale of a finite-difference step.
    pub fn scale(&self, u: f64) -> f64 {
        u.abs().max((self.reference() - self.null()).abs()).max(1e-300)
    }

    /// Whether the test of this coordinate is one-sided (the null on a bound).
    pub fn one_sided(&self) -> bool {
        self.spec.one_sided
    }
}

/// A candidate (an engine effect or a network component) with its fitted
/// coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// The candidate.
    pub effect: CandidateId,
    /// Its strength parameters (nuisance parameters stay at their defaults).
    pub coords: Vec<Coord>,
    /// Every parameter's value when not fitted ([`CandidateId::defaults`]).
    pub defaults: Vec<f64>,
}

impl Candidate {
    /// The candidate of `effect` with the registry's static references.
    pub fn new(effect: impl Into<CandidateId>) -> Self {
        Self::at_stress(effect.into(), None)
    }

    /// The candidate of `effect` on a campaign of peak nominal stress
    /// `sigma_peak_mpa` ([`peak_stress_mpa`]): stress-valued parameters take
    /// their references from it ([`ParamSpec::reference_at`]), the others (and
    /// all of them with `None`) the registry's static ones.
    pub fn at_stress(effect: CandidateId, sigma_peak_mpa: Option<f64>) -> Self {
        let coords = effect
            .params()
            .iter()
            .enumerate()
            .filter(|(_, p)| !p.nuisance)
            .map(|(index, &spec)| Coord {
                spec,
                index,
                inverse: spec.null.is_infinite(),
                reference: spec.reference_at(sigma_peak_mpa),
            })
            .collect();
        Self { effect, coords, defaults: effect.defaults(sigma_peak_mpa) }
    }

    /// [`Candidate::at_stress`] with the effect's nuisance parameters (the
    /// slider's hardening, the thinning exponent, the adhesion opening) as
    /// further coordinates after the strength ones, each fitted as itself from
    /// its registry default (module docs of `diagnosis`, "Nuisance parameters").
    pub fn with_nuisance(effect: CandidateId, sigma_peak_mpa: Option<f64>) -> Self {
        let mut c = Self::at_stress(effect, sigma_peak_mpa);
        c.coords.extend(effect.params().iter().enumerate().filter(|(_, p)| p.nuisance).map(|(index, &spec)| Coord {
            spec,
            index,
            inverse: false,
            reference: spec.reference_at(sigma_peak_mpa),
        }));
        c
    }

    /// Whether the effect has nuisance parameters.
    pub fn has_nuisance(effect: CandidateId) -> bool {
        effect.params().iter().any(|p| p.nuisance)
    }

    /// The number of fitted effect parameters `d_j`.
    pub fn dim(&self) -> usize {
        self.coords.len()
    }

    /// The null coordinates.
    pub fn null(&self) -> Vec<f64> {
        self.coords.iter().map(Coord::null).collect()
    }

    /// Every parameter's value (registry order) at coordinates `u`. A one-sided
    /// coordinate closer to its null than [`DEADBAND`] of its reference distance
    /// is the null itself (module docs).
    pub fn values(&self, u: &[f64]) -> Vec<f64> {
        let mut v = self.defaults.clone();
        for (c, &ui) in self.coords.iter().zip(u) {
            let dead = c.one_sided() && (ui - c.null()).abs() < DEADBAND * (c.reference() - c.null()).abs();
            v[c.index] = c.value(if dead { c.null() } else { ui });
        }
        v
    }
}

/// One trial as the diagnoser runs it.
#[derive(Debug, Clone)]
pub(crate) struct TrialModel {
    pub name: String,
    problem: AnyPress,
    region_material: Vec<String>,
    pub force: Vec<(f64, f64)>,
    /// Marginal force noise [N].
    pub force_sigma_n: f64,
    /// Lag-1 correlation of the force noise between consecutive samples (0: white).
    pub force_rho: f64,
    /// (marker, sample, measured position).
    markers: Vec<(usize, usize, Vec<f64>)>,
    /// The discretisation correction added to the raw residuals [noise units,
    /// before whitening] (empty: none; module docs, "Mesh").
    mesh_correction: Vec<f64>,
    /// Per marker coordinate: its entries in the trial's residuals (whitened
    /// together, module docs "Marker noise").
    marker_groups: Vec<Vec<usize>>,
}

/// A campaign as the diagnoser runs it (module docs).
#[derive(Debug, Clone)]
pub struct Model {
    pub(crate) trials: Vec<TrialModel>,
    /// The unknowns (their values are the `theta` of every call).
    pub unknowns: Vec<Unknown>,
    /// Every material (fixed parameters and the unknowns' start values).
    pub table: BTreeMap<String, MaterialSpec>,
    /// Settings of every simulation.
    pub settings: Settings,
    /// Marker noise [mm].
    pub marker_sigma_mm: f64,
    /// What each residual is, in residual order.
    pub observations: Vec<Observation>,
    /// First residual of each trial, and the total at the end.
    pub offsets: Vec<usize>,
    /// Prior standard deviation of the per-sample log-scales (0: the calibration
    /// has none; module docs, "Per-sample scales").
    pub sample_scale_sd: f64,
    /// Candidates already in the model, at fixed parameter values (registry
    /// order): the forward selection's earlier steps (`diagnosis` module docs,
    /// "Composable verdicts"). Every run carries them under the tested one.
    pub included: Vec<(CandidateId, Vec<f64>)>,
}

/// Phase of a time inside the protocol (`t` within the segment `(t_i, t_i+1]`).
fn phase_at(waypoints: &[[f64; 2]], release_s: f64, t: f64) -> Phase {
    if t > release_s {
        return Phase::Recovery;
    }
    let mut pushed = false;
    for w in waypoints.windows(2) {
        let ([t0, d0], [t1, d1]) = (w[0], w[1]);
        if d1 > d0 {
            pushed = true;
        }
        if t > t0 && t <= t1 {
            return if d1 > d0 {
                Phase::Push
            } else if d1 < d0 {
                Phase::Release
            } else if d0 > 0.0 {
                Phase::Hold
            } else if pushed {
                Phase::Release
            } else {
                Phase::PreContact
            };
        }
    }
    // After the last waypoint: the tool stands where it is.
    match waypoints.last() {
        Some(&[_, d]) if d > 0.0 => Phase::Hold,
        _ if waypoints.windows(2).any(|w| w[1][1] > w[0][1]) => Phase::Release,
        _ => Phase::PreContact,
    }
}

/// The campaign's peak nominal stress [MPa], the stress level that
/// stress-valued effect references follow ([`Candidate::at_stress`]): over the
/// bundles with a measured force, the largest of (largest compressive force /
/// nominal loaded area), the area being the block's `W x T` (the plate's face;
/// in 2D the width times the thickness) or the cylinder's `pi r^2`, for bundles
/// pressed by a plate. `None` when no bundle has both (markers only, a
/// `surface` specimen, or a sphere, punch or surface tool, whose loaded area
/// changes with the indentation): the registry's static references then stand.
///
/// Why the measured force and not the baseline's stress field: it is the data
/// itself, known before any fit, the same for every candidate, and does not
/// move with the baseline's convergence or the mesh (a peak of the element
/// stresses would, at the glued corners); the noise moves it by about sigma /
/// F_peak (0.5 % in the seed's press), far below what a secant reference needs.
pub fn peak_stress_mpa(bundles: &[Bundle]) -> Option<f64> {
    bundles
        .iter()
        .filter_map(|b| {
            if b.experiment.protocol.tool != Tool::Plate {
                return None;
            }
            let specimen = &b.experiment.specimen;
            let area = match specimen.shape {
                Shape::Block => {
                    let [w, _, t] = specimen.block_size()?;
                    w * t
                }
                Shape::Cylinder => std::f64::consts::PI * specimen.radius_mm?.powi(2),
                Shape::Surface | Shape::Mesh => return None,
            };
            let peak = b.force.as_ref()?.samples.iter().map(|s| s.force_n).fold(f64::NEG_INFINITY, f64::max);
            let stress = peak / area;
            (area > 0.0 && stress.is_finite() && stress > 0.0).then_some(stress)
        })
        .fold(None, |acc: Option<f64>, s| Some(acc.map_or(s, |a| a.max(s))))
}

/// Fewest no-contact force samples from which the AR(1) noise is estimated.
pub const MIN_QUIET_SAMPLES: usize = 20;

/// A bundle's force samples as the diagnoser uses them (`0 < t <= end`, thinned)
/// and their noise model `(sigma [N], rho)` (module docs, "Force noise"): from
/// the no-contact segments (pre-contact and recovery phases), each detrended by
/// a straight line, when they hold at least [`MIN_QUIET_SAMPLES`] samples;
/// otherwise the difference-method sigma of the whole series, white.
pub fn force_noise_model(b: &Bundle) -> (Vec<(f64, f64)>, f64, f64) {
    let (force, sigma_diff) = measured_force(b);
    let protocol = &b.experiment.protocol;
    let quiet: Vec<bool> = force
        .iter()
        .map(|&(t, _)| {
            matches!(phase_at(&protocol.waypoints, protocol.release_s, t), Phase::PreContact | Phase::Recovery)
        })
        .collect();
    match ar1_estimate(&force, &quiet) {
        Some((sigma, rho)) => (force, sigma.max(1e-12), rho),
        None => (force, sigma_diff, 0.0),
    }
}

/// `(sigma, rho)` of the samples flagged `quiet`, pooled over their contiguous
/// runs (of at least four samples) after a least-squares line is removed from
/// each; `None` with fewer than [`MIN_QUIET_SAMPLES`] samples. `rho` is clipped
/// to `[0, 0.95]`.
///
/// **Bias correction.** The raw pooled moments, the lag-1 autocovariance over
/// the variance of the detrended runs, are biased low: removing a line takes
/// the low frequencies where a positively correlated noise has most of its
/// power. With the blind check's runs (a 20-sample pre-contact record and a
/// 200-sample recovery, rho = 0.5) the raw lag-1 estimate falls 0.04 short, and
/// the whitened residuals keep a correlation that inflates the LR of every
/// smooth effect (with the raw estimate, development seed 101 measured rho_hat - rho =
/// -0.045 over 92 trials, and force-offset was named on two of seven null
/// campaigns). So the moments are matched to their exact expectations instead:
/// for a run `x ~ AR(1)` with correlation matrix `S(rho)` and the detrending
/// projector `M = I - Q Q^T` (`Q` an orthonormal basis of the constant and the
/// line), `E[e^T e] = sigma^2 tr(M S)` and `E[sum e_i e_(i+1)] = sigma^2 tr(M A M
/// S)`, `A` the symmetric shift halves ([`detrended_moments`], O(n) per run by
/// the AR(1) recursions). `rho` solves `sum E[g1] / n1 = rho_raw sum E[g0] / n0`
/// by bisection (the ratio rises with rho), and `sigma^2 = sum g0 / sum
/// tr(M S(rho))`. Measured (Monte Carlo, 1,500 replicas of runs of 20 and 200
/// samples): the bias of rho falls from -0.027, -0.038, -0.047 to -0.001,
/// -0.004, -0.007 at rho = 0.3, 0.5, 0.7, and sigma^2 is unbiased to 0.4 %.
pub fn ar1_estimate(series: &[(f64, f64)], quiet: &[bool]) -> Option<(f64, f64)> {
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    for (x, &q) in series.iter().zip(quiet) {
        if q {
            current.push(*x);
        } else if !current.is_empty() {
            runs.push(std::mem::take(&mut current));
        }
    }
    runs.push(current);
    runs.retain(|r| r.len() >= 4);
    let total: usize = runs.iter().map(Vec::len).sum();
    if total < MIN_QUIET_SAMPLES {
        return None;
    }
    let (mut g0, mut n0, mut g1, mut n1) = (0.0, 0usize, 0.0, 0usize);
    let mut bases = Vec::with_capacity(runs.len());
    for run in &runs {
        let n = run.len() as f64;
        let (mt, mf) = (run.iter().map(|x| x.0).sum::<f64>() / n, run.iter().map(|x| x.1).sum::<f64>() / n);
        let stt: f64 = run.iter().map(|x| (x.0 - mt).powi(2)).sum();
        let slope = if stt > 0.0 { run.iter().map(|x| (x.0 - mt) * (x.1 - mf)).sum::<f64>() / stt } else { 0.0 };
        let e: Vec<f64> = run.iter().map(|x| x.1 - mf - slope * (x.0 - mt)).collect();
        g0 += e.iter().map(|v| v * v).sum::<f64>();
        n0 += e.len() - 2;
        g1 += e.windows(2).map(|w| w[0] * w[1]).sum::<f64>();
        n1 += e.len() - 1;
        // The detrending basis: the constant and the centred times, orthonormal.
        let mut q = vec![vec![1.0 / n.sqrt(); run.len()]];
        if stt > 0.0 {
            q.push(run.iter().map(|x| (x.0 - mt) / stt.sqrt()).collect());
        }
        bases.push(q);
    }
    if g0 <= 0.0 {
        return None;
    }
    let raw = (g1 / n1 as f64) / (g0 / n0 as f64);
    let moments = |rho: f64| -> (f64, f64) {
        bases.iter().map(|q| detrended_moments(q, rho)).fold((0.0, 0.0), |a, m| (a.0 + m.0, a.1 + m.1))
    };
    let ratio = |rho: f64| {
        let (e0, e1) = moments(rho);
        (e1 / n1 as f64) / (e0 / n0 as f64)
    };
    let rho = if raw <= ratio(0.0) {
        0.0
    } else if raw >= ratio(0.95) {
        0.95
    } else {
        let (mut lo, mut hi) = (0.0, 0.95);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if ratio(mid) < raw {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let var = g0 / moments(rho).0;
    (var > 0.0 && var.is_finite()).then(|| (var.sqrt(), rho))
}

/// `(tr(M S), tr(M A M S))` for one run (see [`ar1_estimate`]): `S` the AR(1)
/// correlation matrix `rho^|i-j|`, `M = I - Q Q^T` with the orthonormal columns
/// `q`, `A` the symmetric lag-1 matrix (halves beside the diagonal). With `Y = S Q`
/// (two AR(1) recursions per column), `tr(M S) = n - tr(Q^T Y)` and `tr(M A M S)
/// = (n - 1) rho - 2 tr(Q^T A Y) + tr(Q^T A Q Q^T Y)`.
fn detrended_moments(q: &[Vec<f64>], rho: f64) -> (f64, f64) {
    let n = q[0].len();
    let sigma_times = |v: &[f64]| -> Vec<f64> {
        let mut forward = v.to_vec();
        for i in 1..n {
            forward[i] += rho * forward[i - 1];
        }
        let mut backward = v.to_vec();
        for i in (0..n - 1).rev() {
            backward[i] += rho * backward[i + 1];
        }
        (0..n).map(|i| forward[i] + backward[i] - v[i]).collect()
    };
    let shift_times = |v: &[f64]| -> Vec<f64> {
        (0..n).map(|i| 0.5 * (if i > 0 { v[i - 1] } else { 0.0 } + if i + 1 < n { v[i + 1] } else { 0.0 })).collect()
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let y: Vec<Vec<f64>> = q.iter().map(|c| sigma_times(c)).collect();
    let aq: Vec<Vec<f64>> = q.iter().map(|c| shift_times(c)).collect();
    let k = q.len();
    let mut tr_ms = n as f64;
    let mut tr_qay = 0.0;
    let mut tr_cross = 0.0;
    for a in 0..k {
        tr_ms -= dot(&q[a], &y[a]);
        tr_qay += dot(&aq[a], &y[a]);
        for b in 0..k {
            tr_cross += dot(&q[a], &aq[b]) * dot(&q[b], &y[a]);
        }
    }
    (tr_ms, (n as f64 - 1.0) * rho - 2.0 * tr_qay + tr_cross)
}

/// Prais-Winsten whitening of an AR(1) series in noise units, in place:
/// `w_0 = r_0`, `w_i = (r_i - rho r_(i-1)) / sqrt(1 - rho^2)`.
pub fn whiten(r: &mut [f64], rho: f64) {
    if rho == 0.0 {
        return;
    }
    let c = (1.0 - rho * rho).sqrt();
    for i in (1..r.len()).rev() {
        r[i] = (r[i] - rho * r[i - 1]) / c;
    }
}

/// Whitening of the marker coordinates: a marker's track starts from its
/// measured initial position, which carries the same noise as every later
/// sample, so the residuals of one coordinate share that error: covariance
/// `sigma^2 (I + 1 1^T)` over its `m` samples, whose inverse square root is
/// `I - (1 - 1/sqrt(1 + m)) 1 1^T / m` (module docs, "Marker noise").
pub fn whiten_markers(r: &mut [f64], groups: &[Vec<usize>]) {
    shift_by_group_mean(r, groups, |m| -(1.0 - 1.0 / (1.0 + m).sqrt()));
}

/// The inverse of [`whiten_markers`]: a whitened group's mean is the raw mean
/// divided by `sqrt(1 + m)`, and the shift is a multiple of the raw mean.
pub fn unwhiten_markers(w: &mut [f64], groups: &[Vec<usize>]) {
    shift_by_group_mean(w, groups, |m| (1.0 + m).sqrt() - 1.0);
}

/// Adds `gain(m)` times its mean to every entry of each group of `m` entries.
fn shift_by_group_mean(r: &mut [f64], groups: &[Vec<usize>], gain: impl Fn(f64) -> f64) {
    for g in groups {
        if g.is_empty() {
            continue;
        }
        let m = g.len() as f64;
        let mean = g.iter().map(|&i| r[i]).sum::<f64>() / m;
        let shift = gain(m) * mean;
        for &i in g {
            r[i] += shift;
        }
    }
}

/// One marker sample of a trial, measured and as a run gives it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MarkerSample {
    /// The marker's index in its bundle.
    pub marker: usize,
    /// Time [s].
    pub t_s: f64,
    /// The phase the sample lies in.
    pub phase: Phase,
    /// Measured position [mm], in the model's coordinates.
    pub measured: Vec<f64>,
    /// Simulated position [mm], mesh correction included.
    pub simulated: Vec<f64>,
}

/// The inverse of [`whiten`].
pub fn unwhiten(w: &mut [f64], rho: f64) {
    if rho == 0.0 {
        return;
    }
    let c = (1.0 - rho * rho).sqrt();
    for i in 1..w.len() {
        w[i] = rho * w[i - 1] + c * w[i];
    }
}

impl Model {
    /// The model of `bundles` with the materials of `table` (every material the
    /// bundles name), elements of `size_mm` (default: each bundle's own), the
    /// axisymmetric section for cylinders when `axisymmetric`.
    pub fn new(
        bundles: &[Bundle],
        table: &BTreeMap<String, MaterialSpec>,
        unknowns: Vec<Unknown>,
        size_mm: Option<f64>,
        axisymmetric: bool,
        marker_sigma_mm: f64,
    ) -> Result<Self, DiagnosisError> {
        Self::with_refinement(bundles, table, unknowns, size_mm, axisymmetric, marker_sigma_mm, 1.0)
    }

    /// [`Model::new`] with every element size multiplied by `factor` (0.5: the
    /// mesh-halving run of step 0); the observation layout is the same.
    pub fn with_refinement(
        bundles: &[Bundle],
        table: &BTreeMap<String, MaterialSpec>,
        unknowns: Vec<Unknown>,
        size_mm: Option<f64>,
        axisymmetric: bool,
        marker_sigma_mm: f64,
        factor: f64,
    ) -> Result<Self, DiagnosisError> {
        let mut trials = Vec::new();
        let mut observations = Vec::new();
        let mut offsets = vec![0];
        for (k, b) in bundles.iter().enumerate() {
            let file = b.experiment_file().display().to_string();
            let mut filled = b.clone();
            for name in b.experiment.specimen.material_names() {
                let Some(spec) = table.get(name) else {
                    return Err(DiagnosisError::Input(format!(
                        "{file}: material {name} is not among the calibrated materials"
                    )));
                };
                filled.experiment.materials.insert(name.to_string(), spec.clone());
            }
            let size = size_mm.or_else(|| b.default_size_mm()).ok_or_else(|| {
                DiagnosisError::Input(format!("{file}: give an element size (--size-mm) for this specimen"))
            })? * factor;
            let problem = if axisymmetric { filled.to_press_axisymmetric(size)? } else { filled.to_press(size)? };
            let region_material = region_names(&problem);
            let protocol = &b.experiment.protocol;
            let (release_s, end_s, last_push_s) = (protocol.release_s, protocol.end_s, protocol.last_push_s());
            let (force, force_sigma_n, force_rho) = force_noise_model(b);
            for &(t, _) in &force {
                observations.push(Observation {
                    trial: k,
                    t_s: t,
                    phase: phase_at(&protocol.waypoints, release_s, t),
                    channel: ObsChannel::Force,
                    region: Region::All,
                    series: 0,
                });
            }
            // Marker observations, as crate::trial selects them.
            let height = match b.experiment.specimen.block_size() {
                Some([_, h, _]) => h,
                None => b.experiment.specimen.height_mm.unwrap_or(1.0),
            };
            let mut markers = Vec::new();
            for (m, series) in b.markers.iter().enumerate() {
                let y0 = series.initial_position().map(|p| p[1]).unwrap_or(0.5 * height);
                let region = if y0 > 2.0 * height / 3.0 {
                    Region::Top
                } else if y0 < height / 3.0 {
                    Region::Bottom
                } else {
                    Region::Middle
                };
                for (i, s) in series.samples.iter().enumerate() {
                    if s.t_s <= 0.0 || s.t_s > end_s || (s.t_s <= release_s && s.t_s < last_push_s) {
                        continue;
                    }
                    let position = model_position(&problem, &s.position_mm);
                    let phase = if s.t_s > release_s { Phase::Recovery } else { Phase::Hold };
                    for c in 0..position.len() {
                        observations.push(Observation {
                            trial: k,
                            t_s: s.t_s,
                            phase,
                            channel: if c == 1 { ObsChannel::Height } else { ObsChannel::Width },
                            region,
                            series: 1 + m * 3 + c,
                        });
                    }
                    markers.push((m, i, position));
                }
            }
            // Entries of each marker coordinate in the trial's residuals.
            let mut marker_groups: BTreeMap<(usize, usize), Vec<usize>> = BTreeMap::new();
            let mut at = force.len();
            for (m, _, position) in &markers {
                for c in 0..position.len() {
                    marker_groups.entry((*m, c)).or_default().push(at);
                    at += 1;
                }
            }
            let marker_groups: Vec<Vec<usize>> = marker_groups.into_values().collect();
            offsets.push(observations.len());
            trials.push(TrialModel {
                name: b.experiment.name.clone(),
                problem,
                region_material,
                force,
                force_sigma_n,
                force_rho,
                markers,
                mesh_correction: Vec::new(),
                marker_groups,
            });
        }
        Ok(Self {
            trials,
            unknowns,
            table: table.clone(),
            settings: Settings::default(),
            marker_sigma_mm,
            observations,
            offsets,
            sample_scale_sd: 0.0,
            included: Vec::new(),
        })
    }

    /// The scale groups present among the unknowns, in order: moduli (`true`),
    /// viscosities (`false`).
    fn scale_groups(&self) -> Vec<bool> {
        let kinds = self.scale_kind();
        [true, false].into_iter().filter(|g| kinds.contains(&Some(*g))).collect()
    }

    /// The number of per-sample log-scales `b` (trials times groups; 0 without a prior).
    pub fn num_scales(&self) -> usize {
        if self.sample_scale_sd > 0.0 {
            self.trials.len() * self.scale_groups().len()
        } else {
            0
        }
    }

    /// The length of `theta` in every call with scales: the unknowns, then `b`.
    pub fn num_theta(&self) -> usize {
        self.unknowns.len() + self.num_scales()
    }

    /// Labels of the per-sample log-scales (`scale.<trial>.moduli` / `.viscosities`).
    pub fn scale_labels(&self) -> Vec<String> {
        if self.num_scales() == 0 {
            return Vec::new();
        }
        let groups = self.scale_groups();
        let mut out = Vec::new();
        for t in &self.trials {
            for &g in &groups {
                out.push(format!("scale.{}.{}", t.name, if g { "moduli" } else { "viscosities" }));
            }
        }
        out
    }

    /// The factor `exp(b)` of trial `k`'s scale of kind `modulus` (1 when `theta`
    /// carries no scales or the kind has none).
    fn scale_factor(&self, k: usize, theta: &[f64], modulus: bool) -> f64 {
        let p = self.unknowns.len();
        if theta.len() <= p || self.num_scales() == 0 {
            return 1.0;
        }
        let groups = self.scale_groups();
        match groups.iter().position(|&g| g == modulus) {
            Some(gi) => theta[p + k * groups.len() + gi].exp(),
            None => 1.0,
        }
    }

    /// The unknowns as trial `k` sees them: scaled by its sample scales when
    /// `theta` carries them.
    fn trial_theta(&self, k: usize, theta: &[f64]) -> Vec<f64> {
        let kinds = self.scale_kind();
        (0..self.unknowns.len())
            .map(|i| match kinds[i] {
                Some(g) => theta[i] * self.scale_factor(k, theta, g),
                None => theta[i],
            })
            .collect()
    }

    /// The prior rows `b / omega` of the scales in `theta` (none without).
    fn prior_rows(&self, theta: &[f64]) -> Vec<f64> {
        let p = self.unknowns.len();
        if theta.len() <= p || self.num_scales() == 0 {
            return Vec::new();
        }
        theta[p..p + self.num_scales()].iter().map(|b| b / self.sample_scale_sd).collect()
    }

    /// The number of trials.
    pub fn num_trials(&self) -> usize {
        self.trials.len()
    }

    /// The trials' names.
    pub fn trial_names(&self) -> Vec<String> {
        self.trials.iter().map(|t| t.name.clone()).collect()
    }

    /// The number of residuals.
    pub fn num_residuals(&self) -> usize {
        self.observations.len()
    }

    /// Whether any trial's bundle sets `effect` itself (it is then part of the
    /// baseline, not a candidate).
    pub fn bundles_set(&self, effect: fem_core::effects::EffectId) -> bool {
        self.trials.iter().any(|t| t.problem.effects().is_set(effect))
    }

    /// Whether any trial gives the covariate `age_h` (what `ageing` acts through).
    pub fn has_age(&self) -> bool {
        self.trials.iter().any(|t| t.problem.effects().age_h().is_some_and(|a| a > 0.0))
    }

    fn table_with(&self, theta: &[f64]) -> BTreeMap<String, MaterialSpec> {
        let mut t = self.table.clone();
        for (u, &v) in self.unknowns.iter().zip(theta) {
            if let Some(spec) = t.get_mut(&u.material) {
                set_parameter(spec, u.key, v);
            }
        }
        t
    }

    /// Trial `k`'s problem at `theta` with the candidate effect `effect` (values in
    /// registry order) on top of the bundle's own effects.
    fn problem(&self, k: usize, theta: &[f64], effect: Option<(CandidateId, &[f64])>) -> Result<AnyPress, EvalError> {
        let trial = &self.trials[k];
        let table = self.table_with(&self.trial_theta(k, theta));
        let applied: Vec<(CandidateId, &[f64])> =
            self.included.iter().map(|(c, v)| (*c, v.as_slice())).chain(effect).collect();
        let components: Vec<(super::library::Component, &[f64])> = applied
            .iter()
            .filter_map(|&(c, values)| match c {
                CandidateId::Component(c) => Some((c, values)),
                CandidateId::Effect(_) => None,
            })
            .collect();
        let materials: Vec<Material> = trial
            .region_material
            .iter()
            .map(|name| {
                let mut m = table[name]
                    .to_material()
                    .map_err(|m| EvalError::new(format!("material {name} lacks {}", m.key)))?;
                m.rheology.validate().map_err(|e| EvalError::new(format!("material {name}: {e}")))?;
                for &(c, values) in &components {
                    if let Some(net) = m.network.as_ref() {
                        let changed = c.apply(net, values);
                        changed
                            .validate()
                            .map_err(|e| EvalError::new(format!("material {name} with {}: {e}", c.id())))?;
                        m.network = Some(changed);
                    }
                }
                Ok(m)
            })
            .collect::<Result<_, EvalError>>()?;
        let mut p = trial.problem.clone();
        let set = |effects: &mut Effects| -> Result<(), EvalError> {
            for &(c, values) in &applied {
                if let CandidateId::Effect(e) = c {
                    effects.set(e, values).map_err(|err| EvalError::new(format!("trial {}: {err}", trial.name)))?;
                }
            }
            Ok(())
        };
        match &mut p {
            AnyPress::Plane(q) => {
                q.materials = materials;
                set(&mut q.effects)?;
            }
            AnyPress::Solid(q) => {
                q.materials = materials;
                set(&mut q.effects)?;
            }
            AnyPress::Axisymmetric(q) => {
                q.materials = materials;
                set(&mut q.effects)?;
            }
        }
        Ok(p)
    }

    fn run(&self, k: usize, problem: &AnyPress, steps: Option<&[f64]>) -> Result<PressResult, EvalError> {
        let mut settings = self.settings.clone();
        if let Some(s) = steps {
            settings.step_ends_s = Some(s.to_vec());
        }
        simulate_any(problem, &settings, &mut |_| {})
            .map_err(|e| EvalError::with_source(format!("trial {}", self.trials[k].name), e))
    }

    /// Trial `k`'s residuals in a run's result, in noise units, neither
    /// corrected nor whitened.
    fn raw_residuals_of(&self, k: usize, result: &PressResult) -> Vec<f64> {
        let trial = &self.trials[k];
        let mut r: Vec<f64> =
            trial.force.iter().map(|&(t, f)| (result.bottom_force_at(t) - f) / trial.force_sigma_n).collect();
        for (m, i, position) in &trial.markers {
            let sim = &result.markers[*m].samples[*i].1;
            r.extend(sim.iter().zip(position).map(|(s, p)| (s - p) / self.marker_sigma_mm));
        }
        r
    }

    /// Trial `k`'s residuals in a run's result: raw, plus the mesh correction,
    /// the force whitened.
    fn residuals_of(&self, k: usize, result: &PressResult) -> Vec<f64> {
        let trial = &self.trials[k];
        let mut r = self.raw_residuals_of(k, result);
        if trial.mesh_correction.len() == r.len() {
            r.iter_mut().zip(&trial.mesh_correction).for_each(|(a, c)| *a += c);
        }
        whiten(&mut r[..trial.force.len()], trial.force_rho);
        whiten_markers(&mut r, &trial.marker_groups);
        r
    }

    /// Trial `k`'s marker samples, the simulated positions recovered from `r`,
    /// the campaign's whitened residuals at some point (the residuals hold the
    /// simulated minus the measured position in noise units; no extra run).
    pub(crate) fn marker_samples(&self, k: usize, r: &[f64]) -> Vec<MarkerSample> {
        let trial = &self.trials[k];
        let start = self.offsets[k];
        let mut raw = r[start..self.offsets[k + 1]].to_vec();
        unwhiten_markers(&mut raw, &trial.marker_groups);
        let mut at = trial.force.len();
        trial
            .markers
            .iter()
            .map(|(m, _, position)| {
                let obs = &self.observations[start + at];
                let simulated =
                    position.iter().zip(&raw[at..]).map(|(p, d)| p + self.marker_sigma_mm * d).collect::<Vec<_>>();
                at += position.len();
                MarkerSample { marker: *m, t_s: obs.t_s, phase: obs.phase, measured: position.clone(), simulated }
            })
            .collect()
    }

    /// Sets every trial's mesh correction to the difference between `fine`'s
    /// run (the same trials on a refined mesh) and this model's, both at
    /// `theta` without candidate (module docs, "Mesh"). Returns the correction,
    /// whitened, in residual order (observation rows).
    pub fn set_mesh_correction(&mut self, fine: &mut Model, theta: &[f64]) -> Result<Vec<f64>, EvalError> {
        fine.sample_scale_sd = self.sample_scale_sd;
        fine.marker_sigma_mm = self.marker_sigma_mm;
        fine.settings = self.settings.clone();
        for (f, t) in fine.trials.iter_mut().zip(&self.trials) {
            f.force_sigma_n = t.force_sigma_n;
            f.force_rho = t.force_rho;
        }
        let fine = &*fine;
        let parts: Vec<Vec<f64>> = (0..self.trials.len())
            .into_par_iter()
            .map(|k| {
                let coarse = self.raw_residuals_of(k, &self.run(k, &self.problem(k, theta, None)?, None)?);
                let refined = fine.raw_residuals_of(k, &fine.run(k, &fine.problem(k, theta, None)?, None)?);
                Ok(refined.iter().zip(&coarse).map(|(a, b)| a - b).collect())
            })
            .collect::<Result<_, EvalError>>()?;
        let mut out = Vec::new();
        for (t, d) in self.trials.iter_mut().zip(parts) {
            let mut w = d.clone();
            whiten(&mut w[..t.force.len()], t.force_rho);
            out.extend(w);
            t.mesh_correction = d;
        }
        Ok(out)
    }

    /// Trial `k`'s residuals at `theta` and `effect`, and the run's step ends; on
    /// the given step ends (replayed) when `steps` is given.
    pub(crate) fn trial_residuals(
        &self,
        k: usize,
        theta: &[f64],
        effect: Option<(CandidateId, &[f64])>,
        steps: Option<&[f64]>,
    ) -> Result<(Vec<f64>, Vec<f64>), EvalError> {
        let p = self.problem(k, theta, effect)?;
        let result = self.run(k, &p, steps)?;
        let ends = result.steps.iter().map(|s| s.t_s).collect();
        Ok((self.residuals_of(k, &result), ends))
    }

    /// Every residual at `theta` and `effect` (trials in parallel), with each
    /// trial's step ends.
    pub fn residuals(
        &self,
        theta: &[f64],
        effect: Option<(CandidateId, &[f64])>,
        steps: Option<&[Vec<f64>]>,
    ) -> Result<(Vec<f64>, Vec<Vec<f64>>), EvalError> {
        let parts: Vec<(Vec<f64>, Vec<f64>)> = (0..self.trials.len())
            .into_par_iter()
            .map(|k| self.trial_residuals(k, theta, effect, steps.map(|s| s[k].as_slice())))
            .collect::<Result<_, _>>()?;
        let mut r = Vec::with_capacity(self.num_residuals());
        let mut ends = Vec::new();
        for (rk, e) in parts {
            r.extend(rk);
            ends.push(e);
        }
        r.extend(self.prior_rows(theta));
        Ok((r, ends))
    }

    /// The engine's sensitivity parameters of the unknowns acting on trial `k`.
    fn sensitivity_parameters(&self, k: usize, problem: &AnyPress) -> Vec<(usize, SensitivityParameter)> {
        let trial = &self.trials[k];
        let materials = match problem {
            AnyPress::Plane(p) => &p.materials,
            AnyPress::Solid(p) => &p.materials,
            AnyPress::Axisymmetric(p) => &p.materials,
        };
        let mut acting = Vec::new();
        for (col, u) in self.unknowns.iter().enumerate() {
            if let Some(parameter) = sensitivity_parameter(u, &trial.region_material, materials) {
                acting.push((col, parameter));
            }
        }
        acting
    }

    /// Trial `k`'s residuals and Jacobian at `(theta, u)` of `candidate`: columns
    /// of the unknowns then of the candidate's coordinates (module docs).
    pub(crate) fn trial_jacobian(
        &self,
        k: usize,
        theta: &[f64],
        candidate: Option<(&Candidate, &[f64])>,
        theta_columns: bool,
    ) -> Result<(Vec<f64>, Vec<Vec<f64>>), EvalError> {
        let values = candidate.map(|(c, u)| (c.effect, c.values(u)));
        let effect = values.as_ref().map(|(e, v)| (*e, v.as_slice()));
        let problem = self.problem(k, theta, effect)?;
        let p = self.unknowns.len();
        let d = candidate.map_or(0, |(c, _)| c.dim());
        // Contact runs, damaged materials and networks have no sensitivities:
        // their columns come from differences.
        let sens_ok = problem.effects().check_sensitivities().is_ok()
            && !problem.has_tools()
            && !problem.has_damage()
            && !problem.has_network();
        let acting = if theta_columns { self.sensitivity_parameters(k, &problem) } else { Vec::new() };
        let (r, mut columns, steps) = if sens_ok && !acting.is_empty() {
            let params: Vec<SensitivityParameter> = acting.iter().map(|a| a.1.clone()).collect();
            let (result, sens) = simulate_any_with_sensitivities(&problem, &self.settings, &params, &mut |_| {})
                .map_err(|e| EvalError::with_source(format!("trial {}", self.trials[k].name), e))?;
            let trial = &self.trials[k];
            let kinds = self.scale_kind();
            let mut cols = vec![vec![0.0; 0]; p];
            for (q, (col, _)) in acting.iter().enumerate() {
                // The engine's derivative is by the trial's scaled value.
                let factor = kinds[*col].map_or(1.0, |g| self.scale_factor(k, theta, g));
                let mut c: Vec<f64> =
                    trial.force.iter().map(|&(t, _)| sens.bottom_force_at(t)[q] / trial.force_sigma_n).collect();
                for (m, i, position) in &trial.markers {
                    for comp in 0..position.len() {
                        c.push(sens.markers[*m][*i][q][comp] / self.marker_sigma_mm);
                    }
                }
                c.iter_mut().for_each(|v| *v *= factor);
                whiten(&mut c[..trial.force.len()], trial.force_rho);
                whiten_markers(&mut c, &trial.marker_groups);
                cols[*col] = c;
            }
            let steps: Vec<f64> = result.steps.iter().map(|s| s.t_s).collect();
            (self.residuals_of(k, &result), cols, steps)
        } else {
            let result = self.run(k, &problem, None)?;
            let steps: Vec<f64> = result.steps.iter().map(|s| s.t_s).collect();
            (self.residuals_of(k, &result), vec![Vec::new(); p], steps)
        };
        let n = r.len();
        let need_fd_theta = theta_columns && (!sens_ok || acting.is_empty());
        if need_fd_theta || d > 0 {
            let acting_all = self.sensitivity_parameters(k, &problem);
            // Frozen steps; when a replayed run fails (contact that does not settle
            // on a step it may not subdivide), adaptive runs with larger steps.
            let fd = |frozen: Option<&[f64]>, rel: f64, rel_u: f64| -> Result<Vec<Vec<f64>>, EvalError> {
                let mut out = Vec::new();
                let base = match frozen {
                    Some(st) => self.residuals_of(k, &self.run(k, &problem, Some(st))?),
                    None => r.clone(),
                };
                let diff =
                    |plus: &[f64], h: f64| -> Vec<f64> { plus.iter().zip(&base).map(|(a, b)| (a - b) / h).collect() };
                if need_fd_theta {
                    // Every unknown of a material the trial holds acts on it (a
                    // network key has no engine sensitivity parameter).
                    let trial = &self.trials[k];
                    let acting_cols: Vec<usize> = (0..self.unknowns.len())
                        .filter(|&i| {
                            acting_all.iter().any(|a| a.0 == i)
                                || trial.region_material.contains(&self.unknowns[i].material)
                        })
                        .collect();
                    for (i, u) in self.unknowns.iter().enumerate() {
                        if !acting_cols.contains(&i) {
                            out.push(Vec::new());
                            continue;
                        }
                        let spec = u.spec();
                        let mut t2 = theta.to_vec();
                        let h = match spec.scale {
                            crate::lsq::Scale::Log => rel * theta[i],
                            crate::lsq::Scale::Linear => rel * (spec.upper - spec.lower),
                        };
                        let h = if t2[i] + h > spec.upper { -h } else { h };
                        t2[i] += h;
                        let pr = self.problem(k, &t2, effect)?;
                        out.push(diff(&self.residuals_of(k, &self.run(k, &pr, frozen)?), h));
                    }
                }
                if let Some((c, u)) = candidate {
                    for (j, coord) in c.coords.iter().enumerate() {
                        let [lo, hi] = coord.bounds();
                        let mut h = rel_u * coord.scale(u[j]);
                        if u[j] + h > hi {
                            h = -h;
                        }
                        if u[j] + h < lo {
                            h = 0.5 * (hi - u[j]);
                        }
                        let mut u2 = u.to_vec();
                        u2[j] += h;
                        let v2 = c.values(&u2);
                        let pr = self.problem(k, theta, Some((c.effect, &v2)))?;
                        out.push(diff(&self.residuals_of(k, &self.run(k, &pr, frozen)?), h));
                    }
                }
                Ok(out)
            };
            // Contact steps cannot be replayed reliably (a step that does not
            // settle may not be subdivided): adaptive runs straight away.
            let contact = candidate.is_some_and(|(c, _)| c.effect.hook() == fem_core::effects::HookPoint::Contact);
            let frozen = if contact { Err(EvalError::new("contact")) } else { fd(Some(&steps), 1e-6, 1e-3) };
            let cols = match frozen {
                Ok(c) => c,
                Err(_) => fd(None, 2e-2, 5e-2)?,
            };
            let mut it = cols.into_iter();
            if need_fd_theta {
                for c in columns.iter_mut().take(p) {
                    *c = it.next().unwrap_or_default();
                }
            }
            columns.extend(it);
        }
        for c in columns.iter_mut().take(p) {
            if c.is_empty() {
                *c = vec![0.0; n];
            }
        }
        Ok((r, columns))
    }

    /// Parameter specs of the unknowns.
    pub fn theta_specs(&self) -> Vec<ParameterSpec> {
        let mut s: Vec<ParameterSpec> = self.unknowns.iter().map(Unknown::spec).collect();
        let w = self.sample_scale_sd;
        s.extend(self.scale_labels().into_iter().map(|l| ParameterSpec::linear(l, -3.0 * w, 3.0 * w)));
        s
    }

    /// Which unknowns are moduli (`true`) or viscosities (`false`), `None` for others.
    pub fn scale_kind(&self) -> Vec<Option<bool>> {
        self.unknowns
            .iter()
            .map(|u| {
                if u.key.ends_with("_MPa_s") {
                    Some(false)
                } else if u.key.ends_with("_MPa") {
                    Some(true)
                } else {
                    None
                }
            })
            .collect()
    }
}

/// A least-squares problem over the unknowns and, with a candidate, its
/// coordinates: `x = (theta, u)`.
pub struct Fitting<'m> {
    /// The model.
    pub model: &'m Model,
    /// The candidate, if any.
    pub candidate: Option<&'m Candidate>,
}

impl Fitting<'_> {
    /// Specs of `x`: the unknowns' then the coordinates' (linear, in their bounds).
    pub fn specs(&self) -> Vec<ParameterSpec> {
        let mut s = self.model.theta_specs();
        if let Some(c) = self.candidate {
            for coord in &c.coords {
                let [lo, hi] = coord.bounds();
                s.push(ParameterSpec::linear(coord.spec.key, lo, hi));
            }
        }
        s
    }
}

impl LeastSquares for Fitting<'_> {
    fn num_parameters(&self) -> usize {
        self.model.num_theta() + self.candidate.map_or(0, Candidate::dim)
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        let pt = self.model.num_theta();
        let p = self.model.unknowns.len();
        let (theta, u) = x.split_at(pt);
        let model = self.model;
        if !want_jacobian {
            let values = self.candidate.map(|c| (c.effect, c.values(u)));
            let (r, _) = model.residuals(theta, values.as_ref().map(|(e, v)| (*e, v.as_slice())), None)?;
            return Ok(Evaluation { residuals: r, jacobian: None });
        }
        let parts: Vec<(Vec<f64>, Vec<Vec<f64>>)> = (0..model.trials.len())
            .into_par_iter()
            .map(|k| model.trial_jacobian(k, theta, self.candidate.map(|c| (c, u)), true))
            .collect::<Result<_, _>>()?;
        let prior = model.prior_rows(theta);
        let n = model.num_residuals() + prior.len();
        let cols = self.num_parameters();
        let mut residuals = Vec::with_capacity(n);
        let mut jac = DMatrix::zeros(n, cols);
        let mut row = 0;
        let kinds = model.scale_kind();
        let groups = model.scale_groups();
        let nb = model.num_scales();
        for (k, (r, c)) in parts.into_iter().enumerate() {
            for (j, col) in c.iter().enumerate() {
                // Unknowns, then (past the scales) the effect's coordinates.
                let target = if j < p { j } else { j - p + pt };
                for (i, v) in col.iter().enumerate() {
                    jac[(row + i, target)] = *v;
                }
            }
            // d r / d b = sum over the kind's unknowns of theta_i d r / d theta_i.
            if nb > 0 {
                for (gi, &g) in groups.iter().enumerate() {
                    let target = p + k * groups.len() + gi;
                    for (j, col) in c.iter().enumerate().take(p) {
                        if kinds[j] == Some(g) {
                            for (i, v) in col.iter().enumerate() {
                                jac[(row + i, target)] += theta[j] * v;
                            }
                        }
                    }
                }
            }
            row += r.len();
            residuals.extend(r);
        }
        for (m, b) in prior.into_iter().enumerate() {
            residuals.push(b);
            jac[(row + m, p + m)] = 1.0 / model.sample_scale_sd;
        }
        Ok(Evaluation { residuals, jacobian: Some(jac) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_follow_the_waypoints() {
        let w = [[0.0, 0.0], [2.0, 0.0], [10.0, 1.5], [20.0, 1.5], [25.0, 0.5]];
        assert_eq!(phase_at(&w, 30.0, 1.0), Phase::PreContact);
        assert_eq!(phase_at(&w, 30.0, 5.0), Phase::Push);
        assert_eq!(phase_at(&w, 30.0, 10.0), Phase::Push);
        assert_eq!(phase_at(&w, 30.0, 15.0), Phase::Hold);
        assert_eq!(phase_at(&w, 30.0, 22.0), Phase::Release);
        assert_eq!(phase_at(&w, 30.0, 28.0), Phase::Hold);
        assert_eq!(phase_at(&w, 30.0, 31.0), Phase::Recovery);
    }

    #[test]
    fn whitening_is_inverted_exactly() {
        let r: Vec<f64> = (0..50).map(|i| (i as f64 * 0.37).sin() + 0.1 * i as f64).collect();
        let mut w = r.clone();
        whiten(&mut w, 0.6);
        unwhiten(&mut w, 0.6);
        for (a, b) in r.iter().zip(&w) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
    }

    #[test]
    fn ar1_noise_is_recovered_from_detrended_quiet_segments() {
        // sigma 2, rho 0.6, an offset and a drift on top; two quiet runs split by a loud one.
        let mut rng = crate::rng::SplitMix64::new(9);
        let (sigma, rho) = (2.0, 0.6);
        let mut e = sigma * rng.next_gaussian();
        let series: Vec<(f64, f64)> = (0..6000)
            .map(|i| {
                if i > 0 {
                    e = rho * e + (1.0 - rho * rho).sqrt() * sigma * rng.next_gaussian();
                }
                let t = i as f64 * 0.1;
                (t, 5.0 + 0.3 * t + e)
            })
            .collect();
        let quiet: Vec<bool> = (0..6000).map(|i| !(2000..2500).contains(&i)).collect();
        let (s, r) = ar1_estimate(&series, &quiet).unwrap();
        // About 5500 samples: sigma within 5 %, rho within 0.04.
        assert!((s / sigma - 1.0).abs() < 0.05, "{s}");
        assert!((r - rho).abs() < 0.04, "{r}");
        assert!(ar1_estimate(&series[..10], &quiet[..10]).is_none());
    }

    /// The blind check's quiet records (a 20-sample pre-contact run and a
    /// 200-sample recovery, split by the loud contact) at rho = 0.5: over 1,000
    /// replicas the mean estimate is within 0.01 of rho and the mean variance
    /// within 2 % (Monte Carlo standard errors about 0.002 and 0.3 %). The raw
    /// moments missed by -0.038 and -3.4 % (module docs of [`ar1_estimate`]).
    #[test]
    fn ar1_estimate_is_unbiased_on_short_detrended_runs() {
        let mut rng = crate::rng::SplitMix64::new(15);
        let (sigma, rho) = (3.0, 0.5);
        let quiet: Vec<bool> = (0..320).map(|i| !(20..120).contains(&i)).collect();
        let replicas = 1000;
        let (mut sum_rho, mut sum_var) = (0.0, 0.0);
        for _ in 0..replicas {
            let mut e = sigma * rng.next_gaussian();
            let series: Vec<(f64, f64)> = (0..320)
                .map(|i| {
                    if i > 0 {
                        e = rho * e + (1.0 - rho * rho).sqrt() * sigma * rng.next_gaussian();
                    }
                    let t = i as f64 * 0.1;
                    (t, 0.01 * t + e)
                })
                .collect();
            let (s, r) = ar1_estimate(&series, &quiet).unwrap();
            sum_rho += r;
            sum_var += s * s;
        }
        let (mean_rho, mean_var) = (sum_rho / replicas as f64, sum_var / replicas as f64);
        assert!((mean_rho - rho).abs() < 0.01, "{mean_rho}");
        assert!((mean_var / (sigma * sigma) - 1.0).abs() < 0.02, "{mean_var}");
    }

    /// The exact moments against the sums over the dense matrices, at n = 7.
    #[test]
    fn detrended_moments_match_the_dense_traces() {
        let n = 7;
        let rho: f64 = 0.6;
        let t: Vec<f64> = (0..n).map(|i| (i * i) as f64 * 0.3).collect();
        let mt = t.iter().sum::<f64>() / n as f64;
        let stt: f64 = t.iter().map(|x| (x - mt).powi(2)).sum();
        let q = vec![vec![1.0 / (n as f64).sqrt(); n], t.iter().map(|x| (x - mt) / stt.sqrt()).collect::<Vec<f64>>()];
        let s = DMatrix::from_fn(n, n, |i, j| rho.powi((i as i32 - j as i32).abs()));
        let a = DMatrix::from_fn(n, n, |i, j| if i.abs_diff(j) == 1 { 0.5 } else { 0.0 });
        let qm = DMatrix::from_fn(n, 2, |i, k| q[k][i]);
        let m = DMatrix::identity(n, n) - &qm * qm.transpose();
        let (e0, e1) = detrended_moments(&q, rho);
        assert!((e0 - (&m * &s).trace()).abs() < 1e-12, "{e0}");
        assert!((e1 - (&m * &a * &m * &s).trace()).abs() < 1e-12, "{e1}");
    }

    #[test]
    fn marker_whitening_whitens_a_shared_initial_error() {
        // Covariance I + 1 1^T over m samples: W (I + 1 1^T) W^T = I.
        let m = 7;
        let group = vec![(0..m).collect::<Vec<usize>>()];
        let w = DMatrix::from_fn(m, m, |i, j| {
            let mut e = vec![0.0; m];
            e[j] = 1.0;
            whiten_markers(&mut e, &group);
            e[i]
        });
        let cov = DMatrix::from_fn(m, m, |i, j| if i == j { 2.0 } else { 1.0 });
        let out = &w * cov * w.transpose();
        for i in 0..m {
            for j in 0..m {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((out[(i, j)] - want).abs() < 1e-12, "{i} {j}: {}", out[(i, j)]);
            }
        }
    }

    #[test]
    fn marker_unwhitening_inverts_the_whitening() {
        // Two groups (sizes 3 and 5) interleaved with untouched entries.
        let groups = vec![vec![1, 4, 6], vec![0, 2, 3, 7, 9]];
        let r: Vec<f64> = (0..10).map(|i| (i as f64 * 1.7).sin() + 0.3).collect();
        let mut w = r.clone();
        whiten_markers(&mut w, &groups);
        assert!(w.iter().zip(&r).any(|(a, b)| (a - b).abs() > 1e-3));
        unwhiten_markers(&mut w, &groups);
        for (a, b) in r.iter().zip(&w) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
    }

    /// The marker positions recovered from whitened residuals are the run's
    /// own, to round-off (1e-9 mm on positions of about 10 mm), and the samples
    /// carry their time and phase.
    #[test]
    fn marker_samples_recover_the_simulated_positions() {
        use wagashi_io::{MarkerSample as Sample, MarkerSeries};
        let mut bundles = crate::diagnosis::tests::campaign("", 3e-3, 16);
        for b in &mut bundles {
            let (release, end) = (b.experiment.protocol.release_s, b.experiment.protocol.end_s);
            let times = [0.0, 0.6 * release, 0.9 * release, 0.5 * (release + end), end];
            b.markers = [[20.0, 4.0], [20.0, 11.0], [6.0, 15.0]]
                .iter()
                .enumerate()
                .map(|(m, &[x, y])| MarkerSeries {
                    name: format!("m{m}"),
                    // Measured: the initial place, moved by a made-up amount.
                    samples: times
                        .iter()
                        .enumerate()
                        .map(|(i, &t)| Sample { t_s: t, position_mm: vec![x + 0.01 * i as f64, y - 0.02 * i as f64] })
                        .collect(),
                })
                .collect();
        }
        let c = crate::trial::Campaign::new(&bundles, &BTreeMap::new(), Some(5.0), false).unwrap();
        let model = Model::new(&bundles, &c.materials, c.unknowns.clone(), Some(5.0), false, 0.05).unwrap();
        let theta = c.values();
        let (r, _) = model.residuals(&theta, None, None).unwrap();
        for (k, b) in bundles.iter().enumerate() {
            let result = model.run(k, &model.problem(k, &theta, None).unwrap(), None).unwrap();
            let samples = model.marker_samples(k, &r);
            // Three markers; the t = 0 and in-push samples are not observations.
            assert!(samples.len() >= 9, "{}", samples.len());
            let release = b.experiment.protocol.release_s;
            for s in &samples {
                let i = b.markers[s.marker].samples.iter().position(|x| x.t_s == s.t_s).unwrap();
                assert_eq!(s.phase, if s.t_s > release { Phase::Recovery } else { Phase::Hold });
                let want = &result.markers[s.marker].samples[i].1;
                for (a, w) in s.simulated.iter().zip(want) {
                    assert!((a - w).abs() < 1e-9, "trial {k} marker {} t {}: {a} vs {w}", s.marker, s.t_s);
                }
                assert_eq!(s.measured, b.markers[s.marker].samples[i].position_mm);
            }
        }
    }

    /// The campaign's stress level: the largest measured force over the 20 x 10
    /// mm top face under a plate (to 1e-12); none under a sphere, whose loaded
    /// area the bundle does not state.
    #[test]
    fn peak_stress_is_the_largest_force_over_the_plates_face() {
        let mut bundles = crate::diagnosis::tests::campaign("", 3e-3, 17);
        let peak = bundles
            .iter()
            .flat_map(|b| b.force.as_ref().unwrap().samples.iter().map(|s| s.force_n))
            .fold(f64::MIN, f64::max);
        let sigma = peak_stress_mpa(&bundles).unwrap();
        assert!((sigma - peak / 200.0).abs() < 1e-12 * sigma, "{sigma} against {peak} N / 200 mm^2");
        for b in &mut bundles {
            b.experiment.protocol.tool = Tool::Sphere;
        }
        assert_eq!(peak_stress_mpa(&bundles), None);
    }

    #[test]
    fn infinite_nulls_are_fitted_by_their_inverse() {
        let c = Candidate::new(fem_core::effects::EffectId::PlasticSlider);
        assert_eq!(c.dim(), 1);
        assert!(c.coords[0].inverse);
        assert_eq!(c.null(), vec![0.0]);
        assert_eq!(c.values(&[0.0])[0], f64::INFINITY);
        assert!((c.values(&[c.coords[0].reference()])[0] - 0.01).abs() < 1e-15);
        assert_eq!(c.coords[0].bounds(), [0.0, f64::INFINITY]);
        let f = Candidate::new(fem_core::effects::EffectId::ForceOffset);
        assert_eq!(f.dim(), 2);
        assert!(!f.coords[0].inverse && !f.coords[0].one_sided());
    }
}
