//! `garments list | show | make | import | check`.

use std::path::Path;

use anyhow::{Context, Result, bail};
use garments::Pattern;
use garments::library::{DESIGNS, resolve};
use motions::BodyModel;

use crate::cli::GarmentsCommand;

use files::write_json;

/// Runs a `garments` subcommand.
pub fn run(command: GarmentsCommand) -> Result<()> {
    match command {
        GarmentsCommand::List { json } => list(json.as_deref()),
        GarmentsCommand::Show { name, pattern_out } => show(&name, pattern_out.as_deref()),
        GarmentsCommand::Make {
            source,
            out,
            report,
            edge_length,
        } => make(&source, &out, report.as_deref(), edge_length),
        GarmentsCommand::Import {
            mesh,
            motion,
            frame,
            betas,
            out,
            scale,
            rest_shrink,
            report,
            model,
        } => import(
            &mesh,
            &Worn {
                motion: &motion,
                frame,
                betas: betas.as_deref(),
                body_model: model.body_model.as_deref(),
            },
            &out,
            surrogate::import::ImportOptions {
                scale,
                rest_shrink,
                ..Default::default()
            },
            report.as_deref(),
        ),
        GarmentsCommand::Check { file, scale, json } => check(&file, scale, json.as_deref()),
    }
}

/// The body a mesh to import is worn by.
struct Worn<'a> {
    motion: &'a str,
    frame: usize,
    betas: Option<&'a [f64]>,
    body_model: Option<&'a Path>,
}

fn import(
    mesh: &Path,
    worn: &Worn,
    out: &Path,
    options: surrogate::import::ImportOptions,
    report: Option<&Path>,
) -> Result<()> {
    let (scale, shrink) = (options.scale, options.rest_shrink);
    anyhow::ensure!(
        scale.is_finite() && scale > 0.0,
        "--scale {scale}: must be a positive number"
    );
    anyhow::ensure!(
        (0.8..=1.0).contains(&shrink),
        "--rest-shrink {shrink}: must be from 0.8 to 1"
    );
    let model = sim::sources::body_model(worn.body_model)?;
    let garment = garments::read_mesh(mesh)?;
    // The motion's own shape where it carries one (AMASS files do) and none is given.
    let unshaped = model.shape(&[])?;
    let motion = sim::sources::motion(worn.motion, &model, &unshaped)?;
    let betas: Vec<f64> = match (worn.betas, &motion.betas) {
        (Some(b), _) => b.to_vec(),
        (None, Some(b)) => b.clone(),
        (None, None) => Vec::new(),
    };
    let shaped = model.shape(&betas)?;
    let motion = sim::sources::motion(worn.motion, &model, &shaped)?;
    let pose = motion.frames.get(worn.frame).with_context(|| {
        format!(
            "--frame {}: the motion '{}' has {} frames",
            worn.frame,
            worn.motion,
            motion.frames.len()
        )
    })?;
    eprintln!(
        "{}: {} vertices, {} triangles; cleaning, unwinding and draping ...",
        mesh.display(),
        garment.positions.len(),
        garment.triangles.len()
    );
    let (template, made) =
        surrogate::import::import_garment(&model, &garment, &shaped, pose, &options)
            .with_context(|| format!("importing {}", mesh.display()))?;
    sim::templates::write_template(out, &template)?;
    say!(
        "{}: {} vertices ({} welded, {} subdivisions), UVs {}; carried back {:.1} cm on average; \
         inside {}, moving {:.1}%, max stretch {:.3}, self-intersections {}; {:.1} s -> {}",
        mesh.display(),
        made.drape.vertices,
        made.welded,
        made.subdivisions,
        made.uvs,
        100.0 * made.unposed_mean_m,
        made.drape.verts_inside,
        100.0 * made.drape.moving_fraction,
        made.drape.max_edge_stretch,
        made.drape.self_intersections,
        made.drape.drape_s,
        out.display()
    );
    if let Some(path) = report {
        write_json(path, &made)?;
    }
    if !made.drape.gates_passed {
        bail!("quality gates failed: {}", made.drape.failed.join("; "));
    }
    say!("gates passed");
    Ok(())
}

fn unknown(name: &str) -> anyhow::Error {
    anyhow::anyhow!(
        "unknown design '{name}' (designs: {})",
        garments::library::naming()
    )
}

fn list(json: Option<&Path>) -> Result<()> {
    let mut rows = Vec::new();
    say!(
        "{:<24} {:<6} {:>8} {:>6}  description",
        "name",
        "split",
        "vertices",
        "panels"
    );
    for d in DESIGNS {
        let row = d.summary()?;
        say!("{row}");
        rows.push(row);
    }
    if let Some(path) = json {
        write_json(path, &rows)?;
    }
    Ok(())
}

fn show(name: &str, pattern_out: Option<&Path>) -> Result<()> {
    let design = resolve(name).ok_or_else(|| unknown(name))?;
    let pattern = design.pattern()?;
    let base = design.base;
    if design.index == 0 {
        say!("{}: {} ({} split)", base.name, base.description, base.split);
    } else {
        let kind = design.kind.describe();
        say!(
            "{}: {kind} {} of {} ({})",
            design.name,
            design.index,
            base.name,
            base.description
        );
    }
    say!(
        "parameters (cm): {}",
        serde_json::to_string(&design.params).unwrap_or_default()
    );
    for panel in &pattern.panels {
        say!(
            "  panel {:<16} {} corners, {} edges",
            panel.name,
            panel.vertices.len(),
            panel.edges.len()
        );
    }
    let mesh = pattern.mesh(garments::pattern::DEFAULT_EDGE_LENGTH_M)?;
    let merged = mesh.merged(&mesh.garment.positions)?;
    say!(
        "  {} stitches; template {} vertices, {} triangles at {} m edges",
        pattern.stitches.len(),
        merged.positions.len(),
        merged.triangles.len(),
        garments::pattern::DEFAULT_EDGE_LENGTH_M
    );
    if let Some(path) = pattern_out {
        files::create_folder_of(path)?;
        files::write_atomic(path, format!("{}\n", pattern.to_json()).as_bytes())?;
        say!("wrote {}", path.display());
    }
    Ok(())
}

/// A design or a pattern file.
pub fn load_pattern(source: &str) -> Result<Pattern> {
    if let Some(d) = resolve(source) {
        return Ok(d.pattern()?);
    }
    let path = Path::new(source);
    if path.extension().is_some_and(|e| e == "json") || path.exists() {
        return Ok(Pattern::read_seated(path)?);
    }
    Err(unknown(source))
}

fn make(source: &str, out: &Path, report: Option<&Path>, edge_length: f64) -> Result<()> {
    let pattern = load_pattern(source)?;
    let meshed = |panels, vertices| {
        eprintln!(
            "{}: {panels} panels, {vertices} vertices before sewing; sewing and draping ...",
            pattern.name
        )
    };
    let made = sim::templates::make_template(&pattern, edge_length, out, meshed)
        .with_context(|| format!("making the template of '{source}'"))?;
    say!(
        "{}: {} vertices, {} triangles; inside {}, seam gap {:.2} mm, moving {:.1}%, max stretch \
         {:.3}, self-intersections {}; {:.1} s -> {}",
        made.name,
        made.sewing.vertices,
        made.sewing.triangles,
        made.sewing.verts_inside,
        1e3 * made.sewing.max_seam_gap_m,
        100.0 * made.sewing.moving_fraction,
        made.sewing.max_edge_stretch,
        made.sewing.self_intersections,
        made.wall_s,
        out.display()
    );
    if let Some(path) = report {
        write_json(path, &made)?;
    }
    if !made.sewing.gates_passed {
        bail!("quality gates failed: {}", made.sewing.failed.join("; "));
    }
    say!("gates passed");
    Ok(())
}

fn check(file: &Path, scale: f64, json: Option<&Path>) -> Result<()> {
    let shown = file.display().to_string();
    if file.extension().is_some_and(|e| e == "json") {
        let pattern = Pattern::read_seated(file)?;
        let mesh = pattern
            .mesh(garments::pattern::DEFAULT_EDGE_LENGTH_M)
            .map_err(|e| anyhow::anyhow!("{shown}: {e}"))?;
        // What `garments make` needs before it drapes: the mesh builds and its system
        // factorizes (a pattern passed here does not fail there in the solver).
        sim::sewing::preflight(
            &BodyModel::default_body(),
            &mesh,
            &sim::sewing::SewingOptions::default(),
        )
        .map_err(|e| anyhow::anyhow!("{shown}: cannot be sewn: {e}"))?;
        say!(
            "{shown}: a valid sewing pattern: {} panels, {} stitches, {} vertices at {} m edges",
            pattern.panels.len(),
            pattern.stitches.len(),
            mesh.garment.positions.len(),
            garments::pattern::DEFAULT_EDGE_LENGTH_M
        );
        return Ok(());
    }
    let out = garments::check_obj_file(file, scale)?;
    say!(
        "{shown}: {} vertices, {} triangles, {} panels, extent {:.3} x {:.3} x {:.3} m",
        out.vertices,
        out.triangles,
        out.panels,
        out.extent_m[0],
        out.extent_m[1],
        out.extent_m[2]
    );
    if out.findings.is_empty() {
        say!("  no problems found");
    }
    for line in &out.findings {
        say!("  {line}");
    }
    if let Some(path) = json {
        write_json(path, &out)?;
    }
    if !out.usable {
        bail!("{shown}: cannot be used as a garment template (see the findings above)");
    }
    Ok(())
}
