//! What a run reports: `summary.json` ([`Summary`]) and `steps.csv` ([`steps_csv`]).
//!
//! Keys name their units as the bundle format does (`_s`, `_mm`, `_N`).

use std::fmt::Write as _;

use fem_core::press::StepRecord;
use serde::Serialize;
use wagashi_io::ForceSeries;

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The version of the `wagashi` that wrote it.
    pub wagashi_version: &'static str,
    /// The input bundle's `name`.
    pub name: String,
    /// The input bundle's folder, as given.
    pub input: String,
    /// The output folder, as given.
    pub output: String,
    /// 2 or 3 (2 for the axisymmetric section of a cylinder).
    pub dimension: usize,
    /// `solid`, `plane-stress`, `plane-strain` or `axisymmetric` (`--axisymmetric`).
    pub formulation: &'static str,
    /// Number of cells (triangles or tetrahedra).
    pub cells: usize,
    /// Number of nodes.
    pub nodes: usize,
    /// Free degrees of freedom (largest constraint set).
    pub free_dofs: usize,
    /// `implicit`, `dynamic` or `seed`.
    pub integrator: &'static str,
    /// Relative tolerance of the adaptive steps.
    pub rtol: f64,
    /// Fixed time step [s]; null: adaptive.
    pub dt_s: Option<f64>,
    /// Target element size [mm].
    pub size_mm: f64,
    /// How a `shape = "surface"` specimen was meshed on the fly: `"conforming"`
    /// or `"envelope"`; absent for blocks and cylinders.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_mesh_mode: Option<&'static str>,
    /// Accepted time steps.
    pub steps: usize,
    /// Numeric factorizations.
    pub factorizations: usize,
    /// Nonzeros of the largest Cholesky factor.
    pub factor_nonzeros: usize,
    /// Wall time of the simulation alone [s].
    pub wall_time_s: f64,
    /// Wall time from the bundle read to the last output file [s].
    pub total_time_s: f64,
    /// Largest bottom force over the steps [N].
    #[serde(rename = "peak_force_N")]
    pub peak_force_n: f64,
    /// Bottom force at the end of the hold (`keep_time_s`) [N].
    #[serde(rename = "force_end_of_hold_N")]
    pub force_end_of_hold_n: f64,
    /// Minus the mean y displacement of the top face at `keep_time_s` [mm] (mean
    /// over the top nodes; area-weighted for an axisymmetric section).
    pub keep_height_loss_mm: f64,
    /// Minus the mean y displacement of the top face at `final_time_s` [mm] (as above).
    pub final_height_loss_mm: f64,
    /// Time of the keep shape: `release_s` (or `end_s` when that comes first) [s].
    pub keep_time_s: f64,
    /// Time of the final shape: `end_s` [s].
    pub final_time_s: f64,
    /// A protocol of two or more strokes: each stroke's peak and the shape after
    /// it (`strokeN-peak.vtu`, `strokeN-after.vtu`); empty otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub strokes: Vec<StrokeShape>,
    /// Rows of the written `force.csv`.
    pub force_samples: usize,
    /// Markers in the written `markers.csv`.
    pub markers: usize,
    /// Rows of the input's measured force; null: none measured.
    pub measured_force_samples: Option<usize>,
    /// Root mean square of simulated minus measured force at the measured times [N];
    /// null: none measured.
    #[serde(rename = "force_rms_diff_N")]
    pub force_rms_diff_n: Option<f64>,
    /// Largest |simulated - measured| force at the measured times [N]; null: none measured.
    #[serde(rename = "force_max_abs_diff_N")]
    pub force_max_abs_diff_n: Option<f64>,
    /// The files written, relative to the output folder.
    pub files: Vec<String>,
}

/// One stroke of a protocol with several: the plate at its deepest, and back.
#[derive(Debug, Clone, Serialize)]
pub struct StrokeShape {
    /// The end of the stroke's push (the plate deepest) [s].
    pub peak_t_s: f64,
    /// The bottom force then [N].
    #[serde(rename = "peak_force_N")]
    pub peak_force_n: f64,
    /// The height loss then [mm] (as `keep_height_loss_mm`).
    pub peak_height_loss_mm: f64,
    /// The end of the plate's retreat after it (or `end_s`) [s].
    pub after_t_s: f64,
    /// The height loss then [mm].
    pub after_height_loss_mm: f64,
}

impl Summary {
    /// Pretty-printed JSON with a final newline.
    pub fn to_json(&self) -> serde_json::Result<String> {
        Ok(serde_json::to_string_pretty(self)? + "\n")
    }
}

/// Simulated against measured force at the same times.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceComparison {
    /// Root mean square difference [N].
    pub rms_n: f64,
    /// Largest absolute difference [N].
    pub max_abs_n: f64,
}

impl ForceComparison {
    /// Compares `simulated` with `measured` sample by sample (the simulated series
    /// is sampled at the measured times).
    pub fn new(simulated: &ForceSeries, measured: &ForceSeries) -> Self {
        assert_eq!(simulated.samples.len(), measured.samples.len(), "sampled at the measured times");
        let diffs = simulated.samples.iter().zip(&measured.samples).map(|(s, m)| s.force_n - m.force_n);
        let (sum_sq, max_abs) = diffs.fold((0.0, 0.0f64), |(sq, mx), d| (sq + d * d, mx.max(d.abs())));
        let n = measured.samples.len().max(1) as f64;
        Self { rms_n: (sum_sq / n).sqrt(), max_abs_n: max_abs }
    }
}

/// The header of `steps.csv`.
pub const STEPS_HEADER: &str = "t_s,dt_s,solve_s,residual,refactored,bottom_force_N,plate_force_N";

/// `steps.csv`: one row per accepted step; `refactored` is 1 or 0.
pub fn steps_csv(steps: &[StepRecord]) -> String {
    let mut out = String::with_capacity(96 * (steps.len() + 1));
    out.push_str(STEPS_HEADER);
    out.push('\n');
    for s in steps {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{}",
            number(s.t_s),
            number(s.dt_s),
            number(s.solve_s),
            number(s.residual),
            u8::from(s.refactored),
            number(s.bottom_force_n),
            number(s.plate_force_n)
        );
    }
    out
}

/// The shortest text that reads back to `x`, in exponent form for very small or
/// large magnitudes.
pub(crate) fn number(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && !(1e-4..1e15).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wagashi_io::ForceSample;

    #[test]
    fn numbers_read_back_exactly() {
        for x in [0.0, 1.0, -2.5, 0.1, 1e-17, 3.25e-5, 123456.789, 1e20, f64::MIN_POSITIVE] {
            let s = number(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(number(1e-17), "1e-17");
        assert_eq!(number(0.25), "0.25");
    }

    #[test]
    fn steps_csv_has_one_row_per_step() {
        let step = StepRecord {
            t_s: 0.5,
            dt_s: 0.5,
            solve_s: 1e-3,
            residual: 1e-16,
            refactored: true,
            bottom_force_n: 1.5,
            plate_force_n: 1.25,
            error_ratio: 0.1,
            newton_iterations: 0,
        };
        let csv = steps_csv(&[step.clone(), StepRecord { refactored: false, ..step }]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines, [STEPS_HEADER, "0.5,0.5,0.001,1e-16,1,1.5,1.25", "0.5,0.5,0.001,1e-16,0,1.5,1.25"]);
    }

    #[test]
    fn comparison_is_rms_and_max() {
        let series = |f: &[f64]| ForceSeries {
            samples: f.iter().enumerate().map(|(i, &f)| ForceSample { t_s: i as f64, force_n: f }).collect(),
        };
        let c = ForceComparison::new(&series(&[1.0, 2.0, 3.0, 4.0]), &series(&[1.0, 1.0, 3.0, 5.0]));
        assert!((c.rms_n - (2.0f64 / 4.0).sqrt()).abs() < 1e-15);
        assert_eq!(c.max_abs_n, 1.0);
    }
}
