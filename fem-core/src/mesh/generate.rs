//! Structured generators at a target element size.
//!
//! Every generator places the bottom face on y = 0 and fills the node sets
//! `bottom` (y = 0) and `top` (y = H) and the face sets of the same names.
//! Blocks are split into six tetrahedra per hexahedral cell along one main
//! diagonal (Kuhn/Freudenthal), rectangles into two triangles per quad, so
//! neighbouring cells always conform. Layers stack along y, bottom first.
//! The axisymmetric section of a cylinder is the rectangle `[0, R] x [0, H]` in
//! the `r-y` plane (x = r), with the node set `axis` (r = 0) as well.

use super::{MeshError, TetMesh, TriMesh};
use std::collections::BTreeMap;

/// One layer of a layered specimen, stacked along y from the bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Region name (usually the material name).
    pub region: String,
    /// Layer thickness along y [mm].
    pub thickness_mm: f64,
}

fn intervals(length: f64, h: f64, what: &str) -> Result<usize, MeshError> {
    if !(length.is_finite() && length > 0.0) {
        return Err(MeshError::BadGeometry(format!("{what} = {length} mm must be > 0")));
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(MeshError::BadGeometry(format!("element size {h} mm must be > 0")));
    }
    let n = (length / h - 1e-9).ceil().max(1.0);
    if n > 1.0e7 {
        return Err(MeshError::BadGeometry(format!("{what} = {length} mm at size {h} mm needs {n} intervals")));
    }
    Ok(n as usize)
}

/// y coordinates of the grid planes and the region of each y interval.
/// Grid planes along y, the region of each interval, and the region names.
type LayerGrid = (Vec<f64>, Vec<u16>, Vec<String>);

fn layer_grid(layers: &[Layer], h: f64) -> Result<LayerGrid, MeshError> {
    if layers.is_empty() {
        return Err(MeshError::BadGeometry("no layers".into()));
    }
    let mut names: Vec<String> = Vec::new();
    let mut ys = vec![0.0];
    let mut regions = Vec::new();
    let mut y0 = 0.0;
    for layer in layers {
        let n = intervals(layer.thickness_mm, h, &format!("layer `{}` thickness", layer.region))?;
        let region = match names.iter().position(|r| *r == layer.region) {
            Some(i) => i,
            None => {
                names.push(layer.region.clone());
                names.len() - 1
            }
        } as u16;
        for i in 1..=n {
            ys.push(y0 + layer.thickness_mm * i as f64 / n as f64);
            regions.push(region);
        }
        y0 += layer.thickness_mm;
    }
    Ok((ys, regions, names))
}

/// A `width` x `height` rectangle (x right, y up) of one region.
pub fn rectangle(width_mm: f64, height_mm: f64, size_mm: f64, region: &str) -> Result<TriMesh, MeshError> {
    layered_rectangle(width_mm, &[Layer { region: region.into(), thickness_mm: height_mm }], size_mm)
}

/// A rectangle of layers stacked along y.
pub fn layered_rectangle(width_mm: f64, layers: &[Layer], size_mm: f64) -> Result<TriMesh, MeshError> {
    let nx = intervals(width_mm, size_mm, "width")?;
    let (ys, layer_of_row, region_names) = layer_grid(layers, size_mm)?;
    let ny = ys.len() - 1;
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
    for &y in &ys {
        for i in 0..=nx {
            nodes.push([width_mm * i as f64 / nx as f64, y]);
        }
    }
    let mut cells = Vec::with_capacity(2 * nx * ny);
    let mut cell_regions = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            cells.push([a, b, c]);
            cells.push([a, c, d]);
            cell_regions.extend([layer_of_row[j]; 2]);
        }
    }
    let height = *ys.last().unwrap();
    let mut mesh =
        TriMesh { nodes, cells, cell_regions, region_names, node_sets: BTreeMap::new(), face_sets: BTreeMap::new() };
    add_bottom_top(&mut mesh, height);
    Ok(mesh)
}

/// The axisymmetric section `[0, R] x [0, H]` (x = r, y up) of a cylinder of
/// `radius` and `height` with its axis along y, for
/// [`crate::element::Formulation::Axisymmetric`]: a [`rectangle`] with the node set
/// `axis` (the nodes on r = 0) besides `bottom` and `top`.
pub fn axisymmetric_section(radius_mm: f64, height_mm: f64, size_mm: f64, region: &str) -> Result<TriMesh, MeshError> {
    layered_axisymmetric_section(radius_mm, &[Layer { region: region.into(), thickness_mm: height_mm }], size_mm)
}

/// The axisymmetric section of a cylinder of layers stacked along y (see
/// [`axisymmetric_section`]).
pub fn layered_axisymmetric_section(radius_mm: f64, layers: &[Layer], size_mm: f64) -> Result<TriMesh, MeshError> {
    let mut mesh = layered_rectangle(radius_mm, layers, size_mm).map_err(|e| match e {
        MeshError::BadGeometry(m) => MeshError::BadGeometry(m.replace("width", "radius")),
        other => other,
    })?;
    // Grid nodes at r = 0 are exactly 0.0.
    mesh.add_node_set("axis", |p| p[0] == 0.0);
    Ok(mesh)
}

/// The axisymmetric section `[0, R] x [0, H]` of a cylinder graded toward the
/// centre of its top face, for indentation: spacing `fine_mm` within `fine_extent_mm`
/// of the axis (in r) and of the top (in y), then growing by `growth` per element
/// out to the radius and down to the floor. Node sets `bottom`, `top`, `axis`.
pub fn indentation_section(
    radius_mm: f64,
    height_mm: f64,
    fine_mm: f64,
    fine_extent_mm: f64,
    growth: f64,
    region: &str,
) -> Result<TriMesh, MeshError> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    let sizes_ok = positive(radius_mm) && positive(height_mm) && positive(fine_mm) && positive(fine_extent_mm);
    if !(sizes_ok && growth.is_finite() && growth >= 1.0) || fine_mm > fine_extent_mm.min(radius_mm).min(height_mm) {
        return Err(MeshError::BadGeometry(format!(
            "indentation section: radius {radius_mm}, height {height_mm}, fine size {fine_mm} within \
             {fine_extent_mm} mm, growth {growth}: sizes must be > 0, the fine size below the extents, growth >= 1"
        )));
    }
    let graded = |length: f64| graded_coordinates(length, fine_mm, fine_extent_mm, growth);
    let rs = graded(radius_mm);
    let ys: Vec<f64> = graded(height_mm).into_iter().rev().map(|d| height_mm - d).collect();
    let (nr, ny) = (rs.len() - 1, ys.len() - 1);
    let id = |i: usize, j: usize| (j * (nr + 1) + i) as u32;
    let mut nodes = Vec::with_capacity((nr + 1) * (ny + 1));
    for &y in &ys {
        for &r in &rs {
            nodes.push([r, y]);
        }
    }
    let mut cells = Vec::with_capacity(2 * nr * ny);
    for j in 0..ny {
        for i in 0..nr {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            cells.push([a, b, c]);
            cells.push([a, c, d]);
        }
    }
    let mut mesh = TriMesh {
        nodes,
        cell_regions: vec![0; cells.len()],
        cells,
        region_names: vec![region.to_string()],
        node_sets: BTreeMap::new(),
        face_sets: BTreeMap::new(),
    };
    add_bottom_top(&mut mesh, height_mm);
    mesh.add_node_set("axis", |p| p[0] == 0.0);
    Ok(mesh)
}

/// Distances from 0 to `length`: spacing `fine` up to `extent`, then growing by
/// `growth` per interval; the last interval is merged when it would be shorter than
/// half the one before.
fn graded_coordinates(length: f64, fine: f64, extent: f64, growth: f64) -> Vec<f64> {
    let mut x = vec![0.0];
    let mut h = fine;
    while *x.last().expect("starts with 0") < length {
        let last = *x.last().expect("starts with 0");
        if last >= extent {
            h *= growth;
        }
        x.push((last + h).min(length));
    }
    let n = x.len();
    if n > 2 && x[n - 1] - x[n - 2] < 0.5 * (x[n - 2] - x[n - 3]) {
        x.remove(n - 2);
    }
    x
}

/// Kuhn simplices of an `n[0] x n[1] x n[2]` grid of cells, cell by cell in x, y, z
/// order (six per cell): walk from corner (0,0,0) to (1,1,1) adding unit steps in
/// every axis order; an odd permutation gives a negatively oriented path, which is
/// swapped. Neighbouring cells share their faces' diagonals, so the mesh conforms.
fn kuhn_tets(n: [usize; 3], id: impl Fn(usize, usize, usize) -> u32) -> Vec<[u32; 4]> {
    const ORDERS: [([usize; 3], bool); 6] = [
        ([0, 1, 2], false),
        ([1, 2, 0], false),
        ([2, 0, 1], false),
        ([0, 2, 1], true),
        ([2, 1, 0], true),
        ([1, 0, 2], true),
    ];
    let mut cells = Vec::with_capacity(6 * n[0] * n[1] * n[2]);
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                for (order, odd) in ORDERS {
                    let mut c = [i, j, k];
                    let mut tet = [id(c[0], c[1], c[2]); 4];
                    for (s, &axis) in order.iter().enumerate() {
                        c[axis] += 1;
                        tet[s + 1] = id(c[0], c[1], c[2]);
                    }
                    if odd {
                        tet.swap(2, 3);
                    }
                    cells.push(tet);
                }
            }
        }
    }
    cells
}

/// A `size = [W, H, T]` block (x, y, z) of one region.
pub fn block(size_mm: [f64; 3], element_size_mm: f64, region: &str) -> Result<TetMesh, MeshError> {
    layered_block(size_mm[0], size_mm[2], &[Layer { region: region.into(), thickness_mm: size_mm[1] }], element_size_mm)
}

/// A block of width `W` (x) and thickness `T` (z) made of layers stacked along y.
pub fn layered_block(width_mm: f64, thickness_mm: f64, layers: &[Layer], size_mm: f64) -> Result<TetMesh, MeshError> {
    let nx = intervals(width_mm, size_mm, "width")?;
    let nz = intervals(thickness_mm, size_mm, "thickness")?;
    let (ys, layer_of_row, region_names) = layer_grid(layers, size_mm)?;
    let ny = ys.len() - 1;
    let num_nodes = (nx + 1) * (ny + 1) * (nz + 1);
    if num_nodes > u32::MAX as usize / 2 {
        return Err(MeshError::BadGeometry(format!("{num_nodes} nodes is too many")));
    }
    let id = |i: usize, j: usize, k: usize| ((k * (ny + 1) + j) * (nx + 1) + i) as u32;
    let mut nodes = Vec::with_capacity(num_nodes);
    for k in 0..=nz {
        for &y in &ys {
            for i in 0..=nx {
                nodes.push([width_mm * i as f64 / nx as f64, y, thickness_mm * k as f64 / nz as f64]);
            }
        }
    }
    let cells = kuhn_tets([nx, ny, nz], id);
    // Six tets per grid cell, cells in x, y, z order: the row of a tet is its cell's j.
    let cell_regions = (0..cells.len()).map(|c| layer_of_row[(c / 6 / nx) % ny]).collect();
    let height = *ys.last().unwrap();
    let mut mesh =
        TetMesh { nodes, cells, cell_regions, region_names, node_sets: BTreeMap::new(), face_sets: BTreeMap::new() };
    add_bottom_top(&mut mesh, height);
    Ok(mesh)
}

/// A cylinder of `radius` and `height` with its axis along y, centred on x = z = 0.
///
/// The disk is meshed in rings (ring k has 6k nodes), extruded along y, and each
/// prism split into three tetrahedra by the global-index rule, which keeps
/// neighbouring prisms conforming.
pub fn cylinder(radius_mm: f64, height_mm: f64, size_mm: f64, region: &str) -> Result<TetMesh, MeshError> {
    let num_rings = intervals(radius_mm, size_mm, "radius")?;
    let ny = intervals(height_mm, size_mm, "height")?;
    // Disk nodes, ring by ring.
    let mut disk: Vec<[f64; 2]> = vec![[0.0, 0.0]];
    let mut ring_start = vec![0usize];
    for ring in 1..=num_rings {
        ring_start.push(disk.len());
        let n = 6 * ring;
        let r = radius_mm * ring as f64 / num_rings as f64;
        for j in 0..n {
            let th = std::f64::consts::TAU * j as f64 / n as f64;
            disk.push([r * th.cos(), r * th.sin()]);
        }
    }
    // Disk triangles between consecutive rings, merged by angle.
    let mut tris: Vec<[usize; 3]> = Vec::new();
    for ring in 1..=num_rings {
        let (s_in, s_out) = (ring_start[ring - 1], ring_start[ring]);
        let n_out = 6 * ring;
        if ring == 1 {
            for j in 0..n_out {
                tris.push([s_in, s_out + j, s_out + (j + 1) % n_out]);
            }
            continue;
        }
        let n_in = 6 * (ring - 1);
        let (mut i, mut j) = (0usize, 0usize);
        while i + j < n_in + n_out {
            let ang_in = (i + 1) as f64 / n_in as f64;
            let ang_out = (j + 1) as f64 / n_out as f64;
            let a = s_in + i % n_in;
            let b = s_out + j % n_out;
            if j < n_out && (i == n_in || ang_out <= ang_in) {
                tris.push([a, b, s_out + (j + 1) % n_out]);
                j += 1;
            } else {
                tris.push([a, b, s_in + (i + 1) % n_in]);
                i += 1;
            }
        }
    }
    // Orient counter-clockwise in the (x, z) plane seen from +y.
    for t in &mut tris {
        let (p, q, r) = (disk[t[0]], disk[t[1]], disk[t[2]]);
        let cross = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
        if cross < 0.0 {
            t.swap(1, 2);
        }
    }
    let nd = disk.len();
    let mut nodes = Vec::with_capacity(nd * (ny + 1));
    for j in 0..=ny {
        let y = height_mm * j as f64 / ny as f64;
        for p in &disk {
            nodes.push([p[0], y, p[1]]);
        }
    }
    let mut cells = Vec::with_capacity(3 * tris.len() * ny);
    for j in 0..ny {
        for t in &tris {
            let mut v = *t;
            v.sort_unstable();
            let lo = |k: usize| (j * nd + v[k]) as u32;
            let hi = |k: usize| ((j + 1) * nd + v[k]) as u32;
            for mut tet in [[lo(0), lo(1), lo(2), hi(0)], [lo(1), lo(2), hi(0), hi(1)], [lo(2), hi(0), hi(1), hi(2)]] {
                let x = tet.map(|n| nodes[n as usize]);
                if crate::element::signed_measure::<3, 4>(&x) < 0.0 {
                    tet.swap(2, 3);
                }
                cells.push(tet);
            }
        }
    }
    let num_cells = cells.len();
    let mut mesh = TetMesh {
        nodes,
        cells,
        cell_regions: vec![0; num_cells],
        region_names: vec![region.to_string()],
        node_sets: BTreeMap::new(),
        face_sets: BTreeMap::new(),
    };
    add_bottom_top(&mut mesh, height_mm);
    Ok(mesh)
}

fn add_bottom_top<const D: usize, const N: usize>(mesh: &mut super::SimplexMesh<D, N>, height: f64)
where
    crate::element::Simplex<D, N>: crate::element::ReferenceSimplex<D, N>,
{
    let tol = 1e-9 * height.max(1.0);
    mesh.add_node_set("bottom", |p| p[1].abs() <= tol);
    mesh.add_node_set("top", |p| (p[1] - height).abs() <= tol);
    mesh.add_face_set("bottom", |p| p[1].abs() <= tol);
    mesh.add_face_set("top", |p| (p[1] - height).abs() <= tol);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_volume_and_sets() {
        let m = block([58.0, 59.5, 12.0], 5.0, "mat1").unwrap();
        m.validate().unwrap();
        assert!((m.measure() - 58.0 * 59.5 * 12.0).abs() < 1e-8 * 58.0 * 59.5 * 12.0);
        // 12 x 12 x 3 cells.
        assert_eq!(m.num_cells(), 6 * 12 * 12 * 3);
        assert_eq!(m.node_sets["bottom"].len(), 13 * 4);
        let bottom_area: f64 = m.face_sets["bottom"].len() as f64;
        assert_eq!(bottom_area, (2 * 12 * 3) as f64);
        // Closed boundary: Euler characteristic of a sphere-like surface V - E + F = 2
        // is implied by every facet edge being shared by exactly two facets.
        let facets = m.boundary_facets();
        let mut edges = std::collections::BTreeMap::new();
        for f in &facets {
            for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                // Outward orientation: each directed edge appears once.
            }
        }
        assert!(edges.values().all(|&c| c == 2));
    }

    #[test]
    fn layered_block_regions_follow_layers() {
        let layers = [
            Layer { region: "mat1".into(), thickness_mm: 80.0 / 3.0 },
            Layer { region: "mat2".into(), thickness_mm: 80.0 / 3.0 },
            Layer { region: "mat1".into(), thickness_mm: 80.0 / 3.0 },
        ];
        let m = layered_block(60.0, 11.0, &layers, 6.0).unwrap();
        m.validate().unwrap();
        assert_eq!(m.region_names, vec!["mat1".to_string(), "mat2".to_string()]);
        for (e, &r) in m.cell_regions.iter().enumerate() {
            let x = m.cell_coordinates(e);
            let yc = x.iter().map(|p| p[1]).sum::<f64>() / 4.0;
            let expected = if (80.0 / 3.0..160.0 / 3.0).contains(&yc) { 1 } else { 0 };
            assert_eq!(r, expected, "cell {e} at y = {yc}");
        }
    }

    #[test]
    fn cylinder_is_valid_and_converges_to_its_volume() {
        let mut last_err = f64::INFINITY;
        for h in [2.0, 1.0, 0.5] {
            let m = cylinder(4.0, 9.0, h, "gel").unwrap();
            m.validate().unwrap();
            let exact = std::f64::consts::PI * 16.0 * 9.0;
            let err = (m.measure() - exact).abs() / exact;
            assert!(err < last_err, "volume error must fall under refinement");
            last_err = err;
            // Every boundary edge shared twice: the surface is closed and conforming.
            let mut edges = std::collections::BTreeMap::new();
            for f in m.boundary_facets() {
                for (a, b) in [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])] {
                    *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
            assert!(edges.values().all(|&c| c == 2), "non-conforming cylinder at h = {h}");
        }
        assert!(last_err < 0.01);
    }

    #[test]
    fn rectangle_area() {
        let m = rectangle(58.0, 59.5, 4.0, "mat1").unwrap();
        m.validate().unwrap();
        assert!((m.measure() - 58.0 * 59.5).abs() < 1e-9 * 58.0 * 59.5);
        assert!(m.node_sets["top"].iter().all(|&i| (m.nodes[i as usize][1] - 59.5).abs() < 1e-12));
    }

    #[test]
    fn axisymmetric_section_has_its_axis() {
        let m = axisymmetric_section(4.0, 9.0, 1.0, "gel").unwrap();
        m.validate().unwrap();
        assert!((m.measure() - 36.0).abs() < 1e-12 * 36.0);
        let axis = &m.node_sets["axis"];
        assert_eq!(axis.len(), 10);
        assert!(axis.iter().all(|&i| m.nodes[i as usize][0] == 0.0));
        assert_eq!(m.nodes.iter().filter(|p| p[0] == 0.0).count(), axis.len());
        assert!(m.node_sets["bottom"].len() == 5 && m.node_sets["top"].len() == 5);
        assert!(
            matches!(axisymmetric_section(-1.0, 9.0, 1.0, "gel"), Err(MeshError::BadGeometry(m)) if m.contains("radius"))
        );
    }

    #[test]
    fn bad_sizes_are_refused() {
        assert!(matches!(block([1.0, -1.0, 1.0], 0.5, "m"), Err(MeshError::BadGeometry(_))));
        assert!(matches!(rectangle(1.0, 1.0, 0.0, "m"), Err(MeshError::BadGeometry(_))));
    }
}
