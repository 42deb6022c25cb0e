//! Bad bundles: one case per refusal of experiment-format.md ("What a reader
//! must refuse"). Each case copies a good bundle, breaks one thing, and checks
//! that `wagashi press` exits with status 1 and one line naming the file, the
//! line and the field, and writes nothing.

mod common;

use std::path::{Path, PathBuf};

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

// ---- outputs never touch inputs or files wagashi did not write -------------

/// `press EXAMPLE -o OUT --size-mm 20` plus `extra`, in `cwd`.
fn press_example(cwd: &Path, name: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args: Vec<std::ffi::OsString> =
        vec!["press".into(), example(name).into(), "-o".into(), out.into(), "--size-mm".into(), "20".into()];
    args.extend(extra.iter().map(Into::into));
    wagashi_in(cwd, args)
}

/// A closed cube of side 4 mm, outward triangles, as OBJ text.
const CUBE_OBJ: &str = "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 0 0 4\nv 4 0 4\nv 4 4 4\nv 0 4 4\n\
f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";

/// `mesh IN.obj --report IN.obj` would replace the input with the report, and
/// `--report` onto the mesh would replace the mesh: both refused, nothing written.
#[test]
fn mesh_outputs_may_not_be_the_input() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("cube.obj"), CUBE_OBJ).unwrap();
    let cases: [(&[&str], &str); 2] = [
        (&["mesh", "cube.obj", "-o", "x.vtu", "--size-mm", "1", "--report", "cube.obj"], "--report may not be"),
        (&["mesh", "cube.obj", "-o", "x.vtu", "--size-mm", "1", "--report", "x.vtu"], "--report would overwrite"),
    ];
    for (args, want) in cases {
        let line = assert_one_line_error(&wagashi_in(tmp.path(), args));
        assert!(line.contains(want), "{args:?}: {line}");
        assert_eq!(std::fs::read_to_string(tmp.path().join("cube.obj")).unwrap(), CUBE_OBJ);
        assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1, "{args:?}: something was written");
    }
}

/// `-o x.node` writes x.node, x.ele and x.face: an existing one that wagashi
/// did not write is replaced only with --force; wagashi's own are replaced.
#[test]
fn mesh_replaces_a_foreign_tetgen_file_only_with_force() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("cube.obj"), CUBE_OBJ).unwrap();
    std::fs::write(tmp.path().join("x.ele"), "# my own mesh\n0 4 0\n").unwrap();
    let run = |force: bool| {
        let mut args = vec!["mesh", "cube.obj", "-o", "x.node", "--size-mm", "1"];
        if force {
            args.push("--force");
        }
        wagashi_in(tmp.path(), args)
    };
    let line = assert_one_line_error(&run(false));
    assert!(line.contains("x.ele") && line.contains("--force"), "{line}");
    assert_eq!(std::fs::read_to_string(tmp.path().join("x.ele")).unwrap(), "# my own mesh\n0 4 0\n");
    assert!(!tmp.path().join("x.node").exists() && !tmp.path().join("x.face").exists());
    assert_success(&run(true));
    assert!(std::fs::read_to_string(tmp.path().join("x.ele")).unwrap().starts_with("# written by wagashi"));
    // Now all three are wagashi's: a second run replaces them without --force.
    assert_success(&run(false));
}

/// A materials file inside the output folder is an input: `--force` may not
/// delete it, even when the folder's manifest lists it (as `fit`'s does).
#[test]
fn press_never_replaces_its_own_materials_file() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    assert_success(&press_example(tmp.path(), "paper/mat1-2d", &out, &[]));
    std::fs::copy(example("paper/x-shape.toml"), out.join("materials.toml")).unwrap();
    let manifest_path = out.join("wagashi-manifest.json");
    let mut manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest_path).unwrap()).unwrap();
    manifest["files"].as_array_mut().unwrap().push("materials.toml".into());
    std::fs::write(&manifest_path, manifest.to_string()).unwrap();
    let before = contents(&out);
    let materials = out.join("materials.toml");
    let o = press_example(tmp.path(), "paper/mat1-2d", &out, &["--materials", materials.to_str().unwrap(), "--force"]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("input materials file"), "{line}");
    assert_eq!(contents(&out), before);
}

/// `export OUT --gltf OUT/x.glb` would write into the folder it reads.
#[test]
fn export_may_not_write_into_its_source() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    assert_success(&press_example(tmp.path(), "paper/mat1-2d", &out, &[]));
    let before = contents(&out);
    let glb = out.join("x.glb");
    let o = wagashi_in(tmp.path(), ["export".as_ref(), out.as_os_str(), "--gltf".as_ref(), glb.as_os_str()]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("input press output"), "{line}");
    assert_eq!(contents(&out), before);
}

/// `--force` replaces only a folder whose wagashi manifest lists every file in
/// it: a folder that merely holds a summary.json (a file or a link), or a
/// previous output the user added a file to, is refused untouched.
#[test]
fn force_trusts_only_a_wagashi_manifest() {
    let tmp = tempfile::tempdir().unwrap();
    let fake = tmp.path().join("fake");
    std::fs::create_dir(&fake).unwrap();
    std::fs::write(fake.join("summary.json"), "{}").unwrap();
    std::fs::write(fake.join("data.csv"), "mine").unwrap();
    let before = contents(&fake);
    let line = assert_one_line_error(&press_example(tmp.path(), "paper/mat1-2d", &fake, &["--force"]));
    assert!(line.contains("refusing to overwrite") && line.contains("manifest"), "{line}");
    assert_eq!(contents(&fake), before);

    let linked = tmp.path().join("linked");
    std::fs::create_dir(&linked).unwrap();
    std::fs::write(linked.join("data.csv"), "mine").unwrap();
    std::os::unix::fs::symlink(fake.join("summary.json"), linked.join("summary.json")).unwrap();
    assert_one_line_error(&press_example(tmp.path(), "paper/mat1-2d", &linked, &["--force"]));
    assert_eq!(std::fs::read_to_string(linked.join("data.csv")).unwrap(), "mine");

    let out = tmp.path().join("out");
    assert_success(&press_example(tmp.path(), "paper/mat1-2d", &out, &[]));
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let before = contents(&out);
    let line = assert_one_line_error(&press_example(tmp.path(), "paper/mat1-2d", &out, &["--force"]));
    assert!(line.contains("notes.txt is not a file wagashi wrote"), "{line}");
    assert_eq!(contents(&out), before);
}

// ---- bounded runs ------------------------------------------------------------

/// `--dt 1e-9` over the 400 s trial asks for 4e11 steps: refused before the
/// run, as `--output-dt`'s sample count is.
#[test]
fn a_fixed_step_count_beyond_the_limit_is_refused_before_the_run() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let clock = std::time::Instant::now();
    let line = assert_one_line_error(&press_example(tmp.path(), "paper/mat1-2d", &out, &["--dt", "1e-9"]));
    assert!(line.contains("--dt 0.000000001 s gives 4.000e11 steps") && line.contains("at most"), "{line}");
    assert!(clock.elapsed().as_secs_f64() < 5.0);
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

/// The seed block at 0.3 mm (9.27M tetrahedra) is refused before meshing with
/// one line naming the estimate, the available memory and the option, by
/// `press`, `fit` and `diagnose`; where
/// the machine has the memory, the test says so and passes.
#[test]
fn a_mesh_beyond_the_available_memory_is_refused_before_meshing() {
    let available_gib = std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        let line = m.lines().find(|l| l.starts_with("MemAvailable:"))?.to_string();
        Some(line.split_whitespace().nth(1)?.parse::<f64>().ok()? / 1024.0 / 1024.0)
    });
    // The estimate for this mesh is about 106 GiB.
    match available_gib {
        Some(gib) if gib < 100.0 => {}
        other => {
            println!("skipped: the machine's available memory ({other:?} GiB) is not below the estimate");
            return;
        }
    }
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let bundle = example("paper/mat1");
    let args = ["press", bundle.to_str().unwrap(), "-o", "out", "--size-mm", "0.3"];
    let clock = std::time::Instant::now();
    let line = assert_one_line_error(&wagashi_in(tmp.path(), args));
    for want in ["--size-mm 0.3", "9.203M tetrahedra", "GiB available", "MemAvailable", "--allow-large"] {
        assert!(line.contains(want), "{want}: {line}");
    }
    assert!(clock.elapsed().as_secs_f64() < 5.0);
    assert!(!out.exists());
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
    // fit checks each 3D trial the same way, naming it (the seed block with a measured force).
    let t = Trial::new();
    let args = ["fit", t.dir.to_str().unwrap(), "-o", "out", "--size-mm", "0.3"];
    let line = assert_one_line_error(&wagashi_in(tmp.path(), args));
    assert!(line.contains("experiment.toml: --size-mm 0.3") && line.contains("--allow-large"), "{line}");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
    let args = ["diagnose", "--calibrate", t.dir.to_str().unwrap(), "-o", "out", "--size-mm", "0.3"];
    let line = assert_one_line_error(&wagashi_in(tmp.path(), args));
    assert!(line.contains("experiment.toml: --size-mm 0.3") && line.contains("--allow-large"), "{line}");
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 0);
}

// ---- interrupts ----------------------------------------------------------------

/// SIGTERM and SIGINT during a run: exit status 130, one line, and neither the
/// output nor its hidden temporary folder is left.
#[test]
fn an_interrupted_run_leaves_nothing_behind() {
    for signal in ["TERM", "INT"] {
        let tmp = tempfile::tempdir().unwrap();
        let child = std::process::Command::new(env!("CARGO_BIN_EXE_wagashi"))
            .args(["press", example("paper/mat1").to_str().unwrap(), "-o", "out", "--size-mm", "1.5"])
            .current_dir(tmp.path())
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // Wait for the temporary output folder, then a little into the run.
        let clock = std::time::Instant::now();
        while std::fs::read_dir(tmp.path()).unwrap().count() == 0 {
            assert!(clock.elapsed().as_secs() < 30, "no temporary folder appeared");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::thread::sleep(std::time::Duration::from_millis(300));
        let kill = std::process::Command::new("kill").args([format!("-{signal}"), child.id().to_string()]).status();
        assert!(kill.unwrap().success());
        let o = child.wait_with_output().unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(130), "SIG{signal}: {err}");
        assert_eq!(err.lines().count(), 1, "SIG{signal}: {err}");
        assert!(err.starts_with("error: interrupted: ") && err.contains("removed"), "SIG{signal}: {err}");
        let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert!(left.is_empty(), "SIG{signal}: left behind: {left:?}");
    }
}

/// A run killed outright (SIGKILL: no handler runs) leaves `.out.tmp-PID-*`;
/// the next run on the same output removes it and says so.
#[test]
fn the_next_run_removes_a_killed_runs_temporary_folder() {
    let tmp = tempfile::tempdir().unwrap();
    // Above Linux's largest process id (2^22): no running process has it.
    let stale = tmp.path().join(".out.tmp-4999999-Ab12Cd");
    std::fs::create_dir(&stale).unwrap();
    std::fs::write(stale.join("force.csv"), "t_s,force_N\n0,0\n").unwrap();
    let o = press_example(tmp.path(), "paper/mat1-2d", &tmp.path().join("out"), &[]);
    assert_success(&o);
    assert!(
        stderr(&o).contains(&format!("note: removed {}, left by an interrupted run", stale.display())),
        "{}",
        stderr(&o)
    );
    assert!(!stale.exists());
    let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left, vec![std::ffi::OsString::from("out")]);
}

// ---- glTF files with external buffers ------------------------------------------

/// A closed box from `lo` to `hi` (outward triangles) as a glTF file whose
/// positions and indices live in the external buffer `bin_name`: the JSON text
/// and the buffer's bytes.
fn box_gltf(lo: [f64; 3], hi: [f64; 3], bin_name: &str) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    for i in 0..8 {
        for k in 0..3 {
            let x = if i >> (2 - k) & 1 == 1 { hi[k] } else { lo[k] };
            bin.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
    let quads = [[5, 7, 8, 6], [1, 2, 4, 3], [3, 4, 8, 7], [1, 5, 6, 2], [2, 6, 8, 4], [1, 3, 7, 5]];
    for f in quads {
        for v in [f[0], f[1], f[2], f[0], f[2], f[3]] {
            bin.extend_from_slice(&(v as u16 - 1).to_le_bytes());
        }
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"name":"box","primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":8,"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},
{{"bufferView":1,"componentType":5123,"count":36,"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":96}},{{"buffer":0,"byteOffset":96,"byteLength":72}}],
"buffers":[{{"uri":"{bin_name}","byteLength":168}}]}}"#,
        lo[0] as f32, lo[1] as f32, lo[2] as f32, hi[0] as f32, hi[1] as f32, hi[2] as f32
    );
    (json, bin)
}

/// `mesh scene.gltf --report scene.bin` would replace the glTF's buffer: the
/// files a glTF input names are inputs too, refused even with --force.
#[test]
fn mesh_outputs_may_not_be_a_gltf_inputs_buffer() {
    let tmp = tempfile::tempdir().unwrap();
    let (json, bin) = box_gltf([0.0; 3], [0.004; 3], "scene.bin");
    std::fs::write(tmp.path().join("scene.gltf"), &json).unwrap();
    std::fs::write(tmp.path().join("scene.bin"), &bin).unwrap();
    let before = contents(tmp.path());
    for args in [
        ["mesh", "scene.gltf", "-o", "x.vtu", "--size-mm", "1", "--report", "scene.bin", "--force"],
        ["mesh", "scene.gltf", "-o", "x.vtu", "--size-mm", "1", "--report", "./scene.bin", "--force"],
    ] {
        let line = assert_one_line_error(&wagashi_in(tmp.path(), args));
        assert!(line.contains("scene.bin") && line.contains("file of the glTF surface"), "{args:?}: {line}");
        assert_eq!(contents(tmp.path()), before, "{args:?}");
    }
    assert_success(&wagashi_in(tmp.path(), ["mesh", "scene.gltf", "-o", "x.vtu", "--size-mm", "1"]));
}

/// A `.gltf` tool surface whose data lie in an external buffer is copied into
/// the output with that buffer (renamed beside it), so the output reads back
/// as a bundle.
#[test]
fn a_gltf_tool_travels_with_its_buffer() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = tmp.path().join("lid");
    std::fs::create_dir_all(bundle.join("shapes")).unwrap();
    let (json, bin) = box_gltf([-30.0, 10.0, -40.0], [50.0, 50.0, 40.0], "lid%20data.bin");
    std::fs::write(bundle.join("shapes/lid.gltf"), json).unwrap();
    std::fs::write(bundle.join("shapes/lid data.bin"), &bin).unwrap();
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
tool_surface = "shapes/lid.gltf"
tool_surface_units = "mm"
tool_contact = "frictionless"
support = "glued"
waypoints = [[0.0, 0.0], [10.0, 1.0]]
release_s = 10.0
end_s = 10.0
"#;
    std::fs::write(bundle.join("experiment.toml"), toml).unwrap();
    let out = tmp.path().join("out");
    assert_success(&press_in(tmp.path(), &bundle, &out, &["--size-mm", "2"]));
    assert_eq!(std::fs::read(out.join("tools/surface.buffer0.bin")).unwrap(), bin);
    let listed = read_summary(&out)["files"].clone();
    let listed: Vec<&str> = listed.as_array().unwrap().iter().map(|f| f.as_str().unwrap()).collect();
    assert!(listed.contains(&"tools/surface.gltf") && listed.contains(&"tools/surface.buffer0.bin"), "{listed:?}");
    let copy: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("tools/surface.gltf")).unwrap()).unwrap();
    assert_eq!(copy["buffers"][0]["uri"], "surface.buffer0.bin");
    // The output is a bundle that reads back, its tool included.
    assert_success(&press_in(tmp.path(), &out, &tmp.path().join("again"), &["--size-mm", "2"]));
}

/// A single-file write killed outright leaves `.NAME.tmp-PID-*` beside the
/// file; the next run writing that file removes it and says so.
#[test]
fn the_next_run_removes_a_killed_single_file_writes_temporary() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("cube.obj"), CUBE_OBJ).unwrap();
    // Above Linux's largest process id (2^22): no running process has it.
    let stale = [tmp.path().join(".x.vtu.tmp-4999999-Ab12Cd"), tmp.path().join(".r.json.tmp-4999999-Ef34Gh")];
    for s in &stale {
        std::fs::write(s, "partial").unwrap();
    }
    let o = wagashi_in(tmp.path(), ["mesh", "cube.obj", "-o", "x.vtu", "--size-mm", "1", "--report", "r.json"]);
    assert_success(&o);
    for s in &stale {
        let name = s.file_name().unwrap().to_string_lossy();
        let note = format!("{name}, left by an interrupted run");
        assert!(stderr(&o).contains(&note), "{note}: {}", stderr(&o));
        assert!(!s.exists());
    }
    let mut left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    left.sort();
    assert_eq!(left, ["cube.obj", "r.json", "x.vtu"].map(std::ffi::OsString::from));
}
