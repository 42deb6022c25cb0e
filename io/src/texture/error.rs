//! [`ImportError`]: why a raw texture-analyser file was refused or could not be
//! turned into a bundle. Displayed as `FILE:LINE: FIELD: CAUSE`, the style of
//! [`crate::BundleError`].

use std::path::PathBuf;

use thiserror::Error;

/// Why a raw file was refused or could not be turned into a bundle.
#[derive(Debug, Error)]
pub enum ImportError {
    /// A file that could not be read (missing, unreadable).
    // The reason is in the message and not a `source`, so that a report of the
    // whole chain (anyhow's `{:#}`) does not repeat it.
    #[error("{}: cannot read: {reason}", file.display())]
    Read {
        /// The file, as the caller gave it.
        file: PathBuf,
        /// The operating system's reason.
        reason: std::io::Error,
    },
    /// Content that the reader refuses, or a test in which the detection finds
    /// no contact, stroke or separation it needs.
    #[error("{}:{line}: {field}: {cause}", file.display())]
    Invalid {
        /// The file, as the caller gave it.
        file: PathBuf,
        /// 1-based line of the file.
        line: usize,
        /// The column (as the file's header names it, e.g. `Gap (um)`), or
        /// `header` / `units` / `row`.
        field: String,
        /// What is wrong, and what was expected.
        cause: String,
    },
    /// An import option that does not fit the file (e.g. no height for a file
    /// that has no gap to read it from).
    #[error("{}: {option}: {cause}", file.display())]
    Options {
        /// The raw file being imported.
        file: PathBuf,
        /// The option, as [`super::ImportOptions`] names it (e.g. `height`).
        option: String,
        /// What is wrong, and what to give instead.
        cause: String,
    },
}

impl ImportError {
    pub(crate) fn invalid(
        file: impl Into<PathBuf>,
        line: usize,
        field: impl Into<String>,
        cause: impl Into<String>,
    ) -> Self {
        ImportError::Invalid { file: file.into(), line, field: field.into(), cause: cause.into() }
    }

    pub(crate) fn options(file: impl Into<PathBuf>, option: impl Into<String>, cause: impl Into<String>) -> Self {
        ImportError::Options { file: file.into(), option: option.into(), cause: cause.into() }
    }
}
