//! `dit-garment`: garment dynamics on SMPL-compatible bodies (see README.md).
//!
//! Exit codes: 0 success, 1 error (the message names the file and the problem), 2 bad usage.

mod cli;
mod commands;
mod inputs;
mod run;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    // On SIGINT, SIGTERM or SIGHUP: remove the outputs being written, then stop (130, as a
    // shell reports an interrupted command).
    let stopped = ctrlc::set_handler(|| {
        files::remove_temporaries();
        eprintln!("stopped by a signal; outputs being written were removed");
        std::process::exit(130);
    });
    if let Err(err) = stopped {
        eprintln!(
            "warning: cannot handle signals ({err}); an interrupted run may leave *.tmp files"
        );
    }
    match commands::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // A closed pipe (e.g. `| head`) is not an error.
            if err.chain().any(|c| {
                c.downcast_ref::<std::io::Error>()
                    .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
            }) {
                return ExitCode::SUCCESS;
            }
            eprintln!("error: {}", one_line(&err));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line (scripts read the first line of standard error),
/// each cause once: a cause whose text its context already quotes is not repeated.
fn one_line(err: &anyhow::Error) -> String {
    let mut line = err.to_string();
    for cause in err.chain().skip(1) {
        let cause = cause.to_string();
        if !line.contains(&cause) {
            line.push_str(": ");
            line.push_str(&cause);
        }
    }
    // A multi-line message (a TOML parse error shows the line) joined with "; ".
    line.lines()
        .map(str::trim_end)
        .filter(|l| !l.trim().is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}
