//! Bad bundles: one case per refusal of experiment-format.md ("What a reader
//! must refuse"). Each case copies a good bundle, breaks one thing, and checks
//! that `wagashi press` exits with status 1 and one line naming the file, the
//! line and the field, and writes nothing.

mod common;

use std::path::PathBuf;

use common::*;

/// A good bundle to break: examples/markers-demo (markers on the front face)
/// with a measured force file added.
struct Trial {
    root: tempfile::TempDir,
    dir: PathBuf,
}

const FORCE: &str = "t_s,force_N\n0.0,0.0\n10.0,0.4\n28.87,1.1\n210.93,0.9\n400.0,0.0\n";

impl Trial {
    fn new() -> Self {
        Self::from_example("markers-demo")
    }

    fn from_example(name: &str) -> Self {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("trial");
        copy_dir(&example(name), &dir);
        let t = Self { root, dir };
        if name == "markers-demo" {
            t.edit("experiment.toml", "[data]\n", "[data]\nforce = \"force.csv\"\n");
            std::fs::write(t.dir.join("force.csv"), FORCE).unwrap();
        }
        t
    }

    fn path(&self, file: &str) -> PathBuf {
        self.dir.join(file)
    }

    fn read(&self, file: &str) -> String {
        std::fs::read_to_string(self.path(file)).unwrap()
    }

    /// Replaces the first `from` in `file` by `to`.
    fn edit(&self, file: &str, from: &str, to: &str) {
        let text = self.read(file);
        assert!(text.contains(from), "test setup: {from:?} not in {file}");
        std::fs::write(self.path(file), text.replacen(from, to, 1)).unwrap();
    }

    /// The 1-based line of `file` holding `needle`.
    fn line_of(&self, file: &str, needle: &str) -> usize {
        let text = self.read(file);
        text.lines().position(|l| l.contains(needle)).unwrap_or_else(|| panic!("{needle:?} not in {file}")) + 1
    }

    /// Runs `wagashi press` (plus `extra`); asserts a one-line refusal that leaves
    /// the bundle as it was and writes no output. Returns the line.
    fn refused(&self, extra: &[&str]) -> String {
        let before = contents(&self.dir);
        let out = self.root.path().join("out");
        let mut args =
            vec!["press".into(), self.dir.clone().into_os_string(), "-o".into(), out.clone().into_os_string()];
        args.extend(extra.iter().map(Into::into));
        let o = wagashi_in(self.root.path(), args);
        let line = assert_one_line_error(&o);
        assert_eq!(contents(&self.dir), before, "the bundle changed");
        assert!(!out.exists(), "an output was written");
        line
    }

    /// Asserts the refusal names `file:LINE: FIELD`.
    fn assert_names(&self, line: &str, file: &str, at: usize, field: &str) {
        let want = format!("{}:{at}: {field}", self.path(file).display());
        assert!(line.contains(&want), "expected {want:?} in\n{line}");
    }

    /// Edits `experiment.toml` and checks that the refusal names `field` on the
    /// line that now holds `needle`.
    fn refuse_toml(&self, from: &str, to: &str, needle: &str, field: &str) -> String {
        self.edit("experiment.toml", from, to);
        let at = self.line_of("experiment.toml", needle);
        let line = self.refused(&[]);
        self.assert_names(&line, "experiment.toml", at, field);
        line
    }

    /// Writes `file` and checks that the refusal names `field` on line `at`.
    fn refuse_csv(&self, file: &str, text: &str, at: usize, field: &str) -> String {
        std::fs::write(self.path(file), text).unwrap();
        let line = self.refused(&[]);
        self.assert_names(&line, file, at, field);
        line
    }
}

/// The base bundle itself is accepted (so each case below fails for its one edit).
#[test]
fn the_unbroken_bundle_runs() {
    let t = Trial::new();
    let out = t.root.path().join("out");
    let o = wagashi_in(
        t.root.path(),
        ["press".as_ref(), t.dir.as_os_str(), "-o".as_ref(), out.as_os_str(), "--size-mm".as_ref(), "20".as_ref()],
    );
    assert_success(&o);
    let summary = check_output(&out, 3);
    assert_eq!(summary["measured_force_samples"].as_u64(), Some(5));
    assert!(summary["force_rms_diff_N"].as_f64().unwrap() >= 0.0);
}

// ---- a missing file -------------------------------------------------------

#[test]
fn missing_experiment_toml() {
    let t = Trial::new();
    std::fs::remove_file(t.path("experiment.toml")).unwrap();
    let line = t.refused(&[]);
    assert!(line.contains(&format!("{}: cannot read", t.path("experiment.toml").display())), "{line}");
}

#[test]
fn missing_data_file() {
    let t = Trial::new();
    std::fs::remove_file(t.path("force.csv")).unwrap();
    let line = t.refused(&[]);
    assert!(line.contains(&format!("{}: cannot read", t.path("force.csv").display())), "{line}");
}

#[test]
fn missing_materials_file() {
    let t = Trial::new();
    let line = t.refused(&["--materials", "no-such-materials.toml"]);
    assert!(line.contains("no-such-materials.toml: cannot read"), "{line}");
}

// ---- a missing required key, an unknown key, a value of the wrong type ----

#[test]
fn missing_required_key() {
    let t = Trial::new();
    let line = t.refuse_toml("end_s = 400.0", "", "[protocol]", "protocol.end_s");
    assert!(line.contains("missing required key"), "{line}");
}

#[test]
fn unknown_key() {
    let t = Trial::new();
    let line = t.refuse_toml("mass_g = 52.43", "mass_g = 52.43\ncolour = \"white\"", "colour", "specimen.colour");
    assert!(line.contains("unknown key"), "{line}");
}

#[test]
fn unit_less_key() {
    let t = Trial::new();
    let line = t.refuse_toml("mass_g = 52.43", "mass = 52.43", "mass = ", "specimen.mass");
    assert!(line.contains("unknown key"), "{line}");
}

#[test]
fn wrong_type() {
    let t = Trial::new();
    let line = t.refuse_toml("dimension = 3", "dimension = \"three\"", "dimension", "dimension");
    assert!(line.contains("wrong type"), "{line}");
}

// ---- negative sizes, masses, times, moduli; Poisson's ratio ---------------

#[test]
fn negative_size() {
    let t = Trial::new();
    t.refuse_toml("size_mm = [58.0, 59.5, 12.0]", "size_mm = [58.0, -59.5, 12.0]", "size_mm", "specimen.size_mm");
}

#[test]
fn negative_mass() {
    let t = Trial::new();
    t.refuse_toml("mass_g = 52.43", "mass_g = -52.43", "mass_g", "specimen.mass_g");
}

#[test]
fn negative_time() {
    let t = Trial::new();
    t.refuse_toml("end_s = 400.0", "end_s = -400.0", "end_s", "protocol.end_s");
}

#[test]
fn negative_waypoint_time() {
    let t = Trial::new();
    t.refuse_toml("[[0.0, 0.0], [28.87", "[[-1.0, 0.0], [28.87", "waypoints =", "protocol.waypoints[0]");
}

#[test]
fn negative_modulus() {
    let t = Trial::new();
    t.refuse_toml("E1_MPa = 0.0349", "E1_MPa = -0.0349", "E1_MPa", "materials.mat1.E1_MPa");
}

#[test]
fn poisson_ratio_out_of_range() {
    let t = Trial::new();
    t.refuse_toml("poisson = 0.3746", "poisson = 0.5", "poisson", "materials.mat1.poisson");
}

#[test]
fn poisson_ratio_out_of_range_in_a_materials_file() {
    let t = Trial::new();
    let file = t.root.path().join("fitted.toml");
    std::fs::write(&file, "[materials.mat1]\nmodel = \"five-element\"\npoisson = -1.5\n").unwrap();
    let line = t.refused(&["--materials", file.to_str().unwrap()]);
    let want = format!("{}:3: materials.mat1.poisson", file.display());
    assert!(line.contains(&want), "expected {want:?} in\n{line}");
}

// ---- layers; materials ----------------------------------------------------

#[test]
fn layers_that_do_not_sum_to_h() {
    let t = Trial::from_example("paper/mat1+2");
    t.edit("experiment.toml", "thickness_mm = 26.666666666666668", "thickness_mm = 26.0");
    let at = t.line_of("experiment.toml", "[[specimen.layers]]");
    let line = t.refused(&[]);
    t.assert_names(&line, "experiment.toml", at, "specimen.layers");
}

#[test]
fn material_named_but_not_defined() {
    let t = Trial::new();
    t.refuse_toml("material = \"mat1\"", "material = \"mat9\"", "material = ", "specimen.material");
}

#[test]
fn layer_material_named_but_not_defined() {
    let t = Trial::from_example("paper/mat2+3");
    t.edit("experiment.toml", "material = \"mat3\"", "material = \"mat4\"");
    let at = t.line_of("experiment.toml", "mat4");
    let line = t.refused(&[]);
    t.assert_names(&line, "experiment.toml", at, "specimen.layers[1].material");
}

// ---- protocol -------------------------------------------------------------

#[test]
fn waypoints_not_in_increasing_time() {
    let t = Trial::new();
    t.refuse_toml("[210.93, 5.774]]", "[20.0, 5.774]]", "waypoints =", "protocol.waypoints[2]");
}

#[test]
fn release_before_the_last_push() {
    let t = Trial::new();
    t.refuse_toml("release_s = 210.93", "release_s = 10.0", "release_s", "protocol.release_s");
}

#[test]
fn end_before_the_last_push() {
    let t = Trial::new();
    t.refuse_toml("end_s = 400.0", "end_s = 20.0", "end_s", "protocol.end_s");
}

// ---- CSV files ------------------------------------------------------------

#[test]
fn csv_with_a_bad_header() {
    let t = Trial::new();
    t.refuse_csv("force.csv", "time,force\n0.0,0.0\n", 1, "header");
}

#[test]
fn markers_csv_with_a_2d_header_in_3d() {
    let t = Trial::new();
    t.refuse_csv("markers.csv", "marker,t_s,x_mm,y_mm\nm1,0.0,5.0,5.0\n", 1, "header");
}

#[test]
fn csv_with_a_non_numeric_cell() {
    let t = Trial::new();
    t.refuse_csv("force.csv", "t_s,force_N\n0.0,0.0\n0.1,about one\n", 3, "force_N");
}

#[test]
fn csv_with_nan() {
    let t = Trial::new();
    t.refuse_csv("force.csv", "t_s,force_N\n0.0,0.0\n0.1,NaN\n", 3, "force_N");
}

#[test]
fn csv_with_infinity() {
    let t = Trial::new();
    t.refuse_csv("force.csv", "t_s,force_N\n0.0,0.0\ninf,1.0\n", 3, "t_s");
}

#[test]
fn csv_with_time_going_backwards() {
    let t = Trial::new();
    let line = t.refuse_csv("force.csv", "t_s,force_N\n0.0,0.0\n0.2,0.1\n0.1,0.2\n", 4, "t_s");
    assert!(line.contains("backwards"), "{line}");
}

#[test]
fn marker_time_going_backwards() {
    let t = Trial::new();
    let text = "marker,t_s,x_mm,y_mm,z_mm\nm1,0.0,29.0,29.75,12.0\nm1,300.0,29.0,29.0,12.0\nm1,200.0,29.0,29.0,12.0\n";
    t.refuse_csv("markers.csv", text, 4, "t_s");
}

// ---- markers --------------------------------------------------------------

#[test]
fn marker_without_a_row_at_t_0() {
    let t = Trial::new();
    let text = "marker,t_s,x_mm,y_mm,z_mm\nm1,0.0,29.0,29.75,12.0\nm2,210.9,14.5,14.9,12.0\n";
    let line = t.refuse_csv("markers.csv", text, 3, "t_s");
    assert!(line.contains("m2"), "{line}");
}

#[test]
fn marker_not_on_the_surface() {
    let t = Trial::new();
    // The block is 58 x 59.5 x 12 mm; z = 6 is 6 mm deep, beyond 1 % of 12 mm.
    let text = "marker,t_s,x_mm,y_mm,z_mm\nm1,0.0,29.0,29.75,12.0\nm2,0.0,29.0,29.75,6.0\n";
    let line = t.refuse_csv("markers.csv", text, 3, "marker m2");
    assert!(line.contains("surface"), "{line}");
}

// ---- a surface specimen without its surface ----------------------------

#[test]
fn a_missing_specimen_surface_names_its_key() {
    let t = Trial::new();
    t.refuse_toml(
        "shape = \"block\"\nsize_mm = [58.0, 59.5, 12.0]",
        "shape = \"surface\"\nsurface = \"daifuku.obj\"",
        "surface = ",
        "specimen.surface",
    );
}
