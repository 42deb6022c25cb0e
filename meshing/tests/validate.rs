//! Validation and repair on the Stanford bunny (`tests/fixtures`) and the shared
//! defect corpus (`../shared/data/meshes`, read in place, never copied; a test
//! that reads it skips without it, see `tests/support/data.rs`).

use std::time::Instant;

use meshing::repair::{repair, RepairOptions};
use meshing::validate::{validate, Defect, DegenerateKind, ValidateOptions};
use meshing::InvalidSurface;
use meshing::{Surface, SurfaceReport};

mod common;
use common::{bunny, read_obj, skip_without_shared_data};

fn check(s: &Surface) -> SurfaceReport {
    validate(s, &ValidateOptions::default()).expect("well-formed")
}

fn kinds(r: &SurfaceReport) -> Vec<&'static str> {
    r.defects.iter().map(|d| d.kind()).collect()
}

/// Triangles as oriented cycles starting at their lowest vertex, sorted: equal
/// for two surfaces with the same oriented triangles in any order.
fn oriented_set(s: &Surface) -> Vec<[u32; 3]> {
    let mut t: Vec<[u32; 3]> = s
        .triangles
        .iter()
        .map(|&[a, b, c]| {
            if a < b && a < c {
                [a, b, c]
            } else if b < c {
                [b, c, a]
            } else {
                [c, a, b]
            }
        })
        .collect();
    t.sort_unstable();
    t
}

fn rel_close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1e-300)
}

#[test]
fn the_bunny_is_closed_outward_and_valid() {
    let s = bunny();
    let r = s.require_closed_manifold().expect("valid");
    assert_eq!((r.num_vertices, r.num_triangles, r.num_edges), (1839, 3674, 5511));
    assert_eq!(r.components.len(), 1);
    assert_eq!(r.num_shells, 2);
    let c = &r.components[0];
    assert!(c.closed);
    // The enclosed volume from the shells equals the signed volume as given (outward).
    assert!(rel_close(c.enclosed_volume_mm3.unwrap(), c.signed_volume_mm3, 1e-12));
    assert!(rel_close(c.signed_volume_mm3, 194.288, 1e-5), "{}", c.signed_volume_mm3);
    let fixed = repair(&s, &RepairOptions::default()).unwrap();
    assert!(fixed.report.is_unchanged(), "{}", fixed.report);
    assert_eq!(fixed.surface, s);
}

#[test]
fn validation_is_fast_on_the_bunny_and_on_a_235k_subdivision() {
    let s = bunny();
    let t = Instant::now();
    let r = check(&s);
    let bunny = t.elapsed().as_secs_f64();
    assert!(r.is_valid());
    // Three rounds of 1-to-4 midpoint subdivision: 235,136 triangles, still
    // closed and free of intersections.
    let mut big = s.clone();
    for _ in 0..3 {
        big = subdivide(&big);
    }
    assert_eq!(big.num_triangles(), 3674 * 64);
    let t = Instant::now();
    let r = check(&big);
    let large = t.elapsed().as_secs_f64();
    assert!(r.is_valid(), "{r}");
    println!("validate: bunny (3,674 triangles) {:.1} ms, subdivided (235,136) {:.0} ms", bunny * 1e3, large * 1e3);
    // Budgets far above the times measured on the 2-core development machine
    // (12 ms and 1.7 s, with the other tests running).
    assert!(bunny < 1.0, "bunny validation took {bunny} s");
    assert!(large < 30.0, "235k-triangle validation took {large} s");
}

/// Splits every triangle into four at its edge midpoints (shared between
/// neighbours).
fn subdivide(s: &Surface) -> Surface {
    let mut out = Surface { vertices: s.vertices.clone(), region_names: s.region_names.clone(), ..Default::default() };
    let mut midpoint = std::collections::HashMap::new();
    let mut mid = |a: u32, b: u32, out: &mut Surface| {
        *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (p, q) = (out.vertices[a as usize], out.vertices[b as usize]);
            out.vertices.push([(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, (p[2] + q[2]) / 2.0]);
            out.vertices.len() as u32 - 1
        })
    };
    for (&[a, b, c], &r) in s.triangles.iter().zip(&s.triangle_regions) {
        let (ab, bc, ca) = (mid(a, b, &mut out), mid(b, c, &mut out), mid(c, a, &mut out));
        for t in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
            out.triangles.push(t);
            out.triangle_regions.push(r);
        }
    }
    out
}

#[test]
fn the_teapot_is_open_in_several_pieces_and_self_intersecting() {
    if skip_without_shared_data("the mesh fixture npm_teapot.obj") {
        return;
    }
    let s = read_obj("meshes/npm_teapot.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["unwelded vertices", "open boundary", "self-intersections"]);
    // Its 32 patches repeat their seam vertices at exactly the same points.
    let Defect::UnweldedVertices { clusters, .. } = &r.defects[0] else { unreachable!() };
    assert_eq!(clusters.len(), 193);
    assert!(clusters.iter().all(|c| c.iter().all(|&v| s.vertices[v as usize] == s.vertices[c[0] as usize])));
    let Defect::OpenBoundary { edges, num_loops } = &r.defects[1] else { unreachable!() };
    assert_eq!((edges.len(), *num_loops), (64, 6));
    assert_eq!(r.components.len(), 4);
    assert!(r.components.iter().all(|c| !c.closed));
    let Defect::SelfIntersections { pairs } = &r.defects[2] else { unreachable!() };
    assert_eq!(pairs.len(), 56);
    // Welding joins the patches but cannot close the holes or undo the intersections.
    let fixed = repair(&s, &RepairOptions::default()).unwrap();
    assert_eq!(fixed.surface.num_vertices(), 529);
    assert_eq!(kinds(&check(&fixed.surface)), vec!["open boundary", "self-intersections"]);
    let err = s.require_valid().unwrap_err();
    assert!(err.to_string().starts_with("unwelded vertices: 193 groups"), "{err}");
}

#[test]
fn the_layered_bunny_is_three_nested_shells_with_the_exact_region_volumes() {
    if skip_without_shared_data("the mesh fixture layered_bunny.obj") {
        return;
    }
    let s = read_obj("meshes/layered_bunny.obj");
    assert_eq!(s.region_names, vec!["layer0_bunny", "layer1_sphereA", "layer2_sphereB"]);
    let r = s.require_closed_manifold().expect("valid");
    assert_eq!(r.components.len(), 3);
    assert_eq!(r.num_shells, 6);
    let v: Vec<f64> = r.components.iter().map(|c| c.enclosed_volume_mm3.unwrap()).collect();
    // layered_bunny.json: region 1 = bunny - sphereA, 2 = sphereA - sphereB, 3 = sphereB.
    let exact = [158.62009327399934, 29.361096028883264, 6.307182509536498];
    assert!(rel_close(v[0] - v[1], exact[0], 1e-12), "{}", v[0] - v[1]);
    assert!(rel_close(v[1] - v[2], exact[1], 1e-12), "{}", v[1] - v[2]);
    assert!(rel_close(v[2], exact[2], 1e-12), "{}", v[2]);
    for (comp, region) in r.components.iter().zip([0, 1, 2]) {
        assert!(rel_close(s.signed_volume(Some(region)), comp.signed_volume_mm3, 1e-12));
    }
}

#[test]
fn two_boxes_sharing_a_face_are_a_valid_two_region_input_once_oriented() {
    if skip_without_shared_data("the mesh fixture layered_two_boxes.obj") {
        return;
    }
    let s = read_obj("meshes/layered_two_boxes.obj");
    let r = check(&s);
    // The four edges around the shared face carry three triangles each: junctions
    // between the two boxes and the outside, not defects.
    assert_eq!(r.junction_edges.len(), 4);
    assert!(r.junction_edges.iter().all(|e| e.triangles.len() == 3));
    assert_eq!(r.num_shells, 3, "outside, box 1, box 2");
    assert_eq!(r.components.len(), 1);
    assert!(rel_close(r.components[0].enclosed_volume_mm3.unwrap(), 2.0, 1e-15));
    // The file's x = 0 face (triangles 0 and 1) faces +x, into box 1: its four
    // edges are run the same way as by their neighbours.
    assert_eq!(kinds(&r), vec!["inconsistent orientation"]);
    let Defect::InconsistentOrientation { edges } = &r.defects[0] else { unreachable!() };
    assert_eq!(edges.len(), 4);
    assert!(edges.iter().all(|e| e.triangles.iter().any(|&t| t <= 1)));
    let fixed = repair(&s, &RepairOptions::default()).unwrap();
    assert_eq!(fixed.report.flipped, vec![0, 1]);
    let r = fixed.surface.require_valid().expect("valid two-region input");
    assert_eq!((r.junction_edges.len(), r.num_shells), (4, 3));
    // The strict single-region check refuses the junctions, naming one.
    let err = fixed.surface.require_closed_manifold().unwrap_err();
    assert!(
        matches!(&err, InvalidSurface::Defect { defect, .. } if matches!(**defect, Defect::NonManifoldEdges { .. }))
    );
    assert!(err.to_string().contains("shared by triangles"), "{err}");
}

#[test]
fn a_hole_is_an_open_boundary_with_its_border_edges() {
    if skip_without_shared_data("the mesh fixture bad_syn_hole.obj") {
        return;
    }
    let s = read_obj("meshes/bad_syn_hole.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["open boundary"]);
    let Defect::OpenBoundary { edges, num_loops } = &r.defects[0] else { unreachable!() };
    assert_eq!((edges.len(), *num_loops), (12, 1));
    // Each border edge is an edge of its triangle, in the triangle's direction.
    for e in edges {
        let t = s.triangles[e.triangle as usize];
        assert!((0..3).any(|i| [t[i], t[(i + 1) % 3]] == e.vertices));
    }
    let err = s.require_valid().unwrap_err();
    assert!(err.to_string().starts_with("open boundary: 12 border edges in 1 loops; the first from vertex"), "{err}");
    // Repair drops the 4 vertices only the missing triangles used, and leaves the hole.
    let fixed = repair(&s, &RepairOptions::default()).unwrap();
    assert_eq!(fixed.report.removed_vertices.len(), 4);
    assert_eq!(kinds(&check(&fixed.surface)), vec!["open boundary"]);
}

#[test]
fn ten_percent_flipped_is_inconsistent_and_repairs_to_the_bunny() {
    if skip_without_shared_data("the mesh fixture bad_syn_flipped10pct.obj") {
        return;
    }
    let bunny = bunny();
    let s = read_obj("meshes/bad_syn_flipped10pct.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["inconsistent orientation"]);
    assert_eq!(r.defects[0].count(), 987);
    let fixed = repair(&s, &RepairOptions::default()).unwrap();
    assert_eq!(fixed.report.flipped.len(), 367);
    assert!(fixed.surface.require_closed_manifold().is_ok());
    assert_eq!(oriented_set(&fixed.surface), oriented_set(&bunny));
}

#[test]
fn an_inverted_bunny_has_negative_volume_and_repairs_outward() {
    if skip_without_shared_data("the mesh fixture bad_syn_inverted.obj") {
        return;
    }
    let s = read_obj("meshes/bad_syn_inverted.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["inverted"]);
    let Defect::Inverted { num_triangles, signed_volume_mm3, .. } = r.defects[0] else { unreachable!() };
    assert_eq!(num_triangles, 3674);
    assert!(rel_close(signed_volume_mm3, -194.288, 1e-5));
    let fixed = repair(&s, &RepairOptions::default()).unwrap();
    assert_eq!(fixed.report.flipped.len(), 3674);
    assert!(rel_close(fixed.surface.signed_volume(None), 194.288, 1e-5));
    assert_eq!(oriented_set(&fixed.surface), oriented_set(&bunny()));
}

#[test]
fn overlapping_spheres_self_intersect() {
    if skip_without_shared_data("the mesh fixture bad_syn_overlapping_spheres.obj") {
        return;
    }
    let s = read_obj("meshes/bad_syn_overlapping_spheres.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["self-intersections"]);
    let Defect::SelfIntersections { pairs } = &r.defects[0] else { unreachable!() };
    assert_eq!(pairs.len(), 158);
    // Every pair joins the two spheres (each sphere alone is clean).
    assert_eq!(r.components.len(), 2);
    let split = r.components[1].first_triangle;
    assert!(pairs.iter().all(|&[a, b]| a < split && b >= split));
    let fixed = repair(&s, &RepairOptions::default()).unwrap();
    assert!(fixed.report.is_unchanged());
}

#[test]
fn a_jittered_soup_is_unwelded_and_welds_into_a_closed_surface() {
    if skip_without_shared_data("the mesh fixture bad_syn_soup_jitter.obj") {
        return;
    }
    let s = read_obj("meshes/bad_syn_soup_jitter.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["unwelded vertices", "open boundary", "self-intersections"]);
    assert_eq!(r.components.len(), 3674, "every triangle on its own");
    assert_eq!(r.find(|d| matches!(d, Defect::OpenBoundary { .. })).unwrap().count(), 11022);
    // The copies of a vertex lie up to 1.5e-7 mm (1e-8 of the diagonal) apart,
    // more than the default tolerance (1e-9 of the diagonal): by default only
    // some weld.
    let partial = repair(&s, &RepairOptions::default()).unwrap();
    assert!(!check(&partial.surface).is_valid());
    let opts = RepairOptions { weld_tolerance_rel: 1e-6, ..Default::default() };
    let fixed = repair(&s, &opts).unwrap();
    assert_eq!(fixed.surface.num_vertices(), 1839);
    assert_eq!(fixed.report.welded.len(), 1839);
    let r = fixed.surface.require_closed_manifold().expect("closed after welding");
    assert!(rel_close(r.components[0].signed_volume_mm3, 194.288, 1e-5));
}

#[test]
fn degenerate_and_duplicate_triangles_are_found_and_dropped() {
    if skip_without_shared_data("the mesh fixture bad_syn_degenerate_dup.obj") {
        return;
    }
    let s = read_obj("meshes/bad_syn_degenerate_dup.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["degenerate triangles", "duplicate triangles"]);
    // 20 needles on existing edges (apex at the edge's midpoint): 4 exactly
    // collinear, 16 off the line by rounding only (height ~1e-17 mm).
    let Defect::DegenerateTriangles { triangles } = &r.defects[0] else { unreachable!() };
    assert_eq!(triangles.len(), 20);
    assert_eq!(triangles.iter().filter(|d| d.kind == DegenerateKind::Collinear).count(), 4);
    assert_eq!(triangles.iter().filter(|d| d.kind == DegenerateKind::Thin).count(), 16);
    assert!(triangles.iter().all(|d| d.height_mm < 1e-15));
    assert_eq!(r.defects[1].count(), 20);
    let fixed = repair(&s, &RepairOptions::default()).unwrap();
    assert_eq!(fixed.report.dropped_degenerate.len(), 20);
    assert_eq!(fixed.report.dropped_duplicates.len(), 20);
    assert_eq!(fixed.report.removed_vertices.len(), 20, "the needles' apexes");
    assert!(fixed.surface.require_closed_manifold().is_ok());
    assert_eq!(oriented_set(&fixed.surface), oriented_set(&bunny()));
}

#[test]
fn cubes_touching_along_an_edge_are_non_manifold() {
    if skip_without_shared_data("the mesh fixture bad_syn_nonmanifold_edge.obj") {
        return;
    }
    let s = read_obj("meshes/bad_syn_nonmanifold_edge.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["non-manifold edges"]);
    let Defect::NonManifoldEdges { edges } = &r.defects[0] else { unreachable!() };
    assert_eq!(edges.len(), 1);
    assert_eq!(edges[0].vertices, [6, 7]);
    assert_eq!(edges[0].triangles.len(), 4);
    assert!(r.junction_edges.is_empty());
    let err = s.require_valid().unwrap_err();
    assert!(err.to_string().contains("vertex 6 (0.5, 0.5, -0.5) to vertex 7 (0.5, 0.5, 0.5)"), "{err}");
}

#[test]
fn the_thin_fin_pierces_the_cube() {
    if skip_without_shared_data("the mesh fixture bad_syn_thin_fin.obj") {
        return;
    }
    // A 0.8 x 0.8 x 1e-4 mm plate whose face lies 1e-6 mm inside the cube's
    // x = 0.5 face: two closed boxes that intersect, one thinner than 1e-4 of the
    // diagonal.
    let s = read_obj("meshes/bad_syn_thin_fin.obj");
    let r = check(&s);
    assert_eq!(kinds(&r), vec!["self-intersections"]);
    assert_eq!(r.defects[0].count(), 12);
    assert_eq!(r.components.len(), 2);
    assert!(rel_close(r.components[0].enclosed_volume_mm3.unwrap(), 1.0, 1e-12));
    assert!(rel_close(r.components[1].enclosed_volume_mm3.unwrap(), 0.8 * 0.8 * 1e-4, 1e-6));
}
