//! The seed's press: a specimen between a floor and a rigid plate.
//!
//! The plate's downward displacement `d(t)` follows piecewise-linear waypoints;
//! the top face is glued to it or slides on it without friction; the bottom face
//! is glued to, or slides on, the floor. At `release_s` the plate lets go and the
//! specimen recovers until `end_s`. Forces are reported compression positive: the
//! bottom reaction (what the seed's tactile sensor measured) and the plate force.
//!
//! Integrators ([`Integrator`]): the quasi-static implicit scheme with the exact
//! exponential history update (design.md 3.3, the default), a dynamic
//! generalized-alpha scheme (lumped mass), and the seed's own scheme (eq. 8:
//! dynamics, constraint stabilisation with psi = 2000, explicit Runge-Kutta), kept
//! as a reference.

mod model;
mod problem;
mod result;
mod seed;
mod stepper;

pub use problem::{
    AnyPress, Attachment, Integrator, MarkerRequest, PlanePress, PressError, PressProblem, Protocol, Settings,
    SolidPress,
};
pub use result::{MarkerTrack, PressResult, Progress, Snapshot, StepRecord};

/// Runs a press problem; `progress` is called after every step.
pub fn simulate<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError>
where
    crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
{
    match settings.integrator {
        Integrator::QuasiStatic | Integrator::Dynamic => stepper::run(problem, settings, progress),
        Integrator::Seed => seed::run(problem, settings, progress),
    }
}

/// Runs either dimension.
pub fn simulate_any(
    problem: &AnyPress,
    settings: &Settings,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError> {
    match problem {
        AnyPress::Plane(p) => simulate(p, settings, progress),
        AnyPress::Solid(p) => simulate(p, settings, progress),
    }
}
