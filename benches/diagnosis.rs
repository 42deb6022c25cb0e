//! Benchmark of the gap diagnosis (issue: sim-to-real gap diagnosis, "Performance":
//! three trials with all twelve candidates on an axisymmetric or 2D model in at
//! most 2 minutes on this 2-core machine).
//!
//! The case is the real one: the shared fungi-steak double compressions
//! (../shared/data/real/fungi-steak, read from beside the checkout, never copied),
//! imported as `wagashi import rheometer --cylinder-radius-mm 4` does (first
//! stroke, glued plates, five-element material), calibrated on specimen 1 and validated on specimens 2
//! and 3, axisymmetric, with every candidate of the library (`--effects all`; the
//! ones the engine cannot run are listed as not evaluated and cost nothing).
//!
//! That campaign cannot run all twelve (its plates are glued and it gives no
//! `age_h`), so a second case is synthetic: three trials of the blind check's
//! 2D campaign (`calibrate::diagnosis::blind`, a null campaign of development
//! seed 101: frictionless plate, `age_h` given, issue-level sample scatter and
//! noise), diagnosed with the library's default options (4 starts, 5 mm
//! elements) and every candidate.
//!
//! One diagnosis takes seconds to tens of seconds, so the bench prints one timed
//! run of each case (with the verdict and how many candidates were evaluated)
//! before criterion's ten samples; `cargo bench -p wagashi-workspace-tests
//! --bench diagnosis -- none` prints those runs and skips the samples. Figures
//! in BENCHMARKS.md.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use calibrate::diagnosis::blind::{campaign_seed, default_options, generate, Case, Scatter, Truth, MARKER_SIGMA_MM};
use calibrate::diagnosis::{diagnose, DiagnosisOptions};
use criterion::{criterion_group, criterion_main, Criterion};
use wagashi_io::texture::{read_rheometer, to_bundle, ImportOptions};
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

/// The three first strokes as bundles in `dir` (calibration: specimen 1).
fn bundles(dir: &std::path::Path) -> Vec<Bundle> {
    (1..=3)
        .map(|i| {
            let name = format!("double-compression-slowest-inplane-{i}");
            let raw = read_rheometer(fungi().join(format!("{name}.txt"))).unwrap();
            let options = ImportOptions { model: Some(Model::FiveElement), ..ImportOptions::new(name.clone(), 4.0) };
            let trial = to_bundle(&raw, &options).unwrap();
            trial.write(dir.join(&name)).unwrap();
            read_bundle(dir.join(&name)).unwrap()
        })
        .collect()
}

fn run(all: &[Bundle]) -> calibrate::diagnosis::Diagnosis {
    let options = DiagnosisOptions { axisymmetric: true, ..DiagnosisOptions::default() };
    diagnose(&all[..1], &all[1..], &BTreeMap::new(), &options, &|_, _, _| {}).unwrap()
}

/// Three trials of a synthetic 2D null campaign (module docs).
fn synthetic() -> Vec<Bundle> {
    let case = Case { truth: Truth::Null, lambda: 0.0 };
    let generated = generate(&case, campaign_seed(101, 0), &Scatter::ISSUE, &default_options(101)).unwrap();
    generated.bundles.into_iter().take(3).collect()
}

fn run_synthetic(trials: &[Bundle]) -> calibrate::diagnosis::Diagnosis {
    let options =
        DiagnosisOptions { size_mm: Some(5.0), marker_sigma_mm: MARKER_SIGMA_MM, ..DiagnosisOptions::default() };
    diagnose(trials, &[], &BTreeMap::new(), &options, &|_, _, _| {}).unwrap()
}

fn report(name: &str, run: impl Fn() -> calibrate::diagnosis::Diagnosis) {
    let start = Instant::now();
    let d = run();
    eprintln!(
        "diagnosis/{name}: one run {:.1} s, verdict `{}`, {} candidates evaluated, {} not evaluated ({})",
        start.elapsed().as_secs_f64(),
        d.verdict.label,
        d.candidates.len(),
        d.not_evaluated.len(),
        d.not_evaluated.iter().map(|(e, _)| e.id()).collect::<Vec<_>>().join(", ")
    );
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let all = bundles(dir.path());
    let trials = synthetic();
    report("fungi_3_trials", || run(&all));
    report("synthetic_2d_3_trials", || run_synthetic(&trials));
    let mut group = c.benchmark_group("diagnosis");
    group.sample_size(10).measurement_time(Duration::from_secs(30));
    group.bench_function("fungi_3_trials", |b| b.iter(|| run(&all)));
    group.bench_function("synthetic_2d_3_trials", |b| b.iter(|| run_synthetic(&trials)));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
