//! STL, binary and ASCII, read and written.
//!
//! Which one a file is comes from its content: binary when its size is exactly
//! `84 + 50 n` bytes with `n` the triangle count at byte 80 (binary files may
//! begin with `solid` too), ASCII when it begins with `solid`.
//!
//! - **ASCII**: `solid NAME`, then `facet normal nx ny nz`, `outer loop`, three
//!   or more `vertex x y z`, `endloop`, `endfacet` per facet, then
//!   `endsolid [NAME]`; keywords in any case. Each solid is a region named NAME
//!   (or after the file's stem when unnamed). A loop of more than three vertices
//!   becomes a fan of triangles.
//! - **Binary**: an 80-byte header, a little-endian `u32` triangle count and 50
//!   bytes per triangle (normal, three vertices as `f32`, a `u16` attribute). One
//!   region, named after the file's stem.
//!
//! STL stores each triangle's corners by value: vertices at bit-identical
//! positions are merged into one, which gives the surface its topology. The
//! stored normals are ignored (the corner order defines the orientation).

use std::fmt::Write as _;
use std::path::Path;

use meshing::Surface;

use super::error::{Location, SurfaceError};
use super::read::{owned, stem, Builder, Raw};
use crate::error::WriteError;

/// Whether `bytes` has the exact size of a binary STL with the triangle count it
/// states.
pub(crate) fn is_binary(bytes: &[u8]) -> bool {
    if bytes.len() < 84 {
        return false;
    }
    let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    bytes.len() as u64 == 84 + 50 * n
}

/// Whether `bytes` begins (after white space) with `solid`.
pub(crate) fn is_ascii(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|c| !c.is_ascii_whitespace()).unwrap_or(bytes.len());
    bytes[start..].len() >= 5 && bytes[start..start + 5].eq_ignore_ascii_case(b"solid")
}

pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Raw, SurfaceError> {
    if is_binary(bytes) {
        parse_binary(path, bytes)
    } else if is_ascii(bytes) {
        parse_ascii(path, bytes)
    } else if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        Err(SurfaceError::Format {
            path: owned(path),
            message: format!(
                "not ASCII STL (no 'solid' at the start) and not binary STL: the header states {n} triangles, \
                 which take {} bytes, but the file has {}",
                84 + 50 * n,
                bytes.len()
            ),
        })
    } else if bytes.iter().all(|c| c.is_ascii_whitespace()) {
        Err(SurfaceError::Empty { path: owned(path) })
    } else {
        Err(SurfaceError::Format {
            path: owned(path),
            message: format!("not STL: {} bytes, neither 'solid ...' text nor an 84-byte binary header", bytes.len()),
        })
    }
}

fn parse_binary(path: &Path, bytes: &[u8]) -> Result<Raw, SurfaceError> {
    let n = (bytes.len() - 84) / 50;
    let mut b = Builder::new(true);
    let region = b.region(&stem(path));
    let f32_at = |offset: usize| {
        f64::from(f32::from_le_bytes([bytes[offset], bytes[offset + 1], bytes[offset + 2], bytes[offset + 3]]))
    };
    for t in 0..n {
        let record = 84 + 50 * t;
        let mut tri = [0u32; 3];
        for (k, corner) in tri.iter_mut().enumerate() {
            let at = record + 12 + 12 * k;
            let p = [f32_at(at), f32_at(at + 4), f32_at(at + 8)];
            if !p.iter().all(|x| x.is_finite()) {
                return Err(SurfaceError::NonFinite { path: owned(path), at: Location::Triangle(t), coordinates: p });
            }
            *corner = b.vertex(p, || Location::Triangle(t));
        }
        b.triangle(tri, region);
    }
    Ok(b.finish(Vec::new()))
}

fn parse_ascii(path: &Path, bytes: &[u8]) -> Result<Raw, SurfaceError> {
    #[derive(PartialEq, Clone, Copy, Debug)]
    enum State {
        Outside,
        InSolid,
        InFacet,
        InLoop,
        LoopDone,
    }
    let text = String::from_utf8_lossy(bytes);
    let mut b = Builder::new(true);
    let mut state = State::Outside;
    let mut region = 0;
    let mut loop_corners: Vec<u32> = Vec::new();
    let mut num_solids = 0usize;
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let mut tokens = line.split_whitespace();
        let Some(keyword) = tokens.next() else { continue };
        let keyword = keyword.to_ascii_lowercase();
        let syntax = |message: String| SurfaceError::Syntax { path: owned(path), at: Location::Line(line_no), message };
        let expected = |state: State| match state {
            State::Outside => "'solid'",
            State::InSolid => "'facet' or 'endsolid'",
            State::InFacet => "'outer loop'",
            State::InLoop => "'vertex' or 'endloop'",
            State::LoopDone => "'endfacet'",
        };
        match (state, keyword.as_str()) {
            (State::Outside, "solid") => {
                num_solids += 1;
                let name = line.trim_start()[5..].trim();
                let name = if name.is_empty() {
                    if num_solids == 1 {
                        stem(path)
                    } else {
                        format!("{}_{num_solids}", stem(path))
                    }
                } else {
                    name.to_string()
                };
                region = b.region(&name);
                state = State::InSolid;
            }
            (State::InSolid, "facet") => state = State::InFacet,
            (State::InSolid, "endsolid") => state = State::Outside,
            (State::InFacet, "outer") => {
                loop_corners.clear();
                state = State::InLoop;
            }
            (State::InLoop, "vertex") => {
                let mut p = [0.0; 3];
                for (k, c) in p.iter_mut().enumerate() {
                    let tok = tokens.next().ok_or_else(|| syntax(format!("vertex: {k} coordinates, expected 3")))?;
                    *c = tok.parse::<f64>().map_err(|_| syntax(format!("vertex: {tok:?} is not a number")))?;
                }
                if !p.iter().all(|x| x.is_finite()) {
                    return Err(SurfaceError::NonFinite {
                        path: owned(path),
                        at: Location::Line(line_no),
                        coordinates: p,
                    });
                }
                loop_corners.push(b.vertex(p, || Location::Line(line_no)));
            }
            (State::InLoop, "endloop") => {
                if loop_corners.len() < 3 {
                    return Err(syntax(format!("facet with {} vertices, expected at least 3", loop_corners.len())));
                }
                b.polygon(&loop_corners, region);
                state = State::LoopDone;
            }
            (State::LoopDone, "endfacet") => state = State::InSolid,
            (s, other) => return Err(syntax(format!("unexpected {other:?}, expected {}", expected(s)))),
        }
    }
    if state != State::Outside {
        let n = text.lines().count();
        return Err(SurfaceError::Syntax {
            path: owned(path),
            at: Location::Line(n.max(1)),
            message: "file ends inside a solid: 'endsolid' missing".to_string(),
        });
    }
    Ok(b.finish(Vec::new()))
}

/// The two STL encodings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StlEncoding {
    /// Binary (`f32` coordinates: about 7 significant digits).
    Binary,
    /// ASCII, one solid per region, coordinates written exactly (shortest
    /// round-trip decimal form of each f64).
    Ascii,
}

/// Writes `surface` [mm] to `path` as STL (atomically), with facet normals from
/// the corner order. Binary STL has one solid; ASCII STL one solid per region
/// (named by the region).
pub fn write_stl(path: impl AsRef<Path>, surface: &Surface, encoding: StlEncoding) -> Result<(), WriteError> {
    let path = path.as_ref();
    let bad = |cause: String| WriteError::BadInput { path: path.to_path_buf(), cause };
    if let Err(e) = meshing::validate::check_indices(surface) {
        return Err(bad(e.to_string()));
    }
    let normal = |tri: &[u32; 3]| {
        let [a, b, c] = tri.map(|v| surface.vertices[v as usize]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if len > 0.0 {
            n.map(|x| x / len)
        } else {
            [0.0; 3]
        }
    };
    let bytes = match encoding {
        StlEncoding::Binary => {
            let n = u32::try_from(surface.triangles.len()).map_err(|_| bad("more than 2^32 triangles".into()))?;
            let mut out = Vec::with_capacity(84 + 50 * surface.triangles.len());
            let mut header = [b' '; 80];
            let tag = b"binary STL written by wagashi, mm";
            header[..tag.len()].copy_from_slice(tag);
            out.extend_from_slice(&header);
            out.extend_from_slice(&n.to_le_bytes());
            for tri in &surface.triangles {
                let corners = tri.map(|v| surface.vertices[v as usize]);
                for x in normal(tri).iter().chain(corners.iter().flatten()) {
                    out.extend_from_slice(&(*x as f32).to_le_bytes());
                }
                out.extend_from_slice(&0u16.to_le_bytes());
            }
            out
        }
        StlEncoding::Ascii => {
            let mut out = String::new();
            for (r, name) in surface.region_names.iter().enumerate() {
                let name = name.replace(['\n', '\r'], " ");
                let _ = writeln!(out, "solid {name}");
                for (tri, _) in
                    surface.triangles.iter().zip(&surface.triangle_regions).filter(|(_, &g)| g as usize == r)
                {
                    let n = normal(tri);
                    let _ = writeln!(out, "  facet normal {:?} {:?} {:?}\n    outer loop", n[0], n[1], n[2]);
                    for v in tri {
                        let p = surface.vertices[*v as usize];
                        let _ = writeln!(out, "      vertex {:?} {:?} {:?}", p[0], p[1], p[2]);
                    }
                    let _ = writeln!(out, "    endloop\n  endfacet");
                }
                let _ = writeln!(out, "endsolid {name}");
            }
            out.into_bytes()
        }
    };
    crate::write_atomic(path, &bytes)
}
