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
//! | `machine-compliance` | load path | `machine_compliance_mm_per_N` 1/k_m | the plate's displacement is `d = d_cmd - F/k_m` with `F` the plate force at the step's end, found exactly per step (below); with contact tools the tools that move (not floors) are held back together by `F/k_m` along the push axis, `F` the sum of their forces along it |
//! | `ageing` | trial covariate | `ageing_E_rate_per_h` gamma_E, `ageing_c_rate_per_h` gamma_c; covariate `age_h` tau | `E_i -> E_i exp(gamma_E tau)`, `c_i -> c_i exp(gamma_c tau)` in every material before the run (a network's parts by unit: stresses and moduli by the first, viscosities by the second, relaxation times by their ratio; [`Effects::aged_network`]) |
//! | `plate-friction` | contact | `plate_friction` mu | the frictionless constrained plate (and a frictionless floor) become rigid contact tools with Coulomb friction mu ([`crate::press::Tool::plate_above`], [`crate::press::Tool::floor_below`]); a glued floor stays glued |
//! | `adhesion` | contact | `adhesion_strength_MPa` sigma_a (null 0), `adhesion_opening_mm` delta_c (nuisance) | a rigid-linear cohesive zone in the normal law of the pressing tools that are not glued (not the floor): a node that touched holds the tool in tension down to `-sigma_a A`, softening linearly to zero at the opening `delta_c` (below); a frictionless constrained plate becomes a frictionless contact tool ([`crate::press::Tool::plate_above`]) |
//! | `plastic-slider` | material point | `plastic_yield_stress_MPa` sigma_y (null inf), `plastic_hardening_MPa` H | a slider in series with the chain, `|tau - H e_p|_C <= sigma_y`, associative flow, radial return (below) |
//! | `bingham-dashpot` | material point | `bingham_threshold_MPa` sigma_B (null 0) | the dashpot c3 flows at `<|tau|_C - sigma_B>/|tau|_C tau/c3` |
//! | `stress-thinning` | material point | `thinning_inverse_stress_1_per_MPa` 1/sigma_c (null 0), `thinning_exponent` m | the dashpot's viscosity is `c3/(1 + (|tau|_C/sigma_c)^m)` (Cross) |
//! | `dual-viscosity` | material point | `dual_viscosity_log_ratio` psi (null 0) | the dashpot's viscosity is `c3` while a cell loads or holds, `c3 exp(psi)` while it unloads (`s . de < 0` over the step) |
//! | `finite-strain` | material point | `finite_strain` b (null 0, in [0, 1]) | total Lagrangian: the chain acts on `eps + b 1/2 H^T H`, internal force `w B(u)^T S`, geometric tangent (below) |
//! | `strain-stiffening` | material point | `strain_stiffening` a (null 0, in [-4, 50]) | tangent moduli `E_i0 (1 + a e_eq)`, `e_eq = |e|_C = sqrt(e . C1 e)`: the chain acts on `psi(e) = (1 + a e_eq/2) e` (below) |
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
//! moves linearly, as every prescribed displacement does. With contact tools
//! (and `adhesion`, whose plate is a contact tool), and next to
//! a material-point effect or the Mullins damage, the step is not affine in `d`:
//! a safeguarded scalar iteration (Illinois on a bracket, `press::stepper`,
//! "Machine compliance") takes the step to the root of `delta - c F(delta)`,
//! within 1e-11 of the displacement scale; the crosshead's tools are the moving
//! tools that are not floors, lifted together along +y, and `F` the sum of the y
//! forces on them. Quasi-static integrator only (refused with the dynamic or the
//! seed's scheme, and with sensitivities); with tools, refused when none of them
//! moves (floors and fixed tools only); refused with a Coulomb floor
//! (`plate-friction` over a frictionless support, or a floor tool's friction),
//! whose contact does not settle at the push's first step once the deflection
//! lifts the plate; a Coulomb plate (a tool's friction, or `plate-friction` over
//! a glued support) runs (`fem-core/tests/compliance.rs`).
//!
//! **Sensitivities.** `force-offset` and `gravity` do not depend on the material
//! parameters, so the forward sensitivities stay exact with them held at any
//! value and `wagashi fit` fits materials with them in place. `ageing`,
//! `machine-compliance` and `plate-friction` are refused with sensitivities
//! ([`Effects::check_sensitivities`], one line naming the key) rather than giving
//! wrong Jacobians: ageing would need the chain rule through the scales inside
//! the sensitivity tracker, compliance the plate displacement's own derivative,
//! and friction needs sensitivities through contact. The material-point effects
//! (E1 to E6) are refused the same way: their tangent equation needs the
//! consistent tangent and the internal variables' derivatives (design below).
//! `wagashi fit` (`wagashi_calibrate::trial`) differences the effects without
//! sensitivities on frozen step ends instead; the contact ones (`plate-friction`,
//! `adhesion`) on adaptive runs with a larger step, because a contact step may
//! not be subdivided on a replay. `adhesion` is refused with sensitivities as
//! friction is.
//!
//! ## The material-point path (E1 to E6, built)
//!
//! **What runs.** When one of `plastic-slider`, `bingham-dashpot`,
//! `stress-thinning`, `dual-viscosity`, `strain-stiffening`, `finite-strain` is
//! active (E6 changes the kinematics instead, see its section), every cell carries an *inelastic
//! strain* `e_in` in series with the linear chain ([`crate::material::InelasticLaw`];
//! the global iteration in `press/inelastic.rs`). The chain is left exactly as the
//! baseline integrates it (its exponential histories and the BDF viscous term), but
//! it sees the strain `e - e_in`: the stepper's `State` keeps the chain's strain and
//! histories, plus `e_in` (and E4's per-cell unloading flag), so a failed step is
//! retried from the old state. Inactive (absent or at the nulls), the model has no
//! law and the linear path runs untouched, bit for bit (`tests/effects.rs`);
//! [`Effects::force_material_point_path`] runs the new path at the nulls for the
//! null tests (`tests/material_point.rs`: equal to the baseline, measured bit for bit).
//!
//! **Equivalent stress and flow: the Lamé split, not J2.** The baseline's chain acts
//! on the unit-Young stress image `tau = C1^-1 s`. The effects keep that shape: the
//! inelastic flow is directed along `tau` (for the slider, along `tau - H e_p`),
//! and its size is governed by `|tau|_C = sqrt(tau . C1 tau) = sqrt(s . C1^-1 s)`,
//! the square root of twice the unit-Young elastic energy (Beltrami's measure).
//! This departs from the J2 of diagnosis-details.md §4.2 on purpose: (1) in
//! uniaxial stress `|tau|_C = |sigma|` exactly, so the 1D laws hold as written in
//! homogeneous compression, in all four formulations (plane stress and strain,
//! axisymmetric, solid) with no plane-stress return algorithm; (2) the flow is the
//! normal of `|tau|_C` in stress space, so the law is associative and the
//! consistent tangent `g C1 T` is symmetric (a Cholesky factor serves); (3) the
//! inelastic strain has the chain's own Poisson ratio, as the baseline's dashpot
//! has, and for `nu -> 0.5` the measure becomes von Mises' and the flow isochoric.
//! At the seed's `nu` = 0.37 a hydrostatic stress contributes to `|tau|_C` too.
//!
//! **Local update.** `tau1 = g (e1 - e_in1) - q = tau_trial - g (e_in1 - e_in0)`
//! with the step factor `g` and the history part `q`. Every law is radial, so one
//! scalar equation: the slider's return `dl = (|x_trial|_C - sigma_y)/(g + H)` with
//! `x = tau - H e_p` (linear kinematic hardening with the uniaxial modulus `H`);
//! Bingham's `|tau_m|_C = |tau_m,trial|_C + k_m sigma_B` above the threshold and
//! `tau_m = tau_m,trial/(1 - k_m)` below it on the chain's mean stress over the
//! step, `tau_m = g_m (e1 - e_in1) - q_m`, `k_m = g_m dt/c3 < 1` at every step
//! (the dashpot laws add the correction `(psi - 1) tau/c3` of the flow to the
//! chain's own `c3`, `psi` the law's flow factor; Bingham's on the mean stress,
//! with which the chain's own dashpot flows over the step, so that below the
//! threshold the net flow is exactly zero: [`crate::material::StepMean`]; the
//! others by backward Euler, `k = g dt/c3`); Cross's `r (1 + k (r/sigma_c)^m) =
//! |tau_trial|_C` by safeguarded Newton; the dual law's
//! `tau1 = tau_trial/(1 + k (exp(-psi) - 1))` in unloading cells. A step with
//! the dual denominator too close to the singular value is refused locally and
//! retried shorter ([`crate::material::MAX_DASHPOT_RATIO`]).
//!
//! **Global iteration.** `g K u1 = f_body + f_hist + f_in(e_in1)`: modified Newton
//! with the step's own linear factor (no new factorization), switching to full
//! Newton with the assembled consistent tangent when an iteration reduces the
//! residual by less than half, each Newton step line-searched on the step's convex
//! potential; converged at 1e-12 of the force scale (the larger of the step's
//! own and the run's largest force so far: `press::inelastic`, "The force
//! scale"); not
//! converged in 100 iterations: [`crate::press::PressError::NotConverged`], and the
//! step is retried from its old state at a quarter of the step (three times, never
//! below the least step `1e-10` of the trial: the press stepper's "Retries"). E4's
//! flags are frozen during the iteration and re-checked at convergence (at most
//! three passes). With contact tools (and `plate-friction`, `adhesion`) every
//! solve of the iteration is a settled contact solve and the iteration stays
//! modified Newton (no consistent tangent; design in `press::inelastic`, "With
//! contact tools"). Quasi-static integrator only; with `machine-compliance` the
//! deflection's scalar iteration wraps the step (above). Refused with two
//! material-point effects at once, and a dashpot law on a chain without `c3` (an
//! elastic region). The slider's tangent is exact down to
//! `H = 1e-8 g` ([`crate::material::TANGENT_HARDENING`], a floor only so that
//! `H = 0` does not make it singular; the earlier floor of 1 % of `g` stalled the
//! steps after an instant release, where `g ~ B2/dt`). Perfect plasticity (`H = 0`) in
//! an inhomogeneous state can still fail to converge, or flow until a cell
//! inverts (small strain); both end the run with a typed error naming the step.
//! The dashpot laws need `g dt/c3` well below 1: true for chains whose `c3`
//! dominates the instantaneous viscosity `B2` (the seed's: `B2/c3` = 2e-4); a
//! chain with `c1 >> c3` takes a consistent tangent nearly every step.
//!
//! **Forces.** The reactions use the reaction functionals on the chain's strain,
//! so the step-end forces are exactly `sum rho . s1`; inside a step the chain's
//! closed form for its strain linear in time is used (an O(dt) interpolation where
//! the inelastic strain moves within the step: the slider's knee is resolved at the
//! step ends).
//!
//! **Accuracy (measured, `tests/material_point.rs`).** Slider on an elastic chain:
//! exact at any step (forces 1e-15, set 1e-12 mm). Bingham hold above the threshold:
//! exact at any step (the correction's rate is constant, so the chain's strain is
//! linear in time); where the threshold is crossed inside a step (the correction
//! acts on the step's mean stress), 1.8e-8 MPa against an RK4 reference of the
//! 1D chain at dt = 0.25 s (4.5e-6 of the threshold; backward Euler on the end
//! stress would be first order, 0.28 %); for the Cross and dual
//! laws first order in dt (orders 0.99 to 1.3; 0.1 to 0.3 % of the peak stress
//! at dt = 0.25 s). With a blocked chain much faster than the steps (`c3/E` far
//! below dt) Bingham's end stress lags the blocked chain's by about half a step,
//! which no error estimate measures (`tests/step_control.rs`, (d)). This error belongs
//! in the diagnosis's numerical-error budget (step 0). Adaptive steps control it:
//! the step control estimates the inelastic strains' local error
//! ([`crate::press::Settings::flow_rtol`]; `press::stepper`, "Step control"), so a
//! hold's steps follow the flow (measured in `tests/step_control.rs`: a 400 s
//! thinning hold within 1.5e-3 of the peak force at the default tolerances, where
//! the displacements' estimate alone left 1.0e-2).
//!
//! ## Strain stiffening (E5, built)
//!
//! **Strain measure.** `e_eq = |e|_C = sqrt(e . C1 e)`, the energy norm of the
//! cell's total (small) strain in the unit-Young metric of the formulation: the
//! strain counterpart of the stress measure `|tau|_C` of E1 to E4. In uniaxial
//! stress (homogeneous compression between frictionless plates) it is the axial
//! strain's size `|e_yy|` exactly, in all four formulations; it is symmetric in
//! tension and compression, and a hydrostatic strain counts too.
//!
//! **Law (Fung's quasi-linear viscoelasticity).** The chain acts on the stiffened
//! strain `psi(e) = (1 + a e_eq / 2) e` instead of `e`: `s(t) = C1 int G(t - t')
//! d psi(e(t'))`. `psi` is the gradient (in the `C1` metric) of the potential
//! `e_eq^2/2 + a e_eq^3/6`, so for an elastic chain the material is hyperelastic
//! with the tangent modulus `E0 (1 + a e_eq)` along the strain (and `E0 (1 + a
//! e_eq/2)` across it); in uniaxial stress `sigma = E0 (e + a e |e| / 2)` with no
//! lateral stress, and for a viscoelastic chain every modulus *and* viscosity of
//! the chain scales by the same factor, so the relaxation rates (the Lamé split's
//! shared kernel) are kept and the relaxation amplitude grows with the strain
//! level (the signature of diagnosis-details.md §4.2). On the material-point path
//! it is the inelastic strain `e_in = e - psi(e) = -(a e_eq/2) e`, a function of
//! the current strain (no history of its own): `tau1 = g psi(e1) - q`, tangent
//! `T = d psi/de = (1 + a e_eq/2) I + (a / 2 e_eq) e (C1 e)^T` (`C1 T` symmetric).
//!
//! **Bounds.** `a` in [-4, 50] (null 0, two-sided): 50 makes a cell 11 times
//! stiffer at 20 % strain; softening below -4 leaves no stiffness below 25 %. A
//! cell whose tangent factor `1 + a e_eq` falls below
//! [`crate::material::MIN_STIFFENING_FACTOR`] (0.05) is refused: the step is
//! retried shorter and then ends the run with
//! [`crate::press::PressError::NotConverged`] naming the step and the element.
//!
//! **Accuracy (measured, `tests/material_point.rs`).** Elastic chain, uniaxial
//! stress against `E0 (e + a e^2/2) A`: 4e-15 of the peak at fixed steps, 5e-13
//! adaptive (plane stress and axisymmetric, a = 8 and -2). Three-element chain
//! under a constant-rate push against the closed-form hereditary integral of
//! `psi`: second order in dt (orders 2.00; 6e-7 of the peak at dt = 0.125 s), since
//! the chain is integrated exactly for a chain strain linear in a step and `psi`
//! is quadratic in time there.
//!
//! ## Finite strain (E6, built)
//!
//! **Kinematics (total Lagrangian).** Each P1 cell's displacement gradient `H`
//! is constant; the chain acts on the blended Green-Lagrange strain
//! `E_b = eps + b 1/2 H^T H` (`b` = `finite_strain` in [0, 1], null 0, one-sided;
//! `b = 1` is Green-Lagrange, `1/2 (F^T F - I)`), with the axisymmetric hoop strain
//! `e_tt + b e_tt^2/2` (`e_tt = u_r/r`). The same chain through the same Lamé
//! split and exact history updates gives the 2nd Piola-Kirchhoff stress
//! `S = C1 (g E_b - q)` (for an elastic chain at `b = 1`: Saint Venant-Kirchhoff).
//! The internal force of node `a` is `w B_a(u)^T S` on the reference weight, with
//! `B_a(u) = dE_b/du_a` ([`crate::element::green_lagrange_block`]), and so are the
//! reactions: the functionals move with the deformation,
//! `rho(u) = sum w B_a(u)^T e_y`, exact at the step ends and interpolated linearly
//! inside a step. Snapshots' cell stresses are `S`.
//!
//! **Iteration** (`press/inelastic.rs`, `solve_finite_step`): the small-strain
//! step as predictor, then modified Newton with the step's linear factorization,
//! switching to full Newton with the tangent `sum_e w [B(u)^T g C1 B(u) + K_G(S)]`
//! (`K_G,ab = b (G_a^T S G_b) I`, plus `b hoop^2 S_tt` in `r-r`; symmetric) when an
//! iteration contracts by less than half; the tolerance, limits, typed
//! `NotConverged` and quarter-step retry of E1 to E5. No inelastic strain.
//!
//! **Signature (measured, honest).** In compression the Green-Lagrange form
//! *softens*: the nominal uniaxial stress is `(1 + b eps) E (eps + b eps^2/2)`, at
//! `b = 1` `E lambda (lambda^2 - 1)/2`, 0.855 of the small-strain force at 10 %
//! and 0.72 at 20 % (on the seed's material 0.848 and 0.707), so the push force
//! is more *concave* than the baseline's, not convex as diagnosis.md's table
//! expects (that expectation holds for Hencky or neo-Hookean forms, whose area
//! growth `1/(1 - eps)` wins). The deviation scales with the strain level and is
//! independent of lubrication, as the table says.
//!
//! **Accuracy (measured, `tests/material_point.rs`).** Elastic chain, uniaxial
//! compression to 20 % with free lateral faces against the closed form (force and
//! the lateral stretch from `x + b x^2/2 = -nu E_yy`): 6e-13 of the peak (plane
//! stress, fixed and adaptive steps) and 2e-12 (axisymmetric), b = 1 and 0.5;
//! the lateral face to 1e-11 mm. Three-element chain at a constant rate against
//! the closed-form hereditary integral: second order in dt (orders 2.00, 2e-7 of
//! the peak at 0.125 s). Null with the path forced: equal to the baseline.
//!
//! ## Adhesion (E8, built)
//!
//! **Law.** Rigid-linear cohesive zone on each boundary node against a pressing
//! tool (diagnosis-details.md E8 with `delta_0 = 0`): in contact the node is held
//! bilaterally while its normal force pulls less than its strength `sigma_a A`;
//! past it, it opens with the traction `t = -sigma_a A (1 - delta/delta_c)`
//! (`delta` the gap), zero from `delta_c` on (`G_c = sigma_a delta_c / 2` per
//! unit area). `A` is the node's share `int N_a dA` of its boundary facets,
//! projected on the tool's normal (`sum a_f max(0, -n_f . n_tool)`): a flat plate
//! sees the top face whole and the sides not at all, and a uniform traction
//! `sigma_a` over the face is exactly the nodes' strengths (axisymmetric: the
//! shares carry the weight `2 pi r`, linear along an edge, not the tributary
//! halves the contact's reported area uses).
//!
//! **History and irreversibility.** Per pair, the largest opening `delta_max`
//! since the node last touched, committed at step ends (a failed step is retried
//! from the old state; within a step's iteration it grows with the iterates'
//! openings, so that an iteration that overshoots cannot swing between torn and
//! bonded): a node in contact at a step end is *bonded*
//! (`delta_max = 0`, full strength); an open one unloads along the secant to the
//! origin, `t = -sigma_a A (1 - delta_max/delta_c) delta/delta_max`; once
//! `delta_max >= delta_c` it is separated and carries nothing. A separated or
//! damaged node **re-adheres with full strength when it touches the tool again**
//! (a sticky food surface bonds wherever it touches; a second compression
//! re-sticks). Nodes that never touched carry nothing; a tool that lets go at
//! `release_s` drops every bond.
//!
//! **Solution** (`press/contact.rs`, inside the augmented-Lagrangian loop). A
//! bonded pair is a normal-contact pair whose multiplier may pull down to
//! `-sigma_a A`; it tears off on its *updated* multiplier, in the pass after the
//! Uzawa update (the trial `lambda - k g` would count the gap twice there and
//! make pairs near their strength tear off and touch again in turn), and it
//! starts each step moved along the normal with its tool (as friction's stuck
//! pairs): left behind by a retreating tool it would open by the tool's whole
//! increment in the first pass. The softening branch is non-convex: its
//! traction is *explicit* in the iteration (matrix block 0: the negative tangent
//! could make the step matrix indefinite for the Cholesky factor), and the step
//! ends only when no cohesive force moved in the last solve by more than 1e-10 of
//! the node's strength; the iteration then contracts at the ratio of the
//! softening stiffness `sigma_a A/delta_c` to the specimen's, and where that
//! ratio exceeds 1 (a snap-back under displacement control) the explicit
//! iteration runs on to the fully separated state, which is then the only
//! equilibrium. The secant unloading branch is implicit (its stiffness in the
//! node's block). A bond that lets go at once (a jump of the force) defeats the
//! adaptive step control, which ends with `PressError::StepTooSmall` at the
//! jump: such trials need fixed steps (`Settings::fixed_dt_s`). At the peak, tearing off and staying give the same force: the
//! rounding of the position times the penalty decides there, as at friction's
//! cone edge, and a pair keeps its status within it. A step that does not settle
//! in 400 solves ends with `PressError::ContactNotSettled` naming the step, the
//! time, the tool and the nodes, after three retries at a quarter of the step.
//! The exact elimination path of flat frictionless plates (`settle_exact`) is
//! bypassed for adhesive tools (a cohesive node is free, held by a traction).
//!
//! **Where it acts.** Every pressing tool that is not glued (glued tools hold
//! tension already) and not a floor ("top region only"): the constrained
//! frictionless plate, converted to a frictionless contact tool (a friction one
//! with `plate-friction`), or the trial's own tools. Refused on a glued plate,
//! on tools that are all glued or floors, with sensitivities, and with
//! the dynamic and the seed's integrators (contact needs the quasi-static one).
//! **Nesting caveat:** the constrained frictionless plate is bilateral until
//! `release_s`; the converted plate is unilateral. Where a plate withdraws before
//! its release faster than the specimen recovers, the baseline plate pulls on the
//! specimen (an unlimited adhesion), and `sigma_a -> 0+` gives the unilateral
//! plate, not that baseline (as `plate-friction`'s `mu -> 0+` does). At
//! `sigma_a = 0` the effect is inactive and the baseline runs bit for bit.
//!
//! **Accuracy (measured, `tests/adhesion.rs`).** Elastic block in uniaxial stress
//! pressed 0.15 mm and pulled 1.5 mm above its unloaded height (softening
//! stiffness a quarter of `EA/h`), against the spring `EA/h` in series with the
//! cohesive law: 8.5e-11 of `sigma_a A` at every step end (asserted 1e-9), the
//! peak `-sigma_a A` and the separation at `delta_c` included (plane stress,
//! converted plate and explicit tool bit for bit equal; axisymmetric 8.5e-11).
//! Pulled into the softening branch, pushed back (secant to the origin), pressed
//! again and pulled off again (re-adhered, full strength): 3.9e-11. Signature on
//! the seed's five-element material pressed 10 %, held and withdrawn 1 mm above
//! the unloaded height (sigma_a = 0.002 MPa, delta_c = 0.1 mm), against the
//! unilateral plate: a pull of -0.3995 N (strength 0.4 N), the last pull 2.7 s
//! later (43.79 s against 41.09 s), the final height 4.4e-3 mm larger. A bond
//! softer than the block (glued floor) peels from the middle, corners last.
//!
//! ## Design of the material-point path for E5 and E6, and its sensitivities
//!
//! *The design note the material-point path was built from. E1 to E6 were built
//! from it as the sections above describe; where they differ, the sections above
//! hold.*
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

pub use registry::{EffectId, HookPoint, ParamSpec, StressScale};
pub use set::{EffectError, Effects, AGE_KEY};
