//! Cutting a tetrahedral mesh along an interface (a closed shell or a plane) so
//! that no cell crosses it: the interface becomes a conforming set of faces.
//!
//! The same three steps as isosurface stuffing, on any mesh:
//!
//! 1. each node is inside (`-`), outside (`+`) or on the interface (`0`);
//! 2. each edge from `-` to `+` gets a cut point on the interface;
//! 3. a node closer to a cut point of one of its edges than `alpha` times the
//!    edge's length moves onto it (and becomes `0`), unless the node is locked
//!    (on an earlier interface), the node is on the mesh's boundary and the edge
//!    is not (the boundary keeps its shape), or the move would make one of its
//!    cells inverted or worse than [`MIN_SHAPE`] (when it was not already);
//! 4. every cell with both `-` and `+` nodes is split along the cut points into
//!    tets, pyramids and prisms, each quadrilateral split by the diagonal through
//!    its smallest node index (a rule of the face alone, so neighbours agree, and
//!    one that never makes a prism's diagonals cyclic).
//!
//! Unlike the stuffing of the outer surface, the quality of the split cells has
//! no proven bound; the quality report measures it.

use rayon::prelude::*;

use super::stuffing::signed_volume;
use super::tree::{dot, lerp, sub};

type P = [f64; 3];

/// The warp threshold: a fraction of the edge's length.
pub(crate) const ALPHA: f64 = 0.3;
/// The worst shape (`6 √2 V / l_rms^3`) a warp may leave.
pub(crate) const MIN_SHAPE: f64 = 0.25;

/// An interface: which side a point is on and where a segment crosses it.
pub(crate) trait Interface: Sync {
    /// -1 inside, 0 on, +1 outside.
    fn side(&self, p: P) -> i8;
    /// The crossing of segment `a` (inside) -> `b` (outside).
    fn cut(&self, a: P, b: P) -> P;
}

/// The mesh being cut.
#[derive(Debug, Clone, Default)]
pub(crate) struct Work {
    pub nodes: Vec<P>,
    pub cells: Vec<[u32; 4]>,
    /// Nodes that may not move (on an earlier interface). Boundary nodes move
    /// only along boundary edges.
    pub locked: Vec<bool>,
}

/// Where each new node came from: the edge `(a, b)` it was cut on.
pub(crate) struct CutResult {
    /// The side of every node (old and new) after the cut: `0` for cut points and moved nodes.
    pub side: Vec<i8>,
    /// For each new node (index `old_len + k`), the edge it lies on.
    pub new_nodes_from: Vec<(u32, u32)>,
    /// Nodes moved onto the interface.
    pub num_moved: usize,
}

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
    6.0 * std::f64::consts::SQRT_2 * signed_volume(p) / (lrms * lrms * lrms)
}

/// Cuts `work` along `iface` (see the module docs).
pub(crate) fn cut(work: &mut Work, iface: &dyn Interface) -> CutResult {
    let nv = work.nodes.len();
    let mut side: Vec<i8> = work.nodes.par_iter().map(|&p| iface.side(p)).collect();

    // Crossing edges and their cut points.
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for t in &work.cells {
        for i in 0..4 {
            for j in i + 1..4 {
                let (a, b) = (t[i], t[j]);
                if side[a as usize] * side[b as usize] < 0 {
                    edges.push(if a < b { (a, b) } else { (b, a) });
                }
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let nodes = &work.nodes;
    let cut_at: Vec<(P, f64)> = edges
        .par_iter()
        .map(|&(a, b)| {
            let (pa, pb) = (nodes[a as usize], nodes[b as usize]);
            let c = if side[a as usize] < 0 { iface.cut(pa, pb) } else { iface.cut(pb, pa) };
            // Parameter from a, measured along the edge.
            let d = sub(pb, pa);
            let t = (dot(sub(c, pa), d) / dot(d, d)).clamp(0.0, 1.0);
            (lerp(pa, pb, t), t)
        })
        .collect();

    // Node -> cells, for the warp checks.
    let mut start = vec![0u32; nv + 1];
    for t in &work.cells {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..nv {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut node_cells = vec![0u32; start[nv] as usize];
    for (c, t) in work.cells.iter().enumerate() {
        for &v in t {
            node_cells[fill[v as usize] as usize] = c as u32;
            fill[v as usize] += 1;
        }
    }
    let mut incident: Vec<Vec<u32>> = Vec::new();
    let mut slot = std::collections::BTreeMap::<u32, usize>::new();
    for (e, &(a, b)) in edges.iter().enumerate() {
        for v in [a, b] {
            let s = *slot.entry(v).or_insert_with(|| {
                incident.push(Vec::new());
                incident.len() - 1
            });
            incident[s].push(e as u32);
        }
    }

    // Boundary edges: a boundary node may move only along them, so the boundary
    // keeps its shape (the cut point lies on a boundary triangle's edge).
    let mut faces: Vec<[u32; 3]> = Vec::with_capacity(4 * work.cells.len());
    for c in &work.cells {
        for i in 0..4 {
            let mut f = [c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]];
            f.sort_unstable();
            faces.push(f);
        }
    }
    faces.par_sort_unstable();
    let mut on_boundary = vec![false; nv];
    let mut boundary_edges: Vec<(u32, u32)> = Vec::new();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j] == faces[i] {
            j += 1;
        }
        if j - i == 1 {
            let f = faces[i];
            for v in f {
                on_boundary[v as usize] = true;
            }
            boundary_edges.extend([(f[0], f[1]), (f[1], f[2]), (f[0], f[2])]);
        }
        i = j;
    }
    drop(faces);
    boundary_edges.sort_unstable();
    boundary_edges.dedup();

    // Warping, in node order.
    let mut num_moved = 0;
    for (&v, &s) in &slot {
        if work.locked[v as usize] || side[v as usize] == 0 {
            continue;
        }
        let mut cands: Vec<(f64, u32)> = Vec::new();
        for &e in &incident[s] {
            let (a, b) = edges[e as usize];
            let other = if a == v { b } else { a };
            if side[other as usize] == 0 {
                continue;
            }
            if on_boundary[v as usize] && boundary_edges.binary_search(&(a, b)).is_err() {
                continue;
            }
            let t = if a == v { cut_at[e as usize].1 } else { 1.0 - cut_at[e as usize].1 };
            if t < ALPHA {
                let d = sub(work.nodes[b as usize], work.nodes[a as usize]);
                cands.push((t * dot(d, d).sqrt(), e));
            }
        }
        cands.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let cells_of_v = &node_cells[start[v as usize] as usize..start[v as usize + 1] as usize];
        let old = work.nodes[v as usize];
        let old_min = cells_of_v
            .iter()
            .map(|&c| shape(&work.cells[c as usize].map(|x| work.nodes[x as usize])))
            .fold(f64::INFINITY, f64::min);
        for (_, e) in cands {
            work.nodes[v as usize] = cut_at[e as usize].0;
            let new_min = cells_of_v
                .iter()
                .map(|&c| shape(&work.cells[c as usize].map(|x| work.nodes[x as usize])))
                .fold(f64::INFINITY, f64::min);
            if new_min > 0.0 && new_min >= old_min.min(MIN_SHAPE) {
                side[v as usize] = 0;
                num_moved += 1;
                break;
            }
            work.nodes[v as usize] = old;
        }
    }

    // Splitting. Cut points get ids nv + edge index; only edges still crossing are used.
    let cut_id = |a: u32, b: u32| -> u32 {
        let key = if a < b { (a, b) } else { (b, a) };
        edges.binary_search(&key).map(|i| nv as u32 + i as u32).unwrap_or(u32::MAX)
    };
    let position = |v: u32| -> P {
        if (v as usize) < nv {
            work.nodes[v as usize]
        } else {
            cut_at[v as usize - nv].0
        }
    };
    let pieces: Vec<Vec<[u32; 4]>> = work
        .cells
        .par_iter()
        .map(|t| {
            let s = t.map(|v| side[v as usize]);
            if !(s.contains(&-1) && s.contains(&1)) {
                return vec![*t];
            }
            let mut out = Vec::new();
            part(t, &s, &cut_id, &mut out);
            let neg = s.map(|x| -x);
            part(t, &neg, &cut_id, &mut out);
            out
        })
        .collect();

    // Renumber: old nodes keep their ids, used cut points follow in edge order.
    let mut used = vec![false; edges.len()];
    for p in &pieces {
        for t in p {
            for &v in t {
                if v as usize >= nv && v != u32::MAX {
                    used[v as usize - nv] = true;
                }
            }
        }
    }
    let mut new_id = vec![u32::MAX; edges.len()];
    let mut new_nodes_from = Vec::new();
    let mut new_positions = Vec::new();
    for (e, &u) in used.iter().enumerate() {
        if u {
            new_id[e] = (nv + new_nodes_from.len()) as u32;
            new_nodes_from.push(edges[e]);
            new_positions.push(position((nv + e) as u32));
        }
    }
    let mut cells = Vec::with_capacity(pieces.iter().map(Vec::len).sum());
    for p in pieces {
        for t in p {
            let mut c = t.map(|v| if (v as usize) < nv { v } else { new_id[v as usize - nv] });
            let pts =
                c.map(|v| if (v as usize) < nv { work.nodes[v as usize] } else { new_positions[v as usize - nv] });
            let vol = signed_volume(&pts);
            if vol < 0.0 {
                c.swap(2, 3);
            }
            // Split pieces of zero volume (a cut through a node) are dropped: they
            // cover nothing, and their faces are covered by the neighbours' pieces.
            if vol != 0.0 {
                cells.push(c);
            }
        }
    }
    side.extend(std::iter::repeat_n(0, new_nodes_from.len()));
    work.nodes.extend(new_positions);
    let num_new = new_nodes_from.len();
    work.locked.extend(std::iter::repeat_n(true, num_new));
    work.cells = cells;
    CutResult { side, new_nodes_from, num_moved }
}

/// Quad `(x0, x1, x2, x3)` (cyclic): whether its diagonal is `x0 - x2` (through the
/// smallest index) rather than `x1 - x3`.
fn diagonal_02(x: [u32; 4]) -> bool {
    let m = *x.iter().min().unwrap_or(&0);
    m == x[0] || m == x[2]
}

/// Appends the tets of the part of cell `t` where `s < 0`, given that it has both
/// `-` and `+` nodes.
fn part(t: &[u32; 4], s: &[i8; 4], cut_id: &impl Fn(u32, u32) -> u32, out: &mut Vec<[u32; 4]>) {
    let inside: Vec<u32> = (0..4).filter(|&i| s[i] < 0).map(|i| t[i]).collect();
    let zero: Vec<u32> = (0..4).filter(|&i| s[i] == 0).map(|i| t[i]).collect();
    let outside: Vec<u32> = (0..4).filter(|&i| s[i] > 0).map(|i| t[i]).collect();
    match (inside.len(), zero.len(), outside.len()) {
        (1, _, _) => {
            let a = inside[0];
            let mut tet = [a; 4];
            for (k, (&v, &sv)) in t.iter().zip(s).filter(|(&v, _)| v != a).enumerate() {
                tet[k + 1] = if sv == 0 { v } else { cut_id(a, v) };
            }
            out.push(tet);
        }
        (2, 1, 1) => {
            let (a, b, z, p) = (inside[0], inside[1], zero[0], outside[0]);
            let (cap, cbp) = (cut_id(a, p), cut_id(b, p));
            // Quad (a, b, cbp, cap).
            if diagonal_02([a, b, cbp, cap]) {
                out.push([z, a, b, cbp]);
                out.push([z, a, cbp, cap]);
            } else {
                out.push([z, a, b, cap]);
                out.push([z, b, cbp, cap]);
            }
        }
        (2, 0, 2) => {
            let (a, b, p, q) = (inside[0], inside[1], outside[0], outside[1]);
            let u = [a, cut_id(a, p), cut_id(a, q)];
            let w = [b, cut_id(b, p), cut_id(b, q)];
            prism_min_index(u, w, out);
        }
        (3, 0, 1) => {
            let p = outside[0];
            let u = [inside[0], inside[1], inside[2]];
            let w = u.map(|x| cut_id(x, p));
            prism_min_index(u, w, out);
        }
        _ => {}
    }
}

/// The prism with bottom `u` and top `w` (vertical edges `u[i] - w[i]`), each side
/// quad split through its smallest index: cone from the prism's smallest vertex.
fn prism_min_index(u: [u32; 3], w: [u32; 3], out: &mut Vec<[u32; 4]>) {
    // The smallest vertex lies on two quads whose diagonals both pass through it;
    // coning from it over the faces not containing it gives three tets.
    let all = [u[0], u[1], u[2], w[0], w[1], w[2]];
    let Some(k) = (0..6).min_by_key(|&i| all[i]) else { return };
    let (j, bottom) = if k < 3 { (k, true) } else { (k - 3, false) };
    let apex = all[k];
    let next = (j + 1) % 3;
    let prev = (j + 2) % 3;
    // The quad opposite the apex: between verticals next and prev.
    let q = [u[next], u[prev], w[prev], w[next]];
    let tris = if diagonal_02(q) {
        [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    } else {
        [[q[0], q[1], q[3]], [q[1], q[2], q[3]]]
    };
    let cap = if bottom { w } else { u };
    out.push([apex, cap[0], cap[1], cap[2]]);
    for t in tris {
        out.push([apex, t[0], t[1], t[2]]);
    }
}

/// A plane `y = c` [mm]: below is inside.
pub(crate) struct PlaneY {
    pub y: f64,
    pub eps: f64,
}

impl Interface for PlaneY {
    fn side(&self, p: P) -> i8 {
        if (p[1] - self.y).abs() <= self.eps {
            0
        } else if p[1] < self.y {
            -1
        } else {
            1
        }
    }
    fn cut(&self, a: P, b: P) -> P {
        let t = ((self.y - a[1]) / (b[1] - a[1])).clamp(0.0, 1.0);
        let mut c = lerp(a, b, t);
        c[1] = self.y;
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn volume(w: &Work) -> f64 {
        w.cells.iter().map(|c| signed_volume(&c.map(|v| w.nodes[v as usize]))).sum()
    }

    #[test]
    fn a_plane_cut_keeps_the_volume_and_no_cell_crosses_it() {
        // Five tets of a unit cube.
        let nodes = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let mut cells = vec![[0, 1, 2, 4], [1, 3, 2, 7], [1, 5, 4, 7], [2, 6, 7, 4], [1, 2, 4, 7]];
        for c in &mut cells {
            if signed_volume(&c.map(|v: u32| nodes[v as usize])) < 0.0 {
                c.swap(2, 3);
            }
        }
        for y in [0.5, 0.1, 0.37] {
            let mut w = Work { nodes: nodes.clone(), cells: cells.clone(), locked: vec![true; 8] };
            let r = cut(&mut w, &PlaneY { y, eps: 1e-12 });
            assert!((volume(&w) - 1.0).abs() < 1e-12, "{y}: {}", volume(&w));
            assert!(!r.new_nodes_from.is_empty());
            for c in &w.cells {
                let above = c.iter().any(|&v| w.nodes[v as usize][1] > y + 1e-12);
                let below = c.iter().any(|&v| w.nodes[v as usize][1] < y - 1e-12);
                assert!(!(above && below), "{y}: a cell crosses the plane");
                assert!(signed_volume(&c.map(|v| w.nodes[v as usize])) > 0.0);
            }
            // Conforming: every interior face is shared by exactly two cells.
            let mut faces = std::collections::BTreeMap::<[u32; 3], usize>::new();
            for c in &w.cells {
                for i in 0..4 {
                    let mut f: Vec<u32> = (0..4).filter(|&k| k != i).map(|k| c[k]).collect();
                    f.sort_unstable();
                    *faces.entry([f[0], f[1], f[2]]).or_default() += 1;
                }
            }
            let boundary = faces.values().filter(|&&n| n == 1).count();
            assert!(faces.values().all(|&n| n <= 2));
            let area: f64 = faces
                .iter()
                .filter(|(_, &n)| n == 1)
                .map(|(f, _)| {
                    let p = f.map(|v| w.nodes[v as usize]);
                    let c = super::super::tree::cross(sub(p[1], p[0]), sub(p[2], p[0]));
                    0.5 * dot(c, c).sqrt()
                })
                .sum();
            assert!((area - 6.0).abs() < 1e-12, "{y}: boundary area {area} over {boundary} faces");
        }
    }
}
