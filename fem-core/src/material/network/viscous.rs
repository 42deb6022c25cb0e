//! A viscous (Maxwell) network: `F = Fe Fv`, a Hencky spring on `Fe` and
//! Newtonian flow of relaxation time `tau` (Reese-Govindjee, with the viscosity
//! proportional to the spring's moduli: the flow relaxes the spring's whole log
//! strain, volume included, as the seed's Lamé split does). The update is the
//! exponential integrator of the module docs of [`super`], exact for the chain
//! at small strain.
//!
//! History (12 values): `A - I` (`A = C_v^-1`), then the second
//! Piola-Kirchhoff stress `S_n` at the step's start, symmetric tensors as
//! `[xx, yy, zz, xy, xz, yz]`; in small-strain kinematics the network's stress
//! at the step's start, then six unused values.

use std::sync::Arc;

use nalgebra::Matrix3;

use super::hencky;
use super::part::{Kinematics, Part, PartKind, SmallKinematics};
use super::{sym_from, sym_to};
use crate::material::law::{LawFailure, ParameterSpec, Start, Tangent};
use crate::material::phi1;

/// A viscous (Maxwell) network: a Hencky spring and Newtonian flow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViscousNetwork {
    /// The spring's Young's modulus [MPa].
    pub e_mpa: f64,
    /// The relaxation time `tau` [s] (viscosity over modulus).
    pub tau_s: f64,
}

/// `[[viscous]]`: at most four viscous networks.
pub static KIND: PartKind = PartKind {
    table: "viscous",
    meaning: "a Maxwell network: a Hencky spring and Newtonian flow",
    max_count: 4,
    parameters: &[
        super::part::SPRING_MODULUS,
        ParameterSpec::new("tau_s", "relaxation time", "s", (0.0, true), 1e9, None)
            .fit(1e-3, 1e5, true)
            .start(Start::Decades(1.0)),
    ],
    build: |v| Arc::new(ViscousNetwork { e_mpa: v[0], tau_s: v[1] }),
};

impl Part for ViscousNetwork {
    fn kind(&self) -> &'static PartKind {
        &KIND
    }

    fn values(&self) -> Vec<f64> {
        vec![self.e_mpa, self.tau_s]
    }

    fn history_len(&self) -> usize {
        12
    }

    fn small_strain_modulus(&self) -> f64 {
        self.e_mpa
    }

    fn has_small_strain_form(&self) -> bool {
        true
    }

    /// The chain's exact exponential update for a strain linear in the step
    /// (design.md 3.3): `sigma = e sigma_n + phi E C1 : (eps - eps_n)`, the
    /// network's stress `sigma_n` at the step's start kept in `old[0..6]`.
    fn respond_small(
        &self,
        k: &SmallKinematics,
        old: &[f64],
        new: &mut [f64],
    ) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let lame = hencky::unit_lame(k.poisson);
        let x = k.dt_s / self.tau_s;
        let (decay, phi) = ((-x).exp(), phi1(x));
        let sigma = sym_from(&old[0..6]) * decay + hencky::hooke(self.e_mpa * phi, lame, &(k.eps - k.eps_n));
        sym_to(&sigma, &mut new[0..6]);
        Ok((sigma, hencky::hooke_tangent(self.e_mpa * phi, lame)))
    }

    fn respond(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let (p, tangent) = self.step(k, old, new, true)?;
        Ok((p, tangent.expect("asked for")))
    }

    fn stress(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<Matrix3<f64>, LawFailure> {
        self.step(k, old, new, false).map(|(p, _)| p)
    }
}

impl ViscousNetwork {
    /// The step's stress, its tangent when `with_tangent`, and the new history
    /// ([`Part::respond`]).
    fn step(
        &self,
        k: &Kinematics,
        old: &[f64],
        new: &mut [f64],
        with_tangent: bool,
    ) -> Result<(Matrix3<f64>, Option<Tangent>), LawFailure> {
        let (f, f_inv, f_inv_t) = (k.f, k.f_inv, k.f_inv_t);
        let lame = hencky::unit_lame(k.poisson);
        let a_dev = sym_from(&old[0..6]);
        let s_n = sym_from(&old[6..12]);
        let x = k.dt_s / self.tau_s;
        let (decay, phi) = ((-x).exp(), phi1(x));
        let spring = hencky::spring_stress(k.h, &f_inv_t, &a_dev, self.e_mpa, lame);
        // The old stress carried into the current frame: the mean of its push
        // forward as a contravariant (F S_n F^T) and as a covariant
        // (F^-T M_n F^-1, M_n = C_n S_n C_n) tensor, as Kirchhoff stresses.
        let c_n = (Matrix3::identity() + k.c_n_inv_dev).try_inverse().ok_or(LawFailure::NonFinite)?;
        let m_n = c_n * s_n * c_n;
        let c_inv = f_inv * f_inv_t;
        let w = 0.5 * (decay - phi);
        let pv = spring.p * phi + (f * s_n + f_inv_t * m_n * c_inv) * w;
        let tangent = with_tangent.then(|| {
            let mut tangent = hencky::spring_tangent(k.h, &f_inv_t, &a_dev, self.e_mpa, lame, &spring) * phi;
            // d/dF of (F S_n + F^-T M_n C^-1) w at dF = e_k e_l^T, with
            // a = F^-T e_l, b = F^-1 e_k (d F^-T = -a b^T) and c = F^-1 a
            // (d C^-1 = -b c^T - c b^T): every term an outer product.
            let x_mc = m_n * c_inv;
            let y_fm = f_inv_t * m_n;
            for kk in 0..3 {
                let b = f_inv.column(kk).into_owned();
                let xb = x_mc.transpose() * b;
                let yb = y_fm * b;
                for l in 0..3 {
                    let a = f_inv_t.column(l).into_owned();
                    let c = f_inv * a;
                    let yc = y_fm * c;
                    for i in 0..3 {
                        for jj in 0..3 {
                            let df_s = if i == kk { s_n[(l, jj)] } else { 0.0 };
                            let dp = df_s - a[i] * xb[jj] - yb[i] * c[jj] - yc[i] * b[jj];
                            tangent[(3 * i + jj, 3 * kk + l)] += dp * w;
                        }
                    }
                }
            }
            tangent
        });
        // The new state from the stress: A - I = F^-1 (b_e - I) F^-T + (C^-1 - I).
        let tau = hencky::symmetrize(&(pv * f.transpose()));
        let eps_e = hencky::hooke_inverse(self.e_mpa, lame, &tau);
        let b_e_dev = hencky::sym_exp_m1(&(eps_e * 2.0));
        let a_new = f_inv * b_e_dev * f_inv_t + hencky::inverse_right_deviation(k.h, &f_inv);
        sym_to(&hencky::symmetrize(&a_new), &mut new[0..6]);
        sym_to(&hencky::symmetrize(&(f_inv * tau * f_inv_t)), &mut new[6..12]);
        Ok((pv, tangent))
    }
}
