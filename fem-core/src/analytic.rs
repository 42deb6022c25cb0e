//! Closed forms for the verification ladder (design.md 3.1, 3.5).
//!
//! Homogeneous uniaxial compression between frictionless plates: the strain
//! `e(t) = d(t)/H` (compression positive) is piecewise linear, and the stress is
//! `s(t) = B2 e'(t) + G_inf e(t) + sum_k a_k h_k(t)` with the histories integrated
//! exactly segment by segment. After release the stress is zero: springs unload at
//! once, each Voigt element's strain decays as `exp(-E t / c)` from its value at
//! release, and the dashpot keeps its strain. Every integral of an exponential
//! against the piecewise stress is evaluated in closed form.

use crate::material::{phi1, ChainElement, Rheology};

/// `int_0^1 u exp(-x u) du = (1 - exp(-x)(1 + x))/x^2`, accurate for small x.
fn psi(x: f64) -> f64 {
    if x.abs() < 1e-3 {
        0.5 - x / 3.0 + x * x / 8.0 - x * x * x / 30.0
    } else {
        (1.0 - (-x).exp() * (1.0 + x)) / (x * x)
    }
}

/// `int_0^L exp(-lambda (L - s)) exp(-k s) ds`, stable when lambda ~ k.
fn exp_exp(lambda: f64, k: f64, l: f64) -> f64 {
    let (lo, hi) = if lambda < k { (lambda, k) } else { (k, lambda) };
    (-lo * l).exp() * l * phi1((hi - lo) * l)
}

/// One linear piece of the strain history, with the stress on it written as
/// `alpha + beta s + sum_k gamma_k exp(-r_k s)` for `s` in `[0, L]`.
struct Piece {
    t0: f64,
    len: f64,
    alpha: f64,
    beta: f64,
    gamma: [f64; 2],
}

/// Splits the strain history `[t, e]` (piecewise linear, e held after its last
/// point) into pieces up to `t_end`.
fn pieces(rheology: &Rheology, strain: &[[f64; 2]], t_end: f64) -> (Vec<Piece>, [f64; 2], f64) {
    let k = rheology.relaxation();
    let mut out = Vec::new();
    let mut h = [0.0; 2];
    let mut e = 0.0;
    let mut points: Vec<[f64; 2]> = strain.to_vec();
    if points.first().is_none_or(|p| p[0] > 0.0) {
        points.insert(0, [0.0, 0.0]);
    }
    let last = *points.last().unwrap();
    if last[0] < t_end {
        points.push([t_end, last[1]]);
    }
    for w in points.windows(2) {
        let (t0, t1) = (w[0][0], w[1][0].min(t_end));
        if t1 <= t0 {
            if w[0][0] >= t_end {
                break;
            }
            continue;
        }
        let full = w[1][0] - w[0][0];
        let rate = (w[1][1] - w[0][1]) / full;
        let len = t1 - t0;
        let mut alpha = k.viscous * rate + k.equilibrium * e;
        let mut gamma = [0.0; 2];
        for j in 0..k.num_terms {
            alpha += k.amplitudes[j] * rate / k.rates[j];
            gamma[j] = k.amplitudes[j] * (h[j] - rate / k.rates[j]);
        }
        out.push(Piece { t0, len, alpha, beta: k.equilibrium * rate, gamma });
        for j in 0..k.num_terms {
            let x = k.rates[j] * len;
            h[j] = (-x).exp() * h[j] + phi1(x) * len * rate;
        }
        e += rate * len;
        if t1 >= t_end {
            break;
        }
    }
    (out, h, e)
}

/// The uniaxial stress [MPa] at time `t` for the strain history `[t_s, strain]`
/// (piecewise linear; the left limit at a kink).
pub fn uniaxial_stress(rheology: &Rheology, strain: &[[f64; 2]], t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    let k = rheology.relaxation();
    let (ps, _, _) = pieces(rheology, strain, t);
    let p = ps.last().expect("t > 0 gives a piece");
    let s = p.len;
    let mut v = p.alpha + p.beta * s;
    for j in 0..k.num_terms {
        v += p.gamma[j] * (-k.rates[j] * s).exp();
    }
    v
}

/// `int_0^t_end exp(-lambda (t_end - t)) s(t) dt` over the stress of the history.
fn weighted_stress_integral(rheology: &Rheology, strain: &[[f64; 2]], t_end: f64, lambda: f64) -> f64 {
    let k = rheology.relaxation();
    let (ps, _, _) = pieces(rheology, strain, t_end);
    let mut total = 0.0;
    for p in &ps {
        let l = p.len;
        let mut i = p.alpha * l * phi1(lambda * l) + p.beta * l * l * (phi1(lambda * l) - psi(lambda * l));
        for j in 0..k.num_terms {
            i += p.gamma[j] * exp_exp(lambda, k.rates[j], l);
        }
        let after = t_end - (p.t0 + l);
        total += (-lambda * after).exp() * i;
    }
    total
}

/// The uniaxial strain at time `t >= release_s` of a specimen released (stress
/// zero) at `release_s` after the strain history `[t_s, strain]`.
pub fn uniaxial_recovery_strain(rheology: &Rheology, strain: &[[f64; 2]], release_s: f64, t: f64) -> f64 {
    assert!(t >= release_s);
    rheology
        .chain()
        .iter()
        .map(|el| match *el {
            ChainElement::Spring { .. } => 0.0,
            ChainElement::Voigt { e_mpa, c_mpa_s } => {
                let lambda = e_mpa / c_mpa_s;
                weighted_stress_integral(rheology, strain, release_s, lambda) / c_mpa_s
                    * (-lambda * (t - release_s)).exp()
            }
            ChainElement::Dashpot { c_mpa_s } => weighted_stress_integral(rheology, strain, release_s, 0.0) / c_mpa_s,
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat1() -> Rheology {
        crate::material::Material::seed_mat1_force().rheology
    }

    /// Integrates the chain ODE (eq. 1) under the stress closed form with a fine
    /// RK4 and compares the strain: the closed forms agree with each other.
    #[test]
    fn chain_ode_reproduces_the_strain_history() {
        for model in [
            mat1(),
            Rheology::ThreeElement { e1_mpa: 0.05, c1_mpa_s: 0.3, c3_mpa_s: 12.0 },
            Rheology::FourElement { e1_mpa: 0.05, c1_mpa_s: 0.3, e2_mpa: 0.02, c3_mpa_s: 12.0 },
        ] {
            let h = 59.5;
            let strain = [[0.0, 0.0], [28.87, 5.774 / h], [210.93, 5.774 / h]];
            // Element strains driven by the closed-form stress, integrated by RK4.
            let chain = model.chain();
            let mut x = vec![0.0; chain.len()];
            let n = 400_000;
            let dt = 210.93 / n as f64;
            let rhs = |t: f64, x: &[f64]| -> Vec<f64> {
                let s = uniaxial_stress(&model, &strain, t);
                chain
                    .iter()
                    .zip(x)
                    .map(|(el, &xi)| match *el {
                        ChainElement::Spring { .. } => 0.0,
                        ChainElement::Voigt { e_mpa, c_mpa_s } => (s - e_mpa * xi) / c_mpa_s,
                        ChainElement::Dashpot { c_mpa_s } => s / c_mpa_s,
                    })
                    .collect()
            };
            for i in 0..n {
                let t = i as f64 * dt + 1e-12;
                let k1 = rhs(t, &x);
                let x2: Vec<f64> = x.iter().zip(&k1).map(|(a, b)| a + 0.5 * dt * b).collect();
                let k2 = rhs(t + 0.5 * dt, &x2);
                let x3: Vec<f64> = x.iter().zip(&k2).map(|(a, b)| a + 0.5 * dt * b).collect();
                let k3 = rhs(t + 0.5 * dt, &x3);
                let x4: Vec<f64> = x.iter().zip(&k3).map(|(a, b)| a + dt * b).collect();
                let k4 = rhs(t + dt, &x4);
                for j in 0..x.len() {
                    x[j] += dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
                }
            }
            let s_end = uniaxial_stress(&model, &strain, 210.93);
            let total: f64 = chain
                .iter()
                .zip(&x)
                .map(|(el, &xi)| match *el {
                    ChainElement::Spring { e_mpa } => s_end / e_mpa,
                    _ => xi,
                })
                .sum();
            let want = 5.774 / h;
            assert!((total - want).abs() < 1e-7 * want, "{model:?}: chain strain {total} vs {want}");
            // At release the closed-form recovery strain equals the chain's
            // non-spring strains.
            let rec = uniaxial_recovery_strain(&model, &strain, 210.93, 210.93);
            let non_spring: f64 = chain
                .iter()
                .zip(&x)
                .filter(|(el, _)| !matches!(el, ChainElement::Spring { .. }))
                .map(|(_, &xi)| xi)
                .sum();
            assert!((rec - non_spring).abs() < 1e-7 * want, "{model:?}: {rec} vs {non_spring}");
        }
    }

    #[test]
    fn elastic_stress_is_hookean() {
        let m = Rheology::Elastic { e_mpa: 2.0 };
        let s = uniaxial_stress(&m, &[[0.0, 0.0], [1.0, 0.1]], 0.5);
        assert!((s - 0.1).abs() < 1e-15);
        assert_eq!(uniaxial_recovery_strain(&m, &[[0.0, 0.0], [1.0, 0.1]], 1.0, 3.0), 0.0);
    }
}
