//! Conforming (TetGen-equivalent) tetrahedralization: a mesh whose boundary
//! reproduces a clean, closed input surface exactly.
//!
//! ## Stages, each in its file
//!
//! 1. **Delaunay** (`delaunay.rs`): incremental 3D Delaunay tetrahedralization
//!    (Bowyer–Watson, ghost tets closing the hull) with exact predicates and
//!    symbolic perturbation (`perturb.rs`), so cospherical and coplanar input
//!    (grids, CAD boxes) is handled without tolerances and the result is unique;
//!    points go in BRIO order with Hilbert-sorted rounds (`order.rs`).
//! 2. **Boundary recovery** (`recover.rs`, `facet.rs`) by *conforming Delaunay*
//!    refinement: the tetrahedralization stays Delaunay throughout, and Steiner
//!    points are added on the input until every input edge and triangle is a
//!    union of its edges and faces. First, input triangles that are coplanar
//!    with a neighbour (the far corner within 1e-12 of the bounding-box
//!    diagonal of its plane, across an edge that only those two share) merge
//!    into one planar polygon, a *facet*; the *segments* are the input edges
//!    between facets, and the edges inside a facet are dropped. A CAD model's
//!    planes are cut into needle triangles (the hinge's 1 212 triangles have
//!    488 with an angle under 5 deg): kept as they were, every needle edge had
//!    to appear in the mesh, and it was split into runs of tiny subsegments
//!    wherever another feature passed near it (boundary recovery and
//!    refinement of the hinge had not finished after 7 min; merged, they take
//!    5 s). Then:
//!    - a subsegment (piece of an input edge) that is not an edge of the
//!      tetrahedralization is split, at its midpoint or, next to an input vertex,
//!      at a power-of-two distance from it (Ruppert's concentric shells, which
//!      keep segments meeting at small angles from splitting each other forever);
//!    - each facet keeps its own 2D constrained Delaunay triangulation of the
//!      points on it (built combinatorially, so a point on a segment stays on
//!      it whatever the rounding of its coordinates); a subfacet that is not a
//!      face of the tetrahedralization gets its circumcentre (computed in the
//!      facet's plane: a skinny subfacet's own normal is too inaccurate)
//!      inserted when that lies inside it, else its centroid, unless the point
//!      encroaches a subsegment of the facet (lies in its diametral ball),
//!      which is then split instead.
//!
//!    Then the tets reachable from outside the hull without crossing an input
//!    triangle are removed, and the rest is split into the components the input
//!    triangles separate; each component becomes the region of the smallest
//!    shell (by enclosed volume) whose winding number says it contains it
//!    (nested shells, and touching shells given once, become regions as in
//!    envelope mode).
//!
//! ## Why conforming rather than constrained Delaunay
//!
//! A constrained Delaunay tetrahedralization (TetGen's route) keeps the input
//! triangles as they are but needs boundary recovery by flips, with Steiner
//! points where flips get stuck and their later removal: a large, delicate body
//! of code. Conforming Delaunay needs only point insertion into a Delaunay
//! tetrahedralization, which stage 1 makes exact and robust; the price is more
//! Steiner points on the boundary (every boundary face is a Delaunay face),
//! which is acceptable since a finite-element mesh wants boundary points at
//! about the element size anyway. Steiner points on an input edge or triangle
//! are computed in floating point, so they lie on it within rounding (about
//! 1e-16 of the coordinates): far inside the 1e-9 volume and Hausdorff gates.
//!
//! 3. **Size and quality** (`refine.rs`): Delaunay refinement of the inside
//!    tets that are too large (volume over that of the regular tet of edge
//!    `size_mm`, `h^3 / (6 sqrt 2)`, TetGen's `-a`), too elongated
//!    (radius-edge ratio over [`ConformingOptions::radius_edge`], 1.414 as
//!    TetGen's `-q1.414`) or slivers (a dihedral angle under
//!    [`ConformingOptions::sliver_deg`], 10 deg). The point inserted for a bad
//!    tet is the best of its circumcentre and a few points near it (the star
//!    each would create is evaluated before inserting, and the one with the
//!    largest smallest dihedral angle wins: Li and Teng's sliver-avoiding
//!    choice); a point that would remove a subfacet, or lies in a subfacet's
//!    equatorial ball (Shewchuk's encroachment rule), is not inserted. Before
//!    the tets, the facets are refined for quality (Ruppert's rule in each
//!    facet's plane, `Recovery::refine_facet_quality`): a subfacet of
//!    radius-edge ratio over the tets' bound whose shortest edge is under
//!    `refine::FACET_QUALITY_EDGE` (2) target lengths gets its circumcentre,
//!    or the subsegment that encroaches split, unless its smallest angle is a
//!    corner of the input between two segments (which no split improves). A
//!    tet's ratio is at least that of each of its faces, so a skinny subfacet
//!    next to a short input edge (the hinge's, 0.44 mm at h = 2 mm) made a bad
//!    tet that nothing else fixed: on the hinge 1 220 of the 2 597 tets over
//!    1.414 had one. Then, for a bad tet whose candidates are all blocked:
//!    - a too-large tet refines the subfacet instead (its circumcentre when
//!      that lies inside it, else its centroid, or a split of the subsegment the
//!      point encroaches);
//!    - a sliver *cap*, two of whose faces lie on two input triangles meeting
//!      at a nearly flat hinge (the tet's angle there over 150 deg), gets that
//!      hinge's subsegment split when the hinge is the longest edge of both
//!      subfacets (longest-edge bisection, which keeps their angles
//!      bounded); that is what removes most slivers of a curved surface (on
//!      the bunny 643 of 749 slivers were caps). Splitting a shorter hinge
//!      made skinnier subfacets and, over their halves, wedges over ever
//!      shorter hinges: on the armadillo ("What was not done") the splits
//!      ran to their bound and left 15 000 tets under 10 deg;
//!    - a tet on four input vertices (which smoothing cannot move) refines the
//!      subfacet its circumcentre encroaches: on fandisk those were slivers
//!      under a curved strip of the surface, spanning two rows of its grid,
//!      down to 0.15 deg;
//!    - a tet of radius-edge ratio over `refine::PLANE_RADIUS_EDGE` (1.5)
//!      refines the subfacet its circumcentre encroaches when that lies on a
//!      merged plane of the input (a facet of more than one input triangle)
//!      and its circumradius is at least the tet's shortest edge: on the
//!      hinge that (at 2.3, before the facets were refined first) lowered the
//!      p99.9 radius-edge ratio from 3.95 to 2.23 and left no tet under 10
//!      deg; a scanned surface (the bunny) has few merged planes;
//!    - other tets that are bad for quality alone are left.
//! 4. **Flat caps** (`drop_flat_caps`): tets whose smallest height is under
//!    1e-12 of the diagonal, with a face on the boundary (on coplanar input triangles, where
//!    the symbolic perturbation of stage 1 makes zero-volume tets legal) are
//!    removed: the boundary becomes their other faces, the same piece of plane.
//! 5. **Edge removal** (`flip.rs`): around a tet under the sliver bound
//!    (caps first), an interior edge with a ring of `n` tets (3 to 12, one
//!    region, no subfacet through it) is replaced with those tets by the
//!    `2 (n - 2)` tets of the best triangulation of the ring polygon joined
//!    to its two ends (Shewchuk's edge removal, Klincsek's dynamic
//!    programme; `n = 3` is the 3-2 flip), when every new tet is positive
//!    (exact `orient3d`) and the worst is better; the boundary does not
//!    change and no point moves. Measured on the final meshes: bunny at
//!    0.3 mm 6.21..167.84 deg to 10.00..159.99 deg, 0.007 % under 10 deg to
//!    0 (115 removals, 12 on rings of 4; the 3-2 flip alone made 38).
//! 6. **Star insertion** (`star.rs`): for a tet still under the sliver bound
//!    (caps first), a new interior point replaces a cavity of tets with its
//!    star: the cavity grows from the tet into the neighbours whose
//!    circumball contains the point, never across a subfacet nor into another
//!    region, and is then grown or shrunk until the point sees every face of
//!    its boundary strictly from inside (exact `orient3d`), so the star's tets
//!    are positive and fill the cavity exactly; the boundary, the interfaces
//!    and every existing point stay as they were. Candidates: the apexes of
//!    regular tets over the tet's boundary faces (three heights), their mean
//!    for a cap, its circumcentre, points under its short boundary edges and
//!    hinges, and from each the mean of the regular apexes over the faces of
//!    the star it makes (the whole patch); the best star is taken when its worst tet
//!    beats the cavity's, its dihedral angles stay within the cavity's range
//!    and no tet exceeds the volume bound. This is the
//!    constrained insertion the Delaunay stages cannot make on a bent scan
//!    ("What is not done").
//! 7. **Smoothing** (`smooth.rs`): Steiner vertices of bad tets (smallest
//!    dihedral angle, or 180 deg minus the largest, under the sliver bound)
//!    move to the candidate position that most raises that quality over their
//!    star, never inverting a tet (exact `orient3d`), exceeding the volume
//!    bound nor taking the star's dihedral angles out of their range: interior ones anywhere, those on an input triangle within its
//!    plane, those on an input edge along it; input vertices never move, so the
//!    boundary stays exact. Then the Steiner vertices of tets of radius-edge
//!    ratio over the refinement bound move likewise to lower their star's
//!    largest ratio, never taking its smallest angle quality under the sliver
//!    bound (`smooth::smooth_radius_edge`): the tets refinement leaves next to
//!    the boundary, whose candidates are blocked by subfacets (hinge: p99.9
//!    ratio 1.74 to 1.47; fandisk 2.23 to 1.74; bunny 1.75 to 1.41).
//!
//! Everything is deterministic (candidate points come from generators seeded by
//! the tet's or vertex's indices). Two steps run on both cores: the probing
//! of a bad tet's candidate points (`refine.rs`: each verdict is a function
//! of the tetrahedralization and the point, read in candidate order), and
//! the judging of vertices in smoothing (`smooth.rs`: a batch of vertices
//! judged against the positions at its start, those whose star moved since
//! judged again, the moves made in vertex order), so the result does not
//! depend on the number of threads. The output's cells are
//! sorted by their corners (vertex indices, in insertion order), not taken in
//! the order of their slots in the tetrahedralization: which slot a new tet
//! gets depends on where the location walk of its point ended when the point
//! lies on a face or edge (a midpoint of an input edge with coordinates read
//! from single precision is exactly on it), which depends on the walk's start
//! and random face order, i.e. on machinery; the corners do not, and
//! smoothing sums over each vertex's star in cell order, so its result
//! (rounding, then which move wins) depends on that order. Sorting made the
//! meshes independent of how points are located; against the unsorted order it
//! changes the smoothed coordinates (same cells, same refinement: measured
//! with `conforming_probe`'s fingerprints) and the quality within the noise of
//! smoothing, every gate holding (BENCHMARKS.md).
//!
//! ## What is not done, and why
//!
//! Refining subfacets for every tet that is bad for quality alone (a bad
//! radius-edge ratio or a sliver next to the boundary that is no cap), beyond
//! tets on four input vertices and tets of ratio over 1.5 on merged planes,
//! does not converge: measured with the merged facets (before the off-centres
//! of `refine.rs`), refining the subfacet encroached by any radius-edge-bad
//! tet doubled fandisk's count and stopped at the pass limit with 468 bad
//! tets left; with the off-centres, on every facet for tets of ratio over 3,
//! the bunny's smallest angle fell to 1.43 deg (against TetGen's 3.81); with
//! the facets refined first, on every facet for tets over 1.5, the hinge's
//! count rose to 44 653 and its p99.9 ratio to 2.30. Before the facets were
//! refined first, bounds under 2.3 for merged planes made slivers next to
//! the splits (2.0: 5.00 deg; 1.5: p99.9 8.5, 1.84 deg); with them refined
//! first they do not (1.5: 10.03 deg). Refining the facets after the tets
//! instead of before (when no bad tet is left) made the hinge worse (p99.9
//! 1.88; with the merged-plane bound at 1.5, 2.75 and 5.00 deg): the tets
//! then have no room to adapt to the new boundary points.
//!
//! **The hinge's p99.9 radius-edge ratio cannot reach TetGen's 1.41 with an
//! exact boundary.** 100 of its input triangles have a corner under 20.8 deg
//! between two input edges across which the surface bends by more than the
//! 1e-9 Hausdorff gate allows (chamfer quads split into two triangles whose
//! 7-digit coordinates make them coplanar only to 1e-6 mm): a mesh that keeps
//! those edges has a boundary face in each such corner of ratio at least
//! 1 / (2 sin 20.8 deg) = 1.41, hence a tet as bad, and 100 is more than
//! 0.1 % of 1.25 x TetGen's count (`tests/tetgen_golden.rs` asserts both).
//! TetGen merges such triangles (its coplanarity tolerance) and drops the
//! edge: its faces there lie 2e-7 mm off the input. Ours is at that floor:
//! 1.47 (2.23 without the facets refined first and smoothing for the ratio;
//! 1.74 with the facets refined first but without the smoothing). No flips are done during refinement: it keeps
//! the tetrahedralization Delaunay, which boundary recovery relies on; the
//! 3-2 flips of stage 5 come after it.

//! **Splitting every cap's hinge leaves thousands of flat tets on a coarse,
//! bent scan (CGAL's armadillo).** At h = 8 mm 15 190 of its
//! 16 458 tets under 10 deg had two faces on the boundary and four corners
//! on the surface (down to 0.004 deg, which also made its p99.9 radius-edge
//! ratio 3e4), and edge removal, star insertion and smoothing removed few
//! (BENCHMARKS.md). Classified by shape (a corner over the
//! opposite face is a cap, corners in convex position a sliver, one edge
//! under a third of the longest a wedge, more a needle) they were no caps:
//! 9 247 wedges and 5 934 needles, their largest angle at the hinge (mostly
//! 160 to 170 deg). The cap rule of stage 3 made them (inferred from the
//! fix's effect; where their short edge lay was not counted): it split each
//! cap's hinge, whichever edge of its subfacets that was, until its bound
//! (30 171 splits), and a split of a hinge shorter than the subfacets' other
//! edges makes skinnier subfacets whose caps are wedges over shorter hinges
//! again. Splitting only a hinge that is the longest edge of both subfacets
//! ends the cascade (9 324 splits; 3 tets with two boundary faces left
//! under 10 deg at the end): 383 881 tets, 7.64..161.62 deg, 0.004 % under
//! 10 deg, p99.9 ratio 3.13, every gate against TetGen held, in a fifth of
//! the time.
//!
//! Quality refinement runs on a copy of the state, each boundary recovery it
//! triggers bounded (20 000 points) and its cap splits bounded (as many as the
//! points present when it starts); when a recovery does not converge, size
//! refinement runs alone on the original (`RefineStats::quality_failed`). At
//! coarse sizes cap splitting can cascade up to its bound and leave more
//! slivers than size refinement alone (measured: bunny at 0.8 mm, 5.6 % of tets
//! under 10 deg, 7 s); at the size of the TetGen comparison (0.3 mm) it does
//! not (0.012 %, 4.4 s).
//!
//! Termination is not proven for input with very sharp angles between facets
//! (the theory needs protecting balls around such edges); a budget of Steiner
//! points turns a run that does not converge into a typed error. Merging
//! coplanar triangles removes the small angles that only the triangulation of
//! a plane made (needle triangles), which is what made the hinge run away
//! (merged, its shortest mesh edge is 0.135 mm at h = 2 mm; the
//! `conforming_probe` example's `PROBE_WORST` prints it).

mod delaunay;
mod facet;
mod flip;
mod order;
mod perturb;
mod recover;
mod refine;
mod smooth;
mod star;

use std::collections::{BTreeMap, HashMap};
use std::time::Instant;

use fem_core::mesh::TetMesh;
use serde::Serialize;
use thiserror::Error;

pub use delaunay::{Delaunay, DelaunayError, Probe, ProbeScratch, FACE, GHOST};
pub use flip::FlipStats;
pub use perturb::insphere;
pub use refine::RefineStats;
pub use smooth::SmoothStats;
pub use star::StarStats;

/// Passes of sliver smoothing.
pub const SMOOTHING_PASSES: usize = 8;

use crate::validate::InvalidSurface;
use crate::{Surface, WindingNumber};

/// The options of [`conforming_mesh`].
#[derive(Debug, Clone, PartialEq)]
pub struct ConformingOptions {
    /// Target edge length [mm]: tets larger than the regular tet of this edge
    /// (volume `h^3 / (6 sqrt 2)`, TetGen's `-a`) are refined. `None`: no size bound.
    pub size_mm: Option<f64>,
    /// The most Steiner points boundary recovery may add, as a multiple of the
    /// input vertices (plus 10 000); default 50.
    pub max_steiner_per_vertex: usize,
    /// Radius-edge bound of quality refinement (TetGen's `-q`); default
    /// [`DEFAULT_RADIUS_EDGE`]. Infinite: none.
    pub radius_edge: f64,
    /// Sliver bound: tets whose smallest dihedral angle is under it [deg] are
    /// refined or improved; default [`DEFAULT_SLIVER_DEG`]. 0: none, and no
    /// smoothing at all (the smoothing for the radius-edge ratio keeps angles
    /// at this bound, so it runs only with it).
    pub sliver_deg: f64,
}

/// The default radius-edge bound.
pub const DEFAULT_RADIUS_EDGE: f64 = 1.414;
/// The default sliver bound [deg].
pub const DEFAULT_SLIVER_DEG: f64 = 10.0;

impl Default for ConformingOptions {
    fn default() -> Self {
        Self {
            size_mm: None,
            max_steiner_per_vertex: 50,
            radius_edge: DEFAULT_RADIUS_EDGE,
            sliver_deg: DEFAULT_SLIVER_DEG,
        }
    }
}

impl ConformingOptions {
    /// Options for target edge length `size_mm` [mm] and the default quality bound.
    pub fn new(size_mm: f64) -> Self {
        Self { size_mm: Some(size_mm), ..Self::default() }
    }
}

/// Why the conforming mesher refused or failed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ConformingError {
    /// The surface is not clean and closed (strict mode): the defect, named.
    #[error("conforming mode needs a clean, closed surface: {0}")]
    Invalid(InvalidSurface),
    /// The points have no tetrahedralization.
    #[error(transparent)]
    Delaunay(DelaunayError),
    /// Boundary recovery did not converge.
    #[error("boundary recovery failed after {steiner_points} Steiner points: {missing}")]
    RecoveryFailed {
        /// Steiner points added.
        steiner_points: usize,
        /// What went wrong.
        missing: String,
    },
    /// The size is not a positive, finite length.
    #[error("element size {size_mm} mm: must be finite and > 0")]
    BadSize {
        /// The size given [mm].
        size_mm: f64,
    },
    /// The result failed its final check (a bug: please report it with the input).
    #[error("the conforming mesh failed its check: {cause}")]
    Internal {
        /// The check that failed.
        cause: String,
    },
}

// Not `#[from]`: that would also make it the error's source, and error chains
// would name the defect twice.
impl From<InvalidSurface> for ConformingError {
    fn from(e: InvalidSurface) -> Self {
        ConformingError::Invalid(e)
    }
}

/// Counts and timings of a run.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ConformingStats {
    /// Input vertices.
    pub input_vertices: usize,
    /// Input triangles.
    pub input_triangles: usize,
    /// Facets: the planar polygons the coplanar input triangles merge into.
    pub facets: usize,
    /// Steiner points added on input edges.
    pub steiner_on_edges: usize,
    /// Steiner points added inside input triangles.
    pub steiner_on_triangles: usize,
    /// Subfacets (boundary and interface triangles) recovered.
    pub subfacets: usize,
    /// Tets of the Delaunay tetrahedralization (all, before removing the outside).
    pub delaunay_tets: usize,
    /// Quality refinement.
    pub refinement: RefineStats,
    /// Edge removal around slivers, before smoothing (`flip.rs`).
    pub flips: FlipStats,
    /// Star insertion around slivers and caps, after edge removal (`star.rs`).
    pub stars: StarStats,
    /// Sliver smoothing.
    pub smoothing: SmoothStats,
    /// Smoothing for the radius-edge ratio, after sliver smoothing.
    pub radius_edge_smoothing: SmoothStats,
    /// Wall time [s].
    pub time_s: f64,
    /// Wall time of each stage [s].
    pub stage_times: StageTimes,
}

/// Wall time of each stage of [`conforming_mesh`] [s] (module docs' numbering).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Validation, the Delaunay tetrahedralization and boundary recovery (stages 1, 2) [s].
    pub recovery_s: f64,
    /// Size and quality refinement (stage 3) [s].
    pub refinement_s: f64,
    /// The inside's components, regions and flat caps (stage 4) [s].
    pub regions_s: f64,
    /// Edge removal (stage 5) [s].
    pub edge_removal_s: f64,
    /// Star insertion (stage 6) [s].
    pub stars_s: f64,
    /// Sliver smoothing (stage 7) [s].
    pub smoothing_s: f64,
    /// Smoothing for the radius-edge ratio (stage 7) [s].
    pub radius_edge_smoothing_s: f64,
    /// The boundary sets and the final check [s].
    pub check_s: f64,
}

/// The result of [`conforming_mesh`].
#[derive(Debug, Clone)]
pub struct ConformingMesh {
    /// The mesh: nodes [mm], positive tets, regions, node set and face set
    /// `boundary` (the outer boundary).
    pub mesh: TetMesh,
    /// Counts and timings.
    pub stats: ConformingStats,
}

/// Tetrahedralizes the inside of the clean, closed `surface` so that every
/// input triangle is a union of mesh faces (see the module docs).
pub fn conforming_mesh(surface: &Surface, options: &ConformingOptions) -> Result<ConformingMesh, ConformingError> {
    let start = Instant::now();
    if let Some(h) = options.size_mm {
        if !(h.is_finite() && h > 0.0) {
            return Err(ConformingError::BadSize { size_mm: h });
        }
    }
    surface.require_valid()?;
    // Touching shells given once become one closed region per cell of space.
    let split = crate::envelope::split_cells(surface);
    let regions_surface = split.as_ref().unwrap_or(surface);

    // The vertices the triangles use, and the unique triangles.
    let mut map: HashMap<u32, u32> = HashMap::new();
    let mut vertices = Vec::new();
    let mut facets: Vec<[u32; 3]> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for t in &surface.triangles {
        let mut key = *t;
        key.sort_unstable();
        if !seen.insert(key) {
            continue;
        }
        facets.push(t.map(|v| {
            *map.entry(v).or_insert_with(|| {
                vertices.push(surface.vertices[v as usize]);
                (vertices.len() - 1) as u32
            })
        }));
    }
    let max_steiner = options.max_steiner_per_vertex * vertices.len() + 10_000;
    let mut rec = recover::Recovery::new(&vertices, &facets, max_steiner)?;
    rec.run()?;
    let mut stage_times = StageTimes::default();
    let mut lap = start;
    let mut stage = |slot: &mut f64| {
        *slot = lap.elapsed().as_secs_f64();
        lap = Instant::now();
    };
    stage(&mut stage_times.recovery_s);
    let mut refinement = RefineStats::default();
    if options.size_mm.is_some() {
        let max_volume = options.size_mm.map_or(f64::INFINITY, |h| h.powi(3) / (6.0 * 2f64.sqrt()));
        let enclosed = surface.signed_volume(None).abs();
        let expected = if max_volume.is_finite() { enclosed / max_volume } else { 0.0 };
        let budget = (10.0 * expected).min(5e7) as usize + max_steiner;
        let bounds =
            refine::Bounds { radius_edge: options.radius_edge, max_volume, min_dihedral_deg: options.sliver_deg };
        // Quality refinement on a copy, each recovery it triggers bounded: when
        // it fails (module docs, "What is not done"), size refinement alone.
        let mut trial = rec.clone();
        trial.recover_limit = 20_000;
        match trial.refine(bounds, budget) {
            Ok(stats) => {
                rec = trial;
                rec.recover_limit = usize::MAX;
                refinement = stats;
            }
            Err(_) => {
                let size_only = refine::Bounds { radius_edge: f64::INFINITY, min_dihedral_deg: 0.0, ..bounds };
                refinement = rec.refine(size_only, budget)?;
                refinement.quality_failed = true;
            }
        }
    }
    stage(&mut stage_times.refinement_s);
    let delaunay_tets = rec.dt.finite_tets().count();
    let (mut tets, num_components) = recover::interior_components(&rec);
    // In the order of their corners, not of their slots in the
    // tetrahedralization: the slots depend on where each location walk ended
    // (a point on a face or edge lies in several tets), which is machinery;
    // the corners (vertex indices in insertion order, each tet's corner order
    // inherited from the cavity tet it replaced) do not. Smoothing sums over
    // stars in cell order, so the output depends on this order.
    tets.sort_unstable_by_key(|&(_, t, _)| t);
    if tets.is_empty() {
        return Err(ConformingError::Internal { cause: "no tet is inside the surface".into() });
    }

    // Regions: the smallest shell containing each component.
    let nreg = regions_surface
        .region_names
        .len()
        .max(regions_surface.triangle_regions.iter().map(|&r| r as usize + 1).max().unwrap_or(1))
        .max(1);
    let points = rec.dt.points();
    let mut component_region = vec![0u16; num_components];
    if nreg > 1 {
        let windings: Vec<WindingNumber> =
            (0..nreg as u32).map(|r| WindingNumber::of_region(regions_surface, r)).collect();
        let volume: Vec<f64> = (0..nreg as u32).map(|r| regions_surface.signed_volume(Some(r)).abs()).collect();
        let mut probe: Vec<Option<[u32; 4]>> = vec![None; num_components];
        for (_, t, c) in &tets {
            // The largest tet of each component is the safest probe.
            let vol = |t: &[u32; 4]| crate::quality::tet_quality(&t.map(|v| points[v as usize])).volume_mm3;
            let slot = &mut probe[*c as usize];
            if slot.is_none_or(|p| vol(t) > vol(&p)) {
                *slot = Some(*t);
            }
        }
        for (c, p) in probe.iter().enumerate() {
            let Some(t) = p else { continue };
            let q = t.map(|v| points[v as usize]);
            let centroid = [0, 1, 2].map(|k| (q[0][k] + q[1][k] + q[2][k] + q[3][k]) / 4.0);
            let best =
                (0..nreg).filter(|&r| windings[r].is_inside(centroid)).min_by(|&a, &b| volume[a].total_cmp(&volume[b]));
            component_region[c] = best.unwrap_or(0) as u16;
        }
    }
    // Flat caps on coplanar input triangles go (see `drop_flat_caps`).
    let tets = drop_flat_caps(points, tets, facet::COPLANAR_TOL * surface.diagonal());
    let cell_tets: Vec<[u32; 4]> = tets.iter().map(|(_, t, _)| *t).collect();
    let (mut nodes, mut cells) = recover::compact(points, &cell_tets);
    let mut cell_regions: Vec<u16> = tets.iter().map(|(_, _, c)| component_region[*c as usize]).collect();
    let mut smoothing = SmoothStats::default();
    let mut radius_edge_smoothing = SmoothStats::default();
    let mut flips = FlipStats::default();
    let mut stars = StarStats::default();
    if options.sliver_deg > 0.0 {
        // `compact` numbers the used vertices in increasing order.
        let mut index: Vec<u32> = cell_tets.iter().flatten().copied().collect();
        index.sort_unstable();
        index.dedup();
        let renumber = |v: u32| index.binary_search(&v).ok().map(|i| i as u32);
        // The subfacets, in the compacted numbering (sorted corners): edge
        // removal keeps them.
        let constrained: flip::FaceSet = rec
            .face_owner
            .keys()
            .filter_map(|f| {
                let [a, b, c] = f.map(renumber);
                let mut k = [a?, b?, c?];
                k.sort_unstable();
                Some(k)
            })
            .collect();
        stage(&mut stage_times.regions_s);
        flips = flip::remove_edges(&nodes, &mut cells, &mut cell_regions, &constrained, options.sliver_deg);
        stage(&mut stage_times.edge_removal_s);
        let max_volume = options.size_mm.map_or(f64::INFINITY, |h| h.powi(3) / (6.0 * 2f64.sqrt()));
        stars =
            star::insert_stars(&mut nodes, &mut cells, &mut cell_regions, &constrained, options.sliver_deg, max_volume);
        stage(&mut stage_times.stars_s);
        let all = rec.freedom();
        // The points star insertion added are interior: free.
        let freedom: Vec<recover::Freedom> = index
            .iter()
            .map(|&v| all[v as usize])
            .chain(std::iter::repeat(recover::Freedom::Free))
            .take(nodes.len())
            .collect();
        smoothing = smooth::smooth(
            &mut nodes,
            &cells,
            &freedom,
            options.sliver_deg,
            max_volume,
            SMOOTHING_PASSES,
            smooth::BATCH,
        );
        stage(&mut stage_times.smoothing_s);
        if options.radius_edge.is_finite() {
            radius_edge_smoothing = smooth::smooth_radius_edge(
                &mut nodes,
                &cells,
                &freedom,
                options.radius_edge,
                options.sliver_deg,
                max_volume,
                SMOOTHING_PASSES,
                smooth::BATCH,
            );
        }
        stage(&mut stage_times.radius_edge_smoothing_s);
    } else {
        stage(&mut stage_times.regions_s);
    }
    let region_names = if nreg > 1 {
        regions_surface.region_names.clone()
    } else {
        vec![surface.region_names.first().cloned().unwrap_or_else(|| "region0".into())]
    };
    let mut mesh =
        TetMesh { nodes, cells, cell_regions, region_names, node_sets: BTreeMap::new(), face_sets: BTreeMap::new() };
    mesh.add_boundary_sets("boundary");
    mesh.validate().map_err(|e| ConformingError::Internal { cause: e.to_string() })?;
    stage(&mut stage_times.check_s);
    let stats = ConformingStats {
        input_vertices: vertices.len(),
        input_triangles: facets.len(),
        facets: rec.facets.len(),
        steiner_on_edges: rec.steiner_on_segments,
        steiner_on_triangles: rec.steiner_on_facets,
        subfacets: rec.face_owner.len(),
        delaunay_tets,
        refinement,
        flips,
        stars,
        smoothing,
        radius_edge_smoothing,
        time_s: start.elapsed().as_secs_f64(),
        stage_times,
    };
    Ok(ConformingMesh { mesh, stats })
}

/// Below this smallest dihedral angle [deg] a tet is flat (its corners coplanar
/// within the rounding of Steiner points).
const FLAT_DEG: f64 = 1e-3;

/// Removes the *flat caps*: tets whose corners are coplanar within rounding
/// (smallest dihedral angle under [`FLAT_DEG`]) with a face on the region's
/// boundary. Such a tet lies on coplanar input triangles (the symbolic
/// perturbation of the Delaunay stage makes zero-volume tets legal there, and
/// Steiner points on them are coplanar within rounding); without it the
/// boundary is its other faces,
/// which cover the same piece of the plane: the boundary is geometrically the
/// same (coplanar input triangles merged, as the issue allows), the volume
/// changes by the cap's (about 1e-17 of a cubic mm). Repeats until none is left.
fn drop_flat_caps(
    points: &[crate::predicates::Point],
    mut tets: Vec<(u32, [u32; 4], u32)>,
    tol: f64,
) -> Vec<(u32, [u32; 4], u32)> {
    loop {
        // Faces by sorted corners -> (count, component); never iterated.
        let mut faces: recover::FaceMap<(u32, u32)> = recover::FaceMap::default();
        for (_, t, c) in &tets {
            for f in FACE {
                let mut k = f.map(|j| t[j]);
                k.sort_unstable();
                let e = faces.entry(k).or_insert((0, *c));
                e.0 += 1;
                if e.1 != *c {
                    e.0 += 1; // an interface between regions is a boundary too
                }
            }
        }
        let removed: Vec<bool> = tets
            .iter()
            .map(|(_, t, _)| {
                let on_boundary = FACE
                    .iter()
                    .filter(|f| {
                        let mut k = f.map(|j| t[j]);
                        k.sort_unstable();
                        faces.get(&k).is_some_and(|&(n, _)| n != 2)
                    })
                    .count();
                // Flat: its smallest height under `tol` (a needle or a wedge
                // with a tiny angle is no flat cap: removing it would move the
                // boundary).
                on_boundary >= 1 && {
                    let q = t.map(|v| points[v as usize]);
                    crate::quality::dihedral_range_deg(&q).0 < FLAT_DEG && on_its_plane(q, tol)
                }
            })
            .collect();
        if !removed.contains(&true) {
            return tets;
        }
        let mut flags = removed.into_iter();
        tets.retain(|_| !flags.next().unwrap_or(false));
    }
}

/// Whether the tet `q`'s smallest height (its far corner's distance from the
/// plane of its largest face) is at most `tol`.
fn on_its_plane(q: [crate::predicates::Point; 4], tol: f64) -> bool {
    use crate::predicates::{cross, dot, sub};
    let (n, far) = FACE
        .iter()
        .enumerate()
        .map(|(i, f)| (cross(sub(q[f[1]], q[f[0]]), sub(q[f[2]], q[f[0]])), q[i], q[f[0]]))
        .map(|(n, opposite, origin)| (n, (opposite, origin)))
        .max_by(|a, b| dot(a.0, a.0).total_cmp(&dot(b.0, b.0)))
        .unwrap_or(([0.0; 3], ([0.0; 3], [0.0; 3])));
    let l = dot(n, n).sqrt();
    l > 0.0 && (dot(sub(far.0, far.1), n) / l).abs() <= tol
}
