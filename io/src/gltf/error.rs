use std::path::PathBuf;

use thiserror::Error;

use crate::error::WriteError;

/// Why a glTF scene could not be written, or a file it is built from read.
///
/// The input variants name the object and the item at fault, e.g.
/// `specimen `mat1-sim`, frame 3 (t = 14.2 s): displacement has 12 vectors, expected 20`.
#[derive(Debug, Error)]
pub enum GltfError {
    /// A list whose length does not fit the others.
    #[error("{what} has {found} {item}, expected {expected}")]
    LengthMismatch {
        /// The list, e.g. `specimen `a`, frame 3 (t = 1.5 s): displacement`.
        what: String,
        /// What it counts: `vectors`, `values`, `nodes`.
        item: &'static str,
        /// Its length.
        found: usize,
        /// The length it needs.
        expected: usize,
    },
    /// A NaN or an infinity.
    #[error("{what} is not finite ({value})")]
    NonFinite {
        /// The number, e.g. `tool `plate`, key 2: translation_mm[1]`.
        what: String,
        /// Its value.
        value: f64,
    },
    /// Times that do not strictly increase (also after rounding to the 32-bit
    /// floats that glTF stores).
    #[error("{what}: t = {t_s} s is not after the previous time {previous_s} s (times must increase, also as the 32-bit floats glTF stores)")]
    NotIncreasing {
        /// The item, e.g. `specimen `a`, frame 4`.
        what: String,
        /// Its time [s].
        t_s: f64,
        /// The time before it [s].
        previous_s: f64,
    },
    /// A triangle naming a vertex that does not exist.
    #[error("{what}: triangle {triangle} names vertex {vertex}, but there are {num_vertices} vertices")]
    IndexOutOfRange {
        /// The surface, e.g. `tool `plate``.
        what: String,
        /// The triangle's index.
        triangle: usize,
        /// The vertex it names.
        vertex: u32,
        /// How many vertices there are.
        num_vertices: usize,
    },
    /// Anything else the scene cannot hold: no triangles, no frames, a zero
    /// rotation, a repeated frame name, a buffer over glTF's 4 GiB.
    #[error("{what}: {cause}")]
    Invalid {
        /// The item.
        what: String,
        /// What is wrong, and what is expected.
        cause: String,
    },
    /// A file that could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A file whose content is not what it should be (a `frames.bin`, a `.vtu`, a `.pvd`).
    #[error("{}: {cause}", path.display())]
    BadFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        cause: String,
    },
    /// The output could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
}

impl GltfError {
    pub(crate) fn invalid(what: impl Into<String>, cause: impl Into<String>) -> Self {
        GltfError::Invalid { what: what.into(), cause: cause.into() }
    }

    pub(crate) fn bad_file(path: impl Into<PathBuf>, cause: impl Into<String>) -> Self {
        GltfError::BadFile { path: path.into(), cause: cause.into() }
    }
}

/// `Ok` when `x` is finite, else [`GltfError::NonFinite`] naming `what()`.
pub(crate) fn finite(x: f64, what: impl FnOnce() -> String) -> Result<f64, GltfError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(GltfError::NonFinite { what: what(), value: x })
    }
}
