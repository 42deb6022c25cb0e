//! The finite-strain parallel rheological network (`model = "network"`): the
//! family of Abaqus's PRF, Reese & Govindjee (1998) and Bergström & Boyce
//! (1998), built so that at small strain it is the seed's chain exactly.
//!
//! ## Parts (all in parallel, each on the whole deformation)
//!
//! - an optional **equilibrium** network ([`Equilibrium`]): a neo-Hookean,
//!   exponential or Ogden isochoric energy with `U(J) = K/2 (J - 1)^2`,
//!   optionally with Ogden-Roxburgh softening; absent, the material is a fluid
//!   like the chain;
//!
//! and the **parts** ([`part`]: each one file behind the [`Part`] trait, listed
//! once in the registry [`PARTS`] that readers and fitters follow):
//!
//! - `N >= 0` **viscous networks** ([`ViscousNetwork`]): `F = Fe Fv`, a Hencky
//!   spring of modulus `E_i` on `Fe` and Newtonian flow of relaxation time
//!   `tau_i` (Reese-Govindjee with the viscosity proportional to the spring's
//!   moduli: the flow relaxes the spring's whole log strain, volume included, as
//!   the seed's Lamé split does);
//! - an optional **plastic** network ([`PlasticNetwork`]): a Hencky spring on
//!   `F = Fe Fp` with von Mises yield, linear isotropic and linear kinematic
//!   (Prager) hardening, by the exponential map's closed-form radial return
//!   ([`plastic`]); it holds the permanent set against the other networks;
//! - up to two **power-law flow** networks ([`FlowNetwork`]): a Hencky spring
//!   whose shear flows by Norton's law, by the plastic network's radial return
//!   with a rate-dependent radius ([`flow`]);
//! - an optional **Bingham** network ([`BinghamNetwork`]): a Hencky spring
//!   whose shear flows only above a yield stress, at a rate proportional to the
//!   excess, by the same return with a closed-form multiplier ([`bingham`]);
//! - an optional parallel Newtonian **damper** of Young-type viscosity `c`
//!   [MPa s], acting on the rate of the logarithmic strain;
//! - up to two **dual-viscosity** networks ([`DualNetwork`]): a viscous network
//!   whose relaxation time differs between loading and unloading of its spring
//!   ([`dual`]).
//!
//! Every part uses the material's one Poisson ratio.
//!
//! ## Small-strain kinematics
//!
//! A network may also run in small-strain kinematics ([`Strain::Small`],
//! `kinematics = "small"`): every part on `eps = sym(h)`, the stress Cauchy's
//! and no geometric term. The viscous networks then update by the chain's exact
//! exponential rule and the damper is `c C1 : de/dt`, so the seed's chain as a
//! network ([`Network::from_chain`]) is the chain itself to round-off. Parts
//! without a small-strain form (plastic, flow, an energy other than
//! neo-Hookean's, softening) are refused by [`Network::validate`].
//!
//! ## The viscous update: exact for the chain
//!
//! A network's state is its elastic log strain `eps_e`, kept as the inverse
//! viscous right Cauchy-Green tensor `A = C_v^-1` (so `b_e = F A F^T`) together
//! with its second Piola-Kirchhoff stress `S_n` at the step's start. With
//! `x = dt / tau`, `e = exp(-x)` and `phi = (1 - e) / x`, the step's Kirchhoff
//! stress is
//!
//! ```text
//! tau_{n+1} = phi E_i C1 : log(F A_n F^T)/2  +  (e - phi) (f tau_n f^T + f^-T tau_n f^-1) / 2,
//! ```
//!
//! `f = F F_n^-1` the step's relative deformation (computed from the reference
//! tensors `S_n = F_n^-1 tau_n F_n^-T` and `M_n = F_n^T tau_n F_n`: `F S_n F^T`
//! and `F^-T M_n F^-1`). At small strain the first term is
//! `phi E_i C1 : (e_e,n + de)` and the second `(e - phi) E_i C1 : e_e,n`, so
//! `tau_{n+1} = E_i C1 : (e e_e,n + phi de)`: the chain's exact exponential
//! history update (design.md 3.3) for a strain linear in the step. At finite
//! strain, on a coaxial path whose log strain is linear in the step, the exact
//! solution of Reese-Govindjee's flow with a Hencky spring carries `tau_n`
//! unstretched; the mean of the two push-forwards stretches it by
//! `cosh(2 de) = 1 + O(de^2)` only, so the update is second-order accurate in
//! the step (measured in `tests/network.rs`), where either push-forward alone is
//! first order. It is objective (`A_n`, `S_n` and `M_n` live in the reference
//! configuration) and needs no local iteration. Its stress derives from the
//! step's potential `phi psi_Hencky(F A_n F^T) + (e - phi)(S_n : C - M_n : C^-1)/4`,
//! so its tangent is major-symmetric and the global tangent keeps the chain's
//! symmetric Cholesky factorization. The new state follows from the stress:
//! `eps_e = C1^-1 : tau / E_i`, `A = F^-1 exp(2 eps_e) F^-T`, `S_n = F^-1 tau F^-T`.
//!
//! The damper is a Hencky spring of modulus `c / dt` on the configuration of the
//! step's start (`A = C_n^-1`): its stress is `c C1 : log(F C_n^-1 F^T)/(2 dt)`,
//! the chain's `B2 de/dt` at small strain.
//!
//! ## The seed's chain as a network
//!
//! A chain's relaxation function `G(t) = B2 delta(t) + a exp(-m t) + b exp(-n t)`
//! (design.md 3.1) is a damper `c = B2` and two viscous networks `(a, 1/m)` and
//! `(b, 1/n)` ([`Network::from_chain`]); an elastic chain or one with
//! `G(inf) > 0` adds a neo-Hookean equilibrium network of modulus `G(inf)`.
//!
//! ## History layout (per point)
//!
//! `[C_n^-1 - I (6), W_max (1)]`, then each part's own history in the order of
//! [`Network::parts`] (a viscous network: `A - I (6), S_n (6)`; the plastic
//! network: `Cp^-1 - I (6), alpha (1)`; a flow network: `Cv^-1 - I (6)`; a
//! Bingham network: `Cv^-1 - I (6)` and one unused value; the damper: none; a
//! dual-viscosity network: a viscous network's, then the direction of its last
//! step (1)), symmetric tensors as `[xx, yy, zz, xy, xz, yz]`. The
//! configurations are kept as deviations from the identity, so that small
//! strains keep their precision ([`hencky`]).

pub mod bingham;
mod damper;
pub mod dual;
mod equilibrium;
pub mod flow;
mod hencky;
pub mod part;
pub mod plastic;
mod viscous;

pub use bingham::BinghamNetwork;
pub use damper::Damper;
pub use dual::DualNetwork;
pub use equilibrium::{energy_keys, Energy, Equilibrium, Mullins, ENERGIES, OGDEN_TERMS};
pub use flow::FlowNetwork;
pub use part::{Kinematics, Part, PartKind, SmallKinematics, PARTS};
pub use plastic::PlasticNetwork;
pub use viscous::ViscousNetwork;

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use nalgebra::Matrix3;

use crate::material::law::{LawFailure, ParameterSpec, PointLaw, PointResponse, Tangent};
use crate::material::Rheology;

/// How many cell-law evaluations the Newton path has made in this process:
/// with their tangent and of the stress alone ([`Network::stress`]). For
/// benchmarks (the `network_cost` example prints them); one atomic addition
/// per evaluation of the whole body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EvaluationCounts {
    /// Cell evaluations with the tangent.
    pub with_tangent: u64,
    /// Cell evaluations of the stress alone.
    pub stress_only: u64,
}

static WITH_TANGENT: AtomicU64 = AtomicU64::new(0);
static STRESS_ONLY: AtomicU64 = AtomicU64::new(0);

/// The evaluations counted so far ([`EvaluationCounts`]).
pub fn evaluation_counts() -> EvaluationCounts {
    EvaluationCounts {
        with_tangent: WITH_TANGENT.load(Ordering::Relaxed),
        stress_only: STRESS_ONLY.load(Ordering::Relaxed),
    }
}

/// Counts an evaluation of `cells` cells' laws.
pub(crate) fn count_evaluations(cells: usize, with_tangent: bool) {
    let counter = if with_tangent { &WITH_TANGENT } else { &STRESS_ONLY };
    counter.fetch_add(cells as u64, Ordering::Relaxed);
}

/// The kinematics a network works in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Strain {
    /// Finite strain: the deformation gradient, logarithmic strains and the
    /// exponential map (the module docs).
    #[default]
    Finite,
    /// Small strain: every part on `eps = sym(h)`, the stress Cauchy's, with no
    /// geometric terms. The seed's chain as a network is then the chain itself
    /// (the linear chain's exact exponential update, design.md 3.3), which is
    /// what a network layer beside a chain layer, or the null of a
    /// finite-strain candidate, needs. Only the neo-Hookean equilibrium energy
    /// without softening, the viscous networks and the damper have this form
    /// ([`Part::has_small_strain_form`]).
    Small,
}

impl Strain {
    /// Every kinematics by its bundle name.
    pub const NAMES: &'static [(&'static str, Strain)] = &[("finite", Strain::Finite), ("small", Strain::Small)];

    /// Its bundle name.
    pub fn name(self) -> &'static str {
        Self::NAMES.iter().find(|(_, s)| *s == self).map(|(n, _)| *n).expect("every kinematics is named")
    }
}

/// The finite-strain network material (module docs).
#[derive(Debug, Clone)]
pub struct Network {
    /// Poisson's ratio of every part, in (-1, 0.5).
    pub poisson: f64,
    /// The kinematics ([`Strain`]; finite unless asked).
    pub strain: Strain,
    /// The equilibrium network; `None`: a fluid.
    pub equilibrium: Option<Equilibrium>,
    /// The parts in parallel ([`part`]), in their order in the point's history.
    pub parts: Vec<Arc<dyn Part>>,
}

impl PartialEq for Network {
    fn eq(&self, other: &Self) -> bool {
        self.poisson == other.poisson
            && self.strain == other.strain
            && self.equilibrium == other.equilibrium
            && self.parts.len() == other.parts.len()
            && self
                .parts
                .iter()
                .zip(&other.parts)
                .all(|(a, b)| std::ptr::eq(a.kind(), b.kind()) && a.values() == b.values())
    }
}

/// Why a network was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NetworkError {
    /// A parameter outside its bounds.
    #[error("{key} = {value}: must lie in {range}")]
    OutOfBounds { key: String, value: f64, range: String },
    /// More parts of a kind than it allows.
    #[error("{count} {table} parts: at most {max}")]
    TooMany { table: &'static str, count: usize, max: usize },
    /// A part without a small-strain form in a small-strain network.
    #[error("{what} has no small-strain form (kinematics = \"small\"; it needs \"finite\")")]
    NoSmallStrainForm { what: String },
    /// Nothing carries stress.
    #[error("the network has no part: give an equilibrium network, a viscous network or a damper")]
    Empty,
}

/// The network's own parameter tables (the parts' are their kinds',
/// [`PartKind::parameters`]): keys, units, bounds, fit ranges and starts, named once.
pub mod parameters {
    use std::sync::OnceLock;

    use super::{ParameterSpec, PARTS};
    use crate::material::law::Start;

    /// The material's own keys (beside `model = "network"`).
    pub const MATERIAL: &[ParameterSpec] =
        &[ParameterSpec::new("poisson", "Poisson's ratio of every part", "1", (-1.0, true), 0.4999, None)];
    /// `[equilibrium]`: `energy = "neo-hookean" | "exponential" | "ogden"` and
    /// these, each energy its own ([`super::energy_keys`]): `stiffening` the
    /// exponential's, the `alpha` and `share` keys Ogden's (the first term's
    /// share is one less the others'). Ogden's terms are fitted with their
    /// signs kept (a term through `alpha = 0` vanishes): a stiffening first and
    /// third, a softening second.
    pub const EQUILIBRIUM: &[ParameterSpec] = &[
        ParameterSpec::new("E_MPa", "Young's modulus at small strain", "MPa", (0.0, true), 1e4, None)
            .fit(1e-5, 1e2, true)
            .start(Start::OfModulus(0.5)),
        ParameterSpec::new("stiffening", "b of the exponential energy", "1", (0.0, true), 100.0, None)
            .fit(1e-3, 50.0, true)
            .start(Start::Value(1.0)),
        ParameterSpec::new("alpha1", "exponent of Ogden's first term (nonzero)", "1", (-30.0, false), 30.0, None)
            .fit(0.5, 30.0, false)
            .start(Start::Value(6.0)),
        ParameterSpec::new(
            "alpha2",
            "exponent of Ogden's second term (nonzero)",
            "1",
            (-30.0, false),
            30.0,
            Some(-2.0),
        )
        .fit(-30.0, -0.5, false)
        .start(Start::Value(-2.0)),
        ParameterSpec::new(
            "share2",
            "Ogden's second term's share of the shear modulus",
            "1",
            (0.0, false),
            1.0,
            Some(0.0),
        )
        .fit(0.0, 0.45, false)
        .start(Start::Value(0.1)),
        ParameterSpec::new("alpha3", "exponent of Ogden's third term (nonzero)", "1", (-30.0, false), 30.0, Some(4.0))
            .fit(0.5, 30.0, false)
            .start(Start::Value(4.0)),
        ParameterSpec::new(
            "share3",
            "Ogden's third term's share of the shear modulus",
            "1",
            (0.0, false),
            1.0,
            Some(0.0),
        )
        .fit(0.0, 0.45, false)
        .start(Start::Value(0.1)),
    ];
    /// The smallest accepted `|alpha|` of an Ogden term.
    pub const OGDEN_ALPHA_MIN: f64 = 1e-2;
    /// `[equilibrium.mullins]`: Ogden-Roxburgh softening.
    pub const MULLINS: &[ParameterSpec] = &[
        ParameterSpec::new("r", "the softened stress is at least 1 - 1/r of the virgin", "1", (1.0, true), 1e3, None)
            .fit(1.01, 50.0, true)
            .start(Start::Value(3.0)),
        ParameterSpec::new("m_MPa", "energy scale of the softening", "MPa", (0.0, true), 1e3, None)
            .fit(1e-6, 1.0, true)
            .start(Start::OfModulus(0.05)),
        ParameterSpec::new("beta", "growth of the scale with W_max", "1", (0.0, false), 1e3, Some(0.0))
            .fit(0.0, 5.0, false)
            .start(Start::Value(0.1)),
    ];

    /// The spec of `key` in `table`.
    pub fn find(table: &[ParameterSpec], key: &str) -> Option<ParameterSpec> {
        table.iter().find(|s| s.key == key).copied()
    }

    /// Every parameter of a network material as a flat key, the path of its
    /// sub-table key (`equilibrium.E_MPa`, `equilibrium.mullins.r`,
    /// `viscous[1].tau_s`, `plastic.yield_MPa`): what identification names and
    /// frees. Built once from the tables and the part registry.
    pub fn flat_keys() -> &'static [&'static str] {
        static KEYS: OnceLock<Vec<&'static str>> = OnceLock::new();
        KEYS.get_or_init(|| {
            let mut keys: Vec<String> = EQUILIBRIUM.iter().map(|s| format!("equilibrium.{}", s.key)).collect();
            keys.extend(MULLINS.iter().map(|s| format!("equilibrium.mullins.{}", s.key)));
            for kind in PARTS {
                for i in 0..kind.max_count {
                    keys.extend(kind.parameters.iter().map(|s| kind.flat_key(i, s.key)));
                }
            }
            // Leaked once per process: a bounded set of names that lives as long
            // as the program, like the tables it comes from.
            keys.into_iter().map(|k| &*Box::leak(k.into_boxed_str())).collect()
        })
    }

    /// The spec of a flat key ([`flat_keys`]) and the index of its part among
    /// those of its kind (0 for the equilibrium network's).
    pub fn spec_of(flat_key: &str) -> Option<(ParameterSpec, usize)> {
        let (path, leaf) = flat_key.rsplit_once('.')?;
        match path {
            "equilibrium" => return find(EQUILIBRIUM, leaf).map(|s| (s, 0)),
            "equilibrium.mullins" => return find(MULLINS, leaf).map(|s| (s, 0)),
            _ => {}
        }
        let (table, index) = match path.split_once('[') {
            Some((table, rest)) => (table, rest.strip_suffix(']')?.parse::<usize>().ok()?),
            None => (path, 0),
        };
        let kind = super::part::kind(table)?;
        if index >= kind.max_count || (kind.max_count > 1) != path.contains('[') {
            return None;
        }
        find(kind.parameters, leaf).map(|s| (s, index))
    }
}

/// The network's own history before the parts': `C_n^-1 - I` (in small-strain
/// kinematics the strain) and `W_max`.
const HISTORY_BASE: usize = 7;

pub(crate) fn sym_to(m: &Matrix3<f64>, out: &mut [f64]) {
    out[..6].copy_from_slice(&[m[(0, 0)], m[(1, 1)], m[(2, 2)], m[(0, 1)], m[(0, 2)], m[(1, 2)]]);
}

pub(crate) fn sym_from(v: &[f64]) -> Matrix3<f64> {
    Matrix3::new(v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2])
}

impl Network {
    /// A network of Poisson ratio `poisson` with no part yet.
    pub fn new(poisson: f64) -> Self {
        Self { poisson, strain: Strain::Finite, equilibrium: None, parts: Vec::new() }
    }

    /// The same network in the kinematics `strain`.
    pub fn with_strain(self, strain: Strain) -> Self {
        Self { strain, ..self }
    }

    /// The same network with the equilibrium network `equilibrium`.
    pub fn with_equilibrium(self, equilibrium: Equilibrium) -> Self {
        Self { equilibrium: Some(equilibrium), ..self }
    }

    /// The same network with `part` added after the others.
    pub fn with(mut self, part: impl Part + 'static) -> Self {
        self.parts.push(Arc::new(part));
        self
    }

    /// The parts of the kind whose sub-table is `table`, in order.
    pub fn parts_of<'a>(&'a self, table: &'a str) -> impl Iterator<Item = &'a Arc<dyn Part>> + 'a {
        self.parts.iter().filter(move |p| p.kind().table == table)
    }

    /// The seed's chain `rheology` with Poisson ratio `poisson` as a network
    /// (module docs): equal to the chain at small strain.
    pub fn from_chain(rheology: &Rheology, poisson: f64) -> Self {
        let k = rheology.relaxation();
        let mut net = Self::new(poisson);
        if k.equilibrium > 0.0 {
            net = net.with_equilibrium(Equilibrium { energy: Energy::NeoHookean, e_mpa: k.equilibrium, mullins: None });
        }
        for i in 0..k.num_terms {
            net = net.with(ViscousNetwork { e_mpa: k.amplitudes[i], tau_s: 1.0 / k.rates[i] });
        }
        if k.viscous > 0.0 {
            net = net.with(Damper { c_mpa_s: k.viscous });
        }
        net
    }

    /// Checks every parameter against its table, and each kind's count.
    pub fn validate(&self) -> Result<(), NetworkError> {
        use parameters::*;
        let check = |s: ParameterSpec, value: f64, key: String| {
            if s.accepts(value) {
                Ok(())
            } else {
                Err(NetworkError::OutOfBounds { key, value, range: s.range() })
            }
        };
        let in_table = |table: &[ParameterSpec], key: &str, value: f64, prefix: &str| {
            check(part::spec(table, key), value, format!("{prefix}{key}"))
        };
        in_table(MATERIAL, "poisson", self.poisson, "")?;
        if let Some(eq) = &self.equilibrium {
            in_table(EQUILIBRIUM, "E_MPa", eq.e_mpa, "equilibrium.")?;
            if let Energy::Exponential { stiffening } = eq.energy {
                in_table(EQUILIBRIUM, "stiffening", stiffening, "equilibrium.")?;
            }
            if let Energy::Ogden { alpha, share } = eq.energy {
                for p in 0..OGDEN_TERMS {
                    let key = format!("alpha{}", p + 1);
                    in_table(EQUILIBRIUM, &key, alpha[p], "equilibrium.")?;
                    if share[p] > 0.0 && alpha[p].abs() < OGDEN_ALPHA_MIN {
                        return Err(NetworkError::OutOfBounds {
                            key: format!("equilibrium.{key}"),
                            value: alpha[p],
                            range: format!("[-30, -{OGDEN_ALPHA_MIN}] or [{OGDEN_ALPHA_MIN}, 30] (nonzero)"),
                        });
                    }
                }
                for p in 1..OGDEN_TERMS {
                    in_table(EQUILIBRIUM, &format!("share{}", p + 1), share[p], "equilibrium.")?;
                }
                if !(share[0] > 0.0 && (share.iter().sum::<f64>() - 1.0).abs() < 1e-12) {
                    return Err(NetworkError::OutOfBounds {
                        key: "equilibrium.share2".into(),
                        value: share[1],
                        range: "[0, 1) with share2 + share3 < 1".into(),
                    });
                }
            }
            if let Some(m) = eq.mullins {
                in_table(MULLINS, "r", m.r, "equilibrium.mullins.")?;
                in_table(MULLINS, "m_MPa", m.m_mpa, "equilibrium.mullins.")?;
                in_table(MULLINS, "beta", m.beta, "equilibrium.mullins.")?;
            }
        }
        for kind in PARTS {
            let of_kind: Vec<&Arc<dyn Part>> = self.parts.iter().filter(|p| std::ptr::eq(p.kind(), *kind)).collect();
            if of_kind.len() > kind.max_count {
                return Err(NetworkError::TooMany { table: kind.table, count: of_kind.len(), max: kind.max_count });
            }
            for (i, p) in of_kind.iter().enumerate() {
                for (s, v) in kind.parameters.iter().zip(p.values()) {
                    check(*s, v, kind.flat_key(i, s.key))?;
                }
            }
        }
        if self.equilibrium.is_none() && self.parts.is_empty() {
            return Err(NetworkError::Empty);
        }
        if self.strain == Strain::Small {
            if let Some(eq) = &self.equilibrium {
                if eq.energy != Energy::NeoHookean {
                    return Err(NetworkError::NoSmallStrainForm { what: "the equilibrium network's energy".into() });
                }
                if eq.mullins.is_some() {
                    return Err(NetworkError::NoSmallStrainForm { what: "the equilibrium network's softening".into() });
                }
            }
            if let Some(p) = self.parts.iter().find(|p| !p.has_small_strain_form()) {
                return Err(NetworkError::NoSmallStrainForm { what: format!("the {} part", p.kind().table) });
            }
        }
        Ok(())
    }
}

impl Network {
    /// [`PointLaw::update`] in small-strain kinematics ([`Strain::Small`]):
    /// the point's own history holds the strain at the step's start.
    fn update_small(
        &self,
        h: &Matrix3<f64>,
        dt_s: f64,
        old: &[f64],
        new: &mut [f64],
    ) -> Result<PointResponse, LawFailure> {
        let eps = hencky::symmetrize(h);
        let lame = hencky::unit_lame(self.poisson);
        let mut stress = Matrix3::zeros();
        let mut tangent = Tangent::zeros();
        new.copy_from_slice(old);
        if let Some(eq) = &self.equilibrium {
            if eq.energy != Energy::NeoHookean || eq.mullins.is_some() {
                return Err(LawFailure::NoSmallStrainForm { law: "equilibrium" });
            }
            stress += hencky::hooke(eq.e_mpa, lame, &eps);
            tangent += hencky::hooke_tangent(eq.e_mpa, lame);
        }
        let kinematics = SmallKinematics { eps, eps_n: sym_from(&old[0..6]), poisson: self.poisson, dt_s };
        let mut o = HISTORY_BASE;
        for part in &self.parts {
            let n = part.history_len();
            let (s, t) = part.respond_small(&kinematics, &old[o..o + n], &mut new[o..o + n])?;
            stress += s;
            tangent += t;
            o += n;
        }
        sym_to(&eps, &mut new[0..6]);
        if !(stress.iter().all(|x| x.is_finite()) && tangent.iter().all(|x| x.is_finite())) {
            return Err(LawFailure::NonFinite);
        }
        Ok(PointResponse { stress, tangent })
    }
}

impl PointLaw for Network {
    fn name(&self) -> &'static str {
        "network"
    }

    fn history_len(&self) -> usize {
        HISTORY_BASE + self.parts.iter().map(|p| p.history_len()).sum::<usize>()
    }

    fn initial_history(&self, h: &mut [f64]) {
        // Every tensor is kept as its deviation from the identity (`C_n^-1 - I`,
        // `A - I`) or is a stress: all zero at rest.
        h.fill(0.0);
    }

    fn small_strain_modulus(&self) -> f64 {
        self.equilibrium.map_or(0.0, |e| e.e_mpa) + self.parts.iter().map(|p| p.small_strain_modulus()).sum::<f64>()
    }

    fn update(&self, h: &Matrix3<f64>, dt_s: f64, old: &[f64], new: &mut [f64]) -> Result<PointResponse, LawFailure> {
        if self.strain == Strain::Small {
            return self.update_small(h, dt_s, old, new);
        }
        let (stress, tangent) = self.respond(h, dt_s, old, new, true)?;
        Ok(PointResponse { stress, tangent: tangent.expect("asked for") })
    }
}

impl Network {
    /// The stress of [`PointLaw::update`] alone, bit for bit, with the same
    /// history: each part's [`Part::stress`], for the evaluations whose tangent
    /// is not used (a line search's trials, a converged iterate).
    pub fn stress(
        &self,
        h: &Matrix3<f64>,
        dt_s: f64,
        old: &[f64],
        new: &mut [f64],
    ) -> Result<Matrix3<f64>, LawFailure> {
        if self.strain == Strain::Small {
            // Hooke's tangents cost no more than the stress.
            return self.update_small(h, dt_s, old, new).map(|r| r.stress);
        }
        self.respond(h, dt_s, old, new, false).map(|(p, _)| p)
    }

    /// The finite-strain update: the stress and, when `with_tangent`, its tangent.
    fn respond(
        &self,
        h: &Matrix3<f64>,
        dt_s: f64,
        old: &[f64],
        new: &mut [f64],
        with_tangent: bool,
    ) -> Result<(Matrix3<f64>, Option<Tangent>), LawFailure> {
        let f = Matrix3::identity() + h;
        let tr = h.trace();
        let j = 1.0 + tr + 0.5 * (tr * tr - (h * h).trace()) + h.determinant();
        if !(j > 0.0) {
            return Err(LawFailure::Inverted { det: j });
        }
        let f_inv = f.try_inverse().ok_or(LawFailure::Inverted { det: j })?;
        let f_inv_t = f_inv.transpose();
        let mut p = Matrix3::zeros();
        let mut tangent = with_tangent.then(Tangent::zeros);
        new.copy_from_slice(old);

        if let Some(eq) = &self.equilibrium {
            let (pe, te, w_max) = eq.respond(h, &f_inv_t, self.poisson, old[6], with_tangent);
            p += pe;
            if let (Some(t), Some(te)) = (&mut tangent, te) {
                *t += te;
            }
            new[6] = w_max;
        }
        let kinematics =
            Kinematics { h, f, f_inv, f_inv_t, c_n_inv_dev: sym_from(&old[0..6]), poisson: self.poisson, dt_s };
        let mut o = HISTORY_BASE;
        for part in &self.parts {
            let n = part.history_len();
            let (old, new) = (&old[o..o + n], &mut new[o..o + n]);
            match &mut tangent {
                Some(t) => {
                    let (pp, tp) = part.respond(&kinematics, old, new)?;
                    p += pp;
                    *t += tp;
                }
                None => p += part.stress(&kinematics, old, new)?,
            }
            o += n;
        }
        sym_to(&hencky::inverse_right_deviation(h, &f_inv), &mut new[0..6]);
        if !(p.iter().all(|x| x.is_finite()) && tangent.iter().flat_map(|t| t.iter()).all(|x| x.is_finite())) {
            return Err(LawFailure::NonFinite);
        }
        Ok((p, tangent))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::law::tangent_by_differences;

    fn full() -> Network {
        Network::new(0.35)
            .with_equilibrium(Equilibrium {
                energy: Energy::Exponential { stiffening: 1.5 },
                e_mpa: 0.02,
                mullins: Some(Mullins { r: 2.5, m_mpa: 2e-3, beta: 0.1 }),
            })
            .with(ViscousNetwork { e_mpa: 0.015, tau_s: 2.0 })
            .with(ViscousNetwork { e_mpa: 0.01, tau_s: 40.0 })
            .with(PlasticNetwork { e_mpa: 0.04, yield_mpa: 1e-3, hardening_mpa: 5e-3, kinematic_mpa: 8e-3 })
            .with(FlowNetwork { e_mpa: 0.01, stress_mpa: 3e-3, exponent: 2.5 })
            .with(BinghamNetwork { e_mpa: 0.02, yield_mpa: 5e-4, viscosity_mpa_s: 2e-3 })
            .with(Damper { c_mpa_s: 5e-3 })
            .with(DualNetwork { e_mpa: 0.012, tau_load_s: 5.0, tau_unload_s: 0.8 })
    }

    /// A history after a few steps along a non-proportional path, so that every
    /// state is away from the identity.
    fn loaded_history(net: &Network) -> (Vec<f64>, Matrix3<f64>) {
        let mut h = vec![0.0; net.history_len()];
        net.initial_history(&mut h);
        let mut next = h.clone();
        let mut f = Matrix3::identity();
        for s in 1..=4 {
            let t = s as f64 * 0.25;
            f = Matrix3::new(
                1.0 + 0.1 * t,
                0.15 * t,
                0.0,
                0.02 * t,
                1.0 - 0.3 * t,
                0.05 * t * t,
                0.0,
                0.01,
                1.0 + 0.08 * t,
            );
            net.update(&(f - Matrix3::identity()), 0.7, &h, &mut next).unwrap();
            std::mem::swap(&mut h, &mut next);
        }
        (h, f)
    }

    #[test]
    fn the_networks_tangent_matches_central_differences_with_every_part() {
        let net = full();
        let (h, f_last) = loaded_history(&net);
        // Unloading a little from the last state: the softened branch of Mullins.
        let f = f_last * 0.98 + Matrix3::new(0.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut scratch = h.clone();
        let r = net.update(&(f - Matrix3::identity()), 0.3, &h, &mut scratch).unwrap();
        let stress = |f: &Matrix3<f64>| {
            let mut s = h.clone();
            net.update(&(f - Matrix3::identity()), 0.3, &h, &mut s).unwrap().stress
        };
        let fd = tangent_by_differences(&f, 1e-6, &stress);
        let err = (r.tangent - fd).amax() / r.tangent.amax();
        assert!(err < 1e-6, "tangent error {err:.3e}");
        assert!((r.tangent - r.tangent.transpose()).amax() < 1e-12 * r.tangent.amax(), "major symmetry");
    }

    /// The stress-only path ([`Network::stress`], [`Part::stress`]) is the full
    /// update's stress and history bit for bit: for every part on its own (the
    /// plastic network yielding, with kinematic hardening), for the network
    /// with every part and softening on its unloading branch, for Ogden's
    /// energy and in small-strain kinematics. Compared by their bits: the two
    /// paths run the same operations on the stress, so no rounding separates them.
    #[test]
    fn the_stress_only_path_is_the_full_updates_stress_bit_for_bit() {
        let bits = |m: &Matrix3<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let hist_bits = |h: &[f64]| h.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let net = full();
        let (h, f_last) = loaded_history(&net);
        let f = f_last * 0.98 + Matrix3::new(0.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let d = f - Matrix3::identity();
        let f_inv = f.try_inverse().unwrap();
        let kinematics = Kinematics {
            h: &d,
            f,
            f_inv,
            f_inv_t: f_inv.transpose(),
            c_n_inv_dev: sym_from(&h[0..6]),
            poisson: net.poisson,
            dt_s: 0.3,
        };
        let mut o = HISTORY_BASE;
        for part in &net.parts {
            let n = part.history_len();
            let old = &h[o..o + n];
            let (mut full_new, mut stress_new) = (old.to_vec(), old.to_vec());
            let (p, _) = part.respond(&kinematics, old, &mut full_new).unwrap();
            let s = part.stress(&kinematics, old, &mut stress_new).unwrap();
            assert_eq!(bits(&p), bits(&s), "{} stress", part.kind().table);
            assert_eq!(hist_bits(&full_new), hist_bits(&stress_new), "{} history", part.kind().table);
            o += n;
        }
        let ogden = Network::new(0.45)
            .with_equilibrium(Equilibrium {
                energy: Energy::Ogden { alpha: [5.0, -2.5, 1.3], share: [0.5, 0.3, 0.2] },
                e_mpa: 0.03,
                mullins: Some(Mullins { r: 2.0, m_mpa: 1e-3, beta: 0.1 }),
            })
            .with(Damper { c_mpa_s: 5e-3 });
        let small = Network::new(0.3)
            .with_strain(Strain::Small)
            .with_equilibrium(Equilibrium { energy: Energy::NeoHookean, e_mpa: 0.02, mullins: None })
            .with(ViscousNetwork { e_mpa: 0.015, tau_s: 2.0 })
            .with(Damper { c_mpa_s: 5e-3 });
        for net in [net, ogden, small] {
            let (h, f_last) = loaded_history(&net);
            let d = f_last * 0.98 - Matrix3::identity();
            let (mut full_new, mut stress_new) = (h.clone(), h.clone());
            let r = net.update(&d, 0.3, &h, &mut full_new).unwrap();
            let s = net.stress(&d, 0.3, &h, &mut stress_new).unwrap();
            assert_eq!(bits(&r.stress), bits(&s), "{net:?}");
            assert_eq!(hist_bits(&full_new), hist_bits(&stress_new), "{net:?}");
        }
    }

    /// Objectivity: a superposed rotation `Q F` rotates the stress, `P -> Q P`,
    /// and leaves the history (reference quantities) unchanged.
    #[test]
    fn a_superposed_rotation_rotates_the_stress() {
        let net = full();
        let (h, f) = loaded_history(&net);
        let q = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).into_inner();
        let f1 = f * 1.01;
        let (mut n1, mut n2) = (h.clone(), h.clone());
        let p = net.update(&(f1 - Matrix3::identity()), 0.5, &h, &mut n1).unwrap().stress;
        let pq = net.update(&(q * f1 - Matrix3::identity()), 0.5, &h, &mut n2).unwrap().stress;
        assert!((pq - q * p).amax() < 1e-13 * p.amax(), "{:.3e}", (pq - q * p).amax());
        for (a, b) in n1.iter().zip(&n2) {
            assert!((a - b).abs() < 1e-12 * (1.0 + a.abs()));
        }
    }

    /// A hold at a fixed deformation relaxes each viscous network's stress by
    /// `exp(-dt / tau)` exactly.
    #[test]
    fn a_hold_relaxes_each_network_exponentially() {
        let net = Network::new(0.3).with(ViscousNetwork { e_mpa: 0.02, tau_s: 3.0 });
        let f = Matrix3::new(1.1, 0.05, 0.0, 0.0, 0.6, 0.0, 0.0, 0.0, 1.2);
        let mut h = vec![0.0; net.history_len()];
        net.initial_history(&mut h);
        let mut h1 = h.clone();
        let p0 = net.update(&(f - Matrix3::identity()), 0.5, &h, &mut h1).unwrap().stress;
        let mut h2 = h1.clone();
        let p1 = net.update(&(f - Matrix3::identity()), 2.0, &h1, &mut h2).unwrap().stress;
        let want = p0 * (-2.0f64 / 3.0).exp();
        assert!((p1 - want).amax() < 1e-12 * p0.amax(), "{:.3e}", (p1 - want).amax());
    }

    /// Small-strain kinematics: the tangent matches central differences, the
    /// stress is symmetric, and a rigid rotation's skew part of `h` carries no
    /// stress (linearised objectivity); parts without the form are refused.
    #[test]
    fn the_small_strain_network_has_an_exact_tangent_and_refuses_finite_only_parts() {
        let net = Network::new(0.3)
            .with_strain(Strain::Small)
            .with_equilibrium(Equilibrium { energy: Energy::NeoHookean, e_mpa: 0.02, mullins: None })
            .with(ViscousNetwork { e_mpa: 0.015, tau_s: 2.0 })
            .with(Damper { c_mpa_s: 5e-3 });
        net.validate().unwrap();
        let mut h0 = vec![0.0; net.history_len()];
        net.initial_history(&mut h0);
        let mut h1 = h0.clone();
        let first = Matrix3::new(0.01, 0.02, 0.0, -0.01, -0.03, 0.005, 0.0, 0.002, 0.004);
        net.update(&first, 0.7, &h0, &mut h1).unwrap();
        let h = first * 1.5 + Matrix3::new(0.0, 0.0, 0.01, 0.0, 0.0, 0.0, -0.02, 0.0, 0.0);
        let mut scratch = h1.clone();
        let r = net.update(&h, 0.3, &h1, &mut scratch).unwrap();
        let stress = |f: &Matrix3<f64>| {
            let mut s = h1.clone();
            net.update(&(f - Matrix3::identity()), 0.3, &h1, &mut s).unwrap().stress
        };
        let fd = tangent_by_differences(&(Matrix3::identity() + h), 1e-6, &stress);
        let err = (r.tangent - fd).amax() / r.tangent.amax();
        assert!(err < 1e-6, "tangent error {err:.3e}");
        assert!((r.stress - r.stress.transpose()).amax() < 1e-15, "symmetric stress");
        let skew = Matrix3::new(0.0, 0.01, -0.02, -0.01, 0.0, 0.03, 0.02, -0.03, 0.0);
        let mut s2 = h1.clone();
        let rotated = net.update(&(h + skew), 0.3, &h1, &mut s2).unwrap().stress;
        assert!((rotated - r.stress).amax() < 1e-15 * r.stress.amax().max(1.0));
        let refused = |n: Network| n.with_strain(Strain::Small).validate().unwrap_err().to_string();
        assert_eq!(
            refused(Network::new(0.3).with(PlasticNetwork {
                e_mpa: 0.04,
                yield_mpa: 1e-3,
                hardening_mpa: 0.0,
                kinematic_mpa: 0.0,
            })),
            "the plastic part has no small-strain form (kinematics = \"small\"; it needs \"finite\")"
        );
        assert!(refused(full()).contains("the equilibrium network's energy"));
        assert_eq!(Strain::Small.name(), "small");
    }

    #[test]
    fn the_table_refuses_out_of_bounds_values() {
        let mut net = full();
        net.parts[1] = Arc::new(ViscousNetwork { e_mpa: 0.01, tau_s: -1.0 });
        assert_eq!(net.validate().unwrap_err().to_string(), "viscous[1].tau_s = -1: must lie in (0, 1000000000]");
        assert_eq!(Network::new(0.3).validate(), Err(NetworkError::Empty));
        let crowded = Network::new(0.3).with(Damper { c_mpa_s: 1.0 }).with(Damper { c_mpa_s: 2.0 });
        assert_eq!(crowded.validate(), Err(NetworkError::TooMany { table: "damper", count: 2, max: 1 }));
    }
}
