use nalgebra::{Matrix2, Matrix3, SMatrix};

/// The reference simplex with `N = D + 1` nodes in `D` dimensions.
#[derive(Debug, Clone, Copy, Default)]
pub struct Simplex<const D: usize, const N: usize>;

/// What generic kernels need from the concrete reference cells.
pub trait ReferenceSimplex<const D: usize, const N: usize> {
    /// Measure of the reference simplex, `1/D!`.
    const MEASURE_FACTOR: f64;
    /// Determinant and (when non-singular) inverse of a Jacobian.
    fn det_and_inverse(jac: &SMatrix<f64, D, D>) -> (f64, Option<SMatrix<f64, D, D>>);
}

impl ReferenceSimplex<2, 3> for Simplex<2, 3> {
    const MEASURE_FACTOR: f64 = 0.5;
    fn det_and_inverse(jac: &Matrix2<f64>) -> (f64, Option<Matrix2<f64>>) {
        (jac.determinant(), jac.try_inverse())
    }
}

impl ReferenceSimplex<3, 4> for Simplex<3, 4> {
    const MEASURE_FACTOR: f64 = 1.0 / 6.0;
    fn det_and_inverse(jac: &Matrix3<f64>) -> (f64, Option<Matrix3<f64>>) {
        (jac.determinant(), jac.try_inverse())
    }
}

/// The Jacobian of the map from the reference simplex: column `i` is `x_(i+1) - x_0`.
pub fn jacobian<const D: usize, const N: usize>(x: &[[f64; D]; N]) -> SMatrix<f64, D, D> {
    const { assert!(N == D + 1) };
    SMatrix::<f64, D, D>::from_fn(|k, i| x[i + 1][k] - x[0][k])
}

/// Signed measure (area, volume) of a simplex [mm^D]; positive in VTK order.
pub fn signed_measure<const D: usize, const N: usize>(x: &[[f64; D]; N]) -> f64
where
    Simplex<D, N>: ReferenceSimplex<D, N>,
{
    <Simplex<D, N> as ReferenceSimplex<D, N>>::det_and_inverse(&jacobian(x)).0
        * <Simplex<D, N> as ReferenceSimplex<D, N>>::MEASURE_FACTOR
}

/// Facet `i` of a positively oriented cell (the facet opposite node `i`), with its
/// nodes ordered so that its normal points out of the cell.
pub fn outward_facet<const D: usize, const N: usize>(cell: &[u32; N], i: usize) -> [u32; D] {
    const { assert!(N == D + 1) };
    let mut f = [0u32; D];
    let mut k = 0;
    for (j, &v) in cell.iter().enumerate() {
        if j != i {
            f[k] = v;
            k += 1;
        }
    }
    // Dropping node i leaves the facet in the order of an outward normal for even
    // i and of an inward one for odd i (2D: edges (1,2), (2,0), (0,1) are the
    // counter-clockwise ones; 3D: faces (1,2,3), (0,3,2), (0,1,3), (0,2,1)).
    if i % 2 == 1 {
        f.swap(D - 2, D - 1);
    }
    f
}
