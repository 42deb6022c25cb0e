//! Animated glTF 2.0 export of press simulations: one binary file (`.glb`) that
//! web viewers, three.js and Blender open, showing the specimen deform and the
//! tools move.
//!
//! ## What a file holds
//!
//! - **The specimen**: node 0, one mesh of its boundary surface with `POSITION`
//!   (the reference shape), `NORMAL` and `COLOR_0`, and **one morph target per
//!   frame** holding that frame's displacement, normals and colours as offsets.
//!   The animation `press` drives the mesh's weights: at frame `i` the weights are
//!   1 for target `i` and 0 elsewhere, linear in between, so the shape shown is the
//!   displacement interpolated linearly in time. Without the animation, the first
//!   frame is shown (`mesh.weights`).
//! - **The tools**: one node each (after the specimen), with its own mesh placed
//!   by `translation` and `rotation` channels of the same animation (linear, the
//!   rotation spherically).
//! - **Colours**: `COLOR_0` maps the displacement magnitude `|u|` from 0 to the
//!   largest over all frames and vertices through viridis (linear RGB, as glTF
//!   requires). The scale is in `asset.extras.colour_scale`:
//!   `{"attribute": "COLOR_0", "quantity": "displacement magnitude", "colormap": "viridis", "min_mm": 0, "max_mm": ...}`.
//! - **Names**: the morph targets are named in `mesh.extras.targetNames` (three.js
//!   reads it into `morphTargetDictionary`): a frame's name (`keep` at the
//!   release, `final` at the end) or its time, `t=12.5s`. `asset.extras.frames`
//!   lists `{t_s, name}` per frame and `asset.extras.named_frames` maps each name
//!   to its frame's index. `asset.extras.run` holds the caller's own extras.
//!
//! Why morph targets and not one mesh per keyframe: the topology is stored once
//! and every viewer interpolates between frames by itself, whereas glTF has no
//! animated visibility, so meshes per keyframe would need scale-to-zero tricks
//! and would jump from one frame to the next.
//!
//! ## Conventions
//!
//! - **Units**: glTF's metres (the engine's millimetres times
//!   [`METRES_PER_MM`]) and seconds of simulated time (a 400 s trial plays for 400 s).
//! - **Axes**: the engine's: y up (the push axis), the specimen's bottom on y = 0;
//!   glTF is y-up and right-handed too, so no axis is swapped.
//! - **The file**: little-endian, both chunks padded to 4 bytes, every buffer view
//!   on a 4-byte boundary; `POSITION` accessors and animation times carry exact
//!   min/max; times are strictly increasing as 32-bit floats. Files pass the
//!   Khronos glTF-Validator with no error and no warning (`tests/browser`).
//!
//! ## Building a scene
//!
//! [`GltfScene`] is plain data ([`AnimatedSurface`] with [`Frame`]s,
//! [`AnimatedTool`]s with [`ToolKey`]s); the helpers fill it from fem-core:
//!
//! - [`SpecimenSurface`]: the boundary of a [`fem_core::mesh::TetMesh`]
//!   ([`from_tet_mesh`](SpecimenSurface::from_tet_mesh)), a plane
//!   [`fem_core::mesh::TriMesh`] extruded into a slab of its thickness
//!   ([`extruded`](SpecimenSurface::extruded)), or an axisymmetric section revolved
//!   about y ([`revolved`](SpecimenSurface::revolved), [`DEFAULT_SEGMENTS`]
//!   segments); each vertex follows a mesh node, so a
//!   [`fem_core::press::Snapshot`]'s displacement becomes a [`Frame`].
//! - [`AnimatedTool::plate`]: the seed's plate following a
//!   [`fem_core::press::Protocol`]; [`AnimatedTool::cuboid`] for any box.
//!
//! For `wagashi export`, which rebuilds the animation from a press output folder:
//! [`FrameSeries`] (the `frames.bin` that `press --gltf` writes), [`VtuShape`] and
//! [`read_pvd`] (the `.vtu`/`.pvd` shapes every press output holds).
//!
//! ## Errors
//!
//! [`GltfError`]: input that would make an invalid file (lengths that do not
//! match, times that do not increase, NaN, indices out of range) is refused
//! before anything is written, naming the object and the item.
//!
//! ## Example
//!
//! ```
//! use fem_core::mesh;
//! use fem_core::press::Protocol;
//! use wagashi_io::gltf::{write_glb, AnimatedTool, GltfScene, SpecimenSurface};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // 1. The boundary surface of a 20 x 10 x 5 mm block of tetrahedra.
//! let block = mesh::block([20.0, 10.0, 5.0], 2.5, "gel")?;
//! let surface = SpecimenSurface::from_tet_mesh(&block)?;
//!
//! // 2. Frames from nodal displacements (here: a uniform squash, 3 per node).
//! let squash = |t: f64| -> Vec<f64> {
//!     block.nodes.iter().flat_map(|p| [0.1 * t * (p[0] - 10.0), -0.2 * t * p[1], 0.0]).collect()
//! };
//! let frames = vec![
//!     surface.frame(0.0, None, &squash(0.0))?,
//!     surface.frame(1.0, Some("keep"), &squash(1.0))?,
//!     surface.frame(2.0, Some("final"), &squash(0.5))?,
//! ];
//!
//! // 3. The plate, pushing 2 mm in 1 s and letting go.
//! let protocol = Protocol::ramp_hold_release(2.0, 1.0, 1.0, 2.0);
//! let plate = AnimatedTool::plate(&protocol, surface.bounds_mm());
//!
//! // 4. Write: metres, morph targets, viridis colours, named frames.
//! let scene = GltfScene {
//!     specimen: surface.animated("gel", frames),
//!     tools: vec![plate],
//!     extras: serde_json::json!({ "trial": "example" }),
//! };
//! let dir = tempfile::tempdir()?;
//! write_glb(dir.path().join("press.glb"), &scene)?;
//! let bytes = std::fs::read(dir.path().join("press.glb"))?;
//! assert_eq!(&bytes[..4], b"glTF");
//! # Ok(()) }
//! ```

mod colormap;
mod error;
mod frame_series;
mod glb;
mod scene;
mod specimen_surface;
mod tool;
mod vtu_shape;

pub use colormap::{viridis_linear, COLORMAP};
pub use error::GltfError;
pub use frame_series::{FrameSeries, NodalFrame, FRAMES_MAGIC, FRAMES_VERSION};
pub use glb::{glb_bytes, write_glb, MAX_FRAMES, METRES_PER_MM};
pub use scene::{AnimatedSurface, AnimatedTool, Frame, GltfScene, ToolKey};
pub use specimen_surface::{SpecimenSurface, SurfaceLift, CREASE_ANGLE_DEG, DEFAULT_SEGMENTS};
pub use vtu_shape::{read_pvd, ShapeCells, VtuShape};
