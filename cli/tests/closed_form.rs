//! The engine issue's bar for third parties: `wagashi press` on any v1 bundle with
//! frictionless plates (three-, four- or five-element material, 2D or 3D)
//! reproduces the closed form within 1e-6 of the peak force at every output time.
//! The bundles are written here as a third party would write them.

mod common;

use common::*;
use fem_core::analytic::uniaxial_stress;
use fem_core::material::Rheology;

struct Case {
    dim: usize,
    model: &'static str,
    params: &'static str,
    rheology: Rheology,
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            dim: 3,
            model: "five-element",
            params: "E1_MPa = 0.0349\nE2_MPa = 0.0221\nc1_MPa_s = 0.0071\nc2_MPa_s = 0.1869\nc3_MPa_s = 29.719",
            rheology: Rheology::FiveElement {
                e1_mpa: 0.0349,
                e2_mpa: 0.0221,
                c1_mpa_s: 0.0071,
                c2_mpa_s: 0.1869,
                c3_mpa_s: 29.719,
            },
        },
        Case {
            dim: 2,
            model: "four-element",
            params: "E1_MPa = 0.05\nc1_MPa_s = 0.3\nE2_MPa = 0.02\nc3_MPa_s = 12.0",
            rheology: Rheology::FourElement { e1_mpa: 0.05, c1_mpa_s: 0.3, e2_mpa: 0.02, c3_mpa_s: 12.0 },
        },
        Case {
            dim: 3,
            model: "three-element",
            params: "E1_MPa = 0.05\nc1_MPa_s = 0.3\nc3_MPa_s = 12.0",
            rheology: Rheology::ThreeElement { e1_mpa: 0.05, c1_mpa_s: 0.3, c3_mpa_s: 12.0 },
        },
        Case {
            dim: 2,
            model: "five-element",
            params: "E1_MPa = 0.0454\nE2_MPa = 0.0141\nc1_MPa_s = 0.0115\nc2_MPa_s = 0.1991\nc3_MPa_s = 13.370",
            rheology: Rheology::FiveElement {
                e1_mpa: 0.0454,
                e2_mpa: 0.0141,
                c1_mpa_s: 0.0115,
                c2_mpa_s: 0.1991,
                c3_mpa_s: 13.370,
            },
        },
    ]
}

#[test]
fn third_party_frictionless_bundles_match_the_closed_form() {
    let (w, h, t) = (50.0, 40.0, 11.0);
    // A push, a partial unload that stays in compression, a hold, then release.
    let waypoints = [[0.0, 0.0], [20.0, 4.0], [30.0, 3.0], [90.0, 3.0]];
    for case in cases() {
        let dir = tempfile::tempdir().unwrap();
        let bundle = dir.path().join("trial");
        std::fs::create_dir(&bundle).unwrap();
        let toml = format!(
            "format = \"wagashi-experiment/1\"\nname = \"third-party\"\ndimension = {}\n\n[specimen]\nshape = \"block\"\n\
             size_mm = [{w}, {h}, {t}]\nmaterial = \"gel\"\n\n[materials.gel]\nmodel = \"{}\"\npoisson = 0.31\n{}\n\n\
             [protocol]\ntool = \"plate\"\ntool_contact = \"frictionless\"\nsupport = \"frictionless\"\n\
             waypoints = [[0.0, 0.0], [20.0, 4.0], [30.0, 3.0], [90.0, 3.0]]\nrelease_s = 90.0\nend_s = 150.0\n",
            case.dim, case.model, case.params
        );
        std::fs::write(bundle.join("experiment.toml"), toml).unwrap();
        let out = dir.path().join("out");
        let o = wagashi_in(dir.path(), ["press", "trial", "-o", "out", "--size-mm", "9", "--output-dt", "0.25"]);
        assert_success(&o);
        let strain: Vec<[f64; 2]> = waypoints.iter().map(|p| [p[0], p[1] / h]).collect();
        let area = w * t;
        let csv = std::fs::read_to_string(out.join("force.csv")).unwrap();
        let mut rows = 0;
        let mut peak: f64 = 0.0;
        let mut samples = Vec::new();
        for line in csv.lines().skip(1) {
            let mut it = line.split(',').map(|v| v.parse::<f64>().unwrap());
            let (ts, f) = (it.next().unwrap(), it.next().unwrap());
            // After release the free specimen carries no load: the closed form is 0.
            let want = if ts <= 90.0 { area * uniaxial_stress(&case.rheology, &strain, ts) } else { 0.0 };
            peak = peak.max(want.abs());
            samples.push((ts, f, want));
            rows += 1;
        }
        assert_eq!(rows, 601, "{}D {}: one row every 0.25 s from 0 to 150 s", case.dim, case.model);
        let worst = samples.iter().map(|&(_, f, want)| (f - want).abs()).fold(0.0, f64::max) / peak;
        eprintln!("{}D {}: largest deviation {worst:.2e} of the peak", case.dim, case.model);
        assert!(worst < 1e-6, "{}D {}: force.csv deviates by {worst:e} of the peak", case.dim, case.model);
    }
}
