//! Benchmarks of the contact issue (criterion;
//! `cargo bench -p wagashi-workspace-tests --bench contact`).
//!
//! - `plate_step/{constrained,tool,frictionless_tool}`: the engine issue's plate
//!   case (the seed's material 1 trial, glued plate and floor) on a 3D block of
//!   about 100k tetrahedra, shortened to its push (28.87 s) with 20 fixed steps,
//!   once with the constrained plate, once with the plate as a glued contact tool
//!   and once as a frictionless one. The ratio of the times is the cost contact
//!   adds per step (same steps; the tools' held dofs are eliminated exactly, one
//!   factorization and one solve per step).
//! - `sphere_indentation`: a frictionless rigid sphere (R = 20 mm) pressed 2 mm
//!   into an elastic block of about 100k tetrahedra, glued on the floor, end to end.
//!
//! Steps, solves and factorizations are printed once per case on stderr. The
//! sphere case also prints one timed run before criterion's samples: at 100k tets
//! ten samples take long on the shared machine, so BENCHMARKS.md records that run
//! (`cargo bench -p wagashi-workspace-tests --bench contact -- plate_step` prints
//! it and skips the sphere's samples).

use criterion::{criterion_group, criterion_main, Criterion};
use fem_core::material::{Material, Rheology};
use fem_core::mesh;
use fem_core::press::{self, Protocol, Settings, SolidPress, Tool, ToolContact, ToolShape};
use std::time::Duration;

const SIZE: [f64; 3] = [58.0, 59.5, 12.0];

fn element_size(cells: f64) -> f64 {
    (6.0 * SIZE[0] * SIZE[1] * SIZE[2] / cells).cbrt()
}

fn push_only() -> Protocol {
    let mut p = Protocol::ramp_hold_release(0.2, 28.87, 28.87, 28.87);
    p.waypoints.truncate(2);
    p
}

fn plate_problem(tool: Option<ToolContact>) -> SolidPress {
    let m = mesh::block(SIZE, element_size(1e5), "mat1").unwrap();
    let mut p = SolidPress::new_3d(m, vec![Material::seed_mat1_force()], push_only()).unwrap();
    if let Some(contact) = tool {
        let (lo, hi) = p.mesh.bounding_box();
        p.tools = vec![Tool::plate_above("plate", lo, hi, &p.protocol.waypoints, contact, p.protocol.release_s)];
    }
    p
}

fn sphere_problem() -> SolidPress {
    let m = mesh::block(SIZE, element_size(1e5), "gel").unwrap();
    let material = Material::new(Rheology::Elastic { e_mpa: 0.05 }, 0.3).unwrap();
    let mut protocol = Protocol::ramp_hold_release(0.2, 10.0, 10.0, 10.0);
    protocol.waypoints.truncate(2);
    let mut p = SolidPress::new_3d(m, vec![material], protocol).unwrap();
    let radius = 20.0;
    p.tools = vec![Tool::moving_down(
        "sphere",
        ToolShape::Sphere { radius },
        [SIZE[0] / 2.0, SIZE[1] + radius, SIZE[2] / 2.0],
        &p.protocol.waypoints,
        ToolContact::Frictionless,
        f64::INFINITY,
    )];
    p
}

fn fixed_steps() -> Settings {
    Settings { fixed_dt_s: Some(28.87 / 20.0), max_dt_s: Some(28.87 / 20.0), ..Settings::default() }
}

fn bench_plate(c: &mut Criterion) {
    let mut group = c.benchmark_group("plate_step");
    group.sample_size(10).measurement_time(Duration::from_secs(30));
    let cases = [
        ("constrained", None),
        ("tool", Some(ToolContact::Glued)),
        ("frictionless_tool", Some(ToolContact::Frictionless)),
    ];
    for (name, tool) in cases {
        let p = plate_problem(tool);
        let r = press::simulate(&p, &fixed_steps(), &mut |_| {}).unwrap();
        eprintln!(
            "plate_step/{name}: {} cells, {} steps, {} factorizations, {} contact solves, peak {:.4} N",
            p.mesh.num_cells(),
            r.steps.len(),
            r.num_factorizations,
            r.contact_solves,
            r.peak_force()
        );
        group.bench_function(name, |b| {
            b.iter(|| press::simulate(&plate_problem(tool), &fixed_steps(), &mut |_| {}).unwrap())
        });
    }
    group.finish();
}

fn bench_sphere(c: &mut Criterion) {
    let mut group = c.benchmark_group("sphere_indentation");
    group.sample_size(10).measurement_time(Duration::from_secs(60));
    let p = sphere_problem();
    // One run, timed here too: at 100k tets criterion's ten samples take ten times
    // as long, which is often more than a session can give.
    let start = std::time::Instant::now();
    let r = press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
    let elapsed = start.elapsed();
    let last = r.tools[0].samples.last().unwrap();
    eprintln!(
        "sphere_indentation: {} cells, {} steps, {} factorizations, final force {:.4} N on {:.2} mm^2, one run {:.1} s",
        p.mesh.num_cells(),
        r.steps.len(),
        r.num_factorizations,
        last.force_n[1],
        last.area_mm2,
        elapsed.as_secs_f64()
    );
    group.bench_function("100k", |b| {
        b.iter(|| press::simulate(&sphere_problem(), &Settings::default(), &mut |_| {}).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench_plate, bench_sphere);
criterion_main!(benches);
