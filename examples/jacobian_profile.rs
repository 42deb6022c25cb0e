//! Temporary profile: primal vs sensitivity runs of the Mat1 2D trial.
use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, ParameterKind, PlanePress, Protocol, SensitivityParameter, Settings};
use std::time::Instant;

fn main() {
    let h: f64 = std::env::args().nth(1).map(|s| s.parse().unwrap()).unwrap_or(3.0);
    let protocol = Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0);
    let mesh = mesh::rectangle(58.0, 59.5, h, "mat1").unwrap();
    let p = PlanePress::new_2d(mesh, 12.0, vec![Material::seed_mat1_force()], protocol).unwrap();
    let params: Vec<SensitivityParameter> =
        (0..5).map(|k| SensitivityParameter { regions: vec![0], kind: ParameterKind::Rheology(k) }).collect();
    let s = Settings::default();
    let n = 20;
    let t = Instant::now();
    let mut steps = 0;
    for _ in 0..n {
        let r = press::simulate(&p, &s, &mut |_| {}).unwrap();
        steps = r.steps.len();
    }
    let tp = t.elapsed().as_secs_f64() / n as f64;
    let t = Instant::now();
    for _ in 0..n {
        press::simulate_with_sensitivities(&p, &s, &params, &mut |_| {}).unwrap();
    }
    let ts = t.elapsed().as_secs_f64() / n as f64;
    println!(
        "h {h}: primal {:.2} ms ({steps} steps), with 5 sensitivities {:.2} ms, ratio 6*primal/sens = {:.2}",
        tp * 1e3,
        ts * 1e3,
        6.0 * tp / ts
    );
}
