//! From a bundle to the engine's press problem.
//!
//! - Mesh: 3D blocks with `fem_core::mesh::block` / `layered_block`, 2D blocks with
//!   `rectangle` / `layered_rectangle` in plane stress of thickness `T = size_mm[2]`,
//!   3D cylinders with `cylinder`. Region names are material names; the materials
//!   vector follows the mesh's region order.
//! - Density [t/mm^3]: `density_g_cm3` x 1e-9, else `mass_g` / volume (the exact
//!   volume of the shape, W H T or pi R^2 H) x 1e-6, else 1 g/cm^3.
//! - Protocol: the waypoints, `release_s`, `end_s` and `gravity` as they are. The
//!   seed's press (`tool = "plate"` with `glued` or `frictionless` contact and
//!   support, no `[[protocol.tools]]`) holds the top and bottom faces by
//!   constraints (`Protocol::plate`, `Protocol::support`). Every other trial runs
//!   with rigid contact tools ([`Bundle::contact_tools`], the module docs of
//!   [`super`]): `PressProblem::tools`, and `support = "friction"` as
//!   `Attachment::Free` with a floor tool. A `shape = "surface"` specimen is
//!   meshed on the fly (conforming mode unless told otherwise,
//!   [`Bundle::to_press_meshed`]) and always runs with contact tools: see
//!   `surface_specimen.rs`. A `shape = "mesh"` specimen is read from its file and
//!   pressed with its own cells (the element size does not apply), with contact
//!   tools: see `mesh_specimen.rs`.
//! - Markers: one request per marker at its initial position, reported at every
//!   time the marker was measured (`t_s = 0` included). No extra snapshots.
//!
//! ## The axisymmetric model of a cylinder (a solver option)
//!
//! [`Bundle::to_press_axisymmetric`] models a `shape = "cylinder"` bundle (whose
//! format meaning stays a 3D cylinder, `dimension = 3`) by its `r-y` section
//! `[0, R] x [0, H]` with axisymmetric triangles (`fem_core::mesh::layered_axisymmetric_section`,
//! [`Formulation::Axisymmetric`]): the same trial at a fraction of the cost.
//! Forces are full-circle forces, as in 3D. A marker given at `(x, y, z)` is
//! located in the section at `(r, y)` with `r = sqrt(x^2 + z^2)`; its simulated
//! `(r, y)` positions go back to 3D on the marker's own azimuth
//! ([`Bundle::simulated_markers`]): `(r cos θ, y, r sin θ)` with `cos θ = x/r0`,
//! `sin θ = z/r0` from its initial position (θ = 0 for a marker on the axis).
//! Other shapes are refused with the key `specimen.shape`.

use fem_core::effects::Effects;
use fem_core::element::Formulation;
use fem_core::material::{Material, MaterialError};
use fem_core::mesh::{self, Layer};
use fem_core::press::{
    AnyPress, Attachment, AxisymmetricPress, MarkerRequest, MarkerTrack, PlanePress, PressError, Protocol, SolidPress,
};

use super::experiment::{Contact, Shape, Tool};
use super::read::Bundle;
use super::series::{MarkerSample, MarkerSeries};
use super::surface_specimen::SurfaceMeshing;
use super::validate::validate_experiment;
use crate::error::BundleError;

/// 1 g/cm^3 in t/mm^3.
pub const G_CM3_IN_T_MM3: f64 = 1e-9;

impl Bundle {
    fn unsupported(&self, field: &str, what: String) -> BundleError {
        BundleError::Unsupported {
            file: self.experiment_file(),
            line: self.line_of(field),
            field: field.to_string(),
            what,
        }
    }

    fn engine_error(&self, source: PressError) -> BundleError {
        let (file, line, field) = match &source {
            PressError::Material { region, source: m } => {
                let key = match m {
                    MaterialError::NotPositive { name, .. } if name.starts_with('E') => {
                        format!("{name}_MPa")
                    }
                    MaterialError::NotPositive { name, .. } => format!("{name}_MPa_s"),
                    MaterialError::PoissonOutOfRange { .. } => "poisson".to_string(),
                    MaterialError::DamageOutOfRange { name, .. } => format!("mullins_{name}"),
                    MaterialError::Network(_) => "model".to_string(),
                };
                let field = format!("materials.{region}.{key}");
                match self.experiment.materials.get(region).and_then(|s| s.location(&key)) {
                    Some((file, line)) => (file.to_path_buf(), line, field),
                    None => (self.experiment_file(), self.line_of(&field), field),
                }
            }
            PressError::Mesh(_) | PressError::MaterialCount { .. } | PressError::BadFormulation(_) => {
                (self.experiment_file(), self.line_of("specimen"), "specimen".to_string())
            }
            PressError::MarkerOutside { .. } => {
                (self.experiment_file(), self.line_of("data.markers"), "data.markers".to_string())
            }
            PressError::BadTool { tool, .. } => {
                let field = self.tool_field(tool);
                (self.experiment_file(), self.line_of(&field), field)
            }
            PressError::Effect(e) => {
                let field = format!("effects.{}", e.key());
                (self.experiment_file(), self.line_of(&field), field)
            }
            _ => (self.experiment_file(), self.line_of("protocol"), "protocol".to_string()),
        };
        BundleError::Engine { file, line, field, source: Box::new(source) }
    }

    /// The specimen's volume [mm^3] from its nominal size (W H T; pi R^2 H; the
    /// volume a surface encloses, or a mesh's cells fill), when known.
    pub fn volume_mm3(&self) -> Option<f64> {
        let s = &self.experiment.specimen;
        match s.shape {
            Shape::Block => s.block_size().map(|[w, h, t]| w * h * t),
            Shape::Cylinder => Some(std::f64::consts::PI * s.radius_mm?.powi(2) * s.height_mm?),
            Shape::Surface => self.specimen_surface().ok().map(|s| s.signed_volume(None).abs()),
            Shape::Mesh => self.specimen_mesh().ok().map(|m| m.measure()),
        }
    }

    /// The engine's effects of `[effects]` (module docs of [`super`], "Effects").
    pub fn effects(&self) -> Result<Effects, BundleError> {
        super::validate::effects_of(&self.experiment, &self.map)
    }

    /// The density [t/mm^3]: `density_g_cm3`, else `mass_g` / volume, else 1 g/cm^3.
    pub fn density_t_mm3(&self) -> f64 {
        let s = &self.experiment.specimen;
        if let Some(rho) = s.density_g_cm3 {
            return rho * G_CM3_IN_T_MM3;
        }
        match (s.mass_g, self.volume_mm3()) {
            // g/mm^3 -> t/mm^3.
            (Some(m), Some(v)) => m / v * 1e-6,
            _ => G_CM3_IN_T_MM3,
        }
    }

    /// The engine's protocol. `plate` is the v1 tool's contact as a constraint
    /// (`"friction"` maps to `Frictionless`; the engine ignores `plate` when the
    /// trial has contact tools, which a friction contact always gives); `support`
    /// is `Glued`, `Frictionless`, or `Free` for `"friction"` (the floor tool of
    /// [`Bundle::contact_tools`] then holds the bottom).
    pub fn protocol(&self) -> Result<Protocol, BundleError> {
        let p = &self.experiment.protocol;
        let plate = match p.tool_contact {
            Contact::Glued => Attachment::Glued,
            Contact::Frictionless | Contact::Friction => Attachment::Frictionless,
        };
        let support = match p.support {
            Contact::Glued => Attachment::Glued,
            Contact::Frictionless => Attachment::Frictionless,
            Contact::Friction => Attachment::Free,
        };
        Ok(Protocol {
            waypoints: p.waypoints.clone(),
            release_s: p.release_s,
            end_s: p.end_s,
            plate,
            support,
            gravity: p.gravity,
        })
    }

    /// One request per marker in the section of the axisymmetric model: `(x, y, z)`
    /// becomes `(r, y)` with `r = sqrt(x^2 + z^2)`.
    fn axisymmetric_marker_requests(&self) -> Vec<MarkerRequest> {
        self.marker_requests()
            .into_iter()
            .map(|mut m| {
                if let [x, y, z] = m.position[..] {
                    m.position = vec![x.hypot(z), y];
                }
                m
            })
            .collect()
    }

    /// The simulated marker series of `tracks` (`PressResult::markers` of a run of
    /// `problem`, built from this bundle), in the bundle's coordinates: the tracks
    /// as they are, except for the axisymmetric model, whose `(r, y)` tracks are
    /// put back on each marker's azimuth, `(r cos θ, y, r sin θ)` (θ from the
    /// marker's initial `(x, z)`; 0 on the axis).
    pub fn simulated_markers(&self, problem: &AnyPress, tracks: &[MarkerTrack]) -> Vec<MarkerSeries> {
        let AnyPress::Axisymmetric(_) = problem else {
            return MarkerSeries::from_tracks(tracks);
        };
        tracks.iter().map(|track| self.marker_on_its_azimuth(track)).collect()
    }

    fn marker_on_its_azimuth(&self, track: &MarkerTrack) -> MarkerSeries {
        let (cos, sin) = match self.marker(&track.name).and_then(|m| m.initial_position()) {
            Some(&[x, _, z]) if x.hypot(z) > 0.0 => (x / x.hypot(z), z / x.hypot(z)),
            _ => (1.0, 0.0),
        };
        let samples = track
            .samples
            .iter()
            .map(|(t_s, p)| {
                let position_mm = match p[..] {
                    [r, y] => vec![r * cos, y, r * sin],
                    _ => p.clone(),
                };
                MarkerSample { t_s: *t_s, position_mm }
            })
            .collect();
        MarkerSeries { name: track.name.clone(), samples }
    }

    /// One request per marker: its initial position, reported at every measured time.
    pub fn marker_requests(&self) -> Vec<MarkerRequest> {
        self.markers
            .iter()
            .map(|m| MarkerRequest {
                name: m.name.clone(),
                position: m.initial_position().map(<[f64]>::to_vec).unwrap_or_default(),
                times: m.samples.iter().map(|s| s.t_s).collect(),
            })
            .collect()
    }

    /// The default element size [mm]: a quarter of the specimen's smallest dimension
    /// (min(W, H, T) for a block, min(R, H) for a cylinder, the smallest side of
    /// the bounding box for a surface or mesh); `None` for a surface or mesh that
    /// cannot be read. `wagashi press` and `wagashi fit` use it; a `shape = "mesh"`
    /// specimen is pressed with its own cells whatever the size.
    pub fn default_size_mm(&self) -> Option<f64> {
        let s = &self.experiment.specimen;
        let smallest = match s.shape {
            Shape::Block => s.block_size().map(|[w, h, t]| w.min(h).min(t)),
            Shape::Cylinder => Some(s.radius_mm?.min(s.height_mm?)),
            Shape::Surface => {
                let (lo, hi) = self.specimen_surface().ok()?.bounding_box();
                Some((0..3).map(|k| hi[k] - lo[k]).fold(f64::INFINITY, f64::min))
            }
            Shape::Mesh => {
                let (lo, hi) = self.specimen_mesh().ok()?.bounding_box();
                Some((0..3).map(|k| hi[k] - lo[k]).fold(f64::INFINITY, f64::min))
            }
        };
        smallest.filter(|d| *d > 0.0).map(|d| d / 4.0)
    }

    /// The element size [mm] of one cell through the specimen, when the trial's
    /// solution is homogeneous and such a mesh solves it exactly; `None`
    /// otherwise.
    ///
    /// Homogeneous: a block (any dimension), or a cylinder modelled by its
    /// axisymmetric section, of one material, between a plate and the support
    /// that are both frictionless, with no other tool, no gravity and no
    /// effect. The exact solution is then a uniform stretch about the
    /// specimen's centre, which linear cells reproduce exactly on any mesh, so
    /// every mesh gives the same force and markers to the solver's tolerance
    /// (a 3D cylinder is excluded: its faceted circle's area depends on the
    /// mesh). `wagashi fit` takes it as its default element size: one fit
    /// evaluation then costs a few cells instead of hundreds.
    pub fn homogeneous_size_mm(&self, axisymmetric: bool) -> Option<f64> {
        let e = &self.experiment;
        let (s, p) = (&e.specimen, &e.protocol);
        let homogeneous = s.layers.is_empty()
            && s.regions.is_empty()
            && p.tool == Tool::Plate
            && p.tool_contact == Contact::Frictionless
            && p.support == Contact::Frictionless
            && p.tools.is_empty()
            && !p.gravity
            && e.effects.is_empty();
        if !homogeneous {
            return None;
        }
        let largest = match s.shape {
            Shape::Block => s.block_size().map(|[w, h, t]| w.max(h).max(t)),
            Shape::Cylinder if axisymmetric => Some(s.radius_mm?.max(s.height_mm?)),
            _ => None,
        };
        largest.filter(|d| d.is_finite() && *d > 0.0)
    }

    /// The engine materials of `regions` (material names), in that order.
    pub fn materials_for(&self, regions: &[String]) -> Result<Vec<Material>, BundleError> {
        regions
            .iter()
            .map(|name| {
                let spec = self.experiment.materials.get(name).ok_or_else(|| BundleError::Invalid {
                    file: self.experiment_file(),
                    line: self.line_of("specimen"),
                    field: "specimen".into(),
                    cause: format!("material \"{name}\" is not defined"),
                })?;
                spec.to_material().map_err(|missing| {
                    let field = format!("materials.{name}.{}", missing.key);
                    let (file, line) = match spec.location("") {
                        Some((f, l)) => (f.to_path_buf(), l),
                        None => (self.experiment_file(), self.line_of(&field)),
                    };
                    BundleError::Invalid {
                        file,
                        line,
                        field,
                        cause: format!(
                            "missing: a simulation needs every parameter of the {} model (this material lacks {})",
                            spec.model.as_str(),
                            spec.missing().join(", ")
                        ),
                    }
                })
            })
            .collect()
    }

    /// The engine's press problem at element size `size_mm` [mm], checked by the
    /// engine (`PressProblem::validate`); no extra snapshot times.
    /// A surface specimen is meshed in conforming mode ([`Bundle::to_press_meshed`]).
    pub fn to_press(&self, size_mm: f64) -> Result<AnyPress, BundleError> {
        self.build_press(size_mm, false, SurfaceMeshing::Conforming)
    }

    /// [`Bundle::to_press`], a surface specimen being meshed by `mode` (other
    /// shapes ignore it).
    pub fn to_press_meshed(&self, size_mm: f64, mode: SurfaceMeshing) -> Result<AnyPress, BundleError> {
        self.build_press(size_mm, false, mode)
    }

    /// The axisymmetric model of a cylinder bundle at element size `size_mm` [mm]:
    /// [`AnyPress::Axisymmetric`] on the section `[0, R] x [0, H]` (see the module
    /// docs), checked by the engine; no extra snapshot times. Refused, naming
    /// `specimen.shape`, for a specimen that is not a cylinder.
    pub fn to_press_axisymmetric(&self, size_mm: f64) -> Result<AnyPress, BundleError> {
        self.build_press(size_mm, true, SurfaceMeshing::Conforming)
    }

    fn build_press(&self, size_mm: f64, axisymmetric: bool, mode: SurfaceMeshing) -> Result<AnyPress, BundleError> {
        if !(size_mm.is_finite() && size_mm > 0.0) {
            return Err(BundleError::ElementSize { size_mm });
        }
        // The fields are public: check again whatever may have been edited since reading.
        validate_experiment(&self.experiment, &self.map)?;
        let s = &self.experiment.specimen;
        if axisymmetric && s.shape != Shape::Cylinder {
            return Err(BundleError::Invalid {
                file: self.experiment_file(),
                line: self.line_of("specimen.shape"),
                field: "specimen.shape".into(),
                cause: format!(
                    "the axisymmetric model needs shape = \"cylinder\" (a body of revolution about y); this specimen is a \"{}\"",
                    s.shape.as_str()
                ),
            });
        }
        let protocol = self.protocol()?;
        let tools = self.contact_tools(axisymmetric)?;
        let effects = self.effects()?;
        let missing = |field: &str| self.map.invalid(field, "missing required key");
        let block_size = || s.block_size().ok_or_else(|| missing("specimen.size_mm"));
        let layers: Vec<Layer> = match &s.material {
            Some(m) => vec![Layer {
                region: m.clone(),
                thickness_mm: s.block_size().map_or(s.height_mm.unwrap_or(0.0), |b| b[1]),
            }],
            None => {
                s.layers.iter().map(|l| Layer { region: l.material.clone(), thickness_mm: l.thickness_mm }).collect()
            }
        };
        let mesh_err = |e: mesh::MeshError| self.engine_error(PressError::Mesh(e));
        let density_t_mm3 = self.density_t_mm3();
        let markers = self.marker_requests();
        // A 3D problem on `mesh` (blocks and cylinders differ only in the mesh).
        let solid = |mesh: mesh::TetMesh| -> Result<AnyPress, BundleError> {
            let materials = self.materials_for(&mesh.region_names)?;
            Ok(AnyPress::Solid(SolidPress {
                mesh,
                formulation: Formulation::Solid,
                materials,
                density_t_mm3,
                protocol: protocol.clone(),
                markers: markers.clone(),
                snapshot_times: Vec::new(),
                tools: tools.clone(),
                effects: effects.clone(),
            }))
        };
        let problem = match (s.shape, self.dimension()) {
            (Shape::Cylinder, _) if axisymmetric => {
                let r = s.radius_mm.ok_or_else(|| missing("specimen.radius_mm"))?;
                s.height_mm.ok_or_else(|| missing("specimen.height_mm"))?;
                let mesh = mesh::layered_axisymmetric_section(r, &layers, size_mm).map_err(mesh_err)?;
                let materials = self.materials_for(&mesh.region_names)?;
                AnyPress::Axisymmetric(AxisymmetricPress {
                    mesh,
                    formulation: Formulation::Axisymmetric,
                    materials,
                    density_t_mm3,
                    protocol,
                    markers: self.axisymmetric_marker_requests(),
                    snapshot_times: Vec::new(),
                    tools: tools.clone(),
                    effects: effects.clone(),
                })
            }
            (Shape::Block, 2) => {
                let [w, _, t] = block_size()?;
                let mesh = mesh::layered_rectangle(w, &layers, size_mm).map_err(mesh_err)?;
                let materials = self.materials_for(&mesh.region_names)?;
                AnyPress::Plane(PlanePress {
                    mesh,
                    formulation: match self.experiment.specimen.plane {
                        Some(crate::bundle::Plane::Strain) => Formulation::PlaneStrain { thickness_mm: t },
                        _ => Formulation::PlaneStress { thickness_mm: t },
                    },
                    materials,
                    density_t_mm3,
                    protocol,
                    markers,
                    snapshot_times: Vec::new(),
                    tools: tools.clone(),
                    effects: effects.clone(),
                })
            }
            (Shape::Block, _) => {
                let [w, _, t] = block_size()?;
                solid(mesh::layered_block(w, t, &layers, size_mm).map_err(mesh_err)?)?
            }
            (Shape::Cylinder, _) => {
                let r = s.radius_mm.ok_or_else(|| missing("specimen.radius_mm"))?;
                let h = s.height_mm.ok_or_else(|| missing("specimen.height_mm"))?;
                let material = s.material.as_deref().ok_or_else(|| missing("specimen.material"))?;
                solid(mesh::cylinder(r, h, size_mm, material).map_err(mesh_err)?)?
            }
            (Shape::Surface, 2) => {
                return Err(
                    self.unsupported("dimension", "shape = \"surface\" is a 3D shape: it needs dimension = 3".into())
                )
            }
            (Shape::Surface | Shape::Mesh, _) => {
                let mesh = match s.shape {
                    Shape::Mesh => self.specimen_mesh()?,
                    _ => self.mesh_specimen_surface(size_mm, mode)?,
                };
                let materials = self.materials_for(&self.surface_region_materials(&mesh)?)?;
                AnyPress::Solid(SolidPress {
                    mesh,
                    formulation: Formulation::Solid,
                    materials,
                    density_t_mm3,
                    protocol,
                    markers: markers.clone(),
                    snapshot_times: Vec::new(),
                    tools: tools.clone(),
                    effects: effects.clone(),
                })
            }
        };
        match &problem {
            AnyPress::Plane(p) => p.validate(),
            AnyPress::Solid(p) => p.validate(),
            AnyPress::Axisymmetric(p) => p.validate(),
        }
        .map_err(|e| self.engine_error(e))?;
        Ok(problem)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bundle::read_bundle;

    /// The engine's material errors name the bundle key that caused them.
    #[test]
    fn engine_errors_map_to_bundle_keys() {
        let dir = tempfile::tempdir().unwrap();
        let text = "format = \"wagashi-experiment/1\"\nname = \"a\"\ndimension = 2\n[specimen]\nshape = \"block\"\n\
                    size_mm = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n[materials.m]\nmodel = \"four-element\"\n\
                    poisson = 0.3\nE1_MPa = 1.0\nc1_MPa_s = 1.0\nE2_MPa = 1.0\nc3_MPa_s = 1.0\n[protocol]\n\
                    tool = \"plate\"\ntool_contact = \"glued\"\nsupport = \"glued\"\nwaypoints = [[0.0, 0.0]]\n\
                    release_s = 1.0\nend_s = 1.0\n";
        std::fs::write(dir.path().join("experiment.toml"), text).unwrap();
        let bundle = read_bundle(dir.path()).unwrap();
        let cases = [
            (MaterialError::NotPositive { name: "E2", value: 0.0 }, "materials.m.E2_MPa", 13),
            (MaterialError::NotPositive { name: "c3", value: 0.0 }, "materials.m.c3_MPa_s", 14),
            (MaterialError::PoissonOutOfRange { value: 0.6 }, "materials.m.poisson", 10),
        ];
        for (source, key, line) in cases {
            let err = bundle.engine_error(PressError::Material { region: "m".into(), source });
            let want =
                format!("{}:{line}: {key}: material of region `m`: ", dir.path().join("experiment.toml").display());
            assert!(err.to_string().starts_with(&want), "{err}");
        }
        let err = bundle.engine_error(PressError::BadProtocol("x".into()));
        assert!(err.to_string().contains(":15: protocol: protocol: x"), "{err}");
    }

    const CYLINDER: &str = "format = \"wagashi-experiment/1\"\nname = \"gel\"\ndimension = 3\n[specimen]\n\
                            shape = \"cylinder\"\nradius_mm = 4.0\nheight_mm = 9.0\nmass_g = 0.5\nmaterial = \"gel\"\n\
                            [materials.gel]\nmodel = \"elastic\"\npoisson = 0.45\nE_MPa = 0.05\n[protocol]\n\
                            tool = \"plate\"\ntool_contact = \"glued\"\nsupport = \"glued\"\n\
                            waypoints = [[0.0, 0.0], [2.0, 0.9]]\nrelease_s = 2.0\nend_s = 10.0\n\
                            [data]\nmarkers = \"markers.csv\"\n";

    /// A cylinder's axisymmetric model: the section [0, R] x [0, H] with its axis,
    /// the same density and protocol, markers located at (r, y); tracks go back
    /// onto each marker's azimuth.
    #[test]
    fn cylinder_as_its_axisymmetric_section() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("experiment.toml"), CYLINDER).unwrap();
        let markers = "marker,t_s,x_mm,y_mm,z_mm\nside,0.0,0.0,4.5,-4.0\nside,2.0,0.0,4.5,-4.1\n\
                       diag,0.0,2.4,9.0,3.2\ndiag,2.0,2.4,8.1,3.2\n";
        std::fs::write(dir.path().join("markers.csv"), markers).unwrap();
        let bundle = read_bundle(dir.path()).unwrap();
        let AnyPress::Axisymmetric(p) = bundle.to_press_axisymmetric(1.0).unwrap() else {
            panic!("expected the axisymmetric model")
        };
        assert_eq!(p.formulation, Formulation::Axisymmetric);
        assert!((p.mesh.measure() - 36.0).abs() < 1e-12 * 36.0);
        assert_eq!(p.mesh.node_sets["axis"].len(), 10);
        let AnyPress::Solid(solid) = bundle.to_press(1.0).unwrap() else { panic!("expected 3D") };
        assert_eq!(
            (p.density_t_mm3, &p.protocol, &p.materials),
            (solid.density_t_mm3, &solid.protocol, &solid.materials)
        );
        assert_eq!(p.markers[0].position, vec![4.0, 4.5]);
        assert!((p.markers[1].position[0] - 4.0).abs() < 1e-15 && p.markers[1].position[1] == 9.0);
        assert_eq!(p.markers[1].times, vec![0.0, 2.0]);

        // Simulated (r, y) tracks back in 3D on each marker's azimuth.
        let tracks = [
            MarkerTrack { name: "side".into(), samples: vec![(0.0, vec![4.0, 4.5]), (2.0, vec![4.2, 4.4])] },
            MarkerTrack { name: "diag".into(), samples: vec![(0.0, vec![4.0, 9.0]), (2.0, vec![5.0, 8.1])] },
        ];
        let series = bundle.simulated_markers(&AnyPress::Axisymmetric(p), &tracks);
        let close = |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
        assert!(close(&series[0].samples[1].position_mm, &[0.0, 4.4, -4.2]), "{:?}", series[0]);
        assert!(close(&series[1].samples[0].position_mm, &[2.4, 9.0, 3.2]), "{:?}", series[1]);
        assert!(close(&series[1].samples[1].position_mm, &[3.0, 8.1, 4.0]), "{:?}", series[1]);
    }

    /// Only a cylinder has an axisymmetric model; the refusal names the key.
    #[test]
    fn axisymmetric_model_of_a_block_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let text = CYLINDER
            .replace(
                "shape = \"cylinder\"\nradius_mm = 4.0\nheight_mm = 9.0",
                "shape = \"block\"\nsize_mm = [4.0, 9.0, 4.0]",
            )
            .replace("[data]\nmarkers = \"markers.csv\"\n", "");
        std::fs::write(dir.path().join("experiment.toml"), text).unwrap();
        let bundle = read_bundle(dir.path()).unwrap();
        let err = bundle.to_press_axisymmetric(1.0).unwrap_err().to_string();
        let want = format!(
            "{}:5: specimen.shape: the axisymmetric model needs shape = \"cylinder\"",
            bundle.experiment_file().display()
        );
        assert!(err.starts_with(&want) && err.contains("\"block\""), "{err}");
    }
}
