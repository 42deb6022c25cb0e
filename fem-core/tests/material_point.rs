//! The material-point effects (E1 to E4 of the gap diagnosis:
//! `plastic-slider`, `bingham-dashpot`, `stress-thinning`, `dual-viscosity`) on
//! the engine's material-point path: the nulls against the linear baseline, and
//! homogeneous compression between frictionless plates (uniaxial stress: every
//! cell alike, `sigma = F / A`, `e = d / H`) against 1D closed forms and an
//! independent 1D reference integration.
//!
//! In uniaxial stress the engine's equivalent stress is `|sigma|` exactly
//! (`fem_core::material::InelasticLaw`), so the 1D laws of diagnosis-details.md
//! §4.2 apply as written.

use fem_core::effects::{EffectError, EffectId, Effects};
use fem_core::material::{Material, Rheology};
use fem_core::mesh;
use fem_core::press::{
    self, Attachment, AxisymmetricPress, Integrator, MarkerRequest, PlanePress, PressError, PressResult, Protocol,
    SensitivityParameter, Settings,
};

const W: f64 = 20.0;
const H: f64 = 15.0;
const T: f64 = 10.0;
/// The loaded area of the plane-stress block [mm^2].
const A: f64 = W * T;

fn material(rheology: Rheology, nu: f64) -> Material {
    Material::new(rheology, nu).unwrap()
}

/// Frictionless plate and floor: homogeneous uniaxial stress.
fn uniaxial(waypoints: Vec<[f64; 2]>, release_s: f64, end_s: f64) -> Protocol {
    let mut p = Protocol::ramp_hold_release(0.1, 1.0, release_s, end_s);
    p.waypoints = waypoints;
    p.plate = Attachment::Frictionless;
    p.support = Attachment::Frictionless;
    p
}

fn block(m: Material, protocol: Protocol, effects: Effects) -> PlanePress {
    let mut p = PlanePress::new_2d(mesh::rectangle(W, H, 5.0, "m").unwrap(), T, vec![m], protocol).unwrap();
    p.effects = effects;
    p
}

/// The axisymmetric runs' cylinder radius [mm].
const RADIUS: f64 = 10.0;

/// A cylinder (radius [`RADIUS`], height `H`, 2.5 mm cells) of `m`, axisymmetric.
fn cylinder(m: Material, protocol: Protocol, effects: Effects) -> AxisymmetricPress {
    let mut p = AxisymmetricPress::new_axisymmetric(
        mesh::axisymmetric_section(RADIUS, H, 2.5, "m").unwrap(),
        vec![m],
        protocol,
    )
    .unwrap();
    p.effects = effects;
    p
}

fn fixed(dt: f64) -> Settings {
    Settings { fixed_dt_s: Some(dt), ..Settings::default() }
}

fn effect(id: EffectId, values: &[f64]) -> Effects {
    Effects::none().with(id, values).unwrap()
}

/// The largest |plate force / `area` - `closed(d)`| over the step ends up to
/// `until_s`, over `peak` [MPa]: `d` is the protocol's plate displacement [mm],
/// `closed` the uniaxial stress it gives [MPa].
fn largest_stress_error(
    r: &PressResult,
    protocol: &Protocol,
    area: f64,
    until_s: f64,
    peak: f64,
    closed: impl Fn(f64) -> f64,
) -> f64 {
    r.steps
        .iter()
        .filter(|s| s.t_s <= until_s)
        .map(|s| (s.plate_force_n / area - closed(protocol.displacement(s.t_s))).abs() / peak)
        .fold(0.0, f64::max)
}

/// Largest |a - b| over the step ends that fall on `times` (to 1e-9 s).
fn largest_difference(r: &PressResult, times: &[f64], reference: &[f64]) -> f64 {
    times
        .iter()
        .zip(reference)
        .map(|(&t, &s)| {
            let step = r.steps.iter().find(|x| (x.t_s - t).abs() < 1e-9).unwrap_or_else(|| panic!("no step at {t}"));
            (step.plate_force_n / A - s).abs()
        })
        .fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------------------------------------------
// An independent 1D reference: the three-element chain (Voigt (E1, c1) + dashpot c3)
// with a modified dashpot flow, integrated by classical RK4 with tiny steps.

/// Dashpot flow laws of the reference: `e3' = flow(sigma, e')`.
#[derive(Clone, Copy)]
enum Flow {
    Bingham { threshold: f64 },
    Cross { inverse: f64, exponent: f64 },
    Dual { log_ratio: f64 },
}

struct Chain1d {
    e1: f64,
    c1: f64,
    c3: f64,
    flow: Flow,
}

impl Chain1d {
    /// `e3'` at stress `sigma` under the strain rate `rate`.
    fn flow(&self, sigma: f64, rate: f64) -> f64 {
        match self.flow {
            Flow::Bingham { threshold } => (sigma.abs() - threshold).max(0.0) * sigma.signum() / self.c3,
            Flow::Cross { inverse, exponent } => sigma * (1.0 + (inverse * sigma.abs()).powf(exponent)) / self.c3,
            Flow::Dual { log_ratio } => {
                let unloading = sigma * rate < 0.0;
                sigma / self.c3 * if unloading { (-log_ratio).exp() } else { 1.0 }
            }
        }
    }

    /// The stress for the dashpot strain `e3` at total strain `e` and rate `rate`:
    /// `sigma = E1 (e - e3) + c1 (rate - e3'(sigma))`, increasing in sigma (bisection).
    fn stress(&self, e: f64, e3: f64, rate: f64) -> f64 {
        let rhs = self.e1 * (e - e3) + self.c1 * rate;
        let f = |s: f64| s + self.c1 * self.flow(s, rate) - rhs;
        let (mut lo, mut hi) = (-rhs.abs() - 1.0, rhs.abs() + 1.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
            if hi - lo <= 1e-17 {
                break;
            }
        }
        0.5 * (lo + hi)
    }

    /// The stress at `times` (sorted, on multiples of `h`) under the strain of the
    /// waypoints `[t, e]` (linear in between, constant after the last).
    fn integrate(&self, waypoints: &[[f64; 2]], times: &[f64], h: f64) -> Vec<f64> {
        let strain = |t: f64| -> (f64, f64) {
            for w in waypoints.windows(2) {
                if t <= w[1][0] + 1e-12 {
                    let rate = (w[1][1] - w[0][1]) / (w[1][0] - w[0][0]);
                    return (w[0][1] + rate * (t - w[0][0]), rate);
                }
            }
            (waypoints.last().unwrap()[1], 0.0)
        };
        let rhs = |t: f64, e3: f64, mid: f64| {
            // Rates are taken in the segment of the step's midpoint (steps never straddle a kink).
            let (e, _) = strain(t);
            let rate = strain(mid).1;
            self.flow(self.stress(e, e3, rate), rate)
        };
        let (mut t, mut e3) = (0.0, 0.0);
        let mut out = Vec::new();
        for &target in times {
            while t < target - 0.5 * h {
                let mid = t + 0.5 * h;
                let k1 = rhs(t, e3, mid);
                let k2 = rhs(mid, e3 + 0.5 * h * k1, mid);
                let k3 = rhs(mid, e3 + 0.5 * h * k2, mid);
                let k4 = rhs(t + h, e3 + h * k3, mid);
                e3 += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                t += h;
            }
            let (e, rate) = strain(target - 0.25 * h);
            out.push(self.stress(e, e3, rate));
        }
        out
    }
}

/// Largest errors of the FE stress against the 1D reference (RK4 at
/// `reference_step` [s]) for the steps `dts`, with the observed orders between
/// successive halvings.
#[allow(clippy::too_many_arguments)]
fn convergence(
    chain: &Chain1d,
    nu: f64,
    waypoints_mm: &[[f64; 2]],
    release_s: f64,
    effects: &Effects,
    times: &[f64],
    dts: &[f64],
    reference_step: f64,
) -> (Vec<f64>, Vec<f64>) {
    let strain_waypoints: Vec<[f64; 2]> = waypoints_mm.iter().map(|w| [w[0], w[1] / H]).collect();
    let reference = chain.integrate(&strain_waypoints, times, reference_step);
    let rheology = Rheology::ThreeElement { e1_mpa: chain.e1, c1_mpa_s: chain.c1, c3_mpa_s: chain.c3 };
    let p = block(material(rheology, nu), uniaxial(waypoints_mm.to_vec(), release_s, release_s), effects.clone());
    let errors: Vec<f64> = dts
        .iter()
        .map(|&dt| largest_difference(&press::simulate(&p, &fixed(dt), &mut |_| {}).unwrap(), times, &reference))
        .collect();
    let orders = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    (errors, orders)
}

// ---------------------------------------------------------------------------------------------------------------
// Nulls.

/// Each material-point effect at its null values with the material-point path
/// forced on (inelastic strains, global iteration) gives the linear baseline's
/// forces, displacements and stresses within 1e-12 of their sizes, on the seed's
/// five-element material with a glued floor (an inhomogeneous state): at the null
/// every local update returns its trial unchanged (measured: equal bit for bit).
/// Without forcing, the engine takes the linear path itself
/// (`tests/effects.rs`, bit for bit).
#[test]
fn forced_material_point_path_at_the_null_is_the_baseline() {
    let mut protocol = Protocol::ramp_hold_release(0.75, 10.0, 40.0, 80.0);
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Glued;
    let base = PlanePress::new_2d(
        mesh::rectangle(W, H, 2.5, "m").unwrap(),
        T,
        vec![Material::seed_mat1_force()],
        protocol.clone(),
    )
    .unwrap();
    let settings = Settings::default();
    let reference = press::simulate(&base, &settings, &mut |_| {}).unwrap();
    let peak = reference.peak_force();
    for id in [
        EffectId::PlasticSlider,
        EffectId::BinghamDashpot,
        EffectId::StressThinning,
        EffectId::DualViscosity,
        EffectId::StrainStiffening,
        EffectId::FiniteStrain,
    ] {
        let mut p = base.clone();
        p.effects = effect(id, &id.null_values());
        p.effects.force_material_point_path(true);
        assert_eq!(p.effects.material_point().map(|m| m.0), Some(id));
        let r = press::simulate(&p, &settings, &mut |_| {}).unwrap_or_else(|e| panic!("{id}: {e}"));
        assert_eq!(r.steps.len(), reference.steps.len(), "{id}");
        let mut worst: f64 = 0.0;
        for (x, y) in reference.steps.iter().zip(&r.steps) {
            assert_eq!(x.t_s, y.t_s, "{id}");
            worst =
                worst.max((x.bottom_force_n - y.bottom_force_n).abs()).max((x.plate_force_n - y.plate_force_n).abs());
        }
        for (x, y) in reference.snapshots.iter().zip(&r.snapshots) {
            let size = x.displacement.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in x.displacement.iter().zip(&y.displacement) {
                assert!((a - b).abs() <= 1e-12 * size, "{id}: displacement");
            }
            let size = x.cell_stress.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in x.cell_stress.iter().zip(&y.cell_stress) {
                assert!((a - b).abs() <= 1e-12 * size, "{id}: stress");
            }
        }
        println!("{id} forced at the null: largest force difference {:.1e} of the peak", worst / peak);
        assert!(worst <= 1e-12 * peak, "{id}: {worst}");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// plastic-slider.

/// An elastic chain (E) in series with the slider (sigma_y, H), pushed to 10 %,
/// held, released. 1D: the slider does not move while `|sigma - H e_p| < sigma_y`,
/// so up to the knee `sigma = E e`; beyond it `sigma = sigma_y + H e_p` and
/// `e = sigma/E + e_p`, hence
/// `sigma = sigma_y + E H/(E + H) (e - sigma_y/E)` (the knee at `e = sigma_y/E`).
/// Unloaded to zero stress (the release) the slider stays put as long as
/// `sigma_peak < 2 sigma_y` (no reverse yield): the set is
/// `e_p = <sigma_peak - sigma_y>/H`, and the top sits at `H0 (1 - e_p)`.
/// The return mapping is exact for a rate-independent chain, so every step end
/// matches, at any step: forces to 1e-9 relative, the top to 1e-9 mm, with fixed
/// steps (1 s, not landing on the knee) and with the adaptive control; and the
/// same in the axisymmetric formulation (a cylinder: area pi R^2).
#[test]
fn slider_knee_and_set_match_the_closed_form() {
    let (e, nu, sy, hh) = (0.05, 0.3, 0.0033, 0.01);
    let depth = 0.1 * H;
    let closed = |strain: f64| {
        if strain <= sy / e {
            e * strain
        } else {
            sy + e * hh / (e + hh) * (strain - sy / e)
        }
    };
    let peak = closed(0.1);
    assert!(peak > sy && peak < 2.0 * sy);
    let set = (peak - sy) / hh;
    let waypoints = vec![[0.0, 0.0], [10.0, depth], [15.0, depth]];
    let slider = effect(EffectId::PlasticSlider, &[sy, hh]);
    for (name, settings) in [("fixed 1 s", fixed(1.0)), ("adaptive", Settings::default())] {
        let mut p = block(
            material(Rheology::Elastic { e_mpa: e }, nu),
            uniaxial(waypoints.clone(), 15.0, 25.0),
            slider.clone(),
        );
        p.markers = vec![MarkerRequest { name: "top".into(), position: vec![W / 2.0, H], times: vec![25.0] }];
        let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
        let worst = largest_stress_error(&r, &p.protocol, A, 15.0, peak, |d| closed(d / H));
        let top = r.markers[0].samples[0].1[1];
        println!("{name}: largest stress error {worst:.2e} of the peak; top {top:.12} vs {:.12}", H * (1.0 - set));
        assert!(worst < 1e-9, "{name}: {worst}");
        assert!((top - H * (1.0 - set)).abs() < 1e-9, "{name}: top {top}");
        // The knee: the stress at 5 % is elastic, the last push step is on the hardening line.
        let before = r.steps.iter().find(|s| (s.t_s - 5.0).abs() < 1e-9);
        if let Some(b) = before {
            assert!((b.plate_force_n / A - e * 0.05).abs() < 1e-9 * peak);
        }
    }
    // Axisymmetric: a cylinder R = 10 mm, H = 15 mm.
    let radius = RADIUS;
    let mut p = cylinder(material(Rheology::Elastic { e_mpa: e }, nu), uniaxial(waypoints, 15.0, 25.0), slider);
    p.markers = vec![MarkerRequest { name: "top".into(), position: vec![0.0, H], times: vec![25.0] }];
    let r = press::simulate(&p, &fixed(1.0), &mut |_| {}).unwrap();
    let area = std::f64::consts::PI * radius * radius;
    let worst = largest_stress_error(&r, &p.protocol, area, 15.0, peak, |d| closed(d / H));
    let top = r.markers[0].samples[0].1[1];
    println!("axisymmetric: largest stress error {worst:.2e}; top {top:.12}");
    assert!(worst < 1e-9, "axisymmetric: {worst}");
    assert!((top - H * (1.0 - set)).abs() < 1e-9, "axisymmetric: top {top}");
}

/// The slider on the seed's five-element material: a knee in the push force
/// (equal to the baseline at the step ends before the stress reaches sigma_y,
/// below it from there on; inside a yielding step the force is the chain's
/// closed form for the step's strain, an O(dt) interpolation), a larger permanent set than the baseline's, and the same
/// set whatever the hold time adds to it: the slider's share (final height,
/// slider minus baseline) changes by less than 5 % between a 10 s and a 60 s hold
/// while the baseline's own set grows by more than that.
#[test]
fn slider_signature_on_the_seed_material() {
    let m = Material::seed_mat1_force();
    let run = |hold: f64, effects: Effects| {
        let waypoints = vec![[0.0, 0.0], [10.0, 1.5], [10.0 + hold, 1.5]];
        let end = 10.0 + hold + 200.0;
        let mut p = block(m.clone(), uniaxial(waypoints, 10.0 + hold, end), effects);
        p.markers = vec![MarkerRequest { name: "top".into(), position: vec![W / 2.0, H], times: vec![end] }];
        let r = press::simulate(&p, &Settings { max_dt_s: Some(2.0), ..Settings::default() }, &mut |_| {}).unwrap();
        let top = r.markers[0].samples[0].1[1];
        (r, top)
    };
    let (base, base_top) = run(10.0, Effects::none());
    let peak = base.peak_force() / A;
    let sy = 0.5 * peak;
    let slider = effect(EffectId::PlasticSlider, &[sy, 0.02]);
    let (r, top) = run(10.0, slider.clone());
    // Step ends of the push (the same steps until the stress reaches sigma_y).
    let mut yielded = false;
    for (x, y) in base.steps.iter().zip(&r.steps).filter(|(x, _)| x.t_s <= 10.0) {
        let (b, s) = (x.plate_force_n / A, y.plate_force_n / A);
        if !yielded && b < sy {
            assert_eq!(x.t_s, y.t_s);
            assert!((s - b).abs() <= 1e-12 * peak, "t = {}: below yield {s} vs {b}", x.t_s);
        } else {
            yielded = true;
            assert!(s < b, "t = {}: the knee lowers the force: {s} vs {b}", x.t_s);
        }
    }
    assert!(yielded);
    let (base_long, base_long_top) = run(60.0, Effects::none());
    let (_, long_top) = run(60.0, slider);
    let (share, share_long) = (base_top - top, base_long_top - long_top);
    println!(
        "sets: baseline {:.4} / {:.4} mm (10 s / 60 s hold), slider's share {share:.4} / {share_long:.4} mm",
        H - base_top,
        H - base_long_top
    );
    assert!(share > 0.0 && share_long > 0.0);
    assert!((share_long / share - 1.0).abs() < 0.05, "{share} vs {share_long}");
    assert!((H - base_long_top) / (H - base_top) > 1.05);
    drop(base_long);
}

// ---------------------------------------------------------------------------------------------------------------
// bingham-dashpot.

/// A three-element chain (Voigt (E1, c1) + dashpot c3) with a Bingham dashpot
/// held at a fixed strain. 1D, while sigma > sigma_B: `e3' = (sigma - sigma_B)/c3`,
/// `sigma = E1 e1 + c1 e1'`, `e1 + e3 = const`, so
/// `sigma' (1 + c1/c3) = -E1 e3'`, i.e. the overstress decays as
/// `sigma - sigma_B ~ exp(-E1 t / (c1 + c3))` and the hold force tends to the
/// plateau `F_inf = sigma_B A` (a single exponential: it never crosses below).
///
/// In the discrete scheme the hold above the threshold is exact at any step: the
/// correction's rate `-sigma_B/c3` along the fixed uniaxial direction is constant,
/// so the chain's strain is linear in time and its kernel integrates it exactly.
/// Checked: the decay rate between 20 s and 60 s into the hold equals
/// `E1/(c1 + c3)` to 1e-10 at dt = 1, 0.5, 0.25 s (measured 1e-14); the plateau
/// after 22 relaxation times to 1e-8 relative (the remaining overstress is below
/// `exp(-22) (sigma_hold - sigma_B)/sigma_B` = 2e-10; measured 5e-11); the
/// push (where the threshold is crossed inside a step) and the hold against the
/// RK4 reference (step 1e-4 s), converging (orders > 0.8; error < 1 % of sigma_B
/// at dt = 0.25 s). Measured, errors at dt = 1, 0.5, 0.25 s: 2.26e-5, 3.4e-8,
/// 1.8e-8 MPa (orders 9.4 and 0.93; 4.5e-6 of sigma_B), with the correction on
/// the step's mean stress (`material::point`, module doc); against a reference
/// at 1e-5 s 2.26e-5, 2.3e-8, 6.6e-9 (orders 10.0 and 1.8: at 1e-4 s the
/// reference's own error shows at 0.25 s; at 1e-3 s, about 1.3e-7 MPa, it hid
/// the convergence). Backward Euler on the end stress would be first order,
/// 0.28 % of sigma_B at 0.25 s. The linear chain relaxes towards
/// zero instead.
#[test]
fn bingham_hold_relaxes_to_the_plateau() {
    let (e1, c1, c3, nu, sb) = (0.05, 0.2, 2.0, 0.3, 0.004);
    let lambda = e1 / (c1 + c3);
    let depth = 0.1 * H;
    let hold_end = 10.0 + 22.0 / lambda;
    let waypoints = vec![[0.0, 0.0], [10.0, depth], [hold_end, depth]];
    let rheology = Rheology::ThreeElement { e1_mpa: e1, c1_mpa_s: c1, c3_mpa_s: c3 };
    let bingham = effect(EffectId::BinghamDashpot, &[sb]);
    let p = block(material(rheology, nu), uniaxial(waypoints.clone(), hold_end, hold_end), bingham.clone());
    let dts = [1.0, 0.5, 0.25];
    for &dt in &dts {
        let r = press::simulate(&p, &fixed(dt), &mut |_| {}).unwrap();
        let at = |t: f64| r.steps.iter().find(|s| (s.t_s - t).abs() < 1e-9).unwrap().plate_force_n / A;
        let (s20, s60) = (at(30.0), at(70.0));
        assert!(s60 > sb, "still above the threshold at 60 s into the hold");
        let rate = ((s20 - sb) / (s60 - sb)).ln() / 40.0;
        let plateau = r.steps.last().unwrap().plate_force_n / (sb * A) - 1.0;
        println!(
            "dt = {dt}: hold-start stress {:.5} MPa, decay rate {rate:.6} vs {lambda:.6}, plateau {plateau:.2e}",
            at(10.0)
        );
        assert!(plateau.abs() < 1e-8, "dt = {dt}: plateau {plateau}");
        assert!((rate / lambda - 1.0).abs() < 1e-10, "dt = {dt}: rate {rate} vs {lambda}");
    }
    // The linear baseline relaxes towards zero instead.
    let base = block(material(rheology, nu), uniaxial(waypoints, hold_end, hold_end), Effects::none());
    let r = press::simulate(&base, &fixed(1.0), &mut |_| {}).unwrap();
    assert!(r.steps.last().unwrap().plate_force_n / A < 1e-3 * sb);
    // Against the RK4 reference over the push and 60 s of hold.
    let chain = Chain1d { e1, c1, c3, flow: Flow::Bingham { threshold: sb } };
    let short = vec![[0.0, 0.0], [10.0, depth], [70.0, depth]];
    let times: Vec<f64> = (1..=70).map(f64::from).collect();
    let (errors, orders) = convergence(&chain, nu, &short, 70.0, &bingham, &times, &dts, 1e-4);
    println!("bingham vs 1D reference: errors {errors:?} MPa, orders {orders:.3?}");
    assert!(orders.iter().all(|&o| o > 0.8), "{orders:?}");
    assert!(errors[2] < 0.01 * sb, "{errors:?}");
}

// ---------------------------------------------------------------------------------------------------------------
// stress-thinning.

/// The Cross law `c3(sigma) = c3_0 / (1 + (sigma / sigma_c)^m)` on a three-element
/// chain against the RK4 reference (push to 10 % in 10 s, hold to 60 s): the
/// error falls at first order in dt (orders > 0.8; under 1 % of the peak at
/// dt = 0.25 s), for m = 1 and m = 2. Signature: the normalised relaxation
/// `F(t)/F(t_hold)` differs between 5 % and 10 % strain (by more than 1 % at 30 s
/// into the hold), while the linear chain's curves overlay (to 1e-9).
#[test]
fn stress_thinning_matches_the_1d_reference() {
    let (e1, c1, c3, nu) = (0.05, 0.2, 20.0, 0.3);
    let depth = 0.1 * H;
    let waypoints = vec![[0.0, 0.0], [10.0, depth], [60.0, depth]];
    let times: Vec<f64> = (1..=60).map(f64::from).collect();
    let dts = [1.0, 0.5, 0.25];
    for (inverse, exponent) in [(400.0, 1.0), (300.0, 2.0)] {
        let chain = Chain1d { e1, c1, c3, flow: Flow::Cross { inverse, exponent } };
        let effects = effect(EffectId::StressThinning, &[inverse, exponent]);
        let reference_peak = chain.integrate(&[[0.0, 0.0], [10.0, 0.1]], &[10.0], 1e-3)[0];
        let (errors, orders) = convergence(&chain, nu, &waypoints, 60.0, &effects, &times, &dts, 1e-3);
        println!("cross m = {exponent}: peak {reference_peak:.5} MPa, errors {errors:?} MPa, orders {orders:.3?}");
        assert!(orders.iter().all(|&o| o > 0.8), "{orders:?}");
        assert!(errors[2] < 0.01 * reference_peak, "{errors:?}");
    }
    let rheology = Rheology::ThreeElement { e1_mpa: e1, c1_mpa_s: c1, c3_mpa_s: c3 };
    let normalised = |strain: f64, effects: Effects| {
        let d = strain * H;
        let p = block(material(rheology, nu), uniaxial(vec![[0.0, 0.0], [10.0, d], [60.0, d]], 60.0, 60.0), effects);
        let r = press::simulate(&p, &fixed(0.5), &mut |_| {}).unwrap();
        let at = |t: f64| r.steps.iter().find(|s| (s.t_s - t).abs() < 1e-9).unwrap().plate_force_n;
        at(40.0) / at(10.0)
    };
    let thinning = effect(EffectId::StressThinning, &[400.0, 1.0]);
    let (low, high) = (normalised(0.05, thinning.clone()), normalised(0.1, thinning));
    let (low0, high0) = (normalised(0.05, Effects::none()), normalised(0.1, Effects::none()));
    println!("F(40)/F(10): thinning {low:.5} (5 %) vs {high:.5} (10 %); linear {low0:.9} vs {high0:.9}");
    assert!((low0 - high0).abs() < 1e-9);
    assert!(low - high > 0.01, "the higher strain relaxes faster: {low} vs {high}");
}

// ---------------------------------------------------------------------------------------------------------------
// dual-viscosity.

/// `c3` becomes `c3 exp(psi)` while unloading (`s . de < 0` per cell): a
/// three-element chain pushed to 10 % in 10 s, held 10 s, drawn back to 5 % in
/// 10 s with the plate attached. The push and hold equal the baseline (1e-12 of
/// the peak); the retraction matches the RK4 reference with first-order
/// convergence (orders > 0.8, under 1 % of the peak at dt = 0.25 s), for
/// psi = 1.5 (a stiffer unloading: the force falls more slowly than the
/// baseline's) and psi = -1.5.
#[test]
fn dual_viscosity_matches_the_1d_reference_in_unloading() {
    let (e1, c1, c3, nu) = (0.05, 0.2, 2.0, 0.3);
    let depth = 0.1 * H;
    let waypoints = vec![[0.0, 0.0], [10.0, depth], [20.0, depth], [30.0, 0.5 * depth]];
    let times: Vec<f64> = (1..=30).map(f64::from).collect();
    let dts = [1.0, 0.5, 0.25];
    let rheology = Rheology::ThreeElement { e1_mpa: e1, c1_mpa_s: c1, c3_mpa_s: c3 };
    let base = block(material(rheology, nu), uniaxial(waypoints.clone(), 30.0, 30.0), Effects::none());
    let baseline = press::simulate(&base, &fixed(0.5), &mut |_| {}).unwrap();
    let peak = baseline.peak_force() / A;
    for psi in [1.5, -1.5] {
        let effects = effect(EffectId::DualViscosity, &[psi]);
        let chain = Chain1d { e1, c1, c3, flow: Flow::Dual { log_ratio: psi } };
        let (errors, orders) = convergence(&chain, nu, &waypoints, 30.0, &effects, &times, &dts, 1e-3);
        println!("dual psi = {psi}: errors {errors:?} MPa, orders {orders:.3?}");
        assert!(orders.iter().all(|&o| o > 0.8), "{orders:?}");
        assert!(errors[2] < 0.01 * peak, "{errors:?}");
        let mut p = base.clone();
        p.effects = effects;
        let r = press::simulate(&p, &fixed(0.5), &mut |_| {}).unwrap();
        for (x, y) in baseline.steps.iter().zip(&r.steps) {
            if x.t_s <= 20.0 + 1e-9 {
                assert!((x.plate_force_n - y.plate_force_n).abs() <= 1e-12 * peak * A, "t = {}", x.t_s);
            }
        }
        let (b, d) = (baseline.steps.last().unwrap().plate_force_n, r.steps.last().unwrap().plate_force_n);
        assert!(if psi > 0.0 { d > b } else { d < b }, "psi = {psi}: {d} vs {b}");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// strain-stiffening.

/// An elastic chain with strain stiffening `a`, pushed to 20 % between
/// frictionless plates (uniaxial stress), held, released. The engine's law is
/// the tangent modulus `E0 (1 + a e_eq)` with `e_eq = |e|_C`, which is `|e_yy|` in
/// uniaxial stress, so `sigma = E0 (e + a e^2 / 2)` (compression positive) at
/// every step end, and no set after release. The update is a function of the
/// strain, so every step end matches at any step: forces to 1e-9 of the peak
/// (measured about 1e-14), fixed and adaptive steps, plane stress and
/// axisymmetric; softening (`a = -2`) the same way.
#[test]
fn strain_stiffening_matches_the_elastic_closed_form() {
    let (e, nu) = (0.05, 0.3);
    let depth = 0.2 * H;
    let waypoints = vec![[0.0, 0.0], [10.0, depth], [15.0, depth]];
    for a in [8.0, -2.0] {
        let closed = |strain: f64| e * (strain + 0.5 * a * strain * strain);
        let peak = closed(0.2).abs();
        let stiff = effect(EffectId::StrainStiffening, &[a]);
        for (name, settings) in [("fixed 1 s", fixed(1.0)), ("adaptive", Settings::default())] {
            let mut p = block(
                material(Rheology::Elastic { e_mpa: e }, nu),
                uniaxial(waypoints.clone(), 15.0, 25.0),
                stiff.clone(),
            );
            p.markers = vec![MarkerRequest { name: "top".into(), position: vec![W / 2.0, H], times: vec![25.0] }];
            let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
            let worst = largest_stress_error(&r, &p.protocol, A, 15.0, peak, |d| closed(d / H));
            let top = r.markers[0].samples[0].1[1];
            println!("a = {a}, {name}: largest stress error {worst:.2e} of the peak; top {top:.12}");
            assert!(worst < 1e-9, "a = {a}, {name}: {worst}");
            assert!((top - H).abs() < 1e-9, "a = {a}, {name}: top {top}");
        }
        let radius = RADIUS;
        let p = cylinder(material(Rheology::Elastic { e_mpa: e }, nu), uniaxial(waypoints.clone(), 15.0, 25.0), stiff);
        let r = press::simulate(&p, &fixed(1.0), &mut |_| {}).unwrap();
        let area = std::f64::consts::PI * radius * radius;
        let worst = largest_stress_error(&r, &p.protocol, area, 15.0, peak, |d| closed(d / H));
        println!("a = {a}, axisymmetric: largest stress error {worst:.2e}");
        assert!(worst < 1e-9, "axisymmetric: {worst}");
    }
}

/// A viscoelastic chain (three-element: Voigt (E1, c1) + dashpot c3) with strain
/// stiffening under a constant-rate push `e = v t` in uniaxial stress. The
/// chain acts on `psi(e) = e + a e^2 / 2` (Fung's quasi-linear form), so with the
/// relaxation function `G(t) = B2 delta(t) + A exp(-r t)` the stress is
/// `sigma(t) = B2 psi' + A v int_0^t exp(-r (t - s)) (1 + a v s) ds`
/// `= B2 v (1 + a v t) + A v [(1 - exp(-r t))/r + a v (t/r - (1 - exp(-r t))/r^2)]`.
/// The engine integrates the chain exactly for a chain strain linear in a step;
/// `psi` is quadratic in time, so the error is second order in dt: measured
/// orders between dt = 0.5, 0.25 and 0.125 s at least 1.8, and the error at
/// 0.125 s below 1e-4 of the peak stress.
#[test]
fn strain_stiffening_matches_the_viscoelastic_closed_form() {
    let (e1, c1, c3, nu, a) = (0.05, 0.4, 3.0, 0.3, 6.0);
    let rheology = Rheology::ThreeElement { e1_mpa: e1, c1_mpa_s: c1, c3_mpa_s: c3 };
    let k = rheology.relaxation();
    let (b2, amp, rate) = (k.viscous, k.amplitudes[0], k.rates[0]);
    let (push, depth) = (10.0, 0.2 * H);
    let v = depth / H / push;
    let closed = |t: f64| {
        let decay = -(-rate * t).exp_m1();
        b2 * v * (1.0 + a * v * t) + amp * v * (decay / rate + a * v * (t / rate - decay / (rate * rate)))
    };
    let peak = closed(push);
    let times: Vec<f64> = (1..=10).map(|i| i as f64).collect();
    let reference: Vec<f64> = times.iter().map(|&t| closed(t)).collect();
    let waypoints = vec![[0.0, 0.0], [push, depth]];
    let p = block(material(rheology, nu), uniaxial(waypoints, push, push), effect(EffectId::StrainStiffening, &[a]));
    assert_second_order(&p, &times, &reference, peak, "viscoelastic stiffening");
}

/// Runs `p` at fixed steps of 0.5, 0.25 and 0.125 s against the closed form
/// `reference` at `times`: the error (of `peak`) falls at order > 1.8 and ends
/// under 1e-4.
fn assert_second_order(p: &PlanePress, times: &[f64], reference: &[f64], peak: f64, label: &str) {
    let errors: Vec<f64> = [0.5, 0.25, 0.125]
        .iter()
        .map(|&dt| largest_difference(&press::simulate(p, &fixed(dt), &mut |_| {}).unwrap(), times, reference) / peak)
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("{label}: errors {errors:?} of the peak, orders {orders:.2?}");
    assert!(orders.iter().all(|&o| o > 1.8), "{orders:?}");
    assert!(errors[2] < 1e-4, "{errors:?}");
}

/// The signature on the seed's five-element material (uniaxial stress, push to
/// 20 % in 10 s): the force above the baseline's grows faster than the strain
/// (more than 3x from 10 % to 20 %, a quadratic term gives about 4x), so the push
/// force is convex where the baseline's is not; the relaxation during a hold is
/// the baseline's shape scaled by the strain level (quasi-linear): the hold force
/// of the effect over the baseline's is larger at 20 % than at 10 %.
#[test]
fn strain_stiffening_signature_on_the_seed_material() {
    let m = Material::seed_mat1_force();
    let run = |depth: f64, effects: Effects| {
        let waypoints = vec![[0.0, 0.0], [10.0, depth], [40.0, depth]];
        let p = block(m.clone(), uniaxial(waypoints, 40.0, 40.0), effects);
        press::simulate(&p, &fixed(0.5), &mut |_| {}).unwrap()
    };
    let force_at = |r: &PressResult, t: f64| r.steps.iter().find(|s| (s.t_s - t).abs() < 1e-9).unwrap().plate_force_n;
    let stiff = effect(EffectId::StrainStiffening, &[5.0]);
    let (base, with) = (run(0.2 * H, Effects::none()), run(0.2 * H, stiff.clone()));
    let extra = |t: f64| force_at(&with, t) - force_at(&base, t);
    println!("extra force at 10 % {:.4e} N, at 20 % {:.4e} N", extra(5.0), extra(10.0));
    assert!(extra(5.0) > 0.0 && extra(10.0) > 3.0 * extra(5.0));
    // Convex push: the second difference of the effect's force over the last half of the push.
    let f = [7.0, 8.5, 10.0].map(|t| force_at(&with, t));
    let fb = [7.0, 8.5, 10.0].map(|t| force_at(&base, t));
    assert!(f[2] - 2.0 * f[1] + f[0] > 0.0, "{f:?}");
    assert!(fb[2] - 2.0 * fb[1] + fb[0] < f[2] - 2.0 * f[1] + f[0], "{fb:?} vs {f:?}");
    // Strain-level dependence of the hold: ratio to the baseline at the end of the hold.
    let low = (run(0.1 * H, Effects::none()), run(0.1 * H, stiff));
    let ratio_low = force_at(&low.1, 40.0) / force_at(&low.0, 40.0);
    let ratio_high = force_at(&with, 40.0) / force_at(&base, 40.0);
    println!("hold-end force ratio: {ratio_low:.4} at 10 %, {ratio_high:.4} at 20 %");
    assert!(ratio_low > 1.0 && ratio_high > ratio_low + 0.5 * (ratio_low - 1.0));
}

// ---------------------------------------------------------------------------------------------------------------
// finite-strain.

/// The nominal uniaxial stress [MPa, compression positive] of the blended
/// Green-Lagrange kinematics at the axial stretch `1 + eps` (`eps = -d/H`) for an
/// axial 2nd Piola-Kirchhoff stress `s_yy`: `P = (1 + b eps) S_yy` (the axial row of
/// `B(u)^T S` with `S_xx = 0` on free lateral faces).
fn nominal(blend: f64, eps: f64, s_yy: f64) -> f64 {
    -(1.0 + blend * eps) * s_yy
}

/// Homogeneous large-strain compression of an elastic chain between frictionless
/// plates with free lateral faces (total Lagrangian, Saint Venant-Kirchhoff at
/// blend 1). With the axial stretch `lambda = 1 - d/H`, `eps = lambda - 1`, the
/// axial strain is `E_yy = eps + b eps^2/2`; the free faces carry `P_xx = F_xx S_xx
/// = 0`, so `S_xx = 0`, the 2nd Piola-Kirchhoff stress is uniaxial, `S_yy = E E_yy`
/// and `E_xx = -nu E_yy`; the force is `A0 (1 + b eps) E E_yy` (`A0 lambda (1 -
/// lambda^2)/2 E` at b = 1). The lateral stretch `1 + x` solves the scalar
/// `x + b x^2/2 = -nu E_yy`. Every step end matches (P1 cells are exact for a
/// homogeneous deformation): forces to 1e-9 of the peak, the lateral face to
/// 1e-9 mm, fixed and adaptive steps, blends 1 and 0.5, plane stress and
/// axisymmetric (a cylinder: A0 = pi R^2).
#[test]
fn finite_strain_matches_the_large_strain_closed_form() {
    let (e, nu) = (0.05, 0.3);
    let depth = 0.2 * H;
    let waypoints = vec![[0.0, 0.0], [10.0, depth]];
    for blend in [1.0, 0.5] {
        let force = |d: f64| {
            let eps = -d / H;
            nominal(blend, eps, e * (eps + 0.5 * blend * eps * eps))
        };
        let lateral = |d: f64| {
            let eps = -d / H;
            let e_xx = -nu * (eps + 0.5 * blend * eps * eps);
            // x + b x^2/2 = e_xx, the root near e_xx.
            2.0 * e_xx / (1.0 + (1.0 + 2.0 * blend * e_xx).sqrt())
        };
        let peak = force(depth);
        let effects = effect(EffectId::FiniteStrain, &[blend]);
        for (name, settings) in [("fixed 1 s", fixed(1.0)), ("adaptive", Settings::default())] {
            let mut p = block(
                material(Rheology::Elastic { e_mpa: e }, nu),
                uniaxial(waypoints.clone(), 10.0, 10.0),
                effects.clone(),
            );
            p.markers = vec![MarkerRequest { name: "side".into(), position: vec![W, H / 2.0], times: vec![10.0] }];
            let r = press::simulate(&p, &settings, &mut |_| {}).unwrap();
            let worst = largest_stress_error(&r, &p.protocol, A, f64::INFINITY, peak, force);
            let side = r.markers[0].samples[0].1[0];
            // The block stretches about its centre x = W/2 (frictionless plates: the centred hold).
            let expected = 0.5 * W + 0.5 * W * (1.0 + lateral(depth));
            println!("blend {blend}, {name}: largest stress error {worst:.2e} of the peak; side {side:.12} vs {expected:.12}");
            assert!(worst < 1e-9, "blend {blend}, {name}: {worst}");
            assert!((side - expected).abs() < 1e-9, "blend {blend}, {name}: side {side} vs {expected}");
        }
        let radius = RADIUS;
        let mut p =
            cylinder(material(Rheology::Elastic { e_mpa: e }, nu), uniaxial(waypoints.clone(), 10.0, 10.0), effects);
        p.markers = vec![MarkerRequest { name: "side".into(), position: vec![radius, H / 2.0], times: vec![10.0] }];
        let r = press::simulate(&p, &fixed(1.0), &mut |_| {}).unwrap();
        let area = std::f64::consts::PI * radius * radius;
        let worst = largest_stress_error(&r, &p.protocol, area, f64::INFINITY, peak, force);
        let side = r.markers[0].samples[0].1[0];
        let expected = radius * (1.0 + lateral(depth));
        println!("blend {blend}, axisymmetric: largest stress error {worst:.2e}; side {side:.12} vs {expected:.12}");
        assert!(worst < 1e-9, "axisymmetric: {worst}");
        assert!((side - expected).abs() < 1e-9, "axisymmetric: side {side} vs {expected}");
    }
}

/// A three-element chain (Voigt (E1, c1) + dashpot c3) under a constant-rate
/// push with full finite strain (b = 1). The chain acts on `E_yy(t) = eps + eps^2/2`,
/// `eps = -v t`, so `E_yy' = -v (1 - v t)` and with `G(t) = B2 delta(t) + A exp(-r t)`
/// `S_yy = -v [B2 (1 - v t) + A ((1 - exp(-r t))/r - v (t/r - (1 - exp(-r t))/r^2))]`,
/// and the nominal stress is `(1 + eps) S_yy`. `E_yy` is quadratic in time, so the
/// engine's error is second order in dt: orders at least 1.8 between 0.5, 0.25
/// and 0.125 s, and the error at 0.125 s below 1e-4 of the peak.
#[test]
fn finite_strain_matches_the_viscoelastic_closed_form() {
    let (e1, c1, c3, nu) = (0.05, 0.4, 3.0, 0.3);
    let rheology = Rheology::ThreeElement { e1_mpa: e1, c1_mpa_s: c1, c3_mpa_s: c3 };
    let k = rheology.relaxation();
    let (b2, amp, rate) = (k.viscous, k.amplitudes[0], k.rates[0]);
    let (push, depth) = (10.0, 0.2 * H);
    let v = depth / H / push;
    let closed = |t: f64| {
        let decay = -(-rate * t).exp_m1();
        let s_yy = -v * (b2 * (1.0 - v * t) + amp * (decay / rate - v * (t / rate - decay / (rate * rate))));
        nominal(1.0, -v * t, s_yy)
    };
    let peak = closed(push);
    let times: Vec<f64> = (1..=10).map(|i| i as f64).collect();
    let reference: Vec<f64> = times.iter().map(|&t| closed(t)).collect();
    let waypoints = vec![[0.0, 0.0], [push, depth]];
    let p = block(material(rheology, nu), uniaxial(waypoints, push, push), effect(EffectId::FiniteStrain, &[1.0]));
    assert_second_order(&p, &times, &reference, peak, "viscoelastic finite strain");
}

/// The signature on the seed's five-element material (uniaxial stress, push to
/// 20 % in 10 s, full finite strain): the Green-Lagrange (Saint Venant-Kirchhoff)
/// kinematics *soften* in compression, the force over the baseline's is about
/// `(1 + eps)(1 + eps/2)` (0.855 at 10 %, 0.72 at 20 %, elastic): its deficit grows
/// with the strain level (more than 1.8x from 10 % to 20 %), and the push force is
/// more concave than the baseline's over the last half of the push.
#[test]
fn finite_strain_signature_on_the_seed_material() {
    let m = Material::seed_mat1_force();
    let run = |effects: Effects| {
        let waypoints = vec![[0.0, 0.0], [10.0, 0.2 * H]];
        let p = block(m.clone(), uniaxial(waypoints, 10.0, 10.0), effects);
        press::simulate(&p, &fixed(0.5), &mut |_| {}).unwrap()
    };
    let force_at = |r: &PressResult, t: f64| r.steps.iter().find(|s| (s.t_s - t).abs() < 1e-9).unwrap().plate_force_n;
    let (base, with) = (run(Effects::none()), run(effect(EffectId::FiniteStrain, &[1.0])));
    let ratio = |t: f64| force_at(&with, t) / force_at(&base, t);
    println!("finite / small strain force: {:.4} at 10 %, {:.4} at 20 %", ratio(5.0), ratio(10.0));
    assert!(ratio(5.0) < 1.0 && 1.0 - ratio(10.0) > 1.8 * (1.0 - ratio(5.0)));
    let f = [7.0, 8.5, 10.0].map(|t| force_at(&with, t));
    let fb = [7.0, 8.5, 10.0].map(|t| force_at(&base, t));
    assert!(f[2] - 2.0 * f[1] + f[0] < fb[2] - 2.0 * fb[1] + fb[0], "{f:?} vs {fb:?}");
}

/// The real fungi-steak cylinder (R = 4 mm, H = 9 mm) of material `m`, pushed to
/// `depth` [mm] in 20 s by a plate with `plates` at both ends, meshed at `size` [mm].
fn fungi_cylinder(m: Material, size: f64, depth: f64, plates: Attachment, effects: Effects) -> AxisymmetricPress {
    let mut protocol = Protocol::ramp_hold_release(depth / 20.0, 20.0, 20.0, 20.0);
    protocol.waypoints = vec![[0.0, 0.0], [20.0, depth]];
    protocol.plate = plates;
    protocol.support = plates;
    let section = mesh::axisymmetric_section(4.0, 9.0, size, "m").unwrap();
    let mut p = AxisymmetricPress::new_axisymmetric(section, vec![m], protocol).unwrap();
    p.effects = effects;
    p
}

/// Past the Saint Venant-Kirchhoff limit: the fungi-steak cylinder pushed to
/// 50 % (the real first strokes, whose `finite-strain` candidate was not
/// evaluated: "element 46 inverted" at t = 18.09 s, 46 %).
///
/// The blended kinematics' nominal stress in uniaxial compression, `E (1 + b
/// eps)(eps + b eps^2/2)`, peaks at `eps = -(1 - 1/sqrt 3)/b` (42.3 % at b = 1,
/// 84.5 % at b = 1/2) and falls beyond it.
/// 1. Frictionless plates, elastic (E = 0.14 MPa, nu = 0.23), b = 1 and 1/2, to
///    50 %: the homogeneous branch, past the b = 1 limit too, matches the closed
///    form of `finite_strain_matches_the_large_strain_closed_form` at every step
///    end to 1e-9 of the force (measured: 1.1e-12 at b = 1/2, 1.8e-12 at b = 1):
///    the kinematics hold past the limit.
/// 2. Glued plates, the real first strokes' baseline fit (five-element), b = 1/2
///    (inside its limit), to 50 % at 0.225 mm/s: completes on 1, 0.5 and 0.25 mm
///    meshes and the peak force converges (measured: 0.60328, 0.60029 and
///    0.59856 N, order 0.79, last difference 2.9e-3 of the force); asserted: an
///    order above 0.5 (the glued corner's singularity keeps it below 2) and the
///    last difference below 1 %.
/// 3. Glued plates, b = 1, 1 mm: the compression localises past the limit (in
///    the bulk, not at a corner: the real first stroke's cell 51 of 72 at r = 1
///    to 2 mm, y = 6 to 7 mm) and a cell inverts: a typed `PressError::Inverted`
///    naming step, time and element, no panic (measured: step 65, t = 18.47 s,
///    46 %, element 51, volume ratio -8.8e-10). No mesh or step cures it: on the real stroke at 2, 1, 0.5 and 0.25 mm
///    it came at 47, 46, 40 and 32 % (earlier on finer meshes), after the
///    stepper's quarter-step retries; so the diagnosis takes its finite-strain
///    secant at a blend the trial supports (`calibrate::diagnosis::which`).
///
/// Not asserted, seen: elastic (E = 0.14 MPa) between glued plates at b = 1/2
/// on 0.25 mm cells, the corner cell at the support (its free node 0.25 mm up
/// the side) inverts at 47 % (t = 18.80 s): the side face folds onto the glued
/// plate, which a model without contact between side and plate cannot follow.
#[test]
fn finite_strain_on_the_fungi_cylinder_at_half_height() {
    let (e, depth, height) = (0.14, 4.5, 9.0);
    let area = std::f64::consts::PI * 16.0;
    for blend in [1.0, 0.5] {
        let elastic = material(Rheology::Elastic { e_mpa: e }, 0.23);
        let p = fungi_cylinder(elastic, 1.0, depth, Attachment::Frictionless, effect(EffectId::FiniteStrain, &[blend]));
        let r = press::simulate(&p, &fixed(1.0), &mut |_| {}).unwrap();
        let force = |d: f64| {
            let eps = -d / height;
            nominal(blend, eps, e * (eps + 0.5 * blend * eps * eps)) * area
        };
        let peak = force(depth);
        let worst = r
            .steps
            .iter()
            .map(|s| (s.plate_force_n - force(p.protocol.displacement(s.t_s))).abs() / peak)
            .fold(0.0, f64::max);
        let end = r.steps.last().unwrap().plate_force_n;
        println!(
            "frictionless, blend {blend}: {end:.6} N at 50 % (closed form {peak:.6} N), largest error {worst:.2e}"
        );
        assert!(worst < 1e-9, "frictionless, blend {blend}: {worst}");
    }

    // The real first strokes' baseline fit (VALIDATION.md, the gap diagnosis).
    let fit = Material::new(
        Rheology::FiveElement { e1_mpa: 0.1402, e2_mpa: 0.1253, c1_mpa_s: 1e-5, c2_mpa_s: 0.2702, c3_mpa_s: 1.0479 },
        0.228,
    )
    .unwrap();
    let sizes = [1.0, 0.5, 0.25];
    let peaks: Vec<f64> = sizes
        .iter()
        .map(|&h| {
            let p = fungi_cylinder(fit.clone(), h, depth, Attachment::Glued, effect(EffectId::FiniteStrain, &[0.5]));
            press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap().peak_force()
        })
        .collect();
    let order = ((peaks[0] - peaks[1]) / (peaks[1] - peaks[2])).log2();
    let last = (peaks[1] - peaks[2]).abs() / peaks[2];
    println!("glued, blend 0.5: peak forces {peaks:?} N at {sizes:?} mm, order {order:.2}, last difference {last:.2e}");
    assert!(order > 0.5 && last < 0.01, "{peaks:?}: order {order}, last difference {last}");

    let p = fungi_cylinder(fit, 1.0, depth, Attachment::Glued, effect(EffectId::FiniteStrain, &[1.0]));
    let err = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap_err();
    println!("glued, blend 1: {err}");
    assert!(matches!(err, PressError::Inverted { .. }), "{err}");
}

// ---------------------------------------------------------------------------------------------------------------
// Refusals.

/// What the material-point path does not do is refused, naming the key: a dashpot
/// law on an elastic chain, two material-point effects at once, sensitivities;
/// the dynamic and the seed's integrators. (With plate friction, a contact tool,
/// and with machine compliance, it runs.)
#[test]
fn material_point_refusals_name_the_key() {
    let elastic = material(Rheology::Elastic { e_mpa: 0.05 }, 0.3);
    let protocol = uniaxial(vec![[0.0, 0.0], [1.0, 1.5]], 1.0, 1.0);
    let p = block(elastic.clone(), protocol.clone(), effect(EffectId::BinghamDashpot, &[0.001]));
    let err = press::simulate(&p, &fixed(0.5), &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("bingham_threshold_MPa") && err.to_string().contains("c3"), "{err}");

    let both = effect(EffectId::PlasticSlider, &[0.01, 0.01]).with(EffectId::StressThinning, &[10.0, 1.0]).unwrap();
    let err = both.validate().unwrap_err();
    assert!(matches!(err, EffectError::Conflict { key: "thinning_inverse_stress_1_per_MPa", .. }), "{err}");

    let slider = effect(EffectId::PlasticSlider, &[0.01, 0.01]);
    let with_friction = slider.clone().with(EffectId::PlateFriction, &[0.3]).unwrap();
    // Plate friction (a friction contact tool) is not refused: it runs.
    let r = press::simulate(&block(elastic.clone(), protocol.clone(), with_friction), &fixed(0.5), &mut |_| {});
    assert!(r.as_ref().is_ok_and(|r| r.peak_force() > 0.0), "{:?}", r.err());
    // Machine compliance is not refused either (`tests/compliance.rs`): it runs.
    let with_compliance = slider.clone().with(EffectId::MachineCompliance, &[0.01]).unwrap();
    let r = press::simulate(&block(elastic.clone(), protocol.clone(), with_compliance), &fixed(0.5), &mut |_| {});
    assert!(r.as_ref().is_ok_and(|r| r.peak_force() > 0.0), "{:?}", r.err());

    let p = block(elastic, protocol, slider);
    let parameters = [SensitivityParameter { regions: vec![0], kind: press::ParameterKind::Rheology(0) }];
    let err = press::simulate_with_sensitivities(&p, &fixed(0.5), &parameters, &mut |_| {}).unwrap_err();
    assert!(matches!(err, PressError::Effect(EffectError::NoSensitivities { key: "plastic_yield_stress_MPa", .. })));
    for integrator in [Integrator::Dynamic, Integrator::Seed] {
        let settings = Settings { integrator, ..fixed(0.5) };
        let err = press::simulate(&p, &settings, &mut |_| {}).unwrap_err();
        assert!(matches!(err, PressError::BadSettings(_)), "{err}");
    }
}
