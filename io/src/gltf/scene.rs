use super::error::{finite, GltfError};

/// Everything one glTF file shows: the specimen's surface deforming over time and
/// the rigid tools moving, on one time line.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfScene {
    /// The specimen.
    pub specimen: AnimatedSurface,
    /// The rigid tools, each its own node; default: none.
    pub tools: Vec<AnimatedTool>,
    /// Free JSON written as `asset.extras.run` (e.g. the trial's name and the
    /// writing program's version); `Null`: none.
    pub extras: serde_json::Value,
}

/// A triangulated surface that deforms: its reference shape and its displacement
/// at a few times (the frames), interpolated linearly in between.
///
/// Vertices shared by several triangles get one averaged normal; a sharp edge
/// (a block's) needs its vertices repeated on each side, as
/// [`SpecimenSurface`](super::SpecimenSurface) does.
#[derive(Debug, Clone, PartialEq)]
pub struct AnimatedSurface {
    /// The name of its node and mesh; unique in the scene, not empty.
    pub name: String,
    /// Reference (undeformed) vertex positions [mm].
    pub positions_mm: Vec<[f64; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// The frames, at strictly increasing times `>= 0`; at least one.
    pub frames: Vec<Frame>,
}

/// The displacement of every vertex of an [`AnimatedSurface`] at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Time [s].
    pub t_s: f64,
    /// A name, e.g. `keep` (at release) or `final` (at the end), written as the
    /// morph target's name; unique among the frames, not empty. Default (`None`):
    /// the target is named after its time to the millisecond, `t=12.5s`.
    pub name: Option<String>,
    /// Displacement of each vertex [mm], in the order of `positions_mm`.
    pub displacement_mm: Vec<[f64; 3]>,
}

/// A rigid tool: a triangulated shape in its own frame, placed by a rigid motion
/// that is interpolated linearly between keys (rotations spherically).
#[derive(Debug, Clone, PartialEq)]
pub struct AnimatedTool {
    /// The name of its node and mesh; unique in the scene, not empty.
    pub name: String,
    /// Vertex positions in the tool's frame [mm].
    pub vertices_mm: Vec<[f64; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// The motion, at strictly increasing times `>= 0`; none: the tool stands still
    /// at the identity pose.
    pub keys: Vec<ToolKey>,
}

/// The pose of a tool at one time: `x_world = R x_tool + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolKey {
    /// Time [s].
    pub t_s: f64,
    /// Translation [mm].
    pub translation_mm: [f64; 3],
    /// Rotation as a quaternion `[x, y, z, w]`; any non-zero length (it is normalized).
    pub rotation_xyzw: [f64; 4],
}

impl ToolKey {
    /// The identity rotation `[0, 0, 0, 1]`.
    pub const NO_ROTATION: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

    /// A key at `t_s` with a translation and no rotation.
    pub fn translated(t_s: f64, translation_mm: [f64; 3]) -> Self {
        Self { t_s, translation_mm, rotation_xyzw: Self::NO_ROTATION }
    }
}

impl AnimatedSurface {
    /// The label of this surface in error messages.
    pub(crate) fn label(&self) -> String {
        format!("specimen `{}`", self.name)
    }

    /// The label of frame `i`.
    pub(crate) fn frame_label(&self, i: usize) -> String {
        format!("{}, frame {i} (t = {} s)", self.label(), self.frames[i].t_s)
    }

    /// The morph target names: a frame's name, or its time to the millisecond
    /// (`t=6.667s`), in full where that is not unique, with `#index` appended
    /// where even that is not.
    pub(crate) fn target_names(&self) -> Vec<String> {
        let short = |t: f64| {
            let s = format!("{t:.3}");
            let s = s.trim_end_matches('0').trim_end_matches('.');
            format!("t={s}s")
        };
        let mut names: Vec<String> =
            self.frames.iter().map(|f| f.name.clone().unwrap_or_else(|| short(f.t_s))).collect();
        let clashes = |names: &[String], i: usize| names.iter().enumerate().any(|(j, n)| j != i && *n == names[i]);
        for pass in 0..2 {
            let clashing: Vec<usize> =
                (0..names.len()).filter(|&i| self.frames[i].name.is_none() && clashes(&names, i)).collect();
            for i in clashing {
                names[i] = if pass == 0 { format!("t={}s", self.frames[i].t_s) } else { format!("{}#{i}", names[i]) };
            }
        }
        names
    }
}

impl AnimatedTool {
    pub(crate) fn label(&self) -> String {
        format!("tool `{}`", self.name)
    }
}

impl GltfScene {
    /// Checks everything the writer relies on; see [`GltfError`] for what is refused.
    pub fn validate(&self) -> Result<(), GltfError> {
        let s = &self.specimen;
        check_mesh(&s.label(), &s.positions_mm, &s.triangles)?;
        if s.frames.is_empty() {
            return Err(GltfError::invalid(s.label(), "no frames: an animation needs at least one"));
        }
        check_times(s.frames.iter().map(|f| f.t_s), |i| format!("{}, frame {i}", s.label()))?;
        let mut names: Vec<&str> = Vec::new();
        for (i, f) in s.frames.iter().enumerate() {
            if f.displacement_mm.len() != s.positions_mm.len() {
                return Err(GltfError::LengthMismatch {
                    what: format!("{}: displacement_mm", s.frame_label(i)),
                    item: "vectors",
                    found: f.displacement_mm.len(),
                    expected: s.positions_mm.len(),
                });
            }
            for (v, d) in f.displacement_mm.iter().enumerate() {
                for (k, &x) in d.iter().enumerate() {
                    finite(x, || format!("{}: displacement_mm of vertex {v} [{k}]", s.frame_label(i)))?;
                }
            }
            if let Some(name) = &f.name {
                if name.is_empty() || names.contains(&name.as_str()) {
                    return Err(GltfError::invalid(
                        s.frame_label(i),
                        format!("frame name `{name}` is empty or already used by another frame"),
                    ));
                }
                names.push(name);
            }
        }

        let mut node_names = vec![s.name.as_str()];
        for tool in &self.tools {
            check_mesh(&tool.label(), &tool.vertices_mm, &tool.triangles)?;
            check_times(tool.keys.iter().map(|k| k.t_s), |i| format!("{}, key {i}", tool.label()))?;
            for (i, key) in tool.keys.iter().enumerate() {
                for (k, &x) in key.translation_mm.iter().enumerate() {
                    finite(x, || format!("{}, key {i}: translation_mm[{k}]", tool.label()))?;
                }
                for (k, &x) in key.rotation_xyzw.iter().enumerate() {
                    finite(x, || format!("{}, key {i}: rotation_xyzw[{k}]", tool.label()))?;
                }
                let norm = key.rotation_xyzw.iter().map(|x| x * x).sum::<f64>().sqrt();
                if norm <= 1e-12 {
                    return Err(GltfError::invalid(
                        format!("{}, key {i}", tool.label()),
                        "rotation_xyzw has zero length; the identity is [0, 0, 0, 1]",
                    ));
                }
            }
            node_names.push(&tool.name);
        }
        for (i, name) in node_names.iter().enumerate() {
            if name.is_empty() {
                return Err(GltfError::invalid("scene", "a specimen or tool has an empty name"));
            }
            if node_names[..i].contains(name) {
                return Err(GltfError::invalid(
                    "scene",
                    format!("two objects are named `{name}`; names must be unique"),
                ));
            }
        }
        Ok(())
    }
}

/// Vertices finite, at least one triangle, every index in range.
fn check_mesh(what: &str, positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Result<(), GltfError> {
    for (v, p) in positions.iter().enumerate() {
        for (k, &x) in p.iter().enumerate() {
            finite(x, || format!("{what}: position of vertex {v} [{k}]"))?;
        }
    }
    if triangles.is_empty() {
        return Err(GltfError::invalid(what, "no triangles"));
    }
    for (t, tri) in triangles.iter().enumerate() {
        if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(GltfError::IndexOutOfRange {
                what: what.to_string(),
                triangle: t,
                vertex,
                num_vertices: positions.len(),
            });
        }
    }
    Ok(())
}

/// Times finite, `>= 0` and strictly increasing, also as `f32` (glTF's storage).
fn check_times(times: impl Iterator<Item = f64>, label: impl Fn(usize) -> String) -> Result<(), GltfError> {
    let mut previous: Option<f64> = None;
    for (i, t) in times.enumerate() {
        finite(t, || format!("{}: t_s", label(i)))?;
        if t < 0.0 {
            return Err(GltfError::invalid(label(i), format!("t = {t} s is negative; glTF times start at 0")));
        }
        if let Some(p) = previous {
            if !(t > p && (t as f32) > (p as f32)) {
                return Err(GltfError::NotIncreasing { what: label(i), t_s: t, previous_s: p });
            }
        }
        previous = Some(t);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_names_are_short_and_unique() {
        let frame = |t_s: f64, name: Option<&str>| Frame { t_s, name: name.map(String::from), displacement_mm: vec![] };
        let surface = AnimatedSurface {
            name: "s".into(),
            positions_mm: vec![],
            triangles: vec![],
            frames: vec![
                frame(0.0, None),
                frame(20.0 / 3.0, None),
                frame(1.0001, None),
                frame(1.0002, None),
                frame(2.0, Some("t=2.5s")),
                frame(2.5, None),
                frame(210.93, Some("keep")),
            ],
        };
        assert_eq!(
            surface.target_names(),
            ["t=0s", "t=6.667s", "t=1.0001s", "t=1.0002s", "t=2.5s", "t=2.5s#5", "keep"]
        );
    }
}
