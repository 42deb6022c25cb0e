//! A written bundle reads back with the same values.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

use common::*;
use wagashi_io::{
    read_bundle, read_bundle_from_str, read_bundle_with, read_materials_file, write_bundle, BundleWrite, ForceSample,
    ForceSeries, MarkerSample, MarkerSeries,
};

fn awkward_force() -> ForceSeries {
    let samples = (0..50)
        .map(|i| {
            let t = i as f64 / 3.0;
            ForceSample { t_s: t, force_n: (t * 0.7).sin() * 1e-7 + 1.0 / 7.0 * t }
        })
        .collect();
    ForceSeries { samples }
}

fn marker(name: &str, positions: &[(f64, &[f64])]) -> MarkerSeries {
    MarkerSeries {
        name: name.into(),
        samples: positions.iter().map(|(t, p)| MarkerSample { t_s: *t, position_mm: p.to_vec() }).collect(),
    }
}

#[test]
fn three_d_bundle_round_trips() {
    let toml = format!("{EXPERIMENT}\n[extra]\nnote = \"camera B\"\n");
    let b = with_experiment(&toml);
    let input = read_bundle(&b.dir).unwrap();
    let force = awkward_force();
    let markers = vec![
        marker(
            "m01",
            &[(0.0, &[5.0, 5.0, 12.0]), (210.93, &[4.6 + 1e-13, 4.9, 12.0 - 1.0 / 3.0]), (400.0, &[4.9, 5.0, 12.0])],
        ),
        marker("top", &[(0.0, &[29.0, 59.5, 6.0]), (1e-9, &[29.0, 59.5 - 1e-12, 6.0])]),
    ];
    let out = b.root.path().join("sim");
    let w = BundleWrite::simulated(&input, "mat1-uniform-sim", &force, &markers);
    write_bundle(&out, &w).unwrap();

    let text = std::fs::read_to_string(out.join("force.csv")).unwrap();
    assert!(text.starts_with("t_s,force_N\n"), "{text}");
    let text = std::fs::read_to_string(out.join("markers.csv")).unwrap();
    assert!(text.starts_with("marker,t_s,x_mm,y_mm,z_mm\n"), "{text}");

    let back = read_bundle(&out).unwrap();
    assert_eq!(back.experiment.name, "mat1-uniform-sim");
    assert_eq!(back.force.as_ref(), Some(&force));
    assert_eq!(back.markers, markers);
    let data = back.experiment.data.clone().unwrap();
    assert_eq!(data.force.as_deref(), Some("force.csv"));
    assert_eq!(data.markers.as_deref(), Some("markers.csv"));
    assert_eq!(data.force_tared, Some(true));
    // Everything else is the input's.
    let mut expected = input.experiment.clone();
    expected.name = back.experiment.name.clone();
    expected.data = back.experiment.data.clone();
    assert_eq!(back.experiment, expected);
    assert_eq!(back.experiment.extra.as_ref().unwrap()["note"].as_str(), Some("camera B"));
}

#[test]
fn two_d_bundle_round_trips_without_z() {
    let toml = edit(EXPERIMENT, "dimension = 3", "dimension = 2");
    let toml = edit(&toml, "markers = \"markers.csv\"\n", "");
    let toml = edit(&toml, "support = \"glued\"", "support = \"frictionless\"\ngravity = true");
    let b = bundle(&[("experiment.toml", &toml), ("force.csv", FORCE)]);
    let input = read_bundle(&b.dir).unwrap();
    let markers = vec![marker("m01", &[(0.0, &[0.0, 30.0]), (5.0, &[-0.1, 30.2])])];
    let force = awkward_force();
    let out = b.root.path().join("sim2d");
    write_bundle(&out, &BundleWrite::simulated(&input, "sim", &force, &markers)).unwrap();
    let text = std::fs::read_to_string(out.join("markers.csv")).unwrap();
    assert!(text.starts_with("marker,t_s,x_mm,y_mm\nm01,0,0,30\n"), "{text}");
    let back = read_bundle(&out).unwrap();
    assert_eq!(back.markers, markers);
    assert_eq!(back.experiment.protocol, input.experiment.protocol);
    assert!(back.experiment.protocol.gravity);
    assert_eq!(back.experiment.data.unwrap().force_tared, Some(false));
}

#[test]
fn external_materials_are_written_into_the_output() {
    let (_, rest) = EXPERIMENT.split_once("[materials.mat1]").unwrap();
    let (mat1, _) = rest.split_once("[protocol]").unwrap();
    let toml = EXPERIMENT.replacen(&format!("[materials.mat1]{mat1}"), "", 1);
    let b = with_experiment(&toml);
    let lib_path = b.root.path().join("fitted.toml");
    std::fs::write(&lib_path, format!("[materials.mat1]{mat1}")).unwrap();
    let input = read_bundle_with(&b.dir, &read_materials_file(&lib_path).unwrap()).unwrap();
    let out = b.root.path().join("sim");
    let force = ForceSeries::default();
    write_bundle(&out, &BundleWrite::simulated(&input, "sim", &force, &[])).unwrap();
    // Self-contained: reads back without the materials file.
    let back = read_bundle(&out).unwrap();
    assert_eq!(back.experiment.materials, input.experiment.materials);
    assert!(back.markers.is_empty());
    assert_eq!(back.force, Some(ForceSeries::default()));
    assert_eq!(back.experiment.data.unwrap().markers, None);
}

#[test]
fn materials_with_unknowns_and_integer_valued_numbers_round_trip() {
    let toml = edit(EXPERIMENT, "c3_MPa_s = 29.719\n", "");
    let toml = edit(&toml, "end_s = 400.0", "end_s = 400");
    let b = with_experiment(&toml);
    let input = read_bundle(&b.dir).unwrap();
    let out = b.root.path().join("sim");
    let w = BundleWrite { experiment: &input.experiment, name: "x", force: None, markers: &[], force_tared: None };
    write_bundle(&out, &w).unwrap();
    let back = read_bundle(&out).unwrap();
    assert_eq!(back.experiment.materials["mat1"].c3_mpa_s, None);
    assert_eq!(back.experiment.protocol.end_s, 400.0);
    assert_eq!(back.experiment.data, None);
    assert!(back.force.is_none());
}

#[test]
fn bad_data_is_refused_before_anything_is_written() {
    let b = with_experiment(EXPERIMENT);
    let input = read_bundle(&b.dir).unwrap();
    let out = b.root.path().join("sim");
    let markers = vec![marker("m01", &[(0.0, &[1.0, 2.0])])];
    let force = ForceSeries::default();
    let err = write_bundle(&out, &BundleWrite::simulated(&input, "x", &force, &markers)).unwrap_err();
    assert!(err.to_string().contains("2 coordinates; dimension is 3"), "{err}");
    let force = ForceSeries { samples: vec![ForceSample { t_s: 0.0, force_n: f64::NAN }] };
    assert!(write_bundle(&out, &BundleWrite::simulated(&input, "x", &force, &[])).is_err());
    assert!(!out.exists());
}

/// A bundle parsed from text (the demo's embedded bundle) is the same as one read
/// from a folder, and its messages name the folder it stands for.
#[test]
fn a_bundle_from_text_equals_the_one_read_from_disk() {
    let text = edit(EXPERIMENT, "[data]\nforce = \"force.csv\"\nmarkers = \"markers.csv\"\nforce_tared = true\n", "");
    let b = with_experiment(&text);
    let from_disk = read_bundle(&b.dir).unwrap();
    let from_text = read_bundle_from_str(&b.dir, &text, &BTreeMap::new()).unwrap();
    assert_eq!(from_text.experiment, from_disk.experiment);
    assert_eq!(from_text.dir, from_disk.dir);
    assert!(from_text.force.is_none() && from_text.markers.is_empty());

    // Nothing is read from disk without `[data]`: the folder need not exist.
    let virtual_dir = Path::new("embedded/mat1");
    let bundle = read_bundle_from_str(virtual_dir, &text, &BTreeMap::new()).unwrap();
    assert_eq!(bundle.experiment_file(), virtual_dir.join("experiment.toml"));

    // Refusals name the stated folder, line and field.
    let bad = edit(&text, "size_mm = [58.0, 59.5, 12.0]", "size_mm = [58.0, -59.5, 12.0]");
    let msg = read_bundle_from_str(virtual_dir, &bad, &BTreeMap::new()).unwrap_err().to_string();
    let want = format!("{}:7: specimen.size_mm: ", virtual_dir.join("experiment.toml").display());
    assert!(msg.starts_with(&want), "{msg}");
}

/// Data files named by a bundle given as text are read from its folder.
#[test]
fn a_bundle_from_text_reads_its_data_files_from_the_folder() {
    let b = bundle(&[("force.csv", FORCE), ("markers.csv", MARKERS)]);
    let bundle = read_bundle_from_str(&b.dir, EXPERIMENT, &BTreeMap::new()).unwrap();
    assert_eq!(bundle.force.unwrap().samples.len(), 4);
    assert_eq!(bundle.markers.len(), 2);
}
