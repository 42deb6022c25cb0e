//! The glTF export: files written from fem-core meshes read back with the `gltf`
//! crate (metres, frames, names, colours, the tool's motion), checked by the
//! Khronos glTF-Validator (see `tests/browser/harness.rs` for when it runs), and
//! bad input refused with a typed error and no file.

#[path = "../../tests/browser/harness.rs"]
mod harness;

use std::path::Path;

use fem_core::mesh;
use fem_core::press::Protocol;
use serde_json::Value;
use wagashi_io::gltf::{
    glb_bytes, viridis_linear, write_glb, AnimatedSurface, AnimatedTool, Frame, FrameSeries, GltfError, GltfScene,
    SpecimenSurface, ToolKey,
};

/// f32 storage: a relative error of 2^-24 on each stored number.
const F32_TOL: f64 = 1e-6;

/// The glTF JSON of a `.glb` (the first chunk), for the extras the `gltf` crate skips.
fn glb_json(bytes: &[u8]) -> Value {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// The floats of accessor `index` (tightly packed, float components), read by hand.
fn accessor_f32(json: &Value, blob: &[u8], index: u64) -> Vec<f32> {
    let a = &json["accessors"][index as usize];
    assert_eq!(a["componentType"], 5126);
    let view = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let per = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        "VEC4" => 4,
        t => panic!("type {t}"),
    };
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    let n = per * a["count"].as_u64().unwrap() as usize;
    (0..n).map(|i| f32::from_le_bytes(blob[start + 4 * i..start + 4 * i + 4].try_into().unwrap())).collect()
}

/// A 20 x 10 x 5 mm block squashed by `0.2 t` of its height at time `t`, bulging in x.
fn squash(block: &mesh::TetMesh, s: f64) -> Vec<f64> {
    block.nodes.iter().flat_map(|p| [0.05 * s * (p[0] - 10.0), -0.2 * s * p[1], 0.02 * s * (p[2] - 2.5)]).collect()
}

fn tet_scene() -> (mesh::TetMesh, SpecimenSurface, GltfScene) {
    let block = mesh::block([20.0, 10.0, 5.0], 2.5, "gel").unwrap();
    let surface = SpecimenSurface::from_tet_mesh(&block).unwrap();
    let frames = vec![
        surface.frame(0.0, None, &squash(&block, 0.0)).unwrap(),
        surface.frame(1.0, Some("keep"), &squash(&block, 1.0)).unwrap(),
        surface.frame(2.0, Some("final"), &squash(&block, 0.5)).unwrap(),
    ];
    let protocol = Protocol::ramp_hold_release(2.0, 1.0, 1.0, 2.0);
    let plate = AnimatedTool::plate(&protocol, surface.bounds_mm());
    let scene = GltfScene {
        specimen: surface.animated("gel", frames),
        tools: vec![plate],
        extras: serde_json::json!({ "trial": "squash" }),
    };
    (block, surface, scene)
}

#[test]
fn a_tet_mesh_animation_reads_back_in_metres_with_its_frames_colours_and_tool() {
    let (block, surface, scene) = tet_scene();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("squash.glb");
    write_glb(&path, &scene).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes.len() % 4, 0);
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize, bytes.len());

    let gltf = gltf::Gltf::from_slice(&bytes).expect("the gltf crate reads and validates it");
    let blob = gltf.blob.as_deref().expect("a BIN chunk");
    let json = glb_json(&bytes);
    let nodes: Vec<_> = gltf.nodes().collect();
    assert_eq!(nodes.iter().map(|n| n.name().unwrap()).collect::<Vec<_>>(), ["gel", "plate"]);

    // The specimen: reference positions in metres, unit normals, viridis(0) at rest.
    let mesh = nodes[0].mesh().unwrap();
    let primitive = mesh.primitives().next().unwrap();
    let reader = primitive.reader(|_| Some(blob));
    let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    assert_eq!(positions.len(), surface.positions_mm.len());
    for (p, x) in positions.iter().zip(&surface.positions_mm) {
        for k in 0..3 {
            assert!((f64::from(p[k]) - 1e-3 * x[k]).abs() <= F32_TOL * 0.02, "{p:?} vs {x:?} mm");
        }
    }
    let bounds = primitive.bounding_box();
    assert!((f64::from(bounds.max[0]) - 0.020).abs() < 1e-9 && (f64::from(bounds.max[1]) - 0.010).abs() < 1e-9);
    for n in reader.read_normals().unwrap() {
        let length = n.iter().map(|x| f64::from(*x).powi(2)).sum::<f64>().sqrt();
        assert!((length - 1.0).abs() < 1e-6, "{n:?}");
    }
    let rest = viridis_linear(0.0);
    for c in reader.read_colors(0).unwrap().into_rgb_f32() {
        assert!((0..3).all(|k| (f64::from(c[k]) - rest[k]).abs() < 1e-6), "{c:?}");
    }
    assert_eq!(reader.read_indices().unwrap().into_u32().count(), 3 * surface.triangles.len());

    // One morph target per frame: the displacement in metres; frame names in extras.
    let targets: Vec<_> = reader.read_morph_targets().collect();
    assert_eq!(targets.len(), 3);
    let expected = surface.displacement_mm(&squash(&block, 1.0)).unwrap();
    let keep: Vec<[f32; 3]> = targets[1].0.clone().unwrap().collect();
    for (d, u) in keep.iter().zip(&expected) {
        for k in 0..3 {
            assert!((f64::from(d[k]) - 1e-3 * u[k]).abs() <= 1e-9, "{d:?} vs {u:?} mm");
        }
    }
    assert_eq!(json["meshes"][0]["extras"]["targetNames"], serde_json::json!(["t=0s", "keep", "final"]));
    assert_eq!(mesh.weights(), Some(&[1.0, 0.0, 0.0][..]), "the first frame shows without the animation");

    // Colours: the most displaced vertex of the keep frame is at the top of the scale.
    let extras = &json["asset"]["extras"];
    let max_mm = expected.iter().map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt()).fold(0.0, f64::max);
    assert!((extras["colour_scale"]["max_mm"].as_f64().unwrap() - max_mm).abs() < 1e-12);
    assert_eq!(extras["colour_scale"]["min_mm"], 0.0);
    assert_eq!(extras["colour_scale"]["colormap"], "viridis");
    assert_eq!(extras["colour_scale"]["attribute"], "COLOR_0");
    assert_eq!(extras["units"]["length"], "m");
    assert_eq!(extras["named_frames"], serde_json::json!({ "keep": 1, "final": 2 }));
    assert_eq!(extras["run"]["trial"], "squash");
    let target = &json["meshes"][0]["primitives"][0]["targets"][1];
    let d_colour = accessor_f32(&json, blob, target["COLOR_0"].as_u64().unwrap());
    let (worst, _) = expected
        .iter()
        .enumerate()
        .map(|(v, u)| (v, u[0] * u[0] + u[1] * u[1] + u[2] * u[2]))
        .fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a });
    let top = viridis_linear(1.0);
    for k in 0..3 {
        assert!((rest[k] + f64::from(d_colour[3 * worst + k]) - top[k]).abs() < 1e-6);
    }

    // The animation: weights one-hot at 0, 1, 2 s; the plate's translation in metres.
    let animation = gltf.animations().next().unwrap();
    assert_eq!(animation.name(), Some("press"));
    let mut seen = Vec::new();
    for channel in animation.channels() {
        let r = channel.reader(|_| Some(blob));
        let times: Vec<f32> = r.read_inputs().unwrap().collect();
        let node = channel.target().node().index();
        match r.read_outputs().unwrap() {
            gltf::animation::util::ReadOutputs::MorphTargetWeights(gltf::animation::util::MorphTargetWeights::F32(
                w,
            )) => {
                assert_eq!(node, 0);
                assert_eq!(times, [0.0, 1.0, 2.0]);
                let w: Vec<f32> = w.collect();
                assert_eq!(w, [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
                seen.push("weights");
            }
            gltf::animation::util::ReadOutputs::Translations(t) => {
                assert_eq!(node, 1);
                let t: Vec<[f32; 3]> = t.collect();
                // Pushed 2 mm in 1 s from the top (10 mm), then lifted 15 % of the height above it.
                assert_eq!(times, [0.0, 1.0, 1.1]);
                let y: Vec<f64> = t.iter().map(|p| f64::from(p[1])).collect();
                for (got, want) in y.iter().zip([0.010, 0.008, 0.0115]) {
                    assert!((got - want).abs() < 1e-9, "{y:?}");
                }
                seen.push("translation");
            }
            gltf::animation::util::ReadOutputs::Rotations(r) => {
                assert_eq!(node, 1);
                assert!(r.into_f32().all(|q| q == [0.0, 0.0, 0.0, 1.0]));
                seen.push("rotation");
            }
            _ => panic!("unexpected channel"),
        }
    }
    seen.sort_unstable();
    assert_eq!(seen, ["rotation", "translation", "weights"]);

    // Deterministic: the same scene gives the same bytes.
    assert_eq!(glb_bytes(&scene).unwrap(), bytes);
    harness::validate(&[&path]);
}

#[test]
fn plane_and_axisymmetric_specimens_export_valid_files() {
    let dir = tempfile::tempdir().unwrap();
    let protocol = Protocol::ramp_hold_release(0.5, 2.0, 3.0, 4.0);

    // Plane stress: a 30 x 20 rectangle, 8 mm thick, squashed.
    let rect = mesh::rectangle(30.0, 20.0, 4.0, "a").unwrap();
    let slab = SpecimenSurface::extruded(&rect, 8.0).unwrap();
    let u =
        |s: f64| -> Vec<f64> { rect.nodes.iter().flat_map(|p| [0.02 * s * (p[0] - 15.0), -0.05 * s * p[1]]).collect() };
    let frames: Vec<Frame> =
        [0.0, 1.0, 3.0, 4.0].iter().map(|&t| slab.frame(t, None, &u(t.min(3.0))).unwrap()).collect();
    let scene = GltfScene {
        specimen: slab.animated("slab", frames),
        tools: vec![AnimatedTool::plate(&protocol, slab.bounds_mm())],
        extras: Value::Null,
    };
    let plane = dir.path().join("plane.glb");
    write_glb(&plane, &scene).unwrap();
    let g = gltf::Gltf::from_slice(&std::fs::read(&plane).unwrap()).unwrap();
    let b = g.meshes().next().unwrap().primitives().next().unwrap().bounding_box();
    assert_eq!((b.min[2], b.max[2]), (0.0, 0.008), "z from 0 to T, in metres");

    // Axisymmetric: a cylinder section of radius 10 and height 15 revolved.
    let section = mesh::axisymmetric_section(10.0, 15.0, 2.5, "a").unwrap();
    let solid = SpecimenSurface::revolved(&section, 48).unwrap();
    let u = |s: f64| -> Vec<f64> { section.nodes.iter().flat_map(|p| [0.03 * s * p[0], -0.1 * s * p[1]]).collect() };
    let frames: Vec<Frame> = [0.0, 2.0, 4.0].iter().map(|&t| solid.frame(t, None, &u(t)).unwrap()).collect();
    let scene = GltfScene {
        specimen: solid.animated("cylinder", frames),
        tools: vec![AnimatedTool::plate(&protocol, solid.bounds_mm())],
        extras: Value::Null,
    };
    let revolved = dir.path().join("revolved.glb");
    write_glb(&revolved, &scene).unwrap();
    let g = gltf::Gltf::from_slice(&std::fs::read(&revolved).unwrap()).unwrap();
    let b = g.meshes().next().unwrap().primitives().next().unwrap().bounding_box();
    assert!((f64::from(b.min[0]) + 0.010).abs() < 1e-9 && (f64::from(b.max[0]) - 0.010).abs() < 1e-9);
    assert!((f64::from(b.max[1]) - 0.015).abs() < 1e-9);

    harness::validate(&[&plane, &revolved]);
}

/// A scene, broken by `edit`, is refused with the error `check` expects, and
/// neither the file nor a temporary is left.
fn refused(edit: impl FnOnce(&mut GltfScene), check: impl FnOnce(&GltfError) -> bool) -> String {
    let (_, _, mut scene) = tet_scene();
    edit(&mut scene);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.glb");
    let err = write_glb(&path, &scene).unwrap_err();
    assert!(check(&err), "unexpected error: {err:?}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "{err}: something was left in the folder");
    err.to_string()
}

#[test]
fn bad_input_is_a_typed_error_and_leaves_no_file() {
    let msg = refused(
        |s| s.specimen.frames[1].displacement_mm.pop().map(drop).unwrap(),
        |e| matches!(e, GltfError::LengthMismatch { item: "vectors", .. }),
    );
    assert!(msg.contains("specimen `gel`, frame 1 (t = 1 s): displacement_mm has"), "{msg}");

    let msg = refused(|s| s.specimen.frames[2].t_s = 1.0, |e| matches!(e, GltfError::NotIncreasing { .. }));
    assert!(msg.contains("frame 2") && msg.contains("not after"), "{msg}");
    // Distinct as f64, equal as the f32 glTF stores.
    refused(
        |s| {
            s.specimen.frames[1].t_s = 1e6;
            s.specimen.frames[2].t_s = 1e6 + 1e-3;
        },
        |e| matches!(e, GltfError::NotIncreasing { .. }),
    );
    refused(|s| s.specimen.frames[0].t_s = -1.0, |e| matches!(e, GltfError::Invalid { .. }));

    let msg = refused(
        |s| s.specimen.frames[1].displacement_mm[7][2] = f64::NAN,
        |e| matches!(e, GltfError::NonFinite { .. }),
    );
    assert!(msg.contains("vertex 7"), "{msg}");
    refused(|s| s.specimen.positions_mm[3][0] = f64::INFINITY, |e| matches!(e, GltfError::NonFinite { .. }));
    refused(|s| s.tools[0].keys[1].translation_mm[1] = f64::NAN, |e| matches!(e, GltfError::NonFinite { .. }));
    let msg = refused(|s| s.tools[0].keys[1].rotation_xyzw = [0.0; 4], |e| matches!(e, GltfError::Invalid { .. }));
    assert!(msg.contains("tool `plate`, key 1"), "{msg}");
    refused(|s| s.tools[0].keys.swap(0, 1), |e| matches!(e, GltfError::NotIncreasing { .. }));

    refused(|s| s.specimen.triangles[5][1] = 1 << 30, |e| matches!(e, GltfError::IndexOutOfRange { .. }));
    refused(|s| s.specimen.frames.clear(), |e| matches!(e, GltfError::Invalid { .. }));
    refused(|s| s.specimen.triangles.clear(), |e| matches!(e, GltfError::Invalid { .. }));
    refused(|s| s.tools[0].name = "gel".into(), |e| matches!(e, GltfError::Invalid { .. }));
    refused(|s| s.specimen.frames[0].name = Some("keep".into()), |e| matches!(e, GltfError::Invalid { .. }));
    refused(|s| s.specimen.positions_mm[0][0] = 1e300, |e| matches!(e, GltfError::Invalid { .. }));

    // A surface's displacement of the wrong length is refused before any frame is made.
    let block = mesh::block([2.0, 2.0, 2.0], 1.0, "a").unwrap();
    let surface = SpecimenSurface::from_tet_mesh(&block).unwrap();
    assert!(matches!(surface.frame(0.0, None, &[0.0; 5]), Err(GltfError::LengthMismatch { .. })));
}

#[test]
fn a_scene_without_tools_and_one_frame_is_valid() {
    let block = mesh::block([3.0, 3.0, 3.0], 1.5, "a").unwrap();
    let surface = SpecimenSurface::from_tet_mesh(&block).unwrap();
    let scene = GltfScene {
        specimen: AnimatedSurface {
            frames: vec![surface.frame(0.5, Some("final"), &vec![0.0; 3 * block.nodes.len()]).unwrap()],
            ..surface.animated("still", Vec::new())
        },
        tools: Vec::new(),
        extras: Value::Null,
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("still.glb");
    write_glb(&path, &scene).unwrap();
    let json = glb_json(&std::fs::read(&path).unwrap());
    assert_eq!(json["materials"].as_array().unwrap().len(), 1, "no unused tool material");
    assert_eq!(json["asset"]["extras"]["colour_scale"]["max_mm"], 0.0);
    harness::validate(&[&path]);
}

#[test]
fn a_tool_with_a_rotation_is_normalized() {
    let (_, _, mut scene) = tet_scene();
    let half = std::f64::consts::FRAC_PI_8;
    scene.tools.push(AnimatedTool::cuboid(
        "roller",
        [-1.0, -1.0, -1.0],
        [1.0, 1.0, 1.0],
        vec![
            ToolKey { t_s: 0.0, translation_mm: [25.0, 5.0, 2.5], rotation_xyzw: [0.0, 0.0, 0.0, 2.0] },
            ToolKey { t_s: 2.0, translation_mm: [30.0, 5.0, 2.5], rotation_xyzw: [0.0, 0.0, half.sin(), half.cos()] },
        ],
    ));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("roller.glb");
    write_glb(&path, &scene).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let json = glb_json(&bytes);
    assert_eq!(json["nodes"][2]["rotation"], serde_json::json!([0.0, 0.0, 0.0, 1.0]));
    assert_eq!(json["nodes"][2]["translation"], serde_json::json!([0.025, 0.005, 0.0025]));
    harness::validate(&[&path]);
}

#[test]
fn frames_files_round_trip_and_missing_ones_name_the_path() {
    let block = mesh::block([2.0, 1.0, 1.0], 0.5, "a").unwrap();
    let surface = SpecimenSurface::from_tet_mesh(&block).unwrap();
    let u = squash(&block, 0.3);
    let zero = vec![0.0; u.len()];
    let series = FrameSeries::from_nodal(
        3,
        block.nodes.len(),
        surface.nodes_used(),
        [(0.0, None, &zero[..]), (2.0, Some("final"), &u[..])],
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frames.bin");
    series.write(&path).unwrap();
    let back = FrameSeries::read(&path).unwrap();
    assert_eq!(back, series);
    // The surface sees the same displacement through the stored nodes alone.
    assert_eq!(surface.displacement_mm(&back.nodal(1)).unwrap(), surface.displacement_mm(&u).unwrap());
    let err = FrameSeries::read(Path::new("no/such/frames.bin")).unwrap_err();
    assert!(matches!(err, GltfError::Read { .. }) && err.to_string().starts_with("no/such/frames.bin: "), "{err}");
}
