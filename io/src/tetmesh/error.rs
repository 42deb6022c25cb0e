use std::path::PathBuf;

use thiserror::Error;

/// Why a TetGen or Gmsh mesh file was refused.
#[derive(Debug, Error)]
pub enum TetMeshError {
    /// A file that could not be read (missing, unreadable, not UTF-8).
    #[error("{}: cannot read: {source}", file.display())]
    Read {
        /// The file.
        file: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// Content the format refuses, displayed as `FILE:LINE: FIELD: CAUSE`.
    #[error("{}:{line}: {field}: {cause}", file.display())]
    Invalid {
        /// The file.
        file: PathBuf,
        /// 1-based line (0 when the file ended early: the cause says so).
        line: usize,
        /// The field: a header entry, a column, a section.
        field: String,
        /// What is wrong, and what was expected.
        cause: String,
    },
    /// A file name whose extension names no mesh format this crate reads or writes.
    #[error("{}: unknown mesh format (expected .vtu, .msh, .node or .ele)", file.display())]
    UnknownFormat {
        /// The file.
        file: PathBuf,
    },
}

impl TetMeshError {
    pub(crate) fn invalid(file: &std::path::Path, line: usize, field: &str, cause: impl Into<String>) -> Self {
        TetMeshError::Invalid { file: file.to_path_buf(), line, field: field.to_string(), cause: cause.into() }
    }
}
