//! Shared helpers of the end-to-end tests: run the real `wagashi` binary in a
//! temporary folder and check what it wrote.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

#[path = "../../../tests/support/data.rs"]
mod data;
#[allow(unused_imports)]
pub use data::{fixture, shared_data, shared_data_path, skip_without_shared_data};

/// The `experiment.toml` text (a `&'static str`) of a specimen of the seed's
/// material 1 (five-element) pressed by a plate: `name`, `dimension`, the
/// `[specimen]` lines before `material` (shape, sizes, mass) and the `[protocol]`
/// lines after `tool = "plate"`, each a string literal ending in a newline.
#[allow(unused_macros)] // not every test file builds a mat1 bundle
macro_rules! mat1_experiment {
    ($name:literal, $dimension:literal, $specimen:literal, $protocol:literal) => {
        concat!(
            "format = \"wagashi-experiment/1\"\nname = \"",
            $name,
            "\"\ndimension = ",
            $dimension,
            "\n\n[specimen]\n",
            $specimen,
            "material = \"mat1\"\n\n[materials.mat1]\nmodel = \"five-element\"\npoisson = 0.3746\n",
            "E1_MPa = 0.0349\nE2_MPa = 0.0221\nc1_MPa_s = 0.0071\nc2_MPa_s = 0.1869\nc3_MPa_s = 29.719\n\n",
            "[protocol]\ntool = \"plate\"\n",
            $protocol
        )
    };
}
#[allow(unused_imports)] // not every test file builds a mat1 bundle
pub(crate) use mat1_experiment;

/// Writes `files` (name, text) into the folder `dir` (created); returns `dir`.
pub fn write_files(dir: &Path, files: &[(&str, &str)]) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir.to_path_buf()
}

/// The repository's `examples/` folder.
pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples").canonicalize().unwrap()
}

/// The bundle `examples/NAME`.
pub fn example(name: &str) -> PathBuf {
    examples().join(name)
}

/// The six Table I bundles and the 2D one.
pub const PAPER_BUNDLES: [&str; 7] = ["mat1", "mat2", "mat3", "mat1+2", "mat2+3", "mat1+3", "mat1-2d"];

/// Runs `wagashi ARGS` in `cwd` with no standard input.
pub fn wagashi_in<I, S>(cwd: &Path, args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_wagashi"))
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .output()
        .expect("the wagashi binary runs")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts exit status 0, showing the output otherwise.
pub fn assert_success(o: &Output) {
    assert!(o.status.success(), "exit {:?}\nstdout:\n{}\nstderr:\n{}", o.status.code(), stdout(o), stderr(o));
}

/// Asserts a failure with exit status 1 and one line `error: ...` on stderr; returns that line.
pub fn assert_one_line_error(o: &Output) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "stdout:\n{}\nstderr:\n{err}", stdout(o));
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line expected:\n{err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    lines[0].to_string()
}

/// Every file under `dir` (relative path -> content), to compare before and after.
pub fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                out.insert(path.strip_prefix(root).unwrap().to_path_buf(), std::fs::read(&path).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Copies the folder `from` (files only, recursively) to `to`.
pub fn copy_dir(from: &Path, to: &Path) {
    for (rel, bytes) in contents(from) {
        let path = to.join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
}

/// `force.csv`: checks the exact header and parses every row.
pub fn read_force_csv(path: &Path) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t_s,force_N"), "{}", path.display());
    lines
        .map(|l| {
            let (t, f) = l.split_once(',').unwrap_or_else(|| panic!("bad row {l:?}"));
            let (t, f): (f64, f64) = (t.parse().unwrap(), f.parse().unwrap());
            assert!(t.is_finite() && f.is_finite(), "{l}");
            (t, f)
        })
        .collect()
}

/// `summary.json` as JSON, with the keys every run writes checked.
pub fn read_summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "name",
        "dimension",
        "cells",
        "nodes",
        "free_dofs",
        "integrator",
        "size_mm",
        "steps",
        "factorizations",
        "factor_nonzeros",
        "wall_time_s",
        "peak_force_N",
        "force_end_of_hold_N",
        "final_height_loss_mm",
        "keep_time_s",
        "final_time_s",
        "force_rms_diff_N",
        "force_max_abs_diff_N",
    ] {
        assert!(v.get(key).is_some(), "summary.json lacks `{key}`: {text}");
    }
    for key in ["cells", "nodes", "free_dofs", "steps", "factorizations", "factor_nonzeros"] {
        assert!(v[key].as_u64().unwrap() > 0, "{key} = {}", v[key]);
    }
    for key in ["size_mm", "wall_time_s", "peak_force_N", "keep_time_s", "final_time_s"] {
        assert!(v[key].as_f64().unwrap() > 0.0, "{key} = {}", v[key]);
    }
    assert!(v["final_height_loss_mm"].as_f64().unwrap().is_finite());
    assert!(v["force_end_of_hold_N"].as_f64().unwrap().is_finite());
    v
}

/// Parses a `.vtu` and checks its counts and arrays; returns (points, cells).
pub fn check_vtu(path: &Path, num_nodes: u64, num_cells: u64, cell_type: u8) -> (usize, usize) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let doc = roxmltree::Document::parse(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "VTKFile");
    assert_eq!(root.attribute("type"), Some("UnstructuredGrid"));
    let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).expect("a Piece");
    let points: usize = piece.attribute("NumberOfPoints").unwrap().parse().unwrap();
    let cells: usize = piece.attribute("NumberOfCells").unwrap().parse().unwrap();
    assert_eq!((points as u64, cells as u64), (num_nodes, num_cells), "{}", path.display());
    let array = |name: &str| {
        doc.descendants()
            .find(|n| n.has_tag_name("DataArray") && n.attribute("Name") == Some(name))
            .unwrap_or_else(|| panic!("{}: no DataArray {name}", path.display()))
    };
    let values = |name: &str| -> Vec<f64> {
        array(name).text().unwrap_or("").split_whitespace().map(|x| x.parse().unwrap()).collect()
    };
    assert_eq!(values("displacement").len(), 3 * points);
    assert!(values("displacement").iter().all(|x| x.is_finite()));
    assert_eq!(values("region").len(), cells);
    assert_eq!(values("stress").len(), 6 * cells);
    assert!(values("types").iter().all(|&t| t == f64::from(cell_type)));
    (points, cells)
}

/// Checks the output folder of a successful `press`: the files, force.csv,
/// summary.json and both shapes. Returns the summary.
pub fn check_output(out: &Path, dimension: u64) -> serde_json::Value {
    for f in ["experiment.toml", "force.csv", "summary.json", "steps.csv", "keep.vtu", "final.vtu", "force.svg"] {
        assert!(out.join(f).is_file(), "{} missing", out.join(f).display());
    }
    let summary = read_summary(out);
    assert_eq!(summary["dimension"].as_u64(), Some(dimension));
    let force = read_force_csv(&out.join("force.csv"));
    assert_eq!(force.len() as u64, summary["force_samples"].as_u64().unwrap());
    assert!(force.windows(2).all(|w| w[0].0 <= w[1].0), "force.csv times in order");
    let peak = summary["peak_force_N"].as_f64().unwrap();
    assert!(force.iter().any(|&(_, f)| f > 0.5 * peak), "force.csv holds the curve");
    let (nodes, cells) = (summary["nodes"].as_u64().unwrap(), summary["cells"].as_u64().unwrap());
    let cell_type = if dimension == 2 { 5 } else { 10 };
    check_vtu(&out.join("keep.vtu"), nodes, cells, cell_type);
    check_vtu(&out.join("final.vtu"), nodes, cells, cell_type);
    let steps = std::fs::read_to_string(out.join("steps.csv")).unwrap();
    let mut lines = steps.lines();
    assert_eq!(lines.next(), Some("t_s,dt_s,solve_s,residual,refactored,bottom_force_N,plate_force_N"));
    assert_eq!(lines.count() as u64, summary["steps"].as_u64().unwrap());
    let svg = std::fs::read_to_string(out.join("force.svg")).unwrap();
    roxmltree::Document::parse(&svg).expect("force.svg is well-formed XML");
    assert!(svg.contains("time [s]") && svg.contains("[N]"));
    let shape = std::fs::read_to_string(out.join("shape.svg")).unwrap();
    roxmltree::Document::parse(&shape).expect("shape.svg is well-formed XML");
    for needle in ["x [mm]", "y [mm]", "start", "keep, t = ", "end, t = "] {
        assert!(shape.contains(needle), "shape.svg lacks {needle:?}");
    }
    // No temporary folders are left beside the output.
    let parent = out.parent().unwrap();
    for entry in std::fs::read_dir(parent).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.contains(".tmp-") && !name.contains(".old-"), "leftover {name}");
    }
    summary
}

/// Runs `wagashi press BUNDLE -o OUT EXTRA...` in `cwd`.
pub fn press_in(cwd: &Path, bundle: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args: Vec<std::ffi::OsString> =
        vec!["press".into(), bundle.as_os_str().into(), "-o".into(), out.as_os_str().into()];
    args.extend(extra.iter().map(Into::into));
    wagashi_in(cwd, args)
}
