//! One module per subcommand; each turns parsed flags into a run.

mod body;
mod compare;
mod dataset_cmd;
mod demo;
mod drape_bench;
mod evaluate;
mod garments_cmd;
mod motions_cmd;
mod predict;
mod regress;
mod render;
mod simulate;
mod synth;
mod train;
mod uv;

use anyhow::Result;

use crate::cli::{Cli, Command};

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<()> {
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
    }
}

/// Vertical extent of a vertex set, metres.
pub fn height(vertices: &[[f64; 3]]) -> f64 {
    let (lo, hi) = vertices.iter().fold((f64::MAX, f64::MIN), |(lo, hi), v| {
        (lo.min(v[1]), hi.max(v[1]))
    });
    hi - lo
}
