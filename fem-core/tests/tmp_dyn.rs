use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::*;
#[test]
fn dyn_probe() {
    let m = mesh::rectangle(58.0, 59.5, 10.0, "m").unwrap();
    let mut p = PlanePress::new_2d(
        m,
        12.0,
        vec![Material::seed_mat1_force()],
        Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0),
    )
    .unwrap();
    p.density_t_mm3 = 1.27e-9;
    for fixed in [None, Some(0.01)] {
        let dy = simulate(
            &p,
            &Settings { integrator: Integrator::Dynamic, fixed_dt_s: fixed, ..Settings::default() },
            &mut |_| {},
        )
        .unwrap();
        let qs = simulate(&p, &Settings::default(), &mut |_| {}).unwrap();
        let peak = qs.peak_force();
        eprintln!("fixed {fixed:?}: dyn steps {}", dy.steps.len());
        for s in dy.steps.iter().take(12) {
            eprintln!(
                "  t {:.5} dt {:.2e} dyn {:.6e} qs {:.6e} rel {:.2e}",
                s.t_s,
                s.dt_s,
                s.bottom_force_n,
                qs.bottom_force_at(s.t_s),
                (s.bottom_force_n - qs.bottom_force_at(s.t_s)) / peak
            );
        }
        for t in [1.0, 5.0, 20.0, 28.0, 28.87, 29.0, 100.0] {
            eprintln!("  t {t}: rel {:.3e}", (dy.bottom_force_at(t) - qs.bottom_force_at(t)) / peak);
        }
    }
}
