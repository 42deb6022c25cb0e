//! The effects a trial is simulated with: values per effect, the trial
//! covariates, and the checks and maps the engine applies.

use std::collections::BTreeMap;

use thiserror::Error;

use super::registry::EffectId;
use crate::material::network::{Equilibrium, Mullins, Network};
use crate::material::{InelasticLaw, Material, Rheology};

/// Why effect values were refused.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EffectError {
    /// The effect is listed in the library but the engine does not simulate it.
    #[error("{key}: the effect `{effect}` is in the library but not implemented in the engine yet")]
    NotImplemented { effect: EffectId, key: &'static str },
    /// A value outside its parameter's bounds (or NaN).
    #[error("{key} = {value} is outside [{low}, {high}] (effect `{effect}`)")]
    OutOfBounds { effect: EffectId, key: &'static str, value: f64, low: f64, high: f64 },
    /// Not one value per parameter.
    #[error("{key}: the effect `{effect}` has {expected} parameters, {given} values were given")]
    WrongCount { effect: EffectId, key: &'static str, expected: usize, given: usize },
    /// The effect does not fit the rest of the problem.
    #[error("{key}: {detail}")]
    Conflict { key: &'static str, detail: String },
    /// A covariate that is negative or not finite.
    #[error("{key} = {value} must be finite and >= 0")]
    BadCovariate { key: &'static str, value: f64 },
    /// Forward sensitivities do not carry the effect yet.
    #[error(
        "{key}: the effect `{effect}` has no forward sensitivities yet, so materials cannot be fitted with it \
         in place (simulate it with `wagashi press`, or leave it at its null)"
    )]
    NoSensitivities { effect: EffectId, key: &'static str },
}

impl EffectError {
    /// The `[effects]` bundle key the error is about.
    pub fn key(&self) -> &'static str {
        match self {
            EffectError::NotImplemented { key, .. }
            | EffectError::OutOfBounds { key, .. }
            | EffectError::WrongCount { key, .. }
            | EffectError::Conflict { key, .. }
            | EffectError::BadCovariate { key, .. }
            | EffectError::NoSensitivities { key, .. } => key,
        }
    }
}

/// The trial covariate of `ageing`: the specimen's age since preparation [h].
pub const AGE_KEY: &str = "age_h";

/// Effect values of one trial (default: none, the baseline).
///
/// Only implemented effects can be set ([`EffectId::implemented`]); an effect that
/// is absent, or whose strength parameters are all at their null values, is
/// *inactive*: the engine then runs exactly the baseline code path, so the results
/// equal the baseline's bit for bit.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Effects {
    values: BTreeMap<EffectId, Vec<f64>>,
    age_h: Option<f64>,
    /// Run the material-point path even with its effect at the nulls (verification).
    force_material_point: bool,
}

impl Effects {
    /// No effect: the baseline.
    pub fn none() -> Self {
        Self::default()
    }

    /// Sets every parameter of `effect`, in the order of [`EffectId::params`].
    /// Refuses an effect the engine does not implement, a wrong number of values
    /// and a value outside its bounds, naming the bundle key.
    pub fn set(&mut self, effect: EffectId, values: &[f64]) -> Result<(), EffectError> {
        let params = effect.params();
        let key = params[0].key;
        if !effect.implemented() {
            return Err(EffectError::NotImplemented { effect, key });
        }
        if values.len() != params.len() {
            return Err(EffectError::WrongCount { effect, key, expected: params.len(), given: values.len() });
        }
        for (p, &v) in params.iter().zip(values) {
            if !p.admits(v) {
                return Err(EffectError::OutOfBounds {
                    effect,
                    key: p.key,
                    value: v,
                    low: p.bounds[0],
                    high: p.bounds[1],
                });
            }
        }
        self.values.insert(effect, values.to_vec());
        Ok(())
    }

    /// Sets one parameter by its bundle key (the effect's other parameters keep
    /// their values, or take their nulls). Refuses an unknown key.
    pub fn set_key(&mut self, key: &str, value: f64) -> Result<(), EffectError> {
        let Some((effect, i)) = EffectId::from_key(key) else {
            return Err(EffectError::Conflict { key: "effects", detail: format!("unknown effect key `{key}`") });
        };
        let mut values = self.values(effect);
        values[i] = value;
        self.set(effect, &values)
    }

    /// Builder form of [`Effects::set`].
    pub fn with(mut self, effect: EffectId, values: &[f64]) -> Result<Self, EffectError> {
        self.set(effect, values)?;
        Ok(self)
    }

    /// Removes an effect (back to its null).
    pub fn clear(&mut self, effect: EffectId) {
        self.values.remove(&effect);
    }

    /// Sets the trial's age since preparation [h] (the covariate of `ageing`).
    pub fn set_age_h(&mut self, age_h: Option<f64>) -> Result<(), EffectError> {
        if let Some(v) = age_h {
            if !(v.is_finite() && v >= 0.0) {
                return Err(EffectError::BadCovariate { key: AGE_KEY, value: v });
            }
        }
        self.age_h = age_h;
        Ok(())
    }

    /// The trial's age since preparation [h], if given.
    pub fn age_h(&self) -> Option<f64> {
        self.age_h
    }

    /// The values of `effect`'s parameters (its nulls when it was not set).
    pub fn values(&self, effect: EffectId) -> Vec<f64> {
        self.values.get(&effect).cloned().unwrap_or_else(|| effect.null_values())
    }

    /// Whether `effect` was set, at any value.
    pub fn is_set(&self, effect: EffectId) -> bool {
        self.values.contains_key(&effect)
    }

    /// Whether `effect` acts: set, with a strength parameter away from its null.
    pub fn is_active(&self, effect: EffectId) -> bool {
        self.values
            .get(&effect)
            .is_some_and(|v| effect.params().iter().zip(v).any(|(p, &x)| !p.nuisance && x != p.null))
    }

    /// The active effects, in registry order.
    pub fn active(&self) -> Vec<EffectId> {
        EffectId::ALL.into_iter().filter(|&e| self.is_active(e)).collect()
    }

    /// Whether no effect acts.
    pub fn is_null(&self) -> bool {
        self.active().is_empty()
    }

    /// The gravity factor in [0, 1] (0 when inactive).
    pub fn gravity_factor(&self) -> f64 {
        if self.is_active(EffectId::Gravity) {
            self.values(EffectId::Gravity)[0]
        } else {
            0.0
        }
    }

    /// The force sensor's `[offset N, drift N/s]`, when active.
    pub fn force_offset(&self) -> Option<[f64; 2]> {
        self.is_active(EffectId::ForceOffset).then(|| {
            let v = self.values(EffectId::ForceOffset);
            [v[0], v[1]]
        })
    }

    /// The machine compliance [mm/N], when active.
    pub fn machine_compliance_mm_per_n(&self) -> Option<f64> {
        self.is_active(EffectId::MachineCompliance).then(|| self.values(EffectId::MachineCompliance)[0])
    }

    /// The Coulomb coefficient at the plates, when active.
    pub fn plate_friction(&self) -> Option<f64> {
        self.is_active(EffectId::PlateFriction).then(|| self.values(EffectId::PlateFriction)[0])
    }

    /// The adhesion at the plate `[strength sigma_a MPa, critical opening delta_c mm]`, when active.
    pub fn adhesion(&self) -> Option<[f64; 2]> {
        self.is_active(EffectId::Adhesion).then(|| {
            let v = self.values(EffectId::Adhesion);
            [v[0], v[1]]
        })
    }

    /// The ageing scales `[exp(gamma_E age), exp(gamma_c age)]` of the moduli and
    /// the viscosities, when active (an age of 0 when none is given).
    pub fn ageing_scales(&self) -> Option<[f64; 2]> {
        self.is_active(EffectId::Ageing).then(|| {
            let v = self.values(EffectId::Ageing);
            let tau = self.age_h.unwrap_or(0.0);
            [(v[0] * tau).exp(), (v[1] * tau).exp()]
        })
    }

    /// `material` aged by `scales = [modulus scale, viscosity scale]`:
    /// `E_i -> E_i s_E`, `c_i -> c_i s_c`, Poisson's ratio unchanged; its
    /// network, if any, by [`Effects::aged_network`].
    pub fn aged(material: &Material, scales: [f64; 2]) -> Material {
        let [se, sc] = scales;
        let rheology = match material.rheology {
            Rheology::Elastic { e_mpa } => Rheology::Elastic { e_mpa: e_mpa * se },
            Rheology::ThreeElement { e1_mpa, c1_mpa_s, c3_mpa_s } => {
                Rheology::ThreeElement { e1_mpa: e1_mpa * se, c1_mpa_s: c1_mpa_s * sc, c3_mpa_s: c3_mpa_s * sc }
            }
            Rheology::FourElement { e1_mpa, c1_mpa_s, e2_mpa, c3_mpa_s } => Rheology::FourElement {
                e1_mpa: e1_mpa * se,
                c1_mpa_s: c1_mpa_s * sc,
                e2_mpa: e2_mpa * se,
                c3_mpa_s: c3_mpa_s * sc,
            },
            Rheology::FiveElement { e1_mpa, e2_mpa, c1_mpa_s, c2_mpa_s, c3_mpa_s } => Rheology::FiveElement {
                e1_mpa: e1_mpa * se,
                e2_mpa: e2_mpa * se,
                c1_mpa_s: c1_mpa_s * sc,
                c2_mpa_s: c2_mpa_s * sc,
                c3_mpa_s: c3_mpa_s * sc,
            },
        };
        let network = material.network.as_ref().map(|n| Self::aged_network(n, scales));
        Material { rheology, poisson: material.poisson, damage: material.damage, network }
    }

    /// `network` aged by `scales = [s_E, s_c]`, each parameter by what it is
    /// (its unit in the part's table): a stress or modulus [MPa] by `s_E` (the
    /// springs' moduli, the equilibrium network's modulus and its softening's
    /// energy scale, yield stresses and hardening moduli); a viscosity
    /// [MPa s] by `s_c` (the damper's `c`, a Bingham network's viscosity), and a
    /// flow network's `stress_MPa`, the stress at a unit strain rate, which is a
    /// viscosity's resistance (its Newtonian relaxation time is
    /// `sigma_0 / (3 mu)`); a time [s] by `s_c / s_E` (a viscous network's
    /// `tau = viscosity / modulus`); dimensionless ones unchanged. So the
    /// seed's chain as a network ([`Network::from_chain`]) aged is the aged
    /// chain as a network, and with `s_E = s_c` every stress of the network
    /// scales by `s_E` at unchanged times.
    pub fn aged_network(network: &Network, scales: [f64; 2]) -> Network {
        let [se, sc] = scales;
        let equilibrium = network.equilibrium.map(|eq| Equilibrium {
            e_mpa: eq.e_mpa * se,
            mullins: eq.mullins.map(|m| Mullins { m_mpa: m.m_mpa * se, ..m }),
            ..eq
        });
        let parts = network
            .parts
            .iter()
            .map(|part| {
                let kind = part.kind();
                let values: Vec<f64> = kind
                    .parameters
                    .iter()
                    .zip(part.values())
                    .map(|(spec, v)| match (spec.unit, kind.table, spec.key) {
                        ("MPa", "flow", "stress_MPa") | ("MPa s", _, _) => v * sc,
                        ("MPa", _, _) => v * se,
                        ("s", _, _) => v * (sc / se),
                        _ => v,
                    })
                    .collect();
                (kind.build)(&values)
            })
            .collect();
        Network { equilibrium, parts, ..network.clone() }
    }

    /// For verification: run the material-point path (the inelastic strain, the
    /// global iteration) even when the material-point effect that is set sits at
    /// its null values, which otherwise leaves the linear path untouched. The null
    /// tests compare the two.
    pub fn force_material_point_path(&mut self, on: bool) {
        self.force_material_point = on;
    }

    /// Whether [`Effects::force_material_point_path`] is on (it also runs a
    /// material's Mullins-type damage at its null, [`crate::material::MullinsDamage`]).
    pub fn forces_material_point_path(&self) -> bool {
        self.force_material_point
    }

    /// The material-point effect (E1 to E5) the engine runs, with its values: the
    /// active one, or with [`Effects::force_material_point_path`] the one that is
    /// set. `None`: the linear path. At most one is allowed ([`Effects::validate`]).
    pub fn material_point(&self) -> Option<(EffectId, Vec<f64>)> {
        EffectId::ALL
            .into_iter()
            .filter(|&e| e.hook() == super::HookPoint::MaterialPoint)
            .find(|&e| self.is_active(e) || (self.force_material_point && self.is_set(e)))
            .map(|e| (e, self.values(e)))
    }

    /// The inelastic law of the material-point effect for a region with
    /// `rheology`, if one runs. Refuses a dashpot law (E2 to E4) on a chain without
    /// the dashpot `c3` (an elastic region), naming the key.
    pub fn inelastic_law(&self, rheology: &Rheology) -> Result<Option<InelasticLaw>, EffectError> {
        let Some((effect, v)) = self.material_point() else {
            return Ok(None);
        };
        let key = effect.params()[0].key;
        let c3 = || {
            rheology.dashpot_c3().ok_or_else(|| EffectError::Conflict {
                key,
                detail: format!(
                    "the effect `{effect}` modifies the dashpot c3, and a `{}` chain has none",
                    rheology.model_name()
                ),
            })
        };
        Ok(Some(match effect {
            EffectId::PlasticSlider => InelasticLaw::Slider { yield_mpa: v[0], hardening_mpa: v[1] },
            EffectId::BinghamDashpot => InelasticLaw::Bingham { threshold_mpa: v[0], c3_mpa_s: c3()? },
            EffectId::StressThinning => {
                InelasticLaw::Thinning { inverse_stress_per_mpa: v[0], exponent: v[1], c3_mpa_s: c3()? }
            }
            EffectId::DualViscosity => InelasticLaw::Dual { log_ratio: v[0], c3_mpa_s: c3()? },
            EffectId::StrainStiffening => InelasticLaw::Stiffening { a: v[0] },
            EffectId::FiniteStrain => InelasticLaw::FiniteStrain { blend: v[0] },
            other => {
                return Err(EffectError::NotImplemented { effect: other, key: other.params()[0].key });
            }
        }))
    }

    /// Refuses a combination with forward sensitivities that they cannot carry
    /// (the first active effect without them, in registry order).
    pub fn check_sensitivities(&self) -> Result<(), EffectError> {
        match self.active().into_iter().find(|e| !e.has_sensitivities()) {
            Some(effect) => Err(EffectError::NoSensitivities { effect, key: effect.params()[0].key }),
            None => Ok(()),
        }
    }

    /// Checks the values against each other and the covariates: every set effect
    /// is implemented and in bounds (already checked by [`Effects::set`]), and an
    /// active `ageing` has its age.
    pub fn validate(&self) -> Result<(), EffectError> {
        for (&effect, values) in &self.values {
            let mut copy = Effects::none();
            copy.set(effect, values)?;
        }
        if let Some(v) = self.age_h {
            if !(v.is_finite() && v >= 0.0) {
                return Err(EffectError::BadCovariate { key: AGE_KEY, value: v });
            }
        }
        let point: Vec<EffectId> =
            self.active().into_iter().filter(|e| e.hook() == super::HookPoint::MaterialPoint).collect();
        if point.len() > 1 {
            return Err(EffectError::Conflict {
                key: point[1].params()[0].key,
                detail: format!(
                    "the material-point effects `{}` and `{}` cannot be combined yet (one inelastic law per run)",
                    point[0], point[1]
                ),
            });
        }
        if self.is_active(EffectId::Ageing) && self.age_h.is_none() {
            return Err(EffectError::Conflict {
                key: AGE_KEY,
                detail: "the effect `ageing` needs the trial covariate age_h (hours since preparation)".into(),
            });
        }
        Ok(())
    }
}
