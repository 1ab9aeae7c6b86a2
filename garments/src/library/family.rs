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

impl Family {
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
}
