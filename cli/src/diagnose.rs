//! `wagashi diagnose`: the sim-to-real gap diagnosis (`calibrate::diagnosis`).
//!
//! Reads the calibration (and validation) bundles, runs the diagnosis with
//! progress bars for the baseline calibration and the candidates, and writes
//! the output folder atomically:
//!
//! | file             | what                                                                 |
//! |------------------|----------------------------------------------------------------------|
//! | `diagnosis.json` | `verdict` (label, effects, sentence, separating experiment), `selection` (the forward selection, one entry per step: the candidates included, the step's label, the candidate it names, its LR and gap closure with its 90 % interval, the step's candidates), `where` (one entry per cell), `candidates` (per effect id: score, LR, p-value, held-out gain, gap closure with its 90 % interval, fitted effect parameters), `numerical_error` (noise units), `peak_stress_MPa` (the campaign's stress level, which the stress-valued effects' references follow), `marker_shapes` (per trial, the last photograph of the hold and of the recovery: measured, baseline and with the effect), the baseline, the candidates not evaluated and why, warnings |
//! | `report.html`    | one self-contained page (inline SVG, no network): the verdict, measured against simulated force [N] against time [s] per trial and phase before and after the named set, calibration and validation trials, the marker shapes before and after on axes in mm (misfits magnified, RMS in mm), the WHERE heat table, the candidates as a bar chart, the forward selection's steps, the recommended next experiment |
//! | `summary.json`   | a short summary (and the mark of a wagashi output folder for `--force`) |

use std::collections::BTreeMap;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use anyhow::bail;
use calibrate::diagnosis::CandidateId;
use calibrate::diagnosis::{diagnose, Diagnosis, DiagnosisOptions, Stage};
use clap::Args;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::{json, Map, Value};
use wagashi_io::{read_bundle_with, read_materials_file, write_atomic, MaterialSpec};

use crate::press::positive_number;

const DIAGNOSE_AFTER_HELP: &str = "\
Examples:
  # Three trials at different speeds and holds, every implemented candidate:
  wagashi diagnose --calibrate trials/slow trials/fast trials/long-hold -o out/diagnosis

  # Calibrate on two trials, check on a third, only two candidates:
  wagashi diagnose --calibrate trials/a trials/b --validate trials/c --effects force-offset,gravity -o out/d

  # Start values (and freed parameters) from a materials file, cylinders by their section:
  wagashi diagnose --calibrate bundles/s1 bundles/s2 --materials start.toml --axisymmetric -o out/d

Candidates of a chain campaign (the seed's five-element materials): plastic-slider, bingham-dashpot,
stress-thinning, dual-viscosity, strain-stiffening, finite-strain, plate-friction, adhesion,
machine-compliance, gravity, force-offset, ageing.
Candidates of a network campaign (every material model = \"network\"): the network's components
exponential-stiffening, plastic-set, mullins-softening, extra-viscous-network, power-law-flow,
loading-unloading-viscosity, and plate-friction, adhesion, machine-compliance, gravity, force-offset,
ageing. A candidate that cannot act on the campaign is listed in diagnosis.json as not evaluated.";

/// `wagashi diagnose --calibrate BUNDLE... -o OUT`.
#[derive(Debug, Args)]
#[command(
    about = "Diagnose the sim-to-real gap: where it lies, which unmodelled effect causes it, how far it shrinks",
    long_about = "Diagnose the sim-to-real gap of measured trials: calibrate the baseline material model, \
estimate the numerical error, localise the misfit by phase, channel and region, test every candidate effect of \
the library (score test, refit, likelihood ratio with multiplicity control, held-out check) and measure how far \
the named effect closes the gap on held-out data. Writes OUT/diagnosis.json atomically.",
    after_help = DIAGNOSE_AFTER_HELP
)]
pub struct DiagnoseArgs {
    /// Measured trials to calibrate on: bundle folders.
    #[arg(long, value_name = "BUNDLE", num_args = 1.., required_unless_present = "blind")]
    pub calibrate: Vec<PathBuf>,

    /// Measured trials held out for validation (default: leave each calibration trial out in turn).
    #[arg(long, value_name = "BUNDLE", num_args = 1..)]
    pub validate: Vec<PathBuf>,

    /// A TOML file of [materials.NAME] tables (start values; their parameters are calibrated).
    #[arg(long, value_name = "FILE")]
    pub materials: Option<PathBuf>,

    /// Blind self-check instead of a diagnosis: generate N synthetic campaigns (seed --seed), each
    /// withholding one effect of the library at lambda 12, 30 or 100, nothing, or an out-of-library
    /// mechanism; diagnose each without being told; write OUT/blind.json and print the scores.
    #[arg(long, value_name = "N", conflicts_with_all = ["calibrate", "validate", "materials", "axisymmetric"],
          value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub blind: Option<u32>,

    /// With --blind: ideal samples (no sample-to-sample variability, no geometry errors); the
    /// diagnoser has no per-sample scales in its calibration yet, so the issue's scatter swamps
    /// every effect (see calibrate::diagnosis::blind).
    #[arg(long = "blind-ideal-samples", requires = "blind")]
    pub blind_ideal_samples: bool,

    /// The output folder; refused if it exists and is not a previous wagashi output.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,

    /// Candidate effects: `all`, or effect ids separated by commas.
    #[arg(long, value_name = "all|ID,ID", default_value = "all")]
    pub effects: String,

    /// Latin hypercube starts of the baseline calibration besides the start values.
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(0..=256))]
    pub starts: u32,

    /// Seed of the starts and of the bootstrap (with --blind: of the campaigns too).
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,

    /// Target element size [mm]; default: a quarter of each specimen's smallest dimension.
    #[arg(long = "size-mm", value_name = "H", value_parser = positive_number, allow_negative_numbers = true)]
    pub size_mm: Option<f64>,

    /// Model cylinders by their axisymmetric r-y section.
    #[arg(long)]
    pub axisymmetric: bool,

    /// Marker noise [mm].
    #[arg(long = "marker-sigma-mm", value_name = "MM", default_value_t = 0.05, value_parser = positive_number, allow_negative_numbers = true)]
    pub marker_sigma_mm: f64,

    /// Replace OUT when it holds a previous wagashi output (a folder whose
    /// wagashi-manifest.json lists every file in it; only those files are removed).
    #[arg(long)]
    pub force: bool,

    /// Run even when a trial's estimated memory (6 V / h^3 tetrahedra in 3D)
    /// exceeds the memory the machine has available.
    #[arg(long = "allow-large")]
    pub allow_large: bool,
}

/// `--effects`: `all` or ids.
fn parse_effects(text: &str) -> anyhow::Result<Option<Vec<CandidateId>>> {
    if text.trim() == "all" {
        return Ok(None);
    }
    let mut out = Vec::new();
    for id in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match CandidateId::from_id(id) {
            Some(e) if !out.contains(&e) => out.push(e),
            Some(_) => {}
            None => bail!(
                "--effects: unknown candidate id `{id}` (known: all, {})",
                CandidateId::all().iter().map(|e| e.id()).collect::<Vec<_>>().join(", ")
            ),
        }
    }
    if out.is_empty() {
        bail!("--effects: no effect id given (use `all` or ids separated by commas)");
    }
    Ok(Some(out))
}

/// `wagashi diagnose`.
pub fn run(args: &DiagnoseArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let effects = parse_effects(&args.effects)?;
    if let Some(n) = args.blind {
        return run_blind(args, n as usize, effects, out);
    }
    let start: BTreeMap<String, MaterialSpec> = match &args.materials {
        Some(path) => read_materials_file(path)?,
        None => Default::default(),
    };
    let read = |dirs: &[PathBuf]| -> anyhow::Result<Vec<wagashi_io::Bundle>> {
        dirs.iter().map(|d| Ok(read_bundle_with(d, &start)?)).collect()
    };
    let calibration = read(&args.calibrate)?;
    let validation = read(&args.validate)?;
    let all: Vec<&wagashi_io::Bundle> = calibration.iter().chain(&validation).collect();
    let mut inputs: Vec<(&str, &std::path::Path)> = all.iter().map(|b| ("bundle", b.dir.as_path())).collect();
    inputs.extend(args.materials.iter().map(|m| ("materials file", m.as_path())));
    crate::outputs::check_trials_memory(
        &all,
        args.size_mm,
        args.size_mm.is_some(),
        args.axisymmetric,
        args.allow_large,
    )?;
    let output = crate::press::prepare_output(&inputs, &args.output, args.force)?;
    let options = DiagnosisOptions {
        starts: args.starts as usize,
        seed: args.seed,
        effects,
        size_mm: args.size_mm,
        axisymmetric: args.axisymmetric,
        marker_sigma_mm: args.marker_sigma_mm,
        ..DiagnosisOptions::default()
    };
    let bars = StageBars::new();
    let result =
        diagnose(&calibration, &validation, &start, &options, &|stage, done, total| bars.update(stage, done, total));
    bars.finish();
    let d = result?;
    let doc = diagnosis_json(&d);
    let dir = output.path().to_path_buf();
    write_atomic(dir.join("diagnosis.json"), serde_json::to_string_pretty(&doc)?.as_bytes())?;
    write_atomic(dir.join("report.html"), report_html(&d).as_bytes())?;
    let summary = json!({
        "command": "diagnose",
        "verdict": d.verdict.label,
        "calibration": args.calibrate.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "validation": args.validate.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    });
    write_atomic(dir.join(wagashi_io::atomic::OUTPUT_MARKER_FILE), serde_json::to_string_pretty(&summary)?.as_bytes())?;
    output.commit()?;
    print_report(&d, &args.output, out)?;
    Ok(())
}

/// Two bars (calibration starts, candidates) on stderr; hidden when stderr is not a terminal.
struct StageBars {
    multi: MultiProgress,
    bars: Mutex<BTreeMap<&'static str, ProgressBar>>,
}

impl StageBars {
    fn new() -> Self {
        let target =
            if std::io::stderr().is_terminal() { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
        Self { multi: MultiProgress::with_draw_target(target), bars: Mutex::new(BTreeMap::new()) }
    }

    fn update(&self, stage: Stage, done: usize, total: usize) {
        let name = match stage {
            Stage::Calibration => "baseline calibration (starts)",
            Stage::Candidates => "candidate effects",
        };
        let Ok(mut bars) = self.bars.lock() else { return };
        let bar = bars.entry(name).or_insert_with(|| {
            let b = self.multi.add(ProgressBar::new(total as u64));
            let style = ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:24}] {pos}/{len} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> ");
            b.set_style(style);
            b.set_message(name);
            b.enable_steady_tick(Duration::from_millis(200));
            b
        });
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    }

    fn finish(&self) {
        if let Ok(bars) = self.bars.lock() {
            for bar in bars.values() {
                bar.finish_and_clear();
            }
        }
    }
}

/// `diagnosis.json` (module docs).
pub fn diagnosis_json(d: &Diagnosis) -> Value {
    let cells: Vec<Value> = d
        .where_cells
        .iter()
        .map(|c| {
            json!({
                "phase": c.phase.as_str(),
                "channel": c.channel.as_str(),
                "region": c.region.as_str(),
                "n": c.n,
                "dof": c.dof,
                "statistic": c.statistic,
                "p_value": c.p_value,
                "flagged": c.flagged,
                "rms_noise_units": c.rms_noise_units,
                "mean_noise_units": c.mean_noise_units,
                "systematic_fraction": c.systematic_fraction,
            })
        })
        .collect();
    let mut candidates = Map::new();
    for c in &d.candidates {
        let params: Map<String, Value> = c
            .parameters
            .iter()
            .map(|p| (p.key.to_string(), json!({"value": p.value, "null": p.null, "unit": p.unit, "symbol": p.name})))
            .collect();
        let theta: Map<String, Value> =
            d.baseline.labels.iter().zip(&c.theta).map(|(l, v)| (l.clone(), json!(v))).collect();
        let closure = c.heldout.as_ref().map(|h| {
            json!({
                "value": h.closure,
                "ci90": [h.closure_ci90[0], h.closure_ci90[1]],
                "heldout_gap": h.gap,
                "reportable": h.reportable,
            })
        });
        candidates.insert(
            c.effect.id().to_string(),
            json!({
                "score_statistic": c.score_statistic,
                "score_p_value": c.score_p_value,
                "epc": c.epc,
                "lr": c.lr,
                "p_value": c.p_value,
                "lr_critical": c.lr_critical,
                "significant": c.significant,
                "heldout_gain": c.heldout.as_ref().map(|h| h.gain),
                "heldout_gain_se": c.heldout.as_ref().map(|h| h.gain_se),
                "heldout_gain_se_segments": c.heldout.as_ref().map(|h| h.gain_se_segments),
                "eligible": c.eligible,
                "combined": c.combined,
                "gap_closure": closure,
                "parameters": params,
                "theta": theta,
                "remaining_flagged": c.remaining_flagged,
                "lm_num": c.lm_num,
                "refit_starts": c.refit_starts,
                "fell_back_to_null": c.fell_back,
                "refit_errors": c.refit_errors,
            }),
        );
    }
    let not_evaluated: Map<String, Value> =
        d.not_evaluated.iter().map(|(e, why)| (e.id().to_string(), json!(why))).collect();
    let baseline: Map<String, Value> =
        d.baseline.labels.iter().zip(&d.baseline.values).map(|(l, v)| (l.clone(), json!(v))).collect();
    let lm_num: Map<String, Value> =
        d.numerical_error.per_candidate.iter().map(|(e, v)| (e.id().to_string(), json!(v))).collect();
    json!({
        "verdict": {
            "label": d.verdict.label,
            "effects": d.verdict.effects.iter().map(|e| e.id()).collect::<Vec<_>>(),
            "sentence": d.verdict.sentence,
            "separating_experiment": d.verdict.separating_experiment,
            "remaining_cells": d.verdict.remaining_cells,
            "tie_test": d.verdict.tie_test.as_ref().map(tie_test_json),
        },
        "selection": d.selection.iter().map(|s| json!({
            "included": s.included.iter().map(|c| c.id()).collect::<Vec<_>>(),
            "label": s.label,
            "named": s.named.map(|c| c.id()),
            "baseline_objective": s.baseline_objective,
            "lr": s.lr,
            "p_value": s.p_value,
            "gap_closure": s.heldout.as_ref().map(|h| json!({"G": h.closure, "ci90": h.closure_ci90, "reportable": h.reportable})),
            "remaining_cells": s.remaining_cells,
            "candidates": s.candidates.iter().map(|c| json!({"id": c.effect.id(), "lr": c.lr, "p_value": c.p_value, "eligible": c.eligible, "combined": c.combined})).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "where": cells,
        "candidates": candidates,
        "not_evaluated": not_evaluated,
        "peak_stress_MPa": d.peak_stress_mpa,
        "force_noise": d.force_noise.iter().map(|(t, s, r)| json!({"trial": t, "sigma_N": s, "lag1_correlation": r})).collect::<Vec<_>>(),
        "numerical_error": {
            "refinement": d.numerical_error.refinement,
            "chi2_noise_units": d.numerical_error.chi2,
            "rms_noise_units": d.numerical_error.rms_noise_units,
            "max_abs_noise_units": d.numerical_error.max_abs_noise_units,
            "mesh_correction_chi2_noise_units": d.numerical_error.mesh_chi2,
            "mesh_unabsorbed_chi2_noise_units": d.numerical_error.mesh_chi2_unabsorbed,
            "lm_num": lm_num,
        },
        "baseline": {
            "parameters": baseline,
            "objective": d.baseline.objective,
            "rms_noise_units": d.baseline.rms_noise_units,
            "residuals": d.baseline.num_residuals,
            "stop": d.baseline.stop,
        },
        "marker_shapes": d.shapes.iter().map(|s| json!({
            "trial": s.trial,
            "t_s": s.t_s,
            "phase": s.phase.as_str(),
            "markers": s.markers.iter().map(|p| json!({
                "marker": p.marker, "measured_mm": p.measured, "baseline_mm": p.baseline, "with_effect_mm": p.with_effect,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "trials": d.trials,
        "validation_trials": d.validation_trials,
        "heldout_method": d.heldout_method,
        "warnings": d.warnings,
    })
}

fn print_report(d: &Diagnosis, output: &std::path::Path, out: &mut dyn Write) -> anyhow::Result<()> {
    writeln!(out, "verdict: {}", d.verdict.label)?;
    writeln!(out, "  {}", d.verdict.sentence)?;
    if let Some(e) = &d.verdict.separating_experiment {
        writeln!(out, "  next experiment: {e}")?;
    }
    let flagged: Vec<String> = d.where_cells.iter().filter(|c| c.flagged).map(|c| c.label()).collect();
    writeln!(out, "where: {}", if flagged.is_empty() { "no cell flagged".to_string() } else { flagged.join(", ") })?;
    writeln!(out, "{:<20} {:>10} {:>10} {:>10} {:>12} {:>8}", "candidate", "score", "LR", "p", "held-out", "G")?;
    for c in &d.candidates {
        writeln!(
            out,
            "{:<20} {:>10.1} {:>10.1} {:>10.2e} {:>12} {:>8}",
            c.effect.id(),
            c.score_statistic,
            c.lr,
            c.p_value,
            c.heldout.as_ref().map_or("-".into(), |h| format!("{:.1}", h.gain)),
            c.heldout.as_ref().map_or("-".into(), |h| format!("{:.2}", h.closure)),
        )?;
    }
    for (e, why) in &d.not_evaluated {
        writeln!(out, "{:<20} not evaluated: {why}", e.id())?;
    }
    for w in &d.warnings {
        writeln!(out, "warning: {w}")?;
    }
    writeln!(out, "results in {}", output.display())?;
    Ok(())
}

/// Escapes text for HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Tick positions of an axis over `[lo, hi]`: multiples of a "nice" step (1, 2
/// or 5 times a power of ten) giving at most about `max_ticks` ticks, and the
/// decimals their labels need.
fn ticks(lo: f64, hi: f64, max_ticks: usize) -> (Vec<f64>, usize) {
    let span = (hi - lo).abs().max(1e-12);
    let raw = span / max_ticks.max(1) as f64;
    let p = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * p).find(|&v| v >= raw).unwrap_or(10.0 * p);
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    let values = (first..=last).map(|k| k as f64 * step).map(|v| if v == 0.0 { 0.0 } else { v }).collect();
    (values, decimals)
}

/// The estimated width [px] of `text` at `font_px` in a sans-serif face (a
/// generous 0.62 em a character, so that estimates err on the wide side).
fn text_width(text: &str, font_px: f64) -> f64 {
    text.chars().count() as f64 * 0.62 * font_px
}

/// The plot area of an SVG chart [px] and its axes' ranges: draws the frame,
/// the ticks with their labels and the axis titles (`x_title` below,
/// `y_title` turned along the left side).
struct Axes {
    left: f64,
    right: f64,
    top: f64,
    bottom: f64,
    x_range: [f64; 2],
    y_range: [f64; 2],
}

impl Axes {
    fn x(&self, v: f64) -> f64 {
        self.left + (self.right - self.left) * (v - self.x_range[0]) / (self.x_range[1] - self.x_range[0])
    }

    fn y(&self, v: f64) -> f64 {
        self.bottom - (self.bottom - self.top) * (v - self.y_range[0]) / (self.y_range[1] - self.y_range[0])
    }

    /// The frame, the ticks and their labels (11 px), and the titles.
    fn draw(&self, x_title: &str, y_title: &str, svg_h: f64) -> String {
        let mut s = format!(
            r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#888"/>"##,
            self.left,
            self.top,
            self.right - self.left,
            self.bottom - self.top
        );
        // As many ticks as fit their labels side by side.
        let max_x = |decimals: usize| {
            let longest = [self.x_range[0], self.x_range[1]]
                .iter()
                .map(|v| text_width(&format!("{v:.decimals$}"), 11.0))
                .fold(0.0, f64::max);
            ((self.right - self.left) / (longest + 12.0)).floor().max(2.0) as usize
        };
        let (mut xs, mut xd) = ticks(self.x_range[0], self.x_range[1], 8);
        if xs.len() > max_x(xd) {
            (xs, xd) = ticks(self.x_range[0], self.x_range[1], max_x(xd));
        }
        for v in xs {
            let px = self.x(v);
            s.push_str(&format!(
                r##"<line x1="{px:.1}" y1="{:.1}" x2="{px:.1}" y2="{:.1}" stroke="#888"/><text x="{px:.1}" y="{:.1}" font-size="11" text-anchor="middle">{v:.xd$}</text>"##,
                self.bottom,
                self.bottom + 4.0,
                self.bottom + 15.0
            ));
        }
        let max_y = ((self.bottom - self.top) / 18.0).floor().max(2.0) as usize;
        let (ys, yd) = ticks(self.y_range[0], self.y_range[1], max_y.min(6));
        for v in ys {
            let py = self.y(v);
            s.push_str(&format!(
                r##"<line x1="{:.1}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#888"/><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{v:.yd$}</text>"##,
                self.left - 4.0,
                self.left,
                self.left - 6.0,
                py + 4.0
            ));
        }
        s.push_str(&format!(
            r#"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">{x_title}</text><text transform="translate(13 {:.1}) rotate(-90)" font-size="12" text-anchor="middle">{y_title}</text>"#,
            0.5 * (self.left + self.right),
            svg_h - 5.0,
            0.5 * (self.top + self.bottom)
        ));
        s
    }
}

/// The left margin [px] that fits the y tick labels of `range` and the turned title.
fn left_margin(range: [f64; 2]) -> f64 {
    let (ys, yd) = ticks(range[0], range[1], 6);
    let widest = ys.iter().map(|v| text_width(&format!("{v:.yd$}"), 11.0)).fold(0.0, f64::max);
    widest + 30.0
}

/// One trial's measured and simulated force against time as an inline SVG
/// (before: baseline, after: with the named effect), phases shaded and named
/// above the plot where their names fit.
fn force_svg(c: &calibrate::diagnosis::ForceCurves, named: bool) -> String {
    let (w, h) = (560.0, 250.0);
    let t_max = c.times.last().map_or(1.0, |t| t.0).max(1e-9);
    let t_min = c.times.first().map_or(0.0, |t| t.0).min(0.0);
    let shown: Vec<&f64> = if named {
        c.measured.iter().chain(&c.baseline).chain(&c.with_effect).collect()
    } else {
        c.measured.iter().chain(&c.baseline).collect()
    };
    let (f_min, f_max) = shown.into_iter().fold((0.0f64, 0.0f64), |(a, b), &f| (a.min(f), b.max(f)));
    let margin = 0.05 * (f_max - f_min).max(1e-12);
    let y_range = [f_min - margin, f_max + margin];
    let axes = Axes {
        left: left_margin(y_range),
        right: w - 14.0,
        top: 30.0,
        bottom: h - 42.0,
        x_range: [t_min, t_max],
        y_range,
    };
    let line = |v: &[f64], colour: &str, width: f64| {
        let pts: Vec<String> =
            c.times.iter().zip(v).map(|((t, _), f)| format!("{:.1},{:.1}", axes.x(*t), axes.y(*f))).collect();
        format!(r#"<polyline fill="none" stroke="{colour}" stroke-width="{width}" points="{}"/>"#, pts.join(" "))
    };
    let mut svg = format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}">"#);
    // Phase bands; each name on the first of two rows where it clears the
    // name before it, else on the second, else left out (the band stays).
    let (mut start, mut band) = (0usize, 0usize);
    let mut row_end = [f64::NEG_INFINITY; 2];
    for i in 1..=c.times.len() {
        if i == c.times.len() || c.times[i].1 != c.times[start].1 {
            let t0 = c.times[start].0;
            let t1 = if i == c.times.len() { c.times[i - 1].0 } else { c.times[i].0 };
            let shade = if band.is_multiple_of(2) { "#f4f4f4" } else { "#e9eef5" };
            band += 1;
            let (x0, x1) = (axes.x(t0), axes.x(t1));
            svg.push_str(&format!(
                r#"<rect x="{x0:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{shade}"/>"#,
                axes.top,
                (x1 - x0).max(0.5),
                axes.bottom - axes.top
            ));
            let name = c.times[start].1.as_str();
            let (tx, tw) = (x0 + 2.0, text_width(name, 10.0));
            if tx + tw <= axes.right {
                if let Some(row) = (0..2).find(|&r| tx >= row_end[r] + 4.0) {
                    row_end[row] = tx + tw;
                    svg.push_str(&format!(
                        r#"<text x="{tx:.1}" y="{:.1}" font-size="10" fill="gray">{name}</text>"#,
                        axes.top - 4.0 - 12.0 * row as f64
                    ));
                }
            }
            start = i;
        }
    }
    svg.push_str(&line(&c.measured, "#999", 1.0));
    svg.push_str(&line(&c.baseline, "#c0392b", 1.5));
    if named {
        svg.push_str(&line(&c.with_effect, "#2471a3", 1.5));
    }
    svg.push_str(&axes.draw("time [s]", "force [N]", h));
    svg.push_str("</svg>");
    svg
}

/// Root-mean-square distance [mm] between two sets of positions.
fn rms_distance(a: &[&Vec<f64>], b: &[&Vec<f64>]) -> f64 {
    let n = a.len().max(1) as f64;
    let sum: f64 =
        a.iter().zip(b).map(|(p, q)| p.iter().zip(q.iter()).map(|(x, y)| (x - y).powi(2)).sum::<f64>()).sum();
    (sum / n).sqrt()
}

/// A "nice" number (1, 2 or 5 times a power of ten) at most `x`.
fn nice_floor(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    [5.0, 2.0, 1.0].into_iter().map(|m| m * p).find(|&v| v <= x).unwrap_or(p)
}

/// The factor by which [`shapes_svg`] magnifies the marker errors: the largest
/// error drawn as about a fifth of the markers' extent.
fn error_gain(s: &calibrate::diagnosis::MarkerShapes, named: bool) -> f64 {
    let (lo, hi) = marker_extent(s);
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0) * 1.3;
    let err = |a: &[f64], b: &[f64]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
    let largest = s
        .markers
        .iter()
        .map(|p| err(&p.baseline, &p.measured).max(if named { err(&p.with_effect, &p.measured) } else { 0.0 }))
        .fold(0.0, f64::max);
    if largest > 0.0 {
        nice_floor(0.2 * span / largest).max(1.0)
    } else {
        1.0
    }
}

/// The measured markers' lower and upper corners [mm] (first two coordinates).
fn marker_extent(s: &calibrate::diagnosis::MarkerShapes) -> ([f64; 2], [f64; 2]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in s.markers.iter().map(|m| &m.measured) {
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    if lo[0] > hi[0] {
        return ([0.0; 2], [1.0; 2]);
    }
    (lo, hi)
}

/// One photograph's markers as an inline SVG on axes in mm (x across, y up,
/// equal scales): the measured places (grey dots) and, from each, the error of
/// the baseline (red) and of the model with the named effect (blue), simulated
/// minus measured, magnified by [`error_gain`] so that millimetre shapes show
/// tenth-of-a-millimetre misfits.
fn shapes_svg(s: &calibrate::diagnosis::MarkerShapes, named: bool) -> String {
    let (w, h): (f64, f64) = (360.0, 290.0);
    let (lo, hi) = marker_extent(s);
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0) * 1.3;
    let gain = error_gain(s, named);
    let (cx, cy) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
    // Equal scales: the ranges fill the plot area at the scale that fits the
    // span both ways; the left margin fits the y labels of those ranges.
    let (top, bottom, right) = (10.0, h - 42.0, w - 14.0);
    let mut left = 50.0;
    let mut axes = None;
    for _ in 0..2 {
        let scale = (right - left).min(bottom - top) / span;
        let (hx, hy) = (0.5 * (right - left) / scale, 0.5 * (bottom - top) / scale);
        let a = Axes { left, right, top, bottom, x_range: [cx - hx, cx + hx], y_range: [cy - hy, cy + hy] };
        left = left_margin(a.y_range);
        axes = Some(a);
    }
    let axes = axes.expect("two passes");
    let mut svg = format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}">"#);
    svg.push_str(&format!(
        r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="#fafafa"/>"##,
        axes.left,
        axes.top,
        axes.right - axes.left,
        axes.bottom - axes.top
    ));
    for calibrate::diagnosis::MarkerPlaces { measured, baseline, with_effect: with, .. } in &s.markers {
        let (mx, my) = (axes.x(measured[0]), axes.y(measured[1]));
        let mut arrow = |to: &[f64], colour: &str| {
            let (ex, ey) = (
                axes.x(measured[0] + gain * (to[0] - measured[0])),
                axes.y(measured[1] + gain * (to[1] - measured[1])),
            );
            svg.push_str(&format!(
                r##"<line x1="{mx:.1}" y1="{my:.1}" x2="{ex:.1}" y2="{ey:.1}" stroke="{colour}" stroke-width="1.5"/><circle cx="{ex:.1}" cy="{ey:.1}" r="2.5" fill="{colour}"/>"##
            ));
        };
        arrow(baseline, "#c0392b");
        if named {
            arrow(with, "#2471a3");
        }
        svg.push_str(&format!(r##"<circle cx="{mx:.1}" cy="{my:.1}" r="3" fill="#777"/>"##));
    }
    svg.push_str(&axes.draw("x [mm]", "y [mm]", h));
    svg.push_str("</svg>");
    svg
}

/// `report.html`: one self-contained page (inline SVG, no network).
pub fn report_html(d: &Diagnosis) -> String {
    let named = !d.verdict.effects.is_empty() && d.verdict.label != "tie";
    let mut html = String::from(
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"/><title>wagashi diagnosis</title><style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 6px;font-size:13px}</style></head><body>",
    );
    html.push_str(&format!(
        "<h1>Sim-to-real gap: {}</h1><p><b>{}</b></p>",
        esc(&d.verdict.label),
        esc(&d.verdict.sentence)
    ));
    html.push_str("<h2>Measured and simulated force, per phase</h2><p>grey: measured; red: baseline");
    if named {
        html.push_str(&format!("; blue: with {}", esc(&d.verdict.label)));
    }
    html.push_str(
        ". Calibration trials: the fits. Validation trials: the held-out predictions at the calibrated \
         parameters, each trial's two sample scales re-estimated, as the gap closure is measured.</p>",
    );
    for c in &d.curves {
        html.push_str(&format!("<h3>{}</h3>{}", esc(&c.trial), force_svg(c, named)));
    }
    for c in &d.validation_curves {
        html.push_str(&format!("<h3>{} (validation)</h3>{}", esc(&c.trial), force_svg(c, named)));
    }
    if !d.shapes.is_empty() {
        html.push_str("<h2>Marker shapes</h2><p>The markers at the last photograph of each phase in the model's coordinates (x across, y up; r and y in an axisymmetric section; x and y of a 3D trial), grey dots where they were measured; from each, the error of the simulation (simulated minus measured place, magnified by the stated factor): red the baseline");
        if named {
            html.push_str(&format!(", blue with {}", esc(&d.verdict.label)));
        }
        html.push_str(".</p><div style=\"display:flex;flex-wrap:wrap;gap:12px\">");
        for s in &d.shapes {
            let measured: Vec<&Vec<f64>> = s.markers.iter().map(|m| &m.measured).collect();
            let baseline: Vec<&Vec<f64>> = s.markers.iter().map(|m| &m.baseline).collect();
            let with: Vec<&Vec<f64>> = s.markers.iter().map(|m| &m.with_effect).collect();
            let mut caption = format!(
                "{}, {} at {:.1} s: RMS distance to measured {:.3} mm (baseline)",
                esc(&s.trial),
                s.phase.as_str(),
                s.t_s,
                rms_distance(&baseline, &measured)
            );
            if named {
                caption.push_str(&format!(", {:.3} mm (with the effect)", rms_distance(&with, &measured)));
            }
            caption.push_str(&format!("; errors magnified x {}", error_gain(s, named)));
            html.push_str(&format!("<figure style=\"margin:0\">{}<figcaption style=\"font-size:12px;max-width:360px\">{caption}</figcaption></figure>", shapes_svg(s, named)));
        }
        html.push_str("</div>");
    }
    html.push_str("<h2>Where: smooth test per cell</h2><table><tr><th>phase</th><th>channel</th><th>region</th><th>RMS [noise units]</th><th>-log10 p</th><th>flagged</th></tr>");
    for c in &d.where_cells {
        let lp = -c.p_value.max(1e-300).log10();
        let heat = (lp / 20.0).clamp(0.0, 1.0);
        let colour = format!("rgb(255,{0},{0})", (255.0 * (1.0 - heat)).round());
        html.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.2}</td><td style=\"background:{colour}\">{lp:.1}</td><td>{}</td></tr>",
            c.phase.as_str(),
            c.channel.as_str(),
            c.region.as_str(),
            c.rms_noise_units,
            if c.flagged { "yes" } else { "" }
        ));
    }
    html.push_str("</table><h2>Which: candidates (likelihood ratio)</h2>");
    let lr_max = d.candidates.iter().map(|c| c.lr).fold(1.0, f64::max);
    let bar_h = 22.0;
    let bars_h = bar_h * d.candidates.len() as f64 + 10.0;
    let total_h = bars_h + 40.0;
    // The label column fits the longest id (12 px text).
    let label_w = d.candidates.iter().map(|c| text_width(c.effect.id(), 12.0)).fold(0.0, f64::max) + 10.0;
    let width = label_w + 400.0 + 120.0;
    let bar_x = |lr: f64| label_w + 400.0 * (lr / lr_max).max(0.0);
    html.push_str(&format!(r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{total_h}">"#));
    for (i, c) in d.candidates.iter().enumerate() {
        let wbar = bar_x(c.lr) - label_w;
        let y = 5.0 + i as f64 * bar_h;
        let colour = if d.verdict.effects.contains(&c.effect) { "#2471a3" } else { "#aab7c4" };
        html.push_str(&format!(
            r#"<text x="0" y="{:.1}" font-size="12">{}</text><rect x="{label_w:.1}" y="{y:.1}" width="{wbar:.1}" height="{:.1}" fill="{colour}"/><text x="{:.1}" y="{:.1}" font-size="11">LR {:.1}{}</text>"#,
            y + 14.0,
            c.effect.id(),
            bar_h - 6.0,
            label_w + 5.0 + wbar,
            y + 14.0,
            c.lr,
            if c.significant { " *" } else { "" }
        ));
    }
    // The LR axis under the bars.
    html.push_str(&format!(
        r##"<line x1="{label_w:.1}" y1="{bars_h:.1}" x2="{:.1}" y2="{bars_h:.1}" stroke="#888"/>"##,
        bar_x(lr_max)
    ));
    let (lrs, decimals) = ticks(0.0, lr_max, 6);
    for v in lrs {
        let px = bar_x(v);
        html.push_str(&format!(
            r##"<line x1="{px:.1}" y1="{bars_h:.1}" x2="{px:.1}" y2="{:.1}" stroke="#888"/><text x="{px:.1}" y="{:.1}" font-size="11" text-anchor="middle">{v:.decimals$}</text>"##,
            bars_h + 4.0,
            bars_h + 15.0
        ));
    }
    html.push_str(&format!(
        r#"<text x="{:.1}" y="{:.1}" font-size="12" text-anchor="middle">likelihood ratio LR (dimensionless)</text>"#,
        label_w + 200.0,
        total_h - 5.0
    ));
    html.push_str("</svg><p>* significant after Holm's correction.</p>");
    if !d.not_evaluated.is_empty() {
        html.push_str("<p>Not evaluated: ");
        let list: Vec<String> = d.not_evaluated.iter().map(|(e, why)| format!("{} ({})", e.id(), esc(why))).collect();
        html.push_str(&list.join("; "));
        html.push_str("</p>");
    }
    if d.selection.len() > 1 {
        html.push_str(
            "<h2>Forward selection</h2><p>Each step tests the candidates left with the ones named before it \
             included (their values refitted), by the same rules; it stops when none is named and improves the \
             held-out prediction.</p><table><tr><th>step</th><th>included</th><th>step verdict</th><th>named</th>\
             <th>LR</th><th>gap closure G [90 % interval]</th></tr>",
        );
        for (i, s) in d.selection.iter().enumerate() {
            let included = if s.included.is_empty() {
                "(baseline)".to_string()
            } else {
                s.included.iter().map(|c| c.id()).collect::<Vec<_>>().join(" + ")
            };
            let closure = s.heldout.as_ref().map_or(String::new(), |h| {
                format!("{:.2} [{:.2}, {:.2}]", h.closure, h.closure_ci90[0], h.closure_ci90[1])
            });
            html.push_str(&format!(
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                i + 1,
                esc(&included),
                esc(&s.label),
                s.named.map_or("", |c| c.id()),
                if s.named.is_some() { format!("{:.1}", s.lr) } else { String::new() },
                closure
            ));
        }
        html.push_str("</table>");
    }
    html.push_str("<h2>Recommended next experiment</h2><p>");
    let next = match (&d.verdict.separating_experiment, d.verdict.effects.first()) {
        (Some(e), _) => e.clone(),
        (None, Some(e)) => format!("To confirm {}: {}.", e.id(), calibrate::diagnosis::discriminator(*e)),
        (None, None) => "The design of diagnosis-details.md §5.7: speed, hold, strain level and aspect ratio varied, \
                         a long hold, force recorded before contact and after separation, the shape tracked after release."
            .to_string(),
    };
    html.push_str(&esc(&next));
    html.push_str(&format!(
        "</p><h2>Numerical error</h2><p>Halved time steps change the residuals by chi2 = {:.3e} (RMS {:.3e} noise units).</p>",
        d.numerical_error.chi2, d.numerical_error.rms_noise_units
    ));
    for w in &d.warnings {
        html.push_str(&format!("<p>warning: {}</p>", esc(w)));
    }
    html.push_str("</body></html>\n");
    html
}

/// `wagashi diagnose --blind N --seed S -o OUT` (`calibrate::diagnosis::blind`):
/// `OUT/blind.json` (every campaign: what it withheld, the realised strength,
/// the generator's draws, the verdict, the gap closures, the timings; the
/// scores, the targets and the confusion matrix) and the table on stdout.
fn run_blind(
    args: &DiagnoseArgs,
    n: usize,
    effects: Option<Vec<CandidateId>>,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    use calibrate::diagnosis::blind;
    let output = crate::press::prepare_output(&[], &args.output, args.force)?;
    let options = DiagnosisOptions {
        starts: args.starts as usize,
        effects,
        size_mm: Some(args.size_mm.unwrap_or(5.0)),
        ..blind::default_options(args.seed)
    };
    let cases = blind::plan(n, args.seed);
    let terminal = std::io::stderr().is_terminal();
    let target = if terminal { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
    let bar = ProgressBar::with_draw_target(Some(n as u64), target);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:24}] {pos}/{len} campaigns {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    let scatter = if args.blind_ideal_samples { blind::Scatter::IDEAL } else { blind::Scatter::ISSUE };
    let result = blind::run_blind(&cases, args.seed, &scatter, &options, &|done, _, what| {
        bar.set_position(done as u64);
        bar.set_message(what.to_string());
        // Without a terminal (a long run in the background), one line per
        // campaign, so that a run stopped early still tells what it did.
        if !terminal && done > 0 {
            eprintln!("campaign {}/{n}: {what}", done - 1);
        }
    });
    bar.finish_and_clear();
    let (outcomes, failures) = result;
    let summary = blind::summarise(&outcomes);
    let mut doc = blind_json(args, &options, &outcomes, &summary);
    doc["failures"] = failures
        .iter()
        .map(|f| {
            json!({"index": f.index, "seed": f.seed, "truth": f.case.truth.name(), "lambda_target": f.case.lambda,
                   "error": f.error})
        })
        .collect();
    let dir = output.path().to_path_buf();
    write_atomic(dir.join("blind.json"), serde_json::to_string_pretty(&doc)?.as_bytes())?;
    let marker = json!({"command": "diagnose --blind", "campaigns": n, "seed": args.seed});
    write_atomic(dir.join(wagashi_io::atomic::OUTPUT_MARKER_FILE), serde_json::to_string_pretty(&marker)?.as_bytes())?;
    output.commit()?;
    print_blind(&outcomes, &summary, &args.output, out)?;
    for f in &failures {
        writeln!(
            out,
            "campaign {} (seed {}, withheld {} at lambda {}) not scored: {}",
            f.index,
            f.seed,
            f.case.truth.name(),
            f.case.lambda,
            f.error
        )?;
    }
    Ok(())
}

fn rate_json(r: &calibrate::diagnosis::blind::Rate) -> Value {
    json!({"hits": r.hits, "total": r.total, "value": if r.total > 0 { json!(r.value()) } else { Value::Null }})
}

/// A number, or null when not finite (JSON has no NaN).
fn num(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

/// The tie rule's numbers (`calibrate::diagnosis::TieTest`).
fn tie_test_json(t: &calibrate::diagnosis::TieTest) -> Value {
    json!({"runner_up": t.runner_up.id(), "margin": num(t.margin), "se": num(t.se), "se_blocks": num(t.se_blocks),
           "se_segments": num(t.se_segments), "cosine": num(t.cosine)})
}

/// `blind.json` (see [`run_blind`]).
pub fn blind_json(
    args: &DiagnoseArgs,
    options: &DiagnosisOptions,
    outcomes: &[calibrate::diagnosis::blind::Outcome],
    s: &calibrate::diagnosis::blind::BlindSummary,
) -> Value {
    let campaigns: Vec<Value> = outcomes
        .iter()
        .map(|o| {
            let g = &o.generated;
            json!({
                "index": o.index,
                "seed": o.seed,
                "truth": o.case.truth.name(),
                "kind": o.case.truth.kind(),
                "lambda_target": o.case.lambda,
                "lambda_eff": num(g.lambda_eff),
                "lambda_raw": num(g.lambda_raw),
                "lambda_null": num(g.lambda_null),
                "strength_reached": g.reached,
                "strength_evaluations": g.strength_evals,
                "strength": g.strength.iter().map(|(k, v)| (k.clone(), num(*v))).collect::<Map<String, Value>>(),
                "variability": g.variability,
                "sample_scales": g.sample_scales,
                "geometry_errors": g.geometry_errors,
                "force_rho": g.force_rho,
                "force_sigma_hat_N": g.force_sigma_hat_n,
                "force_rho_hat": g.force_rho_hat,
                "verdict": o.label,
                "named": o.named.iter().map(|e| e.id()).collect::<Vec<_>>(),
                "column": o.column,
                "top1": o.top1,
                "closure_hat": o.closure_hat,
                "closure_true": o.closure_true,
                "tie_test": o.tie_test.as_ref().map(tie_test_json),
                "seconds": {"generate": o.generate_s, "diagnose": o.diagnose_s, "score": o.score_s},
            })
        })
        .collect();
    let top1: Map<String, Value> = s.top1.iter().map(|((e, l), r)| (format!("{e} @ {l}"), rate_json(r))).collect();
    let by_lambda: Map<String, Value> = s.top1_by_lambda.iter().map(|(l, r)| (l.to_string(), rate_json(r))).collect();
    let confusion: Map<String, Value> = s
        .confusion
        .iter()
        .map(|(t, row)| (t.clone(), json!(row.iter().map(|(c, n)| (c.clone(), json!(n))).collect::<Map<_, _>>())))
        .collect();
    let targets: Vec<Value> = s
        .targets
        .iter()
        .map(|t| {
            json!({"metric": t.metric, "relation": t.relation, "threshold": t.threshold, "value": num(t.value),
                   "cases": t.cases, "holds": t.holds})
        })
        .collect();
    json!({
        "campaigns_requested": args.blind,
        "seed": args.seed,
        "scatter": if args.blind_ideal_samples { "ideal samples (no variability, no geometry errors)" }
                   else { "variability 3-10 %, geometry errors 0.5 % (the blind set's generator)" },
        "diagnoser": {
            "size_mm": options.size_mm,
            "starts": options.starts,
            "bootstrap": options.bootstrap,
            "tie_bootstrap": format!("{:?}", options.tie_bootstrap).to_lowercase(),
            "marker_sigma_mm": options.marker_sigma_mm,
            "effects": options.effects.as_ref().map(|v| v.iter().map(|e| e.id()).collect::<Vec<_>>()),
        },
        "summary": {
            "top1": top1,
            "top1_by_lambda": by_lambda,
            "false_attribution_on_null": rate_json(&s.false_attribution),
            "any_gap_on_null": rate_json(&s.any_gap_on_null),
            "out_of_library_flagged": rate_json(&s.out_of_library_flagged),
            "closure_errors": s.closure_errors,
            "targets": targets,
            "confusion": confusion,
        },
        "campaigns": campaigns,
    })
}

fn print_blind(
    outcomes: &[calibrate::diagnosis::blind::Outcome],
    s: &calibrate::diagnosis::blind::BlindSummary,
    output: &std::path::Path,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    writeln!(
        out,
        "{:<4} {:<22} {:>7} {:>9} {:<34} {:>7} {:>7} {:>8}",
        "#", "withheld", "lambda", "lam_eff", "verdict", "G_hat", "G_true", "seconds"
    )?;
    for o in outcomes {
        let f = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.2}"));
        writeln!(
            out,
            "{:<4} {:<22} {:>7} {:>9.1} {:<34} {:>7} {:>7} {:>8.1}",
            o.index,
            o.case.truth.name(),
            o.case.lambda,
            o.generated.lambda_eff,
            o.label,
            f(o.closure_hat),
            f(o.closure_true),
            o.generate_s + o.diagnose_s + o.score_s
        )?;
    }
    writeln!(out, "\ntop-1 attribution per effect and lambda:")?;
    for ((e, l), r) in &s.top1 {
        writeln!(out, "  {e:<22} {l:>4}: {}/{}", r.hits, r.total)?;
    }
    let columns: Vec<String> = {
        let mut c: Vec<String> = s.confusion.values().flat_map(|row| row.keys().cloned()).collect();
        c.sort();
        c.dedup();
        c
    };
    writeln!(out, "\nconfusion matrix (rows: withheld; columns: top-1 of the verdict):")?;
    write!(out, "  {:<22}", "")?;
    for c in &columns {
        write!(out, " {:>8}", c.chars().take(8).collect::<String>())?;
    }
    writeln!(out)?;
    for (t, row) in &s.confusion {
        write!(out, "  {t:<22}")?;
        for c in &columns {
            write!(out, " {:>8}", row.get(c).copied().unwrap_or(0))?;
        }
        writeln!(out)?;
    }
    writeln!(out, "\ntargets of the diagnosis:")?;
    for t in &s.targets {
        writeln!(
            out,
            "  {:<62} {} {:.2}: {} ({} cases) {}",
            t.metric,
            t.relation,
            t.threshold,
            if t.value.is_finite() { format!("{:.3}", t.value) } else { "-".into() },
            t.cases,
            if t.cases == 0 {
                "no case"
            } else if t.holds {
                "holds"
            } else {
                "MISSES"
            }
        )?;
    }
    writeln!(out, "wrote {}", output.join("blind.json").display())?;
    Ok(())
}
