//! Sliver removal by smoothing (stage 7), after refinement, edge removal and star insertion.
//!
//! Steiner points move; input vertices do not. How far a Steiner point may
//! move depends on where it lies (`Recovery::freedom`): one inside a region
//! anywhere, one inside an input triangle within that triangle's plane, one on
//! an input edge along that edge. The boundary and the interfaces therefore
//! keep reproducing the input: a point that stays in its triangle's plane and
//! keeps every tet positive stays inside the polygon of its boundary
//! neighbours, which lies in the triangle (and likewise between its neighbours
//! on an edge); the directions come from the input's exact coordinates, so a
//! face of a box keeps its points' coordinate across it exactly. When only
//! interior points moved (and only the smallest angle counted), the worst tets
//! of two boxes sharing a face, at the boxes' edges with three corners on the
//! boundary, stayed at 6.39 and 169.24 deg; now that mesh's angles are
//! 10.01..163.08 deg.
//!
//! Passes visit, in vertex order, the movable vertices of tets whose quality
//! ([`angle_quality`]: the smallest dihedral angle, or half of 180 deg minus
//! the largest when that is smaller) is under the bound; each tries candidate
//! positions — the centroid of its star's other vertices, points part-way
//! towards it, and points drawn in a small ball about the vertex (a generator
//! seeded by the vertex: deterministic), all projected on what the vertex may
//! move along — and moves to the one that most raises the smallest quality of
//! its star, provided every tet of the star stays positively oriented (exact
//! `orient3d`), under the volume bound of refinement and with the star's
//! dihedral angles within their range where the vertex is (no smaller
//! smallest angle, no larger largest one: a better quality alone could
//! trade a small angle for a larger largest one, session 18). A move never
//! lowers the star's smallest quality; the connectivity is unchanged (the mesh is no
//! longer Delaunay afterwards, which nothing downstream needs).
//!
//! Then [`smooth_radius_edge`] moves, the same way, the movable vertices of
//! tets of radius-edge ratio over the refinement bound to the candidate that
//! most lowers their star's largest ratio, never taking the star's smallest
//! angle quality under the sliver bound (or what it was, when less). Those
//! tets are left by refinement next to the boundary (their candidates blocked
//! by subfacets); measured in the TetGen comparison (p99.9 ratio): hinge 1.74
//! to 1.47 (the floor its input corners force), fandisk 2.23 to 1.74, bunny
//! 1.75 to 1.41, two boxes 1.38 to 1.34, no gate on angles lost.

use super::order::SplitMix;
use super::recover::Freedom;
use crate::predicates::{orient3d, Point};
use crate::quality::{dihedral_range_deg, tet_quality, tet_volume};

/// What smoothing did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct SmoothStats {
    /// Vertex moves made.
    pub moves: usize,
    /// Those of them of Steiner points on an input edge or triangle.
    pub boundary_moves: usize,
    /// Passes run.
    pub passes: usize,
}

/// Candidate positions tried per vertex (12 left fandisk's worst tet at 166 deg).
const TRIES: usize = 24;

/// `f` folded over the tets of `star` with `v` at `at`, from `init`; `None`
/// when one of them would not be positively oriented or would be larger than
/// `max_volume` [mm^3].
fn fold_star<A>(
    (nodes, cells, star): (&[Point], &[[u32; 4]], &[u32]),
    v: u32,
    at: Point,
    max_volume: f64,
    init: A,
    mut f: impl FnMut(A, &[Point; 4]) -> A,
) -> Option<A> {
    let mut acc = init;
    for &c in star {
        let q = cells[c as usize].map(|u| if u == v { at } else { nodes[u as usize] });
        // `tet_volume` is `tet_quality`'s `volume_mm3`, bit for bit.
        if orient3d(q[0], q[1], q[2], q[3]) != 1 || tet_volume(&q) > max_volume {
            return None;
        }
        acc = f(acc, &q);
    }
    Some(acc)
}

/// [`fold_star`]'s step for [`smooth`]: the smallest [`angle_quality`] and
/// the smallest and largest dihedral angle [deg] so far, with tet `q`.
fn add_angles((worst, range): (f64, (f64, f64)), q: &[Point; 4]) -> (f64, (f64, f64)) {
    let (lo, hi) = dihedral_range_deg(q);
    (worst.min(angle_quality(lo, hi)), (range.0.min(lo), range.1.max(hi)))
}

/// [`fold_star`]'s start for [`add_angles`].
const NO_ANGLES: (f64, (f64, f64)) = (f64::INFINITY, (f64::INFINITY, f64::NEG_INFINITY));

/// Whether the dihedral range `new` [deg] is within `old`: neither its
/// smallest nor its largest angle is worse.
pub(crate) fn within(new: (f64, f64), old: (f64, f64)) -> bool {
    new.0 >= old.0 && new.1 <= old.1
}

/// The quality smoothing raises: the smallest dihedral angle, or the supplement
/// of the largest times [`MAX_ANGLE_WEIGHT`] when that is smaller (a tet with an
/// angle near 180 deg is as bad as one with an angle near 0) [deg].
pub(crate) fn angle_quality(min_deg: f64, max_deg: f64) -> f64 {
    min_deg.min(MAX_ANGLE_WEIGHT * (180.0 - max_deg))
}

/// The [`angle_quality`] of the tet `t` of `nodes`.
pub(crate) fn tet_angle_quality(nodes: &[Point], t: [u32; 4]) -> f64 {
    let (lo, hi) = dihedral_range_deg(&t.map(|v| nodes[v as usize]));
    angle_quality(lo, hi)
}

/// The weight of the largest dihedral angle's supplement in [`angle_quality`]:
/// with the default sliver bound of 10 deg, tets with an angle over 160 deg are
/// smoothed too. With a weight of 1 (angles over 170 deg only), tets at 166 to
/// 170 deg stayed on fandisk and hinge, whose TetGen meshes stop at 165 deg;
/// with 1/2 they do not (fandisk 160.3, hinge 164.5 deg), and the bunnies' and
/// two boxes' gates still hold.
pub const MAX_ANGLE_WEIGHT: f64 = 0.5;

/// `at` moved within what `freedom` allows from `here`: the displacement
/// projected on its plane or line (`None` when the vertex is fixed).
fn constrain(freedom: Freedom, here: Point, at: Point) -> Option<Point> {
    let d = [0, 1, 2].map(|k| at[k] - here[k]);
    let along = |t: Point| d[0] * t[0] + d[1] * t[1] + d[2] * t[2];
    match freedom {
        Freedom::Fixed => None,
        Freedom::Free => Some(at),
        Freedom::Line(t) => {
            let s = along(t);
            Some([0, 1, 2].map(|k| here[k] + s * t[k]))
        }
        Freedom::Plane([t1, t2]) => {
            let (s1, s2) = (along(t1), along(t2));
            Some([0, 1, 2].map(|k| here[k] + s1 * t1[k] + s2 * t2[k]))
        }
    }
}

/// Smooths the movable vertices (`freedom`) of bad tets ([`angle_quality`]
/// under `bound_deg`) in `passes` passes (module docs), keeping every tet
/// under `max_volume` [mm^3].
pub(crate) fn smooth(
    nodes: &mut [Point],
    cells: &[[u32; 4]],
    freedom: &[Freedom],
    bound_deg: f64,
    max_volume: f64,
    passes: usize,
) -> SmoothStats {
    let bad = |q: &[Point; 4]| {
        let (lo, hi) = dihedral_range_deg(q);
        angle_quality(lo, hi) < bound_deg
    };
    // The cost is the star's smallest quality, negated; a candidate must
    // keep the star's dihedral angles within their range where it is.
    let start = |nodes: &[Point], star: &[u32], v: u32, here: Point| {
        fold_star((nodes, cells, star), v, here, f64::INFINITY, NO_ANGLES, add_angles).map(|(q, range)| (-q, range))
    };
    let cost = |nodes: &[Point], star: &[u32], v: u32, at: Point, range: &(f64, f64)| {
        fold_star((nodes, cells, star), v, at, max_volume, NO_ANGLES, add_angles)
            .filter(|&(_, r)| within(r, *range))
            .map(|(q, _)| -q)
    };
    smooth_with(nodes, cells, freedom, passes, 0xD1E5, bad, start, cost)
}

/// The pass loop of both smoothings. Each pass visits, in vertex order, the
/// movable vertices of the tets `bad` picks and moves each to the candidate
/// place of lowest `cost` (`None`: refused), if lower than `start`'s cost
/// where it is (`start` also gives what `cost` judges the candidates by). The
/// candidates: the centroid of the star's other vertices, three points
/// part-way towards it, then points drawn in a shrinking ball about the best
/// so far (a generator seeded by `seed` and the vertex), each projected on what
/// the vertex may move along.
#[allow(clippy::too_many_arguments)]
fn smooth_with<S>(
    nodes: &mut [Point],
    cells: &[[u32; 4]],
    freedom: &[Freedom],
    passes: usize,
    seed: u64,
    bad: impl Fn(&[Point; 4]) -> bool,
    start: impl Fn(&[Point], &[u32], u32, Point) -> Option<(f64, S)>,
    cost: impl Fn(&[Point], &[u32], u32, Point, &S) -> Option<f64>,
) -> SmoothStats {
    let mut stats = SmoothStats::default();
    let mut stars: Vec<Vec<u32>> = vec![Vec::new(); nodes.len()];
    for (c, cell) in cells.iter().enumerate() {
        for &v in cell {
            stars[v as usize].push(c as u32);
        }
    }
    for _ in 0..passes {
        stats.passes += 1;
        let mut todo: Vec<u32> = cells
            .iter()
            .filter(|cell| bad(&cell.map(|v| nodes[v as usize])))
            .flatten()
            .copied()
            .filter(|&v| freedom[v as usize] != Freedom::Fixed)
            .collect();
        todo.sort_unstable();
        todo.dedup();
        let mut moved = 0;
        for v in todo {
            let star = &stars[v as usize];
            let here = nodes[v as usize];
            let Some((now, judge)) = start(nodes, star, v, here) else { continue };
            let mut sum = [0.0; 3];
            let mut n = 0.0;
            let mut reach: f64 = 0.0;
            for &c in star {
                for &u in &cells[c as usize] {
                    if u != v {
                        let p = nodes[u as usize];
                        (0..3).for_each(|k| sum[k] += p[k]);
                        n += 1.0;
                        let d = [0, 1, 2].map(|k| p[k] - here[k]);
                        reach = reach.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
                    }
                }
            }
            let centroid = sum.map(|x| x / n);
            let mut rng = SplitMix(seed ^ (u64::from(v) << 20));
            let mut best = (now, here);
            for k in 0..TRIES {
                let at = match k {
                    0 => centroid,
                    1..=3 => {
                        let f = k as f64 / 4.0;
                        [0, 1, 2].map(|i| here[i] + f * (centroid[i] - here[i]))
                    }
                    _ => {
                        let r = 0.1 * reach * (1.0 - (k as f64 - 4.0) / TRIES as f64);
                        let u = [0; 3].map(|_| (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0);
                        [0, 1, 2].map(|i| best.1[i] + r * u[i])
                    }
                };
                let Some(at) = constrain(freedom[v as usize], here, at) else { continue };
                if let Some(c) = cost(nodes, star, v, at, &judge) {
                    if c < best.0 {
                        best = (c, at);
                    }
                }
            }
            if best.0 < now {
                nodes[v as usize] = best.1;
                moved += 1;
                if freedom[v as usize] != Freedom::Free {
                    stats.boundary_moves += 1;
                }
            }
        }
        stats.moves += moved;
        if moved == 0 {
            break;
        }
    }
    stats
}

/// [`fold_star`]'s step for [`smooth_radius_edge`]: the largest radius-edge
/// ratio and the smallest [`angle_quality`] so far, with tet `q`.
fn add_ratio((ratio, angles): (f64, f64), q: &[Point; 4]) -> (f64, f64) {
    let t = tet_quality(q);
    (ratio.max(t.radius_edge), angles.min(angle_quality(t.min_dihedral_deg, t.max_dihedral_deg)))
}

/// Smoothing for the radius-edge ratio, after [`smooth`]: the movable
/// vertices of tets of ratio over `bound` move, as in [`smooth`], to the
/// candidate position that most lowers the largest ratio of their star,
/// provided its smallest [`angle_quality`] stays at least `bound_deg` (or
/// what it was, when less): no tet gets an angle under `bound_deg` or over
/// 180 - 2 `bound_deg` that did not have one.
pub(crate) fn smooth_radius_edge(
    nodes: &mut [Point],
    cells: &[[u32; 4]],
    freedom: &[Freedom],
    bound: f64,
    bound_deg: f64,
    max_volume: f64,
    passes: usize,
) -> SmoothStats {
    let bad = |q: &[Point; 4]| tet_quality(q).radius_edge > bound;
    // The cost is the star's largest ratio; a candidate must keep the star's
    // smallest angle quality at the floor (`bound_deg`, or what it was).
    let start = |nodes: &[Point], star: &[u32], v: u32, here: Point| {
        fold_star((nodes, cells, star), v, here, f64::INFINITY, (0.0, f64::INFINITY), add_ratio)
            .map(|(ratio, angles)| (ratio, angles.min(bound_deg)))
    };
    let cost = |nodes: &[Point], star: &[u32], v: u32, at: Point, floor: &f64| {
        fold_star((nodes, cells, star), v, at, max_volume, (0.0, f64::INFINITY), add_ratio)
            .filter(|&(_, angles)| angles >= *floor)
            .map(|(r, _)| r)
    };
    smooth_with(nodes, cells, freedom, passes, 0x5EED, bad, start, cost)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sliver smoothing of the octahedron's free centre put near the face
    /// x + y + z = 1 (its star's dihedral angles 5.34 to 170.33 deg): the
    /// centre moves, the star's smallest angle rises by over 10 deg (measured:
    /// to 54.74, the largest to 90.00 deg, the octants') and its angles stay
    /// within their range before (smallest not smaller, largest not larger).
    /// `within` itself: both ends are checked.
    #[test]
    fn sliver_smoothing_keeps_the_stars_angles_within_their_range() {
        let (mut nodes, cells) = crate::fixtures::octahedron_star([0.3, 0.3, 0.33]);
        let range = |nodes: &[Point]| {
            cells
                .iter()
                .map(|c| dihedral_range_deg(&c.map(|v| nodes[v as usize])))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (lo, hi)| (a.min(lo), b.max(hi)))
        };
        let before = range(&nodes);
        let mut freedom = vec![Freedom::Fixed; nodes.len()];
        freedom[0] = Freedom::Free;
        let stats = smooth(&mut nodes, &cells, &freedom, 30.0, f64::INFINITY, 8);
        let after = range(&nodes);
        eprintln!("dihedral range {before:?} -> {after:?}");
        assert!(stats.moves > 0, "{stats:?}");
        assert!(after.0 > before.0 + 10.0, "{before:?} -> {after:?}");
        assert!(within(after, before), "{before:?} -> {after:?}");
        assert!(!within((before.0 - 1e-9, before.1), before) && !within((before.0, before.1 + 1e-9), before));
    }

    /// The eight tets of an octahedron about a free centre moved off its
    /// middle: smoothing for the radius-edge ratio lowers the star's largest
    /// ratio (at the middle it is sqrt(3)/2, the octant tet's), keeps every
    /// tet positive and no tet's angles under the bound they were over.
    #[test]
    fn radius_edge_smoothing_lowers_the_stars_ratio_and_keeps_its_angles() {
        let (mut nodes, cells) = crate::fixtures::octahedron_star([0.55, 0.3, -0.2]);
        let measure = |nodes: &[Point]| {
            cells.iter().fold((0.0f64, f64::INFINITY), |(r, a), c| {
                let t = tet_quality(&c.map(|v| nodes[v as usize]));
                (r.max(t.radius_edge), a.min(angle_quality(t.min_dihedral_deg, t.max_dihedral_deg)))
            })
        };
        let (ratio, angles) = measure(&nodes);
        let mut freedom = vec![Freedom::Fixed; nodes.len()];
        freedom[0] = Freedom::Free;
        let stats = smooth_radius_edge(&mut nodes, &cells, &freedom, 0.9, 10.0, f64::INFINITY, 8);
        let (after, angles_after) = measure(&nodes);
        assert!(stats.moves > 0 && stats.boundary_moves == 0, "{stats:?}");
        assert!(after < ratio - 0.1, "ratio {ratio} -> {after}");
        assert!(after >= 3f64.sqrt() / 2.0 - 1e-12, "{after} under the octant's");
        assert!(angles_after >= angles.min(10.0), "angle quality {angles} -> {angles_after}");
        for c in &cells {
            let q = c.map(|v| nodes[v as usize]);
            assert_eq!(orient3d(q[0], q[1], q[2], q[3]), 1);
        }
        // Fixed vertices do not move.
        let mut fixed = nodes.clone();
        let all_fixed = vec![Freedom::Fixed; fixed.len()];
        let none = smooth_radius_edge(&mut fixed, &cells, &all_fixed, 0.9, 10.0, f64::INFINITY, 8);
        assert_eq!((none.moves, fixed), (0, nodes));
    }
}
