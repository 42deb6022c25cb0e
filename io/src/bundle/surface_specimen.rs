//! A `shape = "surface"` specimen: its closed surface read and meshed on the fly.
//!
//! - The surface file (`specimen.surface`, relative to the bundle folder) is read
//!   by [`crate::surface::read_surface`] in the format's unit (mm for OBJ and STL,
//!   m for glTF/GLB), its regions being the file's objects, groups or meshes.
//! - It is meshed at the element size of [`Bundle::to_press`] by
//!   [`SurfaceMeshing::Conforming`] (the default: `meshing::conforming`, whose
//!   boundary is the input surface exactly; a defective surface is refused with
//!   [`BundleError::SurfaceMesh`] naming the defect and suggesting envelope mode)
//!   or [`SurfaceMeshing::Envelope`] (`meshing::envelope`: any input, boundary
//!   within the lattice's chord error). Nothing is repaired silently.
//! - Regions: each mesh region (a surface region) takes the material that
//!   `[specimen.regions]` maps it to, or `material` for all. A surface region
//!   without a material, or a `[specimen.regions]` key that names no region of the
//!   file, is refused naming `specimen.regions` and listing the file's regions.
//! - Support: the specimen stands on the floor at its lowest y (y = 0 in a bundle
//!   that follows the format). The node set `bottom` holds the boundary nodes
//!   within [`BASE_BAND`] of the height above that lowest y; they must span a
//!   triangle (three nodes not on one line), else the specimen would be free to
//!   turn about them and is refused. `top` holds the boundary nodes within the
//!   same band of the highest y.
//! - Tools: a surface specimen always runs with rigid contact tools
//!   ([`Bundle::has_contact_tools`]), since a plate touches a curved top where it
//!   is highest rather than on a flat face; tools are placed against the
//!   surface's bounding box.

use std::path::PathBuf;

use fem_core::mesh::TetMesh;
use meshing::conforming::{conforming_mesh, ConformingOptions};
use meshing::envelope::{envelope_mesh, EnvelopeOptions};
use meshing::Surface;

use super::experiment::Shape;
use super::read::Bundle;
use crate::error::{BundleError, SurfaceMeshError};
use crate::surface::{read_surface, SurfaceOptions};

/// The band, as a fraction of the specimen's height, within which boundary nodes
/// at the lowest (highest) y form the node set `bottom` (`top`).
pub const BASE_BAND: f64 = 1e-3;

/// How a surface specimen is meshed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SurfaceMeshing {
    /// `meshing::conforming`: the boundary is the input surface exactly; clean,
    /// closed input only (the default).
    #[default]
    Conforming,
    /// `meshing::envelope`: any input; boundary within the lattice's chord error.
    Envelope,
}

impl SurfaceMeshing {
    /// The mode's name, as `wagashi mesh --mode` spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            SurfaceMeshing::Conforming => "conforming",
            SurfaceMeshing::Envelope => "envelope",
        }
    }
}

impl Bundle {
    /// The path of the specimen's surface file (`shape = "surface"`), if any.
    pub fn surface_path(&self) -> Option<PathBuf> {
        let s = &self.experiment.specimen;
        (s.shape == Shape::Surface).then(|| s.surface.as_deref().map(|f| self.dir.join(f))).flatten()
    }

    /// Reads the specimen's surface [mm]; refused naming `specimen.surface`.
    pub fn specimen_surface(&self) -> Result<Surface, BundleError> {
        let path = self.surface_path().ok_or_else(|| {
            self.map.invalid("specimen.surface", "missing required key for shape = \"surface\"".to_string())
        })?;
        let imported = read_surface(&path, &SurfaceOptions::default())
            .map_err(|e| self.map.invalid("specimen.surface", e.to_string()))?;
        Ok(imported.surface)
    }

    /// The tetrahedral mesh of the specimen's surface at element size `size_mm`
    /// [mm] by `mode`, with node sets `bottom`, `top` and `boundary` (module docs).
    /// Its region names are the surface's; [`Bundle::surface_region_materials`]
    /// gives their materials.
    pub fn mesh_specimen_surface(&self, size_mm: f64, mode: SurfaceMeshing) -> Result<TetMesh, BundleError> {
        if !(size_mm.is_finite() && size_mm > 0.0) {
            return Err(BundleError::ElementSize { size_mm });
        }
        let surface = self.specimen_surface()?;
        let path = self.surface_path().unwrap_or_default();
        let failed = |source: SurfaceMeshError, hint: String| BundleError::SurfaceMesh {
            file: self.experiment_file(),
            line: self.line_of("specimen.surface"),
            field: "specimen.surface".into(),
            surface: path.clone(),
            source: Box::new(source),
            hint,
        };
        let mut mesh = match mode {
            SurfaceMeshing::Conforming => {
                conforming_mesh(&surface, &ConformingOptions::new(size_mm))
                    .map_err(|e| {
                        let hint = format!(
                            "; envelope mode meshes defective surfaces: `wagashi press --mesh-mode envelope`, or \
                             `wagashi mesh {} --mode envelope`",
                            path.display()
                        );
                        failed(SurfaceMeshError::Conforming(e), hint)
                    })?
                    .mesh
            }
            SurfaceMeshing::Envelope => {
                envelope_mesh(&surface, &EnvelopeOptions::new(size_mm))
                    .map_err(|e| failed(SurfaceMeshError::Envelope(e), String::new()))?
                    .mesh
            }
        };
        self.add_support_sets(&mut mesh)?;
        Ok(mesh)
    }

    /// The material of each region of `mesh` (a mesh of the specimen's surface,
    /// or the mesh of a `shape = "mesh"` specimen), in region order (module docs).
    pub fn surface_region_materials(&self, mesh: &TetMesh) -> Result<Vec<String>, BundleError> {
        let s = &self.experiment.specimen;
        let listed = || mesh.region_names.iter().map(|r| format!("\"{r}\"")).collect::<Vec<_>>().join(", ");
        let file = s.surface.as_deref().or(s.mesh.as_deref()).unwrap_or("");
        if s.regions.is_empty() {
            let material = s.material.clone().ok_or_else(|| {
                self.map
                    .invalid("specimen.regions", format!("missing required key for shape = \"{}\"", s.shape.as_str()))
            })?;
            return Ok(vec![material; mesh.region_names.len()]);
        }
        if let Some(unknown) = s.regions.keys().find(|k| !mesh.region_names.contains(k)) {
            return Err(self.map.invalid(
                "specimen.regions",
                format!("\"{unknown}\" is not a region of {file} (its regions: {})", listed()),
            ));
        }
        mesh.region_names
            .iter()
            .map(|r| {
                s.regions.get(r).or(s.material.as_ref()).cloned().ok_or_else(|| {
                    self.map.invalid(
                        "specimen.regions",
                        format!("region \"{r}\" of {file} has no material (its regions: {})", listed()),
                    )
                })
            })
            .collect()
    }

    /// Adds the node sets `bottom` and `top` (module docs) to a mesh with the node
    /// set `boundary` (a meshed surface, or a `shape = "mesh"` specimen's mesh);
    /// a refusal names `specimen.surface` or `specimen.mesh`.
    pub(super) fn add_support_sets(&self, mesh: &mut TetMesh) -> Result<(), BundleError> {
        let field = if self.experiment.specimen.shape == Shape::Mesh { "specimen.mesh" } else { "specimen.surface" };
        let boundary: Vec<u32> = mesh.node_sets.get("boundary").cloned().unwrap_or_default();
        let ys = boundary.iter().map(|&i| mesh.nodes[i as usize][1]);
        let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
        let band = BASE_BAND * (hi - lo);
        let bottom: Vec<u32> = boundary.iter().copied().filter(|&i| mesh.nodes[i as usize][1] <= lo + band).collect();
        let top: Vec<u32> = boundary.iter().copied().filter(|&i| mesh.nodes[i as usize][1] >= hi - band).collect();
        if !spans_a_triangle(&bottom.iter().map(|&i| mesh.nodes[i as usize]).collect::<Vec<_>>()) {
            return Err(self.map.invalid(
                field,
                format!(
                    "the specimen must stand on the floor: the mesh has {} boundary node(s) within {band:.3e} mm of its \
                     lowest y = {lo} mm, which do not span a triangle (give the shape a base)",
                    bottom.len()
                ),
            ));
        }
        mesh.node_sets.insert("bottom".into(), bottom);
        mesh.node_sets.insert("top".into(), top);
        Ok(())
    }
}

/// Whether three of `points` span a triangle of positive area (relative to the
/// points' extent, 1e-12).
fn spans_a_triangle(points: &[[f64; 3]]) -> bool {
    let Some(&a) = points.first() else { return false };
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let norm2 = |v: [f64; 3]| v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    let Some(&b) = points.iter().max_by(|p, q| norm2(sub(**p, a)).total_cmp(&norm2(sub(**q, a)))) else {
        return false;
    };
    let ab = sub(b, a);
    let l2 = norm2(ab);
    if l2 == 0.0 {
        return false;
    }
    points.iter().any(|&p| {
        let ap = sub(p, a);
        let c = [ab[1] * ap[2] - ab[2] * ap[1], ab[2] * ap[0] - ab[0] * ap[2], ab[0] * ap[1] - ab[1] * ap[0]];
        norm2(c) > 1e-24 * l2 * l2
    })
}

#[cfg(test)]
mod tests {
    use super::spans_a_triangle;

    #[test]
    fn a_triangle_needs_three_points_off_a_line() {
        assert!(!spans_a_triangle(&[]));
        assert!(!spans_a_triangle(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]));
        assert!(spans_a_triangle(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 0.0, 1e-3]]));
    }
}
