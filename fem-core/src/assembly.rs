//! Sparse assembly: node topology, the CSR pattern, and parallel, deterministic
//! assembly of stiffness matrices and force vectors.
//!
//! Degrees of freedom are node-major: dof `D * node + k`. The pattern holds, for
//! every node row, all nodes that share a cell with it (itself included), sorted,
//! each as a `D x D` block, so the rows of one node are contiguous and equally long.
//!
//! Determinism: rows are assembled node by node (rayon over nodes); a node row sums
//! the contributions of its incident cells in increasing cell order, whatever the
//! number of threads. Vectors are assembled the same way from per-cell buffers.

use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

use crate::element::{stiffness_block, CellGeometry};

/// Node-to-cell and node-to-node adjacency of a mesh (CSR lists, sorted).
#[derive(Debug, Clone, PartialEq)]
pub struct Topology {
    /// `node_cells[cell_ptr[i]..cell_ptr[i+1]]`: the cells that hold node i, with the
    /// local index of node i in each, sorted by cell.
    pub cell_ptr: Vec<usize>,
    /// `(cell, local index)` pairs.
    pub node_cells: Vec<(u32, u8)>,
    /// `neighbours[adj_ptr[i]..adj_ptr[i+1]]`: nodes sharing a cell with node i, sorted, i included.
    pub adj_ptr: Vec<usize>,
    /// Neighbour node indices.
    pub neighbours: Vec<u32>,
}

impl Topology {
    /// Builds the adjacency of `num_nodes` nodes and the given cells (of any
    /// number of nodes each, e.g. the F-bar path's patches of cells).
    pub fn new<C: AsRef<[u32]> + Sync>(num_nodes: usize, cells: &[C]) -> Self {
        let mut counts = vec![0usize; num_nodes + 1];
        for c in cells {
            for &v in c.as_ref() {
                counts[v as usize + 1] += 1;
            }
        }
        for i in 0..num_nodes {
            counts[i + 1] += counts[i];
        }
        let cell_ptr = counts;
        let mut fill = cell_ptr.clone();
        let mut node_cells = vec![(0u32, 0u8); cell_ptr[num_nodes]];
        for (e, c) in cells.iter().enumerate() {
            for (a, &v) in c.as_ref().iter().enumerate() {
                node_cells[fill[v as usize]] = (e as u32, a as u8);
                fill[v as usize] += 1;
            }
        }
        // Cells were visited in increasing order, so each list is already sorted.
        let lists: Vec<Vec<u32>> = (0..num_nodes)
            .into_par_iter()
            .map(|i| {
                let mut nb: Vec<u32> = node_cells[cell_ptr[i]..cell_ptr[i + 1]]
                    .iter()
                    .flat_map(|&(e, _)| cells[e as usize].as_ref().iter().copied())
                    .collect();
                nb.push(i as u32);
                nb.sort_unstable();
                nb.dedup();
                nb
            })
            .collect();
        let mut adj_ptr = Vec::with_capacity(num_nodes + 1);
        adj_ptr.push(0);
        for l in &lists {
            adj_ptr.push(adj_ptr.last().unwrap() + l.len());
        }
        let neighbours = lists.concat();
        Self { cell_ptr, node_cells, adj_ptr, neighbours }
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.adj_ptr.len() - 1
    }
}

/// The CSR pattern over all dofs (symmetric, full storage).
#[derive(Debug, Clone, PartialEq)]
pub struct CsrPattern {
    /// Dofs per node.
    pub dim: usize,
    /// Row start offsets, length `num_dofs + 1`.
    pub row_ptr: Vec<usize>,
    /// Column indices, sorted within each row.
    pub col_idx: Vec<u32>,
}

impl CsrPattern {
    /// The block pattern of the topology with `dim` dofs per node.
    pub fn new(topology: &Topology, dim: usize) -> Self {
        let n = topology.num_nodes();
        let mut row_ptr = Vec::with_capacity(n * dim + 1);
        row_ptr.push(0usize);
        let mut col_idx = Vec::new();
        for i in 0..n {
            let nb = &topology.neighbours[topology.adj_ptr[i]..topology.adj_ptr[i + 1]];
            for _ in 0..dim {
                for &j in nb {
                    for l in 0..dim {
                        col_idx.push((j as usize * dim + l) as u32);
                    }
                }
                row_ptr.push(col_idx.len());
            }
        }
        Self { dim, row_ptr, col_idx }
    }

    /// Number of rows (dofs).
    pub fn num_dofs(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.col_idx.len()
    }

    /// `y = A x` for the values `a` on this pattern (parallel over rows, deterministic).
    pub fn mul_vec(&self, a: &[f64], x: &[f64], y: &mut [f64]) {
        crate::parallel::for_each_mut(y, |r, yr| {
            let mut s = 0.0;
            for p in self.row_ptr[r]..self.row_ptr[r + 1] {
                s += a[p] * x[self.col_idx[p] as usize];
            }
            *yr = s;
        });
    }

    /// Splits `values` into the contiguous blocks of each node's `dim` rows.
    fn node_row_blocks<'a>(&self, mut values: &'a mut [f64]) -> Vec<&'a mut [f64]> {
        let n = self.num_dofs() / self.dim;
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            let len = self.row_ptr[(i + 1) * self.dim] - self.row_ptr[i * self.dim];
            let (head, tail) = values.split_at_mut(len);
            out.push(head);
            values = tail;
        }
        out
    }
}

/// Assembles `sum_e w_e B_a^T C_e B_b` over the cells for which `cell_matrix(e)` is
/// `Some(C_e)`, into values on `pattern` (rows by node, in parallel; fixed order).
pub fn assemble_stiffness<const D: usize, const N: usize, const S: usize>(
    topology: &Topology,
    pattern: &CsrPattern,
    cells: &[[u32; N]],
    geometry: &[CellGeometry<D, N>],
    cell_matrix: &(dyn Fn(usize) -> Option<SMatrix<f64, S, S>> + Sync),
) -> Vec<f64> {
    assert_eq!(pattern.dim, D);
    let mut values = vec![0.0; pattern.nnz()];
    let blocks = pattern.node_row_blocks(&mut values);
    blocks.into_par_iter().enumerate().for_each(|(i, block)| {
        let nb = &topology.neighbours[topology.adj_ptr[i]..topology.adj_ptr[i + 1]];
        let row_len = D * nb.len();
        for &(e, a) in &topology.node_cells[topology.cell_ptr[i]..topology.cell_ptr[i + 1]] {
            let Some(c) = cell_matrix(e as usize) else { continue };
            let g = &geometry[e as usize];
            for (b, &j) in cells[e as usize].iter().enumerate() {
                let kab = stiffness_block::<D, N, S>(g, &c, a as usize, b);
                let pos = nb.binary_search(&j).expect("pattern holds every cell neighbour");
                for r in 0..D {
                    for l in 0..D {
                        block[r * row_len + pos * D + l] += kab[(r, l)];
                    }
                }
            }
        }
    });
    values
}

/// Assembles per-cell node-pair blocks `cell_block(e, a, b)` (node `a` of cell `e`
/// against node `b`, `D x D`, weight included) into values on `pattern`: the
/// general form of [`assemble_stiffness`] for tangents that are not `B^T C B`
/// (the finite-strain tangent with its geometric part). Rows by node, in
/// parallel, in a fixed order.
pub fn assemble_blocks<const D: usize, C: AsRef<[u32]> + Sync>(
    topology: &Topology,
    pattern: &CsrPattern,
    cells: &[C],
    cell_block: &(dyn Fn(usize, usize, usize) -> SMatrix<f64, D, D> + Sync),
) -> Vec<f64> {
    assert_eq!(pattern.dim, D);
    let mut values = vec![0.0; pattern.nnz()];
    let blocks = pattern.node_row_blocks(&mut values);
    blocks.into_par_iter().enumerate().for_each(|(i, block)| {
        let nb = &topology.neighbours[topology.adj_ptr[i]..topology.adj_ptr[i + 1]];
        let row_len = D * nb.len();
        for &(e, a) in &topology.node_cells[topology.cell_ptr[i]..topology.cell_ptr[i + 1]] {
            for (b, &j) in cells[e as usize].as_ref().iter().enumerate() {
                let kab = cell_block(e as usize, a as usize, b);
                let pos = nb.binary_search(&j).expect("pattern holds every cell neighbour");
                for r in 0..D {
                    for l in 0..D {
                        block[r * row_len + pos * D + l] += kab[(r, l)];
                    }
                }
            }
        }
    });
    values
}

/// Sums per-cell nodal vectors (`cell_forces[e][a]`, node `a` of cell `e`) into a
/// global vector, node by node in increasing cell order.
pub fn assemble_vector<const D: usize, const N: usize>(
    topology: &Topology,
    cell_forces: &[[SVector<f64, D>; N]],
    out: &mut [f64],
) {
    crate::parallel::for_each_chunk_mut(out, D, |i, o| {
        let mut s = SVector::<f64, D>::zeros();
        for &(e, a) in &topology.node_cells[topology.cell_ptr[i]..topology.cell_ptr[i + 1]] {
            s += cell_forces[e as usize][a as usize];
        }
        o.copy_from_slice(s.as_slice());
    });
}

/// Sums per-cell nodal vectors of cells with any number of nodes
/// (`cell_forces[e][D a + k]`, node `a` of cell `e` in the topology's lists)
/// into a global vector, node by node in increasing cell order.
pub fn assemble_list_vector<const D: usize>(topology: &Topology, cell_forces: &[Vec<f64>], out: &mut [f64]) {
    crate::parallel::for_each_chunk_mut(out, D, |i, o| {
        let mut s = SVector::<f64, D>::zeros();
        for &(e, a) in &topology.node_cells[topology.cell_ptr[i]..topology.cell_ptr[i + 1]] {
            let f = &cell_forces[e as usize][a as usize * D..(a as usize + 1) * D];
            for k in 0..D {
                s[k] += f[k];
            }
        }
        o.copy_from_slice(s.as_slice());
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{cell_geometry, unit_young_matrix, Formulation};
    use crate::mesh;

    /// The parallel node-row assembly equals a plain element-by-element triplet
    /// assembly through sprs (an independent reference).
    #[test]
    fn matches_triplet_assembly_through_sprs() {
        let m = mesh::block([3.0, 2.0, 2.0], 1.0, "a").unwrap();
        let topo = Topology::new(m.num_nodes(), &m.cells);
        let pat = CsrPattern::new(&topo, 3);
        let geo: Vec<_> =
            (0..m.num_cells()).map(|e| cell_geometry::<3, 4>(&m.cell_coordinates(e), 1.0).unwrap()).collect();
        let c = unit_young_matrix::<6>(Formulation::Solid, 0.3);
        let vals = assemble_stiffness::<3, 4, 6>(&topo, &pat, &m.cells, &geo, &|_| Some(c));
        let n = pat.num_dofs();
        let mut tri = sprs::TriMat::new((n, n));
        for (e, cell) in m.cells.iter().enumerate() {
            for a in 0..4 {
                for b in 0..4 {
                    let k = stiffness_block::<3, 4, 6>(&geo[e], &c, a, b);
                    for r in 0..3 {
                        for l in 0..3 {
                            tri.add_triplet(cell[a] as usize * 3 + r, cell[b] as usize * 3 + l, k[(r, l)]);
                        }
                    }
                }
            }
        }
        let reference: sprs::CsMat<f64> = tri.to_csr();
        let mut max_diff: f64 = 0.0;
        for r in 0..n {
            for p in pat.row_ptr[r]..pat.row_ptr[r + 1] {
                let j = pat.col_idx[p] as usize;
                let want = reference.get(r, j).copied().unwrap_or(0.0);
                max_diff = max_diff.max((vals[p] - want).abs());
            }
        }
        assert!(max_diff < 1e-12, "max difference {max_diff}");
        assert_eq!(reference.nnz(), pat.nnz());
    }
}
