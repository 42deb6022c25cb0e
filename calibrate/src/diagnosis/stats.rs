//! The statistics of the diagnosis: chi-square and chi-bar-square tails and
//! critical values, Holm's step-down rule, the discrete orthonormal Legendre
//! basis of the smooth test, and percentile intervals.
//!
//! **Chi-square tail.** `P(chi2_k > x) = Q(k/2, x/2)`, the regularized upper
//! incomplete gamma function: its power series for `x < a + 1` and its continued
//! fraction (modified Lentz) otherwise (both converge fast there), `ln Gamma`
//! from [`crate::stats::ln_gamma`]. `k = 0` is the point mass at 0.
//!
//! **Chi-bar-square** (Self & Liang 1987). A test of `d` parameters of which `q`
//! sit on a bound at the null (one-sided), with an information matrix that does
//! not couple them strongly, has the null distribution
//! `sum_i C(q, i) / 2^q chi2_{d - q + i}`: each one-sided parameter is at its
//! bound (contributes nothing) or inside (one degree of freedom) with
//! probability 1/2. For `d = q = 1` this is `1/2 chi2_0 + 1/2 chi2_1`, whose
//! upper `alpha` point is the `(1 - alpha)` normal quantile squared.
//! (Correlated one-sided parameters change the weights; the library's effects
//! have at most one one-sided strength parameter, where the formula is exact.)
//!
//! **Legendre basis.** The smooth test projects a residual segment on the
//! Legendre polynomials `P_0..P_3` of its normalised time `x in [-1, 1]`,
//! orthonormalised *on the sample points* (modified Gram-Schmidt, twice, so the
//! columns are orthonormal to rounding whatever the spacing); a column that is
//! (numerically) dependent on the previous ones is dropped, so a segment of
//! `n <= 4` samples gets the full `n`-dimensional space. Then
//! `T = |Q^T r|^2 ~ chi2_{dim Q}` for white unit-variance noise.

use crate::stats::ln_gamma;

/// The regularized lower incomplete gamma function `P(a, x)`, `a > 0`, `x >= 0`.
pub fn gamma_p(a: f64, x: f64) -> f64 {
    1.0 - gamma_q(a, x)
}

/// The regularized upper incomplete gamma function `Q(a, x)`, `a > 0`, `x >= 0`.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0, "gamma_q needs a > 0, got {a}");
    if x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    if x.is_infinite() {
        return 0.0;
    }
    let log_prefactor = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // Series: P(a, x) = e^{-x} x^a / Gamma(a + 1) sum_n x^n / ((a + 1) ... (a + n)).
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut ap = a;
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-17 {
                break;
            }
        }
        (1.0 - sum * log_prefactor.exp()).clamp(0.0, 1.0)
    } else {
        // Continued fraction for Q (modified Lentz).
        const TINY: f64 = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (log_prefactor.exp() * h).clamp(0.0, 1.0)
    }
}

/// `P(chi2_k > x)`; `k = 0` is the point mass at 0.
pub fn chi2_sf(x: f64, dof: usize) -> f64 {
    if dof == 0 {
        return if x > 0.0 { 0.0 } else { 1.0 };
    }
    gamma_q(dof as f64 / 2.0, x.max(0.0) / 2.0)
}

/// The weights of the chi-bar-square mixture of a test of `dof` parameters, `one_sided`
/// of them on a bound at the null: `(weight, degrees of freedom)` pairs.
pub fn chibar2_weights(dof: usize, one_sided: usize) -> Vec<(f64, usize)> {
    assert!(one_sided <= dof, "{one_sided} one-sided of {dof} parameters");
    let q = one_sided;
    let mut binom = 1.0;
    let scale = 0.5f64.powi(q as i32);
    (0..=q)
        .map(|i| {
            let w = binom * scale;
            binom = binom * (q - i) as f64 / (i + 1) as f64;
            (w, dof - q + i)
        })
        .collect()
}

/// `P(chibar2 > x)` for `dof` parameters, `one_sided` of them on a bound.
pub fn chibar2_sf(x: f64, dof: usize, one_sided: usize) -> f64 {
    chibar2_weights(dof, one_sided).iter().map(|&(w, k)| w * chi2_sf(x, k)).sum()
}

/// The upper `alpha` point of a decreasing tail function `sf` (bisection to
/// 1e-12 relative): the `x` with `sf(x) = alpha`.
pub fn critical_value(alpha: f64, sf: impl Fn(f64) -> f64) -> f64 {
    assert!(alpha > 0.0 && alpha < 1.0, "alpha = {alpha}");
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while sf(hi) > alpha {
        hi *= 2.0;
        if hi > 1e8 {
            return f64::INFINITY;
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if sf(mid) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-12 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// Holm's step-down rule at family-wise level `alpha`: which of `p_values`
/// are rejected. NaN p-values are never rejected and do not count in the family.
pub fn holm(p_values: &[f64], alpha: f64) -> Vec<bool> {
    let mut order: Vec<usize> = (0..p_values.len()).filter(|&i| !p_values[i].is_nan()).collect();
    order.sort_by(|&a, &b| p_values[a].total_cmp(&p_values[b]).then(a.cmp(&b)));
    let m = order.len();
    let mut rejected = vec![false; p_values.len()];
    for (rank, &i) in order.iter().enumerate() {
        if p_values[i] <= alpha / (m - rank) as f64 {
            rejected[i] = true;
        } else {
            break;
        }
    }
    rejected
}

/// Legendre polynomial `P_n(x)` by the three-term recurrence.
pub fn legendre(n: usize, x: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, x);
    match n {
        0 => p0,
        1 => p1,
        _ => {
            for k in 1..n {
                let p2 = ((2 * k + 1) as f64 * x * p1 - k as f64 * p0) / (k + 1) as f64;
                p0 = p1;
                p1 = p2;
            }
            p1
        }
    }
}

/// The columns of an orthonormal basis (on the sample points) of the Legendre
/// polynomials of degree `<= max_degree` in the normalised `times` (module
/// docs). Each column has `times.len()` entries.
pub fn legendre_basis(times: &[f64], max_degree: usize) -> Vec<Vec<f64>> {
    let n = times.len();
    if n == 0 {
        return Vec::new();
    }
    let (lo, hi) = times.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| (a.min(t), b.max(t)));
    let span = hi - lo;
    let x: Vec<f64> = times.iter().map(|&t| if span > 0.0 { 2.0 * (t - lo) / span - 1.0 } else { 0.0 }).collect();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for degree in 0..=max_degree.min(n.saturating_sub(1)) {
        let mut v: Vec<f64> = x.iter().map(|&xi| legendre(degree, xi)).collect();
        let norm0 = dot(&v, &v).sqrt();
        for _ in 0..2 {
            for q in &basis {
                let c = dot(q, &v);
                v.iter_mut().zip(q).for_each(|(a, b)| *a -= c * b);
            }
        }
        let norm = dot(&v, &v).sqrt();
        if norm > 1e-8 * norm0.max(1.0) {
            v.iter_mut().for_each(|a| *a /= norm);
            basis.push(v);
        }
    }
    basis
}

/// `|Q^T r|^2` and `dim Q` of the smooth test of one segment.
pub fn smooth_statistic(times: &[f64], residuals: &[f64], max_degree: usize) -> (f64, usize) {
    let basis = legendre_basis(times, max_degree);
    let t = basis.iter().map(|q| dot(q, residuals).powi(2)).sum();
    (t, basis.len())
}

/// The `q`-quantile (`0 <= q <= 1`) of `values` by linear interpolation between
/// order statistics (type 7). `values` need not be sorted; NaN goes last.
pub fn quantile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let h = q.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let (i, frac) = (h.floor() as usize, h - h.floor());
    if i + 1 < v.len() {
        v[i] + frac * (v[i + 1] - v[i])
    } else {
        v[i]
    }
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi_square_tails_match_closed_forms() {
        // k = 2: P(chi2 > x) = exp(-x/2); k = 1: erfc(sqrt(x/2)), here at x = 3.841458820694124 -> 0.05.
        for x in [0.1, 1.0, 5.0, 14.18, 40.0] {
            assert!((chi2_sf(x, 2) - (-x / 2.0).exp()).abs() < 1e-13 * (-x / 2.0f64).exp().max(1e-300) + 1e-15);
        }
        assert!((chi2_sf(3.841_458_820_694_124, 1) - 0.05).abs() < 1e-12);
        // k = 4: exp(-x/2) (1 + x/2).
        for x in [0.5, 3.0, 9.0, 30.0] {
            let exact = (-x / 2.0f64).exp() * (1.0 + x / 2.0);
            assert!((chi2_sf(x, 4) - exact).abs() < 1e-13, "{x}");
        }
        assert_eq!(chi2_sf(1.0, 0), 0.0);
        assert!((gamma_p(2.5, 1.7) + gamma_q(2.5, 1.7) - 1.0).abs() < 1e-15);
    }

    /// The Bonferroni critical values of diagnosis-details.md §5.4 over 12
    /// candidates at alpha = 0.01: chi2_1 -> 11.17 (11.2), chi2_2 -> -2 ln(alpha/12)
    /// exactly (14.2), the one-sided chi-bar-square(1) -> 9.88 (9.9). References:
    /// the roots of erfc(sqrt(x/2)) = alpha (11.165481613648781) and
    /// erfc(sqrt(x/2))/2 = alpha (9.884612045478974), by bisection with Python's
    /// math.erfc.
    #[test]
    fn critical_values_of_the_library_test() {
        let alpha = 0.01 / 12.0;
        let c1 = critical_value(alpha, |x| chi2_sf(x, 1));
        let c2 = critical_value(alpha, |x| chi2_sf(x, 2));
        let cbar = critical_value(alpha, |x| chibar2_sf(x, 1, 1));
        assert!((c2 - (-2.0 * alpha.ln())).abs() < 1e-9, "{c2}");
        assert!((c1 - 11.165_481_613_648_781).abs() < 1e-8, "{c1}");
        assert!((cbar - 9.884_612_045_478_974).abs() < 1e-8, "{cbar}");
        // chibar(1,1) at c is half of chi2_1 at c, so its point is chi2_1's at 2 alpha.
        let c1_2a = critical_value(2.0 * alpha, |x| chi2_sf(x, 1));
        assert!((cbar - c1_2a).abs() < 1e-9 * cbar);
        // Weights of two parameters, one one-sided: 1/2 chi2_1 + 1/2 chi2_2.
        assert_eq!(chibar2_weights(2, 1), vec![(0.5, 1), (0.5, 2)]);
        assert_eq!(chibar2_weights(2, 2), vec![(0.25, 0), (0.5, 1), (0.25, 2)]);
    }

    #[test]
    fn holm_steps_down() {
        // m = 4, alpha = 0.05: thresholds 0.0125, 0.0167, 0.025, 0.05 in p order.
        let p = [0.01, 0.06, 0.012, 0.02];
        assert_eq!(holm(&p, 0.05), vec![true, false, true, true]);
        // A first failure stops the procedure: 0.04 would pass its own threshold
        // (0.05) but 0.03 fails 0.025 before it.
        assert_eq!(holm(&[0.03, 0.04, 0.001], 0.05), vec![false, false, true]);
        assert_eq!(holm(&[f64::NAN, 0.04], 0.05), vec![false, true]);
    }

    #[test]
    fn legendre_basis_is_orthonormal_and_spans_the_cubics() {
        // Uneven spacing.
        let times: Vec<f64> = (0..37).map(|i| (i as f64).powf(1.3) * 0.1 + 2.0).collect();
        let q = legendre_basis(&times, 3);
        assert_eq!(q.len(), 4);
        for a in 0..4 {
            for b in 0..4 {
                let expected = if a == b { 1.0 } else { 0.0 };
                assert!((dot(&q[a], &q[b]) - expected).abs() < 1e-13, "{a} {b}");
            }
        }
        // A cubic in t lies in the span: its projection is itself.
        let r: Vec<f64> = times.iter().map(|t| 1.0 - 2.0 * t + 0.3 * t * t - 0.01 * t * t * t).collect();
        let (t, dim) = smooth_statistic(&times, &r, 3);
        assert_eq!(dim, 4);
        assert!((t - dot(&r, &r)).abs() < 1e-10 * dot(&r, &r));
        // A quartic component is not (it keeps a part outside).
        let r4: Vec<f64> =
            times.iter().map(|t| legendre(4, (t - times[0]) / (times[36] - times[0]) * 2.0 - 1.0)).collect();
        let (t4, _) = smooth_statistic(&times, &r4, 3);
        assert!(t4 < 0.9 * dot(&r4, &r4));
        // Short segments get the full space.
        assert_eq!(legendre_basis(&[1.0, 2.0], 3).len(), 2);
        assert_eq!(legendre_basis(&[1.0], 3).len(), 1);
    }

    /// Under white unit noise the smooth statistic is chi2_4: its mean over many
    /// segments is 4 within 3 standard errors (sd of chi2_4 is sqrt 8).
    #[test]
    fn smooth_statistic_is_chi_square_under_noise() {
        let mut rng = crate::rng::SplitMix64::new(7);
        let times: Vec<f64> = (0..50).map(|i| i as f64).collect();
        let n = 2000;
        let mean: f64 = (0..n)
            .map(|_| {
                let r: Vec<f64> = times.iter().map(|_| rng.next_gaussian()).collect();
                smooth_statistic(&times, &r, 3).0
            })
            .sum::<f64>()
            / n as f64;
        assert!((mean - 4.0).abs() < 3.0 * (8.0f64 / n as f64).sqrt(), "{mean}");
    }

    #[test]
    fn quantiles_interpolate() {
        let v = [3.0, 1.0, 2.0, 4.0];
        assert_eq!(quantile(&v, 0.0), 1.0);
        assert_eq!(quantile(&v, 1.0), 4.0);
        assert!((quantile(&v, 0.5) - 2.5).abs() < 1e-15);
    }
}
