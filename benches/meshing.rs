//! Benchmarks of the conforming mesher (criterion;
//! `cargo bench -p wagashi-workspace-tests --bench meshing`).
//!
//! - `delaunay/random_100k`: the Delaunay tetrahedralization of 100 000 uniform
//!   random points in the unit cube (BRIO/Hilbert order, exact perturbed predicates).
//! - `delaunay/grid_46`: a 46^3 grid (97 336 points, every cube's corners
//!   cospherical): the fully degenerate case, decided by the perturbation.

use criterion::{criterion_group, criterion_main, Criterion};
use meshing::conforming::Delaunay;
use std::time::Duration;

fn random_points(n: usize) -> Vec<[f64; 3]> {
    let mut s = 0x1234_5678_u64;
    let mut next = || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n).map(|_| [next(), next(), next()]).collect()
}

fn delaunay(c: &mut Criterion) {
    let mut g = c.benchmark_group("delaunay");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    let random = random_points(100_000);
    g.bench_function("random_100k", |b| b.iter(|| Delaunay::new(&random).unwrap().finite_tets().count()));
    let n = 46;
    let grid: Vec<[f64; 3]> =
        (0..n * n * n).map(|i| [(i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64]).collect();
    g.bench_function("grid_46", |b| b.iter(|| Delaunay::new(&grid).unwrap().finite_tets().count()));
    g.finish();
}

criterion_group!(benches, delaunay);
criterion_main!(benches);
