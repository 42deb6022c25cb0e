//! `experiment.toml` as typed structs: the keys of experiment-format.md v1 and the
//! project's extensions, each struct refusing unknown keys except `[extra]`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::material_spec::MaterialSpec;

/// The only format this crate reads and writes.
pub const FORMAT_V1: &str = "wagashi-experiment/1";

/// The content of `experiment.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// Must be [`FORMAT_V1`].
    pub format: String,
    /// Free text, unique within a campaign.
    pub name: String,
    /// 3: solid tetrahedra; 2: plane stress in x-y with thickness `size_mm[2]`.
    pub dimension: u32,
    /// The specimen's shape, size and materials.
    pub specimen: Specimen,
    /// Material definitions by name; may be empty when they come from a
    /// `--materials` file (see [`super::read_bundle_with`]). Default: none.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub materials: BTreeMap<String, MaterialSpec>,
    /// The loading.
    pub protocol: ProtocolSpec,
    /// What was measured (or simulated); default: nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data: Option<DataSpec>,
    /// Project extension: `[effects]`, candidate effects of the gap diagnosis
    /// (`fem_core::effects`) by their keys (`force_offset_N = 0.01`, ...) and the
    /// trial covariate `age_h`; see the [`super`] module docs. Default: none.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub effects: BTreeMap<String, f64>,
    /// Any table: kept and written back, never interpreted. Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extra: Option<toml::Table>,
}

/// The specimen's shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Shape {
    /// A box `[0, W] x [0, H] x [0, T]` (x, y, z); `size_mm = [W, H, T]`.
    Block,
    /// A cylinder of `radius_mm` around the y axis (x = z = 0), `height_mm` tall; 3D only.
    Cylinder,
    /// A closed surface (OBJ, glTF or GLB) named by `surface`, meshed on the fly.
    Surface,
    /// A tetrahedral mesh (Gmsh `.msh` 4.1, TetGen `.node`/`.ele`, `.vtu`) named by `mesh`,
    /// pressed as it is; 3D only.
    Mesh,
}

impl Shape {
    /// The name as the format spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            Shape::Block => "block",
            Shape::Cylinder => "cylinder",
            Shape::Surface => "surface",
            Shape::Mesh => "mesh",
        }
    }
}

/// `[specimen]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Specimen {
    /// Block, cylinder, surface or mesh.
    pub shape: Shape,
    /// Block only: `[W, H, T]` [mm], each > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size_mm: Option<Vec<f64>>,
    /// Cylinder only: radius [mm], > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_mm: Option<f64>,
    /// Cylinder only: height along y [mm], > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_mm: Option<f64>,
    /// The specimen's mass [g], > 0; optional.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_g: Option<f64>,
    /// Project extension: density [g/cm^3], > 0; optional. When absent the engine
    /// takes `mass_g` / volume, or else 1 g/cm^3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density_g_cm3: Option<f64>,
    /// Project extension, 2D only: `"stress"` (plane stress with thickness T, the
    /// seed's choice; the default) or `"strain"` (plane strain, forces per T).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<Plane>,
    /// The one material of an unlayered block or cylinder (or of a whole surface or mesh).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Block only: layers stacked along y, bottom first; thicknesses sum to H.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<Layer>,
    /// Surface only: the closed surface file, relative to the bundle folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<String>,
    /// Mesh only: the tetrahedral mesh file, relative to the bundle folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    /// Surface or mesh only: region (OBJ object/group, glTF mesh; Gmsh volume
    /// physical group, TetGen region) -> material name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub regions: BTreeMap<String, String>,
}

/// The 2D kinematic assumption (`[specimen] plane`, a project extension).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Plane {
    /// Plane stress with the specimen's thickness T (the seed's choice).
    Stress,
    /// Plane strain; forces are per thickness T.
    Strain,
}

impl Specimen {
    /// The block's `[W, H, T]` [mm], when it has exactly three entries.
    pub fn block_size(&self) -> Option<[f64; 3]> {
        match self.size_mm.as_deref() {
            Some(&[w, h, t]) => Some([w, h, t]),
            _ => None,
        }
    }

    /// The material names this specimen refers to, each once, in order of appearance
    /// (`material`, then layers bottom first, then surface regions).
    pub fn material_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        let all = self
            .material
            .iter()
            .map(String::as_str)
            .chain(self.layers.iter().map(|l| l.material.as_str()))
            .chain(self.regions.values().map(String::as_str));
        for n in all {
            if !names.contains(&n) {
                names.push(n);
            }
        }
        names
    }
}

/// `[[specimen.layers]]`: one layer of a block.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layer {
    /// The layer's material name.
    pub material: String,
    /// Its thickness along y [mm], > 0.
    pub thickness_mm: f64,
}

/// The rigid tool that presses the specimen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tool {
    /// A rigid plate larger than the top face.
    Plate,
    /// A sphere of `tool_radius_mm`.
    Sphere,
    /// A flat cylindrical punch of `tool_radius_mm`.
    Punch,
    /// A closed rigid shape from `tool_surface`.
    Surface,
}

impl Tool {
    /// The name as the format spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            Tool::Plate => "plate",
            Tool::Sphere => "sphere",
            Tool::Punch => "punch",
            Tool::Surface => "surface",
        }
    }
}

/// How a face is held by the tool or the floor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Contact {
    /// No slip; a glued tool holds on until `release_s`.
    Glued,
    /// Slides freely.
    Frictionless,
    /// Coulomb friction with coefficient `friction`.
    Friction,
}

impl Contact {
    /// The name as the format spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            Contact::Glued => "glued",
            Contact::Frictionless => "frictionless",
            Contact::Friction => "friction",
        }
    }
}

/// `[protocol]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProtocolSpec {
    /// The tool.
    pub tool: Tool,
    /// Sphere and punch only: the tool's radius [mm], > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_radius_mm: Option<f64>,
    /// Surface tool only: the tool's closed surface file, relative to the bundle folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_surface: Option<String>,
    /// How the tool holds the specimen's top.
    pub tool_contact: Contact,
    /// How the floor holds the specimen's bottom face.
    pub support: Contact,
    /// Coulomb coefficient, >= 0; required when `tool_contact` or `support` is
    /// `"friction"`, refused otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// `[t_s, d_mm]`: the tool's downward displacement from first touch, piecewise
    /// linear; times >= 0 and strictly increasing.
    pub waypoints: Vec<[f64; 2]>,
    /// The tool leaves the specimen at this time [s], > 0, not before the last
    /// waypoint that pushes.
    pub release_s: f64,
    /// The trial ends here [s], > 0, not before the last waypoint that pushes.
    pub end_s: f64,
    /// Project extension: gravity along -y. Default false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub gravity: bool,
    /// Project extension, surface tool only: the length unit of `tool_surface`'s
    /// coordinates, `"mm"`, `"cm"`, `"m"` or `"in"`. Default: the file format's
    /// (mm for OBJ and STL, m for glTF/GLB, as `wagashi_io::surface` reads them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_surface_units: Option<String>,
    /// Project extension: more rigid tools, `[[protocol.tools]]`, each with its own
    /// shape, contact and trajectory; pressed together with the tool above (see
    /// the [`super`] module docs). Default: none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tools: Vec<ToolSpec>,
}

/// The shape of a tool of `[[protocol.tools]]` (a project extension).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ToolKind {
    /// A box of `half_extents_mm` centred on the tool's origin.
    Plate,
    /// A ball of `radius_mm` centred on the tool's origin.
    Sphere,
    /// A flat cylinder of `radius_mm` with axis y, centred on the tool's origin,
    /// flat faces at `y = ±half_height_mm` (default half height: the radius).
    Punch,
    /// A cylinder of `radius_mm` and `half_height_mm` with hemispherical caps, axis y.
    Capsule,
    /// A closed triangle surface read from `surface` (OBJ, STL, glTF/GLB), its
    /// coordinates in the tool's frame.
    Surface,
}

impl ToolKind {
    /// The name as the bundle spells it.
    pub fn as_str(self) -> &'static str {
        match self {
            ToolKind::Plate => "plate",
            ToolKind::Sphere => "sphere",
            ToolKind::Punch => "punch",
            ToolKind::Capsule => "capsule",
            ToolKind::Surface => "surface",
        }
    }
}

/// `[[protocol.tools]]`: one more rigid tool with its own trajectory (a project
/// extension; see the [`super`] module docs for the syntax and the rules).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolSpec {
    /// The tool's name, unique among the trial's tools (reports, `tools.csv`, glTF).
    pub name: String,
    /// The tool's shape.
    pub shape: ToolKind,
    /// Sphere, punch and capsule: radius [mm], > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_mm: Option<f64>,
    /// Punch (optional, default `radius_mm`) and capsule (required): half the
    /// height of the cylindrical part [mm], > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_height_mm: Option<f64>,
    /// Plate: half its size along x, y and z [mm], three values > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub half_extents_mm: Option<Vec<f64>>,
    /// Surface: the closed surface file, relative to the bundle folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<String>,
    /// Surface: the unit of the file's coordinates (`"mm"`, `"cm"`, `"m"`, `"in"`);
    /// default: the format's (mm for OBJ and STL, m for glTF/GLB).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<String>,
    /// How the tool holds what it touches.
    pub contact: Contact,
    /// Coulomb coefficient, >= 0; required when `contact = "friction"`, refused otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// The tool lets go at this time [s], > 0; default: the protocol's `release_s`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub release_s: Option<f64>,
    /// The tool's pose over time: rows `[t_s, x_mm, y_mm, z_mm]`, or
    /// `[t_s, x_mm, y_mm, z_mm, rx_deg, ry_deg, rz_deg]` with a rotation vector
    /// (axis times angle, degrees); the position of the tool's origin in the
    /// specimen's frame, interpolated linearly (rotations by slerp), held before
    /// the first row and after the last. Times >= 0, strictly increasing.
    pub keyframes: Vec<Vec<f64>>,
}

fn is_false(b: &bool) -> bool {
    !*b
}

impl ProtocolSpec {
    /// The time of the last waypoint that ends a segment of changing displacement
    /// [s] (0 when the tool never moves).
    pub fn last_push_s(&self) -> f64 {
        self.waypoints.windows(2).filter(|p| p[1][1] != p[0][1]).map(|p| p[1][0]).fold(0.0, f64::max)
    }
}

/// `[data]`: the measured (or simulated) files, relative to the bundle folder.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataSpec {
    /// `t_s,force_N`: the force on the bottom sensor, compression positive.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<String>,
    /// `marker,t_s,x_mm,y_mm[,z_mm]`: marker positions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub markers: Option<String>,
    /// The force sensor was zeroed with the specimen on it; default: not stated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_tared: Option<bool>,
}
