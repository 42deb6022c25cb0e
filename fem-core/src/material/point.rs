//! Inelastic series strains at a material point: the local update of the
//! material-point effects (`plastic-slider`, `bingham-dashpot`,
//! `stress-thinning`, `dual-viscosity`, `strain-stiffening`; see
//! [`crate::effects`] for the design).
//!
//! ## Formulation
//!
//! The linear chain acts on the *unit-Young stress image* `tau = C1^-1 s` (the
//! stress is `s = C1 tau`, [`crate::element::unit_young_matrix`]): through the
//! Lamé split every element of the chain deforms along `C1^-1 s`, so the chain is
//! one scalar relaxation function applied to `tau` component by component. An
//! effect adds an inelastic strain `e_in` in series with the linear chain, so the
//! chain sees the strain `e - e_in` and the step's stress image is
//!
//! ```text
//! tau1 = g (e1 - e_in1) - q = tau_trial - g (e_in1 - e_in0),   tau_trial = g (e1 - e_in0) - q
//! ```
//!
//! with the stepper's step factor `g` and history part `q`. The inelastic flow
//! keeps the Lamé split's shape too: it is directed along `tau` (for the slider,
//! along `tau - H e_p`), and its size is governed by the *equivalent stress*
//! `|tau|_C = sqrt(tau . C1 tau) = sqrt(s . C1^-1 s)`, the square root of twice the
//! unit-Young elastic energy density of the stress (Beltrami's measure). In
//! uniaxial stress `s = sigma e_y` it is `|sigma|` exactly, so the 1D laws of
//! diagnosis-details.md §4.2 hold as written in homogeneous compression, in every
//! formulation (plane stress and strain, axisymmetric, solid: `C1` is the
//! formulation's, so the energy is the 3D one). The flow `tau / |tau|_C` is the
//! normal to `|tau|_C = const` in stress space (`d|tau|_C / ds = C1^-1 s / |tau|_C`),
//! so the flow is associative and the consistent tangent `C1 T` is symmetric: the
//! step matrix stays a Cholesky candidate. For `nu -> 0.5` the measure tends to
//! von Mises' and the flow to an isochoric one; at the seed's `nu` the flow has
//! the chain's own Poisson ratio (as the baseline's dashpot `c3` has).
//!
//! Strain stiffening (E5) is the exception to the stress-driven laws: its
//! inelastic strain `e_in = -(a |e1|_C / 2) e1` is a function of the total strain
//! `e1` alone (the chain then acts on `psi(e1) = e1 - e_in`, Fung's quasi-linear
//! form), so its update needs `e1` and no iteration of its own.
//!
//! Mullins-type damage ([`InelasticLaw::Damage`], a material's law, not an effect
//! of the diagnosis; [`super::MullinsDamage`]) is strain-driven too: the chain
//! acts on `(1 - d(alpha1)) e1`, i.e. `e_in = d(alpha1) e1`, with the cell's
//! history `alpha1 = max(alpha0, |e1|_C)`, the largest equivalent strain at the
//! step ends so far. That is the exact largest value over the step too: the
//! strain is linear in time inside a step and `|e|_C` is convex along a line, so
//! its maximum over the step lies at an end.
//!
//! Every other update is *radial*: the new stress image is a positive multiple of the
//! trial (relative to the back stress for the slider), which turns each law into
//! one scalar equation, solved in closed form (slider, Bingham, dual) or by a
//! safeguarded Newton iteration (Cross).
//!
//! The dashpot laws are corrections of the chain's own dashpot `c3`: with the flow
//! `psi tau / c3` of the modified dashpot, the inelastic strain carries the
//! difference `(psi - 1) tau / c3` (backward Euler over the step for thinning and
//! the dual viscosity), so the linear chain (whose kernel integrates `c3` exactly
//! for a strain linear in time) is never rebuilt. At the nulls the correction is
//! exactly zero.
//!
//! *Bingham's correction on the step's mean stress.* Bingham's correction takes
//! back `min(1, sigma_B/|tau|_C) tau/c3`, all of the chain's dashpot flow below
//! the threshold. Evaluated at the step's end (backward Euler) it is
//! `tau1 = tau_trial/(1 - k)`, `k = g dt/c3`, whose `k` tends to 1 as the step
//! outgrows the chain's fastest relaxation time: with a small `c3` (1.35e-5 MPa s
//! in a refit of the fungi-steak diagnosis, relaxation time 3.3e-4 s) every step
//! had to stay under about 7e-4 s (270,000 steps a 40 s trial), and even there the
//! end-point rule missed the blocked chain's stress by 5 to 12 % of the peak
//! (backward Euler's error `dt tau'/(2 c3)` in a correction whose stiffness is
//! `E/c3`). It is evaluated instead on the chain's *mean* stress over the step,
//! the one the chain's own dashpot flows with: for the chain's strain linear in
//! time (what the stepper integrates), the dashpot's flow over the step is exactly
//! `(1/c3) int tau dt = dt tau_mean/c3`, with `tau_mean = g_m (e1 - e_in1) - q_m`
//! ([`crate::material::RelaxationKernel::mean_factor`]). So
//!
//! ```text
//! e_in1 - e_in0 = -(dt/c3) min(1, sigma_B/|tau_mean|_C) tau_mean,
//! tau_mean = tau_mean_trial - g_m (e_in1 - e_in0),   tau_mean_trial = g_m (e1 - e_in0) - q_m
//! ```
//!
//! the end-point algebra with `(tau_mean_trial, g_m)` for `(tau_trial, g)`, and
//! `tau1 = tau_trial - g (e_in1 - e_in0)`. Below the threshold the chain's net
//! dashpot flow over the step is then exactly zero, and `k_m = g_m dt/c3 < 1` at
//! every step (`g_m dt = int_0^dt (1 - u/dt) G(u) du` and `int_0^inf G = c3`): no
//! step is too long.
//! The tangent `d tau1/d tau_trial` is the end-point rule's at `(tau_mean_trial,
//! k_m)` (`d e1` moves `tau_trial` by `g de1` and `tau_mean_trial` by `g_m de1`), so
//! `C1 T` stays symmetric. Measured on the 1D chain of that refit against its
//! blocked chain (RK4): 1e-4 to 9e-4 of the peak at 0.1 s steps, 2e-3 to 4e-3 at
//! 0.5 s (first order: the chain's strain is linear inside a step, so its end
//! stress lags the blocked chain's by about half a step); on a chain with a large
//! `c3` (30 MPa s) 3e-5 to 2e-4 at 0.5 s, as backward Euler's or better
//! (`fem-core/tests/material_point.rs`).

use nalgebra::{SMatrix, SVector};

/// An inelastic strain law in series with a region's chain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InelasticLaw {
    /// E1: a slider with uniaxial yield stress `sigma_y` [MPa] (`inf`: never yields)
    /// and linear kinematic hardening `H` [MPa]: `|tau - H e_p|_C <= sigma_y`.
    Slider { yield_mpa: f64, hardening_mpa: f64 },
    /// E2: the dashpot `c3` [MPa s] flows at `<|tau|_C - sigma_B> / |tau|_C tau / c3`.
    Bingham { threshold_mpa: f64, c3_mpa_s: f64 },
    /// E3: the dashpot's viscosity is `c3 / (1 + (|tau|_C / sigma_c)^m)` (Cross).
    Thinning { inverse_stress_per_mpa: f64, exponent: f64, c3_mpa_s: f64 },
    /// E4: the dashpot's viscosity is `c3` while loading, `c3 exp(psi)` while unloading.
    Dual { log_ratio: f64, c3_mpa_s: f64 },
    /// E5: strain stiffening, `E_i(e) = E_i0 (1 + a |e|_C)` as a tangent modulus
    /// (Fung's quasi-linear form: the chain acts on `psi(e) = (1 + a |e|_C / 2) e`).
    Stiffening { a: f64 },
    /// E6: finite strain. No inelastic strain: the law leaves the chain as it is,
    /// and the kinematics change (the blended Green-Lagrange strain, the internal
    /// force `w B(u)^T S`; [`crate::element::green_lagrange_strain`]).
    FiniteStrain { blend: f64 },
    /// Mullins-type damage (a material's law, [`super::MullinsDamage`]): the chain
    /// acts on `(1 - d(alpha)) e`, `d(alpha) = d_inf (1 - exp(-alpha / strain_c))`,
    /// `alpha` the cell's largest `|e|_C` so far (its history).
    Damage { d_inf: f64, strain_c: f64 },
}

/// The result of a local update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointUpdate<const S: usize> {
    /// The inelastic strain at the step's end.
    pub inelastic: SVector<f64, S>,
    /// The stress image `tau1` at the step's end (the stress is `C1 tau1`).
    pub tau: SVector<f64, S>,
    /// `d tau1 / d tau_trial` (so `d s1 / d e1 = g C1 T`, symmetric); for a
    /// slider with `H < TANGENT_HARDENING g` the tangent of `H = TANGENT_HARDENING g`
    /// ([`TANGENT_HARDENING`] is 1e-8: in practice only `H = 0`).
    pub tangent: SMatrix<f64, S, S>,
    /// The law's scalar history at the step's end: for [`InelasticLaw::Damage`] the
    /// largest equivalent strain so far; the start's value for the other laws.
    pub history: f64,
}

/// The chain's mean stress image over a step, for the laws that correct the
/// chain's dashpot with it (Bingham's; module doc): `tau_mean = trial - g (e_in1 -
/// e_in0)` for the step's inelastic strain `e_in1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepMean<const S: usize> {
    /// `tau_mean_trial = g_m (e1 - e_in0) - q_m`, the mean with the inelastic strain
    /// held at the step's start.
    pub trial: SVector<f64, S>,
    /// The step's mean factor `g_m` [MPa]
    /// ([`crate::material::RelaxationKernel::mean_factor`]).
    pub g: f64,
}

/// Why a local update has no solution for this step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PointFailure {
    /// The step is too long for the dashpot correction: `g dt / c3` is not below 1
    /// (`g dt` tends to the chain's total viscosity `c3` as `dt` grows, and can
    /// exceed it with the BDF2 factor), so the backward-Euler correction of a
    /// slower dashpot has no positive solution. A shorter step cures it.
    StepTooLong { ratio: f64 },
    /// Strain softening (`a < 0`) has used up the stiffness: the tangent modulus
    /// `1 + a |e|_C` of the stiffened strain is not positive at `|e|_C = strain`.
    NoStiffness { strain: f64 },
}

/// The least tangent factor `1 + a |e|_C` strain softening accepts: below it a
/// cell is refused ([`PointFailure::NoStiffness`]), since the stiffened strain
/// then no longer grows with the strain and equilibrium loses uniqueness.
pub const MIN_STIFFENING_FACTOR: f64 = 0.05;

/// `|x|_C = sqrt(x . C1 x)`.
pub fn energy_norm<const S: usize>(c1: &SMatrix<f64, S, S>, x: &SVector<f64, S>) -> f64 {
    x.dot(&(c1 * x)).max(0.0).sqrt()
}

/// The largest `g dt / c3` a dashpot correction accepts (a step with a larger
/// ratio is refused and retried shorter: near 1 the correction amplifies the trial
/// by `1 / (1 - ratio)`).
pub const MAX_DASHPOT_RATIO: f64 = 0.95;

/// The largest `g_m dt / c3` Bingham's correction on the step's mean stress accepts
/// (module doc): it is below 1 at every step in exact arithmetic, and the
/// correction amplifies the mean trial by `1 / (1 - ratio)`, so only a chain whose
/// `c3` does not match its kernel's reaches it.
pub const MAX_MEAN_DASHPOT_RATIO: f64 = 1.0 - 1e-9;

/// The least hardening, relative to the step factor `g`, the slider's tangent is
/// taken with (the update itself uses the true `H`, 0 included). It only keeps
/// the tangent of perfect plasticity (`H = 0`) from being exactly singular: any
/// floor above the true `H` makes the tangent too stiff along the flow, and
/// Newton's method then contracts only by about `1 - H / floor` an iteration.
/// The floor was `1e-2 g` and stalled the steps right after an instant release:
/// there `g` is the chain's instantaneous viscosity over the step (`B2 / dt`, 188
/// to 3000 MPa on the seed's material at dt = 2e-4 to 1e-5 s), `H / g` was 5e-5
/// to 3e-6, and the iteration stopped at 1e-7 of the force scale after 60
/// iterations. At `1e-8 g` the tangent is exact for every `H / g` above 1e-8,
/// and the factorization's conditioning (about `g / H` times the mesh's) stays
/// far from double precision's limit.
pub const TANGENT_HARDENING: f64 = 1e-8;

impl InelasticLaw {
    /// Whether the law is at its null (gives back the linear chain exactly).
    pub fn is_null(&self) -> bool {
        match *self {
            InelasticLaw::Slider { yield_mpa, .. } => yield_mpa == f64::INFINITY,
            InelasticLaw::Bingham { threshold_mpa, .. } => threshold_mpa == 0.0,
            InelasticLaw::Thinning { inverse_stress_per_mpa, .. } => inverse_stress_per_mpa == 0.0,
            InelasticLaw::Dual { log_ratio, .. } => log_ratio == 0.0,
            InelasticLaw::Stiffening { a } => a == 0.0,
            InelasticLaw::FiniteStrain { blend } => blend == 0.0,
            InelasticLaw::Damage { d_inf, .. } => d_inf == 0.0,
        }
    }

    /// Whether the inelastic strain follows a flow rule integrated over the step
    /// (E1 to E4: the slider's return map, the dashpot corrections' backward Euler),
    /// so that its value at a step end carries a time-discretisation error that the
    /// stepper's error control must see. The strain-driven laws (stiffening, damage)
    /// and finite strain are exact functions of the step end's strain: no.
    pub fn flows(&self) -> bool {
        matches!(
            self,
            InelasticLaw::Slider { .. }
                | InelasticLaw::Bingham { .. }
                | InelasticLaw::Thinning { .. }
                | InelasticLaw::Dual { .. }
        )
    }

    /// The largest share of the chain's dashpot flow that the law's correction takes
    /// back, per unit viscosity [1/(MPa s)]: the correction's rate is at most this
    /// times the chain's stress, against it. Bingham below its threshold blocks `c3`
    /// whole (`1/c3`); the dual viscosity while unloading takes back
    /// `(1 - exp(-psi))/c3` when `psi > 0`. The other laws take back none (the slider
    /// is rate-independent; thinning adds flow). The stepper compares it with the
    /// chain's instantaneous viscosity to keep BDF2 stable (the press stepper's module
    /// doc, "Blocking corrections").
    pub fn blocking_per_mpa_s(&self) -> f64 {
        match *self {
            InelasticLaw::Bingham { threshold_mpa, c3_mpa_s } if threshold_mpa != 0.0 => 1.0 / c3_mpa_s,
            InelasticLaw::Dual { log_ratio, c3_mpa_s } if log_ratio > 0.0 => -(-log_ratio).exp_m1() / c3_mpa_s,
            _ => 0.0,
        }
    }

    /// The viscosity `c3` [MPa s] of the chain's dashpot whose flow the law's
    /// correction takes with the step's mean stress ([`StepMean`]; module doc):
    /// Bingham's away from its null. The step control measures such a cell's net
    /// dashpot flow, the correction plus the chain's own `dt tau_mean/c3`
    /// (`press::stepper`, "Step control").
    pub fn mean_corrected_c3(&self) -> Option<f64> {
        match *self {
            InelasticLaw::Bingham { threshold_mpa, c3_mpa_s } if threshold_mpa != 0.0 => Some(c3_mpa_s),
            _ => None,
        }
    }

    /// Whether the law carries a scalar history per cell (the damage's largest strain).
    pub fn needs_history(&self) -> bool {
        matches!(self, InelasticLaw::Damage { .. })
    }

    /// Whether the law needs the per-cell loading flag (E4).
    pub fn needs_direction(&self) -> bool {
        matches!(self, InelasticLaw::Dual { .. })
    }

    /// The local update of one cell over a step: `c1` the region's unit-Young
    /// matrix, `tau_trial = g (e1 - e_in0) - q`, `inelastic0 = e_in0`, `g` the
    /// step factor, `dt` the step, `unloading` the cell's direction flag (E4 only),
    /// `strain = e1` the cell's total strain at the step's end (E5 only: its law is
    /// a function of the strain, not of the stress; and the damage), `history0` the
    /// law's scalar history at the step's start (damage only: the largest `|e|_C`
    /// so far; any value for the other laws, returned unchanged), `mean` the chain's
    /// mean stress over the step (needed where [`Self::mean_corrected_c3`] is
    /// `Some`: Bingham's; `None` for the other laws).
    #[allow(clippy::too_many_arguments)]
    pub fn update<const S: usize>(
        &self,
        c1: &SMatrix<f64, S, S>,
        tau_trial: &SVector<f64, S>,
        inelastic0: &SVector<f64, S>,
        g: f64,
        dt: f64,
        unloading: bool,
        strain: &SVector<f64, S>,
        history0: f64,
        mean: Option<&StepMean<S>>,
    ) -> Result<PointUpdate<S>, PointFailure> {
        let identity = SMatrix::<f64, S, S>::identity();
        let unchanged = PointUpdate { inelastic: *inelastic0, tau: *tau_trial, tangent: identity, history: history0 };
        // `n (C1 n)^T` for a unit direction n: the radial part of a tangent.
        let radial = |n: &SVector<f64, S>| n * (c1 * n).transpose();
        match *self {
            InelasticLaw::Slider { yield_mpa, hardening_mpa: h } => {
                // Trial relative stress x = tau_trial - H e_p0; radial return:
                // x1 = x (1 - (g + H) dl / |x|), |x1| = sigma_y, dl = (|x| - sigma_y)/(g + H).
                let x = tau_trial - inelastic0 * h;
                let sigma = energy_norm(c1, &x);
                if sigma <= yield_mpa {
                    return Ok(unchanged);
                }
                let n = x / sigma;
                let dl = (sigma - yield_mpa) / (g + h);
                let de = n * dl;
                // d(dl n)/dx = n (C1 n)^T / (g + H) + (dl / |x|) (I - n (C1 n)^T). With
                // H = 0 the radial part g H/(g + H) vanishes and a cell makes the tangent
                // singular: it is taken with H at least TANGENT_HARDENING g (tiny, so that
                // the tangent is exact for any real hardening; see the constant).
                let nn = radial(&n);
                let ht = h.max(TANGENT_HARDENING * g);
                let d = nn / (g + ht) + (identity - nn) * (dl / sigma);
                Ok(PointUpdate {
                    inelastic: inelastic0 + de,
                    tau: tau_trial - de * g,
                    tangent: identity - d * g,
                    history: history0,
                })
            }
            InelasticLaw::Bingham { threshold_mpa: sb, c3_mpa_s } => {
                if sb == 0.0 {
                    return Ok(unchanged);
                }
                // On the step's mean stress (module doc): tau_m = tau_m,trial + k min(1,
                // sB/|tau_m|) tau_m with k = g_m dt / c3 (c3's flow over the step undone),
                // radial. Above the threshold |tau_m| = |tau_m,trial| + k sB; below it
                // tau_m = tau_m,trial / (1 - k). Then e_in1 - e_in0 = (tau_m,trial - tau_m)/g_m
                // and tau1 = tau_trial - g (e_in1 - e_in0); d tau1/d tau_trial is
                // d tau_m/d tau_m,trial.
                let mean = mean.expect("Bingham's update needs the step's mean stress");
                let k = mean.g * dt / c3_mpa_s;
                if !(k < MAX_MEAN_DASHPOT_RATIO) {
                    return Err(PointFailure::StepTooLong { ratio: k });
                }
                let trial = &mean.trial;
                let sigma = energy_norm(c1, trial);
                let (tau_mean, tangent) = if sigma > 0.0 && sigma >= sb * (1.0 - k) {
                    let n = trial / sigma;
                    (trial + n * (k * sb), identity + (identity - radial(&n)) * (k * sb / sigma))
                } else {
                    (trial / (1.0 - k), identity / (1.0 - k))
                };
                let de = (trial - tau_mean) / mean.g;
                Ok(PointUpdate { inelastic: inelastic0 + de, tau: tau_trial - de * g, tangent, history: history0 })
            }
            InelasticLaw::Thinning { inverse_stress_per_mpa: w, exponent: m, c3_mpa_s } => {
                if w == 0.0 {
                    return Ok(unchanged);
                }
                // tau1 = tau_trial - k (w |tau1|)^m tau1: radial, |tau1| = r solves
                // r (1 + k (w r)^m) = |tau_trial| (increasing in r: one root in (0, |tau_trial|]).
                let k = g * dt / c3_mpa_s;
                let sigma = energy_norm(c1, tau_trial);
                if sigma == 0.0 {
                    return Ok(unchanged);
                }
                let f = |r: f64| r * (1.0 + k * (w * r).powf(m)) - sigma;
                let df = |r: f64| 1.0 + k * (1.0 + m) * (w * r).powf(m);
                let (mut lo, mut hi) = (0.0, sigma);
                let mut r = sigma / (1.0 + k * (w * sigma).powf(m)).min(1e300);
                for _ in 0..200 {
                    let v = f(r);
                    if v > 0.0 {
                        hi = r;
                    } else {
                        lo = r;
                    }
                    let mut next = r - v / df(r);
                    if !(next > lo && next < hi) {
                        next = 0.5 * (lo + hi);
                    }
                    if (next - r).abs() <= 1e-15 * sigma {
                        r = next;
                        break;
                    }
                    r = next;
                }
                let rho = r / sigma;
                // d|tau1|/d|tau_trial| = 1 / f'(r); T = rho I + (p - rho) n (C1 n)^T.
                let p = 1.0 / df(r);
                let n = tau_trial / sigma;
                let tau = tau_trial * rho;
                let tangent = identity * rho + radial(&n) * (p - rho);
                Ok(PointUpdate { inelastic: inelastic0 + (tau_trial - tau) / g, tau, tangent, history: history0 })
            }
            InelasticLaw::Dual { log_ratio, c3_mpa_s } => {
                if log_ratio == 0.0 || !unloading {
                    return Ok(unchanged);
                }
                // Unloading: c3 -> c3 exp(psi), flow (exp(-psi) - 1) tau1 / c3 added:
                // tau1 = tau_trial / (1 + k (exp(-psi) - 1)).
                let k = g * dt / c3_mpa_s;
                let a = (-log_ratio).exp_m1();
                let denom = 1.0 + k * a;
                if denom < 1.0 - MAX_DASHPOT_RATIO {
                    return Err(PointFailure::StepTooLong { ratio: k });
                }
                let tau = tau_trial / denom;
                Ok(PointUpdate {
                    inelastic: inelastic0 + (tau_trial - tau) / g,
                    tau,
                    tangent: identity / denom,
                    history: history0,
                })
            }
            InelasticLaw::FiniteStrain { .. } => Ok(unchanged),
            InelasticLaw::Stiffening { a } => {
                if a == 0.0 {
                    return Ok(unchanged);
                }
                // The chain's strain is psi(e1) = (1 + a n / 2) e1 with n = |e1|_C, so
                // e_in1 = e1 - psi(e1) = -(a n / 2) e1 and tau1 = tau_trial - g (e_in1 - e_in0)
                // = g psi(e1) - q. T = d psi / d e1 = (1 + a n / 2) I + (a / 2n) e1 (C1 e1)^T;
                // C1 T is symmetric (psi is the gradient of the potential n^2/2 + a n^3/6
                // in the C1 metric), with eigenvalues 1 + a n / 2 and, along e1, 1 + a n.
                let n = energy_norm(c1, strain);
                if 1.0 + a * n < MIN_STIFFENING_FACTOR {
                    return Err(PointFailure::NoStiffness { strain: n });
                }
                let inelastic = strain * (-0.5 * a * n);
                let tau = tau_trial - (inelastic - inelastic0) * g;
                let mut tangent = identity * (1.0 + 0.5 * a * n);
                if n > 0.0 {
                    tangent += strain * (c1 * strain).transpose() * (0.5 * a / n);
                }
                Ok(PointUpdate { inelastic, tau, tangent, history: history0 })
            }
            InelasticLaw::Damage { d_inf, strain_c } => {
                // e_in1 = d(alpha1) e1 with alpha1 = max(alpha0, n), n = |e1|_C, so the
                // chain's strain is (1 - d) e1 and tau1 = tau_trial - g (e_in1 - e_in0)
                // = g (1 - d) e1 - q. Below the largest strain (alpha1 = alpha0) the
                // damage is frozen: T = (1 - d) I. On the virgin curve (n > alpha0)
                // T = (1 - d) I - (d'(n) / n) e1 (C1 e1)^T: C1 T is symmetric (the
                // damaged strain is the C1-gradient of W(n) = int_0^n (1 - d(m)) m dm),
                // with eigenvalues 1 - d across e1 and 1 - d - n d'(n) > 0.09 along it.
                let law = super::MullinsDamage { d_inf, strain_c };
                let n = energy_norm(c1, strain);
                let virgin = n > history0;
                let alpha = if virgin { n } else { history0 };
                let d = law.damage(alpha);
                let inelastic = strain * d;
                let tau = tau_trial - (inelastic - inelastic0) * g;
                let mut tangent = identity * (1.0 - d);
                if virgin && n > 0.0 {
                    tangent -= strain * (c1 * strain).transpose() * (law.damage_derivative(n) / n);
                }
                Ok(PointUpdate { inelastic, tau, tangent, history: alpha })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{unit_young_matrix, Formulation};

    fn c1() -> SMatrix<f64, 4, 4> {
        unit_young_matrix::<4>(Formulation::Axisymmetric, 0.37)
    }

    /// Uniaxial stress image: `tau = sigma C1^-1 e_y`, whose energy norm is |sigma|.
    fn uniaxial(sigma: f64) -> SVector<f64, 4> {
        c1().try_inverse().unwrap() * SVector::<f64, 4>::from([0.0, sigma, 0.0, 0.0])
    }

    /// A step mean that moves with the trial as the stepper's does: both are affine
    /// in the step's strain `e1`, with the factors `g` and `g_m = 0.6 g`, so a change
    /// `x` of `tau_trial` is one of `0.6 x` of `tau_mean_trial`; the offset is a
    /// history part of its own.
    fn mean_of(trial: &SVector<f64, 4>, g: f64) -> StepMean<4> {
        let offset = SVector::<f64, 4>::from([0.00004, -0.00011, 0.00002, -0.00003]);
        StepMean { trial: trial * 0.6 + offset, g: 0.6 * g }
    }

    #[test]
    fn energy_norm_of_uniaxial_stress_is_its_size() {
        for s in [-0.3, 1e-3, 2.0] {
            assert!((energy_norm(&c1(), &uniaxial(s)) - s.abs()).abs() < 1e-15 * s.abs().max(1.0));
        }
        let c = unit_young_matrix::<3>(Formulation::PlaneStress { thickness_mm: 1.0 }, 0.3);
        let tau = c.try_inverse().unwrap() * SVector::<f64, 3>::from([0.0, -0.7, 0.0]);
        assert!((energy_norm(&c, &tau) - 0.7).abs() < 1e-15);
    }

    /// Every law's tangent against central differences of its own update, at
    /// random-ish trial states on the active branch (relative step 1e-6: the
    /// differences agree to about 1e-8 relative), and `C1 T` symmetric.
    #[test]
    fn tangents_match_finite_differences() {
        let c = c1();
        let trial = uniaxial(-0.02) + SVector::<f64, 4>::from([0.003, -0.001, 0.002, 0.004]);
        let e0 = SVector::<f64, 4>::from([0.01, -0.02, 0.01, 0.003]);
        let laws = [
            InelasticLaw::Slider { yield_mpa: 0.005, hardening_mpa: 0.01 },
            InelasticLaw::Bingham { threshold_mpa: 0.004, c3_mpa_s: 3.0 },
            InelasticLaw::Thinning { inverse_stress_per_mpa: 150.0, exponent: 1.3, c3_mpa_s: 3.0 },
            InelasticLaw::Dual { log_ratio: 1.2, c3_mpa_s: 3.0 },
        ];
        let (g, dt) = (0.05, 2.0);
        for law in laws {
            let at = |t: &SVector<f64, 4>| {
                let mean = mean_of(t, g);
                law.update(&c, t, &e0, g, dt, true, &e0, 0.0, law.mean_corrected_c3().map(|_| &mean)).unwrap()
            };
            let u = at(&trial);
            for j in 0..4 {
                let h = 1e-6 * trial.norm();
                let mut up = trial;
                up[j] += h;
                let mut down = trial;
                down[j] -= h;
                let fd = (at(&up).tau - at(&down).tau) / (2.0 * h);
                for i in 0..4 {
                    assert!(
                        (u.tangent[(i, j)] - fd[i]).abs() < 1e-7,
                        "{law:?} ({i}, {j}): {} vs {}",
                        u.tangent[(i, j)],
                        fd[i]
                    );
                }
            }
            let ct = c * u.tangent;
            assert!((ct - ct.transpose()).norm() < 1e-14 * ct.norm(), "{law:?}: C1 T not symmetric");
            // tau1 = tau_trial - g (e_in1 - e_in0).
            assert!((u.tau - (trial - (u.inelastic - e0) * g)).norm() < 1e-15 * trial.norm());
        }
    }

    /// The slider's return lands on the yield surface; Bingham's update stops the
    /// flow below the threshold and leaves `sigma_B / c3` of it above; at the nulls
    /// every law returns the trial unchanged, bit for bit.
    /// The blocking ratio the stepper uses is the one the updates take back: below
    /// Bingham's threshold and while the dual viscosity unloads, the step's
    /// inelastic strain is `-blocking dt tau` (the step's mean stress for Bingham,
    /// its end stress for the dual law's backward Euler), to 1e-14 relative
    /// (the round-off of `tau_trial - tau1`; measured 1.3e-15 for the dual law);
    /// the laws that take back nothing give 0.
    #[test]
    fn blocking_ratio_matches_the_updates() {
        let c = c1();
        let e0 = SVector::<f64, 4>::zeros();
        let (g, dt, c3) = (0.05, 2.0, 3.0);
        let small = uniaxial(-0.001);
        let mean = mean_of(&small, g);
        for (law, unloading) in [
            (InelasticLaw::Bingham { threshold_mpa: 0.004, c3_mpa_s: c3 }, false),
            (InelasticLaw::Dual { log_ratio: 1.2, c3_mpa_s: c3 }, true),
        ] {
            let with_mean = law.mean_corrected_c3().map(|_| &mean);
            let u = law.update(&c, &small, &e0, g, dt, unloading, &e0, 0.0, with_mean).unwrap();
            // The stress the correction acts on: tau_mean = trial_m - g_m (e_in1 - e_in0).
            let acting = match with_mean {
                Some(m) => m.trial - (u.inelastic - e0) * m.g,
                None => u.tau,
            };
            let expected = -acting * (law.blocking_per_mpa_s() * dt);
            assert!(
                (u.inelastic - expected).norm() <= 1e-14 * expected.norm(),
                "{law:?}: {} vs {expected}",
                u.inelastic
            );
        }
        for law in [
            InelasticLaw::Slider { yield_mpa: 0.005, hardening_mpa: 0.01 },
            InelasticLaw::Thinning { inverse_stress_per_mpa: 400.0, exponent: 1.0, c3_mpa_s: c3 },
            InelasticLaw::Dual { log_ratio: -1.2, c3_mpa_s: c3 },
            InelasticLaw::Bingham { threshold_mpa: 0.0, c3_mpa_s: c3 },
        ] {
            assert_eq!(law.blocking_per_mpa_s(), 0.0, "{law:?}");
            assert_eq!(law.mean_corrected_c3(), None, "{law:?}");
        }
    }

    /// The slider lands on its yield surface; Bingham's correction leaves the net
    /// dashpot flow `(1 - sigma_B/|tau_mean|_C) dt tau_mean/c3` above the threshold
    /// and none below it, on the step's mean stress (`tau1` follows with the end
    /// factor `g`); a mean factor whose `g_m dt` reaches `c3` (a kernel that does
    /// not match the law's `c3`) is refused; at the nulls every law returns the
    /// trial unchanged, bit for bit.
    #[test]
    fn updates_satisfy_their_laws() {
        let c = c1();
        let e0 = SVector::<f64, 4>::zeros();
        let trial = uniaxial(-0.02);
        let (g, dt, c3) = (0.05, 2.0, 3.0);
        let s = InelasticLaw::Slider { yield_mpa: 0.005, hardening_mpa: 0.01 }
            .update(&c, &trial, &e0, g, dt, false, &e0, 0.0, None);
        let s = s.unwrap();
        assert!((energy_norm(&c, &(s.tau - s.inelastic * 0.01)) - 0.005).abs() < 1e-15);
        let bingham = InelasticLaw::Bingham { threshold_mpa: 0.004, c3_mpa_s: c3 };
        let mean = mean_of(&trial, g);
        let b = bingham.update(&c, &trial, &e0, g, dt, false, &e0, 0.0, Some(&mean)).unwrap();
        let tau_mean = mean.trial - b.inelastic * mean.g;
        // Net dashpot flow over the step: the chain's tau_mean/c3 dt plus the correction.
        let net = tau_mean * (dt / c3) + b.inelastic;
        let expected = tau_mean * ((1.0 - 0.004 / energy_norm(&c, &tau_mean)) * dt / c3);
        assert!((net - expected).norm() < 1e-15, "{net} vs {expected}");
        assert!((b.tau - (trial - b.inelastic * g)).norm() < 1e-18);
        let small = uniaxial(-0.001);
        let mean = mean_of(&small, g);
        let k = mean.g * dt / c3;
        let b = bingham.update(&c, &small, &e0, g, dt, false, &e0, 0.0, Some(&mean)).unwrap();
        let tau_mean = mean.trial - b.inelastic * mean.g;
        // Zero to the round-off of recomputing tau_mean (measured 1.3e-18 against
        // |e_in1| = 5e-4).
        let flow = (tau_mean * (dt / c3) + b.inelastic).norm();
        assert!(flow < 1e-14 * b.inelastic.norm(), "{flow}");
        let off = (tau_mean - mean.trial / (1.0 - k)).norm();
        assert!(off < 1e-14 * tau_mean.norm(), "{off}");
        let nulls = [
            InelasticLaw::Slider { yield_mpa: f64::INFINITY, hardening_mpa: 0.01 },
            InelasticLaw::Bingham { threshold_mpa: 0.0, c3_mpa_s: c3 },
            InelasticLaw::Thinning { inverse_stress_per_mpa: 0.0, exponent: 1.0, c3_mpa_s: c3 },
            InelasticLaw::Dual { log_ratio: 0.0, c3_mpa_s: c3 },
            InelasticLaw::Stiffening { a: 0.0 },
            InelasticLaw::Damage { d_inf: 0.0, strain_c: 0.1 },
        ];
        for law in nulls {
            assert!(law.is_null());
            let u = law.update(&c, &trial, &e0, g, dt, true, &e0, 0.0, None).unwrap();
            assert_eq!(u.tau, trial, "{law:?}");
            assert_eq!(u.inelastic, e0, "{law:?}");
        }
        let mismatched = StepMean { trial: trial * 0.6, g: c3 / 60.0 };
        let long = bingham.update(&c, &trial, &e0, g, 60.0, false, &e0, 0.0, Some(&mismatched));
        assert!(matches!(long, Err(PointFailure::StepTooLong { .. })));
    }

    /// Strain stiffening: in uniaxial stress `sigma = E0 (e + a e |e| / 2)` (tangent
    /// `E0 (1 + a |e|)`) with no lateral stress; the update gives `tau1 = g psi(e1) - q`
    /// from any start; its tangent matches central differences of `psi` (relative
    /// step 1e-6, agreement 1e-8) and `C1 T` is symmetric; softening past the
    /// least tangent factor is refused.
    #[test]
    fn stiffening_update_matches_its_closed_form() {
        let c = c1();
        let (g, dt, a) = (0.7, 1.0, 6.0);
        let e0 = SVector::<f64, 4>::from([0.003, -0.002, 0.001, 0.0005]);
        let law = InelasticLaw::Stiffening { a };
        // tau_trial = g (e1 - e_in0) - q with q = 0.
        let at = |e1: &SVector<f64, 4>| law.update(&c, &((e1 - e0) * g), &e0, g, dt, false, e1, 0.0, None).unwrap();
        for sigma in [-0.12, 0.05] {
            let e1 = uniaxial(sigma);
            let u = at(&e1);
            let s = c * u.tau / g;
            let expected = sigma + a * sigma * sigma.abs() / 2.0;
            assert!((s[1] - expected).abs() < 1e-15, "{} vs {expected}", s[1]);
            for k in [0, 2, 3] {
                assert!(s[k].abs() < 1e-15, "lateral stress {}", s[k]);
            }
        }
        let e1 = uniaxial(-0.1) + SVector::<f64, 4>::from([0.01, -0.004, 0.02, 0.03]);
        let u = at(&e1);
        for j in 0..4 {
            let h = 1e-6 * e1.norm();
            let (mut up, mut down) = (e1, e1);
            up[j] += h;
            down[j] -= h;
            let fd = (at(&up).tau - at(&down).tau) / (2.0 * h * g);
            for i in 0..4 {
                assert!((u.tangent[(i, j)] - fd[i]).abs() < 1e-8, "({i}, {j}): {} vs {}", u.tangent[(i, j)], fd[i]);
            }
        }
        let ct = c * u.tangent;
        assert!((ct - ct.transpose()).norm() < 1e-14 * ct.norm());
        let soft = InelasticLaw::Stiffening { a: -4.0 };
        let e1 = uniaxial(-0.3);
        assert!(matches!(
            soft.update(&c, &(e1 * g), &SVector::zeros(), g, dt, false, &e1, 0.0, None),
            Err(PointFailure::NoStiffness { .. })
        ));
    }

    /// Mullins-type damage: in uniaxial stress `sigma = (1 - d(alpha)) e` with
    /// `alpha = max(alpha0, |e|)`, no lateral stress; the history is the largest
    /// strain; the tangent matches central differences of the update on the virgin
    /// curve and below it (relative step 1e-6, agreement 1e-8) and `C1 T` is symmetric.
    #[test]
    fn damage_update_matches_its_closed_form() {
        let c = c1();
        let (g, dt) = (0.7, 1.0);
        let law = InelasticLaw::Damage { d_inf: 0.6, strain_c: 0.05 };
        let d = |alpha: f64| 0.6 * (1.0 - (-alpha / 0.05).exp());
        let e0 = SVector::<f64, 4>::from([0.003, -0.002, 0.001, 0.0005]);
        let at = |e1: &SVector<f64, 4>, alpha0: f64| {
            law.update(&c, &((e1 - e0) * g), &e0, g, dt, false, e1, alpha0, None).unwrap()
        };
        for (sigma, alpha0) in [(-0.12, 0.0), (-0.12, 0.2), (0.05, 0.03)] {
            let e1 = uniaxial(sigma);
            let u = at(&e1, alpha0);
            let alpha = alpha0.max(sigma.abs());
            assert!((u.history - alpha).abs() < 1e-15, "{} vs {alpha}", u.history);
            let s = c * u.tau / g;
            let expected = (1.0 - d(alpha)) * sigma;
            assert!((s[1] - expected).abs() < 1e-15, "{} vs {expected}", s[1]);
            for k in [0, 2, 3] {
                assert!(s[k].abs() < 1e-15, "lateral stress {}", s[k]);
            }
        }
        let e1 = uniaxial(-0.1) + SVector::<f64, 4>::from([0.01, -0.004, 0.02, 0.03]);
        let n = energy_norm(&c, &e1);
        for alpha0 in [0.5 * n, 2.0 * n] {
            let u = at(&e1, alpha0);
            for j in 0..4 {
                let h = 1e-6 * e1.norm();
                let (mut up, mut down) = (e1, e1);
                up[j] += h;
                down[j] -= h;
                let fd = (at(&up, alpha0).tau - at(&down, alpha0).tau) / (2.0 * h * g);
                for i in 0..4 {
                    assert!(
                        (u.tangent[(i, j)] - fd[i]).abs() < 1e-8,
                        "alpha0 {alpha0} ({i}, {j}): {} vs {}",
                        u.tangent[(i, j)],
                        fd[i]
                    );
                }
            }
            let ct = c * u.tangent;
            assert!((ct - ct.transpose()).norm() < 1e-14 * ct.norm());
        }
    }
}
