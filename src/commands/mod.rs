//! One module per subcommand; each turns parsed flags into a run.

/// `println!` that returns a closed pipe (`| head`) as an error, which `main` ends quietly,
/// instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write;
        writeln!(std::io::stdout().lock(), $($arg)*)?;
    }};
}

/// [`say!`] without the line end, as `print!`.
macro_rules! say_part {
    ($($arg:tt)*) => {{
        use std::io::Write;
        write!(std::io::stdout().lock(), $($arg)*)?;
    }};
}

mod body;
mod compare;
mod dataset_cmd;
mod demo;
mod drape_bench;
mod evaluate;
mod garments_cmd;
mod motions_cmd;
mod paired;
mod predict;
mod regress;
mod render;
mod simulate;
mod spread;
mod synth;
mod train;
mod uv;

use std::path::Path;

use anyhow::Result;

use crate::cli::{Cli, Command, DatasetCommand, GarmentsCommand, MotionsCommand};

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    check_outputs(&cli.command)?;
    match cli.command {
        Command::Demo(args) => demo::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::DrapeBench(args) => drape_bench::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Regress(args) => regress::run(&args),
        Command::Render(args) => render::run(&args),
        Command::View(args) => render::view(&args),
        Command::Synth(args) => synth::run(&args),
        Command::Dataset { command } => dataset_cmd::run(command),
        Command::Body(args) => body::run(&args),
        Command::Motions { command } => motions_cmd::run(command),
        Command::Garments { command } => garments_cmd::run(command),
        Command::Uv(args) => uv::run(&args),
        Command::Train(args) => train::run(&args),
        Command::Predict(args) => predict::run(&args),
        Command::Evaluate(args) => evaluate::run(&args),
        Command::Paired(args) => paired::run(&args),
    }
}

/// Refuses, before any work, output paths that hold something a run must not replace: a
/// file output must be a regular file or nothing (never a directory, link, FIFO or device),
/// a folder output a folder or nothing.
fn check_outputs(command: &Command) -> Result<()> {
    let (files_out, folders_out): (Vec<Option<&Path>>, Vec<Option<&Path>>) = match command {
        Command::Demo(a) => (vec![a.json.as_deref()], vec![a.out.as_deref()]),
        Command::Simulate(a) => (
            vec![a.out.as_deref(), a.json.as_deref()],
            vec![a.obj_dir.as_deref()],
        ),
        Command::DrapeBench(a) => (vec![a.json.as_deref()], vec![Some(a.out.as_path())]),
        Command::Regress(a) => (vec![a.json.as_deref()], vec![]),
        Command::Compare(a) => (vec![a.json.as_deref()], vec![]),
        Command::Render(a) => (vec![a.json.as_deref()], vec![Some(a.out.as_path())]),
        Command::View(a) => (vec![Some(a.out.as_path())], vec![]),
        Command::Synth(a) => (vec![a.json.as_deref()], vec![a.out.as_deref()]),
        Command::Dataset { command } => match command {
            DatasetCommand::Verify { json, .. }
            | DatasetCommand::Stats { json, .. }
            | DatasetCommand::Spread { json, .. } => (vec![json.as_deref()], vec![]),
            DatasetCommand::Tensors { out, .. } | DatasetCommand::Merge { out, .. } => {
                (vec![], vec![Some(out.as_path())])
            }
        },
        Command::Body(a) => (vec![a.out.as_deref(), a.json.as_deref()], vec![]),
        Command::Motions { command } => match command {
            MotionsCommand::List { json } | MotionsCommand::Show { json, .. } => {
                (vec![json.as_deref()], vec![])
            }
            MotionsCommand::Export { out, json, .. } => {
                (vec![Some(out.as_path()), json.as_deref()], vec![])
            }
        },
        Command::Garments { command } => match command {
            GarmentsCommand::List { json } | GarmentsCommand::Check { json, .. } => {
                (vec![json.as_deref()], vec![])
            }
            GarmentsCommand::Show { pattern_out, .. } => (vec![pattern_out.as_deref()], vec![]),
            GarmentsCommand::Make { out, report, .. }
            | GarmentsCommand::Import { out, report, .. } => {
                (vec![Some(out.as_path()), report.as_deref()], vec![])
            }
        },
        Command::Uv(a) => (vec![a.json.as_deref()], vec![Some(a.out.as_path())]),
        Command::Train(a) => (vec![], vec![Some(a.out.as_path())]),
        Command::Predict(a) => (
            vec![Some(a.out.as_path()), a.json.as_deref()],
            vec![a.obj_dir.as_deref()],
        ),
        Command::Evaluate(a) => (vec![a.json.as_deref()], vec![a.report.as_deref()]),
        Command::Paired(a) => (vec![a.json.as_deref()], vec![]),
    };
    let outputs: Vec<&Path> = files_out
        .iter()
        .chain(&folders_out)
        .flatten()
        .copied()
        .collect();
    for (i, a) in outputs.iter().enumerate() {
        if let Some(b) = outputs[..i].iter().find(|b| resolved(b) == resolved(a)) {
            anyhow::bail!(
                "{} and {}: two outputs of one command name one file",
                b.display(),
                a.display()
            );
        }
    }
    // A command never writes into the dataset folder it reads.
    if let Command::Evaluate(a) = command {
        let data = resolved(&a.data);
        if let Some(out) = outputs.iter().find(|o| resolved(o).starts_with(&data)) {
            anyhow::bail!(
                "{}: inside the dataset folder {} that evaluate reads; write it elsewhere",
                out.display(),
                a.data.display()
            );
        }
    }
    for path in files_out.into_iter().flatten() {
        files::check_destination(path)?;
    }
    for path in folders_out.into_iter().flatten() {
        files::check_folder_destination(path)?;
    }
    Ok(())
}

/// A path as the file system will resolve it: absolute, with its deepest existing ancestor's
/// links and `..` resolved, so two spellings of one place compare equal.
fn resolved(path: &Path) -> std::path::PathBuf {
    let absolute = std::env::current_dir().map_or_else(|_| path.to_path_buf(), |d| d.join(path));
    let mut rest = Vec::new();
    let mut base = absolute.as_path();
    loop {
        if let Ok(real) = std::fs::canonicalize(base) {
            return rest.iter().rev().fold(real, |p, c| p.join(c));
        }
        match (base.parent(), base.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                base = parent;
            }
            _ => return absolute,
        }
    }
}
