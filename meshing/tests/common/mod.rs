//! Test support shared by the meshing tests: the test data (the repository's
//! fixtures and the shared data folder beside the checkout, which a test that
//! reads it checks for first: see `tests/support/data.rs`) and a reader for the
//! fixtures' OBJ subset.

use std::path::{Path, PathBuf};

use meshing::Surface;

#[path = "../../../tests/support/data.rs"]
mod support;
#[allow(unused_imports)]
pub use support::{fixture, shared_data, skip_without_shared_data};

/// A file of the shared data folder beside the workspace (`<workspace>/../shared/data`).
pub fn data(rel: &str) -> PathBuf {
    support::shared_data_path().join(rel)
}

/// The Stanford bunny of the repository's fixtures (`tests/fixtures/npm_bunny.obj`).
#[allow(dead_code)]
pub fn bunny() -> Surface {
    read_obj_file(&fixture("npm_bunny.obj"))
}

/// The OBJ file `rel` of the shared data folder (the test has checked that the
/// folder is there), read as [`read_obj_file`] does.
#[allow(dead_code)]
pub fn read_obj(rel: &str) -> Surface {
    read_obj_file(&data(rel))
}

/// The fixtures' OBJ subset: `v`, `f` (first index of each corner, polygons as
/// fans), `o`/`g` regions. The full reader is `wagashi_io::surface` (which
/// depends on this crate); these files need nothing more.
pub fn read_obj_file(path: &Path) -> Surface {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut s = Surface::default();
    let mut region: Option<u32> = None;
    for line in text.lines() {
        let mut tok = line.split_whitespace();
        match tok.next() {
            Some("v") => {
                let p: Vec<f64> = tok.take(3).map(|x| x.parse().expect("number")).collect();
                s.vertices.push([p[0], p[1], p[2]]);
            }
            Some("f") => {
                let r = *region.get_or_insert_with(|| {
                    s.region_names.push("default".into());
                    s.region_names.len() as u32 - 1
                });
                let c: Vec<u32> =
                    tok.map(|x| x.split('/').next().unwrap().parse::<u32>().expect("index") - 1).collect();
                for k in 1..c.len() - 1 {
                    s.triangles.push([c[0], c[k], c[k + 1]]);
                    s.triangle_regions.push(r);
                }
            }
            Some("o") | Some("g") => {
                s.region_names.push(tok.collect::<Vec<_>>().join(" "));
                region = Some(s.region_names.len() as u32 - 1);
            }
            _ => {}
        }
    }
    s
}

/// A surface in the OFF format (`OFF`, counts, vertices, polygons as fans; one
/// region), as CGAL's data files give them. `what` names the file in messages.
#[allow(dead_code)]
pub fn parse_off(text: &str, what: &str) -> Surface {
    let mut tok = text.lines().map(|l| l.split('#').next().unwrap_or("")).flat_map(str::split_whitespace);
    assert_eq!(tok.next(), Some("OFF"), "{what}: not an OFF file");
    let mut int = |field: &str| -> usize {
        let t = tok.next().unwrap_or_else(|| panic!("{what}: ends before {field}"));
        t.parse().unwrap_or_else(|e| panic!("{what}: {field} `{t}`: {e}"))
    };
    let (nv, nf) = (int("vertex count"), int("face count"));
    int("edge count");
    let mut s = Surface { region_names: vec!["default".into()], ..Surface::default() };
    let mut num = |field: &str| -> f64 {
        let t = tok.next().unwrap_or_else(|| panic!("{what}: ends before {field}"));
        t.parse().unwrap_or_else(|e| panic!("{what}: {field} `{t}`: {e}"))
    };
    for _ in 0..nv {
        s.vertices.push([num("x"), num("y"), num("z")]);
    }
    for f in 0..nf {
        let n = num("face size") as usize;
        let c: Vec<u32> = (0..n).map(|_| num("face index") as u32).collect();
        assert!(c.iter().all(|&v| (v as usize) < nv), "{what}: face {f} has an index out of range");
        for k in 1..n - 1 {
            s.triangles.push([c[0], c[k], c[k + 1]]);
            s.triangle_regions.push(0);
        }
    }
    s
}

/// A surface in ASCII STL (`vertex x y z` lines, three per facet; identical
/// coordinates become one vertex; one region). `what` names the file in messages.
#[allow(dead_code)]
pub fn parse_ascii_stl(text: &str, what: &str) -> Surface {
    let mut s = Surface { region_names: vec!["default".into()], ..Surface::default() };
    let mut index: std::collections::HashMap<[u64; 3], u32> = std::collections::HashMap::new();
    let mut corners = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut tok = line.split_whitespace();
        if tok.next() != Some("vertex") {
            continue;
        }
        let p: Vec<f64> =
            tok.map(|t| t.parse().unwrap_or_else(|e| panic!("{what}:{}: coordinate `{t}`: {e}", i + 1))).collect();
        assert_eq!(p.len(), 3, "{what}:{}: a vertex needs three coordinates", i + 1);
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
    assert!(corners.is_empty() && !s.triangles.is_empty(), "{what}: not a whole number of facets");
    s
}
