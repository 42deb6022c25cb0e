//! A dual-viscosity network: a viscous (Maxwell) network whose relaxation time
//! is `tau_load` while its spring loads and `tau_unload` while it unloads, the
//! finite-strain form of the chain's dual viscosity (Wang & Hirai 2012: foods
//! recover at another rate than they relax).
//!
//! The step is the viscous network's ([`super::viscous`], the exponential
//! integrator exact for the chain at small strain) with the time of the step's
//! direction. The step loads when the trial state, the step's end deformation
//! with no flow, would not lower the spring's energy:
//!
//! ```text
//! psi(eps_tr) >= psi(eps_n),   psi(eps) = E (lambda1 tr(eps)^2 / 2 + mu1 eps : eps),
//! ```
//!
//! `eps_tr = log(F A_n F^T) / 2` the trial elastic log strain and `eps_n` the
//! one at the step's start (its energy from the stored stress, whose
//! invariants are those of `S_n C_n`). Otherwise it unloads. The continuous law
//! is the chain's criterion: the spring loads while `s : de/dt >= 0` (its
//! elastic strain grows in its own energy norm) and unloads while its energy
//! falls. A hold loads: a step whose `C^-1` equals the start's to the last bit
//! is taken as loading without comparing rounded energies, and the first step
//! from rest loads (its start energy is 0). At small strain the energy change
//! is `s_n : de + de : E C1 : de / 2`. Under a hold the solver's iterates move
//! about `F_n` by its corrections, where the change is the product of residual
//! stresses and those corrections, of either sign: a fall of less than 1e-10 of
//! the start energy counts as a hold (loading), so that the choice cannot
//! flip between Newton's iterations there.
//!
//! Both energies are invariants, so the choice is objective. Being decided by
//! the step's end deformation, the switch lands on the protocol's kinks (no
//! step of delay); the price is a stress that jumps across the switch (by the
//! difference of the two relaxations over the step). The tangent is the
//! viscous network's of the chosen time: exact on either side. With
//! `tau_unload = tau_load` the part is the viscous network bit for bit.
//!
//! History (12 values): the viscous network's, `A - I` and `S_n`.

use std::sync::Arc;

use nalgebra::Matrix3;

use super::hencky;
use super::part::{Kinematics, Part, PartKind};
use super::sym_from;
use super::viscous::ViscousNetwork;
use crate::material::law::{LawFailure, ParameterSpec, Start, Tangent};

/// A Maxwell network with a relaxation time for loading and one for unloading
/// (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualNetwork {
    /// The spring's Young's modulus [MPa].
    pub e_mpa: f64,
    /// The relaxation time while the spring loads or holds [s].
    pub tau_load_s: f64,
    /// The relaxation time while the spring unloads [s].
    pub tau_unload_s: f64,
}

/// `[[dual]]`: at most two dual-viscosity networks.
pub static KIND: PartKind = PartKind {
    table: "dual",
    meaning: "a Maxwell network relaxing at one time while its spring loads and another while it unloads",
    max_count: 2,
    parameters: &[
        ParameterSpec::new("E_MPa", "the spring's Young's modulus", "MPa", (0.0, true), 1e4, None)
            .fit(1e-5, 1e2, true)
            .start(Start::OfModulus(0.25)),
        ParameterSpec::new(
            "tau_load_s",
            "relaxation time while the spring loads or holds",
            "s",
            (0.0, true),
            1e9,
            None,
        )
        .fit(1e-3, 1e5, true)
        .start(Start::Decades(1.0)),
        // Starting at the loading time: the viscous network, the null of the
        // dual viscosity.
        ParameterSpec::new("tau_unload_s", "relaxation time while the spring unloads", "s", (0.0, true), 1e9, None)
            .fit(1e-3, 1e5, true)
            .start(Start::Decades(1.0)),
    ],
    build: |v| Arc::new(DualNetwork { e_mpa: v[0], tau_load_s: v[1], tau_unload_s: v[2] }),
};

/// The relative fall of the spring's trial energy that still counts as a hold
/// (module docs): above the rounding of the two energies and the solver's
/// residual stresses times its last corrections (1e-13 of the energy and
/// below), far below a step that unloads (a strain step of `x` of the elastic
/// strain lowers the energy by about `2 x`).
const HOLD_BAND: f64 = 1e-10;

impl DualNetwork {
    /// Whether the step to the deformation of `k` loads the spring, from the
    /// part's history at the step's start `old` (module docs).
    pub fn loads(&self, k: &Kinematics, old: &[f64]) -> Result<bool, LawFailure> {
        // A hold: the same `C^-1 - I` as at the step's start, to the last bit.
        if hencky::inverse_right_deviation(k.h, &k.f_inv) == k.c_n_inv_dev {
            return Ok(true);
        }
        let (lambda1, mu1) = hencky::unit_lame(k.poisson);
        // The trial energy: the principal elastic log strains of F A_n F^T.
        let (_, x) = hencky::eigen(&hencky::push_deviation(k.h, &sym_from(&old[0..6])));
        let eps = x.map(|v| 0.5 * v.ln_1p());
        let tr = eps[0] + eps[1] + eps[2];
        let trial =
            self.e_mpa * (0.5 * lambda1 * tr * tr + mu1 * (eps[0] * eps[0] + eps[1] * eps[1] + eps[2] * eps[2]));
        // The start's energy from its stress: tau_n = F_n S_n F_n^T has the
        // invariants of S_n C_n.
        let c_n = (Matrix3::identity() + k.c_n_inv_dev).try_inverse().ok_or(LawFailure::NonFinite)?;
        let sc = sym_from(&old[6..12]) * c_n;
        let tr_tau = sc.trace();
        let start =
            ((sc * sc).trace() - lambda1 * tr_tau * tr_tau / (3.0 * lambda1 + 2.0 * mu1)) / (4.0 * mu1 * self.e_mpa);
        Ok(trial >= start * (1.0 - HOLD_BAND))
    }
}

impl Part for DualNetwork {
    fn kind(&self) -> &'static PartKind {
        &KIND
    }

    fn values(&self) -> Vec<f64> {
        vec![self.e_mpa, self.tau_load_s, self.tau_unload_s]
    }

    fn history_len(&self) -> usize {
        12
    }

    fn small_strain_modulus(&self) -> f64 {
        self.e_mpa
    }

    fn respond(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let tau_s = if self.loads(k, old)? { self.tau_load_s } else { self.tau_unload_s };
        ViscousNetwork { e_mpa: self.e_mpa, tau_s }.respond(k, old, new)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::law::{tangent_by_differences, PointLaw};
    use crate::material::network::Network;

    const NET: DualNetwork = DualNetwork { e_mpa: 0.03, tau_load_s: 4.0, tau_unload_s: 0.5 };

    /// One step of a network holding only `part`, from `old` to `f`.
    fn step(net: &Network, f: &Matrix3<f64>, dt: f64, old: &[f64]) -> (Matrix3<f64>, Tangent, Vec<f64>) {
        let mut new = old.to_vec();
        let r = net.update(&(f - Matrix3::identity()), dt, old, &mut new).unwrap();
        (r.stress, r.tangent, new)
    }

    /// The tangent against central differences on both sides of the switch: a
    /// step further along a loading path and one back from it, from a loaded
    /// state away from the identity.
    #[test]
    fn the_tangent_matches_central_differences_loading_and_unloading() {
        let net = Network::new(0.35).with(NET);
        let f1 = Matrix3::new(1.05, 0.1, 0.0, 0.02, 0.8, 0.03, 0.0, 0.01, 1.1);
        let (_, _, loaded) = step(&net, &f1, 0.5, &vec![0.0; net.history_len()]);
        let further = f1 * Matrix3::new(1.02, 0.01, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 1.03);
        let back = f1 * Matrix3::new(0.99, 0.0, 0.0, 0.0, 1.04, 0.0, 0.0, 0.005, 0.98);
        for (f, loading) in [(further, true), (back, false)] {
            let h = f - Matrix3::identity();
            let f_inv = f.try_inverse().unwrap();
            let k = Kinematics {
                h: &h,
                f,
                f_inv,
                f_inv_t: f_inv.transpose(),
                c_n_inv_dev: sym_from(&loaded[0..6]),
                poisson: 0.35,
                dt_s: 0.3,
            };
            let o = super::super::HISTORY_BASE;
            assert_eq!(NET.loads(&k, &loaded[o..o + 12]).unwrap(), loading);
            let (_, t, _) = step(&net, &f, 0.3, &loaded);
            let fd = tangent_by_differences(&f, 1e-7, &|f: &Matrix3<f64>| step(&net, f, 0.3, &loaded).0);
            let err = (t - fd).amax() / t.amax();
            assert!(err < 1e-6, "loading {loading}: tangent error {err:.3e}");
            assert!((t - t.transpose()).amax() < 1e-10 * t.amax(), "major symmetry");
        }
    }

    /// Equal times give the viscous network bit for bit; a hold at a fixed
    /// deformation relaxes at the loading time exactly (a hold loads); unloading
    /// relaxes at the unloading time.
    #[test]
    fn equal_times_are_the_viscous_network_and_a_hold_relaxes_at_the_loading_time() {
        let f = Matrix3::new(1.1, 0.05, 0.0, 0.0, 0.6, 0.0, 0.0, 0.0, 1.2);
        let f_back = Matrix3::new(1.05, 0.02, 0.0, 0.0, 0.8, 0.0, 0.0, 0.0, 1.1);
        let same = Network::new(0.3).with(DualNetwork { e_mpa: 0.02, tau_load_s: 3.0, tau_unload_s: 3.0 });
        let viscous = Network::new(0.3).with(ViscousNetwork { e_mpa: 0.02, tau_s: 3.0 });
        let zero = vec![0.0; same.history_len()];
        let (mut h_d, mut h_v) = (zero.clone(), zero.clone());
        for (g, dt) in [(f, 0.5), (f, 2.0), (f_back, 0.7)] {
            let (pd, td, nd) = step(&same, &g, dt, &h_d);
            let (pv, tv, nv) = step(&viscous, &g, dt, &h_v);
            assert_eq!((pd, td, &nd), (pv, tv, &nv));
            (h_d, h_v) = (nd, nv);
        }
        let net = Network::new(0.3).with(NET);
        let (p0, _, h1) = step(&net, &f, 0.5, &zero);
        let (p1, _, h2) = step(&net, &f, 2.0, &h1);
        let want = p0 * (-2.0 / NET.tau_load_s).exp();
        assert!((p1 - want).amax() < 1e-12 * p0.amax(), "{:.3e}", (p1 - want).amax());
        // Unloading: the same step as a viscous network of the unloading time.
        let fast = Network::new(0.3).with(ViscousNetwork { e_mpa: NET.e_mpa, tau_s: NET.tau_unload_s });
        let (pu, _, _) = step(&net, &f_back, 0.7, &h2);
        let (pf, _, _) = step(&fast, &f_back, 0.7, &h2);
        assert_eq!(pu, pf);
    }

    /// Registered: a network with `[[dual]]` parts names their keys through the
    /// registry.
    #[test]
    fn the_part_is_registered() {
        assert!(std::ptr::eq(super::super::part::kind("dual").unwrap(), &KIND));
        Network::new(0.3).with(NET).with(NET).validate().unwrap();
        let keys = super::super::parameters::flat_keys();
        assert!(keys.contains(&"dual[1].tau_unload_s"));
    }
}
