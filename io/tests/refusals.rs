//! One test per refusal of experiment-format.md ("What a reader must refuse"),
//! each checking that the message names the file, the line and the field.

mod common;

use common::*;
use wagashi_io::{read_bundle, read_bundle_with, read_materials_file, BundleError};

fn refused_toml(toml: &str, line_needle: &str, field: &str) -> String {
    let b = with_experiment(toml);
    assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line_of(toml, line_needle), field)
}

#[test]
fn the_example_bundle_is_accepted() {
    let b = with_experiment(EXPERIMENT);
    let bundle = read_bundle(&b.dir).unwrap();
    assert_eq!(bundle.experiment.name, "mat1-uniform");
    assert_eq!(bundle.force.as_ref().unwrap().samples.len(), 4);
    assert_eq!(bundle.markers.len(), 2);
    assert_eq!(bundle.markers[0].samples.len(), 3);
    assert_eq!(bundle.markers[1].initial_position(), Some(&[29.0, 59.5, 6.0][..]));
}

// ---- a missing file -------------------------------------------------------

#[test]
fn missing_experiment_toml() {
    let b = bundle(&[]);
    let err = read_bundle(&b.dir).unwrap_err();
    let msg = err.to_string();
    let want = format!("{}: cannot read: ", b.file("experiment.toml").display());
    assert!(matches!(err, BundleError::Read { .. }) && msg.starts_with(&want), "{msg}");
}

#[test]
fn missing_data_file() {
    let b = bundle(&[("experiment.toml", EXPERIMENT), ("force.csv", FORCE)]);
    let msg = read_bundle(&b.dir).unwrap_err().to_string();
    assert!(msg.starts_with(&format!("{}: cannot read: ", b.file("markers.csv").display())), "{msg}");
}

#[test]
fn missing_materials_file() {
    let b = bundle(&[]);
    let path = b.dir.join("fitted.toml");
    let msg = read_materials_file(&path).unwrap_err().to_string();
    assert!(msg.starts_with(&format!("{}: cannot read: ", path.display())), "{msg}");
}

/// Devices, FIFOs and folders are refused before they are opened (`/dev/zero`
/// would otherwise be read without end), naming the file.
#[cfg(unix)]
#[test]
fn a_materials_file_or_bundle_that_is_not_a_regular_file() {
    let msg = read_materials_file("/dev/zero").unwrap_err().to_string();
    assert_eq!(msg, "/dev/zero: cannot read: not a regular file (a character device)");
    let b = bundle(&[]);
    std::fs::create_dir(b.dir.join("experiment.toml")).unwrap();
    let msg = read_bundle(&b.dir).unwrap_err().to_string();
    assert!(msg.ends_with("experiment.toml: cannot read: not a regular file (a folder)"), "{msg}");
}

// ---- a missing required key ----------------------------------------------

#[test]
fn missing_top_level_key() {
    let toml = edit(EXPERIMENT, "name = \"mat1-uniform\"\n", "");
    let msg = refused_toml(&toml, "format", "name");
    assert!(msg.contains("missing required key"), "{msg}");
}

#[test]
fn missing_key_in_a_table_names_the_table_line() {
    let toml = edit(EXPERIMENT, "release_s = 210.93\n", "");
    refused_toml(&toml, "[protocol]", "protocol.release_s");
}

#[test]
fn missing_size_of_a_block() {
    let toml = edit(EXPERIMENT, "size_mm = [58.0, 59.5, 12.0]\n", "");
    let msg = refused_toml(&toml, "[specimen]", "specimen.size_mm");
    assert!(msg.contains("missing required key"), "{msg}");
}

#[test]
fn missing_key_in_the_second_layer() {
    let toml = edit(
        EXPERIMENT,
        "material = \"mat1\"\n",
        "[[specimen.layers]]\nmaterial = \"mat1\"\nthickness_mm = 30.0\n[[specimen.layers]]\nmaterial = \"mat1\"\n",
    );
    let b = with_experiment(&toml);
    // The second `[[specimen.layers]]` header.
    let line = toml.lines().enumerate().filter(|(_, l)| l.contains("[[specimen.layers]]")).nth(1).unwrap().0 + 1;
    assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line, "specimen.layers[1].thickness_mm");
}

#[test]
fn missing_material_of_a_block() {
    let toml = edit(EXPERIMENT, "material = \"mat1\"\n", "");
    refused_toml(&toml, "[specimen]", "specimen.material");
}

// ---- an unknown key -------------------------------------------------------

#[test]
fn unknown_key_in_specimen() {
    let toml = edit(EXPERIMENT, "mass_g = 52.43\n", "mass_g = 52.43\ncolour = \"white\"\n");
    let msg = refused_toml(&toml, "colour", "specimen.colour");
    assert!(msg.contains("unknown key"), "{msg}");
}

#[test]
fn unitless_key_is_unknown() {
    // "a unit-less size": `size` instead of `size_mm`.
    let toml = edit(EXPERIMENT, "size_mm = ", "size = ");
    refused_toml(&toml, "size = ", "specimen.size");
}

#[test]
fn unknown_material_parameter() {
    let toml = edit(EXPERIMENT, "c3_MPa_s = 29.719\n", "c3_MPa_s = 29.719\nE3_MPa = 1.0\n");
    refused_toml(&toml, "E3_MPa", "materials.mat1.E3_MPa");
}

#[test]
fn unknown_table() {
    let toml = format!("{EXPERIMENT}\n[extras]\nnote = \"typo of extra\"\n");
    refused_toml(&toml, "[extras]", "extras");
}

#[test]
fn extra_takes_any_table() {
    let toml = format!("{EXPERIMENT}\n[extra]\nnote = \"anything\"\n[extra.camera]\nfps = 30\n");
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let extra = bundle.experiment.extra.unwrap();
    assert_eq!(extra["camera"]["fps"].as_integer(), Some(30));
}

#[test]
fn parameter_outside_the_model_key_set() {
    let toml = edit(EXPERIMENT, "model = \"five-element\"", "model = \"four-element\"");
    // A four-element material has no c2.
    let msg = refused_toml(&toml, "c2_MPa_s", "materials.mat1.c2_MPa_s");
    assert!(msg.contains("not a parameter of the four-element model"), "{msg}");
}

#[test]
fn elastic_keys_in_a_chain_model() {
    let toml = edit(EXPERIMENT, "E1_MPa = 0.0349\n", "E_MPa = 0.0349\n");
    refused_toml(&toml, "E_MPa", "materials.mat1.E_MPa");
}

// ---- a value of the wrong type ---------------------------------------------

#[test]
fn wrong_type_of_dimension() {
    let toml = edit(EXPERIMENT, "dimension = 3", "dimension = \"3\"");
    let msg = refused_toml(&toml, "dimension", "dimension");
    assert!(msg.contains("wrong type"), "{msg}");
}

#[test]
fn wrong_type_of_mass() {
    let toml = edit(EXPERIMENT, "mass_g = 52.43", "mass_g = \"heavy\"");
    refused_toml(&toml, "mass_g", "specimen.mass_g");
}

#[test]
fn wrong_type_inside_a_multiline_waypoint_array() {
    let toml = edit(
        EXPERIMENT,
        "waypoints = [[0.0, 0.0], [28.87, 5.774], [210.93, 5.774]]",
        "waypoints = [\n  [0.0, 0.0],\n  [28.87, \"5.774\"],\n  [210.93, 5.774],\n]",
    );
    refused_toml(&toml, "[28.87, \"5.774\"]", "protocol.waypoints[1][1]");
}

#[test]
fn wrong_enum_value() {
    let toml = edit(EXPERIMENT, "tool = \"plate\"", "tool = \"anvil\"");
    refused_toml(&toml, "anvil", "protocol.tool");
}

// ---- non-positive size, mass, time, modulus; Poisson ratio -------------------

#[test]
fn negative_size() {
    let toml = edit(EXPERIMENT, "[58.0, 59.5, 12.0]", "[58.0, -59.5, 12.0]");
    let msg = refused_toml(&toml, "size_mm", "specimen.size_mm");
    assert!(msg.ends_with("specimen.size_mm: must be three positive lengths [W, H, T] in mm"), "{msg}");
}

#[test]
fn size_with_two_entries() {
    let toml = edit(EXPERIMENT, "[58.0, 59.5, 12.0]", "[58.0, 59.5]");
    refused_toml(&toml, "size_mm", "specimen.size_mm");
}

#[test]
fn zero_mass() {
    let toml = edit(EXPERIMENT, "mass_g = 52.43", "mass_g = 0.0");
    refused_toml(&toml, "mass_g", "specimen.mass_g");
}

#[test]
fn non_positive_density() {
    let toml = edit(EXPERIMENT, "mass_g = 52.43", "density_g_cm3 = -1.05");
    refused_toml(&toml, "density_g_cm3", "specimen.density_g_cm3");
}

#[test]
fn zero_cylinder_radius() {
    let toml = edit(
        EXPERIMENT,
        "shape = \"block\"\nsize_mm = [58.0, 59.5, 12.0]",
        "shape = \"cylinder\"\nradius_mm = 0.0\nheight_mm = 9.0",
    );
    let b = bundle(&[("experiment.toml", &toml), ("force.csv", FORCE)]);
    let toml = edit(&toml, "markers = \"markers.csv\"\n", "");
    std::fs::write(b.file("experiment.toml"), &toml).unwrap();
    assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line_of(&toml, "radius_mm"), "specimen.radius_mm");
}

#[test]
fn negative_end_time() {
    let toml = edit(EXPERIMENT, "end_s = 400.0", "end_s = -400.0");
    refused_toml(&toml, "end_s", "protocol.end_s");
}

#[test]
fn zero_release_time() {
    let toml =
        edit(EXPERIMENT, "waypoints = [[0.0, 0.0], [28.87, 5.774], [210.93, 5.774]]", "waypoints = [[0.0, 0.0]]");
    let toml = edit(&toml, "release_s = 210.93", "release_s = 0.0");
    refused_toml(&toml, "release_s", "protocol.release_s");
}

#[test]
fn negative_waypoint_time() {
    let toml = edit(EXPERIMENT, "[[0.0, 0.0], [28.87", "[[-1.0, 0.0], [28.87");
    refused_toml(&toml, "waypoints", "protocol.waypoints[0]");
}

/// E = 1e308 MPa would overflow the first step ("non-finite displacement in
/// element 1"): refused at read time, naming the file, the line, the key and why.
#[test]
fn a_modulus_too_large_to_compute_with() {
    for (from, to, key) in
        [("E1_MPa = 0.0349", "E1_MPa = 1e308", "E1_MPa"), ("c3_MPa_s = ", "c3_MPa_s = 1e101 # ", "c3_MPa_s")]
    {
        let toml = edit(EXPERIMENT, from, to);
        let msg = refused_toml(&toml, key, &format!("materials.mat1.{key}"));
        assert!(msg.contains("is larger than the 1e100") && msg.contains("overflow"), "{msg}");
    }
    let toml = edit(EXPERIMENT, "E1_MPa = 0.0349", "E1_MPa = 1e100");
    assert!(read_bundle(&with_experiment(&toml).dir).is_ok());
}

#[test]
fn zero_modulus() {
    let toml = edit(EXPERIMENT, "E1_MPa = 0.0349", "E1_MPa = 0.0");
    refused_toml(&toml, "E1_MPa", "materials.mat1.E1_MPa");
}

#[test]
fn negative_viscosity() {
    let toml = edit(EXPERIMENT, "c3_MPa_s = 29.719", "c3_MPa_s = -29.719");
    refused_toml(&toml, "c3_MPa_s", "materials.mat1.c3_MPa_s");
}

#[test]
fn poisson_ratio_of_one_half() {
    let toml = edit(EXPERIMENT, "poisson = 0.3746", "poisson = 0.5");
    let msg = refused_toml(&toml, "poisson", "materials.mat1.poisson");
    assert!(msg.contains("(-1, 0.5)"), "{msg}");
}

#[test]
fn poisson_ratio_of_minus_one() {
    let toml = edit(EXPERIMENT, "poisson = 0.3746", "poisson = -1.0");
    refused_toml(&toml, "poisson", "materials.mat1.poisson");
}

// ---- layers; materials named but not defined --------------------------------

fn layered(thicknesses: [&str; 2]) -> String {
    edit(
        EXPERIMENT,
        "material = \"mat1\"\n",
        &format!(
            "\n[[specimen.layers]]\nmaterial = \"mat1\"\nthickness_mm = {}\n\n[[specimen.layers]]\nmaterial = \"mat1\"\nthickness_mm = {}\n",
            thicknesses[0], thicknesses[1]
        ),
    )
}

#[test]
fn layers_that_do_not_sum_to_the_height() {
    let toml = layered(["30.0", "29.4"]);
    let msg = refused_toml(&toml, "[[specimen.layers]]", "specimen.layers");
    assert!(msg.contains("59.4") && msg.contains("59.5"), "{msg}");
}

#[test]
fn layers_within_the_tolerance_are_accepted() {
    let b = with_experiment(&layered(["30.0", "29.5000005"]));
    read_bundle(&b.dir).unwrap();
}

#[test]
fn material_named_but_not_defined() {
    let toml = edit(EXPERIMENT, "material = \"mat1\"", "material = \"mat9\"");
    let msg = refused_toml(&toml, "mat9", "specimen.material");
    assert!(msg.contains("\"mat9\" is not defined"), "{msg}");
}

#[test]
fn layer_material_named_but_not_defined() {
    let toml = layered(["30.0", "29.5"]);
    let toml = toml.replacen("material = \"mat1\"\nthickness_mm = 29.5", "material = \"mat2\"\nthickness_mm = 29.5", 1);
    refused_toml(&toml, "mat2", "specimen.layers[1].material");
}

#[test]
fn materials_from_a_materials_file_resolve_references() {
    let (_, rest) = EXPERIMENT.split_once("[materials.mat1]").unwrap();
    let (mat1, _) = rest.split_once("[protocol]").unwrap();
    let toml = EXPERIMENT.replacen(&format!("[materials.mat1]{mat1}"), "", 1);
    let b = with_experiment(&toml);
    // Without the file: refused.
    assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line_of(&toml, "material ="), "specimen.material");
    // With it: accepted.
    let lib_path = b.root.path().join("fitted.toml");
    std::fs::write(&lib_path, format!("[materials.mat1]{mat1}")).unwrap();
    let lib = read_materials_file(&lib_path).unwrap();
    let bundle = read_bundle_with(&b.dir, &lib).unwrap();
    assert_eq!(bundle.experiment.materials["mat1"].c3_mpa_s, Some(29.719));
}

#[test]
fn materials_file_errors_name_that_file() {
    let b = bundle(&[]);
    let path = b.dir.join("fitted.toml");
    let text = "[materials.gel]\nmodel = \"elastic\"\npoisson = 0.3\nE_MPa = 0.05\nc3_MPa_s = 2.0\n";
    std::fs::write(&path, text).unwrap();
    assert_invalid(read_materials_file(&path), &path, 5, "materials.gel.c3_MPa_s");
    let text = "[materials.gel]\nmodel = \"elastic\"\npoisson = 0.3\nE_MPa = 0.05\n[specimen]\n";
    std::fs::write(&path, text).unwrap();
    assert_invalid(read_materials_file(&path), &path, 5, "specimen");
}

#[test]
fn bad_external_material_is_reported_in_its_own_file() {
    let b = with_experiment(EXPERIMENT);
    let path = b.root.path().join("fitted.toml");
    std::fs::write(&path, "[materials.mat1]\nmodel = \"elastic\"\nE_MPa = 1.0\n").unwrap();
    let mut lib = read_materials_file(&path).unwrap();
    lib.get_mut("mat1").unwrap().poisson = Some(0.7);
    // Edited after reading: still located in the file it came from.
    assert_invalid(read_bundle_with(&b.dir, &lib), &path, 1, "materials.mat1.poisson");
}

// ---- waypoints, release and end -----------------------------------------------

#[test]
fn waypoints_not_in_increasing_time() {
    let toml = edit(
        EXPERIMENT,
        "waypoints = [[0.0, 0.0], [28.87, 5.774], [210.93, 5.774]]",
        "waypoints = [\n  [0.0, 0.0],\n  [28.87, 5.774],\n  [28.87, 5.774],\n]",
    );
    let b = with_experiment(&toml);
    let line = toml.lines().enumerate().filter(|(_, l)| l.contains("[28.87, 5.774]")).nth(1).unwrap().0 + 1;
    let msg = assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line, "protocol.waypoints[2]");
    assert!(msg.contains("increasing time"), "{msg}");
}

#[test]
fn release_before_the_last_push() {
    let toml = edit(EXPERIMENT, "release_s = 210.93", "release_s = 20.0");
    let msg = refused_toml(&toml, "release_s", "protocol.release_s");
    assert!(msg.contains("28.87"), "{msg}");
}

#[test]
fn end_before_the_last_push() {
    let toml = edit(EXPERIMENT, "end_s = 400.0", "end_s = 28.0");
    refused_toml(&toml, "end_s", "protocol.end_s");
}

/// The run ends before the release: refused (the release, and the recovery
/// after it, would never be simulated).
#[test]
fn end_before_the_release() {
    let toml = edit(EXPERIMENT, "end_s = 400.0", "end_s = 200.0");
    let msg = refused_toml(&toml, "end_s", "protocol.end_s");
    assert!(
        msg.ends_with("protocol.end_s: 200 s is before release_s (210.93 s): the run must go on until the release"),
        "{msg}"
    );
    // Ending at the release is fine.
    let toml = edit(EXPERIMENT, "end_s = 400.0", "end_s = 210.93");
    read_bundle(with_experiment(&toml).dir).unwrap();
}

#[test]
fn release_during_a_hold_after_the_last_push_is_accepted() {
    let toml = edit(EXPERIMENT, "release_s = 210.93", "release_s = 28.87");
    read_bundle(with_experiment(&toml).dir).unwrap();
}

// ---- CSV ---------------------------------------------------------------------------

fn refused_csv(name: &str, text: &str, line: usize, field: &str) -> String {
    let mut files = vec![("experiment.toml", EXPERIMENT), ("force.csv", FORCE), ("markers.csv", MARKERS)];
    files.retain(|(n, _)| *n != name);
    files.push((name, text));
    let b = bundle(&files);
    assert_invalid(read_bundle(&b.dir), &b.file(name), line, field)
}

#[test]
fn force_csv_with_a_bad_header() {
    refused_csv("force.csv", "t,force\n0.0,0.0\n", 1, "header");
}

#[test]
fn force_csv_with_a_unitless_header() {
    refused_csv("force.csv", "t_s,force\n0.0,0.0\n", 1, "header");
}

#[test]
fn markers_csv_without_z_in_3d() {
    refused_csv("markers.csv", "marker,t_s,x_mm,y_mm\nm01,0.0,5.0,5.0\n", 1, "header");
}

#[test]
fn empty_csv() {
    refused_csv("force.csv", "", 1, "header");
}

#[test]
fn non_numeric_cell() {
    let msg = refused_csv("force.csv", "t_s,force_N\n0.0,0.0\n0.1,abc\n", 3, "force_N");
    assert!(msg.ends_with("force_N: not a number: \"abc\""), "{msg}");
}

#[test]
fn non_numeric_marker_coordinate() {
    refused_csv("markers.csv", "marker,t_s,x_mm,y_mm,z_mm\nm01,0.0,5.0,five,12.0\n", 2, "y_mm");
}

#[test]
fn row_with_a_missing_cell() {
    refused_csv("force.csv", "t_s,force_N\n0.0,0.0\n0.1\n", 3, "row");
}

#[test]
fn nan_cell() {
    let msg = refused_csv(
        "markers.csv",
        "marker,t_s,x_mm,y_mm,z_mm\nm01,0.0,5.0,5.0,12.0\nm01,1.0,NaN,5.0,12.0\n",
        3,
        "x_mm",
    );
    assert!(msg.contains("not a finite number"), "{msg}");
}

#[test]
fn infinite_cell() {
    refused_csv("force.csv", "t_s,force_N\n0.0,0.0\n\n0.1,inf\n", 4, "force_N");
    refused_csv("force.csv", "t_s,force_N\r\n0.0,0.0\r\n\r\n\r\n0.1,-infinity\r\n", 5, "force_N");
}

#[test]
fn force_time_going_backwards() {
    let msg = refused_csv("force.csv", "t_s,force_N\n0.0,0.0\n0.1,0.2\n0.05,0.3\n", 4, "t_s");
    assert!(msg.contains("backwards"), "{msg}");
}

#[test]
fn marker_time_going_backwards() {
    let text = "marker,t_s,x_mm,y_mm,z_mm\nm01,0.0,5.0,5.0,12.0\nm02,0.0,5.0,5.0,0.0\nm01,10.0,5.0,5.0,12.0\nm01,9.0,5.0,5.0,12.0\n";
    refused_csv("markers.csv", text, 5, "t_s");
}

#[test]
fn negative_csv_time() {
    refused_csv("force.csv", "t_s,force_N\n-0.1,0.0\n", 2, "t_s");
}

// ---- markers --------------------------------------------------------------------------

#[test]
fn marker_without_a_row_at_time_zero() {
    let text = "marker,t_s,x_mm,y_mm,z_mm\nm01,0.0,5.0,5.0,12.0\nm03,1.0,5.0,5.0,12.0\nm03,2.0,5.0,5.0,12.0\n";
    let msg = refused_csv("markers.csv", text, 3, "t_s");
    assert!(msg.contains("m03") && msg.contains("t_s = 0"), "{msg}");
}

#[test]
fn marker_inside_a_block() {
    let text = "marker,t_s,x_mm,y_mm,z_mm\nm01,0.0,5.0,5.0,12.0\nm03,0.0,29.0,30.0,6.0\n";
    let msg = refused_csv("markers.csv", text, 3, "marker m03");
    assert!(msg.contains("surface"), "{msg}");
}

#[test]
fn marker_just_beyond_one_percent_of_the_thickness() {
    // Smallest size 12 mm: 0.12 mm allowed. 0.2 mm inside is refused, 0.1 mm outside accepted.
    refused_csv("markers.csv", "marker,t_s,x_mm,y_mm,z_mm\nm01,0.0,5.0,5.0,11.8\n", 2, "marker m01");
    let b = bundle(&[
        ("experiment.toml", EXPERIMENT),
        ("force.csv", FORCE),
        ("markers.csv", "marker,t_s,x_mm,y_mm,z_mm\nm01,0.0,5.0,5.0,12.1\nm02,0.0,-0.05,20.0,3.0\n"),
    ]);
    read_bundle(&b.dir).unwrap();
}

#[test]
fn marker_off_a_cylinder() {
    // Smallest size min(2R, H) = 8 mm: 0.08 mm allowed.
    let ok = "marker,t_s,x_mm,y_mm,z_mm\nside,0.0,4.0,4.5,0.0\ntop,0.0,1.0,9.0,1.0\ndiag,0.0,2.8284,3.0,2.8284\n";
    let b = bundle(&[("experiment.toml", GEL_CYLINDER), ("markers.csv", ok)]);
    read_bundle(&b.dir).unwrap();
    let bad = "marker,t_s,x_mm,y_mm,z_mm\nside,0.0,4.0,4.5,0.0\naxis,0.0,0.0,4.5,3.0\n";
    let b = bundle(&[("experiment.toml", GEL_CYLINDER), ("markers.csv", bad)]);
    assert_invalid(read_bundle(&b.dir), &b.file("markers.csv"), 3, "marker axis");
}

fn two_d(toml: &str) -> String {
    edit(toml, "dimension = 3", "dimension = 2")
}

#[test]
fn marker_outside_the_2d_rectangle() {
    let toml = two_d(EXPERIMENT);
    let ok = "marker,t_s,x_mm,y_mm\nm01,0.0,29.0,30.0\nm01,10.0,29.0,29.0\nm02,0.0,58.1,59.5\n";
    let b = bundle(&[("experiment.toml", &toml), ("force.csv", FORCE), ("markers.csv", ok)]);
    read_bundle(&b.dir).unwrap();
    let bad = "marker,t_s,x_mm,y_mm\nm01,0.0,29.0,30.0\nm02,0.0,59.0,30.0\n";
    let b = bundle(&[("experiment.toml", &toml), ("force.csv", FORCE), ("markers.csv", bad)]);
    assert_invalid(read_bundle(&b.dir), &b.file("markers.csv"), 3, "marker m02");
}

#[test]
fn markers_csv_with_z_in_2d() {
    let b = bundle(&[("experiment.toml", &two_d(EXPERIMENT)), ("force.csv", FORCE), ("markers.csv", MARKERS)]);
    assert_invalid(read_bundle(&b.dir), &b.file("markers.csv"), 1, "header");
}

// ---- format, dimension ------------------------------------------------------------------

#[test]
fn unknown_format() {
    let toml = edit(EXPERIMENT, "wagashi-experiment/1", "wagashi-experiment/2");
    refused_toml(&toml, "format", "format");
}

#[test]
fn dimension_other_than_two_or_three() {
    let toml = edit(EXPERIMENT, "dimension = 3", "dimension = 1");
    refused_toml(&toml, "dimension", "dimension");
}

#[test]
fn cylinder_in_2d() {
    let toml = two_d(GEL_CYLINDER);
    let b = bundle(&[("experiment.toml", &toml), ("markers.csv", "marker,t_s,x_mm,y_mm\n")]);
    let msg =
        assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line_of(&toml, "shape"), "specimen.shape");
    assert!(msg.contains("3D only"), "{msg}");
}

#[test]
fn key_of_another_shape() {
    let toml = edit(EXPERIMENT, "mass_g = 52.43", "radius_mm = 4.0");
    refused_toml(&toml, "radius_mm", "specimen.radius_mm");
}

#[test]
fn friction_without_friction_contact() {
    let toml = edit(EXPERIMENT, "support = \"glued\"", "support = \"glued\"\nfriction = 0.3");
    refused_toml(&toml, "friction", "protocol.friction");
}

#[test]
fn friction_contact_needs_a_coefficient() {
    let toml = edit(EXPERIMENT, "support = \"glued\"", "support = \"friction\"");
    refused_toml(&toml, "[protocol]", "protocol.friction");
}

#[test]
fn sphere_needs_a_radius() {
    let toml = edit(EXPERIMENT, "tool = \"plate\"", "tool = \"sphere\"");
    refused_toml(&toml, "[protocol]", "protocol.tool_radius_mm");
}

#[test]
fn toml_syntax_error_names_its_line() {
    let toml = edit(EXPERIMENT, "mass_g = 52.43", "mass_g = = 52.43");
    let msg = refused_toml(&toml, "mass_g", "specimen.mass_g");
    assert!(msg.contains("not valid TOML"), "{msg}");
}

// ---- every key of the format is accepted ------------------------------------------------

#[test]
fn every_key_of_the_format_is_accepted() {
    let surface = r#"format = "wagashi-experiment/1"
name = "daifuku"
dimension = 3

[specimen]
shape = "surface"
surface = "daifuku.obj"
mass_g = 40.0
density_g_cm3 = 1.1

[specimen.regions]
skin = "mat1"
filling = "mat2"

[materials.mat1]
model = "three-element"
poisson = 0.3
E1_MPa = 0.05
c1_MPa_s = 0.1
c3_MPa_s = 20.0

[materials.mat2]
model = "four-element"

[protocol]
tool = "sphere"
tool_radius_mm = 10.0
tool_contact = "friction"
friction = 0.3
support = "frictionless"
waypoints = [[0.0, 0.0], [5.0, 2.0], [6.0, 0.0], [10.0, 2.0], [11.0, -1.0]]
release_s = 11.0
end_s = 30.0
gravity = true

[data]
force = "force.csv"
force_tared = false

[extra]
operator = "K."
"#;
    let b = bundle(&[("experiment.toml", surface), ("force.csv", FORCE)]);
    let bundle = read_bundle(&b.dir).unwrap();
    assert_eq!(bundle.experiment.specimen.regions.len(), 2);
    assert_eq!(
        bundle.experiment.materials["mat2"].missing(),
        vec!["E1_MPa", "c1_MPa_s", "E2_MPa", "c3_MPa_s", "poisson"]
    );
    for (tool, extra) in [("punch", "tool_radius_mm = 3.0"), ("surface", "tool_surface = \"tool.obj\"")] {
        let toml = edit(surface, "tool = \"sphere\"\ntool_radius_mm = 10.0", &format!("tool = \"{tool}\"\n{extra}"));
        let b = bundle_dir_with(&toml);
        read_bundle(&b.dir).unwrap();
    }
}

fn bundle_dir_with(toml: &str) -> TestBundle {
    bundle(&[("experiment.toml", toml), ("force.csv", FORCE)])
}

#[test]
fn reading_never_modifies_the_bundle() {
    let b = with_experiment(EXPERIMENT);
    let snapshot = |dir: &std::path::Path| {
        let mut v: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (e.file_name(), std::fs::read(e.path()).unwrap(), e.metadata().unwrap().modified().unwrap())
            })
            .collect();
        v.sort();
        v
    };
    let before = snapshot(&b.dir);
    read_bundle(&b.dir).unwrap();
    let _ = read_bundle(&b.dir).unwrap().to_press(20.0);
    assert_eq!(before, snapshot(&b.dir));
}

// ---- files outside the bundle folder ----------------------------------------------------

/// `experiment.toml` with `key = "from"` replaced by `key = "to"` is refused
/// on that line as `KEY: path leaves the bundle folder`; `setup` prepares the
/// test bundle (files outside it, symlinks).
fn refused_outside(toml: &str, from: &str, to: &str, field: &str, setup: impl Fn(&TestBundle)) {
    let toml = edit(toml, from, to);
    let b = with_experiment(&toml);
    setup(&b);
    let line = line_of(&toml, to);
    let msg = assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line, field);
    assert!(msg.ends_with(": path leaves the bundle folder"), "{to}: {msg}");
}

/// A copy of the bundle's own CSV files beside the bundle folder (in its parent).
fn csv_outside(b: &TestBundle) {
    std::fs::write(b.root.path().join("force.csv"), FORCE).unwrap();
    std::fs::write(b.root.path().join("markers.csv"), MARKERS).unwrap();
}

#[test]
fn data_files_outside_the_bundle_folder_are_refused() {
    let force = "force = \"force.csv\"";
    let markers = "markers = \"markers.csv\"";
    refused_outside(EXPERIMENT, force, "force = \"../force.csv\"", "data.force", csv_outside);
    refused_outside(EXPERIMENT, markers, "markers = \"sub/../../markers.csv\"", "data.markers", csv_outside);
    // Absolute, even when it names the bundle's own file: the bundle is read
    // relative to its folder, wherever that is.
    refused_outside(EXPERIMENT, force, "force = \"/etc/hostname\"", "data.force", csv_outside);
    // Refused by name, whether the file exists or not.
    refused_outside(EXPERIMENT, force, "force = \"../../no/such.csv\"", "data.force", |_| {});
}

#[cfg(unix)]
#[test]
fn a_symlink_out_of_the_bundle_folder_is_refused() {
    let force = "force = \"force.csv\"";
    refused_outside(EXPERIMENT, force, "force = \"link.csv\"", "data.force", |b| {
        csv_outside(b);
        std::os::unix::fs::symlink(b.root.path().join("force.csv"), b.dir.join("link.csv")).unwrap();
    });
    // A folder inside that is a symlink to the outside.
    refused_outside(EXPERIMENT, force, "force = \"up/force.csv\"", "data.force", |b| {
        csv_outside(b);
        std::os::unix::fs::symlink(b.root.path(), b.dir.join("up")).unwrap();
    });
    // Symlinks that stay inside the folder are read, and the folder itself may be
    // reached by a symlink.
    let b = with_experiment(&edit(EXPERIMENT, force, "force = \"data/f.csv\""));
    std::fs::create_dir(b.dir.join("data")).unwrap();
    std::os::unix::fs::symlink("../force.csv", b.dir.join("data/f.csv")).unwrap();
    let link = b.root.path().join("trial-link");
    std::os::unix::fs::symlink(&b.dir, &link).unwrap();
    assert_eq!(read_bundle(&link).unwrap().force.unwrap().samples.len(), 4);
}

#[test]
fn a_specimen_surface_outside_the_bundle_folder_is_refused() {
    let surface = edit(
        GEL_CYLINDER,
        "shape = \"cylinder\"\nradius_mm = 4.0\nheight_mm = 9.0\n",
        "shape = \"surface\"\nsurface = \"gel.obj\"\n",
    );
    let outside = |b: &TestBundle| std::fs::write(b.root.path().join("gel.obj"), "v 0 0 0\n").unwrap();
    let inside = with_experiment(&surface);
    assert!(read_bundle(&inside.dir).is_ok(), "the surface is read when it is meshed");
    for to in ["surface = \"../gel.obj\"", "surface = \"/etc/passwd\"", "surface = \"./a/../../gel.obj\""] {
        refused_outside(&surface, "surface = \"gel.obj\"", to, "specimen.surface", outside);
    }
}

// ---- surfaces ------------------------------------------------------------------

/// A vertex at 1e300 mm (a typo) would leave every triangle degenerate next to
/// the surface's size ("the surface has no triangles" from the mesher): refused
/// at read time, naming the file, the line and the coordinates. The same in
/// another unit: 2e4 m is 2e7 mm. A 10 km shape in mm passes.
#[test]
fn a_vertex_far_out_names_its_line() {
    use wagashi_io::surface::{read_surface, LengthUnit, SurfaceOptions, MAX_COORDINATE_MM};
    let dir = tempfile::tempdir().unwrap();
    let obj = |far: &str| format!("v 0 0 0\nv {far} 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    let path = dir.path().join("big.obj");
    std::fs::write(&path, obj("1e300")).unwrap();
    let msg = read_surface(&path, &SurfaceOptions::default()).unwrap_err().to_string();
    let want = format!("{}:2: coordinates [1e300, 0.0, 0.0] (mm) lie 1.000e300 mm from the origin", path.display());
    assert!(msg.starts_with(&want) && msg.contains("the wrong unit"), "{msg}");
    std::fs::write(&path, obj("2e4")).unwrap();
    let metres = SurfaceOptions { units: Some(LengthUnit::M), ..Default::default() };
    let msg = read_surface(&path, &metres).unwrap_err().to_string();
    assert!(
        msg.starts_with(&format!("{}:2: coordinates [20000.0, 0.0, 0.0] (m) lie 2.000e7 mm", path.display())),
        "{msg}"
    );
    std::fs::write(&path, obj(&MAX_COORDINATE_MM.to_string())).unwrap();
    assert!(read_surface(&path, &SurfaceOptions::default()).is_ok());
}

// ---- meshes --------------------------------------------------------------------

/// An empty or comment-only mesh file ends before its first record: the
/// refusal names line 1 at least (lines count from 1), never line 0.
#[test]
fn an_empty_mesh_file_names_a_line_from_1() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &str, &str); 4] = [
        ("a.node", "", ":1: "),
        ("b.node", "# only a comment\n", ":1: "),
        ("c.msh", "", ":1: "),
        ("d.msh", "\n\n", ":1: "),
    ];
    for (name, text, want) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        if name.ends_with(".node") {
            std::fs::write(path.with_extension("ele"), "1 4 0\n1 1 2 3 4\n").unwrap();
        }
        let msg = wagashi_io::tetmesh::read_tetmesh(&path).unwrap_err().to_string();
        let file = path.display().to_string();
        assert!(msg.starts_with(&format!("{file}{want}")), "{name}: {msg}");
    }
    // A binary byte on line 2 of a .msh: that line, not line 0.
    let path = dir.path().join("e.msh");
    std::fs::write(&path, b"$MeshFormat\n4.1 0 \xff\n$EndMeshFormat\n").unwrap();
    let msg = wagashi_io::tetmesh::read_tetmesh(&path).unwrap_err().to_string();
    assert!(msg.starts_with(&format!("{}:2: $MeshFormat: not ASCII text", path.display())), "{msg}");
}
