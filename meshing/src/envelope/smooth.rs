//! Quality improvement by node relocation: the worst tets' nodes move where their
//! worst tet gets better.
//!
//! A tet's score is `min(θ_min / 12°, (180° - θ_max) / 25°)` over its dihedral
//! angles θ: at least 1 when its angles are within the envelope targets
//! [12°, 155°]. Every node of a tet scoring under [`GOOD`] is visited in index
//! order (deterministic, sequential), [`ROUNDS`] times; candidate positions are
//! the centroid of its neighbours and steps of a tenth and a fortieth of its mean
//! edge length along the axes. A node on the input surface has each candidate
//! projected back onto the surface (its closest point), so the boundary stays on
//! the input; interface nodes (region shells, layer planes) and boundary nodes off
//! the input (spanning a hole) do not move. A candidate is taken when the worst
//! score of the node's tets improves, none inverting.

use super::tree::{add, cross, dot, norm, scale, sub, TriangleTree};

type P = [f64; 3];

/// Tets scoring under this are worked on.
const GOOD: f64 = 1.15;
/// Passes over the bad nodes.
const ROUNDS: usize = 4;

/// How a node may move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mobility {
    Fixed,
    Free,
    OnSurface,
}

/// The score of the tet with corners `p` (see the module docs); negative when inverted.
pub(crate) fn score(p: &[P; 4]) -> f64 {
    let vol = dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0])));
    if !(vol > 0.0) {
        return -1.0;
    }
    // Dihedral angle at edge (i, j) from the outward face normals opposite k and l.
    let normal = |k: usize| -> P {
        let f = [p[(k + 1) % 4], p[(k + 2) % 4], p[(k + 3) % 4]];
        let n = cross(sub(f[1], f[0]), sub(f[2], f[0]));
        // Orient away from node k.
        let s = if dot(n, sub(f[0], p[k])) > 0.0 { 1.0 } else { -1.0 };
        let l = norm(n);
        if l > 0.0 {
            scale(n, s / l)
        } else {
            [0.0; 3]
        }
    };
    let n = [normal(0), normal(1), normal(2), normal(3)];
    let mut lo: f64 = 180.0;
    let mut hi: f64 = 0.0;
    for k in 0..4 {
        for l in k + 1..4 {
            let c = dot(n[k], n[l]).clamp(-1.0, 1.0);
            let theta = 180.0 - c.acos().to_degrees();
            lo = lo.min(theta);
            hi = hi.max(theta);
        }
    }
    (lo / 12.0).min((180.0 - hi) / 25.0)
}

/// Improves the mesh in place (see the module docs). Returns the nodes moved.
pub(crate) fn improve(nodes: &mut [P], cells: &[[u32; 4]], mobility: &[Mobility], surface: &TriangleTree) -> usize {
    let nv = nodes.len();
    // Node -> cells.
    let mut start = vec![0usize; nv + 1];
    for c in cells {
        for &v in c {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..nv {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut of_node = vec![0u32; start[nv]];
    for (k, c) in cells.iter().enumerate() {
        for &v in c {
            of_node[fill[v as usize]] = k as u32;
            fill[v as usize] += 1;
        }
    }
    let worst = |nodes: &[P], v: usize| -> f64 {
        of_node[start[v]..start[v + 1]]
            .iter()
            .map(|&k| score(&cells[k as usize].map(|x| nodes[x as usize])))
            .fold(f64::INFINITY, f64::min)
    };
    let mut moved = vec![false; nv];
    for _ in 0..ROUNDS {
        let mut bad: Vec<u32> = cells
            .iter()
            .filter(|c| score(&c.map(|x| nodes[x as usize])) < GOOD)
            .flat_map(|c| c.iter().copied())
            .filter(|&v| mobility[v as usize] != Mobility::Fixed)
            .collect();
        bad.sort_unstable();
        bad.dedup();
        if bad.is_empty() {
            break;
        }
        let mut changed = false;
        for v in bad {
            let v = v as usize;
            let here = nodes[v];
            let current = worst(nodes, v);
            // Neighbours' centroid and mean edge length.
            let mut sum = [0.0; 3];
            let mut count = 0.0;
            let mut length = 0.0;
            for &k in &of_node[start[v]..start[v + 1]] {
                for &x in &cells[k as usize] {
                    if x as usize != v {
                        sum = add(sum, nodes[x as usize]);
                        length += norm(sub(nodes[x as usize], here));
                        count += 1.0;
                    }
                }
            }
            if count == 0.0 {
                continue;
            }
            let centroid = scale(sum, 1.0 / count);
            let h = length / count;
            let mut candidates = vec![centroid, add(scale(here, 0.5), scale(centroid, 0.5))];
            for step in [0.1 * h, 0.025 * h] {
                for k in 0..3 {
                    for sign in [-1.0, 1.0] {
                        let mut q = here;
                        q[k] += sign * step;
                        candidates.push(q);
                    }
                }
            }
            let mut best = (current, here);
            for mut q in candidates {
                if mobility[v] == Mobility::OnSurface {
                    match surface.closest_point(q) {
                        Some((c, _, _)) => q = c,
                        None => continue,
                    }
                }
                nodes[v] = q;
                let s = worst(nodes, v);
                if s > best.0 {
                    best = (s, q);
                }
            }
            nodes[v] = best.1;
            if best.1 != here {
                moved[v] = true;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    moved.iter().filter(|&&m| m).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_regular_tet_scores_above_one_and_a_sliver_below() {
        // Positively oriented.
        let regular = [[1.0, 1.0, 1.0], [-1.0, 1.0, -1.0], [1.0, -1.0, -1.0], [-1.0, -1.0, 1.0]];
        // min(70.53 / 12, (180 - 70.53) / 25) = 4.38.
        assert!((score(&regular) - (180.0 - (1.0f64 / 3.0).acos().to_degrees()) / 25.0).abs() < 1e-9);
        let sliver = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.05]];
        assert!(score(&sliver) < 0.5 && score(&sliver) > 0.0);
        let inverted = [regular[0], regular[2], regular[1], regular[3]];
        assert!(score(&inverted) < 0.0);
    }

    #[test]
    fn a_bad_interior_node_is_moved_to_a_better_place() {
        // An octahedron around a node pushed towards one corner.
        let (mut nodes, cells) = crate::fixtures::octahedron_star([0.9, 0.0, 0.0]);
        let before = cells.iter().map(|c| score(&c.map(|x| nodes[x as usize]))).fold(f64::INFINITY, f64::min);
        let mut mobility = vec![Mobility::Fixed; 7];
        mobility[0] = Mobility::Free;
        let tree = TriangleTree::new(vec![[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
        assert_eq!(improve(&mut nodes, &cells, &mobility, &tree), 1);
        let after = cells.iter().map(|c| score(&c.map(|x| nodes[x as usize]))).fold(f64::INFINITY, f64::min);
        assert!(after > before + 0.5, "{before} -> {after}");
    }
}
