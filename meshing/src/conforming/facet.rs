//! The triangulation of one *facet*: a planar polygon of the input, made of the
//! input triangles that are coplanar with their neighbours (see
//! [`coplanar_groups`]), by the points on it: its input vertices and the
//! Steiner points on its sides and in its interior.
//!
//! Kept combinatorially: a point on a side splits the triangle along that side
//! (no geometric test decides which side it is on, so rounding of the point's
//! coordinates cannot move it off the facet's boundary), an interior point
//! splits the triangle containing it; Lawson flips then make the triangulation
//! constrained Delaunay in the facet's plane, never flipping a side (a
//! *constrained* edge: a piece of an input edge between two facets). The input
//! edges inside a facet (between coplanar input triangles) are not kept: a CAD
//! model's needle triangles on a plane do not become needle subfacets, nor
//! their long edges runs of tiny subsegments. The *subfacets* are the
//! triangles the tetrahedralization must contain.
//!
//! Triangles are a list with a map from directed edges to them; the point
//! location of interior points is a linear search (facets have few points
//! compared with the mesh). The triangles removed and added since the last
//! [`Facet::take_changes`] are logged, so the owner's index of subfacets is
//! updated in time proportional to the change, not to the facet.

use std::collections::{HashMap, HashSet};

use robust::Coord;

use crate::predicates::{cross, dot, orient2d, projection_for, sub, Point};

/// Input triangles are coplanar when the far corner of the smaller of two
/// neighbours lies within this fraction of the input's bounding-box diagonal of
/// the larger's plane: rounding of coordinates on a plane (about 1e-16), far
/// below the 1e-9 Hausdorff gate, far above it curvature between neighbours.
pub const COPLANAR_TOL: f64 = 1e-12;

/// The facets of `triangles` (indices into `vertices`): groups of triangles,
/// each joined to another of its group across an edge that exactly two
/// triangles share, both of them coplanar ([`COPLANAR_TOL`]) and facing the
/// same way; a group any of whose vertices is off its largest triangle's plane
/// by more than ten times the tolerance (drift along a chain) is split back into
/// its triangles. Groups are ordered by their first triangle, their triangles
/// increasing: deterministic.
pub(crate) fn coplanar_groups(vertices: &[Point], triangles: &[[u32; 3]]) -> Vec<Vec<usize>> {
    let n = triangles.len();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in vertices {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let d = sub(hi, lo);
    let tol = COPLANAR_TOL * dot(d, d).sqrt();
    let normal = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| vertices[v as usize]);
        cross(sub(b, a), sub(c, a))
    };
    let off_plane = |t: &[u32; 3], v: u32| {
        let nn = normal(t);
        let l = dot(nn, nn).sqrt();
        if l == 0.0 {
            return f64::INFINITY;
        }
        dot(sub(vertices[v as usize], vertices[t[0] as usize]), nn).abs() / l
    };
    let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    let mut order = Vec::new();
    for (f, t) in triangles.iter().enumerate() {
        for i in 0..3 {
            let e = (t[i].min(t[(i + 1) % 3]), t[i].max(t[(i + 1) % 3]));
            let list = edges.entry(e).or_default();
            if list.is_empty() {
                order.push(e);
            }
            list.push(f);
        }
    }
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for e in &order {
        let &[f, g] = edges[e].as_slice() else { continue };
        let (nf, ng) = (normal(&triangles[f]), normal(&triangles[g]));
        if dot(nf, ng) <= 0.0 {
            continue;
        }
        let (big, small) = if dot(nf, nf) >= dot(ng, ng) { (f, g) } else { (g, f) };
        let Some(&far) = triangles[small].iter().find(|&&v| v != e.0 && v != e.1) else { continue };
        if off_plane(&triangles[big], far) <= tol {
            let (a, b) = (root(&mut parent, f), root(&mut parent, g));
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut slot: HashMap<usize, usize> = HashMap::new();
    for f in 0..n {
        let r = root(&mut parent, f);
        let k = *slot.entry(r).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[k].push(f);
    }
    let mut out = Vec::with_capacity(groups.len());
    for g in groups {
        let seed = largest(triangles, &g, vertices);
        let flat = g.iter().flat_map(|&f| triangles[f]).all(|v| off_plane(&triangles[seed], v) <= 10.0 * tol);
        if flat {
            out.push(g);
        } else {
            out.extend(g.into_iter().map(|f| vec![f]));
        }
    }
    out.sort_by_key(|g| g[0]);
    out
}

/// The triangle of `group` with the largest area (ties: the first).
fn largest(triangles: &[[u32; 3]], group: &[usize], vertices: &[Point]) -> usize {
    let area2 = |f: usize| {
        let [a, b, c] = triangles[f].map(|v| vertices[v as usize]);
        let n = cross(sub(b, a), sub(c, a));
        dot(n, n)
    };
    group.iter().copied().fold(group[0], |best, f| if area2(f) > area2(best) { f } else { best })
}

/// The triangulation of one facet (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Facet {
    /// The input triangles the facet is made of.
    inputs: Vec<[u32; 3]>,
    /// Unit normal (of its largest input triangle).
    normal: Point,
    /// Its triangles, counter-clockwise in the facet's frame.
    pub tris: Vec<[u32; 3]>,
    /// Points of the facet and their coordinates in its frame.
    local: HashMap<u32, [f64; 2]>,
    /// The triangle left of each directed edge.
    edge_tri: HashMap<(u32, u32), usize>,
    /// The sides (pieces of input edges between facets), as sorted pairs.
    constrained: HashSet<(u32, u32)>,
    /// Triangles removed and added since the last `take_changes`.
    removed: Vec<[u32; 3]>,
    added: Vec<[u32; 3]>,
    origin: Point,
    e1: Point,
    e2: Point,
}

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl Facet {
    /// How many input triangles the facet is made of (more than one: a plane
    /// of the input, merged).
    pub fn num_inputs(&self) -> usize {
        self.inputs.len()
    }

    /// The facet made of the input triangles `inputs` (coplanar, consistently
    /// oriented, not degenerate) whose sides are the edges `sides`: its
    /// triangulation is made constrained Delaunay at once.
    pub fn new(inputs: Vec<[u32; 3]>, sides: &[(u32, u32)], points: &[Point]) -> Self {
        let seed = {
            let all: Vec<usize> = (0..inputs.len()).collect();
            inputs[largest(&inputs, &all, points)]
        };
        let [a, b, cc] = seed.map(|i| points[i as usize]);
        let u = sub(b, a);
        let lu = dot(u, u).sqrt();
        let e1 = [u[0] / lu, u[1] / lu, u[2] / lu];
        let n = cross(u, sub(cc, a));
        let ln = dot(n, n).sqrt();
        let normal = n.map(|x| x / ln);
        let m = cross(n, e1);
        let lm = dot(m, m).sqrt();
        let e2 = [m[0] / lm, m[1] / lm, m[2] / lm];
        let mut f = Facet {
            inputs: Vec::new(),
            normal,
            tris: Vec::new(),
            local: HashMap::new(),
            edge_tri: HashMap::new(),
            constrained: sides.iter().map(|&(x, y)| key(x, y)).collect(),
            removed: Vec::new(),
            added: Vec::new(),
            origin: a,
            e1,
            e2,
        };
        for t in &inputs {
            for &v in t {
                f.add_local(v, points);
            }
        }
        let mut stack = Vec::new();
        for t in &inputs {
            let [p, q, r] = *t;
            let ccw = robust::orient2d(f.xy(p), f.xy(q), f.xy(r)) >= 0.0;
            let t = if ccw { [p, q, r] } else { [p, r, q] };
            f.push(t);
            stack.extend([(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]);
        }
        f.inputs = inputs;
        f.flip_stack(&mut stack);
        f
    }

    /// The facet's unit normal.
    pub fn normal(&self) -> Point {
        self.normal
    }

    /// The triangles removed and added since the last call (a triangle may be in
    /// both; the caller checks which of them are still there with [`Self::has_tri`]).
    pub fn take_changes(&mut self) -> (Vec<[u32; 3]>, Vec<[u32; 3]>) {
        (std::mem::take(&mut self.removed), std::mem::take(&mut self.added))
    }

    /// Whether `t` (as logged by [`Self::take_changes`]) is a triangle of the facet now.
    pub fn has_tri(&self, t: [u32; 3]) -> bool {
        self.edge_tri.get(&(t[0], t[1])).is_some_and(|&k| {
            let mut a = self.tris[k];
            let mut b = t;
            a.sort_unstable();
            b.sort_unstable();
            a == b
        })
    }

    /// The circumcentre of the triangle `t` of the facet, computed in the facet's
    /// frame (so that it lies on the facet's plane however skinny `t` is).
    pub fn circumcentre(&self, t: [u32; 3]) -> Point {
        let [a, b, c] = t.map(|v| self.xy(v));
        let (bx, by) = (b.x - a.x, b.y - a.y);
        let (cx, cy) = (c.x - a.x, c.y - a.y);
        let d = 2.0 * (bx * cy - by * cx);
        let (bb, cc) = (bx * bx + by * by, cx * cx + cy * cy);
        let ux = a.x + (cy * bb - by * cc) / d;
        let uy = a.y + (bx * cc - cx * bb) / d;
        [0, 1, 2].map(|k| self.origin[k] + ux * self.e1[k] + uy * self.e2[k])
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

    /// Whether `(a, b)` is a side of the facet (a constrained edge).
    fn is_boundary(&self, a: u32, b: u32) -> bool {
        self.constrained.contains(&key(a, b))
    }

    /// Splits the side `(a, b)` at the new point `m`.
    pub fn split_edge(&mut self, a: u32, b: u32, m: u32, points: &[Point]) {
        self.add_local(m, points);
        if self.constrained.remove(&key(a, b)) {
            self.constrained.insert(key(a, m));
            self.constrained.insert(key(m, b));
        }
        let k = self.edge_tri.get(&(a, b)).or_else(|| self.edge_tri.get(&(b, a))).copied();
        if let Some(k) = k {
            let t = self.tris[k];
            let i =
                (0..3).find(|&i| (t[i] == a && t[(i + 1) % 3] == b) || (t[i] == b && t[(i + 1) % 3] == a)).unwrap_or(0);
            let (p, q, r) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            self.set(k, [p, m, r]);
            let n = self.push([m, q, r]);
            let _ = n;
            let mut stack = vec![(r, p), (q, r)];
            self.flip_stack(&mut stack);
        }
    }

    /// Inserts the interior point `m` (in the facet's plane).
    pub fn insert_interior(&mut self, m: u32, points: &[Point]) {
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
            if robust::orient2d(self.xy(p), self.xy(q), pm) != 0.0 || self.is_boundary(p, q) {
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
            self.flip_stack(&mut stack);
            return;
        }
        let [p, q, r] = t;
        self.set(k, [p, q, m]);
        self.push([q, r, m]);
        self.push([r, p, m]);
        let mut stack = vec![(p, q), (q, r), (r, p)];
        self.flip_stack(&mut stack);
    }

    fn unindex(&mut self, k: usize) {
        let t = self.tris[k];
        self.removed.push(t);
        for i in 0..3 {
            self.edge_tri.remove(&(t[i], t[(i + 1) % 3]));
        }
    }

    fn index(&mut self, k: usize) {
        let t = self.tris[k];
        self.added.push(t);
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
    pub fn flips_of(&self, t: [u32; 3]) -> Vec<(u32, u32, u32, u32)> {
        let mut out = Vec::new();
        for e in 0..3 {
            let (u, v, w) = (t[e], t[(e + 1) % 3], t[(e + 2) % 3]);
            if self.is_boundary(u, v) {
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
    fn flip_stack(&mut self, stack: &mut Vec<(u32, u32)>) {
        let mut budget = 64 * self.tris.len() + 64;
        while let Some((u, v)) = stack.pop() {
            if self.is_boundary(u, v) {
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
    /// inside one of the facet's input triangles, exactly on the projection along
    /// the axis the triangle is not parallel to (a point on a side is not inside).
    pub fn contains(&self, p: Point, points: &[Point]) -> bool {
        self.inputs.iter().any(|t| {
            let c = t.map(|v| points[v as usize]);
            let Some(drop) = projection_for(c[0], c[1], c[2]) else { return false };
            let s = orient2d(c[0], c[1], c[2], drop);
            (0..3).all(|i| orient2d(c[i], c[(i + 1) % 3], p, drop) == s)
        })
    }
}
