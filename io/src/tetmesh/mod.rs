//! Tetrahedral meshes from and to other meshers' files: TetGen's `.node`/`.ele`/
//! `.face` ([`tetgen`]), Gmsh's MSH 4.1 ASCII ([`gmsh`]) and, read only, VTK's
//! ASCII `.vtu` ([`vtu`]), so that meshes made with TetGen, Gmsh or meshio can be
//! pressed, and wagashi's meshes opened there.
//!
//! Both read into fem-core's [`fem_core::mesh::TetMesh`]: nodes [mm] (the files
//! carry no unit; they are taken as mm), linear tets in VTK's positive order
//! (tets given the other way round are reversed; flat ones are refused),
//! regions (TetGen's region attribute, Gmsh's volume physical groups) with
//! names, and boundary triangles as face sets. Writing keeps nodes, cells and
//! regions so that reading the file back gives the same mesh (the round trip is
//! tested). [`read_tetmesh`] and [`write_tetmesh`] choose the format by extension
//! (`.vtu` is written by [`crate::vtu`] and read by [`vtu`]).
//!
//! Every refusal is a [`TetMeshError`] naming the file, the 1-based line and the
//! field (`cake.ele:7: node 3: 812 names no point (points 1..640)`); no input
//! makes these functions panic.
//!
//! ```
//! use wagashi_io::tetmesh::{read_tetmesh, write_tetmesh};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let dir = tempfile::tempdir()?;
//! let mesh = fem_core::mesh::block([2.0, 1.0, 1.0], 0.5, "gel")?;
//! for name in ["block.msh", "block.node"] {
//!     let path = dir.path().join(name);
//!     write_tetmesh(&path, &mesh)?;
//!     let back = read_tetmesh(&path)?;
//!     assert_eq!((back.nodes.len(), back.cells.len()), (mesh.nodes.len(), mesh.cells.len()));
//!     assert_eq!(back.region_names, vec!["gel"]);
//! }
//! # Ok(()) }
//! ```

mod error;
mod format;
pub mod gmsh;
pub mod tetgen;
pub mod vtu;

pub use error::TetMeshError;
pub use format::{read_tetmesh, write_tetmesh, TetMeshFormat};
pub use gmsh::{gmsh_string, parse_gmsh, read_gmsh, write_gmsh};
pub use tetgen::{parse_tetgen, read_tetgen, tetgen_strings, write_tetgen};
pub use vtu::{parse_vtu_tetmesh, read_vtu_tetmesh};
