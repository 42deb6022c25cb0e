//! Multi-start: the same fit from many starting points, in parallel.
//!
//! Least-squares fits of rheological models can have several local minima (a
//! fast and a slow Voigt element may swap roles). Multi-start runs
//! [`levenberg_marquardt`] from the user's `x0` (start 0) and from
//! `num_starts` Latin hypercube points (starts 1..) in the box.
//!
//! **Latin hypercube in the solver coordinates.** Each parameter's range, in
//! `ln x` for log parameters and `x` for linear ones, is cut into `N` equal
//! strata; each stratum of each parameter holds exactly one start, at a uniform
//! random position inside it, and the strata are paired across parameters by
//! independent random permutations. So a log parameter's starts are spread
//! evenly over its decades. The points depend only on `seed` ([`SplitMix64`]).
//!
//! **Determinism.** The starts are fitted in parallel with rayon (each fit is
//! itself deterministic), collected in start order, then sorted by objective
//! and, for equal objectives, by start index; failed starts go last. The result
//! is therefore the same bit for bit for any number of threads.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::lsq::{levenberg_marquardt, validate, Fit, FitError, LeastSquares, Options, ParameterSpec};
use crate::rng::SplitMix64;

/// Settings of [`multistart`].
#[derive(Clone, Debug, PartialEq)]
pub struct MultiStartOptions {
    /// Latin hypercube starts besides the user's `x0`. Default 16.
    pub num_starts: usize,
    /// Seed of the Latin hypercube. Default 0x5eed.
    pub seed: u64,
    /// Settings of each fit.
    pub fit: Options,
}

impl Default for MultiStartOptions {
    fn default() -> Self {
        Self { num_starts: 16, seed: 0x5eed, fit: Options::default() }
    }
}

/// One start and its outcome.
#[derive(Debug)]
pub struct StartResult {
    /// 0 for the user's `x0`, then the Latin hypercube points in order.
    pub start_index: usize,
    /// The starting point, physical units.
    pub start: Vec<f64>,
    /// The fit, or why it could not be run (typically a simulation that fails
    /// at the starting point).
    pub result: Result<Fit, FitError>,
}

/// All starts of a multi-start, best first.
#[derive(Debug)]
pub struct MultiStart {
    /// Successful fits by increasing objective (ties by start index), then the
    /// failed starts by start index. The first is always a success.
    pub runs: Vec<StartResult>,
}

impl MultiStart {
    /// The fit with the lowest objective.
    pub fn best(&self) -> &Fit {
        self.runs[0].result.as_ref().expect("multistart keeps at least one successful fit first")
    }

    /// The successful fits, best first.
    pub fn fits(&self) -> impl Iterator<Item = &Fit> {
        self.runs.iter().filter_map(|run| run.result.as_ref().ok())
    }

    /// The number of starts whose fit could not be run.
    pub fn num_failed(&self) -> usize {
        self.runs.iter().filter(|run| run.result.is_err()).count()
    }
}

/// `num_points` Latin hypercube points in the box of `specs` (module docs),
/// physical units. Every bound must be finite (positive for log parameters).
pub fn latin_hypercube(specs: &[ParameterSpec], num_points: usize, seed: u64) -> Result<Vec<Vec<f64>>, FitError> {
    let mut ranges = Vec::with_capacity(specs.len());
    for spec in specs {
        spec.validate()?;
        let (low, high) = spec.solver_bounds();
        if !(low.is_finite() && high.is_finite()) {
            return Err(FitError::UnboundedParameter { name: spec.name.clone(), lower: spec.lower, upper: spec.upper });
        }
        ranges.push((low, high));
    }
    let mut rng = SplitMix64::new(seed);
    let mut points = vec![vec![0.0; specs.len()]; num_points];
    for (j, (spec, (low, high))) in specs.iter().zip(ranges).enumerate() {
        let mut strata: Vec<usize> = (0..num_points).collect();
        rng.shuffle(&mut strata);
        for (point, stratum) in points.iter_mut().zip(strata) {
            let position = (stratum as f64 + rng.next_f64()) / num_points as f64;
            point[j] = spec.to_physical(low + position * (high - low));
        }
    }
    Ok(points)
}

/// Fits from `x0` and `options.num_starts` Latin hypercube points in parallel
/// (module docs). `progress`, if given, is called as each start finishes with
/// (starts done, total starts), from the worker threads.
///
/// Fails on malformed input, on an unbounded parameter, or when no start at all
/// could be fitted.
pub fn multistart<P: LeastSquares + ?Sized>(
    problem: &P,
    specs: &[ParameterSpec],
    x0: &[f64],
    options: &MultiStartOptions,
    progress: Option<&(dyn Fn(usize, usize) + Sync)>,
) -> Result<MultiStart, FitError> {
    validate(problem, specs, x0)?;
    let mut starts = vec![x0.to_vec()];
    starts.extend(latin_hypercube(specs, options.num_starts, options.seed)?);
    let total = starts.len();
    let done = AtomicUsize::new(0);
    let mut runs: Vec<StartResult> = starts
        .into_par_iter()
        .enumerate()
        .map(|(start_index, start)| {
            let result = levenberg_marquardt(problem, specs, &start, &options.fit);
            let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
            if let Some(report) = progress {
                report(finished, total);
            }
            StartResult { start_index, start, result }
        })
        .collect();
    runs.sort_by(|a, b| match (&a.result, &b.result) {
        (Ok(fa), Ok(fb)) => fa.objective.total_cmp(&fb.objective).then(a.start_index.cmp(&b.start_index)),
        (Ok(_), Err(_)) => std::cmp::Ordering::Less,
        (Err(_), Ok(_)) => std::cmp::Ordering::Greater,
        (Err(_), Err(_)) => a.start_index.cmp(&b.start_index),
    });
    if runs[0].result.is_err() {
        let first = runs.into_iter().find(|run| run.start_index == 0).expect("start 0 exists");
        let error = first.result.expect_err("every start failed");
        return Err(FitError::AllStartsFailed { num_starts: total, first: Box::new(error) });
    }
    Ok(MultiStart { runs })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsq::StopReason;
    use crate::test_problems::{ExponentialDecay, TwoMinima};
    use std::sync::Mutex;

    fn specs() -> Vec<ParameterSpec> {
        vec![ParameterSpec::linear("x1", -3.0, 3.0), ParameterSpec::linear("x2", -2.0, 2.0)]
    }

    #[test]
    fn latin_hypercube_has_one_point_per_stratum() {
        let specs = vec![ParameterSpec::log("E_MPa", 1e-3, 1e1), ParameterSpec::linear("nu", 0.0, 0.49)];
        let points = latin_hypercube(&specs, 20, 7).unwrap();
        assert_eq!(points.len(), 20);
        for (j, spec) in specs.iter().enumerate() {
            let (low, high) = spec.solver_bounds();
            let mut strata: Vec<usize> =
                points.iter().map(|p| ((spec.to_solver(p[j]) - low) / (high - low) * 20.0).floor() as usize).collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..20).collect::<Vec<_>>(), "parameter {j}");
            assert!(points.iter().all(|p| p[j] >= spec.lower && p[j] <= spec.upper));
        }
        // Deterministic from the seed, different for another.
        assert_eq!(points, latin_hypercube(&specs, 20, 7).unwrap());
        assert_ne!(points, latin_hypercube(&specs, 20, 8).unwrap());
    }

    #[test]
    fn unbounded_parameters_are_refused() {
        let specs = vec![ParameterSpec::log("E_MPa", 0.0, 1.0)];
        assert!(matches!(latin_hypercube(&specs, 4, 1), Err(FitError::UnboundedParameter { .. })));
    }

    /// (g) From x0 = (-1.5, 0) a single fit stops in the local minimum near
    /// x1 = -1; multi-start finds the global one at x1 = 1.
    #[test]
    fn multistart_finds_the_global_minimum() {
        let x0 = [-1.5, 0.0];
        let single = levenberg_marquardt(&TwoMinima, &specs(), &x0, &Options::default()).unwrap();
        assert!(
            single.x[0] < 0.0 && single.objective > 0.1,
            "the start must lead to the local minimum: {:?}",
            single.x
        );
        let options = MultiStartOptions { num_starts: 12, ..MultiStartOptions::default() };
        let result = multistart(&TwoMinima, &specs(), &x0, &options, None).unwrap();
        let best = result.best();
        assert!((best.x[0] - 1.0).abs() < 1e-8 && (best.x[1] - 0.5).abs() < 1e-8, "{:?}", best.x);
        assert!(best.objective < 1e-15);
        assert_eq!(result.runs.len(), 13);
        assert!(result.runs.iter().any(|r| r.start_index == 0 && r.result.as_ref().unwrap().x[0] < 0.0));
        let objectives: Vec<f64> = result.fits().map(|f| f.objective).collect();
        assert!(objectives.windows(2).all(|w| w[0] <= w[1]));
    }

    /// (g) The same result, bit for bit, on 1 and 2 threads.
    #[test]
    fn multistart_is_independent_of_the_thread_count() {
        let problem = ExponentialDecay::noisy(2.0, 1.3, 0.05, 0.05, 15, 9);
        let specs = ExponentialDecay::specs();
        let options = MultiStartOptions { num_starts: 24, ..MultiStartOptions::default() };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| multistart(&problem, &specs, &[1.0, 1.0], &options, None).unwrap())
        };
        let (one, two) = (run(1), run(2));
        let summary = |m: &MultiStart| -> Vec<(usize, Vec<u64>, u64, StopReason)> {
            m.runs
                .iter()
                .map(|r| {
                    let fit = r.result.as_ref().unwrap();
                    // Bit patterns: the claim is exact reproducibility, not closeness.
                    (r.start_index, fit.x.iter().map(|v| v.to_bits()).collect(), fit.objective.to_bits(), fit.stop)
                })
                .collect()
        };
        assert_eq!(summary(&one), summary(&two));
        let converged = one.fits().filter(|f| (f.objective - one.best().objective) < 1e-6).count();
        assert!(converged > 12, "most starts reach the same minimum: {converged}");
    }

    #[test]
    fn progress_is_reported_for_every_start() {
        let calls = Mutex::new(Vec::new());
        let record = |done: usize, total: usize| calls.lock().unwrap().push((done, total));
        let options = MultiStartOptions { num_starts: 5, ..MultiStartOptions::default() };
        multistart(&TwoMinima, &specs(), &[0.5, 0.0], &options, Some(&record)).unwrap();
        let mut calls = calls.into_inner().unwrap();
        calls.sort_unstable();
        assert_eq!(calls, (1..=6).map(|d| (d, 6)).collect::<Vec<_>>());
    }

    /// Starts whose simulation fails are kept, last, and do not stop the others.
    #[test]
    fn failed_starts_are_kept_last() {
        let mut problem = ExponentialDecay::noise_free(2.0, 1.3, 10);
        // The failure limit sits at 60 % of [ln 0.1, ln 100]: the top 4 of 10 strata fail.
        problem.fail_above_rate = Some(0.1 * 1000f64.powf(0.6));
        let specs = vec![ParameterSpec::log("A", 0.1, 10.0), ParameterSpec::log("k_per_s", 0.1, 100.0)];
        let options = MultiStartOptions { num_starts: 10, ..MultiStartOptions::default() };
        let result = multistart(&problem, &specs, &[1.0, 1.0], &options, None).unwrap();
        assert_eq!(result.num_failed(), 4);
        assert!(result.runs.iter().rev().take(4).all(|r| r.result.is_err()));
        assert!((result.best().x[1] - 1.3).abs() < 1e-8);

        problem.fail_above_rate = Some(0.0);
        let all_fail = multistart(&problem, &specs, &[1.0, 1.0], &options, None);
        assert!(matches!(all_fail, Err(FitError::AllStartsFailed { num_starts: 11, .. })), "{all_fail:?}");
    }
}
