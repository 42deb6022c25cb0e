//! `wagashi press`: simulate an experiment bundle.
//!
//! Reading, meshing and simulating belong to `wagashi-io` and `fem-core`; this
//! module chooses the defaults of the command line, drives the progress bar and
//! writes the output folder (atomically, through [`wagashi_io::AtomicDir`]):
//!
//! | file               | what                                                              |
//! |--------------------|-------------------------------------------------------------------|
//! | `experiment.toml`  | the input trial under the name `NAME-sim`, naming the files below |
//! | `force.csv`        | `t_s,force_N`: the simulated bottom force at the measured times, or every `--output-dt` |
//! | `markers.csv`      | the bundle's markers, simulated, at their measured times (when it has markers) |
//! | `summary.json`     | sizes, counts, timings and the results printed on stdout          |
//! | `steps.csv`        | one row per accepted time step                                    |
//! | `keep.vtu`         | the keep shape (at `release_s`): displacement, region, stress     |
//! | `final.vtu`        | the final shape (at `end_s`)                                      |
//! | `force.svg`        | simulated (and measured) force against time                       |
//! | `tpa.json`         | with two loading strokes in the protocol: the simulated force's texture profile ([`crate::tpa`]) |
//! | `shape.svg`        | the specimen's outline (a 3D body's section through the middle of its depth) at the start, the keep time and the end, to scale in mm ([`crate::shape_svg`]) |
//! | `stress_strain.csv` | `t_s,strain,stress_kPa` for a block or cylinder under the protocol's plate, until `release_s`: nominal strain (the plate's travel over the initial height) and nominal stress (`force.csv` over the initial cross-section), compression positive |
//! | `shapes.pvd`, `shapes/` | with `--pvd N`: N + 1 shapes evenly spaced in time           |
//! | `frames.bin`       | with `--gltf`: the glTF's frames, for `wagashi export` ([`crate::export`]) |
//! | `tools.csv`        | with contact tools: each tool's contact force, normal and tangential parts and contact area at every step |
//! | `contact_nodes.json` | with contact tools: the nodes touching each tool at the kept times |
//! | `specimen/FILE`    | with `shape = "surface"` or `"mesh"`: a copy of the specimen's surface or mesh file(s), which the output's `experiment.toml` names |
//! | `tools/NAME.EXT`   | with surface tools: a copy of each tool's surface file, which the output's `experiment.toml` names |
//! | `*.bufferI.EXT`, `*.imageI.EXT` | beside a copied glTF file: the buffers and images it names by relative URIs, renamed (the copy's URIs name them), so that the copy reads back |
//!
//! Trials other than the seed's press (a sphere, a punch, a surface tool,
//! friction, `[[protocol.tools]]`; `Bundle::has_contact_tools`) run with rigid
//! contact tools, which need `--integrator implicit` (refused up front
//! otherwise). `force.csv` stays the bottom force (the floor's, with
//! `support = "friction"`); `tools.csv` has one row per tool and accepted step
//! (and t = 0), in time order:
//! `t_s,tool,force_x_N,force_y_N,force_z_N,normal_N,tangential_N,area_mm2`, the
//! force being the one the specimen puts on the tool (world axes: a tool pressing
//! down feels +y, the floor -y; full-circle forces for the axisymmetric model,
//! whose x and z parts are 0). `contact_nodes.json` lists, per tool and kept time
//! (the release, the end, the `--pvd` and `--gltf` frames), the 0-based indices of
//! the mesh nodes in contact (the points of the `.vtu` files):
//! `{"tools": [{"name", "snapshots": [{"t_s", "normal_N", "area_mm2", "nodes"}]}]}`.
//! A contact that does not settle ends the run with one line naming the step,
//! the time, the tool and the nodes.
//!
//! `--gltf FILE.glb` also writes the run as an animated glTF 2.0 binary
//! ([`crate::export`]): the `--pvd` times as frames, else 60 intervals; inside
//! `OUT`, the file is part of the folder's atomic write.
//!
//! The output folder is itself a bundle: `wagashi press OUT -o OUT2` reads it back
//! as if measured and reports the difference.
//!
//! A `shape = "surface"` specimen is meshed on the fly at `--size-mm` (default: a
//! quarter of the smallest side of its bounding box) by `--mesh-mode conforming` (the default: the
//! boundary is the surface exactly; a defective surface is refused naming the
//! defect, with envelope mode suggested) or `--mesh-mode envelope`; the mode is
//! printed with the mesh and recorded as `surface_mesh_mode` in `summary.json`.
//! Such a specimen stands on the floor at its lowest y and always runs with
//! contact tools (`wagashi_io::Bundle::mesh_specimen_surface`). A `shape = "mesh"`
//! specimen (a Gmsh `.msh`, TetGen `.node`/`.ele` or `.vtu` mesh, e.g. from `wagashi mesh`)
//! is pressed with the cells of its file, `--size-mm` not applying, likewise on
//! the floor and with contact tools (`wagashi_io::Bundle::specimen_mesh`).
//!
//! `--axisymmetric` simulates a cylinder bundle by its axisymmetric `r-y` section
//! (`Bundle::to_press_axisymmetric`): the same full-circle force, shapes written
//! as the section (x = r) with the stress components `RR, YY, TT, RY`, and the
//! markers put back on their azimuths in `markers.csv`.

use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use fem_core::element::Formulation;
use fem_core::press::{
    simulate_any_cancellable, AnyPress, Integrator, PressResult, Settings, Snapshot, Tool, ToolSample, ToolTrack,
    Volumetric,
};
use wagashi_io::vtu::{write_pvd, write_vtu, VtuFields};
use wagashi_io::{
    read_bundle_with, read_materials_file, write_atomic, write_bundle, AtomicDir, Bundle, BundleWrite, ForceSample,
    ForceSeries, MarkerSeries, SurfaceMeshing, WriteError,
};

use crate::plot::force_svg;
use crate::progress::SimulationBar;
use crate::summary::{number, steps_csv, ForceComparison, StrokeShape, Summary};

/// The most force samples `--output-dt` may ask for.
const MAX_OUTPUT_SAMPLES: f64 = 1e7;

/// The most steps `--dt` may ask for: each takes at least one solve and keeps a
/// step record, so more is hours of work and gigabytes of records.
const MAX_FIXED_STEPS: f64 = 1e6;

const PRESS_AFTER_HELP: &str = "\
Examples:
  # The seed paper's material 1 trial, default element size (a quarter of the smallest side):
  wagashi press examples/paper/mat1 -o out/mat1

  # A coarse, quick run of a layered trial, shapes every 40 s for ParaView:
  wagashi press examples/paper/mat1+2 -o out/mat1+2 --size-mm 10 --pvd 10

  # The material 1 trial with the seed's shape parameters (x_shape) from a materials file:
  wagashi press examples/paper/mat1 --materials examples/paper/x-shape.toml -o out/mat1-shape

  # A specimen given as a closed surface (shape = \"surface\"), meshed on the fly (conforming mode):
  wagashi press bunny-trial -o out/bunny --size-mm 1.5

  # A specimen given as a tetrahedral mesh (shape = \"mesh\", mesh = \"bunny.msh\"), pressed as it is:
  wagashi mesh bunny.obj -o mesh-trial/bunny.msh --size-mm 1.5 && wagashi press mesh-trial -o out/mesh

  # Run again into the same folder (replaces the previous output):
  wagashi press examples/paper/mat1 -o out/mat1 --force

  # A cylinder bundle by its axisymmetric section (2D cost, full-circle force):
  wagashi press my/cylinder -o out/cylinder --axisymmetric

  # With an animated glTF of the run (60 frames; open it in any glTF viewer):
  wagashi press examples/paper/mat1 -o out/mat1 --size-mm 6 --gltf out/mat1.glb

  # A double compression: the plate leaves the specimen and touches it again (tools.csv):
  wagashi press examples/paper/double-compression -o out/tpa --gltf out/tpa.glb";

/// `wagashi press BUNDLE -o OUT`.
#[derive(Debug, Args)]
#[command(
    about = "Simulate a compression trial described by an experiment bundle",
    long_about = "Simulate a compression trial described by an experiment bundle (a folder holding \
experiment.toml, see experiment-format.md) and write the results into OUT: the simulated trial as a \
bundle (experiment.toml, force.csv, markers.csv), summary.json, steps.csv, the keep and final shapes \
(keep.vtu, final.vtu, for ParaView) and force.svg; with rigid contact tools (a sphere, a punch, a \
surface tool, friction, a second stroke, [[protocol.tools]]) also tools.csv and contact_nodes.json. OUT \
is written atomically; the input bundle is never modified.",
    after_help = PRESS_AFTER_HELP
)]
pub struct PressArgs {
    /// The experiment bundle: a folder holding experiment.toml.
    #[arg(value_name = "BUNDLE")]
    pub bundle: PathBuf,

    /// The output folder; refused if it exists and is not a previous wagashi output.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,

    /// Target element size [mm]; default: a quarter of the specimen's smallest
    /// dimension (min(W, H, T) / 4 for a block, min(R, H) / 4 for a cylinder, the
    /// smallest side of the bounding box / 4 for a surface); a mesh specimen
    /// (shape = "mesh") is pressed with its file's cells, whatever the size.
    #[arg(long = "size-mm", value_name = "H", value_parser = positive_number, allow_negative_numbers = true)]
    pub size_mm: Option<f64>,

    /// Time integrator: implicit (quasi-static, exact history update), dynamic
    /// (generalized-alpha, lumped mass) or seed (the seed paper's explicit scheme; slow).
    /// Trials with rigid contact tools need implicit.
    #[arg(long, value_enum, default_value_t = IntegratorArg::Implicit)]
    pub integrator: IntegratorArg,

    /// Local error tolerance of the adaptive time steps, relative to the largest
    /// plate displacement.
    #[arg(long, value_name = "R", default_value_t = Settings::default().rtol, value_parser = positive_number, allow_negative_numbers = true)]
    pub rtol: f64,

    /// A fixed time step [s] instead of adaptive steps (steps still land on the
    /// protocol's kinks).
    #[arg(long = "dt", value_name = "S", value_parser = positive_number, allow_negative_numbers = true)]
    pub dt_s: Option<f64>,

    /// A TOML file of [materials.NAME] tables; each replaces the bundle's
    /// material of the same name.
    #[arg(long, value_name = "FILE")]
    pub materials: Option<PathBuf>,

    /// Spacing [s] of the simulated force samples when the bundle has no measured
    /// force (with measured force, the measured times are used).
    #[arg(long = "output-dt", value_name = "S", default_value_t = 0.1, value_parser = positive_number, allow_negative_numbers = true)]
    pub output_dt_s: f64,

    /// Also write N + 1 shapes evenly spaced in time from 0 to end_s
    /// (shapes/shape-*.vtu) and shapes.pvd, a time series for ParaView.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub pvd: Option<u32>,

    /// Replace OUT when it holds a previous wagashi output (a folder whose
    /// wagashi-manifest.json lists every file in it; only those files are
    /// removed); any other existing folder is never replaced.
    #[arg(long)]
    pub force: bool,

    /// Run even when the estimated memory of the mesh (6 V / h^3 tetrahedra in
    /// 3D) exceeds the memory the machine has available.
    #[arg(long = "allow-large")]
    pub allow_large: bool,

    /// Also write the run as an animated glTF 2.0 binary (name ending in .glb):
    /// the specimen's surface deforming (frames at the --pvd times, else 60
    /// intervals over the trial), the plate (or the contact tools) moving, lengths in metres, colours
    /// for the displacement magnitude. Adds frames.bin to OUT for `wagashi export`.
    /// An existing .glb is replaced; any other existing file is refused.
    #[arg(long, value_name = "FILE.glb")]
    pub gltf: Option<PathBuf>,

    /// How a shape = "surface" specimen is meshed: conforming (the default; the
    /// boundary is the surface exactly, a defective surface is refused with the
    /// defect named) or envelope (any surface, boundary within the lattice's
    /// chord error). Ignored for blocks and cylinders.
    #[arg(long = "mesh-mode", value_enum, default_value_t = MeshModeArg::Conforming)]
    pub mesh_mode: MeshModeArg,

    /// Simulate a cylinder (shape = "cylinder") by its axisymmetric r-y section
    /// with 2D axisymmetric triangles instead of 3D tetrahedra: the same
    /// full-circle force at a small fraction of the cost. Refused for other shapes.
    #[arg(long)]
    pub axisymmetric: bool,

    /// F-bar patches for network materials near incompressibility (poisson
    /// from about 0.45): the cells of each patch of 4 tetrahedra (3
    /// triangles) share its volume change, so the mesh does not lock. Costs
    /// 1.6-3x per step in 3D. Refused without a network material.
    #[arg(long)]
    pub fbar: bool,
}

/// `--mesh-mode`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MeshModeArg {
    /// A boundary made of the input triangles exactly (clean, closed input).
    Conforming,
    /// Isosurface stuffing on the generalized winding number (any input).
    Envelope,
}

impl MeshModeArg {
    fn mode(self) -> SurfaceMeshing {
        match self {
            MeshModeArg::Conforming => SurfaceMeshing::Conforming,
            MeshModeArg::Envelope => SurfaceMeshing::Envelope,
        }
    }
}

/// `--integrator`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IntegratorArg {
    /// Quasi-static implicit steps with the exact history update (default).
    Implicit,
    /// Dynamic generalized-alpha steps (rho_inf = 0.5) with a lumped mass.
    Dynamic,
    /// The seed paper's scheme: dynamics, constraint stabilisation, explicit Runge-Kutta.
    Seed,
}

impl IntegratorArg {
    fn integrator(self) -> Integrator {
        match self {
            IntegratorArg::Implicit => Integrator::QuasiStatic,
            IntegratorArg::Dynamic => Integrator::Dynamic,
            IntegratorArg::Seed => Integrator::Seed,
        }
    }

    /// The name as the command line spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            IntegratorArg::Implicit => "implicit",
            IntegratorArg::Dynamic => "dynamic",
            IntegratorArg::Seed => "seed",
        }
    }
}

/// The Poisson ratio at which a network material locks on linear cells
/// without F-bar (0.45 or more), to say so before the run.
pub(crate) fn locking_poisson(problem: &AnyPress, volumetric: Volumetric) -> Option<f64> {
    const LOCKS_FROM: f64 = 0.45;
    problem.largest_network_poisson().filter(|&nu| nu >= LOCKS_FROM && volumetric == Volumetric::Standard)
}

/// A clap value parser for a finite number > 0 (every `*-mm` and `*-s` flag).
pub(crate) fn positive_number(s: &str) -> Result<f64, String> {
    let x: f64 = s.trim().parse().map_err(|_| format!("`{s}` is not a number"))?;
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(format!("{s} must be a finite number > 0"))
    }
}

/// Everything one simulation needs besides the bundle: what `press` reads from
/// its flags and `demo` fixes.
#[derive(Debug, Clone)]
pub struct PressOptions {
    /// Element size [mm]; `None`: a quarter of the smallest dimension.
    pub size_mm: Option<f64>,
    /// Where a given `size_mm` comes from, for the report (e.g. `--size-mm`).
    pub size_origin: &'static str,
    /// The integrator.
    pub integrator: IntegratorArg,
    /// Relative tolerance of the adaptive steps.
    pub rtol: f64,
    /// Fixed step [s], if any.
    pub dt_s: Option<f64>,
    /// Force sample spacing [s] when nothing was measured.
    pub output_dt_s: f64,
    /// Number of intervals of the `--pvd` time series.
    pub pvd: Option<u32>,
    /// The output folder.
    pub output: PathBuf,
    /// Replace a previous wagashi output in `output`.
    pub replace: bool,
    /// The Newton path's volumetric treatment (`--fbar`).
    pub volumetric: Volumetric,
    /// Run a mesh whose estimated memory exceeds the available memory (`--allow-large`).
    pub allow_large: bool,
    /// Input files besides the bundle (`("materials file", path)`), which no
    /// output may touch.
    pub other_inputs: Vec<(&'static str, PathBuf)>,
}

/// `wagashi press`; the mesh line and the results go to `out` (stdout for the binary).
pub fn run(args: &PressArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let external = match &args.materials {
        Some(path) => read_materials_file(path)?,
        None => Default::default(),
    };
    let dir = bundle_dir(&args.bundle)?;
    let bundle = read_bundle_with(&dir, &external)?;
    let options = PressOptions {
        size_mm: args.size_mm,
        size_origin: "--size-mm",
        integrator: args.integrator,
        rtol: args.rtol,
        dt_s: args.dt_s,
        output_dt_s: args.output_dt_s,
        pvd: args.pvd,
        output: args.output.clone(),
        replace: args.force,
        volumetric: if args.fbar { Volumetric::FBar } else { Volumetric::Standard },
        allow_large: args.allow_large,
        other_inputs: args.materials.iter().map(|m| ("materials file", m.clone())).collect(),
    };
    let how = How { axisymmetric: args.axisymmetric, surface_mesh: args.mesh_mode.mode() };
    let summary = press_bundle_as(&bundle, &options, how, args.gltf.as_deref(), out)?;
    print_results(&summary, out)?;
    if let Some(gltf) = &args.gltf {
        writeln!(out, "glTF                  {}", gltf.display())?;
    }
    Ok(())
}

/// The bundle folder of a BUNDLE argument: the folder itself, or the folder of a
/// given `experiment.toml`.
fn bundle_dir(path: &Path) -> anyhow::Result<PathBuf> {
    if path.is_dir() {
        return Ok(path.to_path_buf());
    }
    if path.is_file() && path.file_name().is_some_and(|n| n == wagashi_io::bundle::EXPERIMENT_FILE) {
        let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        return Ok(parent.to_path_buf());
    }
    if path.exists() {
        bail!("{}: not a bundle: a bundle is a folder holding experiment.toml", path.display());
    }
    bail!("{}: no such folder (a bundle is a folder holding experiment.toml)", path.display());
}

/// Simulates `bundle` with `options` and writes the output folder; reports the
/// mesh and progress on the way (`out`: stdout; the bar: stderr). Both `press`
/// and `demo` go through here.
pub fn press_bundle(bundle: &Bundle, options: &PressOptions, out: &mut dyn Write) -> anyhow::Result<Summary> {
    press_bundle_as(bundle, options, How::default(), None, out)
}

/// How `press` models the specimen beyond its element size.
#[derive(Debug, Clone, Copy, Default)]
struct How {
    /// A cylinder by its axisymmetric section (`--axisymmetric`).
    axisymmetric: bool,
    /// The mesher of a surface specimen (`--mesh-mode`).
    surface_mesh: SurfaceMeshing,
}

/// [`press_bundle`], with the cylinder modelled by its axisymmetric section when
/// `how.axisymmetric` (`--axisymmetric`), a surface specimen meshed by
/// `how.surface_mesh` (`--mesh-mode`), and the animated glTF written to `gltf` (`--gltf`).
fn press_bundle_as(
    bundle: &Bundle,
    options: &PressOptions,
    how: How,
    gltf: Option<&Path>,
    out: &mut dyn Write,
) -> anyhow::Result<Summary> {
    let clock = Instant::now();
    let protocol = &bundle.experiment.protocol;
    let end_s = protocol.end_s;
    let keep_time_s = protocol.release_s.min(end_s);

    // Refuse a bad output folder before the (possibly long) simulation.
    let mut inputs: Vec<(&str, &Path)> = vec![("bundle", bundle.dir.as_path())];
    inputs.extend(options.other_inputs.iter().map(|(what, p)| (*what, p.as_path())));
    let output = prepare_output(&inputs, &options.output, options.replace)?;
    let gltf = match gltf {
        Some(path) => {
            crate::export::check_frame_count(options.pvd)?;
            Some(crate::export::GltfTarget::check(path, &inputs, Some(&options.output))?)
        }
        None => None,
    };
    if let Some(dt_s) = options.dt_s {
        let steps = end_s / dt_s;
        if steps > MAX_FIXED_STEPS {
            bail!("--dt {dt_s} s gives {steps:.3e} steps over {end_s} s; at most {MAX_FIXED_STEPS:.0e} fixed steps are taken");
        }
    }

    let (size_mm, size_origin) = match (options.size_mm, bundle.default_size_mm()) {
        (Some(h), _) => (h, options.size_origin),
        (None, Some(h)) => (h, "default: a quarter of the smallest dimension"),
        // A surface that cannot be read: `to_press` refuses it, naming the file
        // and line, before the size is used.
        (None, None) => (1.0, "default"),
    };
    let pvd_times: Vec<f64> = match options.pvd {
        Some(n) => (0..=n).map(|i| if i == n { end_s } else { end_s * f64::from(i) / f64::from(n) }).collect(),
        None => Vec::new(),
    };
    let snapshot_times = match gltf {
        Some(_) => crate::export::frame_times(end_s, &pvd_times),
        None => pvd_times.clone(),
    };
    // A protocol of several strokes: the shapes at each stroke's peak and after it.
    let strokes = if crate::tpa::is_double_compression(&protocol.waypoints) {
        stroke_times(&protocol.waypoints, end_s)
    } else {
        Vec::new()
    };
    let mut snapshot_times = snapshot_times;
    snapshot_times.extend(strokes.iter().flat_map(|&(peak, after)| [peak, after]));
    snapshot_times.sort_by(f64::total_cmp);
    snapshot_times.dedup();
    let surface_mesh_mode = bundle.surface_path().map(|_| how.surface_mesh.as_str());
    // A `shape = "mesh"` specimen has the cells of its file, whatever the size.
    let mesh_file = bundle.mesh_path();
    if bundle.experiment.dimension == 3 && !how.axisymmetric && mesh_file.is_none() {
        if let Some(volume) = bundle.volume_mm3() {
            // The kept shapes: the frames, the stroke shapes, the release and the end.
            let kept = snapshot_times.len() + crate::outputs::DEFAULT_SNAPSHOTS;
            crate::outputs::check_memory(volume, size_mm, kept, options.size_origin, options.allow_large)?;
        }
    }
    let mut problem = if how.axisymmetric {
        bundle.to_press_axisymmetric(size_mm)?
    } else {
        bundle.to_press_meshed(size_mm, how.surface_mesh)?
    };
    let tool_names: Vec<String> = problem_tools(&problem).iter().map(|t| t.name.clone()).collect();
    if !tool_names.is_empty() && options.integrator != IntegratorArg::Implicit {
        bail!(
            "--integrator {}: {} runs with rigid contact tools ({}), which need --integrator implicit",
            options.integrator.as_str(),
            bundle.experiment_file().display(),
            tool_names.join(", ")
        );
    }
    set_snapshot_times(&mut problem, &snapshot_times);
    let mesh = MeshInfo::of(&problem)?;
    let model = match (&problem, surface_mesh_mode) {
        (AnyPress::Axisymmetric(_), _) => "axisymmetric (r-y section)".to_string(),
        (_, Some(mode)) => format!("{}D, surface meshed in {mode} mode", mesh.dimension),
        _ => format!("{}D", mesh.dimension),
    };
    let elements = match &mesh_file {
        Some(path) => format!("the elements of {}", path.display()),
        None => format!("{size_mm} mm elements ({size_origin})"),
    };
    writeln!(
        out,
        "{}: {model}, {elements}, {} {}, {} nodes",
        bundle.experiment.name, mesh.num_cells, mesh.cell_kind, mesh.num_nodes
    )?;

    let settings = Settings {
        integrator: options.integrator.integrator(),
        rtol: options.rtol,
        fixed_dt_s: options.dt_s,
        volumetric: options.volumetric,
        ..Settings::default()
    };
    if let Some(nu) = locking_poisson(&problem, options.volumetric) {
        writeln!(
            out,
            "note: a network material with poisson = {nu} on linear cells locks (too stiff); --fbar removes that"
        )?;
    }
    let bar = SimulationBar::new(end_s);
    let sim_clock = Instant::now();
    let result = {
        // An interrupt stops the run between steps (`crate::outputs`).
        let _cancellable = crate::outputs::CancellableRun::start();
        simulate_any_cancellable(&problem, &settings, crate::outputs::cancel_flag(), &mut |p| bar.update(p))
    };
    bar.finish();
    let result = result.with_context(|| format!("simulating {}", bundle.experiment_file().display()))?;
    let wall_time_s = sim_clock.elapsed().as_secs_f64();

    // Force samples: at the measured times up to end_s (nothing is simulated
    // after it: no held value is written or compared), else on the --output-dt grid.
    let in_run = bundle.force.as_ref().map(|m| measured_until(m, end_s));
    if let Some((_, left_out @ 1..)) = in_run {
        writeln!(out, "note: {left_out} measured force samples after end_s = {end_s} s are left out (not simulated)")?;
    }
    let measured = in_run.as_ref().map(|(m, _)| m).filter(|m| !m.samples.is_empty());
    let times = match measured {
        Some(m) => m.samples.iter().map(|s| s.t_s).collect(),
        None => uniform_times(end_s, options.output_dt_s)?,
    };
    let force = ForceSeries::sampled(&result, &times);
    let comparison = measured.map(|m| ForceComparison::new(&force, m));
    // In the bundle's coordinates (the axisymmetric (r, y) back on each marker's azimuth).
    let markers: Vec<MarkerSeries> = bundle.simulated_markers(&problem, &result.markers);

    let keep = snapshot(&result, keep_time_s)?;
    let mut stroke_files: Vec<String> = Vec::new();
    let last = snapshot(&result, end_s)?;
    let name = format!("{}-sim", bundle.experiment.name);
    let dir = output.path();
    // Surface tools: their files go into the output, which names its copies.
    let mut experiment = bundle.experiment.clone();
    let tool_files = copy_tool_surfaces(bundle, &mut experiment, dir)?;
    write_bundle(
        dir,
        &BundleWrite { experiment: &experiment, ..BundleWrite::simulated(bundle, &name, &force, &markers) },
    )?;
    write_atomic(dir.join("steps.csv"), steps_csv(&result.steps).as_bytes())?;
    write_shape(&dir.join("keep.vtu"), &problem, keep)?;
    write_shape(&dir.join("final.vtu"), &problem, last)?;
    let mut stroke_shapes = Vec::new();
    for (i, &(peak_t, after_t)) in strokes.iter().enumerate() {
        let (peak, after) = (snapshot(&result, peak_t)?, snapshot(&result, after_t)?);
        for (file, shape) in
            [(format!("stroke{}-peak.vtu", i + 1), peak), (format!("stroke{}-after.vtu", i + 1), after)]
        {
            write_shape(&dir.join(&file), &problem, shape)?;
            stroke_files.push(file);
        }
        stroke_shapes.push(StrokeShape {
            peak_t_s: peak_t,
            peak_force_n: result.bottom_force_at(peak_t),
            peak_height_loss_mm: mesh.height_loss_mm(peak),
            after_t_s: after_t,
            after_height_loss_mm: mesh.height_loss_mm(after),
        });
    }
    write_atomic(dir.join("force.svg"), force_svg(&bundle.experiment.name, &force, measured)?.as_bytes())?;
    let rest = Snapshot { t_s: 0.0, displacement: vec![0.0; keep.displacement.len()], cell_stress: Vec::new() };
    let (keep_label, end_label) =
        (format!("keep, t = {} s", number(keep.t_s)), format!("end, t = {} s", number(last.t_s)));
    let shapes = [("start", &rest), (keep_label.as_str(), keep), (end_label.as_str(), last)];
    let outline = crate::shape_svg::Outline::of(&problem);
    let svg = crate::shape_svg::shape_svg(&bundle.experiment.name, &problem, &outline, &shapes)?;
    write_atomic(dir.join("shape.svg"), svg.as_bytes())?;
    let mut files: Vec<String> = ["experiment.toml", "force.csv"].map(String::from).to_vec();
    if crate::tpa::is_double_compression(&protocol.waypoints) {
        // The texture profile of the simulated force.csv (what `wagashi tpa OUT` reports).
        match crate::tpa::simulated_tpa(&options.output.join("force.csv"), &force) {
            Ok(tpa) => {
                let json = crate::tpa::tpa_json(&options.output.display().to_string(), &tpa);
                write_atomic(dir.join("tpa.json"), format!("{}\n", serde_json::to_string_pretty(&json)?).as_bytes())?;
                files.push("tpa.json".into());
            }
            Err(why) => writeln!(out, "note: no texture profile (tpa.json): {why}")?,
        }
    }
    if let Some(csv) = stress_strain_csv(&bundle.experiment, &force) {
        write_atomic(dir.join(STRESS_STRAIN_FILE), csv.as_bytes())?;
        files.push(STRESS_STRAIN_FILE.into());
    }
    if !markers.is_empty() {
        files.push("markers.csv".into());
    }
    files.extend(["summary.json", "steps.csv", "keep.vtu", "final.vtu", "force.svg", "shape.svg"].map(String::from));
    files.extend(stroke_files);
    if !pvd_times.is_empty() {
        write_time_series(dir, &problem, &result, &pvd_times)?;
        files.extend(["shapes.pvd".to_string(), "shapes/".to_string()]);
    }
    if !result.tools.is_empty() {
        write_atomic(dir.join(TOOLS_FILE), tools_csv(&result.tools).as_bytes())?;
        write_atomic(dir.join(CONTACT_NODES_FILE), contact_nodes_json(&result)?.as_bytes())?;
        files.extend([TOOLS_FILE.to_string(), CONTACT_NODES_FILE.to_string()]);
        files.extend(tool_files);
        for track in &result.tools {
            let peak = track.samples.iter().map(|s| s.normal_n).fold(0.0, f64::max);
            let area = track.samples.iter().map(|s| s.area_mm2).fold(0.0, f64::max);
            writeln!(
                out,
                "tool {:<16} peak normal force {peak:.4} N, largest contact area {area:.4} mm^2",
                track.name
            )?;
        }
    }
    if let Some(target) = &gltf {
        let written = crate::export::write_press_gltf(target, dir, &name, &problem, &result.snapshots, keep_time_s)
            .with_context(|| format!("--gltf {}", target.path().display()))?;
        files.extend(written);
    }

    let summary = Summary {
        wagashi_version: env!("CARGO_PKG_VERSION"),
        name: bundle.experiment.name.clone(),
        input: bundle.dir.display().to_string(),
        output: options.output.display().to_string(),
        dimension: mesh.dimension,
        formulation: mesh.formulation,
        cells: mesh.num_cells,
        nodes: mesh.num_nodes,
        free_dofs: result.num_free_dofs,
        integrator: options.integrator.as_str(),
        rtol: options.rtol,
        dt_s: options.dt_s,
        size_mm,
        surface_mesh_mode,
        steps: result.steps.len(),
        factorizations: result.num_factorizations,
        factor_nonzeros: result.factor_nonzeros,
        wall_time_s,
        total_time_s: 0.0,
        peak_force_n: result.peak_force(),
        force_end_of_hold_n: result.bottom_force_at(keep_time_s),
        keep_height_loss_mm: mesh.height_loss_mm(keep),
        final_height_loss_mm: mesh.height_loss_mm(last),
        keep_time_s,
        final_time_s: end_s,
        strokes: stroke_shapes,
        force_samples: force.samples.len(),
        markers: markers.len(),
        measured_force_samples: measured.map(|m| m.samples.len()),
        force_rms_diff_n: comparison.map(|c| c.rms_n),
        force_max_abs_diff_n: comparison.map(|c| c.max_abs_n),
        files,
    };
    // summary.json marks the folder as a wagashi output: it goes in last.
    let summary = Summary { total_time_s: clock.elapsed().as_secs_f64(), ..summary };
    write_atomic(dir.join("summary.json"), summary.to_json()?.as_bytes())?;
    output.commit()?;
    Ok(summary)
}

/// Prints the results of a run (the same for `press` and `demo`).
pub fn print_results(s: &Summary, out: &mut dyn Write) -> anyhow::Result<()> {
    writeln!(
        out,
        "simulated {} s in {} steps ({} factorizations, {} free dofs) in {:.2} s",
        s.final_time_s, s.steps, s.factorizations, s.free_dofs, s.wall_time_s
    )?;
    writeln!(out, "peak force            {:.4} N", s.peak_force_n)?;
    if s.strokes.is_empty() {
        writeln!(out, "force at end of hold  {:.4} N (t = {} s)", s.force_end_of_hold_n, s.keep_time_s)?;
    }
    for (i, k) in s.strokes.iter().enumerate() {
        writeln!(
            out,
            "stroke {}              peak {:.4} N, height loss {:.4} mm (t = {} s); after it {:.4} mm (t = {} s)",
            i + 1,
            k.peak_force_n,
            k.peak_height_loss_mm,
            number(k.peak_t_s),
            k.after_height_loss_mm,
            number(k.after_t_s)
        )?;
    }
    writeln!(out, "final height loss     {:.4} mm (t = {} s)", s.final_height_loss_mm, s.final_time_s)?;
    if let (Some(rms), Some(max)) = (s.force_rms_diff_n, s.force_max_abs_diff_n) {
        writeln!(out, "simulated - measured  rms {rms:.4} N, max {max:.4} N")?;
    }
    writeln!(out, "output                {}", s.output)?;
    Ok(())
}

/// Checks `target` and starts building it. Refused: a target that is one of
/// the `inputs` (`(what, path)`: bundles, materials files), lies inside one or
/// holds one; an existing previous output unless `replace`; and (by
/// [`AtomicDir`]) any other existing, non-empty folder or file, and a previous
/// output holding a file its manifest does not list. Says on stderr which
/// temporary folders of interrupted runs it removed.
pub(crate) fn prepare_output(inputs: &[(&str, &Path)], target: &Path, replace: bool) -> anyhow::Result<AtomicDir> {
    crate::outputs::refuse_input_overlap("the output folder", target, inputs)?;
    if wagashi_io::atomic::is_previous_output(target) && !replace {
        bail!("{}: exists (a previous wagashi output); pass --force to replace it", target.display());
    }
    let dir = AtomicDir::new(target)?;
    report_stale(&dir);
    Ok(dir)
}

/// Tells on stderr which temporary folders of interrupted runs `dir` removed.
pub(crate) fn report_stale(dir: &AtomicDir) {
    for stale in dir.stale_removed() {
        eprintln!("note: removed {}, left by an interrupted run", stale.display());
    }
}

/// `path` made absolute with symbolic links resolved as far as it exists.
pub(crate) fn resolve(path: &Path) -> anyhow::Result<PathBuf> {
    let absolute = std::path::absolute(path).with_context(|| format!("{}: cannot resolve", path.display()))?;
    let mut existing = absolute.as_path();
    let mut rest = Vec::new();
    while !existing.exists() {
        match (existing.parent(), existing.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                existing = parent;
            }
            _ => break,
        }
    }
    let mut resolved = existing.canonicalize().unwrap_or_else(|_| existing.to_path_buf());
    resolved.extend(rest.iter().rev());
    Ok(resolved)
}

/// The samples of `measured` up to `end_s` (within 1e-12 relative), and how
/// many are left out after it.
fn measured_until(measured: &ForceSeries, end_s: f64) -> (ForceSeries, usize) {
    let until = end_s + 1e-12 * end_s.abs();
    let kept: Vec<ForceSample> = measured.samples.iter().filter(|s| s.t_s <= until).copied().collect();
    let left_out = measured.samples.len() - kept.len();
    (ForceSeries { samples: kept }, left_out)
}

/// `0, dt, 2 dt, ...` up to `end_s`, and `end_s` itself when it is not on the grid.
/// The strokes of a protocol of several (`waypoints`, `[t_s, d_mm]`): each
/// push's end (the plate deepest) and the end of the retreat that follows it
/// (the plate highest again, or `end_s`).
fn stroke_times(waypoints: &[[f64; 2]], end_s: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut i = 1;
    while i < waypoints.len() {
        // The end of a push: rising into it, not rising after it.
        let rising_in = waypoints[i][1] > waypoints[i - 1][1];
        let rising_out = waypoints.get(i + 1).is_some_and(|w| w[1] > waypoints[i][1]);
        if rising_in && !rising_out {
            let peak = waypoints[i][0].min(end_s);
            let mut j = i;
            while j + 1 < waypoints.len() && waypoints[j + 1][1] <= waypoints[j][1] {
                j += 1;
            }
            let after = if j + 1 < waypoints.len() { waypoints[j][0] } else { end_s };
            out.push((peak, after.min(end_s)));
            i = j;
        }
        i += 1;
    }
    out
}

/// The nominal stress-strain curve's file ([`stress_strain_csv`]).
pub const STRESS_STRAIN_FILE: &str = "stress_strain.csv";

/// `stress_strain.csv`: the nominal strain (the plate's travel from first touch
/// over the initial height) and the nominal stress (the force of `force.csv`
/// over the initial cross-section: `W T` of a block, `pi R^2` of a cylinder)
/// at each force sample until `release_s`, compression positive; `None` when
/// the specimen has no defined height and area (a surface or a mesh) or the
/// tool is not the plate.
fn stress_strain_csv(experiment: &wagashi_io::Experiment, force: &ForceSeries) -> Option<String> {
    use wagashi_io::bundle::{Shape, Tool};
    let protocol = &experiment.protocol;
    if protocol.tool != Tool::Plate {
        return None;
    }
    let specimen = &experiment.specimen;
    let (height_mm, area_mm2) = match specimen.shape {
        Shape::Block => {
            let size = specimen.size_mm.as_deref()?;
            (size[1], size[0] * size[2])
        }
        Shape::Cylinder => {
            let r = specimen.radius_mm?;
            (specimen.height_mm?, std::f64::consts::PI * r * r)
        }
        _ => return None,
    };
    let travel = |t: f64| {
        let w = &protocol.waypoints;
        match w.iter().position(|p| p[0] >= t) {
            None => w.last().map_or(0.0, |p| p[1]),
            Some(0) => w[0][1],
            Some(i) => {
                let (a, b) = (w[i - 1], w[i]);
                a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0])
            }
        }
    };
    let mut csv = String::from("t_s,strain,stress_kPa\n");
    for s in force.samples.iter().filter(|s| s.t_s <= protocol.release_s) {
        let strain = travel(s.t_s) / height_mm;
        let stress_kpa = 1e3 * s.force_n / area_mm2;
        let _ = writeln!(csv, "{},{},{}", number(s.t_s), number(strain), number(stress_kpa));
    }
    Some(csv)
}

fn uniform_times(end_s: f64, dt_s: f64) -> anyhow::Result<Vec<f64>> {
    let n = (end_s / dt_s + 1e-9).floor();
    if n > MAX_OUTPUT_SAMPLES {
        bail!("--output-dt {dt_s} s gives {n:.0} force samples over {end_s} s; at most {MAX_OUTPUT_SAMPLES:.0} are written");
    }
    let n = n as usize;
    let mut times: Vec<f64> = (0..=n).map(|i| (i as f64 * dt_s).min(end_s)).collect();
    if end_s - times[n] > 1e-9 * end_s {
        times.push(end_s);
    } else {
        times[n] = end_s;
    }
    Ok(times)
}

/// The contact forces of each tool at every step.
pub const TOOLS_FILE: &str = "tools.csv";
/// The nodes in contact with each tool at the kept times.
pub const CONTACT_NODES_FILE: &str = "contact_nodes.json";
/// The header of `tools.csv`.
pub const TOOLS_HEADER: &str = "t_s,tool,force_x_N,force_y_N,force_z_N,normal_N,tangential_N,area_mm2";
/// The folder of the copied specimen surface in an output.
const SPECIMEN_SURFACE_DIR: &str = "specimen";

/// The folder of the copied tool surfaces in an output.
const TOOL_SURFACES_DIR: &str = "tools";

/// The contact tools of a problem (empty for the seed's press).
pub(crate) fn problem_tools(problem: &AnyPress) -> &[Tool] {
    match problem {
        AnyPress::Plane(p) => &p.tools,
        AnyPress::Solid(p) => &p.tools,
        AnyPress::Axisymmetric(p) => &p.tools,
    }
}

/// `tools.csv`: one row per tool and sample, in time order (tools in the
/// problem's order at equal times).
fn tools_csv(tracks: &[ToolTrack]) -> String {
    let mut rows: Vec<(f64, usize, &ToolSample)> =
        tracks.iter().enumerate().flat_map(|(i, t)| t.samples.iter().map(move |s| (s.t_s, i, s))).collect();
    rows.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut out = String::with_capacity(96 * (rows.len() + 1));
    out.push_str(TOOLS_HEADER);
    out.push('\n');
    for (t, i, s) in rows {
        let [fx, fy, fz] = s.force_n.map(number);
        let _ = writeln!(
            out,
            "{},{},{fx},{fy},{fz},{},{},{}",
            number(t),
            tracks[i].name,
            number(s.normal_n),
            number(s.tangential_n),
            number(s.area_mm2)
        );
    }
    out
}

/// `contact_nodes.json`: per tool, the nodes in contact at each kept time.
fn contact_nodes_json(result: &PressResult) -> anyhow::Result<String> {
    let end = result.snapshots.iter().map(|s| s.t_s).fold(1.0, f64::max);
    let tools: Vec<serde_json::Value> = result
        .tools
        .iter()
        .map(|track| {
            let snapshots: Vec<serde_json::Value> = result
                .snapshots
                .iter()
                .filter_map(|snap| {
                    let s = track.samples.iter().find(|s| (s.t_s - snap.t_s).abs() <= 1e-9 * end)?;
                    Some(serde_json::json!({
                        "t_s": snap.t_s,
                        "normal_N": s.normal_n,
                        "area_mm2": s.area_mm2,
                        "nodes": s.nodes,
                    }))
                })
                .collect();
            serde_json::json!({ "name": track.name, "snapshots": snapshots })
        })
        .collect();
    Ok(serde_json::to_string_pretty(&serde_json::json!({ "tools": tools }))? + "\n")
}

/// Copies the specimen's surface or mesh file (`shape = "surface"` or `"mesh"`)
/// into `dir/specimen/FILE` and the surface file of each surface tool into `dir/tools/NAME.EXT` (NAME:
/// the tool's, unique) and points `experiment` at the copies, so that the output
/// reads back as a bundle (`press OUT`, `export OUT`). Returns the files written,
/// relative to `dir`.
fn copy_tool_surfaces(
    bundle: &Bundle,
    experiment: &mut wagashi_io::Experiment,
    dir: &Path,
) -> anyhow::Result<Vec<String>> {
    let mut written = Vec::new();
    // The specimen's own surface or mesh, likewise (`specimen/NAME.EXT`; a TetGen
    // mesh with its `.node`, `.ele` and, when there is one, `.face` file).
    let specimen = &mut experiment.specimen;
    if let Some(file) = specimen.surface.as_mut().or(specimen.mesh.as_mut()) {
        let name = Path::new(file.as_str()).file_name().map_or_else(|| "surface.obj".into(), |n| n.to_string_lossy());
        let relative = format!("{SPECIMEN_SURFACE_DIR}/{name}");
        let tetgen = matches!(Path::new(&relative).extension().and_then(|e| e.to_str()), Some("node" | "ele"));
        let copies: Vec<(String, String, bool)> = if tetgen {
            let stem = |f: &str| Path::new(f).with_extension("").to_string_lossy().into_owned();
            let (from, to) = (stem(file), stem(&relative));
            ["node", "ele", "face"].map(|ext| (format!("{from}.{ext}"), format!("{to}.{ext}"), ext != "face")).into()
        } else {
            vec![(file.clone(), relative.clone(), true)]
        };
        std::fs::create_dir_all(dir.join(SPECIMEN_SURFACE_DIR))
            .with_context(|| format!("{}: cannot create", dir.join(SPECIMEN_SURFACE_DIR).display()))?;
        for (from, to, required) in copies {
            let from = bundle.dir.join(from);
            if !required && !from.is_file() {
                continue;
            }
            written.extend(copy_input_file(&from, dir, &to)?);
        }
        *file = relative;
    }
    let mut copy = |tool: &str, file: &mut String| -> anyhow::Result<()> {
        let from = bundle.dir.join(file.as_str());
        let ext = Path::new(file.as_str()).extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
        let relative = format!("{TOOL_SURFACES_DIR}/{tool}{ext}");
        std::fs::create_dir_all(dir.join(TOOL_SURFACES_DIR))
            .with_context(|| format!("{}: cannot create", dir.join(TOOL_SURFACES_DIR).display()))?;
        written.extend(copy_input_file(&from, dir, &relative)?);
        *file = relative;
        Ok(())
    };
    let p = &mut experiment.protocol;
    if p.tool == wagashi_io::bundle::Tool::Surface {
        if let Some(file) = p.tool_surface.as_mut() {
            copy(p.tool.as_str(), file)?;
        }
    }
    for t in &mut p.tools {
        if let Some(file) = t.surface.as_mut() {
            copy(&t.name, file)?;
        }
    }
    Ok(written)
}

/// Copies the input file `from` to `dir/relative` and returns the names written
/// (relative to `dir`): the file, and for a glTF or GLB file the buffers and
/// images it names by relative URIs, beside the copy as `STEM.bufferI.EXT` and
/// `STEM.imageI.EXT` with the copy's URIs renamed to match, so that the copy
/// reads back ([`wagashi_io::surface::portable_gltf`]).
fn copy_input_file(from: &Path, dir: &Path, relative: &str) -> anyhow::Result<Vec<String>> {
    let to = Path::new(relative);
    let stem = to.file_stem().map_or_else(|| "copy".into(), |s| s.to_string_lossy().into_owned());
    let copy = wagashi_io::surface::portable_gltf(from, &stem)?;
    write_atomic(dir.join(to), &copy.bytes)?;
    let mut written = vec![relative.to_string()];
    let folder = to.parent().unwrap_or(Path::new(""));
    for (name, bytes) in &copy.companions {
        let companion = folder.join(name);
        write_atomic(dir.join(&companion), bytes)?;
        written.push(companion.to_string_lossy().into_owned());
    }
    Ok(written)
}

fn set_snapshot_times(problem: &mut AnyPress, times: &[f64]) {
    let t: Vec<f64> = times.iter().copied().filter(|&t| t > 0.0).collect();
    match problem {
        AnyPress::Plane(p) => p.snapshot_times = t,
        AnyPress::Solid(p) => p.snapshot_times = t,
        AnyPress::Axisymmetric(p) => p.snapshot_times = t,
    }
}

fn snapshot(result: &PressResult, t_s: f64) -> anyhow::Result<&Snapshot> {
    result.snapshot_at(t_s).with_context(|| format!("the engine kept no shape at t = {t_s} s"))
}

fn write_shape(path: &Path, problem: &AnyPress, snapshot: &Snapshot) -> Result<(), WriteError> {
    let fields = VtuFields::from_snapshot(snapshot);
    match problem {
        AnyPress::Plane(p) => write_vtu(path, &p.mesh, &fields),
        AnyPress::Solid(p) => write_vtu(path, &p.mesh, &fields),
        AnyPress::Axisymmetric(p) => write_vtu(path, &p.mesh, &fields),
    }
}

/// `shapes/shape-NNNN.vtu` at `times` and `shapes.pvd`. The shape at t = 0 is the
/// engine's initial state: zero displacement and stress.
fn write_time_series(dir: &Path, problem: &AnyPress, result: &PressResult, times: &[f64]) -> anyhow::Result<()> {
    let shapes = dir.join("shapes");
    std::fs::create_dir(&shapes).with_context(|| format!("{}: cannot create", shapes.display()))?;
    let initial = |num_nodes: usize, num_cells: usize| Snapshot {
        t_s: 0.0,
        displacement: vec![0.0; result.dim * num_nodes],
        cell_stress: vec![0.0; result.num_stress * num_cells],
    };
    let mut entries = Vec::with_capacity(times.len());
    for (i, &t) in times.iter().enumerate() {
        let name = format!("shape-{i:04}.vtu");
        let zero;
        let snap = if t > 0.0 {
            snapshot(result, t)?
        } else {
            let (nodes, cells) = match problem {
                AnyPress::Plane(p) => (p.mesh.num_nodes(), p.mesh.num_cells()),
                AnyPress::Solid(p) => (p.mesh.num_nodes(), p.mesh.num_cells()),
                AnyPress::Axisymmetric(p) => (p.mesh.num_nodes(), p.mesh.num_cells()),
            };
            zero = initial(nodes, cells);
            &zero
        };
        write_shape(&shapes.join(&name), problem, snap)?;
        entries.push((t, PathBuf::from("shapes").join(name)));
    }
    write_pvd(dir.join("shapes.pvd"), &entries)?;
    Ok(())
}

/// What the output reports about the mesh.
struct MeshInfo {
    dimension: usize,
    /// `solid`, `plane-stress`, `plane-strain` or `axisymmetric`.
    formulation: &'static str,
    num_cells: usize,
    num_nodes: usize,
    cell_kind: &'static str,
    /// The node set `top` (the face under the plate).
    top: Vec<u32>,
    /// The weight of each `top` node in the mean: 1, or for an axisymmetric
    /// section the node's share of the top disk's area (a node at radius r stands
    /// for a ring).
    top_weights: Vec<f64>,
}

impl MeshInfo {
    fn of(problem: &AnyPress) -> anyhow::Result<Self> {
        let (dimension, num_cells, num_nodes, cell_kind, top) = match problem {
            AnyPress::Plane(p) => (2, p.mesh.num_cells(), p.mesh.num_nodes(), "triangles", p.mesh.node_set("top")),
            AnyPress::Solid(p) => (3, p.mesh.num_cells(), p.mesh.num_nodes(), "tetrahedra", p.mesh.node_set("top")),
            AnyPress::Axisymmetric(p) => {
                (2, p.mesh.num_cells(), p.mesh.num_nodes(), "axisymmetric triangles", p.mesh.node_set("top"))
            }
        };
        let top = top.context("the mesh")?.to_vec();
        let formulation = match problem {
            AnyPress::Plane(p) => match p.formulation {
                Formulation::PlaneStrain { .. } => "plane-strain",
                _ => "plane-stress",
            },
            AnyPress::Solid(_) => "solid",
            AnyPress::Axisymmetric(_) => "axisymmetric",
        };
        let top_weights = match problem {
            AnyPress::Axisymmetric(p) => match p.mesh.face_sets.get("top") {
                Some(edges) => ring_weights(&p.mesh.nodes, &top, edges),
                None => vec![1.0; top.len()],
            },
            _ => vec![1.0; top.len()],
        };
        Ok(Self { dimension, formulation, num_cells, num_nodes, cell_kind, top, top_weights })
    }

    /// Minus the mean y displacement of the top face [mm] in `snapshot`.
    fn height_loss_mm(&self, snapshot: &Snapshot) -> f64 {
        let d = self.dimension;
        let sum: f64 =
            self.top.iter().zip(&self.top_weights).map(|(&n, w)| w * snapshot.displacement[d * n as usize + 1]).sum();
        -sum / self.top_weights.iter().sum::<f64>().max(f64::MIN_POSITIVE)
    }
}

/// The share of the disk swept by the `edges` of an axisymmetric section that
/// each node of `set` stands for: `int N_a 2π r dr` over its edges [mm^2].
fn ring_weights(nodes: &[[f64; 2]], set: &[u32], edges: &[[u32; 2]]) -> Vec<f64> {
    let mut w = vec![0.0; set.len()];
    for &[a, b] in edges {
        let (ra, rb) = (nodes[a as usize][0], nodes[b as usize][0]);
        let length = (rb - ra).abs();
        for (n, own, other) in [(a, ra, rb), (b, rb, ra)] {
            if let Ok(i) = set.binary_search(&n) {
                w[i] += std::f64::consts::TAU * length * (2.0 * own + other) / 6.0;
            }
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strokes_are_the_pushes_ends_and_the_retreats_ends() {
        let w = [[0.0, 0.0], [10.0, 2.0], [20.0, 0.0], [25.0, 0.0], [35.0, 2.0], [36.0, 2.0], [45.0, 0.0]];
        assert_eq!(stroke_times(&w, 50.0), vec![(10.0, 25.0), (35.0, 50.0)]);
        let w = [[0.0, 0.0], [10.0, 2.0], [20.0, 0.5], [30.0, 2.5], [40.0, 0.0]];
        assert_eq!(stroke_times(&w, 40.0), vec![(10.0, 20.0), (30.0, 40.0)]);
    }

    #[test]
    fn uniform_times_cover_zero_to_end() {
        let t = uniform_times(400.0, 0.1).unwrap();
        assert_eq!(t.len(), 4001);
        assert_eq!((t[0], t[4000]), (0.0, 400.0));
        let t = uniform_times(1.05, 0.5).unwrap();
        assert_eq!(t, vec![0.0, 0.5, 1.0, 1.05]);
        assert!(uniform_times(400.0, 1e-9).is_err());
    }

    #[test]
    fn positive_numbers_only() {
        assert_eq!(positive_number("2.5"), Ok(2.5));
        for bad in ["0", "-1", "nan", "inf", "x"] {
            assert!(positive_number(bad).is_err(), "{bad}");
        }
    }

    /// The top disk of radius 2 split at r = 0.5 and 2: the weights sum to its area
    /// and each node's is its ring's share.
    #[test]
    fn ring_weights_sum_to_the_disk() {
        let nodes = [[0.0, 1.0], [0.5, 1.0], [2.0, 1.0]];
        let w = ring_weights(&nodes, &[0, 1, 2], &[[1, 0], [2, 1]]);
        let pi = std::f64::consts::PI;
        assert!((w.iter().sum::<f64>() - 4.0 * pi).abs() < 1e-12);
        assert!((w[0] - pi * 0.5 * 0.5 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn resolve_keeps_missing_components() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a/b");
        assert_eq!(resolve(&p).unwrap(), dir.path().canonicalize().unwrap().join("a/b"));
    }
}
