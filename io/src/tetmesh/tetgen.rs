//! TetGen's `.node`, `.ele` and `.face` files (TetGen 1.5 manual, section 5.2).
//!
//! - `.node`: `N 3 A B`, then `i x y z [A attributes] [B = 1: a boundary marker]`.
//! - `.ele`: `M 4 A`, then `i n1 n2 n3 n4 [A attributes]`; the first attribute is
//!   the *region attribute* (TetGen's `-A`): equal values form a region.
//! - `.face`: `F B`, then `i n1 n2 n3 [marker]` (optional when reading).
//!
//! `#` starts a comment; indices start at 0 or 1 (told by the first node) and
//! run consecutively. Only linear tets (4 nodes) are read.
//!
//! ## What wagashi writes
//!
//! 1-based indices (TetGen's default), coordinates [mm] in their shortest
//! round-trip form, tets in fem-core's (VTK's) positive order, the region as
//! attribute `region index + 1` with comment lines `# region 1 = NAME` naming them,
//! and the boundary faces (outward) in `.face` with marker `region index + 1` of
//! the cell they bound. Reading such files gives back the same nodes, cells,
//! regions and names; a region attribute without such a comment is named
//! `region<value>`. Tets read in the negative orientation are reversed; a flat
//! one is refused. `.face` markers become face sets `marker<m>` (`faces` when
//! there are no markers).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use fem_core::mesh::TetMesh;

use super::error::TetMeshError;
use crate::atomic::write_atomic;
use crate::error::WriteError;
use crate::number::push_shortest;

/// The lines of a TetGen file without comments and blank lines: (1-based line, fields).
pub(crate) struct Lines<'a> {
    pub file: PathBuf,
    items: Vec<(usize, Vec<&'a str>)>,
    pos: usize,
    comments: Vec<&'a str>,
}

impl<'a> Lines<'a> {
    fn new(file: &Path, text: &'a str) -> Self {
        let mut items = Vec::new();
        let mut comments = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let (content, comment) = match line.find('#') {
                Some(k) => (&line[..k], Some(&line[k + 1..])),
                None => (line, None),
            };
            if let Some(c) = comment {
                comments.push(c.trim());
            }
            let fields: Vec<&str> = content.split_whitespace().collect();
            if !fields.is_empty() {
                items.push((i + 1, fields));
            }
        }
        Self { file: file.to_path_buf(), items, pos: 0, comments }
    }

    fn next(&mut self, what: &str) -> Result<(usize, Vec<&'a str>), TetMeshError> {
        let item = self.items.get(self.pos).cloned().ok_or_else(|| {
            TetMeshError::invalid(&self.file, self.items.last().map_or(1, |l| l.0), what, "the file ends here")
        })?;
        self.pos += 1;
        Ok(item)
    }

    fn err(&self, line: usize, field: &str, cause: impl Into<String>) -> TetMeshError {
        TetMeshError::invalid(&self.file, line, field, cause)
    }

    fn int(&self, line: usize, fields: &[&str], k: usize, field: &str) -> Result<i64, TetMeshError> {
        let s = fields.get(k).ok_or_else(|| self.err(line, field, "missing"))?;
        s.parse::<i64>().map_err(|_| self.err(line, field, format!("`{s}` is not an integer")))
    }

    fn count(&self, line: usize, fields: &[&str], k: usize, field: &str) -> Result<usize, TetMeshError> {
        let v = self.int(line, fields, k, field)?;
        usize::try_from(v).map_err(|_| self.err(line, field, format!("{v} is negative")))
    }

    fn real(&self, line: usize, fields: &[&str], k: usize, field: &str) -> Result<f64, TetMeshError> {
        let s = fields.get(k).ok_or_else(|| self.err(line, field, "missing"))?;
        let x = s.parse::<f64>().map_err(|_| self.err(line, field, format!("`{s}` is not a number")))?;
        if !x.is_finite() {
            return Err(self.err(line, field, format!("`{s}` is not finite")));
        }
        Ok(x)
    }
}

fn read_text(path: &Path) -> Result<String, TetMeshError> {
    crate::input::read_to_string(path).map_err(|source| TetMeshError::Read { file: path.to_path_buf(), source })
}

/// `STEM.ext`: the extension appended to the stem, which may hold dots of its own
/// (TetGen names its output `bunny.1.node`, whose stem is `bunny.1`).
fn sibling(stem: &Path, ext: &str) -> PathBuf {
    let mut name = stem.as_os_str().to_owned();
    name.push(".");
    name.push(ext);
    PathBuf::from(name)
}

/// Reads `STEM.node`, `STEM.ele` and, if it exists, `STEM.face`, given any of
/// those paths (or the stem).
pub fn read_tetgen(path: impl AsRef<Path>) -> Result<TetMesh, TetMeshError> {
    let path = path.as_ref();
    let stem = match path.extension().and_then(|e| e.to_str()) {
        Some("node" | "ele" | "face") => path.with_extension(""),
        _ => path.to_path_buf(),
    };
    let node_path = sibling(&stem, "node");
    let ele_path = sibling(&stem, "ele");
    let face_path = sibling(&stem, "face");
    let node_text = read_text(&node_path)?;
    let ele_text = read_text(&ele_path)?;
    let face_text = if face_path.is_file() { Some(read_text(&face_path)?) } else { None };
    parse_tetgen(&node_path, &node_text, &ele_path, &ele_text, face_text.as_deref().map(|t| (face_path.as_path(), t)))
}

/// Parses the texts of a `.node`, an `.ele` and optionally a `.face` file (the
/// paths are for the messages).
pub fn parse_tetgen(
    node_path: &Path,
    node_text: &str,
    ele_path: &Path,
    ele_text: &str,
    face: Option<(&Path, &str)>,
) -> Result<TetMesh, TetMeshError> {
    // .node
    let mut l = Lines::new(node_path, node_text);
    let (ln, h) = l.next("header")?;
    let n = l.count(ln, &h, 0, "number of points")?;
    let dim = l.count(ln, &h, 1, "dimension")?;
    if dim != 3 {
        return Err(l.err(ln, "dimension", format!("{dim}: only 3D meshes are read")));
    }
    let nattr = if h.len() > 2 { l.count(ln, &h, 2, "number of attributes")? } else { 0 };
    let nmark = if h.len() > 3 { l.count(ln, &h, 3, "boundary markers")? } else { 0 };
    if nmark > 1 {
        return Err(l.err(ln, "boundary markers", format!("{nmark}: must be 0 or 1")));
    }
    let mut nodes = Vec::with_capacity(n.min(1 << 24));
    let mut base = 0i64;
    for i in 0..n {
        let (ln, f) = l.next(&format!("point {}", i + 1))?;
        let idx = l.int(ln, &f, 0, "point index")?;
        if i == 0 {
            if idx != 0 && idx != 1 {
                return Err(l.err(ln, "point index", format!("{idx}: the first point is numbered 0 or 1")));
            }
            base = idx;
        } else if idx != base + i as i64 {
            return Err(l.err(
                ln,
                "point index",
                format!("{idx}: expected {} (points are numbered in order)", base + i as i64),
            ));
        }
        if f.len() < 4 + nattr + nmark {
            return Err(l.err(ln, "point", format!("{} fields; the header announces {}", f.len(), 4 + nattr + nmark)));
        }
        nodes.push([l.real(ln, &f, 1, "x")?, l.real(ln, &f, 2, "y")?, l.real(ln, &f, 3, "z")?]);
    }

    // .ele
    let mut e = Lines::new(ele_path, ele_text);
    let (ln, h) = e.next("header")?;
    let m = e.count(ln, &h, 0, "number of tetrahedra")?;
    let per = e.count(ln, &h, 1, "nodes per tetrahedron")?;
    if per != 4 {
        return Err(e.err(ln, "nodes per tetrahedron", format!("{per}: only linear tetrahedra (4 nodes) are read")));
    }
    let eattr = if h.len() > 2 { e.count(ln, &h, 2, "number of attributes")? } else { 0 };
    let mut cells = Vec::with_capacity(m.min(1 << 24));
    let mut attrs: Vec<f64> = Vec::with_capacity(if eattr > 0 { m.min(1 << 24) } else { 0 });
    let mut ebase = None;
    for i in 0..m {
        let (ln, f) = e.next(&format!("tetrahedron {}", i + 1))?;
        let idx = e.int(ln, &f, 0, "tetrahedron index")?;
        let first = *ebase.get_or_insert(idx);
        if idx != first + i as i64 {
            return Err(e.err(ln, "tetrahedron index", format!("{idx}: expected {}", first + i as i64)));
        }
        if f.len() < 5 + eattr {
            return Err(e.err(ln, "tetrahedron", format!("{} fields; the header announces {}", f.len(), 5 + eattr)));
        }
        let mut c = [0u32; 4];
        for (k, slot) in c.iter_mut().enumerate() {
            let field = format!("node {}", k + 1);
            let v = e.int(ln, &f, 1 + k, &field)?;
            let local = v - base;
            if local < 0 || local >= n as i64 {
                return Err(e.err(ln, &field, format!("{v} names no point (points {base}..{})", base + n as i64 - 1)));
            }
            *slot = local as u32;
        }
        let vol = signed_volume(&c.map(|v| nodes[v as usize]));
        if !(vol != 0.0) {
            return Err(e.err(ln, "tetrahedron", "flat (zero volume)"));
        }
        if vol < 0.0 {
            c.swap(2, 3);
        }
        cells.push(c);
        if eattr > 0 {
            attrs.push(e.real(ln, &f, 5, "region attribute")?);
        }
    }

    // Regions: distinct attribute values, ascending; names from `# region V = NAME`.
    let mut named: BTreeMap<String, String> = BTreeMap::new();
    for c in &e.comments {
        if let Some(rest) = c.strip_prefix("region ") {
            if let Some((v, name)) = rest.split_once('=') {
                named.insert(v.trim().to_string(), name.trim().to_string());
            }
        }
    }
    let (cell_regions, region_names) = if attrs.is_empty() {
        (vec![0u16; cells.len()], vec!["region0".to_string()])
    } else {
        let mut values = attrs.clone();
        values.sort_by(f64::total_cmp);
        values.dedup();
        if values.len() > u16::MAX as usize {
            return Err(e.err(
                0,
                "region attribute",
                format!("{} distinct regions; at most {}", values.len(), u16::MAX),
            ));
        }
        let regions = attrs.iter().map(|a| values.partition_point(|v| v < a) as u16).collect();
        let names = values
            .iter()
            .map(|&v| {
                let key = attr_text(v);
                named.get(&key).cloned().unwrap_or_else(|| format!("region{key}"))
            })
            .collect();
        (regions, names)
    };

    // .face
    let mut face_sets: BTreeMap<String, Vec<[u32; 3]>> = BTreeMap::new();
    if let Some((fp, ft)) = face {
        let mut g = Lines::new(fp, ft);
        let (ln, h) = g.next("header")?;
        let nf = g.count(ln, &h, 0, "number of faces")?;
        let fmark = if h.len() > 1 { g.count(ln, &h, 1, "boundary markers")? } else { 0 };
        for i in 0..nf {
            let (ln, f) = g.next(&format!("face {}", i + 1))?;
            let mut t = [0u32; 3];
            for (k, slot) in t.iter_mut().enumerate() {
                let field = format!("node {}", k + 1);
                let v = g.int(ln, &f, 1 + k, &field)?;
                let local = v - base;
                if local < 0 || local >= n as i64 {
                    return Err(g.err(
                        ln,
                        &field,
                        format!("{v} names no point (points {base}..{})", base + n as i64 - 1),
                    ));
                }
                *slot = local as u32;
            }
            let name =
                if fmark > 0 { format!("marker{}", g.int(ln, &f, 4, "boundary marker")?) } else { "faces".into() };
            face_sets.entry(name).or_default().push(t);
        }
    }

    Ok(TetMesh { nodes, cells, cell_regions, region_names, node_sets: BTreeMap::new(), face_sets })
}

/// A region attribute as written (integers without a fraction).
fn attr_text(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v}")
    }
}

pub(crate) fn signed_volume(p: &[[f64; 3]; 4]) -> f64 {
    let d = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let (u, v, w) = (d(p[1], p[0]), d(p[2], p[0]), d(p[3], p[0]));
    (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0
}

/// The `.node`, `.ele` and `.face` texts of `mesh` (see the module docs).
pub fn tetgen_strings(mesh: &TetMesh) -> (String, String, String) {
    let mut node = String::with_capacity(mesh.nodes.len() * 48);
    node.push_str("# written by wagashi: points [mm]\n");
    let _ = writeln!(node, "{} 3 0 0", mesh.nodes.len());
    for (i, p) in mesh.nodes.iter().enumerate() {
        let _ = write!(node, "{}", i + 1);
        for &x in p {
            node.push(' ');
            push_shortest(&mut node, x);
        }
        node.push('\n');
    }
    let mut ele = String::with_capacity(mesh.cells.len() * 32);
    ele.push_str("# written by wagashi: tetrahedra (positive orientation), region attribute\n");
    for (r, name) in mesh.region_names.iter().enumerate() {
        let _ = writeln!(ele, "# region {} = {}", r + 1, name.replace(['\n', '\r'], " "));
    }
    let _ = writeln!(ele, "{} 4 1", mesh.cells.len());
    for (i, c) in mesh.cells.iter().enumerate() {
        let r = mesh.cell_regions.get(i).copied().unwrap_or(0) as usize + 1;
        let _ = writeln!(ele, "{} {} {} {} {} {r}", i + 1, c[0] + 1, c[1] + 1, c[2] + 1, c[3] + 1);
    }
    let faces = boundary_faces_with_region(mesh);
    let mut face = String::with_capacity(faces.len() * 32);
    face.push_str("# written by wagashi: boundary faces (outward), marker = region of their cell\n");
    let _ = writeln!(face, "{} 1", faces.len());
    for (i, (f, r)) in faces.iter().enumerate() {
        let _ = writeln!(face, "{} {} {} {} {}", i + 1, f[0] + 1, f[1] + 1, f[2] + 1, r + 1);
    }
    (node, ele, face)
}

/// Boundary faces (outward, sorted) with the region of the cell each bounds.
pub(crate) fn boundary_faces_with_region(mesh: &TetMesh) -> Vec<([u32; 3], u16)> {
    let mut all: Vec<([u32; 3], [u32; 3], u16)> = Vec::with_capacity(4 * mesh.cells.len());
    for (c, cell) in mesh.cells.iter().enumerate() {
        let r = mesh.cell_regions.get(c).copied().unwrap_or(0);
        // Outward faces of a positive tet [0, 1, 2, 3]: opposite each node.
        for f in [
            [cell[1], cell[2], cell[3]],
            [cell[0], cell[3], cell[2]],
            [cell[0], cell[1], cell[3]],
            [cell[0], cell[2], cell[1]],
        ] {
            let mut key = f;
            key.sort_unstable();
            all.push((key, f, r));
        }
    }
    all.sort_unstable_by_key(|a| a.0);
    let mut out = Vec::new();
    let mut i = 0;
    while i < all.len() {
        let mut j = i + 1;
        while j < all.len() && all[j].0 == all[i].0 {
            j += 1;
        }
        if j - i == 1 {
            out.push((all[i].1, all[i].2));
        }
        i = j;
    }
    out
}

/// Writes `mesh` as `STEM.node`, `STEM.ele` and `STEM.face`, each atomically;
/// `path` is any of them or the stem.
pub fn write_tetgen(path: impl AsRef<Path>, mesh: &TetMesh) -> Result<(), WriteError> {
    let path = path.as_ref();
    let stem = match path.extension().and_then(|e| e.to_str()) {
        Some("node" | "ele" | "face") => path.with_extension(""),
        _ => path.to_path_buf(),
    };
    let (node, ele, face) = tetgen_strings(mesh);
    write_atomic(sibling(&stem, "node"), node.as_bytes())?;
    write_atomic(sibling(&stem, "ele"), ele.as_bytes())?;
    write_atomic(sibling(&stem, "face"), face.as_bytes())
}
