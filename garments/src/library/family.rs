//! Garment families, for reporting a model's errors where they differ: fitted tops, loose
//! tops, and dresses or skirts (the cloth that swings free of the legs).

use serde::Serialize;

use super::DesignParams;

/// A garment family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// A top close to the body.
    FittedTop,
    /// A top with ease: wide at the chest or hem, or a dropped armhole.
    LooseTop,
    /// A dress or skirt: the hem below the hips.
    DressOrSkirt,
}

/// Hem height (cm above the feet on GarmentCode's average body) below which a garment is a
/// dress or skirt: the library's tunics end at 74-76 cm, its shortest dress at 62.
const DRESS_HEM_CM: f64 = 70.0;
/// Chest half-width (cm) from which a top is loose (`tshirt_regular`: 27; `tank_loose`: 30).
const LOOSE_CHEST_CM: f64 = 29.0;
/// Hem half-width (cm) from which a top is loose (`tunic_longsleeve`: 31).
const LOOSE_HEM_CM: f64 = 31.0;
/// Armhole drop (cm) from which a top is loose (dropped shoulders).
const LOOSE_DROP_CM: f64 = 3.0;

/// Hem height above the feet, as a fraction of the body's height, below which a garment that is
/// not a library design is a dress or skirt: the library's [`DRESS_HEM_CM`] on our default body
/// (its templates' hems sit at 0.0062 of the body's height per cm of the design's hem height;
/// measured tunics 0.45-0.47, dresses 0.19-0.39).
const DRESS_HEM_FRACTION: f64 = 0.43;
/// Ease (see [`Family::of_fit`]) from which a top that is not a library design is loose, m:
/// midway between the library's fitted tops (at most 4.75 cm, `boatneck_top`) and its loose
/// ones (at least 5.46 cm, `camisole_long`), measured on their templates.
const LOOSE_EASE_M: f64 = 0.051;

impl Family {
    /// The family of a garment that is not a library design (a pattern file, an imported
    /// mesh), from how its template is worn on the canonical body, by the library's own rule
    /// made geometric: a hem below [`DRESS_HEM_FRACTION`] of the body's height above the feet
    /// makes a dress or skirt; otherwise an `ease_m` (the mean of the 75th and 90th
    /// percentiles of its vertices' distances from the body's surface, m) of at least
    /// [`LOOSE_EASE_M`] a loose top. Every library design's template gets its design's family
    /// this way (`surrogate`'s `every_library_template_is_worn_as_its_design_s_family`).
    pub fn of_fit(hem_height_fraction: f64, ease_m: f64) -> Family {
        if hem_height_fraction < DRESS_HEM_FRACTION {
            Family::DressOrSkirt
        } else if ease_m >= LOOSE_EASE_M {
            Family::LooseTop
        } else {
            Family::FittedTop
        }
    }

    /// The name used in reports (`fitted_top`, `loose_top`, `dress_or_skirt`).
    pub fn name(self) -> &'static str {
        match self {
            Family::FittedTop => "fitted_top",
            Family::LooseTop => "loose_top",
            Family::DressOrSkirt => "dress_or_skirt",
        }
    }

    /// The family of a library garment by name (a design, a variant, or the built-in skirt);
    /// `None` for anything else (template files, patterns).
    pub fn of_garment(name: &str) -> Option<Family> {
        if crate::BUILTIN.contains(&name) {
            return Some(Family::DressOrSkirt);
        }
        super::resolve(name).map(|d| d.params.family())
    }
}

impl DesignParams {
    /// The design's family, decided from its measurements.
    pub fn family(&self) -> Family {
        if self.hem_height < DRESS_HEM_CM {
            Family::DressOrSkirt
        } else if self.chest_half_width >= LOOSE_CHEST_CM
            || self.hem_half_width >= LOOSE_HEM_CM
            || self.armhole_drop >= LOOSE_DROP_CM
        {
            Family::LooseTop
        } else {
            Family::FittedTop
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_library_splits_into_the_three_families() {
        for (name, family) in [
            ("tank_tight", Family::FittedTop),
            ("vneck_tee", Family::FittedTop),
            ("elbow_sleeve_top", Family::FittedTop),
            ("tshirt_oversized", Family::LooseTop),
            ("tunic_longsleeve", Family::LooseTop),
            ("dress_loose_maxi", Family::DressOrSkirt),
            ("dress_tshirt", Family::DressOrSkirt),
            ("skirt", Family::DressOrSkirt),
        ] {
            assert_eq!(Family::of_garment(name), Some(family), "{name}");
        }
        assert_eq!(Family::of_garment("my_scan.obj"), None);
        let counts = crate::library::DESIGNS.iter().fold([0; 3], |mut c, d| {
            c[d.params.family() as usize] += 1;
            c
        });
        assert_eq!(counts, [9, 6, 4], "fitted, loose, dress");
    }

    #[test]
    fn a_worn_garment_is_a_dress_by_its_hem_and_loose_by_its_ease() {
        assert_eq!(Family::of_fit(0.30, 0.02), Family::DressOrSkirt);
        assert_eq!(Family::of_fit(0.30, 0.09), Family::DressOrSkirt);
        assert_eq!(Family::of_fit(0.58, 0.03), Family::FittedTop);
        assert_eq!(Family::of_fit(0.58, 0.06), Family::LooseTop);
        assert_eq!(Family::of_fit(0.45, 0.06), Family::LooseTop);
    }
}
