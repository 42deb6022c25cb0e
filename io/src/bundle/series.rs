//! The measured (or simulated) series: `force.csv` and `markers.csv`.
//!
//! Both files are plain CSV with the exact headers `t_s,force_N` and
//! `marker,t_s,x_mm,y_mm,z_mm` (`z_mm` omitted in 2D); cells may be padded with
//! spaces and blank lines are skipped. Refused, with `FILE:LINE: COLUMN: CAUSE`:
//! a bad header, a row with the wrong number of cells, a cell that is not a number,
//! NaN or infinity, a negative time, time going backwards (in `force.csv`, equal
//! times are accepted; a marker may not have two rows at one time), a marker
//! without a row at `t_s = 0`.

use std::path::Path;

use fem_core::press::{MarkerTrack, PressResult};

use crate::error::BundleError;

/// One force sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceSample {
    /// Time [s].
    pub t_s: f64,
    /// Force on the bottom sensor, compression positive [N].
    pub force_n: f64,
}

/// `force.csv`: the force on the bottom sensor in time order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ForceSeries {
    /// Samples in non-decreasing time.
    pub samples: Vec<ForceSample>,
}

/// One measured (or simulated) marker position.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerSample {
    /// Time [s].
    pub t_s: f64,
    /// Position [mm], `dimension` components (x, y[, z]).
    pub position_mm: Vec<f64>,
}

/// One marker of `markers.csv`: a material point on the specimen's surface.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerSeries {
    /// The marker's name (`marker` column).
    pub name: String,
    /// Its rows in increasing time; the first is at `t_s = 0` and gives the
    /// initial position, which fixes the material point.
    pub samples: Vec<MarkerSample>,
}

impl MarkerSeries {
    /// The initial position [mm] (the row at `t_s = 0`), or `None` when the series is empty.
    pub fn initial_position(&self) -> Option<&[f64]> {
        self.samples.first().filter(|s| s.t_s == 0.0).map(|s| s.position_mm.as_slice())
    }

    /// The marker tracks of a run, as series.
    pub fn from_tracks(tracks: &[MarkerTrack]) -> Vec<MarkerSeries> {
        tracks
            .iter()
            .map(|t| MarkerSeries {
                name: t.name.clone(),
                samples: t.samples.iter().map(|(t_s, p)| MarkerSample { t_s: *t_s, position_mm: p.clone() }).collect(),
            })
            .collect()
    }
}

impl ForceSeries {
    /// The bottom force of a run at `t = 0` (zero) and at every step end.
    pub fn from_steps(result: &PressResult) -> Self {
        let mut samples = vec![ForceSample { t_s: 0.0, force_n: 0.0 }];
        samples.extend(result.steps.iter().map(|s| ForceSample { t_s: s.t_s, force_n: s.bottom_force_n }));
        Self { samples }
    }

    /// The bottom force of a run sampled at `times` [s] (exact inside each
    /// quasi-static step, see [`PressResult::bottom_force_at`]).
    pub fn sampled(result: &PressResult, times: &[f64]) -> Self {
        Self { samples: times.iter().map(|&t| ForceSample { t_s: t, force_n: result.bottom_force_at(t) }).collect() }
    }
}

/// The CSV header of `force.csv`.
pub const FORCE_HEADER: [&str; 2] = ["t_s", "force_N"];

/// The CSV header of `markers.csv` in `dimension` 2 or 3.
pub fn markers_header(dimension: usize) -> &'static [&'static str] {
    const H: [&str; 5] = ["marker", "t_s", "x_mm", "y_mm", "z_mm"];
    if dimension == 2 {
        &H[..4]
    } else {
        &H
    }
}

/// The rows of a CSV file whose header must be `header`: `(line, cells)`.
fn read_rows(file: &Path, header: &[&str]) -> Result<Vec<(usize, Vec<String>)>, BundleError> {
    let bytes = crate::input::read(file).map_err(|source| BundleError::Read { file: file.to_path_buf(), source })?;
    let invalid = |line: usize, field: &str, cause: String| BundleError::Invalid {
        file: file.to_path_buf(),
        line,
        field: field.to_string(),
        cause,
    };
    let mut reader =
        csv::ReaderBuilder::new().has_headers(false).flexible(true).trim(csv::Trim::All).from_reader(bytes.as_slice());
    // csv positions a record after blank lines at the first of them: step over them.
    let line_of = |pos: &csv::Position| {
        let mut line = pos.line() as usize;
        for &b in bytes.get(pos.byte() as usize..).unwrap_or_default() {
            match b {
                b'\n' => line += 1,
                b'\r' => {}
                _ => break,
            }
        }
        line
    };
    let mut rows = Vec::new();
    let mut record = csv::StringRecord::new();
    let mut seen_header = false;
    loop {
        let more = reader.read_record(&mut record).map_err(|e| {
            let line = e.position().map_or(1, line_of);
            match e.kind() {
                csv::ErrorKind::Utf8 { .. } => invalid(line, "row", "not valid UTF-8".into()),
                _ => invalid(line, "row", e.to_string()),
            }
        })?;
        if !more {
            break;
        }
        let line = record.position().map_or(1, line_of);
        let cells: Vec<String> = record.iter().map(str::to_string).collect();
        if !seen_header {
            if cells != header {
                return Err(invalid(
                    line,
                    "header",
                    format!("bad header \"{}\"; expected \"{}\"", cells.join(","), header.join(",")),
                ));
            }
            seen_header = true;
            continue;
        }
        if cells.len() != header.len() {
            return Err(invalid(
                line,
                "row",
                format!("{} cells; expected {} ({})", cells.len(), header.len(), header.join(",")),
            ));
        }
        rows.push((line, cells));
    }
    if !seen_header {
        return Err(invalid(1, "header", format!("the file is empty; expected the header \"{}\"", header.join(","))));
    }
    Ok(rows)
}

/// A finite number from a cell, or the error naming the column.
fn number(file: &Path, line: usize, column: &str, cell: &str) -> Result<f64, BundleError> {
    let invalid =
        |cause: String| BundleError::Invalid { file: file.to_path_buf(), line, field: column.to_string(), cause };
    let x: f64 = cell.parse().map_err(|_| invalid(format!("not a number: \"{cell}\"")))?;
    if !x.is_finite() {
        return Err(invalid(format!("not a finite number: \"{cell}\"")));
    }
    Ok(x)
}

fn time(file: &Path, line: usize, cell: &str) -> Result<f64, BundleError> {
    let t = number(file, line, "t_s", cell)?;
    if t < 0.0 {
        return Err(BundleError::Invalid {
            file: file.to_path_buf(),
            line,
            field: "t_s".into(),
            cause: format!("negative time {t} s"),
        });
    }
    Ok(t)
}

/// Reads `force.csv`.
pub(crate) fn read_force(file: &Path) -> Result<ForceSeries, BundleError> {
    let mut samples: Vec<ForceSample> = Vec::new();
    for (line, cells) in read_rows(file, &FORCE_HEADER)? {
        let t_s = time(file, line, &cells[0])?;
        let force_n = number(file, line, "force_N", &cells[1])?;
        if let Some(prev) = samples.last() {
            if t_s < prev.t_s {
                return Err(BundleError::Invalid {
                    file: file.to_path_buf(),
                    line,
                    field: "t_s".into(),
                    cause: format!("time goes backwards: {t_s} s after {} s", prev.t_s),
                });
            }
        }
        samples.push(ForceSample { t_s, force_n });
    }
    Ok(ForceSeries { samples })
}

/// Reads `markers.csv` for a specimen of `dimension` 2 or 3; returns each marker
/// (in order of first appearance) with the line of its first row.
pub(crate) fn read_markers(file: &Path, dimension: usize) -> Result<Vec<(MarkerSeries, usize)>, BundleError> {
    let header = markers_header(dimension);
    let mut out: Vec<(MarkerSeries, usize)> = Vec::new();
    for (line, cells) in read_rows(file, header)? {
        let invalid = |field: &str, cause: String| BundleError::Invalid {
            file: file.to_path_buf(),
            line,
            field: field.to_string(),
            cause,
        };
        let name = &cells[0];
        if name.is_empty() {
            return Err(invalid("marker", "empty marker name".into()));
        }
        let t_s = time(file, line, &cells[1])?;
        let mut position_mm = Vec::with_capacity(dimension);
        for (k, cell) in cells[2..].iter().enumerate() {
            position_mm.push(number(file, line, header[2 + k], cell)?);
        }
        let i = match out.iter().position(|(m, _)| m.name == *name) {
            Some(i) => i,
            None => {
                out.push((MarkerSeries { name: name.clone(), samples: Vec::new() }, line));
                out.len() - 1
            }
        };
        let marker = &mut out[i].0;
        if let Some(prev) = marker.samples.last() {
            if t_s < prev.t_s {
                return Err(invalid(
                    "t_s",
                    format!("time goes backwards for marker `{name}`: {t_s} s after {} s", prev.t_s),
                ));
            }
            if t_s == prev.t_s {
                return Err(invalid("t_s", format!("marker `{name}` has a second row at t_s = {t_s} s")));
            }
        }
        marker.samples.push(MarkerSample { t_s, position_mm });
    }
    for (marker, first_line) in &out {
        if marker.initial_position().is_none() {
            return Err(BundleError::Invalid {
                file: file.to_path_buf(),
                line: *first_line,
                field: "t_s".into(),
                cause: format!(
                    "marker `{}` has no row at t_s = 0 (its initial position); its first row is at {} s",
                    marker.name, marker.samples[0].t_s
                ),
            });
        }
    }
    Ok(out)
}
