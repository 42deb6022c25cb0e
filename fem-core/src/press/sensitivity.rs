//! Forward sensitivities of the quasi-static scheme: the derivatives of the
//! reactions and marker positions with respect to material parameters, at the
//! cost of one extra right-hand side and one extra solve with the step's own
//! factorization per parameter and step (design.md 4).
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
use crate::assembly::assemble_vector;
use crate::element::{cell_strain, nodal_force, Formulation, ReferenceSimplex, Simplex};
use crate::material::{phi1, phi1_derivative, RelaxationKernel};
use crate::parallel::map_collect;
use crate::solve::{Factor, ReducedSystem};

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
}

/// The derivative of the state at a step end.
#[derive(Clone)]
struct TangentState<const S: usize> {
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
    pub system: &'a ReducedSystem,
    pub factor: &'a Factor<'a>,
    /// `Some(g)` when the factor is of the unscaled stiffness (one kernel group).
    pub single_group_factor: Option<f64>,
    /// Whether the viscous rate continues from the previous step (a BDF2 step).
    pub continues: bool,
    /// The primal segment of this step (its `detached_ends` tells a detached step).
    pub segment: &'a ForceSegment,
}

/// The sensitivity state of a run.
pub(crate) struct Tracker<const S: usize> {
    /// `[p][r]`.
    tangents: Vec<Vec<RegionTangent<S>>>,
    states: Vec<TangentState<S>>,
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
                            return RegionTangent { kernel: zero_kernel, c1: SMatrix::zeros() };
                        }
                        let m = &problem.materials[r];
                        match p.kind {
                            ParameterKind::Rheology(k) => {
                                RegionTangent { kernel: m.rheology.relaxation_derivatives()[k], c1: SMatrix::zeros() }
                            }
                            ParameterKind::Poisson => RegionTangent {
                                kernel: zero_kernel,
                                c1: unit_young_matrix_poisson_derivative::<S>(problem.formulation, m.poisson),
                            },
                        }
                    })
                    .collect()
            })
            .collect();
        let (ndof, ncell) = (model.num_dofs(), problem.mesh.num_cells());
        let zero = TangentState {
            u: vec![0.0; ndof],
            strain: vec![SVector::zeros(); ncell],
            strain_prev: vec![SVector::zeros(); ncell],
            history: vec![[SVector::zeros(); 2]; ncell],
        };
        let num_markers = problem.markers.len();
        let mut tracker = Self {
            tangents,
            states: vec![zero; parameters.len()],
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

    /// Advances every parameter's derivative over one accepted step.
    pub fn advance<const D: usize, const N: usize>(&mut self, model: &Model<'_, D, N, S>, step: &StepView<'_, S>)
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let num_parameters = self.tangents.len();
        let mut segments = Vec::with_capacity(num_parameters);
        let mut old_u = Vec::with_capacity(num_parameters);
        for p in 0..num_parameters {
            let (state, mut segment) = advance_one(model, step, &self.tangents[p], &self.states[p]);
            old_u.push(std::mem::replace(&mut self.states[p], state).u);
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
            segments.push(segment);
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
        old_u: &[Vec<f64>],
        step: &StepView<'_, S>,
    ) where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        if self.markers.is_empty() {
            return;
        }
        let (t0, t1) = (step.t0, step.t0 + step.dt);
        // marker_positions adds the initial position: subtract it (the derivative is linear in du).
        let base = model.marker_positions(&vec![0.0; model.num_dofs()]);
        let d0: Vec<Vec<Vec<f64>>> = old_u.iter().map(|u| model.marker_positions(u)).collect();
        let d1: Vec<Vec<Vec<f64>>> = self.states.iter().map(|s| model.marker_positions(&s.u)).collect();
        for (m, req) in model.problem.markers.iter().enumerate() {
            while self.marker_next[m] < req.times.len() && req.times[self.marker_next[m]] <= t1 * (1.0 + 1e-12) {
                let t = req.times[self.marker_next[m]];
                let w = if t1 <= t0 { 1.0 } else { ((t - t0) / (t1 - t0)).clamp(0.0, 1.0) };
                let row = (0..old_u.len())
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

/// One parameter over one step: the new derivative state and force terms.
fn advance_one<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    step: &StepView<'_, S>,
    tangent: &[RegionTangent<S>],
    s0: &TangentState<S>,
) -> (TangentState<S>, TangentSegment)
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mesh = &model.problem.mesh;
    let (dt, [a0, a1, a2]) = (step.dt, step.alpha);
    // Per region: g, g', and per term phi, phi', delta, delta'.
    struct Scalars {
        g: f64,
        dg: f64,
        phi: [f64; 2],
        dphi: [f64; 2],
        decay: [f64; 2],
        ddecay: [f64; 2],
    }
    let scalars: Vec<Scalars> = model
        .region_kernel
        .iter()
        .zip(tangent)
        .map(|(k, t)| {
            let dk = &t.kernel;
            let mut s = Scalars {
                g: k.viscous * a0 / dt + k.equilibrium,
                dg: dk.viscous * a0 / dt + dk.equilibrium,
                phi: [0.0; 2],
                dphi: [0.0; 2],
                decay: [0.0; 2],
                ddecay: [0.0; 2],
            };
            for j in 0..k.num_terms {
                let x = k.rates[j] * dt;
                s.phi[j] = phi1(x);
                s.dphi[j] = phi1_derivative(x) * dt * dk.rates[j];
                s.decay[j] = (-x).exp();
                s.ddecay[j] = -dt * s.decay[j] * dk.rates[j];
                s.g += k.amplitudes[j] * s.phi[j];
                s.dg += dk.amplitudes[j] * s.phi[j] + k.amplitudes[j] * s.dphi[j];
            }
            s
        })
        .collect();

    // The load: tau_e = C1' (g e1 - q) + C1 (g' e1 - q'), force -sum w B^T tau_e.
    let cell_forces: Vec<[SVector<f64, D>; N]> = map_collect(mesh.num_cells(), |e| {
        let r = mesh.cell_regions[e] as usize;
        let (k, t, s) = (&model.region_kernel[r], &tangent[r], &scalars[r]);
        let (e0, em1, e1) = (step.strain0[e], step.strain_prev0[e], step.strain1[e]);
        let mut q = (e0 * a1 - em1 * a2) * (k.viscous / dt);
        let mut dq = (e0 * a1 - em1 * a2) * (t.kernel.viscous / dt)
            + (s0.strain[e] * a1 - s0.strain_prev[e] * a2) * (k.viscous / dt);
        for j in 0..k.num_terms {
            let h0 = step.history0[e][j];
            q += (e0 * s.phi[j] - h0 * s.decay[j]) * k.amplitudes[j];
            dq += (e0 * s.phi[j] - h0 * s.decay[j]) * t.kernel.amplitudes[j]
                + (e0 * s.dphi[j] + s0.strain[e] * s.phi[j] - h0 * s.ddecay[j] - s0.history[e][j] * s.decay[j])
                    * k.amplitudes[j];
        }
        let tau = t.c1 * (e1 * s.g - q) + model.region_c1[r] * (e1 * s.dg - dq);
        let load = -tau;
        std::array::from_fn(|a| nodal_force::<D, N, S>(&model.geometry[e], &load, a))
    });
    let mut rhs = vec![0.0; model.num_dofs()];
    assemble_vector::<D, N>(&model.topology, &cell_forces, &mut rhs);
    drop(cell_forces);
    let mut x: Vec<f64> = step.system.dof_of_free.iter().map(|&d| rhs[d as usize]).collect();
    step.factor.solve_in_place(&mut x);
    if let Some(g) = step.single_group_factor {
        x.iter_mut().for_each(|v| *v /= g);
    }
    let mut u = vec![0.0; model.num_dofs()];
    for (i, &d) in step.system.dof_of_free.iter().enumerate() {
        u[d as usize] = x[i];
    }

    // Cell update.
    let updated: Vec<(SVector<f64, S>, [SVector<f64, S>; 2])> = map_collect(mesh.num_cells(), |e| {
        let r = mesh.cell_regions[e] as usize;
        let (k, s) = (&model.region_kernel[r], &scalars[r]);
        let de1 = cell_strain::<D, N, S>(&model.geometry[e].gradients, &model.cell_displacements(e, &u));
        let mut h1 = [SVector::<f64, S>::zeros(); 2];
        for j in 0..k.num_terms {
            h1[j] = step.history0[e][j] * s.ddecay[j]
                + s0.history[e][j] * s.decay[j]
                + (step.strain1[e] - step.strain0[e]) * s.dphi[j]
                + (de1 - s0.strain[e]) * s.phi[j];
        }
        (de1, h1)
    });

    // Derivatives of the reaction functionals' terms.
    let nreg = model.region_kernel.len();
    let mut terms: Vec<TangentTerms> = (0..nreg)
        .map(|r| TangentTerms {
            kernel: tangent[r].kernel,
            rate: [0.0; 2],
            rate_end: [0.0; 2],
            rate_start: [0.0; 2],
            strain: [0.0; 2],
            history: [[0.0; 2]; 2],
        })
        .collect();
    for (side, list) in model.functionals.iter().enumerate() {
        for f in list {
            let (c, r) = (f.cell, mesh.cell_regions[f.cell] as usize);
            let rc = model.region_c1[r] * f.rho;
            let drc = tangent[r].c1 * f.rho;
            let (e0, em1, e1) = (step.strain0[c], step.strain_prev0[c], step.strain1[c]);
            let (de0, dem1, de1) = (s0.strain[c], s0.strain_prev[c], updated[c].0);
            let t = &mut terms[r];
            t.rate[side] += (drc.dot(&(e1 - e0)) + rc.dot(&(de1 - de0))) / dt;
            t.rate_end[side] +=
                (drc.dot(&(e1 * a0 - e0 * a1 + em1 * a2)) + rc.dot(&(de1 * a0 - de0 * a1 + dem1 * a2))) / dt;
            t.strain[side] += drc.dot(&e0) + rc.dot(&de0);
            for j in 0..model.region_kernel[r].num_terms {
                t.history[j][side] += drc.dot(&step.history0[c][j]) + rc.dot(&s0.history[c][j]);
            }
        }
    }
    for t in &mut terms {
        t.rate_start = t.rate;
    }

    let mut strain = Vec::with_capacity(updated.len());
    let mut history = Vec::with_capacity(updated.len());
    for (de1, h1) in updated {
        strain.push(de1);
        history.push(h1);
    }
    let state = TangentState { u, strain, strain_prev: s0.strain.clone(), history };
    (state, TangentSegment { terms, detached_ends: None })
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
