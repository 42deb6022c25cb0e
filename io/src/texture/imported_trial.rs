//! [`to_bundle`]: a [`RawTest`] and [`ImportOptions`] -> an [`ImportedTrial`],
//! the experiment bundle of one measured compression.

use std::path::Path;

use serde::Serialize;

use super::error::ImportError;
use super::raw_test::RawTest;
use super::simplify::simplify;
use super::stroke::{find_stroke, ramp_speed, Stroke, StrokeEnd};
use super::touch::{argmax, detect_touch, locate_rise, NoTouch, MIN_CONTACT_ROWS};
use crate::bundle::{write_bundle, BundleWrite, Contact, Experiment, ProtocolSpec, Shape, Specimen, Tool, FORMAT_V1};
use crate::error::WriteError;
use crate::{ForceSample, ForceSeries};

/// The waypoints follow the measured displacement within this [mm] at least ...
pub const WAYPOINT_TOLERANCE_MM: f64 = 1e-3;
/// ... or within this fraction of the largest displacement after touch, if larger.
pub const WAYPOINT_TOLERANCE_FRACTION: f64 = 1e-3;
/// Stroke detection hysteresis, as a fraction of the largest displacement after touch.
pub const STROKE_HYSTERESIS_FRACTION: f64 = 0.05;

/// Where the specimen's height comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HeightSource {
    /// The gap at first touch (rheometer files only: their tool position is the
    /// distance between the plates). The default.
    GapAtTouch,
    /// Given [mm].
    Given(f64),
    /// The tool's height above the support at the file's first row [mm], minus
    /// the tool's travel from there to first touch (e.g. an Exponent test's start
    /// height).
    StartHeight(f64),
}

/// Which part of the test the bundle describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StrokeChoice {
    /// From first touch to the end of the first unloading (the default).
    #[default]
    First,
    /// The second stroke's window only, times still from the first touch.
    Second,
    /// The whole test from first touch.
    All,
}

impl StrokeChoice {
    /// `"1"`, `"2"` or `"all"`.
    pub fn as_str(self) -> &'static str {
        match self {
            StrokeChoice::First => "1",
            StrokeChoice::Second => "2",
            StrokeChoice::All => "all",
        }
    }
}

/// How to turn a raw test into a bundle.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportOptions {
    /// The bundle's `name`.
    pub name: String,
    /// The cylinder's radius [mm], > 0.
    pub radius_mm: f64,
    /// The cylinder's height; default [`HeightSource::GapAtTouch`].
    pub height: HeightSource,
    /// `[specimen] material`; default `"sample"`.
    pub material: String,
    /// When given, a `[materials.NAME]` table with only this model is written: every
    /// parameter an unknown for `wagashi fit` (experiment-format.md: "a material may
    /// give only its model"); `wagashi press` needs `--materials` to give values.
    /// Default `None`: no table, the material comes from `--materials`.
    pub model: Option<crate::bundle::Model>,
    /// `[protocol] tool_contact` and `support`: glued (the default) or frictionless.
    pub contact: Contact,
    /// Which stroke; default [`StrokeChoice::First`].
    pub stroke: StrokeChoice,
    /// Write every `every`-th force sample (and the window's last); default 1: all.
    pub every: usize,
}

impl ImportOptions {
    /// The defaults for a cylinder of `radius_mm`, named `name`.
    pub fn new(name: impl Into<String>, radius_mm: f64) -> Self {
        Self {
            name: name.into(),
            radius_mm,
            height: HeightSource::GapAtTouch,
            material: "sample".into(),
            model: None,
            contact: Contact::Glued,
            stroke: StrokeChoice::First,
            every: 1,
        }
    }
}

/// What the import detected and chose, written to the bundle's `[extra.import]`
/// table (and by `wagashi import` to `summary.json`). Times without `raw` are
/// from first touch [s]; forces are tared [N] unless said otherwise.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportFacts {
    /// The raw file's name.
    pub source_file: String,
    /// `"exponent"` or `"rheometer"`.
    pub source_format: &'static str,
    /// The test's name in the raw file, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source_test: Option<String>,
    /// The importer and its version.
    pub imported_by: String,
    /// `"1"`, `"2"` or `"all"`.
    pub stroke: &'static str,
    /// The first-touch time in the raw file's clock [s].
    pub touch_raw_s: f64,
    /// The first-touch row's line in the raw file.
    pub touch_line: usize,
    /// The mean force of the pre-contact segment, subtracted from every force [N].
    #[serde(rename = "tare_N")]
    pub tare_n: f64,
    /// The noise of the pre-contact segment (1.4826 x MAD) [N].
    #[serde(rename = "noise_sigma_N")]
    pub noise_sigma_n: f64,
    /// The contact threshold above the tare [N].
    #[serde(rename = "touch_threshold_N")]
    pub threshold_n: f64,
    /// The noise band above the tare (2 sigma) [N].
    #[serde(rename = "noise_band_N")]
    pub band_n: f64,
    /// The number of rows the tare and noise come from.
    pub pre_contact_rows: usize,
    /// The tool position column at first touch, in mm (the gap, or the Exponent's distance).
    pub tool_at_touch_mm: f64,
    /// The specimen's height [mm].
    pub height_mm: f64,
    /// Where the height comes from.
    pub height_source: String,
    /// The number of strokes found (0, 1 or 2: the search stops after two).
    pub strokes_found: usize,
    /// The loading speed of the first stroke [mm/s] (least squares over 10-90 % of its travel).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed_mm_s: Option<f64>,
    /// The second stroke's touch [s], when there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub second_touch_s: Option<f64>,
    /// The start of the window written [s] (0 unless `stroke = "2"`).
    pub window_start_s: f64,
    /// The end of the window written [s] (= `end_s`).
    pub window_end_s: f64,
    /// How the window ends.
    pub window_end: &'static str,
    /// The largest tared force in the window [N].
    #[serde(rename = "peak_force_N")]
    pub peak_force_n: f64,
    /// Its time [s].
    pub peak_force_s: f64,
    /// The largest displacement from first touch in the window [mm].
    pub max_travel_mm: f64,
    /// Where the plate separates from the specimen [s] (= `release_s`).
    pub separation_s: f64,
    /// How the separation was found.
    pub separation: &'static str,
    /// The number of waypoints.
    pub waypoints: usize,
    /// The waypoints follow the measured displacement within this [mm].
    pub waypoint_tolerance_mm: f64,
    /// The number of force samples written.
    pub force_samples: usize,
    /// Every how many raw rows a force sample was written.
    pub force_every: usize,
}

/// A raw test turned into a bundle: write it with [`ImportedTrial::write`].
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedTrial {
    /// `experiment.toml` (its `[data]` is set by [`ImportedTrial::bundle_write`]).
    pub experiment: Experiment,
    /// `force.csv`: tared force from first touch, compression positive.
    pub force: ForceSeries,
    /// What was detected; also in `experiment.extra["import"]`.
    pub facts: ImportFacts,
}

impl ImportedTrial {
    /// The bundle as [`write_bundle`] takes it: `force.csv`, `force_tared = true`.
    pub fn bundle_write(&self) -> BundleWrite<'_> {
        BundleWrite {
            experiment: &self.experiment,
            name: &self.experiment.name,
            force: Some(&self.force),
            markers: &[],
            force_tared: Some(true),
        }
    }

    /// Writes `experiment.toml` and `force.csv` into `dir` (created if missing),
    /// each atomically; for a whole folder at once write into an
    /// [`crate::AtomicDir`].
    pub fn write(&self, dir: impl AsRef<Path>) -> Result<(), WriteError> {
        write_bundle(dir, &self.bundle_write())
    }
}

/// Turns `raw` into a bundle (see the [module docs](super) for the rules).
pub fn to_bundle(raw: &RawTest, options: &ImportOptions) -> Result<ImportedTrial, ImportError> {
    raw.check()?;
    check_options(raw, options)?;
    let file = raw.file.as_path();
    let format = raw.format;
    let s = &raw.samples;
    let n = s.len();
    let t: Vec<f64> = s.iter().map(|x| x.t_s).collect();
    let f: Vec<f64> = s.iter().map(|x| x.force_n).collect();
    let y: Vec<f64> = s.iter().map(|x| x.tool_mm).collect();
    let force_column = format.force_column();
    let line = |i: usize| s.get(i).map_or(1, |x| x.line);

    // Tare, noise, first touch.
    let touch = detect_touch(&f).map_err(|e| match e {
        NoTouch::TooShort { samples, needed } => ImportError::invalid(
            file,
            line(n.saturating_sub(1)),
            force_column,
            format!("only {samples} rows; finding the touch needs at least {needed}"),
        ),
        NoTouch::NoRise { peak, level, threshold } => ImportError::invalid(
            file,
            line(peak),
            force_column,
            format!(
                "no contact found: the force never stays more than {} N above its pre-contact level {} N \
                 for {MIN_CONTACT_ROWS} rows (its largest value, {} N, is on this line)",
                sig(threshold),
                sig(level),
                sig(f[peak])
            ),
        ),
        NoTouch::NoPreContact { crossing } => ImportError::invalid(
            file,
            line(0),
            force_column,
            format!(
                "no contact found: the force is above the noise from the first rows on (rising up to line {}); \
                 the file must start before the tool touches, so that the force can be tared",
                line(crossing)
            ),
        ),
    })?;
    let i0 = touch.touch;
    let t0 = t[i0];
    let tare = touch.tare;

    // The displacement from first touch, the strokes.
    let d: Vec<f64> = y.iter().map(|&v| y[i0] - v).collect();
    let max_travel = d[i0..].iter().copied().fold(0.0, f64::max);
    let tolerance = WAYPOINT_TOLERANCE_MM.max(WAYPOINT_TOLERANCE_FRACTION * max_travel);
    let hysteresis = STROKE_HYSTERESIS_FRACTION * max_travel;
    let stroke1 = if max_travel > 0.0 { find_stroke(&d, i0, hysteresis, tolerance) } else { None };
    let stroke2 = stroke1
        .filter(|s| s.end_rule != StrokeEnd::FileEnd)
        .and_then(|s1| find_stroke(&d, s1.end, hysteresis, tolerance));
    let strokes_found = usize::from(stroke1.is_some()) + usize::from(stroke2.is_some());
    let whole = Stroke { start: i0, peak: argmax(&d, i0..n), end: n - 1, end_rule: StrokeEnd::FileEnd };
    let window = match options.stroke {
        StrokeChoice::First => stroke1.unwrap_or(whole),
        StrokeChoice::Second => match (stroke1, stroke2) {
            (_, Some(s2)) => s2,
            (Some(s1), None) => {
                return Err(ImportError::invalid(
                    file,
                    line(s1.end),
                    format.tool_column(),
                    format!(
                        "no second stroke: the tool does not push again after the first stroke ends here (t = {} s in the file)",
                        t[s1.end]
                    ),
                ))
            }
            (None, None) => {
                return Err(ImportError::invalid(
                    file,
                    line(i0),
                    format.tool_column(),
                    "no second stroke: the tool makes no stroke after first touch (on this line)",
                ))
            }
        },
        StrokeChoice::All => whole,
    };
    let (start, end) = (window.start, window.end);

    // The force peak and the separation in the window.
    let peak = argmax(&f, start..end + 1);
    let (release, separation) = match options.stroke {
        StrokeChoice::All => (end, "end of the test (stroke = \"all\")"),
        _ => match (peak..=end).find(|&j| f[j] - tare <= touch.band) {
            Some(j) => (j, "force back in the noise band after the peak"),
            None => (end, "force not back in the noise band: end of the window"),
        },
    };
    let release_s = t[release] - t0;
    let end_s = t[end] - t0;
    if !(release_s > 0.0 && end_s > 0.0) {
        return Err(ImportError::invalid(
            file,
            line(end),
            force_column,
            format!("the window of stroke {} ends at first touch: nothing to write", options.stroke.as_str()),
        ));
    }

    // The waypoints: the displacement up to the separation (the format refuses
    // waypoints that move after release_s), at each update of the position (a
    // row repeating the previous position is the instrument holding its last
    // reading), simplified.
    let points: Vec<[f64; 2]> = (start..=release)
        .filter(|&i| i == start || i == release || y[i] != y[i - 1])
        .map(|i| [t[i] - t0, d[i]])
        .collect();
    let waypoints: Vec<[f64; 2]> = simplify(&points, tolerance).into_iter().map(|k| points[k]).collect();

    // The height.
    let travel_in_window = d[start..=end].iter().copied().fold(0.0, f64::max);
    let (height_mm, height_source) = height(raw, options, i0)?;
    if travel_in_window >= height_mm {
        return Err(ImportError::options(
            file,
            "height",
            format!(
                "the specimen would be {height_mm} mm high but the tool travels {travel_in_window} mm after first touch"
            ),
        ));
    }

    // The force samples.
    let every = options.every.max(1);
    let mut rows: Vec<usize> = (start..=end).step_by(every).collect();
    if rows.last() != Some(&end) {
        rows.push(end);
    }
    let force =
        ForceSeries { samples: rows.iter().map(|&i| ForceSample { t_s: t[i] - t0, force_n: f[i] - tare }).collect() };

    let speed_mm_s = stroke1.and_then(|s1| ramp_speed(&t, &d, s1.start..s1.peak + 1, d[s1.peak]));
    let second_touch_s =
        stroke2.and_then(|s2| locate_rise(&f, s2.start..s2.end + 1, tare, touch.sigma).ok()).map(|(k, ..)| t[k] - t0);
    let facts = ImportFacts {
        source_file: file.file_name().map_or_else(|| file.display().to_string(), |n| n.to_string_lossy().into_owned()),
        source_format: format.as_str(),
        source_test: raw.test_name.clone(),
        imported_by: format!("wagashi-io {}", env!("CARGO_PKG_VERSION")),
        stroke: options.stroke.as_str(),
        touch_raw_s: t0,
        touch_line: line(i0),
        tare_n: tare,
        noise_sigma_n: touch.sigma,
        threshold_n: touch.threshold,
        band_n: touch.band,
        pre_contact_rows: touch.pre_contact,
        tool_at_touch_mm: if format.tool_is_absolute() { y[i0] } else { -y[i0] },
        height_mm,
        height_source,
        strokes_found,
        speed_mm_s,
        second_touch_s,
        window_start_s: t[start] - t0,
        window_end_s: end_s,
        window_end: if options.stroke == StrokeChoice::All {
            StrokeEnd::FileEnd.as_str()
        } else {
            window.end_rule.as_str()
        },
        peak_force_n: f[peak] - tare,
        peak_force_s: t[peak] - t0,
        max_travel_mm: travel_in_window,
        separation_s: release_s,
        separation,
        waypoints: waypoints.len(),
        waypoint_tolerance_mm: tolerance,
        force_samples: force.samples.len(),
        force_every: every,
    };
    let extra_import = toml::Table::try_from(&facts)
        .map_err(|e| ImportError::invalid(file, line(i0), "extra.import", format!("cannot be written as TOML: {e}")))?;
    let mut extra = toml::Table::new();
    extra.insert("import".into(), toml::Value::Table(extra_import));

    let experiment = Experiment {
        format: FORMAT_V1.into(),
        name: options.name.clone(),
        dimension: 3,
        specimen: Specimen {
            shape: Shape::Cylinder,
            size_mm: None,
            radius_mm: Some(options.radius_mm),
            height_mm: Some(height_mm),
            mass_g: None,
            density_g_cm3: None,
            plane: None,
            material: Some(options.material.clone()),
            layers: Vec::new(),
            surface: None,
            mesh: None,
            regions: Default::default(),
        },
        materials: options
            .model
            .map(|m| [(options.material.clone(), crate::bundle::MaterialSpec::skeleton(m))].into_iter().collect())
            .unwrap_or_default(),
        protocol: ProtocolSpec {
            tool: Tool::Plate,
            tool_radius_mm: None,
            tool_surface: None,
            tool_contact: options.contact,
            support: options.contact,
            friction: None,
            waypoints,
            release_s,
            end_s,
            gravity: false,
            tool_surface_units: None,
            tools: Vec::new(),
        },
        data: None,
        effects: Default::default(),
        extra: Some(extra),
    };
    Ok(ImportedTrial { experiment, force, facts })
}

/// The height [mm] and where it comes from.
fn height(raw: &RawTest, options: &ImportOptions, touch: usize) -> Result<(f64, String), ImportError> {
    let s = &raw.samples;
    let (h, source) = match options.height {
        HeightSource::Given(h) => (h, "given".to_string()),
        HeightSource::StartHeight(start) => {
            let travel = s[0].tool_mm - s[touch].tool_mm;
            let h = start - travel;
            let positive = h > 0.0; // false for NaN
            if !positive {
                return Err(ImportError::options(
                    &raw.file,
                    "height",
                    format!(
                        "the start height {start} mm minus the travel to first touch {travel} mm leaves {h} mm; give the specimen's height"
                    ),
                ));
            }
            (h, format!("start height {start} mm minus the travel to first touch {travel} mm"))
        }
        HeightSource::GapAtTouch => {
            if !raw.format.tool_is_absolute() {
                return Err(ImportError::options(
                    &raw.file,
                    "height",
                    format!(
                        "an {} file has no gap to read the height from: give the specimen's height or the tool's start height",
                        raw.format.as_str()
                    ),
                ));
            }
            let h = s[touch].tool_mm;
            let positive = h > 0.0; // false for NaN
            if !positive {
                return Err(ImportError::invalid(
                    &raw.file,
                    s[touch].line,
                    raw.format.tool_column(),
                    format!("the gap at first touch, {h} mm, is not a height > 0"),
                ));
            }
            (h, "gap at first touch".to_string())
        }
    };
    Ok((h, source))
}

fn check_options(raw: &RawTest, o: &ImportOptions) -> Result<(), ImportError> {
    let bad = |option: &str, cause: String| Err(ImportError::options(&raw.file, option, cause));
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if o.name.trim().is_empty() {
        return bad("name", "empty bundle name".into());
    }
    if o.material.trim().is_empty() {
        return bad("material", "empty material name".into());
    }
    if !positive(o.radius_mm) {
        return bad("radius_mm", format!("{} is not a length > 0", o.radius_mm));
    }
    match o.height {
        HeightSource::Given(h) | HeightSource::StartHeight(h) if !positive(h) => {
            return bad("height", format!("{h} is not a length > 0"));
        }
        _ => {}
    }
    if o.contact == Contact::Friction {
        return bad("contact", "\"friction\" needs a coefficient; import with glued or frictionless".into());
    }
    if o.every == 0 {
        return bad("every", "0: give 1 to keep every row".into());
    }
    if raw.samples.is_empty() {
        return Err(ImportError::invalid(&raw.file, 1, "row", "no data rows"));
    }
    Ok(())
}

/// `x` with 4 significant digits, for messages.
fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 12) as usize;
    format!("{x:.digits$}")
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::path::PathBuf;

    use super::*;
    use crate::bundle::{MaterialSpec, Model};
    use crate::texture::raw_test::{RawFormat, RawSample};
    use crate::texture::simplify::interpolate;
    use crate::texture::touch::tests::Rng;
    use crate::texture::{parse_exponent, parse_rheometer};

    /// A synthetic double compression on a rheometer, 100 Hz: 3 s at rest touching
    /// a 9 mm specimen, 0.2 mm/s down 4 mm, up 0.2 mm/s to 0.05 mm above touch,
    /// 2 s rest, down 3.6 mm, up, rest. Force 0.1 N/mm^2 of (d - offset)^2 while
    /// in contact (the second stroke touches 0.4 mm lower: residual deformation;
    /// on unloading the specimen lags, leaving the plate 1 mm before d = 0),
    /// tare 0.02 N, noise 0.002 N.
    pub(crate) fn double_compression(seed: u64) -> RawTest {
        let legs = [
            (0.0, 0.0),
            (3.0, 0.0),
            (23.0, 4.0),
            (43.25, -0.05),
            (45.25, -0.05),
            (63.25, 3.55),
            (83.25, -0.45),
            (90.0, -0.45),
        ];
        let mut rng = Rng(seed);
        let mut samples = Vec::new();
        for i in 0..=9000usize {
            let t = i as f64 * 0.01;
            let w = legs.windows(2).find(|w| t <= w[1].0).unwrap_or(&legs[legs.len() - 2..]);
            let ((ta, da), (tb, db)) = (w[0], w[1]);
            let d = da + (db - da) * (t - ta) / (tb - ta);
            let loading = db > da;
            // The specimen's top: 0 in stroke 1's loading, 0.4 mm lower from its unloading on,
            // and lagging 1 mm behind the plate while unloading.
            let top = if t < 23.0 { 0.0 } else { 0.4 };
            let contact = if loading { d - top } else { d - top - 1.0 };
            let force = if contact > 0.0 { 0.1 * contact * contact } else { 0.0 };
            samples.push(RawSample {
                line: i + 2,
                t_s: t,
                force_n: 0.02 + force + 0.002 * rng.normal(),
                tool_mm: 9.0 - d,
            });
        }
        RawTest { file: PathBuf::from("double.txt"), format: RawFormat::Rheometer, test_name: None, samples }
    }

    fn options() -> ImportOptions {
        ImportOptions::new("double", 4.0)
    }

    /// The refusal's message (without printing a whole trial when there is none).
    fn refused(result: Result<ImportedTrial, ImportError>) -> String {
        match result {
            Ok(_) => panic!("accepted"),
            Err(e) => e.to_string(),
        }
    }

    fn placeholder_materials() -> BTreeMap<String, MaterialSpec> {
        BTreeMap::from([("sample".to_string(), MaterialSpec::new(Model::Elastic))])
    }

    #[test]
    fn stroke_one_of_a_double_compression() {
        let raw = double_compression(1);
        let trial = to_bundle(&raw, &options()).unwrap();
        let facts = &trial.facts;
        // Contact at 3 s, but the force rises as 0.1 d^2 = 0.1 (0.2 (t - 3))^2, slowly:
        // it leaves the 2 sigma band (0.004 N) at t = 4 s and passes the threshold
        // (1 % of the peak, 0.016 N) at 5 s; the touch lies in between, late by the noise.
        assert!(facts.touch_raw_s >= 3.0 && facts.touch_raw_s < 5.0, "{facts:?}");
        // The tare: 0.02 N, lifted by at most 0.004 N * (1/3) * (2 s / 5 s) by the toe
        // of the rise that the pre-contact segment holds (3 s to touch).
        assert!((facts.tare_n - 0.02).abs() < 1.5e-3, "{facts:?}");
        assert!((facts.noise_sigma_n / 0.002 - 1.0).abs() < 0.25, "{facts:?}");
        assert_eq!(facts.strokes_found, 2);
        assert!((facts.speed_mm_s.unwrap() - 0.2).abs() < 1e-3, "{facts:?}");
        // The height: the gap at touch.
        let d_touch = 0.2 * (facts.touch_raw_s - 3.0);
        assert!((facts.height_mm - (9.0 - d_touch)).abs() < 1e-9, "{facts:?}");
        // The window ends when the tool is back at the touch position.
        let p = &trial.experiment.protocol;
        assert!((p.end_s + facts.touch_raw_s - (23.0 + (4.0 - d_touch) / 0.2)).abs() < 0.02, "{p:?}");
        // Separation: the contact ends at d = top + 1 mm = 1.4 mm on the way up, at
        // 36 s; the force 0.1 (d - 1.4)^2 falls below the threshold at 34 s and into
        // the band just before 35 s (earlier with the noise) ...
        let separation_raw = p.release_s + facts.touch_raw_s;
        assert!((34.0..=36.0).contains(&separation_raw), "{p:?} {facts:?}");
        // ... and the waypoints stop there, start at [0, 0] and increase in time.
        assert_eq!(p.waypoints[0], [0.0, 0.0]);
        assert_eq!(p.waypoints.last().unwrap()[0], p.release_s);
        assert!(p.waypoints.windows(2).all(|w| w[1][0] > w[0][0]));
        // Touch (mid-ramp), turn and separation: 3 or 4 points.
        assert!((3..=4).contains(&p.waypoints.len()), "{:?}", p.waypoints);
        // The peak: 0.1 * 4^2 = 1.6 N above the tare.
        assert!((facts.peak_force_n - 1.6).abs() < 0.01, "{facts:?}");
        // The force starts at touch, tared.
        let first = trial.force.samples[0];
        assert_eq!(first.t_s, 0.0);
        assert!(first.force_n.abs() < 0.01);
        assert_eq!(trial.force.samples.last().unwrap().t_s, p.end_s);
    }

    #[test]
    fn waypoints_follow_the_displacement_within_the_tolerance() {
        let raw = double_compression(2);
        for stroke in [StrokeChoice::First, StrokeChoice::Second, StrokeChoice::All] {
            let trial = to_bundle(&raw, &ImportOptions { stroke, ..options() }).unwrap();
            let p = &trial.experiment.protocol;
            let t0 = trial.facts.touch_raw_s;
            let y0 = 9.0 - trial.facts.height_mm; // d at touch in the synthetic's frame
            let tol = trial.facts.waypoint_tolerance_mm;
            // 0.1 % of the largest displacement after touch, 4 mm - d(touch).
            assert!((tol - 1e-3 * (trial.facts.height_mm - 5.0)).abs() < 1e-12, "{tol}");
            let (a, b) = (p.waypoints[0][0], p.waypoints.last().unwrap()[0]);
            for (k, s) in raw.samples.iter().enumerate() {
                let t = s.t_s - t0;
                let update = k == 0 || s.tool_mm != raw.samples[k - 1].tool_mm;
                if t >= a && t <= b && update {
                    let d = (9.0 - s.tool_mm) - y0;
                    let e = (interpolate(&p.waypoints, t) - d).abs();
                    assert!(e <= tol, "{stroke:?}: error {e} > {tol} at t = {t}");
                }
            }
        }
    }

    #[test]
    fn held_positions_do_not_make_waypoints() {
        // The position updated every 5th row and held in between (as the rheometer's
        // gap), with 0.3 um of jitter: a staircase around the ramps.
        let mut raw = double_compression(15);
        let mut rng = Rng(21);
        let exact: Vec<f64> = raw.samples.iter().map(|s| s.tool_mm).collect();
        for (k, s) in raw.samples.iter_mut().enumerate() {
            s.tool_mm = exact[k - k % 5] + if k % 5 == 0 { 3e-4 * rng.normal() } else { 0.0 };
        }
        for k in 0..raw.samples.len() {
            if k % 5 != 0 {
                raw.samples[k].tool_mm = raw.samples[k - k % 5].tool_mm;
            }
        }
        let trial = to_bundle(&raw, &options()).unwrap();
        let p = &trial.experiment.protocol;
        assert!(p.waypoints.len() <= 8, "{:?}", p.waypoints);
        // Every update lies within the tolerance (~3.7 um).
        let (t0, y0) = (trial.facts.touch_raw_s, raw.samples[trial.facts.touch_line - 2].tool_mm);
        let tol = trial.facts.waypoint_tolerance_mm;
        for (k, s) in raw.samples.iter().enumerate() {
            let t = s.t_s - t0;
            if k % 5 == 0 && t >= 0.0 && t <= p.release_s {
                let e = (interpolate(&p.waypoints, t) - (y0 - s.tool_mm)).abs();
                assert!(e <= tol, "error {e} > {tol} at t = {t}");
            }
        }
    }

    #[test]
    fn stroke_two_and_all() {
        let raw = double_compression(3);
        let one = to_bundle(&raw, &options()).unwrap();
        let two = to_bundle(&raw, &ImportOptions { stroke: StrokeChoice::Second, ..options() }).unwrap();
        let all = to_bundle(&raw, &ImportOptions { stroke: StrokeChoice::All, ..options() }).unwrap();
        let (p1, p2, pa) = (&one.experiment.protocol, &two.experiment.protocol, &all.experiment.protocol);
        // Stroke 2 starts where stroke 1 ends, times from the first touch.
        assert_eq!(p2.waypoints[0][0], p1.end_s);
        assert_eq!(two.force.samples[0].t_s, p1.end_s);
        assert_eq!(two.facts.touch_raw_s, one.facts.touch_raw_s);
        assert_eq!(two.facts.window_start_s, p1.end_s);
        // Its contact is 0.4 mm lower, at 47.5 s (the push starts at 45.25 s from
        // d = -0.05 mm); the force passes the threshold at d = 0.8 mm, 49.5 s.
        let touch2 = two.facts.second_touch_s.unwrap() + one.facts.touch_raw_s;
        assert!((47.5..49.5).contains(&touch2), "{touch2}");
        assert!((two.facts.peak_force_n - 0.1 * 3.15f64.powi(2)).abs() < 0.01, "{:?}", two.facts);
        assert!(p2.release_s < p2.end_s && p2.release_s > two.facts.peak_force_s);
        // All: the whole test, released at its end.
        assert_eq!((pa.release_s, pa.end_s), (pa.end_s, 90.0 - one.facts.touch_raw_s));
        assert_eq!(pa.waypoints.last().unwrap()[0], pa.end_s);
        assert_eq!(all.facts.peak_force_n, one.facts.peak_force_n);
    }

    #[test]
    fn the_bundle_reads_back() {
        let raw = double_compression(4);
        for stroke in [StrokeChoice::First, StrokeChoice::Second, StrokeChoice::All] {
            let trial = to_bundle(&raw, &ImportOptions { stroke, every: 7, ..options() }).unwrap();
            let dir = tempfile::tempdir().unwrap();
            trial.write(dir.path()).unwrap();
            let back = crate::read_bundle_with(dir.path(), &placeholder_materials()).unwrap();
            let e = &back.experiment;
            assert_eq!(e.protocol, trial.experiment.protocol);
            assert_eq!(e.specimen, trial.experiment.specimen);
            assert_eq!(e.extra, trial.experiment.extra);
            assert_eq!(e.data.as_ref().unwrap().force_tared, Some(true));
            assert_eq!(back.force.as_ref(), Some(&trial.force));
            assert!(e.materials.len() == 1 && e.specimen.material.as_deref() == Some("sample"));
            let text = std::fs::read_to_string(dir.path().join("experiment.toml")).unwrap();
            assert!(text.contains("[extra.import]") && text.contains("tare_N = "), "{text}");
        }
    }

    #[test]
    fn without_materials_the_reader_refuses_the_bundle() {
        // The bundle names a material it does not define (it comes from --materials
        // or a fit), which read_bundle refuses: callers use read_bundle_with.
        let trial = to_bundle(&double_compression(5), &options()).unwrap();
        let dir = tempfile::tempdir().unwrap();
        trial.write(dir.path()).unwrap();
        let err = crate::read_bundle(dir.path()).unwrap_err().to_string();
        assert!(err.contains("specimen.material: material \"sample\" is not defined"), "{err}");
    }

    /// With a model, the bundle defines its material by the model alone: it reads
    /// back as it is, every parameter unknown (for a fit).
    #[test]
    fn with_a_model_the_bundle_reads_back_alone() {
        let options = ImportOptions { model: Some(crate::bundle::Model::FiveElement), ..options() };
        let trial = to_bundle(&double_compression(5), &options).unwrap();
        let dir = tempfile::tempdir().unwrap();
        trial.write(dir.path()).unwrap();
        let back = crate::read_bundle(dir.path()).unwrap();
        let spec = &back.experiment.materials["sample"];
        assert_eq!(spec.model, crate::bundle::Model::FiveElement);
        assert_eq!(spec.missing().len(), 6, "{spec:?}");
    }

    #[test]
    fn every_keeps_the_last_row() {
        let raw = double_compression(6);
        let all_rows = to_bundle(&raw, &options()).unwrap();
        let some = to_bundle(&raw, &ImportOptions { every: 10, ..options() }).unwrap();
        let n = all_rows.force.samples.len();
        // Rows 0, 10, 20, ... and the last one when it is not among them.
        let last_on_grid = (0..n).step_by(10).any(|i| i == n - 1);
        assert_eq!(some.force.samples.len(), (0..n).step_by(10).count() + usize::from(!last_on_grid));
        assert_eq!(some.force.samples.last(), all_rows.force.samples.last());
        assert_eq!(some.force.samples[1], all_rows.force.samples[10]);
    }

    #[test]
    fn no_contact_is_refused_with_the_line_of_the_largest_force() {
        let mut raw = double_compression(7);
        let mut rng = Rng(9);
        for s in &mut raw.samples {
            s.force_n = 0.02 + 0.002 * rng.normal();
        }
        let peak = raw.samples.iter().max_by(|a, b| a.force_n.total_cmp(&b.force_n)).unwrap().line;
        let err = refused(to_bundle(&raw, &options()));
        assert!(err.starts_with(&format!("double.txt:{peak}: Normal force (N): no contact found:")), "{err}");
    }

    #[test]
    fn a_file_that_starts_at_the_peak_is_refused() {
        let mut raw = double_compression(8);
        raw.samples.drain(..2295); // start at 22.95 s, 0.05 s before the peak
        let err = refused(to_bundle(&raw, &options()));
        assert!(err.starts_with("double.txt:") && err.contains(": Normal force (N): no contact found: "), "{err}");
    }

    #[test]
    fn a_single_stroke_has_no_second() {
        let mut raw = double_compression(9);
        raw.samples.truncate(4400); // up to 44 s: stroke 1 only
        let err = refused(to_bundle(&raw, &ImportOptions { stroke: StrokeChoice::Second, ..options() }));
        assert!(err.contains("Gap (um): no second stroke"), "{err}");
        assert!(to_bundle(&raw, &options()).is_ok());
    }

    #[test]
    fn heights_given_from_a_start_height_or_refused() {
        let raw = double_compression(10);
        let h = |height| {
            to_bundle(&raw, &ImportOptions { height, ..options() })
                .map(|t| t.facts.height_mm)
                .map_err(|e| e.to_string())
        };
        assert_eq!(h(HeightSource::Given(12.5)).unwrap(), 12.5);
        let touch = to_bundle(&raw, &options()).unwrap().facts;
        let travel = 9.0 - touch.height_mm;
        assert!((h(HeightSource::StartHeight(10.0)).unwrap() - (10.0 - travel)).abs() < 1e-12);
        let e = h(HeightSource::Given(3.0)).unwrap_err();
        assert!(e.starts_with("double.txt: height: the specimen would be 3 mm high but the tool travels"), "{e}");
        let e = h(HeightSource::StartHeight(0.1)).unwrap_err();
        assert!(e.starts_with("double.txt: height: the start height 0.1 mm minus the travel"), "{e}");
        let e = h(HeightSource::Given(f64::NAN)).unwrap_err();
        assert_eq!(e, "double.txt: height: NaN is not a length > 0");
        // An Exponent file has no gap.
        let mut exp = raw.clone();
        exp.format = RawFormat::Exponent;
        let e = refused(to_bundle(&exp, &options()));
        assert!(e.starts_with("double.txt: height: an exponent file has no gap"), "{e}");
    }

    #[test]
    fn options_are_checked() {
        let raw = double_compression(11);
        let err = |o: ImportOptions| refused(to_bundle(&raw, &o));
        assert_eq!(err(ImportOptions::new("x", -1.0)), "double.txt: radius_mm: -1 is not a length > 0");
        assert_eq!(err(ImportOptions::new(" ", 1.0)), "double.txt: name: empty bundle name");
        assert!(err(ImportOptions { every: 0, ..options() }).contains("every"));
        assert!(err(ImportOptions { contact: Contact::Friction, ..options() }).contains("contact"));
        let trial = to_bundle(&raw, &ImportOptions { contact: Contact::Frictionless, ..options() }).unwrap();
        assert_eq!(trial.experiment.protocol.tool_contact, Contact::Frictionless);
        assert_eq!(trial.experiment.protocol.support, Contact::Frictionless);
    }

    #[test]
    fn hand_built_tests_are_checked_again() {
        let mut raw = double_compression(12);
        raw.samples[100].t_s = f64::NAN;
        assert_eq!(refused(to_bundle(&raw, &options())), "double.txt:102: Time (s): NaN is not finite");
        let mut raw = double_compression(12);
        raw.samples[100].t_s = 0.5;
        assert!(refused(to_bundle(&raw, &options())).contains(":102: Time (s): time goes backwards"));
        raw.samples.clear();
        assert!(to_bundle(&raw, &options()).is_err());
    }

    /// The synthetic test as a rheometer file's text.
    fn rheometer_text(raw: &RawTest) -> String {
        let mut text = String::from("Time (s)\tEncoder (rad)\tTorque (Nm)\tMarker\tNormal force (N)\tGap (um)\t\n");
        for s in &raw.samples {
            text += &format!("{}\t0\t0\t0\t{}\t{}\t\n", s.t_s, s.force_n, s.tool_mm * 1000.0);
        }
        text
    }

    /// The synthetic test as an Exponent file's text (force in g, distance from the start).
    fn exponent_text(raw: &RawTest) -> String {
        let mut text = String::from("t\tt\tt\t\r\nForce\tDistance\tTime\t\r\ng\tmm\tsec\t\r\n\t\t\t\r\n");
        let y0 = raw.samples[0].tool_mm;
        for s in &raw.samples {
            text += &format!("{}\t{}\t{}\t\r\n", s.force_n / GRAM_FORCE_N, y0 - s.tool_mm, s.t_s);
        }
        text
    }

    use crate::texture::GRAM_FORCE_N;

    #[test]
    fn both_formats_give_the_same_trial() {
        let raw = double_compression(13);
        let r = parse_rheometer(Path::new("double.txt"), &rheometer_text(&raw)).unwrap();
        let e = parse_exponent(Path::new("double.tab"), &exponent_text(&raw)).unwrap();
        let a = to_bundle(&r, &options()).unwrap();
        let b = to_bundle(&e, &ImportOptions { height: HeightSource::StartHeight(9.0), ..options() }).unwrap();
        assert_eq!(b.facts.touch_line, a.facts.touch_line + 3);
        assert!((a.facts.height_mm - b.facts.height_mm).abs() < 1e-9);
        assert!((a.facts.tare_n - b.facts.tare_n).abs() < 1e-12);
        assert_eq!(a.force.samples.len(), b.force.samples.len());
        let p = (&a.experiment.protocol, &b.experiment.protocol);
        assert_eq!((p.0.release_s, p.0.end_s), (p.1.release_s, p.1.end_s));
    }

    /// Garbled and truncated files: never a panic, always a result.
    #[test]
    fn garbled_files_never_panic() {
        let raw = double_compression(14);
        let texts = [rheometer_text(&raw), exponent_text(&raw)];
        let mut rng = Rng(77);
        let junk = ["", "\t", "\n", "\r\n", "x", "-", "1e999", "NaN", "0", "\u{feff}", "é", "(", ")", " (um)"];
        for case in 0..400 {
            let base = &texts[case % 2];
            let mut bytes = base.as_bytes().to_vec();
            match case % 4 {
                // Truncate anywhere.
                0 => bytes.truncate((rng.next_u64() % bytes.len() as u64) as usize),
                // Overwrite a few random bytes.
                1 => {
                    for _ in 0..1 + rng.next_u64() % 5 {
                        let i = (rng.next_u64() % bytes.len() as u64) as usize;
                        bytes[i] = (rng.next_u64() % 256) as u8;
                    }
                }
                // Insert junk.
                2 => {
                    let i = (rng.next_u64() % bytes.len() as u64) as usize;
                    let j = junk[(rng.next_u64() % junk.len() as u64) as usize];
                    bytes.splice(i..i, j.bytes());
                }
                // Keep a random slice of lines.
                _ => {
                    let lines: Vec<&str> = base.split('\n').collect();
                    let a = (rng.next_u64() % lines.len() as u64) as usize;
                    let b = a + (rng.next_u64() % 200) as usize;
                    bytes = lines[a..b.min(lines.len())].join("\n").into_bytes();
                }
            }
            let file = Path::new("fuzz");
            let Ok(text) = super::super::raw_test::decode(file, bytes) else { continue };
            for raw in [parse_rheometer(file, &text), parse_exponent(file, &text)].into_iter().flatten() {
                {
                    for stroke in [StrokeChoice::First, StrokeChoice::Second, StrokeChoice::All] {
                        let o = ImportOptions { stroke, height: HeightSource::Given(50.0), ..options() };
                        if let Ok(trial) = to_bundle(&raw, &o) {
                            assert!(trial.experiment.protocol.waypoints.windows(2).all(|w| w[1][0] > w[0][0]));
                            assert!(crate::bundle::force_csv(&trial.force).is_ok());
                        }
                    }
                }
            }
        }
    }

    /// Random raw tests (small, flat, spiky, constant): never a panic.
    #[test]
    fn random_raw_tests_never_panic() {
        let mut rng = Rng(5);
        for case in 0..300 {
            let n = (rng.next_u64() % 200) as usize;
            let kind = case % 5;
            let samples = (0..n)
                .map(|i| {
                    let x = i as f64;
                    let (f, y) = match kind {
                        0 => (rng.normal(), rng.normal()),
                        1 => (0.0, 0.0),
                        2 => (if i == n / 2 { 1e6 } else { 0.0 }, -x),
                        3 => (x, 10.0 - 0.01 * x),
                        _ => ((x - 50.0).max(0.0) + 0.01 * rng.normal(), 5.0 - 0.05 * (x - 100.0).abs()),
                    };
                    RawSample { line: i + 2, t_s: x * 0.1, force_n: f, tool_mm: y }
                })
                .collect();
            let raw = RawTest { file: PathBuf::from("r"), format: RawFormat::Rheometer, test_name: None, samples };
            for stroke in [StrokeChoice::First, StrokeChoice::Second, StrokeChoice::All] {
                let _ = to_bundle(&raw, &ImportOptions { stroke, every: 3, ..options() });
            }
        }
    }
}
