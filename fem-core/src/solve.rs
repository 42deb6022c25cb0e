//! Linear solves: the free-dof system and faer's sparse Cholesky.
//!
//! Three phases (deal.II, fenris, faer): [`ReducedSystem::new`] builds the reduced
//! pattern and the symbolic factorization once per constraint set;
//! [`ReducedSystem::factor`] does the numeric factorization when the matrix values
//! change (a new step size); [`Factor::solve_in_place`] runs as often as needed.
//!
//! faer runs with a fixed degree of parallelism ([`FAER_PARALLELISM`]), not the size
//! of the thread pool, so results do not depend on the number of threads.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

use crate::assembly::CsrPattern;

/// The degree of parallelism given to faer: fixed, so that its work split (and so
/// its floating-point results) is the same whatever the thread pool.
pub const FAER_PARALLELISM: usize = 2;

/// Batched solves of fewer free dofs than this run on the calling thread.
pub const SEQUENTIAL_BATCH_BELOW: usize = 20_000;

fn par() -> Par {
    Par::rayon(FAER_PARALLELISM)
}

/// Why a factorization failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// The matrix is not numerically positive definite; `dof` is the free dof (its
    /// index in the full numbering) whose pivot failed, when faer says which.
    #[error("not positive definite{}", dof.map_or(String::new(), |d| format!(" at dof {d}")))]
    NotPositiveDefinite { dof: Option<usize> },
    /// faer could not allocate or set up the factorization.
    #[error("factorization failed: {0}")]
    Setup(String),
}

/// The free-dof block of a symmetric matrix on a [`CsrPattern`], upper triangle in
/// CSC form, with its symbolic Cholesky factorization.
pub struct ReducedSystem {
    /// Reduced index of each dof, `u32::MAX` for a constrained one.
    pub free_of_dof: Vec<u32>,
    /// Dof of each reduced index.
    pub dof_of_free: Vec<u32>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Position in the full pattern's values of each reduced entry.
    positions: Vec<usize>,
    /// Reduced entry index of each diagonal.
    diagonal: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
}

/// A numeric Cholesky factorization of a [`ReducedSystem`].
pub struct Factor<'a> {
    system: &'a ReducedSystem,
    values: Vec<f64>,
}

impl ReducedSystem {
    /// Builds the reduced pattern for the dofs with `constrained[dof] == false`,
    /// ordered for elimination by `node_order` (position -> node; a node's dofs stay
    /// together) or, without one, by faer's AMD.
    pub fn new(pattern: &CsrPattern, constrained: &[bool], node_order: Option<&[u32]>) -> Result<Self, SolveError> {
        let n = pattern.num_dofs();
        assert_eq!(constrained.len(), n);
        let mut free_of_dof = vec![u32::MAX; n];
        let mut dof_of_free = Vec::new();
        for (d, &c) in constrained.iter().enumerate() {
            if !c {
                free_of_dof[d] = dof_of_free.len() as u32;
                dof_of_free.push(d as u32);
            }
        }
        let nf = dof_of_free.len();
        let mut col_ptr = Vec::with_capacity(nf + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        let mut positions = Vec::new();
        let mut diagonal = Vec::with_capacity(nf);
        // Column j of the symmetric matrix is row j of the CSR; keep free rows i <= j.
        for (j, &dof) in dof_of_free.iter().enumerate() {
            let r = dof as usize;
            for p in pattern.row_ptr[r]..pattern.row_ptr[r + 1] {
                let i = free_of_dof[pattern.col_idx[p] as usize];
                if i != u32::MAX && (i as usize) <= j {
                    if i as usize == j {
                        diagonal.push(row_idx.len());
                    }
                    row_idx.push(i as usize);
                    positions.push(p);
                }
            }
            col_ptr.push(row_idx.len());
        }
        let sym = SymbolicSparseColMat::new_checked(nf, nf, col_ptr.clone(), None, row_idx.clone());
        // The elimination order of the free dofs, from the node order.
        let (forward, inverse): (Vec<usize>, Vec<usize>) = match node_order {
            Some(order) => {
                let dim = pattern.dim;
                let forward: Vec<usize> = order
                    .iter()
                    .flat_map(|&node| (0..dim).map(move |k| node as usize * dim + k))
                    .filter(|&d| free_of_dof[d] != u32::MAX)
                    .map(|d| free_of_dof[d] as usize)
                    .collect();
                assert_eq!(forward.len(), nf, "the node order must hold every node once");
                let mut inverse = vec![0usize; nf];
                for (i, &f) in forward.iter().enumerate() {
                    inverse[f] = i;
                }
                (forward, inverse)
            }
            None => (Vec::new(), Vec::new()),
        };
        let ordering = if node_order.is_some() {
            SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&forward, &inverse, nf))
        } else {
            SymmetricOrdering::Amd
        };
        let symbolic =
            factorize_symbolic_cholesky(sym.as_ref(), Side::Upper, ordering, CholeskySymbolicParams::default())
                .map_err(|e| SolveError::Setup(format!("{e:?}")))?;
        Ok(Self { free_of_dof, dof_of_free, col_ptr, row_idx, positions, diagonal, symbolic })
    }

    /// The dof of a failed pivot: faer reports the pivot's position (one-based) in
    /// the elimination order; the ordering maps it back to a reduced dof.
    fn failed_dof(&self, e: &faer::linalg::cholesky::llt::factor::LltError) -> Option<usize> {
        let faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } = e;
        let position = index.checked_sub(1)?;
        let reduced = match self.symbolic.perm() {
            Some(perm) => *perm.arrays().0.get(position)?,
            None => position,
        };
        self.dof_of_free.get(reduced).map(|&d| d as usize)
    }

    /// Number of free dofs.
    pub fn num_free(&self) -> usize {
        self.dof_of_free.len()
    }

    /// Nonzeros of the Cholesky factor.
    pub fn factor_nonzeros(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Factors `sum_i coef_i A_i + diag(extra)` (restricted to the free dofs), where
    /// each `A_i` holds values on the full pattern and `extra` is per dof.
    pub fn factor(&self, terms: &[(f64, &[f64])], extra_diagonal: Option<&[f64]>) -> Result<Factor<'_>, SolveError> {
        let mut vals: Vec<f64> = self.positions.iter().map(|&p| terms.iter().map(|(c, a)| c * a[p]).sum()).collect();
        if let Some(extra) = extra_diagonal {
            for (j, &q) in self.diagonal.iter().enumerate() {
                vals[q] += extra[self.dof_of_free[j] as usize];
            }
        }
        self.factor_values(vals)
    }

    /// Factors `sum_i coef_i A_i` with the free dofs marked in `decoupled` (per
    /// dof) cut off from the others: their off-diagonal entries are zero, their
    /// diagonal kept. Solving with it and a zero right-hand side on those dofs is
    /// the exact elimination of dofs held at given values (their coupling moved to
    /// the right-hand side beforehand), without a new symbolic factorization: the
    /// pattern is the same, and the cut entries stay exact zeros in the factor.
    ///
    /// `extra_diagonal` (per dof) is added to the diagonal, as in [`Self::factor`].
    pub fn factor_decoupled(
        &self,
        terms: &[(f64, &[f64])],
        decoupled: &[bool],
        extra_diagonal: Option<&[f64]>,
    ) -> Result<Factor<'_>, SolveError> {
        let mut vals: Vec<f64> = self.positions.iter().map(|&p| terms.iter().map(|(c, a)| c * a[p]).sum()).collect();
        if let Some(extra) = extra_diagonal {
            for (j, &q) in self.diagonal.iter().enumerate() {
                vals[q] += extra[self.dof_of_free[j] as usize];
            }
        }
        for j in 0..self.num_free() {
            let cut_column = decoupled[self.dof_of_free[j] as usize];
            for q in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[q];
                if i != j && (cut_column || decoupled[self.dof_of_free[i] as usize]) {
                    vals[q] = 0.0;
                }
            }
        }
        self.factor_values(vals)
    }

    fn factor_values(&self, vals: Vec<f64>) -> Result<Factor<'_>, SolveError> {
        let sym = unsafe {
            // The pattern was checked in `new`.
            faer::sparse::SymbolicSparseColMatRef::new_unchecked(
                self.num_free(),
                self.num_free(),
                &self.col_ptr,
                None,
                &self.row_idx,
            )
        };
        let mat = SparseColMatRef::new(sym, &vals);
        let mut values = vec![0.0; self.symbolic.len_val()];
        let req = self.symbolic.factorize_numeric_llt_scratch::<f64>(par(), Default::default());
        let mut buf = MemBuffer::try_new(req).map_err(|e| SolveError::Setup(format!("{e:?}")))?;
        self.symbolic
            .factorize_numeric_llt(
                &mut values,
                mat,
                Side::Upper,
                Default::default(),
                par(),
                MemStack::new(&mut buf),
                Default::default(),
            )
            .map_err(|e| SolveError::NotPositiveDefinite { dof: self.failed_dof(&e) })?;
        Ok(Factor { system: self, values })
    }
}

impl Factor<'_> {
    /// Solves `A x = b` in place (`rhs` holds b on entry, x on exit; free dofs only).
    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        self.solve_columns_in_place(rhs, 1);
    }

    /// Solves `A X = B` in place for `ncols` right-hand sides stored one column
    /// after the other (column-major, free dofs only). faer's sparse triangular
    /// solves update four columns per pass over the factor, so a batch reads the
    /// factor about `ncols/4` times instead of `ncols` times.
    pub fn solve_columns_in_place(&self, rhs: &mut [f64], ncols: usize) {
        let n = self.system.num_free();
        assert_eq!(rhs.len(), n * ncols);
        if ncols == 0 {
            return;
        }
        // A small batch is solved on the calling thread: handing a solve of a few
        // thousand unknowns to the pool costs more than the solve. The choice
        // depends on the size only, and faer's split over columns does not change
        // any column's arithmetic, so results do not depend on the thread pool.
        let par = if ncols > 1 && n < SEQUENTIAL_BATCH_BELOW { Par::Seq } else { par() };
        let req = self.system.symbolic.solve_in_place_scratch::<f64>(ncols, par);
        let mut buf = MemBuffer::new(req);
        let llt = LltRef::new(&self.system.symbolic, &self.values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, ncols),
            par,
            MemStack::new(&mut buf),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assembly::{assemble_stiffness, Topology};
    use crate::element::{cell_geometry, unit_young_matrix, Formulation};

    /// A plane-strain 4 x 3 block of unit elements: its mesh, topology, pattern,
    /// stiffness values and the bottom's dofs (both held).
    fn plane_strain_block() -> (crate::mesh::TriMesh, Topology, CsrPattern, Vec<f64>, Vec<bool>) {
        let m = crate::mesh::rectangle(4.0, 3.0, 1.0, "a").unwrap();
        let topo = Topology::new(m.num_nodes(), &m.cells);
        let pat = CsrPattern::new(&topo, 2);
        let geo: Vec<_> =
            (0..m.num_cells()).map(|e| cell_geometry::<2, 3>(&m.cell_coordinates(e), 1.0).unwrap()).collect();
        let c = unit_young_matrix::<3>(Formulation::PlaneStrain { thickness_mm: 1.0 }, 0.25);
        let k = assemble_stiffness::<2, 3, 3>(&topo, &pat, &m.cells, &geo, &|_| Some(c));
        let mut bottom = vec![false; pat.num_dofs()];
        for &n in &m.node_sets["bottom"] {
            bottom[2 * n as usize] = true;
            bottom[2 * n as usize + 1] = true;
        }
        (m, topo, pat, k, bottom)
    }

    #[test]
    fn solves_a_constrained_stiffness_system() {
        let (m, topo, pat, k, constrained) = plane_strain_block();
        let sys = ReducedSystem::new(&pat, &constrained, None).unwrap();
        let order = crate::ordering::nested_dissection(&m.nodes, &topo);
        let nd = ReducedSystem::new(&pat, &constrained, Some(&order)).unwrap();
        let mut y_nd: Vec<f64> = (0..nd.num_free()).map(|i| (i as f64).sin()).collect();
        nd.factor(&[(2.0, &k)], None).unwrap().solve_in_place(&mut y_nd);
        let f = sys.factor(&[(2.0, &k)], None).unwrap();
        let b: Vec<f64> = (0..sys.num_free()).map(|i| (i as f64).sin()).collect();
        let mut x = b.clone();
        f.solve_in_place(&mut x);
        // Residual with the full matrix: (2K x)_free = b.
        let mut full = vec![0.0; pat.num_dofs()];
        for (i, &d) in sys.dof_of_free.iter().enumerate() {
            full[d as usize] = x[i];
        }
        let mut y = vec![0.0; pat.num_dofs()];
        pat.mul_vec(&k, &full, &mut y);
        for (i, &d) in sys.dof_of_free.iter().enumerate() {
            assert!((2.0 * y[d as usize] - b[i]).abs() < 1e-10, "row {i}");
        }
        // The nested-dissection ordering solves the same system.
        for i in 0..x.len() {
            assert!((x[i] - y_nd[i]).abs() < 1e-9 * x.iter().fold(1.0f64, |a, v| a.max(v.abs())), "row {i}");
        }
        // Without constraints the stiffness is singular: the factorization must say so.
        let free_all = ReducedSystem::new(&pat, &vec![false; pat.num_dofs()], None).unwrap();
        assert!(free_all.factor(&[(1.0, &k)], None).is_err());

        // Five columns at once (a batch of four and one) give each column's own solve.
        let n = sys.num_free();
        let columns: Vec<Vec<f64>> =
            (0..5).map(|c| (0..n).map(|i| ((i * (c + 2)) as f64).cos() + c as f64).collect()).collect();
        let mut batch: Vec<f64> = columns.concat();
        f.solve_columns_in_place(&mut batch, 5);
        for (c, col) in columns.iter().enumerate() {
            let mut single = col.clone();
            f.solve_in_place(&mut single);
            for i in 0..n {
                assert!((batch[c * n + i] - single[i]).abs() <= 1e-12 * single[i].abs().max(1.0), "column {c} row {i}");
            }
        }
    }

    /// Cutting dofs off the matrix and solving with their coupling on the right-hand
    /// side is the elimination of those dofs: the same solution as the system
    /// built with them held, on the same pattern (no new symbolic factorization).
    #[test]
    fn decoupled_dofs_are_eliminated_exactly() {
        let (m, _, pat, k, bottom) = plane_strain_block();
        let nd = pat.num_dofs();
        // The top's y dofs held at -0.1, the x dof of its first node at 0.05.
        let top = &m.node_sets["top"];
        let mut held: Vec<(usize, f64)> = top.iter().map(|&n| (2 * n as usize + 1, -0.1)).collect();
        held.push((2 * top[0] as usize, 0.05));
        let mut both = bottom.clone();
        let mut cut = vec![false; nd];
        let mut u_held = vec![0.0; nd];
        for &(d, v) in &held {
            both[d] = true;
            cut[d] = true;
            u_held[d] = v;
        }
        let b: Vec<f64> = (0..nd).map(|d| 0.01 * (d as f64).sin()).collect();
        let mut coupling = vec![0.0; nd];
        pat.mul_vec(&k, &u_held, &mut coupling);
        let rhs: Vec<f64> = (0..nd).map(|d| if cut[d] { 0.0 } else { b[d] - coupling[d] }).collect();
        // Reference: the reduced system without the held dofs.
        let reduced = ReducedSystem::new(&pat, &both, None).unwrap();
        let mut x_ref: Vec<f64> = reduced.dof_of_free.iter().map(|&d| rhs[d as usize]).collect();
        reduced.factor(&[(1.0, &k)], None).unwrap().solve_in_place(&mut x_ref);
        // The same held dofs cut off a system that leaves them free.
        let sys = ReducedSystem::new(&pat, &bottom, None).unwrap();
        let mut x: Vec<f64> = sys.dof_of_free.iter().map(|&d| rhs[d as usize]).collect();
        sys.factor_decoupled(&[(1.0, &k)], &cut, None).unwrap().solve_in_place(&mut x);
        let scale = x_ref.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(scale > 1e-3);
        for (i, &d) in reduced.dof_of_free.iter().enumerate() {
            let j = sys.free_of_dof[d as usize] as usize;
            assert!((x[j] - x_ref[i]).abs() <= 1e-12 * scale, "dof {d}: {} vs {}", x[j], x_ref[i]);
        }
        for &(d, _) in &held {
            assert_eq!(x[sys.free_of_dof[d] as usize], 0.0, "a cut dof with a zero right-hand side stays zero");
        }
    }
}
