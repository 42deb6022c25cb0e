//! `wagashi`: the command-line tool of the wagashi finite-element engine for soft
//! rheological foods.
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
mod summary;
mod tpa;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// The `wagashi` command line.
#[derive(Debug, Parser)]
#[command(
    name = "wagashi",
    version,
    about = "A finite-element engine for soft rheological foods (five-element rheology, 2D and 3D)",
    after_help = "Example:\n  wagashi demo\n  wagashi press examples/paper/mat1 -o out/mat1\n\nRun `wagashi help COMMAND` for a command's options."
)]
struct Cli {
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

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Press(args) => press::run(&args),
        Command::Demo(args) => demo::run(&args),
        Command::Import(args) => import::run(&args),
        Command::Fit(args) => fit::run(&args),
        Command::Diagnose(args) => diagnose::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Mesh(args) => mesh::run(&args),
        Command::Tpa(args) => tpa::run(&args),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    outputs::install_interrupt_handler();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // Output piped into a program that stopped reading (`| head`): not an error.
        Err(err) if is_broken_pipe(&err) => ExitCode::SUCCESS,
        // The interrupt handler removed the output being written and ends the
        // process itself (status 130): wait for it.
        Err(_) if outputs::interrupted() => loop {
            std::thread::park();
        },
        Err(err) => {
            // One line, as ripgrep does: the context chain joined with ": ".
            eprintln!("error: {}", one_line(&chain_line(err.chain())));
            ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|e| e.downcast_ref::<std::io::Error>().is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe))
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
}
