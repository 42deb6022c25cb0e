//! Boundary fitting: guarded refinement of the stuffed mesh's boundary towards the
//! input, until both directions of the Hausdorff distance are within a tolerance
//! or no guarded step is left.
//!
//! The stuffing's boundary nodes lie on the input, but its boundary triangles are
//! chords of size `h`: on curved parts they stray by about `h^2 κ / 8`, and sharp
//! edges, corners and thin tips of the input are cut off by up to about `h`
//! (measured on the bunny: the error falls only at first order in `h`, from the
//! faceted input's creases and its ears). Making the whole lattice finer costs
//! `h^-3` cells; this step refines where the distance is, only.
//!
//! Each round (sequential, in a fixed order: deterministic whatever the thread
//! count; only the distance queries run in parallel, collected in order):
//!
//! 1. **Candidates**, sorted by distance, largest first: a boundary edge whose
//!    midpoint, or a boundary triangle whose centroid, is farther than `tol` from
//!    the solid's true boundary (output -> input; for a triangle its edges,
//!    longest first), measured as the quality report does
//!    ([`crate::distance`]): the distance `d` to the input, or where that
//!    exceeds `tol` the smaller of `d` and the level-set probe along the face's
//!    normal within `d` ([`crate::distance::level_set_bound`], the exact
//!    inside test near `w = 1/2`), so a boundary over a cap `w = 1/2` (a hole,
//!    an open tube's mouth) counts by its distance to the level set, not to the
//!    hole's rim (with `d` alone such a boundary would be a candidate whose
//!    split pulls it towards the rim). Unlike the report's, `d` is
//!    to every input triangle, not to the bounding part only: a boundary inside
//!    the solid along input that bounds nothing (the teapot spout's wall inside
//!    the body) is not seen; and
//!    each input vertex farther than `tol` from the output (input -> output), with
//!    the edges of the nearest boundary triangle. Vertices of input triangles
//!    that bound nothing (the caps of overlapping parts inside each other) are
//!    left out, as in the quality report. After the first round only edges and
//!    triangles with a node of a changed tet, and the input vertices still far,
//!    are looked at again.
//! 2. **Carve** (output -> true boundary): the tet on a boundary
//!    face farther than `tol` is removed when its centroid is outside the solid
//!    (the exact inside test), each of its corners is in another tet too and is
//!    a boundary node or inside the solid (a node inside the mesh that comes to
//!    the boundary stays where it is: [`Mobility::Fixed`]), and the boundary
//!    stays manifold at its edges (each then in 0 or 2 boundary faces); the
//!    faces it exposes that are farther than `tol` are tried next, in order,
//!    so a void is carved out as deep as it is wider than `2 tol`. This is
//!    where the stuffing filled a void thinner than its lattice bounded by a
//!    level set (its lattice vertices warped onto the two walls, a tet with one
//!    corner inside and three on the walls kept whole): the teapot handle's
//!    mouth, between the body and the level set over the open tube
//!    (BENCHMARKS.md). Removing tets makes no new ones, so the angle guard holds.
//!    A tet straddling the void with corners inside the solid on both of its
//!    sides (its centroid inside) is not taken: cutting it along the void
//!    would be needed (not done).
//! 3. **Snap** (input -> output): the nearest corner of the nearest boundary
//!    triangle moves onto the far input vertex, when that is closer than half its
//!    shortest edge and every tet of it passes the guard below.
//! 4. **Split** (Rivara's longest-edge propagation): before edge `(a, b)` is split,
//!    the longer edges of the tets around it are split (up to [`LEPP_DEPTH`]
//!    levels), so that each tet is cut across its longest edge, which keeps the
//!    shapes. A split puts a new node on the edge; every tet around the edge is cut
//!    in two (`a` or `b` replaced by the new node), which keeps the mesh
//!    conforming. On the boundary the new node is the far input vertex (input ->
//!    output) or the input's closest point to the midpoint, within half the edge's
//!    length of the midpoint (not across a hole of an open input, and not so far
//!    that the new edges' chords stray more); inside it is the
//!    midpoint. A split or snap is taken only when **every tet it makes has its
//!    dihedral angles in [12°, 155°]** (the envelope targets;
//!    [`super::smooth::score`] >= 1). So the step never widens the angle range
//!    the stuffing and the interfaces left: that is the guarantee it keeps, and
//!    why it may stop short of `tol` (where the stuffing's tets leave no room:
//!    thin parts, tips). It stops when a round takes nothing.
//!
//! After the last round, **smoothing** ([`super::smooth::improve`]) of the tets
//! the splits left under its threshold, new nodes sliding along the input.
//!
//! Boundary edges are split only between two nodes that slide on the input (not
//! on a region interface, not across a hole); an inside edge between two fixed
//! (interface) nodes gets a fixed midpoint, so interfaces stay where they were.
//! The radius-edge ratio is not guarded (the envelope gates are angles):
//! measured, it grows (bunny at 0.3 mm: max 2.8 -> 6.7).

use std::collections::BTreeMap;

use rayon::prelude::*;

use super::smooth::{self, Mobility};
use super::tree::{add, norm, scale, sub, TriangleTree};
use crate::cells::CellStore;
use crate::distance::{level_set_bound, unit_normal};

type P = [f64; 3];

/// New tets must score at least this (dihedral angles in [12°, 155°]).
const GUARD: f64 = 1.0;

/// What the fitting did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct FitStats {
    pub rounds: usize,
    pub splits: usize,
    pub refused: usize,
    pub snaps: usize,
    /// Boundary tets outside the solid removed.
    pub carved: usize,
}

/// Refines the boundary of `nodes`/`cells` towards `input` (see the module docs).
/// `mobility` is extended for the new nodes, `regions` for the new cells;
/// `input_points`: the input vertices on triangles that bound the inside; `tol` [mm].
#[allow(clippy::too_many_arguments)]
pub(crate) fn fit(
    nodes: &mut Vec<P>,
    cells: &mut Vec<[u32; 4]>,
    regions: &mut Vec<u16>,
    mobility: &mut Vec<Mobility>,
    input: &TriangleTree,
    input_points: &[P],
    tol: f64,
    max_rounds: usize,
) -> FitStats {
    let mut stats = FitStats::default();
    let boundary = boundary_faces(cells).into_iter().map(|f| (sorted(f), f)).collect();
    let store = CellStore::new(nodes.len(), std::mem::take(cells), std::mem::take(regions));
    let mut w = Work { nodes, cells: store, mobility, input, touched: Vec::new(), boundary };
    // After the first round, only what the last round changed is looked at again:
    // edges and triangles with a touched node (a node of a changed tet), and the
    // input points that were still far.
    let mut touched: Option<Vec<bool>> = None;
    let mut far_points: Vec<P> = input_points.to_vec();
    for _ in 0..max_rounds {
        let faces: Vec<[u32; 3]> = w.boundary.values().copied().collect();
        let mut candidates: Vec<Candidate> = Vec::new();
        let mut snaps: Vec<(f64, [u32; 3], P)> = Vec::new();
        let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
        let movable = |w: &Work, v: u32| w.mobility[v as usize] == Mobility::OnSurface;
        // A boundary triangle's edges that may be split, longest first (ties by key).
        let longest_movable_edges = |w: &Work, f: [u32; 3]| -> Vec<(u32, u32)> {
            let mut e: Vec<(f64, (u32, u32))> = [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])]
                .into_iter()
                .filter(|&(a, b)| movable(w, a) && movable(w, b))
                .map(|(a, b)| (norm(sub(w.nodes[a as usize], w.nodes[b as usize])), key(a, b)))
                .collect();
            e.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
            e.into_iter().map(|x| x.1).collect()
        };
        // Output -> input: boundary edge midpoints (each with the first of its
        // faces, by index, for the level-set probe's direction).
        let mut edges: Vec<((u32, u32), usize)> = faces
            .iter()
            .enumerate()
            .flat_map(|(i, f)| [key(f[0], f[1]), key(f[1], f[2]), key(f[0], f[2])].map(|e| (e, i)))
            .collect();
        edges.par_sort_unstable();
        edges.dedup_by_key(|e| e.0);
        if let Some(t) = &touched {
            edges.retain(|&((a, b), _)| t[a as usize] || t[b as usize]);
        }
        let nodes: &[P] = w.nodes;
        let normal = |f: [u32; 3]| unit_normal(&f.map(|v| nodes[v as usize]));
        let far: Vec<f64> = edges
            .par_iter()
            .map(|&((a, b), f)| {
                let m = scale(add(nodes[a as usize], nodes[b as usize]), 0.5);
                to_true_boundary(input, m, normal(faces[f]), tol)
            })
            .collect();
        let edges: Vec<(u32, u32)> = edges.into_iter().map(|e| e.0).collect();
        let fresh = |v: u32| touched.as_ref().is_none_or(|t| t[v as usize]);
        for (&(a, b), &d) in edges.iter().zip(&far) {
            if d > tol && (fresh(a) || fresh(b)) && movable(&w, a) && movable(&w, b) {
                candidates.push((d, vec![(a, b)], None));
            }
        }
        // Output -> input: boundary triangle centroids (a tip can be far with its
        // edges near), the longest edge first.
        let nodes: &[P] = w.nodes;
        let far: Vec<f64> = faces
            .par_iter()
            .map(|f| {
                if !f.iter().any(|&v| fresh(v)) {
                    return 0.0;
                }
                let q = f.map(|v| nodes[v as usize]);
                let c = scale(add(add(q[0], q[1]), q[2]), 1.0 / 3.0);
                to_true_boundary(input, c, unit_normal(&q), tol)
            })
            .collect();
        let mut outside: Vec<(f64, [u32; 3])> = Vec::new();
        for (f, &d) in faces.iter().zip(&far) {
            if d <= tol {
                continue;
            }
            outside.push((d, *f));
            let e = longest_movable_edges(&w, *f);
            if !e.is_empty() {
                candidates.push((d, e, None));
            }
        }
        // Input -> output: the edges of the nearest boundary triangle, longest first.
        let out_tree = TriangleTree::new(faces.iter().map(|f| f.map(|v| w.nodes[v as usize])).collect());
        let near: Vec<Option<(P, f64, u32)>> = far_points.par_iter().map(|&p| out_tree.closest_point(p)).collect();
        let mut still_far = Vec::new();
        for (&p, near) in far_points.iter().zip(near) {
            let Some((_, d, t)) = near else { continue };
            if d <= tol {
                continue;
            }
            still_far.push(p);
            let f = faces[t as usize];
            snaps.push((d, f, p));
            let e = longest_movable_edges(&w, f);
            if !e.is_empty() {
                candidates.push((d, e, Some(p)));
            }
        }
        far_points = still_far;
        if candidates.is_empty() && outside.is_empty() {
            break;
        }
        w.touched = vec![false; w.nodes.len()];
        // Output -> true boundary, first: boundary tets outside the solid carved
        // off, the farthest face first.
        outside.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        let carved = w.carve(outside.into_iter().map(|x| x.1).collect(), tol);
        stats.carved += carved;
        // Input -> output, first: the nearest corner of the nearest boundary
        // triangle moved onto the input vertex, if the guard allows.
        snaps.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        let snaps_before = stats.snaps;
        for (_, f, p) in snaps {
            let mut corners = f;
            corners.sort_by(|&x, &y| {
                norm(sub(w.nodes[x as usize], p)).total_cmp(&norm(sub(w.nodes[y as usize], p))).then(x.cmp(&y))
            });
            for v in corners {
                if w.mobility[v as usize] == Mobility::OnSurface && w.snap(v, p) {
                    stats.snaps += 1;
                    break;
                }
            }
        }
        candidates.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        stats.rounds += 1;
        let before = w.nodes.len();
        for (_, edges, point) in candidates {
            // The first edge the guard allows.
            if !edges.into_iter().any(|(a, b)| w.refine(a, b, point, LEPP_DEPTH)) {
                stats.refused += 1;
            }
        }
        let added = w.nodes.len() - before;
        stats.splits += added;
        if added == 0 && stats.snaps == snaps_before && carved == 0 {
            break;
        }
        touched = Some(std::mem::take(&mut w.touched));
    }
    (*cells, *regions) = w.cells.into_live();
    if stats.rounds > 0 {
        smooth::improve(w.nodes, cells, w.mobility, input);
    }
    stats
}

/// The fitting's estimate of the distance from `p`, on a boundary face with
/// unit normal `n`, to the solid's true boundary, as the quality report
/// measures it ([`crate::distance`]; an upper bound where the nearest input
/// bounds the solid: `d` counts every input triangle, also those that bound
/// nothing, which the report leaves out): its distance `d` to the input, or where that exceeds
/// `tol`, the smaller of `d` and the level-set probe along `n` within `d`
/// ([`level_set_bound`], to 1e-2 of `tol`; stopped once below `tol`).
fn to_true_boundary(input: &TriangleTree, p: P, n: Option<P>, tol: f64) -> f64 {
    let Some((_, d, _)) = input.closest_point(p) else { return 0.0 };
    match n {
        Some(n) if d > tol => {
            let inside = |q: P| input.is_inside_checked(q);
            d.min(level_set_bound(&inside, p, n, d, tol, 1e-2 * tol))
        }
        _ => d,
    }
}

/// A split candidate: its distance [mm], the edges to try in order, the input
/// vertex to put the new node on (else the input's closest point to the midpoint).
type Candidate = (f64, Vec<(u32, u32)>, Option<P>);

/// How deep the longest-edge propagation goes.
const LEPP_DEPTH: usize = 4;

struct Work<'a> {
    nodes: &'a mut Vec<P>,
    /// The cells (splits keep every slot; carving kills some) and their regions.
    cells: CellStore,
    mobility: &'a mut Vec<Mobility>,
    input: &'a TriangleTree,
    /// Nodes of the tets changed in this round (new nodes included).
    touched: Vec<bool>,
    /// The boundary faces (in one cell only), oriented as in their cell, by their sorted corners.
    boundary: BTreeMap<[u32; 3], [u32; 3]>,
}

fn sorted(mut f: [u32; 3]) -> [u32; 3] {
    f.sort_unstable();
    f
}

impl Work<'_> {
    fn touch(&mut self, v: u32) {
        let v = v as usize;
        if v >= self.touched.len() {
            self.touched.resize(v + 1, false);
        }
        self.touched[v] = true;
    }
}

impl Work<'_> {
    fn around(&self, a: u32, b: u32) -> Vec<u32> {
        self.cells.around(a, b).collect()
    }

    /// Moves node `v` to `p` if every tet of it then scores at least [`GUARD`] and
    /// `p` is closer than half its shortest edge (farther, its boundary edges
    /// lengthen and their chords stray: measured on the sphere). Returns whether it did.
    fn snap(&mut self, v: u32, p: P) -> bool {
        let here = self.nodes[v as usize];
        let shortest = self.cells.star[v as usize]
            .iter()
            .flat_map(|&k| self.cells.cells[k as usize])
            .filter(|&x| x != v)
            .map(|x| norm(sub(self.nodes[x as usize], here)))
            .fold(f64::INFINITY, f64::min);
        if !(norm(sub(p, here)) < 0.5 * shortest) {
            return false;
        }
        self.nodes[v as usize] = p;
        let ok = self.cells.star[v as usize]
            .iter()
            .all(|&k| smooth::score(&self.cells.cells[k as usize].map(|x| self.nodes[x as usize])) >= GUARD);
        if !ok {
            self.nodes[v as usize] = here;
        } else {
            let around: Vec<u32> =
                self.cells.star[v as usize].iter().flat_map(|&k| self.cells.cells[k as usize]).collect();
            for x in around {
                self.touch(x);
            }
        }
        ok
    }

    /// Carves boundary tets outside the solid (module docs): from the faces
    /// `outside` (their true-boundary distance > `tol`, farthest first), then
    /// from the faces each removal exposes that are farther than `tol` too, in
    /// the order they come. Returns how many tets it removed.
    fn carve(&mut self, outside: Vec<[u32; 3]>, tol: f64) -> usize {
        let mut queue: std::collections::VecDeque<[u32; 3]> = outside.into();
        let mut carved = 0;
        while let Some(f) = queue.pop_front() {
            let Some(exposed) = self.carve_at(f) else { continue };
            carved += 1;
            for g in exposed {
                let q = g.map(|v| self.nodes[v as usize]);
                let centroid = scale(add(add(q[0], q[1]), q[2]), 1.0 / 3.0);
                if to_true_boundary(self.input, centroid, unit_normal(&q), tol) > tol {
                    queue.push_back(g);
                }
            }
        }
        carved
    }

    /// Removes the tet on boundary face `f` when its centroid is outside the
    /// solid, each of its corners is in another tet too (no node leaves the
    /// mesh) and is on the boundary already or inside the solid, and the
    /// boundary stays manifold at its edges (each then in 0 or 2 boundary
    /// faces). Returns the faces it exposed, if it did.
    fn carve_at(&mut self, f: [u32; 3]) -> Option<Vec<[u32; 3]>> {
        if !self.boundary.contains_key(&sorted(f)) {
            return None;
        }
        let k = self.cells.around(f[0], f[1]).find(|&k| self.cells.cells[k as usize].contains(&f[2]))?;
        let c = self.cells.cells[k as usize];
        let p = c.map(|v| self.nodes[v as usize]);
        if self.input.is_inside_checked(scale(add(add(p[0], p[1]), add(p[2], p[3])), 0.25)) {
            return None;
        }
        let keeps = |v: u32| {
            self.cells.star[v as usize].len() > 1
                && (self.mobility[v as usize] != Mobility::Free || self.input.is_inside_checked(self.nodes[v as usize]))
        };
        if !c.iter().all(|&v| keeps(v)) {
            return None;
        }
        // The tet's faces, as `boundary_faces` orients them, and whether each is on the boundary now.
        let faces: [[u32; 3]; 4] = std::array::from_fn(|i| [c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]]);
        let on: [bool; 4] = faces.map(|g| self.boundary.contains_key(&sorted(g)));
        // After the removal, an edge of the tet is in as many boundary faces as
        // before, minus the tet's boundary faces at it, plus its exposed ones.
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (c[i], c[j]);
                let change: isize = faces
                    .iter()
                    .zip(&on)
                    .filter(|(g, _)| g.contains(&a) && g.contains(&b))
                    .map(|(_, &was)| if was { -1 } else { 1 })
                    .sum();
                let after = self.boundary_faces_at(a, b) as isize + change;
                if after != 0 && after != 2 {
                    return None;
                }
            }
        }
        self.cells.kill(k);
        // A node inside the mesh comes to the boundary: it stays where it is.
        for v in c {
            if self.mobility[v as usize] == Mobility::Free {
                self.mobility[v as usize] = Mobility::Fixed;
            }
            self.touch(v);
        }
        let mut exposed = Vec::new();
        for (g, &was) in faces.iter().zip(&on) {
            if was {
                self.boundary.remove(&sorted(*g));
            } else {
                // Reversed from the removed tet's face (the stored faces are not
                // consistently oriented; the level-set probe looks both ways).
                let h = [g[0], g[2], g[1]];
                self.boundary.insert(sorted(h), h);
                exposed.push(h);
            }
        }
        Some(exposed)
    }

    /// The boundary faces at edge `(a, b)`.
    fn boundary_faces_at(&self, a: u32, b: u32) -> usize {
        let mut third: Vec<u32> =
            self.cells.around(a, b).flat_map(|k| self.cells.cells[k as usize]).filter(|&v| v != a && v != b).collect();
        third.sort_unstable();
        third.dedup();
        third.iter().filter(|&&x| self.boundary.contains_key(&sorted([a, b, x]))).count()
    }

    fn length(&self, a: u32, b: u32) -> f64 {
        norm(sub(self.nodes[a as usize], self.nodes[b as usize]))
    }

    /// Splits edge `(a, b)` after splitting, longest-edge first (Rivara's LEPP, up
    /// to `depth` levels), the longest edges of the tets around it that are longer,
    /// so that the split cuts each tet across its longest edge. Returns whether
    /// `(a, b)` was split.
    fn refine(&mut self, a: u32, b: u32, point: Option<P>, depth: usize) -> bool {
        let lab = self.length(a, b);
        for _ in 0..16 {
            let around = self.around(a, b);
            if around.is_empty() {
                return false;
            }
            let mut longer: Option<(f64, (u32, u32))> = None;
            for &k in &around {
                let c = self.cells.cells[k as usize];
                for i in 0..4 {
                    for j in i + 1..4 {
                        let (x, y) = if c[i] < c[j] { (c[i], c[j]) } else { (c[j], c[i]) };
                        let l = self.length(x, y);
                        if l > lab * (1.0 + 1e-9) && longer.is_none_or(|(bl, be)| l > bl || (l == bl && (x, y) < be)) {
                            longer = Some((l, (x, y)));
                        }
                    }
                }
            }
            match longer {
                None => return self.split(a, b, point),
                Some((_, (x, y))) => {
                    if depth == 0 || !self.refine(x, y, None, depth - 1) {
                        return false;
                    }
                }
            }
        }
        false
    }

    /// Splits edge `(a, b)`: on the boundary at `point` (an input vertex) or else
    /// the input's closest point to its midpoint, inside at its midpoint, if the
    /// guard allows (see the module docs). Returns whether it did.
    fn split(&mut self, a: u32, b: u32, point: Option<P>) -> bool {
        let around = self.around(a, b);
        if around.is_empty() {
            return false;
        }
        // On the boundary when a face (a, b, x) is in one tet only.
        let mut third: Vec<u32> = Vec::with_capacity(2 * around.len());
        for &k in &around {
            third.extend(self.cells.cells[k as usize].iter().copied().filter(|&v| v != a && v != b));
        }
        third.sort_unstable();
        let single: Vec<u32> =
            third.iter().copied().filter(|&x| third.iter().filter(|&&y| y == x).count() == 1).collect();
        let on_boundary = !single.is_empty();
        let (ma, mb) = (self.mobility[a as usize], self.mobility[b as usize]);
        let (pa, pb) = (self.nodes[a as usize], self.nodes[b as usize]);
        let mid = scale(add(pa, pb), 0.5);
        let (target, mobility) = if on_boundary {
            if !(ma == Mobility::OnSurface && mb == Mobility::OnSurface) {
                return false;
            }
            let target = match point {
                Some(p) => p,
                None => match self.input.closest_point(mid) {
                    Some((c, _, _)) => c,
                    None => return false,
                },
            };
            if !(norm(sub(target, mid)) <= 0.5 * norm(sub(pa, pb))) {
                return false;
            }
            (target, Mobility::OnSurface)
        } else if ma == Mobility::Fixed && mb == Mobility::Fixed {
            // Possibly along a region interface: the midpoint stays on it.
            (mid, Mobility::Fixed)
        } else {
            (mid, Mobility::Free)
        };
        let m = self.nodes.len() as u32;
        let at = |v: u32| if v == m { target } else { self.nodes[v as usize] };
        let replaced = |c: [u32; 4], from: u32| c.map(|v| if v == from { m } else { v });
        for &k in &around {
            let c = self.cells.cells[k as usize];
            for from in [a, b] {
                if !(smooth::score(&replaced(c, from).map(at)) >= GUARD) {
                    return false;
                }
            }
        }
        self.nodes.push(target);
        self.mobility.push(mobility);
        self.cells.add_node();
        self.touch(m);
        for x in single {
            if let Some(f) = self.boundary.remove(&sorted([a, b, x])) {
                for from in [a, b] {
                    let g = f.map(|v| if v == from { m } else { v });
                    self.boundary.insert(sorted(g), g);
                }
            }
        }
        for &k in &around {
            for v in self.cells.cells[k as usize] {
                self.touch(v);
            }
        }
        self.cells.bisect(a, b, m, &around);
        true
    }
}

/// The faces in exactly one cell, sorted (deterministic), oriented as in their cell.
fn boundary_faces(cells: &[[u32; 4]]) -> Vec<[u32; 3]> {
    let mut faces: Vec<([u32; 3], [u32; 3])> = Vec::with_capacity(4 * cells.len());
    for c in cells {
        for i in 0..4 {
            let f = [c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]];
            let mut s = f;
            s.sort_unstable();
            faces.push((s, f));
        }
    }
    faces.par_sort_unstable_by(|x, y| x.0.cmp(&y.0));
    let mut out = Vec::new();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j].0 == faces[i].0 {
            j += 1;
        }
        if j - i == 1 {
            out.push(faces[i].1);
        }
        i = j;
    }
    out
}
