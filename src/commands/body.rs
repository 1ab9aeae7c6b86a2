//! `dit-garment body`: pose a body and write it as OBJ (and its numbers as JSON).

use anyhow::{Result, bail};
use serde_json::json;
use sim::sources::BodyParams;

use crate::cli::BodyArgs;
use files::write_json;

pub fn run(args: &BodyArgs) -> Result<()> {
    if args.out.is_none() && args.json.is_none() {
        bail!("nothing to write: give --out FILE.obj and/or --json FILE");
    }
    let model = sim::sources::body_model(args.model.body_model.as_deref())?;
    let params = match &args.params {
        Some(p) => BodyParams::load(p)?,
        None => BodyParams::default(),
    };
    let shaped = model.shape(&params.betas)?;
    let mut frame = params.frame();
    if let (Some(source), Some(k)) = (&args.motion, args.frame) {
        let motion = sim::sources::motion(source, &model, &shaped)?;
        let Some(f) = motion.frames.get(k) else {
            bail!(
                "--frame {k} is past the end of '{source}' ({} frames at 30 fps)",
                motion.len()
            );
        };
        frame = *f;
    }
    let posed = model.pose(&shaped, &frame)?;
    let height = shaped.height();
    let boundary = model.boundary_edge_count();
    if let Some(out) = &args.out {
        let comment = format!(
            "dit-garment body: model {}, betas {:?}\nmetres, y up, facing +z; vertices in the model's order",
            model.name(),
            shaped.betas
        );
        files::create_folder_of(out)?;
        files::write_with(out, |w| {
            garments::write_mesh_obj(w, &comment, &posed.vertices, model.faces())
        })?;
        say!(
            "wrote {} ({} vertices, {} triangles, rest height {:.3} m, {} boundary edges)",
            out.display(),
            model.num_vertices(),
            model.faces().len(),
            height,
            boundary
        );
    }
    if let Some(path) = &args.json {
        write_json(
            path,
            &json!({
                "vertices": model.num_vertices(),
                "faces": model.faces().len(),
                "boundary_edges": boundary,
                "height_m": height,
                "posed_height_m": posed.height(),
                "betas": shaped.betas,
                "beta_names": model.beta_names(),
                "joints": posed.joints,
                "model": model.name(),
            }),
        )?;
    }
    Ok(())
}
