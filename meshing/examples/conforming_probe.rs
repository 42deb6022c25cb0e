//! Conforming meshes of a 10 x 20 x 5 mm box at several sizes, or of an OBJ file
//! at one size; prints the counts and the quality of each.
//!
//! ```text
//! cargo run --release -p wagashi-meshing --example conforming_probe
//! cargo run --release -p wagashi-meshing --example conforming_probe -- ../shared/data/meshes/npm_bunny.obj 0.3 [Q] [SLIVER_DEG]
//! cargo run --release -p wagashi-meshing --example conforming_probe -- /usr/share/doc/netgen/examples/hinge.stl 2.0
//! ```
//!
//! OBJ (read with `tobj`), OFF and ASCII STL files are read (`PROBE_REPAIR=1`:
//! an OBJ file repaired first, as the two boxes in `tests/tetgen_golden.rs`).
//! `PROBE_WORST=N` also prints where the N worst tets are (see `diagnose`), the
//! radius-edge histogram, the boundary faces over 1.414 by the kinds of their
//! corners and the `PROBE_TOP` (30) tets of largest ratio with the kinds of
//! their corners (I input vertex, S on a sharp input edge, F on the surface,
//! V inside) and of their shortest edge's ends.
//! `PROBE_CLASSIFY=1` counts the tets under 10 deg by how many of their
//! corners are input vertices and other boundary points and how many of their
//! faces lie on the boundary (`classify`), and by shape (needle, wedge, cap,
//! sliver), with the angle at the hinge of those with two boundary faces and
//! where their shortest edge lies (`classify_shapes`).
//! `PROBE_TIMES=1` prints the wall time of reading the file, of the surface's
//! validation, of the quality report and of each of its parts computed again
//! alone (cell statistics, volumes, boundary faces, boundary distance).
//! The mesh's fingerprints (hashes of its nodes and cells, with the cells
//! sorted and as output) tell identical meshes apart from merely similar ones.
//!
//! ```text
//! ```
mod common;

use std::time::Instant;

use common::read_obj;
use meshing::conforming::{conforming_mesh, ConformingOptions};
use meshing::quality::report;
use meshing::Surface;

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
    let clock = Instant::now();
    let (s, sizes) = match args.get(1) {
        Some(path) if path.ends_with(".obj") => (read_obj(path), vec![arg(2)]),
        Some(path) => (read_off_or_stl(path), vec![arg(2)]),
        None => (Surface::cuboid([0.0; 3], [10.0, 20.0, 5.0], "box"), vec![None, Some(4.0), Some(2.0), Some(1.0)]),
    };
    // `PROBE_REPAIR=1`: repaired first (the shared two-boxes fixture needs it;
    // any format).
    let s = if std::env::var_os("PROBE_REPAIR").is_some() {
        meshing::repair::repair(&s, &meshing::repair::RepairOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
            .surface
    } else {
        s
    };
    let read_s = clock.elapsed().as_secs_f64();
    if std::env::var_os("PROBE_TIMES").is_some() {
        report_times(&s, read_s);
    }
    for h in sizes {
        let o = ConformingOptions { size_mm: h, radius_edge: q, sliver_deg: sliver, ..defaults.clone() };
        let clock = Instant::now();
        match conforming_mesh(&s, &o) {
            Ok(m) => {
                let t = clock.elapsed().as_secs_f64();
                if let Some(n) = std::env::var("PROBE_WORST").ok().and_then(|x| x.parse().ok()) {
                    diagnose(&m.mesh, &s, n);
                }
                if std::env::var_os("PROBE_CLASSIFY").is_some() {
                    classify(&m.mesh, &s);
                }
                let (canonical, ordered, cells) = fingerprints(&m.mesh);
                println!(
                    "mesh fingerprint {canonical:016x} (cells sorted), {ordered:016x} (as output), {cells:016x} (sorted cells alone)"
                );
                let clock = Instant::now();
                let r = report(&m.mesh, &s, t);
                if std::env::var_os("PROBE_TIMES").is_some() {
                    println!("report {:.3} s", clock.elapsed().as_secs_f64());
                    report_part_times(&m.mesh, &s);
                }
                println!(
                    "h {h:?} q {q} sliver {sliver}: {} tets, dihedral {:.2}..{:.2}, <10deg {:.3} %, r-e max {:.2} p99.9 {:.3}, \
                     vol err {:.1e}, Hausdorff {:.1e}, {t:.2} s\n  {:?}\n  {:?}\n  {:?}\n  {:?}\n  {:?}\n  {:?}",
                    r.num_cells,
                    r.min_dihedral_deg,
                    r.max_dihedral_deg,
                    100.0 * r.fraction_below_10_deg,
                    r.max_radius_edge,
                    r.p999_radius_edge,
                    r.volume_error,
                    r.hausdorff_relative,
                    m.stats.refinement,
                    m.stats.flips,
                    m.stats.stars,
                    m.stats.smoothing,
                    m.stats.radius_edge_smoothing,
                    m.stats.stage_times
                );
            }
            Err(e) => println!("h {h:?}: {e}"),
        }
    }
}

/// `PROBE_TIMES=1`: the wall time of reading the file and of the surface's
/// checks the mesher starts with.
fn report_times(s: &Surface, read_s: f64) {
    let clock = Instant::now();
    let valid = s.require_valid().map(|_| ());
    println!("read {read_s:.3} s, require_valid {:.3} s ({valid:?})", clock.elapsed().as_secs_f64());
}

/// `PROBE_TIMES=1`: the wall time of the quality report's parts, each
/// computed again alone.
fn report_part_times(mesh: &fem_core::mesh::TetMesh, s: &Surface) {
    let lap = |name: &str, clock: &mut Instant| {
        println!("  {name} {:.3} s", clock.elapsed().as_secs_f64());
        *clock = Instant::now();
    };
    let mut clock = Instant::now();
    let _ = meshing::quality::cell_statistics(mesh);
    lap("cell statistics", &mut clock);
    let _ = mesh.measure();
    let _ = s.signed_volume(None);
    lap("volumes", &mut clock);
    let faces = mesh.boundary_facets();
    lap("boundary faces", &mut clock);
    let tris: Vec<[[f64; 3]; 3]> = faces.iter().map(|f| f.map(|v| mesh.nodes[v as usize])).collect();
    let _ = meshing::distance::boundary_distance(&tris, s, s.diagonal() / 300.0);
    lap("boundary distance", &mut clock);
}

/// FNV-1a hashes of the mesh (node coordinates' bits, cells with their
/// regions): with the cells sorted (the same mesh whatever their order) and as
/// output (byte-identical meshes), and of the sorted cells alone (the
/// connectivity, which smoothing does not change).
fn fingerprints(mesh: &fem_core::mesh::TetMesh) -> (u64, u64, u64) {
    let fnv = |words: &mut dyn Iterator<Item = u64>| {
        words.fold(0xcbf2_9ce4_8422_2325u64, |h, w| (h ^ w).wrapping_mul(0x0100_0000_01b3))
    };
    let mut cells: Vec<([u32; 4], u16)> = mesh.cells.iter().copied().zip(mesh.cell_regions.iter().copied()).collect();
    let nodes = || mesh.nodes.iter().flat_map(|p| p.map(f64::to_bits));
    let words = |cells: &[([u32; 4], u16)]| {
        let c: Vec<u64> =
            cells.iter().flat_map(|(c, r)| c.iter().map(|&v| u64::from(v)).chain([u64::from(*r)])).collect();
        c
    };
    let ordered = fnv(&mut nodes().chain(words(&cells)));
    cells.sort_unstable();
    (fnv(&mut nodes().chain(words(&cells))), ordered, fnv(&mut words(&cells).into_iter()))
}

fn seg_dist(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(b, a);
    let t = (dot(sub(p, a), d) / dot(d, d)).clamp(0.0, 1.0);
    let q = [a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]];
    dot(sub(p, q), sub(p, q)).sqrt()
}
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn tri_dist(p: [f64; 3], t: [[f64; 3]; 3]) -> f64 {
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let nn = dot(n, n);
    let inside = (0..3).all(|i| dot(cross(sub(t[(i + 1) % 3], t[i]), sub(p, t[i])), n) >= 0.0);
    if inside && nn > 0.0 {
        return (dot(sub(p, t[0]), n) / nn.sqrt()).abs();
    }
    (0..3).map(|i| seg_dist(p, t[i], t[(i + 1) % 3])).fold(f64::INFINITY, f64::min)
}
/// Where the bad tets are: boundary points off the input surface (over 1e-9 mm;
/// brute force), the shortest edge, and the `n` worst tets by
/// min(smallest dihedral angle, 180 - largest) (`PROBE_SORT=max`: by the
/// largest angle, `PROBE_SORT=re`: by radius-edge ratio) with their corners'
/// input vertex indices and how many of their faces are on the boundary.
fn diagnose(mesh: &fem_core::mesh::TetMesh, s: &Surface, n: usize) {
    let faces = mesh.boundary_facets();
    let tris: Vec<[[f64; 3]; 3]> = s.triangles.iter().map(|t| t.map(|v| s.vertices[v as usize])).collect();
    let mut bad = 0;
    for f in &faces {
        let q = f.map(|v| mesh.nodes[v as usize]);
        for p in [q[0], q[1], q[2], [0, 1, 2].map(|k| (q[0][k] + q[1][k] + q[2][k]) / 3.0)] {
            let d = tris.iter().map(|t| tri_dist(p, *t)).fold(f64::INFINITY, f64::min);
            if d > 1e-9 {
                bad += 1;
                if bad < 20 {
                    println!("off surface by {d:.3e}: face {f:?} point {p:?}");
                }
            }
        }
    }
    println!("{} boundary faces, {bad} points off the surface", faces.len());
    let shortest = mesh
        .cells
        .iter()
        .flat_map(|c| (0..4).flat_map(move |a| (a + 1..4).map(move |b| (c[a], c[b]))))
        .map(|(a, b)| {
            dot(
                sub(mesh.nodes[a as usize], mesh.nodes[b as usize]),
                sub(mesh.nodes[a as usize], mesh.nodes[b as usize]),
            )
            .sqrt()
        })
        .fold(f64::INFINITY, f64::min);
    println!("shortest edge {shortest:.3e} mm");
    // worst tets
    let mut worst: Vec<(f64, usize)> = mesh
        .cells
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let q = meshing::quality::tet_quality(&c.map(|v| mesh.nodes[v as usize]));
            (
                match std::env::var("PROBE_SORT").as_deref() {
                    Ok("re") => -q.radius_edge,
                    Ok("max") => 180.0 - q.max_dihedral_deg,
                    _ => q.min_dihedral_deg.min(180.0 - q.max_dihedral_deg),
                },
                i,
            )
        })
        .collect();
    worst.sort_by(|a, b| a.0.total_cmp(&b.0));
    let res: Vec<f64> = mesh
        .cells
        .iter()
        .map(|c| meshing::quality::tet_quality(&c.map(|v| mesh.nodes[v as usize])).radius_edge)
        .collect();
    for b in [1.414, 1.6, 1.8, 2.0, 2.3, 3.0] {
        println!("radius-edge over {b}: {} tets", res.iter().filter(|&&r| r > b).count());
    }
    let tri_re = |f: [u32; 3]| {
        let q = f.map(|v| mesh.nodes[v as usize]);
        let (a, b, c) = (sub(q[1], q[0]), sub(q[2], q[0]), sub(q[2], q[1]));
        let (la, lb, lc) = (dot(a, a).sqrt(), dot(b, b).sqrt(), dot(c, c).sqrt());
        let area2 = dot(cross(a, b), cross(a, b)).sqrt();
        la * lb * lc / (2.0 * area2) / la.min(lb).min(lc)
    };
    let face_re: Vec<f64> = faces.iter().map(|f| tri_re(*f)).collect();
    for b in [1.0, 1.414, 2.0] {
        println!("boundary faces over {b}: {}", face_re.iter().filter(|&&r| r > b).count());
    }
    let bad_faces: std::collections::HashSet<[u32; 3]> = faces
        .iter()
        .zip(&face_re)
        .filter(|(_, &r)| r > 1.414)
        .map(|(f, _)| {
            let mut k = *f;
            k.sort_unstable();
            k
        })
        .collect();
    let forced = mesh
        .cells
        .iter()
        .zip(&res)
        .filter(|(c, &r)| {
            r > 1.414
                && [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]].iter().any(|f| {
                    let mut k = f.map(|j: usize| c[j]);
                    k.sort_unstable();
                    bad_faces.contains(&k)
                })
        })
        .count();
    println!("tets over 1.414 with a boundary face over 1.414: {forced}");
    // Vertex classes: I input vertex, S on a sharp input edge (segment), F on
    // the surface, V inside.
    let sharp: Vec<[[f64; 3]; 2]> = {
        let mut by_edge: std::collections::HashMap<(u32, u32), Vec<usize>> = Default::default();
        for (i, t) in s.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                by_edge.entry((a.min(b), a.max(b))).or_default().push(i);
            }
        }
        let normal = |t: &[u32; 3]| {
            let q = t.map(|v| s.vertices[v as usize]);
            let n = cross(sub(q[1], q[0]), sub(q[2], q[0]));
            let l = dot(n, n).sqrt();
            n.map(|x| x / l)
        };
        by_edge
            .iter()
            .filter(|(_, ts)| {
                ts.len() != 2 || dot(normal(&s.triangles[ts[0]]), normal(&s.triangles[ts[1]])) < 1.0 - 1e-9
            })
            .map(|(&(a, b), _)| [s.vertices[a as usize], s.vertices[b as usize]])
            .collect()
    };
    let on_bnd0: std::collections::HashSet<u32> = faces.iter().flatten().copied().collect();
    let class = |v: u32| -> char {
        let p = mesh.nodes[v as usize];
        if s.vertices.contains(&p) {
            'I'
        } else if !on_bnd0.contains(&v) {
            'V'
        } else if sharp.iter().any(|e| seg_dist(p, e[0], e[1]) < 1e-9) {
            'S'
        } else {
            'F'
        }
    };
    let mut ftally: std::collections::BTreeMap<String, usize> = Default::default();
    for (f, &r) in faces.iter().zip(&face_re) {
        if r > 1.414 {
            let q = f.map(|v| mesh.nodes[v as usize]);
            let l = [0, 1, 2].map(|i| dot(sub(q[(i + 1) % 3], q[(i + 2) % 3]), sub(q[(i + 1) % 3], q[(i + 2) % 3])));
            let apex = (0..3).fold(0, |b, i| if l[i] < l[b] { i } else { b });
            let key = format!(
                "apex {} others {}{} re>{}",
                class(f[apex]),
                class(f[(apex + 1) % 3]),
                class(f[(apex + 2) % 3]),
                if r > 2.0 {
                    2.0
                } else if r > 1.6 {
                    1.6
                } else {
                    1.414
                }
            );
            *ftally.entry(key).or_default() += 1;
        }
    }
    println!("{ftally:#?}");
    let mut re_sorted: Vec<usize> = (0..res.len()).collect();
    re_sorted.sort_by(|&a, &b| res[b].total_cmp(&res[a]));
    let mut tally: std::collections::BTreeMap<String, usize> = Default::default();
    for &i in re_sorted.iter().take(std::env::var("PROBE_TOP").ok().and_then(|x| x.parse().ok()).unwrap_or(30)) {
        let c = mesh.cells[i];
        let q = c.map(|v| mesh.nodes[v as usize]);
        let mut e = (f64::INFINITY, 0, 0);
        for a in 0..4 {
            for b in a + 1..4 {
                let l = dot(sub(q[a], q[b]), sub(q[a], q[b])).sqrt();
                if l < e.0 {
                    e = (l, a, b);
                }
            }
        }
        let mut cls: Vec<char> = c.iter().map(|&v| class(v)).collect();
        let short = format!("{}{}", class(c[e.1]), class(c[e.2]));
        cls.sort_unstable();
        let key = format!("{} short {}", cls.iter().collect::<String>(), short);
        *tally.entry(key.clone()).or_default() += 1;
        let qq = meshing::quality::tet_quality(&q);
        println!(
            "top re {:.2} min {:.1} max {:.1} {key} shortest {:.3} at {:?}",
            res[i], qq.min_dihedral_deg, qq.max_dihedral_deg, e.0, q[0]
        );
    }
    println!("{tally:#?}");
    let on_bnd: std::collections::HashSet<u32> = faces.iter().flatten().copied().collect();
    for &(qv, i) in worst.iter().take(n) {
        let c = mesh.cells[i];
        let q = meshing::quality::tet_quality(&c.map(|v| mesh.nodes[v as usize]));
        let nb = c.iter().filter(|v| on_bnd.contains(v)).count();
        let inp: Vec<usize> =
            c.iter().map(|&v| s.vertices.iter().position(|p| *p == mesh.nodes[v as usize]).map_or(0, |_| 1)).collect();
        let edges: Vec<f64> = (0..4)
            .flat_map(|a| (a + 1..4).map(move |b| (a, b)))
            .map(|(a, b)| {
                dot(
                    sub(mesh.nodes[c[a] as usize], mesh.nodes[c[b] as usize]),
                    sub(mesh.nodes[c[a] as usize], mesh.nodes[c[b] as usize]),
                )
                .sqrt()
            })
            .collect();
        let fs: std::collections::HashSet<[u32; 3]> = faces
            .iter()
            .map(|f| {
                let mut k = *f;
                k.sort_unstable();
                k
            })
            .collect();
        let nbf = [[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]]
            .iter()
            .filter(|f| {
                let mut k = f.map(|j: usize| c[j]);
                k.sort_unstable();
                fs.contains(&k)
            })
            .count();
        let idx: Vec<Option<usize>> =
            c.iter().map(|&v| s.vertices.iter().position(|p| *p == mesh.nodes[v as usize])).collect();
        println!("bnd faces {nbf} input idx {idx:?}");
        println!(
            "re {:.2} q {qv:.2} min {:.2} max {:.2} bnd verts {nb} input verts {inp:?} at {:?} edges {:?}",
            q.radius_edge,
            q.min_dihedral_deg,
            q.max_dihedral_deg,
            mesh.nodes[c[0] as usize],
            edges.iter().map(|e| format!("{e:.4}")).collect::<Vec<_>>()
        );
    }
}

/// The tets under 10 deg by how many of their corners are input vertices (I),
/// other boundary points (B) and interior points, and by how many of their
/// faces lie on the boundary; with the smallest angle of each class.
fn classify(mesh: &fem_core::mesh::TetMesh, s: &Surface) {
    let input: std::collections::HashSet<[u64; 3]> = s.vertices.iter().map(|p| p.map(f64::to_bits)).collect();
    let boundary: std::collections::HashSet<u32> = mesh.node_sets["boundary"].iter().copied().collect();
    let faces: std::collections::HashSet<[u32; 3]> = mesh
        .boundary_facets()
        .iter()
        .map(|f| {
            let mut k = *f;
            k.sort_unstable();
            k
        })
        .collect();
    let mut classes: std::collections::BTreeMap<(usize, usize, usize), (usize, f64)> = Default::default();
    let mut total = 0;
    for c in &mesh.cells {
        let q = c.map(|v| mesh.nodes[v as usize]);
        let t = meshing::quality::tet_quality(&q);
        if t.min_dihedral_deg >= 10.0 {
            continue;
        }
        total += 1;
        let ni = q.iter().filter(|p| input.contains(&p.map(f64::to_bits))).count();
        let nb = c.iter().filter(|v| boundary.contains(v)).count() - ni;
        let nf = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]
            .iter()
            .filter(|f| {
                let mut k = f.map(|j: usize| c[j]);
                k.sort_unstable();
                faces.contains(&k)
            })
            .count();
        let e = classes.entry((ni, nb, nf)).or_insert((0, f64::INFINITY));
        e.0 += 1;
        e.1 = e.1.min(t.min_dihedral_deg);
    }
    println!("{total} tets under 10 deg, by (input corners, other boundary corners, boundary faces): count, min deg");
    for (k, (n, d)) in classes {
        println!("  {k:?}: {n} ({d:.3} deg)");
    }
    classify_shapes(mesh, &boundary, &faces);
}

/// The shape of a flat tet (smallest dihedral angle under 10 deg): a *needle*
/// (two or more edges under a third of the longest: three or four corners
/// close together), a *wedge* (one such edge: two corners close together),
/// else a *cap* (a corner whose projection on the plane of the opposite face
/// lies inside that face) or a *sliver* (the four corners near a plane in
/// convex position, two opposite edges crossing).
fn shape(q: &[[f64; 3]; 4]) -> &'static str {
    let pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
    let len: Vec<f64> = pairs.iter().map(|&(a, b)| dot(sub(q[a], q[b]), sub(q[a], q[b])).sqrt()).collect();
    let longest = len.iter().copied().fold(0.0, f64::max);
    match len.iter().filter(|&&l| l < longest / 3.0).count() {
        0 => {}
        1 => return "wedge",
        _ => return "needle",
    }
    for i in 0..4 {
        let f = [q[(i + 1) % 4], q[(i + 2) % 4], q[(i + 3) % 4]];
        let n = cross(sub(f[1], f[0]), sub(f[2], f[0]));
        if (0..3).all(|k| dot(cross(sub(f[(k + 1) % 3], f[k]), sub(q[i], f[k])), n) > 0.0) {
            return "cap";
        }
    }
    "sliver"
}

/// The tets under 10 deg by shape (`shape`), by how many faces they have on
/// the boundary and whether all four corners lie on the surface (such a tet
/// has no interior point that Delaunay refinement inside could move or
/// remove); for those with two boundary faces, the dihedral angle at their
/// common edge (the hinge: 180 deg minus the surface's bend there).
fn classify_shapes(
    mesh: &fem_core::mesh::TetMesh,
    boundary: &std::collections::HashSet<u32>,
    faces: &std::collections::HashSet<[u32; 3]>,
) {
    let mut by: std::collections::BTreeMap<(&str, usize, bool), (usize, f64)> = Default::default();
    let mut hinge = [0usize; 7];
    let mut worst_at_hinge_opposite = 0;
    let mut shortest_at = [0usize; 3];
    for c in &mesh.cells {
        let q = c.map(|v| mesh.nodes[v as usize]);
        let t = meshing::quality::tet_quality(&q);
        if t.min_dihedral_deg >= 10.0 {
            continue;
        }
        let on_face: Vec<usize> = (0..4)
            .filter(|&i| {
                let mut k = [c[(i + 1) % 4], c[(i + 2) % 4], c[(i + 3) % 4]];
                k.sort_unstable();
                faces.contains(&k)
            })
            .collect();
        let all_surface = c.iter().all(|v| boundary.contains(v));
        let e = by.entry((shape(&q), on_face.len(), all_surface)).or_insert((0, f64::INFINITY));
        e.0 += 1;
        e.1 = e.1.min(t.min_dihedral_deg);
        if on_face.len() == 2 {
            // Faces opposite corners i and j share the edge of the other two corners.
            let (i, j) = (on_face[0], on_face[1]);
            let others: Vec<usize> = (0..4).filter(|&k| k != i && k != j).collect();
            let (a, b) = (q[others[0]], q[others[1]]);
            let d = sub(b, a);
            let dd = dot(d, d);
            let perp = |p: [f64; 3]| {
                let u = sub(p, a);
                let s = dot(u, d) / dd;
                sub(u, [s * d[0], s * d[1], s * d[2]])
            };
            let (u, v) = (perp(q[i]), perp(q[j]));
            let angle = (dot(u, v) / (dot(u, u) * dot(v, v)).sqrt()).clamp(-1.0, 1.0).acos().to_degrees();
            let bin = match angle {
                x if x < 150.0 => 0,
                x if x < 160.0 => 1,
                x if x < 165.0 => 2,
                x if x < 170.0 => 3,
                x if x < 175.0 => 4,
                x if x < 178.0 => 5,
                _ => 6,
            };
            hinge[bin] += 1;
            // Where the shortest edge is: the hinge, the free edge (the two
            // corners off the hinge) or a side.
            let len = |u: usize, v: usize| dot(sub(q[u], q[v]), sub(q[u], q[v])).sqrt();
            let pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
            let (su, sv) = pairs.into_iter().min_by(|x, y| len(x.0, x.1).total_cmp(&len(y.0, y.1))).unwrap_or((0, 1));
            let k = if [su, sv] == [others[0], others[1]] {
                0
            } else if [su, sv] == [i.min(j), i.max(j)] {
                1
            } else {
                2
            };
            shortest_at[k] += 1;
            if t.max_dihedral_deg >= angle - 1e-9 {
                worst_at_hinge_opposite += 1;
            }
        }
    }
    println!("tets under 10 deg by (shape, boundary faces, all four corners on the surface): count, min deg");
    for (k, (n, d)) in by {
        println!("  {k:?}: {n} ({d:.3} deg)");
    }
    println!(
        "two boundary faces, dihedral at their common edge <150/150-160/160-165/165-170/170-175/175-178/>=178 deg: {hinge:?}; \
         the tet's largest angle there: {worst_at_hinge_opposite}; shortest edge on the hinge/free edge/a side: \
         {shortest_at:?}"
    );
}
