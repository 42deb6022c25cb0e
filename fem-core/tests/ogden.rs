//! Ogden's equilibrium energy on the Newton path against a closed form written
//! here in principal stretches.

use fem_core::material::network::{Energy, Equilibrium, Network};
use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Attachment, Protocol, Settings, SolidPress};

/// Uniaxial stress of the compressible Ogden energy
/// `sum_p 2 mu_p / alpha_p^2 sum_i (lbar_i^alpha_p - 1) + K/2 (J - 1)^2` at the
/// axial stretch `lambda`: the principal Kirchhoff stresses
/// `tau_i = sum_p 2 mu_p / alpha_p (lbar_i^alpha_p - mean_j lbar_j^alpha_p) + K J (J - 1)`
/// from the energy's derivative by the principal stretches; the lateral
/// stretch solves `tau_lateral = 0` by bisection; the nominal axial stress is
/// returned.
fn ogden_uniaxial(terms: &[(f64, f64)], kappa: f64, lambda: f64) -> f64 {
    let tau = |l: f64, axial: bool| {
        let j = lambda * l * l;
        let bar = |x: f64| x * j.powf(-1.0 / 3.0);
        let mut t = kappa * j * (j - 1.0);
        for &(alpha, mu) in terms {
            let (a, b) = (bar(lambda).powf(alpha), bar(l).powf(alpha));
            let mean = (a + 2.0 * b) / 3.0;
            t += 2.0 * mu / alpha * (if axial { a } else { b } - mean);
        }
        t
    };
    let (mut lo, mut hi) = (0.5, 3.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if tau(mid, false) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    tau(0.5 * (lo + hi), true) / lambda
}

/// A block of a three-term Ogden material (a stiffening, a softening and a
/// mild term) between frictionless plates, pushed to 50 %: homogeneous, so the
/// force equals the closed form at every step end (1e-8 of the peak).
#[test]
fn an_ogden_block_in_uniaxial_compression_follows_the_closed_form_to_50_percent() {
    let (e, nu) = (0.03, 0.45);
    let (alpha, share) = ([6.0, -2.0, 1.5], [0.6, 0.3, 0.1]);
    let net = Network::new(nu).with_equilibrium(Equilibrium {
        energy: Energy::Ogden { alpha, share },
        e_mpa: e,
        mullins: None,
    });
    let mu = e / (2.0 * (1.0 + nu));
    let kappa = e / (3.0 * (1.0 - 2.0 * nu));
    let terms: Vec<(f64, f64)> = alpha.iter().zip(share).map(|(&a, s)| (a, s * mu)).collect();
    let h = 10.0;
    let problem = SolidPress::new_3d(
        mesh::block([12.0, h, 8.0], 4.0, "m").unwrap(),
        vec![Material::network(net).unwrap()],
        Protocol {
            waypoints: vec![[0.0, 0.0], [10.0, 5.0]],
            release_s: 10.0,
            end_s: 10.0,
            plate: Attachment::Frictionless,
            support: Attachment::Frictionless,
            gravity: false,
        },
    )
    .unwrap();
    let result = press::simulate(&problem, &Settings::default(), &mut |_| {}).unwrap();
    let area = 12.0 * 8.0;
    let peak = ogden_uniaxial(&terms, kappa, 0.5).abs() * area;
    let mut worst: f64 = 0.0;
    for s in &result.steps {
        let lambda = 1.0 - problem.protocol.displacement(s.t_s) / h;
        let want = -ogden_uniaxial(&terms, kappa, lambda) * area;
        worst = worst.max((s.bottom_force_n - want).abs() / peak);
        worst = worst.max((s.plate_force_n - want).abs() / peak);
    }
    eprintln!("Ogden uniaxial: {} steps, worst force error {worst:.3e} of the peak {peak:.5} N", result.steps.len());
    assert!(worst < 1e-8, "worst {worst:.3e}");
}
