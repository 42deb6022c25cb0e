//! The diagnosis's candidate library: what a candidate is, its parameters with
//! their nulls, secant references, plausible ranges and nuisance flags, and how
//! it is put on a trial.
//!
//! A candidate is one of two kinds:
//!
//! - **An engine effect** ([`EffectId`], fem-core's registry): the seed chain's
//!   material-point effects and the load-path and observation effects (machine
//!   compliance, force offset, gravity, plate friction, adhesion, ageing), set
//!   on the trial's `Effects`.
//! - **A component of the network model** ([`Component`]): a part added to, or
//!   a change of, every network material of the campaign (`model = "network"`),
//!   built on the network's constitutive seam, so it composes with the
//!   baseline's parts and runs wherever the network runs (glued and
//!   frictionless plates, plates that leave and touch again, spheres, punches,
//!   surfaces). Its diagnosis metadata lives here, not in fem-core.
//!
//! **Which library a campaign gets** ([`library_for`]). A campaign whose
//! materials are all networks is diagnosed with the network's components and
//! the load-path and observation effects: the chain's material-point effects
//! act on the chain's own inelastic loop and do not run on a network. A
//! campaign with a chain material keeps the engine's effects.
//!
//! **Nulls.** Every component has a null that gives back the baseline exactly:
//! at the null (and inside the dead band of [`super::model::DEADBAND`]) the
//! material is the baseline's, the same `Network` value, so the run is the
//! baseline's bit for bit. Strength parameters carry the component; the
//! nuisance parameters (a relaxation time, a yield stress, an exponent) only
//! shape it and stay at their defaults until the strength is significant
//! (module docs of `diagnosis`, "Nuisance parameters").
//!
//! **Finite-strain kinematics** is not a component: it has no continuous
//! parameter between `kinematics = "small"` and `"finite"` in the network, so no
//! score test or nested LR exists for it. A campaign that wants it tested runs
//! on a chain baseline, whose `finite-strain` effect blends the kinematics.

use std::fmt;

use fem_core::effects::{EffectId, HookPoint, ParamSpec, StressScale};
use fem_core::material::network::{DualNetwork, Energy, FlowNetwork, Mullins, Network, PlasticNetwork, ViscousNetwork};
use fem_core::material::Material;

const INF: f64 = f64::INFINITY;

/// A component of the network model that the diagnosis can add (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Component {
    /// The neo-Hookean equilibrium energy becomes the exponential one,
    /// `W = mu/(2 b) [exp(b (I1bar - 3)) - 1]`; null `b = 0`.
    Stiffening,
    /// A parallel plastic network: a Hencky spring with J2 yield (perfectly
    /// plastic), which leaves a permanent set; null: no modulus.
    PlasticSet,
    /// Ogden-Roxburgh Mullins softening of the equilibrium network; null: `1/r = 0`.
    Mullins,
    /// Another viscous network (Hencky spring, Newtonian flow); null: no modulus.
    ExtraViscous,
    /// A parallel power-law (Norton) flow network; null: no modulus.
    PowerLawFlow,
    /// Every viscous network relaxes `e^s` times slower while its spring's
    /// energy falls than while it rises; null `s = 0`.
    LoadingUnloadingViscosity,
}

const MODULUS: ParamSpec = ParamSpec {
    name: "E",
    key: "E_MPa",
    unit: "MPa",
    null: 0.0,
    bounds: [0.0, INF],
    one_sided: true,
    reference: 0.01,
    stress_scale: StressScale::Stress(0.5),
    plausible: [1e-4, 1.0],
    nuisance: false,
    description: "Young's modulus of the added network at small strain",
};

const STIFFENING: &[ParamSpec] = &[ParamSpec {
    name: "b",
    key: "stiffening",
    unit: "1",
    null: 0.0,
    bounds: [0.0, 50.0],
    one_sided: true,
    reference: 1.0,
    stress_scale: StressScale::Fixed,
    plausible: [0.05, 10.0],
    nuisance: false,
    description: "b of the exponential equilibrium energy",
}];

const PLASTIC_SET: &[ParamSpec] = &[
    MODULUS,
    ParamSpec {
        name: "sigma_y",
        key: "yield_MPa",
        unit: "MPa",
        null: 0.005,
        bounds: [1e-9, INF],
        one_sided: false,
        reference: 0.005,
        stress_scale: StressScale::Stress(0.25),
        plausible: [1e-4, 0.1],
        nuisance: true,
        description: "yield stress of the plastic network",
    },
];

const MULLINS: &[ParamSpec] = &[
    ParamSpec {
        name: "r",
        key: "r",
        unit: "1",
        null: INF,
        bounds: [1.01, INF],
        one_sided: true,
        reference: 3.0,
        stress_scale: StressScale::Fixed,
        plausible: [1.1, 20.0],
        nuisance: false,
        description: "the softened stress is at least 1 - 1/r of the virgin",
    },
    ParamSpec {
        name: "m",
        key: "m_MPa",
        unit: "MPa",
        null: 0.001,
        bounds: [1e-9, INF],
        one_sided: false,
        reference: 0.001,
        stress_scale: StressScale::Stress(0.1),
        plausible: [1e-5, 0.1],
        nuisance: true,
        description: "energy scale of the softening",
    },
];

const EXTRA_VISCOUS: &[ParamSpec] = &[
    MODULUS,
    ParamSpec {
        name: "tau",
        key: "tau_s",
        unit: "s",
        null: 1.0,
        bounds: [1e-4, 1e5],
        one_sided: false,
        reference: 1.0,
        stress_scale: StressScale::Fixed,
        plausible: [1e-2, 1e3],
        nuisance: true,
        description: "relaxation time of the added viscous network",
    },
];

const POWER_LAW_FLOW: &[ParamSpec] = &[
    MODULUS,
    ParamSpec {
        name: "sigma_0",
        key: "stress_MPa",
        unit: "MPa",
        null: 0.005,
        bounds: [1e-9, INF],
        one_sided: false,
        reference: 0.005,
        stress_scale: StressScale::Stress(0.25),
        plausible: [1e-4, 0.1],
        nuisance: true,
        description: "the stress at which the network flows at 1/s",
    },
    ParamSpec {
        name: "n",
        key: "exponent",
        unit: "1",
        null: 3.0,
        bounds: [1.0, 20.0],
        one_sided: false,
        reference: 3.0,
        stress_scale: StressScale::Fixed,
        plausible: [1.0, 10.0],
        nuisance: true,
        description: "the flow's stress exponent",
    },
];

const LOADING_UNLOADING: &[ParamSpec] = &[ParamSpec {
    name: "s",
    key: "log_unload_ratio",
    unit: "1",
    null: 0.0,
    bounds: [-6.0, 6.0],
    one_sided: false,
    reference: 1.386_294_361_119_890_6,
    stress_scale: StressScale::Fixed,
    plausible: [-3.0, 3.0],
    nuisance: false,
    description: "ln(tau_unload / tau_load) of every viscous network",
}];

impl Component {
    /// Every component, in report order.
    pub const ALL: [Component; 6] = [
        Component::Stiffening,
        Component::PlasticSet,
        Component::Mullins,
        Component::ExtraViscous,
        Component::PowerLawFlow,
        Component::LoadingUnloadingViscosity,
    ];

    /// The id in reports and on the command line.
    pub fn id(self) -> &'static str {
        match self {
            Component::Stiffening => "exponential-stiffening",
            Component::PlasticSet => "plastic-set",
            Component::Mullins => "mullins-softening",
            Component::ExtraViscous => "extra-viscous-network",
            Component::PowerLawFlow => "power-law-flow",
            Component::LoadingUnloadingViscosity => "loading-unloading-viscosity",
        }
    }

    /// What it models, in one line.
    pub fn description(self) -> &'static str {
        match self {
            Component::Stiffening => "the equilibrium network stiffens exponentially with strain",
            Component::PlasticSet => "a parallel J2 plastic network: permanent set",
            Component::Mullins => "Ogden-Roxburgh softening of the equilibrium on reloading",
            Component::ExtraViscous => "one more viscous network (another relaxation time)",
            Component::PowerLawFlow => "a parallel network whose flow is a power of the stress",
            Component::LoadingUnloadingViscosity => "the viscous networks relax at another rate while unloading",
        }
    }

    /// Its parameters, strength parameters first.
    pub fn params(self) -> &'static [ParamSpec] {
        match self {
            Component::Stiffening => STIFFENING,
            Component::PlasticSet => PLASTIC_SET,
            Component::Mullins => MULLINS,
            Component::ExtraViscous => EXTRA_VISCOUS,
            Component::PowerLawFlow => POWER_LAW_FLOW,
            Component::LoadingUnloadingViscosity => LOADING_UNLOADING,
        }
    }

    /// Why the component cannot act on `net`, if it cannot: it needs finite
    /// kinematics, or a baseline part it changes (or does not already hold).
    pub fn not_applicable(self, net: &Network) -> Option<&'static str> {
        use fem_core::material::network::Strain;
        if net.strain != Strain::Finite && self != Component::ExtraViscous {
            return Some("the network's kinematics are small; this component needs finite kinematics");
        }
        match self {
            Component::Stiffening => match &net.equilibrium {
                None => Some("the network has no equilibrium network to stiffen"),
                Some(e) if !matches!(e.energy, Energy::NeoHookean) => {
                    Some("the equilibrium energy is not neo-Hookean: its stiffening is part of the baseline")
                }
                Some(_) => None,
            },
            Component::Mullins => match &net.equilibrium {
                None => Some("the network has no equilibrium network to soften"),
                Some(e) if e.mullins.is_some() => {
                    Some("the equilibrium network's Mullins softening is part of the baseline")
                }
                Some(_) => None,
            },
            Component::LoadingUnloadingViscosity => {
                (!net.parts.iter().any(|p| p.kind().table == "viscous")).then_some("the network has no viscous network")
            }
            Component::PlasticSet | Component::ExtraViscous | Component::PowerLawFlow => None,
        }
    }

    /// `net` with the component at `values` (in [`Component::params`] order). At
    /// the null of the strength parameter the network is returned unchanged
    /// (module docs, "Nulls").
    pub fn apply(self, net: &Network, values: &[f64]) -> Network {
        let mut out = net.clone();
        let strength = values[0];
        if strength == self.params()[0].null {
            return out;
        }
        match self {
            Component::Stiffening => {
                if let Some(e) = out.equilibrium.as_mut() {
                    e.energy = Energy::Exponential { stiffening: strength };
                }
                out
            }
            Component::PlasticSet => out.with(PlasticNetwork {
                e_mpa: strength,
                yield_mpa: values[1],
                hardening_mpa: 0.0,
                kinematic_mpa: 0.0,
            }),
            Component::Mullins => {
                if let Some(e) = out.equilibrium.as_mut() {
                    e.mullins = Some(Mullins { r: strength, m_mpa: values[1], beta: 0.0 });
                }
                out
            }
            Component::ExtraViscous => out.with(ViscousNetwork { e_mpa: strength, tau_s: values[1] }),
            Component::PowerLawFlow => {
                out.with(FlowNetwork { e_mpa: strength, stress_mpa: values[1], exponent: values[2] })
            }
            Component::LoadingUnloadingViscosity => {
                let ratio = strength.exp();
                let parts = std::mem::take(&mut out.parts);
                for p in parts {
                    if p.kind().table == "viscous" {
                        let v = p.values();
                        out = out.with(DualNetwork { e_mpa: v[0], tau_load_s: v[1], tau_unload_s: v[1] * ratio });
                    } else {
                        out.parts.push(p);
                    }
                }
                out
            }
        }
    }
}

/// A candidate of the diagnosis (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CandidateId {
    /// An effect of the engine's registry.
    Effect(EffectId),
    /// A component of the network model.
    Component(Component),
}

impl From<EffectId> for CandidateId {
    fn from(e: EffectId) -> Self {
        CandidateId::Effect(e)
    }
}

impl PartialEq<EffectId> for CandidateId {
    fn eq(&self, other: &EffectId) -> bool {
        *self == CandidateId::Effect(*other)
    }
}

impl From<Component> for CandidateId {
    fn from(c: Component) -> Self {
        CandidateId::Component(c)
    }
}

impl CandidateId {
    /// The id in reports and on the command line.
    pub fn id(self) -> &'static str {
        match self {
            CandidateId::Effect(e) => e.id(),
            CandidateId::Component(c) => c.id(),
        }
    }

    /// The candidate of an id, if any (effects first, then components).
    pub fn from_id(id: &str) -> Option<CandidateId> {
        EffectId::from_id(id)
            .map(CandidateId::Effect)
            .or_else(|| Component::ALL.into_iter().find(|c| c.id() == id).map(CandidateId::Component))
    }

    /// Every candidate id known (effects, then components).
    pub fn all() -> Vec<CandidateId> {
        EffectId::ALL.into_iter().map(CandidateId::Effect).chain(Component::ALL.map(CandidateId::Component)).collect()
    }

    /// What it models, in one line.
    pub fn description(self) -> &'static str {
        match self {
            CandidateId::Effect(e) => e.description(),
            CandidateId::Component(c) => c.description(),
        }
    }

    /// Its parameters, strength parameters first.
    pub fn params(self) -> &'static [ParamSpec] {
        match self {
            CandidateId::Effect(e) => e.params(),
            CandidateId::Component(c) => c.params(),
        }
    }

    /// The null values of its parameters.
    pub fn null_values(self) -> Vec<f64> {
        self.params().iter().map(|p| p.null).collect()
    }

    /// Where it acts: a component acts at the material points.
    pub fn hook(self) -> HookPoint {
        match self {
            CandidateId::Effect(e) => e.hook(),
            CandidateId::Component(_) => HookPoint::MaterialPoint,
        }
    }

    /// Whether the engine's forward sensitivities carry the candidate held at a
    /// fixed value (a component changes the network: never).
    pub fn has_sensitivities(self) -> bool {
        self.effect().is_some_and(EffectId::has_sensitivities)
    }

    /// The values its parameters take when not fitted: the nulls of an
    /// effect's; for a component, the strength parameters' nulls and the
    /// nuisance parameters' references on a campaign of peak nominal stress
    /// `sigma_peak_mpa` (a yield stress follows the campaign's stress level).
    pub fn defaults(self, sigma_peak_mpa: Option<f64>) -> Vec<f64> {
        match self {
            CandidateId::Effect(e) => e.null_values(),
            CandidateId::Component(c) => {
                c.params().iter().map(|p| if p.nuisance { p.reference_at(sigma_peak_mpa) } else { p.null }).collect()
            }
        }
    }

    /// The effect, if the candidate is one.
    pub fn effect(self) -> Option<EffectId> {
        match self {
            CandidateId::Effect(e) => Some(e),
            CandidateId::Component(_) => None,
        }
    }
}

impl fmt::Display for CandidateId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// Whether every material is a network (module docs, "Which library").
pub fn all_networks<'a>(materials: impl IntoIterator<Item = &'a Material>) -> bool {
    let mut any = false;
    for m in materials {
        if m.network.is_none() {
            return false;
        }
        any = true;
    }
    any
}

/// The library of a campaign (module docs, "Which library"): on networks, the
/// components and the effects that do not act at the material points; else
/// the engine's effects.
pub fn library_for(networks: bool) -> Vec<CandidateId> {
    if networks {
        Component::ALL
            .map(CandidateId::Component)
            .into_iter()
            .chain(EffectId::ALL.into_iter().filter(|e| e.hook() != HookPoint::MaterialPoint).map(CandidateId::Effect))
            .collect()
    } else {
        EffectId::ALL.into_iter().map(CandidateId::Effect).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fem_core::material::network::Equilibrium;

    fn baseline() -> Network {
        Network::new(0.45)
            .with_equilibrium(Equilibrium { energy: Energy::NeoHookean, e_mpa: 0.01, mullins: None })
            .with(ViscousNetwork { e_mpa: 0.05, tau_s: 0.1 })
            .with(ViscousNetwork { e_mpa: 0.02, tau_s: 5.0 })
    }

    #[test]
    fn ids_are_unique_and_read_back() {
        let all = CandidateId::all();
        for (i, a) in all.iter().enumerate() {
            assert_eq!(CandidateId::from_id(a.id()), Some(*a));
            assert!(all[i + 1..].iter().all(|b| b.id() != a.id()), "{a} twice");
        }
    }

    #[test]
    fn every_component_at_its_null_is_the_baseline_and_off_it_is_valid() {
        let net = baseline();
        for c in Component::ALL {
            assert_eq!(c.not_applicable(&net), None, "{c:?}");
            let null: Vec<f64> = c.params().iter().map(|p| p.null).collect();
            let same = c.apply(&net, &null);
            assert_eq!(format!("{same:?}"), format!("{net:?}"), "{c:?} at its null");
            let mut off = null.clone();
            off[0] = if c.params()[0].null.is_infinite() { 3.0 } else { c.params()[0].reference };
            let changed = c.apply(&net, &off);
            assert_ne!(format!("{changed:?}"), format!("{net:?}"), "{c:?} off its null");
            changed.validate().unwrap_or_else(|e| panic!("{c:?}: {e}"));
        }
    }

    #[test]
    fn components_that_change_a_baseline_part_say_when_it_is_missing() {
        let fluid = Network::new(0.45).with(fem_core::material::network::Damper { c_mpa_s: 1e-3 });
        assert!(Component::Stiffening.not_applicable(&fluid).is_some());
        assert!(Component::Mullins.not_applicable(&fluid).is_some());
        assert!(Component::LoadingUnloadingViscosity.not_applicable(&fluid).is_some());
        assert_eq!(Component::ExtraViscous.not_applicable(&fluid), None);
        let small = baseline().with_strain(fem_core::material::network::Strain::Small);
        assert!(Component::PlasticSet.not_applicable(&small).is_some());
        assert_eq!(Component::ExtraViscous.not_applicable(&small), None);
    }

    #[test]
    fn the_network_library_holds_the_components_and_no_chain_material_point_effect() {
        let lib = library_for(true);
        assert!(Component::ALL.iter().all(|c| lib.contains(&CandidateId::Component(*c))));
        assert!(lib.iter().all(|c| c.effect().is_none_or(|e| e.hook() != HookPoint::MaterialPoint)));
        assert!(lib.contains(&CandidateId::Effect(EffectId::MachineCompliance)));
        assert_eq!(library_for(false).len(), EffectId::ALL.len());
    }
}
