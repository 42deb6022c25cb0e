//! Benchmarks of the engine issue (criterion; `cargo bench -p wagashi-workspace-tests`).
//!
//! - `seed_mat1_glued_3d/N`: the seed's material 1 trial (Table I protocol, Table
//!   II x_force, glued plates) on 3D blocks of about N tetrahedra, end to end
//!   (problem setup, assembly, factorization, all steps). N = 10k and 100k by
//!   default; set `WAGASHI_BENCH_1M=1` to add the 1M case (minutes per sample).
//! - `scheme/fast` and `scheme/seed`: the default quasi-static scheme and the
//!   seed's explicit scheme on the same small 2D mesh and a shortened trial (push
//!   2 s, hold 4 s, recover 4 s) on which the explicit scheme finishes; their force
//!   curves agree within 0.5 % of the peak (tests/verification.rs), so the ratio of
//!   the two times is the speed ratio at equal force accuracy.
//!
//! Steps, factor size and free dofs are printed once per case on stderr; peak
//! memory comes from `examples/press_scaling.rs` (one process per size).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Integrator, PlanePress, Protocol, Settings, SolidPress};
use std::time::Duration;

fn size_for(cells: f64) -> f64 {
    (6.0 * 58.0 * 59.5 * 12.0 / cells).cbrt()
}

fn seed_trial(cells: f64) -> SolidPress {
    let m = mesh::block([58.0, 59.5, 12.0], size_for(cells), "mat1").unwrap();
    SolidPress::new_3d(m, vec![Material::seed_mat1_force()], Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0))
        .unwrap()
}

fn bench_blocks(c: &mut Criterion) {
    let mut group = c.benchmark_group("seed_mat1_glued_3d");
    group.sample_size(10).measurement_time(Duration::from_secs(20));
    let mut sizes = vec![1e4, 1e5];
    if std::env::var_os("WAGASHI_BENCH_1M").is_some() {
        sizes.push(1e6);
    }
    for n in sizes {
        let p = seed_trial(n);
        let r = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
        eprintln!(
            "seed_mat1_glued_3d: {} cells, {} free dofs, {} steps, {} factorizations, {} factor entries",
            p.mesh.num_cells(),
            r.num_free_dofs,
            r.steps.len(),
            r.num_factorizations,
            r.factor_nonzeros
        );
        group.bench_with_input(BenchmarkId::from_parameter(p.mesh.num_cells()), &n, |b, &n| {
            b.iter(|| {
                let p = seed_trial(n);
                press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap()
            })
        });
    }
    group.finish();
}

fn bench_schemes(c: &mut Criterion) {
    let m = mesh::rectangle(58.0, 59.5, 20.0, "mat1").unwrap();
    let mut p = PlanePress::new_2d(
        m,
        12.0,
        vec![Material::seed_mat1_force()],
        Protocol::ramp_hold_release(0.2, 2.0, 6.0, 10.0),
    )
    .unwrap();
    p.density_t_mm3 = 1.27e-9;
    let mut group = c.benchmark_group("scheme");
    group.sample_size(10).measurement_time(Duration::from_secs(30));
    let fast = Settings::default();
    let seed = Settings { integrator: Integrator::Seed, ..Settings::default() };
    let rf = press::simulate(&p, &fast, &mut |_| {}).unwrap();
    let rs = press::simulate(&p, &seed, &mut |_| {}).unwrap();
    eprintln!(
        "scheme: {} cells; fast {} steps; seed {} recorded samples",
        p.mesh.num_cells(),
        rf.steps.len(),
        rs.steps.len()
    );
    group.bench_function("fast", |b| b.iter(|| press::simulate(&p, &fast, &mut |_| {}).unwrap()));
    group.bench_function("seed", |b| b.iter(|| press::simulate(&p, &seed, &mut |_| {}).unwrap()));
    group.finish();
}

criterion_group!(benches, bench_blocks, bench_schemes);
criterion_main!(benches);
