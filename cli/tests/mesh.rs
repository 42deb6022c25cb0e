//! `wagashi mesh`: the real binary on the bunny (`tests/fixtures`) and the
//! shared mesh fixtures (`<workspace>/../shared/data/meshes`, never copied into
//! the repository; a test that reads them skips without them, see
//! `tests/support/data.rs`).

use std::path::{Path, PathBuf};

mod common;

use common::{
    assert_one_line_error, assert_success, fixture, shared_data_path, skip_without_shared_data, stderr, stdout,
    wagashi_in,
};
use wagashi_io::tetmesh::read_tetmesh;

/// The mesh fixture `name`: the repository's (`tests/fixtures`) when it has it,
/// else the shared data folder's (the test has checked that the folder is there).
fn mesh_data(name: &str) -> PathBuf {
    let fixture = fixture(name);
    if fixture.is_file() {
        return fixture.canonicalize().unwrap();
    }
    let path = shared_data_path().join("meshes").join(name);
    assert!(path.is_file(), "{} is missing from the shared data folder", path.display());
    path.canonicalize().unwrap()
}

fn mesh(cwd: &Path, args: &[&str]) -> std::process::Output {
    let mut all = vec!["mesh"];
    all.extend_from_slice(args);
    wagashi_in(cwd, all)
}

/// `wagashi mesh` of the shared mesh `name` to `out` at `size_mm` with a JSON
/// report `r.json` and the arguments `more`, in `cwd`, asserted successful: its
/// standard output and the report.
fn mesh_with_report(cwd: &Path, name: &str, out: &str, size_mm: &str, more: &[&str]) -> (String, serde_json::Value) {
    let input = mesh_data(name);
    let mut args = vec![input.to_str().unwrap(), "-o", out, "--size-mm", size_mm, "--report", "r.json"];
    args.extend_from_slice(more);
    let o = mesh(cwd, &args);
    assert_success(&o);
    let json = serde_json::from_str(&std::fs::read_to_string(cwd.join("r.json")).unwrap()).unwrap();
    (stdout(&o), json)
}

#[test]
fn the_bunny_to_vtu_with_a_json_report() {
    let dir = tempfile::tempdir().unwrap();
    let (out, json) = mesh_with_report(dir.path(), "npm_bunny.obj", "bunny.vtu", "0.4", &[]);
    for key in
        ["dihedral angles", "radius-edge", "radius ratio", "volume", "Hausdorff", "Hausdorff (raw)", "region", "time"]
    {
        assert!(out.contains(key), "{key} missing:\n{out}");
    }
    let q = &json["quality"];
    let cells = q["num_cells"].as_u64().unwrap();
    let nodes = q["num_nodes"].as_u64().unwrap();
    assert!(cells > 10_000, "{cells}");
    assert!(q["min_dihedral_deg"].as_f64().unwrap() >= 12.0, "{q}");
    assert!(q["max_dihedral_deg"].as_f64().unwrap() <= 155.0, "{q}");
    assert!(q["volume_error"].as_f64().unwrap().abs() < 1e-2, "{q}");
    for key in [
        "fraction_below_10_deg",
        "max_radius_edge",
        "p999_radius_edge",
        "mean_radius_ratio",
        "hausdorff_relative",
        "raw_hausdorff_relative",
        "hole_cap_relative",
        "mesh_time_s",
    ] {
        assert!(q[key].as_f64().unwrap().is_finite(), "{key}");
    }
    // A closed input: no hole, so no cap row and no cap figures.
    assert!(!out.contains("hole caps"), "{out}");
    assert_eq!(q["num_border_edges"].as_u64(), Some(0));
    // A structural zero (nothing measured), not a computed one.
    assert!(q["cap_to_level_set_relative"].as_f64().unwrap() <= 0.0, "{q}");
    assert_eq!(json["input"]["triangles"].as_u64(), Some(3674));
    assert_eq!(json["mode"], "envelope");
    assert_eq!(json["quality"]["regions"].as_array().unwrap().len(), 1);
    // The VTU holds what the report says.
    let text = std::fs::read_to_string(dir.path().join("bunny.vtu")).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
    assert_eq!(piece.attribute("NumberOfCells").unwrap().parse::<u64>().unwrap(), cells);
    assert_eq!(piece.attribute("NumberOfPoints").unwrap().parse::<u64>().unwrap(), nodes);
}

/// The bunny with a hole, in envelope mode at 0.8 mm: the mesh closes the hole
/// with a cap on the level set `w = 1/2`. The report's "hole caps" row and its
/// JSON keys give the cap's distance from the input (about the hole's radius)
/// and from the level set, measured at the cap's vertices by the report's
/// normal probe, whose floor is 9e-7 of the diagonal.
/// Measured: 12 border edges, widest hole 1.866 mm, caps 2.89e-2 of
/// the diagonal from the input and 9.0e-7 (the floor) from the level set.
/// Asserted: the caps' vertices within 1e-6 of the diagonal of the level set,
/// and the cap farther from the input than that.
#[test]
fn a_holed_bunny_reports_its_caps_on_the_level_set() {
    if skip_without_shared_data("the mesh fixture bad_syn_hole.obj") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (out, json) = mesh_with_report(dir.path(), "bad_syn_hole.obj", "h.vtu", "0.8", &[]);
    let row = out.lines().find(|l| l.trim_start().starts_with("hole caps")).unwrap_or_else(|| panic!("{out}"));
    assert!(row.contains("from the level set") && row.contains("border edges"), "{row}");
    let q = &json["quality"];
    assert!(q["num_border_edges"].as_u64().unwrap() > 0, "{q}");
    let to_level_set = q["cap_to_level_set_relative"].as_f64().unwrap();
    let from_input = q["hole_cap_relative"].as_f64().unwrap();
    assert!((0.0..=1e-6).contains(&to_level_set), "{q}");
    assert!(from_input > 1e-3, "{q}");
    let fraction = q["hole_cap_fraction"].as_f64().unwrap();
    assert!(fraction > 0.0 && fraction < 0.05, "{q}");
}

#[test]
fn the_layered_bunny_to_gmsh_and_tetgen_keeps_its_three_regions() {
    if skip_without_shared_data("the mesh fixture layered_bunny.obj") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let layered = mesh_data("layered_bunny.obj");
    for out in ["l.msh", "l.node"] {
        let o = mesh(dir.path(), &[layered.to_str().unwrap(), "-o", out, "--size-mm", "0.35"]);
        assert_success(&o);
        let m = read_tetmesh(dir.path().join(out)).unwrap();
        assert_eq!(m.region_names, vec!["layer0_bunny", "layer1_sphereA", "layer2_sphereB"], "{out}");
        for r in 0..3u16 {
            assert!(m.cell_regions.contains(&r), "{out}: region {r} empty");
        }
        m.validate().unwrap();
    }
    assert!(dir.path().join("l.ele").is_file() && dir.path().join("l.face").is_file());
}

#[test]
fn layers_along_y_and_a_defective_input() {
    if skip_without_shared_data("the mesh fixture npm_teapot.obj") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let teapot = mesh_data("npm_teapot.obj");
    // The teapot is 15.75 mm tall along y.
    let o = mesh(dir.path(), &[teapot.to_str().unwrap(), "-o", "t.msh", "--size-mm", "0.8", "--layers-mm", "5,5,5.75"]);
    assert_success(&o);
    let m = read_tetmesh(dir.path().join("t.msh")).unwrap();
    assert_eq!(m.region_names, vec!["layer1", "layer2", "layer3"]);
    let e = stderr(&o);
    assert!(e.lines().all(|l| l.starts_with("warning: ")), "{e}");
}

/// An unwelded soup (1e-9 jitter) and 10 % flipped faces: both give the bunny.
#[test]
fn defective_bunnies_give_the_bunny() {
    if skip_without_shared_data("the mesh fixtures bad_syn_soup_jitter.obj, bad_syn_flipped10pct.obj") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for name in ["bad_syn_soup_jitter.obj", "bad_syn_flipped10pct.obj"] {
        let (_, json) = mesh_with_report(dir.path(), name, "b.msh", "0.4", &[]);
        // Against the clean bunny's 194.29 mm^3.
        let v = json["quality"]["volume_mm3"].as_f64().unwrap();
        assert!((v / 194.2884 - 1.0).abs() < 1e-2, "{name}: {v}");
    }
}

#[test]
fn conforming_mode_keeps_the_input_boundary_and_refuses_defects() {
    let dir = tempfile::tempdir().unwrap();
    let (out, json) = mesh_with_report(dir.path(), "npm_bunny.obj", "b.node", "0.8", &["--mode", "conforming"]);
    assert!(out.contains("(conforming, 0.8 mm)"), "{out}");
    assert_eq!(json["mode"], "conforming");
    assert!(json["quality"]["volume_error"].as_f64().unwrap().abs() <= 1e-9);
    assert!(json["quality"]["hausdorff_relative"].as_f64().unwrap() <= 1e-9);
    assert_eq!(json["quality"]["num_inverted"], 0);
    let m = read_tetmesh(dir.path().join("b.node")).unwrap();
    assert!(m.cells.len() > 1000);
    // A bunny with a hole: refused in strict mode, the defect named, nothing written.
    if skip_without_shared_data("the mesh fixture bad_syn_hole.obj") {
        return;
    }
    let hole = mesh_data("bad_syn_hole.obj");
    let o = mesh(dir.path(), &[hole.to_str().unwrap(), "-o", "h.vtu", "--size-mm", "0.8", "--mode", "conforming"]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("conforming mode") && line.contains("border"), "{line}");
    assert!(!dir.path().join("h.vtu").exists());
}

#[test]
fn refusals_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = mesh_data("npm_bunny.obj");
    let b = bunny.to_str().unwrap();
    let cases: [(&[&str], &str); 6] = [
        (&[b, "-o", "x.vtu", "--size-mm", "1", "--mode", "conforming", "--layers-mm", "1"], "--mode envelope only"),
        (&[b, "-o", "x.stl", "--size-mm", "1"], "unknown mesh format"),
        (&[b, "-o", "no/such/x.vtu", "--size-mm", "1"], "does not exist"),
        (&[b, "-o", "x.vtu", "--size-mm", "1", "--units", "furlong"], "unknown length unit"),
        (&[b, "-o", "x.vtu", "--size-mm", "1", "--layers-mm", "1,2"], "add up to 3 mm but the shape is"),
        (&["missing.obj", "-o", "x.vtu", "--size-mm", "1"], "missing.obj"),
    ];
    for (args, want) in cases {
        let o = mesh(dir.path(), args);
        let line = assert_one_line_error(&o);
        assert!(line.contains(want), "{args:?}: {line}");
    }
    // Nothing was written.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // Flags are checked by clap (status 2).
    let o = mesh(dir.path(), &[b, "-o", "x.vtu", "--size-mm", "-1"]);
    assert_eq!(o.status.code(), Some(2));
}

/// `--grade-levels`: the graded lattice (bisection down to `--size-mm / 2^N` at
/// creases, curved and thin parts) on the bunny at 0.8 mm: a closer boundary than
/// the uniform lattice at the same size, the angles within [12°, 155°] (the
/// envelope's final guard), and the levels in the report; out of range, a clap error.
/// Measured: Hausdorff / diagonal 9.3e-2 uniform (the ears lost at
/// this size), 7.1e-3 graded; asserted: graded under half the uniform.
#[test]
fn grade_levels_refine_the_boundary() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = mesh_data("npm_bunny.obj");
    let b = bunny.to_str().unwrap();
    let run = |levels: &str, report: &str| {
        let o = mesh(dir.path(), &[b, "-o", "g.vtu", "--size-mm", "0.8", "--grade-levels", levels, "--report", report]);
        assert_success(&o);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join(report)).unwrap()).unwrap();
        json
    };
    let uniform = run("0", "u.json");
    let graded = run("2", "g.json");
    assert_eq!(uniform["grade_levels"], 0);
    assert_eq!(graded["grade_levels"], 2);
    assert_eq!(uniform["envelope"]["grade_bisections"], 0);
    assert!(graded["envelope"]["grade_bisections"].as_u64().unwrap() > 0, "{}", graded["envelope"]);
    let (hu, hg) = (
        uniform["quality"]["hausdorff_relative"].as_f64().unwrap(),
        graded["quality"]["hausdorff_relative"].as_f64().unwrap(),
    );
    eprintln!("bunny 0.8 mm: Hausdorff / diag uniform {hu:.3e}, graded (2 levels) {hg:.3e}");
    assert!(hg < 0.5 * hu, "graded {hg} vs uniform {hu}");
    for q in [&uniform["quality"], &graded["quality"]] {
        assert!(q["min_dihedral_deg"].as_f64().unwrap() >= 12.0, "{q}");
        assert!(q["max_dihedral_deg"].as_f64().unwrap() <= 155.0, "{q}");
    }
    let o = mesh(dir.path(), &[b, "-o", "x.vtu", "--size-mm", "1", "--grade-levels", "9"]);
    assert_eq!(o.status.code(), Some(2));
    // The default is documented in --help.
    let o = wagashi_in(dir.path(), ["mesh", "--help"]);
    assert_success(&o);
    let help = stdout(&o);
    assert!(
        help.contains("--grade-levels")
            && help.contains(&format!("[default: {}]", meshing::envelope::DEFAULT_GRADE_LEVELS)),
        "{help}"
    );
}
