//! The plastic network: a Hencky spring on `F = Fe Fp` with von Mises (J2)
//! yield, linear isotropic hardening and isochoric plastic flow, integrated by
//! the exponential map, and optional linear kinematic hardening (below). It
//! gives the permanent set.
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
//! ## Kinematic hardening
//!
//! With a kinematic modulus `H_k > 0` the network hardens kinematically too:
//! linear Prager hardening, the back stress `beta = 2/3 H_k eps_p` (a
//! deviatoric tensor), the yield function `|dev tau - beta| - sqrt(2/3)
//! (sigma_y + H alpha)`; under uniaxial stress the scalar law
//! `|tau - H_k p| <= sigma_y + H alpha`, `tau = E (eps - p)`, which yields
//! again in reverse once the stress has fallen by `2 (sigma_y + H alpha)` from
//! the back stress `H_k p` (the Bauschinger effect).
//!
//! It is built as the sublayer (overlay) form of Prager's law (Besseling 1958):
//! at small strain, on every path, J2 with linear kinematic hardening equals a
//! J2 network with isotropic hardening only in parallel with an elastic spring,
//! both of the material's Poisson ratio, with the share
//! `s = 3 mu / (3 mu + H_k)` (`mu` the spring's shear modulus):
//!
//! ```text
//! E_sub = s E,   sigma_y,sub = s sigma_y,   H_sub = s^2 H,   E_spring = (1 - s) E,
//! ```
//!
//! since the sublayer's deviatoric stress is `s (dev tau - beta)` and its
//! plastic strain `eps_p / s`: the two yield together, and the sublayer's
//! multiplier is Prager's over `s`. At finite strain the network is that pair: the
//! sublayer is this file's exponential-map return on `F = Fe Fp` and the spring
//! a Hencky spring on `F`. The back stress is thus held as a tensor, the
//! sublayer's plastic configuration `Cp` (a reference tensor), so the law is
//! objective on any path, its return stays closed-form and radial in the
//! principal logarithmic strains, and its tangent (the sum of the two exact
//! ones) stays major-symmetric. On paths of fixed principal axes (homogeneous
//! compression and pull back) the logarithmic strains add, and the network is
//! Prager's law in the log strains exactly; on rotating paths it is the
//! sublayer model's finite-strain form, one of the extensions of Prager's law,
//! not another. `H_k = 0` runs the isotropic network alone (bit for bit).
//!
//! History (7 values): `Cp^-1 - I` as `[xx, yy, zz, xy, xz, yz]`, then the
//! equivalent plastic strain `alpha` of the return (the sublayer's, `1 / s`
//! times the material's, with kinematic hardening).

use std::sync::Arc;

use nalgebra::Matrix3;

use super::hencky::{self, eigen, symmetrize};
use super::part::{Kinematics, Part, PartKind};
use crate::material::law::{LawFailure, ParameterSpec, Start, Tangent};

/// The history length of a plastic network.
pub(crate) const HISTORY: usize = 7;

/// A plastic network: a Hencky spring with J2 yield, linear isotropic and
/// linear kinematic hardening (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlasticNetwork {
    /// The spring's Young's modulus [MPa].
    pub e_mpa: f64,
    /// The uniaxial yield stress (Kirchhoff) of the virgin material [MPa].
    pub yield_mpa: f64,
    /// The linear isotropic hardening modulus `H` [MPa]: the yield stress grows
    /// by `H` per unit equivalent plastic strain.
    pub hardening_mpa: f64,
    /// The linear kinematic (Prager) hardening modulus `H_k` [MPa]: the back
    /// stress grows by `H_k` per unit uniaxial plastic strain (module docs).
    pub kinematic_mpa: f64,
}

/// `[plastic]`: one plastic network.
pub static KIND: PartKind = PartKind {
    table: "plastic",
    meaning: "a plastic network: the permanent set",
    max_count: 1,
    parameters: &[
        super::part::SPRING_MODULUS,
        // Yielding at a tenth of the apparent stress at 20 % strain.
        ParameterSpec::new("yield_MPa", "uniaxial yield stress", "MPa", (0.0, true), 1e4, None)
            .fit(1e-6, 1e2, true)
            .start(Start::OfModulus(0.02)),
        ParameterSpec::new("hardening_MPa", "linear isotropic hardening modulus", "MPa", (0.0, false), 1e4, Some(0.0))
            .fit(1e-6, 1e2, true)
            .start(Start::OfModulus(0.1)),
        ParameterSpec::new(
            "kinematic_MPa",
            "linear kinematic (Prager) hardening modulus",
            "MPa",
            (0.0, false),
            1e4,
            Some(0.0),
        )
        .fit(1e-6, 1e2, true)
        .start(Start::OfModulus(0.1)),
    ],
    build: |v| Arc::new(PlasticNetwork { e_mpa: v[0], yield_mpa: v[1], hardening_mpa: v[2], kinematic_mpa: v[3] }),
};

impl Part for PlasticNetwork {
    fn kind(&self) -> &'static PartKind {
        &KIND
    }

    fn values(&self) -> Vec<f64> {
        vec![self.e_mpa, self.yield_mpa, self.hardening_mpa, self.kinematic_mpa]
    }

    fn history_len(&self) -> usize {
        HISTORY
    }

    fn small_strain_modulus(&self) -> f64 {
        self.e_mpa
    }

    fn respond(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let (p, tangent) = self.step(k, old, new, true);
        Ok((p, tangent.expect("asked for")))
    }

    fn stress(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<Matrix3<f64>, LawFailure> {
        Ok(self.step(k, old, new, false).0)
    }
}

impl PlasticNetwork {
    /// The step's stress, its tangent when `with_tangent`, and the new history
    /// ([`Part::respond`]).
    fn step(
        &self,
        k: &Kinematics,
        old: &[f64],
        new: &mut [f64],
        with_tangent: bool,
    ) -> (Matrix3<f64>, Option<Tangent>) {
        if self.kinematic_mpa == 0.0 {
            return respond(self, k.h, &k.f_inv, k.poisson, old, new, with_tangent);
        }
        let (sublayer, spring_e_mpa) = self.sublayer(k.poisson);
        let (p, tangent) = respond(&sublayer, k.h, &k.f_inv, k.poisson, old, new, with_tangent);
        let (zero, lame) = (Matrix3::zeros(), hencky::unit_lame(k.poisson));
        let spring = hencky::spring_stress(k.h, &k.f_inv_t, &zero, spring_e_mpa, lame);
        let tangent = tangent.map(|t| t + hencky::spring_tangent(k.h, &k.f_inv_t, &zero, spring_e_mpa, lame, &spring));
        (p + spring.p, tangent)
    }

    /// The sublayer form of the kinematic hardening at Poisson ratio `poisson`
    /// (module docs): the isotropic network `(s E, s sigma_y, s^2 H)` and the
    /// Young's modulus `(1 - s) E` of the spring beside it [MPa].
    pub fn sublayer(&self, poisson: f64) -> (PlasticNetwork, f64) {
        let three_mu = 3.0 * self.e_mpa * hencky::unit_lame(poisson).1;
        let s = three_mu / (three_mu + self.kinematic_mpa);
        let sublayer = PlasticNetwork {
            e_mpa: s * self.e_mpa,
            yield_mpa: s * self.yield_mpa,
            hardening_mpa: s * s * self.hardening_mpa,
            kinematic_mpa: 0.0,
        };
        (sublayer, self.e_mpa * self.kinematic_mpa / (three_mu + self.kinematic_mpa))
    }
}

/// The plastic network's response at `F = I + h`: the first Piola-Kirchhoff
/// stress and, when `with_tangent`, its tangent; writes the new history into `new`.
pub(crate) fn respond(
    net: &PlasticNetwork,
    h: &Matrix3<f64>,
    f_inv: &Matrix3<f64>,
    poisson: f64,
    old: &[f64],
    new: &mut [f64],
    with_tangent: bool,
) -> (Matrix3<f64>, Option<Tangent>) {
    let alpha_n = old[6];
    let (p, tangent, dgamma) = radial_return(net.e_mpa, h, f_inv, poisson, old, new, with_tangent, |s_norm, mu| {
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
/// into `new[0..6]`; returns `P`, its exact tangent (when `with_tangent`) and
/// `dgamma`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn radial_return(
    e_mpa: f64,
    h: &Matrix3<f64>,
    f_inv: &Matrix3<f64>,
    poisson: f64,
    old: &[f64],
    new: &mut [f64],
    with_tangent: bool,
    rule: impl Fn(f64, f64) -> Option<(f64, f64)>,
) -> (Matrix3<f64>, Option<Tangent>, f64) {
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
    let tangent = with_tangent.then(|| {
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
        hencky::log_strain_tangent(&f, &cp_inv_dev, &q, x, &tau, &f_inv_t, |d_eps| modulus(&symmetrize(d_eps)))
    });

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

    const NET: PlasticNetwork =
        PlasticNetwork { e_mpa: 0.05, yield_mpa: 2e-3, hardening_mpa: 0.01, kinematic_mpa: 0.0 };

    fn step(f: &Matrix3<f64>, old: &[f64]) -> (Matrix3<f64>, Tangent, Vec<f64>) {
        let mut new = old.to_vec();
        let (p, t) = respond(&NET, &(f - Matrix3::identity()), &f.try_inverse().unwrap(), 0.35, old, &mut new, true);
        (p, t.expect("asked for"), new)
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

    /// One step of a (possibly kinematic) plastic network through the part's
    /// own entry point.
    fn part_step(net: &PlasticNetwork, f: &Matrix3<f64>, old: &[f64]) -> (Matrix3<f64>, Tangent, Vec<f64>) {
        let h = f - Matrix3::identity();
        let f_inv = f.try_inverse().unwrap();
        let k = Kinematics {
            h: &h,
            f: *f,
            f_inv,
            f_inv_t: f_inv.transpose(),
            c_n_inv_dev: Matrix3::zeros(),
            poisson: 0.35,
            dt_s: 1.0,
        };
        let mut new = old.to_vec();
        let (p, t) = net.respond(&k, old, &mut new).unwrap();
        (p, t, new)
    }

    /// With kinematic hardening: the tangent against central differences on the
    /// plastic and the elastic branch from a yielded state; and a kinematic
    /// modulus tending to 0 tends to the isotropic network.
    #[test]
    fn the_kinematic_tangent_matches_central_differences_and_vanishes_continuously() {
        let kin = PlasticNetwork { kinematic_mpa: 0.02, ..NET };
        let f1 = Matrix3::new(1.05, 0.1, 0.0, 0.02, 0.8, 0.03, 0.0, 0.01, 1.1);
        let (_, _, yielded) = part_step(&kin, &f1, &[0.0; HISTORY]);
        assert!(yielded[6] > 0.0, "the first step yields");
        let further = f1 * Matrix3::new(1.02, 0.01, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 1.03);
        let back = f1 * Matrix3::new(0.995, 0.0, 0.0, 0.0, 1.01, 0.0, 0.0, 0.0, 0.995);
        for (f, plastic) in [(further, true), (back, false)] {
            let (_, t, new) = part_step(&kin, &f, &yielded);
            assert_eq!(new[6] > yielded[6], plastic);
            let fd = tangent_by_differences(&f, 1e-7, &|f: &Matrix3<f64>| part_step(&kin, f, &yielded).0);
            let err = (t - fd).amax() / t.amax();
            assert!(err < 1e-6, "plastic {plastic}: tangent error {err:.3e}");
            assert!((t - t.transpose()).amax() < 1e-10 * t.amax(), "major symmetry");
        }
        let tiny = PlasticNetwork { kinematic_mpa: 1e-12, ..NET };
        let (p0, _, h0) = part_step(&NET, &f1, &[0.0; HISTORY]);
        let (p1, _, h1) = part_step(&tiny, &f1, &[0.0; HISTORY]);
        assert!((p1 - p0).amax() < 1e-9 * p0.amax(), "{:.3e}", (p1 - p0).amax());
        assert!(h0.iter().zip(&h1).all(|(a, b)| (a - b).abs() < 1e-9 * (1.0 + a.abs())));
    }

    /// At small strain, on a path whose principal axes turn (shear, then
    /// tension, then back), the network is the small-strain J2 return with
    /// linear isotropic and kinematic (Prager) hardening written here, the back
    /// stress a tensor `beta = 2/3 H_k eps_p`: they differ by the order of the
    /// strain, measured at strains of 2e-5 and 2e-7 (the yield stress scaled
    /// with them, so that every step yields): at most 10 strains, and falling
    /// by the strain's factor (100) within 10 %.
    #[test]
    fn at_small_strain_the_kinematic_network_is_pragers_tensorial_law() {
        let (e, nu, h_iso, h_kin) = (0.05, 0.35, 0.01, 0.03);
        let mu = e / (2.0 * (1.0 + nu));
        let bulk = e / (3.0 * (1.0 - 2.0 * nu));
        let dev = |m: Matrix3<f64>| m - Matrix3::identity() * (m.trace() / 3.0);
        let path = [
            Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            Matrix3::new(1.0, 1.0, 0.0, 1.0, -0.4, 0.3, 0.0, 0.3, -0.4),
            Matrix3::new(-0.5, 0.2, 0.0, 0.2, 0.3, -0.6, 0.0, -0.6, 0.1),
        ];
        let mut gaps = Vec::new();
        for a in [2e-5, 2e-7] {
            let sigma_y = 5e-3 * e * a;
            let net = PlasticNetwork { e_mpa: e, yield_mpa: sigma_y, hardening_mpa: h_iso, kinematic_mpa: h_kin };
            let (mut eps_p, mut alpha) = (Matrix3::<f64>::zeros(), 0.0f64);
            let mut history = vec![0.0; HISTORY];
            let (mut yielded, mut worst) = (0, 0.0f64);
            for g in path {
                let f = Matrix3::identity() + g * a;
                let (p, _, new) = part_step(&net, &f, &history);
                history = new;
                // Prager's return on the small strain.
                let eps = g * a;
                let xi = dev(eps) * (2.0 * mu) - eps_p * (2.0 * mu) - eps_p * (2.0 / 3.0 * h_kin);
                let excess = xi.norm() - (2.0f64 / 3.0).sqrt() * (sigma_y + h_iso * alpha);
                if excess > 0.0 {
                    let dgamma = excess / (2.0 * mu + 2.0 / 3.0 * (h_iso + h_kin));
                    eps_p += xi * (dgamma / xi.norm());
                    alpha += (2.0f64 / 3.0).sqrt() * dgamma;
                    yielded += 1;
                }
                let sigma = Matrix3::identity() * (bulk * eps.trace()) + (dev(eps) - eps_p) * (2.0 * mu);
                worst = worst.max((p - sigma).amax() / sigma.amax());
            }
            eprintln!("kinematic network against Prager's law at {a:.0e} strain: {worst:.3e} of the stress");
            assert_eq!(yielded, 3, "every step yields");
            assert!(worst < 10.0 * a, "{worst:.3e}");
            gaps.push(worst);
        }
        let ratio = gaps[0] / gaps[1];
        assert!((ratio / 100.0 - 1.0).abs() < 0.1, "ratio {ratio}");
    }
}
