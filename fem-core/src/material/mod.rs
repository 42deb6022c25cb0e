//! Materials: the seed's rheological chains imposed through the Lamé split.
//!
//! The seed applies its chain separately to the lambda and mu parts of the stress
//! (its eq. 4) with one Poisson ratio. Because every modulus and viscosity of one
//! material is scaled by the same factor, the relaxation rates are shared and the
//! stress is `D1(nu) : (G * e')`: the unit-Young constitutive shape `D1` applied to
//! the hereditary integral of the strain with the chain's relaxation function `G`
//! (design.md 3.2). [`Material`] carries both halves, and optionally a
//! Mullins-type stress softening ([`MullinsDamage`]).
//!
//! ## Mullins-type damage (not an effect of the diagnosis)
//!
//! A material may carry a continuum damage law of the Simo (1987) / Miehe (1995)
//! discontinuous kind: the chain acts on the damaged strain `(1 - d(alpha)) e`
//! instead of `e`, with the damage driven by the largest equivalent strain seen so far,
//!
//! ```text
//! alpha(t) = max_{t' <= t} |e(t')|_C,   d(alpha) = d_inf (1 - exp(-alpha / strain_c)),
//! ```
//!
//! `|e|_C = sqrt(e . C1 e)` the energy norm of the total (small) strain in the
//! formulation's unit-Young metric (the strain measure of `strain-stiffening`,
//! [`crate::effects`]; in uniaxial stress it is `|e_yy|` exactly). Since the
//! undamaged elastic energy density of a spring `E` is `E |e|_C^2 / 2`, the largest
//! `|e|_C` is the largest undamaged energy re-parametrised: this is Miehe's
//! discontinuous damage driven by the undamaged energy. For an elastic chain the
//! stress is `(1 - d) C e`, Simo's effective-stress form; for a viscoelastic
//! chain the damaged strain goes through the chain's hereditary integral (Fung's
//! quasi-linear form, as `strain-stiffening`), so at a frozen damage every modulus
//! *and* viscosity acts on `(1 - d) e` and the Lamé split's shared kernel is kept.
//! In uniaxial stress: the virgin curve `sigma = E (1 - d(|e|)) e`; unloading and
//! reloading below the previous largest strain `alpha` follow the secant
//! `E (1 - d(alpha)) e` to the origin (softer than the first loading at the same
//! strain: the Mullins signature); past `alpha` the virgin curve again.
//!
//! `d_inf` in [0, [`MAX_DAMAGE`]] (null 0), `strain_c > 0`. The bound keeps the
//! virgin tangent factor `1 - d - alpha d'(alpha) >= 1 - d_inf (1 + exp(-2))`
//! (its least value, at `alpha = 2 strain_c`) above 0.09, so the softening never
//! runs out of stiffness and the step's incremental potential stays convex.
//!
//! It is a law of the engine, not one of the diagnosis's effects (no
//! [`crate::effects::EffectId`]): the blind self-check of the diagnosis generates
//! campaigns with it as an out-of-library mechanism. It runs on the material-point
//! path ([`InelasticLaw::Damage`], the global iteration of `press/inelastic.rs`)
//! with the largest equivalent strain as a per-cell history. A material with
//! `d_inf = 0` leaves the linear path untouched (bit for bit), unless
//! [`crate::effects::Effects::force_material_point_path`] is set.

pub mod law;
pub mod network;
mod point;
mod rheology;

pub use point::{
    energy_norm, InelasticLaw, PointFailure, PointUpdate, StepMean, MAX_DASHPOT_RATIO, MAX_MEAN_DASHPOT_RATIO,
    MIN_STIFFENING_FACTOR, TANGENT_HARDENING,
};
pub use rheology::{phi1, phi1_derivative, phi2, ChainElement, MaterialError, RelaxationKernel, Rheology};

/// The largest `d_inf` of [`MullinsDamage`] (module docs: the virgin tangent
/// factor stays above 0.09).
pub const MAX_DAMAGE: f64 = 0.8;

/// Mullins-type stress softening: `d(alpha) = d_inf (1 - exp(-alpha / strain_c))`
/// with `alpha` the largest equivalent strain so far (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MullinsDamage {
    /// Saturated damage, in [0, [`MAX_DAMAGE`]] (0: no damage).
    pub d_inf: f64,
    /// Characteristic equivalent strain of the damage's growth, > 0.
    pub strain_c: f64,
}

impl MullinsDamage {
    /// A validated law: `d_inf` in [0, [`MAX_DAMAGE`]], `strain_c` finite and > 0.
    pub fn new(d_inf: f64, strain_c: f64) -> Result<Self, MaterialError> {
        if !(d_inf.is_finite() && (0.0..=MAX_DAMAGE).contains(&d_inf)) {
            return Err(MaterialError::DamageOutOfRange { name: "d_inf", value: d_inf, range: "[0, 0.8]" });
        }
        if !(strain_c.is_finite() && strain_c > 0.0) {
            return Err(MaterialError::DamageOutOfRange { name: "strain_c", value: strain_c, range: "(0, inf)" });
        }
        Ok(Self { d_inf, strain_c })
    }

    /// Whether the law is at its null (`d_inf = 0`).
    pub fn is_null(&self) -> bool {
        self.d_inf == 0.0
    }

    /// The damage `d(alpha)` at the largest equivalent strain `alpha >= 0`.
    pub fn damage(&self, alpha: f64) -> f64 {
        -self.d_inf * (-alpha / self.strain_c).exp_m1()
    }

    /// `d'(alpha)`.
    pub fn damage_derivative(&self, alpha: f64) -> f64 {
        self.d_inf / self.strain_c * (-alpha / self.strain_c).exp()
    }
}

/// A material: a rheological chain, a Poisson ratio and optionally a Mullins-type damage.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The chain and its Young-type parameters.
    pub rheology: Rheology,
    /// Poisson's ratio, in (-1, 0.5).
    pub poisson: f64,
    /// Mullins-type stress softening of the chain (module docs); `None`: none.
    pub damage: Option<MullinsDamage>,
    /// The finite-strain network ([`network::Network`]) when the material is
    /// one (`model = "network"`): the press then runs it on the Newton path and
    /// `rheology` is only the elastic chain of its small-strain modulus (a scale
    /// for reports; [`Material::network`]).
    pub network: Option<network::Network>,
}

impl Material {
    /// A validated material: positive finite moduli and viscosities, -1 < nu < 0.5; no damage.
    pub fn new(rheology: Rheology, poisson: f64) -> Result<Self, MaterialError> {
        rheology.validate()?;
        if !(poisson.is_finite() && poisson > -1.0 && poisson < 0.5) {
            return Err(MaterialError::PoissonOutOfRange { value: poisson });
        }
        Ok(Self { rheology, poisson, damage: None, network: None })
    }

    /// The material with the Mullins-type damage `damage` (validated again).
    pub fn with_damage(self, damage: MullinsDamage) -> Result<Self, MaterialError> {
        let damage = MullinsDamage::new(damage.d_inf, damage.strain_c)?;
        Ok(Self { damage: Some(damage), ..self })
    }

    /// A network material; its `rheology` is the elastic chain of the network's
    /// small-strain modulus (the viscosity of a damper-only network over 1 s).
    pub fn network(network: network::Network) -> Result<Self, MaterialError> {
        network.validate().map_err(MaterialError::Network)?;
        let modulus = law::PointLaw::small_strain_modulus(&network);
        let viscosity: f64 = network.parts.iter().map(|p| p.viscosity_mpa_s()).sum();
        let e_mpa = if modulus > 0.0 {
            modulus
        } else if viscosity > 0.0 {
            viscosity
        } else {
            1.0
        };
        Ok(Self {
            rheology: Rheology::Elastic { e_mpa },
            poisson: network.poisson,
            damage: None,
            network: Some(network),
        })
    }

    /// Checks every part: the chain, the Poisson ratio and the damage law.
    pub fn validate(&self) -> Result<(), MaterialError> {
        if let Some(n) = &self.network {
            n.validate().map_err(MaterialError::Network)?;
        }
        Material::new(self.rheology, self.poisson)?;
        if let Some(d) = self.damage {
            MullinsDamage::new(d.d_inf, d.strain_c)?;
        }
        Ok(())
    }

    /// Whether the damage law runs: set, and not at its null (or `forced`).
    pub fn damage_runs(&self, forced: bool) -> bool {
        self.damage.is_some_and(|d| forced || !d.is_null())
    }

    /// The seed's material 1, force set (Table II, x_force).
    pub fn seed_mat1_force() -> Self {
        Self {
            rheology: Rheology::FiveElement {
                e1_mpa: 0.0349,
                e2_mpa: 0.0221,
                c1_mpa_s: 0.0071,
                c2_mpa_s: 0.1869,
                c3_mpa_s: 29.719,
            },
            poisson: 0.3746,
            damage: None,
            network: None,
        }
    }

    /// The relaxation function of the chain.
    pub fn relaxation(&self) -> RelaxationKernel {
        self.rheology.relaxation()
    }
}
