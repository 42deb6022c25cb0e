//! Writing a bundle: a simulated trial in the same form as a measured one, so
//! that it reads back with [`super::read_bundle`].
//!
//! `experiment.toml` repeats the input's specimen, materials (external ones
//! merged in, so the output is self-contained), protocol and `[extra]`, under a
//! new `name`, with `[data] force = "force.csv"` and, when there are markers,
//! `markers = "markers.csv"`. Numbers are written in their shortest form that
//! reads back to the same `f64`. Every file is written atomically.

use std::fmt::Write as _;
use std::path::Path;

use super::experiment::{DataSpec, Experiment};
use super::read::{Bundle, EXPERIMENT_FILE};
use super::series::{markers_header, ForceSeries, MarkerSeries, FORCE_HEADER};
use crate::atomic::write_atomic;
use crate::error::WriteError;
use crate::number::push_shortest;

/// The force file a written bundle names.
pub const FORCE_FILE: &str = "force.csv";
/// The markers file a written bundle names.
pub const MARKERS_FILE: &str = "markers.csv";

/// What [`write_bundle`] writes.
#[derive(Debug, Clone, Copy)]
pub struct BundleWrite<'a> {
    /// The trial: specimen, materials, protocol and `[extra]` are copied; `name`
    /// and `[data]` are replaced.
    pub experiment: &'a Experiment,
    /// The written bundle's `name`.
    pub name: &'a str,
    /// The force series, written to `force.csv`; `None`: no force file.
    pub force: Option<&'a ForceSeries>,
    /// The markers, written to `markers.csv` when not empty. [`super::read_bundle`]
    /// needs each to have a row at `t_s = 0`.
    pub markers: &'a [MarkerSeries],
    /// `[data] force_tared`; `None`: not stated.
    pub force_tared: Option<bool>,
}

impl<'a> BundleWrite<'a> {
    /// A simulation's results for `input`, named `name` (e.g. `format!("{}-sim",
    /// input.experiment.name)`). `force_tared` is true when gravity is off (the
    /// simulated force then holds no weight, as a tared sensor's): neither
    /// `[protocol] gravity` nor a non-zero `[effects] gravity` factor.
    pub fn simulated(input: &'a Bundle, name: &'a str, force: &'a ForceSeries, markers: &'a [MarkerSeries]) -> Self {
        Self {
            experiment: &input.experiment,
            name,
            force: Some(force),
            markers,
            force_tared: Some(
                !(input.experiment.protocol.gravity
                    || input.experiment.effects.get("gravity").is_some_and(|&f| f != 0.0)),
            ),
        }
    }

    /// The `experiment.toml` to be written.
    pub fn experiment(&self) -> Experiment {
        let mut e = self.experiment.clone();
        e.name = self.name.to_string();
        let data = DataSpec {
            force: self.force.map(|_| FORCE_FILE.to_string()),
            markers: (!self.markers.is_empty()).then(|| MARKERS_FILE.to_string()),
            force_tared: self.force_tared,
        };
        e.data = (data != DataSpec::default()).then_some(data);
        e
    }
}

fn bad(path: &Path, cause: String) -> WriteError {
    WriteError::BadInput { path: path.to_path_buf(), cause }
}

/// `experiment` as TOML text.
pub fn experiment_toml(experiment: &Experiment) -> Result<String, WriteError> {
    let body = toml::to_string(experiment).map_err(|e| bad(Path::new(EXPERIMENT_FILE), e.to_string()))?;
    Ok(format!("# wagashi experiment bundle ({})\n{body}", super::experiment::FORMAT_V1))
}

/// `force.csv` text; refuses non-finite values (they would not read back).
pub fn force_csv(force: &ForceSeries) -> Result<String, WriteError> {
    let mut out = String::with_capacity(32 * (force.samples.len() + 1));
    out.push_str(&FORCE_HEADER.join(","));
    out.push('\n');
    for s in &force.samples {
        if !(s.t_s.is_finite() && s.force_n.is_finite()) {
            return Err(bad(
                Path::new(FORCE_FILE),
                format!("non-finite sample t_s = {}, force_N = {}", s.t_s, s.force_n),
            ));
        }
        push_shortest(&mut out, s.t_s);
        out.push(',');
        push_shortest(&mut out, s.force_n);
        out.push('\n');
    }
    Ok(out)
}

/// `markers.csv` text for `dimension` 2 or 3; refuses positions of another
/// dimension, non-finite values and names that CSV would need to quote.
pub fn markers_csv(markers: &[MarkerSeries], dimension: usize) -> Result<String, WriteError> {
    let path = Path::new(MARKERS_FILE);
    let mut out = String::new();
    out.push_str(&markers_header(dimension).join(","));
    out.push('\n');
    for m in markers {
        if m.name.is_empty() || m.name.trim() != m.name || m.name.contains([',', '"', '\n', '\r']) {
            return Err(bad(path, format!("marker name {:?} cannot be written unquoted", m.name)));
        }
        for s in &m.samples {
            if s.position_mm.len() != dimension {
                return Err(bad(
                    path,
                    format!(
                        "marker `{}` at t = {} s has {} coordinates; dimension is {dimension}",
                        m.name,
                        s.t_s,
                        s.position_mm.len()
                    ),
                ));
            }
            if !(s.t_s.is_finite() && s.position_mm.iter().all(|x| x.is_finite())) {
                return Err(bad(path, format!("marker `{}` has a non-finite value at t = {} s", m.name, s.t_s)));
            }
            let _ = write!(out, "{},", m.name);
            push_shortest(&mut out, s.t_s);
            for &x in &s.position_mm {
                out.push(',');
                push_shortest(&mut out, x);
            }
            out.push('\n');
        }
    }
    Ok(out)
}

/// Writes the bundle into `dir` (created if missing): `experiment.toml`,
/// `force.csv` and `markers.csv`, each atomically.
pub fn write_bundle(dir: impl AsRef<Path>, bundle: &BundleWrite<'_>) -> Result<(), WriteError> {
    let dir = dir.as_ref();
    let experiment = bundle.experiment();
    let dimension = experiment.dimension as usize;
    // Build every text first, so that bad input writes nothing.
    let toml_text = experiment_toml(&experiment)?;
    let force_text = bundle.force.map(force_csv).transpose()?;
    let markers_text = (!bundle.markers.is_empty()).then(|| markers_csv(bundle.markers, dimension)).transpose()?;
    std::fs::create_dir_all(dir).map_err(|e| WriteError::io(dir, e))?;
    if let Some(text) = force_text {
        write_atomic(dir.join(FORCE_FILE), text.as_bytes())?;
    }
    if let Some(text) = markers_text {
        write_atomic(dir.join(MARKERS_FILE), text.as_bytes())?;
    }
    write_atomic(dir.join(EXPERIMENT_FILE), toml_text.as_bytes())
}
