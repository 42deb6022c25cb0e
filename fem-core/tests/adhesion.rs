//! The `adhesion` effect (E8): a cohesive zone in the normal law of the plate's
//! contact. Null bit for bit; a closed form for a homogeneous elastic block pulled
//! off the plate (a spring in series with the rigid-linear cohesive law); the
//! signature on a viscoelastic block (a pull in the withdrawal, a taller final
//! shape); refusals.

use fem_core::effects::{EffectId, Effects};
use fem_core::material::{Material, Rheology};
use fem_core::mesh;
use fem_core::press::{
    self, Attachment, AxisymmetricPress, MarkerRequest, PlanePress, PressError, PressResult, Protocol, Settings, Tool,
    ToolContact,
};

mod common;
use common::series_force;

const W: f64 = 20.0;
const H: f64 = 15.0;
const T: f64 = 10.0;
const E: f64 = 0.05;

fn elastic() -> Material {
    Material::new(Rheology::Elastic { e_mpa: E }, 0.3).unwrap()
}

/// Pressed to `push` mm at t = 1 s, then pulled up to `lift` mm above the unloaded
/// height at t = 5 s; frictionless plate and support, never released.
fn push_pull(push: f64, lift: f64) -> Protocol {
    let mut p = Protocol::ramp_hold_release(push, 1.0, 5.0, 5.0);
    p.waypoints = vec![[0.0, 0.0], [1.0, push], [5.0, -lift]];
    p.plate = Attachment::Frictionless;
    p.support = Attachment::Frictionless;
    p
}

fn plane(material: Material, protocol: Protocol) -> PlanePress {
    PlanePress::new_2d(mesh::rectangle(W, H, 2.5, "m").unwrap(), T, vec![material], protocol).unwrap()
}

fn bits_equal(a: &PressResult, b: &PressResult) -> bool {
    a.steps.len() == b.steps.len()
        && a.steps.iter().zip(&b.steps).all(|(x, y)| {
            x.t_s.to_bits() == y.t_s.to_bits()
                && x.plate_force_n.to_bits() == y.plate_force_n.to_bits()
                && x.bottom_force_n.to_bits() == y.bottom_force_n.to_bits()
        })
        && a.snapshots
            .iter()
            .zip(&b.snapshots)
            .all(|(x, y)| x.displacement.iter().zip(&y.displacement).all(|(p, q)| p.to_bits() == q.to_bits()))
        && a.markers == b.markers
}

/// An elastic block in uniaxial stress (plane stress, frictionless plate and
/// support), pressed and then pulled 1.5 mm above its unloaded height: the plate
/// force follows the series closed form at every step end (1e-9 of the strength):
/// bonded and linear down to `-sigma_a A` at `d = -sigma_a A/k`, then linear
/// softening to zero at an opening of `delta_c`, zero after. The same with the
/// plate given as an explicit frictionless tool (bit for bit the converted plate),
/// and at the axisymmetric section (the facet shares weighted by `2 pi r`).
#[test]
fn pulled_block_follows_the_series_closed_form() {
    // k = E A / h; sigma_a so that the peak comes at 0.3 mm above the unloaded
    // height; delta_c so that the softening stiffness is a quarter of k (1.2 mm).
    // The plate rises at 0.4125 mm/s from 0.15 mm down at t = 1 s: the peak at
    // t = 1 + 0.45/0.4125 s, the full separation at t = 1 + 1.35/0.4125 s; both
    // are step ends, with steps of 0.05 s around them.
    let (peak_t, separation_t) = (1.0 + 0.45 / 0.4125, 1.0 + 1.35 / 0.4125);
    let mut ends: Vec<f64> = (1..=100).map(|i| 0.05 * i as f64).chain([peak_t, separation_t]).collect();
    ends.sort_by(f64::total_cmp);
    let settings = Settings { step_ends_s: Some(ends), ..Settings::default() };
    let check = |name: &str, base: AnyCase, area: f64| {
        let k = E * area / H;
        let strength = 0.3 * k;
        let sigma_a = strength / area;
        let dc = strength / (0.25 * k);
        let effects = Effects::none().with(EffectId::Adhesion, &[sigma_a, dc]).unwrap();
        let r = base.run(effects, &settings).unwrap();
        let at = |t: f64| r.steps.iter().find(|s| (s.t_s - t).abs() < 1e-12).unwrap().plate_force_n;
        assert!((at(peak_t) + strength).abs() <= 1e-9 * strength, "{name}: peak {}", at(peak_t));
        assert!(at(separation_t).abs() <= 1e-9 * strength, "{name}: separation {}", at(separation_t));
        let mut worst: f64 = 0.0;
        let (mut min, mut saw_softening) = (f64::INFINITY, false);
        for s in &r.steps {
            let d = push_pull(0.15, 1.5).displacement(s.t_s);
            let expected = series_force(k, strength, dc, d);
            worst = worst.max((s.plate_force_n - expected).abs() / strength);
            min = min.min(s.plate_force_n);
            saw_softening |= expected < 0.0 && k * d < -strength;
            assert!(
                (s.plate_force_n - expected).abs() <= 1e-9 * strength,
                "{name}, t = {}: d = {d}, force {} vs {expected}",
                s.t_s,
                s.plate_force_n
            );
        }
        println!("{name}: largest force error {worst:.2e} of sigma_a A = {strength:.4} N (min force {min:.4} N)");
        assert!(saw_softening && min < -0.99 * strength);
        r
    };
    let block = || plane(elastic(), push_pull(0.15, 1.5));
    let converted = check("plane stress, converted plate", AnyCase::Plane(block()), W * T);
    // The same plate as an explicit tool.
    let mut explicit = block();
    let (lo, hi) = ([0.0, 0.0, 0.0], [W, H, 0.0]);
    let pr = &explicit.protocol;
    explicit.tools = vec![Tool::plate_above("plate", lo, hi, &pr.waypoints, ToolContact::Frictionless, pr.release_s)];
    let tool = check("plane stress, explicit tool", AnyCase::Plane(explicit), W * T);
    assert!(bits_equal(&converted, &tool));
    // Axisymmetric: a cylinder of radius R; the top's area pi R^2.
    let radius = 10.0;
    let axi = AxisymmetricPress::new_axisymmetric(
        mesh::axisymmetric_section(radius, H, 2.5, "m").unwrap(),
        vec![elastic()],
        push_pull(0.15, 1.5),
    )
    .unwrap();
    check("axisymmetric", AnyCase::Axi(axi), std::f64::consts::PI * radius * radius);
}

enum AnyCase {
    Plane(PlanePress),
    Axi(AxisymmetricPress),
}

impl AnyCase {
    fn run(mut self, effects: Effects, settings: &Settings) -> Result<PressResult, PressError> {
        match &mut self {
            AnyCase::Plane(p) => {
                p.effects = effects;
                press::simulate(p, settings, &mut |_| {})
            }
            AnyCase::Axi(p) => {
                p.effects = effects;
                press::simulate(p, settings, &mut |_| {})
            }
        }
    }
}

/// At its null (strength 0, any opening) adhesion leaves the run bit for bit the
/// baseline's: with the constrained plate and with explicit contact tools.
#[test]
fn null_adhesion_is_the_baseline_bit_for_bit() {
    let settings = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let mut base = plane(elastic(), push_pull(0.15, 0.5));
    base.markers = vec![MarkerRequest { name: "top".into(), position: vec![W / 2.0, H], times: vec![0.0, 2.0, 5.0] }];
    let mut tools = base.clone();
    let pr = &tools.protocol;
    tools.tools =
        vec![Tool::plate_above("plate", [0.0; 3], [W, H, 0.0], &pr.waypoints, ToolContact::Frictionless, pr.release_s)];
    for p in [base, tools] {
        let reference = press::simulate(&p, &settings, &mut |_| {}).unwrap();
        for opening in [0.1, 0.0, 3.0] {
            let mut q = p.clone();
            q.effects = Effects::none().with(EffectId::Adhesion, &[0.0, opening]).unwrap();
            assert!(q.effects.is_null());
            assert!(bits_equal(&reference, &press::simulate(&q, &settings, &mut |_| {}).unwrap()));
        }
    }
}

/// The signature (diagnosis-details.md E8): a five-element block pressed 10 %,
/// held, and then left by a plate that rises 1 mm above the unloaded height at
/// 0.5 mm/s (the withdrawal) before it lets go. Against the same trial without
/// adhesion (the frictionless plate as a unilateral contact tool, adhesion's limit
/// at strength 0), adhesion pulls on the plate during the withdrawal (a negative
/// force, at most the strength `sigma_a A`), the top separates later, and the final
/// height is larger (the viscous chain was stretched while held).
#[test]
fn withdrawal_pulls_and_leaves_a_taller_specimen() {
    let mut protocol = Protocol::ramp_hold_release(0.15, 10.0, 40.0, 80.0);
    protocol.waypoints = vec![[0.0, 0.0], [10.0, 1.5], [40.0, 1.5], [45.0, -1.0]];
    protocol.release_s = 45.0;
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Frictionless;
    let mut base = plane(Material::seed_mat1_force(), protocol);
    base.markers =
        vec![MarkerRequest { name: "top".into(), position: vec![W / 2.0, H], times: vec![40.0, 42.0, 80.0] }];
    let pr = &base.protocol;
    base.tools =
        vec![Tool::plate_above("plate", [0.0; 3], [W, H, 0.0], &pr.waypoints, ToolContact::Frictionless, 45.0)];
    let settings = Settings::default();
    let reference = press::simulate(&base, &settings, &mut |_| {}).unwrap();
    let (sigma_a, opening) = (0.002, 0.1);
    let mut p = base.clone();
    p.effects = Effects::none().with(EffectId::Adhesion, &[sigma_a, opening]).unwrap();
    let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
    let min = |r: &PressResult| r.steps.iter().filter(|s| s.t_s > 40.0).map(|s| s.plate_force_n).fold(0.0, f64::min);
    // The last step end at which the plate carries a force (1e-6 N).
    let last_touch = |r: &PressResult| {
        r.steps.iter().filter(|s| s.t_s <= 45.0 && s.plate_force_n.abs() > 1e-6).map(|s| s.t_s).fold(0.0, f64::max)
    };
    let height = |r: &PressResult| r.markers[0].samples.last().unwrap().1[1];
    println!(
        "min force {:.4} N (baseline {:.4}), last pull at {:.3} s (baseline {:.3}), final height {:.5} mm (baseline {:.5})",
        min(&r),
        min(&reference),
        last_touch(&r),
        last_touch(&reference),
        height(&r),
        height(&reference)
    );
    let strength = sigma_a * W * T;
    assert!(min(&reference) >= -1e-9 * strength, "the unilateral plate never pulls: {}", min(&reference));
    assert!(min(&r) < -0.1 * strength && min(&r) >= -strength * (1.0 + 1e-9), "{}", min(&r));
    assert!(last_touch(&r) > last_touch(&reference));
    assert!(height(&r) > height(&reference) + 1e-3, "{} vs {}", height(&r), height(&reference));
}

/// Refused where it does not extend the baseline (a glued plate, tools that are
/// all glued), each naming the key; with machine compliance it runs.
#[test]
fn adhesion_refusals_name_the_key() {
    let settings = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let adhesion = Effects::none().with(EffectId::Adhesion, &[0.002, 0.1]).unwrap();
    let mut glued = plane(elastic(), push_pull(0.15, 0.5));
    glued.protocol.plate = Attachment::Glued;
    glued.effects = adhesion.clone();
    let err = press::simulate(&glued, &settings, &mut |_| {}).unwrap_err();
    assert!(err.to_string().starts_with("effects: adhesion_strength_MPa:"), "{err}");
    let mut glued_tools = plane(elastic(), push_pull(0.15, 0.5));
    let pr = &glued_tools.protocol;
    glued_tools.tools =
        vec![Tool::plate_above("plate", [0.0; 3], [W, H, 0.0], &pr.waypoints, ToolContact::Glued, pr.release_s)];
    glued_tools.effects = adhesion.clone();
    let err = press::simulate(&glued_tools, &settings, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("adhesion_strength_MPa"), "{err}");
    // With machine compliance it runs (`tests/compliance.rs`): the plate tool rides on the crosshead.
    let mut compliant = plane(elastic(), push_pull(0.15, 0.5));
    compliant.effects = adhesion.with(EffectId::MachineCompliance, &[0.01]).unwrap();
    let r = press::simulate(&compliant, &settings, &mut |_| {});
    assert!(r.as_ref().is_ok_and(|r| r.peak_force() > 0.0), "{:?}", r.err());
    let err = Effects::none().with(EffectId::Adhesion, &[-1e-3, 0.1]).unwrap_err();
    assert!(err.to_string().starts_with("adhesion_strength_MPa = -0.001 is outside"), "{err}");
}

/// History and re-adhesion against the same series closed form: pulled into the
/// softening branch (to 0.6 mm above the unloaded height, opening 0.4 mm of
/// `delta_c` = 1.2 mm), pushed back (the open top unloads along the secant to the
/// origin, `s = sigma_a A (1 - 0.4/1.2)/0.4` = k/2 in series with k: `F = k d/3`),
/// touches again at `d = 0` and is pressed (bonded again, `F = k d`), then pulled
/// off again: the full strength again (a node that touches re-adheres), peak
/// `-sigma_a A` and the same softening. Every step end to 1e-9 of the strength.
#[test]
fn unloading_follows_the_secant_and_touching_again_re_adheres() {
    let mut protocol = push_pull(0.15, 0.6);
    protocol.waypoints = vec![[0.0, 0.0], [1.0, 0.15], [2.0, -0.6], [3.0, 0.15], [4.0, -0.6]];
    protocol.release_s = 4.0;
    protocol.end_s = 4.0;
    let mut p = plane(elastic(), protocol.clone());
    let area = W * T;
    let k = E * area / H;
    let strength = 0.3 * k;
    let dc = strength / (0.25 * k);
    p.effects = Effects::none().with(EffectId::Adhesion, &[strength / area, dc]).unwrap();
    // Step ends every 0.05 s plus both peaks (d = -0.3 mm at t = 1.6 and 3.6 s).
    let mut ends: Vec<f64> = (1..=80).map(|i| 0.05 * i as f64).chain([1.6, 3.6]).collect();
    ends.sort_by(f64::total_cmp);
    ends.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let settings = Settings { step_ends_s: Some(ends), ..Settings::default() };
    let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
    let mut worst: f64 = 0.0;
    for s in &r.steps {
        let d = protocol.displacement(s.t_s);
        let expected =
            if s.t_s > 2.0 && s.t_s <= 3.0 && d < 0.0 { k * d / 3.0 } else { series_force(k, strength, dc, d) };
        worst = worst.max((s.plate_force_n - expected).abs() / strength);
        assert!(
            (s.plate_force_n - expected).abs() <= 1e-9 * strength,
            "t = {}: d = {d}, force {} vs {expected}",
            s.t_s,
            s.plate_force_n
        );
    }
    println!("history: largest force error {worst:.2e} of sigma_a A");
    let at = |t: f64| r.steps.iter().find(|s| (s.t_s - t).abs() < 1e-9).unwrap().plate_force_n;
    assert!((at(3.6) + strength).abs() <= 1e-9 * strength, "second peak {}", at(3.6));
}

/// The softening stiffness `sigma_a A/delta_c` (0.8 N/mm) above the block's
/// (about 0.7 N/mm, glued floor): a uniform opening would snap back; the top
/// peels from its middle instead (the corners stay bonded longest), the explicit
/// cohesive iteration settles every step, the pull stays within the strength, and
/// once the plate has risen 1 mm above the unloaded height (t >= 24 s) the top is
/// free (force 0 to 1e-9 of the strength). Fixed steps: the last nodes let go at
/// once (a jump of the force), which the adaptive step control cannot resolve
/// (it ends with `StepTooSmall` at the jump).
#[test]
fn soft_bond_peels_and_lets_go() {
    let mut protocol = Protocol::ramp_hold_release(0.15, 10.0, 25.0, 30.0);
    protocol.waypoints = vec![[0.0, 0.0], [10.0, 1.5], [20.0, 1.5], [24.0, -1.0]];
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Glued;
    let mut p = plane(elastic(), protocol);
    let strength = 0.002 * W * T;
    p.effects = Effects::none().with(EffectId::Adhesion, &[0.002, 0.5]).unwrap();
    let r = press::simulate(&p, &Settings { fixed_dt_s: Some(0.25), ..Settings::default() }, &mut |_| {}).unwrap();
    let (i, min) = r.steps.iter().enumerate().map(|(i, s)| (i, s.plate_force_n)).fold((0, f64::INFINITY), |a, b| {
        if b.1 < a.1 {
            b
        } else {
            a
        }
    });
    println!("peeling: peak pull {min:.6} N at t = {:.4} s", r.steps[i].t_s);
    assert!(min >= -strength * (1.0 + 1e-9) && min < -0.5 * strength, "{min}");
    for s in r.steps.iter().filter(|s| s.t_s >= 24.0) {
        assert!(s.plate_force_n.abs() <= 1e-9 * strength, "t = {}: {}", s.t_s, s.plate_force_n);
    }
}
