//! A power-law flow network: a Hencky spring on `F = Fe Fv` whose deviatoric
//! stress flows by Norton's law, the equivalent flow rate
//!
//! ```text
//! d(eps_bar)/dt = (q / sigma_0)^n   [1/s],   q = sqrt(3/2) |dev tau|,
//! ```
//!
//! with `sigma_0` the equivalent stress at which it flows at a strain rate of
//! 1/s and `n >= 1` the exponent: 1 is Newtonian (a Maxwell network relaxing
//! only its shear, of time `sigma_0 / (3 mu)`), larger exponents thin (the flow
//! speeds up with the stress), as doughs and pastes do. There is no threshold:
//! the network flows at any stress, and holds no permanent set.
//!
//! The step is integrated by backward Euler in the logarithmic strains with the
//! exponential map, the plastic network's radial return
//! ([`super::plastic::radial_return`]) with a rate-dependent radius: the
//! multiplier `dgamma` (`eps_e = eps_tr - dgamma n`, the equivalent strain
//! increment `sqrt(2/3) dgamma`) solves
//!
//! ```text
//! |s_tr| - 2 mu dgamma = R(dgamma) = sqrt(2/3) sigma_0 (sqrt(2/3) dgamma / dt)^(1/n),
//! ```
//!
//! one increasing convex equation in `y = dgamma^(1/n)`: Newton's iteration
//! from above converges monotonically. The exact tangent takes
//! `R'(dgamma) = R / (n dgamma)`. At small strain and `n = 1`, a hold relaxes
//! the deviatoric stress by `1 / (1 + 3 mu dt / sigma_0)` per step, backward
//! Euler of `exp(-3 mu t / sigma_0)`: first order in the step.
//!
//! History (6 values): `Cv^-1 - I` as `[xx, yy, zz, xy, xz, yz]`.

use std::sync::Arc;

use nalgebra::Matrix3;

use super::part::{Kinematics, Part, PartKind};
use super::plastic::radial_return;
use crate::material::law::{LawFailure, ParameterSpec, Start, Tangent};

/// A power-law (Norton) flow network (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowNetwork {
    /// The spring's Young's modulus [MPa].
    pub e_mpa: f64,
    /// `sigma_0`: the equivalent stress at which it flows at 1/s [MPa].
    pub stress_mpa: f64,
    /// `n >= 1`: the exponent of the flow rate in the stress.
    pub exponent: f64,
}

/// `[[flow]]`: at most two power-law flow networks.
pub static KIND: PartKind = PartKind {
    table: "flow",
    meaning: "a Maxwell network with power-law (Norton) flow of its shear",
    max_count: 2,
    parameters: &[
        super::part::SPRING_MODULUS,
        ParameterSpec::new(
            "stress_MPa",
            "equivalent stress flowing at a strain rate of 1/s",
            "MPa",
            (0.0, true),
            1e4,
            None,
        )
        .fit(1e-6, 1e2, true)
        .start(Start::OfModulus(0.1)),
        ParameterSpec::new(
            "exponent",
            "exponent n of the flow rate (1: Newtonian)",
            "1",
            (1.0, false),
            20.0,
            Some(1.0),
        )
        .fit(1.0, 10.0, false)
        .start(Start::Value(2.0)),
    ],
    build: |v| Arc::new(FlowNetwork { e_mpa: v[0], stress_mpa: v[1], exponent: v[2] }),
};

/// The most Newton iterations of the return.
const MAX_ITERATIONS: usize = 100;

impl FlowNetwork {
    /// `dgamma` and the flow's stiffness share for a trial `|s_tr|` (module
    /// docs); `None` when the return does not converge.
    fn multiplier(&self, s_norm: f64, mu: f64, dt_s: f64) -> Option<(f64, f64)> {
        let n = self.exponent;
        let two_mu = 2.0 * mu;
        let k = (2.0f64 / 3.0).sqrt();
        // R(dgamma) = c dgamma^(1/n); in y = dgamma^(1/n): 2 mu y^n + c y = |s_tr|.
        let c = k * self.stress_mpa * (k / dt_s).powf(1.0 / n);
        let psi = |y: f64| two_mu * y.powf(n) + c * y - s_norm;
        let mut y = (s_norm / two_mu).powf(1.0 / n).min(s_norm / c);
        let mut converged = false;
        for _ in 0..MAX_ITERATIONS {
            let step = psi(y) / (n * two_mu * y.powf(n - 1.0) + c);
            let next = y - step;
            // From above on a convex increasing function the iterates fall
            // monotonically; rounding ends it.
            if !(next < y) || step <= 4.0 * f64::EPSILON * y {
                y = next.min(y);
                converged = true;
                break;
            }
            y = next;
        }
        if !(converged && y > 0.0 && y.is_finite()) {
            return None;
        }
        let dgamma = y.powf(n);
        let radius = c * y;
        let slope = radius / (n * dgamma);
        Some((dgamma, 1.0 / (1.0 + slope / two_mu)))
    }
}

impl Part for FlowNetwork {
    fn kind(&self) -> &'static PartKind {
        &KIND
    }

    fn values(&self) -> Vec<f64> {
        vec![self.e_mpa, self.stress_mpa, self.exponent]
    }

    fn history_len(&self) -> usize {
        6
    }

    fn small_strain_modulus(&self) -> f64 {
        self.e_mpa
    }

    fn respond(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let failed = std::cell::Cell::new(false);
        let (p, tangent, _) = radial_return(self.e_mpa, k.h, &k.f_inv, k.poisson, old, new, true, |s_norm, mu| {
            let m = self.multiplier(s_norm, mu, k.dt_s);
            failed.set(m.is_none());
            m
        });
        if failed.get() {
            return Err(LawFailure::ReturnMapping { law: "flow" });
        }
        Ok((p, tangent.expect("asked for")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::law::tangent_by_differences;
    use crate::material::network::{sym_from, Network};

    fn step(net: &FlowNetwork, f: &Matrix3<f64>, dt: f64, old: &[f64]) -> (Matrix3<f64>, Tangent, Vec<f64>) {
        super::super::part::step_at(net, f, 0.35, dt, old)
    }

    /// The tangent against central differences, Newtonian and thinning, from a
    /// state that has flowed (so that `Cv` is away from the identity).
    #[test]
    fn the_tangent_matches_central_differences() {
        for exponent in [1.0, 3.0, 7.5] {
            let net = FlowNetwork { e_mpa: 0.05, stress_mpa: 4e-3, exponent };
            let f1 = Matrix3::new(1.05, 0.1, 0.0, 0.02, 0.8, 0.03, 0.0, 0.01, 1.1);
            let (_, _, flowed) = step(&net, &f1, 0.5, &[0.0; 6]);
            assert!(sym_from(&flowed).amax() > 1e-3, "the first step flows");
            let f = f1 * Matrix3::new(1.02, 0.01, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 1.03);
            let (_, t, _) = step(&net, &f, 0.3, &flowed);
            let fd = tangent_by_differences(&f, 1e-7, &|f: &Matrix3<f64>| step(&net, f, 0.3, &flowed).0);
            let err = (t - fd).amax() / t.amax();
            assert!(err < 1e-6, "n = {exponent}: tangent error {err:.3e}");
            assert!((t - t.transpose()).amax() < 1e-10 * t.amax(), "major symmetry");
        }
    }

    /// The return solves its equation: the returned deviatoric stress flows at
    /// Norton's rate, `sqrt(2/3) dgamma / dt = (q / sigma_0)^n`, and the flow
    /// keeps the volume.
    #[test]
    fn the_return_flows_at_nortons_rate() {
        for exponent in [1.0, 2.0, 12.0] {
            let net = FlowNetwork { e_mpa: 0.05, stress_mpa: 2e-3, exponent };
            let f = Matrix3::new(1.2, 0.05, 0.0, 0.0, 0.7, 0.0, 0.0, 0.0, 1.15);
            let dt = 0.2;
            let (p, _, new) = step(&net, &f, dt, &[0.0; 6]);
            let tau = p * f.transpose();
            let dev = tau - Matrix3::identity() * (tau.trace() / 3.0);
            let q = (1.5f64).sqrt() * dev.norm();
            // The elastic log strain's deviator is dev(tau) / (2 mu); the flow
            // took the rest of the trial strain.
            let mu = net.e_mpa / (2.0 * 1.35);
            let eps_tr = {
                let (qq, x) = super::super::hencky::eigen(&(f * f.transpose() - Matrix3::identity()));
                super::super::hencky::spectral(&qq, x, |v| 0.5 * v.ln_1p())
            };
            let dev_tr = eps_tr - Matrix3::identity() * (eps_tr.trace() / 3.0);
            let dgamma = (dev_tr - dev / (2.0 * mu)).norm();
            let rate = (2.0f64 / 3.0).sqrt() * dgamma / dt;
            let want = (q / net.stress_mpa).powf(exponent);
            assert!((rate - want).abs() < 1e-10 * want, "n = {exponent}: {rate} against {want}");
            let cv_inv = Matrix3::identity() + sym_from(&new);
            assert!((cv_inv.determinant() - 1.0).abs() < 1e-12, "isochoric flow");
        }
    }

    /// A Newtonian hold relaxes the deviatoric stress by `1 / (1 + 3 mu dt / sigma_0)`
    /// per step, and the relaxation converges to `exp(-3 mu t / sigma_0)` at
    /// first order in the step (measured).
    #[test]
    fn a_newtonian_hold_relaxes_at_first_order() {
        let net = FlowNetwork { e_mpa: 0.03, stress_mpa: 0.01, exponent: 1.0 };
        let mu = net.e_mpa / (2.0 * 1.35);
        let time = 3.0 * 0.01 / (3.0 * mu); // three relaxation times
        let f = Matrix3::new(1.0 + 1e-7, 0.0, 0.0, 0.0, 1.0 - 1e-7, 0.0, 0.0, 0.0, 1.0);
        let relaxed = |steps: usize| {
            let dt = time / steps as f64;
            // Load in a step too short to flow, then hold.
            let (p0, _, mut h) = step(&net, &f, 1e-12, &[0.0; 6]);
            let mut p = p0;
            for _ in 0..steps {
                let (pn, _, hn) = step(&net, &f, dt, &h);
                p = pn;
                h = hn;
            }
            // The difference of the normal stresses is deviatoric: the volume does not relax.
            let ratio = (p[(0, 0)] - p[(1, 1)]) / (p0[(0, 0)] - p0[(1, 1)]);
            let per_step = 1.0 / (1.0 + 3.0 * mu * dt / net.stress_mpa);
            assert!(
                (ratio - per_step.powi(steps as i32)).abs() < 1e-6 * ratio,
                "{ratio} against {}",
                per_step.powi(steps as i32)
            );
            (ratio - (-3.0f64).exp()).abs()
        };
        let (e1, e2) = (relaxed(40), relaxed(80));
        let order = (e1 / e2).log2();
        assert!((order - 1.0).abs() < 0.05, "order {order:.3}");
    }

    /// Registered: a network with a `[[flow]]` part names its keys through the
    /// registry.
    #[test]
    fn the_part_is_registered() {
        assert!(std::ptr::eq(super::super::part::kind("flow").unwrap(), &KIND));
        let net = Network::new(0.3).with(FlowNetwork { e_mpa: 0.02, stress_mpa: 1e-3, exponent: 2.0 });
        net.validate().unwrap();
        let keys = super::super::parameters::flat_keys();
        assert!(keys.contains(&"flow[1].stress_MPa"));
    }
}
