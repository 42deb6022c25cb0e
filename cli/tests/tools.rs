//! `wagashi press` with rigid contact tools, end to end: the real binary in a
//! temporary folder on the sphere-indentation and double-compression examples,
//! on two asynchronous plates (`[[protocol.tools]]`) and on a surface tool;
//! `tools.csv` and `contact_nodes.json` read back and checked against the
//! physics (quasi-static equilibrium, contact that grows, leaves and touches
//! again), the animated glTF checked by the Khronos glTF-Validator (see
//! `tests/browser/harness.rs` for when it runs).

mod common;
#[path = "../../tests/browser/harness.rs"]
mod harness;

use std::collections::BTreeMap;
use std::path::Path;

use common::*;
use serde_json::Value;

/// One row of `tools.csv`.
#[derive(Debug, Clone, PartialEq)]
struct ToolRow {
    t_s: f64,
    tool: String,
    force_n: [f64; 3],
    normal_n: f64,
    tangential_n: f64,
    area_mm2: f64,
}

/// `tools.csv`: checks the header and the time order, parses every row.
fn read_tools_csv(out: &Path) -> Vec<ToolRow> {
    let text = std::fs::read_to_string(out.join("tools.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_s,tool,force_x_N,force_y_N,force_z_N,normal_N,tangential_N,area_mm2"));
    let rows: Vec<ToolRow> = lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), 8, "{l}");
            let x = |i: usize| -> f64 {
                let v: f64 = cells[i].parse().unwrap_or_else(|_| panic!("bad number in {l}"));
                assert!(v.is_finite(), "{l}");
                v
            };
            ToolRow {
                t_s: x(0),
                tool: cells[1].to_string(),
                force_n: [x(2), x(3), x(4)],
                normal_n: x(5),
                tangential_n: x(6),
                area_mm2: x(7),
            }
        })
        .collect();
    assert!(rows.windows(2).all(|w| w[0].t_s <= w[1].t_s), "tools.csv in time order");
    rows
}

/// The rows of one tool.
fn track<'a>(rows: &'a [ToolRow], tool: &str) -> Vec<&'a ToolRow> {
    rows.iter().filter(|r| r.tool == tool).collect()
}

/// `steps.csv`: (t_s, bottom_force_N) per step.
fn bottom_forces(out: &Path) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(out.join("steps.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (c[0], c[5])
        })
        .collect()
}

/// Quasi-static equilibrium without gravity: at every step the forces on the
/// tools that press from above balance the bottom force (`floors`: tools whose
/// force is the bottom's, subtracted). Returns the largest bottom force.
fn assert_balance(out: &Path, rows: &[ToolRow], floors: &[&str]) -> f64 {
    let steps = bottom_forces(out);
    let peak = steps.iter().map(|s| s.1.abs()).fold(0.0, f64::max);
    assert!(peak > 0.0);
    let mut at: BTreeMap<u64, f64> = BTreeMap::new();
    for r in rows.iter().filter(|r| !floors.contains(&r.tool.as_str())) {
        *at.entry(r.t_s.to_bits()).or_default() += r.force_n[1];
    }
    for (t, bottom) in &steps {
        let tools = at.get(&t.to_bits()).unwrap_or_else(|| panic!("no tools.csv rows at step t = {t}"));
        assert!((tools - bottom).abs() <= 1e-6 * peak, "t = {t}: tools {tools} N, bottom {bottom} N (peak {peak} N)");
    }
    peak
}

/// `contact_nodes.json`: each tool's snapshots `(t_s, nodes)`; node indices below `num_nodes`.
fn read_contact_nodes(out: &Path, num_nodes: u64) -> BTreeMap<String, Vec<(f64, Vec<u64>)>> {
    let text = std::fs::read_to_string(out.join("contact_nodes.json")).unwrap();
    let json: Value = serde_json::from_str(&text).unwrap();
    let mut map = BTreeMap::new();
    for tool in json["tools"].as_array().unwrap() {
        let snapshots = tool["snapshots"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| {
                let nodes: Vec<u64> = s["nodes"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
                assert!(nodes.iter().all(|&n| n < num_nodes), "{nodes:?}");
                assert!(s["area_mm2"].as_f64().unwrap() >= 0.0 && s["normal_N"].as_f64().is_some());
                (s["t_s"].as_f64().unwrap(), nodes)
            })
            .collect();
        map.insert(tool["name"].as_str().unwrap().to_string(), snapshots);
    }
    map
}

fn files_listed(summary: &Value) -> Vec<String> {
    summary["files"].as_array().unwrap().iter().map(|f| f.as_str().unwrap().to_string()).collect()
}

/// The glTF JSON chunk of a `.glb`.
fn glb_json(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[0..4], b"glTF");
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// The translation keys [m] of node `node`'s animation channel, read from the
/// `.glb`'s binary chunk.
fn translation_keys(path: &Path, json: &Value, node: u64) -> Vec<[f64; 3]> {
    let bytes = std::fs::read(path).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin = &bytes[20 + json_len + 8..];
    let animation = &json["animations"][0];
    let channel = animation["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["target"]["node"].as_u64() == Some(node) && c["target"]["path"] == "translation")
        .unwrap_or_else(|| panic!("no translation channel for node {node}"));
    let sampler = &animation["samplers"][channel["sampler"].as_u64().unwrap() as usize];
    let accessor = &json["accessors"][sampler["output"].as_u64().unwrap() as usize];
    assert_eq!((accessor["type"].as_str(), accessor["componentType"].as_u64()), (Some("VEC3"), Some(5126)));
    let view = &json["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
    let start =
        view["byteOffset"].as_u64().unwrap_or(0) as usize + accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
    (0..accessor["count"].as_u64().unwrap() as usize)
        .map(|i| {
            std::array::from_fn(|k| {
                let at = start + 12 * i + 4 * k;
                f64::from(f32::from_le_bytes(bin[at..at + 4].try_into().unwrap()))
            })
        })
        .collect()
}

fn node_names(json: &Value) -> Vec<String> {
    json["nodes"].as_array().unwrap().iter().map(|n| n["name"].as_str().unwrap().to_string()).collect()
}

/// The sphere of examples/paper/sphere-indentation: its force balances the
/// floor's at every step (1e-6 of the peak), its contact area grows while it
/// pushes, and it no longer touches after the release.
#[test]
fn sphere_indentation_end_to_end() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &example("paper/sphere-indentation"), &out, &[]);
    assert_success(&o);
    assert!(stdout(&o).contains("tool sphere"), "{}", stdout(&o));
    let summary = check_output(&out, 3);
    let files = files_listed(&summary);
    assert!(files.contains(&"tools.csv".into()) && files.contains(&"contact_nodes.json".into()), "{files:?}");
    let rows = read_tools_csv(&out);
    let sphere = track(&rows, "sphere");
    assert_eq!(sphere.len(), rows.len(), "one tool");
    assert_eq!(sphere.len() as u64, summary["steps"].as_u64().unwrap() + 1, "t = 0 and every step");
    let peak = assert_balance(&out, &rows, &[]);
    // Frictionless: no tangential force; the normal force is the push.
    for r in &sphere {
        assert!(r.tangential_n <= 1e-6 * peak && r.normal_n >= -1e-9 * peak, "{r:?}");
    }
    // The contact area grows while the sphere pushes (0 to 10 s; by whole rings of
    // nodes on this mesh) and is gone after the release.
    let pushing: Vec<f64> = sphere.iter().filter(|r| r.t_s > 0.0 && r.t_s <= 10.0 + 1e-9).map(|r| r.area_mm2).collect();
    assert!(pushing.windows(2).all(|w| w[1] >= w[0]), "areas while pushing: {pushing:?}");
    let (first, end) = (pushing[0], pushing[pushing.len() - 1]);
    assert!(0.0 < first && first < end, "areas {first} then {end} mm^2");
    // The contact (R = 5 mm, 1.5 mm deep: radius about 2.7 mm) stays well inside the top (R = 15 mm).
    assert!(end < std::f64::consts::PI * 25.0, "{end} mm^2");
    assert!(sphere.iter().filter(|r| r.t_s > 20.0 + 1e-9).all(|r| r.area_mm2 == 0.0 && r.force_n == [0.0; 3]));
    // Nodes in contact at the kept times: the release (touching) and the end (not).
    let nodes = read_contact_nodes(&out, summary["nodes"].as_u64().unwrap());
    let snapshots = &nodes["sphere"];
    assert_eq!(snapshots.iter().map(|s| s.0).collect::<Vec<_>>(), [20.0, 30.0]);
    assert!(!snapshots[0].1.is_empty() && snapshots[1].1.is_empty(), "{snapshots:?}");
}

/// examples/paper/double-compression: the frictionless plate leaves the
/// cylinder after the first stroke and touches it again later than a fully
/// recovered specimen would be touched (17.5 s: 0.5 mm at 0.2 mm/s from 15 s),
/// with a lower peak at the same depth and speed, its force balancing the bottom
/// force; the run's animated glTF holds the plate and validates; `export`
/// rebuilds it from the output, which reads back as a bundle.
#[test]
fn double_compression_end_to_end_with_its_animation() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = press_in(
        tmp.path(),
        &example("paper/double-compression"),
        &out,
        &["--size-mm", "5", "--gltf", "out/view/dc.glb"],
    );
    assert_success(&o);
    let summary = check_output(&out, 3);
    let rows = read_tools_csv(&out);
    let plate = track(&rows, "plate");
    assert_eq!(plate.len(), rows.len());
    let peak = assert_balance(&out, &rows, &[]);
    // Touching in the first stroke, free in between, touching again after 17 s.
    let touching = |r: &&ToolRow| r.area_mm2 > 0.0;
    assert!(plate.iter().filter(|r| r.t_s > 0.0 && r.t_s <= 10.0).all(touching));
    assert!(plate.iter().filter(|r| r.t_s > 10.6 && r.t_s < 17.5).all(|r| !touching(r) && r.force_n == [0.0; 3]));
    let second_touch = plate.iter().find(|r| r.t_s > 15.0 && touching(r)).expect("the second stroke touches").t_s;
    assert!(second_touch > 17.5 && second_touch < 27.5, "second touch at {second_touch} s");
    let stroke_peak = |from: f64, to: f64| {
        plate.iter().filter(|r| r.t_s >= from && r.t_s <= to).map(|r| r.force_n[1]).fold(0.0, f64::max)
    };
    let (first, second) = (stroke_peak(0.0, 10.5), stroke_peak(15.0, 28.0));
    assert!((first - peak).abs() <= 1e-6 * peak && second > 0.0 && second < first, "{first} N then {second} N");
    // The kept frames (the --gltf times) list the plate's nodes while it touches.
    let nodes = read_contact_nodes(&out, summary["nodes"].as_u64().unwrap());
    let at = |t: f64| nodes["plate"].iter().find(|s| (s.0 - t).abs() < 1e-9).unwrap_or_else(|| panic!("{t}")).1.len();
    assert!(at(8.0) > 0 && at(14.0) == 0 && at(24.0) > 0);

    // The animation: the specimen and the plate; valid; rebuilt by export.
    let glb = out.join("view/dc.glb");
    let json = glb_json(&glb);
    assert_eq!(node_names(&json), ["double-compression-sim", "plate"]);
    harness::validate(&[&glb]);
    let again = tmp.path().join("again.glb");
    assert_success(&wagashi_in(tmp.path(), ["export", "out", "--gltf", again.to_str().unwrap()]));
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&glb).unwrap(), "export reproduces press --gltf");

    // The output reads back as the same trial.
    let o = press_in(tmp.path(), &out, &tmp.path().join("again"), &["--size-mm", "5", "--gltf", "out2.glb"]);
    assert_success(&o);
    let again = read_summary(&tmp.path().join("again"));
    assert!(again["force_max_abs_diff_N"].as_f64().unwrap() <= 1e-9 * peak, "{again}");
}

/// `[[protocol.tools]]`: the v1 plate presses first and rises away; a second,
/// extra plate presses later. Their forces add up to the bottom force, only one
/// touches at a time, the second first touches where the specimen has recovered
/// to; the 2D run's animation holds both, across the slab.
#[test]
fn two_asynchronous_plates_end_to_end() {
    let toml = mat1_experiment!(
        "two-plates",
        2,
        r#"shape = "block"
size_mm = [20.0, 10.0, 8.0]
"#,
        r#"tool_contact = "frictionless"
support = "frictionless"
waypoints = [[0.0, 0.0], [10.0, 2.0], [10.5, -3.0]]
release_s = 30.0
end_s = 30.0

[[protocol.tools]]
name = "second"
shape = "plate"
half_extents_mm = [40.0, 20.0, 40.0]
contact = "frictionless"
keyframes = [[0.0, 10.0, 30.5, 0.0], [15.0, 10.0, 30.5, 0.0], [25.0, 10.0, 28.0, 0.0], [25.5, 10.0, 30.5, 0.0]]
"#
    );
    let tmp = tempfile::tempdir().unwrap();
    let bundle = write_files(&tmp.path().join("two"), &[("experiment.toml", toml)]);
    let out = tmp.path().join("out");
    let glb = tmp.path().join("two.glb");
    let o = press_in(tmp.path(), &bundle, &out, &["--size-mm", "1", "--pvd", "6", "--gltf", glb.to_str().unwrap()]);
    assert_success(&o);
    check_output(&out, 2);
    let rows = read_tools_csv(&out);
    let (plate, second) = (track(&rows, "plate"), track(&rows, "second"));
    assert_eq!(plate.len(), second.len());
    assert_eq!(plate.len() + second.len(), rows.len());
    assert_balance(&out, &rows, &[]);
    let touches = |rows: &[&ToolRow]| -> Vec<f64> { rows.iter().filter(|r| r.area_mm2 > 0.0).map(|r| r.t_s).collect() };
    let (a, b) = (touches(&plate), touches(&second));
    assert!(a.iter().all(|&t| t <= 10.5) && a.len() > 3, "{a:?}");
    // The second plate's face comes down from 0.5 mm above the initial top at 0.25 mm/s from 15 s.
    assert!(b.iter().all(|&t| t > 17.0 && t < 25.5) && b.len() > 3, "{b:?}");
    // The --pvd 6 times are kept: the first plate's nodes at 5 s, the second's at 20 s.
    let nodes = read_contact_nodes(&out, read_summary(&out)["nodes"].as_u64().unwrap());
    let at = |tool: &str, t: f64| nodes[tool].iter().find(|s| (s.0 - t).abs() < 1e-9).unwrap().1.len();
    assert!(at("plate", 5.0) > 0 && at("second", 5.0) == 0 && at("plate", 20.0) == 0 && at("second", 20.0) > 0);

    let json = glb_json(&glb);
    assert_eq!(node_names(&json), ["two-plates-sim", "plate", "second"]);
    // The plates act in z = 0 and are drawn across the middle of the slab
    // (0 <= z <= 8 mm): every translation key at z = 4 mm; the second plate's
    // lower face comes down 2.5 mm from 0.5 mm above the top (y = 10.5 mm).
    for (node, lowest_mm) in [(1, 10.0 - 2.0), (2, 10.0 - 2.0)] {
        let keys = translation_keys(&glb, &json, node);
        assert!(keys.len() >= 7, "{} keys", keys.len());
        assert!(keys.iter().all(|k| (k[2] - 0.004).abs() < 1e-9), "{keys:?}");
        // The slab's underside is the mesh's lowest y; the box's centre is 20 mm above it.
        let lowest = keys.iter().map(|k| k[1] * 1e3 - 20.0).fold(f64::INFINITY, f64::min);
        assert!((lowest - lowest_mm).abs() < 1e-3, "node {node}: lowest face at {lowest} mm");
    }
    harness::validate(&[&glb]);
    let again = tmp.path().join("again.glb");
    assert_success(&wagashi_in(tmp.path(), ["export", "out", "--gltf", again.to_str().unwrap()]));
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&glb).unwrap());
}

/// A surface tool (a closed OBJ box above a 2D block): its file is copied into
/// the output, whose `experiment.toml` names the copy, so that the output reads
/// back as a bundle and `export` draws the tool from it.
#[test]
fn a_surface_tool_travels_with_the_output() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = tmp.path().join("lid");
    std::fs::create_dir_all(bundle.join("shapes")).unwrap();
    // A box x in [-30, 50], y in [10, 50], z in [-40, 40] mm, faces outward.
    let (lo, hi) = ([-30.0, 10.0, -40.0], [50.0, 50.0, 40.0]);
    let mut obj = String::from("o lid\n");
    for i in 0..8 {
        let p = [0, 1, 2].map(|k| if i >> (2 - k) & 1 == 1 { hi[k] } else { lo[k] });
        obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for f in [[5, 7, 8, 6], [1, 2, 4, 3], [3, 4, 8, 7], [1, 5, 6, 2], [2, 6, 8, 4], [1, 3, 7, 5]] {
        obj += &format!("f {} {} {}\nf {} {} {}\n", f[0], f[1], f[2], f[0], f[2], f[3]);
    }
    std::fs::write(bundle.join("shapes/lid.obj"), obj).unwrap();
    let toml = r#"format = "wagashi-experiment/1"
name = "lid"
dimension = 2

[specimen]
shape = "block"
size_mm = [20.0, 10.0, 8.0]
material = "gel"

[materials.gel]
model = "elastic"
poisson = 0.45
E_MPa = 0.05

[protocol]
tool = "surface"
tool_surface = "shapes/lid.obj"
tool_contact = "frictionless"
support = "glued"
waypoints = [[0.0, 0.0], [10.0, 1.0]]
release_s = 10.0
end_s = 10.0
"#;
    std::fs::write(bundle.join("experiment.toml"), toml).unwrap();
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &bundle, &out, &["--size-mm", "1", "--gltf", "out/lid.glb"]);
    assert_success(&o);
    let summary = check_output(&out, 2);
    assert!(files_listed(&summary).contains(&"tools/surface.obj".to_string()));
    assert_eq!(
        std::fs::read(out.join("tools/surface.obj")).unwrap(),
        std::fs::read(bundle.join("shapes/lid.obj")).unwrap()
    );
    let written = std::fs::read_to_string(out.join("experiment.toml")).unwrap();
    assert!(written.contains("tool_surface = \"tools/surface.obj\""), "{written}");
    let rows = read_tools_csv(&out);
    assert_balance(&out, &rows, &[]);
    // A 1 mm push of a 10 mm high elastic block, E = 0.05 MPa, plane stress,
    // glued below and frictionless above: close to E A strain = 0.8 N.
    let end = rows.last().unwrap();
    assert!(end.force_n[1] > 0.7 && end.force_n[1] < 1.0, "{end:?}");
    let glb = out.join("lid.glb");
    assert_eq!(node_names(&glb_json(&glb)), ["lid-sim", "surface"]);
    harness::validate(&[&glb]);
    let again = tmp.path().join("again.glb");
    assert_success(&wagashi_in(tmp.path(), ["export", "out", "--gltf", again.to_str().unwrap()]));
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&glb).unwrap());
    let o = press_in(tmp.path(), &out, &tmp.path().join("again"), &["--size-mm", "1"]);
    assert_success(&o);
}

/// Contact tools run only with the implicit integrator: any other is refused in
/// one line before the run, and nothing is written.
#[test]
fn contact_tools_need_the_implicit_integrator() {
    let tmp = tempfile::tempdir().unwrap();
    for integrator in ["dynamic", "seed"] {
        let out = tmp.path().join("out");
        let o = press_in(tmp.path(), &example("paper/double-compression"), &out, &["--integrator", integrator]);
        let line = assert_one_line_error(&o);
        assert!(
            line.contains(&format!("--integrator {integrator}"))
                && line.contains("contact tools (plate)")
                && line.contains("--integrator implicit"),
            "{line}"
        );
        assert!(!out.exists());
    }
}
