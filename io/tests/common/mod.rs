//! Shared helpers of the io tests: a valid bundle to start from, edits, and
//! assertions on `FILE:LINE: FIELD: CAUSE` messages.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use wagashi_io::BundleError;

#[path = "../../../tests/support/data.rs"]
mod data;
#[allow(unused_imports)]
pub use data::{fixture, shared_data, shared_data_path, skip_without_shared_data};

/// The `experiment.toml` text (a `&'static str`) of an elastic gel (E = 0.05
/// MPa, nu = 0.45) pressed by a plate: `name`, `dimension`, the `[specimen]`
/// lines before `material` (shape and sizes) and the `[protocol]` lines after
/// `tool = "plate"`, each a string literal ending in a newline.
#[allow(unused_macros)] // not every test file builds a gel bundle
macro_rules! gel_experiment {
    ($name:literal, $dimension:literal, $specimen:literal, $protocol:literal) => {
        concat!(
            "format = \"wagashi-experiment/1\"\nname = \"",
            $name,
            "\"\ndimension = ",
            $dimension,
            "\n\n[specimen]\n",
            $specimen,
            "material = \"gel\"\n\n[materials.gel]\nmodel = \"elastic\"\npoisson = 0.45\nE_MPa = 0.05\n\n[protocol]\ntool = \"plate\"\n",
            $protocol
        )
    };
}
#[allow(unused_imports)] // not every test file builds a gel bundle
pub(crate) use gel_experiment;

/// The gel cylinder (R = 4 mm, H = 9 mm) between frictionless plates, pushed
/// 0.9 mm in 2 s, with markers.
pub const GEL_CYLINDER: &str = gel_experiment!(
    "gel",
    3,
    r#"shape = "cylinder"
radius_mm = 4.0
height_mm = 9.0
"#,
    r#"tool_contact = "frictionless"
support = "frictionless"
waypoints = [[0.0, 0.0], [2.0, 0.9]]
release_s = 2.0
end_s = 10.0

[data]
markers = "markers.csv"
"#
);

/// A valid 3D block bundle (experiment-format.md's example).
pub const EXPERIMENT: &str = r#"format = "wagashi-experiment/1"
name = "mat1-uniform"
dimension = 3

[specimen]
shape = "block"
size_mm = [58.0, 59.5, 12.0]
mass_g = 52.43
material = "mat1"

[materials.mat1]
model = "five-element"
poisson = 0.3746
E1_MPa = 0.0349
E2_MPa = 0.0221
c1_MPa_s = 0.0071
c2_MPa_s = 0.1869
c3_MPa_s = 29.719

[protocol]
tool = "plate"
tool_contact = "glued"
support = "glued"
waypoints = [[0.0, 0.0], [28.87, 5.774], [210.93, 5.774]]
release_s = 210.93
end_s = 400.0

[data]
force = "force.csv"
markers = "markers.csv"
force_tared = true
"#;

pub const FORCE: &str = "t_s,force_N
0.0,0.0
0.1,0.0049
28.87,5.2
400.0,0.1
";

pub const MARKERS: &str = "marker,t_s,x_mm,y_mm,z_mm
m01,0.0,5.0,5.0,12.0
m01,210.9,4.6,4.9,12.0
m01,400.0,4.9,5.0,12.0
m02,0.0,29.0,59.5,6.0
m02,400.0,29.0,58.0,6.0
";

/// A bundle folder in a fresh temporary folder; the bundle is `dir/trial`.
pub struct TestBundle {
    pub root: tempfile::TempDir,
    pub dir: PathBuf,
}

impl TestBundle {
    pub fn file(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }
}

/// Writes `files` (name, content) into a new bundle folder.
pub fn bundle(files: &[(&str, &str)]) -> TestBundle {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("trial");
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    TestBundle { root, dir }
}

/// The default bundle with `experiment.toml` replaced.
pub fn with_experiment(toml: &str) -> TestBundle {
    bundle(&[("experiment.toml", toml), ("force.csv", FORCE), ("markers.csv", MARKERS)])
}

/// `text` with the first occurrence of `from` replaced (which must exist).
pub fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "test setup: `{from}` not in the text");
    text.replacen(from, to, 1)
}

/// The 1-based line of the first line of `text` that contains `needle`.
pub fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap_or_else(|| panic!("test setup: `{needle}` not in the text"))
        + 1
}

/// Asserts a content refusal displayed as `FILE:LINE: FIELD: ...`; returns the message.
pub fn assert_invalid(
    result: Result<impl std::fmt::Debug, BundleError>,
    file: &Path,
    line: usize,
    field: &str,
) -> String {
    let err = result.expect_err("the bundle must be refused");
    let msg = err.to_string();
    let prefix = format!("{}:{line}: {field}: ", file.display());
    assert!(matches!(err, BundleError::Invalid { .. }), "expected Invalid, got {err:?}");
    assert!(msg.starts_with(&prefix), "expected `{prefix}...`\n     got `{msg}`");
    msg
}
