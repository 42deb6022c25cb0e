//! Boundary recovery by conforming Delaunay refinement (stage 2), exterior
//! removal and region tagging.
//!
//! See the module docs of [`crate::conforming`] for the design and why.

use std::collections::{BTreeSet, HashMap};

use super::delaunay::{Delaunay, FACE, GHOST};
use super::facet::Facet;
use super::ConformingError;
use crate::predicates::{cross, dot, sub, Point};

/// A map keyed by sorted face corners, hashed with `rustc_hash`'s FxHash, far
/// cheaper than the default SipHash on the millions of face look-ups of
/// refinement (no random state: the same hashes on every run). Used only for
/// maps that are never iterated, so their order cannot reach the output.
pub(crate) type FaceMap<V> = rustc_hash::FxHashMap<[u32; 3], V>;

/// The input as a piecewise-linear complex: vertices, the input edges between
/// facets (*segments*) and the *facets* (planar polygons of coplanar input
/// triangles, `facet::coplanar_groups`), each split as Steiner points arrive.
#[derive(Clone)]
pub(crate) struct Recovery {
    pub dt: Delaunay,
    /// Subsegments: `(a, b, segment id)`.
    subsegs: Vec<(u32, u32, u32)>,
    /// The subsegment with each pair of ends (smaller index first).
    subseg_at: rustc_hash::FxHashMap<(u32, u32), usize>,
    /// The subsegments of each segment.
    seg_subs: Vec<Vec<usize>>,
    /// Input vertex at each end of each segment (for the concentric-shell rule).
    segment_ends: Vec<[u32; 2]>,
    /// Facets containing each segment.
    segment_facets: Vec<Vec<u32>>,
    /// Segment ids of each facet's sides.
    facet_segments: Vec<Vec<u32>>,
    pub facets: Vec<Facet>,
    pub steiner_on_segments: usize,
    pub steiner_on_facets: usize,
    max_steiner: usize,
    star: Vec<u32>,
    /// The facet of each subfacet (sorted corners).
    pub face_owner: FaceMap<u32>,
    /// Facets to check for missing subsegments and subfacets.
    pending: BTreeSet<u32>,
    destroyed: Vec<[u32; 3]>,
    /// What made each Steiner point (for messages): "edge", "triangle", "interior".
    kinds: Vec<&'static str>,
    /// Whether each Steiner point lies on the input surface (kind "edge" or
    /// "triangle"): only those and input vertices can be corners of subfacets.
    on_surface: Vec<bool>,
    /// The kind of the next point added.
    pub next_kind: &'static str,
    /// Whether the last point refused was a duplicate of a vertex (the
    /// tetrahedralization is then unchanged).
    pub last_duplicate: bool,
    /// The most Steiner points one `recover_pending` call may add (unbounded
    /// but for the budget during boundary recovery; bounded during quality
    /// refinement, whose failure falls back to size refinement alone).
    pub recover_limit: usize,
}

impl Recovery {
    pub fn new(vertices: &[Point], triangles: &[[u32; 3]], max_steiner: usize) -> Result<Self, ConformingError> {
        let dt = Delaunay::new(vertices).map_err(ConformingError::Delaunay)?;
        let groups = super::facet::coplanar_groups(vertices, triangles);
        let mut group_of = vec![0u32; triangles.len()];
        for (g, members) in groups.iter().enumerate() {
            for &f in members {
                group_of[f] = g as u32;
            }
        }
        // Edges and the triangles on them, in order of first use.
        let mut edge_tris: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        let mut edge_order = Vec::new();
        for (f, t) in triangles.iter().enumerate() {
            for i in 0..3 {
                let e = (t[i].min(t[(i + 1) % 3]), t[i].max(t[(i + 1) % 3]));
                let list = edge_tris.entry(e).or_default();
                if list.is_empty() {
                    edge_order.push(e);
                }
                list.push(f);
            }
        }
        // A segment is an edge that is not inside one facet (two triangles of it).
        let mut segment_ends = Vec::new();
        let mut segment_facets: Vec<Vec<u32>> = Vec::new();
        let mut facet_segments: Vec<Vec<u32>> = vec![Vec::new(); groups.len()];
        for e in edge_order {
            let on = &edge_tris[&e];
            if on.len() == 2 && group_of[on[0]] == group_of[on[1]] {
                continue;
            }
            let id = segment_ends.len() as u32;
            segment_ends.push([e.0, e.1]);
            let mut gs: Vec<u32> = on.iter().map(|&f| group_of[f]).collect();
            gs.sort_unstable();
            gs.dedup();
            for &g in &gs {
                facet_segments[g as usize].push(id);
            }
            segment_facets.push(gs);
        }
        let facets: Vec<Facet> = groups
            .iter()
            .enumerate()
            .map(|(g, members)| {
                let sides: Vec<(u32, u32)> = facet_segments[g]
                    .iter()
                    .map(|&s| (segment_ends[s as usize][0], segment_ends[s as usize][1]))
                    .collect();
                Facet::new(members.iter().map(|&f| triangles[f]).collect(), &sides, vertices)
            })
            .collect();
        let subsegs: Vec<(u32, u32, u32)> =
            segment_ends.iter().enumerate().map(|(i, e)| (e[0], e[1], i as u32)).collect();
        let subseg_at = subsegs.iter().enumerate().map(|(k, &(a, b, _))| ((a.min(b), a.max(b)), k)).collect();
        let seg_subs = (0..segment_ends.len()).map(|i| vec![i]).collect();
        Ok(Recovery {
            dt,
            subsegs,
            subseg_at,
            seg_subs,
            segment_ends,
            segment_facets,
            facet_segments,
            facets,
            steiner_on_segments: 0,
            steiner_on_facets: 0,
            max_steiner,
            star: Vec::new(),
            face_owner: FaceMap::default(),
            pending: BTreeSet::new(),
            destroyed: Vec::new(),
            kinds: Vec::new(),
            on_surface: Vec::new(),
            last_duplicate: false,
            recover_limit: usize::MAX,
            next_kind: "edge",
        })
        .map(|mut r| {
            for f in 0..r.facets.len() {
                r.index_facet(f);
            }
            r
        })
    }

    fn has_edge(&mut self, a: u32, b: u32) -> bool {
        let mut star = std::mem::take(&mut self.star);
        self.dt.star(a, &mut star);
        let found = star.iter().any(|&t| self.dt.tet(t).contains(&b));
        self.star = star;
        found
    }

    fn has_face(&mut self, a: u32, b: u32, c: u32) -> bool {
        let mut star = std::mem::take(&mut self.star);
        self.dt.star(a, &mut star);
        let found = star.iter().any(|&t| {
            let v = self.dt.tet(t);
            v.contains(&b) && v.contains(&c)
        });
        self.star = star;
        found
    }

    fn steiner(&self) -> usize {
        self.steiner_on_segments + self.steiner_on_facets
    }

    /// Inserts `p`, its location walk starting at tet `hint` (one near it).
    fn add_point(&mut self, p: Point, hint: u32) -> Result<u32, ConformingError> {
        if self.steiner() >= self.max_steiner {
            return Err(ConformingError::RecoveryFailed {
                steiner_points: self.steiner(),
                missing: "the Steiner point budget ran out".into(),
            });
        }
        let n = self.dt.points().len() as u32;
        let mut destroyed = std::mem::take(&mut self.destroyed);
        let v = self.dt.insert_reporting_near(p, hint, &mut destroyed);
        for f in &destroyed {
            if let Some(&owner) = self.face_owner.get(f) {
                self.pending.insert(owner);
            }
        }
        self.destroyed = destroyed;
        self.last_duplicate = v != n;
        if v != n {
            let what =
                (v as usize).checked_sub(self.dt.points().len() - self.kinds.len()).map_or("input", |k| self.kinds[k]);
            return Err(ConformingError::RecoveryFailed {
                steiner_points: self.steiner(),
                missing: format!(
                    "a Steiner point ({}) at {p:?} coincides with vertex {v} (a {what} point)",
                    self.next_kind
                ),
            });
        }
        self.kinds.push(self.next_kind);
        self.on_surface.push(self.next_kind != "interior");
        Ok(v)
    }

    /// Splits subsegment `k`: at its midpoint, or, when one end is an input
    /// vertex, at the power-of-two distance from it nearest to the midpoint
    /// (Ruppert's concentric shells: subsegments meeting at an input vertex at a
    /// small angle are split at equal radii and stop encroaching each other).
    fn split_subsegment(&mut self, k: usize) -> Result<(), ConformingError> {
        let (a, b, s) = self.subsegs[k];
        let pts = self.dt.points();
        let (pa, pb) = (pts[a as usize], pts[b as usize]);
        let d = sub(pb, pa);
        let len = dot(d, d).sqrt();
        let ends = self.segment_ends[s as usize];
        let a_input = ends.contains(&a);
        let b_input = ends.contains(&b);
        let t = if a_input != b_input {
            // The power of two in [len / 3, 2 len / 3] (there is always one).
            let r = 2f64.powi((len / 3.0).log2().ceil() as i32);
            let r = if r <= 2.0 * len / 3.0 { r } else { 0.5 * len };
            if a_input {
                r / len
            } else {
                1.0 - r / len
            }
        } else {
            0.5
        };
        let m = [pa[0] + t * d[0], pa[1] + t * d[1], pa[2] + t * d[2]];
        self.next_kind = "edge";
        let v = self.add_point(m, self.dt.tet_at(a))?;
        self.steiner_on_segments += 1;
        self.subsegs[k] = (a, v, s);
        self.subsegs.push((v, b, s));
        self.subseg_at.remove(&(a.min(b), a.max(b)));
        self.subseg_at.insert((a.min(v), a.max(v)), k);
        self.subseg_at.insert((v.min(b), v.max(b)), self.subsegs.len() - 1);
        self.seg_subs[s as usize].push(self.subsegs.len() - 1);
        let facets = self.segment_facets[s as usize].clone();
        for f in facets {
            let pts = self.dt.points();
            self.facets[f as usize].split_edge(a, b, v, pts);
            self.index_facet(f as usize);
            self.pending.insert(f);
        }
        Ok(())
    }

    /// Whether vertex `v` lies on the input surface (an input vertex or a
    /// Steiner point on an input edge or triangle): a face with a corner that
    /// does not (or a ghost corner) is no subfacet, with no map look-up.
    pub fn on_surface(&self, v: u32) -> bool {
        let first = self.num_input();
        (v as usize) < first || self.on_surface.get((v as usize).wrapping_sub(first)).copied().unwrap_or(false)
    }

    /// The number of input vertices (the first points of the tetrahedralization).
    pub fn num_input(&self) -> usize {
        self.dt.points().len() - self.kinds.len()
    }

    /// Whether quality refinement may still add boundary points: a tenth of the
    /// Steiner budget stays for the recovery their insertion triggers.
    pub fn boundary_room(&self) -> bool {
        self.steiner() < self.max_steiner - self.max_steiner / 10
    }

    /// Splits the subsegment with ends `a` and `b` (either order), if there is
    /// one; whether there was.
    pub fn split_subsegment_between(&mut self, a: u32, b: u32) -> Result<bool, ConformingError> {
        let Some(&k) = self.subseg_at.get(&(a.min(b), a.max(b))) else {
            return Ok(false);
        };
        self.split_subsegment(k)?;
        Ok(true)
    }

    /// Indices of the subsegments on facet `f`'s sides.
    fn facet_subsegs(&self, f: usize) -> impl Iterator<Item = usize> + '_ {
        self.facet_segments[f].iter().flat_map(|&s| self.seg_subs[s as usize].iter().copied())
    }

    /// Brings facet `f`'s entries in `face_owner` up to date with the changes of
    /// its triangulation since the last call.
    fn index_facet(&mut self, f: usize) {
        let (removed, added) = self.facets[f].take_changes();
        for t in removed {
            let mut k = t;
            k.sort_unstable();
            if self.face_owner.get(&k) == Some(&(f as u32)) {
                self.face_owner.remove(&k);
            }
        }
        for t in added {
            if self.facets[f].has_tri(t) {
                let mut k = t;
                k.sort_unstable();
                self.face_owner.insert(k, f as u32);
            }
        }
    }

    /// Recovers every subsegment and subfacet (module docs, stage 2).
    pub fn run(&mut self) -> Result<(), ConformingError> {
        let mut k = 0;
        while k < self.subsegs.len() {
            let (a, b, _) = self.subsegs[k];
            if !self.has_edge(a, b) {
                self.split_subsegment(k)?;
                continue;
            }
            k += 1;
        }
        self.pending.extend(0..self.facets.len() as u32);
        self.recover_pending()
    }

    /// Recovers the pending facets: their missing subsegments are split, then their
    /// missing subfacets refined, until every one is present (each Steiner point
    /// marks the facets whose subfacets its insertion removed as pending).
    pub fn recover_pending(&mut self) -> Result<(), ConformingError> {
        // Flips add no point, so nothing else bounds them: past this many in
        // one call (cocircular subfacets flipping back and forth), missing
        // subfacets are refined instead, which the Steiner budget bounds.
        let mut flips_left = 16 * self.pending.len() + 1024;
        let start = self.steiner();
        while let Some(f) = self.pending.pop_first() {
            if self.steiner() - start > self.recover_limit {
                return Err(ConformingError::RecoveryFailed {
                    steiner_points: self.steiner(),
                    missing: format!("recovery after one refinement point needed over {} points", self.recover_limit),
                });
            }
            let subs: Vec<usize> = self.facet_subsegs(f as usize).collect();
            let missing_seg = subs.into_iter().find(|&k| {
                let (a, b, _) = self.subsegs[k];
                !self.has_edge(a, b)
            });
            if let Some(k) = missing_seg {
                self.split_subsegment(k)?;
                self.pending.insert(f);
                continue;
            }
            let tris = self.facets[f as usize].tris.clone();
            for t in tris {
                if !self.has_face(t[0], t[1], t[2]) {
                    // Cocircular points have two Delaunay triangulations: when the
                    // tetrahedralization took the other diagonal, flip to it.
                    if flips_left > 0 && self.match_by_flip(f as usize, t) {
                        flips_left -= 1;
                        self.pending.insert(f);
                        break;
                    }
                    self.refine_subfacet(f as usize, t)?;
                    self.pending.insert(f);
                    break;
                }
            }
        }
        Ok(())
    }

    /// Flips an edge of the missing subfacet `t` of facet `f` when both triangles
    /// of the flipped quad are faces of the tetrahedralization; whether it did.
    fn match_by_flip(&mut self, f: usize, t: [u32; 3]) -> bool {
        for (u, v, w, x) in self.facets[f].flips_of(t) {
            if self.has_face(w, u, x) && self.has_face(x, v, w) {
                self.facets[f].flip(u, v);
                self.index_facet(f);
                return true;
            }
        }
        false
    }

    /// How smoothing may move each vertex (`Freedom`): an interior Steiner
    /// point anywhere, a Steiner point inside an input triangle within that
    /// triangle's plane, one on an input edge along that edge; input vertices
    /// not at all. The directions come from the input's exact coordinates, so a
    /// plane or edge parallel to a coordinate axis keeps the moved vertex's
    /// coordinates across it exact.
    pub fn freedom(&self) -> Vec<Freedom> {
        let n = self.dt.points().len();
        let first = n - self.kinds.len();
        let mut out = vec![Freedom::Fixed; n];
        for (k, kind) in self.kinds.iter().enumerate() {
            if *kind == "interior" {
                out[first + k] = Freedom::Free;
            }
        }
        let pts = self.dt.points();
        for &(a, b, s) in &self.subsegs {
            let [p, q] = self.segment_ends[s as usize].map(|v| pts[v as usize]);
            for v in [a, b] {
                if (v as usize) >= first && self.kinds[v as usize - first] == "edge" {
                    out[v as usize] = Freedom::Line(unit(sub(q, p)));
                }
            }
        }
        for f in &self.facets {
            let normal = f.normal();
            for v in f.points() {
                if (v as usize) >= first && self.kinds[v as usize - first] == "triangle" {
                    out[v as usize] = Freedom::Plane(tangents(normal));
                }
            }
        }
        out
    }

    /// Inserts a point that removes no subfacet (checked by the caller), its
    /// location walk starting at tet `hint` (one near it).
    pub fn insert_free(&mut self, p: Point, hint: u32) -> Result<u32, ConformingError> {
        self.next_kind = "interior";
        self.add_point(p, hint)
    }

    /// [`Self::refine_subfacet`] for refinement.
    pub fn refine_subfacet_pub(&mut self, f: usize, t: [u32; 3]) -> Result<(), ConformingError> {
        self.refine_subfacet(f, t)
    }

    /// Ruppert's refinement of every facet's triangulation to radius-edge
    /// ratio `bound` (module docs of `conforming`, stage 3): the subfacets over
    /// it whose shortest edge is under `max_edge`, worst first, get their circumcentre (in the facet's plane) inserted,
    /// or the subsegment of the facet it encroaches split; a subfacet whose
    /// shortest edge joins two segments meeting at an input vertex (a small
    /// angle of the input, which no split improves) is left, as is one whose
    /// circumcentre lies off the facet. Rounds until none is left, at most
    /// `max_rounds`; the number of points added.
    pub fn refine_facet_quality(
        &mut self,
        bound: f64,
        max_edge: f64,
        max_rounds: usize,
    ) -> Result<usize, ConformingError> {
        let mut added = 0;
        let mut skipped: BTreeSet<[u32; 3]> = BTreeSet::new();
        for _ in 0..max_rounds {
            // The segments through each vertex.
            let mut on_segs: HashMap<u32, Vec<u32>> = HashMap::new();
            for &(a, b, s) in &self.subsegs {
                on_segs.entry(a).or_default().push(s);
                on_segs.entry(b).or_default().push(s);
            }
            let pts = self.dt.points();
            let mut bad: Vec<(f64, usize, [u32; 3])> = Vec::new();
            for (f, facet) in self.facets.iter().enumerate() {
                for &t in &facet.tris {
                    let mut key = t;
                    key.sort_unstable();
                    if skipped.contains(&key) {
                        continue;
                    }
                    let q = t.map(|v| pts[v as usize]);
                    let (ratio, apex) = triangle_radius_edge(q);
                    if ratio <= bound {
                        continue;
                    }
                    let shortest = [0, 1, 2]
                        .map(|i| {
                            let d = sub(q[(i + 1) % 3], q[i]);
                            dot(d, d).sqrt()
                        })
                        .into_iter()
                        .fold(f64::INFINITY, f64::min);
                    if shortest >= max_edge {
                        continue;
                    }
                    let w = t[apex];
                    let (p, r) = (t[(apex + 1) % 3], t[(apex + 2) % 3]);
                    let ends = |s: &u32| self.segment_ends[*s as usize].contains(&w);
                    let on = |v: u32| on_segs.get(&v).is_some_and(|ss| ss.iter().any(ends));
                    if (w as usize) < self.num_input() && on(p) && on(r) {
                        skipped.insert(key);
                        continue;
                    }
                    bad.push((ratio, f, t));
                }
            }
            if bad.is_empty() {
                break;
            }
            bad.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
            let before = added;
            for (_, f, t) in bad {
                if !self.facets[f].has_tri(t) {
                    continue;
                }
                if !self.boundary_room() {
                    return Ok(added);
                }
                let pts = self.dt.points();
                let c = self.facets[f].circumcentre(t);
                if let Some(k) = self.encroached_subseg(f, c) {
                    self.split_subsegment(k)?;
                } else if self.facets[f].contains(c, pts) {
                    self.next_kind = "triangle";
                    let v = match self.add_point(c, self.dt.tet_at(t[0])) {
                        Err(_) if self.last_duplicate => {
                            self.last_duplicate = false;
                            let mut key = t;
                            key.sort_unstable();
                            skipped.insert(key);
                            continue;
                        }
                        r => r?,
                    };
                    self.insert_on_facet(f, v);
                } else {
                    let mut key = t;
                    key.sort_unstable();
                    skipped.insert(key);
                    continue;
                }
                added += 1;
                self.recover_pending()?;
            }
            if added == before {
                break;
            }
        }
        Ok(added)
    }

    /// The subsegment of facet `f` whose closed diametral ball holds `c`
    /// deepest (with a margin for rounding: a point on a subsegment, a right
    /// subfacet's circumcentre, splits the subsegment instead of landing next
    /// to it).
    fn encroached_subseg(&self, f: usize, c: Point) -> Option<usize> {
        let pts = self.dt.points();
        let mut worst: Option<(usize, f64)> = None;
        for k in self.facet_subsegs(f) {
            let (a, b, _) = self.subsegs[k];
            let (pa, pb) = (pts[a as usize], pts[b as usize]);
            let m = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1]), 0.5 * (pa[2] + pb[2])];
            let r2 = 0.25 * dot(sub(pb, pa), sub(pb, pa));
            let d2 = dot(sub(c, m), sub(c, m));
            if d2 <= r2 * (1.0 + 1e-9) && worst.is_none_or(|(_, w)| d2 / r2 < w) {
                worst = Some((k, d2 / r2));
            }
        }
        worst.map(|(k, _)| k)
    }

    /// A missing subfacet `t` of facet `f`: insert its circumcentre, or split a
    /// subsegment of `f` that the circumcentre encroaches (lies in the diametral
    /// ball of).
    fn refine_subfacet(&mut self, f: usize, t: [u32; 3]) -> Result<(), ConformingError> {
        let pts = self.dt.points();
        // In the facet's frame: a skinny subfacet's normal is inaccurate, and a
        // circumcentre computed in 3D would leave the facet's plane.
        let c = self.facets[f].circumcentre(t);
        if let Some(k) = self.encroached_subseg(f, c) {
            return self.split_subsegment(k);
        }
        let q = t.map(|v| pts[v as usize]);
        // The circumcentre when it lies strictly inside the subfacet itself, so
        // that its insertion splits this subfacet whatever the rest of the
        // facet's triangulation (an obtuse subfacet's circumcentre lies in a
        // neighbour, whose split need not remove this one); else the centroid,
        // unless that encroaches a subsegment (a needle subfacet's centroid lies
        // next to its long sides), which is split instead.
        let inside = crate::predicates::projection_for(q[0], q[1], q[2]).is_some_and(|drop| {
            let s = crate::predicates::orient2d(q[0], q[1], q[2], drop);
            (0..3).all(|i| crate::predicates::orient2d(q[i], q[(i + 1) % 3], c, drop) == s)
        }) && self.facets[f].contains(c, pts);
        let centroid = [0, 1, 2].map(|k| (q[0][k] + q[1][k] + q[2][k]) / 3.0);
        if !inside {
            if let Some(k) = self.encroached_subseg(f, centroid) {
                return self.split_subsegment(k);
            }
        }
        let p = if inside { c } else { centroid };
        self.next_kind = "triangle";
        // A circumcentre that is a vertex already (one placed on a neighbouring,
        // nearly coplanar facet): the centroid, inside the subfacet, instead.
        let hint = self.dt.tet_at(t[0]);
        let v = match self.add_point(p, hint) {
            Err(_) if self.last_duplicate && p != centroid => self.add_point(centroid, self.dt.tet_at(t[0]))?,
            r => r?,
        };

        self.insert_on_facet(f, v);
        Ok(())
    }

    /// Records vertex `v`, just inserted inside facet `f`, as a Steiner point
    /// of that facet (its 2D triangulation, the subfacet index, the facets to
    /// recover again).
    fn insert_on_facet(&mut self, f: usize, v: u32) {
        self.steiner_on_facets += 1;
        let pts = self.dt.points();
        self.facets[f].insert_interior(v, pts);
        self.index_facet(f);
        self.pending.insert(f as u32);
    }
}

/// The radius-edge ratio of a triangle (circumradius over shortest edge) and
/// the corner opposite its shortest edge.
pub(crate) fn triangle_radius_edge(q: [Point; 3]) -> (f64, usize) {
    let l = [0, 1, 2].map(|i| {
        let d = sub(q[(i + 2) % 3], q[(i + 1) % 3]);
        dot(d, d).sqrt()
    });
    let n = cross(sub(q[1], q[0]), sub(q[2], q[0]));
    let area2 = dot(n, n).sqrt();
    let apex = (0..3).fold(0, |b, i| if l[i] < l[b] { i } else { b });
    (l[0] * l[1] * l[2] / (2.0 * area2) / l[apex], apex)
}

/// The circumcentre of a triangle in 3D.
pub(crate) fn circumcentre(q: [Point; 3]) -> Point {
    let a = sub(q[1], q[0]);
    let b = sub(q[2], q[0]);
    let n = cross(a, b);
    let nn = dot(n, n);
    let t1 = cross(n, a);
    let t2 = cross(b, n);
    let (aa, bb) = (dot(a, a), dot(b, b));
    // c - q0 = (|a|^2 (b x n) + |b|^2 (n x a)) / (2 |n|^2)
    [0, 1, 2].map(|k| q[0][k] + (aa * t2[k] + bb * t1[k]) / (2.0 * nn))
}

/// The finite tets of `rec` not reachable from the outside (the ghosts)
/// without crossing a subfacet, grouped into the components that subfacets
/// separate: `(slot, tet corners, component)` and the number of components.
/// A face with a corner off the surface is no subfacet: settled without a
/// look-up in the map (most faces; the flood runs once per refinement pass).
pub(crate) fn interior_components(rec: &Recovery) -> (Vec<(u32, [u32; 4], u32)>, usize) {
    let (dt, constrained) = (&rec.dt, &rec.face_owner);
    let live: Vec<(u32, [u32; 4])> = dt.live_tets().collect();
    let slots = live.iter().map(|(t, _)| *t as usize + 1).max().unwrap_or(0);
    const UNSEEN: u32 = u32::MAX;
    const OUTSIDE: u32 = u32::MAX - 1;
    let mut comp = vec![UNSEEN; slots];
    // Whether face `i` of the tet with corners `v` is a subfacet (sorted for
    // the look-up only when every corner is on the surface).
    let subfacet = |v: [u32; 4], i: usize| {
        let mut k = FACE[i].map(|j| v[j]);
        k.iter().all(|&x| x != GHOST && rec.on_surface(x)) && {
            k.sort_unstable();
            constrained.contains_key(&k)
        }
    };
    let flood = |seeds: Vec<u32>, label: u32, comp: &mut Vec<u32>| {
        let mut stack = seeds;
        for &s in &stack {
            comp[s as usize] = label;
        }
        while let Some(t) = stack.pop() {
            let v = dt.tet(t);
            let n = dt.neighbours(t);
            for i in 0..4 {
                if comp[n[i] as usize] != UNSEEN {
                    continue;
                }
                if subfacet(v, i) {
                    continue;
                }
                comp[n[i] as usize] = label;
                stack.push(n[i]);
            }
        }
    };
    let ghosts: Vec<u32> = live.iter().filter(|(_, v)| v.contains(&GHOST)).map(|(t, _)| *t).collect();
    flood(ghosts, OUTSIDE, &mut comp);
    let mut count = 0u32;
    for &(t, _) in &live {
        if comp[t as usize] == UNSEEN {
            flood(vec![t], count, &mut comp);
            count += 1;
        }
    }
    let out =
        live.iter().filter(|(t, _)| comp[*t as usize] < OUTSIDE).map(|(t, v)| (*t, *v, comp[*t as usize])).collect();
    (out, count as usize)
}

/// Compacts the vertices used by `tets`: `(nodes, renumbered tets)`.
pub(crate) fn compact(points: &[Point], tets: &[[u32; 4]]) -> (Vec<Point>, Vec<[u32; 4]>) {
    // The used vertices in increasing order get 0, 1, ...
    let mut index = vec![u32::MAX; points.len()];
    tets.iter().flatten().for_each(|&v| index[v as usize] = 0);
    let mut nodes = Vec::new();
    for (v, slot) in index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = nodes.len() as u32;
            nodes.push(points[v]);
        }
    }
    let cells = tets.iter().map(|t| t.map(|v| index[v as usize])).collect();
    (nodes, cells)
}

/// How smoothing may move a vertex (see [`Recovery::freedom`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Freedom {
    /// Not at all (an input vertex).
    Fixed,
    /// Anywhere (an interior Steiner point).
    Free,
    /// Within the plane spanned by these two orthonormal directions.
    Plane([Point; 2]),
    /// Along this unit direction.
    Line(Point),
}

fn unit(d: Point) -> Point {
    let l = dot(d, d).sqrt();
    d.map(|x| x / l)
}

/// Two orthonormal directions across `normal`: for a normal along a coordinate
/// axis they are exactly the other two axes (zero components stay exact zeros).
fn tangents(normal: Point) -> [Point; 2] {
    let k = (0..3).min_by(|&i, &j| normal[i].abs().total_cmp(&normal[j].abs())).unwrap_or(0);
    let mut e = [0.0; 3];
    e[k] = 1.0;
    let t1 = unit(cross(normal, e));
    let t2 = unit(cross(unit(normal), t1));
    [t1, t2]
}
