//! `[effects]` end to end: `wagashi press` simulates them, `wagashi fit` fits
//! materials with every effect held at its bundle value (by forward
//! sensitivities where the engine carries them, else by forward differences).

mod common;

use std::path::Path;

use common::*;

/// A small 2D elastic trial (frictionless plate, glued floor), no data.
const TRIAL: &str = r#"format = "wagashi-experiment/1"
name = "gel"
dimension = 2

[specimen]
shape = "block"
size_mm = [20.0, 15.0, 10.0]
density_g_cm3 = 1.1
material = "gel"

[materials.gel]
model = "elastic"
poisson = 0.3
E_MPa = 0.05

[protocol]
tool = "plate"
tool_contact = "frictionless"
support = "glued"
waypoints = [[0.0, 0.0], [10.0, 1.5], [20.0, 1.5]]
release_s = 20.0
end_s = 30.0
"#;

fn write_trial(dir: &Path, effects: &str) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("experiment.toml"), format!("{TRIAL}{effects}")).unwrap();
}

fn force_csv(path: &Path) -> Vec<(f64, f64)> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let mut it = l.split(',').map(|v| v.parse::<f64>().unwrap());
            (it.next().unwrap(), it.next().unwrap())
        })
        .collect()
}

/// `wagashi press` with a force offset and drift writes the baseline's force plus
/// `b0 + b1 t` at every sample (to the CSV's printed precision, 1e-9 N), also
/// after release where nothing touches; with gravity the released specimen
/// rests its weight on the floor (rho g W H T, 1e-6 relative).
#[test]
fn press_simulates_effects() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    write_trial(&cwd.join("base"), "");
    write_trial(&cwd.join("offset"), "\n[effects]\nforce_offset_N = 0.5\nforce_drift_N_per_s = 0.001\n");
    write_trial(&cwd.join("weight"), "\n[effects]\ngravity = 1.0\n");
    for name in ["base", "offset", "weight"] {
        assert_success(&wagashi_in(cwd, ["press", name, "-o", &format!("out-{name}"), "--size-mm", "2.5"]));
    }
    let base = force_csv(&cwd.join("out-base/force.csv"));
    let offset = force_csv(&cwd.join("out-offset/force.csv"));
    assert_eq!(base.len(), offset.len());
    for ((t, f0), (_, f1)) in base.iter().zip(&offset) {
        assert!((f1 - f0 - (0.5 + 0.001 * t)).abs() < 1e-9, "t = {t}: {f0} -> {f1}");
    }
    let weight = force_csv(&cwd.join("out-weight/force.csv"));
    let w = 1.1e-9 * 9810.0 * 20.0 * 15.0 * 10.0;
    let last = weight.last().unwrap().1;
    assert!((last - w).abs() < 1e-6 * w, "{last} vs weight {w}");
    let toml = std::fs::read_to_string(cwd.join("out-weight/experiment.toml")).unwrap();
    assert!(toml.contains("[effects]") && toml.contains("force_tared = false"), "{toml}");
}

/// A trial simulated with a force offset and gravity is fitted back (E to 1e-4)
/// with the same effects in place; with ageing, compliance, plate friction or
/// adhesion added to the bundle `wagashi fit` fits with forward differences
/// (ageing by `exp(0.01 * 2)` absorbs into E: E = 0.05 exp(-0.02) to 1e-4; a
/// compliance needs a stiffer E; friction restrains the barrel, so a softer E;
/// adhesion is never loaded by this push-hold trial, whose plate does not
/// withdraw, so E = 0.05 to 1e-3: the adhesive plate is a contact tool, not the
/// constrained one, and its differences come from adaptive runs); a trial
/// measured with friction is fitted back with it (E to 1e-3); a bad adhesion
/// strength is refused by `press` with the file, line and key.
#[test]
fn fit_holds_every_effect() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    write_trial(&cwd.join("in"), "\n[effects]\nforce_offset_N = 0.05\nforce_drift_N_per_s = -0.002\ngravity = 1.0\n");
    assert_success(&wagashi_in(cwd, ["press", "in", "-o", "measured", "--size-mm", "2.5"]));
    std::fs::write(cwd.join("start.toml"), "[materials.gel]\nmodel = \"elastic\"\npoisson = 0.3\nE_MPa = 0.02\n")
        .unwrap();
    let o = wagashi_in(
        cwd,
        ["fit", "measured", "--materials", "start.toml", "--size-mm", "2.5", "--procedure", "joint", "-o", "fit"],
    );
    assert_success(&o);
    let fit: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("fit/fit.json")).unwrap()).unwrap();
    let e = fit["sets"]["joint"]["gel"]["E_MPa"]["value"].as_f64().unwrap_or_else(|| panic!("{fit}"));
    assert!((e - 0.05).abs() < 1e-4 * 0.05, "E = {e}");

    for (effects, key) in [
        ("ageing_E_rate_per_h = 0.01\nage_h = 2.0", "ageing_E_rate_per_h"),
        ("machine_compliance_mm_per_N = 0.01", "machine_compliance_mm_per_N"),
        ("plate_friction = 0.3", "plate_friction"),
        ("adhesion_strength_MPa = 0.002", "adhesion_strength_MPa"),
    ] {
        let measured = cwd.join("measured/experiment.toml");
        let text = std::fs::read_to_string(&measured).unwrap();
        let dir = cwd.join(format!("with-{key}"));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(cwd.join("measured/force.csv"), dir.join("force.csv")).unwrap();
        // E alone is the unknown (poisson held at its truth: with both free, a
        // friction fit slides to poisson = 0, where friction does nothing).
        let text = text.replace("[effects]\n", &format!("[effects]\n{effects}\n")).replace("E_MPa = 0.05\n", "");
        std::fs::write(dir.join("experiment.toml"), text).unwrap();
        let out = format!("fit-{key}");
        let o = wagashi_in(cwd, ["fit", dir.to_str().unwrap(), "--size-mm", "2.5", "--procedure", "joint", "-o", &out]);
        assert_success(&o);
        let fit: serde_json::Value =
            serde_json::from_slice(&std::fs::read(cwd.join(&out).join("fit.json")).unwrap()).unwrap();
        let e = fit["sets"]["joint"]["gel"]["E_MPa"]["value"].as_f64().unwrap_or_else(|| panic!("{fit}"));
        println!("{key}: E = {e}");
        match key {
            "ageing_E_rate_per_h" => {
                let expected = 0.05 * (-0.02f64).exp();
                assert!((e - expected).abs() < 1e-4 * expected, "{key}: E = {e} vs {expected}");
            }
            "machine_compliance_mm_per_N" => assert!(e > 0.05 * (1.0 + 1e-3), "{key}: E = {e}"),
            "plate_friction" => assert!(e < 0.05 * (1.0 - 1e-3), "{key}: E = {e}"),
            _ => assert!((e - 0.05).abs() < 1e-3 * 0.05, "{key}: E = {e}"),
        }
    }

    // Measured with friction, fitted with it: adaptive-run differences.
    write_trial(&cwd.join("in-friction"), "\n[effects]\nplate_friction = 0.3\n");
    assert_success(&wagashi_in(cwd, ["press", "in-friction", "-o", "measured-friction", "--size-mm", "2.5"]));
    let measured = cwd.join("measured-friction/experiment.toml");
    let text = std::fs::read_to_string(&measured).unwrap();
    std::fs::write(&measured, text.replace("E_MPa = 0.05\n", "")).unwrap();
    let o =
        wagashi_in(cwd, ["fit", "measured-friction", "--size-mm", "2.5", "--procedure", "joint", "-o", "fit-friction"]);
    assert_success(&o);
    let fit: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cwd.join("fit-friction/fit.json")).unwrap()).unwrap();
    let e = fit["sets"]["joint"]["gel"]["E_MPa"]["value"].as_f64().unwrap_or_else(|| panic!("{fit}"));
    println!("measured with friction: E = {e}");
    assert!((e - 0.05).abs() < 1e-3 * 0.05, "E = {e}");

    write_trial(&cwd.join("sticky"), "\n[effects]\nadhesion_strength_MPa = -0.01\n");
    let o = wagashi_in(cwd, ["press", "sticky", "-o", "x"]);
    let line = assert_one_line_error(&o);
    assert!(
        line.contains("experiment.toml:25: effects.adhesion_strength_MPa:") && line.contains("outside [0, inf]"),
        "{line}"
    );
    assert!(!cwd.join("x").exists());
}

/// `wagashi press` simulates adhesion: the trial's plate rises 1 mm above the
/// unloaded height before it lets go; without adhesion the frictionless plate
/// holds the top bilaterally until release (the constrained baseline), with
/// adhesion (delta_c = 2 mm, a softening 0.2 N/mm below the block's 0.7 N/mm) it
/// is a contact tool that pulls at most `sigma_a A` = 0.4 N (1e-9) and softens
/// before the plate stops. An opening out of bounds and adhesion on a glued plate
/// are refused in one line naming the file, the line and the key, with no output
/// written.
#[test]
fn press_simulates_adhesion() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let lift = |t: &str| {
        t.replace("[20.0, 1.5]]", "[20.0, 1.5], [24.0, -1.0]]").replace("release_s = 20.0", "release_s = 25.0")
    };
    let write = |name: &str, text: String| {
        std::fs::create_dir_all(cwd.join(name)).unwrap();
        std::fs::write(cwd.join(name).join("experiment.toml"), text).unwrap();
    };
    write("base", lift(TRIAL));
    write("sticky", format!("{}\n[effects]\nadhesion_strength_MPa = 0.002\nadhesion_opening_mm = 2.0\n", lift(TRIAL)));
    for name in ["base", "sticky"] {
        assert_success(&wagashi_in(cwd, ["press", name, "-o", &format!("out-{name}"), "--size-mm", "2.5"]));
    }
    let base = force_csv(&cwd.join("out-base/force.csv"));
    let sticky = force_csv(&cwd.join("out-sticky/force.csv"));
    let min = |f: &[(f64, f64)]| f.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
    let strength = 0.002 * 20.0 * 10.0;
    println!("min force: baseline {:.4} N, adhesion {:.4} N", min(&base), min(&sticky));
    // The bottom force (what force.csv holds) equals the plate's with a glued floor
    // and no weight: the pull shows there too.
    assert!(min(&sticky) < -0.5 * strength && min(&sticky) >= -strength * (1.0 + 1e-9), "{}", min(&sticky));
    assert!(min(&base) < -strength, "the constrained plate pulls without limit: {}", min(&base));
    let last_pull = sticky.iter().rfind(|x| x.0 <= 24.0).unwrap().1;
    assert!(last_pull < 0.0 && last_pull > min(&sticky) + 0.05 * strength, "softened: {last_pull}");
    for (effects, key, cause) in [
        ("adhesion_strength_MPa = 0.002\nadhesion_opening_mm = -1.0", "adhesion_opening_mm", "outside [0, inf]"),
        ("adhesion_strength_MPa = 0.002", "adhesion_strength_MPa", "not frictionless"),
    ] {
        let mut text = format!("{}\n[effects]\n{effects}\n", lift(TRIAL));
        if cause == "not frictionless" {
            text = text.replace("tool_contact = \"frictionless\"", "tool_contact = \"glued\"");
        }
        write("bad", text);
        let o = wagashi_in(cwd, ["press", "bad", "-o", "out-bad", "--size-mm", "2.5"]);
        let line = assert_one_line_error(&o);
        assert!(
            line.contains("experiment.toml:") && line.contains(&format!("effects.{key}")) && line.contains(cause),
            "{line}"
        );
        assert!(!cwd.join("out-bad").exists());
    }
}

/// The material-point effects in `wagashi press`: a slider (yield stress below
/// the gel's peak stress of 0.005 MPa) lowers the force at the end of the push
/// and leaves the released specimen pressed (the force file ends at zero force
/// either way); an out-of-bounds value is refused naming the file, the line and
/// the key; `wagashi fit` fits E back (to 1e-4) from a trial simulated with strain
/// stiffening, with the effect in place (forward-difference Jacobians).
#[test]
fn press_runs_material_point_effects() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    write_trial(&cwd.join("base"), "");
    write_trial(&cwd.join("slider"), "\n[effects]\nplastic_yield_stress_MPa = 0.003\nplastic_hardening_MPa = 0.02\n");
    write_trial(&cwd.join("stiff"), "\n[effects]\nstrain_stiffening = 5.0\n");
    write_trial(&cwd.join("large"), "\n[effects]\nfinite_strain = 1.0\n");
    for name in ["base", "slider", "stiff", "large"] {
        assert_success(&wagashi_in(cwd, ["press", name, "-o", &format!("out-{name}"), "--size-mm", "5"]));
    }
    let force_at = |name: &str, t: f64| {
        let f = force_csv(&cwd.join(format!("out-{name}/force.csv")));
        f.iter().min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs())).unwrap().1
    };
    // Elastic gel, uniaxial-like push to 10 %: 0.005 MPa on 200 mm^2 at 10 s.
    let (base, slider) = (force_at("base", 10.0), force_at("slider", 10.0));
    assert!(slider < 0.9 * base, "{slider} vs {base}");
    // Strain stiffening a = 5 at 10 %: about 1 + a e / 2 = 1.25 times the force.
    let stiff = force_at("stiff", 10.0);
    assert!(stiff > 1.15 * base && stiff < 1.35 * base, "{stiff} vs {base}");
    // Finite strain (Saint Venant-Kirchhoff) softens: about (1 + eps)(1 + eps/2) = 0.855 at 10 %.
    let large = force_at("large", 10.0);
    assert!(large > 0.75 * base && large < 0.95 * base, "{large} vs {base}");
    assert!(force_at("slider", 5.0) > 0.0);

    write_trial(&cwd.join("bad"), "\n[effects]\nplastic_yield_stress_MPa = -0.003\n");
    let o = wagashi_in(cwd, ["press", "bad", "-o", "x"]);
    let line = assert_one_line_error(&o);
    assert!(
        line.contains("experiment.toml:25: effects.plastic_yield_stress_MPa:") && line.contains("outside"),
        "{line}"
    );

    std::fs::write(cwd.join("start.toml"), "[materials.gel]\nmodel = \"elastic\"\npoisson = 0.3\nE_MPa = 0.02\n")
        .unwrap();
    let o = wagashi_in(
        cwd,
        ["fit", "out-stiff", "--materials", "start.toml", "--size-mm", "5", "--procedure", "joint", "-o", "fit-stiff"],
    );
    assert_success(&o);
    let fit: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cwd.join("fit-stiff/fit.json")).unwrap()).unwrap();
    let e = fit["sets"]["joint"]["gel"]["E_MPa"]["value"].as_f64().unwrap_or_else(|| panic!("{fit}"));
    assert!((e - 0.05).abs() < 1e-4 * 0.05, "E = {e}");
}

/// A material with a Mullins-type damage (`mullins_d_inf`, `mullins_strain_c`)
/// runs without forward sensitivities, so `wagashi fit` differences it on the
/// run's frozen step ends: a trial simulated with the damage is fitted back
/// with it held (E to 1e-4). Before, the fit stopped with the engine's refusal.
#[test]
fn fit_holds_a_mullins_damage() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let dir = cwd.join("in");
    std::fs::create_dir_all(&dir).unwrap();
    let damaged = TRIAL.replace("E_MPa = 0.05\n", "E_MPa = 0.05\nmullins_d_inf = 0.3\nmullins_strain_c = 0.05\n");
    assert!(damaged.contains("mullins_d_inf"));
    std::fs::write(dir.join("experiment.toml"), damaged).unwrap();
    assert_success(&wagashi_in(cwd, ["press", "in", "-o", "measured", "--size-mm", "2.5"]));
    let measured = cwd.join("measured/experiment.toml");
    let text = std::fs::read_to_string(&measured).unwrap();
    assert!(text.contains("mullins_d_inf = 0.3"), "{text}");
    std::fs::write(&measured, text.replace("E_MPa = 0.05\n", "")).unwrap();
    let o = wagashi_in(cwd, ["fit", "measured", "--size-mm", "2.5", "--procedure", "joint", "-o", "fit"]);
    assert_success(&o);
    let fit: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("fit/fit.json")).unwrap()).unwrap();
    let e = fit["sets"]["joint"]["gel"]["E_MPa"]["value"].as_f64().unwrap_or_else(|| panic!("{fit}"));
    println!("E = {e}");
    assert!((e - 0.05).abs() < 1e-4 * 0.05, "E = {e}");
}

/// Machine compliance with a contact tool: a disc (a sphere in the plane, R =
/// 10 mm) pressed 1.5 mm into the trial's block behind a frame of 2 mm/N. `wagashi
/// press` simulates it (before, it was refused: constrained plate only), and
/// the compliant force lies below the rigid frame's at the end of the push; a
/// trial simulated so is fitted back with the compliance held (E to 1e-4: the
/// tool trial is differenced on frozen step ends, or on adaptive runs when a
/// replay fails).
#[test]
fn fit_holds_machine_compliance_with_a_sphere_tool() {
    let tmp = tempfile::tempdir().unwrap();
    let cwd = tmp.path();
    let sphere = TRIAL.replace("tool = \"plate\"\n", "tool = \"sphere\"\ntool_radius_mm = 10.0\n");
    assert!(sphere.contains("tool = \"sphere\""));
    for (name, effects) in [("rigid", ""), ("in", "\n[effects]\nmachine_compliance_mm_per_N = 2.0\n")] {
        let dir = cwd.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("experiment.toml"), format!("{sphere}{effects}")).unwrap();
        let out = format!("out-{name}");
        assert_success(&wagashi_in(cwd, ["press", name, "-o", out.as_str(), "--size-mm", "2.5"]));
    }
    // The sample nearest to `t`.
    let at =
        |rows: &[(f64, f64)], t: f64| rows.iter().min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs())).unwrap().1;
    let (rigid, compliant) = (force_csv(&cwd.join("out-rigid/force.csv")), force_csv(&cwd.join("out-in/force.csv")));
    let (f_rigid, f_compliant) = (at(&rigid, 10.0), at(&compliant, 10.0));
    println!("force at the end of the push: rigid frame {f_rigid:.6} N, compliant {f_compliant:.6} N");
    // The frame takes 2 F of the 1.5 mm stroke.
    assert!(f_compliant < f_rigid * 0.95 && 2.0 * f_compliant > 0.1 * 1.5, "{f_rigid} {f_compliant}");
    let measured = cwd.join("out-in/experiment.toml");
    let text = std::fs::read_to_string(&measured).unwrap();
    assert!(text.contains("machine_compliance_mm_per_N = 2"), "{text}");
    std::fs::write(&measured, text.replace("E_MPa = 0.05\n", "")).unwrap();
    let o = wagashi_in(cwd, ["fit", "out-in", "--size-mm", "2.5", "--procedure", "joint", "-o", "fit"]);
    assert_success(&o);
    let fit: serde_json::Value = serde_json::from_slice(&std::fs::read(cwd.join("fit/fit.json")).unwrap()).unwrap();
    let e = fit["sets"]["joint"]["gel"]["E_MPa"]["value"].as_f64().unwrap_or_else(|| panic!("{fit}"));
    println!("E = {e}");
    assert!((e - 0.05).abs() < 1e-4 * 0.05, "E = {e}");
}
