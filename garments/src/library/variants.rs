//! Variants of the library's designs: `tshirt_regular~3` is variant 3 of `tshirt_regular`,
//! its measurements drawn around the base design's; `tshirt_regular~w3` is its wide variant
//! 3, a design of another kind drawn over the library's whole range; `tank_loose~d3` is its
//! dress variant 3, a dress drawn over the range of dresses, from straight to flared and from
//! above the knee to the floor. The name is the whole recipe (the draw is seeded by the base's
//! name, the kind and the index), so the same name sews the same design in every command and
//! on every machine.
//!
//! Why: the surrogate generalizes to unseen designs by what its training designs span, and a
//! 19-design library spans little (docs/SURROGATE_ARMS.md, "The ablation"). A variant keeps its
//! base's family: the neckline type and whether it has sleeves never change, and every
//! measurement moves by at most a few cm (a sleeve by 15% of its length), so a variant of a
//! t-shirt is a t-shirt of another cut. Such variants did not help unseen designs, whose
//! neckline, sleeve length or hem no training design had; a wide variant keeps only whether
//! its base has sleeves and draws every measurement and the neckline type over the range the
//! library's designs span, so the training designs cover the space the library's kinds sit in.
//! A dress variant does the same over dresses alone: the library has four, one of them held
//! out for testing at the corner of the wide range (the longest and widest hem), so cloth that
//! swings free of the legs was a small corner of training (issue 53). Its range reaches past
//! the library's dresses on every side, so none of them sits at its edge.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{DESIGNS, Design, DesignParams, Neckline};
use crate::error::Result;
use crate::pattern::Pattern;

/// Between a base design's name and its variant's index.
pub(crate) const SEPARATOR: char = '~';

/// How a variant is drawn, and the mark its name carries after the separator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VariantKind {
    /// Measurements moved a few cm around the base's (`base~K`).
    Near,
    /// Everything but the sleeves drawn over the library's range (`base~wK`).
    Wide,
    /// A dress over the range of dresses, sleeves as the base's (`base~dK`).
    Dress,
}

impl VariantKind {
    /// The mark between the separator and the index.
    fn mark(self) -> &'static str {
        match self {
            VariantKind::Near => "",
            VariantKind::Wide => "w",
            VariantKind::Dress => "d",
        }
    }

    /// What a report calls it.
    pub fn describe(self) -> &'static str {
        match self {
            VariantKind::Near => "variant",
            VariantKind::Wide => "wide variant",
            VariantKind::Dress => "dress variant",
        }
    }
}

/// The largest variant index.
pub const MAX_INDEX: u32 = 9999;

/// A library design or a variant of one, resolved from its name.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedDesign {
    /// The name it was asked by (`base` or `base~k`).
    pub name: String,
    /// The library design it is, or is a variant of.
    pub base: &'static Design,
    /// The variant's index; 0 for the base design itself.
    pub index: u32,
    /// How the variant was drawn (`Near` for the base design itself).
    pub kind: VariantKind,
    /// Its measurements.
    pub params: DesignParams,
}

impl NamedDesign {
    /// The design as a checked pattern.
    pub fn pattern(&self) -> Result<Pattern> {
        self.params.pattern(&self.name)
    }
}

/// What a design name may be, for error messages: the library's names or a variant's form.
pub fn naming() -> String {
    format!(
        "{}; or a variant NAME{SEPARATOR}K, a wide variant NAME{SEPARATOR}wK or a dress variant \
         NAME{SEPARATOR}dK, K in 1..={MAX_INDEX}",
        super::design_names().join(", ")
    )
}

/// The name of variant `index` of `base`, of that kind.
pub fn variant_name(base: &str, index: u32, kind: VariantKind) -> String {
    format!("{base}{SEPARATOR}{}{index}", kind.mark())
}

/// The design called `name`: a library design, or `base~k`, `base~wk` or `base~dk` with k in
/// 1..=[`MAX_INDEX`].
pub fn resolve(name: &str) -> Option<NamedDesign> {
    let (base_name, index, kind) = match name.split_once(SEPARATOR) {
        None => (name, 0, VariantKind::Near),
        Some((base, k)) => {
            let (k, kind) = if let Some(k) = k.strip_prefix('w') {
                (k, VariantKind::Wide)
            } else if let Some(k) = k.strip_prefix('d') {
                (k, VariantKind::Dress)
            } else {
                (k, VariantKind::Near)
            };
            // Digits only, no sign or leading zero, so one design has one name.
            if k.is_empty() || k.starts_with('0') || !k.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            (
                base,
                k.parse::<u32>().ok().filter(|&k| k <= MAX_INDEX)?,
                kind,
            )
        }
    };
    let base = DESIGNS.iter().find(|d| d.name == base_name)?;
    let params = match (index, kind) {
        (0, _) => base.params,
        (_, VariantKind::Near) => jittered(base, index),
        (_, VariantKind::Wide) => wide_draw(base, index),
        (_, VariantKind::Dress) => dress_draw(base, index),
    };
    Some(NamedDesign {
        name: name.to_string(),
        base,
        index,
        kind,
        params,
    })
}

/// FNV-1a of the base's name: a seed that no Rust or crate version changes (std's hashers
/// may change between releases).
fn name_seed(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Variant `index` of `base`: each measurement drawn uniformly in a band around the base's,
/// cm. Widths move more outwards than inwards, so a tight base never gets tighter than the
/// body allows.
fn jittered(base: &Design, index: u32) -> DesignParams {
    let mut rng = ChaCha8Rng::seed_from_u64(name_seed(base.name) ^ ((index as u64) << 32));
    let p = base.params;
    let mut draw = |value: f64, below: f64, above: f64| value + rng.random_range(-below..=above);
    let mut v = p;
    v.hem_height = draw(p.hem_height, 6.0, 6.0).clamp(30.0, 110.0);
    v.chest_half_width = draw(p.chest_half_width, 1.0, 2.5);
    v.hem_half_width = draw(p.hem_half_width, 1.0, 3.0).max(v.chest_half_width - 1.0);
    v.armhole_drop = draw(p.armhole_drop, 1.0, 1.0).max(0.0);
    v.shoulder_half_width = draw(p.shoulder_half_width, 1.0, 1.0);
    v.neck_half_width = draw(p.neck_half_width, 1.0, 1.0);
    v.front_neck_depth = draw(p.front_neck_depth, 2.5, 2.5).max(2.0);
    v.back_neck_depth = draw(p.back_neck_depth, 1.0, 1.0).max(1.0);
    if p.sleeve_length > 0.0 {
        v.sleeve_length = (p.sleeve_length * draw(1.0, 0.15, 0.15)).max(6.0);
        v.cuff_half_width = draw(p.cuff_half_width, 1.5, 1.5).max(8.0);
    }
    v
}

/// Wide variant `index` of `base`: whether it has sleeves is its base's; everything else is
/// drawn uniformly over the range the library's designs span (cm), the neckline type among
/// all three. Widths are drawn from the chest out, so the hem is never narrower than the
/// chest allows and a loose hem comes with a loose chest as often as with a tight one.
fn wide_draw(base: &Design, index: u32) -> DesignParams {
    let seed = name_seed(base.name) ^ ((index as u64) << 32) ^ 0x5749_4445; // "WIDE"
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut uniform = |low: f64, high: f64| rng.random_range(low..=high);
    let mut v = base.params;
    v.hem_height = uniform(40.0, 106.0);
    v.chest_half_width = uniform(24.5, 32.0);
    v.hem_half_width = uniform(
        v.chest_half_width - 1.0,
        (v.chest_half_width + 14.0).min(44.0),
    );
    v.armhole_drop = uniform(0.0, 4.0);
    v.shoulder_half_width = uniform(15.0, 20.0);
    neck_and_sleeves(&mut v, base, &mut uniform);
    v
}

/// The neckline and the sleeves drawn over the library's range (the last draws of a wide or
/// dress variant, in this order): neck width 10-14 cm, back depth 2.5-5, front depth 4-18, the
/// neckline type among all three, and for a sleeved base sleeve length 9-57 and cuff 9-19.
fn neck_and_sleeves(
    v: &mut DesignParams,
    base: &Design,
    uniform: &mut impl FnMut(f64, f64) -> f64,
) {
    v.neck_half_width = uniform(10.0, 14.0);
    v.back_neck_depth = uniform(2.5, 5.0);
    v.front_neck_depth = uniform(4.0, 18.0);
    v.neckline = match uniform(0.0, 3.0) {
        x if x < 1.0 => Neckline::Round,
        x if x < 2.0 => Neckline::V,
        _ => Neckline::Scoop,
    };
    if base.params.sleeve_length > 0.0 {
        v.sleeve_length = uniform(9.0, 57.0);
        v.cuff_half_width = uniform(9.0, 19.0);
    }
}

/// Dress variant `index` of `base`: whether it has sleeves is its base's; the hem drawn from
/// above the knee to the floor (the library's dresses end at 40-62 cm above the feet), the hem
/// from straight to flared (38-44 cm half-width in the library), the rest over the library's
/// range as in a wide variant.
fn dress_draw(base: &Design, index: u32) -> DesignParams {
    let seed = name_seed(base.name) ^ ((index as u64) << 32) ^ 0x4452_4553; // "DRES"
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut uniform = |low: f64, high: f64| rng.random_range(low..=high);
    let mut v = base.params;
    v.hem_height = uniform(32.0, 66.0);
    v.chest_half_width = uniform(25.5, 33.0);
    v.hem_half_width = uniform(v.chest_half_width + 2.0, v.chest_half_width + 20.0).min(50.0);
    v.armhole_drop = uniform(0.0, 4.5);
    v.shoulder_half_width = uniform(15.5, 19.5);
    neck_and_sleeves(&mut v, base, &mut uniform);
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_base_name_resolves_to_the_library_design() {
        let d = resolve("tshirt_regular").unwrap();
        assert_eq!((d.index, d.base.name), (0, "tshirt_regular"));
        assert_eq!(d.params, d.base.params);
        assert_eq!(d.pattern().unwrap(), d.base.pattern().unwrap());
    }

    #[test]
    fn variants_are_deterministic_distinct_and_stay_in_their_family() {
        for base in DESIGNS.iter() {
            let mut seen = vec![base.params];
            for k in 1..=4 {
                let name = format!("{}~{k}", base.name);
                let v = resolve(&name).unwrap();
                assert_eq!(v, resolve(&name).unwrap(), "{name}: not deterministic");
                assert!(!seen.contains(&v.params), "{name}: repeats a design");
                seen.push(v.params);
                let (p, b) = (v.params, base.params);
                assert_eq!(p.neckline, b.neckline, "{name}");
                assert_eq!(p.sleeve_length > 0.0, b.sleeve_length > 0.0, "{name}");
                assert!((p.hem_height - b.hem_height).abs() <= 6.0, "{name}");
                assert!(p.chest_half_width >= b.chest_half_width - 1.0, "{name}");
                if b.sleeve_length > 0.0 {
                    assert!((p.sleeve_length / b.sleeve_length - 1.0).abs() <= 0.15 + 1e-12);
                }
                let pattern = v.pattern().unwrap_or_else(|e| panic!("{name}: {e}"));
                assert_eq!(pattern.name, name);
            }
        }
    }

    /// Wide variants keep only whether their base has sleeves, stay in the library's range,
    /// sew, and over a few draws bring every neckline type to a design that had one.
    #[test]
    fn wide_variants_span_the_library_and_sew() {
        let mut necklines = Vec::new();
        for base in DESIGNS.iter().filter(|d| d.split == "train") {
            let name = variant_name(base.name, 1, VariantKind::Wide);
            assert_eq!(name, format!("{}~w1", base.name));
            let v = resolve(&name).unwrap();
            assert!(v.kind == VariantKind::Wide && v.index == 1, "{name}");
            assert_eq!(v, resolve(&name).unwrap(), "{name}: not deterministic");
            assert_ne!(
                v.params,
                resolve(&variant_name(base.name, 1, VariantKind::Near))
                    .unwrap()
                    .params
            );
            let (p, b) = (v.params, base.params);
            assert_eq!(p.sleeve_length > 0.0, b.sleeve_length > 0.0, "{name}");
            assert!((40.0..=106.0).contains(&p.hem_height), "{name}");
            assert!(p.hem_half_width >= p.chest_half_width - 1.0 && p.hem_half_width <= 44.0);
            if p.sleeve_length > 0.0 {
                assert!((9.0..=57.0).contains(&p.sleeve_length), "{name}");
            }
            necklines.push(p.neckline);
            let pattern = v.pattern().unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(pattern.name, name);
        }
        for line in [Neckline::Round, Neckline::V, Neckline::Scoop] {
            assert!(necklines.contains(&line), "no {line:?} in {necklines:?}");
        }
    }

    #[test]
    fn malformed_variant_names_resolve_to_nothing() {
        for bad in [
            "tshirt_regular~",
            "tshirt_regular~0",
            "tshirt_regular~01",
            "tshirt_regular~-1",
            "tshirt_regular~+1",
            "tshirt_regular~1.5",
            "tshirt_regular~10000",
            "tshirt_regular~1~2",
            "tshirt_regular~w",
            "tshirt_regular~w0",
            "tshirt_regular~ww1",
            "tshirt_regular~W1",
            "tshirt_regular~1w",
            "tshirt_regular~d",
            "tshirt_regular~d0",
            "tshirt_regular~dw1",
            "tshirt_regular~D1",
            "no_such_design~1",
            "~1",
        ] {
            assert!(resolve(bad).is_none(), "{bad}");
        }
        assert!(resolve("tshirt_regular~9999").is_some());
        assert!(resolve("tshirt_regular~w9999").is_some());
        assert!(resolve("tshirt_regular~d9999").is_some());
    }

    /// Dress variants are dresses with their base's sleeves, sew, and over a few draws reach
    /// past the library's dresses: a hem lower than its lowest and wider than its widest.
    #[test]
    fn dress_variants_are_dresses_that_span_the_library_dresses() {
        let (mut lowest, mut widest) = (f64::MAX, 0.0f64);
        for base in DESIGNS.iter().filter(|d| d.split == "train") {
            for k in 1..=3 {
                let name = variant_name(base.name, k, VariantKind::Dress);
                assert_eq!(name, format!("{}~d{k}", base.name));
                let v = resolve(&name).unwrap();
                assert_eq!(v.kind, VariantKind::Dress, "{name}");
                assert_eq!(v, resolve(&name).unwrap(), "{name}: not deterministic");
                let (p, b) = (v.params, base.params);
                assert_eq!(p.family(), super::super::Family::DressOrSkirt, "{name}");
                assert_eq!(p.sleeve_length > 0.0, b.sleeve_length > 0.0, "{name}");
                assert!(p.hem_half_width >= p.chest_half_width + 2.0, "{name}");
                lowest = lowest.min(p.hem_height);
                widest = widest.max(p.hem_half_width);
                let pattern = v.pattern().unwrap_or_else(|e| panic!("{name}: {e}"));
                assert_eq!(pattern.name, name);
            }
        }
        let maxi = super::super::find("dress_loose_maxi").unwrap().params;
        assert!(lowest < maxi.hem_height, "lowest hem {lowest}");
        assert!(widest > maxi.hem_half_width, "widest hem {widest}");
    }
}
