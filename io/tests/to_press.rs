//! From a bundle to fem-core's press problem.

mod common;

use common::*;
use fem_core::element::Formulation;
use fem_core::press::{AnyPress, Attachment};
use wagashi_io::{read_bundle, read_bundle_with, read_materials_file, BundleError};

fn solid(p: AnyPress) -> fem_core::press::SolidPress {
    match p {
        AnyPress::Solid(p) => p,
        _ => panic!("expected a 3D problem"),
    }
}

fn plane(p: AnyPress) -> fem_core::press::PlanePress {
    match p {
        AnyPress::Plane(p) => p,
        _ => panic!("expected a 2D problem"),
    }
}

#[test]
fn block_3d_with_mass_markers_and_protocol() {
    let b = with_experiment(EXPERIMENT);
    let bundle = read_bundle(&b.dir).unwrap();
    let p = solid(bundle.to_press(10.0).unwrap());
    assert_eq!(p.formulation, Formulation::Solid);
    assert_eq!(p.mesh.region_names, vec!["mat1".to_string()]);
    assert_eq!(p.materials, vec![fem_core::material::Material::seed_mat1_force()]);
    let volume = 58.0 * 59.5 * 12.0;
    assert!((p.mesh.measure() - volume).abs() < 1e-9 * volume);
    // 52.43 g in 41 412 mm^3 = 1.266 g/cm^3 = 1.266e-9 t/mm^3.
    let rho = 52.43 / volume * 1e-6;
    assert!((p.density_t_mm3 - rho).abs() < 1e-12 * rho, "{}", p.density_t_mm3);
    assert!((p.density_t_mm3 - 1.266e-9).abs() < 1e-12);
    assert_eq!(p.protocol.waypoints, vec![[0.0, 0.0], [28.87, 5.774], [210.93, 5.774]]);
    assert_eq!((p.protocol.release_s, p.protocol.end_s), (210.93, 400.0));
    assert_eq!(
        (p.protocol.plate, p.protocol.support, p.protocol.gravity),
        (Attachment::Glued, Attachment::Glued, false)
    );
    assert_eq!(p.markers.len(), 2);
    assert_eq!(p.markers[0].name, "m01");
    assert_eq!(p.markers[0].position, vec![5.0, 5.0, 12.0]);
    assert_eq!(p.markers[0].times, vec![0.0, 210.9, 400.0]);
    assert!(p.snapshot_times.is_empty());
}

#[test]
fn block_2d_is_plane_stress_with_the_thickness() {
    let toml = edit(EXPERIMENT, "dimension = 3", "dimension = 2");
    let toml = edit(&toml, "mass_g = 52.43", "density_g_cm3 = 1.1");
    let toml = edit(
        &toml,
        "tool_contact = \"glued\"\nsupport = \"glued\"",
        "tool_contact = \"frictionless\"\nsupport = \"glued\"\ngravity = true",
    );
    let markers = "marker,t_s,x_mm,y_mm\nm01,0.0,0.0,30.0\nm01,5.0,0.1,30.0\n";
    let b = bundle(&[("experiment.toml", &toml), ("force.csv", FORCE), ("markers.csv", markers)]);
    let p = plane(read_bundle(&b.dir).unwrap().to_press(10.0).unwrap());
    assert_eq!(p.formulation, Formulation::PlaneStress { thickness_mm: 12.0 });
    assert!((p.mesh.measure() - 58.0 * 59.5).abs() < 1e-9 * 58.0 * 59.5);
    assert!((p.density_t_mm3 - 1.1e-9).abs() < 1e-24);
    assert_eq!(
        (p.protocol.plate, p.protocol.support, p.protocol.gravity),
        (Attachment::Frictionless, Attachment::Glued, true)
    );
    assert_eq!(p.markers[0].position, vec![0.0, 30.0]);
    assert_eq!(p.markers[0].times, vec![0.0, 5.0]);
}

#[test]
fn plane_strain_is_a_2d_option_and_refused_in_3d() {
    let toml2 = edit(EXPERIMENT, "dimension = 3", "dimension = 2");
    let toml2 = edit(&toml2, "mass_g = 52.43", "mass_g = 52.43\nplane = \"strain\"");
    let markers = "marker,t_s,x_mm,y_mm\nm01,0.0,0.0,30.0\n";
    let b = bundle(&[("experiment.toml", &toml2), ("force.csv", FORCE), ("markers.csv", markers)]);
    let p = plane(read_bundle(&b.dir).unwrap().to_press(10.0).unwrap());
    assert_eq!(p.formulation, Formulation::PlaneStrain { thickness_mm: 12.0 });
    let toml3 = edit(EXPERIMENT, "mass_g = 52.43", "mass_g = 52.43\nplane = \"stress\"");
    let b3 = with_experiment(&toml3);
    let err = read_bundle(&b3.dir).unwrap_err().to_string();
    assert!(err.contains("experiment.toml:") && err.contains("specimen.plane"), "{err}");
}

#[test]
fn default_density_is_one_g_per_cm3() {
    let toml = edit(EXPERIMENT, "mass_g = 52.43\n", "");
    let p = solid(read_bundle(with_experiment(&toml).dir).unwrap().to_press(20.0).unwrap());
    assert!((p.density_t_mm3 - 1e-9).abs() < 1e-24);
}

#[test]
fn layers_become_regions_in_order() {
    let toml = edit(
        EXPERIMENT,
        "material = \"mat1\"\n",
        "[[specimen.layers]]\nmaterial = \"soft\"\nthickness_mm = 20.0\n[[specimen.layers]]\nmaterial = \"mat1\"\nthickness_mm = 19.5\n[[specimen.layers]]\nmaterial = \"soft\"\nthickness_mm = 20.0\n",
    );
    let toml = format!("{toml}\n[materials.soft]\nmodel = \"elastic\"\nE_MPa = 0.02\npoisson = 0.45\n");
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    for dim in [3, 2] {
        let p = if dim == 3 {
            solid(bundle.to_press(10.0).unwrap()).materials
        } else {
            let toml2 = edit(&toml, "dimension = 3", "dimension = 2");
            let b2 = bundle_files(&toml2);
            let p = plane(read_bundle(&b2.dir).unwrap().to_press(10.0).unwrap());
            assert_eq!(p.mesh.region_names, vec!["soft".to_string(), "mat1".to_string()]);
            p.materials
        };
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].rheology, fem_core::material::Rheology::Elastic { e_mpa: 0.02 });
        assert_eq!(p[1], fem_core::material::Material::seed_mat1_force());
    }
    let p = solid(bundle.to_press(10.0).unwrap());
    assert_eq!(p.mesh.region_names, vec!["soft".to_string(), "mat1".to_string()]);
}

fn bundle_files(toml: &str) -> TestBundle {
    let markers = if toml.contains("dimension = 2") { "marker,t_s,x_mm,y_mm\n" } else { MARKERS };
    bundle(&[("experiment.toml", toml), ("force.csv", FORCE), ("markers.csv", markers)])
}

#[test]
fn cylinder() {
    // The gel cylinder with a mass, three-element, without markers.
    let toml = edit(GEL_CYLINDER, "height_mm = 9.0\n", "height_mm = 9.0\nmass_g = 0.5\n");
    let toml = edit(
        &toml,
        "model = \"elastic\"\npoisson = 0.45\nE_MPa = 0.05\n",
        "model = \"three-element\"\npoisson = 0.45\nE1_MPa = 0.05\nc1_MPa_s = 0.3\nc3_MPa_s = 12.0\n",
    );
    let toml = edit(&toml, "\n[data]\nmarkers = \"markers.csv\"\n", "");
    let b = bundle(&[("experiment.toml", &toml)]);
    let p = solid(read_bundle(&b.dir).unwrap().to_press(1.0).unwrap());
    assert_eq!(p.mesh.region_names, vec!["gel".to_string()]);
    let v = std::f64::consts::PI * 16.0 * 9.0;
    assert!((p.density_t_mm3 - 0.5 / v * 1e-6).abs() < 1e-12 * p.density_t_mm3);
    let (lo, hi) = p.mesh.bounding_box();
    assert!((hi[1] - 9.0).abs() < 1e-12 && lo[1].abs() < 1e-12 && (hi[0] - 4.0).abs() < 1e-12);
}

/// The tools of the format other than the seed's press build contact problems;
/// the mapping of each is checked in `tests/tools.rs`.
#[test]
fn sphere_punch_and_friction_build_contact_problems() {
    let cases = [
        edit(EXPERIMENT, "tool = \"plate\"", "tool = \"sphere\"\ntool_radius_mm = 5.0"),
        edit(EXPERIMENT, "tool = \"plate\"", "tool = \"punch\"\ntool_radius_mm = 5.0"),
        edit(EXPERIMENT, "support = \"glued\"", "support = \"friction\"\nfriction = 0.4"),
        edit(EXPERIMENT, "tool_contact = \"glued\"", "tool_contact = \"friction\"\nfriction = 0.4"),
    ];
    for (toml, (names, support)) in cases.iter().zip([
        (vec!["sphere"], Attachment::Glued),
        (vec!["punch"], Attachment::Glued),
        (vec!["plate", "floor"], Attachment::Free),
        (vec!["plate"], Attachment::Glued),
    ]) {
        let b = bundle_files(toml);
        let bundle = read_bundle(&b.dir).unwrap();
        assert!(bundle.has_contact_tools());
        let p = solid(bundle.to_press(20.0).unwrap());
        assert_eq!(p.tools.iter().map(|t| t.name.as_str()).collect::<Vec<_>>(), names, "{toml}");
        assert_eq!(p.protocol.support, support);
        assert_eq!(p.protocol.waypoints, vec![[0.0, 0.0], [28.87, 5.774], [210.93, 5.774]]);
    }
    // The seed's press has no contact tool.
    let p = solid(read_bundle(with_experiment(EXPERIMENT).dir).unwrap().to_press(20.0).unwrap());
    assert!(p.tools.is_empty());
}

/// A surface specimen is meshed on the fly (`tests/press_surface.rs` of the cli
/// runs it); a surface file that cannot be read is refused naming `specimen.surface`.
#[test]
fn a_surface_specimen_needs_its_surface_file() {
    let toml = edit(
        EXPERIMENT,
        "shape = \"block\"\nsize_mm = [58.0, 59.5, 12.0]",
        "shape = \"surface\"\nsurface = \"daifuku.obj\"",
    );
    let b = bundle_files(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let err = bundle.to_press(10.0).unwrap_err();
    let prefix = format!("{}:{}: specimen.surface: ", b.file("experiment.toml").display(), line_of(&toml, "surface ="));
    let msg = err.to_string();
    assert!(msg.starts_with(&prefix) && msg.contains("daifuku.obj"), "expected `{prefix}...daifuku.obj`, got `{msg}`");
    assert!(bundle.default_size_mm().is_none());
}

#[test]
fn a_material_with_unknowns_cannot_be_simulated() {
    let toml = edit(EXPERIMENT, "c3_MPa_s = 29.719\n", "");
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    assert_invalid(
        bundle.to_press(10.0),
        &b.file("experiment.toml"),
        line_of(&toml, "[materials.mat1]"),
        "materials.mat1.c3_MPa_s",
    );
}

#[test]
fn a_material_with_unknowns_from_a_materials_file_names_that_file() {
    let (_, rest) = EXPERIMENT.split_once("[materials.mat1]").unwrap();
    let (mat1, _) = rest.split_once("[protocol]").unwrap();
    let toml = EXPERIMENT.replacen(&format!("[materials.mat1]{mat1}"), "", 1);
    let b = with_experiment(&toml);
    let path = b.root.path().join("fit.toml");
    std::fs::write(&path, "# held fixed\n\n[materials.mat1]\nmodel = \"elastic\"\npoisson = 0.3\n").unwrap();
    let lib = read_materials_file(&path).unwrap();
    let bundle = read_bundle_with(&b.dir, &lib).unwrap();
    let msg = assert_invalid(bundle.to_press(10.0), &path, 3, "materials.mat1.E_MPa");
    assert!(msg.contains("elastic"), "{msg}");
}

#[test]
fn bad_element_size() {
    let bundle = read_bundle(with_experiment(EXPERIMENT).dir).unwrap();
    for h in [0.0, -1.0, f64::NAN] {
        assert!(matches!(bundle.to_press(h), Err(BundleError::ElementSize { .. })));
    }
}

#[test]
fn edits_after_reading_are_checked_again() {
    let b = with_experiment(EXPERIMENT);
    let mut bundle = read_bundle(&b.dir).unwrap();
    bundle.experiment.specimen.size_mm = Some(vec![1.0, 2.0]);
    assert_invalid(
        bundle.to_press(10.0),
        &b.file("experiment.toml"),
        line_of(EXPERIMENT, "size_mm"),
        "specimen.size_mm",
    );
}

/// A two-layer block (filling below crust, 4 x 3 x 2 mm) as a `shape = "mesh"`
/// bundle pressed by frictionless plates, with `mesh` naming `file`.
fn mesh_experiment(file: &str, regions: &str) -> String {
    format!(
        "format = \"wagashi-experiment/1\"\nname = \"layered\"\ndimension = 3\n\n[specimen]\nshape = \"mesh\"\n\
         mesh = \"{file}\"\n\n[specimen.regions]\n{regions}\n[materials.gel]\nmodel = \"elastic\"\npoisson = 0.45\n\
         E_MPa = 0.05\n\n[materials.soft]\nmodel = \"elastic\"\npoisson = 0.3\nE_MPa = 0.02\n\n[protocol]\n\
         tool = \"plate\"\ntool_contact = \"frictionless\"\nsupport = \"frictionless\"\n\
         waypoints = [[0.0, 0.0], [2.0, 0.3]]\nrelease_s = 2.0\nend_s = 4.0\n"
    )
}

const MESH_REGIONS: &str = "crust = \"gel\"\nfilling = \"soft\"\n";

fn two_layer_block() -> fem_core::mesh::TetMesh {
    let layers = [("filling", 2.0), ("crust", 1.0)]
        .map(|(region, thickness_mm)| fem_core::mesh::Layer { region: region.into(), thickness_mm });
    fem_core::mesh::layered_block(4.0, 2.0, &layers, 1.0).unwrap()
}

/// A mesh written by the io writer (Gmsh, TetGen, VTK) is read back through
/// `shape = "mesh"`: its nodes, cells and regions as written, each region with
/// the material `[specimen.regions]` gives it, the floor and top found on the
/// boundary, and contact tools. A node no cell uses is left out.
#[test]
fn a_mesh_specimen_is_read_from_its_file_with_regions_mapped_to_materials() {
    use fem_core::material::Rheology;
    let mesh = two_layer_block();
    let mut written = mesh.clone();
    written.nodes.push([40.0, 40.0, 40.0]); // a construction point no cell uses
    for file in ["specimen.msh", "specimen.node", "specimen.vtu"] {
        let toml = mesh_experiment(file, MESH_REGIONS);
        let b = bundle(&[("experiment.toml", &toml)]);
        wagashi_io::tetmesh::write_tetmesh(b.file(file), &written).unwrap();
        let bundle = read_bundle(&b.dir).unwrap();
        assert!(bundle.has_contact_tools());
        assert_eq!(bundle.volume_mm3().map(|v| (v - 24.0).abs() < 1e-9), Some(true), "{file}");
        // The element size does not apply to a mesh specimen.
        let p = solid(bundle.to_press(0.25).unwrap());
        assert_eq!((p.mesh.nodes.len(), p.mesh.cells.len()), (mesh.nodes.len(), mesh.cells.len()), "{file}");
        assert_eq!(p.mesh.region_names, vec!["filling".to_string(), "crust".to_string()], "{file}");
        let e: Vec<Rheology> = p.materials.iter().map(|m| m.rheology).collect();
        assert_eq!(e, vec![Rheology::Elastic { e_mpa: 0.02 }, Rheology::Elastic { e_mpa: 0.05 }], "{file}");
        let crust = p.mesh.cell_regions.iter().filter(|&&r| r == 1).count();
        assert_eq!(crust, mesh.cell_regions.iter().filter(|&&r| r == 1).count(), "{file}");
        let (bottom, top) = (p.mesh.node_set("bottom").unwrap(), p.mesh.node_set("top").unwrap());
        assert_eq!((bottom.len(), top.len()), (5 * 3, 5 * 3), "{file}");
        assert!(bottom.iter().all(|&i| p.mesh.nodes[i as usize][1] == 0.0));
        assert!(top.iter().all(|&i| p.mesh.nodes[i as usize][1] == 3.0));
        assert_eq!(p.tools.iter().map(|t| t.name.as_str()).collect::<Vec<_>>(), vec!["plate"]);
        // `material` alone gives every region the same material.
        let toml = edit(&toml, "[specimen.regions]\ncrust = \"gel\"\nfilling = \"soft\"\n", "material = \"gel\"\n");
        std::fs::write(b.file("experiment.toml"), &toml).unwrap();
        let p = solid(read_bundle(&b.dir).unwrap().to_press(1.0).unwrap());
        assert!(p.materials.iter().all(|m| m.rheology == Rheology::Elastic { e_mpa: 0.05 }), "{file}");
    }
}

/// A bad mesh specimen is refused in one line naming `experiment.toml`, the
/// line of the key at fault and the key; a defect inside the mesh file names
/// that file too (and its line, where it has one).
#[test]
fn a_mesh_specimen_refuses_bad_input_naming_file_line_and_key() {
    let head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
    let four_nodes =
        |z: f64| format!("$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 {z}\n$EndNodes\n");
    let flat = format!("{head}{}$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n", four_nodes(0.0));
    let triangles_only = format!("{head}{}$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n", four_nodes(1.0));
    let mut apart = two_layer_block();
    let shift = apart.nodes.len() as u32;
    let copy = two_layer_block();
    apart.nodes.extend(copy.nodes.iter().map(|p| [p[0] + 10.0, p[1], p[2]]));
    apart.cells.extend(copy.cells.iter().map(|c| c.map(|v| v + shift)));
    apart.cell_regions.extend(copy.cell_regions.iter().copied());
    let apart = wagashi_io::tetmesh::gmsh_string(&apart);
    let good = wagashi_io::tetmesh::gmsh_string(&two_layer_block());
    let regions = MESH_REGIONS;
    // (mesh file content, experiment.toml edit, key, line needle, cause)
    let cases: Vec<(&str, String, &str, &str, &str)> = vec![
        ("", mesh_experiment("absent.msh", regions), "specimen.mesh", "mesh =", "absent.msh: cannot read"),
        (&flat, mesh_experiment("m.msh", regions), "specimen.mesh", "mesh =", "m.msh:19: element: flat tetrahedron"),
        (&triangles_only, mesh_experiment("m.msh", regions), "specimen.mesh", "mesh =", "no tetrahedra"),
        (&apart, mesh_experiment("m.msh", regions), "specimen.mesh", "mesh =", "form 2 pieces that share no face"),
        (
            &good,
            mesh_experiment("m.msh", "crust = \"gel\"\ncream = \"soft\"\n"),
            "specimen.regions",
            "[specimen.regions]",
            "\"cream\" is not a region of m.msh (its regions: \"filling\", \"crust\")",
        ),
        (
            &good,
            mesh_experiment("m.msh", "crust = \"gel\"\n"),
            "specimen.regions",
            "[specimen.regions]",
            "region \"filling\" of m.msh has no material",
        ),
        (
            &good,
            edit(&mesh_experiment("m.msh", regions), "dimension = 3", "dimension = 2"),
            "dimension",
            "dimension =",
            "needs dimension = 3",
        ),
        (&good, mesh_experiment("m.obj", regions), "specimen.mesh", "mesh =", "expected a Gmsh .msh"),
        (&good, mesh_experiment("../m.msh", regions), "specimen.mesh", "mesh =", "path leaves the bundle folder"),
        (
            &good,
            edit(&mesh_experiment("m.msh", regions), "mesh = \"m.msh\"\n", ""),
            "specimen.mesh",
            "[specimen]",
            "missing required key",
        ),
        (
            &good,
            edit(
                &mesh_experiment("m.msh", regions),
                "mesh = \"m.msh\"\n",
                "mesh = \"m.msh\"\nsize_mm = [1.0, 1.0, 1.0]\n",
            ),
            "specimen.size_mm",
            "size_mm",
            "size_mm belongs to a block",
        ),
    ];
    for (content, toml, key, needle, cause) in cases {
        let mut files = vec![("experiment.toml", toml.as_str())];
        if !content.is_empty() {
            files.push(("m.msh", content));
        }
        let b = bundle(&files);
        let result = read_bundle(&b.dir).and_then(|bundle| bundle.to_press(1.0));
        let msg = assert_invalid(result, &b.file("experiment.toml"), line_of(&toml, needle), key);
        assert!(msg.contains(cause), "wanted `{cause}` in `{msg}`");
        assert_eq!(msg.lines().count(), 1, "{msg}");
    }
}
