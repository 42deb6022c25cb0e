//! Triangle surfaces from OBJ, STL, glTF and OFF files (`wagashi mesh SURFACE`).
//!
//! [`read_surface`] reads a file into an [`ImportedSurface`]: a
//! [`meshing::Surface`] in mm with named regions, the format and unit it was
//! read in, and warnings about what was left out. Each format's rules are in its
//! module: [`obj`] (objects and groups become regions, polygons become fans),
//! [`stl`] (binary or ASCII, told by content; solids become regions), [`gltf`]
//! (node transforms applied, meshes become regions), [`off`] (ASCII OFF, one
//! region; polygons become fans).
//!
//! # Units
//!
//! The engine's unit is mm. A file's coordinates are taken in
//! [`SurfaceOptions::units`], by default the format's: mm for OBJ, STL and OFF
//! (they have none), m for glTF (its specification's). They are multiplied by the
//! unit's mm and by [`SurfaceOptions::scale`]. The CLI's `--units` and `--scale`
//! set these.
//!
//! # Errors
//!
//! Every refusal is a [`SurfaceError`] naming the file, and the line where the
//! format has lines (`cake.obj:12: vertex index 40 out of range (38 vertices)`),
//! the triangle record for binary STL, the mesh primitive for glTF: an unreadable
//! or empty file, a syntax error, a NaN or infinite coordinate, an index out of
//! range. No input makes these functions panic; reading never modifies the file.
//! Defects of the surface itself (holes, flipped or intersecting triangles) are
//! not import errors: [`meshing::validate`] reports them and [`meshing::repair`]
//! fixes what can be fixed.
//!
//! # Example
//!
//! ```
//! use wagashi_io::surface::{read_surface, write_stl, LengthUnit, StlEncoding, SurfaceOptions};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let dir = tempfile::tempdir()?;
//! let obj = dir.path().join("tet.obj");
//! std::fs::write(&obj, "o tet\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")?;
//!
//! // 1. Read it, taking the coordinates as cm.
//! let opts = SurfaceOptions { units: Some(LengthUnit::Cm), ..Default::default() };
//! let imported = read_surface(&obj, &opts)?;
//! let surface = &imported.surface;
//! assert_eq!(surface.region_names, vec!["tet"]);
//! assert!((surface.signed_volume(None) - 1000.0 / 6.0).abs() < 1e-9); // mm^3
//!
//! // 2. Validate: closed, outward, no defect.
//! let report = surface.require_closed_manifold()?;
//! assert_eq!(report.components.len(), 1);
//!
//! // 3. Write it as binary STL and read it back (in mm, STL's default).
//! let stl = dir.path().join("tet.stl");
//! write_stl(&stl, surface, StlEncoding::Binary)?;
//! let back = read_surface(&stl, &SurfaceOptions::default())?;
//! assert_eq!(back.surface.num_triangles(), 4);
//! assert_eq!(back.surface.num_vertices(), 4);
//!
//! // 4. A bad index names the file and the line.
//! std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nf 1 2 3\n")?;
//! let err = read_surface(&obj, &SurfaceOptions::default()).unwrap_err();
//! assert!(err.to_string().ends_with("tet.obj:3: vertex index 3 out of range (2 vertices)"));
//! # Ok(()) }
//! ```

mod error;
pub mod gltf;
mod gltf_buffers;
mod gltf_companions;
pub mod obj;
pub mod off;
mod options;
mod read;
pub mod stl;

pub use error::{Location, SurfaceError};
pub use gltf_companions::{gltf_companions, portable_gltf, PortableGltf};
pub use options::{LengthUnit, SurfaceFormat, SurfaceOptions, UnknownUnit};
pub use read::{read_surface, ImportedSurface, MAX_COORDINATE_MM};
pub use stl::{write_stl, StlEncoding};
