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
//! dimension bounds.

mod constitutive;
mod simplex;

pub use constitutive::{unit_young_matrix, Formulation};
pub use simplex::{jacobian, outward_facet, signed_measure, ReferenceSimplex, Simplex};

use nalgebra::{SMatrix, SVector};

/// Per-cell geometry for P1 kernels: barycentric gradients and the integration weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellGeometry<const D: usize, const N: usize> {
    /// Row `a` is the gradient of shape function `a` [1/mm].
    pub gradients: SMatrix<f64, N, D>,
    /// Measure times the out-of-plane thickness in 2D [mm^3].
    pub weight: f64,
}

/// Barycentric gradients and signed measure of a simplex, or `Err(measure)` when
/// the simplex is inverted or degenerate.
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
    Ok(CellGeometry { gradients, weight: measure * thickness })
}

/// The strain-displacement block of node `a`: `e = sum_a B_a u_a`.
#[inline]
pub fn strain_block<const D: usize, const N: usize, const S: usize>(
    gradients: &SMatrix<f64, N, D>,
    a: usize,
) -> SMatrix<f64, S, D> {
    const { assert!(S == D * (D + 1) / 2, "S must count the symmetric strain components") };
    let mut b = SMatrix::<f64, S, D>::zeros();
    for k in 0..D {
        b[(k, k)] = gradients[(a, k)];
    }
    let mut row = D;
    for i in 0..D {
        for j in i + 1..D {
            b[(row, i)] = gradients[(a, j)];
            b[(row, j)] = gradients[(a, i)];
            row += 1;
        }
    }
    b
}

/// The (constant) strain of a cell from its nodal displacements.
#[inline]
pub fn cell_strain<const D: usize, const N: usize, const S: usize>(
    gradients: &SMatrix<f64, N, D>,
    u: &[SVector<f64, D>; N],
) -> SVector<f64, S> {
    const { assert!(S == D * (D + 1) / 2) };
    // Displacement gradient H = sum_a u_a (grad N_a)^T.
    let mut h = SMatrix::<f64, D, D>::zeros();
    for a in 0..N {
        for i in 0..D {
            for j in 0..D {
                h[(i, j)] += u[a][i] * gradients[(a, j)];
            }
        }
    }
    let mut e = SVector::<f64, S>::zeros();
    for k in 0..D {
        e[k] = h[(k, k)];
    }
    let mut row = D;
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

    #[test]
    fn measures_of_reference_cells() {
        let tri = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!((signed_measure::<2, 3>(&tri) - 0.5).abs() < 1e-15);
        let tet = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!((signed_measure::<3, 4>(&tet) - 1.0 / 6.0).abs() < 1e-15);
        assert!(cell_geometry::<3, 4>(&[tet[0], tet[2], tet[1], tet[3]], 1.0).is_err());
    }
}
