//! Forward sensitivities against central finite differences of replayed runs
//! (issue: parameter identification, "agreement within 1e-6 relative").
//!
//! Each check compares, for every parameter, the exact derivative of the bottom
//! force at many times and of the marker positions with the fourth-order central
//! difference `(f(p - 2h) - 8 f(p - h) + 8 f(p + h) - f(p + 2h))/(12 h)` computed with
//! the same step sequence (`Settings::step_ends_s`), at a relative step `h/p` of 1e-3:
//! the truncation error is about (1e-3)^4 = 1e-12 relative, and the round-off of a
//! marker position (about 30 mm x 2.2e-16) over the step stays near 1e-7 of the
//! derivatives here (a second-order difference at 1e-5 has round-off of several 1e-6
//! on marker positions: measured, it failed for c1 of the layered body). The error
//! is measured relative to the largest magnitude of the derivative over the curve (a
//! pointwise relative error is meaningless where a derivative crosses zero).

use fem_core::material::{Material, Rheology};
use fem_core::mesh::{self, Layer};
use fem_core::press::{
    self, Attachment, AxisymmetricPress, MarkerRequest, ParameterKind, PlanePress, PressResult, Protocol,
    SensitivityParameter, Settings, SolidPress,
};

fn mat1() -> Material {
    Material::seed_mat1_force()
}

fn mat2() -> Material {
    Material::new(
        Rheology::FiveElement { e1_mpa: 0.0454, e2_mpa: 0.0141, c1_mpa_s: 0.0115, c2_mpa_s: 0.1991, c3_mpa_s: 13.370 },
        0.3353,
    )
    .unwrap()
}

/// Sets parameter `kind` of the materials of `regions` to `value`.
fn set(materials: &mut [Material], regions: &[usize], kind: ParameterKind, value: f64) {
    for &r in regions {
        let m = &mut materials[r];
        match kind {
            ParameterKind::Poisson => m.poisson = value,
            ParameterKind::Rheology(i) => {
                let mut p: Vec<f64> = m.rheology.parameters().iter().map(|x| x.1).collect();
                p[i] = value;
                m.rheology = match m.rheology {
                    Rheology::Elastic { .. } => Rheology::Elastic { e_mpa: p[0] },
                    Rheology::ThreeElement { .. } => {
                        Rheology::ThreeElement { e1_mpa: p[0], c1_mpa_s: p[1], c3_mpa_s: p[2] }
                    }
                    Rheology::FourElement { .. } => {
                        Rheology::FourElement { e1_mpa: p[0], e2_mpa: p[1], c1_mpa_s: p[2], c3_mpa_s: p[3] }
                    }
                    Rheology::FiveElement { .. } => Rheology::FiveElement {
                        e1_mpa: p[0],
                        e2_mpa: p[1],
                        c1_mpa_s: p[2],
                        c2_mpa_s: p[3],
                        c3_mpa_s: p[4],
                    },
                };
            }
        }
    }
}

fn value_of(materials: &[Material], region: usize, kind: ParameterKind) -> f64 {
    match kind {
        ParameterKind::Poisson => materials[region].poisson,
        ParameterKind::Rheology(i) => materials[region].rheology.parameters()[i].1,
    }
}

/// Compares the sensitivities of `run` with central differences at `times`.
fn check<F>(materials: Vec<Material>, parameters: Vec<SensitivityParameter>, times: &[f64], run: F)
where
    F: Fn(&[Material], &Settings, Option<&[SensitivityParameter]>) -> (PressResult, Option<press::Sensitivities>),
{
    let (base, sens) = run(&materials, &Settings::default(), Some(&parameters));
    let sens = sens.unwrap();
    let replay = Settings { step_ends_s: Some(base.steps.iter().map(|s| s.t_s).collect()), ..Settings::default() };
    for (p, param) in parameters.iter().enumerate() {
        let x = value_of(&materials, param.regions[0], param.kind);
        let h = 1e-3 * x.abs();
        let shifted = |v: f64| {
            let mut m = materials.clone();
            set(&mut m, &param.regions, param.kind, v);
            run(&m, &replay, None).0
        };
        let runs = [shifted(x - 2.0 * h), shifted(x - h), shifted(x + h), shifted(x + 2.0 * h)];
        for r in &runs {
            assert_eq!(r.steps.len(), base.steps.len(), "the replay took other steps");
        }
        let stencil = |f: &dyn Fn(&PressResult) -> f64| {
            (f(&runs[0]) - 8.0 * f(&runs[1]) + 8.0 * f(&runs[2]) - f(&runs[3])) / (12.0 * h)
        };
        let exact: Vec<f64> = times.iter().map(|&t| sens.bottom_force_at(t)[p]).collect();
        let fd: Vec<f64> = times.iter().map(|&t| stencil(&|r: &PressResult| r.bottom_force_at(t))).collect();
        let scale = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(scale > 0.0, "parameter {p} has no effect on the force");
        for (i, (e, f)) in exact.iter().zip(&fd).enumerate() {
            assert!((e - f).abs() <= 1e-6 * scale, "param {p} {param:?}, t = {}: exact {e} vs fd {f}", times[i]);
        }
        // Markers: every sample, every component.
        let mut mscale = 0.0f64;
        let mut pairs = Vec::new();
        for (m, track) in base.markers.iter().enumerate() {
            for i in 0..track.samples.len() {
                for k in 0..track.samples[i].1.len() {
                    let fd = stencil(&|r: &PressResult| r.markers[m].samples[i].1[k]);
                    let e = sens.markers[m][i][p][k];
                    mscale = mscale.max(e.abs());
                    pairs.push((m, i, k, e, fd));
                }
            }
        }
        for (m, i, k, e, f) in pairs {
            assert!((e - f).abs() <= 1e-6 * mscale.max(1e-300), "param {p}, marker {m} sample {i}[{k}]: {e} vs {f}");
        }
    }
}

fn all_parameters(regions: &[usize]) -> Vec<SensitivityParameter> {
    let mut v: Vec<SensitivityParameter> =
        (0..5).map(|i| SensitivityParameter { regions: regions.to_vec(), kind: ParameterKind::Rheology(i) }).collect();
    v.push(SensitivityParameter { regions: regions.to_vec(), kind: ParameterKind::Poisson });
    v
}

/// The five rheology parameters only: on a body of one region the engine then
/// carries the derivatives as nodal vectors and lifts the held rows with one solve
/// per constraint set (`NodalBatch`), instead of a cell pass and a solve per step.
fn rheology_parameters(regions: &[usize]) -> Vec<SensitivityParameter> {
    (0..5).map(|i| SensitivityParameter { regions: regions.to_vec(), kind: ParameterKind::Rheology(i) }).collect()
}

fn sample_times(end: f64) -> Vec<f64> {
    (1..=80).map(|i| end * i as f64 / 80.0 - 0.37).collect()
}

/// The seed's glued 2D trial (shortened), all six parameters, markers at the keep
/// and final shapes: one kernel group, one factorization.
#[test]
fn glued_plane_stress_trial_matches_differences() {
    let protocol = Protocol::ramp_hold_release(0.2, 28.87, 80.0, 160.0);
    let mesh = mesh::rectangle(58.0, 59.5, 6.0, "mat1").unwrap();
    let run = |m: &[Material], s: &Settings, params: Option<&[SensitivityParameter]>| {
        let mut p = PlanePress::new_2d(mesh.clone(), 12.0, m.to_vec(), protocol.clone()).unwrap();
        p.markers = vec![
            MarkerRequest { name: "side".into(), position: vec![58.0, 29.75], times: vec![0.0, 50.0, 80.0, 160.0] },
            MarkerRequest { name: "top".into(), position: vec![20.0, 59.5], times: vec![0.0, 100.0, 160.0] },
        ];
        match params {
            Some(ps) => {
                let (r, s) = press::simulate_with_sensitivities(&p, s, ps, &mut |_| {}).unwrap();
                (r, Some(s))
            }
            None => (press::simulate(&p, s, &mut |_| {}).unwrap(), None),
        }
    };
    check(vec![mat1()], all_parameters(&[0]), &sample_times(160.0), run);
    check(vec![mat1()], rheology_parameters(&[0]), &sample_times(160.0), run);
}

/// A layered, frictionless 2D body (two materials, two kernel groups, the matrix
/// refactored per step size): the outer layers share one material, so its
/// parameters are shared unknowns of two regions.
#[test]
fn layered_frictionless_trial_matches_differences() {
    let protocol = Protocol {
        plate: Attachment::Frictionless,
        support: Attachment::Frictionless,
        ..Protocol::ramp_hold_release(0.2, 20.0, 60.0, 120.0)
    };
    let layers = [
        Layer { region: "a-low".into(), thickness_mm: 10.0 },
        Layer { region: "b".into(), thickness_mm: 10.0 },
        Layer { region: "a-high".into(), thickness_mm: 10.0 },
    ];
    let mesh = mesh::layered_rectangle(30.0, &layers, 5.0).unwrap();
    let run = |m: &[Material], s: &Settings, params: Option<&[SensitivityParameter]>| {
        let mut p = PlanePress::new_2d(mesh.clone(), 10.0, m.to_vec(), protocol.clone()).unwrap();
        p.markers =
            vec![MarkerRequest { name: "side".into(), position: vec![30.0, 15.0], times: vec![0.0, 30.0, 120.0] }];
        match params {
            Some(ps) => {
                let (r, s) = press::simulate_with_sensitivities(&p, s, ps, &mut |_| {}).unwrap();
                (r, Some(s))
            }
            None => (press::simulate(&p, s, &mut |_| {}).unwrap(), None),
        }
    };
    let mut params = all_parameters(&[0, 2]);
    params.extend(all_parameters(&[1]));
    check(vec![mat1(), mat2(), mat1()], params, &sample_times(120.0), run);
}

/// 3D, glued, a coarse block: E1, c3 and nu.
#[test]
fn glued_solid_trial_matches_differences() {
    let protocol = Protocol::ramp_hold_release(0.2, 10.0, 30.0, 60.0);
    let mesh = mesh::block([10.0, 10.0, 6.0], 2.5, "mat1").unwrap();
    let run = |m: &[Material], s: &Settings, params: Option<&[SensitivityParameter]>| {
        let mut p = SolidPress::new_3d(mesh.clone(), m.to_vec(), protocol.clone()).unwrap();
        p.markers =
            vec![MarkerRequest { name: "side".into(), position: vec![10.0, 5.0, 3.0], times: vec![0.0, 30.0, 60.0] }];
        match params {
            Some(ps) => {
                let (r, s) = press::simulate_with_sensitivities(&p, s, ps, &mut |_| {}).unwrap();
                (r, Some(s))
            }
            None => (press::simulate(&p, s, &mut |_| {}).unwrap(), None),
        }
    };
    let params = vec![
        SensitivityParameter { regions: vec![0], kind: ParameterKind::Rheology(0) },
        SensitivityParameter { regions: vec![0], kind: ParameterKind::Rheology(4) },
        SensitivityParameter { regions: vec![0], kind: ParameterKind::Poisson },
    ];
    check(vec![mat1()], params.clone(), &sample_times(60.0), run);
    check(vec![mat1()], params[..2].to_vec(), &sample_times(60.0), run);
}

/// Axisymmetric, glued (the hoop strain row): all six parameters.
#[test]
fn glued_axisymmetric_trial_matches_differences() {
    let protocol = Protocol::ramp_hold_release(0.2, 10.0, 30.0, 60.0);
    let mesh = mesh::axisymmetric_section(4.0, 9.0, 1.0, "mat1").unwrap();
    let run = |m: &[Material], s: &Settings, params: Option<&[SensitivityParameter]>| {
        let mut p = AxisymmetricPress::new_axisymmetric(mesh.clone(), m.to_vec(), protocol.clone()).unwrap();
        p.markers = vec![MarkerRequest { name: "side".into(), position: vec![4.0, 4.5], times: vec![0.0, 30.0, 60.0] }];
        match params {
            Some(ps) => {
                let (r, s) = press::simulate_with_sensitivities(&p, s, ps, &mut |_| {}).unwrap();
                (r, Some(s))
            }
            None => (press::simulate(&p, s, &mut |_| {}).unwrap(), None),
        }
    };
    check(vec![mat1()], all_parameters(&[0]), &sample_times(60.0), run);
    check(vec![mat1()], rheology_parameters(&[0]), &sample_times(60.0), run);
}

/// Axisymmetric, frictionless plate and floor (the imported texture-analyser
/// trials), the rheology parameters alone: the nodal path across the release,
/// where the plate's rows change from held to free.
#[test]
fn frictionless_axisymmetric_rheology_matches_differences() {
    let protocol = Protocol {
        plate: Attachment::Frictionless,
        support: Attachment::Frictionless,
        ..Protocol::ramp_hold_release(0.3, 10.0, 30.0, 60.0)
    };
    let mesh = mesh::axisymmetric_section(4.0, 9.0, 1.0, "mat1").unwrap();
    let run = |m: &[Material], s: &Settings, params: Option<&[SensitivityParameter]>| {
        let mut p = AxisymmetricPress::new_axisymmetric(mesh.clone(), m.to_vec(), protocol.clone()).unwrap();
        p.markers = vec![
            MarkerRequest { name: "side".into(), position: vec![4.0, 4.5], times: vec![0.0, 20.0, 45.0, 60.0] },
            MarkerRequest { name: "top".into(), position: vec![2.0, 9.0], times: vec![0.0, 40.0, 60.0] },
        ];
        match params {
            Some(ps) => {
                let (r, s) = press::simulate_with_sensitivities(&p, s, ps, &mut |_| {}).unwrap();
                (r, Some(s))
            }
            None => (press::simulate(&p, s, &mut |_| {}).unwrap(), None),
        }
    };
    check(vec![mat1()], rheology_parameters(&[0]), &sample_times(60.0), run);
}
