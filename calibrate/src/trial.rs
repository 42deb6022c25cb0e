//! Residuals from experiment bundles, with exact Jacobians from the engine's
//! forward sensitivities.
//!
//! A [`Campaign`] holds the trials (one bundle each) and the unknowns: every
//! material parameter that no bundle gives (or that the caller frees), named by
//! material and key (`mat1.E1_MPa`). A material used by several trials or layers
//! is one set of unknowns. An [`Objective`] is a least-squares problem over some
//! of the unknowns and some channels:
//!
//! | channel  | residual                                   | noise `sigma`                       |
//! |----------|--------------------------------------------|-------------------------------------|
//! | `force`  | `(F_sim(t_i) - F_meas(t_i))/sigma_F`       | from the data, see below            |
//! | `keep`   | marker coordinates during the hold         | `sigma_m` per coordinate            |
//! | `final`  | marker coordinates after the release       | `sigma_m` per coordinate            |
//!
//! Force noise `sigma_F` is estimated from the measured curve itself by the
//! difference method: for a signal that is smooth on the sampling scale, the first
//! differences of the samples are noise differences, so `sigma_F = 1.4826
//! MAD(dF)/sqrt(2)` (a robust standard deviation of white noise). It is floored at
//! 1e-4 of the peak force, the resolution of a typical 16-bit acquisition, so that a
//! noise-free (simulated) curve still has finite weights. Marker noise is not
//! repeatable from one measurement per time, so `sigma_m` is a setting (default
//! 0.05 mm, the camera resolution the seed's figures suggest); the joint
//! procedure re-estimates both from the residuals of its single-channel fits.
//! Intervals assume independent errors at the samples used: at most
//! [`MAX_FORCE_SAMPLES`] force samples per trial are used (a uniform stride), since
//! neighbouring samples of a fast acquisition are not independent.
//!
//! Marker observations at `t = 0` are the definition of the material points and
//! carry no residual.
//!
//! A bundle's `[effects]` (`fem_core::effects`), and a material's Mullins-type
//! damage, are held at their values while the materials are fitted. With `force-offset` and `gravity` alone the Jacobian
//! comes from the engine's forward sensitivities. With an active effect whose
//! sensitivities the engine does not carry (`ageing`, `machine-compliance` and
//! the material-point effects `plastic-slider`, `bingham-dashpot`,
//! `stress-thinning`, `dual-viscosity`, `strain-stiffening`, `finite-strain`), or
//! with a material's Mullins-type damage, the trial's Jacobian columns are *forward differences on a frozen discretisation*:
//! the run at the point fixes the step ends, the point is replayed on them
//! (`Settings::step_ends_s`) and so is each perturbed run, so the adaptive step
//! choice does not enter the difference (the diagnosis's rule,
//! diagnosis-details.md §5.1.3). Step: [`FD_STEP`] of a log-scaled unknown's value,
//! of a linear one's range. Trials with contact tools (a sphere, a punch, a
//! surface, a plate that leaves and touches again) have no forward sensitivities
//! either and are differenced the same way. A contact step that does not settle
//! may not be subdivided on a replay, so when a replay fails, and always with a
//! contact effect (`plate-friction`, `adhesion`), the columns come from adaptive
//! runs instead, with the larger step [`ADAPTIVE_FD_STEP`]: their step choice
//! moves the force by about the step tolerance (the diagnosis's rule,
//! `diagnosis::model`).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use fem_core::effects::HookPoint;
use fem_core::material::Material;
use fem_core::press::{
    simulate_any, simulate_any_with_sensitivities, AnyPress, ParameterKind, PressResult, Sensitivities,
    SensitivityParameter, Settings,
};
use nalgebra::DMatrix;
use rayon::prelude::*;
use wagashi_io::{Bundle, MaterialSpec};

use crate::lsq::{EvalError, Evaluation, LeastSquares, ParameterSpec};

/// The relative step of the forward differences of a trial whose effects have no
/// forward sensitivities (module docs).
pub const FD_STEP: f64 = 1e-6;

/// The relative step of the forward differences on adaptive runs, for the trials
/// whose frozen replay is not possible (contact; module docs): the adaptive step
/// choice moves the force by about the step tolerance, so the step must be far
/// larger than [`FD_STEP`] (the diagnosis uses the same, `diagnosis::model`).
pub const ADAPTIVE_FD_STEP: f64 = 2e-2;

/// Force samples per trial used in a fit, at most.
pub const MAX_FORCE_SAMPLES: usize = 1500;

/// A measured quantity's channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Channel {
    /// The bottom force.
    Force,
    /// Marker positions during the hold (the keep-shape).
    Keep,
    /// Marker positions after the release (the final shape).
    Final,
}

impl Channel {
    /// The channel's name in reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Channel::Force => "force",
            Channel::Keep => "keep",
            Channel::Final => "final",
        }
    }
}

/// An unknown material parameter: a material name and a bundle key.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Unknown {
    /// The material's name, as in `[materials.NAME]`.
    pub material: String,
    /// The bundle key: `poisson`, `E1_MPa`, `c3_MPa_s`, ...
    pub key: &'static str,
}

impl Unknown {
    /// `material.key`.
    pub fn label(&self) -> String {
        format!("{}.{}", self.material, self.key)
    }

    /// Default bounds and scale: moduli in [1e-5, 1e2] MPa and viscosities in
    /// [1e-5, 1e5] MPa s on a log scale; Poisson's ratio in [0, 0.499], linear.
    /// A network's keys ([`wagashi_io::bundle::network_keys`]) take the fit
    /// range of their law's table ([`fem_core::material::law::ParameterSpec::fit`]).
    pub fn spec(&self) -> ParameterSpec {
        let label = self.label();
        if let Some((s, _)) = fem_core::material::network::parameters::spec_of(self.key) {
            return if s.fit.log {
                ParameterSpec::log(label, s.fit.lower, s.fit.upper)
            } else {
                ParameterSpec::linear(label, s.fit.lower, s.fit.upper)
            };
        }
        match self.key {
            "poisson" => ParameterSpec::linear(label, 0.0, 0.499),
            k if k.ends_with("_MPa_s") => ParameterSpec::log(label, 1e-5, 1e5),
            _ => ParameterSpec::log(label, 1e-5, 1e2),
        }
    }
}

/// Sets `key` of `spec` to `value`; false for a key the spec does not have.
pub fn set_parameter(spec: &mut MaterialSpec, key: &str, value: f64) -> bool {
    let slot = match key {
        "poisson" => &mut spec.poisson,
        "E_MPa" => &mut spec.e_mpa,
        "E1_MPa" => &mut spec.e1_mpa,
        "E2_MPa" => &mut spec.e2_mpa,
        "c1_MPa_s" => &mut spec.c1_mpa_s,
        "c2_MPa_s" => &mut spec.c2_mpa_s,
        "c3_MPa_s" => &mut spec.c3_mpa_s,
        _ => return spec.set_network_parameter(key, value),
    };
    *slot = Some(value);
    true
}

/// Merges `new`, the same material as another trial gives it, into `old`: a key
/// given by either is given (so the campaign does not depend on the order of its
/// trials); a key both give with different values is an error, returned as
/// `(key, old value, new value)`. `old` is unchanged on error.
fn merge_spec(old: &mut MaterialSpec, new: &MaterialSpec) -> Result<(), (&'static str, f64, f64)> {
    let pairs = |s: &MaterialSpec| {
        let mut v: Vec<(&'static str, Option<f64>)> = vec![("poisson", s.poisson)];
        v.extend(s.parameters());
        v.extend(wagashi_io::bundle::network_keys().iter().map(|&k| (k, s.get(k))));
        v.push(("mullins_d_inf", s.mullins_d_inf));
        v.push(("mullins_strain_c", s.mullins_strain_c));
        v
    };
    for ((key, a), (_, b)) in pairs(old).into_iter().zip(pairs(new)) {
        if let (Some(a), Some(b)) = (a, b) {
            if a != b {
                return Err((key, a, b));
            }
        }
    }
    let mut merged = old.clone();
    for (key, value) in pairs(new) {
        if let (Some(v), None) = (value, pairs(old).into_iter().find(|(k, _)| *k == key).and_then(|(_, v)| v)) {
            match key {
                "mullins_d_inf" => merged.mullins_d_inf = Some(v),
                "mullins_strain_c" => merged.mullins_strain_c = Some(v),
                _ => {
                    set_parameter(&mut merged, key, v);
                }
            }
        }
    }
    *old = merged;
    Ok(())
}

/// The bundle key of an engine rheology parameter name (`E1` -> `E1_MPa`);
/// `None` for a name the chain's models do not have.
fn key_of(name: &str) -> Option<&'static str> {
    Some(match name {
        "E" => "E_MPa",
        "E1" => "E1_MPa",
        "E2" => "E2_MPa",
        "c1" => "c1_MPa_s",
        "c2" => "c2_MPa_s",
        "c3" => "c3_MPa_s",
        _ => return None,
    })
}

/// The engine's sensitivity parameter of unknown `u` on a trial whose regions
/// carry `region_material` and the `materials`: the regions of its material
/// and its place among the rheology's parameters (or Poisson's ratio). `None`
/// when its material is not on the trial or its model has no such key.
pub(crate) fn sensitivity_parameter(
    u: &Unknown,
    region_material: &[String],
    materials: &[Material],
) -> Option<SensitivityParameter> {
    let regions: Vec<usize> = (0..region_material.len()).filter(|&r| region_material[r] == u.material).collect();
    if regions.is_empty() {
        return None;
    }
    let kind = if u.key == "poisson" {
        ParameterKind::Poisson
    } else {
        let names = materials[regions[0]].rheology.parameters();
        ParameterKind::Rheology(names.iter().position(|(n, _)| key_of(n) == Some(u.key))?)
    };
    Some(SensitivityParameter { regions, kind })
}

/// One measured marker coordinate set.
#[derive(Debug, Clone)]
struct MarkerObservation {
    marker: usize,
    /// Index into the simulated track's samples.
    sample: usize,
    position: Vec<f64>,
    channel: Channel,
}

/// Why a campaign could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// A bundle could not be turned into a press problem.
    #[error(transparent)]
    Bundle(#[from] wagashi_io::BundleError),
    /// Something else about the trials, in words.
    #[error("{0}")]
    Invalid(String),
}

/// A measured marker position and its simulated counterpart.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerPair {
    /// The marker's name.
    pub name: String,
    /// Time [s].
    pub t_s: f64,
    /// Keep or final.
    pub channel: Channel,
    /// Measured position [mm].
    pub measured: Vec<f64>,
    /// Simulated position [mm].
    pub simulated: Vec<f64>,
}

/// One trial prepared for fitting.
#[derive(Debug, Clone)]
pub struct Trial {
    /// The bundle's name.
    pub name: String,
    /// The press problem (its materials are replaced at each evaluation).
    problem: AnyPress,
    /// Region index -> material name.
    region_material: Vec<String>,
    /// `(t_s, force_N)` used in the fit.
    pub force: Vec<(f64, f64)>,
    /// Estimated force noise [N].
    pub force_sigma_n: f64,
    markers: Vec<MarkerObservation>,
    /// Marker names, in the problem's order.
    pub marker_names: Vec<String>,
    /// Release time [s].
    pub release_s: f64,
    /// End of the last push [s].
    pub last_push_s: f64,
    /// End time [s].
    pub end_s: f64,
}

impl Trial {
    /// The number of observations in `channel`.
    pub fn count(&self, channel: Channel) -> usize {
        match channel {
            Channel::Force => self.force.len(),
            c => self.markers.iter().filter(|m| m.channel == c).map(|m| m.position.len()).sum(),
        }
    }

    fn materials(&self, table: &BTreeMap<String, MaterialSpec>) -> Result<Vec<Material>, EvalError> {
        self.region_material
            .iter()
            .map(|name| {
                let spec = &table[name];
                spec.to_material().map_err(|m| EvalError::new(format!("material {name} lacks {}", m.key))).and_then(
                    |m| {
                        m.rheology.validate().map_err(|e| EvalError::new(format!("material {name}: {e}")))?;
                        Ok(m)
                    },
                )
            })
            .collect()
    }

    fn with_materials(&self, materials: Vec<Material>) -> AnyPress {
        let mut p = self.problem.clone();
        match &mut p {
            AnyPress::Plane(q) => q.materials = materials,
            AnyPress::Solid(q) => q.materials = materials,
            AnyPress::Axisymmetric(q) => q.materials = materials,
        }
        p
    }

    /// Simulates the trial with the materials of `table`.
    pub fn simulate(
        &self,
        table: &BTreeMap<String, MaterialSpec>,
        settings: &Settings,
    ) -> Result<PressResult, EvalError> {
        let p = self.with_materials(self.materials(table)?);
        simulate_any(&p, settings, &mut |_| {}).map_err(|e| EvalError::with_source(format!("trial {}", self.name), e))
    }

    /// Simulated force at the used sample times [N].
    pub fn simulated_force(&self, result: &PressResult) -> Vec<f64> {
        self.force.iter().map(|&(t, _)| result.bottom_force_at(t)).collect()
    }

    /// Every marker observation (t > 0) with its simulated position in `result`.
    pub fn marker_pairs(&self, result: &PressResult) -> Vec<MarkerPair> {
        self.markers
            .iter()
            .map(|o| {
                let (t, sim) = &result.markers[o.marker].samples[o.sample];
                MarkerPair {
                    name: self.marker_names[o.marker].clone(),
                    t_s: *t,
                    channel: o.channel,
                    measured: o.position.clone(),
                    simulated: sim.clone(),
                }
            })
            .collect()
    }
}

/// Trials and unknowns.
#[derive(Debug)]
pub struct Campaign {
    /// The trials.
    pub trials: Vec<Trial>,
    /// Every material's spec, unknowns included (filled with their current values).
    pub materials: BTreeMap<String, MaterialSpec>,
    /// The unknowns, sorted by material then by the model's key order.
    pub unknowns: Vec<Unknown>,
    /// Settings of every simulation.
    pub settings: Settings,
    /// Marker noise [mm].
    pub marker_sigma_mm: f64,
    simulations: AtomicUsize,
}

impl Campaign {
    /// Prepares `bundles` for fitting, with elements of `size_mm` (or a quarter of
    /// each specimen's smallest dimension); `axisymmetric` models cylinders by their
    /// r-y section (markers compared at `r = sqrt(x^2 + z^2)`). `start` gives values for unknowns and may
    /// free given ones: its parameters override the bundles' (they are starting
    /// values); parameters the bundles give and `start` does not are held fixed.
    /// Trials naming the same material give one material: the keys any of them
    /// gives are given, and a key two trials give with different values is an
    /// error naming the second trial's file.
    pub fn new(
        bundles: &[Bundle],
        start: &BTreeMap<String, MaterialSpec>,
        size_mm: Option<f64>,
        axisymmetric: bool,
    ) -> Result<Self, CampaignError> {
        if bundles.is_empty() {
            return Err(CampaignError::Invalid("no trial to fit".into()));
        }
        // The material table: bundles' specs merged, the start values over them.
        let mut materials: BTreeMap<String, MaterialSpec> = BTreeMap::new();
        for b in bundles {
            for name in b.experiment.specimen.material_names() {
                let spec = b.experiment.materials.get(name).cloned().or_else(|| start.get(name).cloned());
                let Some(spec) = spec else {
                    return Err(CampaignError::Invalid(format!(
                        "{}: material {name} has no model: give it in the bundle or with --materials",
                        b.experiment_file().display()
                    )));
                };
                match materials.get_mut(name) {
                    Some(old) if old.model != spec.model => {
                        return Err(CampaignError::Invalid(format!(
                            "material {name} is {} in one trial and {} in {}",
                            old.model.as_str(),
                            spec.model.as_str(),
                            b.experiment_file().display()
                        )))
                    }
                    Some(old) => merge_spec(old, &spec).map_err(|(key, was, now)| {
                        CampaignError::Invalid(format!(
                            "{}: material {name} gives {key} = {now}, but an earlier trial gave {was}: a campaign \
                             fits one material, so its given (fixed) parameters must agree; give the value once, or \
                             free it with --materials",
                            b.experiment_file().display()
                        ))
                    })?,
                    None => {
                        materials.insert(name.to_string(), spec);
                    }
                }
            }
        }
        let mut unknowns = Vec::new();
        for (name, spec) in materials.iter_mut() {
            let s = start.get(name);
            let mut keys: Vec<&'static str> = vec!["poisson"];
            keys.extend(spec.parameter_keys());
            for key in keys {
                let started = s.and_then(|s| s.get(key));
                if spec.get(key).is_none() || started.is_some() {
                    unknowns.push(Unknown { material: name.clone(), key });
                    if let Some(v) = started {
                        set_parameter(spec, key, v);
                    }
                }
            }
        }
        default_starts(&mut materials, &unknowns, bundles);

        let mut trials = Vec::new();
        for b in bundles {
            let mut filled = b.clone();
            for name in b.experiment.specimen.material_names() {
                filled.experiment.materials.insert(name.to_string(), materials[name].clone());
            }
            let size = match size_mm.or_else(|| b.default_size_mm()) {
                Some(h) => h,
                None => {
                    return Err(CampaignError::Invalid(format!(
                        "{}: give an element size (--size-mm) for this specimen",
                        b.experiment_file().display()
                    )))
                }
            };
            let problem = if axisymmetric { filled.to_press_axisymmetric(size)? } else { filled.to_press(size)? };
            trials.push(trial_of(b, problem)?);
        }
        Ok(Self {
            trials,
            materials,
            unknowns,
            settings: Settings::default(),
            marker_sigma_mm: 0.05,
            simulations: AtomicUsize::new(0),
        })
    }

    /// The current values of the unknowns.
    pub fn values(&self) -> Vec<f64> {
        self.unknowns.iter().map(|u| self.materials[&u.material].get(u.key).expect("filled")).collect()
    }

    /// The material table with the unknowns set to `values`.
    pub fn table_with(&self, values: &[f64]) -> BTreeMap<String, MaterialSpec> {
        let mut t = self.materials.clone();
        for (u, &v) in self.unknowns.iter().zip(values) {
            set_parameter(t.get_mut(&u.material).expect("known material"), u.key, v);
        }
        t
    }

    /// Whether any trial's Jacobian comes from finite differences (a run per
    /// column), so that a least-squares fit should ask for it only at accepted
    /// points ([`crate::lsq::Options::jacobian_with_trial`]).
    pub fn differenced(&self) -> bool {
        self.trials.iter().any(|t| t.materials(&self.materials).is_ok_and(|m| differenced(&t.with_materials(m))))
    }

    /// Simulations run so far.
    pub fn simulations(&self) -> usize {
        self.simulations.load(Ordering::Relaxed)
    }

    /// Simulates every trial with the unknowns at `values` (in parallel).
    pub fn simulate_all(&self, values: &[f64]) -> Result<Vec<PressResult>, EvalError> {
        let table = self.table_with(values);
        self.simulations.fetch_add(self.trials.len(), Ordering::Relaxed);
        self.trials.par_iter().map(|t| t.simulate(&table, &self.settings)).collect()
    }
}

/// Starting values for unknowns that have none: an apparent modulus from the
/// measured peak force over the peak strain and the area, spread over the chain
/// (`E1 = E2 = 2 E_app`: two springs in series), time constants of 0.1 s, 10 s and
/// 1000 s for c1, c2, c3 (`c = E tau`), and nu = 0.3.
fn default_starts(materials: &mut BTreeMap<String, MaterialSpec>, unknowns: &[Unknown], bundles: &[Bundle]) {
    let mut e_app: Vec<f64> = Vec::new();
    for b in bundles {
        let s = &b.experiment.specimen;
        let (area, height) = match s.block_size() {
            Some([w, h, t]) => (w * t, h),
            None => (std::f64::consts::PI * s.radius_mm.unwrap_or(1.0).powi(2), s.height_mm.unwrap_or(1.0)),
        };
        let d_max = b.experiment.protocol.waypoints.iter().map(|w| w[1]).fold(0.0, f64::max);
        if let Some(f) = &b.force {
            let f_max = f.samples.iter().map(|s| s.force_n).fold(0.0, f64::max);
            if f_max > 0.0 && d_max > 0.0 {
                e_app.push(f_max / area / (d_max / height));
            }
        }
    }
    let e = if e_app.is_empty() { 0.05 } else { e_app.iter().sum::<f64>() / e_app.len() as f64 };
    for u in unknowns {
        let spec = materials.get_mut(&u.material).expect("known material");
        if spec.get(u.key).is_some() {
            continue;
        }
        // A network's keys start where their law's table says
        // ([`fem_core::material::law::Start`]): the apparent modulus shared by
        // the equilibrium and the viscous networks, relaxation times spread by
        // decades, a mild stiffening and softening, a slow damper.
        let v = match fem_core::material::network::parameters::spec_of(u.key) {
            Some((s, index)) => s.start.value(e, index),
            None => match u.key {
                "poisson" => 0.3,
                "E_MPa" => e,
                "E1_MPa" | "E2_MPa" => 2.0 * e,
                "c1_MPa_s" => 2.0 * e * 0.1,
                "c2_MPa_s" => 2.0 * e * 10.0,
                _ => 2.0 * e * 1000.0,
            },
        };
        set_parameter(spec, u.key, v);
    }
}

/// The region names of a problem's mesh, whatever its formulation.
pub(crate) fn region_names(problem: &AnyPress) -> Vec<String> {
    match problem {
        AnyPress::Plane(p) => p.mesh.region_names.clone(),
        AnyPress::Solid(p) => p.mesh.region_names.clone(),
        AnyPress::Axisymmetric(p) => p.mesh.region_names.clone(),
    }
}

/// The force samples a fit uses (`0 < t <= end_s`, thinned to at most
/// [`MAX_FORCE_SAMPLES`]) and their noise, estimated before thinning.
pub(crate) fn measured_force(b: &Bundle) -> (Vec<(f64, f64)>, f64) {
    let end_s = b.experiment.protocol.end_s;
    let mut force: Vec<(f64, f64)> = b
        .force
        .as_ref()
        .map(|f| f.samples.iter().filter(|s| s.t_s > 0.0 && s.t_s <= end_s).map(|s| (s.t_s, s.force_n)).collect())
        .unwrap_or_default();
    let force_sigma_n = force_noise(&force);
    if force.len() > MAX_FORCE_SAMPLES {
        let stride = force.len().div_ceil(MAX_FORCE_SAMPLES);
        force = force.into_iter().step_by(stride).collect();
    }
    (force, force_sigma_n)
}

/// A marker position in the model's frame: the axisymmetric model's markers
/// live in its r-y section.
pub(crate) fn model_position(problem: &AnyPress, position_mm: &[f64]) -> Vec<f64> {
    match (problem, position_mm) {
        (AnyPress::Axisymmetric(_), &[x, y, z]) => vec![x.hypot(z), y],
        _ => position_mm.to_vec(),
    }
}

fn trial_of(b: &Bundle, problem: AnyPress) -> Result<Trial, CampaignError> {
    let region_material = region_names(&problem);
    let protocol = &b.experiment.protocol;
    let (release_s, end_s, last_push_s) = (protocol.release_s, protocol.end_s, protocol.last_push_s());
    let (force, force_sigma_n) = measured_force(b);
    let mut markers = Vec::new();
    for (m, series) in b.markers.iter().enumerate() {
        for (i, s) in series.samples.iter().enumerate() {
            if s.t_s <= 0.0 || s.t_s > end_s {
                continue;
            }
            let channel = if s.t_s > release_s {
                Channel::Final
            } else if s.t_s >= last_push_s {
                Channel::Keep
            } else {
                continue;
            };
            let position = model_position(&problem, &s.position_mm);
            markers.push(MarkerObservation { marker: m, sample: i, position, channel });
        }
    }
    Ok(Trial {
        name: b.experiment.name.clone(),
        problem,
        region_material,
        force,
        force_sigma_n,
        markers,
        marker_names: b.markers.iter().map(|m| m.name.clone()).collect(),
        release_s,
        last_push_s,
        end_s,
    })
}

/// Whether a problem's Jacobian comes from finite differences rather than
/// forward sensitivities: effects without sensitivities, contact tools, damage
/// and the network model (module docs).
fn differenced(problem: &AnyPress) -> bool {
    problem.effects().check_sensitivities().is_err()
        || problem.has_tools()
        || problem.has_damage()
        || problem.has_network()
}

/// The difference-method noise estimate, floored at 1e-4 of the peak (module docs).
pub fn force_noise(force: &[(f64, f64)]) -> f64 {
    let peak = force.iter().map(|f| f.1.abs()).fold(0.0, f64::max);
    if force.len() < 3 {
        return (1e-4 * peak).max(1e-12);
    }
    let mut d: Vec<f64> = force.windows(2).map(|w| (w[1].1 - w[0].1).abs()).collect();
    d.sort_by(f64::total_cmp);
    let mad = d[d.len() / 2];
    (1.4826 * mad / std::f64::consts::SQRT_2).max(1e-4 * peak).max(1e-12)
}

/// A least-squares problem over some unknowns and channels of a campaign.
pub struct Objective<'c> {
    campaign: &'c Campaign,
    /// Indices into `campaign.unknowns` of the fitted parameters.
    pub free: Vec<usize>,
    /// Values of every unknown (the fixed ones stay at these).
    pub base: Vec<f64>,
    /// Channels and their noise scale factors (1 = the campaign's sigma).
    pub channels: Vec<(Channel, f64)>,
}

impl<'c> Objective<'c> {
    /// An objective over `free` unknowns and `channels`, the others held at `base`.
    pub fn new(campaign: &'c Campaign, free: Vec<usize>, base: Vec<f64>, channels: &[Channel]) -> Self {
        Self { campaign, free, base, channels: channels.iter().map(|&c| (c, 1.0)).collect() }
    }

    /// The parameter specs of the free unknowns.
    pub fn specs(&self) -> Vec<ParameterSpec> {
        self.free.iter().map(|&i| self.campaign.unknowns[i].spec()).collect()
    }

    /// The full vector of unknowns for free values `x`.
    pub fn full(&self, x: &[f64]) -> Vec<f64> {
        let mut v = self.base.clone();
        for (&i, &xi) in self.free.iter().zip(x) {
            v[i] = xi;
        }
        v
    }

    fn sigma(&self, trial: &Trial, channel: Channel) -> Option<f64> {
        let scale = self.channels.iter().find(|c| c.0 == channel)?.1;
        Some(
            scale
                * match channel {
                    Channel::Force => trial.force_sigma_n,
                    _ => self.campaign.marker_sigma_mm,
                },
        )
    }

    /// Residuals (and Jacobian columns) of one trial.
    fn trial_residuals(
        &self,
        trial: &Trial,
        table: &BTreeMap<String, MaterialSpec>,
        want_jacobian: bool,
    ) -> Result<(Vec<f64>, Vec<Vec<f64>>), EvalError> {
        let materials = trial.materials(table)?;
        let problem = trial.with_materials(materials.clone());
        let differenced = differenced(&problem);
        // The free unknowns that act on this trial: with forward sensitivities,
        // as engine parameters; differenced, every unknown of a material the
        // trial holds (a network's parameters have no engine parameter).
        let mut acting: Vec<(usize, Option<SensitivityParameter>)> = Vec::new();
        if want_jacobian {
            for (col, &i) in self.free.iter().enumerate() {
                let u = &self.campaign.unknowns[i];
                let parameter = sensitivity_parameter(u, &trial.region_material, &materials);
                let on_trial = trial.region_material.contains(&u.material);
                if parameter.is_some() || (differenced && on_trial) {
                    acting.push((col, parameter));
                }
            }
        }
        self.campaign.simulations.fetch_add(1, Ordering::Relaxed);
        let settings = &self.campaign.settings;
        let (result, sens): (PressResult, Option<Sensitivities>) = if acting.is_empty() || differenced {
            let r = simulate_any(&problem, settings, &mut |_| {});
            (r.map_err(|e| EvalError::with_source(format!("trial {}", trial.name), e))?, None)
        } else {
            let params: Vec<SensitivityParameter> =
                acting.iter().map(|a| a.1.clone().expect("an engine parameter unless differenced")).collect();
            let (r, s) = simulate_any_with_sensitivities(&problem, settings, &params, &mut |_| {})
                .map_err(|e| EvalError::with_source(format!("trial {}", trial.name), e))?;
            (r, Some(s))
        };
        let n = self.free.len();
        let mut res = Vec::new();
        let mut jac: Vec<Vec<f64>> = Vec::new();
        if differenced && want_jacobian && !acting.is_empty() {
            res = self.trial_residuals_of(trial, &result);
            let run = |table: &BTreeMap<String, MaterialSpec>, settings: &Settings| -> Result<Vec<f64>, EvalError> {
                self.campaign.simulations.fetch_add(1, Ordering::Relaxed);
                let r = simulate_any(&trial.with_materials(trial.materials(table)?), settings, &mut |_| {})
                    .map_err(|e| EvalError::with_source(format!("trial {}", trial.name), e))?;
                Ok(self.trial_residuals_of(trial, &r))
            };
            // The columns from runs on `settings`, differenced against `base`.
            // The columns are independent runs: in parallel, each written to its
            // own column, so the Jacobian does not depend on the thread count.
            let columns = |settings: &Settings, base: &[f64], step: f64| -> Result<Vec<Vec<f64>>, EvalError> {
                let differences: Vec<(usize, f64, Vec<f64>)> = acting
                    .par_iter()
                    .map(|&(col, _)| {
                        let u = &self.campaign.unknowns[self.free[col]];
                        let spec = u.spec();
                        let value = table[&u.material].get(u.key).expect("a free unknown has a value");
                        let h = match spec.scale {
                            crate::lsq::Scale::Log => step * value,
                            crate::lsq::Scale::Linear => step * (spec.upper - spec.lower),
                        };
                        let h = if value + h > spec.upper { -h } else { h };
                        let mut perturbed = table.clone();
                        set_parameter(
                            perturbed.get_mut(&u.material).expect("the unknown's material"),
                            u.key,
                            value + h,
                        );
                        Ok((col, h, run(&perturbed, settings)?))
                    })
                    .collect::<Result<_, EvalError>>()?;
                let mut jac = vec![vec![0.0; n]; base.len()];
                for (col, h, plus) in differences {
                    for (row, (p, at)) in jac.iter_mut().zip(plus.iter().zip(base)) {
                        row[col] = (p - at) / h;
                    }
                }
                Ok(jac)
            };
            // Frozen steps first; a contact effect, or a replay that fails (a
            // contact step that does not settle may not be subdivided), falls back
            // to adaptive runs with the larger step.
            let contact_effect = problem.effects().active().into_iter().any(|e| e.hook() == HookPoint::Contact);
            let frozen = Settings {
                step_ends_s: Some(result.steps.iter().map(|s| s.t_s).collect()),
                fixed_dt_s: None,
                ..settings.clone()
            };
            let replayed = if contact_effect {
                Err(EvalError::new("contact effect"))
            } else {
                run(table, &frozen).and_then(|base| columns(&frozen, &base, FD_STEP))
            };
            // Only contact may fall back; any other failed replay stops the fit.
            jac = match replayed {
                Ok(jac) => jac,
                Err(_) if contact_effect || problem.has_tools() => columns(settings, &res, ADAPTIVE_FD_STEP)?,
                Err(e) => return Err(e),
            };
            return Ok((res, jac));
        }
        for &(channel, _) in &self.channels {
            let Some(sigma) = self.sigma(trial, channel) else { continue };
            match channel {
                Channel::Force => {
                    for &(t, f) in &trial.force {
                        res.push((result.bottom_force_at(t) - f) / sigma);
                        if want_jacobian {
                            let mut row = vec![0.0; n];
                            if let Some(s) = &sens {
                                let d = s.bottom_force_at(t);
                                for (k, a) in acting.iter().enumerate() {
                                    row[a.0] = d[k] / sigma;
                                }
                            }
                            jac.push(row);
                        }
                    }
                }
                c => {
                    for o in trial.markers.iter().filter(|o| o.channel == c) {
                        let sim = &result.markers[o.marker].samples[o.sample].1;
                        for (k, (&x_sim, &x_meas)) in sim.iter().zip(&o.position).enumerate() {
                            res.push((x_sim - x_meas) / sigma);
                            if want_jacobian {
                                let mut row = vec![0.0; n];
                                if let Some(s) = &sens {
                                    for (q, a) in acting.iter().enumerate() {
                                        row[a.0] = s.markers[o.marker][o.sample][q][k] / sigma;
                                    }
                                }
                                jac.push(row);
                            }
                        }
                    }
                }
            }
        }
        Ok((res, jac))
    }
}

impl Objective<'_> {
    /// The residuals of one trial for a run (those of [`Self::trial_residuals`]).
    fn trial_residuals_of(&self, trial: &Trial, result: &PressResult) -> Vec<f64> {
        let mut res = Vec::new();
        for &(channel, _) in &self.channels {
            let Some(sigma) = self.sigma(trial, channel) else { continue };
            match channel {
                Channel::Force => {
                    res.extend(trial.force.iter().map(|&(t, f)| (result.bottom_force_at(t) - f) / sigma));
                }
                c => {
                    for o in trial.markers.iter().filter(|o| o.channel == c) {
                        let sim = &result.markers[o.marker].samples[o.sample].1;
                        res.extend(sim.iter().zip(&o.position).map(|(x_sim, x_meas)| (x_sim - x_meas) / sigma));
                    }
                }
            }
        }
        res
    }
}

impl LeastSquares for Objective<'_> {
    fn num_parameters(&self) -> usize {
        self.free.len()
    }

    fn evaluate(&self, x: &[f64], want_jacobian: bool) -> Result<Evaluation, EvalError> {
        let table = self.campaign.table_with(&self.full(x));
        let parts: Vec<(Vec<f64>, Vec<Vec<f64>>)> = self
            .campaign
            .trials
            .par_iter()
            .map(|t| self.trial_residuals(t, &table, want_jacobian))
            .collect::<Result<_, _>>()?;
        let residuals: Vec<f64> = parts.iter().flat_map(|p| p.0.iter().copied()).collect();
        let jacobian = want_jacobian.then(|| {
            let rows: Vec<&Vec<f64>> = parts.iter().flat_map(|p| p.1.iter()).collect();
            DMatrix::from_fn(rows.len(), self.free.len(), |i, j| rows[i][j])
        });
        Ok(Evaluation { residuals, jacobian })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wagashi_io::bundle::Model;

    fn three(e1: Option<f64>, damage: Option<(f64, f64)>) -> MaterialSpec {
        let mut s = MaterialSpec::new(Model::ThreeElement);
        s.e1_mpa = e1;
        s.poisson = Some(0.3);
        if let Some((d, c)) = damage {
            s.mullins_d_inf = Some(d);
            s.mullins_strain_c = Some(c);
        }
        s
    }

    #[test]
    fn merged_specs_take_the_union_of_the_given_keys_whatever_the_order() {
        let a = three(Some(0.03), None);
        let b = three(None, Some((0.4, 0.05)));
        let (mut ab, mut ba) = (a.clone(), b.clone());
        merge_spec(&mut ab, &b).unwrap();
        merge_spec(&mut ba, &a).unwrap();
        assert_eq!(ab, ba);
        assert_eq!(ab.e1_mpa, Some(0.03));
        assert_eq!((ab.mullins_d_inf, ab.mullins_strain_c), (Some(0.4), Some(0.05)));
    }

    #[test]
    fn merged_specs_refuse_a_key_given_twice_with_different_values() {
        let mut a = three(Some(0.03), Some((0.4, 0.05)));
        let before = a.clone();
        assert_eq!(merge_spec(&mut a, &three(Some(0.03), Some((0.5, 0.05)))), Err(("mullins_d_inf", 0.4, 0.5)));
        assert_eq!(merge_spec(&mut a, &three(Some(0.04), None)), Err(("E1_MPa", 0.03, 0.04)));
        assert_eq!(a, before, "unchanged on error");
        // The same values agree.
        merge_spec(&mut a, &before.clone()).unwrap();
        assert_eq!(a, before);
    }

    #[test]
    fn a_campaign_names_the_trial_whose_fixed_parameter_disagrees() {
        let toml = |poisson: f64| {
            format!(
                "format = \"wagashi-experiment/1\"\nname = \"t\"\ndimension = 2\n\n[specimen]\nshape = \"block\"\n\
                 size_mm = [20.0, 15.0, 10.0]\nmaterial = \"gel\"\n\n[materials.gel]\nmodel = \"elastic\"\n\
                 poisson = {poisson}\n\n[protocol]\ntool = \"plate\"\ntool_contact = \"glued\"\nsupport = \"glued\"\nwaypoints = [[0.0, 0.0], [10.0, 1.0]]\nrelease_s = 10.0\n\
                 end_s = 20.0\n"
            )
        };
        let none = BTreeMap::new();
        let a = wagashi_io::read_bundle_from_str("first", &toml(0.3), &none).unwrap();
        let b = wagashi_io::read_bundle_from_str("second", &toml(0.4), &none).unwrap();
        let Err(CampaignError::Invalid(message)) = Campaign::new(&[a.clone(), b], &none, Some(5.0), false) else {
            panic!("conflicting poisson accepted");
        };
        assert!(message.contains("second/experiment.toml") && message.contains("poisson = 0.4"), "{message}");
        assert!(Campaign::new(&[a.clone(), a], &none, Some(5.0), false).is_ok());
    }
}
