//! The Delaunay predicates with symbolic perturbation.
//!
//! Exact signs come from Shewchuk's adaptive arithmetic (the `robust` crate). A
//! zero sign (five cospherical points, or four cocircular coplanar ones) is
//! resolved by *symbolic perturbation* of the lifting map (Devillers and
//! Teillaud, "Perturbations for Delaunay and weighted Delaunay 3D
//! triangulations", 2011, the scheme CGAL uses): every point `p` is lifted to
//! `|p|^2 + eps^rank(p)` for an infinitesimal `eps`, where the rank orders the
//! points lexicographically by `(x, y, z)`, the largest point being perturbed
//! most. The perturbed sign of a degenerate determinant is then the sign of the
//! first non-vanishing cofactor in that order, which is an orientation: an
//! exact `orient3d` (or, on a plane, `orient2d`) with the query point put in
//! place of the most perturbed vertex.
//!
//! Because the order is a property of the coordinates alone, the perturbed
//! Delaunay tetrahedralization is unique for a point set: it depends neither on
//! the insertion order nor on the indices, which is what makes the result
//! deterministic (and testable against a shuffled input).

use std::cmp::Ordering;

use robust::Coord3D;

use crate::predicates::{orient2d, orient3d, projection_for, Point};

/// The perturbation order: lexicographic on `(x, y, z)`.
#[inline]
pub(crate) fn lex(a: &Point, b: &Point) -> Ordering {
    a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])).then(a[2].total_cmp(&b[2]))
}

/// The exact sign of "`e` is inside the sphere through `a, b, c, d`" for a
/// positively oriented tet (`orient3d(a, b, c, d) > 0`): `+1` inside, `-1`
/// outside, `0` on it. (`robust::insphere` assumes the opposite orientation.)
#[inline]
pub fn insphere(a: Point, b: Point, c: Point, d: Point, e: Point) -> i8 {
    let p = |q: Point| Coord3D { x: q[0], y: q[1], z: q[2] };
    sign(-robust::insphere(p(a), p(b), p(c), p(d), p(e)))
}

/// [`insphere`] with the symbolic perturbation: never `0` for a non-flat tet
/// and `pe` not one of its corners. `pts` are the coordinates of the tet's
/// corners `v`; `pe` is given by its coordinates (it need not be a vertex of
/// `pts`: a probe), the perturbation depending on coordinates only.
pub(crate) fn insphere_perturbed_at(pts: &[Point], v: [u32; 4], pe: Point) -> i8 {
    let q = v.map(|i| pts[i as usize]);
    let s = insphere(q[0], q[1], q[2], q[3], pe);
    if s != 0 {
        return s;
    }
    // Slots 0..4: the corners; 4: the query point.
    let at = |k: usize| if k == 4 { pe } else { q[k] };
    let mut ids = [0, 1, 2, 3, 4];
    ids.sort_by(|&i, &j| lex(&at(i), &at(j)));
    for k in (2..5).rev() {
        let pos = ids[k];
        if pos == 4 {
            return -1;
        }
        let mut w = q;
        w[pos] = pe;
        let o = orient3d(w[0], w[1], w[2], w[3]);
        if o != 0 {
            return o;
        }
    }
    debug_assert!(false, "insphere_perturbed: flat tet {v:?}");
    -1
}

/// For `e` coplanar with the non-degenerate triangle `f = (a, b, c)`: `+1` when
/// `e` is inside its circumcircle under the perturbation, `-1` outside (never
/// `0` unless `e` is a corner).
pub(crate) fn incircle_perturbed_at(pts: &[Point], f: [u32; 3], pe: Point) -> i8 {
    let q = f.map(|i| pts[i as usize]);
    let Some(drop) = projection_for(q[0], q[1], q[2]) else {
        debug_assert!(false, "incircle_perturbed: degenerate face {f:?}");
        return -1;
    };
    let local = orient2d(q[0], q[1], q[2], drop);
    // The circle is the trace on the plane of any sphere through a, b, c: take
    // the one through a fourth point off the plane (a moved along the axis the
    // plane is not parallel to; exact on the rounded point). A projected 2D
    // incircle would test an ellipse instead.
    let mut off = q[0];
    off[drop] += q[0][drop].abs().max(1.0);
    let o = orient3d(q[0], q[1], q[2], off);
    debug_assert!(o != 0, "incircle_perturbed: the offset point is on the plane");
    let s = insphere(q[0], q[1], q[2], off, pe) * o;
    if s != 0 {
        return s;
    }
    // Slots 0..3: the corners; 3: the query point.
    let at = |k: usize| if k == 3 { pe } else { q[k] };
    let mut ids = [0, 1, 2, 3];
    ids.sort_by(|&x, &y| lex(&at(x), &at(y)));
    for k in (1..4).rev() {
        let pos = ids[k];
        if pos == 3 {
            return -1;
        }
        let mut w = q;
        w[pos] = pe;
        let o = orient2d(w[0], w[1], w[2], drop);
        if o != 0 {
            return o * local;
        }
    }
    debug_assert!(false, "incircle_perturbed: collinear points");
    -1
}

#[inline]
fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn insphere_follows_the_orientation_convention() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(orient3d(t[0], t[1], t[2], t[3]), 1);
        assert_eq!(insphere(t[0], t[1], t[2], t[3], [0.2, 0.2, 0.2]), 1);
        assert_eq!(insphere(t[0], t[1], t[2], t[3], [2.0, 2.0, 2.0]), -1);
        assert_eq!(insphere(t[0], t[1], t[2], t[3], [1.0, 1.0, 0.0]), 0);
    }

    #[test]
    fn perturbation_breaks_cospherical_ties_consistently() {
        // The eight corners of a cube are cospherical. For the two tets sharing a
        // face, the perturbed tests must agree: the fifth point is inside one
        // sphere iff the other tet's apex is inside the first (Delaunay flip
        // symmetry of the perturbed lifting).
        let pts: Vec<Point> = (0..8).map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64]).collect();
        let pos = |v: [u32; 4]| {
            let q = v.map(|i| pts[i as usize]);
            if orient3d(q[0], q[1], q[2], q[3]) > 0 {
                v
            } else {
                [v[1], v[0], v[2], v[3]]
            }
        };
        for quad in [[0u32, 1, 2, 4], [1, 2, 4, 7], [0, 3, 5, 6], [1, 2, 3, 4]] {
            let t = pos(quad);
            if orient3d(pts[t[0] as usize], pts[t[1] as usize], pts[t[2] as usize], pts[t[3] as usize]) == 0 {
                continue;
            }
            for e in 0..8u32 {
                if t.contains(&e) {
                    continue;
                }
                let s = insphere_perturbed_at(&pts, t, pts[e as usize]);
                assert_ne!(s, 0);
                // Swapping the roles: e replaces the corner x, x is tested.
                for k in 0..4 {
                    let mut u = t;
                    let x = u[k];
                    u[k] = e;
                    let q = u.map(|i| pts[i as usize]);
                    if orient3d(q[0], q[1], q[2], q[3]) <= 0 {
                        continue;
                    }
                    // The lifted five points: x inside sphere(u) iff e outside sphere(t)
                    // when e and x are on the same side of their common face.
                    assert_eq!(insphere_perturbed_at(&pts, u, pts[x as usize]), -s, "t {t:?} e {e} k {k}");
                }
            }
        }
    }
}
