//! The material-point iteration on the seed's material with the plastic slider
//! matched to Table II (`calibrate::seed_gap`, VALIDATION.md "The seed's own
//! gap"): material 1, 58 x 59.5 x 12 mm in plane stress, glued to plate and
//! floor, x_force's E1, E2, c1, c2 times 5.197, c3 = 154.4 MPa s, a slider with
//! sigma_y = 7.333e-4 MPa and H = 9.139e-3 MPa. Two failures of the engine's
//! iteration (`fem_core::press`, the material-point path) are kept here:
//!
//! - with adaptive steps, the first step after the instant release (dt ~ 2e-4 s,
//!   where the chain's step factor `g ~ B2/dt` is 188 MPa and `H/g` 5e-5) stalled at
//!   1e-7 of the force scale: the slider's tangent was taken with at least 1 % of
//!   `g` as hardening, far stiffer than the true `H`;
//! - pushed at 0.8 mm/s on 2.5 mm elements with fixed 0.25 s steps, every cell
//!   yields in the first step and full Newton diverged (the residual grew a
//!   hundredfold) until the retries ran out at t = 0.16 s.
//!
//! Both runs failed before the exact tangent and the line search of
//! `press::inelastic`. The physics check: an adaptive run and fixed-step runs
//! agree at the step ends (forces) and in the final set, the fixed steps
//! converging to the adaptive value as they shrink.

use fem_core::effects::{EffectId, Effects};
use fem_core::material::{Material, Rheology};
use fem_core::mesh;
use fem_core::press::{self, MarkerRequest, PlanePress, PressResult, Protocol, Settings};

/// The chain scale and c3 of the matched slider truth (`tests/seed_gap.rs`).
const SCALE: f64 = 5.197;
const C3_MPA_S: f64 = 5.197 * 29.719;
const DEPTH_MM: f64 = 5.774;

/// The seed's material 1 with the matched slider: push `DEPTH_MM` at `speed`,
/// hold, release at once, recover; a marker at the middle of the top face at the end.
fn seed_slider(speed: f64, hold_s: f64, recovery_s: f64, size_mm: f64) -> PlanePress {
    let m = Material::new(
        Rheology::FiveElement {
            e1_mpa: 0.0349 * SCALE,
            e2_mpa: 0.0221 * SCALE,
            c1_mpa_s: 0.0071 * SCALE,
            c2_mpa_s: 0.1869 * SCALE,
            c3_mpa_s: C3_MPA_S,
        },
        0.3746,
    )
    .unwrap();
    let push = DEPTH_MM / speed;
    let end = push + hold_s + recovery_s;
    let protocol = Protocol::ramp_hold_release(speed, push, push + hold_s, end);
    let mut p =
        PlanePress::new_2d(mesh::rectangle(58.0, 59.5, size_mm, "mat1").unwrap(), 12.0, vec![m], protocol).unwrap();
    p.effects = Effects::none().with(EffectId::PlasticSlider, &[7.333e-4, 9.139e-3]).unwrap();
    p.markers = vec![MarkerRequest { name: "top".into(), position: vec![29.0, 59.5], times: vec![end] }];
    p
}

fn fixed(dt: f64) -> Settings {
    Settings { fixed_dt_s: Some(dt), ..Settings::default() }
}

fn top(r: &PressResult) -> f64 {
    r.markers[0].samples[0].1[1]
}

/// Failure (a): the seed's protocol (0.2 mm/s, 182.06 s hold, instant release,
/// 189.07 s of recovery) on 5 mm elements with adaptive steps, rtol 1e-3 and
/// 1e-4. Before the fix: "step 37 at t = 210.930003 s: the material-point
/// iteration did not converge" (residual 1.2e-7 of the force scale).
#[test]
fn slider_converges_after_the_instant_release_with_adaptive_steps() {
    let p = seed_slider(0.2, 182.06, 189.07, 5.0);
    for rtol in [1e-3, 1e-4] {
        let r = press::simulate(&p, &Settings { rtol, ..Settings::default() }, &mut |_| {});
        let r = r.unwrap_or_else(|e| panic!("rtol {rtol}: {e}"));
        // Steps land on the release, and the run reaches the end with a set.
        assert!(r.steps.iter().any(|s| (s.t_s - p.protocol.release_s).abs() < 1e-9));
        assert!((r.steps.last().unwrap().t_s - p.protocol.end_s).abs() < 1e-9);
        let set = 59.5 - top(&r);
        assert!(set > 3.0 && set < DEPTH_MM, "rtol {rtol}: set {set} mm");
    }
}

/// Failure (b): a push at 0.8 mm/s on 2.5 mm elements with fixed 0.25 s steps
/// (2 s of hold and of recovery: the failure was in the push). Before the fix:
/// "step 6 at t = 0.164062 s: ... the residual is 5.971e-3 of the force scale
/// after 60 iterations".
#[test]
fn slider_converges_in_a_fast_push_on_fine_elements() {
    let p = seed_slider(0.8, 2.0, 2.0, 2.5);
    let r = press::simulate(&p, &fixed(0.25), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    assert!((r.steps.last().unwrap().t_s - p.protocol.end_s).abs() < 1e-9);
    // The push lands on its end; the force there is positive (compression).
    let push_end = r.steps.iter().find(|s| (s.t_s - DEPTH_MM / 0.8).abs() < 1e-9).expect("a step at the push's end");
    assert!(push_end.plate_force_n > 0.0);
}

/// Adaptive against fixed steps on the same trial (0.8 mm/s, 10 s hold, instant
/// release, 10 s recovery; 5 mm elements). Measured: the adaptive step ends
/// (rtol 1e-3) agree with the fixed 0.0125 s run's dense force to 9.8e-4 of the
/// peak (outside the reference's first step after the release, where its
/// interpolation spans the instant drop); the final top of the fixed runs goes
/// 54.780778 (0.025 s), 54.784536 (0.0125 s), 54.786925 (0.00625 s) mm towards the
/// adaptive 54.789494 mm (rtol 1e-3; 54.789347 at 1e-4, 54.789520 at 1e-5), at
/// about first order; the first-order extrapolation of the 0.025 s and 0.0125 s
/// runs is 1.2e-3 mm from the adaptive value (the set is 4.7 mm). Asserted:
/// forces to 2e-3 of the peak, the extrapolated set to 3e-3 mm, the fixed runs
/// closer to the adaptive value at the shorter step.
#[test]
fn adaptive_and_fixed_steps_agree_through_the_release() {
    let p = seed_slider(0.8, 10.0, 10.0, 5.0);
    let release = p.protocol.release_s;
    let adaptive = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let coarse = press::simulate(&p, &fixed(0.025), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let fine = press::simulate(&p, &fixed(0.0125), &mut |_| {}).unwrap_or_else(|e| panic!("{e}"));
    let peak = fine.peak_force();
    let mut worst: f64 = 0.0;
    for s in adaptive.steps.iter().filter(|s| !(s.t_s > release && s.t_s < release + 0.0125 * (1.0 + 1e-9))) {
        worst = worst.max((s.bottom_force_n - fine.bottom_force_at(s.t_s)).abs() / peak);
    }
    let (a, c, f) = (top(&adaptive), top(&coarse), top(&fine));
    let extrapolated = 2.0 * f - c;
    println!("step-end forces within {worst:.2e} of the peak; top: adaptive {a:.6}, fixed {c:.6} / {f:.6}, extrapolated {extrapolated:.6} mm");
    assert!(worst < 2e-3, "forces differ by {worst} of the peak");
    assert!((extrapolated - a).abs() < 3e-3, "top: adaptive {a}, extrapolated fixed {extrapolated}");
    assert!((f - a).abs() < (c - a).abs(), "the fixed steps do not approach the adaptive set: {c}, {f} vs {a}");
}
