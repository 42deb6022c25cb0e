/// One accepted time step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepRecord {
    /// Time at the end of the step [s].
    pub t_s: f64,
    /// Step size [s].
    pub dt_s: f64,
    /// Wall time spent in factorization and solve [s].
    pub solve_s: f64,
    /// Relative residual of the step's linear solve on the free rows, `|A u - b|`
    /// over the size of the balancing terms `(|b|^2 + |A_held u_held|^2)^(1/2)`.
    pub residual: f64,
    /// Whether the step needed a new numeric factorization.
    pub refactored: bool,
    /// Bottom reaction at the step's end, compression positive [N].
    pub bottom_force_n: f64,
    /// Plate force at the step's end, compression positive [N].
    pub plate_force_n: f64,
    /// The step controller's local error estimate, relative to its tolerance (<= 1 accepted).
    pub error_ratio: f64,
    /// Newton iterations of the step on the Newton path (network materials,
    /// `press::network`); 0 on the other paths.
    pub newton_iterations: usize,
}

/// The nodal state kept at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// Time [s].
    pub t_s: f64,
    /// Nodal displacements [mm], `dim` per node.
    pub displacement: Vec<f64>,
    /// Cell stresses [MPa], Voigt order (`[xx, yy, xy]`, `[xx, yy, zz, xy, xz, yz]`, or
    /// axisymmetric `[rr, yy, tt, ry]`).
    pub cell_stress: Vec<f64>,
}

/// A marker's simulated positions.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerTrack {
    /// The marker's name.
    pub name: String,
    /// `(t_s, position_mm)` with `dim` components each.
    pub samples: Vec<(f64, Vec<f64>)>,
}

/// How far a run has come.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Current simulated time [s].
    pub t_s: f64,
    /// End time [s].
    pub end_s: f64,
    /// Accepted steps so far.
    pub steps: usize,
}

/// Exact force between two step ends for the quasi-static scheme: the stress in a
/// step is known in closed form for a strain linear in time (design.md 3.3), so the
/// forces at any time inside follow from a few reaction functionals per region.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ForceSegment {
    pub t0: f64,
    pub dt: f64,
    /// Per region: [rate term P, strain term Q, history terms H_k...], bottom then plate.
    pub terms: Vec<RegionTerms>,
    /// Constant body-force part of the reactions (gravity), bottom and plate.
    pub constant: [f64; 2],
    /// Forces at the step's start and end when the plate is detached: then nothing
    /// but the body force loads the specimen, the reactions are fixed by equilibrium
    /// and are interpolated linearly between the (exact) step ends.
    pub detached_ends: Option<[[f64; 2]; 2]>,
    /// With contact tools: the plate force (the sum over the tools that are not
    /// floors) at the step's start and end, interpolated linearly inside.
    pub plate_ends: Option<[f64; 2]>,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RegionTerms {
    pub kernel: crate::material::RelaxationKernel,
    /// `R(C1 de/dt)` (the mean rate), `R(C1 e'(t1))` (the backward-difference rate at
    /// the step's end), `R(C1 e_n)`, `R(C1 h_k,n)` for the bottom [0] and plate [1]
    /// functionals. Both rates are equal for a strain linear in time.
    pub rate: [f64; 2],
    pub rate_end: [f64; 2],
    /// The viscous rate at the step's start: the previous step's end rate, or the
    /// mean rate after a kink (where the true rate jumps).
    pub rate_start: [f64; 2],
    pub strain: [f64; 2],
    pub history: [[f64; 2]; 2],
    /// Whether the plate is attached during this step.
    pub plate_attached: bool,
}

impl ForceSegment {
    pub(crate) fn eval(&self, tau: f64) -> [f64; 2] {
        if let Some([start, end]) = self.detached_ends {
            let w = tau / self.dt;
            return [start[0] + w * (end[0] - start[0]), start[1] + w * (end[1] - start[1])];
        }
        let mut f = self.eval_formula(tau);
        if let Some([a, b]) = self.plate_ends {
            f[1] = a + (tau / self.dt) * (b - a);
        }
        f
    }

    /// The closed-form force inside the step for a strain linear in time.
    pub(crate) fn eval_formula(&self, tau: f64) -> [f64; 2] {
        let mut f = self.constant;
        for r in &self.terms {
            let k = &r.kernel;
            for side in 0..2 {
                if side == 1 && !r.plate_attached {
                    continue;
                }
                let viscous_rate = r.rate_start[side] + (tau / self.dt) * (r.rate_end[side] - r.rate_start[side]);
                let mut v = k.viscous * viscous_rate + k.equilibrium * (r.strain[side] + tau * r.rate[side]);
                for j in 0..k.num_terms {
                    let x = k.rates[j] * tau;
                    v += k.amplitudes[j]
                        * ((-x).exp() * r.history[j][side] + crate::material::phi1(x) * tau * r.rate[side]);
                }
                f[side] += v;
            }
        }
        f
    }
}

/// Everything a run produced.
#[derive(Debug, Clone, PartialEq)]
pub struct PressResult {
    /// Spatial dimension (2 or 3).
    pub dim: usize,
    /// Number of strain components per cell stress in snapshots.
    pub num_stress: usize,
    /// Accepted steps, in time order.
    pub steps: Vec<StepRecord>,
    /// Kept nodal states: the release time, the end time and any requested ones.
    pub snapshots: Vec<Snapshot>,
    /// Marker positions at the requested times.
    pub markers: Vec<MarkerTrack>,
    /// Number of numeric factorizations.
    pub num_factorizations: usize,
    /// Right-hand sides solved with the step matrix in steps with contact tools
    /// (penalized, eliminated or low-rank solves; zero without tools).
    pub contact_solves: usize,
    /// Nonzeros of the (largest) Cholesky factor.
    pub factor_nonzeros: usize,
    /// Free degrees of freedom (largest constraint set).
    pub num_free_dofs: usize,
    /// Per tool (in the problem's order): contact forces, area and nodes over time;
    /// empty without tools.
    pub tools: Vec<super::contact::ToolTrack>,
    pub(crate) segments: Vec<ForceSegment>,
    /// The `force-offset` effect's `[b0 N, b1 N/s]` on the bottom force, when active.
    pub(crate) force_offset: Option<[f64; 2]>,
}

impl PressResult {
    /// The sensor's offset at time `t` [N] (0 without the `force-offset` effect).
    fn offset_at(&self, t: f64) -> f64 {
        self.force_offset.map_or(0.0, |[b0, b1]| b0 + b1 * t)
    }

    /// Applies the `force-offset` effect to the reported bottom force: `F + b0 + b1 t`
    /// in every step record and at every time of [`PressResult::bottom_force_at`].
    pub(crate) fn observe_force_offset(&mut self, offset: [f64; 2]) {
        self.force_offset = Some(offset);
        for s in &mut self.steps {
            s.bottom_force_n += offset[0] + offset[1] * s.t_s;
        }
    }

    fn forces_at(&self, t: f64) -> [f64; 2] {
        let mut f = self.engine_forces_at(t);
        if self.force_offset.is_some() {
            f[0] += self.offset_at(t);
        }
        f
    }

    /// The engine's forces, without the sensor's offset.
    fn engine_forces_at(&self, t: f64) -> [f64; 2] {
        if let Some(first) = self.segments.first() {
            // Left limits at kinks (as the closed forms): nothing has moved at t <= 0.
            if t <= first.t0 {
                return first.constant;
            }
            // The segment whose interval contains t (the first one at a shared end).
            let i = self.segments.partition_point(|s| s.t0 + s.dt < t).min(self.segments.len() - 1);
            let s = &self.segments[i];
            return s.eval((t - s.t0).clamp(0.0, s.dt));
        }
        // Integrators without dense output: linear interpolation of step ends (the
        // engine's bottom force, without the sensor's offset).
        let bottom = |s: &StepRecord| s.bottom_force_n - self.offset_at(s.t_s);
        let i = self.steps.partition_point(|s| s.t_s < t);
        if i == 0 {
            let s = &self.steps[0];
            let w = (t / s.t_s).clamp(0.0, 1.0);
            return [w * bottom(s), w * s.plate_force_n];
        }
        if i >= self.steps.len() {
            let s = self.steps.last().unwrap();
            return [bottom(s), s.plate_force_n];
        }
        let (a, b) = (&self.steps[i - 1], &self.steps[i]);
        let w = (t - a.t_s) / (b.t_s - a.t_s);
        [bottom(a) + w * (bottom(b) - bottom(a)), a.plate_force_n + w * (b.plate_force_n - a.plate_force_n)]
    }

    /// The bottom reaction at time `t` [N], compression positive (exact inside each
    /// quasi-static step; interpolated for the dynamic schemes).
    pub fn bottom_force_at(&self, t: f64) -> f64 {
        self.forces_at(t)[0]
    }

    /// The plate force at time `t` [N], compression positive.
    pub fn plate_force_at(&self, t: f64) -> f64 {
        self.forces_at(t)[1]
    }

    /// The largest bottom force over the step ends [N] (as reported: with the
    /// `force-offset` effect, offset included).
    pub fn peak_force(&self) -> f64 {
        self.steps.iter().map(|s| s.bottom_force_n).fold(f64::NEG_INFINITY, f64::max)
    }

    /// The snapshot kept at time `t` (within 1e-9 s).
    pub fn snapshot_at(&self, t: f64) -> Option<&Snapshot> {
        self.snapshots.iter().find(|s| (s.t_s - t).abs() <= 1e-9 * t.abs().max(1.0))
    }
}
