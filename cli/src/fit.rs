//! `wagashi fit`: identify material parameters from measured trials.
//!
//! The identification itself is `wagashi-calibrate`'s; this module reads the
//! bundles, drives the progress bars and writes the output folder atomically:
//!
//! | file             | what                                                                  |
//! |------------------|-----------------------------------------------------------------------|
//! | `materials.toml` | the fitted `[materials.NAME]` tables, loadable with `--materials`; with the seed procedure the force set under the materials' names and the shape set as `NAME-shape` |
//! | `fit.json`       | per set (`sets.force`, `sets.shape`, or `sets.joint`), per material, per key: `{"value": v, "ci95": [low, high]}`; the steps with objective, iterations, correlations and warnings; simulations used |
//! | `fit.svg`        | measured against simulated force, per trial                          |
//! | `shapes.svg`     | marker positions: initial, keep and final, measured against simulated |
//! | `summary.json`   | a short summary (and the mark of a wagashi output folder for `--force`) |

use std::collections::BTreeMap;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use crate::press::positive_number;
use anyhow::{anyhow, bail};
use calibrate::procedure::{run as run_procedure, Estimate, FitReport, Procedure, ProcedureOptions};
use calibrate::trial::{set_parameter, Campaign, Channel};
use clap::{Args, ValueEnum};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::{json, Map, Value};
use wagashi_io::{read_bundle_with, read_materials_file, write_atomic, AtomicDir, Bundle, MaterialSpec};

const FIT_AFTER_HELP: &str = "\
Examples:
  # The seed's three steps on a measured trial (materials given by their model only):
  wagashi fit trials/mat1 -o out/fit-mat1

  # One parameter set for force and shapes together, from several trials at once:
  wagashi fit trials/mat1 trials/mat1+2 --procedure joint -o out/fit-joint

  # Start from (and free) the values of a materials file, 8 starts per step:
  wagashi fit trials/mat1 --materials start.toml --starts 8 -o out/fit

  # A cylinder imported from a texture analyser, by its axisymmetric section:
  wagashi import rheometer ../shared/data/real/fungi-steak/double-compression-slowest-inplane-1.txt \
      --cylinder-radius-mm 4 -o bundles/fungi
  wagashi fit bundles/fungi/double-compression-slowest-inplane-1 --axisymmetric -o out/fit-fungi";

/// `wagashi fit BUNDLE... -o OUT`.
#[derive(Debug, Args)]
#[command(
    about = "Identify material parameters from measured trials (the seed's three steps, or a joint fit)",
    long_about = "Identify material parameters from measured trials. Every material parameter a bundle does not \
give is an unknown; a --materials file gives starting values and frees those parameters. A material used by \
several trials is one set of unknowns. Writes materials.toml (loadable with --materials), fit.json (values with \
95 % intervals, correlations, warnings), fit.svg and shapes.svg into OUT, atomically.",
    after_help = FIT_AFTER_HELP
)]
pub struct FitArgs {
    /// Measured trials: bundle folders.
    #[arg(value_name = "BUNDLE", required = true)]
    pub bundles: Vec<PathBuf>,

    /// The output folder; refused if it exists and is not a previous wagashi output.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,

    /// seed: nu from the keep-shape, the rheology from the force, c3 from the final
    /// shape (two sets); joint: one set from everything.
    #[arg(long, value_enum, default_value_t = ProcedureArg::Seed)]
    pub procedure: ProcedureArg,

    /// A TOML file of [materials.NAME] tables. Each replaces the bundle's table of
    /// the same name (as in `press`); every parameter of such a material is fitted,
    /// the values given being start values (a table may give only its model).
    #[arg(long, value_name = "FILE")]
    pub materials: Option<PathBuf>,

    /// Starts per multi-parameter step (Latin hypercube in the log box, plus the start values).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub starts: u32,

    /// Target element size [mm]. Default: one cell through each specimen when every trial's solution is
    /// homogeneous (a block, or a cylinder with --axisymmetric, of one material between a frictionless plate and
    /// support, with no other tool, gravity or effect), which any mesh solves exactly; otherwise a quarter of
    /// each specimen's smallest dimension.
    #[arg(long = "size-mm", value_name = "H", value_parser = positive_number, allow_negative_numbers = true)]
    pub size_mm: Option<f64>,

    /// Model cylinders (shape = "cylinder") by their axisymmetric r-y section:
    /// the same full-circle force at a 2D cost (markers compared at r = sqrt(x^2 + z^2)).
    #[arg(long)]
    pub axisymmetric: bool,

    /// Marker noise [mm]: the standard deviation of a measured marker coordinate.
    #[arg(long = "marker-sigma-mm", value_name = "MM", default_value_t = 0.05, value_parser = positive_number, allow_negative_numbers = true)]
    pub marker_sigma_mm: f64,

    /// Replace OUT when it holds a previous wagashi output (a folder whose
    /// wagashi-manifest.json lists every file in it; only those files are removed).
    #[arg(long)]
    pub force: bool,

    /// Fit even when a trial's estimated memory (6 V / h^3 tetrahedra in 3D)
    /// exceeds the memory the machine has available.
    #[arg(long = "allow-large")]
    pub allow_large: bool,

    /// F-bar patches for network materials near incompressibility (as
    /// `press --fbar`); refused without a network material.
    #[arg(long)]
    pub fbar: bool,
}

/// `--procedure`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ProcedureArg {
    /// The seed's three steps, two parameter sets.
    Seed,
    /// One set fitted to force and shapes together.
    Joint,
}

/// `wagashi fit`.
pub fn run(args: &FitArgs) -> anyhow::Result<()> {
    let start: BTreeMap<String, MaterialSpec> = match &args.materials {
        Some(path) => read_materials_file(path)?,
        None => Default::default(),
    };
    let mut bundles = Vec::new();
    for dir in &args.bundles {
        // A --materials table replaces the bundle's of the same name (as in `press`).
        bundles.push(read_bundle_with(dir, &start)?);
    }
    for b in &bundles {
        if b.force.is_none() && b.markers.is_empty() {
            bail!("{}: has no measured data ([data] force or markers): nothing to fit", b.experiment_file().display());
        }
    }
    let mut inputs: Vec<(&str, &std::path::Path)> = bundles.iter().map(|b| ("bundle", b.dir.as_path())).collect();
    inputs.extend(args.materials.iter().map(|m| ("materials file", m.as_path())));
    let output = crate::press::prepare_output(&inputs, &args.output, args.force)?;
    // A campaign whose every trial is homogeneous is solved exactly on one cell
    // through each specimen (`Bundle::homogeneous_size_mm`).
    let homogeneous: Option<Vec<f64>> = bundles.iter().map(|b| b.homogeneous_size_mm(args.axisymmetric)).collect();
    let size_mm = args.size_mm.or_else(|| homogeneous.map(|sizes| sizes.into_iter().fold(0.0, f64::max)));
    // Each 3D trial's mesh must fit in memory (a homogeneous campaign's one cell always does).
    let trials: Vec<&Bundle> = bundles.iter().collect();
    crate::outputs::check_trials_memory(&trials, size_mm, args.size_mm.is_some(), args.axisymmetric, args.allow_large)?;
    let mut campaign = Campaign::new(&bundles, &start, size_mm, args.axisymmetric)?;
    campaign.marker_sigma_mm = args.marker_sigma_mm;
    if args.fbar {
        // Every trial runs on the Newton path: each names a network material.
        for b in &bundles {
            if !b.experiment.materials.values().any(|m| m.model == wagashi_io::Model::Network) {
                bail!(
                    "{}: --fbar: F-bar patches run with network materials only, and this trial has none",
                    b.experiment_file().display()
                );
            }
        }
        campaign.settings.volumetric = fem_core::press::Volumetric::FBar;
    }
    if campaign.unknowns.is_empty() {
        bail!("every material parameter is given: nothing to fit (give a material only its model, or free parameters with --materials)");
    }
    let mut err = std::io::stderr().lock();
    writeln!(
        err,
        "fitting {} unknowns ({}) to {} trial(s)",
        campaign.unknowns.len(),
        campaign.unknowns.iter().map(|u| u.label()).collect::<Vec<_>>().join(", "),
        campaign.trials.len()
    )?;
    if args.size_mm.is_none() && size_mm.is_some() {
        writeln!(
            err,
            "every trial is homogeneous (frictionless plate and support, one material): one cell per specimen"
        )?;
    }
    drop(err);

    let procedure = match args.procedure {
        ProcedureArg::Seed => Procedure::Seed,
        ProcedureArg::Joint => Procedure::Joint,
    };
    let options = ProcedureOptions { starts: args.starts as usize, ..ProcedureOptions::default() };
    let bars = StepBars::new();
    let report = run_procedure(&campaign, procedure, &options, &|step, done, total| bars.update(step, done, total))?;
    bars.finish();

    write_outputs(&campaign, &bundles, &report, output)?;
    print_report(&report, &args.output)?;
    Ok(())
}

/// One bar per step, on stderr (hidden when stderr is not a terminal).
struct StepBars {
    multi: MultiProgress,
    bars: Mutex<BTreeMap<String, ProgressBar>>,
}

impl StepBars {
    fn new() -> Self {
        let target =
            if std::io::stderr().is_terminal() { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
        Self { multi: MultiProgress::with_draw_target(target), bars: Mutex::new(BTreeMap::new()) }
    }

    fn update(&self, step: &str, done: usize, total: usize) {
        let mut bars = self.bars.lock().expect("bar lock");
        let bar = bars.entry(step.to_string()).or_insert_with(|| {
            let b = self.multi.add(ProgressBar::new(total as u64));
            let style =
                ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:24}] {pos}/{len} starts: {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> ");
            b.set_style(style);
            b.set_message(step.to_string());
            b.enable_steady_tick(Duration::from_millis(200));
            b
        });
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    }

    fn finish(&self) {
        for bar in self.bars.lock().expect("bar lock").values() {
            bar.finish_and_clear();
        }
    }
}

/// `sets.NAME.MATERIAL.KEY = {value, ci95}`.
fn set_json(estimates: &[Estimate]) -> Value {
    let mut by_material: BTreeMap<&str, Map<String, Value>> = BTreeMap::new();
    for e in estimates {
        let entry = json!({
            "value": e.value,
            "ci95": e.ci95.map(|c| json!([c[0], c[1]])).unwrap_or(Value::Null),
            "fitted_in": e.step,
        });
        by_material.entry(&e.material).or_default().insert(e.key.to_string(), entry);
    }
    Value::Object(by_material.into_iter().map(|(k, v)| (k.to_string(), Value::Object(v))).collect())
}

fn fit_json(campaign: &Campaign, report: &FitReport) -> Value {
    let sets: Map<String, Value> = report.sets.iter().map(|(name, est)| (name.clone(), set_json(est))).collect();
    let steps: Vec<Value> = report
        .steps
        .iter()
        .map(|s| {
            json!({
                "name": s.name,
                "parameters": s.parameters,
                "channels": s.channels.iter().map(|c| c.as_str()).collect::<Vec<_>>(),
                "values": s.values,
                "ci95": s.ci95,
                "correlation": s.correlation,
                "objective": s.objective,
                "rms_noise_units": s.rms,
                "iterations": s.iterations,
                "evaluations": s.evaluations,
                "starts": s.starts,
                "stop": s.stop,
                "warnings": s.warnings,
                "skipped": s.skipped,
                "profiles": s.profiles.iter().map(|p| json!({
                    "parameter": p.parameter,
                    "points": p.points.iter().map(|q| [q.0, q.1]).collect::<Vec<_>>(),
                    "ci95": p.ci95,
                    "flat": p.flat,
                })).collect::<Vec<_>>(),
                "wall_s": s.wall_s,
            })
        })
        .collect();
    let trials: Vec<Value> = campaign
        .trials
        .iter()
        .map(|t| {
            json!({
                "name": t.name,
                "force_samples": t.count(Channel::Force),
                "force_sigma_N": t.force_sigma_n,
                "keep_coordinates": t.count(Channel::Keep),
                "final_coordinates": t.count(Channel::Final),
            })
        })
        .collect();
    let last = report.steps.iter().rev().find(|s| s.skipped.is_none());
    json!({
        "procedure": match report.procedure { Procedure::Seed => "seed", Procedure::Joint => "joint" },
        "sets": sets,
        "objective": last.map(|s| s.objective),
        "iterations": report.steps.iter().map(|s| s.iterations).sum::<usize>(),
        "evaluations": report.steps.iter().map(|s| s.evaluations).sum::<usize>(),
        "simulations": report.simulations,
        "wall_s": report.wall_s,
        "marker_sigma_mm": campaign.marker_sigma_mm,
        "steps": steps,
        "trials": trials,
    })
}

/// `materials.toml`: the force (or joint) set under the materials' names, the
/// shape set as `NAME-shape`.
fn materials_toml(campaign: &Campaign, report: &FitReport) -> anyhow::Result<String> {
    let mut tables: BTreeMap<String, MaterialSpec> = BTreeMap::new();
    for (set, est) in &report.sets {
        for (name, spec) in &campaign.materials {
            let mut spec = spec.clone();
            for e in est.iter().filter(|e| &e.material == name) {
                set_parameter(&mut spec, e.key, e.value);
            }
            let key = if set == "shape" { format!("{name}-shape") } else { name.clone() };
            tables.insert(key, spec);
        }
    }
    let mut doc = String::from("# Fitted by `wagashi fit`; load with `--materials`.\n");
    for (name, spec) in tables {
        let mut t = toml::Table::new();
        t.insert(
            "materials".into(),
            toml::Value::Table(toml::Table::from_iter([(name, toml::Value::try_from(&spec)?)])),
        );
        doc.push_str(&toml::to_string(&t)?);
        doc.push('\n');
    }
    Ok(doc)
}

fn write_outputs(campaign: &Campaign, bundles: &[Bundle], report: &FitReport, output: AtomicDir) -> anyhow::Result<()> {
    let dir = output.path().to_path_buf();
    let json = fit_json(campaign, report);
    write_atomic(dir.join("fit.json"), serde_json::to_string_pretty(&json)?.as_bytes())?;
    write_atomic(dir.join("materials.toml"), materials_toml(campaign, report)?.as_bytes())?;
    // Plots: force from the force (or joint) set, shapes from the shape (or joint) set.
    let force_set = report.values("force").or_else(|| report.values("joint")).ok_or_else(|| anyhow!("no set"))?;
    let shape_set = report.values("shape").unwrap_or_else(|| force_set.clone());
    let force_runs = campaign.simulate_all(&force_set).map_err(|e| anyhow!("simulating the fitted trials: {e}"))?;
    let shape_runs = campaign.simulate_all(&shape_set).map_err(|e| anyhow!("simulating the fitted trials: {e}"))?;
    write_atomic(dir.join("fit.svg"), crate::plot::fit_svg(campaign, &force_runs)?.as_bytes())?;
    write_atomic(dir.join("shapes.svg"), crate::plot::shapes_svg(campaign, bundles, &shape_runs)?.as_bytes())?;
    let summary = json!({
        "command": "fit",
        "procedure": json["procedure"],
        "trials": bundles.iter().map(|b| b.dir.display().to_string()).collect::<Vec<_>>(),
        "simulations": report.simulations,
        "wall_s": report.wall_s,
    });
    write_atomic(dir.join(wagashi_io::atomic::OUTPUT_MARKER_FILE), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    output.commit()?;
    Ok(())
}

fn print_report(report: &FitReport, output: &std::path::Path) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    for s in &report.steps {
        match &s.skipped {
            Some(why) => writeln!(out, "step {}: skipped: {why}", s.name)?,
            None => writeln!(
                out,
                "step {}: rms {:.3} noise units, {} iterations, {} evaluations over {} start(s), {:.2} s ({})",
                s.name, s.rms, s.iterations, s.evaluations, s.starts, s.wall_s, s.stop
            )?,
        }
        for w in s.warnings.iter().filter(|_| s.skipped.is_none()) {
            writeln!(out, "  warning: {w}")?;
        }
    }
    for (name, est) in &report.sets {
        writeln!(out, "set {name}:")?;
        for e in est {
            match e.ci95 {
                Some([lo, hi]) => writeln!(out, "  {:<24} {:>12.5e}   95 % [{lo:.4e}, {hi:.4e}]", e.label, e.value)?,
                None => writeln!(out, "  {:<24} {:>12.5e}   (held)", e.label, e.value)?,
            }
        }
    }
    writeln!(out, "{} simulations, {:.1} s; results in {}", report.simulations, report.wall_s, output.display())?;
    Ok(())
}
