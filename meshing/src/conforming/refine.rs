//! Quality: Delaunay refinement (stage 3).
//!
//! First the facets are refined for quality where size refinement would not
//! (`Recovery::refine_facet_quality`, [`FACET_QUALITY_EDGE`]). Then passes
//! over the inside tets (classified by a flood that crosses no subfacet, at
//! the start of each pass), worst first. A tet is *bad* when its radius-edge
//! ratio exceeds the bound, its volume exceeds the largest allowed, or its
//! smallest dihedral angle is under the sliver bound ([`Bounds`]).
//!
//! For a bad tet with circumcentre `c` and circumradius `r`, candidate points
//! are `c`, [`CANDIDATES`] - 1 points drawn in the ball of radius
//! [`OFF_CENTRE`] `r` about it and up to two off-centres between `c` and the
//! tet's shortest edge (`off_centres`; on the hinge they lowered the p99.9
//! radius-edge ratio from 4.10 to 3.95 and the largest from 18.3 to 7.4) (for a flat tet, whose circumcentre is at
//! infinity or far off, `c` is its centroid and `r` half its longest edge) (a generator seeded by the tet's corners: the run
//! is deterministic). The star each candidate would create is computed without
//! inserting it (`Delaunay::probe_star`, the candidates of a tet in
//! parallel), and a candidate is *blocked* when its
//! insertion would remove a subfacet (it lies beyond the boundary or too near
//! it) or when it encroaches a subfacet among the faces of its cavity (lies in
//! the subfacet's equatorial ball): Shewchuk's rule, which keeps interior points
//! away from the boundary so that refinement near it does not cascade. Of the
//! free candidates the one whose star has the largest smallest dihedral angle is
//! inserted (Li and Teng's idea of choosing, near the circumcentre, a point that
//! creates no sliver). When every candidate is blocked: a tet over the volume
//! bound refines the subfacet that `c` encroaches most deeply (see
//! `Recovery::refine_subfacet`); a *cap* (two faces on input triangles meeting
//! at a hinge flatter than [`CAP_HINGE_DEG`]) gets the hinge's subsegment
//! split when the hinge is the longest edge of both subfacets (longest-edge
//! bisection; a shorter hinge's splits cascaded on the armadillo, module docs
//! of `conforming`); a tet on four input vertices refines the subfacet its circumcentre
//! blocks on (smoothing cannot move its corners, so nothing else would fix it);
//! a tet of ratio over [`PLANE_RADIUS_EDGE`] refines the subfacet of a merged
//! plane its circumcentre blocks on; any other tet is left (module docs of
//! `conforming`, "What is not done"), and so is a tet with no free candidate
//! whose circumcentre is a vertex already or beyond the hull. The facets whose subfacets went missing are recovered before going
//! on. A tet that is bad only as a sliver is also left when no free
//! candidate's star is better than it (it then waits for `smooth.rs`); a tet
//! left is not tried again.
//!
//! The tetrahedralization stays Delaunay and conforming throughout; a budget of
//! points ends the passes (the mesh is valid whenever they stop).

use super::delaunay::{Probe, ProbeScratch, GHOST};
use super::order::SplitMix;
use std::cell::RefCell;

use rayon::prelude::*;

use super::recover::{interior_components, Recovery};
use super::ConformingError;
use crate::predicates::{cross, dot, sub, Point};
use crate::quality::{dihedral_cos_range, dihedral_range_deg};

/// Candidate points per bad tet (the circumcentre and points near it).
pub const CANDIDATES: usize = 8;
/// The radius of the ball about the circumcentre that candidates are drawn from,
/// as a fraction of the circumradius.
pub const OFF_CENTRE: f64 = 0.3;

/// A tet whose radius-edge ratio exceeds this, and all of whose candidates
/// are blocked by a subfacet of a merged plane of the input (a facet of more
/// than one input triangle) with circumradius at least the tet's shortest
/// edge, refines that subfacet. Without the facets refined for quality first
/// (hinge: p99.9 radius-edge ratio, smallest dihedral angle), 2.3 is the
/// smallest bound that keeps every tet of the hinge over 10 deg (2.0 gives
/// 2.08 but 5.00 deg; 1.5 gives 8.5 and 1.84 deg). With the facets refined
/// first ([`FACET_QUALITY_EDGE`]) these slivers do not come:
/// measured on the hinge, 2.3 gives 1.90, 1.5 gives 1.74 (10.03 deg), 1.414
/// gives 1.78.
pub const PLANE_RADIUS_EDGE: f64 = 1.5;

/// Before the tets are refined, the subfacets whose radius-edge ratio
/// exceeds the tets' bound and whose shortest edge is under this many target
/// edge lengths are refined (Ruppert's rule in each facet's plane,
/// `Recovery::refine_facet_quality`): those are the skinny subfacets next to
/// short input edges, which size refinement would not split, and every tet on
/// one has at least its radius-edge ratio. Measured on the hinge (p99.9
/// radius-edge ratio): 2.23 without, 1.74 with; without the length limit the
/// coarse subfacets of two boxes sharing a face were split too early and
/// their ratio rose from 1.38 to 1.41 (over TetGen's 1.401).
pub const FACET_QUALITY_EDGE: f64 = 2.0;

/// A sliver with two faces on the boundary whose dihedral angle at their shared
/// edge exceeds this [deg] is a *cap* over a nearly flat hinge of the input.
pub const CAP_HINGE_DEG: f64 = 150.0;

/// What makes a tet bad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Largest circumradius over shortest edge (infinite: none).
    pub radius_edge: f64,
    /// Largest volume [mm^3] (infinite: none).
    pub max_volume: f64,
    /// Smallest dihedral angle [deg] (0: none).
    pub min_dihedral_deg: f64,
}

/// What refinement did.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct RefineStats {
    /// Circumcentres of bad tets inserted.
    pub circumcentres: usize,
    /// Boundary refinements (a subfacet or subsegment split instead of a circumcentre).
    pub boundary_splits: usize,
    /// Passes run.
    pub passes: usize,
    /// Slivers left alone (no candidate made a better star).
    pub slivers_skipped: usize,
    /// Whether quality refinement failed (a recovery it triggered did not
    /// converge) and size refinement ran alone instead.
    pub quality_failed: bool,
    /// Bad tets left when the passes stopped (0 when refinement converged).
    pub bad_left: usize,
    /// Points added by refining the facets for quality before the tets
    /// ([`FACET_QUALITY_EDGE`]).
    pub facet_points: usize,
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
    /// Delaunay refinement (module docs) to `bounds`, at most `budget` points added.
    pub fn refine(&mut self, bounds: Bounds, budget: usize) -> Result<RefineStats, ConformingError> {
        let mut stats = RefineStats::default();
        let start_points = self.dt.points().len();
        // Never iterated: its hasher cannot reach the output.
        let mut skipped: rustc_hash::FxHashSet<[u32; 4]> = Default::default();
        // Cap splits at most as many as the points present when refinement
        // starts: on some inputs they would otherwise cascade along the surface.
        let mut caps_left = start_points;
        // Ruppert's refinement of the facets first (module docs), for the
        // subfacets size refinement would not split anyway.
        if bounds.radius_edge.is_finite() {
            let h = (bounds.max_volume * 6.0 * 2f64.sqrt()).cbrt();
            stats.facet_points = self.refine_facet_quality(bounds.radius_edge, FACET_QUALITY_EDGE * h, 16)?;
        }
        // The corners of the tet last found good in each slot of the
        // tetrahedralization: a pass evaluates only the tets created since
        // (the passes rescanned every tet, about 1e6 on the armadillo).
        let mut good: Vec<[u32; 4]> = Vec::new();
        for _pass in 0..64 {
            stats.passes += 1;
            let (inside, _) = interior_components(self);
            let pts = self.dt.points();
            let mut bad: Vec<(f64, u32, [u32; 4], bool, bool, f64)> = Vec::new();
            for &(t, v, _) in &inside {
                // A tet found good in an earlier pass is still there, with
                // the same corners (refinement never moves a point): good still.
                if good.get(t as usize) == Some(&v) {
                    continue;
                }
                let q = v.map(|i| pts[i as usize]);
                let (_, re, vol) = circumsphere(q);
                let too_big = vol / bounds.max_volume;
                let size = (re / bounds.radius_edge).max(too_big);
                let sliver = if bounds.min_dihedral_deg > 0.0 {
                    let d = dihedral_range_deg(&q).0;
                    if d < bounds.min_dihedral_deg {
                        bounds.min_dihedral_deg / d.max(1e-6)
                    } else {
                        0.0
                    }
                } else {
                    0.0
                };
                let only_sliver = size <= 1.0;
                let badness = size.max(sliver);
                if badness <= 1.0 {
                    if good.len() <= t as usize {
                        good.resize(t as usize + 1, [GHOST; 4]);
                    }
                    good[t as usize] = v;
                } else if !skipped.contains(&v) {
                    bad.push((badness, t, v, only_sliver, too_big > 1.0, re));
                }
            }
            stats.bad_left = bad.len();
            if bad.is_empty() {
                break;
            }
            bad.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.2.cmp(&y.2)));
            for (_, t, v, only_sliver, too_big, re) in bad {
                if self.dt.points().len() - start_points >= budget {
                    return Ok(stats);
                }
                if self.dt.tet(t) != v {
                    continue; // gone since the pass started
                }
                let pts = self.dt.points();
                let q = v.map(|i| pts[i as usize]);
                let (c, _, _) = circumsphere(q);
                let longest = (0..4)
                    .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
                    .map(|(i, j)| dot(sub(q[j], q[i]), sub(q[j], q[i])).sqrt())
                    .fold(0.0, f64::max);
                let r = dot(sub(q[0], c), sub(q[0], c)).sqrt();
                // A flat tet (coplanar corners: its circumcentre is at infinity
                // or far off): candidates about its centroid instead.
                let (c, r) = if c.iter().all(|x| x.is_finite()) && r <= 1e3 * longest {
                    (c, r)
                } else {
                    ([0, 1, 2].map(|k| (q[0][k] + q[1][k] + q[2][k] + q[3][k]) / 4.0), 0.5 * longest)
                };
                let own = dihedral_range_deg(&q).0;
                let mut rng = SplitMix(v.iter().fold(0x9E37_79B9u64, |h, &x| h.rotate_left(17) ^ u64::from(x)));
                let mut best: Option<(f64, Point)> = None;
                let mut blocked_by: Option<[u32; 3]> = None;
                let off = off_centres(q, c);
                let candidates: Vec<Point> = (0..CANDIDATES + off.len())
                    .map(|k| match k {
                        0 => c,
                        k if k < CANDIDATES => near(c, OFF_CENTRE * r, &mut rng),
                        k => off[k - CANDIDATES],
                    })
                    .collect();
                // Each candidate's verdict is a function of the
                // tetrahedralization and the point alone (`try_candidate`),
                // so they are found in parallel and read in candidate order:
                // the same choice whatever the number of threads.
                let this = &*self;
                // Only the circumcentre's blocking subfacet is used (to
                // refine it); the other candidates need only know whether
                // they are free, and their probes stop at the first subfacet
                // they would remove.
                let verdicts: Vec<Candidate> = candidates
                    .par_iter()
                    .enumerate()
                    .map(|(k, &p)| {
                        PROBE.with(|s| {
                            let (scratch, star, destroyed) = &mut *s.borrow_mut();
                            this.try_candidate(p, t, k > 0, scratch, star, destroyed)
                        })
                    })
                    .collect();
                for (k, (&p, verdict)) in candidates.iter().zip(verdicts).enumerate() {
                    match verdict {
                        Candidate::Free(quality) => {
                            if best.is_none_or(|(b, _)| quality > b) {
                                best = Some((quality, p));
                            }
                        }
                        Candidate::Blocked(face) => {
                            if k == 0 {
                                blocked_by = Some(face);
                            }
                        }
                        Candidate::Duplicate => {}
                    }
                }
                match (best, blocked_by) {
                    (Some((quality, _)), _) if only_sliver && quality <= own => {
                        skipped.insert(v);
                        stats.slivers_skipped += 1;
                    }
                    (Some((_, p)), _) => {
                        self.insert_free(p, t)?;
                        stats.circumcentres += 1;
                    }
                    // Refine the subfacet the circumcentre encroaches
                    // (Shewchuk's rule, restricted; module docs) for a bad tet
                    // on four input vertices (smoothing cannot move them), and
                    // for a tet of radius-edge ratio over PLANE_RADIUS_EDGE when
                    // the subfacet lies on a merged plane of the input (CAD; a
                    // scan's triangles are rarely coplanar) and is at least as
                    // large as the tet's shortest edge.
                    (None, Some(face))
                        if !too_big
                            && caps_left > 0
                            && self.boundary_room()
                            && (v.iter().all(|&x| (x as usize) < self.num_input())
                                || (re > PLANE_RADIUS_EDGE && self.plane_subfacet_larger(face, v))) =>
                    {
                        caps_left -= 1;
                        match self.refine_face(face) {
                            Ok(()) => stats.boundary_splits += 1,
                            Err(_) if self.last_duplicate => {
                                self.last_duplicate = false;
                                skipped.insert(v);
                                stats.slivers_skipped += 1;
                                continue;
                            }
                            Err(e) => return Err(e),
                        }
                    }
                    // A cap: two of its faces are subfacets (on two input
                    // triangles meeting at a flat angle); split the
                    // subsegment they share.
                    (None, Some(_))
                        if !too_big && caps_left > 0 && self.boundary_room() && self.cap_edge(v).is_some() =>
                    {
                        caps_left -= 1;
                        let (a, b) = self.cap_edge(v).unwrap_or_default();
                        if !self.split_subsegment_between(a, b)? {
                            skipped.insert(v);
                            stats.slivers_skipped += 1;
                            continue;
                        }
                        stats.boundary_splits += 1;
                    }
                    // Quality alone does not otherwise refine the boundary:
                    // refining subfacets for radius-edge or slivers does not
                    // converge yet (module docs of `conforming`).
                    (None, Some(_)) if !too_big => {
                        skipped.insert(v);
                        stats.slivers_skipped += 1;
                        continue;
                    }
                    (None, Some(face)) => match self.refine_face(face) {
                        Ok(()) => stats.boundary_splits += 1,
                        // Its point is a vertex already (cocircular subfacets):
                        // nothing changed; leave this tet.
                        Err(_) if self.last_duplicate => {
                            self.last_duplicate = false;
                            skipped.insert(v);
                            stats.slivers_skipped += 1;
                            continue;
                        }
                        Err(e) => return Err(e),
                    },
                    // No free candidate, and the circumcentre is a vertex
                    // already or beyond the hull: left, not tried again (it
                    // used to be retried until the pass limit, 64, with
                    // nothing changing: the hinge took 64 passes).
                    (None, None) => {
                        skipped.insert(v);
                        continue;
                    }
                }
                self.recover_pending()?;
            }
        }
        Ok(stats)
    }

    /// Refines the subfacet with sorted corners `face` (`Recovery::refine_subfacet`).
    fn refine_face(&mut self, face: [u32; 3]) -> Result<(), ConformingError> {
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
        self.refine_subfacet_pub(f, tri)
    }

    /// Whether subfacet `face` lies on a merged plane of the input and its
    /// circumradius is at least the shortest edge of tet `v`.
    fn plane_subfacet_larger(&self, face: [u32; 3], v: [u32; 4]) -> bool {
        let f = self.face_owner[&face] as usize;
        if self.facets[f].num_inputs() < 2 {
            return false;
        }
        let pts = self.dt.points();
        let q = face.map(|x| pts[x as usize]);
        let cc = super::recover::circumcentre(q);
        let r = dot(sub(q[0], cc), sub(q[0], cc)).sqrt();
        let mut lmin = f64::INFINITY;
        for i in 0..4 {
            for j in i + 1..4 {
                let d = sub(pts[v[j] as usize], pts[v[i] as usize]);
                lmin = lmin.min(dot(d, d).sqrt());
            }
        }
        r >= lmin
    }

    /// The edge shared by two subfacet faces of tet `v`, if it has two and is
    /// not flat.
    fn cap_edge(&self, v: [u32; 4]) -> Option<(u32, u32)> {
        let faces: Vec<[u32; 3]> = super::delaunay::FACE
            .iter()
            .map(|f| {
                let mut k = f.map(|j| v[j]);
                k.sort_unstable();
                k
            })
            .filter(|k| self.face_owner.contains_key(k))
            .collect();
        let [f, g] = faces.as_slice() else { return None };
        // A flat cap (on coplanar input triangles) is removed after refinement
        // (`drop_flat_caps`); splitting its edge would make more flat caps.
        let pts = self.dt.points();
        if dihedral_range_deg(&v.map(|i| pts[i as usize])).0 < super::FLAT_DEG {
            return None;
        }
        let shared: Vec<u32> = f.iter().copied().filter(|x| g.contains(x)).collect();
        let &[a, b] = shared.as_slice() else { return None };
        // Only over a hinge that is nearly flat (the tet's dihedral angle at the
        // shared edge, the domain's angle there, over CAP_HINGE_DEG): at a
        // sharper edge of the input (a box's) the tet is no cap, and splitting
        // the edge would only make more tets like it.
        let [c, d] = {
            let mut o = v.iter().copied().filter(|&x| x != a && x != b);
            [o.next()?, o.next()?]
        };
        let p = |x: u32| pts[x as usize];
        let e = sub(p(b), p(a));
        let ee = dot(e, e);
        let perp = |x: u32| {
            let u = sub(p(x), p(a));
            let t = dot(u, e) / ee;
            [0, 1, 2].map(|k| u[k] - t * e[k])
        };
        let (u, w) = (perp(c), perp(d));
        let angle = (dot(u, w) / (dot(u, u) * dot(w, w)).sqrt()).clamp(-1.0, 1.0).acos().to_degrees();
        // Only the longest edge of both subfacets (Rivara's longest-edge
        // bisection, which keeps the subfacets' angles bounded): splitting a
        // shorter hinge makes skinnier subfacets, and the caps over their
        // halves are wedges over still shorter hinges (module docs of
        // `conforming`, "What was not done").
        let sq = |x: u32, y: u32| dot(sub(p(x), p(y)), sub(p(x), p(y)));
        let longest = [sq(a, c), sq(b, c), sq(a, d), sq(b, d)].into_iter().fold(0.0, f64::max);
        (angle > CAP_HINGE_DEG && ee >= longest).then_some((a, b))
    }

    /// Whether `p` may be inserted (module docs): its star's smallest dihedral
    /// angle, or the subfacet it blocks on (the one whose equatorial ball holds
    /// it deepest; ties: lowest key). The location walk starts at tet `hint`
    /// (the bad tet, near `p`).
    ///
    /// With `first_blocking`, the subfacet reported for a blocked candidate
    /// is the first removed one the probe meets, not the deepest: whether the
    /// candidate is free is the same.
    fn try_candidate(
        &self,
        p: Point,
        hint: u32,
        first_blocking: bool,
        scratch: &mut ProbeScratch,
        star: &mut Vec<[u32; 4]>,
        destroyed: &mut Vec<[u32; 3]>,
    ) -> Candidate {
        let subfacet = |f: [u32; 3]| f.iter().all(|&v| self.on_surface(v)) && self.face_owner.contains_key(&f);
        match self.dt.probe_star(p, hint, scratch, star, destroyed, |f| first_blocking && subfacet(f)) {
            Probe::Duplicate => return Candidate::Duplicate,
            Probe::Stopped(f) => return Candidate::Blocked(f),
            Probe::Star => {}
        }
        let pts = self.dt.points();
        let n = pts.len() as u32;
        let depth = |f: &[u32; 3]| {
            let q = f.map(|v| pts[v as usize]);
            let cc = super::recover::circumcentre(q);
            let r2 = dot(sub(q[0], cc), sub(q[0], cc));
            dot(sub(p, cc), sub(p, cc)) / r2
        };
        let mut hit: Option<(f64, [u32; 3])> = None;
        let mut consider = |f: [u32; 3], removed: bool| {
            // Only faces on surface vertices can be subfacets: most faces of a
            // cavity inside the volume are settled without a map look-up.
            if !f.iter().all(|&v| self.on_surface(v)) || !self.face_owner.contains_key(&f) {
                return;
            }
            let d = depth(&f);
            if (removed || d < 1.0) && hit.is_none_or(|(b, k)| d < b || (d == b && f < k)) {
                hit = Some((d, f));
            }
        };
        for f in destroyed.iter() {
            consider(*f, true);
        }
        for t in star.iter() {
            let i = t.iter().position(|&x| x == n).unwrap_or(0);
            let mut f = super::delaunay::FACE[i].map(|j| t[j]);
            if f.contains(&super::delaunay::GHOST) {
                continue;
            }
            f.sort_unstable();
            consider(f, false);
        }
        if let Some((_, f)) = hit {
            return Candidate::Blocked(f);
        }
        if star.iter().any(|t| t.contains(&super::delaunay::GHOST)) {
            return Candidate::Duplicate; // beyond the hull: never inserted
        }
        // The smallest dihedral angle of the star: the `acos` of its
        // largest cosine (`dihedral_cos_range`), one `acos` for the star.
        let mut cos = f64::NEG_INFINITY;
        for t in star.iter() {
            let q = t.map(|v| if v == n { p } else { pts[v as usize] });
            cos = cos.max(dihedral_cos_range(&q).1);
        }
        Candidate::Free(if cos == f64::NEG_INFINITY { f64::INFINITY } else { cos.acos().to_degrees() })
    }
}

/// A thread's scratch for `try_candidate`: the probe's, the star, the removed faces.
type CandidateScratch = (ProbeScratch, Vec<[u32; 4]>, Vec<[u32; 3]>);

thread_local! {
    /// Each thread's scratch for `try_candidate`.
    static PROBE: RefCell<CandidateScratch> = RefCell::default();
}

/// What inserting a candidate point would do.
enum Candidate {
    /// No subfacet removed or encroached: the smallest dihedral angle [deg] of the star.
    Free(f64),
    /// It would remove or encroaches this subfacet.
    Blocked([u32; 3]),
    /// It is a vertex already (or beyond the hull).
    Duplicate,
}

/// Off-centres of the tet `q` with circumcentre `c` (Üngör's idea): points on
/// the line from the midpoint `m` of its shortest edge (length `l`) towards
/// `c`, at [`OFF_CENTRE_DISTANCES`] times `l` from `m` when that is short of
/// `c`. They lie inside the circumsphere (their insertion removes the tet) and
/// nearer the tet than `c`, so they are free when `c` encroaches the boundary.
fn off_centres(q: [Point; 4], c: Point) -> Vec<Point> {
    let mut best = (f64::INFINITY, 0, 0);
    for i in 0..4 {
        for j in i + 1..4 {
            let d = sub(q[j], q[i]);
            let l = dot(d, d).sqrt();
            if l < best.0 {
                best = (l, i, j);
            }
        }
    }
    let (l, i, j) = best;
    let m = [0, 1, 2].map(|k| 0.5 * (q[i][k] + q[j][k]));
    let to = sub(c, m);
    let dist = dot(to, to).sqrt();
    if !(dist.is_finite() && dist > 0.0) {
        return Vec::new();
    }
    OFF_CENTRE_DISTANCES
        .iter()
        .filter(|&&f| f * l < dist)
        .map(|&f| [0, 1, 2].map(|k| m[k] + f * l / dist * to[k]))
        .collect()
}

/// Distances of the off-centres from the shortest edge's midpoint, in its
/// lengths: 2.74 is where the triangle of the edge and the point has the
/// radius-edge ratio 1.414.
pub const OFF_CENTRE_DISTANCES: [f64; 2] = [2.74, 1.9];

/// A point uniformly drawn in the ball of radius `r` about `c`.
fn near(c: Point, r: f64, rng: &mut SplitMix) -> Point {
    loop {
        let u = [0; 3].map(|_| (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0);
        if dot(u, u) <= 1.0 {
            return [0, 1, 2].map(|k| c[k] + r * u[k]);
        }
    }
}
