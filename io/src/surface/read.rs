//! [`read_surface`]: the entry point, format detection, units.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use meshing::Surface;

use super::error::SurfaceError;
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

/// Reads the surface in `path` (OBJ, STL binary or ASCII, glTF or GLB, OFF) into mm.
///
/// The format is [`SurfaceOptions::format`], else told by the extension
/// (`.obj`, `.stl`, `.gltf`, `.glb`, `.off`, any case), else by the content (GLB's
/// magic, binary STL's size, ASCII STL's `solid`, OFF's keyword). Coordinates are multiplied by the
/// unit's mm (the format's default unit unless [`SurfaceOptions::units`] says)
/// and by [`SurfaceOptions::scale`]. The file is never modified.
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
}

/// Collects vertices, triangles and regions while a file is parsed.
pub(crate) struct Builder {
    surface: Surface,
    region_index: HashMap<String, u32>,
    /// Exact positions already seen, for formats that weld (`None`: keep indices).
    welded: Option<HashMap<[u64; 3], u32>>,
}

impl Builder {
    /// `weld`: merge vertices at bit-identical positions (STL and glTF, which
    /// repeat a vertex for every triangle or every primitive that uses it).
    pub(crate) fn new(weld: bool) -> Builder {
        Builder { surface: Surface::default(), region_index: HashMap::new(), welded: weld.then(HashMap::new) }
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

    /// Adds a vertex (welded to an identical one when welding), returns its index.
    pub(crate) fn vertex(&mut self, p: [f64; 3]) -> u32 {
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
        Raw { surface: self.surface, warnings }
    }
}

/// The file's stem, naming the region of a file with no named parts.
pub(crate) fn stem(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "surface".to_string())
}

pub(crate) fn owned(path: &Path) -> PathBuf {
    path.to_path_buf()
}
