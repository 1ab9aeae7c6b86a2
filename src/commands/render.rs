//! `dit-garment render` (PNG pictures, contact sheet, GIF) and `dit-garment view` (the HTML
//! viewer) of recordings, over `render::recording`.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use render::recording::{RenderJob, render_recording, write_view};
use render::{ColourScale, View};
use serde_json::json;

use crate::cli::{RenderArgs, ViewArgs};
use crate::run::gif_progress;
use files::write_json;

pub fn run(args: &RenderArgs) -> Result<()> {
    let views = args
        .views
        .iter()
        .map(|v| {
            View::parse(v)
                .with_context(|| format!("unknown view '{v}' (front, side or three-quarter)"))
        })
        .collect::<Result<Vec<_>>>()?;
    if args.size == 0 || args.size > 8192 {
        bail!("--size {} is out of range (1 to 8192)", args.size);
    }
    if args.ssaa == 0 || args.ssaa > 4 {
        bail!("--ssaa {} is out of range (1 to 4)", args.ssaa);
    }
    if !(16..=2048).contains(&args.gif_size) {
        bail!("--gif-size {} is out of range (16 to 2048)", args.gif_size);
    }
    // Every picture is drawn supersampled: bound the samples per side.
    if args.size.max(args.gif_size) * args.ssaa > 8192 {
        bail!(
            "--size {} (or --gif-size {}) with --ssaa {} is more than 8192 samples per side; \
             lower one",
            args.size,
            args.gif_size,
            args.ssaa
        );
    }
    if args.frames.len() * views.len() > 64 {
        bail!(
            "--frames and --views ask for {} pictures; at most 64 per run (use --gif for the \
             whole sequence)",
            args.frames.len() * views.len()
        );
    }
    let range = match args.range.as_slice() {
        [] => None,
        [lo, hi] if lo < hi => Some(ColourScale { min: *lo, max: *hi }),
        _ => bail!("--range needs two values min,max with min < max"),
    };
    if args.color_by.is_none() && (args.against.is_some() || range.is_some()) {
        bail!("--against and --range need --color-by");
    }
    let model = sim::sources::body_model(args.model.body_model.as_deref())?;
    let job = RenderJob {
        frames: &args.frames,
        views: &views,
        size: args.size,
        ssaa: args.ssaa,
        colour_by: args
            .color_by
            .map(|by| (by.into(), args.against.as_deref(), range)),
        gif: args.gif.then_some((args.gif_every, args.gif_size)),
    };
    let mut progress = gif_progress();
    let r = render_recording(
        &args.recording,
        &model,
        !args.no_body,
        &job,
        &args.out,
        &mut progress,
    )
    .with_context(|| format!("rendering {}", args.recording.display()))?;
    say!(
        "render: {} pictures of {} in {:.2} s ({:.0} ms each, {} garment pixels in the first); contact sheet {}{}",
        r.pictures,
        args.recording.display(),
        r.wall_s,
        1e3 * r.wall_s / r.pictures.max(1) as f64,
        r.pixels_garment,
        r.sheet.display(),
        r.gif
            .as_ref()
            .map(|g| format!(", GIF {}", g.display()))
            .unwrap_or_default()
    );
    if let Some(path) = &args.json {
        let mut images = r.images.clone();
        images.push(r.sheet.clone());
        write_json(
            path,
            &json!({
                "images": images, "pixels_garment": r.pixels_garment, "sheet": r.sheet,
                "gif": r.gif, "pictures": r.pictures, "wall_s": r.wall_s,
                "size": args.size, "views": args.views,
            }),
        )?;
    }
    Ok(())
}

pub fn view(args: &ViewArgs) -> Result<()> {
    let model = sim::sources::body_model(args.model.body_model.as_deref())?;
    let started = Instant::now();
    write_view(
        &args.recordings,
        &model,
        !args.no_body,
        args.every,
        &args.out,
    )?;
    let bytes = std::fs::metadata(&args.out).map(|m| m.len()).unwrap_or(0);
    say!(
        "view: wrote {} ({:.1} MB, {} recording{}) in {:.1} s; open it in a browser",
        args.out.display(),
        bytes as f64 / 1e6,
        args.recordings.len(),
        if args.recordings.len() == 1 { "" } else { "s" },
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
