//! The seed's own gap: the generator of `examples/seed_gap.rs` makes
//! material-1 trials in the seed's protocol whose final shape needs the seed's
//! second c3. These checks keep its physics honest and cheap (5 mm elements,
//! fixed 0.25 s steps, a few seconds); the diagnosis of those trials is the
//! example's (VALIDATION.md, "The seed's own gap"), too slow for a test.
//!
//! The slider truth is the example's match to Table II (rounded): x_force's E1,
//! E2, c1, c2, c3 times 5.197, a series slider with sigma_y = 7.333e-4 MPa and
//! H = 9.139e-3 MPa.

use calibrate::seed_gap::{simulate, SeedTrial, Truth, X_FORCE, X_SHAPE_C3};
use fem_core::effects::EffectId;
use fem_core::press::Settings;

fn settings() -> Settings {
    Settings { fixed_dt_s: Some(0.25), ..Settings::default() }
}

fn slider() -> Truth {
    Truth {
        scale: 5.197,
        c3_mpa_s: 5.197 * X_FORCE[4],
        effect: Some((EffectId::PlasticSlider, vec![7.333e-4, 9.139e-3])),
    }
}

/// The seed's symptom: x_shape's c3 keeps about nine times x_force's set; the
/// slider truth keeps x_shape's set (within 0.25 mm of 3.8 mm) while its force
/// at the end of the push and of the hold stays within 10 % of x_force's.
#[test]
fn the_matched_slider_gives_x_force_s_force_and_x_shape_s_set() {
    let seed = SeedTrial::SEED;
    let run = |c3: f64, truth: Option<Truth>| {
        let t = truth.unwrap_or(Truth { scale: 1.0, c3_mpa_s: c3, effect: None });
        simulate(&seed, &t, 5.0, &settings()).expect("the truth runs")
    };
    let (force, shape, truth) = (run(X_FORCE[4], None), run(X_SHAPE_C3, None), run(0.0, Some(slider())));
    let (set_f, set_s, set_t) = (force.final_set_mm(), shape.final_set_mm(), truth.final_set_mm());
    assert!(set_s / set_f > 8.0, "x_shape keeps {set_s} mm, x_force {set_f} mm");
    assert!((set_t - set_s).abs() < 0.25, "the slider keeps {set_t} mm against x_shape's {set_s} mm");
    for t in [seed.push_s(), seed.release_s() - 0.5] {
        let (a, b) = (truth.force_near(t), force.force_near(t));
        assert!((a / b - 1.0).abs() < 0.10, "force at {t} s: slider {a} N, x_force {b} N");
    }
}

/// The slider's signature (diagnosis-details.md §4.2): its set does not depend
/// on the hold (within 2 % between 45 s and 182 s), while a linear chain's grows
/// with the hold.
#[test]
fn the_slider_s_set_does_not_depend_on_the_hold() {
    let short = SeedTrial { hold_s: 45.0, ..SeedTrial::SEED };
    let set = |trial: &SeedTrial, truth: &Truth| simulate(trial, truth, 5.0, &settings()).expect("runs").final_set_mm();
    let (long_s, short_s) = (set(&SeedTrial::SEED, &slider()), set(&short, &slider()));
    assert!((long_s / short_s - 1.0).abs() < 0.02, "slider: {long_s} mm after 182 s, {short_s} mm after 45 s");
    let linear = Truth { scale: 1.0, c3_mpa_s: X_SHAPE_C3, effect: None };
    let (long_l, short_l) = (set(&SeedTrial::SEED, &linear), set(&short, &linear));
    assert!(long_l / short_l > 1.5, "linear chain: {long_l} mm after 182 s, {short_l} mm after 45 s");
}
