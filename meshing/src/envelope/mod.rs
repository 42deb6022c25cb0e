//! Envelope (robust) tetrahedralization: isosurface stuffing of the inside of a
//! triangle soup, for input the conforming mode refuses (open scans,
//! self-intersections, non-manifold edges, overlapping parts, flipped shells).
//!
//! ## What it does
//!
//! 1. **Inside test**: the generalized winding number of the whole soup
//!    ([`crate::WindingNumber`]), inside where `w > 1/2`; shells given inside out
//!    count flipped. Faces flipped against their neighbours in a shell are
//!    turned back first (`orient.rs`; [`EnvelopeWarning::FlippedFaces`]): the
//!    winding number is inverted next to each of them.
//! 2. **Isosurface stuffing** (Labelle and Shewchuk 2007) on a uniform BCC lattice
//!    of spacing `size_mm` (the long lattice edges; the short ones are `0.87 h`):
//!    every boundary node lies on the input surface (a cut point of a lattice edge,
//!    or a lattice vertex warped onto one), and the dihedral angles are proven to
//!    lie in [10.7°, 164.8°] for the outer boundary's stencils where the input
//!    is flat at the lattice's scale (not across its creases: below). With
//!    [`EnvelopeOptions::grade_levels`] > 0, on a **graded** lattice instead
//!    (`graded.rs`): the BCC lattice refined by conforming longest-edge
//!    bisection down to `size_mm / 2^levels` where the input's chord error at the
//!    cell's size exceeds [`EnvelopeOptions::grade_tolerance`] (creases, curved
//!    parts, thin parts, the rims of holes and blades, edges whose faces meet
//!    at less than 90°; these deeper, as the tolerance asks), coarse elsewhere; the same stuffing per tet, with
//!    measured (not proven) warping thresholds, then boundary slivers peeled.
//! 3. **Regions**: with several input regions (OBJ objects or groups, glTF meshes),
//!    each region's shell is cut into the mesh as a conforming interface
//!    (`cut.rs`: warp nodes onto it where close, split the cells that cross it),
//!    then each cell belongs to the *smallest* region (by enclosed volume) whose
//!    shell contains it: nested shells (a filling inside a skin) become nested
//!    regions, overlapping ones go to the smaller.
//! 4. **Layers**: with `layers_mm`, the planes `y = y_min + t1`, `y_min + t1 + t2`, ...
//!    are cut in the same way and each cell belongs to the layer holding its
//!    centroid (regions `layer1`, `layer2`, ... bottom-up; they replace the input's).
//! 5. **Smoothing** of the worst tets (`smooth.rs`), boundary nodes sliding on the input.
//! 6. **Boundary fitting** (`fit.rs`, [`EnvelopeOptions::fit_tolerance`], default
//!    1e-3 of the diagonal): where the boundary is farther than the tolerance
//!    from the solid's true boundary (the input, or the level set `w = 1/2`
//!    where it leaves the input, as the quality report measures it) or the
//!    input from it, boundary tets outside the solid are carved off, boundary
//!    nodes are snapped onto input vertices and edges split (longest-edge
//!    propagation, new boundary nodes on the input), each step taken only if
//!    every tet it makes keeps its dihedral angles in [12°, 155°].
//! 7. **Angle guard** (`guard.rs`): what is still outside [12°, 155°] is smoothed
//!    again (region-shell interface nodes now sliding along the input), flipped
//!    (2-3, 3-2), peeled (thin boundary slivers) or split (an edge inside the
//!    mesh at a point moved off it, which repairs a tet spanning a crease of the
//!    input, whose angle there is the crease's); whatever stays outside
//!    is refused ([`EnvelopeError::AngleGuard`]), never emitted. So every tet of a
//!    returned mesh has its dihedral angles in [12°, 155°].
//!
//! ## What it does not promise
//!
//! The stuffed boundary is a piecewise-linear interpolation of the input on the
//! lattice: its distance to the input is the chord error of triangles of size
//! `h`, and sharp edges, corners and tips of the input are rounded to the lattice
//! (on the bunny the distance falls only at first order in `h`: 2.0e-2, 9.4e-3,
//! 4.5e-3 of the diagonal at h = 0.3, 0.2, 0.1 mm). The fitting brings it within
//! its tolerance only where the angle guard lets it: on the sphere (h = 0.2 of a
//! unit radius) to 9.8e-4 of the diagonal from 1.75e-3, but on the bunny most far
//! points are fitted (input vertices farther than 1e-3 of the diagonal: 290 -> 39
//! at h = 0.2 mm) while the farthest ones, at the ear tips (thin parts the
//! stuffing's tets leave no room to refine under the guard), are not: the
//! bunny's Hausdorff distance stays 9.4e-3 at h = 0.2 mm and 2.0e-2 at 0.3 mm, a
//! miss against the issue's 1e-3 on the uniform lattice (the default). The
//! graded lattice reaches it on the bunny (base 0.2 mm, 3 levels, default
//! grading tolerance: 9.98e-4, tested) but it is opt-in (about 10x the uniform
//! lattice's time), and its angles are measured, not proven: no Labelle–Shewchuk
//! bound covers its tets and thresholds. Measured on the corpus (BENCHMARKS.md):
//! within [13.8°, 151.3°] on every file with 3 levels, once faces
//! flipped against their neighbours are turned back (step 1) and the final guard
//! (step 7) has smoothed the layered bunny's one interface tet; its boundary
//! slivers are peeled off within half the tolerance of the input. On a shape curved everywhere (a sphere) grading
//! saves nothing over a finer uniform lattice; the sizing only looks at the
//! input's triangles within each cell's ball, so a feature the lattice's cells
//! near it miss entirely is not refined.
//! A tighter fit tolerance can bring the volume error down (one-sided chords) but
//! does not bound the Hausdorff distance either. The fitting's splits do not guard
//! the radius-edge ratio: its maximum grows (bunny at 0.3 mm: 2.8 -> 6.7).
//! A part of the input thinner than half the lattice spacing may be lost or
//! thinned: such parts are detected (inward rays shorter than `h / 2` that leave
//! the inside) and reported as [`EnvelopeWarning::ThinFeature`], never dropped
//! silently; likewise a gap narrower than that (outward rays that enter the
//! inside again within `h / 2`: [`EnvelopeWarning::ThinGap`]), which may be
//! closed. Both test one ray per input triangle, from its centroid, with the
//! graded lattice's ray test (`TriangleTree::thin_along`), and where `w` is
//! within 0.1 of 1/2 (a wall may be the level set `w = 1/2`: the teapot
//! handle's open mouth against the body, BENCHMARKS.md, reported as a thin
//! gap) rays from a grid of points on the triangle; a thin
//! part or gap between input triangles that no centroid faces is still not seen. Cells cut by region interfaces and layer planes have no proven angle
//! bound; the quality report measures them, and the final guard refuses what it
//! cannot bring into [12°, 155°]. The outer stencils' proven bound [10.7°,
//! 164.8°] is wider than the targets, and holds for an input flat at the
//! lattice's scale only: a lattice tet whose four vertices are warped onto the
//! input, one edge onto a crease, has the crease's interior angle there (the
//! teapot at 0.25 mm: 158° at the 22° crease along the lid knob's seam, 157° at
//! a 23° one along the handle's; a roof with a 10° crease: 170°), which the
//! guard's splits repair (BENCHMARKS.md).

//! ## Example
//!
//! ```
//! use meshing::envelope::{envelope_mesh, EnvelopeOptions};
//! use meshing::Surface;
//!
//! // A unit cube, outward.
//! let v = |x: f64, y: f64, z: f64| [x, y, z];
//! let s = Surface {
//!     vertices: vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.),
//!                    v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
//!     triangles: vec![[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
//!                     [2, 3, 7], [2, 7, 6], [1, 2, 6], [1, 6, 5], [0, 4, 7], [0, 7, 3]],
//!     triangle_regions: vec![0; 12],
//!     region_names: vec!["cube".into()],
//! };
//! let out = envelope_mesh(&s, &EnvelopeOptions::new(0.25)).unwrap();
//! assert!((out.mesh.measure() - 1.0).abs() < 1e-9);
//! assert!(out.mesh.validate().is_ok());
//! ```

#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)] // `!(x > 0.0)` also refuses NaN, deliberately.

pub(crate) mod cut;
pub(crate) mod fit;
pub(crate) mod graded;
pub(crate) mod guard;
pub(crate) mod lattice;
pub(crate) mod orient;
pub(crate) mod smooth;
pub(crate) mod stuffing;
pub(crate) mod tree;

use std::collections::BTreeMap;
use std::fmt;
use std::time::Instant;

use fem_core::mesh::TetMesh;
use rayon::prelude::*;
use serde::Serialize;
use thiserror::Error;

pub use stuffing::{ALPHA_LONG, ALPHA_SHORT};
pub use tree::TriangleTree;

use crate::winding::WindingNumber;
use crate::Surface;
use tree::{add, cross, norm, scale, sub};

/// The default of [`EnvelopeOptions::grade_levels`] (and of `wagashi mesh --grade-levels`).
pub const DEFAULT_GRADE_LEVELS: u32 = 0;

/// The options of [`envelope_mesh`].
#[derive(Debug, Clone, PartialEq)]
pub struct EnvelopeOptions {
    /// Lattice spacing: the target edge length [mm]. No default: see [`Self::new`].
    pub size_mm: f64,
    /// Layer thicknesses along y, bottom-up from the surface's lowest point [mm];
    /// empty (default): no layers. They must add up to the surface's height within
    /// 1 % (the last layer reaches the top).
    pub layers_mm: Vec<f64>,
    /// The largest lattice (vertices) to build; default 40 million (about 3 GB of
    /// work memory). A finer size is refused with [`EnvelopeError::TooFine`].
    pub max_lattice_vertices: usize,
    /// Boundary fitting tolerance, relative to the surface's bounding-box
    /// diagonal (default 1e-3, the issue's Hausdorff target): the boundary is
    /// refined where it is farther than this from the input, or the input from
    /// it, as far as the angle guard allows (`fit.rs`). 0 turns fitting off.
    pub fit_tolerance: f64,
    /// At most this many fitting rounds (default 10).
    pub max_fit_rounds: usize,
    /// Grading (`graded.rs`): the lattice is refined by bisection down to
    /// `size_mm / 2^grade_levels` where the input is curved, creased or thin at
    /// the scale of the cells, and at the rims of holes (the input's border
    /// edges) deeper, as far as [`Self::grade_tolerance`] asks (to `size_mm /
    /// 2^8` at most); 0 (default): the uniform lattice. At most 8.
    pub grade_levels: u32,
    /// The grading's chord-error tolerance, relative to the bounding-box diagonal
    /// (default 5e-4): a cell is cut while its estimated chord error exceeds it.
    pub grade_tolerance: f64,
}

impl EnvelopeOptions {
    /// Options with lattice spacing `size_mm` [mm] and the defaults.
    pub fn new(size_mm: f64) -> Self {
        Self {
            size_mm,
            layers_mm: Vec::new(),
            max_lattice_vertices: 40_000_000,
            fit_tolerance: 1e-3,
            max_fit_rounds: 10,
            grade_levels: DEFAULT_GRADE_LEVELS,
            grade_tolerance: 5e-4,
        }
    }
}

/// Why the envelope mesher refused or failed.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EnvelopeError {
    /// The size is not a positive, finite length.
    #[error("element size {size_mm} mm: must be finite and > 0")]
    BadSize {
        /// The size given [mm].
        size_mm: f64,
    },
    /// The surface has no triangles.
    #[error("the surface has no triangles")]
    EmptySurface,
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate {position:?}")]
    NonFinite {
        /// 0-based vertex index.
        vertex: usize,
        /// Its coordinates [mm].
        position: [f64; 3],
    },
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} names vertex {vertex}, but the surface has {num_vertices} vertices")]
    BadIndex {
        /// 0-based triangle index.
        triangle: usize,
        /// The vertex it names.
        vertex: u32,
        /// How many there are.
        num_vertices: usize,
    },
    /// The lattice would be too large for this size.
    #[error(
        "element size {size_mm} mm is too fine for a {extent_mm:?} mm shape: {vertices} lattice vertices \
         (at most {max}); use --size-mm {suggest_mm:.3} or larger"
    )]
    TooFine {
        /// The size given [mm].
        size_mm: f64,
        /// The surface's extent [mm].
        extent_mm: [f64; 3],
        /// Lattice vertices needed.
        vertices: usize,
        /// The limit.
        max: usize,
        /// The smallest size within the limit [mm].
        suggest_mm: f64,
    },
    /// Nothing is inside at this size.
    #[error(
        "nothing to mesh: no lattice point at size {size_mm} mm is inside the surface (winding number > 0.5); \
         it encloses no volume (an open sheet?) or is thinner than the size everywhere"
    )]
    NothingInside {
        /// The size given [mm].
        size_mm: f64,
    },
    /// Layer thicknesses that do not fit the shape.
    #[error("layers: {cause}")]
    BadLayers {
        /// What is wrong.
        cause: String,
    },
    /// Tets outside the dihedral angle targets [12°, 155°] that the final guard
    /// (smoothing, flips, peeling of thin boundary slivers, edge splits) could
    /// not repair: refused rather than emitted.
    #[error(
        "{num_cells} tets have dihedral angles outside [12, 155] deg after the repair (no smoothing move, flip, \
         peeling of a thin boundary sliver or edge split improved them); the worst, tet {cell} \
         ({min_deg:.2}..{max_deg:.2} deg) at {centroid_mm:?} mm; try another --size-mm or --grade-levels"
    )]
    AngleGuard {
        /// How many tets are outside.
        num_cells: usize,
        /// The worst one (0-based, in the mesh that would have been emitted).
        cell: usize,
        /// Its smallest dihedral angle [deg].
        min_deg: f64,
        /// Its largest dihedral angle [deg].
        max_deg: f64,
        /// Its centroid [mm].
        centroid_mm: [f64; 3],
    },
    /// The result failed its final check (a bug: please report it with the input).
    #[error("the envelope mesh failed its check: {cause}")]
    Internal {
        /// The check that failed.
        cause: String,
    },
}

/// Something the user should know about the result.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum EnvelopeWarning {
    /// Part of the input is thinner than half the lattice spacing: it may be lost or thinned.
    ThinFeature {
        /// The input region.
        region: String,
        /// Triangles whose inward ray leaves the inside within `h / 2`.
        num_triangles: usize,
        /// Their area [mm^2].
        area_mm2: f64,
        /// The thinnest ray [mm].
        min_thickness_mm: f64,
        /// Bounding box of those triangles [mm].
        lo_mm: [f64; 3],
        /// Bounding box of those triangles [mm].
        hi_mm: [f64; 3],
        /// The lattice spacing [mm].
        size_mm: f64,
    },
    /// A gap of the input (outside between two parts of the inside) narrower
    /// than half the lattice spacing: it may be closed or narrowed.
    ThinGap {
        /// The input region.
        region: String,
        /// Triangles whose outward ray enters the inside again within `h / 2`.
        num_triangles: usize,
        /// Their area [mm^2].
        area_mm2: f64,
        /// The narrowest ray [mm].
        min_width_mm: f64,
        /// Bounding box of those triangles [mm].
        lo_mm: [f64; 3],
        /// Bounding box of those triangles [mm].
        hi_mm: [f64; 3],
        /// The lattice spacing [mm].
        size_mm: f64,
    },
    /// A region's shell was given inside out; it was counted flipped.
    InsideOut {
        /// The input region.
        region: String,
    },
    /// Triangles faced against their neighbours; they were turned to agree with
    /// the larger part of their shell before the inside test.
    FlippedFaces {
        /// The input region.
        region: String,
        /// Triangles turned.
        num_triangles: usize,
    },
    /// An input region got no cell (inside another region of smaller volume, or too thin).
    EmptyRegion {
        /// The input region.
        region: String,
    },
}

impl fmt::Display for EnvelopeWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EnvelopeWarning::ThinFeature {
                region,
                num_triangles,
                area_mm2,
                min_thickness_mm,
                lo_mm,
                hi_mm,
                size_mm,
            } => write!(
                f,
                "region `{region}`: {num_triangles} triangles ({area_mm2:.3e} mm^2) bound a part thinner than half \
                 the lattice spacing {size_mm} mm (thinnest {min_thickness_mm:.3e} mm) in the box \
                 [{:.4}, {:.4}, {:.4}]..[{:.4}, {:.4}, {:.4}] mm; it may be lost or thinned: use a smaller --size-mm",
                lo_mm[0], lo_mm[1], lo_mm[2], hi_mm[0], hi_mm[1], hi_mm[2]
            ),
            EnvelopeWarning::ThinGap { region, num_triangles, area_mm2, min_width_mm, lo_mm, hi_mm, size_mm } => {
                write!(
                    f,
                    "region `{region}`: {num_triangles} triangles ({area_mm2:.3e} mm^2) face a gap narrower than half \
                     the lattice spacing {size_mm} mm (narrowest {min_width_mm:.3e} mm) in the box \
                     [{:.4}, {:.4}, {:.4}]..[{:.4}, {:.4}, {:.4}] mm; it may be closed or narrowed: use a smaller \
                     --size-mm",
                    lo_mm[0], lo_mm[1], lo_mm[2], hi_mm[0], hi_mm[1], hi_mm[2]
                )
            }
            EnvelopeWarning::InsideOut { region } => {
                write!(f, "region `{region}` is inside out (negative enclosed volume); it was counted flipped")
            }
            EnvelopeWarning::FlippedFaces { region, num_triangles } => write!(
                f,
                "region `{region}`: {num_triangles} triangles faced against their neighbours; they were turned to \
                 agree with the rest of their shell"
            ),
            EnvelopeWarning::EmptyRegion { region } => write!(f, "region `{region}` got no cells"),
        }
    }
}

/// Counts and timings of a run.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct EnvelopeStats {
    /// Lattice spacing [mm].
    pub size_mm: f64,
    /// Lattice vertices evaluated.
    pub lattice_vertices: usize,
    /// Of which inside.
    pub inside_vertices: usize,
    /// Cut points of the outer surface.
    pub cut_points: usize,
    /// Lattice vertices warped onto the surface.
    pub warped_vertices: usize,
    /// Interfaces (region shells, layer planes) cut into the mesh.
    pub interfaces: usize,
    /// Nodes moved onto an interface.
    pub interface_moved_nodes: usize,
    /// Nodes added on interfaces.
    pub interface_new_nodes: usize,
    /// Nodes moved by the quality improvement.
    pub smoothed_nodes: usize,
    /// Tets of the lattice stuffed (after grading).
    pub lattice_tets: usize,
    /// Bisections of the grading (0 on the uniform lattice).
    pub grade_bisections: usize,
    /// Boundary slivers removed after the stuffing on the graded lattice.
    pub peeled_slivers: usize,
    /// Boundary fitting rounds run.
    pub fit_rounds: usize,
    /// Edges split by the fitting (boundary ones, and inside ones by its longest-edge propagation).
    pub fit_splits: usize,
    /// Boundary nodes the fitting moved onto input vertices.
    pub fit_snaps: usize,
    /// Boundary tets outside the solid the fitting removed (carved).
    pub fit_carved: usize,
    /// Candidates for which the fitting's angle guard refused every split.
    pub fit_refused: usize,
    /// The smallest and largest dihedral angle [deg] of the mesh the final guard
    /// was handed (after stuffing, smoothing and fitting): on the uniform
    /// lattice, within the stuffing's proven bounds wherever the input is flat at
    /// the lattice's scale (module docs).
    pub dihedral_before_guard_deg: [f64; 2],
    /// Tets outside [12°, 155°] before the final guard.
    pub guard_bad: usize,
    /// Flips (2-3, 3-2) taken by the final guard.
    pub guard_flips: usize,
    /// Thin boundary tets removed by the final guard.
    pub guard_peeled: usize,
    /// Edges split by the final guard (at their midpoints, or off the line for
    /// an edge inside one region: `guard.rs`).
    pub guard_splits: usize,
    /// Wall time [s].
    pub time_s: f64,
}

/// The result of [`envelope_mesh`].
#[derive(Debug, Clone)]
pub struct EnvelopeMesh {
    /// The mesh: nodes [mm], positive tets, regions, node set and face set
    /// `boundary` (the outer boundary).
    pub mesh: TetMesh,
    /// What the user should know (thin parts, flipped shells, empty regions).
    pub warnings: Vec<EnvelopeWarning>,
    /// Counts and timings.
    pub stats: EnvelopeStats,
}

/// Meshes the inside of `surface` (see the module docs).
pub fn envelope_mesh(surface: &Surface, options: &EnvelopeOptions) -> Result<EnvelopeMesh, EnvelopeError> {
    envelope_mesh_with_progress(surface, options, &|_, _| {})
}

/// [`envelope_mesh`], calling `progress(stage, fraction)` as it goes.
pub fn envelope_mesh_with_progress(
    surface: &Surface,
    options: &EnvelopeOptions,
    progress: &(dyn Fn(&str, f64) + Sync),
) -> Result<EnvelopeMesh, EnvelopeError> {
    let start = Instant::now();
    let h = options.size_mm;
    if !(h.is_finite() && h > 0.0) {
        return Err(EnvelopeError::BadSize { size_mm: h });
    }
    check_surface(surface)?;
    let (lo, hi) = surface.bounding_box();
    let diag = surface.diagonal();
    let extent = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    // Lattice size (as in stuffing::stuff): cubes per axis, black + red vertices.
    let cubes = |h: f64| extent.map(|e| ((e + 2.0 * h) / h).ceil() + 3.0);
    let count = |h: f64| {
        let c = cubes(h);
        (c[0] + 1.0) * (c[1] + 1.0) * (c[2] + 1.0) + c[0] * c[1] * c[2]
    };
    let vertices = count(h);
    if vertices > options.max_lattice_vertices as f64 {
        let mut s = h;
        while count(s) > options.max_lattice_vertices as f64 {
            s *= 1.05;
        }
        return Err(EnvelopeError::TooFine {
            size_mm: h,
            extent_mm: extent,
            vertices: vertices.min(usize::MAX as f64) as usize,
            max: options.max_lattice_vertices,
            suggest_mm: s,
        });
    }
    let layer_planes = crate::layers::layer_planes(&options.layers_mm, lo[1], hi[1])
        .map_err(|e| EnvelopeError::BadLayers { cause: e.to_string() })?;

    // Touching closed shells (a face shared by two cells, given once): each cell
    // becomes a closed region of its own.
    let split = split_cells(surface);
    let surface = split.as_ref().unwrap_or(surface);
    // Faces flipped against their neighbours (`orient.rs`): turned back, said.
    let oriented = orient::consistent_orientation(surface);
    let surface = oriented.as_ref().map_or(surface, |o| &o.0);

    let mut warnings = Vec::new();
    let num_regions = num_regions(surface);
    let region_name = |r: usize| surface.region_names.get(r).cloned().unwrap_or_else(|| format!("region{r}"));
    if let Some((_, turned)) = &oriented {
        for (r, &n) in turned.iter().enumerate() {
            if n > 0 {
                warnings.push(EnvelopeWarning::FlippedFaces { region: region_name(r), num_triangles: n });
            }
        }
    }
    for r in 0..num_regions {
        if surface.signed_volume(Some(r as u32)) < 0.0 {
            warnings.push(EnvelopeWarning::InsideOut { region: region_name(r) });
        }
    }

    // 1-2. Stuff the inside of the whole soup.
    progress("inside test", 0.0);
    let winding = WindingNumber::new(surface);
    let eps = 1e-9 * diag.max(f64::MIN_POSITIVE);
    let (stuffed, grade_bisections) = if options.grade_levels > 0 {
        progress("grading", 0.0);
        // The input's border edges (hole rims) and blades (edges whose two
        // triangles' normals are more than 90° apart), each with a third corner
        // of its triangle: the sizing cuts the cells they pass as at a rim.
        let weld = 1e-6 * diag;
        let rims = TriangleTree::new(
            crate::distance::border_edges(surface, weld)
                .into_iter()
                .chain(crate::distance::blade_edges(surface, weld))
                .map(|t| t.map(|v| surface.vertices[v as usize]))
                .collect(),
        );
        let (g, gs) = graded::GradedLattice::new(
            winding.tree(),
            &rims,
            lo,
            hi,
            h,
            options.grade_levels,
            options.grade_tolerance * diag,
            options.max_lattice_vertices,
        );
        (stuffing::stuff_grid(&g, winding.tree(), eps, &|f| progress("stuffing", f)), gs.bisections)
    } else {
        (stuffing::stuff(winding.tree(), lo, hi, h, eps, &|f| progress("stuffing", f)), 0)
    };
    if stuffed.num_inside_vertices == 0 || stuffed.cells.is_empty() {
        return Err(EnvelopeError::NothingInside { size_mm: h });
    }
    let mut stats = EnvelopeStats {
        size_mm: h,
        lattice_vertices: stuffed.num_lattice_vertices,
        inside_vertices: stuffed.num_inside_vertices,
        cut_points: stuffed.num_cut_points,
        warped_vertices: stuffed.num_warped,
        lattice_tets: stuffed.num_lattice_tets,
        grade_bisections,
        ..EnvelopeStats::default()
    };
    let mut mesh = TetMesh {
        nodes: stuffed.nodes,
        cells: stuffed.cells,
        cell_regions: Vec::new(),
        region_names: vec![region_name(0)],
        node_sets: BTreeMap::new(),
        face_sets: BTreeMap::new(),
    };
    if options.grade_levels > 0 {
        let near = 0.5 * options.grade_tolerance.max(options.fit_tolerance) * diag;
        let delta = crate::distance::JUMP_OFFSET * diag;
        stats.peeled_slivers = graded::peel_slivers(&mut mesh.nodes, &mut mesh.cells, &winding, near, delta, 10);
    }
    mesh.cell_regions = vec![0; mesh.cells.len()];

    // 3-4. Interfaces: layer planes, or region shells.
    let cut = if !layer_planes.is_empty() {
        progress("layers", 0.0);
        crate::layers::cut_into_layers(&mut mesh, &layer_planes)
    } else if num_regions > 1 {
        progress("regions", 0.0);
        crate::layers::cut_shells(&mut mesh, surface)
    } else {
        crate::layers::InterfaceStats::default()
    };
    stats.interfaces = cut.interfaces;
    stats.interface_moved_nodes = cut.moved_nodes;
    stats.interface_new_nodes = cut.new_nodes;
    // 5. Quality: move the worst tets' nodes (boundary ones along the input).
    progress("smoothing", 0.0);
    let mut mobility = mobility(&mesh, winding.tree(), eps, false);
    stats.smoothed_nodes = smooth::improve(&mut mesh.nodes, &mesh.cells, &mobility, winding.tree());
    if options.grade_levels > 0 {
        // The graded lattice's stencils have no proven angle bound: a second pass.
        stats.smoothed_nodes += smooth::improve(&mut mesh.nodes, &mesh.cells, &mobility, winding.tree());
    }

    // 6. Boundary fitting towards the input.
    if options.fit_tolerance > 0.0 && options.max_fit_rounds > 0 {
        progress("fitting", 0.0);
        let points = bounding_vertices(surface, &winding, diag);
        let f = fit::fit(
            &mut mesh.nodes,
            &mut mesh.cells,
            &mut mesh.cell_regions,
            &mut mobility,
            winding.tree(),
            &points,
            options.fit_tolerance * diag,
            options.max_fit_rounds,
        );
        stats.fit_rounds = f.rounds;
        stats.fit_splits = f.splits;
        stats.fit_refused = f.refused;
        stats.fit_snaps = f.snaps;
        stats.fit_carved = f.carved;
    }

    // 7. The final angle guard (`guard.rs`): repair, or refuse. First more
    // smoothing of what is left outside [12°, 155°], region-shell interface
    // nodes now sliding along the input like boundary ones (they lie on it; layer
    // planes are not input, so their nodes stay).
    progress("angle guard", 0.0);
    stats.dihedral_before_guard_deg = mesh
        .cells
        .par_iter()
        .map(|c| crate::quality::dihedral_range_deg(&c.map(|v| mesh.nodes[v as usize])))
        .reduce(|| (f64::INFINITY, f64::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)))
        .into();
    if !guard::bad_cells(&mesh.nodes, &mesh.cells).is_empty() {
        let slide = self::mobility(&mesh, winding.tree(), eps, layer_planes.is_empty());
        for _ in 0..3 {
            stats.smoothed_nodes += smooth::improve(&mut mesh.nodes, &mesh.cells, &slide, winding.tree());
            if guard::bad_cells(&mesh.nodes, &mesh.cells).is_empty() {
                break;
            }
        }
    }
    let near = 0.5 * options.grade_tolerance.max(options.fit_tolerance) * diag;
    let g = guard::repair(&mut mesh.nodes, &mut mesh.cells, &mut mesh.cell_regions, near);
    stats.guard_bad = g.bad_before;
    stats.guard_flips = g.flips;
    stats.guard_peeled = g.peeled;
    stats.guard_splits = g.splits;
    let bad = guard::bad_cells(&mesh.nodes, &mesh.cells);
    if let Some(&worst) = bad.iter().min_by(|&&a, &&b| {
        let s = |k: usize| smooth::score(&mesh.cells[k].map(|v| mesh.nodes[v as usize]));
        s(a).total_cmp(&s(b)).then(a.cmp(&b))
    }) {
        let p = mesh.cells[worst].map(|v| mesh.nodes[v as usize]);
        let (min_deg, max_deg) = crate::quality::dihedral_range_deg(&p);
        return Err(EnvelopeError::AngleGuard {
            num_cells: bad.len(),
            cell: worst,
            min_deg,
            max_deg,
            centroid_mm: [0, 1, 2].map(|k| 0.25 * (p[0][k] + p[1][k] + p[2][k] + p[3][k])),
        });
    }

    for (r, name) in mesh.region_names.iter().enumerate() {
        if !mesh.cell_regions.iter().any(|&c| c as usize == r) {
            warnings.push(EnvelopeWarning::EmptyRegion { region: name.clone() });
        }
    }

    // The thin parts of the input.
    progress("thin parts", 0.0);
    warnings.extend(thin_features(surface, &winding, h, diag, false));
    warnings.extend(thin_features(surface, &winding, h, diag, true));

    mesh.add_boundary_sets("boundary");
    mesh.validate().map_err(|e| EnvelopeError::Internal { cause: e.to_string() })?;
    stats.time_s = start.elapsed().as_secs_f64();
    progress("done", 1.0);
    Ok(EnvelopeMesh { mesh, warnings, stats })
}

fn check_surface(surface: &Surface) -> Result<(), EnvelopeError> {
    if surface.triangles.is_empty() {
        return Err(EnvelopeError::EmptySurface);
    }
    for (i, p) in surface.vertices.iter().enumerate() {
        if !p.iter().all(|x| x.is_finite()) {
            return Err(EnvelopeError::NonFinite { vertex: i, position: *p });
        }
    }
    for (i, t) in surface.triangles.iter().enumerate() {
        for &v in t {
            if v as usize >= surface.vertices.len() {
                return Err(EnvelopeError::BadIndex { triangle: i, vertex: v, num_vertices: surface.vertices.len() });
            }
        }
    }
    Ok(())
}

fn num_regions(surface: &Surface) -> usize {
    surface.region_names.len().max(surface.triangle_regions.iter().map(|&r| r as usize + 1).max().unwrap_or(1)).max(1)
}

/// The vertices of the input triangles that bound the inside (the winding number
/// differs on their two sides), in index order: the caps of overlapping parts
/// inside each other are left out (tested at the centroid; the quality report's
/// Hausdorff distance, `crate::distance`, tests a grid on each triangle).
fn bounding_vertices(surface: &Surface, winding: &WindingNumber, diag: f64) -> Vec<[f64; 3]> {
    let delta = 1e-6 * diag;
    let bounding: Vec<bool> = surface
        .triangles
        .par_iter()
        .map(|t| {
            let p = t.map(|v| surface.vertices[v as usize]);
            let c = scale(
                [p[0][0] + p[1][0] + p[2][0], p[0][1] + p[1][1] + p[2][1], p[0][2] + p[1][2] + p[2][2]],
                1.0 / 3.0,
            );
            crate::distance::unit_normal(&p).is_some_and(|n| crate::distance::winding_jumps(winding, c, n, delta))
        })
        .collect();
    let mut used = vec![false; surface.vertices.len()];
    for (t, &b) in surface.triangles.iter().zip(&bounding) {
        if b {
            for &v in t {
                used[v as usize] = true;
            }
        }
    }
    surface.vertices.iter().zip(&used).filter(|(_, &u)| u).map(|(p, _)| *p).collect()
}

/// Triangles whose inward ray (from the inside) leaves the inside within `h / 2`
/// (thin parts), or with `gaps`, whose outward ray (from the outside) enters it
/// again within `h / 2` (thin gaps), grouped by region: the ray test of the
/// graded lattice's sizing ([`TriangleTree::thin_along`]: a thin wall may be
/// the level set `w = 1/2` in an open tube's mouth), from each triangle's
/// centroid and, in the soft field only, from a grid of points of spacing about
/// `h / 2` on it. (Tried: the grid everywhere also flags 39
/// triangles of the clean bunny at 0.2 mm, thinnest 0.026 mm, which the corpus
/// test expects warning-free; not kept.)
fn thin_features(surface: &Surface, winding: &WindingNumber, h: f64, diag: f64, gaps: bool) -> Vec<EnvelopeWarning> {
    let tree = winding.tree();
    let nreg = num_regions(surface);
    let flip: Vec<bool> = (0..nreg as u32).map(|r| surface.signed_volume(Some(r)) < 0.0).collect();
    let reach = 0.5 * h;
    let offset = 1e-7 * diag;
    let hits: Vec<Option<(f64, f64)>> = surface
        .triangles
        .par_iter()
        .enumerate()
        .map(|(i, t)| {
            let r = surface.triangle_regions.get(i).copied().unwrap_or(0) as usize;
            let p = t.map(|v| surface.vertices[v as usize]);
            let n = crate::distance::unit_normal(&p)?;
            // Outward for gaps, inward for parts.
            let dir = if flip.get(r).copied().unwrap_or(false) != gaps { n } else { scale(n, -1.0) };
            let area = 0.5 * norm(cross(sub(p[1], p[0]), sub(p[2], p[0])));
            // The centroid, and in the soft field (`w` within 0.1 of 1/2 just off
            // the triangle, where a wall may be the level set `w = 1/2`) the
            // centroids of the sub-triangles of a grid of spacing about `h / 2`
            // (at most 8 intervals an edge).
            let longest = (0..3).map(|i| norm(sub(p[(i + 1) % 3], p[i]))).fold(0.0, f64::max);
            let m = ((longest / reach).ceil() as usize).clamp(1, 8);
            let at = |u: f64, v: f64| {
                let (u, v) = (u / m as f64, v / m as f64);
                add(p[0], add(scale(sub(p[1], p[0]), u), scale(sub(p[2], p[0]), v)))
            };
            let mut points = vec![scale(add(add(p[0], p[1]), p[2]), 1.0 / 3.0)];
            for i in 0..m {
                for j in 0..m - i {
                    points.push(at(i as f64 + 1.0 / 3.0, j as f64 + 1.0 / 3.0));
                    if i + j + 1 < m {
                        points.push(at(i as f64 + 2.0 / 3.0, j as f64 + 2.0 / 3.0));
                    }
                }
            }
            let mut thinnest: Option<f64> = None;
            for (k, x) in points.into_iter().enumerate() {
                let start = add(x, scale(dir, offset));
                if k > 0 && (tree.winding_number(start) - 0.5).abs() >= crate::winding::NEAR_HALF {
                    continue;
                }
                // The inside (outside) must be there at all (an interior sheet of overlapping parts is not thin).
                if tree.is_inside_checked(start) == gaps {
                    continue;
                }
                if let Some(d) = tree.thin_along(x, dir, reach, offset, crate::winding::NEAR_HALF) {
                    thinnest = Some(thinnest.map_or(d, |t: f64| t.min(d)));
                }
            }
            thinnest.map(|d| (d, area))
        })
        .collect();
    let mut out = Vec::new();
    for r in 0..nreg {
        let mut num = 0;
        let mut area = 0.0;
        let mut thinnest = f64::INFINITY;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (i, hit) in hits.iter().enumerate() {
            let Some((d, a)) = hit else { continue };
            if surface.triangle_regions.get(i).copied().unwrap_or(0) as usize != r {
                continue;
            }
            num += 1;
            area += a;
            thinnest = thinnest.min(*d);
            for &v in &surface.triangles[i] {
                let p = surface.vertices[v as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        if num > 0 {
            let region = surface.region_names.get(r).cloned().unwrap_or_else(|| format!("region{r}"));
            out.push(if gaps {
                EnvelopeWarning::ThinGap {
                    region,
                    num_triangles: num,
                    area_mm2: area,
                    min_width_mm: thinnest,
                    lo_mm: lo,
                    hi_mm: hi,
                    size_mm: h,
                }
            } else {
                EnvelopeWarning::ThinFeature {
                    region,
                    num_triangles: num,
                    area_mm2: area,
                    min_thickness_mm: thinnest,
                    lo_mm: lo,
                    hi_mm: hi,
                    size_mm: h,
                }
            });
        }
    }
    out
}

/// How each node may move in the quality improvement: boundary nodes on the
/// input slide along it, nodes of cells of two regions (interfaces) and boundary
/// nodes off the input (across a hole) stay, the others are free. With
/// `interfaces_slide`, interface nodes on the input slide along it too.
fn mobility(mesh: &TetMesh, tree: &TriangleTree, eps: f64, interfaces_slide: bool) -> Vec<smooth::Mobility> {
    let n = mesh.nodes.len();
    let mut region = vec![u16::MAX; n];
    let mut interface = vec![false; n];
    for (c, &r) in mesh.cells.iter().zip(&mesh.cell_regions) {
        for &v in c {
            let v = v as usize;
            if region[v] == u16::MAX {
                region[v] = r;
            } else if region[v] != r {
                interface[v] = true;
            }
        }
    }
    let mut boundary = vec![false; n];
    for f in mesh.boundary_facets() {
        for v in f {
            boundary[v as usize] = true;
        }
    }
    (0..n)
        .into_par_iter()
        .map(|v| {
            if interface[v] {
                if interfaces_slide && tree.closest_point_within(mesh.nodes[v], eps).is_some() {
                    smooth::Mobility::OnSurface
                } else {
                    smooth::Mobility::Fixed
                }
            } else if boundary[v] {
                if tree.closest_point_within(mesh.nodes[v], eps).is_some() {
                    smooth::Mobility::OnSurface
                } else {
                    smooth::Mobility::Fixed
                }
            } else {
                smooth::Mobility::Free
            }
        })
        .collect()
}

/// A surface whose shells meet at non-manifold edges (two boxes sharing a face
/// given once, or touching along an edge) and that has no border edge, split into
/// one closed region per cell of space it bounds (its shells of positive volume,
/// `crate::topology`), each cell's triangles oriented outward: a shared face is
/// given twice, once per cell. `None` for any other surface (meshed as it is).
pub(crate) fn split_cells(surface: &Surface) -> Option<Surface> {
    use crate::topology::{shells, side, Edges};
    let skip: Vec<bool> = surface
        .triangles
        .iter()
        .map(|t| {
            crate::predicates::is_degenerate(
                surface.vertices[t[0] as usize],
                surface.vertices[t[1] as usize],
                surface.vertices[t[2] as usize],
            )
        })
        .collect();
    let edges = Edges::new(&surface.triangles, &skip);
    let counts: Vec<usize> = (0..edges.len()).map(|e| edges.uses(e).len()).collect();
    if !counts.iter().any(|&c| c > 2) || counts.iter().any(|&c| c < 2) {
        return None;
    }
    let sh = shells(&surface.vertices, &surface.triangles, &edges, &skip);
    let tol = 1e-9 * surface.diagonal().powi(3);
    let cells: Vec<u32> = (0..sh.volume.len() as u32).filter(|&k| sh.volume[k as usize] > tol).collect();
    if cells.len() < 2 {
        return None;
    }
    let mut out = Surface { vertices: surface.vertices.clone(), ..Surface::default() };
    let mut name_count: BTreeMap<String, usize> = BTreeMap::new();
    let mut names = Vec::new();
    for (r, &k) in cells.iter().enumerate() {
        let mut first_region = None;
        for (t, tri) in surface.triangles.iter().enumerate() {
            if skip[t] {
                continue;
            }
            // The side facing the cell: `+` faces it (normal into the cell): reverse.
            if sh.of_side[side(t as u32, true) as usize] == k {
                out.triangles.push([tri[0], tri[2], tri[1]]);
            } else if sh.of_side[side(t as u32, false) as usize] == k {
                out.triangles.push(*tri);
            } else {
                continue;
            }
            out.triangle_regions.push(r as u32);
            first_region.get_or_insert(surface.triangle_regions.get(t).copied().unwrap_or(0));
        }
        let base = first_region
            .and_then(|g| surface.region_names.get(g as usize).cloned())
            .unwrap_or_else(|| "region".to_string());
        *name_count.entry(base.clone()).or_default() += 1;
        names.push(base);
    }
    // Cells sharing a name are numbered.
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    out.region_names = names
        .into_iter()
        .map(|n| {
            if name_count[&n] > 1 {
                let k = seen.entry(n.clone()).or_default();
                *k += 1;
                format!("{n}-{k}")
            } else {
                n
            }
        })
        .collect();
    Some(out)
}
