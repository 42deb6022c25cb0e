//! Simplex meshes: triangles in 2D, tetrahedra in 3D.
//!
//! Node order is VTK's: a triangle `[0, 1, 2]` is counter-clockwise seen from +z;
//! a tetrahedron `[0, 1, 2, 3]` has node 3 on the side of `(x1 - x0) x (x2 - x0)`
//! (positive signed volume). Coordinates are in mm. The push axis is y; the
//! specimen's bottom face lies on y = 0. An axisymmetric mesh is a triangle mesh
//! of the `r-y` section (x = r >= 0) with the node set `axis` on r = 0.

mod generate;
mod simplex_mesh;

pub use generate::{
    axisymmetric_section, block, cylinder, indentation_section, layered_axisymmetric_section, layered_block,
    layered_rectangle, rectangle, Layer,
};
pub use simplex_mesh::{MeshError, SimplexMesh, TetMesh, TriMesh};
