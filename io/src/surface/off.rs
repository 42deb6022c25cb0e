//! OFF (Object File Format: Geomview, CGAL's sample meshes, the Princeton
//! shape benchmark), ASCII, read.
//!
//! A header keyword `OFF` (or one of its variants with extra per-vertex data:
//! `COFF`, `NOFF`, `CNOFF`, `STOFF`, ...), the counts `vertices faces edges`
//! (on the keyword's line or the next), one vertex per line (`x y z`, then
//! whatever the variant adds: colours, normals, texture coordinates, which are
//! ignored), one face per line (`n i_1 ... i_n`, 0-based indices, then an
//! optional colour, ignored). `#` starts a comment; blank lines are skipped. The
//! keyword may be left out, as many writers do. A face of more than three
//! vertices becomes a fan of triangles. The file is one region, named after its
//! stem.
//!
//! Refused, with the line: binary OFF (`OFF BINARY`), 4D or n-dimensional
//! variants (`4OFF`, `nOFF`), counts that are not non-negative integers, a file
//! ending before the counts are met, a face of fewer than three vertices, an
//! index out of range, a non-finite coordinate.

use std::path::Path;

use super::error::{Location, SurfaceError};
use super::read::{owned, stem, Builder, Raw};

/// Whether `bytes` begins (after white space and comments) with an OFF keyword.
pub(crate) fn is_off(bytes: &[u8]) -> bool {
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]);
    let first = text.lines().map(content).find(|l| !l.is_empty());
    first.and_then(|l| l.split_whitespace().next()).is_some_and(|k| keyword(k).is_some())
}

/// A line without its comment.
fn content(line: &str) -> &str {
    line.split('#').next().unwrap_or("").trim()
}

/// The prefixes of an OFF keyword (`ST`, `C`, `N`, `4`, `n`), when `word` is one.
fn keyword(word: &str) -> Option<&str> {
    let prefix = word.strip_suffix("OFF")?;
    let mut rest = prefix;
    for p in ["ST", "C", "N", "4", "n"] {
        rest = rest.strip_prefix(p).unwrap_or(rest);
    }
    rest.is_empty().then_some(prefix)
}

pub(crate) fn parse(path: &Path, bytes: &[u8]) -> Result<Raw, SurfaceError> {
    let text = String::from_utf8_lossy(bytes);
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, content(l))).filter(|(_, l)| !l.is_empty());
    let syntax =
        |line: usize, message: String| SurfaceError::Syntax { path: owned(path), at: Location::Line(line), message };

    let Some((first_line, first)) = lines.next() else {
        return Err(SurfaceError::Empty { path: owned(path) });
    };
    let mut tokens: Vec<&str> = first.split_whitespace().collect();
    let mut counts_line = first_line;
    if let Some(prefix) = keyword(tokens[0]) {
        if prefix.contains('4') || prefix.contains('n') {
            return Err(syntax(first_line, format!("`{}`: only 3D OFF is read (not 4D or n-dimensional)", tokens[0])));
        }
        if tokens.get(1).is_some_and(|t| t.eq_ignore_ascii_case("BINARY")) {
            return Err(syntax(first_line, "binary OFF is not read; write it as ASCII OFF".into()));
        }
        tokens.remove(0);
        if tokens.is_empty() {
            let Some((line, next)) = lines.next() else {
                return Err(syntax(first_line, "the file ends before the counts `vertices faces edges`".into()));
            };
            counts_line = line;
            tokens = next.split_whitespace().collect();
        }
    }
    if tokens.len() < 2 {
        return Err(syntax(
            counts_line,
            format!("expected the counts `vertices faces edges`, found `{}`", tokens.join(" ")),
        ));
    }
    let count = |what: &str, token: &str| {
        token
            .parse::<usize>()
            .map_err(|_| syntax(counts_line, format!("the {what} count `{token}` is not a non-negative integer")))
    };
    let (num_vertices, num_faces) = (count("vertex", tokens[0])?, count("face", tokens[1])?);

    let mut b = Builder::new(false);
    let region = b.region(&stem(path));
    let mut last_line = counts_line;
    for k in 0..num_vertices {
        let Some((line, l)) = lines.next() else {
            return Err(syntax(last_line, format!("the file ends after {k} of its {num_vertices} vertices")));
        };
        last_line = line;
        let mut p = [0.0f64; 3];
        let mut values = l.split_whitespace();
        for (axis, x) in p.iter_mut().enumerate() {
            let token = values
                .next()
                .ok_or_else(|| syntax(line, format!("vertex {k}: expected three coordinates, found {axis}")))?;
            *x =
                token.parse().map_err(|_| syntax(line, format!("vertex {k}: coordinate `{token}` is not a number")))?;
        }
        if !p.iter().all(|x| x.is_finite()) {
            return Err(SurfaceError::NonFinite { path: owned(path), at: Location::Line(line), coordinates: p });
        }
        b.vertex(p, || Location::Line(line));
    }
    let mut corners = Vec::new();
    for k in 0..num_faces {
        let Some((line, l)) = lines.next() else {
            return Err(syntax(last_line, format!("the file ends after {k} of its {num_faces} faces")));
        };
        last_line = line;
        let mut values = l.split_whitespace();
        let n_token = values.next().unwrap_or("");
        let n: usize = n_token
            .parse()
            .map_err(|_| syntax(line, format!("face {k}: vertex count `{n_token}` is not an integer")))?;
        if n < 3 {
            return Err(syntax(line, format!("face {k} has {n} vertices; a face needs at least 3")));
        }
        corners.clear();
        for j in 0..n {
            let token = values
                .next()
                .ok_or_else(|| syntax(line, format!("face {k}: expected {n} vertex indices, found {j}")))?;
            let index: i64 = token
                .parse()
                .map_err(|_| syntax(line, format!("face {k}: vertex index `{token}` is not an integer")))?;
            if index < 0 || index as usize >= num_vertices {
                return Err(SurfaceError::IndexOutOfRange {
                    path: owned(path),
                    at: Location::Line(line),
                    index,
                    num_vertices,
                    relative: false,
                });
            }
            corners.push(index as u32);
        }
        b.polygon(&corners, region);
    }
    let mut warnings = Vec::new();
    if let Some((line, _)) = lines.next() {
        warnings
            .push(format!("{}:{line}: text after the {num_faces} faces the counts announce, ignored", path.display()));
    }
    Ok(b.finish(warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Raw, SurfaceError> {
        parse(Path::new("shape.off"), text.as_bytes())
    }

    const TET: &str = "OFF\n# a tetrahedron\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

    #[test]
    fn a_tetrahedron_is_read_with_its_volume() {
        let raw = read(TET).unwrap();
        assert_eq!(raw.surface.num_triangles(), 4);
        assert_eq!(raw.surface.region_names, vec!["shape"]);
        assert!((raw.surface.signed_volume(None) - 1.0 / 6.0).abs() < 1e-15);
        assert!(raw.warnings.is_empty());
    }

    #[test]
    fn the_keyword_may_carry_the_counts_or_be_left_out_and_quads_become_fans() {
        let square = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3 255 0 0\n";
        for text in [format!("OFF 4 1 0\n{square}"), format!("4 1 0\n{square}"), format!("COFF\n4 1 0\n{square}")] {
            let raw = read(&text).unwrap();
            assert_eq!(raw.surface.triangles, vec![[0, 1, 2], [0, 2, 3]], "{text}");
        }
        assert!(is_off(b"# comment\n  NOFF\n"));
        assert!(!is_off(b"solid x\n"));
        assert!(!is_off(b"v 0 0 0\n"));
    }

    #[test]
    fn defects_name_the_line() {
        let cases = [
            ("OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n", "shape.off:5: the file ends after 3 of its 4 vertices"),
            ("OFF\n4 x 6\n", "shape.off:2: the face count `x` is not a non-negative integer"),
            ("OFF\n1 1 0\n0 nan 0\n3 0 0 0\n", "shape.off:3: coordinates [0.0, NaN, 0.0] are not all finite"),
            ("OFF\n1 1 0\n0 0\n", "shape.off:3: vertex 0: expected three coordinates, found 2"),
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "shape.off:6: vertex index 3 out of range (3 vertices)"),
            ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "shape.off:6: face 0 has 2 vertices; a face needs at least 3"),
            ("OFF BINARY\n", "shape.off:1: binary OFF is not read; write it as ASCII OFF"),
            ("4OFF\n", "shape.off:1: `4OFF`: only 3D OFF is read (not 4D or n-dimensional)"),
        ];
        for (text, message) in cases {
            let err = read(text).err().unwrap_or_else(|| panic!("accepted: {text:?}"));
            assert_eq!(err.to_string(), message);
        }
        assert!(matches!(read("# nothing\n\n"), Err(SurfaceError::Empty { .. })));
    }

    #[test]
    fn trailing_text_is_a_warning() {
        let raw = read(&format!("{TET}3 0 1 2\n")).unwrap();
        assert_eq!(raw.surface.num_triangles(), 4);
        assert_eq!(raw.warnings, vec!["shape.off:12: text after the 4 faces the counts announce, ignored"]);
    }
}
