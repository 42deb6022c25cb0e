//! The Newton path: quasi-static steps of a body whose regions run a
//! finite-strain law behind the constitutive seam ([`crate::material::law`]),
//! such as the network model ([`crate::material::network`]).
//!
//! ## Kinematics
//!
//! Total Lagrangian on P1 cells: per cell the deformation gradient is
//! `F = I + sum_a u_a (x) grad N_a`, embedded in 3 x 3 (plane strain:
//! `F_zz = 1`; axisymmetric: `F_θθ = 1 + u_r / r` at the centroid, the hoop row of
//! [`crate::element`]). Writing `F - I = G u_e` with the cell's `9 x N D`
//! operator `G` (row `3 i + J`), the nodal forces are `f_e = w G^T P` and the
//! tangent `K_e = w G^T A G` (`P` the first Piola-Kirchhoff stress, `A = dP/dF`,
//! `w` the cell's weight). The seam's laws have major-symmetric tangents, so the
//! global tangent is symmetric and factored by the chain's own sparse Cholesky
//! (its symbolic factorization made once per constraint set and reused).
//!
//! A chain region in the same body (a layered specimen mixing the two) runs as
//! its network equivalent ([`crate::material::network::Network::from_chain`]):
//! the chain itself at small strain. Plane stress is refused (its `F_zz` would
//! need a local iteration); use plane strain, axisymmetric or 3D.
//!
//! ## Contact tools
//!
//! Every tool shape and contact law runs, in plane strain, axisymmetric and 3D:
//!
//! - **Flat, unrotated, frictionless plates only** (plate tools and floors):
//!   unilateral contact on the `y` dofs of the boundary nodes, by an active set.
//!   A node past a plate's face is held on it, its `y` dof cut off the matrix
//!   (the same symbolic factorization); a held node whose reaction pulls is let
//!   go; the step is solved again until the set holds ([`FlatPlate`]).
//! - **Any other tool** (sphere, punch, capsule, convex hull, triangle mesh,
//!   turned plates; frictionless, Coulomb friction or glued; each with its
//!   release): the contact iteration of the linear chain's tools
//!   ([`super::contact`]: an augmented Lagrangian on the boundary nodes with
//!   closest points and normals from [`super::tools`], stick and slip, glued
//!   anchors), each of its solves a Newton solve of the step with the
//!   contact's node penalties in the tangent ([`super::network_contact`]).
//!   The tools' samples (force, normal and tangential parts, area, nodes at
//!   kept times) are the chain's. Such a step starts from the last step's end
//!   (friction's trial tractions are measured from there), not from the
//!   velocity's extrapolation.
//!
//! ## Effects
//!
//! Of the diagnosis's effects ([`crate::effects`]) these run, applied as on the
//! chain's path: `ageing` (each network aged before the run,
//! [`crate::effects::Effects::aged_network`]), `plate-friction` (the plates
//! become Coulomb contact tools, run by the contact iteration above),
//! `gravity` (the model's body force in the residual; the floor's reaction
//! carries the weight), `force-offset` (added to the reported bottom
//! force) and `machine-compliance` on the constrained plate (the plate held
//! back by `delta = c F`, `F` the plate force at the step's end: the chain's
//! scalar iteration on `delta - c F(delta)`, Illinois on a bracket to 1e-11 of
//! the displacement scale, each evaluation a Newton solve of the whole step).
//! Refused by name: adhesion, machine compliance with contact tools
//! (`plate-friction` included), the chain's material-point effects.
//!
//! ## A step
//!
//! Newton-Raphson with the consistent tangent and a backtracking line search on
//! the residual's norm: from the previous step's end, extrapolated along its
//! velocity, with the held dofs at the step's prescribed values, until the
//! free rows' out-of-balance force is below [`TOLERANCE`] of the force scale
//! (the largest reaction so far, at least that of the current iterate). Each
//! Newton step solves the current tangent, which may be indefinite: by MINRES
//! preconditioned with the last numeric factorization while it reaches the
//! solve's tolerance within a few iterations, else by a new factorization
//! (shifted where the tangent is not positive definite, and then the
//! preconditioner of MINRES on the tangent itself), which is kept
//! ([`solve_tangent`]); the contact tools' solves factor every time (their
//! penalties change the tangent from solve to solve). Iterates whose tangent
//! is not used (line-search trials expected to converge, shortened trials) are
//! evaluated without it ([`crate::material::network::Network::stress`]) and
//! get it only if they go on. A step
//! that does not converge in [`MAX_ITERATIONS`], or whose law fails (an inverted
//! cell), is retried at a quarter of its length; below [`MIN_STEP_FRACTION`] of
//! the trial the run ends with an error naming the step, the time, the element
//! and the law.
//!
//! ## Step control
//!
//! Steps land on every kink of the protocol, on the release and on every
//! requested snapshot time. Inside a segment the local error of a step is
//! estimated by the distance between the converged displacement and its linear
//! extrapolation from the previous step (second-order predictor), relative to
//! `rtol` times the displacement scale; the next step is scaled by
//! `0.9 / sqrt(ratio)` (between 0.25 and 2), and a step with a ratio over 1 is
//! redone shorter. The first step after a kink starts at a fiftieth of its
//! segment (at most `max_dt`) and is accepted on convergence alone.

use std::cell::{OnceCell, RefCell};
use std::time::Instant;

use nalgebra::{DMatrix, DVector, Matrix3, SVector};
use rayon::prelude::*;

use super::contact::{ContactState, Settled};
use super::fbar::{self, PatchCell, Patches};
use super::model::Model;
use super::network_contact::{ContactStep, NetworkContact, Penalty};
use super::stepper::{deflected_step, emit_markers, DEFLECTION_RTOL};
use super::{
    Integrator, MarkerTrack, PressError, PressProblem, PressResult, Progress, Settings, Snapshot, StepRecord, Tool,
    ToolContact, ToolSample, ToolShape, ToolTrack, Volumetric,
};
use crate::assembly::{assemble_blocks, assemble_vector, CsrPattern};
use crate::effects::EffectId;
use crate::element::{CellGeometry, Formulation, ReferenceSimplex, Simplex};
use crate::material::law::{LawFailure, PointLaw, PointResponse, Tangent};
use crate::material::network::{Network, Strain};
use crate::solve::{Factor, ReducedSystem};

/// Converged at this out-of-balance force, relative to the force scale.
pub(crate) const TOLERANCE: f64 = 1e-10;
/// Or, after at least one Newton step, when every free dof's out-of-balance
/// force is within this many unit roundoffs of its rounding bound
/// ([`Evaluation::magnitude`]): a stiff part beside a soft one (a damper at a
/// short step in series with a soft layer) turns the displacements' last bits
/// into forces far above the soft part's reactions. Dof by dof, so a stiff
/// region's floor never hides a soft region's residual.
pub(crate) const ROUNDING_ULPS: f64 = 64.0;
/// The most Newton iterations of one step.
pub(crate) const MAX_ITERATIONS: usize = 30;
/// The shortest step, as a share of the trial's duration.
pub(crate) const MIN_STEP_FRACTION: f64 = 1e-9;
/// Halvings of the line search.
const LINE_SEARCH_HALVINGS: usize = 10;

/// Whether `problem` runs on the Newton path: some region is a network material.
pub(crate) fn applies<const D: usize, const N: usize, const S: usize>(problem: &PressProblem<D, N, S>) -> bool {
    problem.materials.iter().any(|m| m.network.is_some())
}

/// Refuses what the Newton path cannot run, naming both sides.
fn check<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
) -> Result<(), PressError> {
    let bad = |what: &str| Err(PressError::BadSettings(format!("the network model cannot run {what}")));
    if settings.integrator != Integrator::QuasiStatic {
        return bad(&format!("with the {:?} integrator (use the quasi-static one)", settings.integrator));
    }
    if let Formulation::PlaneStress { .. } = problem.formulation {
        return bad("in plane stress (use plane strain, axisymmetric or 3D)");
    }
    // `ageing` and `plate-friction` arrive applied (aged networks, friction
    // tools), `gravity` is the model's body force, `force-offset` is added to the
    // result: these run. The material-point effects are the chain's (the
    // network has its own components); adhesion has no cohesive law here.
    let runs = [
        EffectId::ForceOffset,
        EffectId::Ageing,
        EffectId::Gravity,
        EffectId::PlateFriction,
        EffectId::MachineCompliance,
    ];
    if let Some(effect) = problem.effects.active().into_iter().find(|e| !runs.contains(e)) {
        return bad(&format!("with the {effect} effect"));
    }
    if problem.effects.is_active(EffectId::MachineCompliance) && !problem.tools.is_empty() {
        return bad("with the machine-compliance effect and contact tools (`plate-friction` included)");
    }
    if problem.effects.forces_material_point_path() {
        return bad("on the chain's material-point path (the network has its own components)");
    }
    if problem.materials.iter().any(|m| m.damage.is_some()) {
        return bad("beside a chain with Mullins damage (give the network's own `[equilibrium.mullins]`)");
    }
    Ok(())
}

/// Per region: the law it runs.
fn region_laws<const D: usize, const N: usize, const S: usize>(problem: &PressProblem<D, N, S>) -> Vec<Network> {
    problem
        .materials
        .iter()
        .map(|m| m.network.clone().unwrap_or_else(|| Network::from_chain(&m.rheology, m.poisson)))
        .collect()
}

/// A flat, unrotated, frictionless plate tool: unilateral contact on the
/// `y` dofs of the boundary nodes it reaches (an active set, below).
#[derive(Debug, Clone, Copy)]
struct FlatPlate {
    /// Pressing down from above (its lower face) or a floor (its upper face).
    above: bool,
    half_height: f64,
}

impl FlatPlate {
    fn of(tool: &Tool) -> Option<Self> {
        let ToolShape::Plate { half_extents } = tool.shape else { return None };
        let flat = tool.keyframes.iter().all(|k| k.rotation_rad == [0.0; 3]);
        (flat && tool.contact == ToolContact::Frictionless)
            .then_some(Self { above: !tool.floor, half_height: half_extents[1] })
    }

    /// The height of the pressing face at `t` [mm].
    fn face_y(&self, tool: &Tool, t: f64) -> f64 {
        let y = tool.pose_at(t).0[1];
        if self.above {
            y - self.half_height
        } else {
            y + self.half_height
        }
    }
}

/// The cell operator `G` (`F - I = G u_e`), `9 x N D`, node-major dofs.
pub(super) fn deformation_operator<const D: usize, const N: usize>(g: &CellGeometry<D, N>) -> DMatrix<f64> {
    let mut op = DMatrix::zeros(9, N * D);
    for a in 0..N {
        for i in 0..D {
            for j in 0..D {
                op[(3 * i + j, a * D + i)] = g.gradients[(a, j)];
            }
        }
        // Axisymmetric: F_θθ = 1 + hoop * sum_a u_r,a (zero hoop otherwise).
        op[(8, a * D)] += g.gradients.hoop;
    }
    op
}

/// One cell's response at `u` (with F-bar patches: its stress and `Fbar` only,
/// the forces and tangent being the patch's).
struct CellResponse {
    force: DVector<f64>,
    stiffness: DMatrix<f64>,
    stress: Matrix3<f64>,
    f: Matrix3<f64>,
}

/// The whole body's response at a displacement.
struct Evaluation {
    cells: Vec<CellResponse>,
    /// With F-bar patches: each patch's tangent.
    patch_stiffness: Vec<DMatrix<f64>>,
    history: Vec<f64>,
    internal: Vec<f64>,
    /// The nodal sums of the cells' rounding bounds `sum_e |K_e| |u_e|`: an
    /// error of a unit roundoff in every displacement moves `internal` by up to
    /// this, the floor of the residual.
    magnitude: Vec<f64>,
    /// Whether the cells' (or patches') tangents were evaluated.
    with_tangent: bool,
}

/// A failed evaluation: the cell and why.
struct CellFailure {
    element: usize,
    failure: LawFailure,
}

struct Newton<'m, 'p, const D: usize, const N: usize, const S: usize> {
    model: &'m Model<'p, D, N, S>,
    laws: Vec<Network>,
    operators: Vec<DMatrix<f64>>,
    offsets: Vec<usize>,
    /// F-bar patches ([`Volumetric::FBar`]), or `None`: each cell its own `J`.
    patches: Option<Patches>,
}

impl<const D: usize, const N: usize, const S: usize> Newton<'_, '_, D, N, S>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    fn law_of(&self, e: usize) -> &Network {
        &self.laws[self.model.problem.mesh.cell_regions[e] as usize]
    }

    /// The tangent's pattern: the cells' or the patches'.
    fn pattern(&self) -> &CsrPattern {
        self.patches.as_ref().map_or(&self.model.pattern, |p| &p.pattern)
    }

    fn diagonal_positions(&self) -> &[usize] {
        self.patches.as_ref().map_or(&self.model.diagonal_positions, |p| &p.diagonal_positions)
    }

    fn node_order(&self) -> &[u32] {
        self.patches.as_ref().map_or(&self.model.node_order, |p| &p.node_order)
    }

    /// Every cell's stress and, when `with_tangent`, tangent at `u` after a
    /// step of `dt` from `history` (the stress, history and internal force are
    /// the same to the bit either way; without the tangent the laws skip it,
    /// [`Network::stress`]).
    fn evaluate(&self, u: &[f64], dt: f64, history: &[f64], with_tangent: bool) -> Result<Evaluation, CellFailure> {
        crate::material::network::count_evaluations(self.model.problem.mesh.num_cells(), with_tangent);
        if let Some(patches) = &self.patches {
            return self.evaluate_patches(patches, u, dt, history, with_tangent);
        }
        let mesh = &self.model.problem.mesh;
        let mut new_history = history.to_vec();
        let chunks = split_by_offsets(&mut new_history, &self.offsets);
        let cells = chunks
            .into_par_iter()
            .enumerate()
            .map(|(e, new)| {
                let g = &self.model.geometry[e];
                let op = &self.operators[e];
                let ue = DVector::from_iterator(
                    N * D,
                    mesh.cells[e].iter().flat_map(|&v| (0..D).map(move |k| u[v as usize * D + k])),
                );
                let grad = op * &ue;
                let h = Matrix3::from_fn(|i, j| grad[3 * i + j]);
                let f = Matrix3::identity() + h;
                let old = &history[self.offsets[e]..self.offsets[e + 1]];
                let law = self.law_of(e);
                let fail = |failure| CellFailure { element: e, failure };
                let (stress, tangent) = if with_tangent {
                    let r = law.update(&h, dt, old, new).map_err(fail)?;
                    (r.stress, Some(r.tangent))
                } else {
                    (law.stress(&h, dt, old, new).map_err(fail)?, None)
                };
                let p = DVector::from_iterator(9, (0..9).map(|r| stress[(r / 3, r % 3)]));
                let force = op.tr_mul(&p) * g.weight;
                let stiffness = match tangent {
                    Some(t) => {
                        let a = DMatrix::from_iterator(9, 9, t.iter().copied());
                        op.tr_mul(&(a * op)) * g.weight
                    }
                    None => DMatrix::zeros(0, 0),
                };
                Ok(CellResponse { force, stiffness, stress, f })
            })
            .collect::<Result<Vec<_>, CellFailure>>()?;
        let per_cell: Vec<[SVector<f64, D>; N]> = cells
            .iter()
            .map(|c| std::array::from_fn(|a| SVector::<f64, D>::from_fn(|k, _| c.force[a * D + k])))
            .collect();
        let mut internal = vec![0.0; u.len()];
        assemble_vector::<D, N>(&self.model.topology, &per_cell, &mut internal);
        // The rounding bound of each cell force, |K_e| |u_e| (|f_e| without a tangent).
        let per_cell_abs: Vec<[SVector<f64, D>; N]> = cells
            .iter()
            .enumerate()
            .map(|(e, c)| {
                let bound = |r: usize| -> f64 {
                    if c.stiffness.is_empty() {
                        return c.force[r].abs();
                    }
                    let mut s = 0.0;
                    for (b, &v) in mesh.cells[e].iter().enumerate() {
                        for k in 0..D {
                            s += c.stiffness[(r, b * D + k)].abs() * u[v as usize * D + k].abs();
                        }
                    }
                    s
                };
                std::array::from_fn(|a| SVector::<f64, D>::from_fn(|k, _| bound(a * D + k)))
            })
            .collect();
        let mut magnitude = vec![0.0; u.len()];
        assemble_vector::<D, N>(&self.model.topology, &per_cell_abs, &mut magnitude);
        Ok(Evaluation { cells, patch_stiffness: Vec::new(), history: new_history, internal, magnitude, with_tangent })
    }

    /// [`Self::evaluate`] on F-bar patches ([`fbar`]).
    fn evaluate_patches(
        &self,
        patches: &Patches,
        u: &[f64],
        dt: f64,
        history: &[f64],
        with_tangent: bool,
    ) -> Result<Evaluation, CellFailure> {
        let mesh = &self.model.problem.mesh;
        let responses = patches
            .cells
            .par_iter()
            .enumerate()
            .map(|(p, group)| {
                let cells: Vec<PatchCell<'_>> = group
                    .iter()
                    .map(|&e| {
                        let e = e as usize;
                        PatchCell {
                            op: &self.operators[e],
                            weight: self.model.geometry[e].weight,
                            local: &patches.local[e],
                            u: DVector::from_iterator(
                                N * D,
                                mesh.cells[e].iter().flat_map(|&v| (0..D).map(move |k| u[v as usize * D + k])),
                            ),
                        }
                    })
                    .collect();
                let mut new: Vec<Vec<f64>> =
                    group.iter().map(|&e| vec![0.0; self.offsets[e as usize + 1] - self.offsets[e as usize]]).collect();
                let mut update = |i: usize, h: &Matrix3<f64>| {
                    let e = group[i] as usize;
                    let old = &history[self.offsets[e]..self.offsets[e + 1]];
                    if with_tangent {
                        self.law_of(e).update(h, dt, old, &mut new[i])
                    } else {
                        // The patch reads no tangent without one.
                        let stress = self.law_of(e).stress(h, dt, old, &mut new[i])?;
                        Ok(PointResponse { stress, tangent: Tangent::zeros() })
                    }
                };
                let plane_strain = matches!(self.model.problem.formulation, Formulation::PlaneStrain { .. });
                let response =
                    fbar::respond::<D>(patches.nodes[p].len(), &cells, plane_strain, &mut update, with_tangent)
                        .map_err(|(i, failure)| CellFailure { element: group[i] as usize, failure })?;
                Ok((response, new))
            })
            .collect::<Result<Vec<_>, CellFailure>>()?;
        let mut new_history = history.to_vec();
        let mut cells: Vec<Option<CellResponse>> = (0..mesh.num_cells()).map(|_| None).collect();
        let mut forces = Vec::with_capacity(responses.len());
        let mut patch_stiffness = Vec::with_capacity(responses.len());
        for ((response, new), group) in responses.into_iter().zip(&patches.cells) {
            for (i, &e) in group.iter().enumerate() {
                let e = e as usize;
                new_history[self.offsets[e]..self.offsets[e + 1]].copy_from_slice(&new[i]);
                let (stress, f) = response.cells[i];
                cells[e] = Some(CellResponse { force: DVector::zeros(0), stiffness: DMatrix::zeros(0, 0), stress, f });
            }
            forces.push(response.force);
            patch_stiffness.push(response.stiffness);
        }
        let mut internal = vec![0.0; u.len()];
        patches.assemble_vector::<D>(&forces, &mut internal);
        let forces_abs: Vec<Vec<f64>> = forces
            .iter()
            .zip(&patch_stiffness)
            .zip(&patches.nodes)
            .map(|((f, k), nodes)| {
                if k.is_empty() {
                    return f.iter().map(|x| x.abs()).collect();
                }
                (0..f.len())
                    .map(|r| {
                        let mut s = 0.0;
                        for (b, &v) in nodes.iter().enumerate() {
                            for c in 0..D {
                                s += k[(r, b * D + c)].abs() * u[v as usize * D + c].abs();
                            }
                        }
                        s
                    })
                    .collect()
            })
            .collect();
        let mut magnitude = vec![0.0; u.len()];
        patches.assemble_vector::<D>(&forces_abs, &mut magnitude);
        let cells = cells.into_iter().map(|c| c.expect("every cell is in a patch")).collect();
        Ok(Evaluation { cells, patch_stiffness, history: new_history, internal, magnitude, with_tangent })
    }

    fn tangent(&self, eval: &Evaluation) -> Vec<f64> {
        if let Some(patches) = &self.patches {
            return patches.assemble_matrix::<D>(&eval.patch_stiffness);
        }
        let block = |e: usize, a: usize, b: usize| {
            let k = &eval.cells[e].stiffness;
            nalgebra::SMatrix::<f64, D, D>::from_fn(|r, c| k[(a * D + r, b * D + c)])
        };
        assemble_blocks::<D, _>(&self.model.topology, &self.model.pattern, &self.model.problem.mesh.cells, &block)
    }
}

/// Splits `buf` into the consecutive slices `offsets[i]..offsets[i + 1]`.
fn split_by_offsets<'a>(mut buf: &'a mut [f64], offsets: &[usize]) -> Vec<&'a mut [f64]> {
    let mut out = Vec::with_capacity(offsets.len().saturating_sub(1));
    for w in offsets.windows(2) {
        let (head, tail) = buf.split_at_mut(w[1] - w[0]);
        out.push(head);
        buf = tail;
    }
    out
}

/// The accepted state at a step's end.
#[derive(Clone)]
struct State {
    t: f64,
    u: Vec<f64>,
    history: Vec<f64>,
    /// Cauchy stress per cell, Voigt order of the formulation.
    stress: Vec<f64>,
    /// Per node: the plate tool holding it, or [`FREE`].
    holder: Vec<u8>,
}

/// A node no tool holds.
const FREE: u8 = u8::MAX;
/// The most active-set passes of one step.
const MAX_CONTACT_PASSES: usize = 30;

/// The nodes on the mesh's boundary, sorted.
fn boundary_nodes<const D: usize, const N: usize>(mesh: &crate::mesh::SimplexMesh<D, N>) -> Vec<u32>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mut nodes: Vec<u32> = mesh.boundary_facets().into_iter().flatten().collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// The `y` dofs of the nodes a tool holds.
fn cut_dofs<const D: usize>(holder: &[u8]) -> Vec<bool> {
    let mut cut = vec![false; holder.len() * D];
    for (n, &h) in holder.iter().enumerate() {
        if h != FREE {
            cut[n * D + 1] = true;
        }
    }
    cut
}

/// The active-set update after a converged pass: a boundary node that has
/// passed a plate's face is held by it; a held node whose reaction pulls on the
/// plate is let go. Returns whether anything changed.
fn update_contact<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    plates: &[FlatPlate],
    faces: &[Option<f64>],
    candidates: &[u32],
    c: &Converged,
    holder: &mut [u8],
    largest_force: f64,
) -> bool
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mesh = &model.problem.mesh;
    let gap_tolerance = 1e-10 * model.displacement_scale;
    let force_tolerance = 1e-10 * largest_force.max(f64::MIN_POSITIVE);
    let mut changed = false;
    for &node in candidates {
        let n = node as usize;
        let dof = n * D + 1;
        let y = mesh.nodes[n][1] + c.u[dof];
        match holder[n] {
            FREE => {
                for (i, (plate, face)) in plates.iter().zip(faces).enumerate() {
                    let Some(face) = *face else { continue };
                    let passed = if plate.above { y > face + gap_tolerance } else { y < face - gap_tolerance };
                    if passed {
                        holder[n] = i as u8;
                        changed = true;
                        break;
                    }
                }
            }
            h => {
                // The reaction on the body: positive y pulls it up.
                let reaction = c.internal[dof] - model.body_force[dof];
                let pulls =
                    if plates[h as usize].above { reaction > force_tolerance } else { reaction < -force_tolerance };
                if pulls {
                    holder[n] = FREE;
                    changed = true;
                }
            }
        }
    }
    changed
}

/// Tool `i`'s sample at the step's end: the force the specimen puts on it and
/// the deformed area of the boundary facets whose nodes it all holds.
fn tool_sample<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    c: &Converged,
    holder: &[u8],
    i: usize,
    t: f64,
    keep_nodes: bool,
) -> ToolSample
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mesh = &model.problem.mesh;
    let mut force_y = 0.0;
    let mut nodes = Vec::new();
    for (n, &h) in holder.iter().enumerate() {
        if h as usize == i {
            let dof = n * D + 1;
            force_y += model.body_force[dof] - c.internal[dof];
            nodes.push(n as u32);
        }
    }
    let position = |v: u32| -> [f64; 3] {
        let mut p = [0.0; 3];
        for k in 0..D {
            p[k] = mesh.nodes[v as usize][k] + c.u[v as usize * D + k];
        }
        p
    };
    let mut area = 0.0;
    for facet in mesh.boundary_facets() {
        if !facet.iter().all(|&v| holder[v as usize] as usize == i) {
            continue;
        }
        let p: Vec<[f64; 3]> = facet.iter().map(|&v| position(v)).collect();
        area += if D == 3 {
            let a = nalgebra::Vector3::from(p[1]) - nalgebra::Vector3::from(p[0]);
            let b = nalgebra::Vector3::from(p[2]) - nalgebra::Vector3::from(p[0]);
            0.5 * a.cross(&b).norm()
        } else {
            let length = ((p[1][0] - p[0][0]).powi(2) + (p[1][1] - p[0][1]).powi(2)).sqrt();
            match model.problem.formulation {
                Formulation::Axisymmetric => std::f64::consts::PI * (p[0][0] + p[1][0]) * length,
                f => f.thickness() * length,
            }
        };
    }
    ToolSample {
        t_s: t,
        force_n: [0.0, force_y, 0.0],
        normal_n: force_y.abs(),
        tangential_n: 0.0,
        area_mm2: area,
        nodes: if keep_nodes { nodes } else { Vec::new() },
    }
}

/// What a converged step gives.
pub(super) struct Converged {
    pub(super) u: Vec<f64>,
    history: Vec<f64>,
    pub(super) internal: Vec<f64>,
    stress: Vec<f64>,
    residual: f64,
    factorizations: usize,
    iterations: usize,
    /// The out-of-balance norm of every iterate, relative to the force scale.
    #[cfg_attr(not(test), allow(dead_code, reason = "read by the convergence-rate test"))]
    norms: Vec<f64>,
}

/// Why a step attempt failed (retried shorter). `Contact` is the error of the
/// contact iteration of [`super::network_contact`], naming the step, the time,
/// the tool and the nodes.
pub(super) enum StepFailure {
    Law { element: usize, failure: LawFailure },
    ContactNotSettled { tool: usize, nodes: Vec<u32> },
    NotConverged { residual: f64, element: usize },
    Singular(crate::solve::SolveError),
    Contact(PressError),
}

/// Runs a problem with network materials on the Newton path.
pub(crate) fn run<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    check(problem, settings)?;
    let model = Model::new(problem)?;
    let laws = region_laws(problem);
    let mesh = &problem.mesh;
    let operators: Vec<DMatrix<f64>> = model.geometry.iter().map(deformation_operator::<D, N>).collect();
    let mut offsets = Vec::with_capacity(mesh.num_cells() + 1);
    offsets.push(0);
    for &r in &mesh.cell_regions {
        offsets.push(offsets.last().unwrap() + laws[r as usize].history_len());
    }
    let patches = (settings.volumetric == Volumetric::FBar)
        .then(|| Patches::new(&mesh.nodes, &mesh.cells, &mesh.cell_regions, fbar::patch_size(D)));
    let newton = Newton { model: &model, laws, operators, offsets, patches };
    let mut history = vec![0.0; *newton.offsets.last().unwrap()];
    for (e, h) in split_by_offsets(&mut history, &newton.offsets).into_iter().enumerate() {
        newton.law_of(e).initial_history(h);
    }

    let protocol = &problem.protocol;
    let end = protocol.end_s;
    let mut landings: Vec<f64> = protocol.kinks();
    landings.extend(problem.snapshot_times.iter().copied().filter(|&t| t > 0.0 && t < end));
    for tool in &problem.tools {
        landings.extend(tool.kinks(end));
    }
    // Flat, unrotated, frictionless plates only: the active set below. Any other
    // tool: the contact iteration of `network_contact` around Newton's solves.
    let all_flat = problem.tools.iter().all(|t| FlatPlate::of(t).is_some());
    let plates: Vec<FlatPlate> =
        if all_flat { problem.tools.iter().filter_map(FlatPlate::of).collect() } else { Vec::new() };
    let tool_contact =
        if all_flat { None } else { Some(NetworkContact::new(problem, newton.pattern(), &model.attached.held)?) };
    let mut contact_state: Option<ContactState> = tool_contact.as_ref().map(NetworkContact::initial_state);
    let candidates = boundary_nodes(mesh);
    let mut tool_tracks: Vec<ToolTrack> = problem
        .tools
        .iter()
        .map(|t| ToolTrack { name: t.name.clone(), samples: vec![ToolSample::default_at(0.0)] })
        .collect();
    landings.sort_by(f64::total_cmp);
    landings.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs().max(1.0));
    let max_dt = settings.max_dt_s.unwrap_or(end / 20.0);
    let min_dt = MIN_STEP_FRACTION * end;

    // Symbolic factorizations per constraint set (attached, released), each
    // with the last numeric factorization made on it ([`solve_tangent`]).
    let systems: [OnceCell<ReducedSystem>; 2] = [OnceCell::new(), OnceCell::new()];
    let kept: [RefCell<Option<Factor<'_>>>; 2] = [RefCell::new(None), RefCell::new(None)];

    let mut state = State {
        t: 0.0,
        u: vec![0.0; model.num_dofs()],
        history,
        stress: vec![0.0; mesh.num_cells() * S],
        holder: vec![FREE; mesh.num_nodes()],
    };
    let mut velocity = vec![0.0; model.num_dofs()];
    let mut steps: Vec<StepRecord> = Vec::new();
    let mut snapshots = Vec::new();
    let mut tracks: Vec<MarkerTrack> =
        problem.markers.iter().map(|m| MarkerTrack { name: m.name.clone(), samples: Vec::new() }).collect();
    let mut marker_next = vec![0usize; problem.markers.len()];
    emit_markers(&model, &mut tracks, &mut marker_next, &state.u, &state.u, 0.0, 0.0, true);
    let mut factorizations = 0usize;
    let mut largest_force: f64 = 0.0;
    let mut after_kink = true;
    let mut dt_next = f64::NAN;
    let mut retry_dt: Option<f64> = None;
    let keep = |t: f64| {
        let near = |x: f64| (t - x).abs() <= 1e-9 * x.abs().max(1.0);
        near(protocol.release_s.min(end)) || near(end) || problem.snapshot_times.iter().any(|&s| near(s))
    };
    let replay = settings.step_ends_s.clone();
    let mut replay_index = 0usize;
    // The `machine-compliance` effect [mm/N] and the machine's deflection at the
    // state's time [mm] (0 without it, and once the plate has let go).
    let compliance = problem.effects.machine_compliance_mm_per_n();
    let mut deflection = 0.0;
    let deflection_tol = DEFLECTION_RTOL * model.displacement_scale;

    while state.t < end * (1.0 - 1e-12) {
        let next_landing = landings.iter().copied().find(|&k| k > state.t * (1.0 + 1e-12) + 1e-15).unwrap_or(end);
        let mut dt = if let Some(ends) = &replay {
            let t1 = *ends.get(replay_index).ok_or_else(|| {
                PressError::BadSettings(format!("the replayed step ends stop at t = {} s before the end", state.t))
            })?;
            t1 - state.t
        } else if let Some(fixed) = settings.fixed_dt_s {
            fixed
        } else if let Some(retry) = retry_dt {
            retry
        } else if after_kink || !dt_next.is_finite() {
            ((next_landing - state.t) / 50.0).min(max_dt)
        } else {
            dt_next.min(max_dt)
        };
        if replay.is_none() && state.t + dt > next_landing - 1e-9 * dt {
            dt = next_landing - state.t;
        }
        let step_index = steps.len() + 1;
        let t1 = state.t + dt;
        let released = t1 > protocol.release_s * (1.0 + 1e-12);
        let constraints = if released { &model.released } else { &model.attached };
        if systems[released as usize].get().is_none() {
            let system = ReducedSystem::new(newton.pattern(), &constraints.held, Some(newton.node_order()))
                .map_err(|e| model.singular(0, 0.0, e))?;
            let _ = systems[released as usize].set(system);
        }
        let system = systems[released as usize].get().expect("set above");
        let kept = &kept[released as usize];
        let clock = Instant::now();

        // Predictor: the previous step's velocity; after a kink, and whenever the
        // contact's active set changes, the tangent's response to the held dofs'
        // increments.
        let mut u0 = state.u.clone();
        if !after_kink {
            for (x, v) in u0.iter_mut().zip(&velocity) {
                *x += v * dt;
            }
        }
        model.prescribe(constraints, t1, &mut u0);
        let faces: Vec<Option<f64>> = problem
            .tools
            .iter()
            .zip(&plates)
            .map(|(tool, plate)| (t1 <= tool.release_s * (1.0 + 1e-12)).then(|| plate.face_y(tool, t1)))
            .collect();
        let mut holder: Vec<u8> =
            state.holder.iter().map(|&h| if h != FREE && faces[h as usize].is_none() { FREE } else { h }).collect();
        let mut start = state.u.clone();
        let mut predict = after_kink;
        let mut passes = 0;
        let mut settled: Option<Settled> = None;
        let mut step_deflection = 0.0;
        // Machine compliance on the constrained plate: the plate held back by
        // the deflection `delta = c F` at the step's end, `F` the plate force,
        // by the chain's scalar iteration around whole Newton solves of the
        // step (`super::stepper::deflected_step`).
        let compliant = compliance.filter(|_| !released && !constraints.plate_dofs.is_empty());
        let attempt = loop {
            if let Some(c) = compliant {
                let d_cmd = protocol.displacement(t1);
                let failed = RefCell::new(None);
                let made = std::cell::Cell::new(0);
                let no_cut = vec![false; u0.len()];
                let step = StepSystem {
                    system,
                    kept: Some(kept),
                    held: &constraints.held,
                    cut: &no_cut,
                    dt,
                    history: &state.history,
                    penalty: None,
                };
                let mut take = |lift: f64| -> Result<(Converged, f64), PressError> {
                    let mut u = u0.clone();
                    for &dof in &constraints.plate_dofs {
                        u[dof] = -(d_cmd - lift);
                    }
                    let solved = if after_kink {
                        tangent_predictor(&newton, &step, &state.u, u).and_then(|(u, n)| {
                            made.set(made.get() + n);
                            solve_step(&newton, &step, u, largest_force)
                        })
                    } else {
                        solve_step(&newton, &step, u, largest_force)
                    };
                    match solved {
                        Ok(converged) => {
                            made.set(made.get() + converged.factorizations);
                            let [_, plate] = reactions(&model, &converged.internal, false);
                            Ok((converged, plate))
                        }
                        Err(f) => {
                            *failed.borrow_mut() = Some(f);
                            Err(PressError::BadSettings("a Newton solve of the deflection's iteration failed".into()))
                        }
                    }
                };
                break match deflected_step(&mut take, deflection, c, deflection_tol, step_index, t1) {
                    Ok((mut converged, lift)) => {
                        converged.factorizations = made.get();
                        step_deflection = lift;
                        Ok(converged)
                    }
                    Err(e) => Err(failed.into_inner().unwrap_or(StepFailure::Contact(e))),
                };
            }
            if let (Some(nc), Some(cs)) = (&tool_contact, &contact_state) {
                // From the step's start, as the chain's contact steps: the contact
                // iteration predicts the nodes on the tools itself (stuck nodes move
                // with their anchors), and friction's trial tractions are measured
                // from there.
                let mut start = state.u.clone();
                model.prescribe(constraints, t1, &mut start);
                let step = ContactSolve { system, held: &constraints.held, dt, t1, step_index, largest_force };
                break contact_step(&newton, nc, cs, &step, &state, start).map(|(c, s)| {
                    settled = Some(s);
                    c
                });
            }
            let cut = cut_dofs::<D>(&holder);
            for (node, &h) in holder.iter().enumerate() {
                if h != FREE {
                    u0[node * D + 1] = faces[h as usize].unwrap() - mesh.nodes[node][1];
                }
            }
            let step = StepSystem {
                system,
                kept: Some(kept),
                held: &constraints.held,
                cut: &cut,
                dt,
                history: &state.history,
                penalty: None,
            };
            let solved = if predict {
                tangent_predictor(&newton, &step, &start, u0)
                    .map(|(u, n)| {
                        factorizations += n;
                        u
                    })
                    .and_then(|u0| solve_step(&newton, &step, u0, largest_force))
            } else {
                solve_step(&newton, &step, u0, largest_force)
            };
            let c = match solved {
                Ok(c) => c,
                Err(e) => break Err(e),
            };
            if plates.is_empty()
                || !update_contact(&model, &plates, &faces, &candidates, &c, &mut holder, largest_force)
            {
                break Ok(c);
            }
            passes += 1;
            if passes > MAX_CONTACT_PASSES {
                let tool = holder.iter().copied().find(|&h| h != FREE).unwrap_or(0) as usize;
                let nodes = (0..holder.len() as u32).filter(|&n| holder[n as usize] == tool as u8).collect();
                break Err(StepFailure::ContactNotSettled { tool, nodes });
            }
            factorizations += c.factorizations;
            start = c.u.clone();
            u0 = c.u;
            predict = true;
        };
        let converged = match attempt {
            Ok(c) => c,
            Err(failure) => {
                if replay.is_some() || settings.fixed_dt_s.is_some() || dt * 0.25 < min_dt {
                    return Err(final_failure(failure, step_index, t1, &newton, &model));
                }
                retry_dt = Some(dt * 0.25);
                continue;
            }
        };
        factorizations += converged.factorizations;
        // Error control on the predictor's distance.
        let free_error = if after_kink {
            0.0
        } else {
            let mut e: f64 = 0.0;
            for d in 0..model.num_dofs() {
                if !constraints.held[d] {
                    let pred = state.u[d] + velocity[d] * dt;
                    e = e.max((converged.u[d] - pred).abs());
                }
            }
            0.5 * e
        };
        let ratio = free_error / (settings.rtol * model.displacement_scale);
        let controlled = replay.is_none() && settings.fixed_dt_s.is_none();
        if controlled && ratio > 1.0 && dt * 0.25 >= min_dt {
            retry_dt = Some(dt * (0.9 / ratio.sqrt()).clamp(0.25, 0.9));
            continue;
        }
        // Accept.
        retry_dt = None;
        deflection = step_deflection;
        let [mut bottom, mut plate] = reactions(&model, &converged.internal, released);
        if let Some(s) = settled {
            let keep_nodes = keep(t1);
            plate = 0.0;
            for ((track, mut sample), tool) in tool_tracks.iter_mut().zip(s.samples).zip(&problem.tools) {
                if !tool.floor {
                    plate += sample.force_n[1];
                } else if problem.protocol.support == super::Attachment::Free {
                    bottom -= sample.force_n[1];
                }
                if !keep_nodes {
                    sample.nodes = Vec::new();
                }
                track.samples.push(sample);
            }
            contact_state = Some(s.state);
        }
        if !plates.is_empty() {
            let keep_nodes = keep(t1);
            plate = 0.0;
            for (i, track) in tool_tracks.iter_mut().enumerate() {
                let sample = tool_sample(&model, &converged, &holder, i, t1, keep_nodes);
                if plates[i].above {
                    plate += sample.force_n[1];
                } else if problem.protocol.support == super::Attachment::Free {
                    bottom -= sample.force_n[1];
                }
                track.samples.push(sample);
            }
        }
        largest_force = largest_force.max(bottom.abs()).max(plate.abs());
        for d in 0..model.num_dofs() {
            velocity[d] = (converged.u[d] - state.u[d]) / dt;
        }
        emit_markers(&model, &mut tracks, &mut marker_next, &state.u, &converged.u, state.t, t1, false);
        state = State { t: t1, u: converged.u, history: converged.history, stress: converged.stress, holder };
        steps.push(StepRecord {
            t_s: t1,
            dt_s: dt,
            solve_s: clock.elapsed().as_secs_f64(),
            residual: converged.residual,
            refactored: converged.factorizations > 0,
            bottom_force_n: bottom,
            plate_force_n: plate,
            error_ratio: ratio,
            newton_iterations: converged.iterations,
        });
        if keep(t1) {
            snapshots.push(Snapshot {
                t_s: t1,
                displacement: model.reported(&state.u, t1),
                cell_stress: state.stress.clone(),
            });
        }
        let landed = (t1 - next_landing).abs() <= 1e-12 * next_landing.abs().max(1.0);
        after_kink = landed;
        if landed {
            velocity.iter_mut().for_each(|v| *v = 0.0);
        }
        dt_next = if ratio > 0.0 { dt * (0.9 / ratio.sqrt()).clamp(0.25, 2.0) } else { dt * 2.0 };
        if replay.is_some() {
            replay_index += 1;
        }
        progress(Progress { t_s: t1, end_s: end, steps: steps.len() });
    }
    let num_free_dofs = systems.iter().filter_map(OnceCell::get).map(|s| s.num_free()).max().unwrap_or(0);
    let factor_nonzeros = systems.iter().filter_map(OnceCell::get).map(|s| s.factor_nonzeros()).max().unwrap_or(0);
    Ok(PressResult {
        dim: D,
        num_stress: S,
        steps,
        snapshots,
        markers: tracks,
        num_factorizations: factorizations,
        contact_solves: 0,
        factor_nonzeros,
        num_free_dofs,
        tools: tool_tracks,
        segments: Vec::new(),
        force_offset: None,
    })
}

/// What a contact step's Newton solves share beside the contact's own data.
struct ContactSolve<'a> {
    system: &'a ReducedSystem,
    held: &'a [bool],
    dt: f64,
    t1: f64,
    step_index: usize,
    largest_force: f64,
}

/// A step with contact tools other than flat frictionless plates: the contact
/// iteration of [`super::network_contact`] from `u0`, each of its solves a
/// Newton solve of the step ([`solve_step`]) with the contact's penalties or
/// held dofs. The penalties scale with the tangent's diagonal at the step's start.
fn contact_step<const D: usize, const N: usize, const S: usize>(
    newton: &Newton<'_, '_, D, N, S>,
    contact: &NetworkContact<'_>,
    contact_state: &ContactState,
    solve: &ContactSolve<'_>,
    state: &State,
    u0: Vec<f64>,
) -> Result<(Converged, Settled), StepFailure>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let model = newton.model;
    let ContactSolve { system, held, dt, t1, step_index, largest_force } = *solve;
    let eval = newton
        .evaluate(&state.u, dt, &state.history, true)
        .map_err(|c| StepFailure::Law { element: c.element, failure: c.failure })?;
    let k = newton.tangent(&eval);
    let diagonal: Vec<f64> = newton.diagonal_positions().iter().map(|&p| k[p].abs()).collect();
    let step = ContactStep {
        t0: state.t,
        t1,
        step: step_index,
        u_start: &state.u,
        diagonal: &diagonal,
        body_force: &model.body_force,
        held,
        pattern: newton.pattern(),
    };
    let mut factorizations = 0;
    let mut newton_solve = |penalty: Option<&Penalty>, fixed: &[(usize, f64)], u: Vec<f64>| {
        let mut cut = vec![false; u.len()];
        fixed.iter().for_each(|&(d, _)| cut[d] = true);
        let step = StepSystem { system, kept: None, held, cut: &cut, dt, history: &state.history, penalty };
        let c = solve_step(newton, &step, u, largest_force)?;
        factorizations += c.factorizations;
        Ok(c)
    };
    let (mut converged, settled) = contact.settle(&step, contact_state, u0, &mut newton_solve)?;
    converged.factorizations = factorizations;
    Ok((converged, settled))
}

/// The bottom and plate reactions (compression positive) from the internal force.
fn reactions<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    internal: &[f64],
    released: bool,
) -> [f64; 2]
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mesh = &model.problem.mesh;
    let sum = |set: &str| -> f64 {
        mesh.node_sets.get(set).map_or(0.0, |nodes| {
            nodes.iter().map(|&i| internal[i as usize * D + 1] - model.body_force[i as usize * D + 1]).sum()
        })
    };
    let bottom = sum("bottom");
    let plate = if released { 0.0 } else { -sum("top") };
    [bottom, plate]
}

/// What one step's solves share: the system of its constraint set, the dofs it
/// holds and those contact holds, the step size and the history at its start.
#[derive(Clone, Copy)]
struct StepSystem<'a, 's> {
    system: &'s ReducedSystem,
    /// The last numeric factorization on `system`, reused while it serves
    /// ([`solve_tangent`]); `None`: every solve factors (the contact tools'
    /// iteration, whose penalties change the tangent from solve to solve).
    kept: Option<&'a RefCell<Option<Factor<'s>>>>,
    held: &'a [bool],
    cut: &'a [bool],
    dt: f64,
    history: &'a [f64],
    /// Contact tools' node penalties ([`super::network_contact`]), if any.
    penalty: Option<&'a Penalty>,
}

/// Newton's iteration of one step from `u` (held dofs already prescribed).
fn solve_step<const D: usize, const N: usize, const S: usize>(
    newton: &Newton<'_, '_, D, N, S>,
    step: &StepSystem<'_, '_>,
    mut u: Vec<f64>,
    largest_force: f64,
) -> Result<Converged, StepFailure>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let StepSystem { system, held, cut, dt, history, penalty, .. } = *step;
    let model = newton.model;
    let body = &model.body_force;
    let law_err = |c: CellFailure| StepFailure::Law { element: c.element, failure: c.failure };
    let residual_of = |eval: &Evaluation, u: &[f64]| -> (Vec<f64>, f64, f64) {
        let mut r = vec![0.0; system.num_free()];
        let mut held_norm: f64 = 0.0;
        // Contact penalties: their forces count in the force scale as reactions do.
        let contact = penalty.map(|p| {
            let mut f = vec![0.0; u.len()];
            p.add_forces(newton.pattern(), u, &mut f);
            held_norm = f.iter().fold(0.0, |m, x| m.max(x.abs()));
            f
        });
        for d in 0..eval.internal.len() {
            let x = match &contact {
                Some(f) => body[d] + f[d] - eval.internal[d],
                None => body[d] - eval.internal[d],
            };
            if held[d] || cut[d] {
                held_norm = held_norm.max(x.abs());
            } else {
                r[system.free_of_dof[d] as usize] = x;
            }
        }
        let norm = r.iter().map(|x| x * x).sum::<f64>().sqrt();
        (r, norm, held_norm)
    };
    // Every free dof's residual at its rounding floor.
    let at_floor = |eval: &Evaluation, r: &[f64]| -> bool {
        eval.magnitude.iter().enumerate().all(|(d, m)| {
            held[d] || cut[d] || r[system.free_of_dof[d] as usize].abs() <= ROUNDING_ULPS * f64::EPSILON * m
        })
    };
    let mut eval = newton.evaluate(&u, dt, history, true).map_err(law_err)?;
    let (mut r, mut norm, held_norm) = residual_of(&eval, &u);
    let mut scale = largest_force.max(held_norm).max(f64::MIN_POSITIVE);
    let mut factorizations = 0;
    let mut norms = Vec::new();
    for iteration in 0..MAX_ITERATIONS {
        norms.push(norm / scale);
        let rounding = penalty.map_or(0.0, |p| p.rounding(newton.diagonal_positions(), &u));
        let mut converged = norm <= TOLERANCE * scale || norm <= rounding;
        if !converged {
            // An iterate evaluated without its tangent (a trial expected to
            // converge) gets it now: the next Newton step and the rounding
            // floor need it. Its stress, history and forces are the same bits.
            if !eval.with_tangent {
                eval = newton.evaluate(&u, dt, history, true).map_err(law_err)?;
            }
            converged = iteration > 0 && at_floor(&eval, &r);
        }
        if converged {
            let stress =
                cauchy_stresses::<S>(&eval, model.problem.formulation, |e| newton.law_of(e).strain == Strain::Small);
            return Ok(Converged {
                u,
                history: eval.history,
                internal: eval.internal,
                stress,
                residual: norm / scale,
                factorizations,
                iterations: iteration,
                norms,
            });
        }
        let mut k = newton.tangent(&eval);
        if let Some(p) = penalty {
            k.iter_mut().zip(&p.values).for_each(|(a, b)| *a += b);
        }
        let mut du = r.clone();
        factorizations += solve_tangent(step, newton, &k, &mut du, LINEAR_TOLERANCE * TOLERANCE * scale)?;
        // Whether the full step is expected to converge: Newton's quadratic
        // rate predicts the next norm as `n_k^3 / n_(k-1)^2`. Such a trial is
        // evaluated without its tangent (the converged iterate's tangent is not
        // used); a wrong guess costs the tangent's evaluation afterwards, never
        // a different iterate.
        let expect_converged = iteration > 0 && {
            let (last, before) = (norms[iteration], norms[iteration - 1]);
            last * last * last <= TOLERANCE * before * before
        };
        // Backtracking line search on the residual's norm; a shortened trial,
        // often refused, is evaluated without its tangent.
        let mut alpha = 1.0;
        let mut accepted = None;
        for _ in 0..=LINE_SEARCH_HALVINGS {
            let mut trial = u.clone();
            for (i, &d) in system.dof_of_free.iter().enumerate() {
                trial[d as usize] += alpha * du[i];
            }
            let with_tangent = alpha == 1.0 && !expect_converged;
            if let Ok(e) = newton.evaluate(&trial, dt, history, with_tangent) {
                let (r1, n1, h1) = residual_of(&e, &trial);
                if n1 < (1.0 - 1e-4 * alpha) * norm || alpha < 1e-3 {
                    accepted = Some((trial, e, r1, n1, h1));
                    break;
                }
            }
            alpha *= 0.5;
        }
        let Some((trial, e, r1, n1, h1)) = accepted else {
            break;
        };
        u = trial;
        eval = e;
        r = r1;
        norm = n1;
        scale = scale.max(h1);
    }
    // The element at the largest out-of-balance force.
    let (mut worst, mut worst_dof) = (0.0, 0usize);
    for (i, &d) in system.dof_of_free.iter().enumerate() {
        if r[i].abs() > worst {
            worst = r[i].abs();
            worst_dof = d as usize;
        }
    }
    let element = model.cell_of_node(worst_dof / D).unwrap_or(0);
    Err(StepFailure::NotConverged { residual: norm / scale, element })
}

/// Solves the tangent system `k du = rhs` on the free dofs (the dofs marked in
/// `step.cut` stay at zero): by MINRES preconditioned with the last numeric
/// factorization on the system ([`minres`]) while that reaches
/// `max(KRYLOV_RELATIVE |rhs|, floor)` within [`krylov_budget`] iterations,
/// otherwise by a new factorization ([`factor_shifted`]), which is kept for
/// the next solves; a shifted one preconditions MINRES on the tangent itself. Over a step and from step to step the tangent changes little, so
/// the factor of an earlier tangent is a close preconditioner and a few
/// triangular solves replace a factorization; Newton's steps stay those of the
/// current tangent (to `KRYLOV_RELATIVE`), so its convergence does not change.
/// Returns the factorizations made.
fn solve_tangent<const D: usize, const N: usize, const S: usize>(
    step: &StepSystem<'_, '_>,
    newton: &Newton<'_, '_, D, N, S>,
    k: &[f64],
    rhs: &mut [f64],
    floor: f64,
) -> Result<usize, StepFailure>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let system = step.system;
    let norm = rhs.iter().map(|x| x * x).sum::<f64>().sqrt();
    let tolerance = (KRYLOV_RELATIVE * norm).max(floor);
    let budget = krylov_budget(system);
    if let Some(factor) = step.kept.and_then(|k| k.try_borrow().ok()).as_ref().and_then(|k| k.as_ref()) {
        if let Some(x) = minres(system, newton.pattern(), k, step.cut, factor, rhs, tolerance, budget) {
            rhs.copy_from_slice(&x);
            return Ok(0);
        }
    }
    let (factor, n) = factor_shifted(system, k, newton.diagonal_positions(), step.cut)?;
    // A shifted factor (the tangent is not positive definite) preconditions
    // the exact solve: Newton's step stays the current tangent's, and with it
    // the quadratic rate. Its own solve, a descent direction still, if not.
    let exact =
        if n > 1 { minres(system, newton.pattern(), k, step.cut, &factor, rhs, tolerance, budget) } else { None };
    match exact {
        Some(x) => rhs.copy_from_slice(&x),
        None => factor.solve_in_place(rhs),
    }
    if let Some(kept) = step.kept {
        *kept.borrow_mut() = Some(factor);
    }
    Ok(n)
}

/// The linear residual the preconditioned solves reach, relative to the
/// right-hand side's norm.
const KRYLOV_RELATIVE: f64 = 1e-10;
/// Or below this share of Newton's own tolerance (absolute, as a force): the
/// linear error then adds at most this share of [`TOLERANCE`] to the next
/// iterate's out-of-balance force.
const LINEAR_TOLERANCE: f64 = 1e-3;

/// The most MINRES iterations before refactoring: about the
/// number of triangular-solve pairs a factorization costs. A factorization
/// takes about `sum_j c_j^2` flops (`c_j` the factor's column counts, here
/// their mean `nnz(L) / n`), an iteration `4 nnz(L)` for its two triangular
/// solves and the tangent's product; a quarter of the mean column count.
fn krylov_budget(system: &ReducedSystem) -> usize {
    let n = system.num_free().max(1);
    (system.factor_nonzeros() / n / 4).clamp(4, 40)
}

/// Preconditioned MINRES (Paige & Saunders 1975) on `k` restricted to the
/// free, uncut dofs, preconditioned by `factor` (a factorization of an earlier
/// tangent, or of this one shifted, with its own cut set; projected onto the
/// uncut dofs). The tangent may be indefinite (compressive stresses soften its
/// geometric part; the viscous networks' step potential is not convex), the
/// preconditioner must be positive definite. The residual `rhs - k x` is
/// carried along (`k w` by the same recurrence as the search directions `w`)
/// and checked against a true product at the end. Returns the solution when
/// the residual's norm falls below `tolerance` within `budget` iterations,
/// `None` otherwise (the caller then factors). Sums run in a fixed order: the
/// result does not depend on the thread count.
#[allow(clippy::too_many_arguments)]
fn minres(
    system: &ReducedSystem,
    pattern: &CsrPattern,
    k: &[f64],
    cut: &[bool],
    factor: &Factor<'_>,
    rhs: &[f64],
    tolerance: f64,
    budget: usize,
) -> Option<Vec<f64>> {
    let n = system.num_free();
    let uncut: Vec<bool> = system.dof_of_free.iter().map(|&d| !cut[d as usize]).collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut full = vec![0.0; pattern.num_dofs()];
    let mut product = vec![0.0; pattern.num_dofs()];
    let mut apply = |x: &[f64], y: &mut [f64]| {
        for (i, &d) in system.dof_of_free.iter().enumerate() {
            full[d as usize] = if uncut[i] { x[i] } else { 0.0 };
        }
        pattern.mul_vec(k, &full, &mut product);
        for (i, &d) in system.dof_of_free.iter().enumerate() {
            y[i] = if uncut[i] { product[d as usize] } else { 0.0 };
        }
    };
    let precondition = |r: &[f64], z: &mut [f64]| {
        z.copy_from_slice(r);
        factor.solve_in_place(z);
        z.iter_mut().zip(&uncut).for_each(|(v, &u)| *v = if u { *v } else { 0.0 });
    };
    let b: Vec<f64> = rhs.iter().zip(&uncut).map(|(&v, &u)| if u { v } else { 0.0 }).collect();
    let mut x = vec![0.0; n];
    let mut residual = b.clone();
    if dot(&residual, &residual).sqrt() <= tolerance {
        return Some(x);
    }
    let mut r1 = b.clone();
    let mut r2 = b;
    let mut y = vec![0.0; n];
    precondition(&r1, &mut y);
    let beta1 = dot(&r1, &y);
    if !(beta1 > 0.0) {
        return None;
    }
    let (mut beta, mut old_beta) = (beta1.sqrt(), 0.0);
    let (mut dbar, mut epsln, mut phibar) = (0.0, 0.0, beta);
    let (mut cs, mut sn) = (-1.0, 0.0);
    let (mut v, mut kv) = (vec![0.0; n], vec![0.0; n]);
    let (mut w, mut w1, mut w2) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut kw, mut kw1, mut kw2) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for iteration in 0..budget {
        v.iter_mut().zip(&y).for_each(|(v, y)| *v = y / beta);
        apply(&v, &mut kv);
        y.copy_from_slice(&kv);
        if iteration > 0 {
            let c = beta / old_beta;
            y.iter_mut().zip(&r1).for_each(|(y, r)| *y -= c * r);
        }
        let alpha = dot(&v, &y);
        let c = alpha / beta;
        y.iter_mut().zip(&r2).for_each(|(y, r)| *y -= c * r);
        std::mem::swap(&mut r1, &mut r2);
        r2.copy_from_slice(&y);
        precondition(&r2, &mut y);
        old_beta = beta;
        let beta2 = dot(&r2, &y);
        if !(beta2 >= 0.0) {
            return None;
        }
        beta = beta2.sqrt();
        let old_eps = epsln;
        let delta = cs * dbar + sn * alpha;
        let gbar = sn * dbar - cs * alpha;
        epsln = sn * beta;
        dbar = -cs * beta;
        let gamma = gbar.hypot(beta);
        if !(gamma > 0.0) {
            return None;
        }
        cs = gbar / gamma;
        sn = beta / gamma;
        let phi = cs * phibar;
        phibar *= sn;
        std::mem::swap(&mut w1, &mut w2);
        std::mem::swap(&mut w2, &mut w);
        std::mem::swap(&mut kw1, &mut kw2);
        std::mem::swap(&mut kw2, &mut kw);
        for i in 0..n {
            w[i] = (v[i] - old_eps * w1[i] - delta * w2[i]) / gamma;
            kw[i] = (kv[i] - old_eps * kw1[i] - delta * kw2[i]) / gamma;
            x[i] += phi * w[i];
            residual[i] -= phi * kw[i];
        }
        if dot(&residual, &residual).sqrt() <= tolerance {
            // The recurrence's residual drifts from the true one: check it.
            apply(&x, &mut kv);
            let true_norm = kv
                .iter()
                .zip(rhs)
                .zip(&uncut)
                .map(|((kx, b), &u)| if u { (b - kx).powi(2) } else { 0.0 })
                .sum::<f64>()
                .sqrt();
            return (true_norm <= 2.0 * tolerance && x.iter().all(|v| v.is_finite())).then_some(x);
        }
        if beta == 0.0 {
            return None;
        }
    }
    None
}

/// Factors the tangent `k`; where it is not positive definite (compressive
/// stresses soften the geometric part, e.g. a layer crushed by the held dofs'
/// jump at a kink), factors `k + beta |diag k|` with the least `beta` of 1e-3,
/// 1e-2, 0.1, 1 that is: a descent direction for the line search, at the price
/// of linear convergence while it lasts. Returns the factorizations made.
///
/// The dofs marked in `cut` (held by contact) are cut off the matrix
/// ([`ReducedSystem::factor_decoupled`]): a zero right-hand side there keeps
/// them where they are.
fn factor_shifted<'s>(
    system: &'s ReducedSystem,
    k: &[f64],
    diagonal_positions: &[usize],
    cut: &[bool],
) -> Result<(crate::solve::Factor<'s>, usize), StepFailure> {
    let any_cut = cut.iter().any(|&c| c);
    let factor = |shift: Option<&[f64]>| {
        if any_cut {
            system.factor_decoupled(&[(1.0, k)], cut, shift)
        } else {
            system.factor(&[(1.0, k)], shift)
        }
    };
    match factor(None) {
        Ok(f) => Ok((f, 1)),
        Err(first) => {
            let diag: Vec<f64> = diagonal_positions.iter().map(|&p| k[p].abs()).collect();
            for (i, beta) in [1e-3, 1e-2, 0.1, 1.0].into_iter().enumerate() {
                let shift: Vec<f64> = diag.iter().map(|d| beta * d).collect();
                if let Ok(f) = factor(Some(&shift)) {
                    return Ok((f, i + 2));
                }
            }
            Err(StepFailure::Singular(first))
        }
    }
}

/// The displacement after a kink, predicted by the tangent at the step's start
/// `u_start` (an equilibrium): the held dofs move to their values in `u0`, the
/// free ones by `K_ff^-1 (r_free - K_fh du_held)`. Returns it and the
/// factorizations made.
fn tangent_predictor<const D: usize, const N: usize, const S: usize>(
    newton: &Newton<'_, '_, D, N, S>,
    step: &StepSystem<'_, '_>,
    u_start: &[f64],
    mut u0: Vec<f64>,
) -> Result<(Vec<f64>, usize), StepFailure>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let StepSystem { system, held, cut, dt, history, .. } = *step;
    let model = newton.model;
    let eval = newton
        .evaluate(u_start, dt, history, true)
        .map_err(|c| StepFailure::Law { element: c.element, failure: c.failure })?;
    let k = newton.tangent(&eval);
    let jump: Vec<f64> = (0..u0.len()).map(|d| if held[d] || cut[d] { u0[d] - u_start[d] } else { 0.0 }).collect();
    let mut coupling = vec![0.0; u0.len()];
    newton.pattern().mul_vec(&k, &jump, &mut coupling);
    let mut rhs: Vec<f64> = system
        .dof_of_free
        .iter()
        .map(|&d| {
            let d = d as usize;
            if cut[d] {
                0.0
            } else {
                model.body_force[d] - eval.internal[d] - coupling[d]
            }
        })
        .collect();
    let n = solve_tangent(step, newton, &k, &mut rhs, 0.0)?;
    for (i, &d) in system.dof_of_free.iter().enumerate() {
        if !cut[d as usize] {
            u0[d as usize] = u_start[d as usize] + rhs[i];
        }
    }
    Ok((u0, n))
}

/// The error of a step that failed at its shortest length.
fn final_failure<const D: usize, const N: usize, const S: usize>(
    failure: StepFailure,
    step: usize,
    time_s: f64,
    newton: &Newton<'_, '_, D, N, S>,
    model: &Model<'_, D, N, S>,
) -> PressError
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    match failure {
        StepFailure::Law { element, failure: LawFailure::Inverted { det } } => {
            PressError::Inverted { step, time_s, element, ratio: det }
        }
        StepFailure::Law { element, failure } => PressError::NotConverged {
            step,
            time_s,
            detail: format!("element {element} (law {}): {failure}", newton.law_of(element).name()),
        },
        StepFailure::NotConverged { residual, element } => PressError::NotConverged {
            step,
            time_s,
            detail: format!(
                "Newton's iteration stopped at a residual of {residual:.3e} of the force scale; largest out-of-balance \
                 force at element {element} (law {})",
                newton.law_of(element).name()
            ),
        },
        StepFailure::Singular(e) => model.singular(step, time_s, e),
        StepFailure::ContactNotSettled { tool, nodes } => {
            PressError::ContactNotSettled { step, time_s, tool: model.problem.tools[tool].name.clone(), nodes }
        }
        StepFailure::Contact(e) => e,
    }
}

/// The Cauchy stress `sigma = P F^T / J` per cell in the formulation's Voigt
/// order; a cell whose law is in small-strain kinematics (`small(e)`) returns
/// its Cauchy stress itself.
fn cauchy_stresses<const S: usize>(
    eval: &Evaluation,
    formulation: Formulation,
    small: impl Fn(usize) -> bool,
) -> Vec<f64> {
    let mut out = Vec::with_capacity(eval.cells.len() * S);
    for (e, c) in eval.cells.iter().enumerate() {
        let sigma = if small(e) { c.stress } else { c.stress * c.f.transpose() / c.f.determinant() };
        let voigt: Vec<f64> = match (formulation, S) {
            (_, 6) => vec![sigma[(0, 0)], sigma[(1, 1)], sigma[(2, 2)], sigma[(0, 1)], sigma[(0, 2)], sigma[(1, 2)]],
            (Formulation::Axisymmetric, 4) => vec![sigma[(0, 0)], sigma[(1, 1)], sigma[(2, 2)], sigma[(0, 1)]],
            _ => vec![sigma[(0, 0)], sigma[(1, 1)], sigma[(0, 1)]],
        };
        out.extend(voigt);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::network::{Energy, Equilibrium};
    use crate::material::Material;
    use crate::press::{Attachment, Protocol, SolidPress};

    /// Newton's iteration converges quadratically near the solution: a glued
    /// neo-Hookean block (an inhomogeneous field) pushed 20 % in one step from
    /// the tangent's prediction at rest, standard cells and F-bar patches. Each iterate's out-of-balance
    /// norm `r_k` is recorded; the observed order `ln(r_k+1 / r_k) / ln(r_k /
    /// r_k-1)` of the last step above the rounding floor must exceed 1.8.
    #[test]
    fn newtons_iteration_converges_quadratically() {
        let net = Network::new(0.45).with_equilibrium(Equilibrium {
            energy: Energy::Exponential { stiffening: 1.0 },
            e_mpa: 0.03,
            mullins: None,
        });
        let protocol = Protocol {
            waypoints: vec![[0.0, 0.0], [1.0, 2.0]],
            release_s: 1.0,
            end_s: 1.0,
            plate: Attachment::Glued,
            support: Attachment::Glued,
            gravity: false,
        };
        let problem = SolidPress::new_3d(
            crate::mesh::block([12.0, 10.0, 8.0], 2.0, "m").unwrap(),
            vec![Material::network(net).unwrap()],
            protocol,
        )
        .unwrap();
        for volumetric in [Volumetric::Standard, Volumetric::FBar] {
            let model = Model::new(&problem).unwrap();
            let laws = region_laws(&problem);
            let mesh = &problem.mesh;
            let operators: Vec<DMatrix<f64>> = model.geometry.iter().map(deformation_operator::<3, 4>).collect();
            let mut offsets = vec![0];
            for &r in &mesh.cell_regions {
                offsets.push(offsets.last().unwrap() + laws[r as usize].history_len());
            }
            let patches = (volumetric == Volumetric::FBar)
                .then(|| Patches::new(&mesh.nodes, &mesh.cells, &mesh.cell_regions, fbar::patch_size(3)));
            let newton = Newton { model: &model, laws, operators, offsets, patches };
            let mut history = vec![0.0; *newton.offsets.last().unwrap()];
            for (e, h) in split_by_offsets(&mut history, &newton.offsets).into_iter().enumerate() {
                newton.law_of(e).initial_history(h);
            }
            let system = ReducedSystem::new(newton.pattern(), &model.attached.held, Some(newton.node_order())).unwrap();
            let mut u0 = vec![0.0; model.num_dofs()];
            model.prescribe(&model.attached, 1.0, &mut u0);
            let cut = vec![false; u0.len()];
            let kept = RefCell::new(None);
            let step = StepSystem {
                system: &system,
                kept: Some(&kept),
                held: &model.attached.held,
                cut: &cut,
                dt: 1.0,
                history: &history,
                penalty: None,
            };
            let rest = vec![0.0; u0.len()];
            let Ok((u0, _)) = tangent_predictor(&newton, &step, &rest, u0) else { panic!("{volumetric:?}: predictor") };
            let Ok(c) = solve_step(&newton, &step, u0, 0.0) else { panic!("{volumetric:?}: no convergence") };
            let r = &c.norms;
            let shown: Vec<String> = r.iter().map(|x| format!("{x:.2e}")).collect();
            let shown = shown.join(", ");
            // The last ratio of three iterates all above the floor (1e-13).
            let k = (2..r.len()).rev().find(|&k| r[k] > 1e-13).expect("at least three iterates above the floor");
            let order = (r[k] / r[k - 1]).ln() / (r[k - 1] / r[k - 2]).ln();
            eprintln!("{volumetric:?}: norms {shown}, observed order {order:.2}");
            assert!(order > 1.8, "{volumetric:?}: order {order:.2} ({shown})");
        }
    }
}
