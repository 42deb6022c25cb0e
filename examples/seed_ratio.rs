//! # Speed ratio: the fast scheme against the seed's own scheme, full trial
//!
//! What it shows: the wall time of the default quasi-static scheme and of the
//! seed's explicit scheme (eq. 8: dynamics, constraint stabilisation with psi =
//! 2000, explicit Runge-Kutta) on the seed's whole material 1 trial (push 28.87 s,
//! hold to 210.93 s, recover to 400 s) in 2D, on the coarsest mesh (2 x 3 quads)
//! where the explicit scheme finishes in minutes, and how far apart their force
//! curves are. The criterion benchmark `scheme/*` measures a shortened trial.
//!
//! Run: `cargo run --release -p wagashi-workspace-tests --example seed_ratio`
//!
//! Steps: 1. build the 2D problem with the seed's density (52.43 g in 58 x 59.5 x
//! 12 mm); 2. run both schemes; 3. print the times, the ratio, and the largest force
//! difference over the trial relative to the peak.

use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Integrator, PlanePress, Protocol, Settings};
use std::time::Instant;

fn main() {
    let m = mesh::rectangle(58.0, 59.5, 30.0, "mat1").expect("mesh");
    let mut p = PlanePress::new_2d(
        m,
        12.0,
        vec![Material::seed_mat1_force()],
        Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0),
    )
    .expect("problem");
    p.density_t_mm3 = 52.43e-6 / (58.0 * 59.5 * 12.0); // 52.43 g = 52.43e-6 t over the block volume [mm^3]
    let t0 = Instant::now();
    let fast = press::simulate(&p, &Settings::default(), &mut |_| {}).expect("fast");
    let fast_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let seed = press::simulate(&p, &Settings { integrator: Integrator::Seed, ..Settings::default() }, &mut |_| {})
        .expect("seed");
    let seed_s = t1.elapsed().as_secs_f64();
    let peak = fast.peak_force();
    let (gap, at) = (1..=8000)
        .map(|i| 400.0 * i as f64 / 8000.0)
        .map(|t| ((fast.bottom_force_at(t) - seed.bottom_force_at(t)).abs() / peak, t))
        .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a });
    println!("cells {}, fast {fast_s:.4} s ({} steps), seed {seed_s:.1} s, ratio {:.0}, largest force gap {gap:.2e} of the peak (at t = {at} s)",
        p.mesh.num_cells(), fast.steps.len(), seed_s / fast_s);
}
