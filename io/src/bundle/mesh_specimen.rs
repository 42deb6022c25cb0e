//! A `shape = "mesh"` specimen: a tetrahedral mesh read from a file and pressed as
//! it is.
//!
//! - The mesh file (`specimen.mesh`, relative to the bundle folder and confined
//!   to it like every file a bundle names) is a Gmsh MSH 4.1 ASCII file (`.msh`),
//!   a TetGen mesh (`.node` or `.ele`, with its siblings) or a VTK `.vtu` with
//!   ASCII data arrays, read by
//!   [`crate::tetmesh::read_tetmesh`]. These files carry no unit: coordinates are
//!   taken in mm, as that reader and `wagashi mesh` (which writes them) do. The
//!   specimen's frame is the file's: y up, the floor at the lowest y.
//! - The element size of [`Bundle::to_press`] does not apply: the mesh is pressed
//!   with the cells it has.
//! - Tetrahedra given in the negative orientation are reversed by the reader; a
//!   flat one, a node index out of range, a file without tetrahedra or another
//!   volume element are refused naming the mesh file, its line and the field,
//!   after the bundle's `experiment.toml:LINE: specimen.mesh:`.
//! - Nodes no tetrahedron uses (a mesher's construction points) carry no
//!   stiffness and are left out; the face sets of the file are kept where all
//!   their nodes are. The node set and face set `boundary` are the mesh's
//!   boundary facets (faces of one cell only), as for a meshed surface.
//! - The cells must fit together and form one piece: a face shared by more
//!   than two tetrahedra, or two tetrahedra on the same side of the face they
//!   share (a folded or inverted region), is refused naming the tetrahedra
//!   (1-based, in file order); so are pieces that share no face (apart, or
//!   touching only at edges or nodes), which would be free to turn or slide
//!   against each other, named by their sizes.
//! - Regions: each mesh region (a Gmsh volume physical group, named by
//!   `$PhysicalNames`, else `physical<tag>`, or `volume<tag>` without a group; a
//!   TetGen region attribute `region<value>`; a `.vtu`'s cell data `region`,
//!   `gmsh:physical` or `CellEntityIds`, see [`crate::tetmesh::vtu`]) takes the material that
//!   `[specimen.regions]` maps it to, or `material` for all, exactly as the
//!   regions of a surface ([`Bundle::surface_region_materials`]).
//! - Support, top and tools: as for a surface specimen (`surface_specimen.rs`):
//!   the node sets `bottom` and `top` are the boundary nodes within
//!   [`super::BASE_BAND`] of the lowest and highest y, the bottom must span a
//!   triangle, and the specimen always runs with rigid contact tools placed
//!   against the mesh's bounding box.

use std::path::PathBuf;

use fem_core::mesh::TetMesh;

use super::experiment::Shape;
use super::read::Bundle;
use crate::error::BundleError;
use crate::tetmesh::read_tetmesh;

impl Bundle {
    /// The path of the specimen's mesh file (`shape = "mesh"`), if any.
    pub fn mesh_path(&self) -> Option<PathBuf> {
        let s = &self.experiment.specimen;
        (s.shape == Shape::Mesh).then(|| s.mesh.as_deref().map(|f| self.dir.join(f))).flatten()
    }

    /// The specimen's tetrahedral mesh [mm] read from `specimen.mesh`, with node
    /// sets `boundary`, `bottom` and `top` (module docs); refused naming
    /// `specimen.mesh`. Its region names are the file's;
    /// [`Bundle::surface_region_materials`] gives their materials.
    pub fn specimen_mesh(&self) -> Result<TetMesh, BundleError> {
        let path = self.mesh_path().ok_or_else(|| {
            self.map.invalid("specimen.mesh", "missing required key for shape = \"mesh\"".to_string())
        })?;
        let read = read_tetmesh(&path).map_err(|e| self.map.invalid("specimen.mesh", e.to_string()))?;
        let mut mesh = used_nodes_only(read);
        let pieces = face_connected_pieces(&mesh)
            .map_err(|cause| self.map.invalid("specimen.mesh", format!("{}: {cause}", path.display())))?;
        if pieces.len() > 1 {
            let sizes: Vec<String> = pieces.iter().take(5).map(|n| n.to_string()).collect();
            let more = if pieces.len() > 5 { ", ..." } else { "" };
            return Err(self.map.invalid(
                "specimen.mesh",
                format!(
                    "{}: the tetrahedra form {} pieces that share no face (of {}{more} tetrahedra): pieces joined \
                     at edges or nodes only, or apart, are free to move against each other",
                    path.display(),
                    pieces.len(),
                    sizes.join(", ")
                ),
            ));
        }
        mesh.add_boundary_sets("boundary");
        self.add_support_sets(&mut mesh)?;
        Ok(mesh)
    }
}

/// `mesh` without the nodes no cell uses, node sets and face sets renumbered
/// (face set members on a dropped node are dropped with it).
fn used_nodes_only(mut mesh: TetMesh) -> TetMesh {
    let mut new_index = vec![u32::MAX; mesh.nodes.len()];
    for cell in &mesh.cells {
        for &v in cell {
            if let Some(slot) = new_index.get_mut(v as usize) {
                *slot = 0;
            }
        }
    }
    if new_index.iter().all(|&i| i == 0) {
        return mesh;
    }
    let mut nodes = Vec::with_capacity(mesh.nodes.len());
    for (i, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = nodes.len() as u32;
            nodes.push(mesh.nodes[i]);
        }
    }
    let renumber = |v: &u32| new_index.get(*v as usize).copied().filter(|&i| i != u32::MAX);
    for cell in &mut mesh.cells {
        for v in cell.iter_mut() {
            *v = renumber(v).unwrap_or(*v);
        }
    }
    for set in mesh.node_sets.values_mut() {
        *set = set.iter().filter_map(renumber).collect();
    }
    for set in mesh.face_sets.values_mut() {
        *set = set.iter().filter_map(|f| Some([renumber(&f[0])?, renumber(&f[1])?, renumber(&f[2])?])).collect();
    }
    mesh.nodes = nodes;
    mesh
}

/// The sizes (cell counts, largest first) of the pieces of `mesh` whose cells
/// are joined through shared faces; or why the cells do not fit together: a
/// face shared by more than two cells, or two cells on the same side of the
/// face they share (a fold). Cells are named 1-based in file order.
fn face_connected_pieces(mesh: &TetMesh) -> Result<Vec<usize>, String> {
    let n = mesh.cells.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    // (sorted face, cell, the cell's node off the face)
    let mut faces: Vec<([u32; 3], usize, u32)> = Vec::with_capacity(4 * n);
    for (c, cell) in mesh.cells.iter().enumerate() {
        for skip in 0..4 {
            let mut f = [0u32; 3];
            let mut k = 0;
            for (j, &v) in cell.iter().enumerate() {
                if j != skip {
                    f[k] = v;
                    k += 1;
                }
            }
            f.sort_unstable();
            faces.push((f, c, cell[skip]));
        }
    }
    faces.sort_unstable();
    let side = |f: &[u32; 3], p: u32| {
        let [a, b, c, p] = [f[0], f[1], f[2], p].map(|v| mesh.nodes[v as usize]);
        let (u, v, w) = (
            [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
            [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
            [p[0] - a[0], p[1] - a[1], p[2] - a[2]],
        );
        (u[1] * v[2] - u[2] * v[1]) * w[0] + (u[2] * v[0] - u[0] * v[2]) * w[1] + (u[0] * v[1] - u[1] * v[0]) * w[2]
    };
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j].0 == faces[i].0 {
            j += 1;
        }
        if j - i > 2 {
            let cells: Vec<String> = faces[i..j].iter().map(|f| format!("#{}", f.1 + 1)).collect();
            return Err(format!(
                "tetrahedra {} share one face: a face belongs to at most two tetrahedra",
                cells.join(", ")
            ));
        }
        if j - i == 2 {
            let (f, a, b) = (faces[i].0, faces[i], faces[i + 1]);
            if side(&f, a.2) * side(&f, b.2) >= 0.0 {
                return Err(format!(
                    "tetrahedra #{} and #{} lie on the same side of the face they share: the mesh folds over itself",
                    a.1 + 1,
                    b.1 + 1
                ));
            }
            let (ra, rb) = (root(&mut parent, a.1), root(&mut parent, b.1));
            if ra != rb {
                parent[ra] = rb;
            }
        }
        i = j;
    }
    let mut sizes = std::collections::BTreeMap::<usize, usize>::new();
    for c in 0..n {
        *sizes.entry(root(&mut parent, c)).or_default() += 1;
    }
    let mut out: Vec<usize> = sizes.into_values().collect();
    out.sort_unstable_by(|a, b| b.cmp(a));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unused_nodes_are_left_out_and_pieces_are_counted() {
        let mut mesh = fem_core::mesh::block([2.0, 1.0, 1.0], 1.0, "gel").unwrap();
        let (nodes, cells) = (mesh.nodes.len(), mesh.cells.len());
        assert_eq!(face_connected_pieces(&mesh), Ok(vec![cells]));
        // A construction point no cell uses, put first so that every index moves.
        mesh.nodes.insert(0, [50.0, 50.0, 50.0]);
        mesh.cells.iter_mut().flatten().for_each(|v| *v += 1);
        let volume = mesh.measure();
        let back = used_nodes_only(mesh);
        assert_eq!((back.nodes.len(), back.cells.len()), (nodes, cells));
        assert!((back.measure() - volume).abs() < 1e-12 * volume);
        assert!(back.nodes.iter().all(|p| p[0] <= 2.0));
        // A copy moved off by 10 mm makes a second piece.
        let mut two = back.clone();
        let offset = two.nodes.len() as u32;
        two.nodes.extend(back.nodes.iter().map(|p| [p[0] + 10.0, p[1], p[2]]));
        two.cells.extend(back.cells.iter().map(|c| c.map(|v| v + offset)));
        two.cell_regions.extend(back.cell_regions.iter().copied());
        assert_eq!(face_connected_pieces(&two), Ok(vec![cells, cells]));
        // A second cell on the nodes of the first: both lie on the same side of
        // every face they share, which is a fold.
        let mut folded = back.clone();
        let extra = folded.cells[0];
        folded.cells.push([extra[0], extra[2], extra[1], extra[3]]);
        folded.cell_regions.push(0);
        let err = face_connected_pieces(&folded).unwrap_err();
        assert!(err.contains(&format!("#{}", cells + 1)), "{err}");
    }
}
