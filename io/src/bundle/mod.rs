//! Experiment bundles (experiment-format.md, version 1): a folder holding
//! `experiment.toml` and the CSV files it names.
//!
//! - [`read_bundle`] / [`read_bundle_with`] read and check a bundle into a
//!   [`Bundle`]; [`read_bundle_from_str`] does the same for an `experiment.toml`
//!   given as text (a bundle embedded in a binary); [`read_materials_file`] reads
//!   a `--materials FILE`.
//! - [`Bundle::to_press`] builds the engine's press problem, with its rigid
//!   contact tools ([`Bundle::contact_tools`], "Rigid tools" below).
//! - [`write_bundle`] writes a simulation's results as a bundle.
//!
//! Every refusal names the file, the line and the field: `FILE:LINE: FIELD: CAUSE`
//! ([`crate::BundleError`]). Reading never modifies the bundle.
//!
//! ## Project extensions and choices beyond the format
//!
//! - `[specimen] density_g_cm3` (optional, > 0) and `[protocol] gravity` (optional,
//!   default false).
//! - `[specimen] plane = "stress" | "strain"` (optional, `dimension = 2` only;
//!   default `"stress"`, the seed's plane stress with thickness T).
//! - Required keys: `format`, `name`, `dimension`, `[specimen] shape`, the shape's
//!   size keys (`size_mm`; `radius_mm` and `height_mm`; `surface`; `mesh`), a
//!   block's `material` or `[[specimen.layers]]` (not both), a cylinder's
//!   `material`, a surface's or mesh's `[specimen.regions]` (or `material`), and
//!   `[protocol] tool`,
//!   `tool_contact`, `support`, `waypoints`, `release_s`, `end_s`;
//!   `tool_radius_mm` for a sphere or punch, `tool_surface` for a surface tool,
//!   `friction` when a contact is `"friction"`. A key that belongs to another
//!   shape, tool or contact is refused.
//! - Times (waypoints, `release_s`, `end_s`, CSV `t_s`) must not be negative;
//!   `release_s` and `end_s` must be > 0, and `end_s` not before `release_s`.
//! - "The specimen's smallest size" of the marker check is min(W, H, T) for a
//!   block (in 2D too) and min(2R, H) for a cylinder; in 3D the distance is to the
//!   surface of the box or cylinder, in 2D to the rectangle `[0, W] x [0, H]`.
//! - Markers of a `surface` or `mesh` specimen are not checked against its
//!   shape when the bundle is read (the file is read by `to_press`; a marker off
//!   the mesh is then refused by the engine, naming `data.markers`).
//! - A material in a `--materials` file replaces the bundle's table of the same name.
//! - Every file the bundle names (`data.force`, `data.markers`,
//!   `specimen.surface`, `specimen.mesh`, `protocol.tool_surface`,
//!   `protocol.tools[i].surface`) lies inside the bundle folder, symlinks followed: an absolute path, a `..`
//!   that climbs out of the folder or a symlink that points out of it is refused,
//!   `FILE:LINE: KEY: path leaves the bundle folder`.
//! - `[protocol] tool_surface_units` (optional, `tool = "surface"` only): see below.
//! - `[[protocol.tools]]` (optional): more rigid tools, see below.
//! - `[effects]` (optional): candidate effects of the gap diagnosis, see below.
//!
//! ## Specimens given by a file: `shape = "surface"` and `shape = "mesh"`
//!
//! Both are 3D only and always run with rigid contact tools placed against the
//! shape's bounding box; the specimen stands on the floor at its lowest y, and
//! the node sets `bottom` and `top` are its boundary nodes at the lowest and
//! highest y (the bottom must span a triangle). Each region of the file takes
//! the material `[specimen.regions]` maps it to, or `material` for all; a key
//! that names no region of the file, or a region left without a material, is
//! refused naming `specimen.regions` and listing the file's regions.
//!
//! ```toml
//! [specimen]
//! shape = "surface"
//! surface = "daifuku.obj"   # OBJ, STL (mm) or glTF/GLB (m), meshed on the fly
//! # shape = "mesh"
//! # mesh = "daifuku.msh"    # Gmsh .msh 4.1, TetGen .node/.ele or ASCII .vtu [mm], pressed as it is
//!
//! [specimen.regions]        # or `material = "gel"` for the whole specimen
//! skin = "mochi"            # OBJ object/group, glTF mesh; Gmsh volume physical group, TetGen region
//! filling = "anko"
//! ```
//!
//! - `surface`: a closed surface in its format's unit (mm for OBJ and STL, m for
//!   glTF/GLB), meshed at the element size of [`Bundle::to_press`] (see
//!   [`SurfaceMeshing`]).
//! - `mesh`: a tetrahedral mesh made by `wagashi mesh`, Gmsh or TetGen. The
//!   files carry no unit; coordinates are mm, as [`crate::tetmesh`] reads them.
//!   The element size does not apply. Region names are Gmsh's volume physical
//!   group names (`physical<tag>` if unnamed, `volume<tag>` without a group) or
//!   TetGen's `region<value>` (a `.vtu`: [`crate::tetmesh::vtu`]). Nodes no tetrahedron uses are left out. Refused,
//!   naming `specimen.mesh` on its line and then the mesh file (with its line
//!   where the defect has one): a missing or unreadable file, another extension,
//!   a file without tetrahedra, a flat tetrahedron or another volume element, a
//!   face shared by more than two tetrahedra or two tetrahedra on the same side
//!   of their shared face (a fold), and cells in several pieces that share no
//!   face. A mesh in `dimension = 2` is refused naming `dimension`.
//!
//! ## Markers: their frame
//!
//! `markers.csv` ([`MarkerSeries`]) gives each marker's position over time,
//! `marker,t_s,x_mm,y_mm[,z_mm]`, in the specimen's frame: mm, y up, the bottom
//! on y = 0, a block spanning `[0, W] x [0, H] x [0, T]` (2D: `[0, W] x [0, H]`),
//! a cylinder's axis on x = z = 0. A marker is the material point at its position
//! at `t_s = 0` (that row defines it; a fit takes no residual from it). The
//! simulated markers ([`Bundle::simulated_markers`], `markers.csv` of `wagashi
//! press`) are in the same frame, at the measured times.
//!
//! The frame is fixed to the specimen's initial position. A specimen that no
//! face holds tangentially (frictionless plate and support, or frictionless
//! plate tools) stays centred laterally: its centre of mass does not move in x
//! (or z) and it does not turn about y (`fem_core::press`), so a specimen that
//! deforms homogeneously expands about its centre, as a real one between
//! frictionless plates does. Measured markers are compared as given: a real
//! specimen that slid sideways as a whole should have that drift taken out
//! first (e.g. its markers' mean lateral motion), since the simulated one does
//! not slide. Under a curved frictionless tool (`sphere`, `punch`, `surface`)
//! the simulated specimen is pinned at its node of least x (then z) instead.
//!
//! ## Effects
//!
//! `[effects]` switches on model extensions of `fem_core::effects` (the
//! library of the sim-to-real gap diagnosis), each key one parameter of one
//! effect, named with its unit suffix; an effect whose keys are absent is off,
//! and one at its null values gives the baseline's results bit for bit
//! ([`Bundle::effects`] builds the engine's `Effects`, [`Bundle::to_press`] puts
//! them in the problem):
//!
//! ```toml
//! [effects]
//! force_offset_N = 0.02               # force-offset b0 [N]: reported force F + b0 + b1 t
//! force_drift_N_per_s = 1e-4          # force-offset b1 [N/s]
//! gravity = 1.0                       # gravity factor in [0, 1] (density as below)
//! machine_compliance_mm_per_N = 0.01  # 1/k_m [mm/N]: the plate moves d_cmd - F/k_m (see below)
//! ageing_E_rate_per_h = 0.01          # ageing gamma_E [1/h]: E_i -> E_i exp(gamma_E age_h)
//! ageing_c_rate_per_h = -0.02         # ageing gamma_c [1/h]: c_i -> c_i exp(gamma_c age_h)
//! age_h = 5.0                         # trial covariate: hours since preparation (needed by ageing)
//! plate_friction = 0.3                # Coulomb mu at a frictionless plate (and a frictionless floor)
//! adhesion_strength_MPa = 0.002       # adhesion sigma_a [MPa]: the plate holds the top in tension
//! adhesion_opening_mm = 0.1           # adhesion delta_c [mm]: the tension falls to 0 at this opening
//! plastic_yield_stress_MPa = 0.002    # plastic-slider sigma_y [MPa] (absent: no slider)
//! plastic_hardening_MPa = 0.01        # plastic-slider H [MPa], kinematic hardening (default 0.01)
//! bingham_threshold_MPa = 0.001       # bingham-dashpot sigma_B [MPa]: c3 flows above it only
//! thinning_inverse_stress_1_per_MPa = 200.0  # stress-thinning 1/sigma_c: c3 / (1 + (s/sigma_c)^m)
//! thinning_exponent = 1.0             # stress-thinning m in [0.2, 4] (default 1)
//! dual_viscosity_log_ratio = 1.0      # dual-viscosity psi in [-10, 10]: c3 exp(psi) in unloading
//! strain_stiffening = 5.0             # strain-stiffening a in [-4, 50]: tangent moduli E_i (1 + a e_eq)
//! finite_strain = 1.0                 # finite-strain blend b in [0, 1]: Green-Lagrange kinematics at 1
//! ```
//!
//! The last eight are the material-point effects (`fem_core::effects`): at most
//! one of them per trial, on the constrained plate or with contact tools (also
//! with `plate_friction`, `adhesion_strength_MPa` and
//! `machine_compliance_mm_per_N`); the dashpot ones need a chain with `c3` (not
//! `elastic`).
//!
//! `machine_compliance_mm_per_N` is a spring in series with what presses, along
//! the push axis y. With contact tools (the trial's tool, `[[protocol.tools]]`, or
//! the plate that `plate_friction` and `adhesion_strength_MPa` make a contact
//! tool) it acts on the crosshead's tools, every tool that moves and is not a
//! floor: they are held back together by `F/k_m` along y, `F` the sum of the y
//! components of the forces on them (the load cell's reading). It needs at least
//! one such tool.
//!
//! Unit suffixes read as the format's (`_N`, `_mm`, `_MPa`) with `_per_` for a
//! quotient (`_N_per_s` is N/s, `_mm_per_N` mm/N, `_per_h` 1/h), since `_MPa_s`
//! already means a product. `strain_stiffening` acts on the strain size
//! `e_eq = sqrt(e . C1 e)` (the axial strain in uniaxial compression): the chain
//! sees `(1 + a e_eq / 2) e`, so an elastic specimen in uniaxial compression
//! carries `sigma = E (e + a e^2 / 2)`. `finite_strain` runs the chain on the
//! strain `eps + b 1/2 H^T H` in a total Lagrangian formulation (2nd
//! Piola-Kirchhoff stress, forces `B(u)^T S`): an elastic specimen in uniaxial
//! compression carries the nominal stress `(1 + b eps) E (eps + b eps^2 / 2)`,
//! softer than the small-strain one. `adhesion_strength_MPa` is a rigid-linear
//! cohesive zone in the normal law of the pressing contact tools that are not
//! glued (a frictionless constrained plate becomes a frictionless contact tool;
//! the floor never adheres): a node that touched holds the tool in tension down
//! to `sigma_a` times its area facing the tool, then opens with a traction falling
//! linearly to zero at `adhesion_opening_mm` (`fem_core::effects`, "Adhesion").
//! Refused, naming the file, the line and the key: any other key; a
//! value outside its parameter's bounds (`gravity` in [0, 1], `plate_friction` in
//! [0, 10], `machine_compliance_mm_per_N` >= 0, ageing rates in [-1, 1] per hour,
//! the slider's stresses and the Bingham threshold >= 0,
//! `thinning_inverse_stress_1_per_MPa` >= 0, `thinning_exponent` in [0.2, 4],
//! `dual_viscosity_log_ratio` in [-10, 10], `strain_stiffening` in [-4, 50],
//! `finite_strain` in [0, 1], both adhesion keys `>= 0`); two
//! material-point effects at once;
//! a dashpot effect on an `elastic` material; a negative `age_h`; ageing rates without
//! `age_h`; `gravity` together with `[protocol] gravity = true` (the factor 1
//! already); `plate_friction` on a plate that is not frictionless or on a trial
//! with contact tools (give the tool's `friction` there); `machine_compliance_mm_per_N`
//! with contact tools that are all floors or fixed; `adhesion_strength_MPa` on a
//! glued plate or on tools that are all glued.
//!
//! `plate_friction = mu` makes the trial the one with `tool_contact = "friction"`,
//! `friction = mu` (and `support = "friction"` when the support is frictionless;
//! a glued floor stays glued): the same tools, the same results. The force in
//! `force.csv` of a simulated trial is the bottom sensor's, with the `gravity`
//! share of the weight in it (an untared sensor under the specimen); such a
//! trial is written with `force_tared = false`. `wagashi fit` fits with the
//! effects in place (forward sensitivities for `force-offset` and `gravity`,
//! forward differences on frozen steps for the others) and refuses
//! `plate_friction` and `adhesion_strength_MPa` (no sensitivities through
//! contact yet, and a contact step may not be subdivided on a frozen replay).
//!
//! ## Rigid tools
//!
//! [`Bundle::to_press`] simulates the seed's press, `tool = "plate"` with
//! `tool_contact` and `support` each `"glued"` or `"frictionless"` and no
//! `[[protocol.tools]]`, as it always has: the top and bottom faces held by
//! constraints (results and sensitivities unchanged). One exception keeps the
//! format's meaning of a plate that "leaves the specimen when it rises faster
//! than the specimen recovers, and may touch again": a frictionless plate whose
//! waypoints push again after rising, before `release_s` (a double compression),
//! is a contact tool. Every other protocol runs with rigid contact tools
//! (`fem_core::press::Tool`, [`Bundle::contact_tools`]); such runs need the
//! quasi-static integrator and have no sensitivities. Positions are in the
//! specimen's frame (mm, y up, the bottom on y = 0).
//!
//! - `tool = "plate"` with `tool_contact = "friction"` (or with a floor, more
//!   tools, or a second stroke): a flat plate wider than the specimen whose lower
//!   face starts on the top face and moves down by the waypoints' `d(t)`.
//! - `tool = "sphere"`: a sphere of `tool_radius_mm` centred over the top face's
//!   centre (the middle of a block's top, `(W/2, H + R, T/2)`; the axis of a
//!   cylinder, `(0, H + R, 0)`), touching the top at t = 0, moving down by `d(t)`.
//! - `tool = "punch"`: a flat cylinder (axis y) of radius `tool_radius_mm` and
//!   height twice the radius, placed as the sphere, its flat lower face on the top.
//! - `tool = "surface"`: the closed surface `tool_surface` (OBJ, STL, glTF/GLB; its
//!   regions taken as one body) where the file places it in the specimen's frame,
//!   moving down by `d(t)` from there. Its coordinates are taken in
//!   `tool_surface_units` (`"mm"`, `"cm"`, `"m"`, `"in"`), by default in the
//!   format's unit: mm for OBJ and STL, m for glTF/GLB (glTF's own unit), as
//!   [`crate::surface`] reads them.
//! - `tool_contact`: `"glued"` (sticks in every direction from first touch until
//!   `release_s`), `"frictionless"`, `"friction"` (Coulomb with `friction`).
//! - `support = "friction"`: the bottom face is free and a flat floor under it
//!   holds it with Coulomb friction `friction` (the tool named `"floor"`, whose
//!   force is the bottom force); `"glued"` and `"frictionless"` hold the bottom by
//!   constraints, as in the seed's press.
//! - The v1 tool lets go at `release_s`; after that it no longer touches the
//!   specimen, wherever it moves.
//! - 2D (`dimension = 2`): the tools act in the plane z = 0 (a sphere presses as a
//!   disc, i.e. as a cylinder across the thickness). The axisymmetric model of a
//!   cylinder ([`Bundle::to_press_axisymmetric`]): the tools act in its section
//!   `z = 0, x = r >= 0`, so they must be bodies of revolution on the axis.
//!
//! ### Several tools: `[[protocol.tools]]`
//!
//! Each `[[protocol.tools]]` table adds one tool with its own shape, contact and
//! trajectory. They act **together with** the v1 tool, which keeps its meaning
//! (named after its shape: `"plate"`, `"sphere"`, `"punch"` or `"surface"`); to
//! press with the extra tools only, let the v1 tool stay clear of the specimen
//! (e.g. waypoints that lift it, `[[0.0, 0.0], [1.0, -5.0]]`) or release it
//! early. For example, a finger pressing one side while a plate holds the other:
//!
//! ```toml
//! [protocol]
//! tool = "plate"
//! tool_contact = "frictionless"
//! support = "glued"
//! waypoints = [[0.0, 0.0], [10.0, 1.0], [40.0, 1.0]]
//! release_s = 40.0
//! end_s = 60.0
//!
//! [[protocol.tools]]
//! name = "finger"                  # unique; not "floor" nor the v1 tool's name
//! shape = "sphere"                 # "plate", "sphere", "punch", "capsule" or "surface"
//! radius_mm = 4.0                  # sphere, punch, capsule
//! # half_height_mm = 6.0           # capsule (required), punch (default: radius_mm)
//! # half_extents_mm = [30.0, 2.0, 30.0]   # plate: half sizes along x, y, z
//! # surface = "finger.obj"         # surface: tool-frame coordinates, relative path
//! # units = "mm"                   # surface: "mm", "cm", "m", "in" (default: the format's)
//! contact = "friction"             # "glued", "frictionless" or "friction"
//! friction = 0.3                   # only with contact = "friction"
//! release_s = 35.0                 # default: the protocol's release_s
//! # The origin of the tool's frame (the sphere's centre) over time, in the
//! # specimen's frame: [t_s, x_mm, y_mm, z_mm], or 7 columns with a rotation
//! # vector [.., rx_deg, ry_deg, rz_deg] (axis times angle). Linear in between
//! # (rotations by slerp), held before the first row and after the last.
//! keyframes = [[0.0, 10.0, 64.0, 6.0], [5.0, 10.0, 64.0, 6.0], [15.0, 10.0, 62.5, 6.0], [25.0, 10.0, 70.0, 6.0]]
//! ```
//!
//! The origin of each shape's frame is its centre: a plate's, a sphere's, the
//! middle of a punch's or capsule's axis (along y). A surface tool's file gives
//! its shape in the tool's frame, so keyframes at the origin leave it where the
//! file places it. Refused, naming the file, the line and the key: a name that is
//! empty, repeated, `"floor"` or the v1 tool's, or holds a comma, a quote or a slash; a
//! missing shape key or one that belongs to another shape; `friction` without
//! `contact = "friction"` or the reverse; no keyframes, a keyframe of other than
//! 4 or 7 values or with other columns than the first, non-finite, at a negative
//! time or not after the one before; in 2D a keyframe off the plane z = 0 or
//! turning about x or y; in the axisymmetric model a keyframe off the axis
//! (x or z not 0) or turning about x or z; a surface file that cannot be read or
//! is not closed.

mod confine;
mod experiment;
mod material_spec;
mod mesh_specimen;
mod read;
mod series;
mod surface_specimen;
mod to_press;
mod tools;
mod validate;
mod write;

pub use experiment::{
    Contact, DataSpec, Experiment, Layer, Plane, ProtocolSpec, Shape, Specimen, Tool, ToolKind, ToolSpec, FORMAT_V1,
};
pub use material_spec::{network_keys, read_materials_file, MaterialSpec, MissingParameter, Model};
pub use read::{read_bundle, read_bundle_from_str, read_bundle_with, Bundle, EXPERIMENT_FILE};
pub(crate) use series::read_force;
pub use series::{markers_header, ForceSample, ForceSeries, MarkerSample, MarkerSeries, FORCE_HEADER};
pub use surface_specimen::{SurfaceMeshing, BASE_BAND};
pub use to_press::G_CM3_IN_T_MM3;
pub use validate::{LAYER_SUM_TOLERANCE_MM, MARKER_SURFACE_TOLERANCE};
pub use write::{experiment_toml, force_csv, markers_csv, write_bundle, BundleWrite, FORCE_FILE, MARKERS_FILE};
