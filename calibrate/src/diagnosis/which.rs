//! Step 3, WHICH, for one candidate: the score test at the baseline fit and the
//! refit (diagnosis-details.md §5.4).
//!
//! **Score.** The effect's residual derivative `J_phi` at the baseline is a
//! secant from the null to the coordinate's reference value ([`Coord::reference`]:
//! the registry's, or for a stress-valued parameter a fraction of the
//! campaign's peak nominal stress, `Candidate::at_stress`) for a one-sided
//! (boundary) parameter, and a small forward difference otherwise, both on the
//! baseline's frozen discretisation. `J~ = (I - P_theta) J_phi` with `P_theta`
//! the projector on the baseline Jacobian's columns, `s = J~^T r`,
//! `LM = s^T (J~^T J~)^-1 s`, `EPC = -(J~^T J~)^-1 s` (the expected parameter
//! change). Where a trial does not support the effect at the reference (its
//! runs fail there: `finite-strain`'s full Green-Lagrange kinematics past their
//! compressive limit, [`effect_columns`]), the secant goes to the first of a
//! half, a quarter or an eighth of the reference whose runs complete.
//! **One-sided rule**: a one-sided coordinate whose EPC points out of
//! its feasible side is held at its null and the statistic recomputed without
//! it (with none left, `LM = 0`); the p-value is the chi-bar-square tail with
//! the remaining one-sided count.
//!
//! **Refit.** `(theta, u)` by Levenberg-Marquardt from `(theta0, clip(EPC))`
//! (clipped to the bounds and to the registry's plausible range widened to
//! hold the reference), and for
//! non-smooth effects (contact, thresholds) also from `{0.3, 1, 3}` times the
//! reference (in the coordinate: for the slider's `u = 1/sigma_y` with its
//! reference `0.5 sigma_peak`, yield stresses of 1.7, 0.5 and 0.17
//! `sigma_peak`), for other boundary nulls also from the reference; the best start
//! is kept. The extra starts of non-smooth effects are screens of at most 15
//! iterations. The extension is nested, so a refit
//! that ends above the baseline's objective falls back to the null (`LR = 0`).

use fem_core::effects::HookPoint;

use super::library::CandidateId;
use nalgebra::{DMatrix, DVector};

use super::heldout::range_basis;
use super::model::{Candidate, Coord, Fitting, Model};
use super::stats::chibar2_sf;
use crate::lsq::{levenberg_marquardt, Fit, Options};

/// The score test of one candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct Score {
    /// The LM statistic (after the one-sided rule).
    pub statistic: f64,
    /// Its p-value (chi-bar-square).
    pub p_value: f64,
    /// The expected parameter change per coordinate (before the one-sided rule).
    pub epc: Vec<f64>,
    /// Coordinates held at the null by the one-sided rule.
    pub held: Vec<bool>,
    /// The projected columns `J~` (one per coordinate), for the numerical-error check.
    pub projected: Vec<Vec<f64>>,
}

/// Whether `effect`'s null is non-smooth (threshold or contact), so that its
/// refit is multi-started.
pub fn non_smooth(effect: CandidateId) -> bool {
    match effect.hook() {
        HookPoint::Contact => true,
        HookPoint::MaterialPoint => effect.params().iter().any(|p| !p.nuisance && p.one_sided),
        _ => false,
    }
}

/// How many times the score's step is halved when the runs at the full step
/// fail ([`effect_columns`]): down to 1/8 of the reference.
pub const SECANT_HALVINGS: usize = 3;

/// The effect's residual-derivative columns at the baseline `theta` (module
/// docs), with `r_frozen` the null run on the frozen `steps`. When a replayed
/// run fails (a contact that does not settle on a step it may not subdivide),
/// the columns come from adaptive runs against the adaptive null `r_adaptive`.
///
/// When both fail at the full step, the trial does not support the effect at
/// its reference: the step is halved, at most [`SECANT_HALVINGS`] times, and the
/// columns are the secant to the first fraction whose runs complete (the
/// first error is returned when none does). The case that needs it:
/// `finite-strain` at its reference, full Green-Lagrange kinematics (Saint
/// Venant-Kirchhoff): its nominal stress in uniaxial compression peaks at the
/// stretch `1 - 0.423/b` and falls beyond, so a cylinder pushed to 50 %
/// between glued plates localises the compression into a few cells, which
/// invert (the real fungi-steak first strokes: an element inverts at 46 %;
/// the finer the mesh, the earlier); at `b = 1/2` the limit lies at 85 % and
/// the runs complete. An effect whose runs complete at the full step gets the
/// columns it always had, bit for bit.
pub fn effect_columns(
    model: &Model,
    theta: &[f64],
    candidate: &Candidate,
    steps: &[Vec<f64>],
    r_frozen: &[f64],
    r_adaptive: &[f64],
) -> Result<Vec<Vec<f64>>, crate::lsq::EvalError> {
    let mut first_error = None;
    for halvings in 0..=SECANT_HALVINGS {
        let fraction = 0.5f64.powi(halvings as i32);
        let columns = match columns_on(model, theta, candidate, Some(steps), r_frozen, fraction) {
            Ok(c) => Ok(c),
            Err(_) => columns_on(model, theta, candidate, None, r_adaptive, fraction),
        };
        match columns {
            Ok(c) => return Ok(c),
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
    }
    Err(first_error.expect("at least one attempt"))
}

/// The columns with steps `fraction` of the usual ones (module docs).
fn columns_on(
    model: &Model,
    theta: &[f64],
    candidate: &Candidate,
    steps: Option<&[Vec<f64>]>,
    r0: &[f64],
    fraction: f64,
) -> Result<Vec<Vec<f64>>, crate::lsq::EvalError> {
    let mut columns = Vec::new();
    for (j, coord) in candidate.coords.iter().enumerate() {
        let mut u = candidate.null();
        let h = fraction
            * if coord.one_sided() {
                coord.reference() - coord.null()
            } else {
                1e-3 * (coord.reference() - coord.null())
            };
        u[j] += h;
        let v = candidate.values(&u);
        let (r1, _) = model.residuals(theta, Some((candidate.effect, &v)), steps)?;
        columns.push(r1.iter().zip(r0).map(|(a, b)| (a - b) / h).collect());
    }
    Ok(columns)
}

/// The score test of `candidate` with effect columns `columns` at the baseline
/// residuals `r` and Jacobian `j_theta`.
pub fn score(candidate: &Candidate, columns: &[Vec<f64>], r: &[f64], j_theta: &DMatrix<f64>) -> Score {
    let q = range_basis(j_theta);
    let n = r.len();
    let r = DVector::from_column_slice(r);
    let projected: Vec<DVector<f64>> = columns
        .iter()
        .map(|c| {
            let v = DVector::from_column_slice(c);
            if q.ncols() == 0 {
                v
            } else {
                &v - &q * (q.transpose() * &v)
            }
        })
        .collect();
    let lm = |active: &[usize]| -> (f64, Vec<f64>) {
        if active.is_empty() {
            return (0.0, Vec::new());
        }
        let jt = DMatrix::from_fn(n, active.len(), |i, c| projected[active[c]][i]);
        let s = jt.transpose() * &r;
        let m = jt.transpose() * &jt;
        let x = pseudo_inverse_solve(&m, &s);
        (s.dot(&x), x.iter().map(|v| -v).collect())
    };
    let all: Vec<usize> = (0..candidate.dim()).collect();
    let (_, epc) = lm(&all);
    let mut statistic;
    let mut active = all.clone();
    let mut held = vec![false; candidate.dim()];
    // The one-sided rule, dropping infeasible coordinates until the rest point inward.
    loop {
        let (stat, e) = lm(&active);
        statistic = stat;
        let infeasible: Vec<usize> = active
            .iter()
            .zip(&e)
            .filter(|(&c, &x)| {
                let coord = &candidate.coords[c];
                let [lo, hi] = coord.bounds();
                coord.one_sided() && ((coord.null() == lo && x <= 0.0) || (coord.null() == hi && x >= 0.0))
            })
            .map(|(&c, _)| c)
            .collect();
        if infeasible.is_empty() {
            break;
        }
        for c in infeasible {
            held[c] = true;
        }
        active.retain(|c| !held[*c]);
        if active.is_empty() {
            statistic = 0.0;
            break;
        }
    }
    let one_sided = active.iter().filter(|&&c| candidate.coords[c].one_sided()).count();
    let p_value = if active.is_empty() { 1.0 } else { chibar2_sf(statistic, active.len(), one_sided) };
    Score { statistic, p_value, epc, held, projected: projected.iter().map(|v| v.iter().copied().collect()).collect() }
}

/// `m^+ s` for a symmetric positive semi-definite `m`.
fn pseudo_inverse_solve(m: &DMatrix<f64>, s: &DVector<f64>) -> DVector<f64> {
    let eig = m.clone().symmetric_eigen();
    let lmax = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut x = DVector::zeros(m.ncols());
    for (i, &l) in eig.eigenvalues.iter().enumerate() {
        if l > 1e-12 * lmax && lmax > 0.0 {
            let v = eig.eigenvectors.column(i);
            x += v * (v.dot(s) / l);
        }
    }
    x
}

/// The refit's outcome.
#[derive(Debug, Clone)]
pub struct Refit {
    /// The best fit over the starts (`None` when every start failed or ended above the baseline).
    pub fit: Option<Fit>,
    /// Starts tried.
    pub starts: usize,
    /// Errors of failed starts, in words.
    pub errors: Vec<String>,
}

/// The refit of `(theta, u)` (module docs) from the baseline `theta0` and the score's EPC.
pub fn refit(
    model: &Model,
    candidate: &Candidate,
    theta0: &[f64],
    epc: &[f64],
    baseline_objective: f64,
    options: &Options,
) -> Refit {
    let problem = Fitting { model, candidate: Some(candidate) };
    let specs = problem.specs();
    let start_of = |u: Vec<f64>| -> Vec<f64> {
        let mut x = theta0.to_vec();
        for (c, ui) in candidate.coords.iter().zip(u) {
            let [lo, hi] = c.bounds();
            let mut v = ui.clamp(lo, hi);
            // Off a one-sided null, inside the box, so that the effect acts.
            if c.one_sided() && v == c.null() {
                v = c.null() + 1e-3 * (c.reference() - c.null());
            }
            x.push(v);
        }
        x
    };
    // The EPC extrapolates a secant or a derivative at the null: clipped to the
    // bounds and to the plausible range (with the null) before it is a start.
    let epc_start: Vec<f64> = candidate
        .coords
        .iter()
        .zip(epc)
        .map(|(c, &e)| {
            let u = if e.is_finite() { c.null() + e } else { c.null() };
            if c.inverse {
                return u;
            }
            // A stress-scaled reference may lie outside the registry's range for
            // foods (a material far softer than its 1 kPa low end): widened to it.
            let [p_lo, p_hi] = c.spec.plausible;
            let (lo, hi) = (p_lo.min(c.null()).min(c.reference()), p_hi.max(c.null()).max(c.reference()));
            u.clamp(lo, hi)
        })
        .collect();
    let mut starts = vec![start_of(epc_start.clone())];
    if non_smooth(candidate.effect) {
        for f in [0.3, 1.0, 3.0] {
            starts.push(start_of(candidate.coords.iter().map(|c| c.null() + f * (c.reference() - c.null())).collect()));
        }
    } else if candidate.coords.iter().any(|c| c.one_sided()) {
        // A boundary null: the reference as a second start, unless the EPC is near it.
        let reference: Vec<f64> = candidate.coords.iter().map(Coord::reference).collect();
        let near = candidate.coords.iter().zip(&epc_start).zip(&reference).all(|((c, &a), &b)| {
            let s = (c.reference() - c.null()).abs();
            (a - b).abs() <= s
        });
        if !near {
            starts.push(start_of(reference));
        }
    }
    let mut best: Option<Fit> = None;
    let mut errors = Vec::new();
    let n = starts.len();
    // Finite-difference Jacobians cost a run per column: only at accepted points.
    let mut first = options.clone();
    if !candidate.effect.has_sensitivities() {
        first.jacobian_with_trial = false;
    }
    // The extra starts of a non-smooth effect are a screen: fewer iterations.
    let extra = Options { max_iterations: first.max_iterations.min(15), ..first.clone() };
    for (i, x0) in starts.into_iter().enumerate() {
        let r = levenberg_marquardt(&problem, &specs, &x0, if i == 0 { &first } else { &extra });
        match r {
            Ok(fit) => {
                if best.as_ref().is_none_or(|b| fit.objective < b.objective) {
                    best = Some(fit);
                }
            }
            Err(e) => errors.push(e.to_string()),
        }
    }
    let fit = best.filter(|f| f.objective <= baseline_objective);
    Refit { fit, starts: n, errors }
}

/// The refit of `extended` (a strength fit's candidate with its nuisance
/// parameters freed, [`Candidate::with_nuisance`]) from the strength fit `x`
/// (the nuisance coordinates at their registry defaults): `Some` when it ends
/// below `objective`.
pub fn refine_nuisance(
    model: &Model,
    extended: &Candidate,
    x: &[f64],
    objective: f64,
    options: &Options,
) -> Result<Option<Fit>, String> {
    let problem = Fitting { model, candidate: Some(extended) };
    let specs = problem.specs();
    let mut x0 = x.to_vec();
    let defaults = &extended.defaults;
    x0.extend(extended.coords.iter().filter(|c| c.spec.nuisance).map(|c| defaults[c.index]));
    let mut first = options.clone();
    if !extended.effect.has_sensitivities() {
        first.jacobian_with_trial = false;
    }
    let fit = levenberg_marquardt(&problem, &specs, &x0, &first).map_err(|e| e.to_string())?;
    Ok((fit.objective < objective).then_some(fit))
}

/// `(J~^T e)^T (J~^T J~)^+ (J~^T e)`: the part of `e` a candidate's projected
/// columns can absorb (the numerical-error check `LM_num`).
pub fn absorbed(projected: &[Vec<f64>], e: &[f64]) -> f64 {
    if projected.is_empty() {
        return 0.0;
    }
    let n = e.len();
    let jt = DMatrix::from_fn(n, projected.len(), |i, c| projected[c][i]);
    let e = DVector::from_column_slice(e);
    let s = jt.transpose() * &e;
    let m = jt.transpose() * &jt;
    s.dot(&pseudo_inverse_solve(&m, &s))
}
