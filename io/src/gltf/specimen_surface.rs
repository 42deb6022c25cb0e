use fem_core::mesh::{TetMesh, TriMesh};

use super::error::{finite, GltfError};
use super::scene::{AnimatedSurface, Frame};

/// Faces meeting at more than this angle get separate vertices (a sharp edge,
/// lit on each side by its own normal); smaller angles are smoothed over.
pub const CREASE_ANGLE_DEG: f64 = 45.0;

/// Segments around the axis of a revolved axisymmetric section, by default.
pub const DEFAULT_SEGMENTS: usize = 48;

/// How the nodal displacements of the mesh map onto the surface.
#[derive(Debug, Clone, PartialEq)]
pub enum SurfaceLift {
    /// A tetrahedral mesh: three components per node, as they are.
    Solid,
    /// A plane mesh extruded along z: `(u_x, u_y, 0)` from two components per node.
    Slab,
    /// An axisymmetric `r-y` section revolved about y: a vertex at azimuth θ moves
    /// by `(u_r cos θ, u_y, u_r sin θ)` (the bundle's convention, `x = r cos θ`,
    /// `z = r sin θ`).
    Revolved {
        /// Each vertex's azimuth θ [rad] (0 on the axis).
        azimuth_rad: Vec<f64>,
    },
}

/// The boundary surface of a specimen mesh, with each vertex tied to the mesh
/// node whose displacement it follows: the bridge from fem-core's meshes and
/// [`fem_core::press::Snapshot`]s to an [`AnimatedSurface`].
///
/// Vertices are repeated across sharp edges (more than [`CREASE_ANGLE_DEG`] in
/// the reference shape), so several vertices may follow one node.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecimenSurface {
    /// Reference vertex positions [mm].
    pub positions_mm: Vec<[f64; 3]>,
    /// Triangles, counter-clockwise seen from outside (outward normals).
    pub triangles: Vec<[u32; 3]>,
    /// The mesh node each vertex follows.
    pub vertex_nodes: Vec<u32>,
    /// How node displacements become vertex displacements.
    pub lift: SurfaceLift,
    /// The mesh's number of nodes.
    pub num_nodes: usize,
}

impl SpecimenSurface {
    /// The boundary of a tetrahedral mesh: the faces that belong to one
    /// tetrahedron only, oriented outward.
    pub fn from_tet_mesh(mesh: &TetMesh) -> Result<Self, GltfError> {
        check_nodes(mesh.nodes.iter().map(|p| p.as_slice()), mesh.cells.iter().flatten(), mesh.nodes.len())?;
        let faces = mesh.boundary_facets();
        let mut vertex_of = vec![u32::MAX; mesh.nodes.len()];
        let mut vertex_nodes = Vec::new();
        let triangles = faces
            .iter()
            .map(|f| {
                f.map(|node| {
                    let v = &mut vertex_of[node as usize];
                    if *v == u32::MAX {
                        *v = vertex_nodes.len() as u32;
                        vertex_nodes.push(node);
                    }
                    *v
                })
            })
            .collect();
        let positions_mm = vertex_nodes.iter().map(|&n| mesh.nodes[n as usize]).collect();
        Ok(Self { positions_mm, triangles, vertex_nodes, lift: SurfaceLift::Solid, num_nodes: mesh.nodes.len() }
            .with_creases_split())
    }

    /// A plane mesh (x-y) extruded into a slab `0 <= z <= thickness_mm`: the mesh
    /// as the back (z = 0) and front (z = T) faces, its boundary edges as the side
    /// walls. For plane stress and plane strain, whose displacement does not vary
    /// through the thickness.
    pub fn extruded(mesh: &TriMesh, thickness_mm: f64) -> Result<Self, GltfError> {
        check_nodes(mesh.nodes.iter().map(|p| p.as_slice()), mesh.cells.iter().flatten(), mesh.nodes.len())?;
        if !(thickness_mm.is_finite() && thickness_mm > 0.0) {
            return Err(GltfError::invalid("slab", format!("thickness {thickness_mm} mm must be finite and > 0")));
        }
        let n = mesh.nodes.len() as u32;
        // Vertex `node` at z = 0, `n + node` at z = T.
        let mut positions_mm: Vec<[f64; 3]> = mesh.nodes.iter().map(|p| [p[0], p[1], 0.0]).collect();
        positions_mm.extend(mesh.nodes.iter().map(|p| [p[0], p[1], thickness_mm]));
        let mut vertex_nodes: Vec<u32> = (0..n).collect();
        vertex_nodes.extend(0..n);
        let mut triangles = Vec::with_capacity(2 * mesh.cells.len());
        for &[a, b, c] in &mesh.cells {
            // Counter-clockwise seen from +z: the front face as it is, the back reversed.
            triangles.push([n + a, n + b, n + c]);
            triangles.push([a, c, b]);
        }
        for [a, b] in mesh.boundary_facets() {
            // Outward edge a -> b (interior on its left): the wall's normal is e x z.
            triangles.push([a, b, n + b]);
            triangles.push([a, n + b, n + a]);
        }
        Ok(Self { positions_mm, triangles, vertex_nodes, lift: SurfaceLift::Slab, num_nodes: mesh.nodes.len() }
            .without_unused_vertices()
            .with_creases_split())
    }

    /// An axisymmetric `r-y` section (`x = r >= 0`) revolved about the y axis in
    /// `segments` steps: each boundary edge off the axis sweeps a band of quads
    /// (a fan of triangles where it touches the axis). Nodes within 1e-9 of the
    /// section's size of `r = 0` are on the axis.
    pub fn revolved(mesh: &TriMesh, segments: usize) -> Result<Self, GltfError> {
        check_nodes(mesh.nodes.iter().map(|p| p.as_slice()), mesh.cells.iter().flatten(), mesh.nodes.len())?;
        if !(3..=100_000).contains(&segments) {
            return Err(GltfError::invalid(
                "revolved surface",
                format!("{segments} segments; 3 to 100000 are allowed"),
            ));
        }
        let (lo, hi) = mesh.bounding_box();
        let tol = 1e-9 * (0..2).map(|k| hi[k] - lo[k]).fold(1.0, f64::max);
        if let Some((i, p)) = mesh.nodes.iter().enumerate().find(|(_, p)| p[0] < -tol) {
            return Err(GltfError::invalid(
                "axisymmetric section",
                format!("node {i} lies at r = x = {} mm < 0 (the section is r >= 0)", p[0]),
            ));
        }
        let on_axis = |node: u32| mesh.nodes[node as usize][0] <= tol;
        let edges: Vec<[u32; 2]> =
            mesh.boundary_facets().into_iter().filter(|&[a, b]| !(on_axis(a) && on_axis(b))).collect();
        let angle = |k: usize| std::f64::consts::TAU * (k % segments) as f64 / segments as f64;
        // The first vertex of each node: one on the axis, `segments` elsewhere.
        let mut first = vec![u32::MAX; mesh.nodes.len()];
        let mut positions_mm = Vec::new();
        let mut vertex_nodes = Vec::new();
        let mut azimuth_rad = Vec::new();
        for &node in edges.iter().flatten() {
            if first[node as usize] != u32::MAX {
                continue;
            }
            first[node as usize] = positions_mm.len() as u32;
            let [r, y] = mesh.nodes[node as usize];
            let copies = if on_axis(node) { 1 } else { segments };
            for k in 0..copies {
                let theta = if copies == 1 { 0.0 } else { angle(k) };
                positions_mm.push(if copies == 1 { [0.0, y, 0.0] } else { [r * theta.cos(), y, r * theta.sin()] });
                vertex_nodes.push(node);
                azimuth_rad.push(theta);
            }
        }
        let vertex = |node: u32, k: usize| first[node as usize] + if on_axis(node) { 0 } else { (k % segments) as u32 };
        let mut triangles = Vec::with_capacity(2 * segments * edges.len());
        for &[a, b] in &edges {
            for k in 0..segments {
                // (r, y, θ) is right-handed, so edge x θ-direction is the outward normal.
                let (ak, bk, bk1, ak1) = (vertex(a, k), vertex(b, k), vertex(b, k + 1), vertex(a, k + 1));
                if !on_axis(b) {
                    triangles.push([ak, bk, bk1]);
                }
                if !on_axis(a) {
                    triangles.push([ak, bk1, ak1]);
                }
            }
        }
        let lift = SurfaceLift::Revolved { azimuth_rad };
        Ok(Self { positions_mm, triangles, vertex_nodes, lift, num_nodes: mesh.nodes.len() }.with_creases_split())
    }

    /// Components per node of the displacements this surface reads: 3 or 2.
    pub fn node_dim(&self) -> usize {
        match self.lift {
            SurfaceLift::Solid => 3,
            SurfaceLift::Slab | SurfaceLift::Revolved { .. } => 2,
        }
    }

    /// The nodes the surface follows, sorted, each once.
    pub fn nodes_used(&self) -> Vec<u32> {
        let mut nodes = self.vertex_nodes.clone();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// Axis-aligned bounding box of the reference surface `(min, max)` [mm].
    pub fn bounds_mm(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.positions_mm {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// Each vertex's displacement [mm] from the nodal displacements `nodal`
    /// ([`node_dim`](Self::node_dim) values per node, node-major, as in
    /// [`fem_core::press::Snapshot::displacement`]).
    pub fn displacement_mm(&self, nodal: &[f64]) -> Result<Vec<[f64; 3]>, GltfError> {
        let d = self.node_dim();
        if nodal.len() != d * self.num_nodes {
            return Err(GltfError::LengthMismatch {
                what: "nodal displacement".into(),
                item: "values",
                found: nodal.len(),
                expected: d * self.num_nodes,
            });
        }
        Ok(self
            .vertex_nodes
            .iter()
            .enumerate()
            .map(|(v, &node)| {
                let u = &nodal[d * node as usize..d * node as usize + d];
                match &self.lift {
                    SurfaceLift::Solid => [u[0], u[1], u[2]],
                    SurfaceLift::Slab => [u[0], u[1], 0.0],
                    SurfaceLift::Revolved { azimuth_rad } => {
                        let theta = azimuth_rad[v];
                        [u[0] * theta.cos(), u[1], u[0] * theta.sin()]
                    }
                }
            })
            .collect())
    }

    /// The frame at `t_s` [s] of the nodal displacements `nodal` (see [`displacement_mm`](Self::displacement_mm)).
    pub fn frame(&self, t_s: f64, name: Option<&str>, nodal: &[f64]) -> Result<Frame, GltfError> {
        Ok(Frame { t_s, name: name.map(str::to_string), displacement_mm: self.displacement_mm(nodal)? })
    }

    /// The animated surface named `name` with these frames.
    pub fn animated(&self, name: &str, frames: Vec<Frame>) -> AnimatedSurface {
        AnimatedSurface {
            name: name.to_string(),
            positions_mm: self.positions_mm.clone(),
            triangles: self.triangles.clone(),
            frames,
        }
    }

    /// Drops vertices no triangle uses (interior nodes of an extruded mesh are
    /// used by its faces; this is for meshes with stray nodes).
    fn without_unused_vertices(mut self) -> Self {
        let mut new_index = vec![u32::MAX; self.positions_mm.len()];
        for t in &self.triangles {
            for &v in t {
                new_index[v as usize] = 0;
            }
        }
        for (kept, slot) in new_index.iter_mut().filter(|s| **s == 0).enumerate() {
            *slot = kept as u32;
        }
        let keep = |i: &usize| new_index[*i] != u32::MAX;
        self.positions_mm = (0..self.positions_mm.len()).filter(keep).map(|i| self.positions_mm[i]).collect();
        self.vertex_nodes = (0..self.vertex_nodes.len()).filter(keep).map(|i| self.vertex_nodes[i]).collect();
        if let SurfaceLift::Revolved { azimuth_rad } = &mut self.lift {
            *azimuth_rad = (0..azimuth_rad.len()).filter(keep).map(|i| azimuth_rad[i]).collect();
        }
        for t in &mut self.triangles {
            *t = t.map(|v| new_index[v as usize]);
        }
        self
    }

    /// Repeats each vertex once per smooth patch around it: faces that share an
    /// edge through the vertex and meet at less than [`CREASE_ANGLE_DEG`] share it.
    fn with_creases_split(mut self) -> Self {
        let source = split_creases(&mut self.positions_mm, &mut self.triangles, CREASE_ANGLE_DEG);
        self.vertex_nodes = source.iter().map(|&v| self.vertex_nodes[v]).collect();
        if let SurfaceLift::Revolved { azimuth_rad } = &mut self.lift {
            *azimuth_rad = source.iter().map(|&v| azimuth_rad[v]).collect();
        }
        self
    }
}

/// Finite coordinates and cell nodes in range.
fn check_nodes<'a>(
    nodes: impl Iterator<Item = &'a [f64]>,
    mut cell_nodes: impl Iterator<Item = &'a u32>,
    num_nodes: usize,
) -> Result<(), GltfError> {
    for (i, p) in nodes.enumerate() {
        for (k, &x) in p.iter().enumerate() {
            finite(x, || format!("mesh node {i} coordinate {k}"))?;
        }
    }
    if let Some(&v) = cell_nodes.find(|&&v| v as usize >= num_nodes) {
        return Err(GltfError::invalid("mesh", format!("a cell names node {v}, but the mesh has {num_nodes} nodes")));
    }
    Ok(())
}

/// Splits vertices along creases (see [`SpecimenSurface::with_creases_split`]);
/// returns, for each vertex after the split, the vertex it was copied from.
fn split_creases(positions: &mut Vec<[f64; 3]>, triangles: &mut [[u32; 3]], max_angle_deg: f64) -> Vec<usize> {
    let cos_max = max_angle_deg.to_radians().cos();
    let original: Vec<[u32; 3]> = triangles.to_vec();
    let normals: Vec<Option<[f64; 3]>> = original
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let n = cross3(sub3(b, a), sub3(c, a));
            let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            (length > 0.0).then(|| n.map(|x| x / length))
        })
        .collect();
    // Triangles around each vertex (compressed rows).
    let num_vertices = positions.len();
    let mut start = vec![0usize; num_vertices + 1];
    for t in &original {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..num_vertices {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut around = vec![0usize; start[num_vertices]];
    for (ti, t) in original.iter().enumerate() {
        for &v in t {
            around[fill[v as usize]] = ti;
            fill[v as usize] += 1;
        }
    }
    let mut source: Vec<usize> = (0..num_vertices).collect();
    for v in 0..num_vertices {
        let ring = &around[start[v]..start[v + 1]];
        let k = ring.len();
        if k < 2 {
            continue;
        }
        let mut parent: Vec<usize> = (0..k).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for i in 0..k {
            for j in i + 1..k {
                let (ti, tj) = (original[ring[i]], original[ring[j]]);
                let shares_edge = ti.iter().any(|&w| w as usize != v && tj.contains(&w));
                let smooth = match (normals[ring[i]], normals[ring[j]]) {
                    (Some(a), Some(b)) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2] >= cos_max,
                    _ => true,
                };
                if shares_edge && smooth {
                    let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                    parent[ri] = rj;
                }
            }
        }
        // The first patch keeps the vertex; each other patch gets a copy.
        let mut copy_of_root: Vec<Option<u32>> = vec![None; k];
        let first_root = root(&mut parent, 0);
        copy_of_root[first_root] = Some(v as u32);
        for i in 0..k {
            let r = root(&mut parent, i);
            let index = *copy_of_root[r].get_or_insert_with(|| {
                positions.push(positions[v]);
                source.push(v);
                (positions.len() - 1) as u32
            });
            let t = &mut triangles[ring[i]];
            for corner in t.iter_mut() {
                if *corner as usize == v {
                    *corner = index;
                }
            }
        }
    }
    source
}

fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use fem_core::mesh;

    /// Signed volume enclosed by a closed, outward-oriented surface (divergence theorem).
    fn enclosed_volume(s: &SpecimenSurface) -> f64 {
        s.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| s.positions_mm[v as usize]);
                let n = cross3(b, c);
                (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / 6.0
            })
            .sum()
    }

    /// Every edge of the surface is shared by exactly two triangles, in opposite
    /// directions, once split vertices are merged by position (closed, consistently oriented).
    fn assert_closed(s: &SpecimenSurface) {
        let key = |v: u32| {
            let p = s.positions_mm[v as usize];
            p.map(|x| (x * 1e6).round() as i64)
        };
        let mut edges = std::collections::BTreeMap::new();
        for t in &s.triangles {
            for i in 0..3 {
                let (a, b) = (key(t[i]), key(t[(i + 1) % 3]));
                *edges.entry((a, b)).or_insert(0) += 1;
            }
        }
        for (&(a, b), &count) in &edges {
            assert_eq!(count, 1, "edge used twice in one direction");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge without its opposite: not closed");
        }
    }

    #[test]
    fn a_block_surface_is_closed_outward_and_split_at_its_edges() {
        let m = mesh::block([4.0, 3.0, 2.0], 1.0, "a").unwrap();
        let s = SpecimenSurface::from_tet_mesh(&m).unwrap();
        assert_closed(&s);
        assert!((enclosed_volume(&s) - 24.0).abs() < 1e-9, "{}", enclosed_volume(&s));
        // A box corner lies on three faces: three vertices follow its node.
        let corner = s.vertex_nodes.iter().position(|&n| m.nodes[n as usize] == [0.0, 0.0, 0.0]).unwrap();
        let node = s.vertex_nodes[corner];
        assert_eq!(s.vertex_nodes.iter().filter(|&&n| n == node).count(), 3);
        // Interior nodes are not on the surface.
        assert!(s.nodes_used().len() < m.nodes.len());
        assert_eq!(s.node_dim(), 3);
        let u: Vec<f64> = (0..3 * m.nodes.len()).map(|i| i as f64).collect();
        let d = s.displacement_mm(&u).unwrap();
        assert_eq!(d[corner], [3.0 * node as f64, 3.0 * node as f64 + 1.0, 3.0 * node as f64 + 2.0]);
        assert!(matches!(s.displacement_mm(&u[1..]), Err(GltfError::LengthMismatch { .. })));
    }

    #[test]
    fn an_extruded_rectangle_is_a_closed_slab() {
        let m = mesh::rectangle(4.0, 3.0, 1.0, "a").unwrap();
        let s = SpecimenSurface::extruded(&m, 2.0).unwrap();
        assert_closed(&s);
        assert!((enclosed_volume(&s) - 24.0).abs() < 1e-9, "{}", enclosed_volume(&s));
        let (lo, hi) = s.bounds_mm();
        assert_eq!((lo, hi), ([0.0, 0.0, 0.0], [4.0, 3.0, 2.0]));
        let u: Vec<f64> = (0..m.nodes.len()).flat_map(|i| [1.0, -(i as f64)]).collect();
        let d = s.displacement_mm(&u).unwrap();
        for (v, dv) in d.iter().enumerate() {
            assert_eq!(*dv, [1.0, -f64::from(s.vertex_nodes[v]), 0.0]);
        }
        assert!(SpecimenSurface::extruded(&m, 0.0).is_err());
    }

    #[test]
    fn a_revolved_section_encloses_the_cylinder() {
        let (r, h) = (2.0, 3.0);
        let m = mesh::axisymmetric_section(r, h, 0.5, "a").unwrap();
        let segments = 96;
        let s = SpecimenSurface::revolved(&m, segments).unwrap();
        assert_closed(&s);
        // The inscribed 96-gon prism.
        let exact = 0.5 * segments as f64 * r * r * (std::f64::consts::TAU / segments as f64).sin() * h;
        assert!((enclosed_volume(&s) - exact).abs() < 1e-9 * exact, "{} vs {exact}", enclosed_volume(&s));
        // No degenerate triangles at the axis.
        for t in &s.triangles {
            let [a, b, c] = t.map(|v| s.positions_mm[v as usize]);
            let n = cross3(sub3(b, a), sub3(c, a));
            assert!(n.iter().map(|x| x * x).sum::<f64>() > 0.0);
        }
        // A radial displacement moves each vertex along its own radius.
        let u: Vec<f64> = m.nodes.iter().flat_map(|_| [0.5, 0.0]).collect();
        let d = s.displacement_mm(&u).unwrap();
        for (v, p) in s.positions_mm.iter().enumerate() {
            let rho = p[0].hypot(p[2]);
            if rho > 1e-12 {
                assert!((d[v][0] - 0.5 * p[0] / rho).abs() < 1e-12 && (d[v][2] - 0.5 * p[2] / rho).abs() < 1e-12);
            }
        }
        let mut bad = m.clone();
        bad.nodes[0][0] = -1.0;
        assert!(SpecimenSurface::revolved(&bad, 48).is_err());
        assert!(SpecimenSurface::revolved(&m, 2).is_err());
    }

    #[test]
    fn smooth_sides_keep_one_vertex_per_node() {
        let m = mesh::axisymmetric_section(2.0, 3.0, 1.0, "a").unwrap();
        let s = SpecimenSurface::revolved(&m, 48).unwrap();
        // A node at mid-height on the outer wall: one vertex per azimuth, no more.
        let mid = (0..m.nodes.len() as u32).find(|&n| m.nodes[n as usize] == [2.0, 1.0]).unwrap();
        assert_eq!(s.vertex_nodes.iter().filter(|&&n| n == mid).count(), 48);
        // The top rim is a crease: two vertices per azimuth.
        let rim = (0..m.nodes.len() as u32).find(|&n| m.nodes[n as usize] == [2.0, 3.0]).unwrap();
        assert_eq!(s.vertex_nodes.iter().filter(|&&n| n == rim).count(), 96);
    }
}
