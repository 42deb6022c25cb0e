//! Where the tests find their input files, shared by every test crate of the
//! workspace (each includes this file with
//! `#[path = "…/tests/support/data.rs"] mod data;`, most through its
//! `tests/common/mod.rs`).
//!
//! - [`fixture`]: a file of `tests/fixtures` in the repository (files with a
//!   licence that lets them live here; `tests/fixtures/README.md` names each
//!   one's source and licence).
//! - [`shared_data`]: the shared data folder beside the checkout
//!   (`<workspace>/../shared/data`: measured records, scans and mesh fixtures
//!   that may not be copied into the repository). A test that needs it starts
//!   with `let Some(data) = shared_data("what it reads") else { return };` (or
//!   `if skip_without_shared_data("what it reads") { return; }`): without the folder it prints one line on stderr saying that it skipped and
//!   why, and passes; on CI (`CI` set to anything but empty, `false` or `0`) it
//!   fails instead, so that CI keeps running it.
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};

/// The workspace root: the nearest folder above the including crate that holds
/// `Cargo.lock`.
pub fn workspace() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest.ancestors().find(|d| d.join("Cargo.lock").is_file()).unwrap_or(manifest).to_path_buf()
}

/// A fixture of the repository: `<workspace>/tests/fixtures/NAME`.
pub fn fixture(name: &str) -> PathBuf {
    workspace().join("tests/fixtures").join(name)
}

/// Whether the tests run on CI: `CI` set to anything but empty, `false` or `0`.
pub fn on_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
}

/// `<workspace>/../shared/data`, whether it exists or not.
pub fn shared_data_path() -> PathBuf {
    workspace().join("../shared/data")
}

/// `<workspace>/../shared/data` when it is there. Otherwise `None`, after one
/// line on stderr (written past the test harness's capture, so that
/// `cargo test` shows it) naming the test and `what` it would have read; on CI
/// (see [`on_ci`]) a missing folder panics instead.
pub fn shared_data(what: &str) -> Option<PathBuf> {
    let path = shared_data_path();
    if path.is_dir() {
        return Some(path);
    }
    let thread = std::thread::current();
    let test = thread.name().unwrap_or("a test");
    assert!(
        !on_ci(),
        "{test}: needs ../shared/data ({what}), which is missing at {}; on CI (CI={:?}) it must be there",
        path.display(),
        std::env::var("CI").unwrap_or_default()
    );
    // One write, so that the lines of tests running in parallel do not mix.
    let line = format!("{test}: skipped: needs ../shared/data ({what}); not present beside the checkout\n");
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
    None
}

/// Whether a test that needs the shared data folder skips: `true` (after
/// saying so, see [`shared_data`]) when the folder is missing off CI. Starts a
/// test as `if skip_without_shared_data("what it reads") { return; }`.
pub fn skip_without_shared_data(what: &str) -> bool {
    shared_data(what).is_none()
}
