//! Logarithmic strain and the Hencky spring.
//!
//! For a symmetric positive definite `b = Q diag(l) Q^T`, `log b = Q diag(ln l) Q^T`
//! and its directional derivative is Daleckii-Krein's
//! `D log(b)[H] = Q (G o (Q^T H Q)) Q^T`, `G_ij = (ln l_i - ln l_j) / (l_i - l_j)`
//! (`1 / l_i` where the eigenvalues meet), which holds whatever basis of a repeated
//! eigenvalue the decomposition picks.
//!
//! Everything is computed from deviations from the identity (`F = I + h`,
//! `b = I + x`, `ln(1 + x)` by `ln_1p`), never by subtracting 1 from a number
//! near 1: a strain of 1e-10 then keeps its relative precision, and Newton's
//! residual its floor, at any strain.
//!
//! A Hencky spring of Young's modulus `E` and Poisson ratio `nu` on an
//! intermediate configuration whose inverse right Cauchy-Green tensor is `A`
//! (`A = C_v^-1` for a Maxwell network, `A = I` for a spring on the whole
//! deformation) has the elastic left Cauchy-Green tensor `b = F A F^T`, the
//! logarithmic strain `eps = log(b) / 2`, the Kirchhoff stress
//! `tau = E (lambda1 tr(eps) I + 2 mu1 eps)` with the unit-Young Lamé constants
//! `lambda1 = nu / ((1 + nu)(1 - 2 nu))`, `mu1 = 1 / (2 (1 + nu))`, and
//! `P = tau F^-T`. It is hyperelastic in `F` (the energy
//! `E (lambda1 tr(eps)^2 / 2 + mu1 eps : eps)` is isotropic in `b`), so its
//! tangent is major-symmetric. At small strain `tau` is Hooke's law
//! `E C1(nu) : e`, the seed's unit-Young shape.

use nalgebra::{Matrix3, SymmetricEigen};

use crate::material::law::{ij, Tangent};

/// Eigen-decomposition of a symmetric 3 x 3 matrix.
pub(crate) fn eigen(b: &Matrix3<f64>) -> (Matrix3<f64>, [f64; 3]) {
    let e = SymmetricEigen::new(*b);
    (e.eigenvectors, [e.eigenvalues[0], e.eigenvalues[1], e.eigenvalues[2]])
}

/// `(ln(1 + a) - ln(1 + b)) / (a - b)`, continuous where `a = b` (`1 / (1 + a)`)
/// and free of cancellation: `ln((1 + a)/(1 + b)) = ln_1p((a - b)/(1 + b))`.
pub(crate) fn log_divided_difference(a: f64, b: f64) -> f64 {
    let d = a - b;
    if d == 0.0 {
        1.0 / (1.0 + b)
    } else {
        (d / (1.0 + b)).ln_1p() / d
    }
}

/// `f(b) = Q diag(f(l)) Q^T` for a symmetric `b` given by its decomposition.
pub(crate) fn spectral(q: &Matrix3<f64>, l: [f64; 3], f: impl Fn(f64) -> f64) -> Matrix3<f64> {
    let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(f(l[0]), f(l[1]), f(l[2])));
    q * d * q.transpose()
}

/// `(x + x^T) / 2`.
pub(crate) fn symmetrize(x: &Matrix3<f64>) -> Matrix3<f64> {
    (x + x.transpose()) * 0.5
}

/// The unit-Young Lamé constants `(lambda1, mu1)` of a Poisson ratio.
pub(crate) fn unit_lame(poisson: f64) -> (f64, f64) {
    (poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)), 0.5 / (1.0 + poisson))
}

/// `E (lambda1 tr(x) I + 2 mu1 x)`.
pub(crate) fn hooke(e_mpa: f64, lame: (f64, f64), x: &Matrix3<f64>) -> Matrix3<f64> {
    (Matrix3::identity() * (lame.0 * x.trace()) + x * (2.0 * lame.1)) * e_mpa
}

/// The tangent of `E C1 : sym(h)` by `h`: `d s_ij / d h_kl` in the layout of
/// [`Tangent`] (rows `3 i + j`, columns `3 k + l`).
pub(crate) fn hooke_tangent(e_mpa: f64, lame: (f64, f64)) -> Tangent {
    let mut t = Tangent::zeros();
    for i in 0..3 {
        for k in 0..3 {
            t[(3 * i + i, 3 * k + k)] += e_mpa * lame.0;
            t[(3 * i + k, 3 * i + k)] += e_mpa * lame.1;
            t[(3 * i + k, 3 * k + i)] += e_mpa * lame.1;
        }
    }
    t
}

/// The inverse of [`hooke`]: the strain of a stress.
pub(crate) fn hooke_inverse(e_mpa: f64, lame: (f64, f64), s: &Matrix3<f64>) -> Matrix3<f64> {
    // s = E (l tr x I + 2 m x): tr s = E (3 l + 2 m) tr x.
    let tr_x = s.trace() / (e_mpa * (3.0 * lame.0 + 2.0 * lame.1));
    (s / e_mpa - Matrix3::identity() * (lame.0 * tr_x)) / (2.0 * lame.1)
}

/// `F A F^T - I` for `F = I + h` and `A = I + y`, summed without cancellation
/// (each term is of the order of the strains, so small strains keep their
/// relative precision).
pub(crate) fn push_deviation(h: &Matrix3<f64>, y: &Matrix3<f64>) -> Matrix3<f64> {
    let hy = h * y;
    symmetrize(&(y + h + h.transpose() + hy + hy.transpose() + h * h.transpose() + hy * h.transpose()))
}

/// A Hencky spring's stress at a point, with the decomposition its tangent
/// ([`spring_tangent`]) reuses.
pub(crate) struct SpringStress {
    /// The first Piola-Kirchhoff stress `P = tau F^-T`.
    pub p: Matrix3<f64>,
    /// The Kirchhoff stress `tau`.
    pub tau: Matrix3<f64>,
    /// The eigenvectors of `b = F A F^T`.
    pub q: Matrix3<f64>,
    /// The eigenvalues of `b - I`.
    pub x: [f64; 3],
}

/// A Hencky spring's stress at `F = I + h` on the intermediate configuration
/// `A = I + a_dev` (module docs), without its tangent.
pub(crate) fn spring_stress(
    h: &Matrix3<f64>,
    f_inv_t: &Matrix3<f64>,
    a_dev: &Matrix3<f64>,
    e_mpa: f64,
    lame: (f64, f64),
) -> SpringStress {
    // b - I = F A F^T - I, decomposed: b = Q diag(1 + x) Q^T.
    let (q, x) = eigen(&push_deviation(h, a_dev));
    let eps = spectral(&q, x, |v| 0.5 * v.ln_1p());
    let tau = hooke(e_mpa, lame, &eps);
    SpringStress { p: tau * f_inv_t, tau, q, x }
}

/// The tangent `dP/dF` of the spring whose stress is `s` ([`spring_stress`]
/// at the same arguments).
pub(crate) fn spring_tangent(
    h: &Matrix3<f64>,
    f_inv_t: &Matrix3<f64>,
    a_dev: &Matrix3<f64>,
    e_mpa: f64,
    lame: (f64, f64),
    s: &SpringStress,
) -> Tangent {
    let f = Matrix3::identity() + h;
    log_strain_tangent(&f, a_dev, &s.q, s.x, &s.tau, f_inv_t, |d_eps| hooke(e_mpa, lame, d_eps))
}

/// A Hencky spring's stress `P`, tangent `dP/dF` and Kirchhoff stress `tau` at
/// `F = I + h` on the intermediate configuration `A = I + a_dev` (module docs).
pub(crate) fn spring(
    h: &Matrix3<f64>,
    f_inv_t: &Matrix3<f64>,
    a_dev: &Matrix3<f64>,
    e_mpa: f64,
    lame: (f64, f64),
) -> (Matrix3<f64>, Tangent, Matrix3<f64>) {
    let s = spring_stress(h, f_inv_t, a_dev, e_mpa, lame);
    let tangent = spring_tangent(h, f_inv_t, a_dev, e_mpa, lame, &s);
    (s.p, tangent, s.tau)
}

/// `dP/dF` of `P = tau F^-T` for a Kirchhoff stress `tau` that depends on the
/// logarithmic strain `eps = 1/2 ln(b)`, `b = F A F^T = Q diag(1 + x) Q^T` on a
/// fixed intermediate configuration `A = I + a_dev`: the derivative of the log
/// by the Daleckii-Krein formula (divided differences in the principal frame),
/// then `d_tau`, the derivative of `tau` by `eps` as a map (the spring's
/// modulus, or a return mapping's consistent one), and the push by `F^-T`.
///
/// For `dF = e_k e_m^T` every rank-one factor is formed as an outer product:
/// with `c = F A e_m`, `db = e_k c^T + c e_k^T` and, in the principal frame,
/// `Q^T db Q = u v^T + v u^T` (`u = Q^T e_k`, `v = Q^T c`); the geometric term
/// `tau F^-T dF^T F^-T` is `(P e_m)(e_k^T F^-T)`. Three 3 x 3 products remain
/// per column (back from the principal frame, and the push by `F^-T`).
pub(crate) fn log_strain_tangent(
    f: &Matrix3<f64>,
    a_dev: &Matrix3<f64>,
    q: &Matrix3<f64>,
    x: [f64; 3],
    tau: &Matrix3<f64>,
    f_inv_t: &Matrix3<f64>,
    d_tau: impl Fn(&Matrix3<f64>) -> Matrix3<f64>,
) -> Tangent {
    let mut g = Matrix3::zeros();
    for i in 0..3 {
        for j in 0..3 {
            // Halved: eps = log(b) / 2.
            g[(i, j)] = 0.5 * log_divided_difference(x[i], x[j]);
        }
    }
    let qt = q.transpose();
    let qt_fa = qt * (f * (Matrix3::identity() + a_dev));
    let p = tau * f_inv_t;
    let mut tangent = Tangent::zeros();
    for k in 0..3 {
        let u = qt.column(k);
        for m in 0..3 {
            let v = qt_fa.column(m);
            let local = Matrix3::from_fn(|i, j| (u[i] * v[j] + v[i] * u[j]) * g[(i, j)]);
            let d_eps = q * local * qt;
            let mut dp = d_tau(&d_eps) * f_inv_t;
            for i in 0..3 {
                for j in 0..3 {
                    dp[(i, j)] -= p[(i, m)] * f_inv_t[(k, j)];
                }
            }
            for i in 0..3 {
                for j in 0..3 {
                    tangent[(ij(i, j), ij(k, m))] = dp[(i, j)];
                }
            }
        }
    }
    tangent
}

/// `C^-1 - I` for `F = I + h`, without cancellation: `-C^-1 (C - I)` with
/// `C - I = h + h^T + h^T h`.
pub(crate) fn inverse_right_deviation(h: &Matrix3<f64>, f_inv: &Matrix3<f64>) -> Matrix3<f64> {
    let c_inv = f_inv * f_inv.transpose();
    symmetrize(&(-c_inv * (h + h.transpose() + h.transpose() * h)))
}

/// `exp(x) - I` of a symmetric matrix.
pub(crate) fn sym_exp_m1(x: &Matrix3<f64>) -> Matrix3<f64> {
    let (q, l) = eigen(&symmetrize(x));
    spectral(&q, l, f64::exp_m1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::law::tangent_by_differences;

    fn sample_f() -> Matrix3<f64> {
        Matrix3::new(1.1, 0.2, -0.05, 0.03, 0.8, 0.1, -0.02, 0.07, 1.25)
    }

    #[test]
    fn the_log_of_exp_is_the_identity_and_the_divided_difference_is_continuous() {
        let x = Matrix3::new(0.2, 0.1, 0.0, 0.1, -0.3, 0.05, 0.0, 0.05, 0.1);
        let (q, l) = eigen(&sym_exp_m1(&x));
        let back = spectral(&q, l, f64::ln_1p);
        assert!((back - x).norm() < 1e-13);
        // Near and at a repeated value, and across it.
        for (a, b) in [(0.5, 0.3), (0.2, 0.2 + 1e-12), (1e-9, 2e-9)] {
            let exact = ((1.0f64 + a).ln() - (1.0f64 + b).ln()) / (a - b);
            let rel = if (a - b).abs() > 1e-6 { 1e-12 } else { 1e-3 };
            assert!((log_divided_difference(a, b) - exact).abs() < rel * exact.abs(), "{a} {b}");
        }
        assert_eq!(log_divided_difference(1.0, 1.0), 0.5);
        // Small strains keep their relative precision: log(I + x) of x ~ 1e-12.
        let tiny = x * 1e-12;
        let (q, l) = eigen(&tiny);
        let log = spectral(&q, l, f64::ln_1p);
        assert!((log - tiny).norm() < 1e-9 * tiny.norm());
    }

    /// The spring's tangent against central differences of its stress, on a
    /// general deformation and intermediate configuration, and at a repeated
    /// eigenvalue (F = I on A = I: the Daleckii-Krein limit).
    #[test]
    fn the_springs_tangent_matches_central_differences() {
        let lame = unit_lame(0.3);
        let a_dev = symmetrize(&Matrix3::new(0.05, 0.02, 0.01, 0.02, -0.03, -0.03, 0.01, -0.03, 0.1));
        for (f, a) in [(sample_f(), a_dev), (Matrix3::identity(), Matrix3::zeros())] {
            let eye = Matrix3::identity();
            let stress = |f: &Matrix3<f64>| spring(&(f - eye), &f.try_inverse().unwrap().transpose(), &a, 0.03, lame).0;
            let (_, t, _) = spring(&(f - eye), &f.try_inverse().unwrap().transpose(), &a, 0.03, lame);
            let fd = tangent_by_differences(&f, 1e-6, &stress);
            let err = (t - fd).amax() / t.amax();
            assert!(err < 1e-6, "tangent error {err:.3e}");
            // Hyperelastic: major symmetry.
            assert!((t - t.transpose()).amax() < 1e-12 * t.amax());
        }
    }

    #[test]
    fn hooke_inverse_inverts() {
        let lame = unit_lame(0.45);
        let x = Matrix3::new(0.2, 0.1, 0.0, 0.1, -0.3, 0.05, 0.0, 0.05, 0.1);
        assert!((hooke_inverse(2.0, lame, &hooke(2.0, lame, &x)) - x).norm() < 1e-14);
    }
}
