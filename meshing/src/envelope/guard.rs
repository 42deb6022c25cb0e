//! The final angle guard: every tet the envelope emits has its dihedral angles
//! in [12°, 155°] (the targets), or the mesher refuses.
//!
//! The stuffing's angles are proven on the uniform lattice's outer stencils only;
//! the graded lattice's, the cells cut by region interfaces and layer planes, and
//! what the smoothing moves are measured, not proven (module docs of
//! [`super`]). So after the fitting, the tets scoring under 1
//! ([`super::smooth::score`]: a dihedral angle under 12° or over 155°) are
//! repaired, in rounds (sequential, in index order: deterministic):
//!
//! 1. **Flips** (Joe's 2-3 and 3-2 flips): the two tets on a face of the bad tet
//!    become three around a new edge, or the three tets around an edge of it
//!    become two on a new face, when all the tets involved belong to one region
//!    (so region interfaces stay), the new ones fill exactly the old ones'
//!    volume (the flip is geometrically valid; relative 1e-9), and the worst new
//!    score beats the worst old one. Flips keep the union of the tets, so the
//!    boundary and the interfaces do not move. The best such flip is taken.
//! 2. **Peeling**: a bad tet with a face on the boundary and a height (the
//!    smallest of its four altitudes) under `near` [mm] is removed, when the
//!    boundary stays manifold at its edges (every edge then in 0 or 2 boundary
//!    faces). The boundary moves inward by less than that height.
//! 3. **Splits**: an edge of the bad tet is cut in every tet around it (each
//!    half keeps its parent's region) when the worst score around the edge rises
//!    and fewer tets there are outside [12°, 155°]; the best edge is taken. A
//!    boundary or interface edge is cut at its midpoint, which stays on that
//!    boundary or interface (they do not move). An edge inside one region (the
//!    tets around it close a ring) is cut at the best of its midpoint, points
//!    towards the centroid of its ring and a pattern search about them: the new
//!    node may leave the edge's line, and the new tets tile the ring exactly
//!    when all are positive. This repairs a tet whose two boundary faces lie on
//!    the two sides of a crease of the input, its edge along the crease: it
//!    has the crease's interior angle there, whatever its nodes do on the
//!    input (the teapot at 0.25 mm: 158° at a 22° crease of the
//!    lid's knob); cutting its inner edge at a point inside gives the crease
//!    edge two tets.
//!
//! Whatever is still outside [12°, 155°] after [`ROUNDS`] rounds is returned to
//! the caller, which refuses the mesh with [`super::EnvelopeError::AngleGuard`].

use std::collections::BTreeSet;

use super::smooth::score;
use super::tree::{cross, dot, norm, sub};

type P = [f64; 3];

/// Repair rounds at most.
pub(crate) const ROUNDS: usize = 8;
/// Pattern-search steps at most per step size when placing a split point.
const SEARCH_STEPS: usize = 8;

/// What the guard did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct GuardStats {
    /// Tets outside [12°, 155°] before the guard.
    pub bad_before: usize,
    /// 2-3 and 3-2 flips taken.
    pub flips: usize,
    /// Boundary tets removed.
    pub peeled: usize,
    /// Edges split (at their midpoints, or off the line for an edge inside one region).
    pub splits: usize,
}

fn volume(p: &[P; 4]) -> f64 {
    dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0]))) / 6.0
}

/// `c` ordered to positive volume (the last two corners swapped if needed).
fn positive(nodes: &[P], c: [u32; 4]) -> [u32; 4] {
    if volume(&c.map(|v| nodes[v as usize])) < 0.0 {
        [c[0], c[1], c[3], c[2]]
    } else {
        c
    }
}

/// The smallest of the four altitudes of the tet `p` [mm].
fn height(p: &[P; 4]) -> f64 {
    let v = volume(p).abs();
    (0..4)
        .map(|k| {
            let f = [p[(k + 1) % 4], p[(k + 2) % 4], p[(k + 3) % 4]];
            let a = 0.5 * norm(cross(sub(f[1], f[0]), sub(f[2], f[0])));
            if a > 0.0 {
                3.0 * v / a
            } else {
                0.0
            }
        })
        .fold(f64::INFINITY, f64::min)
}

/// The indices of the tets of `cells` outside [12°, 155°] (score under 1), ascending.
pub(crate) fn bad_cells(nodes: &[P], cells: &[[u32; 4]]) -> Vec<usize> {
    use rayon::prelude::*;
    cells.par_iter().enumerate().filter(|(_, c)| score(&c.map(|v| nodes[v as usize])) < 1.0).map(|(k, _)| k).collect()
}

/// An edge split the guard may take.
struct Split {
    /// The worst score of the new tets.
    worst: f64,
    /// The edge.
    edge: (u32, u32),
    /// The cells around it.
    around: Vec<u32>,
    /// The new node [mm].
    at: P,
}

struct Work<'a> {
    nodes: &'a mut Vec<P>,
    cells: &'a mut Vec<[u32; 4]>,
    regions: &'a mut Vec<u16>,
    alive: Vec<bool>,
    of_node: Vec<Vec<u32>>,
}

impl Work<'_> {
    fn pts(&self, c: [u32; 4]) -> [P; 4] {
        c.map(|v| self.nodes[v as usize])
    }

    /// Live cells holding all of `vs`, ascending.
    fn holding(&self, vs: &[u32]) -> Vec<u32> {
        let mut out: Vec<u32> = self.of_node[vs[0] as usize]
            .iter()
            .copied()
            .filter(|&k| self.alive[k as usize] && vs.iter().all(|v| self.cells[k as usize].contains(v)))
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    fn add(&mut self, c: [u32; 4], region: u16) {
        let k = self.cells.len() as u32;
        self.cells.push(c);
        self.regions.push(region);
        self.alive.push(true);
        for &v in &c {
            self.of_node[v as usize].push(k);
        }
    }

    /// The best flip on or around cell `k` that raises the worst score: (new
    /// worst score, old cells, new cells).
    fn best_flip(&self, k: usize) -> Option<(f64, Vec<u32>, Vec<[u32; 4]>)> {
        let c = self.cells[k];
        let region = self.regions[k];
        let mut best: Option<(f64, Vec<u32>, Vec<[u32; 4]>)> = None;
        let mut consider = |old: Vec<u32>, new: Vec<[u32; 4]>| {
            let old_worst = old.iter().map(|&o| score(&self.pts(self.cells[o as usize]))).fold(f64::INFINITY, f64::min);
            let old_volume: f64 = old.iter().map(|&o| volume(&self.pts(self.cells[o as usize])).abs()).sum();
            let new: Vec<[u32; 4]> = new.into_iter().map(|n| positive(self.nodes.as_slice(), n)).collect();
            let new_volume: f64 = new.iter().map(|&n| volume(&self.pts(n)).abs()).sum();
            if !((new_volume - old_volume).abs() <= 1e-9 * old_volume) {
                return;
            }
            let new_worst = new.iter().map(|&n| score(&self.pts(n))).fold(f64::INFINITY, f64::min);
            if new_worst > old_worst && best.as_ref().is_none_or(|b| new_worst > b.0) {
                best = Some((new_worst, old, new));
            }
        };
        // 2-3: across each face.
        for i in 0..4 {
            let d = c[i];
            let f = [c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]];
            let around = self.holding(&f);
            let [a, b] = around[..] else { continue };
            let other = if a as usize == k { b } else { a };
            if self.regions[other as usize] != region {
                continue;
            }
            let Some(&e) = self.cells[other as usize].iter().find(|v| !f.contains(v)) else { continue };
            consider(vec![k as u32, other], vec![[f[0], f[1], d, e], [f[1], f[2], d, e], [f[2], f[0], d, e]]);
        }
        // 3-2: around each edge.
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (c[i], c[j]);
                let around = self.holding(&[a, b]);
                if around.len() != 3 || around.iter().any(|&o| self.regions[o as usize] != region) {
                    continue;
                }
                let mut ring: Vec<u32> =
                    around.iter().flat_map(|&o| self.cells[o as usize]).filter(|&v| v != a && v != b).collect();
                ring.sort_unstable();
                ring.dedup();
                // A closed ring of three tets has three other vertices (else the edge is on the boundary).
                let [x, y, z] = ring[..] else { continue };
                consider(around, vec![[x, y, z, a], [x, y, z, b]]);
            }
        }
        best
    }

    /// The scores of the tets that splitting edge `(a, b)` at the point `m` makes
    /// of the cells `around` it (each cut in two, orientations kept).
    fn split_scores(&self, a: u32, b: u32, around: &[u32], m: P) -> Vec<f64> {
        let mut news = Vec::with_capacity(2 * around.len());
        for &o in around {
            let t = self.cells[o as usize];
            for end in [a, b] {
                news.push(score(&t.map(|v| if v == end { m } else { self.nodes[v as usize] })));
            }
        }
        news
    }

    /// Whether the cells `around` edge `(a, b)` close a ring of one region (every
    /// face through the edge in two of them): then the edge is inside one region,
    /// on neither the boundary nor an interface, and a point splitting it may
    /// leave the edge's line (the new cells tile the ring exactly when all are
    /// positive).
    fn closed_ring(&self, a: u32, b: u32, around: &[u32]) -> bool {
        let Some(&first) = around.first() else { return false };
        let region = self.regions[first as usize];
        if around.len() < 3 || around.iter().any(|&o| self.regions[o as usize] != region) {
            return false;
        }
        let mut count: std::collections::BTreeMap<u32, usize> = std::collections::BTreeMap::new();
        for &o in around {
            for v in self.cells[o as usize] {
                if v != a && v != b {
                    *count.entry(v).or_default() += 1;
                }
            }
        }
        count.values().all(|&c| c == 2)
    }

    /// Where to split the interior edge `(a, b)`: the point whose split leaves the
    /// best worst score, among the midpoint, points from it towards the centroid of
    /// the ring's vertices, then axis steps of a tenth and a fortieth of the mean
    /// distance from the midpoint to the ring (pattern search, deterministic).
    fn split_point(&self, a: u32, b: u32, around: &[u32], mid: P) -> (f64, P) {
        let worst = |m: P| self.split_scores(a, b, around, m).into_iter().fold(f64::INFINITY, f64::min);
        let mut ring: Vec<u32> =
            around.iter().flat_map(|&o| self.cells[o as usize]).filter(|&v| v != a && v != b).collect();
        ring.sort_unstable();
        ring.dedup();
        let centroid =
            [0, 1, 2].map(|x| ring.iter().map(|&v| self.nodes[v as usize][x]).sum::<f64>() / ring.len() as f64);
        let reach = ring.iter().map(|&v| norm(sub(self.nodes[v as usize], mid))).sum::<f64>() / ring.len() as f64;
        let mut best = (worst(mid), mid);
        for f in [0.25, 0.5, 0.75, 1.0] {
            let q = [0, 1, 2].map(|x| mid[x] + f * (centroid[x] - mid[x]));
            let s = worst(q);
            if s > best.0 {
                best = (s, q);
            }
        }
        for step in [0.1 * reach, 0.025 * reach] {
            for _ in 0..SEARCH_STEPS {
                let here = best;
                for x in 0..3 {
                    for sign in [-1.0, 1.0] {
                        let mut q = here.1;
                        q[x] += sign * step;
                        let s = worst(q);
                        if s > best.0 {
                            best = (s, q);
                        }
                    }
                }
                if best.1 == here.1 {
                    break;
                }
            }
        }
        best
    }

    /// The best split of an edge of cell `k` (every tet around the edge cut in
    /// two, each half keeping its parent's region), when the worst score around
    /// the edge rises and fewer tets there are outside [12°, 155°]. The new
    /// point is the edge's midpoint, or for an edge inside one region
    /// ([`Self::closed_ring`]) the best of [`Self::split_point`]'s.
    fn best_split(&self, k: usize) -> Option<Split> {
        let c = self.cells[k];
        let mut best: Option<Split> = None;
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (c[i], c[j]);
                let (pa, pb) = (self.nodes[a as usize], self.nodes[b as usize]);
                let mid = [0, 1, 2].map(|x| 0.5 * (pa[x] + pb[x]));
                let around = self.holding(&[a, b]);
                let m = if self.closed_ring(a, b, &around) { self.split_point(a, b, &around, mid).1 } else { mid };
                let olds: Vec<f64> = around.iter().map(|&o| score(&self.pts(self.cells[o as usize]))).collect();
                let news = self.split_scores(a, b, &around, m);
                let old_worst = olds.iter().copied().fold(f64::INFINITY, f64::min);
                let new_worst = news.iter().copied().fold(f64::INFINITY, f64::min);
                let bad = |x: &[f64]| x.iter().filter(|&&s| s < 1.0).count();
                if new_worst > old_worst
                    && new_worst > 0.0
                    && bad(&news) < bad(&olds)
                    && best.as_ref().is_none_or(|b| new_worst > b.worst)
                {
                    best = Some(Split { worst: new_worst, edge: (a, b), around, at: m });
                }
            }
        }
        best
    }

    /// Splits edge `(a, b)` at the point `m` in the cells `around` it; returns the new cells.
    fn split(&mut self, a: u32, b: u32, around: &[u32], m: P) -> Vec<u32> {
        let new = self.nodes.len() as u32;
        self.nodes.push(m);
        self.of_node.push(Vec::new());
        let mut made = Vec::new();
        for &o in around {
            let t = self.cells[o as usize];
            let region = self.regions[o as usize];
            self.alive[o as usize] = false;
            for end in [a, b] {
                made.push(self.cells.len() as u32);
                self.add(t.map(|v| if v == end { new } else { v }), region);
            }
        }
        made
    }

    /// Whether removing cell `k` leaves every one of its edges in 0 or 2 boundary faces.
    fn peel_keeps_manifold(&self, k: usize) -> bool {
        let c = self.cells[k];
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (c[i], c[j]);
                let mut boundary = 0;
                for o in self.holding(&[a, b]) {
                    if o as usize == k {
                        continue;
                    }
                    for &w in &self.cells[o as usize] {
                        if w == a || w == b {
                            continue;
                        }
                        let shared = self.holding(&[a, b, w]).into_iter().filter(|&x| x as usize != k).count();
                        if shared == 1 {
                            boundary += 1;
                        }
                    }
                }
                if boundary != 0 && boundary != 2 {
                    return false;
                }
            }
        }
        true
    }

    fn on_boundary(&self, k: usize) -> bool {
        let c = self.cells[k];
        (0..4).any(|i| self.holding(&[c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]]).len() == 1)
    }
}

/// Repairs the tets outside [12°, 155°] (see the module docs), in place; cells
/// removed or replaced are dropped, new ones appended, unused nodes removed.
/// `near` [mm]: the largest height of a boundary tet that may be peeled.
pub(crate) fn repair(nodes: &mut Vec<P>, cells: &mut Vec<[u32; 4]>, regions: &mut Vec<u16>, near: f64) -> GuardStats {
    let mut stats = GuardStats::default();
    let bad = bad_cells(nodes, cells);
    stats.bad_before = bad.len();
    if bad.is_empty() {
        return stats;
    }
    let mut of_node: Vec<Vec<u32>> = vec![Vec::new(); nodes.len()];
    for (k, c) in cells.iter().enumerate() {
        for &v in c {
            of_node[v as usize].push(k as u32);
        }
    }
    let n = cells.len();
    let mut w = Work { nodes: &mut *nodes, cells: &mut *cells, regions: &mut *regions, alive: vec![true; n], of_node };
    let mut bad: BTreeSet<u32> = bad.into_iter().map(|k| k as u32).collect();
    for _ in 0..ROUNDS {
        let mut changed = false;
        for k in bad.clone() {
            let k = k as usize;
            if !w.alive[k] {
                continue;
            }
            if let Some((_, old, new)) = w.best_flip(k) {
                for &o in &old {
                    w.alive[o as usize] = false;
                    bad.remove(&o);
                }
                let region = w.regions[k];
                for c in new {
                    let id = w.cells.len() as u32;
                    w.add(c, region);
                    if score(&w.pts(c)) < 1.0 {
                        bad.insert(id);
                    }
                }
                stats.flips += 1;
                changed = true;
            } else if height(&w.pts(w.cells[k])) <= near && w.on_boundary(k) && w.peel_keeps_manifold(k) {
                w.alive[k] = false;
                bad.remove(&(k as u32));
                stats.peeled += 1;
                changed = true;
            } else if let Some(Split { edge: (a, b), around, at, .. }) = w.best_split(k) {
                for &o in &around {
                    bad.remove(&o);
                }
                for id in w.split(a, b, &around, at) {
                    if score(&w.pts(w.cells[id as usize])) < 1.0 {
                        bad.insert(id);
                    }
                }
                stats.splits += 1;
                changed = true;
            }
        }
        bad.retain(|&k| w.alive[k as usize]);
        if bad.is_empty() || !changed {
            break;
        }
    }
    // Compaction: live cells in order, used nodes in order.
    let alive = std::mem::take(&mut w.alive);
    let mut k = 0;
    w.cells.retain(|_| {
        k += 1;
        alive[k - 1]
    });
    let mut k = 0;
    w.regions.retain(|_| {
        k += 1;
        alive[k - 1]
    });
    let mut new_id = vec![u32::MAX; nodes.len()];
    for c in cells.iter() {
        for &v in c {
            new_id[v as usize] = 0;
        }
    }
    let mut kept = Vec::with_capacity(nodes.len());
    for (v, id) in new_id.iter_mut().enumerate() {
        if *id == 0 {
            *id = kept.len() as u32;
            kept.push(nodes[v]);
        }
    }
    for c in cells.iter_mut() {
        *c = c.map(|v| new_id[v as usize]);
    }
    *nodes = kept;
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cap (its apex just above the middle of its base) on a good tet: the
    /// 2-3 flip across the shared face makes three tets of the same volume, within
    /// [12°, 155°].
    #[test]
    fn a_cap_on_a_good_tet_is_flipped() {
        let nodes0 = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.9, 0.0], [0.5, 0.3, 0.02], [0.5, 0.3, -0.8]];
        let cells0 = vec![positive(&nodes0, [0, 1, 2, 3]), positive(&nodes0, [0, 1, 2, 4])];
        assert_eq!(bad_cells(&nodes0, &cells0), vec![0]);
        let total = |nodes: &[P], cells: &[[u32; 4]]| -> f64 {
            cells.iter().map(|c| volume(&c.map(|v| nodes[v as usize]))).sum()
        };
        let (mut nodes, mut cells, mut regions) = (nodes0.clone(), cells0.clone(), vec![0u16; 2]);
        let s = repair(&mut nodes, &mut cells, &mut regions, 0.0);
        assert_eq!((s.bad_before, s.flips, s.peeled), (1, 1, 0), "{s:?}");
        assert_eq!(cells.len(), 3);
        assert!(bad_cells(&nodes, &cells).is_empty(), "{cells:?}");
        assert!((total(&nodes, &cells) - total(&nodes0, &cells0)).abs() < 1e-12);
        // Two regions: no flip across the interface, and nothing may be peeled.
        let (mut nodes, mut cells, mut regions) = (nodes0.clone(), cells0.clone(), vec![0u16, 1]);
        let s = repair(&mut nodes, &mut cells, &mut regions, 0.0);
        assert_eq!((s.flips, s.peeled), (0, 0));
        assert_eq!(bad_cells(&nodes, &cells).len(), 1);
    }

    /// A sliver beside a good tet (no flip is valid: its apex is off the shared
    /// face): peeled when thinner than `near`, left to the caller otherwise.
    #[test]
    fn a_thin_boundary_sliver_is_peeled_only_when_thin_enough() {
        let nodes0 = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.9, 0.0], [0.5, -0.6, 0.02], [0.5, 0.3, -0.8]];
        let cells0 = vec![positive(&nodes0, [0, 1, 2, 3]), positive(&nodes0, [0, 1, 2, 4])];
        assert_eq!(bad_cells(&nodes0, &cells0), vec![0]);
        let (mut nodes, mut cells, mut regions) = (nodes0.clone(), cells0.clone(), vec![0u16; 2]);
        let s = repair(&mut nodes, &mut cells, &mut regions, 0.05);
        assert_eq!((s.flips, s.peeled), (0, 1), "{s:?}");
        assert_eq!(cells.len(), 1);
        assert_eq!(nodes.len(), 4, "the sliver's apex is dropped");
        assert!(bad_cells(&nodes, &cells).is_empty());
        let (mut nodes, mut cells, mut regions) = (nodes0.clone(), cells0.clone(), vec![0u16; 2]);
        let s = repair(&mut nodes, &mut cells, &mut regions, 1e-3);
        assert_eq!((s.flips, s.peeled), (0, 0), "{s:?}");
        assert_eq!(bad_cells(&nodes, &cells), vec![0]);
    }

    /// The teapot's crease tet in small: four tets around an inner edge `r1 r2`
    /// (along z), one of them flat, its dihedral angle at `r1 r2` 158.1° (its
    /// ring nodes `b1`, `b2` nearly opposite across the edge). No flip repairs
    /// it and neither does a midpoint split (the halves keep the angle); the
    /// split at a point moved into the ring does: every tet in [12°, 155°]
    /// (measured worst score 2.21 after, 0.87 before), the volume kept (1e-12),
    /// the new node off the edge's line.
    #[test]
    fn an_inner_edge_is_split_off_its_line() {
        let nodes0 = vec![
            [0.0, 0.0, -0.125],
            [0.0, 0.0, 0.125],
            [0.008, -0.125, 0.0],
            [0.041, 0.125, 0.0],
            [-0.25, 0.125, 0.0],
            [-0.25, -0.125, 0.0],
        ];
        let cells0: Vec<[u32; 4]> =
            [[0, 1, 2, 3], [0, 1, 3, 4], [0, 1, 4, 5], [0, 1, 5, 2]].iter().map(|&c| positive(&nodes0, c)).collect();
        let worst = |nodes: &[P], cells: &[[u32; 4]]| {
            cells.iter().map(|c| score(&c.map(|v| nodes[v as usize]))).fold(f64::INFINITY, f64::min)
        };
        let total = |nodes: &[P], cells: &[[u32; 4]]| -> f64 {
            cells.iter().map(|c| volume(&c.map(|v| nodes[v as usize]))).sum()
        };
        assert_eq!(bad_cells(&nodes0, &cells0), vec![0]);
        let (lo, hi) = crate::quality::dihedral_range_deg(&cells0[0].map(|v| nodes0[v as usize]));
        assert!(hi > 158.0 && hi < 158.2, "{lo}..{hi}");
        let (mut nodes, mut cells, mut regions) = (nodes0.clone(), cells0.clone(), vec![0u16; 4]);
        let s = repair(&mut nodes, &mut cells, &mut regions, 0.0);
        eprintln!("{s:?}: worst score {} -> {}", worst(&nodes0, &cells0), worst(&nodes, &cells));
        assert_eq!((s.bad_before, s.splits), (1, 1), "{s:?}");
        assert!(bad_cells(&nodes, &cells).is_empty(), "{cells:?}");
        assert!((total(&nodes, &cells) - total(&nodes0, &cells0)).abs() < 1e-12);
        let m = nodes[nodes.len() - 1];
        assert!(m[0].hypot(m[1]) > 1e-3, "{m:?}");
        // Regions that differ around the edge (an interface through it): the
        // split stays at the midpoint, which does not repair the tet.
        let (mut nodes, mut cells, mut regions) = (nodes0.clone(), cells0.clone(), vec![0u16, 0, 1, 1]);
        repair(&mut nodes, &mut cells, &mut regions, 0.0);
        assert!(!bad_cells(&nodes, &cells).is_empty());
    }

    /// Three tets around an edge, one a sliver: the 3-2 flip makes two good tets
    /// of the same volume; regions that differ block it.
    #[test]
    fn three_tets_around_an_edge_become_two() {
        // Ring x, y, z around the edge a-b (a below, b above); z nearly on the
        // line x-y's extension makes the tet (a, b, x, z)... flat.
        let ring = [[1.0, 0.0, 0.0], [-0.5, 0.866, 0.0], [-0.5, -0.866, 0.0]];
        let a = [0.0, 0.0, -0.6];
        let b = [0.0, 0.0, 0.6];
        // Move the edge a-b near the face x-y's side so one of the three is a sliver.
        let shift = [0.22, 0.38, 0.0];
        let a = [a[0] + shift[0], a[1] + shift[1], a[2]];
        let b = [b[0] + shift[0], b[1] + shift[1], b[2]];
        let nodes0 = vec![ring[0], ring[1], ring[2], a, b];
        let cells0 =
            vec![positive(&nodes0, [3, 4, 0, 1]), positive(&nodes0, [3, 4, 1, 2]), positive(&nodes0, [3, 4, 2, 0])];
        let worst = |nodes: &[P], cells: &[[u32; 4]]| {
            cells.iter().map(|c| score(&c.map(|v| nodes[v as usize]))).fold(f64::INFINITY, f64::min)
        };
        let total = |nodes: &[P], cells: &[[u32; 4]]| -> f64 {
            cells.iter().map(|c| volume(&c.map(|v| nodes[v as usize]))).sum()
        };
        assert!(worst(&nodes0, &cells0) < 1.0, "{}", worst(&nodes0, &cells0));
        let (mut nodes, mut cells, mut regions) = (nodes0.clone(), cells0.clone(), vec![0u16; 3]);
        let s = repair(&mut nodes, &mut cells, &mut regions, 0.0);
        assert!(s.flips >= 1, "{s:?}");
        assert_eq!(cells.len(), 2);
        assert!(worst(&nodes, &cells) >= 1.0, "{}", worst(&nodes, &cells));
        assert!((total(&nodes, &cells) - total(&nodes0, &cells0)).abs() < 1e-12);
        // One tet of another region: no flip across the interface.
        let (mut nodes, mut cells, mut regions) = (nodes0.clone(), cells0.clone(), vec![0u16, 0, 1]);
        let s = repair(&mut nodes, &mut cells, &mut regions, 0.0);
        assert_eq!(s.flips, 0);
        assert_eq!(cells.len(), 3);
    }
}
