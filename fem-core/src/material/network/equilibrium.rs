//! The equilibrium network: an isochoric energy of `I1bar = J^-2/3 tr(F^T F)`, the
//! volume energy `U(J) = K/2 (J - 1)^2` (CalculiX's and Abaqus's NEO HOOKE), and
//! optionally Ogden-Roxburgh softening.
//!
//! | energy        | `W(I1bar)`                                     | small strain      |
//! |---------------|------------------------------------------------|-------------------|
//! | `neo-hookean` | `mu/2 (I1bar - 3)`                             | Hooke, `E`, `nu`  |
//! | `exponential` | `mu/(2 b) [exp(b (I1bar - 3)) - 1]`            | Hooke, `E`, `nu`  |
//! | `ogden`       | `sum_p 2 mu_p / alpha_p^2 sum_i (lbar_i^alpha_p - 1)` | Hooke, `E`, `nu`  |
//!
//! Ogden's terms (at most [`OGDEN_TERMS`]) have the shear moduli `mu_p = s_p mu`,
//! shares `s_p > 0` summing to 1, so `E` keeps its meaning; `lbar_i` are the
//! isochoric principal stretches. In the principal log strains `eps_i` with
//! deviatoric parts `e_i`, `lbar_i^alpha = exp(alpha e_i)`: the energy is an
//! isotropic function of the log strain, its Kirchhoff stress
//! `tau = sum_p 2 mu_p / alpha_p dev(exp(alpha_p e)) + K J (J - 1) I` is coaxial
//! with it, and the tangent goes through the log strain's Daleckii-Krein
//! derivative ([`super::hencky::log_strain_tangent`]). `alpha = 2` (one term)
//! is the neo-Hookean energy.
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
    /// Ogden's energy (module docs): exponents `alpha` and shares of `mu`;
    /// a term whose share is 0 is absent.
    Ogden { alpha: [f64; OGDEN_TERMS], share: [f64; OGDEN_TERMS] },
}

/// The most terms of an Ogden energy.
pub const OGDEN_TERMS: usize = 3;

/// The energies as a bundle names them (`energy = "..."`).
pub const ENERGIES: &[&str] = &["neo-hookean", "exponential", "ogden"];

/// The `[equilibrium]` parameter keys of the energy named `energy`
/// ([`super::parameters::EQUILIBRIUM`]), `None` for an unknown name.
pub fn energy_keys(energy: &str) -> Option<&'static [&'static str]> {
    match energy {
        "neo-hookean" => Some(&["E_MPa"]),
        "exponential" => Some(&["E_MPa", "stiffening"]),
        "ogden" => Some(&["E_MPa", "alpha1", "alpha2", "share2", "alpha3", "share3"]),
        _ => None,
    }
}

impl Energy {
    /// The energy's name in a bundle.
    pub fn name(&self) -> &'static str {
        match self {
            Energy::NeoHookean => "neo-hookean",
            Energy::Exponential { .. } => "exponential",
            Energy::Ogden { .. } => "ogden",
        }
    }
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
            Energy::Ogden { .. } => unreachable!("Ogden's energy is not a function of I1bar"),
        }
    }

    /// Ogden's stress, tangent and energy at `F = I + h` (module docs).
    fn ogden(
        &self,
        alpha: &[f64; OGDEN_TERMS],
        share: &[f64; OGDEN_TERMS],
        h: &Matrix3<f64>,
        f_inv_t: &Matrix3<f64>,
        poisson: f64,
        with_tangent: bool,
    ) -> (Matrix3<f64>, Option<Tangent>, f64) {
        use super::hencky::{eigen, log_strain_tangent, symmetrize};
        let mu = self.e_mpa / (2.0 * (1.0 + poisson));
        let kappa = self.e_mpa / (3.0 * (1.0 - 2.0 * poisson));
        let f = Matrix3::identity() + h;
        // b - I = h + h^T + h h^T, its eigenvalues x_i, eps_i = ln(1 + x_i) / 2.
        let (q, x) = eigen(&symmetrize(&(h + h.transpose() + h * h.transpose())));
        let eps = x.map(|v| 0.5 * v.ln_1p());
        let tr = eps[0] + eps[1] + eps[2];
        let e = eps.map(|v| v - tr / 3.0);
        let tr_h = h.trace();
        let j_m1 = tr_h + 0.5 * (tr_h * tr_h - (h * h).trace()) + h.determinant();
        let j = 1.0 + j_m1;
        let terms: Vec<(f64, f64)> =
            alpha.iter().zip(share).filter(|(_, &s)| s > 0.0).map(|(&a, &s)| (a, s * mu)).collect();
        // Principal Kirchhoff stresses and the energy.
        let mut tau_p = [kappa * j * j_m1; 3];
        let mut w = 0.5 * kappa * j_m1 * j_m1;
        for &(a, mu_p) in &terms {
            let g = e.map(|v| (a * v).exp_m1());
            let mean = (g[0] + g[1] + g[2]) / 3.0;
            for i in 0..3 {
                tau_p[i] += 2.0 * mu_p / a * (g[i] - mean);
            }
            w += 2.0 * mu_p / (a * a) * (g[0] + g[1] + g[2]);
        }
        let qt = q.transpose();
        let tau = q * Matrix3::from_diagonal(&nalgebra::Vector3::from(tau_p)) * qt;
        let p = tau * f_inv_t;
        if !with_tangent {
            return (p, None, w);
        }
        // d tau / d eps in the principal frame: per term, dev of the divided
        // differences of exp(a e) applied to dev(d eps); the volume's
        // K (2 J - 1) J tr(d eps) I.
        let divided: Vec<Matrix3<f64>> = terms
            .iter()
            .map(|&(a, _)| {
                Matrix3::from_fn(|i, k| {
                    let d = e[i] - e[k];
                    if d == 0.0 {
                        a * (a * e[i]).exp()
                    } else {
                        (a * e[k]).exp() * (a * d).exp_m1() / d
                    }
                })
            })
            .collect();
        let d_tau = |d_eps: &Matrix3<f64>| -> Matrix3<f64> {
            let local = qt * d_eps * q;
            let trace = local.trace();
            let dev = local - Matrix3::identity() * (trace / 3.0);
            let mut out = Matrix3::identity() * (kappa * (2.0 * j - 1.0) * j * trace);
            for (&(a, mu_p), g) in terms.iter().zip(&divided) {
                let m = dev.component_mul(g);
                let m = m - Matrix3::identity() * (m.trace() / 3.0);
                out += m * (2.0 * mu_p / a);
            }
            q * out * qt
        };
        let tangent = log_strain_tangent(&f, &Matrix3::zeros(), &q, x, &tau, f_inv_t, d_tau);
        (p, Some(tangent), w)
    }

    /// The virgin stress `P0`, tangent (when `with_tangent`) and energy `W` at `F = I + h`
    /// (`j = det F > 0`, `f_inv_t = F^-T`). The stress is summed from terms of
    /// the order of the strain (`J - 1` from the invariants of `h`,
    /// `F - I1/3 F^-T = h + h^T F^-T - (2 tr h + |h|^2)/3 F^-T`), so that small
    /// strains keep their relative precision.
    pub(crate) fn virgin(
        &self,
        h: &Matrix3<f64>,
        f_inv_t: &Matrix3<f64>,
        poisson: f64,
        with_tangent: bool,
    ) -> (Matrix3<f64>, Option<Tangent>, f64) {
        if let Energy::Ogden { alpha, share } = &self.energy {
            return self.ogden(alpha, share, h, f_inv_t, poisson, with_tangent);
        }
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
        if !with_tangent {
            return (p, None, w + u);
        }
        let mut tangent = Tangent::zeros();
        for k in 0..3 {
            for m in 0..3 {
                let mut df = Matrix3::zeros();
                df[(k, m)] = 1.0;
                let tr = f_inv_t[(k, m)]; // F^-T : dF = dJ / J
                                          // d F^-T = -F^-T dF^T F^-T = -(F^-T e_m)(e_k^T F^-T).
                let d_finv_t = -f_inv_t.column(m) * f_inv_t.row(k);
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
        (p, Some(tangent), w + u)
    }

    /// The stress and (when `with_tangent`) tangent at `F = I + h` with the
    /// softening applied, and the new largest energy, from the largest energy
    /// so far `w_max`.
    pub(crate) fn respond(
        &self,
        h: &Matrix3<f64>,
        f_inv_t: &Matrix3<f64>,
        poisson: f64,
        w_max: f64,
        with_tangent: bool,
    ) -> (Matrix3<f64>, Option<Tangent>, f64) {
        let (p, t, w) = self.virgin(h, f_inv_t, poisson, with_tangent);
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
        (p * eta, t.map(|t| t * eta + pv * pv.transpose() * eta_w), w_max)
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
            Equilibrium {
                energy: Energy::Ogden { alpha: [5.0, -2.5, 1.3], share: [0.5, 0.3, 0.2] },
                e_mpa: 0.03,
                mullins: None,
            },
            Equilibrium {
                energy: Energy::Ogden { alpha: [8.0, 2.0, 2.0], share: [0.6, 0.4, 0.0] },
                e_mpa: 0.03,
                mullins: Some(Mullins { r: 2.0, m_mpa: 1e-3, beta: 0.1 }),
            },
        ];
        for law in laws {
            let w_max = 0.02; // above W at f: the softened branch
            let respond = |f: &Matrix3<f64>| {
                let fit = f.try_inverse().unwrap().transpose();
                law.respond(&(f - Matrix3::identity()), &fit, 0.45, w_max, true)
            };
            let t = respond(&f).1.unwrap();
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
            law.virgin(&(f - Matrix3::identity()), &f.try_inverse().unwrap().transpose(), nu, false).0[(0, 0)]
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
        let p = law.virgin(&(f - Matrix3::identity()), &f.try_inverse().unwrap().transpose(), nu, false).0[(1, 1)];
        let closed = mu * (lambda - lambda.powi(-2));
        assert!(((p - closed) / closed).abs() < 1e-3, "{p} vs {closed}");
    }

    /// Ogden's energy: one term of alpha = 2 is the neo-Hookean energy (stress
    /// and tangent to 1e-12 and 1e-10, at a general F and at F = I + 1e-9 h,
    /// where the stress keeps its relative precision); the tangent at a repeated
    /// eigenvalue (a uniaxial stretch) matches central differences.
    #[test]
    fn ogden_with_alpha_2_is_neo_hookean_and_its_tangent_holds_at_repeated_stretches() {
        let nh = Equilibrium { energy: Energy::NeoHookean, e_mpa: 0.03, mullins: None };
        let og = Equilibrium {
            energy: Energy::Ogden { alpha: [2.0, 3.0, 3.0], share: [1.0, 0.0, 0.0] },
            e_mpa: 0.03,
            mullins: None,
        };
        let general = Matrix3::new(0.1, 0.2, -0.05, 0.03, -0.3, 0.1, -0.02, 0.07, 0.25);
        for h in [general, general * 1e-9] {
            let fit = (Matrix3::identity() + h).try_inverse().unwrap().transpose();
            let (p1, t1, w1) = nh.virgin(&h, &fit, 0.45, true);
            let (p2, t2, w2) = og.virgin(&h, &fit, 0.45, true);
            let (t1, t2) = (t1.unwrap(), t2.unwrap());
            assert!((p1 - p2).amax() <= 1e-12 * p1.amax(), "stress {:.3e}", (p1 - p2).amax() / p1.amax());
            assert!((t1 - t2).amax() <= 1e-10 * t1.amax(), "tangent {:.3e}", (t1 - t2).amax() / t1.amax());
            // The energy's first-order terms cancel (sum_i e_i = 0), so at 1e-9
            // it keeps about 1e-7 relative precision; it only sets the softening.
            let rel = if h == general { 1e-12 } else { 1e-6 };
            assert!((w1 - w2).abs() <= rel * w1.abs(), "energy {w1} vs {w2}");
        }
        let three = Equilibrium {
            energy: Energy::Ogden { alpha: [5.0, -2.5, 1.3], share: [0.5, 0.3, 0.2] },
            e_mpa: 0.03,
            mullins: None,
        };
        let f = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.2, 0.7, 1.2));
        let respond = |f: &Matrix3<f64>| {
            let fit = f.try_inverse().unwrap().transpose();
            three.virgin(&(f - Matrix3::identity()), &fit, 0.45, true)
        };
        let t = respond(&f).1.unwrap();
        let fd = tangent_by_differences(&f, 1e-6, &|f| respond(f).0);
        assert!((t - fd).amax() < 1e-6 * t.amax(), "tangent error {:.3e}", (t - fd).amax() / t.amax());
    }
}
