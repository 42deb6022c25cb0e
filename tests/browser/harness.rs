//! The Rust side of the glTF checks in `tests/browser`, shared by
//! `io/tests/gltf.rs` and `cli/tests/gltf.rs` (each includes this file with
//! `#[path = "../../tests/browser/harness.rs"] mod harness;`).
//!
//! - [`validate`] runs the Khronos glTF-Validator (`validate.mjs`) and asserts no
//!   error and no warning.
//! - [`render`] loads a file with three.js in headless Chromium (`render.mjs`)
//!   and saves a screenshot.
//! - [`layout`] opens HTML pages in headless Chromium (`layout.mjs`) and lists
//!   clipped or overlapping SVG labels and overflowing table cells
//!   (`cli/tests/diagnose.rs` checks `report.html` with it).
//!
//! Both need Node.js and `npm ci` in `tests/browser` (`.ci/run` does it); the
//! render also needs Chromium (`/usr/bin/chromium`, or `WAGASHI_CHROMIUM`).
//! When something is missing the check is skipped with a note on stderr, except
//! when it is required: on CI (`CI` set to anything but `false` or `0`) or with
//! `WAGASHI_BROWSER_TESTS=required`, where a missing tool fails the test.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// `tests/browser` (the including crates sit one level below the root).
pub fn browser_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/browser")
}

/// What a check needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Need {
    /// node and `gltf-validator`.
    Validator,
    /// node, `three`, `playwright-core` and Chromium.
    Browser,
    /// node, `playwright-core` and Chromium.
    Page,
}

/// Whether missing tools fail the tests instead of skipping them.
pub fn required() -> bool {
    let ci = std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0");
    ci || std::env::var("WAGASHI_BROWSER_TESTS").is_ok_and(|v| v == "required")
}

/// The Chromium binary: `WAGASHI_CHROMIUM` or Debian's `/usr/bin/chromium`.
pub fn chromium() -> PathBuf {
    std::env::var_os("WAGASHI_CHROMIUM").map_or_else(|| PathBuf::from("/usr/bin/chromium"), PathBuf::from)
}

/// What is missing for `need`, if anything.
fn missing(need: Need) -> Option<String> {
    let node = Command::new("node").arg("--version").stdout(Stdio::null()).stderr(Stdio::null()).status();
    if !node.is_ok_and(|s| s.success()) {
        return Some("`node` does not run".into());
    }
    let packages: &[&str] = match need {
        Need::Validator => &["gltf-validator"],
        Need::Browser => &["three", "playwright-core"],
        Need::Page => &["playwright-core"],
    };
    for p in packages {
        if !browser_dir().join("node_modules").join(p).join("package.json").is_file() {
            return Some(format!("the npm package {p} is not installed (run `npm ci` in tests/browser)"));
        }
    }
    if need != Need::Validator && !chromium().is_file() {
        return Some(format!("no Chromium at {} (apt-get install chromium)", chromium().display()));
    }
    None
}

/// Whether the tools for `need` are there; panics when they are missing and
/// [`required`], notes the skip on stderr otherwise.
pub fn available(need: Need) -> bool {
    match missing(need) {
        None => true,
        Some(what) if required() => panic!("{need:?} check required (CI or WAGASHI_BROWSER_TESTS=required): {what}"),
        Some(what) => {
            eprintln!("note: {need:?} check skipped: {what}");
            false
        }
    }
}

/// Runs the Khronos glTF-Validator on `files` and asserts that none has an error
/// or a warning (infos and hints are allowed). Returns the report
/// (`{"validator", "reports": [{"file", "errors", "warnings", "infos", "hints", "messages"}]}`),
/// or `None` when skipped.
pub fn validate(files: &[&Path]) -> Option<serde_json::Value> {
    if !available(Need::Validator) {
        return None;
    }
    let output = Command::new("node")
        .arg(browser_dir().join("validate.mjs"))
        .args(files)
        .stdin(Stdio::null())
        .output()
        .expect("node runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| {
        panic!("validate.mjs printed no report ({e}), status {:?}:\n{stdout}\n{stderr}", output.status)
    });
    let reports = report["reports"].as_array().expect("reports");
    assert_eq!(reports.len(), files.len());
    for r in reports {
        let issues: Vec<String> = r["messages"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| m["severity"].as_u64().is_some_and(|s| s <= 1))
            .map(|m| format!("{} {} at {}: {}", m["severity"], m["code"], m["pointer"], m["message"]))
            .collect();
        eprintln!(
            "glTF-Validator {}: {}: {} errors, {} warnings, {} infos, {} hints",
            report["validator"].as_str().unwrap_or("?"),
            r["file"].as_str().unwrap_or("?"),
            r["errors"],
            r["warnings"],
            r["infos"],
            r["hints"]
        );
        assert!(
            r["errors"] == 0 && r["warnings"] == 0,
            "{}: glTF-Validator {}: {} errors, {} warnings:\n{}",
            r["file"],
            report["validator"],
            r["errors"],
            r["warnings"],
            issues.join("\n")
        );
    }
    assert!(output.status.success(), "validate.mjs exited with {:?}:\n{stderr}", output.status);
    Some(report)
}

/// Renders `glb` with three.js in headless Chromium at animation time `time_s`
/// (default: the frame named `keep`) and saves the screenshot as `png`. Returns
/// what `render.mjs` printed (`{"renderer", "time_s", "width", "height", ...}`), or
/// `None` when skipped.
pub fn render(glb: &Path, png: &Path, time_s: Option<f64>) -> Option<serde_json::Value> {
    if !available(Need::Browser) {
        return None;
    }
    let mut command = Command::new("node");
    command.arg(browser_dir().join("render.mjs")).arg(glb).arg(png).env("WAGASHI_CHROMIUM", chromium());
    if let Some(t) = time_s {
        command.arg("--time").arg(t.to_string());
    }
    let output = command.stdin(Stdio::null()).output().expect("node runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "render.mjs exited with {:?}:\n{stdout}\n{stderr}", output.status);
    Some(serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("render.mjs output is not JSON ({e}):\n{stdout}")))
}

/// Opens each HTML page of `pages` in headless Chromium (`layout.mjs`, a 1280 x
/// 900 viewport) and returns what it found per page (`{"pages": [{"file",
/// "svgs", "texts", "cells", "defects": [...]}]}`): SVG labels outside their
/// SVG or overlapping each other, table cells whose content overflows. `None`
/// when skipped.
pub fn layout(pages: &[&Path]) -> Option<serde_json::Value> {
    if !available(Need::Page) {
        return None;
    }
    let output = Command::new("node")
        .arg(browser_dir().join("layout.mjs"))
        .args(pages)
        .env("WAGASHI_CHROMIUM", chromium())
        .stdin(Stdio::null())
        .output()
        .expect("node runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "layout.mjs exited with {:?}:\n{stdout}\n{stderr}", output.status);
    let report: serde_json::Value =
        serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("layout.mjs output is not JSON ({e}):\n{stdout}"));
    assert_eq!(report["pages"].as_array().map(Vec::len), Some(pages.len()), "{report:#}");
    Some(report)
}
