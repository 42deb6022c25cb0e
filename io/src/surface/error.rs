//! [`SurfaceError`]: why a surface file was refused.

use std::fmt;
use std::path::PathBuf;

use thiserror::Error;

/// Where in a file an error is: a line for the text formats, a triangle for
/// binary STL, a mesh primitive for glTF. Displayed so that it follows the path
/// directly: `teapot.obj:12`, `scan.stl: triangle 7`, `cake.glb: mesh "icing" primitive 0`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// A 1-based line (OBJ, ASCII STL, OFF).
    Line(usize),
    /// A 0-based triangle record (binary STL).
    Triangle(usize),
    /// A glTF mesh primitive (0-based index within the mesh).
    Primitive {
        /// The mesh's name (or `mesh<index>` when unnamed).
        mesh: String,
        /// The primitive's index.
        primitive: usize,
    },
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(line) => write!(f, ":{line}"),
            Location::Triangle(t) => write!(f, ": triangle {t}"),
            Location::Primitive { mesh, primitive } => write!(f, ": mesh {mesh:?} primitive {primitive}"),
        }
    }
}

/// Why [`crate::surface::read_surface`] refused a file. Every variant names the
/// file, and the line (or record) where the format has them.
#[derive(Debug, Error)]
pub enum SurfaceError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// Neither the extension nor the content tells the format.
    #[error("{}: unknown surface format: expected .obj, .stl, .gltf, .glb or .off", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// Text that the format does not allow.
    #[error("{}{at}: {message}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// Where.
        at: Location,
        /// What is wrong, and what was expected.
        message: String,
    },
    /// A NaN or infinite coordinate.
    #[error("{}{at}: coordinates {coordinates:?} are not all finite", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// Where.
        at: Location,
        /// The coordinates as read (in the file's unit).
        coordinates: [f64; 3],
    },
    /// A vertex farther from the origin than [`crate::surface::MAX_COORDINATE_MM`].
    #[error("{}{at}: coordinates {coordinates:?} ({unit}) lie {reach_mm:.3e} mm from the origin, beyond the {:.0e} mm a surface may reach: a typo, or the wrong unit?",
        path.display(), crate::surface::MAX_COORDINATE_MM)]
    TooFar {
        /// The file.
        path: PathBuf,
        /// Where.
        at: Location,
        /// The coordinates as read (in the file's unit).
        coordinates: [f64; 3],
        /// The unit they were taken in.
        unit: super::LengthUnit,
        /// The largest coordinate magnitude in mm.
        reach_mm: f64,
    },
    /// A face names a vertex that does not exist.
    #[error("{}{at}: vertex index {index} out of range ({num_vertices} vertices{})", path.display(),
        if *relative { "; negative indices count back from the last vertex so far" } else { "" })]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// Where.
        at: Location,
        /// The index as written (OBJ: 1-based, or negative and relative).
        index: i64,
        /// The number of vertices available there.
        num_vertices: usize,
        /// Whether the index was a negative (relative) one.
        relative: bool,
    },
    /// The file holds no triangle.
    #[error("{}: no triangles", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A binary file whose layout is wrong (binary STL size, glTF structure).
    #[error("{}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// An import option out of range.
    #[error("surface option {name} = {value}: must be finite and > 0")]
    Option {
        /// The option.
        name: &'static str,
        /// The value given.
        value: f64,
    },
}
