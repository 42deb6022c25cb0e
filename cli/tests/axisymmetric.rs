//! `wagashi press --axisymmetric` end to end: the real binary on a small cylinder
//! bundle written into a temporary folder, against the 3D run of the same bundle.

mod common;

use std::path::Path;

use common::*;

/// A gel cylinder (R = 4 mm, H = 9 mm) of the seed's material 1, glued, pushed
/// 20 % in 10 s, held 30 s, released, recovering until 100 s, with two markers:
/// one on the side at mid-height, one on the top face off the x axis.
const CYLINDER: &str = mat1_experiment!(
    "gel",
    3,
    r#"shape = "cylinder"
radius_mm = 4.0
height_mm = 9.0
mass_g = 0.475
"#,
    r#"tool_contact = "glued"
support = "glued"
waypoints = [[0.0, 0.0], [10.0, 1.8], [40.0, 1.8]]
release_s = 40.0
end_s = 100.0

[data]
markers = "markers.csv"
"#
);

const MARKERS: &str = "marker,t_s,x_mm,y_mm,z_mm\n\
side,0.0,0.0,4.5,4.0\nside,40.0,0.0,4.5,4.0\n\
top,0.0,1.2,9.0,-1.6\ntop,40.0,1.2,7.2,-1.6\n";

fn write_cylinder(dir: &Path) -> std::path::PathBuf {
    write_files(&dir.join("cylinder"), &[("experiment.toml", CYLINDER), ("markers.csv", MARKERS)])
}

/// `markers.csv` rows: (name, t_s, [x, y, z]).
fn marker_rows(path: &Path) -> Vec<(String, f64, Vec<f64>)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("marker,t_s,x_mm,y_mm,z_mm"));
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            let numbers: Vec<f64> = cells[1..].iter().map(|c| c.parse().unwrap()).collect();
            (cells[0].to_string(), numbers[0], numbers[1..].to_vec())
        })
        .collect()
}

/// The axisymmetric run's peak force is the 3D run's within 2 % (1 mm elements:
/// measured 0.5 %), its output is a complete 2D output with the axisymmetric
/// stress names, the keep height loss is the plate's 1.8 mm, and its markers come
/// back in 3D on their own azimuths, near the 3D run's.
#[test]
fn axisymmetric_run_matches_the_3d_run() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = write_cylinder(tmp.path());
    let before = contents(&bundle);
    let (out3, outa) = (tmp.path().join("solid"), tmp.path().join("axisymmetric"));
    let o3 = press_in(tmp.path(), &bundle, &out3, &["--size-mm", "1"]);
    assert_success(&o3);
    let oa = press_in(tmp.path(), &bundle, &outa, &["--size-mm", "1", "--axisymmetric"]);
    assert_success(&oa);
    assert_eq!(contents(&bundle), before, "the input bundle changed");
    assert!(stdout(&oa).contains("gel: axisymmetric (r-y section), 1 mm elements"), "{}", stdout(&oa));

    let s3 = check_output(&out3, 3);
    let sa = check_output(&outa, 2);
    assert_eq!(s3["formulation"].as_str(), Some("solid"));
    assert_eq!(sa["formulation"].as_str(), Some("axisymmetric"));
    let (f3, fa) = (s3["peak_force_N"].as_f64().unwrap(), sa["peak_force_N"].as_f64().unwrap());
    let gap = (fa - f3).abs() / f3;
    eprintln!("peak force: 3D {f3:.6} N, axisymmetric {fa:.6} N ({gap:.2e})");
    assert!(gap < 0.02, "peak forces {fa} and {f3} N differ by {gap:e}");
    assert!((sa["cells"].as_u64().unwrap() as f64) < 0.05 * s3["cells"].as_u64().unwrap() as f64);
    let keep = sa["keep_height_loss_mm"].as_f64().unwrap();
    assert!((keep - 1.8).abs() < 1e-9, "keep height loss {keep} mm");

    let vtu = std::fs::read_to_string(outa.join("keep.vtu")).unwrap();
    assert!(vtu.contains("ComponentName2=\"TT\""), "the hoop stress is named");

    // Markers: 3D positions on each marker's azimuth, close to the 3D run's: the
    // two runs' displacements within 5 % of the 3D one (1 mm elements; measured
    // 2.6 %, for the side marker's axial displacement).
    let (ma, m3) = (marker_rows(&outa.join("markers.csv")), marker_rows(&out3.join("markers.csv")));
    let initial = |name: &str| m3.iter().find(|m| m.0 == name && m.1 == 0.0).unwrap().2.clone();
    assert_eq!(ma.len(), 4);
    for ((name, t, pa), (name3, t3, p3)) in ma.iter().zip(&m3) {
        assert_eq!((name, t), (name3, t3));
        let azimuth = if name == "side" { [0.0, 1.0] } else { [0.6, -0.8] };
        let r = pa[0].hypot(pa[2]);
        assert!((pa[0] - r * azimuth[0]).abs() < 1e-12 && (pa[2] - r * azimuth[1]).abs() < 1e-12, "{name}: {pa:?}");
        let norm = |v: &dyn Fn(usize) -> f64| (0..3).map(|k| v(k).powi(2)).sum::<f64>().sqrt();
        let x0 = initial(name);
        let (gap, moved) = (norm(&|k| pa[k] - p3[k]), norm(&|k| p3[k] - x0[k]));
        assert!(gap <= 0.05 * moved + 1e-9, "{name} at t = {t}: {pa:?} vs 3D {p3:?}");
    }
    let side = &ma[1].2;
    assert!(side[2] > 4.2, "the side marker bulges out at release: {side:?}");
}

/// `--axisymmetric` on a block is refused in one line naming the key.
#[test]
fn axisymmetric_block_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &example("paper/mat1"), &out, &["--axisymmetric"]);
    let line = assert_one_line_error(&o);
    assert!(line.contains("specimen.shape: the axisymmetric model needs shape = \"cylinder\""), "{line}");
    assert!(!out.exists());
}
