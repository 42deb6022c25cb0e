//! Identification benchmarks (issue: parameter identification): the five-parameter
//! force fit of the seed's material 1 trial (step 2 of the seed's procedure: E1,
//! E2, c1, c2, c3, nu held) in 2D (plane stress, 3 mm elements) and 3D (9,600
//! tetrahedra, 3 mm), from the same start, one start; and the same 2D fit with a
//! forward-difference Jacobian instead of the forward sensitivities.
//!
//! The `jacobian` group times one Jacobian of the same fit's residuals at the
//! start point, by the forward sensitivities (one run) and by forward differences
//! (six runs), after checking that the two agree (printed: the largest difference
//! relative to the column's largest entry).
//!
//! The "measured" trial is the engine's own (Table II) with 1 % force noise.
//! `cargo bench --bench fit`; figures in BENCHMARKS.md.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use calibrate::lsq::{levenberg_marquardt, EvalError, Evaluation, Fit, LeastSquares, Options};
use calibrate::trial::{Campaign, Channel, Objective};
use criterion::{criterion_group, criterion_main, Criterion};
use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, PlanePress, Protocol, Settings};
use nalgebra::DMatrix;
use wagashi_io::{read_bundle, MaterialSpec};

/// Writes the seed's material 1 trial, force only, with 1 % noise (the data from
/// a fine 2D run; the 3D fit then also absorbs the 2D-3D difference).
fn trial(dir: &Path, dimension: u32) {
    let protocol = Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0);
    let mesh = mesh::rectangle(58.0, 59.5, 1.5, "mat1").unwrap();
    let p = PlanePress::new_2d(mesh, 12.0, vec![Material::seed_mat1_force()], protocol).unwrap();
    let r = press::simulate(&p, &Settings { rtol: 1e-5, ..Settings::default() }, &mut |_| {}).unwrap();
    let peak = r.peak_force();
    let mut state = 12345u64;
    let mut force = String::from("t_s,force_N\n");
    for i in 0..=800 {
        let t = 400.0 * i as f64 / 800.0;
        // A uniform +-1.7 % (standard deviation 1 %) deterministic jitter.
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        let f = r.bottom_force_at(t) + if t > 0.0 { 0.01 * 3f64.sqrt() * 2.0 * u * peak } else { 0.0 };
        writeln!(force, "{t},{f}").unwrap();
    }
    let toml = format!(
        "format = \"wagashi-experiment/1\"\nname = \"mat1-bench\"\ndimension = {dimension}\n\n[specimen]\nshape = \"block\"\n\
size_mm = [58.0, 59.5, 12.0]\nmaterial = \"mat1\"\n\n[materials.mat1]\nmodel = \"five-element\"\npoisson = 0.3746\n\n\
[protocol]\ntool = \"plate\"\ntool_contact = \"glued\"\nsupport = \"glued\"\n\
waypoints = [[0.0, 0.0], [28.87, 5.774], [210.93, 5.774]]\nrelease_s = 210.93\nend_s = 400.0\n\n[data]\nforce = \"force.csv\"\n"
    );
    std::fs::write(dir.join("experiment.toml"), toml).unwrap();
    std::fs::write(dir.join("force.csv"), force).unwrap();
}

fn start() -> BTreeMap<String, MaterialSpec> {
    let toml = "[materials.mat1]\nmodel = \"five-element\"\nE1_MPa = 0.05\nE2_MPa = 0.03\nc1_MPa_s = 0.01\nc2_MPa_s = 0.5\nc3_MPa_s = 50.0\n";
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("start.toml"), toml).unwrap();
    wagashi_io::read_materials_file(dir.path().join("start.toml")).unwrap()
}

/// A forward-difference Jacobian (relative step 1e-6) around any problem.
struct ForwardDifferences<'a, P>(&'a P);

impl<P: LeastSquares> LeastSquares for ForwardDifferences<'_, P> {
    fn num_parameters(&self) -> usize {
        self.0.num_parameters()
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        let base = self.0.evaluate(x, false)?;
        let jacobian = if want_jacobian {
            let mut j = DMatrix::zeros(base.residuals.len(), x.len());
            for k in 0..x.len() {
                let mut xh = x.to_vec();
                let h = 1e-6 * x[k].abs().max(1e-12);
                xh[k] += h;
                let r = self.0.evaluate(&xh, false)?.residuals;
                for i in 0..r.len() {
                    j[(i, k)] = (r[i] - base.residuals[i]) / h;
                }
            }
            Some(j)
        } else {
            None
        };
        Ok(Evaluation { residuals: base.residuals, jacobian })
    }
}

fn force_fit(campaign: &Campaign, finite_differences: bool) -> Fit {
    let free: Vec<usize> = (0..campaign.unknowns.len()).filter(|&i| campaign.unknowns[i].key != "poisson").collect();
    let objective = Objective::new(campaign, free.clone(), campaign.values(), &[Channel::Force]);
    let x0: Vec<f64> = free.iter().map(|&i| campaign.values()[i]).collect();
    let specs = objective.specs();
    if finite_differences {
        levenberg_marquardt(&ForwardDifferences(&objective), &specs, &x0, &Options::default()).unwrap()
    } else {
        levenberg_marquardt(&objective, &specs, &x0, &Options::default()).unwrap()
    }
}

/// The five-parameter force objective of a campaign and its start point.
fn force_objective(campaign: &Campaign) -> (Objective<'_>, Vec<f64>) {
    let free: Vec<usize> = (0..campaign.unknowns.len()).filter(|&i| campaign.unknowns[i].key != "poisson").collect();
    let x0: Vec<f64> = free.iter().map(|&i| campaign.values()[i]).collect();
    (Objective::new(campaign, free, campaign.values(), &[Channel::Force]), x0)
}

/// The largest difference of two Jacobians relative to each column's largest entry.
fn jacobian_difference(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (0..a.ncols())
        .map(|k| {
            let scale = a.column(k).amax();
            (a.column(k) - b.column(k)).amax() / scale
        })
        .fold(0.0, f64::max)
}

fn bench(c: &mut Criterion) {
    let dir2 = tempfile::tempdir().unwrap();
    trial(dir2.path(), 2);
    let dir3 = tempfile::tempdir().unwrap();
    trial(dir3.path(), 3);
    let start = start();
    let c2 = Campaign::new(&[read_bundle(dir2.path()).unwrap()], &start, Some(3.0), false).unwrap();
    let c3 = Campaign::new(&[read_bundle(dir3.path()).unwrap()], &start, Some(3.0), false).unwrap();

    // Report the results once (what "at equal result" compares).
    let mut once = vec![("2D exact", &c2, false), ("2D forward differences", &c2, true), ("3D exact", &c3, false)];
    if std::env::var_os("WAGASHI_BENCH_FIT_3D").is_some() {
        once.push(("3D forward differences", &c3, true));
    }
    for (name, campaign, fd) in once {
        let before = campaign.simulations();
        let t = std::time::Instant::now();
        let fit = force_fit(campaign, fd);
        eprintln!(
            "{name}: {:.2} s, objective {:.6e}, {} iterations, {} simulations, stop: {}, x = {:?}",
            t.elapsed().as_secs_f64(),
            fit.objective,
            fit.iterations,
            campaign.simulations() - before,
            fit.stop,
            fit.x
        );
    }

    // One Jacobian each way: the same matrix first, then the times.
    let mut cases = vec![("2D", &c2)];
    if std::env::var_os("WAGASHI_BENCH_FIT_3D").is_some() {
        cases.push(("3D 9600 tets", &c3));
    }
    let mut g = c.benchmark_group("jacobian");
    g.sample_size(10);
    for (name, campaign) in cases {
        let (objective, x0) = force_objective(campaign);
        let exact = objective.evaluate(&x0, true).unwrap().jacobian.unwrap();
        let fd = ForwardDifferences(&objective).evaluate(&x0, true).unwrap().jacobian.unwrap();
        eprintln!(
            "{name}: Jacobians differ by {:.2e} of each column's largest entry",
            jacobian_difference(&exact, &fd)
        );
        g.bench_function(format!("mat1 five parameters, {name}, sensitivities"), |b| {
            b.iter(|| objective.evaluate(&x0, true).unwrap())
        });
        g.bench_function(format!("mat1 five parameters, {name}, forward differences"), |b| {
            b.iter(|| ForwardDifferences(&objective).evaluate(&x0, true).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group("fit");
    g.sample_size(10);
    g.bench_function("mat1 five-parameter force fit, 2D, sensitivities", |b| b.iter(|| force_fit(&c2, false)));
    g.bench_function("mat1 five-parameter force fit, 2D, forward differences", |b| b.iter(|| force_fit(&c2, true)));
    if std::env::var_os("WAGASHI_BENCH_FIT_3D").is_some() {
        g.bench_function("mat1 five-parameter force fit, 3D 9600 tets, sensitivities", |b| {
            b.iter(|| force_fit(&c3, false))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
