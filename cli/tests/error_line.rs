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
