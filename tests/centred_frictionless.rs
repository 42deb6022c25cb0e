//! A specimen between frictionless plates expands about its centre
//! (`fem_core::press`'s model module, "Free bodies"): the markers, the keep shape and the final shape of a homogeneous
//! frictionless trial are the closed form's lateral stretch about the
//! specimen's centre, `u_x = -nu e (x - x_c)`, `u_y = e y`, `u_z = -nu e (z - z_c)`
//! with `e` the axial strain, in 2D and 3D, on structured meshes and on
//! unstructured ones (a perturbed rectangle, a tetrahedralized box surface), with
//! the constrained plate and with contact tools (a frictionless plate that
//! leaves and touches again; a frictionless plate and floor).
//!
//! Tolerances: the homogeneous field is exact on any mesh (P1 reproduces it, and
//! the centred hold is exact for it), so the shapes match their pattern to
//! round-off: [`TOLERANCE`] of the plate's travel. Until release the axial
//! strain is the prescribed `-d(t)/H`, so markers and the keep shape match the
//! closed form to the same tolerance; after release the run's strain follows
//! the closed-form recovery (`fem_core::analytic::uniaxial_recovery_strain`) to
//! the time scheme's accuracy ([`RECOVERY_TOLERANCE`] of the height, as
//! `tests/homogeneous_compression.rs` measures), and the shape about the centre
//! follows the run's own strain to [`TOLERANCE`].

use fem_core::analytic::uniaxial_recovery_strain;
use fem_core::material::Material;
use fem_core::mesh::{self, TetMesh, TriMesh};
use fem_core::press::{
    self, AnyPress, Attachment, MarkerRequest, PlanePress, PressResult, Protocol, Settings, SolidPress, Tool,
    ToolContact,
};
use meshing::conforming::{conforming_mesh, ConformingOptions};
use meshing::Surface;

const W: f64 = 58.0;
const H: f64 = 59.5;
const T: f64 = 12.0;
const PUSH_S: f64 = 28.87;
const RELEASE_S: f64 = 210.93;
const END_S: f64 = 400.0;
/// The plate's travel [mm].
const TRAVEL: f64 = 0.2 * PUSH_S;
/// Round-off of the homogeneous field, relative to the plate's travel.
const TOLERANCE: f64 = 1e-9;
/// The recovery's time discretization at the default tolerances: the height
/// after release within 1e-4 of itself (`tests/homogeneous_compression.rs`).
const RECOVERY_TOLERANCE: f64 = 1e-4;

fn material() -> Material {
    Material::seed_mat1_force()
}

fn protocol() -> Protocol {
    let mut p = Protocol::ramp_hold_release(0.2, PUSH_S, RELEASE_S, END_S);
    p.plate = Attachment::Frictionless;
    p.support = Attachment::Frictionless;
    p
}

/// The closed-form axial strain `e(t)` (negative in compression) of the trial.
fn closed_form_strain(t: f64) -> f64 {
    let p = protocol();
    if t <= RELEASE_S {
        -p.displacement(t) / H
    } else {
        let history: Vec<[f64; 2]> = p.waypoints.iter().map(|w| [w[0], w[1] / H]).collect();
        -uniaxial_recovery_strain(&material().rheology, &history, RELEASE_S, t)
    }
}

/// The homogeneous uniaxial-stress displacement at the initial position `p` for
/// the axial strain `e`: lateral stretch about the centre `(W/2, T/2)`, the bottom
/// on y = 0.
fn homogeneous(p: &[f64], e: f64) -> Vec<f64> {
    let nu = material().poisson;
    let centre = [W / 2.0, 0.0, T / 2.0];
    (0..p.len()).map(|k| if k == 1 { e * p[1] } else { -nu * e * (p[k] - centre[k]) }).collect()
}

/// Markers on the front face (z = T in 3D), the sides, the top, inside and off
/// every symmetry plane, reported at 0, in the push, at release and in the recovery.
fn markers(dim: usize) -> Vec<MarkerRequest> {
    let points: [[f64; 3]; 7] = [
        [0.0, 29.75, T],
        [W, 14.875, T],
        [W / 2.0, H, T],
        [14.5, H, T],
        [41.3, 7.1, T],
        [5.2, 50.3, T],
        [37.1, 22.4, 3.3],
    ];
    let times = vec![0.0, 10.0, PUSH_S, 150.0, RELEASE_S, 260.0, END_S];
    points
        .iter()
        .enumerate()
        .filter(|(i, _)| dim == 3 || *i < 6)
        .map(|(i, q)| MarkerRequest { name: format!("m{i}"), position: q[..dim].to_vec(), times: times.clone() })
        .collect()
}

/// Nodes moved off the grid, each along the faces it lies on (corners stay), by up
/// to 15 % of the spacing `h`: an unstructured mesh of the same rectangle.
fn perturbed_rectangle(h: f64) -> TriMesh {
    let mut m = mesh::rectangle(W, H, h, "m").unwrap();
    let size = [W, H];
    for (i, p) in m.nodes.iter_mut().enumerate() {
        for (k, x) in p.iter_mut().enumerate() {
            if *x > 1e-9 && *x < size[k] - 1e-9 {
                *x += 0.15 * h * ((7 * i + 3 * k) as f64 * 1.618).sin();
            }
        }
    }
    m.validate().unwrap();
    m
}

/// The box tetrahedralized from its surface by the conforming mesher, with the
/// node sets `bottom` (y = 0) and `top` (y = H).
fn meshed_box(h: f64) -> TetMesh {
    let surface = Surface::cuboid([0.0; 3], [W, H, T], "m");
    let mut m = conforming_mesh(&surface, &ConformingOptions::new(h)).unwrap().mesh;
    let boundary = m.node_sets["boundary"].clone();
    let at = |y: f64| boundary.iter().copied().filter(|&i| (m.nodes[i as usize][1] - y).abs() < 1e-9).collect();
    let (bottom, top): (Vec<u32>, Vec<u32>) = (at(0.0), at(H));
    m.node_sets.insert("bottom".into(), bottom);
    m.node_sets.insert("top".into(), top);
    m
}

/// A frictionless plate tool that pushes, leaves the specimen, and pushes again.
fn double_compression(lo: [f64; 3], hi: [f64; 3]) -> Tool {
    let strokes = [[0.0, 0.0], [PUSH_S, TRAVEL], [40.0, -0.5], [150.0, -0.5], [170.0, 4.0], [RELEASE_S, 4.0]];
    Tool::plate_above("plate", lo, hi, &strokes, ToolContact::Frictionless, RELEASE_S)
}

/// How the run's strain compares with the closed form.
#[derive(Clone, Copy)]
enum Expect {
    /// The trial's: exact until release, the recovery's accuracy after.
    ClosedForm,
    /// A plate that leaves and touches again: the first push only.
    FirstPush,
    /// A plate that never lets go: `-d(t)/H` throughout, exact.
    Held,
}

/// Checks a run's markers and kept shapes against the homogeneous field about
/// the centre; returns the largest deviation from the pattern [mm].
fn check(name: &str, p: &AnyPress, expect: Expect) -> f64 {
    let r: PressResult = press::simulate_any(p, &Settings::default(), &mut |_| {}).unwrap();
    let (nodes, top, dim): (Vec<Vec<f64>>, Vec<u32>, usize) = match p {
        AnyPress::Plane(q) => (q.mesh.nodes.iter().map(|x| x.to_vec()).collect(), q.mesh.node_sets["top"].clone(), 2),
        AnyPress::Solid(q) => (q.mesh.nodes.iter().map(|x| x.to_vec()).collect(), q.mesh.node_sets["top"].clone(), 3),
        AnyPress::Axisymmetric(_) => unreachable!(),
    };
    let strain_peak = TRAVEL / H;
    let mut worst_shape: f64 = 0.0;
    let mut worst_strain: f64 = 0.0;
    let mut compare_strain = |t: f64, e: f64| {
        let want = match expect {
            Expect::ClosedForm => closed_form_strain(t),
            Expect::FirstPush if t <= PUSH_S => closed_form_strain(t),
            Expect::FirstPush => return,
            Expect::Held => -protocol().displacement(t) / H,
        };
        let released = t > RELEASE_S && matches!(expect, Expect::ClosedForm);
        let tolerance = if released { RECOVERY_TOLERANCE } else { TOLERANCE * strain_peak };
        let error = (e - want).abs();
        assert!(error <= tolerance, "{name} t = {t}: strain {e:e} vs the closed form's {want:e}");
        worst_strain = worst_strain.max(error / strain_peak);
    };

    // Markers: the strain from the top-centre marker (y0 = H), every marker on the pattern.
    let requests = markers(dim);
    let reference = r.markers.iter().position(|m| m.name == "m2").unwrap();
    for (i, sample) in r.markers[reference].samples.iter().enumerate() {
        let t = sample.0;
        let e = (sample.1[1] - H) / H;
        compare_strain(t, e);
        for (track, request) in r.markers.iter().zip(&requests) {
            let (tm, position) = &track.samples[i];
            assert_eq!(*tm, t);
            let want = homogeneous(&request.position, e);
            for k in 0..dim {
                let error = (position[k] - request.position[k] - want[k]).abs();
                worst_shape = worst_shape.max(error);
                assert!(
                    error <= TOLERANCE * TRAVEL,
                    "{name} marker {} t = {t}: axis {k} off the pattern by {error:e} mm",
                    track.name
                );
            }
        }
    }

    // The keep and final shapes: every node, the strain from the top's mean.
    for t in [RELEASE_S, END_S] {
        let snap = r.snapshot_at(t).unwrap();
        let u = &snap.displacement;
        let e = top.iter().map(|&i| u[i as usize * dim + 1]).sum::<f64>() / top.len() as f64 / H;
        compare_strain(t, e);
        for (i, x) in nodes.iter().enumerate() {
            let want = homogeneous(x, e);
            for k in 0..dim {
                let error = (u[i * dim + k] - want[k]).abs();
                worst_shape = worst_shape.max(error);
                assert!(error <= TOLERANCE * TRAVEL, "{name} t = {t}: node {i} axis {k} off by {error:e} mm");
            }
        }
    }
    eprintln!(
        "{name}: {} nodes, shapes off the pattern by {worst_shape:.2e} mm, strain off the closed form by \
         {worst_strain:.2e} of the largest",
        nodes.len()
    );
    worst_shape
}

fn plane(mesh: TriMesh) -> PlanePress {
    let mut p = PlanePress::new_2d(mesh, T, vec![material()], protocol()).unwrap();
    p.markers = markers(2);
    p
}

fn solid(mesh: TetMesh) -> SolidPress {
    let mut p = SolidPress::new_3d(mesh, vec![material()], protocol()).unwrap();
    p.markers = markers(3);
    p
}

#[test]
fn plane_specimens_expand_about_their_centre() {
    check("2D structured", &AnyPress::Plane(plane(mesh::rectangle(W, H, 10.0, "m").unwrap())), Expect::ClosedForm);
    check("2D perturbed", &AnyPress::Plane(plane(perturbed_rectangle(6.0))), Expect::ClosedForm);
}

#[test]
fn solid_specimens_expand_about_their_centre() {
    check("3D structured", &AnyPress::Solid(solid(mesh::block([W, H, T], 10.0, "m").unwrap())), Expect::ClosedForm);
    let meshed = meshed_box(12.0);
    assert!(meshed.nodes.len() > 50);
    check("3D meshed surface", &AnyPress::Solid(solid(meshed)), Expect::ClosedForm);
}

/// The contact-tool path: a frictionless plate that leaves and touches again
/// (the support held by constraints), and a frictionless plate and floor (the
/// bottom held by the floor tool only; the plate stays, since nothing would
/// hold the specimen in y once it let go).
#[test]
fn specimens_under_frictionless_tools_expand_about_their_centre() {
    let mut p = plane(perturbed_rectangle(6.0));
    let (lo, hi) = p.mesh.bounding_box();
    p.tools = vec![double_compression([lo[0], lo[1], 0.0], [hi[0], hi[1], 0.0])];
    check("2D perturbed, double compression", &AnyPress::Plane(p), Expect::FirstPush);

    let mut p = solid(meshed_box(12.0));
    let (lo, hi) = p.mesh.bounding_box();
    p.tools = vec![double_compression(lo, hi)];
    check("3D meshed surface, double compression", &AnyPress::Solid(p), Expect::FirstPush);

    let mut p = solid(mesh::block([W, H, T], 10.0, "m").unwrap());
    p.protocol.support = Attachment::Free;
    let (lo, hi) = p.mesh.bounding_box();
    p.tools = vec![
        Tool::plate_above("plate", lo, hi, &protocol().waypoints, ToolContact::Frictionless, f64::INFINITY),
        Tool::floor_below("floor", lo, hi, ToolContact::Frictionless),
    ];
    check("3D structured, plate and floor tools", &AnyPress::Solid(p), Expect::Held);
}
