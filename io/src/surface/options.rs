//! Import options: the file's length unit, an extra scale, the format.

use std::fmt;
use std::str::FromStr;

use thiserror::Error;

/// A length unit of surface coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    /// Millimetres (the engine's unit).
    Mm,
    /// Centimetres.
    Cm,
    /// Metres (glTF's unit).
    M,
    /// Inches (25.4 mm).
    In,
}

impl LengthUnit {
    /// Millimetres per unit.
    pub fn to_mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::Cm => 10.0,
            LengthUnit::M => 1000.0,
            LengthUnit::In => 25.4,
        }
    }

    /// The unit's symbol, as [`LengthUnit::from_str`] reads it.
    pub fn symbol(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::Cm => "cm",
            LengthUnit::M => "m",
            LengthUnit::In => "in",
        }
    }
}

impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.symbol())
    }
}

/// A unit name that is not `mm`, `cm`, `m` or `in`.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("unknown length unit {0:?}: expected mm, cm, m or in")]
pub struct UnknownUnit(pub String);

impl FromStr for LengthUnit {
    type Err = UnknownUnit;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "mm" => Ok(LengthUnit::Mm),
            "cm" => Ok(LengthUnit::Cm),
            "m" => Ok(LengthUnit::M),
            "in" | "inch" => Ok(LengthUnit::In),
            other => Err(UnknownUnit(other.to_string())),
        }
    }
}

/// A surface file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SurfaceFormat {
    /// Wavefront OBJ.
    Obj,
    /// STL, binary or ASCII (told apart by content).
    Stl,
    /// glTF 2.0, JSON (`.gltf`) or binary (`.glb`).
    Gltf,
    /// OFF, ASCII (Geomview's Object File Format; CGAL's sample meshes).
    Off,
}

impl SurfaceFormat {
    /// The length unit a file of this format is read in unless told otherwise:
    /// metres for glTF (its specification's unit), millimetres for OBJ, STL and
    /// OFF (which have none; mm is what CAD and scanners mostly write).
    pub fn default_unit(self) -> LengthUnit {
        match self {
            SurfaceFormat::Gltf => LengthUnit::M,
            SurfaceFormat::Obj | SurfaceFormat::Stl | SurfaceFormat::Off => LengthUnit::Mm,
        }
    }
}

/// How to read a surface file.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceOptions {
    /// The unit of the file's coordinates (default `None`: the format's,
    /// [`SurfaceFormat::default_unit`]).
    pub units: Option<LengthUnit>,
    /// A factor applied after the unit conversion, e.g. `0.5` to halve a model
    /// (default `1`; must be finite and > 0).
    pub scale: f64,
    /// The format (default `None`: by extension, then by content).
    pub format: Option<SurfaceFormat>,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        SurfaceOptions { units: None, scale: 1.0, format: None }
    }
}
