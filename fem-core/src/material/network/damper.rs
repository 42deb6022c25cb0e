//! The parallel Newtonian damper: a Hencky spring of modulus `c / dt` on the
//! configuration of the step's start (`A = C_n^-1`). Its stress is
//! `c C1 : log(F C_n^-1 F^T) / (2 dt)`, the chain's `B2 de/dt` at small strain.
//! It keeps no history of its own (the network keeps `C_n^-1`).

use std::sync::Arc;

use nalgebra::Matrix3;

use super::hencky;
use super::part::{Kinematics, Part, PartKind, SmallKinematics};
use crate::material::law::{LawFailure, ParameterSpec, Start, Tangent};

/// The parallel damper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damper {
    /// The Young-type viscosity `c` [MPa s].
    pub c_mpa_s: f64,
}

/// `[damper]`.
pub static KIND: PartKind = PartKind {
    table: "damper",
    meaning: "a Newtonian damper in parallel",
    max_count: 1,
    parameters: &[ParameterSpec::new(
        "c_MPa_s",
        "Young-type viscosity of the parallel damper",
        "MPa s",
        (0.0, true),
        1e6,
        None,
    )
    .fit(1e-6, 1e4, true)
    .start(Start::OfModulus(0.1))],
    build: |v| Arc::new(Damper { c_mpa_s: v[0] }),
};

impl Part for Damper {
    fn kind(&self) -> &'static PartKind {
        &KIND
    }

    fn values(&self) -> Vec<f64> {
        vec![self.c_mpa_s]
    }

    fn small_strain_modulus(&self) -> f64 {
        0.0
    }

    fn viscosity_mpa_s(&self) -> f64 {
        self.c_mpa_s
    }

    fn has_small_strain_form(&self) -> bool {
        true
    }

    /// `sigma = c C1 : (eps - eps_n) / dt`: the chain's `B2 de/dt`.
    fn respond_small(
        &self,
        k: &SmallKinematics,
        _old: &[f64],
        _new: &mut [f64],
    ) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let lame = hencky::unit_lame(k.poisson);
        let c = self.c_mpa_s / k.dt_s;
        Ok((hencky::hooke(c, lame, &(k.eps - k.eps_n)), hencky::hooke_tangent(c, lame)))
    }

    fn respond(&self, k: &Kinematics, _old: &[f64], _new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        let lame = hencky::unit_lame(k.poisson);
        let (p, t, _) = hencky::spring(k.h, &k.f_inv_t, &k.c_n_inv_dev, self.c_mpa_s / k.dt_s, lame);
        Ok((p, t))
    }

    fn stress(&self, k: &Kinematics, _old: &[f64], _new: &mut [f64]) -> Result<Matrix3<f64>, LawFailure> {
        let lame = hencky::unit_lame(k.poisson);
        Ok(hencky::spring_stress(k.h, &k.f_inv_t, &k.c_n_inv_dev, self.c_mpa_s / k.dt_s, lame).p)
    }
}
