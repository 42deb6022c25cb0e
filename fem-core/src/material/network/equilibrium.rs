//! The equilibrium network: an isochoric energy of `I1bar = J^-2/3 tr(F^T F)`, the
//! volume energy `U(J) = K/2 (J - 1)^2` (CalculiX's and Abaqus's NEO HOOKE), and
//! optionally Ogden-Roxburgh softening.
//!
//! | energy        | `W(I1bar)`                                     | small strain      |
//! |---------------|------------------------------------------------|-------------------|
//! | `neo-hookean` | `mu/2 (I1bar - 3)`                             | Hooke, `E`, `nu`  |
//! | `exponential` | `mu/(2 b) [exp(b (I1bar - 3)) - 1]`            | Hooke, `E`, `nu`  |
//!
//! with `mu = E / (2 (1 + nu))`, `K = E / (3 (1 - 2 nu))`: at small strain the
//! network is the linear spring `E C1(nu)`, the seed's unit-Young shape.
//!
//! Ogden-Roxburgh (1999): the stress is `eta P0` with
//! `eta = 1 - erf((W_max - W) / (m + beta W_max)) / r`, `W` the virgin energy and
//! `W_max` its largest value so far (a per-point history). On the virgin curve
//! (`W >= W_max`) `eta = 1`; unloading and reloading below `W_max` are softer.

use nalgebra::Matrix3;

use crate::material::law::{ij, Tangent};

/// The isochoric energy of the equilibrium network.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Energy {
    /// `mu/2 (I1bar - 3)`.
    NeoHookean,
    /// `mu/(2 b) [exp(b (I1bar - 3)) - 1]`, `b > 0` (dimensionless).
    Exponential { stiffening: f64 },
}

/// Ogden-Roxburgh softening (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mullins {
    /// `r > 1`: the most softening is `1 - 1/r` of the stress.
    pub r: f64,
    /// `m` [MPa = mJ/mm^3]: the energy scale of the softening.
    pub m_mpa: f64,
    /// `beta >= 0`: its growth with `W_max`.
    pub beta: f64,
}

/// The equilibrium network.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Equilibrium {
    /// The isochoric energy.
    pub energy: Energy,
    /// Young's modulus at small strain [MPa].
    pub e_mpa: f64,
    /// Softening, if any.
    pub mullins: Option<Mullins>,
}

impl Equilibrium {
    /// `(W, dW/dI1bar, d2W/dI1bar2)` at `I1bar = 3 + i1bar_m3`, per unit `mu`.
    fn isochoric(&self, i1bar_m3: f64) -> (f64, f64, f64) {
        match self.energy {
            Energy::NeoHookean => (0.5 * i1bar_m3, 0.5, 0.0),
            Energy::Exponential { stiffening: b } => {
                let x = b * i1bar_m3;
                (0.5 * x.exp_m1() / b, 0.5 * x.exp(), 0.5 * b * x.exp())
            }
        }
    }

    /// The virgin stress `P0`, tangent and energy `W` at `F = I + h`
    /// (`j = det F > 0`, `f_inv_t = F^-T`). The stress is summed from terms of
    /// the order of the strain (`J - 1` from the invariants of `h`,
    /// `F - I1/3 F^-T = h + h^T F^-T - (2 tr h + |h|^2)/3 F^-T`), so that small
    /// strains keep their relative precision.
    pub(crate) fn virgin(
        &self,
        h: &Matrix3<f64>,
        f_inv_t: &Matrix3<f64>,
        poisson: f64,
    ) -> (Matrix3<f64>, Tangent, f64) {
        let mu = self.e_mpa / (2.0 * (1.0 + poisson));
        let kappa = self.e_mpa / (3.0 * (1.0 - 2.0 * poisson));
        let f = Matrix3::identity() + h;
        let tr = h.trace();
        let j_m1 = tr + 0.5 * (tr * tr - (h * h).trace()) + h.determinant();
        let j = 1.0 + j_m1;
        let i1_m3 = 2.0 * tr + h.norm_squared();
        let i1 = 3.0 + i1_m3;
        let jm23 = (-2.0 / 3.0 * j_m1.ln_1p()).exp();
        let j23_m1 = (2.0 / 3.0 * j_m1.ln_1p()).exp_m1();
        let i1bar_m3 = jm23 * (i1_m3 - 3.0 * j23_m1);
        let (w, w1, w11) = self.isochoric(i1bar_m3);
        let (w, w1, w11) = (mu * w, mu * w1, mu * w11);
        let (u, u1, u2) = (0.5 * kappa * j_m1 * j_m1, kappa * j_m1, kappa);
        // dI1bar/dF = 2 J^-2/3 (F - I1/3 F^-T).
        let d = (h + h.transpose() * f_inv_t - f_inv_t * (i1_m3 / 3.0)) * (2.0 * jm23);
        let p = d * w1 + f_inv_t * (u1 * j);
        let mut tangent = Tangent::zeros();
        for k in 0..3 {
            for m in 0..3 {
                let mut df = Matrix3::zeros();
                df[(k, m)] = 1.0;
                let tr = f_inv_t[(k, m)]; // F^-T : dF = dJ / J
                let d_finv_t = -f_inv_t * df.transpose() * f_inv_t;
                let d_d = (f * 2.0 - f_inv_t * (2.0 / 3.0 * i1)) * (-2.0 / 3.0 * jm23 * tr)
                    + (df * 2.0 - f_inv_t * (2.0 / 3.0 * 2.0 * f[(k, m)]) - d_finv_t * (2.0 / 3.0 * i1)) * jm23;
                let dp = d * (w11 * d[(k, m)]) + d_d * w1 + f_inv_t * ((u2 * j + u1) * j * tr) + d_finv_t * (u1 * j);
                for i in 0..3 {
                    for n in 0..3 {
                        tangent[(ij(i, n), ij(k, m))] = dp[(i, n)];
                    }
                }
            }
        }
        (p, tangent, w + u)
    }

    /// The stress and tangent at `F = I + h` with the softening applied, and the
    /// new largest energy, from the largest energy so far `w_max`.
    pub(crate) fn respond(
        &self,
        h: &Matrix3<f64>,
        f_inv_t: &Matrix3<f64>,
        poisson: f64,
        w_max: f64,
    ) -> (Matrix3<f64>, Tangent, f64) {
        let (p, t, w) = self.virgin(h, f_inv_t, poisson);
        let Some(mu) = self.mullins else {
            return (p, t, w_max.max(w));
        };
        if w >= w_max {
            return (p, t, w);
        }
        let scale = mu.m_mpa + mu.beta * w_max;
        let x = (w_max - w) / scale;
        let eta = 1.0 - erf(x) / mu.r;
        // d eta / dW = exp(-x^2) 2/sqrt(pi) / (r scale) (W_max is fixed below it).
        let eta_w = std::f64::consts::FRAC_2_SQRT_PI * (-x * x).exp() / (mu.r * scale);
        let pv = nalgebra::SVector::<f64, 9>::from_fn(|r, _| p[(r / 3, r % 3)]);
        (p * eta, t * eta + pv * pv.transpose() * eta_w, w_max)
    }
}

/// The error function (Abramowitz-Stegun 7.1.26 is too coarse for a tangent
/// check; this is the series below 2.5 and the continued fraction above,
/// relative error under 1e-15).
pub(crate) fn erf(x: f64) -> f64 {
    if x < 0.0 {
        return -erf(-x);
    }
    if x < 2.5 {
        // erf x = 2/sqrt(pi) sum_n (-1)^n x^(2n+1) / (n! (2n+1)).
        let mut term = x;
        let mut sum = x;
        let x2 = x * x;
        for n in 1..200 {
            term *= -x2 / n as f64;
            let add = term / (2 * n + 1) as f64;
            sum += add;
            if add.abs() < 1e-17 * sum.abs() {
                break;
            }
        }
        std::f64::consts::FRAC_2_SQRT_PI * sum
    } else {
        // erfc x = exp(-x^2)/sqrt(pi) * 1/(x + 1/2/(x + 1/(x + 3/2/(x + ...)))).
        let mut cf = 0.0;
        for n in (1..60).rev() {
            cf = (n as f64 / 2.0) / (x + cf);
        }
        1.0 - (-x * x).exp() / std::f64::consts::PI.sqrt() / (x + cf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::law::tangent_by_differences;

    #[test]
    fn erf_matches_known_values() {
        for (x, want) in
            [(0.5, 0.520_499_877_813_046_5), (1.0, 0.842_700_792_949_714_9), (3.0, 0.999_977_909_503_001_4)]
        {
            assert!((erf(x) - want).abs() < 1e-15, "erf({x}) = {}", erf(x));
        }
    }

    #[test]
    fn the_equilibrium_tangents_match_central_differences() {
        let f = Matrix3::new(1.1, 0.2, -0.05, 0.03, 0.7, 0.1, -0.02, 0.07, 1.25);
        let laws = [
            Equilibrium { energy: Energy::NeoHookean, e_mpa: 0.03, mullins: None },
            Equilibrium { energy: Energy::Exponential { stiffening: 2.4 }, e_mpa: 0.03, mullins: None },
            Equilibrium {
                energy: Energy::Exponential { stiffening: 0.8 },
                e_mpa: 0.03,
                mullins: Some(Mullins { r: 2.0, m_mpa: 1e-3, beta: 0.1 }),
            },
        ];
        for law in laws {
            let w_max = 0.02; // above W at f: the softened branch
            let respond = |f: &Matrix3<f64>| {
                let fit = f.try_inverse().unwrap().transpose();
                law.respond(&(f - Matrix3::identity()), &fit, 0.45, w_max)
            };
            let (_, t, _) = respond(&f);
            let fd = tangent_by_differences(&f, 1e-6, &|f| respond(f).0);
            let err = (t - fd).amax() / t.amax();
            assert!(err < 1e-6, "{law:?}: tangent error {err:.3e}");
            assert!((t - t.transpose()).amax() < 1e-12 * t.amax(), "major symmetry");
        }
    }

    /// Uniaxial stress in the incompressible limit of the neo-Hookean energy is
    /// `P = mu (lambda - lambda^-2)`; at nu = 0.4999 the law is within 1e-3 of it.
    #[test]
    fn neo_hookean_stress_at_a_stretch_follows_the_closed_form() {
        let law = Equilibrium { energy: Energy::NeoHookean, e_mpa: 0.03, mullins: None };
        let nu = 0.4999;
        let mu = 0.03 / (2.0 * (1.0 + nu));
        let lambda = 0.6;
        // Lateral stretch from the zero lateral stress condition, by bisection.
        let lateral_stress = |lt: f64| {
            let f = Matrix3::from_diagonal(&nalgebra::Vector3::new(lt, lambda, lt));
            law.virgin(&(f - Matrix3::identity()), &f.try_inverse().unwrap().transpose(), nu).0[(0, 0)]
        };
        let (mut lo, mut hi) = (1.0, 2.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if lateral_stress(mid) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let lt = 0.5 * (lo + hi);
        let f = Matrix3::from_diagonal(&nalgebra::Vector3::new(lt, lambda, lt));
        let p = law.virgin(&(f - Matrix3::identity()), &f.try_inverse().unwrap().transpose(), nu).0[(1, 1)];
        let closed = mu * (lambda - lambda.powi(-2));
        assert!(((p - closed) / closed).abs() < 1e-3, "{p} vs {closed}");
    }
}
