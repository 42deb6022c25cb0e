//! Regions of a tetrahedral mesh: nested shells and layers cut by planes.
//!
//! Both work on any [`TetMesh`] and make the interfaces **conforming**: no cell
//! crosses a region shell or a layer plane afterwards, so every region is a union
//! of whole cells bounded by mesh faces. For each interface (the envelope module's
//! `cut.rs` does the work):
//!
//! 1. nodes are inside, outside or on it (within `1e-9` of the mesh's diagonal);
//! 2. each edge from inside to outside gets its crossing point (exact for a plane;
//!    for a shell, the crossing of the segment with its triangles where the
//!    shell's winding number changes side, or the bisection of `w = 1/2`);
//! 3. a node closer to such a crossing than 0.3 of the edge's length moves onto
//!    it, if its cells stay positive and no worse than a shape measure of 0.25
//!    (`6 √2 V / l_rms³`, 0.93 for a BCC lattice tet) — this keeps the cut pieces
//!    from being slivers; boundary nodes move only along boundary edges (so the
//!    boundary keeps its shape) and nodes on earlier interfaces never move;
//! 4. cells with nodes on both sides are split along the crossings (tets,
//!    pyramids and prisms; quadrilaterals by the diagonal through the smallest
//!    node index, which both neighbours agree on).
//!
//! Old nodes keep their indices and new ones are appended; node and face sets are
//! cleared (their faces may have been split): rebuild the ones you need.
//!
//! - [`cut_shells`]: each region of the surface (an OBJ object or group, a glTF
//!   mesh) is cut in, largest enclosed volume first, and each cell belongs to the
//!   **smallest** region whose shell contains it (it has a node inside and none
//!   outside; a cell with every node on the shell is decided at its centroid). So
//!   a filling inside a skin is its own region, and of two overlapping shells the
//!   smaller wins the overlap.
//! - [`cut_into_layers`]: planes `y = c` (from [`layer_planes`], thicknesses
//!   bottom-up like a bundle's layers); each cell belongs to the layer holding its
//!   centroid, regions `layer1` (bottom), `layer2`, ...

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` also refuses NaN, deliberately.

use fem_core::mesh::TetMesh;
use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;

use crate::envelope::cut::{self, Interface, PlaneY, Work};
use crate::envelope::stuffing::find_cut;
use crate::envelope::tree::{lerp, scale};
use crate::{Surface, WindingNumber};

type P = [f64; 3];

/// What cutting interfaces into a mesh did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct InterfaceStats {
    /// Interfaces cut in.
    pub interfaces: usize,
    /// Nodes moved onto an interface.
    pub moved_nodes: usize,
    /// Nodes added on interfaces.
    pub new_nodes: usize,
}

/// Layer thicknesses that do not fit the shape.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LayerError {
    /// A thickness that is not a positive length.
    #[error("layer {layer} has thickness {thickness_mm} mm: must be finite and > 0")]
    BadThickness {
        /// 1-based layer, bottom-up.
        layer: usize,
        /// The thickness given [mm].
        thickness_mm: f64,
    },
    /// The layers do not add up to the shape's height.
    #[error(
        "the layers add up to {total_mm} mm but the shape is {height_mm} mm tall along y \
         (from {y_lo_mm} to {y_hi_mm} mm); they must agree within 1 %"
    )]
    Height {
        /// Sum of the thicknesses [mm].
        total_mm: f64,
        /// The shape's height [mm].
        height_mm: f64,
        /// Its lowest y [mm].
        y_lo_mm: f64,
        /// Its highest y [mm].
        y_hi_mm: f64,
    },
}

/// The planes between layers of thicknesses `layers_mm` [mm] (bottom-up) stacked
/// from `y_lo` [mm]; they must add up to `y_hi - y_lo` within 1 % (the last layer
/// reaches the top whatever its exact thickness). One layer: no plane.
pub fn layer_planes(layers_mm: &[f64], y_lo: f64, y_hi: f64) -> Result<Vec<f64>, LayerError> {
    if let Some((i, &t)) = layers_mm.iter().enumerate().find(|(_, t)| !(t.is_finite() && **t > 0.0)) {
        return Err(LayerError::BadThickness { layer: i + 1, thickness_mm: t });
    }
    if layers_mm.is_empty() {
        return Ok(Vec::new());
    }
    let total: f64 = layers_mm.iter().sum();
    let height = y_hi - y_lo;
    if !((total - height).abs() <= 0.01 * height) {
        return Err(LayerError::Height { total_mm: total, height_mm: height, y_lo_mm: y_lo, y_hi_mm: y_hi });
    }
    let mut y = y_lo;
    Ok(layers_mm[..layers_mm.len() - 1]
        .iter()
        .map(|t| {
            y += t;
            y
        })
        .collect())
}

/// Cuts the planes `y = planes_y_mm[i]` [mm] into `mesh` and tags each cell with
/// its layer (see the module docs).
pub fn cut_into_layers(mesh: &mut TetMesh, planes_y_mm: &[f64]) -> InterfaceStats {
    let eps = 1e-9 * diagonal(mesh);
    let mut work = to_work(mesh);
    let mut stats = InterfaceStats::default();
    for &y in planes_y_mm {
        let r = cut::cut(&mut work, &PlaneY { y, eps });
        stats.interfaces += 1;
        stats.moved_nodes += r.num_moved;
        stats.new_nodes += r.new_nodes_from.len();
    }
    let regions = work
        .cells
        .iter()
        .map(|c| {
            let y = c.iter().map(|&v| work.nodes[v as usize][1]).sum::<f64>() / 4.0;
            planes_y_mm.iter().filter(|&&p| y > p).count() as u16
        })
        .collect();
    let names = (1..=planes_y_mm.len() + 1).map(|i| format!("layer{i}")).collect();
    from_work(mesh, work, regions, names);
    stats
}

/// Cuts the shell of each region of `surface` into `mesh` and tags each cell
/// with the smallest region containing it (see the module docs). The mesh's
/// region names become the surface's.
pub fn cut_shells(mesh: &mut TetMesh, surface: &Surface) -> InterfaceStats {
    let num_regions = surface
        .region_names
        .len()
        .max(surface.triangle_regions.iter().map(|&r| r as usize + 1).max().unwrap_or(1))
        .max(1);
    let names: Vec<String> = (0..num_regions)
        .map(|r| surface.region_names.get(r).cloned().unwrap_or_else(|| format!("region{r}")))
        .collect();
    let eps = 1e-9 * diagonal(mesh).max(surface.diagonal());
    let mut work = to_work(mesh);
    let (regions, stats) = tag_shells(surface, &mut work, eps, num_regions);
    from_work(mesh, work, regions, names);
    stats
}

fn diagonal(mesh: &TetMesh) -> f64 {
    if mesh.nodes.is_empty() {
        return 0.0;
    }
    let (lo, hi) = mesh.bounding_box();
    (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
}

fn to_work(mesh: &TetMesh) -> Work {
    Work { locked: vec![false; mesh.nodes.len()], nodes: mesh.nodes.clone(), cells: mesh.cells.clone() }
}

fn from_work(mesh: &mut TetMesh, work: Work, regions: Vec<u16>, names: Vec<String>) {
    mesh.nodes = work.nodes;
    mesh.cells = work.cells;
    mesh.cell_regions = regions;
    mesh.region_names = names;
    mesh.node_sets.clear();
    mesh.face_sets.clear();
}

/// A region's shell as an interface.
struct Shell<'a> {
    winding: &'a WindingNumber,
    eps: f64,
}

impl Interface for Shell<'_> {
    fn side(&self, p: P) -> i8 {
        // On the shell by distance alone: on a triangle, the winding number's
        // principal value is anything between 0 and 1.
        if self.winding.tree().closest_point_within(p, self.eps).is_some() {
            0
        } else if self.winding.at(p) > 0.5 {
            -1
        } else {
            1
        }
    }
    fn cut(&self, a: P, b: P) -> P {
        lerp(a, b, find_cut(self.winding.tree(), a, b))
    }
}

/// Cuts each region's shell into `work`, largest first; the region of each cell.
fn tag_shells(surface: &Surface, work: &mut Work, eps: f64, num_regions: usize) -> (Vec<u16>, InterfaceStats) {
    let mut stats = InterfaceStats::default();
    if num_regions < 2 {
        return (vec![0; work.cells.len()], stats);
    }
    let windings: Vec<WindingNumber> = (0..num_regions as u32).map(|r| WindingNumber::of_region(surface, r)).collect();
    let volumes: Vec<f64> = (0..num_regions as u32).map(|r| surface.signed_volume(Some(r)).abs()).collect();
    let mut order: Vec<usize> = (0..num_regions).collect();
    order.sort_by(|&a, &b| volumes[b].total_cmp(&volumes[a]).then(a.cmp(&b)));
    // sides[r][node]: the side of region r's shell, once it is cut in.
    let mut sides: Vec<Option<Vec<i8>>> = vec![None; num_regions];
    for &r in &order {
        let res = cut::cut(work, &Shell { winding: &windings[r], eps });
        stats.interfaces += 1;
        stats.moved_nodes += res.num_moved;
        stats.new_nodes += res.new_nodes_from.len();
        // Earlier shells' sides of the new nodes: from their edge, which crossed none of them.
        for s in sides.iter_mut().flatten() {
            for &(a, b) in &res.new_nodes_from {
                let (sa, sb) = (s[a as usize], s[b as usize]);
                s.push(if sa != 0 { sa } else { sb });
            }
        }
        for (v, &sv) in res.side.iter().enumerate() {
            if sv == 0 {
                work.locked[v] = true;
            }
        }
        sides[r] = Some(res.side);
    }
    let nodes = &work.nodes;
    let regions = work
        .cells
        .par_iter()
        .map(|c| {
            let centroid = || -> P {
                let mut p = [0.0; 3];
                for &v in c {
                    let q = nodes[v as usize];
                    p = [p[0] + q[0], p[1] + q[1], p[2] + q[2]];
                }
                scale(p, 0.25)
            };
            // Smallest region first.
            for &r in order.iter().rev() {
                let s = sides[r].as_ref().map_or([0; 4], |s| c.map(|v| s[v as usize]));
                let inside = if s.contains(&-1) {
                    !s.contains(&1)
                } else if s.contains(&1) {
                    false
                } else {
                    windings[r].is_inside(centroid())
                };
                if inside {
                    return r as u16;
                }
            }
            // Inside the union but inside no single region (open shells of several
            // regions closing each other): the region of largest winding number.
            let p = centroid();
            let mut best = (f64::NEG_INFINITY, 0usize);
            for &r in &order {
                let w = windings[r].at(p);
                if w > best.0 {
                    best = (w, r);
                }
            }
            best.1 as u16
        })
        .collect();
    (regions, stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layer_planes_stack_from_the_bottom_and_check_the_height() {
        assert_eq!(layer_planes(&[20.0, 20.0, 19.5], 0.0, 59.5).unwrap(), vec![20.0, 40.0]);
        assert_eq!(layer_planes(&[1.0], -1.0, 0.0).unwrap(), Vec::<f64>::new());
        let e = layer_planes(&[20.0, 20.0], 0.0, 59.5).unwrap_err();
        assert!(e.to_string().contains("add up to 40 mm but the shape is 59.5 mm tall"), "{e}");
        let e = layer_planes(&[20.0, -1.0], 0.0, 19.0).unwrap_err();
        assert_eq!(e, LayerError::BadThickness { layer: 2, thickness_mm: -1.0 });
    }

    #[test]
    fn a_block_cut_into_layers_keeps_its_volume_and_conforms() {
        let mut mesh = fem_core::mesh::block([2.0, 3.0, 1.0], 0.5, "gel").unwrap();
        let before = mesh.measure();
        let stats = cut_into_layers(&mut mesh, &[0.8, 1.9]);
        assert_eq!(stats.interfaces, 2);
        assert!(mesh.validate().is_ok());
        assert!((mesh.measure() - before).abs() < 1e-12 * before);
        let vol = |r: u16| -> f64 {
            mesh.cells
                .iter()
                .zip(&mesh.cell_regions)
                .filter(|(_, &cr)| cr == r)
                .map(|(c, _)| fem_core::element::signed_measure(&c.map(|v| mesh.nodes[v as usize])))
                .sum()
        };
        for (r, expect) in [(0u16, 2.0 * 0.8), (1, 2.0 * 1.1), (2, 2.0 * 1.1)] {
            assert!((vol(r) - expect).abs() < 1e-12, "layer {r}: {} vs {expect}", vol(r));
        }
        assert_eq!(mesh.region_names, vec!["layer1", "layer2", "layer3"]);
    }
}
