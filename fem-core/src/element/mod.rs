//! Element kernels, written once for triangles and tetrahedra.
//!
//! Linear simplices (P1): the shape functions are the barycentric coordinates, so
//! gradients, strains and stresses are constant per cell. Strains use Voigt order
//! `[xx, yy, (zz), xy, (xz, yz)]` with engineering shears: for D = 2 `[xx, yy, xy]`,
//! for D = 3 `[xx, yy, zz, xy, xz, yz]`. Kernels are free functions, inputs first.
//!
//! Generic code is parameterised by `<const D, const N, const S>` (dimension, nodes
//! per cell, strain components); the determinant and inverse live in the two
//! concrete [`ReferenceSimplex`] impls so that generic code needs no nalgebra
//! dimension bounds. The formulations ([`Formulation`]) and their `<D, N, S>`:
//!
//! | formulation                         | cells      | `D, N, S`   | strain (Voigt)               | weight `w` of a cell |
//! |-------------------------------------|------------|-------------|------------------------------|----------------------|
//! | [`Formulation::Solid`]              | tetrahedra | `3, 4, 6`   | `[xx, yy, zz, xy, xz, yz]`   | volume `V`           |
//! | [`Formulation::PlaneStress`]/`Strain` | triangles | `2, 3, 3`  | `[xx, yy, xy]`               | area `A` x thickness `t` |
//! | [`Formulation::Axisymmetric`]       | triangles  | `2, 3, 4`   | `[rr, yy, θθ, ry]`           | `2π r_c A`           |
//!
//! ## Axisymmetric triangles
//!
//! The specimen is a body of revolution about the y axis; a triangle lives in the
//! `r-y` half-plane (`r = x >= 0`) and stands for the ring it sweeps. The
//! displacement is `(u_r, u_y)`, independent of the angle θ (torsionless). Its
//! strain has one more component than plane strain's, the hoop strain
//! `e_θθ = u_r / r`, so the strain-displacement block of node `a` is
//!
//! ```text
//!         | dN_a/dr      0     |   e_rr
//!   B_a = |    0      dN_a/dy  |   e_yy
//!         | N_a/r        0     |   e_θθ
//!         | dN_a/dy   dN_a/dr  |   e_ry (engineering shear)
//! ```
//!
//! Integrals over the ring are `int_ring f dV = int_A f 2π r dA`. One-point
//! (centroid) quadrature is the standard choice for linear triangles: `N_a/r` is
//! evaluated at the centroid, where `N_a = 1/3` and `r = r_c` (the mean of the
//! nodes' radii), and the weight becomes `w = 2π r_c A`. The rule integrates the
//! terms of `K` that are linear in `r` exactly, so a uniform stress state with
//! `s_rr = s_θθ` (the axisymmetric patch test: `u_r = a r`, `u_y = c + d y`) is
//! reproduced exactly; `e_θθ` is exact for `u_r = a r`. A triangle of positive
//! area in `r >= 0` has `r_c > 0`, so cells touching the axis are fine. Forces
//! are full-circle forces (the `2π r` weight). The material matrix is the 3D
//! isotropic one restricted to `[rr, yy, θθ, ry]` ([`unit_young_matrix`]).
//! The shape data the hoop row needs travel in [`CellGeometry::gradients`]
//! ([`ShapeGradients::hoop`], zero for the other formulations), so that
//! [`strain_block`], [`cell_strain`], [`nodal_force`] and [`stiffness_block`]
//! serve every formulation with one signature.

mod constitutive;
mod finite;
mod simplex;

pub use constitutive::{unit_young_matrix, Formulation};
pub use finite::{displacement_gradient, geometric_block, green_lagrange_block, green_lagrange_strain};
pub use simplex::{jacobian, outward_facet, signed_measure, ReferenceSimplex, Simplex};

use nalgebra::{SMatrix, SVector};

/// Whether `S` strain components fit a `D`-dimensional formulation: `D (D + 1)/2`
/// (plane, solid) or, for `D = 2`, 4 (axisymmetric: the hoop strain added).
pub const fn valid_strain_size(dim: usize, num_strains: usize) -> bool {
    num_strains == dim * (dim + 1) / 2 || (dim == 2 && num_strains == 4)
}

/// What the strain-displacement operator `B` of a P1 cell needs: the gradients of
/// the shape functions and, for the axisymmetric formulation, the shape functions
/// over the radius at the quadrature point (the hoop row). At the centroid, the
/// one quadrature point, every `N_a` is `1/N`, so the hoop row is one number.
///
/// Dereferences to the gradient matrix, so `g[(a, k)]` is `dN_a/dx_k`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeGradients<const D: usize, const N: usize> {
    /// Row `a` is the gradient of shape function `a` [1/mm].
    pub grad: SMatrix<f64, N, D>,
    /// `N_a / r` at the centroid, the same for every node `a`: `1 / (N r_c)` [1/mm].
    /// The hoop row of the axisymmetric `B`, `e_θθ = hoop * sum_a u_r,a`; zero for
    /// the other formulations.
    pub hoop: f64,
}

impl<const D: usize, const N: usize> ShapeGradients<D, N> {
    /// Gradients with no hoop row (plane and solid formulations).
    pub fn planar(grad: SMatrix<f64, N, D>) -> Self {
        Self { grad, hoop: 0.0 }
    }
}

impl<const D: usize, const N: usize> std::ops::Deref for ShapeGradients<D, N> {
    type Target = SMatrix<f64, N, D>;
    fn deref(&self) -> &Self::Target {
        &self.grad
    }
}

/// Per-cell geometry for P1 kernels: shape gradients (and the hoop row) and the
/// integration weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellGeometry<const D: usize, const N: usize> {
    /// The shape gradients [1/mm] (row `a`: shape function `a`) and, axisymmetric
    /// only, the hoop row `N_a / r` at the centroid [1/mm].
    pub gradients: ShapeGradients<D, N>,
    /// The cell's integration weight: volume in 3D [mm^3], area times the
    /// out-of-plane thickness in plane 2D [mm^3], `2π r_c` times the area for
    /// axisymmetric cells [mm^3].
    pub weight: f64,
}

/// Barycentric gradients and signed measure of a simplex, or `Err(measure)` when
/// the simplex is inverted or degenerate. The weight is the measure times
/// `thickness` (1 in 3D); there is no hoop row (see [`cell_geometry_in`]).
pub fn cell_geometry<const D: usize, const N: usize>(
    x: &[[f64; D]; N],
    thickness: f64,
) -> Result<CellGeometry<D, N>, f64>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    let jac = jacobian(x);
    let (det, inv) = <Simplex<D, N> as ReferenceSimplex<D, N>>::det_and_inverse(&jac);
    let measure = det * <Simplex<D, N> as ReferenceSimplex<D, N>>::MEASURE_FACTOR;
    // Relative degeneracy guard: a cell whose measure is tiny against its edge lengths.
    let scale = (0..D).map(|i| jac.column(i).norm()).fold(1.0f64, |a, b| a * b);
    if !(measure > 1e-14 * scale * <Simplex<D, N> as ReferenceSimplex<D, N>>::MEASURE_FACTOR) {
        return Err(measure);
    }
    let inv = inv.expect("a cell of positive measure has an invertible Jacobian");
    // grad(lambda_i) for i >= 1 are the rows of J^-1; lambda_0 = 1 - sum.
    let mut gradients = SMatrix::<f64, N, D>::zeros();
    for i in 0..D {
        for k in 0..D {
            gradients[(i + 1, k)] = inv[(i, k)];
            gradients[(0, k)] -= inv[(i, k)];
        }
    }
    Ok(CellGeometry { gradients: ShapeGradients::planar(gradients), weight: measure * thickness })
}

/// The geometry of a cell in `formulation`: [`cell_geometry`] with the
/// formulation's thickness for solid and plane cells; for an axisymmetric
/// triangle (`x[a][0]` the radius) the weight `2π r_c A` and the hoop row
/// `N_a(centroid) / r_c = 1 / (3 r_c)` (one-point quadrature, see the module docs).
/// `Err` carries the (signed) measure of an inverted or degenerate cell, or the
/// weight of an axisymmetric cell that does not lie in `r > 0`.
pub fn cell_geometry_in<const D: usize, const N: usize>(
    formulation: Formulation,
    x: &[[f64; D]; N],
) -> Result<CellGeometry<D, N>, f64>
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    match formulation {
        Formulation::Axisymmetric => {
            assert!(D == 2, "the axisymmetric formulation is two-dimensional (r, y)");
            let mut g = cell_geometry::<D, N>(x, 1.0)?;
            let r_c = x.iter().map(|p| p[0]).sum::<f64>() / N as f64;
            let weight = std::f64::consts::TAU * r_c * g.weight;
            if !(r_c > 0.0) {
                return Err(weight);
            }
            g.weight = weight;
            g.gradients.hoop = 1.0 / (N as f64 * r_c);
            Ok(g)
        }
        _ => cell_geometry::<D, N>(x, formulation.thickness()),
    }
}

/// Whether `<D, S>` is the axisymmetric layout (the hoop strain at index `D`).
const fn has_hoop(dim: usize, num_strains: usize) -> bool {
    dim == 2 && num_strains == 4
}

/// The strain-displacement block of node `a`: `e = sum_a B_a u_a`. For `D = 2, S = 4`
/// (axisymmetric) row 2 is the hoop row `[N_a / r, 0]` (module docs).
#[inline]
pub fn strain_block<const D: usize, const N: usize, const S: usize>(
    gradients: &ShapeGradients<D, N>,
    a: usize,
) -> SMatrix<f64, S, D> {
    const { assert!(valid_strain_size(D, S), "S must count the strain components of a formulation") };
    let mut b = SMatrix::<f64, S, D>::zeros();
    for k in 0..D {
        b[(k, k)] = gradients.grad[(a, k)];
    }
    let mut row = D;
    if has_hoop(D, S) {
        b[(row, 0)] = gradients.hoop;
        row += 1;
    }
    for i in 0..D {
        for j in i + 1..D {
            b[(row, i)] = gradients.grad[(a, j)];
            b[(row, j)] = gradients.grad[(a, i)];
            row += 1;
        }
    }
    b
}

/// The (constant) strain of a cell from its nodal displacements.
#[inline]
pub fn cell_strain<const D: usize, const N: usize, const S: usize>(
    gradients: &ShapeGradients<D, N>,
    u: &[SVector<f64, D>; N],
) -> SVector<f64, S> {
    const { assert!(valid_strain_size(D, S), "S must count the strain components of a formulation") };
    // Displacement gradient H = sum_a u_a (grad N_a)^T.
    let mut h = SMatrix::<f64, D, D>::zeros();
    for a in 0..N {
        for i in 0..D {
            for j in 0..D {
                h[(i, j)] += u[a][i] * gradients.grad[(a, j)];
            }
        }
    }
    let mut e = SVector::<f64, S>::zeros();
    for k in 0..D {
        e[k] = h[(k, k)];
    }
    let mut row = D;
    if has_hoop(D, S) {
        e[row] = gradients.hoop * (0..N).map(|a| u[a][0]).sum::<f64>();
        row += 1;
    }
    for i in 0..D {
        for j in i + 1..D {
            e[row] = h[(i, j)] + h[(j, i)];
            row += 1;
        }
    }
    e
}

/// Nodal force of node `a` from a cell stress: `f_a = w B_a^T s`.
#[inline]
pub fn nodal_force<const D: usize, const N: usize, const S: usize>(
    geometry: &CellGeometry<D, N>,
    stress: &SVector<f64, S>,
    a: usize,
) -> SVector<f64, D> {
    strain_block::<D, N, S>(&geometry.gradients, a).transpose() * stress * geometry.weight
}

/// The stiffness block `K_ab = w B_a^T C B_b` of a cell.
#[inline]
pub fn stiffness_block<const D: usize, const N: usize, const S: usize>(
    geometry: &CellGeometry<D, N>,
    c: &SMatrix<f64, S, S>,
    a: usize,
    b: usize,
) -> SMatrix<f64, D, D> {
    let ba = strain_block::<D, N, S>(&geometry.gradients, a);
    let bb = strain_block::<D, N, S>(&geometry.gradients, b);
    ba.transpose() * (c * bb) * geometry.weight
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn tet_points() -> impl Strategy<Value = [[f64; 3]; 4]> {
        prop::array::uniform4(prop::array::uniform3(-1.0f64..1.0))
            .prop_filter("non-degenerate", |x| signed_measure::<3, 4>(x).abs() > 1e-2)
            .prop_map(|mut x| {
                if signed_measure::<3, 4>(&x) < 0.0 {
                    x.swap(2, 3);
                }
                x
            })
    }

    fn tri_points() -> impl Strategy<Value = [[f64; 2]; 3]> {
        prop::array::uniform3(prop::array::uniform2(-1.0f64..1.0))
            .prop_filter("non-degenerate", |x| signed_measure::<2, 3>(x).abs() > 1e-2)
            .prop_map(|mut x| {
                if signed_measure::<2, 3>(&x) < 0.0 {
                    x.swap(1, 2);
                }
                x
            })
    }

    fn element_matrix<const D: usize, const N: usize, const S: usize>(
        g: &CellGeometry<D, N>,
        c: &SMatrix<f64, S, S>,
    ) -> nalgebra::DMatrix<f64> {
        let mut k = nalgebra::DMatrix::zeros(D * N, D * N);
        for a in 0..N {
            for b in 0..N {
                let kab = stiffness_block::<D, N, S>(g, c, a, b);
                for i in 0..D {
                    for j in 0..D {
                        k[(a * D + i, b * D + j)] = kab[(i, j)];
                    }
                }
            }
        }
        k
    }

    /// Rigid motions lie in the stiffness null space; K is symmetric; the gradients
    /// sum to zero (partition of unity) and reproduce linear fields.
    fn check_invariants<const D: usize, const N: usize, const S: usize>(x: &[[f64; D]; N], c: &SMatrix<f64, S, S>)
    where
        Simplex<D, N>: ReferenceSimplex<D, N>,
    {
        let g = cell_geometry::<D, N>(x, 1.0).unwrap();
        for k in 0..D {
            let s: f64 = (0..N).map(|a| g.gradients[(a, k)]).sum();
            assert!(s.abs() < 1e-10, "partition of unity: {s}");
        }
        let km = element_matrix::<D, N, S>(&g, c);
        assert!((&km - km.transpose()).amax() < 1e-10 * km.amax());
        // Translations and infinitesimal rotations.
        let mut modes: Vec<nalgebra::DVector<f64>> = Vec::new();
        for k in 0..D {
            modes.push(nalgebra::DVector::from_fn(D * N, |i, _| if i % D == k { 1.0 } else { 0.0 }));
        }
        for i in 0..D {
            for j in i + 1..D {
                modes.push(nalgebra::DVector::from_fn(D * N, |r, _| {
                    let (a, comp) = (r / D, r % D);
                    if comp == i {
                        -x[a][j]
                    } else if comp == j {
                        x[a][i]
                    } else {
                        0.0
                    }
                }));
            }
        }
        for m in modes {
            let f = &km * m;
            assert!(f.amax() < 1e-9 * km.amax(), "rigid mode gives force {}", f.amax());
        }
    }

    proptest! {
        #[test]
        fn tet_kernel_invariants(x in tet_points(), nu in -0.9f64..0.49) {
            check_invariants::<3, 4, 6>(&x, &unit_young_matrix::<6>(Formulation::Solid, nu));
        }

        #[test]
        fn tri_kernel_invariants(x in tri_points(), nu in -0.9f64..0.49) {
            check_invariants::<2, 3, 3>(&x, &unit_young_matrix::<3>(Formulation::PlaneStress { thickness_mm: 2.0 }, nu));
            check_invariants::<2, 3, 3>(&x, &unit_young_matrix::<3>(Formulation::PlaneStrain { thickness_mm: 2.0 }, nu));
        }

        /// Patch test at the kernel level: a linear displacement field gives its exact
        /// constant strain in any cell.
        #[test]
        fn linear_field_gives_exact_strain(x in tet_points(), h in prop::array::uniform9(-1.0f64..1.0)) {
            let g = cell_geometry::<3, 4>(&x, 1.0).unwrap();
            let grad = nalgebra::Matrix3::from_row_slice(&h);
            let u = x.map(|p| grad * nalgebra::Vector3::from(p));
            let e = cell_strain::<3, 4, 6>(&g.gradients, &u);
            let expected = [grad[(0,0)], grad[(1,1)], grad[(2,2)], grad[(0,1)] + grad[(1,0)], grad[(0,2)] + grad[(2,0)], grad[(1,2)] + grad[(2,1)]];
            for k in 0..6 {
                prop_assert!((e[k] - expected[k]).abs() < 1e-9);
            }
        }
    }

    /// Triangles in the half-plane r = x > 0 (some touching the axis r = 0).
    fn axisymmetric_points() -> impl Strategy<Value = [[f64; 2]; 3]> {
        prop::array::uniform3((0.0f64..2.0, -1.0f64..1.0).prop_map(|(r, y)| [if r < 0.2 { 0.0 } else { r }, y]))
            .prop_filter("non-degenerate", |x| signed_measure::<2, 3>(x).abs() > 1e-2)
            .prop_map(|mut x| {
                if signed_measure::<2, 3>(&x) < 0.0 {
                    x.swap(1, 2);
                }
                x
            })
    }

    fn axisymmetric(x: &[[f64; 2]; 3]) -> CellGeometry<2, 3> {
        cell_geometry_in::<2, 3>(Formulation::Axisymmetric, x).unwrap()
    }

    proptest! {
        /// Axisymmetric kernel: K symmetric; a rigid translation along the axis (y)
        /// gives no force; a translation in r is not rigid: it stretches the hoop by
        /// `1 / r_c`.
        #[test]
        fn axisymmetric_kernel_invariants(x in axisymmetric_points(), nu in -0.9f64..0.49) {
            let g = axisymmetric(&x);
            let c = unit_young_matrix::<4>(Formulation::Axisymmetric, nu);
            let km = element_matrix::<2, 3, 4>(&g, &c);
            prop_assert!((&km - km.transpose()).amax() < 1e-12 * km.amax());
            let along_y = nalgebra::DVector::from_fn(6, |i, _| if i % 2 == 1 { 1.0 } else { 0.0 });
            prop_assert!((&km * along_y).amax() < 1e-12 * km.amax());
            let along_r = [SVector::<f64, 2>::new(1.0, 0.0); 3];
            let r_c = (x[0][0] + x[1][0] + x[2][0]) / 3.0;
            let e = cell_strain::<2, 3, 4>(&g.gradients, &along_r);
            prop_assert!((e - SVector::<f64, 4>::new(0.0, 0.0, 1.0 / r_c, 0.0)).amax() < 1e-12 / r_c);
            // The weight is 2 pi r_c A.
            let w = std::f64::consts::TAU * r_c * signed_measure::<2, 3>(&x);
            prop_assert!((g.weight - w).abs() < 1e-14 * w);
        }

        /// A uniform radial expansion `u_r = a r` (with any axial stretch `u_y = c + d y`)
        /// gives the exact strain `(a, d, a, 0)`; `e = sum_a B_a u_a` agrees with
        /// `cell_strain` for any nodal displacement.
        #[test]
        fn axisymmetric_strain_is_exact_for_radial_expansion(
            x in axisymmetric_points(),
            (a, c, d) in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            u in prop::array::uniform6(-1.0f64..1.0),
        ) {
            let g = axisymmetric(&x);
            let field = x.map(|p| SVector::<f64, 2>::new(a * p[0], c + d * p[1]));
            let e = cell_strain::<2, 3, 4>(&g.gradients, &field);
            let expected = [a, d, a, 0.0];
            for k in 0..4 {
                prop_assert!((e[k] - expected[k]).abs() < 1e-12, "component {}: {} != {}", k, e[k], expected[k]);
            }
            let nodal: [SVector<f64, 2>; 3] = std::array::from_fn(|n| SVector::<f64, 2>::new(u[2 * n], u[2 * n + 1]));
            let via_b: SVector<f64, 4> = (0..3).map(|n| strain_block::<2, 3, 4>(&g.gradients, n) * nodal[n]).sum();
            prop_assert!((via_b - cell_strain::<2, 3, 4>(&g.gradients, &nodal)).amax() < 1e-12);
        }
    }

    /// The axisymmetric patch test: on a distorted mesh of the section `[0, 2] x [0, 2]`
    /// (cells touching the axis included), boundary values of `u_r = a r`,
    /// `u_y = c + d y` (uniform stress with `s_rr = s_θθ`, in equilibrium without body
    /// force) give the same field at every interior node, to round-off (1e-12 of the
    /// field's size). Centroid quadrature integrates every term of the interior rows
    /// exactly for this field (they are linear in r per cell).
    #[test]
    fn axisymmetric_patch_test() {
        let mut m = crate::mesh::rectangle(2.0, 2.0, 0.4, "m").unwrap();
        let on_boundary = |p: &[f64; 2]| p.iter().any(|c| !(1e-9..=2.0 - 1e-9).contains(c));
        for (i, p) in m.nodes.iter_mut().enumerate() {
            if !on_boundary(p) {
                // Up to 0.1 of the 0.4 spacing along each axis: no cell inverts.
                p[0] += 0.04 * ((i * 7919) % 11) as f64 / 5.0 - 0.04;
                p[1] += 0.04 * ((i * 104729) % 13) as f64 / 6.0 - 0.04;
            }
        }
        m.validate().unwrap();
        let (a, c, d) = (0.013, -0.2, -0.031);
        let exact = |p: &[f64; 2]| [a * p[0], c + d * p[1]];
        let nu = 0.3746;
        let cm = unit_young_matrix::<4>(Formulation::Axisymmetric, nu);
        let n = m.num_nodes() * 2;
        let mut k = nalgebra::DMatrix::<f64>::zeros(n, n);
        for (e, cell) in m.cells.iter().enumerate() {
            let g = axisymmetric(&m.cell_coordinates(e));
            for (ia, &va) in cell.iter().enumerate() {
                for (ib, &vb) in cell.iter().enumerate() {
                    let kab = stiffness_block::<2, 3, 4>(&g, &cm, ia, ib);
                    for i in 0..2 {
                        for j in 0..2 {
                            k[(va as usize * 2 + i, vb as usize * 2 + j)] += kab[(i, j)];
                        }
                    }
                }
            }
        }
        let free: Vec<usize> = (0..n).filter(|&dof| !on_boundary(&m.nodes[dof / 2])).collect();
        let held: Vec<usize> = (0..n).filter(|&dof| on_boundary(&m.nodes[dof / 2])).collect();
        let value = |dof: usize| exact(&m.nodes[dof / 2])[dof % 2];
        let kff = nalgebra::DMatrix::from_fn(free.len(), free.len(), |i, j| k[(free[i], free[j])]);
        let rhs = nalgebra::DVector::from_fn(free.len(), |i, _| {
            -held.iter().map(|&h| k[(free[i], h)] * value(h)).sum::<f64>()
        });
        let u = kff.cholesky().expect("SPD with the boundary held").solve(&rhs);
        let worst = free.iter().zip(u.iter()).map(|(&dof, &ui)| (ui - value(dof)).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-12 * c.abs().max(2.0 * a.abs()), "patch test error {worst:e}");
        // And the cells carry the exact strain.
        for e in 0..m.num_cells() {
            let g = axisymmetric(&m.cell_coordinates(e));
            let ue = m.cells[e].map(|v| SVector::<f64, 2>::from(exact(&m.nodes[v as usize])));
            let s = cell_strain::<2, 3, 4>(&g.gradients, &ue);
            assert!((s - SVector::<f64, 4>::new(a, d, a, 0.0)).amax() < 1e-12);
        }
    }

    #[test]
    fn measures_of_reference_cells() {
        let tri = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!((signed_measure::<2, 3>(&tri) - 0.5).abs() < 1e-15);
        let tet = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!((signed_measure::<3, 4>(&tet) - 1.0 / 6.0).abs() < 1e-15);
        assert!(cell_geometry::<3, 4>(&[tet[0], tet[2], tet[1], tet[3]], 1.0).is_err());
    }
}
