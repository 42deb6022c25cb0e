//! `model = "network"`: read through the law's parameter tables, and every bad
//! key refused as `file:line: key: cause`.

mod common;

use common::*;
use wagashi_io::read_bundle;

const NETWORK: &str = r#"[materials.mat1]
model = "network"
poisson = 0.45

[materials.mat1.equilibrium]
energy = "exponential"
E_MPa = 0.03
stiffening = 0.5

[materials.mat1.equilibrium.mullins]
r = 2.0
m_MPa = 0.002

[[materials.mat1.viscous]]
E_MPa = 0.02
tau_s = 2.0

[[materials.mat1.viscous]]
E_MPa = 0.01
tau_s = 40.0

[materials.mat1.plastic]
E_MPa = 0.01
yield_MPa = 0.002

[[materials.mat1.flow]]
E_MPa = 0.005
stress_MPa = 0.003

[materials.mat1.damper]
c_MPa_s = 0.005
"#;

/// The example experiment with its chain replaced by `material`.
fn with_network(material: &str) -> String {
    let start = EXPERIMENT.find("[materials.mat1]").unwrap();
    let end = EXPERIMENT.find("[protocol]").unwrap();
    format!("{}{material}\n{}", &EXPERIMENT[..start], &EXPERIMENT[end..])
}

#[test]
fn a_network_material_is_read_with_its_parts_and_defaults() {
    let toml = with_network(NETWORK);
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let spec = &bundle.experiment.materials["mat1"];
    let net = spec.to_network().unwrap();
    // The parts in the registry's order, each with its values in its table's
    // order, defaults filled in (the hardenings', the flow's exponent).
    let parts: Vec<(&str, Vec<f64>)> = net.parts.iter().map(|p| (p.kind().table, p.values())).collect();
    assert_eq!(
        parts,
        vec![
            ("viscous", vec![0.02, 2.0]),
            ("viscous", vec![0.01, 40.0]),
            ("plastic", vec![0.01, 0.002, 0.0, 0.0]),
            ("flow", vec![0.005, 0.003, 1.0]),
            ("damper", vec![0.005]),
        ]
    );
    let eq = net.equilibrium.unwrap();
    assert_eq!(eq.e_mpa, 0.03);
    // beta's default.
    assert_eq!(eq.mullins.unwrap().beta, 0.0);
    // Written back and read again: the same material.
    let again = wagashi_io::bundle::MaterialSpec::from_material(&spec.to_material().unwrap());
    assert_eq!(again.to_network().unwrap(), spec.to_network().unwrap());
}

/// A part added as one file and one registration (`[bingham]`) is read,
/// written back and refused through the registry like the others.
#[test]
fn a_bingham_part_is_read_written_back_and_refused_through_the_registry() {
    let bingham = edit(
        NETWORK,
        "[materials.mat1.damper]",
        "[materials.mat1.bingham]\nE_MPa = 0.004\nyield_MPa = 0.001\nviscosity_MPa_s = 0.02\n\n[materials.mat1.damper]",
    );
    let toml = with_network(&bingham);
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let spec = &bundle.experiment.materials["mat1"];
    let net = spec.to_network().unwrap();
    let values: Vec<Vec<f64>> = net.parts_of("bingham").map(|p| p.values()).collect();
    assert_eq!(values, vec![vec![0.004, 0.001, 0.02]]);
    let again = wagashi_io::bundle::MaterialSpec::from_material(&spec.to_material().unwrap());
    assert_eq!(again.to_network().unwrap(), net);
    assert!(spec.parameter_keys().contains(&"bingham.viscosity_MPa_s"));
    let toml = with_network(&edit(&bingham, "viscosity_MPa_s = 0.02", "viscosity_MPa_s = -0.02"));
    let b = with_experiment(&toml);
    let msg = assert_invalid(
        read_bundle(&b.dir),
        &b.file("experiment.toml"),
        line_of(&toml, "viscosity_MPa_s"),
        "materials.mat1.bingham.viscosity_MPa_s",
    );
    assert!(msg.contains("outside (0, 1000000]"), "{msg}");
}

#[test]
fn bad_network_keys_are_refused_naming_file_line_and_key() {
    let cases: [(&str, &str, &str, &str, &str); 10] = [
        ("tau_s = 40.0", "tau_s = -4.0", "tau_s = -4.0", "materials.mat1.viscous[1].tau_s", "outside (0, 1000000000]"),
        (
            "stiffening = 0.5",
            "stiffnening = 0.5",
            "stiffnening",
            "materials.mat1.equilibrium.stiffnening",
            "not a key here",
        ),
        (
            "energy = \"exponential\"",
            "energy = \"exponentail\"",
            "energy =",
            "materials.mat1.equilibrium.energy",
            "is not an energy",
        ),
        ("poisson = 0.45", "poisson = 0.5", "poisson", "materials.mat1.poisson", "outside"),
        ("r = 2.0", "r = 0.5", "r = 0.5", "materials.mat1.equilibrium.mullins.r", "outside (1, 1000]"),
        ("c_MPa_s = 0.005", "c_MPa_s = \"fast\"", "c_MPa_s", "materials.mat1.damper.c_MPa_s", "is not a number"),
        ("yield_MPa = 0.002", "yield_MPa = 0.0", "yield_MPa", "materials.mat1.plastic.yield_MPa", "outside (0, 10000]"),
        (
            "stress_MPa = 0.003",
            "stress_MPa = 0.003\nexponent = 0.5",
            "exponent = 0.5",
            "materials.mat1.flow[0].exponent",
            "outside [1, 20]",
        ),
        (
            "[[materials.mat1.flow]]",
            "[[materials.mat1.flwo]]",
            "[[materials.mat1.flwo]]",
            "materials.mat1.flwo",
            "its parts: [equilibrium], [[viscous]], [plastic], [[flow]], [bingham], [damper], [[dual]]",
        ),
        (
            "[materials.mat1.damper]\n",
            "[[materials.mat1.damper]]\nc_MPa_s = 0.001\n[[materials.mat1.damper]] # a second\n",
            "# a second",
            "materials.mat1.damper[1]",
            "at most 1 damper parts",
        ),
    ];
    for (from, to, line, field, cause) in cases {
        let toml = with_network(&edit(NETWORK, from, to));
        let b = with_experiment(&toml);
        let msg = assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line_of(&toml, line), field);
        assert!(msg.contains(cause), "{msg}");
    }
}

#[test]
fn an_absent_network_key_is_an_unknown_named_when_simulated() {
    // Identification fills absent keys, so reading accepts them; the engine's
    // material names the first one.
    let toml = with_network(&edit(NETWORK, "E_MPa = 0.03\n", ""));
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let spec = &bundle.experiment.materials["mat1"];
    assert_eq!(spec.missing(), vec!["equilibrium.E_MPa"]);
    assert_eq!(spec.to_rheology().unwrap_err().key, "equilibrium.E_MPa");
}

#[test]
fn a_chain_with_network_tables_and_a_network_with_chain_keys_are_refused() {
    let chain_with_damper =
        EXPERIMENT.replace("c3_MPa_s = 29.719\n", "c3_MPa_s = 29.719\n[materials.mat1.damper]\nc_MPa_s = 1.0\n");
    let b = with_experiment(&chain_with_damper);
    let msg = assert_invalid(
        read_bundle(&b.dir),
        &b.file("experiment.toml"),
        line_of(&chain_with_damper, "[materials.mat1.damper]"),
        "materials.mat1.damper",
    );
    assert!(msg.contains("only a network material"), "{msg}");
    let network_with_e1 = with_network(&edit(NETWORK, "poisson = 0.45\n", "poisson = 0.45\nE1_MPa = 0.1\n"));
    let b = with_experiment(&network_with_e1);
    let msg = assert_invalid(
        read_bundle(&b.dir),
        &b.file("experiment.toml"),
        line_of(&network_with_e1, "E1_MPa"),
        "materials.mat1.E1_MPa",
    );
    assert!(msg.contains("not a key of the network model"), "{msg}");
    let empty = with_network("[materials.mat1]\nmodel = \"network\"\npoisson = 0.3\n");
    let b = with_experiment(&empty);
    let msg = read_bundle(&b.dir).unwrap_err().to_string();
    assert!(msg.contains("the network has no part"), "{msg}");
}

/// `kinematics = "small"`: read, written back, and refused with a part that
/// has no small-strain form or with an unknown name.
#[test]
fn a_small_strain_network_is_read_written_back_and_refused_where_it_cannot_run() {
    let small = r#"[materials.mat1]
model = "network"
poisson = 0.3746
kinematics = "small"

[materials.mat1.equilibrium]
energy = "neo-hookean"
E_MPa = 0.01

[[materials.mat1.viscous]]
E_MPa = 0.02
tau_s = 2.0

[materials.mat1.damper]
c_MPa_s = 0.005
"#;
    let toml = with_network(small);
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let spec = &bundle.experiment.materials["mat1"];
    let net = spec.to_network().unwrap();
    assert_eq!(net.strain, fem_core::material::network::Strain::Small);
    let again = wagashi_io::bundle::MaterialSpec::from_material(&spec.to_material().unwrap());
    assert_eq!(again.to_network().unwrap(), net);

    let cases = [
        (edit(small, "kinematics = \"small\"", "kinematics = \"tiny\""), "is not a kinematics (\"finite\", \"small\")"),
        (edit(NETWORK, "poisson = 0.45", "poisson = 0.45\nkinematics = \"small\""), "has no small-strain form"),
    ];
    for (material, cause) in cases {
        let toml = with_network(&material);
        let b = with_experiment(&toml);
        let msg = assert_invalid(
            read_bundle(&b.dir),
            &b.file("experiment.toml"),
            line_of(&toml, "kinematics"),
            "materials.mat1.kinematics",
        );
        assert!(msg.contains(cause), "{msg}");
    }
}

/// A frictionless double compression of one network material: the plate
/// pushes 40 %, leaves the specimen and touches it again.
fn homogeneous_trial(specimen: &str, dimension: u32) -> String {
    format!(
        r#"format = "wagashi-experiment/1"
name = "homogeneous"
dimension = {dimension}

[specimen]
{specimen}
material = "mat1"

{NETWORK}
[protocol]
tool = "plate"
tool_contact = "frictionless"
support = "frictionless"
waypoints = [[0.0, 0.0], [8.0, 1.6], [12.0, 0.0], [14.0, 0.0], [22.0, 1.6], [26.0, 0.0]]
release_s = 26.0
end_s = 26.0
"#
    )
}

/// The force of a run at element size `size_mm`, sampled every second.
fn forces(bundle: &wagashi_io::Bundle, axisymmetric: bool, size_mm: f64) -> Vec<f64> {
    use fem_core::press::{simulate_any, Settings};
    let problem = if axisymmetric { bundle.to_press_axisymmetric(size_mm) } else { bundle.to_press(size_mm) }.unwrap();
    let r = simulate_any(&problem, &Settings::default(), &mut |_| {}).unwrap();
    (0..=26).map(|t| r.bottom_force_at(t as f64)).collect()
}

#[test]
fn a_homogeneous_trial_is_solved_on_one_cell_as_on_a_fine_mesh() {
    // One cell through the specimen gives the fine mesh's force to the Newton
    // tolerance (1e-8 of the peak): linear cells reproduce the uniform stretch
    // exactly, so the fit may take the one-cell mesh.
    let cases = [
        ("shape = \"cylinder\"\nradius_mm = 2.0\nheight_mm = 4.0", 3, true, 0.5, 4.0),
        ("shape = \"block\"\nsize_mm = [3.0, 4.0, 2.0]", 3, false, 1.0, 4.0),
        ("shape = \"block\"\nsize_mm = [6.0, 4.0, 1.0]\nplane = \"strain\"", 2, false, 0.5, 6.0),
    ];
    for (specimen, dimension, axisymmetric, fine_mm, largest) in cases {
        let b = bundle(&[("experiment.toml", &homogeneous_trial(specimen, dimension))]);
        let bundle = read_bundle(&b.dir).unwrap();
        let one = bundle.homogeneous_size_mm(axisymmetric).expect("a homogeneous trial");
        assert_eq!(one, largest);
        let (coarse, fine) = (forces(&bundle, axisymmetric, one), forces(&bundle, axisymmetric, fine_mm));
        let peak = fine.iter().fold(0.0f64, |m, f| m.max(f.abs()));
        assert!(peak > 0.0);
        let worst = coarse.iter().zip(&fine).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / peak;
        assert!(worst < 1e-8, "{specimen}: one cell against {fine_mm} mm: {worst:.2e} of the peak");
    }
    // Glued plates, a 3D cylinder (a faceted circle) or gravity: not homogeneous.
    let glued = homogeneous_trial("shape = \"block\"\nsize_mm = [3.0, 4.0, 2.0]", 3)
        .replace("tool_contact = \"frictionless\"", "tool_contact = \"glued\"");
    let b = bundle(&[("experiment.toml", &glued)]);
    assert_eq!(read_bundle(&b.dir).unwrap().homogeneous_size_mm(false), None);
    let cylinder = homogeneous_trial("shape = \"cylinder\"\nradius_mm = 2.0\nheight_mm = 4.0", 3);
    let b = bundle(&[("experiment.toml", &cylinder)]);
    assert_eq!(read_bundle(&b.dir).unwrap().homogeneous_size_mm(false), None);
    let heavy = cylinder.replace("end_s = 26.0", "end_s = 26.0\ngravity = true");
    let b = bundle(&[("experiment.toml", &heavy)]);
    assert_eq!(read_bundle(&b.dir).unwrap().homogeneous_size_mm(true), None);
}

/// Ogden's energy: read with its defaults (absent third term), written back
/// the same; a `stiffening` beside it, shares summing to 1 and a zero exponent
/// refused naming the key.
#[test]
fn an_ogden_equilibrium_is_read_written_back_and_its_bad_keys_refused() {
    let ogden = edit(
        NETWORK,
        "energy = \"exponential\"\nE_MPa = 0.03\nstiffening = 0.5",
        "energy = \"ogden\"\nE_MPa = 0.03\nalpha1 = 6.0\nalpha2 = -2.0\nshare2 = 0.25",
    );
    let toml = with_network(&ogden);
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let spec = &bundle.experiment.materials["mat1"];
    let net = spec.to_network().unwrap();
    let eq = net.equilibrium.unwrap();
    assert_eq!(
        eq.energy,
        fem_core::material::network::Energy::Ogden { alpha: [6.0, -2.0, 4.0], share: [0.75, 0.25, 0.0] }
    );
    let again = wagashi_io::bundle::MaterialSpec::from_material(&spec.to_material().unwrap());
    assert_eq!(again.to_network().unwrap(), net);
    // Its fit keys: the Ogden keys, not the exponential's.
    let keys = spec.parameter_keys();
    assert!(keys.contains(&"equilibrium.alpha1") && keys.contains(&"equilibrium.share3"), "{keys:?}");
    assert!(!keys.contains(&"equilibrium.stiffening"), "{keys:?}");

    let cases: [(&str, &str, &str, &str, &str); 3] = [
        (
            "share2 = 0.25",
            "share2 = 0.25\nstiffening = 1.0",
            "stiffening",
            "materials.mat1.equilibrium.stiffening",
            "not a key here",
        ),
        (
            "share2 = 0.25",
            "share2 = 0.7\nshare3 = 0.3",
            "share2",
            "materials.mat1.equilibrium.share2",
            "must be under 1",
        ),
        ("alpha1 = 6.0", "alpha1 = 0.0", "alpha1", "materials.mat1.equilibrium.alpha1", "nonzero"),
    ];
    for (from, to, line, field, cause) in cases {
        let toml = with_network(&edit(&ogden, from, to));
        let b = with_experiment(&toml);
        let msg = assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line_of(&toml, line), field);
        assert!(msg.contains(cause), "{msg}");
    }
}

/// The dual-viscosity part and the plastic part's kinematic hardening: read,
/// written back, named for identification, and each bad key refused as
/// `file:line: key: cause`; an absent time is an unknown.
#[test]
fn dual_viscosity_parts_and_kinematic_hardening_are_read_written_back_and_refused() {
    let dual = "[[materials.mat1.dual]]\nE_MPa = 0.004\ntau_load_s = 3.0\ntau_unload_s = 0.5\n";
    let material = edit(NETWORK, "yield_MPa = 0.002", "yield_MPa = 0.002\nkinematic_MPa = 0.006") + dual;
    let toml = with_network(&material);
    let b = with_experiment(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let spec = &bundle.experiment.materials["mat1"];
    let net = spec.to_network().unwrap();
    let parts: Vec<(&str, Vec<f64>)> = net.parts.iter().map(|p| (p.kind().table, p.values())).collect();
    assert_eq!(parts[2], ("plastic", vec![0.01, 0.002, 0.0, 0.006]));
    assert_eq!(parts.last().unwrap(), &("dual", vec![0.004, 3.0, 0.5]));
    let again = wagashi_io::bundle::MaterialSpec::from_material(&spec.to_material().unwrap());
    assert_eq!(again.to_network().unwrap(), net);
    let keys = spec.parameter_keys();
    for key in ["plastic.kinematic_MPa", "dual[0].E_MPa", "dual[0].tau_load_s", "dual[0].tau_unload_s"] {
        assert!(keys.contains(&key), "{key} in {keys:?}");
    }
    // An absent unloading time is an unknown for identification.
    let toml_unknown = with_network(&edit(&material, "tau_unload_s = 0.5\n", ""));
    let b_unknown = with_experiment(&toml_unknown);
    let unknown = read_bundle(&b_unknown.dir).unwrap();
    assert_eq!(unknown.experiment.materials["mat1"].missing(), vec!["dual[0].tau_unload_s"]);

    let cases: [(&str, &str, &str, &str, &str); 5] = [
        (
            "kinematic_MPa = 0.006",
            "kinematic_MPa = -0.006",
            "kinematic_MPa",
            "materials.mat1.plastic.kinematic_MPa",
            "outside [0, 10000]",
        ),
        (
            "tau_unload_s = 0.5",
            "tau_unload_s = 0.0",
            "tau_unload_s",
            "materials.mat1.dual[0].tau_unload_s",
            "outside (0, 1000000000]",
        ),
        (
            "tau_load_s = 3.0",
            "tau_load_s = \"slow\"",
            "tau_load_s",
            "materials.mat1.dual[0].tau_load_s",
            "is not a number",
        ),
        (
            "tau_unload_s = 0.5",
            "tau_unlaod_s = 0.5",
            "tau_unlaod_s",
            "materials.mat1.dual[0].tau_unlaod_s",
            "not a key here",
        ),
        (
            "[[materials.mat1.dual]]\n",
            "[[materials.mat1.dual]]\nE_MPa = 0.001\ntau_load_s = 1.0\ntau_unload_s = 1.0\n\
             [[materials.mat1.dual]]\nE_MPa = 0.001\ntau_load_s = 1.0\ntau_unload_s = 1.0\n\
             [[materials.mat1.dual]] # a third\n",
            "# a third",
            "materials.mat1.dual[2]",
            "at most 2 dual parts",
        ),
    ];
    for (from, to, line, field, cause) in cases {
        let toml = with_network(&edit(&material, from, to));
        let b = with_experiment(&toml);
        let msg = assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line_of(&toml, line), field);
        assert!(msg.contains(cause), "{msg}");
    }
}
