//! Benchmarks of the conforming mesher (criterion;
//! `cargo bench -p wagashi-workspace-tests --bench meshing`).
//!
//! - `delaunay/random_100k`: the Delaunay tetrahedralization of 100 000 uniform
//!   random points in the unit cube (BRIO/Hilbert order, exact perturbed predicates).
//! - `delaunay/grid_46`: a 46^3 grid (97 336 points, every cube's corners
//!   cospherical): the fully degenerate case, decided by the perturbation.
//! - `conforming/...`: the whole conforming mesher (`conforming_mesh`, default
//!   quality bounds) at the sizes of the TetGen comparison
//!   (`meshing/tests/tetgen_golden.rs`): the Stanford bunny (`tests/fixtures`) at 0.3 mm,
//!   and the CAD models from Debian packages, CGAL's fandisk at 0.05 mm
//!   (`libcgal-demo`'s `data.tar.gz`, read with `tar`) and Netgen's hinge at
//!   2 mm (`netgen-doc`), and CGAL's armadillo scan at 8 mm (`libcgal-demo`;
//!   about 3 min a run on the shared machine, so 10 samples take over half an
//!   hour: filter it in or out by name); a model whose package is absent is
//!   skipped with a message. TetGen's times for the same runs are in
//!   BENCHMARKS.md.

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use meshing::conforming::{conforming_mesh, ConformingOptions, Delaunay};
use meshing::Surface;

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

/// An OFF file's polygons as triangle fans, one region.
fn parse_off(text: &str) -> Option<Surface> {
    let mut tok = text.lines().map(|l| l.split('#').next().unwrap_or("")).flat_map(str::split_whitespace).skip(1);
    let mut num = || tok.next()?.parse::<f64>().ok();
    let (nv, nf, _) = (num()? as usize, num()? as usize, num()?);
    let mut s = Surface { region_names: vec!["default".into()], ..Surface::default() };
    for _ in 0..nv {
        s.vertices.push([num()?, num()?, num()?]);
    }
    for _ in 0..nf {
        let n = num()? as usize;
        let c: Vec<u32> = (0..n).map(|_| num().map(|x| x as u32)).collect::<Option<_>>()?;
        for k in 1..n.saturating_sub(1) {
            s.triangles.push([c[0], c[k], c[k + 1]]);
            s.triangle_regions.push(0);
        }
    }
    Some(s)
}

/// The bench models that are present: name, surface, size [mm].
fn models() -> Vec<(&'static str, Surface, f64)> {
    let mut out = Vec::new();
    let read = |path: &str| {
        wagashi_io::surface::read_surface(path, &wagashi_io::surface::SurfaceOptions::default()).map(|s| s.surface)
    };
    match read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/npm_bunny.obj")) {
        Ok(s) => out.push(("bunny_0.3", s, 0.3)),
        Err(e) => eprintln!("bunny skipped: {e}"),
    }
    let cgal = "/usr/share/doc/libcgal-dev/data.tar.gz";
    let cgal_member = |member: &str| {
        Path::new(cgal)
            .exists()
            .then(|| Command::new("tar").args(["-xzOf", cgal, member]).output().ok())
            .flatten()
            .filter(|o| o.status.success())
            .and_then(|o| parse_off(&String::from_utf8_lossy(&o.stdout)))
    };
    match cgal_member("data/meshes/fandisk.off") {
        Some(s) => out.push(("fandisk_0.05", s, 0.05)),
        None => eprintln!("fandisk skipped: {cgal} absent or unreadable (apt-get install libcgal-demo)"),
    }
    match read("/usr/share/doc/netgen/examples/hinge.stl") {
        Ok(s) => out.push(("hinge_2", s, 2.0)),
        Err(e) => eprintln!("hinge skipped (apt-get install netgen-doc): {e}"),
    }
    match cgal_member("data/meshes/armadillo.off") {
        Some(s) => out.push(("armadillo_8", s, 8.0)),
        None => eprintln!("armadillo skipped: {cgal} absent or unreadable (apt-get install libcgal-demo)"),
    }
    out
}

fn conforming(c: &mut Criterion) {
    let mut g = c.benchmark_group("conforming");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    for (name, surface, h) in models() {
        let options = ConformingOptions::new(h);
        g.bench_function(name, |b| {
            b.iter(|| conforming_mesh(&surface, &options).map(|m| m.mesh.cells.len()).unwrap_or(0))
        });
    }
    g.finish();
}

criterion_group!(benches, delaunay, conforming);
criterion_main!(benches);
