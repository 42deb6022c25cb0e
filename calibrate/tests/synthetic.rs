//! Identification on synthetic trials (issue: parameter identification,
//! "Verification"): data made by the engine from the seed's Table II parameters on
//! a finer mesh and with a tighter step tolerance than the fit uses (no inverse
//! crime), then fitted by the seed's procedure. A 3D frictionless block with
//! markers on its front face (symmetric frictionless specimens):
//! its markers expand about the block's centre, as a real specimen's do, and
//! the fit recovers nu from them.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use calibrate::procedure::{run, Procedure, ProcedureOptions};
use calibrate::rng::SplitMix64;
use calibrate::trial::Campaign;
use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Attachment, MarkerRequest, PlanePress, Protocol, Settings, SolidPress};
use wagashi_io::read_bundle;

const END_S: f64 = 400.0;
const RELEASE_S: f64 = 210.93;

/// Writes a 2D bundle of the seed's material 1 trial whose data come from a run on
/// a `data_size_mm` mesh with `rtol` 1e-5, with relative force noise `force_noise`
/// (of the peak) and marker noise `marker_noise_mm`. The material gives only its model.
fn synthetic_bundle(dir: &Path, glued: bool, data_size_mm: f64, force_noise: f64, marker_noise_mm: f64, seed: u64) {
    let attachment = if glued { Attachment::Glued } else { Attachment::Frictionless };
    let protocol = Protocol {
        plate: attachment,
        support: attachment,
        ..Protocol::ramp_hold_release(0.2, 28.87, RELEASE_S, END_S)
    };
    let contact = if glued { "glued" } else { "frictionless" };
    let mesh = mesh::rectangle(58.0, 59.5, data_size_mm, "mat1").unwrap();
    let mut p = PlanePress::new_2d(mesh, 12.0, vec![Material::seed_mat1_force()], protocol).unwrap();
    // Markers on the free side and the top, as a camera sees them.
    let positions = [[58.0, 14.875], [58.0, 29.75], [58.0, 44.625], [0.0, 29.75], [29.0, 59.5], [14.5, 59.5]];
    let times = vec![0.0, 150.0, RELEASE_S, 300.0, END_S];
    p.markers = positions
        .iter()
        .enumerate()
        .map(|(i, q)| MarkerRequest { name: format!("m{i}"), position: q.to_vec(), times: times.clone() })
        .collect();
    let settings = Settings { rtol: 1e-5, ..Settings::default() };
    let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
    let mut noise = SplitMix64::new(seed);
    let peak = r.peak_force();
    let mut force = String::from("t_s,force_N\n");
    for i in 0..=800 {
        let t = END_S * i as f64 / 800.0;
        let f = r.bottom_force_at(t) + if t > 0.0 { force_noise * peak * noise.next_gaussian() } else { 0.0 };
        writeln!(force, "{t},{f}").unwrap();
    }
    let mut markers = String::from("marker,t_s,x_mm,y_mm\n");
    for track in &r.markers {
        for (t, pos) in &track.samples {
            let mut jitter = |v: f64| if *t > 0.0 { v + marker_noise_mm * noise.next_gaussian() } else { v };
            let (x, y) = (jitter(pos[0]), jitter(pos[1]));
            writeln!(markers, "{},{t},{x},{y}", track.name).unwrap();
        }
    }
    let toml = format!(
        r#"format = "wagashi-experiment/1"
name = "synthetic-mat1"
dimension = 2

[specimen]
shape = "block"
size_mm = [58.0, 59.5, 12.0]
material = "mat1"

[materials.mat1]
model = "five-element"

[protocol]
tool = "plate"
tool_contact = "{contact}"
support = "{contact}"
waypoints = [[0.0, 0.0], [28.87, 5.774], [{RELEASE_S}, 5.774]]
release_s = {RELEASE_S}
end_s = {END_S}

[data]
force = "force.csv"
markers = "markers.csv"
"#
    );
    std::fs::write(dir.join("experiment.toml"), toml).unwrap();
    std::fs::write(dir.join("force.csv"), force).unwrap();
    std::fs::write(dir.join("markers.csv"), markers).unwrap();
}

/// Table II, material 1: nu, E1, E2, c1, c2, c3 (force set).
const TRUTH: [(&str, f64); 6] = [
    ("mat1.poisson", 0.3746),
    ("mat1.E1_MPa", 0.0349),
    ("mat1.E2_MPa", 0.0221),
    ("mat1.c1_MPa_s", 0.0071),
    ("mat1.c2_MPa_s", 0.1869),
    ("mat1.c3_MPa_s", 29.719),
];

fn fit(dir: &Path, starts: usize) -> calibrate::procedure::FitReport {
    let bundle = read_bundle(dir).unwrap();
    // The fit's mesh: twice as coarse as the data's.
    let campaign = Campaign::new(&[bundle], &BTreeMap::new(), Some(6.0), false).unwrap();
    let options = ProcedureOptions { starts, ..ProcedureOptions::default() };
    run(&campaign, Procedure::Seed, &options, &|_, _, _| {}).unwrap()
}

/// Noise-free data on frictionless plates: the force set recovers Table II within
/// 1e-3. The data come from a mesh twice as fine and steps 100x tighter; the
/// deformation is homogeneous, so both meshes represent it exactly and what is left
/// is the time discretization and the optimizer. (With glued plates the corner
/// singularities make the two meshes' observables differ by about 2 % in the
/// bulge, and nu moves by as much: measured, see the noisy test and VALIDATION.md.)
#[test]
fn noise_free_recovery() {
    let dir = tempfile::tempdir().unwrap();
    synthetic_bundle(dir.path(), false, 3.0, 0.0, 0.0, 7);
    let report = fit(dir.path(), 4);
    let force = &report.sets.iter().find(|s| s.0 == "force").unwrap().1;
    for (label, truth) in TRUTH {
        let e = force.iter().find(|e| e.label == label).unwrap();
        let rel = (e.value - truth).abs() / truth;
        println!("{label}: {:.6e} (truth {truth:.6e}), rel {rel:.2e}, ci95 {:?}", e.value, e.ci95);
    }
    for (label, truth) in TRUTH {
        let e = force.iter().find(|e| e.label == label).unwrap();
        let rel = (e.value - truth).abs() / truth;
        assert!(rel < 1e-3, "{label}: {} vs {truth} (relative error {rel:.2e})", e.value);
    }
}

/// Glued plates (the seed's trial), data on a 3 mm mesh, fit on 6 mm, 1 % force
/// noise and 0.05 mm marker noise: the truth lies inside the 95 % intervals.
#[test]
fn noisy_recovery_lies_inside_intervals() {
    let dir = tempfile::tempdir().unwrap();
    synthetic_bundle(dir.path(), true, 3.0, 0.01, 0.05, 11);
    let report = fit(dir.path(), 4);
    let force = &report.sets.iter().find(|s| s.0 == "force").unwrap().1;
    for (label, truth) in TRUTH {
        let e = force.iter().find(|e| e.label == label).unwrap();
        println!("{label}: {:.5e} in {:?} (truth {truth:.5e})", e.value, e.ci95);
    }
    for s in &report.steps {
        println!("{}: rms {:.3}, warnings {:?}", s.name, s.rms, s.warnings);
    }
    for (label, truth) in TRUTH {
        let e = force.iter().find(|e| e.label == label).unwrap();
        let [lo, hi] = e.ci95.unwrap();
        assert!(lo <= truth && truth <= hi, "{label}: truth {truth} outside [{lo}, {hi}] (fitted {})", e.value);
    }
}

/// A 50 x 50 x 11 mm frictionless block (W, H, T), its front face z = T.
const BLOCK: [f64; 3] = [50.0, 50.0, 11.0];
/// Its trial: 5 mm at 0.2 mm/s, held to 120 s, released, recovering to 240 s.
const BLOCK_PUSH_S: f64 = 25.0;
const BLOCK_RELEASE_S: f64 = 120.0;
const BLOCK_END_S: f64 = 240.0;
/// The truth: Table II's material 1 with the Poisson ratio of the frictionless trial.
const BLOCK_POISSON: f64 = 0.335;

/// Writes the 3D bundle of the frictionless block with a 5 x 5 grid of markers on
/// its front face, its data from a run on a `data_size_mm` mesh with `rtol` 1e-5,
/// relative force noise `force_noise` (of the peak) and marker noise
/// `marker_noise_mm`. Checks on the way that the simulated markers are the
/// homogeneous field about the block's centre (a real specimen's frame).
fn frictionless_block_bundle(dir: &Path, data_size_mm: f64, force_noise: f64, marker_noise_mm: f64, seed: u64) {
    let [w, h, t] = BLOCK;
    let protocol = Protocol {
        plate: Attachment::Frictionless,
        support: Attachment::Frictionless,
        ..Protocol::ramp_hold_release(0.2, BLOCK_PUSH_S, BLOCK_RELEASE_S, BLOCK_END_S)
    };
    let mesh = mesh::block(BLOCK, data_size_mm, "mat1").unwrap();
    let mut material = Material::seed_mat1_force();
    material.poisson = BLOCK_POISSON;
    let mut p = SolidPress::new_3d(mesh, vec![material], protocol).unwrap();
    let times = vec![0.0, 30.0, 60.0, 90.0, BLOCK_RELEASE_S, 150.0, 180.0, BLOCK_END_S];
    let grid = [0.05, 0.275, 0.5, 0.725, 0.95];
    p.markers = grid
        .iter()
        .flat_map(|&fx| grid.iter().map(move |&fy| [fx * w, fy * h, t]))
        .enumerate()
        .map(|(i, q)| MarkerRequest { name: format!("m{i}"), position: q.to_vec(), times: times.clone() })
        .collect();
    let settings = Settings { rtol: 1e-5, ..Settings::default() };
    let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
    // The hold: the axial strain is -5 mm / H and the markers stretch about the
    // centre (W/2, T/2) by -nu e, to round-off.
    let e = -0.2 * BLOCK_PUSH_S / h;
    for (track, request) in r.markers.iter().zip(&p.markers) {
        let (time, position) = &track.samples[4];
        assert_eq!(*time, BLOCK_RELEASE_S);
        let q = &request.position;
        let want = [-BLOCK_POISSON * e * (q[0] - w / 2.0), e * q[1], -BLOCK_POISSON * e * (q[2] - t / 2.0)];
        for k in 0..3 {
            let error = (position[k] - q[k] - want[k]).abs();
            assert!(error < 1e-9, "{} axis {k}: {error:e} mm off the homogeneous field about the centre", track.name);
        }
    }
    let mut noise = SplitMix64::new(seed);
    let peak = r.peak_force();
    let mut force = String::from("t_s,force_N\n");
    for i in 0..=480 {
        let time = BLOCK_END_S * i as f64 / 480.0;
        let f = r.bottom_force_at(time) + if time > 0.0 { force_noise * peak * noise.next_gaussian() } else { 0.0 };
        writeln!(force, "{time},{f}").unwrap();
    }
    let mut markers = String::from("marker,t_s,x_mm,y_mm,z_mm\n");
    for track in &r.markers {
        for (time, pos) in &track.samples {
            let mut jitter = |v: f64| if *time > 0.0 { v + marker_noise_mm * noise.next_gaussian() } else { v };
            let (x, y, z) = (jitter(pos[0]), jitter(pos[1]), jitter(pos[2]));
            writeln!(markers, "{},{time},{x},{y},{z}", track.name).unwrap();
        }
    }
    let toml = format!(
        r#"format = "wagashi-experiment/1"
name = "frictionless-block"
dimension = 3

[specimen]
shape = "block"
size_mm = [{w}, {h}, {t}]
material = "mat1"

[materials.mat1]
model = "five-element"

[protocol]
tool = "plate"
tool_contact = "frictionless"
support = "frictionless"
waypoints = [[0.0, 0.0], [{BLOCK_PUSH_S}, 5.0], [{BLOCK_RELEASE_S}, 5.0]]
release_s = {BLOCK_RELEASE_S}
end_s = {BLOCK_END_S}

[data]
force = "force.csv"
markers = "markers.csv"
"#
    );
    std::fs::write(dir.join("experiment.toml"), toml).unwrap();
    std::fs::write(dir.join("force.csv"), force).unwrap();
    std::fs::write(dir.join("markers.csv"), markers).unwrap();
}

/// A noisy frictionless 3D trial with front-face markers (1 % force noise, 0.05 mm
/// marker noise, data on a 5 mm mesh, fit on 12.5 mm): the seed procedure
/// recovers nu within 3 %. (With the specimen pinned at a corner, so that it
/// expanded away from it, the fit of markers about the centre gave nu = 0.063
/// against 0.335.)
#[test]
fn frictionless_block_recovers_poisson_from_front_face_markers() {
    let dir = tempfile::tempdir().unwrap();
    frictionless_block_bundle(dir.path(), 5.0, 0.01, 0.05, 26);
    let bundle = read_bundle(dir.path()).unwrap();
    let campaign = Campaign::new(&[bundle], &BTreeMap::new(), Some(12.5), false).unwrap();
    let options = ProcedureOptions { starts: 4, ..ProcedureOptions::default() };
    let report = run(&campaign, Procedure::Seed, &options, &|_, _, _| {}).unwrap();
    let force = &report.sets.iter().find(|s| s.0 == "force").unwrap().1;
    let nu = force.iter().find(|e| e.label == "mat1.poisson").unwrap();
    let rel = (nu.value - BLOCK_POISSON).abs() / BLOCK_POISSON;
    for e in force {
        println!("{}: {:.5e} in {:?}", e.label, e.value, e.ci95);
    }
    println!("nu {:.5} (truth {BLOCK_POISSON}), relative error {rel:.2e}; {:.1} s", nu.value, report.wall_s);
    assert!(rel < 0.03, "nu {} vs {BLOCK_POISSON}: relative error {rel:.3e}", nu.value);
}
