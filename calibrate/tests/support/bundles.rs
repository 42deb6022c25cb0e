//! In-memory bundles and blind campaigns made by the independent generator
//! ([`super::generator`]): what a diagnosis is given, with a truth it did not
//! make.
//!
//! A trial is a frictionless block (3D, or plane strain in 2D) between a
//! frictionless plate and a frictionless floor, [`PRE_CONTACT_S`] of no
//! contact, then its plate protocol. The bundle states the diagnoser's
//! baseline material (a `[materials.gel]` table), the nominal specimen and the
//! protocol; its data come from the truth material:
//!
//! - force at [`FORCE_RATE_HZ`] over the whole trial, with AR(1) noise
//!   (`e_i = rho e_(i-1) + sigma sqrt(1 - rho^2) N(0, 1)`, stationary from the
//!   first sample) and an optional constant offset (the load-path effect
//!   `force-offset`, added to the generator's force);
//! - markers on the front face (`z = T`; in 2D the side and top, as blind.rs
//!   places them), in the specimen's frame (the block expands about its
//!   centre), at `t = 0`, eight times in the last hold before the release and
//!   ten times in the recovery, each coordinate with Gaussian noise of
//!   `marker_sigma_mm` (the `t = 0` row too: the diagnoser starts every track
//!   at the measured position).
//!
//! Both may be rounded to the instrument's resolution (blind.rs's 1 mN and
//! 0.01 mm), [`Noise`].
//!
//! Random draws come from the crate's [`calibrate::rng::SplitMix64`], one stream
//! per trial from the campaign's seed, so a campaign is fixed by its seed.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use calibrate::rng::SplitMix64;
use wagashi_io::{read_bundle_from_str, Bundle, ForceSample, ForceSeries, MarkerSample, MarkerSeries};

use super::generator::{self, GeneratorError, Material, PlateMode, Protocol, Specimen};

/// No contact before the plate starts [s] (the noise model's segment).
pub const PRE_CONTACT_S: f64 = 2.0;
/// Force sampling rate [Hz].
pub const FORCE_RATE_HZ: f64 = 10.0;
/// Recovery recorded after the release [s].
pub const RECOVERY_S: f64 = 20.0;
/// The generator's base step [s] (extrapolated, module docs of the generator).
pub const GENERATOR_DT_S: f64 = 5e-3;

/// The measurement noise of a trial.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Force noise standard deviation [N].
    pub force_sigma_n: f64,
    /// Lag-1 correlation of the force noise.
    pub force_rho: f64,
    /// Marker noise standard deviation per coordinate [mm].
    pub marker_sigma_mm: f64,
    /// Force resolution [N]: samples are rounded to it (0: not rounded).
    pub force_quantum_n: f64,
    /// Marker resolution [mm] (0: not rounded).
    pub marker_quantum_mm: f64,
}

/// `x` rounded to a multiple of `q` (unchanged for `q = 0`).
fn quantise(x: f64, q: f64) -> f64 {
    if q > 0.0 {
        (x / q).round() * q
    } else {
        x
    }
}

/// One trial's plate protocol, from first touch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Design {
    /// Nominal strain of the push (depth over height).
    pub strain: f64,
    /// Push duration [s].
    pub push_s: f64,
    /// Hold at depth [s].
    pub hold_s: f64,
    /// A second stroke: the plate rises to its first touch in `push_s`, then
    /// pushes again to the depth in `push_s` and holds `hold_s` (a double
    /// compression whose plate leaves the specimen).
    pub double: bool,
}

impl Design {
    /// The plate protocol for a block of height `height_mm`, with the pre-contact
    /// segment, released after the last hold and recorded [`RECOVERY_S`] more.
    pub fn protocol(&self, height_mm: f64) -> Protocol {
        let depth = self.strain * height_mm;
        let mut t = PRE_CONTACT_S;
        let mut w = vec![[0.0, 0.0], [t, 0.0]];
        let strokes = if self.double { 2 } else { 1 };
        for k in 0..strokes {
            if k > 0 {
                t += self.push_s;
                w.push([t, 0.0]);
            }
            t += self.push_s;
            w.push([t, depth]);
            t += self.hold_s;
            w.push([t, depth]);
        }
        let plate = if self.double { PlateMode::Contact } else { PlateMode::Held };
        let protocol = Protocol { waypoints: w, release_s: t, end_s: t + RECOVERY_S, plate };
        debug_assert_eq!(protocol.pushes_again(), self.double);
        protocol
    }
}

/// The experiment text of a trial (no `[data]`: the series are set in memory).
fn experiment_toml(name: &str, dimension: usize, specimen: &Specimen, baseline: &str, protocol: &Protocol) -> String {
    let [w, h, t] = specimen.size_mm;
    let mut waypoints = String::new();
    for (i, p) in protocol.waypoints.iter().enumerate() {
        write!(waypoints, "{}[{}, {}]", if i > 0 { ", " } else { "" }, p[0], p[1]).unwrap();
    }
    format!(
        r#"format = "wagashi-experiment/1"
name = "{name}"
dimension = {dim}

[specimen]
shape = "block"
size_mm = [{w}, {h}, {t}]
density_g_cm3 = 1.1
material = "gel"

{material}
[protocol]
tool = "plate"
tool_contact = "frictionless"
support = "frictionless"
waypoints = [{waypoints}]
release_s = {release}
end_s = {end}
"#,
        dim = dimension,
        material = baseline,
        release = protocol.release_s,
        end = protocol.end_s,
    )
}

/// Relative marker places: `(x / W, y / H)` on the front face in 3D; on the
/// free side and the top in 2D.
fn marker_places(dimension: usize) -> Vec<[f64; 2]> {
    if dimension == 3 {
        vec![[0.1, 0.25], [0.9, 0.25], [0.5, 0.5], [0.1, 0.75], [0.9, 0.75]]
    } else {
        vec![[1.0, 0.25], [1.0, 0.5], [1.0, 0.75], [0.25, 1.0], [0.5, 1.0]]
    }
}

/// Marker times: `t = 0`, eight in the last hold, ten in the recovery.
fn marker_times(protocol: &Protocol) -> Vec<f64> {
    let w = &protocol.waypoints;
    let (hold_start, release) = (w[w.len() - 2][0], protocol.release_s);
    let mut t = vec![0.0];
    t.extend((1..=8).map(|i| hold_start + (release - hold_start) * i as f64 / 8.0));
    t.extend((1..=10).map(|i| release + (protocol.end_s - release) * i as f64 / 10.0));
    t
}

/// A generated trial as an in-memory bundle named `name`: the diagnoser is
/// told `baseline` (a `[materials.gel]` table, e.g. [`Material::toml`]); the
/// data come from `truth` (module docs), plus `force_offset_n` [N] on every
/// force sample, with `noise` drawn from `seed`. The bundle's dimension is
/// the specimen's, except that a 3D specimen may be written as a 2D
/// (plane-stress) bundle with `plane_stress`: homogeneous uniaxial stress is
/// the same state, and the markers are given by their `(x, y)`.
#[allow(clippy::too_many_arguments)]
pub fn trial_bundle(
    name: &str,
    truth: &Material,
    baseline: &str,
    plane_stress: bool,
    specimen: &Specimen,
    design: &Design,
    noise: &Noise,
    force_offset_n: f64,
    seed: u64,
) -> Result<Bundle, GeneratorError> {
    if plane_stress && specimen.dimension != 3 {
        return Err(GeneratorError(format!("{name}: a plane-stress bundle needs a 3D generator specimen")));
    }
    let dimension = if plane_stress { 2 } else { specimen.dimension };
    let protocol = design.protocol(specimen.size_mm[1]);
    let num_force = (protocol.end_s * FORCE_RATE_HZ).round() as usize + 1;
    let force_times: Vec<f64> = (0..num_force).map(|i| i as f64 / FORCE_RATE_HZ).collect();
    let marker_t = marker_times(&protocol);
    let mut outputs: Vec<f64> = force_times.iter().chain(&marker_t).copied().collect();
    outputs.sort_by(f64::total_cmp);
    outputs.dedup_by(|a, b| (*a - *b).abs() <= 1e-9);
    let trace = generator::generate(truth, specimen, &protocol, &outputs, GENERATOR_DT_S)?;
    let index = |t: f64| outputs.iter().position(|&o| (o - t).abs() <= 1e-9).expect("an output time");
    let mut rng = SplitMix64::new(seed);
    let mut bundle = read_bundle_from_str(
        "/nonexistent/generated",
        &experiment_toml(name, dimension, specimen, baseline, &protocol),
        &BTreeMap::new(),
    )
    .map_err(|e| GeneratorError(format!("{name}: {e}")))?;
    let innovation = noise.force_sigma_n * (1.0 - noise.force_rho * noise.force_rho).sqrt();
    let mut e = noise.force_sigma_n * rng.next_gaussian();
    let samples = force_times
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            if i > 0 {
                e = noise.force_rho * e + innovation * rng.next_gaussian();
            }
            let force_n = quantise(trace.force_n[index(t)] + force_offset_n + e, noise.force_quantum_n);
            ForceSample { t_s: t, force_n }
        })
        .collect();
    bundle.force = Some(ForceSeries { samples });
    let [w, h, t] = specimen.size_mm;
    bundle.markers = marker_places(dimension)
        .iter()
        .enumerate()
        .map(|(m, &[fx, fy])| {
            let p: Vec<f64> = if dimension == 3 { vec![fx * w, fy * h, t] } else { vec![fx * w, fy * h] };
            let samples = marker_t
                .iter()
                .map(|&time| {
                    let q = trace.position(specimen, index(time), &p);
                    let position_mm = q
                        .iter()
                        .map(|x| quantise(x + noise.marker_sigma_mm * rng.next_gaussian(), noise.marker_quantum_mm))
                        .collect();
                    MarkerSample { t_s: time, position_mm }
                })
                .collect();
            MarkerSeries { name: format!("m{m}"), samples }
        })
        .collect();
    Ok(bundle)
}

/// A campaign: the calibration trials and the validation trials.
#[derive(Debug, Clone)]
pub struct Campaign {
    pub calibration: Vec<Bundle>,
    pub validation: Vec<Bundle>,
}

/// Six trials (calibrate on the first four, validate on the last two):
/// depths of 10 to 25 %, pushes of 4 to 16 s, holds of 5 to 20 s, two double
/// compressions (one of each set).
pub const DESIGN: [Design; 6] = [
    Design { strain: 0.10, push_s: 4.0, hold_s: 10.0, double: false },
    Design { strain: 0.20, push_s: 4.0, hold_s: 5.0, double: false },
    Design { strain: 0.20, push_s: 16.0, hold_s: 20.0, double: false },
    Design { strain: 0.15, push_s: 6.0, hold_s: 5.0, double: true },
    Design { strain: 0.25, push_s: 10.0, hold_s: 10.0, double: false },
    Design { strain: 0.15, push_s: 3.0, hold_s: 8.0, double: true },
];

/// [`DESIGN`] with single strokes only (the double compressions pushed once):
/// trials the constrained plate runs, without contact tools.
pub const SINGLE_STROKES: [Design; 6] = [
    DESIGN[0],
    DESIGN[1],
    DESIGN[2],
    Design { double: false, ..DESIGN[3] },
    DESIGN[4],
    Design { double: false, ..DESIGN[5] },
];

/// Builds the campaign of `designs` (e.g. [`DESIGN`]; the last two validate,
/// the others calibrate) on `specimen`: the diagnoser is
/// told `baseline` (as in [`trial_bundle`]), the data come from `truth` (the
/// baseline with components added or changed), with `force_offset_n` on every
/// force sample and `noise`; trial `k` draws from `SplitMix64::new(seed)`'s
/// `k`-th output.
#[allow(clippy::too_many_arguments)]
pub fn campaign(
    truth: &Material,
    baseline: &str,
    plane_stress: bool,
    specimen: &Specimen,
    designs: &[Design],
    noise: &Noise,
    force_offset_n: f64,
    seed: u64,
) -> Result<Campaign, GeneratorError> {
    let mut seeds = SplitMix64::new(seed);
    let mut bundles = Vec::new();
    for (k, design) in designs.iter().enumerate() {
        let trial_seed = seeds.next_u64();
        bundles.push(trial_bundle(
            &format!("trial{k}"),
            truth,
            baseline,
            plane_stress,
            specimen,
            design,
            noise,
            force_offset_n,
            trial_seed,
        )?);
    }
    let validation = bundles.split_off(designs.len().saturating_sub(2));
    Ok(Campaign { calibration: bundles, validation })
}
