//! The seed's rheological chains (Fig. 1, eqs. 1-3) and their relaxation functions.
//!
//! Every model is a series chain of Voigt elements (`E_i || c_i`), springs and one
//! dashpot `c3`. Under a strain history `e(t)` the stress is the hereditary integral
//!
//! ```text
//! s(t) = B2 e'(t) + g_inf e(t) + sum_k a_k h_k(t),   h_k(t) = int_0^t exp(-r_k (t - t')) e'(t') dt'
//! ```
//!
//! i.e. the relaxation function is `G(t) = B2 delta(t) + g_inf + sum_k a_k exp(-r_k t)`
//! (design.md 3.1). The five-element values follow eq. (3) of the seed:
//! `x^2 + A1 x + A0 = (x + m)(x + n)`, `p = B1 - B2 A1`, `q = B0 - B2 A0`,
//! `a = (q - p m)/(n - m)`, `b = (q - p n)/(m - n)`.
//!
//! Units: moduli in MPa, viscosities in MPa s, rates in 1/s.

use thiserror::Error;

/// One rheological model with its parameters (Young-type moduli, uniaxial viscosities).
///
/// Key sets (experiment-format.md): `elastic` = `E`; `three-element` = a Voigt
/// element `(E1, c1)` in series with a dashpot `c3`; `four-element` = a spring `E2`
/// in series with a Voigt element `(E1, c1)` and a dashpot `c3`; `five-element` = two
/// Voigt elements `(E1, c1)`, `(E2, c2)` and a dashpot `c3` in series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rheology {
    /// Hookean solid, `E` [MPa].
    Elastic { e_mpa: f64 },
    /// Voigt `(E1 [MPa], c1 [MPa s])` + dashpot `c3 [MPa s]`.
    ThreeElement { e1_mpa: f64, c1_mpa_s: f64, c3_mpa_s: f64 },
    /// Spring `E2 [MPa]` + Voigt `(E1, c1)` + dashpot `c3`.
    FourElement { e1_mpa: f64, c1_mpa_s: f64, e2_mpa: f64, c3_mpa_s: f64 },
    /// Voigt `(E1, c1)` + Voigt `(E2, c2)` + dashpot `c3` (the seed's model).
    FiveElement { e1_mpa: f64, e2_mpa: f64, c1_mpa_s: f64, c2_mpa_s: f64, c3_mpa_s: f64 },
}

/// An elementary piece of the series chain; used for creep and recovery closed forms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ChainElement {
    /// A spring of modulus `E` [MPa].
    Spring { e_mpa: f64 },
    /// A Voigt element: spring `E` [MPa] parallel to dashpot `c` [MPa s].
    Voigt { e_mpa: f64, c_mpa_s: f64 },
    /// A dashpot `c` [MPa s].
    Dashpot { c_mpa_s: f64 },
}

/// Why a material's parameters were refused.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MaterialError {
    /// A modulus or viscosity that is not finite and positive.
    #[error("{name} = {value}: must be finite and > 0")]
    NotPositive { name: &'static str, value: f64 },
    /// A Poisson ratio outside (-1, 0.5).
    #[error("poisson = {value}: must lie in (-1, 0.5)")]
    PoissonOutOfRange { value: f64 },
    /// A parameter of the Mullins-type damage law out of its range
    /// ([`super::MullinsDamage`]: `d_inf` in [0, [`super::MAX_DAMAGE`]], `strain_c` finite and > 0).
    #[error("Mullins damage {name} = {value}: must lie in {range}")]
    DamageOutOfRange { name: &'static str, value: f64, range: &'static str },
    /// A network's parameter refused ([`super::network::Network::validate`]).
    #[error("{0}")]
    Network(super::network::NetworkError),
}

/// The relaxation function `G(t) = viscous delta(t) + equilibrium + sum_k a_k exp(-r_k t)`
/// of a chain, Young-type (for a unit-Young constitutive shape, see [`super::Material`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelaxationKernel {
    /// `B2` [MPa s]: the instantaneous viscous coefficient.
    pub viscous: f64,
    /// `G(inf)` [MPa]: the long-time modulus (0 for every chain with a dashpot).
    pub equilibrium: f64,
    /// Number of exponential terms in use (0..=2).
    pub num_terms: usize,
    /// Amplitudes `a_k` [MPa].
    pub amplitudes: [f64; 2],
    /// Rates `r_k` [1/s].
    pub rates: [f64; 2],
}

impl Rheology {
    /// The parameter values with their names, in the order of the model's key set.
    pub fn parameters(&self) -> Vec<(&'static str, f64)> {
        match *self {
            Rheology::Elastic { e_mpa } => vec![("E", e_mpa)],
            Rheology::ThreeElement { e1_mpa, c1_mpa_s, c3_mpa_s } => {
                vec![("E1", e1_mpa), ("c1", c1_mpa_s), ("c3", c3_mpa_s)]
            }
            Rheology::FourElement { e1_mpa, c1_mpa_s, e2_mpa, c3_mpa_s } => {
                vec![("E1", e1_mpa), ("E2", e2_mpa), ("c1", c1_mpa_s), ("c3", c3_mpa_s)]
            }
            Rheology::FiveElement { e1_mpa, e2_mpa, c1_mpa_s, c2_mpa_s, c3_mpa_s } => {
                vec![("E1", e1_mpa), ("E2", e2_mpa), ("c1", c1_mpa_s), ("c2", c2_mpa_s), ("c3", c3_mpa_s)]
            }
        }
    }

    /// The model's name as the bundle format spells it.
    pub fn model_name(&self) -> &'static str {
        match self {
            Rheology::Elastic { .. } => "elastic",
            Rheology::ThreeElement { .. } => "three-element",
            Rheology::FourElement { .. } => "four-element",
            Rheology::FiveElement { .. } => "five-element",
        }
    }

    /// Refuses non-finite or non-positive moduli and viscosities.
    pub fn validate(&self) -> Result<(), MaterialError> {
        for (name, value) in self.parameters() {
            if !(value.is_finite() && value > 0.0) {
                return Err(MaterialError::NotPositive { name, value });
            }
        }
        Ok(())
    }

    /// The series dashpot's viscosity `c3` [MPa s], if the chain has one.
    pub fn dashpot_c3(&self) -> Option<f64> {
        match *self {
            Rheology::Elastic { .. } => None,
            Rheology::ThreeElement { c3_mpa_s, .. }
            | Rheology::FourElement { c3_mpa_s, .. }
            | Rheology::FiveElement { c3_mpa_s, .. } => Some(c3_mpa_s),
        }
    }

    /// The chain as series elements (the seed's Fig. 1).
    pub fn chain(&self) -> Vec<ChainElement> {
        use ChainElement::*;
        match *self {
            Rheology::Elastic { e_mpa } => vec![Spring { e_mpa }],
            Rheology::ThreeElement { e1_mpa, c1_mpa_s, c3_mpa_s } => {
                vec![Voigt { e_mpa: e1_mpa, c_mpa_s: c1_mpa_s }, Dashpot { c_mpa_s: c3_mpa_s }]
            }
            Rheology::FourElement { e1_mpa, c1_mpa_s, e2_mpa, c3_mpa_s } => vec![
                Spring { e_mpa: e2_mpa },
                Voigt { e_mpa: e1_mpa, c_mpa_s: c1_mpa_s },
                Dashpot { c_mpa_s: c3_mpa_s },
            ],
            Rheology::FiveElement { e1_mpa, e2_mpa, c1_mpa_s, c2_mpa_s, c3_mpa_s } => vec![
                Voigt { e_mpa: e1_mpa, c_mpa_s: c1_mpa_s },
                Voigt { e_mpa: e2_mpa, c_mpa_s: c2_mpa_s },
                Dashpot { c_mpa_s: c3_mpa_s },
            ],
        }
    }

    /// The relaxation function of the chain (design.md 3.1).
    pub fn relaxation(&self) -> RelaxationKernel {
        let p: Vec<f64> = self.parameters().iter().map(|&(_, v)| v).collect();
        let k = kernel_of(*self, &p);
        RelaxationKernel {
            viscous: k.viscous,
            equilibrium: k.equilibrium,
            num_terms: k.num_terms,
            amplitudes: k.amplitudes,
            rates: k.rates,
        }
    }

    /// The derivatives of [`Self::relaxation`] with respect to each parameter, in
    /// the order of [`Self::parameters`]: `d viscous/d p_i`, `d a_k/d p_i`, ...,
    /// exact (forward-mode dual numbers through the same formulas).
    pub fn relaxation_derivatives(&self) -> Vec<RelaxationKernel> {
        let values: Vec<f64> = self.parameters().iter().map(|&(_, v)| v).collect();
        (0..values.len())
            .map(|i| {
                let p: Vec<Dual> =
                    values.iter().enumerate().map(|(j, &v)| Dual { v, d: if i == j { 1.0 } else { 0.0 } }).collect();
                let k = kernel_of(*self, &p);
                RelaxationKernel {
                    viscous: k.viscous.d,
                    equilibrium: k.equilibrium.d,
                    num_terms: k.num_terms,
                    amplitudes: [k.amplitudes[0].d, k.amplitudes[1].d],
                    rates: [k.rates[0].d, k.rates[1].d],
                }
            })
            .collect()
    }
}

/// The arithmetic the kernel formulas need: `f64`, and [`Dual`] for their derivatives.
trait KernelScalar:
    Copy
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
{
    fn constant(v: f64) -> Self;
    fn value(self) -> f64;
    fn sqrt(self) -> Self;
}

impl KernelScalar for f64 {
    fn constant(v: f64) -> Self {
        v
    }
    fn value(self) -> f64 {
        self
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
}

/// A forward-mode dual number `v + d eps` (`eps^2 = 0`).
#[derive(Debug, Clone, Copy)]
struct Dual {
    v: f64,
    d: f64,
}

impl std::ops::Add for Dual {
    type Output = Dual;
    fn add(self, o: Dual) -> Dual {
        Dual { v: self.v + o.v, d: self.d + o.d }
    }
}
impl std::ops::Sub for Dual {
    type Output = Dual;
    fn sub(self, o: Dual) -> Dual {
        Dual { v: self.v - o.v, d: self.d - o.d }
    }
}
impl std::ops::Mul for Dual {
    type Output = Dual;
    fn mul(self, o: Dual) -> Dual {
        Dual { v: self.v * o.v, d: self.d * o.v + self.v * o.d }
    }
}
impl std::ops::Div for Dual {
    type Output = Dual;
    fn div(self, o: Dual) -> Dual {
        Dual { v: self.v / o.v, d: (self.d * o.v - self.v * o.d) / (o.v * o.v) }
    }
}
impl KernelScalar for Dual {
    fn constant(v: f64) -> Self {
        Dual { v, d: 0.0 }
    }
    fn value(self) -> f64 {
        self.v
    }
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        Dual { v: r, d: if r > 0.0 { 0.5 * self.d / r } else { 0.0 } }
    }
}

/// [`RelaxationKernel`] over a scalar type.
struct KernelOf<T> {
    viscous: T,
    equilibrium: T,
    num_terms: usize,
    amplitudes: [T; 2],
    rates: [T; 2],
}

impl KernelOf<f64> {
    #[cfg(test)]
    fn into_f64(self) -> RelaxationKernel {
        RelaxationKernel {
            viscous: self.viscous,
            equilibrium: self.equilibrium,
            num_terms: self.num_terms,
            amplitudes: self.amplitudes,
            rates: self.rates,
        }
    }
}

/// The relaxation function of `model` with the parameter values `p` (in the order
/// of [`Rheology::parameters`]), written once for values and derivatives.
fn kernel_of<T: KernelScalar>(model: Rheology, p: &[T]) -> KernelOf<T> {
    let zero = T::constant(0.0);
    match model {
        Rheology::Elastic { .. } => {
            KernelOf { viscous: zero, equilibrium: p[0], num_terms: 0, amplitudes: [zero; 2], rates: [zero; 2] }
        }
        Rheology::ThreeElement { .. } => {
            // Q(s)/s = B2 + a/(s + k): B2 = c1 c3/(c1+c3), a = E1 c3^2/(c1+c3)^2, k = E1/(c1+c3).
            let (e1, c1, c3) = (p[0], p[1], p[2]);
            let sum = c1 + c3;
            KernelOf {
                viscous: c1 * c3 / sum,
                equilibrium: zero,
                num_terms: 1,
                amplitudes: [e1 * c3 * c3 / (sum * sum), zero],
                rates: [e1 / sum, zero],
            }
        }
        Rheology::FourElement { .. } => {
            // Q(s)/s = (E2 s + E1 E2/c1) / (s^2 + A1 s + A0).
            let (e1, e2, c1, c3) = (p[0], p[1], p[2], p[3]);
            let a1 = (c3 * e1 + e2 * c3 + e2 * c1) / (c1 * c3);
            let a0 = e1 * e2 / (c1 * c3);
            second_order(zero, e2, e1 * e2 / c1, a1, a0)
        }
        Rheology::FiveElement { .. } => {
            // The seed's eq. (3).
            let (e1, e2, c1, c2, c3) = (p[0], p[1], p[2], p[3], p[4]);
            let d = c1 * c2 + c2 * c3 + c3 * c1;
            let a0 = e1 * e2 / d;
            let a1 = (e1 * (c2 + c3) + e2 * (c1 + c3)) / d;
            let b0 = e1 * e2 * c3 / d;
            let b1 = (e1 * c2 * c3 + c1 * e2 * c3) / d;
            let b2 = c1 * c2 * c3 / d;
            second_order(b2, b1 - b2 * a1, b0 - b2 * a0, a1, a0)
        }
    }
}

/// `Q(s)/s = b2 + (p s + q)/(s^2 + a1 s + a0)` split into two exponentials.
fn second_order<T: KernelScalar>(b2: T, p: T, q: T, a1: T, a0: T) -> KernelOf<T> {
    // Roots of x^2 + a1 x + a0, m > n > 0, computed without cancellation.
    let disc2 = a1 * a1 - T::constant(4.0) * a0;
    let disc = if disc2.value() > 0.0 { disc2.sqrt() } else { T::constant(0.0) };
    let m = T::constant(0.5) * (a1 + disc);
    let n = a0 / m;
    let a = (q - p * m) / (n - m);
    let b = (q - p * n) / (m - n);
    KernelOf { viscous: b2, equilibrium: T::constant(0.0), num_terms: 2, amplitudes: [a, b], rates: [m, n] }
}

/// `(1 - exp(-x))/x`, accurate for small `x`.
pub fn phi1(x: f64) -> f64 {
    if x.abs() < 1e-8 {
        1.0 - 0.5 * x
    } else {
        -(-x).exp_m1() / x
    }
}

/// `d phi1/dx = (exp(-x) - phi1(x))/x`, accurate for small `x`.
pub fn phi1_derivative(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        -0.5 + x / 3.0 - x * x / 8.0
    } else {
        ((-x).exp() - phi1(x)) / x
    }
}

/// `phi2(x) = (1 - phi1(x))/x = (x - 1 + exp(-x))/x^2`, accurate for small `x`:
/// the mean over a step of `phi1`'s history growth (`(1/x) int_0^x (1 - exp(-y)) dy / x`).
pub fn phi2(x: f64) -> f64 {
    if x.abs() < 1e-3 {
        0.5 - x / 6.0 + x * x / 24.0 - x * x * x / 120.0
    } else {
        (x + (-x).exp_m1()) / (x * x)
    }
}

impl RelaxationKernel {
    /// `G(t)` for `t > 0` [MPa] (the delta part excluded).
    pub fn modulus(&self, t: f64) -> f64 {
        let mut g = self.equilibrium;
        for k in 0..self.num_terms {
            g += self.amplitudes[k] * (-self.rates[k] * t).exp();
        }
        g
    }

    /// The step's stiffness factor `g(dt) = B2/dt + G_inf + sum_k a_k (1 - exp(-r_k dt))/(r_k dt)`
    /// (design.md 3.3): the stress at the step's end is `g(dt) e(t+dt)` plus history terms.
    pub fn step_factor(&self, dt: f64) -> f64 {
        let mut g = self.viscous / dt + self.equilibrium;
        for k in 0..self.num_terms {
            g += self.amplitudes[k] * phi1(self.rates[k] * dt);
        }
        g
    }

    /// The step's mean factor `g_mean(dt) = B2/dt + G_inf/2 + sum_k a_k phi2(r_k dt)`
    /// [MPa]: for a strain linear in time over the step, the stress's mean over the
    /// step is `g_mean e(t+dt)` less history terms (`(1/dt) int s dt = B2 de/dt +
    /// G_inf (e0 + de/2) + sum_k a_k (phi1(r_k dt) h_k0 + phi2(r_k dt) de)`). For a
    /// chain with the dashpot `c3` (and `G_inf = 0`), `g_mean dt = int_0^dt (1 -
    /// u/dt) G(u) du = B2 + sum_k (a_k/r_k) (1 - phi1(r_k dt))` stays below `int_0^inf
    /// G = B2 + sum_k a_k/r_k = c3` at every step.
    pub fn mean_factor(&self, dt: f64) -> f64 {
        let mut g = self.viscous / dt + 0.5 * self.equilibrium;
        for k in 0..self.num_terms {
            g += self.amplitudes[k] * phi2(self.rates[k] * dt);
        }
        g
    }

    /// True when the two kernels are equal up to one positive factor (same shape in time).
    pub fn proportional_to(&self, other: &RelaxationKernel) -> Option<f64> {
        if self.num_terms != other.num_terms {
            return None;
        }
        let scale_of = |a: f64, b: f64| if b != 0.0 { Some(a / b) } else { None };
        let mut scale = None;
        let mut pairs = vec![(self.viscous, other.viscous), (self.equilibrium, other.equilibrium)];
        for k in 0..self.num_terms {
            if self.rates[k] != other.rates[k] {
                return None;
            }
            pairs.push((self.amplitudes[k], other.amplitudes[k]));
        }
        for (a, b) in pairs {
            match (a == 0.0, b == 0.0) {
                (true, true) => continue,
                (false, false) => {
                    let s = scale_of(a, b)?;
                    match scale {
                        None => scale = Some(s),
                        Some(s0) if ((s - s0) / s0).abs() < 1e-14 => {}
                        Some(_) => return None,
                    }
                }
                _ => return None,
            }
        }
        scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat1() -> Rheology {
        Rheology::FiveElement { e1_mpa: 0.0349, e2_mpa: 0.0221, c1_mpa_s: 0.0071, c2_mpa_s: 0.1869, c3_mpa_s: 29.719 }
    }

    /// design.md 3.1 quotes m, n, B2, a, b for the seed's material 1 to five digits.
    #[test]
    fn five_element_matches_design_values() {
        let k = mat1().relaxation();
        let rel = |x: f64, y: f64| ((x - y) / y).abs();
        assert!(rel(k.rates[0], 0.29445) < 5e-5, "m = {}", k.rates[0]);
        assert!(rel(k.rates[1], 4.5422e-4) < 5e-5, "n = {}", k.rates[1]);
        assert!(rel(k.viscous, 6.8386e-3) < 5e-5, "B2 = {}", k.viscous);
        assert!(rel(k.amplitudes[0], 1.8940e-2) < 5e-5, "a = {}", k.amplitudes[0]);
        assert!(rel(k.amplitudes[1], 1.3467e-2) < 5e-5, "b = {}", k.amplitudes[1]);
    }

    /// The relaxation function must invert the creep compliance: in Laplace space
    /// `s G^(s) * s J^(s) = 1`, with `J^` summed from the chain. Checked at several s.
    #[test]
    fn relaxation_inverts_chain_compliance() {
        let models = [
            mat1(),
            Rheology::ThreeElement { e1_mpa: 0.05, c1_mpa_s: 0.3, c3_mpa_s: 12.0 },
            Rheology::FourElement { e1_mpa: 0.05, c1_mpa_s: 0.3, e2_mpa: 0.02, c3_mpa_s: 12.0 },
            Rheology::Elastic { e_mpa: 0.7 },
        ];
        for model in models {
            let k = model.relaxation();
            for s in [1e-4, 1e-2, 0.3, 1.0, 17.0, 1e3] {
                let mut sg = k.viscous * s + k.equilibrium;
                for i in 0..k.num_terms {
                    sg += k.amplitudes[i] * s / (s + k.rates[i]);
                }
                let mut j = 0.0;
                for e in model.chain() {
                    j += match e {
                        ChainElement::Spring { e_mpa } => 1.0 / e_mpa,
                        ChainElement::Voigt { e_mpa, c_mpa_s } => 1.0 / (e_mpa + c_mpa_s * s),
                        ChainElement::Dashpot { c_mpa_s } => 1.0 / (c_mpa_s * s),
                    };
                }
                assert!((sg * j - 1.0).abs() < 1e-12, "{model:?} at s = {s}: {}", sg * j);
            }
        }
    }

    /// The dual-number derivatives of the kernel against central differences
    /// (relative step 1e-6: truncation and rounding both near 1e-9 relative).
    #[test]
    fn relaxation_derivatives_match_finite_differences() {
        let models = [
            mat1(),
            Rheology::ThreeElement { e1_mpa: 0.05, c1_mpa_s: 0.3, c3_mpa_s: 12.0 },
            Rheology::FourElement { e1_mpa: 0.05, c1_mpa_s: 0.3, e2_mpa: 0.02, c3_mpa_s: 12.0 },
            Rheology::Elastic { e_mpa: 0.7 },
        ];
        let flat =
            |k: &RelaxationKernel| [k.viscous, k.equilibrium, k.amplitudes[0], k.amplitudes[1], k.rates[0], k.rates[1]];
        for model in models {
            let exact = model.relaxation_derivatives();
            let values: Vec<f64> = model.parameters().iter().map(|p| p.1).collect();
            for (i, d) in exact.iter().enumerate() {
                let h = 1e-6 * values[i];
                let at = |x: f64| {
                    let mut p = values.clone();
                    p[i] = x;
                    flat(&kernel_of(model, &p).into_f64())
                };
                let (up, down) = (at(values[i] + h), at(values[i] - h));
                let base = flat(&model.relaxation());
                for (c, (&dx, (&u, &l))) in flat(d).iter().zip(up.iter().zip(&down)).enumerate() {
                    let fd = (u - l) / (2.0 * h);
                    // Scale: the component's size over the parameter's size.
                    let scale = (base[c].abs() / values[i]).max(1e-300);
                    assert!((dx - fd).abs() <= 1e-6 * scale, "{model:?} d[{c}]/d p{i}: {dx} vs {fd}");
                }
            }
        }
    }

    #[test]
    fn phi2_is_continuous_and_exact() {
        // Against the quadrature of its definition (Simpson, panels of at most 0.01:
        // 1e-12 relative).
        for x in [1e-9, 5e-4, 9.99e-4, 1.001e-3, 0.3, 4.0, 250.0] {
            let n = 2000.max((x * 100.0) as usize);
            let h = x / n as f64;
            let f = |y: f64| -(-y).exp_m1();
            let simpson: f64 = (0..n)
                .map(|i| {
                    let a = i as f64 * h;
                    h / 6.0 * (f(a) + 4.0 * f(a + 0.5 * h) + f(a + h))
                })
                .sum();
            let expected = simpson / (x * x);
            assert!((phi2(x) - expected).abs() < 1e-12 * expected, "x = {x}: {} vs {expected}", phi2(x));
        }
    }

    /// The mean stress over a step of a unit strain ramp from rest, `g_mean(dt)`,
    /// against the quadrature of `B2/dt + (1/dt^2) int_0^dt (dt - u) G(u) du`
    /// (Simpson on at most 2e6 panels: agreement 1e-8 relative, the quadrature's
    /// own error at 40 s, where a panel spans 0.06 of the fastest relaxation time:
    /// measured 2.2e-9), and `g_mean dt` below its limit `c3`, for the five-element
    /// chain of a fungi-steak refit (`c1 = c3` = 1.35e-5 MPa s) and the seed's.
    #[test]
    fn mean_factor_is_the_mean_stress_of_a_ramp() {
        let chains = [
            Rheology::FiveElement {
                e1_mpa: 0.081,
                e2_mpa: 0.049,
                c1_mpa_s: 1.35e-5,
                c2_mpa_s: 2.88,
                c3_mpa_s: 1.35e-5,
            },
            mat1(),
        ];
        for chain in chains {
            let k = chain.relaxation();
            let c3 = chain.dashpot_c3().unwrap();
            for dt in [1e-6, 1e-3, 0.4, 40.0] {
                let fastest = k.rates[..k.num_terms].iter().fold(0.0f64, |m, &r| m.max(r));
                let n = ((dt * fastest * 1e3).ceil() as usize).clamp(200, 2_000_000);
                let h = dt / n as f64;
                let f = |u: f64| (dt - u) * k.modulus(u);
                let quadrature: f64 = (0..n)
                    .map(|i| {
                        let a = i as f64 * h;
                        h / 6.0 * (f(a) + 4.0 * f(a + 0.5 * h) + f(a + h))
                    })
                    .sum();
                let expected = k.viscous / dt + quadrature / (dt * dt);
                let got = k.mean_factor(dt);
                assert!((got - expected).abs() < 1e-8 * expected, "{chain:?} dt = {dt}: {got} vs {expected}");
                assert!(got * dt < c3, "{chain:?} dt = {dt}");
            }
        }
    }

    #[test]
    fn phi1_derivative_is_continuous_and_exact() {
        for x in [1e-9f64, 1e-5, 9.9e-5, 1.01e-4, 0.3, 4.0, 50.0] {
            let h = 1e-6 * x.max(1e-3);
            let fd = (phi1(x + h) - phi1(x - h)) / (2.0 * h);
            assert!((phi1_derivative(x) - fd).abs() < 1e-7, "x = {x}: {} vs {fd}", phi1_derivative(x));
        }
    }

    #[test]
    fn validation_names_the_parameter() {
        let bad = Rheology::ThreeElement { e1_mpa: 0.05, c1_mpa_s: -1.0, c3_mpa_s: 1.0 };
        assert_eq!(bad.validate(), Err(MaterialError::NotPositive { name: "c1", value: -1.0 }));
        let nan = Rheology::Elastic { e_mpa: f64::NAN };
        assert!(matches!(nan.validate(), Err(MaterialError::NotPositive { name: "E", .. })));
    }
}
