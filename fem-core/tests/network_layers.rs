//! A layered body mixing a network layer with a chain layer on the Newton
//! path: the chain layer runs as its network equivalent, so at small strain the
//! whole body is the chain path's linear solution with the network layer
//! replaced by its small-strain equivalent, to O(strain) and the two paths'
//! time discretizations.

use fem_core::material::network::{Energy, Equilibrium, Network};
use fem_core::material::{Material, Rheology};
use fem_core::mesh::{self, Layer};
use fem_core::press::{self, PressResult, Protocol, Settings, SolidPress};

const E_GEL: f64 = 0.03;
const NU: f64 = 0.3;

fn gel() -> Material {
    Material::network(Network::new(NU).with_equilibrium(Equilibrium {
        energy: Energy::NeoHookean,
        e_mpa: E_GEL,
        mullins: None,
    }))
    .unwrap()
}

/// The largest force difference, both faces, at the network run's step ends
/// (all among the chain's), relative to the chain's peak.
fn gap(reference: &PressResult, result: &PressResult) -> f64 {
    let peak = reference.peak_force();
    let mut gap: f64 = 0.0;
    for b in &result.steps {
        let a = reference.steps.iter().rev().find(|a| (a.t_s - b.t_s).abs() <= 1e-12).expect("a common step end");
        let d = (a.bottom_force_n - b.bottom_force_n).abs().max((a.plate_force_n - b.plate_force_n).abs());
        gap = gap.max(d / peak);
    }
    gap
}

/// Runs the layered block (gel under `top`) on both paths: the chain path with
/// the gel as an elastic chain of its modulus, then the Newton path with the
/// gel as a network, on the chain's step ends (less any within 1e-9 s of the
/// one before: the chain lands on the release with a step of rounding length).
fn both_paths(top: &Material, strain: f64, settings: &Settings) -> (PressResult, PressResult) {
    let layers =
        [Layer { region: "gel".into(), thickness_mm: 10.0 }, Layer { region: "top".into(), thickness_mm: 10.0 }];
    let protocol = Protocol::ramp_hold_release(strain * 20.0 / 10.0, 10.0, 30.0, 40.0);
    let m = mesh::layered_block(20.0, 10.0, &layers, 2.5).unwrap();
    let gel_linear = Material::new(Rheology::Elastic { e_mpa: E_GEL }, NU).unwrap();
    let linear = SolidPress::new_3d(m.clone(), vec![gel_linear, top.clone()], protocol.clone()).unwrap();
    let reference = press::simulate(&linear, settings, &mut |_| {}).unwrap();
    let mut ends: Vec<f64> = Vec::new();
    for s in &reference.steps {
        if ends.last().is_none_or(|&t| s.t_s - t > 1e-9) {
            ends.push(s.t_s);
        }
    }
    let replay = Settings { step_ends_s: Some(ends), ..Settings::default() };
    let mixed = SolidPress::new_3d(m, vec![gel(), top.clone()], protocol).unwrap();
    let result = press::simulate(&mixed, &replay, &mut |_| {}).unwrap();
    (reference, result)
}

/// An elastic chain layer over a neo-Hookean network layer, glued, pushed,
/// held and released: both paths are exact in time for an elastic body, so
/// the difference is the kinematics' alone. At 1e-4 and 1e-6 strain it stays
/// below 3 strains of the peak and falls by the strains' factor (100, within
/// 10 %).
#[test]
fn a_network_layer_under_a_chain_layer_is_the_linear_body_at_small_strain() {
    let top = Material::new(Rheology::Elastic { e_mpa: 0.1 }, NU).unwrap();
    let mut gaps = Vec::new();
    for strain in [1e-4, 1e-6] {
        let (reference, result) = both_paths(&top, strain, &Settings::default());
        let g = gap(&reference, &result);
        eprintln!("elastic top, strain {strain:.0e}: largest difference {g:.3e} of the peak");
        gaps.push(g);
    }
    assert!(gaps[0] < 3e-4, "{gaps:?}");
    assert!(gaps[1] < 3e-6, "{gaps:?}");
    let ratio = gaps[0] / gaps[1];
    assert!((ratio / 100.0 - 1.0).abs() < 0.1, "ratio {ratio}");
}

/// The seed's material 1 (five-element chain) over the network gel, at 1e-4
/// strain with the chain's steps at rtol = 1e-6: within 5e-4 of the peak, the
/// level of the two paths' different time discretizations (the chain's
/// exponential update with a BDF2 viscous term, the network's exact update
/// for a strain linear in the step) on a body whose layers redistribute the
/// strain in time.
#[test]
fn a_network_layer_under_the_seeds_chain_follows_the_chain_path() {
    let (reference, result) =
        both_paths(&Material::seed_mat1_force(), 1e-4, &Settings { rtol: 1e-6, ..Settings::default() });
    let g = gap(&reference, &result);
    eprintln!("seed material 1 on top, strain 1e-4: largest difference {g:.3e} of the peak");
    assert!(g < 5e-4, "{g:.3e}");
}

/// The rounding floor of Newton's convergence test: replayed on the chain's
/// own first steps (7.6e-6 s), the seed's damper (`c/dt` far above the gel's
/// modulus) carries the displacements' last bits into forces above the gel's
/// reactions, which `TOLERANCE` alone cannot reach; the steps converge at
/// their floor, dof by dof, and the run ends.
#[test]
fn a_stiff_damper_at_a_short_step_beside_a_soft_layer_converges_at_the_rounding_floor() {
    let (reference, result) = both_paths(&Material::seed_mat1_force(), 1e-4, &Settings::default());
    assert!((result.steps.last().unwrap().t_s - reference.steps.last().unwrap().t_s).abs() < 1e-9);
    let g = gap(&reference, &result);
    eprintln!("chain's default steps: largest difference {g:.3e} of the peak");
    assert!(g < 2e-3, "{g:.3e}");
}
