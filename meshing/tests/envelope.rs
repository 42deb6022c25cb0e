//! Envelope mode (isosurface stuffing on the generalized winding number): analytic
//! shapes built here, the clean bunny (`tests/fixtures`) and the shared fixtures
//! in `<workspace>/../shared/data/meshes` (the defective corpus, the layered
//! bunny, the teapot; a test that reads them skips without them, see
//! `tests/support/data.rs`), read with `tobj` (in f32), the corpus tests' files
//! with `tests/common`'s reader (in f64).

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Instant;

use meshing::envelope::{envelope_mesh, EnvelopeError, EnvelopeMesh, EnvelopeOptions, EnvelopeWarning};
use meshing::quality::{cell_statistics, report, CellStatistics, QualityReport};
use meshing::{Surface, WindingNumber};

mod common;
use common::skip_without_shared_data;

// ---- shapes built here

/// An icosphere of radius `r` centred at `c`, `level` subdivisions, outward.
fn icosphere(r: f64, c: [f64; 3], level: usize) -> Surface {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut nf = Vec::new();
        for tri in &f {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    let (p, q) = (v[a as usize], v[b as usize]);
                    v.push([(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, (p[2] + q[2]) / 2.0]);
                    (v.len() - 1) as u32
                });
            }
            nf.push([tri[0], m[0], m[2]]);
            nf.push([tri[1], m[1], m[0]]);
            nf.push([tri[2], m[2], m[1]]);
            nf.push([m[0], m[1], m[2]]);
        }
        f = nf;
    }
    for p in &mut v {
        let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        *p = [c[0] + r * p[0] / n, c[1] + r * p[1] / n, c[2] + r * p[2] / n];
    }
    let n = f.len();
    Surface { vertices: v, triangles: f, triangle_regions: vec![0; n], region_names: vec!["sphere".into()] }
}

/// A part of the sphere of radius `r` about `(cx, 0, 0)`, triangulated on the
/// polar angles `thetas` from the +x axis (ascending, in [0, pi]) and `n_lon`
/// longitudes, outward; closed at a pole where `thetas` starts at 0 or ends at
/// pi, open (a circular border) elsewhere. Every vertex lies on the sphere.
fn sphere_zone(cx: f64, r: f64, thetas: &[f64], n_lon: usize) -> Surface {
    let mut s = Surface::default();
    let ring = |s: &mut Surface, theta: f64| -> Vec<u32> {
        if theta.sin().abs() < 1e-15 {
            s.vertices.push([cx + r * theta.cos(), 0.0, 0.0]);
            return vec![(s.vertices.len() - 1) as u32; n_lon];
        }
        (0..n_lon)
            .map(|k| {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / n_lon as f64;
                s.vertices.push([cx + r * theta.cos(), r * theta.sin() * phi.cos(), r * theta.sin() * phi.sin()]);
                (s.vertices.len() - 1) as u32
            })
            .collect()
    };
    let rings: Vec<Vec<u32>> = thetas.iter().map(|&t| ring(&mut s, t)).collect();
    for w in rings.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        for k in 0..n_lon {
            let k1 = (k + 1) % n_lon;
            // Outward: (d/dtheta) x (d/dphi) points away from the centre.
            for t in [[a[k], b[k1], a[k1]], [a[k], b[k], b[k1]]] {
                if t[0] != t[1] && t[1] != t[2] && t[2] != t[0] {
                    s.triangles.push(t);
                }
            }
        }
    }
    s.triangle_regions = vec![0; s.triangles.len()];
    s.region_names = vec!["sphere".into()];
    s
}

/// `n` polar angles from `from` to `to`, both included.
fn angles(from: f64, to: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|i| from + (to - from) * i as f64 / n as f64).collect()
}

/// The surfaces' triangles as one soup, one region.
fn soup(parts: &[&Surface]) -> Surface {
    let mut s = Surface::default();
    for p in parts {
        let base = s.vertices.len() as u32;
        s.vertices.extend(&p.vertices);
        s.triangles.extend(p.triangles.iter().map(|t| t.map(|v| v + base)));
    }
    s.triangle_regions = vec![0; s.triangles.len()];
    s.region_names = vec!["soup".into()];
    s
}

/// A prism along y whose +x side is a roof: two faces meeting at a ridge (at
/// `z = 0`, `x = ridge_x + tilt y`) at the interior angle `180 - 2 half_deg`
/// deg; the cross-section is the pentagon (-1, -w), (r - w tan, -w), (r, 0),
/// (r - w tan, w), (-1, w) with `w = 1.1`, for `y` in [-1.1, 1.1] mm; outward.
/// Its volume is `2.2 (2.2 (ridge_x - 1.1 tan + 1) + 1.21 tan)` mm^3 (the
/// section's area is linear in `y`, odd about its value at `y = 0`).
fn roof(ridge_x: f64, half_deg: f64, tilt: f64) -> Surface {
    let (w, t) = (1.1, half_deg.to_radians().tan());
    let mut vertices = Vec::new();
    for y in [-1.1, 1.1] {
        let r = ridge_x + tilt * y;
        for (x, z) in [(-1.0, -w), (r - w * t, -w), (r, 0.0), (r - w * t, w), (-1.0, w)] {
            vertices.push([x, y, z]);
        }
    }
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for i in 1..4 {
        triangles.push([0, i, i + 1]);
        triangles.push([5, 6 + i, 5 + i]);
    }
    for i in 0..5 {
        let j = (i + 1) % 5;
        triangles.push([i, 5 + j, j]);
        triangles.push([i, 5 + i, 5 + j]);
    }
    let s = Surface { vertices, triangles, triangle_regions: vec![0; 16], region_names: vec!["roof".into()] };
    assert!(s.signed_volume(None) > 0.0);
    s
}

fn corners(s: &Surface) -> Vec<[[f64; 3]; 3]> {
    s.triangles.iter().map(|t| t.map(|v| s.vertices[v as usize])).collect()
}

/// Regression, the teapot at 0.25 mm: a lattice tet whose four
/// vertices are all warped onto the input, its long black edge onto a crease
/// and its red edge's ends onto the two faces beside it, inherits the
/// crease's interior angle (158 deg for a 22 deg crease: inside the stuffing's
/// proven [10.7, 164.8], outside the issue's [12, 155]). Smoothing cannot
/// change it (all four nodes slide on the input); the guard splits the
/// tet's interior edge at a point moved off the edge into its ring, so two
/// tets share the crease edge. Without that split the guard refuses the mesh,
/// 1 tet at 15.23..158.18 deg. Measured (fitting on, the default): dihedral [13.83, 150.91] deg,
/// 1 bad tet before the guard, 1 split; volume error -1.76e-3 against the
/// closed form (asserted under 5e-3: the box's edges are rounded to the
/// lattice); 0.2 s.
#[test]
fn a_tet_spanning_a_crease_is_split_not_refused() {
    let (ridge_x, half_deg, tilt) = (0.52, 11.0, -0.13);
    let s = roof(ridge_x, half_deg, tilt);
    let t = half_deg.to_radians().tan();
    let exact = 2.2 * (2.2 * (ridge_x - 1.1 * t + 1.0) + 1.21 * t);
    assert!((s.signed_volume(None) - exact).abs() < 1e-12 * exact, "{} vs {exact}", s.signed_volume(None));
    let (out, q) = mesh_and_report(&s, 0.25);
    eprintln!("{:?}", out.stats);
    assert!(out.stats.guard_bad >= 1 && out.stats.guard_splits >= 1, "{:?}", out.stats);
    assert_issue_angles(&q);
    assert_conforming(&out.mesh);
    let error = out.mesh.measure() / exact - 1.0;
    eprintln!("volume error against the closed form {error:.3e}");
    assert!(error.abs() <= 2e-3, "{error}");
}

/// A blade: the roof's two faces meet at 49.4 deg (normals 130.6 deg apart,
/// the teapot spout lip's sharpest edge), the ridge tilted off the lattice.
/// The stuffing rounds a blade off at a fraction of its cells' size, and the
/// graded sizing's thin test is blind there (the input point nearest to a
/// cell is the ridge itself, both sides of it outside), so without a cut of
/// their own the cells along it stay at the smallest size; they are cut below it as at a rim (the
/// blade's edge among the sizing's rims) while `GAP_DEPTH` (2.5) times their
/// longest edge exceeds the grading tolerance. h = 0.25 mm, 2 levels, grading
/// tolerance 5e-3 and fitting 1e-2 of the diagonal (4.168 mm; tolerance
/// 0.0208 mm): the ridge's farthest point (of 201) from the mesh boundary,
/// measured 0.0026 mm (before the change 0.0205 mm), asserted under the deep
/// cut's cell size, tolerance / 2.5 = 0.0083 mm. 62k tets (before 28k), 3 s.
/// The whole input -> mesh figure is set by the 90 deg edges between the
/// roof's faces and its end caps (8.6e-3 of the diagonal), not asserted here.
#[test]
fn a_blades_ridge_is_resolved_below_the_smallest_cells() {
    let (ridge_x, half_deg, tilt) = (1.63, 65.3, -0.13);
    let s = roof(ridge_x, half_deg, tilt);
    let options =
        EnvelopeOptions { grade_levels: 2, grade_tolerance: 5e-3, fit_tolerance: 1e-2, ..EnvelopeOptions::new(0.25) };
    let (out, q) = mesh_and_report_with(&s, &options);
    assert_issue_angles(&q);
    assert_conforming(&out.mesh);
    let faces = out.mesh.boundary_facets();
    let boundary =
        meshing::envelope::TriangleTree::new(faces.iter().map(|f| f.map(|v| out.mesh.nodes[v as usize])).collect());
    let ridge = (0..=200)
        .map(|k| {
            let y = -1.0 + 2.0 * k as f64 / 200.0;
            boundary.closest_point([ridge_x + tilt * y, y, 0.0]).map_or(f64::INFINITY, |c| c.1)
        })
        .fold(0.0, f64::max);
    let tol = options.grade_tolerance * s.diagonal();
    eprintln!("ridge: farthest {ridge:.4} mm from the mesh, grading tolerance {tol:.4} mm");
    assert!(ridge < tol / 2.5, "{ridge} vs {tol}");
}

// ---- the fixtures

/// The fixture `name`: the repository's (`tests/fixtures`) when it has it, else
/// the shared data folder's (`../shared/data/meshes`; the test has checked that
/// the folder is there).
fn data(name: &str) -> PathBuf {
    let fixture = common::fixture(name);
    if fixture.is_file() {
        return fixture;
    }
    common::data(&format!("meshes/{name}"))
}

/// An OBJ as a surface, one region per object or group (a minimal reader for tests).
fn obj(name: &str) -> Surface {
    let path = data(name);
    let (models, _) =
        tobj::load_obj(&path, &tobj::LoadOptions { triangulate: true, single_index: false, ..Default::default() })
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut s = Surface::default();
    for (r, m) in models.iter().enumerate() {
        let base = s.vertices.len() as u32;
        let p = &m.mesh.positions;
        for k in 0..p.len() / 3 {
            s.vertices.push([p[3 * k] as f64, p[3 * k + 1] as f64, p[3 * k + 2] as f64]);
        }
        for t in m.mesh.indices.chunks(3) {
            s.triangles.push([base + t[0], base + t[1], base + t[2]]);
            s.triangle_regions.push(r as u32);
        }
        s.region_names.push(if m.name.is_empty() { format!("region{r}") } else { m.name.clone() });
    }
    s
}

/// layered_bunny.json, and its regions' exact volumes [mm^3] in region order.
fn layered_bunny_exact_volumes() -> (serde_json::Value, Vec<f64>) {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(data("layered_bunny.json")).unwrap()).unwrap();
    let exact = json["regions"].as_array().unwrap().iter().map(|r| r["exact_volume"].as_f64().unwrap()).collect();
    (json, exact)
}

fn mesh_and_report(s: &Surface, h: f64) -> (meshing::envelope::EnvelopeMesh, QualityReport) {
    mesh_and_report_with(s, &EnvelopeOptions::new(h))
}

fn mesh_and_report_with(s: &Surface, options: &EnvelopeOptions) -> (meshing::envelope::EnvelopeMesh, QualityReport) {
    let h = options.size_mm;
    let t0 = Instant::now();
    let out = envelope_mesh(s, options).unwrap_or_else(|e| panic!("h = {h}: {e}"));
    let dt = t0.elapsed().as_secs_f64();
    let q = report(&out.mesh, s, dt);
    eprintln!(
        "h {h}: {} cells, dihedral [{:.2}, {:.2}] deg, <10deg {:.2e}, radius-edge max {:.2} p99.9 {:.2}, \
         radius ratio mean {:.3}, volume error {:.2e}, Hausdorff {:.2e} of diag ({:.2e} / {:.2e} mm), \
         mesh {:.2} s, report {:.2} s, {} warnings, fit {} splits {} snaps",
        q.num_cells,
        q.min_dihedral_deg,
        q.max_dihedral_deg,
        q.fraction_below_10_deg,
        q.max_radius_edge,
        q.p999_radius_edge,
        q.mean_radius_ratio,
        q.volume_error,
        q.hausdorff_relative,
        q.mesh_to_surface_mm,
        q.surface_to_mesh_mm,
        q.mesh_time_s,
        q.report_time_s,
        out.warnings.len(),
        out.stats.fit_splits,
        out.stats.fit_snaps
    );
    for w in &out.warnings {
        eprintln!("  warning: {w}");
    }
    (out, q)
}

/// The proven bounds of the stuffing's outer stencils (Labelle and Shewchuk 2007,
/// alpha_long = 0.24999, alpha_short = 0.41189): [10.7, 164.8] deg.
///
/// Checked on the mesh handed to the final guard (`dihedral_before_guard_deg`),
/// not on the returned one: the guard refuses any tet outside [12°, 155°], so
/// the returned mesh could not fail this.
fn assert_proven_bounds(out: &meshing::envelope::EnvelopeMesh, q: &impl CellFigures) {
    assert_eq!(q.figures().num_inverted, 0);
    let [lo, hi] = out.stats.dihedral_before_guard_deg;
    assert!(lo >= 10.7 && hi <= 164.8, "dihedral before the guard [{lo}, {hi}] deg");
}

/// The cell figures the angle gates read, from the full report or from the cell
/// statistics alone (`cell_statistics`: no surface distance, for tests that do
/// not assert one).
trait CellFigures {
    fn figures(&self) -> CellStatistics;
}

impl CellFigures for CellStatistics {
    fn figures(&self) -> CellStatistics {
        *self
    }
}

impl CellFigures for QualityReport {
    fn figures(&self) -> CellStatistics {
        CellStatistics {
            min_dihedral_deg: self.min_dihedral_deg,
            max_dihedral_deg: self.max_dihedral_deg,
            fraction_below_10_deg: self.fraction_below_10_deg,
            max_radius_edge: self.max_radius_edge,
            p999_radius_edge: self.p999_radius_edge,
            mean_radius_ratio: self.mean_radius_ratio,
            min_radius_ratio: self.min_radius_ratio,
            num_inverted: self.num_inverted,
        }
    }
}

/// The issue's envelope targets for the angles: [12, 155] deg.
fn assert_issue_angles(q: &impl CellFigures) {
    let q = q.figures();
    assert!(q.min_dihedral_deg >= 12.0, "min dihedral {}", q.min_dihedral_deg);
    assert!(q.max_dihedral_deg <= 155.0, "max dihedral {}", q.max_dihedral_deg);
    assert_eq!(q.fraction_below_10_deg, 0.0);
}

/// A valid, conforming mesh: positive cells, every face in at most two cells, and
/// a closed boundary (every boundary edge in exactly two boundary faces).
fn assert_conforming(mesh: &fem_core::mesh::TetMesh) {
    mesh.validate().unwrap();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    for c in &mesh.cells {
        for i in 0..4 {
            let mut f = [c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]];
            f.sort_unstable();
            faces.push(f);
        }
    }
    faces.sort_unstable();
    let mut boundary_edges: std::collections::BTreeMap<(u32, u32), usize> = Default::default();
    let mut i = 0;
    while i < faces.len() {
        let mut j = i + 1;
        while j < faces.len() && faces[j] == faces[i] {
            j += 1;
        }
        assert!(j - i <= 2, "face {:?} in {} cells", faces[i], j - i);
        if j - i == 1 {
            let f = faces[i];
            for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[0], f[2])] {
                *boundary_edges.entry((a, b)).or_default() += 1;
            }
        }
        i = j;
    }
    let open = boundary_edges.values().filter(|&&n| n % 2 == 1).count();
    assert_eq!(open, 0, "{open} boundary edges in an odd number of boundary faces");
}

/// Least-squares slope of log(error) against log(h).
fn order(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (sx, sy) = points.iter().fold((0.0, 0.0), |a, &(h, e)| (a.0 + h.ln(), a.1 + e.ln()));
    let (mx, my) = (sx / n, sy / n);
    let num: f64 = points.iter().map(|&(h, e)| (h.ln() - mx) * (e.ln() - my)).sum();
    let den: f64 = points.iter().map(|&(h, _)| (h.ln() - mx).powi(2)).sum();
    num / den
}

// ---- shapes with known volume

/// The sphere of the sphere tests: an icosphere of 20480 triangles, radius 1
/// about this centre [mm].
const SPHERE_CENTRE: [f64; 3] = [0.1, -0.2, 0.05];

/// The sphere's stuffing alone (no boundary fitting) at size `h` [mm].
fn unfitted(h: f64) -> EnvelopeOptions {
    EnvelopeOptions { fit_tolerance: 0.0, ..EnvelopeOptions::new(h) }
}

/// The sphere, and its unfitted mesh at 0.2 mm with its report, built once for
/// the two tests that use them: the coarsest size of
/// `sphere_quality_and_volume_convergence` and the unfitted reference of
/// `sphere_boundary_is_fitted_to_one_thousandth_of_the_diagonal`.
fn sphere_unfitted_at_0_2() -> &'static (Surface, EnvelopeMesh, QualityReport) {
    static SHARED: OnceLock<(Surface, EnvelopeMesh, QualityReport)> = OnceLock::new();
    SHARED.get_or_init(|| {
        let s = icosphere(1.0, SPHERE_CENTRE, 5);
        let (out, q) = mesh_and_report_with(&s, &unfitted(0.2));
        (s, out, q)
    })
}

/// The sphere (an icosphere of 20480 triangles, volume by the divergence theorem),
/// stuffing without boundary fitting: proven angle bounds at every size, the volume error converges at second order.
#[test]
fn sphere_quality_and_volume_convergence() {
    // The stuffing alone (the fitting's error follows its tolerance, not h).
    let check = |h: f64, out: &EnvelopeMesh, q: &QualityReport| {
        assert_proven_bounds(out, q);
        assert_issue_angles(q);
        assert_conforming(&out.mesh);
        assert!(out.warnings.is_empty(), "{:?}", out.warnings);
        // Every boundary node lies on the input: the distance is the chord error
        // of boundary triangles (edges up to about 1.2 h on a unit sphere: 0.18 h^2)
        // plus the icosphere's own facets.
        assert!(q.mesh_to_surface_mm < 0.5 * h * h, "chord error {} at h = {h}", q.mesh_to_surface_mm);
        (h, q.volume_error.abs())
    };
    let (s, out, q) = sphere_unfitted_at_0_2();
    let mut errors = vec![check(0.2, out, q)];
    for h in [0.1, 0.05] {
        let (out, q) = mesh_and_report_with(s, &unfitted(h));
        errors.push(check(h, &out, &q));
    }
    let p = order(&errors);
    eprintln!("sphere volume errors {errors:?}: order {p:.2}");
    assert!(errors[2].1 < 1e-3, "{errors:?}");
    assert!(p > 1.8, "order {p}: {errors:?}");
}

/// A cube turned against the lattice (side 0.93, rotated 20 deg about (1, 2, 3)):
/// its edges and corners are rounded by the lattice, an error that converges too.
/// Nothing here reads a surface distance: the cells' statistics alone
/// (`cell_statistics`) and the volume against the closed form (the report's
/// distance was 30 % of the test's time). Measured: volume errors
/// -3.47e-3, -9.19e-4, -3.15e-4 at 0.1, 0.05, 0.025 mm (order 1.73; asserted
/// the finest under 5e-3, order above 1).
#[test]
fn cube_quality_and_volume_convergence() {
    let mut s = Surface::cuboid([-0.465; 3], [0.465; 3], "box");
    let (axis, angle) = ([1.0, 2.0, 3.0].map(|x: f64| x / 14f64.sqrt()), 20f64.to_radians());
    for p in &mut s.vertices {
        // Rodrigues' rotation.
        let (c, sn) = (angle.cos(), angle.sin());
        let k = axis;
        let kxp = [k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0]];
        let kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
        *p = [0, 1, 2].map(|i| p[i] * c + kxp[i] * sn + k[i] * kp * (1.0 - c) + 0.1);
    }
    let exact = 0.93f64.powi(3);
    assert!((s.signed_volume(None) - exact).abs() < 1e-12);
    let mut errors = Vec::new();
    for h in [0.1, 0.05, 0.025] {
        let out = envelope_mesh(&s, &EnvelopeOptions::new(h)).unwrap_or_else(|e| panic!("h = {h}: {e}"));
        let cells = cell_statistics(&out.mesh);
        assert_proven_bounds(&out, &cells);
        assert_issue_angles(&cells);
        assert_conforming(&out.mesh);
        let error = out.mesh.measure() / exact - 1.0;
        eprintln!(
            "h {h}: {} cells, dihedral [{:.2}, {:.2}] deg, volume error {error:.2e}",
            out.mesh.cells.len(),
            cells.min_dihedral_deg,
            cells.max_dihedral_deg
        );
        errors.push((h, error.abs()));
    }
    let p = order(&errors);
    eprintln!("cube volume errors {errors:?}: order {p:.2}");
    assert!(errors[2].1 < 5e-3, "{errors:?}");
    assert!(p > 1.0, "order {p}: {errors:?}");
}

/// Boundary fitting on the sphere (closed form): at h = 0.2 the stuffing's chords
/// alone stray by about 0.18 h^2 = 7e-3 mm, 2e-3 of the diagonal; the fitted
/// boundary is within the issue's 1e-3 of the diagonal of the input both ways,
/// and of the exact sphere (radius 1) within that plus the icosphere's own
/// facets (sagitta 3.8e-4 mm), the angles within [12, 155] deg (volume error
/// -3e-3). Fitted to 2.5e-4, the volume is within 2e-3 of the exact ball's, but
/// the Hausdorff distance is only no worse than unfitted. Without fitting the
/// same size misses the Hausdorff target.
#[test]
fn sphere_boundary_is_fitted_to_one_thousandth_of_the_diagonal() {
    let c = SPHERE_CENTRE;
    let h = 0.2;
    let (s, _, q0) = sphere_unfitted_at_0_2();
    eprintln!("unfitted: Hausdorff {:.2e} of diag, volume error {:.2e}", q0.hausdorff_relative, q0.volume_error);
    assert!(q0.hausdorff_relative > 1e-3, "{}", q0.hausdorff_relative);
    let (out, q) = mesh_and_report(s, h);
    assert!(out.stats.fit_splits > 0);
    assert_eq!(q.num_inverted, 0);
    assert_issue_angles(&q);
    assert_conforming(&out.mesh);
    assert!(q.hausdorff_relative <= 1e-3, "Hausdorff {} of the diagonal", q.hausdorff_relative);
    // Against the exact sphere: boundary nodes and face centroids.
    let diag = s.diagonal();
    let radial =
        |p: [f64; 3]| (((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt() - 1.0).abs();
    let mut worst: f64 = 0.0;
    for f in out.mesh.boundary_facets() {
        let p = f.map(|v| out.mesh.nodes[v as usize]);
        worst = worst.max(radial(p[0]));
        worst = worst.max(radial([0, 1, 2].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0)));
    }
    let sagitta = 3.8e-4;
    assert!(worst <= 1e-3 * diag + sagitta, "{worst} mm from the exact sphere");
    eprintln!("fitted: {worst:.2e} mm from the exact sphere");
    // The volume: chords on a convex part all err inward, so the issue's volume
    // gate (2e-3) needs a tighter fit than its Hausdorff gate here: 2.5e-4.
    let exact = 4.0 / 3.0 * std::f64::consts::PI;
    let tight = EnvelopeOptions { fit_tolerance: 2.5e-4, ..EnvelopeOptions::new(h) };
    let (out, q) = mesh_and_report_with(s, &tight);
    assert_eq!(q.num_inverted, 0);
    assert_issue_angles(&q);
    assert_conforming(&out.mesh);
    // Its Hausdorff distance is measured, not promised: a spot where the guard
    // refused every split keeps the unfitted distance (measured 1.75e-3).
    assert!(q.hausdorff_relative <= q0.hausdorff_relative, "{} > {}", q.hausdorff_relative, q0.hausdorff_relative);
    let err = (q.volume_mm3 - exact) / exact;
    eprintln!(
        "fitted to 2.5e-4: volume error {err:.2e} against the exact ball, {:.2e} against the input",
        q.volume_error
    );
    assert!(err.abs() <= 2e-3, "{err}");
    assert!(q.volume_error.abs() <= 2e-3, "{}", q.volume_error);
}

/// Faces on lattice planes: lattice vertices exactly on the surface count as on it.
#[test]
fn a_cube_on_the_lattice_planes_is_meshed_exactly() {
    let s = Surface::cuboid([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], "box");
    let out = envelope_mesh(&s, &EnvelopeOptions::new(0.25)).unwrap();
    assert_conforming(&out.mesh);
    assert!((out.mesh.measure() - 1.0).abs() < 1e-12, "{}", out.mesh.measure());
}

// ---- the shared fixtures

/// The Stanford bunny (clean, closed): the issue's angle and volume targets at
/// h = 0.2 mm (1/50 of its size). Its Hausdorff target (1e-3 of the diagonal) is
/// not reached by a uniform lattice at this size, nor after the boundary fitting
/// (the ear tips, where the angle guard refuses the splits): measured 9.4e-3,
/// asserted < 1.2e-2.
#[test]
fn bunny_meets_the_angle_and_volume_targets() {
    let s = obj("npm_bunny.obj");
    let (out, q) = mesh_and_report(&s, 0.2);
    assert_proven_bounds(&out, &q);
    assert_issue_angles(&q);
    assert_conforming(&out.mesh);
    assert!(q.volume_error.abs() <= 2e-3, "{}", q.volume_error);
    assert!(q.hausdorff_relative < 1.2e-2, "{}", q.hausdorff_relative);
    // The report carries the time (measured in benches, not asserted here).
    assert!(q.mesh_time_s > 0.0 && q.mesh_time_s.is_finite());
    assert_eq!(out.mesh.region_names, vec!["unnamed_object"]);
    assert_eq!(out.mesh.node_sets["boundary"].len(), {
        let mut v: Vec<u32> = out.mesh.boundary_facets().iter().flatten().copied().collect();
        v.sort_unstable();
        v.dedup();
        v.len()
    });
}

/// The layered bunny on the graded lattice (base 0.2 mm, 3 levels, as the
/// bunny family): three regions, and the envelope gates on clean input:
/// every tet within [12°, 155°] (a tet of 10.06° at a region interface at
/// these options is smoothed by the final guard, whose smoothing lets the
/// region shells' nodes slide along them), the boundary
/// figure within 1e-3 of the diagonal (the inner shells bound no solid: left
/// out), the whole volume within 2e-3 of the exact one (the json's three
/// regions). Measured: 740k tets, dihedral [13.80, 151.24] deg,
/// boundary figure 9.98e-4, volume error -4.4e-4; region volume errors
/// -2.5e-5 (bunny), -1.80e-3 (sphere A), -4.50e-3 (sphere B: a **miss** of
/// 2e-3 per region). Asserted per region: the bunny 2e-3, the spheres 1e-2
/// (the bound of the uniform lattice at 0.15 mm, 750k tets), and no cell
/// across sphere A (conforming interfaces).
#[test]
fn the_graded_layered_bunny_meets_every_envelope_gate() {
    if skip_without_shared_data("the mesh fixture layered_bunny.obj") {
        return;
    }
    let s = obj("layered_bunny.obj");
    let (json, exact) = layered_bunny_exact_volumes();
    assert_eq!(exact.len(), 3);
    let (out, q) = mesh_and_report_with(&s, &bunny_graded());
    assert_envelope_gates("layered_bunny.obj", &out, &q, exact.iter().sum(), 2e-3);
    assert_eq!(out.mesh.region_names, vec!["layer0_bunny", "layer1_sphereA", "layer2_sphereB"]);
    for (r, e) in q.regions.iter().zip(&exact) {
        let err = (r.volume_mm3 - e) / e;
        eprintln!("graded region {}: {} cells, error {err:.2e}", r.name, r.num_cells);
        let bound = if r.name == "layer0_bunny" { 2e-3 } else { 1e-2 };
        assert!(err.abs() <= bound, "{}: {err}", r.name);
        // The report's reference: each shell less the shells nested in it.
        assert!((r.reference_volume_mm3.unwrap() - e).abs() < 1e-4 * e);
    }
    // The sphere interfaces are conforming: no cell has nodes strictly on both sides.
    let centre = [0.8843064102564098, 2.968511615384615, 0.7171120256410255];
    let r_a = json["rA"].as_f64().unwrap();
    for (c, &reg) in out.mesh.cells.iter().zip(&out.mesh.cell_regions) {
        let d: Vec<f64> = c
            .iter()
            .map(|&v| {
                let p = out.mesh.nodes[v as usize];
                ((p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2) + (p[2] - centre[2]).powi(2)).sqrt() - r_a
            })
            .collect();
        let straddles = d.iter().any(|&x| x < -0.02) && d.iter().any(|&x| x > 0.02);
        assert!(!straddles, "a cell of region {reg} crosses sphere A: {d:?}");
    }
}

/// The distance the envelope is judged by (`meshing::distance`), against closed
/// forms, on two unit spheres about x = 0 and x = d = 1 given whole as one soup
/// (each with a latitude ring on their intersection circle, x = d/2, radius
/// rho = sqrt(1 - d^2/4)), 64 longitudes and polar steps of at most pi/32:
///
/// - "mesh" = the exact union's boundary (each sphere's outer zone): the
///   boundary Hausdorff distance is 0 (measured 1.6e-16, asserted < 1e-12 mm),
///   while the raw one counts the inner caps: the pole (1, 0, 0) of the first
///   sphere is the second's centre, d = 1 from its surface (measured 0.99766,
///   asserted within the facets' sagitta 1 - cos(sqrt(2) pi / 64) = 2.4e-3 of
///   it: the facets are chords);
/// - "mesh" = the boundary of the union of the spheres grown to 1 + eps, eps =
///   0.05: the grown union is the union's offset, so every "mesh" point is eps
///   from it (measured 0.05092, asserted within the sagitta), but the union's
///   concave crease circle is farther, sqrt((1 + eps)^2 - d^2/4) - rho = 0.05729
///   from the grown crease: the Hausdorff distance (measured 0.05721, asserted
///   within the sagitta of it, and above eps + 4e-3).
///
/// No input border: no hole caps.
#[test]
fn the_boundary_distance_of_overlapping_spheres_has_its_closed_form() {
    use meshing::distance::boundary_distance;
    let d = 1.0f64;
    let n_lon = 64;
    // Polar steps of at most pi / 32, with a ring at x = d / 2.
    let zones = |r: f64| {
        let ta = (d / (2.0 * r)).acos(); // first sphere: x = r cos(theta) = d / 2
        let tb = (-d / (2.0 * r)).acos(); // second sphere: x = d + r cos(theta) = d / 2
        let steps = |a: f64, b: f64| ((b - a) / (std::f64::consts::PI / 32.0)).ceil().max(1.0) as usize;
        let pi = std::f64::consts::PI;
        let a_inner = sphere_zone(0.0, r, &angles(0.0, ta, steps(0.0, ta)), n_lon);
        let a_outer = sphere_zone(0.0, r, &angles(ta, pi, steps(ta, pi)), n_lon);
        let b_outer = sphere_zone(d, r, &angles(0.0, tb, steps(0.0, tb)), n_lon);
        let b_inner = sphere_zone(d, r, &angles(tb, pi, steps(tb, pi)), n_lon);
        (a_inner, a_outer, b_outer, b_inner)
    };
    let (a_in, a_out, b_out, b_in) = zones(1.0);
    let input = soup(&[&a_in, &a_out, &b_out, &b_in]);
    // Each whole sphere is closed and outward.
    assert!(soup(&[&a_in, &a_out]).signed_volume(None) > 4.0, "{}", soup(&[&a_in, &a_out]).signed_volume(None));
    let diag = input.diagonal();
    let union = corners(&soup(&[&a_out, &b_out]));
    let t0 = Instant::now();
    let exact = boundary_distance(&union, &input, diag / 50.0);
    eprintln!("exact union: {exact:?} ({:.2} s)", t0.elapsed().as_secs_f64());
    assert!(exact.hausdorff_mm < 1e-12, "{exact:?}");
    // The facets are chords: within 1 - cos(psi) of the sphere, psi = sqrt(2) pi / 64
    // the angular half-diagonal of a polar and longitude step of pi / 32.
    let sagitta = 1.0 - (2f64.sqrt() * std::f64::consts::PI / 64.0).cos();
    assert!((exact.raw_hausdorff_mm - d).abs() <= sagitta, "{exact:?}");
    assert!(exact.raw_surface_to_mesh_mm > exact.raw_mesh_to_surface_mm);
    assert!(exact.num_interior_input_triangles > 0 && exact.num_border_edges == 0, "{exact:?}");
    assert_eq!(exact.hole_cap_mm, 0.0);

    let eps = 0.05;
    let (_, ga_out, gb_out, _) = zones(1.0 + eps);
    let grown = corners(&soup(&[&ga_out, &gb_out]));
    let g = boundary_distance(&grown, &input, diag / 50.0);
    let crease = ((1.0f64 + eps).powi(2) - d * d / 4.0).sqrt() - (1.0 - d * d / 4.0).sqrt();
    eprintln!("grown union: {g:?}, closed form {crease:.5}");
    assert!((g.hausdorff_mm - crease).abs() < sagitta, "{g:?} against {crease}");
    assert!(g.hausdorff_mm > eps + 4e-3, "{g:?}");
    assert!((g.mesh_to_boundary_mm - eps).abs() < sagitta, "{g:?}");
}

/// The faces of the box `lo..hi` outside the box `other_lo..other_hi`, as
/// triangles: each face cut into the rectangles between the coordinates
/// `breaks` (which must hold both boxes' bounds), those whose centre is outside
/// the other box kept (two triangles each). With no coplanar faces, the union
/// of two boxes' boundaries is exactly this for each box against the other.
fn box_faces_outside(
    lo: [f64; 3],
    hi: [f64; 3],
    other_lo: [f64; 3],
    other_hi: [f64; 3],
    breaks: &[f64],
) -> Vec<[[f64; 3]; 3]> {
    let inside = |p: [f64; 3]| (0..3).all(|k| p[k] > other_lo[k] && p[k] < other_hi[k]);
    let mut out = Vec::new();
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let cuts = |k: usize| -> Vec<f64> { breaks.iter().copied().filter(|&x| x >= lo[k] && x <= hi[k]).collect() };
        let (cu, cv) = (cuts(u), cuts(v));
        for plane in [lo[axis], hi[axis]] {
            for a in cu.windows(2) {
                for b in cv.windows(2) {
                    let at = |x: f64, y: f64| {
                        let mut p = [0.0; 3];
                        (p[axis], p[u], p[v]) = (plane, x, y);
                        p
                    };
                    if !inside(at(0.5 * (a[0] + a[1]), 0.5 * (b[0] + b[1]))) {
                        out.push([at(a[0], b[0]), at(a[1], b[0]), at(a[1], b[1])]);
                        out.push([at(a[0], b[0]), at(a[1], b[1]), at(a[0], b[1])]);
                    }
                }
            }
        }
    }
    out
}

/// The distance's jump curves placed on the curve: two boxes given
/// whole as one soup, A = [0, 1]^3 and B = [0.5, 1.5] x [0.25, 0.75]^2, 12
/// triangles each, so the jump curves (where each box's faces enter the other)
/// cross the input triangles inside. "Mesh" = the exact union's boundary: the
/// boundary figure is 0 but for the placement of those curves, within 1/128 of
/// a refined grid edge (the hypotenuse, sqrt 2 / 48) plus the probes' pull
/// (100 x 1e-7 of the diagonal): asserted <= 2.5e-4 mm, measured 1.63e-4 mm
/// (1/128 of an axis-parallel grid edge of 1/48). The raw figure
/// is B's inner face's centre, A's centre, 0.5 from A's faces (asserted within
/// 1e-12).
#[test]
fn the_boundary_distance_places_jump_curves_inside_triangles() {
    use meshing::distance::boundary_distance;
    let (a_lo, a_hi) = ([0.0; 3], [1.0; 3]);
    let (b_lo, b_hi) = ([0.5, 0.25, 0.25], [1.5, 0.75, 0.75]);
    let input = soup(&[&Surface::cuboid(a_lo, a_hi, "a"), &Surface::cuboid(b_lo, b_hi, "b")]);
    let breaks = [0.0, 0.25, 0.5, 0.75, 1.0, 1.5];
    let mut union = box_faces_outside(a_lo, a_hi, b_lo, b_hi, &breaks);
    union.extend(box_faces_outside(b_lo, b_hi, a_lo, a_hi, &breaks));
    // The union's area: A's 6 minus the square B covers on x = 1, plus B's outside part.
    let area: f64 = union
        .iter()
        .map(|t| {
            let (u, v) = ([0, 1, 2].map(|k| t[1][k] - t[0][k]), [0, 1, 2].map(|k| t[2][k] - t[0][k]));
            let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
        })
        .sum();
    assert!((area - (6.0 - 0.25 + 4.0 * 0.5 * 0.5 + 0.25)).abs() < 1e-12, "{area}");
    let t0 = Instant::now();
    let m = boundary_distance(&union, &input, input.diagonal() / 50.0);
    eprintln!("overlapping boxes: {m:?} ({:.2} s)", t0.elapsed().as_secs_f64());
    assert!(m.hausdorff_mm <= 2.5e-4, "{m:?}");
    assert!((m.raw_hausdorff_mm - 0.5).abs() < 1e-12, "{m:?}");
    assert!(m.num_interior_input_triangles > 0 && m.num_partly_interior_input_triangles > 0, "{m:?}");
    assert_eq!((m.num_border_edges, m.hole_cap_mm), (0, 0.0));
}

/// An open scan: the unit sphere with a polar cap of angular radius alpha = 40 deg
/// cut off (one border loop of n = 64 chords). The solid's boundary over the hole
/// is the flat rim polygon: the scan and the polygon bound a convex polyhedron,
/// so from a point of the polygon every direction into the scan's side leaves
/// through the scan once, and w = 1/2 there exactly.
///
/// - "Mesh" = the whole sphere: off the hole it is the input; over it, the
///   cut-off cap. Its samples farther than a sample spacing s (diag / 50 =
///   0.0667) from the input straddle the level set within 0.9 of that
///   distance: over the hole, reported apart. Those nearer count: they lie on
///   the last cap ring's facets (the next ring, 2 sin 2.5 deg = 0.087 from the
///   rim, is farther), whose nearest input point is on the rim chord (the
///   scan's first ring bends away), so at a distance e <= s from the chord,
///   e sin(beta) above the polygon's plane, beta < alpha the facet's tilt, and
///   the probe along the normal meets the plane at e tan(beta) < s tan(alpha)
///   = 0.0559 (asserted, plus the precision; measured 0.03349 at x = 0.7926,
///   0.0266 above the plane).
///   The cap apart: (a) how far it strays from the solid's boundary. The level
///   set over the hole is the flat rim polygon x = cos alpha, and the sphere's
///   farthest point above it is the pole, 1 - cos alpha = 0.23396 above the
///   polygon's centre (inside the polygon: no sagitta enters). The pole is a
///   mesh vertex (the caps are bounded at the vertices: module docs of
///   `distance.rs`), and every figure is an upper bound of a distance, so
///   the figure is at least 1 - cos alpha (asserted, to 1e-12); each sample
///   is probed along a facet's normal, which meets the plane at (x - cos
///   alpha) / n_x, at most 0.23418 over the cap's corners (the pole's facets
///   tilted 2.5 deg): asserted within [1 - cos alpha, 0.23418 + 1e-6 of the
///   diagonal], measured 0.23418. (b) Its farthest point from the input is the pole, at
///   sqrt((1 - cos alpha)^2 + sin^2 alpha cos^2(pi / n)) = 0.68331 from the
///   rim's chord midpoints (measured 0.68331, asserted within 1e-9); the
///   border loop's extent is 2 sqrt(2) sin(alpha) = 1.81808 (its vertices at
///   phi = 0, 90, 180, 270 deg; asserted within 1e-9); the raw distance is the
///   cap's.
/// - "Mesh" = the scan and the polygon (the fan from its centre) moved out by
///   delta = 0, 0.01, 0.05: every point of the moved polygon is delta from the
///   solid's boundary (the polygon below it; the scan is on the other side of
///   the polygon's plane), and the probe along its normal meets the level set
///   at delta: over the samples within a spacing of the input (the others are
///   over the hole, reported apart), the figure must be within [delta, delta +
///   1e-6 of the diagonal] (asserted; measured delta + 0 to 2.0e-6, the
///   diagonal 3.3 mm), and so must the caps' distance to the level set, for a
///   lift of 0.1 > s too (all of the polygon over the hole).
#[test]
fn the_cap_over_an_open_scans_hole_is_measured_apart() {
    use meshing::distance::boundary_distance;
    let alpha = 40f64.to_radians();
    let pi = std::f64::consts::PI;
    let scan = sphere_zone(0.0, 1.0, &angles(alpha, pi, 28), 64);
    let cap = sphere_zone(0.0, 1.0, &angles(0.0, alpha, 8), 64);
    let whole = corners(&soup(&[&scan, &cap]));
    let t0 = Instant::now();
    let m = boundary_distance(&whole, &scan, scan.diagonal() / 50.0);
    eprintln!("open scan: {m:?} ({:.2} s)", t0.elapsed().as_secs_f64());
    let precision = meshing::distance::LEVEL_SET_PRECISION * scan.diagonal();
    // The normal probe's bound over the cap: linear in x on each facet, largest at a corner.
    let probe_bound = corners(&cap)
        .iter()
        .map(|t| {
            let (u, v) = ([0, 1, 2].map(|k| t[1][k] - t[0][k]), [0, 1, 2].map(|k| t[2][k] - t[0][k]));
            let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            let nx = c[0] / (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            t.iter().map(|p| (p[0] - alpha.cos()) / nx).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    eprintln!("cap against the level set: 1 - cos alpha {:.5}, probe bound {probe_bound:.5}", 1.0 - alpha.cos());
    let spacing = scan.diagonal() / 50.0;
    assert!(m.hausdorff_mm > 0.0 && m.hausdorff_mm <= spacing * alpha.tan() + precision, "{m:?}");
    let pole = 1.0 - alpha.cos();
    assert!(m.cap_to_level_set_mm >= pole - 1e-12 && m.cap_to_level_set_mm <= probe_bound + precision, "{m:?}");
    let chord = ((1.0 - alpha.cos()).powi(2) + (alpha.sin() * (pi / 64.0).cos()).powi(2)).sqrt();
    assert!((m.hole_cap_mm - chord).abs() < 1e-9, "{m:?} against {chord}");
    assert!((m.raw_hausdorff_mm - chord).abs() < 1e-9, "{m:?}");
    assert_eq!(m.num_border_edges, 64);
    assert!((m.widest_hole_mm - 2.0 * 2f64.sqrt() * alpha.sin()).abs() < 1e-9, "{m:?}");
    assert!(m.hole_cap_fraction > 0.0 && m.hole_cap_fraction < 0.5, "{m:?}");
    assert_eq!(m.num_interior_input_triangles, 0);

    // The scan and the rim polygon moved out by delta.
    let rim: Vec<[f64; 3]> = (0..64)
        .map(|k| {
            let phi = 2.0 * pi * k as f64 / 64.0;
            [alpha.cos(), alpha.sin() * phi.cos(), alpha.sin() * phi.sin()]
        })
        .collect();
    for delta in [0.0, 0.01, 0.05, 0.1] {
        let lift = |p: [f64; 3]| [p[0] + delta, p[1], p[2]];
        let mut mesh = corners(&scan);
        mesh.extend((0..64).map(|k| [lift([alpha.cos(), 0.0, 0.0]), lift(rim[(k + 1) % 64]), lift(rim[k])]));
        let m = boundary_distance(&mesh, &scan, scan.diagonal() / 50.0);
        eprintln!(
            "rim polygon moved by {delta}: {:.3e} over, caps {:.3e} over",
            m.mesh_to_boundary_mm - delta,
            m.cap_to_level_set_mm - delta
        );
        assert!(m.mesh_to_boundary_mm <= delta + precision, "{delta}: {m:?}");
        if delta < spacing {
            assert!(m.mesh_to_boundary_mm >= delta, "{delta}: {m:?}");
        }
        assert!(m.cap_to_level_set_mm >= delta && m.cap_to_level_set_mm <= delta + precision, "{delta}: {m:?}");
        assert!(m.hole_cap_mm > 0.0 && m.hole_cap_fraction > 0.0, "{delta}: {m:?}");
    }
}

/// The fitting carves boundary tets outside the solid: a thin void
/// bounded by a level set. The 40 deg open scan (the unit sphere, its cap x >
/// cos 40 deg off: the level set over the hole is the plane x = cos 40 deg,
/// as in the test above) and a box hovering over the hole, its bottom a gap g
/// = 0.07 above that plane, on a uniform lattice of 0.1: the slab between the
/// plane and the box's bottom is outside the solid, and the stuffing fills it
/// (its lattice vertices warped onto the two walls: tets with one corner
/// inside and three on the walls are kept whole, as at the teapot handle's
/// mouth). Every point of the slab is outside both parts, so its distance to
/// the solid's boundary is, in closed form, the smaller of its height above
/// the plane and its distance to the box (the sphere is at least 0.08 away).
/// Over the mesh boundary's vertices, edge midpoints and face centroids in the
/// slab: unfitted measured 0.0350 (g/2: faces across the slab), asserted at
/// least 0.4 g; fitted (tolerance 1e-3 of the diagonal 3.51: 3.5e-3), 144
/// tets carved and the farthest such point measured 4.8e-12 (every boundary
/// point left in the slab lies on one of its walls, to the bisection of the
/// level-set cut points), asserted within the tolerance; 12 s.
/// Where a tet straddles the slab with corners inside both parts (gaps 0.03
/// to 0.06 on this lattice), carving cannot take it and nothing changes
/// (measured: the figure stays g/2 with g = 0.05, 0.06).
#[test]
fn the_fitting_carves_off_a_void_thinner_than_the_lattice_bounded_by_a_level_set() {
    let alpha = 40f64.to_radians();
    let (plane, g) = (alpha.cos(), 0.07);
    let scan = sphere_zone(0.0, 1.0, &angles(alpha, std::f64::consts::PI, 28), 64);
    let (lo, hi) = ([plane + g, -0.3, -0.3], [plane + g + 0.25, 0.3, 0.3]);
    let box_ = Surface::cuboid(lo, hi, "box");
    let s = soup(&[&scan, &box_]);
    let tol = 1e-3 * s.diagonal();
    // The farthest mesh boundary point in the slab from the solid's boundary.
    let farthest_in_slab = |out: &EnvelopeMesh| -> f64 {
        let nodes = &out.mesh.nodes;
        let mut worst: f64 = 0.0;
        for f in out.mesh.boundary_facets() {
            let q = f.map(|v| nodes[v as usize]);
            let mid = |a: [f64; 3], b: [f64; 3], t: f64| [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k]));
            let centroid = mid(mid(q[0], q[1], 0.5), q[2], 1.0 / 3.0);
            let points = [q[0], q[1], q[2], mid(q[0], q[1], 0.5), mid(q[1], q[2], 0.5), mid(q[2], q[0], 0.5), centroid];
            for p in points {
                if p[0] > plane && p[0] < plane + g {
                    let to_box = (0..3).map(|k| (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0).powi(2)).sum::<f64>().sqrt();
                    worst = worst.max((p[0] - plane).min(to_box));
                }
            }
        }
        worst
    };
    let unfitted = envelope_mesh(&s, &EnvelopeOptions { fit_tolerance: 0.0, ..EnvelopeOptions::new(0.1) }).unwrap();
    let fitted = envelope_mesh(&s, &EnvelopeOptions::new(0.1)).unwrap();
    let (before, after) = (farthest_in_slab(&unfitted), farthest_in_slab(&fitted));
    eprintln!(
        "slab: unfitted {before:.4e}, fitted {after:.4e} (tol {tol:.4e}); {} tets carved, {} -> {} tets",
        fitted.stats.fit_carved,
        unfitted.mesh.cells.len(),
        fitted.mesh.cells.len()
    );
    assert!(before >= 0.4 * g, "the stuffing left the slab open: {before}");
    assert!(fitted.stats.fit_carved > 0);
    assert!(after <= tol, "{after} against {tol}");
    assert_conforming(&fitted.mesh);
}

/// An open scan on the graded lattice: the unit sphere with a
/// polar cap of angular radius 40 deg cut off (as above). Where the solid leaves
/// the input for the cap over the hole, its boundary has a crease along the rim
/// that no input triangle shows, and the fitting cannot bring the boundary onto
/// it (`graded.rs` module docs): the grading refines the cells the rim passes
/// below the smallest size, until their crease estimate meets the grading
/// tolerance. Measured (h = 0.25 mm, 3 levels, 156k tets, mesh 4 to 9 s,
/// report 2 to 3 s, the machine shared with four other helpers): boundary
/// figure (caps apart) 7.43e-4 of the diagonal, its maximum off the rim
/// (in -> out at an input vertex by the equator; out -> in 6.91e-4); with the
/// rim refined to the smallest size only (83k tets) 2.19e-3 at the midpoint of
/// a rim chord, without the rim's refinement 3.65e-3. Asserted <= 1e-3 (the
/// issue's gate), angles in [12, 155] deg (measured [13.82, 150.89]). The cap
/// over the hole is reported apart (1.9e-1).
#[test]
fn an_open_scans_rim_is_refined_on_the_graded_lattice() {
    let alpha = 40f64.to_radians();
    let scan = sphere_zone(0.0, 1.0, &angles(alpha, std::f64::consts::PI, 28), 64);
    let options = EnvelopeOptions { grade_levels: 3, ..EnvelopeOptions::new(0.25) };
    let (out, q) = mesh_and_report_with(&scan, &options);
    eprintln!(
        "open scan, graded: boundary {:.3e} (out->in {:.3e}, in->out {:.3e} mm), caps {:.3e}, {} border edges",
        q.hausdorff_relative, q.mesh_to_surface_mm, q.surface_to_mesh_mm, q.hole_cap_relative, q.num_border_edges
    );
    assert_eq!(q.num_inverted, 0);
    assert_issue_angles(&q);
    assert_conforming(&out.mesh);
    assert_eq!(q.num_border_edges, 64);
    assert!(q.hole_cap_relative > q.hausdorff_relative, "{q:?}");
    assert!(q.hausdorff_relative <= 1e-3, "{q:?}");
}

/// Two unit boxes sharing a face given once (four edges in three faces): two
/// regions, one per box, volume 1 each (within 1e-9), a conforming interface
/// between them, and every envelope gate.
#[test]
fn boxes_sharing_a_face_become_two_regions() {
    if skip_without_shared_data("the mesh fixture layered_two_boxes.obj") {
        return;
    }
    let s = obj("layered_two_boxes.obj");
    let (out, q) = mesh_and_report(&s, 0.1);
    assert_proven_bounds(&out, &q);
    // The envelope gates (measured: dihedral [45, 90] deg, boundary figure 2.8e-16).
    assert_envelope_gates("layered_two_boxes.obj", &out, &q, 2.0, 1e-9);
    assert_eq!(out.mesh.region_names.len(), 2, "{:?}", out.mesh.region_names);
    for r in 0..2u16 {
        let v: f64 = out
            .mesh
            .cells
            .iter()
            .zip(&out.mesh.cell_regions)
            .filter(|(_, &cr)| cr == r)
            .map(|(c, _)| fem_core::element::signed_measure(&c.map(|v| out.mesh.nodes[v as usize])))
            .sum();
        assert!((v - 1.0).abs() < 1e-9, "region {r}: {v}");
    }
}

/// Two unit boxes 0.01 mm apart: the gap between them, narrower
/// than half the lattice spacing (0.05 mm at h = 0.1 mm), is reported as a thin
/// gap on the two facing faces (x = 1 and x = 1.01), its width the boxes'
/// distance: measured 1.0e-2 mm (the ray's start offset, 1e-7 of the
/// diagonal, aside), asserted within 1e-6 mm; no thin part is reported.
#[test]
fn a_thin_gap_is_reported_not_closed_silently() {
    let g = 0.01;
    let s = soup(&[
        &Surface::cuboid([0.0; 3], [1.0; 3], "a"),
        &Surface::cuboid([1.0 + g, 0.0, 0.0], [2.0 + g, 1.0, 1.0], "b"),
    ]);
    let (out, q) = mesh_and_report(&s, 0.1);
    assert_eq!(q.num_inverted, 0);
    assert_conforming(&out.mesh);
    let gaps: Vec<_> = out
        .warnings
        .iter()
        .filter_map(|w| match w {
            EnvelopeWarning::ThinGap { min_width_mm, lo_mm, hi_mm, num_triangles, .. } => {
                Some((*min_width_mm, *lo_mm, *hi_mm, *num_triangles))
            }
            _ => None,
        })
        .collect();
    assert_eq!(gaps.len(), 1, "{:?}", out.warnings);
    let (width, lo, hi, num) = gaps[0];
    assert!((width - g).abs() < 1e-6, "narrowest {width}");
    assert_eq!(num, 4, "the two facing faces, two triangles each");
    assert!((lo[0] - 1.0).abs() < 1e-12 && (hi[0] - 1.0 - g).abs() < 1e-12, "{lo:?}..{hi:?}");
    assert!(!out.warnings.iter().any(|w| matches!(w, EnvelopeWarning::ThinFeature { .. })), "{:?}", out.warnings);
}

/// The volume [mm^3] of the solid `w > 1/2` of `s`, by stratified sampling: one
/// point in each cell of a grid of spacing `h` [mm] over the input's box, placed
/// in its cell by a fixed hash of the cell's index (the same at any thread
/// count), classified by the inside test exact near 1/2. Only the cells the
/// boundary crosses err, independently, each by at most `h^3` with variance at
/// most `h^6 / 4`; a surface of area `A` crosses at most about `sqrt(3) A / h^2`
/// cells, so the standard deviation is at most `h^3 sqrt(sqrt(3) A / (4 h^2))`.
fn solid_volume_by_sampling(s: &Surface, h: f64) -> f64 {
    use rayon::prelude::*;
    fn mix(mut z: u64) -> u64 {
        // SplitMix64's finalizer.
        z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    let w = WindingNumber::new(s);
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for v in &s.vertices {
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    let n: [u64; 3] = std::array::from_fn(|k| ((hi[k] - lo[k]) / h).ceil() as u64 + 1);
    let unit = |z: u64| (mix(z) >> 11) as f64 / (1u64 << 53) as f64;
    let inside = (0..n[0] * n[1] * n[2])
        .into_par_iter()
        .filter(|&c| {
            let cell = [c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])];
            let r = mix(c);
            w.is_inside_checked(std::array::from_fn(|k| lo[k] + (cell[k] as f64 + unit(r + k as u64)) * h))
        })
        .count();
    inside as f64 * h.powi(3)
}

/// The Utah teapot: open (64 border edges), four parts, self-intersecting.
///
/// Volume: the report's reference is the divergence-theorem volume of the
/// triangles, 3172.52 mm^3, which counts twice the spout's and the handle's
/// ends inside the body. The issue's gate for defective input (1 %, against
/// the exact union) is checked against the solid `w > 1/2` itself, sampled
/// ([`solid_volume_by_sampling`]). The sampler is first checked on the closed
/// bunny, whose solid's volume is its divergence-theorem volume, 194.288 mm^3.
/// Measured: bunny (218.7 mm^2) at h = 0.2 mm 194.648 mm^3
/// (+1.85e-3; the bound on the standard deviation 2.0e-3), asserted within
/// 4.6e-3 (2.3 of them); teapot (1288.8 mm^2 of triangles) at h = 0.3 mm
/// 3137.157 (six seeds of the hash: 3132.97 to 3137.16, mean 3135.73,
/// standard deviation 1.45 mm^3 = 4.6e-4; the bound 6.8e-4), the mesh
/// 3130.519 mm^3 (343,752 tets; 3132.473 without the fitting's carving): -1.32e-2
/// against the divergence-theorem volume, -2.12e-3 against the solid's,
/// asserted within 1e-2 less the sampler's three standard deviations' bound
/// (2.1e-3).
#[test]
fn the_teapot_meshes_with_the_proven_bounds() {
    if skip_without_shared_data("the mesh fixture npm_teapot.obj") {
        return;
    }
    let s = obj("npm_teapot.obj");
    let (out, q) = mesh_and_report(&s, 0.5);
    assert_proven_bounds(&out, &q);
    assert_issue_angles(&q);
    assert_conforming(&out.mesh);
    let bunny = obj("npm_bunny.obj");
    let (sampled, exact) = (solid_volume_by_sampling(&bunny, 0.2), bunny.signed_volume(None));
    eprintln!("bunny: solid sampled {sampled:.3} mm^3, divergence theorem {exact:.3}");
    assert!((sampled / exact - 1.0).abs() < 4.6e-3, "{sampled} vs {exact}");
    let solid = solid_volume_by_sampling(&s, 0.3);
    let error = q.volume_mm3 / solid - 1.0;
    eprintln!(
        "teapot: mesh {:.3} mm^3, solid sampled {solid:.3}, error {error:.3e} (against the triangles' {:.3}: {:.3e})",
        q.volume_mm3, q.reference_volume_mm3, q.volume_error
    );
    assert!(error.abs() < 1e-2 - 2.1e-3, "{error}");
    // The triangles' volume counts the overlaps twice: about 1 % over the solid's.
    assert!(q.reference_volume_mm3 / solid - 1.0 > 5e-3, "{} vs {solid}", q.reference_volume_mm3);
    // 64 border edges once welded, the widest the body's top opening (a circle
    // of diameter 14 mm: extent 14 sqrt 2 = 19.80 mm); measured: the caps
    // 1.31e-2 of the diagonal from the input; the boundary distance 2.35e-2 (a
    // miss of the issue's 1e-3), the raw one 4.16e-2; the boundary distance's
    // maximum (input -> mesh) at the spout's tip, (16.07,
    // 4.51, 0) mm, 0.96 mm from the mesh: inside the box of the thin-feature
    // warning asserted below (the spout's wall, thinner than the lattice).
    assert_eq!(q.num_border_edges, 64);
    assert!((q.widest_hole_mm - 14.0 * 2f64.sqrt()).abs() < 1e-2, "{q:?}");
    assert!(q.hole_cap_relative > 0.0 && q.hausdorff_relative < 2.5e-2, "{q:?}");
    assert!(q.raw_hausdorff_relative > q.hausdorff_relative, "{q:?}");
    assert!(out.warnings.iter().any(|w| matches!(w, EnvelopeWarning::ThinFeature { .. })), "{:?}", out.warnings);
    assert!(q.mesh_time_s > 0.0 && q.mesh_time_s.is_finite());
    // Where the handle's open tube meets the body, outside the body
    // `w` is 0.49 to 0.51 (the tube's mouth), and the solid has a void there, a
    // wedge between the body and the level set `w = 1/2` (0 at |z| = 0.23 mm,
    // 0.15 mm thick at |z| = 1.06 mm, up to 0.5 mm), which no centroid ray sees:
    // the sampled thin test reports it as a thin gap, on the handle's side.
    let gap = out.warnings.iter().find_map(|w| match w {
        EnvelopeWarning::ThinGap { lo_mm, hi_mm, .. } => Some((*lo_mm, *hi_mm)),
        _ => None,
    });
    let (lo, hi) = gap.unwrap_or_else(|| panic!("no thin gap reported: {:?}", out.warnings));
    let mouth = [-10.83, -4.12, 0.23];
    assert!((0..3).all(|k| lo[k] <= mouth[k] && mouth[k] <= hi[k]), "{lo:?}..{hi:?}");
    assert!(hi[0] < 0.0, "the gap is on the handle's side: {lo:?}..{hi:?}");
}

/// The teapot on the graded lattice (0.5 mm, 3 levels). The sizing refines
/// cells across which the solid or a gap of it is thinner than the cell (the
/// level set `w = 1/2` counted as a wall); the stuffing decides the inside
/// exactly where `w` is within 0.1 of 1/2 (the figure 1.15e-2 -> 3.63e-3 of
/// the diagonal, at the handle's mouth). Below the smallest size, cells across
/// which such a part or gap is thinner than the cell are cut again while 2.5
/// times their longest edge exceeds the grading tolerance (the void at the
/// handle's mouth, then the void between the spout's wall and the cap over its
/// opening): input -> mesh 1.005e-3 with that alone (0.0412 mm at the spout's
/// tip). The spout lip's blade (its two faces 49.4 deg apart, the solid between
/// them thinner than any cell) is cut below the smallest size as at a rim:
/// input -> mesh 9.74e-4 (0.0399 mm, next at a quad's fold under the spout, a
/// 50 deg crease the chord estimate passes at 0.177 mm cells). Mesh -> input
/// is measured against the solid's true boundary (`distance.rs`): without the
/// fitting's carving of the boundary tets outside the solid (`fit.rs`: tets
/// with one corner inside the handle and three on the void's walls, kept whole
/// by the stuffing) the mesh is 0.06 mm outside the level set at the handle's
/// mouth (1.548e-3); with it, and with the peeling of boundary slivers
/// (`graded.rs`, `peel_slivers`) counting a corner as near the boundary when
/// within half the tolerance of any input triangle, the spout's wall inside
/// the body included, 1.4155e-3 (0.0580 mm at (8.25, -1.125, 1.5): a trench
/// dug along the spout's wall inside the body). The peeling counts by the
/// solid's boundary (the bounding part of the input, as the report measures).
/// Measured: 1,600,573 tets, 12.05-154.42 deg (asserted in [12, 155]), out->in
/// 8.5721e-4 (then at (-6.53, 4.55, 4.28)), in->out 9.7373e-4, both asserted
/// < 1e-3 (the gate); volume -1.199e-2 against the triangles, -8.56e-4 against
/// the sampled solid (asserted within 1e-2 less the sampler's bound, 2.1e-3).
#[test]
fn the_graded_teapot_resolves_the_voids_at_the_handles_mouth_and_the_spouts_lip() {
    if skip_without_shared_data("the mesh fixture npm_teapot.obj") {
        return;
    }
    let s = obj("npm_teapot.obj");
    let (out, q) = mesh_and_report_with(&s, &EnvelopeOptions { grade_levels: 3, ..EnvelopeOptions::new(0.5) });
    eprintln!(
        "teapot graded: {} tets, [{:.2}, {:.2}] deg, out->in {:.4e}, in->out {:.4e}, volume {:.3e}",
        q.num_cells,
        q.min_dihedral_deg,
        q.max_dihedral_deg,
        q.mesh_to_surface_mm / s.diagonal(),
        q.surface_to_mesh_mm / s.diagonal(),
        q.volume_error
    );
    assert_issue_angles(&q);
    assert_conforming(&out.mesh);
    assert!(q.volume_error.abs() < 3e-2, "{}", q.volume_error);
    assert!(q.surface_to_mesh_mm / s.diagonal() < 1e-3, "{q:?}");
    assert!(q.mesh_to_surface_mm / s.diagonal() < 1e-3, "{q:?}");
    // The issue's volume gate against the solid, as in `the_teapot_meshes_with_the_proven_bounds`.
    let solid = solid_volume_by_sampling(&s, 0.3);
    let error = q.volume_mm3 / solid - 1.0;
    eprintln!("teapot graded: mesh {:.3} mm^3, solid sampled {solid:.3}, error {error:.3e}", q.volume_mm3);
    assert!(error.abs() < 1e-2 - 2.1e-3, "{error}");
}

/// Layers along y: conforming planes, each layer's cells between its planes.
#[test]
fn the_bunny_cut_into_layers() {
    let s = obj("npm_bunny.obj");
    let (lo, hi) = s.bounding_box();
    let height = hi[1] - lo[1];
    let layers = [0.3 * height, 0.3 * height, 0.4 * height];
    let mut opts = EnvelopeOptions::new(0.3);
    opts.layers_mm = layers.to_vec();
    let out = envelope_mesh(&s, &opts).unwrap();
    assert_conforming(&out.mesh);
    let q = report(&out.mesh, &s, 0.0);
    eprintln!("layers: dihedral [{:.2}, {:.2}], {:?}", q.min_dihedral_deg, q.max_dihedral_deg, q.regions);
    assert_eq!(q.num_inverted, 0);
    assert!(q.min_dihedral_deg > 5.0 && q.max_dihedral_deg < 170.0, "{} {}", q.min_dihedral_deg, q.max_dihedral_deg);
    assert!(q.fraction_below_10_deg < 1e-3, "{}", q.fraction_below_10_deg);
    assert_eq!(out.mesh.region_names, vec!["layer1", "layer2", "layer3"]);
    let planes = [lo[1] + layers[0], lo[1] + layers[0] + layers[1]];
    for (c, &r) in out.mesh.cells.iter().zip(&out.mesh.cell_regions) {
        let below = if r == 0 { f64::NEG_INFINITY } else { planes[r as usize - 1] };
        let above = if r == 2 { f64::INFINITY } else { planes[r as usize] };
        for &v in c {
            let y = out.mesh.nodes[v as usize][1];
            assert!(y >= below - 1e-9 && y <= above + 1e-9, "layer {r}: node at y = {y}");
        }
    }
    let total: f64 = q.regions.iter().map(|r| r.volume_mm3).sum();
    assert!((total - q.volume_mm3).abs() < 1e-9 * total);
    let err = opts.layers_mm.iter().sum::<f64>() - height;
    assert!(err.abs() < 1e-12);
}

// ---- the corpus: every envelope gate, one run per file

/// A corpus file as written (`common::read_obj` parses f64; `obj` above, with
/// tobj's default f32, rounds the coordinates to 6e-8 relative: the thin fin's
/// 9.9e-5 mm would be off by 3e-8 mm).
fn corpus_obj(name: &str) -> Surface {
    common::read_obj_file(&data(name))
}

/// The graded lattice the bunny family needs for the Hausdorff gate: base 0.2
/// mm, 3 levels (finest 0.025 mm). Measured (BENCHMARKS.md): 0.4 mm
/// with 4 levels and 0.8 mm with 5 (the same finest size) cost the same within
/// 3 % and warn of the ear as thinner than half the base spacing; 0.3 mm with 3
/// levels and 0.5 mm with 4 miss (1.54e-3 and 1.19e-3 of the diagonal), as does
/// a grading tolerance of 7e-4 (1.49e-3).
fn bunny_graded() -> EnvelopeOptions {
    EnvelopeOptions { grade_levels: 3, ..EnvelopeOptions::new(0.2) }
}

/// The envelope gates on a mesh of the corpus: no inverted tet, every
/// dihedral angle in [12, 155] deg (none under 10 deg), a conforming mesh with a
/// closed boundary, the report's boundary figure (caps over holes apart, see
/// `meshing::distance`) within 1e-3 of the diagonal, and the volume within
/// `bound` of `reference_mm3` (relative). Returns the volume error.
fn assert_envelope_gates(name: &str, out: &EnvelopeMesh, q: &QualityReport, reference_mm3: f64, bound: f64) -> f64 {
    assert_eq!(q.num_inverted, 0, "{name}");
    assert_issue_angles(q);
    assert_conforming(&out.mesh);
    assert!(q.hausdorff_relative <= 1e-3, "{name}: boundary figure {} of the diagonal", q.hausdorff_relative);
    let err = (q.volume_mm3 - reference_mm3) / reference_mm3;
    eprintln!("{name}: volume {:.6} mm^3 against {reference_mm3:.6} mm^3, error {err:.2e}", q.volume_mm3);
    assert!(err.abs() <= bound, "{name}: volume error {err} against {reference_mm3} mm^3");
    err
}

/// A defective variant of the bunny, raw (no repair), on [`bunny_graded`]: the
/// gates, its volume within 1 % of the clean bunny's enclosed volume.
fn defective_bunny(name: &str) -> (EnvelopeMesh, QualityReport) {
    let clean = corpus_obj("npm_bunny.obj").signed_volume(None);
    let (out, q) = mesh_and_report_with(&corpus_obj(name), &bunny_graded());
    assert_envelope_gates(name, &out, &q, clean, 1e-2);
    (out, q)
}

/// The vertices of the surface's border edges (edges of one triangle).
fn border_vertices(s: &Surface) -> Vec<[f64; 3]> {
    let mut edges: std::collections::BTreeMap<(u32, u32), usize> = Default::default();
    for t in &s.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut v: Vec<u32> = edges.iter().filter(|(_, &n)| n == 1).flat_map(|(&(a, b), _)| [a, b]).collect();
    v.sort_unstable();
    v.dedup();
    v.iter().map(|&i| s.vertices[i as usize]).collect()
}

/// Two closed parts of `s` given as its triangles `0..split` and `split..`: their
/// bounding boxes, each checked to be the part (its enclosed volume the box's,
/// within 1e-12 relative).
fn two_boxes(s: &Surface, split: usize) -> [([f64; 3], [f64; 3]); 2] {
    let part = |range: std::ops::Range<usize>| {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let mut volume = 0.0;
        for t in &s.triangles[range] {
            let p = t.map(|v| s.vertices[v as usize]);
            for q in p {
                for k in 0..3 {
                    lo[k] = lo[k].min(q[k]);
                    hi[k] = hi[k].max(q[k]);
                }
            }
            volume += fem_core::element::signed_measure(&[[0.0; 3], p[0], p[1], p[2]]);
        }
        let boxed = (0..3).map(|k| hi[k] - lo[k]).product::<f64>();
        assert!((volume - boxed).abs() <= 1e-12 * boxed, "a part of volume {volume} in a box of {boxed}");
        (lo, hi)
    };
    [part(0..split), part(split..s.triangles.len())]
}

/// The volume of the union of two axis-aligned boxes (closed form).
fn box_union_volume(a: ([f64; 3], [f64; 3]), b: ([f64; 3], [f64; 3])) -> f64 {
    let size = |lo: [f64; 3], hi: [f64; 3]| (0..3).map(|k| (hi[k] - lo[k]).max(0.0)).product::<f64>();
    let common = size([0, 1, 2].map(|k| a.0[k].max(b.0[k])), [0, 1, 2].map(|k| a.1[k].min(b.1[k])));
    size(a.0, a.1) + size(b.0, b.1) - common
}

/// The volume of the union of two closed, outward, **convex** polyhedra given as
/// triangles, by the divergence theorem over the union's boundary: each one's
/// triangles less their parts inside the other, those parts cut out exactly
/// (but for rounding) by clipping the triangle against the other's face planes
/// (Sutherland-Hodgman). Asserts the convexity it relies on (every vertex on
/// the inner side of every face plane of its own polyhedron, within 1e-12).
fn convex_union_volume(a: &[[[f64; 3]; 3]], b: &[[[f64; 3]; 3]]) -> f64 {
    type V3 = [f64; 3];
    let sub = |p: V3, q: V3| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let dot = |p: V3, q: V3| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    let cross = |u: V3, v: V3| [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    // Outward unit normal and offset of each face plane: inside where n.x <= d.
    let planes = |s: &[[V3; 3]]| -> Vec<(V3, f64)> {
        s.iter()
            .map(|t| {
                let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
                let l = dot(n, n).sqrt();
                let n = [n[0] / l, n[1] / l, n[2] / l];
                (n, dot(n, t[0]))
            })
            .collect()
    };
    let (pa, pb) = (planes(a), planes(b));
    for (s, p) in [(a, &pa), (b, &pb)] {
        for &(n, d) in p {
            for t in s {
                for &v in t {
                    assert!(dot(n, v) - d <= 1e-12, "not convex: {}", dot(n, v) - d);
                }
            }
        }
    }
    // The signed volume of the cone from the origin over a planar polygon (a fan).
    let cone = |poly: &[V3]| -> f64 {
        (1..poly.len().saturating_sub(1)).map(|i| dot(poly[0], cross(poly[i], poly[i + 1])) / 6.0).sum()
    };
    let inside_part = |t: &[V3; 3], planes: &[(V3, f64)]| -> Vec<V3> {
        let mut poly = t.to_vec();
        for &(n, d) in planes {
            if poly.is_empty() {
                break;
            }
            let mut next = Vec::with_capacity(poly.len() + 1);
            for i in 0..poly.len() {
                let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                let (dp, dq) = (dot(n, p) - d, dot(n, q) - d);
                if dp <= 0.0 {
                    next.push(p);
                }
                if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
                    let u = dp / (dp - dq);
                    next.push([p[0] + u * (q[0] - p[0]), p[1] + u * (q[1] - p[1]), p[2] + u * (q[2] - p[2])]);
                }
            }
            poly = next;
        }
        poly
    };
    let outside =
        |s: &[[V3; 3]], other: &[(V3, f64)]| -> f64 { s.iter().map(|t| cone(t) - cone(&inside_part(t, other))).sum() };
    outside(a, &pb) + outside(b, &pa)
}

/// The clean bunny with every gate. Measured (0.2 mm, 3 levels): 713k tets,
/// dihedral [13.80, 151.24] deg,
/// volume error -4.4e-4 against its enclosed volume, boundary figure 9.98e-4
/// of the diagonal (a thin margin: the same 9.98e-4 at every base size whose
/// finest cells are 0.025 mm). Asserted: the gates, the volume within 2e-3
/// (clean input), no warning, no border.
#[test]
fn corpus_clean_bunny_meets_every_envelope_gate() {
    let s = corpus_obj("npm_bunny.obj");
    let (out, q) = mesh_and_report_with(&s, &bunny_graded());
    let err = assert_envelope_gates("npm_bunny.obj", &out, &q, s.signed_volume(None), 2e-3);
    assert!((err - q.volume_error).abs() < 1e-12, "{err} {}", q.volume_error);
    assert!(out.warnings.is_empty(), "{:?}", out.warnings);
    assert!(out.stats.grade_bisections > 0);
    assert_eq!((q.num_border_edges, q.hole_cap_mm), (0, 0.0));
}

/// The holed bunny (12 border edges in one loop, 1.87 mm wide), raw. Off the
/// hole, the gates: boundary figure measured 9.98e-4 (with the rim's
/// refinement), volume -6.1e-4 from the clean bunny's (+8.5e-3 from the holed
/// file's own divergence-theorem volume, which misses the hole's part).
///
/// The cap over the hole is measured apart (`hole_cap_mm`: the mesh boundary
/// samples farther than a sample spacing from the input where the level set is
/// nearer, their distance to the input), against a closed-form bound. With the holed input closed by a fan
/// from its rim's centroid c (inside the rim's convex hull), the winding number
/// is w = k - Omega/(4 pi), k an integer (the closed surface's) and Omega the
/// fan's solid angle; from a point outside the hull the fan lies in an open
/// half-space, |Omega| < 2 pi, so w = 1/2 (the solid's boundary) only inside
/// the hull. A point p = sum l_i v_i of the hull has sum l_i |p - v_i|^2 = sum
/// l_i |v_i - c|^2 - |p - c|^2 <= rho^2, rho = max |v_i - c|: it is within rho
/// of a rim vertex, a point of the input. The mesh's cap interpolates w = 1/2 on
/// the lattice, whose finest spacing (0.025 mm) is added. Measured: cap 0.461 mm
/// (2.93e-2 of the diagonal) against the bound 0.742 + 0.025 mm; the cap's
/// distance to the level set (printed only) 1.42e-5 mm = 9.0e-7 of the diagonal (the probe's floor: every cap
/// vertex within 0.9e-6 of the diagonal of the level set); the widest hole's
/// extent, the rim's bounding-box diagonal, 1.866 mm (asserted to 1e-9 mm).
#[test]
fn corpus_holed_bunny_meets_every_gate_its_cap_within_its_bound() {
    if skip_without_shared_data("the mesh fixture bad_syn_hole.obj") {
        return;
    }
    let name = "bad_syn_hole.obj";
    let (_, q) = defective_bunny(name);
    let rim = border_vertices(&corpus_obj(name));
    assert_eq!((q.num_border_edges, rim.len()), (12, 12));
    let n = rim.len() as f64;
    let c = [0, 1, 2].map(|k| rim.iter().map(|v| v[k]).sum::<f64>() / n);
    let rho = rim
        .iter()
        .map(|v| ((v[0] - c[0]).powi(2) + (v[1] - c[1]).powi(2) + (v[2] - c[2]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    let finest = bunny_graded().size_mm / 8.0;
    eprintln!(
        "{name}: cap {:.4} mm ({:.3e} of the diagonal), bound rho {rho:.4} + {finest} mm; \
         from the level set {:.4e} mm ({:.3e})",
        q.hole_cap_mm, q.hole_cap_relative, q.cap_to_level_set_mm, q.cap_to_level_set_relative
    );
    assert!(q.hole_cap_mm > 0.0 && q.hole_cap_mm <= rho + finest, "{q:?}");
    let extent = {
        let lo = [0, 1, 2].map(|k| rim.iter().map(|v| v[k]).fold(f64::INFINITY, f64::min));
        let hi = [0, 1, 2].map(|k| rim.iter().map(|v| v[k]).fold(f64::NEG_INFINITY, f64::max));
        ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt()
    };
    assert!((q.widest_hole_mm - extent).abs() < 1e-9, "{} against {extent}", q.widest_hole_mm);
}

/// The bunny with 10 % of its faces flipped, raw. Regression: left flipped, on
/// the graded lattice it gave 200 tets outside [12, 155] deg (down to 0.36 deg)
/// and 2.25M tets, the winding number inverted next to each flipped face; they
/// are turned back before the inside test, and said (367 triangles, as
/// `repair` flips). Measured: the clean bunny's 713k tets,
/// angles, boundary figure 9.98e-4 and volume (-4.4e-4 from the clean one's).
#[test]
fn corpus_flipped_bunny_meets_every_envelope_gate() {
    if skip_without_shared_data("the mesh fixture bad_syn_flipped10pct.obj") {
        return;
    }
    let (out, _) = defective_bunny("bad_syn_flipped10pct.obj");
    let turned: usize = out
        .warnings
        .iter()
        .filter_map(|w| match w {
            EnvelopeWarning::FlippedFaces { num_triangles, .. } => Some(*num_triangles),
            _ => None,
        })
        .sum();
    assert_eq!(turned, 367, "{:?}", out.warnings);
}

/// The bunny given inside out, raw: meshed as the bunny (measured: its 713k
/// tets, boundary figure 9.98e-4, volume -4.4e-4 from the clean one's), with
/// an `InsideOut` warning.
#[test]
fn corpus_inverted_bunny_meets_every_envelope_gate() {
    if skip_without_shared_data("the mesh fixture bad_syn_inverted.obj") {
        return;
    }
    let (out, _) = defective_bunny("bad_syn_inverted.obj");
    assert!(out.warnings.iter().any(|w| matches!(w, EnvelopeWarning::InsideOut { .. })), "{:?}", out.warnings);
}

/// The bunny as an unwelded soup with 1e-9 jitter, raw: welded by the
/// distance's border test (no border edge), meshed as the bunny (measured: 713k
/// tets, boundary figure 9.98e-4, volume -4.4e-4 from the clean one's).
#[test]
fn corpus_soup_bunny_meets_every_envelope_gate() {
    if skip_without_shared_data("the mesh fixture bad_syn_soup_jitter.obj") {
        return;
    }
    let (_, q) = defective_bunny("bad_syn_soup_jitter.obj");
    assert_eq!((q.num_border_edges, q.hole_cap_mm), (0, 0.0), "{q:?}");
}

/// The bunny with 20 degenerate (needle) and 20 duplicate triangles, raw: the
/// needles leave 32 border edges beside them (34 when read in f32, as tobj
/// does: the rounding makes or unmakes needles), slits enclosing no area (the
/// widest chain's extent 1.26 mm): no mesh sample is over them (a sample over
/// a hole is farther than a sample spacing, 1/300 of the diagonal, from the
/// input), so no cap and no cap distance to the level set (measured 0 and 0,
/// asserted; taking the samples nearer to a fan patch over each border chain
/// than to the input as caps would measure slit caps of 2.4e-3 mm).
/// Measured 748k tets (the
/// border edges refined), boundary figure 9.98e-4, volume -4.4e-4 from the
/// clean bunny's.
#[test]
fn corpus_degenerate_bunny_meets_every_envelope_gate() {
    if skip_without_shared_data("the mesh fixture bad_syn_degenerate_dup.obj") {
        return;
    }
    let (_, q) = defective_bunny("bad_syn_degenerate_dup.obj");
    eprintln!(
        "degenerate: caps {:.3e} mm, fraction {:.3e}, from the level set {:.3e} mm, widest chain {:.3} mm",
        q.hole_cap_mm, q.hole_cap_fraction, q.cap_to_level_set_mm, q.widest_hole_mm
    );
    assert_eq!(q.num_border_edges, 32, "{q:?}");
    assert_eq!((q.hole_cap_mm, q.cap_to_level_set_mm, q.hole_cap_fraction), (0.0, 0.0, 0.0), "{q:?}");
}

/// Two overlapping icospheres (unit radius, 1280 triangles each, centres
/// d = sqrt(1.05) apart), raw, on the graded lattice (0.2 mm, 4 levels; 0.1 mm
/// with 3 and 0.4 mm with 5 cost the same). The reference is the exact union of
/// the two polyhedra (`convex_union_volume`): 7.071708 mm^3, against the
/// closed form of the two balls' union (7.126287) less the facets' deficit per
/// unit area times the union's area, 7.071768 (a first-order estimate: within
/// 8.5e-6, asserted 1e-4). (The balls' union scaled by the deficit per unit
/// volume, 7.064957, is 9.6e-4 low: the lens has more area per volume than a
/// ball.) Measured: 250k tets, dihedral
/// [13.89, 151.21] deg, boundary figure 9.39e-4 (the inner caps, 540 input
/// triangles wholly and 158 in part, bound nothing and are left out; the raw
/// figure, 0.97 mm, is the inner poles' depth), volume -9.6e-4 from the exact
/// union (the chords across the facets' convex edges cut inward).
#[test]
fn corpus_overlapping_spheres_mesh_their_exact_union() {
    if skip_without_shared_data("the mesh fixture bad_syn_overlapping_spheres.obj") {
        return;
    }
    let name = "bad_syn_overlapping_spheres.obj";
    let s = corpus_obj(name);
    assert_eq!((s.vertices.len(), s.triangles.len()), (1284, 2560));
    let (a, b) = s.triangles.split_at(1280);
    assert!(a.iter().flatten().all(|&v| v < 642) && b.iter().flatten().all(|&v| v >= 642));
    let tris =
        |part: &[[u32; 3]]| -> Vec<[[f64; 3]; 3]> { part.iter().map(|t| t.map(|v| s.vertices[v as usize])).collect() };
    let (ta, tb) = (tris(a), tris(b));
    let centre = |range: std::ops::Range<usize>| {
        [0, 1, 2].map(|k| s.vertices[range.clone()].iter().map(|v| v[k]).sum::<f64>() / 642.0)
    };
    let (ca, cb) = (centre(0..642), centre(642..1284));
    let d = ((cb[0] - ca[0]).powi(2) + (cb[1] - ca[1]).powi(2) + (cb[2] - ca[2]).powi(2)).sqrt();
    assert!((d - 1.05f64.sqrt()).abs() < 1e-9, "{d}");
    let exact = convex_union_volume(&ta, &tb);
    // The balls' union, closed form: two balls less the lens pi (4 + d)(2 - d)^2 / 12,
    // less the facets' deficit: the icosphere's per unit area of its sphere,
    // delta = (4/3 pi - V_ico) / (4 pi), times the union's area, 8 pi less the
    // two caps inside the other ball (each 2 pi h, h = 1 - d/2).
    let pi = std::f64::consts::PI;
    let ball = 4.0 / 3.0 * pi;
    let balls = 2.0 * ball - pi * (4.0 + d) * (2.0 - d).powi(2) / 12.0;
    let delta = (ball - 0.5 * s.signed_volume(None)) / (4.0 * pi);
    let area = 8.0 * pi - 4.0 * pi * (1.0 - d / 2.0);
    let estimate = balls - delta * area;
    eprintln!("{name}: exact union {exact:.6} mm^3; balls' union {balls:.6} less the facets' deficit: {estimate:.6}");
    assert!((exact / estimate - 1.0).abs() < 1e-4, "{exact} against {estimate}");
    let options = EnvelopeOptions { grade_levels: 4, ..EnvelopeOptions::new(0.2) };
    let (out, q) = mesh_and_report_with(&s, &options);
    assert_envelope_gates(name, &out, &q, exact, 1e-2);
    assert!(q.num_interior_input_triangles > 0 && q.num_partly_interior_input_triangles > 0, "{q:?}");
    assert!(q.raw_hausdorff_mm > 0.9, "{q:?}");
}

/// A fin 1e-4 mm thick (0.8 x 0.8 mm) through a face of a unit box, raw, on
/// the graded lattice (0.2 mm, 2 levels): the fin, thinner than half the
/// lattice spacing, is reported (`ThinFeature`: 1e-4 mm, at x = 0.5), not
/// dropped silently. Reference: the union of the two boxes (closed form), 1 +
/// 0.64 x 9.9e-5 mm^3. Measured: 16k tets, dihedral [44.89,
/// 120.03] deg, boundary figure 4.04e-5 of the diagonal (the fin, 9.9e-5 mm
/// proud of the face, is within that of the box's face), volume error -6.35e-6.
#[test]
fn corpus_thin_fin_meets_every_gate_and_is_reported() {
    if skip_without_shared_data("the mesh fixture bad_syn_thin_fin.obj") {
        return;
    }
    let name = "bad_syn_thin_fin.obj";
    let s = corpus_obj(name);
    let [cube, fin] = two_boxes(&s, 12);
    let exact = box_union_volume(cube, fin);
    assert!((exact - (1.0 + 0.64 * 9.9e-5)).abs() < 1e-12, "{exact}");
    let options = EnvelopeOptions { grade_levels: 2, ..EnvelopeOptions::new(0.2) };
    let (out, q) = mesh_and_report_with(&s, &options);
    assert_envelope_gates(name, &out, &q, exact, 1e-2);
    let thin: Vec<_> = out
        .warnings
        .iter()
        .filter_map(|w| match w {
            EnvelopeWarning::ThinFeature { min_thickness_mm, lo_mm, hi_mm, .. } => {
                Some((*min_thickness_mm, *lo_mm, *hi_mm))
            }
            _ => None,
        })
        .collect();
    assert_eq!(thin.len(), 1, "{:?}", out.warnings);
    let (t, lo, hi) = thin[0];
    assert!((t - 1e-4).abs() < 2e-5, "thinnest {t}");
    assert!(lo[0] > 0.49 && hi[0] < 0.51, "{lo:?}..{hi:?}");
}

/// Two unit boxes sharing an edge (non-manifold), raw, on the uniform lattice
/// (0.25 mm: their faces on lattice planes, exact): both boxes meshed, each
/// with its exact volume 1 (cells by centroid, within 1e-9), the union 2
/// (closed form); angles [45, 90] deg, boundary figure ~1e-16.
#[test]
fn corpus_boxes_sharing_an_edge_mesh_both_exactly() {
    if skip_without_shared_data("the mesh fixture bad_syn_nonmanifold_edge.obj") {
        return;
    }
    let name = "bad_syn_nonmanifold_edge.obj";
    let s = corpus_obj(name);
    let boxes = two_boxes(&s, 12);
    let exact = box_union_volume(boxes[0], boxes[1]);
    assert!((exact - 2.0).abs() < 1e-12, "{exact}");
    let (out, q) = mesh_and_report(&s, 0.25);
    assert_proven_bounds(&out, &q);
    assert_envelope_gates(name, &out, &q, exact, 1e-9);
    for (lo, hi) in boxes {
        let v: f64 = out
            .mesh
            .cells
            .iter()
            .map(|c| c.map(|v| out.mesh.nodes[v as usize]))
            .filter(|p| (0..3).all(|k| (lo[k]..hi[k]).contains(&((p[0][k] + p[1][k] + p[2][k] + p[3][k]) / 4.0))))
            .map(|p| fem_core::element::signed_measure(&p))
            .sum();
        assert!((v - 1.0).abs() < 1e-9, "the box {lo:?}..{hi:?}: {v}");
    }
}

/// The uniform lattice (the default) on the corpus, at coarse sizes: what it
/// alone proves, the stuffing's angle bounds (Labelle and Shewchuk) on a
/// conforming mesh of positive cells, on every file raw (no repair); the
/// issue's gates are the tests' above. The angles are those of the mesh handed
/// to the final guard (`dihedral_before_guard_deg`: the returned mesh is within
/// [12°, 155°] by construction, or refused), not the quality report's (whose
/// distances cost more than the meshes).
#[test]
fn the_uniform_lattice_keeps_the_proven_bounds_on_the_corpus() {
    if skip_without_shared_data("the defect corpus bad_syn_*.obj") {
        return;
    }
    for (name, h) in [
        ("npm_bunny.obj", 0.4),
        ("bad_syn_hole.obj", 0.4),
        ("bad_syn_flipped10pct.obj", 0.4),
        ("bad_syn_inverted.obj", 0.4),
        ("bad_syn_soup_jitter.obj", 0.4),
        ("bad_syn_degenerate_dup.obj", 0.4),
        ("bad_syn_overlapping_spheres.obj", 0.2),
        ("bad_syn_thin_fin.obj", 0.1),
    ] {
        let out = envelope_mesh(&corpus_obj(name), &EnvelopeOptions::new(h)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_conforming(&out.mesh);
        let [lo, hi] = out.stats.dihedral_before_guard_deg;
        eprintln!("{name} at {h} mm: {} cells, dihedral before the guard [{lo:.2}, {hi:.2}] deg", out.mesh.cells.len());
        assert!(lo >= 10.7 && hi <= 164.8, "{name}: dihedral [{lo}, {hi}] deg");
    }
}

// ---- determinism and refusals

/// The same input gives bit-identical output with 1 and 2 threads.
#[test]
fn output_does_not_depend_on_the_thread_count() {
    if skip_without_shared_data("the mesh fixture layered_bunny.obj") {
        return;
    }
    let s = obj("layered_bunny.obj");
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| envelope_mesh(&s, &EnvelopeOptions::new(0.35)).unwrap().mesh)
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.cells, b.cells);
    assert_eq!(a.cell_regions, b.cell_regions);
    let bits = |m: &fem_core::mesh::TetMesh| -> Vec<u64> { m.nodes.iter().flatten().map(|x| x.to_bits()).collect() };
    assert_eq!(bits(&a), bits(&b));
}

/// The graded lattice (sizing in parallel, bisection and peeling sequential) on
/// a sphere: the same mesh, bit for bit, on 1 and 2 threads, and the sphere's
/// volume and angle targets (from the cells' statistics and the volume: no
/// surface distance is asserted here).
#[test]
fn graded_output_does_not_depend_on_the_thread_count() {
    let s = icosphere(1.0, [0.1, -0.2, 0.05], 4);
    let options = EnvelopeOptions { grade_levels: 2, ..EnvelopeOptions::new(0.4) };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| envelope_mesh(&s, &options).unwrap().mesh)
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.cells, b.cells);
    let bits = |m: &fem_core::mesh::TetMesh| -> Vec<u64> { m.nodes.iter().flatten().map(|x| x.to_bits()).collect() };
    assert_eq!(bits(&a), bits(&b));
    let cells = cell_statistics(&a);
    let volume_error = a.measure() / s.signed_volume(None) - 1.0;
    eprintln!(
        "graded sphere: {} cells, dihedral [{:.2}, {:.2}], volume error {volume_error:.2e}",
        a.cells.len(),
        cells.min_dihedral_deg,
        cells.max_dihedral_deg
    );
    assert_eq!(cells.num_inverted, 0);
    assert_issue_angles(&cells);
    assert_conforming(&a);
    assert!(volume_error.abs() <= 2e-3, "{volume_error}");
}

#[test]
fn bad_input_is_a_typed_error_never_an_empty_success() {
    let cube = Surface::cuboid([0.0; 3], [1.0; 3], "box");
    assert_eq!(
        envelope_mesh(&Surface::default(), &EnvelopeOptions::new(0.1)).unwrap_err(),
        EnvelopeError::EmptySurface
    );
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(envelope_mesh(&cube, &EnvelopeOptions::new(h)), Err(EnvelopeError::BadSize { .. })), "{h}");
    }
    let mut nan = cube.clone();
    nan.vertices[3][1] = f64::NAN;
    assert!(matches!(envelope_mesh(&nan, &EnvelopeOptions::new(0.1)), Err(EnvelopeError::NonFinite { vertex: 3, .. })));
    let mut bad = cube.clone();
    bad.triangles[5][2] = 99;
    assert!(matches!(
        envelope_mesh(&bad, &EnvelopeOptions::new(0.1)),
        Err(EnvelopeError::BadIndex { triangle: 5, vertex: 99, num_vertices: 8 })
    ));
    // A single triangle encloses nothing.
    let sheet = Surface {
        vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        triangles: vec![[0, 1, 2]],
        triangle_regions: vec![0],
        region_names: vec!["sheet".into()],
    };
    let err = envelope_mesh(&sheet, &EnvelopeOptions::new(0.1)).unwrap_err();
    assert_eq!(err, EnvelopeError::NothingInside { size_mm: 0.1 });
    assert!(err.to_string().contains("encloses no volume"), "{err}");
    let mut tiny = EnvelopeOptions::new(1e-4);
    tiny.max_lattice_vertices = 1_000_000;
    let err = envelope_mesh(&cube, &tiny).unwrap_err();
    match &err {
        EnvelopeError::TooFine { suggest_mm, .. } => assert!(*suggest_mm > 0.005 && *suggest_mm < 0.05, "{err}"),
        other => panic!("{other}"),
    }
    let mut layers = EnvelopeOptions::new(0.2);
    layers.layers_mm = vec![0.5, 0.2];
    let err = envelope_mesh(&cube, &layers).unwrap_err();
    assert!(err.to_string().contains("add up to 0.7 mm but the shape is 1 mm tall"), "{err}");
}

/// The winding number on the shared bunny: 1 inside, 0 outside, fast and exact agree
/// to the far field's accuracy.
#[test]
fn winding_number_of_the_bunny() {
    let s = obj("npm_bunny.obj");
    let w = WindingNumber::new(&s);
    let (lo, hi) = s.bounding_box();
    let mut max_diff: f64 = 0.0;
    let mut n = 0;
    for i in 0..7 {
        for j in 0..7 {
            for k in 0..7 {
                let p = [
                    lo[0] + (hi[0] - lo[0]) * (i as f64 + 0.5) / 7.0,
                    lo[1] + (hi[1] - lo[1]) * (j as f64 + 0.5) / 7.0,
                    lo[2] + (hi[2] - lo[2]) * (k as f64 + 0.5) / 7.0,
                ];
                let fast = w.at(p);
                let exact: f64 = s
                    .triangles
                    .iter()
                    .map(|t| {
                        let [a, b, c] = t.map(|v| {
                            let q = s.vertices[v as usize];
                            [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
                        });
                        let l = |u: [f64; 3]| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
                        let d = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
                        let cross = [b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]];
                        let num = d(a, cross);
                        let den = l(a) * l(b) * l(c) + d(a, b) * l(c) + d(b, c) * l(a) + d(c, a) * l(b);
                        num.atan2(den) / (2.0 * std::f64::consts::PI)
                    })
                    .sum();
                max_diff = max_diff.max((fast - exact).abs());
                assert!(exact.abs() < 1e-9 || (exact - 1.0).abs() < 1e-9, "{exact} at {p:?}");
                n += usize::from(exact > 0.5);
            }
        }
    }
    assert!(n > 20, "{n} points inside");
    // The far field (beta = 2, second order) is within a few hundredths of the
    // exact sum; the inside test needs far less near 0 and 1.
    assert!(max_diff < 0.08, "fast vs exact: {max_diff}");
}
