//! Small analytic least-squares problems shared by the unit tests.

use nalgebra::{DMatrix, DVector};

use crate::lsq::{EvalError, Evaluation, LeastSquares, ParameterSpec};
use crate::rng::SplitMix64;

/// `r = (A x - b) / sigma`.
pub struct Linear {
    pub matrix: DMatrix<f64>,
    pub data: DVector<f64>,
    pub sigma: f64,
}

impl Linear {
    /// A quadratic polynomial fitted to 10 points with a fixed perturbation.
    pub fn example() -> Self {
        let t: Vec<f64> = (0..10).map(|i| i as f64 / 3.0).collect();
        let matrix = DMatrix::from_fn(10, 3, |i, j| t[i].powi(j as i32));
        let wiggle = [0.03, -0.05, 0.02, 0.04, -0.01, -0.06, 0.05, 0.0, -0.02, 0.03];
        let data = DVector::from_fn(10, |i, _| 0.5 - 1.2 * t[i] + 0.3 * t[i] * t[i] + wiggle[i]);
        Self { matrix, data, sigma: 0.04 }
    }

    /// `y = a + b t` with a fixed perturbation, at 8 points in [0, 2], sigma 1.
    pub fn line(a: f64, b: f64) -> Self {
        let t: Vec<f64> = (0..8).map(|i| i as f64 * 2.0 / 7.0).collect();
        let matrix = DMatrix::from_fn(8, 2, |i, j| if j == 0 { 1.0 } else { t[i] });
        let wiggle = [0.1, -0.2, 0.05, 0.15, -0.1, 0.0, 0.2, -0.15];
        let data = DVector::from_fn(8, |i, _| a + b * t[i] + wiggle[i]);
        Self { matrix, data, sigma: 1.0 }
    }

    /// [`Linear::example`]'s first two columns and a third, all-zero one.
    pub fn with_dead_column() -> Self {
        let mut problem = Self::example();
        problem.matrix.column_mut(2).fill(0.0);
        problem
    }

    /// A random `m x n` problem.
    pub fn random(seed: u64, m: usize, n: usize) -> Self {
        let mut rng = SplitMix64::new(seed);
        let matrix = DMatrix::from_fn(m, n, |_, _| rng.next_gaussian());
        let data = DVector::from_fn(m, |_, _| 2.0 * rng.next_gaussian());
        Self { matrix, data, sigma: 1.0 }
    }

    /// Wide linear bounds [-100, 100].
    pub fn specs(&self) -> Vec<ParameterSpec> {
        (0..self.matrix.ncols()).map(|j| ParameterSpec::linear(format!("x{j}"), -100.0, 100.0)).collect()
    }

    /// The least-squares solution (minimum norm when rank deficient).
    pub fn solution(&self) -> Vec<f64> {
        let svd = self.matrix.clone().svd(true, true);
        svd.solve(&self.data, 1e-12).expect("SVD solve").as_slice().to_vec()
    }

    /// The closed form `(A^T A)^-1 sigma^2` (normal equations: fine for the
    /// well-conditioned examples here).
    pub fn covariance(&self) -> DMatrix<f64> {
        let normal = self.matrix.tr_mul(&self.matrix);
        normal.try_inverse().expect("full rank") * (self.sigma * self.sigma)
    }

    /// The bounded least-squares optimum's objective, by brute force: every
    /// assignment of each parameter to free, lower or upper; the free ones solved
    /// by unconstrained least squares; the best assignment that stays in the box.
    pub fn bounded_optimum(&self, specs: &[ParameterSpec]) -> f64 {
        let n = self.matrix.ncols();
        let mut best = f64::INFINITY;
        for code in 0..3usize.pow(n as u32) {
            let states: Vec<usize> = (0..n).map(|j| code / 3usize.pow(j as u32) % 3).collect();
            let mut x = vec![0.0; n];
            let free: Vec<usize> = (0..n).filter(|&j| states[j] == 0).collect();
            for j in 0..n {
                x[j] = match states[j] {
                    1 => specs[j].lower,
                    2 => specs[j].upper,
                    _ => 0.0,
                };
            }
            let fixed_part = &self.matrix * DVector::from_column_slice(&x);
            if !free.is_empty() {
                let reduced = self.matrix.select_columns(&free);
                let rhs = &self.data - &fixed_part;
                let solution = reduced.svd(true, true).solve(&rhs, 1e-14).expect("SVD solve");
                for (k, &j) in free.iter().enumerate() {
                    x[j] = solution[k];
                }
            }
            if (0..n).all(|j| x[j] >= specs[j].lower - 1e-12 && x[j] <= specs[j].upper + 1e-12) {
                let residual = (&self.matrix * DVector::from_column_slice(&x) - &self.data) / self.sigma;
                best = best.min(0.5 * residual.norm_squared());
            }
        }
        best
    }

    /// For [`Linear::line`]: the intercept that is best with the slope held at `b`.
    pub fn conditional_intercept(&self, b: f64) -> f64 {
        let m = self.data.len() as f64;
        (0..self.data.len()).map(|i| self.data[i] - b * self.matrix[(i, 1)]).sum::<f64>() / m
    }
}

impl LeastSquares for Linear {
    fn num_parameters(&self) -> usize {
        self.matrix.ncols()
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        let x = DVector::from_column_slice(x);
        let residuals = (&self.matrix * x - &self.data) / self.sigma;
        Ok(Evaluation {
            residuals: residuals.as_slice().to_vec(),
            jacobian: want_jacobian.then(|| &self.matrix / self.sigma),
        })
    }
}

/// Rosenbrock's function as least squares: `r = [10 (x2 - x1^2), 1 - x1]`.
pub struct Rosenbrock;

impl LeastSquares for Rosenbrock {
    fn num_parameters(&self) -> usize {
        2
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        Ok(Evaluation {
            residuals: vec![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]],
            jacobian: want_jacobian.then(|| DMatrix::from_row_slice(2, 2, &[-20.0 * x[0], 10.0, -1.0, 0.0])),
        })
    }
}

/// `y = A exp(-k t)` sampled at `t` in [0, 2]; `r_i = (A exp(-k t_i) - y_i) / sigma`.
pub struct ExponentialDecay {
    pub times: Vec<f64>,
    pub data: Vec<f64>,
    /// The sigma the residuals are divided by (the assumed noise level).
    pub sigma: f64,
    /// Evaluations fail (as an inverted element would) for rates above this.
    pub fail_above_rate: Option<f64>,
}

impl ExponentialDecay {
    fn times(count: usize) -> Vec<f64> {
        (0..count).map(|i| 2.0 * i as f64 / (count - 1) as f64).collect()
    }

    pub fn noise_free(amplitude: f64, rate: f64, count: usize) -> Self {
        let times = Self::times(count);
        let data = times.iter().map(|t| amplitude * (-rate * t).exp()).collect();
        Self { times, data, sigma: 0.05, fail_above_rate: None }
    }

    /// Data with Gaussian noise of `sigma_true`, residuals weighted by
    /// `sigma_assumed`.
    pub fn noisy(amplitude: f64, rate: f64, sigma_true: f64, sigma_assumed: f64, count: usize, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let times = Self::times(count);
        let data = times.iter().map(|t| amplitude * (-rate * t).exp() + sigma_true * rng.next_gaussian()).collect();
        Self { times, data, sigma: sigma_assumed, fail_above_rate: None }
    }

    /// `A` and `k`, both log scale in [1e-3, 1e3].
    pub fn specs() -> Vec<ParameterSpec> {
        vec![ParameterSpec::log("A", 1e-3, 1e3), ParameterSpec::log("k_per_s", 1e-3, 1e3)]
    }
}

impl LeastSquares for ExponentialDecay {
    fn num_parameters(&self) -> usize {
        2
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        let (amplitude, rate) = (x[0], x[1]);
        if self.fail_above_rate.is_some_and(|limit| rate > limit) {
            return Err(EvalError::new(format!("simulated failure at k = {rate}")));
        }
        let m = self.times.len();
        let residuals =
            (0..m).map(|i| (amplitude * (-rate * self.times[i]).exp() - self.data[i]) / self.sigma).collect();
        let jacobian = want_jacobian.then(|| {
            DMatrix::from_fn(m, 2, |i, j| {
                let e = (-rate * self.times[i]).exp();
                if j == 0 {
                    e / self.sigma
                } else {
                    -amplitude * self.times[i] * e / self.sigma
                }
            })
        });
        Ok(Evaluation { residuals, jacobian })
    }
}

/// Unidentifiable: `r_i = (x1 x2 t_i - y_i) / sigma` depends on the product only.
pub struct Product {
    pub times: Vec<f64>,
    pub data: Vec<f64>,
}

impl Product {
    pub fn new() -> Self {
        let times: Vec<f64> = (1..=10).map(|i| i as f64 / 10.0).collect();
        let wiggle = [0.01, -0.02, 0.015, 0.0, -0.01, 0.02, -0.015, 0.01, 0.005, -0.01];
        let data = times.iter().zip(wiggle).map(|(t, w)| 2.0 * t + w).collect();
        Self { times, data }
    }

    /// x2's box is wide enough to compensate any x1 in its box (x1 x2 = 2).
    pub fn specs() -> Vec<ParameterSpec> {
        vec![ParameterSpec::log("x1", 0.1, 10.0), ParameterSpec::log("x2", 0.01, 100.0)]
    }
}

impl LeastSquares for Product {
    fn num_parameters(&self) -> usize {
        2
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        let sigma = 0.01;
        let product = x[0] * x[1];
        let m = self.times.len();
        let residuals = (0..m).map(|i| (product * self.times[i] - self.data[i]) / sigma).collect();
        let jacobian = want_jacobian
            .then(|| DMatrix::from_fn(m, 2, |i, j| self.times[i] * if j == 0 { x[1] } else { x[0] } / sigma));
        Ok(Evaluation { residuals, jacobian })
    }
}

/// Two local minima in `x1` (near -1 and 1, the one at 1 global) and a
/// quadratic bowl in `x2`: `r = [x1^2 - 1, 0.3 (x1 - 1), x2 - 0.5]`.
pub struct TwoMinima;

impl LeastSquares for TwoMinima {
    fn num_parameters(&self) -> usize {
        2
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        Ok(Evaluation {
            residuals: vec![x[0] * x[0] - 1.0, 0.3 * (x[0] - 1.0), x[1] - 0.5],
            jacobian: want_jacobian.then(|| DMatrix::from_row_slice(3, 2, &[2.0 * x[0], 0.0, 0.3, 0.0, 0.0, 1.0])),
        })
    }
}
