//! Quality: Delaunay refinement (stage 3).
//!
//! Passes over the inside tets (classified by a flood that crosses no subfacet,
//! at the start of each pass), worst first. A tet is *bad* when its radius-edge
//! ratio exceeds the bound or its volume exceeds the largest allowed. Its
//! circumcentre is inserted unless the insertion would remove a subfacet (the
//! point encroaches it, or lies beyond the boundary): then that subfacet is
//! refined instead (its circumcentre on the facet, or a split of the subsegment
//! that one encroaches), and the facets whose subfacets went missing are
//! recovered before going on. The tetrahedralization stays Delaunay and
//! conforming throughout; a budget of points ends the passes (the mesh is valid
//! whenever they stop).

use super::recover::{interior_components, Recovery};
use super::ConformingError;
use crate::predicates::{cross, dot, sub, Point};

/// What refinement did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct RefineStats {
    /// Circumcentres of bad tets inserted.
    pub circumcentres: usize,
    /// Boundary refinements (a subfacet or subsegment split instead of a circumcentre).
    pub boundary_splits: usize,
    /// Passes run.
    pub passes: usize,
    /// Bad tets left when the passes stopped (0 when refinement converged).
    pub bad_left: usize,
}

/// Circumcentre and radius-edge ratio of a tet.
pub(crate) fn circumsphere(q: [Point; 4]) -> (Point, f64, f64) {
    let a = sub(q[1], q[0]);
    let b = sub(q[2], q[0]);
    let c = sub(q[3], q[0]);
    let det = dot(a, cross(b, c));
    let (aa, bb, cc) = (dot(a, a), dot(b, b), dot(c, c));
    let bc = cross(b, c);
    let ca = cross(c, a);
    let ab = cross(a, b);
    let num = [0, 1, 2].map(|k| aa * bc[k] + bb * ca[k] + cc * ab[k]);
    let off = [0, 1, 2].map(|k| num[k] / (2.0 * det));
    let centre = [0, 1, 2].map(|k| q[0][k] + off[k]);
    let r = dot(off, off).sqrt();
    let mut lmin = f64::INFINITY;
    for i in 0..4 {
        for j in i + 1..4 {
            let d = sub(q[j], q[i]);
            lmin = lmin.min(dot(d, d));
        }
    }
    (centre, r / lmin.sqrt(), det / 6.0)
}

impl Recovery {
    /// Delaunay refinement (module docs): radius-edge bound `bound`, largest
    /// volume `max_volume` (infinite: none), at most `budget` points added.
    pub fn refine(&mut self, bound: f64, max_volume: f64, budget: usize) -> Result<RefineStats, ConformingError> {
        let mut stats = RefineStats::default();
        let start_points = self.dt.points().len();
        let mut faces = Vec::new();
        for _pass in 0..64 {
            stats.passes += 1;
            let (inside, _) = interior_components(&self.dt, &self.face_owner);
            let pts = self.dt.points();
            let mut bad: Vec<(f64, u32, [u32; 4])> = inside
                .iter()
                .filter_map(|&(t, v, _)| {
                    let (_, re, vol) = circumsphere(v.map(|i| pts[i as usize]));
                    let badness = (re / bound).max(vol / max_volume);
                    (badness > 1.0).then_some((badness, t, v))
                })
                .collect();
            stats.bad_left = bad.len();
            if bad.is_empty() {
                break;
            }
            bad.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.2.cmp(&y.2)));
            for (_, t, v) in bad {
                if self.dt.points().len() - start_points >= budget {
                    return Ok(stats);
                }
                if self.dt.tet(t) != v {
                    continue; // gone since the pass started
                }
                let pts = self.dt.points();
                let (c, _, _) = circumsphere(v.map(|i| pts[i as usize]));
                if !c.iter().all(|x| x.is_finite()) || !self.dt.cavity_faces(c, &mut faces) {
                    continue;
                }
                // Of the subfacets the insertion would remove, the one whose
                // equatorial ball holds the point deepest (ties: lowest key).
                let pts = self.dt.points();
                let depth = |f: &[u32; 3]| {
                    let q = f.map(|v| pts[v as usize]);
                    let cc = super::recover::circumcentre(q);
                    let r2 = dot(sub(q[0], cc), sub(q[0], cc));
                    dot(sub(c, cc), sub(c, cc)) / r2
                };
                let hit = faces
                    .iter()
                    .filter(|f| self.face_owner.contains_key(*f))
                    .min_by(|x, y| depth(x).total_cmp(&depth(y)).then(x.cmp(y)))
                    .copied();
                match hit {
                    None => {
                        self.insert_free(c)?;
                        stats.circumcentres += 1;
                    }
                    Some(face) => {
                        let f = self.face_owner[&face] as usize;
                        let tri = self.facets[f]
                            .tris
                            .iter()
                            .copied()
                            .find(|t| {
                                let mut k = *t;
                                k.sort_unstable();
                                k == face
                            })
                            .unwrap_or(face);
                        self.refine_subfacet_pub(f, tri)?;
                        stats.boundary_splits += 1;
                    }
                }
                self.recover_pending()?;
            }
        }
        Ok(stats)
    }
}
