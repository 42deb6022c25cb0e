//! # Scaling study: the seed's material 1 trial on ever larger 3D blocks
//!
//! What it shows: wall time, steps, factorizations, factor size and peak memory
//! of the default (quasi-static) engine on the seed's Table I protocol with glued
//! plates, for blocks of about the requested numbers of tetrahedra. The criterion
//! benchmarks (`cargo bench`) measure the same runs; this example is the quick way
//! to see one size, including the 1M case that takes minutes.
//!
//! Run: `cargo run --release -p wagashi-workspace-tests --example press_scaling -- 10000 100000`
//!
//! Steps: 1. pick the element size that gives about N cells on the 58 x 59.5 x 12 mm
//! block; 2. build the problem; 3. simulate; 4. print the figures and the peak
//! resident memory of the process (VmHWM).

use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Protocol, Settings, SolidPress};
use std::time::Instant;

/// Element size giving about `cells` Kuhn tetrahedra (6 per cube) on the block.
fn size_for(cells: f64) -> f64 {
    (6.0 * 58.0 * 59.5 * 12.0 / cells).cbrt()
}

fn peak_memory_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("VmHWM")).map(|l| l.to_string()))
        .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse::<f64>().ok()))
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() {
    let targets: Vec<f64> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let targets = if targets.is_empty() { vec![1e4, 1e5] } else { targets };
    println!("cells,size_mm,free_dofs,steps,factorizations,factor_nnz,setup_s,simulate_s,peak_force_N,peak_rss_MB");
    for n in targets {
        let t0 = Instant::now();
        let h = size_for(n);
        let m = mesh::block([58.0, 59.5, 12.0], h, "mat1").expect("mesh");
        let cells = m.num_cells();
        let p = SolidPress::new_3d(
            m,
            vec![Material::seed_mat1_force()],
            Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0),
        )
        .expect("problem");
        let setup = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let r = press::simulate(&p, &Settings::default(), &mut |_| {}).expect("simulation");
        let sim = t1.elapsed().as_secs_f64();
        println!(
            "{cells},{h:.4},{},{},{},{},{setup:.2},{sim:.2},{:.6},{:.0}",
            r.num_free_dofs,
            r.steps.len(),
            r.num_factorizations,
            r.factor_nonzeros,
            r.peak_force(),
            peak_memory_mb()
        );
    }
}
