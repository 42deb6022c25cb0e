//! The conforming mesher: its Delaunay core on random and degenerate point sets,
//! and boundary recovery on a cube, the bunny (`tests/fixtures`) and, from the
//! shared data folder (`../shared/data/meshes`, read in place; a test that reads
//! it skips without it, see `tests/support/data.rs`), the layered bunny, two
//! boxes sharing a face and the defect corpus.

use fem_core::mesh::TetMesh;
use meshing::conforming::{conforming_mesh, insphere, ConformingError, ConformingOptions, Delaunay, FACE, GHOST};
use meshing::predicates::orient3d;
use meshing::quality::{report, QualityReport};
use meshing::repair::{repair, RepairOptions};
use meshing::Surface;

mod common;
use common::{bunny, read_obj, skip_without_shared_data};

type P = [f64; 3];

/// A SplitMix64 stream of uniform numbers in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn random_points(n: usize, seed: u64) -> Vec<P> {
    let mut r = Rng(seed);
    (0..n).map(|_| [r.next(), r.next(), r.next()]).collect()
}

fn grid(n: usize) -> Vec<P> {
    let mut v = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                v.push([i as f64, j as f64, k as f64]);
            }
        }
    }
    v
}

/// All integer points on the sphere x^2 + y^2 + z^2 = r2 (exactly cospherical).
fn sphere_points(r2: i64) -> Vec<P> {
    let r = (r2 as f64).sqrt() as i64 + 1;
    let mut v = Vec::new();
    for x in -r..=r {
        for y in -r..=r {
            for z in -r..=r {
                if x * x + y * y + z * z == r2 {
                    v.push([x as f64, y as f64, z as f64]);
                }
            }
        }
    }
    v
}

fn volume(q: [P; 4]) -> f64 {
    let d = |a: P, b: P| [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let (a, b, c) = (d(q[0], q[1]), d(q[0], q[2]), d(q[0], q[3]));
    (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0
}

/// Everything the Delaunay tetrahedralization of `pts` must satisfy, checked
/// exactly and independently of the structure's own bookkeeping:
/// - its own structural check (neighbours, orientation, local Delaunay);
/// - every distinct input point is a vertex;
/// - every finite tet is positive (exact orient3d) and its circumsphere has no
///   input point strictly inside (exact insphere, brute force over all points);
/// - the hull faces (the ghosts' finite faces) have every point on their inner
///   side or on them (so the union of tets is convex and contains the points:
///   the convex hull), and the tet volumes add up to the volume the hull faces
///   enclose.
///
/// Returns the sorted tets as coordinate quadruples (for comparisons).
fn check_delaunay(pts: &[P]) -> Vec<[[u64; 3]; 4]> {
    let d = Delaunay::new(pts).expect("tetrahedralization");
    d.check().unwrap();
    let mut distinct: Vec<P> = pts.to_vec();
    distinct.sort_by(|a, b| a.partial_cmp(b).unwrap());
    distinct.dedup();
    let used: std::collections::BTreeSet<u32> = d.finite_tets().flatten().collect();
    let used_points: std::collections::BTreeSet<[u64; 3]> =
        used.iter().map(|&v| pts[v as usize].map(f64::to_bits)).collect();
    assert_eq!(used_points.len(), distinct.len(), "every distinct point is a vertex");
    let mut tet_volume = 0.0;
    for t in d.finite_tets() {
        let q = t.map(|v| pts[v as usize]);
        assert_eq!(orient3d(q[0], q[1], q[2], q[3]), 1, "tet {t:?} is not positive");
        for (i, p) in pts.iter().enumerate() {
            assert!(insphere(q[0], q[1], q[2], q[3], *p) <= 0, "point {i} is strictly inside the sphere of {t:?}");
        }
        tet_volume += volume(q);
    }
    let mut hull_volume = 0.0;
    for (_, t) in d.live_tets() {
        let Some(g) = t.iter().position(|&v| v == GHOST) else { continue };
        let f = FACE[g].map(|k| pts[t[k] as usize]);
        for p in pts {
            // The outside is the infinite vertex's side: no point may be there.
            assert!(orient3d(f[0], f[1], f[2], *p) <= 0, "a point is outside hull face {t:?}");
        }
        // The face's normal points to the ghost's side: outward (divergence theorem).
        hull_volume += volume([[0.0; 3], f[0], f[1], f[2]]);
    }
    assert!((tet_volume - hull_volume).abs() <= 1e-12 * hull_volume.abs(), "{tet_volume} vs hull {hull_volume}");
    let mut out: Vec<[[u64; 3]; 4]> = d
        .finite_tets()
        .map(|t| {
            let mut c = t.map(|v| pts[v as usize].map(f64::to_bits));
            c.sort_unstable();
            c
        })
        .collect();
    out.sort_unstable();
    out
}

#[test]
fn random_points_give_a_delaunay_tetrahedralization_of_their_hull() {
    for (n, seed) in [(5, 1), (50, 2), (1500, 3)] {
        check_delaunay(&random_points(n, seed));
    }
}

#[test]
fn a_grid_is_fully_degenerate_and_still_exact() {
    // Every cube of the grid has eight cospherical corners and every hull face is
    // a plane of many points: only the perturbation decides.
    let pts = grid(7);
    let tets = check_delaunay(&pts);
    // Each unit cube is split into tets of volume adding to 1: 6^3 cubes.
    let total: f64 = tets.iter().map(|t| volume(t.map(|c| c.map(f64::from_bits))).abs()).sum();
    assert!((total - 216.0).abs() < 1e-12 * 216.0, "{total}");
}

#[test]
fn cospherical_points_and_duplicates() {
    let mut pts = sphere_points(194); // 240 integer points on one sphere
    assert_eq!(pts.len(), 240);
    let n = pts.len();
    pts.extend_from_within(0..10); // duplicates map to the first copies
    pts.push([0.0, 0.0, 0.0]); // the centre
    let tets = check_delaunay(&pts);
    assert!(!tets.is_empty());
    let _ = n;
}

#[test]
fn the_result_does_not_depend_on_the_input_order() {
    for pts in [random_points(800, 7), grid(5), sphere_points(101)] {
        eprintln!("{} points", pts.len());
        let a = check_delaunay(&pts);
        let mut shuffled = pts.clone();
        shuffled.reverse();
        let mut r = Rng(9);
        for i in (1..shuffled.len()).rev() {
            let j = (r.next() * (i + 1) as f64) as usize;
            shuffled.swap(i, j);
        }
        let b = check_delaunay(&shuffled);
        assert_eq!(a, b, "same point set, different tetrahedralization");
        // And running twice gives the same tets in the same slots.
        let d1 = Delaunay::new(&pts).unwrap();
        let d2 = Delaunay::new(&pts).unwrap();
        assert_eq!(d1.finite_tets().collect::<Vec<_>>(), d2.finite_tets().collect::<Vec<_>>());
    }
}

#[test]
fn flat_and_non_finite_input_is_refused() {
    let flat: Vec<P> = (0..20).map(|i| [i as f64, (i * i) as f64, 0.0]).collect();
    assert!(Delaunay::new(&flat).is_err());
    assert!(Delaunay::new(&[[0.0; 3]; 5]).is_err());
    let bad = vec![[0.0, 0.0, 0.0], [1.0, f64::NAN, 0.0]];
    assert!(Delaunay::new(&bad).unwrap_err().to_string().contains("point 1"));
}

#[test]
fn points_added_later_keep_it_delaunay() {
    let pts = random_points(200, 11);
    let mut d = Delaunay::new(&pts[..100]).unwrap();
    for p in &pts[100..] {
        d.insert(*p);
    }
    // Outside the hull, on a hull face's plane, and a duplicate.
    d.insert([2.0, 0.5, 0.5]);
    let dup = d.insert(pts[3]);
    assert_eq!(dup, 3);
    d.check().unwrap();
    let all = d.points().to_vec();
    for t in d.finite_tets() {
        let q = t.map(|v| all[v as usize]);
        for p in &all {
            assert!(insphere(q[0], q[1], q[2], q[3], *p) <= 0);
        }
    }
}

/// Cospherical points inserted one at a time (each outside the hull of the
/// previous ones, many on the planes of hull faces): the structure is checked
/// after every insertion.
#[test]
fn each_insertion_keeps_the_structure_valid() {
    let pts = sphere_points(101);
    let mut d = Delaunay::new(&pts[..6]).unwrap();
    d.check().unwrap();
    for (k, p) in pts[6..].iter().enumerate() {
        let v = d.insert(*p);
        if let Err(e) = d.check() {
            panic!("after inserting point {} ({v}) {:?}: {e}", k + 6, p);
        }
    }
}

// ---- stage 2: boundary recovery

/// Boundary recovery alone (stage 2), no quality refinement.
const RECOVERY_ONLY: ConformingOptions =
    ConformingOptions { size_mm: None, max_steiner_per_vertex: 50, radius_edge: f64::INFINITY, sliver_deg: 0.0 };

/// The gates every conforming mesh must pass, checked here independently of the
/// mesher: exact positive orientation of every tet, every face shared by at most
/// two tets, a closed boundary (every boundary edge on exactly two boundary
/// faces), and against the input (the quality report): volume error and
/// Hausdorff distance at most 1e-9 (relative), per-region volumes too.
fn check_conforming(mesh: &TetMesh, surface: &Surface) -> QualityReport {
    for (e, c) in mesh.cells.iter().enumerate() {
        let q = c.map(|v| mesh.nodes[v as usize]);
        assert_eq!(orient3d(q[0], q[1], q[2], q[3]), 1, "cell {e} is not positively oriented (exact)");
    }
    let mut faces: std::collections::HashMap<[u32; 3], usize> = std::collections::HashMap::new();
    for c in &mesh.cells {
        for i in 0..4 {
            let mut f: Vec<u32> = (0..4).filter(|&k| k != i).map(|k| c[k]).collect();
            f.sort_unstable();
            *faces.entry([f[0], f[1], f[2]]).or_default() += 1;
        }
    }
    assert!(faces.values().all(|&n| n <= 2), "a face is shared by more than two tets");
    let boundary = mesh.boundary_facets();
    let mut edges: std::collections::HashMap<(u32, u32), usize> = std::collections::HashMap::new();
    let mut directed = std::collections::HashSet::new();
    for f in &boundary {
        for i in 0..3 {
            let (a, b) = (f[i], f[(i + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            assert!(directed.insert((a, b)), "boundary faces are not consistently oriented");
        }
    }
    assert!(edges.values().all(|&n| n == 2), "the boundary is not closed");
    mesh.validate().unwrap();
    let r = report(mesh, surface, 0.0);
    assert_eq!(r.num_inverted, 0);
    assert!(r.volume_error.abs() <= 1e-9, "volume error {:e}", r.volume_error);
    assert!(r.hausdorff_relative <= 1e-9, "Hausdorff {:e} of the diagonal", r.hausdorff_relative);
    for reg in &r.regions {
        if let Some(e) = reg.volume_error {
            assert!(e.abs() <= 1e-9, "region {}: volume error {e:e}", reg.name);
        }
    }
    r
}

#[test]
fn a_cube_is_meshed_with_its_exact_boundary() {
    let s = Surface::cuboid([0.0, 0.0, 0.0], [10.0, 20.0, 5.0], "cube");
    let out = conforming_mesh(&s, &RECOVERY_ONLY).unwrap();
    let r = check_conforming(&out.mesh, &s);
    assert!((r.volume_mm3 - 1000.0).abs() < 1e-9);
    eprintln!("cube: {:?}", out.stats);
}

/// A 10 x 20 x 5 mm box whose faces are each cut into needle triangles: a fan
/// from one corner of each face to `n` points along each of its two far sides
/// (the three faces at one corner of the box fan from it, the other three from
/// the opposite corner, so every edge of the box is split alike on both its
/// faces; `n` a power of two keeps the points exact).
fn needle_box(n: usize) -> Surface {
    let mut s = Surface { region_names: vec!["box".into()], ..Surface::default() };
    let mut index = std::collections::HashMap::new();
    // Each face: fan corner and two edge vectors, u x v pointing outwards.
    let faces: [(P, P, P); 6] = [
        ([0.0, 0.0, 0.0], [0.0, 20.0, 0.0], [10.0, 0.0, 0.0]),
        ([0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 0.0, 5.0]),
        ([0.0, 0.0, 0.0], [0.0, 0.0, 5.0], [0.0, 20.0, 0.0]),
        ([10.0, 20.0, 5.0], [-10.0, 0.0, 0.0], [0.0, -20.0, 0.0]),
        ([10.0, 20.0, 5.0], [0.0, 0.0, -5.0], [-10.0, 0.0, 0.0]),
        ([10.0, 20.0, 5.0], [0.0, -20.0, 0.0], [0.0, 0.0, -5.0]),
    ];
    for (o, u, v) in faces {
        let at = |a: f64, b: f64| [0, 1, 2].map(|k| o[k] + a * u[k] + b * v[k]);
        // The far sides (a = 1, then b = 1) as one chain of 2n + 1 points.
        let chain: Vec<P> = (0..=n)
            .map(|i| at(1.0, i as f64 / n as f64))
            .chain((0..n).rev().map(|i| at(i as f64 / n as f64, 1.0)))
            .collect();
        let mut vertex = |p: P| -> u32 {
            *index.entry(p.map(f64::to_bits)).or_insert_with(|| {
                s.vertices.push(p);
                s.vertices.len() as u32 - 1
            })
        };
        let c0 = vertex(at(0.0, 0.0));
        let ids: Vec<u32> = chain.into_iter().map(&mut vertex).collect();
        for w in ids.windows(2) {
            s.triangles.push([c0, w[0], w[1]]);
            s.triangle_regions.push(0);
        }
    }
    s
}

#[test]
fn coplanar_needle_triangles_merge_into_one_facet_per_face() {
    // 32 points per side: fan triangles with angles down to about 1 deg.
    let s = needle_box(32);
    s.require_valid().unwrap();
    let out = conforming_mesh(&s, &ConformingOptions::new(2.0)).unwrap();
    assert_eq!(out.stats.input_triangles, 6 * 64);
    assert_eq!(out.stats.facets, 6, "one facet per face of the box");
    let r = check_conforming(&out.mesh, &s);
    assert!((r.volume_mm3 - 1000.0).abs() < 1e-9, "volume {}", r.volume_mm3);
    // The fans' edges inside the faces need not appear, so the mesh is not
    // tied to the needles: measured 5.67..166.37 deg (the box's edges keep
    // their 32 fixed input points each).
    assert!(r.min_dihedral_deg > 5.0, "dihedral {}..{}", r.min_dihedral_deg, r.max_dihedral_deg);
    eprintln!("needle box: {:?}, dihedral {:.2}..{:.2}", out.stats, r.min_dihedral_deg, r.max_dihedral_deg);
}

#[test]
fn nearly_coplanar_triangles_stay_apart() {
    // A box whose top is a tent over its centre raised by 1e-6 mm (4e-8 of the
    // diagonal: far above the 1e-12 merging tolerance, invisible): the four
    // tent triangles are not coplanar and stay four facets, and the boundary
    // follows the tent exactly (volume and Hausdorff within 1e-9).
    let c = |x: f64, y: f64, z: f64| [x, y, z];
    let mut s = Surface { region_names: vec!["box".into()], ..Surface::default() };
    let quads = [
        [c(0.0, 0.0, 0.0), c(0.0, 20.0, 0.0), c(10.0, 20.0, 0.0), c(10.0, 0.0, 0.0)],
        [c(0.0, 0.0, 0.0), c(10.0, 0.0, 0.0), c(10.0, 0.0, 5.0), c(0.0, 0.0, 5.0)],
        [c(0.0, 20.0, 0.0), c(0.0, 20.0, 5.0), c(10.0, 20.0, 5.0), c(10.0, 20.0, 0.0)],
        [c(0.0, 0.0, 0.0), c(0.0, 0.0, 5.0), c(0.0, 20.0, 5.0), c(0.0, 20.0, 0.0)],
        [c(10.0, 0.0, 0.0), c(10.0, 20.0, 0.0), c(10.0, 20.0, 5.0), c(10.0, 0.0, 5.0)],
    ];
    let mut index = std::collections::HashMap::new();
    let mut vertex = |s: &mut Surface, p: P| -> u32 {
        *index.entry(p.map(f64::to_bits)).or_insert_with(|| {
            s.vertices.push(p);
            s.vertices.len() as u32 - 1
        })
    };
    let mut tri = |s: &mut Surface, t: [P; 3]| {
        let t = t.map(|p| vertex(s, p));
        s.triangles.push(t);
        s.triangle_regions.push(0);
    };
    for q in quads {
        tri(&mut s, [q[0], q[1], q[2]]);
        tri(&mut s, [q[0], q[2], q[3]]);
    }
    let top = [c(0.0, 0.0, 5.0), c(10.0, 0.0, 5.0), c(10.0, 20.0, 5.0), c(0.0, 20.0, 5.0)];
    for i in 0..4 {
        tri(&mut s, [top[i], top[(i + 1) % 4], c(5.0, 10.0, 5.0 + 1e-6)]);
    }
    s.require_valid().unwrap();
    let out = conforming_mesh(&s, &ConformingOptions::new(2.0)).unwrap();
    assert_eq!(out.stats.input_triangles, 14);
    // Five flat faces of two triangles each merge; the four tent triangles do not.
    assert_eq!(out.stats.facets, 5 + 4);
    check_conforming(&out.mesh, &s);
}

#[test]
fn the_bunny_is_meshed_with_its_exact_boundary() {
    let s = bunny();
    let out = conforming_mesh(&s, &RECOVERY_ONLY).unwrap();
    let r = check_conforming(&out.mesh, &s);
    eprintln!(
        "bunny: {:?}\n{} tets, dihedral {:.2}..{:.2}, volume error {:e}, Hausdorff {:e}",
        out.stats, r.num_cells, r.min_dihedral_deg, r.max_dihedral_deg, r.volume_error, r.hausdorff_relative
    );
}

/// The same input gives bit-identical output with 1 and 2 threads: the bad
/// tets' candidates are probed in parallel and their verdicts read in
/// candidate order, and smoothing judges batches of vertices in parallel and
/// moves them in vertex order (the bunny at 0.5 mm: refinement, facet
/// refinement, edge removal and smoothing for the radius-edge ratio all run;
/// edge removal leaves sliver smoothing nothing to do there).
#[test]
fn conforming_output_does_not_depend_on_the_thread_count() {
    let s = bunny();
    let options = ConformingOptions { size_mm: Some(0.5), ..ConformingOptions::default() };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| conforming_mesh(&s, &options).unwrap())
    };
    let (a, b) = (run(1), run(2));
    let st = &a.stats;
    assert!(st.refinement.circumcentres > 0 && st.flips.flips > 0 && st.radius_edge_smoothing.moves > 0, "{st:?}");
    assert_eq!(a.mesh.cells, b.mesh.cells);
    assert_eq!(a.mesh.cell_regions, b.mesh.cell_regions);
    let bits = |m: &TetMesh| -> Vec<u64> { m.nodes.iter().flatten().map(|x| x.to_bits()).collect() };
    assert_eq!(bits(&a.mesh), bits(&b.mesh));
}

#[test]
fn two_boxes_sharing_a_face_become_two_regions() {
    if skip_without_shared_data("the mesh fixture layered_two_boxes.obj") {
        return;
    }
    let raw = read_obj("meshes/layered_two_boxes.obj");
    // The file's x = 0 face faces into box 1 (a fixture defect): strict mode
    // refuses it, naming the defect; once repaired it meshes.
    let err = conforming_mesh(&raw, &ConformingOptions::default()).unwrap_err();
    assert!(matches!(err, ConformingError::Invalid(_)), "{err}");
    let s = repair(&raw, &RepairOptions::default()).unwrap().surface;
    let out = conforming_mesh(&s, &RECOVERY_ONLY).unwrap();
    assert_eq!(out.mesh.region_names.len(), 2, "{:?}", out.mesh.region_names);
    let r = check_conforming(&out.mesh, &s);
    assert_eq!(r.regions.len(), 2);
    for reg in &r.regions {
        assert!(reg.num_cells > 0);
        assert!(reg.volume_error.is_some_and(|e| e.abs() <= 1e-9), "{reg:?}");
    }
}

/// Smoothing moves Steiner points on the boundary and the interface too, within
/// their face: at the quality size every boundary node of two boxes sharing a
/// face keeps a coordinate exactly on a face of its box (x in {0, 1, 2}, y or z
/// in {0, 1}), and every node of the interface (in both regions) keeps x = 1
/// exactly (the gates against TetGen are in `tests/tetgen_golden.rs`).
#[test]
fn smoothing_moves_boundary_points_within_their_faces_exactly() {
    if skip_without_shared_data("the mesh fixture layered_two_boxes.obj") {
        return;
    }
    let s = repair(&read_obj("meshes/layered_two_boxes.obj"), &RepairOptions::default()).unwrap().surface;
    let out = conforming_mesh(&s, &ConformingOptions::new(0.1)).unwrap();
    check_conforming(&out.mesh, &s);
    // Since edge removal, the sliver smoothing has nothing left to move
    // there; the smoothing for the radius-edge ratio moves boundary points
    // with the same freedoms.
    let moved = out.stats.smoothing.boundary_moves + out.stats.radius_edge_smoothing.boundary_moves;
    assert!(moved > 0, "{:?}", out.stats);
    let m = &out.mesh;
    for &v in &m.node_sets["boundary"] {
        let p = m.nodes[v as usize];
        let on = [0.0, 2.0].contains(&p[0]) || [0.0, 1.0].contains(&p[1]) || [0.0, 1.0].contains(&p[2]);
        assert!(on, "boundary node {v} at {p:?} is on no face of the boxes");
    }
    let mut regions = vec![0u8; m.nodes.len()];
    for (c, &reg) in m.cells.iter().zip(&m.cell_regions) {
        for &v in c {
            regions[v as usize] |= 1 << reg;
        }
    }
    let interface: Vec<usize> = (0..m.nodes.len()).filter(|&v| regions[v] == 3).collect();
    assert!(interface.len() > 100, "{} interface nodes", interface.len());
    for v in interface {
        assert_eq!(m.nodes[v][0], 1.0, "interface node {v} at {:?}", m.nodes[v]);
    }
}

#[test]
fn the_layered_bunny_keeps_its_three_nested_regions_exactly() {
    if skip_without_shared_data("the mesh fixture layered_bunny.obj") {
        return;
    }
    let s = read_obj("meshes/layered_bunny.obj");
    let out = conforming_mesh(&s, &RECOVERY_ONLY).unwrap();
    assert_eq!(out.mesh.region_names.len(), 3);
    let r = check_conforming(&out.mesh, &s);
    // Each region against its shell less the shells nested in it (1e-9, checked above).
    assert_eq!(r.regions.len(), 3);
    assert!(r.regions.iter().all(|g| g.num_cells > 0 && g.volume_error.is_some()), "{:?}", r.regions);
}

#[test]
fn defective_input_is_refused_with_the_defect_named() {
    let mut s = Surface::cuboid([0.0; 3], [1.0; 3], "cube");
    s.triangles.pop();
    s.triangle_regions.pop();
    let err = conforming_mesh(&s, &ConformingOptions::default()).unwrap_err();
    assert!(matches!(err, ConformingError::Invalid(_)));
    assert!(err.to_string().contains("border") || err.to_string().contains("open"), "{err}");
}

/// Strict mode on the defect corpus (`bad_syn_*.obj`): each file is
/// refused before any meshing with `ConformingError::Invalid`, whose defect is
/// the file's (the first `meshing::validate` finds, with its count as in
/// `tests/validate.rs`) and whose message names it and where it is (a vertex
/// with its coordinates, or a triangle's centroid). The teapot is another
/// test's (`tests/validate.rs`); the clean bunny and the layered files are
/// accepted (tests above).
#[test]
fn the_defect_corpus_is_refused_with_each_defect_named() {
    if skip_without_shared_data("the defect corpus bad_syn_*.obj") {
        return;
    }
    use meshing::{Defect, InvalidSurface};
    // (file, the defect's kind, its count, the number of kinds found, the message's start)
    let corpus: [(&str, &str, usize, usize, &str); 8] = [
        (
            "bad_syn_hole.obj",
            "open boundary",
            12,
            1,
            "open boundary: 12 border edges in 1 loops; the first from vertex",
        ),
        ("bad_syn_flipped10pct.obj", "inconsistent orientation", 987, 1, "inconsistent orientation: 987 edges"),
        ("bad_syn_inverted.obj", "inverted", 3674, 1, "inverted: component 0 (triangle 0 and 3673 more, first at ("),
        ("bad_syn_soup_jitter.obj", "unwelded vertices", 0, 3, "unwelded vertices: "),
        ("bad_syn_degenerate_dup.obj", "degenerate triangles", 20, 2, "degenerate triangles: 20 in all; the first"),
        (
            "bad_syn_nonmanifold_edge.obj",
            "non-manifold edges",
            1,
            1,
            "non-manifold edges: 1 in all; the first from vertex 6",
        ),
        (
            "bad_syn_overlapping_spheres.obj",
            "self-intersections",
            158,
            1,
            "self-intersections: 158 triangle pairs; the first",
        ),
        ("bad_syn_thin_fin.obj", "self-intersections", 12, 1, "self-intersections: 12 triangle pairs; the first"),
    ];
    for (name, kind, count, kinds, start) in corpus {
        let s = read_obj(&format!("meshes/{name}"));
        let err = conforming_mesh(&s, &ConformingOptions::default()).unwrap_err();
        let message = err.to_string();
        eprintln!("{name}: {message}");
        let ConformingError::Invalid(InvalidSurface::Defect { defect, description, num_defects }) = &err else {
            panic!("{name}: not a defect: {err:?}");
        };
        assert_eq!(defect.kind(), kind, "{name}");
        // The soup's count of unwelded groups depends on the weld tolerance: only its presence is asserted.
        assert!(if count > 0 { defect.count() == count } else { defect.count() > 0 }, "{name}: {}", defect.count());
        assert_eq!(*num_defects, kinds, "{name}");
        assert!(message.starts_with("conforming mode needs a clean, closed surface: "), "{name}: {message}");
        assert!(description.starts_with(start), "{name}: {description}");
        assert!(message.contains(description.as_str()), "{name}: {message}");
        // The place: a vertex with its coordinates, or a triangle with its centroid.
        let by_triangle = matches!(defect.as_ref(), Defect::SelfIntersections { .. } | Defect::Inverted { .. });
        let what = if by_triangle { "triangle" } else { "vertex" };
        assert!(description.contains(what) && description.contains('('), "{name}: {description}");
    }
}

// ---- stage 3: size

#[test]
fn size_refinement_bounds_every_tet_and_keeps_the_boundary() {
    for (name, s, h) in
        [("cube", Surface::cuboid([0.0, 0.0, 0.0], [10.0, 20.0, 5.0], "cube"), 2.0), ("bunny", bunny(), 0.5)]
    {
        let out = conforming_mesh(&s, &ConformingOptions::new(h)).unwrap();
        let r = check_conforming(&out.mesh, &s);
        let max_volume = h * h * h / (6.0 * 2f64.sqrt());
        for c in &out.mesh.cells {
            let q = c.map(|v| out.mesh.nodes[v as usize]);
            assert!(volume(q) <= max_volume, "{name}: a tet of volume {} > {max_volume}", volume(q));
        }
        assert_eq!(out.stats.refinement.bad_left, 0);
        eprintln!(
            "{name} h {h}: {} tets, {} nodes, dihedral {:.2}..{:.2}, <10deg {:.4}, radius-edge max {:.3} p99.9 {:.3}, \
             volume error {:.2e}, Hausdorff {:.2e}, {:.3} s\n  {:?}",
            r.num_cells,
            r.num_nodes,
            r.min_dihedral_deg,
            r.max_dihedral_deg,
            r.fraction_below_10_deg,
            r.max_radius_edge,
            r.p999_radius_edge,
            r.volume_error,
            r.hausdorff_relative,
            out.stats.time_s,
            out.stats
        );
    }
}
