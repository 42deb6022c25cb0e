//! Conforming meshes of a 10 x 20 x 5 mm box at several sizes; prints the counts and the quality of each
//! (`cargo run --release -p wagashi-meshing --example conforming_probe`).
use meshing::conforming::{conforming_mesh, ConformingOptions};
use meshing::quality::cell_statistics;
use meshing::Surface;

fn main() {
    let (lo, hi) = ([0.0, 0.0, 0.0], [10.0, 20.0, 5.0]);
    let s = Surface::cuboid(lo, hi, "box");
    for h in [None, Some(4.0), Some(2.0), Some(1.0)] {
        let o = ConformingOptions { size_mm: h, max_steiner_per_vertex: 50 };
        match conforming_mesh(&s, &o) {
            Ok(m) => println!("h {h:?}: {} cells {:?}\n  {:?}", m.mesh.cells.len(), m.stats, cell_statistics(&m.mesh)),
            Err(e) => println!("h {h:?}: {e}"),
        }
    }
}
