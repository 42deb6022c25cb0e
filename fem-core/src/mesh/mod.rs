//! Simplex meshes: triangles in 2D, tetrahedra in 3D.
//!
//! Node order is VTK's: a triangle `[0, 1, 2]` is counter-clockwise seen from +z;
//! a tetrahedron `[0, 1, 2, 3]` has node 3 on the side of `(x1 - x0) x (x2 - x0)`
//! (positive signed volume). Coordinates are in mm. The push axis is y; the
//! specimen's bottom face lies on y = 0.

mod generate;
mod simplex_mesh;

pub use generate::{block, cylinder, layered_block, layered_rectangle, rectangle, Layer};
pub use simplex_mesh::{MeshError, SimplexMesh, TetMesh, TriMesh};
