//! Sliver and cap removal by constrained star insertion (stage 6), after edge
//! removal and before smoothing.
//!
//! ## Star insertion
//!
//! For a bad tet `t` (its [`angle_quality`] under the sliver bound), a new
//! interior point `p` replaces a *cavity* of tets by the *star* of `p`: the
//! tets joining `p` to the cavity's boundary faces. The cavity
//!
//! 1. starts as `t` and, in one of the two cavities tried for each point,
//!    grows, breadth first, into the neighbours whose circumball contains
//!    `p` (exact `insphere`), as Bowyer–Watson would, up to half of
//!    [`MAX_CAVITY`] tets (the other cavity skips this step: the smallest
//!    one the next step finds);
//! 2. is then made *star-shaped* from `p`: while one of its boundary faces
//!    does not have `p` strictly on its inner side (exact [`orient3d`]), the
//!    cavity grows across that face when it may (it is not constrained, a
//!    subfacet: boundary or region interface, given by the caller, or a face
//!    with one tet; the tet beyond is of the same region and was not
//!    dropped), else the tet inside it is dropped
//!    (and never taken back); dropping `t` itself, or growing past
//!    [`MAX_CAVITY`] tets, refuses `p`.
//!
//! When every boundary face of the cavity has `p` strictly on its inner side,
//! the star's tets are all positive and they cover the cavity exactly once
//! (the boundary is closed and `p` sees all of it from inside, so each point
//! of the cavity is in exactly one cone of a face from `p`): the rest of the
//! mesh, its boundary faces and its interfaces do not change. A cavity whose
//! tets have a vertex on none of its boundary faces (the star would orphan
//! it), or that has a constrained face inside it, is refused.
//!
//! ## Why not Delaunay
//!
//! On a bent scan, a *cap* `abcd` (two boundary faces `abc`, `abd` on a nearly
//! flat hinge `ab`) has a circumball reaching far under the surface, but the
//! conforming Delaunay tetrahedralization also contains the outside, whose flat
//! tets over the same hinges have circumballs reaching under the surface too:
//! every point that would remove the cap was blocked there (module docs of
//! `conforming`, "What is not done"). Here the outside is gone and the cavity
//! stops at the subfacets, so a point under the cap removes it and keeps the
//! boundary faces (now on `pabc` and `pabd`).
//!
//! ## Candidates and order
//!
//! For each boundary face of `t`, the apex of the regular tet over it on the
//! inside (height `sqrt(2/3)` times its mean edge length) at three heights
//! (1, 0.7 and 0.45 of that); for a cap, the mean of its two faces' apexes;
//! `t`'s circumcentre when its circumradius is at most twice its longest
//! edge; and, for each edge of `t` on its boundary faces that is a hinge
//! (on two of them) or shorter than half `t`'s longest edge, the points
//! under the edge's midpoint along the mean inner normal of those faces at
//! [`UNDER_EDGE`] times its length (a wedge over a short hinge is seen from
//! there as an equilateral triangle's apex sees its base; the face apexes
//! lie over the far corners). From each candidate, [`PATCH_STEPS`] more:
//! the mean of the regular tets' apexes over the faces of the star it made
//! (`Work::patch_point`), placed for the whole patch the cavity covers
//! rather than for `t`'s own faces. The candidate whose star has the best
//! worst tet wins, and the
//! insertion is made only when that worst tet is better than the cavity's
//! worst, the star has fewer tets under the sliver bound than the cavity,
//! its dihedral angles lie within the range of the cavity's (neither a
//! smaller smallest angle nor a larger largest one), and no new tet exceeds
//! the volume bound. Without the second condition the
//! stars traded each cap for several slivers (tets from the point to surface
//! faces seen at a grazing angle): the armadillo at 8 mm went from 3.44 % of
//! tets under 10 deg to 7.11 %. Bad tets are visited caps
//! first, then by increasing quality, then by index, in rounds (at most
//! [`STAR_ROUNDS`]) while a round inserts something; new bad tets join the
//! queue. Without the range condition, stars whose worst tet was better by
//! [`angle_quality`] (the smallest angle, or half the supplement of the
//! largest) could still have a larger largest angle than the cavity they
//! replaced: on the armadillo at 8 mm two stars for slivers
//! raised it from 165.80 and 171.68 deg to 176.62 and 176.88 deg (the
//! cavities' worst tets were flat at their smallest angle, 0.004 and 1.12
//! deg). Sequential, every choice in a fixed order: the result depends on
//! neither hashing nor threads.

use std::collections::VecDeque;

use rustc_hash::{FxHashMap, FxHashSet};

use super::delaunay::FACE;
use super::flip::FaceSet;
use super::perturb::insphere;
use super::smooth::{angle_quality, tet_angle_quality as quality, within};
use crate::cells::{improve_in_rounds, CellStore, LocalEdit};
use crate::predicates::{cross, dot, orient3d, sub, Point};
use crate::quality::dihedral_range_deg;

/// Rounds of insertions at most.
pub const STAR_ROUNDS: usize = 4;

/// Depths of the candidates under a short boundary edge, in edge lengths
/// (`Work::under_short_edges`): the equilateral triangle's apex over it
/// (`sqrt(3) / 2`) and half that.
const UNDER_EDGE: [f64; 2] = [0.866_025_403_784_438_6, 0.433_012_701_892_219_3];

/// Steps from each candidate to the point for the patch its star covers
/// (`Work::patch_point`): each step's point is tried too.
const PATCH_STEPS: usize = 1;

/// The most tets a cavity may have.
pub const MAX_CAVITY: usize = 64;

/// What star insertion did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct StarStats {
    /// Points inserted.
    pub inserted: usize,
    /// Of those, inserted for caps (tets with two or more boundary faces).
    pub caps_inserted: usize,
    /// Tets removed and made.
    pub tets_removed: usize,
    /// See `tets_removed`.
    pub tets_made: usize,
    /// Bad caps (under the sliver bound) before and after.
    pub caps_before: usize,
    /// See `caps_before`.
    pub caps_after: usize,
    /// Bad tets visited for which no candidate was accepted.
    pub refused: usize,
    /// Rounds run.
    pub rounds: usize,
}

fn volume(q: [Point; 4]) -> f64 {
    dot(sub(q[1], q[0]), cross(sub(q[2], q[0]), sub(q[3], q[0]))) / 6.0
}

/// The mesh being improved: nodes (new ones appended), its cells and the
/// subfacets.
struct Work<'a> {
    nodes: Vec<Point>,
    cells: CellStore,
    constrained: &'a FaceSet,
    /// No new tet may be larger [mm^3].
    max_volume: f64,
}

/// A face of a cell (inner normal) and the cell across it (`None`: a
/// boundary face).
type Side = ([u32; 3], Option<u32>);

/// An insertion found: the point, the cavity, its boundary faces (oriented
/// so that each with the point is positive), and the new and old worst
/// qualities.
struct Insertion {
    p: Point,
    cavity: Vec<u32>,
    faces: Vec<[u32; 3]>,
    quality: f64,
    old: f64,
    bad_new: usize,
    bad_old: usize,
    /// The smallest and largest dihedral angle of the star [deg].
    range_new: (f64, f64),
    /// The same of the cavity.
    range_old: (f64, f64),
}

impl Insertion {
    /// Whether the star may replace its cavity: its worst tet is better, it
    /// has fewer tets under the sliver bound, and neither its smallest nor
    /// its largest dihedral angle is worse than the cavity's (module docs).
    fn improves(&self) -> bool {
        self.quality > self.old && self.bad_new < self.bad_old && within(self.range_new, self.range_old)
    }
}

impl Work<'_> {
    /// The live cell other than `t` with the face `f`, if any.
    fn across(&self, t: u32, f: [u32; 3]) -> Option<u32> {
        self.cells.around(f[0], f[1]).find(|&k| k != t && self.cells.cells[k as usize].contains(&f[2]))
    }

    fn constrained(&self, f: [u32; 3]) -> bool {
        let mut k = f;
        k.sort_unstable();
        self.constrained.contains(&k)
    }

    /// The faces of cell `t` (inner normals) and the cells across them
    /// (`None`: a boundary face, constrained or with one tet).
    fn faces(&self, t: u32) -> [Side; 4] {
        let c = self.cells.cells[t as usize];
        FACE.map(|f| {
            let f = f.map(|j| c[j]);
            (f, if self.constrained(f) { None } else { self.across(t, f) })
        })
    }

    /// Whether cell `t` is a cap: two or more boundary faces.
    fn cap(&self, t: u32) -> bool {
        self.faces(t).iter().filter(|(_, n)| n.is_none()).count() >= 2
    }

    fn point(&self, v: u32) -> Point {
        self.nodes[v as usize]
    }

    /// The candidate points for the bad cell `t` (module docs).
    fn candidates(&self, t: u32) -> Vec<Point> {
        let mut out = Vec::new();
        let mut apexes = Vec::new();
        for (f, n) in self.faces(t) {
            if n.is_some() {
                continue;
            }
            let q = f.map(|v| self.point(v));
            let Some((centroid, offset)) = regular_offset(q) else { continue };
            for s in [1.0, 0.7, 0.45] {
                out.push([0, 1, 2].map(|k| centroid[k] + offset[k] * s));
            }
            apexes.push(out[out.len() - 3]);
        }
        if apexes.len() >= 2 {
            out.push([0, 1, 2].map(|k| (apexes[0][k] + apexes[1][k]) / 2.0));
        }
        let q = self.cells.cells[t as usize].map(|v| self.point(v));
        let longest = (0..4)
            .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
            .map(|(i, j)| dot(sub(q[i], q[j]), sub(q[i], q[j])))
            .fold(0.0, f64::max)
            .sqrt();
        if let Some(c) = circumcentre(q) {
            if dot(sub(c, q[0]), sub(c, q[0])).sqrt() <= 2.0 * longest {
                out.push(c);
            }
        }
        out.extend(self.under_short_edges(t, longest));
        out
    }

    /// Points under the short boundary edges of cell `t` (module docs): for
    /// each edge of `t` on one of its boundary faces that is shared by two of
    /// them (a hinge) or shorter than half `longest` (`t`'s longest edge),
    /// the points under its midpoint, along the mean of those faces' inner
    /// unit normals, at [`UNDER_EDGE`] times its length: where a point sees
    /// the two faces of a short hinge as an equilateral triangle's apex sees
    /// its base, rather than from over the faces' far corners.
    fn under_short_edges(&self, t: u32, longest: f64) -> Vec<Point> {
        let c = self.cells.cells[t as usize];
        let boundary: Vec<[u32; 3]> = self.faces(t).into_iter().filter(|(_, n)| n.is_none()).map(|(f, _)| f).collect();
        let mut out = Vec::new();
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (self.point(c[i]), self.point(c[j]));
                let on: Vec<&[u32; 3]> = boundary.iter().filter(|f| f.contains(&c[i]) && f.contains(&c[j])).collect();
                let length = dot(sub(b, a), sub(b, a)).sqrt();
                if on.is_empty() || (on.len() < 2 && length > 0.5 * longest) {
                    continue;
                }
                let mut normal = [0.0; 3];
                for f in on {
                    let q = f.map(|v| self.point(v));
                    let n = cross(sub(q[1], q[0]), sub(q[2], q[0]));
                    let l = dot(n, n).sqrt();
                    if l > 0.0 {
                        normal = [0, 1, 2].map(|k| normal[k] + n[k] / l);
                    }
                }
                let l = dot(normal, normal).sqrt();
                if l <= 0.0 {
                    continue;
                }
                for depth in UNDER_EDGE {
                    out.push([0, 1, 2].map(|k| (a[k] + b[k]) / 2.0 + normal[k] / l * length * depth));
                }
            }
        }
        out
    }

    /// The point for the whole patch a star covers: the mean of the apexes
    /// of the regular tets over its boundary faces `faces` (each oriented with
    /// its normal into the cavity), so that the point sits at a regular tet's
    /// height over the surface faces and the other faces around it at once,
    /// rather than over the bad tet's own faces alone (module docs). `None`
    /// for a degenerate face.
    fn patch_point(&self, faces: &[[u32; 3]]) -> Option<Point> {
        let mut sum = [0.0; 3];
        for f in faces {
            let q = f.map(|v| self.point(v));
            let (centroid, offset) = regular_offset(q)?;
            sum = [0, 1, 2].map(|k| sum[k] + centroid[k] + offset[k]);
        }
        Some(sum.map(|x| x / faces.len() as f64))
    }

    /// The insertion of `p` for the bad cell `t` (module docs), when `p`'s
    /// star is valid and within the volume bound.
    fn insertion(&self, t: u32, p: Point, max_volume: f64, circumballs: bool, sliver_deg: f64) -> Option<Insertion> {
        let region = self.cells.regions[t as usize];
        let mut member: FxHashSet<u32> = FxHashSet::default();
        let mut dropped: FxHashSet<u32> = FxHashSet::default();
        let mut order: Vec<u32> = vec![t];
        member.insert(t);
        let mut faces_of: FxHashMap<u32, [Side; 4]> = FxHashMap::default();
        let mut faces = |w: &Self, k: u32| *faces_of.entry(k).or_insert_with(|| w.faces(k));
        let same = |k: u32| self.cells.regions[k as usize] == region;
        // 1. Circumballs.
        let mut queue = VecDeque::from([t]);
        while let Some(k) = queue.pop_front() {
            for (_, n) in faces(self, k) {
                let Some(u) = n else { continue };
                if member.contains(&u) || !same(u) {
                    continue;
                }
                let q = self.cells.cells[u as usize].map(|v| self.point(v));
                if circumballs
                    && order.len() < MAX_CAVITY / 2
                    && orient3d(q[0], q[1], q[2], q[3]) == 1
                    && insphere(q[0], q[1], q[2], q[3], p) == 1
                {
                    member.insert(u);
                    order.push(u);
                    queue.push_back(u);
                }
            }
        }
        // 2. Star-shaped from `p`.
        loop {
            let mut changed = false;
            let mut i = 0;
            while i < order.len() {
                let k = order[i];
                i += 1;
                if !member.contains(&k) {
                    continue;
                }
                for (f, n) in faces(self, k) {
                    if !member.contains(&k) {
                        break;
                    }
                    if n.is_some_and(|u| member.contains(&u)) {
                        continue;
                    }
                    let q = f.map(|v| self.point(v));
                    if orient3d(q[0], q[1], q[2], p) == 1 {
                        continue;
                    }
                    changed = true;
                    match n {
                        Some(u) if !dropped.contains(&u) && same(u) => {
                            if member.len() >= MAX_CAVITY {
                                return None;
                            }
                            member.insert(u);
                            order.push(u);
                        }
                        _ => {
                            if k == t {
                                return None;
                            }
                            member.remove(&k);
                            dropped.insert(k);
                        }
                    }
                }
            }
            if !changed {
                break;
            }
        }
        let cavity: Vec<u32> = order.into_iter().filter(|k| member.contains(k)).collect();
        let mut boundary = Vec::new();
        for &k in &cavity {
            for (f, n) in faces(self, k) {
                match n {
                    Some(u) if member.contains(&u) => {
                        if self.constrained(f) {
                            return None;
                        }
                    }
                    _ => boundary.push(f),
                }
            }
        }
        // Every vertex of the cavity stays (is on a boundary face).
        let on_boundary: FxHashSet<u32> = boundary.iter().flatten().copied().collect();
        if cavity.iter().any(|&k| self.cells.cells[k as usize].iter().any(|v| !on_boundary.contains(v))) {
            return None;
        }
        let mut worst = f64::INFINITY;
        let mut bad_new = 0;
        let mut range_new = (f64::INFINITY, f64::NEG_INFINITY);
        for f in &boundary {
            let q = [self.point(f[0]), self.point(f[1]), self.point(f[2]), p];
            if volume(q) > max_volume {
                return None;
            }
            let (lo, hi) = dihedral_range_deg(&q);
            range_new = (range_new.0.min(lo), range_new.1.max(hi));
            let a = angle_quality(lo, hi);
            worst = worst.min(a);
            bad_new += usize::from(a < sliver_deg);
        }
        let mut range_old = (f64::INFINITY, f64::NEG_INFINITY);
        let mut old = f64::INFINITY;
        let mut bad_old = 0;
        for &k in &cavity {
            let (lo, hi) = dihedral_range_deg(&self.cells.cells[k as usize].map(|v| self.point(v)));
            range_old = (range_old.0.min(lo), range_old.1.max(hi));
            let a = angle_quality(lo, hi);
            old = old.min(a);
            bad_old += usize::from(a < sliver_deg);
        }
        Some(Insertion { p, cavity, faces: boundary, quality: worst, old, bad_new, bad_old, range_new, range_old })
    }

    /// Makes the insertion `s`; the new cells.
    fn apply(&mut self, s: &Insertion) -> Vec<u32> {
        let region = self.cells.regions[s.cavity[0] as usize];
        self.nodes.push(s.p);
        let v = self.cells.add_node();
        for &k in &s.cavity {
            self.cells.kill(k);
        }
        s.faces.iter().map(|f| self.cells.add([f[0], f[1], f[2], v], region)).collect()
    }
}

impl LocalEdit for Work<'_> {
    type Stats = StarStats;

    fn store(&self) -> &CellStore {
        &self.cells
    }

    fn quality(&self, cell: [u32; 4]) -> f64 {
        quality(&self.nodes, cell)
    }

    fn cap(&self, k: u32) -> bool {
        Work::cap(self, k)
    }

    /// The best acceptable star of a candidate point for `t`.
    fn improve(&mut self, t: u32, bound: f64, stats: &mut StarStats) -> Option<Vec<u32>> {
        let mut chosen: Option<Insertion> = None;
        for p in self.candidates(t) {
            for circumballs in [false, true] {
                let mut p = p;
                for _ in 0..=PATCH_STEPS {
                    let Some(s) = self.insertion(t, p, self.max_volume, circumballs, bound) else { break };
                    let next = self.patch_point(&s.faces);
                    if s.improves() && chosen.as_ref().is_none_or(|c| s.quality > c.quality) {
                        chosen = Some(s);
                    }
                    match next {
                        Some(q) => p = q,
                        None => break,
                    }
                }
            }
        }
        let Some(s) = chosen else {
            stats.refused += 1;
            return None;
        };
        if self.cap(t) {
            stats.caps_inserted += 1;
        }
        stats.tets_removed += s.cavity.len();
        stats.tets_made += s.faces.len();
        Some(self.apply(&s))
    }
}

/// The centroid of the triangle `q` and the offset from it to the apex of the
/// regular tet over `q` on the side its normal (`(q1 - q0) x (q2 - q0)`, into
/// the cell in [`FACE`]'s order) points to: `sqrt(2/3)` times the mean edge
/// length along the unit normal. `None` for a degenerate triangle.
fn regular_offset(q: [Point; 3]) -> Option<(Point, Point)> {
    let normal = cross(sub(q[1], q[0]), sub(q[2], q[0]));
    let l = dot(normal, normal).sqrt();
    if l <= 0.0 {
        return None;
    }
    let mean = (0..3).map(|i| dot(sub(q[(i + 1) % 3], q[i]), sub(q[(i + 1) % 3], q[i])).sqrt()).sum::<f64>() / 3.0;
    let height = mean * (2.0f64 / 3.0).sqrt();
    let centroid = [0, 1, 2].map(|k| (q[0][k] + q[1][k] + q[2][k]) / 3.0);
    Some((centroid, [0, 1, 2].map(|k| normal[k] / l * height)))
}

/// The centre of the sphere through the corners of `q`, if they are not coplanar.
fn circumcentre(q: [Point; 4]) -> Option<Point> {
    let [a, b, c, d] = q.map(|x| sub(x, q[0]));
    let _ = a;
    let det = dot(b, cross(c, d));
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let (bb, cc, dd) = (dot(b, b), dot(c, c), dot(d, d));
    let u = cross(c, d);
    let v = cross(d, b);
    let w = cross(b, c);
    let r = [0, 1, 2].map(|k| (bb * u[k] + cc * v[k] + dd * w[k]) / (2.0 * det));
    r.iter().all(|x| x.is_finite()).then(|| [0, 1, 2].map(|k| q[0][k] + r[k]))
}

/// Star insertion for the bad tets of `cells` (regions `regions`, same
/// length; tets of [`angle_quality`] under `sliver_deg`), never through a face
/// of `constrained`, no new tet over `max_volume` [mm^3] (module docs). New
/// nodes are appended to `nodes` (interior points: the caller may move them
/// anywhere); removed cells are dropped from `cells` and `regions` and the
/// new ones appended, in a fixed order.
pub fn insert_stars(
    nodes: &mut Vec<Point>,
    cells: &mut Vec<[u32; 4]>,
    regions: &mut Vec<u16>,
    constrained: &FaceSet,
    sliver_deg: f64,
    max_volume: f64,
) -> StarStats {
    let mut stats = StarStats::default();
    let cells_in = CellStore::new(nodes.len(), std::mem::take(cells), std::mem::take(regions));
    let mut w = Work { nodes: std::mem::take(nodes), cells: cells_in, constrained, max_volume };
    stats.caps_before = w.bad_caps(sliver_deg);
    (stats.rounds, stats.inserted) = improve_in_rounds(&mut w, &mut stats, STAR_ROUNDS, sliver_deg);
    stats.caps_after = w.bad_caps(sliver_deg);
    *nodes = w.nodes;
    (*cells, *regions) = w.cells.into_live();
    stats
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cells::{outer_faces, positive, sorted_faces};

    fn volume_of(nodes: &[Point], t: [u32; 4]) -> f64 {
        volume(t.map(|v| nodes[v as usize]))
    }

    /// A cap with the tets over it: `c = (0, 1, e)`, `d = (0, -1, e)`
    /// (vertices 0, 1), the hinge `ab`, `a = (1, 0, 0)`, `b = (-1, 0, 0)`
    /// (vertices 2, 3; the boundary faces `abc` and `abd` are bent by
    /// `atan(e)` at `ab`), and three points 2 from `cd`'s midpoint at 135, 90
    /// and 45 deg in the plane `y = 0` (vertices 4, 5, 6). The cells are the
    /// five tets around `cd`, the cap `(c, d, a, b)` first; together they
    /// fill a convex polyhedron.
    fn capped(e: f64) -> (Vec<Point>, Vec<[u32; 4]>) {
        let mut nodes = vec![[0.0, 1.0, e], [0.0, -1.0, e], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]];
        for deg in [135.0f64, 90.0, 45.0] {
            let th = deg.to_radians();
            nodes.push([2.0 * th.cos(), 0.0, e + 2.0 * th.sin()]);
        }
        let ring = [2, 3, 4, 5, 6];
        let cells = (0..5).map(|i| positive(&nodes, [0, 1, ring[i], ring[(i + 1) % 5]])).collect();
        (nodes, cells)
    }

    fn hinge_faces() -> FaceSet {
        [[0, 2, 3], [1, 2, 3]].into_iter().collect()
    }

    fn worst(nodes: &[Point], cells: &[[u32; 4]]) -> f64 {
        cells.iter().map(|&t| quality(nodes, t)).fold(f64::INFINITY, f64::min)
    }

    /// A cap bent by 1.15 deg at its hinge (e = 0.02; its quality 1.15 deg)
    /// is removed by one point under it: the input points keep their
    /// coordinates, the outer faces (the two boundary faces among them) are
    /// the same, the volume is kept (1e-12), every tet is positive (exact
    /// `orient3d`) and the worst quality rises to at least 17 deg (measured:
    /// 17.22).
    #[test]
    fn a_bent_cap_is_removed_by_a_point_under_it() {
        let (mut nodes, mut cells) = capped(0.02);
        let input = nodes.clone();
        let before: f64 = cells.iter().map(|&t| volume_of(&nodes, t)).sum();
        let lo = worst(&nodes, &cells);
        assert!(lo < 1.2, "{lo}");
        let (lo_before, hi_before) = range(&nodes, &cells);
        let outer = outer_faces(&cells);
        let constrained = hinge_faces();
        for f in &constrained {
            assert!(outer.contains(f), "{f:?}");
        }
        let mut regions = vec![0u16; cells.len()];
        let stats = insert_stars(&mut nodes, &mut cells, &mut regions, &constrained, 10.0, f64::INFINITY);
        assert_eq!((stats.caps_before, stats.caps_after), (1, 0), "{stats:?}");
        assert_eq!((stats.inserted, stats.caps_inserted), (1, 1), "{stats:?}");
        assert_eq!(nodes.len(), input.len() + 1);
        assert_eq!(&nodes[..input.len()], &input[..]);
        assert_eq!(regions.len(), cells.len());
        assert_kept(&nodes, &cells, &outer, before);
        assert!(cells.iter().all(|t| !(t.contains(&0) && t.contains(&1) && t.contains(&2) && t.contains(&3))));
        let lo = worst(&nodes, &cells);
        assert!(lo >= 17.0, "{lo}");
        let (lo_after, hi_after) = range(&nodes, &cells);
        assert!(lo_after >= lo_before && hi_after <= hi_before, "{lo_before}..{hi_before} -> {lo_after}..{hi_after}");
    }

    /// The point for a patch is the mean of the regular tets' apexes over its
    /// faces: over each face of a regular tet of edge 2, oriented into it, the
    /// apex is the opposite corner (the orientation of `FACE` points into the
    /// cell), so the point for the four is the tet's centroid (closed form;
    /// asserted within 1e-14 mm).
    #[test]
    fn the_patch_point_of_a_regular_tet_is_its_centroid() {
        let s = 2.0f64.sqrt();
        let nodes = vec![[1.0, 0.0, -1.0 / s], [-1.0, 0.0, -1.0 / s], [0.0, 1.0, 1.0 / s], [0.0, -1.0, 1.0 / s]];
        let t = positive(&nodes, [0, 1, 2, 3]);
        let faces = FACE.map(|f| f.map(|j| t[j]));
        let constrained = FaceSet::default();
        let w = Work {
            nodes: nodes.clone(),
            cells: CellStore::new(nodes.len(), vec![t], vec![0]),
            constrained: &constrained,
            max_volume: f64::INFINITY,
        };
        for (i, f) in faces.iter().enumerate() {
            let (centroid, offset) = regular_offset(f.map(|v| nodes[v as usize])).expect("regular face");
            let apex = [0, 1, 2].map(|k| centroid[k] + offset[k]);
            let corner = nodes[t[i] as usize];
            assert!(dot(sub(apex, corner), sub(apex, corner)).sqrt() < 1e-14, "face {i}: {apex:?} vs {corner:?}");
        }
        let p = w.patch_point(&faces).expect("regular faces");
        let centroid = [0, 1, 2].map(|k| nodes.iter().map(|q| q[k]).sum::<f64>() / 4.0);
        let err = dot(sub(p, centroid), sub(p, centroid)).sqrt();
        assert!(err < 1e-14, "{p:?} vs {centroid:?}: {err:e}");
        let flat = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert!(regular_offset(flat).is_none());
    }

    /// A wedge over a short hinge: `capped`'s cap with the hinge shortened
    /// to `ab`, `a = (0.2, 0, 0)`, `b = (-0.2, 0, 0)` (one edge under a third
    /// of the longest, `cd`), bent by `atan(e)` at `ab`.
    fn wedged(e: f64) -> (Vec<Point>, Vec<[u32; 4]>) {
        let (mut nodes, _) = capped(e);
        nodes[2] = [0.2, 0.0, 0.0];
        nodes[3] = [-0.2, 0.0, 0.0];
        let ring = [2, 3, 4, 5, 6];
        let cells = (0..5).map(|i| positive(&nodes, [0, 1, ring[i], ring[(i + 1) % 5]])).collect();
        (nodes, cells)
    }

    /// The points under a short hinge lie under its midpoint along the mean
    /// of its two faces' inner normals, at `sqrt(3) / 2` and half that times
    /// its length (closed form for `wedged(e)`: the normals of `abc` and `abd`
    /// are `(0, -e, 1)` and `(0, e, 1)` normalized, their mean is `+z`, so
    /// the points are `(0, 0, 0.4 sqrt(3) / 2)` and `(0, 0, 0.4 sqrt(3) / 4)`;
    /// asserted within 1e-12 mm). The edges `ac`, `ad`, `bc`, `bd` (over half
    /// the longest edge, one boundary face each) give none.
    #[test]
    fn points_under_a_short_hinge() {
        let (nodes, cells) = wedged(0.02);
        let constrained = hinge_faces();
        let w = Work {
            nodes: nodes.clone(),
            cells: CellStore::new(nodes.len(), cells.clone(), vec![0; cells.len()]),
            constrained: &constrained,
            max_volume: f64::INFINITY,
        };
        let under = w.under_short_edges(0, 2.0);
        let expected = [[0.0, 0.0, 0.4 * 3f64.sqrt() / 2.0], [0.0, 0.0, 0.4 * 3f64.sqrt() / 4.0]];
        assert_eq!(under.len(), 2, "{under:?}");
        for (p, q) in under.iter().zip(expected) {
            assert!(dot(sub(*p, q), sub(*p, q)).sqrt() < 1e-12, "{p:?} vs {q:?}");
        }
    }

    /// The wedge over a short hinge (`wedged(0.02)`, quality 1.15 deg) is
    /// removed by one star: the outer faces and the volume are kept (1e-12),
    /// every tet is positive (exact `orient3d`) and the worst quality rises to
    /// at least 28 deg (measured: 28.42, angles 28.42..119.79 deg; the same
    /// without the points under the hinge: this small ring does not need
    /// them, the armadillo's wedges are measured in BENCHMARKS.md).
    #[test]
    fn a_wedge_over_a_short_hinge_is_removed() {
        let (mut nodes, mut cells) = wedged(0.02);
        let before: f64 = cells.iter().map(|&t| volume_of(&nodes, t)).sum();
        let lo = worst(&nodes, &cells);
        assert!(lo < 1.2, "{lo}");
        let outer = outer_faces(&cells);
        let mut regions = vec![0u16; cells.len()];
        let stats = insert_stars(&mut nodes, &mut cells, &mut regions, &hinge_faces(), 10.0, f64::INFINITY);
        assert_eq!((stats.caps_after, stats.inserted), (0, 1), "{stats:?}");
        assert_kept(&nodes, &cells, &outer, before);
        let lo = worst(&nodes, &cells);
        assert!(lo >= 28.0, "worst quality {lo} deg, {:?}", range(&nodes, &cells));
    }

    /// What a star keeps: the outer faces `outer`, the volume `before`
    /// (within 1e-12) and every tet positive (exact `orient3d`).
    fn assert_kept(nodes: &[Point], cells: &[[u32; 4]], outer: &[[u32; 3]], before: f64) {
        assert_eq!(outer_faces(cells), outer);
        let after: f64 = cells.iter().map(|&t| volume_of(nodes, t)).sum();
        assert!((after - before).abs() < 1e-12, "{before} -> {after}");
        for &t in cells {
            let q = t.map(|v| nodes[v as usize]);
            assert_eq!(orient3d(q[0], q[1], q[2], q[3]), 1, "{t:?}");
        }
    }

    /// The smallest and largest dihedral angle of `cells` [deg].
    fn range(nodes: &[Point], cells: &[[u32; 4]]) -> (f64, f64) {
        cells
            .iter()
            .map(|&t| dihedral_range_deg(&t.map(|v| nodes[v as usize])))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (lo, hi)| (a.min(lo), b.max(hi)))
    }

    /// The same cap with the interior face `c d p` (p at 90 deg) constrained
    /// (a subfacet through the middle of the polyhedron): a point on `a`'s
    /// side of it, which the whole polyhedron would take as its cavity
    /// without that subfacet, is refused (its cavity would cross the
    /// subfacet), and whatever star insertion does, the subfacet stays a face.
    #[test]
    fn a_point_whose_cavity_would_cross_a_subfacet_is_refused() {
        let (nodes, cells) = capped(0.02);
        let p = [0.3, 0.0, 1.0];
        let free = hinge_faces();
        let mut split = hinge_faces();
        split.insert([0, 1, 5]);
        let work = |constrained| Work {
            nodes: nodes.clone(),
            cells: CellStore::new(nodes.len(), cells.clone(), vec![0; cells.len()]),
            constrained,
            max_volume: f64::INFINITY,
        };
        let open = work(&free).insertion(0, p, f64::INFINITY, true, 10.0).expect("star of p without the subfacet");
        assert_eq!(open.cavity.len(), 5);
        assert!(work(&split).insertion(0, p, f64::INFINITY, true, 10.0).is_none());
        let (mut nodes, mut cells) = (nodes.clone(), cells.clone());
        let before: f64 = cells.iter().map(|&t| volume_of(&nodes, t)).sum();
        let mut regions = vec![0u16; cells.len()];
        insert_stars(&mut nodes, &mut cells, &mut regions, &split, 10.0, f64::INFINITY);
        assert!(sorted_faces(&cells).contains(&[0, 1, 5]));
        let after: f64 = cells.iter().map(|&t| volume_of(&nodes, t)).sum();
        assert!((after - before).abs() < 1e-12, "{before} -> {after}");
    }

    /// The same cap in two regions (the cap's neighbours in another): the
    /// cavity cannot leave the cap, so nothing changes.
    #[test]
    fn no_insertion_across_regions() {
        let (mut nodes, mut cells) = capped(0.02);
        let kept = cells.clone();
        let mut regions = vec![0, 1, 1, 1, 1];
        let stats = insert_stars(&mut nodes, &mut cells, &mut regions, &hinge_faces(), 10.0, f64::INFINITY);
        assert_eq!(stats.inserted, 0);
        assert_eq!(cells, kept);
        assert_eq!(nodes.len(), 7);
    }

    /// The volume bound refuses stars with a tet over it: with a bound under
    /// the smallest star tet any candidate could make, nothing changes.
    #[test]
    fn the_volume_bound_is_kept() {
        let (mut nodes, mut cells) = capped(0.02);
        let kept = cells.clone();
        let mut regions = vec![0u16; 5];
        let stats = insert_stars(&mut nodes, &mut cells, &mut regions, &hinge_faces(), 10.0, 1e-3);
        assert_eq!(stats.inserted, 0);
        assert_eq!(cells, kept);
    }

    /// The circumcentre is equidistant from the corners.
    #[test]
    fn circumcentre_is_equidistant() {
        let q = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.2, 0.9, 0.0], [0.3, 0.1, 0.7]];
        let c = circumcentre(q).expect("not flat");
        let r: Vec<f64> = q.iter().map(|&x| dot(sub(x, c), sub(x, c)).sqrt()).collect();
        for x in &r {
            assert!((x - r[0]).abs() < 1e-12, "{r:?}");
        }
        assert!(circumcentre([q[0], q[1], q[2], [0.5, 0.5, 0.0]]).is_none());
    }
}
