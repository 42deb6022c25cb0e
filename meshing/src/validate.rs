//! Surface validation: every defect of a [`Surface`], with where it is.
//!
//! [`validate`] returns a [`SurfaceReport`] listing each [`Defect`] found:
//!
//! | defect | meaning |
//! |---|---|
//! | [`Defect::DegenerateTriangles`] | zero area, exactly (a repeated vertex index, three collinear points), or thinner than the weld tolerance |
//! | [`Defect::DuplicateTriangles`] | the same three points as an earlier triangle, in any order or orientation |
//! | [`Defect::UnweldedVertices`] | distinct vertices within the weld tolerance of each other (exact duplicates included) |
//! | [`Defect::OpenBoundary`] | edges with one triangle (the border edges, as vertex pairs) |
//! | [`Defect::NonManifoldEdges`] | edges where one shell passes more than once (see below) |
//! | [`Defect::InconsistentOrientation`] | edges two neighbours run in the same direction |
//! | [`Defect::Inverted`] | a closed component whose triangles all face inward (negative volume) |
//! | [`Defect::SelfIntersections`] | triangle pairs meeting other than at a shared vertex or edge |
//!
//! Degeneracy, intersections and orientation use exact predicates
//! ([`crate::predicates`]); candidate pairs for intersections come from a
//! bounding-volume hierarchy ([`crate::bvh`]), so the cost grows like
//! `n log n` (the 3.7k-triangle bunny validates in milliseconds).
//! Topology (edges, components, shells), duplicates and intersections are by
//! position: vertices at exactly the same point count as one (the lowest index
//! names it in the report), so a surface whose patches repeat their seam vertices
//! shows its real holes, and the repeated vertices are reported once, as
//! unwelded.
//!
//! # Multi-region surfaces
//!
//! A valid surface here is one that cuts space into cells, each bounded by closed
//! surfaces: the input of a multi-region mesher. Nested closed shells (a bunny
//! with two spheres inside) are valid. So are two boxes sharing one face given
//! once: the four edges around the shared face carry three triangles each, yet
//! every cell (the outside, each box) meets each edge once. Such edges are listed
//! as [`SurfaceReport::junction_edges`], not as defects. An edge is a
//! [`Defect::NonManifoldEdges`] defect when one cell's boundary passes it twice, as
//! for two cubes that touch along an edge only.
//!
//! ## Shells
//!
//! Every triangle has two sides: `+`, the side its normal `(b - a) x (c - a)`
//! points to, and `-`. Around an edge shared by `k` triangles, the triangles
//! ordered by angle (exactly, with [`crate::predicates::orient3d`]) cut space into
//! `k` wedges; each wedge joins the side of one triangle to the facing side of the
//! next. A *shell* is a class of sides joined this way, across all edges: the
//! boundary of one connected piece of a cell (a region of space) seen from inside
//! that cell. At a border edge (one triangle) the two sides of the triangle join.
//!
//! A closed 2-manifold sphere has two shells: its outside and its inside. Two
//! boxes sharing one face given once have three (the outside of the union and
//! each box's inside), although the four edges around the shared face carry three
//! triangles each; two cubes touching along an edge have three as well, but the
//! outside shell passes that edge twice, which is what makes it non-manifold.
//!
//! The volume of a shell is the divergence-theorem volume of its sides, each
//! oriented away from its cell: positive when the shell encloses its cell,
//! negative when the cell lies outside it (the exterior, or around a cavity).
//!
//! Orientation: each closed component must face outward (the side its triangles'
//! normals point to is the outside of the component); a cavity is a nested region,
//! not an inward-facing shell. Faces inside a component (region interfaces) may
//! face either way. Neighbours across a two-triangle edge must run it in opposite
//! directions, and so must the two triangles around the outside wedge of a
//! junction edge.
//!
//! [`Surface::require_valid`] turns the first defect into an [`InvalidSurface`]
//! error naming the triangle or vertex and its coordinates;
//! [`Surface::require_closed_manifold`] also refuses junction edges.
//!
//! # Example
//!
//! ```
//! use meshing::validate::{validate, Defect, ValidateOptions};
//! use meshing::Surface;
//!
//! // A tetrahedron with one face missing.
//! let open = Surface {
//!     vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
//!     triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2]],
//!     triangle_regions: vec![0; 3],
//!     region_names: vec!["tet".into()],
//! };
//! let report = validate(&open, &ValidateOptions::default())?;
//! assert!(matches!(&report.defects[0], Defect::OpenBoundary { edges, .. } if edges.len() == 3));
//! let err = open.require_valid().unwrap_err();
//! assert!(err.to_string().contains("open boundary: 3 border edges"));
//!
//! // Closed with the fourth face.
//! let mut closed = open.clone();
//! closed.triangles.push([1, 2, 3]);
//! closed.triangle_regions.push(0);
//! assert!(closed.require_valid()?.is_valid());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::collections::HashMap;
use std::fmt;

use rayon::prelude::*;
use thiserror::Error;

use crate::bvh::{Aabb, Bvh};
use crate::predicates::{
    is_degenerate, triangles_intersect, triangles_meet_beyond_vertex, triangles_overlap_across_edge, Point,
};
use crate::topology::{self, side, Edges, UnionFind};
use crate::Surface;

/// What [`validate`] checks, and with what tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidateOptions {
    /// Vertices closer than this fraction of the bounding-box diagonal are
    /// reported as unwelded (default `1e-9`; the same default as
    /// [`crate::repair::RepairOptions::weld_tolerance_rel`]). `0` reports exact
    /// duplicates only.
    pub weld_tolerance_rel: f64,
    /// Whether to search for self-intersections, the costliest check (default
    /// `true`).
    pub self_intersections: bool,
}

impl Default for ValidateOptions {
    fn default() -> Self {
        ValidateOptions { weld_tolerance_rel: 1e-9, self_intersections: true }
    }
}

/// A surface whose indices or numbers cannot be analysed at all.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MalformedSurface {
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle}: vertex index {index} out of range ({num_vertices} vertices)")]
    VertexIndex {
        /// The triangle.
        triangle: usize,
        /// The index it gives.
        index: u32,
        /// The number of vertices.
        num_vertices: usize,
    },
    /// `triangle_regions` and `triangles` differ in length.
    #[error("{num_regions} triangle regions for {num_triangles} triangles")]
    RegionCount {
        /// Length of `triangle_regions`.
        num_regions: usize,
        /// Length of `triangles`.
        num_triangles: usize,
    },
    /// A triangle's region names no entry of `region_names`.
    #[error("triangle {triangle}: region {region} out of range ({num_names} region names)")]
    RegionIndex {
        /// The triangle.
        triangle: usize,
        /// Its region.
        region: u32,
        /// The number of region names.
        num_names: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex}: coordinates {coordinates:?} are not all finite")]
    NonFinite {
        /// The vertex.
        vertex: usize,
        /// Its coordinates [mm].
        coordinates: [f64; 3],
    },
    /// An option out of its range.
    #[error("option {name} = {value}: {expected}")]
    InvalidOption {
        /// The option's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
}

/// Checks that every index is in range and every coordinate finite.
pub fn check_indices(surface: &Surface) -> Result<(), MalformedSurface> {
    let nv = surface.vertices.len();
    if surface.triangle_regions.len() != surface.triangles.len() {
        return Err(MalformedSurface::RegionCount {
            num_regions: surface.triangle_regions.len(),
            num_triangles: surface.triangles.len(),
        });
    }
    for (v, p) in surface.vertices.iter().enumerate() {
        if !p.iter().all(|x| x.is_finite()) {
            return Err(MalformedSurface::NonFinite { vertex: v, coordinates: *p });
        }
    }
    for (t, (tri, &region)) in surface.triangles.iter().zip(&surface.triangle_regions).enumerate() {
        if let Some(&index) = tri.iter().find(|&&i| i as usize >= nv) {
            return Err(MalformedSurface::VertexIndex { triangle: t, index, num_vertices: nv });
        }
        if region as usize >= surface.region_names.len() {
            return Err(MalformedSurface::RegionIndex { triangle: t, region, num_names: surface.region_names.len() });
        }
    }
    Ok(())
}

/// Why a triangle is degenerate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DegenerateKind {
    /// A vertex index appears twice.
    RepeatedVertex,
    /// Three distinct indices at collinear (or coincident) points.
    Collinear,
    /// A positive area, but a height (twice the area over the longest edge)
    /// within the weld tolerance: a needle or cap folded onto its longest edge.
    Thin,
}

/// One degenerate triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DegenerateTriangle {
    /// The triangle's index.
    pub triangle: u32,
    /// Why it has no area.
    pub kind: DegenerateKind,
    /// Its height: twice its area over its longest edge [mm] (0 when exactly
    /// degenerate).
    pub height_mm: f64,
}

/// An edge given by its two vertices, with the triangles using it (ascending).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdgeTriangles {
    /// The edge's vertices, lower index first.
    pub vertices: [u32; 2],
    /// The triangles using the edge.
    pub triangles: Vec<u32>,
}

/// A border edge: an edge used by one triangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BorderEdge {
    /// The edge's vertices in the triangle's direction.
    pub vertices: [u32; 2],
    /// The triangle.
    pub triangle: u32,
}

/// One kind of defect, with every place it occurs (lists ascending by index).
#[derive(Debug, Clone, PartialEq)]
pub enum Defect {
    /// Zero-area triangles.
    DegenerateTriangles {
        /// Each degenerate triangle and why.
        triangles: Vec<DegenerateTriangle>,
    },
    /// Triangles on the same three points as an earlier one.
    DuplicateTriangles {
        /// `[earlier, duplicate]` triangle pairs.
        pairs: Vec<[u32; 2]>,
    },
    /// Groups of distinct vertices within the weld tolerance of each other.
    UnweldedVertices {
        /// Each group, ascending; [`crate::repair`] would merge it into its first.
        clusters: Vec<Vec<u32>>,
        /// The tolerance used [mm].
        tolerance_mm: f64,
    },
    /// Edges with a single triangle.
    OpenBoundary {
        /// The border edges.
        edges: Vec<BorderEdge>,
        /// How many closed loops (or open chains) they form.
        num_loops: usize,
    },
    /// Edges with more than two triangles where one cell's boundary passes more
    /// than once.
    NonManifoldEdges {
        /// The edges and their triangles.
        edges: Vec<EdgeTriangles>,
    },
    /// Edges whose neighbouring triangles run them in the same direction.
    InconsistentOrientation {
        /// The edges and the two triangles running them the same way.
        edges: Vec<EdgeTriangles>,
    },
    /// A closed component whose triangles all face inward.
    Inverted {
        /// The component (see [`SurfaceReport::components`]).
        component: usize,
        /// Its lowest triangle index.
        first_triangle: u32,
        /// Its number of triangles.
        num_triangles: usize,
        /// Its signed volume as given [mm^3] (negative).
        signed_volume_mm3: f64,
    },
    /// Triangle pairs that meet other than at a shared vertex or edge.
    SelfIntersections {
        /// `[lower, higher]` triangle pairs.
        pairs: Vec<[u32; 2]>,
    },
}

impl Defect {
    /// A short name of the kind of defect (`"open boundary"`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            Defect::DegenerateTriangles { .. } => "degenerate triangles",
            Defect::DuplicateTriangles { .. } => "duplicate triangles",
            Defect::UnweldedVertices { .. } => "unwelded vertices",
            Defect::OpenBoundary { .. } => "open boundary",
            Defect::NonManifoldEdges { .. } => "non-manifold edges",
            Defect::InconsistentOrientation { .. } => "inconsistent orientation",
            Defect::Inverted { .. } => "inverted",
            Defect::SelfIntersections { .. } => "self-intersections",
        }
    }

    /// How many places the defect occurs at (triangles, pairs, groups, edges).
    pub fn count(&self) -> usize {
        match self {
            Defect::DegenerateTriangles { triangles } => triangles.len(),
            Defect::DuplicateTriangles { pairs } | Defect::SelfIntersections { pairs } => pairs.len(),
            Defect::UnweldedVertices { clusters, .. } => clusters.len(),
            Defect::OpenBoundary { edges, .. } => edges.len(),
            Defect::NonManifoldEdges { edges } | Defect::InconsistentOrientation { edges } => edges.len(),
            Defect::Inverted { num_triangles, .. } => *num_triangles,
        }
    }

    /// One line naming the defect and its first place, with coordinates [mm] from
    /// `surface` (the surface it was found on).
    pub fn describe(&self, surface: &Surface) -> String {
        let at = |v: u32| {
            let p = surface.vertices.get(v as usize).copied().unwrap_or([f64::NAN; 3]);
            format!("vertex {v} ({}, {}, {})", p[0], p[1], p[2])
        };
        let tri = |t: u32| surface.triangles.get(t as usize).copied().unwrap_or([u32::MAX; 3]);
        let centroid = |t: u32| {
            let ps = tri(t).map(|v| surface.vertices.get(v as usize).copied().unwrap_or([f64::NAN; 3]));
            let c: [f64; 3] = std::array::from_fn(|k| (ps[0][k] + ps[1][k] + ps[2][k]) / 3.0);
            format!("({}, {}, {})", c[0], c[1], c[2])
        };
        match self {
            Defect::DegenerateTriangles { triangles } => {
                let d = triangles[0];
                let why = match d.kind {
                    DegenerateKind::RepeatedVertex => "a repeated vertex".to_string(),
                    DegenerateKind::Collinear => "collinear vertices".to_string(),
                    DegenerateKind::Thin => format!("a height of {:e} mm", d.height_mm),
                };
                let [a, b, c] = tri(d.triangle);
                format!(
                    "degenerate triangles: {} in all; the first, triangle {} (vertices {a}, {b}, {c}), has {why}, at {}",
                    triangles.len(),
                    d.triangle,
                    at(a)
                )
            }
            Defect::DuplicateTriangles { pairs } => {
                let [first, dup] = pairs[0];
                format!(
                    "duplicate triangles: {} in all; the first, triangle {dup}, repeats triangle {first}, at {} mm",
                    pairs.len(),
                    centroid(dup)
                )
            }
            Defect::UnweldedVertices { clusters, tolerance_mm } => {
                let c = &clusters[0];
                format!(
                    "unwelded vertices: {} groups within {tolerance_mm:e} mm; the first, {} and vertex {}, apart by {:e} mm",
                    clusters.len(),
                    at(c[0]),
                    c[1],
                    match (surface.vertices.get(c[0] as usize), surface.vertices.get(c[1] as usize)) {
                        (Some(&p), Some(&q)) => dist(p, q),
                        _ => f64::NAN,
                    }
                )
            }
            Defect::OpenBoundary { edges, num_loops } => {
                let e = edges[0];
                format!(
                    "open boundary: {} border edges in {num_loops} loops; the first from {} to {}, of triangle {}",
                    edges.len(),
                    at(e.vertices[0]),
                    at(e.vertices[1]),
                    e.triangle
                )
            }
            Defect::NonManifoldEdges { edges } => {
                let e = &edges[0];
                format!(
                    "non-manifold edges: {} in all; the first from {} to {}, shared by triangles {:?}",
                    edges.len(),
                    at(e.vertices[0]),
                    at(e.vertices[1]),
                    e.triangles
                )
            }
            Defect::InconsistentOrientation { edges } => {
                let e = &edges[0];
                format!(
                    "inconsistent orientation: {} edges; the first from {} to {}, run the same way by triangles {:?}",
                    edges.len(),
                    at(e.vertices[0]),
                    at(e.vertices[1]),
                    e.triangles
                )
            }
            Defect::Inverted { component, first_triangle, num_triangles, signed_volume_mm3 } => format!(
                "inverted: component {component} (triangle {first_triangle} and {} more, first at {} mm) faces inward, \
                 signed volume {signed_volume_mm3} mm^3",
                num_triangles - 1,
                centroid(*first_triangle)
            ),
            Defect::SelfIntersections { pairs } => {
                let [a, b] = pairs[0];
                format!(
                    "self-intersections: {} triangle pairs; the first, triangles {a} and {b}, near {} mm",
                    pairs.len(),
                    centroid(a)
                )
            }
        }
    }
}

impl fmt::Display for Defect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.kind(), self.count())
    }
}

/// One edge-connected component of the triangles (degenerate and duplicate ones
/// left out).
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// Its lowest triangle index.
    pub first_triangle: u32,
    /// Its number of triangles.
    pub num_triangles: usize,
    /// Whether no edge of it is a border edge.
    pub closed: bool,
    /// Its divergence-theorem volume with the triangles as given [mm^3]
    /// (meaningful when closed and consistently oriented).
    pub signed_volume_mm3: f64,
    /// For a closed component, the volume its outside encloses [mm^3] (from the
    /// shells, whatever the triangles' orientation); `None` when open.
    pub enclosed_volume_mm3: Option<f64>,
}

/// What [`validate`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceReport {
    /// Number of vertices.
    pub num_vertices: usize,
    /// Number of triangles.
    pub num_triangles: usize,
    /// The bounding-box diagonal [mm].
    pub diagonal_mm: f64,
    /// Number of undirected edges.
    pub num_edges: usize,
    /// Edge-connected components, by lowest triangle index.
    pub components: Vec<Component>,
    /// Number of shells (boundaries of cells seen from inside; see the module
    /// docs): 2 for one closed sphere, 3 for two boxes sharing a face.
    pub num_shells: usize,
    /// Edges with more than two triangles where distinct cells meet (region
    /// interfaces, not defects).
    pub junction_edges: Vec<EdgeTriangles>,
    /// Every defect found, in the order of [`Defect`]'s variants.
    pub defects: Vec<Defect>,
}

impl SurfaceReport {
    /// Whether no defect was found.
    pub fn is_valid(&self) -> bool {
        self.defects.is_empty()
    }

    /// The defect of the given kind, if found (e.g.
    /// `report.find(|d| matches!(d, Defect::OpenBoundary { .. }))`).
    pub fn find(&self, pred: impl Fn(&Defect) -> bool) -> Option<&Defect> {
        self.defects.iter().find(|d| pred(d))
    }
}

impl fmt::Display for SurfaceReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let closed = self.components.iter().filter(|c| c.closed).count();
        write!(
            f,
            "{} vertices, {} triangles, {} components ({closed} closed), {} shells, {} junction edges",
            self.num_vertices,
            self.num_triangles,
            self.components.len(),
            self.num_shells,
            self.junction_edges.len()
        )?;
        if self.defects.is_empty() {
            write!(f, "; no defects")
        } else {
            let list: Vec<String> = self.defects.iter().map(|d| d.to_string()).collect();
            write!(f, "; defects: {}", list.join(", "))
        }
    }
}

/// Why a surface was refused by [`Surface::require_valid`] or
/// [`Surface::require_closed_manifold`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum InvalidSurface {
    /// Indices or coordinates that cannot be analysed.
    #[error(transparent)]
    Malformed(#[from] MalformedSurface),
    /// No triangle with an area (none at all, or only degenerate and duplicate
    /// ones): nothing to mesh.
    #[error("no triangle with an area ({num_triangles} triangles given)")]
    Empty {
        /// The number of triangles given.
        num_triangles: usize,
    },
    /// The first defect found, described with its place.
    #[error("{description}{}", if *num_defects > 1 { format!(" (and {} more kinds of defect)", num_defects - 1) } else { String::new() })]
    Defect {
        /// The defect (boxed: it holds lists).
        defect: Box<Defect>,
        /// [`Defect::describe`]'s line.
        description: String,
        /// How many kinds of defect were found in all.
        num_defects: usize,
    },
}

impl Surface {
    /// Validates with [`ValidateOptions::default`] and refuses the surface at the
    /// first defect, naming where it is, or when no triangle has an area.
    /// Junction edges (region interfaces) are accepted.
    pub fn require_valid(&self) -> Result<SurfaceReport, InvalidSurface> {
        let report = validate(self, &ValidateOptions::default())?;
        match report.defects.first() {
            None if report.components.is_empty() => Err(InvalidSurface::Empty { num_triangles: report.num_triangles }),
            None => Ok(report),
            Some(d) => Err(InvalidSurface::Defect {
                defect: Box::new(d.clone()),
                description: d.describe(self),
                num_defects: report.defects.len(),
            }),
        }
    }

    /// As [`Surface::require_valid`], and also refuses junction edges: every edge
    /// must have exactly two triangles (a single-region closed 2-manifold).
    pub fn require_closed_manifold(&self) -> Result<SurfaceReport, InvalidSurface> {
        let report = self.require_valid()?;
        if report.junction_edges.is_empty() {
            return Ok(report);
        }
        let d = Defect::NonManifoldEdges { edges: report.junction_edges.clone() };
        Err(InvalidSurface::Defect { description: d.describe(self), defect: Box::new(d), num_defects: 1 })
    }
}

/// Validates `surface`: every defect, with its place (see the module docs).
///
/// Fails only when the surface is malformed (an index out of range, a non-finite
/// coordinate) or an option is out of range; never modifies the surface.
pub fn validate(surface: &Surface, options: &ValidateOptions) -> Result<SurfaceReport, MalformedSurface> {
    check_indices(surface)?;
    if !(options.weld_tolerance_rel >= 0.0 && options.weld_tolerance_rel.is_finite()) {
        return Err(MalformedSurface::InvalidOption {
            name: "weld_tolerance_rel",
            value: options.weld_tolerance_rel,
            expected: "must be finite and >= 0",
        });
    }
    let n = surface.triangles.len();
    let pos = |v: u32| surface.vertices[v as usize];
    let mut defects = Vec::new();
    let diagonal = surface.diagonal();
    let tolerance = options.weld_tolerance_rel * diagonal;

    // 1. Degenerate triangles.
    let mut degenerate = Vec::new();
    for (t, tri) in surface.triangles.iter().enumerate() {
        let [a, b, c] = *tri;
        let (kind, height_mm) = if a == b || b == c || a == c {
            (DegenerateKind::RepeatedVertex, 0.0)
        } else if is_degenerate(pos(a), pos(b), pos(c)) {
            (DegenerateKind::Collinear, 0.0)
        } else {
            let h = triangle_height(pos(a), pos(b), pos(c));
            if h > tolerance {
                continue;
            }
            (DegenerateKind::Thin, h)
        };
        degenerate.push(DegenerateTriangle { triangle: t as u32, kind, height_mm });
    }
    let mut skip = vec![false; n];
    for d in &degenerate {
        skip[d.triangle as usize] = true;
    }
    if !degenerate.is_empty() {
        defects.push(Defect::DegenerateTriangles { triangles: degenerate });
    }

    // 2. Duplicates, by position.
    let referenced = referenced_vertices(surface);
    let canonical = weld_representatives(&surface.vertices, &referenced, 0.0);
    let canonical_triangles: Vec<[u32; 3]> =
        surface.triangles.iter().map(|t| t.map(|v| canonical[v as usize])).collect();
    let mut first_with: HashMap<[u32; 3], u32> = HashMap::new();
    let mut duplicates = Vec::new();
    for (t, tri) in surface.triangles.iter().enumerate() {
        if skip[t] {
            continue;
        }
        let mut key = tri.map(|v| canonical[v as usize]);
        key.sort_unstable();
        match first_with.get(&key) {
            Some(&first) => duplicates.push([first, t as u32]),
            None => {
                first_with.insert(key, t as u32);
            }
        }
    }
    // From here on, a duplicate is not there: its topology is its original's.
    for &[_, dup] in &duplicates {
        skip[dup as usize] = true;
    }
    if !duplicates.is_empty() {
        defects.push(Defect::DuplicateTriangles { pairs: duplicates });
    }

    // 3. Unwelded vertices.
    let reps = weld_representatives(&surface.vertices, &referenced, tolerance);
    let clusters = clusters_of(&reps);
    if !clusters.is_empty() {
        defects.push(Defect::UnweldedVertices { clusters, tolerance_mm: tolerance });
    }

    // 4. Edges, components, shells.
    let edges = Edges::new(&canonical_triangles, &skip);
    let (component_of, num_components) = topology::components(n, &edges, &skip);
    let shells = topology::shells(&surface.vertices, &canonical_triangles, &edges, &skip);
    let mut components: Vec<Component> = Vec::with_capacity(num_components);
    for (t, &c) in component_of.iter().enumerate() {
        if c == u32::MAX {
            continue;
        }
        if c as usize == components.len() {
            components.push(Component {
                first_triangle: t as u32,
                num_triangles: 0,
                closed: true,
                signed_volume_mm3: 0.0,
                enclosed_volume_mm3: None,
            });
        }
        let comp = &mut components[c as usize];
        comp.num_triangles += 1;
        comp.signed_volume_mm3 += topology::tet_volume(&surface.vertices, surface.triangles[t]);
    }

    let mut border = Vec::new();
    let mut non_manifold = Vec::new();
    let mut junction_edges = Vec::new();
    let mut junction_index = Vec::new();
    let mut inconsistent = Vec::new();
    for e in 0..edges.len() {
        let uses = edges.uses(e);
        let key = edges.keys[e];
        match uses.len() {
            1 => {
                let u = uses[0];
                let vertices = if u.forward { key } else { [key[1], key[0]] };
                border.push(BorderEdge { vertices, triangle: u.tri });
                components[component_of[u.tri as usize] as usize].closed = false;
            }
            2 => {
                if uses[0].forward == uses[1].forward {
                    inconsistent.push(EdgeTriangles { vertices: key, triangles: vec![uses[0].tri, uses[1].tri] });
                }
            }
            _ => {
                let mut seen: Vec<u32> = shells.wedges[e].iter().map(|w| w.shell).collect();
                seen.sort_unstable();
                let repeated = seen.windows(2).any(|w| w[0] == w[1]);
                let entry = EdgeTriangles { vertices: key, triangles: uses.iter().map(|u| u.tri).collect() };
                if repeated {
                    non_manifold.push(entry);
                } else {
                    junction_edges.push(entry);
                    junction_index.push(e);
                }
            }
        }
    }

    // Outer shells of closed components: the shell of least (most negative) volume
    // among the component's sides.
    let mut outer: Vec<Option<u32>> = vec![None; num_components];
    for (t, &c) in component_of.iter().enumerate() {
        if c == u32::MAX || !components[c as usize].closed {
            continue;
        }
        for s in [side(t as u32, true), side(t as u32, false)] {
            let sh = shells.of_side[s as usize];
            let better = match outer[c as usize] {
                None => true,
                Some(o) => shells.volume[sh as usize] < shells.volume[o as usize],
            };
            if better {
                outer[c as usize] = Some(sh);
            }
        }
    }
    for (c, comp) in components.iter_mut().enumerate() {
        comp.enclosed_volume_mm3 = outer[c].map(|o| -shells.volume[o as usize]);
    }
    // Junction edges: the outside wedge's two triangles must run the edge in
    // opposite directions.
    for (je, &e) in junction_edges.iter().zip(&junction_index) {
        for w in &shells.wedges[e] {
            let c = component_of[w.tris[0] as usize] as usize;
            if outer[c] == Some(w.shell) && !w.consistent {
                let mut tris = w.tris.to_vec();
                tris.sort_unstable();
                inconsistent.push(EdgeTriangles { vertices: je.vertices, triangles: tris });
            }
        }
    }
    inconsistent.sort_by_key(|e| e.vertices);

    if !border.is_empty() {
        let num_loops = count_loops(&border);
        defects.push(Defect::OpenBoundary { edges: border, num_loops });
    }
    if !non_manifold.is_empty() {
        defects.push(Defect::NonManifoldEdges { edges: non_manifold });
    }
    if !inconsistent.is_empty() {
        defects.push(Defect::InconsistentOrientation { edges: inconsistent });
    }

    // 5. Inverted closed components: every triangle on the outer shell shows it
    // its `-` side.
    let mut on_outer = vec![0usize; num_components];
    let mut inward = vec![0usize; num_components];
    for (t, &c) in component_of.iter().enumerate() {
        if c == u32::MAX {
            continue;
        }
        let Some(o) = outer[c as usize] else { continue };
        let plus = shells.of_side[side(t as u32, true) as usize] == o;
        let minus = shells.of_side[side(t as u32, false) as usize] == o;
        if plus != minus {
            on_outer[c as usize] += 1;
            if minus {
                inward[c as usize] += 1;
            }
        }
    }
    for (c, comp) in components.iter().enumerate() {
        if on_outer[c] > 0 && inward[c] == on_outer[c] {
            defects.push(Defect::Inverted {
                component: c,
                first_triangle: comp.first_triangle,
                num_triangles: comp.num_triangles,
                signed_volume_mm3: comp.signed_volume_mm3,
            });
        }
    }

    // 6. Self-intersections.
    if options.self_intersections {
        let pairs = self_intersections(surface, &skip, &canonical);
        if !pairs.is_empty() {
            defects.push(Defect::SelfIntersections { pairs });
        }
    }

    Ok(SurfaceReport {
        num_vertices: surface.vertices.len(),
        num_triangles: n,
        diagonal_mm: diagonal,
        num_edges: edges.len(),
        components,
        num_shells: shells.volume.len(),
        junction_edges,
        defects,
    })
}

/// Twice the area over the longest edge [mm]: the smallest height.
pub(crate) fn triangle_height(a: Point, b: Point, c: Point) -> f64 {
    use crate::predicates::{cross, sub};
    let n = cross(sub(b, a), sub(c, a));
    let longest = dist(a, b).max(dist(b, c)).max(dist(c, a));
    if longest == 0.0 {
        return 0.0;
    }
    (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() / longest
}

fn dist(a: Point, b: Point) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Which vertices some triangle uses.
pub(crate) fn referenced_vertices(surface: &Surface) -> Vec<bool> {
    let mut used = vec![false; surface.vertices.len()];
    for tri in &surface.triangles {
        for &v in tri {
            used[v as usize] = true;
        }
    }
    used
}

/// For each vertex, the lowest-index vertex it is welded to: vertices within
/// `tolerance` [mm] of each other join, transitively; only `used` vertices take
/// part (the others map to themselves). `tolerance == 0` joins exact duplicates.
pub(crate) fn weld_representatives(vertices: &[Point], used: &[bool], tolerance: f64) -> Vec<u32> {
    let mut uf = UnionFind::new(vertices.len());
    let max_abs = vertices.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    // Grid cells of the tolerance's size, unless cells would overflow the key or
    // the tolerance is below the coordinates' resolution (then only exact
    // duplicates can be within it).
    let gridded = tolerance > 0.0 && max_abs / tolerance < 1e15;
    if gridded {
        let key = |p: Point| p.map(|x| (x / tolerance).floor() as i64);
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (v, p) in vertices.iter().enumerate() {
            if !used[v] {
                continue;
            }
            let k = key(*p);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(list) = cells.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                            for &w in list {
                                if dist(*p, vertices[w as usize]) <= tolerance {
                                    uf.union(v as u32, w);
                                }
                            }
                        }
                    }
                }
            }
            cells.entry(k).or_default().push(v as u32);
        }
    } else {
        let mut seen: HashMap<[u64; 3], u32> = HashMap::new();
        for (v, p) in vertices.iter().enumerate() {
            if !used[v] {
                continue;
            }
            // `+ 0.0` turns -0.0 into 0.0.
            let k = p.map(|x| (x + 0.0).to_bits());
            match seen.get(&k) {
                Some(&w) => uf.union(v as u32, w),
                None => {
                    seen.insert(k, v as u32);
                }
            }
        }
    }
    (0..vertices.len() as u32).map(|v| uf.find(v)).collect()
}

/// The groups of two or more vertices sharing a representative, ascending.
pub(crate) fn clusters_of(reps: &[u32]) -> Vec<Vec<u32>> {
    let mut members: std::collections::BTreeMap<u32, Vec<u32>> = std::collections::BTreeMap::new();
    for (v, &r) in reps.iter().enumerate() {
        members.entry(r).or_default().push(v as u32);
    }
    members.into_values().filter(|l| l.len() > 1).collect()
}

/// Number of connected chains of border edges (joined at shared vertices).
fn count_loops(border: &[BorderEdge]) -> usize {
    let mut index: HashMap<u32, u32> = HashMap::new();
    for e in border {
        for v in e.vertices {
            let next = index.len() as u32;
            index.entry(v).or_insert(next);
        }
    }
    let mut uf = UnionFind::new(index.len());
    for e in border {
        uf.union(index[&e.vertices[0]], index[&e.vertices[1]]);
    }
    uf.labels().1
}

/// Triangle pairs meeting other than at shared vertices or edges (by position:
/// `canonical` maps each vertex to the first vertex at the same point), leaving
/// out skipped (degenerate and duplicate) triangles.
fn self_intersections(surface: &Surface, skip: &[bool], canonical: &[u32]) -> Vec<[u32; 2]> {
    let live: Vec<u32> = (0..surface.triangles.len() as u32).filter(|&t| !skip[t as usize]).collect();
    let corners = |t: u32| surface.triangles[t as usize].map(|v| surface.vertices[v as usize]);
    let boxes: Vec<Aabb> = live.iter().map(|&t| Aabb::of_points(&corners(t))).collect();
    let bvh = Bvh::new(&boxes);
    let mut pairs: Vec<[u32; 2]> = (0..live.len())
        .into_par_iter()
        .flat_map_iter(|i| {
            let t = live[i];
            let mut found = Vec::new();
            bvh.for_each_overlap(&boxes[i], |j| {
                let u = live[j];
                if u <= t {
                    return;
                }
                if pair_intersects(surface, canonical, t, u) {
                    found.push([t, u]);
                }
            });
            found
        })
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// The exact test for one pair, by the number of vertices they share by position.
fn pair_intersects(surface: &Surface, canonical: &[u32], t: u32, u: u32) -> bool {
    let ct = surface.triangles[t as usize].map(|v| canonical[v as usize]);
    let cu = surface.triangles[u as usize].map(|v| canonical[v as usize]);
    let p = |v: u32| surface.vertices[v as usize];
    let shared: Vec<(usize, usize)> =
        (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).filter(|&(i, j)| ct[i] == cu[j]).collect();
    match shared.len() {
        0 => triangles_intersect(ct.map(p), cu.map(p)),
        1 => {
            let (i, j) = shared[0];
            let t1 = [ct[i], ct[(i + 1) % 3], ct[(i + 2) % 3]].map(p);
            let t2 = [cu[j], cu[(j + 1) % 3], cu[(j + 2) % 3]].map(p);
            triangles_meet_beyond_vertex(t1, t2)
        }
        2 => {
            let (i0, _) = shared[0];
            let (i1, _) = shared[1];
            let a = ct[3 - i0 - i1];
            let b = *cu.iter().find(|v| !ct.contains(v)).unwrap_or(&cu[0]);
            triangles_overlap_across_edge(p(ct[i0]), p(ct[i1]), p(a), p(b))
        }
        // Same three points: a duplicate, reported as such.
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(offset: [f64; 3]) -> (Vec<Point>, Vec<[u32; 3]>) {
        let v: Vec<Point> = (0..8)
            .map(|i| {
                [offset[0] + f64::from(i & 1), offset[1] + f64::from((i >> 1) & 1), offset[2] + f64::from((i >> 2) & 1)]
            })
            .collect();
        // Outward faces of the unit cube with vertex i at (i&1, i>>1&1, i>>2&1).
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let tris = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        (v, tris)
    }

    fn surface(vertices: Vec<Point>, triangles: Vec<[u32; 3]>) -> Surface {
        let n = triangles.len();
        Surface { vertices, triangles, triangle_regions: vec![0; n], region_names: vec!["r".into()] }
    }

    #[test]
    fn a_cube_is_valid_and_encloses_one() {
        let (v, t) = cube([0.0; 3]);
        let s = surface(v, t);
        let r = s.require_closed_manifold().unwrap();
        assert_eq!(r.components.len(), 1);
        assert_eq!(r.num_shells, 2);
        assert!((r.components[0].enclosed_volume_mm3.unwrap() - 1.0).abs() < 1e-14);
        assert!((s.signed_volume(None) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn an_inverted_cube_is_reported() {
        let (v, mut t) = cube([0.0; 3]);
        for tri in &mut t {
            tri.swap(1, 2);
        }
        let r = validate(&surface(v, t), &ValidateOptions::default()).unwrap();
        assert_eq!(r.defects.len(), 1);
        assert!(matches!(r.defects[0], Defect::Inverted { num_triangles: 12, .. }));
    }

    #[test]
    fn a_flipped_triangle_is_inconsistent_not_inverted() {
        let (v, mut t) = cube([0.0; 3]);
        t[5].swap(1, 2);
        let r = validate(&surface(v, t), &ValidateOptions::default()).unwrap();
        assert_eq!(r.defects.len(), 1);
        assert!(matches!(&r.defects[0], Defect::InconsistentOrientation { edges } if edges.len() == 3));
    }

    #[test]
    fn malformed_surfaces_are_errors_not_panics() {
        let (v, mut t) = cube([0.0; 3]);
        t[3][1] = 99;
        let s = surface(v.clone(), t);
        assert!(matches!(
            validate(&s, &ValidateOptions::default()),
            Err(MalformedSurface::VertexIndex { triangle: 3, index: 99, .. })
        ));
        let (_, t) = cube([0.0; 3]);
        let mut v2 = v;
        v2[4][2] = f64::NAN;
        let err = surface(v2, t).require_valid().unwrap_err();
        assert!(matches!(err, InvalidSurface::Malformed(MalformedSurface::NonFinite { vertex: 4, .. })), "{err}");
    }

    #[test]
    fn cubes_sharing_an_edge_are_non_manifold_but_a_shared_face_is_a_junction() {
        // Two cubes touching along one edge only.
        let (v1, t1) = cube([0.0; 3]);
        let (v2, t2) = cube([1.0, 1.0, 0.0]);
        let mut v = v1.clone();
        v.extend(v2);
        let mut t = t1.clone();
        t.extend(t2.iter().map(|tri| tri.map(|i| i + 8)));
        // Weld the shared edge: cube 2's vertices 0 and 4 are cube 1's 3 and 7.
        for tri in &mut t {
            for i in tri.iter_mut() {
                if *i == 8 {
                    *i = 3;
                } else if *i == 12 {
                    *i = 7;
                }
            }
        }
        let r = validate(&surface(v, t), &ValidateOptions::default()).unwrap();
        let nm = r.find(|d| matches!(d, Defect::NonManifoldEdges { .. })).expect("non-manifold");
        assert!(matches!(nm, Defect::NonManifoldEdges { edges } if edges.len() == 1 && edges[0].vertices == [3, 7]));
        assert!(r.junction_edges.is_empty());
        assert_eq!(r.defects.len(), 1, "{r}");
    }

    #[test]
    fn an_empty_surface_has_no_defects_but_is_refused() {
        let empty = surface(vec![[0.0; 3]; 3], vec![]);
        assert!(validate(&empty, &ValidateOptions::default()).unwrap().is_valid());
        assert!(matches!(empty.require_valid(), Err(InvalidSurface::Empty { num_triangles: 0 })));
        let only_degenerate = surface(vec![[0.0; 3]; 3], vec![[0, 1, 2]]);
        assert!(matches!(only_degenerate.require_valid(), Err(InvalidSurface::Defect { .. })));
    }

    #[test]
    fn welding_tolerance_groups_and_counts_loops() {
        let v = vec![[0.0, 0.0, 0.0], [1e-12, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 0.0, 0.0], [9.0, 0.0, 0.0]];
        let used = vec![true, true, true, true, false];
        assert_eq!(weld_representatives(&v, &used, 0.0), vec![0, 1, 2, 0, 4]);
        assert_eq!(weld_representatives(&v, &used, 1e-9), vec![0, 0, 2, 0, 4]);
        assert_eq!(clusters_of(&[0, 0, 2, 0, 4]), vec![vec![0, 1, 3]]);
        let border = [
            BorderEdge { vertices: [0, 1], triangle: 0 },
            BorderEdge { vertices: [1, 2], triangle: 1 },
            BorderEdge { vertices: [5, 6], triangle: 2 },
        ];
        assert_eq!(count_loops(&border), 2);
    }
}
