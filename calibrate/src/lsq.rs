//! Bounded nonlinear least squares: a trust-region Levenberg-Marquardt method.
//!
//! # Problem
//!
//! Minimize the objective
//!
//! ```text
//! f(x) = 1/2 sum_i r_i(x)^2,    lower_j <= x_j <= upper_j,
//! ```
//!
//! where the residuals `r_i` come weighted by their measurement noise
//! (`r_i = (sim_i - meas_i) / sigma_i`) and the problem supplies the exact
//! Jacobian `J = dr/dx` in physical units ([`LeastSquares`]).
//!
//! # Transformed variables
//!
//! The solver works on `y`, one coordinate per parameter ([`ParameterSpec`]):
//! `y = ln x` for [`Scale::Log`] (positive parameters spanning decades: moduli,
//! viscosities), `y = x` for [`Scale::Linear`] (a bounded box, e.g. Poisson's
//! ratio in [0, 0.499]). Bounds map the same way (`ln lower`, `ln upper`), and the
//! Jacobian by the chain rule, `dr/dy_j = dr/dx_j * x_j` for log parameters.
//! Everything reported ([`Fit`]) is physical.
//!
//! # Iteration
//!
//! Each iteration solves the trust-region subproblem (Moré 1978, MINPACK's
//! `lmder`)
//!
//! ```text
//! min_p 1/2 |r + J p|^2   subject to |D p| <= Delta,
//! ```
//!
//! with Moré's scaling `D = diag(d_j)`, `d_j` the largest norm column `j` of `J`
//! has had so far (so the method does not depend on the units of `y`). The
//! solution is `p(lambda) = -(J^T J + lambda D^2)^-1 J^T r` with `lambda = 0` if
//! the Gauss-Newton step fits in the region, else the `lambda` with
//! `|D p(lambda)| = Delta` (to 10 %), found by Moré's safeguarded Newton
//! iteration on `1/|D p| - 1/Delta`. The subproblem is solved through the thin
//! SVD `J D^-1 = U S V^T` of the free columns:
//!
//! ```text
//! D p(lambda) = -V diag(s_k / (s_k^2 + lambda)) U^T r,
//! ```
//!
//! which is the least-squares solution of the augmented system
//! `[J; sqrt(lambda) D] p = -[r; 0]` computed without forming `J^T J`, so the
//! conditioning is that of `J`, not its square. Singular values below
//! `eps * max(m, n) * s_max` count as zero (minimum-norm Gauss-Newton step when
//! the Jacobian is rank deficient). Since `n <= 12`, one SVD per trial costs
//! microseconds against a finite-element simulation.
//!
//! The step is accepted when the ratio of the actual to the predicted reduction,
//! `rho = (f(y) - f(y + p)) / (f(y) - 1/2 |r + J p|^2)`, exceeds 1e-4. The
//! radius then grows to `max(Delta, 2 |D p|)` when `rho > 0.75`, shrinks to
//! `|D p| / 2` when `rho < 0.25`; a rejected step shrinks it to `|D p| / 4`. The
//! first radius is `initial_trust_radius * |D t|`, with `t` the typical size of
//! each coordinate (1 for a log parameter, `|x_j|` for a linear one; see
//! [`Options::step_tolerance`]).
//!
//! **Failed evaluations.** A simulation may fail for wild parameters (an inverted
//! element, a solver that does not converge). [`LeastSquares::evaluate`] then
//! returns an [`EvalError`], and a non-finite residual or Jacobian counts the same:
//! the step is rejected and the radius shrinks as for `rho < 0`. Only a failure at
//! the start point is an error ([`FitError::StartEvaluation`]).
//!
//! # Bounds
//!
//! Iterates stay inside the box; the problem is never evaluated outside it. An
//! active-set rule: parameter `j` at its lower bound with `g_j > 0` (`g = J^T r`,
//! the gradient wants it lower) or at its upper bound with `g_j < 0` is held
//! fixed, and so is a parameter at a bound whose computed step points out of the
//! box (the subproblem is then solved again without it). The step `p` of the free
//! parameters is then made feasible two ways, by projecting `y + p` onto the box
//! and by shortening `p` until it meets the first bound, and the one with the
//! larger predicted reduction is tried. (The shortened step always keeps a
//! positive predicted reduction, since the model decreases along `p`.) A
//! parameter that reaches a bound is set exactly to it and reported in
//! [`Fit::at_bound`].
//!
//! # Stopping
//!
//! Like the seed paper's `lsqnonlin` (tolerance 1e-6 on the objective or the
//! step), checked in this order ([`StopReason`]):
//!
//! 1. [`StopReason::GradientTolerance`]: first-order optimality. The largest
//!    cosine between `r` and a free column of `J`, `|g_j| / (|J_j| |r|)`, is at
//!    most `gradient_tolerance` (MINPACK's `gtol` test; 1 means "orthogonal"), or
//!    `r = 0`, or every parameter is held at a bound.
//! 2. [`StopReason::ObjectiveTolerance`] (`ftol`): either the Gauss-Newton
//!    decrement, `1/2 |P r|^2` with `P` the projector onto the range of the free
//!    columns (the most the linear model could still gain), is at most
//!    `objective_tolerance * f`, tested before a step so that no evaluation is
//!    spent to confirm it; or an accepted step reduced `f` by at most
//!    `objective_tolerance * f` while the model predicted as little (MINPACK's
//!    `ftol` test).
//! 3. [`StopReason::StepTolerance`] (`xtol`): a step, accepted or rejected, is
//!    relatively at most `step_tolerance` in every parameter (so a trust region
//!    collapsed by repeated failures also stops here).
//! 4. [`StopReason::MaxIterations`]: `max_iterations` trial steps were taken.
//!
//! An iteration is one trial step, so one evaluation (two when the Jacobian is
//! not requested with trial points and the step is accepted).

use std::error::Error as StdError;
use std::fmt;

use nalgebra::{DMatrix, DVector};

/// A nonlinear least-squares problem: noise-weighted residuals and their
/// Jacobian as functions of the physical parameters.
///
/// `Sync` so that multi-start and profiles can evaluate it from several threads.
pub trait LeastSquares: Sync {
    /// The number of parameters `n` (the length of `x`).
    fn num_parameters(&self) -> usize;

    /// The residuals at `x` (physical units, inside the bounds), and
    /// `dr/dx` when `want_jacobian` is true (it may be given anyway, and is then
    /// ignored). The number of residuals must be the same at every `x`.
    ///
    /// An `Err` (e.g. an inverted element at wild parameters) is not fatal: the
    /// solver rejects the step and shrinks its trust region.
    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError>;
}

/// One evaluation of a [`LeastSquares`] problem.
#[derive(Clone, Debug)]
pub struct Evaluation {
    /// Noise-weighted residuals `r_i = (sim_i - meas_i) / sigma_i` [-].
    pub residuals: Vec<f64>,
    /// `dr/dx` in physical units: one row per residual, one column per parameter
    /// (column `j` in 1 / (unit of `x_j`)). Required when requested.
    pub jacobian: Option<DMatrix<f64>>,
}

/// A failed evaluation: the simulation could not be run at these parameters.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct EvalError {
    /// What went wrong, in words (e.g. "element 17 inverted (det J = -0.002) at t = 12.3 s").
    pub message: String,
    /// The underlying error, if any.
    #[source]
    pub source: Option<Box<dyn StdError + Send + Sync>>,
}

impl EvalError {
    /// A failure described by a message.
    pub fn new(message: impl Into<String>) -> Self {
        Self { message: message.into(), source: None }
    }

    /// A failure caused by another error (e.g. the engine's), with a message
    /// saying what was being done.
    pub fn with_source(message: impl Into<String>, source: impl Into<Box<dyn StdError + Send + Sync>>) -> Self {
        Self { message: message.into(), source: Some(source.into()) }
    }
}

/// How the solver sees a parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// `y = ln x`: for positive parameters known to within decades (moduli,
    /// viscosities). Steps are relative changes, intervals asymmetric.
    Log,
    /// `y = x`: for parameters in a fixed box that may touch zero (Poisson's ratio).
    Linear,
}

/// One parameter to identify: its name, bounds and scale.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterSpec {
    /// Name used in reports and warnings, with its unit (e.g. `"E1_MPa"`).
    pub name: String,
    /// Lower bound, in the parameter's unit. May be `-inf` (linear) or 0 (log);
    /// multi-start needs it finite (and positive for log).
    pub lower: f64,
    /// Upper bound, in the parameter's unit. May be `+inf`; multi-start needs it finite.
    pub upper: f64,
    /// The solver's coordinate for this parameter.
    pub scale: Scale,
}

impl ParameterSpec {
    /// A positive parameter identified in `ln x`, within `[lower, upper]`.
    pub fn log(name: impl Into<String>, lower: f64, upper: f64) -> Self {
        Self { name: name.into(), lower, upper, scale: Scale::Log }
    }

    /// A parameter identified in `x` itself, within `[lower, upper]`.
    pub fn linear(name: impl Into<String>, lower: f64, upper: f64) -> Self {
        Self { name: name.into(), lower, upper, scale: Scale::Linear }
    }

    /// The solver coordinate `y` of a physical value `x` (`ln x` or `x`).
    pub fn to_solver(&self, x: f64) -> f64 {
        match self.scale {
            Scale::Log => x.ln(),
            Scale::Linear => x,
        }
    }

    /// The bounds in the solver coordinate.
    pub fn solver_bounds(&self) -> (f64, f64) {
        (self.to_solver(self.lower), self.to_solver(self.upper))
    }

    /// The physical value of a solver coordinate, clamped to the bounds (a
    /// coordinate at a bound gives the bound itself, bit for bit).
    pub fn to_physical(&self, y: f64) -> f64 {
        let (low, high) = self.solver_bounds();
        if y <= low {
            return self.lower;
        }
        if y >= high {
            return self.upper;
        }
        let x = match self.scale {
            Scale::Log => y.exp(),
            Scale::Linear => y,
        };
        x.clamp(self.lower, self.upper)
    }

    /// Checks the bounds: ordered, not NaN, positive upper bound and
    /// non-negative lower bound for a log parameter.
    pub fn validate(&self) -> Result<(), FitError> {
        let reason = if self.lower.is_nan() || self.upper.is_nan() {
            Some("a bound is NaN")
        } else if self.lower > self.upper {
            Some("lower bound above upper bound")
        } else if self.scale == Scale::Log && (self.lower < 0.0 || self.upper <= 0.0) {
            Some("a log-scale parameter needs 0 <= lower and 0 < upper")
        } else {
            None
        };
        match reason {
            Some(reason) => {
                Err(FitError::InvalidBounds { name: self.name.clone(), lower: self.lower, upper: self.upper, reason })
            }
            None => Ok(()),
        }
    }
}

/// Settings of [`levenberg_marquardt`].
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// `ftol`: stop when the objective can fall, or just fell, by at most this
    /// fraction (see the module docs). Default 1e-6, as the seed paper.
    pub objective_tolerance: f64,
    /// `xtol`: stop when a step changes every parameter by at most this fraction.
    /// The change is measured in `ln x` for a log parameter (a relative change)
    /// and as `|dx| / max(|x|, w)` for a linear one, where `w` is a thousandth of
    /// the box width (or, for an unbounded parameter, of `|x0|`, or 1e-3 if
    /// `x0 = 0`), so a parameter converging to zero still stops. Default 1e-6, as
    /// the seed paper.
    pub step_tolerance: f64,
    /// `gtol`: stop when the largest cosine between the residual vector and a
    /// free Jacobian column is at most this. Default 1e-10.
    pub gradient_tolerance: f64,
    /// Maximum number of trial steps (each costs one evaluation). Default 100.
    pub max_iterations: usize,
    /// First trust-region radius as a multiple of `|D t|` (module docs): 1 lets
    /// the first step change a log parameter by about a factor e, or a linear one
    /// by about its own size. Default 1.
    pub initial_trust_radius: f64,
    /// Request the Jacobian with every trial point (one simulation per accepted
    /// step; the Jacobian of a rejected step is wasted) rather than only after a
    /// step is accepted (a second simulation per accepted step). Forward
    /// sensitivities are much cheaper than a second simulation, so the default is
    /// `true`.
    pub jacobian_with_trial: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            objective_tolerance: 1e-6,
            step_tolerance: 1e-6,
            gradient_tolerance: 1e-10,
            max_iterations: 100,
            initial_trust_radius: 1.0,
            jacobian_with_trial: true,
        }
    }
}

/// Why [`levenberg_marquardt`] stopped (module docs, "Stopping").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// The objective could not, or did not, decrease by more than `objective_tolerance` relative.
    ObjectiveTolerance,
    /// The last step was relatively smaller than `step_tolerance`.
    StepTolerance,
    /// First-order optimality: the gradient is orthogonal to the residuals within
    /// `gradient_tolerance`, the residuals are zero, or every parameter is held at a bound.
    GradientTolerance,
    /// `max_iterations` trial steps were taken without convergence.
    MaxIterations,
}

impl StopReason {
    /// True for every reason but [`StopReason::MaxIterations`].
    pub fn converged(self) -> bool {
        self != StopReason::MaxIterations
    }
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            StopReason::ObjectiveTolerance => "relative change of the objective below tolerance",
            StopReason::StepTolerance => "relative step below tolerance",
            StopReason::GradientTolerance => "first-order optimality (gradient below tolerance)",
            StopReason::MaxIterations => "maximum number of iterations reached",
        })
    }
}

/// The result of a fit. All values physical.
#[derive(Clone, Debug)]
pub struct Fit {
    /// The parameters at the best point found, in their units.
    pub x: Vec<f64>,
    /// `1/2 sum r_i^2` at `x` [-].
    pub objective: f64,
    /// Trial steps taken (accepted or rejected).
    pub iterations: usize,
    /// Calls to [`LeastSquares::evaluate`], with or without Jacobian, failed ones included.
    pub evaluations: usize,
    /// Calls that requested the Jacobian.
    pub jacobian_evaluations: usize,
    /// Calls that failed (an `Err` or a non-finite value) and were treated as rejected steps.
    pub failed_evaluations: usize,
    /// Why the iteration stopped.
    pub stop: StopReason,
    /// Per parameter: whether it ended at its lower or upper bound.
    pub at_bound: Vec<bool>,
    /// The residuals at `x`.
    pub residuals: Vec<f64>,
    /// `dr/dx` at `x`, physical units (rows residuals, columns parameters).
    pub jacobian: DMatrix<f64>,
}

/// Why a fit could not be run. Failed evaluations after the start are not
/// errors (module docs); these are.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The parameter list does not match the problem.
    #[error("{num_specs} parameter specs for a problem with {num_parameters} parameters")]
    SpecCount { num_specs: usize, num_parameters: usize },
    /// The start vector has the wrong length.
    #[error("the start point has {got} values for {expected} parameters")]
    StartLength { got: usize, expected: usize },
    /// A parameter's bounds are unusable.
    #[error("parameter {name}: bounds [{lower}, {upper}] are invalid: {reason}")]
    InvalidBounds { name: String, lower: f64, upper: f64, reason: &'static str },
    /// The start point is not inside the box.
    #[error("parameter {name}: start value {value} is outside its bounds [{lower}, {upper}]{extra}")]
    StartOutsideBounds { name: String, value: f64, lower: f64, upper: f64, extra: &'static str },
    /// The problem could not be evaluated at the start point.
    #[error("evaluation at the start point failed: {0}")]
    StartEvaluation(#[source] EvalError),
    /// The problem returned no residuals.
    #[error("the problem returned no residuals")]
    NoResiduals,
    /// The number of residuals changed between evaluations.
    #[error("the problem returned {got} residuals after {expected} at the start point; it must return the same number at every point")]
    ResidualCount { got: usize, expected: usize },
    /// A requested Jacobian was not returned.
    #[error("the problem returned no Jacobian although one was requested")]
    MissingJacobian,
    /// The Jacobian has the wrong shape.
    #[error("the Jacobian is {rows} x {cols}, expected {expected_rows} x {expected_cols} (residuals x parameters)")]
    JacobianShape { rows: usize, cols: usize, expected_rows: usize, expected_cols: usize },
    /// Multi-start needs finite bounds to place its starts.
    #[error(
        "parameter {name}: multi-start needs finite bounds (positive for a log parameter), got [{lower}, {upper}]"
    )]
    UnboundedParameter { name: String, lower: f64, upper: f64 },
    /// Every start of a multi-start failed; the first start's error is kept.
    #[error("all {num_starts} starts failed; start 0: {first}")]
    AllStartsFailed {
        num_starts: usize,
        #[source]
        first: Box<FitError>,
    },
}

/// Fits `problem` from `x0` within the box of `specs` (module docs for the
/// method and the stopping rules).
///
/// `x0` must lie inside the bounds (strictly positive for log parameters). Fails
/// only on malformed input or when the start point itself cannot be evaluated.
pub fn levenberg_marquardt<P: LeastSquares + ?Sized>(
    problem: &P,
    specs: &[ParameterSpec],
    x0: &[f64],
    options: &Options,
) -> Result<Fit, FitError> {
    validate(problem, specs, x0)?;
    assert!(
        options.objective_tolerance >= 0.0 && options.step_tolerance >= 0.0 && options.gradient_tolerance >= 0.0,
        "tolerances must be non-negative"
    );
    assert!(
        options.initial_trust_radius > 0.0 && options.initial_trust_radius.is_finite(),
        "initial_trust_radius must be positive"
    );
    Solver::new(problem, specs, x0).run(options)
}

/// Checks specs and start point against the problem.
pub(crate) fn validate<P: LeastSquares + ?Sized>(
    problem: &P,
    specs: &[ParameterSpec],
    x0: &[f64],
) -> Result<(), FitError> {
    if specs.len() != problem.num_parameters() {
        return Err(FitError::SpecCount { num_specs: specs.len(), num_parameters: problem.num_parameters() });
    }
    if x0.len() != specs.len() {
        return Err(FitError::StartLength { got: x0.len(), expected: specs.len() });
    }
    for (spec, &value) in specs.iter().zip(x0) {
        spec.validate()?;
        let extra = if spec.scale == Scale::Log && value <= 0.0 { " (a log parameter must be positive)" } else { "" };
        if !value.is_finite() || value < spec.lower || value > spec.upper || !extra.is_empty() {
            return Err(FitError::StartOutsideBounds {
                name: spec.name.clone(),
                value,
                lower: spec.lower,
                upper: spec.upper,
                extra,
            });
        }
    }
    Ok(())
}

/// The box in solver coordinates and the per-parameter step scales.
struct Domain<'a> {
    specs: &'a [ParameterSpec],
    lower: Vec<f64>,
    upper: Vec<f64>,
    /// Tolerance for "at a bound" in solver coordinates.
    bound_tolerance: Vec<f64>,
    /// Linear parameters: the floor of the step measure's denominator.
    floor: Vec<f64>,
}

impl<'a> Domain<'a> {
    fn new(specs: &'a [ParameterSpec], x0: &[f64]) -> Self {
        let (lower, upper): (Vec<f64>, Vec<f64>) = specs.iter().map(ParameterSpec::solver_bounds).unzip();
        let bound_tolerance = lower
            .iter()
            .zip(&upper)
            .map(|(l, u)| 1e-12 * [l.abs(), u.abs()].into_iter().filter(|b| b.is_finite()).fold(0.0, f64::max))
            .collect();
        let floor = specs
            .iter()
            .zip(x0)
            .map(|(spec, &x)| {
                let width = spec.upper - spec.lower;
                if width.is_finite() && width > 0.0 {
                    1e-3 * width
                } else if x != 0.0 {
                    1e-3 * x.abs()
                } else {
                    1e-3
                }
            })
            .collect();
        Self { specs, lower, upper, bound_tolerance, floor }
    }

    fn physical(&self, y: &[f64]) -> Vec<f64> {
        self.specs.iter().zip(y).map(|(spec, &v)| spec.to_physical(v)).collect()
    }

    /// `dr/dy` from `dr/dx`: column `j` times `x_j` for log parameters.
    fn solver_jacobian(&self, jacobian_x: &DMatrix<f64>, x: &[f64]) -> DMatrix<f64> {
        let mut jacobian_y = jacobian_x.clone();
        for (j, spec) in self.specs.iter().enumerate() {
            if spec.scale == Scale::Log {
                jacobian_y.column_mut(j).scale_mut(x[j]);
            }
        }
        jacobian_y
    }

    /// The size against which a step in coordinate `j` is measured.
    fn typical(&self, j: usize, x: f64) -> f64 {
        match self.specs[j].scale {
            Scale::Log => 1.0,
            Scale::Linear => x.abs().max(self.floor[j]),
        }
    }

    fn at_lower(&self, j: usize, y: f64) -> bool {
        y <= self.lower[j] + self.bound_tolerance[j]
    }

    fn at_upper(&self, j: usize, y: f64) -> bool {
        y >= self.upper[j] - self.bound_tolerance[j]
    }
}

/// A successfully evaluated point.
struct Point {
    y: Vec<f64>,
    x: Vec<f64>,
    residuals: DVector<f64>,
    objective: f64,
    jacobian_x: Option<DMatrix<f64>>,
}

#[derive(Default)]
struct Counters {
    evaluations: usize,
    jacobian_evaluations: usize,
    failed_evaluations: usize,
}

/// The trust-region subproblem on a set of free columns, through the SVD of
/// the scaled Jacobian (module docs).
struct Subproblem {
    free: Vec<usize>,
    /// Kept singular values `s_k`.
    singular_values: Vec<f64>,
    /// `s_k * (U^T r)_k`.
    weights: Vec<f64>,
    /// `(U^T r)_k`.
    projections: Vec<f64>,
    /// Kept right singular vectors, one column each (free.len() rows).
    right: DMatrix<f64>,
}

impl Subproblem {
    fn new(jacobian_scaled: &DMatrix<f64>, residuals: &DVector<f64>, free: Vec<usize>) -> Self {
        let mut singular_values = Vec::new();
        let mut weights = Vec::new();
        let mut projections = Vec::new();
        let mut right_columns = Vec::new();
        if !free.is_empty() {
            let columns = jacobian_scaled.select_columns(&free);
            let (rows, cols) = columns.shape();
            let svd = columns.svd(true, true);
            let (u, v_t) = (svd.u.expect("U requested"), svd.v_t.expect("V requested"));
            let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
            let threshold = f64::EPSILON * rows.max(cols) as f64 * largest;
            for (k, &s) in svd.singular_values.iter().enumerate() {
                if s > threshold && s > 0.0 {
                    let c = u.column(k).dot(residuals);
                    singular_values.push(s);
                    weights.push(s * c);
                    projections.push(c);
                    right_columns.push(v_t.row(k).transpose());
                }
            }
        }
        let right = if right_columns.is_empty() {
            DMatrix::zeros(free.len(), 0)
        } else {
            DMatrix::from_columns(&right_columns)
        };
        Self { free, singular_values, weights, projections, right }
    }

    /// `1/2 |P r|^2`: the reduction of the full Gauss-Newton step.
    fn gauss_newton_decrement(&self) -> f64 {
        0.5 * self.projections.iter().map(|c| c * c).sum::<f64>()
    }

    /// `|D p(lambda)|`.
    fn step_norm(&self, lambda: f64) -> f64 {
        self.singular_values.iter().zip(&self.weights).map(|(s, w)| (w / (s * s + lambda)).powi(2)).sum::<f64>().sqrt()
    }

    /// `D p(lambda)` on the free coordinates.
    fn scaled_step(&self, lambda: f64) -> DVector<f64> {
        let mut step = DVector::zeros(self.free.len());
        for (k, (s, w)) in self.singular_values.iter().zip(&self.weights).enumerate() {
            step.axpy(-w / (s * s + lambda), &self.right.column(k), 1.0);
        }
        step
    }

    /// The damping `lambda >= 0` whose step fits the radius: 0 if the
    /// Gauss-Newton step does, else `|D p| = radius` to within 10 % (Moré's
    /// Newton iteration on `1/|D p| - 1/radius`, safeguarded by bisection).
    fn damping_for(&self, radius: f64) -> f64 {
        let norm0 = self.step_norm(0.0);
        if norm0 <= radius {
            return 0.0;
        }
        let gradient_norm = self.weights.iter().map(|w| w * w).sum::<f64>().sqrt();
        let (mut low, mut high) = (0.0_f64, gradient_norm / radius);
        let mut lambda = 0.0;
        for _ in 0..100 {
            let norm = self.step_norm(lambda);
            if (norm - radius).abs() <= 0.1 * radius {
                break;
            }
            if norm > radius {
                low = lambda;
            } else {
                high = lambda;
            }
            // d|Dp|/dlambda = -sum w^2 / (s^2 + lambda)^3 / |Dp|
            let derivative = -self
                .singular_values
                .iter()
                .zip(&self.weights)
                .map(|(s, w)| w * w / (s * s + lambda).powi(3))
                .sum::<f64>()
                / norm;
            let newton = lambda + (norm / radius) * (radius - norm) / derivative;
            lambda = if newton > low && newton < high && newton.is_finite() {
                newton
            } else {
                (0.001 * high).max((low * high).sqrt())
            };
        }
        lambda
    }
}

/// The predicted reduction of a step: `f - 1/2 |r + J p|^2 = -g.p - 1/2 |J p|^2`.
fn predicted_reduction(jacobian_y: &DMatrix<f64>, gradient: &DVector<f64>, step: &DVector<f64>) -> f64 {
    -gradient.dot(step) - 0.5 * (jacobian_y * step).norm_squared()
}

struct Solver<'a, P: ?Sized> {
    problem: &'a P,
    domain: Domain<'a>,
    x0: &'a [f64],
    counters: Counters,
}

/// What an evaluation gave: a point, or a failure to be treated as a rejected step.
enum Outcome {
    Evaluated(Point),
    Failed(EvalError),
}

impl<'a, P: LeastSquares + ?Sized> Solver<'a, P> {
    fn new(problem: &'a P, specs: &'a [ParameterSpec], x0: &'a [f64]) -> Self {
        Self { problem, domain: Domain::new(specs, x0), x0, counters: Counters::default() }
    }

    /// Evaluates at solver coordinates `y`. Structural faults of the problem
    /// (wrong sizes, a missing Jacobian) are errors; failures are outcomes.
    fn evaluate(
        &mut self,
        y: Vec<f64>,
        want_jacobian: bool,
        expected_residuals: Option<usize>,
    ) -> Result<Outcome, FitError> {
        let x = self.domain.physical(&y);
        self.counters.evaluations += 1;
        if want_jacobian {
            self.counters.jacobian_evaluations += 1;
        }
        let evaluation = match self.problem.evaluate(&x, want_jacobian) {
            Ok(evaluation) => evaluation,
            Err(error) => {
                self.counters.failed_evaluations += 1;
                return Ok(Outcome::Failed(error));
            }
        };
        let m = evaluation.residuals.len();
        if m == 0 {
            return Err(FitError::NoResiduals);
        }
        if let Some(expected) = expected_residuals {
            if m != expected {
                return Err(FitError::ResidualCount { got: m, expected });
            }
        }
        let n = self.domain.specs.len();
        let jacobian_x = if want_jacobian {
            let jacobian = evaluation.jacobian.ok_or(FitError::MissingJacobian)?;
            if jacobian.shape() != (m, n) {
                return Err(FitError::JacobianShape {
                    rows: jacobian.nrows(),
                    cols: jacobian.ncols(),
                    expected_rows: m,
                    expected_cols: n,
                });
            }
            Some(jacobian)
        } else {
            None
        };
        let residuals = DVector::from_vec(evaluation.residuals);
        let objective = 0.5 * residuals.norm_squared();
        let finite_jacobian = jacobian_x.as_ref().is_none_or(|j| j.iter().all(|v| v.is_finite()));
        if !objective.is_finite() || !finite_jacobian {
            self.counters.failed_evaluations += 1;
            let what = if objective.is_finite() { "Jacobian" } else { "residual" };
            return Ok(Outcome::Failed(EvalError::new(format!("non-finite {what} at x = {x:?}"))));
        }
        Ok(Outcome::Evaluated(Point { y, x, residuals, objective, jacobian_x }))
    }

    fn run(mut self, options: &Options) -> Result<Fit, FitError> {
        let n = self.domain.specs.len();
        let y0: Vec<f64> = self.domain.specs.iter().zip(self.x0).map(|(s, &x)| s.to_solver(x)).collect();
        let mut current = match self.evaluate(y0, true, None)? {
            Outcome::Evaluated(point) => point,
            Outcome::Failed(error) => {
                return Err(FitError::StartEvaluation(error));
            }
        };
        let m = current.residuals.len();
        let mut jacobian_y =
            self.domain.solver_jacobian(current.jacobian_x.as_ref().expect("requested at the start"), &current.x);
        // Moré's scaling: the largest column norms seen so far (1 for a zero column).
        let mut scale: Vec<f64> =
            jacobian_y.column_iter().map(|c| c.norm()).map(|v| if v > 0.0 { v } else { 1.0 }).collect();
        let typical_size =
            (0..n).map(|j| (scale[j] * self.domain.typical(j, current.x[j])).powi(2)).sum::<f64>().sqrt();
        let mut radius = options.initial_trust_radius * typical_size;
        if !(radius > 0.0 && radius.is_finite()) {
            radius = options.initial_trust_radius;
        }
        let mut iterations = 0;

        let stop = loop {
            let objective = current.objective;
            if objective <= 0.0 {
                break StopReason::GradientTolerance;
            }
            let residuals = &current.residuals;
            let gradient = jacobian_y.tr_mul(residuals);
            let y = &current.y;
            // Held: at a bound with the gradient pointing out of the box.
            let held = |j: usize| {
                (self.domain.at_lower(j, y[j]) && gradient[j] > 0.0)
                    || (self.domain.at_upper(j, y[j]) && gradient[j] < 0.0)
            };
            let free: Vec<usize> = (0..n).filter(|&j| !held(j)).collect();

            // 1. First-order optimality (MINPACK's cosine test on the free columns).
            let residual_norm = residuals.norm();
            let largest_cosine = free
                .iter()
                .map(|&j| {
                    let column_norm = jacobian_y.column(j).norm();
                    if column_norm > 0.0 {
                        gradient[j].abs() / (column_norm * residual_norm)
                    } else {
                        0.0
                    }
                })
                .fold(0.0, f64::max);
            if largest_cosine <= options.gradient_tolerance {
                break StopReason::GradientTolerance;
            }

            // 2. The Gauss-Newton decrement.
            let mut jacobian_scaled = jacobian_y.clone();
            for (j, d) in scale.iter().enumerate() {
                jacobian_scaled.column_mut(j).unscale_mut(*d);
            }
            let mut subproblem = Subproblem::new(&jacobian_scaled, residuals, free);
            if subproblem.gauss_newton_decrement() <= options.objective_tolerance * objective {
                break StopReason::ObjectiveTolerance;
            }
            if iterations >= options.max_iterations {
                break StopReason::MaxIterations;
            }
            iterations += 1;

            // The step of the free parameters; a parameter at a bound whose
            // step points out of the box is held and the subproblem solved again.
            let step = loop {
                let lambda = subproblem.damping_for(radius);
                let scaled = subproblem.scaled_step(lambda);
                let mut step = DVector::zeros(n);
                for (k, &j) in subproblem.free.iter().enumerate() {
                    step[j] = scaled[k] / scale[j];
                }
                let blocked = |j: &usize| {
                    (self.domain.at_lower(*j, y[*j]) && step[*j] < 0.0)
                        || (self.domain.at_upper(*j, y[*j]) && step[*j] > 0.0)
                };
                if !subproblem.free.iter().any(blocked) {
                    break step;
                }
                let still_free: Vec<usize> = subproblem.free.iter().copied().filter(|j| !blocked(j)).collect();
                subproblem = Subproblem::new(&jacobian_scaled, residuals, still_free);
            };

            // Feasible candidates: projected and shortened.
            let projected: Vec<f64> =
                (0..n).map(|j| (y[j] + step[j]).clamp(self.domain.lower[j], self.domain.upper[j])).collect();
            let mut fraction = 1.0_f64;
            let mut limiting = None;
            for j in 0..n {
                let room = if step[j] > 0.0 {
                    (self.domain.upper[j] - y[j]) / step[j]
                } else if step[j] < 0.0 {
                    (self.domain.lower[j] - y[j]) / step[j]
                } else {
                    f64::INFINITY
                };
                if room < fraction {
                    fraction = room.max(0.0);
                    limiting = Some(j);
                }
            }
            let mut shortened: Vec<f64> =
                (0..n).map(|j| (y[j] + fraction * step[j]).clamp(self.domain.lower[j], self.domain.upper[j])).collect();
            if let Some(j) = limiting {
                shortened[j] = if step[j] > 0.0 { self.domain.upper[j] } else { self.domain.lower[j] };
            }
            let difference = |target: &[f64]| DVector::from_iterator(n, (0..n).map(|j| target[j] - y[j]));
            let (projected_step, shortened_step) = (difference(&projected), difference(&shortened));
            let projected_gain = predicted_reduction(&jacobian_y, &gradient, &projected_step);
            let shortened_gain = predicted_reduction(&jacobian_y, &gradient, &shortened_step);
            let (trial_y, step, predicted) = if projected_gain >= shortened_gain {
                (projected, projected_step, projected_gain)
            } else {
                (shortened, shortened_step, shortened_gain)
            };
            if predicted.is_nan() || predicted <= 0.0 {
                // The model cannot decrease: numerically stationary.
                break StopReason::GradientTolerance;
            }
            let step_norm = (0..n).map(|j| (scale[j] * step[j]).powi(2)).sum::<f64>().sqrt();
            let relative_step =
                (0..n).map(|j| step[j].abs() / self.domain.typical(j, current.x[j])).fold(0.0, f64::max);

            // Evaluate the trial point.
            let trial = match self.evaluate(trial_y, options.jacobian_with_trial, Some(m))? {
                Outcome::Evaluated(trial) if objective - trial.objective > 1e-4 * predicted => trial,
                _ => {
                    // Rejected (no decrease, or the evaluation failed).
                    radius = 0.25 * step_norm;
                    if relative_step <= options.step_tolerance {
                        break StopReason::StepTolerance;
                    }
                    continue;
                }
            };
            let trial = match trial.jacobian_x {
                Some(_) => trial,
                None => match self.evaluate(trial.y, true, Some(m))? {
                    Outcome::Evaluated(point) => point,
                    Outcome::Failed(_) => {
                        radius = 0.25 * step_norm;
                        if relative_step <= options.step_tolerance {
                            break StopReason::StepTolerance;
                        }
                        continue;
                    }
                },
            };
            let actual = objective - trial.objective;
            let ratio = actual / predicted;
            current = trial;
            jacobian_y = self.domain.solver_jacobian(current.jacobian_x.as_ref().expect("evaluated"), &current.x);
            for (j, d) in scale.iter_mut().enumerate() {
                *d = d.max(jacobian_y.column(j).norm());
            }
            if ratio < 0.25 {
                radius = 0.5 * step_norm;
            } else if ratio > 0.75 {
                radius = radius.max(2.0 * step_norm);
            }
            if actual <= options.objective_tolerance * objective && predicted <= options.objective_tolerance * objective
            {
                break StopReason::ObjectiveTolerance;
            }
            if relative_step <= options.step_tolerance {
                break StopReason::StepTolerance;
            }
        };

        let at_bound =
            (0..n).map(|j| self.domain.at_lower(j, current.y[j]) || self.domain.at_upper(j, current.y[j])).collect();
        Ok(Fit {
            x: current.x,
            objective: current.objective,
            iterations,
            evaluations: self.counters.evaluations,
            jacobian_evaluations: self.counters.jacobian_evaluations,
            failed_evaluations: self.counters.failed_evaluations,
            stop,
            at_bound,
            residuals: current.residuals.as_slice().to_vec(),
            jacobian: current.jacobian_x.expect("the current point always has its Jacobian"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_problems::{ExponentialDecay, Linear, Rosenbrock};
    use proptest::prelude::*;

    #[test]
    fn linear_least_squares_is_solved_exactly() {
        let problem = Linear::example();
        let specs = problem.specs();
        let fit = levenberg_marquardt(&problem, &specs, &[0.0, 0.0, 0.0], &Options::default()).unwrap();
        let exact = problem.solution();
        for (j, (x, expected)) in fit.x.iter().zip(&exact).enumerate() {
            assert!((x - expected).abs() < 1e-10, "x{j}: {x} vs {expected}");
        }
        assert!(fit.stop.converged());
        assert_eq!(fit.evaluations, fit.jacobian_evaluations);
        assert_eq!(fit.failed_evaluations, 0);
    }

    #[test]
    fn rosenbrock_converges_to_one_one() {
        let specs = vec![ParameterSpec::linear("x1", -5.0, 5.0), ParameterSpec::linear("x2", -5.0, 5.0)];
        let fit = levenberg_marquardt(&Rosenbrock, &specs, &[-1.2, 1.0], &Options::default()).unwrap();
        assert!((fit.x[0] - 1.0).abs() < 1e-8 && (fit.x[1] - 1.0).abs() < 1e-8, "{:?} after {}", fit.x, fit.iterations);
        assert!(fit.stop.converged(), "{}", fit.stop);
        assert!(fit.iterations < 40, "{} iterations", fit.iterations);
        assert!(fit.at_bound.iter().all(|&b| !b));
    }

    #[test]
    fn rosenbrock_converges_without_bounds_and_with_jacobians_on_acceptance() {
        let inf = f64::INFINITY;
        let specs = vec![ParameterSpec::linear("x1", -inf, inf), ParameterSpec::linear("x2", -inf, inf)];
        let options = Options { jacobian_with_trial: false, ..Options::default() };
        let fit = levenberg_marquardt(&Rosenbrock, &specs, &[-1.2, 1.0], &options).unwrap();
        assert!((fit.x[0] - 1.0).abs() < 1e-8 && (fit.x[1] - 1.0).abs() < 1e-8, "{:?}", fit.x);
        // Residual-only trial evaluations plus one Jacobian per accepted step.
        assert!(fit.jacobian_evaluations < fit.evaluations);
        assert_eq!(fit.evaluations, fit.iterations + fit.jacobian_evaluations);
    }

    #[test]
    fn exponential_decay_recovers_noise_free_parameters() {
        let problem = ExponentialDecay::noise_free(2.0, 1.3, 12);
        let specs = ExponentialDecay::specs();
        let fit = levenberg_marquardt(&problem, &specs, &[0.5, 0.2], &Options::default()).unwrap();
        assert!((fit.x[0] - 2.0).abs() < 1e-8 && (fit.x[1] - 1.3).abs() < 1e-8, "{:?}", fit.x);
    }

    /// (d) The unconstrained optimum of the slope is 2, the box stops it at 1.5.
    #[test]
    fn bound_active_fit_stops_at_the_bound() {
        let problem = Linear::line(1.0, 2.0);
        let specs = vec![ParameterSpec::linear("a", -10.0, 10.0), ParameterSpec::linear("b", -1.0, 1.5)];
        let fit = levenberg_marquardt(&problem, &specs, &[0.0, 0.0], &Options::default()).unwrap();
        assert_eq!(fit.at_bound, vec![false, true]);
        assert_eq!(fit.x[1], 1.5, "a parameter at a bound is the bound, bit for bit");
        // With b held at 1.5 the intercept is the mean of y - 1.5 t.
        let expected_a = problem.conditional_intercept(1.5);
        assert!((fit.x[0] - expected_a).abs() < 1e-10, "{} vs {expected_a}", fit.x[0]);
        assert_eq!(fit.stop, StopReason::GradientTolerance);
    }

    /// (d) The same on a log scale: the decay rate wants 1.3 but may not exceed 1.
    #[test]
    fn log_parameter_stops_at_its_upper_bound() {
        let problem = ExponentialDecay::noise_free(2.0, 1.3, 12);
        let specs = vec![ParameterSpec::log("A", 0.01, 100.0), ParameterSpec::log("k", 0.01, 1.0)];
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 0.1], &Options::default()).unwrap();
        assert_eq!(fit.at_bound, vec![false, true]);
        assert_eq!(fit.x[1], 1.0);
        assert!(fit.stop.converged());
    }

    /// (f) Evaluations fail for k > 3: the first, long step lands there, and the
    /// trust region shrinks until the fit converges anyway.
    #[test]
    fn failed_evaluations_shrink_the_trust_region() {
        let mut problem = ExponentialDecay::noise_free(2.0, 1.3, 12);
        problem.fail_above_rate = Some(3.0);
        let specs = ExponentialDecay::specs();
        let options = Options { initial_trust_radius: 100.0, ..Options::default() };
        let fit = levenberg_marquardt(&problem, &specs, &[0.5, 0.2], &options).unwrap();
        assert!(fit.failed_evaluations >= 1, "the test must hit the failing region");
        assert!((fit.x[0] - 2.0).abs() < 1e-8 && (fit.x[1] - 1.3).abs() < 1e-8, "{:?}", fit.x);
        assert!(fit.stop.converged());
    }

    #[test]
    fn failure_at_the_start_is_an_error() {
        let mut problem = ExponentialDecay::noise_free(2.0, 1.3, 12);
        problem.fail_above_rate = Some(3.0);
        let error = levenberg_marquardt(&problem, &ExponentialDecay::specs(), &[1.0, 5.0], &Options::default());
        assert!(matches!(error, Err(FitError::StartEvaluation(_))), "{error:?}");
    }

    #[test]
    fn malformed_input_is_refused() {
        let problem = ExponentialDecay::noise_free(2.0, 1.3, 12);
        let specs = ExponentialDecay::specs();
        let fit = |specs: &[ParameterSpec], x0: &[f64]| levenberg_marquardt(&problem, specs, x0, &Options::default());
        assert!(matches!(fit(&specs[..1], &[1.0]), Err(FitError::SpecCount { .. })));
        assert!(matches!(fit(&specs, &[1.0]), Err(FitError::StartLength { .. })));
        assert!(matches!(fit(&specs, &[1.0, 1e9]), Err(FitError::StartOutsideBounds { .. })));
        let bad = vec![ParameterSpec::log("A", -1.0, 10.0), specs[1].clone()];
        assert!(matches!(fit(&bad, &[1.0, 1.0]), Err(FitError::InvalidBounds { .. })));
        let reversed = vec![ParameterSpec::linear("A", 5.0, 1.0), specs[1].clone()];
        let message = fit(&reversed, &[1.0, 1.0]).unwrap_err().to_string();
        assert!(message.contains("parameter A") && message.contains("lower bound above upper"), "{message}");
    }

    /// (h) Each stopping rule, isolated by switching the others off.
    #[test]
    fn stopping_rules_report_their_reason() {
        let problem = ExponentialDecay::noisy(2.0, 1.3, 0.05, 0.05, 20, 11);
        let specs = ExponentialDecay::specs();
        let x0 = [0.5, 0.2];
        let run = |options: Options| levenberg_marquardt(&problem, &specs, &x0, &options).unwrap();
        let off = Options {
            objective_tolerance: 0.0,
            step_tolerance: 0.0,
            gradient_tolerance: 0.0,
            max_iterations: 200,
            ..Options::default()
        };

        let objective = run(Options { objective_tolerance: 1e-6, ..off.clone() });
        assert_eq!(objective.stop, StopReason::ObjectiveTolerance);
        let step = run(Options { step_tolerance: 1e-6, ..off.clone() });
        assert_eq!(step.stop, StopReason::StepTolerance);
        let gradient = run(Options { gradient_tolerance: 1e-8, ..off.clone() });
        assert_eq!(gradient.stop, StopReason::GradientTolerance);
        let capped = run(Options { max_iterations: 2, ..Options::default() });
        assert_eq!(capped.stop, StopReason::MaxIterations);
        assert_eq!(capped.iterations, 2);
        assert!(!capped.stop.converged());

        // All three converged to the same point, within what their tolerances allow.
        for fit in [&objective, &step, &gradient] {
            assert!((fit.x[0] - objective.x[0]).abs() < 1e-5 * objective.x[0], "{:?}", fit.x);
            assert!((fit.x[1] - objective.x[1]).abs() < 1e-5 * objective.x[1], "{:?}", fit.x);
        }

        // A linear problem: after the exact step nothing is left to gain.
        let linear = Linear::example();
        let fit = levenberg_marquardt(&linear, &linear.specs(), &[0.0; 3], &Options::default()).unwrap();
        assert!(matches!(fit.stop, StopReason::GradientTolerance | StopReason::ObjectiveTolerance), "{}", fit.stop);
    }

    /// The log transform's chain rule against central differences in ln x.
    #[test]
    fn solver_jacobian_matches_finite_differences_in_ln_x() {
        let problem = ExponentialDecay::noisy(2.0, 1.3, 0.05, 0.05, 9, 4);
        let specs = vec![ParameterSpec::log("A", 1e-3, 1e3), ParameterSpec::linear("k_per_s", 0.0, 10.0)];
        let x = [1.7, 0.9];
        let domain = Domain::new(&specs, &x);
        let evaluation = problem.evaluate(&x, true).unwrap();
        let analytic = domain.solver_jacobian(evaluation.jacobian.as_ref().unwrap(), &x);
        let y: Vec<f64> = specs.iter().zip(&x).map(|(s, &v)| s.to_solver(v)).collect();
        let h = 1e-6;
        for j in 0..2 {
            let shifted = |delta: f64| {
                let mut y = y.clone();
                y[j] += delta;
                problem.evaluate(&domain.physical(&y), false).unwrap().residuals
            };
            let (plus, minus) = (shifted(h), shifted(-h));
            for i in 0..9 {
                let numeric = (plus[i] - minus[i]) / (2.0 * h);
                // Central differences: truncation ~h^2, rounding ~eps |r| / h.
                assert!((numeric - analytic[(i, j)]).abs() < 1e-6 * (1.0 + numeric.abs()), "({i}, {j})");
            }
        }
    }

    #[test]
    fn bounds_map_back_bit_for_bit() {
        for spec in [ParameterSpec::log("E_MPa", 0.0123, 45.6), ParameterSpec::linear("nu", 0.0, 0.499)] {
            let (low, high) = spec.solver_bounds();
            assert_eq!(spec.to_physical(low), spec.lower);
            assert_eq!(spec.to_physical(high), spec.upper);
            assert_eq!(spec.to_physical(high + 1.0), spec.upper);
            let inside = spec.to_physical(0.5 * (low + high));
            assert!(inside > spec.lower && inside < spec.upper);
        }
    }

    /// A parameter that does not affect the residuals (zero Jacobian column)
    /// stays where it started and does not disturb the others.
    #[test]
    fn ineffective_parameter_is_left_alone() {
        let problem = Linear::with_dead_column();
        let specs = problem.specs();
        let fit = levenberg_marquardt(&problem, &specs, &[0.0, 0.0, 0.7], &Options::default()).unwrap();
        assert!((fit.x[2] - 0.7).abs() < 1e-12);
        let exact = problem.solution();
        assert!((fit.x[0] - exact[0]).abs() < 1e-10 && (fit.x[1] - exact[1]).abs() < 1e-10);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Bounded linear least squares from random boxes and starts: the fit
        /// stays in the box and reaches the bounded optimum (found by trying every
        /// assignment of free / lower / upper) to within the objective tolerance.
        #[test]
        fn bounded_linear_fits_reach_the_optimum(
            seed in 0u64..1000,
            low in proptest::collection::vec(-3.0..0.5_f64, 3),
            width in proptest::collection::vec(0.1..4.0_f64, 3),
            start in proptest::collection::vec(0.0..1.0_f64, 3),
        ) {
            let problem = Linear::random(seed, 15, 3);
            let specs: Vec<ParameterSpec> = (0..3)
                .map(|j| ParameterSpec::linear(format!("x{j}"), low[j], low[j] + width[j]))
                .collect();
            let x0: Vec<f64> = (0..3).map(|j| low[j] + start[j] * width[j]).collect();
            let fit = levenberg_marquardt(&problem, &specs, &x0, &Options::default()).unwrap();
            prop_assert!(fit.stop.converged());
            for ((x, spec), at_bound) in fit.x.iter().zip(&specs).zip(&fit.at_bound) {
                prop_assert!(*x >= spec.lower && *x <= spec.upper);
                // Bit-exact: a parameter at a bound is set to the bound itself.
                let on_bound = *x == spec.lower || *x == spec.upper;
                prop_assert_eq!(*at_bound, on_bound);
            }
            let best = problem.bounded_optimum(&specs);
            // ftol = 1e-6 bounds the relative gain left; 1e-5 leaves room for
            // the last step's model error.
            prop_assert!(fit.objective <= best * (1.0 + 1e-5), "{} vs {}", fit.objective, best);
        }
    }
}
