//! `wagashi`: the command-line tool of the wagashi finite-element engine for soft
//! rheological foods, as a library: the binary (`src/main.rs`) and the Python
//! package (`python/`) both run a command line through [`run_command`], so that
//! both give the same results from the same code.
//!
//! The binary only wires `wagashi-io` (bundles, VTU, atomic outputs) to
//! `wagashi-fem-core` (the engine) and formats what they return; it holds no
//! physics and no numerics. Commands:
//!
//! - `wagashi press BUNDLE -o OUT` ([`press`]): simulate an experiment bundle and
//!   write the results as a bundle plus a summary, a step log, shapes and a plot.
//! - `wagashi demo` ([`demo`]): the seed paper's material 1 trial, embedded, run
//!   through the same code path.
//! - `wagashi import exponent|rheometer FILE... -o OUT_DIR` ([`import`]): raw
//!   texture-analyser exports into experiment bundles, one folder per file.
//! - `wagashi fit BUNDLE... -o OUT` ([`fit`]): identify material parameters
//!   (`wagashi-calibrate`): the seed's three steps or a joint fit, with intervals.
//! - `wagashi diagnose --calibrate BUNDLE... -o OUT` ([`diagnose`]): the sim-to-real
//!   gap diagnosis (`wagashi-calibrate`): where the gap lies, which candidate
//!   effect causes it, how far it shrinks.
//! - `wagashi export OUT_DIR --gltf FILE.glb` ([`export`]): a press output as an
//!   animated glTF 2.0 binary (also `wagashi press ... --gltf FILE.glb`).
//! - `wagashi mesh SURFACE -o OUT --size-mm H` ([`mesh`]): tetrahedralize an OBJ,
//!   STL or glTF surface (envelope mode), with a quality report.
//! - `wagashi tpa INPUT...` ([`tpa`]): texture-profile analysis (hardness,
//!   cohesiveness, springiness, ...) of measured or simulated double compressions.
//!
//! Errors: `main` prints one line, `error: CAUSE` (the causes joined with `: `),
//! and exits with status 1; argument errors are clap's (status 2). Ctrl-C or
//! SIGTERM removes the unfinished outputs and exits with status 130 after one
//! line ([`outputs`]).

mod demo;
mod diagnose;
mod export;
mod fit;
mod import;
mod mesh;
mod outputs;
mod plot;
mod press;
mod progress;
mod shape_svg;
mod summary;
mod tpa;

use std::ffi::OsString;
use std::io::Write;

use clap::{Parser, Subcommand};

pub use outputs::{claim_exit, install_interrupt_handler, interrupted};

/// The `wagashi` command line.
#[derive(Debug, Parser)]
#[command(
    name = "wagashi",
    version,
    about = "A finite-element engine for soft rheological foods (five-element rheology, 2D and 3D)",
    after_help = "Example:\n  wagashi demo\n  wagashi press examples/paper/mat1 -o out/mat1\n\nRun `wagashi help COMMAND` for a command's options."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    Press(press::PressArgs),
    Demo(demo::DemoArgs),
    Import(import::ImportArgs),
    Fit(fit::FitArgs),
    Diagnose(diagnose::DiagnoseArgs),
    Export(export::ExportArgs),
    Mesh(mesh::MeshArgs),
    Tpa(tpa::TpaArgs),
}

/// Runs a parsed command line; what the command prints for the user (tables,
/// results, `tpa --json`) goes to `out`, progress bars and notes to stderr.
pub fn run(cli: Cli, out: &mut dyn Write) -> anyhow::Result<()> {
    match cli.command {
        Command::Press(args) => press::run(&args, out),
        Command::Demo(args) => demo::run(&args, out),
        Command::Import(args) => import::run(&args),
        Command::Fit(args) => fit::run(&args, out),
        Command::Diagnose(args) => diagnose::run(&args, out),
        Command::Export(args) => export::run(&args, out),
        Command::Mesh(args) => mesh::run(&args, out),
        Command::Tpa(args) => tpa::run(&args, out),
    }
}

/// Why [`run_command`] failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CommandError {
    /// The arguments do not parse (an unknown option, a bad value): clap's
    /// first line, without its `error: ` prefix. The binary exits with status 2.
    Usage(String),
    /// The command failed: the one line the binary prints after `error: `
    /// (`file:line: key: cause`, or the step and its cause). Status 1.
    Failed(String),
}

impl std::fmt::Display for CommandError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CommandError::Usage(m) | CommandError::Failed(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for CommandError {}

/// Parses `argv` (the program name first, as `std::env::args_os` gives it) and
/// runs the command, writing what it prints for the user to `out`. The same
/// path as the binary, without its interrupt handler and exit codes.
pub fn run_command<I, T>(argv: I, out: &mut dyn Write) -> Result<(), CommandError>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = Cli::try_parse_from(argv).map_err(|e| CommandError::Usage(usage_line(&e.render().to_string())))?;
    run(cli, out).map_err(|e| CommandError::Failed(error_line(&e)))
}

/// The one line an error prints as (after `error: `): the context chain joined with ": ".
pub fn error_line(err: &anyhow::Error) -> String {
    one_line(&chain_line(err.chain()))
}

/// Whether `err` is a write to a closed pipe (output piped into a program that stopped reading).
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|e| e.downcast_ref::<std::io::Error>().is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe))
}

/// The first line of clap's rendered error, without `error: `.
fn usage_line(rendered: &str) -> String {
    let first = rendered.lines().map(str::trim).find(|l| !l.is_empty()).unwrap_or("invalid arguments");
    first.strip_prefix("error: ").unwrap_or(first).to_string()
}

/// The messages of an error and its sources joined with ": ", each once: the
/// libraries' errors often print their source in their own message too (a
/// `{0}` beside `#[from]`), and a message the line already holds adds nothing.
fn chain_line<'a>(chain: impl Iterator<Item = &'a (dyn std::error::Error + 'static)>) -> String {
    let mut line = String::new();
    for e in chain {
        let message = e.to_string();
        if line.contains(&message) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&message);
    }
    line
}

/// `text` on one line: lines trimmed and joined with a space (the messages of
/// wagashi's libraries are one line already and pass unchanged).
fn one_line(text: &str) -> String {
    text.lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn errors_are_one_line() {
        assert_eq!(one_line("a: b"), "a: b");
        assert_eq!(one_line("a:\n  b\n\n"), "a: b");
    }

    #[test]
    fn the_command_line_is_well_formed() {
        Cli::command().debug_assert();
    }

    /// A bad option is a usage error on one line; a missing bundle a failure
    /// naming the path, as the binary prints them.
    #[test]
    fn run_command_reports_usage_and_failures_on_one_line() {
        let mut out = Vec::new();
        let usage = run_command(["wagashi", "press", "b", "-o", "o", "--size-mm", "-1"], &mut out).unwrap_err();
        assert!(matches!(&usage, CommandError::Usage(m) if m.contains("--size-mm") && !m.contains('\n')), "{usage:?}");
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no-bundle");
        let out_dir = dir.path().join("out");
        let failed = run_command(
            [OsString::from("wagashi"), "press".into(), missing.clone().into(), "-o".into(), out_dir.clone().into()],
            &mut out,
        )
        .unwrap_err();
        assert_eq!(
            failed,
            CommandError::Failed(format!(
                "{}: no such folder (a bundle is a folder holding experiment.toml)",
                missing.display()
            ))
        );
        assert!(out.is_empty() && !out_dir.exists());
    }
}
