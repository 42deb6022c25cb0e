//! F-bar patches: near incompressibility on linear simplices for the Newton
//! path (de Souza Neto, Pires & Owen's F-bar-patch method, in its variational
//! form).
//!
//! ## Why
//!
//! A linear triangle or tetrahedron has one constant `J` per cell: at a
//! Poisson ratio near 1/2 every cell must keep its volume, and a tet mesh has
//! about twice as many cells as free dofs per node can follow, so it locks (the
//! sphere on a block at nu = 0.49 is 20 % too stiff on a 0.5 mm mesh).
//!
//! ## What
//!
//! The cells are grouped into disjoint patches of [`patch_size`] face-connected
//! cells. A patch's volume ratio is the weighted mean `Jbar = sum_c w_c J_c /
//! sum_c w_c`, and every cell of the patch is evaluated at the modified gradient
//!
//! ```text
//! Fbar_e = (Jbar / J_e)^(1/3) F_e,
//! ```
//!
//! (in plane strain the in-plane block only, `(Jbar / J)^(1/2)`, so that
//! `Fbar_zz = F_zz = 1`), which keeps the cell's isochoric part and takes the
//! patch's volume change:
//! one volume constraint per patch, not per cell. Any law behind the seam runs
//! at `Fbar` unchanged (its viscous and plastic networks included).
//!
//! The internal force is the derivative of `sum_e w_e psi_e(Fbar_e(u))` (the
//! step's potential), `f = sum_e w_e B_e^T P(Fbar_e)` with
//! `dFbar_e = B_e du = s (G_e du + F_e (k_e . du) / 3)`, `s = (Jbar/J_e)^(1/3)`,
//! `k_e = d ln Jbar - d ln J_e`, and its tangent is the exact second
//! derivative:
//!
//! ```text
//! K = sum_e w_e [ B_e^T A B_e + s/3 (g_e k_e^T + k_e g_e^T) + s/9 (P:F_e) k_e k_e^T
//!                 + s/3 (P:F_e) (H(ln Jbar) - H(ln J_e)) ],      g_e = G_e^T P,
//! ```
//!
//! symmetric wherever the law's tangent is major-symmetric, so the Cholesky
//! factorization stays. (The classical F-bar tests with the unmodified virtual
//! gradient and has a non-symmetric tangent.) A patch of one cell is the
//! standard element exactly (`k = 0`, `s = 1`).
//!
//! The tangent couples every pair of nodes of a patch: the pattern is the
//! patches' ([`Patches::pattern`]), a superset of the cells'.
//!
//! ## Patches
//!
//! Greedy and deterministic: cells in index order seed patches that grow by
//! breadth-first search over facets shared with cells of the same region until
//! they hold `patch_size` cells; a patch left smaller than half of that (hemmed in by full ones)
//! joins its smallest neighbouring patch. With `n` cells per patch the volume
//! constraints per free dof fall from about 2 (tets) and 1 (triangles) to
//! `2/n` and `1/n`.

use nalgebra::{DMatrix, DVector, Matrix3, SMatrix};
use rayon::prelude::*;

use crate::assembly::{assemble_blocks, assemble_list_vector, CsrPattern, Topology};
use crate::material::law::{LawFailure, PointResponse};

/// Cells per patch in `dim` dimensions: 4 tetrahedra (a constraint per 1.5
/// nodes, the ratio of quadratic tetrahedra with linear pressure, P2-P1), 3
/// triangles (a constraint per 1.5 nodes, as P2-P1 triangles).
pub(crate) fn patch_size(dim: usize) -> usize {
    if dim == 3 {
        4
    } else {
        3
    }
}

/// A mesh's cells grouped into F-bar patches, with the patches' stencil.
#[derive(Debug, Clone)]
pub(crate) struct Patches {
    /// The cells of each patch, increasing.
    pub cells: Vec<Vec<u32>>,
    /// The nodes of each patch, sorted.
    pub nodes: Vec<Vec<u32>>,
    /// Per cell: the patch-local index of each of its nodes.
    pub local: Vec<Vec<u8>>,
    /// Node adjacency through the patches.
    pub topology: Topology,
    /// The block pattern of every pair of nodes sharing a patch.
    pub pattern: CsrPattern,
    /// Position of each dof's diagonal entry in `pattern`.
    pub diagonal_positions: Vec<usize>,
    /// A fill-reducing node order for `pattern`.
    pub node_order: Vec<u32>,
}

impl Patches {
    /// Groups `cells` (of `D`-dimensional nodes at `coordinates`, in `regions`)
    /// into patches of about `target` cells of one region each.
    pub(crate) fn new<const D: usize, const N: usize>(
        coordinates: &[[f64; D]],
        cells: &[[u32; N]],
        regions: &[u16],
        target: usize,
    ) -> Self {
        let groups = partition(cells, regions, target);
        let mut nodes = Vec::with_capacity(groups.len());
        let mut local = vec![Vec::new(); cells.len()];
        for group in &groups {
            let mut list: Vec<u32> = group.iter().flat_map(|&e| cells[e as usize]).collect();
            list.sort_unstable();
            list.dedup();
            assert!(list.len() <= u8::MAX as usize, "an F-bar patch of {} nodes", list.len());
            for &e in group {
                local[e as usize] = cells[e as usize]
                    .iter()
                    .map(|v| list.binary_search(v).expect("a cell's node is in its patch") as u8)
                    .collect();
            }
            nodes.push(list);
        }
        let topology = Topology::new(coordinates.len(), &nodes);
        let pattern = CsrPattern::new(&topology, D);
        let diagonal_positions = (0..pattern.num_dofs())
            .map(|r| {
                let row = &pattern.col_idx[pattern.row_ptr[r]..pattern.row_ptr[r + 1]];
                pattern.row_ptr[r] + row.iter().position(|&c| c as usize == r).expect("the diagonal is in the pattern")
            })
            .collect();
        let node_order = crate::ordering::nested_dissection(coordinates, &topology);
        Self { cells: groups, nodes, local, topology, pattern, diagonal_positions, node_order }
    }

    /// Sums the patches' nodal vectors (`forces[p][D a + k]`) into `out`.
    pub(crate) fn assemble_vector<const D: usize>(&self, forces: &[Vec<f64>], out: &mut [f64]) {
        assemble_list_vector::<D>(&self.topology, forces, out);
    }

    /// The patches' matrices (`n D x n D`, node-major) on [`Self::pattern`].
    pub(crate) fn assemble_matrix<const D: usize>(&self, matrices: &[DMatrix<f64>]) -> Vec<f64> {
        let block =
            |p: usize, a: usize, b: usize| SMatrix::<f64, D, D>::from_fn(|r, c| matrices[p][(a * D + r, b * D + c)]);
        assemble_blocks::<D, _>(&self.topology, &self.pattern, &self.nodes, &block)
    }
}

/// Face-connected groups of about `target` cells, deterministic (module docs).
pub(crate) fn partition<const N: usize>(cells: &[[u32; N]], regions: &[u16], target: usize) -> Vec<Vec<u32>> {
    let n = cells.len();
    // Facet neighbours: cells sharing a facet (the cell without one node).
    let mut facets: Vec<([u32; 3], u32)> = Vec::with_capacity(n * N);
    for (e, cell) in cells.iter().enumerate() {
        for skip in 0..N {
            let mut key = [u32::MAX; 3];
            let mut k = 0;
            for (a, &v) in cell.iter().enumerate() {
                if a != skip {
                    key[k] = v;
                    k += 1;
                }
            }
            key[..N - 1].sort_unstable();
            facets.push((key, e as u32));
        }
    }
    facets.par_sort_unstable();
    let mut neighbours = vec![Vec::new(); n];
    // Patches stay inside a region: a volume constraint never spans materials.
    for w in facets.windows(2) {
        if w[0].0 == w[1].0 && regions[w[0].1 as usize] == regions[w[1].1 as usize] {
            neighbours[w[0].1 as usize].push(w[1].1);
            neighbours[w[1].1 as usize].push(w[0].1);
        }
    }
    for list in &mut neighbours {
        list.sort_unstable();
    }

    const NONE: u32 = u32::MAX;
    let mut patch_of = vec![NONE; n];
    let mut groups: Vec<Vec<u32>> = Vec::new();
    for seed in 0..n {
        if patch_of[seed] != NONE {
            continue;
        }
        let id = groups.len() as u32;
        let mut members = vec![seed as u32];
        patch_of[seed] = id;
        let mut next = 0;
        while members.len() < target && next < members.len() {
            let c = members[next] as usize;
            for &nb in &neighbours[c] {
                if members.len() >= target {
                    break;
                }
                if patch_of[nb as usize] == NONE {
                    patch_of[nb as usize] = id;
                    members.push(nb);
                }
            }
            next += 1;
        }
        groups.push(members);
    }
    // Small leftovers join their smallest neighbouring patch.
    let small = target.div_ceil(2);
    for g in 0..groups.len() {
        if groups[g].is_empty() || groups[g].len() >= small {
            continue;
        }
        let mut best: Option<(usize, u32)> = None;
        for &c in &groups[g] {
            for &nb in &neighbours[c as usize] {
                let p = patch_of[nb as usize];
                if p as usize == g {
                    continue;
                }
                let size = groups[p as usize].len();
                if best.is_none_or(|(s, q)| (size, p) < (s, q)) {
                    best = Some((size, p));
                }
            }
        }
        if let Some((_, p)) = best {
            let moved = std::mem::take(&mut groups[g]);
            for &c in &moved {
                patch_of[c as usize] = p;
            }
            groups[p as usize].extend(moved);
        }
    }
    let mut groups: Vec<Vec<u32>> = groups.into_iter().filter(|g| !g.is_empty()).collect();
    for g in &mut groups {
        g.sort_unstable();
    }
    groups
}

/// One cell of a patch, as [`respond`] takes it.
pub(crate) struct PatchCell<'a> {
    /// The cell operator `G` (`F - I = G u_e`), `9 x N D`.
    pub op: &'a DMatrix<f64>,
    /// The cell's integration weight [mm^3].
    pub weight: f64,
    /// The patch-local index of each of the cell's nodes.
    pub local: &'a [u8],
    /// The cell's nodal displacements, node-major.
    pub u: DVector<f64>,
}

/// A patch's response.
pub(crate) struct PatchResponse {
    /// Nodal forces, node-major over the patch's nodes.
    pub force: Vec<f64>,
    /// The tangent (empty when not asked for).
    pub stiffness: DMatrix<f64>,
    /// Per cell of the patch: the stress `P(Fbar)` and `Fbar`.
    pub cells: Vec<(Matrix3<f64>, Matrix3<f64>)>,
}

/// A cell's own kinematics.
struct Kinematics {
    h: Matrix3<f64>,
    j: f64,
    j_m1: f64,
    /// `d ln J / du_e` (`N D`).
    dlnj: DVector<f64>,
    /// `d^2 ln J / du_e^2` (with the tangent only).
    hlnj: DMatrix<f64>,
}

fn row_major(m: &Matrix3<f64>) -> DVector<f64> {
    DVector::from_iterator(9, (0..9).map(|r| m[(r / 3, r % 3)]))
}

/// Runs cell `i` of a patch (its index in the patch) at `Fbar = I + hbar`.
pub(crate) type CellUpdate<'a> = dyn FnMut(usize, &Matrix3<f64>) -> Result<PointResponse, LawFailure> + 'a;

/// The responses of one patch's cells at their displacements: `update(i, hbar)`
/// runs cell `i`'s law at `Fbar = I + hbar`. Returns the failing cell's index in
/// the patch and why on failure.
pub(crate) fn respond<const D: usize>(
    num_nodes: usize,
    cells: &[PatchCell<'_>],
    plane_strain: bool,
    update: &mut CellUpdate<'_>,
    with_tangent: bool,
) -> Result<PatchResponse, (usize, LawFailure)> {
    let n = num_nodes * D;
    // Plane strain keeps F_zz = 1: the in-plane block takes the volume change,
    // Fbar_P = (Jbar/J)^(1/2) F_P; otherwise all of F, (Jbar/J)^(1/3).
    let q = if plane_strain { 0.5 } else { 1.0 / 3.0 };
    let scaled = |m: &Matrix3<f64>| {
        let mut m = *m;
        if plane_strain {
            m[(2, 2)] = 0.0;
        }
        m
    };
    let dof = |cell: &PatchCell<'_>, c: usize| cell.local[c / D] as usize * D + c % D;
    let mut kin = Vec::with_capacity(cells.len());
    for (i, cell) in cells.iter().enumerate() {
        let grad = cell.op * &cell.u;
        let h = Matrix3::from_fn(|r, c| grad[3 * r + c]);
        let tr = h.trace();
        let j_m1 = tr + 0.5 * (tr * tr - (h * h).trace()) + h.determinant();
        let j = 1.0 + j_m1;
        let f = Matrix3::identity() + h;
        let inverse = (j > 0.0).then(|| f.try_inverse()).flatten().ok_or((i, LawFailure::Inverted { det: j }))?;
        let dlnj = cell.op.tr_mul(&row_major(&inverse.transpose()));
        let hlnj = if with_tangent {
            // d^2 ln J [dF, dG] = -tr(F^-1 dG F^-1 dF).
            let m = DMatrix::from_fn(9, 9, |r, c| {
                let (i, jj) = (r / 3, r % 3);
                let (k, l) = (c / 3, c % 3);
                -inverse[(jj, k)] * inverse[(l, i)]
            });
            cell.op.tr_mul(&(m * cell.op))
        } else {
            DMatrix::zeros(0, 0)
        };
        kin.push(Kinematics { h, j, j_m1, dlnj, hlnj });
    }
    let total: f64 = cells.iter().map(|c| c.weight).sum();
    let mut jbar_m1 = 0.0;
    let mut djbar = DVector::zeros(n);
    let mut hjbar = if with_tangent { DMatrix::zeros(n, n) } else { DMatrix::zeros(0, 0) };
    for (cell, k) in cells.iter().zip(&kin) {
        let w = cell.weight / total;
        jbar_m1 += w * k.j_m1;
        let m = k.dlnj.len();
        for a in 0..m {
            djbar[dof(cell, a)] += w * k.j * k.dlnj[a];
            if with_tangent {
                for b in 0..m {
                    hjbar[(dof(cell, a), dof(cell, b))] += w * k.j * (k.dlnj[a] * k.dlnj[b] + k.hlnj[(a, b)]);
                }
            }
        }
    }
    let jbar = 1.0 + jbar_m1;
    let dlnjbar = &djbar / jbar;
    let hlnjbar = if with_tangent { &hjbar / jbar - &dlnjbar * dlnjbar.transpose() } else { hjbar };

    let mut force = DVector::zeros(n);
    let mut stiffness = if with_tangent { DMatrix::zeros(n, n) } else { DMatrix::zeros(0, 0) };
    let mut out = Vec::with_capacity(cells.len());
    for (i, (cell, k)) in cells.iter().zip(&kin).enumerate() {
        let m = k.dlnj.len();
        // s - 1 = (Jbar / J)^q - 1 from the differences of J - 1.
        let s_m1 = (((jbar_m1 - k.j_m1) / k.j).ln_1p() * q).exp_m1();
        let s = 1.0 + s_m1;
        let hbar = k.h * s + scaled(&Matrix3::identity()) * s_m1;
        let response = update(i, &hbar).map_err(|e| (i, e))?;
        let p = row_major(&response.stress);
        let f = row_major(&scaled(&(Matrix3::identity() + k.h)));
        let mut kvec = dlnjbar.clone();
        for a in 0..m {
            kvec[dof(cell, a)] -= k.dlnj[a];
        }
        // B = s (G + q F k^T), 9 x n (F's scaled part).
        let mut b = &f * kvec.transpose() * (s * q);
        for a in 0..m {
            let col = dof(cell, a);
            for r in 0..9 {
                b[(r, col)] += s * cell.op[(r, a)];
            }
        }
        force += b.tr_mul(&p) * cell.weight;
        if with_tangent {
            let a = DMatrix::from_iterator(9, 9, response.tangent.iter().copied());
            let mut g: DVector<f64> = DVector::zeros(n);
            let g_cell = cell.op.tr_mul(&p);
            for c in 0..m {
                g[dof(cell, c)] += g_cell[c];
            }
            let pf = p.dot(&f);
            let mut h = hlnjbar.clone();
            for c in 0..m {
                for d in 0..m {
                    h[(dof(cell, c), dof(cell, d))] -= k.hlnj[(c, d)];
                }
            }
            let gk: DMatrix<f64> = &g * kvec.transpose();
            let term = b.tr_mul(&(a * &b))
                + (&gk + gk.transpose()) * (s * q)
                + &kvec * kvec.transpose() * (s * q * q * pf)
                + h * (s * q * pf);
            stiffness += term * cell.weight;
        }
        out.push((response.stress, Matrix3::identity() + hbar));
    }
    Ok(PatchResponse { force: force.as_slice().to_vec(), stiffness, cells: out })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{cell_geometry_in, Formulation};
    use crate::material::law::PointLaw;
    use crate::material::network::{Damper, Energy, Equilibrium, Network, ViscousNetwork};
    use crate::mesh;

    use super::super::network::deformation_operator as operator;

    /// Runs `respond` on every patch of a small mesh at displacement `u` with
    /// `law`, returning the global force and, per patch, the tangent.
    fn patch_forces<const D: usize, const N: usize>(
        m: &crate::mesh::SimplexMesh<D, N>,
        formulation: Formulation,
        patches: &Patches,
        law: &Network,
        u: &[f64],
    ) -> (Vec<f64>, Vec<DMatrix<f64>>)
    where
        crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
    {
        let geometry: Vec<_> = (0..m.num_cells())
            .map(|e| cell_geometry_in::<D, N>(formulation, &m.cell_coordinates(e)).unwrap())
            .collect();
        let ops: Vec<_> = geometry.iter().map(operator::<D, N>).collect();
        let mut forces = Vec::new();
        let mut tangents = Vec::new();
        for (p, group) in patches.cells.iter().enumerate() {
            let cells: Vec<PatchCell<'_>> = group
                .iter()
                .map(|&e| {
                    let e = e as usize;
                    PatchCell {
                        op: &ops[e],
                        weight: geometry[e].weight,
                        local: &patches.local[e],
                        u: DVector::from_iterator(
                            N * D,
                            m.cells[e].iter().flat_map(|&v| (0..D).map(move |k| u[v as usize * D + k])),
                        ),
                    }
                })
                .collect();
            let mut old = vec![0.0; law.history_len()];
            law.initial_history(&mut old);
            let mut new = old.clone();
            let plane_strain = matches!(formulation, Formulation::PlaneStrain { .. });
            let r = respond::<D>(
                patches.nodes[p].len(),
                &cells,
                plane_strain,
                &mut |_, h| law.update(h, 0.1, &old, &mut new),
                true,
            )
            .unwrap();
            if plane_strain {
                assert!(r.cells.iter().all(|(_, f)| f[(2, 2)] == 1.0), "plane strain keeps Fbar_zz = 1");
            }
            forces.push(r.force);
            tangents.push(r.stiffness);
        }
        let mut global = vec![0.0; u.len()];
        patches.assemble_vector::<D>(&forces, &mut global);
        (global, tangents)
    }

    fn material() -> Network {
        Network::new(0.45)
            .with_equilibrium(Equilibrium {
                e_mpa: 0.03,
                energy: Energy::Exponential { stiffening: 0.8 },
                mullins: None,
            })
            .with(ViscousNetwork { e_mpa: 0.05, tau_s: 0.3 })
            .with(Damper { c_mpa_s: 0.01 })
    }

    fn pseudo_random(i: usize) -> f64 {
        let x = (i as f64 * 12.9898 + 78.233).sin() * 43758.5453;
        x - x.floor() - 0.5
    }

    /// The assembled tangent is the central difference of the assembled force
    /// (1e-6 of the tangent's largest entry), on 3D, plane strain and
    /// axisymmetric patches with a viscous network and a damper at 15 % strains.
    #[test]
    fn the_patch_tangent_is_the_derivative_of_the_patch_force() {
        fn check<const D: usize, const N: usize>(m: crate::mesh::SimplexMesh<D, N>, formulation: Formulation)
        where
            crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
        {
            let patches = Patches::new(&m.nodes, &m.cells, &m.cell_regions, patch_size(D));
            assert!(patches.cells.iter().any(|g| g.len() > 1));
            let law = material();
            let u: Vec<f64> = (0..m.num_nodes() * D).map(|i| 0.15 * pseudo_random(i)).collect();
            let (_, tangents) = patch_forces(&m, formulation, &patches, &law, &u);
            let k = patches.assemble_matrix::<D>(&tangents);
            let scale = k.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
            let eps = 1e-6;
            let mut worst: f64 = 0.0;
            for col in 0..u.len() {
                let mut up = u.clone();
                up[col] += eps;
                let mut um = u.clone();
                um[col] -= eps;
                let (fp, _) = patch_forces(&m, formulation, &patches, &law, &up);
                let (fm, _) = patch_forces(&m, formulation, &patches, &law, &um);
                for row in 0..u.len() {
                    let fd = (fp[row] - fm[row]) / (2.0 * eps);
                    let pat = &patches.pattern;
                    let exact = (pat.row_ptr[row]..pat.row_ptr[row + 1])
                        .find(|&q| pat.col_idx[q] as usize == col)
                        .map_or(0.0, |q| k[q]);
                    worst = worst.max((fd - exact).abs());
                }
            }
            assert!(worst <= 1e-6 * scale, "{D}D: tangent off its differences by {:.3e} of its scale", worst / scale);
        }
        check(mesh::block([2.0, 1.0, 1.0], 0.5, "a").unwrap(), Formulation::Solid);
        check(mesh::rectangle(2.0, 1.0, 0.5, "a").unwrap(), Formulation::PlaneStrain { thickness_mm: 1.0 });
        let mut axi = mesh::rectangle(2.0, 1.0, 0.5, "a").unwrap();
        for p in &mut axi.nodes {
            p[0] += 0.5;
        }
        check(axi, Formulation::Axisymmetric);
    }

    /// Patches of one cell are the standard element: the assembled forces agree
    /// to 1e-13 of their largest.
    #[test]
    fn a_patch_of_one_cell_is_the_standard_element() {
        let m = mesh::block([1.0, 1.0, 1.0], 1.0, "a").unwrap();
        let patches = Patches::new(&m.nodes, &m.cells, &m.cell_regions, 1);
        assert_eq!(patches.cells.len(), m.num_cells());
        let law = material();
        let u: Vec<f64> = (0..m.num_nodes() * 3).map(|i| 0.2 * pseudo_random(i)).collect();
        let (f, _) = patch_forces(&m, Formulation::Solid, &patches, &law, &u);
        // The standard element's force.
        let mut standard = vec![0.0; u.len()];
        for e in 0..m.num_cells() {
            let g = cell_geometry_in::<3, 4>(Formulation::Solid, &m.cell_coordinates(e)).unwrap();
            let op = operator(&g);
            let u = &u;
            let ue =
                DVector::from_iterator(12, m.cells[e].iter().flat_map(|&v| (0..3).map(move |k| u[v as usize * 3 + k])));
            let grad = &op * ue;
            let h = Matrix3::from_fn(|i, j| grad[3 * i + j]);
            let mut old = vec![0.0; law.history_len()];
            law.initial_history(&mut old);
            let mut new = old.clone();
            let r = law.update(&h, 0.1, &old, &mut new).unwrap();
            let fe = op.tr_mul(&row_major(&r.stress)) * g.weight;
            for (a, &v) in m.cells[e].iter().enumerate() {
                for k in 0..3 {
                    standard[v as usize * 3 + k] += fe[a * 3 + k];
                }
            }
        }
        let scale = standard.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let worst = f.iter().zip(&standard).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(worst <= 1e-13 * scale, "one-cell patches off the standard element by {:.3e}", worst / scale);
    }

    /// Every cell is in exactly one patch, of one region (a layered block);
    /// no patch is under half the target and the mean is near it; the same
    /// mesh gives the same patches.
    #[test]
    fn patches_partition_the_cells() {
        let layers = [
            mesh::Layer { region: "a".into(), thickness_mm: 1.0 },
            mesh::Layer { region: "b".into(), thickness_mm: 1.0 },
        ];
        let m = mesh::layered_block(3.0, 2.0, &layers, 0.5).unwrap();
        let groups = partition(&m.cells, &m.cell_regions, 4);
        for g in &groups {
            let r = m.cell_regions[g[0] as usize];
            assert!(g.iter().all(|&c| m.cell_regions[c as usize] == r), "a patch spans two regions");
        }
        let mut seen = vec![0u32; m.num_cells()];
        for g in &groups {
            for &c in g {
                seen[c as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        let sizes: Vec<usize> = groups.iter().map(|g| g.len()).collect();
        assert!(sizes.iter().all(|&s| s >= 2), "a patch under half the target");
        let mean = m.num_cells() as f64 / groups.len() as f64;
        assert!(mean >= 3.5, "mean patch size {mean}");
        assert_eq!(groups, partition(&m.cells, &m.cell_regions, 4));
    }
}
