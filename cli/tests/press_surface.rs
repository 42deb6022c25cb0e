//! `wagashi press` on a `shape = "surface"` specimen, end to end: the real
//! binary meshes the closed surface on the fly (conforming mode by default) and
//! presses it with a plate; a defective surface is refused naming the defect and
//! suggesting envelope mode, which then meshes it. The Stanford bunny (the
//! repository's copy in `tests/fixtures`) becomes a press problem at a coarse size.

mod common;

use std::path::{Path, PathBuf};

use common::*;
use fem_core::press::AnyPress;
use serde_json::Value;

/// A W x H x T box with one corner at the origin, faces outward, as OBJ text;
/// `drop_last`: leave out the last triangle (an open surface).
fn box_obj(size: [f64; 3], drop_last: bool) -> String {
    let mut obj = String::from("o gel\n");
    for i in 0..8 {
        let c = [i & 1, (i >> 1) & 1, (i >> 2) & 1];
        obj += &format!("v {} {} {}\n", c[0] as f64 * size[0], c[1] as f64 * size[1], c[2] as f64 * size[2]);
    }
    // Vertex 1 + x + 2y + 4z; each quad counter-clockwise seen from outside.
    let quads = [[1, 5, 7, 3], [2, 4, 8, 6], [1, 2, 6, 5], [3, 7, 8, 4], [1, 3, 4, 2], [5, 6, 8, 7]];
    let mut tris: Vec<[usize; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    if drop_last {
        tris.pop();
    }
    for t in tris {
        obj += &format!("f {} {} {}\n", t[0], t[1], t[2]);
    }
    obj
}

/// An elastic specimen pressed `push_mm` in 5 s by a frictionless plate, glued below.
fn experiment(surface: &str, push_mm: f64) -> String {
    format!(
        r#"format = "wagashi-experiment/1"
name = "shape"
dimension = 3

[specimen]
shape = "surface"
surface = "{surface}"

[specimen.regions]
gel = "gel"

[materials.gel]
model = "elastic"
poisson = 0.3
E_MPa = 0.05

[protocol]
tool = "plate"
tool_contact = "frictionless"
support = "glued"
waypoints = [[0.0, 0.0], [5.0, {push_mm}]]
release_s = 5.0
end_s = 5.0
"#
    )
}

/// A bundle folder `tmp/bundle` holding `name` (the surface) and experiment.toml.
fn bundle(tmp: &Path, name: &str, surface: &[u8], toml: &str) -> PathBuf {
    let dir = tmp.join("bundle");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(name), surface).unwrap();
    std::fs::write(dir.join("experiment.toml"), toml).unwrap();
    dir
}

fn summary(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The plate's `force_y_N` column of `tools.csv` (every value finite).
fn plate_forces(out: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(out.join("tools.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_s,tool,force_x_N,force_y_N,force_z_N,normal_N,tangential_N,area_mm2"));
    lines
        .filter(|l| l.split(',').nth(1) == Some("plate"))
        .map(|l| {
            let cells: Vec<f64> =
                l.split(',').enumerate().filter(|(i, _)| *i != 1).map(|(_, c)| c.parse::<f64>().unwrap()).collect();
            assert!(cells.iter().all(|c| c.is_finite()), "{l}");
            cells[2]
        })
        .collect()
}

/// The mesh `press` simulated, built again in process (meshing is deterministic),
/// and its volume [mm^3] (sum of the tets' signed volumes).
fn meshed_volume(dir: &Path, size_mm: f64, summary: &Value) -> f64 {
    let b = wagashi_io::read_bundle(dir).unwrap();
    let AnyPress::Solid(p) = b.to_press(size_mm).unwrap() else { panic!("a surface specimen is solid") };
    assert_eq!(summary["cells"].as_u64(), Some(p.mesh.cells.len() as u64));
    assert_eq!(summary["nodes"].as_u64(), Some(p.mesh.nodes.len() as u64));
    p.mesh
        .cells
        .iter()
        .map(|c| {
            let q = c.map(|v| p.mesh.nodes[v as usize]);
            let d = |i: usize| [0, 1, 2].map(|k| q[i][k] - q[0][k]);
            let (a, b, c) = (d(1), d(2), d(3));
            let v = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0;
            assert!(v > 0.0, "an inverted tet");
            v
        })
        .sum()
}

/// A 10 mm cube pressed 0.5 mm (strain 0.05) by a frictionless plate, glued on
/// the floor: conforming mode, the exact volume, and a plate force between the
/// uniaxial bound E A e (frictionless on both faces) and the confined one
/// E (1 - nu) / ((1 + nu)(1 - 2 nu)) A e (no lateral strain anywhere).
#[test]
fn a_cube_surface_is_meshed_on_the_fly_and_pressed() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = bundle(tmp.path(), "cube.obj", box_obj([10.0; 3], false).as_bytes(), &experiment("cube.obj", 0.5));
    let out = tmp.path().join("out");
    let o = wagashi_in(tmp.path(), ["press", "bundle", "-o", "out", "--size-mm", "5", "--dt", "1"]);
    assert_success(&o);
    assert!(stdout(&o).contains("surface meshed in conforming mode"), "{}", stdout(&o));
    let s = summary(&out);
    assert_eq!(s["surface_mesh_mode"], "conforming");
    let volume = meshed_volume(&dir, 5.0, &s);
    assert!((volume - 1000.0).abs() <= 1e-9 * 1000.0, "{volume}");
    let forces = plate_forces(&out);
    assert!(forces.len() >= 6, "{forces:?}");
    let (e, nu, area, strain) = (0.05, 0.3, 100.0, 0.05);
    let uniaxial = e * area * strain;
    let confined = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)) * area * strain;
    let end = *forces.last().unwrap();
    assert!(end >= uniaxial && end <= confined, "{end} N not in [{uniaxial}, {confined}]");
    // The output reads back as a bundle: its experiment.toml names its own copy of the surface.
    let written = std::fs::read_to_string(out.join("experiment.toml")).unwrap();
    assert!(written.contains("surface = \"specimen/cube.obj\""), "{written}");
    assert_eq!(std::fs::read(out.join("specimen/cube.obj")).unwrap(), std::fs::read(dir.join("cube.obj")).unwrap());
}

/// An open surface is refused in conforming mode, in one line naming the key,
/// the file, the defect and envelope mode, writing nothing; envelope mode meshes it.
#[test]
fn a_defective_surface_is_refused_and_envelope_mode_meshes_it() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = bundle(tmp.path(), "open.obj", box_obj([10.0; 3], true).as_bytes(), &experiment("open.obj", 0.5));
    let o = wagashi_in(tmp.path(), ["press", "bundle", "-o", "out", "--size-mm", "5"]);
    let line = assert_one_line_error(&o);
    for part in ["experiment.toml:7: specimen.surface", "open.obj", "conforming", "open", "--mesh-mode envelope"] {
        assert!(line.contains(part), "`{part}` missing: {line}");
    }
    assert!(!tmp.path().join("out").exists());
    let before = std::fs::read(dir.join("open.obj")).unwrap();
    let o = wagashi_in(
        tmp.path(),
        ["press", "bundle", "-o", "out", "--size-mm", "2.5", "--dt", "1", "--mesh-mode", "envelope"],
    );
    assert_success(&o);
    assert!(stdout(&o).contains("surface meshed in envelope mode"), "{}", stdout(&o));
    assert_eq!(summary(&tmp.path().join("out"))["surface_mesh_mode"], "envelope");
    assert!(plate_forces(&tmp.path().join("out")).last().is_some_and(|f| *f > 0.0));
    assert_eq!(std::fs::read(dir.join("open.obj")).unwrap(), before, "the input was modified");
}

/// The Stanford bunny (`tests/fixtures`) at 1.5 mm becomes a press problem (meshed in
/// conforming mode) whose mesh volume is the surface's within 1e-9, standing on
/// the floor by nodes at its lowest y, with the plate as a contact tool. (Not
/// simulated here: the plate first touches an ear tip, and the contact steps
/// take a minute; the cube above runs the binary end to end.)
#[test]
fn the_bunny_becomes_a_press_problem_at_a_coarse_size() {
    let path = fixture("npm_bunny.obj");
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let tmp = tempfile::tempdir().unwrap();
    let toml = experiment("bunny.obj", 0.3).replace("[specimen.regions]\ngel = \"gel\"", "material = \"gel\"");
    assert!(toml.contains("material = \"gel\"\n"));
    let dir = bundle(tmp.path(), "bunny.obj", &bytes, &toml);
    let b = wagashi_io::read_bundle(&dir).unwrap();
    let AnyPress::Solid(p) = b.to_press(1.5).unwrap() else { panic!("a surface specimen is solid") };
    let s = serde_json::json!({"cells": p.mesh.cells.len(), "nodes": p.mesh.nodes.len()});
    let surface = wagashi_io::surface::read_surface(&path, &Default::default()).unwrap().surface;
    let reference = surface.signed_volume(None).abs();
    let volume = meshed_volume(&dir, 1.5, &s);
    assert!((volume - reference).abs() <= 1e-9 * reference, "{volume} vs {reference}");
    let (lo, hi) = surface.bounding_box();
    let bottom = &p.mesh.node_sets["bottom"];
    assert!(bottom.len() >= 3);
    assert!(bottom.iter().all(|&i| p.mesh.nodes[i as usize][1] <= lo[1] + 1e-3 * (hi[1] - lo[1])));
    assert_eq!(p.tools.len(), 1);
    assert_eq!(p.tools[0].name, "plate");
}

/// The 10 mm cube of the test above, meshed by `wagashi mesh --mode conforming`
/// into a Gmsh `.msh` and pressed through `shape = "mesh"`: the same mesh as the
/// surface meshed on the fly at the same size, so the same plate force (to the
/// solver's tolerance), within the bounds above; the output names its own copy
/// of the mesh. A TetGen or `.vtu` mesh of the same cube gives the same force.
#[test]
fn a_mesh_made_by_wagashi_mesh_is_pressed_through_shape_mesh() {
    let tmp = tempfile::tempdir().unwrap();
    let cube = box_obj([10.0; 3], false);
    let surface_dir = bundle(tmp.path(), "cube.obj", cube.as_bytes(), &experiment("cube.obj", 0.5));
    let o = wagashi_in(tmp.path(), ["press", "bundle", "-o", "surface-out", "--size-mm", "5", "--dt", "1"]);
    assert_success(&o);
    let by_surface = *plate_forces(&tmp.path().join("surface-out")).last().unwrap();
    for (file, out) in [("cube.msh", "mesh-out"), ("cube.node", "tetgen-out"), ("cube.vtu", "vtu-out")] {
        let target = format!("bundle/{file}");
        let o = wagashi_in(
            tmp.path(),
            ["mesh", "bundle/cube.obj", "-o", &target, "--size-mm", "5", "--mode", "conforming"],
        );
        assert_success(&o);
        let toml = experiment("cube.obj", 0.5)
            .replace("shape = \"surface\"\nsurface = \"cube.obj\"", &format!("shape = \"mesh\"\nmesh = \"{file}\""));
        std::fs::write(surface_dir.join("experiment.toml"), &toml).unwrap();
        let before = std::fs::read(surface_dir.join(file)).unwrap();
        // --size-mm does not apply to a mesh: the file's cells are pressed.
        let o = wagashi_in(tmp.path(), ["press", "bundle", "-o", out, "--size-mm", "1", "--dt", "1"]);
        assert_success(&o);
        let said = stdout(&o);
        assert!(said.contains("the elements of ") && said.contains(file), "{said}");
        let out = tmp.path().join(out);
        let s = summary(&out);
        let AnyPress::Solid(p) = wagashi_io::read_bundle(&surface_dir).unwrap().to_press(1.0).unwrap() else {
            panic!("a mesh specimen is solid")
        };
        assert_eq!(s["cells"].as_u64(), Some(p.mesh.cells.len() as u64));
        assert_eq!(s["nodes"].as_u64(), Some(p.mesh.nodes.len() as u64));
        assert!((p.mesh.measure() - 1000.0).abs() <= 1e-9 * 1000.0);
        let end = *plate_forces(&out).last().unwrap();
        let (e, nu, area, strain) = (0.05, 0.3, 100.0, 0.05);
        let uniaxial = e * area * strain;
        let confined = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu)) * area * strain;
        assert!(end >= uniaxial && end <= confined, "{file}: {end} N not in [{uniaxial}, {confined}]");
        assert!(
            (end - by_surface).abs() <= 1e-6 * by_surface,
            "{file}: {end} N by the mesh, {by_surface} N by the surface"
        );
        let written = std::fs::read_to_string(out.join("experiment.toml")).unwrap();
        assert!(written.contains(&format!("mesh = \"specimen/{file}\"")), "{written}");
        assert_eq!(std::fs::read(out.join("specimen").join(file)).unwrap(), before);
        assert_eq!(std::fs::read(surface_dir.join(file)).unwrap(), before, "the input was modified");
    }
}
