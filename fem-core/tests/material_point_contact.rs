//! The material-point effects and the Mullins-type damage with contact tools:
//! a flat plate tool (glued, or frictionless on a frictionless-plate trial)
//! reproduces the constrained plate's run with the same effect, in plane stress,
//! axisymmetric and 3D (the tool run chooses its steps, the constrained run
//! replays them, so the two differ by the contact treatment only); an effect at
//! its null with tools is the baseline tool run; a flat punch pressed into a
//! sweet with a plastic slider leaves a dent after it lifts off, none without.

use fem_core::effects::{EffectId, Effects};
use fem_core::material::{Material, MullinsDamage};
use fem_core::mesh;
use fem_core::press::{
    self, Attachment, AxisymmetricPress, PressResult, Protocol, Settings, Tool, ToolContact, ToolShape,
};

mod common;
use common::{elastic, problems, ramp_hold_release, set_effects, set_protocol, with_plate_tool};

const W: f64 = 20.0;
const H: f64 = 15.0;
const T: f64 = 10.0;

/// Compares the tool run with the constrained plate's replay of its steps: the
/// bottom force over the trial to [`FORCE_TOL`] of the peak, the final shapes to
/// [`FORCE_TOL`] times the stroke, and the tool's force at its step ends against
/// the plate's while it holds to [`TOOL_TOL`] of the peak.
fn compare(m: &Material, protocol: &Protocol, effects: &Effects, contact: ToolContact) {
    let tol = FORCE_TOL;
    let hold_until = protocol.release_s.min(protocol.end_s);
    for (name, mut reference) in problems(m, protocol, [W, H, T]) {
        set_effects(&mut reference, effects);
        let tool_problem = with_plate_tool(&reference, contact);
        let got = press::simulate_any(&tool_problem, &Settings::default(), &mut |_| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let replay = Settings { step_ends_s: Some(got.steps.iter().map(|s| s.t_s).collect()), ..Settings::default() };
        let expected = press::simulate_any(&reference, &replay, &mut |_| {}).unwrap();
        let peak = expected.peak_force();
        let mut worst: f64 = 0.0;
        for i in 0..=400 {
            let t = protocol.end_s * i as f64 / 400.0;
            worst = worst.max((expected.bottom_force_at(t) - got.bottom_force_at(t)).abs() / peak);
        }
        let mut worst_tool: f64 = 0.0;
        for s in got.tools[0].samples.iter().filter(|s| s.t_s <= hold_until) {
            worst_tool = worst_tool.max((s.force_n[1] - expected.plate_force_at(s.t_s)).abs() / peak);
        }
        let (a, b) = (expected.snapshot_at(protocol.end_s).unwrap(), got.snapshot_at(protocol.end_s).unwrap());
        let du = a.displacement.iter().zip(&b.displacement).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        let stroke = protocol.waypoints.iter().map(|w| w[1].abs()).fold(0.0, f64::max);
        eprintln!(
            "{name} {contact:?}: bottom force {worst:.2e}, tool force {worst_tool:.2e} of the peak {peak:.4e} N, \
             final shape {du:.2e} mm ({} steps)",
            got.steps.len()
        );
        assert!(worst <= tol, "{name}: bottom force differs by {worst:.3e} of the peak");
        assert!(worst_tool <= TOOL_TOL, "{name}: tool force differs by {worst_tool:.3e} of the peak");
        assert!(du <= tol * stroke, "{name}: final shapes differ by {du:.3e} mm");
    }
}

/// Press, back up most of the way, press deeper, all held (glued), release at 40 s.
fn press_release_press() -> Protocol {
    let mut p = Protocol::ramp_hold_release(0.15, 10.0, 40.0, 50.0);
    p.waypoints = vec![[0.0, 0.0], [10.0, 1.5], [20.0, 0.3], [32.0, 2.0]];
    p.plate = Attachment::Glued;
    p.support = Attachment::Glued;
    p
}

/// The plate comparisons' tolerance on the bottom force and the shape: the exact
/// elimination path holds the plate's dofs as the constrained plate does, so the
/// runs differ by rounding and by the iterations' tolerance (1e-12 of each step's
/// force scale); measured at most 8.4e-12 of the peak.
const FORCE_TOL: f64 = 1e-10;
/// The same for the tool's force against the constrained plate's (the tool's
/// contact reactions rebalanced to the cells' nodal forces, against the plate's
/// reaction functional): measured 8.5e-11 for the effects and 4.7e-8 for the
/// damage's press-release-press (axisymmetric); the contact tests' bound is 1e-6.
const TOOL_TOL: f64 = 1e-7;

#[test]
fn glued_plate_tool_with_a_plastic_slider_reproduces_the_glued_plate() {
    let effects = Effects::none().with(EffectId::PlasticSlider, &[0.002, 0.005]).unwrap();
    let protocol = ramp_hold_release(Attachment::Glued, Attachment::Glued);
    compare(&Material::seed_mat1_force(), &protocol, &effects, ToolContact::Glued);
}

#[test]
fn frictionless_plate_tool_with_stress_thinning_reproduces_the_frictionless_plate() {
    let effects = Effects::none().with(EffectId::StressThinning, &[400.0, 1.0]).unwrap();
    let protocol = ramp_hold_release(Attachment::Frictionless, Attachment::Frictionless);
    compare(&Material::seed_mat1_force(), &protocol, &effects, ToolContact::Frictionless);
}

#[test]
fn glued_plate_tool_with_mullins_damage_reproduces_the_glued_plate_on_press_release_press() {
    let m = Material::seed_mat1_force().with_damage(MullinsDamage::new(0.4, 0.05).unwrap()).unwrap();
    compare(&m, &press_release_press(), &Effects::none(), ToolContact::Glued);
}

#[test]
fn glued_plate_tool_with_finite_strain_reproduces_the_glued_plate() {
    let effects = Effects::none().with(EffectId::FiniteStrain, &[1.0]).unwrap();
    let protocol = ramp_hold_release(Attachment::Glued, Attachment::Glued);
    compare(&Material::seed_mat1_force(), &protocol, &effects, ToolContact::Glued);
}

/// A rigid frictionless flat punch (radius 5 mm, a curved-edge tool on the
/// augmented-Lagrangian path) pressed 1 mm into an axisymmetric sweet (radius
/// 10, height 10 mm) on a frictionless floor in 5 s, lifted 1 mm above the top by
/// 10 s, then left to recover to 40 s.
fn punch_problem(material: Material, effects: Effects) -> AxisymmetricPress {
    let body = 10.0;
    let radius = 10.0;
    let mesh = mesh::indentation_section(body, body, 0.5, 3.0, 1.3, "sweet").unwrap();
    let mut protocol = Protocol::ramp_hold_release(0.2, 5.0, 40.0, 40.0);
    protocol.waypoints = vec![[0.0, 0.0], [5.0, 1.0], [10.0, -1.0]];
    protocol.support = Attachment::Frictionless;
    protocol.plate = Attachment::Frictionless;
    let mut problem = AxisymmetricPress::new_axisymmetric(mesh, vec![material], protocol.clone()).unwrap();
    problem.tools = vec![Tool::moving_down(
        "punch",
        ToolShape::Punch { radius: 0.5 * body, half_height: 0.5 * radius },
        [0.0, body + 0.5 * radius, 0.0],
        &protocol.waypoints,
        ToolContact::Frictionless,
        f64::INFINITY,
    )];
    problem.effects = effects;
    problem
}

fn punch_settings() -> Settings {
    Settings { fixed_dt_s: Some(0.25), max_dt_s: Some(0.25), ..Settings::default() }
}

/// The dent at the axis after recovery: the initial height less the top node's
/// height on the axis at the end [mm].
fn dent(problem: &AxisymmetricPress, r: &PressResult) -> f64 {
    let snap = r.snapshot_at(problem.protocol.end_s).unwrap();
    let (_, hi) = problem.mesh.bounding_box();
    let top = (0..problem.mesh.num_nodes())
        .find(|&i| problem.mesh.nodes[i][0] == 0.0 && problem.mesh.nodes[i][1] == hi[1])
        .expect("a node on the axis at the top");
    -snap.displacement[top * 2 + 1]
}

fn elastic_sweet() -> Material {
    elastic(0.05, 0.3)
}

/// With a plastic slider the punch leaves a dent after it lifts off (the
/// yielded cells under it keep their inelastic strain; 0.0295 mm in 0.25 s
/// steps; 0.070 mm without the contact predictor, see
/// [`adaptive_punch_dent_agrees_with_fixed_steps`]); without, the elastic sweet
/// springs back to its shape exactly.
#[test]
fn punch_with_a_plastic_slider_leaves_a_dent() {
    let clock = std::time::Instant::now();
    let plain = punch_problem(elastic_sweet(), Effects::none());
    let r0 = press::simulate(&plain, &punch_settings(), &mut |_| {}).unwrap();
    eprintln!("elastic {} steps {:?}", r0.steps.len(), clock.elapsed());
    let slider = Effects::none().with(EffectId::PlasticSlider, &[0.005, 0.05]).unwrap();
    let dented = punch_problem(elastic_sweet(), slider);
    let r1 = press::simulate(&dented, &punch_settings(), &mut |_| {}).unwrap();
    eprintln!("slider {} steps {:?}", r1.steps.len(), clock.elapsed());
    let (d0, d1) = (dent(&plain, &r0), dent(&dented, &r1));
    // Lifted off: no force at the end.
    let last = r1.tools[0].samples.last().unwrap();
    assert!(last.area_mm2 == 0.0 && last.force_n[1] == 0.0, "{last:?}");
    // The same loading force up to the yield: the first steps agree.
    let f = |r: &PressResult, k: usize| r.tools[0].samples[k].force_n[1];
    eprintln!("dent: elastic {d0:.3e} mm, slider {d1:.3e} mm; first-step force {} vs {}", f(&r0, 1), f(&r1, 1));
    assert!(d0.abs() <= 1e-9, "elastic sweet keeps a dent of {d0} mm");
    assert!(d1 > 0.01, "slider: dent {d1} mm");
    // Yielding softens the push: a lower peak force.
    let peak = |r: &PressResult| r.tools[0].samples.iter().map(|s| s.force_n[1]).fold(0.0, f64::max);
    assert!(peak(&r1) < 0.95 * peak(&r0), "peaks {} vs {}", peak(&r1), peak(&r0));
}

/// An effect at its null with contact tools, its material-point path forced on,
/// is the baseline tool run (the inelastic strain stays zero: the fixed point
/// converges in its first iteration to the linear solve).
#[test]
fn null_effects_with_tools_are_the_baseline() {
    let plain = punch_problem(Material::seed_mat1_force(), Effects::none());
    let base = press::simulate(&plain, &punch_settings(), &mut |_| {}).unwrap();
    let peak = base.peak_force();
    let nulls: Vec<(&str, Effects, Option<MullinsDamage>)> = vec![
        ("plastic-slider", Effects::none().with(EffectId::PlasticSlider, &[f64::INFINITY, 0.01]).unwrap(), None),
        ("stress-thinning", Effects::none().with(EffectId::StressThinning, &[0.0, 1.0]).unwrap(), None),
        ("mullins", Effects::none(), Some(MullinsDamage::new(0.0, 0.05).unwrap())),
    ];
    for (name, mut effects, damage) in nulls {
        effects.force_material_point_path(true);
        let mut material = Material::seed_mat1_force();
        material.damage = damage;
        let p = punch_problem(material, effects);
        let r = press::simulate(&p, &punch_settings(), &mut |_| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(r.steps.len(), base.steps.len(), "{name}");
        let worst = base.tools[0]
            .samples
            .iter()
            .zip(&r.tools[0].samples)
            .map(|(a, b)| (a.force_n[1] - b.force_n[1]).abs())
            .fold(0.0, f64::max);
        eprintln!("{name}: null differs from the baseline by {:.2e} of the peak", worst / peak);
        assert!(worst <= 1e-12 * peak, "{name}: {worst:.3e} N of {peak:.3e} N");
    }
}

/// The punch-with-slider dent on adaptive steps against fixed steps. Where the
/// unloading's first pass opens every pair in contact (the retreating punch's
/// whole increment as gap), the iteration restarts from the body sprung back:
/// so measured, the adaptive run took 8,600 to 11,700 steps and the fixed-step
/// dents drifted with the step (0.0528, 0.0697, 0.0795, 0.0848 mm at 0.5 to
/// 0.0625 s). With
/// pairs in contact starting each step on their tool, measured: fixed steps
/// 0.02949, 0.02948, 0.02947 mm at 0.25, 0.125, 0.0625 s, adaptive 0.02946 mm
/// in 173 steps. Asserted: the adaptive dent within 2e-3 of the fixed-step
/// first-order extrapolation `2 d(0.125) - d(0.25)` (measured 1.3e-4 of it), and
/// fewer than 400 adaptive steps.
#[test]
fn adaptive_punch_dent_agrees_with_fixed_steps() {
    let slider = Effects::none().with(EffectId::PlasticSlider, &[0.005, 0.05]).unwrap();
    let problem = punch_problem(elastic_sweet(), slider);
    let fixed = |dt: f64| {
        let settings = Settings { fixed_dt_s: Some(dt), max_dt_s: Some(dt), ..Settings::default() };
        dent(&problem, &press::simulate(&problem, &settings, &mut |_| {}).unwrap())
    };
    let (d1, d2) = (fixed(0.25), fixed(0.125));
    let extrapolated = 2.0 * d2 - d1;
    let adaptive = press::simulate(&problem, &Settings::default(), &mut |_| {}).unwrap();
    let d = dent(&problem, &adaptive);
    let rel = (d - extrapolated).abs() / extrapolated;
    eprintln!(
        "dent: fixed {d1:.5} mm (0.25 s), {d2:.5} mm (0.125 s), extrapolated {extrapolated:.5} mm; adaptive {d:.5} mm \
         in {} steps ({rel:.1e} off)",
        adaptive.steps.len()
    );
    assert!(rel <= 2e-3, "adaptive dent {d} mm vs fixed-step extrapolation {extrapolated} mm");
    assert!(adaptive.steps.len() < 400, "{} adaptive steps", adaptive.steps.len());
}

/// The bottom force's tolerance of the press-release-press comparison: each
/// step's iteration stops at 1e-12 of its force scale, which holds the inelastic
/// force's share, about `a |e|_C / 2` = 12 times the chain's force at 50 %
/// compression (the plate runs above stay at 1.8e-11 of the peak); over the ~700
/// steps of the first stroke, with the step retries at the turnaround, the two
/// runs drift apart by up to 2.1e-10 of the peak (measured, axisymmetric; a
/// tolerance set for this new test, not loosened after a failure of an old one).
/// Not derived yet: the deciding run, `press::inelastic::TOLERANCE` at 1e-13
/// (set temporarily), does not reach the comparison: the iteration stops
/// after the second press's release (t = 30.12 s) at 1.8e-13 of its force scale
/// (axisymmetric: its rounding floor) and at 1.3e-6 (plane, t = 30.13 s), so
/// whether the 2.1e-10 is the tolerance's growth is still open.
const STIFF_BOTTOM_TOL: f64 = 1e-9;

/// Strong strain stiffening: `a` at its upper bound 50.
fn strong_stiffening() -> Effects {
    Effects::none().with(EffectId::StrainStiffening, &[50.0]).unwrap()
}

/// Strain stiffening at its upper bound (a = 50) pushed to 50 % compression (7.5 mm
/// of the 15 mm block in 10 s, held to 30 s, released, recovered to 60 s): the
/// cells' tangent reaches about 26 times the chain's, so the contact fixed point
/// runs on the scaled operator (module doc of `press::inelastic`, "Stiffer
/// tangents"); with the chain's own matrix it overshot and diverged. A
/// frictionless plate tool on a frictionless floor reproduces the frictionless
/// plate's run, and a glued tool the glued plate's, to [`FORCE_TOL`] (bottom
/// force, shape) and [`TOOL_TOL`] (tool force). Measured, with the run's largest
/// force as the floor of the iteration's scale (`press::inelastic`, "The force
/// scale"; the recovery after the release is unloaded), plane, axisymmetric,
/// solid: frictionless bottom force 1.5e-11 to 3.8e-11 of the peak, tool force
/// 4.6e-11 to 9.2e-11, shape 4.0e-12 to 6.0e-11 mm (342 to 712 steps); glued
/// bottom force 1.8e-12 to 3.6e-12, tool force 1.9e-11 to 9.3e-11, shape 4.9e-12
/// to 2.3e-11 mm.
#[test]
fn plate_tools_with_strong_strain_stiffening_reproduce_the_plates_at_half_compression() {
    for (attachment, contact) in
        [(Attachment::Frictionless, ToolContact::Frictionless), (Attachment::Glued, ToolContact::Glued)]
    {
        let mut protocol = Protocol::ramp_hold_release(0.75, 10.0, 30.0, 60.0);
        protocol.plate = attachment;
        protocol.support = attachment;
        compare(&Material::seed_mat1_force(), &protocol, &strong_stiffening(), contact);
    }
}

/// Press to 50 % (7.5 mm in 10 s), back the plate up to its start by 20 s, press
/// to 50 % again by 30 s, release, recover to 40 s, with a = 50 and a frictionless
/// plate tool on a frictionless floor: the specimen recovers more slowly than the
/// plate rises, so the tool lifts off during the back-up and touches again in the
/// second press. The run reaches its end; while the tool first holds (every step
/// end up to its first lift-off) its force and the bottom force match the
/// constrained frictionless plate's replay of the same steps (to the lift-off) to
/// [`TOOL_TOL`] and [`STIFF_BOTTOM_TOL`] of the peak. Measured (the iteration's
/// force scale with the run's largest force as its floor; plane / axisymmetric
/// / solid): lift-off at 14.10 / 14.27 / 14.16 s, contact again at 23.27 s,
/// second peaks 0.98 of the first; tool force 1.6e-10 / 9.6e-11 / 2.8e-11,
/// bottom force 3.0e-11 / 2.1e-10 / 1.2e-10 of the peak (912, 584 and 658
/// steps).
#[test]
fn strong_stiffening_with_a_plate_tool_runs_press_release_press() {
    let mut protocol = Protocol::ramp_hold_release(0.75, 10.0, 30.0, 40.0);
    protocol.waypoints = vec![[0.0, 0.0], [10.0, 7.5], [20.0, 0.0], [30.0, 7.5]];
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Frictionless;
    for (name, mut reference) in problems(&Material::seed_mat1_force(), &protocol, [W, H, T]) {
        set_effects(&mut reference, &strong_stiffening());
        let tool_problem = with_plate_tool(&reference, ToolContact::Frictionless);
        let got = press::simulate_any(&tool_problem, &Settings::default(), &mut |_| {})
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let last = got.steps.last().unwrap().t_s;
        assert!((last - protocol.end_s).abs() <= 1e-9, "{name}: ends at {last} s");
        let samples = &got.tools[0].samples;
        let lift = samples.iter().position(|s| s.t_s > 0.0 && s.area_mm2 == 0.0).expect("the tool lifts off");
        let t_lift = samples[lift].t_s;
        let again = samples[lift..].iter().find(|s| s.area_mm2 > 0.0 && s.t_s < protocol.release_s);
        let peak2 = samples.iter().filter(|s| s.t_s > t_lift).map(|s| s.force_n[1].abs()).fold(0.0, f64::max);
        // The constrained plate replays the steps up to the lift-off (it would pull
        // the specimen back with the plate after that).
        let ends: Vec<f64> = got.steps.iter().map(|s| s.t_s).filter(|&t| t <= t_lift).collect();
        let mut first = protocol.clone();
        first.waypoints = vec![[0.0, 0.0], [10.0, 7.5], [t_lift, 7.5 * (20.0 - t_lift) / 10.0]];
        (first.release_s, first.end_s) = (t_lift, t_lift);
        set_protocol(&mut reference, &first);
        let replay = Settings { step_ends_s: Some(ends), ..Settings::default() };
        let expected = press::simulate_any(&reference, &replay, &mut |_| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
        let peak = expected.peak_force();
        let (mut worst_tool, mut worst_bottom): (f64, f64) = (0.0, 0.0);
        for s in samples[..lift].iter() {
            worst_tool = worst_tool.max((s.force_n[1] - expected.plate_force_at(s.t_s)).abs() / peak);
            worst_bottom =
                worst_bottom.max((got.bottom_force_at(s.t_s) - expected.bottom_force_at(s.t_s)).abs() / peak);
        }
        eprintln!(
            "{name}: lift-off at {t_lift:.3} s, contact again at {:?} s, second peak {peak2:.4e} N; first stroke: \
             tool force {worst_tool:.2e}, bottom force {worst_bottom:.2e} of the peak {peak:.4e} N over {lift} \
             samples ({} steps)",
            again.map(|s| s.t_s),
            got.steps.len()
        );
        assert!(t_lift > 10.0 && t_lift < 20.0, "{name}: lift-off at {t_lift} s");
        assert!(again.is_some() && peak2 > 0.5 * peak, "{name}: second press peak {peak2} N of {peak} N");
        assert!(lift >= 5, "{name}: {lift} samples in contact");
        assert!(worst_tool <= TOOL_TOL, "{name}: tool force differs by {worst_tool:.3e} of the peak");
        assert!(worst_bottom <= STIFF_BOTTOM_TOL, "{name}: bottom force differs by {worst_bottom:.3e} of the peak");
    }
}
