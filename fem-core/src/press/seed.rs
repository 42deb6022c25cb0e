//! The seed's own scheme (its eq. 8), kept as a reference integrator.
//!
//! Dynamics with a lumped mass, the plate and floor constraints imposed by
//! constraint stabilisation (eq. 6, `psi = 2000` 1/s), and the hereditary force
//! carried by nodal history variables integrated with an explicit Runge-Kutta
//! method. The seed's `omega` variables (eq. 5) combine, per material, into
//! `J (omega_1 - omega_2) = K1 (B2 v + G_inf u + sum_k a_k w_k)` with
//! `w_k' = -r_k w_k + v`: the same relaxation function written as nodal state.
//! The system is integrated by Dormand-Prince 5(4) with error control (what
//! MATLAB's ode45, the seed's tool, does); the viscous term `B2 K1 v` against the
//! mass makes it stiff, so its steps are tiny: that is the cost this reference
//! measures.

use std::time::Instant;

use nalgebra::SVector;
use rayon::prelude::*;

use crate::parallel::{for_each_mut, max_of};

use super::model::{Constraints, Model};
use super::stepper::emit_markers;
use super::{MarkerTrack, PressError, PressProblem, PressResult, Progress, Settings, Snapshot, StepRecord};
use crate::element::{cell_strain, ReferenceSimplex, Simplex};

// Dormand-Prince 5(4) tableau.
const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
/// Fifth-order weights minus fourth-order ones (the error estimate).
const E: [f64; 7] =
    [71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];
/// Relative tolerance of the Runge-Kutta error control.
const RK_RTOL: f64 = 1e-6;

/// Layout of the state vector: `[u, v, w_(g,k)...]`, each block `ndof` long.
struct Layout {
    ndof: usize,
    /// `(group, term)` of each history block.
    histories: Vec<(usize, usize)>,
}

impl Layout {
    fn len(&self) -> usize {
        self.ndof * (2 + self.histories.len())
    }
}

pub(crate) fn run<const D: usize, const N: usize, const S: usize>(
    problem: &PressProblem<D, N, S>,
    settings: &Settings,
    progress: &mut dyn FnMut(Progress),
) -> Result<PressResult, PressError>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    if !(settings.seed_psi.is_finite() && settings.seed_psi > 0.0) {
        return Err(PressError::BadSettings(format!("psi = {} must be > 0", settings.seed_psi)));
    }
    let model = Model::new(problem)?;
    let protocol = &problem.protocol;
    let end = protocol.end_s;
    let ndof = model.num_dofs();
    let layout = Layout {
        ndof,
        histories: model
            .groups
            .iter()
            .enumerate()
            .flat_map(|(g, grp)| (0..grp.kernel.num_terms).map(move |k| (g, k)))
            .collect(),
    };
    let schedule = problem.schedule();
    let atol = 1e-9 * model.displacement_scale;
    let record_every = end / 4000.0;

    let mut y = vec![0.0; layout.len()];
    let mut t: f64 = 0.0;
    let mut h: f64 = 1e-6;
    let mut k: Vec<Vec<f64>> = vec![vec![0.0; layout.len()]; 7];
    let mut steps = Vec::new();
    let mut snapshots = Vec::new();
    let mut tracks: Vec<MarkerTrack> =
        problem.markers.iter().map(|m| MarkerTrack { name: m.name.clone(), samples: Vec::new() }).collect();
    let mut marker_next = vec![0usize; problem.markers.len()];
    emit_markers(&model, &mut tracks, &mut marker_next, &y[..ndof], &y[..ndof], 0.0, 0.0, true);
    let mut num_steps = 0usize;
    let mut last_record = 0.0;
    let (mut last_force, mut peak_force) = (0.0f64, 0.0f64);
    let clock = Instant::now();
    let mut constraints = model.constraints_at(1e-300);
    let mut reactions = [0.0; 2];
    rhs(&model, &layout, constraints, settings.seed_psi, t, &y, &mut k[0], &mut reactions);
    let mut ytmp = vec![0.0; layout.len()];
    while t < end * (1.0 - 1e-13) {
        let landing = schedule.next_landing(t, end);
        let mut step = h.min(landing - t);
        let lands = step >= (landing - t) * (1.0 - 1e-12);
        if lands {
            step = landing - t;
        }
        let t1 = if lands { landing } else { t + step };
        constraints = model.constraints_at(t1);
        // Stages 2..7 (stage 1 is the previous step's last, first-same-as-last).
        for s in 1..7 {
            for_each_mut(&mut ytmp, |i, yi| {
                let mut acc = y[i];
                for j in 0..s {
                    acc += step * A[s][j] * k[j][i];
                }
                *yi = acc;
            });
            let (_, tail) = k.split_at_mut(s);
            rhs(&model, &layout, constraints, settings.seed_psi, t + C[s] * step, &ytmp, &mut tail[0], &mut reactions);
        }
        // ytmp now holds the fifth-order solution (stage 7 node). Error norm:
        let err = max_of(layout.len(), |i| {
            let e: f64 = (0..7).map(|j| E[j] * k[j][i]).sum::<f64>() * step;
            let scale =
                atol * if i / ndof == 1 { settings.seed_psi } else { 1.0 } + RK_RTOL * y[i].abs().max(ytmp[i].abs());
            (e / scale).abs()
        });
        if !err.is_finite() {
            let dof = ytmp.iter().position(|v| !v.is_finite()).unwrap_or(0) % ndof;
            let node = dof / D;
            let element = model.cell_of_node(node).unwrap_or(usize::MAX);
            return Err(PressError::NonFinite { step: num_steps + 1, time_s: t1, element, node });
        }
        if err > 1.0 {
            h = step * (0.9 * err.powf(-0.2)).clamp(0.2, 0.9);
            if h < 1e-14 * end {
                return Err(PressError::StepTooSmall { step: num_steps + 1, time_s: t, dt_s: h });
            }
            continue;
        }
        num_steps += 1;
        emit_markers(&model, &mut tracks, &mut marker_next, &y[..ndof], &ytmp[..ndof], t, t1, false);
        std::mem::swap(&mut y, &mut ytmp);
        k.swap(0, 6);
        let prev_t = t;
        t = t1;
        // The reactions at t1 come with the last stage's evaluation (at t1, y1).
        // Record every `record_every` seconds, at kinks, and whenever the force has
        // moved by more than 0.1 % of the largest so far (so that the fast drop at
        // release, about 1/psi long, is resolved in the kept samples).
        let moved = (reactions[0] - last_force).abs() > 1e-3 * peak_force.max(f64::MIN_POSITIVE);
        if t - last_record >= record_every || lands || moved {
            last_force = reactions[0];
            peak_force = peak_force.max(reactions[0].abs());
            steps.push(StepRecord {
                t_s: t,
                dt_s: t - prev_t,
                solve_s: clock.elapsed().as_secs_f64(),
                residual: 0.0,
                refactored: false,
                bottom_force_n: reactions[0],
                plate_force_n: reactions[1],
                error_ratio: err,
                newton_iterations: 0,
            });
            last_record = t;
            progress(Progress { t_s: t, end_s: end, steps: num_steps });
        }
        if schedule.is_snapshot(t, end) {
            snapshots.push(Snapshot {
                t_s: t,
                displacement: model.reported(&y[..ndof], t),
                cell_stress: cell_stress(&model, &layout, &y),
            });
        }
        if lands {
            // The constraint set may change: restart the stage cache at the new set.
            let next = model.constraints_at(t + 1e-9 * end);
            rhs(&model, &layout, next, settings.seed_psi, t, &y, &mut k[0], &mut reactions);
        }
        h = step * (0.9 * err.max(1e-10).powf(-0.2)).clamp(0.2, 5.0);
    }
    Ok(PressResult {
        dim: D,
        num_stress: S,
        steps,
        snapshots,
        markers: tracks,
        num_factorizations: 0,
        contact_solves: 0,
        factor_nonzeros: 0,
        num_free_dofs: model.released.held.iter().filter(|h| !**h).count(),
        tools: Vec::new(),
        segments: Vec::new(),
        force_offset: None,
    })
}

/// `dy/dt` of the seed's system; writes the bottom and plate reactions (compression positive).
#[allow(clippy::too_many_arguments)]
fn rhs<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    layout: &Layout,
    constraints: &Constraints,
    psi: f64,
    t: f64,
    y: &[f64],
    dy: &mut [f64],
    reactions: &mut [f64; 2],
) where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let n = layout.ndof;
    let (u, rest) = y.split_at(n);
    let (v, w) = rest.split_at(n);
    // Internal force: sum_g K_g (B2 v + G_inf u + sum_k a_k w_k).
    let mut f = vec![0.0; n];
    let mut tmp = vec![0.0; n];
    for (g, grp) in model.groups.iter().enumerate() {
        let kern = &grp.kernel;
        let mut x: Vec<f64> = (0..n).map(|i| kern.viscous * v[i] + kern.equilibrium * u[i]).collect();
        for (b, &(hg, term)) in layout.histories.iter().enumerate() {
            if hg == g {
                let wb = &w[b * n..(b + 1) * n];
                x.iter_mut().zip(wb).for_each(|(xi, wi)| *xi += kern.amplitudes[term] * wi);
            }
        }
        model.pattern.mul_vec(&grp.stiffness, &x, &mut tmp);
        f.iter_mut().zip(&tmp).for_each(|(fi, ti)| *fi += ti);
    }
    let (du, rest) = dy.split_at_mut(n);
    let (dv, dw) = rest.split_at_mut(n);
    du.copy_from_slice(v);
    let d = model.problem.protocol.displacement(t);
    let dd = model.problem.protocol.velocity(t);
    let mut target = vec![0.0; n];
    let mut target_v = vec![0.0; n];
    for &dof in &constraints.plate_dofs {
        target[dof] = -d;
        target_v[dof] = -dd;
    }
    let mut reaction = [0.0; 2];
    for i in 0..n {
        if constraints.held[i] {
            // Constraint stabilisation (eq. 6): the held dofs relax onto their targets.
            dv[i] = -2.0 * psi * (v[i] - target_v[i]) - psi * psi * (u[i] - target[i]);
        } else {
            dv[i] = (model.body_force[i] - f[i]) / model.mass[i];
        }
    }
    // Reactions lambda = M v' + f - f_body on the bottom and top y dofs.
    let mesh = &model.problem.mesh;
    for (side, name) in ["bottom", "top"].iter().enumerate() {
        if side == 1 && !constraints.plate_attached {
            continue;
        }
        let sign = if side == 0 { 1.0 } else { -1.0 };
        for &node in &mesh.node_sets[*name] {
            let i = node as usize * D + 1;
            reaction[side] += sign * (model.mass[i] * dv[i] + f[i] - model.body_force[i]);
        }
    }
    *reactions = reaction;
    for (b, &(g, term)) in layout.histories.iter().enumerate() {
        let r = model.groups[g].kernel.rates[term];
        let wb = &w[b * n..(b + 1) * n];
        let dwb = &mut dw[b * n..(b + 1) * n];
        for i in 0..n {
            dwb[i] = -r * wb[i] + v[i];
        }
    }
}

/// Cell stresses from the nodal state (for snapshots).
fn cell_stress<const D: usize, const N: usize, const S: usize>(
    model: &Model<'_, D, N, S>,
    layout: &Layout,
    y: &[f64],
) -> Vec<f64>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let n = layout.ndof;
    let mesh = &model.problem.mesh;
    (0..mesh.num_cells())
        .into_par_iter()
        .flat_map_iter(|e| {
            let r = mesh.cell_regions[e] as usize;
            let k = &model.region_kernel[r];
            let strain_of =
                |x: &[f64]| cell_strain::<D, N, S>(&model.geometry[e].gradients, &model.cell_displacements(e, x));
            let mut s: SVector<f64, S> = strain_of(&y[n..2 * n]) * k.viscous + strain_of(&y[..n]) * k.equilibrium;
            // Region kernels are proportional to their group's: reuse the group histories.
            for (b, &(_, term)) in layout.histories.iter().enumerate() {
                let group_kernel = model
                    .groups
                    .iter()
                    .position(|g| k.proportional_to(&g.kernel).is_some())
                    .expect("every region belongs to a group");
                if layout.histories[b].0 == group_kernel {
                    s += strain_of(&y[(2 + b) * n..(3 + b) * n]) * k.amplitudes[term];
                }
            }
            let stress = model.region_c1[r] * s;
            stress.iter().copied().collect::<Vec<_>>()
        })
        .collect()
}
