//! Conforming meshes of a 10 x 20 x 5 mm box at several sizes, or of an OBJ file
//! at one size; prints the counts and the quality of each.
//!
//! ```text
//! cargo run --release -p wagashi-meshing --example conforming_probe
//! cargo run --release -p wagashi-meshing --example conforming_probe -- ../shared/data/meshes/npm_bunny.obj 0.3 [Q] [SLIVER_DEG]
//! cargo run --release -p wagashi-meshing --example conforming_probe -- /usr/share/doc/netgen/examples/hinge.stl 2.0
//! ```
//!
//! OBJ (read with `tobj`), OFF and ASCII STL files are read.
//!
//! ```text
//! ```
use std::time::Instant;

use meshing::conforming::{conforming_mesh, ConformingOptions};
use meshing::quality::report;
use meshing::Surface;

fn read_obj(path: &str) -> Surface {
    let (models, _) = tobj::load_obj(path, &tobj::LoadOptions { triangulate: true, ..Default::default() })
        .unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut s =
        Surface { vertices: Vec::new(), triangles: Vec::new(), triangle_regions: Vec::new(), region_names: Vec::new() };
    for (r, m) in models.iter().enumerate() {
        let base = s.vertices.len() as u32;
        let p = &m.mesh.positions;
        s.vertices.extend(p.chunks(3).map(|c| [c[0] as f64, c[1] as f64, c[2] as f64]));
        s.triangles.extend(m.mesh.indices.chunks(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
        s.triangle_regions.extend(std::iter::repeat_n(r as u32, m.mesh.indices.len() / 3));
        s.region_names.push(m.name.clone());
    }
    s
}

/// An OFF file (polygons as fans) or an ASCII STL file (identical coordinates
/// become one vertex), one region.
fn read_off_or_stl(path: &str) -> Surface {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut s = Surface { region_names: vec!["default".into()], ..Surface::default() };
    if path.ends_with(".off") {
        let mut tok = text.lines().map(|l| l.split('#').next().unwrap_or("")).flat_map(str::split_whitespace);
        let _ = tok.next();
        let mut num = || tok.next().and_then(|t| t.parse::<f64>().ok()).unwrap_or_else(|| panic!("{path}: bad number"));
        let (nv, nf, _) = (num() as usize, num() as usize, num());
        for _ in 0..nv {
            s.vertices.push([num(), num(), num()]);
        }
        for _ in 0..nf {
            let n = num() as usize;
            let c: Vec<u32> = (0..n).map(|_| num() as u32).collect();
            for k in 1..n - 1 {
                s.triangles.push([c[0], c[k], c[k + 1]]);
                s.triangle_regions.push(0);
            }
        }
    } else {
        let mut index = std::collections::HashMap::new();
        let mut corners = Vec::new();
        for line in text.lines() {
            let mut tok = line.split_whitespace();
            if tok.next() != Some("vertex") {
                continue;
            }
            let p: Vec<f64> = tok.map(|t| t.parse().unwrap_or_else(|e| panic!("{path}: {e}"))).collect();
            let p = [p[0], p[1], p[2]];
            let next = s.vertices.len() as u32;
            let v = *index.entry(p.map(f64::to_bits)).or_insert(next);
            if v == next {
                s.vertices.push(p);
            }
            corners.push(v);
            if corners.len() == 3 {
                s.triangles.push([corners[0], corners[1], corners[2]]);
                s.triangle_regions.push(0);
                corners.clear();
            }
        }
    }
    s
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize| args.get(i).and_then(|a| a.parse::<f64>().ok());
    let defaults = ConformingOptions::default();
    let (q, sliver) = (arg(3).unwrap_or(defaults.radius_edge), arg(4).unwrap_or(defaults.sliver_deg));
    let (s, sizes) = match args.get(1) {
        Some(path) if path.ends_with(".obj") => (read_obj(path), vec![arg(2)]),
        Some(path) => (read_off_or_stl(path), vec![arg(2)]),
        None => (Surface::cuboid([0.0; 3], [10.0, 20.0, 5.0], "box"), vec![None, Some(4.0), Some(2.0), Some(1.0)]),
    };
    for h in sizes {
        let o = ConformingOptions { size_mm: h, radius_edge: q, sliver_deg: sliver, ..defaults.clone() };
        let clock = Instant::now();
        match conforming_mesh(&s, &o) {
            Ok(m) => {
                let t = clock.elapsed().as_secs_f64();
                let r = report(&m.mesh, &s, t);
                println!(
                    "h {h:?} q {q} sliver {sliver}: {} tets, dihedral {:.2}..{:.2}, <10deg {:.3} %, r-e max {:.2} p99.9 {:.3}, \
                     vol err {:.1e}, Hausdorff {:.1e}, {t:.2} s\n  {:?}",
                    r.num_cells,
                    r.min_dihedral_deg,
                    r.max_dihedral_deg,
                    100.0 * r.fraction_below_10_deg,
                    r.max_radius_edge,
                    r.p999_radius_edge,
                    r.volume_error,
                    r.hausdorff_relative,
                    m.stats.refinement
                );
            }
            Err(e) => println!("h {h:?}: {e}"),
        }
    }
}
