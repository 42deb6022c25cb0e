//! The engine's verification ladder beyond rung 1 (design.md 3.5; issue: engine
//! foundation, tests 2-6), plus determinism and failure reporting. Every test
//! states its tolerance and where it comes from.

use fem_core::assembly::{assemble_stiffness, CsrPattern, Topology};
use fem_core::element::{cell_geometry, unit_young_matrix, Formulation};
use fem_core::material::{Material, Rheology};
use fem_core::mesh::{self, Layer};
use fem_core::press::{
    self, Attachment, Integrator, MarkerRequest, PlanePress, PressError, PressResult, Protocol, Settings, SolidPress,
};
use fem_core::solve::ReducedSystem;
use proptest::prelude::*;

fn seed_protocol() -> Protocol {
    Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0)
}

fn mat1() -> Material {
    Material::seed_mat1_force()
}

fn mat2() -> Material {
    Material::new(
        Rheology::FiveElement { e1_mpa: 0.0454, e2_mpa: 0.0141, c1_mpa_s: 0.0115, c2_mpa_s: 0.1991, c3_mpa_s: 13.370 },
        0.3353,
    )
    .unwrap()
}

// ---------------------------------------------------------------------------
// Rung 2: patch test and rigid motions on whole, distorted meshes.

/// A structured block whose interior nodes are moved by up to 15 % of the spacing
/// along each axis: at most 0.26 of the spacing in norm, so two nodes together can
/// shrink a height by at most 0.52 < 0.707 (the smallest height of a Kuhn
/// tetrahedron) and no cell inverts.
fn distorted_block(jitter: &[f64]) -> fem_core::mesh::TetMesh {
    let mut m = mesh::block([3.0, 3.0, 3.0], 1.0, "m").unwrap();
    for (i, p) in m.nodes.iter_mut().enumerate() {
        let interior = p.iter().all(|&c| c > 1e-9 && c < 3.0 - 1e-9);
        if interior {
            for k in 0..3 {
                p[k] += 0.15 * jitter[(3 * i + k) % jitter.len()];
            }
        }
    }
    m.validate().unwrap();
    m
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]

    /// Constant strain is reproduced exactly: prescribe a linear field on the
    /// boundary of a distorted mesh; the interior solution is the same field
    /// (to 1e-10 of its magnitude: round-off of a well-conditioned solve).
    #[test]
    fn patch_test_reproduces_linear_fields(
        grad in prop::array::uniform9(-0.01f64..0.01),
        shift in prop::array::uniform3(-1.0f64..1.0),
        jitter in prop::collection::vec(-1.0f64..1.0, 64),
        nu in 0.0f64..0.49,
    ) {
        let m = distorted_block(&jitter);
        let topo = Topology::new(m.num_nodes(), &m.cells);
        let pat = CsrPattern::new(&topo, 3);
        let geo: Vec<_> = (0..m.num_cells()).map(|e| cell_geometry::<3, 4>(&m.cell_coordinates(e), 1.0).unwrap()).collect();
        let c = unit_young_matrix::<6>(Formulation::Solid, nu);
        let k = assemble_stiffness::<3, 4, 6>(&topo, &pat, &m.cells, &geo, &|_| Some(c));
        let field = |p: &[f64; 3]| -> [f64; 3] {
            std::array::from_fn(|i| shift[i] + (0..3).map(|j| grad[3 * i + j] * p[j]).sum::<f64>())
        };
        let boundary: std::collections::BTreeSet<u32> = m.boundary_facets().iter().flatten().copied().collect();
        let mut held = vec![false; pat.num_dofs()];
        let mut u = vec![0.0; pat.num_dofs()];
        for &n in &boundary {
            let f = field(&m.nodes[n as usize]);
            for k in 0..3 {
                held[3 * n as usize + k] = true;
                u[3 * n as usize + k] = f[k];
            }
        }
        let sys = ReducedSystem::new(&pat, &held, None).unwrap();
        let factor = sys.factor(&[(1.0, &k)], None).unwrap();
        let mut ku = vec![0.0; pat.num_dofs()];
        pat.mul_vec(&k, &u, &mut ku);
        let mut x: Vec<f64> = sys.dof_of_free.iter().map(|&d| -ku[d as usize]).collect();
        factor.solve_in_place(&mut x);
        let scale = grad.iter().fold(0.0f64, |a, b| a.max(b.abs())) * 3.0 + 1e-3;
        for (i, &d) in sys.dof_of_free.iter().enumerate() {
            let node = d as usize / 3;
            let want = field(&m.nodes[node])[d as usize % 3];
            prop_assert!((x[i] - want).abs() < 1e-10 * scale, "node {node}: {} vs {want}", x[i]);
        }
    }

    /// Rigid translations and infinitesimal rotations produce no force: K r = 0
    /// to 1e-12 of |K| |r| (round-off), in 2D and 3D.
    #[test]
    fn rigid_motions_give_no_force(
        t in prop::array::uniform3(-1.0f64..1.0),
        w in prop::array::uniform3(-0.1f64..0.1),
        jitter in prop::collection::vec(-1.0f64..1.0, 64),
        nu in -0.5f64..0.49,
    ) {
        let m = distorted_block(&jitter);
        let topo = Topology::new(m.num_nodes(), &m.cells);
        let pat = CsrPattern::new(&topo, 3);
        let geo: Vec<_> = (0..m.num_cells()).map(|e| cell_geometry::<3, 4>(&m.cell_coordinates(e), 1.0).unwrap()).collect();
        let k = assemble_stiffness::<3, 4, 6>(&topo, &pat, &m.cells, &geo, &|_| Some(unit_young_matrix::<6>(Formulation::Solid, nu)));
        let mut r = vec![0.0; pat.num_dofs()];
        for (n, p) in m.nodes.iter().enumerate() {
            let rot = [w[1] * p[2] - w[2] * p[1], w[2] * p[0] - w[0] * p[2], w[0] * p[1] - w[1] * p[0]];
            for k in 0..3 {
                r[3 * n + k] = t[k] + rot[k];
            }
        }
        let mut f = vec![0.0; pat.num_dofs()];
        pat.mul_vec(&k, &r, &mut f);
        let kmax = k.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let rmax = r.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let fmax = f.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        prop_assert!(fmax < 1e-12 * kmax * rmax * 30.0, "force {fmax} for |K| {kmax}, |r| {rmax}");

        // The same in 2D (plane stress) on a distorted rectangle.
        let mut m2 = mesh::rectangle(3.0, 3.0, 1.0, "m").unwrap();
        for (i, p) in m2.nodes.iter_mut().enumerate() {
            if p.iter().all(|&c| c > 1e-9 && c < 3.0 - 1e-9) {
                p[0] += 0.15 * jitter[(2 * i) % 64];
                p[1] += 0.15 * jitter[(2 * i + 1) % 64];
            }
        }
        let topo2 = Topology::new(m2.num_nodes(), &m2.cells);
        let pat2 = CsrPattern::new(&topo2, 2);
        let geo2: Vec<_> = (0..m2.num_cells()).map(|e| cell_geometry::<2, 3>(&m2.cell_coordinates(e), 2.0).unwrap()).collect();
        let k2 = assemble_stiffness::<2, 3, 3>(&topo2, &pat2, &m2.cells, &geo2, &|_| Some(unit_young_matrix::<3>(Formulation::PlaneStress { thickness_mm: 2.0 }, nu)));
        let r2: Vec<f64> = m2.nodes.iter().flat_map(|p| [t[0] - w[2] * p[1], t[1] + w[2] * p[0]]).collect();
        let mut f2 = vec![0.0; pat2.num_dofs()];
        pat2.mul_vec(&k2, &r2, &mut f2);
        let kmax2 = k2.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let fmax2 = f2.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        prop_assert!(fmax2 < 1e-12 * kmax2 * 30.0 * r2.iter().fold(0.0f64, |a, b| a.max(b.abs())));
    }
}

// ---------------------------------------------------------------------------
// Rung 3: glued plates converge under mesh refinement.

/// Force at the end of the push and the bulge of the material point at
/// (W, H/2) at the end of the hold, 2D plane stress, glued plates.
fn glued_2d(h: f64) -> (f64, f64) {
    let m = mesh::rectangle(58.0, 59.5, h, "mat1").unwrap();
    let mut p = PlanePress::new_2d(m, 12.0, vec![mat1()], seed_protocol()).unwrap();
    p.markers = vec![MarkerRequest { name: "mid".into(), position: vec![58.0, 29.75], times: vec![0.0, 210.93] }];
    let r = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
    let bulge = r.markers[0].samples[1].1[0] - 58.0;
    (r.bottom_force_at(28.87), bulge)
}

/// Observed order and the fine-grid GCI (Roache, safety factor 1.25) from three
/// grids refined by 2.
fn order_and_gci(coarse: f64, medium: f64, fine: f64) -> (f64, f64) {
    let p = ((coarse - medium) / (medium - fine)).abs().ln() / 2f64.ln();
    let gci = 1.25 * ((medium - fine) / fine).abs() / (2f64.powf(p) - 1.0);
    (p, gci)
}

#[test]
fn glued_plates_converge_under_refinement() {
    let (fc, bc) = glued_2d(4.0);
    let (fm, bm) = glued_2d(2.0);
    let (ff, bf) = glued_2d(1.0);
    let (pf, gci_f) = order_and_gci(fc, fm, ff);
    let (pb, gci_b) = order_and_gci(bc, bm, bf);
    eprintln!("force {fc:.6} {fm:.6} {ff:.6}: order {pf:.3}, GCI {gci_f:.2e}");
    eprintln!("bulge {bc:.6} {bm:.6} {bf:.6}: order {pb:.3}, GCI {gci_b:.2e}");
    // Monotone convergence. The glued corners are stress singularities, so the
    // force converges below the smooth-solution order 2 (measured 1.30); the
    // bulge is a displacement away from the corners (measured 2.44: P1
    // displacements at a point converge at order 2 or a little better).
    assert!(fc > fm && fm > ff, "force must decrease monotonically under refinement");
    assert!((1.0..2.2).contains(&pf), "force order {pf} outside [1.0, 2.2)");
    assert!((1.5..3.0).contains(&pb), "bulge order {pb} outside [1.5, 3.0)");
    assert!(gci_f < 5e-3, "force GCI {gci_f} not below 0.5 %");
    assert!(gci_b < 5e-3, "bulge GCI {gci_b} not below 0.5 %");
}

// ---------------------------------------------------------------------------
// Rung 4: the fast scheme against the seed's scheme.

fn max_force_gap(fast: &PressResult, seed: &PressResult, end: f64) -> f64 {
    let peak = fast.peak_force();
    let n = 2000;
    (1..=n)
        .map(|i| end * i as f64 / n as f64)
        .map(|t| (fast.bottom_force_at(t) - seed.bottom_force_at(t)).abs() / peak)
        .fold(0.0, f64::max)
}

/// A shortened seed-like trial (push 2 s, hold 4 s, recover 4 s) on a small 2D
/// mesh: the explicit reference needs about 4000 Runge-Kutta steps a second of
/// simulated time here, so the trial is short. Forces within 0.5 % of the peak
/// over the whole trial (the bar), uniform and layered.
#[test]
fn fast_scheme_matches_the_seed_scheme() {
    let protocol = Protocol::ramp_hold_release(0.2, 2.0, 6.0, 10.0);
    let uniform = mesh::rectangle(58.0, 59.5, 20.0, "mat1").unwrap();
    let layered = mesh::layered_rectangle(
        60.0,
        &[
            Layer { region: "mat1".into(), thickness_mm: 80.0 / 3.0 },
            Layer { region: "mat2".into(), thickness_mm: 80.0 / 3.0 },
            Layer { region: "mat1".into(), thickness_mm: 80.0 / 3.0 },
        ],
        20.0,
    )
    .unwrap();
    for (name, m, mats) in [("uniform", uniform, vec![mat1()]), ("layered", layered, vec![mat1(), mat2()])] {
        let mut p = PlanePress::new_2d(m, 12.0, mats, protocol.clone()).unwrap();
        p.density_t_mm3 = 1.27e-9; // 52.43 g over 58 x 59.5 x 12 mm (Table I)
        let fast = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
        let seed = press::simulate(&p, &Settings { integrator: Integrator::Seed, ..Settings::default() }, &mut |_| {})
            .unwrap();
        let gap = max_force_gap(&fast, &seed, 10.0);
        eprintln!("{name}: fast {} steps, largest gap {gap:.2e} of the peak", fast.steps.len());
        assert!(gap < 5e-3, "{name}: fast and seed schemes differ by {gap:e} of the peak");
    }
}

// ---------------------------------------------------------------------------
// Rung 6 (design.md): 2D plane stress against a thin 3D block, T/W = 0.05.

#[test]
fn plane_stress_matches_a_thin_block() {
    let (w, h, t) = (58.0, 59.5, 58.0 * 0.05);
    for contact in [Attachment::Frictionless, Attachment::Glued] {
        let mut protocol = seed_protocol();
        protocol.plate = contact;
        protocol.support = contact;
        let p2 =
            PlanePress::new_2d(mesh::rectangle(w, h, 2.0, "m").unwrap(), t, vec![mat1()], protocol.clone()).unwrap();
        let p3 = SolidPress::new_3d(mesh::block([w, h, t], 1.45, "m").unwrap(), vec![mat1()], protocol).unwrap();
        let r2 = press::simulate(&p2, &Settings::default(), &mut |_| {}).unwrap();
        let r3 = press::simulate(&p3, &Settings::default(), &mut |_| {}).unwrap();
        let mut worst: f64 = 0.0;
        for i in 1..=420 {
            let tt = 0.5 * i as f64;
            worst = worst.max((r2.bottom_force_at(tt) - r3.bottom_force_at(tt)).abs() / r3.peak_force());
        }
        eprintln!("{contact:?}: 2D vs thin 3D largest difference {worst:.3e} of the peak");
        // Frictionless: both are exactly uniaxial (1e-9). Glued: plane stress
        // misses the thin block's through-thickness restraint at the plates
        // (measured 0.94 %); the bar is 2 %.
        let bar = if contact == Attachment::Frictionless { 1e-9 } else { 2e-2 };
        assert!(worst < bar, "{contact:?}: {worst:e} >= {bar:e}");
    }
}

// ---------------------------------------------------------------------------
// The seed's qualitative claim: the four-element model "vibrates", the five does not.

/// Oscillation of the dynamic force about the quasi-static one over [0.5, 2] s
/// of a 0.2 mm/s push: (largest deviation / force at 2 s, sign changes).
fn oscillation(rheology: Rheology) -> (f64, usize) {
    let mut protocol = Protocol::ramp_hold_release(0.2, 2.0, 2.0, 2.0);
    protocol.waypoints = vec![[0.0, 0.0], [2.0, 0.4]];
    let m = mesh::rectangle(58.0, 59.5, 6.0, "m").unwrap();
    let mut p = PlanePress::new_2d(m, 12.0, vec![Material::new(rheology, 0.3746).unwrap()], protocol).unwrap();
    p.density_t_mm3 = 1.27e-9;
    // 5e-4 s resolves the first axial mode (period about 2H/c = 0.03 s for E2).
    let dynamic = Settings { integrator: Integrator::Dynamic, fixed_dt_s: Some(5e-4), ..Settings::default() };
    let dy = press::simulate(&p, &dynamic, &mut |_| {}).unwrap();
    let qs = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
    let dev: Vec<f64> =
        dy.steps.iter().filter(|s| s.t_s >= 0.5).map(|s| s.bottom_force_n - qs.bottom_force_at(s.t_s)).collect();
    let amplitude = dev.iter().fold(0.0f64, |a, b| a.max(b.abs())) / qs.bottom_force_at(2.0);
    let sign_changes = dev.windows(2).filter(|w| w[0] * w[1] < 0.0).count();
    (amplitude, sign_changes)
}

#[test]
fn four_element_vibrates_and_five_element_does_not() {
    let m1 = mat1().rheology;
    let Rheology::FiveElement { e1_mpa, e2_mpa, c1_mpa_s, c3_mpa_s, .. } = m1 else { unreachable!() };
    let (a4, n4) = oscillation(Rheology::FourElement { e1_mpa, c1_mpa_s, e2_mpa, c3_mpa_s });
    let (a5, n5) = oscillation(m1);
    eprintln!("four-element: amplitude {a4:.3e}, {n4} sign changes; five-element: {a5:.3e}, {n5}");
    // Measured: 4.1e-3 (109 sign changes) vs 3.3e-9 (none). The four-element series spring carries an
    // undamped axial wave; the five-element chain's instantaneous viscosity B2
    // damps it.
    assert!(a4 > 1e-3 && n4 >= 20, "four-element shows no vibration: {a4:e}, {n4} sign changes");
    assert!(a5 < 2e-4, "five-element vibrates: {a5:e}");
    assert!(a4 > 20.0 * a5);
}

/// Slow loading: the dynamic integrator tends to the quasi-static one once the
/// start-up transient has decayed (five-element; within 1e-4 of the peak).
#[test]
fn dynamic_tends_to_quasi_static() {
    let m = mesh::rectangle(58.0, 59.5, 10.0, "m").unwrap();
    let mut p = PlanePress::new_2d(m, 12.0, vec![mat1()], seed_protocol()).unwrap();
    p.density_t_mm3 = 1.27e-9;
    let dy =
        press::simulate(&p, &Settings { integrator: Integrator::Dynamic, ..Settings::default() }, &mut |_| {}).unwrap();
    let qs = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
    let peak = qs.peak_force();
    for t in [5.0, 28.87, 100.0, 210.93] {
        let gap = (dy.bottom_force_at(t) - qs.bottom_force_at(t)).abs() / peak;
        assert!(gap < 1e-4, "t = {t}: dynamic differs from quasi-static by {gap:e} of the peak");
    }
}

// ---------------------------------------------------------------------------
// Determinism, gravity, failure reporting.

/// The same run in a 1-thread and a 2-thread pool gives bit-identical results
/// (mesh large enough for the parallel paths and faer's supernodal solver).
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let m = mesh::layered_block(
        58.0,
        12.0,
        &[Layer { region: "mat1".into(), thickness_mm: 30.0 }, Layer { region: "mat2".into(), thickness_mm: 29.5 }],
        2.5,
    )
    .unwrap();
    assert!(m.num_cells() > 10_000);
    let p = SolidPress::new_3d(m, vec![mat1(), mat2()], seed_protocol()).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.steps.len(), b.steps.len());
    for (x, y) in a.steps.iter().zip(&b.steps) {
        assert_eq!(x.bottom_force_n.to_bits(), y.bottom_force_n.to_bits(), "t = {}", x.t_s);
    }
    for (x, y) in a.snapshots.iter().zip(&b.snapshots) {
        assert!(x.displacement.iter().zip(&y.displacement).all(|(p, q)| p.to_bits() == q.to_bits()));
    }
}

/// With gravity the bottom carries the plate force plus the weight (quasi-static
/// force balance, to 1e-9 of the weight).
#[test]
fn gravity_adds_the_weight_to_the_bottom() {
    let mut protocol = seed_protocol();
    protocol.gravity = true;
    let m = mesh::block([58.0, 59.5, 12.0], 10.0, "m").unwrap();
    let mut p = SolidPress::new_3d(m, vec![mat1()], protocol).unwrap();
    p.density_t_mm3 = 1.27e-9;
    let weight = 1.27e-9 * 58.0 * 59.5 * 12.0 * 9810.0;
    let r = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
    for s in r.steps.iter().filter(|s| s.t_s <= 210.93) {
        let balance = s.bottom_force_n - s.plate_force_n - weight;
        assert!(balance.abs() < 1e-9 * weight.max(1.0), "t = {}: {balance:e}", s.t_s);
    }
    // After release only the weight rests on the floor.
    let last = r.steps.last().unwrap();
    assert!((last.bottom_force_n - weight).abs() < 1e-6 * weight, "{} vs weight {weight}", last.bottom_force_n);
}

/// Pressing an elastic block beyond its height inverts cells: the run stops with
/// an error naming the step, the time and the element, and does not panic.
#[test]
fn inverted_elements_are_reported() {
    let mut protocol = Protocol::ramp_hold_release(10.0, 7.0, 7.0, 7.0);
    protocol.waypoints = vec![[0.0, 0.0], [7.0, 70.0]];
    let m = mesh::block([58.0, 59.5, 12.0], 15.0, "m").unwrap();
    let p =
        SolidPress::new_3d(m, vec![Material::new(Rheology::Elastic { e_mpa: 1.0 }, 0.3).unwrap()], protocol).unwrap();
    let err = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap_err();
    assert!(matches!(err, PressError::Inverted { .. }), "{err}");
    let text = err.to_string();
    assert!(text.contains("step") && text.contains("t =") && text.contains("element"), "{text}");
}

#[test]
fn bad_parameters_are_refused_with_their_name() {
    let bad = Material::new(
        Rheology::FiveElement { e1_mpa: 0.03, e2_mpa: 0.02, c1_mpa_s: 0.0, c2_mpa_s: 0.2, c3_mpa_s: 3.0 },
        0.3,
    );
    assert!(bad.unwrap_err().to_string().contains("c1"));
    let nu = Material::new(Rheology::Elastic { e_mpa: 1.0 }, 0.5);
    assert!(nu.unwrap_err().to_string().contains("poisson"));
    let m = mesh::block([10.0, 10.0, 10.0], 5.0, "m").unwrap();
    let mut protocol = seed_protocol();
    protocol.release_s = 10.0; // before the end of the push at 28.87 s
    let err = SolidPress::new_3d(m, vec![mat1()], protocol).unwrap_err();
    assert!(err.to_string().contains("release_s"), "{err}");
}

/// A node that belongs to no cell has no stiffness: the step matrix is singular
/// and the run stops with an error naming the step and the time, not a panic.
#[test]
fn a_singular_step_matrix_is_reported() {
    let mut m = mesh::block([10.0, 10.0, 10.0], 5.0, "m").unwrap();
    m.nodes.push([5.0, 5.0, 5.0]); // dangling: in no cell
    let p = SolidPress::new_3d(m, vec![mat1()], seed_protocol()).unwrap();
    let err = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap_err();
    let dangling = p.mesh.num_nodes() - 1;
    assert!(
        matches!(err, PressError::Singular { step: 1, node: Some(n), element: None, .. } if n == dangling),
        "{err}"
    );
    assert!(
        err.to_string().contains("step 1 at t = ") && err.to_string().contains(&format!("node {dangling}")),
        "{err}"
    );
}

/// Glued plates, one material: the field is not uniform (the block barrels), but
/// it separates in time, u = d(t) U(x), because every cell shares one relaxation
/// function. After release each free dof therefore recovers like the 1D chain, and
/// the top face (U_y = -1 there) stays flat and follows the closed-form uniaxial
/// recovery, to the step control's accuracy (rtol 1e-3: 1e-4 of H here).
#[test]
fn glued_block_recovers_like_the_chain() {
    use fem_core::analytic::uniaxial_recovery_strain;
    let h = 59.5;
    let m = mesh::block([58.0, h, 12.0], 6.0, "mat1").unwrap();
    let mut p = SolidPress::new_3d(m, vec![mat1()], seed_protocol()).unwrap();
    p.snapshot_times = vec![215.0, 250.0, 300.0];
    let r = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
    let strain: Vec<[f64; 2]> = seed_protocol().waypoints.iter().map(|w| [w[0], w[1] / h]).collect();
    let top = &p.mesh.node_sets["top"];
    for t in [215.0, 250.0, 300.0, 400.0] {
        let snap = r.snapshot_at(t).unwrap();
        let want = -h * uniaxial_recovery_strain(&mat1().rheology, &strain, 210.93, t);
        for &n in top {
            let uy = snap.displacement[3 * n as usize + 1];
            assert!((uy - want).abs() < 1e-4 * h, "t = {t}, node {n}: {uy} vs {want}");
            // Flat and unsheared: no lateral motion of the (formerly glued) top.
            assert!(
                snap.displacement[3 * n as usize].abs() < 1e-9 && snap.displacement[3 * n as usize + 2].abs() < 1e-9
            );
        }
    }
}
