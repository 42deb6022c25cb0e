//! Shared by the meshing examples: an OBJ file as a [`Surface`], one region
//! per object or group (the io crate's reader is not a dependency of meshing).

use meshing::Surface;

/// The OBJ file at `path`, triangulated; panics with the path on a read error
/// (examples only).
pub fn read_obj(path: &str) -> Surface {
    let (models, _) = tobj::load_obj(path, &tobj::LoadOptions { triangulate: true, ..Default::default() })
        .unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut s = Surface::default();
    for (r, m) in models.iter().enumerate() {
        let base = s.vertices.len() as u32;
        let p = &m.mesh.positions;
        s.vertices.extend(p.chunks(3).map(|c| [c[0] as f64, c[1] as f64, c[2] as f64]));
        s.triangles.extend(m.mesh.indices.chunks(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
        s.triangle_regions.extend(std::iter::repeat_n(r as u32, m.mesh.indices.len() / 3));
        s.region_names.push(m.name.clone());
    }
    s
}
