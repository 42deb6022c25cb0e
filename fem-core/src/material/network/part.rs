//! The network's parallel parts behind one trait, and their registry.
//!
//! A part is one network in parallel with the others (a viscous network, the
//! plastic network, the damper, ...). It owns its parameters, its history
//! layout and its response; the [`Network`](super::Network) only sums the
//! parts' stresses and tangents and hands each its slice of the point's history.
//! Its [`PartKind`] tells readers and fitters what it is: the bundle sub-table
//! (`[[viscous]]`), how many a material may hold, and the parameter table
//! (keys with units, bounds, defaults, fit ranges and starts).
//!
//! ## Adding a part
//!
//! A new part is one file in this folder: a type implementing [`Part`] and its
//! `static KIND: PartKind`, plus one line in [`PARTS`]. The bundle reader, the
//! writer, the flat keys identification names (`flow[0].stress_MPa`), the fit's
//! ranges and starts and the validation all follow from the kind: no other
//! file names its keys. [`super::flow`] and [`super::dual`] were added that way.

use std::sync::Arc;

use nalgebra::Matrix3;

use crate::material::law::{LawFailure, ParameterSpec, Tangent};

/// What a part sees of a point in a step: the deformation gradient
/// `F = I + h`, its inverse, the configuration at the step's start and the
/// material's Poisson ratio.
#[derive(Debug, Clone, Copy)]
pub struct Kinematics<'a> {
    /// The displacement gradient `h = F - I`.
    pub h: &'a Matrix3<f64>,
    /// `F`.
    pub f: Matrix3<f64>,
    /// `F^-1`.
    pub f_inv: Matrix3<f64>,
    /// `F^-T`.
    pub f_inv_t: Matrix3<f64>,
    /// `C_n^-1 - I`: the inverse right Cauchy-Green tensor at the step's start,
    /// as its deviation from the identity.
    pub c_n_inv_dev: Matrix3<f64>,
    /// The material's Poisson ratio (every part uses it).
    pub poisson: f64,
    /// The step [s].
    pub dt_s: f64,
}

/// What a part sees of a point in a step in small-strain (linearised)
/// kinematics ([`super::Strain::Small`]): the strain `eps = sym(h)` and its
/// value at the step's start.
#[derive(Debug, Clone, Copy)]
pub struct SmallKinematics {
    /// The strain at the step's end.
    pub eps: Matrix3<f64>,
    /// The strain at the step's start.
    pub eps_n: Matrix3<f64>,
    /// The material's Poisson ratio (every part uses it).
    pub poisson: f64,
    /// The step [s].
    pub dt_s: f64,
}

/// One network in parallel with the others.
pub trait Part: std::fmt::Debug + Send + Sync {
    /// What kind of part it is.
    fn kind(&self) -> &'static PartKind;
    /// Its parameter values, in the order of its kind's table.
    fn values(&self) -> Vec<f64>;
    /// Length of its per-point history.
    fn history_len(&self) -> usize {
        0
    }
    /// Its Young-type modulus at small strain and no rate [MPa] (0 for a damper).
    fn small_strain_modulus(&self) -> f64;
    /// Its viscosity [MPa s], for a part that is only a viscosity (a damper).
    fn viscosity_mpa_s(&self) -> f64 {
        0.0
    }
    /// Its first Piola-Kirchhoff stress and exact tangent `dP/dF` for the step
    /// from its history `old` (zeros at rest); writes its history at the step's
    /// end into `new` (same length, a copy of `old` on entry).
    fn respond(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<(Matrix3<f64>, Tangent), LawFailure>;
    /// Its first Piola-Kirchhoff stress alone, bit for bit that of
    /// [`Part::respond`] with the same history contract: for the evaluations
    /// whose tangent is not used (a line search's trials, a converged
    /// iterate). The default calls [`Part::respond`]; a part whose tangent
    /// costs more than its stress overrides it.
    fn stress(&self, k: &Kinematics, old: &[f64], new: &mut [f64]) -> Result<Matrix3<f64>, LawFailure> {
        self.respond(k, old, new).map(|(p, _)| p)
    }
    /// Whether it has a small-strain form ([`Part::respond_small`]); a network
    /// in small-strain kinematics with a part that has none is refused
    /// ([`super::Network::validate`]).
    fn has_small_strain_form(&self) -> bool {
        false
    }
    /// Its stress and exact tangent `d sigma / d h` in small-strain kinematics
    /// (the stress is the Cauchy stress, the tangent's layout that of
    /// [`Part::respond`]), with the same history contract.
    fn respond_small(
        &self,
        _k: &SmallKinematics,
        _old: &[f64],
        _new: &mut [f64],
    ) -> Result<(Matrix3<f64>, Tangent), LawFailure> {
        Err(LawFailure::NoSmallStrainForm { law: self.kind().table })
    }
}

/// A kind of part, as readers and fitters see it.
#[derive(Debug)]
pub struct PartKind {
    /// Its sub-table in a material: `[viscous]` or `[[viscous]]`.
    pub table: &'static str,
    /// What it is, in words.
    pub meaning: &'static str,
    /// How many a material may hold (1: a single `[table]`).
    pub max_count: usize,
    /// Its parameters.
    pub parameters: &'static [ParameterSpec],
    /// The part from its parameter values (in the table's order, within bounds).
    pub build: fn(&[f64]) -> Arc<dyn Part>,
}

impl PartKind {
    /// The flat key of parameter `key` of the `index`-th part of this kind:
    /// `plastic.E_MPa` (one allowed) or `viscous[1].tau_s`.
    pub fn flat_key(&self, index: usize, key: &str) -> String {
        if self.max_count == 1 {
            format!("{}.{key}", self.table)
        } else {
            format!("{}[{index}].{key}", self.table)
        }
    }
}

/// The Young's modulus of a part's Hencky spring (`E_MPa`), as every part with
/// one publishes it.
pub(crate) const SPRING_MODULUS: ParameterSpec =
    ParameterSpec::new("E_MPa", "the spring's Young's modulus", "MPa", (0.0, true), 1e4, None)
        .fit(1e-5, 1e2, true)
        .start(crate::material::law::Start::OfModulus(0.25));

/// Every kind of part, in the order a network holds them (its history layout).
pub static PARTS: &[&PartKind] = &[
    &super::viscous::KIND,
    &super::plastic::KIND,
    &super::flow::KIND,
    &super::bingham::KIND,
    &super::damper::KIND,
    &super::dual::KIND,
];

/// The kind whose sub-table is `table`.
pub fn kind(table: &str) -> Option<&'static PartKind> {
    PARTS.iter().copied().find(|k| k.table == table)
}

/// A part's step at the deformation gradient `f` from the history `old`, the
/// configuration at the step's start the reference (the parts' unit tests):
/// its stress, tangent and new history.
#[cfg(test)]
pub(crate) fn step_at(
    part: &dyn Part,
    f: &Matrix3<f64>,
    poisson: f64,
    dt_s: f64,
    old: &[f64],
) -> (Matrix3<f64>, Tangent, Vec<f64>) {
    let h = f - Matrix3::identity();
    let f_inv = f.try_inverse().expect("an invertible F");
    let k =
        Kinematics { h: &h, f: *f, f_inv, f_inv_t: f_inv.transpose(), c_n_inv_dev: Matrix3::zeros(), poisson, dt_s };
    let mut new = old.to_vec();
    let (p, t) = part.respond(&k, old, &mut new).expect("the part responds");
    (p, t, new)
}

/// The spec of `key` in a parameter table.
pub(crate) fn spec(table: &[ParameterSpec], key: &str) -> ParameterSpec {
    *table.iter().find(|s| s.key == key).expect("the key is in its table")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every registered part's parameters: the fit range inside the accepted
    /// bounds, the start inside the fit range for apparent moduli from 1 kPa to
    /// 100 MPa and every part of the kind, the default accepted.
    #[test]
    fn every_kinds_fit_ranges_starts_and_defaults_lie_within_its_bounds() {
        for kind in PARTS {
            for s in kind.parameters {
                let name = kind.flat_key(0, s.key);
                assert!(s.fit.lower < s.fit.upper, "{name}");
                assert!(s.accepts(s.fit.lower) && s.accepts(s.fit.upper), "{name}: fit range outside {}", s.range());
                for e_app in [1e-3, 1.0, 100.0] {
                    for index in 0..kind.max_count {
                        let v = s.start.value(e_app, index);
                        assert!(v >= s.fit.lower && v <= s.fit.upper, "{name}: start {v} at E_app {e_app}");
                    }
                }
                if let Some(d) = s.default {
                    assert!(s.accepts(d), "{name}: default {d}");
                }
            }
        }
    }
}
