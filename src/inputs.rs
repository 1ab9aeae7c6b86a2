//! A garment as the commands load it: with a notice when its template is first made.

use std::path::Path;

use motions::BodyModel;

/// A garment template and its body attachments ([`sim::sources::garment`]), a library
/// design's made on first use and cached in the cache folder, with a notice when it is made.
pub fn garment(
    source: &str,
    model: &BodyModel,
) -> sim::Result<(garments::Garment, Vec<sim::scene::BodyAttachment>)> {
    let cache = sim::templates::cache_dir();
    sim::sources::garment(source, model, &cache, making_template(source))
}

/// The notice that the template of `source` is being made (the first use of a design).
pub fn making_template(source: &str) -> impl FnOnce(&Path) + '_ {
    move |path| {
        eprintln!(
            "making the template of '{source}' (first use; cached in {})",
            path.display()
        )
    }
}
