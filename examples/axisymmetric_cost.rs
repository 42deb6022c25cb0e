//! The measurement behind "axisymmetric triangles make cylinder fits 100x cheaper
//! than 3D" (issue: parameter identification): whole runs (`press::simulate`:
//! model, assembly, ordering, factorization, all steps) of the glued Mat1 cylinder
//! of `tests/axisymmetric.rs` (R 4 mm, H 9 mm, 20 % in 10 s, hold to 40 s, end 100
//! s), timed against the peak force's error relative to the Richardson-extrapolated
//! axisymmetric limit; for each 3D run, the axisymmetric time at the same error
//! (log-log interpolation between the two axisymmetric runs that bracket it).
//!
//! Run: `cargo run --release -p wagashi-workspace-tests --example axisymmetric_cost`
//! (about a minute). Figures in BENCHMARKS.md.

use std::time::Instant;

use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Attachment, AxisymmetricPress, Protocol, Settings, SolidPress};

const R: f64 = 4.0;
const H: f64 = 9.0;

fn protocol() -> Protocol {
    let mut p = Protocol::ramp_hold_release(0.2 * H / 10.0, 10.0, 40.0, 100.0);
    p.plate = Attachment::Glued;
    p.support = Attachment::Glued;
    p
}

fn axisymmetric(h: f64) -> AxisymmetricPress {
    let m = mesh::axisymmetric_section(R, H, h, "gel").unwrap();
    AxisymmetricPress::new_axisymmetric(m, vec![Material::seed_mat1_force()], protocol()).unwrap()
}

fn solid(h: f64) -> SolidPress {
    SolidPress::new_3d(mesh::cylinder(R, H, h, "gel").unwrap(), vec![Material::seed_mat1_force()], protocol()).unwrap()
}

/// Median wall time [s] of `repeats` runs of `f`, and its last value.
fn timed<T>(repeats: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats {
        let clock = Instant::now();
        last = Some(f());
        times.push(clock.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], last.unwrap())
}

/// Cost of a whole run (`press::simulate`: model, assembly, ordering,
/// factorization, all steps) against the peak force's error relative to the
/// Richardson-extrapolated axisymmetric limit, for both models; then, for each 3D
/// run, the axisymmetric time at the same error (log-log interpolation between the
/// two axisymmetric runs that bracket it) and the ratio.
fn main() {
    let axi_sizes = [1.0, 0.5, 0.4, 0.3, 0.25, 0.2, 0.15, 0.125, 0.1, 0.0625, 0.03125];
    let mut axi: Vec<(f64, f64, f64)> = Vec::new(); // (h, time, peak)
    for h in axi_sizes {
        let p = axisymmetric(h);
        let repeats = if h >= 0.1 { 7 } else { 3 };
        let (t, r) = timed(repeats, || press::simulate(&p, &Settings::default(), &mut |_| {}).unwrap());
        axi.push((h, t, r.peak_force()));
    }
    // Richardson on the three finest, refined by 2.
    let peak_at = |h: f64| axi.iter().find(|a| a.0 == h).expect("run").2;
    let (f1, f2, f3) = (peak_at(0.125), peak_at(0.0625), peak_at(0.03125));
    let p = ((f1 - f2) / (f2 - f3)).log2();
    let limit = f3 - (f2 - f3) / (2f64.powf(p) - 1.0);
    eprintln!("axisymmetric limit {limit:.7} N (observed order {p:.3} on h = 0.125, 0.0625, 0.03125)");
    eprintln!("model         h [mm]   cells    time [s]   peak [N]    error");
    let err = |f: f64| (f - limit) / limit;
    for &(h, t, f) in &axi {
        let cells = 2 * (R / h).ceil() as usize * (H / h - 1e-9).ceil() as usize;
        eprintln!("axisymmetric  {h:<7}  {cells:<7}  {t:<9.4}  {f:.7}   {:.3e}", err(f));
    }
    for h in [1.0, 0.5, 0.25] {
        let ps = solid(h);
        let (t, r) =
            timed(if h >= 0.5 { 3 } else { 1 }, || press::simulate(&ps, &Settings::default(), &mut |_| {}).unwrap());
        let e = err(r.peak_force());
        eprintln!("3D            {h:<7}  {:<7}  {t:<9.4}  {:.7}   {e:.3e}", ps.mesh.num_cells(), r.peak_force());
        // The axisymmetric runs that bracket this error (errors fall as h falls).
        let bracket = axi.windows(2).find(|w| err(w[0].2) >= e && err(w[1].2) <= e);
        if let Some(w) = bracket {
            let (ea, eb) = (err(w[0].2).ln(), err(w[1].2).ln());
            let s = (e.ln() - ea) / (eb - ea);
            let t_axi = (w[0].1.ln() + s * (w[1].1.ln() - w[0].1.ln())).exp();
            eprintln!(
                "    same error axisymmetric: {t_axi:.4} s (h between {} and {}); ratio 3D/axi = {:.0}",
                w[0].0,
                w[1].0,
                t / t_axi
            );
        }
    }
}
