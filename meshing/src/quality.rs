//! Mesh quality and fidelity: what `wagashi mesh` prints and writes as JSON.
//!
//! Per tetrahedron ([`tet_quality`]):
//!
//! - the six **dihedral angles** [deg] (the angle between the two faces at an edge);
//! - the **radius-edge ratio** `R / l_min` (circumradius over shortest edge;
//!   `√6 / 4 ≈ 0.612` for the regular tet, unbounded for slivers' cousins);
//! - the **radius ratio** `3 r / R` (inradius over circumradius, normalized to 1
//!   for the regular tet, 0 for a flat one).
//!
//! Over the mesh ([`report`]): min and max dihedral angle, the fraction of tets
//! whose smallest dihedral angle is under 10°, max and 99.9th percentile of the
//! radius-edge ratio, mean and min radius ratio, the volume against the surface's
//! enclosed volume, per-region volumes, and the **symmetric Hausdorff distance**
//! between the mesh's boundary and the input surface, relative to the input's
//! bounding-box diagonal.
//!
//! ## Reference volumes
//!
//! A region's enclosed volume is [`Surface::signed_volume`] of its triangles (the
//! divergence theorem). Regions inside others (nested shells: a vertex of the
//! inner shell has winding number > 1/2 for the outer one, and its volume is
//! smaller) are subtracted from their smallest container, so the layered bunny's
//! references are `bunny - sphereA`, `sphereA - sphereB`, `sphereB`. The whole
//! reference is the sum over the outermost regions. Shells touching along
//! non-manifold edges (two boxes sharing a face given once) are first split into
//! the cells they bound, as the envelope mesher does. Overlapping, non-nested
//! shells are counted twice: compare such input against its exact union instead
//! (as the tests do).
//!
//! ## Hausdorff distance
//!
//! The distance the envelope mode is judged by ([`crate::distance`]): the
//! larger of an upper bound of the distance from the mesh boundary to the
//! boundary of the solid its winding number defines (the part of the input
//! bounding it, plus the level set `w = 1/2` where it leaves the input: caps
//! over holes, the mouth of an open tube) and the distance from the bounding
//! input to the mesh boundary (inner caps of overlapping parts, parts of a
//! self-intersecting input inside the rest, region interfaces and stray faces
//! are not boundary). The mesh's caps over holes of an open input (farther
//! than a sample spacing from the input, nearer to the level set) are reported
//! apart ([`QualityReport::hole_cap_mm`], [`QualityReport::widest_hole_mm`]), with
//! how far they stray from the level set ([`QualityReport::cap_to_level_set_mm`]),
//! and the raw figure (every input triangle, caps included) beside it. Both surfaces are sampled on a
//! barycentric grid of spacing at most 1/300 of the diagonal; the sampled maximum
//! is below the true one by at most a sample spacing.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` also refuses NaN, deliberately.

use std::time::Instant;

use fem_core::mesh::TetMesh;
use rayon::prelude::*;
use serde::Serialize;

use crate::distance::boundary_distance;
use crate::envelope::tree::{cross, dot, norm, scale, sub};
use crate::{Surface, WindingNumber};

type P = [f64; 3];

/// The quality of one tetrahedron.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetQuality {
    /// Smallest dihedral angle [deg].
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle [deg].
    pub max_dihedral_deg: f64,
    /// Circumradius over shortest edge (0.612 for the regular tet).
    pub radius_edge: f64,
    /// 3 x inradius over circumradius (1 for the regular tet).
    pub radius_ratio: f64,
    /// Signed volume [mm^3].
    pub volume_mm3: f64,
}

/// The six edges `(i, j)` of a tet, each with its two other corners `(k, l)`.
const EDGES: [(usize, usize, usize, usize); 6] =
    [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)];

/// The length of edge `(i, j)` of the tet `p` and the cosine of the dihedral
/// angle there; 1 (an angle of 0) for a degenerate edge or face.
fn edge_dihedral_cos(p: &[P; 4], (i, j, k, l): (usize, usize, usize, usize)) -> (f64, f64) {
    let e = sub(p[j], p[i]);
    let le = norm(e);
    if le > 0.0 {
        let e = scale(e, 1.0 / le);
        let u = sub(p[k], p[i]);
        let v = sub(p[l], p[i]);
        let u = sub(u, scale(e, dot(u, e)));
        let v = sub(v, scale(e, dot(v, e)));
        let (nu, nv) = (norm(u), norm(v));
        if nu > 0.0 && nv > 0.0 {
            return (le, (dot(u, v) / (nu * nv)).clamp(-1.0, 1.0));
        }
    }
    (le, 1.0)
}

/// The quality of the tet with corners `p` [mm].
pub fn tet_quality(p: &[P; 4]) -> TetQuality {
    let mut min_d = f64::INFINITY;
    let mut max_d: f64 = 0.0;
    let mut l_min = f64::INFINITY;
    for edge in EDGES {
        let (le, cos) = edge_dihedral_cos(p, edge);
        l_min = l_min.min(le);
        let angle = cos.acos().to_degrees();
        min_d = min_d.min(angle);
        max_d = max_d.max(angle);
    }
    let (circumradius, det) = circumradius(p);
    // `tet_volume`'s expression, bit for bit.
    let volume = det / 6.0;
    let area: f64 = (0..4)
        .map(|i| {
            let f = [p[(i + 1) % 4], p[(i + 2) % 4], p[(i + 3) % 4]];
            0.5 * norm(cross(sub(f[1], f[0]), sub(f[2], f[0])))
        })
        .sum();
    let inradius = if area > 0.0 { 3.0 * volume.abs() / area } else { 0.0 };
    let radius_ratio = if circumradius.is_finite() && circumradius > 0.0 { 3.0 * inradius / circumradius } else { 0.0 };
    let radius_edge = if l_min > 0.0 { circumradius / l_min } else { f64::INFINITY };
    TetQuality { min_dihedral_deg: min_d, max_dihedral_deg: max_d, radius_edge, radius_ratio, volume_mm3: volume }
}

/// The circumradius [mm] of the tet with corners `p` (infinite when it is
/// flat) and the determinant of its edge vectors from `p[0]` (6 times its
/// signed volume, `tet_volume`'s expression).
fn circumradius(p: &[P; 4]) -> (f64, f64) {
    let a = sub(p[1], p[0]);
    let b = sub(p[2], p[0]);
    let c = sub(p[3], p[0]);
    let det = dot(a, cross(b, c));
    let num = [
        dot(a, a) * cross(b, c)[0] + dot(b, b) * cross(c, a)[0] + dot(c, c) * cross(a, b)[0],
        dot(a, a) * cross(b, c)[1] + dot(b, b) * cross(c, a)[1] + dot(c, c) * cross(a, b)[1],
        dot(a, a) * cross(b, c)[2] + dot(b, b) * cross(c, a)[2] + dot(c, c) * cross(a, b)[2],
    ];
    (if det != 0.0 { norm(num) / (2.0 * det.abs()) } else { f64::INFINITY }, det)
}

/// The radius-edge ratio of the tet with corners `p`: [`tet_quality`]'s
/// `radius_edge`, bit for bit, without the angles (for the smoothing loops
/// that need only the ratio).
pub fn radius_edge_ratio(p: &[P; 4]) -> f64 {
    let l_min = EDGES.iter().map(|&(i, j, _, _)| norm(sub(p[j], p[i]))).fold(f64::INFINITY, f64::min);
    if l_min > 0.0 {
        circumradius(p).0 / l_min
    } else {
        f64::INFINITY
    }
}

/// The signed volume [mm^3] of the tet with corners `p` (`tet_quality`'s `volume_mm3`).
pub fn tet_volume(p: &[P; 4]) -> f64 {
    dot(sub(p[1], p[0]), cross(sub(p[2], p[0]), sub(p[3], p[0]))) / 6.0
}

/// The smallest and largest dihedral angles [deg] of the tet with corners
/// `p`: the same values, bit for bit, as [`tet_quality`]'s
/// `min_dihedral_deg` and `max_dihedral_deg`, for the refinement and
/// smoothing loops that need only those. Each angle's cosine is computed as
/// there, and only the extreme cosines go through `acos` (2 calls instead of
/// 6; `acos` and the conversion to degrees are monotone, so the extremes of
/// the angles are the angles of the extreme cosines). A degenerate edge or
/// face counts as an angle of 0 (a cosine of 1), as there; NaN cosines are
/// ignored, as `f64::min` ignores them there.
pub fn dihedral_range_deg(p: &[P; 4]) -> (f64, f64) {
    let (lo, hi) = dihedral_cos_range(p);
    // No finite cosine: `tet_quality`'s starting values.
    let min_deg = if hi == f64::NEG_INFINITY { f64::INFINITY } else { hi.acos().to_degrees() };
    let max_deg = if lo == f64::INFINITY { 0.0 } else { lo.acos().to_degrees() };
    (min_deg, max_deg)
}

/// The smallest and largest cosine of the dihedral angles of the tet with
/// corners `p` (NaN cosines ignored; infinite, of the wrong sign, when all
/// are NaN): what [`dihedral_range_deg`] takes the `acos` of. The smallest
/// dihedral angle of several tets is the `acos` of the largest of their
/// largest cosines, bit for bit (`acos` and the conversion to degrees are
/// monotone), for loops over stars.
pub fn dihedral_cos_range(p: &[P; 4]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for edge in EDGES {
        let (_, cos) = edge_dihedral_cos(p, edge);
        lo = lo.min(cos);
        hi = hi.max(cos);
    }
    (lo, hi)
}

/// One region's share of the mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegionQuality {
    /// The region's name.
    pub name: String,
    /// Its cells.
    pub num_cells: usize,
    /// Its volume [mm^3].
    pub volume_mm3: f64,
    /// The enclosed volume of its shell less the shells nested in it [mm^3], when
    /// the mesh's regions are the surface's (see the module docs).
    pub reference_volume_mm3: Option<f64>,
    /// `(volume - reference) / reference`.
    pub volume_error: Option<f64>,
}

/// The quality report (see the module docs). Angles in degrees, lengths in mm.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QualityReport {
    /// Nodes.
    pub num_nodes: usize,
    /// Tetrahedra.
    pub num_cells: usize,
    /// Boundary triangles.
    pub num_boundary_faces: usize,
    /// Smallest dihedral angle [deg].
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle [deg].
    pub max_dihedral_deg: f64,
    /// Fraction of the tets whose smallest dihedral angle is under 10°.
    pub fraction_below_10_deg: f64,
    /// Largest radius-edge ratio.
    pub max_radius_edge: f64,
    /// 99.9th percentile of the radius-edge ratio.
    pub p999_radius_edge: f64,
    /// Mean radius ratio (1 = regular).
    pub mean_radius_ratio: f64,
    /// Smallest radius ratio.
    pub min_radius_ratio: f64,
    /// Tets of non-positive volume (0 for a valid mesh).
    pub num_inverted: usize,
    /// Mesh volume [mm^3].
    pub volume_mm3: f64,
    /// The surface's enclosed volume [mm^3] (see the module docs).
    pub reference_volume_mm3: f64,
    /// `(volume - reference) / reference`.
    pub volume_error: f64,
    /// The input's bounding-box diagonal [mm].
    pub diagonal_mm: f64,
    /// The larger of `mesh_to_surface_mm` and `surface_to_mesh_mm` [mm] (module docs).
    pub hausdorff_mm: f64,
    /// `hausdorff_mm / diagonal_mm`.
    pub hausdorff_relative: f64,
    /// Largest upper bound of the distance from the mesh boundary (caps over
    /// holes left out) to the solid's boundary (the bounding input and the level
    /// set `w = 1/2`) [mm].
    pub mesh_to_surface_mm: f64,
    /// Largest distance from the bounding part of the input to the mesh boundary [mm].
    pub surface_to_mesh_mm: f64,
    /// Largest distance to the input of the mesh boundary over the input's holes
    /// (farther than a sample spacing from the input, nearer to the level set
    /// `w = 1/2`) [mm] (0: none).
    pub hole_cap_mm: f64,
    /// `hole_cap_mm / diagonal_mm`.
    pub hole_cap_relative: f64,
    /// Largest upper bound of the distance from the mesh boundary over the
    /// input's holes to the level set `w = 1/2` closing them [mm] (0: none).
    pub cap_to_level_set_mm: f64,
    /// `cap_to_level_set_mm / diagonal_mm`.
    pub cap_to_level_set_relative: f64,
    /// Fraction of the mesh boundary's samples over the input's holes.
    pub hole_cap_fraction: f64,
    /// Border edges of the input (after welding within 1e-6 of the diagonal).
    pub num_border_edges: usize,
    /// The widest connected chain of border edges: its bounding-box diagonal [mm].
    pub widest_hole_mm: f64,
    /// Raw symmetric Hausdorff distance: every input triangle counted, caps included [mm].
    pub raw_hausdorff_mm: f64,
    /// `raw_hausdorff_mm / diagonal_mm`.
    pub raw_hausdorff_relative: f64,
    /// Raw: largest distance from the mesh boundary to any input triangle [mm].
    pub raw_mesh_to_surface_mm: f64,
    /// Raw: largest distance from any input triangle to the mesh boundary [mm].
    pub raw_surface_to_mesh_mm: f64,
    /// Input triangles left out of the Hausdorff distance (not bounding the solid anywhere).
    pub num_interior_input_triangles: usize,
    /// Input triangles bounding the solid in part (crossed by a jump of the winding number).
    pub num_partly_interior_input_triangles: usize,
    /// Per region, in the mesh's order.
    pub regions: Vec<RegionQuality>,
    /// Meshing time [s], as given by the caller (0 when not given).
    pub mesh_time_s: f64,
    /// Time to compute this report [s].
    pub report_time_s: f64,
}

/// The cell statistics of [`QualityReport`] alone (no surface needed):
/// `(min dihedral, max dihedral, fraction < 10°, max radius-edge, p99.9 radius-edge,
/// mean radius ratio, min radius ratio, inverted count)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CellStatistics {
    /// Smallest dihedral angle [deg].
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle [deg].
    pub max_dihedral_deg: f64,
    /// Fraction of the tets whose smallest dihedral angle is under 10°.
    pub fraction_below_10_deg: f64,
    /// Largest radius-edge ratio.
    pub max_radius_edge: f64,
    /// 99.9th percentile of the radius-edge ratio.
    pub p999_radius_edge: f64,
    /// Mean radius ratio.
    pub mean_radius_ratio: f64,
    /// Smallest radius ratio.
    pub min_radius_ratio: f64,
    /// Tets of non-positive volume.
    pub num_inverted: usize,
}

/// The cell statistics of `mesh`.
pub fn cell_statistics(mesh: &TetMesh) -> CellStatistics {
    let q: Vec<TetQuality> = mesh.cells.par_iter().map(|c| tet_quality(&c.map(|v| mesh.nodes[v as usize]))).collect();
    let n = q.len().max(1) as f64;
    let mut re: Vec<f64> = q.iter().map(|t| t.radius_edge).collect();
    re.sort_by(f64::total_cmp);
    let p999 = if re.is_empty() { 0.0 } else { re[((re.len() - 1) as f64 * 0.999).floor() as usize] };
    CellStatistics {
        min_dihedral_deg: q.iter().map(|t| t.min_dihedral_deg).fold(f64::INFINITY, f64::min),
        max_dihedral_deg: q.iter().map(|t| t.max_dihedral_deg).fold(0.0, f64::max),
        fraction_below_10_deg: q.iter().filter(|t| t.min_dihedral_deg < 10.0).count() as f64 / n,
        max_radius_edge: re.last().copied().unwrap_or(0.0),
        p999_radius_edge: p999,
        mean_radius_ratio: q.iter().map(|t| t.radius_ratio).sum::<f64>() / n,
        min_radius_ratio: q.iter().map(|t| t.radius_ratio).fold(f64::INFINITY, f64::min),
        num_inverted: q.iter().filter(|t| !(t.volume_mm3 > 0.0)).count(),
    }
}

/// The full report of `mesh` against the input `surface`; `mesh_time_s` is copied in.
pub fn report(mesh: &TetMesh, surface: &Surface, mesh_time_s: f64) -> QualityReport {
    let start = Instant::now();
    // Touching shells given once are measured as the cells the envelope meshes.
    let split = crate::envelope::split_cells(surface);
    let surface = split.as_ref().unwrap_or(surface);
    let cells = cell_statistics(mesh);
    let volume_mm3 = mesh.measure();
    let diagonal_mm = surface.diagonal();

    // Reference volumes of nested shells.
    let nreg =
        surface.region_names.len().max(surface.triangle_regions.iter().map(|&r| r as usize + 1).max().unwrap_or(1));
    let shell_volume: Vec<f64> = (0..nreg as u32).map(|r| surface.signed_volume(Some(r)).abs()).collect();
    let parent = nesting(surface, &shell_volume);
    let mut own = shell_volume.clone();
    for (s, p) in parent.iter().enumerate() {
        if let Some(p) = p {
            own[*p] -= shell_volume[s];
        }
    }
    let reference_volume_mm3: f64 = (0..nreg).filter(|&r| parent[r].is_none()).map(|r| shell_volume[r]).sum();
    let same_regions = mesh.region_names.len() == nreg && nreg > 1 && mesh.region_names == surface.region_names;
    // Each region's cells and volume, summed in cell order (one pass over the
    // cells, not one per region; the volumes are `tet_quality`'s, bit for bit).
    let cell_volumes: Vec<f64> =
        mesh.cells.par_iter().map(|c| tet_volume(&c.map(|x| mesh.nodes[x as usize]))).collect();
    let mut region_sums = vec![(0.0, 0usize); mesh.region_names.len()];
    for (&v, &cr) in cell_volumes.iter().zip(&mesh.cell_regions) {
        if let Some((sum, n)) = region_sums.get_mut(cr as usize) {
            *sum += v;
            *n += 1;
        }
    }
    let regions = mesh
        .region_names
        .iter()
        .zip(region_sums)
        .enumerate()
        .map(|(r, (name, (v, n)))| {
            let reference = if same_regions || (nreg == 1 && mesh.region_names.len() == 1) {
                Some(if nreg == 1 { reference_volume_mm3 } else { own[r] })
            } else {
                None
            };
            RegionQuality {
                name: name.clone(),
                num_cells: n,
                volume_mm3: v,
                reference_volume_mm3: reference,
                volume_error: reference.map(|rv| (v - rv) / rv),
            }
        })
        .collect();

    // Hausdorff distance.
    let faces = mesh.boundary_facets();
    let out_tris: Vec<[P; 3]> = faces.iter().map(|f| f.map(|v| mesh.nodes[v as usize])).collect();
    let d = boundary_distance(&out_tris, surface, diagonal_mm / 300.0);
    let relative = |x: f64| if diagonal_mm > 0.0 { x / diagonal_mm } else { 0.0 };
    QualityReport {
        num_nodes: mesh.nodes.len(),
        num_cells: mesh.cells.len(),
        num_boundary_faces: faces.len(),
        min_dihedral_deg: cells.min_dihedral_deg,
        max_dihedral_deg: cells.max_dihedral_deg,
        fraction_below_10_deg: cells.fraction_below_10_deg,
        max_radius_edge: cells.max_radius_edge,
        p999_radius_edge: cells.p999_radius_edge,
        mean_radius_ratio: cells.mean_radius_ratio,
        min_radius_ratio: cells.min_radius_ratio,
        num_inverted: cells.num_inverted,
        volume_mm3,
        reference_volume_mm3,
        volume_error: (volume_mm3 - reference_volume_mm3) / reference_volume_mm3,
        diagonal_mm,
        hausdorff_mm: d.hausdorff_mm,
        hausdorff_relative: relative(d.hausdorff_mm),
        mesh_to_surface_mm: d.mesh_to_boundary_mm,
        surface_to_mesh_mm: d.boundary_to_mesh_mm,
        hole_cap_mm: d.hole_cap_mm,
        hole_cap_relative: relative(d.hole_cap_mm),
        cap_to_level_set_mm: d.cap_to_level_set_mm,
        cap_to_level_set_relative: relative(d.cap_to_level_set_mm),
        hole_cap_fraction: d.hole_cap_fraction,
        num_border_edges: d.num_border_edges,
        widest_hole_mm: d.widest_hole_mm,
        raw_hausdorff_mm: d.raw_hausdorff_mm,
        raw_hausdorff_relative: relative(d.raw_hausdorff_mm),
        raw_mesh_to_surface_mm: d.raw_mesh_to_surface_mm,
        raw_surface_to_mesh_mm: d.raw_surface_to_mesh_mm,
        num_interior_input_triangles: d.num_interior_input_triangles,
        num_partly_interior_input_triangles: d.num_partly_interior_input_triangles,
        regions,
        mesh_time_s,
        report_time_s: start.elapsed().as_secs_f64(),
    }
}

/// For each region, the smallest other region whose shell contains it.
fn nesting(surface: &Surface, volume: &[f64]) -> Vec<Option<usize>> {
    let n = volume.len();
    if n < 2 {
        return vec![None; n];
    }
    let windings: Vec<WindingNumber> = (0..n as u32).map(|r| WindingNumber::of_region(surface, r)).collect();
    // Up to five vertices of each region, to test for containment by majority.
    let mut probes: Vec<Vec<P>> = vec![Vec::new(); n];
    for (t, &r) in surface.triangles.iter().zip(&surface.triangle_regions) {
        let list = &mut probes[r as usize];
        if list.len() < 5 {
            list.push(surface.vertices[t[0] as usize]);
        }
    }
    (0..n)
        .map(|s| {
            let mut best: Option<usize> = None;
            for r in 0..n {
                if r == s || !(volume[r] > volume[s]) || probes[s].is_empty() {
                    continue;
                }
                let inside = probes[s].iter().filter(|&&p| windings[r].is_inside(p)).count();
                if 2 * inside > probes[s].len() && best.is_none_or(|b| volume[r] < volume[b]) {
                    best = Some(r);
                }
            }
            best
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_regular_tet_scores_its_textbook_values() {
        let p = [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]];
        let q = tet_quality(&p);
        let dihedral = (1.0f64 / 3.0).acos().to_degrees();
        assert!((q.min_dihedral_deg - dihedral).abs() < 1e-9 && (q.max_dihedral_deg - dihedral).abs() < 1e-9);
        assert!((q.radius_edge - 6f64.sqrt() / 4.0).abs() < 1e-12);
        assert!((q.radius_ratio - 1.0).abs() < 1e-12);
        assert!(q.volume_mm3.abs() > 0.0);
    }

    #[test]
    fn dihedral_range_and_radius_edge_ratio_are_tet_qualitys_bit_for_bit() {
        // Random tets, slivers (a corner near the opposite face), needles and
        // degenerate ones (repeated corners, collinear corners).
        let mut state = 0x1234_5678_9abc_def0u64;
        let mut rand = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut cases: Vec<[P; 4]> = Vec::new();
        for n in 0..20_000 {
            let mut p = [[0.0; 3]; 4].map(|_| [rand(), rand(), rand()]);
            match n % 5 {
                1 => p[3] = [0, 1, 2].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0 + 1e-9 * rand()),
                2 => p[1] = [0, 1, 2].map(|k| p[0][k] + 1e-7 * rand()),
                3 => p[2] = p[1],
                4 => p[2] = [0, 1, 2].map(|k| 0.5 * (p[0][k] + p[1][k])),
                _ => {}
            }
            cases.push(p);
        }
        cases.push([[0.0; 3]; 4]);
        for p in &cases {
            let q = tet_quality(p);
            let (lo, hi) = dihedral_range_deg(p);
            assert_eq!(lo.to_bits(), q.min_dihedral_deg.to_bits(), "{p:?}: {lo} against {q:?}");
            assert_eq!(hi.to_bits(), q.max_dihedral_deg.to_bits(), "{p:?}: {hi} against {q:?}");
            let re = radius_edge_ratio(p);
            assert_eq!(re.to_bits(), q.radius_edge.to_bits(), "{p:?}: {re} against {q:?}");
        }
        // The smallest angle of a group of tets (a star) from its largest cosine.
        for star in cases.chunks(7) {
            let min = star.iter().map(|p| tet_quality(p).min_dihedral_deg).fold(f64::INFINITY, f64::min);
            let cos = star.iter().map(|p| dihedral_cos_range(p).1).fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(min.to_bits(), cos.acos().to_degrees().to_bits(), "{star:?}");
        }
    }

    #[test]
    fn a_right_corner_tet_has_a_right_dihedral_angle() {
        let q = tet_quality(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        assert!((q.max_dihedral_deg - 90.0).abs() < 1e-9);
        assert!((q.min_dihedral_deg - 54.735_610_317_245_35).abs() < 1e-9, "{q:?}");
        assert!((q.volume_mm3 - 1.0 / 6.0).abs() < 1e-15);
    }
}
