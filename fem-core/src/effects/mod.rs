//! The effect library of the sim-to-real gap diagnosis (diagnosis.md,
//! diagnosis-details.md §4 and §5.8): model extensions, each with named, bounded
//! parameters and a null value that gives back the baseline exactly.
//!
//! ## Design
//!
//! [`EffectId`] is the registry: the twelve candidates with their ids
//! (`plastic-slider`, ..., `ageing`), their [`HookPoint`] (where in the engine
//! they act) and their [`ParamSpec`]s (symbol, `[effects]` bundle key with its
//! unit suffix, null value, bounds, one-sided flag, secant reference value,
//! plausible range, nuisance flag). The diagnosis iterates over the registry; the
//! engine reads [`Effects`], the values of one trial, from
//! [`crate::press::PressProblem::effects`].
//!
//! An enum with tables rather than a trait object per effect: the set is closed
//! (the blind check and the reports enumerate it), each effect acts at one fixed
//! place in the stepper, and a `match` there keeps the physics where it is
//! computed rather than behind callbacks.
//!
//! **Nesting.** An effect that is absent or whose strength parameters are all at
//! their nulls is *inactive*, and the engine then runs the baseline's code path
//! unchanged: results equal the baseline bit for bit (`fem-core/tests/effects.rs`
//! checks it for every implemented effect). Only the effects the engine
//! implements ([`EffectId::implemented`]) can be set; the others are listed but
//! refused by [`Effects::set`] with an error naming the key ("not implemented
//! yet"): no placeholder physics.
//!
//! ## The implemented effects and where they act
//!
//! | id | hook | parameters (bundle key) | engine |
//! |---|---|---|---|
//! | `force-offset` | observation | `force_offset_N` b0, `force_drift_N_per_s` b1 | the reported bottom force becomes `F + b0 + b1 t` at every time, contact or not (step records and [`crate::press::PressResult::bottom_force_at`]); the plate force is the engine's own, untouched |
//! | `gravity` | body force | `gravity` factor f in [0, 1] | body force `-f rho g e_y` (lumped, `g` = 9810 mm/s^2) from t = 0 on the specimen as placed; the bottom force is the floor's reaction and so includes `f W` (what a sensor under the specimen reads, untared); the plate force does not (a top load cell does not see the weight, except for the pull a glued plate needs to hold a sagging top) |
//! | `machine-compliance` | load path | `machine_compliance_mm_per_N` 1/k_m | the plate's displacement is `d = d_cmd - F/k_m` with `F` the plate force at the step's end, found exactly per step (below) |
//! | `ageing` | trial covariate | `ageing_E_rate_per_h` gamma_E, `ageing_c_rate_per_h` gamma_c; covariate `age_h` tau | `E_i -> E_i exp(gamma_E tau)`, `c_i -> c_i exp(gamma_c tau)` in every material before the run |
//! | `plate-friction` | contact | `plate_friction` mu | the frictionless constrained plate (and a frictionless floor) become rigid contact tools with Coulomb friction mu ([`crate::press::Tool::plate_above`], [`crate::press::Tool::floor_below`]); a glued floor stays glued |
//!
//! **Machine compliance, exactly per step.** With the strain linear in time inside
//! a quasi-static step, the step is linear in the prescribed plate displacement
//! `d`: the plate force at the step's end is `F(d) = F(d_cmd) + k (d - d_cmd)`.
//! The stepper solves the step at `d_cmd` and at `d_cmd - delta` with the same
//! factorization (two solves), reads `k` from the two plate forces, solves the
//! scalar relation `d = d_cmd - c F(d)` (`c = 1/k_m`) in closed form,
//! `d = d_cmd - c F(d_cmd) / (1 + c k)`, and takes the step at that `d` (a third
//! solve, so every state variable is the exact step's, not a combination). The
//! relation then holds at every step end to rounding; inside a step the plate
//! moves linearly, as every prescribed displacement does. Quasi-static
//! integrator and constrained plate only (refused with contact tools and with the
//! dynamic or the seed's scheme).
//!
//! **Sensitivities.** `force-offset` and `gravity` do not depend on the material
//! parameters, so the forward sensitivities stay exact with them held at any
//! value and `wagashi fit` fits materials with them in place. `ageing`,
//! `machine-compliance` and `plate-friction` are refused with sensitivities
//! ([`Effects::check_sensitivities`], one line naming the key) rather than giving
//! wrong Jacobians: ageing would need the chain rule through the scales inside
//! the sensitivity tracker, compliance the plate displacement's own derivative,
//! and friction needs sensitivities through contact.
//!
//! ## Not implemented yet
//!
//! `plastic-slider`, `bingham-dashpot`, `stress-thinning`, `dual-viscosity`,
//! `strain-stiffening` and `finite-strain` (material point: they need a local
//! return mapping over the series chain and global Newton iterations), and
//! `adhesion` (a cohesive law in the contact tools).

mod registry;
mod set;

pub use registry::{EffectId, HookPoint, ParamSpec};
pub use set::{EffectError, Effects, AGE_KEY};
