//! `wagashi fit`: identify material parameters from measured trials.
//!
//! The identification itself is `wagashi-calibrate`'s; this module reads the
//! bundles, drives the progress bars and writes the output folder atomically:
//!
//! | file             | what                                                                  |
//! |------------------|-----------------------------------------------------------------------|
//! | `materials.toml` | the fitted `[materials.NAME]` tables, loadable with `--materials`; with the seed procedure the force set under the materials' names and the shape set as `NAME-shape` |
//! | `fit.json`       | per set (`sets.force`, `sets.shape`, or `sets.joint`), per material, per key: `{"value": v, "ci95": [low, high]}`; the steps with objective, iterations, correlations and warnings; per trial the fitted simulation's misfit and, for a double compression, the measured and simulated texture profiles; simulations used |
//! | `fit.svg`        | measured against simulated force, per trial                          |
//! | `shapes.svg`     | marker positions: initial, keep and final, measured against simulated |
//! | `summary.json`   | a short summary (and the mark of a wagashi output folder for `--force`) |
//!
//! # What it prints
//!
//! - Per step, the residual RMS in the campaign's noise units (each channel's
//!   own sigma, whatever scales the step weighted it with).
//! - Per trial, the misfit of the fitted simulation: the force RMS [N], in
//!   noise units (over the trial's force sigma) and as a share of the trial's
//!   peak measured force; the marker RMS [mm] and in noise units (over
//!   `--marker-sigma-mm`). The force is the force (or joint) set's simulation,
//!   the markers the shape (or joint) set's.
//! - Per trial whose protocol pushes twice (a double compression), the texture
//!   profile ([`wagashi_io::texture::tpa`], default threshold, no smoothing) of
//!   the measured force and of the fitted simulation's force at the same sample
//!   times, both over `0 <= t <= end_s`: hardness, cohesiveness, springiness and
//!   resilience. A trial whose record the analysis refuses (one stroke, no
//!   contact) gets a note and no profile.
//! - Each estimate as `value [low, high]`, the 95 % interval, with its width
//!   relative to the value only when that is finite and at most 100 %: a wider
//!   interval says the data do not determine the value, and its width in
//!   percent says nothing more.

use std::collections::BTreeMap;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use crate::press::positive_number;
use anyhow::{anyhow, bail};
use calibrate::procedure::{run as run_procedure, Estimate, FitReport, Procedure, ProcedureOptions};
use calibrate::trial::{set_parameter, Campaign, Channel};
use calibrate::warning::number;
use clap::{Args, ValueEnum};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::{json, Map, Value};
use wagashi_io::texture::{analyse, read_tpa_record, Tpa, TpaOptions, TpaRecord};
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
95 % intervals, correlations, warnings, each trial's misfit and, for a double compression, its measured and simulated \
texture profile), fit.svg and shapes.svg into OUT, atomically. Prints each estimate as value [low, high], each \
trial's misfit in noise units and as a share of its peak force, and the texture profiles.",
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
pub fn run(args: &FitArgs, out: &mut dyn Write) -> anyhow::Result<()> {
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

    // Force from the force (or joint) set, shapes from the shape (or joint) set.
    let force_set = report.values("force").or_else(|| report.values("joint")).ok_or_else(|| anyhow!("no set"))?;
    let shape_set = report.values("shape").unwrap_or_else(|| force_set.clone());
    let force_runs = campaign.simulate_all(&force_set).map_err(|e| anyhow!("simulating the fitted trials: {e}"))?;
    let shape_runs = campaign.simulate_all(&shape_set).map_err(|e| anyhow!("simulating the fitted trials: {e}"))?;
    let outcomes = trial_outcomes(&campaign, &bundles, &force_runs, &shape_runs);

    write_outputs(&campaign, &bundles, &report, &outcomes, (&force_runs, &shape_runs), output)?;
    print_report(&report, &outcomes, &args.output, out)?;
    Ok(())
}

/// The force misfit of one trial's fitted simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ForceMisfit {
    /// RMS of simulated minus measured force over the fitted samples [N].
    rms_n: f64,
    /// The trial's force noise [N].
    sigma_n: f64,
    /// The largest measured force magnitude over `0 < t <= end_s` [N], all samples.
    peak_n: f64,
}

/// The marker misfit of one trial's fitted simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
struct MarkerMisfit {
    /// RMS of simulated minus measured marker coordinates [mm].
    rms_mm: f64,
    /// The marker noise [mm].
    sigma_mm: f64,
    /// Coordinates compared.
    num_coordinates: usize,
}

/// The measured and simulated texture profiles of a double compression.
#[derive(Debug, Clone)]
struct TpaPair {
    measured: Tpa,
    simulated: Tpa,
}

/// What the fitted simulations say about one trial.
#[derive(Debug, Clone)]
struct TrialOutcome {
    name: String,
    force: Option<ForceMisfit>,
    markers: Option<MarkerMisfit>,
    /// `Ok` for a double compression the analysis accepts, `Err(why)` when it
    /// refuses one, `None` for any other protocol.
    tpa: Option<Result<TpaPair, String>>,
}

fn trial_outcomes(
    campaign: &Campaign,
    bundles: &[Bundle],
    force_runs: &[fem_core::press::PressResult],
    shape_runs: &[fem_core::press::PressResult],
) -> Vec<TrialOutcome> {
    campaign
        .trials
        .iter()
        .zip(bundles)
        .zip(force_runs.iter().zip(shape_runs))
        .map(|((trial, bundle), (force_run, shape_run))| {
            let force = (!trial.force.is_empty()).then(|| {
                let simulated = trial.simulated_force(force_run);
                let sum: f64 = trial.force.iter().zip(&simulated).map(|(m, s)| (s - m.1).powi(2)).sum();
                ForceMisfit {
                    rms_n: (sum / trial.force.len() as f64).sqrt(),
                    sigma_n: trial.force_sigma_n,
                    peak_n: full_peak_n(bundle).unwrap_or(0.0),
                }
            });
            let pairs = trial.marker_pairs(shape_run);
            let (sum, count) = pairs
                .iter()
                .flat_map(|p| p.measured.iter().zip(&p.simulated))
                .fold((0.0, 0usize), |(s, n), (m, x)| (s + (x - m).powi(2), n + 1));
            let markers = (count > 0).then(|| MarkerMisfit {
                rms_mm: (sum / count as f64).sqrt(),
                sigma_mm: campaign.marker_sigma_mm,
                num_coordinates: count,
            });
            let double = crate::tpa::is_double_compression(&bundle.experiment.protocol.waypoints);
            let tpa = (double && bundle.force.is_some())
                .then(|| tpa_pair(bundle, force_run, bundle.experiment.protocol.end_s));
            TrialOutcome { name: trial.name.clone(), force, markers, tpa }
        })
        .collect()
}

/// The largest measured force magnitude over `0 < t <= end_s` [N], from every
/// sample of the bundle's force (the fit may use a thinned subset, which can
/// miss the peak sample).
fn full_peak_n(bundle: &Bundle) -> Option<f64> {
    let end_s = bundle.experiment.protocol.end_s;
    let force = bundle.force.as_ref()?;
    Some(force.samples.iter().filter(|s| s.t_s > 0.0 && s.t_s <= end_s).map(|s| s.force_n.abs()).fold(0.0, f64::max))
}

/// The texture profiles of a bundle's measured force (read as `wagashi tpa
/// BUNDLE` reads it) and of the simulation's force at the same sample times,
/// both over `0 <= t <= end_s`.
fn tpa_pair(bundle: &Bundle, run: &fem_core::press::PressResult, end_s: f64) -> Result<TpaPair, String> {
    let record = read_tpa_record(&bundle.dir).map_err(|e| e.to_string())?;
    let keep: Vec<usize> = (0..record.t_s.len()).filter(|&i| (0.0..=end_s).contains(&record.t_s[i])).collect();
    let measured = TpaRecord {
        file: record.file.clone(),
        force_column: record.force_column.clone(),
        t_s: keep.iter().map(|&i| record.t_s[i]).collect(),
        force_n: keep.iter().map(|&i| record.force_n[i]).collect(),
        lines: keep.iter().map(|&i| record.lines[i]).collect(),
    };
    let simulated = TpaRecord {
        force_column: "simulated force".into(),
        force_n: measured.t_s.iter().map(|&t| run.bottom_force_at(t)).collect(),
        ..measured.clone()
    };
    let options = TpaOptions::default();
    let measured = analyse(&measured, &options).map_err(|e| format!("measured: {e}"))?;
    let simulated = analyse(&simulated, &options).map_err(|e| format!("simulated: {e}"))?;
    Ok(TpaPair { measured, simulated })
}

/// The four texture numbers compared, with their JSON keys.
fn tpa_numbers(tpa: &Tpa) -> [(&'static str, f64); 4] {
    [
        ("hardness_N", tpa.hardness_n),
        ("cohesiveness", tpa.cohesiveness),
        ("springiness", tpa.springiness),
        ("resilience", tpa.resilience),
    ]
}

/// `{"measured": {...}, "simulated": {...}}`, each the four numbers, the
/// gumminess, chewiness and adhesiveness, the split and the strokes.
fn tpa_pair_json(pair: &TpaPair) -> Value {
    let one = |t: &Tpa| {
        json!({
            "hardness_N": t.hardness_n,
            "cohesiveness": t.cohesiveness,
            "springiness": t.springiness,
            "resilience": t.resilience,
            "gumminess_N": t.gumminess_n,
            "chewiness_N": t.chewiness_n,
            "adhesiveness_N_s": t.adhesiveness_n_s,
            "threshold_N": t.threshold_n,
            "split_s": t.split_s,
            "strokes": t.strokes,
        })
    };
    json!({ "measured": one(&pair.measured), "simulated": one(&pair.simulated) })
}

/// Per trial, the fitted simulation's misfit: force in N, in noise units and as a
/// share of the peak; markers in mm and in noise units.
fn misfit_text(outcomes: &[TrialOutcome]) -> String {
    let mut s = String::from("misfit of the fitted simulation, per trial:\n");
    for o in outcomes {
        let mut parts = Vec::new();
        if let Some(f) = o.force {
            let share = share(f.rms_n, f.peak_n);
            let of_peak = if share.is_finite() {
                format!("{} % of its peak {} N", number(100.0 * share), number(f.peak_n))
            } else {
                String::from("no peak (the measured force is zero)")
            };
            parts.push(format!(
                "force rms {} N = {} noise units (sigma {} N) = {of_peak}",
                number(f.rms_n),
                number(f.rms_n / f.sigma_n),
                number(f.sigma_n)
            ));
        }
        if let Some(m) = o.markers {
            parts.push(format!(
                "markers rms {} mm = {} noise units (sigma {} mm, {} coordinates)",
                number(m.rms_mm),
                number(m.rms_mm / m.sigma_mm),
                number(m.sigma_mm),
                m.num_coordinates
            ));
        }
        if parts.is_empty() {
            parts.push("no data".into());
        }
        s += &format!("  {}: {}\n", o.name, parts.join("; "));
    }
    s
}

/// The measured against simulated texture profile of every double compression,
/// as a table (empty when there is none), then a note per refused record.
fn tpa_text(outcomes: &[TrialOutcome]) -> String {
    let pairs: Vec<(&str, &TpaPair)> =
        outcomes.iter().filter_map(|o| o.tpa.as_ref()?.as_ref().ok().map(|p| (o.name.as_str(), p))).collect();
    let mut s = String::new();
    if !pairs.is_empty() {
        let width = pairs.iter().map(|p| p.0.chars().count()).max().unwrap_or(5).max(5);
        s += "texture profile, measured / simulated:\n";
        s += &format!("  {:<width$}", "trial");
        for (key, _) in tpa_numbers(&pairs[0].1.measured) {
            s += &format!("  {key:>19}");
        }
        s.push('\n');
        for (name, pair) in &pairs {
            s += &format!("  {name:<width$}");
            for ((_, m), (_, x)) in tpa_numbers(&pair.measured).into_iter().zip(tpa_numbers(&pair.simulated)) {
                s += &format!("  {:>19}", format!("{m:.4} / {x:.4}"));
            }
            s.push('\n');
        }
    }
    for o in outcomes {
        if let Some(Err(why)) = &o.tpa {
            s += &format!("note: {}: no texture profile: {why}\n", o.name);
        }
    }
    s
}

/// `value [low, high]` with the 95 % interval, and its width relative to the
/// value when that is meaningful: finite and at most 100 % (wider, the data do
/// not determine the value, and the percentage says nothing more).
fn interval_text(value: f64, ci95: Option<[f64; 2]>) -> String {
    match ci95 {
        None => format!("{value:.5e}   (held)"),
        Some([lo, hi]) if lo.is_nan() || hi.is_nan() => format!("{value:.5e}   (no interval)"),
        Some([lo, hi]) => {
            let relative = (hi - lo) / value.abs();
            let range = format!("{value:.5e} [{lo:.4e}, {hi:.4e}]");
            if relative.is_finite() && relative <= 1.0 {
                format!("{range}   95 %, width {} % of the value", number(100.0 * relative))
            } else {
                format!("{range}   95 %, wider than the value: not determined by the data")
            }
        }
    }
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

fn fit_json(campaign: &Campaign, report: &FitReport, outcomes: &[TrialOutcome]) -> Value {
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
        .zip(outcomes)
        .map(|(t, o)| {
            let mut entry = json!({
                "name": t.name,
                "force_samples": t.count(Channel::Force),
                "force_sigma_N": t.force_sigma_n,
                "keep_coordinates": t.count(Channel::Keep),
                "final_coordinates": t.count(Channel::Final),
            });
            let mut misfit = Map::new();
            if let Some(f) = o.force {
                misfit.insert("force_rms_N".into(), json!(f.rms_n));
                misfit.insert("force_rms_noise_units".into(), json!(f.rms_n / f.sigma_n));
                misfit.insert("force_peak_N".into(), json!(f.peak_n));
                misfit.insert("force_rms_share_of_peak".into(), json!(share(f.rms_n, f.peak_n)));
            }
            if let Some(m) = o.markers {
                misfit.insert("marker_rms_mm".into(), json!(m.rms_mm));
                misfit.insert("marker_rms_noise_units".into(), json!(m.rms_mm / m.sigma_mm));
            }
            entry["misfit"] = Value::Object(misfit);
            if let Some(Ok(pair)) = &o.tpa {
                entry["tpa"] = tpa_pair_json(pair);
            }
            entry
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

/// `part / whole`, or NaN (JSON null) for a zero whole.
fn share(part: f64, whole: f64) -> f64 {
    if whole > 0.0 {
        part / whole
    } else {
        f64::NAN
    }
}

/// The fitted runs: the force (or joint) set's and the shape (or joint) set's.
type FittedRuns<'a> = (&'a [fem_core::press::PressResult], &'a [fem_core::press::PressResult]);

fn write_outputs(
    campaign: &Campaign,
    bundles: &[Bundle],
    report: &FitReport,
    outcomes: &[TrialOutcome],
    (force_runs, shape_runs): FittedRuns<'_>,
    output: AtomicDir,
) -> anyhow::Result<()> {
    let dir = output.path().to_path_buf();
    let json = fit_json(campaign, report, outcomes);
    write_atomic(dir.join("fit.json"), serde_json::to_string_pretty(&json)?.as_bytes())?;
    write_atomic(dir.join("materials.toml"), materials_toml(campaign, report)?.as_bytes())?;
    write_atomic(dir.join("fit.svg"), crate::plot::fit_svg(campaign, force_runs)?.as_bytes())?;
    write_atomic(dir.join("shapes.svg"), crate::plot::shapes_svg(campaign, bundles, shape_runs)?.as_bytes())?;
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

fn print_report(
    report: &FitReport,
    outcomes: &[TrialOutcome],
    output: &std::path::Path,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    for s in &report.steps {
        match &s.skipped {
            Some(why) => writeln!(out, "step {}: skipped: {why}", s.name)?,
            None => writeln!(
                out,
                "step {}: rms {} noise units, {} iterations, {} evaluations over {} start(s), {:.2} s ({})",
                s.name,
                number(s.rms),
                s.iterations,
                s.evaluations,
                s.starts,
                s.wall_s,
                s.stop
            )?,
        }
        for w in s.warnings.iter().filter(|_| s.skipped.is_none()) {
            writeln!(out, "  warning: {w}")?;
        }
    }
    for (name, est) in &report.sets {
        writeln!(out, "set {name}:")?;
        for e in est {
            writeln!(out, "  {:<24} {}", e.label, interval_text(e.value, e.ci95))?;
        }
    }
    out.write_all(misfit_text(outcomes).as_bytes())?;
    out.write_all(tpa_text(outcomes).as_bytes())?;
    writeln!(out, "{} simulations, {:.1} s; results in {}", report.simulations, report.wall_s, output.display())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_read_as_ranges_with_a_width_only_when_it_means_something() {
        assert_eq!(
            interval_text(2.0, Some([1.9, 2.1])),
            "2.00000e0 [1.9000e0, 2.1000e0]   95 %, width 10.00 % of the value"
        );
        // Exactly as wide as the value: still a width.
        assert!(interval_text(2.0, Some([1.0, 3.0])).ends_with("width 100.0 % of the value"));
        assert!(interval_text(2.0, Some([2.0 - 1e-9, 2.0 + 1e-9])).ends_with("width 1.000e-7 % of the value"));
        // Wider, unbounded or around a zero value: the range only.
        for (value, ci) in [(2.0, [0.01, 6.3e4]), (2.0, [0.5, f64::INFINITY]), (0.0, [-1.0, 1.0])] {
            let text = interval_text(value, Some(ci));
            assert!(text.ends_with("wider than the value: not determined by the data"), "{text}");
            assert!(!text.contains("width"), "{text}");
        }
        assert!(interval_text(2.0, Some([0.5, f64::INFINITY])).contains("[5.0000e-1, inf]"));
        assert_eq!(interval_text(0.3, None), "3.00000e-1   (held)");
        assert_eq!(interval_text(0.3, Some([f64::NAN, f64::NAN])), "3.00000e-1   (no interval)");
    }

    #[test]
    fn misfit_lines_give_noise_units_and_the_share_of_the_peak() {
        let outcome = |force, markers| TrialOutcome { name: "t".into(), force, markers, tpa: None };
        let text = misfit_text(&[
            outcome(Some(ForceMisfit { rms_n: 0.02, sigma_n: 0.01, peak_n: 4.0 }), None),
            outcome(None, Some(MarkerMisfit { rms_mm: 0.1, sigma_mm: 0.05, num_coordinates: 8 })),
            outcome(Some(ForceMisfit { rms_n: 0.02, sigma_n: 0.01, peak_n: 0.0 }), None),
        ]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "misfit of the fitted simulation, per trial:");
        assert_eq!(
            lines[1],
            "  t: force rms 0.02000 N = 2.000 noise units (sigma 0.01000 N) = 0.5000 % of its peak 4.000 N"
        );
        assert_eq!(lines[2], "  t: markers rms 0.1000 mm = 2.000 noise units (sigma 0.05000 mm, 8 coordinates)");
        assert!(lines[3].ends_with("no peak (the measured force is zero)"), "{}", lines[3]);
        assert_eq!(
            [number(0.0), number(2.3165e-12), number(12345.6), number(-0.5)],
            ["0", "2.317e-12", "12346", "-0.5000"]
        );
    }

    /// Two triangular compressions, peaks `first` and `second` [N], 0.1 s apart samples.
    fn double_triangle(first: f64, second: f64) -> Tpa {
        let t_s: Vec<f64> = (0..=300).map(|i| 0.1 * i as f64).collect();
        let triangle = |t: f64, start: f64, peak: f64| (peak * (1.0 - (t - start - 5.0).abs() / 5.0)).max(0.0);
        let record = TpaRecord {
            file: "synthetic.csv".into(),
            force_column: "force_N".into(),
            force_n: t_s.iter().map(|&t| triangle(t, 0.0, first) + triangle(t, 15.0, second)).collect(),
            lines: (0..t_s.len()).map(|i| i + 2).collect(),
            t_s,
        };
        analyse(&record, &TpaOptions::default()).unwrap()
    }

    #[test]
    fn texture_table_pairs_measured_and_simulated_per_trial() {
        let pair = TpaPair { measured: double_triangle(2.0, 1.5), simulated: double_triangle(2.5, 1.5) };
        let outcome = TrialOutcome { name: "dc".into(), force: None, markers: None, tpa: Some(Ok(pair)) };
        let text = tpa_text(&[outcome]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3, "{text}");
        assert_eq!(lines[0], "texture profile, measured / simulated:");
        let header: Vec<&str> = lines[1].split_whitespace().collect();
        assert_eq!(header, ["trial", "hardness_N", "cohesiveness", "springiness", "resilience"]);
        assert!(lines[2].starts_with("  dc     ") && lines[2].contains("2.0000 / 2.5000"), "{}", lines[2]);
        let json =
            tpa_pair_json(&TpaPair { measured: double_triangle(2.0, 1.5), simulated: double_triangle(2.0, 1.0) });
        assert!((json["measured"]["hardness_N"].as_f64().unwrap() - 2.0).abs() < 1e-12, "{json}");
        assert!(
            json["simulated"]["cohesiveness"].as_f64().unwrap() < json["measured"]["cohesiveness"].as_f64().unwrap()
        );
    }

    #[test]
    fn texture_notes_name_the_trial_and_no_table_without_a_profile() {
        let refused =
            TrialOutcome { name: "once".into(), force: None, markers: None, tpa: Some(Err("no second stroke".into())) };
        let other = TrialOutcome { name: "creep".into(), force: None, markers: None, tpa: None };
        assert_eq!(tpa_text(&[refused, other]), "note: once: no texture profile: no second stroke\n");
    }
}
