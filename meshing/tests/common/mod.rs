//! Test support shared by the meshing tests: the shared data folder and a reader
//! for the fixtures' OBJ subset.

use std::path::PathBuf;

use meshing::Surface;

/// A file of the shared data folder beside the workspace (`<workspace>/../shared/data`).
pub fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data").join(rel)
}

/// The fixtures' OBJ subset: `v`, `f` (first index of each corner, polygons as
/// fans), `o`/`g` regions. The full reader is `wagashi_io::surface` (which
/// depends on this crate); these files need nothing more.
pub fn read_obj(rel: &str) -> Surface {
    let path = data(rel);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!("{}: {e} (the shared data folder beside the workspace, <workspace>/../shared/data)", path.display())
    });
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
