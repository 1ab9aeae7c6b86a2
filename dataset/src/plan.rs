//! From a spec to the list of sequences: stable keys, ids and seeds, sampled shapes and
//! materials, and the splits.
//!
//! Every random draw comes from a generator seeded by SHA-256 of the dataset seed and the
//! draw's key, so a sequence is the same whichever shard, order or re-run produces it.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::spec::{DatasetSpec, MAX_PLANNED_SEQUENCES, MaterialRanges, SplitSpec, Tag};
use super::split::Split;
use crate::error::{Error, Result};
use sim::Material;

/// One sequence to simulate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedSequence {
    /// Stable id (file name stem).
    pub id: String,
    /// The key its seeds derive from (absent in manifests written before it was recorded).
    #[serde(default)]
    pub key: String,
    /// The split.
    pub split: Split,
    /// Garment (as named in the spec).
    pub garment: String,
    /// Motion source (built-in with parameters, or AMASS file).
    pub motion: String,
    /// Shape coefficients.
    pub betas: Vec<f64>,
    /// Material.
    pub material: Material,
    /// Friction coefficient.
    pub friction: f64,
    /// The sequence's seed.
    pub seed: u64,
}

/// A 64-bit seed from the dataset seed and a key.
pub fn derive_seed(dataset_seed: u64, key: &str) -> u64 {
    let digest = Sha256::digest(format!("{dataset_seed}/{key}").as_bytes());
    u64::from_le_bytes(digest[..8].try_into().expect("8 bytes"))
}

fn rng(dataset_seed: u64, key: &str) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(derive_seed(dataset_seed, key))
}

fn uniform(rng: &mut ChaCha8Rng, r: [f64; 2]) -> f64 {
    if r[1] > r[0] {
        rng.random_range(r[0]..r[1])
    } else {
        r[0]
    }
}

fn material(rng: &mut ChaCha8Rng, m: &MaterialRanges) -> Material {
    Material {
        stretch: uniform(rng, m.k_s),
        density: uniform(rng, m.rho),
        bending: 10f64.powf(uniform(rng, m.log10_k_b)),
    }
}

fn betas(rng: &mut ChaCha8Rng, n: usize, r: [f64; 2]) -> Vec<f64> {
    (0..n).map(|_| uniform(rng, r)).collect()
}

/// A short, file-name-safe name for a motion or garment source.
fn slug(source: &str) -> String {
    let stem = std::path::Path::new(source.split(':').next().unwrap_or(source))
        .file_stem()
        .map_or(source.to_string(), |s| s.to_string_lossy().into_owned());
    let s: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .take(32)
        .collect();
    if s.is_empty() { "x".into() } else { s }
}

/// The motions of a spec with their tags: variants expanded, globs expanded (sorted).
pub fn expand_motions(spec: &DatasetSpec) -> Result<Vec<(String, Tag)>> {
    let mut out = Vec::new();
    for entry in &spec.motions {
        let is_glob = entry.source.contains(['*', '?', '[']);
        if is_glob {
            let paths = glob::glob(&entry.source).map_err(|e| Error::Spec {
                path: String::new(),
                message: format!("motions: bad glob '{}': {e}", entry.source),
            })?;
            let mut files: Vec<String> = paths
                .filter_map(|p| p.ok())
                .map(|p| p.display().to_string())
                .collect();
            files.sort();
            if files.is_empty() {
                return Err(Error::Spec {
                    path: String::new(),
                    message: format!("motions: glob '{}' matches no file", entry.source),
                });
            }
            out.extend(files.into_iter().map(|f| (f, entry.split)));
        } else if entry.variants.is_empty() {
            out.push((entry.source.clone(), entry.split));
        } else {
            for v in &entry.variants {
                out.push((format!("{}:{v}", entry.source), entry.split));
            }
        }
    }
    // Two spellings of one motion (`walk` and `walk:speed=1`, `random:seed=01`, `./a.bvh`) are
    // one motion: listed twice it is refused, and in train and test it would be a leak.
    let mut seen: std::collections::HashMap<String, &(String, Tag)> = Default::default();
    for entry in &out {
        let (text, tag) = entry;
        let identity =
            motions::MotionSource::parse(text).map_or_else(|_| text.clone(), |m| m.identity());
        if let Some((first, first_tag)) = seen.insert(identity.clone(), entry) {
            let message = if first_tag == tag {
                format!(
                    "motions: '{first}' and '{text}' are the same motion ({identity}), listed twice"
                )
            } else {
                format!(
                    "motions: '{first}' ({}) and '{text}' ({}) are the same motion ({identity}): \
                     a train/test leak",
                    first_tag.name(),
                    tag.name()
                )
            };
            return Err(Error::Spec {
                path: String::new(),
                message,
            });
        }
    }
    Ok(out)
}

/// Every sequence of the dataset, training first, then the test sets, then the test grid.
///
/// A plan of more than [`MAX_PLANNED_SEQUENCES`] sequences is refused before it is built.
pub fn plan(spec: &DatasetSpec, motions: &[(String, Tag)]) -> Result<Vec<PlannedSequence>> {
    check_size(spec, motions)?;
    let planner = Planner::new(spec, motions);
    let mut out = planner.training();
    for set in HeldOut::sets(&spec.splits) {
        out.extend(planner.held_out(set));
    }
    out.extend(planner.test_grid());
    Ok(out)
}

/// Refuses a plan of more than [`MAX_PLANNED_SEQUENCES`] sequences, counted without
/// overflow before any is made.
fn check_size(spec: &DatasetSpec, motions: &[(String, Tag)]) -> Result<()> {
    let s = &spec.sequence;
    let sp = &spec.splits;
    let train_motions = motions.iter().filter(|m| m.1 == Tag::Train).count();
    let test_garments: usize = spec
        .garments
        .iter()
        .filter(|g| g.split == Tag::Test)
        .map(|g| g.names().count())
        .sum();
    let test_motions = motions.iter().filter(|m| m.1 == Tag::Test).count();
    let grid = test_garments
        .checked_mul(test_motions)
        .and_then(|n| n.checked_mul(sp.test_grid_shapes));
    let count = [
        sp.test,
        sp.test_garment,
        sp.test_motion,
        sp.test_shape,
        sp.test_material,
    ]
    .into_iter()
    .fold(
        train_motions
            .checked_mul(s.shapes_per_motion)
            .and_then(|n| n.checked_mul(s.draws_per_shape)),
        |total, n| total.and_then(|t| t.checked_add(n)),
    )
    .and_then(|t| grid.and_then(|g| t.checked_add(g)))
    .filter(|&n| n <= MAX_PLANNED_SEQUENCES);
    if count.is_none() {
        return Err(Error::value(
            "plan",
            format!(
                "{train_motions} training motions x {} shapes x {} draws + the test splits",
                s.shapes_per_motion, s.draws_per_shape
            ),
            &format!("must hold at most {MAX_PLANNED_SEQUENCES} sequences"),
        ));
    }
    Ok(())
}

/// A random test set: how many sequences, where its garment and motion come from, and
/// whether its shape and material are drawn from the held-out ranges.
#[derive(Debug, Clone, Copy)]
struct HeldOut {
    split: Split,
    count: usize,
    garments: Tag,
    motions: Tag,
    new_shape: bool,
    new_material: bool,
}

impl HeldOut {
    /// The random test sets, each drawing its unseen factors from the held-out tags or
    /// ranges, in the plan's order.
    fn sets(sp: &SplitSpec) -> [HeldOut; 5] {
        let set = |split, count, garments, motions, new_shape, new_material| HeldOut {
            split,
            count,
            garments,
            motions,
            new_shape,
            new_material,
        };
        [
            set(Split::Test, sp.test, Tag::Test, Tag::Test, true, true),
            set(
                Split::TestGarment,
                sp.test_garment,
                Tag::Test,
                Tag::Train,
                false,
                false,
            ),
            set(
                Split::TestMotion,
                sp.test_motion,
                Tag::Train,
                Tag::Test,
                false,
                false,
            ),
            set(
                Split::TestShape,
                sp.test_shape,
                Tag::Train,
                Tag::Train,
                true,
                false,
            ),
            set(
                Split::TestMaterial,
                sp.test_material,
                Tag::Train,
                Tag::Train,
                false,
                true,
            ),
        ]
    }
}

/// What every stage of a plan draws from: the spec, its garment names (variants expanded)
/// and motions with their tags, and the held-out ranges.
struct Planner<'a> {
    spec: &'a DatasetSpec,
    garments: Vec<(String, Tag)>,
    motions: &'a [(String, Tag)],
    test_betas: [f64; 2],
    test_material: MaterialRanges,
}

impl<'a> Planner<'a> {
    fn new(spec: &'a DatasetSpec, motions: &'a [(String, Tag)]) -> Self {
        Self {
            spec,
            garments: spec
                .garments
                .iter()
                .flat_map(|g| g.names().map(move |name| (name, g.split)))
                .collect(),
            motions,
            test_betas: spec
                .splits
                .test_betas_range
                .unwrap_or(spec.sequence.betas_range),
            test_material: spec.splits.test_material_ranges.unwrap_or(spec.material),
        }
    }

    fn garments(&self, tag: Tag) -> Vec<&String> {
        self.garments
            .iter()
            .filter(|g| g.1 == tag)
            .map(|g| &g.0)
            .collect()
    }

    fn motions(&self, tag: Tag) -> Vec<&String> {
        self.motions
            .iter()
            .filter(|m| m.1 == tag)
            .map(|m| &m.0)
            .collect()
    }

    /// One sequence, its seed derived from its key.
    fn sequence(
        &self,
        split: Split,
        key: String,
        name: String,
        (garment, motion): (String, String),
        betas: Vec<f64>,
        material: Material,
    ) -> PlannedSequence {
        let seed = derive_seed(self.spec.seed, &key);
        PlannedSequence {
            id: format!("{split}-{name}-{:08x}", seed as u32),
            key,
            split,
            garment,
            motion,
            betas,
            material,
            friction: self.spec.sequence.friction,
            seed,
        }
    }

    /// Training: every training motion x shapes x draws (garment + material per draw).
    fn training(&self) -> Vec<PlannedSequence> {
        let (spec, s) = (self.spec, &self.spec.sequence);
        let garments = self.garments(Tag::Train);
        let mut out = Vec::new();
        for motion in self.motions(Tag::Train) {
            for shape in 0..s.shapes_per_motion {
                let shape_key = format!("train/{motion}/shape{shape}");
                let b = betas(&mut rng(spec.seed, &shape_key), s.betas, s.betas_range);
                for draw in 0..s.draws_per_shape {
                    let key = format!("{shape_key}/draw{draw}");
                    let mut r = rng(spec.seed, &key);
                    let garment = pick(&garments, &mut r);
                    let m = material(&mut r, &spec.material);
                    let name = format!("{}-s{shape}d{draw}", slug(motion));
                    let pair = (garment, motion.clone());
                    out.push(self.sequence(Split::Train, key, name, pair, b.clone(), m));
                }
            }
        }
        out
    }

    /// A random test set's sequences.
    fn held_out(&self, set: HeldOut) -> Vec<PlannedSequence> {
        let (spec, s) = (self.spec, &self.spec.sequence);
        let (garments, motions) = (self.garments(set.garments), self.motions(set.motions));
        (0..set.count)
            .map(|i| {
                let key = format!("{}/{i}", set.split);
                let mut r = rng(spec.seed, &key);
                let garment = pick(&garments, &mut r);
                let motion = pick(&motions, &mut r);
                let range = if set.new_shape {
                    self.test_betas
                } else {
                    s.betas_range
                };
                let b = betas(&mut r, s.betas, range);
                let ranges = if set.new_material {
                    &self.test_material
                } else {
                    &spec.material
                };
                let m = material(&mut r, ranges);
                let name = format!("{}-{i}", slug(&motion));
                self.sequence(set.split, key, name, (garment, motion), b, m)
            })
            .collect()
    }

    /// The test grid: every held-out garment x every held-out motion x its shapes.
    fn test_grid(&self) -> Vec<PlannedSequence> {
        let (spec, s) = (self.spec, &self.spec.sequence);
        let mut out = Vec::new();
        for garment in self.garments(Tag::Test) {
            for motion in self.motions(Tag::Test) {
                for shape in 0..spec.splits.test_grid_shapes {
                    let key = format!("test_grid/{garment}/{motion}/shape{shape}");
                    let mut r = rng(spec.seed, &key);
                    let b = betas(&mut r, s.betas, self.test_betas);
                    let m = material(&mut r, &self.test_material);
                    let name = format!("{}-{}-s{shape}", slug(garment), slug(motion));
                    let pair = (garment.clone(), motion.clone());
                    out.push(self.sequence(Split::TestGrid, key, name, pair, b, m));
                }
            }
        }
        out
    }
}

/// One of `list`, uniformly.
fn pick(list: &[&String], rng: &mut ChaCha8Rng) -> String {
    list[rng.random_range(0..list.len())].clone()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::{GarmentEntry, MotionEntry, SplitSpec};

    fn spec() -> DatasetSpec {
        let g = |name: &str, split| GarmentEntry {
            name: name.into(),
            split,
            variants: 0,
            wide_variants: 0,
            dress_variants: 0,
        };
        let m = |source: &str, split| MotionEntry {
            source: source.into(),
            variants: vec![],
            split,
        };
        DatasetSpec {
            name: "t".into(),
            seed: 7,
            sequence: Default::default(),
            material: Default::default(),
            solver: Default::default(),
            gates: Default::default(),
            garments: vec![g("a", Tag::Train), g("b", Tag::Train), g("c", Tag::Test)],
            motions: vec![
                m("walk", Tag::Train),
                m("run", Tag::Train),
                m("kick", Tag::Test),
            ],
            splits: SplitSpec {
                test: 2,
                test_garment: 1,
                test_motion: 1,
                test_shape: 1,
                test_material: 1,
                test_grid_shapes: 0,
                test_betas_range: Some([1.5, 2.0]),
                test_material_ranges: None,
            },
        }
    }

    #[test]
    fn a_test_grid_covers_every_held_out_garment_motion_and_shape() {
        let mut spec = spec();
        spec.garments.push(GarmentEntry {
            name: "d".into(),
            split: Tag::Test,
            variants: 0,
            wide_variants: 0,
            dress_variants: 0,
        });
        spec.motions.push(MotionEntry {
            source: "sway".into(),
            variants: vec![],
            split: Tag::Test,
        });
        spec.splits = SplitSpec {
            test_grid_shapes: 2,
            test_betas_range: Some([1.5, 2.0]),
            ..Default::default()
        };
        let planned = plan(&spec, &expand_motions(&spec).unwrap()).unwrap();
        let grid: Vec<_> = planned
            .iter()
            .filter(|p| p.split == Split::TestGrid)
            .collect();
        assert_eq!(grid.len(), 2 * 2 * 2);
        for garment in ["c", "d"] {
            for motion in ["kick", "sway"] {
                let cells: Vec<_> = grid
                    .iter()
                    .filter(|p| p.garment == garment && p.motion == motion)
                    .collect();
                assert_eq!(cells.len(), 2, "{garment} x {motion}");
                assert_ne!(cells[0].betas, cells[1].betas, "two shapes");
                assert!(cells.iter().all(|p| p.betas.iter().all(|b| *b >= 1.5)));
            }
        }
        // A grid alone needs no training entries.
        spec.garments.retain(|g| g.split == Tag::Test);
        spec.motions.retain(|m| m.split == Tag::Test);
        let text = toml::to_string(&spec).unwrap();
        let alone = DatasetSpec::parse(&text, std::path::Path::new("grid.toml")).unwrap();
        let planned = plan(&alone, &expand_motions(&alone).unwrap()).unwrap();
        assert_eq!(planned.len(), 8);
        spec.splits.test_grid_shapes = 0;
        let text = toml::to_string(&spec).unwrap();
        let err = DatasetSpec::parse(&text, std::path::Path::new("grid.toml")).unwrap_err();
        assert!(
            matches!(&err, crate::Error::Spec { path, message } if path == "grid.toml" && message.contains("split = \"train\"")),
            "{err}"
        );
    }

    #[test]
    fn plan_is_reproducible_and_splits_keep_unseen_factors_out_of_training() {
        let spec = spec();
        let motions = expand_motions(&spec).unwrap();
        let a = plan(&spec, &motions).unwrap();
        assert_eq!(a, plan(&spec, &motions).unwrap(), "same spec, same plan");
        assert_eq!(
            a.iter().filter(|p| p.split == Split::Train).count(),
            2 * 3 * 3
        );
        assert_eq!(a.len(), 18 + 2 + 1 + 1 + 1 + 1);
        let ids: std::collections::HashSet<_> = a.iter().map(|p| &p.id).collect();
        assert_eq!(ids.len(), a.len(), "ids are unique");
        for p in &a {
            match p.split.name() {
                "train" => assert!(p.garment != "c" && p.motion != "kick"),
                "test" => assert!(p.garment == "c" && p.motion == "kick"),
                "test_garment" => assert!(p.garment == "c" && p.motion != "kick"),
                "test_motion" => assert!(p.garment != "c" && p.motion == "kick"),
                "test_shape" => assert!(p.betas.iter().all(|b| *b >= 1.5)),
                _ => {}
            }
            assert!((40.0..=200.0).contains(&p.material.stretch));
            assert!((1e-8..=1e-4).contains(&p.material.bending));
            assert_eq!(p.betas.len(), 10);
        }
        // Draws of one shape share the betas; another seed changes everything.
        assert_eq!(a[0].betas, a[1].betas);
        assert_ne!(a[0].betas, a[3].betas);
        let mut other = spec.clone();
        other.seed = 8;
        assert_ne!(plan(&other, &motions).unwrap()[0].betas, a[0].betas);
        // Adding a motion does not change the existing sequences.
        let mut more = spec.clone();
        more.motions.push(MotionEntry {
            source: "squat".into(),
            variants: vec![],
            split: Tag::Train,
        });
        let b = plan(&more, &expand_motions(&more).unwrap()).unwrap();
        for p in a.iter().filter(|p| p.split == Split::Train) {
            assert!(b.contains(p), "{} changed", p.id);
        }
    }

    #[test]
    fn garment_variants_are_drawn_with_their_entry_split() {
        let mut spec = spec();
        spec.garments[0].variants = 3;
        spec.garments[0].wide_variants = 2;
        let names: Vec<String> = spec.garments[0].names().collect();
        assert_eq!(names, ["a", "a~1", "a~2", "a~3", "a~w1", "a~w2"]);
        let planned = plan(&spec, &expand_motions(&spec).unwrap()).unwrap();
        let train: std::collections::BTreeSet<&str> = planned
            .iter()
            .filter(|p| p.split == Split::Train)
            .map(|p| p.garment.as_str())
            .collect();
        assert!(train.iter().any(|g| g.starts_with("a~")), "{train:?}");
        let allowed = ["a", "a~1", "a~2", "a~3", "a~w1", "a~w2", "b"];
        assert!(train.iter().all(|g| allowed.contains(g)), "{train:?}");
        for p in planned.iter().filter(|p| p.split == Split::Test) {
            assert_eq!(p.garment, "c");
        }
    }

    #[test]
    fn variants_expand_and_duplicates_are_refused() {
        let mut spec = spec();
        spec.motions[0].variants = vec!["speed=0.8".into(), "speed=1.2".into()];
        let m = expand_motions(&spec).unwrap();
        assert_eq!(m[0].0, "walk:speed=0.8");
        assert_eq!(m.len(), 4);
        spec.motions.push(spec.motions[1].clone());
        assert!(expand_motions(&spec).is_err());
        // Two spellings of one motion: twice on one side, or a leak across the split.
        let mut spec = self::spec();
        spec.motions.push(MotionEntry {
            source: "run:speed=1".into(),
            variants: vec![],
            split: Tag::Train,
        });
        let e = expand_motions(&spec).unwrap_err().to_string();
        assert!(
            e.contains("'run' and 'run:speed=1' are the same motion (run), listed twice"),
            "{e}"
        );
        spec.motions.pop();
        spec.motions.push(MotionEntry {
            source: "walk".into(),
            variants: vec!["amplitude=1".into()],
            split: Tag::Test,
        });
        let e = expand_motions(&spec).unwrap_err().to_string();
        assert!(
            e.contains("'walk' (train) and 'walk:amplitude=1' (test) are the same motion (walk): a train/test leak"),
            "{e}"
        );
        spec.motions.pop();
        spec.motions.push(MotionEntry {
            source: "random".into(),
            variants: vec!["seed=1".into(), "seed=01".into()],
            split: Tag::Test,
        });
        let e = expand_motions(&spec).unwrap_err().to_string();
        assert!(e.contains("(random:seed=1)"), "{e}");
    }
}
