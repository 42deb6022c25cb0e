//! Isosurface stuffing (Labelle and Shewchuk 2007, "Isosurface Stuffing: Fast
//! Tetrahedral Meshes with Good Dihedral Angles"), uniform BCC lattice.
//!
//! 1. **Signs.** Each lattice vertex is inside (`-`, winding number > 1/2,
//!    summed exactly where the fast value is within 0.1 of 1/2, as the quality
//!    report's distance decides it: `TriangleTree::is_inside_checked`),
//!    outside (`+`) or on the surface (`0`, closer than `eps` to a triangle).
//! 2. **Cut points.** On each lattice edge from a `-` to a `+` vertex, the point
//!    where the inside test changes, walking from the inside end: a crossing with
//!    a triangle (exact orient3d predicates), or, across a hole of an open surface
//!    where the winding number varies smoothly, the bisection of `w = 1/2`.
//! 3. **Warping.** A vertex `v` is *violated* by a cut point `c` on one of its edges
//!    `(v, x)` when `|v - c| < α |v - x|`, with `α_long = 0.24999` on long edges and
//!    `α_short = 0.41189` on short ones (the paper's values for the proven bounds,
//!    dihedral angles in [10.7°, 164.8°]). Vertices are visited in index order; a
//!    violated one moves to its nearest violating cut point and becomes `0`, which
//!    removes the cut points of its edges.
//! 4. **Stencils.** Each lattice tet with a `-` vertex is filled with the part of it
//!    on the inside: whole when it has no `+` vertex; else one tet (one `-`), a
//!    pyramid (`--0+`), or a prism (`--++`, `---+`). Quadrilateral faces on lattice
//!    faces are split by a rule that depends on the face only, so neighbours agree:
//!    when the face's long edge joins an outside and an inside vertex, the diagonal
//!    joins the cut point on that long edge to the other inside vertex; when it
//!    joins the two inside vertices, the *parity rule* alternates the diagonal's end
//!    around the long edge. Quadrilaterals on the isosurface are split the way that
//!    triangulates the prism with the best worst tet. A tet whose four vertices are
//!    all `0` is kept when its centroid is inside.

use rayon::prelude::*;

use super::lattice::Lattice;
use super::tree::{dot, lerp, sub, TriangleTree};

/// Warping threshold on long (axis-parallel) lattice edges.
pub const ALPHA_LONG: f64 = 0.24999;
/// Warping threshold on short (diagonal) lattice edges.
pub const ALPHA_SHORT: f64 = 0.41189;

type P = [f64; 3];

/// What the stuffing made, before compaction into a mesh.
#[derive(Debug, Clone, Default)]
pub(crate) struct Stuffed {
    /// Node positions [mm].
    pub nodes: Vec<P>,
    /// Tets, positively oriented.
    pub cells: Vec<[u32; 4]>,
    /// Counts for the report.
    pub num_lattice_vertices: usize,
    pub num_lattice_tets: usize,
    pub num_inside_vertices: usize,
    pub num_cut_points: usize,
    pub num_warped: usize,
}

/// Where on segment `a -> b` (`a` inside, `b` outside for `inside`) the inside test
/// changes first, walking from `a`: the parameter in [0, 1].
pub(crate) fn find_cut(tree: &TriangleTree, a: P, b: P) -> f64 {
    let inside = |t: f64| tree.is_inside_checked(lerp(a, b, t));
    let mut ts: Vec<f64> = Vec::new();
    for (t, _) in tree.segment_crossings(a, b) {
        if ts.last().is_none_or(|&l| t - l > 1e-12) {
            ts.push(t);
        }
    }
    // Probes: just before and after each crossing, then b; the state at a is inside.
    let mut prev_t = 0.0;
    for (i, &t) in ts.iter().enumerate() {
        let gap_before = if i == 0 { t } else { t - ts[i - 1] };
        let gap_after = if i + 1 < ts.len() { ts[i + 1] - t } else { 1.0 - t };
        let delta = (1e-7f64).min(0.25 * gap_before).min(0.25 * gap_after);
        let before = t - delta;
        let after = t + delta;
        if !inside(before) {
            return bisect(&inside, prev_t, before);
        }
        if !inside(after) {
            return t;
        }
        prev_t = after;
    }
    bisect(&inside, prev_t, 1.0)
}

/// The change of `inside` in `[lo, hi]` (inside at `lo`, outside at `hi`) by bisection.
fn bisect(inside: &impl Fn(f64) -> bool, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..48 {
        if hi - lo < 1e-9 {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if inside(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Output vertex of the cut point on lattice edge `(a, b)`.
struct Cuts {
    edges: Vec<(u32, u32)>,
    base: u32,
}

impl Cuts {
    fn id(&self, a: u32, b: u32) -> u32 {
        let key = if a < b { (a, b) } else { (b, a) };
        match self.edges.binary_search(&key) {
            Ok(i) => self.base + i as u32,
            // Every stencil asks only for edges from a `-` to a `+` vertex, all of
            // which have a cut point; this arm is unreachable by construction.
            Err(_) => u32::MAX,
        }
    }
}

/// A tetrahedral grid to stuff: the uniform BCC [`Lattice`] or the graded one
/// (`super::graded`). Its tets must be conforming and positively or negatively
/// oriented (the output is oriented afterwards).
pub(crate) trait Grid: Sync {
    fn num_vertices(&self) -> usize;
    fn position(&self, v: u32) -> P;
    /// The tets, in a fixed order.
    fn tets(&self) -> Vec<[u32; 4]>;
    /// The warping threshold of edge `(a, b)` (a fraction of its length).
    fn alpha(&self, a: u32, b: u32) -> f64;
    /// The distance from the edge's end to a cut point at parameter `t` along it.
    fn warp_distance(&self, a: u32, b: u32, t: f64) -> f64;
    /// Which inside vertex of face `(a, b, p)` (`a`, `b` inside, `p` outside) the
    /// diagonal of its quadrilateral `(a, b, c_bp, c_ap)` starts from: `a` or `b`.
    /// It must depend on the face only (both tets of a face agree) and, around
    /// each tet, leave no cycle (a prism with cyclic diagonals has no triangulation).
    fn diagonal_from(&self, a: u32, b: u32, p: u32) -> u32;
}

impl Grid for Lattice {
    fn num_vertices(&self) -> usize {
        Lattice::num_vertices(self)
    }
    fn position(&self, v: u32) -> P {
        Lattice::position(self, v)
    }
    fn tets(&self) -> Vec<[u32; 4]> {
        Lattice::tets(self)
    }
    fn alpha(&self, a: u32, b: u32) -> f64 {
        if self.is_long(a, b) {
            ALPHA_LONG
        } else {
            ALPHA_SHORT
        }
    }
    fn warp_distance(&self, a: u32, b: u32, t: f64) -> f64 {
        // Comparable across edges: the long/short length ratio is fixed.
        let d = t * self.h;
        if self.is_long(a, b) {
            d
        } else {
            d * 0.75f64.sqrt()
        }
    }
    fn diagonal_from(&self, a: u32, b: u32, p: u32) -> u32 {
        diagonal_from(self, a, b, p)
    }
}

/// Stuffs the inside of `tree` (winding number > 1/2) on a lattice of spacing `h`
/// [mm] covering the box `lo..hi` grown by `h`. `eps` [mm]: lattice vertices this
/// close to a triangle count as on the surface. `progress(fraction)` is called
/// between the phases.
pub(crate) fn stuff(tree: &TriangleTree, lo: P, hi: P, h: f64, eps: f64, progress: &(dyn Fn(f64) + Sync)) -> Stuffed {
    stuff_grid(&uniform_lattice(lo, hi, h), tree, eps, progress)
}

/// The uniform lattice of spacing `h` covering the box `lo..hi` grown by `h`, centred on it.
pub(crate) fn uniform_lattice(lo: P, hi: P, h: f64) -> Lattice {
    let margin = h;
    let mut n = [0usize; 3];
    let mut origin = [0.0; 3];
    for k in 0..3 {
        let span = (hi[k] - lo[k]).max(0.0) + 2.0 * margin;
        n[k] = ((span / h).ceil() as usize).max(2) + 1;
        // Centre the lattice on the box.
        origin[k] = 0.5 * (lo[k] + hi[k]) - 0.5 * n[k] as f64 * h;
    }
    Lattice { origin, h, n }
}

/// Stuffs the inside of `tree` on `lattice` (see the module docs).
pub(crate) fn stuff_grid(
    lattice: &impl Grid,
    tree: &TriangleTree,
    eps: f64,
    progress: &(dyn Fn(f64) + Sync),
) -> Stuffed {
    let nv = lattice.num_vertices();

    // 1. Signs.
    let mut sign: Vec<i8> = (0..nv as u32)
        .into_par_iter()
        .map(|v| {
            let p = lattice.position(v);
            // On the surface by distance alone (on a triangle, the winding number's
            // principal value is anything between 0 and 1).
            if tree.closest_point_within(p, eps).is_some() {
                0
            } else if tree.is_inside_checked(p) {
                -1
            } else {
                1
            }
        })
        .collect();
    progress(0.5);
    let num_inside_vertices = sign.iter().filter(|&&s| s < 0).count();

    // Lattice tets with an inside vertex, or with all four on the surface.
    let all_tets = lattice.tets();
    let num_lattice_tets = all_tets.len();
    let tets: Vec<[u32; 4]> = all_tets
        .into_iter()
        .filter(|t| t.iter().any(|&v| sign[v as usize] < 0) || t.iter().all(|&v| sign[v as usize] == 0))
        .collect();

    // 2. Cut points on the edges from `-` to `+`.
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for t in &tets {
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (t[i], t[j]);
                if sign[a as usize] * sign[b as usize] < 0 {
                    edges.push(if a < b { (a, b) } else { (b, a) });
                }
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    // For each edge: the cut point and its parameter from the edge's first vertex.
    let cut: Vec<(P, f64)> = edges
        .par_iter()
        .map(|&(a, b)| {
            let (pa, pb) = (lattice.position(a), lattice.position(b));
            if sign[a as usize] < 0 {
                let t = find_cut(tree, pa, pb);
                (lerp(pa, pb, t), t)
            } else {
                let t = find_cut(tree, pb, pa);
                (lerp(pb, pa, t), 1.0 - t)
            }
        })
        .collect();
    progress(0.8);

    // 3. Warping, in vertex order.
    let mut incident: Vec<Vec<u32>> = Vec::new();
    let mut slot: std::collections::BTreeMap<u32, usize> = std::collections::BTreeMap::new();
    for (e, &(a, b)) in edges.iter().enumerate() {
        for v in [a, b] {
            let s = *slot.entry(v).or_insert_with(|| {
                incident.push(Vec::new());
                incident.len() - 1
            });
            incident[s].push(e as u32);
        }
    }
    let mut warped_to: Vec<u32> = vec![u32::MAX; nv];
    let mut num_warped = 0;
    for (&v, &s) in &slot {
        let mut best: Option<(f64, u32)> = None;
        for &e in &incident[s] {
            let (a, b) = edges[e as usize];
            let other = if a == v { b } else { a };
            if warped_to[other as usize] != u32::MAX || sign[other as usize] == 0 || sign[v as usize] == 0 {
                continue;
            }
            let t = if a == v { cut[e as usize].1 } else { 1.0 - cut[e as usize].1 };
            if t < lattice.alpha(a, b) {
                let d = lattice.warp_distance(a, b, t);
                if best.is_none_or(|(bd, be)| d < bd || (d == bd && e < be)) {
                    best = Some((d, e));
                }
            }
        }
        if let Some((_, e)) = best {
            warped_to[v as usize] = e;
            sign[v as usize] = 0;
            num_warped += 1;
        }
    }

    // 4. Stencils.
    let cuts = Cuts { edges, base: nv as u32 };
    let position = |v: u32| -> P {
        if (v as usize) < nv {
            let e = warped_to[v as usize];
            if e == u32::MAX {
                lattice.position(v)
            } else {
                cut[e as usize].0
            }
        } else {
            cut[(v - cuts.base) as usize].0
        }
    };
    let pieces: Vec<Vec<[u32; 4]>> = tets
        .par_iter()
        .map(|t| {
            let mut out = Vec::new();
            fill(lattice, &sign, &cuts, t, &position, tree, &mut out);
            out
        })
        .collect();
    progress(0.95);

    // Compaction and orientation.
    let total = nv + cuts.edges.len();
    let mut used = vec![false; total];
    for p in &pieces {
        for t in p {
            for &v in t {
                used[v as usize] = true;
            }
        }
    }
    let mut new_id = vec![u32::MAX; total];
    let mut nodes = Vec::new();
    for v in 0..total {
        if used[v] {
            new_id[v] = nodes.len() as u32;
            nodes.push(position(v as u32));
        }
    }
    let mut cells = Vec::with_capacity(pieces.iter().map(Vec::len).sum());
    for p in pieces {
        for t in p {
            let mut c = t.map(|v| new_id[v as usize]);
            if signed_volume(&c.map(|v| nodes[v as usize])) < 0.0 {
                c.swap(2, 3);
            }
            cells.push(c);
        }
    }
    Stuffed {
        nodes,
        cells,
        num_lattice_vertices: nv,
        num_lattice_tets,
        num_inside_vertices,
        num_cut_points: cuts.edges.len(),
        num_warped,
    }
}

pub(crate) fn signed_volume(p: &[P; 4]) -> f64 {
    let u = sub(p[1], p[0]);
    let v = sub(p[2], p[0]);
    let w = sub(p[3], p[0]);
    dot(u, super::tree::cross(v, w)) / 6.0
}

/// Which inside vertex of face `(a, b, p)` (`a`, `b` inside, `p` outside) the
/// diagonal of its quadrilateral `(a, b, c_bp, c_ap)` starts from: `a` (diagonal
/// `a - c_bp`) or `b` (diagonal `b - c_ap`). Depends on the face only.
fn diagonal_from(lattice: &Lattice, a: u32, b: u32, p: u32) -> u32 {
    if lattice.is_long(a, p) {
        return b;
    }
    if lattice.is_long(b, p) {
        return a;
    }
    // The long edge is (a, b): the parity rule.
    let ca = lattice.coords(a);
    let cb = lattice.coords(b);
    let cp = lattice.coords(p);
    let k0 = (0..3).find(|&k| ca[k] != cb[k]).unwrap_or(0);
    let (k1, k2) = ((k0 + 1) % 3, (k0 + 2) % 3);
    let s = (cp[k1] > ca[k1]) ^ (cp[k2] > ca[k2]);
    let from_greater = s ^ lattice.is_red(a);
    let (greater, lesser) = if ca[k0] > cb[k0] { (a, b) } else { (b, a) };
    if from_greater {
        greater
    } else {
        lesser
    }
}

/// A shape measure in (0, 1] (1 for the regular tet): `6 √2 V / l_rms^3`, signed.
fn shape(p: &[P; 4]) -> f64 {
    let mut l2 = 0.0;
    for i in 0..4 {
        for j in i + 1..4 {
            let d = sub(p[i], p[j]);
            l2 += dot(d, d);
        }
    }
    let lrms = (l2 / 6.0).sqrt();
    if !(lrms > 0.0) {
        return -1.0;
    }
    6.0 * std::f64::consts::SQRT_2 * signed_volume(p).abs() / (lrms * lrms * lrms)
}

/// Triangulates the prism with bottom `u`, top `w` (vertical edges `u[i] - w[i]`)
/// whose side quad `i` (between verticals `i` and `i + 1`) has its diagonal at
/// bottom vertex `diag[i]` (`i`: `u[i] - w[i+1]`; `i + 1`: `u[i+1] - w[i]`), or free
/// (`None`): the acyclic choice with the best worst tet.
fn prism(u: [u32; 3], w: [u32; 3], diag: [Option<usize>; 3], position: &impl Fn(u32) -> P, out: &mut Vec<[u32; 4]>) {
    let mut best: Option<(f64, Vec<[u32; 4]>)> = None;
    for choice in 0..8usize {
        let mut d = [0usize; 3];
        let mut ok = true;
        for i in 0..3 {
            let bit = (choice >> i) & 1;
            let opt = if bit == 0 { i } else { (i + 1) % 3 };
            match diag[i] {
                Some(fixed) if fixed != opt => ok = false,
                _ => d[i] = opt,
            }
        }
        if !ok {
            continue;
        }
        let Some(tets) = prism_tets(u, w, d) else { continue };
        let q = tets.iter().map(|t| shape(&t.map(position))).fold(f64::INFINITY, f64::min);
        if best.as_ref().is_none_or(|(bq, _)| q > *bq) {
            best = Some((q, tets));
        }
    }
    if let Some((_, tets)) = best {
        out.extend(tets);
    }
}

fn prism_tets(u: [u32; 3], w: [u32; 3], d: [usize; 3]) -> Option<Vec<[u32; 4]>> {
    let quad_tris = |q: usize| -> [[u32; 3]; 2] {
        let q1 = (q + 1) % 3;
        if d[q] == q {
            [[u[q], u[q1], w[q1]], [u[q], w[q1], w[q]]]
        } else {
            [[u[q], u[q1], w[q]], [u[q1], w[q1], w[q]]]
        }
    };
    for j in 0..3 {
        let prev = (j + 2) % 3;
        let next = (j + 1) % 3;
        // Bottom vertex j carries the diagonals of quads prev and j.
        if d[prev] == j && d[j] == j {
            let [t1, t2] = quad_tris(next);
            return Some(vec![[u[j], w[0], w[1], w[2]], [u[j], t1[0], t1[1], t1[2]], [u[j], t2[0], t2[1], t2[2]]]);
        }
        // Top vertex j carries them: quad prev's diagonal is u[prev] - w[j]
        // (d[prev] == prev), quad j's is u[next] - w[j] (d[j] == next).
        if d[prev] == prev && d[j] == next {
            let [t1, t2] = quad_tris(next);
            return Some(vec![[w[j], u[0], u[1], u[2]], [w[j], t1[0], t1[1], t1[2]], [w[j], t2[0], t2[1], t2[2]]]);
        }
    }
    None
}

/// The stencil of lattice tet `t` (see the module docs).
fn fill(
    lattice: &impl Grid,
    sign: &[i8],
    cuts: &Cuts,
    t: &[u32; 4],
    position: &(impl Fn(u32) -> P + Sync),
    tree: &TriangleTree,
    out: &mut Vec<[u32; 4]>,
) {
    let s = t.map(|v| sign[v as usize]);
    let inside: Vec<u32> = (0..4).filter(|&i| s[i] < 0).map(|i| t[i]).collect();
    let zero: Vec<u32> = (0..4).filter(|&i| s[i] == 0).map(|i| t[i]).collect();
    let outside: Vec<u32> = (0..4).filter(|&i| s[i] > 0).map(|i| t[i]).collect();
    if outside.is_empty() {
        if !inside.is_empty() {
            out.push(*t);
        } else {
            let c = t.iter().fold([0.0; 3], |acc, &v| {
                let p = position(v);
                [acc[0] + 0.25 * p[0], acc[1] + 0.25 * p[1], acc[2] + 0.25 * p[2]]
            });
            // Four vertices warped onto one flat patch of the input make a flat
            // tet whose centroid is on the input (on the graded lattice, cells
            // smaller than the input's triangles): not kept.
            let mut longest: f64 = 0.0;
            for i in 0..4 {
                for j in i + 1..4 {
                    let d = sub(position(t[i]), position(t[j]));
                    longest = longest.max(dot(d, d).sqrt());
                }
            }
            if tree.is_inside_checked(c) && tree.closest_point_within(c, 1e-3 * longest).is_none() {
                out.push(*t);
            }
        }
        return;
    }
    let cut = |a: u32, b: u32| cuts.id(a, b);
    match (inside.len(), zero.len(), outside.len()) {
        (0, _, _) => {}
        (1, _, _) => {
            let a = inside[0];
            let mut tet = [a; 4];
            for (k, &v) in t.iter().filter(|&&v| v != a).enumerate() {
                tet[k + 1] = if sign[v as usize] == 0 { v } else { cut(a, v) };
            }
            out.push(tet);
        }
        (2, 1, 1) => {
            let (a, b, z, p) = (inside[0], inside[1], zero[0], outside[0]);
            let (cap, cbp) = (cut(a, p), cut(b, p));
            if lattice.diagonal_from(a, b, p) == a {
                out.push([z, a, b, cbp]);
                out.push([z, a, cbp, cap]);
            } else {
                out.push([z, a, b, cap]);
                out.push([z, b, cbp, cap]);
            }
        }
        (2, 0, 2) => {
            let (a, b, p, q) = (inside[0], inside[1], outside[0], outside[1]);
            let u = [a, cut(a, p), cut(a, q)];
            let w = [b, cut(b, p), cut(b, q)];
            // Quad 0 = face (a, b, p); quad 1 = the isosurface; quad 2 = face (a, b, q).
            let d0 = if lattice.diagonal_from(a, b, p) == a { 0 } else { 1 };
            let d2 = if lattice.diagonal_from(a, b, q) == a { 0 } else { 2 };
            prism(u, w, [Some(d0), None, Some(d2)], position, out);
        }
        (3, 0, 1) => {
            let p = outside[0];
            let u = [inside[0], inside[1], inside[2]];
            let w = u.map(|x| cut(x, p));
            let mut d = [None; 3];
            for i in 0..3 {
                let i1 = (i + 1) % 3;
                d[i] = Some(if lattice.diagonal_from(u[i], u[i1], p) == u[i] { i } else { i1 });
            }
            prism(u, w, d, position, out);
        }
        _ => {}
    }
    debug_assert!(out.iter().all(|t| t.iter().all(|&v| v != u32::MAX)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prism_refuses_cyclic_diagonals_and_triangulates_the_rest() {
        let u = [0, 1, 2];
        let w = [3, 4, 5];
        assert!(prism_tets(u, w, [0, 1, 2]).is_none());
        assert!(prism_tets(u, w, [1, 2, 0]).is_none());
        let mut n = 0;
        for c in 0..8usize {
            let d = [0, 1, 2].map(|i| if (c >> i) & 1 == 0 { i } else { (i + 1) % 3 });
            if let Some(t) = prism_tets(u, w, d) {
                n += 1;
                assert_eq!(t.len(), 3);
                // The volume of a unit right prism is 1/2.
                let pos = |v: u32| -> P {
                    let base = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
                    let b = base[(v % 3) as usize];
                    [b[0], b[1], if v >= 3 { 1.0 } else { 0.0 }]
                };
                let vol: f64 = t.iter().map(|t| signed_volume(&t.map(pos)).abs()).sum();
                assert!((vol - 0.5).abs() < 1e-12, "{d:?}: {vol}");
            }
        }
        assert_eq!(n, 6);
    }

    #[test]
    fn diagonals_alternate_around_a_long_edge() {
        let l = Lattice { origin: [0.0; 3], h: 1.0, n: [4, 4, 4] };
        // Black edge along x from (2,2,2) to (4,2,2) (doubled), four red apexes.
        let a = l.at([2, 2, 2]).unwrap();
        let b = l.at([4, 2, 2]).unwrap();
        let apex = [[3, 3, 3], [3, 1, 3], [3, 1, 1], [3, 3, 1]].map(|c| l.at(c).unwrap());
        let ends: Vec<u32> = apex.iter().map(|&p| diagonal_from(&l, a, b, p)).collect();
        for i in 0..4 {
            assert_ne!(ends[i], ends[(i + 1) % 4], "{ends:?}");
            assert_eq!(diagonal_from(&l, b, a, apex[i]), ends[i], "independent of the order of a and b");
        }
    }
}
