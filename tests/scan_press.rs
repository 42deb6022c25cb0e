//! End to end: a scanned pear cut into two layers, pressed by a sphere
//! and then, out of sync, by a plate, released, and written as glTF and VTU.
//!
//! The tests run the example's own pipeline (`examples/scan_press.rs`, included
//! below; see its docs for the trial) on an 8 mm mesh: once as the example does
//! (glued sphere), shared by five tests that check the layers and their volumes,
//! when each tool touches, the forces while pressing and after release, the
//! recovery of the shape, and the files; and once with a frictionless sphere.
//! Both runs take about 28 s together in release on 2 cores (11 s and 28 s of
//! simulation, in parallel).
//!
//! It reads the YCB pear from `<workspace>/../shared/data`; without that folder it
//! is skipped with a note, except on CI (`CI` set to anything but `false` or `0`),
//! where it fails (`tests/support/data.rs`). The Khronos glTF-Validator check follows `tests/browser`: it is
//! skipped with a note when Node.js or the npm package is missing, except on CI or
//! with `WAGASHI_BROWSER_TESTS=required`.

#[path = "../examples/scan_press.rs"]
#[allow(dead_code)]
mod scan_press;

#[path = "support/data.rs"]
mod data;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::Instant;

use fem_core::press::{ToolSample, ToolTrack};
use scan_press::{
    deformed_top, first_touch, last_touch, Options, Outcome, END_S, KEEP_S, PLATE_DOWN_S, PLATE_START_S, PLATE_UP_S,
    SPHERE_DOWN_S,
};
use wagashi_io::gltf::{ShapeCells, VtuShape};

/// The element size of the run [mm]: coarse, so that the whole pipeline takes
/// seconds (about 1,200 nodes and 5,000 tets for the pear).
const SIZE_MM: f64 = 8.0;

/// The run, shared by the tests below; `None` (after saying so) when the shared
/// data is absent (not on CI).
fn outcome() -> Option<&'static Outcome> {
    data::shared_data("the YCB pear scan")?;
    static RUN: OnceLock<Outcome> = OnceLock::new();
    Some(RUN.get_or_init(|| {
        let options = Options {
            size_mm: SIZE_MM,
            output: Path::new(env!("CARGO_TARGET_TMPDIR")).join("scan_press/out"),
            ..Options::new()
        };
        let clock = Instant::now();
        let out = scan_press::run(&options, &mut |line| eprintln!("{line}")).unwrap_or_else(|e| panic!("{e}"));
        eprintln!("scan_press pipeline: {:.1} s in all", clock.elapsed().as_secs_f64());
        out
    }))
}

fn sphere(out: &Outcome) -> &ToolTrack {
    &out.result.tools[0]
}

fn plate(out: &Outcome) -> &ToolTrack {
    &out.result.tools[1]
}

fn sample_at(track: &ToolTrack, t_s: f64) -> &ToolSample {
    track.samples.iter().find(|s| (s.t_s - t_s).abs() <= 1e-9).unwrap_or_else(|| panic!("no sample at {t_s} s"))
}

/// The two layers meet at the plane `y = H/2` with no cell across it, and each
/// holds the scan's volume on its side of the plane within 3 %. (Measured: -1.5 %
/// for both at 8 mm. The mesh's boundary is the envelope's chord approximation of
/// the scan on an 8 mm lattice, which cuts the convex pear's volume by a little;
/// one row of cells tagged to the wrong layer would move a layer's volume by
/// about 2,000 mm^3 per cell, a few per cent for ten cells.)
#[test]
fn the_mesh_has_two_layers_with_the_scans_volumes() {
    let Some(out) = outcome() else { return };
    let mesh = &out.mesh;
    assert_eq!(mesh.region_names, ["layer1", "layer2"]);
    let cut = out.cut_y_mm;
    let (lo, hi) = out.surface.bounding_box();
    assert!(lo[1].abs() <= 1e-12 * hi[1], "the scan's bottom is at y = {} mm", lo[1]);
    assert!((cut - 0.5 * hi[1]).abs() <= 1e-12 * hi[1], "plane at {cut} mm, the scan is {} mm tall", hi[1]);
    let eps = 1e-9 * out.quality.diagonal_mm;
    for (e, (cell, &region)) in mesh.cells.iter().zip(&mesh.cell_regions).enumerate() {
        let y = cell.map(|v| mesh.nodes[v as usize][1]);
        match region {
            0 => assert!(y.iter().all(|&y| y <= cut + eps), "lower cell {e} reaches above the plane: {y:?}"),
            1 => assert!(y.iter().all(|&y| y >= cut - eps), "upper cell {e} reaches below the plane: {y:?}"),
            r => panic!("cell {e} in region {r}"),
        }
    }
    // The scan's volumes on either side add up to its enclosed volume.
    let [below, above] = out.reference_volumes_mm3;
    let enclosed = out.surface.signed_volume(None);
    assert!((below + above - enclosed).abs() <= 1e-9 * enclosed, "{below} + {above} vs {enclosed}");
    for (region, reference) in out.quality.regions.iter().zip(out.reference_volumes_mm3) {
        let error = region.volume_mm3 / reference - 1.0;
        eprintln!(
            "{}: {} tets, {:.0} mm^3 vs {reference:.0} mm^3 ({:+.2} %)",
            region.name,
            region.num_cells,
            region.volume_mm3,
            100.0 * error
        );
        assert!(region.num_cells > 0);
        assert!(
            error.abs() <= 0.03,
            "{}: volume {:.0} mm^3 vs the scan's {reference:.0} mm^3",
            region.name,
            region.volume_mm3
        );
    }
    assert_eq!(out.quality.num_inverted, 0);
    // Isosurface stuffing proves 10.7 deg for the outer boundary's cells; cells cut
    // by the plane have no proven bound but the cut keeps them off slivers.
    assert!(out.quality.min_dihedral_deg > 10.0, "smallest dihedral angle {} deg", out.quality.min_dihedral_deg);
    // The glued base: a patch of the bottom, not a point.
    let bottom = mesh.node_set("bottom").unwrap();
    assert!(bottom.len() >= 3, "{} bottom nodes", bottom.len());
}

/// The sphere touches from the first step, long before the plate starts; the
/// plate touches after it starts (3 s), by the time it reaches the apex of the
/// undeformed pear plus the little the apex sank meanwhile, and well before the
/// sphere lets go: at the keep time (5 s) both press.
#[test]
fn the_tools_touch_out_of_sync() {
    let Some(out) = outcome() else { return };
    let (s, p) = (sphere(out), plate(out));
    assert_eq!((s.name.as_str(), p.name.as_str()), ("sphere", "plate"));
    let sphere_touch = first_touch(s).expect("the sphere touches");
    let plate_touch = first_touch(p).expect("the plate touches");
    eprintln!("first touch: sphere {sphere_touch:.6} s, plate {plate_touch:.4} s");
    assert!(sphere_touch <= out.result.steps[0].t_s + 1e-12, "the sphere first touches at {sphere_touch} s");
    // The plate comes down from PLATE_START_S at a constant speed: it reaches the
    // undeformed apex (PLATE_GAP H below its start) at `reach`.
    let (gap, depth) = (scan_press::PLATE_GAP * out.height_mm, out.tools[1].depth_mm);
    let reach = PLATE_START_S + (PLATE_DOWN_S - PLATE_START_S) * gap / (gap + depth);
    assert!(p.samples.iter().filter(|x| x.t_s <= PLATE_START_S).all(|x| x.area_mm2 == 0.0 && x.normal_n == 0.0));
    assert!(
        plate_touch > PLATE_START_S && plate_touch >= reach - 1e-9,
        "plate touches at {plate_touch} s, reach {reach} s"
    );
    assert!(plate_touch < reach + 0.25, "plate touches at {plate_touch} s, long after it reaches the apex ({reach} s)");
    // Both press at the keep time; the contact node lists are kept there.
    for track in [s, p] {
        let at_keep = sample_at(track, KEEP_S);
        assert!(!at_keep.nodes.is_empty() && at_keep.normal_n > 0.0, "{} at {KEEP_S} s: {at_keep:?}", track.name);
    }
    // The glued sphere holds until it lets go at its deepest point; the plate until
    // it has risen off the specimen.
    assert_eq!(last_touch(s), Some(SPHERE_DOWN_S));
    let plate_last = last_touch(p).unwrap();
    assert!((PLATE_DOWN_S..PLATE_UP_S).contains(&plate_last), "the plate last touches at {plate_last} s");
}

/// Each tool pushes the specimen down (positive normal force, upward force on
/// the tool) at every step end while it presses, and carries exactly nothing once
/// released; the floor carries what the tools push (quasi-static equilibrium, no
/// gravity), to 1e-6 of the peak.
#[test]
fn forces_push_while_pressing_and_vanish_after_release() {
    let Some(out) = outcome() else { return };
    let (s, p) = (sphere(out), plate(out));
    let plate_touch = first_touch(p).unwrap();
    for x in &s.samples {
        if x.t_s > 0.0 && x.t_s <= SPHERE_DOWN_S {
            assert!(x.normal_n > 0.0 && x.force_n[1] > 0.0, "sphere at {} s: {x:?}", x.t_s);
        } else if x.t_s > SPHERE_DOWN_S {
            assert!(x.force_n == [0.0; 3] && x.normal_n == 0.0 && x.area_mm2 == 0.0, "sphere at {} s: {x:?}", x.t_s);
        }
    }
    for x in &p.samples {
        if x.t_s < plate_touch {
            assert!(x.force_n == [0.0; 3] && x.area_mm2 == 0.0, "plate at {} s: {x:?}", x.t_s);
        } else if x.t_s <= PLATE_DOWN_S {
            assert!(x.normal_n > 0.0 && x.force_n[1] > 0.0, "plate at {} s: {x:?}", x.t_s);
        } else if x.t_s > PLATE_UP_S {
            assert!(x.force_n == [0.0; 3] && x.area_mm2 == 0.0, "plate at {} s: {x:?}", x.t_s);
        } else {
            assert!(x.normal_n >= 0.0, "plate at {} s pulls: {x:?}", x.t_s);
        }
    }
    // Both loads grow to the deepest point: the peaks are there.
    let (sphere_peak_s, sphere_peak) = scan_press::peak_force(s);
    let (plate_peak_s, plate_peak) = scan_press::peak_force(p);
    eprintln!(
        "peak forces: sphere {sphere_peak:.4} N at {sphere_peak_s} s, plate {plate_peak:.4} N at {plate_peak_s} s"
    );
    assert_eq!((sphere_peak_s, plate_peak_s), (SPHERE_DOWN_S, PLATE_DOWN_S));
    // Equilibrium: the glued base's reaction is the tools' push, at every step end.
    let peak = out.result.steps.iter().map(|r| r.bottom_force_n.abs()).fold(0.0, f64::max);
    let mut worst: f64 = 0.0;
    for r in &out.result.steps {
        let pushed = sample_at(s, r.t_s).force_n[1] + sample_at(p, r.t_s).force_n[1];
        worst = worst.max((r.bottom_force_n - pushed).abs());
    }
    eprintln!("floor vs tools: worst difference {worst:.2e} N of a peak {peak:.4} N");
    assert!(worst <= 1e-6 * peak, "the floor's reaction differs from the tools' push by {worst} N");
}

/// At the plate's deepest point the pear is exactly as high as the plate's face
/// (the plate's depth below the apex, to the contact tolerance); the glued node
/// under the sphere follows it exactly. After both let go the shape recovers
/// partly: the height loss and the dent fall but stay clearly above zero (the
/// five-element material's dashpot keeps a permanent set; the slow Voigt element
/// has not fully recovered by 30 s).
#[test]
fn the_shape_recovers_partly() {
    let Some(out) = outcome() else { return };
    let loss = |t: f64| out.height_mm - deformed_top(&out.mesh, out.result.snapshot_at(t).unwrap());
    let plate_depth = out.tools[1].depth_mm;
    let peak = loss(PLATE_DOWN_S);
    eprintln!("height loss: {:.6} mm at {PLATE_DOWN_S} s (plate depth {plate_depth:.6} mm), {:.4} mm at 10 s, {:.4} mm at {END_S} s",
        peak, loss(10.0), loss(END_S));
    assert!((peak - plate_depth).abs() <= 1e-6 * SIZE_MM, "height loss {peak} mm vs plate depth {plate_depth} mm");
    let summary = &out.summary;
    assert_eq!(summary["peak_height_loss_t_s"].as_f64(), Some(PLATE_DOWN_S));
    let last = loss(END_S);
    assert!(last > 0.01 && last < loss(10.0) && loss(10.0) < peak, "height loss {peak} -> {} -> {last} mm", loss(10.0));
    assert!(last < 0.25 * peak, "the pear recovered only from {peak} mm to {last} mm");
    // The dent under the sphere.
    let dent_keep = summary["sphere_dent_at_keep_mm"].as_f64().unwrap();
    let dent_final = summary["final_sphere_dent_mm"].as_f64().unwrap();
    let sphere_depth = out.tools[0].depth_mm;
    eprintln!(
        "sphere dent: {dent_keep:.9} mm at {KEEP_S} s (depth {sphere_depth:.9} mm), {dent_final:.4} mm at the end"
    );
    assert!((dent_keep - sphere_depth).abs() <= 1e-6 * SIZE_MM, "dent {dent_keep} mm vs depth {sphere_depth} mm");
    assert!(dent_final > 0.01 && dent_final < 0.25 * dent_keep, "dent {dent_keep} -> {dent_final} mm");
}

/// `final.vtu` and `keep.vtu` read back as the mesh with the kept displacement;
/// `press.glb` is glTF 2.0 with the pear, the sphere and the plate, named `keep`
/// and `final` frames, and passes the Khronos glTF-Validator; `summary.json`
/// holds the run's figures.
#[test]
fn the_outputs_read_back() {
    let Some(out) = outcome() else { return };
    let dir = &out.output;
    for (file, t) in [("final.vtu", END_S), ("keep.vtu", KEEP_S)] {
        let shape = VtuShape::read(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(shape.points_mm, out.mesh.nodes, "{file}: points");
        let ShapeCells::Tetrahedra(cells) = &shape.cells else { panic!("{file}: not tetrahedra") };
        assert_eq!(cells, &out.mesh.cells, "{file}: cells");
        let u = &out.result.snapshot_at(t).unwrap().displacement;
        let worst = shape.nodal_displacement(3).iter().zip(u).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-12, "{file}: displacement differs by {worst} mm from the engine's at {t} s");
    }

    let glb = dir.join("press.glb");
    let bytes = std::fs::read(&glb).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 2);
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize, bytes.len());
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    let gltf: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let names: Vec<&str> = gltf["nodes"].as_array().unwrap().iter().map(|n| n["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["YcbPear_collision_vhacd", "sphere", "plate"]);
    let targets: Vec<&str> =
        gltf["meshes"][0]["extras"]["targetNames"].as_array().unwrap().iter().map(|n| n.as_str().unwrap()).collect();
    assert_eq!(targets.len(), out.result.snapshots.len() + 1, "a frame per kept shape and the undeformed one");
    assert!(targets.contains(&"keep") && targets.last() == Some(&"final"), "{targets:?}");
    assert_eq!(gltf["asset"]["extras"]["run"]["example"], "scan_press");
    if let Some(report) = khronos_validate(&glb) {
        eprintln!("glTF-Validator {}: no error, no warning", report["validator"]);
    }

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert!(same_json(&summary, &out.summary), "summary.json differs from the run's summary");
    assert_eq!(summary["mesh"]["nodes"].as_u64(), Some(out.mesh.nodes.len() as u64));
    assert_eq!(summary["mesh"]["tets"].as_u64(), Some(out.mesh.cells.len() as u64));
    // To 1e-15 relative, as `same_json`: the shortest decimal reads back within an ulp.
    let (written, peak) = (summary["tools"][1]["peak_force_N"].as_f64(), scan_press::peak_force(plate(out)).1);
    assert!(written.is_some_and(|w| (w - peak).abs() <= 1e-15 * peak.abs()), "summary {written:?} vs run {peak}");
}

/// Whether two JSON values are equal, numbers to 1e-15 relative (the shortest
/// decimal of an f64 reads back to within an ulp or so).
fn same_json(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            (x - y).abs() <= 1e-15 * x.abs().max(y.abs())
        }
        (Value::Array(x), Value::Array(y)) => x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same_json(x, y)),
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same_json(v, w)))
        }
        _ => a == b,
    }
}

/// Runs the Khronos glTF-Validator (`tests/browser/validate.mjs`) on `glb` and
/// asserts no error and no warning; `None` (with a note) when Node.js or the npm
/// package is missing, unless required (CI, or `WAGASHI_BROWSER_TESTS=required`),
/// as `tests/browser/harness.rs` does. That harness is not included here: it
/// finds `tests/browser` one level above the including crate, which from the
/// root package lies outside the workspace.
fn khronos_validate(glb: &Path) -> Option<serde_json::Value> {
    let browser: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser");
    let required = data::on_ci() || std::env::var("WAGASHI_BROWSER_TESTS").is_ok_and(|v| v == "required");
    let node = Command::new("node").arg("--version").stdout(Stdio::null()).stderr(Stdio::null()).status();
    let missing = if !node.is_ok_and(|s| s.success()) {
        Some("`node` does not run".to_string())
    } else if !browser.join("node_modules/gltf-validator/package.json").is_file() {
        Some("the npm package gltf-validator is not installed (run `npm ci` in tests/browser)".to_string())
    } else {
        None
    };
    if let Some(what) = missing {
        assert!(!required, "the glTF-Validator check is required (CI or WAGASHI_BROWSER_TESTS=required): {what}");
        eprintln!("note: glTF-Validator check skipped: {what}");
        return None;
    }
    let output = Command::new("node")
        .arg(browser.join("validate.mjs"))
        .arg(glb)
        .stdin(Stdio::null())
        .output()
        .expect("node runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| {
        panic!("validate.mjs printed no report ({e}): {stdout}\n{}", String::from_utf8_lossy(&output.stderr))
    });
    let r = &report["reports"][0];
    assert!(r["errors"] == 0 && r["warnings"] == 0, "{}: {}", glb.display(), r["messages"]);
    assert!(output.status.success(), "validate.mjs exited with {:?}", output.status);
    Some(report)
}

/// The same trial with a frictionless sphere, which slides on the neck and lets
/// go once it has risen off it (5.25 s). A regression: while the contact solver
/// was being reworked, this run stopped with `ContactNotSettled` (naming no node)
/// in the tiny first step after the plate starts at 3 s, after minutes of 2-3 s
/// steps. It should finish, the sphere pressing until it rises and carrying
/// nothing after, and the shape should recover as with the glued sphere.
#[test]
fn frictionless_sphere_settles_after_the_plate_starts() {
    if data::skip_without_shared_data("the YCB pear scan") {
        return;
    }
    let options = Options {
        size_mm: SIZE_MM,
        sphere_contact: fem_core::press::ToolContact::Frictionless,
        output: Path::new(env!("CARGO_TARGET_TMPDIR")).join("scan_press/frictionless"),
        ..Options::new()
    };
    let clock = Instant::now();
    let out = scan_press::run(&options, &mut |line| eprintln!("{line}")).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("scan_press pipeline, frictionless sphere: {:.1} s in all", clock.elapsed().as_secs_f64());
    let (s, p) = (sphere(&out), plate(&out));
    assert!(first_touch(s).is_some_and(|t| t <= out.result.steps[0].t_s + 1e-12));
    assert!(first_touch(p).is_some_and(|t| t > PLATE_START_S && t < KEEP_S));
    for x in &s.samples {
        if x.t_s > 0.0 && x.t_s <= SPHERE_DOWN_S {
            assert!(x.normal_n > 0.0 && x.force_n[1] > 0.0, "sphere at {} s: {x:?}", x.t_s);
        } else if x.t_s > scan_press::SPHERE_UP_S {
            assert!(x.force_n == [0.0; 3] && x.area_mm2 == 0.0, "sphere at {} s: {x:?}", x.t_s);
        }
    }
    let loss = |t: f64| out.height_mm - deformed_top(&out.mesh, out.result.snapshot_at(t).unwrap());
    assert!((loss(PLATE_DOWN_S) - out.tools[1].depth_mm).abs() <= 1e-6 * SIZE_MM);
    assert!(loss(END_S) > 0.01 && loss(END_S) < 0.25 * loss(PLATE_DOWN_S), "height loss at the end {}", loss(END_S));
}
