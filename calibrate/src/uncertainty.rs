//! Parameter uncertainty from a fit: Gauss-Newton covariance, 95 % intervals,
//! correlations and the identifiability checks that need only the Jacobian.
//!
//! # Covariance
//!
//! With `m` residuals, `n` parameters and the Jacobian `J = dr/dx` at the fit
//! (physical units),
//!
//! ```text
//! Cov = s^2 (J^T J)^-1,    s^2 = 2 f / (m - n) = sum r_i^2 / (m - n).
//! ```
//!
//! `s^2` is the residual variance factor. The residuals are already divided by
//! the measurement noise, so when the model fits the data to within the noise
//! `s^2` is close to 1 and `Cov` is the plain `(J^T J)^-1`. When it is not (the
//! noise was underestimated, or the model cannot follow the data), `s^2 > 1`
//! widens every interval by `s`, so the intervals stay honest about how well the
//! data actually pin the parameters down; `s^2 < 1` means the noise was
//! overestimated and narrows them. (The classical nonlinear-regression estimate:
//! Bates and Watts 1988, ch. 2; Seber and Wild 1989, sec. 5.1.)
//!
//! `(J^T J)^-1` is not formed. The columns of `J` are first scaled to unit
//! norm, `J = J_s D` (so the rank decision and the condition number do not
//! depend on the parameters' units), then `J_s = U S V^T` (SVD), and
//!
//! ```text
//! (J^T J)^+ = D^-1 V S^-2 V^T D^-1,
//! ```
//!
//! keeping only singular values above `1e-10 s_max` ([`RANK_TOLERANCE`]): the
//! data determine about `-log10(cond)` of the 16 digits of double precision,
//! so a direction with `s_k < 1e-10 s_max` is determined to fewer than 6 digits
//! even without noise, and is treated as not determined at all. The right
//! singular vectors of the dropped values span the directions the data cannot see
//! (the null space). A parameter with a component above 1e-3 in one of them is
//! *unidentifiable*: its standard error is infinite, its interval the whole box
//! (flagged as clipped), and its correlations NaN. The covariance matrix itself is
//! the pseudo-inverse above, i.e. the covariance within the identifiable subspace.
//!
//! # Intervals
//!
//! Two-sided 95 % intervals use Student's t quantile `t = t_{0.975, m - n}`
//! (exact for every `m - n`, [`crate::stats`]): for a linear model with Gaussian
//! noise of unknown level they are exact. For a [`Scale::Log`] parameter the
//! interval is computed in `ln x`, where the estimate is closer to Gaussian and
//! cannot go negative, and mapped back:
//!
//! ```text
//! se_ln = se_x / x,    [x exp(-t se_ln), x exp(t se_ln)]     (asymmetric, positive)
//! ```
//!
//! For a [`Scale::Linear`] one it is `x -+ t se_x`. Both are clipped to the
//! bounds, with a flag per side.
//!
//! # Warnings
//!
//! [`Warning`]s in plain words: rank deficiency (naming the combination of
//! parameters the data cannot see), a condition number of the scaled Jacobian
//! above 1e8, correlations above 0.99 in magnitude, parameters at a bound, and 95 %
//! intervals wider than the value itself. Flat profiles come from
//! [`crate::profile`](mod@crate::profile).

use nalgebra::DMatrix;

use crate::lsq::{Fit, ParameterSpec, Scale};
use crate::stats::student_t_quantile;
use crate::warning::{Side, Term, Warning};

/// Singular values below this fraction of the largest count as zero.
pub const RANK_TOLERANCE: f64 = 1e-10;
/// Condition numbers of the scaled Jacobian above this give a warning.
pub const CONDITION_LIMIT: f64 = 1e8;
/// Correlations above this in magnitude give a warning.
pub const CORRELATION_LIMIT: f64 = 0.99;
/// 95 % intervals wider than this fraction of the value give a warning.
pub const RELATIVE_WIDTH_LIMIT: f64 = 1.0;
/// A parameter with a null-space component above this is unidentifiable.
const NULL_COMPONENT: f64 = 1e-3;

/// A 95 % confidence interval, in the parameter's unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower end, clipped to the lower bound.
    pub lower: f64,
    /// Upper end, clipped to the upper bound.
    pub upper: f64,
    /// The unclipped interval reached below the lower bound.
    pub clipped_lower: bool,
    /// The unclipped interval reached above the upper bound.
    pub clipped_upper: bool,
}

/// The uncertainty of a fit (module docs). Physical units throughout.
#[derive(Clone, Debug)]
pub struct Uncertainty {
    /// Parameter names, from the specs.
    pub names: Vec<String>,
    /// The estimates (the fit's `x`).
    pub x: Vec<f64>,
    /// `m - n`.
    pub degrees_of_freedom: usize,
    /// `s^2 = 2 f / (m - n)` [-]: about 1 when the model fits to within the noise.
    pub residual_variance: f64,
    /// `t_{0.975, m - n}`, the multiplier of the standard errors.
    pub t_quantile: f64,
    /// `s^2 (J^T J)^+` in physical units (entry `(i, j)` in unit_i * unit_j).
    pub covariance: DMatrix<f64>,
    /// Standard errors in the parameters' units; infinite when unidentifiable.
    pub standard_errors: Vec<f64>,
    /// Standard errors in the solver coordinate: of `ln x` (a relative error)
    /// for log parameters, of `x` for linear ones.
    pub solver_standard_errors: Vec<f64>,
    /// Correlation matrix [-]; NaN in the rows and columns of unidentifiable parameters.
    pub correlation: DMatrix<f64>,
    /// 95 % intervals.
    pub intervals: Vec<Interval>,
    /// Numerical rank of the scaled Jacobian.
    pub rank: usize,
    /// Singular values of the column-scaled Jacobian, largest first.
    pub singular_values: Vec<f64>,
    /// `s_max / s_min` of the column-scaled Jacobian (infinite when rank deficient).
    pub condition_number: f64,
    /// Per parameter: false when it takes part in a direction the data cannot see.
    pub identifiable: Vec<bool>,
    /// What the Jacobian says about identifiability (module docs).
    pub warnings: Vec<Warning>,
}

/// Why no uncertainty could be computed.
#[derive(Debug, thiserror::Error)]
pub enum UncertaintyError {
    /// `m <= n`: no residual degrees of freedom to estimate `s^2`.
    #[error("{num_residuals} residuals for {num_parameters} parameters: the uncertainty needs more residuals than parameters")]
    NoDegreesOfFreedom { num_residuals: usize, num_parameters: usize },
}

/// The Gauss-Newton uncertainty of `fit` (module docs).
///
/// `specs` must be the ones the fit was made with (panics on a length mismatch).
pub fn uncertainty(specs: &[ParameterSpec], fit: &Fit) -> Result<Uncertainty, UncertaintyError> {
    let n = specs.len();
    let m = fit.residuals.len();
    assert_eq!(fit.x.len(), n, "the fit has {} parameters, the specs {n}", fit.x.len());
    assert_eq!(fit.jacobian.shape(), (m, n), "the fit's Jacobian does not match its residuals and parameters");
    if m <= n {
        return Err(UncertaintyError::NoDegreesOfFreedom { num_residuals: m, num_parameters: n });
    }
    let degrees_of_freedom = m - n;
    let residual_variance = 2.0 * fit.objective / degrees_of_freedom as f64;
    let t_quantile = student_t_quantile(0.975, degrees_of_freedom as f64);

    // Column scaling and SVD of the scaled Jacobian.
    let column_norms: Vec<f64> =
        fit.jacobian.column_iter().map(|c| c.norm()).map(|v| if v > 0.0 { v } else { 1.0 }).collect();
    let mut scaled = fit.jacobian.clone();
    for (j, d) in column_norms.iter().enumerate() {
        scaled.column_mut(j).unscale_mut(*d);
    }
    let svd = scaled.svd(false, true);
    let v_t = svd.v_t.expect("V requested");
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let singular_values: Vec<f64> = order.iter().map(|&k| svd.singular_values[k]).collect();
    let largest = singular_values[0];
    let threshold = RANK_TOLERANCE * largest;
    let rank = singular_values.iter().filter(|&&s| s > threshold && s > 0.0).count();
    let condition_number = if rank == n { largest / singular_values[n - 1] } else { f64::INFINITY };
    let right = |position: usize| -> Vec<f64> { v_t.row(order[position]).iter().copied().collect() };

    // (J_s^T J_s)^+ and the covariance.
    let mut scaled_inverse = DMatrix::zeros(n, n);
    for (position, &s) in singular_values.iter().enumerate().take(rank) {
        let v = nalgebra::DVector::from_vec(right(position));
        scaled_inverse += (&v * v.transpose()) / (s * s);
    }
    let covariance =
        DMatrix::from_fn(n, n, |i, j| residual_variance * scaled_inverse[(i, j)] / (column_norms[i] * column_norms[j]));

    // Unidentifiable parameters: components in the null space.
    let null_vectors: Vec<Vec<f64>> = (rank..n).map(right).collect();
    let identifiable: Vec<bool> = (0..n).map(|j| null_vectors.iter().all(|v| v[j].abs() <= NULL_COMPONENT)).collect();

    let standard_errors: Vec<f64> =
        (0..n).map(|j| if identifiable[j] { covariance[(j, j)].max(0.0).sqrt() } else { f64::INFINITY }).collect();
    let solver_standard_errors: Vec<f64> = (0..n)
        .map(|j| match specs[j].scale {
            Scale::Log => standard_errors[j] / fit.x[j],
            Scale::Linear => standard_errors[j],
        })
        .collect();
    let correlation = DMatrix::from_fn(n, n, |i, j| {
        if !identifiable[i] || !identifiable[j] {
            f64::NAN
        } else if i == j {
            1.0
        } else {
            scaled_inverse[(i, j)] / (scaled_inverse[(i, i)] * scaled_inverse[(j, j)]).sqrt()
        }
    });

    let intervals: Vec<Interval> = (0..n)
        .map(|j| {
            let spec = &specs[j];
            let half = t_quantile * solver_standard_errors[j];
            let (low, high) = match spec.scale {
                Scale::Log => (fit.x[j] * (-half).exp(), fit.x[j] * half.exp()),
                Scale::Linear => (fit.x[j] - half, fit.x[j] + half),
            };
            Interval {
                lower: low.max(spec.lower),
                upper: high.min(spec.upper),
                clipped_lower: low.is_nan() || low < spec.lower,
                clipped_upper: high.is_nan() || high > spec.upper,
            }
        })
        .collect();

    let mut result = Uncertainty {
        names: specs.iter().map(|s| s.name.clone()).collect(),
        x: fit.x.clone(),
        degrees_of_freedom,
        residual_variance,
        t_quantile,
        covariance,
        standard_errors,
        solver_standard_errors,
        correlation,
        intervals,
        rank,
        singular_values,
        condition_number,
        identifiable,
        warnings: Vec::new(),
    };
    result.warnings = jacobian_warnings(specs, fit, &result, &null_vectors, &column_norms, &right(n - 1));
    Ok(result)
}

/// The warnings of the module docs, in the order: rank, conditioning,
/// correlations, bounds, widths.
fn jacobian_warnings(
    specs: &[ParameterSpec],
    fit: &Fit,
    result: &Uncertainty,
    null_vectors: &[Vec<f64>],
    column_norms: &[f64],
    weakest: &[f64],
) -> Vec<Warning> {
    let n = specs.len();
    let mut warnings = Vec::new();
    for v in null_vectors {
        // The direction in natural units: d ln x_j for log parameters, d x_j for linear.
        let mut terms: Vec<Term> = (0..n)
            .filter(|&j| v[j].abs() > NULL_COMPONENT)
            .map(|j| {
                let natural = v[j] / column_norms[j];
                let (coefficient, log) = match specs[j].scale {
                    Scale::Log => (natural * fit.x[j], true),
                    Scale::Linear => (natural, false),
                };
                Term { parameter: specs[j].name.clone(), coefficient, log }
            })
            .collect();
        let largest = terms.iter().map(|t| t.coefficient.abs()).fold(0.0, f64::max);
        let sign = terms.first().map_or(1.0, |t| t.coefficient.signum());
        for term in &mut terms {
            term.coefficient *= sign / largest;
        }
        warnings.push(Warning::RankDeficient { rank: result.rank, num_parameters: n, combination: terms });
    }
    if result.rank == n && result.condition_number > CONDITION_LIMIT {
        let parameters = (0..n).filter(|&j| weakest[j].abs() >= 0.1).map(|j| specs[j].name.clone()).collect();
        warnings.push(Warning::IllConditioned { condition_number: result.condition_number, parameters });
    }
    for i in 0..n {
        for j in i + 1..n {
            let r = result.correlation[(i, j)];
            if r.abs() > CORRELATION_LIMIT {
                warnings.push(Warning::HighCorrelation {
                    first: specs[i].name.clone(),
                    second: specs[j].name.clone(),
                    correlation: r,
                });
            }
        }
    }
    for ((spec, &x), _) in specs.iter().zip(&fit.x).zip(&fit.at_bound).filter(|(_, &at_bound)| at_bound) {
        let lower = (x - spec.lower).abs() <= (x - spec.upper).abs();
        warnings.push(Warning::AtBound {
            parameter: spec.name.clone(),
            value: x,
            side: if lower { Side::Lower } else { Side::Upper },
        });
    }
    for (j, spec) in specs.iter().enumerate() {
        if !result.identifiable[j] {
            continue;
        }
        // The unclipped width relative to the value.
        let half = result.t_quantile * result.solver_standard_errors[j];
        let relative_width = match spec.scale {
            Scale::Log => half.exp() - (-half).exp(),
            Scale::Linear => 2.0 * half / fit.x[j].abs(),
        };
        if relative_width > RELATIVE_WIDTH_LIMIT {
            warnings.push(Warning::WideInterval {
                parameter: spec.name.clone(),
                lower: result.intervals[j].lower,
                upper: result.intervals[j].upper,
                relative_width,
            });
        }
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsq::{levenberg_marquardt, Options};
    use crate::stats::NORMAL_975;
    use crate::test_problems::{ExponentialDecay, Linear, Product};

    /// (a) A linear problem: the covariance is the closed form
    /// (A^T A)^-1 sigma^2 s^2, and the intervals are x -+ t se.
    #[test]
    fn linear_covariance_matches_the_closed_form() {
        let problem = Linear::example();
        let specs = problem.specs();
        let fit = levenberg_marquardt(&problem, &specs, &[0.0; 3], &Options::default()).unwrap();
        let result = uncertainty(&specs, &fit).unwrap();
        let solution = problem.solution();
        let residual = &problem.matrix * nalgebra::DVector::from_vec(solution) - &problem.data;
        let s2 = residual.norm_squared() / (problem.sigma * problem.sigma) / 7.0;
        assert!((result.residual_variance - s2).abs() < 1e-10 * s2);
        let expected = problem.covariance() * s2;
        for i in 0..3 {
            for j in 0..3 {
                let scale = (expected[(i, i)] * expected[(j, j)]).sqrt();
                assert!(
                    (result.covariance[(i, j)] - expected[(i, j)]).abs() < 1e-10 * scale,
                    "({i}, {j}): {} vs {}",
                    result.covariance[(i, j)],
                    expected[(i, j)]
                );
            }
        }
        // t_{0.975, 7}
        assert!((result.t_quantile - 2.364_624_251_592_785).abs() < 1e-9);
        for j in 0..3 {
            let half = result.t_quantile * expected[(j, j)].sqrt();
            assert!((result.intervals[j].lower - (fit.x[j] - half)).abs() < 1e-9);
            assert!((result.intervals[j].upper - (fit.x[j] + half)).abs() < 1e-9);
        }
        assert_eq!(result.rank, 3);
        assert!(result.identifiable.iter().all(|&b| b));
        assert!((result.correlation[(0, 0)] - 1.0).abs() < 1e-14);
    }

    /// Log-scale intervals are asymmetric and positive: x exp(-+ t se_ln).
    #[test]
    fn log_intervals_are_multiplicative() {
        let problem = ExponentialDecay::noisy(2.0, 1.3, 0.05, 0.05, 10, 3);
        let specs = ExponentialDecay::specs();
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 1.0], &Options::default()).unwrap();
        let result = uncertainty(&specs, &fit).unwrap();
        for j in 0..2 {
            let interval = result.intervals[j];
            assert!(interval.lower > 0.0);
            // The estimate is the geometric mean of the ends.
            let geometric = (interval.lower * interval.upper).sqrt();
            assert!((geometric - fit.x[j]).abs() < 1e-12 * fit.x[j]);
            assert!(interval.upper - fit.x[j] > fit.x[j] - interval.lower);
            assert!((result.solver_standard_errors[j] - result.standard_errors[j] / fit.x[j]).abs() < 1e-15);
        }
    }

    /// Intervals reaching past the bounds are clipped and flagged.
    #[test]
    fn intervals_are_clipped_to_the_bounds() {
        let problem = ExponentialDecay::noisy(2.0, 1.3, 0.05, 0.05, 10, 3);
        let specs = vec![ParameterSpec::log("A", 1e-3, 1e3), ParameterSpec::linear("k_per_s", 1.0, 1.35)];
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 1.2], &Options::default()).unwrap();
        let result = uncertainty(&specs, &fit).unwrap();
        let interval = result.intervals[1];
        assert!(interval.clipped_upper && interval.upper == 1.35, "{interval:?}");
    }

    /// (c) Coverage: over 1000 noisy replicates the 95 % interval holds the true
    /// value in 95 % +- 3.5 % of the cases, for both parameters; with 8 points
    /// (6 degrees of freedom, where t = 2.45 differs from the normal 1.96), and
    /// also when the assumed noise is twice the true one (s^2 ~ 1/4 corrects it).
    #[test]
    fn intervals_cover_the_truth_95_percent_of_the_time() {
        let (amplitude, rate) = (2.0, 1.3);
        let specs = ExponentialDecay::specs();
        let replicates = 1000;
        for sigma_assumed in [0.05, 0.1] {
            let mut covered = [0usize; 2];
            // The same intervals with the normal quantile, and without s^2: the
            // test can tell them apart.
            let (mut covered_normal, mut covered_unscaled) = (0usize, 0usize);
            let mut iterations = 0;
            for seed in 0..replicates {
                let problem = ExponentialDecay::noisy(amplitude, rate, 0.05, sigma_assumed, 8, 1000 + seed);
                let fit = levenberg_marquardt(&problem, &specs, &[1.0, 1.0], &Options::default()).unwrap();
                assert!(fit.stop.converged());
                iterations += fit.iterations;
                let result = uncertainty(&specs, &fit).unwrap();
                for (j, truth) in [amplitude, rate].into_iter().enumerate() {
                    let interval = result.intervals[j];
                    if interval.lower <= truth && truth <= interval.upper {
                        covered[j] += 1;
                    }
                }
                let distance = (rate.ln() - fit.x[1].ln()).abs() / result.solver_standard_errors[1];
                covered_normal += usize::from(distance <= NORMAL_975);
                let unscaled = distance * result.residual_variance.sqrt();
                covered_unscaled += usize::from(unscaled <= result.t_quantile);
            }
            for (j, count) in covered.iter().enumerate() {
                let fraction = *count as f64 / replicates as f64;
                eprintln!(
                    "coverage, sigma assumed {sigma_assumed}, parameter {j}: {fraction:.3} (mean iterations {:.1})",
                    iterations as f64 / replicates as f64
                );
                assert!((fraction - 0.95).abs() <= 0.035, "parameter {j}: coverage {fraction}");
            }
            let normal = covered_normal as f64 / replicates as f64;
            let unscaled = covered_unscaled as f64 / replicates as f64;
            eprintln!("  with the normal quantile: {normal:.3}; without s^2: {unscaled:.3}");
            assert!(normal < 0.935, "the t quantile must matter at 6 degrees of freedom: {normal}");
            if sigma_assumed > 0.05 {
                assert!(unscaled > 0.985, "the s^2 factor must matter when sigma is misjudged: {unscaled}");
            }
        }
    }

    /// (e) r depends on x1 x2 only: rank 1, both named, ln x1 + ln x2 fixed.
    #[test]
    fn product_problem_is_rank_deficient() {
        let problem = Product::new();
        let specs = Product::specs();
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 1.0], &Options::default()).unwrap();
        assert!((fit.x[0] * fit.x[1] - 2.0).abs() < 0.05);
        let result = uncertainty(&specs, &fit).unwrap();
        assert_eq!(result.rank, 1);
        assert_eq!(result.identifiable, vec![false, false]);
        assert!(result.standard_errors.iter().all(|s| s.is_infinite()));
        assert!(result.intervals.iter().all(|i| i.clipped_lower && i.clipped_upper));
        let Some(Warning::RankDeficient { combination, rank: 1, num_parameters: 2 }) = result.warnings.first() else {
            panic!("no rank warning: {:?}", result.warnings);
        };
        let names: Vec<&str> = combination.iter().map(|t| t.parameter.as_str()).collect();
        assert_eq!(names, ["x1", "x2"]);
        // Along d ln x1 = -d ln x2 the product does not change.
        assert!((combination[0].coefficient - 1.0).abs() < 1e-6 && (combination[1].coefficient + 1.0).abs() < 1e-6);
        assert!(combination.iter().all(|t| t.log));
        let text = result.warnings[0].to_string();
        assert!(text.contains("x1") && text.contains("x2"), "{text}");
        eprintln!("{text}");
    }

    /// Nearly collinear columns: full rank, but ill-conditioned and correlated.
    #[test]
    fn nearly_collinear_columns_warn() {
        let mut problem = Linear::example();
        // Column 2 := column 1 + 1e-9 * column 2: condition number ~1e9.
        let column = problem.matrix.column(1) + problem.matrix.column(2) * 1e-9;
        problem.matrix.set_column(2, &column);
        let specs = problem.specs();
        let fit = levenberg_marquardt(&problem, &specs, &[0.0; 3], &Options::default()).unwrap();
        let result = uncertainty(&specs, &fit).unwrap();
        assert_eq!(result.rank, 3);
        assert!(result.condition_number > CONDITION_LIMIT);
        let has = |f: &dyn Fn(&Warning) -> bool| result.warnings.iter().any(f);
        assert!(has(&|w| matches!(w, Warning::IllConditioned { parameters, .. }
            if parameters.contains(&"x1".to_string()) && parameters.contains(&"x2".to_string()))));
        assert!(has(
            &|w| matches!(w, Warning::HighCorrelation { first, second, .. } if first == "x1" && second == "x2")
        ));
        assert!(has(&|w| matches!(w, Warning::WideInterval { parameter, .. } if parameter == "x1")));
        for warning in &result.warnings {
            eprintln!("{warning}");
        }
    }

    #[test]
    fn parameters_at_bounds_warn() {
        let problem = ExponentialDecay::noise_free(2.0, 1.3, 12);
        let specs = vec![ParameterSpec::log("A", 0.01, 100.0), ParameterSpec::log("k_per_s", 0.01, 1.0)];
        let fit = levenberg_marquardt(&problem, &specs, &[1.0, 0.1], &Options::default()).unwrap();
        let result = uncertainty(&specs, &fit).unwrap();
        assert!(result.warnings.iter().any(|w| matches!(w,
            Warning::AtBound { parameter, side: Side::Upper, .. } if parameter == "k_per_s")));
    }

    #[test]
    fn too_few_residuals_is_an_error() {
        let problem = Linear::random(1, 3, 3);
        let specs = problem.specs();
        let fit = levenberg_marquardt(&problem, &specs, &[0.0; 3], &Options::default()).unwrap();
        assert!(matches!(uncertainty(&specs, &fit), Err(UncertaintyError::NoDegreesOfFreedom { .. })));
    }
}
