//! The quality report of a tetrahedral mesh made by another mesher (fTetWild,
//! TetGen, ...) against its input surface, measured as `wagashi mesh` measures
//! its own: the surface is read and repaired the same way (the repaired copy is
//! kept when its inside is no more ambiguous than the file's), then
//! `meshing::quality::report` runs on the mesh read with `read_tetmesh`
//! (TetGen `.node`/`.ele` or Gmsh `.msh`). Prints the report as JSON (the
//! `quality` object of `wagashi mesh --report`); `TIME_S`, the other mesher's
//! time, is copied into `mesh_time_s`. It asserts nothing: it is the ruler of
//! BENCHMARKS.md's comparison with fTetWild at matched accuracy.
//!
//! ```text
//! cargo run --release --example mesh_report -- ../shared/data/meshes/npm_bunny.obj bunny_ftw.node 61.2
//! ```

use meshing::quality::report;
use meshing::repair::{repair, RepairOptions};
use meshing::WindingNumber;
use wagashi_io::surface::{read_surface, SurfaceOptions};
use wagashi_io::tetmesh::read_tetmesh;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (surface, mesh, time_s) = match args.as_slice() {
        [_, surface, mesh] => (surface, mesh, 0.0),
        [_, surface, mesh, t] => (surface, mesh, t.parse().map_err(|e| format!("TIME_S `{t}`: {e}"))?),
        _ => return Err("usage: mesh_report SURFACE MESH.node|MESH.msh [TIME_S]".into()),
    };
    let imported = read_surface(surface, &SurfaceOptions { units: None, scale: 1.0, format: None })?.surface;
    let repaired = repair(&imported, &RepairOptions::default())?.surface;
    let (lo, hi) = imported.bounding_box();
    let ambiguity = |s: &meshing::Surface| WindingNumber::new(s).ambiguous_fraction(lo, hi, 16);
    let reference = if ambiguity(&repaired) <= ambiguity(&imported) { &repaired } else { &imported };
    let quality = report(&read_tetmesh(mesh)?, reference, time_s);
    println!("{}", serde_json::to_string_pretty(&quality)?);
    Ok(())
}
