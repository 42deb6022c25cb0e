//! Forward sensitivities of the quasi-static scheme: the derivatives of the
//! reactions and marker positions with respect to material parameters, at the
//! cost of one extra right-hand side and one extra solve with the step's own
//! factorization per parameter and step (design.md 4). The parameters go
//! together: one pass over the cells builds all their right-hand sides and one
//! multi-column solve takes them all (see `advance_all`).
//!
//! The discrete quasi-static step (see the stepper) is, per cell of region `r`,
//!
//! ```text
//! s1 = C1 [g e1 - q],   q = B2 (alpha1 e0 - alpha2 e_-1)/dt + sum_k a_k (phi_k e0 - delta_k h_k0)
//! g  = B2 alpha0/dt + G_inf + sum_k a_k phi_k,   phi_k = phi1(r_k dt),  delta_k = exp(-r_k dt)
//! h_k1 = delta_k h_k0 + phi_k (e1 - e0),        sum_e w B^T s1 = f_body on the free rows,
//! ```
//!
//! with the held values independent of the parameters. Differentiating with
//! respect to a parameter `p` (primes: d/dp):
//!
//! ```text
//! (sum_r g_r K1_r) u1' = - sum_e w B^T [C1' (g e1 - q) + C1 (g' e1 - q')]    (free rows; u1' = 0 held)
//! q'   = B2' (alpha1 e0 - alpha2 e_-1)/dt + B2 (alpha1 e0' - alpha2 e_-1')/dt
//!        + sum_k [a_k' (phi_k e0 - delta_k h_k0) + a_k (phi_k' e0 + phi_k e0' - delta_k' h_k0 - delta_k h_k0')]
//! h_k1' = delta_k' h_k0 + delta_k h_k0' + phi_k' (e1 - e0) + phi_k (e1' - e0')
//! phi_k' = phi1'(r_k dt) dt r_k',   delta_k' = -dt delta_k r_k'
//! ```
//!
//! The matrix on the left is the step matrix, already factored. The kernel
//! derivatives `B2'`, `a_k'`, `r_k'` come exactly from the chain's formulas
//! ([`crate::material::Rheology::relaxation_derivatives`]); `C1'` from the Lamé
//! parts of `C1(nu)`. The reactions inside each step are differentiated through the
//! same closed form that gives them (exact dense output), so the force derivative
//! is exact at any time for the step sequence taken. Finite differences of the
//! results agree when the steps are replayed ([`super::Settings::step_ends_s`]);
//! the adaptive step choice itself is not differentiated (it moves the results by
//! less than the step tolerance).

use nalgebra::{SMatrix, SVector};

use super::model::Model;
use super::result::ForceSegment;
use super::{PressError, PressProblem};
use crate::element::{cell_strain, nodal_force, Formulation, ReferenceSimplex, Simplex};
use crate::material::{phi1, phi1_derivative, RelaxationKernel};
use crate::parallel::PARALLEL_MIN_ITEMS;
use crate::solve::{Factor, ReducedSystem};
use rayon::prelude::*;

/// Which parameter of a material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParameterKind {
    /// The rheology parameter at this index of [`crate::material::Rheology::parameters`]
    /// (for the five-element model: 0 = E1, 1 = E2, 2 = c1, 3 = c2, 4 = c3).
    Rheology(usize),
    /// Poisson's ratio.
    Poisson,
}

/// A parameter to differentiate the results by: one material parameter, shared by
/// every region listed (a material used by several regions is one unknown).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SensitivityParameter {
    /// The regions (indices into the mesh's region names) whose material carries it.
    pub regions: Vec<usize>,
    /// Which of the material's parameters.
    pub kind: ParameterKind,
}

/// The derivatives of a run's outputs, one per parameter, in the order given.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensitivities {
    /// Number of parameters.
    pub num_parameters: usize,
    /// `markers[m][i][p]`: the derivative of marker `m`'s `i`-th simulated position
    /// (the samples of [`super::MarkerTrack`]) by parameter `p` [mm per unit of p].
    pub markers: Vec<Vec<Vec<Vec<f64>>>>,
    primal: Vec<ForceSegment>,
    /// Per step, per parameter.
    tangents: Vec<Vec<TangentSegment>>,
}

impl Sensitivities {
    fn forces_at(&self, t: f64) -> Vec<[f64; 2]> {
        let zero = vec![[0.0; 2]; self.num_parameters];
        let Some(first) = self.primal.first() else { return zero };
        if t <= first.t0 {
            return zero;
        }
        let i = self.primal.partition_point(|s| s.t0 + s.dt < t).min(self.primal.len() - 1);
        let s = &self.primal[i];
        let tau = (t - s.t0).clamp(0.0, s.dt);
        self.tangents[i].iter().map(|tg| tg.eval(s, tau)).collect()
    }

    /// d(bottom reaction)/dp at time `t`, one per parameter [N per unit of p].
    pub fn bottom_force_at(&self, t: f64) -> Vec<f64> {
        self.forces_at(t).iter().map(|f| f[0]).collect()
    }

    /// d(plate force)/dp at time `t`, one per parameter [N per unit of p].
    pub fn plate_force_at(&self, t: f64) -> Vec<f64> {
        self.forces_at(t).iter().map(|f| f[1]).collect()
    }
}

/// One region's derivative terms of the reaction functionals in one step (as
/// [`super::result::RegionTerms`], for the derivative quantities).
#[derive(Debug, Clone, PartialEq)]
struct TangentTerms {
    /// The derivative of the region's kernel.
    kernel: RelaxationKernel,
    rate: [f64; 2],
    rate_end: [f64; 2],
    rate_start: [f64; 2],
    strain: [f64; 2],
    history: [[f64; 2]; 2],
}

#[derive(Debug, Clone, PartialEq)]
struct TangentSegment {
    terms: Vec<TangentTerms>,
    detached_ends: Option<[[f64; 2]; 2]>,
}

impl TangentSegment {
    fn eval(&self, primal: &ForceSegment, tau: f64) -> [f64; 2] {
        if let Some([start, end]) = self.detached_ends {
            let w = tau / primal.dt;
            return [start[0] + w * (end[0] - start[0]), start[1] + w * (end[1] - start[1])];
        }
        self.eval_formula(primal, tau)
    }

    /// The derivative of [`ForceSegment::eval_formula`].
    fn eval_formula(&self, primal: &ForceSegment, tau: f64) -> [f64; 2] {
        let mut f = [0.0; 2];
        let w = tau / primal.dt;
        for (r, d) in primal.terms.iter().zip(&self.terms) {
            let (k, dk) = (&r.kernel, &d.kernel);
            for side in 0..2 {
                if side == 1 && !r.plate_attached {
                    continue;
                }
                let rate = r.rate_start[side] + w * (r.rate_end[side] - r.rate_start[side]);
                let d_rate = d.rate_start[side] + w * (d.rate_end[side] - d.rate_start[side]);
                let strain = r.strain[side] + tau * r.rate[side];
                let d_strain = d.strain[side] + tau * d.rate[side];
                let mut v = dk.viscous * rate + k.viscous * d_rate + dk.equilibrium * strain + k.equilibrium * d_strain;
                for j in 0..k.num_terms {
                    let x = k.rates[j] * tau;
                    let (decay, ph) = ((-x).exp(), phi1(x));
                    let dx = dk.rates[j] * tau;
                    v += dk.amplitudes[j] * (decay * r.history[j][side] + ph * tau * r.rate[side])
                        + k.amplitudes[j]
                            * (-dx * decay * r.history[j][side]
                                + decay * d.history[j][side]
                                + phi1_derivative(x) * dx * tau * r.rate[side]
                                + ph * tau * d.rate[side]);
                }
                f[side] += v;
            }
        }
        f
    }
}

/// The derivative of the unit-Young matrix `C1(nu) = lambda1 m m^T + mu1 diag(2.., 1..)`
/// by `nu`: `lambda1' m m^T + mu1' diag(2.., 1..)`, with `mu1 = 1/(2 (1 + nu))`,
/// `lambda1 = nu/((1 + nu)(1 - 2 nu))`, and in plane stress `lambda* = nu/(1 - nu^2)`.
pub(crate) fn unit_young_matrix_poisson_derivative<const S: usize>(
    formulation: Formulation,
    nu: f64,
) -> SMatrix<f64, S, S> {
    // Normal components: the first two in plane problems, three otherwise.
    let normals = if S == 3 { 2 } else { 3 };
    let d_mu = -0.5 / ((1.0 + nu) * (1.0 + nu));
    let d_lambda = match formulation {
        Formulation::PlaneStress { .. } => (1.0 + nu * nu) / ((1.0 - nu * nu) * (1.0 - nu * nu)),
        _ => (1.0 + 2.0 * nu * nu) / ((1.0 + nu) * (1.0 + nu) * (1.0 - 2.0 * nu) * (1.0 - 2.0 * nu)),
    };
    let mut c = SMatrix::<f64, S, S>::zeros();
    for i in 0..normals {
        for j in 0..normals {
            c[(i, j)] = d_lambda;
        }
        c[(i, i)] += 2.0 * d_mu;
    }
    for k in normals..S {
        c[(k, k)] = d_mu;
    }
    c
}

/// One parameter's derivative of each region's kernel and `C1`.
struct RegionTangent<const S: usize> {
    kernel: RelaxationKernel,
    c1: SMatrix<f64, S, S>,
    /// Whether `c1` is nonzero (Poisson's ratio of this region).
    has_c1: bool,
}

/// The derivatives of the state at a step end, every parameter at once: `u` holds
/// one displacement vector per parameter (`u[p * ndof + dof]`), the cell arrays
/// one value per cell and parameter (`strain[e * P + p]`), so that a cell's
/// values for all parameters sit together for the batched cell passes.
struct BatchState<const S: usize> {
    u: Vec<f64>,
    strain: Vec<SVector<f64, S>>,
    strain_prev: Vec<SVector<f64, S>>,
    history: Vec<[SVector<f64, S>; 2]>,
}

/// What the stepper hands over for one accepted step.
pub(crate) struct StepView<'a, const S: usize> {
    pub t0: f64,
    pub dt: f64,
    /// BDF coefficients `alpha0, alpha1, alpha2` of this step.
    pub alpha: [f64; 3],
    pub strain0: &'a [SVector<f64, S>],
    pub strain_prev0: &'a [SVector<f64, S>],
    pub history0: &'a [[SVector<f64, S>; 2]],
    pub strain1: &'a [SVector<f64, S>],
    /// The displacement at the step's end (held dofs at their prescribed values).
    pub u1: &'a [f64],
    /// The dofs held at the plate's displacement in this step's constraint set.
    pub plate_dofs: &'a [usize],
    pub system: &'a ReducedSystem,
    pub factor: &'a Factor<'a>,
    /// `Some(g)` when the factor is of the unscaled stiffness (one kernel group).
    pub single_group_factor: Option<f64>,
    /// Whether the viscous rate continues from the previous step (a BDF2 step).
    pub continues: bool,
    /// The primal segment of this step (its `detached_ends` tells a detached step).
    pub segment: &'a ForceSegment,
}

/// The two ways of carrying the derivatives (see [`NodalBatch`]).
enum TangentStates<const S: usize> {
    /// Cell strains and histories: any regions and parameters.
    Cells(BatchState<S>),
    /// Nodal vectors: one region, rheology parameters only.
    Nodal(Box<NodalBatch>),
}

/// The derivatives carried as nodal vectors, for a body of one region and
/// rheology parameters only (no `C1'`): the common case of a uniform trial.
///
/// Every cell strain of the scheme is `B` of a nodal vector: `e = B u`, and the
/// exact history `h_k1 = delta_k h_k0 + phi_k (e1 - e0)` has the same scalar
/// coefficients in every cell of a region, so `h_k = B eta_k` with
/// `eta_k1 = delta_k eta_k0 + phi_k (u1 - u0)`; likewise for the derivatives. The
/// load of the sensitivity step is then `-sum_e w B^T C1 B V = -K V` with the nodal
/// `V = g' u1 - q'` (`q'` as in the module formula, with nodal vectors for cell
/// strains), and with the step matrix `g K` the free rows solve to
///
/// ```text
/// u1'_f = -(V_f + K_ff^-1 K_fh V_h) / g .
/// ```
///
/// The held values of every nodal vector are multiples of one pattern `P` (1 on
/// the plate's dofs, 0 on the other held dofs): the primal's held values are
/// `-d(t) P` and the derivatives vanish there. So `V_h = c P_h` with `c` read at a
/// plate dof, and `K_ff^-1 K_fh P_h` is one solve per constraint set and run, not
/// one per parameter and step: a sensitivity step costs a few vector operations.
/// A column whose held values are not such a multiple (checked every step), or a
/// step whose factor is not of the unscaled `K`, is solved with the factor
/// instead. The reaction functionals are linear in the nodal vectors too: `rho .
/// C1 B u = w . u` with `w` assembled once.
struct NodalBatch {
    /// The primal displacement at the step start and one step back, and `eta_k`.
    u0: Vec<f64>,
    u_prev: Vec<f64>,
    eta: [Vec<f64>; 2],
    /// The derivatives, `[p * ndof + dof]`.
    du0: Vec<f64>,
    du_prev: Vec<f64>,
    deta: [Vec<f64>; 2],
    /// The reaction functionals' nodal weights, bottom and plate.
    weights: [Vec<f64>; 2],
    /// Per constraint set (keyed by its plate dofs): `K_ff^-1 K_fh P_h` on the free rows.
    lift: Vec<(Vec<usize>, Vec<f64>)>,
}

/// The sensitivity state of a run.
pub(crate) struct Tracker<const S: usize> {
    /// `[p][r]`.
    tangents: Vec<Vec<RegionTangent<S>>>,
    state: TangentStates<S>,
    segments: Vec<Vec<TangentSegment>>,
    /// `[m][i][p]`.
    markers: Vec<Vec<Vec<Vec<f64>>>>,
    marker_next: Vec<usize>,
    /// The primal segments, kept for the dense output of the derivatives.
    primal: Vec<ForceSegment>,
}

/// Checks the parameters against the problem: known regions, a rheology index
/// every listed region's model has, and the quasi-static integrator.
pub(crate) fn check_parameters<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    parameters: &[SensitivityParameter],
) -> Result<(), PressError> {
    for (i, p) in parameters.iter().enumerate() {
        if p.regions.is_empty() {
            return Err(PressError::BadSettings(format!("sensitivity parameter {i} lists no region")));
        }
        for &r in &p.regions {
            let Some(m) = problem.materials.get(r) else {
                return Err(PressError::BadSettings(format!(
                    "sensitivity parameter {i}: region {r} does not exist ({} regions)",
                    problem.materials.len()
                )));
            };
            if let ParameterKind::Rheology(k) = p.kind {
                let n = m.rheology.parameters().len();
                if k >= n {
                    return Err(PressError::BadSettings(format!(
                        "sensitivity parameter {i}: the {} model of region {r} has {n} parameters, not {}",
                        m.rheology.model_name(),
                        k + 1
                    )));
                }
            }
        }
    }
    Ok(())
}

impl<const S: usize> Tracker<S> {
    pub fn new<const D: usize, const N: usize>(model: &Model<'_, D, N, S>, parameters: &[SensitivityParameter]) -> Self
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let problem = model.problem;
        let nreg = model.region_kernel.len();
        let tangents = parameters
            .iter()
            .map(|p| {
                (0..nreg)
                    .map(|r| {
                        let zero_kernel =
                            RelaxationKernel { num_terms: model.region_kernel[r].num_terms, ..ZERO_KERNEL };
                        if !p.regions.contains(&r) {
                            return RegionTangent { kernel: zero_kernel, c1: SMatrix::zeros(), has_c1: false };
                        }
                        let m = &problem.materials[r];
                        match p.kind {
                            ParameterKind::Rheology(k) => RegionTangent {
                                kernel: m.rheology.relaxation_derivatives()[k],
                                c1: SMatrix::zeros(),
                                has_c1: false,
                            },
                            ParameterKind::Poisson => RegionTangent {
                                kernel: zero_kernel,
                                c1: unit_young_matrix_poisson_derivative::<S>(problem.formulation, m.poisson),
                                has_c1: true,
                            },
                        }
                    })
                    .collect()
            })
            .collect();
        let (ndof, ncell, np) = (model.num_dofs(), problem.mesh.num_cells(), parameters.len());
        let nodal = nreg == 1 && model.groups.len() == 1 && parameters.iter().all(|p| p.kind != ParameterKind::Poisson);
        let state = if nodal {
            TangentStates::Nodal(Box::new(NodalBatch::new(model, np)))
        } else {
            TangentStates::Cells(BatchState {
                u: vec![0.0; ndof * np],
                strain: vec![SVector::zeros(); ncell * np],
                strain_prev: vec![SVector::zeros(); ncell * np],
                history: vec![[SVector::zeros(); 2]; ncell * np],
            })
        };
        let num_markers = problem.markers.len();
        let mut tracker = Self {
            tangents,
            state,
            segments: Vec::new(),
            markers: vec![Vec::new(); num_markers],
            marker_next: vec![0; num_markers],
            primal: Vec::new(),
        };
        // Initial marker samples (t <= 0): nothing has moved.
        for (m, req) in problem.markers.iter().enumerate() {
            while tracker.marker_next[m] < req.times.len() && req.times[tracker.marker_next[m]] <= 0.0 {
                tracker.markers[m].push(vec![vec![0.0; D]; parameters.len()]);
                tracker.marker_next[m] += 1;
            }
        }
        tracker
    }

    /// Advances every parameter's derivative over one accepted step (one batched
    /// pass, see [`advance_all`]).
    pub fn advance<const D: usize, const N: usize>(&mut self, model: &Model<'_, D, N, S>, step: &StepView<'_, S>)
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let (old_u, mut segments) = match &mut self.state {
            TangentStates::Cells(state) => {
                let (next, segments) = advance_all(model, step, &self.tangents, state);
                let old = std::mem::replace(state, next);
                state.strain_prev = old.strain;
                (old.u, segments)
            }
            TangentStates::Nodal(batch) => batch.advance(model, step, &self.tangents),
        };
        for (p, segment) in segments.iter_mut().enumerate() {
            let previous = self.segments.last().map(|s: &Vec<TangentSegment>| &s[p]);
            if step.segment.detached_ends.is_some() {
                let start = match (previous, self.primal.last()) {
                    (Some(prev), Some(primal)) => prev.eval(primal, primal.dt),
                    _ => [0.0; 2],
                };
                segment.detached_ends = Some([start, segment.eval_formula(step.segment, step.dt)]);
            }
            if let (true, Some(prev)) = (step.continues, previous) {
                for (t, l) in segment.terms.iter_mut().zip(&prev.terms) {
                    t.rate_start = l.rate_end;
                }
            }
        }
        self.emit_markers(model, &old_u, step);
        self.primal.push(step.segment.clone());
        self.segments.push(segments);
    }

    /// Marker derivatives at requested times inside `(t0, t1]`, interpolated
    /// between the step ends as the positions are.
    fn emit_markers<const D: usize, const N: usize>(
        &mut self,
        model: &Model<'_, D, N, S>,
        old_u: &[f64],
        step: &StepView<'_, S>,
    ) where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        if self.markers.is_empty() {
            return;
        }
        let (t0, t1) = (step.t0, step.t0 + step.dt);
        let ndof = model.num_dofs();
        // marker_positions adds the initial position: subtract it (the derivative is linear in du).
        let base = model.marker_positions(&vec![0.0; ndof], t1);
        let d0: Vec<Vec<Vec<f64>>> = old_u.chunks(ndof).map(|u| model.marker_positions(u, t0)).collect();
        let new_u = match &self.state {
            TangentStates::Cells(state) => &state.u,
            TangentStates::Nodal(batch) => &batch.du0,
        };
        let d1: Vec<Vec<Vec<f64>>> = new_u.chunks(ndof).map(|u| model.marker_positions(u, t1)).collect();
        for (m, req) in model.problem.markers.iter().enumerate() {
            while self.marker_next[m] < req.times.len() && req.times[self.marker_next[m]] <= t1 * (1.0 + 1e-12) {
                let t = req.times[self.marker_next[m]];
                let w = if t1 <= t0 { 1.0 } else { ((t - t0) / (t1 - t0)).clamp(0.0, 1.0) };
                let row = (0..d0.len())
                    .map(|p| (0..D).map(|k| d0[p][m][k] - base[m][k] + w * (d1[p][m][k] - d0[p][m][k])).collect())
                    .collect();
                self.markers[m].push(row);
                self.marker_next[m] += 1;
            }
        }
    }

    pub fn finish(self) -> Sensitivities {
        Sensitivities {
            num_parameters: self.tangents.len(),
            markers: self.markers,
            primal: self.primal,
            tangents: self.segments,
        }
    }
}

const ZERO_KERNEL: RelaxationKernel =
    RelaxationKernel { viscous: 0.0, equilibrium: 0.0, num_terms: 0, amplitudes: [0.0; 2], rates: [0.0; 2] };

impl NodalBatch {
    fn new<const D: usize, const N: usize, const S: usize>(model: &Model<'_, D, N, S>, np: usize) -> Self
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let ndof = model.num_dofs();
        let mesh = &model.problem.mesh;
        // w . u = sum_f rho_f . C1 B_f u: the derivative of each functional by each
        // nodal displacement, from the strain of unit displacements.
        let mut weights = [vec![0.0; ndof], vec![0.0; ndof]];
        for (side, list) in model.functionals.iter().enumerate() {
            for f in list {
                let rc = model.region_c1[mesh.cell_regions[f.cell] as usize] * f.rho;
                let cell = &mesh.cells[f.cell];
                for a in 0..N {
                    for k in 0..D {
                        let mut unit = [SVector::<f64, D>::zeros(); N];
                        unit[a][k] = 1.0;
                        let e = cell_strain::<D, N, S>(&model.geometry[f.cell].gradients, &unit);
                        weights[side][cell[a] as usize * D + k] += rc.dot(&e);
                    }
                }
            }
        }
        Self {
            u0: vec![0.0; ndof],
            u_prev: vec![0.0; ndof],
            eta: [vec![0.0; ndof], vec![0.0; ndof]],
            du0: vec![0.0; ndof * np],
            du_prev: vec![0.0; ndof * np],
            deta: [vec![0.0; ndof * np], vec![0.0; ndof * np]],
            weights,
            lift: Vec::new(),
        }
    }

    /// `K_ff^-1 K_fh P_h` for the step's constraint set (computed once per set).
    fn lift<const D: usize, const N: usize, const S: usize>(
        &mut self,
        model: &Model<'_, D, N, S>,
        step: &StepView<'_, S>,
    ) -> &[f64]
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let pos = match self.lift.iter().position(|(dofs, _)| dofs.as_slice() == step.plate_dofs) {
            Some(pos) => pos,
            None => {
                let ndof = model.num_dofs();
                let mut pattern = vec![0.0; ndof];
                step.plate_dofs.iter().for_each(|&d| pattern[d] = 1.0);
                let mut k_p = vec![0.0; ndof];
                model.pattern.mul_vec(&model.groups[0].stiffness, &pattern, &mut k_p);
                let mut z: Vec<f64> = step.system.dof_of_free.iter().map(|&d| k_p[d as usize]).collect();
                step.factor.solve_in_place(&mut z);
                self.lift.push((step.plate_dofs.to_vec(), z));
                self.lift.len() - 1
            }
        };
        &self.lift[pos].1
    }

    /// Advances every parameter over one step; returns the derivatives of the
    /// displacement at the step start and the force terms.
    fn advance<const D: usize, const N: usize, const S: usize>(
        &mut self,
        model: &Model<'_, D, N, S>,
        step: &StepView<'_, S>,
        tangents: &[Vec<RegionTangent<S>>],
    ) -> (Vec<f64>, Vec<TangentSegment>)
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let (ndof, np) = (model.num_dofs(), tangents.len());
        let k = &model.region_kernel[0];
        let (dt, [a0, a1, a2]) = (step.dt, step.alpha);
        // The factor's scale is the step's g (the unscaled K is factored).
        let lift = step.single_group_factor.is_some().then(|| self.lift(model, step).to_vec());
        let (u0, u1, up) = (&self.u0, step.u1, &self.u_prev);
        let (mut phi, mut decay) = ([0.0; 2], [0.0; 2]);
        for j in 0..k.num_terms {
            let x = k.rates[j] * dt;
            phi[j] = phi1(x);
            decay[j] = (-x).exp();
        }

        // V = g' u1 - q' per parameter, every dof.
        let mut v = vec![0.0; ndof * np];
        let mut dphi = vec![[0.0; 2]; np];
        let mut ddecay = vec![[0.0; 2]; np];
        for (p, tangent) in tangents.iter().enumerate() {
            let dk = &tangent[0].kernel;
            let mut dg = dk.viscous * a0 / dt + dk.equilibrium;
            for j in 0..k.num_terms {
                dphi[p][j] = phi1_derivative(k.rates[j] * dt) * dt * dk.rates[j];
                ddecay[p][j] = -dt * decay[j] * dk.rates[j];
                dg += dk.amplitudes[j] * phi[j] + k.amplitudes[j] * dphi[p][j];
            }
            let range = p * ndof..(p + 1) * ndof;
            let (du0, dup) = (&self.du0[range.clone()], &self.du_prev[range.clone()]);
            let (deta0, deta1) = (&self.deta[0][range.clone()], &self.deta[1][range.clone()]);
            for (d, out) in v[range].iter_mut().enumerate() {
                let mut dq =
                    (u0[d] * a1 - up[d] * a2) * (dk.viscous / dt) + (du0[d] * a1 - dup[d] * a2) * (k.viscous / dt);
                for j in 0..k.num_terms {
                    let (eta, deta) = (self.eta[j][d], if j == 0 { deta0[d] } else { deta1[d] });
                    dq += (u0[d] * phi[j] - eta * decay[j]) * dk.amplitudes[j]
                        + (u0[d] * dphi[p][j] + du0[d] * phi[j] - eta * ddecay[p][j] - deta * decay[j])
                            * k.amplitudes[j];
                }
                *out = dg * u1[d] - dq;
            }
        }

        // Free rows: -(V_f + c z)/g where V_h = c P_h; otherwise a solve.
        let free = &step.system.dof_of_free;
        let held: Vec<usize> = (0..ndof).filter(|&d| step.system.free_of_dof[d] == u32::MAX).collect();
        let mut du1 = vec![0.0; ndof * np];
        let mut solve_columns = Vec::new();
        let mut on_plate = vec![false; ndof];
        step.plate_dofs.iter().for_each(|&d| on_plate[d] = true);
        for p in 0..np {
            let vp = &v[p * ndof..(p + 1) * ndof];
            let c = step.plate_dofs.first().map_or(0.0, |&d| vp[d]);
            let size = vp.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let proportional = held.iter().all(|&d| {
                let expected = if on_plate[d] { c } else { 0.0 };
                (vp[d] - expected).abs() <= 1e-12 * size
            });
            match (&lift, step.single_group_factor, proportional) {
                (Some(z), Some(g), true) => {
                    for (i, &d) in free.iter().enumerate() {
                        du1[p * ndof + d as usize] = -(vp[d as usize] + c * z[i]) / g;
                    }
                }
                _ => solve_columns.push(p),
            }
        }
        if !solve_columns.is_empty() {
            let nf = free.len();
            let mut x = vec![0.0; nf * solve_columns.len()];
            let mut kv = vec![0.0; ndof];
            for (col, &p) in solve_columns.iter().enumerate() {
                model.pattern.mul_vec(&model.groups[0].stiffness, &v[p * ndof..(p + 1) * ndof], &mut kv);
                for (i, &d) in free.iter().enumerate() {
                    x[col * nf + i] = -kv[d as usize];
                }
            }
            step.factor.solve_columns_in_place(&mut x, solve_columns.len());
            // The factor is of K (then scaled by 1/g) or of the step matrix itself.
            let scale = step.single_group_factor.map_or(1.0, |g| 1.0 / g);
            for (col, &p) in solve_columns.iter().enumerate() {
                for (i, &d) in free.iter().enumerate() {
                    du1[p * ndof + d as usize] = x[col * nf + i] * scale;
                }
            }
        }

        // The reaction functionals' terms (C1' = 0: only the derivative states act).
        let dot = |w: &[f64], x: &[f64]| w.iter().zip(x).map(|(a, b)| a * b).sum::<f64>();
        let segments = tangents
            .iter()
            .enumerate()
            .map(|(p, tangent)| {
                let range = p * ndof..(p + 1) * ndof;
                let (du0, dup, du1p) = (&self.du0[range.clone()], &self.du_prev[range.clone()], &du1[range.clone()]);
                let mut t = TangentTerms {
                    kernel: tangent[0].kernel,
                    rate: [0.0; 2],
                    rate_end: [0.0; 2],
                    rate_start: [0.0; 2],
                    strain: [0.0; 2],
                    history: [[0.0; 2]; 2],
                };
                for side in 0..2 {
                    let w = &self.weights[side];
                    let (w1, w0, wp) = (dot(w, du1p), dot(w, du0), dot(w, dup));
                    t.rate[side] = (w1 - w0) / dt;
                    t.rate_end[side] = (w1 * a0 - w0 * a1 + wp * a2) / dt;
                    t.strain[side] = w0;
                    for j in 0..k.num_terms {
                        t.history[j][side] = dot(w, &self.deta[j][range.clone()]);
                    }
                }
                t.rate_start = t.rate;
                TangentSegment { terms: vec![t], detached_ends: None }
            })
            .collect();

        // Histories, then roll the states.
        for j in 0..k.num_terms {
            for p in 0..np {
                for d in 0..ndof {
                    let i = p * ndof + d;
                    self.deta[j][i] = ddecay[p][j] * self.eta[j][d]
                        + decay[j] * self.deta[j][i]
                        + dphi[p][j] * (u1[d] - u0[d])
                        + phi[j] * (du1[i] - self.du0[i]);
                }
            }
            for d in 0..ndof {
                self.eta[j][d] = decay[j] * self.eta[j][d] + phi[j] * (u1[d] - u0[d]);
            }
        }
        self.u_prev = std::mem::replace(&mut self.u0, u1.to_vec());
        let old_du0 = std::mem::replace(&mut self.du0, du1);
        self.du_prev.clone_from(&old_du0);
        (old_du0, segments)
    }
}

/// `(0..ncell).flat_map(f)`, where `f(e, out)` pushes cell `e`'s `np` values: in
/// parallel over the cells when there are many, in order either way.
fn per_cell<T: Send>(ncell: usize, np: usize, f: impl Fn(usize, &mut Vec<T>) + Sync + Send) -> Vec<T> {
    if ncell < PARALLEL_MIN_ITEMS {
        let mut v = Vec::with_capacity(ncell * np);
        (0..ncell).for_each(|e| f(e, &mut v));
        v
    } else {
        (0..ncell)
            .into_par_iter()
            .flat_map_iter(|e| {
                let mut v = Vec::with_capacity(np);
                f(e, &mut v);
                v
            })
            .collect()
    }
}

/// Every parameter over one step: the new derivative state (its `strain_prev`
/// left empty for the caller to fill with the old strains) and force terms.
///
/// Batched: one pass over the cells builds every parameter's load (the primal
/// history part `q`, shared by all, is computed once per cell), one node-row
/// assembly gathers them, one multi-column solve with the step's factorization
/// takes all right-hand sides (faer updates four columns per pass over the
/// factor), and one more pass over the cells updates every parameter's strains
/// and histories. Per parameter it is the same arithmetic as one parameter at a
/// time; only the loops are interchanged.
fn advance_all<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    step: &StepView<'_, S>,
    tangents: &[Vec<RegionTangent<S>>],
    s0: &BatchState<S>,
) -> (BatchState<S>, Vec<TangentSegment>)
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mesh = &model.problem.mesh;
    let (ndof, ncell, np, nreg) = (model.num_dofs(), mesh.num_cells(), tangents.len(), model.region_kernel.len());
    let (dt, [a0, a1, a2]) = (step.dt, step.alpha);
    // Per region: g and per term phi, delta; per parameter and region: g', phi', delta'.
    struct Primal {
        g: f64,
        phi: [f64; 2],
        decay: [f64; 2],
    }
    struct Derivative {
        dg: f64,
        dphi: [f64; 2],
        ddecay: [f64; 2],
    }
    let primal: Vec<Primal> = model
        .region_kernel
        .iter()
        .map(|k| {
            let mut s = Primal { g: k.viscous * a0 / dt + k.equilibrium, phi: [0.0; 2], decay: [0.0; 2] };
            for j in 0..k.num_terms {
                let x = k.rates[j] * dt;
                s.phi[j] = phi1(x);
                s.decay[j] = (-x).exp();
                s.g += k.amplitudes[j] * s.phi[j];
            }
            s
        })
        .collect();
    // `[p * nreg + r]`.
    let derivative: Vec<Derivative> = tangents
        .iter()
        .flat_map(|tangent| {
            model.region_kernel.iter().zip(tangent).zip(&primal).map(|((k, t), s)| {
                let dk = &t.kernel;
                let mut d = Derivative { dg: dk.viscous * a0 / dt + dk.equilibrium, dphi: [0.0; 2], ddecay: [0.0; 2] };
                for j in 0..k.num_terms {
                    d.dphi[j] = phi1_derivative(k.rates[j] * dt) * dt * dk.rates[j];
                    d.ddecay[j] = -dt * s.decay[j] * dk.rates[j];
                    d.dg += dk.amplitudes[j] * s.phi[j] + k.amplitudes[j] * d.dphi[j];
                }
                d
            })
        })
        .collect();

    // The loads: tau_e = C1' (g e1 - q) + C1 (g' e1 - q'), force -sum w B^T tau_e;
    // `cell_forces[e * np + p]`.
    let cell_forces: Vec<[SVector<f64, D>; N]> = per_cell(ncell, np, |e, out| {
        let r = mesh.cell_regions[e] as usize;
        let (k, s) = (&model.region_kernel[r], &primal[r]);
        let (e0, em1, e1) = (step.strain0[e], step.strain_prev0[e], step.strain1[e]);
        let h0 = &step.history0[e];
        let rate = (e0 * a1 - em1 * a2) / dt;
        let mut q = rate * k.viscous;
        let mut memory = [SVector::<f64, S>::zeros(); 2];
        for j in 0..k.num_terms {
            memory[j] = e0 * s.phi[j] - h0[j] * s.decay[j];
            q += memory[j] * k.amplitudes[j];
        }
        let primal_stress = e1 * s.g - q;
        let c1 = &model.region_c1[r];
        for (p, t) in tangents.iter().enumerate() {
            let (t, d) = (&t[r], &derivative[p * nreg + r]);
            let i = e * np + p;
            let mut dq = rate * t.kernel.viscous + (s0.strain[i] * a1 - s0.strain_prev[i] * a2) * (k.viscous / dt);
            for j in 0..k.num_terms {
                dq += memory[j] * t.kernel.amplitudes[j]
                    + (e0 * d.dphi[j] + s0.strain[i] * s.phi[j] - h0[j] * d.ddecay[j] - s0.history[i][j] * s.decay[j])
                        * k.amplitudes[j];
            }
            let mut tau = c1 * (e1 * d.dg - dq);
            if t.has_c1 {
                tau += t.c1 * primal_stress;
            }
            let load = -tau;
            out.push(std::array::from_fn(|a| nodal_force::<D, N, S>(&model.geometry[e], &load, a)));
        }
    });
    // Node-row assembly, `rhs[dof * np + p]`.
    let mut rhs = vec![0.0; ndof * np];
    let topology = &model.topology;
    let node_rows = |(node, o): (usize, &mut [f64])| {
        for &(e, a) in &topology.node_cells[topology.cell_ptr[node]..topology.cell_ptr[node + 1]] {
            for p in 0..np {
                let f = &cell_forces[e as usize * np + p][a as usize];
                for k in 0..D {
                    o[k * np + p] += f[k];
                }
            }
        }
    };
    if topology.cell_ptr.len() - 1 < PARALLEL_MIN_ITEMS {
        rhs.chunks_mut(D * np).enumerate().for_each(node_rows);
    } else {
        rhs.par_chunks_mut(D * np).enumerate().for_each(node_rows);
    }
    drop(cell_forces);
    // The free rows, column after column, solved together.
    let free = &step.system.dof_of_free;
    let nf = free.len();
    let mut x = vec![0.0; nf * np];
    for p in 0..np {
        for (i, &d) in free.iter().enumerate() {
            x[p * nf + i] = rhs[d as usize * np + p];
        }
    }
    drop(rhs);
    step.factor.solve_columns_in_place(&mut x, np);
    let scale = step.single_group_factor.map_or(1.0, |g| 1.0 / g);
    let mut u = vec![0.0; ndof * np];
    for p in 0..np {
        for (i, &d) in free.iter().enumerate() {
            u[p * ndof + d as usize] = x[p * nf + i] * scale;
        }
    }
    drop(x);

    // Cell update, `updated[e * np + p]`.
    let updated: Vec<(SVector<f64, S>, [SVector<f64, S>; 2])> = per_cell(ncell, np, |e, out| {
        let r = mesh.cell_regions[e] as usize;
        let (k, s) = (&model.region_kernel[r], &primal[r]);
        let de = step.strain1[e] - step.strain0[e];
        let gradients = &model.geometry[e].gradients;
        for p in 0..np {
            let d = &derivative[p * nreg + r];
            let i = e * np + p;
            let de1 = cell_strain::<D, N, S>(gradients, &model.cell_displacements(e, &u[p * ndof..(p + 1) * ndof]));
            let mut h1 = [SVector::<f64, S>::zeros(); 2];
            for j in 0..k.num_terms {
                h1[j] = step.history0[e][j] * d.ddecay[j]
                    + s0.history[i][j] * s.decay[j]
                    + de * d.dphi[j]
                    + (de1 - s0.strain[i]) * s.phi[j];
            }
            out.push((de1, h1));
        }
    });

    // Derivatives of the reaction functionals' terms.
    let mut segments: Vec<TangentSegment> = tangents
        .iter()
        .map(|tangent| TangentSegment {
            terms: (0..nreg)
                .map(|r| TangentTerms {
                    kernel: tangent[r].kernel,
                    rate: [0.0; 2],
                    rate_end: [0.0; 2],
                    rate_start: [0.0; 2],
                    strain: [0.0; 2],
                    history: [[0.0; 2]; 2],
                })
                .collect(),
            detached_ends: None,
        })
        .collect();
    for (side, list) in model.functionals.iter().enumerate() {
        for f in list {
            let (c, r) = (f.cell, mesh.cell_regions[f.cell] as usize);
            let rc = model.region_c1[r] * f.rho;
            let (e0, em1, e1) = (step.strain0[c], step.strain_prev0[c], step.strain1[c]);
            for (p, segment) in segments.iter_mut().enumerate() {
                let drc = tangents[p][r].c1 * f.rho;
                let i = c * np + p;
                let (de0, dem1, de1) = (s0.strain[i], s0.strain_prev[i], updated[i].0);
                let t = &mut segment.terms[r];
                t.rate[side] += (drc.dot(&(e1 - e0)) + rc.dot(&(de1 - de0))) / dt;
                t.rate_end[side] +=
                    (drc.dot(&(e1 * a0 - e0 * a1 + em1 * a2)) + rc.dot(&(de1 * a0 - de0 * a1 + dem1 * a2))) / dt;
                t.strain[side] += drc.dot(&e0) + rc.dot(&de0);
                for j in 0..model.region_kernel[r].num_terms {
                    t.history[j][side] += drc.dot(&step.history0[c][j]) + rc.dot(&s0.history[i][j]);
                }
            }
        }
    }
    for segment in &mut segments {
        for t in &mut segment.terms {
            t.rate_start = t.rate;
        }
    }

    let (strain, history): (Vec<_>, Vec<_>) = updated.into_iter().unzip();
    (BatchState { u, strain, strain_prev: Vec::new(), history }, segments)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::unit_young_matrix;

    /// The Lamé-part derivative of C1 against central differences, every formulation.
    #[test]
    fn poisson_derivative_of_c1_matches_differences() {
        let nu = 0.3746;
        let h = 1e-6;
        let check = |f: Formulation| {
            let d3 = unit_young_matrix_poisson_derivative::<3>(f, nu);
            let fd3 = (unit_young_matrix::<3>(f, nu + h) - unit_young_matrix::<3>(f, nu - h)) / (2.0 * h);
            assert!((d3 - fd3).amax() < 1e-8, "{f:?}: {d3} vs {fd3}");
        };
        check(Formulation::PlaneStress { thickness_mm: 1.0 });
        check(Formulation::PlaneStrain { thickness_mm: 1.0 });
        let d6 = unit_young_matrix_poisson_derivative::<6>(Formulation::Solid, nu);
        let fd6 = (unit_young_matrix::<6>(Formulation::Solid, nu + h)
            - unit_young_matrix::<6>(Formulation::Solid, nu - h))
            / (2.0 * h);
        assert!((d6 - fd6).amax() < 1e-8, "solid: {d6} vs {fd6}");
        let axi = Formulation::Axisymmetric;
        let d4 = unit_young_matrix_poisson_derivative::<4>(axi, nu);
        let fd4 = (unit_young_matrix::<4>(axi, nu + h) - unit_young_matrix::<4>(axi, nu - h)) / (2.0 * h);
        assert!((d4 - fd4).amax() < 1e-8, "axisymmetric: {d4} vs {fd4}");
    }
}
