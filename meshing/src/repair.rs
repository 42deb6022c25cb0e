//! Surface repair: weld, drop degenerate and duplicate triangles, orient
//! consistently and outward, and say what was changed.
//!
//! [`repair`] never modifies its input; it returns a new [`Surface`] and a
//! [`RepairReport`] in the input's indices. The steps, in order:
//!
//! 1. **Weld** vertices within `weld_tolerance_rel x` the bounding-box diagonal
//!    of each other (transitively; exact duplicates always). Each group becomes
//!    its lowest-index vertex, whose coordinates are kept unchanged.
//! 2. **Drop degenerate triangles**: a repeated index after welding, three
//!    collinear points (exactly), or a height within the weld tolerance (a needle
//!    or cap folded onto its longest edge). Dropping does not split the
//!    neighbours of a degenerate triangle that is part of the surface (a
//!    T-junction remains, as border edges): validate the result.
//! 3. **Drop duplicate triangles**: the same three vertices as an earlier
//!    triangle, in any order; the first is kept. (A face shared by two regions is
//!    given once: the multi-region convention of [`crate::validate`].)
//! 4. **Orient**: in each closed component, every triangle of its outside shell
//!    (see [`crate::topology`]) is turned to face out, whatever the orientation
//!    of its neighbours. The remaining triangles (open components, faces inside a
//!    component) are oriented by a breadth-first walk over two-triangle edges,
//!    from the outside triangles where there are some, otherwise keeping the
//!    majority's orientation; an open component is then turned so that its
//!    signed volume about its centroid is positive (outward for a scan with a
//!    few holes).
//! 5. **Compact**: vertices no triangle uses are removed.
//!
//! Repair does not close holes, resolve self-intersections or split non-manifold
//! edges: validate the result to see what is left.
//!
//! # Example
//!
//! ```
//! use meshing::repair::{repair, RepairOptions};
//! use meshing::Surface;
//!
//! // A tetrahedron given as a triangle soup, one face inward, one face twice.
//! let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
//! let faces = [[0, 2, 1], [0, 1, 3], [0, 2, 3], [1, 2, 3], [1, 2, 3]];
//! let soup = Surface {
//!     vertices: faces.iter().flatten().map(|&i| p[i]).collect(),
//!     triangles: (0..5u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
//!     triangle_regions: vec![0; 5],
//!     region_names: vec!["tet".into()],
//! };
//! let fixed = repair(&soup, &RepairOptions::default())?;
//! assert_eq!(fixed.surface.num_vertices(), 4);
//! assert_eq!(fixed.report.dropped_duplicates, vec![[3, 4]]);
//! assert_eq!(fixed.report.flipped, vec![2]);
//! assert!((fixed.surface.signed_volume(None) - 1.0 / 6.0).abs() < 1e-15);
//! assert!(fixed.surface.require_closed_manifold().is_ok());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::collections::{HashMap, VecDeque};
use std::fmt;

use crate::predicates::is_degenerate;
use crate::topology::{self, side, Edges, UnionFind};
use crate::validate::{
    check_indices, clusters_of, referenced_vertices, triangle_height, weld_representatives, MalformedSurface,
};
use crate::Surface;

/// What [`repair`] does.
#[derive(Debug, Clone, PartialEq)]
pub struct RepairOptions {
    /// Weld tolerance as a fraction of the bounding-box diagonal (default `1e-9`;
    /// `0` welds exact duplicates only).
    pub weld_tolerance_rel: f64,
    /// Drop zero-area triangles (default `true`).
    pub drop_degenerate: bool,
    /// Drop repeated triangles (default `true`).
    pub drop_duplicates: bool,
    /// Orient consistently and outward (default `true`).
    pub orient: bool,
    /// Remove vertices no triangle uses (default `true`).
    pub remove_unreferenced: bool,
}

impl Default for RepairOptions {
    fn default() -> Self {
        RepairOptions {
            weld_tolerance_rel: 1e-9,
            drop_degenerate: true,
            drop_duplicates: true,
            orient: true,
            remove_unreferenced: true,
        }
    }
}

/// What [`repair`] changed, in the input's indices (lists ascending).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RepairReport {
    /// The weld tolerance used [mm].
    pub weld_tolerance_mm: f64,
    /// Groups of input vertices welded into their first.
    pub welded: Vec<Vec<u32>>,
    /// Input triangles dropped as degenerate.
    pub dropped_degenerate: Vec<u32>,
    /// `[kept, dropped]` input triangles, the second a repeat of the first.
    pub dropped_duplicates: Vec<[u32; 2]>,
    /// Input triangles whose orientation was reversed.
    pub flipped: Vec<u32>,
    /// Input vertices removed (unused after welding and dropping).
    pub removed_vertices: Vec<u32>,
    /// Input triangles where the orientation walk met a contradiction (a
    /// non-orientable patch, like a Moebius strip); their orientation is arbitrary.
    pub orientation_conflicts: Vec<u32>,
    /// For each input vertex, its output vertex (`None` when removed).
    pub vertex_map: Vec<Option<u32>>,
    /// For each output triangle, the input triangle it comes from.
    pub triangle_origin: Vec<u32>,
}

impl RepairReport {
    /// Whether nothing was changed.
    pub fn is_unchanged(&self) -> bool {
        self.welded.is_empty()
            && self.dropped_degenerate.is_empty()
            && self.dropped_duplicates.is_empty()
            && self.flipped.is_empty()
            && self.removed_vertices.is_empty()
    }
}

impl fmt::Display for RepairReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let merged: usize = self.welded.iter().map(|c| c.len() - 1).sum();
        write!(
            f,
            "welded {merged} vertices in {} groups (tolerance {:e} mm), dropped {} degenerate and {} duplicate \
             triangles, flipped {}, removed {} unused vertices",
            self.welded.len(),
            self.weld_tolerance_mm,
            self.dropped_degenerate.len(),
            self.dropped_duplicates.len(),
            self.flipped.len(),
            self.removed_vertices.len()
        )?;
        if !self.orientation_conflicts.is_empty() {
            write!(f, "; {} triangles in non-orientable patches", self.orientation_conflicts.len())?;
        }
        Ok(())
    }
}

/// A repaired surface and what was changed.
#[derive(Debug, Clone, PartialEq)]
pub struct Repaired {
    /// The new surface.
    pub surface: Surface,
    /// What changed.
    pub report: RepairReport,
}

impl Surface {
    /// [`repair`] with [`RepairOptions::default`].
    pub fn repaired(&self) -> Result<Repaired, MalformedSurface> {
        repair(self, &RepairOptions::default())
    }
}

/// Repairs `surface` (see the module docs); fails only on a malformed surface or
/// an option out of range.
pub fn repair(surface: &Surface, options: &RepairOptions) -> Result<Repaired, MalformedSurface> {
    check_indices(surface)?;
    if !(options.weld_tolerance_rel >= 0.0 && options.weld_tolerance_rel.is_finite()) {
        return Err(MalformedSurface::InvalidOption {
            name: "weld_tolerance_rel",
            value: options.weld_tolerance_rel,
            expected: "must be finite and >= 0",
        });
    }
    let mut report =
        RepairReport { weld_tolerance_mm: options.weld_tolerance_rel * surface.diagonal(), ..Default::default() };

    // 1. Weld.
    let used = referenced_vertices(surface);
    let reps = weld_representatives(&surface.vertices, &used, report.weld_tolerance_mm);
    report.welded = clusters_of(&reps);

    // 2, 3. Degenerate and duplicate triangles.
    let mut kept: Vec<u32> = Vec::with_capacity(surface.triangles.len());
    let mut first_with: HashMap<[u32; 3], u32> = HashMap::new();
    for (t, tri) in surface.triangles.iter().enumerate() {
        let w = tri.map(|v| reps[v as usize]);
        let pos = |v: u32| surface.vertices[v as usize];
        let degenerate = w[0] == w[1]
            || w[1] == w[2]
            || w[0] == w[2]
            || is_degenerate(pos(w[0]), pos(w[1]), pos(w[2]))
            || triangle_height(pos(w[0]), pos(w[1]), pos(w[2])) <= report.weld_tolerance_mm;
        if degenerate && options.drop_degenerate {
            report.dropped_degenerate.push(t as u32);
            continue;
        }
        if options.drop_duplicates && !degenerate {
            let mut key = w;
            key.sort_unstable();
            if let Some(&first) = first_with.get(&key) {
                report.dropped_duplicates.push([first, t as u32]);
                continue;
            }
            first_with.insert(key, t as u32);
        }
        kept.push(t as u32);
    }

    // The welded surface, in the input's vertex indices.
    let mut work = Surface {
        vertices: surface.vertices.clone(),
        triangles: kept.iter().map(|&t| surface.triangles[t as usize].map(|v| reps[v as usize])).collect(),
        triangle_regions: kept.iter().map(|&t| surface.triangle_regions[t as usize]).collect(),
        region_names: surface.region_names.clone(),
    };

    // 4. Orient.
    if options.orient {
        let (flip, conflicts) = orientation_flips(&work);
        for (k, tri) in work.triangles.iter_mut().enumerate() {
            if flip[k] {
                tri.swap(1, 2);
                report.flipped.push(kept[k]);
            }
        }
        report.orientation_conflicts = conflicts.into_iter().map(|k| kept[k as usize]).collect();
        report.flipped.sort_unstable();
        report.orientation_conflicts.sort_unstable();
    }

    // 5. Compact.
    let still_used = referenced_vertices(&work);
    let mut vertex_map: Vec<Option<u32>> = vec![None; surface.vertices.len()];
    let mut vertices = Vec::new();
    for (v, p) in surface.vertices.iter().enumerate() {
        if reps[v] == v as u32 && (still_used[v] || !options.remove_unreferenced) {
            vertex_map[v] = Some(vertices.len() as u32);
            vertices.push(*p);
        }
    }
    for v in 0..surface.vertices.len() {
        if reps[v] != v as u32 {
            vertex_map[v] = vertex_map[reps[v] as usize];
        }
    }
    report.removed_vertices =
        (0..surface.vertices.len() as u32).filter(|&v| vertex_map[v as usize].is_none()).collect();
    let out = Surface {
        vertices,
        triangles: work.triangles.iter().map(|tri| tri.map(|v| vertex_map[v as usize].unwrap_or(u32::MAX))).collect(),
        triangle_regions: work.triangle_regions,
        region_names: work.region_names,
    };
    debug_assert!(out.triangles.iter().flatten().all(|&v| (v as usize) < out.vertices.len()));
    report.vertex_map = vertex_map;
    report.triangle_origin = kept;
    Ok(Repaired { surface: out, report })
}

/// Which triangles to flip (see the module docs, step 4), and the triangles
/// where the walk met a contradiction.
fn orientation_flips(surface: &Surface) -> (Vec<bool>, Vec<u32>) {
    let n = surface.triangles.len();
    let pos = |v: u32| surface.vertices[v as usize];
    let skip: Vec<bool> = surface.triangles.iter().map(|t| is_degenerate(pos(t[0]), pos(t[1]), pos(t[2]))).collect();
    let edges = Edges::new(&surface.triangles, &skip);
    let (component_of, num_components) = topology::components(n, &edges, &skip);
    let shells = topology::shells(&surface.vertices, &surface.triangles, &edges, &skip);

    let mut closed = vec![true; num_components];
    for e in 0..edges.len() {
        if let [only] = edges.uses(e) {
            closed[component_of[only.tri as usize] as usize] = false;
        }
    }
    // The outside shell of each closed component: least volume.
    let mut outer: Vec<Option<u32>> = vec![None; num_components];
    for (t, &c) in component_of.iter().enumerate() {
        if c == u32::MAX || !closed[c as usize] {
            continue;
        }
        for s in [side(t as u32, true), side(t as u32, false)] {
            let sh = shells.of_side[s as usize];
            if outer[c as usize].is_none_or(|o| shells.volume[sh as usize] < shells.volume[o as usize]) {
                outer[c as usize] = Some(sh);
            }
        }
    }
    // Fixed orientations: outside triangles face out.
    let mut fixed: Vec<Option<bool>> = vec![None; n];
    for (t, &c) in component_of.iter().enumerate() {
        let Some(o) = (c != u32::MAX).then(|| outer[c as usize]).flatten() else { continue };
        let plus = shells.of_side[side(t as u32, true) as usize] == o;
        let minus = shells.of_side[side(t as u32, false) as usize] == o;
        if plus != minus {
            fixed[t] = Some(minus);
        }
    }

    // Manifold adjacency: (neighbour, this triangle runs the edge forward,
    // the neighbour runs it forward).
    let mut adjacent: Vec<Vec<(u32, bool, bool)>> = vec![Vec::new(); n];
    let mut patches = UnionFind::new(n);
    for e in 0..edges.len() {
        if let [a, b] = edges.uses(e) {
            adjacent[a.tri as usize].push((b.tri, a.forward, b.forward));
            adjacent[b.tri as usize].push((a.tri, b.forward, a.forward));
            patches.union(a.tri, b.tri);
        }
    }
    let (patch_of, num_patches) = patches.labels();
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); num_patches];
    for t in 0..n {
        if !skip[t] {
            members[patch_of[t] as usize].push(t as u32);
        }
    }

    let mut flip: Vec<Option<bool>> = vec![None; n];
    let mut conflicts = Vec::new();
    let mut queue = VecDeque::new();
    for patch in &members {
        if patch.is_empty() {
            continue;
        }
        let seeds: Vec<u32> = patch.iter().copied().filter(|&t| fixed[t as usize].is_some()).collect();
        let has_fixed = !seeds.is_empty();
        if has_fixed {
            for &t in &seeds {
                flip[t as usize] = fixed[t as usize];
                queue.push_back(t);
            }
        } else {
            flip[patch[0] as usize] = Some(false);
            queue.push_back(patch[0]);
        }
        while let Some(t) = queue.pop_front() {
            let ft = flip[t as usize].unwrap_or(false);
            for &(u, t_forward, u_forward) in &adjacent[t as usize] {
                // Consistent when the two run the shared edge in opposite directions.
                let want = u_forward == (t_forward ^ ft);
                match flip[u as usize] {
                    None => {
                        flip[u as usize] = Some(want);
                        queue.push_back(u);
                    }
                    Some(have) if have != want && fixed[u as usize].is_none() && fixed[t as usize].is_none() => {
                        conflicts.push(u);
                    }
                    Some(_) => {}
                }
            }
        }
        if !has_fixed {
            let flipped = patch.iter().filter(|&&t| flip[t as usize] == Some(true)).count();
            if 2 * flipped > patch.len() {
                for &t in patch {
                    flip[t as usize] = flip[t as usize].map(|f| !f);
                }
            }
        }
    }
    let mut flip: Vec<bool> = flip.into_iter().map(|f| f.unwrap_or(false)).collect();

    // Open components: outward by the sign of the signed volume about the centroid.
    let mut centroid = vec![[0.0f64; 3]; num_components];
    let mut count = vec![0usize; num_components];
    for (t, &c) in component_of.iter().enumerate() {
        if c == u32::MAX || closed[c as usize] {
            continue;
        }
        for &v in &surface.triangles[t] {
            for (sum, x) in centroid[c as usize].iter_mut().zip(surface.vertices[v as usize]) {
                *sum += x;
            }
            count[c as usize] += 1;
        }
    }
    for c in 0..num_components {
        if count[c] > 0 {
            centroid[c] = centroid[c].map(|x| x / count[c] as f64);
        }
    }
    let mut volume = vec![0.0f64; num_components];
    for (t, &c) in component_of.iter().enumerate() {
        if c == u32::MAX || closed[c as usize] {
            continue;
        }
        let [a, b, cc] = surface.triangles[t].map(|v| {
            let p = surface.vertices[v as usize];
            let o = centroid[c as usize];
            [p[0] - o[0], p[1] - o[1], p[2] - o[2]]
        });
        let v = crate::predicates::dot(a, crate::predicates::cross(b, cc)) / 6.0;
        volume[c as usize] += if flip[t] { -v } else { v };
    }
    for (t, &c) in component_of.iter().enumerate() {
        if c != u32::MAX && !closed[c as usize] && volume[c as usize] < 0.0 {
            flip[t] = !flip[t];
        }
    }
    conflicts.sort_unstable();
    conflicts.dedup();
    (flip, conflicts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validate::{validate, Defect, ValidateOptions};

    fn tetra(flip: &[usize]) -> Surface {
        let mut triangles = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        for &t in flip {
            triangles[t].swap(1, 2);
        }
        Surface {
            vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            triangles,
            triangle_regions: vec![0; 4],
            region_names: vec!["tet".into()],
        }
    }

    #[test]
    fn a_clean_surface_is_unchanged() {
        let s = tetra(&[]);
        let r = s.repaired().unwrap();
        assert!(r.report.is_unchanged(), "{}", r.report);
        assert_eq!(r.surface, s);
    }

    #[test]
    fn inverted_and_half_flipped_tetrahedra_come_out_outward() {
        for flips in [vec![0, 1, 2, 3], vec![1, 3], vec![2]] {
            let r = tetra(&flips).repaired().unwrap();
            assert_eq!(r.report.flipped.len(), flips.len(), "{flips:?}");
            assert!((r.surface.signed_volume(None) - 1.0 / 6.0).abs() < 1e-15);
            assert!(r.surface.require_closed_manifold().is_ok());
        }
    }

    #[test]
    fn an_open_inverted_patch_is_turned_by_its_volume() {
        // Three faces of the tetrahedron, all inward: open, so oriented by volume.
        let mut s = tetra(&[0, 1, 2, 3]);
        s.triangles.pop();
        s.triangle_regions.pop();
        let r = s.repaired().unwrap();
        assert_eq!(r.report.flipped, vec![0, 1, 2]);
        let v = validate(&r.surface, &ValidateOptions::default()).unwrap();
        assert_eq!(v.defects.len(), 1);
        assert!(matches!(v.defects[0], Defect::OpenBoundary { .. }));
    }

    #[test]
    fn bad_options_and_indices_are_errors() {
        let s = tetra(&[]);
        let opts = RepairOptions { weld_tolerance_rel: f64::NAN, ..Default::default() };
        assert!(matches!(repair(&s, &opts), Err(MalformedSurface::InvalidOption { .. })));
        let mut bad = s.clone();
        bad.triangle_regions[2] = 7;
        assert!(matches!(
            repair(&bad, &RepairOptions::default()),
            Err(MalformedSurface::RegionIndex { triangle: 2, .. })
        ));
    }
}
