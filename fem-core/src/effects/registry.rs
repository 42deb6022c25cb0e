//! The twelve candidate effects of the gap diagnosis: ids, hook points and
//! parameter specifications (diagnosis-details.md §4.2 and §5.8).
//!
//! **Stress-valued references.** A yield stress, a threshold, a critical
//! stress or a strength only acts where the material's stress reaches it, so a
//! fixed secant reference is blind on a material whose whole stress range lies
//! below it (a slider yielding at 0.7 kPa against a 10 kPa reference never
//! yields at any point the diagnosis tries: its score is exactly zero). Such
//! parameters carry a [`StressScale`]: given the campaign's peak nominal stress
//! `sigma_peak`, their reference is a stated fraction of it (or, for an inverse
//! stress, the inverse of one), [`ParamSpec::reference_at`]; without one (no
//! measured force, a specimen whose loaded area is not known) the static
//! `reference` stands. The fractions: the slider's `sigma_y` at 0.5
//! `sigma_peak` (the top of the grid `{0, 0.25, 0.5} sigma_peak` of
//! diagnosis-details.md §4.2 for E1, so that the secant yields over the upper
//! half of the stress range), the Bingham threshold and the adhesion strength
//! at 0.25 `sigma_peak` (the plateau a hold relaxes to, the tension a release
//! pulls, both a fraction of the peak), the thinning's `1/sigma_c` at
//! `1/sigma_peak` (the viscosity halves at the peak). On the blind check's gel
//! (`sigma_peak` measured 12 to 18 kPa) these lie within a factor 1.7 of the
//! static references (slider 6 against 10 kPa, threshold and strength 3
//! against 2 kPa, `1/sigma_c` 83 against 100 /MPa), and the frozen blind set's
//! verdicts did not change; on the seed's material 1 (1.5 kPa) the slider's
//! is 0.74 kPa instead of 10. The slider's hardening `H` is a modulus, not a
//! stress level, and keeps its static default.

use std::fmt;

/// Where in the engine an effect acts (diagnosis-details.md §4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum HookPoint {
    /// The constitutive update of each cell (a return mapping over the series chain).
    MaterialPoint,
    /// The boundary conditions at the plates (the rigid contact tools).
    Contact,
    /// The load path between the commanded crosshead and the specimen.
    LoadPath,
    /// A body force on the specimen.
    BodyForce,
    /// What the sensors and the camera report from the engine's state.
    Observation,
    /// A trial-level change of the material parameters (time, order, temperature).
    TrialCovariate,
}

impl HookPoint {
    /// A lower-case name for reports.
    pub fn as_str(self) -> &'static str {
        match self {
            HookPoint::MaterialPoint => "material point",
            HookPoint::Contact => "contact",
            HookPoint::LoadPath => "load path",
            HookPoint::BodyForce => "body force",
            HookPoint::Observation => "observation",
            HookPoint::TrialCovariate => "trial covariate",
        }
    }
}

/// One parameter of an effect.
///
/// A parameter's **null value** gives back the baseline exactly. Strength
/// parameters carry the effect; a **nuisance** parameter (a hardening modulus, an
/// exponent, a critical opening) only shapes it and has no influence while every
/// strength parameter of its effect is at its null: its `null` is then the default
/// it takes in a fit, not a value that switches the effect off.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// A short symbol, as in diagnosis-details.md (`b0`, `mu`, `1/k_m`).
    pub name: &'static str,
    /// The `[effects]` key of an experiment bundle, with its unit suffix.
    pub key: &'static str,
    /// The unit, spelled out (`"N/s"`, `"mm/N"`, `"1"` for none).
    pub unit: &'static str,
    /// The value that gives back the baseline (`f64::INFINITY` where the null is a
    /// limit, as a yield stress that is never reached).
    pub null: f64,
    /// Closed bounds `[low, high]` of admissible values (infinite where unbounded).
    pub bounds: [f64; 2],
    /// Whether the null lies on a bound, so that tests against it are one-sided
    /// (Self & Liang 1987).
    pub one_sided: bool,
    /// The secant reference value for the score test when the null is non-smooth
    /// or infinite (diagnosis-details.md §5.4); for smooth nulls a typical value.
    pub reference: f64,
    /// How the secant reference follows the campaign's stress level
    /// ([`StressScale`]; [`StressScale::Fixed`]: `reference` always).
    pub stress_scale: StressScale,
    /// A prior plausible range for foods in the seed's press, for scaling (§6).
    pub plausible: [f64; 2],
    /// Whether this parameter is a nuisance parameter (see above).
    pub nuisance: bool,
    /// What it is, in one line.
    pub description: &'static str,
}

/// How a parameter's secant reference follows the campaign's peak nominal
/// stress `sigma_peak` [MPa] (module docs, "Stress-valued references").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StressScale {
    /// Not a stress: the static reference always.
    Fixed,
    /// A stress: the reference is this fraction of `sigma_peak`.
    Stress(f64),
    /// An inverse stress: the reference is `1 / (fraction sigma_peak)`.
    InverseStress(f64),
}

impl ParamSpec {
    /// The secant reference on a campaign of peak nominal stress
    /// `sigma_peak_mpa` (module docs): the static `reference` when the parameter
    /// is not stress-valued or the stress level is unknown (`None`, or not a
    /// finite positive number).
    pub fn reference_at(&self, sigma_peak_mpa: Option<f64>) -> f64 {
        match (self.stress_scale, sigma_peak_mpa) {
            (StressScale::Stress(f), Some(s)) if s.is_finite() && s > 0.0 => f * s,
            (StressScale::InverseStress(f), Some(s)) if s.is_finite() && s > 0.0 => 1.0 / (f * s),
            _ => self.reference,
        }
    }

    /// Whether `value` lies within the bounds (and is not NaN).
    pub fn admits(&self, value: f64) -> bool {
        value >= self.bounds[0] && value <= self.bounds[1] && !(self.bounds[1].is_finite() && value.is_infinite())
    }
}

/// The candidate effects, in the order of diagnosis-details.md §4.2 (E1 to E12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EffectId {
    /// E1: rate-independent J2 yield with linear kinematic hardening, in series.
    PlasticSlider,
    /// E2: the dashpot c3 flows only above a threshold stress.
    BinghamDashpot,
    /// E3: c3(s) = c3_0 / (1 + (s/s_c)^m) (Cross).
    StressThinning,
    /// E4: c3 differs between loading and unloading (Wang & Hirai 2012).
    DualViscosity,
    /// E5: E_i(e) = E_i0 (1 + a e).
    StrainStiffening,
    /// E6: large-deformation kinematics, blended with the linear strain.
    FiniteStrain,
    /// E7: Coulomb friction at the plates.
    PlateFriction,
    /// E8: tension allowed at the plate up to a strength (cohesive zone).
    Adhesion,
    /// E9: a spring in series with the tool.
    MachineCompliance,
    /// E10: self-weight.
    Gravity,
    /// E11: force sensor offset and drift.
    ForceOffset,
    /// E12: moduli and viscosities drift with the trial's age.
    Ageing,
}

const INF: f64 = f64::INFINITY;

const PLASTIC_SLIDER: &[ParamSpec] = &[
    ParamSpec {
        name: "sigma_y",
        key: "plastic_yield_stress_MPa",
        unit: "MPa",
        null: INF,
        bounds: [0.0, INF],
        one_sided: true,
        reference: 0.01,
        stress_scale: StressScale::Stress(0.5),
        plausible: [1e-3, 0.1],
        nuisance: false,
        description: "uniaxial yield stress of the series slider (never reached at the null)",
    },
    ParamSpec {
        name: "H",
        key: "plastic_hardening_MPa",
        unit: "MPa",
        null: 0.01,
        bounds: [0.0, INF],
        one_sided: false,
        reference: 0.01,
        stress_scale: StressScale::Fixed,
        plausible: [1e-4, 1.0],
        nuisance: true,
        description: "linear kinematic hardening modulus of the slider",
    },
];

const BINGHAM_DASHPOT: &[ParamSpec] = &[ParamSpec {
    name: "sigma_B",
    key: "bingham_threshold_MPa",
    unit: "MPa",
    null: 0.0,
    bounds: [0.0, INF],
    one_sided: true,
    reference: 0.002,
    stress_scale: StressScale::Stress(0.25),
    plausible: [1e-4, 0.02],
    nuisance: false,
    description: "uniaxial stress below which the dashpot c3 does not flow",
}];

const STRESS_THINNING: &[ParamSpec] = &[
    ParamSpec {
        name: "1/sigma_c",
        key: "thinning_inverse_stress_1_per_MPa",
        unit: "1/MPa",
        null: 0.0,
        bounds: [0.0, INF],
        one_sided: true,
        reference: 100.0,
        stress_scale: StressScale::InverseStress(1.0),
        plausible: [1.0, 1e3],
        nuisance: false,
        description: "inverse critical stress of the Cross law c3(s) = c3_0 / (1 + (s/s_c)^m)",
    },
    ParamSpec {
        name: "m",
        key: "thinning_exponent",
        unit: "1",
        null: 1.0,
        bounds: [0.2, 4.0],
        one_sided: false,
        reference: 1.0,
        stress_scale: StressScale::Fixed,
        plausible: [0.5, 2.0],
        nuisance: true,
        description: "exponent of the Cross law (held at 1 for the score test)",
    },
];

const DUAL_VISCOSITY: &[ParamSpec] = &[ParamSpec {
    name: "psi",
    key: "dual_viscosity_log_ratio",
    unit: "1",
    null: 0.0,
    bounds: [-10.0, 10.0],
    one_sided: false,
    reference: 1.0,
    stress_scale: StressScale::Fixed,
    plausible: [-3.0, 3.0],
    nuisance: false,
    description: "ln(c3 unloading / c3 loading)",
}];

const STRAIN_STIFFENING: &[ParamSpec] = &[ParamSpec {
    name: "a",
    key: "strain_stiffening",
    unit: "1",
    null: 0.0,
    bounds: [-4.0, 50.0],
    one_sided: false,
    reference: 1.0,
    stress_scale: StressScale::Fixed,
    plausible: [-2.0, 10.0],
    nuisance: false,
    description: "E_i(e) = E_i0 (1 + a e_eq): hardening (a > 0) or softening (a < 0)",
}];

const FINITE_STRAIN: &[ParamSpec] = &[ParamSpec {
    name: "lambda_g",
    key: "finite_strain",
    unit: "1",
    null: 0.0,
    bounds: [0.0, 1.0],
    one_sided: true,
    reference: 1.0,
    stress_scale: StressScale::Fixed,
    plausible: [1.0, 1.0],
    nuisance: false,
    description: "blend of the Green-Lagrange strain into the linear one (1 = full finite strain)",
}];

const PLATE_FRICTION: &[ParamSpec] = &[ParamSpec {
    name: "mu",
    key: "plate_friction",
    unit: "1",
    null: 0.0,
    bounds: [0.0, 10.0],
    one_sided: true,
    reference: 0.3,
    stress_scale: StressScale::Fixed,
    plausible: [0.05, 1.0],
    nuisance: false,
    description: "Coulomb coefficient at the plates (0 = frictionless)",
}];

const ADHESION: &[ParamSpec] = &[
    ParamSpec {
        name: "sigma_a",
        key: "adhesion_strength_MPa",
        unit: "MPa",
        null: 0.0,
        bounds: [0.0, INF],
        one_sided: true,
        reference: 0.002,
        stress_scale: StressScale::Stress(0.25),
        plausible: [1e-4, 0.02],
        nuisance: false,
        description: "largest normal tension the plate holds",
    },
    ParamSpec {
        name: "delta_c",
        key: "adhesion_opening_mm",
        unit: "mm",
        null: 0.1,
        bounds: [0.0, INF],
        one_sided: false,
        reference: 0.1,
        stress_scale: StressScale::Fixed,
        plausible: [0.01, 1.0],
        nuisance: true,
        description: "opening at which the cohesive traction has fallen to zero",
    },
];

const MACHINE_COMPLIANCE: &[ParamSpec] = &[ParamSpec {
    name: "1/k_m",
    key: "machine_compliance_mm_per_N",
    unit: "mm/N",
    null: 0.0,
    bounds: [0.0, INF],
    one_sided: true,
    reference: 0.01,
    stress_scale: StressScale::Fixed,
    plausible: [1e-4, 0.1],
    nuisance: false,
    description: "compliance of the frame and load cell in series with the plate (or the moving tools)",
}];

const GRAVITY: &[ParamSpec] = &[ParamSpec {
    name: "g_factor",
    key: "gravity",
    unit: "1",
    null: 0.0,
    bounds: [0.0, 1.0],
    one_sided: true,
    reference: 1.0,
    stress_scale: StressScale::Fixed,
    plausible: [1.0, 1.0],
    nuisance: false,
    description: "fraction of standard gravity acting on the specimen (its density known)",
}];

const FORCE_OFFSET: &[ParamSpec] = &[
    ParamSpec {
        name: "b0",
        key: "force_offset_N",
        unit: "N",
        null: 0.0,
        bounds: [-INF, INF],
        one_sided: false,
        reference: 0.01,
        stress_scale: StressScale::Fixed,
        plausible: [-0.1, 0.1],
        nuisance: false,
        description: "constant offset of the force sensor",
    },
    ParamSpec {
        name: "b1",
        key: "force_drift_N_per_s",
        unit: "N/s",
        null: 0.0,
        bounds: [-INF, INF],
        one_sided: false,
        reference: 1e-4,
        stress_scale: StressScale::Fixed,
        plausible: [-1e-3, 1e-3],
        nuisance: false,
        description: "linear drift of the force sensor from t = 0",
    },
];

const AGEING: &[ParamSpec] = &[
    ParamSpec {
        name: "gamma_E",
        key: "ageing_E_rate_per_h",
        unit: "1/h",
        null: 0.0,
        bounds: [-1.0, 1.0],
        one_sided: false,
        reference: 0.01,
        stress_scale: StressScale::Fixed,
        plausible: [-0.1, 0.1],
        nuisance: false,
        description: "moduli scale by exp(gamma_E age_h)",
    },
    ParamSpec {
        name: "gamma_c",
        key: "ageing_c_rate_per_h",
        unit: "1/h",
        null: 0.0,
        bounds: [-1.0, 1.0],
        one_sided: false,
        reference: 0.01,
        stress_scale: StressScale::Fixed,
        plausible: [-0.1, 0.1],
        nuisance: false,
        description: "viscosities scale by exp(gamma_c age_h)",
    },
];

impl EffectId {
    /// Every effect of the library, in the order of diagnosis-details.md §4.2.
    pub const ALL: [EffectId; 12] = [
        EffectId::PlasticSlider,
        EffectId::BinghamDashpot,
        EffectId::StressThinning,
        EffectId::DualViscosity,
        EffectId::StrainStiffening,
        EffectId::FiniteStrain,
        EffectId::PlateFriction,
        EffectId::Adhesion,
        EffectId::MachineCompliance,
        EffectId::Gravity,
        EffectId::ForceOffset,
        EffectId::Ageing,
    ];

    /// The id used in reports and on the command line (`plastic-slider`, ...).
    pub fn id(self) -> &'static str {
        match self {
            EffectId::PlasticSlider => "plastic-slider",
            EffectId::BinghamDashpot => "bingham-dashpot",
            EffectId::StressThinning => "stress-thinning",
            EffectId::DualViscosity => "dual-viscosity",
            EffectId::StrainStiffening => "strain-stiffening",
            EffectId::FiniteStrain => "finite-strain",
            EffectId::PlateFriction => "plate-friction",
            EffectId::Adhesion => "adhesion",
            EffectId::MachineCompliance => "machine-compliance",
            EffectId::Gravity => "gravity",
            EffectId::ForceOffset => "force-offset",
            EffectId::Ageing => "ageing",
        }
    }

    /// The effect of an id, if any.
    pub fn from_id(id: &str) -> Option<EffectId> {
        Self::ALL.into_iter().find(|e| e.id() == id)
    }

    /// The effect and parameter index of an `[effects]` bundle key, if any.
    pub fn from_key(key: &str) -> Option<(EffectId, usize)> {
        Self::ALL.into_iter().find_map(|e| e.params().iter().position(|p| p.key == key).map(|i| (e, i)))
    }

    /// What it models, in one line.
    pub fn description(self) -> &'static str {
        match self {
            EffectId::PlasticSlider => "rate-independent yield in series (linear kinematic hardening)",
            EffectId::BinghamDashpot => "the dashpot c3 flows only above a threshold stress",
            EffectId::StressThinning => "stress-thinning viscosity of c3 (Cross law)",
            EffectId::DualViscosity => "c3 differs between loading and unloading (Wang & Hirai 2012)",
            EffectId::StrainStiffening => "moduli grow (or fall) linearly with the equivalent strain",
            EffectId::FiniteStrain => "large-deformation kinematics (Green-Lagrange strain)",
            EffectId::PlateFriction => "Coulomb friction at the plates",
            EffectId::Adhesion => "tension allowed at the plate up to a strength",
            EffectId::MachineCompliance => "a spring in series with the tool",
            EffectId::Gravity => "self-weight body force",
            EffectId::ForceOffset => "force sensor offset and drift (an untared weight)",
            EffectId::Ageing => "moduli and viscosities drift with the trial's age",
        }
    }

    /// Where the effect acts.
    pub fn hook(self) -> HookPoint {
        match self {
            EffectId::PlasticSlider
            | EffectId::BinghamDashpot
            | EffectId::StressThinning
            | EffectId::DualViscosity
            | EffectId::StrainStiffening
            | EffectId::FiniteStrain => HookPoint::MaterialPoint,
            EffectId::PlateFriction | EffectId::Adhesion => HookPoint::Contact,
            EffectId::MachineCompliance => HookPoint::LoadPath,
            EffectId::Gravity => HookPoint::BodyForce,
            EffectId::ForceOffset => HookPoint::Observation,
            EffectId::Ageing => HookPoint::TrialCovariate,
        }
    }

    /// Its parameters, strength parameters first.
    pub fn params(self) -> &'static [ParamSpec] {
        match self {
            EffectId::PlasticSlider => PLASTIC_SLIDER,
            EffectId::BinghamDashpot => BINGHAM_DASHPOT,
            EffectId::StressThinning => STRESS_THINNING,
            EffectId::DualViscosity => DUAL_VISCOSITY,
            EffectId::StrainStiffening => STRAIN_STIFFENING,
            EffectId::FiniteStrain => FINITE_STRAIN,
            EffectId::PlateFriction => PLATE_FRICTION,
            EffectId::Adhesion => ADHESION,
            EffectId::MachineCompliance => MACHINE_COMPLIANCE,
            EffectId::Gravity => GRAVITY,
            EffectId::ForceOffset => FORCE_OFFSET,
            EffectId::Ageing => AGEING,
        }
    }

    /// The null values of its parameters.
    pub fn null_values(self) -> Vec<f64> {
        self.params().iter().map(|p| p.null).collect()
    }

    /// Whether the engine simulates this effect. The others are in the registry
    /// (for the diagnosis to list) and refused by [`super::Effects::set`].
    pub fn implemented(self) -> bool {
        matches!(
            self,
            EffectId::PlasticSlider
                | EffectId::BinghamDashpot
                | EffectId::StressThinning
                | EffectId::DualViscosity
                | EffectId::StrainStiffening
                | EffectId::FiniteStrain
                | EffectId::PlateFriction
                | EffectId::Adhesion
                | EffectId::MachineCompliance
                | EffectId::Gravity
                | EffectId::ForceOffset
                | EffectId::Ageing
        )
    }

    /// Whether the engine's forward sensitivities carry this effect held at a fixed
    /// value (so that materials can be fitted with it in place): an observation
    /// offset and a body force do not depend on the material parameters.
    pub fn has_sensitivities(self) -> bool {
        matches!(self, EffectId::Gravity | EffectId::ForceOffset)
    }
}

impl fmt::Display for EffectId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}
