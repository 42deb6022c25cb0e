//! The graded lattice: the uniform BCC lattice refined by conforming longest-edge
//! bisection where the input's surface is curved, creased or thin at the scale of
//! the cells, before the stuffing.
//!
//! ## Why bisection, not the graded BCC octree
//!
//! Labelle and Shewchuk's graded lattice (an octree of BCC cells with transition
//! stencils between sizes) proves dihedral angles in [1.66°, 174.72°] only, and
//! needs a dozen transition cases. Longest-edge bisection (Rivara) of the BCC
//! tets needs none: each tet is cut at the midpoint of its longest edge, and a
//! cut edge is cut in *every* tet around it, so the mesh stays conforming at each
//! step ("conformity closure": before edge `e` is cut, each tet around `e` whose
//! longest edge is not `e` is first cut at its own longest edge, recursively;
//! this terminates because the recursion always goes to a strictly greater edge
//! in the order below). The tets it makes fall into a few similarity classes
//! (the unit test measures at most 4, dihedral angles within [45°, 120°]): the
//! BCC tet's halves, then Kuhn orthoschemes (three orthogonal steps) and their
//! longest-edge children, whatever the grading. The BCC tet itself does *not*
//! come back at half size (a child keeps three of its parent's four vertices,
//! so no third-level descendant has the two new body-centre vertices a BCC tet
//! of the half lattice needs): Labelle and Shewchuk's angle proof does not carry
//! over. All vertices sit on dyadic refinements of the lattice, kept as exact
//! integers (in units of `h / 2^(3 (MAX_LEVELS + 1) + 1)`), so lengths compare exactly
//! and the longest edge of a tet is chosen by (squared length, larger first;
//! then the smaller pair of vertex ids): a function of the edge alone, so that
//! all tets around an edge agree.
//!
//! ## The sizing
//!
//! A cell is cut while its longest edge `L` exceeds `h / 2^levels` (at a rim,
//! `h / 2^MAX_LEVELS`: below) and the chord
//! error of a surface patch of that size, estimated from the input's triangles
//! within the cell's circumscribing ball (centroid, farthest corner), exceeds the
//! tolerance: with `n̄` their area-weighted mean unit normal and `θ` the largest
//! angle between a triangle's normal and `n̄`, the estimate is `L sin θ / 4` (a
//! cylinder of radius `R` spanned by a chord `L` strays `L² / 8R`; its normals
//! within the ball turn by about `L / 2R`), and `L / 4` when the normals cancel
//! (`|Σ A n| < A / 2`: the two sides of a part thinner than the cell, an ear tip,
//! a fin) or a normal turns by more than 90°. So creases, tips and thin parts are
//! refined down to the smallest size and flat parts stay coarse. A cell whose
//! ball meets a **border edge** of the input (an edge of one triangle once
//! vertices within 1e-6 of the diagonal are welded: the rim of a hole) is cut
//! as at a crease (estimate `L / 4`), and **below the smallest size** while
//! that estimate exceeds the tolerance (down to `h / 2^MAX_LEVELS`; so at most
//! until `L = 4 tol`, a cost set by the rims' length over the tolerance, not by
//! `h`): there the solid leaves the input for the cap `w = 1/2`
//! over the hole, a crease no input triangle shows (the holed bunny's rim at
//! 3 levels, 1.08e-3 -> 9.98e-4 of the diagonal; an open sphere's rim,
//! 3.65e-3 -> 2.19e-3). The deeper cut is there
//! because the fitting (`fit.rs`) cannot bring the boundary onto a rim as it
//! does onto an input crease: the stuffing's boundary cuts the rim's corner
//! between nodes on the input and nodes on the cap (both directions of the
//! distance peak there), and the fitting looks at the rim's vertices only.
//! Measured on the open sphere (h = 0.25 mm, 3 levels; its 64 rim vertices
//! 2.0e-3 of the diagonal from the mesh): the nearest boundary corner is 1.2
//! to 3.6 times farther from a rim vertex than a snap allows (half the node's
//! shortest edge); the nearest boundary triangle has no edge between two nodes
//! on the input (52 of 100 tries) or one (48), whose split first needs a longer
//! edge across the rim split (longest-edge propagation), which the fitting
//! does not do (an end on the cap is fixed). Splitting the edges across the rim
//! onto it (tried) makes tets of 6°..169° (the rim lies 0.2 to 0.3 of the
//! edge off its midpoint: the corner's height), which the guard refuses. The
//! distance left at the rim is about `0.18 L` (measured: rim cells of 0.05,
//! 0.031, 0.025, 0.016 mm leave 7.9e-3, 7.3e-3, 4.4e-3, 2.8e-3 mm), under
//! the estimate. With the deeper cut: 2.19e-3 -> 7.43e-4 of the diagonal
//! (82.5k -> 156k tets; the maximum leaves the rim, the fitting has nothing
//! to do; one level deeper only: 99k tets, 8.42e-4 at h = 0.25 mm but 1.32e-3
//! at 0.4 mm); the holed bunny (0.2 mm) and the open teapot (0.5 mm) do not
//! change: at the smallest size their rims' estimate `L / 4` is under the
//! tolerance already (6.3e-3 < 7.9e-3 mm, 1.6e-2 < 2.1e-2 mm).
//! A cell the chord test leaves is
//! still cut while the solid or a gap of it is thinner than its longest edge
//! ([`THIN_FACTOR`]) across the input point nearest to its centroid
//! ([`TriangleTree::thin_across`]: short rays both ways, each turning at a
//! crossing of the input or, where `w` is within 0.1 of 1/2, at the level set
//! `w = 1/2`, found by 8 steps): the void where the teapot handle's open mouth
//! meets the body is a wedge between the body and that level set, which no
//! input triangle shows and which the lattice would close into a crack (the
//! teapot at 3 levels, 1.15e-2 -> 3.63e-3 of the diagonal). And
//! **below the smallest size**, like the rims: a cell that
//! descends from one the thin test cut, or that meets a rim, is cut again while
//! the solid or a gap of it is thinner than the cell and [`GAP_DEPTH`] times its
//! longest edge exceeds the tolerance (down to `h / 2^MAX_LEVELS`): a wedge's
//! tail closed in cells of longest edge `L` leaves the input about `2.4 L`
//! off the mesh boundary (measured at the handle's mouth), so the cost is set
//! by the tails' length over the tolerance, not by `h`; a gap thinner than
//! `tol / GAP_DEPTH` is closed (the `ThinGap` warning names it). Below the
//! smallest size the rays step through the level set wherever `w` is within
//! [`DEEP_SOFT`] (0.2) of 1/2, and at a rim the probe moves a quarter of the
//! cell into the nearest triangle (the nearest point is often on the border
//! edge, where both sides are inside): the void between the spout's wall and
//! the cap over its opening starts at `w` = 0.33. Teapot, 0.5 mm, 3 levels:
//! input -> mesh 3.63e-3 -> 1.00e-3 of the diagonal (971k -> 1.59M tets).
//! **Blades** are cut as rims: an input edge whose two triangles'
//! normals are more than 90° apart ([`crate::distance::blade_edges`]) bounds
//! a wedge of solid (or of void) narrower than 90°, thinner than any cell near
//! its edge, but the input point nearest to such a cell's centroid is mostly
//! the edge itself, where both probes across the input (along either
//! triangle's normal) fall outside the wedge: the thin test sees nothing, and
//! without the cut the cells along the teapot spout's lip (faces 49.4° apart)
//! stay at the smallest size, the stuffing rounding the lip off by 0.04 mm (0.0412 mm
//! input -> mesh, the maximum). Among the rims, their cells get the inset
//! probe and the deep cut: input -> mesh 1.005e-3 -> 9.74e-4 of the diagonal
//! (1.589M -> 1.600M tets); the teapot has 2 blades, the bunny 18 (ear tips,
//! base).
//! Cells meeting no triangle are never cut by the sizing (only by the closure).
//!
//! Cells are visited in rounds: each round evaluates the sizing of the cells the
//! last round made (in parallel, collected in order) and cuts those too large in
//! index order, sequentially: the result does not depend on the thread count.
//!
//! ## The stuffing on it
//!
//! [`super::stuffing::stuff_grid`] applies the same signs, cut points, warping and
//! stencils per tet. The BCC-specific parts are replaced by: warping thresholds
//! by edge direction ([`ALPHA_AXIS`], [`ALPHA_FACE`], [`ALPHA_BODY`]: 0.2, 0.25,
//! 0.3 of the edge), and the quadrilaterals' diagonals start at the inside vertex
//! of smaller index (a function of the face; a total order leaves no prism
//! cyclic). The thresholds were chosen by measurement on the bunny at 0.2 mm
//! with three levels (tets outside [12°, 155°] after smoothing): the uniform
//! lattice's (0.25, 0.3 face, 0.41) leave 24, (0.25, 0.41, 0.41) 7, (0.2, 0.25,
//! 0.3) none (dihedral angles [13.8°, 151.2°]); smaller thresholds warp less,
//! so fewer lattice vertices collapse onto one flat input triangle. What such
//! collapses leave anyway, tets with all four corners within half the tolerance
//! of the solid's boundary (the part of the input that bounds it, not a wall
//! inside it) and angles outside [12°, 155°], are peeled off the boundary
//! ([`peel_slivers`]; their exposed faces stay within that distance of the
//! solid's boundary), and the smoothing gets a second pass. No angle bound is
//! proven: the angles are measured (BENCHMARKS.md), and the fitting's guard
//! follows as on the uniform lattice.

use rayon::prelude::*;

use super::stuffing::Grid;
use super::tree::{add, closest_on_segment, cross, dot, norm, scale, sub, TriangleTree};
use crate::cells::CellStore;

type P = [f64; 3];

/// Bits of the integer coordinates below the base lattice's half spacing: 3 per
/// halving of the cells (three bisections halve a BCC tet) and 3 to spare.
const BITS_PER_LEVEL: u32 = 3;

/// The most halvings of the base spacing (the smallest long edge is `h / 2^MAX_LEVELS`).
pub(crate) const MAX_LEVELS: u32 = 8;

/// A cell is cut while the solid or a gap of it is thinner than this many times
/// its longest edge near it (see the module docs).
pub(crate) const THIN_FACTOR: f64 = 1.0;

/// Below the smallest size, a cell across which a gap of the solid is thinner
/// than it is cut while this many times its longest edge exceeds the grading
/// tolerance: the input surface a gap closed in cells of longest edge `L` leaves
/// inside the mesh reaches about `2.4 L` from the mesh boundary (measured at
/// the teapot handle's mouth, a wedge opening by 0.18 mm per mm, at 3 and 4
/// levels: 0.149 mm at `L` = 0.0625 mm, 0.075 mm at 0.031 mm; see the module docs).
pub(crate) const GAP_DEPTH: f64 = 2.5;

/// Below the smallest size, the thin test's rays step through the level set
/// `w = 1/2` wherever `w` is within this of 1/2 where they start: everywhere
/// (above the smallest size, within `NEAR_HALF`, 0.1): the void at the
/// teapot spout's lip, between its wall and the cap over its opening, starts at
/// `w` = 0.33 beside the wall (exact sum) and reaches 1/2 within 0.02 mm.
pub(crate) const DEEP_SOFT: f64 = 0.2;

/// Warping threshold on axis-parallel edges of the graded lattice (measured, not
/// proven: see the module docs).
pub(crate) const ALPHA_AXIS: f64 = 0.2;
/// Warping threshold on face-diagonal edges of the graded lattice.
pub(crate) const ALPHA_FACE: f64 = 0.25;
/// Warping threshold on body-diagonal edges of the graded lattice.
pub(crate) const ALPHA_BODY: f64 = 0.3;

/// A conforming tet mesh of the box refined from the BCC lattice (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct GradedLattice {
    origin: P,
    /// Length of one integer unit [mm].
    unit: f64,
    coords: Vec<[i64; 3]>,
    cells: Vec<[u32; 4]>,
}

/// What the grading did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct GradeStats {
    /// Tets of the base lattice.
    pub base_tets: usize,
    /// Bisections (new vertices).
    pub bisections: usize,
    /// Sizing rounds.
    pub rounds: usize,
}

impl GradedLattice {
    /// The base lattice (spacing `h` over the box `lo..hi` grown by `h`), refined
    /// down to `h / 2^levels` (at most [`MAX_LEVELS`]) where the chord-error
    /// estimate of `surface` exceeds `tol` [mm], and where a border edge or a
    /// blade of the input (the first edge of each of `rims`' triangles) passes, while `L / 4`
    /// exceeds `tol`, down to `h / 2^MAX_LEVELS` (with `levels` > 0). Stops cutting
    /// (leaving the mesh conforming) when it has `max_vertices` vertices.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        surface: &TriangleTree,
        rims: &TriangleTree,
        lo: P,
        hi: P,
        h: f64,
        levels: u32,
        tol: f64,
        max_vertices: usize,
    ) -> (Self, GradeStats) {
        let levels = levels.min(MAX_LEVELS);
        // At the rims, as deep as the tolerance asks (module docs).
        let rim_levels = if levels > 0 { MAX_LEVELS } else { 0 };
        let base = super::stuffing::uniform_lattice(lo, hi, h);
        let bits = BITS_PER_LEVEL * (rim_levels + 1);
        let unit = 0.5 * h / (1u64 << bits) as f64;
        let coords: Vec<[i64; 3]> =
            (0..base.num_vertices() as u32).map(|v| base.coords(v).map(|c| c << bits)).collect();
        let cells = base.tets();
        // Each cell's tag: whether it descends from a cell the thin test cut.
        let tags = vec![false; cells.len()];
        let store = CellStore::new(coords.len(), cells, tags);
        let mut r = Refiner { coords, cells: store, changed: Vec::new() };
        let mut stats = GradeStats { base_tets: r.cells.cells.len(), ..GradeStats::default() };
        let mut g = GradedLattice { origin: base.origin, unit, coords: Vec::new(), cells: Vec::new() };
        // The smallest longest edge, squared, in integer units (with a margin for
        // the exact comparisons: any edge longer than this is cut).
        let min_long2 = |levels: u32| {
            let min_long = (0.5 * h / unit) / (1u64 << levels) as f64 * 2.0;
            (min_long * min_long * 1.000_001) as i128
        };
        let (min_long2, min_long2_rim) = (min_long2(levels), min_long2(rim_levels));
        // The offset of the thin test's probes off the input [mm].
        let offset = 1e-4 * h / (1u64 << levels) as f64;
        let mut todo: Vec<u32> = (0..r.cells.cells.len() as u32).collect();
        while !todo.is_empty() && r.coords.len() < max_vertices {
            let position = |v: u32| g.position_of(&r.coords, v);
            let cut: Vec<Cut> = todo
                .par_iter()
                .map(|&k| {
                    let c = r.cells.cells[k as usize];
                    let (a, b) = r.longest(c);
                    let l2 = r.len2(a, b);
                    let p = c.map(position);
                    // Above the smallest size: the chord and thin tests; at a rim,
                    // down to the rims' smallest: the chord test.
                    if l2 > min_long2 {
                        too_coarse(surface, rims, &p, tol, offset)
                    } else if l2 <= min_long2_rim {
                        Cut::No
                    } else {
                        let on_rim = meets_rim(rims, &p);
                        if on_rim && chord_too_large(surface, rims, &p, tol) {
                            Cut::Yes
                        } else if (on_rim || r.cells.regions[k as usize])
                            && thin_left_too_deep(surface, &p, tol, offset, on_rim)
                        {
                            Cut::Thin
                        } else {
                            Cut::No
                        }
                    }
                })
                .collect();
            let mut marked: Vec<[u32; 4]> = Vec::new();
            for (&k, &c) in todo.iter().zip(&cut) {
                if c != Cut::No {
                    marked.push(r.cells.cells[k as usize]);
                }
                if c == Cut::Thin {
                    r.cells.regions[k as usize] = true;
                }
            }
            if marked.is_empty() {
                break;
            }
            stats.rounds += 1;
            r.changed.clear();
            for c in marked {
                if r.coords.len() >= max_vertices {
                    break;
                }
                // Still a cell (an earlier cut of this round may have split it)?
                if !r.cells.star[c[0] as usize].iter().any(|&k| r.cells.cells[k as usize] == c) {
                    continue;
                }
                let (a, b) = r.longest(c);
                r.bisect(a, b);
            }
            let mut next = std::mem::take(&mut r.changed);
            next.sort_unstable();
            next.dedup();
            todo = next;
        }
        stats.bisections = r.coords.len() - base.num_vertices();
        g.coords = r.coords;
        g.cells = r.cells.cells;
        (g, stats)
    }

    fn position_of(&self, coords: &[[i64; 3]], v: u32) -> P {
        let c = coords[v as usize];
        [0, 1, 2].map(|k| self.origin[k] + c[k] as f64 * self.unit)
    }

    /// Number of tets.
    #[cfg(test)]
    pub fn num_tets(&self) -> usize {
        self.cells.len()
    }

    fn direction_class(&self, a: u32, b: u32) -> usize {
        let (p, q) = (self.coords[a as usize], self.coords[b as usize]);
        let d: Vec<i64> = (0..3).map(|k| (p[k] - q[k]).abs()).filter(|&x| x != 0).collect();
        match d.len() {
            1 => 1,
            2 if d[0] == d[1] => 2,
            3 if d[0] == d[1] && d[1] == d[2] => 3,
            _ => 0,
        }
    }
}

impl Grid for GradedLattice {
    fn num_vertices(&self) -> usize {
        self.coords.len()
    }
    fn position(&self, v: u32) -> P {
        self.position_of(&self.coords, v)
    }
    fn tets(&self) -> Vec<[u32; 4]> {
        self.cells.clone()
    }
    fn alpha(&self, a: u32, b: u32) -> f64 {
        match self.direction_class(a, b) {
            1 => ALPHA_AXIS,
            3 => ALPHA_BODY,
            _ => ALPHA_FACE,
        }
    }
    fn warp_distance(&self, a: u32, b: u32, t: f64) -> f64 {
        t * norm(sub(self.position(a), self.position(b)))
    }
    fn diagonal_from(&self, a: u32, b: u32, _p: u32) -> u32 {
        a.min(b)
    }
}

/// Whether a rim of the input (a border edge or a blade: the first edge of one
/// of `rims`' triangles) passes through the circumscribing ball (centroid, farthest
/// corner) of the cell with corners `p`.
fn meets_rim(rims: &TriangleTree, p: &[P; 4]) -> bool {
    let (c, radius, _) = ball_and_longest(p);
    let mut on_rim = false;
    rims.for_each_within(c, radius, |_, t| on_rim |= norm(sub(closest_on_segment(t[0], t[1], c), c)) <= radius);
    on_rim
}

/// Whether a cell with corners `p` is coarser than the surface near it allows
/// (see the module docs); `rims`: triangles whose first edge is a border edge or
/// a blade of the input.
fn too_coarse(surface: &TriangleTree, rims: &TriangleTree, p: &[P; 4], tol: f64, offset: f64) -> Cut {
    if chord_too_large(surface, rims, p, tol) {
        Cut::Yes
    } else if thinner_than_cell(surface, p, offset) {
        Cut::Thin
    } else {
        Cut::No
    }
}

/// The sizing's verdict on a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cut {
    No,
    /// Cut for the chord error or a rim.
    Yes,
    /// Cut because the solid or a gap of it is thinner than the cell: its
    /// descendants are tested again below the smallest size.
    Thin,
}

/// Whether the solid or a gap of it is thinner than [`THIN_FACTOR`] times the
/// longest edge of the cell with corners `p`, across the input point nearest to
/// its centroid within its circumscribing ball ([`TriangleTree::thin_across`];
/// `offset` [mm]: its probes' offset off the input). One point per cell: the
/// cells' centroids sample the input at about their own size as they shrink.
fn thinner_than_cell(surface: &TriangleTree, p: &[P; 4], offset: f64) -> bool {
    thin_across_cell(surface, p, offset, false, crate::winding::NEAR_HALF)
        .is_some_and(|(part, gap)| part.is_some() || gap.is_some())
}

/// Below the smallest size: whether the solid or a gap of it is thinner than
/// the cell with corners `p` (as in [`thinner_than_cell`]) while the input
/// surface a closed gap (or a lost part) leaves off the mesh, about
/// [`GAP_DEPTH`] times the cell's longest edge, exceeds `tol` [mm] (see the
/// module docs). `on_rim`: the cell meets a rim of the input (a border edge or a
/// blade), so the input point nearest to its centroid is often on that edge, where the inside
/// test agrees on both sides of the input: the probe moves a quarter of the
/// longest edge into its triangle, towards the triangle's centroid.
fn thin_left_too_deep(surface: &TriangleTree, p: &[P; 4], tol: f64, offset: f64, on_rim: bool) -> bool {
    let (_, _, longest) = ball_and_longest(p);
    GAP_DEPTH * longest > tol
        && thin_across_cell(surface, p, offset, on_rim, DEEP_SOFT)
            .is_some_and(|(part, gap)| part.is_some() || gap.is_some())
}

/// [`TriangleTree::thin_across`] at the input point nearest to the centroid of
/// the cell with corners `p`, within its ball (moved a quarter of the cell's
/// longest edge into its triangle towards the triangle's centroid if `inset`),
/// reaching [`THIN_FACTOR`] times its longest edge.
fn thin_across_cell(
    surface: &TriangleTree,
    p: &[P; 4],
    offset: f64,
    inset: bool,
    soft: f64,
) -> Option<(Option<f64>, Option<f64>)> {
    let (c, radius, longest) = ball_and_longest(p);
    let (x, t) = surface.closest_point_and_triangle(c, radius)?;
    let n = crate::distance::unit_normal(&t)?;
    let x = if inset {
        let g = scale([0, 1, 2].map(|k| t[0][k] + t[1][k] + t[2][k]), 1.0 / 3.0);
        let to_g = sub(g, x);
        let d = norm(to_g);
        if d > 0.0 {
            add(x, scale(to_g, (0.25 * longest / d).min(1.0)))
        } else {
            x
        }
    } else {
        x
    };
    surface.thin_across(x, n, THIN_FACTOR * longest, offset, soft)
}

/// The centroid of a cell with corners `p`, the radius of its ball about it and its longest edge [mm].
fn ball_and_longest(p: &[P; 4]) -> (P, f64, f64) {
    let c = scale([0, 1, 2].map(|k| p[0][k] + p[1][k] + p[2][k] + p[3][k]), 0.25);
    let radius = p.iter().map(|&q| norm(sub(q, c))).fold(0.0, f64::max);
    let mut longest: f64 = 0.0;
    for i in 0..4 {
        for j in i + 1..4 {
            longest = longest.max(norm(sub(p[i], p[j])));
        }
    }
    (c, radius, longest)
}

/// The chord-error part of [`too_coarse`] (see the module docs).
fn chord_too_large(surface: &TriangleTree, rims: &TriangleTree, p: &[P; 4], tol: f64) -> bool {
    let (c, radius, longest) = ball_and_longest(p);
    // A rim in the ball: the crease where the solid leaves the input for the cap
    // over a hole, or a blade's edge.
    if meets_rim(rims, p) {
        return 0.25 * longest > tol;
    }
    let mut normals: Vec<P> = Vec::new();
    let mut sum = [0.0; 3];
    let mut area = 0.0;
    surface.for_each_within(c, radius, |_, t| {
        let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        let l = norm(n);
        if l > 0.0 {
            normals.push(scale(n, 1.0 / l));
            sum = [sum[0] + n[0], sum[1] + n[1], sum[2] + n[2]];
            area += l;
        }
    });
    if normals.is_empty() {
        return false;
    }
    let ls = norm(sum);
    let sin_theta = if ls < 0.5 * area {
        1.0
    } else {
        let mean = scale(sum, 1.0 / ls);
        normals.iter().map(|&n| if dot(n, mean) <= 0.0 { 1.0 } else { norm(cross(n, mean)) }).fold(0.0, f64::max)
    };
    0.25 * longest * sin_theta > tol
}

/// Removes the tets with dihedral angles outside [12°, 155°] (score under 1)
/// that have a face on the boundary and all four corners within `near` [mm] of
/// the solid's boundary, in index order, for up to `rounds` rounds (a removal
/// exposes the next layer): the stuffing on the graded lattice leaves such
/// slivers where vertices warped onto one flat input triangle (see the module
/// docs). The exposed faces are within `near` of the solid's boundary. Unused
/// nodes are dropped. Returns the number of tets removed.
///
/// The solid's boundary is the part of the input where the winding number jumps
/// across 1/2 ([`crate::distance::bounding`], as the quality report measures
/// it, on a grid of spacing `near`), not every input triangle: a wall inside the
/// solid (a spout's end inside a teapot's body, the cap of one sphere inside
/// another) is not, and a corner near it alone would let the peeling dig a
/// trench along it. Only the triangles near the corners of candidates are
/// classified.
pub(crate) fn peel_slivers(
    nodes: &mut Vec<P>,
    cells: &mut Vec<[u32; 4]>,
    winding: &crate::WindingNumber,
    near: f64,
    delta: f64,
    rounds: usize,
) -> usize {
    use crate::distance::Bounding;
    use std::collections::HashMap;
    let surface = winding.tree();
    let near_input: Vec<bool> = nodes.par_iter().map(|&p| surface.closest_point_within(p, near).is_some()).collect();
    // Per input triangle classified so far, its bounding part; per node, whether
    // the solid's boundary is within `near`.
    let mut parts: HashMap<u32, Bounding> = HashMap::new();
    let mut near_boundary: HashMap<u32, bool> = HashMap::new();
    let mut removed = 0;
    for _ in 0..rounds {
        let mut count = HashMap::<[u32; 3], u32>::new();
        for c in cells.iter() {
            for i in 0..4 {
                let mut f = [c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]];
                f.sort_unstable();
                *count.entry(f).or_default() += 1;
            }
        }
        let on_boundary = |c: &[u32; 4]| {
            (0..4).any(|i| {
                let mut f = [c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]];
                f.sort_unstable();
                count.get(&f) == Some(&1)
            })
        };
        let candidate: Vec<bool> = cells
            .par_iter()
            .map(|c| {
                c.iter().all(|&v| near_input[v as usize])
                    && on_boundary(c)
                    && super::smooth::score(&c.map(|v| nodes[v as usize])) < 1.0
            })
            .collect();
        // The candidates' corners not yet decided, and the input triangles near them.
        let mut fresh: Vec<u32> = cells
            .iter()
            .zip(&candidate)
            .filter(|(_, &b)| b)
            .flat_map(|(c, _)| c.iter().copied())
            .filter(|v| !near_boundary.contains_key(v))
            .collect();
        fresh.sort_unstable();
        fresh.dedup();
        let around: Vec<Vec<(u32, [P; 3])>> = fresh
            .par_iter()
            .map(|&v| {
                let mut tris = Vec::new();
                surface.for_each_within(nodes[v as usize], near, |id, t| tris.push((id, *t)));
                tris
            })
            .collect();
        let mut unknown: Vec<(u32, [P; 3])> =
            around.iter().flatten().filter(|(id, _)| !parts.contains_key(id)).copied().collect();
        unknown.sort_unstable_by_key(|t| t.0);
        unknown.dedup_by_key(|t| t.0);
        let classified: Vec<Bounding> =
            unknown.par_iter().map(|(_, t)| crate::distance::bounding(t, near, winding, delta)).collect();
        parts.extend(unknown.into_iter().map(|t| t.0).zip(classified));
        for (&v, ids) in fresh.iter().zip(&around) {
            let p = nodes[v as usize];
            let within = |t: &[P; 3]| {
                let e = sub(super::tree::closest_on_triangle(t, p), p);
                dot(e, e) <= near * near
            };
            let close = ids.iter().any(|(id, _)| match &parts[id] {
                Bounding::All => true,
                Bounding::None => false,
                Bounding::Part(subs) => subs.iter().any(within),
            });
            near_boundary.insert(v, close);
        }
        let before = cells.len();
        let mut k = 0;
        cells.retain(|c| {
            let drop = candidate[k] && c.iter().all(|v| near_boundary[v]);
            k += 1;
            !drop
        });
        if cells.len() == before {
            break;
        }
        removed += before - cells.len();
    }
    // Compaction.
    let mut new_id = vec![u32::MAX; nodes.len()];
    let mut kept = Vec::with_capacity(nodes.len());
    for c in cells.iter() {
        for &v in c {
            if new_id[v as usize] == u32::MAX {
                new_id[v as usize] = 0;
            }
        }
    }
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
    removed
}

struct Refiner {
    coords: Vec<[i64; 3]>,
    /// The cells (none dies: bisection keeps every slot), tagged with whether
    /// they descend from a cell the thin test cut.
    cells: CellStore<bool>,
    /// Cells made or changed since it was cleared.
    changed: Vec<u32>,
}

impl Refiner {
    fn len2(&self, a: u32, b: u32) -> i128 {
        let (p, q) = (self.coords[a as usize], self.coords[b as usize]);
        (0..3).map(|k| (p[k] - q[k]) as i128).map(|d| d * d).sum()
    }

    /// The longest edge of `c` (ties: the smaller sorted pair of ids), sorted.
    fn longest(&self, c: [u32; 4]) -> (u32, u32) {
        let mut best: Option<(i128, (u32, u32))> = None;
        for i in 0..4 {
            for j in i + 1..4 {
                let e = if c[i] < c[j] { (c[i], c[j]) } else { (c[j], c[i]) };
                let l = self.len2(e.0, e.1);
                if best.is_none_or(|(bl, be)| l > bl || (l == bl && e < be)) {
                    best = Some((l, e));
                }
            }
        }
        best.map_or((c[0], c[1]), |b| b.1)
    }

    fn around(&self, a: u32, b: u32) -> Vec<u32> {
        self.cells.around(a, b).collect()
    }

    /// Cuts edge `(a, b)` (sorted) in every tet around it, after cutting first the
    /// longest edges of those tets where that is another edge. Returns whether it
    /// did (not when a midpoint is off the integer grid: too many levels).
    fn bisect(&mut self, a: u32, b: u32) -> bool {
        loop {
            let around = self.around(a, b);
            if around.is_empty() {
                return false;
            }
            let other = around.iter().map(|&k| self.longest(self.cells.cells[k as usize])).find(|&e| e != (a, b));
            match other {
                Some((x, y)) => {
                    if !self.bisect(x, y) {
                        return false;
                    }
                }
                None => return self.split(a, b, &around),
            }
        }
    }

    fn split(&mut self, a: u32, b: u32, around: &[u32]) -> bool {
        let (p, q) = (self.coords[a as usize], self.coords[b as usize]);
        if (0..3).any(|k| (p[k] + q[k]) % 2 != 0) {
            return false;
        }
        let m = self.coords.len() as u32;
        self.coords.push([0, 1, 2].map(|k| (p[k] + q[k]) / 2));
        self.cells.add_node();
        let made = self.cells.bisect(a, b, m, around);
        for (&k, new) in around.iter().zip(made) {
            self.changed.push(k);
            self.changed.push(new);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn volume(p: [P; 4]) -> f64 {
        dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0]))) / 6.0
    }

    /// An octahedron of "radius" 1 around the origin (a crease at each edge, a corner at each vertex).
    fn octahedron() -> TriangleTree {
        let v =
            [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
        let mut t = Vec::new();
        for &x in &[0usize, 1] {
            for &y in &[2usize, 3] {
                for &z in &[4usize, 5] {
                    t.push([v[x], v[y], v[z]]);
                }
            }
        }
        TriangleTree::new(t)
    }

    /// Total volume and boundary area (faces in one tet only); panics on a face in three tets.
    fn volume_and_boundary(g: &GradedLattice) -> (f64, f64) {
        let mut faces = BTreeMap::<[u32; 3], usize>::new();
        let mut total = 0.0;
        for t in &g.cells {
            let v = volume(t.map(|x| g.position(x)));
            assert!(v.abs() > 0.0);
            total += v.abs();
            for i in 0..4 {
                let mut f = [t[(i + 1) % 4], t[(i + 2) % 4], t[(i + 3) % 4]];
                f.sort_unstable();
                *faces.entry(f).or_default() += 1;
            }
        }
        assert!(faces.values().all(|&n| n <= 2), "a face in three tets");
        let area = faces
            .iter()
            .filter(|(_, &n)| n == 1)
            .map(|(f, _)| {
                let p = f.map(|x| g.position(x));
                0.5 * norm(cross(sub(p[1], p[0]), sub(p[2], p[0])))
            })
            .sum();
        (total, area)
    }

    /// Conforming: the same volume and boundary area as the base lattice (a
    /// hanging vertex leaves faces inside in one tet only, adding boundary area).
    fn check_conforming(g: &GradedLattice, base: &GradedLattice) {
        let (v0, a0) = volume_and_boundary(base);
        let (v, a) = volume_and_boundary(g);
        assert!((v - v0).abs() < 1e-9 * v0, "volume {v} vs {v0}");
        assert!((a - a0).abs() < 1e-9 * a0, "boundary area {a} vs {a0}");
    }

    /// The centroid of the tet `p` and its longest edge's length [mm].
    fn centroid_and_longest(p: &[P; 4]) -> (P, f64) {
        let c = scale([0, 1, 2].map(|k| p[0][k] + p[1][k] + p[2][k] + p[3][k]), 0.25);
        let longest = (0..4)
            .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
            .map(|(i, j)| norm(sub(p[i], p[j])))
            .fold(0.0, f64::max);
        (c, longest)
    }

    #[test]
    fn bisection_keeps_the_lattice_conforming_with_few_shapes_and_fine_only_near_the_creases() {
        let tree = octahedron();
        let no_rims = TriangleTree::new(Vec::new());
        let h = 0.5;
        let (g0, _) = GradedLattice::new(&tree, &no_rims, [-1.0; 3], [1.0; 3], h, 0, 1e-3, usize::MAX);
        let (g, stats) = GradedLattice::new(&tree, &no_rims, [-1.0; 3], [1.0; 3], h, 3, 1e-3, usize::MAX);
        assert_eq!(stats.base_tets, g0.num_tets());
        assert!(g.num_tets() > 4 * g0.num_tets(), "{} vs {}", g.num_tets(), g0.num_tets());
        check_conforming(&g, &g0);
        // Shapes: a few similarity classes (the dihedral angle ranges), within [45°, 120°].
        let mut classes = std::collections::BTreeSet::new();
        let (mut lo, mut hi) = (180.0f64, 0.0f64);
        for t in &g.cells {
            let (a, b) = crate::quality::dihedral_range_deg(&t.map(|x| g.position(x)));
            lo = lo.min(a);
            hi = hi.max(b);
            classes.insert(((a * 1e6).round() as i64, (b * 1e6).round() as i64));
        }
        assert!(classes.len() <= 4, "{} shape classes: {classes:?}", classes.len());
        assert!(lo > 45.0 - 1e-6 && hi < 120.0 + 1e-6, "dihedral angles [{lo}, {hi}]");
        // The smallest long edge, h / 8, only near the surface's creases and corners;
        // far from the surface, the base size.
        let pos = |v: u32| g.position(v);
        for t in &g.cells {
            let (c, longest) = centroid_and_longest(&t.map(pos));
            assert!(longest > h / 8.0 * (1.0 - 1e-9), "finer than the smallest size: {longest}");
            let d = tree.closest_point(c).map_or(f64::INFINITY, |x| x.1);
            if d > 2.0 * h {
                assert!(longest >= h * (1.0 - 1e-9), "refined far from the surface: {longest} at {c:?}");
            }
        }
        // Near a corner of the octahedron, the smallest size.
        let corner_cells = g
            .cells
            .iter()
            .filter(|t| {
                let p = t.map(pos);
                p.iter().any(|q| norm(sub(*q, [1.0, 0.0, 0.0])) < 0.1)
            })
            .count();
        assert!(corner_cells > 0);
        // Deterministic.
        let (again, _) = GradedLattice::new(&tree, &no_rims, [-1.0; 3], [1.0; 3], h, 3, 1e-3, usize::MAX);
        assert_eq!(again.cells, g.cells);
        assert_eq!(again.coords, g.coords);
    }

    #[test]
    fn a_flat_face_is_not_refined_but_a_crease_is() {
        let no_rims = TriangleTree::new(Vec::new());
        // One large square in z = 0.1 (two triangles): flat, nothing to refine.
        let flat = TriangleTree::new(vec![
            [[-5.0, -5.0, 0.1], [5.0, -5.0, 0.1], [5.0, 5.0, 0.1]],
            [[-5.0, -5.0, 0.1], [5.0, 5.0, 0.1], [-5.0, 5.0, 0.1]],
        ]);
        let (g0, _) = GradedLattice::new(&flat, &no_rims, [-1.0; 3], [1.0; 3], 0.5, 0, 1e-3, usize::MAX);
        let (g, s) = GradedLattice::new(&flat, &no_rims, [-1.0; 3], [1.0; 3], 0.5, 3, 1e-3, usize::MAX);
        assert_eq!(g.num_tets(), g0.num_tets());
        assert_eq!(s.bisections, 0);
        // A crease along x at z = 0.1 (two half planes at 90°).
        let crease = TriangleTree::new(vec![
            [[-5.0, 0.0, 0.1], [5.0, 0.0, 0.1], [5.0, 5.0, 0.1]],
            [[-5.0, 0.0, 0.1], [5.0, 5.0, 0.1], [-5.0, 5.0, 0.1]],
            [[-5.0, 0.0, 0.1], [5.0, 0.0, -4.9], [5.0, 0.0, 0.1]],
            [[-5.0, 0.0, 0.1], [-5.0, 0.0, -4.9], [5.0, 0.0, -4.9]],
        ]);
        let (g, s) = GradedLattice::new(&crease, &no_rims, [-1.0; 3], [1.0; 3], 0.5, 3, 1e-3, usize::MAX);
        assert!(s.bisections > 0 && g.num_tets() > g0.num_tets());
        // A vertex budget stops the cutting, leaving the mesh conforming.
        let (small, _) = GradedLattice::new(&crease, &no_rims, [-1.0; 3], [1.0; 3], 0.5, 3, 1e-3, g0.coords.len() + 10);
        assert!(small.coords.len() > g0.coords.len() && small.coords.len() < g.coords.len());
        check_conforming(&small, &g0);
        check_conforming(&g, &g0);
    }

    /// The 12 outward triangles of the box `lo..hi`.
    fn cuboid(lo: P, hi: P) -> Vec<[P; 3]> {
        let v = |i: usize| [0, 1, 2].map(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] });
        let quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
        quads.iter().flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]]).collect()
    }

    /// Two boxes with a flat gap of 0.05 between them (z in (0, 0.05)), at 1
    /// level (the smallest cells' long edges h / 2 = 0.25 and h sqrt(3) / 4 = 0.217 mm): the gap is thinner than the
    /// smallest cells, so below them the cells across it are cut while
    /// [`GAP_DEPTH`] `L` exceeds the tolerance: with 0.1 mm, down to `L` = h / 16
    /// (2.5 * 0.03125 = 0.078 <= 0.1), leaving lattice vertices inside the gap
    /// (the stuffing can open it; measured 758 within the gap's middle 3/4),
    /// none finer. With a tolerance of 1 mm, nothing is cut below the smallest
    /// size (the gap would be closed: thinner than the tolerance allows to
    /// resolve). The lattice is the same on one thread as on two. Not asserted: the boxes' edges are cut too (17,790 of the 65,692
    /// cells below the smallest size are farther than 0.25 from the gap): at an
    /// edge the thin test's ray runs along the other face, a false thin part.
    #[test]
    fn a_gap_thinner_than_the_smallest_cells_is_cut_below_them_while_the_tolerance_asks() {
        let g = 0.05;
        let mut t = cuboid([-0.4, -0.4, -0.4], [0.4, 0.4, 0.0]);
        t.extend(cuboid([-0.4, -0.4, g], [0.4, 0.4, 0.4]));
        let tree = TriangleTree::new(t);
        let no_rims = TriangleTree::new(Vec::new());
        let h = 0.5;
        let finest = |g: &GradedLattice| {
            g.cells.iter().map(|t| centroid_and_longest(&t.map(|x| g.position(x))).1).fold(f64::INFINITY, f64::min)
        };
        let (coarse, _) = GradedLattice::new(&tree, &no_rims, [-0.5; 3], [0.5; 3], h, 1, 1.0, usize::MAX);
        assert!(finest(&coarse) > 0.4 * h, "{}", finest(&coarse));
        let (fine, _) = GradedLattice::new(&tree, &no_rims, [-0.5; 3], [0.5; 3], h, 1, 0.1, usize::MAX);
        let (g0, _) = GradedLattice::new(&tree, &no_rims, [-0.5; 3], [0.5; 3], h, 0, 0.1, usize::MAX);
        check_conforming(&fine, &g0);
        assert!((finest(&fine) - h / 16.0).abs() < 1e-9, "{}", finest(&fine));
        let (mut below, mut far) = (0, 0);
        for t in &fine.cells {
            let (c, longest) = centroid_and_longest(&t.map(|x| fine.position(x)));
            if longest < 0.4 * h {
                below += 1;
                far += usize::from((c[2] - 0.5 * g).abs() >= 0.25);
            }
        }
        eprintln!("{far} of {below} cells below the smallest size farther than 0.25 from the gap");
        let inside_gap = (0..fine.coords.len() as u32)
            .map(|v| fine.position(v))
            .filter(|p| p[2] > g / 8.0 && p[2] < g - g / 8.0 && p[0].abs() < 0.3 && p[1].abs() < 0.3)
            .count();
        eprintln!("{below} cells below the smallest size, {inside_gap} vertices inside the gap");
        assert!(below > 0 && inside_gap > 0);
        // The deep cut does not depend on the thread count: the same integer
        // vertices and cells on one thread as on two.
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let (again, _) =
                pool.install(|| GradedLattice::new(&tree, &no_rims, [-0.5; 3], [0.5; 3], h, 1, 0.1, usize::MAX));
            assert!(again.coords == fine.coords && again.cells == fine.cells, "{threads} threads");
        }
    }

    /// An open flat square (side 1 in z = 0.1): flat, but its border edges (the
    /// rims) are where the solid turns onto the cap over the opening: the cells
    /// they pass through are refined below the smallest size while the crease
    /// estimate `L / 4` exceeds the tolerance (1e-2 here: to h / 16 at 3 levels;
    /// the centroids of the cells finer than h / 8 within h / 4 of the rim),
    /// cells farther than 2 h from them keep the base size, and the lattice
    /// stays conforming.
    #[test]
    fn a_border_edge_is_refined_like_a_crease() {
        let [a, b, c, d] = [[-0.5, -0.5, 0.1], [0.5, -0.5, 0.1], [0.5, 0.5, 0.1], [-0.5, 0.5, 0.1]];
        let square = TriangleTree::new(vec![[a, b, c], [a, c, d]]);
        // Each border edge first, with a third corner of its triangle.
        let rims = TriangleTree::new(vec![[a, b, c], [b, c, a], [c, d, a], [d, a, c]]);
        let h = 0.5;
        let (g0, _) =
            GradedLattice::new(&square, &TriangleTree::new(Vec::new()), [-1.0; 3], [1.0; 3], h, 0, 1e-3, usize::MAX);
        let (g, s) = GradedLattice::new(&square, &rims, [-1.0; 3], [1.0; 3], h, 3, 1e-2, usize::MAX);
        assert!(s.bisections > 0);
        check_conforming(&g, &g0);
        let to_rim = |q: P| {
            [(a, b), (b, c), (c, d), (d, a)]
                .iter()
                .map(|&(x, y)| norm(sub(closest_on_segment(x, y, q), q)))
                .fold(f64::INFINITY, f64::min)
        };
        let (mut finest_near_rim, mut deepest_off_rim) = (0, 0.0f64);
        for t in &g.cells {
            let p = t.map(|x| g.position(x));
            let (c, longest) = centroid_and_longest(&p);
            assert!(longest > h / 16.0 * (1.0 - 1e-9), "finer than the rim's size: {longest}");
            // Every cell the rim passes meets the tolerance.
            assert!(!meets_rim(&rims, &p) || 0.25 * longest <= 1e-2, "{longest} at {c:?}");
            if to_rim(c) > 2.0 * h {
                assert!(longest >= h * (1.0 - 1e-9), "refined far from the rim: {longest} at {c:?}");
            }
            if longest < h / 8.0 * (1.0 - 1e-9) {
                finest_near_rim += 1;
                deepest_off_rim = deepest_off_rim.max(to_rim(c));
            }
        }
        eprintln!("{finest_near_rim} cells finer than h / 8, the farthest {deepest_off_rim} from the rim");
        assert!(finest_near_rim > 0);
        // Measured: 14336 cells, centroids within 0.066 of the rim (a level-3 cell's ball reaches about 0.06).
        assert!(deepest_off_rim < h / 4.0, "{deepest_off_rim}");
    }

    /// A triangular prism whose cross-section has angles 40°, 70° and 70°
    /// (apex edge along z through (0.31, 0.07), back face at x = -0.33): its
    /// three long edges are blades (normals 140° and 110° apart; the caps' edges,
    /// at 90°, are not). At the apex the input point nearest to a cell's
    /// centroid is often the edge itself, where both probes across the input
    /// are outside (the thin test sees nothing): without the blades some cells
    /// holding points of the apex edge stay at the smallest size (coarsest
    /// h / 8 = 0.0625, measured at 41 points of the edge). With them (the
    /// sizing's `rims`) the cells they pass are cut as at a rim: the probe moves
    /// into the nearest triangle, the solid is thinner than the cell, and the
    /// cut goes on while [`GAP_DEPTH`] `L` exceeds the tolerance (0.1 mm):
    /// coarsest h / 16 = 0.03125 (2.5 * 0.03125 = 0.078 <= 0.1), measured and
    /// asserted. The same lattice on one thread as on two.
    #[test]
    fn a_blades_edge_is_cut_below_the_smallest_cells_like_a_rim() {
        let (ax, ay, back, half) = (0.31, 0.07, -0.33, 20f64.to_radians());
        let w = (ax - back) * half.tan();
        let vertices = vec![
            [ax, ay, -0.4],
            [back, ay + w, -0.4],
            [back, ay - w, -0.4],
            [ax, ay, 0.4],
            [back, ay + w, 0.4],
            [back, ay - w, 0.4],
        ];
        // Outward: the caps, then the upper, lower and back faces.
        let triangles = vec![[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [0, 3, 5], [0, 5, 2], [1, 2, 5], [1, 5, 4]];
        let surface = crate::Surface {
            vertices,
            triangles: triangles.clone(),
            triangle_regions: vec![0; triangles.len()],
            region_names: vec!["prism".into()],
        };
        assert!(surface.signed_volume(None) > 0.0);
        let blades = crate::distance::blade_edges(&surface, 1e-9);
        assert_eq!(blades.iter().map(|b| [b[0], b[1]]).collect::<Vec<_>>(), vec![[0, 3], [1, 4], [2, 5]]);
        let tris =
            |t: &[[u32; 3]]| -> Vec<[P; 3]> { t.iter().map(|t| t.map(|v| surface.vertices[v as usize])).collect() };
        let tree = TriangleTree::new(tris(&triangles));
        let rims = TriangleTree::new(tris(&blades));
        let no_rims = TriangleTree::new(Vec::new());
        let (h, tol) = (0.5, 0.1);
        // The coarsest cell holding a point of the apex edge (41 points, z in [-0.3, 0.3]).
        let near_apex = |g: &GradedLattice| {
            let mut coarsest: f64 = 0.0;
            for k in 0..=40 {
                let x = [ax, ay, -0.3 + 0.6 * k as f64 / 40.0];
                for t in &g.cells {
                    let p = t.map(|v| g.position(v));
                    let v = super::super::stuffing::signed_volume(&p);
                    let holds = (0..4).all(|i| {
                        let mut q = p;
                        q[i] = x;
                        super::super::stuffing::signed_volume(&q) * v >= 0.0
                    });
                    if holds {
                        coarsest = coarsest.max(centroid_and_longest(&p).1);
                    }
                }
            }
            coarsest
        };
        let (without, _) = GradedLattice::new(&tree, &no_rims, [-0.5; 3], [0.5; 3], h, 1, tol, usize::MAX);
        let (with, _) = GradedLattice::new(&tree, &rims, [-0.5; 3], [0.5; 3], h, 1, tol, usize::MAX);
        let (g0, _) = GradedLattice::new(&tree, &no_rims, [-0.5; 3], [0.5; 3], h, 0, tol, usize::MAX);
        check_conforming(&with, &g0);
        eprintln!("coarsest on the apex: without the blades {}, with {}", near_apex(&without), near_apex(&with));
        assert!(near_apex(&without) >= h / 8.0 * (1.0 - 1e-9), "{}", near_apex(&without));
        assert!(near_apex(&with) <= h / 16.0 * (1.0 + 1e-9), "{}", near_apex(&with));
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let (again, _) =
                pool.install(|| GradedLattice::new(&tree, &rims, [-0.5; 3], [0.5; 3], h, 1, tol, usize::MAX));
            assert!(again.coords == with.coords && again.cells == with.cells, "{threads} threads");
        }
    }

    /// Outward triangles of the box `[lo, hi]`.
    fn box_triangles(lo: P, hi: P) -> Vec<[P; 3]> {
        let c = |i: usize| [0, 1, 2].map(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] });
        // Each face as a quad of corner indices, counter-clockwise seen from outside.
        let quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
        quads.iter().flat_map(|q| [[c(q[0]), c(q[1]), c(q[2])], [c(q[0]), c(q[2]), c(q[3])]]).collect()
    }

    /// A sliver (dihedral angles near 0° and 180°) lying flat on the plane
    /// `y = y0` over the square `[x0, x0 + a] x [-a/2, a/2]` in z, its corners
    /// `a / 100` off the plane.
    fn flat_sliver(x0: f64, y0: f64, a: f64) -> (Vec<P>, Vec<[u32; 4]>) {
        let d = 0.01 * a;
        let nodes =
            vec![[x0, y0 + d, -0.5 * a], [x0 + a, y0 + d, 0.5 * a], [x0 + a, y0 - d, -0.5 * a], [x0, y0 - d, 0.5 * a]];
        (nodes, vec![[0, 1, 2, 3]])
    }

    /// A cube with a bar through its face x = 1 (a spout through a body): the
    /// bar's wall y = 0.2 runs inside the cube for x < 1 (winding number 1.5
    /// there) and bounds the solid for x > 1. Boundary slivers (each alone, so
    /// on the boundary), `near` = 0.01:
    /// - lying on that wall 0.2 to 0.4 inside the cube, or 0.095 to 0.1: not
    ///   peeled (the rule before, every corner within `near` of any input
    ///   triangle, peeled both; on the teapot it dug along the spout's wall
    ///   inside the body, 0.058 mm deep);
    /// - on the wall within 0.005 of the crease x = 1, where the wall meets the
    ///   cube's face (which bounds the solid there): peeled;
    /// - on the cube's face y = 1 (winding number 1/2): peeled.
    #[test]
    fn a_sliver_on_a_wall_inside_the_solid_is_not_peeled_but_one_on_its_boundary_is() {
        let mut soup = box_triangles([-1.0; 3], [1.0; 3]);
        soup.extend(box_triangles([0.5, -0.2, -0.2], [1.5, 0.2, 0.2]));
        let surface = crate::Surface {
            vertices: soup.iter().flatten().copied().collect(),
            triangles: (0..soup.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
            triangle_regions: vec![0; soup.len()],
            region_names: vec!["soup".into()],
        };
        let winding = crate::WindingNumber::new(&surface);
        assert!((winding.at([0.7, 0.2, 0.0]) - 1.5).abs() < 0.05);
        assert!((winding.at([-0.7, 1.0, 0.0]) - 0.5).abs() < 0.05);
        let (near, delta) = (0.01, 1e-9);
        let peeled = |x0: f64, y0: f64, a: f64| {
            let (mut nodes, mut cells) = flat_sliver(x0, y0, a);
            assert!(super::super::smooth::score(&cells[0].map(|v| nodes[v as usize])) < 1.0);
            let n = peel_slivers(&mut nodes, &mut cells, &winding, near, delta, 10);
            assert_eq!(cells.len() + n, 1);
            assert_eq!(nodes.len(), 4 * cells.len());
            n
        };
        assert_eq!(peeled(0.6, 0.2, 0.2), 0, "on the wall inside the solid");
        assert_eq!(peeled(0.9, 0.2, 0.005), 0, "on the wall 0.095 from the crease");
        assert_eq!(peeled(0.995, 0.2, 0.005), 1, "on the wall at the crease");
        assert_eq!(peeled(-0.8, 1.0, 0.2), 1, "on the boundary");
    }
}
