use std::collections::BTreeMap;

use thiserror::Error;

/// A mesh of `N`-node simplices in `D` dimensions, with region tags and named sets.
///
/// `N` is always `D + 1`; the aliases [`TriMesh`] and [`TetMesh`] name the two cases.
#[derive(Debug, Clone, PartialEq)]
pub struct SimplexMesh<const D: usize, const N: usize> {
    /// Node coordinates [mm].
    pub nodes: Vec<[f64; D]>,
    /// Cells as node indices, in VTK order (positive measure).
    pub cells: Vec<[u32; N]>,
    /// Region (material) index of each cell, into `region_names`.
    pub cell_regions: Vec<u16>,
    /// Region names, e.g. the material or layer names.
    pub region_names: Vec<String>,
    /// Named node sets, e.g. `bottom` (y = 0) and `top` (y = H); sorted, unique.
    pub node_sets: BTreeMap<String, Vec<u32>>,
    /// Named boundary face sets: facets of `D` nodes (edges in 2D, triangles in 3D).
    pub face_sets: BTreeMap<String, Vec<[u32; D]>>,
}

/// A triangle mesh (2D).
pub type TriMesh = SimplexMesh<2, 3>;
/// A tetrahedral mesh (3D).
pub type TetMesh = SimplexMesh<3, 4>;

/// Why a mesh was refused.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MeshError {
    /// A cell with zero or negative measure (inverted or degenerate).
    #[error("element {element} is inverted or degenerate (signed measure {measure:e} mm^d)")]
    InvertedElement { element: usize, measure: f64 },
    /// A cell names a node that does not exist.
    #[error("element {element} names node {node}, but the mesh has {num_nodes} nodes")]
    NodeOutOfRange { element: usize, node: u32, num_nodes: usize },
    /// A generator was given a size it cannot mesh.
    #[error("cannot mesh: {0}")]
    BadGeometry(String),
    /// A named set the caller needs is missing.
    #[error("the mesh has no node set named `{0}`")]
    MissingSet(String),
}

impl<const D: usize, const N: usize> SimplexMesh<D, N>
where
    crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
{
    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Number of cells.
    pub fn num_cells(&self) -> usize {
        self.cells.len()
    }

    /// The node set `name`, or an error naming it.
    pub fn node_set(&self, name: &str) -> Result<&[u32], MeshError> {
        self.node_sets.get(name).map(|v| v.as_slice()).ok_or_else(|| MeshError::MissingSet(name.to_string()))
    }

    /// Axis-aligned bounding box `(min, max)` [mm].
    pub fn bounding_box(&self) -> ([f64; D], [f64; D]) {
        let mut lo = [f64::INFINITY; D];
        let mut hi = [f64::NEG_INFINITY; D];
        for p in &self.nodes {
            for k in 0..D {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// Node indices in range; every cell of positive signed measure.
    pub fn validate(&self) -> Result<(), MeshError> {
        const { assert!(N == D + 1, "a simplex in D dimensions has D + 1 nodes") };
        for (e, cell) in self.cells.iter().enumerate() {
            for &v in cell {
                if v as usize >= self.nodes.len() {
                    return Err(MeshError::NodeOutOfRange { element: e, node: v, num_nodes: self.nodes.len() });
                }
            }
            let measure = crate::element::signed_measure(&self.cell_coordinates(e));
            if !(measure > 0.0) {
                return Err(MeshError::InvertedElement { element: e, measure });
            }
        }
        Ok(())
    }

    /// Coordinates of the nodes of cell `e`.
    pub fn cell_coordinates(&self, e: usize) -> [[f64; D]; N] {
        self.cells[e].map(|v| self.nodes[v as usize])
    }

    /// Builds the node sets `name` from the nodes that satisfy `pred`.
    pub fn add_node_set(&mut self, name: &str, pred: impl Fn(&[f64; D]) -> bool) {
        let set: Vec<u32> = (0..self.nodes.len() as u32).filter(|&i| pred(&self.nodes[i as usize])).collect();
        self.node_sets.insert(name.to_string(), set);
    }

    /// Builds the face set `name` from the boundary facets whose nodes all satisfy `pred`.
    pub fn add_face_set(&mut self, name: &str, pred: impl Fn(&[f64; D]) -> bool) {
        let faces =
            self.boundary_facets().into_iter().filter(|f| f.iter().all(|&v| pred(&self.nodes[v as usize]))).collect();
        self.face_sets.insert(name.to_string(), faces);
    }

    /// Builds the node set and the face set `name` from the whole boundary: the
    /// facets of one cell only ([`Self::boundary_facets`]) and their nodes, sorted.
    pub fn add_boundary_sets(&mut self, name: &str) {
        let faces = self.boundary_facets();
        let mut nodes: Vec<u32> = faces.iter().flatten().copied().collect();
        nodes.sort_unstable();
        nodes.dedup();
        self.node_sets.insert(name.to_string(), nodes);
        self.face_sets.insert(name.to_string(), faces);
    }

    /// The facets that belong to exactly one cell, oriented outward, sorted.
    pub fn boundary_facets(&self) -> Vec<[u32; D]> {
        // Facet i of a cell is the cell without node i; an outward orientation
        // follows from the cell's positive orientation (see `element::facet`).
        let mut all: Vec<([u32; D], [u32; D])> = Vec::with_capacity(self.cells.len() * N);
        for cell in &self.cells {
            for i in 0..N {
                let f = crate::element::outward_facet::<D, N>(cell, i);
                let mut key = f;
                key.sort_unstable();
                all.push((key, f));
            }
        }
        all.sort_unstable_by_key(|a| a.0);
        let mut out = Vec::new();
        let mut i = 0;
        while i < all.len() {
            let mut j = i + 1;
            while j < all.len() && all[j].0 == all[i].0 {
                j += 1;
            }
            if j - i == 1 {
                out.push(all[i].1);
            }
            i = j;
        }
        out
    }

    /// Total measure (area in 2D, volume in 3D) [mm^D].
    pub fn measure(&self) -> f64 {
        (0..self.cells.len()).map(|e| crate::element::signed_measure(&self.cell_coordinates(e))).sum()
    }
}
