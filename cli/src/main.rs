//! The `wagashi` binary: parses the command line and runs it through the
//! library ([`wagashi_cli::run`]); the commands and their outputs are described
//! there.
//!
//! Errors: one line, `error: CAUSE` (the causes joined with `: `), and exit
//! status 1; argument errors are clap's (status 2). Ctrl-C or SIGTERM removes
//! the unfinished outputs and exits with status 130 after one line.

use std::process::ExitCode;

use clap::Parser;
use wagashi_cli::{error_line, install_interrupt_handler, interrupted, is_broken_pipe, run, Cli};

fn main() -> ExitCode {
    let cli = Cli::parse();
    install_interrupt_handler();
    match run(cli, &mut std::io::stdout()) {
        Ok(()) => ExitCode::SUCCESS,
        // Output piped into a program that stopped reading (`| head`): not an error.
        Err(err) if is_broken_pipe(&err) => ExitCode::SUCCESS,
        // The interrupt handler removed the output being written and ends the
        // process itself (status 130): wait for it.
        Err(_) if interrupted() => loop {
            std::thread::park();
        },
        Err(err) => {
            eprintln!("error: {}", error_line(&err));
            ExitCode::FAILURE
        }
    }
}
