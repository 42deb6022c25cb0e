//! Conforming mode against TetGen on one surface, at the same size: prints the
//! quality report's figures of both meshes side by side. Criterion-free: it
//! asserts nothing (the issue's gates are not met yet: see BENCHMARKS.md).
//!
//! ```text
//! # TetGen first (Debian's `tetgen`), on a .smesh of the same surface, with
//! # V = h^3 / (6 sqrt 2):
//! tetgen -pq1.414a0.00318198 bunny.smesh
//! cargo run --release --example tetgen_compare -- ../shared/data/meshes/npm_bunny.obj bunny.1.node 0.3
//! ```

use std::time::Instant;

use meshing::conforming::{conforming_mesh, ConformingOptions};
use meshing::quality::{report, QualityReport};
use wagashi_io::surface::{read_surface, SurfaceOptions};
use wagashi_io::tetmesh::read_tetmesh;

fn row(name: &str, q: &QualityReport) {
    println!(
        "{name:<10} {:>8} tets {:>7} nodes  dihedral {:6.2}..{:6.2}  <10deg {:6.3} %  r-e max {:9.3} p99.9 {:6.3}  \
         volume err {:+.2e}  Hausdorff {:.2e}",
        q.num_cells,
        q.num_nodes,
        q.min_dihedral_deg,
        q.max_dihedral_deg,
        100.0 * q.fraction_below_10_deg,
        q.max_radius_edge,
        q.p999_radius_edge,
        q.volume_error,
        q.hausdorff_relative
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, surface, tetgen, h] = args.as_slice() else {
        return Err("usage: tetgen_compare SURFACE TETGEN.node H_MM".into());
    };
    let h: f64 = h.parse().map_err(|e| format!("H_MM `{h}`: {e}"))?;
    let s = read_surface(surface, &SurfaceOptions { units: None, scale: 1.0, format: None })?.surface;
    let clock = Instant::now();
    let ours = conforming_mesh(&s, &ConformingOptions::new(h))?;
    let t = clock.elapsed().as_secs_f64();
    let theirs = read_tetmesh(tetgen)?;
    println!("h = {h} mm, V = {:.6e} mm^3; ours took {t:.3} s", h.powi(3) / (6.0 * 2f64.sqrt()));
    row("wagashi", &report(&ours.mesh, &s, t));
    row("TetGen", &report(&theirs, &s, 0.0));
    Ok(())
}
