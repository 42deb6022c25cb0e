//! Contact between the specimen's boundary nodes and rigid tools: an augmented
//! Lagrangian with an active set, solved inside the quasi-static step.
//!
//! ## Why this method
//! The material is linear and every step is already one sparse Cholesky solve, so
//! the contact must (a) meet the non-penetration bound exactly enough, 1e-6 of the
//! local element size at every converged step, (b) keep the matrix pattern (the
//! symbolic factorization is done once) and (c) cost nothing extra while the
//! contact set does not change (the plate case). Two paths share the statuses,
//! multipliers and output:
//!
//! - **Flat tools: exact elimination.** When every tool engaged in a step is a
//!   plate that never turns, glued or frictionless (the plate and floor cases),
//!   the held dofs are eliminated exactly, as the constrained plate holds its
//!   own: a glued node's free dofs at its anchor, a normal-contact node's dof
//!   along the face's normal (a coordinate axis) on the face. The pattern stays:
//!   the held dofs are cut off the matrix (zero off-diagonal entries, the same
//!   symbolic factorization, `ReducedSystem::factor_decoupled`) and their coupling
//!   moves to the right-hand side; their reactions (`A u - b` on their rows) are
//!   the multipliers. The active set is the primal-dual active set method's, with
//!   the penalty below as its constant (for glued tools: a node sticks where it
//!   first touches, as under the penalty). A step ends when a solve leaves the
//!   statuses and held values as they were, so while the set does not change a
//!   step is one solve with the kept factorization, exact (no constraint error
//!   at all), and no more work than the constrained plate's. With penalties the
//!   plate took two solves per step (the second to confirm the Uzawa update),
//!   about 40 % more per step than the constrained plate at 100k tets.
//! - **Otherwise: an augmented Lagrangian.** Eliminating in a rotated frame per
//!   node (curved tools) or with friction's slip would change the matrix at every
//!   Newton step; a barrier (IPC) never reaches the frictionless plate's exact
//!   solution. Each active node adds a penalty block `k n n^T` (normal), `k I`
//!   (stuck or glued) to the step matrix, in the node's own diagonal block (already
//!   in the pattern), and the multipliers are updated after each solve (Uzawa,
//!   `lambda <- max(0, lambda - k g)`), so the constraint is met exactly in the
//!   limit whatever `k`. With `k` a million times the node's stiffness each update
//!   shrinks the constraint error about a millionfold: on a plate one solve with
//!   the previous step's multipliers mostly settles a step, two at most, and the
//!   factorization is kept while the active set stays the same. The exact path
//!   hands a step here when a dof would be held by two tools or its active set
//!   does not settle in 20 solves.
//!
//! ## Curved tools: the low-rank path
//! Under a curved tool the set grows and the normals turn at every Newton step,
//! so the penalized matrix would be refactored at every one (the 100k-tet sphere
//! took more than 19 minutes that way). The penalties live on a few nodes'
//! diagonal blocks, so the penalized matrix is the unpenalized step matrix `A`
//! plus a low-rank term: each Newton step is one solve with `A`'s factor (kept for
//! the run when one material scales it) and a Woodbury correction through the
//! columns `A^{-1} e` of the penalized dofs (kept too; a node's columns are solved
//! once, when it first touches), a dense system of three unknowns per contact
//! node ([`ContactModel::low_rank_solve`]). It is exact, not an approximation: the
//! same Newton steps, to the solves' rounding. A step whose columns would exceed
//! [`COLUMN_BUDGET`] (a curved tool and a large glued plate at once) refactors as
//! before.
//!
//! Each iteration is a Newton step on the contact forces for the current statuses:
//! `(A + P) u = f + F(u_old) + P u_old`, with `F` the contact forces at `u_old` and `P`
//! their Jacobian for flat tools (an approximation for curved ones, whose normal
//! turns with the closest point; the iteration still converges to the true
//! closest-point contact, more slowly).
//!
//! ## Friction
//! Coulomb, by the augmented Lagrangian return map (Alart & Curnier; Laursen): a
//! pair carries a tangential multiplier and an anchor, the material point of the
//! tool it sticks to; the trial traction `lambda_t - k s` (slip `s` from the
//! anchor, tangential) sticks while `|trial| <= mu lambda_n`, and slips otherwise
//! with the traction `mu lambda_n` along the trial (explicit in the iteration). After
//! a slipping step the anchor moves to the node's contact point.
//!
//! Four rules make the iteration settle when a slide starts or reverses:
//! - **Stick predictor.** A node stuck at the step's start starts the step moved
//!   with its anchor. Left where it was, its trial traction would be the penalty
//!   times the tool's whole increment, far outside the cone, and every stuck node
//!   would start the step slipping, then swing back and forth across its anchor.
//! - **Reversal sticks.** A slip whose direction reverses within a step has
//!   overshot its anchor; it sticks for the next iteration. The stick window is
//!   only `2 mu N / k` wide, so the explicit slip traction alone would never
//!   land in it.
//! - **The cone's edge keeps its status.** A slipping node sits at the edge of
//!   the cone, where stick and slip give the same traction; deciding between them
//!   there is left to the rounding of the node's position times the penalty
//!   (`k x eps`), which for small `mu` is as large as `mu N` itself. Within that
//!   band a pair keeps the last pass's status; flipping there made the statuses
//!   cycle and the step fail to settle at `mu <= 1e-3`.
//! - **Slip tractions settle.** The explicit slip tractions are part of the
//!   convergence test: a step ends when the last solve changed none of them by more
//!   than 1e-8 of itself (or the rounding of `mu k x`). On a plate the iteration
//!   converges linearly, about tenfold per solve.
//!
//! ## Glued
//! A node that touches a glued tool sticks to it in every direction (tension
//! too) until the tool's `release_s`.
//!
//! ## Adhesion
//! With the `adhesion` effect, the normal law of the pressing tools that are not
//! glued carries a rigid-linear cohesive zone (design, history and measured
//! accuracy in [`crate::effects`], "Adhesion"): a *bonded* pair (in contact at
//! the last step end) is a normal pair whose multiplier may pull down to its
//! strength and tears off on its updated multiplier; an adhered pair off the tool
//! is [`Status::Cohesive`], its softening traction explicit in the iteration
//! (settled to 1e-10 of the strength, [`COHESIVE_TOLERANCE`], in at most
//! [`ADHESION_ITERATIONS`] solves) and its secant unloading implicit. Adhesive
//! tools skip the exact elimination path.

use std::collections::HashMap;
use std::sync::Mutex;

use nalgebra::{DMatrix, DVector};

use super::tools::{PlacedTool, ToolContact};
use super::{PressError, PressProblem};
use crate::assembly::CsrPattern;
use crate::element::{Formulation, ReferenceSimplex, Simplex};

/// Penalty relative to the node's diagonal stiffness (large enough that one solve
/// mostly settles a plate step; the factorization stays accurate: the contact
/// tests reproduce the constrained plate to 1e-10).
const KAPPA: f64 = 1e6;
/// Allowed constraint error at a converged step, relative to the local element
/// size. The bound asked is 1e-6; the multipliers are the penalty times the error,
/// so the error is driven far lower for forces accurate to about 1e-9.
const TOLERANCE: f64 = 1e-11;
/// The same for friction (see [`ContactModel::constraint_error`]).
const FRICTION_TOLERANCE: f64 = 1e-8;
/// Allowed change of a slip traction in the last solve, relative to itself (the
/// slip traction is explicit in the iteration).
const SLIP_TOLERANCE: f64 = 1e-8;
/// Iterations before a step counts as not settling.
const MAX_ITERATIONS: usize = 100;
/// The same with adhesion (its explicit softening tractions converge linearly).
const ADHESION_ITERATIONS: usize = 400;
/// Allowed change of a cohesive force in the last solve, relative to the node's
/// full strength `sigma_a A` (the softening traction is explicit in the
/// iteration). At 1e-12 the changes of a peeling front's nodes stalled at the
/// solves' rounding (measured 1e-12 of the strength) and the step did not settle.
const COHESIVE_TOLERANCE: f64 = 1e-10;
/// The rounding of a node's position, relative to its size, that decides
/// friction statuses at the cone's edge (see [`law`]).
const ROUNDING: f64 = 8.0 * f64::EPSILON;
/// Normals turning less than this (in norm of the difference) keep the factorization.
const NORMAL_REUSE: f64 = 1e-6;
/// A pair in contact in the last solve stays in contact while its gap is below
/// this fraction of the local size: a Newton step on a curved tool lands a node
/// that should just touch a hair off the surface (the gap's curvature), and
/// opening it there makes the active set cycle. The next step brings it back to
/// the surface or, if it truly separates, past the band.
const OPEN_BAND: f64 = 1e-4;

/// The status of a node against a tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Status {
    Open,
    /// Normal contact, no tangential stiffness (frictionless or slipping).
    Normal,
    /// Stuck or glued: all directions held.
    Stuck,
    /// Adhesion: off the tool but held by the cohesive traction (explicit on the
    /// softening branch, a secant spring on the unloading one).
    Cohesive,
}

/// A node against one tool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pair {
    pub lambda_n: f64,
    /// Tangential traction (glued: the whole traction) [N], world frame.
    pub lambda_t: [f64; 3],
    /// The tool's material point the node sticks to, at the state's time [mm].
    pub anchor: Option<[f64; 3]>,
    pub status: Status,
    /// The normal used in the matrix.
    matrix_normal: [f64; 3],
    /// Friction: the direction of the slip traction in this step's last iteration
    /// (zero when the pair did not slip).
    slip_direction: [f64; 3],
    /// Friction: the slip traction (explicit in the iteration) of the last pass.
    slip_force: [f64; 3],
    /// Friction: `mu N / |trial|` of the last pass's slip (its tangent's factor).
    slip_scale: f64,
    /// Adhesion: the largest opening since the node last touched the tool, at the
    /// state's time [mm] (`INFINITY`: not adhered, or fully separated).
    opening_max: f64,
    /// Adhesion: `opening_max` within the step's iteration: it also grows with the
    /// iterates' openings (monotone damage within a step, so that an iteration
    /// that overshoots cannot swing between torn and bonded), committed at the end.
    opening_trial: f64,
    /// Adhesion: the tension the pair may carry in contact in the last pass [N]
    /// (its full strength while bonded, else 0).
    tension_cap: f64,
    /// Adhesion: the cohesive normal force of the last pass [N] (negative: a pull).
    cohesive_n: f64,
    /// Adhesion: the secant stiffness of the unloading branch in the last pass
    /// [N/mm] (0 on the softening branch, whose force is explicit).
    cohesive_stiffness: f64,
}

impl Default for Pair {
    fn default() -> Self {
        Self {
            lambda_n: 0.0,
            lambda_t: [0.0; 3],
            anchor: None,
            status: Status::Open,
            matrix_normal: [0.0; 3],
            slip_direction: [0.0; 3],
            slip_force: [0.0; 3],
            slip_scale: 0.0,
            opening_max: f64::INFINITY,
            opening_trial: f64::INFINITY,
            tension_cap: 0.0,
            cohesive_n: 0.0,
            cohesive_stiffness: 0.0,
        }
    }
}

/// The contact state at a step end: a pair per tool and boundary node.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ContactState {
    pub pairs: Vec<Vec<Pair>>,
}

/// A hash of the penalty matrix's statuses and normals: equal hashes, equal matrices.
fn hash_signature(signature: &[(Status, [i64; 3])]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    signature.hash(&mut h);
    h.finish()
}

/// A tool's contact forces at a step end.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolSample {
    /// Time [s].
    pub t_s: f64,
    /// The force the specimen puts on the tool [N] (world x, y, z; full circle for
    /// an axisymmetric problem, whose x is r and whose x and z parts are zero).
    pub force_n: [f64; 3],
    /// Sum of the normal contact forces [N].
    pub normal_n: f64,
    /// Magnitude of the summed tangential forces [N].
    pub tangential_n: f64,
    /// Area in contact [mm^2]: the area of the specimen's boundary facets that
    /// lie on the tool, measured on the undeformed specimen (the nominal contact
    /// area, which force over area turns into a nominal stress; full circle for
    /// an axisymmetric problem, length times thickness in plane problems). A node
    /// in contact (or, with adhesion, held by the cohesive traction) adds `1/D` of
    /// each facet around it (`D` nodes per facet) that faces the tool (outward
    /// normal against the tool's at the node), so a facet whose nodes all touch
    /// counts in full, one at the rim of the contact for the share of its nodes
    /// that touch, and one that meets the tool along an edge only (a side wall
    /// perpendicular to a plate) not at all.
    pub area_mm2: f64,
    /// Nodes in contact or held by adhesion (only at snapshot times; empty otherwise).
    pub nodes: Vec<u32>,
}

impl ToolSample {
    /// A sample at `t_s` with no contact.
    pub(crate) fn default_at(t_s: f64) -> Self {
        Self { t_s, force_n: [0.0; 3], normal_n: 0.0, tangential_n: 0.0, area_mm2: 0.0, nodes: Vec::new() }
    }

    /// Whether some node touches the tool.
    pub(crate) fn touches(&self) -> bool {
        self.area_mm2 > 0.0
    }
}

/// A tool's contact history.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolTrack {
    /// The tool's name.
    pub name: String,
    /// One sample per accepted step, and at t = 0.
    pub samples: Vec<ToolSample>,
}

impl ToolTrack {
    /// The force on the tool at time `t`, interpolated linearly between step ends [N].
    pub fn force_at(&self, t: f64) -> [f64; 3] {
        let s = &self.samples;
        let i = s.partition_point(|x| x.t_s < t);
        if i == 0 {
            return s.first().map_or([0.0; 3], |x| x.force_n);
        }
        if i >= s.len() {
            return s[s.len() - 1].force_n;
        }
        let (a, b) = (&s[i - 1], &s[i]);
        let w = if b.t_s > a.t_s { (t - a.t_s) / (b.t_s - a.t_s) } else { 1.0 };
        std::array::from_fn(|k| a.force_n[k] + w * (b.force_n[k] - a.force_n[k]))
    }
}

/// A boundary facet faces a tool when the cosine between its outward normal and
/// the tool's inward normal exceeds this: zero up to the rounding of the normals,
/// so that a side wall perpendicular to a plate (cosine 0) does not count.
const FACING_COSINE: f64 = 1e-9;

/// The tools and the boundary nodes they may touch.
pub(crate) struct ContactModel<'t> {
    /// Tools in canonical order (sorted by name, then listing), so that results do
    /// not depend on the order they were listed in.
    pub tools: Vec<PlacedTool<'t>>,
    /// `order[c]` is the listed index of canonical tool `c`.
    pub order: Vec<usize>,
    /// Boundary nodes with at least one free dof.
    pub nodes: Vec<u32>,
    /// Per candidate node, its boundary facets' outward unit normals and the
    /// node's share of each facet's area, `1/D` of it [mm^2], on the undeformed
    /// mesh: what [`ToolSample::area_mm2`] adds up.
    area_facets: Vec<Vec<([f64; 3], f64)>>,
    /// Local element size at each candidate node [mm].
    pub size: Vec<f64>,
    pub planar: bool,
    pub dim: usize,
    /// Position in the pattern's values of each candidate's `D x D` diagonal block.
    block: Vec<Vec<usize>>,
    /// Whether each dof of each candidate node is held (prescribed).
    held: Vec<[bool; 3]>,
    /// Columns of the unpenalized step matrix's inverse, for the low-rank path.
    columns: Mutex<ColumnCache>,
    /// Adhesion `[sigma_a MPa, delta_c mm]` (the `adhesion` effect), if active.
    adhesion: Option<[f64; 2]>,
    /// Per canonical tool: whether adhesion acts on it (a pressing tool, not glued).
    adheres: Vec<bool>,
    /// Per candidate node, with adhesion: its boundary facets' outward unit normals
    /// and the node's consistent share of each facet's area [mm^2] (`int N_a dA`).
    facets: Vec<Vec<([f64; 3], f64)>>,
    /// Per canonical tool: whether it rides on the crosshead, behind the machine
    /// compliance (a tool that is not a floor and whose keyframes move it; see
    /// `super::stepper`, "Machine compliance"). Its pose is lifted by
    /// [`StepInput::lift`].
    pub crosshead: Vec<bool>,
    /// Whether curved tools may take the low-rank path ("Curved tools: the
    /// low-rank path"): only where the step matrix without penalties is the same
    /// for every solve of a step (the linear chain). The Newton path's solves
    /// each run Newton's iteration on the penalized problem and clear it.
    pub low_rank: bool,
}

/// The adhesion of one pair: the node's strength `sigma_a A` [N] (`A` its facets'
/// area facing the tool) and the critical opening [mm].
#[derive(Debug, Clone, Copy)]
struct Cohesion {
    strength_n: f64,
    opening_mm: f64,
}

/// Columns `A^{-1} e_dof` of the unpenalized step matrix at unit scale (see
/// [`StepInput::scale`]), valid for one factorization ([`StepInput::factor_key`]).
#[derive(Default)]
struct ColumnCache {
    key: Option<u64>,
    columns: HashMap<usize, Vec<f64>>,
}

/// Solves a step with penalties: `(hash, penalty values, extra right-hand side)`
/// to the full displacement (see [`ContactModel::settle`]).
///
/// With `Some(ncols)` as the last argument, the request is instead `ncols`
/// columns (one after the other, each over all dofs) to solve with the step
/// matrix without penalties (`hash` is then [`PLAIN`] and the penalty zero): the
/// result holds `A^{-1}` of each column on the free dofs and zeros on the held ones.
pub(crate) type PenalizedSolve<'a> =
    dyn FnMut(u64, &dyn Fn() -> Vec<f64>, &[f64], Option<usize>) -> Result<Vec<f64>, PressError> + 'a;

/// The hash of the step matrix without penalties (the low-rank path's factor).
pub(crate) const PLAIN: u64 = 0x706c_6169_6e00_0000;

/// Solves a step with some free dofs held at given values (the exact path, see
/// "Flat tools: exact elimination"): `(hash, held)` with `held` the `(dof, value)`
/// pairs in increasing dof order and `hash` equal for equal sets of dofs (so a
/// factorization may be kept), to the full displacement and, per held dof, its
/// reaction `A u - b` [N]: the force the tool puts on the specimen there.
pub(crate) type EliminatedSolve<'a> = dyn FnMut(u64, &[(usize, f64)]) -> Result<(Vec<f64>, Vec<f64>), PressError> + 'a;

/// Solves the exact path may take in one step before it hands the step to the
/// penalties (an active set that does not settle by then would cycle).
const EXACT_ITERATIONS: usize = 20;

/// The low-rank path keeps at most this many columns of `A^{-1}` times the number
/// of dofs (in f64: 256 MB); past it, a step refactors the penalized matrix.
const COLUMN_BUDGET: usize = 32 << 20;

/// One pass over the pairs: statuses, the Newton right-hand side and blocks.
struct Pass {
    statuses: Vec<Vec<Status>>,
    rhs: Vec<f64>,
    blocks: Vec<[[f64; 3]; 3]>,
    signature: Vec<(Status, [i64; 3])>,
}

/// What one contact-step iteration needs from the stepper.
pub(crate) struct StepInput<'a> {
    pub t0: f64,
    pub t1: f64,
    pub step: usize,
    /// Node positions at rest [mm].
    pub rest: &'a [Vec<f64>],
    /// The diagonal of the step matrix (actual scale) per dof.
    pub diagonal: &'a [f64],
    /// The displacement at the step's start.
    pub u0: &'a [f64],
    /// Identifies the unpenalized step matrix up to its scale: columns of its
    /// inverse are kept while this stays the same.
    pub factor_key: u64,
    /// The unpenalized step matrix is `scale` times the one `factor_key` names.
    pub scale: f64,
    /// The machine compliance's deflection at `t0` and at `t1` [mm]: the tools on
    /// the crosshead ([`ContactModel::crosshead`]) sit this far above (+y) their
    /// keyframes' pose. Zero without the `machine-compliance` effect.
    pub lift: [f64; 2],
}

/// The outcome of a converged contact step.
pub(crate) struct Settled {
    pub state: ContactState,
    /// The converged displacement.
    pub u: Vec<f64>,
    /// The contact forces on the specimen, per dof [N].
    pub forces: Vec<f64>,
    /// Per listed tool: force on the tool, normal sum, tangential vector sum, area, nodes.
    pub samples: Vec<ToolSample>,
}

impl Settled {
    /// Multiplies every contact force and multiplier by `factor`: the settle of a
    /// right-hand side divided by `factor` (the material-point iteration's scaled
    /// operator, [`super::inelastic`], "Stiffer tangents"; glued and frictionless
    /// tools only, whose solve is homogeneous in the forces) reports its forces at
    /// the true scale.
    pub fn scale_forces(&mut self, factor: f64) {
        self.forces.iter_mut().for_each(|f| *f *= factor);
        for sample in &mut self.samples {
            sample.force_n.iter_mut().for_each(|f| *f *= factor);
            sample.normal_n *= factor;
            sample.tangential_n *= factor;
        }
        for pair in self.state.pairs.iter_mut().flatten() {
            pair.lambda_n *= factor;
            pair.lambda_t.iter_mut().for_each(|f| *f *= factor);
        }
    }
}

impl<'t> ContactModel<'t> {
    pub fn new<const D: usize, const N: usize, const S: usize>(
        problem: &'t PressProblem<D, N, S>,
        pattern: &CsrPattern,
        held: &[bool],
    ) -> Result<Self, PressError>
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let mut order: Vec<usize> = (0..problem.tools.len()).collect();
        order.sort_by(|&a, &b| problem.tools[a].name.cmp(&problem.tools[b].name).then(a.cmp(&b)));
        let tools = order.iter().map(|&i| PlacedTool::new(&problem.tools[i])).collect::<Result<Vec<_>, _>>()?;
        let mesh = &problem.mesh;
        // Boundary facets: the facets of exactly one cell.
        let mut count: HashMap<[u32; D], (u32, [u32; D], u32)> = HashMap::new();
        for cell in &mesh.cells {
            for skip in 0..N {
                let mut f = [0u32; D];
                let mut k = 0;
                for (a, &v) in cell.iter().enumerate() {
                    if a != skip {
                        f[k] = v;
                        k += 1;
                    }
                }
                let mut key = f;
                key.sort_unstable();
                count.entry(key).and_modify(|e| e.0 += 1).or_insert((1, f, cell[skip]));
            }
        }
        let mut facets: Vec<([u32; D], u32)> = count.into_values().filter(|e| e.0 == 1).map(|e| (e.1, e.2)).collect();
        facets.sort_unstable();
        let adhesion = problem.effects.adhesion();
        let mut node_facets: Vec<Vec<([f64; 3], f64)>> =
            if adhesion.is_some() { vec![Vec::new(); mesh.num_nodes()] } else { Vec::new() };
        let nn = mesh.num_nodes();
        let mut area_facets: Vec<Vec<([f64; 3], f64)>> = vec![Vec::new(); nn];
        let mut size = vec![0.0f64; nn];
        let mut on_boundary = vec![false; nn];
        for (f, opposite) in &facets {
            let p: Vec<[f64; 3]> = f
                .iter()
                .map(|&v| {
                    let q = mesh.nodes[v as usize];
                    [q[0], q[1], if D == 3 { q[2] } else { 0.0 }]
                })
                .collect();
            let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            let len = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            let (measure, edge) = if D == 3 {
                let (u, v) = (sub(p[1], p[0]), sub(p[2], p[0]));
                let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
                let e = len(u).max(len(v)).max(len(sub(p[2], p[1])));
                (0.5 * len(c), e)
            } else {
                let l = len(sub(p[1], p[0]));
                let weight = match problem.formulation {
                    Formulation::PlaneStress { thickness_mm } | Formulation::PlaneStrain { thickness_mm } => {
                        thickness_mm
                    }
                    Formulation::Axisymmetric => std::f64::consts::TAU * 0.5 * (p[0][0] + p[1][0]),
                    Formulation::Solid => 1.0,
                };
                (l * weight, l)
            };
            // The outward unit normal (away from the cell's opposite vertex).
            let q = mesh.nodes[*opposite as usize];
            let o = sub(p[0], [q[0], q[1], if D == 3 { q[2] } else { 0.0 }]);
            let (u, v) = (sub(p[1], p[0]), if D == 3 { sub(p[2], p[0]) } else { [0.0, 0.0, 1.0] });
            let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            let l = len(c);
            let sign = if c[0] * o[0] + c[1] * o[1] + c[2] * o[2] < 0.0 { -1.0 } else { 1.0 };
            let normal = if l > 0.0 { c.map(|x| sign * x / l) } else { [0.0; 3] };
            for &v in f {
                size[v as usize] = size[v as usize].max(edge);
                on_boundary[v as usize] = true;
                area_facets[v as usize].push((normal, measure / D as f64));
            }
            if adhesion.is_some() {
                // Each node's share `int N_a dA` of the facet (axisymmetric: the
                // weight 2 pi r is linear along the edge, so the shares differ).
                for (a, &vtx) in f.iter().enumerate() {
                    let share = if problem.formulation == Formulation::Axisymmetric {
                        let (ra, rb) = (p[a][0], p[1 - a][0]);
                        std::f64::consts::TAU * edge * (2.0 * ra + rb) / 6.0
                    } else {
                        measure / D as f64
                    };
                    node_facets[vtx as usize].push((normal, share));
                }
            }
        }
        let nodes: Vec<u32> =
            (0..nn as u32).filter(|&i| on_boundary[i as usize] && (0..D).any(|k| !held[i as usize * D + k])).collect();
        let block = nodes
            .iter()
            .map(|&i| {
                let mut pos = Vec::with_capacity(D * D);
                for a in 0..D {
                    let r = i as usize * D + a;
                    for b in 0..D {
                        let c = (i as usize * D + b) as u32;
                        let row = &pattern.col_idx[pattern.row_ptr[r]..pattern.row_ptr[r + 1]];
                        let p = row.iter().position(|&x| x == c).expect("a node's diagonal block is in the pattern");
                        pos.push(pattern.row_ptr[r] + p);
                    }
                }
                pos
            })
            .collect();
        let held = nodes.iter().map(|&i| std::array::from_fn(|k| k < D && held[i as usize * D + k])).collect();
        let adheres =
            tools.iter().map(|t| adhesion.is_some() && !t.tool.floor && t.tool.contact != ToolContact::Glued).collect();
        let facets = if adhesion.is_some() {
            nodes.iter().map(|&i| std::mem::take(&mut node_facets[i as usize])).collect()
        } else {
            Vec::new()
        };
        let crosshead = tools.iter().map(|t| on_crosshead(t.tool)).collect();
        Ok(Self {
            crosshead,
            low_rank: true,
            adhesion,
            adheres,
            facets,
            held,
            tools,
            order,
            area_facets: nodes.iter().map(|&i| std::mem::take(&mut area_facets[i as usize])).collect(),
            size: nodes.iter().map(|&i| size[i as usize]).collect(),
            nodes,
            planar: D == 2,
            dim: D,
            block,
            columns: Mutex::new(ColumnCache::default()),
        })
    }

    pub fn initial_state(&self) -> ContactState {
        ContactState { pairs: vec![vec![Pair::default(); self.nodes.len()]; self.tools.len()] }
    }

    /// The tool samples at t = 0 (no force).
    pub fn initial_samples(&self) -> Vec<ToolSample> {
        (0..self.tools.len())
            .map(|_| ToolSample {
                t_s: 0.0,
                force_n: [0.0; 3],
                normal_n: 0.0,
                tangential_n: 0.0,
                area_mm2: 0.0,
                nodes: Vec::new(),
            })
            .collect()
    }

    /// The lift of tool `c` (canonical) at the step's start and end [mm]: the
    /// machine's deflection on the crosshead tools, zero on the others.
    fn lift(&self, c: usize, input: &StepInput<'_>) -> [f64; 2] {
        if self.crosshead[c] {
            input.lift
        } else {
            [0.0; 2]
        }
    }

    /// The force the machine measures at a step end [N]: the sum over the
    /// crosshead tools of the y components of the forces on them (compression
    /// positive), as `samples` lists them (listed order).
    pub fn crosshead_force(&self, samples: &[ToolSample]) -> f64 {
        (0..self.tools.len()).filter(|&c| self.crosshead[c]).map(|c| samples[self.order[c]].force_n[1]).sum()
    }

    /// Whether a crosshead tool holds at `t1` (the deflection acts then).
    pub fn crosshead_engaged(&self, t1: f64) -> bool {
        (0..self.tools.len()).any(|c| self.crosshead[c] && self.engaged(c, t1))
    }

    /// Whether the tool `c` (canonical) holds at `t1`.
    fn engaged(&self, c: usize, t1: f64) -> bool {
        t1 <= self.tools[c].tool.release_s * (1.0 + 1e-12)
    }

    /// The adhesion of candidate `j` against tool `c` whose outward normal at the
    /// node's closest point is `normal`: the strength `sigma_a A` with `A` the
    /// node's facet shares projected on the tool's normal (`sum a_f max(0, -n_f .
    /// normal)`: a flat plate sees the top face's facets whole and the sides not
    /// at all), so that a uniform traction `sigma_a` over the face is exactly the
    /// nodes' strengths.
    fn cohesion(&self, c: usize, j: usize, normal: [f64; 3]) -> Option<Cohesion> {
        let [sigma, opening_mm] = self.adhesion?;
        if !self.adheres[c] {
            return None;
        }
        let area: f64 = self.facets[j].iter().map(|(n, a)| a * (-dot(*n, normal)).max(0.0)).sum();
        Some(Cohesion { strength_n: sigma * area, opening_mm })
    }

    /// Whether adhesion acts on a tool engaged at `t1`.
    fn adhesive(&self, t1: f64) -> bool {
        self.adheres.iter().enumerate().any(|(c, &a)| a && self.engaged(c, t1))
    }

    /// Solves one step with contact. `solve(hash, penalty, rhs_extra)` must solve the
    /// step with the penalty values `penalty()` (on the pattern, actual scale; equal
    /// for equal `hash`, so a factorization may be kept) added to the matrix and
    /// `rhs_extra` (per dof) added to the right-hand side, returning the full
    /// displacement.
    pub fn settle(
        &self,
        input: &StepInput<'_>,
        state0: &ContactState,
        u_start: Vec<f64>,
        solve: &mut PenalizedSolve<'_>,
        eliminate: &mut EliminatedSolve<'_>,
        nnz: usize,
    ) -> Result<Settled, PressError> {
        let d = self.dim;
        let (t0, t1) = (input.t0, input.t1);
        // Carry anchors with their tools to t1, and predict that stuck nodes move
        // with them: started where they were, a stuck node's trial traction would be
        // the penalty times the tool's whole increment, far outside the friction
        // cone, and every stuck node would start the step slipping.
        let mut state = state0.clone();
        let mut u = u_start;
        let mut moved = vec![false; self.nodes.len()];
        for (c, pairs) in state.pairs.iter_mut().enumerate() {
            if !self.engaged(c, t1) {
                pairs.iter_mut().for_each(|p| *p = Pair::default());
                continue;
            }
            for (j, p) in pairs.iter_mut().enumerate() {
                if let Some(a) = p.anchor {
                    let carried = self.tools[c].carry(a, t0, t1, self.lift(c, input));
                    if p.status == Status::Stuck && !moved[j] {
                        moved[j] = true;
                        let i = self.nodes[j] as usize;
                        for k in 0..d {
                            if !self.held[j][k] {
                                u[i * d + k] += carried[k] - a[k];
                            }
                        }
                    }
                    p.anchor = Some(carried);
                }
                p.slip_direction = [0.0; 3];
                p.opening_trial = p.opening_max;
            }
        }
        // A pair in normal contact at the step's start (frictionless, slipping, or
        // with adhesion bonded) starts the step on its tool, moved along the
        // normal with it (as a stuck pair with its anchor). Left where it was, a
        // retreating tool opens a gap of its whole increment in the first pass:
        // every pair opens, the first solve springs the body back clear of the
        // tool, and the iteration restarts from there. With adhesion every bonded
        // pair would start the step torn off; without, a sphere lifting off an
        // elastic sweet does not settle (tests/contact.rs,
        // `sphere_lifts_off_an_elastic_sweet`) and a punch's unloading with a
        // slider takes thousands of adaptive steps (`tests/material_point_contact.rs`).
        // A pair that truly separates opens in the iteration as before.
        for (c, pairs) in state.pairs.iter().enumerate() {
            if !self.engaged(c, t1) || self.tools[c].tool.contact == ToolContact::Glued {
                continue;
            }
            for (j, p) in pairs.iter().enumerate() {
                if moved[j] || p.status != Status::Normal || (self.adheres[c] && p.opening_max != 0.0) {
                    continue;
                }
                moved[j] = true;
                let i = self.nodes[j];
                let prox =
                    self.tools[c].proximity(self.position(input, &u, i), t1, self.lift(c, input)[1], self.planar);
                for k in 0..d {
                    if !self.held[j][k] {
                        u[i as usize * d + k] -= prox.gap * prox.normal[k];
                    }
                }
            }
        }
        let penalty: Vec<f64> = self
            .nodes
            .iter()
            .map(|&i| (0..d).map(|k| input.diagonal[i as usize * d + k]).fold(0.0, f64::max) * KAPPA)
            .collect();
        // Flat tools that hold exactly: one solve per step while the set holds.
        if let Some(settled) = self.settle_exact(input, &state, &u, &penalty, eliminate)? {
            return Ok(settled);
        }
        // The statuses the last solve used: when they hold again at its result, that
        // result solves the penalized problem for the current multipliers (exactly
        // for flat tools), and the multipliers take their Uzawa update.
        let mut used: Option<Vec<Vec<Status>>> = None;
        // A plate's faces are flat: one solve settles its pairs for given statuses.
        // A curved tool needs Newton steps until the displacement stops changing.
        let all_flat = self
            .tools
            .iter()
            .enumerate()
            .all(|(c, t)| !self.engaged(c, t1) || matches!(t.tool.shape, super::tools::ToolShape::Plate { .. }));
        let mut last_change = f64::INFINITY;
        let smallest_size = self.size.iter().copied().fold(f64::INFINITY, f64::min);
        // The explicit cohesive tractions converge linearly (at the ratio of the
        // softening stiffness to the specimen's): allow them more solves.
        let max_iterations = if self.adhesive(t1) { ADHESION_ITERATIONS } else { MAX_ITERATIONS };
        for iteration in 1..=max_iterations {
            let cohesive_before: Vec<Vec<f64>> = state
                .pairs
                .iter()
                .enumerate()
                .map(
                    |(c, pairs)| {
                        if self.adheres[c] {
                            pairs.iter().map(|p| p.cohesive_n).collect()
                        } else {
                            Vec::new()
                        }
                    },
                )
                .collect();
            // Only friction tools' slip tractions are read (see `slip_settled`).
            let slip_before: Vec<Vec<[f64; 3]>> = self
                .tools
                .iter()
                .zip(&state.pairs)
                .map(|(t, pairs)| match t.tool.contact {
                    ToolContact::Friction(_) => pairs.iter().map(|p| p.slip_force).collect(),
                    _ => Vec::new(),
                })
                .collect();
            let mut pass = self.assemble(&mut state, input, &u, t1, &penalty, true);
            let slip_settled = self.slip_settled(&state, &slip_before, input, &u, &penalty)
                && self.cohesive_unsettled(&state, &cohesive_before, input, &u).is_none();
            let increment = u.iter().zip(input.u0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            // Done when a step changes the displacement by a millionth of the step's
            // increment, or by no more than the solves' rounding (1e-9 of the
            // smallest element), whichever is larger.
            let newton_done = slip_settled && (all_flat || last_change <= (1e-6 * increment).max(1e-9 * smallest_size));
            // Curved tools: Newton converges linearly there (the normal turns with the
            // node), and converging it to 1e-6 for multipliers that the update then
            // moves far wastes solves; so the multipliers take their update once the
            // displacement settles to 1e-3 of the increment. A step still ends only
            // on the full test below.
            let early = !all_flat && slip_settled && last_change <= 1e-3 * increment;
            if used.as_ref() == Some(&pass.statuses) && (newton_done || early) {
                let error = self.constraint_error(input, &u, &state, t1);
                let pulls = self.pulls(&state, input, &u, t1, &penalty);
                if newton_done && error.0 <= 1.0 && !pulls {
                    return Ok(self.finish(input, u, state, t1, &penalty));
                }
                if newton_done || error.0 > 1.0 {
                    self.update_multipliers(&mut state, input, &u, t1, &penalty);
                    // The statuses held: a pair still pulled onto the tool within the
                    // opening band truly separates.
                    pass = self.assemble(&mut state, input, &u, t1, &penalty, false);
                }
            }
            if iteration == max_iterations {
                let (_, mut c, mut nodes) = self.constraint_error(input, &u, &state, t1);
                if nodes.is_empty() {
                    // The gaps hold: what did not settle are statuses flipping or
                    // slip tractions still moving; name those nodes.
                    (c, nodes) =
                        self.unsettled(used.as_deref(), &pass.statuses, &state, &slip_before, input, &u, &penalty);
                }
                if nodes.is_empty() {
                    // Or cohesive tractions still moving.
                    (c, nodes) = self.cohesive_unsettled(&state, &cohesive_before, input, &u).unwrap_or((c, nodes));
                }
                return Err(PressError::ContactNotSettled {
                    step: input.step,
                    time_s: t1,
                    tool: self.tools[c].tool.name.clone(),
                    nodes,
                });
            }
            let Pass { statuses, rhs, blocks, signature } = pass;
            used = Some(statuses);
            let values = || {
                let mut v = vec![0.0; nnz];
                for (j, b) in blocks.iter().enumerate() {
                    for a in 0..d {
                        for bb in 0..d {
                            v[self.block[j][a * d + bb]] += b[a][bb];
                        }
                    }
                }
                v
            };
            let low_rank = if all_flat || !self.low_rank {
                None
            } else {
                self.low_rank_solve(input, solve, &blocks, &rhs, &u, nnz)?
            };
            let next = match low_rank {
                Some(next) => next,
                None => solve(hash_signature(&signature), &values, &rhs, None)?,
            };
            last_change = next.iter().zip(&u).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            u = next;
        }
        unreachable!("the loop returns on its last iteration")
    }

    /// The exact path (module doc, "Flat tools: exact elimination"): every tool
    /// engaged at `t1` a plate that does not turn, glued or frictionless. The held dofs are eliminated
    /// at their values (glued: all of a node's free dofs at its anchor; normal
    /// contact: the dof along the face's normal, a coordinate axis, on the face),
    /// their reactions are the multipliers, and the active set is that of the
    /// primal-dual active set method with the penalty as its constant (the penalty
    /// law's trial `lambda_n - k g > 0` without the band). The step ends when a
    /// solve leaves the statuses and held values as they were: one solve while the
    /// set does not change. `None` hands the step to the penalties from the same
    /// start: a tool that needs them, a dof held by two tools, or a set not
    /// settled in [`EXACT_ITERATIONS`] solves.
    fn settle_exact(
        &self,
        input: &StepInput<'_>,
        state0: &ContactState,
        u_start: &[f64],
        penalty: &[f64],
        eliminate: &mut EliminatedSolve<'_>,
    ) -> Result<Option<Settled>, PressError> {
        let (d, t1) = (self.dim, input.t1);
        let eligible = self.tools.iter().enumerate().all(|(c, t)| {
            // A plate that never turns: its faces' normals are the axes.
            !self.engaged(c, t1)
                || (matches!(t.tool.shape, super::tools::ToolShape::Plate { .. })
                    && t.tool.keyframes.iter().all(|k| k.rotation_rad == [0.0; 3])
                    && matches!(t.tool.contact, ToolContact::Glued | ToolContact::Frictionless)
                    // Adhesion's cohesive branch is a traction, not a held dof.
                    && !self.adheres[c])
        });
        if !eligible {
            return Ok(None);
        }
        let mut state = state0.clone();
        let mut u = u_start.to_vec();
        // The held values and statuses of the last solve.
        type Used = (Vec<(usize, f64)>, Vec<Vec<Status>>);
        let mut used: Option<Used> = None;
        for _ in 0..EXACT_ITERATIONS {
            // Held dofs: (dof, value, canonical tool, candidate).
            let mut held: Vec<(usize, f64, usize, usize)> = Vec::new();
            let mut statuses = Vec::with_capacity(self.tools.len());
            for (c, placed) in self.tools.iter().enumerate() {
                let engaged = self.engaged(c, t1);
                let mut st = Vec::with_capacity(self.nodes.len());
                for (j, &i) in self.nodes.iter().enumerate() {
                    if !engaged {
                        st.push(Status::Open);
                        continue;
                    }
                    let pair = &mut state.pairs[c][j];
                    let x = self.position(input, &u, i);
                    let prox = placed.proximity(x, t1, self.lift(c, input)[1], self.planar);
                    let rest = &input.rest[i as usize];
                    let dof = |k: usize| i as usize * d + k;
                    let status = if placed.tool.contact == ToolContact::Glued {
                        // As the penalty law: a node sticks where it first touches.
                        if pair.anchor.is_none() && prox.gap <= 0.0 {
                            pair.anchor = Some(prox.point);
                        }
                        match pair.anchor {
                            Some(a) => {
                                held.extend(
                                    (0..d).filter(|&k| !self.held[j][k]).map(|k| (dof(k), a[k] - rest[k], c, j)),
                                );
                                Status::Stuck
                            }
                            None => Status::Open,
                        }
                    } else if pair.lambda_n - penalty[j] * prox.gap > 0.0 {
                        // The face's axis (the computed normal may be off it by rounding).
                        let a = (0..d).fold(0, |a, k| if prox.normal[k].abs() > prox.normal[a].abs() { k } else { a });
                        pair.matrix_normal =
                            std::array::from_fn(|k| if k == a { prox.normal[a].signum() } else { 0.0 });
                        if !self.held[j][a] {
                            held.push((dof(a), prox.point[a] - rest[a], c, j));
                        }
                        Status::Normal
                    } else {
                        Status::Open
                    };
                    if status == Status::Open {
                        pair.lambda_n = 0.0;
                        pair.lambda_t = [0.0; 3];
                    }
                    pair.status = status;
                    st.push(status);
                }
                statuses.push(st);
            }
            held.sort_by_key(|h| h.0);
            if held.windows(2).any(|w| w[0].0 == w[1].0) {
                return Ok(None);
            }
            let values: Vec<(usize, f64)> = held.iter().map(|h| (h.0, h.1)).collect();
            if let Some((last, last_statuses)) = used.as_ref() {
                // Flat faces: a node on the same face is held at the same value.
                let same_values = last.len() == values.len()
                    && last
                        .iter()
                        .zip(&held)
                        .all(|(a, h)| a.0 == h.0 && (a.1 - h.1).abs() <= TOLERANCE * self.size[h.3]);
                if same_values && *last_statuses == statuses {
                    return Ok(Some(self.finish(input, u, state, t1, penalty)));
                }
            }
            let hash = {
                use std::hash::{Hash, Hasher};
                let mut h = std::collections::hash_map::DefaultHasher::new();
                values.iter().for_each(|v| v.0.hash(&mut h));
                h.finish()
            };
            let (next, reactions) = eliminate(hash, &values)?;
            // The reactions are the multipliers (zero on dofs the support holds).
            for (c, pairs) in state.pairs.iter_mut().enumerate() {
                if self.engaged(c, t1) {
                    for p in pairs.iter_mut() {
                        p.lambda_n = 0.0;
                        p.lambda_t = [0.0; 3];
                    }
                }
            }
            for (&(dof, _, c, j), r) in held.iter().zip(reactions) {
                let pair = &mut state.pairs[c][j];
                let k = dof % d;
                if self.tools[c].tool.contact == ToolContact::Glued {
                    pair.lambda_t[k] = r;
                } else {
                    pair.lambda_n = r * pair.matrix_normal[k];
                }
            }
            u = next;
            used = Some((values, statuses));
        }
        Ok(None)
    }

    /// Solves `(A + P) u = b + rhs` through the Woodbury identity with the factor of
    /// the unpenalized matrix `A`: with `E` the penalized free dofs, `G = A^{-1} E`
    /// (columns kept from step to step while `A`'s factor stays), `S = E^T G`, and the
    /// right-hand side split as `rhs = r + E P E^T u_old` (the Newton step's `P u_old`;
    /// left in, its size `k u` would cost `y` six digits), `y = A^{-1}(b + r)` and
    /// the dense system `(I + P S) z = P E^T (u_old - y)` give `u = y + G z`. One sparse solve per
    /// iteration, plus one per new column: a curved tool's normals turn and its set
    /// grows at every Newton step, which would otherwise refactor the matrix each
    /// time. `None` when the columns would not fit [`COLUMN_BUDGET`] (the caller
    /// then refactors the penalized matrix) or the dense system is singular.
    fn low_rank_solve(
        &self,
        input: &StepInput<'_>,
        solve: &mut PenalizedSolve<'_>,
        blocks: &[[[f64; 3]; 3]],
        rhs: &[f64],
        u_old: &[f64],
        nnz: usize,
    ) -> Result<Option<Vec<f64>>, PressError> {
        let d = self.dim;
        let ndof = rhs.len();
        // The penalized free dofs: (dof, candidate, component).
        let mut dofs: Vec<(usize, usize, usize)> = Vec::new();
        for (j, b) in blocks.iter().enumerate() {
            if b.iter().flatten().all(|&v| v == 0.0) {
                continue;
            }
            for a in 0..d {
                if !self.held[j][a] {
                    dofs.push((self.nodes[j] as usize * d + a, j, a));
                }
            }
        }
        if dofs.len() * ndof > COLUMN_BUDGET {
            return Ok(None);
        }
        let zero = || vec![0.0; nnz];
        let p_at = |r: usize, c: usize| {
            let ((_, jr, ar), (_, jc, ac)) = (dofs[r], dofs[c]);
            if jr == jc {
                blocks[jr][ar][ac]
            } else {
                0.0
            }
        };
        let mut r = rhs.to_vec();
        for (row, &(dof, j, _)) in dofs.iter().enumerate() {
            for (col, &(other, jc, _)) in dofs.iter().enumerate() {
                if jc == j {
                    r[dof] -= p_at(row, col) * u_old[other];
                }
            }
        }
        let y = solve(PLAIN, &zero, &r, None)?;
        if dofs.is_empty() {
            return Ok(Some(y));
        }
        let mut cache = self.columns.lock().unwrap_or_else(|e| e.into_inner());
        if cache.key != Some(input.factor_key) {
            cache.columns.clear();
            cache.key = Some(input.factor_key);
        }
        let mut missing: Vec<usize> = dofs.iter().map(|x| x.0).filter(|k| !cache.columns.contains_key(k)).collect();
        if (cache.columns.len() + missing.len()) * ndof > COLUMN_BUDGET {
            cache.columns.clear();
            missing = dofs.iter().map(|x| x.0).collect();
        }
        if !missing.is_empty() {
            let mut e = vec![0.0; ndof * missing.len()];
            for (c, &dof) in missing.iter().enumerate() {
                e[c * ndof + dof] = 1.0;
            }
            let x = solve(PLAIN, &zero, &e, Some(missing.len()))?;
            for (c, &dof) in missing.iter().enumerate() {
                cache.columns.insert(dof, x[c * ndof..(c + 1) * ndof].iter().map(|v| v * input.scale).collect());
            }
        }
        let m = dofs.len();
        let columns: Vec<&Vec<f64>> = dofs.iter().map(|x| &cache.columns[&x.0]).collect();
        let p = DMatrix::from_fn(m, m, p_at);
        let s = DMatrix::from_fn(m, m, |r, c| columns[c][dofs[r].0] / input.scale);
        let system = DMatrix::identity(m, m) + &p * s;
        let lag = DVector::from_iterator(m, dofs.iter().map(|x| u_old[x.0] - y[x.0]));
        let Some(z) = system.lu().solve(&(p * lag)) else {
            return Ok(None);
        };
        let mut u = y;
        for (c, column) in columns.iter().enumerate() {
            let zc = z[c] / input.scale;
            if zc != 0.0 {
                u.iter_mut().zip(column.iter()).for_each(|(ui, g)| *ui += g * zc);
            }
        }
        Ok(Some(u))
    }

    /// Statuses, forces and penalty blocks at `u` for the current multipliers: the
    /// right-hand side `F(u) + P u` and the blocks `P` of the Newton step.
    #[allow(clippy::too_many_arguments)]
    fn assemble(
        &self,
        state: &mut ContactState,
        input: &StepInput<'_>,
        u: &[f64],
        t1: f64,
        penalty: &[f64],
        band: bool,
    ) -> Pass {
        let d = self.dim;
        let mut rhs = vec![0.0; u.len()];
        let mut blocks: Vec<[[f64; 3]; 3]> = vec![[[0.0; 3]; 3]; self.nodes.len()];
        let mut statuses: Vec<Vec<Status>> = Vec::with_capacity(self.tools.len());
        let mut signature = Vec::with_capacity(self.nodes.len() * self.tools.len());
        for (c, placed) in self.tools.iter().enumerate() {
            let engaged = self.engaged(c, t1);
            let mut st = Vec::with_capacity(self.nodes.len());
            for (j, &i) in self.nodes.iter().enumerate() {
                if !engaged {
                    st.push(Status::Open);
                    signature.push((Status::Open, [0; 3]));
                    continue;
                }
                let x = self.position(input, u, i);
                let prox = placed.proximity(x, t1, self.lift(c, input)[1], self.planar);
                let k = penalty[j];
                let n = prox.normal;
                let band = if band { OPEN_BAND * self.size[j] } else { 0.0 };
                let cohesion = self.cohesion(c, j, n);
                let pair = &mut state.pairs[c][j];
                let (status, force) = law(placed.tool.contact, pair, &prox, x, k, band, cohesion);
                if matches!(status, Status::Open | Status::Cohesive) {
                    pair.lambda_n = 0.0;
                    pair.lambda_t = [0.0; 3];
                }
                pair.status = status;
                if status != Status::Open
                    && (pair.matrix_normal == [0.0; 3] || dist(pair.matrix_normal, n) > NORMAL_REUSE)
                {
                    pair.matrix_normal = n;
                }
                let m = pair.matrix_normal;
                // The matrix block: k I when stuck, k m m^T for normal contact, the
                // secant s m m^T of an unloading cohesive pair (0 when softening).
                let mut mblock = match status {
                    Status::Open => [[0.0; 3]; 3],
                    Status::Normal => outer(m, m, k),
                    Status::Stuck => diag(k),
                    Status::Cohesive => outer(m, m, pair.cohesive_stiffness),
                };
                // A slipping pair in 3D: the return map's tangent across the slip,
                // `k (mu N / |trial|) (I - n n^T - s s^T)`, which holds the slip's
                // direction (its size along the slip is fixed at mu N).
                let slip = norm(pair.slip_force);
                let across = status == Status::Normal && d == 3 && slip > 0.0;
                if across {
                    let s = pair.slip_force.map(|c| c / slip);
                    let kt = k * pair.slip_scale;
                    for a in 0..3 {
                        for b in 0..3 {
                            let id = if a == b { 1.0 } else { 0.0 };
                            mblock[a][b] += kt * (id - m[a] * m[b] - s[a] * s[b]);
                        }
                    }
                }
                for a in 0..d {
                    let mut v = force[a];
                    for b in 0..d {
                        v += mblock[a][b] * u[i as usize * d + b];
                        blocks[j][a][b] += mblock[a][b];
                    }
                    rhs[i as usize * d + a] += v;
                }
                st.push(status);
                let q = |x: f64| (x / NORMAL_REUSE).round() as i64;
                signature.push((status, if status == Status::Open { [0; 3] } else { m.map(q) }));
                if status == Status::Cohesive {
                    signature.push((status, [pair.cohesive_stiffness.to_bits() as i64, 0, 0]));
                }
                if across {
                    // The exact values: a stale tangent here stalls the iteration.
                    let bits = |x: f64| x.to_bits() as i64;
                    signature.push((status, pair.slip_force.map(bits)));
                    signature.push((status, [bits(pair.slip_scale), bits(k), 0]));
                }
            }
            statuses.push(st);
        }
        Pass { statuses, rhs, blocks, signature }
    }

    /// Slip tractions are explicit in the iteration: they have settled when the
    /// last solve changed none by more than [`SLIP_TOLERANCE`] of itself, or by more
    /// than the rounding of the penalty force (`mu k` times the rounding of the
    /// node's position).
    fn slip_settled(
        &self,
        state: &ContactState,
        before: &[Vec<[f64; 3]>],
        input: &StepInput<'_>,
        u: &[f64],
        penalty: &[f64],
    ) -> bool {
        self.tools.iter().enumerate().all(|(c, placed)| {
            let ToolContact::Friction(mu) = placed.tool.contact else {
                return true;
            };
            self.nodes.iter().enumerate().all(|(j, &i)| {
                !self.slip_moves(mu, state.pairs[c][j].slip_force, before[c][j], input, u, i, penalty[j])
            })
        })
    }

    /// The first adhesive tool and its nodes whose cohesive force changed in the
    /// last pass by more than [`COHESIVE_TOLERANCE`] of the node's strength (or the
    /// rounding of the position times the softening stiffness); `None` when all
    /// have settled.
    fn cohesive_unsettled(
        &self,
        state: &ContactState,
        before: &[Vec<f64>],
        input: &StepInput<'_>,
        u: &[f64],
    ) -> Option<(usize, Vec<u32>)> {
        let [sigma, opening] = self.adhesion?;
        (0..self.tools.len()).filter(|&c| self.adheres[c]).find_map(|c| {
            let nodes: Vec<u32> = self
                .nodes
                .iter()
                .enumerate()
                .filter(|&(j, &i)| {
                    let strength = sigma * self.facets[j].iter().map(|f| f.1).sum::<f64>();
                    let rounding = 64.0 * f64::EPSILON * norm(self.position(input, u, i)) * strength / opening;
                    let change = (state.pairs[c][j].cohesive_n - before[c][j]).abs();
                    change > (COHESIVE_TOLERANCE * strength).max(rounding)
                })
                .map(|(_, &i)| i)
                .collect();
            (!nodes.is_empty()).then_some((c, nodes))
        })
    }

    /// Whether a friction pair's slip traction moved between two passes by more
    /// than [`SLIP_TOLERANCE`] of itself and the rounding of its penalty spring.
    #[allow(clippy::too_many_arguments)]
    fn slip_moves(
        &self,
        mu: f64,
        now: [f64; 3],
        before: [f64; 3],
        input: &StepInput<'_>,
        u: &[f64],
        i: u32,
        penalty: f64,
    ) -> bool {
        let rounding = 64.0 * f64::EPSILON * norm(self.position(input, u, i)) * penalty * mu;
        dist(now, before) > (SLIP_TOLERANCE * norm(now)).max(rounding)
    }

    /// The nodes of the first tool whose status changed between the last two
    /// passes or whose slip traction still moves (as [`Self::slip_settled`]
    /// measures it): what a step that does not settle names when every gap holds.
    #[allow(clippy::too_many_arguments)]
    fn unsettled(
        &self,
        used: Option<&[Vec<Status>]>,
        statuses: &[Vec<Status>],
        state: &ContactState,
        slip_before: &[Vec<[f64; 3]>],
        input: &StepInput<'_>,
        u: &[f64],
        penalty: &[f64],
    ) -> (usize, Vec<u32>) {
        for (c, placed) in self.tools.iter().enumerate() {
            let mu = match placed.tool.contact {
                ToolContact::Friction(mu) => Some(mu),
                _ => None,
            };
            let nodes: Vec<u32> = self
                .nodes
                .iter()
                .enumerate()
                .filter(|&(j, &i)| {
                    let flipped = used.is_some_and(|used| used[c][j] != statuses[c][j]);
                    let slipping = mu.is_some_and(|mu| {
                        self.slip_moves(mu, state.pairs[c][j].slip_force, slip_before[c][j], input, u, i, penalty[j])
                    });
                    flipped || slipping
                })
                .map(|(_, &i)| i)
                .collect();
            if !nodes.is_empty() {
                return (c, nodes);
            }
        }
        (0, Vec::new())
    }

    /// Whether a pair kept in contact by the opening band pulls on its tool (a
    /// negative normal force): it must open before the step may end.
    fn pulls(&self, state: &ContactState, input: &StepInput<'_>, u: &[f64], t1: f64, penalty: &[f64]) -> bool {
        self.tools.iter().enumerate().any(|(c, placed)| {
            placed.tool.contact != ToolContact::Glued
                && self.engaged(c, t1)
                && self.nodes.iter().enumerate().any(|(j, &i)| {
                    let p = &state.pairs[c][j];
                    matches!(p.status, Status::Normal | Status::Stuck) && {
                        let x = self.position(input, u, i);
                        let prox = placed.proximity(x, t1, self.lift(c, input)[1], self.planar);
                        // A bonded pair pulls past its strength beyond the rounding
                        // band within which it keeps its status (see `law`).
                        let limit =
                            if p.tension_cap > 0.0 { -p.tension_cap - penalty[j] * ROUNDING * norm(x) } else { 0.0 };
                        p.lambda_n - penalty[j] * prox.gap < limit
                    }
                })
        })
    }

    /// Candidate `j`'s share of the area in contact with a tool whose outward
    /// normal at it is `tool_normal` [mm^2] (see [`ToolSample::area_mm2`]): `1/D`
    /// of each boundary facet around it that faces the tool (its outward normal
    /// makes a cosine above [`FACING_COSINE`] with `-tool_normal`).
    ///
    /// The share of the facets that face the tool, not the node's whole tributary
    /// area: a node on a plate's rim also carries side-wall facets that meet the
    /// plate along an edge only, and counting them would overstate a 10 mm
    /// cylinder's contact under a plate by 14 % on a 1.5 mm mesh. Counting only
    /// facets whose nodes all touch would miss the rim of a curved contact by
    /// half an element and report no area while a single node touches. A facet
    /// that faces the tool counts in full, not weighted by the angle, so that the
    /// area changes only when nodes come or go (a node sliding along a sphere
    /// does not move it). It is a report only: no force depends on it.
    fn contact_area(&self, j: usize, tool_normal: [f64; 3]) -> f64 {
        self.area_facets[j].iter().filter(|(n, _)| -dot(*n, tool_normal) > FACING_COSINE).map(|(_, share)| share).sum()
    }

    fn position(&self, input: &StepInput<'_>, u: &[f64], i: u32) -> [f64; 3] {
        let d = self.dim;
        let r = &input.rest[i as usize];
        std::array::from_fn(|k| if k < d { r[k] + u[i as usize * d + k] } else { 0.0 })
    }

    /// The multipliers after a solve: `lambda <- lambda - k g` for the pairs in contact.
    fn update_multipliers(&self, state: &mut ContactState, input: &StepInput<'_>, u: &[f64], t1: f64, k: &[f64]) {
        for (c, placed) in self.tools.iter().enumerate() {
            for (j, &i) in self.nodes.iter().enumerate() {
                if matches!(state.pairs[c][j].status, Status::Open | Status::Cohesive) {
                    continue;
                }
                let x = self.position(input, u, i);
                let prox = placed.proximity(x, t1, self.lift(c, input)[1], self.planar);
                let cohesion = self.cohesion(c, j, prox.normal);
                let pair = &mut state.pairs[c][j];
                let (_, force) = law(placed.tool.contact, pair, &prox, x, k[j], OPEN_BAND * self.size[j], cohesion);
                set_multipliers(placed.tool.contact, pair, &prox, force);
            }
        }
    }

    /// The largest constraint error relative to its tolerance, its tool, and the
    /// nodes over the tolerance. The tolerance is 1e-11 of the local element size,
    /// tightened to 1e-10 of the step's largest displacement increment (a tiny step
    /// must still be resolved: its viscous forces are the increment over the step)
    /// but not below the rounding of the positions.
    fn constraint_error(
        &self,
        input: &StepInput<'_>,
        u: &[f64],
        state: &ContactState,
        t1: f64,
    ) -> (f64, usize, Vec<u32>) {
        let increment = u.iter().zip(input.u0).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        let mut worst = (0.0, 0usize);
        let mut nodes = Vec::new();
        for (c, placed) in self.tools.iter().enumerate() {
            if !self.engaged(c, t1) {
                continue;
            }
            for (j, &i) in self.nodes.iter().enumerate() {
                let pair = &state.pairs[c][j];
                let x = self.position(input, u, i);
                let prox = placed.proximity(x, t1, self.lift(c, input)[1], self.planar);
                let mut e = match pair.status {
                    Status::Open | Status::Cohesive => (-prox.gap).max(0.0),
                    _ => prox.gap.abs(),
                };
                if pair.status == Status::Stuck {
                    if let Some(a) = pair.anchor {
                        let s = sub(x, a);
                        // Friction sticks through a penalty spring (elastic slip
                        // `|traction| / k`); only glued pairs must not move at all.
                        if placed.tool.contact == ToolContact::Glued {
                            e = norm(s);
                        }
                    }
                }
                let floor = 16.0 * f64::EPSILON * norm(x).max(norm(prox.point));
                let tolerance = match placed.tool.contact {
                    // Friction's slip traction couples to the normal force outside
                    // the symmetric Newton matrix, so its iteration converges only
                    // linearly: it stops at 1e-8 of the size (the bound is 1e-6).
                    ToolContact::Friction(_) => FRICTION_TOLERANCE * self.size[j],
                    _ => (TOLERANCE * self.size[j]).min((1e-10 * increment).max(floor)),
                };
                let rel = e / tolerance;
                if rel > 1.0 {
                    nodes.push(i);
                }
                if rel > worst.0 {
                    worst = (rel, c);
                }
            }
        }
        (worst.0, worst.1, nodes)
    }

    /// Moves what the free rows leave unbalanced (`imbalance = A u - b - F`, the
    /// multipliers' rounding) into the contact forces of the tools the nodes touch
    /// (the first, in canonical order), so that tool forces are the equilibrium
    /// reactions, as accurate as the displacement.
    pub fn rebalance(&self, settled: &mut Settled, imbalance: &[f64]) {
        let d = self.dim;
        for (j, &i) in self.nodes.iter().enumerate() {
            let Some(c) = (0..self.tools.len()).find(|&c| settled.state.pairs[c][j].status != Status::Open) else {
                continue;
            };
            let sample = &mut settled.samples[self.order[c]];
            for k in 0..d {
                let r = imbalance[i as usize * d + k];
                sample.force_n[k] -= r;
                settled.forces[i as usize * d + k] += r;
            }
        }
    }

    fn finish(&self, input: &StepInput<'_>, u: Vec<f64>, mut state: ContactState, t1: f64, penalty: &[f64]) -> Settled {
        let d = self.dim;
        let mut forces = vec![0.0; u.len()];
        let mut samples = vec![
            ToolSample {
                t_s: t1,
                force_n: [0.0; 3],
                normal_n: 0.0,
                tangential_n: 0.0,
                area_mm2: 0.0,
                nodes: Vec::new()
            };
            self.tools.len()
        ];
        for (c, placed) in self.tools.iter().enumerate() {
            let sample = &mut samples[self.order[c]];
            let mut tangential_sum = [0.0; 3];
            for (j, &i) in self.nodes.iter().enumerate() {
                let pair = &mut state.pairs[c][j];
                if pair.status == Status::Open {
                    pair.anchor = None;
                    pair.lambda_n = 0.0;
                    pair.lambda_t = [0.0; 3];
                    pair.matrix_normal = [0.0; 3];
                    pair.opening_max = f64::INFINITY;
                    pair.opening_trial = f64::INFINITY;
                    continue;
                }
                let x = self.position(input, &u, i);
                let prox = placed.proximity(x, t1, self.lift(c, input)[1], self.planar);
                if pair.status != Status::Cohesive {
                    if let ToolContact::Friction(_) = placed.tool.contact {
                        // The tangential multiplier is not part of the friction law (the
                        // anchor is): take the traction the law gives at the result.
                        let cohesion = self.cohesion(c, j, prox.normal);
                        let pair = &mut state.pairs[c][j];
                        let band = OPEN_BAND * self.size[j];
                        let (_, f) = law(placed.tool.contact, pair, &prox, x, penalty[j], band, cohesion);
                        set_multipliers(placed.tool.contact, pair, &prox, f);
                    }
                }
                let pair = &mut state.pairs[c][j];
                let (f_n, f_t) = match placed.tool.contact {
                    ToolContact::Glued => {
                        let f = pair.lambda_t;
                        let fnn = dot(f, prox.normal);
                        (fnn, tangential(f, prox.normal))
                    }
                    _ if pair.status == Status::Cohesive => (pair.cohesive_n, [0.0; 3]),
                    _ => (pair.lambda_n, pair.lambda_t),
                };
                // Adhesion's history, committed at the step's end: a pair in contact
                // is bonded (it re-adheres whenever it touches again); a cohesive one
                // keeps its largest opening.
                if self.adheres[c] {
                    pair.opening_max = match pair.status {
                        Status::Cohesive => pair.opening_trial.max(prox.gap.max(0.0)),
                        _ => 0.0,
                    };
                    pair.opening_trial = pair.opening_max;
                }
                // The force on the specimen is f_n n + f_t; on the tool its opposite.
                for k in 0..3 {
                    let f = f_n * prox.normal[k] + f_t[k];
                    sample.force_n[k] -= f;
                    tangential_sum[k] += f_t[k];
                    if k < d {
                        forces[i as usize * d + k] += f;
                    }
                }
                sample.normal_n += f_n;
                sample.area_mm2 += self.contact_area(j, prox.normal);
                sample.nodes.push(i);
                // A slipping pair's anchor moves along with it: to where the
                // traction is the penalty times the elastic slip.
                if pair.status == Status::Normal && matches!(placed.tool.contact, ToolContact::Friction(_)) {
                    let k = penalty[j];
                    pair.anchor = Some(std::array::from_fn(|m| prox.point[m] + pair.lambda_t[m] / k));
                }
            }
            sample.tangential_n = norm(tangential_sum);
        }
        Settled { state, u, forces, samples }
    }
}

/// Whether `tool` rides on the machine's crosshead, behind its compliance: a
/// tool that is not a floor and that its keyframes move.
pub(crate) fn on_crosshead(tool: &super::Tool) -> bool {
    !tool.floor && tool.travel() > 0.0
}

/// The contact law of one pair at the position `x`: status, the force on the node
/// (3 components) for the current multipliers.
#[allow(clippy::too_many_arguments)]
fn law(
    contact: ToolContact,
    pair: &mut Pair,
    prox: &super::tools::Proximity,
    x: [f64; 3],
    k: f64,
    band: f64,
    cohesion: Option<Cohesion>,
) -> (Status, [f64; 3]) {
    let n = prox.normal;
    // The hysteresis of opening (see OPEN_BAND).
    let opens = |trial: f64, status: Status| {
        if matches!(status, Status::Open | Status::Cohesive) {
            trial <= 0.0
        } else {
            trial <= -k * band
        }
    };
    // Adhesion: a bonded pair (in contact at the last step end) holds the tool in
    // tension down to its strength.
    let cap = match cohesion {
        Some(c) if pair.opening_trial == 0.0 => c.strength_n,
        _ => 0.0,
    };
    pair.tension_cap = cap;
    pair.cohesive_n = 0.0;
    pair.cohesive_stiffness = 0.0;
    // A bonded pair in contact tears off on its multiplier, not on the trial
    // (see `torn`): within the iteration only the opening band's hysteresis. At
    // the peak, where tearing off and staying give the same force, the rounding
    // of the position times the penalty decides (as at friction's cone edge):
    // within that band a pair keeps its status, so a cohesive pair touches again
    // only past it.
    let rounding = k * ROUNDING * norm(x);
    let opens = |trial: f64, status: Status| {
        if cap > 0.0 && !matches!(status, Status::Open | Status::Cohesive) {
            band > 0.0 && trial <= -k * band
        } else if status == Status::Cohesive {
            trial <= rounding
        } else {
            opens(trial, status)
        }
    };
    match contact {
        ToolContact::Glued => {
            if pair.anchor.is_none() {
                if prox.gap > 0.0 {
                    return (Status::Open, [0.0; 3]);
                }
                pair.anchor = Some(prox.point);
            }
            let a = pair.anchor.expect("set above");
            let s = sub(x, a);
            let f = std::array::from_fn(|i| pair.lambda_t[i] - k * s[i]);
            (Status::Stuck, f)
        }
        ToolContact::Frictionless => {
            let trial = pair.lambda_n - k * prox.gap;
            if opens(trial + cap, pair.status) || torn(pair, cap, band, rounding) {
                return detached(pair, cohesion, prox);
            }
            (Status::Normal, n.map(|c| c * trial))
        }
        ToolContact::Friction(mu) => {
            let trial = pair.lambda_n - k * prox.gap;
            if opens(trial + cap, pair.status) || torn(pair, cap, band, rounding) {
                pair.anchor = None;
                pair.slip_force = [0.0; 3];
                return detached(pair, cohesion, prox);
            }
            // Return mapping: the tangential traction is the penalty times the
            // elastic slip from the anchor, capped at mu times the normal force.
            let a = *pair.anchor.get_or_insert(prox.point);
            let s = tangential(sub(x, a), n);
            let tt: [f64; 3] = s.map(|c| -k * c);
            let limit = mu * trial.max(0.0);
            let mag = norm(tt);
            // A slip that reverses its direction within a step has overshot the
            // anchor: the node sticks there for the next iteration. Held on the
            // explicit slip traction it would swing from side to side, because the
            // stick window is only `2 mu N / k` wide.
            // At the cone's edge the status is decided by the rounding of the
            // position times the penalty (`k x eps`, comparable to `mu N` for small
            // `mu`): within that band the pair keeps the status of the last pass.
            let band = k * ROUNDING * norm(x);
            let slipping = pair.status == Status::Normal && pair.slip_direction != [0.0; 3];
            let reverses = slipping && dot(pair.slip_direction, tt) < -band * norm(pair.slip_direction);
            let sticks = if slipping { mag < limit - band || reverses } else { mag <= limit + band };
            if sticks {
                pair.slip_direction = [0.0; 3];
                pair.slip_force = [0.0; 3];
                let f = std::array::from_fn(|i| n[i] * trial + tt[i]);
                (Status::Stuck, f)
            } else {
                let scale = if mag > 0.0 { limit / mag } else { 0.0 };
                pair.slip_direction = tt;
                pair.slip_force = tt.map(|c| c * scale);
                pair.slip_scale = scale;
                let f = std::array::from_fn(|i| n[i] * trial + tt[i] * scale);
                (Status::Normal, f)
            }
        }
    }
}

/// Whether a bonded pair in contact tears off the tool: in the pass right after
/// the multipliers' update (`band` 0), when its updated multiplier pulls beyond
/// its strength. The trial `lambda - k g` there would count the gap twice (the
/// update already took it in), and pairs close to their strength would tear off
/// and touch again in turn.
fn torn(pair: &Pair, cap: f64, band: f64, rounding: f64) -> bool {
    cap > 0.0
        && band == 0.0
        && !matches!(pair.status, Status::Open | Status::Cohesive)
        && pair.lambda_n < -cap - rounding
}

/// A pair off its tool: open, or with adhesion the cohesive traction of an
/// adhered pair (`opening_max < delta_c`). With `delta = max(gap, 0)` and
/// `d0 = opening_max` (the history at the step's start, committed at step ends):
/// on the softening branch (`delta >= d0`) the rigid-linear law
/// `t = -sigma_a A (1 - delta/delta_c)`, explicit in the iteration (its tangent is
/// negative: in the matrix it could make it indefinite); below `d0` the secant
/// back to the origin, `t = -sigma_a A (1 - d0/delta_c) delta/d0`, implicit (its
/// positive stiffness goes into the matrix block); zero once `delta >= delta_c`.
fn detached(pair: &mut Pair, cohesion: Option<Cohesion>, prox: &super::tools::Proximity) -> (Status, [f64; 3]) {
    pair.tension_cap = 0.0;
    if let Some(c) = cohesion {
        let (delta, d0) = (prox.gap.max(0.0), pair.opening_trial);
        pair.opening_trial = d0.max(delta);
        if d0.max(delta) < c.opening_mm {
            let (f, s) = if delta >= d0 {
                (-c.strength_n * (1.0 - delta / c.opening_mm), 0.0)
            } else {
                let s = c.strength_n * (1.0 - d0 / c.opening_mm) / d0;
                (-s * delta, s)
            };
            pair.cohesive_n = f;
            pair.cohesive_stiffness = s;
            return (Status::Cohesive, prox.normal.map(|x| x * f));
        }
    }
    (Status::Open, [0.0; 3])
}

/// Stores the multipliers that the force `f` (from [`law`]) implies: glued pairs
/// keep the whole traction in `lambda_t`, the others split it along the normal
/// (a bonded adhesive pair's normal multiplier may pull, down to its strength).
fn set_multipliers(contact: ToolContact, pair: &mut Pair, prox: &super::tools::Proximity, f: [f64; 3]) {
    if matches!(pair.status, Status::Open | Status::Cohesive) {
        return;
    }
    match contact {
        ToolContact::Glued => pair.lambda_t = f,
        _ => {
            let fnn = dot(f, prox.normal);
            // A bonded pair's multiplier is not capped: `torn` reads it.
            pair.lambda_n = if pair.tension_cap > 0.0 { fnn } else { fnn.max(0.0) };
            pair.lambda_t = tangential(f, prox.normal);
        }
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(a, b))
}
fn tangential(v: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let vn = dot(v, n);
    [v[0] - vn * n[0], v[1] - vn * n[1], v[2] - vn * n[2]]
}
fn outer(a: [f64; 3], b: [f64; 3], k: f64) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| k * a[i] * b[j]))
}
fn diag(k: f64) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| if i == j { k } else { 0.0 }))
}
