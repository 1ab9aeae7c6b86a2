//! `dit-garment simulate`: a garment on a body through a motion, recorded as MCAP (and
//! optionally OBJ frames), with a progress bar and a JSON summary.

use anyhow::{Context, Result};

use crate::cli::SimulateArgs;
use crate::run::{RecordOptions, prepare, print_config, record, resolve_config, summary_json};
use files::write_json;

pub fn run(args: &SimulateArgs) -> Result<()> {
    let mut config = resolve_config(&args.scene)?;
    config.record.body_vertices |= args.body_vertices;
    config.record.foxglove |= args.foxglove;
    if print_config(&args.scene, &config)? {
        return Ok(());
    }
    let out = args
        .out
        .as_deref()
        .context("simulate needs --out FILE.mcap")?;
    let prepared = prepare(config)?;
    let options = RecordOptions {
        obj: args.obj_dir.as_deref().map(|d| (d, args.obj_every)),
        quiet: args.quiet,
        ..RecordOptions::default()
    };
    let s = record(&prepared, out, options)
        .with_context(|| format!("simulating into {}", out.display()))?;
    if let Some(path) = &args.json {
        write_json(path, &summary_json(&s, out))?;
    }
    say!(
        "simulate: '{}' ({} vertices) on '{}' through '{}': {} frames in {:.1} s ({:.1} frames/s)",
        prepared.garment.name,
        s.vertices,
        prepared.model.name(),
        prepared.scene.motion.name,
        s.frames,
        s.wall_s,
        s.frames_per_s
    );
    say!("  {s}; wrote {}", out.display());
    Ok(())
}
