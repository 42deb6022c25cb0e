//! [`read_surface`]: the entry point, format detection, units.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use meshing::Surface;

use super::error::{Location, SurfaceError};
use super::options::{LengthUnit, SurfaceFormat, SurfaceOptions};

/// A surface read from a file, in mm.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedSurface {
    /// The surface [mm], regions named after the file's objects, groups, solids or
    /// meshes.
    pub surface: Surface,
    /// The format it was read as.
    pub format: SurfaceFormat,
    /// The unit the file's coordinates were taken in.
    pub unit: LengthUnit,
    /// The factor applied to the file's coordinates to give mm (the unit's,
    /// times [`SurfaceOptions::scale`]).
    pub to_mm: f64,
    /// What was read but left out, in words (e.g. OBJ line elements), one entry
    /// per kind.
    pub warnings: Vec<String>,
}

/// The largest coordinate magnitude a surface may have once in mm: 10 km, far
/// beyond any specimen or tool. A larger one is a typo or a wrong unit; meshed,
/// it would make every other triangle degenerate next to the surface's size,
/// or a lattice too large to count, instead of an error naming the vertex.
pub const MAX_COORDINATE_MM: f64 = 1e7;

/// Reads the surface in `path` (OBJ, STL binary or ASCII, glTF or GLB, OFF) into mm.
///
/// The format is [`SurfaceOptions::format`], else told by the extension
/// (`.obj`, `.stl`, `.gltf`, `.glb`, `.off`, any case), else by the content (GLB's
/// magic, binary STL's size, ASCII STL's `solid`, OFF's keyword). Coordinates are multiplied by the
/// unit's mm (the format's default unit unless [`SurfaceOptions::units`] says)
/// and by [`SurfaceOptions::scale`]. A coordinate beyond [`MAX_COORDINATE_MM`]
/// in mm is refused, naming where it is. The file is never modified.
pub fn read_surface(path: impl AsRef<Path>, options: &SurfaceOptions) -> Result<ImportedSurface, SurfaceError> {
    let path = path.as_ref();
    if !(options.scale.is_finite() && options.scale > 0.0) {
        return Err(SurfaceError::Option { name: "scale", value: options.scale });
    }
    let bytes = crate::input::read(path).map_err(|source| SurfaceError::Read { path: path.to_path_buf(), source })?;
    let format = match options.format {
        Some(f) => f,
        None => detect(path, &bytes)?,
    };
    let raw = match format {
        SurfaceFormat::Obj => super::obj::parse(path, &bytes)?,
        SurfaceFormat::Stl => super::stl::parse(path, &bytes)?,
        SurfaceFormat::Gltf => super::gltf::parse(path, &bytes)?,
        SurfaceFormat::Off => super::off::parse(path, &bytes)?,
    };
    if raw.surface.triangles.is_empty() {
        return Err(SurfaceError::Empty { path: path.to_path_buf() });
    }
    let unit = options.units.unwrap_or(format.default_unit());
    let to_mm = unit.to_mm() * options.scale;
    if let Some((magnitude, at, coordinates)) = raw.farthest {
        let reach_mm = magnitude * to_mm;
        if reach_mm > MAX_COORDINATE_MM {
            return Err(SurfaceError::TooFar { path: path.to_path_buf(), at, coordinates, unit, reach_mm });
        }
    }
    let mut surface = raw.surface;
    for p in &mut surface.vertices {
        *p = p.map(|x| x * to_mm);
        if !p.iter().all(|x| x.is_finite()) {
            return Err(SurfaceError::Format {
                path: path.to_path_buf(),
                message: format!("coordinates overflow when scaled by {to_mm} to mm"),
            });
        }
    }
    Ok(ImportedSurface { surface, format, unit, to_mm, warnings: raw.warnings })
}

fn detect(path: &Path, bytes: &[u8]) -> Result<SurfaceFormat, SurfaceError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => return Ok(SurfaceFormat::Obj),
        Some("stl") => return Ok(SurfaceFormat::Stl),
        Some("gltf" | "glb") => return Ok(SurfaceFormat::Gltf),
        Some("off") => return Ok(SurfaceFormat::Off),
        _ => {}
    }
    if bytes.starts_with(b"glTF") {
        Ok(SurfaceFormat::Gltf)
    } else if super::stl::is_binary(bytes) || super::stl::is_ascii(bytes) {
        Ok(SurfaceFormat::Stl)
    } else if super::off::is_off(bytes) {
        Ok(SurfaceFormat::Off)
    } else {
        Err(SurfaceError::UnknownFormat { path: path.to_path_buf() })
    }
}

/// What a format parser returns: the surface in the file's unit.
pub(crate) struct Raw {
    pub surface: Surface,
    pub warnings: Vec<String>,
    /// The vertex farthest from the origin (largest coordinate magnitude, in
    /// the file's unit): that magnitude, where it is, and its coordinates.
    pub farthest: Option<(f64, Location, [f64; 3])>,
}

/// Collects vertices, triangles and regions while a file is parsed.
pub(crate) struct Builder {
    surface: Surface,
    region_index: HashMap<String, u32>,
    /// Exact positions already seen, for formats that weld (`None`: keep indices).
    welded: Option<HashMap<[u64; 3], u32>>,
    /// [`Raw::farthest`] so far.
    farthest: Option<(f64, Location, [f64; 3])>,
}

impl Builder {
    /// `weld`: merge vertices at bit-identical positions (STL and glTF, which
    /// repeat a vertex for every triangle or every primitive that uses it).
    pub(crate) fn new(weld: bool) -> Builder {
        Builder {
            surface: Surface::default(),
            region_index: HashMap::new(),
            welded: weld.then(HashMap::new),
            farthest: None,
        }
    }

    /// The index of the region called `name`, created if new.
    pub(crate) fn region(&mut self, name: &str) -> u32 {
        if let Some(&r) = self.region_index.get(name) {
            return r;
        }
        let r = self.surface.region_names.len() as u32;
        self.surface.region_names.push(name.to_string());
        self.region_index.insert(name.to_string(), r);
        r
    }

    /// Adds a vertex (welded to an identical one when welding), returns its
    /// index; `at` tells where it is in the file, asked for only when it is the
    /// farthest from the origin so far.
    pub(crate) fn vertex(&mut self, p: [f64; 3], at: impl FnOnce() -> Location) -> u32 {
        let magnitude = p.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        if self.farthest.as_ref().is_none_or(|f| magnitude > f.0) {
            self.farthest = Some((magnitude, at(), p));
        }
        let next = self.surface.vertices.len() as u32;
        if let Some(seen) = &mut self.welded {
            let key = p.map(|x| (x + 0.0).to_bits());
            let v = *seen.entry(key).or_insert(next);
            if v != next {
                return v;
            }
        }
        self.surface.vertices.push(p);
        next
    }

    pub(crate) fn num_vertices(&self) -> usize {
        self.surface.vertices.len()
    }

    pub(crate) fn triangle(&mut self, tri: [u32; 3], region: u32) {
        self.surface.triangles.push(tri);
        self.surface.triangle_regions.push(region);
    }

    /// A polygon as a fan of triangles from its first vertex.
    pub(crate) fn polygon(&mut self, corners: &[u32], region: u32) {
        for k in 1..corners.len().saturating_sub(1) {
            self.triangle([corners[0], corners[k], corners[k + 1]], region);
        }
    }

    pub(crate) fn finish(self, warnings: Vec<String>) -> Raw {
        Raw { surface: self.surface, warnings, farthest: self.farthest }
    }
}

/// The file's stem, naming the region of a file with no named parts.
pub(crate) fn stem(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "surface".to_string())
}

pub(crate) fn owned(path: &Path) -> PathBuf {
    path.to_path_buf()
}
