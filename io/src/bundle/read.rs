//! Reading a bundle folder: `experiment.toml` and the CSV files it names.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::confine::confine_paths;
use super::experiment::Experiment;
use super::material_spec::{attach_origins, MaterialSpec};
use super::series::{read_force, read_markers, ForceSeries, MarkerSeries};
use super::validate::{merge_materials, validate_experiment, validate_marker_positions};
use crate::error::BundleError;
use crate::source_map::SourceMap;

/// The name of a bundle's description file.
pub const EXPERIMENT_FILE: &str = "experiment.toml";

/// A read and checked experiment bundle.
///
/// Built only by [`read_bundle`] / [`read_bundle_with`], so that every value in
/// it has passed the checks of experiment-format.md and errors found later (by
/// [`Bundle::to_press`]) can still name the file and line.
#[derive(Debug, Clone)]
pub struct Bundle {
    /// The folder, as the caller gave it.
    pub dir: PathBuf,
    /// `experiment.toml`, with any external materials merged in.
    pub experiment: Experiment,
    /// `force.csv` (or whatever `[data] force` names), if any.
    pub force: Option<ForceSeries>,
    /// The markers of `markers.csv`, in order of first appearance; empty when none.
    pub markers: Vec<MarkerSeries>,
    pub(crate) map: Arc<SourceMap>,
}

impl Bundle {
    /// The path of `experiment.toml` (the folder joined with the file name).
    pub fn experiment_file(&self) -> PathBuf {
        self.dir.join(EXPERIMENT_FILE)
    }

    /// The spatial dimension, 2 or 3.
    pub fn dimension(&self) -> usize {
        self.experiment.dimension as usize
    }

    /// The line of `field` (a TOML key path) in `experiment.toml`, or of its
    /// nearest enclosing table; 1 when neither is written.
    pub fn line_of(&self, field: &str) -> usize {
        self.map.line(field)
    }

    /// The marker named `name`.
    pub fn marker(&self, name: &str) -> Option<&MarkerSeries> {
        self.markers.iter().find(|m| m.name == name)
    }
}

/// Reads and checks the bundle in `dir`. Nothing in the folder is modified.
pub fn read_bundle(dir: impl AsRef<Path>) -> Result<Bundle, BundleError> {
    read_bundle_with(dir, &BTreeMap::new())
}

/// Reads the bundle in `dir` with materials from elsewhere (e.g.
/// [`super::read_materials_file`]); a material of `external` replaces the bundle's
/// own table of the same name. References are checked after the merge.
pub fn read_bundle_with(
    dir: impl AsRef<Path>,
    external: &BTreeMap<String, MaterialSpec>,
) -> Result<Bundle, BundleError> {
    let dir = dir.as_ref();
    let file = dir.join(EXPERIMENT_FILE);
    let text =
        crate::input::read_to_string(&file).map_err(|source| BundleError::Read { file: file.clone(), source })?;
    read_bundle_from_str(dir, &text, external)
}

/// Reads a bundle whose `experiment.toml` is the text `experiment_toml` (e.g.
/// embedded in a binary with `include_str!`), as if it stood in `dir`: messages
/// name `dir/experiment.toml`, and the data files it names are read from `dir`
/// (a bundle without `[data]` reads nothing from disk; every file it names must
/// lie inside `dir`, see the [`super`] module docs). `external` as in
/// [`read_bundle_with`].
pub fn read_bundle_from_str(
    dir: impl AsRef<Path>,
    experiment_toml: &str,
    external: &BTreeMap<String, MaterialSpec>,
) -> Result<Bundle, BundleError> {
    let dir = dir.as_ref();
    let file = dir.join(EXPERIMENT_FILE);
    let map = Arc::new(SourceMap::parse(&file, experiment_toml)?);
    let mut experiment: Experiment = toml::from_str(experiment_toml).map_err(|e| map.toml_error(&e))?;
    attach_origins(&mut experiment.materials, &map);
    merge_materials(&mut experiment, external);
    validate_experiment(&experiment, &map)?;
    confine_paths(&experiment, dir, &map)?;

    let data = experiment.data.clone().unwrap_or_default();
    let force = match &data.force {
        Some(name) => Some(read_force(&dir.join(name))?),
        None => None,
    };
    let markers = match &data.markers {
        Some(name) => {
            let path = dir.join(name);
            let found = read_markers(&path, experiment.dimension as usize)?;
            validate_marker_positions(&experiment, &path, &found)?;
            found.into_iter().map(|(m, _)| m).collect()
        }
        None => Vec::new(),
    };
    Ok(Bundle { dir: dir.to_path_buf(), experiment, force, markers, map })
}
