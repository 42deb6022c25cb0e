//! The effect library: the registry, and each implemented effect at its
//! null (bit for bit the baseline) and away from it (its physical signature and,
//! where one exists, a closed form).

use fem_core::effects::{EffectError, EffectId, Effects, HookPoint, StressScale};
use fem_core::material::{Material, Rheology};
use fem_core::mesh;
use fem_core::press::{
    self, Attachment, MarkerRequest, PlanePress, PressError, PressResult, Protocol, SensitivityParameter, Settings,
};

const W: f64 = 20.0;
const H: f64 = 15.0;
const T: f64 = 10.0;

fn elastic(e_mpa: f64, nu: f64) -> Material {
    Material::new(Rheology::Elastic { e_mpa }, nu).unwrap()
}

/// A push to 10 % in 10 s, a hold to 40 s, release, recovery to 80 s.
fn seed_like(plate: Attachment, support: Attachment) -> Protocol {
    let mut p = Protocol::ramp_hold_release(0.15, 10.0, 40.0, 80.0);
    p.plate = plate;
    p.support = support;
    p
}

fn plane(material: Material, protocol: Protocol, size_mm: f64) -> PlanePress {
    PlanePress::new_2d(mesh::rectangle(W, H, size_mm, "m").unwrap(), T, vec![material], protocol).unwrap()
}

fn run(p: &PlanePress) -> PressResult {
    press::simulate(p, &Settings::default(), &mut |_| {}).unwrap()
}

/// Bit-for-bit equality of two runs: steps, forces at step ends and inside steps,
/// snapshots and markers.
fn assert_bitwise_equal(a: &PressResult, b: &PressResult, what: &str) {
    assert_eq!(a.steps.len(), b.steps.len(), "{what}: step count");
    for (x, y) in a.steps.iter().zip(&b.steps) {
        assert_eq!(x.t_s.to_bits(), y.t_s.to_bits(), "{what}");
        assert_eq!(x.bottom_force_n.to_bits(), y.bottom_force_n.to_bits(), "{what}: t = {}", x.t_s);
        assert_eq!(x.plate_force_n.to_bits(), y.plate_force_n.to_bits(), "{what}: t = {}", x.t_s);
        let mid = x.t_s - 0.5 * x.dt_s;
        assert_eq!(a.bottom_force_at(mid).to_bits(), b.bottom_force_at(mid).to_bits(), "{what}: t = {mid}");
    }
    assert_eq!(a.snapshots.len(), b.snapshots.len(), "{what}");
    for (x, y) in a.snapshots.iter().zip(&b.snapshots) {
        assert!(x.displacement.iter().zip(&y.displacement).all(|(p, q)| p.to_bits() == q.to_bits()), "{what}");
        assert!(x.cell_stress.iter().zip(&y.cell_stress).all(|(p, q)| p.to_bits() == q.to_bits()), "{what}");
    }
    assert_eq!(a.markers, b.markers, "{what}");
}

// ---------------------------------------------------------------------------------------------------------------
// The registry.

/// Twelve effects with the ids, unique bundle keys with unit suffixes,
/// nulls inside the bounds (or the limit +inf), one-sided exactly where the null is
/// a bound, and the hook points of diagnosis-details.md §4.2.
#[test]
fn registry_lists_the_twelve_effects() {
    let ids: Vec<&str> = EffectId::ALL.iter().map(|e| e.id()).collect();
    assert_eq!(
        ids,
        [
            "plastic-slider",
            "bingham-dashpot",
            "stress-thinning",
            "dual-viscosity",
            "strain-stiffening",
            "finite-strain",
            "plate-friction",
            "adhesion",
            "machine-compliance",
            "gravity",
            "force-offset",
            "ageing"
        ]
    );
    let mut keys = Vec::new();
    for e in EffectId::ALL {
        assert_eq!(EffectId::from_id(e.id()), Some(e));
        assert!(!e.params().is_empty() && !e.params()[0].nuisance, "{e}: the first parameter carries the effect");
        for (i, p) in e.params().iter().enumerate() {
            assert_eq!(EffectId::from_key(p.key), Some((e, i)));
            keys.push(p.key);
            assert!(p.bounds[0] <= p.bounds[1], "{}", p.key);
            assert!(p.admits(p.null) || p.null == f64::INFINITY, "{}: null {} outside bounds", p.key, p.null);
            assert!(p.admits(p.reference), "{}", p.key);
            // A reference scaled by the stress level: a stress (or inverse
            // stress) that carries the effect, admitted at any stress level,
            // and the static one when the level is unknown.
            match p.stress_scale {
                StressScale::Fixed => assert_eq!(p.reference_at(Some(1.5e-3)), p.reference, "{}", p.key),
                StressScale::Stress(f) | StressScale::InverseStress(f) => {
                    let inverse = matches!(p.stress_scale, StressScale::InverseStress(_));
                    assert_eq!(p.unit, if inverse { "1/MPa" } else { "MPa" }, "{}", p.key);
                    assert!(!p.nuisance && f > 0.0, "{}", p.key);
                    for s in [1e-4, 1.5e-3, 0.01, 1.0] {
                        let r = p.reference_at(Some(s));
                        assert!(p.admits(r) && r > 0.0, "{} at {s} MPa: {r}", p.key);
                        let expected = if inverse { 1.0 / (f * s) } else { f * s };
                        assert!((r / expected - 1.0).abs() < 1e-15, "{} at {s} MPa: {r}", p.key);
                    }
                    for unknown in [None, Some(0.0), Some(f64::NAN), Some(-1.0)] {
                        assert_eq!(p.reference_at(unknown), p.reference, "{}", p.key);
                    }
                }
            }
            if !p.nuisance {
                assert_eq!(
                    p.one_sided,
                    p.null == p.bounds[0] || p.null == p.bounds[1] || p.null.is_infinite(),
                    "{}",
                    p.key
                );
            }
            let suffix_needed = p.unit != "1";
            let suffix = match p.unit {
                "MPa" => "_MPa",
                "N" => "_N",
                "N/s" => "_N_per_s",
                "mm" => "_mm",
                "mm/N" => "_mm_per_N",
                "1/h" => "_per_h",
                "1/MPa" => "_1_per_MPa",
                "1" => "",
                u => panic!("unit {u} of {} has no suffix rule", p.key),
            };
            assert!(!suffix_needed || p.key.ends_with(suffix), "{} lacks {suffix}", p.key);
        }
    }
    let n = keys.len();
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), n, "bundle keys are unique");
    use HookPoint::*;
    let hooks: Vec<HookPoint> = EffectId::ALL.iter().map(|e| e.hook()).collect();
    assert_eq!(
        hooks,
        [
            MaterialPoint,
            MaterialPoint,
            MaterialPoint,
            MaterialPoint,
            MaterialPoint,
            MaterialPoint,
            Contact,
            Contact,
            LoadPath,
            BodyForce,
            Observation,
            TrialCovariate
        ]
    );
}

/// Effects the engine does not implement are refused, naming their key; the
/// implemented ones are accepted in bounds and refused out of them.
#[test]
fn unimplemented_effects_are_refused_by_key() {
    let implemented: Vec<&str> = EffectId::ALL.iter().filter(|e| e.implemented()).map(|e| e.id()).collect();
    assert_eq!(
        implemented,
        [
            "plastic-slider",
            "bingham-dashpot",
            "stress-thinning",
            "dual-viscosity",
            "strain-stiffening",
            "finite-strain",
            "plate-friction",
            "adhesion",
            "machine-compliance",
            "gravity",
            "force-offset",
            "ageing"
        ]
    );
    for e in EffectId::ALL.into_iter().filter(|e| !e.implemented()) {
        let err = Effects::none().with(e, &e.params().iter().map(|p| p.reference).collect::<Vec<_>>()).unwrap_err();
        assert!(matches!(err, EffectError::NotImplemented { .. }), "{err}");
        let text = err.to_string();
        assert!(text.starts_with(e.params()[0].key) && text.contains("not implemented"), "{text}");
    }
    let err = Effects::none().with(EffectId::Gravity, &[1.5]).unwrap_err();
    assert_eq!(err.to_string(), "gravity = 1.5 is outside [0, 1] (effect `gravity`)");
    let err = Effects::none().with(EffectId::PlateFriction, &[f64::NAN]).unwrap_err();
    assert!(matches!(err, EffectError::OutOfBounds { key: "plate_friction", .. }), "{err}");
    let err = Effects::none().with(EffectId::ForceOffset, &[0.1]).unwrap_err();
    assert!(matches!(err, EffectError::WrongCount { expected: 2, given: 1, .. }), "{err}");
    // Ageing needs its covariate.
    let mut p = plane(elastic(0.05, 0.3), seed_like(Attachment::Glued, Attachment::Glued), 5.0);
    p.effects = Effects::none().with(EffectId::Ageing, &[0.01, 0.0]).unwrap();
    let err = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("age_h"), "{err}");
}

// ---------------------------------------------------------------------------------------------------------------
// Nulls: bit for bit.

/// Every implemented effect set explicitly to its null values (ageing also with an
/// age) gives the baseline's results bit for bit: the engine runs the baseline's
/// code path for an inactive effect.
#[test]
fn null_effects_equal_the_baseline_bit_for_bit() {
    let mut base = plane(Material::seed_mat1_force(), seed_like(Attachment::Frictionless, Attachment::Glued), 2.5);
    base.markers = vec![MarkerRequest { name: "top".into(), position: vec![W / 2.0, H], times: vec![0.0, 40.0, 80.0] }];
    let reference = run(&base);
    for e in EffectId::ALL.into_iter().filter(|e| e.implemented()) {
        let mut p = base.clone();
        p.effects = Effects::none().with(e, &e.null_values()).unwrap();
        p.effects.set_age_h(Some(12.0)).unwrap();
        assert!(p.effects.is_null());
        assert_bitwise_equal(&reference, &run(&p), e.id());
    }
    // Full gravity given either way is one computation.
    let mut a = base.clone();
    a.protocol.gravity = true;
    let mut b = base.clone();
    b.effects = Effects::none().with(EffectId::Gravity, &[1.0]).unwrap();
    assert_bitwise_equal(&run(&a), &run(&b), "gravity = 1 vs protocol gravity");
}

// ---------------------------------------------------------------------------------------------------------------
// force-offset.

/// With no contact at all (the plate never moves) the reported force is exactly
/// `b0 + b1 t` at every step end and inside the steps; with a push, the reported
/// force is the baseline's plus `b0 + b1 t` (1e-12 of the peak: one rounding of
/// the sum), the plate force untouched, and after release, where nothing touches,
/// it is `b0 + b1 t` again to the baseline's own zero (1e-12 of the peak).
#[test]
fn force_offset_adds_b0_plus_b1_t_everywhere() {
    let (b0, b1) = (0.0123, -4.5e-4);
    let offset = Effects::none().with(EffectId::ForceOffset, &[b0, b1]).unwrap();
    let mut still = plane(Material::seed_mat1_force(), seed_like(Attachment::Glued, Attachment::Glued), 5.0);
    still.protocol.waypoints = vec![[0.0, 0.0], [40.0, 0.0]];
    still.effects = offset.clone();
    let r = run(&still);
    for s in &r.steps {
        assert_eq!(s.bottom_force_n, b0 + b1 * s.t_s, "t = {}", s.t_s);
        let mid = s.t_s - 0.5 * s.dt_s;
        assert_eq!(r.bottom_force_at(mid), b0 + b1 * mid, "t = {mid}");
    }

    let base = plane(Material::seed_mat1_force(), seed_like(Attachment::Glued, Attachment::Glued), 2.5);
    let reference = run(&base);
    let mut p = base.clone();
    p.effects = offset;
    let r = run(&p);
    let peak = reference.peak_force();
    assert!(peak > 0.01);
    for (x, y) in reference.steps.iter().zip(&r.steps) {
        assert!((y.bottom_force_n - x.bottom_force_n - (b0 + b1 * x.t_s)).abs() <= 1e-12 * peak, "t = {}", x.t_s);
        assert_eq!(x.plate_force_n.to_bits(), y.plate_force_n.to_bits());
    }
    for t in [0.0, 5.0, 33.3, 40.0, 41.7, 60.0, 80.0] {
        let d = r.bottom_force_at(t) - reference.bottom_force_at(t);
        assert!((d - (b0 + b1 * t)).abs() <= 1e-12 * peak, "t = {t}: {d}");
    }
    for t in [45.0, 60.0, 80.0] {
        assert!((r.bottom_force_at(t) - (b0 + b1 * t)).abs() <= 1e-12 * peak, "released, t = {t}");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// gravity.

/// Relative errors of a free-standing elastic prism (nu = 0, plane stress) on a
/// frictionless floor under `factor` g, against the linear closed form
/// `s_yy = -f rho g (H - y)`, `u_y = -(f rho g / E)(H y - y^2/2)`, `u_x = 0`
/// (exact with nu = 0; with nu != 0 the uniaxial state would curl the base, which
/// the floor forbids): (L2 stress error over f rho g H, largest nodal u_y error
/// over the top's settlement, bottom force over the weight - 1).
fn prism_errors(size_mm: f64, factor: f64) -> (f64, f64, f64) {
    let (e, rho) = (0.01, 1.2e-9);
    let g = 9810.0;
    // The plate holds the top still for 1 s, then lets go; elastic, so the end
    // state is the free-standing one whatever came before.
    let mut protocol = Protocol::ramp_hold_release(0.0, 1.0, 1.0, 2.0);
    protocol.waypoints = vec![[0.0, 0.0], [1.0, 0.0]];
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Frictionless;
    let mut p =
        PlanePress::new_2d(mesh::rectangle(W, H, size_mm, "m").unwrap(), T, vec![elastic(e, 0.0)], protocol).unwrap();
    p.density_t_mm3 = rho;
    p.effects = Effects::none().with(EffectId::Gravity, &[factor]).unwrap();
    let r = run(&p);
    let snap = r.snapshot_at(2.0).unwrap();
    let q = factor * rho * g;
    let (mut err2, mut area) = (0.0, 0.0);
    for (c, cell) in p.mesh.cells.iter().enumerate() {
        let x: Vec<[f64; 2]> = cell.iter().map(|&v| p.mesh.nodes[v as usize]).collect();
        let a = 0.5 * ((x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1])).abs();
        let yc = (x[0][1] + x[1][1] + x[2][1]) / 3.0;
        // Exact s_yy is linear in y: its cell mean is its value at the centroid.
        let d = snap.cell_stress[c * 3 + 1] - (-q * (H - yc));
        err2 += d * d * a;
        area += a;
    }
    let stress = (err2 / area).sqrt() / (q * H);
    let settlement = q / e * H * H / 2.0;
    let disp = p
        .mesh
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| (snap.displacement[2 * i + 1] + q / e * (H * n[1] - n[1] * n[1] / 2.0)).abs())
        .fold(0.0, f64::max)
        / settlement;
    let weight = q * W * H * T;
    (stress, disp, r.steps.last().unwrap().bottom_force_n / weight - 1.0)
}

/// The prism under self-weight converges to the closed form: the L2 stress error
/// falls at first order (P1: constant stress per cell; measured 0.97, 0.99 for
/// h = 2.5, 1.25, 0.625 mm), the largest nodal u_y error faster than 1.5 (measured
/// 1.67, 1.73), both under 1 % at h = 0.625 mm; the bottom carries the weight
/// (1e-9); half the factor gives the same relative errors (linear: 1e-9).
#[test]
fn gravity_prism_converges_to_the_closed_form() {
    let sizes = [2.5, 1.25, 0.625];
    let errors: Vec<(f64, f64, f64)> = sizes.iter().map(|&h| prism_errors(h, 1.0)).collect();
    for (h, e) in sizes.iter().zip(&errors) {
        println!("h = {h} mm: stress L2 {:.3e}, u_y max {:.3e}, weight {:.1e}", e.0, e.1, e.2);
        assert!(e.2.abs() < 1e-9, "bottom force vs weight: {}", e.2);
    }
    for w in errors.windows(2) {
        let rate = (w[0].0 / w[1].0).log2();
        println!("stress rate {rate:.3}");
        assert!(rate > 0.9, "stress rate {rate}");
        let u_rate = (w[0].1 / w[1].1).log2();
        println!("u_y rate {u_rate:.3}");
        assert!(u_rate > 1.5, "u_y rate {u_rate}");
    }
    assert!(errors[2].0 < 0.01 && errors[2].1 < 0.01, "{:?}", errors[2]);
    let half = prism_errors(2.5, 0.5);
    assert!((half.0 - errors[0].0).abs() < 1e-9 && (half.1 - errors[0].1).abs() < 1e-9, "{half:?} vs {:?}", errors[0]);
}

/// A viscoelastic slump: the seed's material 1, pressed and released on a
/// frictionless floor. Without gravity the top recovers (rises) after release;
/// with gravity it keeps sinking, and late in the recovery (Voigt elements long
/// relaxed) at the closed-form creep rate of the c3 dashpot under the weight,
/// `v = -rho g H^2 / (2 c3)` (nu = 0, so the state is exactly uniaxial), to 0.1 %
/// (measured 1.3e-4 with steps of at most 2 s).
#[test]
fn gravity_slump_continues_after_release() {
    let m = Material::seed_mat1_force().rheology;
    let c3 = 29.719;
    let rho = 1.2e-9;
    let times = vec![0.0, 40.0, 150.0, 200.0, 250.0];
    let top = |gravity: f64| {
        let mut protocol = Protocol::ramp_hold_release(0.15, 10.0, 40.0, 250.0);
        protocol.plate = Attachment::Frictionless;
        protocol.support = Attachment::Frictionless;
        let mut p = plane(Material::new(m, 0.0).unwrap(), protocol, 2.5);
        p.density_t_mm3 = rho;
        p.markers = vec![MarkerRequest { name: "top".into(), position: vec![W / 2.0, H], times: times.clone() }];
        if gravity > 0.0 {
            p.effects = Effects::none().with(EffectId::Gravity, &[gravity]).unwrap();
        }
        let r = press::simulate(&p, &Settings { max_dt_s: Some(2.0), ..Settings::default() }, &mut |_| {}).unwrap();
        r.markers[0].samples.iter().map(|s| s.1[1]).collect::<Vec<f64>>()
    };
    let (without, with) = (top(0.0), top(1.0));
    println!("top y without gravity {without:?}\n            with gravity {with:?}");
    assert!(without[3] > without[2] && without[4] >= without[3], "recovers without gravity: {without:?}");
    assert!(with[3] < with[2] && with[4] < with[3], "slumps with gravity: {with:?}");
    let rate = (with[4] - with[3]) / 50.0;
    let rate_without = (without[4] - without[3]) / 50.0;
    let expected = -rho * 9810.0 * H * H / (2.0 * c3);
    println!("late rate {rate:.4e} mm/s (without gravity {rate_without:.3e}), closed form {expected:.4e}");
    // The recovery still under way without gravity adds to the slump (linear superposition).
    let slump = rate - rate_without;
    assert!((slump / expected - 1.0).abs() < 1e-3, "{slump} vs {expected}");
}

// ---------------------------------------------------------------------------------------------------------------
// machine-compliance.

/// An elastic block between frictionless plates (homogeneous uniaxial
/// compression): with a series spring the force is `u_cmd / (1/k_s + 1/k_m)`,
/// `k_s` from the baseline run, at every step end (1e-9 relative; measured
/// 1.1e-15), and the top
/// marker sits at the commanded height plus `F/k_m` (1e-9 mm).
#[test]
fn machine_compliance_is_a_series_spring() {
    let mut protocol = Protocol::ramp_hold_release(0.15, 10.0, 20.0, 20.0);
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Frictionless;
    let mut base = plane(elastic(0.05, 0.3), protocol, 2.5);
    base.markers =
        vec![MarkerRequest { name: "top".into(), position: vec![W / 2.0, H], times: vec![0.0, 5.0, 10.0, 20.0] }];
    let settings = Settings { fixed_dt_s: Some(1.0), ..Settings::default() };
    let reference = press::simulate(&base, &settings, &mut |_| {}).unwrap();
    let last = reference.steps.last().unwrap();
    let k_s = last.plate_force_n / base.protocol.displacement(last.t_s);
    let compliance = 0.7 / k_s; // the frame as soft as 0.7 of the sample
    let mut p = base.clone();
    p.effects = Effects::none().with(EffectId::MachineCompliance, &[compliance]).unwrap();
    let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
    let worst = r
        .steps
        .iter()
        .filter(|s| s.t_s > 0.5)
        .map(|s| {
            let expected = p.protocol.displacement(s.t_s) / (1.0 / k_s + compliance);
            (s.plate_force_n / expected - 1.0).abs()
        })
        .fold(0.0, f64::max);
    println!("largest relative force error with compliance: {worst:.2e}");
    for s in &r.steps {
        let u_cmd = p.protocol.displacement(s.t_s);
        let expected = u_cmd / (1.0 / k_s + compliance);
        assert!((s.plate_force_n - expected).abs() <= 1e-9 * expected.abs().max(1e-3), "t = {}", s.t_s);
        assert!((s.bottom_force_n - s.plate_force_n).abs() <= 1e-9 * expected.abs().max(1e-3));
    }
    for (t, pos) in &r.markers[0].samples {
        let u_cmd = p.protocol.displacement(*t);
        let force = u_cmd / (1.0 / k_s + compliance);
        assert!((pos[1] - (H - u_cmd + compliance * force)).abs() < 1e-9, "t = {t}: {}", pos[1]);
    }
    // Refused where it is not implemented: with sensitivities and other integrators.
    let parameters = [SensitivityParameter { regions: vec![0], kind: press::ParameterKind::Rheology(0) }];
    let err = press::simulate_with_sensitivities(&p, &settings, &parameters, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("machine_compliance_mm_per_N") && err.to_string().contains("sensitivities"));
    let dynamic = Settings { integrator: press::Integrator::Dynamic, ..settings.clone() };
    assert!(matches!(press::simulate(&p, &dynamic, &mut |_| {}), Err(PressError::BadSettings(_))));
}

// ---------------------------------------------------------------------------------------------------------------
// ageing.

/// An elastic specimen aged by tau hours: every force scales by exactly
/// `exp(gamma_E tau)` (1e-12 relative, steps replayed); a five-element one with
/// equal rates for moduli and viscosities too, to 1e-10: its relaxation rates are
/// unchanged in exact arithmetic but recomputed from the scaled parameters (the
/// roots of the chain's quadratic), so they differ in the last bits and the
/// history over 80 s carries that (measured 2.6e-12); the viscosity rate alone
/// slows the relaxation, so the force is higher throughout the push and hold.
#[test]
fn ageing_scales_the_force() {
    let (gamma, tau): (f64, f64) = (0.02, 7.5);
    let scale = (gamma * tau).exp();
    for (name, material, rates, tolerance) in [
        ("elastic", elastic(0.05, 0.3), [gamma, 0.0], 1e-12),
        ("five-element", Material::seed_mat1_force(), [gamma, gamma], 1e-10),
    ] {
        let base = plane(material, seed_like(Attachment::Glued, Attachment::Glued), 2.5);
        let reference = run(&base);
        let mut p = base.clone();
        p.effects = Effects::none().with(EffectId::Ageing, &rates).unwrap();
        p.effects.set_age_h(Some(tau)).unwrap();
        let settings =
            Settings { step_ends_s: Some(reference.steps.iter().map(|s| s.t_s).collect()), ..Settings::default() };
        let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
        let peak = reference.peak_force();
        for (x, y) in reference.steps.iter().zip(&r.steps) {
            assert!(
                (y.bottom_force_n - scale * x.bottom_force_n).abs() <= tolerance * scale * peak,
                "{name}, t = {}: {} vs {}",
                x.t_s,
                y.bottom_force_n,
                scale * x.bottom_force_n
            );
        }
    }
    // Viscosities only: a stiffer (more viscous) material relaxes less during the hold.
    let base = plane(Material::seed_mat1_force(), seed_like(Attachment::Glued, Attachment::Glued), 2.5);
    let mut p = base.clone();
    p.effects = Effects::none().with(EffectId::Ageing, &[0.0, gamma]).unwrap();
    p.effects.set_age_h(Some(tau)).unwrap();
    let (a, b) = (run(&base), run(&p));
    // G_aged(t) = G(t/s) >= G(t) (rates over s, G decreasing) and the strain never
    // falls before release: the force is higher throughout the push and hold.
    for t in [2.0, 5.0, 10.0, 20.0, 40.0] {
        assert!(b.bottom_force_at(t) > a.bottom_force_at(t), "t = {t}");
    }
    let parameters = [SensitivityParameter { regions: vec![0], kind: press::ParameterKind::Rheology(0) }];
    let err = press::simulate_with_sensitivities(&p, &Settings::default(), &parameters, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("ageing_E_rate_per_h"), "{err}");
}

// ---------------------------------------------------------------------------------------------------------------
// plate-friction.

/// An elastic block pressed 10 % between frictionless plates barrels more, and
/// needs more force, as the plates' friction grows (mu = 0.1, 0.3, 1.0); with
/// mu = 0 the sides stay straight (the frictionless baseline, bit for bit, checked
/// above) and the effect is the same problem as friction contact tools.
#[test]
fn plate_friction_barrels_in_order_of_mu() {
    let (e, nu) = (0.05, 0.45);
    let depth = 0.1 * H;
    let mut protocol = Protocol::ramp_hold_release(depth, 1.0, 1.0, 1.0);
    protocol.waypoints.truncate(2);
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Frictionless;
    let base = plane(elastic(e, nu), protocol, 1.25);
    let settings = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let measure = |mu: f64| {
        let mut p = base.clone();
        if mu > 0.0 {
            p.effects = Effects::none().with(EffectId::PlateFriction, &[mu]).unwrap();
        }
        let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
        let snap = r.snapshot_at(1.0).unwrap();
        let side = |x: f64, y: f64| {
            (0..p.mesh.num_nodes())
                .find(|&i| (p.mesh.nodes[i][0] - x).abs() < 1e-9 && (p.mesh.nodes[i][1] - y).abs() < 1e-9)
                .map(|i| snap.displacement[i * 2])
                .unwrap()
        };
        let width = |y: f64| side(W, y) - side(0.0, y);
        (width(H / 2.0) - width(H), r.steps.last().unwrap().bottom_force_n)
    };
    let results: Vec<(f64, (f64, f64))> = [0.0, 0.1, 0.3, 1.0].into_iter().map(|mu| (mu, measure(mu))).collect();
    for (mu, (bulge, force)) in &results {
        println!("mu = {mu}: bulge {bulge:.5} mm, force {force:.5} N");
    }
    assert!(results[0].1 .0.abs() < 1e-9, "frictionless sides stay straight: {}", results[0].1 .0);
    for w in results.windows(2) {
        assert!(w[1].1 .0 > w[0].1 .0 && w[1].1 .1 > w[0].1 .1, "not ordered: {:?} -> {:?}", w[0], w[1]);
    }
    // Refused on a glued plate (it would not extend the baseline).
    let mut glued = base.clone();
    glued.protocol.plate = Attachment::Glued;
    glued.effects = Effects::none().with(EffectId::PlateFriction, &[0.3]).unwrap();
    let err = press::simulate(&glued, &settings, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("plate_friction"), "{err}");
}
