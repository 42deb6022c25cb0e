use std::path::Path;

use fem_core::mesh::TetMesh;

use super::error::TetMeshError;
use super::{gmsh, tetgen};
use crate::error::WriteError;
use crate::vtu::{write_vtu, VtuFields};

/// A tetrahedral mesh file format, told by the file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TetMeshFormat {
    /// VTK XML unstructured grid (`.vtu`; ASCII data arrays when read).
    Vtu,
    /// Gmsh MSH 4.1 ASCII (`.msh`).
    Gmsh,
    /// TetGen `.node` + `.ele` + `.face` (`.node` or `.ele`).
    TetGen,
}

impl TetMeshFormat {
    /// The format of `path` by its extension (case-insensitive), or an error naming the file.
    pub fn of_path(path: &Path) -> Result<Self, TetMeshError> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("vtu") => Ok(TetMeshFormat::Vtu),
            Some("msh") => Ok(TetMeshFormat::Gmsh),
            Some("node" | "ele") => Ok(TetMeshFormat::TetGen),
            _ => Err(TetMeshError::UnknownFormat { file: path.to_path_buf() }),
        }
    }
}

/// Reads a `.msh`, TetGen or `.vtu` mesh, the format told by the extension.
pub fn read_tetmesh(path: impl AsRef<Path>) -> Result<TetMesh, TetMeshError> {
    let path = path.as_ref();
    match TetMeshFormat::of_path(path)? {
        TetMeshFormat::Gmsh => gmsh::read_gmsh(path),
        TetMeshFormat::TetGen => tetgen::read_tetgen(path),
        TetMeshFormat::Vtu => super::vtu::read_vtu_tetmesh(path),
    }
}

/// Writes `mesh` to `path`, the format told by the extension: `.vtu` (nodes,
/// tets and the `region` cell field; zero displacement), `.msh`, or `.node`/`.ele`
/// (writing `.node`, `.ele` and `.face` beside each other).
pub fn write_tetmesh(path: impl AsRef<Path>, mesh: &TetMesh) -> Result<(), WriteError> {
    let path = path.as_ref();
    let format = TetMeshFormat::of_path(path)
        .map_err(|e| WriteError::BadInput { path: path.to_path_buf(), cause: e.to_string() })?;
    match format {
        TetMeshFormat::Vtu => write_vtu(path, mesh, &VtuFields::default()),
        TetMeshFormat::Gmsh => gmsh::write_gmsh(path, mesh),
        TetMeshFormat::TetGen => tetgen::write_tetgen(path, mesh),
    }
}
