//! The dataset specification (TOML): what to simulate, how to sample it, and the gates.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A dataset: the garments and motions with their split tags, how many shapes and draws, the
/// material ranges, solver settings, quality gates and the one-factor test sets.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetSpec {
    /// Dataset name (recorded in the manifest).
    pub name: String,
    /// Every sequence's seed derives from this and the sequence's key.
    pub seed: u64,
    /// Sequence length and sampling counts.
    #[serde(default)]
    pub sequence: SequenceSpec,
    /// Material ranges (uniform; bending log-uniform).
    #[serde(default)]
    pub material: MaterialRanges,
    /// Solver settings.
    #[serde(default)]
    pub solver: SolverSpec,
    /// Per-sequence quality gates and retries.
    #[serde(default)]
    pub gates: GateSpec,
    /// Garments: library names, built-ins or template OBJ files, each with a split.
    pub garments: Vec<GarmentEntry>,
    /// Motions: built-in names (with parameter variants) or AMASS files and globs.
    pub motions: Vec<MotionEntry>,
    /// Sizes of the test sets.
    #[serde(default)]
    pub splits: SplitSpec,
}

/// Which side of the split a garment or motion is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tag {
    /// Seen in training.
    Train,
    /// Held out for testing.
    Test,
}

impl Tag {
    /// The tag as written in specs: `train` or `test`.
    pub fn name(self) -> &'static str {
        match self {
            Tag::Train => "train",
            Tag::Test => "test",
        }
    }
}

/// Sequence length and sampling counts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SequenceSpec {
    /// Output frames per sequence at 30 fps, blend-in and settle included (default: the whole
    /// motion after them).
    pub frames: Option<usize>,
    /// Frames blending from the canonical pose and shape into the motion.
    pub blend_frames: usize,
    /// Frames holding the motion's first frame.
    pub settle_frames: usize,
    /// Body shapes drawn per training motion.
    pub shapes_per_motion: usize,
    /// Garment + material draws per shape.
    pub draws_per_shape: usize,
    /// Shape coefficients drawn per body.
    pub betas: usize,
    /// Each coefficient ~ U(min, max).
    pub betas_range: [f64; 2],
    /// Cloth-body friction coefficient.
    pub friction: f64,
}

impl Default for SequenceSpec {
    fn default() -> Self {
        Self {
            frames: None,
            blend_frames: 30,
            settle_frames: 30,
            shapes_per_motion: 3,
            draws_per_shape: 3,
            betas: 10,
            betas_range: [-1.0, 1.0],
            friction: 0.3,
        }
    }
}

/// Material ranges.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialRanges {
    /// Stretch stiffness k_s ~ U(min, max), N/m.
    pub k_s: [f64; 2],
    /// Area density rho ~ U(min, max), kg/m^2.
    pub rho: [f64; 2],
    /// log10 of the bending stiffness k_b (N m) ~ U(min, max).
    pub log10_k_b: [f64; 2],
}

impl Default for MaterialRanges {
    fn default() -> Self {
        Self {
            k_s: [40.0, 200.0],
            rho: [0.01, 0.7],
            log10_k_b: [-8.0, -4.0],
        }
    }
}

/// The most shapes per motion, and draws per shape, a spec may ask for.
pub const MAX_DRAWS: usize = 1_000;
/// The most sequences a plan may hold (a plan entry is about 400 bytes; a million sequences
/// is five times the paper's dataset).
pub const MAX_PLANNED_SEQUENCES: usize = 1_000_000;
/// The most retries per sequence.
pub const MAX_RETRIES: usize = 8;
/// The longest time limit of one attempt, s (a week).
pub const MAX_TIMEOUT_S: f64 = 604_800.0;

/// Solver settings of every sequence: the keys of a scene configuration's `[solver]` table
/// (docs/DATASETS.md has the mapping).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSpec {
    /// Substeps per 30 fps frame.
    pub substeps: usize,
    /// Maximum iterations per substep (`iterations` in specs written before the scene
    /// configuration).
    #[serde(alias = "iterations")]
    pub max_iterations: usize,
    /// Cloth-cloth contact.
    pub self_contact: bool,
    /// Gap self-contact keeps between layers, m.
    pub self_contact_distance: f64,
    /// Coulomb friction coefficient between layers.
    pub self_friction: f64,
    /// Anderson acceleration depth (0 = off, the default).
    pub acceleration: usize,
    /// The most the penetration may deepen in one frame before the frame is run again with
    /// twice the substeps, m (0 = off).
    pub max_penetration_jump: f64,
}

impl Default for SolverSpec {
    fn default() -> Self {
        let plain = sim::SolverParams::default();
        Self {
            substeps: 4,
            max_iterations: 16,
            self_contact: true,
            self_contact_distance: plain.self_contact_distance,
            self_friction: plain.self_friction,
            acceleration: sim::config::garment_solver().acceleration,
            max_penetration_jump: plain.max_penetration_jump,
        }
    }
}

/// Quality gates on each sequence's statistics, and what a failure gets.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GateSpec {
    /// Deepest garment vertex inside the body over all frames, m.
    pub max_penetration_m: f64,
    /// Most garment vertices inside the body in any frame, as a fraction of the vertices.
    pub max_inside_fraction: f64,
    /// Largest edge length / rest length.
    pub max_edge_stretch: f64,
    /// Most crossing garment triangle pairs in one frame (GarmentCode rejects drapes with
    /// more than 300 self-intersections; so do we, per frame).
    pub max_self_intersections: usize,
    /// Wall-clock limit per attempt, s.
    pub timeout_s: f64,
    /// Attempts after a failed one, each with the retry solver settings.
    pub retries: usize,
    /// Substeps of a retry.
    pub retry_substeps: usize,
    /// Iterations of a retry.
    pub retry_iterations: usize,
}

impl Default for GateSpec {
    fn default() -> Self {
        Self {
            max_penetration_m: 0.02,
            max_inside_fraction: 0.05,
            max_edge_stretch: 1.5,
            max_self_intersections: sim::sewing::MAX_SELF_INTERSECTIONS,
            timeout_s: 900.0,
            retries: 1,
            retry_substeps: 8,
            retry_iterations: 16,
        }
    }
}

/// A garment of the dataset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GarmentEntry {
    /// Library design, built-in garment, or template OBJ file.
    pub name: String,
    /// Split tag.
    pub split: Tag,
    /// Variants of a library design joined to the list (`name~1` ..= `name~N`, each its own
    /// design with this split: `garments::library::resolve`); 0, the design alone.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub variants: u32,
    /// Wide variants joined after them (`name~w1` ..= `name~wN`: designs of other kinds drawn
    /// over the library's range, keeping only whether the design has sleeves); 0, none.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub wide_variants: u32,
    /// Dress variants joined after those (`name~d1` ..= `name~dN`: dresses drawn from above
    /// the knee to the floor and from straight to flared, with the design's sleeves); 0, none.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub dress_variants: u32,
}

fn is_zero(n: &u32) -> bool {
    *n == 0
}

impl GarmentEntry {
    /// The garment's names: the entry's, then its variants', wide variants' and dress
    /// variants'.
    pub fn names(&self) -> impl Iterator<Item = String> + '_ {
        use garments::library::VariantKind;
        let variant = |kind| move |k| garments::library::variant_name(&self.name, k, kind);
        std::iter::once(self.name.clone())
            .chain((1..=self.variants).map(variant(VariantKind::Near)))
            .chain((1..=self.wide_variants).map(variant(VariantKind::Wide)))
            .chain((1..=self.dress_variants).map(variant(VariantKind::Dress)))
    }
}

/// A motion source of the dataset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionEntry {
    /// Built-in name (optionally `name:speed=..,...`), AMASS .npz file, or a glob of them.
    pub source: String,
    /// Parameter variants of a built-in motion (`speed=1.2,amplitude=0.8`), each its own
    /// motion; none: the source as written.
    #[serde(default)]
    pub variants: Vec<String>,
    /// Split tag.
    pub split: Tag,
}

/// Sizes of the test sets (sequences each).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SplitSpec {
    /// Unseen garments x unseen motions x unseen shapes (and new materials).
    pub test: usize,
    /// Only the garment unseen.
    pub test_garment: usize,
    /// Only the motion unseen.
    pub test_motion: usize,
    /// Only the shape unseen (drawn from `test_betas_range`).
    pub test_shape: usize,
    /// Only the material unseen (drawn from `test_material`).
    pub test_material: usize,
    /// The test grid: every test garment x every test motion x this many shapes (from
    /// `test_betas_range`), materials from `test_material_ranges` (split `test_grid`).
    pub test_grid_shapes: usize,
    /// Shapes of the shape-unseen and all-unseen sets (default: the training range).
    pub test_betas_range: Option<[f64; 2]>,
    /// Materials of the material-unseen and all-unseen sets (default: the training ranges).
    pub test_material_ranges: Option<MaterialRanges>,
}

/// `r` is a range `[lo', hi']` of finite numbers within `[lo, hi]`, else an error naming `key`.
fn check_range(key: &str, r: [f64; 2], lo: f64, hi: f64) -> std::result::Result<(), String> {
    if !(r[0].is_finite() && r[1].is_finite() && lo <= r[0] && r[0] <= r[1] && r[1] <= hi) {
        Err(format!(
            "{key} = [{}, {}] must be a range within [{lo}, {hi}]",
            r[0], r[1]
        ))
    } else {
        Ok(())
    }
}

impl DatasetSpec {
    /// Parses and checks a spec; errors name the file and the key at fault.
    pub fn parse(text: &str, origin: &Path) -> Result<Self> {
        let spec: DatasetSpec = toml::from_str(text).map_err(|e| Error::Spec {
            path: origin.display().to_string(),
            message: e.to_string(),
        })?;
        spec.validate().map_err(|message| Error::Spec {
            path: origin.display().to_string(),
            message,
        })?;
        Ok(spec)
    }

    /// Reads and checks a spec file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = files::read_to_string(path, files::limits::TEXT, "dataset spec")?;
        Self::parse(&text, path)
    }

    /// The spec as TOML (the copy stored with a dataset).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// Checks every key, naming the first bad one: the stages below, in order.
    fn validate(&self) -> std::result::Result<(), String> {
        self.check_lists()?;
        self.check_sequence()?;
        self.check_split_sizes()?;
        self.check_gate_limits()?;
        self.check_ranges()?;
        self.check_solver_and_gates()?;
        self.check_variants()?;
        self.check_split_tags()
    }

    /// A name, and at least one garment and one motion.
    fn check_lists(&self) -> std::result::Result<(), String> {
        if self.name.trim().is_empty() {
            return Err("name must not be empty".into());
        }
        if self.garments.is_empty() || self.motions.is_empty() {
            return Err("garments and motions must each list at least one entry".into());
        }
        Ok(())
    }

    /// The sequence's frame counts and draws, within their bounds.
    fn check_sequence(&self) -> std::result::Result<(), String> {
        let s = &self.sequence;
        if s.frames == Some(0) {
            return Err("sequence.frames must be at least 1".into());
        }
        for (key, n) in [
            ("sequence.shapes_per_motion", s.shapes_per_motion),
            ("sequence.draws_per_shape", s.draws_per_shape),
        ] {
            if !(1..=MAX_DRAWS).contains(&n) {
                return Err(format!("{key} = {n} is outside 1..={MAX_DRAWS}"));
            }
        }
        if let Some(n) = s.frames.filter(|&n| n > sim::config::MAX_FRAMES) {
            return Err(format!(
                "sequence.frames = {n} is more than {}",
                sim::config::MAX_FRAMES
            ));
        }
        for (key, n) in [
            ("sequence.blend_frames", s.blend_frames),
            ("sequence.settle_frames", s.settle_frames),
        ] {
            if n > sim::config::MAX_PREFIX_FRAMES {
                return Err(format!(
                    "{key} = {n} is more than {} (an hour at 30 fps)",
                    sim::config::MAX_PREFIX_FRAMES
                ));
            }
        }
        Ok(())
    }

    /// No held-out set larger than a plan may be.
    fn check_split_sizes(&self) -> std::result::Result<(), String> {
        let sp = &self.splits;
        for (key, n) in [
            ("splits.test", sp.test),
            ("splits.test_garment", sp.test_garment),
            ("splits.test_motion", sp.test_motion),
            ("splits.test_shape", sp.test_shape),
            ("splits.test_material", sp.test_material),
            ("splits.test_grid_shapes", sp.test_grid_shapes),
        ] {
            if n > MAX_PLANNED_SEQUENCES {
                return Err(format!("{key} = {n} is more than {MAX_PLANNED_SEQUENCES}"));
            }
        }
        Ok(())
    }

    /// The time-out and retries, within their bounds.
    fn check_gate_limits(&self) -> std::result::Result<(), String> {
        if self.gates.timeout_s > MAX_TIMEOUT_S {
            return Err(format!(
                "gates.timeout_s = {} is more than {MAX_TIMEOUT_S} s (a week)",
                self.gates.timeout_s
            ));
        }
        if self.gates.retries > MAX_RETRIES {
            return Err(format!(
                "gates.retries = {} is more than {MAX_RETRIES}",
                self.gates.retries
            ));
        }
        Ok(())
    }

    /// Shapes, friction and material ranges, within the engine's bounds.
    fn check_ranges(&self) -> std::result::Result<(), String> {
        let s = &self.sequence;
        if s.betas > 300 {
            return Err(format!("sequence.betas = {} is more than 300", s.betas));
        }
        check_range("sequence.betas_range", s.betas_range, -5.0, 5.0)?;
        if !(0.0..=2.0).contains(&s.friction) {
            return Err(format!(
                "sequence.friction = {} is outside [0, 2]",
                s.friction
            ));
        }
        let materials = |prefix: &str, m: &MaterialRanges| {
            check_range(&format!("{prefix}.k_s"), m.k_s, 1.0, 1e5)?;
            check_range(&format!("{prefix}.rho"), m.rho, 1e-3, 10.0)?;
            check_range(&format!("{prefix}.log10_k_b"), m.log10_k_b, -12.0, -1.0)
        };
        materials("material", &self.material)?;
        if let Some(m) = &self.splits.test_material_ranges {
            materials("splits.test_material_ranges", m)?;
        }
        if let Some(r) = self.splits.test_betas_range {
            check_range("splits.test_betas_range", r, -5.0, 5.0)?;
        }
        Ok(())
    }

    /// The solver settings and the gate thresholds.
    fn check_solver_and_gates(&self) -> std::result::Result<(), String> {
        let v = &self.solver;
        let g = &self.gates;
        for (key, n) in [
            ("solver.substeps", v.substeps),
            ("solver.max_iterations", v.max_iterations),
            ("gates.retry_substeps", g.retry_substeps),
            ("gates.retry_iterations", g.retry_iterations),
        ] {
            if !(1..=200).contains(&n) {
                return Err(format!("{key} = {n} is outside 1..=200"));
            }
        }
        if !(v.self_contact_distance > 0.0 && v.self_contact_distance <= 0.05) {
            return Err(format!(
                "solver.self_contact_distance = {} m is outside (0, 0.05]",
                v.self_contact_distance
            ));
        }
        if !(0.0..=2.0).contains(&v.self_friction) {
            return Err(format!(
                "solver.self_friction = {} is outside [0, 2]",
                v.self_friction
            ));
        }
        if !(v.max_penetration_jump.is_finite() && v.max_penetration_jump >= 0.0) {
            return Err(format!(
                "solver.max_penetration_jump = {} m must be finite and non-negative",
                v.max_penetration_jump
            ));
        }
        for (key, x) in [
            ("gates.max_penetration_m", g.max_penetration_m),
            ("gates.max_inside_fraction", g.max_inside_fraction),
            ("gates.max_edge_stretch", g.max_edge_stretch),
            ("gates.timeout_s", g.timeout_s),
        ] {
            if !(x.is_finite() && x > 0.0) {
                return Err(format!("{key} = {x} must be a positive number"));
            }
        }
        Ok(())
    }

    /// Variants only of library designs, and not too many.
    fn check_variants(&self) -> std::result::Result<(), String> {
        for g in &self.garments {
            for (key, n) in [
                ("variants", g.variants),
                ("wide_variants", g.wide_variants),
                ("dress_variants", g.dress_variants),
            ] {
                if n == 0 {
                    continue;
                }
                if garments::library::find(&g.name).is_none() {
                    return Err(format!(
                        "garments: '{}' has {key} = {n}, but only a library design has variants",
                        g.name
                    ));
                }
                if n > garments::library::MAX_INDEX {
                    return Err(format!(
                        "garments: '{}' has {key} = {n} (at most {})",
                        g.name,
                        garments::library::MAX_INDEX
                    ));
                }
            }
        }
        Ok(())
    }

    /// Every held-out set has the garments and motions it draws from, and (but for a test grid alone) something to train on.
    fn check_split_tags(&self) -> std::result::Result<(), String> {
        let has = |tag: Tag| self.garments.iter().any(|e| e.split == tag);
        let has_motion = |tag: Tag| self.motions.iter().any(|e| e.split == tag);
        let sp = &self.splits;
        let needs = [
            (
                "splits.test",
                sp.test,
                has(Tag::Test) && has_motion(Tag::Test),
            ),
            (
                "splits.test_garment",
                sp.test_garment,
                has(Tag::Test) && has_motion(Tag::Train),
            ),
            (
                "splits.test_motion",
                sp.test_motion,
                has(Tag::Train) && has_motion(Tag::Test),
            ),
            (
                "splits.test_shape",
                sp.test_shape,
                has(Tag::Train) && has_motion(Tag::Train),
            ),
            (
                "splits.test_material",
                sp.test_material,
                has(Tag::Train) && has_motion(Tag::Train),
            ),
            (
                "splits.test_grid_shapes",
                sp.test_grid_shapes,
                has(Tag::Test) && has_motion(Tag::Test),
            ),
        ];
        for (key, n, ok) in needs {
            if n > 0 && !ok {
                return Err(format!(
                    "{key} = {n} needs garments and motions with the split tags it draws from"
                ));
            }
        }
        // A test grid alone (a validation or test set) needs no training entries; anything
        // else draws from them.
        let grid_only = sp.test_grid_shapes > 0 && !has(Tag::Train) && !has_motion(Tag::Train);
        if !grid_only && (!has(Tag::Train) || !has_motion(Tag::Train)) {
            return Err(
                "at least one garment and one motion must have split = \"train\" \
                        (or, for a test grid alone, none)"
                    .into(),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_spec_in_the_specs_folder_parses() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../specs");
        let mut count = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                DatasetSpec::load(&path).unwrap_or_else(|e| panic!("{e}"));
                count += 1;
            }
        }
        assert!(count >= 10, "{count} specs");
    }

    /// Issue 53's protocol: no training spec (`specs/train*.toml`) trains on a design or a
    /// motion of a test split (by name: a capture clip by its file, whatever stretch), nor on
    /// the validation sets' (`validation.toml`, `validation_wide.toml`; a capture by the
    /// seconds of its stretch: other seconds of its clip may train).
    #[test]
    fn no_training_spec_trains_on_what_validation_or_a_test_split_holds() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../specs");
        let load = |name: &str| DatasetSpec::load(&dir.join(name)).unwrap();
        let design = |name: &str| name.split('~').next().unwrap_or(name).to_string();
        let mut designs = std::collections::HashSet::<String>::new();
        let mut motions = std::collections::HashSet::<String>::new();
        for name in [
            "test_grid.toml",
            "test_real_motion.toml",
            "test_real_pattern.toml",
        ] {
            let spec = load(name);
            designs.extend(spec.garments.iter().map(|g| design(&g.name)));
            motions.extend(spec.motions.iter().map(|m| clip(&m.source)));
        }
        // A built-in motion by its name; a capture by its clip and stretch (seconds).
        let mut stretches: Vec<(String, f64, f64)> = Vec::new();
        for name in ["validation.toml", "validation_wide.toml"] {
            let validation = load(name);
            designs.extend(validation.garments.iter().map(|g| design(&g.name)));
            for (source, _) in crate::plan::expand_motions(&validation).unwrap() {
                match source.contains('/') {
                    true => stretches.push(stretch_of(&source)),
                    false => {
                        motions.insert(clip(&source));
                    }
                }
            }
        }
        assert!(motions.contains("01_03") && designs.contains("dress_loose_maxi"));
        assert!(
            stretches
                .iter()
                .any(|(c, from, _)| c == "01_01" && *from == 19.0)
        );
        let mut checked = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let file = path.file_name().unwrap().to_string_lossy().to_string();
            if !(file.starts_with("train") && file.ends_with(".toml")) {
                continue;
            }
            let spec = DatasetSpec::load(&path).unwrap();
            for garment in spec.garments.iter().filter(|g| g.split == Tag::Train) {
                let name = design(&garment.name);
                assert!(!designs.contains(&name), "{file} trains on held-out {name}");
            }
            let motions_of = crate::plan::expand_motions(&spec).unwrap();
            let train = motions_of.into_iter().filter(|(_, tag)| *tag == Tag::Train);
            for (source, _) in train {
                assert!(
                    !motions.contains(&clip(&source)),
                    "{file} trains on held-out motion {source}"
                );
                let (c, from, to) = stretch_of(&source);
                let overlaps = |(v, a, b): &(String, f64, f64)| *v == c && from < *b && *a < to;
                assert!(
                    !stretches.iter().any(overlaps),
                    "{file} trains on a validation stretch: {source}"
                );
            }
            checked += 1;
        }
        assert!(checked >= 3, "{checked} training specs");
    }

    /// A motion's clip: a file's stem or a built-in motion's name.
    fn clip(source: &str) -> String {
        let file = source.split(':').next().unwrap_or(source);
        Path::new(file)
            .file_stem()
            .map_or(file.into(), |s| s.to_string_lossy().into())
    }

    /// A motion's clip and the seconds it covers, as the motions crate reads its `start` and
    /// `duration` (a built-in motion, or a whole file, runs to infinity).
    fn stretch_of(source: &str) -> (String, f64, f64) {
        match motions::MotionSource::parse(source) {
            Ok(motions::MotionSource::File(file)) => {
                let end = file.start + file.duration.unwrap_or(f64::INFINITY);
                (clip(source), file.start, end)
            }
            _ => (clip(source), 0.0, f64::INFINITY),
        }
    }
}
