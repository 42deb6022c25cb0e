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
//! Facets have few points (tens), so the triangles are a plain list searched
//! linearly.

use robust::Coord;

use crate::predicates::{cross, dot, sub, Point};

/// The triangulation of one facet (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Facet {
    /// The facet's corners (vertex indices).
    pub corners: [u32; 3],
    /// Its triangles, counter-clockwise in the facet's frame.
    pub tris: Vec<[u32; 3]>,
    /// Points of the facet and their coordinates in its frame.
    local: Vec<(u32, [f64; 2])>,
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
        let mut f = Facet { corners: c, tris: vec![c], local: Vec::new(), origin: a, e1, e2 };
        for v in c {
            f.add_local(v, points);
        }
        f
    }

    fn add_local(&mut self, v: u32, points: &[Point]) {
        let d = sub(points[v as usize], self.origin);
        self.local.push((v, [dot(d, self.e1), dot(d, self.e2)]));
    }

    fn xy(&self, v: u32) -> Coord<f64> {
        let p = self.local.iter().find(|(w, _)| *w == v).map(|(_, p)| *p).unwrap_or([0.0; 2]);
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
        if let Some(k) = self.tris.iter().position(|t| {
            (0..3).any(|i| t[i] == a && t[(i + 1) % 3] == b) || (0..3).any(|i| t[i] == b && t[(i + 1) % 3] == a)
        }) {
            let t = self.tris[k];
            // Rotate so that the edge is t[0] -> t[1].
            let i =
                (0..3).find(|&i| (t[i] == a && t[(i + 1) % 3] == b) || (t[i] == b && t[(i + 1) % 3] == a)).unwrap_or(0);
            let (p, q, r) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            self.tris[k] = [p, m, r];
            self.tris.push([m, q, r]);
        }
        self.make_delaunay(boundary);
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
        let [p, q, r] = self.tris[k];
        self.tris[k] = [p, q, m];
        self.tris.push([q, r, m]);
        self.tris.push([r, p, m]);
        self.make_delaunay(boundary);
    }

    /// Lawson flips until every interior edge is locally Delaunay (incircle in the
    /// facet's frame) or its quad is not strictly convex.
    fn make_delaunay(&mut self, boundary: &[(u32, u32)]) {
        let mut budget = 100 * self.tris.len() * self.tris.len() + 100;
        'again: loop {
            for i in 0..self.tris.len() {
                for e in 0..3 {
                    let t = self.tris[i];
                    let (u, v, w) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
                    if Self::is_boundary(boundary, u, v) {
                        continue;
                    }
                    let Some(j) = self.tris.iter().position(|s| (0..3).any(|k| s[k] == v && s[(k + 1) % 3] == u))
                    else {
                        continue;
                    };
                    let s = self.tris[j];
                    let k = (0..3).find(|&k| s[k] == v && s[(k + 1) % 3] == u).unwrap_or(0);
                    let x = s[(k + 2) % 3];
                    let (pu, pv, pw, px) = (self.xy(u), self.xy(v), self.xy(w), self.xy(x));
                    if robust::incircle(pu, pv, pw, px) > 0.0
                        && robust::orient2d(pw, pu, px) > 0.0
                        && robust::orient2d(px, pv, pw) > 0.0
                    {
                        self.tris[i] = [w, u, x];
                        self.tris[j] = [x, v, w];
                        budget = budget.saturating_sub(1);
                        if budget == 0 {
                            return;
                        }
                        continue 'again;
                    }
                }
            }
            return;
        }
    }

    /// Whether the point `p` (on the facet's plane) is inside the facet, in its frame.
    pub fn contains(&self, p: Point, points: &[Point]) -> bool {
        let d = sub(p, self.origin);
        let q = Coord { x: dot(d, self.e1), y: dot(d, self.e2) };
        let c = self.corners.map(|v| {
            let d = sub(points[v as usize], self.origin);
            Coord { x: dot(d, self.e1), y: dot(d, self.e2) }
        });
        (0..3).all(|i| robust::orient2d(c[i], c[(i + 1) % 3], q) > 0.0)
    }
}
