//! The implicit integrators: quasi-static (default) and dynamic generalized-alpha.
//!
//! Quasi-static step from `t0` to `t1 = t0 + dt` (design.md 3.3). With the strain
//! linear in time inside the step, each cell's history `h_k` updates exactly,
//! `h_k(t1) = exp(-r_k dt) h_k(t0) + phi1(r_k dt) (e1 - e0)`. The instantaneous
//! viscous term `B2 e'(t1)` uses the variable-step BDF2 derivative
//! `(alpha0 e1 - alpha1 e0 + alpha2 e_-1)/dt` (BDF1, `e1 - e0`, on the first step after
//! a kink or after a step more than doubled): both are exact for a strain linear
//! in time, so a ramp-hold on a uniform specimen is integrated exactly, and the
//! recovery converges at second order. The stress at `t1` is `C1 [g e1 - q]` with
//! `g = B2 alpha0/dt + G_inf + sum_k a_k phi1(r_k dt)` and `q` from the history.
//! Equilibrium at `t1` is then linear: `(sum_g g_g K_g) u1 = f_body + f_hist`. For one kernel group the
//! matrix is `g(dt) K`, so `K` is factored once per constraint set and every step is
//! one solve; otherwise a factorization is kept per step size (a sqrt(2) ladder).
//!
//! Dynamic: the same internal force plus a lumped mass, generalized-alpha
//! (Chung & Hulbert 1993) with the spectral radius `rho_inf` at infinite frequency
//! (default 0.5): second order, and it damps the stiff, overdamped modes that the
//! viscous term `B2 K` makes against the mass, which the trapezoidal rule (Newmark
//! average acceleration, `rho_inf = 1`) leaves ringing. Held dofs move with the
//! plate exactly (their acceleration is zero between kinks), so reactions carry no
//! spurious inertia.
//!
//! Material-point effects (E1 to E5, [`crate::effects`], and a material's
//! Mullins-type damage with its per-cell largest strain): each cell carries an
//! inelastic strain in series with the chain, the chain's strain and histories
//! are those of `e - e_in`, and the step is solved by the iteration of
//! `super::inelastic` (modified Newton on the same factorization, full Newton when
//! it contracts slowly). Without such an effect none of it runs. With contact
//! tools each of its solves is a settled contact solve (the contact iteration
//! nested inside the material-point one; `super::inelastic`, "With contact tools").
//!
//! Machine compliance (the `machine-compliance` effect, `c = 1/k_m` [mm/N]): the
//! machine's frame and load cell are a spring in series with what presses, along
//! the push axis y. The crosshead follows the protocol (or the tools' keyframes);
//! what presses lags it by the deflection `delta = c F`, `F` the force the
//! machine measures at the step's end.
//! - *Constrained plate:* the plate's displacement is `d_cmd - delta` and `F` the
//!   plate force. On the linear path the step is affine in `delta` and solved in
//!   closed form (`compliant_step`, [`crate::effects`]).
//! - *Contact tools:* the crosshead carries every tool that is not a floor and
//!   whose keyframes move it (`contact::on_crosshead`); all of them are lifted
//!   together by `delta` along +y from their keyframes' pose (a rotation is kept),
//!   and `F` is the sum of the y components of the forces on them, compression
//!   positive (a fixed tool that is not a floor is not on the crosshead: its
//!   force is reported in the plate force but not measured by the spring). The
//!   contact state's anchors move with the lifted tools. Once every crosshead
//!   tool has let go, `delta = 0`.
//! - *Steps not affine in `delta`* (contact; the material-point path and the
//!   Mullins damage, on the plate or with tools): a scalar iteration around the
//!   step's own solve ([`deflected_step`]): `r(delta) = delta - c F(delta)` is
//!   increasing where the force does not grow as the tools back off (every law
//!   but adhesion's softening branch, where the run stops with
//!   [`PressError::DeflectionNotConverged`]), the last step's deflection and `c F` of it
//!   bracket its root, and Illinois closes the bracket
//!   to `1e-11` of the displacement scale. Each evaluation is a whole step from
//!   the old state (a settled contact solve, a converged material-point
//!   iteration), so the accepted step's state is that of the step at the root.
//!
//! The reported plate (tool) force is `F`, and the relation `delta = c F` holds at
//! every step end to the iteration's tolerance. Without the effect (or at its
//! null) none of it runs and the steps are the baseline's bit for bit.
//!
//! Step control: the local error of the displacement is estimated against an
//! extrapolation of the previous steps (quadratic for BDF2 steps, linear for BDF1
//! ones), relative to `rtol` times the largest plate displacement; steps land on every
//! kink (waypoints, release, end). After a kink the estimator restarts from a tiny
//! step (it cannot check the first step of a segment) and grows at most 4x a step.
//!
//! With a flowing material-point law (E1 to E4: slider, Bingham, thinning, dual
//! viscosity; [`crate::material::InelasticLaw::flows`]) the inelastic strains are
//! checked as well, and the larger of the two error ratios sets the step.
//!
//! *Why the inelastic strains, and not the reaction force.* (1) They are the only
//! state a hold step integrates inexactly: the chain's histories are exact for a
//! strain linear in time, and the displacements barely move while the plate holds
//! still, so the displacements' estimate alone let hold steps grow to the bound (a
//! twentieth of the trial) while the dashpot corrections are backward Euler (first
//! order; `crate::effects`, "Accuracy") and the force drifted with them (measured
//! 1.0 % of the peak in a 400 s thinning hold at the default `rtol`, and 1.8 % at
//! `rtol` 1e-4: tightening did not help; `tests/step_control.rs`). (2) The force
//! is a curved function of time even where the step is exact (a linear chain's
//! relaxation), so a force estimate would shorten the steps of every linear run
//! for nothing; the inelastic strains are zero there, and runs without a flowing
//! law keep their steps bit for bit. (3) The force is the cross-section's integral
//! of the cells' stresses, whose error is the chain's stiffness times that of the
//! inelastic strains, so the measure is a volume-weighted mean over the cells: a
//! largest cell would let a glued corner's fast flow set every step.
//!
//! *The measure.* The RMS over the cells, weighted by their share of the
//! specimen's volume, of the difference between the step's inelastic strain and
//! its linear extrapolation from the last two step ends, in the unit-Young energy
//! norm `|x|_C` of the laws' equivalent stress (in uniaxial stress the axial
//! component); half of it estimates the local error, against `flow_rtol` times
//! the plate's largest nominal strain (its largest displacement over the
//! specimen's height), and the step follows with the exponent 1/2. Why linear,
//! and half: backward Euler's chord over the last step is its end rate, so the
//! linear predictor is forward Euler from that rate and the difference is
//! `h (rate1 - rate0)`, about `h^2 e''`, twice backward Euler's local error
//! `h^2 e''/2`. The quadratic predictor of the displacements does not fit a
//! first-order sequence: its back values carry step-to-step errors of order
//! `h h0`, so the difference did not shrink with the step (measured: rejections
//! down to a sixteenth of the step and a saw-tooth of step sizes).
//!
//! *Bingham's net flow.* Bingham's correction takes back the chain's own dashpot
//! flow on the step's mean stress (`crate::material::point`, module doc), so below
//! its threshold the inelastic strain is minus the chain's dashpot strain, whose
//! rate `tau/c3` changes on the loading's time scale over `c3`: with a small `c3`
//! its second difference would set steps of 1e-4 s where the dashpot does not
//! move at all. For such a cell the measure is the *net* dashpot flow, the
//! inelastic strain plus the chain's own flow `int tau/c3 dt` (`dt tau_mean/c3` a
//! step, exact for the chain's strain linear in time; `State::chain_flow`): zero
//! below the threshold, the Bingham flow `(|tau|_C - sigma_B)/|tau|_C tau/c3`
//! above it. The other laws' corrections are measured as before.
//!
//! *The default* `flow_rtol = FLOW_RTOL_FACTOR rtol` (a tenth): with a first-order
//! corrector under local control the global error falls only as the square root
//! of the tolerance, and a tenth brings the hold force to the displacements'
//! accuracy class (measured on the 400 s thinning hold, largest hold-force error
//! against a converged reference, of the peak: 4.5e-3 with `flow_rtol = rtol`,
//! 1.5e-3 with a tenth, 4.9e-4 with a hundredth; 59, 129 and 362 steps, against
//! 42 steps and 1.0e-2 with the displacements alone). The strain-driven laws
//! (stiffening, damage) are exact functions of the step end's strain and are not
//! checked.
//!
//! *Retries.* A step that fails (a material-point iteration that does not
//! converge, an inverted cell on the material-point path, contact that does not
//! settle, a machine deflection that does not settle) is retried from its old state at a quarter of its length, at most
//! three times in a row, but never below the least step `1e-10` of the trial
//! (the error control's own floor): there the failure is returned as the run's
//! error, on every step, the one that lands on the trial's end included. (That
//! last step needs the floor of the tolerance's scale: the Mullins cycle of
//! `fem-core/tests/mullins.rs` ends unloaded, where the material-point
//! iteration's own force scale is round-off and its tolerance could not be met
//! at any length; the tolerance's scale has the run's largest as its floor,
//! [`super::inelastic`], "The force scale".) Without that floor a step that
//! failed at every length above some tiny one ran at that length for ever: each accepted step grew fourfold (its error
//! ratio negligible), failed and was retried at a quarter (measured: a
//! `dual-viscosity` refit point of the fungi-steak diagnosis, `psi` = -7.13,
//! Poisson ratio 0.4988, steps of 2.6e-12 s at the load peak, every accepted
//! step preceded by one non-converged attempt, 1.6 million steps and 1.4 GB
//! before it was stopped).
//!
//! *Blocking corrections.* A correction that takes back the chain's dashpot flow
//! (Bingham below its threshold, `-tau/c3`; the dual viscosity while unloading,
//! `-(1 - exp(-psi)) tau/c3`: a share `s` of `1/c3`) is driven by the whole chain
//! stress, including the instantaneous viscous part `B2 e'`, whose BDF2 derivative
//! looks two steps back. With `b = B2 s/c3`, an oscillation `y_n` of the inelastic
//! strain at fixed total strain obeys `y_n - y_n-1 = b (alpha0 y_n - alpha1 y_n-1 +
//! alpha2 y_n-2)`: roots 1 and `-alpha2 b/(1 - alpha0 b)`, independent of the step.
//! At constant steps that is `-b/(2 - 3b)`: size 1 at `b = 1/2`, an undamped
//! saw-tooth that no step makes smaller, so the flow control held the step where
//! its ratio stays put (measured: a Bingham candidate of the fungi-steak diagnosis,
//! `c3` 1.35e-5 MPa s, `B2` 6.75e-6 MPa s, `b` 0.49999, steps of 6e-9 s for ever).
//! BDF1's recurrence `(1 - b)(y_n - y_n-1) = 0` has no such root, so a step whose
//! parasitic root would exceed [`PARASITIC_ROOT`] takes BDF1 (first order in the
//! viscous term, as the corrections themselves are). Chains with a small `B2`
//! (`b` about 1e-5 for the real materials' fits) and laws that block nothing keep
//! BDF2, bit for bit. Bingham's correction acts on the step's mean stress, whose
//! viscous part is the exact `B2 de/dt` of the step (no value two steps back:
//! `crate::material::point`), so the root above does not arise from it; the
//! switch covers it all the same (BDF2 with a blocked
//! Bingham chain at `b = 1/2` was not tested).

use std::cell::{Cell, RefCell};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use crate::parallel::map_collect;
use nalgebra::{SMatrix, SVector};

use super::contact::{ContactModel, Settled, StepInput, ToolSample, ToolTrack};
use super::inelastic::{self, PointInput};
use super::model::{Constraints, Model};
use super::result::{ForceSegment, RegionTerms};
use super::sensitivity::{check_parameters, Sensitivities, SensitivityParameter, StepView, Tracker};
use super::{Integrator, MarkerTrack, PressError, PressProblem, PressResult, Progress, Settings, Snapshot, StepRecord};
use crate::assembly::assemble_vector;
use crate::element::{nodal_force, ReferenceSimplex, Simplex};
use crate::material::phi1;
use crate::solve::{Factor, ReducedSystem};

/// Generalized-alpha parameters for a spectral radius `rho_inf` in [0, 1].
#[derive(Debug, Clone, Copy)]
struct GeneralizedAlpha {
    alpha_m: f64,
    alpha_f: f64,
    beta: f64,
    gamma: f64,
}

impl GeneralizedAlpha {
    /// Chung & Hulbert's optimal choice; quasi-static steps use `alpha_m = alpha_f = 0`.
    fn new(rho_inf: f64) -> Self {
        let alpha_m = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0);
        let alpha_f = rho_inf / (rho_inf + 1.0);
        let gamma = 0.5 - alpha_m + alpha_f;
        Self { alpha_m, alpha_f, beta: 0.25 * (1.0 - alpha_m + alpha_f).powi(2), gamma }
    }

    const QUASI_STATIC: GeneralizedAlpha = GeneralizedAlpha { alpha_m: 0.0, alpha_f: 0.0, beta: 0.25, gamma: 0.5 };
}
/// The first step after a kink, as a fraction of the time to the next kink: small,
/// because it cannot be checked (the estimator needs two steps of one segment).
const FIRST_STEP_FRACTION: f64 = 1e-6;
/// The length of the step that takes an instantaneous elastic jump, relative to the trial.
const INSTANT_STEP_FRACTION: f64 = 1e-11;
/// Below this error ratio a step counts as exact (the strain was linear in time).
const EXACT_RATIO: f64 = 1e-4;
/// The default flow tolerance relative to `rtol` (`Settings::flow_rtol`; module doc).
pub(crate) const FLOW_RTOL_FACTOR: f64 = 0.1;
/// The largest size of BDF2's parasitic root that a blocking correction may give it
/// (module doc, "Blocking corrections"): an oscillation then halves every step.
const PARASITIC_ROOT: f64 = 0.5;
/// The largest growth of the step from one step to the next.
const MAX_GROWTH: f64 = 4.0;
/// The factorization cache holds at most this many numeric factors.
const CACHE_SIZE: usize = 3;

/// A numeric factor is valid for one constraint set (plate attached or not) and,
/// unless one kernel group lets it be scaled, one step size and BDF coefficient.
type CacheKey = (bool, (u64, u64));

/// A cell after a step: strain, histories, stress, volume ratio.
type CellUpdate<const S: usize> = (SVector<f64, S>, [SVector<f64, S>; 2], SVector<f64, S>, f64);

/// The state at a step end.
#[derive(Clone)]
struct State<const S: usize> {
    t: f64,
    u: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    strain: Vec<SVector<f64, S>>,
    /// The strain one step back (for BDF2).
    strain_prev: Vec<SVector<f64, S>>,
    history: Vec<[SVector<f64, S>; 2]>,
    /// Internal force at this time (dynamic runs only; empty otherwise) [N].
    f_int: Vec<f64>,
    /// Material-point path only (empty otherwise): the inelastic strain per cell,
    /// in series with the chain; `strain` and `history` are then the chain's, of
    /// `e - e_in` ([`super::inelastic`]).
    inelastic: Vec<SVector<f64, S>>,
    /// The `dual-viscosity` effect's unloading flag per cell (empty otherwise).
    unloading: Vec<bool>,
    /// The Mullins-type damage's largest equivalent strain per cell (empty otherwise).
    damage_history: Vec<f64>,
    /// The largest force measured so far [N]: the magnitude of the plate or bottom
    /// force at the accepted step ends up to this state's (0 at rest). The floor of
    /// the material-point iteration's tolerance scale ([`super::inelastic`], "The
    /// force scale").
    force_scale: f64,
    /// The chain's own dashpot flow per cell, `int tau/c3 dt` from the start, where
    /// the region's law corrects the dashpot on the step's mean stress (Bingham's:
    /// [`crate::material::InelasticLaw::mean_corrected_c3`]; zero elsewhere; empty
    /// without such a law). The step control measures `inelastic + chain_flow`.
    chain_flow: Vec<SVector<f64, S>>,
}

impl<const S: usize> State<S> {
    /// The flow the step control measures in cell `c` (module doc, "Step control"):
    /// the inelastic strain, plus the chain's own dashpot flow where the law
    /// corrects the dashpot on the step's mean stress (then the net dashpot flow).
    fn measured_flow(&self, c: usize) -> SVector<f64, S> {
        match self.chain_flow.get(c) {
            Some(f) => self.inelastic[c] + f,
            None => self.inelastic[c],
        }
    }

    /// [`Self::measured_flow`] of every cell (the inelastic strains themselves
    /// without a mean-corrected law).
    fn measured_flows(self) -> Vec<SVector<f64, S>> {
        if self.chain_flow.is_empty() {
            self.inelastic
        } else {
            (0..self.inelastic.len()).map(|c| self.measured_flow(c)).collect()
        }
    }
}

/// Per-region scalars of one step size.
struct StepFactors {
    g: f64,
    /// The mean factor ([`crate::material::RelaxationKernel::mean_factor`]).
    g_mean: f64,
    decay: [f64; 2],
    phi: [f64; 2],
}

/// The backward-difference coefficients of `e'(t1) = (alpha0 e1 - alpha1 e0 + alpha2 e_-1)/dt`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bdf {
    alpha: [f64; 3],
}

impl Bdf {
    const ONE: Bdf = Bdf { alpha: [1.0, 1.0, 0.0] };

    /// Variable-step BDF2 for `omega = dt / dt_prev`.
    fn two(omega: f64) -> Bdf {
        Bdf { alpha: [(1.0 + 2.0 * omega) / (1.0 + omega), 1.0 + omega, omega * omega / (1.0 + omega)] }
    }

    /// Whether a blocking correction of ratio `blocking` (module doc, "Blocking
    /// corrections") keeps this formula's parasitic root `-alpha2 b / (1 - alpha0 b)`
    /// at most [`PARASITIC_ROOT`] in size. Always true at `b = 0`.
    fn damps(&self, blocking: f64) -> bool {
        let denominator = 1.0 - self.alpha[0] * blocking;
        blocking == 0.0 || (denominator > 0.0 && self.alpha[2] * blocking <= PARASITIC_ROOT * denominator)
    }
}

/// `g = B2 alpha0/dt + G_inf + sum_k a_k phi1(r_k dt)`.
fn step_factor(k: &crate::material::RelaxationKernel, dt: f64, bdf: Bdf) -> f64 {
    k.step_factor(dt) + k.viscous * (bdf.alpha[0] - 1.0) / dt
}

pub(crate) fn run<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
    parameters: &[SensitivityParameter],
    cancel: Option<&AtomicBool>,
    progress: &mut dyn FnMut(Progress),
) -> Result<(PressResult, Option<Sensitivities>), PressError>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    check_settings(settings)?;
    let model = Model::new(problem)?;
    let mut tracker = if parameters.is_empty() {
        None
    } else {
        if settings.integrator != Integrator::QuasiStatic {
            return Err(PressError::BadSettings("sensitivities need the quasi-static integrator".into()));
        }
        check_parameters(problem, parameters)?;
        Some(Tracker::new(&model, parameters))
    };
    let protocol = &problem.protocol;
    let end = protocol.end_s;
    let dynamic = settings.integrator == Integrator::Dynamic;
    // The `machine-compliance` effect [mm/N] (crate::effects: exact per step).
    let compliance = problem.effects.machine_compliance_mm_per_n();
    if compliance.is_some() && (settings.integrator != Integrator::QuasiStatic || tracker.is_some()) {
        return Err(PressError::BadSettings(
            "machine compliance needs the quasi-static integrator and no sensitivities".into(),
        ));
    }
    // The material-point path (crate::effects, E1 to E5; press::inelastic).
    if model.point.is_some() && (settings.integrator != Integrator::QuasiStatic || tracker.is_some()) {
        return Err(PressError::BadSettings(
            "material-point effects (and a material's Mullins damage) need the quasi-static integrator and no \
             sensitivities"
                .into(),
        ));
    }
    let mut point_retries = 0usize;
    // The machine's deflection at the state's time [mm] (0 without compliance),
    // and the tolerance of its scalar iteration ([`deflected_step`]).
    let mut deflection = 0.0;
    let deflection_tol = DEFLECTION_RTOL * model.displacement_scale;
    let ndof = model.num_dofs();
    let ncell = problem.mesh.num_cells();

    // Times the steps must land on: physical kinks restart the error estimator.
    let physical_kinks = problem.kinks();
    let schedule = problem.schedule();

    let dt_max = settings.max_dt_s.unwrap_or(end / 20.0);
    let dt_min = 1e-10 * end;
    let tol = settings.rtol * model.displacement_scale;
    // The inelastic flow's error control (module doc, "Step control"): per cell its
    // share of the specimen's volume where the region's law flows (empty when no
    // law flows: the control is then the displacements' alone, bit for bit).
    let flow_weight: Vec<f64> = match model.point.as_ref() {
        Some(laws) if laws.iter().any(|l| l.flows() && !l.is_null()) => {
            let total: f64 = model.geometry.iter().map(|g| g.weight).sum();
            (0..ncell)
                .map(|e| {
                    let law = &laws[problem.mesh.cell_regions[e] as usize];
                    if law.flows() && !law.is_null() {
                        model.geometry[e].weight / total
                    } else {
                        0.0
                    }
                })
                .collect()
        }
        _ => Vec::new(),
    };
    // The largest blocking ratio `b = B2 s/c3` over the regions whose law flows
    // (module doc, "Blocking corrections"; 0 without such a law: BDF2 as before).
    let blocking = match model.point.as_ref() {
        Some(laws) => laws
            .iter()
            .zip(&model.region_kernel)
            .filter(|(l, _)| l.flows() && !l.is_null())
            .map(|(l, k)| k.viscous * l.blocking_per_mpa_s())
            .fold(0.0, f64::max),
        None => 0.0,
    };
    let flow_tol = {
        let (lo, hi) = problem.mesh.bounding_box();
        settings.flow_rtol.unwrap_or(FLOW_RTOL_FACTOR * settings.rtol) * model.displacement_scale / (hi[1] - lo[1])
    };
    let single_group = model.groups.len() == 1 && !dynamic;
    let ladder = settings.fixed_dt_s.is_none() && !single_group;

    let sys_attached = ReducedSystem::new(&model.pattern, &model.attached.held, Some(&model.node_order))
        .map_err(|e| model.singular(0, 0.0, e))?;
    let sys_released = if protocol.release_s < end {
        Some(
            ReducedSystem::new(&model.pattern, &model.released.held, Some(&model.node_order))
                .map_err(|e| model.singular(0, protocol.release_s, e))?,
        )
    } else {
        None
    };
    let mut cache: Vec<(CacheKey, Factor<'_>)> = Vec::new();
    // Contact: the tools, their state, and the factorization with their penalties.
    let contact = if problem.tools.is_empty() {
        None
    } else {
        if settings.integrator != Integrator::QuasiStatic || tracker.is_some() {
            return Err(PressError::BadSettings(
                "contact tools need the quasi-static integrator and no sensitivities".into(),
            ));
        }
        Some(ContactModel::new(problem, &model.pattern, &model.attached.held)?)
    };
    let mut contact_state = contact.as_ref().map(|c| c.initial_state());
    // Keyed by the path (penalties or eliminated dofs), its matrix's hash and the
    // step key; one slot for both paths, so that two factors never coexist.
    type ContactKey = (bool, u64, (u64, u64));
    let contact_factor: RefCell<Option<(ContactKey, Factor<'_>)>> = RefCell::new(None);
    let mut contact_solves = 0usize;
    let mut contact_retries = 0usize;
    let mut tool_tracks: Vec<ToolTrack> = match contact.as_ref() {
        Some(c) => c
            .initial_samples()
            .into_iter()
            .zip(&problem.tools)
            .map(|(s, tool)| ToolTrack { name: tool.name.clone(), samples: vec![s] })
            .collect(),
        None => Vec::new(),
    };
    let rest: Vec<Vec<f64>> = problem.mesh.nodes.iter().map(|p| p.to_vec()).collect();
    let mut num_factorizations = 0usize;

    let mut state = State::<S> {
        t: 0.0,
        u: vec![0.0; ndof],
        v: vec![0.0; ndof],
        a: vec![0.0; ndof],
        strain: vec![SVector::zeros(); ncell],
        strain_prev: vec![SVector::zeros(); ncell],
        history: vec![[SVector::zeros(); 2]; ncell],
        f_int: if dynamic { vec![0.0; ndof] } else { Vec::new() },
        inelastic: if model.point.is_some() { vec![SVector::zeros(); ncell] } else { Vec::new() },
        unloading: match model.point.as_ref() {
            Some(laws) if laws.iter().any(|l| l.needs_direction()) => vec![false; ncell],
            _ => Vec::new(),
        },
        damage_history: match model.point.as_ref() {
            Some(laws) if laws.iter().any(|l| l.needs_history()) => vec![0.0; ncell],
            _ => Vec::new(),
        },
        force_scale: 0.0,
        chain_flow: match model.point.as_ref() {
            Some(laws) if laws.iter().any(|l| l.mean_corrected_c3().is_some()) => vec![SVector::zeros(); ncell],
            _ => Vec::new(),
        },
    };
    let ga = if dynamic { GeneralizedAlpha::new(settings.rho_inf) } else { GeneralizedAlpha::QUASI_STATIC };
    // Displacements one and two steps back in this segment, with the inelastic
    // strains (only when a law flows; empty otherwise) and the step that left them.
    #[allow(clippy::type_complexity)]
    let mut back: Vec<(Vec<f64>, Vec<SVector<f64, S>>, f64)> = Vec::new();
    let mut steps = Vec::new();
    let mut segments = Vec::new();
    let mut snapshots = Vec::new();
    let mut tracks: Vec<MarkerTrack> =
        problem.markers.iter().map(|m| MarkerTrack { name: m.name.clone(), samples: Vec::new() }).collect();
    let mut marker_next = vec![0usize; problem.markers.len()];
    emit_markers(&model, &mut tracks, &mut marker_next, &state.u, &state.u, 0.0, 0.0, true);

    let first_dt = |t: f64| -> f64 {
        let next = physical_kinks.iter().copied().find(|&k| k > t * (1.0 + 1e-12) + 1e-12).unwrap_or(end);
        settings.fixed_dt_s.unwrap_or_else(|| (FIRST_STEP_FRACTION * (next - t)).min(dt_max).max(dt_min))
    };
    let mut dt = first_dt(0.0);
    let mut step_index = 0usize;
    let mut instant_step = false;

    while state.t < end * (1.0 - 1e-13) {
        let landing = schedule.next_landing(state.t, end);
        let mut h = dt.min(dt_max);
        // Replay: the next given step end after t (the end time if none is left).
        let replay_end = settings
            .step_ends_s
            .as_ref()
            .map(|ends| ends.iter().copied().find(|&t| t > state.t * (1.0 + 1e-12) + 1e-300).unwrap_or(end));
        if let Some(next) = replay_end {
            h = next - state.t;
        } else if ladder {
            h = 2f64.powf((2.0 * h.log2()).floor() / 2.0);
        }
        let remaining = landing - state.t;
        if h >= remaining * (1.0 - 1e-9) {
            h = remaining;
        } else if settings.fixed_dt_s.is_none() && replay_end.is_none() && h > 0.6 * remaining {
            h = 0.5 * remaining;
        }
        let t1 = if h == remaining { landing } else { replay_end.unwrap_or(state.t + h) };
        let constraints = model.constraints_at(t1);
        let system =
            if constraints.plate_attached { &sys_attached } else { sys_released.as_ref().expect("released system") };

        let bdf = match back.first() {
            Some(&(_, _, h_prev)) if h <= 2.0 * h_prev * (1.0 + 1e-9) => Bdf::two(h / h_prev),
            _ => Bdf::ONE,
        };
        // A blocking dashpot correction against a large instantaneous viscosity
        // (module doc, "Blocking corrections"): BDF1 where BDF2's parasitic root is large.
        let bdf = if bdf != Bdf::ONE && !bdf.damps(blocking) { Bdf::ONE } else { bdf };
        // Constraint sets only ever change from attached to released: drop the
        // attached factors then, so that two factors of a large mesh never coexist.
        if !constraints.plate_attached {
            cache.retain(|(k, _)| !k.0);
        }
        let clock = Instant::now();
        let stepped = if let Some(cm) = contact.as_ref() {
            let single_scale = if single_group { step_factor(&model.groups[0].kernel, h, bdf) } else { 1.0 };
            // The step matrix's diagonal at its actual scale sets the penalties.
            let mut diagonal = vec![0.0; ndof];
            for g in &model.groups {
                let c = step_factor(&g.kernel, h, bdf);
                for (d, &p) in model.diagonal_positions.iter().enumerate() {
                    diagonal[d] += c * g.stiffness[p];
                }
            }
            let step_key = if single_group { (0, 0) } else { (h.to_bits(), bdf.alpha[0].to_bits()) };
            let factor_key = {
                use std::hash::{Hash, Hasher};
                let mut hasher = std::collections::hash_map::DefaultHasher::new();
                (constraints.plate_attached, step_key).hash(&mut hasher);
                hasher.finish()
            };
            let refactored = Cell::new(false);
            let factorizations = Cell::new(0usize);
            let solves = Cell::new(0usize);
            // The step with the crosshead tools lifted by `lift` [mm] at its end
            // (machine compliance; 0 without), its contact forces rebalanced.
            let take = |lift: f64| -> Result<(StepOutcome<S>, Settled), PressError> {
                let input = StepInput {
                    t0: state.t,
                    t1,
                    step: step_index + 1,
                    rest: &rest,
                    diagonal: &diagonal,
                    u0: &state.u,
                    factor_key,
                    scale: single_scale,
                    lift: [deflection, lift],
                };
                let mut settled = None;
                let outcome = {
                    let mut solve = |b: &[f64], u: &mut Vec<f64>| -> Result<Option<Vec<f64>>, PressError> {
                        let mut inner =
                            |hash: u64, penalty: &dyn Fn() -> Vec<f64>, extra: &[f64], cols: Option<usize>| {
                                let key = (false, hash, step_key);
                                let mut contact_factor = contact_factor.borrow_mut();
                                if contact_factor.as_ref().map(|(k, _)| *k) != Some(key) {
                                    *contact_factor = None;
                                    let p: Vec<f64> = penalty().into_iter().map(|v| v / single_scale).collect();
                                    let mut terms: Vec<(f64, &[f64])> = model
                                        .groups
                                        .iter()
                                        .map(|g| {
                                            let c = if single_group { 1.0 } else { step_factor(&g.kernel, h, bdf) };
                                            (c, g.stiffness.as_slice())
                                        })
                                        .collect();
                                    terms.push((1.0, p.as_slice()));
                                    let factor = system
                                        .factor(&terms, None)
                                        .map_err(|e| model.singular(step_index + 1, t1, e))?;
                                    factorizations.set(factorizations.get() + 1);
                                    refactored.set(true);
                                    *contact_factor = Some((key, factor));
                                }
                                let factor = &contact_factor.as_ref().expect("set above").1;
                                solves.set(solves.get() + cols.unwrap_or(1));
                                if let Some(ncols) = cols {
                                    // Columns of the unpenalized matrix's inverse (contact's low-rank path).
                                    let (nf, nd) = (system.dof_of_free.len(), u.len());
                                    let mut x = vec![0.0; nf * ncols];
                                    for c in 0..ncols {
                                        for (i, &d) in system.dof_of_free.iter().enumerate() {
                                            x[c * nf + i] = extra[c * nd + d as usize];
                                        }
                                    }
                                    factor.solve_columns_in_place(&mut x, ncols);
                                    let mut out = vec![0.0; nd * ncols];
                                    for c in 0..ncols {
                                        for (i, &d) in system.dof_of_free.iter().enumerate() {
                                            out[c * nd + d as usize] = x[c * nf + i] / single_scale;
                                        }
                                    }
                                    return Ok(out);
                                }
                                let mut x: Vec<f64> =
                                    system.dof_of_free.iter().map(|&d| b[d as usize] + extra[d as usize]).collect();
                                factor.solve_in_place(&mut x);
                                let mut next = u.clone();
                                for (i, &d) in system.dof_of_free.iter().enumerate() {
                                    next[d as usize] = x[i] / single_scale;
                                }
                                Ok(next)
                            };
                        // The exact path: the held dofs cut off the matrix (same pattern,
                        // same symbolic factorization), their coupling moved to the
                        // right-hand side, their reactions `A u - b` from their rows.
                        let coefficients: Vec<f64> =
                            model.groups.iter().map(|g| step_factor(&g.kernel, h, bdf)).collect();
                        let entry = |p: usize| -> f64 {
                            model.groups.iter().zip(&coefficients).map(|(g, c)| c * g.stiffness[p]).sum::<f64>()
                        };
                        let mut eliminate = |hash: u64, held: &[(usize, f64)]| {
                            let pattern = &model.pattern;
                            let mut cut = vec![false; u.len()];
                            held.iter().for_each(|&(dof, _)| cut[dof] = true);
                            let key = (true, hash, step_key);
                            let mut contact_factor = contact_factor.borrow_mut();
                            if contact_factor.as_ref().map(|(k, _)| *k) != Some(key) {
                                *contact_factor = None;
                                let terms: Vec<(f64, &[f64])> = model
                                    .groups
                                    .iter()
                                    .zip(&coefficients)
                                    .map(|(g, &c)| (if single_group { 1.0 } else { c }, g.stiffness.as_slice()))
                                    .collect();
                                let factor = system
                                    .factor_decoupled(&terms, &cut, None)
                                    .map_err(|e| model.singular(step_index + 1, t1, e))?;
                                factorizations.set(factorizations.get() + 1);
                                refactored.set(true);
                                *contact_factor = Some((key, factor));
                            }
                            let factor = &contact_factor.as_ref().expect("set above").1;
                            solves.set(solves.get() + 1);
                            let mut next = u.clone();
                            let mut rhs = b.to_vec();
                            for &(dof, v) in held {
                                next[dof] = v;
                                // The matrix is symmetric: column `dof` is row `dof`.
                                for p in pattern.row_ptr[dof]..pattern.row_ptr[dof + 1] {
                                    rhs[pattern.col_idx[p] as usize] -= entry(p) * v;
                                }
                            }
                            let mut x: Vec<f64> = system
                                .dof_of_free
                                .iter()
                                .map(|&d| if cut[d as usize] { 0.0 } else { rhs[d as usize] })
                                .collect();
                            factor.solve_in_place(&mut x);
                            for (i, &d) in system.dof_of_free.iter().enumerate() {
                                if !cut[d as usize] {
                                    next[d as usize] = x[i] / single_scale;
                                }
                            }
                            // `b` holds the held dofs' coupling already: sum the free columns.
                            let reactions = held
                                .iter()
                                .map(|&(dof, _)| {
                                    (pattern.row_ptr[dof]..pattern.row_ptr[dof + 1])
                                        .filter(|&p| system.free_of_dof[pattern.col_idx[p] as usize] != u32::MAX)
                                        .map(|p| entry(p) * next[pattern.col_idx[p] as usize])
                                        .sum::<f64>()
                                        - b[dof]
                                })
                                .collect();
                            Ok((next, reactions))
                        };
                        let state0 = contact_state.as_ref().expect("contact runs have a state");
                        // Start from the last step's displacement (the held dofs at their new values).
                        let mut start = u.clone();
                        for &d in &system.dof_of_free {
                            start[d as usize] = state.u[d as usize];
                        }
                        let s = cm.settle(&input, state0, start, &mut inner, &mut eliminate, model.pattern.nnz())?;
                        *u = s.u.clone();
                        let forces = s.forces.clone();
                        settled = Some(s);
                        Ok(Some(forces))
                    };
                    step(&model, &state, h, bdf, t1, constraints, system, &mut solve, ga, dynamic, step_index + 1, None)
                }?;
                let mut settled = settled.expect("a contact step solves at least once");
                if outcome.contact_scale != 1.0 {
                    settled.scale_forces(outcome.contact_scale);
                }
                if let Some(r) = outcome.imbalance.as_ref() {
                    cm.rebalance(&mut settled, r);
                }
                Ok((outcome, settled))
            };
            let taken = match compliance {
                Some(c) if cm.crosshead_engaged(t1) => {
                    let mut measured = |lift: f64| {
                        let (o, s) = take(lift)?;
                        let force = cm.crosshead_force(&s.samples);
                        Ok(((o, s), force))
                    };
                    deflected_step(&mut measured, deflection, c, deflection_tol, step_index + 1, t1)
                }
                _ => take(0.0).map(|x| (x, 0.0)),
            };
            num_factorizations += factorizations.get();
            contact_solves += solves.get();
            taken.map(|((o, s), lift)| (o, refactored.get(), Some(s), lift))
        } else {
            // Numeric factor for this constraint set and step size.
            let key =
                (constraints.plate_attached, if single_group { (0, 0) } else { (h.to_bits(), bdf.alpha[0].to_bits()) });
            let refactored = if let Some(pos) = cache.iter().position(|(k, _)| *k == key) {
                let entry = cache.remove(pos);
                cache.push(entry);
                false
            } else {
                let terms: Vec<(f64, &[f64])> = model
                    .groups
                    .iter()
                    .map(|g| {
                        let c = if single_group { 1.0 } else { (1.0 - ga.alpha_f) * step_factor(&g.kernel, h, bdf) };
                        (c, g.stiffness.as_slice())
                    })
                    .collect();
                let mass_term: Option<Vec<f64>> =
                    dynamic.then(|| model.mass.iter().map(|m| m * (1.0 - ga.alpha_m) / (ga.beta * h * h)).collect());
                let factor =
                    system.factor(&terms, mass_term.as_deref()).map_err(|e| model.singular(step_index + 1, t1, e))?;
                num_factorizations += 1;
                if cache.len() >= CACHE_SIZE {
                    cache.remove(0);
                }
                cache.push((key, factor));
                true
            };
            let factor = &cache.last().unwrap().1;

            let single_scale = if single_group { step_factor(&model.groups[0].kernel, h, bdf) } else { 1.0 };
            let mut solve = plain_solve(system, factor, single_scale);
            let mut take = |plate_d: Option<f64>| {
                step(&model, &state, h, bdf, t1, constraints, system, &mut solve, ga, dynamic, step_index + 1, plate_d)
            };
            let d_cmd = protocol.displacement(t1);
            match compliance {
                // The linear step: exact in closed form.
                Some(c) if constraints.plate_attached && model.point.is_none() => {
                    compliant_step(&mut take, d_cmd, model.displacement_scale, c)
                }
                // The material-point path: the scalar iteration on the deflection.
                Some(c) if constraints.plate_attached => {
                    let mut measured = |lift: f64| {
                        let o = take(Some(d_cmd - lift))?;
                        let force = o.segment.eval_end()[1];
                        Ok((o, force))
                    };
                    deflected_step(&mut measured, deflection, c, deflection_tol, step_index + 1, t1)
                }
                _ => take(None).map(|o| (o, 0.0)),
            }
            .map(|(o, lift)| (o, refactored, None, lift))
        };
        // A failed step is retried from its old state at a quarter of its length,
        // never below the least step (module doc, "Retries"): there the failure is the run's error.
        let retry = settings.step_ends_s.is_none() && h / 4.0 >= dt_min;
        let (mut outcome, refactored, settled, lift) = match stepped {
            Ok(x) => x,
            Err(PressError::ContactNotSettled { .. }) if contact_retries < 3 && retry => {
                // Retry at a quarter of the step before giving up.
                contact_retries += 1;
                dt = h / 4.0;
                continue;
            }
            Err(PressError::NotConverged { .. } | PressError::DeflectionNotConverged { .. })
                if point_retries < 3 && retry =>
            {
                // Retry from the old state at a quarter of the step.
                point_retries += 1;
                dt = h / 4.0;
                continue;
            }
            Err(PressError::Inverted { .. }) if point_retries < 3 && retry && model.point.is_some() => {
                // On the material-point path a step too long for a strong effect may end on
                // an inverted cell (strong stiffening as a tool lifts off); retried as above.
                point_retries += 1;
                dt = h / 4.0;
                continue;
            }
            Err(e) => return Err(e),
        };
        contact_retries = 0;
        point_retries = 0;
        num_factorizations += outcome.factorizations;
        if let Some(settled) = settled.as_ref() {
            let plate: f64 = settled
                .samples
                .iter()
                .zip(&problem.tools)
                .filter(|(_, tool)| !tool.floor)
                .map(|(s, _)| s.force_n[1])
                .sum();
            let start = segments.last().map_or(0.0, |l: &ForceSegment| l.eval(l.dt)[1]);
            outcome.segment.plate_ends = Some([start, plate]);
            // No tool touched the specimen at either end: the reactions are fixed by
            // equilibrium at the ends, so interpolate them (as for a released plate).
            let before = tool_tracks.iter().any(|t| t.samples.last().is_some_and(ToolSample::touches));
            let after = settled.samples.iter().any(ToolSample::touches);
            if !before && !after {
                let start = segments.last().map_or([0.0; 2], |l: &ForceSegment| l.eval(l.dt));
                outcome.segment.detached_ends = Some([start, outcome.segment.eval_formula(h)]);
            }
        }
        // Finite strain: the reactions are exact at the step ends only (the
        // functional moves with the deformation), so interpolate between them.
        if !constraints.plate_attached || model.finite.is_some_and(|b| b != 0.0) {
            let start = segments.last().map_or([0.0; 2], |l: &ForceSegment| l.eval(l.dt));
            outcome.segment.detached_ends = Some([start, outcome.segment.eval_formula(h)]);
        }
        if let (false, Some(last)) = (bdf == Bdf::ONE, segments.last()) {
            // Continue the viscous rate from the previous step's end (no kink here).
            let last: &ForceSegment = last;
            for (t, l) in outcome.segment.terms.iter_mut().zip(&last.terms) {
                t.rate_start = l.rate_end;
            }
        }
        let solve_s = clock.elapsed().as_secs_f64();

        // Error control: quadratic extrapolation for BDF2 steps (local error about
        // 2/11 of the difference, exponent 1/3), linear for BDF1 ones (exponent 1/2).
        let adaptive = settings.fixed_dt_s.is_none() && settings.step_ends_s.is_none();
        let (error_ratio, exponent) = if !adaptive {
            (0.0, 0.5)
        } else {
            match (back.first(), back.get(1)) {
                (Some((u1b, _, h0)), Some((u2b, _, hm))) if bdf != Bdf::ONE => {
                    let (t0, tm1, tm2) = (state.t, state.t - h0, state.t - h0 - hm);
                    let tt = t1;
                    let l0 = (tt - tm1) * (tt - tm2) / ((t0 - tm1) * (t0 - tm2));
                    let l1 = (tt - t0) * (tt - tm2) / ((tm1 - t0) * (tm1 - tm2));
                    let l2 = (tt - t0) * (tt - tm1) / ((tm2 - t0) * (tm2 - tm1));
                    let mut e: f64 = 0.0;
                    for &d in &system.dof_of_free {
                        let d = d as usize;
                        let pred = l0 * state.u[d] + l1 * u1b[d] + l2 * u2b[d];
                        e = e.max((outcome.state.u[d] - pred).abs());
                    }
                    (e * 2.0 / 11.0 / tol, 1.0 / 3.0)
                }
                (Some((u1b, _, h0)), _) => {
                    let w = h / h0;
                    let mut e: f64 = 0.0;
                    for &d in &system.dof_of_free {
                        let d = d as usize;
                        let pred = state.u[d] + w * (state.u[d] - u1b[d]);
                        e = e.max((outcome.state.u[d] - pred).abs());
                    }
                    (e * h / (h + h0) / tol, 0.5)
                }
                _ => (0.0, 0.5),
            }
        };
        // The inelastic flow (module doc): the linear predictor, whose difference
        // `h (rate1 - rate0)` is twice backward Euler's local error; exponent 1/2.
        let flow_ratio = match back.first() {
            Some((_, i1b, h0)) if adaptive && !flow_weight.is_empty() => {
                let w = h / h0;
                let mut sum = 0.0;
                for (c, &weight) in flow_weight.iter().enumerate() {
                    if weight > 0.0 {
                        let c1 = &model.region_c1[problem.mesh.cell_regions[c] as usize];
                        let now = state.measured_flow(c);
                        let pred = now + (now - i1b[c]) * w;
                        let d = outcome.state.measured_flow(c) - pred;
                        sum += weight * d.dot(&(c1 * d)).max(0.0);
                    }
                }
                0.5 * sum.sqrt() / flow_tol
            }
            _ => 0.0,
        };
        let (error_ratio, exponent) =
            if flow_ratio > error_ratio { (flow_ratio, 0.5) } else { (error_ratio, exponent) };
        if error_ratio > 1.0 {
            dt = h * (0.9 * error_ratio.powf(-exponent)).clamp(0.1, 0.7);
            if dt < dt_min {
                return Err(PressError::StepTooSmall { step: step_index + 1, time_s: state.t, dt_s: dt });
            }
            continue;
        }

        // Accept.
        step_index += 1;
        deflection = lift;
        let [bottom_force_n, plate_force_n] = outcome.segment.eval_end();
        outcome.state.force_scale = state.force_scale.max(bottom_force_n.abs()).max(plate_force_n.abs());
        steps.push(StepRecord {
            t_s: t1,
            dt_s: h,
            solve_s,
            residual: outcome.residual,
            refactored,
            bottom_force_n,
            plate_force_n,
            error_ratio,
            newton_iterations: 0,
        });
        if let Some(tracker) = tracker.as_mut() {
            let view = StepView {
                t0: state.t,
                dt: h,
                alpha: bdf.alpha,
                strain0: &state.strain,
                strain_prev0: &state.strain_prev,
                history0: &state.history,
                strain1: &outcome.state.strain,
                u1: &outcome.state.u,
                plate_dofs: &constraints.plate_dofs,
                system,
                factor: &cache.last().expect("a step without contact keeps its factor").1,
                single_group_factor: single_group.then(|| step_factor(&model.groups[0].kernel, h, bdf)),
                continues: bdf != Bdf::ONE && !segments.is_empty(),
                segment: &outcome.segment,
            };
            tracker.advance(&model, &view);
        }
        segments.push(outcome.segment);
        if let Some(settled) = settled {
            let keep_nodes = schedule.is_snapshot(t1, end);
            for (track, mut sample) in tool_tracks.iter_mut().zip(settled.samples) {
                if !keep_nodes {
                    sample.nodes = Vec::new();
                }
                track.samples.push(sample);
            }
            contact_state = Some(settled.state);
        }
        emit_markers(&model, &mut tracks, &mut marker_next, &state.u, &outcome.state.u, state.t, t1, false);
        if schedule.is_snapshot(t1, end) {
            snapshots.push(Snapshot {
                t_s: t1,
                displacement: model.reported(&outcome.state.u, t1),
                cell_stress: outcome.stress.iter().flat_map(|s| s.iter().copied()).collect(),
            });
        }
        // A material with no instantaneous viscosity (B2 = 0) jumps elastically when
        // the plate lets go: that jump is taken as its own near-zero step (a strain
        // linear over a whole step cannot represent it), after which the segment
        // starts afresh.
        let at_kink = physical_kinks.iter().any(|&k| (k - t1).abs() <= 1e-12 * end.max(1.0)) || instant_step;
        let releasing = (t1 - protocol.release_s).abs() <= 1e-12 * end.max(1.0) && t1 < end;
        instant_step = releasing && !instant_step && model.region_kernel.iter().any(|k| k.viscous == 0.0);
        let mut old = std::mem::replace(&mut state, outcome.state);
        if at_kink {
            back.clear();
            dt = if instant_step { INSTANT_STEP_FRACTION * end } else { first_dt(t1) };
        } else {
            dt = match settings.fixed_dt_s {
                Some(f) => f,
                None if back.is_empty() => MAX_GROWTH * h,
                None => {
                    // BDF2 needs dt/dt_prev <= 2; grow faster only where the error is
                    // negligible (a strain linear in time: any scheme is exact there).
                    let cap = if error_ratio < EXACT_RATIO { MAX_GROWTH } else { 2.0 };
                    h * (0.9 * error_ratio.max(1e-12).powf(-exponent)).clamp(0.2, cap)
                }
            };
            let u_old = std::mem::take(&mut old.u);
            let flow = if flow_weight.is_empty() { Vec::new() } else { old.measured_flows() };
            back.insert(0, (u_old, flow, h));
            back.truncate(2);
        }
        progress(Progress { t_s: state.t, end_s: end, steps: step_index });
        // Read only between steps: a run never cancelled takes the same steps.
        if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(PressError::Cancelled { step: step_index, time_s: state.t });
        }
    }

    Ok((
        PressResult {
            dim: D,
            num_stress: S,
            steps,
            snapshots,
            markers: tracks,
            num_factorizations,
            contact_solves,
            factor_nonzeros: sys_attached
                .factor_nonzeros()
                .max(sys_released.as_ref().map_or(0, |s| s.factor_nonzeros())),
            num_free_dofs: sys_attached.num_free().max(sys_released.as_ref().map_or(0, |s| s.num_free())),
            segments,
            tools: tool_tracks,
            force_offset: None,
        },
        tracker.map(Tracker::finish),
    ))
}

fn check_settings(s: &Settings) -> Result<(), PressError> {
    if !(0.0..=1.0).contains(&s.rho_inf) {
        return Err(PressError::BadSettings(format!("rho_inf = {} must lie in [0, 1]", s.rho_inf)));
    }
    if !(s.rtol.is_finite() && s.rtol > 0.0) {
        return Err(PressError::BadSettings(format!("rtol = {} must be > 0", s.rtol)));
    }
    if let Some(r) = s.flow_rtol {
        if !(r.is_finite() && r > 0.0) {
            return Err(PressError::BadSettings(format!("flow rtol = {r} must be > 0")));
        }
    }
    for (name, v) in [("fixed dt", s.fixed_dt_s), ("max dt", s.max_dt_s)] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                return Err(PressError::BadSettings(format!("{name} = {v} s must be > 0")));
            }
        }
    }
    Ok(())
}

/// Solves a step's free rows: given the right-hand side per dof (the held dofs'
/// coupling already subtracted; valid on the free rows) and the displacement with
/// its held values, writes the free values; returns the contact forces on the
/// specimen per dof, if any.
pub(crate) type FreeSolve<'a> = dyn FnMut(&[f64], &mut Vec<f64>) -> Result<Option<Vec<f64>>, PressError> + 'a;

/// The plain solve: one triangular solve pair with the step's factorization.
fn plain_solve<'a>(
    system: &'a ReducedSystem,
    factor: &'a Factor<'a>,
    scale: f64,
) -> impl FnMut(&[f64], &mut Vec<f64>) -> Result<Option<Vec<f64>>, PressError> + 'a {
    move |b: &[f64], u: &mut Vec<f64>| {
        let mut x: Vec<f64> = system.dof_of_free.iter().map(|&d| b[d as usize]).collect();
        factor.solve_in_place(&mut x);
        for (i, &d) in system.dof_of_free.iter().enumerate() {
            u[d as usize] = x[i] / scale;
        }
        Ok(None)
    }
}

struct StepOutcome<const S: usize> {
    state: State<S>,
    stress: Vec<SVector<f64, S>>,
    segment: ForceSegment,
    residual: f64,
    /// With contact: what the free rows leave unbalanced, `A u - b - F_contact`
    /// (the multipliers' rounding), per dof; zero on held rows.
    imbalance: Option<Vec<f64>>,
    /// Factorizations the step made itself (the material-point path's tangents).
    factorizations: usize,
    /// The factor the last contact solve's forces are to be multiplied by (the
    /// material-point iteration's scaled operator; 1 otherwise).
    contact_scale: f64,
}

impl ForceSegment {
    fn eval_end(&self) -> [f64; 2] {
        self.eval(self.dt)
    }
}

#[allow(clippy::too_many_arguments)]
fn step<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    s0: &State<S>,
    dt: f64,
    bdf: Bdf,
    t1: f64,
    constraints: &Constraints,
    system: &ReducedSystem,
    solve: &mut FreeSolve<'_>,
    ga: GeneralizedAlpha,
    dynamic: bool,
    step_index: usize,
    plate_d: Option<f64>,
) -> Result<StepOutcome<S>, PressError>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mesh = &model.problem.mesh;
    let factors: Vec<StepFactors> = model
        .region_kernel
        .iter()
        .map(|k| {
            let g = step_factor(k, dt, bdf);
            let mut decay = [0.0; 2];
            let mut phi = [0.0; 2];
            for j in 0..k.num_terms {
                decay[j] = (-k.rates[j] * dt).exp();
                phi[j] = phi1(k.rates[j] * dt);
            }
            StepFactors { g, g_mean: k.mean_factor(dt), decay, phi }
        })
        .collect();

    // The history part q of the stress at t1 = C1 [g e1 - q]:
    // q = B2 (alpha1 e0 - alpha2 e_-1)/dt + sum_k a_k (phi_k e0 - decay_k h_k).
    let history_part = |e: usize| -> SVector<f64, S> {
        let r = mesh.cell_regions[e] as usize;
        let (k, f) = (&model.region_kernel[r], &factors[r]);
        let mut q = (s0.strain[e] * bdf.alpha[1] - s0.strain_prev[e] * bdf.alpha[2]) * (k.viscous / dt);
        for j in 0..k.num_terms {
            q += (s0.strain[e] * f.phi[j] - s0.history[e][j] * f.decay[j]) * k.amplitudes[j];
        }
        q
    };
    // History force: f_hist = sum_e w B^T C1 q.
    let cell_forces: Vec<[SVector<f64, D>; N]> = map_collect(mesh.num_cells(), |e| {
        let r = mesh.cell_regions[e] as usize;
        let sigma = model.region_c1[r] * history_part(e);
        std::array::from_fn(|a| nodal_force::<D, N, S>(&model.geometry[e], &sigma, a))
    });
    let ndof = model.num_dofs();
    let mut f_hist = vec![0.0; ndof];
    assemble_vector::<D, N>(&model.topology, &cell_forces, &mut f_hist);
    drop(cell_forces);
    // Right-hand side: f_body + (1 - af) f_hist - af f_int,n + inertia terms.
    let (am, af) = (ga.alpha_m, ga.alpha_f);
    let inv_bdt2 = 1.0 / (ga.beta * dt * dt);
    let mut rhs: Vec<f64> = (0..ndof).map(|d| model.body_force[d] + (1.0 - af) * f_hist[d]).collect();
    if dynamic {
        for d in 0..ndof {
            let newmark = inv_bdt2 * (s0.u[d] + dt * s0.v[d]) + (0.5 / ga.beta - 1.0) * s0.a[d];
            rhs[d] += model.mass[d] * ((1.0 - am) * newmark - am * s0.a[d]) - af * s0.f_int[d];
        }
    }

    // Held values, then the coupling of held dofs into the free rows.
    let mut u1 = vec![0.0; ndof];
    model.prescribe(constraints, t1, &mut u1);
    // The plate's displacement when it is not the protocol's (machine compliance).
    if let Some(d) = plate_d {
        for &dof in &constraints.plate_dofs {
            u1[dof] = -d;
        }
    }
    // `stiffness_only` gives sum_g g_g K_g x, the elastic part of the internal force.
    let stiffness_only = |x: &[f64], y: &mut [f64]| {
        let mut tmp = vec![0.0; ndof];
        y.iter_mut().for_each(|v| *v = 0.0);
        for g in &model.groups {
            model.pattern.mul_vec(&g.stiffness, x, &mut tmp);
            let c = step_factor(&g.kernel, dt, bdf);
            for (yi, ti) in y.iter_mut().zip(&tmp) {
                *yi += c * ti;
            }
        }
    };
    // `apply` is the step matrix: (1 - af) sum_g g_g K_g + (1 - am) M / (beta dt^2).
    let apply = |x: &[f64], y: &mut [f64]| {
        stiffness_only(x, y);
        for d in 0..ndof {
            y[d] *= 1.0 - af;
            if dynamic {
                y[d] += model.mass[d] * (1.0 - am) * inv_bdt2 * x[d];
            }
        }
    };
    let mut coupling = vec![0.0; ndof];
    apply(&u1, &mut coupling);
    let base: Vec<f64> = (0..ndof).map(|d| rhs[d] - coupling[d]).collect();
    // The history part of the chain's mean stress over the step, where a law
    // corrects the dashpot on it (`crate::material`'s module doc): `tau_mean =
    // g_mean e1 - q_mean`, `q_mean = (g_mean - G_inf) e0 - sum_k a_k phi_k h_k`.
    let q_mean: Vec<SVector<f64, S>> = if s0.chain_flow.is_empty() {
        Vec::new()
    } else {
        map_collect(mesh.num_cells(), |e| {
            let r = mesh.cell_regions[e] as usize;
            let (k, f) = (&model.region_kernel[r], &factors[r]);
            let mut q = s0.strain[e] * (f.g_mean - k.equilibrium);
            for j in 0..k.num_terms {
                q -= s0.history[e][j] * (f.phi[j] * k.amplitudes[j]);
            }
            q
        })
    };
    let g_mean: Vec<f64> = if q_mean.is_empty() { Vec::new() } else { factors.iter().map(|f| f.g_mean).collect() };
    // The material-point path: the same step with an inelastic strain per cell,
    // solved by the iteration of `super::inelastic`.
    let mut point = match model.point.as_ref() {
        None => None,
        Some(_) => {
            let q: Vec<SVector<f64, S>> = map_collect(mesh.num_cells(), history_part);
            let g: Vec<f64> = factors.iter().map(|f| f.g).collect();
            let scale = system
                .dof_of_free
                .iter()
                .map(|&d| rhs[d as usize].powi(2) + coupling[d as usize].powi(2))
                .sum::<f64>()
                .sqrt();
            let input = PointInput {
                g: &g,
                q: &q,
                g_mean: &g_mean,
                q_mean: &q_mean,
                chain0: &s0.strain,
                inelastic0: &s0.inelastic,
                unloading0: &s0.unloading,
                history0: &s0.damage_history,
                base: &base,
                scale,
                run_scale: s0.force_scale,
                dt,
                t1,
                step: step_index,
                contact: !model.problem.tools.is_empty(),
            };
            Some(inelastic::solve_step(model, &input, system, solve, &mut u1)?)
        }
    };
    let external = match point.as_mut() {
        Some(p) => p.contact_forces.take(),
        None => solve(&base, &mut u1)?,
    };
    for &d in &system.dof_of_free {
        let d = d as usize;
        if !u1[d].is_finite() {
            let node = d / D;
            return Err(PressError::NonFinite {
                step: step_index,
                time_s: t1,
                element: model.cell_of_node(node).unwrap_or(usize::MAX),
                node,
            });
        }
    }
    // Contact forces are external forces on the free rows.
    let with_contact = external.is_some();
    if let Some(f) = external.as_ref() {
        rhs.iter_mut().zip(f).for_each(|(r, f)| *r += f);
    }
    // Residual of the free rows.
    let mut y = vec![0.0; ndof];
    apply(&u1, &mut y);
    // Relative to the size of the terms that balance on the free rows: the history
    // right-hand side and the held dofs' coupling (each may vanish alone, e.g. both
    // the history and A u1 are zero at the start of a push).
    let (mut rr, mut bb) = (0.0, 0.0);
    for &d in &system.dof_of_free {
        let d = d as usize;
        rr += (y[d] - rhs[d]).powi(2);
        bb += rhs[d].powi(2) + coupling[d].powi(2);
    }
    let residual = match point.as_ref() {
        Some(p) => p.residual,
        None if bb > 0.0 => (rr / bb).sqrt(),
        None => 0.0,
    };
    // On the material-point path the free rows' balance is that of the cells'
    // nodal forces (`f_int(u1) - f_body`, from the iteration) against the contact
    // forces; `rhs` holds those already.
    let imbalance = with_contact.then(|| {
        let mut r = vec![0.0; ndof];
        for &d in &system.dof_of_free {
            let d = d as usize;
            r[d] = match (point.as_ref(), external.as_ref()) {
                (Some(p), Some(f)) => p.out_of_balance[d] - f[d],
                _ => y[d] - rhs[d],
            };
        }
        r
    });

    // Cell update: strain, exact history, stress, inversion check.
    let updated: Vec<CellUpdate<S>> = map_collect(mesh.num_cells(), |e| {
        let r = mesh.cell_regions[e] as usize;
        let (k, f) = (&model.region_kernel[r], &factors[r]);
        let ue = model.cell_displacements(e, &u1);
        // The small strain, or the finite-strain effect's blended Green-Lagrange strain.
        let e1 = model.strain_of(e, &ue);
        // The chain's strain on the material-point path.
        let e1 = match point.as_ref() {
            Some(p) => e1 - p.inelastic[e],
            None => e1,
        };
        let de = e1 - s0.strain[e];
        let mut h1 = [SVector::<f64, S>::zeros(); 2];
        for j in 0..k.num_terms {
            h1[j] = s0.history[e][j] * f.decay[j] + de * f.phi[j];
        }
        let stress = model.region_c1[r] * (e1 * f.g - history_part(e));
        (e1, h1, stress, model.volume_ratio(e, &ue))
    });
    if let Some((e, ratio)) = updated.iter().enumerate().map(|(e, x)| (e, x.3)).find(|(_, r)| !(*r > 0.0)) {
        return Err(PressError::Inverted { step: step_index, time_s: t1, element: e, ratio });
    }

    // Reaction functionals for exact dense force output.
    let nreg = model.region_kernel.len();
    let mut terms: Vec<RegionTerms> = (0..nreg)
        .map(|r| RegionTerms {
            kernel: model.region_kernel[r],
            rate: [0.0; 2],
            rate_end: [0.0; 2],
            rate_start: [0.0; 2],
            strain: [0.0; 2],
            history: [[0.0; 2]; 2],
            plate_attached: constraints.plate_attached,
        })
        .collect();
    for (side, list) in model.functionals.iter().enumerate() {
        for f in list {
            let r = mesh.cell_regions[f.cell] as usize;
            let c: &SMatrix<f64, S, S> = &model.region_c1[r];
            // The deformed functional on the finite-strain path (`f.rho` otherwise).
            let rc = c * model.functional_at(f, &u1); // C1 symmetric: rho . (C1 x) = (C1 rho) . x
            let t = &mut terms[r];
            let e1 = &updated[f.cell].0;
            t.rate[side] += rc.dot(&(e1 - s0.strain[f.cell])) / dt;
            t.rate_end[side] += rc
                .dot(&(e1 * bdf.alpha[0] - s0.strain[f.cell] * bdf.alpha[1] + s0.strain_prev[f.cell] * bdf.alpha[2]))
                / dt;
            t.strain[side] += rc.dot(&s0.strain[f.cell]);
            for j in 0..t.kernel.num_terms {
                t.history[j][side] += rc.dot(&s0.history[f.cell][j]);
            }
        }
    }
    for t in &mut terms {
        t.rate_start = t.rate;
    }
    let segment = ForceSegment {
        t0: s0.t,
        dt,
        terms,
        constant: [model.body_reaction[0], if constraints.plate_attached { model.body_reaction[1] } else { 0.0 }],
        detached_ends: None,
        plate_ends: None,
    };

    // Dynamic state update (held dofs move with the plate at constant velocity).
    let (mut v1, mut a1) = (vec![0.0; ndof], vec![0.0; ndof]);
    let mut f_int = Vec::new();
    if dynamic {
        for &d in &system.dof_of_free {
            let d = d as usize;
            a1[d] = inv_bdt2 * (u1[d] - s0.u[d] - dt * s0.v[d]) - (0.5 / ga.beta - 1.0) * s0.a[d];
            v1[d] = s0.v[d] + dt * ((1.0 - ga.gamma) * s0.a[d] + ga.gamma * a1[d]);
        }
        f_int = vec![0.0; ndof];
        stiffness_only(&u1, &mut f_int);
        f_int.iter_mut().zip(&f_hist).for_each(|(f, h)| *f -= h);
        let vel = model.problem.protocol.velocity(0.5 * (s0.t + t1));
        for &d in &constraints.plate_dofs {
            v1[d] = -vel;
        }
    }

    // The chain's own dashpot flow over the step, `dt tau_mean/c3`, where the law
    // corrects the dashpot on the mean stress (`State::chain_flow`).
    let chain_flow: Vec<SVector<f64, S>> = match model.point.as_ref() {
        Some(laws) if !q_mean.is_empty() => (0..mesh.num_cells())
            .map(|e| {
                let r = mesh.cell_regions[e] as usize;
                match laws[r].mean_corrected_c3() {
                    Some(c3) => s0.chain_flow[e] + (updated[e].0 * g_mean[r] - q_mean[e]) * (dt / c3),
                    None => s0.chain_flow[e],
                }
            })
            .collect(),
        _ => Vec::new(),
    };
    let mut strain = Vec::with_capacity(updated.len());
    let mut history = Vec::with_capacity(updated.len());
    let mut stress = Vec::with_capacity(updated.len());
    for (e1, h1, s1, _) in updated {
        strain.push(e1);
        history.push(h1);
        stress.push(s1);
    }
    let strain_prev = s0.strain.clone();
    let (inelastic, unloading, damage_history, factorizations, contact_scale) = match point {
        Some(p) => (p.inelastic, p.unloading, p.history, p.factorizations, p.operator),
        None => (Vec::new(), Vec::new(), Vec::new(), 0, 1.0),
    };
    Ok(StepOutcome {
        state: State {
            t: t1,
            u: u1,
            v: v1,
            a: a1,
            strain,
            strain_prev,
            history,
            f_int,
            inelastic,
            unloading,
            damage_history,
            // The stepper raises it to this step's forces once the step is accepted.
            force_scale: s0.force_scale,
            chain_flow,
        },
        stress,
        segment,
        residual,
        imbalance,
        factorizations,
        contact_scale,
    })
}

/// A step with the plate behind a series spring of compliance `c` [mm/N]: the
/// plate displacement `d` that satisfies `d = d_cmd - c F(d)`, `F` the plate force
/// at the step's end. The step is affine in `d`, so two steps (at `d_cmd` and
/// `d_cmd - delta`, one factorization) give `F(d) = F(d_cmd) + k (d - d_cmd)`, the
/// relation gives `d = d_cmd - c F(d_cmd) / (1 + c k)` in closed form, and a third
/// step takes it there (every state variable that of the exact step).
/// Returns the step and the machine's deflection `d_cmd - d` [mm].
fn compliant_step<const S: usize>(
    take: &mut dyn FnMut(Option<f64>) -> Result<StepOutcome<S>, PressError>,
    d_cmd: f64,
    delta: f64,
    c: f64,
) -> Result<(StepOutcome<S>, f64), PressError> {
    let f_cmd = take(Some(d_cmd))?.segment.eval_end()[1];
    let f_probe = take(Some(d_cmd - delta))?.segment.eval_end()[1];
    let k = (f_cmd - f_probe) / delta;
    let deflection = c * f_cmd / (1.0 + c * k);
    take(Some(d_cmd - deflection)).map(|o| (o, deflection))
}

/// The tolerance of the deflection's scalar iteration on its residual `delta - c
/// F`, relative to the displacement scale: the force's error is then at most the
/// residual times `min(k, 1/c)` (`k` the step's stiffness against the
/// deflection), at most this fraction of the peak force on the plate, and far
/// less on a soft machine.
pub(super) const DEFLECTION_RTOL: f64 = 1e-11;
/// Evaluations of the deflection's scalar iteration before a step counts as not
/// converged (a step affine in the deflection takes three; the bracket halves at
/// least every third evaluation).
const DEFLECTION_ITERATIONS: usize = 150;

/// A step behind a series spring of compliance `c` [mm/N] whose step is not
/// affine in the deflection (the material-point path; contact tools): the
/// deflection `delta` [mm] that solves `r(delta) = delta - c F(delta) = 0`, `F`
/// the force the machine measures at the step's end with the tools (or the
/// plate) held back by `delta`. `take(delta)` takes the step and returns it
/// with that force.
///
/// Where the force does not grow as the tools back off (`F' <= 0`; not on
/// adhesion's softening branch, which pulls harder as the bond opens and ends
/// here as [`PressError::DeflectionNotConverged`], see `fem-core/tests/compliance.rs`),
/// `r' >= 1`: one root, and `delta_0` (the last step's deflection) and `delta_1 = c F(delta_0)`
/// bracket it (`r(delta_1) = c (F(delta_0) - F(delta_1))` has the sign opposite to
/// `r(delta_0) = delta_0 - delta_1`). Illinois (regula falsi halving the weight of
/// a side kept twice) then closes the bracket superlinearly: an affine step takes
/// three evaluations (the bracket, then the root), as the closed form does. `F`
/// has kinks where the contact set changes: a tool that just touches (the
/// first step of a push, whose viscous force is steep) leaves `r` piecewise
/// affine with slopes `1 + c k` and `1`, on which regula falsi creeps; so the
/// bracket is bisected whenever two evaluations have not halved it.
/// Converged at `|r| <= tol`, or when the bracket cannot shrink further in
/// floating point (the end with the smaller residual). A force that grows as the
/// tools back off (no sign change), or no convergence in
/// [`DEFLECTION_ITERATIONS`] evaluations, is [`PressError::DeflectionNotConverged`]
/// (the step is then retried shorter; a step's own failure inside an evaluation
/// is returned as it is, e.g. the material-point iteration's `NotConverged`). Every state variable is that of the step
/// taken at the returned deflection.
pub(super) fn deflected_step<T>(
    take: &mut dyn FnMut(f64) -> Result<(T, f64), PressError>,
    guess: f64,
    c: f64,
    tol: f64,
    step: usize,
    t1: f64,
) -> Result<(T, f64), PressError> {
    let not_converged = |detail: String| PressError::DeflectionNotConverged { step, time_s: t1, detail };
    let (outcome, force) = take(guess)?;
    let r = guess - c * force;
    if r.abs() <= tol {
        return Ok((outcome, guess));
    }
    // (deflection, residual, weighted residual, outcome) at the bracket's ends.
    let mut a = (guess, r, r, outcome);
    let next = c * force;
    let (outcome, force) = take(next)?;
    let r = next - c * force;
    if r.abs() <= tol {
        return Ok((outcome, next));
    }
    if r.signum() == a.1.signum() {
        return Err(not_converged(format!(
            "the measured force grows as the tools back off (deflection {:.6e} mm: residual {:.3e} mm; {next:.6e} mm: \
             {r:.3e} mm)",
            a.0, a.1
        )));
    }
    let mut b = (next, r, r, outcome);
    // The side replaced last: -1 for `a`, 1 for `b`.
    let mut side = 0;
    // The bracket's width when it last halved, and the evaluations since.
    let (mut halved_at, mut since) = ((b.0 - a.0).abs(), 0);
    for _ in 2..DEFLECTION_ITERATIONS {
        let x = if since >= 2 {
            since = 0;
            0.5 * (a.0 + b.0)
        } else {
            (a.0 * b.2 - b.0 * a.2) / (b.2 - a.2)
        };
        let (outcome, force) = take(x)?;
        let r = x - c * force;
        if r.abs() <= tol {
            return Ok((outcome, x));
        }
        if r.signum() == a.1.signum() {
            a = (x, r, r, outcome);
            if side == -1 {
                b.2 *= 0.5;
            }
            side = -1;
        } else {
            b = (x, r, r, outcome);
            if side == 1 {
                a.2 *= 0.5;
            }
            side = 1;
        }
        let width = (b.0 - a.0).abs();
        if width <= 0.5 * halved_at {
            (halved_at, since) = (width, 0);
        } else {
            since += 1;
        }
        if width <= 4.0 * f64::EPSILON * a.0.abs().max(b.0.abs()) {
            let best = if a.1.abs() <= b.1.abs() { a } else { b };
            return Ok((best.3, best.0));
        }
    }
    Err(not_converged(format!(
        "the deflection did not settle in {DEFLECTION_ITERATIONS} steps (bracket [{:.6e}, {:.6e}] mm, residuals {:.3e}, \
         {:.3e} mm)",
        a.0, b.0, a.1, b.1
    )))
}

/// Records marker positions at their requested times inside `(t0, t1]` (or at 0).
#[allow(clippy::too_many_arguments)]
pub(crate) fn emit_markers<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    tracks: &mut [MarkerTrack],
    next: &mut [usize],
    u0: &[f64],
    u1: &[f64],
    t0: f64,
    t1: f64,
    initial: bool,
) where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    if tracks.is_empty() {
        return;
    }
    let p0 = model.marker_positions(u0, t0);
    let p1 = model.marker_positions(u1, t1);
    for (m, req) in model.problem.markers.iter().enumerate() {
        while next[m] < req.times.len() {
            let t = req.times[next[m]];
            let inside = if initial { t <= 0.0 } else { t <= t1 * (1.0 + 1e-12) };
            if !inside {
                break;
            }
            let w = if initial || t1 <= t0 { 1.0 } else { ((t - t0) / (t1 - t0)).clamp(0.0, 1.0) };
            let pos = (0..D).map(|k| p0[m][k] + w * (p1[m][k] - p0[m][k])).collect();
            tracks[m].samples.push((t, pos));
            next[m] += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, Ordering};

    use crate::material::{Material, Rheology};
    use crate::mesh;
    use crate::press::{self, PlanePress, PressError, PressResult, Protocol, Settings};

    /// A 20 x 15 mm plane-stress block (10 mm thick, 5 mm elements) of a
    /// three-element chain, pushed 1.5 mm in 10 s and held to 60 s.
    fn block() -> PlanePress {
        let chain = Rheology::ThreeElement { e1_mpa: 0.05, c1_mpa_s: 0.2, c3_mpa_s: 20.0 };
        let protocol = Protocol::ramp_hold_release(0.15, 10.0, 60.0, 60.0);
        PlanePress::new_2d(
            mesh::rectangle(20.0, 15.0, 5.0, "m").unwrap(),
            10.0,
            vec![Material::new(chain, 0.3).unwrap()],
            protocol,
        )
        .unwrap()
    }

    /// The steps' times, lengths and forces and the snapshots, as bits.
    fn fingerprint(r: &PressResult) -> Vec<u64> {
        let steps = r.steps.iter().flat_map(|s| [s.t_s, s.dt_s, s.bottom_force_n, s.plate_force_n]);
        let shapes = r.snapshots.iter().flat_map(|s| s.displacement.iter().chain(&s.cell_stress).copied());
        steps.chain(shapes).map(f64::to_bits).collect()
    }

    /// A flag set during step 3 ends the run after that step, naming it and its
    /// end time; a flag never set changes nothing, bit for bit.
    #[test]
    fn a_cancel_flag_stops_the_run_between_steps() {
        let p = block();
        let settings = Settings::default();
        let full = press::simulate(&p, &settings, &mut |_| {}).unwrap();
        assert!(full.steps.len() > 5, "{} steps", full.steps.len());
        let cancel = AtomicBool::new(false);
        let kept = press::simulate_cancellable(&p, &settings, &cancel, &mut |_| {}).unwrap();
        assert_eq!(fingerprint(&kept), fingerprint(&full));
        let mut seen = 0;
        let err = press::simulate_cancellable(&p, &settings, &cancel, &mut |progress| {
            seen = progress.steps;
            if progress.steps == 3 {
                cancel.store(true, Ordering::Relaxed);
            }
        })
        .unwrap_err();
        assert_eq!(seen, 3, "no step after the cancel");
        match err {
            PressError::Cancelled { step, time_s } => {
                assert_eq!(step, 3);
                assert_eq!(time_s.to_bits(), full.steps[2].t_s.to_bits());
            }
            other => panic!("expected Cancelled, got {other}"),
        }
        assert!(err.to_string().starts_with("step 3 at t = ") && err.to_string().ends_with("cancelled between steps"));
    }
}
