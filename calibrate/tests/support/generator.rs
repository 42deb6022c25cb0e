//! An independent generator of press trials: homogeneous uniaxial compression
//! of a block between frictionless plates, integrated in principal stretches
//! with the network model's components written here from their definitions
//! (design.md 3.6 and the network laws' module docs), with no call into the
//! engine's material code.
//!
//! ## The state
//!
//! Axes: `x` the width `W`, `y` the push axis (height `H`, floor at `y = 0`,
//! plate on top), `z` the thickness `T` (the front face at `z = T`). Between
//! frictionless plates a homogeneous block is in uniaxial stress: principal
//! stretches `(l_x, l_y, l_z)` fixed in these axes, `l_y` set by the plate
//! (`l_y = 1 - d(t) / H` while it touches), the lateral stretches by zero
//! lateral stress. In 3D `l_x = l_z` (the material is isotropic and every
//! internal variable starts at zero); in plane strain (`dimension = 2`) `l_z = 1`.
//! The block expands about its centre `(W/2, T/2)` and slides on the floor, so a
//! material point `p` is at `(W/2 + l_x (p_x - W/2), l_y p_y, T/2 + l_z (p_z - T/2))`.
//!
//! In finite-strain kinematics every component works on the principal
//! logarithmic strains `eps_i = ln l_i` and gives a principal Kirchhoff stress
//! `tau_i`; the measured (bottom) force is the nominal one, `-A0 tau_y / l_y`
//! (compression positive, `A0 = W T`, in plane strain `W` times the thickness).
//! In small-strain kinematics the strains are `eps_i = l_i - 1`, the stresses
//! Cauchy's, and the force `-A0 sigma_y`.
//!
//! ## The components (all in parallel, one Poisson ratio `nu`)
//!
//! Unit-Young Lamé constants `lambda1 = nu / ((1 + nu)(1 - 2 nu))`,
//! `mu1 = 1 / (2 (1 + nu))`; a Hencky spring of modulus `E` on an elastic log
//! strain `e` has `tau = E (lambda1 tr(e) + 2 mu1 e)`, its shear modulus
//! `mu = E mu1` and `dev tau = 2 mu dev e`.
//!
//! - equilibrium: `W(I1bar) + K/2 (J - 1)^2`, `I1bar = J^-2/3 sum l_i^2`,
//!   `mu = E / (2 (1 + nu))`, `K = E / (3 (1 - 2 nu))`, neo-Hookean
//!   `W = mu/2 (I1bar - 3)` or exponential `W = mu/(2 b) [exp(b (I1bar - 3)) - 1]`:
//!   `tau_i = 2 W'(I1bar) J^-2/3 (l_i^2 - I1/3) + K J (J - 1)`;
//!   Ogden-Roxburgh softening multiplies it by
//!   `eta = 1 - erf((W_max - W) / (m + beta W_max)) / r` (`W` the whole energy,
//!   `W_max` its largest value so far);
//! - viscous network (modulus `E`, time `tau`): `e = eps - eps_v`,
//!   `d eps_v / dt = e / tau` (the whole elastic strain relaxes, volume included);
//! - dual-viscosity network: the same with `tau_load` while the spring loads or
//!   holds (`tau : d eps/dt >= 0`, its energy does not fall under the total
//!   strain rate) and `tau_unload` while it unloads;
//! - power-law flow network: `d eps_v / dt = sqrt(3/2) (q / sigma_0)^n n`,
//!   `q = sqrt(3/2) |dev tau|`, `n = dev tau / |dev tau|` (isochoric flow);
//! - Bingham network: `d eps_v / dt = sqrt(3/2) <q - sigma_y> / eta n`;
//! - plastic network: J2 in the log strains, `|dev tau - beta| <= sqrt(2/3)
//!   (sigma_y + H alpha)`, isotropic hardening `H` on the equivalent plastic
//!   strain `alpha`, Prager's back stress `beta = 2/3 H_k eps_p`;
//! - damper: `tau = c (lambda1 tr(D) + 2 mu1 D)`, `D = d eps / dt`.
//!
//! In small-strain kinematics the equilibrium network is Hooke's `E C1 : eps`
//! and the viscous networks and the damper are the same laws on `eps`; the
//! other components have no small-strain form (as in the engine).
//!
//! ## The integration
//!
//! Backward Euler on every rate law (closed-form or scalar-Newton returns per
//! component, the plastic return exact on these fixed-axis paths), the lateral
//! stretch of each step from zero lateral stress by a scalar Newton iteration
//! with a bracketing (bisection) fallback, and Richardson extrapolation of two
//! runs (steps `dt` and `dt/2`) to second order. Step ends land on every
//! waypoint, the release, the end and every output time. A third run at
//! `dt/4` gives the error estimate of the extrapolation ([`Trace::error_estimate`]).
//!
//! ## The plate
//!
//! A constrained plate (the engine's frictionless plate, [`PlateMode::Held`])
//! holds `l_y` until the release, in tension too. A contact plate
//! ([`PlateMode::Contact`], the engine's plate tool of a double compression)
//! pushes only: contact is lost when the nominal stress would turn tensile, and
//! the specimen then recovers free of stress until its top meets the plate
//! again. After the release the specimen is free.

use std::fmt::Write as _;

/// The kinematics the components work in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinematics {
    /// Principal logarithmic strains, Kirchhoff stresses, nominal force.
    Finite,
    /// Engineering strains `l - 1`, Cauchy stresses, no geometric term.
    Small,
}

/// The equilibrium network's isochoric energy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Energy {
    /// `mu/2 (I1bar - 3)`.
    NeoHookean,
    /// `mu/(2 b) [exp(b (I1bar - 3)) - 1]`, `b` dimensionless.
    Exponential { stiffening: f64 },
}

/// Ogden-Roxburgh softening of the equilibrium network.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mullins {
    /// `r > 1`: the most softening is `1 - 1/r` of the stress.
    pub r: f64,
    /// Energy scale `m` [MPa].
    pub m_mpa: f64,
    /// Growth `beta` of the scale with `W_max`.
    pub beta: f64,
}

/// The equilibrium (hyperelastic) network.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Equilibrium {
    pub energy: Energy,
    /// Young's modulus at small strain [MPa].
    pub e_mpa: f64,
    pub mullins: Option<Mullins>,
}

/// A network component in parallel with the others (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Component {
    /// Maxwell network: Hencky spring `e_mpa` [MPa], relaxation time `tau_s` [s].
    Viscous { e_mpa: f64, tau_s: f64 },
    /// J2 plastic network: spring [MPa], yield stress [MPa], isotropic and
    /// kinematic hardening moduli [MPa].
    Plastic { e_mpa: f64, yield_mpa: f64, hardening_mpa: f64, kinematic_mpa: f64 },
    /// Norton flow network: spring [MPa], `sigma_0` [MPa], exponent `n >= 1`.
    Flow { e_mpa: f64, stress_mpa: f64, exponent: f64 },
    /// Bingham network: spring [MPa], yield stress [MPa], plastic viscosity [MPa s].
    Bingham { e_mpa: f64, yield_mpa: f64, viscosity_mpa_s: f64 },
    /// Parallel Newtonian damper of Young-type viscosity `c` [MPa s].
    Damper { c_mpa_s: f64 },
    /// Maxwell network with a loading and an unloading relaxation time [s].
    Dual { e_mpa: f64, tau_load_s: f64, tau_unload_s: f64 },
}

/// A network material: the equilibrium network and the components.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Poisson's ratio of every component.
    pub poisson: f64,
    pub kinematics: Kinematics,
    pub equilibrium: Option<Equilibrium>,
    pub components: Vec<Component>,
}

/// The block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Specimen {
    /// 3 (a block) or 2 (plane strain, `size_mm[2]` the thickness).
    pub dimension: usize,
    /// `[W, H, T]` [mm].
    pub size_mm: [f64; 3],
}

impl Specimen {
    /// The loaded cross-section `A0` [mm^2].
    pub fn area_mm2(&self) -> f64 {
        self.size_mm[0] * self.size_mm[2]
    }
}

/// How the plate holds the top face.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlateMode {
    /// Bilateral until the release (a constrained frictionless plate).
    Held,
    /// Unilateral (a frictionless contact plate that may leave and touch again).
    Contact,
}

/// The plate protocol.
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    /// `[t_s, d_mm]`: downward plate displacement from first touch, piecewise
    /// linear, held after the last waypoint.
    pub waypoints: Vec<[f64; 2]>,
    /// The plate lets go [s].
    pub release_s: f64,
    /// The trial ends [s].
    pub end_s: f64,
    pub plate: PlateMode,
}

impl Protocol {
    /// The plate displacement `d(t)` [mm].
    pub fn displacement(&self, t: f64) -> f64 {
        let w = &self.waypoints;
        if t <= w[0][0] {
            return w[0][1];
        }
        for p in w.windows(2) {
            if t <= p[1][0] {
                return p[0][1] + (p[1][1] - p[0][1]) * (t - p[0][0]) / (p[1][0] - p[0][0]);
            }
        }
        w[w.len() - 1][1]
    }

    /// Whether the plate pushes again after rising before the release (a double
    /// compression: the bundle format runs such a plate as a contact tool).
    pub fn pushes_again(&self) -> bool {
        let mut rose = false;
        for w in self.waypoints.windows(2).take_while(|w| w[0][0] < self.release_s) {
            if w[1][1] < w[0][1] {
                rose = true;
            } else if w[1][1] > w[0][1] && rose {
                return true;
            }
        }
        false
    }
}

/// The generator's output at the requested times.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Output times [s].
    pub t_s: Vec<f64>,
    /// Bottom force [N], compression positive.
    pub force_n: Vec<f64>,
    /// Principal stretches `[l_x, l_y, l_z]`.
    pub stretch: Vec<[f64; 3]>,
    /// Whether the plate touched the specimen at the end of the step ending there.
    pub contact: Vec<bool>,
    /// The largest difference between the extrapolations of runs
    /// `(dt, dt/2)` and `(dt/2, dt/4)` over the forces [N]: the error estimate.
    pub error_estimate: f64,
}

impl Trace {
    /// The position [mm] at output `i` of the material point initially at `p`
    /// (`[x, y]` in 2D, `[x, y, z]` in 3D; module docs).
    pub fn position(&self, specimen: &Specimen, i: usize, p: &[f64]) -> Vec<f64> {
        let [w, _, t] = specimen.size_mm;
        let l = self.stretch[i];
        let mut q = vec![0.5 * w + l[0] * (p[0] - 0.5 * w), l[1] * p[1]];
        if p.len() == 3 {
            q.push(0.5 * t + l[2] * (p[2] - 0.5 * t));
        }
        q
    }

    /// The largest force [N].
    pub fn peak_force(&self) -> f64 {
        self.force_n.iter().fold(0.0, |m, f| f.max(m))
    }
}

/// Why a generation failed.
#[derive(Debug, Clone, PartialEq)]
pub struct GeneratorError(pub String);

impl std::fmt::Display for GeneratorError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// The unit-Young Lamé constants `(lambda1, mu1)`.
fn unit_lame(nu: f64) -> (f64, f64) {
    (nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), 1.0 / (2.0 * (1.0 + nu)))
}

/// `E (lambda1 tr(e) I + 2 mu1 e)` in principal values.
fn hooke(e_mpa: f64, lame: (f64, f64), e: [f64; 3]) -> [f64; 3] {
    let tr = e[0] + e[1] + e[2];
    [0, 1, 2].map(|i| e_mpa * (lame.0 * tr + 2.0 * lame.1 * e[i]))
}

fn dev(e: [f64; 3]) -> [f64; 3] {
    let m = (e[0] + e[1] + e[2]) / 3.0;
    [e[0] - m, e[1] - m, e[2] - m]
}

fn norm(e: [f64; 3]) -> f64 {
    (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn axpy(a: f64, x: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    [y[0] + a * x[0], y[1] + a * x[1], y[2] + a * x[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The error function to about 1e-16 (the Maclaurin series below 3, the
/// continued fraction of erfc above).
pub fn erf(x: f64) -> f64 {
    if x < 0.0 {
        return -erf(-x);
    }
    if x < 3.0 {
        let (mut term, mut sum, mut n) = (x, x, 0.0);
        while term.abs() > 1e-17 * sum.abs() {
            n += 1.0;
            term *= -x * x / n;
            sum += term / (2.0 * n + 1.0);
        }
        return sum * std::f64::consts::FRAC_2_SQRT_PI;
    }
    // erfc x = exp(-x^2)/sqrt(pi) / (x + (1/2)/(x + 1/(x + (3/2)/(x + ...)))), backward.
    let mut f = x;
    for k in (1..60).rev() {
        f = x + 0.5 * k as f64 / f;
    }
    1.0 - (-x * x).exp() / (std::f64::consts::PI.sqrt() * f)
}

/// A component's internal variables (principal values).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Internal {
    /// Viscous, flow, Bingham or dual: the viscous log strain; plastic: the plastic strain.
    strain: [f64; 3],
    /// Plastic: the equivalent plastic strain `alpha`.
    alpha: f64,
}

/// Everything carried from one step to the next.
#[derive(Debug, Clone, PartialEq)]
struct State {
    /// The total strains (log or engineering) at the step's start.
    eps: [f64; 3],
    /// The largest equilibrium energy so far [MPa].
    w_max: f64,
    internal: Vec<Internal>,
    contact: bool,
}

impl Material {
    fn validate(&self) -> Result<(), GeneratorError> {
        let bad = |m: String| Err(GeneratorError(m));
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return bad(format!("poisson = {} outside (-1, 0.5)", self.poisson));
        }
        if self.kinematics == Kinematics::Small {
            if let Some(eq) = &self.equilibrium {
                if eq.energy != Energy::NeoHookean || eq.mullins.is_some() {
                    return bad("the equilibrium network has no small-strain form beyond Hooke's law".into());
                }
            }
            if let Some(c) =
                self.components.iter().find(|c| !matches!(c, Component::Viscous { .. } | Component::Damper { .. }))
            {
                return bad(format!("{c:?} has no small-strain form"));
            }
        }
        Ok(())
    }

    /// The sum of the springs' moduli [MPa]: the scale of stresses per unit strain.
    fn modulus_scale(&self) -> f64 {
        let mut e = self.equilibrium.map_or(0.0, |q| q.e_mpa);
        for c in &self.components {
            e += match *c {
                Component::Viscous { e_mpa, .. }
                | Component::Plastic { e_mpa, .. }
                | Component::Flow { e_mpa, .. }
                | Component::Bingham { e_mpa, .. }
                | Component::Dual { e_mpa, .. } => e_mpa,
                Component::Damper { .. } => 0.0,
            };
        }
        e.max(1e-300)
    }

    fn initial_state(&self) -> State {
        State {
            eps: [0.0; 3],
            w_max: 0.0,
            internal: vec![Internal { strain: [0.0; 3], alpha: 0.0 }; self.components.len()],
            contact: true,
        }
    }

    /// The equilibrium network's stress and energy at the strains `eps`.
    fn equilibrium_stress(&self, eq: &Equilibrium, eps: [f64; 3], w_max: f64) -> ([f64; 3], f64) {
        let lame = unit_lame(self.poisson);
        if self.kinematics == Kinematics::Small {
            let s = hooke(eq.e_mpa, lame, eps);
            return (s, 0.5 * dot(s, eps));
        }
        let mu = eq.e_mpa / (2.0 * (1.0 + self.poisson));
        let kappa = eq.e_mpa / (3.0 * (1.0 - 2.0 * self.poisson));
        let ln_j = eps[0] + eps[1] + eps[2];
        let j_m1 = ln_j.exp_m1();
        let j = 1.0 + j_m1;
        // Isochoric stretches squared: exp(2 (eps_i - ln J / 3)); I1bar - 3 without cancellation.
        let e_dev = dev(eps);
        let lbar2_m1 = e_dev.map(|e| (2.0 * e).exp_m1());
        let i1bar_m3 = lbar2_m1[0] + lbar2_m1[1] + lbar2_m1[2];
        let (w_iso, w1) = match eq.energy {
            Energy::NeoHookean => (0.5 * mu * i1bar_m3, 0.5 * mu),
            Energy::Exponential { stiffening: b } => {
                let x = b * i1bar_m3;
                (0.5 * mu / b * x.exp_m1(), 0.5 * mu * x.exp())
            }
        };
        let mean = i1bar_m3 / 3.0;
        let vol = kappa * j * j_m1;
        let mut tau = [0, 1, 2].map(|i| 2.0 * w1 * (lbar2_m1[i] - mean) + vol);
        let w = w_iso + 0.5 * kappa * j_m1 * j_m1;
        if let Some(m) = eq.mullins {
            if w < w_max {
                let eta = 1.0 - erf((w_max - w) / (m.m_mpa + m.beta * w_max)) / m.r;
                tau = tau.map(|s| s * eta);
            }
        }
        (tau, w)
    }

    /// The stress at the step's end strains `eps` from `state` over `dt`, and the
    /// internal variables and the equilibrium energy there.
    fn respond(&self, state: &State, eps: [f64; 3], dt: f64) -> Result<([f64; 3], Vec<Internal>, f64), GeneratorError> {
        let lame = unit_lame(self.poisson);
        let mut tau = [0.0; 3];
        let mut w = 0.0;
        if let Some(eq) = &self.equilibrium {
            let (s, energy) = self.equilibrium_stress(eq, eps, state.w_max);
            tau = s;
            w = energy;
        }
        let mut internal = state.internal.clone();
        for (c, iv) in self.components.iter().zip(internal.iter_mut()) {
            let s = match *c {
                Component::Viscous { e_mpa, tau_s } => {
                    // Backward Euler of d eps_v/dt = (eps - eps_v) / tau.
                    let x = dt / tau_s;
                    iv.strain = [0, 1, 2].map(|i| (iv.strain[i] + x * eps[i]) / (1.0 + x));
                    hooke(e_mpa, lame, sub(eps, iv.strain))
                }
                Component::Dual { e_mpa, tau_load_s, tau_unload_s } => {
                    // Loading when the spring's stress does work on the step's
                    // total strain increment (its energy does not fall without flow).
                    let e_n = sub(state.eps, iv.strain);
                    let trial = sub(eps, iv.strain);
                    let psi = |e: [f64; 3]| dot(hooke(e_mpa, lame, e), e);
                    let tau_s = if psi(trial) >= psi(e_n) { tau_load_s } else { tau_unload_s };
                    let x = dt / tau_s;
                    iv.strain = [0, 1, 2].map(|i| (iv.strain[i] + x * eps[i]) / (1.0 + x));
                    hooke(e_mpa, lame, sub(eps, iv.strain))
                }
                Component::Flow { e_mpa, stress_mpa, exponent } => {
                    let trial = sub(eps, iv.strain);
                    let mu = e_mpa * lame.1;
                    let s_tr = 2.0 * mu * norm(dev(trial));
                    if s_tr > 0.0 {
                        // |s_tr| - 2 mu g = sqrt(2/3) sigma_0 (sqrt(2/3) g / dt)^(1/n), g >= 0;
                        // in y = g^(1/n): 2 mu y^n + c y = |s_tr|, c = sqrt(2/3) sigma_0
                        // (sqrt(2/3) / dt)^(1/n), convex and increasing: Newton from
                        // above (y = |s_tr| / c) falls monotonically to the root.
                        let c = (2.0f64 / 3.0).sqrt() * stress_mpa * ((2.0f64 / 3.0).sqrt() / dt).powf(1.0 / exponent);
                        let mut y = s_tr / c;
                        for _ in 0..200 {
                            let f = 2.0 * mu * y.powf(exponent) + c * y - s_tr;
                            let next = y - f / (2.0 * mu * exponent * y.powf(exponent - 1.0) + c);
                            if next.is_nan() || next >= y || next <= 0.0 {
                                break;
                            }
                            y = next;
                        }
                        let g = y.powf(exponent);
                        let n = dev(trial).map(|x| x * 2.0 * mu / s_tr);
                        iv.strain = axpy(g, n, iv.strain);
                    }
                    hooke(e_mpa, lame, sub(eps, iv.strain))
                }
                Component::Bingham { e_mpa, yield_mpa, viscosity_mpa_s } => {
                    let trial = sub(eps, iv.strain);
                    let mu = e_mpa * lame.1;
                    let s_tr = 2.0 * mu * norm(dev(trial));
                    let over = s_tr - (2.0f64 / 3.0).sqrt() * yield_mpa;
                    if over > 0.0 {
                        let g = over / (2.0 * mu + 2.0 * viscosity_mpa_s / (3.0 * dt));
                        let n = dev(trial).map(|x| x * 2.0 * mu / s_tr);
                        iv.strain = axpy(g, n, iv.strain);
                    }
                    hooke(e_mpa, lame, sub(eps, iv.strain))
                }
                Component::Plastic { e_mpa, yield_mpa, hardening_mpa, kinematic_mpa } => {
                    let trial = sub(eps, iv.strain);
                    let mu = e_mpa * lame.1;
                    // Relative stress: dev tau - beta, beta = 2/3 H_k eps_p.
                    let xi = sub(dev(trial).map(|x| 2.0 * mu * x), iv.strain.map(|p| 2.0 / 3.0 * kinematic_mpa * p));
                    let f = norm(xi) - (2.0f64 / 3.0).sqrt() * (yield_mpa + hardening_mpa * iv.alpha);
                    if f > 0.0 {
                        let g = f / (2.0 * mu + 2.0 / 3.0 * (hardening_mpa + kinematic_mpa));
                        let n = xi.map(|x| x / norm(xi));
                        iv.strain = axpy(g, n, iv.strain);
                        iv.alpha += (2.0f64 / 3.0).sqrt() * g;
                    }
                    hooke(e_mpa, lame, sub(eps, iv.strain))
                }
                Component::Damper { c_mpa_s } => hooke(c_mpa_s / dt, lame, sub(eps, state.eps)),
            };
            tau = [tau[0] + s[0], tau[1] + s[1], tau[2] + s[2]];
        }
        if !tau.iter().all(|s| s.is_finite()) {
            return Err(GeneratorError(format!("non-finite stress at strains {eps:?}")));
        }
        Ok((tau, internal, w))
    }
}

/// The root of an increasing `f` near `x0`: Newton with a difference
/// derivative, kept inside a bracket once one is found; bisection when a
/// Newton step leaves it or stalls. Converged when the step is below `xtol` or
/// `|f|` below `ftol`.
fn solve_increasing(
    f: &mut dyn FnMut(f64) -> Result<f64, GeneratorError>,
    x0: f64,
    xtol: f64,
    ftol: f64,
) -> Result<f64, GeneratorError> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut x = x0;
    let mut fx = f(x)?;
    let mut width = 1e-3;
    for _ in 0..400 {
        if fx.abs() <= ftol {
            return Ok(x);
        }
        if fx < 0.0 {
            lo = lo.max(x);
        } else {
            hi = hi.min(x);
        }
        let h = 1e-7 * (1.0 + x.abs());
        let slope = (f(x + h)? - fx) / h;
        let mut next = if slope > 0.0 { x - fx / slope } else { f64::NAN };
        let bracketed = lo.is_finite() && hi.is_finite();
        if !(next.is_finite()) || next <= lo || next >= hi {
            next = if bracketed {
                0.5 * (lo + hi)
            } else {
                // Expand toward the root until it is bracketed.
                width *= 2.0;
                if fx < 0.0 {
                    x + width
                } else {
                    x - width
                }
            };
        }
        if (next - x).abs() <= xtol || (bracketed && hi - lo <= xtol) {
            return Ok(next);
        }
        x = next;
        fx = f(x)?;
    }
    Err(GeneratorError(format!("the lateral equilibrium did not converge near strain {x:e} (residual {fx:e} MPa)")))
}

/// The trial's step ends: every kink and output time, each interval cut in
/// `ceil(length / dt) * 2^level` equal steps.
fn grid(protocol: &Protocol, outputs: &[f64], dt: f64, level: u32) -> Vec<f64> {
    let mut kinks: Vec<f64> = protocol.waypoints.iter().map(|w| w[0]).collect();
    kinks.extend([0.0, protocol.release_s, protocol.end_s]);
    kinks.extend(outputs.iter().copied());
    kinks.retain(|&t| (0.0..=protocol.end_s).contains(&t));
    kinks.sort_by(f64::total_cmp);
    kinks.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs().max(1.0));
    let mut t = vec![kinks[0]];
    for w in kinks.windows(2) {
        let n = ((w[1] - w[0]) / dt).ceil().max(1.0) as usize * (1 << level);
        t.extend((1..=n).map(|i| if i == n { w[1] } else { w[0] + (w[1] - w[0]) * i as f64 / n as f64 }));
    }
    t
}

/// One step to `t1` from `state` (at `t0`): the step's end strains, stress,
/// internal variables and contact.
fn step(
    material: &Material,
    specimen: &Specimen,
    protocol: &Protocol,
    state: &State,
    t0: f64,
    t1: f64,
) -> Result<(State, [f64; 3]), GeneratorError> {
    let dt = t1 - t0;
    let small = material.kinematics == Kinematics::Small;
    let plane = specimen.dimension == 2;
    let scale = material.modulus_scale();
    let ftol = 1e-14 * scale;
    let xtol = 1e-15;
    let strains = |axial: f64, lateral: f64| [lateral, axial, if plane { 0.0 } else { lateral }];
    // The lateral strain of zero lateral stress at a given axial strain.
    let lateral_at = |axial: f64, guess: f64| -> Result<f64, GeneratorError> {
        let mut f = |l: f64| material.respond(state, strains(axial, l), dt).map(|r| r.0[0]);
        solve_increasing(&mut f, guess, xtol, ftol)
    };
    let finish = |axial: f64, lateral: f64, contact: bool| -> Result<(State, [f64; 3]), GeneratorError> {
        let eps = strains(axial, lateral);
        let (tau, internal, w) = material.respond(state, eps, dt)?;
        let w_max = state.w_max.max(w);
        Ok((State { eps, w_max, internal, contact }, tau))
    };
    let plate_axial = {
        let stretch = 1.0 - protocol.displacement(t1) / specimen.size_mm[1];
        if small {
            stretch - 1.0
        } else {
            stretch.ln()
        }
    };
    let released = t1 > protocol.release_s + 1e-12 * protocol.release_s.max(1.0);
    let held = || -> Result<(State, [f64; 3]), GeneratorError> {
        let lateral = lateral_at(plate_axial, state.eps[0])?;
        finish(plate_axial, lateral, true)
    };
    let free = || -> Result<(State, [f64; 3]), GeneratorError> {
        // Zero axial and lateral stress: the axial strain by the outer
        // iteration, the lateral one inside it.
        let mut lateral = state.eps[0];
        let mut f = |a: f64| -> Result<f64, GeneratorError> {
            lateral = lateral_at(a, lateral)?;
            Ok(material.respond(state, strains(a, lateral), dt)?.0[1])
        };
        let axial = solve_increasing(&mut f, state.eps[1], xtol, ftol)?;
        let lateral = lateral_at(axial, lateral)?;
        finish(axial, lateral, false)
    };
    if released {
        return free();
    }
    match protocol.plate {
        PlateMode::Held => held(),
        PlateMode::Contact => {
            if state.contact {
                let (s, tau) = held()?;
                if tau[1] <= 0.0 {
                    return Ok((s, tau));
                }
                free()
            } else {
                let (s, tau) = free()?;
                if s.eps[1] < plate_axial {
                    return Ok((s, tau));
                }
                held()
            }
        }
    }
}

/// One run at steps of about `dt / 2^level`: force, stretches and contact at
/// the output times.
#[allow(clippy::type_complexity)]
fn run(
    material: &Material,
    specimen: &Specimen,
    protocol: &Protocol,
    outputs: &[f64],
    dt: f64,
    level: u32,
) -> Result<(Vec<f64>, Vec<[f64; 3]>, Vec<bool>), GeneratorError> {
    let times = grid(protocol, outputs, dt, level);
    let small = material.kinematics == Kinematics::Small;
    let area = specimen.area_mm2();
    let mut state = material.initial_state();
    let mut force = vec![0.0; outputs.len()];
    let mut stretch = vec![[1.0; 3]; outputs.len()];
    let mut contact = vec![true; outputs.len()];
    let mut k = 0;
    let mut tau = [0.0; 3];
    for (i, &t) in times.iter().enumerate() {
        if i > 0 {
            let (s, sigma) = step(material, specimen, protocol, &state, times[i - 1], t)?;
            state = s;
            tau = sigma;
        }
        while k < outputs.len() && (outputs[k] - t).abs() <= 1e-12 * t.abs().max(1.0) {
            let l = if small { state.eps.map(|e| 1.0 + e) } else { state.eps.map(f64::exp) };
            // Free of the plate, the axial stress is zero (to the iteration's
            // tolerance): nothing is on the sensor.
            force[k] = match (state.contact, small) {
                (false, _) => 0.0,
                (true, true) => -area * tau[1],
                (true, false) => -area * tau[1] / l[1],
            };
            stretch[k] = l;
            contact[k] = state.contact;
            k += 1;
        }
    }
    if k != outputs.len() {
        return Err(GeneratorError(format!(
            "output times must be sorted and in [0, end_s]: {} of {} reached",
            k,
            outputs.len()
        )));
    }
    Ok((force, stretch, contact))
}

/// Generates a trial at the sorted output times `outputs` [s] with base step
/// `dt` [s] (module docs: backward Euler at `dt` and `dt/2`, extrapolated, a
/// third run at `dt/4` for the error estimate).
pub fn generate(
    material: &Material,
    specimen: &Specimen,
    protocol: &Protocol,
    outputs: &[f64],
    dt: f64,
) -> Result<Trace, GeneratorError> {
    material.validate()?;
    let runs: Vec<_> =
        (0..3).map(|level| run(material, specimen, protocol, outputs, dt, level)).collect::<Result<_, _>>()?;
    let extrapolate = |a: f64, b: f64| 2.0 * b - a;
    let force: Vec<f64> = (0..outputs.len()).map(|i| extrapolate(runs[0].0[i], runs[1].0[i])).collect();
    let finer: Vec<f64> = (0..outputs.len()).map(|i| extrapolate(runs[1].0[i], runs[2].0[i])).collect();
    let error_estimate = force.iter().zip(&finer).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let stretch =
        (0..outputs.len()).map(|i| [0, 1, 2].map(|k| extrapolate(runs[0].1[i][k], runs[1].1[i][k]))).collect();
    Ok(Trace { t_s: outputs.to_vec(), force_n: force, stretch, contact: runs[1].2.clone(), error_estimate })
}

impl Material {
    /// The material as a bundle's `[materials.NAME]` table (`model = "network"`).
    pub fn toml(&self, name: &str) -> String {
        let mut s = format!("[materials.{name}]\nmodel = \"network\"\npoisson = {}\n", self.poisson);
        if self.kinematics == Kinematics::Small {
            s.push_str("kinematics = \"small\"\n");
        }
        if let Some(eq) = &self.equilibrium {
            let energy = match eq.energy {
                Energy::NeoHookean => "energy = \"neo-hookean\"\n".to_string(),
                Energy::Exponential { stiffening } => format!("energy = \"exponential\"\nstiffening = {stiffening}\n"),
            };
            write!(s, "\n[materials.{name}.equilibrium]\n{energy}E_MPa = {}\n", eq.e_mpa).unwrap();
            if let Some(m) = eq.mullins {
                write!(
                    s,
                    "\n[materials.{name}.equilibrium.mullins]\nr = {}\nm_MPa = {}\nbeta = {}\n",
                    m.r, m.m_mpa, m.beta
                )
                .unwrap();
            }
        }
        for c in &self.components {
            match *c {
                Component::Viscous { e_mpa, tau_s } => {
                    write!(s, "\n[[materials.{name}.viscous]]\nE_MPa = {e_mpa}\ntau_s = {tau_s}\n")
                }
                Component::Plastic { e_mpa, yield_mpa, hardening_mpa, kinematic_mpa } => write!(
                    s,
                    "\n[materials.{name}.plastic]\nE_MPa = {e_mpa}\nyield_MPa = {yield_mpa}\nhardening_MPa = {hardening_mpa}\nkinematic_MPa = {kinematic_mpa}\n"
                ),
                Component::Flow { e_mpa, stress_mpa, exponent } => write!(
                    s,
                    "\n[[materials.{name}.flow]]\nE_MPa = {e_mpa}\nstress_MPa = {stress_mpa}\nexponent = {exponent}\n"
                ),
                Component::Bingham { e_mpa, yield_mpa, viscosity_mpa_s } => write!(
                    s,
                    "\n[materials.{name}.bingham]\nE_MPa = {e_mpa}\nyield_MPa = {yield_mpa}\nviscosity_MPa_s = {viscosity_mpa_s}\n"
                ),
                Component::Damper { c_mpa_s } => write!(s, "\n[materials.{name}.damper]\nc_MPa_s = {c_mpa_s}\n"),
                Component::Dual { e_mpa, tau_load_s, tau_unload_s } => write!(
                    s,
                    "\n[[materials.{name}.dual]]\nE_MPa = {e_mpa}\ntau_load_s = {tau_load_s}\ntau_unload_s = {tau_unload_s}\n"
                ),
            }
            .unwrap();
        }
        s
    }
}
