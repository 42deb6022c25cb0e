//! Edge adjacency, connected components and shells of a triangle surface: the
//! combinatorics under [`crate::validate`] and [`crate::repair`] (crate-private).
//!
//! The shells' definition is in [`crate::validate`]'s docs.

use crate::predicates::{orient3d, Point};

/// A plain union-find with path halving; the smaller index becomes the root, so
/// the classes' representatives do not depend on the order of unions.
#[derive(Debug, Clone)]
pub(crate) struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    pub(crate) fn new(n: usize) -> Self {
        UnionFind { parent: (0..n as u32).collect() }
    }

    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let grand = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grand;
            x = grand;
        }
        x
    }

    pub(crate) fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.parent[hi as usize] = lo;
        }
    }

    /// Class labels `0, 1, ...` numbered in order of first appearance.
    pub(crate) fn labels(&mut self) -> (Vec<u32>, usize) {
        let n = self.parent.len();
        let mut label_of_root = vec![u32::MAX; n];
        let mut labels = vec![0; n];
        let mut count = 0u32;
        for x in 0..n as u32 {
            let r = self.find(x) as usize;
            if label_of_root[r] == u32::MAX {
                label_of_root[r] = count;
                count += 1;
            }
            labels[x as usize] = label_of_root[r];
        }
        (labels, count as usize)
    }
}

/// One use of an edge by a triangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct EdgeUse {
    /// The triangle.
    pub tri: u32,
    /// Whether the triangle runs along the edge from its lower to its higher vertex
    /// index.
    pub forward: bool,
    /// The triangle's third vertex.
    pub apex: u32,
}

/// The undirected edges of the triangles not skipped, each with its uses
/// (compressed rows, edges sorted by vertex pair, uses by triangle).
#[derive(Debug, Clone)]
pub(crate) struct Edges {
    /// The edge's vertices, lower index first.
    pub keys: Vec<[u32; 2]>,
    offsets: Vec<usize>,
    uses: Vec<EdgeUse>,
}

impl Edges {
    /// Edges of `triangles`, leaving out triangles with `skip[t]` (and any with a
    /// repeated vertex index).
    pub(crate) fn new(triangles: &[[u32; 3]], skip: &[bool]) -> Edges {
        let mut entries: Vec<([u32; 2], EdgeUse)> = Vec::with_capacity(3 * triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            if skip[t] || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                continue;
            }
            for i in 0..3 {
                let (u, v, apex) = (tri[i], tri[(i + 1) % 3], tri[(i + 2) % 3]);
                let key = if u < v { [u, v] } else { [v, u] };
                entries.push((key, EdgeUse { tri: t as u32, forward: u < v, apex }));
            }
        }
        entries.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.tri.cmp(&y.1.tri)).then(x.1.forward.cmp(&y.1.forward)));
        let mut keys = Vec::new();
        let mut offsets = vec![0];
        let mut uses = Vec::with_capacity(entries.len());
        for (i, (key, u)) in entries.iter().enumerate() {
            if i > 0 && entries[i - 1].0 != *key {
                offsets.push(uses.len());
            }
            if i == 0 || entries[i - 1].0 != *key {
                keys.push(*key);
            }
            uses.push(*u);
        }
        offsets.push(uses.len());
        if keys.is_empty() {
            offsets.truncate(1);
        }
        Edges { keys, offsets, uses }
    }

    pub(crate) fn len(&self) -> usize {
        self.keys.len()
    }

    /// The uses of edge `e`, sorted by triangle.
    pub(crate) fn uses(&self, e: usize) -> &[EdgeUse] {
        &self.uses[self.offsets[e]..self.offsets[e + 1]]
    }
}

/// Edge-connected components of the triangles not skipped: `(label per triangle,
/// u32::MAX for skipped ones; count)`, numbered by lowest triangle index.
pub(crate) fn components(num_triangles: usize, edges: &Edges, skip: &[bool]) -> (Vec<u32>, usize) {
    let mut uf = UnionFind::new(num_triangles);
    for e in 0..edges.len() {
        let uses = edges.uses(e);
        for w in uses.windows(2) {
            uf.union(w[0].tri, w[1].tri);
        }
    }
    // Relabel so that skipped triangles get no component.
    let (labels, _) = uf.labels();
    let mut relabel = vec![u32::MAX; num_triangles];
    let mut count = 0u32;
    let mut out = vec![u32::MAX; num_triangles];
    for t in 0..num_triangles {
        if skip[t] {
            continue;
        }
        let l = labels[t] as usize;
        if relabel[l] == u32::MAX {
            relabel[l] = count;
            count += 1;
        }
        out[t] = relabel[l];
    }
    (out, count as usize)
}

/// The index of side `positive` (`true`: `+`) of triangle `t`.
#[inline]
pub(crate) fn side(t: u32, positive: bool) -> u32 {
    2 * t + u32::from(!positive)
}

/// The shells of a surface (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct Shells {
    /// Shell of each side ([`side`]); `u32::MAX` for skipped triangles.
    pub of_side: Vec<u32>,
    /// Volume of each shell [mm^3], sides oriented away from their cell.
    pub volume: Vec<f64>,
    /// For each edge, the shells of its wedges in angular order (one entry per
    /// wedge), and whether the two sides bounding each wedge have the same sign
    /// (both normals pointing into the wedge, or both out of it).
    pub wedges: Vec<Vec<Wedge>>,
}

/// One wedge around an edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Wedge {
    /// The shell the wedge belongs to (before relabelling: a side index root;
    /// after [`shells`] returns: the shell label).
    pub shell: u32,
    /// The triangle before and after the wedge, in angular order.
    pub tris: [u32; 2],
    /// Whether the two bounding sides have the same sign.
    pub consistent: bool,
}

/// Computes the shells of the triangles not skipped. Skipped triangles must
/// include every geometrically degenerate one (the angular order needs a proper
/// third vertex).
pub(crate) fn shells(vertices: &[Point], triangles: &[[u32; 3]], edges: &Edges, skip: &[bool]) -> Shells {
    let n = triangles.len();
    let mut uf = UnionFind::new(2 * n);
    let mut raw_wedges: Vec<Vec<(u32, [u32; 2], bool)>> = Vec::with_capacity(edges.len());
    let pos = |v: u32| vertices[v as usize];
    for e in 0..edges.len() {
        let [a, b] = edges.keys[e];
        let mut ring: Vec<EdgeUse> = edges.uses(e).to_vec();
        if ring.len() > 2 {
            radial_sort(pos(a), pos(b), &mut ring, pos);
        }
        let mut wedges = Vec::with_capacity(ring.len());
        if ring.len() == 1 {
            let t = ring[0].tri;
            uf.union(side(t, true), side(t, false));
            wedges.push((side(t, true), [t, t], false));
        } else {
            for i in 0..ring.len() {
                let f = ring[i];
                let g = ring[(i + 1) % ring.len()];
                // A triangle running a -> b has its normal towards increasing angle
                // about a -> b (right-hand rule): its `+` side faces the wedge after it.
                let s_after_f = side(f.tri, f.forward);
                let s_before_g = side(g.tri, !g.forward);
                uf.union(s_after_f, s_before_g);
                wedges.push((s_after_f, [f.tri, g.tri], f.forward != g.forward));
            }
        }
        raw_wedges.push(wedges);
    }
    // Label the shells of used sides.
    let mut of_side = vec![u32::MAX; 2 * n];
    let mut label_of_root = vec![u32::MAX; 2 * n];
    let mut count = 0u32;
    for (t, &skipped) in skip.iter().enumerate() {
        if skipped {
            continue;
        }
        for s in [side(t as u32, true), side(t as u32, false)] {
            let r = uf.find(s) as usize;
            if label_of_root[r] == u32::MAX {
                label_of_root[r] = count;
                count += 1;
            }
            of_side[s as usize] = label_of_root[r];
        }
    }
    let mut volume = vec![0.0; count as usize];
    for t in 0..n {
        if skip[t] {
            continue;
        }
        let v = tet_volume(vertices, triangles[t]);
        // The `+` side's cell is where the normal points: away from it is the
        // reversed triangle.
        volume[of_side[side(t as u32, true) as usize] as usize] -= v;
        volume[of_side[side(t as u32, false) as usize] as usize] += v;
    }
    let wedges = raw_wedges
        .into_iter()
        .map(|ws| {
            ws.into_iter().map(|(s, tris, consistent)| Wedge { shell: of_side[s as usize], tris, consistent }).collect()
        })
        .collect();
    Shells { of_side, volume, wedges }
}

/// Signed volume of the tetrahedron (origin, a, b, c) [mm^3], about the origin.
pub(crate) fn tet_volume(vertices: &[Point], tri: [u32; 3]) -> f64 {
    let [a, b, c] = tri.map(|i| vertices[i as usize]);
    crate::predicates::dot(a, crate::predicates::cross(b, c)) / 6.0
}

/// Sorts the triangles around the edge `a -> b` by the angle of their third vertex
/// (right-hand rule about `a -> b`), starting from the first one; ties (triangles
/// folded onto each other) by triangle index. Exact.
fn radial_sort(a: Point, b: Point, ring: &mut [EdgeUse], pos: impl Fn(u32) -> Point) {
    let c0 = pos(ring[0].apex);
    // A point off the plane (a, b, c0): its plane through ab separates the two
    // half-planes of (a, b, c0) bounded by the line ab.
    let scale = (0..3).map(|k| (b[k] - a[k]).abs() + (c0[k] - a[k]).abs()).fold(0.0, f64::max).max(1.0);
    let n = crate::predicates::cross(crate::predicates::sub(b, a), crate::predicates::sub(c0, a));
    let candidates = [
        [a[0] + n[0], a[1] + n[1], a[2] + n[2]],
        [a[0] + scale, a[1], a[2]],
        [a[0], a[1] + scale, a[2]],
        [a[0], a[1], a[2] + scale],
    ];
    let off = candidates.into_iter().find(|&e| orient3d(a, b, c0, e) != 0);
    let half = |c: Point| -> u8 {
        match orient3d(a, b, c0, c) {
            1 => 0,
            -1 => 1,
            _ => match off {
                Some(e) if orient3d(a, b, e, c) != orient3d(a, b, e, c0) => 1,
                _ => 0,
            },
        }
    };
    let first = ring[0];
    ring.sort_by(|x, y| {
        if x.tri == first.tri || y.tri == first.tri {
            // The reference itself is at angle zero, before everything.
            return (x.tri != first.tri).cmp(&(y.tri != first.tri)).then(x.tri.cmp(&y.tri));
        }
        let (cx, cy) = (pos(x.apex), pos(y.apex));
        half(cx).cmp(&half(cy)).then_with(|| match orient3d(a, b, cx, cy) {
            1 => std::cmp::Ordering::Less,
            -1 => std::cmp::Ordering::Greater,
            _ => x.tri.cmp(&y.tri),
        })
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Surface;

    fn surface(vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Surface {
        let n = triangles.len();
        Surface { vertices, triangles, triangle_regions: vec![0; n], region_names: vec!["r".into()] }
    }

    #[test]
    fn radial_order_around_an_edge() {
        // Edge along +z; apexes at angles 0, 90, 180, 270 degrees, given shuffled.
        let verts =
            [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.5], [0.0, 1.0, 0.5], [-1.0, 0.0, 0.5], [0.0, -1.0, 0.5]];
        let mut ring: Vec<EdgeUse> = [2u32, 4, 5, 3]
            .iter()
            .enumerate()
            .map(|(i, &apex)| EdgeUse { tri: i as u32, forward: true, apex })
            .collect();
        radial_sort(verts[0], verts[1], &mut ring, |v| verts[v as usize]);
        let order: Vec<u32> = ring.iter().map(|u| u.apex).collect();
        assert_eq!(order, vec![2, 3, 4, 5]);
    }

    #[test]
    fn a_tetrahedron_has_two_shells_of_opposite_volume() {
        let s = surface(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        );
        let skip = vec![false; 4];
        let edges = Edges::new(&s.triangles, &skip);
        assert_eq!(edges.len(), 6);
        let sh = shells(&s.vertices, &s.triangles, &edges, &skip);
        assert_eq!(sh.volume.len(), 2);
        let mut v = sh.volume.clone();
        v.sort_by(f64::total_cmp);
        assert!((v[0] + 1.0 / 6.0).abs() < 1e-15 && (v[1] - 1.0 / 6.0).abs() < 1e-15);
        // Outward triangles: every `+` side is in the outside (negative) shell.
        for t in 0..4 {
            assert!(sh.volume[sh.of_side[side(t, true) as usize] as usize] < 0.0);
        }
        assert!(sh.wedges.iter().flatten().all(|w| w.consistent));
    }
}
