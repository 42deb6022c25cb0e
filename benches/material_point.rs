//! The material-point path's cost (effects E1 to E6, `fem_core::effects`)
//! against the linear baseline (criterion; `cargo bench -p wagashi-workspace-tests
//! --bench material_point`).
//!
//! `material_point/<case>`: the seed's Table I trial (0.2 mm/s push for 28.87 s,
//! hold to 210.93 s, release, recovery to 400 s) with its material 1 (x_force) on a
//! plane-stress section of the seed's block (58 x 59.5 mm, 12 mm thick, about 1.7k
//! triangles), frictionless plate, glued floor, default settings. Cases:
//! `baseline` (no effect: the linear path), `slider` (sigma_y = half the baseline's
//! peak stress, H = 0.01 MPa), `bingham` (sigma_B = 0.3 of the peak), `thinning`
//! (1/sigma_c = 2/peak, m = 1), `dual` (psi = 1), `stiffening` (a = 8: moduli
//! up 80 % at the 10 % strain of the push), `finite` (blend 1: Green-Lagrange
//! strain, total Lagrangian). Steps and factorizations are
//! printed once per case on stderr. The problem is built inside each case, so a
//! filter (`-- baseline`) runs that case alone.

use criterion::{criterion_group, criterion_main, Criterion};
use fem_core::effects::{EffectId, Effects};
use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Attachment, PlanePress, Protocol, Settings};
use std::time::Duration;

fn trial(effects: Effects) -> PlanePress {
    let m = mesh::rectangle(58.0, 59.5, 2.0, "mat1").unwrap();
    let mut protocol = Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0);
    protocol.plate = Attachment::Frictionless;
    protocol.support = Attachment::Glued;
    let mut p = PlanePress::new_2d(m, 12.0, vec![Material::seed_mat1_force()], protocol).unwrap();
    p.effects = effects;
    p
}

/// The baseline's peak stress of this trial [MPa] (plate force over 58 x 12 mm^2).
fn peak_mpa() -> f64 {
    let r = press::simulate(&trial(Effects::none()), &Settings::default(), &mut |_| {}).unwrap();
    r.steps.iter().map(|s| s.plate_force_n).fold(0.0, f64::max) / (58.0 * 12.0)
}

fn case(c: &mut Criterion, name: &str, effects: impl Fn(f64) -> Effects) {
    let mut group = c.benchmark_group("material_point");
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    // Built (and described) once, on the first call: criterion calls the closure
    // once per warm-up and sampling pass, and only for the cases a filter selects.
    let mut prepared: Option<PlanePress> = None;
    group.bench_function(name, |b| {
        let p = prepared.get_or_insert_with(|| {
            let p = trial(effects(peak_mpa()));
            let r = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
            eprintln!(
                "material_point/{name}: {} cells, {} steps, {} factorizations",
                p.mesh.num_cells(),
                r.steps.len(),
                r.num_factorizations
            );
            p
        });
        b.iter(|| press::simulate(p, &Settings::default(), &mut |_| {}).unwrap())
    });
    group.finish();
}

fn bench(c: &mut Criterion) {
    let with = |id: EffectId, v: Vec<f64>| Effects::none().with(id, &v).unwrap();
    case(c, "baseline", |_| Effects::none());
    case(c, "slider", |peak| with(EffectId::PlasticSlider, vec![0.5 * peak, 0.01]));
    case(c, "bingham", |peak| with(EffectId::BinghamDashpot, vec![0.3 * peak]));
    case(c, "thinning", |peak| with(EffectId::StressThinning, vec![2.0 / peak, 1.0]));
    case(c, "dual", |_| with(EffectId::DualViscosity, vec![1.0]));
    case(c, "stiffening", |_| with(EffectId::StrainStiffening, vec![8.0]));
    case(c, "finite", |_| with(EffectId::FiniteStrain, vec![1.0]));
}

criterion_group!(benches, bench);
criterion_main!(benches);
