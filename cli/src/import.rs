//! `wagashi import exponent|rheometer FILE... -o OUT_DIR`: raw texture-analyser
//! exports into experiment bundles.
//!
//! Reading, detection and the bundle belong to [`wagashi_io::texture`] (its docs
//! give the formats and the rules); this module maps the flags to
//! [`ImportOptions`], checks the output folders and writes one bundle folder per
//! input file, `OUT_DIR/STEM/`, each atomically ([`AtomicDir`]):
//!
//! | file              | what                                                             |
//! |-------------------|------------------------------------------------------------------|
//! | `experiment.toml` | cylinder, plate, waypoints, release and end; `[extra.import]` the detected facts |
//! | `force.csv`       | `t_s,force_N`: the tared force from first touch                  |
//! | `summary.json`    | the input, the output and the detected facts                     |
//!
//! Every input is read and converted before anything is written: one bad file
//! writes nothing. An existing `OUT_DIR/STEM` is replaced only with `--force` and
//! only if it is a previous wagashi output (it holds `summary.json`). Inputs are
//! never modified.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};

use crate::press::positive_number;
use clap::{ArgGroup, Args, Subcommand, ValueEnum};
use serde::Serialize;
use wagashi_io::bundle::{Contact, Model};
use wagashi_io::texture::{
    read_exponent, read_rheometer, to_bundle, HeightSource, ImportFacts, ImportOptions, ImportedTrial, RawFormat,
    StrokeChoice,
};
use wagashi_io::{write_atomic, AtomicDir};

const IMPORT_AFTER_HELP: &str = "\
Examples (the shared test data, from the repository root):
  # Stroke 1 of the fungi-steak double compressions (cylinders punched to 8 mm; height = the gap at touch):
  wagashi import rheometer ../shared/data/real/fungi-steak/double-compression-slowest-inplane-1.txt \\
      ../shared/data/real/fungi-steak/double-compression-slowest-inplane-2.txt --cylinder-radius-mm 4 -o bundles/fungi

  # The second stroke of specimen 1 (times still from the first touch), frictionless plates:
  wagashi import rheometer ../shared/data/real/fungi-steak/double-compression-slowest-inplane-1.txt \\
      --cylinder-radius-mm 4 --stroke 2 --contact frictionless -o bundles/fungi-stroke2

  # A CMC gel on an Exponent texture analyser (5 mm gel, probe started 2.5 mm above the support):
  wagashi import exponent ../shared/data/real/cmc-gel/sampleGel.tab --cylinder-radius-mm 2.5 \\
      --start-height-mm 2.5 --every 10 -o bundles/gel

Then simulate one with a material: wagashi press bundles/fungi/double-compression-slowest-inplane-1 --materials M.toml -o out/f1";

/// `wagashi import`.
#[derive(Debug, Args)]
#[command(
    about = "Turn texture-analyser raw exports into experiment bundles",
    long_about = "Turn raw exports of a texture analyser into experiment bundles, one folder per input \
file (OUT_DIR/STEM): first touch, tare and noise are detected from the force, the tool's trajectory \
from first touch is read from its position (waypoints), the specimen is a cylinder. See `wagashi \
import exponent --help` and `wagashi import rheometer --help`.",
    after_help = IMPORT_AFTER_HELP
)]
pub struct ImportArgs {
    #[command(subcommand)]
    pub kind: ImportKind,
}

/// The instrument export.
#[derive(Debug, Subcommand)]
pub enum ImportKind {
    /// Stable Micro Systems Exponent text (Force g, Distance mm, Time sec after a name line)
    #[command(
        long_about = "Stable Micro Systems Exponent text exports: a name line, the column names \
`Force Distance Time`, their units `g mm sec`, then tab-separated rows. Distance is the probe's \
travel from where the test started, so the height must be given (--height-mm) or derived from the \
probe's start height above the support (--start-height-mm minus the travel to first touch).",
        after_help = IMPORT_AFTER_HELP
    )]
    Exponent(ExponentArgs),
    /// TA Instruments rheometer text (Time (s), Normal force (N), Gap (um), tab-separated)
    #[command(
        long_about = "TA Instruments rheometer text exports: one header line of tab-separated \
`NAME (UNIT)` columns among which Time (s), Normal force (N) and Gap (um), then rows. The height is \
the gap at first touch unless --height-mm or --start-height-mm is given.",
        after_help = IMPORT_AFTER_HELP
    )]
    Rheometer(RheometerArgs),
}

/// `wagashi import exponent`.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("height").required(true).args(["height_mm", "start_height_mm"])))]
pub struct ExponentArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// The specimen's height [mm].
    #[arg(long = "height-mm", value_name = "H", value_parser = positive_number, allow_negative_numbers = true)]
    pub height_mm: Option<f64>,
    /// The probe's height above the support at the file's first row [mm]; the
    /// specimen's height is this minus the probe's travel to first touch.
    #[arg(long = "start-height-mm", value_name = "S", value_parser = positive_number, allow_negative_numbers = true)]
    pub start_height_mm: Option<f64>,
}

/// `wagashi import rheometer`.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("height").required(false).args(["height_mm", "start_height_mm"])))]
pub struct RheometerArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// The specimen's height [mm]; default: the gap at first touch.
    #[arg(long = "height-mm", value_name = "H", value_parser = positive_number, allow_negative_numbers = true)]
    pub height_mm: Option<f64>,
    /// The upper plate's height above the lower at the file's first row [mm];
    /// the specimen's height is this minus the plate's travel to first touch.
    #[arg(long = "start-height-mm", value_name = "S", value_parser = positive_number, allow_negative_numbers = true)]
    pub start_height_mm: Option<f64>,
}

/// The flags both formats take.
#[derive(Debug, Args)]
pub struct CommonArgs {
    /// The raw files; each becomes the bundle OUT_DIR/STEM (STEM: the file name without its extension).
    #[arg(value_name = "FILE", required = true)]
    pub files: Vec<PathBuf>,

    /// The folder to write the bundles into (created if missing).
    #[arg(short = 'o', long = "output", value_name = "OUT_DIR")]
    pub output: PathBuf,

    /// The cylindrical specimen's radius [mm].
    #[arg(long = "cylinder-radius-mm", value_name = "R", value_parser = positive_number, allow_negative_numbers = true)]
    pub radius_mm: f64,

    /// The specimen's material name ([specimen] material); define it with
    /// `wagashi press --materials FILE` or fit it.
    #[arg(long, value_name = "NAME", default_value = "sample")]
    pub material: String,

    /// The material's rheological model, written as a [materials.NAME] table with
    /// the model only (every parameter an unknown for `wagashi fit`); `none` writes
    /// no table (give one with --materials).
    #[arg(long, value_enum, default_value_t = ModelArg::FiveElement)]
    pub model: ModelArg,

    /// How the plate and the support hold the specimen (tool_contact and support).
    /// Default: glued for --stroke 1 and 2 (the food sticks to the plates in these
    /// tests, and the plates' friction is not known); frictionless for --stroke
    /// all, whose plate leaves the specimen between the strokes and touches it
    /// again (a glued plate would pull it back up).
    #[arg(long, value_enum)]
    pub contact: Option<ContactArg>,

    /// Which part of the test: 1 (first touch to the end of the first unloading),
    /// 2 (the second stroke's window, times from the first touch) or all (the
    /// whole test; the engine needs contact to simulate a double compression).
    #[arg(long, value_enum, default_value_t = StrokeArg::One)]
    pub stroke: StrokeArg,

    /// Write every N-th force row (and the window's last); default: every row.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub every: u32,

    /// Replace an OUT_DIR/STEM that holds a previous wagashi output (a folder
    /// whose wagashi-manifest.json lists every file in it; only those files are
    /// removed); any other existing folder is never replaced.
    #[arg(long)]
    pub force: bool,
}

/// `--contact`.
/// `--model`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelArg {
    /// The seed's five-element chain.
    FiveElement,
    /// Spring + Voigt + dashpot.
    FourElement,
    /// Voigt + dashpot.
    ThreeElement,
    /// Hookean solid.
    Elastic,
    /// The finite-strain network, in its default structure: an exponential
    /// equilibrium network with Ogden-Roxburgh softening, two viscous networks
    /// and a damper (every parameter unknown; `beta` of the softening held at 0).
    Network,
    /// No [materials] table.
    None,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ContactArg {
    /// No slip on the plate or the support (default).
    Glued,
    /// Free sliding on both.
    Frictionless,
}

/// `--stroke`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StrokeArg {
    /// The first stroke (default).
    #[value(name = "1")]
    One,
    /// The second stroke.
    #[value(name = "2")]
    Two,
    /// The whole test.
    All,
}

/// What `summary.json` of an imported bundle holds (it also marks the folder as
/// a wagashi output that `--force` may replace).
#[derive(Debug, Serialize)]
struct ImportSummary<'a> {
    wagashi_version: &'static str,
    command: &'static str,
    input: String,
    output: String,
    #[serde(rename = "import")]
    facts: &'a ImportFacts,
}

/// One input and where it goes.
struct Job {
    input: PathBuf,
    target: PathBuf,
    trial: ImportedTrial,
}

/// `wagashi import`.
pub fn run(args: &ImportArgs) -> anyhow::Result<()> {
    let (format, common, height) = match &args.kind {
        ImportKind::Exponent(a) => (RawFormat::Exponent, &a.common, height_source(a.height_mm, a.start_height_mm)),
        ImportKind::Rheometer(a) => (RawFormat::Rheometer, &a.common, height_source(a.height_mm, a.start_height_mm)),
    };
    let targets = targets(&common.files, &common.output)?;

    // Read and convert every input before writing anything.
    let mut jobs = Vec::with_capacity(targets.len());
    for (input, (stem, target)) in common.files.iter().zip(targets) {
        let raw = match format {
            RawFormat::Exponent => read_exponent(input)?,
            RawFormat::Rheometer => read_rheometer(input)?,
        };
        let options = ImportOptions {
            name: stem,
            radius_mm: common.radius_mm,
            height,
            material: common.material.clone(),
            model: match common.model {
                ModelArg::FiveElement => Some(Model::FiveElement),
                ModelArg::FourElement => Some(Model::FourElement),
                ModelArg::ThreeElement => Some(Model::ThreeElement),
                ModelArg::Elastic => Some(Model::Elastic),
                ModelArg::Network => Some(Model::Network),
                ModelArg::None => None,
            },
            contact: match common.contact {
                Some(ContactArg::Glued) => Contact::Glued,
                Some(ContactArg::Frictionless) => Contact::Frictionless,
                None if common.stroke == StrokeArg::All => Contact::Frictionless,
                None => Contact::Glued,
            },
            stroke: match common.stroke {
                StrokeArg::One => StrokeChoice::First,
                StrokeArg::Two => StrokeChoice::Second,
                StrokeArg::All => StrokeChoice::All,
            },
            every: common.every as usize,
        };
        let trial = to_bundle(&raw, &options)?;
        jobs.push(Job { input: input.clone(), target, trial });
    }

    // Check every output folder, then build them aside and move them into place.
    let mut outputs = Vec::with_capacity(jobs.len());
    for job in &jobs {
        outputs.push(prepare_output(&job.input, &job.target, common.force)?);
    }
    for (job, out) in jobs.iter().zip(&outputs) {
        job.trial.write(out.path())?;
        let summary = ImportSummary {
            wagashi_version: env!("CARGO_PKG_VERSION"),
            command: "import",
            input: job.input.display().to_string(),
            output: job.target.display().to_string(),
            facts: &job.trial.facts,
        };
        let json = serde_json::to_string_pretty(&summary).context("summary.json")?;
        write_atomic(out.path().join(wagashi_io::atomic::OUTPUT_MARKER_FILE), format!("{json}\n").as_bytes())?;
    }
    for (job, out) in jobs.iter().zip(outputs) {
        let written = out.commit()?;
        eprintln!("{}", summary_line(&job.input, &job.trial, &written));
    }
    Ok(())
}

fn height_source(height_mm: Option<f64>, start_height_mm: Option<f64>) -> HeightSource {
    match (height_mm, start_height_mm) {
        (Some(h), _) => HeightSource::Given(h),
        (None, Some(s)) => HeightSource::StartHeight(s),
        (None, None) => HeightSource::GapAtTouch,
    }
}

/// `(STEM, OUT_DIR/STEM)` for each input; two inputs of one stem are refused.
fn targets(files: &[PathBuf], output: &Path) -> anyhow::Result<Vec<(String, PathBuf)>> {
    let mut out: Vec<(String, PathBuf)> = Vec::with_capacity(files.len());
    for file in files {
        let Some(stem) = file.file_stem().map(|s| s.to_string_lossy().into_owned()).filter(|s| !s.is_empty()) else {
            bail!("{}: not a file name", file.display());
        };
        if let Some(j) = out.iter().position(|(s, _)| *s == stem) {
            bail!(
                "{} and {} would both be written to {}: import them into different folders",
                files[j].display(),
                file.display(),
                output.join(&stem).display()
            );
        }
        out.push((stem.clone(), output.join(stem)));
    }
    Ok(out)
}

/// Checks `target` and starts building it: refused when it would hold `input`,
/// when it is a previous output and `replace` is not set, and (by [`AtomicDir`])
/// when it is any other existing, non-empty folder or a file.
fn prepare_output(input: &Path, target: &Path, replace: bool) -> anyhow::Result<AtomicDir> {
    if crate::press::resolve(input)?.starts_with(crate::press::resolve(target)?) {
        bail!(
            "{}: the output folder may not hold the input {} (inputs are never modified)",
            target.display(),
            input.display()
        );
    }
    if wagashi_io::atomic::is_previous_output(target) && !replace {
        bail!("{}: exists (a previous wagashi output); pass --force to replace it", target.display());
    }
    let dir = AtomicDir::new(target)?;
    crate::press::report_stale(&dir);
    Ok(dir)
}

/// One line per imported file, for stderr.
fn summary_line(input: &Path, trial: &ImportedTrial, written: &Path) -> String {
    let f = &trial.facts;
    let p = &trial.experiment.protocol;
    let speed = f.speed_mm_s.map_or(String::new(), |v| format!(", {v:.4} mm/s"));
    format!(
        "{}: touch at {:.3} s (line {}), height {:.3} mm ({}), tare {:.4} N, peak {:.4} N at {:.2} s{speed}, \
         {} waypoints, release {:.2} s, end {:.2} s -> {}",
        input.display(),
        f.touch_raw_s,
        f.touch_line,
        f.height_mm,
        f.height_source,
        f.tare_n,
        f.peak_force_n,
        f.peak_force_s,
        p.waypoints.len(),
        p.release_s,
        p.end_s,
        written.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_are_named_after_the_stems_and_unique() {
        let files = [PathBuf::from("a/x.txt"), PathBuf::from("b/y.tab")];
        let t = targets(&files, Path::new("out")).unwrap();
        assert_eq!(t, vec![("x".into(), PathBuf::from("out/x")), ("y".into(), PathBuf::from("out/y"))]);
        let e = targets(&[PathBuf::from("a/x.txt"), PathBuf::from("b/x.tab")], Path::new("out")).unwrap_err();
        assert!(e.to_string().contains("would both be written to out/x"), "{e}");
    }

    #[test]
    fn heights_from_the_flags() {
        assert_eq!(height_source(Some(2.0), None), HeightSource::Given(2.0));
        assert_eq!(height_source(None, Some(3.0)), HeightSource::StartHeight(3.0));
        assert_eq!(height_source(None, None), HeightSource::GapAtTouch);
    }
}
