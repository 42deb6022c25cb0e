//! The plastic network: a Hencky spring on `F = Fe Fp` with von Mises (J2)
//! yield, linear isotropic hardening and isochoric plastic flow, integrated by
//! the exponential map. It gives the permanent set.
//!
//! With a Hencky spring the exponential map's return is radial in the principal
//! logarithmic strains (Simo 1992; Eterovic & Bathe 1990), in closed form: the
//! trial elastic strain `eps_tr = log(F Cp_n^-1 F^T) / 2`, its deviator
//! `s_tr = 2 mu dev(eps_tr)` (Kirchhoff), the yield function
//! `f = |s_tr| - sqrt(2/3) (sigma_y + H alpha_n)` and, when `f > 0`, the
//! plastic multiplier `dgamma = f / (2 mu + 2/3 H)`, the return
//! `eps_e = eps_tr - dgamma n` with `n = s_tr / |s_tr|` and
//! `alpha = alpha_n + sqrt(2/3) dgamma`. The flow is deviatoric, so the plastic
//! deformation keeps the volume. The elastic configuration follows:
//! `Cp^-1 = F^-1 exp(2 eps_e) F^-T`.
//!
//! The Kirchhoff stress is the small-strain radial return's, applied to the
//! tensor `eps_tr`: `tau = K tr(eps_tr) I + 2 mu (dev eps_tr - dgamma n)`. Its
//! derivative is the classical consistent modulus (Simo & Taylor 1985)
//! `K 1 x 1 + 2 mu theta I_dev - 2 mu theta_bar n x n`, with
//! `theta = 1 - 2 mu dgamma / |s_tr|` and
//! `theta_bar = 1 / (1 + H / (3 mu)) - (1 - theta)`, and `eps_tr` follows `F`
//! through Daleckii-Krein's derivative of the logarithm ([`super::hencky`]).
//! The step's stress is the gradient of an incremental potential isotropic in
//! `F Cp_n^-1 F^T`, so `P = tau F^-T` and the tangent is major-symmetric.
//!
//! At small strain the network is the classical elastoplastic element (a spring
//! in series with a friction slider that hardens).
//!
//! History (7 values): `Cp^-1 - I` as `[xx, yy, zz, xy, xz, yz]`, then the
//! equivalent plastic strain `alpha`.

use std::sync::Arc;

use nalgebra::Matrix3;

use super::hencky::{self, eigen, symmetrize};
use super::part::{Kinematics, Part, PartKind};
use crate::material::law::{LawFailure, ParameterSpec, Start, Tangent};

/// The history length of a plastic network.
pub(crate) const HISTORY: usize = 7;

/// A plastic network: a Hencky spring with J2 yield and linear isotropic hardening.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlasticNetwork {
    /// The spring's Young's modulus [MPa].
    pub e_mpa: f64,
    /// The uniaxial yield stress (Kirchhoff) of the virgin material [MPa].
    pub yield_mpa: f64,
    /// The linear isotropic hardening modulus `H` [MPa]: the yield stress grows
    /// by `H` per unit equivalent plastic strain.
    pub hardening_mpa: f64,
}

/// `[plastic]`: one plastic network.
pub static KIND: PartKind = PartKind {
    table: "plastic",
    meaning: "a plastic network: the permanent set",
    max_count: 1,
    parameters: &[
        ParameterSpec::new("E_MPa", "the spring's Young's modulus", "MPa", (0.0, true), 1e4, None)
            .fit(1e-5, 1e2, true)
            .start(Start::OfModulus(0.25)),
        // Yielding at a tenth of the apparent stress at 20 % strain.
        ParameterSpec::new("yield_MPa", "uniaxial yield stress", "MPa", (0.0, true), 1e4, None)
            .fit(1e-6, 1e2, true)
            .start(Start::OfModulus(0.02)),
        ParameterSpec::new("hardening_MPa", "linear isotropic hardening modulus", "MPa", (0.0, false), 1e4, Some(0.0))
            .fit(1e-6, 1e2, true)
            .start(Start::OfModulus(0.1)),
    ],
    build: |v| Arc::new(PlasticNetwork { e_mpa: v[0], yield_mpa: v[1], hardening_mpa: v[2] }),
};

impl Part for PlasticNetwork {
    fn kind(&self) -> &'static PartKind {
        &KIND
    }

    fn values(&self) -> Vec<f64> {
        vec![self.e_mpa, self.yield_mpa, self.hardening_mpa]
    }

    fn history_len(&self) -> usize {
        HISTORY
    }

    fn small_strain_modulus(&self) -> f64 {
        self.e_mpa
    }

    fn respond(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        Ok(respond(self, k.h, &k.f_inv, k.poisson, old, new))
    }
}

/// The plastic network's response at `F = I + h`: the first Piola-Kirchhoff
/// stress and its tangent; writes the new history into `new`.
pub(crate) fn respond(
    net: &PlasticNetwork,
    h: &Matrix3<f64>,
    f_inv: &Matrix3<f64>,
    poisson: f64,
    old: &[f64],
    new: &mut [f64],
) -> (Matrix3<f64>, Tangent) {
    let alpha_n = old[6];
    let (p, tangent, dgamma) = radial_return(net.e_mpa, h, f_inv, poisson, old, new, |s_norm, mu| {
        let radius = (2.0f64 / 3.0).sqrt() * (net.yield_mpa + net.hardening_mpa * alpha_n);
        let yielding = s_norm - radius;
        (yielding > 0.0).then(|| {
            (yielding / (2.0 * mu + 2.0 / 3.0 * net.hardening_mpa), 1.0 / (1.0 + net.hardening_mpa / (3.0 * mu)))
        })
    });
    new[6] = alpha_n + (2.0f64 / 3.0).sqrt() * dgamma;
    (p, tangent)
}

/// The exponential map's radial return of a Hencky spring of modulus `e_mpa`
/// on `F = Fe Fp`, `Cp_n^-1 - I` in `old[0..6]` (module docs), for any
/// isochoric flow whose multiplier depends on the trial stress only:
/// `rule(|s_tr|, mu)` gives `None` when the step is elastic, otherwise the
/// multiplier `dgamma > 0` and the flow's stiffness share
/// `1 / (1 + R'(dgamma) / (2 mu))`, `R` the return's radius `|s|` as a
/// function of `dgamma` (`2/3 H` for linear hardening). Writes `Cp^-1 - I`
/// into `new[0..6]`; returns `P`, its exact tangent and `dgamma`.
pub(crate) fn radial_return(
    e_mpa: f64,
    h: &Matrix3<f64>,
    f_inv: &Matrix3<f64>,
    poisson: f64,
    old: &[f64],
    new: &mut [f64],
    rule: impl Fn(f64, f64) -> Option<(f64, f64)>,
) -> (Matrix3<f64>, Tangent, f64) {
    let f_inv_t = f_inv.transpose();
    let (lambda1, mu1) = hencky::unit_lame(poisson);
    let mu = e_mpa * mu1;
    let bulk = e_mpa * (lambda1 + 2.0 * mu1 / 3.0);
    let cp_inv_dev = super::sym_from(&old[0..6]);
    let f = Matrix3::identity() + h;

    // The trial elastic strain, in the principal frame of b_tr = F Cp_n^-1 F^T.
    let (q, x) = eigen(&hencky::push_deviation(h, &cp_inv_dev));
    let eps = [0.5 * x[0].ln_1p(), 0.5 * x[1].ln_1p(), 0.5 * x[2].ln_1p()];
    let mean = (eps[0] + eps[1] + eps[2]) / 3.0;
    let dev = [eps[0] - mean, eps[1] - mean, eps[2] - mean];
    let s_norm = 2.0 * mu * (dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]).sqrt();
    let flow = if s_norm > 0.0 { rule(s_norm, mu) } else { None };
    let (dgamma, share, n) = match flow {
        Some((dgamma, share)) => {
            let n = [2.0 * mu * dev[0] / s_norm, 2.0 * mu * dev[1] / s_norm, 2.0 * mu * dev[2] / s_norm];
            (dgamma, share, n)
        }
        None => (0.0, 1.0, [0.0; 3]),
    };
    let eps_e = [eps[0] - dgamma * n[0], eps[1] - dgamma * n[1], eps[2] - dgamma * n[2]];
    let tr = 3.0 * mean;
    let tau_p: [f64; 3] = std::array::from_fn(|i| bulk * tr + 2.0 * mu * (dev[i] - dgamma * n[i]));
    let qt = q.transpose();
    let tau = q * Matrix3::from_diagonal(&tau_p.into()) * qt;
    let p = tau * f_inv_t;

    // The consistent modulus on the trial strain, as a map of symmetric tensors.
    let (theta, theta_bar) = if dgamma > 0.0 {
        let theta = 1.0 - 2.0 * mu * dgamma / s_norm;
        (theta, share - (1.0 - theta))
    } else {
        (1.0, 0.0)
    };
    let n_tensor = q * Matrix3::from_diagonal(&n.into()) * qt;
    let modulus = |d_eps: &Matrix3<f64>| {
        let t = d_eps.trace();
        let d_dev = d_eps - Matrix3::identity() * (t / 3.0);
        Matrix3::identity() * (bulk * t) + d_dev * (2.0 * mu * theta)
            - n_tensor * (2.0 * mu * theta_bar * n_tensor.dot(d_eps))
    };
    let tangent =
        hencky::log_strain_tangent(&f, &cp_inv_dev, &q, x, &tau, &f_inv_t, |d_eps| modulus(&symmetrize(d_eps)));

    // The new state: Cp^-1 - I = F^-1 (b_e - I) F^-T + (C^-1 - I).
    let b_e_dev = q * Matrix3::from_diagonal(&eps_e.map(|e| (2.0 * e).exp_m1()).into()) * qt;
    let cp_inv_new = f_inv * b_e_dev * f_inv_t + hencky::inverse_right_deviation(h, f_inv);
    super::sym_to(&symmetrize(&cp_inv_new), &mut new[0..6]);
    (p, tangent, dgamma)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::law::tangent_by_differences;

    const NET: PlasticNetwork = PlasticNetwork { e_mpa: 0.05, yield_mpa: 2e-3, hardening_mpa: 0.01 };

    fn step(f: &Matrix3<f64>, old: &[f64]) -> (Matrix3<f64>, Tangent, Vec<f64>) {
        let mut new = old.to_vec();
        let (p, t) = respond(&NET, &(f - Matrix3::identity()), &f.try_inverse().unwrap(), 0.35, old, &mut new);
        (p, t, new)
    }

    /// The tangent against central differences of the stress, on the elastic
    /// branch and on the plastic one, from a yielded state (so that `Cp` is away
    /// from the identity).
    #[test]
    fn the_tangent_matches_central_differences_elastic_and_plastic() {
        let f1 = Matrix3::new(1.05, 0.1, 0.0, 0.02, 0.8, 0.03, 0.0, 0.01, 1.1);
        let (_, _, yielded) = step(&f1, &[0.0; HISTORY]);
        assert!(yielded[6] > 0.0, "the first step yields");
        // Further along the same path (plastic) and back a little (elastic).
        let further = f1 * Matrix3::new(1.02, 0.01, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 1.03);
        let back = f1 * Matrix3::new(0.995, 0.0, 0.0, 0.0, 1.01, 0.0, 0.0, 0.0, 0.995);
        for (f, plastic) in [(further, true), (back, false)] {
            let (_, t, new) = step(&f, &yielded);
            assert_eq!(new[6] > yielded[6], plastic);
            let fd = tangent_by_differences(&f, 1e-7, &|f: &Matrix3<f64>| step(f, &yielded).0);
            let err = (t - fd).amax() / t.amax();
            assert!(err < 1e-6, "plastic {plastic}: tangent error {err:.3e}");
            assert!((t - t.transpose()).amax() < 1e-10 * t.amax(), "major symmetry");
        }
    }

    /// After yielding, the stress lies on the yield surface, the plastic flow
    /// keeps the volume (det Cp = 1), and unloading to `F = I` leaves a stress
    /// (the spring holds the permanent set).
    #[test]
    fn the_return_lands_on_the_surface_and_keeps_the_volume() {
        let f = Matrix3::new(1.2, 0.05, 0.0, 0.0, 0.7, 0.0, 0.0, 0.0, 1.15);
        let (p, _, new) = step(&f, &[0.0; HISTORY]);
        let tau = p * f.transpose();
        let dev = tau - Matrix3::identity() * (tau.trace() / 3.0);
        let radius = (2.0f64 / 3.0).sqrt() * (NET.yield_mpa + NET.hardening_mpa * new[6]);
        assert!((dev.norm() - radius).abs() < 1e-12 * radius, "{} against {radius}", dev.norm());
        let cp_inv = Matrix3::identity() + super::super::sym_from(&new[0..6]);
        assert!((cp_inv.determinant() - 1.0).abs() < 1e-12);
        let (p0, _, _) = step(&Matrix3::identity(), &new);
        assert!(p0.norm() > 0.1 * NET.yield_mpa);
    }
}
