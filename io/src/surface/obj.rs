//! Wavefront OBJ: `v` and `f` statements, regions from `o` and `g`.
//!
//! - `v x y z` gives a vertex; further numbers on the line (a `w`, vertex colours)
//!   are ignored. Coordinates must be finite.
//! - `f a b c ...` gives a face by 1-based vertex indices, or negative ones
//!   counting back from the last vertex so far (`-1` is the last); each corner may
//!   carry texture and normal indices (`a/t/n`, `a//n`), which are ignored. A
//!   polygon of more than three corners becomes a fan of triangles from its first
//!   corner (right for the convex, planar polygons exporters write; validation
//!   reports the overlaps a non-convex one gives).
//! - `o NAME` and `g NAME ...` start a region named by the rest of the line; a
//!   name met again continues its region. Faces before any `o` or `g` go to a
//!   region named after the file's stem.
//! - Point and line elements (`p`, `l`) have no area: they are left out and
//!   counted in the warnings. Everything else (`vt`, `vn`, `s`, `usemtl`,
//!   `mtllib`, comments) is ignored. A line ending in `\` continues on the next.
//!
//! Vertex indices are kept as the file gives them (no welding), so the file's
//! own topology is what validation sees.

use std::path::Path;

use super::error::{Location, SurfaceError};
use super::read::{owned, stem, Builder, Raw};

pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Raw, SurfaceError> {
    let text = String::from_utf8_lossy(bytes);
    let mut b = Builder::new(false);
    let default_region = stem(path);
    let mut region_name: Option<String> = None;
    let mut region: Option<u32> = None;
    let mut num_points = 0usize;
    let mut num_lines = 0usize;
    let mut corners: Vec<u32> = Vec::new();

    let mut lines = text.split('\n').enumerate();
    while let Some((i, first)) = lines.next() {
        let line_no = i + 1;
        let mut line = first.trim_end_matches('\r').to_string();
        while line.ends_with('\\') {
            line.pop();
            match lines.next() {
                Some((_, more)) => {
                    line.push(' ');
                    line.push_str(more.trim_end_matches('\r'));
                }
                None => break,
            }
        }
        let content = line.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace();
        let Some(keyword) = tokens.next() else { continue };
        let syntax = |message: String| SurfaceError::Syntax { path: owned(path), at: Location::Line(line_no), message };
        match keyword {
            "v" => {
                let mut p = [0.0; 3];
                for (k, c) in p.iter_mut().enumerate() {
                    let tok = tokens.next().ok_or_else(|| syntax(format!("vertex: {} coordinates, expected 3", k)))?;
                    *c = tok.parse::<f64>().map_err(|_| syntax(format!("vertex: {tok:?} is not a number")))?;
                }
                if !p.iter().all(|x| x.is_finite()) {
                    return Err(SurfaceError::NonFinite {
                        path: owned(path),
                        at: Location::Line(line_no),
                        coordinates: p,
                    });
                }
                b.vertex(p, || Location::Line(line_no));
            }
            "f" | "fo" => {
                corners.clear();
                for tok in tokens {
                    let index_text = tok.split('/').next().unwrap_or("");
                    let index: i64 = index_text
                        .parse()
                        .map_err(|_| syntax(format!("face: {tok:?} does not start with a vertex index")))?;
                    let n = b.num_vertices();
                    let resolved = if index > 0 { index - 1 } else { n as i64 + index };
                    if index == 0 || resolved < 0 || resolved >= n as i64 {
                        return Err(SurfaceError::IndexOutOfRange {
                            path: owned(path),
                            at: Location::Line(line_no),
                            index,
                            num_vertices: n,
                            relative: index < 0,
                        });
                    }
                    corners.push(resolved as u32);
                }
                if corners.len() < 3 {
                    return Err(syntax(format!("face: {} vertices, expected at least 3", corners.len())));
                }
                let r = match region {
                    Some(r) => r,
                    None => {
                        let name = region_name.clone().unwrap_or_else(|| default_region.clone());
                        let r = b.region(&name);
                        region = Some(r);
                        r
                    }
                };
                b.polygon(&corners, r);
            }
            "o" | "g" => {
                let name = content.trim_start()[keyword.len()..].trim();
                // `g` with no name is the default group: back to the file's region.
                region_name = (!name.is_empty()).then(|| name.to_string());
                region = None;
            }
            "p" => num_points += 1,
            "l" => num_lines += 1,
            _ => {}
        }
    }
    let mut warnings = Vec::new();
    if num_points > 0 {
        warnings.push(format!("{num_points} point elements (p) left out"));
    }
    if num_lines > 0 {
        warnings.push(format!("{num_lines} line elements (l) left out"));
    }
    Ok(b.finish(warnings))
}
