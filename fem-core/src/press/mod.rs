//! The seed's press: a specimen between a floor and a rigid plate.
//!
//! The plate's downward displacement `d(t)` follows piecewise-linear waypoints;
//! the top face is glued to it or slides on it without friction; the bottom face
//! is glued to, or slides on, the floor. At `release_s` the plate lets go and the
//! specimen recovers until `end_s`. Forces are reported compression positive: the
//! bottom reaction (what the seed's tactile sensor measured) and the plate force.
//!
//! Formulations: 3D tetrahedra ([`SolidPress`]), plane triangles ([`PlanePress`])
//! and axisymmetric triangles ([`AxisymmetricPress`]): the `r-y` section of a body
//! of revolution about the push axis y, whose nodes on the axis (node set `axis`)
//! hold `u_r = 0` at all times and whose reactions are full-circle forces. Markers
//! of an axisymmetric problem are located, and tracked, in the section: `(r, y)`.
//!
//! A specimen that no face or tool holds tangentially (frictionless plate and
//! floor, or only frictionless plate tools that never turn) is free to slide in
//! x (and z) and to turn about y. It is held so that its centre of mass and its
//! mean rotation about y stay where they were: a homogeneous specimen expands
//! about its centre, as a real one between frictionless plates does, on any
//! mesh. Snapshots and markers report that frame. Under a curved frictionless
//! tool (sphere, punch, surface) the node at min x (then min z) is pinned
//! instead. (The model module's docs, "Free bodies", give the constraints and
//! how they are imposed.)
//!
//! Integrators ([`Integrator`]): the quasi-static implicit scheme with the exact
//! exponential history update (design.md 3.3, the default), a dynamic
//! generalized-alpha scheme (lumped mass), and the seed's own scheme (eq. 8:
//! dynamics, constraint stabilisation with psi = 2000, explicit Runge-Kutta), kept
//! as a reference.

use std::sync::atomic::AtomicBool;

mod contact;
mod fbar;
mod inelastic;
mod model;
mod network;
mod network_contact;
mod problem;
mod result;
mod seed;
mod sensitivity;
mod stepper;
mod tools;

pub use contact::{ToolSample, ToolTrack};
pub use problem::{
    AnyPress, Attachment, AxisymmetricPress, Integrator, MarkerRequest, PlanePress, PressError, PressProblem, Protocol,
    Settings, SolidPress, Volumetric,
};
pub use result::{MarkerTrack, PressResult, Progress, Snapshot, StepRecord};
pub use sensitivity::{ParameterKind, Sensitivities, SensitivityParameter};
pub use tools::{Keyframe, Tool, ToolContact, ToolShape};

/// Runs a press problem; `progress` is called after every step.
///
/// With effects ([`PressProblem::effects`], [`crate::effects`]): `ageing`,
/// `plate-friction` and `adhesion` change the problem before the run (aged
/// materials; friction or adhesive plates as contact tools; adhesion then acts in
/// the tools' normal contact law), `gravity` and `machine-compliance` act inside the
/// steps, the material-point effects (`plastic-slider`, `bingham-dashpot`,
/// `stress-thinning`, `dual-viscosity`, `strain-stiffening`) in each cell's update with a global
/// iteration per step, `finite-strain` in the kinematics of that iteration (total
/// Lagrangian), and `force-offset` on the reported bottom force afterwards.
pub fn simulate<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError>
where
    crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
{
    run_press(problem, settings, None, progress)
}

/// [`simulate`] that a caller (an interrupt handler) can stop: once `cancel`
/// is set, the run ends after the step being taken with
/// [`PressError::Cancelled`], naming that step and its end time, and returns
/// no result. The quasi-static and dynamic schemes read the flag after each
/// accepted step, and only there, so a run whose flag stays clear takes the
/// same steps as [`simulate`], bit for bit. Network materials and the seed's
/// scheme do not read it: they run to their end.
pub fn simulate_cancellable<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError>
where
    crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
{
    run_press(problem, settings, Some(cancel), progress)
}

fn run_press<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
    cancel: Option<&AtomicBool>,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError>
where
    crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
{
    problem.validate_effects()?;
    if network::applies(problem) {
        let effective = effects_applied(problem)?;
        let mut result = network::run(effective.as_ref(), settings, progress)?;
        if let Some(offset) = problem.effects.force_offset() {
            result.observe_force_offset(offset);
        }
        return Ok(result);
    }
    if settings.volumetric == Volumetric::FBar {
        return Err(PressError::BadSettings(
            "F-bar patches run with network materials only (the chain's linear path keeps its own cells)".into(),
        ));
    }
    let effective = effects_applied(problem)?;
    let problem = effective.as_ref();
    let mut result = match settings.integrator {
        Integrator::QuasiStatic | Integrator::Dynamic => {
            stepper::run(problem, settings, &[], cancel, progress).map(|r| r.0)
        }
        Integrator::Seed if !problem.tools.is_empty() => {
            Err(PressError::BadSettings("contact tools need the quasi-static integrator".into()))
        }
        Integrator::Seed
            if problem.effects.material_point().is_some()
                || problem.materials.iter().any(|m| m.damage_runs(problem.effects.forces_material_point_path())) =>
        {
            Err(PressError::BadSettings(
                "material-point effects (and a material's Mullins damage) need the quasi-static integrator".into(),
            ))
        }
        Integrator::Seed if problem.effects.machine_compliance_mm_per_n().is_some() => {
            Err(PressError::BadSettings("machine compliance needs the quasi-static integrator".into()))
        }
        Integrator::Seed => seed::run(problem, settings, progress),
    }?;
    if let Some(offset) = problem.effects.force_offset() {
        result.observe_force_offset(offset);
    }
    Ok(result)
}

/// The problem the engine runs for `problem`'s effects: `ageing` applied to the
/// materials and `plate-friction` as contact tools (a friction plate over the top
/// and, when the support is frictionless, a friction floor; placed as
/// `Tool::plate_above` and `Tool::floor_below` place them around the mesh's
/// bounding box, or around `[-R, R]` for an axisymmetric section), both then
/// removed from its effects; `adhesion` on the constrained plate makes it a
/// frictionless contact tool the same way (a friction one with `plate-friction`),
/// and stays in the effects for the contact model's normal law. Borrowed as it is
/// when none of them acts. (The engine validates the result when it builds its
/// model.)
fn effects_applied<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
) -> Result<std::borrow::Cow<'_, PressProblem<D, N, S>>, PressError>
where
    crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
{
    use crate::effects::{EffectId, Effects};
    let ageing = problem.effects.ageing_scales();
    let friction = problem.effects.plate_friction();
    // Adhesion on the constrained plate: the plate becomes a frictionless contact
    // tool (the effect itself stays: the contact model reads it).
    let adhesive_plate = problem.effects.adhesion().is_some() && problem.tools.is_empty();
    if ageing.is_none() && friction.is_none() && !adhesive_plate {
        return Ok(std::borrow::Cow::Borrowed(problem));
    }
    let mut p = problem.clone();
    if let Some(scales) = ageing {
        p.materials = p.materials.iter().map(|m| Effects::aged(m, scales)).collect();
        p.effects.clear(EffectId::Ageing);
    }
    if friction.is_some() || adhesive_plate {
        let (lo, hi) = p.mesh.bounding_box();
        let (mut lo3, mut hi3) = ([0.0; 3], [0.0; 3]);
        for k in 0..D {
            (lo3[k], hi3[k]) = (lo[k], hi[k]);
        }
        if p.formulation == crate::element::Formulation::Axisymmetric {
            (lo3, hi3) = ([-hi[0], lo[1], -hi[0]], [hi[0], hi[1], hi[0]]);
        }
        let contact = friction.map_or(ToolContact::Frictionless, ToolContact::Friction);
        let pr = &p.protocol;
        let mut tools = vec![Tool::plate_above("plate", lo3, hi3, &pr.waypoints, contact, pr.release_s)];
        // A friction floor with plate friction; adhesion alone leaves the support as it is.
        if friction.is_some() && pr.support == Attachment::Frictionless {
            tools.push(Tool::floor_below("floor", lo3, hi3, contact));
            p.protocol.support = Attachment::Free;
        }
        p.tools = tools;
        p.effects.clear(EffectId::PlateFriction);
    }
    Ok(std::borrow::Cow::Owned(p))
}

/// Runs a problem of any formulation.
pub fn simulate_any(
    problem: &AnyPress,
    settings: &Settings,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError> {
    match problem {
        AnyPress::Plane(p) => simulate(p, settings, progress),
        AnyPress::Solid(p) => simulate(p, settings, progress),
        AnyPress::Axisymmetric(p) => simulate(p, settings, progress),
    }
}

/// [`simulate_cancellable`] for any formulation.
pub fn simulate_any_cancellable(
    problem: &AnyPress,
    settings: &Settings,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError> {
    match problem {
        AnyPress::Plane(p) => simulate_cancellable(p, settings, cancel, progress),
        AnyPress::Solid(p) => simulate_cancellable(p, settings, cancel, progress),
        AnyPress::Axisymmetric(p) => simulate_cancellable(p, settings, cancel, progress),
    }
}

/// Runs a press problem with the quasi-static scheme and differentiates its
/// reactions and marker positions by `parameters` (forward sensitivities: at most
/// one extra solve per parameter and step with the step's own factorization, all
/// parameters in one batch; none for the rheology parameters of a one-region body).
pub fn simulate_with_sensitivities<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
    parameters: &[SensitivityParameter],
    progress: &mut dyn FnMut(Progress),
) -> Result<(PressResult, Sensitivities), PressError>
where
    crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
{
    if parameters.is_empty() {
        return Err(PressError::BadSettings("no sensitivity parameter given".into()));
    }
    problem.validate_effects()?;
    problem.effects.check_sensitivities()?;
    let (mut result, sensitivities) = stepper::run(problem, settings, parameters, None, progress)?;
    if let Some(offset) = problem.effects.force_offset() {
        result.observe_force_offset(offset);
    }
    Ok((result, sensitivities.expect("parameters were given")))
}

/// [`simulate_with_sensitivities`] for either dimension.
pub fn simulate_any_with_sensitivities(
    problem: &AnyPress,
    settings: &Settings,
    parameters: &[SensitivityParameter],
    progress: &mut dyn FnMut(Progress),
) -> Result<(PressResult, Sensitivities), PressError> {
    match problem {
        AnyPress::Plane(p) => simulate_with_sensitivities(p, settings, parameters, progress),
        AnyPress::Solid(p) => simulate_with_sensitivities(p, settings, parameters, progress),
        AnyPress::Axisymmetric(p) => simulate_with_sensitivities(p, settings, parameters, progress),
    }
}
