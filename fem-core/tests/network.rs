//! The network model on the Newton path against closed forms and the chain.

use fem_core::effects::{EffectId, Effects};
use fem_core::element::Formulation;
use fem_core::material::network::{
    DualNetwork, Energy, Equilibrium, FlowNetwork, Network, PlasticNetwork, Strain, ViscousNetwork,
};
use fem_core::material::{Material, Rheology};
use fem_core::mesh;
use fem_core::press::{self, Attachment, MarkerRequest, PlanePress, PressResult, Protocol, Settings, SolidPress};

/// A push to `depth` mm over `push_s`, then a hold until `end_s` (no release
/// before the end), frictionless plates.
fn frictionless(depth: f64, push_s: f64, end_s: f64) -> Protocol {
    Protocol {
        waypoints: vec![[0.0, 0.0], [push_s, depth]],
        release_s: end_s,
        end_s,
        plate: Attachment::Frictionless,
        support: Attachment::Frictionless,
        gravity: false,
    }
}

fn run(problem: &SolidPress, settings: &Settings) -> PressResult {
    press::simulate(problem, settings, &mut |_| {}).unwrap()
}

/// RK4 on `dx/dt = f(t, x)` from `x(0) = 0` to `t_end` in `steps` steps.
fn rk4(f: impl Fn(f64, f64) -> f64, t_end: f64, steps: usize) -> f64 {
    let dt = t_end / steps as f64;
    let mut x = 0.0;
    for i in 0..steps {
        let t = i as f64 * dt;
        let k1 = f(t, x);
        let k2 = f(t + dt / 2.0, x + dt / 2.0 * k1);
        let k3 = f(t + dt / 2.0, x + dt / 2.0 * k2);
        let k4 = f(t + dt, x + dt * k3);
        x += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    x
}

/// The largest force error at the step ends `times` against `want`, as a
/// share of the first.
fn worst_error(result: &PressResult, times: &[f64], want: &[f64]) -> f64 {
    times
        .iter()
        .zip(want)
        .map(|(&t, &w)| {
            let s = result.steps.iter().find(|s| (s.t_s - t).abs() < 1e-9).expect("a step lands there");
            (s.bottom_force_n - w).abs() / want[0].abs()
        })
        .fold(0.0, f64::max)
}

/// The observed orders of errors at halved steps.
fn observed_orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// Uniaxial stress of the compressible neo-Hookean energy
/// `mu/2 (I1bar - 3) + K/2 (J - 1)^2` at the axial stretch `lambda`, written
/// here from the energy (not the engine's code): the lateral stretch `l` solves
/// `P_xx = 0` by bisection, and the nominal axial stress is returned.
fn neo_hookean_uniaxial(e: f64, nu: f64, lambda: f64) -> f64 {
    let mu = e / (2.0 * (1.0 + nu));
    let k = e / (3.0 * (1.0 - 2.0 * nu));
    let p = |l: f64, along: f64| {
        let j = lambda * l * l;
        let i1 = lambda * lambda + 2.0 * l * l;
        mu * j.powf(-2.0 / 3.0) * (along - i1 / (3.0 * along)) + k * (j - 1.0) * j / along
    };
    let (mut lo, mut hi) = (0.5, 3.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if p(mid, mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    p(0.5 * (lo + hi), lambda)
}

/// A neo-Hookean block between frictionless plates, pushed to 50 % strain, on
/// an unstructured-looking tetrahedral mesh: the deformation is homogeneous, so
/// the force equals the closed form at every step end to the solver's tolerance.
#[test]
fn a_neo_hookean_block_in_uniaxial_compression_follows_the_closed_form_to_50_percent() {
    let (e, nu) = (0.03, 0.3);
    let net = Network::new(nu).with_equilibrium(Equilibrium { energy: Energy::NeoHookean, e_mpa: e, mullins: None });
    let h = 10.0;
    let problem = SolidPress::new_3d(
        mesh::block([12.0, h, 8.0], 4.0, "m").unwrap(),
        vec![Material::network(net).unwrap()],
        frictionless(5.0, 10.0, 10.0),
    )
    .unwrap();
    let result = run(&problem, &Settings::default());
    let area = 12.0 * 8.0;
    let mut worst: f64 = 0.0;
    let peak = neo_hookean_uniaxial(e, nu, 0.5).abs() * area;
    for s in &result.steps {
        let lambda = 1.0 - problem.protocol.displacement(s.t_s) / h;
        let want = -neo_hookean_uniaxial(e, nu, lambda) * area;
        worst = worst.max((s.bottom_force_n - want).abs() / peak);
        worst = worst.max((s.plate_force_n - want).abs() / peak);
    }
    eprintln!(
        "neo-Hookean uniaxial: {} steps, worst force error {worst:.3e} of the peak {peak:.5} N",
        result.steps.len()
    );
    assert!(worst < 1e-8, "worst {worst:.3e}");
    assert!((result.steps.last().unwrap().t_s - 10.0).abs() < 1e-12);
}

/// The seed's Table II material 1 as a network against the chain itself on a
/// glued block (an inhomogeneous field), on the chain's own step ends. The
/// network differs from the chain by its finite-strain kinematics alone, a
/// relative difference of the order of the strain: measured at 1e-4 and 1e-6
/// strain, it must fall in proportion.
#[test]
fn the_seeds_chain_as_a_network_equals_the_chain_at_small_strain() {
    let chain = Material::seed_mat1_force();
    let net = Material::network(Network::from_chain(&chain.rheology, chain.poisson)).unwrap();
    let (w, h, t) = (58.0, 59.5, 12.0);
    let mut gaps = Vec::new();
    for strain in [1e-4, 1e-6] {
        let depth = strain * h;
        let protocol = Protocol::ramp_hold_release(depth / 28.87, 28.87, 210.93, 400.0);
        let m = mesh::block([w, h, t], 12.0, "m").unwrap();
        let linear = SolidPress::new_3d(m.clone(), vec![chain.clone()], protocol.clone()).unwrap();
        let reference = run(&linear, &Settings::default());
        let settings =
            Settings { step_ends_s: Some(reference.steps.iter().map(|s| s.t_s).collect()), ..Settings::default() };
        let finite = SolidPress::new_3d(m, vec![net.clone()], protocol).unwrap();
        let result = run(&finite, &settings);
        let peak = reference.peak_force();
        let gap = reference
            .steps
            .iter()
            .zip(&result.steps)
            .map(|(a, b)| (a.bottom_force_n - b.bottom_force_n).abs() / peak)
            .fold(0.0, f64::max);
        eprintln!("strain {strain:.0e}: peak {peak:.6e} N, largest difference {gap:.3e} of the peak");
        gaps.push(gap);
    }
    // Within the chain's own tolerance (1e-3 of the displacement scale), and
    // falling as its steps shorten (first order: 2.5 times the steps, half the gap).
    assert!(gaps[0] < 1e-3 && gaps[1] < 0.6 * gaps[0], "{gaps:?}");
    // The difference is the kinematics' O(strain): at most a few strains, and it
    // falls by the strain's factor (100) within 10 %.
    assert!(gaps[0] < 3e-4, "{gaps:?}");
    assert!(gaps[1] < 3e-6, "{gaps:?}");
    let ratio = gaps[0] / gaps[1];
    assert!((ratio / 100.0 - 1.0).abs() < 0.1, "ratio {ratio}");
}

/// The seed's six Table II sets (materials 1-3, `x_force` and `x_shape`:
/// `E1, E2, c1, c2, c3` [MPa, MPa s] and Poisson's ratio), as in
/// `examples/paper`.
const TABLE_II: [([f64; 5], f64); 6] = [
    ([0.0349, 0.0221, 0.0071, 0.1869, 29.719], 0.3746),
    ([0.0349, 0.0221, 0.0071, 0.1869, 1.4951], 0.3746),
    ([0.0454, 0.0141, 0.0115, 0.1991, 13.370], 0.3353),
    ([0.0454, 0.0141, 0.0115, 0.1991, 0.8987], 0.3353),
    ([0.0575, 0.0113, 0.0172, 0.1954, 8.3936], 0.3267),
    ([0.0575, 0.0113, 0.0172, 0.1954, 1.1421], 0.3267),
];

/// The seed's Table II sets as small-strain networks (a damper and two
/// viscous networks, `kinematics = "small"`) against the chain on a glued
/// block pushed to 1e-4 strain, held and released, in 3D and in plane strain,
/// on the chain's own step ends: the network's update is the chain's exact
/// exponential one, so the forces agree to the Newton tolerance, far inside
/// the 1e-6 of the peak.
#[test]
fn the_seeds_table_ii_sets_as_small_strain_networks_equal_the_chain() {
    let (w, h, t) = (58.0, 59.5, 12.0);
    let depth = 1e-4 * h;
    let protocol = Protocol::ramp_hold_release(depth / 28.87, 28.87, 210.93, 400.0);
    let mut worst: f64 = 0.0;
    for (k, ([e1, e2, c1, c2, c3], nu)) in TABLE_II.into_iter().enumerate() {
        let rheology = Rheology::FiveElement { e1_mpa: e1, e2_mpa: e2, c1_mpa_s: c1, c2_mpa_s: c2, c3_mpa_s: c3 };
        let chain = Material::new(rheology, nu).unwrap();
        let net = Material::network(Network::from_chain(&rheology, nu).with_strain(Strain::Small)).unwrap();
        let gap = |reference: &PressResult, result: &PressResult| {
            let peak = reference.peak_force();
            assert_eq!(reference.steps.len(), result.steps.len());
            reference
                .steps
                .iter()
                .zip(&result.steps)
                .map(|(a, b)| {
                    (a.bottom_force_n - b.bottom_force_n).abs().max((a.plate_force_n - b.plate_force_n).abs()) / peak
                })
                .fold(0.0, f64::max)
        };
        let on_step_ends = |r: &PressResult| Settings {
            step_ends_s: Some(r.steps.iter().map(|s| s.t_s).collect()),
            ..Settings::default()
        };
        // 3D.
        let m = mesh::block([w, h, t], 12.0, "m").unwrap();
        let reference =
            run(&SolidPress::new_3d(m.clone(), vec![chain.clone()], protocol.clone()).unwrap(), &Settings::default());
        let result =
            run(&SolidPress::new_3d(m, vec![net.clone()], protocol.clone()).unwrap(), &on_step_ends(&reference));
        let gap_3d = gap(&reference, &result);
        // Plane strain.
        let plane = |material: &Material| {
            let mut p = PlanePress::new_2d(
                mesh::rectangle(w, h, 6.0, "m").unwrap(),
                t,
                vec![material.clone()],
                protocol.clone(),
            )
            .unwrap();
            p.formulation = Formulation::PlaneStrain { thickness_mm: t };
            p
        };
        let reference = press::simulate(&plane(&chain), &Settings::default(), &mut |_| {}).unwrap();
        let result = press::simulate(&plane(&net), &on_step_ends(&reference), &mut |_| {}).unwrap();
        let gap_2d = gap(&reference, &result);
        eprintln!(
            "Table II set {}: largest difference {gap_3d:.3e} (3D), {gap_2d:.3e} (plane strain) of the peak",
            k + 1
        );
        worst = worst.max(gap_3d).max(gap_2d);
    }
    assert!(worst < 1e-6, "worst {worst:.3e} of the peak");
}

/// The load-path and observation effects on the Newton path: the seed's
/// material 1 as a small-strain network against the chain with the same
/// effect, in plane strain on the chain's own step ends, pushed to 1 %
/// strain (small-strain kinematics: the chain at any strain), held and released. `force-offset` (b0 + b1 t on the bottom force),
/// `ageing` (moduli by exp(gamma_E tau), viscosities by exp(gamma_c tau), the
/// viscous networks' times by their ratio) and `gravity` (a thousandth of g:
/// the specimen's weight about a fifth of the peak force) change nothing in either path's iteration,
/// so they agree to the Newton tolerance as the baseline does (1e-8 of the
/// peak; measured 8e-12, 9e-12 and 2.4e-10). `plate-friction` makes both
/// paths' plates Coulomb contact tools settled by the same contact iteration,
/// which stops friction's linearly converging iteration at 1e-8 of the
/// specimen's size (58 mm), about 1e-6 of the push's depth: the paths agree
/// to that tolerance, not to Newton's (1e-5 of the peak; measured 3.0e-6, in
/// the push's first steps), and each path's plate force equals its bottom
/// force (the tools' forces are the equilibrium's reactions): the bottom
/// force less the plate's is the offset or the weight, or zero, throughout
/// (1e-8 of the peak). `machine-compliance` (c = 3 mm/N, the frame about as
/// soft as the block): exact for an elastic network (a series spring, 1e-9),
/// the plate at the commanded height plus `c F` (1e-9 mm); on the viscous
/// block the plate's motion inside a step is no longer piecewise linear, so
/// the chain's BDF damper and the network's one-step damper differ at the
/// steps' own order: within the chain's step tolerance (1e-3 of the peak;
/// measured 5.8e-4), and halving at 2.5 times the steps.
#[test]
fn the_load_path_and_observation_effects_on_a_small_strain_network_equal_the_chain() {
    let (w, h, t) = (58.0, 59.5, 12.0);
    let depth = 1e-2 * h;
    let chain = Material::seed_mat1_force();
    let net =
        Material::network(Network::from_chain(&chain.rheology, chain.poisson).with_strain(Strain::Small)).unwrap();
    let mut protocol = Protocol::ramp_hold_release(depth / 28.87, 28.87, 210.93, 400.0);
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Frictionless;
    let plane = |material: &Material, effects: &Effects| {
        let mut protocol = protocol.clone();
        // A Coulomb floor does not settle on the chain's path at the push's
        // first steps: the friction plate over a glued support.
        if effects.is_active(EffectId::PlateFriction) {
            protocol.support = Attachment::Glued;
        }
        let mut p =
            PlanePress::new_2d(mesh::rectangle(w, h, 6.0, "m").unwrap(), t, vec![material.clone()], protocol).unwrap();
        p.formulation = Formulation::PlaneStrain { thickness_mm: t };
        p.density_t_mm3 = 1e-9;
        p.effects = effects.clone();
        p
    };
    let mut aged = Effects::none().with(EffectId::Ageing, &[0.02, 0.05]).unwrap();
    aged.set_age_h(Some(7.5)).unwrap();
    let cases = [
        ("force-offset", Effects::none().with(EffectId::ForceOffset, &[1e-3, -2e-6]).unwrap(), 1e-8),
        ("ageing", aged, 1e-8),
        ("gravity", Effects::none().with(EffectId::Gravity, &[1e-3]).unwrap(), 1e-8),
        ("plate-friction", Effects::none().with(EffectId::PlateFriction, &[0.3]).unwrap(), 1e-5),
    ];
    let baseline = press::simulate(&plane(&chain, &Effects::none()), &Settings::default(), &mut |_| {}).unwrap();
    let mut glued = plane(&chain, &Effects::none());
    glued.protocol.support = Attachment::Glued;
    let glued = press::simulate(&glued, &Settings::default(), &mut |_| {}).unwrap();
    for (name, effects, tolerance) in cases {
        let reference = press::simulate(&plane(&chain, &effects), &Settings::default(), &mut |_| {}).unwrap();
        let settings =
            Settings { step_ends_s: Some(reference.steps.iter().map(|s| s.t_s).collect()), ..Settings::default() };
        let result = press::simulate(&plane(&net, &effects), &settings, &mut |_| {}).unwrap();
        let peak = reference.peak_force();
        assert_eq!(reference.steps.len(), result.steps.len(), "{name}");
        let gap = reference
            .steps
            .iter()
            .zip(&result.steps)
            .map(|(a, b)| (a.bottom_force_n - b.bottom_force_n).abs().max((a.plate_force_n - b.plate_force_n).abs()))
            .fold(0.0, f64::max)
            / peak;
        // The effect is felt: the chain with it differs from the chain without.
        let felt = reference
            .steps
            .iter()
            .map(|s| {
                let base = if effects.is_active(EffectId::PlateFriction) { &glued } else { &baseline };
                (s.bottom_force_n - base.bottom_force_at(s.t_s)).abs()
            })
            .fold(0.0, f64::max)
            / peak;
        eprintln!("{name}: peak {peak:.4e} N, effect {felt:.3e} of the peak, network vs chain {gap:.3e}");

        assert!(felt > 1e-3, "{name}: the effect changes the chain's force by {felt:.3e} only");
        assert!(gap < tolerance, "{name}: {gap:.3e} of the peak");
        for s in &result.steps {
            // The floor carries the weight, the plate does not (f rho g V).
            let weight = if name == "gravity" { 1e-3 * 1e-9 * 9810.0 * w * h * t } else { 0.0 };
            let offset = s.bottom_force_n - s.plate_force_n - weight;
            let expected = if name == "force-offset" { 1e-3 - 2e-6 * s.t_s } else { 0.0 };
            assert!((offset - expected).abs() < 1e-8 * peak, "{name}, t = {}: bottom less plate {offset:.6e} N", s.t_s);
        }
    }
    // Machine compliance: the plate's motion inside a step is no longer the
    // protocol's, so the chain's BDF damper and the network's one-step damper
    // differ at the steps' own order; the gap is the chain path's time
    // discretisation and falls with its tolerance.
    let compliant = Effects::none().with(EffectId::MachineCompliance, &[3.0]).unwrap();
    let mut gaps = Vec::new();
    for rtol in [1e-3, 1e-5] {
        let tight = Settings { rtol, ..Settings::default() };
        let reference = press::simulate(&plane(&chain, &compliant), &tight, &mut |_| {}).unwrap();
        let settings = Settings { step_ends_s: Some(reference.steps.iter().map(|s| s.t_s).collect()), ..tight };
        let mut p = plane(&net, &compliant);
        let times = vec![28.87, 210.93];
        p.markers = vec![MarkerRequest { name: "top".into(), position: vec![w / 2.0, h], times: times.clone() }];
        let result = press::simulate(&p, &settings, &mut |_| {}).unwrap();
        // The plate sits at the commanded height plus the deflection c F.
        assert_eq!(result.markers[0].samples.len(), 2);
        for (time, position) in &result.markers[0].samples {
            let s = result.steps.iter().find(|s| (s.t_s - time).abs() < 1e-9).expect("a step lands there");
            let want = h - protocol.displacement(*time) + 3.0 * s.plate_force_n;
            assert!((position[1] - want).abs() < 1e-9, "t = {time}: top at {} mm, want {want} mm", position[1]);
        }
        let peak = reference.peak_force();
        let gap = reference
            .steps
            .iter()
            .zip(&result.steps)
            .map(|(a, b)| (a.plate_force_n - b.plate_force_n).abs())
            .fold(0.0, f64::max)
            / peak;
        eprintln!("machine-compliance, rtol {rtol:.0e}: {} steps, network vs chain {gap:.3e}", reference.steps.len());
        gaps.push(gap);
    }
    // Within the chain's own tolerance (1e-3 of the displacement scale), and
    // falling as its steps shorten (first order: 2.5 times the steps, half the gap).
    assert!(gaps[0] < 1e-3 && gaps[1] < 0.6 * gaps[0], "{gaps:?}");
    // An elastic network is a spring in series with the machine's: the force is
    // `d_cmd / (1/k_s + c)` at every step end, `k_s` from the run without it
    // (1e-9 relative: the deflection's iteration stops at 1e-11 of the
    // displacement scale).
    let elastic =
        Material::network(Network::from_chain(&Rheology::Elastic { e_mpa: 0.05 }, 0.3).with_strain(Strain::Small))
            .unwrap();
    let stiff = press::simulate(&plane(&elastic, &Effects::none()), &Settings::default(), &mut |_| {}).unwrap();
    let last = stiff.steps.iter().find(|s| (s.t_s - 28.87).abs() < 1e-9).unwrap();
    let k_s = last.plate_force_n / protocol.displacement(last.t_s);
    let r = press::simulate(&plane(&elastic, &compliant), &Settings::default(), &mut |_| {}).unwrap();
    for s in r.steps.iter().filter(|s| s.t_s <= 210.93) {
        let want = protocol.displacement(s.t_s) / (1.0 / k_s + 3.0);
        assert!(
            (s.plate_force_n - want).abs() <= 1e-9 * last.plate_force_n,
            "t = {}: {} vs {want}",
            s.t_s,
            s.plate_force_n
        );
    }
    // Compliance with contact tools is refused, and the others by name.
    let both = Effects::none()
        .with(EffectId::PlateFriction, &[0.3])
        .unwrap()
        .with(EffectId::MachineCompliance, &[3.0])
        .unwrap();
    let err = press::simulate(&plane(&net, &both), &Settings::default(), &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("machine-compliance effect and contact tools"), "{err}");
    for (effect, values) in [(EffectId::Adhesion, vec![0.002, 0.1]), (EffectId::PlasticSlider, vec![0.01, 0.01])] {
        let effects = Effects::none().with(effect, &values).unwrap();
        let err = press::simulate(&plane(&net, &effects), &Settings::default(), &mut |_| {}).unwrap_err();
        let want = format!("the network model cannot run with the {effect} effect");
        assert!(err.to_string().contains(&want), "{err}");
    }
}

/// `ageing` on a finite-strain network of every rate-independent and viscous
/// kind (an exponential equilibrium network with Mullins softening, a viscous,
/// a plastic and a power-law flow network, a damper) pushed 20 % and held:
/// with equal rates for moduli and viscosities every stress parameter scales
/// by `s = exp(gamma tau)` and every time is kept, so every force scales by
/// exactly `s` (1e-8 of the peak: Newton's tolerance on both runs, steps
/// replayed); the viscosities' rate alone stiffens the push (a slower flow).
#[test]
fn an_aged_network_scales_every_stress_parameter_and_keeps_its_times() {
    use fem_core::material::network::{Damper, Mullins};
    let net = Network::new(0.3)
        .with_equilibrium(Equilibrium {
            energy: Energy::Exponential { stiffening: 2.0 },
            e_mpa: 0.02,
            mullins: Some(Mullins { r: 3.0, m_mpa: 1e-3, beta: 0.1 }),
        })
        .with(ViscousNetwork { e_mpa: 0.01, tau_s: 2.0 })
        .with(PlasticNetwork { e_mpa: 0.02, yield_mpa: 1e-3, hardening_mpa: 2e-3, kinematic_mpa: 1e-3 })
        .with(FlowNetwork { e_mpa: 0.01, stress_mpa: 0.02, exponent: 2.0 })
        .with(Damper { c_mpa_s: 0.01 });
    let problem = |effects: Effects| {
        let mut p = SolidPress::new_3d(
            mesh::block([12.0, 10.0, 8.0], 4.0, "m").unwrap(),
            vec![Material::network(net.clone()).unwrap()],
            frictionless(2.0, 5.0, 10.0),
        )
        .unwrap();
        p.effects = effects;
        p
    };
    let reference = run(&problem(Effects::none()), &Settings::default());
    let on_its_steps =
        Settings { step_ends_s: Some(reference.steps.iter().map(|s| s.t_s).collect()), ..Settings::default() };
    let (gamma, tau) = (0.02, 7.5);
    let aged = |rates: [f64; 2]| {
        let mut e = Effects::none().with(EffectId::Ageing, &rates).unwrap();
        e.set_age_h(Some(tau)).unwrap();
        run(&problem(e), &on_its_steps)
    };
    let scale = f64::exp(gamma * tau);
    let both = aged([gamma, gamma]);
    let peak = reference.peak_force();
    let worst = reference
        .steps
        .iter()
        .zip(&both.steps)
        .map(|(a, b)| (b.bottom_force_n - scale * a.bottom_force_n).abs() / (scale * peak))
        .fold(0.0, f64::max);
    eprintln!("aged network: peak {peak:.4e} N, forces against s times the baseline's {worst:.3e} of the peak");
    assert!(worst < 1e-8, "{worst:.3e}");
    let viscous = aged([0.0, gamma]);
    for (a, b) in reference.steps.iter().zip(&viscous.steps).filter(|(a, _)| a.t_s > 0.5 && a.t_s <= 5.0) {
        assert!(b.bottom_force_n > a.bottom_force_n, "t = {}: {} vs {}", a.t_s, b.bottom_force_n, a.bottom_force_n);
    }
}

/// One viscous network on a homogeneous uniaxial stress path: the engine
/// against an independent integration in principal log strains written here
/// (RK4 on the Maxwell ODE `d eps_e/dt = d eps/dt - eps_e / tau` per principal
/// direction, the lateral strain from zero lateral Kirchhoff stress), at three
/// step sizes: the error falls at second order.
#[test]
fn a_viscous_network_in_uniaxial_compression_converges_to_an_independent_integration() {
    let (e, nu, tau) = (0.02, 0.3, 2.0);
    let net = Network::new(nu).with(ViscousNetwork { e_mpa: e, tau_s: tau });
    let h = 10.0;
    let (depth, push_s, end_s) = (5.0, 4.0, 8.0);
    let protocol = frictionless(depth, push_s, end_s);
    // Reference: eps_y(t) = ln(1 - d(t)/h); lateral eps_x(t) unknown. Kirchhoff
    // stress tau = E (l1 tr(eps_e) I + 2 m1 eps_e); lateral zero stress
    // l1 tr + 2 m1 eps_ex = 0 with the elastic strains following the ODE: since the
    // flow is proportional, the lateral elastic strain is -nu times the axial
    // one at all times, so only the axial elastic strain needs integrating:
    // d ee/dt = d eps_y/dt - ee / tau, and the axial Kirchhoff stress is E ee.
    let eps_rate = |t: f64| {
        if t < push_s {
            let v = depth / push_s;
            -v / (h - v * t)
        } else {
            0.0
        }
    };
    let reference = |t_end: f64| {
        let ee = rk4(|t, x| eps_rate(t) - x / tau, t_end, 200_000);
        // Nominal stress = Kirchhoff / axial stretch.
        let stretch = 1.0 - protocol.displacement(t_end) / h;
        e * ee / stretch
    };
    let area = 6.0 * 6.0;
    let times = [push_s, end_s];
    let want: Vec<f64> = times.iter().map(|&t| -reference(t) * area).collect();
    let mut errors = Vec::new();
    for n in [8usize, 16, 32] {
        let problem = SolidPress::new_3d(
            mesh::block([6.0, h, 6.0], 3.0, "m").unwrap(),
            vec![Material::network(net.clone()).unwrap()],
            protocol.clone(),
        )
        .unwrap();
        let settings = Settings { fixed_dt_s: Some(push_s / n as f64), ..Settings::default() };
        let result = run(&problem, &settings);
        let err = worst_error(&result, &times, &want);
        eprintln!("viscous network, {n} steps per push: error {err:.3e} of the peak");
        errors.push(err);
    }
    let orders = observed_orders(&errors);
    eprintln!("orders {orders:?}");
    assert!(orders.iter().all(|&p| p > 1.8 && p < 2.3), "orders {orders:?}");
    assert!(errors[2] < 1e-3, "{errors:?}");
}

/// A plastic network pushed to 50 % strain between frictionless plates, pulled
/// back to its starting height (through reverse yielding in tension) and held:
/// the engine against the 1D elastoplastic element written here. Under uniaxial
/// stress a Hencky spring is Hooke's law in the axial log strain `eps`, and the
/// isochoric J2 flow with isotropic hardening is the scalar law
/// `tau = E (eps - p)`, `|tau| <= sigma_y + H alpha`, `d alpha = |dp|`: its
/// piecewise-linear return is exact for any step, so the engine must match it
/// to the solver's tolerance at every step end, at the peak and after the set.
#[test]
fn a_plastic_network_in_uniaxial_compression_and_reverse_yield_follows_the_1d_element() {
    let (e, nu, sigma_y, hardening) = (0.04, 0.3, 2e-3, 0.01);
    let net = Network::new(nu).with(PlasticNetwork {
        e_mpa: e,
        yield_mpa: sigma_y,
        hardening_mpa: hardening,
        kinematic_mpa: 0.0,
    });
    let h = 10.0;
    let mut protocol = frictionless(5.0, 10.0, 25.0);
    protocol.waypoints = vec![[0.0, 0.0], [10.0, 5.0], [20.0, 0.0]];
    let problem = SolidPress::new_3d(
        mesh::block([6.0, h, 6.0], 3.0, "m").unwrap(),
        vec![Material::network(net).unwrap()],
        protocol.clone(),
    )
    .unwrap();
    let settings = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let result = run(&problem, &settings);
    let area = 36.0;
    // The 1D element along the engine's step ends.
    let (mut p, mut alpha) = (0.0f64, 0.0f64);
    let mut want = Vec::new();
    for s in &result.steps {
        let stretch = 1.0 - protocol.displacement(s.t_s) / h;
        let eps = stretch.ln();
        let trial = e * (eps - p);
        let excess = trial.abs() - (sigma_y + hardening * alpha);
        if excess > 0.0 {
            let dp = excess / (e + hardening) * trial.signum();
            p += dp;
            alpha += dp.abs();
        }
        want.push(-e * (eps - p) / stretch * area);
    }
    let peak = want.iter().fold(0.0f64, |m, w| m.max(w.abs()));
    let worst = result.steps.iter().zip(&want).map(|(s, w)| (s.bottom_force_n - w).abs() / peak).fold(0.0, f64::max);
    let last = result.steps.last().unwrap();
    eprintln!(
        "plastic network: {} steps, worst force error {worst:.3e} of the peak {peak:.5} N; after the pull back \
         the force is {:.5} N (1D: {:.5} N), the plastic strain {p:.4}",
        result.steps.len(),
        last.bottom_force_n,
        want.last().unwrap()
    );
    assert!(worst < 1e-8, "worst {worst:.3e}");
    // The set: back at its height the block pulls on the plates (it would rest shorter).
    assert!(last.bottom_force_n.abs() > 0.1 * peak && p < -0.1);
}

/// A power-law flow network (Norton, n = 2) pushed to 50 % strain between
/// frictionless plates and held, against the 1D law written here. Under
/// uniaxial stress the Hencky spring is `tau = E (eps - p)` in the axial log
/// strain and the isochoric flow is `dp/dt = sign(tau) (|tau| / sigma_0)^n`.
/// Two checks: the engine's backward-Euler return equals the same 1D scheme
/// along its step ends (to 1e-8 of the peak), and it converges to an RK4
/// integration of the law at first order in the step (measured).
#[test]
fn a_flow_network_in_uniaxial_compression_follows_the_1d_law_at_first_order() {
    let (e, nu, sigma0, n) = (0.03, 0.3, 4e-3, 2.0);
    let net = Network::new(nu).with(FlowNetwork { e_mpa: e, stress_mpa: sigma0, exponent: n });
    let h = 10.0;
    let (depth, push_s, end_s) = (5.0, 4.0, 8.0);
    let protocol = frictionless(depth, push_s, end_s);
    let eps_at = |t: f64| (1.0 - protocol.displacement(t) / h).ln();
    let rate = |tau: f64| tau.signum() * (tau.abs() / sigma0).powf(n);
    let area = 36.0;
    let nominal = |t: f64, tau: f64| -tau / (1.0 - protocol.displacement(t) / h) * area;
    // RK4 on dp/dt with the strain's exact time course.
    let reference = |t_end: f64| {
        let p = rk4(|t, p| rate(e * (eps_at(t) - p)), t_end, 400_000);
        nominal(t_end, e * (eps_at(t_end) - p))
    };
    let times = [push_s, end_s];
    let want: Vec<f64> = times.iter().map(|&t| reference(t)).collect();
    let mut errors = Vec::new();
    for steps in [8usize, 16, 32] {
        let problem = SolidPress::new_3d(
            mesh::block([6.0, h, 6.0], 3.0, "m").unwrap(),
            vec![Material::network(net.clone()).unwrap()],
            protocol.clone(),
        )
        .unwrap();
        let settings = Settings { fixed_dt_s: Some(push_s / steps as f64), ..Settings::default() };
        let result = run(&problem, &settings);
        // The same backward-Euler return in 1D along the engine's step ends:
        // tau = E (eps - p_n) - E dp with dp = dt (|tau| / sigma0)^n sign(tau),
        // solved by bisection on tau between 0 and the trial stress.
        let (mut p, mut t_prev, mut worst_scheme) = (0.0f64, 0.0f64, 0.0f64);
        for s in &result.steps {
            let dt = s.t_s - t_prev;
            t_prev = s.t_s;
            let trial = e * (eps_at(s.t_s) - p);
            let (mut lo, mut hi) = (0.0f64, trial.abs());
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid + e * dt * (mid / sigma0).powf(n) > trial.abs() {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let tau = trial.signum() * 0.5 * (lo + hi);
            p += (trial - tau) / e;
            worst_scheme = worst_scheme.max((s.bottom_force_n - nominal(s.t_s, tau)).abs() / want[0].abs());
        }
        assert!(worst_scheme < 1e-8, "{steps} steps: the 1D scheme differs by {worst_scheme:.3e} of the peak");
        let err = worst_error(&result, &times, &want);
        eprintln!("flow network, {steps} steps per push: error {err:.3e} of the peak, scheme {worst_scheme:.1e}");
        errors.push(err);
    }
    let orders = observed_orders(&errors);
    eprintln!("orders {orders:?}");
    assert!(orders.iter().all(|&p| p > 0.85 && p < 1.2), "orders {orders:?}");
    // The flow matters: the held stress relaxes well below the peak.
    assert!(want[1].abs() < 0.7 * want[0].abs(), "{want:?}");
}

/// A double compression with a plate tool that leaves the specimen and touches
/// it again, on a neo-Hookean cylinder's axisymmetric section: while the plate
/// pushes, the unilateral contact gives the constrained frictionless plate's
/// forces; the contact area is the top face's, pi R^2; once the plate has risen
/// above the (elastic, fully recovered) top, the force is zero; the second stroke
/// repeats the first.
#[test]
fn a_plate_tool_leaves_an_elastic_network_cylinder_and_touches_it_again() {
    use fem_core::press::{AxisymmetricPress, Tool, ToolContact};
    let net = Network::new(0.3).with_equilibrium(Equilibrium {
        energy: Energy::Exponential { stiffening: 1.0 },
        e_mpa: 0.03,
        mullins: None,
    });
    let (r, h) = (4.0, 8.0);
    let section = mesh::axisymmetric_section(r, h, 1.0, "m").unwrap();
    let strokes = vec![[0.0, 0.0], [10.0, 3.0], [15.0, -0.5], [20.0, 0.0], [30.0, 3.0]];
    let mut protocol = frictionless(3.0, 10.0, 30.0);
    protocol.waypoints = strokes.clone();
    let mut with_tool = AxisymmetricPress::new_axisymmetric(
        section.clone(),
        vec![Material::network(net.clone()).unwrap()],
        protocol.clone(),
    )
    .unwrap();
    with_tool.tools =
        vec![Tool::plate_above("plate", [-r, 0.0, -r], [r, h, r], &strokes, ToolContact::Frictionless, f64::INFINITY)];
    let settings = Settings { fixed_dt_s: Some(0.5), ..Settings::default() };
    let result = press::simulate(&with_tool, &settings, &mut |_| {}).unwrap();
    // The constrained plate on the first push.
    let mut push = frictionless(3.0, 10.0, 10.0);
    push.waypoints = vec![[0.0, 0.0], [10.0, 3.0]];
    let constrained =
        AxisymmetricPress::new_axisymmetric(section, vec![Material::network(net).unwrap()], push).unwrap();
    let reference = press::simulate(&constrained, &settings, &mut |_| {}).unwrap();
    let peak = reference.peak_force();
    for s in &reference.steps {
        let c = result.steps.iter().find(|x| (x.t_s - s.t_s).abs() < 1e-9).unwrap();
        assert!((c.plate_force_n - s.plate_force_n).abs() < 1e-8 * peak, "t = {}", s.t_s);
        assert!((c.bottom_force_n - s.bottom_force_n).abs() < 1e-8 * peak, "t = {}", s.t_s);
    }
    let track = &result.tools[0];
    let at = |t: f64| track.samples.iter().find(|x| (x.t_s - t).abs() < 1e-9).unwrap();
    let top_area = std::f64::consts::PI * r * r;
    // Touching from the first step: the whole top face, deformed (it grows as the
    // cylinder bulges, so the first step's is within its strain of pi R^2).
    assert!((at(0.5).area_mm2 / top_area - 1.0).abs() < 0.02, "area {}", at(0.5).area_mm2);
    // Above the specimen: no force, no area; the second stroke repeats the first.
    assert_eq!(at(15.0).area_mm2, 0.0);
    assert_eq!(at(15.0).normal_n, 0.0);
    for t in [5.0, 10.0] {
        let (a, b) = (at(t).normal_n, at(t + 20.0).normal_n);
        assert!((a - b).abs() < 1e-6 * peak, "t = {t}: {a} vs {b}");
    }
    eprintln!("double compression: peak {peak:.6} N, {} steps", result.steps.len());
}

/// A dual-viscosity network pushed to 30 % strain between frictionless plates
/// in 2 s, held 1 s, pulled back to 25 % in 1 s and held, against the 1D law
/// integrated here. Under uniaxial stress the flow is proportional, so the axial
/// elastic log strain `ee` alone follows `d ee/dt = d eps/dt - ee / tau`, with
/// `tau = tau_load` while `ee d eps/dt >= 0` (the spring loads or holds) and
/// `tau_unload` otherwise, integrated by RK4 per protocol segment. The spring
/// stays compressed throughout (`ee` at least 0.026 from 0), so the direction
/// changes only at the protocol's kinks. The engine takes each step's time
/// from the previous step's direction, one step late at the reversal: at three
/// step sizes its error falls at first order (measured), and the unloading
/// time matters.
#[test]
fn a_dual_viscosity_network_in_compression_and_pull_back_converges_to_the_1d_law() {
    let (e, nu, tau_load, tau_unload) = (0.02, 0.3, 3.0, 1.0);
    let net = Network::new(nu).with(DualNetwork { e_mpa: e, tau_load_s: tau_load, tau_unload_s: tau_unload });
    let h = 10.0;
    let mut protocol = frictionless(3.0, 2.0, 6.0);
    protocol.waypoints = vec![[0.0, 0.0], [2.0, 3.0], [3.0, 3.0], [4.0, 2.5], [6.0, 2.5]];
    let kinks = [0.0, 2.0, 3.0, 4.0, 6.0];
    // The axial log strain rate on a segment of constant plate speed v.
    let eps_rate = |t: f64, v: f64| -v / (h - protocol.displacement(t));
    let area = 36.0;
    // The nominal axial force at each kink after the first, for a given
    // unloading time.
    let reference = |tau_u: f64| {
        let mut ee = 0.0f64;
        let mut out = Vec::new();
        for w in kinks.windows(2) {
            let (t0, t1) = (w[0], w[1]);
            let v = (protocol.displacement(t1) - protocol.displacement(t0)) / (t1 - t0);
            let rhs = |t: f64, x: f64| {
                let r = eps_rate(t, v);
                let tau = if x * r >= 0.0 { tau_load } else { tau_u };
                r - x / tau
            };
            let steps = 100_000;
            let dt = (t1 - t0) / steps as f64;
            for i in 0..steps {
                let t = t0 + i as f64 * dt;
                let k1 = rhs(t, ee);
                let k2 = rhs(t + dt / 2.0, ee + dt / 2.0 * k1);
                let k3 = rhs(t + dt / 2.0, ee + dt / 2.0 * k2);
                let k4 = rhs(t + dt, ee + dt * k3);
                ee += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            }
            let stretch = 1.0 - protocol.displacement(t1) / h;
            out.push(-e * ee / stretch * area);
        }
        out
    };
    let want = reference(tau_unload);
    let times = &kinks[1..];
    let mut errors = Vec::new();
    for n in [8usize, 16, 32] {
        let problem = SolidPress::new_3d(
            mesh::block([6.0, h, 6.0], 3.0, "m").unwrap(),
            vec![Material::network(net.clone()).unwrap()],
            protocol.clone(),
        )
        .unwrap();
        let settings = Settings { fixed_dt_s: Some(2.0 / n as f64), ..Settings::default() };
        let result = run(&problem, &settings);
        let err = worst_error(&result, times, &want);
        eprintln!("dual-viscosity network, {n} steps per push: error {err:.3e} of the peak");
        errors.push(err);
    }
    let orders = observed_orders(&errors);
    eprintln!("orders {orders:?}; forces at the kinks {want:?}");
    assert!(orders.iter().all(|&p| p > 0.9 && p < 1.15), "orders {orders:?}");
    assert!(errors[2] < 1.1e-2, "{errors:?}");
    // The unloading time matters: with the loading time throughout, the force
    // at the end of the pull back differs by a sixth of the peak or more.
    let single = reference(tau_load);
    eprintln!("with the loading time throughout: {single:?}");
    assert!((single[2] - want[2]).abs() > 0.16 * want[0].abs(), "{single:?} against {want:?}");
}

/// Kinematic hardening: a plastic network with linear isotropic and kinematic
/// (Prager) hardening pushed to 40 % strain between frictionless plates, pulled
/// back past its starting height and held, against the 1D law written here:
/// `tau = E (eps - p)` in the axial log strain, `|tau - H_k p| <= sigma_y + H alpha`,
/// `d alpha = |dp|`, whose return from the trial `xi = tau_tr - H_k p_n` is
/// `dp = (|xi| - sigma_y - H alpha_n) / (E + H_k + H) sign(xi)`, exact for any
/// step. The engine must match it to the solver's tolerance at every step end;
/// and the Bauschinger effect shows: reverse yield starts where the stress has
/// fallen by `2 (sigma_y + H alpha)` from the back stress `H_k p`, well before
/// the reversed stress reaches the forward peak.
#[test]
fn a_kinematically_hardening_plastic_network_in_push_pull_follows_the_1d_law() {
    let (e, nu, sigma_y, h_iso, h_kin) = (0.04, 0.3, 2e-3, 2e-3, 0.012);
    let net = Network::new(nu).with(PlasticNetwork {
        e_mpa: e,
        yield_mpa: sigma_y,
        hardening_mpa: h_iso,
        kinematic_mpa: h_kin,
    });
    let h = 10.0;
    let mut protocol = frictionless(4.0, 10.0, 25.0);
    protocol.waypoints = vec![[0.0, 0.0], [10.0, 4.0], [20.0, -1.0]];
    let problem = SolidPress::new_3d(
        mesh::block([6.0, h, 6.0], 3.0, "m").unwrap(),
        vec![Material::network(net).unwrap()],
        protocol.clone(),
    )
    .unwrap();
    let settings = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let result = run(&problem, &settings);
    let area = 36.0;
    let (mut p, mut alpha) = (0.0f64, 0.0f64);
    let mut want = Vec::new();
    // The Kirchhoff stress where yield first reverses (closed form), and the
    // trial stress of that step.
    let mut reverse: Option<(f64, f64)> = None;
    let mut last_sign = 0.0;
    for s in &result.steps {
        let stretch = 1.0 - protocol.displacement(s.t_s) / h;
        let eps = stretch.ln();
        let xi = e * (eps - p) - h_kin * p;
        let excess = xi.abs() - (sigma_y + h_iso * alpha);
        if excess > 0.0 {
            if last_sign != 0.0 && xi.signum() != last_sign && reverse.is_none() {
                // Yield reverses within this step: where it starts, the stress
                // is the back stress less the radius (both of the step's start).
                reverse = Some((h_kin * p - last_sign * (sigma_y + h_iso * alpha), e * (eps - p)));
            }
            last_sign = xi.signum();
            let dp = excess / (e + h_kin + h_iso) * xi.signum();
            p += dp;
            alpha += dp.abs();
        }
        want.push(-e * (eps - p) / stretch * area);
    }
    let peak = want.iter().fold(0.0f64, |m, w| m.max(w.abs()));
    let worst = result.steps.iter().zip(&want).map(|(s, w)| (s.bottom_force_n - w).abs() / peak).fold(0.0, f64::max);
    let (reverse_yield, _) = reverse.expect("the pull back yields in reverse");
    eprintln!(
        "kinematic plastic network: {} steps, worst force error {worst:.3e} of the peak {peak:.5} N; reverse \
         yield at a Kirchhoff stress of {reverse_yield:.3e} MPa, plastic strain at the end {p:.4}",
        result.steps.len()
    );
    assert!(worst < 1e-8, "worst {worst:.3e}");
    // The yield surface moved with the back stress: the pull back yields again
    // while the block is still in compression (isotropic hardening alone would
    // need a tension of sigma_y + H alpha).
    assert!(reverse_yield < -0.2 * sigma_y, "{reverse_yield}");
}

/// A dual-viscosity network in an inhomogeneous field: a block glued to both
/// plates (with an exponential equilibrium network), pushed, held, pulled back
/// and held, on adaptive steps. With equal times it is the viscous network to
/// the last bit; with a fast unloading time it runs to the end (the choice of
/// time is fixed within a step, so Newton's iteration converges as the
/// viscous network's) and the pull back's force falls further than the
/// viscous network's.
#[test]
fn a_glued_block_with_a_dual_viscosity_network_runs_and_equal_times_are_the_viscous_network() {
    let equilibrium = Equilibrium { energy: Energy::Exponential { stiffening: 1.0 }, e_mpa: 0.01, mullins: None };
    let base = Network::new(0.35).with_equilibrium(equilibrium);
    let mut protocol = frictionless(1.2, 2.0, 6.0);
    protocol.waypoints = vec![[0.0, 0.0], [2.0, 1.2], [3.0, 1.2], [4.0, 0.8], [6.0, 0.8]];
    protocol.plate = Attachment::Glued;
    protocol.support = Attachment::Glued;
    let press = |net: Network| {
        let problem = SolidPress::new_3d(
            mesh::block([6.0, 4.0, 6.0], 2.0, "m").unwrap(),
            vec![Material::network(net).unwrap()],
            protocol.clone(),
        )
        .unwrap();
        run(&problem, &Settings::default())
    };
    let viscous = press(base.clone().with(ViscousNetwork { e_mpa: 0.02, tau_s: 3.0 }));
    let same = press(base.clone().with(DualNetwork { e_mpa: 0.02, tau_load_s: 3.0, tau_unload_s: 3.0 }));
    assert_eq!(viscous.steps.len(), same.steps.len());
    for (a, b) in viscous.steps.iter().zip(&same.steps) {
        assert_eq!((a.t_s, a.bottom_force_n, a.plate_force_n), (b.t_s, b.bottom_force_n, b.plate_force_n));
    }
    let dual = press(base.with(DualNetwork { e_mpa: 0.02, tau_load_s: 3.0, tau_unload_s: 0.3 }));
    let at = |r: &PressResult, t: f64| {
        r.steps.iter().find(|s| (s.t_s - t).abs() < 1e-9).expect("a step lands").bottom_force_n
    };
    let peak = at(&viscous, 2.0);
    eprintln!(
        "glued block: dual-viscosity network {} steps; force at the pull back's end {:.5} N against the viscous \
         network's {:.5} N (peak {peak:.5} N)",
        dual.steps.len(),
        at(&dual, 4.0),
        at(&viscous, 4.0)
    );
    assert_eq!(at(&dual, 2.0), peak, "the push loads: the same as the viscous network");
    assert!(at(&dual, 4.0) < at(&viscous, 4.0) - 0.05 * peak.abs());
}
