//! `wagashi press --gltf` and `wagashi export` end to end: the real binary in a
//! temporary folder; every file checked by the Khronos glTF-Validator, and one
//! rendered with three.js in headless Chromium (see `tests/browser/harness.rs`
//! for when those run: always on CI).

mod common;
#[path = "../../tests/browser/harness.rs"]
mod harness;

use std::path::{Path, PathBuf};

use common::*;
use serde_json::Value;

/// A gel cylinder (R = 5 mm, H = 8 mm), pushed 1.6 mm in 10 s, held, released at
/// 30 s, recovering until 60 s.
const CYLINDER: &str = mat1_experiment!(
    "gel",
    3,
    r#"shape = "cylinder"
radius_mm = 5.0
height_mm = 8.0
"#,
    r#"tool_contact = "glued"
support = "glued"
waypoints = [[0.0, 0.0], [10.0, 1.6], [30.0, 1.6]]
release_s = 30.0
end_s = 60.0
"#
);

fn write_cylinder(dir: &Path) -> PathBuf {
    write_files(&dir.join("cylinder"), &[("experiment.toml", CYLINDER)])
}

/// The glTF JSON chunk of a `.glb`, after checking the container.
fn glb_json(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[0..4], b"glTF", "{}", path.display());
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize, bytes.len());
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// The frame times and names of a written file (`asset.extras.frames`).
fn frames(json: &Value) -> Vec<(f64, String)> {
    json["asset"]["extras"]["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| (f["t_s"].as_f64().unwrap(), f["name"].as_str().unwrap().to_string()))
        .collect()
}

fn files_listed(summary: &Value) -> Vec<String> {
    summary["files"].as_array().unwrap().iter().map(|f| f.as_str().unwrap().to_string()).collect()
}

/// `press --gltf` writes 61 evenly spaced frames plus the keep frame, and frames.bin;
/// `export` of that folder gives the same bytes.
#[test]
fn press_writes_the_animation_and_export_reproduces_it() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let glb = tmp.path().join("anim/mat1.glb");
    let o = press_in(tmp.path(), &example("paper/mat1"), &out, &["--size-mm", "10", "--gltf", glb.to_str().unwrap()]);
    assert_success(&o);
    assert!(stdout(&o).contains(&format!("glTF                  {}", glb.display())), "{}", stdout(&o));
    let summary = check_output(&out, 3);
    assert!(files_listed(&summary).contains(&"frames.bin".to_string()));
    assert!(out.join("frames.bin").is_file());

    let json = glb_json(&glb);
    let f = frames(&json);
    assert_eq!(f.len(), 62, "0, 400/60, ..., 400 s and the release");
    assert_eq!(f[0], (0.0, "t=0s".to_string()));
    assert_eq!(f[61], (400.0, "final".to_string()));
    assert!(f.contains(&(210.93, "keep".to_string())));
    assert!(f.windows(2).all(|w| w[0].0 < w[1].0));
    let extras = &json["asset"]["extras"];
    assert_eq!(extras["named_frames"]["keep"].as_u64(), Some(32));
    assert_eq!(extras["units"]["length"], "m");
    assert_eq!(extras["run"]["trial"], "mat1-sim");
    // The colour scale tops at the largest displacement: the 5.774 mm push, or a little more.
    let max_mm = extras["colour_scale"]["max_mm"].as_f64().unwrap();
    assert!(max_mm > 5.7 && max_mm < 7.0, "{max_mm}");
    let names: Vec<&str> = json["nodes"].as_array().unwrap().iter().map(|n| n["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["mat1-sim", "plate"]);
    // The block is 58 x 59.5 x 12 mm: metres.
    let max = &json["accessors"]
        [json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap() as usize]["max"];
    let metres = |mm: f64| f64::from((mm * 1e-3) as f32);
    assert_eq!(max, &serde_json::json!([metres(58.0), metres(59.5), metres(12.0)]));

    let again = tmp.path().join("again.glb");
    let o = wagashi_in(tmp.path(), ["export", out.to_str().unwrap(), "--gltf", again.to_str().unwrap()]);
    assert_success(&o);
    assert!(stdout(&o).contains("62 frames from frames.bin"), "{}", stdout(&o));
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&glb).unwrap(), "export reproduces press --gltf");

    harness::validate(&[&glb]);
}

/// A `.glb` inside OUT is part of the folder's atomic write and listed in summary.json.
#[test]
fn a_gltf_inside_the_output_folder_is_part_of_it() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = press_in(tmp.path(), &example("paper/mat1-2d"), &out, &["--size-mm", "10", "--gltf", "out/view/anim.glb"]);
    assert_success(&o);
    let summary = check_output(&out, 2);
    let files = files_listed(&summary);
    assert!(files.contains(&"view/anim.glb".to_string()) && files.contains(&"frames.bin".to_string()), "{files:?}");
    let glb = out.join("view/anim.glb");
    let json = glb_json(&glb);
    // Plane stress: the slab is T = 12 mm thick.
    let position = json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap() as usize;
    assert_eq!(json["accessors"][position]["max"][2], f64::from((12.0 * 1e-3) as f32));
    assert_eq!(json["asset"]["extras"]["run"]["formulation"], "plane");
    harness::validate(&[&glb]);
    let again = tmp.path().join("again.glb");
    assert_success(&wagashi_in(tmp.path(), ["export", "out", "--gltf", "again.glb"]));
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&glb).unwrap(), "export reproduces the slab");

    // Replacing the output replaces the file with it.
    let o = press_in(tmp.path(), &example("paper/mat1-2d"), &out, &["--size-mm", "10", "--force", "--pvd", "4"]);
    assert_success(&o);
    assert!(!glb.exists() && !out.join("frames.bin").exists());
    let exported = tmp.path().join("from-shapes.glb");
    let o = wagashi_in(tmp.path(), ["export", "out", "--gltf", exported.to_str().unwrap()]);
    assert_success(&o);
    assert!(stdout(&o).contains("from shapes.pvd, keep.vtu and final.vtu"), "{}", stdout(&o));
    let f = frames(&glb_json(&exported));
    let times: Vec<f64> = f.iter().map(|x| x.0).collect();
    assert_eq!(times, [0.0, 100.0, 200.0, 210.93, 300.0, 400.0]);
    assert_eq!((f[3].1.as_str(), f[5].1.as_str()), ("keep", "final"));
    harness::validate(&[&exported]);
}

/// The axisymmetric section is revolved; an output without frames.bin or
/// shapes.pvd exports the undeformed, keep and final shapes.
#[test]
fn axisymmetric_runs_and_plain_outputs_export() {
    let tmp = tempfile::tempdir().unwrap();
    let bundle = write_cylinder(tmp.path());
    let out = tmp.path().join("out");
    let glb = tmp.path().join("gel.glb");
    let o = press_in(tmp.path(), &bundle, &out, &["--axisymmetric", "--size-mm", "1", "--gltf", "gel.glb"]);
    assert_success(&o);
    let json = glb_json(&glb);
    assert_eq!(json["asset"]["extras"]["run"]["formulation"], "axisymmetric");
    let position = json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap() as usize;
    let (min, max) = (&json["accessors"][position]["min"], &json["accessors"][position]["max"]);
    let metres = |mm: f64| Some(f64::from((mm * 1e-3) as f32));
    assert_eq!((min[0].as_f64(), max[0].as_f64()), (metres(-5.0), metres(5.0)));
    assert_eq!(max[1].as_f64(), metres(8.0));
    assert_eq!(frames(&json).len(), 61, "the release at 30 s is on the 1 s grid");
    let again = tmp.path().join("again.glb");
    assert_success(&wagashi_in(tmp.path(), ["export", "out", "--gltf", "again.glb"]));
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&glb).unwrap(), "export reproduces the revolved section");

    let plain = tmp.path().join("plain");
    assert_success(&press_in(tmp.path(), &bundle, &plain, &["--axisymmetric", "--size-mm", "1"]));
    let exported = tmp.path().join("plain.glb");
    let o = wagashi_in(tmp.path(), ["export", "plain", "--gltf", "plain.glb"]);
    assert_success(&o);
    assert!(stdout(&o).contains("3 frames from keep.vtu and final.vtu"), "{}", stdout(&o));
    let f = frames(&glb_json(&exported));
    assert_eq!(f, [(0.0, "t=0s".into()), (30.0, "keep".into()), (60.0, "final".into())]);
    harness::validate(&[&glb, &exported]);
}

#[test]
fn bad_paths_and_folders_are_refused_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let mat1 = example("paper/mat1");
    let run = |extra: &[&str]| press_in(tmp.path(), &mat1, &tmp.path().join("out"), extra);

    let line = assert_one_line_error(&run(&["--size-mm", "10", "--gltf", "anim.gltf"]));
    assert!(line.contains("anim.gltf") && line.contains(".glb"), "{line}");
    std::fs::write(tmp.path().join("notes.glb"), "my notes").unwrap();
    let line = assert_one_line_error(&run(&["--size-mm", "10", "--gltf", "notes.glb"]));
    assert!(line.contains("notes.glb: exists and is not a glTF binary"), "{line}");
    assert_eq!(std::fs::read_to_string(tmp.path().join("notes.glb")).unwrap(), "my notes");
    let inside = mat1.join("anim.glb");
    let line = assert_one_line_error(&run(&["--size-mm", "10", "--gltf", inside.to_str().unwrap()]));
    assert!(line.contains("inside the input bundle"), "{line}");
    assert!(!inside.exists());
    let line = assert_one_line_error(&run(&["--size-mm", "10", "--pvd", "5000", "--gltf", "a.glb"]));
    assert!(line.contains("--pvd 5000"), "{line}");
    assert!(!tmp.path().join("out").exists(), "refused before the run: no output");

    // export: a folder that is not a press output, a missing one, a damaged frames.bin.
    let line = assert_one_line_error(&wagashi_in(tmp.path(), ["export", ".", "--gltf", "x.glb"]));
    assert!(line.contains("not a wagashi press output"), "{line}");
    let line = assert_one_line_error(&wagashi_in(tmp.path(), ["export", "nowhere", "--gltf", "x.glb"]));
    assert!(line.contains("nowhere: no such folder"), "{line}");
    assert_success(&run(&["--size-mm", "10", "--gltf", "a.glb"]));
    let frames_bin = tmp.path().join("out/frames.bin");
    let bytes = std::fs::read(&frames_bin).unwrap();
    std::fs::write(&frames_bin, &bytes[..bytes.len() - 3]).unwrap();
    let line = assert_one_line_error(&wagashi_in(tmp.path(), ["export", "out", "--gltf", "x.glb"]));
    assert!(line.contains("out/frames.bin: "), "{line}");
    std::fs::remove_file(&frames_bin).unwrap();
    std::fs::write(tmp.path().join("out/keep.vtu"), "<VTKFile").unwrap();
    let line = assert_one_line_error(&wagashi_in(tmp.path(), ["export", "out", "--gltf", "x.glb"]));
    assert!(line.contains("out/keep.vtu: ") && line.contains("XML"), "{line}");
    assert!(!tmp.path().join("x.glb").exists());
}

#[test]
fn help_shows_examples() {
    let tmp = tempfile::tempdir().unwrap();
    let o = wagashi_in(tmp.path(), ["export", "--help"]);
    assert_success(&o);
    for needle in ["--gltf <FILE.glb>", "Examples:", "wagashi export out/mat1 --gltf", "frames.bin"] {
        assert!(stdout(&o).contains(needle), "export --help lacks {needle:?}:\n{}", stdout(&o));
    }
    let o = wagashi_in(tmp.path(), ["press", "--help"]);
    assert!(stdout(&o).contains("--gltf <FILE.glb>"), "{}", stdout(&o));
}

/// The screenshot's pixels: RGB rows, top to bottom.
struct Image {
    width: usize,
    height: usize,
    rgb: Vec<[u8; 3]>,
}

fn read_png(path: &Path) -> Image {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut decoder = png::Decoder::new(file);
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    assert!(channels >= 3, "{:?}", info.color_type);
    let rgb = buf[..info.buffer_size()].chunks_exact(channels).map(|p| [p[0], p[1], p[2]]).collect();
    Image { width: info.width as usize, height: info.height as usize, rgb }
}

impl Image {
    /// Pixels further than 24 (of 255, any channel) from the top-left corner's colour.
    fn foreground(&self) -> Vec<(usize, usize)> {
        let background = self.rgb[0];
        (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let p = self.rgb[y * self.width + x];
                (0..3).any(|k| p[k].abs_diff(background[k]) > 24)
            })
            .collect()
    }
}

/// The specimen renders in the browser: the keep frame fills a good part of the
/// picture, lies wholly inside it, and differs from the undeformed frame.
#[test]
fn the_browser_shows_the_specimen_in_frame() {
    if !harness::available(harness::Need::Browser) {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let glb = tmp.path().join("mat1.glb");
    let o = press_in(
        tmp.path(),
        &example("paper/mat1"),
        &tmp.path().join("out"),
        &["--size-mm", "10", "--gltf", glb.to_str().unwrap()],
    );
    assert_success(&o);
    // Kept for people to look at: target/tmp/gltf-browser/.
    let shots = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("gltf-browser");
    std::fs::create_dir_all(&shots).unwrap();
    let keep_png = shots.join("mat1-keep.png");
    let start_png = shots.join("mat1-start.png");
    let report = harness::render(&glb, &keep_png, None).unwrap();
    eprintln!("render: {report}\nscreenshot: {}", keep_png.display());
    assert_eq!(report["time_s"].as_f64(), Some(210.93), "the keep frame by default");
    assert_eq!(report["morph_targets"].as_u64(), Some(62));
    assert!(report["target_names"].as_array().unwrap().iter().any(|n| n == "keep"));
    assert_eq!(report["nodes"], serde_json::json!(["mat1-sim", "plate"]));
    assert!((report["animation_s"].as_f64().unwrap() - 400.0).abs() < 1e-3);

    let keep = read_png(&keep_png);
    assert_eq!((keep.width, keep.height), (800, 600));
    let background = keep.rgb[0];
    assert!(background.iter().all(|&c| c >= 250), "white background, got {background:?}");
    let fg = keep.foreground();
    let share = fg.len() as f64 / (keep.width * keep.height) as f64;
    assert!(share > 0.05, "not blank: {:.1} % of the pixels show something", 100.0 * share);
    let (x0, x1) = (fg.iter().map(|p| p.0).min().unwrap(), fg.iter().map(|p| p.0).max().unwrap());
    let (y0, y1) = (fg.iter().map(|p| p.1).min().unwrap(), fg.iter().map(|p| p.1).max().unwrap());
    let margin = 8;
    assert!(
        x0 >= margin && y0 >= margin && x1 + margin < keep.width && y1 + margin < keep.height,
        "the object touches the border: x {x0}..{x1}, y {y0}..{y1} in {}x{}",
        keep.width,
        keep.height
    );
    // Colours of the scale: viridis's yellow (the pushed top) and its purple (the
    // bottom, which does not move) are both there.
    let yellowish = keep.rgb.iter().filter(|p| p[0] > 180 && p[1] > 170 && p[2] < 120).count();
    let purplish = keep.rgb.iter().filter(|p| p[2] > p[1] + 20 && p[0] > p[1] + 10 && p[1] < 80).count();
    assert!(yellowish > 500 && purplish > 500, "yellow {yellowish}, purple {purplish} pixels");

    // The undeformed frame looks different (one colour, no push).
    harness::render(&glb, &start_png, Some(0.0)).unwrap();
    let start = read_png(&start_png);
    let changed = keep.rgb.iter().zip(&start.rgb).filter(|(a, b)| (0..3).any(|k| a[k].abs_diff(b[k]) > 24)).count();
    assert!(changed > keep.rgb.len() / 50, "only {changed} pixels change between t = 0 and the keep frame");
}
