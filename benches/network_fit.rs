//! The network model's identification (issue: network model, "Performance"): the
//! joint fit of the default network structure to the three shared fungi-steak
//! double compressions (../shared/data/real/fungi-steak, read from beside the
//! checkout, never copied), imported as `wagashi import rheometer --model network
//! --stroke all` does (frictionless contact plates), on the axisymmetric section,
//! with `wagashi fit`'s defaults: four starts, and one cell through each specimen
//! because every trial is homogeneous (`Bundle::homogeneous_size_mm`).
//!
//! `cargo bench --bench network_fit`; figures in BENCHMARKS.md. Target: at most
//! 60 s.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use calibrate::procedure::{run, FitReport, Procedure, ProcedureOptions};
use calibrate::trial::Campaign;
use criterion::{criterion_group, criterion_main, Criterion};
use wagashi_io::bundle::Contact;
use wagashi_io::texture::{read_rheometer, to_bundle, ImportOptions, StrokeChoice};
use wagashi_io::{read_bundle, Bundle, Model};

fn fungi() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/real/fungi-steak");
    assert!(
        dir.is_dir(),
        "{} is missing: this bench reads the shared measured data beside the checkout",
        dir.display()
    );
    dir
}

/// The three whole double compressions as network bundles in `dir`.
fn bundles(dir: &std::path::Path) -> Vec<Bundle> {
    (1..=3)
        .map(|i| {
            let name = format!("double-compression-slowest-inplane-{i}");
            let raw = read_rheometer(fungi().join(format!("{name}.txt"))).unwrap();
            let options = ImportOptions {
                model: Some(Model::Network),
                contact: Contact::Frictionless,
                stroke: StrokeChoice::All,
                ..ImportOptions::new(name.clone(), 4.0)
            };
            to_bundle(&raw, &options).unwrap().write(dir.join(&name)).unwrap();
            read_bundle(dir.join(&name)).unwrap()
        })
        .collect()
}

fn fit(all: &[Bundle]) -> (FitReport, usize) {
    let size: Option<Vec<f64>> = all.iter().map(|b| b.homogeneous_size_mm(true)).collect();
    let size = size.expect("homogeneous trials").into_iter().fold(0.0, f64::max);
    let campaign = Campaign::new(all, &BTreeMap::new(), Some(size), true).unwrap();
    let report = run(&campaign, Procedure::Joint, &ProcedureOptions::default(), &|_, _, _| {}).unwrap();
    (report, campaign.unknowns.len())
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let all = bundles(dir.path());
    let start = Instant::now();
    let (report, unknowns) = fit(&all);
    eprintln!(
        "network_fit/fungi_3_records: one run {:.1} s, {unknowns} unknowns, {} simulations, {} iterations",
        start.elapsed().as_secs_f64(),
        report.simulations,
        report.steps.iter().map(|s| s.iterations).sum::<usize>()
    );
    let mut group = c.benchmark_group("network_fit");
    group.sample_size(10).measurement_time(Duration::from_secs(60));
    group.bench_function("fungi_3_records", |b| b.iter(|| fit(&all)));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
