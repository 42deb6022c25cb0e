//! `wagashi export OUT_DIR --gltf FILE.glb`, and the glTF half of
//! `wagashi press ... --gltf FILE.glb`: the run as an animated glTF 2.0 binary
//! (`wagashi_io::gltf`: the specimen's surface deforming, the tools moving, in
//! metres, coloured by displacement magnitude, with the keep and final frames named).
//!
//! Both commands build the scene here, from the same pieces, so that exporting a
//! press output again gives the same file:
//!
//! - **The surface**: the boundary of the tetrahedra; a plane mesh extruded to the
//!   specimen's thickness; an axisymmetric section revolved in 48 segments.
//! - **The frames**: t = 0 (undeformed) and every shape the engine kept, named
//!   `keep` at the release and `final` at the end. `press --gltf` keeps the
//!   `--pvd N` times when given, else [`DEFAULT_FRAMES`] evenly spaced intervals.
//! - **The tools**: [`tools_for`]: a run with rigid contact tools draws each of
//!   them, its real shape ([`Tool::surface_mesh`]; a flat plate or floor, whose
//!   box reaches far past the specimen, as the slab of its pressing face) moving
//!   on its trajectory ([`Tool::pose_at`] at every frame time and keyframe,
//!   quaternions); a plane run's tools (which act in z = 0) are drawn
//!   across the middle of the slab, z = T/2. A run of the seed's press draws its
//!   plate following the protocol ([`AnimatedTool::plate`]). `export` rebuilds the
//!   tools from the output's `experiment.toml` (surface tools from the copies
//!   `press` wrote into the output).
//!
//! `press --gltf` also writes `frames.bin` into its output folder
//! ([`wagashi_io::gltf::FrameSeries`]: the displacement of the surface's nodes at
//! each frame, f64), which `export` reads. An output without it (a run without
//! `--gltf`, or `wagashi demo`'s) is exported from its shapes: `shapes.pvd` (with
//! `--pvd N`) plus `keep.vtu` and `final.vtu`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::Args;
use fem_core::mesh::{TetMesh, TriMesh};
use fem_core::press::{AnyPress, Protocol, Tool};
use serde_json::json;
use wagashi_io::gltf::{
    glb_bytes, read_pvd, AnimatedTool, FrameSeries, GltfScene, SpecimenSurface, ToolKey, VtuShape, DEFAULT_SEGMENTS,
    MAX_FRAMES,
};
use wagashi_io::{read_bundle, write_atomic};

/// Frames (intervals from 0 to `end_s`) of `press --gltf` without `--pvd`.
pub const DEFAULT_FRAMES: u32 = 60;

/// The file `press --gltf` adds to its output folder for `export`.
pub const FRAMES_FILE: &str = "frames.bin";

const EXPORT_AFTER_HELP: &str = "\
Examples:
  # Simulate and write the animation at once (60 frames over the trial):
  wagashi press examples/paper/mat1 -o out/mat1 --size-mm 6 --gltf out/mat1.glb

  # The same animation again, later, from the output folder (it holds frames.bin):
  wagashi export out/mat1 --gltf out/mat1-again.glb

  # Any press output, e.g. the demo's: frames from shapes.pvd (press --pvd N),
  # else the undeformed, keep and final shapes:
  wagashi demo
  wagashi export demo-out --gltf demo.glb

Open the .glb in a glTF viewer (three.js editor, Blender, Windows 3D Viewer): the
specimen deforms over the trial's real time; its colour is the displacement
magnitude (viridis, 0 to max_mm in the file's asset.extras.colour_scale).";

/// `wagashi export OUT_DIR --gltf FILE.glb`.
#[derive(Debug, Args)]
#[command(
    about = "Write a press output folder as an animated glTF 2.0 file (.glb)",
    long_about = "Write a press output folder (what `wagashi press -o OUT_DIR` wrote) as an animated \
glTF 2.0 binary: the specimen's surface deforming over time (morph targets), the plate or the contact tools moving, \
lengths in metres, vertex colours for the displacement magnitude, and the keep and final shapes \
named. Frames come from OUT_DIR/frames.bin (written by `press --gltf`), else from shapes.pvd and \
keep.vtu/final.vtu. The file is written atomically; OUT_DIR is only read.",
    after_help = EXPORT_AFTER_HELP
)]
pub struct ExportArgs {
    /// A press output folder: experiment.toml, summary.json, keep.vtu, final.vtu...
    #[arg(value_name = "OUT_DIR")]
    pub output_dir: PathBuf,

    /// The glTF binary to write; its name must end in .glb. An existing .glb is
    /// replaced; any other existing file is refused.
    #[arg(long = "gltf", value_name = "FILE.glb")]
    pub gltf: PathBuf,
}

/// `wagashi export`.
pub fn run(args: &ExportArgs, out: &mut dyn std::io::Write) -> anyhow::Result<()> {
    let dir = &args.output_dir;
    // The source first (what is wrong with it is the first thing to tell), then
    // the target, which may not lie inside it; both before anything is written.
    let run = PressOutput::read(dir)?;
    let target = GltfTarget::check(&args.gltf, &[("press output", dir.as_path())], None)?;
    let scene = run.scene()?;
    let bytes = glb_bytes(&scene).with_context(|| format!("{}: building the glTF", dir.display()))?;
    target.write(&bytes, None)?;
    writeln!(
        out,
        "{}: {} frames from {} ({} to {} s), {} triangles, tools: {}",
        args.gltf.display(),
        scene.specimen.frames.len(),
        run.frames_source,
        scene.specimen.frames.first().map_or(0.0, |f| f.t_s),
        scene.specimen.frames.last().map_or(0.0, |f| f.t_s),
        scene.specimen.triangles.len(),
        scene.tools.iter().map(|t| t.name.as_str()).collect::<Vec<_>>().join(", "),
    )?;
    Ok(())
}

/// The frame times `press --gltf` asks the engine for: the `--pvd` times when
/// given, else `DEFAULT_FRAMES` intervals from 0 to `end_s`.
pub fn frame_times(end_s: f64, pvd_times: &[f64]) -> Vec<f64> {
    if !pvd_times.is_empty() {
        return pvd_times.to_vec();
    }
    let n = DEFAULT_FRAMES;
    (0..=n).map(|i| if i == n { end_s } else { end_s * f64::from(i) / f64::from(n) }).collect()
}

/// Refuses, before a long run, `--pvd N` with more frames than a glTF file holds.
pub fn check_frame_count(pvd: Option<u32>) -> anyhow::Result<()> {
    // N + 1 shapes, and the release may add one.
    if let Some(n) = pvd.filter(|&n| n as usize + 2 > MAX_FRAMES) {
        bail!("--gltf holds at most {MAX_FRAMES} frames; --pvd {n} asks for {} (use --pvd {} or fewer)", n + 2, {
            MAX_FRAMES - 2
        });
    }
    Ok(())
}

/// The rigid tools drawn with the specimen. Without contact tools (`tools`
/// empty): the seed's plate following `protocol`. With them: each tool's
/// surface ([`Tool::surface_mesh`], in its frame, mm; a flat plate or floor as
/// its pressing slab, see [`plate_slab`]) with a key at each of
/// `times` and at each of its keyframes inside `[0, end_s]`, placed by
/// [`Tool::pose_at`] (the rotation vector as a unit quaternion) and shifted by
/// `offset_mm` (a plane run's `[0, 0, T/2]`). A tool named like the specimen
/// (`specimen_name`) is drawn as `NAME (tool)`, so that node names stay unique.
pub fn tools_for(
    tools: &[Tool],
    protocol: &Protocol,
    surface: &SpecimenSurface,
    times: &[f64],
    offset_mm: [f64; 3],
    specimen_name: &str,
) -> Vec<AnimatedTool> {
    if tools.is_empty() {
        return vec![AnimatedTool::plate(protocol, surface.bounds_mm())];
    }
    let end = protocol.end_s;
    tools
        .iter()
        .filter_map(|tool| {
            let (vertices_mm, triangles) = match plate_slab(tool, surface.bounds_mm(), offset_mm) {
                Some(slab) => (slab.vertices_mm, slab.triangles),
                None => tool.surface_mesh(),
            };
            if triangles.is_empty() {
                return None;
            }
            let mut t: Vec<f64> = times.to_vec();
            t.extend(tool.keyframes.iter().map(|k| k.t_s).filter(|&k| (0.0..=end).contains(&k)));
            t.sort_by(f64::total_cmp);
            let mut keys: Vec<ToolKey> = Vec::with_capacity(t.len());
            for time in t {
                // glTF stores times as f32: keep them strictly increasing there.
                if keys.last().is_some_and(|k| (time as f32) <= (k.t_s as f32)) || !time.is_finite() {
                    continue;
                }
                let (translation, rotation) = tool.pose_at(time);
                let mut q = quaternion_xyzw(rotation);
                // The same rotation as the previous key's hemisphere: interpolation
                // then takes the short way.
                if let Some(p) = keys.last() {
                    if (0..4).map(|k| p.rotation_xyzw[k] * q[k]).sum::<f64>() < 0.0 {
                        q = q.map(|x| -x);
                    }
                }
                keys.push(ToolKey {
                    t_s: time,
                    translation_mm: std::array::from_fn(|k| translation[k] + offset_mm[k]),
                    rotation_xyzw: q,
                });
            }
            let name = if tool.name == specimen_name { format!("{} (tool)", tool.name) } else { tool.name.clone() };
            Some(AnimatedTool { name, vertices_mm, triangles, keys })
        })
        .collect()
}

/// A flat plate tool that never turns (the plate and the floor of the bundles)
/// drawn as its pressing slab: the engine's box reaches far past the specimen
/// (it must, as the specimen bulges) and would hide it. The slab keeps the
/// pressing face where it is (the lower face of a plate above the specimen's
/// middle, the upper face of one below) and as much of the box as lies within
/// 15 % of the specimen's larger side around it, 6 % of that side thick, as
/// [`AnimatedTool::plate`] draws the seed's plate. `None`: draw the real shape.
fn plate_slab(tool: &Tool, bounds_mm: ([f64; 3], [f64; 3]), offset_mm: [f64; 3]) -> Option<AnimatedTool> {
    let fem_core::press::ToolShape::Plate { half_extents: h } = tool.shape else {
        return None;
    };
    if tool.keyframes.iter().any(|k| k.rotation_rad.iter().any(|&r| r != 0.0)) {
        return None;
    }
    let (lo, hi) = bounds_mm;
    let span = (hi[0] - lo[0]).max(hi[2] - lo[2]);
    let (overhang, thickness) = (0.15 * span, (0.06 * span).min(2.0 * h[1]));
    // The tool's centre at t = 0 as drawn; the slab in the tool's frame.
    let (c, _) = tool.pose_at(0.0);
    let c: [f64; 3] = std::array::from_fn(|k| c[k] + offset_mm[k]);
    let side = |k: usize| ((lo[k] - overhang - c[k]).max(-h[k]), (hi[k] + overhang - c[k]).min(h[k]));
    let ((x0, x1), (z0, z1)) = (side(0), side(2));
    if !(x0 < x1 && z0 < z1 && thickness > 0.0) {
        return None;
    }
    let above = c[1] > 0.5 * (lo[1] + hi[1]);
    let (y0, y1) = if above { (-h[1], -h[1] + thickness) } else { (h[1] - thickness, h[1]) };
    Some(AnimatedTool::cuboid(&tool.name, [x0, y0, z0], [x1, y1, z1], Vec::new()))
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

/// The name of the frame at `t_s`: `final` at `end_s`, `keep` at `keep_s` (when
/// that is before the end).
fn frame_name(t_s: f64, keep_s: f64, end_s: f64) -> Option<&'static str> {
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * end_s.abs().max(1.0);
    if same(t_s, end_s) {
        Some("final")
    } else if same(t_s, keep_s) {
        Some("keep")
    } else {
        None
    }
}

/// A specimen's mesh as the glTF surface sees it.
pub enum SpecimenMesh<'a> {
    /// Tetrahedra.
    Solid(&'a TetMesh),
    /// A plane mesh and its thickness [mm].
    Slab(&'a TriMesh, f64),
    /// An axisymmetric `r-y` section.
    Section(&'a TriMesh),
}

impl SpecimenMesh<'_> {
    /// The mesh of a press problem.
    pub fn of(problem: &AnyPress) -> SpecimenMesh<'_> {
        match problem {
            AnyPress::Solid(p) => SpecimenMesh::Solid(&p.mesh),
            AnyPress::Plane(p) => {
                let thickness = match p.formulation {
                    fem_core::element::Formulation::PlaneStress { thickness_mm }
                    | fem_core::element::Formulation::PlaneStrain { thickness_mm } => thickness_mm,
                    _ => 1.0,
                };
                SpecimenMesh::Slab(&p.mesh, thickness)
            }
            AnyPress::Axisymmetric(p) => SpecimenMesh::Section(&p.mesh),
        }
    }

    /// Its boundary surface.
    pub fn surface(&self) -> anyhow::Result<SpecimenSurface> {
        Ok(match *self {
            SpecimenMesh::Solid(m) => SpecimenSurface::from_tet_mesh(m)?,
            SpecimenMesh::Slab(m, t) => SpecimenSurface::extruded(m, t)?,
            SpecimenMesh::Section(m) => SpecimenSurface::revolved(m, DEFAULT_SEGMENTS)?,
        })
    }

    fn formulation(&self) -> &'static str {
        match self {
            SpecimenMesh::Solid(_) => "solid",
            SpecimenMesh::Slab(..) => "plane",
            SpecimenMesh::Section(_) => "axisymmetric",
        }
    }
}

/// The scene of a run named `name`: `frames` are `(t_s, nodal displacement)` in
/// time order (t = 0 included); `keep_s` and `end_s` name the keep and final
/// frames; `tools` are the run's contact tools (none: the seed's plate).
pub fn scene(
    name: &str,
    mesh: &SpecimenMesh<'_>,
    protocol: &Protocol,
    tools: &[Tool],
    frames: &[(f64, &[f64])],
    keep_s: f64,
) -> anyhow::Result<(GltfScene, FrameSeries)> {
    let surface = mesh.surface()?;
    let times: Vec<f64> = frames.iter().map(|f| f.0).collect();
    // Plane runs act in z = 0; their slab spans 0 <= z <= T.
    let offset_mm = match mesh {
        SpecimenMesh::Slab(_, thickness) => [0.0, 0.0, 0.5 * thickness],
        _ => [0.0; 3],
    };
    let end_s = protocol.end_s;
    let named: Vec<(f64, Option<&str>, &[f64])> =
        frames.iter().map(|&(t, u)| (t, frame_name(t, keep_s, end_s), u)).collect();
    let series = FrameSeries::from_nodal(surface.node_dim(), surface.num_nodes, surface.nodes_used(), named.clone())?;
    let frames = named.iter().map(|&(t, n, u)| surface.frame(t, n, u)).collect::<Result<Vec<_>, _>>()?;
    let scene = GltfScene {
        specimen: surface.animated(name, frames),
        tools: tools_for(tools, protocol, &surface, &times, offset_mm, name),
        extras: json!({
            "trial": name,
            "formulation": mesh.formulation(),
            "generator": concat!("wagashi ", env!("CARGO_PKG_VERSION")),
        }),
    };
    Ok((scene, series))
}

/// Where `--gltf` writes, checked before anything runs.
#[derive(Debug)]
pub struct GltfTarget {
    path: PathBuf,
    /// The path relative to the output folder of `press`, when it lies inside:
    /// the file then goes into the folder's atomic build.
    inside_output: Option<PathBuf>,
}

impl GltfTarget {
    /// Refuses a name without `.glb`, a folder, a link, an existing file that is
    /// not a glTF binary, and a path that is one of the `inputs` (`(what, path)`:
    /// bundles, materials files, the folder `export` reads) or lies inside one
    /// (inputs are never modified).
    pub fn check(path: &Path, inputs: &[(&str, &Path)], output: Option<&Path>) -> anyhow::Result<Self> {
        let shown = path.display();
        if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb")) {
            bail!("{shown}: --gltf writes a binary glTF file, whose name must end in .glb");
        }
        if path.is_dir() {
            bail!("{shown}: is a folder; --gltf needs a file name ending in .glb");
        }
        if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
            bail!("{shown}: is a symbolic link; refusing to write through it");
        }
        crate::outputs::refuse_input_overlap("--gltf", path, inputs)?;
        if path.exists() {
            let mut magic = [0u8; 4];
            let is_glb = std::fs::File::open(path)
                .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut magic))
                .is_ok_and(|()| &magic == b"glTF");
            if !is_glb {
                bail!("{shown}: exists and is not a glTF binary; refusing to overwrite it");
            }
        }
        let resolved = crate::press::resolve(path)?;
        crate::outputs::sweep_stale(path);
        let inside_output = match output {
            Some(out) => resolved.strip_prefix(crate::press::resolve(out)?).ok().map(Path::to_path_buf),
            None => None,
        };
        Ok(Self { path: path.to_path_buf(), inside_output })
    }

    /// The file, as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The path relative to the output folder, when it lies inside it.
    pub fn inside_output(&self) -> Option<&Path> {
        self.inside_output.as_deref()
    }

    /// Writes `bytes`, atomically: into `building` (the output folder being
    /// built) when the file lies inside the output, else at its path, creating
    /// its folder.
    pub fn write(&self, bytes: &[u8], building: Option<&Path>) -> anyhow::Result<()> {
        let path = match (&self.inside_output, building) {
            (Some(relative), Some(dir)) => dir.join(relative),
            _ => self.path.clone(),
        };
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).with_context(|| format!("{}: cannot create", parent.display()))?;
        }
        write_atomic(&path, bytes).with_context(|| format!("writing {}", self.path.display()))?;
        Ok(())
    }
}

/// What `export` reads from a press output folder.
struct PressOutput {
    dir: PathBuf,
    name: String,
    formulation: String,
    protocol: Protocol,
    /// The contact tools (none for the seed's press).
    tools: Vec<Tool>,
    /// The plane thickness [mm] (block `T`).
    thickness_mm: Option<f64>,
    keep_s: f64,
    mesh: VtuShape,
    /// `(t_s, nodal displacement)`, in time order, t = 0 first.
    frames: Vec<(f64, Vec<f64>)>,
    /// Where the frames came from, for the report.
    frames_source: &'static str,
}

impl PressOutput {
    fn read(dir: &Path) -> anyhow::Result<Self> {
        let summary_path = dir.join(wagashi_io::atomic::OUTPUT_MARKER_FILE);
        if !dir.is_dir() {
            bail!("{}: no such folder (export reads what `wagashi press -o OUT_DIR` wrote)", dir.display());
        }
        if !summary_path.is_file() {
            bail!("{}: not a wagashi press output (it has no summary.json)", dir.display());
        }
        let summary: serde_json::Value = serde_json::from_str(
            &wagashi_io::input::read_to_string(&summary_path)
                .with_context(|| format!("{}: cannot read", summary_path.display()))?,
        )
        .with_context(|| format!("{}: not JSON", summary_path.display()))?;
        let bundle = read_bundle(dir)?;
        let protocol = bundle.protocol()?;
        let end_s = protocol.end_s;
        let time = |key: &str, default: f64| summary[key].as_f64().filter(|t| t.is_finite()).unwrap_or(default);
        let keep_s = time("keep_time_s", protocol.release_s.min(end_s));
        let final_s = time("final_time_s", end_s);

        let keep_path = dir.join("keep.vtu");
        let mesh = VtuShape::read(&keep_path)?;
        let is_2d = mesh.tri_mesh().is_some();
        let formulation = match summary["formulation"].as_str() {
            Some(f) => f.to_string(),
            None if !is_2d => "solid".into(),
            None if bundle.experiment.specimen.shape == wagashi_io::bundle::Shape::Cylinder => "axisymmetric".into(),
            None => "plane-stress".into(),
        };
        let tools = bundle.contact_tools(formulation == "axisymmetric")?;
        let dim = match (formulation.as_str(), is_2d) {
            ("solid", false) => 3,
            ("plane-stress" | "plane-strain" | "axisymmetric", true) => 2,
            (f, _) => bail!(
                "{}: formulation `{f}` in {} does not fit its {} cells",
                keep_path.display(),
                summary_path.display(),
                if is_2d { "triangle" } else { "tetrahedron" }
            ),
        };
        let num_nodes = mesh.points_mm.len();
        let zero = (0.0, vec![0.0; dim * num_nodes]);

        let frames_path = dir.join(FRAMES_FILE);
        let (mut frames, frames_source) = if frames_path.is_file() {
            let series = FrameSeries::read(&frames_path)?;
            if series.num_nodes != num_nodes || series.dim != dim {
                bail!(
                    "{}: frames of {} nodes with {} components, but {} has {num_nodes} nodes in {dim}D",
                    frames_path.display(),
                    series.num_nodes,
                    series.dim,
                    keep_path.display()
                );
            }
            let frames = (0..series.frames.len()).map(|i| (series.frames[i].t_s, series.nodal(i))).collect();
            (frames, FRAMES_FILE)
        } else {
            let mut shapes: Vec<(f64, PathBuf)> = Vec::new();
            let pvd = dir.join("shapes.pvd");
            let source = if pvd.is_file() {
                shapes = read_pvd(&pvd)?;
                "shapes.pvd, keep.vtu and final.vtu"
            } else {
                "keep.vtu and final.vtu"
            };
            shapes.push((keep_s, keep_path.clone()));
            shapes.push((final_s, dir.join("final.vtu")));
            let mut frames = Vec::with_capacity(shapes.len());
            for (t, path) in shapes {
                let shape = if path == keep_path { mesh.clone() } else { VtuShape::read(&path)? };
                if shape.points_mm.len() != num_nodes {
                    bail!(
                        "{}: {} points, but {} has {num_nodes}",
                        path.display(),
                        shape.points_mm.len(),
                        keep_path.display()
                    );
                }
                frames.push((t, shape.nodal_displacement(dim)));
            }
            (frames, source)
        };
        if !frames.iter().any(|(t, _)| *t == 0.0) {
            frames.push(zero);
        }
        frames.sort_by(|a, b| a.0.total_cmp(&b.0));
        frames.dedup_by(|b, a| (a.0 - b.0).abs() <= 1e-9 * end_s.abs().max(1.0));

        Ok(Self {
            dir: dir.to_path_buf(),
            name: bundle.experiment.name.clone(),
            formulation,
            protocol,
            tools,
            thickness_mm: bundle.experiment.specimen.block_size().map(|b| b[2]),
            keep_s,
            mesh,
            frames,
            frames_source,
        })
    }

    fn scene(&self) -> anyhow::Result<GltfScene> {
        let (tri, tet) = (self.mesh.tri_mesh(), self.mesh.tet_mesh());
        let mesh = match (self.formulation.as_str(), &tri, &tet) {
            ("axisymmetric", Some(m), _) => SpecimenMesh::Section(m),
            (_, Some(m), _) => {
                let t = self.thickness_mm.with_context(|| {
                    format!("{}: a plane run needs the block's thickness, specimen.size_mm[2]", self.dir.display())
                })?;
                SpecimenMesh::Slab(m, t)
            }
            (_, None, Some(m)) => SpecimenMesh::Solid(m),
            _ => unreachable!("a VtuShape holds triangles or tetrahedra"),
        };
        let frames: Vec<(f64, &[f64])> = self.frames.iter().map(|(t, u)| (*t, u.as_slice())).collect();
        let (scene, _) = scene(&self.name, &mesh, &self.protocol, &self.tools, &frames, self.keep_s)
            .with_context(|| format!("{}", self.dir.display()))?;
        Ok(scene)
    }
}

/// What `press --gltf` writes: `frames.bin` into the output folder being built
/// (`building`) and the `.glb` (inside that folder too when it lies there).
/// `snapshots` are the engine's kept states; returns the files added to the
/// output folder, relative to it.
pub fn write_press_gltf(
    target: &GltfTarget,
    building: &Path,
    name: &str,
    problem: &AnyPress,
    snapshots: &[fem_core::press::Snapshot],
    keep_s: f64,
) -> anyhow::Result<Vec<String>> {
    let (protocol, tools) = match problem {
        AnyPress::Plane(p) => (&p.protocol, &p.tools),
        AnyPress::Solid(p) => (&p.protocol, &p.tools),
        AnyPress::Axisymmetric(p) => (&p.protocol, &p.tools),
    };
    let mesh = SpecimenMesh::of(problem);
    let num_values = snapshots.first().map_or(0, |s| s.displacement.len());
    let zero = vec![0.0; num_values];
    let mut frames: Vec<(f64, &[f64])> = snapshots.iter().map(|s| (s.t_s, s.displacement.as_slice())).collect();
    if !frames.iter().any(|(t, _)| *t == 0.0) {
        frames.push((0.0, &zero));
    }
    frames.sort_by(|a, b| a.0.total_cmp(&b.0));
    frames.dedup_by(|b, a| (a.0 - b.0).abs() <= 1e-9 * protocol.end_s.abs().max(1.0));
    let (scene, series) = scene(name, &mesh, protocol, tools, &frames, keep_s)?;
    let bytes = glb_bytes(&scene).context("building the glTF")?;
    series.write(building.join(FRAMES_FILE))?;
    target.write(&bytes, Some(building))?;
    let mut files = vec![FRAMES_FILE.to_string()];
    if let Some(relative) = target.inside_output() {
        files.push(relative.to_string_lossy().replace('\\', "/"));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_frames_cover_the_trial() {
        let t = frame_times(400.0, &[]);
        assert_eq!(t.len(), DEFAULT_FRAMES as usize + 1);
        assert_eq!((t[0], t[60]), (0.0, 400.0));
        assert_eq!(frame_times(400.0, &[0.0, 200.0, 400.0]), vec![0.0, 200.0, 400.0]);
    }

    #[test]
    fn frames_are_named_keep_and_final() {
        assert_eq!(frame_name(400.0, 210.93, 400.0), Some("final"));
        assert_eq!(frame_name(210.93, 210.93, 400.0), Some("keep"));
        assert_eq!(frame_name(100.0, 210.93, 400.0), None);
        // Released at the end: the last frame is the final one.
        assert_eq!(frame_name(400.0, 400.0, 400.0), Some("final"));
    }

    #[test]
    fn rotation_vectors_become_unit_quaternions() {
        assert_eq!(quaternion_xyzw([0.0; 3]), ToolKey::NO_ROTATION);
        let q = quaternion_xyzw([std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((q[0] - h).abs() < 1e-15 && q[1] == 0.0 && q[2] == 0.0 && (q[3] - h).abs() < 1e-15, "{q:?}");
        let q = quaternion_xyzw([0.3, -1.2, 2.0]);
        assert!((q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-15);
    }

    /// Keys at the frame times and the keyframes; a turn past 180 degrees keeps
    /// the quaternions in one hemisphere (the short way between keys).
    #[test]
    fn tools_are_drawn_on_their_trajectories() {
        use fem_core::press::{Keyframe, ToolContact, ToolShape};
        let mesh = fem_core::mesh::block([10.0, 5.0, 4.0], 2.5, "m").unwrap();
        let surface = SpecimenSurface::from_tet_mesh(&mesh).unwrap();
        let protocol = Protocol::ramp_hold_release(0.1, 10.0, 20.0, 30.0);
        let key = |t_s: f64, y: f64, turn: f64| Keyframe {
            t_s,
            translation_mm: [5.0, y, 2.0],
            rotation_rad: [0.0, turn, 0.0],
        };
        let tool = Tool {
            name: "m".into(),
            shape: ToolShape::Capsule { radius: 1.0, half_height: 2.0 },
            contact: ToolContact::Frictionless,
            keyframes: vec![key(0.0, 8.0, 0.0), key(7.0, 6.0, 3.0), key(25.0, 6.0, 3.5)],
            release_s: 20.0,
            floor: false,
        };
        let drawn =
            tools_for(std::slice::from_ref(&tool), &protocol, &surface, &[0.0, 10.0, 20.0, 30.0], [0.0; 3], "m");
        assert_eq!(drawn.len(), 1);
        assert_eq!(drawn[0].name, "m (tool)");
        assert_eq!(drawn[0].keys.iter().map(|k| k.t_s).collect::<Vec<_>>(), [0.0, 7.0, 10.0, 20.0, 25.0, 30.0]);
        for (k, t) in drawn[0].keys.iter().zip([0.0, 7.0, 10.0, 20.0, 25.0, 30.0]) {
            assert_eq!(k.translation_mm, tool.pose_at(t).0);
        }
        assert!(drawn[0]
            .keys
            .windows(2)
            .all(|w| (0..4).map(|i| w[0].rotation_xyzw[i] * w[1].rotation_xyzw[i]).sum::<f64>() > 0.0));
        // Without tools: the seed's plate.
        let plate = tools_for(&[], &protocol, &surface, &[0.0], [0.0; 3], "m");
        assert_eq!(plate, vec![AnimatedTool::plate(&protocol, surface.bounds_mm())]);
    }

    /// The bundles' plate and floor are drawn as the slab of their pressing face:
    /// the plate's underside on the top, the floor's top on the bottom.
    #[test]
    fn flat_plates_are_drawn_as_their_pressing_slab() {
        use fem_core::press::ToolContact;
        let (lo, hi) = ([0.0, 0.0, 0.0], [10.0, 5.0, 4.0]);
        let bounds = (lo, hi);
        let plate = Tool::plate_above("plate", lo, hi, &[[0.0, 0.0], [1.0, 1.0]], ToolContact::Glued, 1.0);
        let floor = Tool::floor_below("floor", lo, hi, ToolContact::Frictionless);
        for (tool, face) in [(&plate, 5.0), (&floor, 0.0)] {
            let slab = plate_slab(tool, bounds, [0.0; 3]).unwrap();
            let (c, _) = tool.pose_at(0.0);
            let y: Vec<f64> = slab.vertices_mm.iter().map(|p| p[1] + c[1]).collect();
            let (low, high) =
                (y.iter().copied().fold(f64::INFINITY, f64::min), y.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            let pressing = if tool.floor { high } else { low };
            assert!((pressing - face).abs() < 1e-12, "{}: {pressing}", tool.name);
            assert!((high - low - 0.6).abs() < 1e-12, "6 % of the 10 mm side");
            let x: Vec<f64> = slab.vertices_mm.iter().map(|p| p[0] + c[0]).collect();
            assert!((x.iter().copied().fold(f64::INFINITY, f64::min) + 1.5).abs() < 1e-12);
        }
    }

    #[test]
    fn too_many_pvd_frames_are_refused_up_front() {
        assert!(check_frame_count(Some(10)).is_ok());
        assert!(check_frame_count(None).is_ok());
        assert!(check_frame_count(Some(MAX_FRAMES as u32)).unwrap_err().to_string().contains("--pvd"));
    }
}
