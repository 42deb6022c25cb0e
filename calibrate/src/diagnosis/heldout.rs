//! Held-out prediction (diagnosis-details.md §5.4.3 and §5.5) and the gap
//! closure with its bootstrap interval.
//!
//! **Held-out residuals.** With validation trials, they are the validation
//! trials' residuals at the calibrated parameters. Without, every calibration
//! trial is left out in turn (grouped by trial, never by time point) and
//! predicted from the others, by one Gauss-Newton step of case deletion: with
//! `J` and `r` at the fit on all trials, the fit without trial `k` moves the
//! parameters by `delta = (J_-k^T J_-k)^+ J_k^T r_k` (the normal equations of the
//! other trials, whose gradient at the full fit is `-J_k^T r_k`), and trial `k`
//! is predicted with `r_k + J_k delta`. This costs no simulation (the refits of
//! §5.5 would cost one per fold and candidate); it is exact for a model linear in
//! its parameters and a first-order approximation otherwise.
//!
//! **Per-sample anchoring.** Each held-out trial then re-estimates its own two
//! sample scales (all moduli times `s_E`, all viscosities times `s_c`), again by
//! one linear step: its residual is projected off the span of
//! `sum_moduli theta_i dr/dtheta_i` and `sum_viscosities theta_i dr/dtheta_i`.
//! So held-out error measures missing structure, not sample-to-sample scatter
//! (§7.8).
//!
//! **Gap closure.** `G = (S0 - S1) / (S0 - k)` with `S = sum over segments of
//! |Q^T h|^2` of the held-out residuals `h` (smooth projection, `k` the summed
//! dimension). Its 90 % interval and the standard error of the held-out gain
//! `SS0 - SS1` come from a paired bootstrap over segments (the same resampled
//! segments for the baseline and the candidate), with a fixed seed.

use nalgebra::{DMatrix, DVector};

use super::cells::Segment;
use super::stats::quantile;
use crate::rng::SplitMix64;

/// An orthonormal basis of the column space of `a` (thin SVD, relative rank
/// tolerance 1e-10).
pub fn range_basis(a: &DMatrix<f64>) -> DMatrix<f64> {
    if a.ncols() == 0 || a.nrows() == 0 {
        return DMatrix::zeros(a.nrows(), 0);
    }
    let svd = a.clone().svd(true, false);
    let u = svd.u.expect("requested");
    let s = &svd.singular_values;
    let smax = s.iter().copied().fold(0.0, f64::max);
    let keep: Vec<usize> = (0..s.len()).filter(|&i| s[i] > 1e-10 * smax && smax > 0.0).collect();
    DMatrix::from_fn(a.nrows(), keep.len(), |i, j| u[(i, keep[j])])
}

/// `v` minus its projection on the orthonormal columns of `q`.
pub fn project_out(q: &DMatrix<f64>, v: &DVector<f64>) -> DVector<f64> {
    if q.ncols() == 0 {
        return v.clone();
    }
    v - q * (q.transpose() * v)
}

/// The rows `rows` of `j`.
fn rows_of(j: &DMatrix<f64>, rows: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), j.ncols(), |i, c| j[(rows[i], c)])
}

/// Trial `rows`' residual `h` anchored on its sample scales: projected off the
/// span of the summed log-derivatives of the moduli and of the viscosities
/// (`kinds[i]`: `Some(true)` modulus, `Some(false)` viscosity), the first
/// `kinds.len()` columns of `j` being the unknowns at `theta`.
pub fn anchor(h: &DVector<f64>, j_rows: &DMatrix<f64>, theta: &[f64], kinds: &[Option<bool>]) -> DVector<f64> {
    let mut cols: Vec<DVector<f64>> = Vec::new();
    for kind in [true, false] {
        let mut a = DVector::zeros(h.len());
        let mut any = false;
        for (i, k) in kinds.iter().enumerate() {
            if *k == Some(kind) {
                a += j_rows.column(i) * theta[i];
                any = true;
            }
        }
        if any {
            cols.push(a);
        }
    }
    if cols.is_empty() {
        return h.clone();
    }
    let a = DMatrix::from_columns(&cols);
    project_out(&range_basis(&a), h)
}

/// Leave-one-trial-out held-out residuals (module docs) of a fit with residuals
/// `r` and Jacobian `j` (columns: the unknowns at `theta`, then any effect
/// coordinates), trial `k` owning rows `offsets[k]..offsets[k + 1]`; anchored.
/// `None` with fewer than two trials.
pub fn leave_one_out(
    r: &[f64],
    j: &DMatrix<f64>,
    offsets: &[usize],
    theta: &[f64],
    kinds: &[Option<bool>],
) -> Option<Vec<f64>> {
    let num_trials = offsets.len() - 1;
    if num_trials < 2 {
        return None;
    }
    // Column scaling, so that the pseudo-inverse's tolerance is unit-free.
    let norms: Vec<f64> = (0..j.ncols()).map(|c| j.column(c).norm()).collect();
    let js = DMatrix::from_fn(j.nrows(), j.ncols(), |i, c| if norms[c] > 0.0 { j[(i, c)] / norms[c] } else { 0.0 });
    let mut out = vec![0.0; r.len()];
    for k in 0..num_trials {
        let own: Vec<usize> = (offsets[k]..offsets[k + 1]).collect();
        let others: Vec<usize> = (0..r.len()).filter(|i| !(offsets[k]..offsets[k + 1]).contains(i)).collect();
        let jk = rows_of(&js, &own);
        let jo = rows_of(&js, &others);
        let rk = DVector::from_iterator(own.len(), own.iter().map(|&i| r[i]));
        let a = jo.transpose() * &jo;
        let b = jk.transpose() * &rk;
        let delta = pseudo_solve(&a, &b);
        let h = &rk + &jk * delta;
        let jk_phys = rows_of(j, &own);
        let h = anchor(&h, &jk_phys, theta, kinds);
        for (q, &i) in own.iter().enumerate() {
            out[i] = h[q];
        }
    }
    Some(out)
}

/// `a^+ b` for a symmetric positive semi-definite `a` (eigenvalues below 1e-12 of
/// the largest are dropped).
fn pseudo_solve(a: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    if a.ncols() == 0 {
        return DVector::zeros(0);
    }
    let eig = a.clone().symmetric_eigen();
    let lmax = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut x = DVector::zeros(a.ncols());
    for (i, &l) in eig.eigenvalues.iter().enumerate() {
        if l > 1e-12 * lmax && lmax > 0.0 {
            let v = eig.eigenvectors.column(i);
            x += v * (v.dot(b) / l);
        }
    }
    x
}

/// Held-out comparison of a candidate against the baseline.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// `SS0 - SS1` over the held-out residuals [chi-square units].
    pub gain: f64,
    /// Its bootstrap standard error.
    pub gain_se: f64,
    /// The held-out smooth gap `S0 - k` [smooth chi-square units].
    pub gap: f64,
    /// `G = (S0 - S1) / (S0 - k)`.
    pub closure: f64,
    /// Its 90 % paired-bootstrap interval.
    pub closure_ci90: [f64; 2],
    /// Whether the held-out gap is large enough to report G (>= 50, §5.5).
    pub reportable: bool,
}

/// Bootstrap resamples: each a list of segment indices drawn with replacement.
pub fn resamples(num_segments: usize, num_resamples: usize, seed: u64) -> Vec<Vec<usize>> {
    let mut rng = SplitMix64::new(seed);
    (0..num_resamples).map(|_| (0..num_segments).map(|_| rng.next_below(num_segments.max(1))).collect()).collect()
}

/// The held-out comparison of residuals `h1` (candidate) against `h0`
/// (baseline) over `segments`, with the bootstrap `samples` ([`resamples`]).
pub fn compare(segments: &[Segment], h0: &[f64], h1: &[f64], samples: &[Vec<usize>]) -> HeldOut {
    let per: Vec<(f64, f64, f64, f64, f64)> =
        segments.iter().map(|s| (s.energy(h0), s.energy(h1), s.smooth(h0), s.smooth(h1), s.dof() as f64)).collect();
    let stats = |idx: &mut dyn Iterator<Item = usize>| -> (f64, f64) {
        let (mut gain, mut s0, mut s1, mut k) = (0.0, 0.0, 0.0, 0.0);
        for i in idx {
            let p = per[i];
            gain += p.0 - p.1;
            s0 += p.2;
            s1 += p.3;
            k += p.4;
        }
        let g = if s0 - k != 0.0 { (s0 - s1) / (s0 - k) } else { 0.0 };
        (gain, g)
    };
    let (gain, closure) = stats(&mut (0..per.len()));
    let s0: f64 = per.iter().map(|p| p.2).sum();
    let k: f64 = per.iter().map(|p| p.4).sum();
    let boot: Vec<(f64, f64)> = samples.iter().map(|s| stats(&mut s.iter().copied())).collect();
    let gains: Vec<f64> = boot.iter().map(|b| b.0).collect();
    let mean = gains.iter().sum::<f64>() / gains.len().max(1) as f64;
    let var = gains.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / (gains.len().max(2) - 1) as f64;
    let closures: Vec<f64> = boot.iter().map(|b| b.1).collect();
    HeldOut {
        gain,
        gain_se: var.sqrt(),
        gap: s0 - k,
        closure,
        closure_ci90: [quantile(&closures, 0.05), quantile(&closures, 0.95)],
        reportable: s0 - k >= 50.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For a model linear in its parameters, the one-step case deletion is the
    /// exact leave-one-trial-out prediction: compare with refitting the other
    /// trials by least squares.
    #[test]
    fn case_deletion_is_exact_for_linear_models() {
        let mut rng = SplitMix64::new(3);
        let offsets = [0, 7, 15, 24];
        let n = 24;
        let j = DMatrix::from_fn(n, 3, |_, _| rng.next_gaussian());
        let y = DVector::from_fn(n, |_, _| rng.next_gaussian());
        // Full fit: r = J x - y at the least-squares x.
        let x = j.clone().svd(true, true).solve(&y, 1e-14).unwrap();
        let r = &j * &x - &y;
        let kinds = [None, None, None];
        let h = leave_one_out(r.as_slice(), &j, &offsets, &[1.0, 1.0, 1.0], &kinds).unwrap();
        for k in 0..3 {
            let others: Vec<usize> = (0..n).filter(|i| !(offsets[k]..offsets[k + 1]).contains(i)).collect();
            let jo = rows_of(&j, &others);
            let yo = DVector::from_iterator(others.len(), others.iter().map(|&i| y[i]));
            let xo = jo.svd(true, true).solve(&yo, 1e-14).unwrap();
            for i in offsets[k]..offsets[k + 1] {
                let pred = (j.row(i) * &xo)[0] - y[i];
                assert!((pred - h[i]).abs() < 1e-10, "trial {k} row {i}: {pred} vs {}", h[i]);
            }
        }
    }

    #[test]
    fn bootstrap_is_deterministic_and_paired() {
        let a = resamples(10, 50, 42);
        assert_eq!(a, resamples(10, 50, 42));
        assert_ne!(a, resamples(10, 50, 43));
        assert!(a.iter().all(|s| s.len() == 10 && s.iter().all(|&i| i < 10)));
    }

    #[test]
    fn anchoring_removes_a_scale_change() {
        // Residual exactly along the modulus direction is removed.
        let j = DMatrix::from_fn(5, 2, |i, c| (i + 1) as f64 * (c + 1) as f64 + (i * i) as f64 * c as f64);
        let theta = [2.0, 3.0];
        let dir = j.column(0) * 2.0;
        let h = anchor(&dir.clone_owned(), &j, &theta, &[Some(true), None]);
        assert!(h.norm() < 1e-12 * dir.norm());
    }
}
