//! Where the envelope mesh's Hausdorff distance comes from: for an OBJ file and
//! a list of sizes, both directions of the distance (output boundary -> input,
//! input -> output boundary), where their maxima sit, and the input's dihedral
//! angle at the worst input point (a sharp edge or a smooth part).
//!
//! ```text
//! cargo run --release -p wagashi-meshing --example envelope_probe -- ../shared/data/meshes/npm_bunny.obj 0.3 0.2 0.1
//! ```
//!
//! `PROBE_GRADE=levels[,tolerance]` meshes on the graded lattice;
//! `PROBE_FINGERPRINT=1` prints only a hash of each mesh (nodes' bits, cells,
//! regions, warnings), to show that a change leaves the meshes bit-identical.
mod common;

use std::time::Instant;

use common::read_obj;
use meshing::envelope::{envelope_mesh_with_progress, EnvelopeOptions, TriangleTree};
use meshing::quality::report;

type P = [f64; 3];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn norm(a: P) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).map(String::as_str).unwrap_or("../shared/data/meshes/npm_bunny.obj");
    let sizes: Vec<f64> = args.iter().skip(2).filter_map(|a| a.parse().ok()).collect();
    let s = read_obj(path);
    let diag = s.diagonal();
    let in_tree = TriangleTree::new(s.triangles.iter().map(|t| t.map(|v| s.vertices[v as usize])).collect());
    println!("{path}: {} triangles, diagonal {diag:.4} mm", s.triangles.len());
    for h in sizes {
        let t0 = Instant::now();
        let mut opts = EnvelopeOptions::new(h);
        if let Ok(f) = std::env::var("PROBE_FIT") {
            opts.fit_tolerance = f.parse().unwrap_or(0.0);
        }
        // PROBE_GRADE=levels[,tolerance]: the graded lattice.
        if let Ok(g) = std::env::var("PROBE_GRADE") {
            let mut it = g.split(',');
            opts.grade_levels = it.next().and_then(|x| x.parse().ok()).unwrap_or(0);
            if let Some(t) = it.next().and_then(|x| x.parse().ok()) {
                opts.grade_tolerance = t;
            }
        }
        let stage = std::sync::Mutex::new(String::new());
        let timing = |name: &str, _: f64| {
            let mut last = stage.lock().unwrap_or_else(|e| e.into_inner());
            if *last != name && std::env::var("PROBE_STAGES").is_ok() {
                println!("  {:.2} s: {name}", t0.elapsed().as_secs_f64());
            }
            *last = name.to_string();
        };
        let out = match envelope_mesh_with_progress(&s, &opts, &timing) {
            Ok(out) => out,
            Err(e) => {
                println!("h {h}: refused after {:.2} s: {e}", t0.elapsed().as_secs_f64());
                continue;
            }
        };
        let dt = t0.elapsed().as_secs_f64();
        if std::env::var("PROBE_FINGERPRINT").is_ok() {
            // A hash of the mesh (the nodes' bits, the cells and their regions,
            // the warnings): equal before and after a change that must not alter
            // the mesh. The report is skipped.
            use std::hash::{Hash, Hasher};
            let mut hash = std::collections::hash_map::DefaultHasher::new();
            out.mesh.nodes.iter().flatten().for_each(|c| c.to_bits().hash(&mut hash));
            out.mesh.cells.hash(&mut hash);
            out.mesh.cell_regions.hash(&mut hash);
            format!("{:?}", out.warnings).hash(&mut hash);
            println!(
                "h {h}: fingerprint {:016x}, {} nodes, {} cells, time {dt:.2} s",
                hash.finish(),
                out.mesh.nodes.len(),
                out.mesh.cells.len()
            );
            continue;
        }
        let q = report(&out.mesh, &s, dt);
        let faces = out.mesh.boundary_facets();
        let out_tree = TriangleTree::new(faces.iter().map(|f| f.map(|v| out.mesh.nodes[v as usize])).collect());
        // Input vertices: distance to the output boundary, the worst few and a histogram.
        let mut d: Vec<(f64, usize)> = s
            .vertices
            .iter()
            .enumerate()
            .map(|(i, &p)| (out_tree.closest_point(p).map_or(f64::INFINITY, |c| c.1), i))
            .collect();
        d.sort_by(|a, b| b.0.total_cmp(&a.0));
        let over = |t: f64| d.iter().filter(|x| x.0 > t * diag).count();
        // Output boundary triangle centroids: distance to the input.
        let mut e: Vec<(f64, P)> = faces
            .iter()
            .map(|f| {
                let p = f.map(|v| out.mesh.nodes[v as usize]);
                let c = [0, 1, 2].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0);
                (in_tree.closest_point(c).map_or(f64::INFINITY, |x| x.1), c)
            })
            .collect();
        e.sort_by(|a, b| b.0.total_cmp(&a.0));
        let eover = |t: f64| e.iter().filter(|x| x.0 > t * diag).count();
        println!(
            "h {h}: {} cells, dihedral [{:.2}, {:.2}], volume err {:.2e}, time {dt:.2} s; Hausdorff {:.2e} \
             (out->in {:.2e}, in->out {:.2e} of diag)",
            q.num_cells,
            q.min_dihedral_deg,
            q.max_dihedral_deg,
            q.volume_error,
            q.hausdorff_relative,
            q.mesh_to_surface_mm / diag,
            q.surface_to_mesh_mm / diag
        );
        println!(
            "  raw Hausdorff {:.2e} (out->in {:.2e}, in->out {:.2e}); hole caps {:.2e} of diag ({:.2e} of the \
             boundary samples, {} border edges, widest hole {:.3} mm); input triangles interior {}, in part {}; \
             report {:.2} s",
            q.raw_hausdorff_relative,
            q.raw_mesh_to_surface_mm / diag,
            q.raw_surface_to_mesh_mm / diag,
            q.hole_cap_relative,
            q.hole_cap_fraction,
            q.num_border_edges,
            q.widest_hole_mm,
            q.num_interior_input_triangles,
            q.num_partly_interior_input_triangles,
            q.report_time_s
        );
        println!(
            "  fit: {} rounds, {} splits, {} refused, {} carved",
            out.stats.fit_rounds, out.stats.fit_splits, out.stats.fit_refused, out.stats.fit_carved
        );
        let outside_angles = out
            .mesh
            .cells
            .iter()
            .filter(|c| {
                let (lo, hi) = meshing::quality::dihedral_range_deg(&c.map(|x| out.mesh.nodes[x as usize]));
                lo < 12.0 || hi > 155.0
            })
            .count();
        println!(
            "  lattice tets {}, grading bisections {}, peeled slivers {}, tets outside [12, 155] deg: {outside_angles} \
             (before the final guard {}: {} flips, {} peeled, {} splits)",
            out.stats.lattice_tets,
            out.stats.grade_bisections,
            out.stats.peeled_slivers,
            out.stats.guard_bad,
            out.stats.guard_flips,
            out.stats.guard_peeled,
            out.stats.guard_splits
        );
        for w in &out.warnings {
            println!("  warning: {w}");
        }
        println!(
            "  input vertices farther than 1e-3/3e-3/1e-2 diag: {} / {} / {} of {}; boundary centroids: {} / {} / {} of {}",
            over(1e-3),
            over(3e-3),
            over(1e-2),
            d.len(),
            eover(1e-3),
            eover(3e-3),
            eover(1e-2),
            e.len()
        );
        for &(dist, i) in d.iter().take(5) {
            println!("  input vertex {i} at {:?}: {:.2e} diag", s.vertices[i], dist / diag);
        }
        if std::env::var("PROBE_WHERE").is_ok() {
            // Where the boundary figure's two maxima are.
            let tris: Vec<[P; 3]> = faces.iter().map(|f| f.map(|v| out.mesh.nodes[v as usize])).collect();
            let b = meshing::distance::boundary_distance(&tris, &s, diag / 300.0);
            println!(
                "  boundary figure: out->in {:.2e} diag at {:?}; in->out {:.2e} diag at {:?}",
                b.mesh_to_boundary_mm / diag,
                b.mesh_to_boundary_at_mm,
                b.boundary_to_mesh_mm / diag,
                b.boundary_to_mesh_at_mm
            );
            // Around the input -> mesh maximum: the input there, the winding number
            // along the way to the mesh, and the gaps on both sides along the normal.
            let w = meshing::WindingNumber::new(&s);
            let p = b.boundary_to_mesh_at_mm;
            let (_, _, t) = in_tree.closest_point(p).unwrap();
            let tri = s.triangles[t as usize].map(|v| s.vertices[v as usize]);
            let nrm = {
                let (u, v) = (sub(tri[1], tri[0]), sub(tri[2], tri[0]));
                let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
                let l = norm(c);
                [c[0] / l, c[1] / l, c[2] / l]
            };
            let at = |a: f64| [p[0] + a * nrm[0], p[1] + a * nrm[1], p[2] + a * nrm[2]];
            println!(
                "  input triangle {t} {tri:?}, normal {nrm:?}: w at -1e-4 {:.3}, +1e-4 {:.3}",
                w.at(at(-1e-4)),
                w.at(at(1e-4))
            );
            for side in [1.0, -1.0] {
                let hits = in_tree.segment_crossings(at(side * 1e-6), at(side * 5.0));
                let first: Vec<String> = hits
                    .iter()
                    .take(4)
                    .map(|&(u, k)| {
                        format!(
                            "{:.4} mm (tri {k}, w beyond {:.3})",
                            1e-6 + u * (5.0 - 1e-6),
                            w.at(at(side * (1e-6 + u * (5.0 - 1e-6) + 1e-4)))
                        )
                    })
                    .collect();
                println!("    along {side:+} n: {first:?}");
            }
            let (c, dc, _) = out_tree.closest_point(p).unwrap();
            let line: Vec<String> = (0..=8)
                .map(|k| {
                    let f = k as f64 / 8.0;
                    let q = [0, 1, 2].map(|j| p[j] + f * (c[j] - p[j]));
                    format!("{:.4} (exact {:.4})", w.at(q), in_tree.winding_number_exact(q))
                })
                .collect();
            println!("    nearest mesh boundary point {c:?} at {dc:.4} mm; w on the way: {line:?}");
            // Is the input point inside the mesh (winding number of its boundary), and what is beside that face?
            let (_, _, f) = out_tree.closest_point(c).unwrap();
            let ft = faces[f as usize].map(|v| out.mesh.nodes[v as usize]);
            let (u, v) = (sub(ft[1], ft[0]), sub(ft[2], ft[0]));
            let fc = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
            let fl = norm(fc);
            let fnrm = [fc[0] / fl, fc[1] / fl, fc[2] / fl];
            let side = |a: f64| [c[0] + a * fnrm[0], c[1] + a * fnrm[1], c[2] + a * fnrm[2]];
            println!(
                "    mesh winding at the input point {:.3}; the face {ft:?}, normal {fnrm:?}: input w at +-0.02 mm {:.4} / {:.4}, mesh w {:.3} / {:.3}",
                out_tree.winding_number_exact(p),
                w.at(side(0.02)),
                w.at(side(-0.02)),
                out_tree.winding_number_exact(side(0.02)),
                out_tree.winding_number_exact(side(-0.02))
            );
            let (_, i) = d[0];
            let p = s.vertices[i];
            let (c, dist, t) = out_tree.closest_point(p).unwrap();
            let f = faces[t as usize];
            println!("  worst input vertex {i}: nearest boundary point {c:?} at {dist:.4} mm, face {f:?}");
            for v in f {
                let q = out.mesh.nodes[v as usize];
                let mut angles = (180.0f64, 0.0f64);
                let mut n = 0;
                for cell in &out.mesh.cells {
                    if cell.contains(&v) {
                        let (lo, hi) = meshing::quality::dihedral_range_deg(&cell.map(|x| out.mesh.nodes[x as usize]));
                        angles = (angles.0.min(lo), angles.1.max(hi));
                        n += 1;
                    }
                }
                println!(
                    "    node {v} at {q:?}: {:.4} mm from the vertex, {:.2e} from the input, {n} tets, angles [{:.1}, {:.1}]",
                    norm(sub(q, p)),
                    in_tree.closest_point(q).unwrap().1,
                    angles.0,
                    angles.1
                );
            }
        }
        for &(dist, c) in e.iter().take(3) {
            println!("  boundary centroid at {c:?}: {:.2e} diag", dist / diag);
        }
        let _ = sub([0.0; 3], [0.0; 3]);
        let _ = norm([0.0; 3]);
    }
}
