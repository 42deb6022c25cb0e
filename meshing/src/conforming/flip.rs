//! Sliver removal by edge removal (stage 5), after refinement and before
//! smoothing.
//!
//! ## Edge removal
//!
//! An interior edge `cd` around which `n` tets lie, `(c, d, p_i, p_{i+1})`
//! for the ring `p_0 .. p_{n-1}` of its other vertices (cyclic), is replaced,
//! with those tets, by `2 (n - 2)` tets: a triangulation of the ring polygon,
//! each triangle `p_i p_k p_j` joined to `c` and to `d` (Shewchuk, "Two
//! discrete optimization algorithms for the topological improvement of
//! tetrahedral meshes", 2002). The triangulation taken is the one whose worst
//! tet is best ([`angle_quality`], the measure smoothing raises), found by
//! Klincsek's dynamic programme over the polygon's sub-chains: the best
//! triangulation of the chain `p_i .. p_j` takes, over the apexes `k` between
//! them, the largest of the minimum of its two sub-chains' figures and of the
//! two tets on `p_i p_k p_j`; `O(n^3)` time for the `C(n, 3)` triangles, each
//! evaluated once. `n = 3` is the 3-2 flip (one triangle, two tets).
//!
//! The removal is made only when every new tet is positively oriented (exact
//! [`orient3d`]) and the worst new tet is better than the worst of the ring.
//! Both sets of tets have the same outer faces (`c p_i p_{i+1}` and
//! `d p_i p_{i+1}`; the inner faces of the new set cancel in pairs), so when
//! all new tets are positive they cover the ring's space exactly once: no
//! point moves and the boundary and the interfaces do not change. The edge is
//! left when a face around it is constrained (a subfacet: boundary or region
//! interface, given by the caller; a face with one tet counts too), when its
//! tets are not all of one region, when they do not close a ring (the edge is
//! on the boundary) or when the ring has more than [`MAX_RING`] tets.
//!
//! This is what removes the flat *caps* refinement leaves on a bent scan
//! (module docs of `conforming`): a cap `abcd` has two boundary faces `abc`,
//! `abd` on a hinge `ab` of the surface, and its apexes `c`, `d` span an
//! interior edge; any triangulation of that edge's ring contains one triangle
//! `a b p` (the ring's side `ab` is in exactly one), so the cap's boundary
//! faces stay, now on `(a, b, p, c)` and `(a, b, p, d)`. The 3-2 flip alone
//! reached only caps with three tets around `cd`, which are rare (on the
//! armadillo at 8 mm, 15 135 caps were left after it).
//!
//! ## Order
//!
//! The bad tets (quality under the sliver bound) are visited caps first (two
//! or more boundary faces), then by increasing quality, then by index; a
//! visited tet that is still bad removes, of its six edges, the one whose
//! removal gives the best worst tet. New tets that are bad join the end of the
//! queue. Rounds repeat this while a round removes something (at most
//! [`FLIP_ROUNDS`]). Every removal raises the worst quality of the tets it
//! replaces, so the sorted vector of the mesh's qualities grows
//! lexicographically: the process terminates. It is sequential and every
//! choice is made in a fixed order (ties go to the first), so the result does
//! not depend on hashing or threads. The mesh is no longer Delaunay
//! afterwards; nothing downstream needs it.

use rustc_hash::FxHashSet;

use super::smooth::tet_angle_quality as quality;
use crate::cells::{improve_in_rounds, CellStore, LocalEdit};
use crate::predicates::{orient3d, Point};

/// Rounds of removals at most.
pub const FLIP_ROUNDS: usize = 8;

/// The most tets around an edge that edge removal considers (Shewchuk found
/// larger rings rarely worth it; the programme's cost grows as `n^3`).
pub const MAX_RING: usize = 12;

/// Faces (sorted corners) that edge removal must keep: subfacets.
pub type FaceSet = FxHashSet<[u32; 3]>;

/// What edge removal did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct FlipStats {
    /// Edges removed (a 3-2 flip counts as one).
    pub flips: usize,
    /// Edges removed by the number of tets around them (index `n`, 3 to
    /// [`MAX_RING`]).
    pub by_ring_size: [usize; MAX_RING + 1],
    /// Caps (tets with two or more boundary faces) under the sliver bound
    /// before and after.
    pub caps_before: usize,
    /// See `caps_before`.
    pub caps_after: usize,
    /// Visits of caps that removed nothing, by the furthest any of its six
    /// edges got: 0 no closed ring (a boundary edge), 1 a closed ring over
    /// [`MAX_RING`], 2 tets of two regions, 3 a constrained face around the
    /// edge, 4 no triangulation with all tets positive, 5 none better.
    pub cap_refusals: [usize; 6],
    /// Rounds run.
    pub rounds: usize,
}

/// The best triangulation of the ring `ring` (cyclic, so that each
/// `(c, d, ring[i], ring[i + 1])` is positively oriented) around the edge
/// `cd`: its worst tet's quality and its triangles (indices into `ring`,
/// each in the ring's order), or `None` when no triangulation has all its tets
/// positively oriented. Klincsek's programme (module docs).
fn best_triangulation(nodes: &[Point], c: u32, d: u32, ring: &[u32]) -> Option<(f64, Vec<[usize; 3]>)> {
    let n = ring.len();
    let p = |i: usize| nodes[ring[i] as usize];
    let (pc, pd) = (nodes[c as usize], nodes[d as usize]);
    // best[i * n + j]: the figure of the chain i..j; apex[i * n + j]: its k.
    let mut best = vec![f64::INFINITY; n * n];
    let mut apex = vec![usize::MAX; n * n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            let mut top = f64::NEG_INFINITY;
            let mut arg = usize::MAX;
            for k in i + 1..j {
                let sub = best[i * n + k].min(best[k * n + j]);
                if sub <= top {
                    continue;
                }
                // The tets (p_i, p_k, p_j, d) and (p_k, p_i, p_j, c) are the
                // ones on the same side of the outer faces as the ring's.
                if orient3d(p(i), p(k), p(j), pd) != 1 || orient3d(p(k), p(i), p(j), pc) != 1 {
                    continue;
                }
                let q = quality(nodes, [ring[i], ring[k], ring[j], d])
                    .min(quality(nodes, [ring[k], ring[i], ring[j], c]))
                    .min(sub);
                if q > top {
                    top = q;
                    arg = k;
                }
            }
            best[i * n + j] = top;
            apex[i * n + j] = arg;
        }
    }
    let q = best[n - 1];
    if q == f64::NEG_INFINITY {
        return None;
    }
    let mut triangles = Vec::with_capacity(n - 2);
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j - i < 2 {
            continue;
        }
        let k = apex[i * n + j];
        triangles.push([i, k, j]);
        stack.push((i, k));
        stack.push((k, j));
    }
    Some((q, triangles))
}

/// Whether the permutation taking `t` to `u` (the same four vertices) is even.
fn even(t: [u32; 4], u: [u32; 4]) -> bool {
    let pos = u.map(|v| t.iter().position(|&w| w == v).unwrap_or(0));
    let mut inversions = 0;
    for a in 0..4 {
        for b in a + 1..4 {
            if pos[a] > pos[b] {
                inversions += 1;
            }
        }
    }
    inversions % 2 == 0
}

/// The mesh being improved: its cells and the subfacets.
struct Work<'a> {
    nodes: &'a [Point],
    cells: CellStore,
    constrained: &'a FaceSet,
}

/// A removal found: the ring's tets, the edge, the ring, the triangulation and
/// the new worst quality.
struct Removal {
    tets: Vec<u32>,
    c: u32,
    d: u32,
    ring: Vec<u32>,
    triangles: Vec<[usize; 3]>,
    quality: f64,
}

impl Work<'_> {
    /// Whether the face `f` is on the boundary: constrained, or with one tet.
    fn boundary_face(&self, f: [u32; 3]) -> bool {
        let mut k = f;
        k.sort_unstable();
        self.constrained.contains(&k)
            || self.cells.around(f[0], f[1]).filter(|&t| self.cells.cells[t as usize].contains(&f[2])).count() < 2
    }

    /// Whether cell `t` is a cap: two or more boundary faces.
    fn cap(&self, t: u32) -> bool {
        let c = self.cells.cells[t as usize];
        super::delaunay::FACE.iter().filter(|f| self.boundary_face(f.map(|j| c[j]))).count() >= 2
    }

    /// The removal of the edge `cd` of cell `t`, when it is allowed and better
    /// than `floor` (module docs).
    /// `Err`: why not, as an index of [`FlipStats::cap_refusals`].
    fn removal(&self, t: u32, c: u32, d: u32, floor: f64) -> Result<Removal, usize> {
        let tets: Vec<u32> = self.cells.around(c, d).collect();
        let n = tets.len();
        if n < 3 {
            return Err(0);
        }
        // Each tet (c, d, x, y), positively oriented: the ring's step x -> y.
        let mut next: Vec<(u32, u32)> = Vec::with_capacity(n);
        for &k in &tets {
            let cell = self.cells.cells[k as usize];
            let mut o = cell.iter().copied().filter(|&v| v != c && v != d);
            let (Some(x), Some(y)) = (o.next(), o.next()) else { return Err(0) };
            next.push(if even(cell, [c, d, x, y]) { (x, y) } else { (y, x) });
        }
        next.sort_unstable();
        if next.windows(2).any(|w| w[0].0 == w[1].0) {
            return Err(0);
        }
        let mut ring = vec![next[0].0];
        while ring.len() < n {
            let last = ring[ring.len() - 1];
            let Ok(at) = next.binary_search_by_key(&last, |e| e.0) else { return Err(0) };
            let y = next[at].1;
            ring.push(y);
        }
        let last = ring[n - 1];
        if !next.iter().any(|e| e.0 == last && e.1 == ring[0]) {
            return Err(0);
        }
        let mut seen = ring.clone();
        seen.sort_unstable();
        if seen.windows(2).any(|w| w[0] == w[1]) {
            return Err(0);
        }
        if n > MAX_RING {
            return Err(1);
        }
        let regions = &self.cells.regions;
        if tets.iter().any(|&k| regions[k as usize] != regions[t as usize]) {
            return Err(2);
        }
        for &x in &ring {
            let mut k = [c, d, x];
            k.sort_unstable();
            if self.constrained.contains(&k) {
                return Err(3);
            }
        }
        let old = tets.iter().map(|&k| quality(self.nodes, self.cells.cells[k as usize])).fold(floor, f64::min);
        let (q, triangles) = best_triangulation(self.nodes, c, d, &ring).ok_or(4usize)?;
        if q <= old {
            return Err(5);
        }
        Ok(Removal { tets, c, d, ring, triangles, quality: q })
    }

    /// Makes the removal `r`; the new cells.
    fn apply(&mut self, r: &Removal) -> Vec<u32> {
        let region = self.cells.regions[r.tets[0] as usize];
        for &k in &r.tets {
            self.cells.kill(k);
        }
        let mut made = Vec::with_capacity(2 * r.triangles.len());
        for &[i, k, j] in &r.triangles {
            let [a, b, e] = [r.ring[i], r.ring[k], r.ring[j]];
            made.push(self.cells.add([a, b, e, r.d], region));
            made.push(self.cells.add([b, a, e, r.c], region));
        }
        made
    }
}

impl LocalEdit for Work<'_> {
    type Stats = FlipStats;

    fn store(&self) -> &CellStore {
        &self.cells
    }

    fn quality(&self, cell: [u32; 4]) -> f64 {
        quality(self.nodes, cell)
    }

    fn cap(&self, k: u32) -> bool {
        Work::cap(self, k)
    }

    /// The best removal of an edge of `t` that raises its ring's worst quality.
    fn improve(&mut self, t: u32, _bound: f64, stats: &mut FlipStats) -> Option<Vec<u32>> {
        let cell = self.cells.cells[t as usize];
        let own = quality(self.nodes, cell);
        let mut chosen: Option<Removal> = None;
        let mut furthest = 0;
        for a in 0..4 {
            for b in a + 1..4 {
                let floor = chosen.as_ref().map_or(own, |r| r.quality);
                match self.removal(t, cell[a], cell[b], own) {
                    Ok(r) if r.quality > floor => chosen = Some(r),
                    Ok(_) => {}
                    Err(why) => furthest = furthest.max(why),
                }
            }
        }
        let Some(r) = chosen else {
            if self.cap(t) {
                stats.cap_refusals[furthest] += 1;
            }
            return None;
        };
        stats.by_ring_size[r.tets.len()] += 1;
        Some(self.apply(&r))
    }
}

/// Edge removal around the slivers of `cells` (regions `regions`, same
/// length; tets of [`angle_quality`] under `sliver_deg`), never through a
/// face of `constrained` (module docs). The removed cells are dropped from
/// both vectors and the new ones appended, in a fixed order.
pub fn remove_edges(
    nodes: &[Point],
    cells: &mut Vec<[u32; 4]>,
    regions: &mut Vec<u16>,
    constrained: &FaceSet,
    sliver_deg: f64,
) -> FlipStats {
    let mut stats = FlipStats::default();
    let cells_in = CellStore::new(nodes.len(), std::mem::take(cells), std::mem::take(regions));
    let mut w = Work { nodes, cells: cells_in, constrained };
    stats.caps_before = w.bad_caps(sliver_deg);
    (stats.rounds, stats.flips) = improve_in_rounds(&mut w, &mut stats, FLIP_ROUNDS, sliver_deg);
    stats.caps_after = w.bad_caps(sliver_deg);
    (*cells, *regions) = w.cells.into_live();
    stats
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cells::{outer_faces, positive};
    use crate::quality::dihedral_range_deg;

    fn volume(nodes: &[Point], t: [u32; 4]) -> f64 {
        let [a, b, c, d] = t.map(|v| nodes[v as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
        (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]))
            / 6.0
    }

    /// The ring's tets `(c, d, p_i, p_{i+1})` around the edge `cd` (vertices
    /// 0 and 1; the ring is vertices 2, 3, ...), positively oriented.
    fn ring_cells(nodes: &[Point]) -> Vec<[u32; 4]> {
        let n = nodes.len() as u32 - 2;
        (0..n).map(|i| positive(nodes, [0, 1, 2 + i, 2 + (i + 1) % n])).collect()
    }

    fn worst(nodes: &[Point], cells: &[[u32; 4]]) -> f64 {
        cells.iter().map(|&t| dihedral_range_deg(&t.map(|v| nodes[v as usize])).0).fold(180.0, f64::min)
    }

    /// A flat boundary cap with a ring of `n` tets around its interior edge
    /// `cd`: `c = (0, 1, e)`, `d = (0, -1, e)` (vertices 0, 1), the cap's
    /// hinge `ab` with `a = (1, 0, 0)`, `b = (-1, 0, 0)` (vertices 2, 3; `abc`
    /// and `abd` are the boundary, bent by `atan(e)` at `ab`), and `n - 2`
    /// interior points on the arc of radius 1 around `cd` in the plane
    /// `y = 0` above it. The cap `(c, d, a, b)` has corners within `e` of a
    /// plane.
    fn cap(n: usize, e: f64) -> Vec<Point> {
        let mut nodes = vec![[0.0, 1.0, e], [0.0, -1.0, e], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]];
        for k in 1..n - 1 {
            let th = std::f64::consts::PI * (1.0 - k as f64 / (n - 1) as f64);
            nodes.push([th.cos(), 0.0, e + th.sin()]);
        }
        // Ring order: a, b (below `cd`), then the arc from b's side to a's.
        nodes
    }

    fn hinge_faces() -> FaceSet {
        [[0, 2, 3], [1, 2, 3]].into_iter().collect()
    }

    /// Caps with rings of 4, 5 and 6 tets (corners 0.02 off a plane: the cap's
    /// smallest dihedral angle under 3 deg): removed, the volume kept (1e-12),
    /// the outer faces (the two boundary faces among them) kept, and the
    /// smallest dihedral angle raised to at least 28.7, 19.0 and 14.3 deg
    /// (measured: 28.74, 19.04, 14.31; the arc's points are 144 / (n - 1) deg
    /// apart around `cd`, which bounds the new tets on them).
    #[test]
    fn caps_with_rings_of_four_to_six_tets_are_removed() {
        for (n, floor) in [(4, 28.7), (5, 19.0), (6, 14.3)] {
            let nodes = cap(n, 0.02);
            let mut cells = ring_cells(&nodes);
            assert_eq!(cells.len(), n);
            let before: f64 = cells.iter().map(|&t| volume(&nodes, t)).sum();
            let lo = worst(&nodes, &cells);
            assert!(lo < 3.0, "n = {n}: {lo}");
            let outer = outer_faces(&cells);
            let mut regions = vec![0u16; n];
            let constrained = hinge_faces();
            let stats = remove_edges(&nodes, &mut cells, &mut regions, &constrained, 10.0);
            assert_eq!(stats.flips, 1, "n = {n}");
            assert_eq!(stats.by_ring_size[n], 1, "n = {n}");
            assert_eq!((stats.caps_before, stats.caps_after), (1, 0), "n = {n}");
            assert_eq!((cells.len(), regions.len()), (2 * (n - 2), 2 * (n - 2)), "n = {n}");
            let after: f64 = cells.iter().map(|&t| volume(&nodes, t)).sum();
            assert!((after - before).abs() < 1e-12, "n = {n}: {before} -> {after}");
            assert!(cells.iter().all(|&t| volume(&nodes, t) > 0.0), "n = {n}");
            assert!(cells.iter().all(|t| !(t.contains(&0) && t.contains(&1))), "n = {n}: cd left");
            assert_eq!(outer_faces(&cells), outer, "n = {n}");
            for f in &constrained {
                assert!(outer.contains(f), "n = {n}: {f:?}");
            }
            let lo = worst(&nodes, &cells);
            assert!(lo >= floor, "n = {n}: {lo}");
        }
    }

    /// The same caps with a ring face `c d p` constrained (a subfacet through
    /// the edge): nothing changes.
    #[test]
    fn no_removal_through_a_constrained_face() {
        let nodes = cap(5, 0.02);
        let mut cells = ring_cells(&nodes);
        let kept = cells.clone();
        let mut constrained = hinge_faces();
        constrained.insert([0, 1, 4]);
        let stats = remove_edges(&nodes, &mut cells, &mut vec![0u16; 5], &constrained, 10.0);
        assert_eq!(stats.flips, 0);
        assert_eq!(cells, kept);
    }

    /// The same cap with its tets in two regions: nothing changes.
    #[test]
    fn no_removal_across_regions() {
        let nodes = cap(4, 0.02);
        let mut cells = ring_cells(&nodes);
        let kept = cells.clone();
        let stats = remove_edges(&nodes, &mut cells, &mut vec![0, 0, 1, 1], &hinge_faces(), 10.0);
        assert_eq!(stats.flips, 0);
        assert_eq!(cells, kept);
    }

    /// A ring of four around `cd` (on the z axis, from -1 to 1) whose points
    /// alternate at heights +-2: every triangle of the ring polygon has `c`
    /// and `d` on one side, so no triangulation has all its tets positive and
    /// nothing changes even with every tet counted bad (bound 90 deg).
    #[test]
    fn no_removal_when_no_positive_triangulation_exists() {
        let nodes = vec![
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 2.0],
            [0.0, 1.0, -2.0],
            [-1.0, 0.0, 2.0],
            [0.05, -1.0, -2.0],
        ];
        let mut cells = ring_cells(&nodes);
        let kept = cells.clone();
        assert!(best_triangulation(&nodes, 0, 1, &[2, 3, 4, 5]).is_none());
        let stats = remove_edges(&nodes, &mut cells, &mut vec![0u16; 4], &FaceSet::default(), 90.0);
        assert_eq!(stats.flips, 0);
        assert_eq!(cells, kept);
    }

    /// Three tets around the edge `cd` (a = 0, b = 1, p = 2, c = 3, d = 4); the
    /// edge passes through the triangle `abp` at `(0.5, y, 0)`.
    fn ring(y: f64) -> (Vec<Point>, Vec<[u32; 4]>) {
        let nodes = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, y, 0.8], [0.5, y, -0.8]];
        let cells = [[3, 4, 0, 1], [3, 4, 1, 2], [3, 4, 2, 0]].map(|t| positive(&nodes, t)).to_vec();
        (nodes, cells)
    }

    /// n = 3, the 3-2 flip: the edge 0.02 from `ab`, the tet `(c, d, a, b)` is
    /// a sliver (its corners nearly coplanar), and the removal gives two tets
    /// on `abp` that fill the same volume (1e-12) with every dihedral angle
    /// over the 10 deg bound.
    #[test]
    fn a_sliver_on_a_three_tet_edge_is_flipped_into_two_good_tets() {
        let (nodes, mut cells) = ring(0.02);
        let before: f64 = cells.iter().map(|&t| volume(&nodes, t)).sum();
        assert!(worst(&nodes, &cells) < 10.0);
        let mut regions = vec![0u16; 3];
        let stats = remove_edges(&nodes, &mut cells, &mut regions, &FaceSet::default(), 10.0);
        assert_eq!((stats.flips, stats.by_ring_size[3]), (1, 1));
        assert_eq!((cells.len(), regions.len()), (2, 2));
        let after: f64 = cells.iter().map(|&t| volume(&nodes, t)).sum();
        assert!((after - before).abs() < 1e-12, "{before} -> {after}");
        for &t in &cells {
            assert!(volume(&nodes, t) > 0.0, "{t:?}");
            assert!(t.contains(&0) && t.contains(&1) && t.contains(&2), "{t:?}");
            let (lo, _) = dihedral_range_deg(&t.map(|v| nodes[v as usize]));
            assert!(lo > 10.0, "{t:?}: {lo}");
        }
    }

    /// n = 3 with the edge outside the triangle (`y` < 0): the two tets on
    /// `abp` would not fill the ring's space, so nothing flips.
    #[test]
    fn no_flip_when_the_edge_misses_the_triangle() {
        let (nodes, mut cells) = ring(-0.02);
        let kept = cells.clone();
        let mut regions = vec![0u16; 3];
        let stats = remove_edges(&nodes, &mut cells, &mut regions, &FaceSet::default(), 10.0);
        assert_eq!(stats.flips, 0);
        assert_eq!(cells, kept);
    }
}
