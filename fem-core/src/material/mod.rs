//! Materials: the seed's rheological chains imposed through the Lamé split.
//!
//! The seed applies its chain separately to the lambda and mu parts of the stress
//! (its eq. 4) with one Poisson ratio. Because every modulus and viscosity of one
//! material is scaled by the same factor, the relaxation rates are shared and the
//! stress is `D1(nu) : (G * e')`: the unit-Young constitutive shape `D1` applied to
//! the hereditary integral of the strain with the chain's relaxation function `G`
//! (design.md 3.2). [`Material`] carries both halves.

mod point;
mod rheology;

pub use point::{
    energy_norm, InelasticLaw, PointFailure, PointUpdate, MAX_DASHPOT_RATIO, MIN_STIFFENING_FACTOR, TANGENT_HARDENING,
};
pub use rheology::{phi1, phi1_derivative, ChainElement, MaterialError, RelaxationKernel, Rheology};

/// A material: a rheological chain and a Poisson ratio.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The chain and its Young-type parameters.
    pub rheology: Rheology,
    /// Poisson's ratio, in (-1, 0.5).
    pub poisson: f64,
}

impl Material {
    /// A validated material: positive finite moduli and viscosities, -1 < nu < 0.5.
    pub fn new(rheology: Rheology, poisson: f64) -> Result<Self, MaterialError> {
        rheology.validate()?;
        if !(poisson.is_finite() && poisson > -1.0 && poisson < 0.5) {
            return Err(MaterialError::PoissonOutOfRange { value: poisson });
        }
        Ok(Self { rheology, poisson })
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
        }
    }

    /// The relaxation function of the chain.
    pub fn relaxation(&self) -> RelaxationKernel {
        self.rheology.relaxation()
    }
}
