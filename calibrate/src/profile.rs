//! Profile likelihood: one parameter held at a sequence of values, the others
//! refitted at each.
//!
//! # Statistic and interval
//!
//! For parameter `j` held at `v`, let `f_j(v)` be the best objective over the
//! other parameters. With `f*` the fit's objective and `s^2 = 2 f* / (m - n)`
//! ([`crate::uncertainty`](mod@crate::uncertainty)), the profile statistic is
//!
//! ```text
//! W(v) = 2 (f_j(v) - f*) / s^2,
//! ```
//!
//! and the 95 % profile interval is where `W <= t_{0.975, m-n}^2`. That threshold
//! is the 0.95 quantile of F(1, m - n), the exact distribution of `W` for a
//! linear model when `s^2` is estimated from the same residuals; it tends to the
//! chi-square(1) value 3.841 ([`crate::stats::CHI_SQUARE_1_95`]) as `m - n`
//! grows (3.94 at 100 degrees of freedom), and with it the profile interval of
//! a linear model equals the Wald interval of [`crate::uncertainty`](mod@crate::uncertainty) exactly.
//! For a nonlinear model the profile interval follows the real shape of the
//! objective, asymmetric where it is.
//!
//! # Grid
//!
//! Each side of the optimum is walked outward in the parameter's solver
//! coordinate (`ln x` or `x`), the two sides in parallel, each refit starting
//! from the previous point's solution:
//!
//! - `grid_points` steps of `h = 2 t se / grid_points` (`se` the Wald standard
//!   error in that coordinate), so the grid reaches twice the Wald half-width;
//!   when `se` is infinite (an unidentifiable parameter) or zero, `h` is the
//!   distance to the bound over `grid_points` (1 if unbounded);
//! - then up to `grid_points` more steps, each twice the last;
//! - the walk ends where `W` first exceeds the threshold (the interval's end is
//!   interpolated linearly in `sqrt(W)`, exact for a quadratic profile), at the
//!   bound, or where a refit fails.
//!
//! A side that reaches its bound (or the end of the doubling steps) without
//! crossing is *flat*: the data do not bound the parameter on that side.

use crate::lsq::{levenberg_marquardt, EvalError, Evaluation, Fit, FitError, LeastSquares, Options, ParameterSpec};
use crate::uncertainty::{uncertainty, UncertaintyError};
use crate::warning::{Side, Warning};

/// One point of a profile.
#[derive(Clone, Debug, PartialEq)]
pub struct ProfilePoint {
    /// The held parameter's value, in its unit.
    pub value: f64,
    /// The best objective with it held there.
    pub objective: f64,
    /// All parameters at that best fit (the held one included).
    pub x: Vec<f64>,
}

/// How one side of a profile ended.
#[derive(Clone, Debug, PartialEq)]
pub enum ProfileEnd {
    /// The statistic crossed the threshold: the 95 % interval ends at `value`.
    Crossed { value: f64 },
    /// The bound `value` was reached without crossing: flat on this side.
    Flat { value: f64 },
    /// The doubling steps ended at `value` (an unbounded side) without crossing:
    /// flat on this side.
    Open { value: f64 },
    /// The estimate sits on this bound: there is no room to profile.
    AtBound { value: f64 },
    /// A refit failed beyond `last`, the last value profiled.
    Failed { last: f64, message: String },
}

impl ProfileEnd {
    /// The interval's end on this side: the crossing, or as far as the profile
    /// got (infinite for an open side).
    pub fn limit(&self, side: Side) -> f64 {
        match self {
            ProfileEnd::Crossed { value } | ProfileEnd::Flat { value } | ProfileEnd::AtBound { value } => *value,
            ProfileEnd::Open { .. } => match side {
                Side::Lower => f64::NEG_INFINITY,
                _ => f64::INFINITY,
            },
            ProfileEnd::Failed { last, .. } => *last,
        }
    }

    /// Reached the bound or the end of the walk without crossing.
    pub fn is_flat(&self) -> bool {
        matches!(self, ProfileEnd::Flat { .. } | ProfileEnd::Open { .. })
    }
}

/// The profile of one parameter (module docs).
#[derive(Clone, Debug)]
pub struct Profile {
    /// Index of the profiled parameter.
    pub index: usize,
    /// Its name.
    pub name: String,
    /// Points in increasing `value`, the fit itself included.
    pub points: Vec<ProfilePoint>,
    /// The fit's objective `f*`.
    pub best_objective: f64,
    /// `s^2` of the fit.
    pub residual_variance: f64,
    /// The threshold on `W`: `t_{0.975, m-n}^2`.
    pub threshold: f64,
    /// How the walk below the estimate ended.
    pub lower: ProfileEnd,
    /// How the walk above the estimate ended.
    pub upper: ProfileEnd,
}

impl Profile {
    /// `W = 2 (objective - f*) / s^2`.
    pub fn statistic(&self, objective: f64) -> f64 {
        statistic(objective, self.best_objective, self.residual_variance)
    }

    /// The 95 % profile interval (ends as [`ProfileEnd::limit`]).
    pub fn interval(&self) -> (f64, f64) {
        (self.lower.limit(Side::Lower), self.upper.limit(Side::Upper))
    }

    /// Whether the threshold is never crossed on one side or both.
    pub fn is_flat(&self) -> bool {
        self.lower.is_flat() || self.upper.is_flat()
    }

    /// `(value, objective)` pairs, in increasing value.
    pub fn pairs(&self) -> Vec<(f64, f64)> {
        self.points.iter().map(|p| (p.value, p.objective)).collect()
    }

    /// A flat side, and a refit better than the fit.
    pub fn warnings(&self) -> Vec<Warning> {
        let mut warnings = Vec::new();
        let side = match (self.lower.is_flat(), self.upper.is_flat()) {
            (true, true) => Some(Side::Both),
            (true, false) => Some(Side::Lower),
            (false, true) => Some(Side::Upper),
            (false, false) => None,
        };
        if let Some(side) = side {
            warnings.push(Warning::FlatProfile { parameter: self.name.clone(), side });
        }
        let lowest = self.points.iter().min_by(|a, b| a.objective.total_cmp(&b.objective));
        if let Some(point) = lowest {
            // Below by more than the fit's own tolerance could explain.
            if point.objective < self.best_objective * (1.0 - 1e-5) {
                warnings.push(Warning::BetterFitInProfile {
                    parameter: self.name.clone(),
                    value: point.value,
                    objective: point.objective,
                    best: self.best_objective,
                });
            }
        }
        warnings
    }
}

fn statistic(objective: f64, best: f64, residual_variance: f64) -> f64 {
    let excess = objective - best;
    if residual_variance > 0.0 {
        2.0 * excess / residual_variance
    } else if excess > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// The problem with parameter `index` held at `value`.
struct Pinned<'a, P: ?Sized> {
    inner: &'a P,
    index: usize,
    value: f64,
}

impl<P: LeastSquares + ?Sized> LeastSquares for Pinned<'_, P> {
    fn num_parameters(&self) -> usize {
        self.inner.num_parameters() - 1
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        let full = insert(x, self.index, self.value);
        let mut evaluation = self.inner.evaluate(&full, want_jacobian)?;
        if let Some(jacobian) = evaluation.jacobian.take() {
            // A wrongly shaped Jacobian is passed on unchanged for the solver to refuse.
            evaluation.jacobian =
                Some(if self.index < jacobian.ncols() { jacobian.remove_column(self.index) } else { jacobian });
        }
        Ok(evaluation)
    }
}

fn insert(reduced: &[f64], index: usize, value: f64) -> Vec<f64> {
    let mut full = reduced.to_vec();
    full.insert(index, value);
    full
}

fn remove(full: &[f64], index: usize) -> Vec<f64> {
    let mut reduced = full.to_vec();
    reduced.remove(index);
    reduced
}

/// Profiles parameter `index` of a fit (module docs): up to `2 grid_points`
/// refits on each side, with `options` for each refit.
///
/// `specs` and `fit` must belong together (panics otherwise, and on
/// `index >= n` or `grid_points == 0`).
pub fn profile<P: LeastSquares + ?Sized>(
    problem: &P,
    specs: &[ParameterSpec],
    fit: &Fit,
    index: usize,
    grid_points: usize,
    options: &Options,
) -> Result<Profile, UncertaintyError> {
    assert!(index < specs.len(), "parameter index {index} out of range");
    assert!(grid_points > 0, "a profile needs at least one grid point per side");
    let wald = uncertainty(specs, fit)?;
    let walk = Walk {
        problem,
        specs,
        fit,
        index,
        grid_points,
        options,
        threshold: wald.t_quantile * wald.t_quantile,
        residual_variance: wald.residual_variance,
        half_width: wald.t_quantile * wald.solver_standard_errors[index],
    };
    let ((mut points, lower), (upper_points, upper)) =
        rayon::join(|| walk.side(Side::Lower), || walk.side(Side::Upper));
    points.reverse();
    points.push(ProfilePoint { value: fit.x[index], objective: fit.objective, x: fit.x.clone() });
    points.extend(upper_points);
    Ok(Profile {
        index,
        name: specs[index].name.clone(),
        points,
        best_objective: fit.objective,
        residual_variance: wald.residual_variance,
        threshold: walk.threshold,
        lower,
        upper,
    })
}

struct Walk<'a, P: ?Sized> {
    problem: &'a P,
    specs: &'a [ParameterSpec],
    fit: &'a Fit,
    index: usize,
    grid_points: usize,
    options: &'a Options,
    threshold: f64,
    residual_variance: f64,
    /// `t se` in the solver coordinate.
    half_width: f64,
}

impl<P: LeastSquares + ?Sized> Walk<'_, P> {
    /// The points of one side, from the estimate outward, and how it ended.
    fn side(&self, side: Side) -> (Vec<ProfilePoint>, ProfileEnd) {
        let spec = &self.specs[self.index];
        let (low, high) = spec.solver_bounds();
        let estimate = spec.to_solver(self.fit.x[self.index]);
        let (direction, bound) = if side == Side::Lower { (-1.0, low) } else { (1.0, high) };
        let distance = (bound - estimate).abs();
        let mut points = Vec::new();
        if distance <= 1e-12 * bound.abs().max(1.0) {
            return (points, ProfileEnd::AtBound { value: self.fit.x[self.index] });
        }
        let mut step = if self.half_width.is_finite() && self.half_width > 0.0 {
            2.0 * self.half_width / self.grid_points as f64
        } else if distance.is_finite() {
            distance / self.grid_points as f64
        } else {
            1.0
        };
        let reduced_specs = remove_spec(self.specs, self.index);
        let fit_others = remove(&self.fit.x, self.index);
        let mut warm = fit_others.clone();
        let (mut previous_y, mut previous_root) = (estimate, 0.0_f64);
        let mut offset = 0.0;
        let mut value = self.fit.x[self.index];
        for k in 1..=2 * self.grid_points {
            if k > self.grid_points {
                step *= 2.0;
            }
            offset += step;
            let reached = offset >= distance;
            let y = if reached { bound } else { estimate + direction * offset };
            let last = value;
            value = spec.to_physical(y);
            let pinned = Pinned { inner: self.problem, index: self.index, value };
            let mut refit = levenberg_marquardt(&pinned, &reduced_specs, &warm, self.options);
            if matches!(refit, Err(FitError::StartEvaluation(_))) && warm != fit_others {
                // The warm start may be what fails; try the fit's own values.
                refit = levenberg_marquardt(&pinned, &reduced_specs, &fit_others, self.options);
            }
            let refit = match refit {
                Ok(refit) => refit,
                Err(error) => {
                    return (
                        points,
                        ProfileEnd::Failed { last, message: format!("at {} = {value:e}: {error}", spec.name) },
                    )
                }
            };
            let w = statistic(refit.objective, self.fit.objective, self.residual_variance);
            points.push(ProfilePoint { value, objective: refit.objective, x: insert(&refit.x, self.index, value) });
            warm = refit.x;
            let root = w.max(0.0).sqrt();
            if w >= self.threshold {
                // Linear in sqrt(W) between the last two points.
                let fraction = (self.threshold.sqrt() - previous_root) / (root - previous_root);
                let crossing = previous_y + fraction.clamp(0.0, 1.0) * (y - previous_y);
                return (points, ProfileEnd::Crossed { value: spec.to_physical(crossing) });
            }
            if reached {
                return (points, ProfileEnd::Flat { value });
            }
            (previous_y, previous_root) = (y, root);
        }
        (points, ProfileEnd::Open { value })
    }
}

fn remove_spec(specs: &[ParameterSpec], index: usize) -> Vec<ParameterSpec> {
    let mut reduced = specs.to_vec();
    reduced.remove(index);
    reduced
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_problems::{ExponentialDecay, Linear, Product};

    /// For a linear model the profile is an exact parabola, so the profile
    /// interval equals the Wald interval.
    #[test]
    fn linear_profile_interval_equals_the_wald_interval() {
        let problem = Linear::example();
        let specs = problem.specs();
        let options = Options::default();
        let fit = levenberg_marquardt(&problem, &specs, &[0.0; 3], &options).unwrap();
        let wald = uncertainty(&specs, &fit).unwrap();
        for index in 0..3 {
            let result = profile(&problem, &specs, &fit, index, 8, &options).unwrap();
            let (low, high) = result.interval();
            let expected = wald.intervals[index];
            let width = expected.upper - expected.lower;
            assert!((low - expected.lower).abs() < 1e-6 * width, "{index}: {low} vs {}", expected.lower);
            assert!((high - expected.upper).abs() < 1e-6 * width, "{index}: {high} vs {}", expected.upper);
            assert!(!result.is_flat());
            assert!(result.warnings().is_empty(), "{:?}", result.warnings());
            // The statistic of each point is the parabola (x - x*)^2 / se^2.
            let se = wald.standard_errors[index];
            for point in &result.points {
                let expected_w = ((point.value - fit.x[index]) / se).powi(2);
                assert!((result.statistic(point.objective) - expected_w).abs() < 1e-6 * (1.0 + expected_w));
            }
            let pairs = result.pairs();
            assert!(pairs.windows(2).all(|w| w[0].0 < w[1].0), "values increase");
        }
    }

    /// A nonlinear model: the profile interval of a log parameter is close to,
    /// but not the same as, the Wald interval.
    #[test]
    fn exponential_profile_is_close_to_wald() {
        let problem = ExponentialDecay::noisy(2.0, 1.3, 0.05, 0.05, 20, 5);
        let specs = ExponentialDecay::specs();
        let options = Options::default();
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 1.0], &options).unwrap();
        let wald = uncertainty(&specs, &fit).unwrap();
        let result = profile(&problem, &specs, &fit, 1, 10, &options).unwrap();
        let (low, high) = result.interval();
        let expected = wald.intervals[1];
        assert!(
            matches!(result.lower, ProfileEnd::Crossed { .. }) && matches!(result.upper, ProfileEnd::Crossed { .. })
        );
        assert!((low / expected.lower - 1.0).abs() < 0.02, "{low} vs {}", expected.lower);
        assert!((high / expected.upper - 1.0).abs() < 0.02, "{high} vs {}", expected.upper);
    }

    /// (e) r depends on x1 x2 only: every x1 is as good as any other, so the
    /// profile is flat on both sides and says so.
    #[test]
    fn unidentifiable_parameter_has_a_flat_profile() {
        let problem = Product::new();
        let specs = Product::specs();
        let options = Options::default();
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 1.0], &options).unwrap();
        let result = profile(&problem, &specs, &fit, 0, 5, &options).unwrap();
        assert!(matches!(result.lower, ProfileEnd::Flat { value } if value == 0.1), "{:?}", result.lower);
        assert!(matches!(result.upper, ProfileEnd::Flat { value } if value == 10.0), "{:?}", result.upper);
        assert!(result.is_flat());
        assert_eq!(result.interval(), (0.1, 10.0));
        let warnings = result.warnings();
        assert_eq!(warnings, vec![Warning::FlatProfile { parameter: "x1".into(), side: Side::Both }]);
        // Every point refits the product (its standard error is 0.005; the refits
        // stop at ftol = 1e-6, which allows a few 1e-5).
        for point in &result.points {
            let product = point.x[0] * point.x[1];
            assert!((product - fit.x[0] * fit.x[1]).abs() < 1e-4, "{product}");
            assert!(result.statistic(point.objective) < 1e-3, "{}", result.statistic(point.objective));
        }
        eprintln!("{}", warnings[0]);
    }

    /// A one-parameter problem profiles by evaluation alone.
    #[test]
    fn single_parameter_profile() {
        let problem = Linear::random(3, 12, 1);
        let specs = problem.specs();
        let options = Options::default();
        let fit = levenberg_marquardt(&problem, &specs, &[0.0], &options).unwrap();
        let wald = uncertainty(&specs, &fit).unwrap();
        let result = profile(&problem, &specs, &fit, 0, 4, &options).unwrap();
        let (low, high) = result.interval();
        assert!((low - wald.intervals[0].lower).abs() < 1e-6 && (high - wald.intervals[0].upper).abs() < 1e-6);
    }

    /// Failing evaluations end a side without an error.
    #[test]
    fn failures_end_the_side() {
        let mut problem = ExponentialDecay::noisy(2.0, 1.3, 0.05, 0.05, 20, 5);
        let specs = ExponentialDecay::specs();
        let options = Options::default();
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 1.0], &options).unwrap();
        // Make every rate above the estimate fail.
        problem.fail_above_rate = Some(fit.x[1] * 1.0001);
        let result = profile(&problem, &specs, &fit, 1, 6, &options).unwrap();
        assert!(matches!(&result.upper, ProfileEnd::Failed { last, .. } if *last == fit.x[1]), "{:?}", result.upper);
        assert!(matches!(result.lower, ProfileEnd::Crossed { .. }));
    }

    /// A fit stopped far too early is caught by its profile.
    #[test]
    fn profile_reports_a_better_fit() {
        let problem = ExponentialDecay::noisy(2.0, 1.3, 0.05, 0.05, 20, 5);
        let specs = ExponentialDecay::specs();
        let rough = Options { max_iterations: 1, ..Options::default() };
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 1.0], &rough).unwrap();
        let result = profile(&problem, &specs, &fit, 0, 4, &Options::default()).unwrap();
        assert!(result.warnings().iter().any(|w| matches!(w, Warning::BetterFitInProfile { .. })));
    }
}
