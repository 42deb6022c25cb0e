//! The generalized winding number of a triangle soup (Jacobson, Kavan and
//! Sorkine-Hornung 2013, "Robust Inside-Outside Segmentation using Generalized
//! Winding Numbers"), evaluated hierarchically (Barill et al. 2018).
//!
//! `w(q)` is the signed solid angle of the surface seen from `q`, over 4π: 1 inside
//! and 0 outside a closed, outward-oriented surface, 2 where two such shells overlap,
//! and a smooth value in between across the holes of an open scan. Inside means
//! `w > 0.5`. It needs no manifoldness, no welding and no closed shells, which is
//! why the envelope mesher uses it as its inside test.
//!
//! A shell (a region of the surface) given inside out is detected by the sign of
//! its enclosed volume ([`Surface::signed_volume`]) and counted with the opposite
//! sign, so an inverted file still has `w = 1` inside ([`WindingNumber::new`]).
//! Faces flipped here and there inside one shell are the business of the repair
//! (`repair.rs`); the winding number is wrong within about one triangle of them.
//!
//! ```
//! use meshing::{Surface, WindingNumber};
//!
//! // A tetrahedron, outward.
//! let s = Surface {
//!     vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
//!     triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
//!     triangle_regions: vec![0; 4],
//!     region_names: vec!["tet".into()],
//! };
//! let w = WindingNumber::new(&s);
//! assert!((w.at([0.1, 0.1, 0.1]) - 1.0).abs() < 1e-9);
//! assert!(w.is_inside([0.1, 0.1, 0.1]) && !w.is_inside([1.0, 1.0, 1.0]));
//! ```

use rayon::prelude::*;

use crate::envelope::tree::TriangleTree;
use crate::Surface;

/// Within this of 1/2, [`WindingNumber::is_inside_checked`] sums exactly: above
/// the far field's error (measured within 0.08 on the bunny's grid, test
/// `winding_number_of_the_bunny`; 0.0056 in the teapot handle's mouth).
pub(crate) const NEAR_HALF: f64 = 0.1;

/// The winding number of (part of) a surface, ready for fast queries.
#[derive(Debug, Clone)]
pub struct WindingNumber {
    tree: TriangleTree,
    num_flipped_regions: usize,
}

impl WindingNumber {
    /// The winding number of every triangle of `surface`, each region counted
    /// with the sign that makes its enclosed volume positive.
    pub fn new(surface: &Surface) -> Self {
        Self::build(surface, None)
    }

    /// The winding number of the triangles of region `region` only.
    pub fn of_region(surface: &Surface, region: u32) -> Self {
        Self::build(surface, Some(region))
    }

    fn build(surface: &Surface, only: Option<u32>) -> Self {
        let num_regions =
            surface.region_names.len().max(surface.triangle_regions.iter().map(|&r| r as usize + 1).max().unwrap_or(0));
        let flip: Vec<bool> = (0..num_regions as u32).map(|r| surface.signed_volume(Some(r)) < 0.0).collect();
        let num_flipped_regions =
            flip.iter().enumerate().filter(|(r, &f)| f && only.is_none_or(|o| o as usize == *r)).count();
        let tris = surface
            .triangles
            .iter()
            .enumerate()
            .filter_map(|(i, t)| {
                let r = surface.triangle_regions.get(i).copied().unwrap_or(0);
                if only.is_some_and(|o| o != r) {
                    return None;
                }
                let mut c = t.map(|v| surface.vertices[v as usize]);
                if flip.get(r as usize).copied().unwrap_or(false) {
                    c.swap(1, 2);
                }
                Some(c)
            })
            .collect();
        Self { tree: TriangleTree::new(tris), num_flipped_regions }
    }

    /// The winding number at `q` [mm].
    pub fn at(&self, q: [f64; 3]) -> f64 {
        self.tree.winding_number(q)
    }

    /// `w(q) > 0.5`.
    pub fn is_inside(&self, q: [f64; 3]) -> bool {
        self.at(q) > 0.5
    }

    /// `w(q) > 0.5` decided by the exact sum over every triangle where the fast
    /// value is within 0.1 of 1/2 (the far field errs by up to a few
    /// hundredths): a point where `w` is close to 1/2 (in the mouth of an open
    /// tube, across a hole) is classified as the solid `w > 1/2` defines it.
    /// Costs one fast evaluation, and a sum over all triangles near 1/2.
    pub fn is_inside_checked(&self, q: [f64; 3]) -> bool {
        self.tree.is_inside_checked(q)
    }

    /// The winding number at each point, in parallel (same result at any thread count).
    pub fn at_many(&self, points: &[[f64; 3]]) -> Vec<f64> {
        points.par_iter().map(|&q| self.at(q)).collect()
    }

    /// The fraction of the points of a regular `n x n x n` grid over the box
    /// `lo..hi` [mm] (cell centres) whose winding number is ambiguous, between 0.25
    /// and 0.75: about 0 for a closed, consistently oriented surface; large when
    /// faces are flipped here and there or the surface is open wide. A cheap
    /// measure to choose between two versions of a surface (e.g. before and
    /// after repair); the same at any thread count.
    pub fn ambiguous_fraction(&self, lo: [f64; 3], hi: [f64; 3], n: usize) -> f64 {
        let n = n.max(1);
        let points: Vec<[f64; 3]> = (0..n * n * n)
            .map(|i| {
                let (a, b, c) = (i % n, (i / n) % n, i / (n * n));
                let f = |k: usize, j: usize| lo[k] + (hi[k] - lo[k]) * (j as f64 + 0.5) / n as f64;
                [f(0, a), f(1, b), f(2, c)]
            })
            .collect();
        let ambiguous = self.at_many(&points).iter().filter(|w| (0.25..=0.75).contains(&w.abs())).count();
        ambiguous as f64 / points.len() as f64
    }

    /// How many regions were given inside out and are counted flipped.
    pub fn num_flipped_regions(&self) -> usize {
        self.num_flipped_regions
    }

    /// The tree of (sign-corrected) triangles.
    pub(crate) fn tree(&self) -> &TriangleTree {
        &self.tree
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flipped_face_makes_the_inside_ambiguous() {
        let mut s = Surface {
            vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            triangle_regions: vec![0; 4],
            region_names: vec!["tet".into()],
        };
        let (lo, hi) = s.bounding_box();
        assert_eq!(WindingNumber::new(&s).ambiguous_fraction(lo, hi, 8), 0.0);
        s.triangles[3] = [1, 3, 2];
        assert!(WindingNumber::new(&s).ambiguous_fraction(lo, hi, 8) > 0.05);
    }
}
