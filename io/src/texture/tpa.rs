//! Texture-profile analysis (TPA) of a double compression (Bourne 1978; Friedman,
//! Whitney & Szczesniak 1963): the force-time record of two compressions of one
//! specimen, reduced to the numbers every texture analyser reports.
//!
//! # Definitions
//!
//! All on the tared force `F(t)` [N], compression positive, taken as the
//! piecewise-linear curve through its samples (areas are exact integrals of it,
//! crossing times are interpolated between the two samples around a crossing):
//!
//! - **Contact**: `F > threshold` (default [`DEFAULT_THRESHOLD_N`] = 0.1 N).
//! - **Compressions**: the contacts (runs of samples above the threshold) whose
//!   force reaches twice the threshold; shorter excursions above it are noise
//!   around the threshold and are ignored.
//! - **Strokes**: the record splits at the middle of the longest time between
//!   two compressions (from where the force falls through the threshold to where
//!   it rises through it again): the probe is up between the two strokes. Stroke
//!   1 is before the split, stroke 2 after. A record of one compression is
//!   refused ("no second stroke").
//! - In stroke `k`: the touch `t_touch` is where `F` rises through the threshold
//!   into its first compression, the peak `t_peak` the sample of the largest
//!   force, the end `t_end` where `F` falls through the threshold out of its
//!   last compression.
//! - **Areas** [N s]: `A1 = int_{t_touch}^{t_peak} F+ dt` and
//!   `A2 = int_{t_peak}^{t_end} F+ dt` in stroke 1 (`F+ = max(F, 0)`), `A3`, `A4`
//!   the same in stroke 2.
//! - **Hardness** [N]: the peak force of stroke 1.
//! - **Cohesiveness**: `(A3 + A4) / (A1 + A2)`.
//! - **Springiness**: `t2 / t1`, the touch-to-peak times `t_peak - t_touch` of
//!   stroke 2 over stroke 1 (at a constant probe speed, the ratio of the
//!   distances the probe pushes the specimen).
//! - **Resilience**: `A2 / A1`.
//! - **Gumminess** [N]: hardness x cohesiveness.
//! - **Chewiness** [N]: gumminess x springiness.
//! - **Adhesiveness** [N s]: the negative area after stroke 1's end up to the
//!   split, `int_{t_end}^{t_split} max(-F, 0) dt` (the pull on the probe as it
//!   leaves a sticky specimen; zero when the force never goes negative).
//!
//! **Smoothing**: none by default. [`TpaOptions::smoothing_samples`] = `s` in
//! `0..=2` convolves the force with a Gaussian of standard deviation `s`
//! samples (truncated at `3 s`, renormalised at the record's ends) before
//! anything is measured; it lowers a sharp peak, so the hardness of a smoothed
//! record is below its largest sample.
//!
//! # Inputs
//!
//! [`read_tpa_record`] reads a record from a raw texture-analyser export (a
//! TA Instruments rheometer export when its first line names a `Normal force`
//! column, else a Stable Micro Systems Exponent export; read by
//! [`super::read_rheometer`] / [`super::read_exponent`] and tared by
//! [`super::detect_touch`], as `wagashi import` does), an experiment bundle or a
//! `wagashi press` output folder (its force file, `force.csv` unless `[data]
//! force` names another; tared by [`super::detect_touch`] only when `[data]
//! force_tared = false`), or a `t_s,force_N` CSV file. Every refusal names the
//! file, the line and the field.

use std::path::{Component, Path, PathBuf};

use serde::Serialize;
use thiserror::Error;

use super::error::ImportError;
use super::{detect_touch, read_exponent, read_rheometer};
use crate::bundle::read_force;
use crate::error::BundleError;

/// The default contact threshold [N].
pub const DEFAULT_THRESHOLD_N: f64 = 0.1;
/// The largest Gaussian smoothing allowed [samples].
pub const MAX_SMOOTHING_SAMPLES: f64 = 2.0;
/// A stroke's force must reach this many thresholds to count as a compression.
pub const STROKE_PEAK_THRESHOLDS: f64 = 2.0;

/// Why a record could not be read or analysed.
#[derive(Debug, Error)]
pub enum TpaError {
    /// A raw export that could not be read or was refused.
    #[error(transparent)]
    Import(#[from] ImportError),
    /// A bundle's force file that could not be read or was refused.
    #[error(transparent)]
    Bundle(#[from] BundleError),
    /// A record the analysis cannot use: no contact, no second stroke, bad options.
    #[error("{}:{line}: {field}: {cause}", file.display())]
    Invalid {
        /// The file the samples came from.
        file: PathBuf,
        /// 1-based line of the file (of the sample concerned; 1 for the file as a whole).
        line: usize,
        /// The column or option concerned.
        field: String,
        /// What is wrong.
        cause: String,
    },
}

/// A force-time record to analyse.
#[derive(Debug, Clone, PartialEq)]
pub struct TpaRecord {
    /// The file the samples came from (named in messages).
    pub file: PathBuf,
    /// The force column as the file names it (named in messages).
    pub force_column: String,
    /// Time of each sample [s], strictly increasing.
    pub t_s: Vec<f64>,
    /// Tared force of each sample [N], compression positive.
    pub force_n: Vec<f64>,
    /// 1-based line of each sample in the file.
    pub lines: Vec<usize>,
}

/// How to analyse a record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TpaOptions {
    /// Contact threshold [N]; default [`DEFAULT_THRESHOLD_N`].
    pub threshold_n: f64,
    /// Standard deviation of the Gaussian smoothing [samples], `0..=2`; default 0 (none).
    pub smoothing_samples: f64,
}

impl Default for TpaOptions {
    fn default() -> Self {
        Self { threshold_n: DEFAULT_THRESHOLD_N, smoothing_samples: 0.0 }
    }
}

/// The landmarks and areas of one stroke.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TpaStroke {
    /// Where the force first rises through the threshold [s].
    pub touch_s: f64,
    /// The sample of the largest force [s].
    pub peak_s: f64,
    /// The largest force [N].
    #[serde(rename = "peak_N")]
    pub peak_n: f64,
    /// Where the force last falls through the threshold [s].
    pub end_s: f64,
    /// Positive force-time area from touch to peak [N s] (A1 or A3).
    #[serde(rename = "area_to_peak_N_s")]
    pub area_to_peak_n_s: f64,
    /// Positive force-time area from peak to end [N s] (A2 or A4).
    #[serde(rename = "area_after_peak_N_s")]
    pub area_after_peak_n_s: f64,
}

/// The texture profile of a double compression (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tpa {
    /// Peak force of stroke 1 [N].
    #[serde(rename = "hardness_N")]
    pub hardness_n: f64,
    /// `(A3 + A4) / (A1 + A2)`.
    pub cohesiveness: f64,
    /// `t2 / t1` (touch-to-peak times).
    pub springiness: f64,
    /// `A2 / A1`.
    pub resilience: f64,
    /// Hardness x cohesiveness [N].
    #[serde(rename = "gumminess_N")]
    pub gumminess_n: f64,
    /// Gumminess x springiness [N].
    #[serde(rename = "chewiness_N")]
    pub chewiness_n: f64,
    /// Negative area between stroke 1's end and the split [N s].
    #[serde(rename = "adhesiveness_N_s")]
    pub adhesiveness_n_s: f64,
    /// The time splitting the strokes [s].
    pub split_s: f64,
    /// The contact threshold used [N].
    #[serde(rename = "threshold_N")]
    pub threshold_n: f64,
    /// The Gaussian smoothing used [samples].
    pub smoothing_samples: f64,
    /// Stroke 1 and stroke 2.
    pub strokes: [TpaStroke; 2],
}

impl TpaRecord {
    fn invalid(&self, sample: Option<usize>, field: &str, cause: String) -> TpaError {
        let line = sample.and_then(|i| self.lines.get(i).copied()).unwrap_or(1);
        TpaError::Invalid { file: self.file.clone(), line, field: field.to_string(), cause }
    }
}

/// Analyses a double compression (see the module docs for the definitions).
pub fn analyse(record: &TpaRecord, options: &TpaOptions) -> Result<Tpa, TpaError> {
    let threshold = options.threshold_n;
    if !(threshold.is_finite() && threshold > 0.0) {
        return Err(record.invalid(None, "threshold_N", format!("{threshold} is not a positive force")));
    }
    let sigma = options.smoothing_samples;
    if !(0.0..=MAX_SMOOTHING_SAMPLES).contains(&sigma) {
        return Err(record.invalid(
            None,
            "smoothing_samples",
            format!("{sigma} is outside 0..={MAX_SMOOTHING_SAMPLES} samples"),
        ));
    }
    let (t, raw) = (&record.t_s, &record.force_n);
    if t.len() != raw.len() || t.len() != record.lines.len() {
        return Err(record.invalid(None, "row", "times, forces and lines differ in number".into()));
    }
    for i in 0..t.len() {
        if !t[i].is_finite() || !raw[i].is_finite() {
            return Err(record.invalid(Some(i), &record.force_column, "not a finite number".into()));
        }
        if i > 0 && t[i] <= t[i - 1] {
            return Err(record.invalid(Some(i), "t_s", format!("time {} s does not increase", t[i])));
        }
    }
    let f = gaussian(raw, sigma);
    let column = record.force_column.as_str();
    // Contacts: runs of samples above the threshold (first and last index).
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for (i, &x) in f.iter().enumerate() {
        if x > threshold {
            match runs.last_mut() {
                Some(run) if run.1 + 1 == i => run.1 = i,
                _ => runs.push((i, i)),
            }
        }
    }
    // Compressions: the contacts that reach STROKE_PEAK_THRESHOLDS thresholds;
    // the others are noise around the threshold.
    let strong = STROKE_PEAK_THRESHOLDS * threshold;
    let kept: Vec<(usize, usize)> =
        runs.iter().copied().filter(|&(a, b)| f[a..=b].iter().any(|&x| x >= strong)).collect();
    if kept.is_empty() {
        let peak = argmax(&f, 0..f.len());
        return Err(record.invalid(
            peak,
            column,
            format!(
                "no contact: the force never rises to {strong} N, {STROKE_PEAK_THRESHOLDS} times the threshold \
                 {threshold} N (largest {:.4} N, here)",
                peak.map_or(f64::NAN, |i| f[i])
            ),
        ));
    }
    // The longest stretch between two compressions: the probe is up.
    let Some(k) = (0..kept.len() - 1).max_by(|&x, &y| {
        let gap = |k: usize| t[kept[k + 1].0] - t[kept[k].1];
        gap(x).total_cmp(&gap(y)).then(y.cmp(&x))
    }) else {
        return Err(record.invalid(
            Some(kept[0].1),
            column,
            format!(
                "no second stroke: one compression only (a contact above the threshold {threshold} N reaching \
                 {strong} N; it ends here)"
            ),
        ));
    };
    let (first, a, b, last) = (kept[0].0, kept[k].1, kept[k + 1].0, kept[kept.len() - 1].1);
    let end1 = crossing(t, &f, a, threshold);
    let touch2 = crossing(t, &f, b - 1, threshold);
    let split_s = 0.5 * (end1 + touch2);
    let peak1 = argmax(&f, first..a + 1).unwrap_or(first);
    let peak2 = argmax(&f, b..last + 1).unwrap_or(b);
    let touch1 = if first == 0 { t[0] } else { crossing(t, &f, first - 1, threshold) };
    let end2 = if last + 1 < f.len() { crossing(t, &f, last, threshold) } else { t[last] };
    let stroke = |touch: f64, peak: usize, end: f64| TpaStroke {
        touch_s: touch,
        peak_s: t[peak],
        peak_n: f[peak],
        end_s: end,
        area_to_peak_n_s: area(t, &f, touch, t[peak], 1.0),
        area_after_peak_n_s: area(t, &f, t[peak], end, 1.0),
    };
    let s1 = stroke(touch1, peak1, end1);
    let s2 = stroke(touch2, peak2, end2);
    let hardness_n = s1.peak_n;
    let cohesiveness = (s2.area_to_peak_n_s + s2.area_after_peak_n_s) / (s1.area_to_peak_n_s + s1.area_after_peak_n_s);
    let t1 = s1.peak_s - s1.touch_s;
    let t2 = s2.peak_s - s2.touch_s;
    if !(t1 > 0.0 && s1.area_to_peak_n_s > 0.0) {
        return Err(record.invalid(
            Some(peak1),
            column,
            "the first stroke peaks at its touch: no loading to measure (springiness and resilience need one)".into(),
        ));
    }
    let springiness = t2 / t1;
    let resilience = s1.area_after_peak_n_s / s1.area_to_peak_n_s;
    let gumminess_n = hardness_n * cohesiveness;
    Ok(Tpa {
        hardness_n,
        cohesiveness,
        springiness,
        resilience,
        gumminess_n,
        chewiness_n: gumminess_n * springiness,
        adhesiveness_n_s: area(t, &f, end1, split_s, -1.0),
        split_s,
        threshold_n: threshold,
        smoothing_samples: sigma,
        strokes: [s1, s2],
    })
}

/// The index of the largest value of `f` in `range` (the first of equals).
fn argmax(f: &[f64], range: std::ops::Range<usize>) -> Option<usize> {
    range.reduce(|best, i| if f[i] > f[best] { i } else { best })
}

/// Where the straight line from sample `i` to `i + 1` crosses `level` [s]
/// (`f[i]` and `f[i + 1]` on either side of it).
fn crossing(t: &[f64], f: &[f64], i: usize, level: f64) -> f64 {
    let (f0, f1) = (f[i], f[i + 1]);
    if f1 == f0 {
        return t[i];
    }
    let w = ((level - f0) / (f1 - f0)).clamp(0.0, 1.0);
    t[i] + w * (t[i + 1] - t[i])
}

/// `int_{ta}^{tb} max(sign F, 0) dt` over the piecewise-linear curve [N s]:
/// the positive area for `sign = 1`, the negative one (as a positive number)
/// for `sign = -1`.
fn area(t: &[f64], f: &[f64], ta: f64, tb: f64, sign: f64) -> f64 {
    let value = |i: usize, x: f64| {
        let w = if t[i + 1] > t[i] { (x - t[i]) / (t[i + 1] - t[i]) } else { 0.0 };
        sign * (f[i] + w * (f[i + 1] - f[i]))
    };
    let mut total = 0.0;
    for i in 0..t.len().saturating_sub(1) {
        let (x0, x1) = (t[i].max(ta), t[i + 1].min(tb));
        if x1 <= x0 {
            continue;
        }
        let (y0, y1) = (value(i, x0), value(i, x1));
        let dx = x1 - x0;
        total += if y0 >= 0.0 && y1 >= 0.0 {
            0.5 * (y0 + y1) * dx
        } else if y0 <= 0.0 && y1 <= 0.0 {
            0.0
        } else {
            // One end positive: the triangle above zero.
            let top = y0.max(y1);
            0.5 * top * top / (y0 - y1).abs() * dx
        };
    }
    total
}

/// `f` convolved with a Gaussian of standard deviation `sigma` samples,
/// truncated at `3 sigma` and renormalised where it reaches past the ends;
/// `f` itself for `sigma = 0`.
fn gaussian(f: &[f64], sigma: f64) -> Vec<f64> {
    if sigma == 0.0 {
        return f.to_vec();
    }
    let radius = (3.0 * sigma).ceil() as isize;
    let weights: Vec<f64> = (-radius..=radius).map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp()).collect();
    let n = f.len() as isize;
    (0..n)
        .map(|i| {
            let (mut sum, mut norm) = (0.0, 0.0);
            for (w, k) in weights.iter().zip(-radius..=radius) {
                let j = i + k;
                if (0..n).contains(&j) {
                    sum += w * f[j as usize];
                    norm += w;
                }
            }
            sum / norm
        })
        .collect()
}

/// Reads the record of `path`: a raw export, a bundle or press output folder
/// (or its `experiment.toml`), or a `t_s,force_N` CSV file (see the module docs).
pub fn read_tpa_record(path: &Path) -> Result<TpaRecord, TpaError> {
    let is_experiment = path.file_name().is_some_and(|n| n == crate::bundle::EXPERIMENT_FILE);
    if path.is_dir() || (is_experiment && path.is_file()) {
        let dir = if path.is_dir() { path } else { path.parent().unwrap_or(Path::new(".")) };
        return read_bundle_force(dir);
    }
    let text = super::raw_test::read_text(path)?;
    let first_line = text.lines().next().unwrap_or("");
    if first_line.trim_start_matches('\u{feff}').starts_with("t_s,force_N") {
        return csv_record(path, false);
    }
    let raw = if first_line.to_ascii_lowercase().contains("normal force") {
        read_rheometer(path)?
    } else {
        read_exponent(path)?
    };
    let force: Vec<f64> = raw.samples.iter().map(|s| s.force_n).collect();
    let tare = detect_touch(&force)
        .map_err(|why| TpaError::Invalid {
            file: path.to_path_buf(),
            line: raw.samples.first().map_or(1, |s| s.line),
            field: raw.format.force_column().to_string(),
            cause: format!("no tare: {}", no_touch_cause(why)),
        })?
        .tare;
    Ok(TpaRecord {
        file: path.to_path_buf(),
        force_column: raw.format.force_column().to_string(),
        t_s: raw.samples.iter().map(|s| s.t_s).collect(),
        force_n: force.iter().map(|f| f - tare).collect(),
        lines: raw.samples.iter().map(|s| s.line).collect(),
    })
}

fn no_touch_cause(why: super::NoTouch) -> String {
    match why {
        super::NoTouch::TooShort { samples, needed } => format!("{samples} samples; at least {needed} needed"),
        super::NoTouch::NoRise { level, threshold, .. } => {
            format!("the force never rises {threshold:.4} above its level {level:.4} (no contact)")
        }
        super::NoTouch::NoPreContact { .. } => {
            "the force is above its noise from the first rows on (no quiet segment to tare from)".into()
        }
    }
}

/// The force of a bundle or press output folder.
fn read_bundle_force(dir: &Path) -> Result<TpaRecord, TpaError> {
    let toml_file = dir.join(crate::bundle::EXPERIMENT_FILE);
    let (mut name, mut tared) = (crate::bundle::FORCE_FILE.to_string(), true);
    if toml_file.is_file() {
        let text = crate::input::read_to_string(&toml_file)
            .map_err(|source| BundleError::Read { file: toml_file.clone(), source })?;
        let value: toml::Table = toml::from_str(&text).map_err(|e| TpaError::Invalid {
            file: toml_file.clone(),
            line: e.span().map_or(1, |s| 1 + text[..s.start].matches('\n').count()),
            field: "toml".into(),
            cause: e.message().to_string(),
        })?;
        let data = value.get("data").and_then(|d| d.as_table());
        // The line of `key = ...` (or of the `[data]` header), for messages.
        let line_of = |key: &str| {
            let at = |l: &str| {
                let l = l.trim_start();
                l == key || l.strip_prefix(key).is_some_and(|rest| rest.trim_start().starts_with('='))
            };
            text.lines().position(at).map_or(1, |i| i + 1)
        };
        match data.and_then(|d| d.get("force")) {
            Some(toml::Value::String(s)) => name = s.clone(),
            Some(_) => {
                return Err(TpaError::Invalid {
                    file: toml_file.clone(),
                    line: line_of("force"),
                    field: "data.force".into(),
                    cause: "not a file name".into(),
                })
            }
            None if data.is_some() || !dir.join(&name).is_file() => {
                return Err(TpaError::Invalid {
                    file: toml_file.clone(),
                    line: line_of("[data]"),
                    field: "data.force".into(),
                    cause: "the bundle has no force record to analyse".into(),
                })
            }
            None => {}
        }
        let relative = Path::new(&name);
        if relative.components().any(|c| !matches!(c, Component::Normal(_) | Component::CurDir)) {
            return Err(TpaError::Invalid {
                file: toml_file.clone(),
                line: line_of("force"),
                field: "data.force".into(),
                cause: format!("\"{name}\" is not a path inside the bundle"),
            });
        }
        tared = data.and_then(|d| d.get("force_tared")).and_then(|v| v.as_bool()) != Some(false);
    }
    csv_record(&dir.join(name), !tared)
}

/// A `t_s,force_N` file; tared by [`detect_touch`] when `tare` is set.
fn csv_record(file: &Path, tare: bool) -> Result<TpaRecord, TpaError> {
    let series = read_force(file)?;
    let t_s: Vec<f64> = series.samples.iter().map(|s| s.t_s).collect();
    let mut force_n: Vec<f64> = series.samples.iter().map(|s| s.force_n).collect();
    if tare {
        let offset = detect_touch(&force_n)
            .map_err(|why| TpaError::Invalid {
                file: file.to_path_buf(),
                line: 2,
                field: "force_N".into(),
                cause: format!("no tare: {}", no_touch_cause(why)),
            })?
            .tare;
        force_n.iter_mut().for_each(|f| *f -= offset);
    }
    // The header is line 1; read_force refuses blank rows, so sample i is on line i + 2.
    let lines = (0..t_s.len()).map(|i| i + 2).collect();
    Ok(TpaRecord { file: file.to_path_buf(), force_column: "force_N".into(), t_s, force_n, lines })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(t: Vec<f64>, f: Vec<f64>) -> TpaRecord {
        let lines = (0..t.len()).map(|i| i + 2).collect();
        TpaRecord { file: PathBuf::from("synthetic.csv"), force_column: "force_N".into(), t_s: t, force_n: f, lines }
    }

    /// A triangle from 0 at `t0` up to `peak` at `t0 + rise` and down to 0 at
    /// `t0 + rise + fall`, zero elsewhere.
    fn triangle(t: f64, t0: f64, rise: f64, fall: f64, peak: f64) -> f64 {
        let x = t - t0;
        if x <= 0.0 || x >= rise + fall {
            0.0
        } else if x <= rise {
            peak * x / rise
        } else {
            peak * (rise + fall - x) / fall
        }
    }

    /// Two triangles on a grid that holds their corners: the areas and times
    /// are exact (the curve through the samples is the triangles themselves).
    fn two_triangles(dt: f64, second: [f64; 4]) -> TpaRecord {
        let n = (60.0 / dt).round() as usize;
        let t: Vec<f64> = (0..=n).map(|i| i as f64 * dt).collect();
        let f = t
            .iter()
            .map(|&x| triangle(x, 5.0, 10.0, 5.0, 8.0) + triangle(x, second[0], second[1], second[2], second[3]))
            .collect();
        record(t, f)
    }

    /// Closed form: a triangle rising over `a` to `P`, falling over `b`, with the
    /// threshold `h`: touch at `a h / P` after its start, the area from the touch
    /// to the peak `P a (1 - (h/P)^2) / 2`, from the peak to the end
    /// `P b (1 - (h/P)^2) / 2`, the touch-to-peak time `a (1 - h/P)`.
    #[test]
    fn triangles_give_the_closed_form() {
        let h = DEFAULT_THRESHOLD_N;
        let (p1, a1, b1) = (8.0, 10.0, 5.0);
        let (p2, a2, b2) = (5.0, 6.0, 4.0);
        let r = two_triangles(0.01, [35.0, a2, b2, p2]);
        let tpa = analyse(&r, &TpaOptions::default()).unwrap();
        let s = |p: f64| 1.0 - (h / p).powi(2);
        let (area1, area2) = (0.5 * p1 * a1 * s(p1), 0.5 * p1 * b1 * s(p1));
        let (area3, area4) = (0.5 * p2 * a2 * s(p2), 0.5 * p2 * b2 * s(p2));
        let close = |got: f64, want: f64, what: &str| {
            // Rounding only: every corner is on the grid (1e-12 relative).
            assert!((got - want).abs() <= 1e-9 * want.abs().max(1.0), "{what}: {got} vs {want}");
        };
        close(tpa.hardness_n, p1, "hardness");
        close(tpa.strokes[0].touch_s, 5.0 + a1 * h / p1, "touch 1");
        close(tpa.strokes[0].end_s, 5.0 + a1 + b1 * (1.0 - h / p1), "end 1");
        close(tpa.strokes[1].touch_s, 35.0 + a2 * h / p2, "touch 2");
        close(tpa.strokes[0].area_to_peak_n_s, area1, "A1");
        close(tpa.strokes[0].area_after_peak_n_s, area2, "A2");
        close(tpa.strokes[1].area_to_peak_n_s, area3, "A3");
        close(tpa.strokes[1].area_after_peak_n_s, area4, "A4");
        close(tpa.cohesiveness, (area3 + area4) / (area1 + area2), "cohesiveness");
        close(tpa.resilience, b1 / a1, "resilience");
        close(tpa.springiness, a2 * (1.0 - h / p2) / (a1 * (1.0 - h / p1)), "springiness");
        close(tpa.gumminess_n, p1 * tpa.cohesiveness, "gumminess");
        close(tpa.chewiness_n, tpa.gumminess_n * tpa.springiness, "chewiness");
        close(tpa.split_s, 0.5 * (tpa.strokes[0].end_s + tpa.strokes[1].touch_s), "split");
        assert_eq!(tpa.adhesiveness_n_s, 0.0);
    }

    /// Half-sines `P sin(pi (t - t0) / T)`: with a threshold far below the peak,
    /// each half's area is `P T / pi` (the touch and end cut off `h^2 T / (pi P)`
    /// at most: 1e-5 relative here) and the touch-to-peak time `T / 2`, so the
    /// cohesiveness is `P2 T2 / (P1 T1)`, the resilience 1 and the springiness
    /// `T2 / T1`; the trapezoid rule on 1e4 samples per stroke is within 1e-6.
    /// A negative dip after stroke 1 is the adhesiveness, `2 D W / pi` for a
    /// dip `-D sin` of width `W`.
    #[test]
    fn half_sines_and_adhesiveness() {
        let (p1, t1, p2, t2, dip, width) = (4.0, 10.0, 3.0, 8.0, 0.05, 4.0);
        let dt: f64 = 1e-3;
        let n = (50.0 / dt).round() as usize;
        let t: Vec<f64> = (0..=n).map(|i| i as f64 * dt).collect();
        let sine = |x: f64, t0: f64, len: f64, amp: f64| {
            if x > t0 && x < t0 + len {
                amp * (std::f64::consts::PI * (x - t0) / len).sin()
            } else {
                0.0
            }
        };
        let f = t.iter().map(|&x| sine(x, 2.0, t1, p1) - sine(x, 13.0, width, dip) + sine(x, 30.0, t2, p2)).collect();
        let options = TpaOptions { threshold_n: 1e-3, ..TpaOptions::default() };
        let tpa = analyse(&record(t, f), &options).unwrap();
        let rel = |got: f64, want: f64, tol: f64, what: &str| {
            assert!((got / want - 1.0).abs() <= tol, "{what}: {got} vs {want}");
        };
        rel(tpa.hardness_n, p1, 1e-6, "hardness");
        rel(tpa.cohesiveness, p2 * t2 / (p1 * t1), 2e-5, "cohesiveness");
        rel(tpa.resilience, 1.0, 2e-5, "resilience");
        rel(tpa.springiness, t2 / t1, 2e-4, "springiness");
        rel(tpa.adhesiveness_n_s, 2.0 * dip * width / std::f64::consts::PI, 1e-6, "adhesiveness");
    }

    #[test]
    fn smoothing_keeps_the_areas_and_lowers_a_sharp_peak() {
        let r = two_triangles(0.01, [35.0, 6.0, 4.0, 5.0]);
        let plain = analyse(&r, &TpaOptions::default()).unwrap();
        let smooth = analyse(&r, &TpaOptions { smoothing_samples: 2.0, ..TpaOptions::default() }).unwrap();
        // A Gaussian of 2 samples (sigma = 0.02 s) rounds the corner between the
        // slopes 0.8 and 1.6 N/s. At the corner it drops by (0.8 + 1.6) sigma /
        // sqrt(2 pi) = 0.019 N; the smoothed maximum lies a little toward the
        // gentler side and drops less, but by more than half of that.
        let drop = (0.8 + 1.6) * 0.02 / (2.0 * std::f64::consts::PI).sqrt();
        let got = plain.hardness_n - smooth.hardness_n;
        assert!(got > 0.5 * drop && got <= drop * (1.0 + 1e-9), "peak drop {got} vs at most {drop}");
        assert!((smooth.cohesiveness - plain.cohesiveness).abs() < 1e-3);
        let too_much = analyse(&r, &TpaOptions { smoothing_samples: 2.5, ..TpaOptions::default() }).unwrap_err();
        assert!(too_much.to_string().contains("smoothing_samples"), "{too_much}");
    }

    #[test]
    fn one_stroke_is_refused_naming_the_file() {
        let dt = 0.01;
        let t: Vec<f64> = (0..=6000).map(|i| i as f64 * dt).collect();
        let f: Vec<f64> = t.iter().map(|&x| triangle(x, 5.0, 10.0, 5.0, 8.0)).collect();
        let err = analyse(&record(t.clone(), f.clone()), &TpaOptions::default()).unwrap_err().to_string();
        assert!(err.starts_with("synthetic.csv:") && err.contains("no second stroke"), "{err}");
        // Noise around the threshold before and after the stroke is not a stroke.
        let noisy: Vec<f64> = f
            .iter()
            .zip(&t)
            .map(|(y, &x)| if !(4.0..=25.0).contains(&x) { 0.1 + 0.02 * (x * 37.0).sin() } else { *y })
            .collect();
        let err = analyse(&record(t.clone(), noisy.clone()), &TpaOptions::default()).unwrap_err().to_string();
        assert!(err.contains("no second stroke: one compression only"), "{err}");
        // With a second stroke, the noise changes nothing but the touch and end
        // it borders on (the curve itself is the same from touch to end).
        let second: Vec<f64> = noisy.iter().zip(&t).map(|(y, &x)| y + triangle(x, 30.0, 6.0, 4.0, 5.0)).collect();
        let clean: Vec<f64> = f.iter().zip(&t).map(|(y, &x)| y + triangle(x, 30.0, 6.0, 4.0, 5.0)).collect();
        let (a, b) = (
            analyse(&record(t.clone(), second), &TpaOptions::default()).unwrap(),
            analyse(&record(t, clean), &TpaOptions::default()).unwrap(),
        );
        assert_eq!(a.hardness_n, b.hardness_n);
        assert!((a.strokes[0].touch_s - b.strokes[0].touch_s).abs() < 1e-12, "{a:?}\n{b:?}");
    }

    #[test]
    fn no_contact_is_refused_naming_the_file_and_line() {
        let t: Vec<f64> = (0..100).map(|i| i as f64).collect();
        let f: Vec<f64> = t.iter().map(|&x| 0.05 * (x / 10.0).sin()).collect();
        let err = analyse(&record(t, f), &TpaOptions::default()).unwrap_err().to_string();
        assert!(err.starts_with("synthetic.csv:") && err.contains(": force_N: no contact"), "{err}");
        let bad =
            analyse(&record(vec![0.0, 1.0], vec![0.0, 1.0]), &TpaOptions { threshold_n: 0.0, ..TpaOptions::default() });
        assert!(bad.unwrap_err().to_string().contains("threshold_N"));
    }

    #[test]
    fn reads_a_force_csv_and_a_bundle_folder() {
        let dir = tempfile::tempdir().unwrap();
        let mut csv = String::from("t_s,force_N\n");
        for i in 0..=600 {
            let x = i as f64 * 0.1;
            let y = triangle(x, 5.0, 10.0, 5.0, 8.0) + triangle(x, 35.0, 6.0, 4.0, 5.0);
            csv += &format!("{x},{y}\n");
        }
        std::fs::write(dir.path().join("force.csv"), &csv).unwrap();
        let from_folder = read_tpa_record(dir.path()).unwrap();
        let from_file = read_tpa_record(&dir.path().join("force.csv")).unwrap();
        assert_eq!(from_folder.force_n, from_file.force_n);
        assert_eq!(from_folder.lines[0], 2);
        let tpa = analyse(&from_folder, &TpaOptions::default()).unwrap();
        assert!((tpa.hardness_n - 8.0).abs() < 1e-12);
        // A bundle naming a force file outside itself is refused.
        std::fs::write(dir.path().join("experiment.toml"), "[data]\nforce = \"../force.csv\"\n").unwrap();
        let err = read_tpa_record(dir.path()).unwrap_err().to_string();
        assert!(err.contains("experiment.toml:2: data.force"), "{err}");
    }
}
