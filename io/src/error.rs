//! The crate's errors: [`BundleError`] for reading and converting bundles,
//! [`WriteError`] for everything that writes files.
//!
//! Every refusal of a bundle's content is [`BundleError::Invalid`], displayed as
//! `FILE:LINE: FIELD: CAUSE` where `FILE` is the path the caller gave joined with
//! the file's name, `LINE` is 1-based and `FIELD` is the TOML key path
//! (`specimen.size_mm`, `specimen.layers[1].thickness_mm`) or the CSV column.

use std::path::PathBuf;

use fem_core::press::PressError;
use thiserror::Error;

/// Why a bundle (or a materials file) was refused or could not be converted.
#[derive(Debug, Error)]
pub enum BundleError {
    /// A file that could not be read (missing, unreadable, not UTF-8).
    #[error("{}: cannot read: {source}", file.display())]
    Read {
        /// The file, as the caller's path joined with its name.
        file: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// Content that the format refuses.
    #[error("{}:{line}: {field}: {cause}", file.display())]
    Invalid {
        /// The file, as the caller's path joined with its name.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// TOML key path or CSV column.
        field: String,
        /// What is wrong, and what was expected.
        cause: String,
    },
    /// Valid bundle content that the engine does not simulate yet.
    #[error("{}:{line}: {field}: {what}", file.display())]
    Unsupported {
        /// The file (the bundle's `experiment.toml`).
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// The TOML key path.
        field: String,
        /// What is not simulated yet and what will bring it.
        what: String,
    },
    /// The engine refused the problem built from the bundle; `field` names the key
    /// that caused it as nearly as it can be told.
    #[error("{}:{line}: {field}: {source}", file.display())]
    Engine {
        /// The file holding `field`.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// The TOML key path.
        field: String,
        /// The engine's reason (boxed: the engine's error is large).
        source: Box<PressError>,
    },
    /// The surface of a `shape = "surface"` specimen could not be meshed (a defect
    /// in conforming mode, or a mesher failure): the surface file and the
    /// mesher's reason (naming the mode), with what to try instead.
    #[error("{}:{line}: {field}: {}: {source}{hint}", file.display(), surface.display())]
    SurfaceMesh {
        /// The bundle's `experiment.toml`.
        file: PathBuf,
        /// 1-based line of `field`.
        line: usize,
        /// The TOML key path (`specimen.surface`).
        field: String,
        /// The surface file.
        surface: PathBuf,
        /// The mesher's reason (a defect names itself and where it is; boxed:
        /// the error is large).
        source: Box<SurfaceMeshError>,
        /// What to try instead (empty, or `"; ..."`).
        hint: String,
    },
    /// The element size given to [`crate::Bundle::to_press`] is not a positive length.
    #[error("element size {size_mm} mm: must be finite and > 0")]
    ElementSize {
        /// The size that was given [mm].
        size_mm: f64,
    },
}

/// The mesher's error behind [`BundleError::SurfaceMesh`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SurfaceMeshError {
    /// Conforming mode ([`meshing::conforming::conforming_mesh`]).
    #[error("conforming meshing failed: {0}")]
    Conforming(meshing::conforming::ConformingError),
    /// Envelope mode ([`meshing::envelope::envelope_mesh`]).
    #[error("envelope meshing failed: {0}")]
    Envelope(meshing::envelope::EnvelopeError),
}

/// Why writing an output failed.
#[derive(Debug, Error)]
pub enum WriteError {
    /// The operating system refused a write, a rename or a folder creation.
    #[error("{}: cannot write: {source}", path.display())]
    Io {
        /// The file or folder being written.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// An output folder would replace a folder that is not a previous wagashi output.
    #[error("refusing to overwrite {}: it exists and is not a wagashi output (no wagashi manifest)", dir.display())]
    RefuseOverwrite {
        /// The existing folder.
        dir: PathBuf,
    },
    /// A previous wagashi output would be replaced, but it holds an entry its
    /// manifest does not list (a file wagashi did not write).
    #[error("refusing to replace {}: {entry} is not a file wagashi wrote there (its manifest does not list it); move it away first", dir.display())]
    RefuseUnlisted {
        /// The existing folder.
        dir: PathBuf,
        /// The unlisted entry, relative to `dir`.
        entry: String,
    },
    /// Data that does not fit what is being written (e.g. a field of the wrong length).
    #[error("{}: {cause}", path.display())]
    BadInput {
        /// The file being written.
        path: PathBuf,
        /// What does not fit.
        cause: String,
    },
}

impl WriteError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        WriteError::Io { path: path.into(), source }
    }
}
