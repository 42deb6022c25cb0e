use fem_core::material::{Material, Rheology};
use fem_core::mesh;
use fem_core::press::*;

fn glued_2d(h: f64) -> (f64, f64, usize) {
    let p = Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0);
    let m = mesh::rectangle(58.0, 59.5, h, "m").unwrap();
    let n = m.num_cells();
    let prob = PlanePress::new_2d(m, 12.0, vec![Material::seed_mat1_force()], p).unwrap();
    let r = simulate(&prob, &Settings::default(), &mut |_| {}).unwrap();
    let f = r.bottom_force_at(28.87);
    let snap = r.snapshot_at(210.93).unwrap();
    // bulge: max x displacement over nodes at x = W
    let mut bulge: f64 = 0.0;
    for (i, p) in prob.mesh.nodes.iter().enumerate() {
        if (p[0] - 58.0).abs() < 1e-9 {
            bulge = bulge.max(snap.displacement[2 * i]);
        }
    }
    (f, bulge, n)
}

#[test]
fn explore_glued() {
    for h in [8.0, 4.0, 2.0, 1.0, 0.5] {
        let t = std::time::Instant::now();
        let (f, b, n) = glued_2d(h);
        eprintln!("2D h {h}: cells {n} force {f:.8} bulge {b:.8} ({:?})", t.elapsed());
    }
}

#[test]
fn explore_vibration() {
    for (name, rh) in [
        ("four", Rheology::FourElement { e1_mpa: 0.0349, c1_mpa_s: 0.0071, e2_mpa: 0.0221, c3_mpa_s: 29.719 }),
        ("five", Material::seed_mat1_force().rheology),
    ] {
        let p = Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0);
        let m = mesh::rectangle(58.0, 59.5, 6.0, "m").unwrap();
        let mut prob = PlanePress::new_2d(m, 12.0, vec![Material::new(rh, 0.3746).unwrap()], p).unwrap();
        prob.density_t_mm3 = 1.27e-9;
        prob.protocol.end_s = 2.0;
        prob.protocol.release_s = 2.0;
        prob.protocol.waypoints = vec![[0.0, 0.0], [2.0, 0.4]];
        let s = Settings { integrator: Integrator::Dynamic, fixed_dt_s: Some(5e-4), ..Settings::default() };
        let t = std::time::Instant::now();
        let dy = simulate(&prob, &s, &mut |_| {}).unwrap();
        let qs = simulate(&prob, &Settings::default(), &mut |_| {}).unwrap();
        let mut amp: f64 = 0.0;
        for st in &dy.steps {
            if st.t_s > 0.5 {
                amp = amp.max((st.bottom_force_n - qs.bottom_force_at(st.t_s)).abs());
            }
        }
        eprintln!(
            "{name}: amp {amp:.3e} N, force(2) {:.4e}, rel {:.3e} ({:?})",
            qs.bottom_force_at(2.0),
            amp / qs.bottom_force_at(2.0),
            t.elapsed()
        );
        for tt in [0.01, 0.02, 0.03, 0.05, 0.1, 0.5, 1.0, 2.0] {
            eprintln!("  t {tt}: dyn {:.5e} qs {:.5e}", dy.bottom_force_at(tt), qs.bottom_force_at(tt));
        }
    }
}

#[test]
fn explore_thin() {
    for plate in [Attachment::Frictionless, Attachment::Glued] {
        let mut p = Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0);
        p.plate = plate;
        p.support = plate;
        let (w, h, t) = (58.0, 59.5, 58.0 * 0.05);
        let m2 = mesh::rectangle(w, h, 2.0, "m").unwrap();
        let p2 = PlanePress::new_2d(m2, t, vec![Material::seed_mat1_force()], p.clone()).unwrap();
        let m3 = mesh::block([w, h, t], 2.9 / 2.0, "m").unwrap();
        let n3 = m3.num_cells();
        let p3 = SolidPress::new_3d(m3, vec![Material::seed_mat1_force()], p.clone()).unwrap();
        let tt = std::time::Instant::now();
        let r2 = simulate(&p2, &Settings::default(), &mut |_| {}).unwrap();
        let r3 = simulate(&p3, &Settings::default(), &mut |_| {}).unwrap();
        eprintln!(
            "{plate:?}: 2D {:.6} 3D {:.6} rel {:.3e} (3D cells {n3}) {:?}",
            r2.bottom_force_at(28.87),
            r3.bottom_force_at(28.87),
            (r2.bottom_force_at(28.87) / r3.bottom_force_at(28.87) - 1.0),
            tt.elapsed()
        );
    }
}
