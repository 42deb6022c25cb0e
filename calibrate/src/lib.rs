//! # wagashi calibrate
//!
//! Parameter identification for wagashi: finds the material parameters (moduli
//! E1, E2 in MPa, viscosities c1..c3 in MPa s, Poisson's ratio nu, ...) whose
//! simulations best match measured trials, says how well the data determine
//! them, and warns when they do not. Two layers:
//!
//! - the numerical core (below): bounded least squares, multi-start, intervals,
//!   profiles, warnings, for any [`LeastSquares`] problem;
//! - the physics glue: [`trial`] turns experiment bundles into residuals with exact
//!   Jacobians (the engine's forward sensitivities: at most one extra solve per
//!   parameter and step, batched), [`procedure`] runs the seed paper's three steps (two parameter
//!   sets) or a joint fit over them. `wagashi fit` is a thin shell around
//!   [`procedure::run`];
//! - [`diagnosis`]: the sim-to-real gap diagnosis over the effect library
//!   (baseline, numerical-error budget, WHERE, WHICH, HOW FAR); `wagashi
//!   diagnose` is a thin shell around [`diagnosis::diagnose`].
//!
//! Each evaluation is a finite-element simulation (0.05 to 20 s), so the
//! methods here are frugal with evaluations, use the exact Jacobians the engine's
//! forward sensitivities provide, and treat a failed simulation (an inverted
//! element at wild parameters) as a rejected step, never a crash.
//!
//! ## Principal types
//!
//! - [`LeastSquares`]: the problem. Residuals weighted by the measurement noise,
//!   `r_i = (sim_i - meas_i) / sigma_i`, and `dr/dx` in physical units.
//! - [`ParameterSpec`]: a parameter's name, bounds and [`Scale`] (`Log`: the
//!   solver works in `ln x`; `Linear`: in `x`).
//! - [`levenberg_marquardt`] ([`lsq`]): bounded trust-region Levenberg-Marquardt
//!   with the seed's `lsqnonlin`-like stopping rules; returns a [`Fit`] (the
//!   parameters, objective, counts, [`StopReason`], which parameters sit at a
//!   bound, residuals and Jacobian).
//! - [`multistart()`] ([`mod@multistart`]): the fit from `x0` and from Latin hypercube
//!   starts, in parallel, deterministic for any number of threads.
//! - [`uncertainty()`] ([`mod@uncertainty`]): Gauss-Newton covariance, 95 % intervals
//!   (asymmetric for log parameters), correlations, rank and conditioning.
//! - [`profile()`] ([`mod@profile`]): profile likelihood of one parameter, its 95 %
//!   interval and whether it is flat.
//! - [`Warning`] ([`warning`]): identifiability problems in plain words.
//!
//! Objective: `f = 1/2 sum r_i^2`. With noise-weighted residuals, `2 f / (m - n)`
//! is about 1 when the model fits to within the noise.
//!
//! ## Example
//!
//! Fit `y = A exp(-k t)` to noisy data, then look at the intervals.
//!
//! ```
//! use calibrate::{
//!     levenberg_marquardt, uncertainty, EvalError, Evaluation, LeastSquares, Options, ParameterSpec,
//! };
//! use calibrate::rng::SplitMix64;
//! use nalgebra::DMatrix;
//!
//! /// A relaxation curve y(t) = A exp(-k t), measured with noise sigma.
//! struct Decay {
//!     times_s: Vec<f64>,
//!     measured: Vec<f64>,
//!     sigma: f64,
//! }
//!
//! impl LeastSquares for Decay {
//!     fn num_parameters(&self) -> usize {
//!         2
//!     }
//!
//!     fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
//!         let (amplitude, rate) = (x[0], x[1]);
//!         let model: Vec<f64> = self.times_s.iter().map(|t| (-rate * t).exp()).collect();
//!         let residuals =
//!             model.iter().zip(&self.measured).map(|(e, y)| (amplitude * e - y) / self.sigma).collect();
//!         let jacobian = want_jacobian.then(|| {
//!             DMatrix::from_fn(model.len(), 2, |i, j| match j {
//!                 0 => model[i] / self.sigma,
//!                 _ => -amplitude * self.times_s[i] * model[i] / self.sigma,
//!             })
//!         });
//!         Ok(Evaluation { residuals, jacobian })
//!     }
//! }
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // 1. Synthetic data: A = 2, k = 1.3 /s, noise 0.02.
//! let mut rng = SplitMix64::new(1);
//! let times_s: Vec<f64> = (0..30).map(|i| 0.1 * i as f64).collect();
//! let measured = times_s.iter().map(|t| 2.0 * (-1.3 * t).exp() + 0.02 * rng.next_gaussian()).collect();
//! let problem = Decay { times_s, measured, sigma: 0.02 };
//!
//! // 2. Both parameters positive and known to within decades: log scale.
//! let specs = [ParameterSpec::log("A", 1e-2, 1e2), ParameterSpec::log("k_per_s", 1e-3, 1e2)];
//!
//! // 3. Fit from a rough guess.
//! let fit = levenberg_marquardt(&problem, &specs, &[1.0, 0.1], &Options::default())?;
//! assert!(fit.stop.converged());
//! println!("A = {:.4}, k = {:.4} /s after {} evaluations ({})", fit.x[0], fit.x[1], fit.evaluations, fit.stop);
//!
//! // 4. Uncertainty: s^2 near 1 (the model fits to the noise), intervals hold the truth.
//! let result = uncertainty(&specs, &fit)?;
//! assert!(result.residual_variance > 0.5 && result.residual_variance < 1.5);
//! for (name, interval) in result.names.iter().zip(&result.intervals) {
//!     println!("{name}: 95 % in [{:.4}, {:.4}]", interval.lower, interval.upper);
//! }
//! assert!(result.intervals[1].lower < 1.3 && 1.3 < result.intervals[1].upper);
//! assert!(result.warnings.is_empty());
//! # Ok(())
//! # }
//! ```

pub mod diagnosis;
pub mod lsq;
pub mod multistart;
pub mod procedure;
pub mod profile;
pub mod rng;
pub mod seed_gap;
pub mod stats;
pub mod trial;
pub mod uncertainty;
pub mod warning;

#[cfg(test)]
mod test_problems;

pub use lsq::{
    levenberg_marquardt, EvalError, Evaluation, Fit, FitError, LeastSquares, Options, ParameterSpec, Scale, StopReason,
};
pub use multistart::{latin_hypercube, multistart, MultiStart, MultiStartOptions, StartResult};
pub use profile::{profile, Profile, ProfileEnd, ProfilePoint};
pub use uncertainty::{uncertainty, Interval, Uncertainty, UncertaintyError};
pub use warning::{Side, Term, Warning};
