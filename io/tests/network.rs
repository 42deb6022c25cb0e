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
    assert_eq!(net.viscous.len(), 2);
    assert_eq!(net.viscous[1].tau_s, 40.0);
    assert_eq!(net.damper_mpa_s, Some(0.005));
    let plastic = net.plastic.unwrap();
    // The hardening's default.
    assert_eq!((plastic.e_mpa, plastic.yield_mpa, plastic.hardening_mpa), (0.01, 0.002, 0.0));
    let eq = net.equilibrium.unwrap();
    assert_eq!(eq.e_mpa, 0.03);
    // beta's default.
    assert_eq!(eq.mullins.unwrap().beta, 0.0);
    // Written back and read again: the same material.
    let again = wagashi_io::bundle::MaterialSpec::from_material(&spec.to_material().unwrap());
    assert_eq!(again.to_network().unwrap(), spec.to_network().unwrap());
}

#[test]
fn bad_network_keys_are_refused_naming_file_line_and_key() {
    let cases: [(&str, &str, &str, &str, &str); 7] = [
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
