//! Tetrahedral meshes from VTK XML unstructured grids (`.vtu`), ASCII data arrays
//! only (as wagashi, meshio's `ascii` mode and ParaView's "ascii" writer save them).
//!
//! - Points: the `<Points>` array, 3 components [mm].
//! - Cells: `connectivity`, `offsets` and `types` of `<Cells>`. Tetrahedra (VTK
//!   type 10) become cells; vertices, lines and triangles (types 1, 3, 5) are
//!   ignored; any other type is refused.
//! - Regions: the cell data `region` (wagashi's: its names are listed in the
//!   file's comment "cell data region indexes these regions: 0 = NAME, ..."),
//!   else `gmsh:physical` (meshio's) or `CellEntityIds`, an integer per cell; a
//!   value without a listed name is `region<value>`. Without such data every
//!   cell is in the region `region0`.
//! - Tets in the negative orientation are reversed; a flat one is refused.
//!
//! Refusals name the file, the line of the element at fault and the field.

use std::collections::BTreeMap;
use std::path::Path;

use fem_core::mesh::TetMesh;

use super::error::TetMeshError;
use super::tetgen::signed_volume;
use crate::vtu::VTK_TETRA;

/// VTK cell types of dimension below 3, which are skipped: vertex, line, triangle.
const LOWER_DIMENSION: [u8; 3] = [1, 3, 5];

/// Reads a `.vtu` tetrahedral mesh (module docs).
pub fn read_vtu_tetmesh(path: impl AsRef<Path>) -> Result<TetMesh, TetMeshError> {
    let path = path.as_ref();
    let text = crate::input::read_to_string(path).map_err(|source| TetMeshError::Read { file: path.into(), source })?;
    parse_vtu_tetmesh(path, &text)
}

/// Parses the text of a `.vtu` tetrahedral mesh; `file` names it in messages.
pub fn parse_vtu_tetmesh(file: &Path, text: &str) -> Result<TetMesh, TetMeshError> {
    let err = |line: u32, field: &str, cause: String| TetMeshError::invalid(file, line as usize, field, cause);
    let doc =
        roxmltree::Document::parse(text).map_err(|e| err(e.pos().row, "xml", format!("not well-formed XML: {e}")))?;
    let line_of = |n: roxmltree::Node| doc.text_pos_at(n.range().start).row;
    let root = doc.root_element();
    if root.tag_name().name() != "VTKFile" || root.attribute("type") != Some("UnstructuredGrid") {
        return Err(err(line_of(root), "VTKFile", "not a VTK UnstructuredGrid file".into()));
    }
    let piece = doc
        .descendants()
        .find(|n| n.has_tag_name("Piece"))
        .ok_or_else(|| err(line_of(root), "Piece", "no <Piece> in the file".into()))?;
    let array = |parent: &str, name: Option<&str>| {
        piece
            .descendants()
            .filter(|n| n.has_tag_name(parent))
            .flat_map(|p| p.children())
            .find(|n| n.has_tag_name("DataArray") && (name.is_none() || n.attribute("Name") == name))
    };
    let words = |node: roxmltree::Node<'_, '_>, field: &str| -> Result<Vec<String>, TetMeshError> {
        if node.attribute("format") != Some("ascii") {
            return Err(err(
                line_of(node),
                field,
                format!(
                    "format=\"{}\": only ASCII data arrays are read (save the file as ASCII)",
                    node.attribute("format").unwrap_or("")
                ),
            ));
        }
        Ok(node.text().unwrap_or("").split_whitespace().map(str::to_string).collect())
    };
    let required = |parent: &str, name: Option<&str>, field: &str| {
        array(parent, name).ok_or_else(|| err(line_of(piece), field, format!("no such DataArray in <{parent}>")))
    };
    let integers = |node: roxmltree::Node<'_, '_>, field: &str| -> Result<Vec<i64>, TetMeshError> {
        words(node, field)?
            .iter()
            .map(|w| w.parse::<i64>().map_err(|_| err(line_of(node), field, format!("`{w}` is not an integer"))))
            .collect()
    };

    let points = required("Points", None, "Points")?;
    let coords: Vec<f64> = words(points, "Points")?
        .iter()
        .map(|w| match w.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(err(line_of(points), "Points", format!("`{w}` is not a finite number"))),
        })
        .collect::<Result<_, _>>()?;
    if points.attribute("NumberOfComponents").unwrap_or("3") != "3" || !coords.len().is_multiple_of(3) {
        return Err(err(line_of(points), "Points", "expected 3 coordinates per point".into()));
    }
    let nodes: Vec<[f64; 3]> = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();

    let connectivity_node = required("Cells", Some("connectivity"), "connectivity")?;
    let offsets_node = required("Cells", Some("offsets"), "offsets")?;
    let types_node = required("Cells", Some("types"), "types")?;
    let (connectivity, offsets) = (integers(connectivity_node, "connectivity")?, integers(offsets_node, "offsets")?);
    let types = integers(types_node, "types")?;
    if offsets.len() != types.len() {
        return Err(err(line_of(types_node), "types", format!("{} types for {} offsets", types.len(), offsets.len())));
    }
    let region_node = ["region", "gmsh:physical", "CellEntityIds"].into_iter().find_map(|n| array("CellData", Some(n)));
    let cell_values = match region_node {
        Some(node) => {
            let v = integers(node, "region")?;
            if v.len() != types.len() {
                return Err(err(line_of(node), "region", format!("{} values for {} cells", v.len(), types.len())));
            }
            v
        }
        None => vec![0; types.len()],
    };
    let names = listed_region_names(text);

    let mut cells = Vec::new();
    let mut values: Vec<i64> = Vec::new();
    let mut start = 0usize;
    let line = line_of(connectivity_node);
    for (c, (&end, &kind)) in offsets.iter().zip(&types).enumerate() {
        let end = usize::try_from(end).ok().filter(|&e| e >= start && e <= connectivity.len()).ok_or_else(|| {
            err(line_of(offsets_node), "offsets", format!("cell {c}: offset {end} out of order or range"))
        })?;
        let ids = &connectivity[start..end];
        start = end;
        if u8::try_from(kind).is_ok_and(|k| LOWER_DIMENSION.contains(&k)) {
            continue;
        }
        if kind != i64::from(VTK_TETRA) {
            return Err(err(
                line_of(types_node),
                "types",
                format!("cell {c}: VTK type {kind}: only linear tetrahedra (10) are read"),
            ));
        }
        let mut cell = [0u32; 4];
        if ids.len() != 4 {
            return Err(err(line, "connectivity", format!("cell {c}: a tetrahedron has 4 points, not {}", ids.len())));
        }
        for (slot, &id) in cell.iter_mut().zip(ids) {
            *slot = u32::try_from(id).ok().filter(|&i| (i as usize) < nodes.len()).ok_or_else(|| {
                err(line, "connectivity", format!("cell {c}: point {id} is not in 0..{}", nodes.len()))
            })?;
        }
        let vol = signed_volume(&cell.map(|v| nodes[v as usize]));
        if !(vol != 0.0) {
            return Err(err(line, "connectivity", format!("cell {c}: flat tetrahedron (zero volume)")));
        }
        if vol < 0.0 {
            cell.swap(2, 3);
        }
        cells.push(cell);
        values.push(cell_values[c]);
    }
    if cells.is_empty() {
        return Err(err(line_of(types_node), "types", "no tetrahedra (type 10) in the file".into()));
    }
    let mut distinct: Vec<i64> = values.clone();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() > u16::MAX as usize {
        return Err(err(line_of(piece), "region", "more than 65535 regions".into()));
    }
    let cell_regions = values.iter().map(|v| distinct.binary_search(v).unwrap_or(0) as u16).collect();
    let region_names = distinct
        .iter()
        .map(|v| {
            let listed = usize::try_from(*v).ok().and_then(|i| names.get(i)).filter(|_| region_node.is_some());
            listed.cloned().unwrap_or_else(|| format!("region{v}"))
        })
        .collect();
    Ok(TetMesh { nodes, cells, cell_regions, region_names, node_sets: BTreeMap::new(), face_sets: BTreeMap::new() })
}

/// The region names wagashi's `.vtu` writer lists in its comment ("cell data
/// region indexes these regions: 0 = a, 1 = b"), by index; none when the
/// comment is absent or not in that form.
fn listed_region_names(text: &str) -> Vec<String> {
    const MARK: &str = "cell data `region` indexes these regions:";
    let Some(rest) = text.find(MARK).map(|i| &text[i + MARK.len()..]) else { return Vec::new() };
    let Some(list) = rest.find("-->").map(|j| &rest[..j]) else { return Vec::new() };
    let mut names = Vec::new();
    for (i, entry) in list.split(',').enumerate() {
        match entry.trim().split_once(" = ") {
            Some((k, name)) if k.trim() == i.to_string() => names.push(name.trim().to_string()),
            _ => return Vec::new(),
        }
    }
    names
}
