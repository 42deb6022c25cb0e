//! TetGen, Gmsh and VTK mesh files: round trips, foreign files, and refusals that name
//! the file, the line and the field.

use std::path::Path;

use fem_core::mesh::{layered_block, Layer, TetMesh};
use wagashi_io::tetmesh::{parse_gmsh, parse_tetgen, read_tetmesh, write_tetmesh, TetMeshError};

fn two_layers() -> TetMesh {
    let layers =
        [Layer { region: "jam".into(), thickness_mm: 0.5 }, Layer { region: "sponge".into(), thickness_mm: 1.0 }];
    layered_block(2.0, 1.0, &layers, 0.5).unwrap()
}

fn same(a: &TetMesh, b: &TetMesh) {
    assert_eq!(a.nodes, b.nodes, "nodes (bit for bit)");
    assert_eq!(a.cells, b.cells);
    assert_eq!(a.cell_regions, b.cell_regions);
    assert_eq!(a.region_names, b.region_names);
}

#[test]
fn tetgen_and_gmsh_round_trip_nodes_cells_and_regions() {
    let dir = tempfile::tempdir().unwrap();
    let mut mesh = two_layers();
    // Coordinates that need all their digits.
    for p in &mut mesh.nodes {
        p[0] += 1.0 / 3.0;
        p[2] *= 1e-7;
    }
    for name in ["m.msh", "m.node", "n.ele"] {
        let path = dir.path().join(name);
        write_tetmesh(&path, &mesh).unwrap();
        let back = read_tetmesh(&path).unwrap();
        same(&mesh, &back);
        let boundary = mesh.boundary_facets().len();
        let faces: usize = back.face_sets.values().map(Vec::len).sum();
        assert_eq!(faces, boundary, "{name}: boundary faces");
    }
    for f in ["m.node", "m.ele", "m.face", "n.node", "n.ele", "n.face", "m.msh"] {
        assert!(dir.path().join(f).is_file(), "{f}");
    }
    // Gmsh names the boundary's physical group.
    let back = read_tetmesh(dir.path().join("m.msh")).unwrap();
    assert_eq!(back.face_sets.keys().collect::<Vec<_>>(), vec!["boundary"]);
}

/// TetGen names its output `STEM.1.node`, `STEM.1.ele`, `STEM.1.face`: the `.1`
/// belongs to the stem, whichever of the files is named.
#[test]
fn tetgen_output_names_keep_their_numbered_stem() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = two_layers();
    write_tetmesh(dir.path().join("bunny.1.node"), &mesh).unwrap();
    for f in ["bunny.1.node", "bunny.1.ele", "bunny.1.face"] {
        assert!(dir.path().join(f).is_file(), "{f}");
    }
    assert!(!dir.path().join("bunny.node").exists());
    for name in ["bunny.1.node", "bunny.1.ele"] {
        same(&mesh, &read_tetmesh(dir.path().join(name)).unwrap());
    }
}

/// A `.vtu` written with its regions reads back as the same mesh, region names
/// included (from the writer's comment).
#[test]
fn a_vtu_round_trips_nodes_cells_and_regions() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.vtu");
    let mut mesh = two_layers();
    for p in &mut mesh.nodes {
        p[0] += 1.0 / 3.0;
    }
    write_tetmesh(&path, &mesh).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("Name=\"region\""));
    same(&mesh, &read_tetmesh(&path).unwrap());
}

/// A `.vtu` as meshio writes it in ASCII: `gmsh:physical` regions without names,
/// triangles and a vertex to skip, a tet in the negative orientation.
#[test]
fn a_foreign_vtu_is_read() {
    let text = r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
<UnstructuredGrid>
<Piece NumberOfPoints="5" NumberOfCells="4">
<Points>
<DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii">
0 0 0 1 0 0 0 1 0 0 0 1 1 1 1
</DataArray>
</Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="ascii">
0 1 2 0 0 1 2 3 1 3 2 4
</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">
3 4 8 12
</DataArray>
<DataArray type="Int64" Name="types" format="ascii">
5 1 10 10
</DataArray>
</Cells>
<CellData>
<DataArray type="Int32" Name="gmsh:physical" format="ascii">
9 9 7 4
</DataArray>
</CellData>
</Piece>
</UnstructuredGrid>
</VTKFile>
"#;
    let m = wagashi_io::tetmesh::parse_vtu_tetmesh(Path::new("f.vtu"), text).unwrap();
    assert_eq!((m.nodes.len(), m.cells.len()), (5, 2));
    assert_eq!(m.region_names, vec!["region4", "region7"]);
    assert_eq!(m.cell_regions, vec![1, 0]);
    m.validate().unwrap();
}

#[test]
fn vtu_refusals_name_file_line_and_field() {
    let grid = |points: &str, conn: &str, offsets: &str, types: &str, format: &str| {
        format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\">\n<UnstructuredGrid>\n<Piece>\n<Points>\n\
             <DataArray Name=\"Points\" NumberOfComponents=\"3\" format=\"{format}\">{points}</DataArray>\n</Points>\n\
             <Cells>\n<DataArray Name=\"connectivity\" format=\"ascii\">{conn}</DataArray>\n\
             <DataArray Name=\"offsets\" format=\"ascii\">{offsets}</DataArray>\n\
             <DataArray Name=\"types\" format=\"ascii\">{types}</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n"
        )
    };
    let tet = "0 0 0 1 0 0 0 1 0 0 0 1";
    let cases = [
        (grid(tet, "0 1 2 3", "4", "10", "binary"), "f.vtu:6: Points: format=\"binary\": only ASCII"),
        (
            grid("0 0 0 1 0 0 0 1 0 1 1 0", "0 1 2 3", "4", "10", "ascii"),
            "f.vtu:9: connectivity: cell 0: flat tetrahedron",
        ),
        (grid(tet, "0 1 2 7", "4", "10", "ascii"), "f.vtu:9: connectivity: cell 0: point 7 is not in 0..4"),
        (
            grid(tet, "0 1 2 3 4 5 6 7", "8", "12", "ascii"),
            "f.vtu:11: types: cell 0: VTK type 12: only linear tetrahedra",
        ),
        (grid(tet, "0 1 2", "3", "5", "ascii"), "f.vtu:11: types: no tetrahedra"),
        (grid(tet, "0 1 2 3", "9", "10", "ascii"), "f.vtu:10: offsets: cell 0: offset 9 out of order or range"),
        ("<VTKFile type=\"PolyData\"/>".to_string(), "f.vtu:1: VTKFile: not a VTK UnstructuredGrid"),
        ("<VTKFile".to_string(), "f.vtu:1: xml: not well-formed XML"),
    ];
    for (text, want) in cases {
        let err = wagashi_io::tetmesh::parse_vtu_tetmesh(Path::new("f.vtu"), &text).unwrap_err();
        assert!(err.to_string().starts_with(want), "{err}\nwanted: {want}");
    }
}

/// A TetGen file as TetGen writes it: 0-based here, comments, a region attribute
/// without names, boundary markers on points, a tet in the other orientation.
#[test]
fn a_foreign_tetgen_file_is_read() {
    let node = "# a comment\n5 3 0 1\n0 0 0 0 1\n1 1 0 0 1\n2 0 1 0 1\n3 0 0 1 1\n4 1 1 1 1 # last\n";
    let ele = "2 4 1\n0 0 1 2 3 -1\n1 1 2 3 4 7.5\n";
    let m = parse_tetgen(Path::new("t.node"), node, Path::new("t.ele"), ele, None).unwrap();
    assert_eq!(m.nodes.len(), 5);
    assert_eq!(m.region_names, vec!["region-1", "region7.5"]);
    assert_eq!(m.cell_regions, vec![0, 1]);
    m.validate().unwrap();
    assert!((m.measure() - (1.0 / 6.0 + 1.0 / 3.0)).abs() < 1e-12, "{}", m.measure());
}

#[test]
fn tetgen_refusals_name_file_line_and_field() {
    let node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    let cases = [
        (
            "3 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n",
            "1 4 0\n1 1 2 3 4\n",
            "t.ele:2: node 4: 4 names no point (points 1..3)",
        ),
        (node, "1 10 0\n1 1 2 3 4 5 6 7 8 9 10\n", "t.ele:1: nodes per tetrahedron: 10: only linear tetrahedra"),
        (node, "1 4 0\n1 1 2 3 x\n", "t.ele:2: node 4: `x` is not an integer"),
        (node, "2 4 0\n1 1 2 3 4\n", "t.ele:2: tetrahedron 2: the file ends here"),
        (node, "1 4 0\n1 1 2 2 4\n", "t.ele:2: tetrahedron: flat (zero volume)"),
        ("4 2 0 0\n", "", "t.node:1: dimension: 2: only 3D meshes are read"),
        ("2 3 0 0\n1 0 0 0\n3 nan 0 0\n", "", "t.node:3: point index: 3: expected 2"),
        ("2 3 0 0\n1 0 0 0\n2 nan 0 0\n", "", "t.node:3: x: `nan` is not finite"),
    ];
    for (n, e, want) in cases {
        let err = parse_tetgen(Path::new("t.node"), n, Path::new("t.ele"), e, None).unwrap_err();
        assert!(matches!(err, TetMeshError::Invalid { .. }), "{err:?}");
        assert!(err.to_string().starts_with(want), "{err}\nwanted: {want}");
    }
    let dir = tempfile::tempdir().unwrap();
    let err = read_tetmesh(dir.path().join("none.node")).unwrap_err();
    assert!(err.to_string().contains("none.node: cannot read"), "{err}");
    let err = read_tetmesh(dir.path().join("x.obj")).unwrap_err();
    assert!(err.to_string().contains("unknown mesh format"), "{err}");
}

/// A file as Gmsh 4.1 writes it: entities with physical groups, sparse node tags,
/// points and lines to ignore, a parametric node block.
#[test]
fn a_foreign_gmsh_file_is_read() {
    let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n\
$PhysicalNames\n2\n3 7 \"filling\"\n2 9 \"skin\"\n$EndPhysicalNames\n\
$Entities\n1 0 1 2\n1 0 0 0 0\n3 0 0 0 1 1 1 1 9 0\n5 0 0 0 1 1 1 1 7 0\n6 0 0 0 1 1 1 0 0\n$EndEntities\n\
$Nodes\n2 5 10 50\n0 1 0 1\n10\n0 0 0\n2 3 1 4\n20\n30\n40\n50\n1 0 0 0.5 0.5\n0 1 0 0.5 0.5\n0 0 1 0.5 0.5\n1 1 1 0.5 0.5\n$EndNodes\n\
$Elements\n4 5 1 5\n0 1 15 1\n1 10\n2 3 2 1\n2 10 20 30\n3 5 4 1\n3 10 20 30 40\n3 6 4 2\n4 20 40 30 50\n5 20 30 40 50\n$EndElements\n";
    let m = parse_gmsh(Path::new("f.msh"), text).unwrap();
    assert_eq!(m.nodes.len(), 5);
    assert_eq!(m.cells.len(), 3);
    assert_eq!(m.region_names, vec!["filling", "volume6"]);
    assert_eq!(m.cell_regions, vec![0, 1, 1]);
    assert_eq!(m.face_sets["skin"], vec![[0, 1, 2]]);
    m.validate().unwrap();
}

#[test]
fn gmsh_refusals_name_file_line_and_field() {
    let head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
    let cases = [
        ("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n".to_string(), "f.msh:2: $MeshFormat: version 2.2: only MSH 4.1 is read"),
        ("$MeshFormat\n4.1 1 8\n$EndMeshFormat\n".to_string(), "f.msh:2: file-type: binary MSH"),
        (format!("{head}$Nodes\n1 1 1 1\n3 1 0 1\n1\n0 0\n$EndNodes\n"), "f.msh:8: node coordinates: 2 values; expected 3"),
        (
            format!("{head}$Nodes\n1 1 1 1\n3 1 0 1\n1\n0 0 0\n$EndNodes\n$Elements\n1 1 1 1\n3 1 11 1\n1 1 1 1 1 1 1 1 1 1 1\n$EndElements\n"),
            "f.msh:12: elementType: 11: only linear tetrahedra",
        ),
        (
            format!("{head}$Nodes\n1 1 1 1\n3 1 0 1\n1\n0 0 0\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 1 1 7\n$EndElements\n"),
            "f.msh:13: node 4: node 7 is not in $Nodes",
        ),
        (format!("{head}$Nodes\n1 1 1 1\n"), "f.msh:5: node block: the file ends here"),
        ("hello\n".to_string(), "f.msh:1: section: expected a `$Section` header"),
        (format!("{head}$Nodes\n0 0 0 0\n$EndNodes\n"), "f.msh:6: $Elements: no tetrahedra"),
    ];
    for (text, want) in cases {
        let err = parse_gmsh(Path::new("f.msh"), &text).unwrap_err();
        assert!(err.to_string().starts_with(want), "{err}\nwanted: {want}");
    }
}
