//! The checks of experiment-format.md that serde's types cannot express.
//!
//! Each check names the key that is wrong and the line it stands on (the line of
//! its table when the key is absent).

use std::collections::BTreeMap;
use std::path::Path;

use fem_core::effects::{EffectError, EffectId, Effects, AGE_KEY};

use super::experiment::{Contact, Experiment, Shape, Tool, ToolKind, FORMAT_V1};
use super::material_spec::MaterialSpec;
use super::series::MarkerSeries;
use crate::error::BundleError;
use crate::source_map::SourceMap;
use crate::surface::LengthUnit;
use crate::tetmesh::TetMeshFormat;

/// Layer thicknesses must sum to H within this [mm].
pub const LAYER_SUM_TOLERANCE_MM: f64 = 1e-6;

/// A marker's initial position may lie this fraction of the specimen's smallest
/// size away from its surface.
pub const MARKER_SURFACE_TOLERANCE: f64 = 0.01;

fn positive(map: &SourceMap, field: &str, value: Option<f64>, what: &str) -> Result<(), BundleError> {
    match value {
        Some(v) if !(v.is_finite() && v > 0.0) => Err(map.invalid(field, format!("{v} is not {what} > 0"))),
        _ => Ok(()),
    }
}

fn refuse_key(map: &SourceMap, field: &str, given: bool, why: String) -> Result<(), BundleError> {
    if given {
        Err(map.invalid(field, why))
    } else {
        Ok(())
    }
}

fn require<T>(map: &SourceMap, field: &str, value: Option<T>, why: &str) -> Result<T, BundleError> {
    value.ok_or_else(|| map.invalid(field, format!("missing required key {why}")))
}

/// Checks an experiment whose materials are already merged.
pub(crate) fn validate_experiment(e: &Experiment, map: &SourceMap) -> Result<(), BundleError> {
    if e.format != FORMAT_V1 {
        return Err(
            map.invalid("format", format!("unsupported format \"{}\"; this reader knows \"{FORMAT_V1}\"", e.format))
        );
    }
    if e.dimension != 2 && e.dimension != 3 {
        return Err(map.invalid("dimension", format!("{} is neither 2 nor 3", e.dimension)));
    }
    validate_specimen(e, map)?;
    for (name, spec) in &e.materials {
        spec.validate(name, map, "materials")?;
    }
    validate_protocol(e, map)?;
    effects_of(e, map)?;
    if let Some(data) = &e.data {
        for (key, file) in [("data.force", &data.force), ("data.markers", &data.markers)] {
            if file.as_deref().is_some_and(|f| f.trim().is_empty()) {
                return Err(map.invalid(key, "empty file name"));
            }
        }
    }
    Ok(())
}

fn validate_specimen(e: &Experiment, map: &SourceMap) -> Result<(), BundleError> {
    let s = &e.specimen;
    let shape = format!("shape = \"{}\"", s.shape.as_str());
    let not_for = |key: &str, belongs: &str| format!("{key} belongs to {belongs}, not to {shape}");
    // A surface or a mesh file brings its own shape: the generated shapes' keys
    // are refused, and its regions need materials.
    let file_shape_keys = |kind: &str| -> Result<(), BundleError> {
        refuse_key(map, "specimen.size_mm", s.size_mm.is_some(), not_for("size_mm", "a block"))?;
        refuse_key(map, "specimen.radius_mm", s.radius_mm.is_some(), not_for("radius_mm", "a cylinder"))?;
        refuse_key(map, "specimen.height_mm", s.height_mm.is_some(), not_for("height_mm", "a cylinder"))?;
        refuse_key(map, "specimen.layers", !s.layers.is_empty(), not_for("layers", "a block"))?;
        if s.regions.is_empty() && s.material.is_none() {
            return Err(map.invalid(
                "specimen.regions",
                format!(
                    "missing required key for shape = \"{kind}\": map each {kind} region to a material (or give `material`)"
                ),
            ));
        }
        Ok(())
    };
    positive(map, "specimen.mass_g", s.mass_g, "a mass")?;
    positive(map, "specimen.density_g_cm3", s.density_g_cm3, "a density")?;
    if e.dimension != 2 && s.plane.is_some() {
        return Err(map.invalid("specimen.plane", "plane stress or strain is for dimension = 2 only"));
    }
    match s.shape {
        Shape::Block => {
            let size = require(map, "specimen.size_mm", s.size_mm.as_ref(), "for shape = \"block\"")?;
            if size.len() != 3 || !size.iter().all(|v| v.is_finite() && *v > 0.0) {
                return Err(map.invalid("specimen.size_mm", "must be three positive lengths [W, H, T] in mm"));
            }
            refuse_key(map, "specimen.radius_mm", s.radius_mm.is_some(), not_for("radius_mm", "a cylinder"))?;
            refuse_key(map, "specimen.height_mm", s.height_mm.is_some(), not_for("height_mm", "a cylinder"))?;
        }
        Shape::Cylinder => {
            if e.dimension == 2 {
                return Err(map.invalid("specimen.shape", "a cylinder is 3D only; dimension = 2 needs a block"));
            }
            let r = require(map, "specimen.radius_mm", s.radius_mm, "for shape = \"cylinder\"")?;
            positive(map, "specimen.radius_mm", Some(r), "a length")?;
            let h = require(map, "specimen.height_mm", s.height_mm, "for shape = \"cylinder\"")?;
            positive(map, "specimen.height_mm", Some(h), "a length")?;
            refuse_key(map, "specimen.size_mm", s.size_mm.is_some(), not_for("size_mm", "a block"))?;
            refuse_key(map, "specimen.layers", !s.layers.is_empty(), not_for("layers", "a block"))?;
        }
        Shape::Surface => {
            let file = require(map, "specimen.surface", s.surface.as_deref(), "for shape = \"surface\"")?;
            if file.trim().is_empty() {
                return Err(map.invalid("specimen.surface", "empty file name"));
            }
            file_shape_keys("surface")?;
        }
        Shape::Mesh => {
            let file = require(map, "specimen.mesh", s.mesh.as_deref(), "for shape = \"mesh\"")?;
            if file.trim().is_empty() {
                return Err(map.invalid("specimen.mesh", "empty file name"));
            }
            if e.dimension == 2 {
                return Err(
                    map.invalid("dimension", "shape = \"mesh\" is a tetrahedral (3D) mesh: it needs dimension = 3")
                );
            }
            if TetMeshFormat::of_path(Path::new(file)).is_err() {
                return Err(map.invalid(
                    "specimen.mesh",
                    format!("\"{file}\": expected a Gmsh .msh (4.1 ASCII), a TetGen .node/.ele or a .vtu mesh"),
                ));
            }
            file_shape_keys("mesh")?;
        }
    }
    if s.shape != Shape::Surface {
        refuse_key(map, "specimen.surface", s.surface.is_some(), not_for("surface", "shape = \"surface\""))?;
    }
    if s.shape != Shape::Mesh {
        refuse_key(map, "specimen.mesh", s.mesh.is_some(), not_for("mesh", "shape = \"mesh\""))?;
    }
    if !matches!(s.shape, Shape::Surface | Shape::Mesh) {
        let owners = "shape = \"surface\" or \"mesh\"";
        refuse_key(map, "specimen.regions", !s.regions.is_empty(), not_for("regions", owners))?;
    }
    // Material or layers.
    if s.shape == Shape::Block {
        match (s.material.is_some(), s.layers.is_empty()) {
            (true, false) => {
                return Err(
                    map.invalid("specimen.material", "give either `material` or `[[specimen.layers]]`, not both")
                )
            }
            (false, true) => {
                return Err(map.invalid(
                    "specimen.material",
                    "missing required key: a block needs `material` or `[[specimen.layers]]`",
                ))
            }
            _ => {}
        }
    } else if s.shape == Shape::Cylinder {
        require(map, "specimen.material", s.material.as_ref(), "for shape = \"cylinder\"")?;
    }
    if !s.layers.is_empty() {
        for (i, layer) in s.layers.iter().enumerate() {
            positive(map, &format!("specimen.layers[{i}].thickness_mm"), Some(layer.thickness_mm), "a length")?;
        }
        let sum: f64 = s.layers.iter().map(|l| l.thickness_mm).sum();
        let h = s.block_size().map_or(f64::NAN, |b| b[1]);
        let sums_to_h = (sum - h).abs() <= LAYER_SUM_TOLERANCE_MM; // false for NaN
        if !sums_to_h {
            return Err(map.invalid(
                "specimen.layers",
                format!(
                    "the layer thicknesses sum to {sum} mm but H = size_mm[1] = {h} mm; they must agree within {LAYER_SUM_TOLERANCE_MM} mm"
                ),
            ));
        }
    }
    // Every material named is defined.
    let mut refs: Vec<(String, &str)> = Vec::new();
    if let Some(m) = &s.material {
        refs.push(("specimen.material".into(), m));
    }
    for (i, l) in s.layers.iter().enumerate() {
        refs.push((format!("specimen.layers[{i}].material"), &l.material));
    }
    for (region, m) in &s.regions {
        refs.push((format!("specimen.regions.{region}"), m));
    }
    for (field, name) in refs {
        if !e.materials.contains_key(name) {
            return Err(map.invalid(
                &field,
                format!("material \"{name}\" is not defined (no [materials.{name}] here or in a materials file)"),
            ));
        }
    }
    Ok(())
}

fn validate_protocol(e: &Experiment, map: &SourceMap) -> Result<(), BundleError> {
    let p = &e.protocol;
    let tool = format!("tool = \"{}\"", p.tool.as_str());
    match p.tool {
        Tool::Plate => {
            refuse_key(map, "protocol.tool_radius_mm", p.tool_radius_mm.is_some(), format!("not used by {tool}"))?;
            refuse_key(map, "protocol.tool_surface", p.tool_surface.is_some(), format!("not used by {tool}"))?;
        }
        Tool::Sphere | Tool::Punch => {
            let r = require(map, "protocol.tool_radius_mm", p.tool_radius_mm, &format!("for {tool}"))?;
            positive(map, "protocol.tool_radius_mm", Some(r), "a length")?;
            refuse_key(map, "protocol.tool_surface", p.tool_surface.is_some(), format!("not used by {tool}"))?;
        }
        Tool::Surface => {
            let f = require(map, "protocol.tool_surface", p.tool_surface.as_deref(), &format!("for {tool}"))?;
            if f.trim().is_empty() {
                return Err(map.invalid("protocol.tool_surface", "empty file name"));
            }
            refuse_key(map, "protocol.tool_radius_mm", p.tool_radius_mm.is_some(), format!("not used by {tool}"))?;
        }
    }
    match (&p.tool_surface_units, p.tool) {
        (Some(unit), Tool::Surface) => {
            length_unit(map, "protocol.tool_surface_units", unit)?;
        }
        (Some(_), _) => {
            return Err(map.invalid("protocol.tool_surface_units", format!("not used by {tool}")));
        }
        (None, _) => {}
    }
    let uses_friction = p.tool_contact == Contact::Friction || p.support == Contact::Friction;
    if uses_friction {
        let mu = require(map, "protocol.friction", p.friction, "when tool_contact or support is \"friction\"")?;
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(map.invalid("protocol.friction", format!("{mu} is not a friction coefficient >= 0")));
        }
    } else {
        refuse_key(
            map,
            "protocol.friction",
            p.friction.is_some(),
            "given, but neither tool_contact nor support is \"friction\"".into(),
        )?;
    }
    if p.waypoints.is_empty() {
        return Err(map.invalid("protocol.waypoints", "no waypoints; give [[t_s, d_mm], ...]"));
    }
    for (i, w) in p.waypoints.iter().enumerate() {
        let field = format!("protocol.waypoints[{i}]");
        if !(w[0].is_finite() && w[1].is_finite()) {
            return Err(map.invalid(&field, format!("[{}, {}] is not finite", w[0], w[1])));
        }
        if w[0] < 0.0 {
            return Err(map.invalid(&field, format!("negative time {} s", w[0])));
        }
        if i > 0 && w[0] <= p.waypoints[i - 1][0] {
            return Err(map.invalid(
                &field,
                format!(
                    "waypoints must be in increasing time: t = {} s is not after the previous t = {} s",
                    w[0],
                    p.waypoints[i - 1][0]
                ),
            ));
        }
    }
    let last_push = p.last_push_s();
    for (key, value) in [("protocol.release_s", p.release_s), ("protocol.end_s", p.end_s)] {
        positive(map, key, Some(value), "a time")?;
        if value < last_push {
            return Err(map.invalid(key, format!("{value} s is before the last waypoint that pushes ({last_push} s)")));
        }
    }
    if p.end_s < p.release_s {
        return Err(map.invalid(
            "protocol.end_s",
            format!("{} s is before release_s ({} s): the run must go on until the release", p.end_s, p.release_s),
        ));
    }
    validate_tools(e, map)
}

/// A length unit's name, as `wagashi_io::surface` reads it.
pub(crate) fn length_unit(map: &SourceMap, field: &str, unit: &str) -> Result<LengthUnit, BundleError> {
    unit.parse::<LengthUnit>().map_err(|e| map.invalid(field, e.to_string()))
}

/// The name the v1 tool goes by among the trial's tools.
pub(crate) fn main_tool_name(e: &Experiment) -> &'static str {
    e.protocol.tool.as_str()
}

/// The name of the floor tool of `support = "friction"`.
pub(crate) const FLOOR_TOOL: &str = "floor";

/// `[[protocol.tools]]` (a project extension): names, shape keys, contact,
/// release and keyframes; in 2D, keyframes in the plane z = 0 turning about z only.
fn validate_tools(e: &Experiment, map: &SourceMap) -> Result<(), BundleError> {
    let main = main_tool_name(e);
    for (i, t) in e.protocol.tools.iter().enumerate() {
        let at = |key: &str| format!("protocol.tools[{i}].{key}");
        let shape = format!("shape = \"{}\"", t.shape.as_str());
        let not_used = |key: &str, given: bool| refuse_key(map, &at(key), given, format!("not used by {shape}"));
        // Name: written unquoted in tools.csv, as a glTF node name, and as a file
        // name in an output (`tools/NAME.obj`).
        let name = t.name.as_str();
        if name.trim().is_empty()
            || name.trim() != name
            || name.contains([',', '"', '/', '\\'])
            || name.chars().any(char::is_control)
        {
            return Err(map.invalid(
                &at("name"),
                format!(
                    "{name:?}: a tool's name must be non-empty text without commas, quotes, slashes, control characters or surrounding spaces"
                ),
            ));
        }
        if name == main || name == FLOOR_TOOL {
            return Err(map.invalid(
                &at("name"),
                format!(
                    "\"{name}\" is taken: \"{main}\" names the tool of `tool = \"{main}\"` and \"{FLOOR_TOOL}\" the floor of `support = \"friction\"`"
                ),
            ));
        }
        if let Some(j) = e.protocol.tools[..i].iter().position(|o| o.name == t.name) {
            return Err(map.invalid(&at("name"), format!("\"{name}\" is already the name of protocol.tools[{j}]")));
        }
        // Shape keys.
        let length = |key: &str, v: Option<f64>| positive(map, &at(key), v, "a length");
        match t.shape {
            ToolKind::Plate => {
                let h = require(map, &at("half_extents_mm"), t.half_extents_mm.as_ref(), &format!("for {shape}"))?;
                if h.len() != 3 || !h.iter().all(|v| v.is_finite() && *v > 0.0) {
                    return Err(
                        map.invalid(&at("half_extents_mm"), "must be three positive half lengths [x, y, z] in mm")
                    );
                }
                not_used("radius_mm", t.radius_mm.is_some())?;
                not_used("half_height_mm", t.half_height_mm.is_some())?;
            }
            ToolKind::Sphere | ToolKind::Punch | ToolKind::Capsule => {
                length("radius_mm", Some(require(map, &at("radius_mm"), t.radius_mm, &format!("for {shape}"))?))?;
                match t.shape {
                    ToolKind::Sphere => not_used("half_height_mm", t.half_height_mm.is_some())?,
                    ToolKind::Capsule => length(
                        "half_height_mm",
                        Some(require(map, &at("half_height_mm"), t.half_height_mm, &format!("for {shape}"))?),
                    )?,
                    _ => length("half_height_mm", t.half_height_mm)?,
                }
                not_used("half_extents_mm", t.half_extents_mm.is_some())?;
            }
            ToolKind::Surface => {
                let f = require(map, &at("surface"), t.surface.as_deref(), &format!("for {shape}"))?;
                if f.trim().is_empty() {
                    return Err(map.invalid(&at("surface"), "empty file name"));
                }
                not_used("radius_mm", t.radius_mm.is_some())?;
                not_used("half_height_mm", t.half_height_mm.is_some())?;
                not_used("half_extents_mm", t.half_extents_mm.is_some())?;
            }
        }
        if t.shape != ToolKind::Surface {
            not_used("surface", t.surface.is_some())?;
            not_used("units", t.units.is_some())?;
        } else if let Some(unit) = &t.units {
            length_unit(map, &at("units"), unit)?;
        }
        // Contact.
        if t.contact == Contact::Friction {
            let mu = require(map, &at("friction"), t.friction, "when contact = \"friction\"")?;
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(map.invalid(&at("friction"), format!("{mu} is not a friction coefficient >= 0")));
            }
        } else {
            refuse_key(map, &at("friction"), t.friction.is_some(), "given, but contact is not \"friction\"".into())?;
        }
        positive(map, &at("release_s"), t.release_s, "a time")?;
        // Keyframes.
        if t.keyframes.is_empty() {
            return Err(map.invalid(
                &at("keyframes"),
                "no keyframes; give [[t_s, x_mm, y_mm, z_mm], ...] (or 7 columns with rx_deg, ry_deg, rz_deg)",
            ));
        }
        let columns = t.keyframes[0].len();
        for (k, row) in t.keyframes.iter().enumerate() {
            let field = format!("protocol.tools[{i}].keyframes[{k}]");
            if row.len() != 4 && row.len() != 7 {
                return Err(map.invalid(
                    &field,
                    format!(
                        "{} values; a keyframe is [t_s, x_mm, y_mm, z_mm] or [t_s, x_mm, y_mm, z_mm, rx_deg, ry_deg, rz_deg]",
                        row.len()
                    ),
                ));
            }
            if row.len() != columns {
                return Err(map.invalid(
                    &field,
                    format!(
                        "{} values, but keyframes[0] has {columns}: give every keyframe the same columns",
                        row.len()
                    ),
                ));
            }
            if let Some(x) = row.iter().find(|x| !x.is_finite()) {
                return Err(map.invalid(&field, format!("{x} is not finite")));
            }
            if row[0] < 0.0 {
                return Err(map.invalid(&field, format!("negative time {} s", row[0])));
            }
            if k > 0 && row[0] <= t.keyframes[k - 1][0] {
                return Err(map.invalid(
                    &field,
                    format!(
                        "keyframes must be in increasing time: t = {} s is not after the previous t = {} s",
                        row[0],
                        t.keyframes[k - 1][0]
                    ),
                ));
            }
            if e.dimension == 2 {
                let (z, rx, ry) = (row[3], row.get(4).copied().unwrap_or(0.0), row.get(5).copied().unwrap_or(0.0));
                if z != 0.0 || rx != 0.0 || ry != 0.0 {
                    return Err(map.invalid(
                        &field,
                        format!(
                            "dimension = 2 presses in the plane z = 0: a keyframe needs z_mm = 0 and may turn about z only \
                             (rx_deg = ry_deg = 0); got z_mm = {z}, rx_deg = {rx}, ry_deg = {ry}"
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The specimen's smallest size [mm] (block: min(W, H, T); cylinder: min(2R, H)),
/// or `None` for a surface or mesh, whose geometry is not loaded to validate a bundle.
pub(crate) fn smallest_size(e: &Experiment) -> Option<f64> {
    let s = &e.specimen;
    match s.shape {
        Shape::Block => s.block_size().map(|b| b[0].min(b[1]).min(b[2])),
        Shape::Cylinder => Some((2.0 * s.radius_mm?).min(s.height_mm?)),
        Shape::Surface | Shape::Mesh => None,
    }
}

/// Distance [mm] from `p` to the specimen's surface (3D) or to its rectangle
/// `[0, W] x [0, H]` (2D, zero inside); `None` for a surface or mesh specimen.
pub(crate) fn distance_to_surface(e: &Experiment, p: &[f64]) -> Option<f64> {
    let s = &e.specimen;
    let outside = |v: f64, lo: f64, hi: f64| (lo - v).max(v - hi).max(0.0);
    match (s.shape, e.dimension) {
        (Shape::Block, 2) => {
            let [w, h, _] = s.block_size()?;
            Some(outside(p[0], 0.0, w).hypot(outside(p[1], 0.0, h)))
        }
        (Shape::Block, _) => {
            let b = s.block_size()?;
            let out = (0..3).map(|k| outside(p[k], 0.0, b[k]).powi(2)).sum::<f64>().sqrt();
            if out > 0.0 {
                return Some(out);
            }
            Some((0..3).map(|k| p[k].min(b[k] - p[k])).fold(f64::INFINITY, f64::min))
        }
        (Shape::Cylinder, _) => {
            let (r, h) = (s.radius_mm?, s.height_mm?);
            let radial = p[0].hypot(p[2]);
            let (dr, dy) = (radial - r, (-p[1]).max(p[1] - h));
            if dr <= 0.0 && dy <= 0.0 {
                Some((-dr).min(-dy))
            } else {
                Some(dr.max(0.0).hypot(dy.max(0.0)))
            }
        }
        (Shape::Surface | Shape::Mesh, _) => None,
    }
}

/// Refuses markers whose initial position is farther from the surface than
/// [`MARKER_SURFACE_TOLERANCE`] of the smallest size.
pub(crate) fn validate_marker_positions(
    e: &Experiment,
    file: &std::path::Path,
    markers: &[(MarkerSeries, usize)],
) -> Result<(), BundleError> {
    let Some(size) = smallest_size(e) else {
        return Ok(());
    };
    let tolerance = MARKER_SURFACE_TOLERANCE * size;
    for (m, line) in markers {
        let Some(p) = m.initial_position() else {
            continue;
        };
        let Some(d) = distance_to_surface(e, p) else {
            continue;
        };
        let on_surface = d <= tolerance; // false for NaN
        if !on_surface {
            let place =
                if e.dimension == 2 { "the specimen's rectangle [0, W] x [0, H]" } else { "the specimen's surface" };
            return Err(BundleError::Invalid {
                file: file.to_path_buf(),
                line: *line,
                field: format!("marker {}", m.name),
                cause: format!(
                    "initial position {p:?} mm is {d:.4} mm from {place}; at most {tolerance} mm (1 % of its smallest size, {size} mm) is allowed"
                ),
            });
        }
    }
    Ok(())
}

/// Merges `external` materials over the experiment's own (a table of the same
/// name in `external` replaces the bundle's).
pub(crate) fn merge_materials(e: &mut Experiment, external: &BTreeMap<String, MaterialSpec>) {
    for (name, spec) in external {
        e.materials.insert(name.clone(), spec.clone());
    }
}

/// The engine's effects of `[effects]`: each key an effect parameter of
/// `fem_core::effects` or the covariate `age_h`; refuses an unknown key, an effect
/// the engine does not implement yet, a value out of bounds, and `ageing` without
/// `age_h`, naming the key.
pub(crate) fn effects_of(e: &Experiment, map: &SourceMap) -> Result<Effects, BundleError> {
    let mut effects = Effects::none();
    for (key, &value) in &e.effects {
        let field = format!("effects.{key}");
        let refused = |err: EffectError| map.invalid(&field, err.to_string());
        if key == AGE_KEY {
            effects.set_age_h(Some(value)).map_err(refused)?;
            continue;
        }
        if EffectId::from_key(key).is_none() {
            let known: Vec<&str> =
                EffectId::ALL.iter().flat_map(|e| e.params().iter().map(|p| p.key)).chain([AGE_KEY]).collect();
            return Err(map.invalid(&field, format!("unknown key; the effect keys are {}", known.join(", "))));
        }
        effects.set_key(key, value).map_err(refused)?;
    }
    effects.validate().map_err(|err| map.invalid(&format!("effects.{}", err.key()), err.to_string()))?;
    Ok(effects)
}
