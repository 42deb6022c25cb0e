//! The triangulation of one input triangle (a *facet*) by the points on it: its
//! corners, the Steiner points on its edges and in its interior.
//!
//! Kept combinatorially: a point on an edge splits the triangles along that edge
//! (no geometric test decides which edge it is on, so rounding of the point's
//! coordinates cannot move it off the facet's boundary), an interior point
//! splits the triangle containing it; Lawson flips then make the triangulation
//! Delaunay in the facet's plane, never flipping an edge of the facet's boundary.
//! The *subfacets* are the triangles the tetrahedralization must contain.
//!
//! Triangles are a list with a map from directed edges to them; the point
//! location of interior points is a linear search (facets have few points
//! compared with the mesh).

use std::collections::HashMap;

use robust::Coord;

use crate::predicates::{cross, dot, orient2d, projection_for, sub, Point};

/// The triangulation of one facet (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Facet {
    /// The facet's corners (vertex indices).
    corners: [u32; 3],
    /// Its triangles, counter-clockwise in the facet's frame.
    pub tris: Vec<[u32; 3]>,
    /// Points of the facet and their coordinates in its frame.
    local: HashMap<u32, [f64; 2]>,
    /// The triangle left of each directed edge.
    edge_tri: HashMap<(u32, u32), usize>,
    origin: Point,
    e1: Point,
    e2: Point,
}

impl Facet {
    /// The facet with corners `c` (non-degenerate) at `points`.
    pub fn new(c: [u32; 3], points: &[Point]) -> Self {
        let [a, b, cc] = c.map(|i| points[i as usize]);
        let u = sub(b, a);
        let lu = dot(u, u).sqrt();
        let e1 = [u[0] / lu, u[1] / lu, u[2] / lu];
        let n = cross(u, sub(cc, a));
        let m = cross(n, e1);
        let lm = dot(m, m).sqrt();
        let e2 = [m[0] / lm, m[1] / lm, m[2] / lm];
        let mut f =
            Facet { corners: c, tris: Vec::new(), local: HashMap::new(), edge_tri: HashMap::new(), origin: a, e1, e2 };
        f.push(c);
        for v in c {
            f.add_local(v, points);
        }
        f
    }

    /// The facet's corners.
    pub fn corners(&self) -> [u32; 3] {
        self.corners
    }

    /// The points on the facet (corners, and Steiner points on its edges and inside).
    pub fn points(&self) -> impl Iterator<Item = u32> + '_ {
        self.local.keys().copied()
    }

    fn add_local(&mut self, v: u32, points: &[Point]) {
        let d = sub(points[v as usize], self.origin);
        self.local.insert(v, [dot(d, self.e1), dot(d, self.e2)]);
    }

    fn xy(&self, v: u32) -> Coord<f64> {
        let p = self.local.get(&v).copied().unwrap_or([0.0; 2]);
        Coord { x: p[0], y: p[1] }
    }

    /// Whether `(a, b)` is an edge on the facet's boundary: both ends on one
    /// corner-to-corner side, recorded as `boundary` pairs by the caller.
    fn is_boundary(boundary: &[(u32, u32)], a: u32, b: u32) -> bool {
        boundary.iter().any(|&(x, y)| (x == a && y == b) || (x == b && y == a))
    }

    /// Splits the boundary edge `(a, b)` at the new point `m`.
    pub fn split_edge(&mut self, a: u32, b: u32, m: u32, points: &[Point], boundary: &[(u32, u32)]) {
        self.add_local(m, points);
        let k = self.edge_tri.get(&(a, b)).or_else(|| self.edge_tri.get(&(b, a))).copied();
        if let Some(k) = k {
            let t = self.tris[k];
            let i =
                (0..3).find(|&i| (t[i] == a && t[(i + 1) % 3] == b) || (t[i] == b && t[(i + 1) % 3] == a)).unwrap_or(0);
            let (p, q, r) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            self.set(k, [p, m, r]);
            let n = self.push([m, q, r]);
            let mut stack = vec![(r, p), (q, r)];
            let _ = n;
            self.flip_stack(&mut stack, boundary);
        }
    }

    /// Inserts the interior point `m` (in the facet's plane).
    pub fn insert_interior(&mut self, m: u32, points: &[Point], boundary: &[(u32, u32)]) {
        self.add_local(m, points);
        let pm = self.xy(m);
        let k = self
            .tris
            .iter()
            .position(|t| (0..3).all(|i| robust::orient2d(self.xy(t[i]), self.xy(t[(i + 1) % 3]), pm) >= 0.0))
            .unwrap_or_else(|| {
                // Outside every triangle by rounding: the nearest by centroid.
                let d = |t: &[u32; 3]| {
                    let c = t.map(|v| self.xy(v));
                    let (x, y) = ((c[0].x + c[1].x + c[2].x) / 3.0, (c[0].y + c[1].y + c[2].y) / 3.0);
                    (x - pm.x).powi(2) + (y - pm.y).powi(2)
                };
                (0..self.tris.len()).min_by(|&i, &j| d(&self.tris[i]).total_cmp(&d(&self.tris[j]))).unwrap_or(0)
            });
        let t = self.tris[k];
        // Exactly on an edge off the boundary (the circumcentre of a right
        // subfacet, on its hypotenuse): split the two triangles beside it, else
        // one of the three would be flat.
        for e in 0..3 {
            let (p, q, r) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
            if robust::orient2d(self.xy(p), self.xy(q), pm) != 0.0 || Self::is_boundary(boundary, p, q) {
                continue;
            }
            let Some(&j) = self.edge_tri.get(&(q, p)) else { continue };
            let u = self.tris[j];
            let i = (0..3).find(|&i| u[i] == q && u[(i + 1) % 3] == p).unwrap_or(0);
            let x = u[(i + 2) % 3];
            self.set(k, [p, m, r]);
            self.push([m, q, r]);
            self.set(j, [q, m, x]);
            self.push([m, p, x]);
            let mut stack = vec![(q, r), (r, p), (p, x), (x, q)];
            self.flip_stack(&mut stack, boundary);
            return;
        }
        let [p, q, r] = t;
        self.set(k, [p, q, m]);
        self.push([q, r, m]);
        self.push([r, p, m]);
        let mut stack = vec![(p, q), (q, r), (r, p)];
        self.flip_stack(&mut stack, boundary);
    }

    fn unindex(&mut self, k: usize) {
        let t = self.tris[k];
        for i in 0..3 {
            self.edge_tri.remove(&(t[i], t[(i + 1) % 3]));
        }
    }

    fn index(&mut self, k: usize) {
        let t = self.tris[k];
        for i in 0..3 {
            self.edge_tri.insert((t[i], t[(i + 1) % 3]), k);
        }
    }

    fn set(&mut self, k: usize, t: [u32; 3]) {
        self.unindex(k);
        self.tris[k] = t;
        self.index(k);
    }

    fn push(&mut self, t: [u32; 3]) -> usize {
        self.tris.push(t);
        let k = self.tris.len() - 1;
        self.index(k);
        k
    }

    /// The flips open to triangle `t`: for each of its edges `(u, v)` off the
    /// boundary whose quad with the triangle `(v, u, x)` across it is strictly
    /// convex, `(u, v, w, x)` with `w` the third corner of `t`. Flipping gives
    /// `(w, u, x)` and `(x, v, w)`.
    pub fn flips_of(&self, t: [u32; 3], boundary: &[(u32, u32)]) -> Vec<(u32, u32, u32, u32)> {
        let mut out = Vec::new();
        for e in 0..3 {
            let (u, v, w) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
            if Self::is_boundary(boundary, u, v) {
                continue;
            }
            let Some(&j) = self.edge_tri.get(&(v, u)) else { continue };
            let s = self.tris[j];
            let k = (0..3).find(|&k| s[k] == v && s[(k + 1) % 3] == u).unwrap_or(0);
            let x = s[(k + 2) % 3];
            let (pu, pv, pw, px) = (self.xy(u), self.xy(v), self.xy(w), self.xy(x));
            if robust::orient2d(pw, pu, px) > 0.0 && robust::orient2d(px, pv, pw) > 0.0 {
                out.push((u, v, w, x));
            }
        }
        out
    }

    /// Flips the edge `(u, v)` (one of [`Self::flips_of`]).
    pub fn flip(&mut self, u: u32, v: u32) {
        let (Some(&i), Some(&j)) = (self.edge_tri.get(&(u, v)), self.edge_tri.get(&(v, u))) else { return };
        let t = self.tris[i];
        let e = (0..3).find(|&e| t[e] == u && t[(e + 1) % 3] == v).unwrap_or(0);
        let w = t[(e + 2) % 3];
        let s = self.tris[j];
        let k = (0..3).find(|&k| s[k] == v && s[(k + 1) % 3] == u).unwrap_or(0);
        let x = s[(k + 2) % 3];
        self.unindex(i);
        self.unindex(j);
        self.tris[i] = [w, u, x];
        self.tris[j] = [x, v, w];
        self.index(i);
        self.index(j);
    }

    /// Lawson flips from the directed edges on `stack` (each with the new point
    /// on its left): an edge is flipped when it is not on the facet's boundary,
    /// the point across it is inside the circumcircle (in the facet's frame) and
    /// the quad is strictly convex.
    fn flip_stack(&mut self, stack: &mut Vec<(u32, u32)>, boundary: &[(u32, u32)]) {
        let mut budget = 64 * self.tris.len() + 64;
        while let Some((u, v)) = stack.pop() {
            if Self::is_boundary(boundary, u, v) {
                continue;
            }
            let (Some(&i), Some(&j)) = (self.edge_tri.get(&(u, v)), self.edge_tri.get(&(v, u))) else { continue };
            let t = self.tris[i];
            let e = (0..3).find(|&e| t[e] == u && t[(e + 1) % 3] == v).unwrap_or(0);
            let w = t[(e + 2) % 3];
            let s = self.tris[j];
            let k = (0..3).find(|&k| s[k] == v && s[(k + 1) % 3] == u).unwrap_or(0);
            let x = s[(k + 2) % 3];
            let (pu, pv, pw, px) = (self.xy(u), self.xy(v), self.xy(w), self.xy(x));
            if robust::incircle(pu, pv, pw, px) > 0.0
                && robust::orient2d(pw, pu, px) > 0.0
                && robust::orient2d(px, pv, pw) > 0.0
            {
                // Unindex both before indexing both: they share the new edge.
                self.unindex(i);
                self.unindex(j);
                self.tris[i] = [w, u, x];
                self.tris[j] = [x, v, w];
                self.index(i);
                self.index(j);
                stack.push((u, x));
                stack.push((x, v));
                budget = budget.saturating_sub(1);
                if budget == 0 {
                    return;
                }
            }
        }
    }

    /// Whether the point `p` (on the facet's plane, within rounding) is strictly
    /// inside the facet, exactly on the projection along the axis the facet is
    /// not parallel to (a point on a side is not inside).
    pub fn contains(&self, p: Point, points: &[Point]) -> bool {
        let c = self.corners.map(|v| points[v as usize]);
        let Some(drop) = projection_for(c[0], c[1], c[2]) else { return false };
        let s = orient2d(c[0], c[1], c[2], drop);
        (0..3).all(|i| orient2d(c[i], c[(i + 1) % 3], p, drop) == s)
    }
}
