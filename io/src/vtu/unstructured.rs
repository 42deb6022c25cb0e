use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use fem_core::mesh::SimplexMesh;
use fem_core::press::Snapshot;

use crate::atomic::write_atomic;
use crate::error::WriteError;
use crate::number::push_shortest;

/// VTK's cell type of a linear triangle.
pub const VTK_TRIANGLE: u8 = 5;
/// VTK's cell type of a linear tetrahedron.
pub const VTK_TETRA: u8 = 10;

/// Which point coordinates a `.vtu` holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Coordinates {
    /// The mesh's reference coordinates, with the displacement as a field (default).
    #[default]
    Reference,
    /// The deformed coordinates `x + u`.
    Deformed,
}

/// The fields written with a mesh.
#[derive(Debug, Clone, Copy, Default)]
pub struct VtuFields<'a> {
    /// Nodal displacements [mm], `D` per node; `None`: zero.
    pub displacement_mm: Option<&'a [f64]>,
    /// Cell stresses [MPa], fem-core's Voigt order, `D (D + 1) / 2` per cell, or
    /// 4 per cell for an axisymmetric section (`[rr, yy, θθ, ry]`, D = 2);
    /// `None`: no `stress` array.
    pub cell_stress_mpa: Option<&'a [f64]>,
    /// Reference (default) or deformed coordinates.
    pub coordinates: Coordinates,
}

impl<'a> VtuFields<'a> {
    /// The displacement and stress of a kept state, reference coordinates.
    pub fn from_snapshot(snapshot: &'a Snapshot) -> Self {
        Self {
            displacement_mm: Some(&snapshot.displacement),
            cell_stress_mpa: Some(&snapshot.cell_stress),
            coordinates: Coordinates::Reference,
        }
    }
}

fn bad(cause: String) -> WriteError {
    WriteError::BadInput { path: PathBuf::from("(vtu)"), cause }
}

/// Positions in fem-core's Voigt order of VTK's `XX, YY, ZZ, XY, YZ, XZ`.
const VOIGT_3D_TO_VTK: [usize; 6] = [0, 1, 2, 3, 5, 4];

/// The stress components' names: Cartesian, and for an axisymmetric section
/// (x = r, z = the hoop direction θ at the section's plane) the cylindrical ones.
const CARTESIAN_NAMES: [&str; 6] = ["XX", "YY", "ZZ", "XY", "YZ", "XZ"];
const AXISYMMETRIC_NAMES: [&str; 6] = ["RR", "YY", "TT", "RY", "YT", "RT"];

/// The `.vtu` text of `mesh` with `fields` (see the module docs).
pub fn vtu_string<const D: usize, const N: usize>(
    mesh: &SimplexMesh<D, N>,
    fields: &VtuFields<'_>,
) -> Result<String, WriteError> {
    const { assert!((D == 2 && N == 3) || (D == 3 && N == 4), "triangles or tetrahedra") };
    let num_nodes = mesh.nodes.len();
    let num_cells = mesh.cells.len();
    // Stress values per cell: D (D + 1)/2, or 4 for an axisymmetric section.
    let mut s = D * (D + 1) / 2;
    let axisymmetric = D == 2 && fields.cell_stress_mpa.is_some_and(|st| num_cells > 0 && st.len() == 4 * num_cells);
    if axisymmetric {
        s = 4;
    }
    if let Some(u) = fields.displacement_mm {
        if u.len() != D * num_nodes {
            return Err(bad(format!("displacement has {} values; {num_nodes} nodes need {}", u.len(), D * num_nodes)));
        }
    }
    if let Some(st) = fields.cell_stress_mpa {
        if st.len() != s * num_cells {
            let need = if D == 2 {
                format!("{} (or {} axisymmetric)", s * num_cells, 4 * num_cells)
            } else {
                (s * num_cells).to_string()
            };
            return Err(bad(format!("stress has {} values; {num_cells} cells need {need}", st.len())));
        }
    }
    if mesh.cell_regions.len() != num_cells {
        return Err(bad(format!("{} cell regions for {num_cells} cells", mesh.cell_regions.len())));
    }
    if let Some((e, v)) =
        mesh.cells.iter().enumerate().find_map(|(e, c)| c.iter().find(|&&v| v as usize >= num_nodes).map(|&v| (e, v)))
    {
        return Err(bad(format!("cell {e} names node {v}, but the mesh has {num_nodes} nodes")));
    }
    let disp = |i: usize, k: usize| -> f64 {
        match fields.displacement_mm {
            Some(u) if k < D => u[D * i + k],
            _ => 0.0,
        }
    };

    let mut x = String::with_capacity(64 * num_nodes + 96 * num_cells + 1024);
    x.push_str("<?xml version=\"1.0\"?>\n");
    x.push_str("<!-- written by wagashi-io; cell data `region` indexes these regions:");
    for (i, name) in mesh.region_names.iter().enumerate() {
        // `--` may not appear inside an XML comment.
        let _ = write!(x, " {i} = {}", name.replace("--", "- -"));
        if i + 1 < mesh.region_names.len() {
            x.push(',');
        }
    }
    x.push_str(" -->\n");
    if axisymmetric {
        x.push_str(
            "<!-- axisymmetric section: x is the radius r, y the axis; stress components RR, YY, TT (hoop), RY -->\n",
        );
    }
    x.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    x.push_str("  <UnstructuredGrid>\n");
    let _ = writeln!(x, "    <Piece NumberOfPoints=\"{num_nodes}\" NumberOfCells=\"{num_cells}\">");

    x.push_str("      <PointData Vectors=\"displacement\">\n");
    x.push_str(
        "        <DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n",
    );
    for i in 0..num_nodes {
        x.push_str("          ");
        for k in 0..3 {
            push_shortest(&mut x, disp(i, k));
            x.push(if k < 2 { ' ' } else { '\n' });
        }
    }
    x.push_str("        </DataArray>\n      </PointData>\n");

    x.push_str("      <CellData Scalars=\"region\">\n");
    x.push_str("        <DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">\n");
    for chunk in mesh.cell_regions.chunks(32) {
        x.push_str("          ");
        for (j, r) in chunk.iter().enumerate() {
            let _ = write!(x, "{r}{}", if j + 1 < chunk.len() { ' ' } else { '\n' });
        }
    }
    x.push_str("        </DataArray>\n");
    if let Some(st) = fields.cell_stress_mpa {
        x.push_str("        <DataArray type=\"Float64\" Name=\"stress\" NumberOfComponents=\"6\"");
        let names = if axisymmetric { AXISYMMETRIC_NAMES } else { CARTESIAN_NAMES };
        for (k, c) in names.iter().enumerate() {
            let _ = write!(x, " ComponentName{k}=\"{c}\"");
        }
        x.push_str(" format=\"ascii\">\n");
        for cell in st.chunks(s) {
            let vtk: [f64; 6] = match (D, s) {
                // [rr, yy, θθ, ry]: the section's tensor with z the hoop direction.
                (2, 4) => [cell[0], cell[1], cell[2], cell[3], 0.0, 0.0],
                (2, _) => [cell[0], cell[1], 0.0, cell[2], 0.0, 0.0],
                _ => VOIGT_3D_TO_VTK.map(|k| cell[k]),
            };
            x.push_str("          ");
            for (k, v) in vtk.iter().enumerate() {
                push_shortest(&mut x, *v);
                x.push(if k < 5 { ' ' } else { '\n' });
            }
        }
        x.push_str("        </DataArray>\n");
    }
    x.push_str("      </CellData>\n");

    x.push_str("      <Points>\n");
    x.push_str("        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (i, p) in mesh.nodes.iter().enumerate() {
        x.push_str("          ");
        for k in 0..3 {
            let mut v = p.get(k).copied().unwrap_or(0.0);
            if fields.coordinates == Coordinates::Deformed {
                v += disp(i, k);
            }
            push_shortest(&mut x, v);
            x.push(if k < 2 { ' ' } else { '\n' });
        }
    }
    x.push_str("        </DataArray>\n      </Points>\n");

    x.push_str("      <Cells>\n");
    x.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for c in &mesh.cells {
        x.push_str("          ");
        for (j, v) in c.iter().enumerate() {
            let _ = write!(x, "{v}{}", if j + 1 < N { ' ' } else { '\n' });
        }
    }
    x.push_str("        </DataArray>\n");
    x.push_str("        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for chunk_start in (0..num_cells).step_by(32) {
        x.push_str("          ");
        let end = (chunk_start + 32).min(num_cells);
        for e in chunk_start..end {
            let _ = write!(x, "{}{}", (e + 1) * N, if e + 1 < end { ' ' } else { '\n' });
        }
    }
    x.push_str("        </DataArray>\n");
    x.push_str("        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    let cell_type = if D == 2 { VTK_TRIANGLE } else { VTK_TETRA };
    for chunk_start in (0..num_cells).step_by(32) {
        x.push_str("          ");
        let end = (chunk_start + 32).min(num_cells);
        for e in chunk_start..end {
            let _ = write!(x, "{cell_type}{}", if e + 1 < end { ' ' } else { '\n' });
        }
    }
    x.push_str("        </DataArray>\n      </Cells>\n");
    x.push_str("    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    Ok(x)
}

/// Writes `mesh` with `fields` to the `.vtu` file `path`, atomically.
pub fn write_vtu<const D: usize, const N: usize>(
    path: impl AsRef<Path>,
    mesh: &SimplexMesh<D, N>,
    fields: &VtuFields<'_>,
) -> Result<(), WriteError> {
    let path = path.as_ref();
    let text = vtu_string(mesh, fields).map_err(|e| match e {
        WriteError::BadInput { cause, .. } => WriteError::BadInput { path: path.to_path_buf(), cause },
        other => other,
    })?;
    write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An axisymmetric section's `[rr, yy, θθ, ry]` is written as the tensor at the
    /// section's plane with the hoop stress as ZZ, under cylindrical names.
    #[test]
    fn axisymmetric_stress_is_named_and_placed() {
        let m = fem_core::mesh::axisymmetric_section(2.0, 1.0, 1.0, "gel").unwrap();
        let num_cells = m.cells.len();
        let stress: Vec<f64> = (0..4 * num_cells).map(|i| i as f64).collect();
        let fields = VtuFields { cell_stress_mpa: Some(&stress), ..VtuFields::default() };
        let text = vtu_string(&m, &fields).unwrap();
        assert!(text.contains("axisymmetric section"));
        for (k, name) in AXISYMMETRIC_NAMES.iter().enumerate() {
            assert!(text.contains(&format!("ComponentName{k}=\"{name}\"")), "{name}");
        }
        // Cell 1's [rr, yy, θθ, ry] = [4, 5, 6, 7].
        assert!(text.contains("\n          4 5 6 7 0 0\n"), "{text}");
        // Plane cells (3 per cell) keep the Cartesian names; other counts are refused.
        let plane: Vec<f64> = vec![1.0; 3 * num_cells];
        let text = vtu_string(&m, &VtuFields { cell_stress_mpa: Some(&plane), ..VtuFields::default() }).unwrap();
        assert!(text.contains("ComponentName2=\"ZZ\"") && !text.contains("axisymmetric"));
        let bad: Vec<f64> = vec![1.0; 5 * num_cells];
        let err = vtu_string(&m, &VtuFields { cell_stress_mpa: Some(&bad), ..VtuFields::default() }).unwrap_err();
        assert!(err.to_string().contains("or 16 axisymmetric"), "{err}");
    }
}
