//! Conforming meshes of a 10 x 20 x 5 mm box at several sizes; prints the counts and the quality of each
//! (`cargo run --release -p wagashi-meshing --example conforming_probe`).
use meshing::conforming::{conforming_mesh, ConformingOptions};
use meshing::quality::cell_statistics;
use meshing::Surface;

fn main() {
    let (lo, hi) = ([0.0, 0.0, 0.0], [10.0, 20.0, 5.0]);
    let v: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        })
        .collect();
    let f = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    let s = Surface { vertices: v, triangles: f, triangle_regions: vec![0; 12], region_names: vec!["box".into()] };
    for h in [None, Some(4.0), Some(2.0), Some(1.0)] {
        let o = ConformingOptions { size_mm: h, max_steiner_per_vertex: 50 };
        match conforming_mesh(&s, &o) {
            Ok(m) => println!("h {h:?}: {} cells {:?}\n  {:?}", m.mesh.cells.len(), m.stats, cell_statistics(&m.mesh)),
            Err(e) => println!("h {h:?}: {e}"),
        }
    }
}
