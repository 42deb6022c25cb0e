//! Finite-strain kinematics of P1 cells (total Lagrangian), for the
//! `finite-strain` effect ([`crate::effects`]).
//!
//! With the displacement gradient `H = grad u` (constant per cell) the
//! Green-Lagrange strain is `E = 1/2 (H + H^T + H^T H)`; the effect blends its
//! quadratic part in, `E_b = eps + b 1/2 H^T H` with `b` in [0, 1] (`b = 1`:
//! Green-Lagrange), in the Voigt order and engineering shears of
//! [`super::cell_strain`]. The axisymmetric hoop strain becomes
//! `e_tt + b e_tt^2 / 2` (`e_tt = u_r / r` at the centroid: the hoop stretch is
//! `1 + e_tt`). The internal force of node `a` is `w B_a(u)^T S` with the second
//! Piola-Kirchhoff stress `S` and `B_a(u) = dE_b/du_a` ([`green_lagrange_block`]),
//! on the reference weight `w`; the tangent adds the geometric stiffness
//! `b w (G_a^T S G_b) I` (plus `b w hoop^2 S_tt` in the `r-r` entry), with `G_a` the
//! reference gradient of shape function `a` ([`geometric_block`]). At `b = 0`
//! every function returns the small-strain one's values exactly.
//!
//! **Limit in compression.** The chain is linear in `E_b` (Saint Venant-Kirchhoff
//! at `b = 1`), so the nominal stress of uniaxial compression, `E (1 + b eps)
//! (eps + b eps^2/2)`, peaks at `eps = -(1 - 1/sqrt 3)/b` (42.3 % at `b = 1`) and
//! falls beyond. Between frictionless plates the homogeneous branch goes on past
//! it; between glued plates the compression localises into a few cells, which
//! invert (a typed `Inverted` error: the fungi-steak cylinder at 46 %, earlier on
//! finer meshes), and no step or mesh size cures that (fem-core's test
//! `finite_strain_on_the_fungi_cylinder_at_half_height`).

use nalgebra::{SMatrix, SVector};

use super::{has_hoop, valid_strain_size, ShapeGradients};

/// The displacement gradient `H = sum_a u_a (grad N_a)^T` of a cell and, for the
/// axisymmetric layout, its hoop strain `u_r / r` (0 otherwise).
pub fn displacement_gradient<const D: usize, const N: usize, const S: usize>(
    gradients: &ShapeGradients<D, N>,
    u: &[SVector<f64, D>; N],
) -> (SMatrix<f64, D, D>, f64) {
    let mut h = SMatrix::<f64, D, D>::zeros();
    for a in 0..N {
        for i in 0..D {
            for j in 0..D {
                h[(i, j)] += u[a][i] * gradients.grad[(a, j)];
            }
        }
    }
    let hoop = if has_hoop(D, S) { gradients.hoop * (0..N).map(|a| u[a][0]).sum::<f64>() } else { 0.0 };
    (h, hoop)
}

/// The blended Green-Lagrange strain `eps + b 1/2 H^T H` (Voigt, engineering shears).
pub fn green_lagrange_strain<const D: usize, const N: usize, const S: usize>(
    gradients: &ShapeGradients<D, N>,
    u: &[SVector<f64, D>; N],
    blend: f64,
) -> SVector<f64, S> {
    const { assert!(valid_strain_size(D, S), "S must count the strain components of a formulation") };
    let (h, hoop) = displacement_gradient::<D, N, S>(gradients, u);
    // C = H^T H.
    let c = h.transpose() * h;
    let mut e = SVector::<f64, S>::zeros();
    for k in 0..D {
        e[k] = h[(k, k)] + blend * (0.5 * c[(k, k)]);
    }
    let mut row = D;
    if has_hoop(D, S) {
        e[row] = hoop + blend * (0.5 * hoop * hoop);
        row += 1;
    }
    for i in 0..D {
        for j in i + 1..D {
            e[row] = (h[(i, j)] + h[(j, i)]) + blend * c[(i, j)];
            row += 1;
        }
    }
    e
}

/// `B_a(u) = dE_b / du_a` for the gradient `h` and hoop strain `hoop_strain` of
/// [`displacement_gradient`]: the small-strain block of [`super::strain_block`] plus
/// `b` times the derivative of `1/2 H^T H`.
pub fn green_lagrange_block<const D: usize, const N: usize, const S: usize>(
    gradients: &ShapeGradients<D, N>,
    h: &SMatrix<f64, D, D>,
    hoop_strain: f64,
    blend: f64,
    a: usize,
) -> SMatrix<f64, S, D> {
    let g = |i: usize| gradients.grad[(a, i)];
    let delta = |i: usize, j: usize| if i == j { 1.0 } else { 0.0 };
    let mut b = SMatrix::<f64, S, D>::zeros();
    for i in 0..D {
        for k in 0..D {
            // d(1/2 sum_m H_mi^2)/du_ak = H_ki G_ai.
            b[(i, k)] = g(i) * (delta(k, i) + blend * h[(k, i)]);
        }
    }
    let mut row = D;
    if has_hoop(D, S) {
        b[(row, 0)] = gradients.hoop * (1.0 + blend * hoop_strain);
        row += 1;
    }
    for i in 0..D {
        for j in i + 1..D {
            for k in 0..D {
                // d(sum_m H_mi H_mj)/du_ak = G_ai H_kj + H_ki G_aj.
                b[(row, k)] = (g(j) * delta(k, i) + g(i) * delta(k, j)) + blend * (g(i) * h[(k, j)] + h[(k, i)] * g(j));
            }
            row += 1;
        }
    }
    b
}

/// The stress `s` (Voigt) as a symmetric `D x D` matrix (no hoop entry).
fn stress_matrix<const D: usize, const S: usize>(s: &SVector<f64, S>) -> SMatrix<f64, D, D> {
    let mut m = SMatrix::<f64, D, D>::zeros();
    for k in 0..D {
        m[(k, k)] = s[k];
    }
    let mut row = if has_hoop(D, S) { D + 1 } else { D };
    for i in 0..D {
        for j in i + 1..D {
            m[(i, j)] = s[row];
            m[(j, i)] = s[row];
            row += 1;
        }
    }
    m
}

/// The geometric stiffness block of nodes `a`, `b` for the stress `s`, without
/// the weight: `b (G_a^T S G_b) I` plus `b hoop^2 S_tt` in the `r-r` entry.
pub fn geometric_block<const D: usize, const N: usize, const S: usize>(
    gradients: &ShapeGradients<D, N>,
    s: &SVector<f64, S>,
    blend: f64,
    a: usize,
    b: usize,
) -> SMatrix<f64, D, D> {
    let m = stress_matrix::<D, S>(s);
    let ga = SVector::<f64, D>::from_fn(|i, _| gradients.grad[(a, i)]);
    let gb = SVector::<f64, D>::from_fn(|i, _| gradients.grad[(b, i)]);
    let mut k = SMatrix::<f64, D, D>::identity() * (blend * ga.dot(&(m * gb)));
    if has_hoop(D, S) {
        k[(0, 0)] += blend * gradients.hoop * gradients.hoop * s[D];
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{cell_geometry, cell_geometry_in, cell_strain, strain_block, Formulation};

    fn tet() -> crate::element::CellGeometry<3, 4> {
        cell_geometry::<3, 4>(&[[0.0, 0.0, 0.0], [1.2, 0.1, 0.0], [0.2, 0.9, 0.1], [0.1, 0.3, 1.1]], 1.0).unwrap()
    }

    fn displacement() -> [SVector<f64, 3>; 4] {
        [
            SVector::from([0.01, -0.02, 0.03]),
            SVector::from([0.15, -0.05, 0.02]),
            SVector::from([-0.04, -0.2, 0.07]),
            SVector::from([0.05, 0.03, -0.12]),
        ]
    }

    /// At `b = 0` the strain and the block are the small-strain ones, bit for bit;
    /// at `b = 1` the strain is `1/2 (F^T F - I)`.
    #[test]
    fn blend_zero_is_small_strain_and_one_is_green_lagrange() {
        let g = tet();
        let u = displacement();
        let e0 = green_lagrange_strain::<3, 4, 6>(&g.gradients, &u, 0.0);
        assert_eq!(e0, cell_strain::<3, 4, 6>(&g.gradients, &u));
        let (h, _) = displacement_gradient::<3, 4, 6>(&g.gradients, &u);
        for a in 0..4 {
            assert_eq!(
                green_lagrange_block::<3, 4, 6>(&g.gradients, &h, 0.0, 0.0, a),
                strain_block::<3, 4, 6>(&g.gradients, a)
            );
        }
        let f = SMatrix::<f64, 3, 3>::identity() + h;
        let gl = (f.transpose() * f - SMatrix::<f64, 3, 3>::identity()) * 0.5;
        let e1 = green_lagrange_strain::<3, 4, 6>(&g.gradients, &u, 1.0);
        let expected = [gl[(0, 0)], gl[(1, 1)], gl[(2, 2)], 2.0 * gl[(0, 1)], 2.0 * gl[(0, 2)], 2.0 * gl[(1, 2)]];
        for k in 0..6 {
            assert!((e1[k] - expected[k]).abs() < 1e-15, "{k}: {} vs {}", e1[k], expected[k]);
        }
    }

    /// The block is the strain's derivative and the geometric block the
    /// derivative of `B^T s` at fixed `s` (central differences, step 1e-6,
    /// agreement 1e-8), in 3D and axisymmetric.
    #[test]
    fn blocks_match_finite_differences() {
        let blend = 0.7;
        let g = tet();
        let u = displacement();
        let s = SVector::<f64, 6>::from([0.3, -0.5, 0.2, 0.1, -0.25, 0.05]);
        check::<3, 4, 6>(&g.gradients, &u, &s, blend);
        let ga = cell_geometry_in::<2, 3>(Formulation::Axisymmetric, &[[1.0, 0.0], [2.5, 0.2], [1.4, 1.3]]).unwrap();
        let ua = [SVector::from([0.05, -0.1]), SVector::from([0.2, -0.02]), SVector::from([0.1, -0.3])];
        let sa = SVector::<f64, 4>::from([0.3, -0.5, 0.2, 0.1]);
        check::<2, 3, 4>(&ga.gradients, &ua, &sa, blend);
    }

    fn check<const D: usize, const N: usize, const S: usize>(
        g: &ShapeGradients<D, N>,
        u: &[SVector<f64, D>; N],
        s: &SVector<f64, S>,
        blend: f64,
    ) {
        let (h, hoop) = displacement_gradient::<D, N, S>(g, u);
        let eps = 1e-6;
        for b in 0..N {
            for l in 0..D {
                let (mut up, mut down) = (*u, *u);
                up[b][l] += eps;
                down[b][l] -= eps;
                let fd = (green_lagrange_strain::<D, N, S>(g, &up, blend)
                    - green_lagrange_strain::<D, N, S>(g, &down, blend))
                    / (2.0 * eps);
                let block = green_lagrange_block::<D, N, S>(g, &h, hoop, blend, b);
                for r in 0..S {
                    assert!((block[(r, l)] - fd[r]).abs() < 1e-8, "B[{r}, {l}] of node {b}");
                }
                for a in 0..N {
                    let force = |v: &[SVector<f64, D>; N]| {
                        let (hv, hoopv) = displacement_gradient::<D, N, S>(g, v);
                        green_lagrange_block::<D, N, S>(g, &hv, hoopv, blend, a).transpose() * s
                    };
                    let fd = (force(&up) - force(&down)) / (2.0 * eps);
                    let k = geometric_block::<D, N, S>(g, s, blend, a, b);
                    for r in 0..D {
                        assert!((k[(r, l)] - fd[r]).abs() < 1e-8, "K_G[{a}{r}, {b}{l}]: {} vs {}", k[(r, l)], fd[r]);
                    }
                }
            }
        }
    }
}
