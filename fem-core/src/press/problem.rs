use thiserror::Error;

use super::ToolContact;
use crate::effects::{EffectError, EffectId, Effects};
use crate::element::{valid_strain_size, Formulation, ReferenceSimplex, Simplex};
use crate::material::Material;
use crate::mesh::{MeshError, SimplexMesh, TetMesh, TriMesh};

/// How a face is held by the plate or the floor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Attachment {
    /// No slip: every displacement component follows the plate (or is zero on the floor).
    Glued,
    /// Only the normal (y) component is held; the face slides freely.
    Frictionless,
    /// Nothing holds the face by a constraint (a contact tool may, e.g. a floor
    /// with friction, [`super::Tool::floor_below`]).
    Free,
}

/// The loading protocol of a press trial.
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    /// `[t_s, d_mm]`: downward plate displacement from first touch, piecewise linear.
    pub waypoints: Vec<[f64; 2]>,
    /// The plate lets go at this time [s].
    pub release_s: f64,
    /// The trial ends here [s]; the shape then is the final shape.
    pub end_s: f64,
    /// How the top face is held by the plate until release.
    pub plate: Attachment,
    /// How the bottom face is held by the floor.
    pub support: Attachment,
    /// Gravity along -y (9.81 m/s^2), off by default.
    pub gravity: bool,
}

impl Protocol {
    /// Push at `speed` [mm/s] for `push_s`, hold until `release_s`, recover until `end_s`;
    /// glued plates, no gravity (the seed's protocol, Table I).
    pub fn ramp_hold_release(speed_mm_s: f64, push_s: f64, release_s: f64, end_s: f64) -> Self {
        let d = speed_mm_s * push_s;
        Self {
            waypoints: vec![[0.0, 0.0], [push_s, d], [release_s, d]],
            release_s,
            end_s,
            plate: Attachment::Glued,
            support: Attachment::Glued,
            gravity: false,
        }
    }

    /// The plate displacement d(t) [mm] (held constant past the last waypoint).
    pub fn displacement(&self, t: f64) -> f64 {
        let w = &self.waypoints;
        if w.is_empty() {
            return 0.0;
        }
        if t <= w[0][0] {
            return w[0][1];
        }
        for pair in w.windows(2) {
            let ([t0, d0], [t1, d1]) = (pair[0], pair[1]);
            if t <= t1 {
                return if t1 > t0 { d0 + (d1 - d0) * (t - t0) / (t1 - t0) } else { d1 };
            }
        }
        w[w.len() - 1][1]
    }

    /// The plate velocity d'(t) [mm/s] on the segment that ends after `t`.
    pub fn velocity(&self, t: f64) -> f64 {
        for pair in self.waypoints.windows(2) {
            let ([t0, d0], [t1, d1]) = (pair[0], pair[1]);
            if t < t1 && t >= t0 && t1 > t0 {
                return (d1 - d0) / (t1 - t0);
            }
        }
        0.0
    }

    /// Times where the loading has a kink: waypoints in (0, end), release, end; sorted.
    pub fn kinks(&self) -> Vec<f64> {
        let mut k: Vec<f64> = self.waypoints.iter().map(|w| w[0]).filter(|&t| t > 0.0 && t < self.end_s).collect();
        k.push(self.release_s.min(self.end_s));
        k.push(self.end_s);
        k.sort_by(f64::total_cmp);
        k.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs().max(1.0));
        k
    }

    /// Refuses waypoints out of time order, negative times, a release or end
    /// before the last waypoint that pushes, and an end before the release.
    pub fn validate(&self) -> Result<(), PressError> {
        let bad = |m: String| Err(PressError::BadProtocol(m));
        if self.waypoints.is_empty() {
            return bad("no waypoints".into());
        }
        for (i, w) in self.waypoints.iter().enumerate() {
            if !(w[0].is_finite() && w[1].is_finite()) || w[0] < 0.0 {
                return bad(format!("waypoint {i} = [{}, {}] must be finite with t >= 0", w[0], w[1]));
            }
            if i > 0 && w[0] <= self.waypoints[i - 1][0] {
                return bad(format!("waypoint {i} at t = {} s is not after the previous one", w[0]));
            }
        }
        let last_push = self.waypoints.windows(2).filter(|p| p[1][1] != p[0][1]).map(|p| p[1][0]).fold(0.0, f64::max);
        if !(self.release_s.is_finite() && self.release_s >= last_push) {
            return bad(format!("release_s = {} is before the last pushing waypoint ({last_push} s)", self.release_s));
        }
        if !(self.end_s.is_finite() && self.end_s >= last_push && self.end_s > 0.0) {
            return bad(format!("end_s = {} is before the last pushing waypoint ({last_push} s)", self.end_s));
        }
        if self.end_s < self.release_s {
            return bad(format!("end_s = {} is before release_s = {}", self.end_s, self.release_s));
        }
        Ok(())
    }
}

/// A marker: the material point at `position` (initial, mm), reported at `times`.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerRequest {
    /// The marker's name.
    pub name: String,
    /// Initial position [mm], `D` components; `(r, y)` in the section of an
    /// axisymmetric problem (its tracks are `(r, y)` too).
    pub position: Vec<f64>,
    /// Times at which to report its position [s].
    pub times: Vec<f64>,
}

/// The time integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Integrator {
    /// Quasi-static implicit with the exact exponential history update (default).
    #[default]
    QuasiStatic,
    /// Dynamic, generalized-alpha with a lumped mass.
    Dynamic,
    /// The seed's scheme: dynamics, constraint stabilisation (psi = 2000), explicit RK.
    Seed,
}

/// How the Newton path's cells take volume changes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Volumetric {
    /// Each linear cell its own `J` (default): locks as the Poisson ratio nears 1/2.
    #[default]
    Standard,
    /// F-bar patches: the cells of a patch share its mean `J`; for Poisson
    /// ratios from about 0.45 to 0.5. Network materials only.
    FBar,
}

/// Numerical settings of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The integrator; default quasi-static.
    pub integrator: Integrator,
    /// Local error tolerance of the adaptive step control, relative to the largest
    /// plate displacement; default 1e-3.
    pub rtol: f64,
    /// Local error tolerance of the adaptive step control on the inelastic flow
    /// (the material-point effects E1 to E4: slider, Bingham, thinning, dual
    /// viscosity), relative to the plate's largest nominal strain (its largest
    /// displacement over the specimen's height): the volume-weighted RMS over the
    /// cells of the inelastic strain's estimated local error, in the energy norm,
    /// must stay below `flow_rtol` times that strain. Default `None`: a tenth of
    /// `rtol` (the flow is integrated to first order; why a tenth, and the
    /// measurements: `press::stepper`, "Step control"). Without such an effect it
    /// has no use.
    pub flow_rtol: Option<f64>,
    /// A fixed step [s] instead of adaptive steps (steps still land on kinks).
    pub fixed_dt_s: Option<f64>,
    /// Upper bound on the step [s]; default: a twentieth of the trial.
    pub max_dt_s: Option<f64>,
    /// The constraint stabilisation frequency of the seed's scheme [1/s]; default 2000.
    pub seed_psi: f64,
    /// Spectral radius at infinite frequency of the dynamic generalized-alpha
    /// scheme, in [0, 1]; default 0.5 (1 is Newmark's trapezoidal rule).
    pub rho_inf: f64,
    /// Replay these step ends [s] (e.g. an earlier run's `steps[i].t_s`) instead of
    /// choosing steps: the quasi-static and dynamic schemes then take exactly those
    /// steps, with no error control. For finite-difference checks of sensitivities.
    pub step_ends_s: Option<Vec<f64>>,
    /// The Newton path's volumetric treatment; default each cell its own.
    pub volumetric: Volumetric,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            integrator: Integrator::QuasiStatic,
            rtol: 1e-3,
            flow_rtol: None,
            fixed_dt_s: None,
            max_dt_s: None,
            seed_psi: 2000.0,
            rho_inf: 0.5,
            step_ends_s: None,
            volumetric: Volumetric::Standard,
        }
    }
}

/// A press problem in `D` dimensions with `N`-node cells and `S` strain components.
#[derive(Debug, Clone)]
pub struct PressProblem<const D: usize, const N: usize, const S: usize> {
    /// The specimen; needs the node sets `bottom` and `top` (and `axis` when
    /// axisymmetric: the nodes on r = 0, which hold `u_r = 0`).
    pub mesh: SimplexMesh<D, N>,
    /// 3D solid, 2D plane stress/strain with a thickness, or 2D axisymmetric (the
    /// `r-y` section of a body of revolution about y, `x = r >= 0`).
    pub formulation: Formulation,
    /// One material per mesh region (indexed like `mesh.region_names`).
    pub materials: Vec<Material>,
    /// Density [t/mm^3] (1 g/cm^3 = 1e-9 t/mm^3), for gravity and the dynamic schemes.
    pub density_t_mm3: f64,
    /// The loading.
    pub protocol: Protocol,
    /// Markers to track.
    pub markers: Vec<MarkerRequest>,
    /// Extra times at which to keep the nodal displacements [s] (release and end are always kept).
    pub snapshot_times: Vec<f64>,
    /// Rigid tools in contact with the specimen. When there are any, they replace
    /// the protocol's plate (the `top` set is then not held; `protocol.plate` is
    /// ignored) and only the quasi-static integrator runs; `protocol.support` still
    /// holds the `bottom` set (use [`Attachment::Free`] with a floor tool for a
    /// floor with friction). The protocol's waypoints and release still set step
    /// landings.
    pub tools: Vec<super::Tool>,
    /// Candidate effects of the gap diagnosis ([`crate::effects`]); default none
    /// (the baseline, unchanged bit for bit).
    pub effects: Effects,
}

/// A 2D (plane) press problem.
pub type PlanePress = PressProblem<2, 3, 3>;
/// A 3D (solid) press problem.
pub type SolidPress = PressProblem<3, 4, 6>;
/// A 2D axisymmetric press problem: triangles in the `r-y` section, strains
/// `[rr, yy, θθ, ry]`, full-circle forces.
pub type AxisymmetricPress = PressProblem<2, 3, 4>;

/// A press problem of any formulation.
#[derive(Debug, Clone)]
pub enum AnyPress {
    /// Triangles, plane stress or plane strain.
    Plane(PlanePress),
    /// Tetrahedra.
    Solid(SolidPress),
    /// Axisymmetric triangles (a body of revolution about y).
    Axisymmetric(AxisymmetricPress),
}

impl AnyPress {
    /// Whether the problem presses with contact tools (which run without
    /// sensitivities: derivatives of such a run are taken by differences).
    pub fn has_tools(&self) -> bool {
        match self {
            AnyPress::Plane(p) => !p.tools.is_empty(),
            AnyPress::Solid(p) => !p.tools.is_empty(),
            AnyPress::Axisymmetric(p) => !p.tools.is_empty(),
        }
    }

    /// Whether a material carries a Mullins-type damage that runs (which, like
    /// the material-point effects, runs without sensitivities).
    pub fn has_damage(&self) -> bool {
        let forced = self.effects().forces_material_point_path();
        match self {
            AnyPress::Plane(p) => p.materials.iter().any(|m| m.damage_runs(forced)),
            AnyPress::Solid(p) => p.materials.iter().any(|m| m.damage_runs(forced)),
            AnyPress::Axisymmetric(p) => p.materials.iter().any(|m| m.damage_runs(forced)),
        }
    }

    /// Whether a material is a network (run on the Newton path, which carries
    /// no forward sensitivities: its derivatives are taken by differences).
    pub fn has_network(&self) -> bool {
        match self {
            AnyPress::Plane(p) => p.materials.iter().any(|m| m.network.is_some()),
            AnyPress::Solid(p) => p.materials.iter().any(|m| m.network.is_some()),
            AnyPress::Axisymmetric(p) => p.materials.iter().any(|m| m.network.is_some()),
        }
    }

    /// The largest Poisson ratio of the network materials, if any: from about
    /// 0.45, linear cells lock and [`Volumetric::FBar`] is due.
    pub fn largest_network_poisson(&self) -> Option<f64> {
        let largest = |materials: &[Material]| {
            materials.iter().filter_map(|m| m.network.as_ref().map(|n| n.poisson)).reduce(f64::max)
        };
        match self {
            AnyPress::Plane(p) => largest(&p.materials),
            AnyPress::Solid(p) => largest(&p.materials),
            AnyPress::Axisymmetric(p) => largest(&p.materials),
        }
    }

    /// The problem's effects.
    pub fn effects(&self) -> &Effects {
        match self {
            AnyPress::Plane(p) => &p.effects,
            AnyPress::Solid(p) => &p.effects,
            AnyPress::Axisymmetric(p) => &p.effects,
        }
    }
}

/// Why a press problem was refused or failed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PressError {
    /// The mesh is invalid.
    #[error("mesh: {0}")]
    Mesh(MeshError),
    /// Regions and materials do not match.
    #[error("the mesh has {regions} regions but {materials} materials were given")]
    MaterialCount { regions: usize, materials: usize },
    /// A material's parameters were refused.
    #[error("material of region `{region}`: {source}")]
    Material { region: String, source: crate::material::MaterialError },
    /// The protocol was refused.
    #[error("protocol: {0}")]
    BadProtocol(String),
    /// The formulation does not fit the problem's dimensions or mesh (e.g. an
    /// axisymmetric mesh with nodes at r < 0).
    #[error("formulation: {0}")]
    BadFormulation(String),
    /// A marker that is not inside the specimen.
    #[error("marker `{name}` at {position:?} mm is not inside the specimen (nearest cell {distance_mm:.3e} mm away)")]
    MarkerOutside { name: String, position: Vec<f64>, distance_mm: f64 },
    /// The step matrix is not positive definite (an unconstrained rigid motion or a
    /// non-physical material).
    #[error("step {step} at t = {time_s:.6} s: the step matrix is singular or not positive definite{}", match (node, element) {
        (Some(n), Some(e)) => format!(" at node {n} (element {e})"),
        (Some(n), None) => format!(" at node {n}, which belongs to no element"),
        _ => format!(" ({detail})"),
    })]
    Singular { step: usize, time_s: f64, node: Option<usize>, element: Option<usize>, detail: String },
    /// A NaN or infinity appeared in the solution.
    #[error("step {step} at t = {time_s:.6} s: non-finite displacement in element {element} (node {node})")]
    NonFinite { step: usize, time_s: f64, element: usize, node: usize },
    /// A cell turned inside out.
    #[error("step {step} at t = {time_s:.6} s: element {element} inverted (volume ratio {ratio:.3e})")]
    Inverted { step: usize, time_s: f64, element: usize, ratio: f64 },
    /// The step size fell below the smallest allowed.
    #[error("step {step} at t = {time_s:.6} s: step size {dt_s:.3e} s below the minimum; the error control cannot meet rtol")]
    StepTooSmall { step: usize, time_s: f64, dt_s: f64 },
    /// Settings out of range.
    #[error("settings: {0}")]
    BadSettings(String),
    /// A tool was refused.
    #[error("tool `{tool}`: {detail}")]
    BadTool { tool: String, detail: String },
    /// The contact did not settle (a chattering active set or a diverging
    /// iteration), even at a smaller step.
    #[error(
        "step {step} at t = {time_s:.6} s: contact with tool `{tool}` did not settle at nodes {}",
        list_nodes(nodes)
    )]
    ContactNotSettled { step: usize, time_s: f64, tool: String, nodes: Vec<u32> },
    /// The material-point iteration of a step did not converge (or a local update
    /// had no solution), even at a smaller step.
    #[error("step {step} at t = {time_s:.6} s: the material-point iteration did not converge: {detail}")]
    NotConverged { step: usize, time_s: f64, detail: String },
    /// The machine's deflection (the `machine-compliance` effect) did not settle
    /// in a step (its scalar iteration found no bracket, or did not close it),
    /// even at a smaller step; `detail` says which, with the deflections [mm] and
    /// the residuals `delta - c F` [mm] it reached.
    #[error("step {step} at t = {time_s:.6} s: the machine-compliance deflection did not converge: {detail}")]
    DeflectionNotConverged { step: usize, time_s: f64, detail: String },
    /// Effect values refused, or an effect that does not fit the problem.
    #[error("effects: {0}")]
    Effect(EffectError),
    /// The caller's cancel flag was set: the run stopped after step `step`
    /// (accepted, ending at `time_s` [s]) and returned nothing.
    #[error("step {step} at t = {time_s:.6} s: cancelled between steps")]
    Cancelled { step: usize, time_s: f64 },
}

// The wrapped errors are printed in the message and not exposed as sources
// (a chain printer would show them twice): `From` by hand, not `#[from]`.
impl From<MeshError> for PressError {
    fn from(e: MeshError) -> Self {
        Self::Mesh(e)
    }
}

impl From<EffectError> for PressError {
    fn from(e: EffectError) -> Self {
        Self::Effect(e)
    }
}

fn list_nodes(nodes: &[u32]) -> String {
    let mut s: Vec<String> = nodes.iter().take(8).map(|n| n.to_string()).collect();
    if nodes.len() > 8 {
        s.push(format!("... ({} in all)", nodes.len()));
    }
    s.join(", ")
}

/// The times an integrator's steps must land on, and the times whose state it keeps.
pub(crate) struct Schedule {
    /// Protocol kinks and requested snapshot times in (0, end], sorted, unique.
    pub landings: Vec<f64>,
    /// Requested snapshot times, the release (when inside the trial) and the end.
    pub snapshots: Vec<f64>,
}

impl Schedule {
    /// Whether `t` is one of the snapshot times.
    pub fn is_snapshot(&self, t: f64, end: f64) -> bool {
        self.snapshots.iter().any(|&s| (s - t).abs() <= 1e-12 * end.max(1.0))
    }

    /// The first landing after `t` (the end when none is left).
    pub fn next_landing(&self, t: f64, end: f64) -> f64 {
        self.landings.iter().copied().find(|&k| k > t + 1e-12 * end.max(1.0)).unwrap_or(end)
    }
}

impl<const D: usize, const N: usize, const S: usize> PressProblem<D, N, S>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    /// The protocol's kinks and the tools' (keyframes, releases), sorted, unique.
    pub(crate) fn kinks(&self) -> Vec<f64> {
        let end = self.protocol.end_s;
        let mut k = self.protocol.kinks();
        for tool in &self.tools {
            k.extend(tool.kinks(end));
        }
        k.sort_by(f64::total_cmp);
        k.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs().max(1.0));
        k
    }

    pub(crate) fn schedule(&self) -> Schedule {
        let end = self.protocol.end_s;
        let mut landings = self.kinks();
        landings.extend(self.snapshot_times.iter().copied().filter(|&t| t > 0.0 && t < end));
        landings.sort_by(f64::total_cmp);
        landings.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs().max(1.0));
        let mut snapshots: Vec<f64> = self.snapshot_times.iter().copied().filter(|&t| t > 0.0 && t <= end).collect();
        if self.protocol.release_s <= end {
            snapshots.push(self.protocol.release_s);
        }
        snapshots.push(end);
        Schedule { landings, snapshots }
    }

    /// Checks the mesh, materials, sets and protocol; for the axisymmetric
    /// formulation also that the mesh lies in `r = x >= 0` and that its node set
    /// `axis` holds exactly the nodes on `r = 0` (within 1e-9 of the mesh's size).
    pub fn validate(&self) -> Result<(), PressError> {
        const { assert!(N == D + 1 && valid_strain_size(D, S)) };
        if self.formulation.num_strains() != S {
            return Err(PressError::BadFormulation(format!(
                "{:?} has {} strain components, the problem {S}",
                self.formulation,
                self.formulation.num_strains()
            )));
        }
        self.mesh.validate()?;
        self.mesh.node_set("bottom")?;
        if self.tools.is_empty() {
            self.mesh.node_set("top")?;
        }
        for tool in &self.tools {
            tool.validate()?;
        }
        if self.formulation == Formulation::Axisymmetric {
            self.validate_axis()?;
        }
        if self.materials.len() != self.mesh.region_names.len() {
            return Err(PressError::MaterialCount {
                regions: self.mesh.region_names.len(),
                materials: self.materials.len(),
            });
        }
        for (m, name) in self.materials.iter().zip(&self.mesh.region_names) {
            m.validate().map_err(|source| PressError::Material { region: name.clone(), source })?;
        }
        if !(self.density_t_mm3.is_finite() && self.density_t_mm3 > 0.0) {
            return Err(PressError::BadProtocol(format!("density {} t/mm^3 must be > 0", self.density_t_mm3)));
        }
        self.protocol.validate()?;
        self.validate_effects()
    }

    /// The effects' own checks, and how they fit the problem: `gravity` not with
    /// `protocol.gravity` (which is the factor 1 already); `plate-friction` only on
    /// a frictionless constrained plate (the baseline it extends); `adhesion` on a
    /// frictionless constrained plate or on contact tools of which one presses and is
    /// not glued; `machine-compliance` with contact tools only when one of them
    /// moves and is not a floor (the crosshead's tools, `super::stepper`, "Machine
    /// compliance"), and not with a Coulomb floor (`plate-friction` over a
    /// frictionless support, or a floor tool's friction). The material-point effects and the damage run with contact
    /// tools too (`super::inelastic`, "With contact tools"), and next to
    /// `machine-compliance`.
    pub(crate) fn validate_effects(&self) -> Result<(), PressError> {
        let e = &self.effects;
        e.validate()?;
        let conflict = |effect: EffectId, detail: &str| {
            Err(PressError::Effect(EffectError::Conflict { key: effect.params()[0].key, detail: detail.into() }))
        };
        if e.is_active(EffectId::Gravity) && self.protocol.gravity {
            return conflict(
                EffectId::Gravity,
                "the protocol already applies full gravity (protocol gravity = true): give one of the two",
            );
        }
        if e.is_active(EffectId::PlateFriction) {
            if !self.tools.is_empty() {
                return conflict(
                    EffectId::PlateFriction,
                    "acts on the constrained frictionless plate; this trial runs with contact tools \
                     (give their friction there)",
                );
            }
            if self.protocol.plate != Attachment::Frictionless {
                return conflict(
                    EffectId::PlateFriction,
                    "extends a frictionless plate; this trial's plate is not frictionless",
                );
            }
        }
        if e.is_active(EffectId::Adhesion) {
            if self.tools.is_empty() && self.protocol.plate != Attachment::Frictionless {
                return conflict(
                    EffectId::Adhesion,
                    "extends a frictionless plate (a glued plate holds the top in tension already); this trial's \
                     plate is not frictionless",
                );
            }
            if !self.tools.is_empty() && self.tools.iter().all(|t| t.floor || t.contact == ToolContact::Glued) {
                return conflict(
                    EffectId::Adhesion,
                    "acts on the pressing tools that are not glued; this trial has none (glued tools and floors only)",
                );
            }
        }
        // A floor with Coulomb friction: a floor tool's, or the one `plate-friction`
        // makes of a frictionless support (`super::effects_applied`).
        let coulomb_floor = (e.is_active(EffectId::PlateFriction) && self.protocol.support == Attachment::Frictionless)
            || self.tools.iter().any(|t| t.floor && matches!(t.contact, ToolContact::Friction(mu) if mu > 0.0));
        if e.is_active(EffectId::MachineCompliance) && coulomb_floor {
            return conflict(
                EffectId::MachineCompliance,
                "cannot be combined with a Coulomb floor yet (`plate_friction` over a frictionless support, or a \
                 floor tool's friction): the floor's contact does not settle at the push's first step once the \
                 crosshead's deflection lifts the plate, nor at any shorter retry; run it without one of the two \
                 (a Coulomb plate over a glued floor runs)",
            );
        }
        if e.is_active(EffectId::MachineCompliance)
            && !self.tools.is_empty()
            && !self.tools.iter().any(super::contact::on_crosshead)
        {
            return conflict(
                EffectId::MachineCompliance,
                "acts on the tools that move (the crosshead's); this trial's tools are all floors or fixed",
            );
        }
        if let Some((_, name)) = self
            .materials
            .iter()
            .zip(&self.mesh.region_names)
            .find(|(m, _)| m.damage_runs(e.forces_material_point_path()))
        {
            let refuse = |detail: String| {
                Err(PressError::BadSettings(format!("material of region `{name}`: the Mullins-type damage {detail}")))
            };
            if let Some((effect, _)) = e.material_point() {
                return refuse(format!(
                    "cannot be combined with the material-point effect `{effect}` (one inelastic law per run)"
                ));
            }
        }
        if e.material_point().is_some() {
            for m in &self.materials {
                e.inelastic_law(&m.rheology)?;
            }
        }
        Ok(())
    }

    /// The fraction of standard gravity acting: 1 with `protocol.gravity`, else the
    /// `gravity` effect's factor (0 when inactive).
    pub fn gravity_factor(&self) -> f64 {
        if self.protocol.gravity {
            1.0
        } else {
            self.effects.gravity_factor()
        }
    }
}

impl<const D: usize, const N: usize, const S: usize> PressProblem<D, N, S>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    /// The radius below which a node lies on the axis [mm]: 1e-9 of the mesh's size (at least 1e-9 mm).
    fn axis_tolerance(&self) -> f64 {
        let (lo, hi) = self.mesh.bounding_box();
        1e-9 * (0..D).map(|k| hi[k] - lo[k]).fold(1.0, f64::max)
    }

    /// The constructors' problem: density 1 g/cm^3, no markers, extra snapshots,
    /// tools or effects; validated.
    fn checked(
        mesh: SimplexMesh<D, N>,
        formulation: Formulation,
        materials: Vec<Material>,
        protocol: Protocol,
    ) -> Result<Self, PressError> {
        let p = Self {
            mesh,
            formulation,
            materials,
            density_t_mm3: 1e-9,
            protocol,
            markers: Vec::new(),
            snapshot_times: Vec::new(),
            tools: Vec::new(),
            effects: Effects::none(),
        };
        p.validate()?;
        Ok(p)
    }

    fn validate_axis(&self) -> Result<(), PressError> {
        let tol = self.axis_tolerance();
        if let Some((i, p)) = self.mesh.nodes.iter().enumerate().find(|(_, p)| !(p[0] >= -tol)) {
            return Err(PressError::BadFormulation(format!(
                "axisymmetric: node {i} lies at r = x = {} mm < 0 (the section is r >= 0)",
                p[0]
            )));
        }
        let axis = self.mesh.node_set("axis")?;
        if let Some(&i) = axis.iter().find(|&&i| self.mesh.nodes[i as usize][0] > tol) {
            return Err(PressError::BadFormulation(format!(
                "axisymmetric: node {i} of the set `axis` lies at r = {} mm, off the axis",
                self.mesh.nodes[i as usize][0]
            )));
        }
        if let Some(i) = (0..self.mesh.num_nodes())
            .find(|&i| self.mesh.nodes[i][0] <= tol && axis.binary_search(&(i as u32)).is_err())
        {
            return Err(PressError::BadFormulation(format!(
                "axisymmetric: node {i} lies on the axis (r = 0) but not in the node set `axis`"
            )));
        }
        Ok(())
    }
}

impl PlanePress {
    /// A plane-stress problem of the given thickness, density 1 g/cm^3, no markers.
    pub fn new_2d(
        mesh: TriMesh,
        thickness_mm: f64,
        materials: Vec<Material>,
        protocol: Protocol,
    ) -> Result<Self, PressError> {
        Self::checked(mesh, Formulation::PlaneStress { thickness_mm }, materials, protocol)
    }
}

impl AxisymmetricPress {
    /// An axisymmetric problem on the `r-y` section `mesh` (with the node sets
    /// `bottom`, `top` and `axis`, e.g. from [`crate::mesh::axisymmetric_section`]),
    /// density 1 g/cm^3, no markers.
    pub fn new_axisymmetric(mesh: TriMesh, materials: Vec<Material>, protocol: Protocol) -> Result<Self, PressError> {
        Self::checked(mesh, Formulation::Axisymmetric, materials, protocol)
    }
}

impl SolidPress {
    /// A 3D problem, density 1 g/cm^3, no markers.
    pub fn new_3d(mesh: TetMesh, materials: Vec<Material>, protocol: Protocol) -> Result<Self, PressError> {
        Self::checked(mesh, Formulation::Solid, materials, protocol)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_end_before_the_release_is_refused() {
        let err = Protocol::ramp_hold_release(0.2, 10.0, 40.0, 30.0).validate().unwrap_err();
        assert_eq!(err.to_string(), "protocol: end_s = 30 is before release_s = 40");
        assert!(Protocol::ramp_hold_release(0.2, 10.0, 40.0, 40.0).validate().is_ok());
    }
}
