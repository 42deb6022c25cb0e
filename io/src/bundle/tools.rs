//! From a bundle's protocol to fem-core's rigid contact tools
//! ([`Bundle::contact_tools`]); the rules are in the [`super`] module docs
//! ("Rigid tools").

use fem_core::press::{Keyframe, Tool as RigidTool, ToolContact, ToolShape};

use super::experiment::{Contact, Shape, Tool, ToolKind, ToolSpec};
use super::read::Bundle;
use super::validate::{length_unit, main_tool_name, FLOOR_TOOL};
use crate::error::BundleError;
use crate::surface::{read_surface, SurfaceOptions};

impl Bundle {
    /// Whether the trial runs with contact tools. It does unless it is the seed's
    /// press: `tool = "plate"` with `tool_contact` and `support` each `"glued"` or
    /// `"frictionless"`, and no `[[protocol.tools]]`; that press holds the top and
    /// bottom faces by constraints (the engine's plate: results and sensitivities
    /// as they always were). One exception keeps the format's meaning: a
    /// frictionless plate whose waypoints push again after rising, before
    /// `release_s` (a double compression), must be free to leave the specimen
    /// and touch it again, so it runs as a contact tool. A `shape = "surface"` or
    /// `"mesh"` specimen always runs with contact tools (its top need not be a flat face).
    pub fn has_contact_tools(&self) -> bool {
        let p = &self.experiment.protocol;
        let held = |c: Contact| matches!(c, Contact::Glued | Contact::Frictionless);
        let plate_held = match p.tool_contact {
            Contact::Glued => true,
            Contact::Frictionless => !self.pushes_again(),
            Contact::Friction => false,
        };
        matches!(self.experiment.specimen.shape, Shape::Surface | Shape::Mesh)
            || !(p.tool == Tool::Plate && plate_held && held(p.support) && p.tools.is_empty())
    }

    /// Whether the waypoints push again (d(t) grows) after a rise (d(t) falls), on
    /// segments that start before `release_s`.
    fn pushes_again(&self) -> bool {
        let p = &self.experiment.protocol;
        let mut rose = false;
        for w in p.waypoints.windows(2).take_while(|w| w[0][0] < p.release_s) {
            if w[1][1] < w[0][1] {
                rose = true;
            } else if w[1][1] > w[0][1] && rose {
                return true;
            }
        }
        false
    }

    /// The trial's rigid tools in the specimen's frame [mm]: the tool of `tool`
    /// (named after it: `"plate"`, `"sphere"`, `"punch"`, `"surface"`), the floor
    /// (`"floor"`) when `support = "friction"`, then the tools of
    /// `[[protocol.tools]]` in their order. Empty when the trial runs without
    /// contact tools ([`Bundle::has_contact_tools`]). `axisymmetric`: for the
    /// axisymmetric model of a cylinder, whose tools must stand on the axis.
    ///
    /// Reads the surface files of surface tools (relative to the bundle folder)
    /// and refuses one that cannot be read or is not a closed surface, naming the
    /// key in `experiment.toml`.
    pub fn contact_tools(&self, axisymmetric: bool) -> Result<Vec<RigidTool>, BundleError> {
        if !self.has_contact_tools() {
            return Ok(Vec::new());
        }
        let e = &self.experiment;
        let p = &e.protocol;
        let (lo, hi) = self.tool_bounds()?;
        // The top face's centre: on the axis for a cylinder, the middle of a block's top.
        let top = [0.5 * (lo[0] + hi[0]), hi[1], 0.5 * (lo[2] + hi[2])];
        let friction = || -> Result<f64, BundleError> {
            p.friction.ok_or_else(|| self.map.invalid("protocol.friction", "missing required key for \"friction\""))
        };
        let contact = |c: Contact| -> Result<ToolContact, BundleError> {
            Ok(match c {
                Contact::Glued => ToolContact::Glued,
                Contact::Frictionless => ToolContact::Frictionless,
                Contact::Friction => ToolContact::Friction(friction()?),
            })
        };
        let name = main_tool_name(e);
        let on_top = |shape: ToolShape, lift: f64| -> Result<RigidTool, BundleError> {
            Ok(RigidTool::moving_down(
                name,
                shape,
                [top[0], top[1] + lift, top[2]],
                &p.waypoints,
                contact(p.tool_contact)?,
                p.release_s,
            ))
        };
        let radius =
            || p.tool_radius_mm.ok_or_else(|| self.map.invalid("protocol.tool_radius_mm", "missing required key"));
        let main = match p.tool {
            Tool::Plate => RigidTool::plate_above(name, lo, hi, &p.waypoints, contact(p.tool_contact)?, p.release_s),
            Tool::Sphere => {
                let r = radius()?;
                on_top(ToolShape::Sphere { radius: r }, r)?
            }
            Tool::Punch => {
                let r = radius()?;
                on_top(ToolShape::Punch { radius: r, half_height: r }, r)?
            }
            Tool::Surface => {
                let file = p
                    .tool_surface
                    .as_deref()
                    .ok_or_else(|| self.map.invalid("protocol.tool_surface", "missing required key"))?;
                let shape = self.tool_surface("protocol.tool_surface", file, p.tool_surface_units.as_deref())?;
                RigidTool::moving_down(name, shape, [0.0; 3], &p.waypoints, contact(p.tool_contact)?, p.release_s)
            }
        };
        let mut tools = vec![main];
        if p.support == Contact::Friction {
            tools.push(RigidTool::floor_below(FLOOR_TOOL, lo, hi, ToolContact::Friction(friction()?)));
        }
        for (i, spec) in p.tools.iter().enumerate() {
            tools.push(self.extra_tool(i, spec, axisymmetric)?);
        }
        Ok(tools)
    }

    /// The TOML key of the tool named `tool` (for errors about it): `protocol.tool`,
    /// `protocol.support` for the floor, `protocol.tools[i]`, else `protocol`.
    pub fn tool_field(&self, tool: &str) -> String {
        let e = &self.experiment;
        if tool == main_tool_name(e) {
            return "protocol.tool".into();
        }
        if tool == FLOOR_TOOL && e.protocol.support == Contact::Friction {
            return "protocol.support".into();
        }
        match e.protocol.tools.iter().position(|t| t.name == tool) {
            Some(i) => format!("protocol.tools[{i}]"),
            None => "protocol".into(),
        }
    }

    /// The specimen's nominal bounding box [mm] as the tools see it: a block
    /// `[0, W] x [0, H] x [0, T]` (2D: `z = 0`), a cylinder `[-R, R] x [0, H] x [-R, R]`
    /// (its axisymmetric section is the slice `z = 0`), a surface's or mesh's
    /// bounding box.
    fn tool_bounds(&self) -> Result<([f64; 3], [f64; 3]), BundleError> {
        let s = &self.experiment.specimen;
        let missing = |field: &str| self.map.invalid(field, "missing required key");
        match s.shape {
            Shape::Block => {
                let [w, h, t] = s.block_size().ok_or_else(|| missing("specimen.size_mm"))?;
                let t = if self.dimension() == 2 { 0.0 } else { t };
                Ok(([0.0; 3], [w, h, t]))
            }
            Shape::Cylinder => {
                let r = s.radius_mm.ok_or_else(|| missing("specimen.radius_mm"))?;
                let h = s.height_mm.ok_or_else(|| missing("specimen.height_mm"))?;
                Ok(([-r, 0.0, -r], [r, h, r]))
            }
            Shape::Surface => Ok(self.specimen_surface()?.bounding_box()),
            Shape::Mesh => Ok(self.specimen_mesh()?.bounding_box()),
        }
    }

    /// Tool `i` of `[[protocol.tools]]`.
    fn extra_tool(&self, i: usize, spec: &ToolSpec, axisymmetric: bool) -> Result<RigidTool, BundleError> {
        let at = |key: &str| format!("protocol.tools[{i}].{key}");
        let missing = |key: &str| self.map.invalid(&at(key), "missing required key");
        let radius = || spec.radius_mm.ok_or_else(|| missing("radius_mm"));
        let shape = match spec.shape {
            ToolKind::Plate => match spec.half_extents_mm.as_deref() {
                Some(&[x, y, z]) => ToolShape::Plate { half_extents: [x, y, z] },
                _ => return Err(missing("half_extents_mm")),
            },
            ToolKind::Sphere => ToolShape::Sphere { radius: radius()? },
            ToolKind::Punch => {
                let r = radius()?;
                ToolShape::Punch { radius: r, half_height: spec.half_height_mm.unwrap_or(r) }
            }
            ToolKind::Capsule => ToolShape::Capsule {
                radius: radius()?,
                half_height: spec.half_height_mm.ok_or_else(|| missing("half_height_mm"))?,
            },
            ToolKind::Surface => {
                let file = spec.surface.as_deref().ok_or_else(|| missing("surface"))?;
                self.tool_surface(&at("surface"), file, spec.units.as_deref())?
            }
        };
        let contact = match spec.contact {
            Contact::Glued => ToolContact::Glued,
            Contact::Frictionless => ToolContact::Frictionless,
            Contact::Friction => ToolContact::Friction(spec.friction.ok_or_else(|| missing("friction"))?),
        };
        let mut keyframes = Vec::with_capacity(spec.keyframes.len());
        for (k, row) in spec.keyframes.iter().enumerate() {
            let field = format!("protocol.tools[{i}].keyframes[{k}]");
            if !(row.len() == 4 || row.len() == 7) {
                return Err(self.map.invalid(&field, "a keyframe has 4 or 7 values"));
            }
            let rotation_deg = if row.len() == 7 { [row[4], row[5], row[6]] } else { [0.0; 3] };
            if axisymmetric && (row[1] != 0.0 || row[3] != 0.0 || rotation_deg[0] != 0.0 || rotation_deg[2] != 0.0) {
                return Err(self.map.invalid(
                    &field,
                    format!(
                        "the axisymmetric model needs every tool on the axis, turning about y only: \
                         x_mm = z_mm = 0 and rx_deg = rz_deg = 0; got x_mm = {}, z_mm = {}, rx_deg = {}, rz_deg = {}",
                        row[1], row[3], rotation_deg[0], rotation_deg[2]
                    ),
                ));
            }
            keyframes.push(Keyframe {
                t_s: row[0],
                translation_mm: [row[1], row[2], row[3]],
                rotation_rad: rotation_deg.map(f64::to_radians),
            });
        }
        Ok(RigidTool {
            name: spec.name.clone(),
            shape,
            contact,
            keyframes,
            release_s: spec.release_s.unwrap_or(self.experiment.protocol.release_s),
            floor: false,
        })
    }

    /// The closed surface in `file` (relative to the bundle folder) as a mesh tool,
    /// its coordinates in mm (from `units`, else the format's unit), all its
    /// regions as one. Refusals name `field`.
    fn tool_surface(&self, field: &str, file: &str, units: Option<&str>) -> Result<ToolShape, BundleError> {
        let units = units.map(|u| length_unit(&self.map, field, u)).transpose()?;
        let path = self.dir.join(file);
        let imported = read_surface(&path, &SurfaceOptions { units, ..SurfaceOptions::default() })
            .map_err(|e| self.map.invalid(field, e.to_string()))?;
        let mut surface = imported.surface;
        // A tool is one rigid body: its regions do not matter.
        surface.triangle_regions.iter_mut().for_each(|r| *r = 0);
        surface.region_names.truncate(1);
        surface.require_closed_manifold().map_err(|e| {
            self.map
                .invalid(field, format!("{}: a tool must be a closed, outward-oriented surface: {e}", path.display()))
        })?;
        Ok(ToolShape::Mesh { vertices: surface.vertices, triangles: surface.triangles })
    }
}
