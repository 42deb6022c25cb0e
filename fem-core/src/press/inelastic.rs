//! The global iteration of a quasi-static step on the material-point path
//! (effects E1 to E5, [`crate::effects`], and a material's Mullins-type damage,
//! [`crate::material::MullinsDamage`]; the local laws in
//! [`crate::material::InelasticLaw`]).
//!
//! With an inelastic strain `e_in` in series, the step's stress image per cell is
//! `tau1 = g (e1 - e_in1) - q`, so equilibrium reads `g K u1 = f_body + f_hist +
//! f_in(e_in1)` with `f_in = sum_e w B^T C1 g e_in`: the linear step with one more
//! right-hand side. The iteration:
//!
//! 1. *Modified Newton* with the step's own linear factorization `g K`: solve with
//!    `f_in` of the current inelastic strains, update every cell locally (radial
//!    return from `e_in0`, the step's start), recompute `f_in`. This is Newton's
//!    method with the chain's linear tangent; it needs no new factorization.
//! 2. When the residual falls by less than [`SLOW_CONTRACTION`] in an iteration
//!    (a strong effect: a slider with little hardening, a Bingham threshold at a
//!    large step), *full Newton*: assemble the consistent tangent
//!    `sum_e w B^T g C1 T_e B` (symmetric, [`crate::material`]'s laws are
//!    associative in the energy norm), factor it, and keep it while it reduces
//!    the residual tenfold an iteration ([`TANGENT_REUSE`]; refactored at the
//!    current state otherwise). If that factorization fails the modified
//!    iteration goes on.
//! 3. Every full-Newton step is *line-searched* ([`line_search`]): each law's
//!    update is monotone and associative (all but softening, strain stiffening
//!    with `a < 0`: [`line_search`]), so the residual is the gradient of a
//!    convex incremental potential of the displacements, and the step length is
//!    chosen where the potential's slope along the Newton direction has fallen to
//!    [`LINE_SEARCH_SLOPE`] of its size at the start (the full step whenever it
//!    qualifies, as it does near the solution). Without it, Newton's method on
//!    the piecewise-smooth slider diverged (the seed's material pushed at
//!    0.8 mm/s on 2.5 mm elements: every cell yields in the first step, the
//!    residual grew a hundredfold in tangent mode) or wandered between
//!    elastic and plastic cells.
//!
//! Converged when the free rows' residual `|f_int(u1) - f_body|` is at most
//! [`TOLERANCE`] of the force scale ("The force scale" below). Not converged after
//! [`MAX_ITERATIONS`], or a local update without a solution:
//! [`PressError::NotConverged`] naming the step, the time and the element (the
//! failing cell, or the one at the largest out-of-balance force), and the
//! stepper retries the step from its old state with a quarter of the step.
//!
//! ## The force scale
//! The step's own force scale is that of the linear step's residual (the norm
//! over the free rows of the right-hand side, body and history forces, and of
//! the held dofs' coupling), with the inelastic strains' own share `f_in(e_in0)`
//! and, with contact tools, the contact forces' share. The tolerance's scale is
//! the larger of that and the largest force the run has measured so far (the
//! magnitude of the plate or bottom force at the accepted step ends; the
//! stepper's state carries it; [`PointInput::reference`]). Why: the residual is
//! an out-of-balance force, and the error it leaves in a reported force is of
//! its own size; every accuracy the press reports or the tests assert is
//! relative to the run's peak force, so [`TOLERANCE`] times the largest force so
//! far bounds every step's error alike, loaded or not. (Not the largest own
//! scale so far: the own scale holds the viscous terms `B2 alpha0/dt` times the
//! strain, which cancel between the history force and the coupling and are
//! huge on the tiny first step after a kink.) The step's own scale alone
//! vanishes where the specimen is unloaded: the Mullins cycle of
//! `tests/mullins.rs` ends at zero strain between frictionless plates, where the
//! held plate is at 0, an elastic chain has no history, and a homogeneous
//! inelastic strain's nodal forces cancel on every free row, so the own scale
//! was the round-off of those sums (3.5e-24 N) and the residual's floor
//! (1e-30 N) stayed at 3e-7 of it after [`MAX_ITERATIONS`] at every step
//! length. Where the own scale is the larger (most loading steps: it holds the
//! viscous terms) a step converges exactly as before; elsewhere it may stop
//! earlier, at the same absolute bound.
//!
//! ## With contact tools
//! The step's `solve(b, u)` then settles the contact ([`super::contact`]: the
//! exact elimination for flat glued or frictionless tools, the augmented
//! Lagrangian otherwise) for the linear step with the right-hand side `b`, and
//! returns the contact forces. The two nonlinearities are combined by nesting:
//! the material-point iteration is the outer loop, and every one of its solves is
//! a fully settled contact solve of the linear step with the current inelastic
//! force, `g K u - F_c(u) = f_body + f_hist + f_in(e_in,k)`. The contact forces
//! of that solve are its exact reactions, so the free rows balance except for
//! the change of the inelastic force, and the iteration is the fixed point
//! `e_in,k+1 = e_in(u_k)` (modified Newton, the chain's linear tangent),
//! converged when `|f_in(e_in,k+1) - f_in(e_in,k)|` is at most [`TOLERANCE`] of
//! the force scale (the step's own then holds the contact forces' share: a push
//! from rest has no other load). For `finite-strain` the same fixed point runs
//! on the extra force `L(u) - N(u)`, the small-strain internal force less the
//! finite-strain one.
//!
//! Why nested, and why no consistent tangent: the contact solves keep their own
//! factorizations (one per active set, kept while it holds: on a plate one solve
//! a settle), built from the step's linear matrix; one Newton with both would
//! refactor the tangent with the contact's eliminations or penalties at every
//! iteration and make the contact's exact path, its low-rank path for curved
//! tools and its column cache depend on the material state. The price is linear
//! convergence: a strong effect that contracts slowly is not switched to full
//! Newton here (a tangent much stiffer than the chain's scales the operator
//! instead: "Stiffer tangents" below); it takes more iterations, and a step that does not converge in
//! [`MAX_ITERATIONS`] is retried at a quarter of its length by the stepper. The
//! stepper's reported contact forces are rebalanced to the cells' nodal forces
//! at the converged state ([`PointStep::out_of_balance`]), so tool and plate
//! forces are the equilibrium reactions of the final inelastic strains.
//!
//! ## Stiffer tangents (the scaled operator)
//! The fixed point above is Richardson's iteration preconditioned by the chain's
//! linear matrix `A`: it contracts while every cell's tangent `T` (relative to
//! the chain, `d tau1 / d tau_trial`) has its eigenvalues in `(0, 2)`. The
//! softening laws (slider, Bingham, thinning, the damage, E4 with `psi < 0`) stay
//! below 1 there. Strain stiffening does not: at `a = 50` and 50 % compression
//! `1 + a |e|_C` is about 26, each iteration overshot about 25-fold, and the run
//! ended with a non-finite displacement (the real fungi-steak double compression,
//! VALIDATION.md). So, with contact tools, the iteration runs on the scaled
//! operator `c A`:
//!
//! ```text
//! c A u_k+1 - F_c = base + x_k,    x_k+1 = f_in(u_k+1) + (c - 1) A u_free,k+1
//! ```
//!
//! whose fixed point is the step's equilibrium `A u - F_c = base + f_in(u)` (the
//! residual `x_k - x_k+1` is exactly the free rows' out-of-balance force, so the
//! tolerance is the same). A scalar factor costs no factorization: the contact
//! solve of `c A` is that of `A` with the right-hand side over `c` and the
//! contact forces times `c` (the same minimization under the same constraints;
//! the augmented Lagrangian's penalties then act `c` times softer, which changes
//! its iterations, not its answer). `c = (1 + t_max) / 2`, `t_max` the largest
//! eigenvalue of the cells' tangents ([`tangent_bound`], at most 5.8 % above it),
//! the Richardson optimum for eigenvalues in `[1, t_max]`: every eigenvalue of
//! `(c A)^-1 K_T` then lies in `(0, 2)` (the constrained subspace's too, by the
//! Rayleigh quotient) and Anderson's acceleration works on a contraction. Only
//! with glued and frictionless tools and no adhesion: friction's stick
//! increments and the cohesive zone carry forces from the step's start and
//! absolute strengths, so their solve is not homogeneous in the forces; with them
//! `c` stays 1 (and a strong stiffening may still diverge, as a typed error).
//! `c` starts at 1, is set from the tangents of each solve's state when
//! `t_max` exceeds [`OPERATOR_SWITCH`] and retargeted (with a fresh Anderson
//! history and a plain step) when the target moves by more than
//! [`OPERATOR_RETARGET`]; while `t_max` stays at most [`OPERATOR_SWITCH`] (every
//! law but stiffening with `a > 0` and E4 with `psi > 0`) `c` stays 1 and the
//! iteration does exactly what it did before. A fixed point that still diverges
//! (its residual past [`DIVERGED_GROWTH`] times its least) or a non-finite
//! displacement ends the step with [`PressError::NotConverged`] naming the step,
//! the time and an element, and the stepper retries it shorter.
//!
//! E6 (`finite-strain`) changes the kinematics, not the law: its steps take
//! [`solve_finite_step`] (the blended Green-Lagrange strain, the internal force
//! `w B(u)^T S`, the tangent with its geometric part).
//!
//! E4's per-cell direction flag (unloading when `s1 . (e1 - e0) < 0`) is frozen
//! during the iteration and re-checked at convergence; if a flag flipped the step
//! is solved again with the new flags, at most [`DIRECTION_PASSES`] times, so that
//! it cannot chatter.

use nalgebra::{SMatrix, SVector};

use super::model::Model;
use super::PressError;
use crate::assembly::{assemble_blocks, assemble_stiffness, assemble_vector};
use crate::element::{
    cell_strain, displacement_gradient, geometric_block, green_lagrange_block, nodal_force, ReferenceSimplex, Simplex,
};
use crate::material::{energy_norm, PointFailure, PointUpdate, StepMean};
use crate::parallel::map_collect;
use crate::solve::ReducedSystem;

/// Converged at this residual, relative to the step's force scale.
pub(crate) const TOLERANCE: f64 = 1e-12;
/// The most iterations of one pass.
pub(crate) const MAX_ITERATIONS: usize = 100;
/// Switch to the consistent tangent when a modified iteration reduces the
/// residual by less than this factor.
pub(crate) const SLOW_CONTRACTION: f64 = 0.5;
/// Keep a factored tangent while it reduces the residual by at least this factor
/// an iteration; refactor at the current state otherwise.
pub(crate) const TANGENT_REUSE: f64 = 0.1;
/// The most passes of one step for E4's direction flags.
pub(crate) const DIRECTION_PASSES: usize = 3;

/// A cell's total strain and local update.
type CellPoint<const S: usize> = (SVector<f64, S>, PointUpdate<S>);

/// The material-point state of the cells at a step's end.
pub(crate) struct PointStep<const S: usize> {
    /// Inelastic strain per cell.
    pub inelastic: Vec<SVector<f64, S>>,
    /// E4's unloading flag per cell (empty for the other laws).
    pub unloading: Vec<bool>,
    /// The damage's largest equivalent strain per cell (empty for the other laws).
    pub history: Vec<f64>,
    /// The residual of the free rows over the force scale of the tolerance
    /// ([`PointInput::reference`]).
    pub residual: f64,
    /// Numeric factorizations of the consistent tangent.
    pub factorizations: usize,
    /// With contact tools: the contact forces on the specimen per dof of the last
    /// solve (that of the returned displacement). `None` without tools.
    pub contact_forces: Option<Vec<f64>>,
    /// With contact tools: the out-of-balance force `f_int(u1) - f_body` per dof at
    /// the returned state, contact forces not subtracted (empty without tools).
    pub out_of_balance: Vec<f64>,
    /// With contact tools: the operator's factor `c` of the last solve (module doc,
    /// "Stiffer tangents"); `contact_forces` are already multiplied by it, the
    /// contact module's record of that solve is not. 1 otherwise.
    pub operator: f64,
}

/// Inputs of the step's iteration that the linear step already computed.
pub(crate) struct PointInput<'a, const S: usize> {
    /// Step factor per region.
    pub g: &'a [f64],
    /// History part of the stress image per cell.
    pub q: &'a [SVector<f64, S>],
    /// The step's mean factor per region (empty unless a law corrects the dashpot on
    /// the step's mean stress: [`crate::material::InelasticLaw::mean_corrected_c3`]).
    pub g_mean: &'a [f64],
    /// The history part of the mean stress image per cell, `tau_mean = g_mean (e1 -
    /// e_in1) - q_mean` (empty as `g_mean`).
    pub q_mean: &'a [SVector<f64, S>],
    /// The chain's strain at the step's start, per cell.
    pub chain0: &'a [SVector<f64, S>],
    /// The inelastic strain at the step's start, per cell.
    pub inelastic0: &'a [SVector<f64, S>],
    /// E4's flags at the step's start (empty for the other laws).
    pub unloading0: &'a [bool],
    /// The damage's largest equivalent strain at the step's start (empty for the other laws).
    pub history0: &'a [f64],
    /// The linear step's right-hand side with the held dofs' coupling removed.
    pub base: &'a [f64],
    /// The step's force scale (that of the linear residual) [N].
    pub scale: f64,
    /// The largest force the run has measured so far [N] (plate or bottom, at the
    /// accepted step ends; 0 on the first step): the floor of the tolerance's
    /// scale (module doc, "The force scale").
    pub run_scale: f64,
    pub dt: f64,
    pub t1: f64,
    pub step: usize,
    /// Whether the step's solve settles contact with tools (module doc, "With
    /// contact tools"): the iteration is then the fixed point on the nonlinear force.
    pub contact: bool,
}

impl<const S: usize> PointInput<'_, S> {
    /// The force scale the tolerance is relative to: the larger of the step's own
    /// (`own` [N]) and the run's largest so far (module doc, "The force scale").
    pub(crate) fn reference(&self, own: f64) -> f64 {
        own.max(self.run_scale)
    }
}

/// The out-of-balance force of the cells' nodal forces against the body force, per
/// dof, and its norm over the free dofs.
fn out_of_balance<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    system: &ReducedSystem,
    forces: &[[SVector<f64, D>; N]],
) -> (Vec<f64>, f64)
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mut residual = vec![0.0; model.num_dofs()];
    assemble_vector::<D, N>(&model.topology, forces, &mut residual);
    for (r, b) in residual.iter_mut().zip(&model.body_force) {
        *r -= b;
    }
    let norm = system.dof_of_free.iter().map(|&d| residual[d as usize].powi(2)).sum::<f64>().sqrt();
    (residual, norm)
}

/// The most earlier iterates Anderson's acceleration combines.
pub(crate) const ANDERSON_DEPTH: usize = 5;
/// Anderson's history restarts when the residual grows past this multiple of the
/// least one so far.
pub(crate) const ANDERSON_RESTART: f64 = 2.0;

/// Anderson's acceleration (type II, Walker & Ni 2011) of the fixed point `x =
/// G(x)` on the free dofs, `x` the inelastic (or extra) force of the contact
/// iteration (module doc, "With contact tools"): the next iterate is `G(x_k) -
/// sum_j gamma_j (dX_j + dF_j)`, `gamma` the least-squares fit of the residual
/// `f_k = G(x_k) - x_k` by the last [`ANDERSON_DEPTH`] residual differences `dF`
/// (`dX` those of the iterates). Without history it is the plain fixed point. The
/// plain iteration contracts at the linear tangent's ratio to the consistent one
/// (a slider with hardening `H` well below the chain's modulus `E`: `E/(E + H)`,
/// e.g. 0.875 an iteration, 200 iterations to 1e-12); the contact settles keep
/// the linear matrix, so no tangent can take over, and the acceleration recovers
/// a Krylov-like rate from the same solves.
struct Anderson<'s> {
    free: &'s [u32],
    xs: Vec<Vec<f64>>,
    fs: Vec<Vec<f64>>,
    best: f64,
}

impl<'s> Anderson<'s> {
    fn new(system: &'s ReducedSystem) -> Self {
        Self { free: &system.dof_of_free, xs: Vec::new(), fs: Vec::new(), best: f64::INFINITY }
    }

    /// The next iterate from `x` (full dofs), `gx = G(x)` and the norm of `gx - x`.
    fn next(&mut self, x: &[f64], gx: Vec<f64>, norm: f64) -> Vec<f64> {
        if norm > ANDERSON_RESTART * self.best {
            self.xs.clear();
            self.fs.clear();
        }
        self.best = self.best.min(norm);
        let xk: Vec<f64> = self.free.iter().map(|&d| x[d as usize]).collect();
        let fk: Vec<f64> = self.free.iter().map(|&d| gx[d as usize] - x[d as usize]).collect();
        self.xs.push(xk);
        self.fs.push(fk);
        if self.xs.len() > ANDERSON_DEPTH + 1 {
            self.xs.remove(0);
            self.fs.remove(0);
        }
        let m = self.xs.len() - 1;
        if m == 0 {
            return gx;
        }
        let n = self.free.len();
        let df = nalgebra::DMatrix::from_fn(n, m, |i, j| self.fs[j + 1][i] - self.fs[j][i]);
        let f = nalgebra::DVector::from_column_slice(&self.fs[m]);
        let svd = df.svd(true, true);
        let cut = 1e-12 * svd.singular_values.max();
        let Ok(gamma) = svd.solve(&f, cut) else {
            return gx;
        };
        let mut out = gx;
        for (i, &d) in self.free.iter().enumerate() {
            let mut c = 0.0;
            for j in 0..m {
                let dx = self.xs[j + 1][i] - self.xs[j][i];
                let dfj = self.fs[j + 1][i] - self.fs[j][i];
                c += gamma[j] * (dx + dfj);
            }
            out[d as usize] -= c;
        }
        out
    }
}

/// The operator's switch: with contact tools the fixed point keeps the chain's
/// linear matrix while every cell's tangent is at most this multiple of the
/// chain's (module doc, "Stiffer tangents"); past it the operator is scaled.
pub(crate) const OPERATOR_SWITCH: f64 = 1.5;
/// The scaled operator's factor is retargeted when the cells' stiffest tangent
/// calls for a factor more than this ratio away from the current one.
pub(crate) const OPERATOR_RETARGET: f64 = 1.25;
/// With contact tools the fixed point is stopped as diverged when its residual
/// grows past this multiple of the least one so far (an error naming the
/// element, before the displacements overflow).
pub(crate) const DIVERGED_GROWTH: f64 = 1e8;

/// An upper bound of the largest eigenvalue of a cell's tangent `T` (`C1 T` is
/// symmetric and `C1` positive definite, so `T` is similar to a symmetric matrix
/// and its eigenvalues are real): `trace(T^32)^(1/32)`, which lies between the
/// largest eigenvalue in size and `S^(1/32)` times it (at most 5.8 % above for
/// `S = 6`). Repeated squaring with a renormalization at each square; the
/// Frobenius norm (a looser bound) if the trace is not positive and finite.
pub(crate) fn tangent_bound<const S: usize>(t: &SMatrix<f64, S, S>) -> f64 {
    let size = t.norm();
    if !(size > 0.0 && size.is_finite()) {
        return size;
    }
    let mut p = t / size;
    let mut log = 0.0;
    for _ in 0..5 {
        p = p * p;
        let f = p.norm();
        if !(f > 0.0 && f.is_finite()) {
            return size;
        }
        p /= f;
        log = 2.0 * log + f.ln();
    }
    let trace = p.trace();
    if !(trace > 0.0 && trace.is_finite()) {
        return size;
    }
    (size * ((log + trace.ln()) / 32.0).exp()).min(size)
}

/// The norm of `v` over the free dofs.
fn free_norm(system: &ReducedSystem, v: &[f64]) -> f64 {
    system.dof_of_free.iter().map(|&d| v[d as usize].powi(2)).sum::<f64>().sqrt()
}

/// The state of the iteration at one displacement.
struct Evaluation<const S: usize> {
    /// Each cell's total strain and local update.
    updates: Vec<CellPoint<S>>,
    /// The out-of-balance force per dof.
    residual: Vec<f64>,
    /// Its norm over the free dofs.
    norm: f64,
}

/// The line search's acceptance: `|du . R(u + alpha du)|` at most this share of
/// `|du . R(u)|` (a strong-Wolfe curvature condition).
pub(crate) const LINE_SEARCH_SLOPE: f64 = 0.1;
/// The most evaluations of one line search past its first (the full step).
pub(crate) const LINE_SEARCH_EVALUATIONS: usize = 16;
/// The largest step length the line search tries (by doubling past 1).
pub(crate) const LINE_SEARCH_LONGEST: f64 = 64.0;

/// A line search along the Newton direction `du` from `u` (residual `r0`) on the
/// step's incremental potential: every law's update is monotone and associative
/// in the `C1` metric (its tangent `C1 T` is symmetric positive semidefinite), so
/// the residual is the gradient of a convex potential of the free displacements
/// and the slope `phi'(alpha) = du . R(u + alpha du)` is continuous and
/// non-decreasing in `alpha`, negative at 0 for a descent direction. The full step
/// is taken when its slope is at most [`LINE_SEARCH_SLOPE`] of the first in size
/// (always so near the solution, where Newton's step is exact to second order) or
/// when it already meets the tolerance; otherwise the root of the slope is
/// bracketed (doubling the step up to [`LINE_SEARCH_LONGEST`] when the slope is
/// still negative at 1, e.g. a tangent stiffer than the true one) and found by
/// regula falsi (Illinois) with a bisection safeguard, to the same acceptance.
/// Returns the step length and the evaluation there. The Mullins-type damage is
/// monotone too: its damaged strain is the `C1`-gradient of a convex function of
/// `|e|_C` (slope `(1 - d) |e|_C`, increasing on both branches and continuous at
/// the largest strain so far, since its virgin tangent factor stays above 0.09).
/// One law is not monotone:
/// strain stiffening with `a < 0` (softening); there the potential need not be
/// convex, the slope may have several roots and the point returned need not
/// lower the potential; the iteration's residual test still decides
/// convergence. A local update without a solution at a trial length ends the
/// search at the point of least slope found so far, in both phases.
fn line_search<const S: usize>(
    u: &[f64],
    du: &[f64],
    r0: &[f64],
    tolerance: f64,
    evaluate: &dyn Fn(&[f64]) -> Result<Evaluation<S>, PressError>,
) -> Result<(f64, Evaluation<S>), PressError> {
    let slope_of = |r: &[f64]| du.iter().zip(r).map(|(d, r)| d * r).sum::<f64>();
    let at = |alpha: f64| -> Result<(Evaluation<S>, f64), PressError> {
        let trial: Vec<f64> = u.iter().zip(du).map(|(u, d)| u + alpha * d).collect();
        let e = evaluate(&trial)?;
        let s = slope_of(&e.residual);
        Ok((e, s))
    };
    let slope0 = slope_of(r0);
    let (full, slope1) = at(1.0)?;
    let accept = |e: &Evaluation<S>, s: f64| e.norm <= tolerance || s.abs() <= LINE_SEARCH_SLOPE * slope0.abs();
    // Not a descent direction (round-off at the tolerance): the full step.
    if slope0 >= 0.0 || slope0.is_nan() || accept(&full, slope1) {
        return Ok((1.0, full));
    }
    // Bracket the root of the slope: [lo, hi] with slope(lo) < 0 < slope(hi).
    let (mut lo, mut slo, mut hi, mut shi) =
        if slope1 < 0.0 { (1.0, slope1, 1.0, slope1) } else { (0.0, slope0, 1.0, slope1) };
    // The evaluated point of the least slope in size, the answer if none is accepted.
    let mut closest = (1.0, full, slope1);
    let mut evaluations = 0usize;
    while shi < 0.0 {
        // Still descending at `lo`: double the step.
        let alpha = 2.0 * lo;
        if alpha > LINE_SEARCH_LONGEST || evaluations == LINE_SEARCH_EVALUATIONS {
            return Ok((closest.0, closest.1));
        }
        evaluations += 1;
        // A local update without a solution this far out: stop expanding.
        let Ok((e, s)) = at(alpha) else {
            return Ok((closest.0, closest.1));
        };
        if accept(&e, s) {
            return Ok((alpha, e));
        }
        if s < 0.0 {
            (lo, slo, hi, shi) = (alpha, s, alpha, s);
            closest = (alpha, e, s);
        } else {
            (hi, shi) = (alpha, s);
            if s.abs() < closest.2.abs() {
                closest = (alpha, e, s);
            }
        }
    }
    // Regula falsi (Illinois) on the bracket, bisection when it falls near an end.
    let mut side = 0i8;
    while evaluations < LINE_SEARCH_EVALUATIONS {
        evaluations += 1;
        let width = hi - lo;
        let mut alpha = lo - slo * width / (shi - slo);
        if !(alpha > lo + 0.01 * width && alpha < hi - 0.01 * width) {
            alpha = 0.5 * (lo + hi);
        }
        let Ok((e, s)) = at(alpha) else {
            return Ok((closest.0, closest.1));
        };
        if accept(&e, s) {
            return Ok((alpha, e));
        }
        if s < 0.0 {
            (lo, slo) = (alpha, s);
            if side < 0 {
                shi *= 0.5;
            }
            side = -1;
        } else {
            (hi, shi) = (alpha, s);
            if side > 0 {
                slo *= 0.5;
            }
            side = 1;
        }
        if s.abs() < closest.2.abs() {
            closest = (alpha, e, s);
        }
    }
    // Not accepted within the evaluations allowed: the bracket is then narrow
    // around the potential's minimum on the line.
    Ok((closest.0, closest.1))
}

/// Solves a step on the material-point path: `u1` holds the held values (and any
/// start for the free ones) on entry and the solution on exit. `solve(b, u)` is
/// the step's linear solve.
pub(crate) fn solve_step<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    input: &PointInput<'_, S>,
    system: &ReducedSystem,
    solve: &mut super::stepper::FreeSolve<'_>,
    u1: &mut Vec<f64>,
) -> Result<PointStep<S>, PressError>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    if let Some(blend) = model.finite {
        return solve_finite_step(model, input, system, solve, u1, blend);
    }
    let laws = model.point.as_ref().expect("the material-point path has laws");
    let mesh = &model.problem.mesh;
    let ncell = mesh.num_cells();
    let ndof = model.num_dofs();
    let directional = laws.iter().any(|l| l.needs_direction());
    let historied = laws.iter().any(|l| l.needs_history());
    let mut unloading: Vec<bool> = if directional { input.unloading0.to_vec() } else { Vec::new() };
    let not_converged = |detail: String| PressError::NotConverged { step: input.step, time_s: input.t1, detail };
    let mut factorizations = 0usize;
    // The scaled operator needs a contact solve homogeneous in the forces (module
    // doc, "Stiffer tangents"): glued and frictionless tools, no adhesion.
    let scalable = input.contact
        && model.problem.effects.adhesion().is_none()
        && model
            .problem
            .tools
            .iter()
            .all(|t| matches!(t.contact, super::ToolContact::Glued | super::ToolContact::Frictionless));

    // f_in = sum_e w B^T C1 g e_in.
    let inelastic_force = |e_in: &(dyn Fn(usize) -> SVector<f64, S> + Sync)| -> Vec<f64> {
        let forces: Vec<[SVector<f64, D>; N]> = map_collect(ncell, |e| {
            let r = mesh.cell_regions[e] as usize;
            let s = model.region_c1[r] * (e_in(e) * input.g[r]);
            std::array::from_fn(|a| nodal_force::<D, N, S>(&model.geometry[e], &s, a))
        });
        let mut f = vec![0.0; ndof];
        assemble_vector::<D, N>(&model.topology, &forces, &mut f);
        f
    };

    for pass in 0..DIRECTION_PASSES {
        let flags = &unloading;
        // Local updates of every cell for a displacement.
        let local = |u: &[f64]| -> Result<Vec<CellPoint<S>>, (usize, PointFailure)> {
            let updates: Vec<Result<CellPoint<S>, PointFailure>> = map_collect(ncell, |e| {
                let r = mesh.cell_regions[e] as usize;
                let e1 = cell_strain::<D, N, S>(&model.geometry[e].gradients, &model.cell_displacements(e, u));
                let trial = (e1 - input.inelastic0[e]) * input.g[r] - input.q[e];
                let unload = directional && flags[e];
                let history0 = if historied { input.history0[e] } else { 0.0 };
                // The chain's mean stress over the step (Bingham's correction).
                let mean = laws[r].mean_corrected_c3().map(|_| StepMean {
                    trial: (e1 - input.inelastic0[e]) * input.g_mean[r] - input.q_mean[e],
                    g: input.g_mean[r],
                });
                laws[r]
                    .update(
                        &model.region_c1[r],
                        &trial,
                        &input.inelastic0[e],
                        input.g[r],
                        input.dt,
                        unload,
                        &e1,
                        history0,
                        mean.as_ref(),
                    )
                    .map(|p| (e1, p))
            });
            updates.into_iter().enumerate().map(|(e, x)| x.map_err(|f| (e, f))).collect()
        };
        let failure = |(e, f): (usize, PointFailure)| match f {
            PointFailure::StepTooLong { ratio } => not_converged(format!(
                "element {e}: the dashpot correction needs g dt / c3 < {} (Bingham's g_m dt / c3 < {}; it is \
                 {ratio:.3}); a shorter step",
                crate::material::MAX_DASHPOT_RATIO,
                crate::material::MAX_MEAN_DASHPOT_RATIO
            )),
            PointFailure::NoStiffness { strain } => not_converged(format!(
                "element {e}: strain softening leaves no stiffness at the strain |e|_C = {strain:.4} \
                 (1 + a |e|_C below {})",
                crate::material::MIN_STIFFENING_FACTOR
            )),
        };

        let mut f_in = inelastic_force(&|e| input.inelastic0[e]);
        // The force scale: the linear step's, and the inelastic strains' own share.
        let scale =
            (input.scale.powi(2) + system.dof_of_free.iter().map(|&d| f_in[d as usize].powi(2)).sum::<f64>()).sqrt();
        // The cells' updates, the out-of-balance force and its norm at a displacement.
        let evaluate = |u: &[f64]| -> Result<Evaluation<S>, PressError> {
            for &d in &system.dof_of_free {
                if !u[d as usize].is_finite() {
                    let node = d as usize / D;
                    let element = model.cell_of_node(node).unwrap_or(usize::MAX);
                    return Err(not_converged(format!(
                        "element {element}: non-finite displacement at node {node} (dof {d})"
                    )));
                }
            }
            let updates = local(u).map_err(failure)?;
            // Residual: f_int(u) - f_body on the free rows.
            let forces: Vec<[SVector<f64, D>; N]> = map_collect(ncell, |e| {
                let r = mesh.cell_regions[e] as usize;
                let s = model.region_c1[r] * updates[e].1.tau;
                std::array::from_fn(|a| nodal_force::<D, N, S>(&model.geometry[e], &s, a))
            });
            let (residual, norm) = out_of_balance(model, system, &forces);
            Ok(Evaluation { updates, residual, norm })
        };
        let mut previous = f64::INFINITY;
        let mut tangent_mode = false;
        let mut tangent: Option<crate::solve::Factor<'_>> = None;
        // The next iterate when a line search has already evaluated it.
        let mut searched: Option<Evaluation<S>> = None;
        let mut converged = None;
        // With contact: the last solve's contact forces, the out-of-balance force
        // at its displacement, the inelastic force there (the next right-hand
        // side's), and the force scale with the contact forces' share.
        let mut contact: Option<(Vec<f64>, Vec<f64>)> = None;
        let mut f_next: Option<Vec<f64>> = None;
        let mut anderson = Anderson::new(system);
        let (linear_scale, mut scale) = (scale, scale);
        // With contact: the operator's factor `c` (module doc, "Stiffer tangents"),
        // and the least residual so far (the divergence guard's reference).
        let mut operator = 1.0;
        let mut least = f64::INFINITY;
        let mut plain_next = false;
        for iteration in 0..MAX_ITERATIONS {
            let Evaluation { updates, residual, norm } = match searched.take() {
                Some(x) => x,
                None => {
                    // The contact solve of `c A u - F_c = base + x` is that of `A u -
                    // F_c / c = (base + x) / c`; at c = 1 the very same operations as ever.
                    let b: Vec<f64> = if operator == 1.0 {
                        input.base.iter().zip(&f_in).map(|(b, f)| b + f).collect()
                    } else {
                        input.base.iter().zip(&f_in).map(|(b, f)| (b + f) / operator).collect()
                    };
                    let forces = solve(&b, u1)?;
                    let evaluation = evaluate(u1)?;
                    match forces.filter(|_| input.contact) {
                        None => evaluation,
                        Some(mut forces) => {
                            if operator != 1.0 {
                                forces.iter_mut().for_each(|f| *f *= operator);
                            }
                            // The fixed point's residual: the change of the right-hand
                            // side's extra force, `f_in(u) + (c - 1) A u_free` (the
                            // contact forces are the reactions of the solve).
                            let inelastic = inelastic_force(&|e| evaluation.updates[e].1.inelastic);
                            // The cells' stiffest tangent sets the operator for the next solve.
                            let stiffest = map_collect(ncell, |e| tangent_bound(&evaluation.updates[e].1.tangent))
                                .into_iter()
                                .fold(1.0, f64::max);
                            let target =
                                if scalable && stiffest > OPERATOR_SWITCH { 0.5 * (1.0 + stiffest) } else { 1.0 };
                            let retarget =
                                target > OPERATOR_RETARGET * operator || target * OPERATOR_RETARGET < operator;
                            // The chain's linear force of the free displacements, `A u_free`.
                            let linear = (operator != 1.0 || retarget).then(|| {
                                let mut free = vec![0.0; ndof];
                                for &d in &system.dof_of_free {
                                    free[d as usize] = u1[d as usize];
                                }
                                inelastic_force(&|e| {
                                    cell_strain::<D, N, S>(
                                        &model.geometry[e].gradients,
                                        &model.cell_displacements(e, &free),
                                    )
                                })
                            });
                            let extra = |c: f64| -> Vec<f64> {
                                match linear.as_ref().filter(|_| c != 1.0) {
                                    None => inelastic.clone(),
                                    Some(l) => inelastic.iter().zip(l).map(|(f, l)| f + (c - 1.0) * l).collect(),
                                }
                            };
                            let next = extra(operator);
                            let change: Vec<f64> = f_in.iter().zip(&next).map(|(a, b)| a - b).collect();
                            let norm = free_norm(system, &change);
                            scale = (linear_scale.powi(2) + free_norm(system, &forces).powi(2)).sqrt();
                            contact = Some((forces, evaluation.residual));
                            if retarget && norm > TOLERANCE * input.reference(scale) {
                                // A new fixed-point map: its plain step, a fresh history.
                                operator = target;
                                anderson = Anderson::new(system);
                                least = f64::INFINITY;
                                plain_next = true;
                                f_next = Some(extra(operator));
                            } else {
                                f_next = Some(next);
                            }
                            Evaluation { updates: evaluation.updates, residual: change, norm }
                        }
                    }
                }
            };
            if norm <= TOLERANCE * input.reference(scale) {
                converged = Some((updates, norm));
                break;
            }
            // Name the cell at the largest out-of-balance nodal force.
            let worst_cell = |residual: &[f64]| {
                let worst = system
                    .dof_of_free
                    .iter()
                    .map(|&d| d as usize)
                    .max_by(|&a, &b| residual[a].abs().total_cmp(&residual[b].abs()))
                    .unwrap_or(0);
                let node = worst / D;
                (model.cell_of_node(node).unwrap_or(usize::MAX), node, worst)
            };
            if input.contact && contact.is_some() {
                if !norm.is_finite() || norm > DIVERGED_GROWTH * least {
                    let (element, node, worst) = worst_cell(&residual);
                    return Err(not_converged(format!(
                        "element {element}: the contact fixed point diverged (residual {:.3e} of the force scale, \
                         {:.1e} times its least, at iteration {iteration}; largest at node {node}, dof {worst})",
                        norm / input.reference(scale),
                        norm / least
                    )));
                }
                least = least.min(norm);
            }
            if iteration + 1 == MAX_ITERATIONS {
                let (element, node, worst) = worst_cell(&residual);
                return Err(not_converged(format!(
                    "element {element}: the residual is {:.3e} of the force scale after {MAX_ITERATIONS} \
                     iterations (largest at node {node}, dof {worst})",
                    norm / input.reference(scale)
                )));
            }
            if !tangent_mode && !input.contact && iteration >= 1 && norm > SLOW_CONTRACTION * previous {
                tangent_mode = true;
            }
            let contraction = norm / previous;
            previous = norm;
            if tangent_mode {
                // Consistent tangent sum_e w B^T g C1 T_e B: factored when first
                // needed, and again whenever the last one contracts slowly.
                if tangent.is_none() || contraction > TANGENT_REUSE {
                    let cell_matrix = |e: usize| {
                        let r = mesh.cell_regions[e] as usize;
                        let ct = model.region_c1[r] * updates[e].1.tangent * input.g[r];
                        Some((ct + ct.transpose()) * 0.5)
                    };
                    let values = assemble_stiffness::<D, N, S>(
                        &model.topology,
                        &model.pattern,
                        &mesh.cells,
                        &model.geometry,
                        &cell_matrix,
                    );
                    tangent = system.factor(&[(1.0, values.as_slice())], None).ok();
                    factorizations += usize::from(tangent.is_some());
                }
                match tangent.as_ref() {
                    Some(factor) => {
                        let mut x: Vec<f64> = system.dof_of_free.iter().map(|&d| -residual[d as usize]).collect();
                        factor.solve_in_place(&mut x);
                        let mut du = vec![0.0; ndof];
                        for (i, &d) in system.dof_of_free.iter().enumerate() {
                            du[d as usize] = x[i];
                        }
                        let (alpha, next) =
                            line_search(u1, &du, &residual, TOLERANCE * input.reference(scale), &evaluate)?;
                        u1.iter_mut().zip(&du).for_each(|(u, d)| *u += alpha * d);
                        searched = Some(next);
                        continue;
                    }
                    // Not positive definite: go on with the linear matrix.
                    None => tangent_mode = false,
                }
            }
            f_in = match f_next.take() {
                // A retargeted operator: its plain step.
                Some(next) if std::mem::take(&mut plain_next) => next,
                // With contact: the fixed point's next right-hand side, accelerated.
                Some(next) => anderson.next(&f_in, next, norm),
                None => inelastic_force(&|e| updates[e].1.inelastic),
            };
        }
        let (updates, norm) = converged.expect("the loop returns or converges");
        // E4: re-check the direction flags at the converged state.
        if directional {
            let flipped: Vec<bool> = map_collect(ncell, |e| {
                let r = mesh.cell_regions[e] as usize;
                let (e1, p) = &updates[e];
                let de = e1 - (input.chain0[e] + input.inelastic0[e]);
                let c1: &SMatrix<f64, S, S> = &model.region_c1[r];
                let work = p.tau.dot(&(c1 * de));
                let size = energy_norm(c1, &p.tau) * energy_norm(c1, e1);
                (work < -1e-10 * size) != unloading[e]
            });
            if flipped.iter().any(|&f| f) && pass + 1 < DIRECTION_PASSES {
                unloading.iter_mut().zip(&flipped).for_each(|(u, &f)| *u ^= f);
                continue;
            }
        }
        let history = if historied { updates.iter().map(|(_, p)| p.history).collect() } else { Vec::new() };
        let (contact_forces, out_of_balance) = match contact {
            Some((forces, residual)) => (Some(forces), residual),
            None => (None, Vec::new()),
        };
        return Ok(PointStep {
            inelastic: updates.into_iter().map(|(_, p)| p.inelastic).collect(),
            unloading,
            history,
            residual: if input.reference(scale) > 0.0 { norm / input.reference(scale) } else { 0.0 },
            factorizations,
            contact_forces,
            out_of_balance,
            operator,
        });
    }
    unreachable!("the last pass returns")
}

/// Solves a step on the finite-strain path (effect E6, [`crate::effects`]): the
/// chain acts on the blended Green-Lagrange strain `E_b(u)` of each cell, the
/// stress `S1 = C1 (g E_b(u1) - q)` is the 2nd Piola-Kirchhoff stress, and the
/// residual is `sum_e w B(u1)^T S1 - f_body` on the free rows
/// ([`crate::element::green_lagrange_block`]). Predictor: the linear step
/// (`solve(base)`); then modified Newton with the step's linear factorization,
/// switching to full Newton with the tangent `sum_e w [B^T g C1 B + K_G(S)]`
/// (material and geometric parts, symmetric) when an iteration reduces the
/// residual by less than [`SLOW_CONTRACTION`], refactored when it contracts by
/// less than [`TANGENT_REUSE`]. Same tolerance, limits and errors as
/// [`solve_step`]. No inelastic strain (the returned ones are zero).
fn solve_finite_step<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    input: &PointInput<'_, S>,
    system: &ReducedSystem,
    solve: &mut super::stepper::FreeSolve<'_>,
    u1: &mut Vec<f64>,
    blend: f64,
) -> Result<PointStep<S>, PressError>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mesh = &model.problem.mesh;
    let ncell = mesh.num_cells();
    let ndof = model.num_dofs();
    let not_converged = |detail: String| PressError::NotConverged { step: input.step, time_s: input.t1, detail };
    let mut scale = input.scale;
    let mut factorizations = 0usize;
    // Predictor: the small-strain step.
    let mut forces_c = solve(input.base, u1)?.filter(|_| input.contact);
    let mut previous = f64::INFINITY;
    let mut tangent_mode = false;
    let mut tangent: Option<crate::solve::Factor<'_>> = None;
    // With contact: the extra force `L(u) - N(u)` of the last solve's right-hand
    // side (the small-strain internal force less the finite-strain one).
    let mut extra = vec![0.0; ndof];
    let mut anderson = Anderson::new(system);
    for iteration in 0..MAX_ITERATIONS {
        for &d in &system.dof_of_free {
            if !u1[d as usize].is_finite() {
                return Err(not_converged(format!("non-finite displacement at dof {d}")));
            }
        }
        // Per cell: the gradient, its hoop strain and the stress S1.
        let cells: Vec<(nalgebra::SMatrix<f64, D, D>, f64, SVector<f64, S>)> = map_collect(ncell, |e| {
            let r = mesh.cell_regions[e] as usize;
            let ue = model.cell_displacements(e, u1);
            let (h, hoop) = displacement_gradient::<D, N, S>(&model.geometry[e].gradients, &ue);
            let strain = model.strain_of(e, &ue);
            let s = model.region_c1[r] * ((strain - input.inelastic0[e]) * input.g[r] - input.q[e]);
            (h, hoop, s)
        });
        let forces: Vec<[SVector<f64, D>; N]> = map_collect(ncell, |e| {
            let g = &model.geometry[e];
            let (h, hoop, s) = &cells[e];
            std::array::from_fn(|a| {
                green_lagrange_block::<D, N, S>(&g.gradients, h, *hoop, blend, a).transpose() * s * g.weight
            })
        });
        let (residual, mut norm) = out_of_balance(model, system, &forces);
        // With contact, the fixed point on the extra force (module doc).
        let next_extra = forces_c.as_ref().map(|contact| {
            let linear: Vec<[SVector<f64, D>; N]> = map_collect(ncell, |e| {
                let r = mesh.cell_regions[e] as usize;
                let small = cell_strain::<D, N, S>(&model.geometry[e].gradients, &model.cell_displacements(e, u1));
                let s = model.region_c1[r] * ((small - input.inelastic0[e]) * input.g[r] - input.q[e]);
                std::array::from_fn(|a| nodal_force::<D, N, S>(&model.geometry[e], &s, a))
            });
            let mut next = vec![0.0; ndof];
            assemble_vector::<D, N>(&model.topology, &linear, &mut next);
            let mut nonlinear = vec![0.0; ndof];
            assemble_vector::<D, N>(&model.topology, &forces, &mut nonlinear);
            next.iter_mut().zip(&nonlinear).for_each(|(l, n)| *l -= n);
            let change: Vec<f64> = extra.iter().zip(&next).map(|(a, b)| a - b).collect();
            norm = free_norm(system, &change);
            scale = (input.scale.powi(2) + free_norm(system, contact).powi(2)).sqrt();
            next
        });
        if norm <= TOLERANCE * input.reference(scale) {
            let (contact_forces, out_of_balance) = match forces_c {
                Some(f) => (Some(f), residual),
                None => (None, Vec::new()),
            };
            return Ok(PointStep {
                inelastic: input.inelastic0.to_vec(),
                unloading: Vec::new(),
                history: Vec::new(),
                residual: if input.reference(scale) > 0.0 { norm / input.reference(scale) } else { 0.0 },
                factorizations,
                contact_forces,
                out_of_balance,
                operator: 1.0,
            });
        }
        if iteration + 1 == MAX_ITERATIONS {
            break;
        }
        if let Some(next) = next_extra {
            // Contact: the modified Newton step with the contact settled, on the
            // total displacement (the contact works on positions, not corrections).
            let next = anderson.next(&extra, next, norm);
            let b: Vec<f64> = input.base.iter().zip(&next).map(|(b, x)| b + x).collect();
            forces_c = solve(&b, u1)?;
            extra = next;
            continue;
        }
        if !tangent_mode && iteration >= 1 && norm > SLOW_CONTRACTION * previous {
            tangent_mode = true;
        }
        let contraction = norm / previous;
        previous = norm;
        let mut du = vec![0.0; ndof];
        if tangent_mode && (tangent.is_none() || contraction > TANGENT_REUSE) {
            let block = |e: usize, a: usize, b: usize| {
                let r = mesh.cell_regions[e] as usize;
                let g = &model.geometry[e];
                let (h, hoop, s) = &cells[e];
                let ba = green_lagrange_block::<D, N, S>(&g.gradients, h, *hoop, blend, a);
                let bb = green_lagrange_block::<D, N, S>(&g.gradients, h, *hoop, blend, b);
                let material = ba.transpose() * (model.region_c1[r] * input.g[r]) * bb;
                (material + geometric_block::<D, N, S>(&g.gradients, s, blend, a, b)) * g.weight
            };
            let values = assemble_blocks::<D, _>(&model.topology, &model.pattern, &mesh.cells, &block);
            tangent = system.factor(&[(1.0, values.as_slice())], None).ok();
            factorizations += usize::from(tangent.is_some());
            if tangent.is_none() {
                // Not positive definite: go on with the linear matrix.
                tangent_mode = false;
            }
        }
        match tangent.as_ref().filter(|_| tangent_mode) {
            Some(factor) => {
                let mut x: Vec<f64> = system.dof_of_free.iter().map(|&d| -residual[d as usize]).collect();
                factor.solve_in_place(&mut x);
                for (i, &d) in system.dof_of_free.iter().enumerate() {
                    du[d as usize] = x[i];
                }
            }
            None => {
                let b: Vec<f64> = residual.iter().map(|r| -r).collect();
                solve(&b, &mut du)?;
            }
        }
        for &d in &system.dof_of_free {
            u1[d as usize] += du[d as usize];
        }
    }
    Err(not_converged(format!(
        "finite strain: the residual is above {TOLERANCE:.0e} of the force scale after {MAX_ITERATIONS} iterations"
    )))
}
