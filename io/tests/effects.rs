//! `[effects]` in experiment bundles: keys to the engine's effects, refusals
//! naming the file, line and key, and `plate_friction` as the friction tools a
//! bundle could give itself.

mod common;

use common::*;
use fem_core::effects::{EffectId, Effects};
use fem_core::press::{simulate_any, AnyPress, Settings};
use wagashi_io::{read_bundle, write_bundle, BundleWrite, ForceSample, ForceSeries};

fn effects_of(p: &AnyPress) -> &Effects {
    match p {
        AnyPress::Plane(p) => &p.effects,
        AnyPress::Solid(p) => &p.effects,
        AnyPress::Axisymmetric(p) => &p.effects,
    }
}

/// A small 2D trial, elastic, frictionless plate, glued floor.
const PLANE: &str = gel_experiment!(
    "small",
    2,
    r#"shape = "block"
size_mm = [20.0, 15.0, 10.0]
"#,
    r#"tool_contact = "frictionless"
support = "glued"
waypoints = [[0.0, 0.0], [1.0, 1.5]]
release_s = 1.0
end_s = 1.0
"#
);

fn plane_bundle(toml: &str) -> TestBundle {
    bundle(&[("experiment.toml", toml)])
}

#[test]
fn effect_keys_reach_the_engine() {
    let toml = format!(
        "{PLANE}\n[effects]\nforce_offset_N = 0.01\nforce_drift_N_per_s = -2e-4\ngravity = 0.5\n\
         machine_compliance_mm_per_N = 0.02\nageing_E_rate_per_h = 0.01\nageing_c_rate_per_h = -0.02\nage_h = 3.0\n"
    );
    let b = plane_bundle(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let p = bundle.to_press(2.5).unwrap();
    let e = effects_of(&p);
    assert_eq!(e.values(EffectId::ForceOffset), vec![0.01, -2e-4]);
    assert_eq!(e.values(EffectId::Gravity), vec![0.5]);
    assert_eq!(e.values(EffectId::MachineCompliance), vec![0.02]);
    assert_eq!(e.values(EffectId::Ageing), vec![0.01, -0.02]);
    assert_eq!(e.age_h(), Some(3.0));
    assert_eq!(e.active(), [EffectId::MachineCompliance, EffectId::Gravity, EffectId::ForceOffset, EffectId::Ageing]);
    // Without [effects]: none.
    let b = plane_bundle(PLANE);
    assert!(effects_of(&read_bundle(&b.dir).unwrap().to_press(2.5).unwrap()).is_null());
}

/// Unknown keys, values out of bounds and ageing
/// without its age are refused at reading, naming the file, the line and the key.
#[test]
fn bad_effect_keys_are_refused_by_line() {
    let cases = [
        ("force_ofset_N = 0.1", "effects.force_ofset_N", "unknown key"),
        ("adhesion_strength_MPa = -0.01", "effects.adhesion_strength_MPa", "outside [0, inf]"),
        ("adhesion_opening_mm = -0.1", "effects.adhesion_opening_mm", "outside [0, inf]"),
        ("strain_stiffening = 60.0", "effects.strain_stiffening", "outside [-4, 50]"),
        ("finite_strain = 1.5", "effects.finite_strain", "outside [0, 1]"),
        ("plastic_yield_stress_MPa = -0.01", "effects.plastic_yield_stress_MPa", "outside [0, inf]"),
        ("plastic_hardening_MPa = -1.0", "effects.plastic_hardening_MPa", "outside [0, inf]"),
        ("bingham_threshold_MPa = -0.001", "effects.bingham_threshold_MPa", "outside [0, inf]"),
        ("thinning_exponent = 5.0", "effects.thinning_exponent", "outside [0.2, 4]"),
        ("thinning_inverse_stress_1_per_MPa = -3.0", "effects.thinning_inverse_stress_1_per_MPa", "outside"),
        ("dual_viscosity_log_ratio = 12.0", "effects.dual_viscosity_log_ratio", "outside [-10, 10]"),
        ("gravity = 2.0", "effects.gravity", "outside [0, 1]"),
        ("plate_friction = -0.1", "effects.plate_friction", "outside"),
        ("age_h = -1.0", "effects.age_h", ">= 0"),
        ("ageing_E_rate_per_h = 0.01", "effects.age_h", "needs the trial covariate age_h"),
    ];
    for (line, field, cause) in cases {
        let toml = format!("{PLANE}\n[effects]\n{line}\n");
        let b = plane_bundle(&toml);
        let at = if field == "effects.age_h" && !line.starts_with("age_h") {
            line_of(&toml, "[effects]")
        } else {
            line_of(&toml, line)
        };
        let msg = assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), at, field);
        assert!(msg.contains(cause), "{msg}");
    }
}

/// Effects that do not fit the protocol are refused by the engine check, naming
/// the effect's key and line.
#[test]
fn conflicting_effects_name_their_key() {
    let cases = [
        (edit(PLANE, "end_s = 1.0", "end_s = 1.0\ngravity = true"), "gravity = 1.0", "effects.gravity"),
        (
            edit(PLANE, "tool_contact = \"frictionless\"", "tool_contact = \"glued\""),
            "plate_friction = 0.3",
            "effects.plate_friction",
        ),
    ];
    for (base, line, field) in cases {
        let toml = format!("{base}\n[effects]\n{line}\n");
        let b = plane_bundle(&toml);
        let err = read_bundle(&b.dir).unwrap().to_press(2.5).unwrap_err().to_string();
        let prefix = format!("{}:{}: {field}: ", b.file("experiment.toml").display(), line_of(&toml, line));
        assert!(err.starts_with(&prefix), "{err}");
    }
    // A dashpot law on the elastic gel (no c3), and two material-point effects at once.
    for (lines, line, field) in [
        ("bingham_threshold_MPa = 0.001", "bingham_threshold_MPa = 0.001", "effects.bingham_threshold_MPa"),
        (
            "plastic_yield_stress_MPa = 0.01\nthinning_inverse_stress_1_per_MPa = 10.0",
            "thinning_inverse_stress_1_per_MPa = 10.0",
            "effects.thinning_inverse_stress_1_per_MPa",
        ),
    ] {
        let toml = format!("{PLANE}\n[effects]\n{lines}\n");
        let b = plane_bundle(&toml);
        let err = match read_bundle(&b.dir) {
            Ok(bundle) => bundle.to_press(2.5).unwrap_err().to_string(),
            Err(e) => e.to_string(),
        };
        let prefix = format!("{}:{}: {field}: ", b.file("experiment.toml").display(), line_of(&toml, line));
        assert!(err.starts_with(&prefix), "{err}");
    }
}

/// The material-point effects' keys reach the engine and a bundle with each runs:
/// on the gel's elastic chain the slider yields (the end force falls below the
/// baseline's), and on a three-element chain the dashpot laws change the force.
#[test]
fn material_point_keys_run() {
    let settings = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let last_force = |toml: &str| {
        let b = plane_bundle(toml);
        let p = read_bundle(&b.dir).unwrap().to_press(5.0).unwrap();
        let r = simulate_any(&p, &settings, &mut |_| {}).unwrap();
        (effects_of(&p).clone(), r.steps.last().unwrap().plate_force_n)
    };
    let (_, base) = last_force(PLANE);
    let (e, slider) =
        last_force(&format!("{PLANE}\n[effects]\nplastic_yield_stress_MPa = 0.002\nplastic_hardening_MPa = 0.02\n"));
    assert_eq!(e.values(EffectId::PlasticSlider), vec![0.002, 0.02]);
    assert!(slider < base, "{slider} vs {base}");
    let chain = edit(PLANE, "model = \"elastic\"", "model = \"three-element\"");
    let chain = edit(&chain, "E_MPa = 0.05", "E1_MPa = 0.05\nc1_MPa_s = 0.2\nc3_MPa_s = 0.5");
    let (_, base) = last_force(&chain);
    for (lines, id) in [
        ("bingham_threshold_MPa = 0.001", EffectId::BinghamDashpot),
        ("thinning_inverse_stress_1_per_MPa = 500.0\nthinning_exponent = 1.5", EffectId::StressThinning),
        ("dual_viscosity_log_ratio = 1.0", EffectId::DualViscosity),
        ("strain_stiffening = 5.0", EffectId::StrainStiffening),
        ("finite_strain = 1.0", EffectId::FiniteStrain),
    ] {
        let (e, f) = last_force(&format!("{chain}\n[effects]\n{lines}\n"));
        assert_eq!(e.material_point().map(|m| m.0), Some(id));
        if id == EffectId::DualViscosity {
            // Loading only: the dual law acts in unloading, so the push is the baseline's.
            assert_eq!(f.to_bits(), base.to_bits(), "{id}");
        } else {
            assert!((f - base).abs() > 1e-6 * base, "{id}: {f} vs {base}");
        }
    }
}

/// `plate_friction = mu` on a frictionless plate is the same trial as
/// `tool_contact = "friction"` with `friction = mu` (bit for bit), and with a
/// frictionless floor as `support = "friction"` too.
#[test]
fn plate_friction_is_the_friction_tool() {
    let settings = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let force = |toml: &str| {
        let b = plane_bundle(toml);
        let p = read_bundle(&b.dir).unwrap().to_press(2.5).unwrap();
        let r = simulate_any(&p, &settings, &mut |_| {}).unwrap();
        r.steps.iter().map(|s| (s.bottom_force_n.to_bits(), s.plate_force_n.to_bits())).collect::<Vec<_>>()
    };
    let effect = force(&format!("{PLANE}\n[effects]\nplate_friction = 0.3\n"));
    let tool = force(&edit(PLANE, "tool_contact = \"frictionless\"", "tool_contact = \"friction\"\nfriction = 0.3"));
    assert_eq!(effect, tool);
    let slide = edit(PLANE, "support = \"glued\"", "support = \"frictionless\"");
    let effect = force(&format!("{slide}\n[effects]\nplate_friction = 0.3\n"));
    let tool = force(&edit(
        PLANE,
        "tool_contact = \"frictionless\"\nsupport = \"glued\"",
        "tool_contact = \"friction\"\nsupport = \"friction\"\nfriction = 0.3",
    ));
    assert_eq!(effect, tool);
    // At mu = 0 the frictionless baseline.
    assert_eq!(force(&format!("{PLANE}\n[effects]\nplate_friction = 0.0\n")), force(PLANE));
}

/// `[effects]` survives a written bundle; a simulated trial with gravity from the
/// effect is not marked tared (its force holds the weight).
#[test]
fn effects_round_trip() {
    let toml = format!("{PLANE}\n[effects]\ngravity = 1.0\nforce_offset_N = 0.5\n");
    let b = plane_bundle(&toml);
    let bundle = read_bundle(&b.dir).unwrap();
    let force =
        ForceSeries { samples: vec![ForceSample { t_s: 0.0, force_n: 0.5 }, ForceSample { t_s: 1.0, force_n: 1.0 }] };
    let out = b.root.path().join("out");
    write_bundle(&out, &BundleWrite::simulated(&bundle, "small-sim", &force, &[])).unwrap();
    let back = read_bundle(&out).unwrap();
    assert_eq!(back.experiment.effects, bundle.experiment.effects);
    assert_eq!(back.experiment.data.as_ref().unwrap().force_tared, Some(false));
    assert_eq!(effects_of(&back.to_press(2.5).unwrap()), effects_of(&bundle.to_press(2.5).unwrap()));
}

/// The Mullins-type damage keys of a material reach the engine: the push force
/// of a damaged elastic gel is below the baseline's (softening on first
/// loading); `mullins_d_inf = 0` gives the baseline bit for bit; out-of-range
/// values and a lone key are refused naming the file, line and key.
#[test]
fn mullins_damage_keys_run_and_are_checked() {
    let settings = Settings { fixed_dt_s: Some(0.25), ..Settings::default() };
    let last_force = |toml: &str| {
        let b = plane_bundle(toml);
        let p = read_bundle(&b.dir).unwrap().to_press(5.0).unwrap();
        simulate_any(&p, &settings, &mut |_| {}).unwrap().steps.last().unwrap().plate_force_n
    };
    let base = last_force(PLANE);
    let with = |lines: &str| edit(PLANE, "E_MPa = 0.05", &format!("E_MPa = 0.05\n{lines}"));
    let damaged = last_force(&with("mullins_d_inf = 0.3\nmullins_strain_c = 0.05"));
    assert!(damaged < 0.9 * base, "{damaged} vs {base}");
    let null = last_force(&with("mullins_d_inf = 0.0\nmullins_strain_c = 0.05"));
    assert_eq!(null.to_bits(), base.to_bits());
    for (lines, key) in [
        ("mullins_d_inf = 0.9\nmullins_strain_c = 0.05", "materials.gel.mullins_d_inf"),
        ("mullins_d_inf = 0.3\nmullins_strain_c = -1.0", "materials.gel.mullins_strain_c"),
        ("mullins_d_inf = 0.3", "materials.gel.mullins_d_inf"),
    ] {
        let b = plane_bundle(&with(lines));
        let err = read_bundle(&b.dir).unwrap_err().to_string();
        assert!(err.contains(key) && err.contains("experiment.toml:"), "{lines}: {err}");
    }
}
