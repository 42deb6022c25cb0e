//! A Bingham network: a Hencky spring on `F = Fe Fv` whose deviatoric stress
//! flows only above a yield stress, at a rate proportional to the excess (a
//! Bingham plastic, Perzyna's overstress with exponent 1):
//!
//! ```text
//! d(eps_bar)/dt = <q - sigma_y> / eta   [1/s],   q = sqrt(3/2) |dev tau|,
//! ```
//!
//! with `sigma_y` the yield stress and `eta` the plastic viscosity [MPa s]: in
//! uniaxial flow `sigma = sigma_y + eta d(eps_v)/dt`. Below the yield stress the
//! network is a spring; it holds a set (the stress it keeps at the yield
//! stress cannot relax), and it flows faster the harder it is pushed: creams,
//! pastes, fillings and set gels that have a yield point.
//!
//! The step is integrated by backward Euler in the logarithmic strains with the
//! exponential map, the plastic network's radial return
//! ([`super::plastic::radial_return`]) with the rate-dependent radius
//! `R(dgamma) = sqrt(2/3) (sigma_y + eta sqrt(2/3) dgamma / dt)`: the multiplier
//! solves `|s_tr| - 2 mu dgamma = R(dgamma)`, linear in `dgamma`, so
//!
//! ```text
//! dgamma = (|s_tr| - sqrt(2/3) sigma_y) / (2 mu + 2 eta / (3 dt))
//! ```
//!
//! in closed form (no local iteration), and the exact tangent takes
//! `R' = 2 eta / (3 dt)`. As `eta / dt` falls to 0 the return is the perfectly
//! plastic network's; as it grows the network is a spring.
//!
//! History (7 values): `Cv^-1 - I` as `[xx, yy, zz, xy, xz, yz]`, then one
//! unused value (the plastic network's layout).

use std::sync::Arc;

use nalgebra::Matrix3;

use super::part::{Kinematics, Part, PartKind};
use super::plastic::radial_return;
use crate::material::law::{LawFailure, ParameterSpec, Start, Tangent};

/// A Bingham (yield stress and plastic viscosity) network (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinghamNetwork {
    /// The spring's Young's modulus [MPa].
    pub e_mpa: f64,
    /// `sigma_y`: the equivalent stress below which it does not flow [MPa].
    pub yield_mpa: f64,
    /// `eta`: the plastic viscosity of the flow above it [MPa s].
    pub viscosity_mpa_s: f64,
}

/// `[bingham]`: one Bingham network.
pub static KIND: PartKind = PartKind {
    table: "bingham",
    meaning: "a Maxwell network that flows only above a yield stress (Bingham)",
    max_count: 1,
    parameters: &[
        super::part::SPRING_MODULUS,
        ParameterSpec::new("yield_MPa", "equivalent yield stress of the flow", "MPa", (0.0, true), 1e4, None)
            .fit(1e-6, 1e2, true)
            .start(Start::OfModulus(0.02)),
        ParameterSpec::new(
            "viscosity_MPa_s",
            "plastic viscosity above the yield stress",
            "MPa s",
            (0.0, true),
            1e6,
            None,
        )
        .fit(1e-6, 1e4, true)
        .start(Start::OfModulus(0.1)),
    ],
    build: |v| Arc::new(BinghamNetwork { e_mpa: v[0], yield_mpa: v[1], viscosity_mpa_s: v[2] }),
};

impl BinghamNetwork {
    /// `dgamma` and the flow's stiffness share for a trial `|s_tr|` (module
    /// docs); `None` below the yield stress.
    fn multiplier(&self, s_norm: f64, mu: f64, dt_s: f64) -> Option<(f64, f64)> {
        let k = (2.0f64 / 3.0).sqrt();
        let excess = s_norm - k * self.yield_mpa;
        let slope = 2.0 * self.viscosity_mpa_s / (3.0 * dt_s);
        (excess > 0.0).then(|| (excess / (2.0 * mu + slope), 1.0 / (1.0 + slope / (2.0 * mu))))
    }
}

impl Part for BinghamNetwork {
    fn kind(&self) -> &'static PartKind {
        &KIND
    }

    fn values(&self) -> Vec<f64> {
        vec![self.e_mpa, self.yield_mpa, self.viscosity_mpa_s]
    }

    fn history_len(&self) -> usize {
        super::plastic::HISTORY
    }

    fn small_strain_modulus(&self) -> f64 {
        self.e_mpa
    }

    fn respond(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let (p, tangent, _) = radial_return(self.e_mpa, k.h, &k.f_inv, k.poisson, old, new, true, |s_norm, mu| {
            self.multiplier(s_norm, mu, k.dt_s)
        });
        Ok((p, tangent.expect("asked for")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::law::tangent_by_differences;
    use crate::material::network::{sym_from, Network};

    const NET: BinghamNetwork = BinghamNetwork { e_mpa: 0.05, yield_mpa: 2e-3, viscosity_mpa_s: 4e-3 };

    fn step(net: &BinghamNetwork, f: &Matrix3<f64>, dt: f64, old: &[f64]) -> (Matrix3<f64>, Tangent, Vec<f64>) {
        super::super::part::step_at(net, f, 0.35, dt, old)
    }

    fn equivalent_stress(p: &Matrix3<f64>, f: &Matrix3<f64>) -> f64 {
        let tau = p * f.transpose();
        (1.5f64).sqrt() * (tau - Matrix3::identity() * (tau.trace() / 3.0)).norm()
    }

    /// The tangent against central differences on the flowing branch and on the
    /// elastic one, from a state that has flowed.
    #[test]
    fn the_tangent_matches_central_differences() {
        let f1 = Matrix3::new(1.05, 0.1, 0.0, 0.02, 0.8, 0.03, 0.0, 0.01, 1.1);
        let (_, _, flowed) = step(&NET, &f1, 0.5, &[0.0; 7]);
        assert!(sym_from(&flowed).amax() > 1e-3, "the first step flows");
        for (g, what) in [
            (Matrix3::new(1.02, 0.01, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 1.03), "flowing"),
            (Matrix3::new(0.98, 0.0, 0.0, 0.0, 1.06, 0.0, 0.0, 0.0, 0.98), "elastic"),
        ] {
            let f = f1 * g;
            let (p, t, _) = step(&NET, &f, 0.3, &flowed);
            let q = equivalent_stress(&p, &f);
            assert_eq!(q > NET.yield_mpa * (1.0 + 1e-9), what == "flowing", "{what}: q = {q:.4e}");
            let fd = tangent_by_differences(&f, 1e-7, &|f: &Matrix3<f64>| step(&NET, f, 0.3, &flowed).0);
            let err = (t - fd).amax() / t.amax();
            assert!(err < 1e-6, "{what}: tangent error {err:.3e}");
            assert!((t - t.transpose()).amax() < 1e-10 * t.amax(), "major symmetry");
        }
    }

    /// The return solves Bingham's law: above the yield stress the flow rate is
    /// `(q - sigma_y) / eta` exactly, the flow keeps the volume, and below it
    /// nothing flows.
    #[test]
    fn the_return_flows_at_binghams_rate() {
        let f = Matrix3::new(1.2, 0.05, 0.0, 0.0, 0.7, 0.0, 0.0, 0.0, 1.15);
        let dt = 0.2;
        let (p, _, new) = step(&NET, &f, dt, &[0.0; 7]);
        let q = equivalent_stress(&p, &f);
        let mu = NET.e_mpa / (2.0 * 1.35);
        let eps_tr = {
            let (qq, x) = super::super::hencky::eigen(&(f * f.transpose() - Matrix3::identity()));
            super::super::hencky::spectral(&qq, x, |v| 0.5 * v.ln_1p())
        };
        let tau = p * f.transpose();
        let dev = tau - Matrix3::identity() * (tau.trace() / 3.0);
        let dev_tr = eps_tr - Matrix3::identity() * (eps_tr.trace() / 3.0);
        let dgamma = (dev_tr - dev / (2.0 * mu)).norm();
        let rate = (2.0f64 / 3.0).sqrt() * dgamma / dt;
        let want = (q - NET.yield_mpa) / NET.viscosity_mpa_s;
        assert!(want > 0.0 && (rate - want).abs() < 1e-10 * want, "{rate} against {want}");
        let cv_inv = Matrix3::identity() + sym_from(&new);
        assert!((cv_inv.determinant() - 1.0).abs() < 1e-12, "isochoric flow");
        // Below the yield stress: a spring.
        let small = Matrix3::new(1.0 + 1e-3, 0.0, 0.0, 0.0, 1.0 - 1e-3, 0.0, 0.0, 0.0, 1.0);
        let (_, _, kept) = step(&NET, &small, dt, &[0.0; 7]);
        assert!(sym_from(&kept).amax() < 1e-15, "{:.3e}", sym_from(&kept).amax());
    }

    /// A hold above the yield stress relaxes the equivalent stress to
    /// `sigma_y`, not to zero: the stress a Bingham material keeps.
    #[test]
    fn a_hold_relaxes_to_the_yield_stress() {
        let dt = 0.01;
        let f = Matrix3::new(1.0 + 0.1, 0.0, 0.0, 0.0, 1.0 - 0.1, 0.0, 0.0, 0.0, 1.0);
        // Load in a step too short to flow, then hold.
        let (p0, _, mut h) = step(&NET, &f, 1e-12, &[0.0; 7]);
        let q0 = equivalent_stress(&p0, &f);
        assert!(q0 > 2.0 * NET.yield_mpa);
        let mut q = q0;
        for _ in 0..400 {
            let (p, _, hn) = step(&NET, &f, dt, &h);
            q = equivalent_stress(&p, &f);
            h = hn;
        }
        assert!((q - NET.yield_mpa).abs() < 1e-6 * NET.yield_mpa, "held at {q:.6e}, yield {:.6e}", NET.yield_mpa);
    }

    /// Registered: a network with a `[bingham]` part names its keys through the
    /// registry.
    #[test]
    fn the_part_is_registered() {
        assert!(std::ptr::eq(super::super::part::kind("bingham").unwrap(), &KIND));
        Network::new(0.3).with(NET).validate().unwrap();
        assert!(super::super::parameters::flat_keys().contains(&"bingham.viscosity_MPa_s"));
    }
}
