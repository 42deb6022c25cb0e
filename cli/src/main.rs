//! The `wagashi` binary: parses the command line and runs it through the
//! library ([`wagashi_cli::run`]); the commands and their outputs are described
//! there.
//!
//! Errors: one line, `error: CAUSE` (the causes joined with `: `), and exit
//! status 1; argument errors are clap's (status 2). Ctrl-C or SIGTERM removes
//! the unfinished outputs and exits with status 130 after one line (a `press`
//! simulation stops between steps first, and the line names the step).

use std::process::ExitCode;

use clap::Parser;
use wagashi_cli::{claim_exit, error_line, install_interrupt_handler, interrupted, is_broken_pipe, run, Cli};

fn main() -> ExitCode {
    let cli = Cli::parse();
    install_interrupt_handler();
    match run(cli, &mut std::io::stdout()) {
        Ok(()) => ExitCode::SUCCESS,
        // Output piped into a program that stopped reading (`| head`): not an error.
        Err(err) if is_broken_pipe(&err) => ExitCode::SUCCESS,
        // A run stopped between steps by an interrupt: its temporary output
        // went with the error. Unless the handler is ending the process itself
        // (it removes what is being written), end it here.
        Err(err) if interrupted() => {
            if claim_exit() {
                wagashi_io::atomic::remove_pending_for_exit();
                eprintln!("error: interrupted: {}; the unfinished output was removed", error_line(&err));
                return ExitCode::from(130);
            }
            loop {
                std::thread::park();
            }
        }
        Err(err) => {
            eprintln!("error: {}", error_line(&err));
            ExitCode::FAILURE
        }
    }
}
