//! The triangle surface: what every importer produces and every mesher consumes.

/// A triangle surface in mm, possibly with several named regions (OBJ objects or
/// groups, glTF meshes).
///
/// Triangles are counter-clockwise seen from outside (outward normals by the
/// right-hand rule) once the surface is valid; an imported surface may break
/// this, and the validation in this crate says where.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Surface {
    /// Vertex positions [mm].
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Region of each triangle, an index into `region_names`.
    pub triangle_regions: Vec<u32>,
    /// Region names, in the order the file gives them.
    pub region_names: Vec<String>,
}

impl Surface {
    /// The axis-aligned box `[lo, hi]` as one closed region named `region`: eight
    /// vertices (bit `k` of a vertex's index picks `hi[k]`), twelve triangles, all
    /// outward.
    pub fn cuboid(lo: [f64; 3], hi: [f64; 3], region: &str) -> Self {
        let vertices = (0..8).map(|i| std::array::from_fn(|k| if i & (1 << k) == 0 { lo[k] } else { hi[k] })).collect();
        let triangles = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        Self { vertices, triangles, triangle_regions: vec![0; 12], region_names: vec![region.to_string()] }
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Axis-aligned bounding box `(min, max)` [mm]; infinite bounds when empty.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// The length of the bounding box's diagonal [mm] (0 when empty).
    pub fn diagonal(&self) -> f64 {
        if self.vertices.is_empty() {
            return 0.0;
        }
        let (lo, hi) = self.bounding_box();
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    }

    /// The signed volume enclosed by the triangles of `region` (all when `None`)
    /// [mm^3]: positive for a closed, outward-oriented shell (divergence theorem).
    pub fn signed_volume(&self, region: Option<u32>) -> f64 {
        self.triangles
            .iter()
            .zip(&self.triangle_regions)
            .filter(|(_, &r)| region.is_none_or(|want| want == r))
            .map(|(t, _)| {
                let [a, b, c] = t.map(|i| self.vertices[i as usize]);
                let cross = [b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]];
                (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tetrahedron() -> Surface {
        Surface {
            vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            triangle_regions: vec![0; 4],
            region_names: vec!["tet".into()],
        }
    }

    #[test]
    fn volume_of_an_outward_tetrahedron_is_one_sixth() {
        let s = unit_tetrahedron();
        assert!((s.signed_volume(None) - 1.0 / 6.0).abs() < 1e-15);
        assert!((s.diagonal() - 3f64.sqrt()).abs() < 1e-15);
    }
}
