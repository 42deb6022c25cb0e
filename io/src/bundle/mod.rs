//! Experiment bundles (experiment-format.md, version 1): a folder holding
//! `experiment.toml` and the CSV files it names.
//!
//! - [`read_bundle`] / [`read_bundle_with`] read and check a bundle into a
//!   [`Bundle`]; [`read_bundle_from_str`] does the same for an `experiment.toml`
//!   given as text (a bundle embedded in a binary); [`read_materials_file`] reads
//!   a `--materials FILE`.
//! - [`Bundle::to_press`] builds the engine's press problem.
//! - [`write_bundle`] writes a simulation's results as a bundle.
//!
//! Every refusal names the file, the line and the field: `FILE:LINE: FIELD: CAUSE`
//! ([`crate::BundleError`]). Reading never modifies the bundle.
//!
//! ## Project extensions and choices beyond the format
//!
//! - `[specimen] density_g_cm3` (optional, > 0) and `[protocol] gravity` (optional,
//!   default false).
//! - `[specimen] plane = "stress" | "strain"` (optional, `dimension = 2` only;
//!   default `"stress"`, the seed's plane stress with thickness T).
//! - Required keys: `format`, `name`, `dimension`, `[specimen] shape`, the shape's
//!   size keys (`size_mm`; `radius_mm` and `height_mm`; `surface`), a block's
//!   `material` or `[[specimen.layers]]` (not both), a cylinder's `material`, a
//!   surface's `[specimen.regions]` (or `material`), and `[protocol] tool`,
//!   `tool_contact`, `support`, `waypoints`, `release_s`, `end_s`;
//!   `tool_radius_mm` for a sphere or punch, `tool_surface` for a surface tool,
//!   `friction` when a contact is `"friction"`. A key that belongs to another
//!   shape, tool or contact is refused.
//! - Times (waypoints, `release_s`, `end_s`, CSV `t_s`) must not be negative;
//!   `release_s` and `end_s` must be > 0.
//! - "The specimen's smallest size" of the marker check is min(W, H, T) for a
//!   block (in 2D too) and min(2R, H) for a cylinder; in 3D the distance is to the
//!   surface of the box or cylinder, in 2D to the rectangle `[0, W] x [0, H]`.
//! - Markers of a `surface` specimen are not checked against the surface (this
//!   crate does not load surfaces yet).
//! - A material in a `--materials` file replaces the bundle's table of the same name.

mod experiment;
mod material_spec;
mod read;
mod series;
mod to_press;
mod validate;
mod write;

pub use experiment::{Contact, DataSpec, Experiment, Layer, Plane, ProtocolSpec, Shape, Specimen, Tool, FORMAT_V1};
pub use material_spec::{read_materials_file, MaterialSpec, MissingParameter, Model};
pub use read::{read_bundle, read_bundle_from_str, read_bundle_with, Bundle, EXPERIMENT_FILE};
pub use series::{markers_header, ForceSample, ForceSeries, MarkerSample, MarkerSeries, FORCE_HEADER};
pub use to_press::G_CM3_IN_T_MM3;
pub use validate::{LAYER_SUM_TOLERANCE_MM, MARKER_SURFACE_TOLERANCE};
pub use write::{experiment_toml, force_csv, markers_csv, write_bundle, BundleWrite, FORCE_FILE, MARKERS_FILE};
