//! VTU and PVD output parse as XML with the right sizes and values.

use fem_core::mesh;
use wagashi_io::vtu::{pvd_string, vtu_string, write_pvd, write_vtu, Coordinates, VtuFields};

fn numbers(doc: &roxmltree::Document<'_>, name: &str) -> Vec<f64> {
    let node = doc
        .descendants()
        .find(|n| n.has_tag_name("DataArray") && n.attribute("Name") == Some(name))
        .unwrap_or_else(|| panic!("no DataArray {name}"));
    node.text().unwrap_or("").split_whitespace().map(|s| s.parse().unwrap()).collect()
}

fn piece_sizes(doc: &roxmltree::Document<'_>) -> (usize, usize) {
    let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
    (
        piece.attribute("NumberOfPoints").unwrap().parse().unwrap(),
        piece.attribute("NumberOfCells").unwrap().parse().unwrap(),
    )
}

#[test]
fn triangles_in_2d() {
    let m = mesh::rectangle(4.0, 3.0, 1.0, "mat1").unwrap();
    let u: Vec<f64> = (0..2 * m.nodes.len()).map(|i| i as f64 * 0.01).collect();
    let stress: Vec<f64> = (0..3 * m.cells.len()).map(|i| i as f64).collect();
    let fields =
        VtuFields { displacement_mm: Some(&u), cell_stress_mpa: Some(&stress), coordinates: Coordinates::Reference };
    let text = vtu_string(&m, &fields).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    assert_eq!(doc.root_element().attribute("type"), Some("UnstructuredGrid"));
    assert_eq!(piece_sizes(&doc), (20, 24));
    let points = numbers(&doc, "Points");
    assert_eq!(points.len(), 3 * 20);
    assert!(points.chunks(3).zip(&m.nodes).all(|(p, n)| p[0] == n[0] && p[1] == n[1] && p[2] == 0.0));
    let disp = numbers(&doc, "displacement");
    assert_eq!(disp.len(), 3 * 20);
    assert_eq!(&disp[3..6], &[0.02, 0.03, 0.0]);
    assert_eq!(numbers(&doc, "connectivity").len(), 3 * 24);
    assert_eq!(numbers(&doc, "offsets").last(), Some(&72.0));
    let types = numbers(&doc, "types");
    assert_eq!(types.len(), 24);
    assert!(types.iter().all(|&t| t == 5.0));
    assert_eq!(numbers(&doc, "region"), vec![0.0; 24]);
    // Cell 1's [xx, yy, xy] = [3, 4, 5] -> [XX, YY, ZZ, XY, YZ, XZ].
    let s = numbers(&doc, "stress");
    assert_eq!(s.len(), 6 * 24);
    assert_eq!(&s[6..12], &[3.0, 4.0, 0.0, 5.0, 0.0, 0.0]);
}

#[test]
fn tetrahedra_in_3d_with_regions_and_deformed_points() {
    let layers =
        [mesh::Layer { region: "a".into(), thickness_mm: 1.0 }, mesh::Layer { region: "b".into(), thickness_mm: 1.0 }];
    let m = mesh::layered_block(2.0, 1.0, &layers, 1.0).unwrap();
    let (n, c) = (m.nodes.len(), m.cells.len());
    assert_eq!((n, c), (18, 24));
    let u: Vec<f64> = (0..3 * n).map(|i| -(i as f64) / 8.0).collect();
    let stress: Vec<f64> = (0..6 * c).map(|i| (i % 6) as f64 + 10.0 * (i / 6) as f64).collect();
    let fields =
        VtuFields { displacement_mm: Some(&u), cell_stress_mpa: Some(&stress), coordinates: Coordinates::Deformed };
    let text = vtu_string(&m, &fields).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    assert_eq!(piece_sizes(&doc), (n, c));
    let points = numbers(&doc, "Points");
    for (i, node) in m.nodes.iter().enumerate() {
        for k in 0..3 {
            assert!((points[3 * i + k] - (node[k] + u[3 * i + k])).abs() < 1e-15);
        }
    }
    let conn = numbers(&doc, "connectivity");
    assert_eq!(conn.len(), 4 * c);
    assert_eq!(conn[4..8], m.cells[1].map(|v| v as f64));
    assert!(numbers(&doc, "types").iter().all(|&t| t == 10.0));
    let regions = numbers(&doc, "region");
    assert_eq!(regions, m.cell_regions.iter().map(|&r| r as f64).collect::<Vec<_>>());
    assert!(regions.contains(&0.0) && regions.contains(&1.0));
    // fem-core [xx, yy, zz, xy, xz, yz] = [0..6] -> VTK [XX, YY, ZZ, XY, YZ, XZ] = [0, 1, 2, 3, 5, 4].
    let s = numbers(&doc, "stress");
    assert_eq!(&s[6..12], &[10.0, 11.0, 12.0, 13.0, 15.0, 14.0]);
    let stress_node = doc.descendants().find(|n| n.attribute("Name") == Some("stress")).unwrap();
    assert_eq!(stress_node.attribute("ComponentName4"), Some("YZ"));
    assert!(text.contains("0 = a, 1 = b"));
}

#[test]
fn defaults_and_files() {
    let m = mesh::block([1.0, 1.0, 1.0], 1.0, "x--y").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("state.vtu");
    write_vtu(&path, &m, &VtuFields::default()).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    assert!(numbers(&doc, "displacement").iter().all(|&v| v == 0.0));
    assert!(!doc.descendants().any(|n| n.attribute("Name") == Some("stress")));

    let pvd = dir.path().join("series.pvd");
    write_pvd(&pvd, &[(0.0, "state_0.vtu"), (210.93, "a&b/state_1.vtu")]).unwrap();
    let text = std::fs::read_to_string(&pvd).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let sets: Vec<_> = doc.descendants().filter(|n| n.has_tag_name("DataSet")).collect();
    assert_eq!(sets.len(), 2);
    assert_eq!(sets[1].attribute("timestep"), Some("210.93"));
    assert_eq!(sets[1].attribute("file"), Some("a&b/state_1.vtu"));
    assert_eq!(pvd_string::<&str>(&[]).matches("DataSet").count(), 0);
}

#[test]
fn wrong_field_lengths_are_errors() {
    let m = mesh::rectangle(1.0, 1.0, 1.0, "m").unwrap();
    let u = vec![0.0; 3];
    let err = vtu_string(&m, &VtuFields { displacement_mm: Some(&u), ..VtuFields::default() }).unwrap_err();
    assert!(err.to_string().contains("displacement has 3 values"), "{err}");
    let s = vec![0.0; 5];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.vtu");
    let err = write_vtu(&path, &m, &VtuFields { cell_stress_mpa: Some(&s), ..VtuFields::default() }).unwrap_err();
    assert!(err.to_string().starts_with(&format!("{}: stress has 5 values", path.display())), "{err}");
    assert!(!path.exists());
    let mut broken = m.clone();
    broken.cells[0][1] = 99;
    assert!(vtu_string(&broken, &VtuFields::default()).is_err());
}
