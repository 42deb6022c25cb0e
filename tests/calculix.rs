//! The network model's finite-strain path against CalculiX, an independent FE
//! code (Debian's `calculix-ccx`), on the glued neo-Hookean block of the
//! network issue's verification list.
//!
//! ## The problem
//!
//! A block `W x H x T = 20 x 10 x 20` mm (y up) of compressible neo-Hookean
//! material, `E = 0.03` MPa, `nu = 0.3`, glued to the floor (every displacement
//! of the bottom face zero) and to the plate (top face: x and z held, y moved
//! down), pushed 3 mm (30 %). The plate force is compared at 1, 2 and 3 mm.
//! The material is elastic, so the answer does not depend on the push's speed.
//!
//! ## The same energy in both codes
//!
//! Ours (`model = "network"`, `[equilibrium] energy = "neo-hookean"`,
//! `fem_core::material::network::equilibrium`):
//! `W = mu/2 (I1bar - 3) + K/2 (J - 1)^2`, `mu = E / (2 (1 + nu))`,
//! `K = E / (3 (1 - 2 nu))`, `I1bar = J^-2/3 tr(F^T F)`.
//! CalculiX's `*HYPERELASTIC, NEO HOOKE` (ccx manual, `*HYPERELASTIC`):
//! `U = C10 (I1bar - 3) + 1/D1 (J - 1)^2` with the same `I1bar = III_C^-1/3 I_C`
//! and `J = III_C^1/2`. Term by term: `C10 = mu/2`, `D1 = 2/K`.
//!
//! ## CalculiX's side
//!
//! The glued problem is symmetric about the planes `x = W/2` and `z = T/2`
//! (geometry, material and both glued faces are), so CalculiX solves a
//! quarter, placed in its own frame as `[0, W/2] x [0, H] x [0, T/2]` with the
//! two symmetry planes at `x = 0` (`u_x = 0`) and `z = 0` (`u_z = 0`), on
//! uniform grids of 20-node bricks (C3D20, full integration), `*STATIC, DIRECT`
//! with `NLGEOM` in three 1 mm increments, the field convergence criteria
//! tightened to 1e-8 (`*CONTROLS`); the plate force is four times the total y
//! reaction of the top face (`*NODE PRINT, TOTALS=ONLY`, RF). The whole block
//! on the coarsest bricks checks the symmetry: it gives four times the
//! quarter's force, to 1e-5.
//! Three grids, 4, 6 and 9 bricks along each 10 mm edge (refinement ratio 1.5),
//! give the Richardson extrapolation and the observed order. The glued edges
//! are singular (the free side meets a held face), so the order is below the
//! smooth C3D20 rate; it is measured, not assumed.
//!
//! ## Ours
//!
//! The full block (the Kuhn split of `mesh::block` is not mirror symmetric, so
//! no quarter) on P1 tetrahedra, the Newton path in 1 mm steps. The strain
//! concentrates at the glued edges as the push deepens, and on uniform grids
//! P1 resolves it late: at 30 % the uniform grids of 10/7, 1 and 5/7 mm give an
//! observed order of 0.2, outside the asymptotic range. So the grid is
//! graded towards the faces, the same map on every grid: each coordinate
//! `s = x / L` in [0, 1] goes to `s - a sin(2 pi s) / (2 pi)` with `a = 0.6`
//! (cells 0.4 of the nominal size at the faces, 1.6 at mid-span). Nominal
//! sizes 10/7, 1 and 5/7 mm (7, 10 and 14 cells over the height); Richardson
//! over the three (unequal ratios: the order solves the three-grid equations by
//! bisection) gives our extrapolated force and order.
//!
//! ## Tolerance
//!
//! The issue's: our extrapolated force within 1 % of CalculiX's at 10, 20 and
//! 30 %. The figures are in VALIDATION.md ("The network model").
//!
//! `ccx` must be on PATH: without it the test prints why and passes, except on
//! CI (`CI` set to anything but empty, `false` or `0`), where `.ci/run`
//! installs it and a missing one fails the test.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use fem_core::material::network::{Energy, Equilibrium, Network};
use fem_core::material::Material;
use fem_core::mesh;
use fem_core::press::{self, Attachment, Protocol, Settings, SolidPress};

/// Young's modulus [MPa] and Poisson's ratio.
const E_MPA: f64 = 0.03;
const NU: f64 = 0.3;
/// Width (x), height (y), thickness (z) [mm].
const SIZE_MM: [f64; 3] = [20.0, 10.0, 20.0];
/// The plate displacements where the forces are compared [mm].
const DEPTHS_MM: [f64; 3] = [1.0, 2.0, 3.0];
/// The grading of our grids towards the faces (module docs).
const GRADING: f64 = 0.6;
/// Relative tolerance (the issue's).
const TOLERANCE: f64 = 0.01;

/// Whether a missing `ccx` fails the test (CI) instead of skipping it.
fn required() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// Whether `ccx` can be started.
fn ccx_on_path() -> bool {
    Command::new("ccx").arg("-v").output().is_ok()
}

/// Which part of the block CalculiX solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Part {
    /// `[0, W/2] x [0, H] x [0, T/2]`, symmetry planes `x = 0` and `z = 0`.
    Quarter,
    /// The whole block, `[0, W] x [0, H] x [0, T]`: checks the symmetry.
    Whole,
}

/// CalculiX's input for `part` of the block on a grid of C3D20 bricks of side
/// `H/n` (the quarter's `n x n x n`, the whole block's `2n x n x 2n`). Nodes
/// live on the grid of half-cells (indices `0..=2 cells` per axis)
/// with at most one odd index (corners and edge midpoints); bricks list the
/// corners counter-clockwise at `z` low then high, then the midside nodes of
/// the low face, the high face and the four vertical edges (ccx's C3D20 order,
/// with the element axes along x, y, z).
fn ccx_input(n: usize, part: Part) -> String {
    let (lengths, cells) = match part {
        Part::Quarter => ([SIZE_MM[0] / 2.0, SIZE_MM[1], SIZE_MM[2] / 2.0], [n, n, n]),
        Part::Whole => (SIZE_MM, [2 * n, n, 2 * n]),
    };
    let m = cells.map(|c| 2 * c);
    let mut ids = vec![0usize; (m[0] + 1) * (m[1] + 1) * (m[2] + 1)];
    let at = |i: usize, j: usize, k: usize| (k * (m[1] + 1) + j) * (m[0] + 1) + i;
    let mut out = format!("*HEADING\nGlued neo-Hookean block, {part:?}\n*NODE, NSET=NALL\n");
    let mut count = 0;
    let mut sets: [Vec<usize>; 4] = Default::default(); // bottom, top, x = 0, z = 0
    for k in 0..=m[2] {
        for j in 0..=m[1] {
            for i in 0..=m[0] {
                if i % 2 + j % 2 + k % 2 > 1 {
                    continue;
                }
                count += 1;
                ids[at(i, j, k)] = count;
                let x = [i as f64 / m[0] as f64, j as f64 / m[1] as f64, k as f64 / m[2] as f64];
                out += &format!(
                    "{count}, {:.12}, {:.12}, {:.12}\n",
                    x[0] * lengths[0],
                    x[1] * lengths[1],
                    x[2] * lengths[2]
                );
                for (set, on) in sets.iter_mut().zip([j == 0, j == m[1], i == 0, k == 0]) {
                    if on {
                        set.push(count);
                    }
                }
            }
        }
    }
    const CORNERS: [[usize; 3]; 8] =
        [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [0, 0, 2], [2, 0, 2], [2, 2, 2], [0, 2, 2]];
    const MIDSIDES: [[usize; 3]; 12] = [
        [1, 0, 0],
        [2, 1, 0],
        [1, 2, 0],
        [0, 1, 0],
        [1, 0, 2],
        [2, 1, 2],
        [1, 2, 2],
        [0, 1, 2],
        [0, 0, 1],
        [2, 0, 1],
        [2, 2, 1],
        [0, 2, 1],
    ];
    out += "*ELEMENT, TYPE=C3D20, ELSET=EALL\n";
    let mut element = 0;
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                element += 1;
                let nodes: Vec<String> = CORNERS
                    .iter()
                    .chain(&MIDSIDES)
                    .map(|o| ids[at(2 * i + o[0], 2 * j + o[1], 2 * k + o[2])].to_string())
                    .collect();
                // At most 16 entries per line: the element number and 15 nodes, then 5.
                out += &format!("{element}, {},\n{}\n", nodes[..15].join(", "), nodes[15..].join(", "));
            }
        }
    }
    for (name, set) in ["BOTTOM", "TOP", "XSYM", "ZSYM"].iter().zip(&sets) {
        out += &format!("*NSET, NSET={name}\n");
        for line in set.chunks(16) {
            out += &line.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ");
            out += "\n";
        }
    }
    let mu = E_MPA / (2.0 * (1.0 + NU));
    let bulk = E_MPA / (3.0 * (1.0 - 2.0 * NU));
    let (c10, d1) = (mu / 2.0, 2.0 / bulk);
    let depth = DEPTHS_MM[2];
    let increment = DEPTHS_MM[0];
    let symmetry = if part == Part::Quarter { "XSYM, 1, 1, 0.0\nZSYM, 3, 3, 0.0\n" } else { "" };
    out += &format!(
        "*MATERIAL, NAME=FOOD\n*HYPERELASTIC, NEO HOOKE\n{c10:.10e}, {d1:.10e}\n\
         *SOLID SECTION, ELSET=EALL, MATERIAL=FOOD\n\
         *BOUNDARY\nBOTTOM, 1, 3, 0.0\nTOP, 1, 1, 0.0\nTOP, 3, 3, 0.0\n{symmetry}\
         *STEP, NLGEOM, INC=100\n*STATIC, DIRECT\n{increment}, {depth}\n\
         *CONTROLS, PARAMETERS=FIELD\n1e-8, 1e-8, 0.01, , 0.02, 1e-5, 1e-3, 1e-8\n\
         *BOUNDARY\nTOP, 2, 2, {}\n\
         *NODE PRINT, NSET=TOP, TOTALS=ONLY\nRF\n*END STEP\n",
        -depth
    );
    out
}

/// The y components of the top face's total reaction in CalculiX's `.dat`
/// file, at the step times `DEPTHS_MM` (the step's time is the displacement).
fn parse_dat(dat: &str) -> Option<[f64; 3]> {
    let mut found = [None; 3];
    let mut lines = dat.lines();
    while let Some(line) = lines.next() {
        let Some(rest) = line.trim().strip_prefix("total force (fx,fy,fz) for set TOP and time") else {
            continue;
        };
        let t: f64 = rest.trim().parse().ok()?;
        let values = lines.by_ref().find(|l| !l.trim().is_empty())?;
        let fy: f64 = values.split_whitespace().nth(1)?.parse().ok()?;
        if let Some(i) = DEPTHS_MM.iter().position(|&d| (d - t).abs() < 1e-6) {
            found[i] = Some(fy);
        }
    }
    Some([found[0]?, found[1]?, found[2]?])
}

/// CalculiX's plate force [N] (compression positive, whole block) at
/// `DEPTHS_MM` on `part` with bricks of side `H/n`, run in `dir`.
fn ccx_forces(dir: &Path, n: usize, part: Part) -> [f64; 3] {
    let job = format!("{part:?}{n}").to_lowercase();
    std::fs::write(dir.join(format!("{job}.inp")), ccx_input(n, part)).unwrap();
    let output = Command::new("ccx")
        .args(["-i", &job])
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "1")
        .env("CCX_NPROC_EQUATION_SOLVER", "1")
        .output()
        .expect("ccx runs");
    let dat = std::fs::read_to_string(dir.join(format!("{job}.dat"))).unwrap_or_default();
    let Some(fy) = parse_dat(&dat) else {
        let log = String::from_utf8_lossy(&output.stdout);
        let lines: Vec<&str> = log.lines().collect();
        let tail = lines[lines.len().saturating_sub(20)..].join("\n");
        panic!("ccx gave no reaction at 1, 2 and 3 mm on grid {n} ({}); its log ends:\n{tail}", output.status);
    };
    let copies = if part == Part::Quarter { 4.0 } else { 1.0 };
    fy.map(|f| -copies * f)
}

/// Our plate force [N] at `DEPTHS_MM` on the full block, graded grid of nominal
/// cell size `size_mm`.
fn our_forces(size_mm: f64) -> [f64; 3] {
    let mut m = mesh::block(SIZE_MM, size_mm, "m").unwrap();
    let g = |s: f64| s - GRADING / std::f64::consts::TAU * (std::f64::consts::TAU * s).sin();
    for p in &mut m.nodes {
        for k in 0..3 {
            p[k] = SIZE_MM[k] * g(p[k] / SIZE_MM[k]);
        }
    }
    let network =
        Network::new(NU).with_equilibrium(Equilibrium { energy: Energy::NeoHookean, e_mpa: E_MPA, mullins: None });
    let end = DEPTHS_MM[2];
    // 1 mm/s, so that time [s] reads as the plate's displacement [mm].
    let protocol = Protocol {
        waypoints: vec![[0.0, 0.0], [end, end]],
        release_s: end,
        end_s: end,
        plate: Attachment::Glued,
        support: Attachment::Glued,
        gravity: false,
    };
    let problem = SolidPress::new_3d(m, vec![Material::network(network).unwrap()], protocol).unwrap();
    let settings = Settings { fixed_dt_s: Some(DEPTHS_MM[0]), ..Settings::default() };
    let result = press::simulate(&problem, &settings, &mut |_| {}).unwrap();
    DEPTHS_MM.map(|d| {
        let step = result.steps.iter().find(|s| (s.t_s - d).abs() < 1e-9).expect("a step ends there");
        step.plate_force_n
    })
}

/// Richardson extrapolation of `f`, computed on three grids of sizes `h`
/// (coarse first): the limit `F` and the observed order `p` of
/// `f_i = F + C h_i^p`, `p` by bisection on the ratio of the two differences.
/// The differences must keep their sign (monotone convergence), or the order
/// means nothing.
fn richardson(h: [f64; 3], f: [f64; 3]) -> (f64, f64) {
    let (d1, d2) = (f[0] - f[1], f[1] - f[2]);
    assert!(d1 * d2 > 0.0, "not monotone: {f:?}");
    let mismatch = |p: f64| (h[0].powf(p) - h[1].powf(p)) / (h[1].powf(p) - h[2].powf(p)) - d1 / d2;
    let (mut lo, mut hi) = (1e-6, 20.0);
    assert!(mismatch(lo) * mismatch(hi) < 0.0, "no order in (0, 20]: {f:?} on {h:?}");
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mismatch(lo) * mismatch(mid) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let order = 0.5 * (lo + hi);
    let c = d1 / (h[0].powf(order) - h[1].powf(order));
    (f[2] - c * h[2].powf(order), order)
}

/// The extrapolation itself, on `f = 2 + 0.3 h^1.3` at unequal ratios:
/// the limit and the order come back to rounding.
#[test]
fn richardson_recovers_a_known_limit_and_order() {
    let h = [10.0 / 7.0, 1.0, 10.0 / 14.0];
    let (limit, order) = richardson(h, h.map(|h| 2.0 + 0.3 * h.powf(1.3)));
    assert!((limit - 2.0).abs() < 1e-12 && (order - 1.3).abs() < 1e-10, "{limit} {order}");
}

#[test]
fn a_glued_neo_hookean_block_matches_calculix_c3d20_within_1_percent() {
    if !ccx_on_path() {
        assert!(!required(), "ccx is not on PATH (CI installs it: apt-get install -y calculix-ccx)");
        eprintln!("ccx is not on PATH (apt-get install -y calculix-ccx): the CalculiX comparison is skipped");
        return;
    }
    let clock = Instant::now();
    let dir = tempfile::tempdir().unwrap();
    let grids = [4usize, 6, 9];
    let ccx: Vec<[f64; 3]> = grids.iter().map(|&n| ccx_forces(dir.path(), n, Part::Quarter)).collect();
    // The quarter stands for the whole block: the same bricks on the whole
    // block give four times its force (to the .dat file's 7 digits).
    let whole = ccx_forces(dir.path(), grids[0], Part::Whole);
    for (q, w) in ccx[0].iter().zip(&whole) {
        assert!((q / w - 1.0).abs() < 1e-5, "quarter {:?} N, whole block {whole:?} N", ccx[0]);
    }
    let ccx_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let sizes = [10.0 / 7.0, 1.0, 10.0 / 14.0];
    let ours: Vec<[f64; 3]> = sizes.iter().map(|&h| our_forces(h)).collect();
    let ours_s = clock.elapsed().as_secs_f64();
    eprintln!("CalculiX: {ccx_s:.1} s; ours: {ours_s:.1} s");
    let mut worst: f64 = 0.0;
    for (i, d) in DEPTHS_MM.iter().enumerate() {
        let reference = [ccx[0][i], ccx[1][i], ccx[2][i]];
        let (limit, order) = richardson(grids.map(|n| SIZE_MM[1] / n as f64), reference);
        let fine = [ours[0][i], ours[1][i], ours[2][i]];
        let (our_limit, our_order) = richardson(sizes, fine);
        let gap = our_limit / limit - 1.0;
        eprintln!(
            "{:.0} %: CalculiX C3D20 on {grids:?} bricks per 10 mm: {reference:.5?} N -> {limit:.5} N (order {order:.2}); \
             ours on {:.3?} mm: {fine:.5?} N -> {our_limit:.5} N (order {our_order:.2}); \
             difference {:+.3} % (our finest grid {:+.3} %)",
            d / SIZE_MM[1] * 100.0,
            sizes,
            gap * 100.0,
            (fine[2] / limit - 1.0) * 100.0
        );
        worst = worst.max(gap.abs());
    }
    assert!(worst < TOLERANCE, "largest relative difference {worst:.4}");
}
