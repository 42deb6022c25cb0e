//! The identification procedures: the seed paper's three steps, and a joint fit.
//!
//! **Seed** (the seed's Section III, Figs. 3 and 4):
//!
//! 1. Poisson's ratio of every material from the keep-shape markers (the other
//!    parameters at their start values: under displacement control the shape of a
//!    uniform specimen depends on nu alone, by the correspondence principle);
//! 2. every rheology parameter (E1, E2, c1, c2, c3 for the five-element model) from
//!    the force curve, nu fixed: the set `x_force`;
//! 3. c3 from the final-shape markers, the rest fixed: the set `x_shape`
//!    (`x_force` with its c3 replaced).
//!
//! A step whose channel has no data is skipped and says so; its parameters keep
//! their values. The seed's Fig. 4 simulation takes the force from `x_force` and
//! the shapes from `x_shape`.
//!
//! **Joint**: one set fitted to force and shapes together. The channels are
//! weighted by their noise (see [`crate::trial`]); after a first fit each
//! channel's noise scale is re-estimated from its residuals (`s_c^2 = RSS_c / n_c`)
//! and the fit is repeated from there, so that a channel the model cannot follow
//! does not drown the others by an arbitrary choice of sigma.
//!
//! Every step runs a multi-start Levenberg-Marquardt (Latin hypercube starts in the
//! log box, the current values as start 0) and reports its intervals and warnings.

use std::time::Instant;

use crate::lsq::{FitError, Options};
use crate::multistart::{multistart, MultiStartOptions};
use crate::profile::profile;
use crate::trial::{Campaign, Channel, Objective};
use crate::uncertainty::uncertainty;

/// Which procedure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Procedure {
    /// The seed's three steps and two parameter sets.
    Seed,
    /// One set fitted to all channels.
    Joint,
}

/// Settings of a procedure.
#[derive(Debug, Clone)]
pub struct ProcedureOptions {
    /// Starts per step with more than one parameter (1 = the start values only).
    pub starts: usize,
    /// Seed of the Latin hypercube.
    pub seed: u64,
    /// Levenberg-Marquardt settings.
    pub lsq: Options,
}

impl Default for ProcedureOptions {
    fn default() -> Self {
        Self { starts: 4, seed: 1, lsq: Options::default() }
    }
}

/// One estimated parameter of a set.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// `material.key`.
    pub label: String,
    /// The material.
    pub material: String,
    /// The bundle key.
    pub key: &'static str,
    /// The value, in the key's unit.
    pub value: f64,
    /// The 95 % interval, or `None` when the value was not fitted (held fixed).
    pub ci95: Option<[f64; 2]>,
    /// The step that fitted it.
    pub step: Option<String>,
}

/// One step's outcome.
#[derive(Debug, Clone)]
pub struct StepReport {
    /// The step's name (`keep-shape`, `force`, `final-shape`, `joint`).
    pub name: String,
    /// Labels of the fitted parameters.
    pub parameters: Vec<String>,
    /// Channels used.
    pub channels: Vec<Channel>,
    /// Values found.
    pub values: Vec<f64>,
    /// 95 % intervals.
    pub ci95: Vec<[f64; 2]>,
    /// Correlation matrix, row-major.
    pub correlation: Vec<Vec<f64>>,
    /// Objective at the best point (`1/2 sum r^2`).
    pub objective: f64,
    /// Residual RMS in the campaign's noise units (each channel's own sigma,
    /// whatever scales the step fitted with).
    pub rms: f64,
    /// Trial steps of the best start.
    pub iterations: usize,
    /// Evaluations over all starts.
    pub evaluations: usize,
    /// Starts run.
    pub starts: usize,
    /// Why the best start stopped.
    pub stop: String,
    /// Identifiability warnings, in words.
    pub warnings: Vec<String>,
    /// Skipped, and why.
    pub skipped: Option<String>,
    /// Profile likelihoods of nu and c3 (the seed's one-parameter steps, and the
    /// joint fit's): `(value, objective)` pairs, the profile's 95 % interval and
    /// whether the profile is flat.
    pub profiles: Vec<ProfileReport>,
    /// Wall time [s].
    pub wall_s: f64,
}

/// A profile likelihood.
#[derive(Debug, Clone)]
pub struct ProfileReport {
    /// The parameter's label.
    pub parameter: String,
    /// `(value, objective)` pairs.
    pub points: Vec<(f64, f64)>,
    /// The 95 % interval where the likelihood-ratio statistic crosses chi-square(1).
    pub ci95: [f64; 2],
    /// True when the statistic does not cross its threshold inside the bounds.
    pub flat: bool,
}

/// A procedure's outcome.
#[derive(Debug, Clone)]
pub struct FitReport {
    /// Which procedure.
    pub procedure: Procedure,
    /// Named sets of every unknown: `force` and `shape` (seed) or `joint`.
    pub sets: Vec<(String, Vec<Estimate>)>,
    /// The steps in order.
    pub steps: Vec<StepReport>,
    /// Simulations run.
    pub simulations: usize,
    /// Wall time [s].
    pub wall_s: f64,
}

impl FitReport {
    /// The values of every unknown in set `name`.
    pub fn values(&self, name: &str) -> Option<Vec<f64>> {
        self.sets.iter().find(|s| s.0 == name).map(|s| s.1.iter().map(|e| e.value).collect())
    }
}

/// Progress of a procedure: the step's name, starts done, starts in all.
pub type ProgressFn<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// Runs `procedure` on `campaign` from the campaign's current values.
pub fn run(
    campaign: &Campaign,
    procedure: Procedure,
    options: &ProcedureOptions,
    progress: ProgressFn<'_>,
) -> Result<FitReport, FitError> {
    let clock = Instant::now();
    let start = campaign.values();
    let index_of = |pred: &dyn Fn(&str) -> bool| -> Vec<usize> {
        (0..campaign.unknowns.len()).filter(|&i| pred(campaign.unknowns[i].key)).collect()
    };
    let mut steps = Vec::new();
    let sets = match procedure {
        Procedure::Seed => {
            let mut x = start.clone();
            let mut fitted_by: Vec<Option<(usize, usize)>> = vec![None; x.len()];
            let plan: [(&str, Vec<usize>, Channel); 3] = [
                ("keep-shape", index_of(&|k| k == "poisson"), Channel::Keep),
                ("force", index_of(&|k| k != "poisson"), Channel::Force),
                ("final-shape", index_of(&|k| k == "c3_MPa_s"), Channel::Final),
            ];
            let mut x_force = None;
            for (name, free, channel) in plan {
                let (report, values) = fit_step(campaign, name, &free, &x, &[channel], options, progress)?;
                if name == "final-shape" {
                    x_force.get_or_insert_with(|| x.clone());
                }
                if report.skipped.is_none() {
                    for (k, &i) in free.iter().enumerate() {
                        x[i] = values[k];
                        fitted_by[i] = Some((steps.len(), k));
                    }
                }
                steps.push(report);
                if name == "force" {
                    x_force = Some(x.clone());
                }
            }
            let x_force = x_force.expect("set after the force step");
            let mut force_by = fitted_by.clone();
            // c3's fit in step 3 belongs to the shape set only.
            for (i, by) in force_by.iter_mut().enumerate() {
                if by.is_some_and(|(s, _)| steps[s].name == "final-shape") {
                    *by = fitted_by_step(&steps, "force", &campaign.unknowns[i].label());
                }
            }
            vec![
                ("force".to_string(), estimates(campaign, &x_force, &force_by, &steps)),
                ("shape".to_string(), estimates(campaign, &x, &fitted_by, &steps)),
            ]
        }
        Procedure::Joint => {
            let all: Vec<usize> = (0..campaign.unknowns.len()).collect();
            let channels: Vec<Channel> = [Channel::Force, Channel::Keep, Channel::Final]
                .into_iter()
                .filter(|&c| campaign.trials.iter().any(|t| t.count(c) > 0))
                .collect();
            // First pass with the campaign's noise, then each channel rescaled.
            let (first, x1) = fit_step(campaign, "joint (first pass)", &all, &start, &channels, options, progress)?;
            let scales = channel_scales(campaign, &all, &x1, &channels)?;
            steps.push(first);
            let (report, x) = fit_weighted(campaign, "joint", &all, &x1, &scales, options, progress)?;
            steps.push(report);
            let by: Vec<Option<(usize, usize)>> = (0..all.len()).map(|k| Some((1, k))).collect();
            vec![("joint".to_string(), estimates(campaign, &x, &by, &steps))]
        }
    };
    Ok(FitReport { procedure, sets, steps, simulations: campaign.simulations(), wall_s: clock.elapsed().as_secs_f64() })
}

fn fitted_by_step(steps: &[StepReport], name: &str, label: &str) -> Option<(usize, usize)> {
    let s = steps.iter().position(|s| s.name == name && s.skipped.is_none())?;
    let k = steps[s].parameters.iter().position(|p| p == label)?;
    Some((s, k))
}

fn estimates(
    campaign: &Campaign,
    x: &[f64],
    fitted_by: &[Option<(usize, usize)>],
    steps: &[StepReport],
) -> Vec<Estimate> {
    campaign
        .unknowns
        .iter()
        .enumerate()
        .map(|(i, u)| Estimate {
            label: u.label(),
            material: u.material.clone(),
            key: u.key,
            value: x[i],
            ci95: fitted_by[i].map(|(s, k)| steps[s].ci95[k]),
            step: fitted_by[i].map(|(s, _)| steps[s].name.clone()),
        })
        .collect()
}

/// The noise scale of each channel from its residuals at `x`: `sqrt(RSS_c / n_c)`.
fn channel_scales(
    campaign: &Campaign,
    free: &[usize],
    x_full: &[f64],
    channels: &[Channel],
) -> Result<Vec<(Channel, f64)>, FitError> {
    use crate::lsq::LeastSquares;
    let mut scales = Vec::new();
    for &c in channels {
        let obj = Objective::new(campaign, free.to_vec(), x_full.to_vec(), &[c]);
        let xf: Vec<f64> = free.iter().map(|&i| x_full[i]).collect();
        let e = obj.evaluate(&xf, false).map_err(FitError::StartEvaluation)?;
        let n = e.residuals.len().max(1) as f64;
        let rss: f64 = e.residuals.iter().map(|r| r * r).sum();
        scales.push((c, (rss / n).sqrt().max(1e-3)));
    }
    Ok(scales)
}

fn fit_step(
    campaign: &Campaign,
    name: &str,
    free: &[usize],
    x_full: &[f64],
    channels: &[Channel],
    options: &ProcedureOptions,
    progress: ProgressFn<'_>,
) -> Result<(StepReport, Vec<f64>), FitError> {
    let scales: Vec<(Channel, f64)> = channels.iter().map(|&c| (c, 1.0)).collect();
    fit_weighted(campaign, name, free, x_full, &scales, options, progress)
}

fn fit_weighted(
    campaign: &Campaign,
    name: &str,
    free: &[usize],
    x_full: &[f64],
    channels: &[(Channel, f64)],
    options: &ProcedureOptions,
    progress: ProgressFn<'_>,
) -> Result<(StepReport, Vec<f64>), FitError> {
    let clock = Instant::now();
    let labels: Vec<String> = free.iter().map(|&i| campaign.unknowns[i].label()).collect();
    let x0: Vec<f64> = free.iter().map(|&i| x_full[i]).collect();
    let has_data: Vec<Channel> =
        channels.iter().map(|c| c.0).filter(|&c| campaign.trials.iter().any(|t| t.count(c) > 0)).collect();
    let skip = |why: String| StepReport {
        name: name.to_string(),
        parameters: labels.clone(),
        channels: channels.iter().map(|c| c.0).collect(),
        values: x0.clone(),
        ci95: x0.iter().map(|&v| [v, v]).collect(),
        correlation: Vec::new(),
        objective: 0.0,
        rms: 0.0,
        iterations: 0,
        evaluations: 0,
        starts: 0,
        stop: "skipped".into(),
        warnings: vec![why.clone()],
        skipped: Some(why),
        profiles: Vec::new(),
        wall_s: 0.0,
    };
    if free.is_empty() {
        return Ok((skip("no unknown to fit in this step".into()), x0));
    }
    if has_data.is_empty() {
        let what = channels.iter().map(|c| c.0.as_str()).collect::<Vec<_>>().join(", ");
        return Ok((skip(format!("no {what} data: {} kept at the start values", labels.join(", "))), x0));
    }
    let mut objective = Objective::new(campaign, free.to_vec(), x_full.to_vec(), &has_data);
    objective.channels = channels.iter().copied().filter(|c| has_data.contains(&c.0)).collect();
    let specs = objective.specs();
    let starts = if free.len() > 1 { options.starts.max(1) } else { 1 };
    // A finite-difference Jacobian costs a run per column: only at accepted points.
    let lsq = Options {
        jacobian_with_trial: options.lsq.jacobian_with_trial && !campaign.differenced(),
        ..options.lsq.clone()
    };
    let ms_options = MultiStartOptions { num_starts: starts - 1, seed: options.seed, fit: lsq.clone() };
    let step_progress = |done: usize, total: usize| progress(name, done, total);
    let result = multistart(&objective, &specs, &x0, &ms_options, Some(&step_progress))?;
    let best = result.best();
    let m = best.residuals.len().max(1) as f64;
    let (ci95, correlation, mut warnings) = match uncertainty(&specs, best) {
        Ok(u) => (
            u.intervals.iter().map(|i| [i.lower, i.upper]).collect(),
            (0..u.correlation.nrows()).map(|i| u.correlation.row(i).iter().copied().collect()).collect(),
            u.warnings.iter().map(|w| w.to_string()).collect::<Vec<_>>(),
        ),
        Err(e) => {
            (best.x.iter().map(|_| [f64::NAN, f64::NAN]).collect(), Vec::new(), vec![format!("no interval: {e}")])
        }
    };
    // Profile likelihoods of nu and c3 (the two): in the seed's
    // one-parameter steps they cost a few simulations; in a joint fit each point
    // re-fits the other parameters.
    let mut profiles = Vec::new();
    let wanted = (0..free.len()).filter(|&k| {
        free.len() == 1 || (name == "joint" && matches!(campaign.unknowns[free[k]].key, "poisson" | "c3_MPa_s"))
    });
    for k in wanted.collect::<Vec<_>>() {
        match profile(&objective, &specs, best, k, 4, &lsq) {
            Ok(p) => {
                warnings.extend(p.warnings().iter().map(|w| w.to_string()));
                let (lo, hi) = p.interval();
                profiles.push(ProfileReport {
                    parameter: labels[k].clone(),
                    points: p.pairs(),
                    ci95: [lo, hi],
                    flat: p.is_flat(),
                });
            }
            Err(e) => warnings.push(format!("no profile for {}: {e}", labels[k])),
        }
    }
    let evaluations = result.fits().map(|f| f.evaluations).sum::<usize>();
    // The RMS in the campaign's own noise units: a step whose channels are
    // rescaled (the joint fit's second pass) would otherwise report about 1 by
    // construction. One more evaluation at the best point.
    let rms = if objective.channels.iter().all(|c| c.1 == 1.0) {
        (2.0 * best.objective / m).sqrt()
    } else {
        use crate::lsq::LeastSquares;
        let unscaled = Objective::new(campaign, free.to_vec(), x_full.to_vec(), &has_data);
        let e = unscaled.evaluate(&best.x, false).map_err(FitError::StartEvaluation)?;
        (e.residuals.iter().map(|r| r * r).sum::<f64>() / e.residuals.len().max(1) as f64).sqrt()
    };
    let report = StepReport {
        name: name.to_string(),
        parameters: labels,
        channels: objective.channels.iter().map(|c| c.0).collect(),
        values: best.x.clone(),
        ci95,
        correlation,
        objective: best.objective,
        rms,
        iterations: best.iterations,
        evaluations,
        starts,
        stop: best.stop.to_string(),
        warnings,
        skipped: None,
        profiles,
        wall_s: clock.elapsed().as_secs_f64(),
    };
    let mut report = report;
    canonical_order(campaign, free, &mut report);
    let values = report.values.clone();
    Ok((report, values))
}

/// The five-element chain is symmetric under the exchange of its two Voigt
/// elements `(E1, c1) <-> (E2, c2)`: both labellings give the same relaxation
/// function, so a fit may land on either. The reported labelling is the seed's
/// Table II one, the faster element first (`c1/E1 <= c2/E2`); values, intervals and
/// correlations are permuted together (exact, by the symmetry).
fn canonical_order(campaign: &Campaign, free: &[usize], report: &mut StepReport) {
    let position = |material: &str, key: &str| {
        free.iter().position(|&i| campaign.unknowns[i].material == material && campaign.unknowns[i].key == key)
    };
    for (name, spec) in &campaign.materials {
        if spec.model != wagashi_io::bundle::Model::FiveElement {
            continue;
        }
        let keys = ["E1_MPa", "c1_MPa_s", "E2_MPa", "c2_MPa_s"];
        let Some([e1, c1, e2, c2]) =
            keys.map(|k| position(name, k)).into_iter().collect::<Option<Vec<_>>>().map(|v| [v[0], v[1], v[2], v[3]])
        else {
            continue;
        };
        let v = &report.values;
        if v[c1] / v[e1] <= v[c2] / v[e2] {
            continue;
        }
        let mut perm: Vec<usize> = (0..report.values.len()).collect();
        perm.swap(e1, e2);
        perm.swap(c1, c2);
        report.values = perm.iter().map(|&k| report.values[k]).collect();
        report.ci95 = perm.iter().map(|&k| report.ci95[k]).collect();
        if !report.correlation.is_empty() {
            let c = &report.correlation;
            report.correlation = perm.iter().map(|&a| perm.iter().map(|&b| c[a][b]).collect()).collect();
        }
        report.warnings.push(format!(
            "{name}: the two Voigt elements were found in the other order and are reported faster first (c1/E1 <= c2/E2); the chain is symmetric in them"
        ));
    }
}
