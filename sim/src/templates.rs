//! Library templates made once and cached: a design's pattern sewn and draped on a body
//! (about 5-20 s), stored as OBJ under a key of everything the result depends on, and always
//! read back from that file, so a warm and a cold cache simulate the same numbers.

use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use garments::Garment;
use garments::library::NamedDesign;
use motions::BodyModel;

use crate::error::{Error, Result};
use crate::sewing::{SewingOptions, sew};

/// Where made templates are cached: `$DIT_GARMENT_CACHE`, else `$XDG_CACHE_HOME/dit-garment`,
/// else `~/.cache/dit-garment`.
pub fn cache_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("DIT_GARMENT_CACHE") {
        return dir.into();
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))
        .unwrap_or_else(|| ".cache".into());
    base.join("dit-garment")
}

/// The cached template's path in `cache`: the design's name and a hash of its pattern, the
/// body, the sewing options, the software version and the engine revision.
pub fn template_path(design: &NamedDesign, model: &BodyModel, cache: &Path) -> Result<PathBuf> {
    let pattern = design
        .pattern()
        .map_err(|e| garment_error(&design.name, e))?;
    Ok(keyed_path(&design.name, &pattern, model, cache))
}

fn keyed_path(name: &str, pattern: &garments::Pattern, model: &BodyModel, cache: &Path) -> PathBuf {
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    pattern.to_json().hash(&mut hasher);
    env!("CARGO_PKG_VERSION").hash(&mut hasher);
    crate::ENGINE_REVISION.hash(&mut hasher);
    model.name().hash(&mut hasher);
    format!("{:?}", SewingOptions::default()).hash(&mut hasher);
    for v in model.template() {
        v.map(f64::to_bits).hash(&mut hasher);
    }
    cache.join(format!("{name}-{:016x}.obj", hasher.finish()))
}

/// A library design's (or a variant's) template on `model`, made on first use (`making` hears
/// the path it is being made for) and cached in `cache` (see [`template_path`]). Refused when
/// the design fails a quality gate. The cached OBJ is always what is returned.
pub fn library_template(
    design: &NamedDesign,
    model: &BodyModel,
    cache: &Path,
    making: impl FnOnce(&Path),
) -> Result<Garment> {
    let pattern = design
        .pattern()
        .map_err(|e| garment_error(&design.name, e))?;
    pattern_template(&design.name, &pattern, model, cache, making)
}

/// A sewing pattern's template on `model` (a GarmentCode specification read by
/// `garments::Pattern::read`, or a library design's), made and cached as a library design's
/// is: the cache key holds the whole pattern, so an edited file is sewn again.
pub fn pattern_template(
    name: &str,
    pattern: &garments::Pattern,
    model: &BodyModel,
    cache: &Path,
    making: impl FnOnce(&Path),
) -> Result<Garment> {
    let path = keyed_path(name, pattern, model, cache);
    if !path.exists() {
        making(&path);
        let mesh = pattern
            .mesh(garments::pattern::DEFAULT_EDGE_LENGTH_M)
            .map_err(|e| garment_error(name, e))?;
        let (template, report) = sew(model, &mesh, &SewingOptions::default())?;
        if !report.gates_passed {
            return Err(Error::TemplateGates {
                garment: name.to_string(),
                failed: report.failed.join("; "),
            });
        }
        write_template(&path, &template)?;
    }
    // Always the cached file, so the first use and every later one simulate the same numbers.
    let mut cached = garments::read_obj(&path).map_err(|e| garment_error(name, e))?;
    cached.name = name.to_string();
    cached.validate().map_err(|e| garment_error(name, e))?;
    Ok(cached)
}

/// What `garments make` reports: the sewing's gates and figures, and its timings.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MadeTemplate {
    /// The pattern's name.
    pub name: String,
    /// The gates and their figures.
    #[serde(flatten)]
    pub sewing: crate::sewing::SewingReport,
    /// The target edge length it was meshed at, m.
    pub edge_length_m: f64,
    /// Meshing time, s.
    pub mesh_s: f64,
    /// Total time, s.
    pub wall_s: f64,
}

/// Meshes `pattern` at `edge_length`, sews and drapes it on the default body and writes the
/// template to `out` (OBJ, or PLY by its name) whether its gates pass or not; `meshed` is told
/// the panel and vertex counts before sewing, which takes a while.
pub fn make_template(
    pattern: &garments::Pattern,
    edge_length: f64,
    out: &Path,
    meshed: impl FnOnce(usize, usize),
) -> Result<MadeTemplate> {
    let started = std::time::Instant::now();
    let mesh = pattern.mesh(edge_length).map_err(|e| Error::Garment {
        garment: pattern.name.clone(),
        problem: e.to_string(),
    })?;
    let mesh_s = started.elapsed().as_secs_f64();
    meshed(mesh.garment.panels.len(), mesh.garment.positions.len());
    let (template, sewing) = sew(&BodyModel::default_body(), &mesh, &SewingOptions::default())?;
    write_template(out, &template)?;
    Ok(MadeTemplate {
        name: pattern.name.clone(),
        sewing,
        edge_length_m: edge_length,
        mesh_s,
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// Writes a template as OBJ, or PLY when the name ends in `.ply`, atomically (its folder
/// created if need be).
pub fn write_template(path: &Path, template: &Garment) -> Result<()> {
    files::create_folder_of(path)?;
    let ply = path.extension().is_some_and(|e| e == "ply");
    Ok(files::write_with(path, |w| {
        if ply {
            garments::write_ply(w, template)
        } else {
            garments::write_obj(w, template, None)
        }
    })?)
}

fn garment_error(name: &str, problem: impl std::fmt::Display) -> Error {
    Error::Garment {
        garment: name.to_string(),
        problem: problem.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_template_is_keyed_by_design_and_body_and_written_as_obj_or_ply() {
        let model = BodyModel::default_body();
        let cache = Path::new("/cache");
        let design = |name| garments::library::resolve(name).unwrap();
        let path = |name| template_path(&design(name), &model, cache).unwrap();
        assert_eq!(path("tshirt_fitted"), path("tshirt_fitted"), "stable");
        assert_ne!(
            path("tshirt_fitted"),
            path("tshirt_fitted~1"),
            "a variant is another"
        );
        let name = path("tshirt_fitted")
            .file_name()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        assert!(
            name.starts_with("tshirt_fitted-") && name.ends_with(".obj"),
            "{name}"
        );

        let dir = tempfile::tempdir().unwrap();
        let (garment, _) = crate::scene::builtin_template(
            &model,
            "skirt",
            &garments::SkirtParams {
                columns: 12,
                rings: 4,
                ..garments::SkirtParams::default()
            },
        )
        .unwrap();
        let obj = dir.path().join("new folder/t.obj");
        write_template(&obj, &garment).unwrap();
        let back = garments::read_obj(&obj).unwrap();
        // The OBJ may number the vertices its own way; the mesh is the same size.
        assert_eq!(back.triangles.len(), garment.triangles.len());
        assert_eq!(back.positions.len(), garment.positions.len());
        let ply = dir.path().join("t.ply");
        write_template(&ply, &garment).unwrap();
        assert!(std::fs::read(&ply).unwrap().starts_with(b"ply\n"));
    }
}
