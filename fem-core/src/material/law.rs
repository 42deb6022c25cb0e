//! The constitutive seam: a material-point law behind one trait.
//!
//! A law takes the point's kinematics and its history at the step's start and
//! returns the stress, its exact consistent tangent and the history at the
//! step's end (style.md, "Constitutive laws"; deal.II's point history). The
//! stepper keeps one flat history buffer per point, commits it when a step is
//! accepted and throws the new one away when it is not: it knows no law by name
//! and holds no per-law field.
//!
//! Kinematics are finite: the deformation gradient `F = I + h` (3 x 3; plane
//! strain and axisymmetric cells embed theirs, `F_zz = 1` and
//! `F_θθ = 1 + u_r / r`), given by the displacement gradient `h` so that a law
//! can form its strains without cancellation (a strain of 1e-10 keeps its
//! relative precision).
//! The stress is the first Piola-Kirchhoff stress `P` [MPa] and the tangent
//! `A = dP/dF` [MPa], both in row-major index order: `P[3 i + J]`,
//! `A[(3 i + J, 3 k + L)] = dP_iJ / dF_kL`.
//!
//! Parameters are named once ([`ParameterSpec`]): the bundle reader, the fitter
//! and the reports take a law's keys, units and bounds from its table.

use nalgebra::{Matrix3, SMatrix};

/// `dP/dF`, row-major over `(i, J)` and `(k, L)`.
pub type Tangent = SMatrix<f64, 9, 9>;

/// One parameter of a law, as every reader and fitter sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParameterSpec {
    /// The key in a bundle, unit suffix included (`E_MPa`).
    pub key: &'static str,
    /// What it is, in words.
    pub meaning: &'static str,
    /// Its unit (`MPa`, `s`, `1`).
    pub unit: &'static str,
    /// The smallest accepted value (exclusive when `lower_open`).
    pub lower: f64,
    /// Whether `lower` itself is refused.
    pub lower_open: bool,
    /// The largest accepted value (inclusive).
    pub upper: f64,
    /// The value when the key is absent; `None`: the key is required.
    pub default: Option<f64>,
    /// Where identification searches for it when it is unknown.
    pub fit: FitRange,
    /// Where identification starts from when it is unknown.
    pub start: Start,
}

/// The range identification searches for an unknown parameter: narrower than
/// the accepted bounds, where the data can tell values apart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitRange {
    /// The smallest value tried.
    pub lower: f64,
    /// The largest value tried.
    pub upper: f64,
    /// Whether the search runs on `ln(value)` (moduli, times, viscosities).
    pub log: bool,
}

/// An unknown parameter's starting value, from the apparent modulus `E_app`
/// [MPa] that identification reads off the measured peaks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// A fixed value.
    Value(f64),
    /// A share of `E_app` (moduli and stresses) [MPa], or, for a viscosity, of
    /// `E_app` times one second [MPa s].
    OfModulus(f64),
    /// `first * 10^i` for the `i`-th part of its kind: relaxation times spread
    /// by decades.
    Decades(f64),
}

impl Start {
    /// The starting value for the `index`-th part of its kind, given the
    /// apparent modulus `e_app` [MPa].
    pub fn value(self, e_app: f64, index: usize) -> f64 {
        match self {
            Start::Value(v) => v,
            Start::OfModulus(k) => k * e_app,
            Start::Decades(first) => first * 10f64.powi(index as i32),
        }
    }
}

impl ParameterSpec {
    /// A parameter whose fit range is its accepted range (linear) and whose
    /// start is its default or its lower bound: set [`Self::fit`] and
    /// [`Self::start`] for a fitted parameter.
    pub const fn new(
        key: &'static str,
        meaning: &'static str,
        unit: &'static str,
        (lower, lower_open): (f64, bool),
        upper: f64,
        default: Option<f64>,
    ) -> Self {
        let start = match default {
            Some(d) => d,
            None => upper,
        };
        Self {
            key,
            meaning,
            unit,
            lower,
            lower_open,
            upper,
            default,
            fit: FitRange { lower, upper, log: false },
            start: Start::Value(start),
        }
    }

    /// The same parameter searched in `[lower, upper]`, on a log scale when `log`.
    pub const fn fit(self, lower: f64, upper: f64, log: bool) -> Self {
        Self { fit: FitRange { lower, upper, log }, ..self }
    }

    /// The same parameter started at `start`.
    pub const fn start(self, start: Start) -> Self {
        Self { start, ..self }
    }

    /// Whether `value` lies in the spec's bounds.
    pub fn accepts(&self, value: f64) -> bool {
        value.is_finite()
            && (if self.lower_open { value > self.lower } else { value >= self.lower })
            && value <= self.upper
    }

    /// The bounds as a reader says them: `(0, 1e3]`.
    pub fn range(&self) -> String {
        format!("{}{}, {}]", if self.lower_open { "(" } else { "[" }, self.lower, self.upper)
    }
}

/// Why a material point could not be updated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LawFailure {
    /// `det F <= 0`: the cell turned inside out.
    #[error("inverted (det F = {det:.3e})")]
    Inverted { det: f64 },
    /// A stress or tangent entry came out NaN or infinite.
    #[error("non-finite stress")]
    NonFinite,
    /// A part's return mapping did not converge.
    #[error("the return mapping of the {law} part did not converge")]
    ReturnMapping { law: &'static str },
    /// A part without a small-strain form asked for one (refused before a run).
    #[error("the {law} part has no small-strain form")]
    NoSmallStrainForm { law: &'static str },
}

/// What a law returns for one point and step.
#[derive(Debug, Clone, PartialEq)]
pub struct PointResponse {
    /// First Piola-Kirchhoff stress [MPa].
    pub stress: Matrix3<f64>,
    /// Its exact derivative by `F` [MPa].
    pub tangent: Tangent,
}

/// A material-point law at finite strain.
pub trait PointLaw: std::fmt::Debug + Send + Sync {
    /// The law's name as a bundle spells it (`network`).
    fn name(&self) -> &'static str;
    /// Length of the per-point history buffer.
    fn history_len(&self) -> usize;
    /// Writes the history of an undeformed point at rest.
    fn initial_history(&self, history: &mut [f64]);
    /// The stress and tangent at `F = I + h` after a step of `dt_s` from the
    /// state `old`; writes the state at the step's end into `new` (same length).
    fn update(&self, h: &Matrix3<f64>, dt_s: f64, old: &[f64], new: &mut [f64]) -> Result<PointResponse, LawFailure>;
    /// The Young-type modulus of the law at small strain and no rate [MPa]: the
    /// scale of its stiffness (for force scales and error messages).
    fn small_strain_modulus(&self) -> f64;
}

/// Row-major index of `(i, J)` in a 9-vector.
#[inline]
pub(crate) fn ij(i: usize, j: usize) -> usize {
    3 * i + j
}

/// Central differences of `stress(F)` at `f`, step `h` relative to 1: the check
/// every law's tangent must pass (its tests and the property tests).
pub fn tangent_by_differences(f: &Matrix3<f64>, h: f64, stress: &dyn Fn(&Matrix3<f64>) -> Matrix3<f64>) -> Tangent {
    let mut a = Tangent::zeros();
    for k in 0..3 {
        for l in 0..3 {
            let mut fp = *f;
            fp[(k, l)] += h;
            let mut fm = *f;
            fm[(k, l)] -= h;
            let d = (stress(&fp) - stress(&fm)) / (2.0 * h);
            for i in 0..3 {
                for j in 0..3 {
                    a[(ij(i, j), ij(k, l))] = d[(i, j)];
                }
            }
        }
    }
    a
}
