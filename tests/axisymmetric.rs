//! Axisymmetric triangles (issue: "2D axisymmetric triangles ... verified against
//! the 3D cylinder within 1 %"). The specimen is the seed-sized gel cylinder of a
//! texture analyser, R = 4 mm, H = 9 mm, compressed 20 % (1.8 mm) in 10 s, held
//! 30 s, released at 40 s and left to recover until 100 s.
//!
//! - Frictionless plates: the homogeneous closed form, force and shape, to 1e-9.
//! - Glued plates: force curve and bulge against the 3D cylinder (`mesh::cylinder`)
//!   at the same element size, within 1 %.
//! - Glued plates: the observed order of the peak force under three refinements,
//!   against the corner singularity's prediction.
//! - Every integrator runs the axisymmetric problem unchanged; the axis holds;
//!   markers live in the section; bad meshes are refused.
//! - The cost ratio 3D / axisymmetric at equal accuracy is a measurement, not a
//!   check: `cargo run --release -p wagashi-workspace-tests --example axisymmetric_cost`
//!   (figures in BENCHMARKS.md).

use fem_core::analytic::{uniaxial_recovery_strain, uniaxial_stress};
use fem_core::element::Formulation;
use fem_core::material::{Material, Rheology};
use fem_core::mesh::{self, MeshError};
use fem_core::press::{
    self, Attachment, AxisymmetricPress, Integrator, MarkerRequest, PressError, PressResult, Protocol, Settings,
    SolidPress,
};

const R: f64 = 4.0;
const H: f64 = 9.0;
const PUSH_S: f64 = 10.0;
const RELEASE_S: f64 = 40.0;
const END_S: f64 = 100.0;
/// 20 % of H in 10 s.
const SPEED_MM_S: f64 = 0.2 * H / PUSH_S;

fn protocol(contact: Attachment) -> Protocol {
    let mut p = Protocol::ramp_hold_release(SPEED_MM_S, PUSH_S, RELEASE_S, END_S);
    p.plate = contact;
    p.support = contact;
    p
}

fn axisymmetric(h: f64, material: Material, contact: Attachment) -> AxisymmetricPress {
    let m = mesh::axisymmetric_section(R, H, h, "gel").unwrap();
    AxisymmetricPress::new_axisymmetric(m, vec![material], protocol(contact)).unwrap()
}

fn solid(h: f64, material: Material, contact: Attachment) -> SolidPress {
    SolidPress::new_3d(mesh::cylinder(R, H, h, "gel").unwrap(), vec![material], protocol(contact)).unwrap()
}

fn run_axisymmetric(p: &AxisymmetricPress) -> PressResult {
    press::simulate(p, &Settings::default(), &mut |_| {}).unwrap()
}

/// The largest radial displacement of the nodes at mid-height at time `t` [mm].
fn bulge_axisymmetric(p: &AxisymmetricPress, r: &PressResult, t: f64) -> f64 {
    let u = &r.snapshot_at(t).expect("snapshot kept").displacement;
    p.mesh
        .nodes
        .iter()
        .enumerate()
        .filter(|(_, q)| (q[1] - H / 2.0).abs() < 1e-9)
        .map(|(i, _)| u[2 * i])
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The largest radial displacement `u . (x, 0, z)/r` of the 3D nodes at mid-height [mm].
fn bulge_solid(p: &SolidPress, r: &PressResult, t: f64) -> f64 {
    let u = &r.snapshot_at(t).expect("snapshot kept").displacement;
    p.mesh
        .nodes
        .iter()
        .enumerate()
        .filter(|(_, q)| (q[1] - H / 2.0).abs() < 1e-9 && q[0].hypot(q[2]) > 1e-9)
        .map(|(i, q)| (u[3 * i] * q[0] + u[3 * i + 2] * q[2]) / q[0].hypot(q[2]))
        .fold(f64::NEG_INFINITY, f64::max)
}

fn elastic() -> Material {
    Material::new(Rheology::Elastic { e_mpa: 0.04 }, 0.3746).unwrap()
}

// ---------------------------------------------------------------------------
// (a) Frictionless plates: uniaxial stress, homogeneous strain.

/// The reaction equals `π R^2 s(t)` of the closed form (`analytic::uniaxial_stress`)
/// at every output time in push and hold, for both plates, within 1e-9 of the peak
/// (rung 1's bar: the homogeneous state lies in the P1 space and the time
/// integration is exact for a ramp-hold); the shape is `u_r = ν e r`, `u_y = -e y`
/// (e = d/H) at every node, within 1e-9 of `e R`, so the radial expansion of the
/// side is `ν e R`. Elastic and five-element, on a mesh of uneven intervals
/// (1.3 mm: 4 x 7 cells of 1 x 1.29 mm) and a fine one.
#[test]
fn frictionless_plates_give_the_homogeneous_closed_form() {
    let area = std::f64::consts::PI * R * R;
    let strain: Vec<[f64; 2]> = protocol(Attachment::Frictionless).waypoints.iter().map(|w| [w[0], w[1] / H]).collect();
    for h in [1.3, 0.25] {
        for material in [elastic(), Material::seed_mat1_force()] {
            let name = material.rheology.model_name();
            let p = axisymmetric(h, material.clone(), Attachment::Frictionless);
            let r = run_axisymmetric(&p);
            let peak = area * uniaxial_stress(&material.rheology, &strain, PUSH_S);
            let mut times: Vec<f64> = (1..=800).map(|i| i as f64 * 0.05).collect(); // to release
            times.extend(r.steps.iter().map(|s| s.t_s).filter(|&t| t <= RELEASE_S));
            let mut worst: f64 = 0.0;
            for t in times {
                let want = area * uniaxial_stress(&material.rheology, &strain, t);
                for got in [r.bottom_force_at(t), r.plate_force_at(t)] {
                    worst = worst.max((got - want).abs() / peak);
                }
            }
            assert!(worst < 1e-9, "h = {h}, {name}: force error {worst:e} of the peak");

            // The shape at release: homogeneous, radial expansion ν e R at the side.
            let e = 0.2;
            let nu = material.poisson;
            let u = &r.snapshot_at(RELEASE_S).unwrap().displacement;
            let mut shape_error: f64 = 0.0;
            for (i, q) in p.mesh.nodes.iter().enumerate() {
                shape_error = shape_error.max((u[2 * i] - nu * e * q[0]).abs()).max((u[2 * i + 1] + e * q[1]).abs());
            }
            assert!(shape_error < 1e-9 * e * R, "h = {h}, {name}: shape error {shape_error:e} mm");
            for (i, _) in p.mesh.nodes.iter().enumerate().filter(|(_, q)| q[0] == R) {
                let side = u[2 * i];
                assert!((side - nu * e * R).abs() < 1e-9 * nu * e * R, "h = {h}, {name}: expansion {side} mm");
            }

            // After release the five-element height follows the closed-form
            // recovery (rung 1's bar at default tolerances: 1e-4 of H).
            if !matches!(material.rheology, Rheology::Elastic { .. }) {
                let u = &r.snapshot_at(END_S).unwrap().displacement;
                let top = &p.mesh.node_sets["top"];
                let got = top.iter().map(|&i| u[2 * i as usize + 1]).sum::<f64>() / top.len() as f64;
                let want = -H * uniaxial_recovery_strain(&material.rheology, &strain, RELEASE_S, END_S);
                assert!((got - want).abs() < 1e-4 * H, "h = {h}: final height {got} mm, closed form {want} mm");
            }
        }
    }
}

// ---------------------------------------------------------------------------
// (b) Glued plates: the axisymmetric model against the 3D cylinder.

/// The seed's material 1 (five-element) glued between the plates, axisymmetric and
/// 3D at the same element size h = 0.5 mm (8 x 18 squares, 288 triangles; 8 rings
/// x 18 layers, 20 736 tetrahedra, about 1.2 s in release on 2 cores): the force
/// curve over the whole trial within 1 % of the 3D peak, the peak force and the
/// bulge (largest radial displacement at mid-height) at release and at the end
/// within 1 %. Measured (2 cores): force curve 0.12 % of the peak, peak 0.12 %,
/// bulges 0.013 %; at h = 0.25 mm the peak gap shrinks to 0.03 % and the bulge gap
/// to 0.001 % (15 s for the 3D run: not repeated here).
#[test]
fn glued_plates_match_the_3d_cylinder() {
    let h = 0.5;
    let pa = axisymmetric(h, Material::seed_mat1_force(), Attachment::Glued);
    let ra = run_axisymmetric(&pa);
    let ps = solid(h, Material::seed_mat1_force(), Attachment::Glued);
    let rs = press::simulate(&ps, &Settings::default(), &mut |_| {}).unwrap();

    let peak = rs.peak_force();
    let curve_gap = (0..=1000)
        .map(|i| i as f64 * END_S / 1000.0)
        .map(|t| (ra.bottom_force_at(t) - rs.bottom_force_at(t)).abs())
        .fold(0.0, f64::max)
        / peak;
    let peak_gap = (ra.peak_force() - peak).abs() / peak;
    eprintln!(
        "h = {h} mm: axisymmetric {} cells, 3D {} cells; peak {:.6} vs {peak:.6} N",
        pa.mesh.num_cells(),
        ps.mesh.num_cells(),
        ra.peak_force()
    );
    eprintln!("force curve gap {curve_gap:.3e} of the peak, peak gap {peak_gap:.3e}");
    assert!(curve_gap < 0.01, "force curves differ by {curve_gap:e} of the peak");
    assert!(peak_gap < 0.01, "peak forces differ by {peak_gap:e}");
    for t in [RELEASE_S, END_S] {
        let (ba, bs) = (bulge_axisymmetric(&pa, &ra, t), bulge_solid(&ps, &rs, t));
        let gap = (ba - bs).abs() / bs.abs();
        eprintln!("t = {t} s: bulge {ba:.6} vs {bs:.6} mm ({gap:.3e})");
        assert!(bs > 0.0 && gap < 0.01, "t = {t} s: bulges {ba} and {bs} mm differ by {gap:e}");
    }
}

// ---------------------------------------------------------------------------
// (c) Mesh convergence of the glued peak force.

/// The exponent λ of the displacement `u ~ ρ^λ` at a corner where a bonded face
/// meets a free face at 90° (Williams 1952, plane strain, the local state at the
/// circular edge of a glued cylinder): the root in (1/2, 1) of
/// `(3 - 4ν) sin^2(λ π/2) = 4 (1 - ν)^2 - λ^2` (λ = 0.711 for ν = 0.3).
fn bonded_free_corner_exponent(nu: f64) -> f64 {
    let f =
        |l: f64| (3.0 - 4.0 * nu) * (l * std::f64::consts::FRAC_PI_2).sin().powi(2) - 4.0 * (1.0 - nu).powi(2) + l * l;
    let (mut lo, mut hi) = (0.5, 1.0);
    assert!(f(lo) < 0.0 && f(hi) > 0.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Peak force of the glued cylinder, axisymmetric, on h = 0.5, 0.25, 0.125, 0.0625
/// mm (three refinements by 2): the force decreases monotonically (P1 is too
/// stiff) and its two observed orders lie in [1, 2λ + 0.1].
///
/// Why not 2: the glued rim is a bonded-free corner whose displacement goes as
/// ρ^λ, λ = 0.664 for ν = 0.3746 ([`bonded_free_corner_exponent`]). The reaction is
/// twice the strain energy over the plate displacement, and the energy error of P1
/// on uniform meshes goes as h^(2λ) = h^1.33 near such a corner. Measured: 1.17
/// then 1.20, rising towards 1.33 from below (pre-asymptotic). The bound 1 says
/// "clearly better than first order"; 2λ + 0.1 that nothing converges faster than
/// the singularity allows.
#[test]
fn glued_peak_force_converges_at_the_corner_singularity_rate() {
    let sizes = [0.5, 0.25, 0.125, 0.0625];
    let forces: Vec<f64> = sizes
        .iter()
        .map(|&h| run_axisymmetric(&axisymmetric(h, Material::seed_mat1_force(), Attachment::Glued)).peak_force())
        .collect();
    let lambda = bonded_free_corner_exponent(Material::seed_mat1_force().poisson);
    let orders: Vec<f64> = forces.windows(3).map(|f| ((f[0] - f[1]) / (f[1] - f[2])).log2()).collect();
    let p = orders[1];
    let extrapolated = forces[3] - (forces[2] - forces[3]) / (2f64.powf(p) - 1.0);
    let gci = 1.25 * ((forces[2] - forces[3]) / forces[3]).abs() / (2f64.powf(p) - 1.0);
    eprintln!("peak forces {forces:?} N, observed orders {orders:?}, 2 lambda = {:.3}", 2.0 * lambda);
    eprintln!("extrapolated {extrapolated:.6} N; fine-grid GCI {gci:.2e}");
    assert!((lambda - 0.664).abs() < 1e-3, "corner exponent {lambda}");
    assert!(forces.windows(2).all(|f| f[0] > f[1]), "the force must decrease under refinement: {forces:?}");
    for &order in &orders {
        assert!(
            (1.0..=2.0 * lambda + 0.1).contains(&order),
            "observed order {order} outside [1, {}]",
            2.0 * lambda + 0.1
        );
    }
    assert!(gci < 2e-3, "fine-grid GCI {gci:e} not below 0.2 %");
}

// ---------------------------------------------------------------------------
// (d) The generic integrators, the axis, markers and refusals.

/// The dynamic generalized-alpha scheme tends to the quasi-static one (slow
/// loading, 1e-4 of the peak, as for plane problems), and the seed's explicit
/// scheme matches it within 0.5 % of the peak on a short trial (push 2 s, hold
/// 2 s, recover 2 s, on a large coarse cylinder: the explicit reference is slow):
/// the integrators are generic over <D, N, S> and need nothing axisymmetric.
#[test]
fn every_integrator_runs_the_axisymmetric_problem() {
    let mut p = axisymmetric(1.5, Material::seed_mat1_force(), Attachment::Glued);
    p.density_t_mm3 = 1.05e-9;
    let qs = run_axisymmetric(&p);
    let dy =
        press::simulate(&p, &Settings { integrator: Integrator::Dynamic, ..Settings::default() }, &mut |_| {}).unwrap();
    for t in [2.0, PUSH_S, 25.0, RELEASE_S] {
        let gap = (dy.bottom_force_at(t) - qs.bottom_force_at(t)).abs() / qs.peak_force();
        assert!(gap < 1e-4, "t = {t}: dynamic differs from quasi-static by {gap:e} of the peak");
    }

    // The explicit scheme's stable step goes as density h^2 / B2: a 30 x 60 mm
    // cylinder on 15 mm cells keeps it near 1e-5 s (rung 4's 2D trial is as large).
    let mesh = mesh::axisymmetric_section(30.0, 60.0, 15.0, "gel").unwrap();
    let mut p = AxisymmetricPress::new_axisymmetric(
        mesh,
        vec![Material::seed_mat1_force()],
        Protocol::ramp_hold_release(0.2, 2.0, 4.0, 6.0),
    )
    .unwrap();
    p.density_t_mm3 = 1.05e-9;
    let qs = run_axisymmetric(&p);
    let seed =
        press::simulate(&p, &Settings { integrator: Integrator::Seed, ..Settings::default() }, &mut |_| {}).unwrap();
    let gap = (1..=600)
        .map(|i| i as f64 * 0.01)
        .map(|t| (seed.bottom_force_at(t) - qs.bottom_force_at(t)).abs())
        .fold(0.0, f64::max)
        / qs.peak_force();
    eprintln!("seed scheme: {} recorded steps, largest gap {gap:.2e} of the peak", seed.steps.len());
    assert!(gap < 5e-3, "seed and quasi-static schemes differ by {gap:e} of the peak");
}

/// The axis nodes keep `u_r = 0` exactly (before and after release, glued and
/// frictionless: no other pin is added, the frictionless problem is still
/// solvable); a marker is located in the section at (r, y) and follows the node
/// it sits on.
#[test]
fn the_axis_holds_and_markers_live_in_the_section() {
    for contact in [Attachment::Glued, Attachment::Frictionless] {
        let mut p = axisymmetric(0.5, Material::seed_mat1_force(), contact);
        p.markers = vec![MarkerRequest { name: "rim".into(), position: vec![R, H / 2.0], times: vec![0.0, RELEASE_S] }];
        let r = run_axisymmetric(&p);
        for t in [RELEASE_S, END_S] {
            let u = &r.snapshot_at(t).unwrap().displacement;
            assert!(p.mesh.node_sets["axis"].iter().all(|&i| u[2 * i as usize] == 0.0), "{contact:?}, t = {t}");
        }
        let rim = p.mesh.nodes.iter().position(|q| q[0] == R && (q[1] - H / 2.0).abs() < 1e-12).unwrap();
        let u = &r.snapshot_at(RELEASE_S).unwrap().displacement;
        let track = &r.markers[0].samples;
        assert_eq!(track[0], (0.0, vec![R, H / 2.0]));
        let want = [R + u[2 * rim], H / 2.0 + u[2 * rim + 1]];
        assert!((track[1].1[0] - want[0]).abs() < 1e-12 && (track[1].1[1] - want[1]).abs() < 1e-12, "{track:?}");
        assert!(track[1].1[0] > R, "the rim bulges out");
    }
}

/// Meshes that are not an axisymmetric section are refused with the reason.
#[test]
fn bad_axisymmetric_problems_are_refused() {
    let material = || vec![Material::seed_mat1_force()];
    let proto = || protocol(Attachment::Glued);
    // No `axis` set.
    let plain = mesh::rectangle(R, H, 1.0, "gel").unwrap();
    let err = AxisymmetricPress::new_axisymmetric(plain, material(), proto()).unwrap_err();
    assert_eq!(err, PressError::Mesh(MeshError::MissingSet("axis".into())));
    // Nodes at r < 0.
    let mut shifted = mesh::axisymmetric_section(R, H, 1.0, "gel").unwrap();
    shifted.nodes.iter_mut().for_each(|q| q[0] -= 1.0);
    let err = AxisymmetricPress::new_axisymmetric(shifted, material(), proto()).unwrap_err();
    assert!(matches!(&err, PressError::BadFormulation(m) if m.contains("r >= 0")), "{err}");
    // An axis node missing from the set.
    let mut partial = mesh::axisymmetric_section(R, H, 1.0, "gel").unwrap();
    partial.node_sets.get_mut("axis").unwrap().pop();
    let err = AxisymmetricPress::new_axisymmetric(partial, material(), proto()).unwrap_err();
    assert!(matches!(&err, PressError::BadFormulation(m) if m.contains("not in the node set `axis`")), "{err}");
    // A formulation that does not match the strain count.
    let mut p =
        AxisymmetricPress::new_axisymmetric(mesh::axisymmetric_section(R, H, 1.0, "gel").unwrap(), material(), proto())
            .unwrap();
    p.formulation = Formulation::PlaneStress { thickness_mm: 1.0 };
    let err = p.validate().unwrap_err();
    assert!(matches!(&err, PressError::BadFormulation(m) if m.contains("3 strain components")), "{err}");
}
