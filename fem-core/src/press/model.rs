//! What every integrator shares: cell geometry, the assembled unit stiffness of
//! each kernel group, the lumped mass, the constraint sets, the reaction
//! functionals and the located markers.
//!
//! Axisymmetric problems differ only in data: the cell weights are `2π r_c A` (so
//! masses, gravity and reactions are full-circle quantities), the nodes of the set
//! `axis` hold `u_r = 0` in every constraint set, and no pins against rigid
//! motions in r are added (the axis holds them: a radial translation is not a
//! rigid motion of a body of revolution).
//!
//! ## Free bodies: the centred hold
//!
//! A specimen that no face or tool holds tangentially (frictionless plate and
//! floor) is free to translate in x (and z) and, in 3D, to turn about y. A real
//! one expands about its centre, so the engine holds these rigid motions by the
//! constraints `C u = 0` that keep the specimen's centre of mass and its mean
//! rotation about y where they were:
//!
//! ```text
//! sum_i w_i u_x,i = 0,   sum_i w_i u_z,i = 0,   sum_i w_i ((z_i - z_c) u_x,i - (x_i - x_c) u_z,i) = 0
//! ```
//!
//! with `w_i = int N_i dV` the node's share of the volume (the lumped mass over the
//! density) and `(x_c, z_c)` the volume centroid. These are the free body's own
//! frame: with no lateral force and no moment about y on it, its momentum and
//! its angular momentum about y stay zero, and their time integrals, linearized,
//! are the three sums. They are exact for a homogeneous deformation on any mesh:
//! P1 fields integrate exactly with these weights, and a symmetric strain
//! about the centroid has zero mean displacement and zero mean rotation. (The
//! bottom face's mean would be as exact on a block or a cylinder, but a rounded
//! surface specimen may stand on a few nodes, where its mean rotation is
//! ill-defined.)
//!
//! *How they are imposed.* By elimination on a gauge: statically determinate
//! pins (node A, min x then min z, holds x and z; in 3D node B, max x at A's z,
//! holds z) make the step matrix regular, and the displacement `x` solved with
//! them maps to the constrained one by `u = x - R (C R)^{-1} C x`, `R` the three
//! rigid motions. Since `K R = 0` and the loads are balanced (`R^T f = 0`), the
//! reduced matrix `T^T K T` of that elimination is the pinned matrix itself, so
//! the factorizations (and the linear path's factor-once property) are those of
//! the pins; the pins carry no load, and strains, stresses, histories and forces
//! do not see the gauge. The map `x -> u` is applied where displacements leave
//! the engine ([`Model::reported`]: snapshots; [`Model::marker_positions`]:
//! markers and their sensitivities, which the map, linear, carries over). With
//! `(x_c, z_c)` the centroid, `C R` is diagonal: `diag(V, V, J)`, `V` the volume
//! and `J = sum_i w_i ((x_i - x_c)^2 + (z_i - z_c)^2)`.
//!
//! The hold applies where the rigid motions are symmetries of the whole problem:
//! no contact tools, or tools that are all plates that never turn (their
//! pressing faces' normals are y; the floor, a frictionless plate, a double
//! compression's plate that leaves and touches again). Under a curved
//! frictionless tool (sphere, punch, surface) the contact resists the lateral
//! motions, `K R != 0`, and the pins stay as they are. The dynamic and seed
//! integrators keep the pins too; there they carry the inertia of the lateral
//! expansion (negligible at a press's rates), and the reported displacements are
//! centred the same way. Axisymmetric problems need none of it: the axis holds
//! `u_r = 0`.

use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

use super::{Attachment, PressError, PressProblem};
use crate::assembly::{assemble_stiffness, CsrPattern, Topology};
use crate::element::{
    cell_geometry, cell_geometry_in, cell_strain, displacement_gradient, green_lagrange_block, green_lagrange_strain,
    strain_block, unit_young_matrix, CellGeometry, Formulation, ReferenceSimplex, Simplex,
};
use crate::material::{InelasticLaw, RelaxationKernel};
use crate::mesh::MeshError;

/// Standard gravity [mm/s^2].
pub(crate) const GRAVITY_MM_S2: f64 = 9810.0;

/// Regions whose kernels are equal up to a factor share one assembled matrix.
pub(crate) struct KernelGroup {
    /// The group's reference kernel (its first region's).
    pub kernel: RelaxationKernel,
    /// `sum_r s_r K1_r` over the group's regions, values on the model's pattern.
    pub stiffness: Vec<f64>,
}

/// A constraint set: which dofs are held, and how their values follow the plate.
#[derive(Clone)]
pub(crate) struct Constraints {
    pub held: Vec<bool>,
    /// Dofs that follow the plate's displacement: `u = -d(t)` (the top's y dofs).
    pub plate_dofs: Vec<usize>,
    /// Whether the plate holds the top face (always true with contact tools: the
    /// reactions then follow from the stresses at all times).
    pub plate_attached: bool,
    /// Whether the set holds a free body by the centred hold (module doc, "Free
    /// bodies"): its pins are a gauge, removed from reported displacements.
    pub centred: bool,
}

/// The centred hold's weights (module doc, "Free bodies").
pub(crate) struct Centring {
    /// Per node: its share of the specimen's volume, `int N_i dV` [mm^3].
    weight: Vec<f64>,
    /// The volume centroid's x and z [mm] (z = 0 in 2D).
    centre: [f64; 2],
    /// The volume `sum_i w_i` [mm^3].
    volume: f64,
    /// `J = sum_i w_i ((x_i - x_c)^2 + (z_i - z_c)^2)` [mm^5] (3D; 0 in 2D).
    polar: f64,
}

impl Centring {
    fn new<const D: usize, const N: usize>(
        mesh: &crate::mesh::SimplexMesh<D, N>,
        geometry: &[CellGeometry<D, N>],
    ) -> Self
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let mut weight = vec![0.0; mesh.num_nodes()];
        for (e, cell) in mesh.cells.iter().enumerate() {
            let w = geometry[e].weight / N as f64;
            for &v in cell {
                weight[v as usize] += w;
            }
        }
        let volume: f64 = weight.iter().sum();
        let lateral = |p: &[f64; D]| [p[0], if D == 3 { p[2] } else { 0.0 }];
        let mut centre = [0.0; 2];
        for (w, p) in weight.iter().zip(&mesh.nodes) {
            let q = lateral(p);
            centre[0] += w * q[0];
            centre[1] += w * q[1];
        }
        centre = centre.map(|c| c / volume);
        let polar = if D == 3 {
            weight
                .iter()
                .zip(&mesh.nodes)
                .map(|(w, p)| w * ((p[0] - centre[0]).powi(2) + (p[2] - centre[1]).powi(2)))
                .sum()
        } else {
            0.0
        };
        Self { weight, centre, volume, polar }
    }

    /// The rigid motion `[a_x, a_z, omega]` that `u` holds: translations along x
    /// and z [mm] and the rotation about y through the centroid [rad], so that
    /// `u` minus it meets `C u = 0`.
    fn rigid<const D: usize>(&self, nodes: &[[f64; D]], u: &[f64]) -> [f64; 3] {
        let (mut ax, mut az, mut moment) = (0.0, 0.0, 0.0);
        for (i, (w, p)) in self.weight.iter().zip(nodes).enumerate() {
            let ux = u[i * D];
            ax += w * ux;
            if D == 3 {
                let uz = u[i * D + 2];
                az += w * uz;
                moment += w * ((p[2] - self.centre[1]) * ux - (p[0] - self.centre[0]) * uz);
            }
        }
        let omega = if D == 3 { moment / self.polar } else { 0.0 };
        [ax / self.volume, az / self.volume, omega]
    }

    /// The displacement of the rigid motion `rigid` at the point `p` (x and z parts).
    fn displacement_at(&self, rigid: &[f64; 3], p: &[f64]) -> [f64; 2] {
        let [ax, az, omega] = *rigid;
        if p.len() == 3 {
            [ax + omega * (p[2] - self.centre[1]), az - omega * (p[0] - self.centre[0])]
        } else {
            [ax, 0.0]
        }
    }
}

/// A boundary cell's reaction functional: the y reaction summed over a node set is
/// `rho . s` for the cell stress `s`.
pub(crate) struct Functional<const S: usize> {
    pub cell: usize,
    pub rho: SVector<f64, S>,
    /// The cell's nodes in the set (local indices) and the functional's sign, for
    /// the deformed functional of the finite-strain path.
    pub locals: Vec<usize>,
    pub sign: f64,
}

/// A marker located in its cell.
pub(crate) struct LocatedMarker<const N: usize> {
    pub cell: usize,
    pub barycentric: [f64; N],
}

pub(crate) struct Model<'p, const D: usize, const N: usize, const S: usize> {
    pub problem: &'p PressProblem<D, N, S>,
    pub geometry: Vec<CellGeometry<D, N>>,
    pub topology: Topology,
    pub pattern: CsrPattern,
    /// Per region: kernel, unit-Young matrix, group index, scale within the group.
    pub region_kernel: Vec<RelaxationKernel>,
    pub region_c1: Vec<SMatrix<f64, S, S>>,
    pub groups: Vec<KernelGroup>,
    /// Lumped mass per dof [t].
    pub mass: Vec<f64>,
    /// External body force per dof (gravity) [N].
    pub body_force: Vec<f64>,
    pub attached: Constraints,
    pub released: Constraints,
    /// Bottom (index 0) and plate (index 1) functionals; the plate one is negated so
    /// both read compression positive.
    pub functionals: [Vec<Functional<S>>; 2],
    /// Constant parts of the reactions from body forces [N].
    pub body_reaction: [f64; 2],
    pub markers: Vec<LocatedMarker<N>>,
    /// Displacement scale for error control [mm].
    pub displacement_scale: f64,
    /// Nested-dissection elimination order of the nodes.
    pub node_order: Vec<u32>,
    /// Position of each dof's diagonal entry in the pattern's values.
    pub diagonal_positions: Vec<usize>,
    /// The inelastic law per region when a material-point effect runs
    /// ([`crate::effects`]); `None`: the linear path.
    pub point: Option<Vec<InelasticLaw>>,
    /// The `finite-strain` blend when that effect runs (the finite-strain
    /// kinematics of `super::inelastic`); `None`: small strain.
    pub finite: Option<f64>,
    /// The centred hold's weights when a constraint set holds a free body.
    pub centring: Option<Centring>,
}

impl<'p, const D: usize, const N: usize, const S: usize> Model<'p, D, N, S>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    pub fn new(problem: &'p PressProblem<D, N, S>) -> Result<Self, PressError> {
        problem.validate()?;
        let mesh = &problem.mesh;
        let geometry = (0..mesh.num_cells())
            .into_par_iter()
            .map(|e| {
                cell_geometry_in::<D, N>(problem.formulation, &mesh.cell_coordinates(e))
                    .map_err(|measure| MeshError::InvertedElement { element: e, measure })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let topology = Topology::new(mesh.num_nodes(), &mesh.cells);
        let pattern = CsrPattern::new(&topology, D);

        let region_kernel: Vec<RelaxationKernel> = problem.materials.iter().map(|m| m.relaxation()).collect();
        let region_c1: Vec<SMatrix<f64, S, S>> =
            problem.materials.iter().map(|m| unit_young_matrix::<S>(problem.formulation, m.poisson)).collect();
        // Group regions with proportional kernels.
        let mut group_of_region = vec![0usize; region_kernel.len()];
        let mut scale_of_region = vec![1.0; region_kernel.len()];
        let mut group_kernels: Vec<RelaxationKernel> = Vec::new();
        for (r, k) in region_kernel.iter().enumerate() {
            match group_kernels.iter().enumerate().find_map(|(g, gk)| k.proportional_to(gk).map(|s| (g, s))) {
                Some((g, s)) => {
                    group_of_region[r] = g;
                    scale_of_region[r] = s;
                }
                None => {
                    group_of_region[r] = group_kernels.len();
                    group_kernels.push(*k);
                }
            }
        }
        let groups = group_kernels
            .iter()
            .enumerate()
            .map(|(g, &kernel)| {
                let cell_matrix = |e: usize| {
                    let r = mesh.cell_regions[e] as usize;
                    (group_of_region[r] == g).then(|| region_c1[r] * scale_of_region[r])
                };
                let stiffness =
                    assemble_stiffness::<D, N, S>(&topology, &pattern, &mesh.cells, &geometry, &cell_matrix);
                KernelGroup { kernel, stiffness }
            })
            .collect();

        // Lumped mass: each node takes 1/N of its cells' mass.
        let mut mass = vec![0.0; mesh.num_nodes() * D];
        for (e, cell) in mesh.cells.iter().enumerate() {
            let m = problem.density_t_mm3 * geometry[e].weight / N as f64;
            for &v in cell {
                for k in 0..D {
                    mass[v as usize * D + k] += m;
                }
            }
        }
        let mut body_force = vec![0.0; mass.len()];
        // Full gravity (`protocol.gravity`) is the factor 1: `-g * 1.0 * m` is `-g * m` bit for bit.
        let gravity = problem.gravity_factor();
        if gravity != 0.0 {
            for i in 0..mesh.num_nodes() {
                body_force[i * D + 1] = -GRAVITY_MM_S2 * gravity * mass[i * D + 1];
            }
        }

        let bottom = mesh.node_set("bottom")?.to_vec();
        let with_tools = !problem.tools.is_empty();
        let top = if with_tools {
            mesh.node_sets.get("top").cloned().unwrap_or_default()
        } else {
            mesh.node_set("top")?.to_vec()
        };
        let axis = match problem.formulation {
            Formulation::Axisymmetric => Some(mesh.node_set("axis")?),
            _ => None,
        };
        // Tools that hold tangentially (glued, friction) hold the rigid motions too:
        // no pins then.
        let tools_hold = problem.tools.iter().any(|t| !matches!(t.contact, crate::press::ToolContact::Frictionless));
        // The centred hold needs the rigid motions to be symmetries of the contact:
        // plates that never turn (module doc, "Free bodies").
        let tools_flat = problem.tools.iter().all(|t| {
            matches!(t.shape, crate::press::ToolShape::Plate { .. })
                && t.keyframes.iter().all(|k| k.rotation_rad == [0.0; 3])
        });
        // With tools, no plate holds the top: both sets hold only the support (and
        // count as "attached": the reactions follow from the stresses throughout).
        let attached = if with_tools {
            let mut c =
                constraints::<D, N>(mesh, &bottom, &top, axis, problem.protocol.support, None, tools_hold, tools_flat);
            c.plate_attached = true;
            c
        } else {
            constraints::<D, N>(
                mesh,
                &bottom,
                &top,
                axis,
                problem.protocol.support,
                Some(problem.protocol.plate),
                false,
                true,
            )
        };
        let released = if with_tools {
            attached.clone()
        } else {
            constraints::<D, N>(mesh, &bottom, &top, axis, problem.protocol.support, None, false, true)
        };
        let centring = (attached.centred || released.centred).then(|| Centring::new(mesh, &geometry));

        let functionals =
            [functional(&geometry, &topology, &bottom, 1.0), functional(&geometry, &topology, &top, -1.0)];
        let body_reaction = [
            0.0 - bottom.iter().map(|&i| body_force[i as usize * D + 1]).sum::<f64>(),
            top.iter().map(|&i| body_force[i as usize * D + 1]).sum::<f64>(),
        ];

        let markers =
            problem.markers.iter().map(|m| locate(mesh, &m.name, &m.position)).collect::<Result<Vec<_>, _>>()?;

        let (lo, hi) = mesh.bounding_box();
        let size = (0..D).map(|k| hi[k] - lo[k]).fold(f64::INFINITY, f64::min);
        let dmax = problem.protocol.waypoints.iter().map(|w| w[1].abs()).fold(0.0, f64::max);
        let dmax = problem.tools.iter().map(|t| t.travel()).fold(dmax, f64::max);
        let displacement_scale = dmax.max(1e-3 * size);

        let node_order = crate::ordering::nested_dissection(&mesh.nodes, &topology);
        let diagonal_positions = (0..pattern.num_dofs())
            .map(|r| {
                let row = &pattern.col_idx[pattern.row_ptr[r]..pattern.row_ptr[r + 1]];
                pattern.row_ptr[r] + row.iter().position(|&c| c as usize == r).expect("the diagonal is in the pattern")
            })
            .collect();
        // The material-point effect's law per region (E1 to E5), if one runs.
        let laws = problem
            .materials
            .iter()
            .map(|m| problem.effects.inelastic_law(&m.rheology))
            .collect::<Result<Vec<_>, _>>()?;
        let mut point = laws.into_iter().collect::<Option<Vec<InelasticLaw>>>();
        // A material's Mullins-type damage (crate::material::MullinsDamage): every
        // region runs the damage law, at its null where a material has none (the
        // problem's validation refuses it next to a material-point effect).
        let forced = problem.effects.forces_material_point_path();
        if problem.materials.iter().any(|m| m.damage_runs(forced)) {
            point = Some(
                problem
                    .materials
                    .iter()
                    .map(|m| {
                        let d = m.damage.unwrap_or(crate::material::MullinsDamage { d_inf: 0.0, strain_c: 1.0 });
                        InelasticLaw::Damage { d_inf: d.d_inf, strain_c: d.strain_c }
                    })
                    .collect(),
            );
        }
        let finite = point.as_ref().and_then(|laws| {
            laws.iter().find_map(|l| match *l {
                InelasticLaw::FiniteStrain { blend } => Some(blend),
                _ => None,
            })
        });
        Ok(Self {
            centring,
            point,
            finite,
            diagonal_positions,
            node_order,
            problem,
            geometry,
            topology,
            pattern,
            region_kernel,
            region_c1,
            groups,
            mass,
            body_force,
            attached,
            released,
            functionals,
            body_reaction,
            markers,
            displacement_scale,
        })
    }

    pub fn num_dofs(&self) -> usize {
        self.pattern.num_dofs()
    }

    /// The constraints in force for a step ending at `t_end`.
    pub fn constraints_at(&self, t_end: f64) -> &Constraints {
        if t_end <= self.problem.protocol.release_s * (1.0 + 1e-12) {
            &self.attached
        } else {
            &self.released
        }
    }

    /// Writes the held values at time `t` into `u` (zero except the plate dofs).
    pub fn prescribe(&self, c: &Constraints, t: f64, u: &mut [f64]) {
        for (d, &h) in c.held.iter().enumerate() {
            if h {
                u[d] = 0.0;
            }
        }
        let d = self.problem.protocol.displacement(t);
        for &dof in &c.plate_dofs {
            u[dof] = -d;
        }
    }

    /// Nodal displacements of cell `e` from a global vector.
    #[inline]
    pub fn cell_displacements(&self, e: usize, u: &[f64]) -> [SVector<f64, D>; N] {
        self.problem.mesh.cells[e].map(|v| SVector::<f64, D>::from_fn(|k, _| u[v as usize * D + k]))
    }

    /// The strain of cell `e` for its nodal displacements `u`: the small strain,
    /// or on the finite-strain path the blended Green-Lagrange strain.
    #[inline]
    pub fn strain_of(&self, e: usize, u: &[SVector<f64, D>; N]) -> SVector<f64, S> {
        match self.finite {
            Some(blend) => green_lagrange_strain::<D, N, S>(&self.geometry[e].gradients, u, blend),
            None => cell_strain::<D, N, S>(&self.geometry[e].gradients, u),
        }
    }

    /// A reaction functional at the displacement `u`: `rho` itself on the small-strain
    /// path (and at the blend 0); on the finite-strain path the y rows of the
    /// deformed `w B_a(u)^T` summed over the set's nodes of the cell, so that the
    /// reaction is `rho(u) . S` with the 2nd Piola-Kirchhoff stress `S`.
    pub fn functional_at(&self, f: &Functional<S>, u: &[f64]) -> SVector<f64, S> {
        match self.finite {
            Some(blend) if blend != 0.0 => {
                let g = &self.geometry[f.cell];
                let ue = self.cell_displacements(f.cell, u);
                let (h, hoop) = displacement_gradient::<D, N, S>(&g.gradients, &ue);
                let mut rho = SVector::<f64, S>::zeros();
                for &a in &f.locals {
                    rho += green_lagrange_block::<D, N, S>(&g.gradients, &h, hoop, blend, a).column(1)
                        * (g.weight * f.sign);
                }
                rho
            }
            _ => f.rho,
        }
    }

    /// `det(I + grad u)` of cell `e`: the deformed-to-initial volume ratio; for an
    /// axisymmetric cell times the hoop stretch `1 + u_r/r` at its centroid.
    pub fn volume_ratio(&self, e: usize, u: &[SVector<f64, D>; N]) -> f64 {
        let g = &self.geometry[e].gradients;
        // Zero hoop row except for axisymmetric cells.
        let hoop_stretch = 1.0 + g.hoop * (0..N).map(|a| u[a][0]).sum::<f64>();
        let mut f = SMatrix::<f64, D, D>::identity();
        for a in 0..N {
            for i in 0..D {
                for j in 0..D {
                    f[(i, j)] += u[a][i] * g[(a, j)];
                }
            }
        }
        let (det, _) = <Simplex<D, N> as ReferenceSimplex<D, N>>::det_and_inverse(&f);
        det * hoop_stretch
    }

    /// The rigid motion to remove from a displacement `u` at time `t` (module doc,
    /// "Free bodies"), when the constraint set in force there is centred.
    fn gauge(&self, u: &[f64], t: f64) -> Option<(&Centring, [f64; 3])> {
        let centring = self.centring.as_ref().filter(|_| self.constraints_at(t).centred)?;
        Some((centring, centring.rigid(&self.problem.mesh.nodes, u)))
    }

    /// The displacement `u` at time `t` as reported: with the centred hold, the
    /// gauge's rigid motion removed (module doc, "Free bodies"); otherwise `u`.
    pub fn reported(&self, u: &[f64], t: f64) -> Vec<f64> {
        let mut u = u.to_vec();
        if let Some((centring, rigid)) = self.gauge(&u, t) {
            for (i, p) in self.problem.mesh.nodes.iter().enumerate() {
                let [rx, rz] = centring.displacement_at(&rigid, p);
                u[i * D] -= rx;
                if D == 3 {
                    u[i * D + 2] -= rz;
                }
            }
        }
        u
    }

    /// Marker positions for the displacement `u` at time `t` (as reported: see
    /// [`Model::reported`]; the map is linear in `u`, so sensitivities follow it).
    pub fn marker_positions(&self, u: &[f64], t: f64) -> Vec<Vec<f64>> {
        let gauge = self.gauge(u, t);
        self.markers
            .iter()
            .zip(&self.problem.markers)
            .map(|(m, req)| {
                let cell = &self.problem.mesh.cells[m.cell];
                // The rigid motion where the marker's cell interpolates it (a marker a
                // little outside a faceted surface is projected in).
                let rigid = gauge.map_or([0.0; 2], |(centring, rigid)| {
                    let nodes = &self.problem.mesh.nodes;
                    let p: Vec<f64> = (0..D)
                        .map(|k| (0..N).map(|a| m.barycentric[a] * nodes[cell[a] as usize][k]).sum::<f64>())
                        .collect();
                    centring.displacement_at(&rigid, &p)
                });
                (0..D)
                    .map(|k| {
                        let shift = match k {
                            0 => rigid[0],
                            2 => rigid[1],
                            _ => 0.0,
                        };
                        req.position[k] + (0..N).map(|a| m.barycentric[a] * u[cell[a] as usize * D + k]).sum::<f64>()
                            - shift
                    })
                    .collect()
            })
            .collect()
    }

    /// The first cell holding `node` (for error messages), if any.
    pub fn cell_of_node(&self, node: usize) -> Option<usize> {
        let (a, b) = (self.topology.cell_ptr[node], self.topology.cell_ptr[node + 1]);
        (a < b).then(|| self.topology.node_cells[a].0 as usize)
    }

    /// A step-matrix failure as an error naming the step, time, node and element.
    pub fn singular(&self, step: usize, time_s: f64, e: crate::solve::SolveError) -> PressError {
        let node = match e {
            crate::solve::SolveError::NotPositiveDefinite { dof: Some(d) } => Some(d / D),
            _ => None,
        };
        PressError::Singular {
            step,
            time_s,
            node,
            element: node.and_then(|n| self.cell_of_node(n)),
            detail: e.to_string(),
        }
    }
}

/// The held dofs: the floor's (bottom), the plate's (top, when `plate` is given),
/// `u_r` on the `axis` nodes of an axisymmetric problem, and otherwise, when no
/// face is glued and no tool holds tangentially (`tools_hold`), the gauge pins
/// against rigid motions in the x(-z) plane: the centred hold's when the tools
/// allow it (`tools_flat`, module doc, "Free bodies"), plain pins otherwise.
#[allow(clippy::too_many_arguments)]
fn constraints<const D: usize, const N: usize>(
    mesh: &crate::mesh::SimplexMesh<D, N>,
    bottom: &[u32],
    top: &[u32],
    axis: Option<&[u32]>,
    support: Attachment,
    plate: Option<Attachment>,
    tools_hold: bool,
    tools_flat: bool,
) -> Constraints
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let mut held = vec![false; mesh.num_nodes() * D];
    for &i in bottom {
        let i = i as usize;
        match support {
            Attachment::Glued => (0..D).for_each(|k| held[i * D + k] = true),
            Attachment::Frictionless => held[i * D + 1] = true,
            Attachment::Free => {}
        }
    }
    let mut plate_dofs = Vec::new();
    if let Some(plate) = plate {
        for &i in top {
            let i = i as usize;
            plate_dofs.push(i * D + 1);
            held[i * D + 1] = true;
            if plate == Attachment::Glued {
                for k in (0..D).filter(|&k| k != 1) {
                    held[i * D + k] = true;
                }
            }
        }
    }
    // Axisymmetric: the axis nodes hold u_r = 0 always. There is no rigid motion in
    // r to pin (a radial translation stretches the hoop), so no pins follow.
    if let Some(axis) = axis {
        for &i in axis {
            held[i as usize * D] = true;
        }
    }
    // Statically determinate pins against the rigid motions in the x(-z) plane when
    // no face is glued: node A (min x, then min z) holds x and z; in 3D node B (max x
    // at A's z) holds z. They carry no load, so they add no stress; with the centred
    // hold they are its gauge.
    let some_face_glued = support == Attachment::Glued || plate == Some(Attachment::Glued) || tools_hold;
    let pinned = !some_face_glued && axis.is_none();
    if pinned {
        let key = |i: u32| {
            let p = mesh.nodes[i as usize];
            (p[0], if D == 3 { p[2] } else { 0.0 })
        };
        let a = *bottom
            .iter()
            .min_by(|&&i, &&j| key(i).partial_cmp(&key(j)).unwrap())
            .expect("the bottom set is not empty");
        held[a as usize * D] = true;
        if D == 3 {
            held[a as usize * D + 2] = true;
            let za = mesh.nodes[a as usize][2];
            let b = bottom.iter().copied().filter(|&i| i != a).min_by(|&i, &j| {
                let score = |n: u32| {
                    let p = mesh.nodes[n as usize];
                    ((p[2] - za).abs(), -p[0])
                };
                score(i).partial_cmp(&score(j)).unwrap()
            });
            if let Some(b) = b {
                held[b as usize * D + 2] = true;
            }
        }
    }
    Constraints { held, plate_dofs, plate_attached: plate.is_some(), centred: pinned && tools_flat }
}

fn functional<const D: usize, const N: usize, const S: usize>(
    geometry: &[CellGeometry<D, N>],
    topology: &Topology,
    set: &[u32],
    sign: f64,
) -> Vec<Functional<S>> {
    let mut rho: std::collections::BTreeMap<usize, (SVector<f64, S>, Vec<usize>)> = Default::default();
    for &i in set {
        let i = i as usize;
        for &(e, a) in &topology.node_cells[topology.cell_ptr[i]..topology.cell_ptr[i + 1]] {
            let g = &geometry[e as usize];
            let b = strain_block::<D, N, S>(&g.gradients, a as usize);
            let entry = rho.entry(e as usize).or_insert_with(|| (SVector::zeros(), Vec::new()));
            entry.0 += b.column(1) * (g.weight * sign);
            entry.1.push(a as usize);
        }
    }
    rho.into_iter().map(|(cell, (rho, locals))| Functional { cell, rho, locals, sign }).collect()
}

fn locate<const D: usize, const N: usize>(
    mesh: &crate::mesh::SimplexMesh<D, N>,
    name: &str,
    p: &[f64],
) -> Result<LocatedMarker<N>, PressError>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    assert_eq!(p.len(), D, "marker `{name}` needs {D} coordinates");
    let best = (0..mesh.num_cells())
        .into_par_iter()
        .map(|e| {
            let x = mesh.cell_coordinates(e);
            let g = cell_geometry::<D, N>(&x, 1.0).expect("validated mesh");
            let mut bary = [0.0; N];
            let mut sum = 0.0;
            for a in 1..N {
                bary[a] = (0..D).map(|k| g.gradients[(a, k)] * (p[k] - x[0][k])).sum();
                sum += bary[a];
            }
            bary[0] = 1.0 - sum;
            let worst = bary.iter().copied().fold(f64::INFINITY, f64::min);
            (worst, e, bary)
        })
        .reduce(
            || (f64::NEG_INFINITY, usize::MAX, [0.0; N]),
            |a, b| if (b.0, std::cmp::Reverse(b.1)) > (a.0, std::cmp::Reverse(a.1)) { b } else { a },
        );
    let (worst, cell, mut bary) = best;
    // Points a little outside a faceted surface (e.g. a cylinder) are projected in.
    if worst < -0.25 {
        let x = mesh.cell_coordinates(cell);
        let centroid: Vec<f64> = (0..D).map(|k| x.iter().map(|q| q[k]).sum::<f64>() / N as f64).collect();
        let distance_mm = (0..D).map(|k| (p[k] - centroid[k]).powi(2)).sum::<f64>().sqrt();
        return Err(PressError::MarkerOutside { name: name.to_string(), position: p.to_vec(), distance_mm });
    }
    for b in &mut bary {
        *b = b.max(0.0);
    }
    let s: f64 = bary.iter().sum();
    bary.iter_mut().for_each(|b| *b /= s);
    Ok(LocatedMarker { cell, barycentric: bary })
}
