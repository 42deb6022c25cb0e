//! What every command checks about its outputs before it starts, and what it
//! does when interrupted.
//!
//! - **Inputs are never written**: no output (`-o`, `--report`, `--gltf`) may be
//!   an input (a bundle, a materials file, a surface, the folder `export` reads),
//!   lie inside one, or be a folder holding one ([`refuse_input_overlap`]). A
//!   glTF input's buffers and images count as inputs.
//! - **User files are never replaced without `--force`**: an existing output file
//!   is replaced only when a wagashi writer made it
//!   ([`wagashi_io::atomic::written_by_wagashi`]) or the user passed `--force`
//!   ([`refuse_foreign_file`]); output folders follow
//!   [`wagashi_io::AtomicDir`]'s rules (a wagashi manifest listing every file).
//! - **Bounded runs**: the memory a 3D run will take is estimated before meshing
//!   from the specimen's volume and the element size (`6 V / h^3` tetrahedra,
//!   [`estimated_bytes`] each, plus [`SNAPSHOT_BYTES_PER_TET`] for each shape
//!   kept beyond the default run's two: `--pvd` and `--gltf` frames, stroke
//!   shapes), and a run that will not fit in the machine's available memory is
//!   refused ([`check_memory`]). The trials of `fit` and `diagnose` run several
//!   at a time (one per thread): the largest that run together must fit
//!   together ([`check_trials_memory`]).
//! - **Interrupts**: Ctrl-C or SIGTERM ends the process with status 130 and one
//!   line, after removing the temporary files and folders of the outputs being
//!   written ([`install_interrupt_handler`]); a `press` simulation stops between
//!   steps and the command unwinds ([`CancellableRun`]). What a killed run left beside an
//!   output is removed by the next run on the same output ([`sweep_stale`]).

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::bail;

use crate::press::resolve;

/// Refuses `output` (given as `flag`) when it is one of `inputs` (`(what, path)`,
/// e.g. `("bundle", dir)`), lies inside one, or holds one. Inputs that do not
/// exist (an embedded bundle) are skipped.
pub fn refuse_input_overlap(flag: &str, output: &Path, inputs: &[(&str, &Path)]) -> anyhow::Result<()> {
    let resolved = resolve(output)?;
    for (what, input) in inputs {
        let Ok(input_path) = input.canonicalize() else {
            continue;
        };
        if resolved.starts_with(&input_path) || input_path.starts_with(&resolved) {
            bail!(
                "{}: {flag} may not be, contain or lie inside the input {what} {} (inputs are never modified)",
                output.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Refuses to replace the existing file `path` unless wagashi wrote it or
/// `force` is set; a folder or a link there is always refused.
pub fn refuse_foreign_file(flag: &str, path: &Path, force: bool) -> anyhow::Result<()> {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    if meta.is_dir() {
        bail!("{}: {flag}: is a folder; give a file name", path.display());
    }
    if meta.file_type().is_symlink() {
        bail!("{}: {flag}: is a symbolic link; refusing to write through it", path.display());
    }
    if !force && !wagashi_io::atomic::written_by_wagashi(path) {
        bail!("{}: {flag}: exists and was not written by wagashi; pass --force to replace it", path.display());
    }
    Ok(())
}

/// Removes the temporary files and folders that a killed run writing `path`
/// left beside it (`.NAME.tmp-PID-*` of a process no longer running) and says
/// so on stderr, one line each.
pub fn sweep_stale(path: &Path) {
    for stale in wagashi_io::atomic::remove_stale_temporaries(path) {
        eprintln!("note: removed {}, left by an interrupted run", stale.display());
    }
}

/// Peak memory of a 3D run per tetrahedron [bytes] at [`REFERENCE_TETS`]:
/// `wagashi press examples/paper/mat1` (implicit, default output) peaked at
/// 391 MB resident with 74,880 tetrahedra (`--size-mm 1.5`, 5.35 kB each) and
/// at 1,656 MB with 250,560 (`--size-mm 1`, 6.61 kB each).
pub const BYTES_PER_TET: f64 = 6.61e3;

/// The mesh of the [`BYTES_PER_TET`] measurement.
pub const REFERENCE_TETS: f64 = 250_560.0;

/// How the memory per tetrahedron grows with their number (the factor's fill
/// in 3D): the exponent fitted to the two measurements of [`BYTES_PER_TET`],
/// `ln(6.61 / 5.35) / ln(250560 / 74880)`.
pub const PER_TET_GROWTH: f64 = 0.175;

/// The memory a 3D run of `tets` tetrahedra takes [bytes]:
/// `BYTES_PER_TET * n * max(n / REFERENCE_TETS, 1)^PER_TET_GROWTH` (smaller
/// meshes keep the reference's per-tetrahedron figure, an over-estimate).
pub fn estimated_bytes(tets: f64) -> f64 {
    BYTES_PER_TET * tets * (tets / REFERENCE_TETS).max(1.0).powf(PER_TET_GROWTH)
}

/// The memory one kept shape of a 3D run takes per tetrahedron [bytes]: its
/// stress (6 components, f64) and its share of the nodal displacements (3
/// components, f64, at about one node per 5 tetrahedra: 14,760 nodes for
/// 74,880 tetrahedra in the [`BYTES_PER_TET`] measurement), `8 (6 + 3 / 5)`.
pub const SNAPSHOT_BYTES_PER_TET: f64 = 8.0 * (6.0 + 3.0 / 5.0);

/// The shapes every run keeps (at the release and at the end), which the
/// [`BYTES_PER_TET`] measurement includes.
pub const DEFAULT_SNAPSHOTS: usize = 2;

/// [`estimated_bytes`] for a run that keeps `snapshots` shapes (the `--pvd`
/// and `--gltf` frames, the stroke shapes, the release and the end).
pub fn estimated_run_bytes(tets: f64, snapshots: usize) -> f64 {
    estimated_bytes(tets) + SNAPSHOT_BYTES_PER_TET * tets * snapshots.saturating_sub(DEFAULT_SNAPSHOTS) as f64
}

/// Tetrahedra per cube of side `h` in a mesh of element size `h`: the block
/// mesher's Kuhn split (6), which the conforming and envelope meshers of a
/// surface specimen come close to.
pub const TETS_PER_CUBE: f64 = 6.0;

/// The tetrahedra a 3D mesh of a specimen of `volume_mm3` at `size_mm` holds,
/// estimated before meshing: `6 V / h^3`.
pub fn estimated_tets(volume_mm3: f64, size_mm: f64) -> f64 {
    TETS_PER_CUBE * volume_mm3 / size_mm.powi(3)
}

/// The memory the operating system can give a new process [bytes]: `MemAvailable`
/// of `/proc/meminfo`; `None` where it cannot be read.
pub fn available_memory_bytes() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_mem_available(&text)
}

fn parse_mem_available(meminfo: &str) -> Option<f64> {
    let line = meminfo.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let mut words = line.split_whitespace().skip(1);
    let value: f64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") | None => Some(1024.0 * value),
        _ => None,
    }
}

/// Refuses a 3D run of `volume_mm3` at `size_mm` (`size_flag`: where the size
/// came from) keeping `snapshots` shapes ([`estimated_run_bytes`]) whose
/// estimated memory exceeds what the machine has available, unless
/// `allow_large`. Where the available memory cannot be read, nothing is refused.
pub fn check_memory(
    volume_mm3: f64,
    size_mm: f64,
    snapshots: usize,
    size_flag: &str,
    allow_large: bool,
) -> anyhow::Result<()> {
    if allow_large {
        return Ok(());
    }
    let Some(available) = available_memory_bytes() else {
        return Ok(());
    };
    refuse_if_too_large(volume_mm3, size_mm, snapshots, size_flag, available)
}

/// [`check_memory`] for each 3D trial of a campaign (`fit`, `diagnose`) at
/// `size_mm`, else its default size; `size_given`: whether `--size-mm` was
/// given (for the message). With `axisymmetric`, the trials are 2D sections and
/// nothing is checked; nor is a trial whose specimen is a mesh file.
pub fn check_trials_memory(
    trials: &[&wagashi_io::Bundle],
    size_mm: Option<f64>,
    size_given: bool,
    axisymmetric: bool,
    allow_large: bool,
) -> anyhow::Result<()> {
    if axisymmetric {
        return Ok(());
    }
    // A `shape = "mesh"` trial has the cells of its file, whatever the size.
    let flag = if size_given { "--size-mm" } else { "the default size" };
    let mut each = Vec::new();
    for b in trials.iter().filter(|b| b.experiment.dimension == 3 && b.mesh_path().is_none()) {
        if let (Some(volume), Some(h)) = (b.volume_mm3(), size_mm.or_else(|| b.default_size_mm())) {
            check_memory(volume, h, DEFAULT_SNAPSHOTS, flag, allow_large)
                .map_err(|e| anyhow::anyhow!("{}: {e}", b.experiment_file().display()))?;
            each.push(estimated_bytes(estimated_tets(volume, h)));
        }
    }
    if allow_large {
        return Ok(());
    }
    let Some(available) = available_memory_bytes() else {
        return Ok(());
    };
    refuse_if_together_too_large(&each, rayon::current_num_threads(), flag, available)
}

/// Refuses trials of estimated memories `each` [bytes] that run `threads` at a
/// time when the largest that can run together need more than `available`.
fn refuse_if_together_too_large(each: &[f64], threads: usize, flag: &str, available: f64) -> anyhow::Result<()> {
    let together = threads.clamp(1, each.len().max(1));
    let mut largest = each.to_vec();
    largest.sort_by(|a, b| b.total_cmp(a));
    let needed: f64 = largest.iter().take(together).sum();
    if needed > available {
        bail!(
            "{} 3D trials run {together} at a time (one per thread): the {together} largest at {flag} would need about \
             {:.1} GiB of memory together, more than the {:.1} GiB available (/proc/meminfo MemAvailable); use a larger \
             --size-mm, fewer threads (RAYON_NUM_THREADS) or pass --allow-large",
            each.len(),
            needed / GIB,
            available / GIB
        );
    }
    Ok(())
}

fn refuse_if_too_large(
    volume_mm3: f64,
    size_mm: f64,
    snapshots: usize,
    size_flag: &str,
    available: f64,
) -> anyhow::Result<()> {
    let tets = estimated_tets(volume_mm3, size_mm);
    let needed = estimated_run_bytes(tets, snapshots);
    if needed > available {
        // The size whose estimate fits: bisection on h (the estimate falls as h grows).
        let (mut small, mut large) = (size_mm, size_mm * 1e3);
        for _ in 0..60 {
            let mid = (small * large).sqrt();
            if estimated_run_bytes(estimated_tets(volume_mm3, mid), snapshots) > available {
                small = mid;
            } else {
                large = mid;
            }
        }
        // Rounded up to the 0.01 mm printed.
        let fits = (large * 100.0).ceil() / 100.0;
        let kept = match snapshots.saturating_sub(DEFAULT_SNAPSHOTS) {
            0 => String::new(),
            n => format!(" with {n} more kept shapes (--pvd, --gltf frames)"),
        };
        bail!(
            "{size_flag} {size_mm}: about {:.3}M tetrahedra (6 V / h^3, V = {volume_mm3:.4e} mm^3){kept} would need \
             about {:.1} GiB of memory, more than the {:.1} GiB available (/proc/meminfo MemAvailable); use a larger \
             --size-mm (about {fits:.2} mm fits) or pass --allow-large",
            tets / 1e6,
            needed / GIB,
            available / GIB
        );
    }
    Ok(())
}

const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Set by the interrupt handler: a run of [`fem_core::press::simulate_any_cancellable`]
/// reading it stops after the step it is taking.
static CANCEL: AtomicBool = AtomicBool::new(false);

/// Whether a simulation that reads [`CANCEL`] is running ([`CancellableRun`]).
static CANCELLABLE: AtomicBool = AtomicBool::new(false);

/// Whether the interrupt handler or `main` has taken on ending the process.
static EXIT_CLAIMED: AtomicBool = AtomicBool::new(false);

/// How long the interrupt handler waits for a cancellable run to stop at the
/// end of its step and the command to unwind, before it ends the process itself.
const STOP_GRACE: Duration = Duration::from_secs(3);

/// Whether an interrupt is being handled: the handler ends the process (status
/// 130); an error the removal of the temporaries caused meanwhile is not reported.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// The flag a simulation reads between its steps to stop on an interrupt.
pub fn cancel_flag() -> &'static AtomicBool {
    &CANCEL
}

/// Takes on ending the process after an interrupt; `false` when the interrupt
/// handler or `main` already has (the caller then waits for it).
pub fn claim_exit() -> bool {
    !EXIT_CLAIMED.swap(true, Ordering::SeqCst)
}

/// Marks a simulation that reads [`cancel_flag`] as running, until dropped: an
/// interrupt then stops it between steps, and the command unwinds (its
/// temporary output removed as on any error) and exits with status 130.
#[derive(Debug)]
pub struct CancellableRun(());

impl CancellableRun {
    /// Marks the run as started.
    pub fn start() -> Self {
        CANCELLABLE.store(true, Ordering::SeqCst);
        Self(())
    }
}

impl Drop for CancellableRun {
    fn drop(&mut self) {
        CANCELLABLE.store(false, Ordering::SeqCst);
    }
}

/// Installs the Ctrl-C / SIGTERM handler. During a cancellable simulation
/// ([`CancellableRun`]) it sets [`cancel_flag`] and leaves the command
/// [`STOP_GRACE`] to stop between steps and unwind (`main` then prints one line
/// and exits with status 130). Otherwise, or when that takes longer, it waits
/// for a folder being moved into place, removes the temporary files and folders
/// of the outputs being written, prints one line and exits with status 130
/// (128 + SIGINT), so that an interrupted run leaves neither a partial output
/// nor a hidden temporary.
pub fn install_interrupt_handler() {
    let installed = ctrlc::set_handler(|| {
        INTERRUPTED.store(true, Ordering::SeqCst);
        CANCEL.store(true, Ordering::SeqCst);
        if CANCELLABLE.load(Ordering::SeqCst) {
            // `main` ends the process once the run has stopped.
            let clock = Instant::now();
            while clock.elapsed() < STOP_GRACE {
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        if !claim_exit() {
            // `main` is ending the process.
            loop {
                std::thread::park();
            }
        }
        let removed = wagashi_io::atomic::remove_pending_for_exit();
        let what = match removed.len() {
            0 => "nothing was written".to_string(),
            n => format!("{n} unfinished output{} removed", if n == 1 { "" } else { "s" }),
        };
        eprintln!("error: interrupted: {what}");
        std::process::exit(130);
    });
    // Without a handler (another one already set, or signals unavailable) the
    // default action stands; the next run removes what a killed run left.
    let _ = installed;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mem_available_is_read_in_bytes() {
        let text = "MemTotal:       16000000 kB\nMemFree:  100 kB\nMemAvailable:    8000000 kB\n";
        assert_eq!(parse_mem_available(text), Some(8000000.0 * 1024.0));
        assert_eq!(parse_mem_available("MemTotal: 1 kB\n"), None);
    }

    /// The seed block (58 x 59.5 x 12 mm) at 0.3 mm: about 9.2M tetrahedra
    /// (the mesher makes 9.27M), refused on a machine with 8 GiB available and
    /// the message naming the estimate, the memory and the option; 3 mm passes,
    /// and so does the suggested size. At the measured mesh the estimate is
    /// the measurement.
    #[test]
    fn the_seed_block_at_0_3_mm_is_refused_on_8_gib() {
        let volume = 58.0 * 59.5 * 12.0;
        let tets = estimated_tets(volume, 0.3);
        assert!((tets / 9.27e6 - 1.0).abs() < 0.01, "{tets}");
        let err = refuse_if_too_large(volume, 0.3, 2, "--size-mm", 8.0 * GIB).unwrap_err().to_string();
        for want in ["--size-mm 0.3", "9.2", "GiB", "8.0 GiB available", "--allow-large"] {
            assert!(err.contains(want), "{want}: {err}");
        }
        assert!(refuse_if_too_large(volume, 3.0, 2, "--size-mm", 8.0 * GIB).is_ok());
        let suggested: f64 = err.split("about ").nth(3).unwrap().split(' ').next().unwrap().parse().unwrap();
        assert!(refuse_if_too_large(volume, suggested, 2, "--size-mm", 8.0 * GIB).is_ok(), "{suggested}");
        assert!(refuse_if_too_large(volume, 0.9 * suggested, 2, "--size-mm", 8.0 * GIB).is_err(), "{suggested}");
        assert!((estimated_bytes(REFERENCE_TETS) / 1_656e6 - 1.0).abs() < 0.01);
        // Below the reference the estimate is high (495 MB for the measured 400 MB).
        let small = estimated_bytes(74_880.0) / 400.4e6;
        assert!((1.0..1.25).contains(&small), "{small}");
    }

    /// The seed block at 1 mm (about 248k tetrahedra, about 1.5 GiB) fits in
    /// 4 GiB with the default two shapes, not with 10,001 more (`--pvd 10000`,
    /// about 13 MB each); the message says why.
    #[test]
    fn kept_shapes_count_in_the_estimate() {
        let volume = 58.0 * 59.5 * 12.0;
        assert!(refuse_if_too_large(volume, 1.0, DEFAULT_SNAPSHOTS, "--size-mm", 4.0 * GIB).is_ok());
        let err = refuse_if_too_large(volume, 1.0, 10_003, "--size-mm", 4.0 * GIB).unwrap_err().to_string();
        assert!(err.contains("with 10001 more kept shapes"), "{err}");
        let tets = estimated_tets(volume, 1.0);
        let extra = estimated_run_bytes(tets, 10_003) - estimated_bytes(tets);
        assert!((extra / (10_001.0 * 52.8 * tets) - 1.0).abs() < 1e-12, "{extra}");
    }

    /// Trials that each fit may not fit when several run at once: the
    /// largest `threads` of them must fit together.
    #[test]
    fn trials_running_together_must_fit_together() {
        let each = [3.0 * GIB, 1.0 * GIB, 2.5 * GIB];
        assert!(refuse_if_together_too_large(&each, 1, "--size-mm", 4.0 * GIB).is_ok());
        let err = refuse_if_together_too_large(&each, 2, "--size-mm", 4.0 * GIB).unwrap_err().to_string();
        assert!(err.contains("3 3D trials run 2 at a time") && err.contains("5.5 GiB"), "{err}");
        // More threads than trials: all of them at once.
        let err = refuse_if_together_too_large(&each, 8, "--size-mm", 6.0 * GIB).unwrap_err().to_string();
        assert!(err.contains("run 3 at a time") && err.contains("6.5 GiB"), "{err}");
        assert!(refuse_if_together_too_large(&[], 8, "--size-mm", 1.0).is_ok());
    }
}
