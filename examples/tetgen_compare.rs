//! Conforming mode against TetGen on one surface, at the same size: runs
//! Debian's `tetgen` (when on PATH) as `tetgen -pq1.414a<V>` with
//! V = h^3 / (6 sqrt 2) on a .smesh of the same surface written to a temporary
//! folder (or reads a TetGen mesh given with `--tetgen FILE.node`), meshes the
//! surface in conforming mode, prints the quality report's figures of both
//! meshes side by side and the issue's gates (ours against TetGen's), one line
//! each, `holds` or `MISSES`. It asserts nothing: the regression test is
//! `meshing/tests/tetgen_golden.rs`.
//!
//! ```text
//! cargo run --release --example tetgen_compare -- ../shared/data/meshes/npm_bunny.obj 0.3
//! cargo run --release --example tetgen_compare -- SURFACE H --tetgen bunny.1.node
//! ```

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use meshing::conforming::{conforming_mesh, ConformingOptions};
use meshing::quality::{report, QualityReport};
use meshing::Surface;
use wagashi_io::surface::{read_surface, SurfaceOptions};
use wagashi_io::tetmesh::read_tetmesh;

fn row(name: &str, q: &QualityReport, t: f64) {
    println!(
        "{name:<10} {:>8} tets {:>7} nodes  dihedral {:6.2}..{:6.2}  <10deg {:6.3} %  r-e max {:9.3} p99.9 {:6.3}  \
         volume err {:+.2e}  Hausdorff {:.2e}  {t:.2} s",
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

/// TetGen's `.smesh` of `s` (1-based, no holes, no regions).
fn smesh(s: &Surface) -> String {
    let mut out = format!("{} 3 0 0\n", s.vertices.len());
    for (i, v) in s.vertices.iter().enumerate() {
        out += &format!("{} {:.17e} {:.17e} {:.17e}\n", i + 1, v[0], v[1], v[2]);
    }
    out += &format!("{} 0\n", s.triangles.len());
    for t in &s.triangles {
        out += &format!("3 {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    out + "0\n0\n"
}

/// Runs tetgen on `s` in a temporary folder; its mesh and wall time.
fn run_tetgen(s: &Surface, max_volume: f64, dir: &Path) -> Result<(PathBuf, f64), Box<dyn std::error::Error>> {
    let input = dir.join("surface.smesh");
    std::fs::write(&input, smesh(s))?;
    let clock = Instant::now();
    let status = Command::new("tetgen").arg(format!("-pq1.414a{max_volume}")).arg("-Q").arg(&input).status()?;
    let t = clock.elapsed().as_secs_f64();
    if !status.success() {
        return Err(format!("tetgen failed: {status}").into());
    }
    Ok((dir.join("surface.1.node"), t))
}

fn gate(name: &str, ours: f64, theirs: f64, holds: bool) {
    println!("  {name:<32} ours {ours:<12.6} TetGen {theirs:<12.6} {}", if holds { "holds" } else { "MISSES" });
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (surface, h, node) = match args.as_slice() {
        [_, surface, h] => (surface, h, None),
        [_, surface, h, flag, node] if flag == "--tetgen" => (surface, h, Some(PathBuf::from(node))),
        _ => return Err("usage: tetgen_compare SURFACE H_MM [--tetgen TETGEN.node]".into()),
    };
    let h: f64 = h.parse().map_err(|e| format!("H_MM `{h}`: {e}"))?;
    let max_volume = h.powi(3) / (6.0 * 2f64.sqrt());
    let s = read_surface(surface, &SurfaceOptions { units: None, scale: 1.0, format: None })?.surface;
    let tmp = tempfile::tempdir()?;
    let (node, t_theirs) = match node {
        Some(n) => (n, f64::NAN),
        None => run_tetgen(&s, max_volume, tmp.path())?,
    };
    let theirs = report(&read_tetmesh(&node)?, &s, t_theirs);
    let clock = Instant::now();
    let out = conforming_mesh(&s, &ConformingOptions::new(h))?;
    let t = clock.elapsed().as_secs_f64();
    let ours = report(&out.mesh, &s, t);
    println!("h = {h} mm, V = {max_volume:.6e} mm^3; {:?}", out.stats.refinement);
    row("wagashi", &ours, t);
    row("TetGen", &theirs, t_theirs);
    let count = ours.num_cells as f64 / theirs.num_cells as f64;
    gate("count <= 1.25 x TetGen's", count, 1.25, count <= 1.25);
    gate("min dihedral >= TetGen's", ours.min_dihedral_deg, theirs.min_dihedral_deg, {
        ours.min_dihedral_deg >= theirs.min_dihedral_deg
    });
    gate("max dihedral <= TetGen's", ours.max_dihedral_deg, theirs.max_dihedral_deg, {
        ours.max_dihedral_deg <= theirs.max_dihedral_deg
    });
    gate("fraction < 10 deg <= TetGen's", ours.fraction_below_10_deg, theirs.fraction_below_10_deg, {
        ours.fraction_below_10_deg <= theirs.fraction_below_10_deg
    });
    gate("p99.9 radius-edge <= TetGen's", ours.p999_radius_edge, theirs.p999_radius_edge, {
        ours.p999_radius_edge <= theirs.p999_radius_edge
    });
    gate("volume error <= 1e-9", ours.volume_error.abs(), 1e-9, ours.volume_error.abs() <= 1e-9);
    gate("Hausdorff <= 1e-9", ours.hausdorff_relative, 1e-9, ours.hausdorff_relative <= 1e-9);
    Ok(())
}
