//! The garment family a sequence is reported under: a library design's from its parameters
//! ([`Family::of_garment`]), any other garment's (a GarmentCode pattern file, an imported
//! mesh) from how its template is worn on the canonical body ([`Family::of_fit`]), so the real
//! patterns' split is reported per family as the library's designs are.

use std::collections::BTreeMap;
use std::path::Path;

use dataset::DatasetDir;
use garments::library::Family;
use motions::BodyModel;
use sim::Vec3;
use sim::obstacles::MeshSurface;

use super::tables::SequenceResult;
use crate::error::Result;

/// How a template (vertices on the canonical body, m) is worn: its hem's height above the feet
/// as a fraction of the body's height, and its ease (the mean of the 75th and 90th percentiles
/// of its vertices' distances from the body's surface, m; a vertex inside counts as 0).
pub fn worn_fit(template: &[[f64; 3]], model: &BodyModel) -> Result<(f64, f64)> {
    let body = sim::scene::canonical_body(model)?;
    let feet = body
        .vertices
        .iter()
        .map(|v| v[1])
        .fold(f64::INFINITY, f64::min);
    let hem = template.iter().map(|v| v[1]).fold(f64::INFINITY, f64::min);
    let vertices: Vec<Vec3> = body.vertices.iter().map(|&v| Vec3::from(v)).collect();
    let surface = MeshSurface::new("body", &vertices, model.faces())?;
    let mut distances: Vec<f64> = template
        .iter()
        .map(|&p| {
            surface
                .query(Vec3::from(p), f64::INFINITY)
                .map_or(0.0, |s| s.distance.max(0.0))
        })
        .collect();
    distances.sort_by(f64::total_cmp);
    let percentile = |q: f64| {
        let last = distances.len().saturating_sub(1);
        distances.get((q * last as f64).round() as usize).copied()
    };
    let ease = match (percentile(0.75), percentile(0.90)) {
        (Some(a), Some(b)) => 0.5 * (a + b),
        _ => 0.0,
    };
    Ok(((hem - feet) / body.height().max(1e-9), ease))
}

/// The family of `garment` as simulated in the dataset at `data`: a library design's own, or,
/// for any other garment, decided from its template in the dataset (`templates/`).
pub fn garment_family(garment: &str, data: &Path, model: &BodyModel) -> Result<Family> {
    if let Some(family) = Family::of_garment(garment) {
        return Ok(family);
    }
    let template = garments::read_obj(&DatasetDir::new(data).template(garment))?;
    let (hem, ease) = worn_fit(&template.positions, model)?;
    Ok(Family::of_fit(hem, ease))
}

/// Sets every result's `family` ([`garment_family`], once per garment), cached results
/// included.
pub fn fill_families(results: &mut [SequenceResult], data: &Path, model: &BodyModel) -> Result<()> {
    let mut known: BTreeMap<String, Family> = BTreeMap::new();
    for r in results {
        let family = match known.get(&r.garment) {
            Some(&family) => family,
            None => {
                let family = garment_family(&r.garment, data, model)?;
                known.insert(r.garment.clone(), family);
                family
            }
        };
        r.family = family.name().to_string();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The built-in skirt's template is worn as a skirt by its geometry alone (its name would
    /// say so too; the geometry is what a pattern file or an imported mesh is judged by).
    #[test]
    fn the_built_in_skirt_is_worn_as_a_skirt() {
        let model = BodyModel::default_body();
        let (skirt, _) =
            sim::scene::builtin_template(&model, "skirt", &garments::SkirtParams::default())
                .unwrap();
        let (hem, ease) = worn_fit(&skirt.positions, &model).unwrap();
        assert!((0.2..0.43).contains(&hem), "hem at {hem:.3} of the height");
        assert_eq!(Family::of_fit(hem, ease), Family::DressOrSkirt);
    }

    /// The body's own surface, pushed out along its normals in the torso's band (between 50%
    /// and 75% of its height), is a top, fitted at 1 cm of ease and loose at 8 cm.
    #[test]
    fn a_band_around_the_torso_is_fitted_or_loose_by_its_distance() {
        let model = BodyModel::default_body();
        let body = sim::scene::canonical_body(&model).unwrap();
        let vertices: Vec<Vec3> = body.vertices.iter().map(|&v| Vec3::from(v)).collect();
        let surface = MeshSurface::new("body", &vertices, model.faces()).unwrap();
        let feet = vertices.iter().map(|v| v.y).fold(f64::INFINITY, f64::min);
        let height = body.height();
        // Torso vertices only: the arms hang beside it in the A-pose.
        let torso: Vec<usize> = (0..vertices.len())
            .filter(|&i| {
                let v = vertices[i];
                let y = (v.y - feet) / height;
                (0.5..0.75).contains(&y) && v.x.abs() < 0.15
            })
            .collect();
        let band = |offset: f64| -> Vec<[f64; 3]> {
            torso
                .iter()
                .map(|&i| (vertices[i] + surface.vertex_normal(i) * offset).into())
                .collect()
        };
        let (hem, fitted) = worn_fit(&band(0.01), &model).unwrap();
        assert!(hem > 0.45, "{hem}");
        assert!((0.005..0.02).contains(&fitted), "ease {fitted}");
        assert_eq!(Family::of_fit(hem, fitted), Family::FittedTop);
        let (_, loose) = worn_fit(&band(0.08), &model).unwrap();
        assert_eq!(Family::of_fit(hem, loose), Family::LooseTop, "ease {loose}");
    }

    /// Every library design's template (sewn and cached as `garments make` does; minutes the
    /// first time) is worn as its design's family: the rule's calibration. Run with
    /// `cargo test -p surrogate -- --ignored every_library_template`.
    #[test]
    #[ignore = "sews every library design the first time (about 10 minutes)"]
    fn every_library_template_is_worn_as_its_design_s_family() {
        let model = BodyModel::default_body();
        let cache = sim::templates::cache_dir();
        let mut wrong = Vec::new();
        for design in garments::library::DESIGNS {
            let named = garments::library::resolve(design.name).unwrap();
            let template =
                sim::templates::library_template(&named, &model, &cache, |_| {}).unwrap();
            let (hem, ease) = worn_fit(&template.positions, &model).unwrap();
            let worn = Family::of_fit(hem, ease);
            eprintln!(
                "{:24} hem {hem:.3} ease {:.2} cm: {} (design: {})",
                design.name,
                ease * 100.0,
                worn.name(),
                design.params.family().name()
            );
            if worn != design.params.family() {
                wrong.push(design.name);
            }
        }
        assert!(wrong.is_empty(), "worn as another family: {wrong:?}");
    }
}
