//! Gmsh's MSH 4.1 ASCII format (Gmsh reference manual, "MSH file format").
//!
//! ## Reading
//!
//! Sections `$MeshFormat` (version 4.1, ASCII), `$PhysicalNames`, `$Entities`,
//! `$Nodes` and `$Elements` are read; others are skipped. Linear tetrahedra
//! (element type 4) become cells; their region is the first physical group of
//! their volume entity, named by `$PhysicalNames` (`physical<tag>` if unnamed), or
//! `volume<tag>` for an entity with no physical group. Triangles (type 2) become
//! the face sets of their surface's physical group name (or `surface<tag>`).
//! Points, lines and other types of dimension 0 to 2 are ignored; a volume element
//! other than a linear tetrahedron is refused. Node tags may be sparse. Version 2
//! and binary files are refused with a message saying so (re-save them from Gmsh
//! as "Version 4 ASCII").
//!
//! ## Writing
//!
//! One volume entity and one physical group (dimension 3) per region, tagged
//! `region index + 1` and named after the region; the boundary faces (outward) on
//! a surface entity with the physical group `boundary` (dimension 2, tag
//! `number of regions + 1`); all nodes in one block on volume 1; tets in VTK
//! order, which is Gmsh's (positive volume). Coordinates [mm], shortest
//! round-trip form. A `$Comments` section (`written by wagashi`, which Gmsh and
//! the reader above skip) marks the file as wagashi's, so that `wagashi mesh`
//! replaces it without `--force`.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::Path;

use fem_core::mesh::TetMesh;

use super::error::TetMeshError;
use super::tetgen::{boundary_faces_with_region, signed_volume};
use crate::atomic::write_atomic;
use crate::error::WriteError;
use crate::number::push_shortest;

struct Reader<'a> {
    file: &'a Path,
    lines: Vec<(usize, &'a str)>,
    pos: usize,
}

impl<'a> Reader<'a> {
    fn err(&self, line: usize, field: &str, cause: impl Into<String>) -> TetMeshError {
        TetMeshError::invalid(self.file, line, field, cause)
    }

    fn line(&mut self, what: &str) -> Result<(usize, &'a str), TetMeshError> {
        let l = self
            .lines
            .get(self.pos)
            .copied()
            .ok_or_else(|| self.err(self.lines.last().map_or(1, |l| l.0), what, "the file ends here"))?;
        self.pos += 1;
        Ok(l)
    }

    fn fields(&mut self, what: &str) -> Result<(usize, Vec<&'a str>), TetMeshError> {
        let (n, l) = self.line(what)?;
        Ok((n, l.split_whitespace().collect()))
    }

    fn int<T: std::str::FromStr>(&self, line: usize, f: &[&str], k: usize, field: &str) -> Result<T, TetMeshError> {
        let s = f.get(k).ok_or_else(|| self.err(line, field, "missing"))?;
        s.parse::<T>().map_err(|_| self.err(line, field, format!("`{s}` is not a valid integer here")))
    }

    fn real(&self, line: usize, f: &[&str], k: usize, field: &str) -> Result<f64, TetMeshError> {
        let s = f.get(k).ok_or_else(|| self.err(line, field, "missing"))?;
        let x = s.parse::<f64>().map_err(|_| self.err(line, field, format!("`{s}` is not a number")))?;
        if !x.is_finite() {
            return Err(self.err(line, field, format!("`{s}` is not finite")));
        }
        Ok(x)
    }

    fn expect_end(&mut self, section: &str) -> Result<(), TetMeshError> {
        let (n, l) = self.line(&format!("$End{section}"))?;
        if l.trim() != format!("$End{section}") {
            return Err(self.err(n, section, format!("expected `$End{section}`, found `{}`", l.trim())));
        }
        Ok(())
    }
}

/// Reads a Gmsh MSH 4.1 ASCII file (see the module docs).
pub fn read_gmsh(path: impl AsRef<Path>) -> Result<TetMesh, TetMeshError> {
    let path = path.as_ref();
    let bytes = crate::input::read(path).map_err(|source| TetMeshError::Read { file: path.to_path_buf(), source })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        // The line of the first byte that is not UTF-8.
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        TetMeshError::invalid(
            path,
            1 + valid.iter().filter(|&&b| b == b'\n').count(),
            "$MeshFormat",
            "not ASCII text (a binary .msh?): re-save it from Gmsh as Version 4 ASCII",
        )
    })?;
    parse_gmsh(path, &text)
}

/// Parses the text of a MSH 4.1 ASCII file (`path` is for the messages).
pub fn parse_gmsh(path: &Path, text: &str) -> Result<TetMesh, TetMeshError> {
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    let mut r = Reader { file: path, lines, pos: 0 };

    let mut version_seen = false;
    let mut physical_names: HashMap<(i32, i32), String> = HashMap::new();
    // (dim, entity tag) -> first physical tag.
    let mut entity_physical: HashMap<(i32, i32), i32> = HashMap::new();
    let mut node_index: HashMap<u64, u32> = HashMap::new();
    let mut nodes: Vec<[f64; 3]> = Vec::new();
    // Tets with their volume entity; triangles with their surface entity.
    let mut tets: Vec<([u32; 4], i32, usize)> = Vec::new();
    let mut tris: Vec<([u32; 3], i32)> = Vec::new();

    while r.pos < r.lines.len() {
        let (ln, head) = r.line("section")?;
        let head = head.trim();
        match head {
            "$MeshFormat" => {
                let (ln, f) = r.fields("$MeshFormat")?;
                let version = f.first().copied().unwrap_or("");
                if !version.starts_with("4.") {
                    return Err(r.err(
                        ln,
                        "$MeshFormat",
                        format!("version {version}: only MSH 4.1 is read; re-save it from Gmsh as Version 4 ASCII"),
                    ));
                }
                let file_type: i32 = r.int(ln, &f, 1, "file-type")?;
                if file_type != 0 {
                    return Err(r.err(ln, "file-type", "binary MSH: re-save it from Gmsh as Version 4 ASCII"));
                }
                version_seen = true;
                r.expect_end("MeshFormat")?;
            }
            "$PhysicalNames" => {
                let (ln, f) = r.fields("$PhysicalNames")?;
                let n: usize = r.int(ln, &f, 0, "numPhysicalNames")?;
                for _ in 0..n {
                    let (ln, l) = r.line("physical name")?;
                    let f: Vec<&str> = l.split_whitespace().collect();
                    let dim: i32 = r.int(ln, &f, 0, "dimension")?;
                    let tag: i32 = r.int(ln, &f, 1, "physicalTag")?;
                    let name = l
                        .split_once('"')
                        .and_then(|(_, rest)| rest.rsplit_once('"').map(|(n, _)| n.to_string()))
                        .ok_or_else(|| r.err(ln, "name", "expected a quoted name"))?;
                    physical_names.insert((dim, tag), name);
                }
                r.expect_end("PhysicalNames")?;
            }
            "$Entities" => {
                let (ln, f) = r.fields("$Entities")?;
                let counts: Vec<usize> = (0..4)
                    .map(|k| r.int(ln, &f, k, ["numPoints", "numCurves", "numSurfaces", "numVolumes"][k]))
                    .collect::<Result<_, _>>()?;
                for (dim, &count) in counts.iter().enumerate() {
                    for _ in 0..count {
                        let (ln, f) = r.fields("entity")?;
                        let tag: i32 = r.int(ln, &f, 0, "entity tag")?;
                        // Points: tag x y z numPhysicalTags ...; others: tag minX minY minZ maxX maxY maxZ numPhysicalTags ...
                        let k = if dim == 0 { 4 } else { 7 };
                        let np: usize = r.int(ln, &f, k, "numPhysicalTags")?;
                        if np > 0 {
                            let p: i32 = r.int(ln, &f, k + 1, "physicalTag")?;
                            entity_physical.insert((dim as i32, tag), p.abs());
                        }
                    }
                }
                r.expect_end("Entities")?;
            }
            "$Nodes" => {
                let (ln, f) = r.fields("$Nodes")?;
                let blocks: usize = r.int(ln, &f, 0, "numEntityBlocks")?;
                let total: usize = r.int(ln, &f, 1, "numNodes")?;
                nodes.reserve(total.min(1 << 24));
                for _ in 0..blocks {
                    let (ln, f) = r.fields("node block")?;
                    let parametric: i32 = r.int(ln, &f, 2, "parametric")?;
                    let dim: i32 = r.int(ln, &f, 0, "entityDim")?;
                    let count: usize = r.int(ln, &f, 3, "numNodesInBlock")?;
                    let mut tags = Vec::with_capacity(count.min(1 << 24));
                    for _ in 0..count {
                        let (ln, f) = r.fields("node tag")?;
                        tags.push((ln, r.int::<u64>(ln, &f, 0, "nodeTag")?));
                    }
                    for (tln, tag) in tags {
                        let (ln, f) = r.fields("node coordinates")?;
                        let need = 3 + if parametric != 0 { dim.max(0) as usize } else { 0 };
                        if f.len() < need {
                            return Err(r.err(ln, "node coordinates", format!("{} values; expected {need}", f.len())));
                        }
                        let p = [r.real(ln, &f, 0, "x")?, r.real(ln, &f, 1, "y")?, r.real(ln, &f, 2, "z")?];
                        if node_index.insert(tag, nodes.len() as u32).is_some() {
                            return Err(r.err(tln, "nodeTag", format!("node {tag} is given twice")));
                        }
                        nodes.push(p);
                    }
                }
                r.expect_end("Nodes")?;
            }
            "$Elements" => {
                let (ln, f) = r.fields("$Elements")?;
                let blocks: usize = r.int(ln, &f, 0, "numEntityBlocks")?;
                for _ in 0..blocks {
                    let (bln, f) = r.fields("element block")?;
                    let dim: i32 = r.int(bln, &f, 0, "entityDim")?;
                    let entity: i32 = r.int(bln, &f, 1, "entityTag")?;
                    let etype: i32 = r.int(bln, &f, 2, "elementType")?;
                    let count: usize = r.int(bln, &f, 3, "numElementsInBlock")?;
                    if dim == 3 && etype != 4 {
                        return Err(r.err(
                            bln,
                            "elementType",
                            format!("{etype}: only linear tetrahedra (type 4) are read as volume elements"),
                        ));
                    }
                    for _ in 0..count {
                        let (ln, f) = r.fields("element")?;
                        let node = |k: usize| -> Result<u32, TetMeshError> {
                            let tag: u64 = r.int(ln, &f, k, &format!("node {k}"))?;
                            node_index
                                .get(&tag)
                                .copied()
                                .ok_or_else(|| r.err(ln, &format!("node {k}"), format!("node {tag} is not in $Nodes")))
                        };
                        match etype {
                            4 => tets.push(([node(1)?, node(2)?, node(3)?, node(4)?], entity, ln)),
                            2 => tris.push(([node(1)?, node(2)?, node(3)?], entity)),
                            _ => {}
                        }
                    }
                }
                r.expect_end("Elements")?;
            }
            s if s.starts_with('$') => {
                // An unknown section: skip to its end.
                let end = format!("$End{}", &s[1..]);
                loop {
                    let (_, l) = r.line(&end)?;
                    if l.trim() == end {
                        break;
                    }
                }
            }
            other => return Err(r.err(ln, "section", format!("expected a `$Section` header, found `{other}`"))),
        }
    }
    if !version_seen {
        return Err(r.err(1, "$MeshFormat", "missing: not a Gmsh .msh file"));
    }
    if tets.is_empty() {
        return Err(r.err(r.lines.last().map_or(0, |l| l.0), "$Elements", "no tetrahedra (type 4) in the file"));
    }

    // Regions: the volume physical groups, by tag (named or used), then volume
    // entities without a physical group, in order of first appearance.
    let mut physical_tags: Vec<i32> = physical_names.keys().filter(|k| k.0 == 3).map(|k| k.1).collect();
    physical_tags.extend(entity_physical.iter().filter(|(k, _)| k.0 == 3).map(|(_, &p)| p));
    physical_tags.sort_unstable();
    physical_tags.dedup();
    let mut key_of_region: Vec<(bool, i32)> = physical_tags.iter().map(|&p| (true, p)).collect();
    let mut region_of_key: HashMap<(bool, i32), u16> = HashMap::new();
    for (i, k) in key_of_region.iter().enumerate() {
        region_of_key.insert(*k, i as u16);
    }
    let mut cells = Vec::with_capacity(tets.len());
    let mut cell_regions = Vec::with_capacity(tets.len());
    for (mut c, entity, ln) in tets {
        let key = match entity_physical.get(&(3, entity)) {
            Some(&p) => (true, p),
            None => (false, entity),
        };
        let region = match region_of_key.get(&key) {
            Some(&r) => r,
            None => {
                if key_of_region.len() >= u16::MAX as usize {
                    return Err(r.err(ln, "entityTag", "more than 65535 regions"));
                }
                key_of_region.push(key);
                region_of_key.insert(key, (key_of_region.len() - 1) as u16);
                (key_of_region.len() - 1) as u16
            }
        };
        let vol = signed_volume(&c.map(|v| nodes[v as usize]));
        if !(vol != 0.0) {
            return Err(r.err(ln, "element", "flat tetrahedron (zero volume)"));
        }
        if vol < 0.0 {
            c.swap(2, 3);
        }
        cells.push(c);
        cell_regions.push(region);
    }
    let region_names = key_of_region
        .iter()
        .map(|&(physical, tag)| {
            if physical {
                physical_names.get(&(3, tag)).cloned().unwrap_or_else(|| format!("physical{tag}"))
            } else {
                format!("volume{tag}")
            }
        })
        .collect();
    let mut face_sets: BTreeMap<String, Vec<[u32; 3]>> = BTreeMap::new();
    for (t, entity) in tris {
        let name = match entity_physical.get(&(2, entity)) {
            Some(&p) => physical_names.get(&(2, p)).cloned().unwrap_or_else(|| format!("physical{p}")),
            None => format!("surface{entity}"),
        };
        face_sets.entry(name).or_default().push(t);
    }
    Ok(TetMesh { nodes, cells, cell_regions, region_names, node_sets: BTreeMap::new(), face_sets })
}

/// The MSH 4.1 ASCII text of `mesh` (see the module docs).
pub fn gmsh_string(mesh: &TetMesh) -> String {
    let nreg = mesh.region_names.len().max(mesh.cell_regions.iter().map(|&r| r as usize + 1).max().unwrap_or(0)).max(1);
    let name = |r: usize| mesh.region_names.get(r).cloned().unwrap_or_else(|| format!("region{r}")).replace('"', "'");
    let faces = boundary_faces_with_region(mesh);
    let (lo, hi) = if mesh.nodes.is_empty() { ([0.0; 3], [0.0; 3]) } else { mesh.bounding_box() };
    let mut s = String::with_capacity(64 * mesh.nodes.len() + 40 * mesh.cells.len());
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    // Readers skip unknown sections (Gmsh too); the line marks the file as wagashi's,
    // which `wagashi mesh` may then replace without --force.
    s.push_str("$Comments\nwritten by wagashi\n$EndComments\n");
    let _ = writeln!(s, "$PhysicalNames\n{}", nreg + 1);
    let boundary_tag = nreg + 1;
    let _ = writeln!(s, "2 {boundary_tag} \"boundary\"");
    for r in 0..nreg {
        let _ = writeln!(s, "3 {} \"{}\"", r + 1, name(r));
    }
    s.push_str("$EndPhysicalNames\n$Entities\n");
    let _ = writeln!(s, "0 0 1 {nreg}");
    let bbox = |s: &mut String| {
        for x in lo.iter().chain(hi.iter()) {
            s.push(' ');
            push_shortest(s, *x);
        }
    };
    s.push('1');
    bbox(&mut s);
    let _ = writeln!(s, " 1 {boundary_tag} 0");
    for r in 0..nreg {
        let _ = write!(s, "{}", r + 1);
        bbox(&mut s);
        let _ = writeln!(s, " 1 {} 0", r + 1);
    }
    s.push_str("$EndEntities\n$Nodes\n");
    let n = mesh.nodes.len();
    let _ = writeln!(s, "1 {n} {} {n}", n.min(1));
    let _ = writeln!(s, "3 1 0 {n}");
    for i in 0..n {
        let _ = writeln!(s, "{}", i + 1);
    }
    for p in &mesh.nodes {
        push_shortest(&mut s, p[0]);
        for &x in &p[1..] {
            s.push(' ');
            push_shortest(&mut s, x);
        }
        s.push('\n');
    }
    s.push_str("$EndNodes\n$Elements\n");
    // Cells in their order, one block per run of equal regions.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for c in 0..mesh.cells.len() {
        match runs.last_mut() {
            Some((start, end)) if region_of(mesh, *start) == region_of(mesh, c) && *end == c => *end = c + 1,
            _ => runs.push((c, c + 1)),
        }
    }
    let blocks = runs.len() + usize::from(!faces.is_empty());
    let total = mesh.cells.len() + faces.len();
    let _ = writeln!(s, "{blocks} {total} {} {total}", total.min(1));
    let mut tag = 1;
    if !faces.is_empty() {
        let _ = writeln!(s, "2 1 2 {}", faces.len());
        for (f, _) in &faces {
            let _ = writeln!(s, "{tag} {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1);
            tag += 1;
        }
    }
    for &(start, end) in &runs {
        let _ = writeln!(s, "3 {} 4 {}", region_of(mesh, start) + 1, end - start);
        for t in &mesh.cells[start..end] {
            let _ = writeln!(s, "{tag} {} {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1);
            tag += 1;
        }
    }
    s.push_str("$EndElements\n");
    s
}

fn region_of(mesh: &TetMesh, c: usize) -> usize {
    mesh.cell_regions.get(c).copied().unwrap_or(0) as usize
}

/// Writes `mesh` to `path` as MSH 4.1 ASCII, atomically.
pub fn write_gmsh(path: impl AsRef<Path>, mesh: &TetMesh) -> Result<(), WriteError> {
    write_atomic(path, gmsh_string(mesh).as_bytes())
}
