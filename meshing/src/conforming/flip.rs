//! Sliver removal by 3-2 flips (stage 5), after refinement and before
//! smoothing.
//!
//! A tet under the sliver bound with an interior edge `cd` around which
//! exactly three tets `(c, d, a, b)`, `(c, d, b, p)`, `(c, d, p, a)` lie
//! (same region) is replaced, with the two others, by `(a, b, p, c)` and
//! `(a, b, p, d)` when the segment `cd` crosses the triangle `abp` (exact
//! `orient3d`: the two tets fill the same space) and the smallest
//! [`angle_quality`] of the two is larger than that of the three. The six
//! outer faces stay, so the boundary and the interfaces are unchanged, and
//! no point moves. This is what removes the flat *caps* refinement leaves
//! on a bent scan (module docs of `conforming`): a cap's two apexes `c`, `d`
//! span an interior edge, and the flip joins its two boundary faces to the
//! interior vertex `p` instead. The mesh is no longer Delaunay afterwards;
//! nothing downstream needs it.
//!
//! Rounds visit the cells in index order; a cell takes part in at most one
//! flip per round (the edge map is rebuilt between rounds), so the result
//! does not depend on hashing or threads.

use std::collections::HashMap;

use super::smooth::angle_quality;
use crate::predicates::{orient3d, Point};
use crate::quality::dihedral_range_deg;

/// Rounds of flips at most.
pub const FLIP_ROUNDS: usize = 8;

/// What the flips did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct FlipStats {
    /// 3-2 flips made.
    pub flips: usize,
    /// Rounds run.
    pub rounds: usize,
}

fn quality(nodes: &[Point], t: [u32; 4]) -> f64 {
    let (lo, hi) = dihedral_range_deg(&t.map(|v| nodes[v as usize]));
    angle_quality(lo, hi)
}

/// Positively oriented order of `t` (exact), or `None` when it is flat.
fn positive(nodes: &[Point], t: [u32; 4]) -> Option<[u32; 4]> {
    let q = t.map(|v| nodes[v as usize]);
    match orient3d(q[0], q[1], q[2], q[3]) {
        1 => Some(t),
        -1 => Some([t[1], t[0], t[2], t[3]]),
        _ => None,
    }
}

/// 3-2 flips of the slivers of `cells` (regions `regions`, same length) under
/// `sliver_deg` (module docs). Cells are replaced in place; removed ones are
/// dropped from both vectors.
pub fn flip_slivers(nodes: &[Point], cells: &mut Vec<[u32; 4]>, regions: &mut Vec<u16>, sliver_deg: f64) -> FlipStats {
    let mut stats = FlipStats::default();
    for _ in 0..FLIP_ROUNDS {
        stats.rounds += 1;
        let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (i, c) in cells.iter().enumerate() {
            for a in 0..4 {
                for b in a + 1..4 {
                    let (x, y) = (c[a].min(c[b]), c[a].max(c[b]));
                    edges.entry((x, y)).or_default().push(i as u32);
                }
            }
        }
        let mut used = vec![false; cells.len()];
        let mut dead = vec![false; cells.len()];
        let mut made = 0;
        for i in 0..cells.len() {
            if used[i] {
                continue;
            }
            let t = cells[i];
            let (lo, hi) = dihedral_range_deg(&t.map(|v| nodes[v as usize]));
            if lo >= sliver_deg {
                continue;
            }
            let own = angle_quality(lo, hi);
            'edges: for a in 0..4 {
                for b in a + 1..4 {
                    let (c, d) = (t[a].min(t[b]), t[a].max(t[b]));
                    let ring = &edges[&(c, d)];
                    if ring.len() != 3 || ring.iter().any(|&k| used[k as usize]) {
                        continue;
                    }
                    if ring.iter().any(|&k| regions[k as usize] != regions[i]) {
                        continue;
                    }
                    // The three other vertices, each in exactly two of the tets
                    // (a closed ring: `cd` is an interior edge).
                    let mut others: Vec<u32> =
                        ring.iter().flat_map(|&k| cells[k as usize]).filter(|&v| v != c && v != d).collect();
                    others.sort_unstable();
                    if others.len() != 6 || !(0..3).all(|k| others[2 * k] == others[2 * k + 1]) {
                        continue;
                    }
                    let [x, y, z] = [others[0], others[2], others[4]];
                    if x == y || y == z {
                        continue;
                    }
                    let p = |v: u32| nodes[v as usize];
                    // cd crosses triangle xyz: c and d on opposite sides of its
                    // plane, and the line cd inside its three edges.
                    let sc = orient3d(p(x), p(y), p(z), p(c));
                    let sd = orient3d(p(x), p(y), p(z), p(d));
                    if sc == 0 || sd == 0 || sc == sd {
                        continue;
                    }
                    let s1 = orient3d(p(c), p(d), p(x), p(y));
                    let s2 = orient3d(p(c), p(d), p(y), p(z));
                    let s3 = orient3d(p(c), p(d), p(z), p(x));
                    if s1 == 0 || s1 != s2 || s2 != s3 {
                        continue;
                    }
                    let (Some(n1), Some(n2)) = (positive(nodes, [x, y, z, c]), positive(nodes, [x, y, z, d])) else {
                        continue;
                    };
                    let old = ring.iter().map(|&k| quality(nodes, cells[k as usize])).fold(own, f64::min);
                    if quality(nodes, n1).min(quality(nodes, n2)) <= old {
                        continue;
                    }
                    let ring = ring.clone();
                    for &k in &ring {
                        used[k as usize] = true;
                    }
                    cells[ring[0] as usize] = n1;
                    cells[ring[1] as usize] = n2;
                    dead[ring[2] as usize] = true;
                    made += 1;
                    break 'edges;
                }
            }
        }
        let mut k = 0;
        cells.retain(|_| {
            k += 1;
            !dead[k - 1]
        });
        let mut k = 0;
        regions.retain(|_| {
            k += 1;
            !dead[k - 1]
        });
        stats.flips += made;
        if made == 0 {
            break;
        }
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    fn volume(nodes: &[Point], t: [u32; 4]) -> f64 {
        let [a, b, c, d] = t.map(|v| nodes[v as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let w = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
        (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]))
            / 6.0
    }

    /// Three tets around the edge `cd` (a = 0, b = 1, p = 2, c = 3, d = 4); the
    /// edge passes through the triangle `abp` at `(0.5, y, 0)`.
    fn ring(y: f64) -> (Vec<Point>, Vec<[u32; 4]>) {
        let nodes = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, y, 0.8], [0.5, y, -0.8]];
        let cells = [[3, 4, 0, 1], [3, 4, 1, 2], [3, 4, 2, 0]].map(|t| positive(&nodes, t).unwrap()).to_vec();
        (nodes, cells)
    }

    /// The edge 0.02 from `ab`: the tet `(c, d, a, b)` is a sliver (its corners
    /// nearly coplanar), and the flip gives two tets on `abp` that fill the same
    /// volume (1e-12) with every dihedral angle over the 10 deg bound.
    #[test]
    fn a_sliver_on_a_three_tet_edge_is_flipped_into_two_good_tets() {
        let (nodes, mut cells) = ring(0.02);
        let before: f64 = cells.iter().map(|&t| volume(&nodes, t)).sum();
        let worst = cells.iter().map(|&t| dihedral_range_deg(&t.map(|v| nodes[v as usize])).0).fold(180.0, f64::min);
        assert!(worst < 10.0, "{worst}");
        let mut regions = vec![0u16; 3];
        let stats = flip_slivers(&nodes, &mut cells, &mut regions, 10.0);
        assert_eq!(stats.flips, 1);
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

    /// The edge outside the triangle (`y` < 0): the two tets on `abp` would not
    /// fill the ring's space, so nothing flips.
    #[test]
    fn no_flip_when_the_edge_misses_the_triangle() {
        let (nodes, mut cells) = ring(-0.02);
        let kept = cells.clone();
        let mut regions = vec![0u16; 3];
        let stats = flip_slivers(&nodes, &mut cells, &mut regions, 10.0);
        assert_eq!(stats.flips, 0);
        assert_eq!(cells, kept);
    }
}
