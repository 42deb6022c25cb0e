//! `wagashi mesh SURFACE -o OUT`: tetrahedralize a triangle surface.
//!
//! The pipeline, each step in its crate:
//!
//! 1. read the surface (`wagashi_io::surface::read_surface`: OBJ, STL, glTF/GLB, OFF;
//!    `--units`, `--scale`);
//! 2. repair it (`meshing::repair`: weld, drop degenerate and duplicate faces,
//!    orient consistently and outward), which the envelope's inside test needs
//!    for shells with flipped faces; the repaired surface is meshed unless its
//!    winding number is more often ambiguous (between 1/4 and 3/4 on a 16^3 grid)
//!    than the file's, which happens when repair cannot weld a soup and orients
//!    its pieces apart;
//! 3. mesh it: `--mode envelope` (the default; `meshing::envelope`, isosurface
//!    stuffing on the generalized winding number), with `--layers-mm` cutting
//!    layers along y; or `--mode conforming` (`meshing::conforming`: a boundary
//!    made of the input triangles exactly), which is strict: the surface as read,
//!    no repair, and a defective one is refused with the defect named;
//! 4. measure it (`meshing::quality::report`) and write the mesh (by extension:
//!    `.vtu`, `.msh`, or `.node`/`.ele` for TetGen's three files) and, with
//!    `--report`, the report as JSON.
//!
//! A short table goes to stdout, warnings to stderr as `warning: ...` lines, and
//! a progress line to stderr when it is a terminal.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use meshing::conforming::{conforming_mesh, ConformingOptions, ConformingStats};
use meshing::envelope::{
    envelope_mesh_with_progress, EnvelopeOptions, EnvelopeStats, EnvelopeWarning, DEFAULT_GRADE_LEVELS,
};
use meshing::quality::{report, QualityReport};
use meshing::repair::{repair, RepairOptions};
use meshing::WindingNumber;
use serde::Serialize;
use wagashi_io::surface::{read_surface, LengthUnit, SurfaceOptions};
use wagashi_io::tetmesh::{write_tetmesh, TetMeshFormat};
use wagashi_io::write_atomic;

use crate::press::positive_number;

const MESH_AFTER_HELP: &str = "\
Examples:
  # The Stanford bunny (OBJ in mm) with 0.3 mm tets, and its quality report:
  wagashi mesh bunny.obj -o bunny.vtu --size-mm 0.3 --report bunny-report.json

  # On a graded lattice (down to 0.2 / 2^3 mm at creases, curved and thin parts):
  # the boundary within 1e-3 of the diagonal, several times slower:
  wagashi mesh bunny.obj -o bunny.vtu --size-mm 0.2 --grade-levels 3

  # A glTF scan (metres by default), for Gmsh, in cm as the scanner wrote it:
  wagashi mesh scan.glb -o scan.msh --size-mm 2 --units cm

  # A cake cut into three layers along y (bottom-up thicknesses in mm), for TetGen:
  wagashi mesh cake.stl -o cake.node --size-mm 3 --layers-mm 20,20,19.5";

/// How to mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// Isosurface stuffing on the generalized winding number: any input (open,
    /// self-intersecting, non-manifold), guaranteed angles, boundary within the
    /// lattice's chord error of the input.
    Envelope,
    /// A boundary that reproduces the input exactly (clean, closed input only:
    /// a defect is refused, named); radius-edge and sliver refinement.
    Conforming,
}

/// `wagashi mesh SURFACE -o OUT --size-mm H`.
#[derive(Debug, Args)]
#[command(
    about = "Tetrahedralize a triangle surface (OBJ, STL, glTF, OFF) into a mesh with a quality report",
    long_about = "Tetrahedralize the triangle surface in SURFACE (OBJ, STL binary or ASCII, glTF or GLB, OFF) \
into tetrahedra of about --size-mm, and write them to OUT: .vtu (ParaView), .msh (Gmsh 4.1 ASCII) or \
.node (TetGen's .node, .ele and .face). Objects, groups, solids or meshes of the file become regions \
(a shell inside another is its own region); --layers-mm cuts the shape into layers along y instead. \
A quality table is printed; --report writes it as JSON.",
    after_help = MESH_AFTER_HELP
)]
pub struct MeshArgs {
    /// The surface file: .obj, .stl, .gltf, .glb or .off.
    #[arg(value_name = "SURFACE")]
    pub surface: PathBuf,

    /// The mesh to write: .vtu, .msh, or .node (writes .node, .ele and .face).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,

    /// Target edge length [mm] (the lattice spacing in envelope mode).
    #[arg(long = "size-mm", value_name = "H", value_parser = positive_number, allow_negative_numbers = true)]
    pub size_mm: f64,

    /// The mesher.
    #[arg(long, value_enum, default_value_t = Mode::Envelope)]
    pub mode: Mode,

    /// Layer thicknesses along y, bottom-up [mm], comma-separated (e.g. 20,20,19.5);
    /// they must add up to the shape's height within 1 %.
    #[arg(long = "layers-mm", value_name = "T1,T2,...", value_delimiter = ',', value_parser = positive_number, allow_negative_numbers = true)]
    pub layers_mm: Vec<f64>,

    /// Envelope mode (ignored by --mode conforming): refine the lattice by bisection down to
    /// --size-mm / 2^N where the surface is creased, curved or thin (0: the uniform lattice; at most 8);
    /// with N > 0 the rims of holes are cut deeper, down to --size-mm / 2^8, while their chord estimate
    /// exceeds 5e-4 of the diagonal. Grading brings the boundary within 1e-3 of the diagonal on
    /// creased input (the bunny at 0.2 mm, 3 levels) at several times the uniform lattice's time.
    #[arg(long = "grade-levels", value_name = "N", default_value_t = DEFAULT_GRADE_LEVELS,
          value_parser = clap::value_parser!(u32).range(0..=8))]
    pub grade_levels: u32,

    /// Also write the quality report as JSON here.
    #[arg(long, value_name = "REPORT.json")]
    pub report: Option<PathBuf>,

    /// The unit of the file's coordinates: mm, cm, m or in (default: mm for OBJ and STL, m for glTF).
    #[arg(long, value_name = "UNIT")]
    pub units: Option<String>,

    /// A factor applied to the coordinates after the unit conversion.
    #[arg(long, value_name = "FACTOR", default_value_t = 1.0, value_parser = positive_number, allow_negative_numbers = true)]
    pub scale: f64,

    /// Replace existing output files that wagashi did not write (OUT, with .node
    /// also the .ele and .face beside it, and the report); files a wagashi
    /// writer made are replaced without it.
    #[arg(long)]
    pub force: bool,
}

/// What the input was and what repair changed.
#[derive(Debug, Serialize)]
struct InputReport {
    file: String,
    format: String,
    unit: String,
    to_mm: f64,
    vertices: usize,
    triangles: usize,
    regions: Vec<String>,
    import_warnings: Vec<String>,
    repair: RepairSummary,
}

#[derive(Debug, Serialize)]
struct RepairSummary {
    welded_vertices: usize,
    dropped_degenerate: usize,
    dropped_duplicates: usize,
    flipped: usize,
    /// Whether the repaired surface was meshed (else the file's, as read).
    used: bool,
}

#[derive(Debug, Serialize)]
struct WarningEntry<'a> {
    message: String,
    #[serde(flatten)]
    detail: &'a EnvelopeWarning,
}

/// The JSON report.
#[derive(Debug, Serialize)]
struct MeshReport<'a> {
    wagashi_version: &'static str,
    input: InputReport,
    output: String,
    mode: &'static str,
    size_mm: f64,
    layers_mm: &'a [f64],
    #[serde(skip_serializing_if = "Option::is_none")]
    grade_levels: Option<u32>,
    quality: &'a QualityReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    envelope: Option<&'a EnvelopeStats>,
    #[serde(skip_serializing_if = "Option::is_none")]
    conforming: Option<&'a ConformingStats>,
    warnings: Vec<WarningEntry<'a>>,
}

/// Runs `wagashi mesh`.
pub fn run(args: &MeshArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    if args.mode == Mode::Conforming && !args.layers_mm.is_empty() {
        bail!("--layers-mm works with --mode envelope only (conforming mode keeps the input's regions)");
    }
    // Refuse bad outputs before the (possibly long) work.
    let format = TetMeshFormat::of_path(&args.output)?;
    check_folder(&args.output)?;
    if let Some(r) = &args.report {
        check_folder(r)?;
    }
    check_outputs(args, format)?;
    let units = match &args.units {
        Some(u) => Some(u.parse::<LengthUnit>().context("--units")?),
        None => None,
    };

    let clock = Instant::now();
    let imported = read_surface(&args.surface, &SurfaceOptions { units, scale: args.scale, format: None })?;
    let conforming = args.mode == Mode::Conforming;
    let repaired = repair(&imported.surface, &RepairOptions::default())
        .with_context(|| format!("{}: repairing the surface", args.surface.display()))?;
    // Repair orients by walking across edges; on a soup it cannot weld it may turn
    // faces the wrong way. Keep the version whose inside is less ambiguous.
    // Conforming mode is strict: the file's surface, as read.
    let (lo, hi) = imported.surface.bounding_box();
    let ambiguity = |s: &meshing::Surface| WindingNumber::new(s).ambiguous_fraction(lo, hi, 16);
    let repair_used = !conforming && ambiguity(&repaired.surface) <= ambiguity(&imported.surface);
    let surface = if repair_used { &repaired.surface } else { &imported.surface };

    let (mesh, warnings, envelope_stats, conforming_stats) = if conforming {
        let out = conforming_mesh(surface, &ConformingOptions::new(args.size_mm))
            .with_context(|| format!("{} (for defective input use --mode envelope)", args.surface.display()))?;
        (out.mesh, Vec::new(), None, Some(out.stats))
    } else {
        let bar = Progress::new();
        let options = EnvelopeOptions {
            layers_mm: args.layers_mm.clone(),
            grade_levels: args.grade_levels,
            ..EnvelopeOptions::new(args.size_mm)
        };
        let meshed = envelope_mesh_with_progress(surface, &options, &|stage, f| bar.update(stage, f));
        bar.finish();
        let meshed = meshed.with_context(|| format!("meshing {}", args.surface.display()))?;
        (meshed.mesh, meshed.warnings, Some(meshed.stats), None)
    };
    let mesh_time_s = clock.elapsed().as_secs_f64();
    let quality = report(&mesh, surface, mesh_time_s);

    write_tetmesh(&args.output, &mesh)?;
    let r = &repaired.report;
    let input = InputReport {
        file: args.surface.display().to_string(),
        format: format!("{:?}", imported.format).to_lowercase(),
        unit: imported.unit.to_string(),
        to_mm: imported.to_mm,
        vertices: imported.surface.num_vertices(),
        triangles: imported.surface.num_triangles(),
        regions: imported.surface.region_names.clone(),
        import_warnings: imported.warnings.clone(),
        repair: RepairSummary {
            welded_vertices: r.welded.iter().map(|g| g.len().saturating_sub(1)).sum(),
            dropped_degenerate: r.dropped_degenerate.len(),
            dropped_duplicates: r.dropped_duplicates.len(),
            flipped: r.flipped.len(),
            used: repair_used,
        },
    };
    let detail = match (&envelope_stats, &conforming_stats) {
        (Some(e), _) => format!("{} lattice vertices, {} warped", e.lattice_vertices, e.warped_vertices),
        (_, Some(c)) => format!(
            "{} Steiner points on input edges, {} in input triangles, {} inside",
            c.steiner_on_edges, c.steiner_on_triangles, c.refinement.circumcentres
        ),
        _ => String::new(),
    };
    print_table(out, args, format, &input, &quality, &detail)?;
    let mut err = std::io::stderr().lock();
    for w in &imported.warnings {
        writeln!(err, "warning: {}: {w}", args.surface.display())?;
    }
    for w in &warnings {
        writeln!(err, "warning: {w}")?;
    }
    if let Some(path) = &args.report {
        let json = MeshReport {
            wagashi_version: env!("CARGO_PKG_VERSION"),
            input,
            output: args.output.display().to_string(),
            mode: if conforming { "conforming" } else { "envelope" },
            size_mm: args.size_mm,
            layers_mm: &args.layers_mm,
            grade_levels: (!conforming).then_some(args.grade_levels),
            quality: &quality,
            envelope: envelope_stats.as_ref(),
            conforming: conforming_stats.as_ref(),
            warnings: warnings.iter().map(|w| WarningEntry { message: w.to_string(), detail: w }).collect(),
        };
        let text = serde_json::to_string_pretty(&json).context("formatting the report")?;
        write_atomic(path, (text + "\n").as_bytes())?;
        writeln!(out, "report: {}", path.display())?;
    }
    Ok(())
}

/// The files `-o OUT` writes: OUT, or for TetGen the three files of its stem.
fn mesh_files(output: &Path, format: TetMeshFormat) -> Vec<PathBuf> {
    match format {
        TetMeshFormat::TetGen => ["node", "ele", "face"].iter().map(|e| output.with_extension(e)).collect(),
        _ => vec![output.to_path_buf()],
    }
}

/// Every output must stay off the input surface (and a glTF's buffers and
/// images), killed writes' temporaries beside an output are removed, and an existing file is
/// replaced only when wagashi wrote it or with `--force`; the report may not
/// be one of the mesh files.
fn check_outputs(args: &MeshArgs, format: TetMeshFormat) -> anyhow::Result<()> {
    // A glTF surface's buffers and images are inputs too; a URI the reader
    // refuses is reported when the surface is read.
    let companions = wagashi_io::surface::gltf_companions(&args.surface).unwrap_or_default();
    let mut inputs = vec![("surface", args.surface.as_path())];
    inputs.extend(companions.iter().map(|c| ("file of the glTF surface", c.as_path())));
    let meshes = mesh_files(&args.output, format);
    for file in &meshes {
        crate::outputs::refuse_input_overlap("-o", file, &inputs)?;
        crate::outputs::refuse_foreign_file("-o", file, args.force)?;
        crate::outputs::sweep_stale(file);
    }
    if let Some(report) = &args.report {
        crate::outputs::refuse_input_overlap("--report", report, &inputs)?;
        crate::outputs::refuse_foreign_file("--report", report, args.force)?;
        crate::outputs::sweep_stale(report);
        let resolved = crate::press::resolve(report)?;
        for file in &meshes {
            if crate::press::resolve(file)? == resolved {
                bail!("{}: --report would overwrite the mesh written by -o; give it another name", report.display());
            }
        }
    }
    Ok(())
}

/// The folder of an output file must exist (the writers do not create folders).
fn check_folder(path: &Path) -> anyhow::Result<()> {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !parent.is_dir() {
        bail!("{}: the folder {} does not exist", path.display(), parent.display());
    }
    if path.is_dir() {
        bail!("{}: is a folder; give a file name (.vtu, .msh or .node)", path.display());
    }
    Ok(())
}

fn print_table(
    out: &mut dyn Write,
    args: &MeshArgs,
    format: TetMeshFormat,
    input: &InputReport,
    q: &QualityReport,
    detail: &str,
) -> std::io::Result<()> {
    let written = match format {
        TetMeshFormat::TetGen => {
            let stem = args.output.with_extension("");
            format!("{0}.node, {0}.ele, {0}.face", stem.display())
        }
        _ => args.output.display().to_string(),
    };
    let mode = if args.mode == Mode::Conforming { "conforming" } else { "envelope" };
    writeln!(out, "{} -> {written} ({mode}, {} mm)", input.file, args.size_mm)?;
    let row = |out: &mut dyn Write, k: &str, v: String| writeln!(out, "  {k:<18} {v}");
    row(
        out,
        "input",
        format!("{} triangles, {} vertices, in {} (x {})", input.triangles, input.vertices, input.unit, input.to_mm),
    )?;
    let rep = &input.repair;
    if rep.welded_vertices + rep.dropped_degenerate + rep.dropped_duplicates + rep.flipped > 0 {
        let used = if rep.used { "" } else { " (not used: its inside was more ambiguous than the file's)" };
        row(
            out,
            "repair",
            format!(
                "{} vertices welded, {} degenerate and {} duplicate triangles dropped, {} flipped{used}",
                rep.welded_vertices, rep.dropped_degenerate, rep.dropped_duplicates, rep.flipped
            ),
        )?;
    }
    row(out, "mesh", format!("{} nodes, {} tets, {} boundary faces", q.num_nodes, q.num_cells, q.num_boundary_faces))?;
    row(
        out,
        "dihedral angles",
        format!(
            "{:.2} .. {:.2} deg, {:.3} % of tets under 10 deg",
            q.min_dihedral_deg,
            q.max_dihedral_deg,
            100.0 * q.fraction_below_10_deg
        ),
    )?;
    row(out, "radius-edge", format!("max {:.3}, p99.9 {:.3}", q.max_radius_edge, q.p999_radius_edge))?;
    row(out, "radius ratio", format!("mean {:.3}, min {:.3}", q.mean_radius_ratio, q.min_radius_ratio))?;
    row(
        out,
        "volume",
        format!(
            "{:.6e} mm^3 (surface {:.6e} mm^3, error {:+.2e})",
            q.volume_mm3, q.reference_volume_mm3, q.volume_error
        ),
    )?;
    row(
        out,
        "Hausdorff",
        format!(
            "{:.3e} mm = {:.2e} of the {:.4} mm diagonal, to the solid's boundary: the input's part bounding it \
             and the level set w = 1/2 over holes (mesh->solid {:.3e}, input->mesh {:.3e}; {} input triangles \
             bound nothing, {} in part)",
            q.hausdorff_mm,
            q.hausdorff_relative,
            q.diagonal_mm,
            q.mesh_to_surface_mm,
            q.surface_to_mesh_mm,
            q.num_interior_input_triangles,
            q.num_partly_interior_input_triangles
        ),
    )?;
    if q.num_border_edges > 0 {
        row(
            out,
            "hole caps",
            format!(
                "{:.3e} mm = {:.2e} of the diagonal from the input, {:.3e} mm = {:.2e} from the level set \
                 w = 1/2 closing them, {:.2} % of the boundary ({} border edges, widest hole {:.3} mm)",
                q.hole_cap_mm,
                q.hole_cap_relative,
                q.cap_to_level_set_mm,
                q.cap_to_level_set_relative,
                100.0 * q.hole_cap_fraction,
                q.num_border_edges,
                q.widest_hole_mm
            ),
        )?;
    }
    row(
        out,
        "Hausdorff (raw)",
        format!(
            "{:.3e} mm = {:.2e} of the diagonal, every input triangle and hole cap counted (mesh->input {:.3e}, \
             input->mesh {:.3e})",
            q.raw_hausdorff_mm, q.raw_hausdorff_relative, q.raw_mesh_to_surface_mm, q.raw_surface_to_mesh_mm
        ),
    )?;
    for r in &q.regions {
        let reference = match (r.reference_volume_mm3, r.volume_error) {
            (Some(v), Some(e)) => format!(" (reference {v:.6e}, error {e:+.2e})"),
            _ => String::new(),
        };
        row(out, &format!("region {}", r.name), format!("{} tets, {:.6e} mm^3{reference}", r.num_cells, r.volume_mm3))?;
    }
    row(out, "time", format!("{:.2} s meshing ({detail}), {:.2} s report", q.mesh_time_s, q.report_time_s))?;
    Ok(())
}

/// A one-line progress display on stderr, hidden when it is not a terminal.
struct Progress {
    bar: ProgressBar,
}

impl Progress {
    fn new() -> Self {
        let target =
            if std::io::stderr().is_terminal() { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
        let bar = ProgressBar::with_draw_target(Some(100), target);
        let style = ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:32}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        bar.set_message("reading");
        bar.enable_steady_tick(Duration::from_millis(200));
        Self { bar }
    }

    fn update(&self, stage: &str, fraction: f64) {
        // Stuffing is most of the work: it spans 0..80 %, the rest the remainder.
        let position = match stage {
            "stuffing" => 80.0 * fraction,
            "inside test" => 0.0,
            "regions" | "layers" => 82.0,
            "thin parts" => 90.0,
            _ => 100.0 * fraction,
        };
        self.bar.set_position(position.clamp(0.0, 100.0) as u64);
        self.bar.set_message(stage.to_string());
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
