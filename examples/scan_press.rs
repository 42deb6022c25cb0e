//! # End to end: a scanned pear, two layers, a sphere and a plate out of sync
//!
//! What it shows: the whole chain from a 3D scan to an animated glTF. The YCB
//! pear (a closed scan in metres) is imported, repaired, filled with tetrahedra,
//! cut by a horizontal plane into two layers of different materials, glued to
//! the floor, pressed by a sphere and then, out of sync, by a plate, released,
//! left to recover, and written for ParaView (`.vtu`) and for web viewers and
//! Blender (`.glb`).
//!
//! Run, from the repository root (about 1 min in release on 2 cores at the
//! default 6 mm; 8 mm takes 10 s, 4 mm 5 min):
//!
//! ```text
//! cargo run --release -p wagashi-workspace-tests --example scan_press -- -o out/scan-press
//! ```
//!
//! Options: `[SCAN]` (OBJ, STL or glTF; default the YCB pear in
//! `<workspace>/../shared/data/real/scans`), `--size-mm H` (element size, default
//! 6), `--units mm|cm|m|in` (the scan's unit, default m: the YCB files are in
//! metres), `--up y|z` (the scan's vertical axis, default z: the YCB frame), `-o
//! OUT` (default `out/scan-press`; an earlier output there is replaced), `--sphere
//! glued|frictionless` (default glued, see below). The test
//! `tests/scan_press.rs` runs the same pipeline ([`run`]) on an 8 mm mesh and
//! checks what it produced.
//!
//! ## The trial
//!
//! The pear lies on its side, as it rests in the YCB frame (turned so that the
//! engine's push axis y is up; bottom on y = 0, centred on x = z = 0). Lengths below
//! are fractions of its height `H` (66 mm for the pear), so that other scans work
//! too; times are in seconds.
//!
//! - **Two layers**, lower and upper (one horizontal plane cuts a shape into
//!   layers; a skin and core would need a second, nested shell). The plane
//!   `y = H/2` is cut into the mesh as a conforming interface; `layer1` (lower) is
//!   the seed's material 1 (five-element, Table II x_force), `layer2` (upper) the
//!   same chain with every modulus and viscosity halved: twice as soft, with the
//!   same relaxation times.
//! - **Glued base**: the boundary nodes within `max(0.05 H, h/2)` of the lowest
//!   point hold still (the node set `bottom`, `protocol.support = Glued`).
//! - **Sphere** (radius `0.15 H`, a fingertip) over the neck, touching its top at
//!   t = 0, `0.06 H` deep at 5 s. It is **glued** (dough sticks to a finger) and
//!   lets go at 5 s, then rises `0.05 H` above its start by 5.25 s.
//!   `--sphere frictionless` makes it a smooth indenter that slides on the neck
//!   and lets go once risen (5.25 s); the run then takes about 4 times longer (a
//!   curved frictionless tool refactors the matrix at every Newton pass of its
//!   contact iteration: 30 s instead of 8 s of simulation at 8 mm).
//! - **Plate** (frictionless) over the body and the blossom end, its edge where
//!   the top has fallen below the plate's lowest position (so only its flat face
//!   touches), `0.01 H` above the apex: it waits until 3 s, comes down to `0.075 H`
//!   below the apex by 8 s (first touch after 3 s, while the sphere still
//!   presses), rises `0.05 H` above its start by 8.5 s and is released there.
//! - The trial ends at 30 s; `keep` is at 5 s, when both tools press.
//!
//! ## Steps
//!
//! 1. Import the scan (`wagashi_io::surface::read_surface`, metres to mm).
//! 2. Repair it (`meshing::repair`) and validate it (`meshing::validate`).
//! 3. Turn it (`--up`) and put its bottom on y = 0.
//! 4. Envelope-mesh it with the plane `y = H/2` cut in (`meshing::envelope` with
//!    `layers_mm`, which cuts with `meshing::layers`); measure it
//!    (`meshing::quality::report`) and compare each layer's volume with the scan's
//!    volume below and above the plane.
//! 5. Build the problem: materials, glued base, sphere and plate placed on the
//!    mesh (`fem_core::press`).
//! 6. Simulate (quasi-static, adaptive steps).
//! 7. Write `OUT/` atomically (built aside, renamed into place): `final.vtu`,
//!    `keep.vtu`, `press.glb` (animated, tools drawn; `wagashi_io::gltf`),
//!    `summary.json`.
//! 8. Print the tools' touch times and peak forces, and the height loss at the
//!    peak and at the end.
//!
//! ## What it writes
//!
//! | file           | what                                                                          |
//! |----------------|-------------------------------------------------------------------------------|
//! | `final.vtu`    | the final shape (30 s): displacement, region, stress per cell (ParaView)      |
//! | `keep.vtu`     | the shape at 5 s, both tools pressing                                         |
//! | `press.glb`    | glTF 2.0: the pear deforming (frames `keep`, `final`), the sphere and plate moving |
//! | `summary.json` | mesh counts and quality, layer volumes, tool touch times and peak forces, height loss |
//!
//! The height loss is the undeformed height less the highest deformed point (its
//! peak is the largest over the kept shapes, every 0.5 s to 10 s, then every 2 s);
//! the dent is the downward displacement of the node the sphere first touches.

use std::error::Error;
use std::path::{Path, PathBuf};
use std::time::Instant;

use fem_core::element::Formulation;
use fem_core::material::{Material, Rheology};
use fem_core::mesh::TetMesh;
use fem_core::press::{
    self, Attachment, PressResult, Protocol, Settings, Snapshot, SolidPress, Tool, ToolContact, ToolShape, ToolTrack,
};
use meshing::envelope::{envelope_mesh, EnvelopeOptions};
use meshing::quality::{report, QualityReport};
use meshing::repair::{repair, RepairOptions};
use meshing::validate::{validate, ValidateOptions};
use meshing::Surface;
use serde_json::json;
use wagashi_io::gltf::{write_glb, AnimatedTool, GltfScene, SpecimenSurface, ToolKey};
use wagashi_io::surface::{read_surface, LengthUnit, SurfaceOptions};
use wagashi_io::vtu::{write_vtu, VtuFields};
use wagashi_io::{write_atomic, AtomicDir};

type Result<T> = std::result::Result<T, Box<dyn Error>>;

/// When the sphere is at its deepest [s].
pub const SPHERE_DOWN_S: f64 = 5.0;
/// When the sphere is back up [s] (it lets go at [`SPHERE_DOWN_S`]).
pub const SPHERE_UP_S: f64 = 5.25;
/// The plate waits above the apex until then [s].
pub const PLATE_START_S: f64 = 3.0;
/// When the plate is at its deepest [s].
pub const PLATE_DOWN_S: f64 = 8.0;
/// When the plate is back up, and released [s].
pub const PLATE_UP_S: f64 = 8.5;
/// The keep shape: both tools press [s].
pub const KEEP_S: f64 = 5.0;
/// The end of the trial: the final shape [s].
pub const END_S: f64 = 30.0;

/// Sphere radius / H.
pub const SPHERE_RADIUS: f64 = 0.15;
/// Sphere depth below its first touch at [`SPHERE_DOWN_S`] / H.
pub const SPHERE_DEPTH: f64 = 0.06;
/// Plate's gap above the apex at t = 0 / H.
pub const PLATE_GAP: f64 = 0.01;
/// Plate depth below the apex at [`PLATE_DOWN_S`] / H.
pub const PLATE_DEPTH: f64 = 0.075;
/// How far the tools rise above their start when they leave / H.
pub const LIFT: f64 = 0.05;

/// What to run.
#[derive(Debug, Clone)]
pub struct Options {
    /// The scan (OBJ, STL, glTF).
    pub scan: PathBuf,
    /// The unit of the scan's coordinates.
    pub units: LengthUnit,
    /// The scan's vertical axis: 1 (y) or 2 (z).
    pub up_axis: usize,
    /// Element size (lattice spacing) [mm].
    pub size_mm: f64,
    /// How the sphere holds the surface: glued (default) or frictionless.
    pub sphere_contact: ToolContact,
    /// The output folder (replaced if it is a previous output).
    pub output: PathBuf,
}

impl Options {
    /// The defaults: the YCB pear, metres, z up, 6 mm, `out/scan-press`.
    pub fn new() -> Self {
        Self {
            scan: shared_data().join("real/scans/YcbPear_collision_vhacd.obj"),
            units: LengthUnit::M,
            up_axis: 2,
            size_mm: 6.0,
            sphere_contact: ToolContact::Glued,
            output: PathBuf::from("out/scan-press"),
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Self::new()
    }
}

/// `<workspace>/../shared/data`.
pub fn shared_data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data")
}

/// A tool as placed on the mesh, with the numbers that describe its stroke.
#[derive(Debug, Clone)]
pub struct Placement {
    /// The tool.
    pub tool: Tool,
    /// The point where it first touches (sphere) or the apex (plate) [mm].
    pub target_mm: [f64; 3],
    /// How deep it goes below its first touch (sphere) or the apex (plate) [mm].
    pub depth_mm: f64,
    /// Where it is, in words (for the log).
    pub description: String,
}

/// Everything a run made.
#[derive(Debug)]
pub struct Outcome {
    /// The surface as meshed (mm, turned, bottom on y = 0).
    pub surface: Surface,
    /// The height of the layer plane [mm].
    pub cut_y_mm: f64,
    /// The scan's volume below and above the plane [mm^3].
    pub reference_volumes_mm3: [f64; 2],
    /// The mesh the engine ran on (regions `layer1`, `layer2`; sets `boundary`, `bottom`).
    pub mesh: TetMesh,
    /// Its quality report against `surface`.
    pub quality: QualityReport,
    /// The sphere and the plate, in that order (as in `result.tools`).
    pub tools: [Placement; 2],
    /// The engine's result.
    pub result: PressResult,
    /// The height of the undeformed mesh (its highest node) [mm].
    pub height_mm: f64,
    /// The summary written to `summary.json`.
    pub summary: serde_json::Value,
    /// The output folder, committed.
    pub output: PathBuf,
    /// Wall times [s]: meshing, simulation, writing.
    pub times_s: [f64; 3],
}

fn main() {
    let options = match parse_args(std::env::args().skip(1)) {
        Ok(Some(o)) => o,
        Ok(None) => return,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    if let Err(e) = run(&options, &mut |line| println!("{line}")) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

const USAGE: &str =
    "usage: scan_press [SCAN] [--size-mm H] [--units mm|cm|m|in] [--up y|z] [--sphere glued|frictionless] [-o OUT]";

/// Parses the command line; `None` after printing the help.
fn parse_args(args: impl Iterator<Item = String>) -> Result<Option<Options>> {
    let mut options = Options::new();
    let mut args = args;
    let mut scan_given = false;
    while let Some(arg) = args.next() {
        let mut value = |name: &str| args.next().ok_or_else(|| format!("{name} needs a value; {USAGE}"));
        match arg.as_str() {
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(None);
            }
            "--size-mm" => {
                let v = value("--size-mm")?;
                options.size_mm = v.parse().map_err(|_| format!("--size-mm {v}: not a number"))?;
                if !(options.size_mm.is_finite() && options.size_mm > 0.0) {
                    return Err(format!("--size-mm {v}: must be a positive length in mm").into());
                }
            }
            "--units" => options.units = value("--units")?.parse()?,
            "--up" => {
                options.up_axis = match value("--up")?.as_str() {
                    "y" => 1,
                    "z" => 2,
                    other => return Err(format!("--up {other}: expected y or z").into()),
                }
            }
            "--sphere" => {
                options.sphere_contact = match value("--sphere")?.as_str() {
                    "glued" => ToolContact::Glued,
                    "frictionless" => ToolContact::Frictionless,
                    other => return Err(format!("--sphere {other}: expected glued or frictionless").into()),
                }
            }
            "-o" | "--output" => options.output = PathBuf::from(value("-o")?),
            flag if flag.starts_with('-') => return Err(format!("unknown option {flag}; {USAGE}").into()),
            path if !scan_given => {
                options.scan = PathBuf::from(path);
                scan_given = true;
            }
            extra => return Err(format!("unexpected argument {extra}; {USAGE}").into()),
        }
    }
    Ok(Some(options))
}

/// Runs the whole pipeline (see the module docs), reporting progress to `log`.
pub fn run(options: &Options, log: &mut dyn FnMut(&str)) -> Result<Outcome> {
    // The output folder is built aside (refused up front if it holds something
    // else than an earlier output) and renamed into place at the end.
    let out = AtomicDir::new(&options.output)?;

    // 1. Import.
    let scan = &options.scan;
    let imported = read_surface(scan, &SurfaceOptions { units: Some(options.units), ..Default::default() })?;
    log(&format!(
        "1. import   {}: {} vertices, {} triangles, {} to mm (x {})",
        scan.display(),
        imported.surface.num_vertices(),
        imported.surface.num_triangles(),
        imported.unit,
        imported.to_mm
    ));
    for w in &imported.warnings {
        log(&format!("   warning: {w}"));
    }

    // 2. Repair and validate.
    let repaired = repair(&imported.surface, &RepairOptions::default())
        .map_err(|e| format!("{}: repairing the surface: {e}", scan.display()))?;
    let check = validate(&repaired.surface, &ValidateOptions::default())
        .map_err(|e| format!("{}: validating the surface: {e}", scan.display()))?;
    log(&format!(
        "2. repair   {}; {} component(s), {} defect(s) left{}",
        repaired.report,
        check.components.len(),
        check.defects.len(),
        if check.defects.is_empty() { "" } else { " (the envelope mesher copes with them)" }
    ));

    // 3. Turn (up = +y) and place: bottom on y = 0, centred on x = z = 0.
    let surface = placed(repaired.surface, options.up_axis);
    let (lo, hi) = surface.bounding_box();
    let height = hi[1] - lo[1];
    log(&format!(
        "3. place    {:.1} x {:.1} x {:.1} mm (x, y up, z), enclosed volume {:.0} mm^3",
        hi[0] - lo[0],
        height,
        hi[2] - lo[2],
        surface.signed_volume(None)
    ));

    // 4. Mesh, with the layer plane cut in.
    let h = options.size_mm;
    let layers_mm = vec![0.5 * height, 0.5 * height];
    let cut_y_mm = meshing::layers::layer_planes(&layers_mm, lo[1], hi[1])?[0];
    let mesh_clock = Instant::now();
    let meshed = envelope_mesh(&surface, &EnvelopeOptions { layers_mm, ..EnvelopeOptions::new(h) })
        .map_err(|e| format!("meshing {}: {e}", scan.display()))?;
    for w in &meshed.warnings {
        log(&format!("   warning: {w}"));
    }
    let mut mesh = meshed.mesh;
    let mesh_time_s = mesh_clock.elapsed().as_secs_f64();
    let quality = report(&mesh, &surface, mesh_time_s);
    let reference_volumes_mm3 = volumes_below_and_above(&surface, cut_y_mm);
    log(&format!(
        "4. mesh     h = {h} mm: {} nodes, {} tets; dihedral angles {:.1}..{:.1} deg; Hausdorff {:.2} mm",
        quality.num_nodes, quality.num_cells, quality.min_dihedral_deg, quality.max_dihedral_deg, quality.hausdorff_mm
    ));
    if quality.regions.len() != 2 {
        return Err(format!("the plane y = {cut_y_mm} mm gave {} regions, not 2", quality.regions.len()).into());
    }
    for ((r, reference), side) in quality.regions.iter().zip(reference_volumes_mm3).zip(["below", "above"]) {
        log(&format!(
            "   {}: {} tets, {:.0} mm^3; the scan {side} y = {cut_y_mm:.2} mm: {reference:.0} mm^3 ({:+.2} %)",
            r.name,
            r.num_cells,
            r.volume_mm3,
            100.0 * (r.volume_mm3 / reference - 1.0)
        ));
    }

    // 5. The problem.
    let base_mm = (0.05 * height).max(0.5 * h);
    let boundary = mesh.node_set("boundary")?.to_vec();
    let bottom: Vec<u32> = boundary.iter().copied().filter(|&i| mesh.nodes[i as usize][1] <= lo[1] + base_mm).collect();
    if bottom.len() < 3 {
        return Err(format!(
            "only {} boundary nodes within {base_mm:.2} mm of the bottom: too few to glue",
            bottom.len()
        )
        .into());
    }
    mesh.node_sets.insert("bottom".into(), bottom.clone());
    let tools = place_tools(&mesh, &boundary, height, h, options.sphere_contact)?;
    let [sphere, plate] = &tools;
    log(&format!("5. problem  glued base: {} nodes (within {base_mm:.2} mm of the bottom)", bottom.len()));
    log(&format!("   {}", sphere.description));
    log(&format!("   {}", plate.description));
    let lower = Material::seed_mat1_force();
    let upper = scaled(&lower, 0.5);
    let problem = SolidPress {
        mesh,
        formulation: Formulation::Solid,
        materials: vec![lower.clone(), upper.clone()],
        density_t_mm3: 1e-9,
        protocol: Protocol {
            // The protocol's plate is unused with tools: no motion, no release before the end.
            waypoints: vec![[0.0, 0.0]],
            release_s: END_S,
            end_s: END_S,
            plate: Attachment::Frictionless,
            support: Attachment::Glued,
            gravity: false,
        },
        markers: Vec::new(),
        snapshot_times: frame_times(),
        tools: tools.iter().map(|p| p.tool.clone()).collect(),
        effects: fem_core::effects::Effects::none(),
    };
    problem.validate()?;

    // 6. Simulate.
    let sim_clock = Instant::now();
    let mut reported = 0.0;
    let result = press::simulate(&problem, &Settings::default(), &mut |p| {
        // A line every 2.5 s of simulated time.
        if (p.t_s / 2.5 + 1e-9).floor() > reported {
            reported = (p.t_s / 2.5 + 1e-9).floor();
            log(&format!("6. simulate t = {:5.2} s of {END_S} s, {} steps", p.t_s, p.steps));
        }
    })?;
    let sim_time_s = sim_clock.elapsed().as_secs_f64();
    let mesh = problem.mesh;

    // 7. Write.
    let write_clock = Instant::now();
    let keep = snapshot(&result, KEEP_S)?;
    let last = snapshot(&result, END_S)?;
    let top_y = mesh.nodes.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    let loss = |s: &Snapshot| top_y - deformed_top(&mesh, s);
    let (peak_loss_s, peak_loss_mm) = result
        .snapshots
        .iter()
        .map(|s| (s.t_s, loss(s)))
        .fold((0.0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
    let final_loss_mm = loss(last);
    let dent = |s: &Snapshot| -s.displacement[3 * nearest_node(&mesh, sphere.target_mm) + 1];
    let tool_json: Vec<serde_json::Value> = tools
        .iter()
        .zip(&result.tools)
        .map(|(p, track)| {
            let (peak_s, peak_n) = peak_force(track);
            let at_keep = track.samples.iter().find(|s| (s.t_s - KEEP_S).abs() < 1e-9).map_or(0, |s| s.nodes.len());
            json!({
                "name": track.name,
                "contact": contact_name(p.tool.contact),
                "released_s": p.tool.release_s,
                "depth_mm": p.depth_mm,
                "target_mm": p.target_mm,
                "first_touch_s": first_touch(track),
                "last_touch_s": last_touch(track),
                "peak_force_N": peak_n,
                "peak_force_t_s": peak_s,
                "nodes_in_contact_at_keep": at_keep,
            })
        })
        .collect();
    let material_json = |m: &Material| {
        let params: serde_json::Map<String, serde_json::Value> =
            m.rheology.parameters().into_iter().map(|(k, v)| (k.to_string(), json!(v))).collect();
        json!({ "model": m.rheology.model_name(), "poisson": m.poisson, "parameters": params })
    };
    let regions: Vec<serde_json::Value> = quality
        .regions
        .iter()
        .zip(reference_volumes_mm3)
        .zip([&lower, &upper])
        .map(|((r, scan_volume), m)| {
            json!({
                "name": r.name,
                "tets": r.num_cells,
                "volume_mm3": r.volume_mm3,
                "scan_volume_mm3": scan_volume,
                "material": material_json(m),
            })
        })
        .collect();
    let summary = json!({
        "scan": scan.display().to_string(),
        "units": imported.unit.to_string(),
        "size_mm": h,
        "extent_mm": [hi[0] - lo[0], height, hi[2] - lo[2]],
        "surface_volume_mm3": surface.signed_volume(None),
        "mesh": {
            "nodes": quality.num_nodes,
            "tets": quality.num_cells,
            "boundary_faces": quality.num_boundary_faces,
            "bottom_nodes": bottom.len(),
            "min_dihedral_deg": quality.min_dihedral_deg,
            "max_dihedral_deg": quality.max_dihedral_deg,
            "fraction_below_10_deg": quality.fraction_below_10_deg,
            "mean_radius_ratio": quality.mean_radius_ratio,
            "volume_mm3": quality.volume_mm3,
            "volume_error": quality.volume_error,
            "hausdorff_mm": quality.hausdorff_mm,
            "time_s": mesh_time_s,
        },
        "layers": { "cut_y_mm": cut_y_mm, "regions": regions },
        "tools": tool_json,
        "trial": {
            "keep_s": KEEP_S,
            "end_s": END_S,
            "steps": result.steps.len(),
            "factorizations": result.num_factorizations,
            "time_s": sim_time_s,
        },
        "height_mm": top_y,
        "peak_height_loss_mm": peak_loss_mm,
        "peak_height_loss_t_s": peak_loss_s,
        "final_height_loss_mm": final_loss_mm,
        "sphere_dent_at_keep_mm": dent(keep),
        "final_sphere_dent_mm": dent(last),
    });
    write_vtu(out.path().join("final.vtu"), &mesh, &VtuFields::from_snapshot(last))?;
    write_vtu(out.path().join("keep.vtu"), &mesh, &VtuFields::from_snapshot(keep))?;
    let name = scan.file_stem().map_or("scan".into(), |s| s.to_string_lossy().into_owned());
    write_glb(out.path().join("press.glb"), &gltf_scene(&name, &mesh, &result, &tools, &summary)?)?;
    write_atomic(out.path().join("summary.json"), (serde_json::to_string_pretty(&summary)? + "\n").as_bytes())?;
    let output = out.commit()?;
    let write_time_s = write_clock.elapsed().as_secs_f64();
    log(&format!("7. write    {}: final.vtu, keep.vtu, press.glb, summary.json", output.display()));

    // 8. Report.
    for t in &tool_json {
        log(&format!(
            "8. {:<7} first touch {:.3} s, last {:.3} s, peak force {:.3} N at {:.2} s",
            t["name"].as_str().unwrap_or("?"),
            t["first_touch_s"].as_f64().unwrap_or(f64::NAN),
            t["last_touch_s"].as_f64().unwrap_or(f64::NAN),
            t["peak_force_N"].as_f64().unwrap_or(f64::NAN),
            t["peak_force_t_s"].as_f64().unwrap_or(f64::NAN),
        ));
    }
    log(&format!(
        "   height loss {peak_loss_mm:.3} mm at {peak_loss_s} s, {final_loss_mm:.3} mm at the end ({END_S} s); \
         mesh {mesh_time_s:.1} s, simulation {sim_time_s:.1} s ({} steps), writing {write_time_s:.1} s",
        result.steps.len()
    ));
    Ok(Outcome {
        surface,
        cut_y_mm,
        reference_volumes_mm3,
        mesh,
        quality,
        tools,
        result,
        height_mm: top_y,
        summary,
        output,
        times_s: [mesh_time_s, sim_time_s, write_time_s],
    })
}

/// `material` with every modulus and viscosity times `factor`: as many times as
/// stiff, with the same relaxation times and Poisson ratio.
pub fn scaled(material: &Material, factor: f64) -> Material {
    let f = factor;
    let rheology = match material.rheology {
        Rheology::Elastic { e_mpa } => Rheology::Elastic { e_mpa: f * e_mpa },
        Rheology::ThreeElement { e1_mpa, c1_mpa_s, c3_mpa_s } => {
            Rheology::ThreeElement { e1_mpa: f * e1_mpa, c1_mpa_s: f * c1_mpa_s, c3_mpa_s: f * c3_mpa_s }
        }
        Rheology::FourElement { e1_mpa, c1_mpa_s, e2_mpa, c3_mpa_s } => Rheology::FourElement {
            e1_mpa: f * e1_mpa,
            c1_mpa_s: f * c1_mpa_s,
            e2_mpa: f * e2_mpa,
            c3_mpa_s: f * c3_mpa_s,
        },
        Rheology::FiveElement { e1_mpa, e2_mpa, c1_mpa_s, c2_mpa_s, c3_mpa_s } => Rheology::FiveElement {
            e1_mpa: f * e1_mpa,
            e2_mpa: f * e2_mpa,
            c1_mpa_s: f * c1_mpa_s,
            c2_mpa_s: f * c2_mpa_s,
            c3_mpa_s: f * c3_mpa_s,
        },
    };
    Material { rheology, poisson: material.poisson, damage: material.damage, network: material.network.clone() }
}

/// The surface turned so that `up_axis` (1 = y, 2 = z) points along +y (a
/// rotation: `(x, y, z) -> (x, z, -y)` for z up), with its bottom on y = 0 and its
/// bounding box centred on x = z = 0.
pub fn placed(mut surface: Surface, up_axis: usize) -> Surface {
    if up_axis == 2 {
        for p in &mut surface.vertices {
            *p = [p[0], p[2], -p[1]];
        }
    }
    let (lo, hi) = surface.bounding_box();
    let shift = [-0.5 * (lo[0] + hi[0]), -lo[1], -0.5 * (lo[2] + hi[2])];
    for p in &mut surface.vertices {
        for k in 0..3 {
            p[k] += shift[k];
        }
    }
    surface
}

/// The volume a closed, outward surface encloses below and above the plane
/// `y = cut_y` [mm^3], by the divergence theorem with `F = (0, y - c, 0)`: `div F =
/// 1` and `F` vanishes on the plane, so no cap is needed; each triangle's part on
/// either side contributes `(mean y - c) x` its area projected on y (exact: the
/// integrand is linear).
pub fn volumes_below_and_above(surface: &Surface, cut_y: f64) -> [f64; 2] {
    let mut volumes = [0.0; 2];
    for t in &surface.triangles {
        let p = t.map(|v| surface.vertices[v as usize]);
        for (side, polygon) in [clip(&p, cut_y, true), clip(&p, cut_y, false)].into_iter().enumerate() {
            for k in 1..polygon.len().saturating_sub(1) {
                let (a, b, c) = (polygon[0], polygon[k], polygon[k + 1]);
                let (u, v) = (sub(b, a), sub(c, a));
                let area_y = 0.5 * (u[2] * v[0] - u[0] * v[2]);
                volumes[side] += ((a[1] + b[1] + c[1]) / 3.0 - cut_y) * area_y;
            }
        }
    }
    volumes
}

/// The part of triangle `p` below (`below`) or above the plane `y = c`, as a polygon.
fn clip(p: &[[f64; 3]; 3], c: f64, below: bool) -> Vec<[f64; 3]> {
    let inside = |q: &[f64; 3]| if below { q[1] <= c } else { q[1] >= c };
    let mut out = Vec::with_capacity(4);
    for i in 0..3 {
        let (a, b) = (p[i], p[(i + 1) % 3]);
        if inside(&a) {
            out.push(a);
        }
        if (a[1] < c && b[1] > c) || (a[1] > c && b[1] < c) {
            let w = (c - a[1]) / (b[1] - a[1]);
            out.push([a[0] + w * (b[0] - a[0]), c, a[2] + w * (b[2] - a[2])]);
        }
    }
    out
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The sphere over the neck and the plate over the body (see the module docs),
/// placed on the mesh's `boundary` nodes; `height` is H [mm], `h` the element size,
/// `sphere_contact` how the sphere holds (glued: it lets go at its deepest point;
/// otherwise once risen).
///
/// The shape's longer horizontal axis (x or z) runs from the plate's side (the
/// apex's) to the sphere's (the side with more room beyond the apex). Along it, the
/// plate's edge is where the highest boundary node within `h/2` has fallen below
/// the plate's lowest position by `max(h/2, 0.02 H)`; the sphere's centre lies
/// `0.05 H + R` beyond that edge, above the highest node there, and starts at the
/// height where it touches the boundary nodes without pressing any.
pub fn place_tools(
    mesh: &TetMesh,
    boundary: &[u32],
    height: f64,
    h: f64,
    sphere_contact: ToolContact,
) -> Result<[Placement; 2]> {
    let nodes: Vec<[f64; 3]> = boundary.iter().map(|&i| mesh.nodes[i as usize]).collect();
    let (lo, hi) = mesh.bounding_box();
    let axis = if hi[0] - lo[0] > hi[2] - lo[2] { 0 } else { 2 };
    let cross = 2 - axis;
    let apex = nodes.iter().copied().fold([0.0, f64::NEG_INFINITY, 0.0], |a, p| if p[1] > a[1] { p } else { a });
    let toward = if hi[axis] - apex[axis] >= apex[axis] - lo[axis] { 1.0 } else { -1.0 };
    let top_near = |s: f64| {
        nodes.iter().filter(|p| (p[axis] - s).abs() <= 0.5 * h).map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max)
    };
    let plate_depth = PLATE_DEPTH * height;
    let plate_gap = PLATE_GAP * height;
    let clearance = (0.5 * h).max(0.02 * height);
    let end = if toward > 0.0 { hi[axis] } else { lo[axis] };
    let step = 0.25 * h;
    let mut edge = apex[axis];
    while top_near(edge) >= apex[1] - plate_depth - clearance {
        edge += toward * step;
        if (end - edge) * toward <= 0.0 {
            return Err("the top never falls below the plate's lowest position: no room for the sphere".into());
        }
    }
    let radius = SPHERE_RADIUS * height;
    let centre_s = edge + toward * (0.05 * height + radius);
    if (end - centre_s) * toward <= 0.5 * radius {
        return Err(format!("no room for the sphere beyond the plate's edge at {edge:.2} mm").into());
    }
    // The sphere: above the highest node near its axis position, touching.
    let ridge = nodes
        .iter()
        .filter(|p| (p[axis] - centre_s).abs() <= 0.5 * h)
        .fold([0.0, f64::NEG_INFINITY, 0.0], |a, &p| if p[1] > a[1] { p } else { a });
    let mut centre = [0.0; 3];
    centre[axis] = centre_s;
    centre[cross] = ridge[cross];
    let mut touch = ridge;
    centre[1] = f64::NEG_INFINITY;
    for p in &nodes {
        let r2 = (p[0] - centre[0]).powi(2) + (p[2] - centre[2]).powi(2);
        if r2 < radius * radius {
            let y = p[1] + (radius * radius - r2).sqrt();
            if y > centre[1] {
                centre[1] = y;
                touch = *p;
            }
        }
    }
    let sphere_depth = SPHERE_DEPTH * height;
    let lift = LIFT * height;
    let sphere = Tool::moving_down(
        "sphere",
        ToolShape::Sphere { radius },
        centre,
        &[[0.0, 0.0], [SPHERE_DOWN_S, sphere_depth], [SPHERE_UP_S, -lift]],
        sphere_contact,
        if sphere_contact == ToolContact::Glued { SPHERE_DOWN_S } else { SPHERE_UP_S },
    );
    // The plate: a slab from beyond the shape on the apex's side to `edge`, across
    // the whole width, its underside `plate_gap` above the apex.
    let margin = 0.15 * (hi[axis] - lo[axis]);
    let far = if toward > 0.0 { lo[axis] - margin } else { hi[axis] + margin };
    let thickness = 0.1 * height;
    let mut half = [0.0; 3];
    half[axis] = 0.5 * (edge - far).abs();
    half[cross] = 0.5 * (hi[cross] - lo[cross]) + margin;
    half[1] = 0.5 * thickness;
    let mut plate_centre = [0.0; 3];
    plate_centre[axis] = 0.5 * (edge + far);
    plate_centre[cross] = 0.5 * (hi[cross] + lo[cross]);
    plate_centre[1] = apex[1] + plate_gap + half[1];
    let plate = Tool::moving_down(
        "plate",
        ToolShape::Plate { half_extents: half },
        plate_centre,
        &[[0.0, 0.0], [PLATE_START_S, 0.0], [PLATE_DOWN_S, plate_gap + plate_depth], [PLATE_UP_S, -lift]],
        ToolContact::Frictionless,
        PLATE_UP_S,
    );
    let axis_name = ["x", "y", "z"][axis];
    Ok([
        Placement {
            description: format!(
                "sphere: R = {radius:.2} mm, {}, first touch at ({:.1}, {:.1}, {:.1}) mm, {sphere_depth:.2} mm deep \
                 at {SPHERE_DOWN_S} s, released at {} s",
                contact_name(sphere.contact),
                touch[0],
                touch[1],
                touch[2],
                sphere.release_s
            ),
            tool: sphere,
            target_mm: touch,
            depth_mm: sphere_depth,
        },
        Placement {
            description: format!(
                "plate: edge at {axis_name} = {edge:.1} mm, {plate_gap:.2} mm above the apex ({:.1}, {:.1}, {:.1}) mm \
                 until {PLATE_START_S} s, {plate_depth:.2} mm below it at {PLATE_DOWN_S} s, released at {PLATE_UP_S} s",
                apex[0], apex[1], apex[2]
            ),
            tool: plate,
            target_mm: apex,
            depth_mm: plate_depth,
        },
    ])
}

fn contact_name(contact: ToolContact) -> &'static str {
    match contact {
        ToolContact::Glued => "glued",
        ToolContact::Frictionless => "frictionless",
        ToolContact::Friction(_) => "friction",
    }
}

/// The kept shapes: every 0.5 s while the tools move, every 2 s after.
pub fn frame_times() -> Vec<f64> {
    let mut t: Vec<f64> = (1..=20).map(|i| 0.5 * i as f64).collect();
    t.extend((6..=15).map(|i| 2.0 * i as f64));
    t
}

fn snapshot(result: &PressResult, t_s: f64) -> Result<&Snapshot> {
    result.snapshot_at(t_s).ok_or_else(|| format!("the engine kept no shape at t = {t_s} s").into())
}

/// The highest deformed y of the mesh in `snapshot` [mm].
pub fn deformed_top(mesh: &TetMesh, snapshot: &Snapshot) -> f64 {
    mesh.nodes
        .iter()
        .enumerate()
        .map(|(i, p)| p[1] + snapshot.displacement[3 * i + 1])
        .fold(f64::NEG_INFINITY, f64::max)
}

fn nearest_node(mesh: &TetMesh, p: [f64; 3]) -> usize {
    let d = |q: &[f64; 3]| (0..3).map(|k| (q[k] - p[k]).powi(2)).sum::<f64>();
    (0..mesh.nodes.len()).min_by(|&a, &b| d(&mesh.nodes[a]).total_cmp(&d(&mesh.nodes[b]))).unwrap_or(0)
}

/// The first step end at which the tool touches [s].
pub fn first_touch(track: &ToolTrack) -> Option<f64> {
    track.samples.iter().find(|s| s.area_mm2 > 0.0).map(|s| s.t_s)
}

/// The last step end at which the tool touches [s].
pub fn last_touch(track: &ToolTrack) -> Option<f64> {
    track.samples.iter().rev().find(|s| s.area_mm2 > 0.0).map(|s| s.t_s)
}

/// The largest normal force on the tool and its time `(t_s, N)`.
pub fn peak_force(track: &ToolTrack) -> (f64, f64) {
    track.samples.iter().map(|s| (s.t_s, s.normal_n)).fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a })
}

/// The animated scene: the specimen's boundary with a frame per kept shape (and
/// the undeformed one at t = 0), `keep` and `final` named; the tools as their
/// surfaces, keyed at every frame and keyframe.
fn gltf_scene(
    name: &str,
    mesh: &TetMesh,
    result: &PressResult,
    tools: &[Placement; 2],
    summary: &serde_json::Value,
) -> Result<GltfScene> {
    let surface = SpecimenSurface::from_tet_mesh(mesh)?;
    let mut frames = vec![surface.frame(0.0, None, &vec![0.0; 3 * mesh.nodes.len()])?];
    for s in &result.snapshots {
        let label = if (s.t_s - END_S).abs() < 1e-9 {
            Some("final")
        } else if (s.t_s - KEEP_S).abs() < 1e-9 {
            Some("keep")
        } else {
            None
        };
        frames.push(surface.frame(s.t_s, label, &s.displacement)?);
    }
    let times: Vec<f64> = frames.iter().map(|f| f.t_s).collect();
    let animated_tools = tools
        .iter()
        .map(|p| {
            let (vertices_mm, triangles) = p.tool.surface_mesh();
            let mut t = times.clone();
            t.extend(p.tool.keyframes.iter().map(|k| k.t_s));
            t.sort_by(f64::total_cmp);
            t.dedup_by(|a, b| (*a as f32) <= (*b as f32));
            let keys = t
                .into_iter()
                .map(|time| {
                    let (translation_mm, rotation) = p.tool.pose_at(time);
                    ToolKey { t_s: time, translation_mm, rotation_xyzw: quaternion_xyzw(rotation) }
                })
                .collect();
            AnimatedTool { name: p.tool.name.clone(), vertices_mm, triangles, keys }
        })
        .collect();
    Ok(GltfScene {
        specimen: surface.animated(name, frames),
        tools: animated_tools,
        extras: json!({
            "example": "scan_press",
            "scan": summary["scan"],
            "size_mm": summary["size_mm"],
            "keep_s": KEEP_S,
            "end_s": END_S,
        }),
    })
}

/// The unit quaternion `[x, y, z, w]` of a rotation vector (axis times angle) [rad].
fn quaternion_xyzw(rotation_rad: [f64; 3]) -> [f64; 4] {
    let angle = rotation_rad.iter().map(|x| x * x).sum::<f64>().sqrt();
    if angle <= 1e-300 {
        return ToolKey::NO_ROTATION;
    }
    let s = (0.5 * angle).sin() / angle;
    [rotation_rad[0] * s, rotation_rad[1] * s, rotation_rad[2] * s, (0.5 * angle).cos()]
}
