//! `wagashi tpa INPUT... [--json] [-o OUT]`: texture-profile analysis of double
//! compressions, measured or simulated.
//!
//! Reading the records and the definitions belong to [`wagashi_io::texture::tpa`]
//! (its docs give them exactly); this module formats the results: a table on
//! stdout (one row per input), or with `--json` a JSON array of objects
//! `{input, hardness_N, cohesiveness, springiness, resilience, gumminess_N,
//! chewiness_N, adhesiveness_N_s}`. With `-o OUT` it also writes the folder OUT
//! atomically ([`AtomicDir`], refused when it exists unless it is a previous
//! wagashi output and `--force` is given):
//!
//! | file           | what                                                            |
//! |----------------|-----------------------------------------------------------------|
//! | `tpa.csv`      | one row per input: the profile, then each stroke's touch, peak, end and areas |
//! | `tpa.svg`      | per input, the force against time with A1..A4 shaded and the split marked |
//! | `summary.json` | the inputs, the options and the profiles                        |
//!
//! Every input is read and analysed before anything is written. `wagashi press`
//! writes the same profile as `tpa.json` for a double compression ([`tpa_json`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context};
use clap::Args;
use plotters::prelude::*;
use serde_json::json;
use wagashi_io::texture::tpa::{DEFAULT_THRESHOLD_N, MAX_SMOOTHING_SAMPLES};
use wagashi_io::texture::{analyse, read_tpa_record, Tpa, TpaOptions, TpaRecord};
use wagashi_io::write_atomic;

const TPA_LONG_ABOUT: &str = "\
Texture-profile analysis (Bourne) of double compressions: hardness, cohesiveness, springiness, \
resilience, gumminess, chewiness and adhesiveness, one row per INPUT.

INPUT is a raw texture-analyser export (a TA Instruments rheometer export when its first line names \
a `Normal force` column, else a Stable Micro Systems Exponent export; tared as `wagashi import` \
tares), an experiment bundle or a `wagashi press` output folder (its force.csv), or a `t_s,force_N` \
CSV file.

Definitions, on the tared force F(t) [N] through its samples:
  contact       F above --threshold-N (0.1 N)
  compression   a contact reaching twice the threshold (shorter excursions are noise)
  strokes       split at the middle of the longest time between two compressions (the probe is \
up between the strokes)
  touch, peak   where F rises through the threshold into a stroke; the sample of the largest force
  A1, A2        positive force-time areas [N s] from touch to peak, and from peak to where F last \
falls through the threshold, in stroke 1; A3, A4 the same in stroke 2
  hardness      peak force of stroke 1 [N]
  cohesiveness  (A3 + A4) / (A1 + A2)
  springiness   t2 / t1, the touch-to-peak times of stroke 2 over stroke 1
  resilience    A2 / A1
  gumminess     hardness x cohesiveness [N]
  chewiness     gumminess x springiness [N]
  adhesiveness  negative force-time area after stroke 1 up to the split [N s]
Smoothing: none unless --smooth-samples S (a Gaussian of S <= 2 samples standard deviation).";

const TPA_AFTER_HELP: &str = "\
Examples:
  # The shared fungi-steak double compressions (rheometer exports), as a table:
  wagashi tpa ../shared/data/real/fungi-steak/double-compression-slowest-inplane-1.txt \\
      ../shared/data/real/fungi-steak/double-compression-slowest-inplane-2.txt

  # A simulated double compression, as JSON, with the plot and the table written to out/tpa:
  wagashi press examples/paper/double-compression -o out/dc
  wagashi tpa out/dc --json -o out/tpa";

/// `wagashi tpa`.
#[derive(Debug, Args)]
#[command(
    about = "Texture-profile analysis of double compressions (hardness, cohesiveness, springiness, ...)",
    long_about = TPA_LONG_ABOUT,
    after_help = TPA_AFTER_HELP
)]
pub struct TpaArgs {
    /// Raw exports, bundles or press output folders; one row each.
    #[arg(value_name = "INPUT", required = true)]
    pub inputs: Vec<PathBuf>,

    /// Print a JSON array (one object per input) instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Also write tpa.csv, tpa.svg and summary.json into this folder.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: Option<PathBuf>,

    /// Replace OUT if it is a previous wagashi output (any other existing folder is never replaced).
    #[arg(long)]
    pub force: bool,

    /// The contact threshold [N]: the force above it is contact.
    #[arg(long = "threshold-N", value_name = "F", default_value_t = DEFAULT_THRESHOLD_N,
          value_parser = crate::press::positive_number, allow_negative_numbers = true)]
    pub threshold_n: f64,

    /// Gaussian smoothing of the force before the analysis [samples, standard deviation, at most 2].
    #[arg(long = "smooth-samples", value_name = "S", default_value_t = 0.0, value_parser = smoothing)]
    pub smooth_samples: f64,
}

fn smoothing(text: &str) -> Result<f64, String> {
    let s: f64 = text.parse().map_err(|_| format!("\"{text}\" is not a number"))?;
    if (0.0..=MAX_SMOOTHING_SAMPLES).contains(&s) {
        Ok(s)
    } else {
        Err(format!("{s} is outside 0..={MAX_SMOOTHING_SAMPLES} samples"))
    }
}

/// One analysed input.
struct Row {
    input: String,
    record: TpaRecord,
    tpa: Tpa,
}

/// `wagashi tpa`.
pub fn run(args: &TpaArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let options = TpaOptions { threshold_n: args.threshold_n, smoothing_samples: args.smooth_samples };
    // Check the output folder first: a bad one fails before the work.
    let output = match &args.output {
        Some(target) => {
            for input in &args.inputs {
                let (i, o) = (crate::press::resolve(input)?, crate::press::resolve(target)?);
                if i.starts_with(&o) || o.starts_with(&i) {
                    bail!(
                        "{}: the output folder may not be, hold or lie inside the input {} (inputs are never modified)",
                        target.display(),
                        input.display()
                    );
                }
            }
            Some(crate::press::prepare_output(&[], target, args.force)?)
        }
        None => None,
    };
    let mut rows = Vec::with_capacity(args.inputs.len());
    for input in &args.inputs {
        let record = read_tpa_record(input)?;
        let tpa = analyse(&record, &options)?;
        rows.push(Row { input: input.display().to_string(), record, tpa });
    }
    if args.json {
        let array: Vec<serde_json::Value> = rows.iter().map(|r| tpa_json(&r.input, &r.tpa)).collect();
        writeln!(out, "{}", serde_json::to_string_pretty(&array)?)?;
    } else {
        write!(out, "{}", table(&rows))?;
    }
    if let (Some(dir), Some(target)) = (output, &args.output) {
        write_atomic(dir.path().join("tpa.csv"), tpa_csv(&rows).as_bytes())?;
        write_atomic(dir.path().join("tpa.svg"), tpa_svg(&rows)?.as_bytes())?;
        let summary = json!({
            "wagashi_version": env!("CARGO_PKG_VERSION"),
            "command": "tpa",
            "output": target.display().to_string(),
            "threshold_N": options.threshold_n,
            "smoothing_samples": options.smoothing_samples,
            "files": ["tpa.csv", "tpa.svg", "summary.json"],
            "profiles": rows.iter().map(|r| tpa_json(&r.input, &r.tpa)).collect::<Vec<_>>(),
        });
        // summary.json marks the folder as a wagashi output: it goes in last.
        let text = serde_json::to_string_pretty(&summary).context("summary.json")?;
        write_atomic(dir.path().join(wagashi_io::atomic::OUTPUT_MARKER_FILE), format!("{text}\n").as_bytes())?;
        dir.commit()?;
        if !args.json {
            writeln!(out, "output  {}", target.display())?;
        }
    }
    Ok(())
}

/// The profile of `input` as the JSON object `wagashi tpa --json` prints (and
/// `press` writes as `tpa.json`): the profile, then each stroke's landmarks.
pub fn tpa_json(input: &str, tpa: &Tpa) -> serde_json::Value {
    json!({
        "input": input,
        "hardness_N": tpa.hardness_n,
        "cohesiveness": tpa.cohesiveness,
        "springiness": tpa.springiness,
        "resilience": tpa.resilience,
        "gumminess_N": tpa.gumminess_n,
        "chewiness_N": tpa.chewiness_n,
        "adhesiveness_N_s": tpa.adhesiveness_n_s,
        "threshold_N": tpa.threshold_n,
        "smoothing_samples": tpa.smoothing_samples,
        "split_s": tpa.split_s,
        "strokes": tpa.strokes,
    })
}

fn table(rows: &[Row]) -> String {
    let width = rows.iter().map(|r| r.input.chars().count()).max().unwrap_or(5).max(5);
    let mut s = format!(
        "{:<width$}  {:>11}  {:>12}  {:>11}  {:>10}  {:>12}  {:>11}  {:>16}\n",
        "input",
        "hardness_N",
        "cohesiveness",
        "springiness",
        "resilience",
        "gumminess_N",
        "chewiness_N",
        "adhesiveness_N_s"
    );
    for r in rows {
        let t = &r.tpa;
        s += &format!(
            "{:<width$}  {:>11.4}  {:>12.4}  {:>11.4}  {:>10.4}  {:>12.4}  {:>11.4}  {:>16.4}\n",
            r.input,
            t.hardness_n,
            t.cohesiveness,
            t.springiness,
            t.resilience,
            t.gumminess_n,
            t.chewiness_n,
            t.adhesiveness_n_s
        );
    }
    s
}

/// The CSV field `text`, quoted when it holds a comma, a quote or a line break.
fn field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

fn tpa_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "input,hardness_N,cohesiveness,springiness,resilience,gumminess_N,chewiness_N,adhesiveness_N_s,split_s,\
         touch1_s,peak1_s,end1_s,A1_N_s,A2_N_s,touch2_s,peak2_s,end2_s,A3_N_s,A4_N_s\n",
    );
    for r in rows {
        let t = &r.tpa;
        let mut cells = vec![
            field(&r.input),
            t.hardness_n.to_string(),
            t.cohesiveness.to_string(),
            t.springiness.to_string(),
            t.resilience.to_string(),
            t.gumminess_n.to_string(),
            t.chewiness_n.to_string(),
            t.adhesiveness_n_s.to_string(),
            t.split_s.to_string(),
        ];
        for k in &t.strokes {
            cells.extend(
                [k.touch_s, k.peak_s, k.end_s, k.area_to_peak_n_s, k.area_after_peak_n_s].map(|x| x.to_string()),
            );
        }
        s += &cells.join(",");
        s.push('\n');
    }
    s
}

/// Colours of A1..A4.
const AREA_COLOURS: [RGBColor; 4] =
    [RGBColor(31, 119, 180), RGBColor(255, 127, 14), RGBColor(44, 160, 44), RGBColor(214, 39, 40)];

/// Panel size per input [px].
const PANEL: (u32, u32) = (900, 420);

/// `tpa.svg`: per input a panel, the force against time with the areas A1..A4
/// shaded, the touches and peaks marked and the split drawn dashed.
fn tpa_svg(rows: &[Row]) -> anyhow::Result<String> {
    let draw_err = |e: DrawingAreaErrorKind<std::io::Error>| anyhow!("drawing tpa.svg: {e}");
    let mut svg = String::new();
    {
        let height = PANEL.1 * rows.len() as u32;
        let root = SVGBackend::with_string(&mut svg, (PANEL.0, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        for (panel, row) in root.split_evenly((rows.len(), 1)).iter().zip(rows) {
            let (t, f) = (&row.record.t_s, &row.record.force_n);
            let tpa = &row.tpa;
            let (t0, t1) = (t[0], t[t.len() - 1].max(t[0] + 1e-9));
            let (lo, hi) = f.iter().fold((0.0f64, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
            let pad = 0.05 * (hi - lo).max(1e-9);
            // The file or folder name: a whole path would not fit beside the values.
            let name = Path::new(&row.input).file_name().map_or(row.input.clone(), |n| n.to_string_lossy().into());
            let caption = format!(
                "{name}: hardness {:.3} N, cohesiveness {:.3}, springiness {:.3}",
                tpa.hardness_n, tpa.cohesiveness, tpa.springiness
            );
            let mut chart = ChartBuilder::on(panel)
                .caption(caption, ("sans-serif", 15))
                .margin(14)
                .x_label_area_size(44)
                .y_label_area_size(64)
                .build_cartesian_2d(t0..t1, (lo - pad)..(hi + pad))
                .map_err(draw_err)?;
            chart
                .configure_mesh()
                .x_desc("time [s]")
                .y_desc("force [N]")
                .bold_line_style(BLACK.mix(0.15))
                .light_line_style(BLACK.mix(0.05))
                .max_light_lines(2)
                .draw()
                .map_err(draw_err)?;
            let bounds = [
                (tpa.strokes[0].touch_s, tpa.strokes[0].peak_s),
                (tpa.strokes[0].peak_s, tpa.strokes[0].end_s),
                (tpa.strokes[1].touch_s, tpa.strokes[1].peak_s),
                (tpa.strokes[1].peak_s, tpa.strokes[1].end_s),
            ];
            for (k, &(a, b)) in bounds.iter().enumerate() {
                let colour = AREA_COLOURS[k];
                chart
                    .draw_series(std::iter::once(Polygon::new(segment(t, f, a, b), colour.mix(0.35).filled())))
                    .map_err(draw_err)?
                    .label(format!("A{}", k + 1))
                    .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], colour.mix(0.35).filled()));
            }
            chart
                .draw_series(LineSeries::new(t.iter().copied().zip(f.iter().copied()), BLACK.stroke_width(2)))
                .map_err(draw_err)?
                .label("force")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(2)));
            let marks = tpa.strokes.iter().flat_map(|s| [(s.touch_s, tpa.threshold_n), (s.peak_s, s.peak_n)]);
            chart.draw_series(marks.map(|p| Circle::new(p, 4, BLACK.filled()))).map_err(draw_err)?;
            let split = DashedLineSeries::new(
                [(tpa.split_s, lo - pad), (tpa.split_s, hi + pad)],
                6,
                4,
                RGBColor(120, 120, 120).stroke_width(1),
            );
            chart
                .draw_series(split)
                .map_err(draw_err)?
                .label("split")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RGBColor(120, 120, 120)));
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.9))
                .border_style(BLACK)
                .draw()
                .map_err(draw_err)?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(svg)
}

/// The outline of the area under the curve through `(t, f)` from `a` to `b`:
/// the curve (its ends interpolated, negative forces cut to zero: the areas are
/// of the positive force) closed along the time axis.
fn segment(t: &[f64], f: &[f64], a: f64, b: f64) -> Vec<(f64, f64)> {
    let at = |x: f64| {
        let i = t.partition_point(|&s| s < x).clamp(1, t.len() - 1);
        let w = ((x - t[i - 1]) / (t[i] - t[i - 1])).clamp(0.0, 1.0);
        f[i - 1] + w * (f[i] - f[i - 1])
    };
    let mut points = vec![(a, 0.0), (a, at(a).max(0.0))];
    points.extend(t.iter().zip(f).filter(|(&s, _)| s > a && s < b).map(|(&s, &y)| (s, y.max(0.0))));
    points.extend([(b, at(b).max(0.0)), (b, 0.0)]);
    points
}

/// Whether the waypoints `[t_s, d_mm]` (plate displacement, down positive) load
/// twice: two pushes separated by a rise.
pub fn is_double_compression(waypoints: &[[f64; 2]]) -> bool {
    let mut pushes = 0;
    let mut rising = false; // the last movement was a push (d increasing)
    for w in waypoints.windows(2) {
        let dd = w[1][1] - w[0][1];
        if dd > 0.0 && !rising {
            pushes += 1;
            rising = true;
        } else if dd < 0.0 {
            rising = false;
        }
    }
    pushes >= 2
}

/// The analysis of a simulated `force` as `OUT/force.csv` holds it, for
/// `press`'s `tpa.json`.
pub fn simulated_tpa(file: &Path, force: &wagashi_io::ForceSeries) -> Result<Tpa, wagashi_io::texture::TpaError> {
    let record = TpaRecord {
        file: file.to_path_buf(),
        force_column: "force_N".into(),
        t_s: force.samples.iter().map(|s| s.t_s).collect(),
        force_n: force.samples.iter().map(|s| s.force_n).collect(),
        lines: (0..force.samples.len()).map(|i| i + 2).collect(),
    };
    analyse(&record, &TpaOptions::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_compressions_are_told_from_single_ones() {
        assert!(is_double_compression(&[
            [0.0, 0.0],
            [10.0, 2.0],
            [10.5, -0.5],
            [15.0, -0.5],
            [27.5, 2.0],
            [28.0, -0.5]
        ]));
        assert!(!is_double_compression(&[[0.0, 0.0], [10.0, 2.0], [40.0, 2.0], [41.0, 0.0]]));
        // A push held at its depth and pushed further is one stroke.
        assert!(!is_double_compression(&[[0.0, 0.0], [10.0, 1.0], [20.0, 1.0], [30.0, 2.0]]));
    }

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(field("a,b"), "\"a,b\"");
        assert_eq!(field("plain"), "plain");
    }
}
