//! `dit-garment uv`: the surrogate's geometry images of a template or a recording, as
//! pictures (position map, mask, target maps, a contact sheet), and for a recording the UV
//! round-trip floor (the ground truth encoded, read back and scored).

use std::path::Path;

use anyhow::{Context, Result};
use render::{ColourScale, contact_sheet, magnitude_picture, texel_picture, vector_picture};
use serde_json::json;
use sim::recording::TemplateArrays;
use surrogate::data::{Sequence, roundtrip_floor};
use surrogate::geometry::{GeometryImage, RootRemoval, TargetKind, Targets};

use crate::cli::UvArgs;
use crate::inputs;
use files::write_json;
use render::recording::save_png;

/// Pixels per side of every picture (texels are drawn as blocks).
const PICTURE_PIXELS: u32 = 384;

/// Target maps drawn for a recording.
const TARGET_PICTURES: usize = 4;

pub fn run(args: &UvArgs) -> Result<()> {
    target_and_root(args)?;
    let model = sim::sources::body_model(args.model.body_model.as_deref())?;
    let is_recording = args.source.ends_with(".mcap");
    let (template, sequence) = if is_recording {
        let sequence = Sequence::read(Path::new(&args.source))?;
        (sequence.template.clone(), Some(sequence))
    } else {
        let (g, _) = inputs::garment(&args.source, &model)?;
        let t = TemplateArrays::from(&g);
        (t, None)
    };
    let image = GeometryImage::of_template(&template, args.resolution)
        .with_context(|| format!("{}: geometry image", args.source))?;
    let r = args.resolution;
    let atlas = image.atlas();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut tiles = Vec::new();
    let position = image.encode(&template.positions)?;
    let inside = atlas.inside().to_vec();
    tiles.push((
        vector_picture(&position, &inside, r, PICTURE_PIXELS / r as u32),
        "position map".to_string(),
    ));
    let loss_mask = image.loss_mask();
    let mask = texel_picture(r, PICTURE_PIXELS / r as u32, |t| {
        match (inside[t], loss_mask[t]) {
            (true, _) => [255, 255, 255],
            (false, true) => [150, 150, 150],
            _ => [0, 0, 0],
        }
    });
    tiles.push((mask, "mask (grey: read back)".to_string()));
    let texel_cm = GeometryImage::texel_cm(&template, r);
    let mut summary = json!({
        "source": args.source, "resolution": r, "coverage": atlas.coverage(),
        "texel_cm": texel_cm, "vertices": template.positions.len(),
        "uv_corners": template.uvs.len(), "charts": atlas.charts(),
        "root": args.root,
    });
    let floor_line = match &sequence {
        Some(sequence) => recording_floor(
            args,
            &model,
            sequence,
            &image,
            &template,
            &mut tiles,
            &mut summary,
        )?,
        None => String::new(),
    };
    let names = ["position_map.png", "mask.png"];
    for (i, (tile, _)) in tiles.iter().enumerate() {
        let name = match names.get(i) {
            Some(n) => n.to_string(),
            None => format!("target_{}.png", i - names.len()),
        };
        save_png(&args.out.join(name), tile)?;
    }
    let sheet = args.out.join("contact_sheet.png");
    save_png(&sheet, &contact_sheet(&tiles, 3))?;
    summary["contact_sheet"] = json!(sheet);
    say!(
        "uv: '{}' at {r} x {r}: {} vertices, {} UV corners, {} charts, coverage {:.2}, texel {:.2} cm{}",
        args.source,
        template.positions.len(),
        template.uvs.len(),
        atlas.charts(),
        atlas.coverage(),
        texel_cm,
        floor_line
    );
    say!("  wrote {}", sheet.display());
    if let Some(path) = &args.json {
        write_json(path, &summary)?;
    }
    Ok(())
}

/// For a recording: the target maps of TARGET_PICTURES frames added to `tiles`, the UV
/// round-trip floor added to `summary`; returns the floor's line for the printout.
fn recording_floor(
    args: &UvArgs,
    model: &motions::BodyModel,
    sequence: &Sequence,
    image: &GeometryImage,
    template: &TemplateArrays,
    tiles: &mut Vec<(render::RgbImage, String)>,
    summary: &mut serde_json::Value,
) -> Result<String> {
    let (kind, removal) = target_and_root(args)?;
    let (r, inside) = (args.resolution, image.atlas().inside().to_vec());
    let mut targets = Targets::new(
        model,
        &template.positions,
        &template.triangles,
        kind,
        removal,
    )?;
    let floor = roundtrip_floor(model, sequence, image, &mut targets, args.every)?;
    let first = sequence.first_motion_frame();
    let frames: Vec<usize> = (0..TARGET_PICTURES)
        .map(|i| first + (sequence.len() - 1 - first) * i / (TARGET_PICTURES - 1))
        .collect();
    let scale = ColourScale {
        min: 0.0,
        max: (floor.target_mean_cm * 3.0).max(1.0) as f32,
    };
    for &k in &frames {
        let target = targets.encode(model, sequence.body(k), &sequence.garment[k])?;
        let map = image.encode(&target)?;
        tiles.push((
            magnitude_picture(&map, &inside, r, PICTURE_PIXELS / r as u32, scale),
            format!("{} frame {k}", kind.name()),
        ));
    }
    summary["target"] = kind.name().into();
    summary["frames_scored"] = floor.frames_scored.into();
    summary["roundtrip_E_v_cm"] = floor.mean_cm.into();
    summary["roundtrip_p95_cm"] = floor.p95_cm.into();
    summary["roundtrip_max_cm"] = floor.max_cm.into();
    summary["worst_vertex"] = floor.worst_vertex.into();
    summary["target_mean_cm"] = floor.target_mean_cm.into();
    summary["target_frames"] = json!(frames);
    Ok(format!(
        "; round trip ({}, {} frames): mean {:.3} cm, p95 {:.3} cm, max {:.2} cm (vertex {}); mean target {:.2} cm",
        kind.name(),
        floor.frames_scored,
        floor.mean_cm,
        floor.p95_cm,
        floor.max_cm,
        floor.worst_vertex,
        floor.target_mean_cm,
    ))
}

/// The target kind and root removal `--target` and `--root` name.
fn target_and_root(args: &UvArgs) -> Result<(TargetKind, RootRemoval)> {
    let kind = TargetKind::parse(&args.target).context("unknown --target")?;
    let removal = match args.root.as_str() {
        "full" => RootRemoval::Full,
        _ => RootRemoval::Heading,
    };
    Ok((kind, removal))
}
