//! Rigid tools: shapes (through parry3d, its f64 build), kinematic trajectories,
//! and the closest-point queries the contact solver needs.
//!
//! A tool is a rigid shape in its own frame, placed in the world by a pose that
//! follows piecewise-linear keyframes in time (translation interpolated linearly,
//! rotation by slerp). Any number of tools may press one specimen, each on its own
//! schedule and with its own contact law ([`ToolContact`]); each lets go at its
//! own `release_s`.
//!
//! 2D problems (plane and axisymmetric) query the tool in the plane `z = 0`: a
//! sphere centred in that plane is a disc in a plane problem and a true sphere in
//! an axisymmetric one (when centred on the axis). A tool used in 2D should be
//! symmetric about `z = 0` so that its normals there lie in the plane; the
//! out-of-plane part of a normal is dropped.

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::shape::{Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder, SharedShape, TriMesh, TriMeshFlags};

use super::PressError;

/// A tool's shape, in its own frame [mm].
#[derive(Debug, Clone, PartialEq)]
pub enum ToolShape {
    /// A box centred on the origin with these half extents (a flat plate: its
    /// faces are the flat pressing surfaces).
    Plate { half_extents: [f64; 3] },
    /// A ball centred on the origin.
    Sphere { radius: f64 },
    /// A flat cylindrical punch: axis y, centred on the origin, flat faces at
    /// `y = ±half_height`.
    Punch { radius: f64, half_height: f64 },
    /// A capsule with axis y: a cylinder of `half_height` with hemispherical caps.
    Capsule { radius: f64, half_height: f64 },
    /// The convex hull of points.
    ConvexHull { points: Vec<[f64; 3]> },
    /// A closed, outward-oriented triangle mesh (e.g. imported from OBJ/glTF/STL).
    Mesh { vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]> },
}

/// How a tool holds the surface it touches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ToolContact {
    /// No slip and no separation: a node that touches sticks until `release_s`.
    Glued,
    /// Unilateral, no tangential force.
    Frictionless,
    /// Unilateral, Coulomb friction with this coefficient (stick and slip).
    Friction(f64),
}

/// The tool's pose at a time: translation [mm] and rotation vector (axis times
/// angle) [rad] of its frame in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keyframe {
    pub t_s: f64,
    pub translation_mm: [f64; 3],
    pub rotation_rad: [f64; 3],
}

/// A rigid tool with its trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct Tool {
    /// The tool's name (reports, errors, exports).
    pub name: String,
    pub shape: ToolShape,
    pub contact: ToolContact,
    /// Keyframes in increasing time; the pose is held before the first and after the last.
    pub keyframes: Vec<Keyframe>,
    /// The tool lets go of the specimen at this time [s] (`f64::INFINITY`: never).
    pub release_s: f64,
    /// A floor: its force counts as the bottom force, not the plate's.
    pub floor: bool,
}

/// The closest point of a tool to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Proximity {
    /// Signed gap [mm]: positive outside the tool, negative inside.
    pub gap: f64,
    /// Unit outward normal of the tool at the closest point.
    pub normal: [f64; 3],
    /// The closest point on the tool's surface [mm].
    pub point: [f64; 3],
}

impl Tool {
    /// A flat plate pressing down on a specimen whose bounding box is `lo..hi`:
    /// its lower face starts on the top (`y = hi[1]`) and moves down by `d(t)` given
    /// as `[t_s, d_mm]` waypoints; it reaches well past the specimen's sides.
    pub fn plate_above(
        name: &str,
        lo: [f64; 3],
        hi: [f64; 3],
        waypoints: &[[f64; 2]],
        contact: ToolContact,
        release_s: f64,
    ) -> Self {
        let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max).max(1e-3);
        let half = [size * 2.0, size, size * 2.0];
        let centre = [0.5 * (lo[0] + hi[0]), hi[1] + half[1], 0.5 * (lo[2] + hi[2])];
        Self::moving_down(name, ToolShape::Plate { half_extents: half }, centre, waypoints, contact, release_s)
    }

    /// A flat floor under a specimen whose bounding box is `lo..hi`: its upper face at `y = lo[1]`, fixed.
    pub fn floor_below(name: &str, lo: [f64; 3], hi: [f64; 3], contact: ToolContact) -> Self {
        let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max).max(1e-3);
        let half = [size * 2.0, size, size * 2.0];
        let centre = [0.5 * (lo[0] + hi[0]), lo[1] - half[1], 0.5 * (lo[2] + hi[2])];
        let mut floor = Self::moving_down(
            name,
            ToolShape::Plate { half_extents: half },
            centre,
            &[[0.0, 0.0]],
            contact,
            f64::INFINITY,
        );
        floor.floor = true;
        floor
    }

    /// A tool whose frame starts at `start_mm` (no rotation) and moves down (-y) by
    /// `d(t)` given as `[t_s, d_mm]` waypoints.
    pub fn moving_down(
        name: &str,
        shape: ToolShape,
        start_mm: [f64; 3],
        waypoints: &[[f64; 2]],
        contact: ToolContact,
        release_s: f64,
    ) -> Self {
        let keyframes = waypoints
            .iter()
            .map(|&[t, d]| Keyframe {
                t_s: t,
                translation_mm: [start_mm[0], start_mm[1] - d, start_mm[2]],
                rotation_rad: [0.0; 3],
            })
            .collect();
        Self { name: name.to_string(), shape, contact, keyframes, release_s, floor: false }
    }

    /// Refuses bad shapes, keyframes and contact parameters, naming the tool.
    pub fn validate(&self) -> Result<(), PressError> {
        let bad = |m: String| Err(PressError::BadTool { tool: self.name.clone(), detail: m });
        let positive = |x: f64| x.is_finite() && x > 0.0;
        match &self.shape {
            ToolShape::Plate { half_extents } => {
                if !half_extents.iter().all(|&h| positive(h)) {
                    return bad(format!("plate half extents {half_extents:?} mm must be > 0"));
                }
            }
            ToolShape::Sphere { radius } => {
                if !positive(*radius) {
                    return bad(format!("sphere radius {radius} mm must be > 0"));
                }
            }
            ToolShape::Punch { radius, half_height } | ToolShape::Capsule { radius, half_height } => {
                if !(positive(*radius) && positive(*half_height)) {
                    return bad(format!("radius {radius} mm and half height {half_height} mm must be > 0"));
                }
            }
            ToolShape::ConvexHull { points } => {
                if points.len() < 4 || points.iter().flatten().any(|x| !x.is_finite()) {
                    return bad(format!("a convex hull needs at least 4 finite points, got {}", points.len()));
                }
            }
            ToolShape::Mesh { vertices, triangles } => {
                if triangles.is_empty() || vertices.iter().flatten().any(|x| !x.is_finite()) {
                    return bad("a mesh tool needs triangles and finite vertices".into());
                }
                if let Some((i, t)) =
                    triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= vertices.len()))
                {
                    return bad(format!("triangle {i} = {t:?} names a vertex past the {} given", vertices.len()));
                }
            }
        }
        match self.contact {
            ToolContact::Friction(mu) if !(mu.is_finite() && mu >= 0.0) => {
                return bad(format!("friction coefficient {mu} must be >= 0"));
            }
            _ => {}
        }
        if self.keyframes.is_empty() {
            return bad("no keyframes".into());
        }
        for (i, k) in self.keyframes.iter().enumerate() {
            if !(k.t_s.is_finite() && k.t_s >= 0.0)
                || k.translation_mm.iter().chain(&k.rotation_rad).any(|x| !x.is_finite())
            {
                return bad(format!("keyframe {i} must be finite with t >= 0"));
            }
            if i > 0 && k.t_s <= self.keyframes[i - 1].t_s {
                return bad(format!("keyframe {i} at t = {} s is not after the previous one", k.t_s));
            }
        }
        if self.release_s.is_nan() || self.release_s < 0.0 {
            return bad(format!("release_s = {} must be >= 0", self.release_s));
        }
        self.parry_shape().map(|_| ())
    }

    /// The tool's shape for parry.
    pub(crate) fn parry_shape(&self) -> Result<SharedShape, PressError> {
        let v = |p: &[f64; 3]| Vector::new(p[0], p[1], p[2]);
        Ok(match &self.shape {
            ToolShape::Plate { half_extents } => SharedShape::new(Cuboid::new(v(half_extents))),
            ToolShape::Sphere { radius } => SharedShape::new(Ball::new(*radius)),
            ToolShape::Punch { radius, half_height } => SharedShape::new(Cylinder::new(*half_height, *radius)),
            ToolShape::Capsule { radius, half_height } => SharedShape::new(Capsule::new_y(*half_height, *radius)),
            ToolShape::ConvexHull { points } => {
                let pts: Vec<Vector> = points.iter().map(v).collect();
                SharedShape::new(ConvexPolyhedron::from_convex_hull(&pts).ok_or_else(|| PressError::BadTool {
                    tool: self.name.clone(),
                    detail: "the convex hull of its points is degenerate".into(),
                })?)
            }
            ToolShape::Mesh { vertices, triangles } => {
                let mesh =
                    TriMesh::with_flags(vertices.iter().map(v).collect(), triangles.clone(), TriMeshFlags::ORIENTED)
                        .map_err(|e| PressError::BadTool { tool: self.name.clone(), detail: format!("mesh: {e}") })?;
                SharedShape::new(mesh)
            }
        })
    }

    /// Keyframe times inside `(0, end)` and the release: where the tool's motion has kinks.
    pub(crate) fn kinks(&self, end: f64) -> impl Iterator<Item = f64> + '_ {
        self.keyframes.iter().map(|k| k.t_s).chain(std::iter::once(self.release_s)).filter(move |&t| t > 0.0 && t < end)
    }

    /// The pose at time `t`.
    pub fn pose_at(&self, t: f64) -> ([f64; 3], [f64; 3]) {
        let k = &self.keyframes;
        let at = |f: &Keyframe| (f.translation_mm, f.rotation_rad);
        if t <= k[0].t_s {
            return at(&k[0]);
        }
        for pair in k.windows(2) {
            if t <= pair[1].t_s {
                let w = (t - pair[0].t_s) / (pair[1].t_s - pair[0].t_s);
                let a = pose(&pair[0]);
                let b = pose(&pair[1]);
                let p = a.lerp(&b, w);
                let tr = p.translation;
                let rv = p.rotation.to_scaled_axis();
                return ([tr.x, tr.y, tr.z], [rv.x, rv.y, rv.z]);
            }
        }
        at(&k[k.len() - 1])
    }

    /// The tool's largest displacement from its first pose over its keyframes [mm].
    pub(crate) fn travel(&self) -> f64 {
        let t0 = self.keyframes[0].translation_mm;
        self.keyframes
            .iter()
            .map(|k| (0..3).map(|i| (k.translation_mm[i] - t0[i]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max)
    }

    /// A triangulation of the tool's surface in its own frame (for visualisation).
    pub fn surface_mesh(&self) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let to = |p: Vec<Vector>| p.into_iter().map(|q| [q.x, q.y, q.z]).collect::<Vec<_>>();
        let v = |p: &[f64; 3]| Vector::new(p[0], p[1], p[2]);
        match &self.shape {
            ToolShape::Plate { half_extents } => {
                let (p, t) = Cuboid::new(v(half_extents)).to_trimesh();
                (to(p), t)
            }
            ToolShape::Sphere { radius } => {
                let (p, t) = Ball::new(*radius).to_trimesh(24, 48);
                (to(p), t)
            }
            ToolShape::Punch { radius, half_height } => {
                let (p, t) = Cylinder::new(*half_height, *radius).to_trimesh(48);
                (to(p), t)
            }
            ToolShape::Capsule { radius, half_height } => {
                let (p, t) = Capsule::new_y(*half_height, *radius).to_trimesh(24, 48);
                (to(p), t)
            }
            ToolShape::ConvexHull { points } => {
                let pts: Vec<Vector> = points.iter().map(v).collect();
                match ConvexPolyhedron::from_convex_hull(&pts) {
                    Some(c) => {
                        let (p, t) = c.to_trimesh();
                        (p.into_iter().map(|q| [q.x, q.y, q.z]).collect(), t)
                    }
                    None => (Vec::new(), Vec::new()),
                }
            }
            ToolShape::Mesh { vertices, triangles } => (vertices.clone(), triangles.clone()),
        }
    }
}

fn pose(k: &Keyframe) -> Pose {
    let [x, y, z] = k.translation_mm;
    let [a, b, c] = k.rotation_rad;
    Pose::new(Vector::new(x, y, z), Vector::new(a, b, c))
}

/// A tool ready for queries: its parry shape and a length scale.
pub(crate) struct PlacedTool<'t> {
    pub tool: &'t Tool,
    shape: SharedShape,
    /// A length scale of the shape (half its bounding-box diagonal) [mm].
    scale: f64,
}

impl<'t> PlacedTool<'t> {
    pub fn new(tool: &'t Tool) -> Result<Self, PressError> {
        let shape = tool.parry_shape()?;
        let aabb = shape.compute_local_aabb();
        let scale = 0.5 * (aabb.maxs - aabb.mins).length();
        Ok(Self { tool, shape, scale })
    }

    /// The pose at time `t`, lifted by `lift` [mm] along +y (the machine
    /// compliance's deflection; `0`: the keyframes' pose exactly).
    fn pose(&self, t: f64, lift: f64) -> Pose {
        let (mut tr, rv) = self.tool.pose_at(t);
        if lift != 0.0 {
            tr[1] += lift;
        }
        pose(&Keyframe { t_s: t, translation_mm: tr, rotation_rad: rv })
    }

    /// The closest point of the tool at time `t`, lifted by `lift` [mm] along +y,
    /// to `x`; in 2D (`planar`) the normal's z part is dropped.
    pub fn proximity(&self, x: [f64; 3], t: f64, lift: f64, planar: bool) -> Proximity {
        let pose = self.pose(t, lift);
        let q = Vector::new(x[0], x[1], x[2]);
        let proj = self.shape.project_point(&pose, q, false);
        let d = q - proj.point;
        let dist = d.length();
        let sign = if proj.is_inside { -1.0 } else { 1.0 };
        let mut n = if dist > 1e-10 * self.scale {
            d * (sign / dist)
        } else {
            // On the surface: the normal from a point a little outside, along the
            // line from the tool's centre.
            let c = pose.translation;
            let mut dir = q - c;
            if planar {
                dir.z = 0.0;
            }
            let dir = if dir.length() > 0.0 { dir / dir.length() } else { Vector::new(0.0, -1.0, 0.0) };
            let probe = q + dir * (1e-6 * self.scale);
            let p2 = self.shape.project_point(&pose, probe, false);
            let d2 = probe - p2.point;
            let s2 = if p2.is_inside { -1.0 } else { 1.0 };
            if d2.length() > 0.0 {
                d2 * (s2 / d2.length())
            } else {
                dir
            }
        };
        if planar {
            n.z = 0.0;
            let l = n.length();
            n = if l > 0.0 { n / l } else { Vector::new(0.0, -1.0, 0.0) };
        }
        let normal = [n.x, n.y, n.z];
        Proximity { gap: sign * dist, normal, point: [proj.point.x, proj.point.y, proj.point.z] }
    }

    /// A world point carried by the tool from time `t0` (lifted by `lift[0]`) to
    /// `t1` (lifted by `lift[1]`): a material point of the tool.
    pub fn carry(&self, x: [f64; 3], t0: f64, t1: f64, lift: [f64; 2]) -> [f64; 3] {
        let local = self.pose(t0, lift[0]).inverse_transform_point(Vector::new(x[0], x[1], x[2]));
        let w = self.pose(t1, lift[1]).transform_point(local);
        [w.x, w.y, w.z]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plate_gap_and_normal() {
        let tool =
            Tool::plate_above("p", [0.0; 3], [10.0, 5.0, 10.0], &[[0.0, 0.0], [1.0, 1.0]], ToolContact::Glued, 2.0);
        tool.validate().unwrap();
        let placed = PlacedTool::new(&tool).unwrap();
        let p = placed.proximity([3.0, 5.0, 4.0], 0.0, 0.0, false);
        assert!(p.gap.abs() < 1e-12);
        assert!((p.normal[1] + 1.0).abs() < 1e-12, "{:?}", p.normal);
        let p = placed.proximity([3.0, 5.0, 4.0], 0.5, 0.0, false);
        assert!((p.gap + 0.5).abs() < 1e-12, "{}", p.gap);
        assert!((p.normal[1] + 1.0).abs() < 1e-12);
        let c = placed.carry([3.0, 5.0, 4.0], 0.0, 1.0, [0.0; 2]);
        assert!((c[1] - 4.0).abs() < 1e-12);
        // Lifted by 0.2 mm (a machine's deflection): the gap and the carried point move up with it.
        let p = placed.proximity([3.0, 5.0, 4.0], 0.5, 0.2, false);
        assert!((p.gap + 0.3).abs() < 1e-12, "{}", p.gap);
        let c = placed.carry([3.0, 5.0, 4.0], 0.0, 1.0, [0.1, 0.3]);
        assert!((c[1] - 4.2).abs() < 1e-12, "{c:?}");
    }

    #[test]
    fn sphere_gap_and_normal() {
        let tool = Tool::moving_down(
            "s",
            ToolShape::Sphere { radius: 2.0 },
            [0.0, 3.0, 0.0],
            &[[0.0, 0.0], [1.0, 1.0]],
            ToolContact::Frictionless,
            f64::INFINITY,
        );
        let placed = PlacedTool::new(&tool).unwrap();
        let p = placed.proximity([0.0, 0.5, 0.0], 0.0, 0.0, false);
        assert!((p.gap - 0.5).abs() < 1e-12);
        assert!((p.normal[1] + 1.0).abs() < 1e-12);
        let p = placed.proximity([0.0, 0.5, 0.0], 1.0, 0.0, false);
        assert!((p.gap + 0.5).abs() < 1e-12);
        let p = placed.proximity([1.0, 1.0, 0.0], 0.0, 0.0, true);
        let expect = (1.0f64 + 4.0).sqrt() - 2.0;
        assert!((p.gap - expect).abs() < 1e-12);
    }
}
