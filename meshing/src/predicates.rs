//! Exact geometric predicates on f64 points, and the triangle tests built on them.
//!
//! The signs come from Shewchuk's adaptive-precision determinants (the `robust`
//! crate): they are exact for every finite f64 input whose products neither
//! overflow nor underflow, so "coplanar", "collinear" and "touching" mean exactly
//! that, never "within some epsilon".
//!
//! Conventions (this module's, stated once):
//!
//! - [`orient3d`]`(a, b, c, d)` is the sign of `det[b - a, c - a, d - a]`: `+1`
//!   when `d` lies on the side of the plane `abc` that the normal
//!   `(b - a) x (c - a)` points to (the right-hand rule), `-1` on the other side,
//!   `0` when the four points are coplanar. (`robust::orient3d` has the opposite
//!   sign; the wrapper flips it.)
//! - [`orient2d`] is counter-clockwise positive, on the projection that drops one
//!   coordinate axis.
//! - Triangles and segments are closed sets: touching counts as meeting.
//!
//! # Example
//!
//! ```
//! use meshing::predicates::{orient3d, triangles_intersect};
//!
//! let a = [0.0, 0.0, 0.0];
//! let b = [1.0, 0.0, 0.0];
//! let c = [0.0, 1.0, 0.0];
//! assert_eq!(orient3d(a, b, c, [0.2, 0.2, 1.0]), 1);
//! assert_eq!(orient3d(a, b, c, [0.2, 0.2, 0.0]), 0);
//!
//! // A triangle piercing `abc`, sharing no vertex with it.
//! let pierce = [[0.2, 0.2, -1.0], [0.2, 0.2, 1.0], [0.3, 0.25, 1.0]];
//! assert!(triangles_intersect([a, b, c], pierce));
//! ```

use robust::{Coord, Coord3D};

/// A point [mm].
pub type Point = [f64; 3];

/// The sign (`-1`, `0` or `+1`) of `det[b - a, c - a, d - a]`, exactly; see the
/// module docs for the convention.
#[inline]
pub fn orient3d(a: Point, b: Point, c: Point, d: Point) -> i8 {
    let p = |q: Point| Coord3D { x: q[0], y: q[1], z: q[2] };
    sign(-robust::orient3d(p(a), p(b), p(c), p(d)))
}

/// The sign of the orientation of `a, b, c` projected onto the plane that drops
/// coordinate `drop` (0, 1 or 2): `+1` counter-clockwise, exactly.
///
/// The kept axes are cyclic, `(1, 2)`, `(2, 0)` or `(0, 1)`, so the sign equals the
/// sign of component `drop` of `(b - a) x (c - a)`.
#[inline]
pub fn orient2d(a: Point, b: Point, c: Point, drop: usize) -> i8 {
    let (i, j) = projection_axes(drop);
    let p = |q: Point| Coord { x: q[i], y: q[j] };
    sign(robust::orient2d(p(a), p(b), p(c)))
}

/// Whether the triangle `abc` has zero area, exactly: all three components of
/// `(b - a) x (c - a)` vanish (repeated or collinear vertices).
pub fn is_degenerate(a: Point, b: Point, c: Point) -> bool {
    (0..3).all(|drop| orient2d(a, b, c, drop) == 0)
}

/// A coordinate axis to drop such that the projection of triangle `abc` keeps a
/// non-zero area (the axis of the largest normal component, checked exactly);
/// `None` when the triangle is degenerate.
pub fn projection_for(a: Point, b: Point, c: Point) -> Option<usize> {
    let n = cross(sub(b, a), sub(c, a));
    let mut axes = [0, 1, 2];
    axes.sort_by(|&i, &j| n[j].abs().total_cmp(&n[i].abs()));
    axes.into_iter().find(|&drop| orient2d(a, b, c, drop) != 0)
}

/// Whether the closed segment `pq` and the closed triangle `abc` share a point.
/// The triangle must not be degenerate (checked in debug builds); the segment may
/// be a single point.
pub fn segment_meets_triangle(p: Point, q: Point, tri: [Point; 3]) -> bool {
    let [a, b, c] = tri;
    let sp = orient3d(a, b, c, p);
    let sq = orient3d(a, b, c, q);
    if sp == sq && sp != 0 {
        return false;
    }
    if sp == 0 && sq == 0 {
        let Some(drop) = projection_for(a, b, c) else {
            debug_assert!(false, "segment_meets_triangle: degenerate triangle");
            return false;
        };
        return segment_meets_triangle_2d(p, q, tri, drop);
    }
    // The line pq crosses the triangle's plane in one point, which lies on the
    // closed segment. It is in the closed triangle iff the three signed volumes of
    // pq with the triangle's edges do not take both strict signs.
    let s = [orient3d(p, q, a, b), orient3d(p, q, b, c), orient3d(p, q, c, a)];
    !(s.contains(&1) && s.contains(&-1))
}

/// Whether two closed, non-degenerate triangles share a point.
///
/// Two triangles meet iff an edge of one meets the other: the intersection of two
/// convex sets, if not empty, reaches the boundary of one of them.
pub fn triangles_intersect(t1: [Point; 3], t2: [Point; 3]) -> bool {
    if separated_by_plane(t1, t2) || separated_by_plane(t2, t1) {
        return false;
    }
    (0..3).any(|i| segment_meets_triangle(t1[i], t1[(i + 1) % 3], t2))
        || (0..3).any(|i| segment_meets_triangle(t2[i], t2[(i + 1) % 3], t1))
}

/// Whether two non-degenerate triangles that share exactly the vertex `t1[0] ==
/// t2[0]` (and no other vertex) meet anywhere else.
///
/// If the intersection holds a point other than the shared vertex, its far end is
/// on an edge that does not touch the shared vertex (or the two triangles
/// overlap along a common direction, where that is true as well), so testing the
/// two opposite edges is enough.
pub fn triangles_meet_beyond_vertex(t1: [Point; 3], t2: [Point; 3]) -> bool {
    if separated_by_plane_except_apex(t1, t2) || separated_by_plane_except_apex(t2, t1) {
        return false;
    }
    segment_meets_triangle(t1[1], t1[2], t2) || segment_meets_triangle(t2[1], t2[2], t1)
}

/// Whether two non-degenerate triangles `(u, w, a)` and `(u, w, b)` that share
/// the edge `uw` (and no third vertex) meet beyond it: only when they are
/// coplanar and fold onto each other (`a` and `b` on the same side of `uw`).
pub fn triangles_overlap_across_edge(u: Point, w: Point, a: Point, b: Point) -> bool {
    if orient3d(u, w, a, b) != 0 {
        return false;
    }
    let Some(drop) = projection_for(u, w, a) else {
        return false;
    };
    orient2d(u, w, a, drop) * orient2d(u, w, b, drop) > 0
}

/// `u - v`.
#[inline]
pub(crate) fn sub(u: Point, v: Point) -> Point {
    [u[0] - v[0], u[1] - v[1], u[2] - v[2]]
}

/// `u x v`.
#[inline]
pub(crate) fn cross(u: Point, v: Point) -> Point {
    [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
}

/// `u . v`.
#[inline]
pub(crate) fn dot(u: Point, v: Point) -> f64 {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

fn projection_axes(drop: usize) -> (usize, usize) {
    match drop {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    }
}

/// All three vertices of `other` strictly on one side of `tri`'s plane.
fn separated_by_plane(tri: [Point; 3], other: [Point; 3]) -> bool {
    let s = other.map(|p| orient3d(tri[0], tri[1], tri[2], p));
    (s[0] == s[1] && s[1] == s[2]) && s[0] != 0
}

/// `other[1]` and `other[2]` strictly on one side of `tri`'s plane; `other[0]`
/// is the shared vertex, on the plane.
fn separated_by_plane_except_apex(tri: [Point; 3], other: [Point; 3]) -> bool {
    let s1 = orient3d(tri[0], tri[1], tri[2], other[1]);
    let s2 = orient3d(tri[0], tri[1], tri[2], other[2]);
    s1 == s2 && s1 != 0
}

/// The 2D test of [`segment_meets_triangle`] for a segment in the triangle's plane,
/// on the projection dropping `drop` (where the triangle keeps its area, so the
/// projection is one-to-one on the plane).
fn segment_meets_triangle_2d(p: Point, q: Point, tri: [Point; 3], drop: usize) -> bool {
    point_in_triangle_2d(p, tri, drop)
        || point_in_triangle_2d(q, tri, drop)
        || (0..3).any(|i| segments_meet_2d(p, q, tri[i], tri[(i + 1) % 3], drop))
}

fn point_in_triangle_2d(p: Point, [a, b, c]: [Point; 3], drop: usize) -> bool {
    let s = [orient2d(a, b, p, drop), orient2d(b, c, p, drop), orient2d(c, a, p, drop)];
    !(s.contains(&1) && s.contains(&-1))
}

/// Closed segments `p1p2` and `q1q2` meet, on the projection dropping `drop`.
fn segments_meet_2d(p1: Point, p2: Point, q1: Point, q2: Point, drop: usize) -> bool {
    let d1 = orient2d(q1, q2, p1, drop);
    let d2 = orient2d(q1, q2, p2, drop);
    let d3 = orient2d(p1, p2, q1, drop);
    let d4 = orient2d(p1, p2, q2, drop);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let (i, j) = projection_axes(drop);
    // A point known collinear with a segment lies on it iff it is inside the
    // segment's bounding box.
    let within =
        |s1: Point, s2: Point, x: Point| [i, j].iter().all(|&k| s1[k].min(s2[k]) <= x[k] && x[k] <= s1[k].max(s2[k]));
    (d1 == 0 && within(q1, q2, p1))
        || (d2 == 0 && within(q1, q2, p2))
        || (d3 == 0 && within(p1, p2, q1))
        || (d4 == 0 && within(p1, p2, q2))
}

#[cfg(test)]
mod tests {
    use super::*;

    const O: Point = [0.0, 0.0, 0.0];
    const X: Point = [1.0, 0.0, 0.0];
    const Y: Point = [0.0, 1.0, 0.0];
    const Z: Point = [0.0, 0.0, 1.0];

    #[test]
    fn orient3d_follows_the_right_hand_rule() {
        assert_eq!(orient3d(O, X, Y, Z), 1);
        assert_eq!(orient3d(O, Y, X, Z), -1);
        assert_eq!(orient3d(O, X, Y, [3.0, -7.0, 0.0]), 0);
        // Exactly coplanar although far from the origin and not representable as a
        // nice decimal: floating-point evaluation of the determinant is not zero here.
        let a = [0.1, 0.2, 0.3];
        let b = [0.1 + 1e6, 0.2, 0.3];
        let c = [0.1, 0.2 + 1e6, 0.3];
        assert_eq!(orient3d(a, b, c, [123.456, 789.012, 0.3]), 0);
    }

    #[test]
    fn orient2d_sign_is_the_normal_component() {
        // (X - O) x (Y - O) = +z: positive when dropping z, zero when dropping x or y.
        assert_eq!(orient2d(O, X, Y, 2), 1);
        assert_eq!(orient2d(O, X, Y, 0), 0);
        assert_eq!(orient2d(O, Y, Z, 0), 1);
        assert_eq!(orient2d(O, Z, X, 1), 1);
    }

    #[test]
    fn degenerate_triangles_are_found_exactly() {
        assert!(is_degenerate(O, X, [2.0, 0.0, 0.0]));
        assert!(is_degenerate(O, O, Y));
        assert!(is_degenerate([0.1, 0.2, 0.3], [0.2, 0.4, 0.6], [0.4, 0.8, 1.2]));
        assert!(!is_degenerate(O, X, [2.0, 1e-300, 0.0]));
        assert_eq!(projection_for(O, X, Z), Some(1));
        assert_eq!(projection_for(O, X, [2.0, 0.0, 0.0]), None);
    }

    #[test]
    fn segments_and_triangles() {
        let t = [O, X, Y];
        assert!(segment_meets_triangle([0.2, 0.2, -1.0], [0.2, 0.2, 1.0], t));
        assert!(!segment_meets_triangle([0.2, 0.2, 0.5], [0.2, 0.2, 1.0], t));
        // Touching at a vertex, at an edge, ending on the face.
        assert!(segment_meets_triangle([0.0, 0.0, -1.0], [0.0, 0.0, 1.0], t));
        assert!(segment_meets_triangle([0.5, 0.5, -1.0], [0.5, 0.5, 1.0], t));
        assert!(segment_meets_triangle([0.2, 0.2, 0.0], [0.2, 0.2, 1.0], t));
        assert!(!segment_meets_triangle([0.6, 0.6, -1.0], [0.6, 0.6, 1.0], t));
        // Coplanar: crossing, inside, outside, touching a vertex.
        assert!(segment_meets_triangle([-1.0, 0.2, 0.0], [2.0, 0.2, 0.0], t));
        assert!(segment_meets_triangle([0.1, 0.1, 0.0], [0.2, 0.1, 0.0], t));
        assert!(!segment_meets_triangle([-1.0, -0.1, 0.0], [2.0, -0.1, 0.0], t));
        assert!(segment_meets_triangle([1.0, 0.0, 0.0], [2.0, 0.0, 0.0], t));
    }

    #[test]
    fn triangle_pairs() {
        let t = [O, X, Y];
        assert!(triangles_intersect(t, [[0.2, 0.2, -1.0], [0.2, 0.2, 1.0], [0.3, 0.25, 1.0]]));
        assert!(!triangles_intersect(t, [[0.2, 0.2, 0.1], [0.2, 0.2, 1.0], [0.3, 0.25, 1.0]]));
        // Coplanar, one inside the other: no edge crossings, still meeting.
        assert!(triangles_intersect(t, [[0.1, 0.1, 0.0], [0.2, 0.1, 0.0], [0.1, 0.2, 0.0]]));
        assert!(triangles_intersect([[0.1, 0.1, 0.0], [0.2, 0.1, 0.0], [0.1, 0.2, 0.0]], t));
        // Coplanar and disjoint.
        assert!(!triangles_intersect(t, [[1.0, 1.0, 0.0], [2.0, 1.0, 0.0], [1.0, 2.0, 0.0]]));
        // A vertex touching the face's interior (a T-junction) meets.
        assert!(triangles_intersect(t, [[0.2, 0.2, 0.0], [0.2, 0.2, 1.0], [0.3, 0.25, 1.0]]));
    }

    #[test]
    fn pairs_sharing_a_vertex() {
        // A fan around O: neighbours that only touch at O.
        assert!(!triangles_meet_beyond_vertex([O, X, Y], [O, Z, [-1.0, 0.0, 1.0]]));
        assert!(!triangles_meet_beyond_vertex([O, X, Y], [O, [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]));
        // Through the face: the second triangle dips below and comes back.
        assert!(triangles_meet_beyond_vertex([O, X, Y], [O, [0.5, 0.5, -1.0], [0.3, 0.3, 1.0]]));
        // Coplanar and overlapping wedges.
        assert!(triangles_meet_beyond_vertex([O, X, Y], [O, [1.0, 1.0, 0.0], [2.0, 0.5, 0.0]]));
        // Coplanar, sharing the direction of an edge.
        assert!(triangles_meet_beyond_vertex([O, X, Y], [O, [0.5, 0.0, 0.0], [0.5, -1.0, 0.0]]));
    }

    #[test]
    fn pairs_sharing_an_edge() {
        assert!(!triangles_overlap_across_edge(O, X, Y, [0.3, -1.0, 0.0]));
        assert!(triangles_overlap_across_edge(O, X, Y, [0.3, 2.0, 0.0]));
        assert!(!triangles_overlap_across_edge(O, X, Y, Z));
    }
}
