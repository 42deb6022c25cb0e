//! The network model's cost against the chain's on a 3D cylinder: a
//! fungi-like double compression to 50 % by a frictionless plate tool that
//! leaves the specimen and touches it again, with the default network
//! structure at the fungi fit's values (VALIDATION.md) and with the seed's
//! five-element chain. Prints the wall time, the process's CPU time (user and
//! system, every thread; Linux), steps, Newton iterations and factorizations
//! of each, and the network's evaluations of its cells' laws (with their
//! tangent and of the stress alone) per cell; with `fbar` after the size, the
//! network with F-bar patches too.
//!
//! `cargo run --release -p wagashi-workspace-tests --example network_cost -- SIZE_MM [fbar]`

use std::time::Instant;

use fem_core::material::network::{evaluation_counts, Damper, Energy, Equilibrium, Mullins, Network, ViscousNetwork};
use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Attachment, Protocol, Settings, SolidPress, Tool, ToolContact, Volumetric};

/// The process's CPU time so far (user and system, every thread) [s], from
/// `/proc/self/stat` (Linux; `None` elsewhere). Its clock ticks are the
/// kernel's fixed user-space 100 Hz.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command's closing parenthesis start at the third: utime
    // and stime are the 14th and 15th.
    let fields: Vec<&str> = stat[stat.rfind(')')? + 1..].split_whitespace().collect();
    let ticks = |i: usize| fields.get(i - 3)?.parse::<f64>().ok();
    Some((ticks(14)? + ticks(15)?) / 100.0)
}

fn main() {
    let size: f64 = std::env::args().nth(1).map_or(1.0, |s| s.parse().expect("SIZE_MM: a number"));
    let (r, h) = (4.0, 10.0);
    let network = Material::network(
        Network::new(0.374)
            .with_equilibrium(Equilibrium {
                energy: Energy::Exponential { stiffening: 1.12 },
                e_mpa: 5.25e-3,
                mullins: Some(Mullins { r: 1.01, m_mpa: 2.69e-3, beta: 0.0 }),
            })
            .with(ViscousNetwork { e_mpa: 0.385, tau_s: 0.107 })
            .with(ViscousNetwork { e_mpa: 0.0162, tau_s: 7.19 })
            .with(Damper { c_mpa_s: 4.36e-3 }),
    )
    .unwrap();
    let chain = Material::seed_mat1_force();
    // Down 5 mm in 22.7 s, up 5.5 mm, down again: the slowest fungi records' speed.
    let strokes = vec![[0.0, 0.0], [22.7, 5.0], [45.4, -0.5], [50.0, -0.5], [72.7, 5.0]];
    let protocol = Protocol {
        waypoints: strokes.clone(),
        release_s: 72.7,
        end_s: 72.7,
        plate: Attachment::Frictionless,
        support: Attachment::Frictionless,
        gravity: false,
    };
    let m = mesh::cylinder(r, h, size, "m").unwrap();
    println!("cylinder R = {r} mm, H = {h} mm, {size} mm cells: {} tets, {} nodes", m.cells.len(), m.nodes.len());
    let mut runs = vec![("chain", chain, Volumetric::Standard), ("network", network.clone(), Volumetric::Standard)];
    if std::env::args().nth(2).as_deref() == Some("fbar") {
        runs.push(("network, F-bar", network, Volumetric::FBar));
    }
    for (name, material, volumetric) in runs {
        let mut problem = SolidPress::new_3d(m.clone(), vec![material], protocol.clone()).unwrap();
        problem.tools = vec![Tool::plate_above(
            "plate",
            [-r, 0.0, -r],
            [r, h, r],
            &strokes,
            ToolContact::Frictionless,
            f64::INFINITY,
        )];
        let clock = Instant::now();
        let cpu0 = cpu_seconds();
        let counts0 = evaluation_counts();
        let settings = Settings { volumetric, ..Settings::default() };
        let result = press::simulate(&problem, &settings, &mut |_| {}).unwrap();
        let wall = clock.elapsed().as_secs_f64();
        let cpu = match (cpu0, cpu_seconds()) {
            (Some(a), Some(b)) => format!("{:.1} s CPU", b - a),
            _ => "CPU time n/a".to_string(),
        };
        let counts = evaluation_counts();
        let steps = result.steps.len();
        let iterations: usize = result.steps.iter().map(|s| s.newton_iterations).sum();
        let per_cell = |n: u64, n0: u64| (n - n0) as f64 / m.cells.len() as f64;
        println!(
            "{name}: {wall:.1} s wall, {cpu}, {steps} steps, {:.2} Newton iterations and {:.2} factorizations per step, \
             {:.0} law evaluations with tangent and {:.0} of the stress alone per cell, peak {:.6} N",
            iterations as f64 / steps as f64,
            result.num_factorizations as f64 / steps as f64,
            per_cell(counts.with_tangent, counts0.with_tangent),
            per_cell(counts.stress_only, counts0.stress_only),
            result.peak_force()
        );
    }
}
