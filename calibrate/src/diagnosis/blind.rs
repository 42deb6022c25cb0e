//! The blind self-check of the diagnosis ("Blind self-check";
//! diagnosis.md "Blind check"; diagnosis-details.md §7.4 and §7.6): synthetic
//! campaigns with one withheld effect, diagnosed without being told, and scored.
//!
//! ## The generator, and how it differs from the diagnoser
//!
//! A campaign is four 2D plane-stress trials of a 20 x H x 10 mm block of a
//! three-element gel (`E1` = 0.05 MPa, `c1` = 0.05 MPa s, `c3` = 5 MPa s,
//! `nu` = 0.3; glued floor, frictionless plate), 2 s before contact, then
//! [`DESIGN`]: push durations 2.5 to 10 s, holds 5 to 30 s, strain 10 to 20 %,
//! heights 10 and 15 mm (speed, hold, strain level and aspect ratio all vary,
//! diagnosis-details.md §5.7), a withdrawal to half the depth over half the push
//! duration (the release phase, where a dual viscosity shows), then the release
//! and 20 s of recovery. The diagnoser is told the model
//! (`three-element`, `nu`), the nominal geometry and protocol, the trials' age
//! (`age_h`, the run order shuffled per campaign), the marker noise, and nothing else.
//!
//! | | diagnoser | generator (the "real" trials) |
//! |---|---|---|
//! | mesh | `size_mm` (default 5 mm), corrected by its own half-size run (mod.rs, step 0) | a quarter of it ([`TRUTH_REFINEMENT`]) |
//! | time steps | adaptive, `rtol` 1e-3 | adaptive, `rtol` 1e-5, at most 0.2 s |
//! | material | one parameter set | per trial (sample) log-scales on the moduli and on the viscosities, N(0, s^2) with s drawn per campaign in [0.03, 0.10] |
//! | geometry | nominal W, H, T | each x (1 + 0.005 N(0,1)), clipped to +-1.5 % (0.1 mm on 20 mm: a calliper on a soft gel); markers at the same relative places of the true block |
//! | force | AR(1) noise estimated on the no-contact segments, whitened | AR(1) noise, sigma 3 mN, lag-1 correlation drawn per trial in [0.3, 0.7], sampled at 10 Hz, quantised to 1 mN |
//! | markers | `marker_sigma_mm` (set to the generator's 0.03 mm, as static frames would give) | five markers (three on the free side, two on the top), Gaussian noise 0.03 mm, quantised to 0.01 mm |
//!
//! The sample scatter (variability and geometry errors) is a [`Scatter`]:
//! [`Scatter::ISSUE`] as above, or [`Scatter::IDEAL`] (none), with the same
//! random stream otherwise. **Measured** (the noise-free misfit of the best
//! baseline on a null campaign, `lambda_null`, in noise units; development seed
//! 101, first three null campaigns): with the issue's scatter it was 2.6e5 to
//! 5.5e5 while the diagnoser had no per-sample scales (a 5 % modulus scale moves
//! every force sample by about 15 noise units); with ideal samples 445 to 580
//! (the diagnoser's 5 mm mesh against the generator's 2.5 mm: its step 0 halved
//! time steps only). Per-sample scales with the 0.1 prior brought both to 29 to
//! 39 (all of it marker error of the coarse mesh); the mesh correction of step
//! 0, with the generator moved to a quarter of the element size, to about 7;
//! whitening the markers for their shared initial-position error (the
//! diagnoser starts every track at the measured, noisy, t = 0 position) left
//! about 1 noise unit, and the null campaigns of the frozen set came out `none`.
//! **Development seeds with the issue's scatter** (not re-run with the current
//! code; `wagashi diagnose --blind 24 --seed S` for S = 101 to 104; 93 campaigns scored,
//! three `plate-friction` truths failed to run): top-1 at lambda of 30 and
//! more 22/40 (0.55; per seed 3/8, 6/9, 6/11, 7/12), at lambda = 12 5/21
//! (0.24); false attribution on nulls 3/24 (0.13: two `force-offset` with LR
//! 14 to 16 on seed 101, whose noise-free null misfit is 1.4 to 3.9, and one
//! `strain-stiffening` on seed 104: the noise model's low-frequency
//! calibration is the suspect, not settled); out-of-library flagged 2/8;
//! median gap-closure error 0.37 over 13. Most misses at lambda of 30 and more
//! are ties between confusable pairs (bingham-dashpot / stress-thinning,
//! strain-stiffening / finite-strain, force-offset / gravity), whose separating
//! experiments (a hold of 5x the c3 time, two strain levels at one aspect
//! ratio, a tared no-contact record) this four-trial design lacks; the others
//! are refits that stop short (`machine-compliance`, LR about a sixth of
//! lambda_eff on seed 101) and effects left at `none`.
//! `plate-friction` truths on the fine mesh sometimes stop with a contact that
//! does not settle; such a campaign is listed as a failure, not scored.
//!
//! **The separating trials, tried and not kept.** The design
//! above, with two trials added and 5 s (not 2 s) before contact, the
//! experiments the diagnosis names when it says `tie`
//! ([`super::separating_experiment`]; commit 7dac917 on branch wt/blind):
//! a hold of five relaxation times (`(c1 + c3)/E1` = 101 s; 10 % in 5 s on
//! the 10 mm block, hold 505 s, 101 s recorded after the release:
//! `bingham-dashpot` against `stress-thinning`, and a long no-contact record
//! for `force-offset`), and 25 % in 12.5 s with a 10 s hold on the 15 mm block
//! (10, 20 and 25 % at one aspect ratio and one strain rate:
//! `strain-stiffening` against `finite-strain`). Left out: a second
//! compression of one sample (a plate that pushes again after rising runs as a
//! contact tool, without sensitivities) and a record with nothing on the
//! sensor (the bundle format cannot say it). Measured on development seeds 101
//! and 102 (`wagashi diagnose --blind 24 --seed S`, the issue's scatter, the
//! same case plans as the four-trial runs, 24 campaigns a seed, 44 scored and four
//! `plate-friction` truths failed;
//! thresholds untouched, the frozen CI seed not used): top-1 at lambda of 30
//! and more 8/17 (0.47; seed 101 5/9, seed 102 3/8), at lambda = 12 2/6
//! (0.33), false attribution on nulls 0/11, out-of-library flagged 5/10
//! (0.50; 2/6 and 3/4), median closure error 1.56 over 6 (1.41 and 1.57);
//! the four-trial design on the same campaigns
//! 9/18 (0.50; 4/9 and 5/9), 1/7, 0/11, 4/10 (0.40; 3/6 and 1/4), 0.006 over 3
//! and 0.088 over 2. What went wrong: (1) the long hold makes a
//! threshold of a few Pa visible (lambda 30 at `sigma_B` = 5.3 Pa on seed 101,
//! against 0.37 kPa with the four trials), and a plateau of about 1 mN over
//! 505 s is much like a force offset with drift: `bingham-dashpot` and
//! `force-offset` took each other's place (seed 102: Bingham at 100 named
//! `force-offset`, offset at 30 named `bingham-dashpot`, margins 166 and 262
//! against 2 SE of 47 and 54), Bingham at 30 on seed 101 tied (margin 54
//! against 105), `gravity` at 100 tied with `force-offset` (cosine 0.93); (2)
//! the broad spectrum (a 30 s second mode, `E1/E2` 0.005 to 0.017) is named as
//! an in-library effect (`bingham-dashpot` twice, margins 136 and 592 against 2
//! SE of 90 and 109, `stress-thinning`, `partial: force-offset`),
//! a wrong attribution the out-of-library score does not count; (3) `finite-strain`
//! is named `strain-stiffening` (2/2: the tie became a misattribution, the
//! 25 % level did not separate them); (4) the held-out closure of a campaign
//! whose evidence sits in the long trial comes out negative (G_hat -1.5 to
//! -12.8: with that trial held out, a drift or a plateau fitted on the short
//! trials extrapolates over 600 s), so the closure errors are 0.2 to 13.8;
//! (5) on the frozen CI set the strength calibration of `ageing` at lambda 100
//! did not land within 20 % in its 12 evaluations (the test's assertion
//! failed; the six campaigns before it came out `none`, `force-offset`,
//! `machine-compliance`, `none` (thinning at 30), `none`, `bingham-dashpot`);
//! and (6) a campaign cost twice the CPU (first three campaigns of seed 101:
//! 14.1 s user with the four trials, 29.2 s with the six). What it did right:
//! Mullins-type damage came out `partial: strain-stiffening` (2/2 at 100 and
//! 300, flagged; 0/12 with the four trials), `gravity` at 30 and
//! `dual-viscosity` at 30 were named. The
//! `plate-friction` failures (4 of 48) are the known contact that does not
//! settle on the generator's fine mesh, three at t = 0 (trials 1, 3 and the
//! new 25 % trial) and one at 0.11 s (the long hold). A design
//! that keeps the long hold needs a diagnosis that tells a plateau from an
//! offset by the no-contact segments alone (the offset's share there) and a
//! held-out closure that does not extrapolate one trial's drift.
//!
//! **Withheld effects.** In-library: every effect the engine implements
//! ([`EffectId::implemented`], taken from the registry, so new effects join the
//! check as soon as they are implemented; except `adhesion`, see [`full_cycle`]), its nuisance parameters at their
//! registry nulls and its strength coordinates (the diagnoser's
//! [`Candidate`] coordinates: `1/sigma_y` for the slider) at
//! `null + a dir (reference - null)` (the registry's static references,
//! [`Candidate::new`]; the diagnoser's own stress-valued references follow the
//! campaign's peak stress, [`Candidate::at_stress`], and the amplitude `a` is
//! set by the strength anyway), with a unit direction `dir` drawn per
//! campaign (signs free for two-sided coordinates; both coordinates for
//! `force-offset` and `ageing`). Out-of-library ([`OutOfLibrary`]): a broad
//! relaxation spectrum and poroelastic-like drainage, both as a second Voigt
//! element in series (the engine's five-element chain, `E1/E2 = a`) that the
//! diagnoser's three-element model lacks; and Mullins-type damage, the
//! engine's continuum damage law ([`fem_core::material::MullinsDamage`], a
//! material's law and not an effect of the library: the chain acts on
//! `(1 - d) e`, `d = d_inf (1 - exp(-alpha / 0.1))` with `alpha` the largest
//! equivalent strain so far; stress softening on first loading, softer
//! unloading) on the three-element truth, with `d_inf = 0.1 a` up to the law's
//! bound 0.8 ([`MULLINS_STRAIN_C`], [`MULLINS_D_INF_PER_AMPLITUDE`]). The
//! generator sets it on the truth's engine problem (the bundles the diagnoser
//! gets carry no `mullins_*` key). Adding
//! it to [`OutOfLibrary::ALL`] lengthened [`full_cycle`], so the
//! plans of the development seeds below, drawn with the shorter cycle, do not
//! come out of [`plan`] case for case.
//!
//! **Mullins-type damage, measured** (development seeds 101 to 104, the issue's
//! scatter, `cargo run --release -p wagashi-calibrate --example blind_mullins --
//! S 30 100 300` for S = 101 to 104: campaign `i` of the case list at
//! [`campaign_seed`]`(S, i)`, as [`run_blind`] runs it): every campaign reached
//! its strength with three lambda_eff evaluations (`strength_evals`; lambda_eff
//! 30.3 to 30.4, 100.1 to 100.9, 300.0 to 301.1; `d_inf` 0.010, 0.017 to 0.020,
//! 0.033 to 0.037) and all
//! twelve came out `tie` between `finite-strain` and `strain-stiffening`
//! (cosine of their corrections 0.88 to 0.97): flagged `unexplained` or
//! `partial` 0/12. On first loading the damage is a softening that grows with
//! the strain (`(1 - d(e)) e = e - 10 d_inf e^2 + ...`), which both
//! candidates reproduce (finite strain softens in compression; stiffening with
//! `a < 0`); at lambda = 300 the best refit still leaves the push's force cell
//! flagged (held-out closure 0.66 to 0.75), but the verdict's tie rule comes
//! first. What would separate it, the softer unloading and reloading below the
//! largest strain so far, this design shows only in its half withdrawal and
//! release: a second compression of the same sample (the fungi steak's double
//! compression) would. Thresholds were not touched. Each campaign took 3 to 8 s
//! to generate and 10 to 32 s to diagnose.
//!
//! **Strength lambda_eff** (diagnosis-details.md §7.4, §7.8): the chi-square that
//! remains when the best baseline is fitted to the noise-free truth, net of what
//! the same fit leaves without the effect (sample variability, geometry errors and
//! discretisation, the counterpart of the random-effect prior term in §7.4):
//! `lambda_eff(a) = 2 min Phi(truth at a) - 2 min Phi(truth at 0)`, in the noise
//! units the diagnoser will use (its difference-method force sigma estimated on
//! the no-effect truth plus this campaign's noise; the marker sigma). The fit is
//! the diagnoser's own model (its mesh, steps, observation layout) started at the
//! nominal parameters. The amplitude `a` is found by a safeguarded secant on
//! `ln lambda` against `ln a` ([`calibrate_strength`]: a power law through the
//! last two points, bisection in log space once the target is bracketed, at most
//! [`MAX_STRENGTH_EVALS`] evaluations, accepted within 20 % of the target); an
//! effect whose bounds do not reach the target runs at the bound and its realised
//! lambda_eff is what is scored. Every record keeps the target and the realised value.
//!
//! **Scoring** ([`BlindSummary`]): top-1 attribution (the verdict is the effect,
//! or `partial: <effect>`; a `tie` is not an attribution) per effect and
//! target strength; false attribution on null campaigns (any verdict naming an
//! effect); `unexplained` or `partial` on out-of-library campaigns; the
//! gap-closure error `|G_hat - G_true|` on correctly attributed campaigns whose
//! closure is reportable, with `G_true = (lambda_raw - chi2_1) / lambda_eff` from
//! a noise-free refit of the true effect (`chi2_1` its misfit), clipped to
//! [0, 1] (a refit that also absorbs part of the no-effect misfit closes more
//! than the effect's share). `G_true` is an
//! in-sample closure of the effect's share of the gap; `G_hat` the diagnoser's
//! held-out one (each trial anchored on its sample scales, which removes the
//! variability share): the two coincide when the effect acts alike on every
//! trial. The targets are the diagnosis's ([`TARGETS`]).
//!
//! **Determinism.** Campaign `i` of seed `S` draws everything from its own
//! [`SplitMix64`] stream seeded by `S` and `i` ([`campaign_seed`]); the
//! simulations and the diagnosis do not depend on the number of threads. Only the
//! recorded timings vary between runs.

use std::collections::BTreeMap;
use std::time::Instant;

use fem_core::effects::EffectId;
use fem_core::material::{MullinsDamage, MAX_DAMAGE};
use fem_core::press::{simulate_any, AnyPress, Settings};
use rayon::prelude::*;
use wagashi_io::{read_bundle_from_str, Bundle, ForceSample, ForceSeries, MarkerSample, MarkerSeries};

use super::model::{Candidate, Fitting, Model};
use super::{diagnose, diagnosis_model, Diagnosis, DiagnosisError, DiagnosisOptions};
use crate::lsq::levenberg_marquardt;
use crate::rng::SplitMix64;
use crate::trial::Campaign;

/// One trial of the campaign design.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialDesign {
    /// Push duration [s].
    pub push_s: f64,
    /// Hold [s].
    pub hold_s: f64,
    /// Nominal strain (push depth / nominal height).
    pub strain: f64,
    /// Nominal height [mm].
    pub height_mm: f64,
}

/// The four trials of every campaign (module docs).
pub const DESIGN: [TrialDesign; 4] = [
    TrialDesign { push_s: 5.0, hold_s: 10.0, strain: 0.10, height_mm: 15.0 },
    TrialDesign { push_s: 10.0, hold_s: 30.0, strain: 0.20, height_mm: 15.0 },
    TrialDesign { push_s: 2.5, hold_s: 5.0, strain: 0.15, height_mm: 10.0 },
    TrialDesign { push_s: 5.0, hold_s: 20.0, strain: 0.20, height_mm: 10.0 },
];

/// Width and thickness of the block [mm].
const WIDTH_MM: f64 = 20.0;
const THICKNESS_MM: f64 = 10.0;
/// Before contact [s].
const PRE_CONTACT_S: f64 = 2.0;
/// After release [s].
const RECOVERY_S: f64 = 20.0;
/// The nominal material.
const E1_MPA: f64 = 0.05;
const C1_MPA_S: f64 = 0.05;
const C3_MPA_S: f64 = 5.0;
const POISSON: f64 = 0.3;
/// Force noise [N], its quantum [N], the sampling interval [s].
pub const FORCE_SIGMA_N: f64 = 3e-3;
const FORCE_QUANTUM_N: f64 = 1e-3;
const FORCE_DT_S: f64 = 0.1;
/// Marker noise and quantum [mm].
pub const MARKER_SIGMA_MM: f64 = 0.03;
const MARKER_QUANTUM_MM: f64 = 0.01;
/// The generator's element size relative to the diagnoser's `size_mm`: a
/// quarter, finer than the diagnoser's own mesh-correction run (half).
pub const TRUTH_REFINEMENT: f64 = 0.25;
/// Evaluations of lambda_eff allowed per strength calibration.
pub const MAX_STRENGTH_EVALS: usize = 12;
/// Accepted relative distance of the realised lambda_eff from its target.
const STRENGTH_TOLERANCE: f64 = 0.2;

/// The in-library strengths of the blind set.
pub const LAMBDAS: [f64; 3] = [12.0, 30.0, 100.0];
/// The out-of-library strengths.
pub const OUT_OF_LIBRARY_LAMBDAS: [f64; 3] = [30.0, 100.0, 300.0];

/// An out-of-library mechanism (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum OutOfLibrary {
    /// A second, slow retardation mode (tau2 = 30 s against the first's 1 s): a
    /// broader relaxation spectrum than the diagnoser's single Voigt element.
    BroadSpectrum,
    /// A second retardation mode whose time grows with the square of the
    /// specimen's height (tau2 = 5 s (H / 15 mm)^2), as drainage of a poroelastic
    /// gel does (diagnosis-details.md §3, Kalcioglu et al. 2012).
    PoroelasticDrainage,
    /// Mullins-type stress softening: the engine's continuum damage of the chain
    /// ([`fem_core::material::MullinsDamage`]), `d = d_inf (1 - exp(-alpha /`
    /// [`MULLINS_STRAIN_C`]`))` with `alpha` the largest equivalent strain so far.
    MullinsDamage,
}

/// The Mullins damage's characteristic strain: half the design's largest
/// nominal strain, so that the damage still grows over the design's strain
/// levels (10 to 20 %: `d / d_inf` = 0.63 to 0.86) rather than saturating at once.
pub const MULLINS_STRAIN_C: f64 = 0.1;
/// `d_inf` per unit amplitude of the Mullins campaigns (`d_inf = a` times it, up
/// to [`fem_core::material::MAX_DAMAGE`]).
pub const MULLINS_D_INF_PER_AMPLITUDE: f64 = 0.1;

impl OutOfLibrary {
    /// Every generated kind.
    pub const ALL: [OutOfLibrary; 3] =
        [OutOfLibrary::BroadSpectrum, OutOfLibrary::PoroelasticDrainage, OutOfLibrary::MullinsDamage];

    /// Its name in reports.
    pub fn id(self) -> &'static str {
        match self {
            OutOfLibrary::BroadSpectrum => "broad-spectrum",
            OutOfLibrary::PoroelasticDrainage => "poroelastic-drainage",
            OutOfLibrary::MullinsDamage => "mullins-damage",
        }
    }

    /// The second mode's retardation time [s] in a specimen of height `h_mm`
    /// (`None` for the damage, which adds no mode).
    fn tau2_s(self, h_mm: f64) -> Option<f64> {
        match self {
            OutOfLibrary::BroadSpectrum => Some(30.0),
            OutOfLibrary::PoroelasticDrainage => Some(5.0 * (h_mm / 15.0).powi(2)),
            OutOfLibrary::MullinsDamage => None,
        }
    }
}

/// What a campaign withholds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Truth {
    /// Nothing: the baseline plus variability, geometry errors and noise.
    Null,
    /// An effect of the library.
    InLibrary(EffectId),
    /// A mechanism outside the library.
    OutOfLibrary(OutOfLibrary),
}

impl Truth {
    /// Its name in reports: the effect id, `none`, or the out-of-library kind.
    pub fn name(&self) -> &'static str {
        match self {
            Truth::Null => "none",
            Truth::InLibrary(e) => e.id(),
            Truth::OutOfLibrary(o) => o.id(),
        }
    }

    /// The kind: `in-library`, `null` or `out-of-library`.
    pub fn kind(&self) -> &'static str {
        match self {
            Truth::Null => "null",
            Truth::InLibrary(_) => "in-library",
            Truth::OutOfLibrary(_) => "out-of-library",
        }
    }
}

/// A campaign to generate: what it withholds and at which target lambda_eff.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Case {
    /// The withheld mechanism.
    pub truth: Truth,
    /// Target lambda_eff (0 for a null campaign).
    pub lambda: f64,
}

/// The cases of one full cycle: every implemented effect at every strength of
/// [`LAMBDAS`], one null campaign per implemented effect, and every
/// out-of-library kind at every strength of [`OUT_OF_LIBRARY_LAMBDAS`].
pub fn full_cycle() -> Vec<Case> {
    // Adhesion is withheld from the check: the design never pulls on the
    // specimen. Its plate withdraws to half the depth before the release, and the
    // nominal trials still press there (measured with `wagashi press` on the four
    // nominal trials, 5 mm elements: the force in the withdrawal stays above 3 to
    // 14 % of the peak, 0.073 N at the least), so no bond is ever loaded and no
    // strength reaches any lambda. Eliciting adhesion needs a pull-off (a plate
    // rising faster than the specimen recovers), where the baseline's
    // constrained plate, bilateral until `release_s`, would itself pull: that
    // trial needs the unilateral plate as the baseline (fem_core::effects,
    // "Nesting caveat").
    let effects: Vec<EffectId> =
        EffectId::ALL.into_iter().filter(|e| e.implemented() && *e != EffectId::Adhesion).collect();
    let mut cases = Vec::new();
    for &e in &effects {
        for &lambda in &LAMBDAS {
            cases.push(Case { truth: Truth::InLibrary(e), lambda });
        }
    }
    for _ in &effects {
        cases.push(Case { truth: Truth::Null, lambda: 0.0 });
    }
    for o in OutOfLibrary::ALL {
        for &lambda in &OUT_OF_LIBRARY_LAMBDAS {
            cases.push(Case { truth: Truth::OutOfLibrary(o), lambda });
        }
    }
    cases
}

/// The `n` campaigns of seed `seed`: full cycles ([`full_cycle`]), each shuffled
/// by the seed, one after the other, cut at `n`.
pub fn plan(n: usize, seed: u64) -> Vec<Case> {
    let mut rng = SplitMix64::new(seed ^ 0x0b11_d0c0_ffee);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let mut cycle = full_cycle();
        rng.shuffle(&mut cycle);
        out.extend(cycle.into_iter().take(n - out.len()));
    }
    out
}

/// The seed of campaign `index` of a blind run of seed `seed`.
pub fn campaign_seed(seed: u64, index: usize) -> u64 {
    let mut rng = SplitMix64::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (index as u64 + 1));
    rng.next_u64()
}

/// What one generated campaign is made of (for the record).
#[derive(Debug, Clone)]
pub struct Generated {
    /// The measured bundles the diagnoser gets.
    pub bundles: Vec<Bundle>,
    /// Sample-to-sample variability (log-sd) of the campaign.
    pub variability: f64,
    /// Per trial: (modulus scale, viscosity scale).
    pub sample_scales: Vec<[f64; 2]>,
    /// Per trial: relative errors of (W, H, T).
    pub geometry_errors: Vec<[f64; 3]>,
    /// Per trial: the force noise's lag-1 correlation.
    pub force_rho: Vec<f64>,
    /// Per trial: the diagnoser's force sigma [N] ([`super::model::force_noise_model`]).
    pub force_sigma_hat_n: Vec<f64>,
    /// Per trial: the diagnoser's lag-1 force-noise correlation.
    pub force_rho_hat: Vec<f64>,
    /// The withheld effect's bundle keys and values (in-library), the second
    /// mode's `E1/E2` or the damage's `mullins_d_inf` and `mullins_strain_c`
    /// (out-of-library); empty for a null campaign.
    pub strength: Vec<(String, f64)>,
    /// The amplitude `a` (module docs).
    pub amplitude: f64,
    /// Realised lambda_eff.
    pub lambda_eff: f64,
    /// `2 min Phi` of the baseline on the noise-free truth with the effect.
    pub lambda_raw: f64,
    /// The same without the effect.
    pub lambda_null: f64,
    /// lambda_eff evaluations spent on the strength.
    pub strength_evals: usize,
    /// Whether the target was reached within 20 %.
    pub reached: bool,
}

/// Why a blind run stopped.
pub type BlindError = DiagnosisError;

/// What the generator puts between the samples and the nominal specimen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scatter {
    /// Range of the campaign's sample-to-sample log-sd (drawn uniformly in it).
    pub variability: [f64; 2],
    /// Relative standard deviation of each true dimension from the nominal one
    /// (clipped at three of them).
    pub geometry_sd: f64,
}

impl Scatter {
    /// The blind set's generator: variability 3 to 10 %, geometry errors 0.5 %.
    pub const ISSUE: Scatter = Scatter { variability: [0.03, 0.10], geometry_sd: 0.005 };
    /// Ideal samples: every sample the nominal material and geometry (the other
    /// differences from the diagnoser stay). The diagnoser has no per-sample
    /// scales in its calibration yet (mod.rs, "Not done here"), so this is the
    /// setting in which the rest of it can be checked.
    pub const IDEAL: Scatter = Scatter { variability: [0.0, 0.0], geometry_sd: 0.0 };
}

/// Everything drawn for one campaign before any simulation.
struct Draws {
    variability: f64,
    scales: Vec<[f64; 2]>,
    geometry: Vec<[f64; 3]>,
    rho: Vec<f64>,
    /// Per trial: the force noise at each sample [N].
    force_noise: Vec<Vec<f64>>,
    /// Per trial, marker, sample, component: the marker noise [mm].
    marker_noise: Vec<Vec<Vec<[f64; 2]>>>,
    age_h: Vec<f64>,
    /// The direction of the withheld effect's strength coordinates.
    direction: Vec<f64>,
}

/// (end of the push, the release time, the end) [s]; the tool withdraws to half
/// the depth over half the push duration before it lets go at the release time.
fn protocol_times(d: &TrialDesign) -> (f64, f64, f64) {
    let push_end = PRE_CONTACT_S + d.push_s;
    let release = push_end + d.hold_s + 0.5 * d.push_s;
    (push_end, release, release + RECOVERY_S)
}

/// Marker sample times: t = 0, eight during the hold, ten during the recovery.
fn marker_times(d: &TrialDesign) -> Vec<f64> {
    let (push_end, release, end) = protocol_times(d);
    let mut t = vec![0.0];
    let hold_end = push_end + d.hold_s;
    t.extend((1..=8).map(|i| push_end + (hold_end - push_end) * i as f64 / 8.0));
    t.extend((1..=10).map(|i| release + (end - release) * i as f64 / 10.0));
    t
}

/// Relative marker places (x / W, y / H).
const MARKERS: [[f64; 2]; 5] = [[1.0, 0.25], [1.0, 0.5], [1.0, 0.75], [0.25, 1.0], [0.5, 1.0]];

fn draws(case: &Case, seed: u64, scatter: &Scatter) -> Draws {
    // The same stream in every scatter setting: only the scales change.
    let mut rng = SplitMix64::new(seed);
    let [lo, hi] = scatter.variability;
    let variability = lo + (hi - lo) * rng.next_f64();
    let g = scatter.geometry_sd;
    let scales = DESIGN
        .iter()
        .map(|_| [(variability * rng.next_gaussian()).exp(), (variability * rng.next_gaussian()).exp()])
        .collect();
    let geometry =
        DESIGN.iter().map(|_| [0; 3].map(|_: i32| (g * rng.next_gaussian()).clamp(-3.0 * g, 3.0 * g))).collect();
    let rho: Vec<f64> = DESIGN.iter().map(|_| 0.3 + 0.4 * rng.next_f64()).collect();
    let force_noise = DESIGN
        .iter()
        .zip(&rho)
        .map(|(d, &r)| {
            let n = (protocol_times(d).2 / FORCE_DT_S).round() as usize + 1;
            let mut e = FORCE_SIGMA_N * rng.next_gaussian();
            (0..n)
                .map(|i| {
                    if i > 0 {
                        e = r * e + (1.0 - r * r).sqrt() * FORCE_SIGMA_N * rng.next_gaussian();
                    }
                    e
                })
                .collect()
        })
        .collect();
    let marker_noise = DESIGN
        .iter()
        .map(|d| {
            let n = marker_times(d).len();
            MARKERS
                .iter()
                .map(|_| {
                    (0..n)
                        .map(|_| [MARKER_SIGMA_MM * rng.next_gaussian(), MARKER_SIGMA_MM * rng.next_gaussian()])
                        .collect()
                })
                .collect()
        })
        .collect();
    let mut order: Vec<usize> = (0..DESIGN.len()).collect();
    rng.shuffle(&mut order);
    let mut age_h = vec![0.0; DESIGN.len()];
    for (rank, &k) in order.iter().enumerate() {
        age_h[k] = 0.5 + rank as f64;
    }
    let direction = match case.truth {
        Truth::InLibrary(effect) => {
            let c = Candidate::new(effect);
            let mut v: Vec<f64> = c
                .coords
                .iter()
                .map(|coord| {
                    let g = rng.next_gaussian();
                    if coord.one_sided() {
                        g.abs().max(0.05)
                    } else {
                        g
                    }
                })
                .collect();
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300);
            v.iter_mut().for_each(|x| *x /= norm);
            v
        }
        _ => Vec::new(),
    };
    Draws { variability, scales, geometry, rho, force_noise, marker_noise, age_h, direction }
}

/// The text of a trial's `experiment.toml`.
fn experiment_toml(name: &str, d: &TrialDesign, size: [f64; 3], material: &str, effects: &str) -> String {
    let (push_end, release, end) = protocol_times(d);
    let depth = d.strain * d.height_mm;
    let (hold_end, half) = (push_end + d.hold_s, 0.5 * d.strain * d.height_mm);
    let [w, h, t] = size;
    format!(
        r#"format = "wagashi-experiment/1"
name = "{name}"
dimension = 2

[specimen]
shape = "block"
size_mm = [{w}, {h}, {t}]
density_g_cm3 = 1.1
material = "gel"

[materials.gel]
{material}
[protocol]
tool = "plate"
tool_contact = "frictionless"
support = "glued"
waypoints = [[0.0, 0.0], [{PRE_CONTACT_S}, 0.0], [{push_end}, {depth}], [{hold_end}, {depth}], [{release}, {half}]]
release_s = {release}
end_s = {end}

[effects]
{effects}"#
    )
}

fn bundle(text: &str) -> Result<Bundle, DiagnosisError> {
    Ok(read_bundle_from_str("/nonexistent/blind", text, &BTreeMap::new())?)
}

/// The strength of a campaign at amplitude `a`.
#[derive(Debug, Clone)]
enum Strength {
    None,
    /// Effect values in registry order.
    Effect(EffectId, Vec<f64>),
    /// `E1 / E2` of the second mode.
    Mode(OutOfLibrary, f64),
    /// `d_inf` of the Mullins damage.
    Damage(f64),
}

impl Strength {
    fn of(case: &Case, direction: &[f64], a: f64) -> Self {
        match case.truth {
            Truth::Null => Strength::None,
            Truth::InLibrary(effect) => {
                let c = Candidate::new(effect);
                let u: Vec<f64> = c
                    .coords
                    .iter()
                    .zip(direction)
                    .map(|(coord, &d)| {
                        let [lo, hi] = coord.bounds();
                        (coord.null() + a * d * (coord.reference() - coord.null())).clamp(lo, hi)
                    })
                    .collect();
                Strength::Effect(effect, c.values(&u))
            }
            Truth::OutOfLibrary(OutOfLibrary::MullinsDamage) => Strength::Damage(a * MULLINS_D_INF_PER_AMPLITUDE),
            Truth::OutOfLibrary(o) => Strength::Mode(o, a),
        }
    }

    fn record(&self) -> Vec<(String, f64)> {
        match self {
            Strength::None => Vec::new(),
            Strength::Effect(e, v) => e.params().iter().zip(v).map(|(p, &x)| (p.key.to_string(), x)).collect(),
            Strength::Mode(_, x) => vec![("E1_over_E2".to_string(), *x)],
            Strength::Damage(d) => {
                vec![("mullins_d_inf".to_string(), *d), ("mullins_strain_c".to_string(), MULLINS_STRAIN_C)]
            }
        }
    }
}

/// The largest amplitude the coordinates' bounds allow (infinite if none binds).
fn max_amplitude(case: &Case, direction: &[f64]) -> f64 {
    match case.truth {
        Truth::InLibrary(effect) => {
            let c = Candidate::new(effect);
            c.coords
                .iter()
                .zip(direction)
                .map(|(coord, &d)| {
                    let step = d * (coord.reference() - coord.null());
                    let [lo, hi] = coord.bounds();
                    let room = if step > 0.0 { hi - coord.null() } else { coord.null() - lo };
                    if step == 0.0 {
                        f64::INFINITY
                    } else {
                        room / step.abs()
                    }
                })
                .fold(f64::INFINITY, f64::min)
        }
        Truth::OutOfLibrary(OutOfLibrary::MullinsDamage) => MAX_DAMAGE / MULLINS_D_INF_PER_AMPLITUDE,
        _ => f64::INFINITY,
    }
}

/// The truth of trial `k` at `strength`, simulated on the generator's mesh and
/// steps: (force at the sample times [N], marker positions per marker and sample).
type TruthRun = (Vec<f64>, Vec<Vec<[f64; 2]>>);

fn simulate_truth(k: usize, draws: &Draws, strength: &Strength, size_mm: f64) -> Result<TruthRun, DiagnosisError> {
    let d = &DESIGN[k];
    let [sw, sh, st] = draws.geometry[k];
    let size = [WIDTH_MM * (1.0 + sw), d.height_mm * (1.0 + sh), THICKNESS_MM * (1.0 + st)];
    let [se, sc] = draws.scales[k];
    let (e1, c1, c3) = (E1_MPA * se, C1_MPA_S * sc, C3_MPA_S * sc);
    let mut effects = format!("age_h = {}\n", draws.age_h[k]);
    let material = match strength {
        Strength::Mode(o, x) if *x > 0.0 && o.tau2_s(size[1]).is_some() => {
            let e2 = e1 / x;
            let c2 = e2 * o.tau2_s(size[1]).unwrap_or(0.0);
            format!(
                "model = \"five-element\"\npoisson = {POISSON}\nE1_MPa = {e1}\nE2_MPa = {e2}\nc1_MPa_s = {c1}\n\
                 c2_MPa_s = {c2}\nc3_MPa_s = {c3}\n"
            )
        }
        _ => {
            format!("model = \"three-element\"\npoisson = {POISSON}\nE1_MPa = {e1}\nc1_MPa_s = {c1}\nc3_MPa_s = {c3}\n")
        }
    };
    if let Strength::Effect(e, values) = strength {
        for (p, v) in e.params().iter().zip(values) {
            if v.is_finite() {
                effects.push_str(&format!("{} = {v:e}\n", p.key));
            }
        }
    }
    let mut truth = bundle(&experiment_toml("truth", d, size, &material, &effects))?;
    let times = marker_times(d);
    truth.markers = MARKERS
        .iter()
        .enumerate()
        .map(|(m, [fx, fy])| MarkerSeries {
            name: format!("m{m}"),
            samples: times
                .iter()
                .map(|&t| MarkerSample { t_s: t, position_mm: vec![fx * size[0], fy * size[1]] })
                .collect(),
        })
        .collect();
    let mut problem = truth.to_press(size_mm)?;
    if let Strength::Damage(d_inf) = *strength {
        // The engine's damage law on the chain of every region (not a bundle key).
        let law = MullinsDamage::new(d_inf, MULLINS_STRAIN_C).map_err(|e| {
            DiagnosisError::Input(format!("blind generator, trial {k}: Mullins damage d_inf = {d_inf}: {e}"))
        })?;
        let materials = match &mut problem {
            AnyPress::Plane(p) => &mut p.materials,
            AnyPress::Solid(p) => &mut p.materials,
            AnyPress::Axisymmetric(p) => &mut p.materials,
        };
        materials.iter_mut().for_each(|m| m.damage = Some(law));
    }
    let settings = Settings { rtol: 1e-5, max_dt_s: Some(0.2), ..Settings::default() };
    let result = simulate_any(&problem, &settings, &mut |_| {})
        .map_err(|e| DiagnosisError::Input(format!("blind generator, trial {k}: the truth does not run: {e}")))?;
    let n = draws.force_noise[k].len();
    let force = (0..n).map(|i| result.bottom_force_at(i as f64 * FORCE_DT_S)).collect();
    let markers =
        result.markers.iter().map(|track| track.samples.iter().map(|(_, p)| [p[0], p[1]]).collect()).collect();
    Ok((force, markers))
}

fn quantise(x: f64, q: f64) -> f64 {
    (x / q).round() * q
}

/// The measured bundles of the truth runs, with the campaign's noise when `noisy`.
fn measured(draws: &Draws, runs: &[TruthRun], noisy: bool) -> Result<Vec<Bundle>, DiagnosisError> {
    DESIGN
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let size = [WIDTH_MM, d.height_mm, THICKNESS_MM];
            let material = format!("model = \"three-element\"\npoisson = {POISSON}\n");
            let effects = format!("age_h = {}\n", draws.age_h[k]);
            let mut b = bundle(&experiment_toml(&format!("trial{k}"), d, size, &material, &effects))?;
            let (force, markers) = &runs[k];
            let samples = force
                .iter()
                .enumerate()
                .map(|(i, &f)| {
                    let value = if noisy { quantise(f + draws.force_noise[k][i], FORCE_QUANTUM_N) } else { f };
                    ForceSample { t_s: i as f64 * FORCE_DT_S, force_n: value }
                })
                .collect();
            b.force = Some(ForceSeries { samples });
            let times = marker_times(d);
            b.markers = markers
                .iter()
                .enumerate()
                .map(|(m, track)| MarkerSeries {
                    name: format!("m{m}"),
                    samples: track
                        .iter()
                        .zip(&times)
                        .enumerate()
                        .map(|(i, (p, &t))| {
                            let position_mm = if noisy {
                                let e = draws.marker_noise[k][m][i];
                                vec![quantise(p[0] + e[0], MARKER_QUANTUM_MM), quantise(p[1] + e[1], MARKER_QUANTUM_MM)]
                            } else {
                                vec![p[0], p[1]]
                            };
                            MarkerSample { t_s: t, position_mm }
                        })
                        .collect(),
                })
                .collect();
            Ok(b)
        })
        .collect()
}

/// The diagnoser's model of `bundles` with the force noise fixed to `noise`
/// (`(sigma, rho)` per trial).
fn noise_free_model(
    bundles: &[Bundle],
    noise: &[(f64, f64)],
    options: &DiagnosisOptions,
) -> Result<(Model, Vec<f64>, Option<Model>), DiagnosisError> {
    let campaign = Campaign::new(bundles, &BTreeMap::new(), options.size_mm, options.axisymmetric)?;
    let mut model = diagnosis_model(bundles, &campaign, options, 1.0)?;
    for (t, &(s, rho)) in model.trials.iter_mut().zip(noise) {
        t.force_sigma_n = s;
        t.force_rho = rho;
    }
    model.sample_scale_sd = options.sample_scale_sd.max(0.0);
    let mut x0: Vec<f64> = campaign
        .unknowns
        .iter()
        .zip(campaign.values())
        .map(|(u, v)| match u.key {
            "E1_MPa" => E1_MPA,
            "c1_MPa_s" => C1_MPA_S,
            "c3_MPa_s" => C3_MPA_S,
            _ => v,
        })
        .collect();
    x0.resize(model.num_theta(), 0.0);
    let fine = if options.mesh_correction {
        let mut f = diagnosis_model(bundles, &campaign, options, 0.5)?;
        model.set_mesh_correction(&mut f, &x0)?;
        Some(f)
    } else {
        None
    };
    Ok((model, x0, fine))
}

/// `2 min Phi` of the baseline on noise-free `bundles`, and the fitted parameters.
fn baseline_misfit(
    bundles: &[Bundle],
    noise: &[(f64, f64)],
    options: &DiagnosisOptions,
) -> Result<(f64, Vec<f64>), DiagnosisError> {
    let (mut model, x0, fine) = noise_free_model(bundles, noise, options)?;
    let mut fit = {
        let problem = Fitting { model: &model, candidate: None };
        levenberg_marquardt(&problem, &problem.specs(), &x0, &options.lsq)?
    };
    // As the diagnoser: the mesh correction again at the fit, and a polish.
    if let Some(mut f) = fine {
        model.set_mesh_correction(&mut f, &fit.x)?;
        let problem = Fitting { model: &model, candidate: None };
        fit = levenberg_marquardt(&problem, &problem.specs(), &fit.x, &options.lsq)?;
    }
    Ok((2.0 * fit.objective, fit.x))
}

/// The truth runs of every trial at `strength` (trials in parallel; each run is
/// deterministic).
fn truth_runs(draws: &Draws, strength: &Strength, size_mm: f64) -> Result<Vec<TruthRun>, DiagnosisError> {
    (0..DESIGN.len()).into_par_iter().map(|k| simulate_truth(k, draws, strength, size_mm)).collect()
}

/// Solves `lambda(a) = target` for `a` in `(0, a_max]` (module docs). Returns
/// `(a, lambda(a), evaluations, reached)`; `eval` gives lambda_eff.
pub fn calibrate_strength(
    target: f64,
    a_max: f64,
    mut eval: impl FnMut(f64) -> Result<f64, DiagnosisError>,
) -> Result<(f64, f64, usize, bool), DiagnosisError> {
    let close = |l: f64| (l / target).ln().abs() < (1.0 + STRENGTH_TOLERANCE).ln();
    let mut points: Vec<(f64, f64)> = Vec::new();
    let mut a = 1.0_f64.min(a_max);
    for evals in 1..=MAX_STRENGTH_EVALS {
        let l = eval(a)?;
        points.push((a, l));
        if l > 0.0 && close(l) {
            return Ok((a, l, evals, true));
        }
        if l < target && a >= a_max {
            return Ok((a, l, evals, false));
        }
        let below = points.iter().filter(|p| p.1 < target).max_by(|x, y| x.0.total_cmp(&y.0));
        let above = points.iter().filter(|p| p.1 > target).min_by(|x, y| x.0.total_cmp(&y.0));
        let next = match (below, above) {
            // Bracketed by a point below the effect's threshold: bisection in ln a.
            (Some(&(a0, l0)), Some(&(a1, _))) if l0 <= 0.0 => (a0 * a1).sqrt(),
            (Some(&(a0, l0)), Some(&(a1, l1))) => {
                // Bracketed: the power law through the bracket, kept inside it.
                let p = (l1 / l0).ln() / (a1 / a0).ln();
                let guess = a0 * (target / l0).powf(1.0 / p.max(1e-3));
                let (lo, hi) = (a0.ln(), a1.ln());
                let g = guess.ln();
                if g.is_finite() && g > lo + 0.05 * (hi - lo) && g < hi - 0.05 * (hi - lo) {
                    guess
                } else {
                    (0.5 * (lo + hi)).exp()
                }
            }
            _ if l <= 1e-9 * target.max(1.0) => a * 10.0,
            _ => {
                // One side only: a power law, slope from the last two positive
                // points (2, the quadratic regime, with one), limited to [0.5, 4].
                let positive: Vec<&(f64, f64)> = points.iter().filter(|p| p.1 > 0.0).collect();
                let p = match positive.as_slice() {
                    [.., x, y] if (y.0 / x.0).ln().abs() > 1e-9 => {
                        ((y.1 / x.1).ln() / (y.0 / x.0).ln()).clamp(0.5, 4.0)
                    }
                    _ => 2.0,
                };
                let step = (target / l).powf(1.0 / p).clamp(1e-3, 1e3);
                a * step
            }
        };
        a = next.min(a_max);
    }
    let best = points
        .iter()
        .min_by(|x, y| (x.1 / target).ln().abs().total_cmp(&(y.1 / target).ln().abs()))
        .copied()
        .unwrap_or((a, 0.0));
    Ok((best.0, best.1, MAX_STRENGTH_EVALS, false))
}

/// Generates campaign `case` from `seed` (module docs).
pub fn generate(
    case: &Case,
    seed: u64,
    scatter: &Scatter,
    options: &DiagnosisOptions,
) -> Result<Generated, DiagnosisError> {
    let size = options.size_mm.ok_or_else(|| DiagnosisError::Input("the blind check needs an element size".into()))?;
    let truth_size = TRUTH_REFINEMENT * size;
    let draws = draws(case, seed, scatter);
    let null_runs = truth_runs(&draws, &Strength::None, truth_size)?;
    let noisy_null = measured(&draws, &null_runs, true)?;
    let noise: Vec<(f64, f64)> = noisy_null
        .iter()
        .map(|b| {
            let (_, sigma, rho) = super::model::force_noise_model(b);
            (sigma, rho)
        })
        .collect();
    let (lambda_null, _) = baseline_misfit(&measured(&draws, &null_runs, false)?, &noise, options)?;
    let lambda_of = |a: f64| -> Result<(f64, Vec<TruthRun>), DiagnosisError> {
        let runs = truth_runs(&draws, &Strength::of(case, &draws.direction, a), truth_size)?;
        let (raw, _) = baseline_misfit(&measured(&draws, &runs, false)?, &noise, options)?;
        Ok((raw, runs))
    };
    let (amplitude, lambda_raw, evals, reached, runs) = if matches!(case.truth, Truth::Null) {
        (0.0, lambda_null, 0, true, null_runs)
    } else {
        let a_max = max_amplitude(case, &draws.direction);
        let (a, _, evals, reached) = calibrate_strength(case.lambda, a_max, |a| Ok(lambda_of(a)?.0 - lambda_null))?;
        let (raw, runs) = lambda_of(a)?;
        (a, raw, evals + 1, reached, runs)
    };
    let strength = Strength::of(case, &draws.direction, amplitude);
    Ok(Generated {
        bundles: measured(&draws, &runs, true)?,
        variability: draws.variability,
        sample_scales: draws.scales.clone(),
        geometry_errors: draws.geometry.clone(),
        force_rho: draws.rho.clone(),
        force_sigma_hat_n: noise.iter().map(|n| n.0).collect(),
        force_rho_hat: noise.iter().map(|n| n.1).collect(),
        strength: strength.record(),
        amplitude,
        lambda_eff: lambda_raw - lambda_null,
        lambda_raw,
        lambda_null,
        strength_evals: evals,
        reached,
    })
}

/// The true gap closure of `effect` on the noise-free campaign `case`/`seed`
/// (module docs): the refit of the effect from its true coordinates.
fn true_closure(
    case: &Case,
    seed: u64,
    scatter: &Scatter,
    gen: &Generated,
    options: &DiagnosisOptions,
) -> Result<f64, DiagnosisError> {
    let Truth::InLibrary(effect) = case.truth else {
        return Ok(f64::NAN);
    };
    let size = options.size_mm.unwrap_or(5.0);
    let draws = draws(case, seed, scatter);
    let strength = Strength::of(case, &draws.direction, gen.amplitude);
    let runs = truth_runs(&draws, &strength, TRUTH_REFINEMENT * size)?;
    let bundles = measured(&draws, &runs, false)?;
    let noise: Vec<(f64, f64)> = gen.force_sigma_hat_n.iter().copied().zip(gen.force_rho_hat.iter().copied()).collect();
    let (model, x0, _) = noise_free_model(&bundles, &noise, options)?;
    let candidate = Candidate::new(effect);
    let problem = Fitting { model: &model, candidate: Some(&candidate) };
    let mut x = x0;
    for (c, &d) in candidate.coords.iter().zip(&draws.direction) {
        let [lo, hi] = c.bounds();
        x.push((c.null() + gen.amplitude * d * (c.reference() - c.null())).clamp(lo, hi));
    }
    let chi2_1 = match levenberg_marquardt(&problem, &problem.specs(), &x, &options.lsq) {
        Ok(f) => (2.0 * f.objective).min(gen.lambda_raw),
        Err(_) => return Ok(f64::NAN),
    };
    // The effect closes at most its own share: a refit that also absorbs part of
    // the no-effect misfit (discretisation) counts as a full closure.
    Ok(((gen.lambda_raw - chi2_1) / gen.lambda_eff.max(1e-12)).clamp(0.0, 1.0))
}

/// One scored campaign.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Its index in the run.
    pub index: usize,
    /// Its seed.
    pub seed: u64,
    /// What it withheld.
    pub case: Case,
    /// The generator's record.
    pub generated: Generated,
    /// The verdict's label.
    pub label: String,
    /// The effects it named.
    pub named: Vec<crate::diagnosis::CandidateId>,
    /// The top-1 column of the confusion matrix: the first named effect's id
    /// (effect or `partial`), or the label (`tie`, `unexplained`, `none`).
    pub column: String,
    /// In-library: the verdict is the effect or `partial: effect`.
    pub top1: bool,
    /// The diagnoser's gap closure of the named effect (reportable only).
    pub closure_hat: Option<f64>,
    /// The true closure (correct in-library attributions).
    pub closure_true: Option<f64>,
    /// The verdict's tie rule, when two candidates were eligible.
    pub tie_test: Option<super::TieTest>,
    /// Seconds spent generating (strength calibration and truth runs).
    pub generate_s: f64,
    /// Seconds spent diagnosing.
    pub diagnose_s: f64,
    /// Seconds spent on the true closure.
    pub score_s: f64,
}

/// The column of a verdict (see [`Outcome::column`]).
fn column_of(d: &Diagnosis) -> String {
    if d.verdict.label == "tie" || d.verdict.label == "none" || d.verdict.label == "unexplained" {
        d.verdict.label.clone()
    } else {
        d.verdict.effects.first().map_or_else(|| d.verdict.label.clone(), |e| e.id().to_string())
    }
}

/// Generates, diagnoses and scores campaign `index` of `case` with `seed`.
pub fn run_case(
    index: usize,
    case: &Case,
    seed: u64,
    scatter: &Scatter,
    options: &DiagnosisOptions,
) -> Result<(Outcome, Diagnosis), DiagnosisError> {
    let t0 = Instant::now();
    let generated = generate(case, seed, scatter, options)?;
    let t1 = Instant::now();
    let diagnosis = diagnose(&generated.bundles, &[], &BTreeMap::new(), options, &|_, _, _| {})?;
    let t2 = Instant::now();
    let column = column_of(&diagnosis);
    let label = diagnosis.verdict.label.clone();
    let top1 = match case.truth {
        Truth::InLibrary(e) => label == e.id() || label == format!("partial: {}", e.id()),
        _ => false,
    };
    let named = diagnosis.verdict.effects.clone();
    let closure_hat = named
        .first()
        .and_then(|e| diagnosis.candidate(*e))
        .and_then(|c| c.heldout.as_ref())
        .filter(|h| h.reportable)
        .map(|h| h.closure);
    let closure_true = if top1 && closure_hat.is_some() {
        Some(true_closure(case, seed, scatter, &generated, options)?).filter(|g| g.is_finite())
    } else {
        None
    };
    let t3 = Instant::now();
    let outcome = Outcome {
        index,
        seed,
        case: *case,
        generated,
        label,
        named,
        column,
        top1,
        closure_hat,
        closure_true,
        tie_test: diagnosis.verdict.tie_test.clone(),
        generate_s: (t1 - t0).as_secs_f64(),
        diagnose_s: (t2 - t1).as_secs_f64(),
        score_s: (t3 - t2).as_secs_f64(),
    };
    Ok((outcome, diagnosis))
}

/// A rate with its counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rate {
    /// Successes.
    pub hits: usize,
    /// Cases.
    pub total: usize,
}

impl Rate {
    /// `hits / total` (NaN with no case).
    pub fn value(&self) -> f64 {
        if self.total == 0 {
            f64::NAN
        } else {
            self.hits as f64 / self.total as f64
        }
    }
}

/// A target of the diagnosis and whether it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetCheck {
    /// What is measured.
    pub metric: &'static str,
    /// `>=` or `<=`.
    pub relation: &'static str,
    /// The threshold.
    pub threshold: f64,
    /// The measured value (NaN with no case).
    pub value: f64,
    /// Cases behind it.
    pub cases: usize,
    /// Whether it holds (false with no case).
    pub holds: bool,
}

/// The diagnosis's targets: (metric, relation, threshold).
pub const TARGETS: [(&str, &str, f64); 5] = [
    ("top-1 attribution, lambda >= 30", ">=", 0.90),
    ("top-1 attribution, lambda = 12", ">=", 0.60),
    ("false attribution on null campaigns", "<=", 0.05),
    ("out-of-library flagged unexplained or partial, lambda >= 30", ">=", 0.80),
    ("median gap-closure error, lambda >= 30", "<=", 0.10),
];

/// The scores of a blind run.
#[derive(Debug, Clone, PartialEq)]
pub struct BlindSummary {
    /// Top-1 attribution per (effect id, target lambda).
    pub top1: BTreeMap<(String, u32), Rate>,
    /// Top-1 attribution per target lambda, over every in-library effect.
    pub top1_by_lambda: BTreeMap<u32, Rate>,
    /// Null campaigns naming an effect.
    pub false_attribution: Rate,
    /// Null campaigns claiming any gap (label other than `none`).
    pub any_gap_on_null: Rate,
    /// Out-of-library campaigns (target lambda >= 30) labelled `unexplained` or `partial: ...`.
    pub out_of_library_flagged: Rate,
    /// `|G_hat - G_true|` of correctly attributed campaigns at lambda >= 30.
    pub closure_errors: Vec<f64>,
    /// Confusion matrix: truth name -> column -> count.
    pub confusion: BTreeMap<String, BTreeMap<String, usize>>,
    /// The targets.
    pub targets: Vec<TargetCheck>,
}

fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// Scores `outcomes` (module docs).
pub fn summarise(outcomes: &[Outcome]) -> BlindSummary {
    let mut top1: BTreeMap<(String, u32), Rate> = BTreeMap::new();
    let mut by_lambda: BTreeMap<u32, Rate> = BTreeMap::new();
    let mut false_attribution = Rate { hits: 0, total: 0 };
    let mut any_gap = Rate { hits: 0, total: 0 };
    let mut ool = Rate { hits: 0, total: 0 };
    let mut closure_errors = Vec::new();
    let mut confusion: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    for o in outcomes {
        *confusion.entry(o.case.truth.name().to_string()).or_default().entry(o.column.clone()).or_default() += 1;
        let lambda = o.case.lambda.round() as u32;
        match o.case.truth {
            Truth::InLibrary(e) => {
                for r in [
                    top1.entry((e.id().to_string(), lambda)).or_insert(Rate { hits: 0, total: 0 }),
                    by_lambda.entry(lambda).or_insert(Rate { hits: 0, total: 0 }),
                ] {
                    r.total += 1;
                    r.hits += usize::from(o.top1);
                }
                if lambda >= 30 {
                    if let (Some(h), Some(t)) = (o.closure_hat, o.closure_true) {
                        closure_errors.push((h - t).abs());
                    }
                }
            }
            Truth::Null => {
                false_attribution.total += 1;
                any_gap.total += 1;
                false_attribution.hits += usize::from(!o.named.is_empty());
                any_gap.hits += usize::from(o.label != "none");
            }
            Truth::OutOfLibrary(_) => {
                if lambda >= 30 {
                    ool.total += 1;
                    ool.hits += usize::from(o.label == "unexplained" || o.label.starts_with("partial:"));
                }
            }
        }
    }
    let high = by_lambda
        .iter()
        .filter(|(l, _)| **l >= 30)
        .fold(Rate { hits: 0, total: 0 }, |a, (_, r)| Rate { hits: a.hits + r.hits, total: a.total + r.total });
    let low = by_lambda.get(&12).copied().unwrap_or(Rate { hits: 0, total: 0 });
    let values = [
        (high.value(), high.total),
        (low.value(), low.total),
        (false_attribution.value(), false_attribution.total),
        (ool.value(), ool.total),
        (median(&closure_errors), closure_errors.len()),
    ];
    let targets = TARGETS
        .iter()
        .zip(values)
        .map(|(&(metric, relation, threshold), (value, cases))| TargetCheck {
            metric,
            relation,
            threshold,
            value,
            cases,
            holds: cases > 0 && if relation == ">=" { value >= threshold } else { value <= threshold },
        })
        .collect();
    BlindSummary {
        top1,
        top1_by_lambda: by_lambda,
        false_attribution,
        any_gap_on_null: any_gap,
        out_of_library_flagged: ool,
        closure_errors,
        confusion,
        targets,
    }
}

/// A campaign that could not be generated or diagnosed (it is not scored, and
/// is reported).
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// Its index in the run.
    pub index: usize,
    /// Its seed.
    pub seed: u64,
    /// What it withheld.
    pub case: Case,
    /// Why, in words (the error and its sources).
    pub error: String,
}

/// Runs `cases` (campaign `i` with seed [`campaign_seed`]`(seed, i)`), one after
/// the other (each diagnosis is parallel inside); `progress(done, total, what)`
/// after each. A campaign whose truth does not run or whose diagnosis fails is
/// listed among the failures and the run goes on.
pub fn run_blind(
    cases: &[Case],
    seed: u64,
    scatter: &Scatter,
    options: &DiagnosisOptions,
    progress: &(dyn Fn(usize, usize, &str) + Sync),
) -> (Vec<Outcome>, Vec<Failure>) {
    let mut out = Vec::with_capacity(cases.len());
    let mut failures = Vec::new();
    progress(0, cases.len(), "");
    for (i, case) in cases.iter().enumerate() {
        let s = campaign_seed(seed, i);
        let what = match run_case(i, case, s, scatter, options) {
            Ok((o, _)) => {
                let w = format!(
                    "{} at {} (lambda_eff {:.1}) -> {} (G_hat {}, G_true {}, {:.0} s)",
                    case.truth.name(),
                    case.lambda,
                    o.generated.lambda_eff,
                    o.label,
                    o.closure_hat.map_or("-".to_string(), |g| format!("{g:.3}")),
                    o.closure_true.map_or("-".to_string(), |g| format!("{g:.3}")),
                    o.generate_s + o.diagnose_s + o.score_s
                );
                out.push(o);
                w
            }
            Err(e) => {
                let error = super::error_chain(&e);
                let w = format!("{} at {} -> failed: {error}", case.truth.name(), case.lambda);
                failures.push(Failure { index: i, seed: s, case: *case, error });
                w
            }
        };
        progress(i + 1, cases.len(), &what);
    }
    (out, failures)
}

/// The diagnosis settings of the blind check: the library's defaults with 5 mm
/// elements, the generator's marker noise, one Latin hypercube start besides the
/// nominal start values and 300 bootstrap resamples (the cost of a campaign).
pub fn default_options(seed: u64) -> DiagnosisOptions {
    DiagnosisOptions {
        starts: 1,
        seed,
        bootstrap: 300,
        size_mm: Some(5.0),
        marker_sigma_mm: MARKER_SIGMA_MM,
        ..DiagnosisOptions::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strength_calibration_finds_a_power_law_target() {
        // lambda = 7 a^2: from a = 1, two or three steps.
        let (a, l, evals, reached) = calibrate_strength(30.0, f64::INFINITY, |a| Ok(7.0 * a * a)).unwrap();
        assert!(reached && (l / 30.0 - 1.0).abs() < 0.2 && evals <= 3, "{a} {l} {evals}");
        // A threshold: nothing below a = 2, then steep (a jump from 0 to 4500 over one step of 10).
        let (a, l, _, reached) = calibrate_strength(12.0, f64::INFINITY, |a| Ok((500.0 * (a - 2.0)).max(0.0))).unwrap();
        assert!(reached && (l / 12.0 - 1.0).abs() < 0.2, "{a} {l}");
        let (a, l, _, reached) = calibrate_strength(100.0, f64::INFINITY, |a| Ok((50.0 * (a - 2.0)).max(0.0))).unwrap();
        assert!(reached && (l / 100.0 - 1.0).abs() < 0.2, "{a} {l}");
        // A bound that does not reach the target: stops there, not reached.
        let (a, l, _, reached) = calibrate_strength(100.0, 2.0, |a| Ok(3.0 * a * a)).unwrap();
        assert!(!reached && a == 2.0 && l == 12.0);
    }

    #[test]
    fn the_plan_is_fixed_by_the_seed_and_covers_the_cycle() {
        let cycle = full_cycle();
        let p = plan(cycle.len(), 5);
        assert_eq!(p, plan(cycle.len(), 5));
        assert_ne!(p, plan(cycle.len(), 6));
        for c in &cycle {
            assert_eq!(cycle.iter().filter(|x| *x == c).count(), p.iter().filter(|x| *x == c).count());
        }
        assert_ne!(campaign_seed(1, 0), campaign_seed(1, 1));
        assert_ne!(campaign_seed(1, 0), campaign_seed(2, 0));
    }

    /// Every out-of-library kind, Mullins-type damage included, has its own id
    /// and enters the cycle at every out-of-library strength; the damage's
    /// amplitude maps to `d_inf = 0.1 a` and stops at the law's bound.
    #[test]
    fn every_out_of_library_kind_is_in_the_cycle() {
        let cycle = full_cycle();
        let ids: std::collections::BTreeSet<&str> = OutOfLibrary::ALL.iter().map(|o| o.id()).collect();
        assert_eq!(ids.len(), 3);
        assert!(ids.contains("mullins-damage"));
        for o in OutOfLibrary::ALL {
            for &lambda in &OUT_OF_LIBRARY_LAMBDAS {
                let case = Case { truth: Truth::OutOfLibrary(o), lambda };
                assert_eq!(cycle.iter().filter(|c| **c == case).count(), 1, "{o:?} {lambda}");
            }
        }
        let mullins = Case { truth: Truth::OutOfLibrary(OutOfLibrary::MullinsDamage), lambda: 30.0 };
        assert!((max_amplitude(&mullins, &[]) * MULLINS_D_INF_PER_AMPLITUDE - MAX_DAMAGE).abs() < 1e-15);
        match Strength::of(&mullins, &[], 2.0) {
            Strength::Damage(d) => assert!((d - 2.0 * MULLINS_D_INF_PER_AMPLITUDE).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        let spectrum = Case { truth: Truth::OutOfLibrary(OutOfLibrary::BroadSpectrum), lambda: 30.0 };
        assert!(max_amplitude(&spectrum, &[]).is_infinite());
    }

    #[test]
    fn ar1_noise_has_its_variance_and_correlation() {
        let case = Case { truth: Truth::Null, lambda: 0.0 };
        let d = draws(&case, 3, &Scatter::ISSUE);
        let e: Vec<f64> = d.force_noise.iter().flatten().copied().collect();
        // The pooled lag-1 correlation estimates the length-weighted mean of the trials' rho.
        let rho_mean = d.rho.iter().zip(&d.force_noise).map(|(r, n)| r * n.len() as f64).sum::<f64>()
            / d.force_noise.iter().map(Vec::len).sum::<usize>() as f64;
        let n = e.len() as f64;
        let var = e.iter().map(|x| x * x).sum::<f64>() / n;
        let lag1 = e.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / (n - 1.0) / var;
        // About 1900 samples: the variance within 15 %, the lag-1 correlation within 0.1.
        assert!((var.sqrt() / FORCE_SIGMA_N - 1.0).abs() < 0.15, "{}", var.sqrt());
        assert!((lag1 - rho_mean).abs() < 0.1, "{lag1} against {rho_mean}");
        assert!(d.variability >= 0.03 && d.variability <= 0.10);
    }
}
