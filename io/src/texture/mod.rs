//! Texture-analyser raw files into experiment bundles (`wagashi import`).
//!
//! - [`read_exponent`] reads a Stable Micro Systems Exponent text export and
//!   [`read_rheometer`] a TA Instruments rheometer text export into a
//!   [`RawTest`]: time [s], force [N] and tool position [mm] per row, with the
//!   row's line. Their modules give each format exactly ([`exponent`],
//!   [`rheometer`]).
//! - [`to_bundle`] finds the tare, the noise and first touch, splits the test
//!   into strokes and builds an [`ImportedTrial`]: `experiment.toml` (as an
//!   [`Experiment`](crate::Experiment)) and `force.csv` (as a
//!   [`ForceSeries`](crate::ForceSeries)); [`ImportedTrial::write`] writes them.
//!
//! Every refusal is an [`ImportError`], displayed `FILE:LINE: FIELD: CAUSE` with
//! `FIELD` the column as the file names it (`Gap (um)`, `Force`), or `header`,
//! `units`, `row`: a wrong header, a wrong unit, a non-numeric or non-finite cell,
//! a row with the wrong number of cells, time going backwards (or repeating), an
//! empty file, no contact found, no second stroke. No input makes these functions
//! panic; reading never modifies the file.
//!
//! # The rules
//!
//! Units: s, N, mm throughout; the Exponent's grams-force become N with
//! 1 g = 9.80665e-3 N, the rheometer's gap (um) becomes mm.
//!
//! 1. **Tare, noise, first touch** ([`detect_touch`], module [`touch`]): the
//!    pre-contact segment is the rows before the force rises; the tare is its
//!    mean, the noise sigma its 1.4826 x median absolute deviation. First touch
//!    is where the force, having risen above `tare + max(5 sigma, 1 % of the
//!    peak)` and staying above it up to half the peak, last lay inside the noise
//!    band `tare + 2 sigma`; a contact keeps the force above the threshold for
//!    at least 10 rows. Time `t = 0` is first touch: every time in the
//!    bundle is from it, and rows before it are dropped. No rise above the
//!    threshold, or no quiet segment before it, is "no contact found".
//! 2. **Displacement**: `d(t) = position(touch) - position(t)`, downward from
//!    first touch, compression positive; `position` is the gap (rheometer) or
//!    minus the distance travelled (Exponent).
//! 3. **Strokes** ([`find_stroke`], module [`stroke`]): a stroke pushes, peaks
//!    and ends when the tool is back at its first-touch position (within the
//!    waypoint tolerance), when it turns down again first, or at the file's end.
//!    A double compression (texture-profile analysis) has two.
//! 4. **Window** ([`StrokeChoice`]): stroke 1 (default) runs from first touch
//!    to the end of the first unloading; stroke 2 from there to the end of the
//!    second unloading, its times still from the *first* touch, so that it stays
//!    one physical test (the waypoints then start at the window's start, with
//!    the tool about back at the first-touch position; the residual deformation
//!    of stroke 1 is in the measured force, not in the bundle); `all` is the
//!    whole test from first touch.
//! 5. **Separation** (`release_s`): for stroke 1 or 2, the first row after the
//!    window's force peak where the tared force is back inside the noise band
//!    (`<= 2 sigma`): the plate has left the specimen (the specimen recovers
//!    more slowly than the plate rises). If the force never comes back, the
//!    window's end. For `all`, the end of the test: the bundle then describes
//!    the whole double compression, which the engine can simulate only once it
//!    models a plate that leaves and touches again (contact).
//! 6. **Waypoints**: `[t_s, d_mm]` from the window's start to the separation (the
//!    format refuses a tool that moves after `release_s`; once separated the
//!    plate no longer acts on the specimen), simplified by Douglas-Peucker on
//!    the vertical error ([`simplify`]) with tolerance `max(1 um, 0.1 % of the
//!    largest displacement after touch)`. The curve simplified is the position's
//!    updates: the rows where it changes (and the window's first row and the
//!    separation's). Instruments log faster than they update or resolve the
//!    position (the rheometer's gap changes every ~20 ms, the Exponent's distance
//!    in 1 um steps), and a repeated value is the last reading held, not a
//!    measurement; kept, its staircase would cost hundreds of waypoints. Every
//!    update lies within the tolerance of the waypoints' polyline; a held row
//!    lies within the tolerance plus one update step. Times strictly increase.
//!    `end_s` is the window's end.
//! 7. **Specimen** ([`HeightSource`]): a cylinder of the given radius. Its
//!    height is given, or the gap at first touch (rheometer), or a start height
//!    minus the tool's travel from the first row to first touch (the Exponent's
//!    `Distance` is relative, so an Exponent file needs one of the two). A
//!    window in which the tool travels the whole height is refused.
//! 8. **Bundle**: `format = "wagashi-experiment/1"`, `dimension = 3`,
//!    `[specimen] shape = "cylinder"`, `radius_mm`, `height_mm`, `material`
//!    (default `"sample"`; no `[materials]` table: it comes from `--materials`
//!    or a fit, so [`crate::read_bundle`] needs it from outside:
//!    [`crate::read_bundle_with`]); `[protocol] tool = "plate"`, `tool_contact`
//!    and `support` both glued by default (food sticks to the plates in these
//!    tests and the friction of the plates is not known; frictionless is the
//!    other bound), the waypoints, `release_s`, `end_s`; `[data] force =
//!    "force.csv"`, `force_tared = true`. `force.csv` (`t_s,force_N`) holds
//!    the tared force over the window, compression positive, every row or every
//!    `every`-th. `[extra.import]` records what was detected ([`ImportFacts`]):
//!    the tare and noise, the touch in the raw file's clock and line, the
//!    height's source, the speed read from the displacement (least squares over
//!    10-90 % of the first stroke's travel), the separation, the window.
//!
//! # Texture-profile analysis
//!
//! [`tpa`] reduces a double compression (a raw export, a bundle's or a press
//! output's `force.csv`) to hardness, cohesiveness, springiness, resilience,
//! gumminess, chewiness and adhesiveness ([`analyse`], [`read_tpa_record`]); its
//! module docs give the definitions (`wagashi tpa`).
//!
//! # Example
//!
//! ```
//! use std::path::Path;
//! use wagashi_io::texture::{parse_rheometer, to_bundle, HeightSource, ImportOptions};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // 2 s at rest touching, then 0.2 mm/s down for 10 s and back up; force 0.5 N/mm.
//! let mut text = String::from("Time (s)\tNormal force (N)\tGap (um)\n");
//! for i in 0..=3000 {
//!     let t = i as f64 * 0.01;
//!     let d: f64 = if t < 2.0 { 0.0 } else if t < 12.0 { 0.2 * (t - 2.0) } else { (2.0 - 0.2 * (t - 12.0)).max(-0.5) };
//!     let noise = 0.001 * ((i * 7919) % 13) as f64 / 13.0;
//!     text += &format!("{t}\t{}\t{}\n", 0.05 + 0.5 * d.max(0.0) + noise, 9000.0 - 1000.0 * d);
//! }
//! let raw = parse_rheometer(Path::new("demo.txt"), &text)?;
//! let trial = to_bundle(&raw, &ImportOptions::new("demo", 4.0))?;
//! assert_eq!(trial.experiment.specimen.height_mm, Some(9.0)); // the gap at touch
//! let touch = trial.facts.touch_raw_s;
//! assert!((touch - 2.0).abs() < 0.05, "{touch}");
//! assert!((trial.facts.speed_mm_s.unwrap() - 0.2).abs() < 1e-3);
//! let dir = tempfile::tempdir()?;
//! trial.write(dir.path())?;
//! # Ok(()) }
//! ```

mod error;
pub mod exponent;
mod imported_trial;
mod raw_test;
pub mod rheometer;
pub mod simplify;
pub mod stroke;
pub mod touch;
pub mod tpa;

pub use error::ImportError;
pub use exponent::{parse_exponent, read_exponent, GRAM_FORCE_N};
pub use imported_trial::{
    to_bundle, HeightSource, ImportFacts, ImportOptions, ImportedTrial, StrokeChoice, STROKE_HYSTERESIS_FRACTION,
    WAYPOINT_TOLERANCE_FRACTION, WAYPOINT_TOLERANCE_MM,
};
pub use raw_test::{RawFormat, RawSample, RawTest};
pub use rheometer::{parse_rheometer, read_rheometer};
pub use simplify::simplify;
pub use stroke::{find_stroke, Stroke, StrokeEnd};
pub use touch::{detect_touch, NoTouch, TouchDetection};
pub use tpa::{analyse, read_tpa_record, Tpa, TpaError, TpaOptions, TpaRecord, TpaStroke};
