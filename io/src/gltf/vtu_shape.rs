use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use fem_core::mesh::SimplexMesh;

use super::error::GltfError;
use crate::vtu::{VTK_TETRA, VTK_TRIANGLE};

/// A shape read back from a `.vtu` that [`crate::vtu`] wrote: the mesh (reference
/// points and cells) and the point field `displacement`. Only what the glTF export
/// needs is read: ASCII data arrays of triangles or tetrahedra, as wagashi writes
/// them; stress and regions are skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuShape {
    /// Point coordinates [mm] (z = 0 for a 2D mesh).
    pub points_mm: Vec<[f64; 3]>,
    /// The cells.
    pub cells: ShapeCells,
    /// The point field `displacement` [mm] (z = 0 in 2D).
    pub displacement_mm: Vec<[f64; 3]>,
}

/// The cells of a [`VtuShape`].
#[derive(Debug, Clone, PartialEq)]
pub enum ShapeCells {
    /// VTK triangles (a 2D mesh).
    Triangles(Vec<[u32; 3]>),
    /// VTK tetrahedra.
    Tetrahedra(Vec<[u32; 4]>),
}

impl VtuShape {
    /// Reads `path`; errors name the file and what is wrong.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, GltfError> {
        let path = path.as_ref();
        let text =
            crate::input::read_to_string(path).map_err(|source| GltfError::Read { path: path.into(), source })?;
        Self::parse(&text, path)
    }

    /// Parses the text of a `.vtu`; `path` is only for the messages.
    pub fn parse(text: &str, path: &Path) -> Result<Self, GltfError> {
        let bad = |cause: String| GltfError::bad_file(path, cause);
        let doc = roxmltree::Document::parse(text).map_err(|e| bad(format!("not well-formed XML: {e}")))?;
        let root = doc.root_element();
        if root.tag_name().name() != "VTKFile" || root.attribute("type") != Some("UnstructuredGrid") {
            return Err(bad("not a VTK UnstructuredGrid file".into()));
        }
        let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).ok_or_else(|| bad("no <Piece>".into()))?;
        let count = |key: &str| -> Result<usize, GltfError> {
            piece
                .attribute(key)
                .and_then(|s| s.trim().parse().ok())
                .ok_or_else(|| bad(format!("<Piece> lacks a valid {key}")))
        };
        let (num_points, num_cells) = (count("NumberOfPoints")?, count("NumberOfCells")?);
        let array = |parent: &str, name: &str| -> Result<Vec<&str>, GltfError> {
            let node = piece
                .descendants()
                .filter(|n| n.has_tag_name(parent))
                .flat_map(|p| p.children())
                .find(|n| n.has_tag_name("DataArray") && n.attribute("Name") == Some(name))
                .ok_or_else(|| bad(format!("no <DataArray Name=\"{name}\"> in <{parent}>")))?;
            if node.attribute("format") != Some("ascii") {
                return Err(bad(format!("DataArray {name}: only format=\"ascii\" is read (wagashi's own .vtu files)")));
            }
            Ok(node.text().unwrap_or("").split_whitespace().collect())
        };
        let numbers = |parent: &str, name: &str, len: usize| -> Result<Vec<f64>, GltfError> {
            let words = array(parent, name)?;
            if words.len() != len {
                return Err(bad(format!("DataArray {name} has {} values, expected {len}", words.len())));
            }
            words
                .iter()
                .map(|w| match w.parse::<f64>() {
                    Ok(x) if x.is_finite() => Ok(x),
                    _ => Err(bad(format!("DataArray {name}: `{w}` is not a finite number"))),
                })
                .collect()
        };
        let integers = |name: &str, len: Option<usize>| -> Result<Vec<u64>, GltfError> {
            let words = array("Cells", name)?;
            if let Some(len) = len.filter(|&l| l != words.len()) {
                return Err(bad(format!("DataArray {name} has {} values, expected {len}", words.len())));
            }
            words
                .iter()
                .map(|w| w.parse::<u64>().map_err(|_| bad(format!("DataArray {name}: `{w}` is not an index"))))
                .collect()
        };
        let vectors = |v: Vec<f64>| -> Vec<[f64; 3]> { v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect() };
        let points_mm = vectors(numbers("Points", "Points", 3 * num_points)?);
        let displacement_mm = vectors(numbers("PointData", "displacement", 3 * num_points)?);

        let types = integers("types", Some(num_cells))?;
        let offsets = integers("offsets", Some(num_cells))?;
        let connectivity = integers("connectivity", None)?;
        let kind = types.first().copied().unwrap_or(u64::from(VTK_TETRA));
        let per_cell = match kind {
            k if k == u64::from(VTK_TRIANGLE) => 3,
            k if k == u64::from(VTK_TETRA) => 4,
            k => return Err(bad(format!("cell type {k}; only triangles (5) and tetrahedra (10) are read"))),
        };
        if let Some((e, t)) = types.iter().enumerate().find(|(_, &t)| t != kind) {
            return Err(bad(format!("cell {e} has type {t}, the first cell {kind}: mixed cells are not read")));
        }
        if connectivity.len() != per_cell * num_cells
            || offsets.iter().enumerate().any(|(e, &o)| o != (per_cell * (e + 1)) as u64)
        {
            return Err(bad(format!(
                "connectivity and offsets do not describe {num_cells} cells of {per_cell} points"
            )));
        }
        if let Some(&v) = connectivity.iter().find(|&&v| v >= num_points as u64) {
            return Err(bad(format!("a cell names point {v}, but there are {num_points} points")));
        }
        let ids: Vec<u32> = connectivity.iter().map(|&v| v as u32).collect();
        let cells = if per_cell == 3 {
            ShapeCells::Triangles(ids.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
        } else {
            ShapeCells::Tetrahedra(ids.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect())
        };
        Ok(Self { points_mm, cells, displacement_mm })
    }

    /// The triangle mesh in x-y, when the cells are triangles (one region, no sets).
    pub fn tri_mesh(&self) -> Option<SimplexMesh<2, 3>> {
        match &self.cells {
            ShapeCells::Triangles(cells) => Some(mesh(self.points_mm.iter().map(|p| [p[0], p[1]]).collect(), cells)),
            ShapeCells::Tetrahedra(_) => None,
        }
    }

    /// The tetrahedral mesh, when the cells are tetrahedra (one region, no sets).
    pub fn tet_mesh(&self) -> Option<SimplexMesh<3, 4>> {
        match &self.cells {
            ShapeCells::Tetrahedra(cells) => Some(mesh(self.points_mm.clone(), cells)),
            ShapeCells::Triangles(_) => None,
        }
    }

    /// The displacement as nodal values with `dim` components per node (the
    /// layout of [`fem_core::press::Snapshot::displacement`]).
    pub fn nodal_displacement(&self, dim: usize) -> Vec<f64> {
        self.displacement_mm.iter().flat_map(|u| u[..dim.min(3)].to_vec()).collect()
    }
}

fn mesh<const D: usize, const N: usize>(nodes: Vec<[f64; D]>, cells: &[[u32; N]]) -> SimplexMesh<D, N> {
    SimplexMesh {
        nodes,
        cells: cells.to_vec(),
        cell_regions: vec![0; cells.len()],
        region_names: vec!["specimen".to_string()],
        node_sets: BTreeMap::new(),
        face_sets: BTreeMap::new(),
    }
}

/// The `(time [s], file)` entries of a `.pvd` collection, files resolved against
/// the `.pvd`'s folder, in the order written.
pub fn read_pvd(path: impl AsRef<Path>) -> Result<Vec<(f64, PathBuf)>, GltfError> {
    let path = path.as_ref();
    let text = crate::input::read_to_string(path).map_err(|source| GltfError::Read { path: path.into(), source })?;
    let bad = |cause: String| GltfError::bad_file(path, cause);
    let doc = roxmltree::Document::parse(&text).map_err(|e| bad(format!("not well-formed XML: {e}")))?;
    if doc.root_element().attribute("type") != Some("Collection") {
        return Err(bad("not a VTK Collection (.pvd) file".into()));
    }
    let folder = path.parent().unwrap_or(Path::new(""));
    doc.descendants()
        .filter(|n| n.has_tag_name("DataSet"))
        .enumerate()
        .map(|(i, n)| {
            let t = n.attribute("timestep").and_then(|s| s.trim().parse::<f64>().ok()).filter(|t| t.is_finite());
            let file = n.attribute("file").filter(|f| !f.is_empty());
            match (t, file) {
                (Some(t), Some(file)) => Ok((t, folder.join(file))),
                _ => Err(bad(format!("DataSet {i} lacks a finite timestep or a file"))),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vtu::{pvd_string, vtu_string, VtuFields};
    use fem_core::mesh;

    #[test]
    fn reads_back_what_the_vtu_writer_wrote_exactly() {
        let m = mesh::block([2.0, 1.0, 1.0 / 3.0], 0.5, "a").unwrap();
        let u: Vec<f64> = (0..3 * m.nodes.len()).map(|i| (i as f64).sqrt() * 1e-3 - 0.1).collect();
        let fields = VtuFields { displacement_mm: Some(&u), ..Default::default() };
        let shape = VtuShape::parse(&vtu_string(&m, &fields).unwrap(), Path::new("a.vtu")).unwrap();
        let back = shape.tet_mesh().unwrap();
        assert_eq!((back.nodes, back.cells), (m.nodes.clone(), m.cells.clone()));
        assert_eq!(shape.nodal_displacement(3), u);
        assert!(shape.tri_mesh().is_none());

        let m = mesh::rectangle(2.0, 1.0, 0.5, "a").unwrap();
        let u: Vec<f64> = (0..2 * m.nodes.len()).map(|i| 0.1 * i as f64).collect();
        let fields = VtuFields { displacement_mm: Some(&u), ..Default::default() };
        let shape = VtuShape::parse(&vtu_string(&m, &fields).unwrap(), Path::new("a.vtu")).unwrap();
        assert_eq!(shape.tri_mesh().unwrap().nodes, m.nodes);
        assert_eq!(shape.nodal_displacement(2), u);
    }

    #[test]
    fn damaged_files_name_the_file() {
        let m = mesh::rectangle(1.0, 1.0, 0.5, "a").unwrap();
        let good = vtu_string(&m, &VtuFields::default()).unwrap();
        for (bad, needle) in [
            (good.replace("NumberOfPoints=\"", "NumberOfPoints=\"1"), "Points has"),
            (good.replace("Name=\"displacement\"", "Name=\"u\""), "displacement"),
            (good.replace("format=\"ascii\"", "format=\"binary\""), "ascii"),
            (good.replace("</VTKFile>", ""), "XML"),
            (good.replace("          0 1", "          0 999"), "point 999"),
        ] {
            let err = VtuShape::parse(&bad, Path::new("out/keep.vtu")).unwrap_err().to_string();
            assert!(err.starts_with("out/keep.vtu: ") && err.contains(needle), "{err}");
        }
    }

    #[test]
    fn pvd_entries_resolve_against_its_folder() {
        let dir = tempfile::tempdir().unwrap();
        let pvd = dir.path().join("shapes.pvd");
        std::fs::write(&pvd, pvd_string(&[(0.0, "shapes/a.vtu"), (2.5, "shapes/b.vtu")])).unwrap();
        let entries = read_pvd(&pvd).unwrap();
        assert_eq!(entries, vec![(0.0, dir.path().join("shapes/a.vtu")), (2.5, dir.path().join("shapes/b.vtu"))]);
        std::fs::write(&pvd, "<VTKFile type=\"Collection\"><Collection><DataSet file=\"x\"/></Collection></VTKFile>")
            .unwrap();
        assert!(read_pvd(&pvd).unwrap_err().to_string().contains("timestep"));
    }
}
