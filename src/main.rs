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
/// each cause once. The program's contexts are printed down to the first error of the
/// workspace's crates, where the line ends: each of those quotes its own cause in its message
/// (docs/ARCHITECTURE.md, "Errors"), so the causes under it are already on the line.
fn one_line(err: &anyhow::Error) -> String {
    let mut parts = Vec::new();
    for cause in err.chain() {
        parts.push(cause.to_string());
        if is_workspace_error(cause) {
            break;
        }
    }
    let line = parts.join(": ");
    // A multi-line message (a TOML parse error shows the line) joined with "; ".
    line.lines()
        .map(str::trim_end)
        .filter(|l| !l.trim().is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

/// Whether `err` is one of the workspace's error types, whose messages quote their causes.
fn is_workspace_error(err: &(dyn std::error::Error + 'static)) -> bool {
    err.is::<files::Error>()
        || err.is::<motions::Error>()
        || err.is::<garments::Error>()
        || err.is::<sim::Error>()
        || err.is::<dataset::Error>()
        || err.is::<regress::Error>()
        || err.is::<render::Error>()
        || err.is::<surrogate::Error>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use anyhow::Context;

    /// A file error under two contexts: each context once, the file's cause (quoted by the
    /// file error's message and also its `source`) once.
    #[test]
    fn each_cause_is_printed_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let file = files::Error::Io {
            path: "a/b.obj".into(),
            source: io,
        };
        let err = Err::<(), _>(sim::Error::from(file))
            .context("importing a/b.obj")
            .context("making the template")
            .unwrap_err();
        assert_eq!(
            one_line(&err),
            "making the template: importing a/b.obj: a/b.obj: no such file"
        );
        let plain = anyhow::anyhow!("first line  \n\nsecond line\n");
        assert_eq!(one_line(&plain), "first line; second line");
    }
}
