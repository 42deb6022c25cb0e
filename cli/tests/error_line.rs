//! The one error line names each cause once: the libraries' errors print their
//! source in their own message and expose it as the source too, and the line
//! used to repeat it once per level of the chain.

mod common;

use common::*;

/// Plate friction on a glued plate is refused by the engine, through the
/// bundle's error (file, line, key) and the engine's effect error: the reason
/// stands in the line once.
#[test]
fn a_refused_effect_names_its_reason_once() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    std::fs::create_dir_all(cwd.join("trial")).unwrap();
    std::fs::write(
        cwd.join("trial/experiment.toml"),
        r#"format = "wagashi-experiment/1"
name = "gel"
dimension = 2

[specimen]
shape = "block"
size_mm = [20.0, 15.0, 10.0]
material = "gel"

[materials.gel]
model = "elastic"
poisson = 0.3
E_MPa = 0.05

[protocol]
tool = "plate"
tool_contact = "glued"
support = "glued"
waypoints = [[0.0, 0.0], [10.0, 1.5]]
release_s = 10.0
end_s = 10.0

[effects]
plate_friction = 0.3
"#,
    )
    .unwrap();
    let line = assert_one_line_error(&wagashi_in(cwd, ["press", "trial", "-o", "out"]));
    assert!(line.contains("experiment.toml:24: effects.plate_friction:"), "{line}");
    assert_eq!(line.matches("extends a frictionless plate").count(), 1, "{line}");
    assert!(!cwd.join("out").exists(), "no output on error");
}

/// A glTF buffer URI whose percent-escapes decode to bytes that are not UTF-8
/// (`%FF%FE.bin`) is one line naming the file and the cause, status 1: the
/// gltf crate, which panics on it, never sees the URI.
#[test]
fn a_gltf_uri_that_is_not_utf8_is_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    std::fs::write(
        cwd.join("tri.gltf"),
        r#"{"asset": {"version": "2.0"},
 "buffers": [{"uri": "%FF%FE.bin", "byteLength": 36}],
 "bufferViews": [{"buffer": 0, "byteLength": 36}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
 "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}
"#,
    )
    .unwrap();
    let line = assert_one_line_error(&wagashi_in(cwd, ["mesh", "tri.gltf", "-o", "t.vtu", "--size-mm", "0.5"]));
    assert!(line.contains("tri.gltf") && line.contains("do not decode to UTF-8"), "{line}");
    assert!(!cwd.join("t.vtu").exists(), "no output on error");
}
