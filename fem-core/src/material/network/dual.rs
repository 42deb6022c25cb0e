//! A dual-viscosity network: a viscous (Maxwell) network whose relaxation time
//! is `tau_load` while its spring loads and `tau_unload` while it unloads, the
//! finite-strain form of the chain's dual viscosity (Wang & Hirai 2012: foods
//! recover at another rate than they relax).
//!
//! The step is the viscous network's ([`super::viscous`], the exponential
//! integrator exact for the chain at small strain) with the time of the
//! spring's direction, decided at the step's start: the direction of the
//! previous step, kept in the history. A step loads when its end deformation
//! with no flow (the trial state) would not lower the spring's energy:
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
//! is loading without comparing rounded energies, a fall of less than 1e-10 of
//! the start energy too (the solver's residual stresses times its last
//! corrections, of either sign), and the first step from rest loads.
//!
//! Why at the step's start: decided by the step's own end deformation, the
//! stress would jump across the switch (by the difference of the two
//! relaxations over the step), and Newton's iteration stalls where a cell sits
//! on it (a glued block's cells at the start of a hold do). Decided at the
//! start, the step is smooth in `F`, its tangent is the viscous network's of
//! the step's time (exact) and the iteration converges as the viscous
//! network's. The price: the time follows a reversal one step late, an error of
//! first order in the step at each reversal (measured in `tests/network.rs`).
//! Both energies are invariants, so the choice is objective. With
//! `tau_unload = tau_load` the part is the viscous network bit for bit.
//!
//! History (13 values): the viscous network's (`A - I` and `S_n`), then the
//! last step's direction (0 loading, 1 unloading).

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
        super::part::SPRING_MODULUS,
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
/// residual stresses times its last corrections (estimated at 1e-13 of the
/// energy or less), far below a step that unloads (a strain step of `x` of the
/// elastic strain lowers the energy by about `2 x`).
const HOLD_BAND: f64 = 1e-10;

impl DualNetwork {
    /// Whether the step to the deformation of `k` loads the spring, from the
    /// part's history at the step's start `old` (module docs): the direction
    /// the next step's time follows.
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
        13
    }

    fn small_strain_modulus(&self) -> f64 {
        self.e_mpa
    }

    fn respond(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let tau_s = if old[12] == 0.0 { self.tau_load_s } else { self.tau_unload_s };
        new[12] = if self.loads(k, old)? { 0.0 } else { 1.0 };
        ViscousNetwork { e_mpa: self.e_mpa, tau_s }.respond(k, &old[..12], &mut new[..12])
    }

    fn stress(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<Matrix3<f64>, LawFailure> {
        let tau_s = if old[12] == 0.0 { self.tau_load_s } else { self.tau_unload_s };
        new[12] = if self.loads(k, old)? { 0.0 } else { 1.0 };
        ViscousNetwork { e_mpa: self.e_mpa, tau_s }.stress(k, &old[..12], &mut new[..12])
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

    /// The tangent against central differences at either time: a step
    /// further along a loading path, after a loading step and after an
    /// unloading one, from states away from the identity.
    #[test]
    fn the_tangent_matches_central_differences_at_either_time() {
        let net = Network::new(0.35).with(NET);
        let o = super::super::HISTORY_BASE;
        let f1 = Matrix3::new(1.05, 0.1, 0.0, 0.02, 0.8, 0.03, 0.0, 0.01, 1.1);
        let (_, _, loaded) = step(&net, &f1, 0.5, &vec![0.0; net.history_len()]);
        let back = f1 * Matrix3::new(0.99, 0.0, 0.0, 0.0, 1.04, 0.0, 0.0, 0.005, 0.98);
        let (_, _, unloaded) = step(&net, &back, 0.3, &loaded);
        assert_eq!((loaded[o + 12], unloaded[o + 12]), (0.0, 1.0), "the directions");
        let further = f1 * Matrix3::new(1.02, 0.01, 0.0, 0.0, 0.95, 0.0, 0.0, 0.0, 1.03);
        let back_further = back * Matrix3::new(0.99, 0.0, 0.0, 0.0, 1.03, 0.0, 0.0, 0.0, 0.99);
        for (f, old) in [(further, &loaded), (back_further, &unloaded)] {
            let (_, t, _) = step(&net, &f, 0.3, old);
            let fd = tangent_by_differences(&f, 1e-7, &|f: &Matrix3<f64>| step(&net, f, 0.3, old).0);
            let err = (t - fd).amax() / t.amax();
            assert!(err < 1e-6, "direction {}: tangent error {err:.3e}", old[o + 12]);
            assert!((t - t.transpose()).amax() < 1e-10 * t.amax(), "major symmetry");
        }
    }

    /// Equal times give the viscous network bit for bit; a hold at a fixed
    /// deformation after loading relaxes at the loading time exactly; a step
    /// back unloads, and the hold after it relaxes at the unloading time (the
    /// direction of the step before), the next at the loading time again (a
    /// hold loads).
    #[test]
    fn equal_times_are_the_viscous_network_and_holds_relax_at_the_last_directions_time() {
        let o = super::super::HISTORY_BASE;
        let f = Matrix3::new(1.1, 0.05, 0.0, 0.0, 0.6, 0.0, 0.0, 0.0, 1.2);
        let f_back = Matrix3::new(1.05, 0.02, 0.0, 0.0, 0.8, 0.0, 0.0, 0.0, 1.1);
        let same = Network::new(0.3).with(DualNetwork { e_mpa: 0.02, tau_load_s: 3.0, tau_unload_s: 3.0 });
        let viscous = Network::new(0.3).with(ViscousNetwork { e_mpa: 0.02, tau_s: 3.0 });
        let (mut h_d, mut h_v) = (vec![0.0; same.history_len()], vec![0.0; viscous.history_len()]);
        for (g, dt) in [(f, 0.5), (f, 2.0), (f_back, 0.7), (f_back, 0.4)] {
            let (pd, td, nd) = step(&same, &g, dt, &h_d);
            let (pv, tv, nv) = step(&viscous, &g, dt, &h_v);
            assert_eq!((pd, td, &nd[..o + 12]), (pv, tv, &nv[..]));
            (h_d, h_v) = (nd, nv);
        }
        let net = Network::new(0.3).with(NET);
        let (p0, _, h1) = step(&net, &f, 0.5, &vec![0.0; net.history_len()]);
        let (p1, _, h2) = step(&net, &f, 2.0, &h1);
        let want = p0 * (-2.0 / NET.tau_load_s).exp();
        assert!((p1 - want).amax() < 1e-12 * p0.amax(), "{:.3e}", (p1 - want).amax());
        assert_eq!(h2[o + 12], 0.0, "a hold loads");
        let (pb, _, h3) = step(&net, &f_back, 0.7, &h2);
        assert_eq!(h3[o + 12], 1.0, "the step back unloads");
        let (ph, _, h4) = step(&net, &f_back, 0.4, &h3);
        let want = pb * (-0.4 / NET.tau_unload_s).exp();
        assert!((ph - want).amax() < 1e-12 * pb.amax(), "{:.3e}", (ph - want).amax());
        let (ph2, _, _) = step(&net, &f_back, 0.4, &h4);
        let want = ph * (-0.4 / NET.tau_load_s).exp();
        assert!((ph2 - want).amax() < 1e-12 * ph.amax(), "{:.3e}", (ph2 - want).amax());
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
