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
//! `strain-stiffening` and `finite-strain` (the material point, designed below),
//! and `adhesion` (a cohesive law, tension down to `-sigma_a` falling to zero at
//! the opening `delta_c`, in the contact tools' normal law).
//!
//! ## Design of the material-point path (E1 to E6)
//!
//! *A design note: none of this is code yet.*
//!
//! **Why a second path.** The baseline integrates each cell through one scalar
//! relaxation kernel on the Lamé split: the stress is a hereditary integral with
//! two exponential histories per cell, the step is linear in `u1`, and its matrix
//! is `g(dt) K`, factored once. A slider, a threshold, a stress-dependent or
//! direction-dependent viscosity, a strain-dependent modulus and finite strain
//! all break that convolution. The chain must then carry its own internal
//! variables and the step becomes non-linear. The path is entered only when one
//! of E1 to E6 is active. Inactive, the linear path runs untouched, bit for bit.
//!
//! **Internal variables per cell** (P1 simplices have one integration point):
//! the strains of the series elements, `e = e_V1 + e_V2 + e_3 + e_p` (Voigt 1,
//! Voigt 2, dashpot c3, plastic), each with `S` components; for E1 the
//! back-stress `alpha = H e_p,dev`. For E4, a loading flag per cell. All sit in
//! the stepper's `State` beside the histories, so a failed step is retried from
//! the old state (style.md).
//!
//! **Local update (return mapping).** For a trial total strain `e1` at `t1`, find
//! the common stress `s1` of the chain. Each Voigt element updates exactly for a
//! stress linear in the step (the same `exp` and `phi1` factors as the linear
//! scheme), so at the nulls the local update gives back the linear one to
//! rounding, 1e-12 in the null tests and not bit for bit. The dashpot takes
//! `e3,1 = e3,0 + dt D3(s1)^-1 s1` (backward Euler on the flow), with
//! - E2 (Bingham): flow `<|s| - sqrt(2/3) s_B> / (2 eta3)` along `s/|s|`; a
//!   Perzyna-type overstress, one scalar equation for `|s1|` in closed form;
//! - E3 (Cross): `c3(|s|)`, one scalar Newton iteration on `|s1|`;
//! - E4 (dual): `c3^L` or `c3^U = c3^L exp(psi)` by the sign of `s : de` over the
//!   step. The flag is frozen for the step's solve and re-checked; the step is
//!   repeated (at most twice) if a flag flips, so that it cannot chatter;
//! - E1 (slider): J2 radial return on the deviatoric part, yield `|s - alpha| -
//!   sqrt(2/3) s_y`. Every element of the chain shares one `nu` (the Lamé split),
//!   so the step's series compliance is isotropic and the plastic multiplier has
//!   the classical closed form `dl = f_trial / (2 mu_step + 2/3 H)` with
//!   `mu_step` the chain's effective shear stiffness for this `dt`;
//! - E5: `E_i(e_eq) = E_i0 (1 + a e_eq)`, secant moduli from `e_eq` at `t1`;
//! - E6: the strain is the blend `e + lambda_g (E_GL - e)` of the cell's constant
//!   Green-Lagrange strain (P1: `F` is constant per cell), the stress the chain's
//!   2nd Piola-Kirchhoff stress, and the nodal forces `w B_NL(u)^T S` with the
//!   geometric stiffness in the tangent.
//!
//! The cell also returns its consistent tangent `dS1/de1` (S x S, implicit
//! function theorem on the local residual `e1 - sum_i e_i(s1) = 0`).
//!
//! **Global iterations.** Residual `R(u1) = sum_e w B^T s_e(u1) - f_body` on the
//! free rows. Modified Newton reuses the step's linear factorization (`g K`, the
//! chain's tangent at the null). For the softening effects (E1, E2, E3, E4 with
//! `psi < 0`) that matrix is stiffer than the true tangent, so the iteration is
//! the initial-stiffness method and contracts monotonically. For stiffening (E5
//! with `a > 0`, E6) it can diverge: refactor with the consistent tangent when the
//! contraction ratio of two iterations exceeds 0.5. Stop at a residual of 1e-10
//! of the force scale. An inactive effect gives `R = 0` at iteration 0: no
//! iteration. Forces inside a step: the closed-form `ForceSegment` holds only for
//! the linear chain, so non-linear steps report exact step-end reactions and
//! interpolate linearly between them. That error (O(dt^2) inside steps) belongs
//! in the diagnosis's numerical-error budget (step 0).
//!
//! **Sensitivities.** The tangent equation of a non-linear step is
//! `(sum_e w B^T C_alg B) u1' = -dR/dp` with the consistent tangent `C_alg`, not
//! the baseline matrix. There are two ways to solve it: factor `C_alg` once per
//! step and reuse it for every parameter, or run PCG with the baseline factor as
//! preconditioner. The second needs few iterations where the effect is weak, and
//! weak is where the score test evaluates it. The internal variables'
//! derivatives are carried between steps as the tracker carries the histories'.
//! The partials of the local update with respect to `e1`, the state and the
//! parameters, the effect's own included, come from forward-mode dual numbers
//! (`num-dual`) through the return mapping, or by hand for the closed forms
//! above. At non-smooth nulls (`s_y = inf`, `s_B = 0`) the score uses the
//! secant to [`ParamSpec::reference`].
//!
//! **Verification plan.** Homogeneous compression between frictionless plates
//! (uniaxial stress) against the 1D closed forms: the slider's knee at `s_y` and
//! its set `<s_peak - s_y>/H`; the Bingham hold plateau `F_inf = s_B A`; the Cross
//! law's non-overlaying normalised relaxation at two strain levels; E4's release
//! with `c3^U`; E5's force `E0 (e + a e^2 / 2) A` for an elastic chain; E6's
//! homogeneous large-strain compression of a St-Venant-Kirchhoff solid
//! (`P = F S` with `S = E E_GL`, `lambda = 1 - d/H`). Nulls: 1e-12 against the
//! linear path with the non-linear path forced on.

mod registry;
mod set;

pub use registry::{EffectId, HookPoint, ParamSpec};
pub use set::{EffectError, Effects, AGE_KEY};
