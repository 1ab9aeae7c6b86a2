//! A synthesized dataset (`synth` output) as training tensors: per split, safetensors shards
//! of frames (`conditions` [N, D] f32, `targets` [N, 3, R, R] f32, for `lbs_residual` also
//! `bodies` [N, 6, R, R] f32 (the skinned template and its change since the previous frame,
//! canonical, m; [N, 12, R, R] with `--body-nearest`: then also each skinned texel's offset
//! to the nearest posed-body point, m, and that point's normal), `template_index` [N] i64, `sequence_index` and `frame_index` [N] i64), `templates.safetensors` (`position_maps`
//! [G, 3, R, R], `masks` [G, 1, R, R], `inside` [G, 1, R, R]) and `manifest.json` (layout,
//! normalization statistics of the train split, counts, checksums). Same input, same bytes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use dataset::{DatasetDir, DatasetSpec, ManifestRecord, MaterialRanges, Split};
use motions::BodyModel;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sim::obstacles::MeshSurface;
use sim::recording::{Recording, TemplateArrays};

use super::conditions::{ConditionLayout, ConditionScaling};
use super::manifest::{Normalization, SplitInfo, TENSORS_FORMAT, TemplateInfo, TensorManifest};
use super::mirror::{
    DEFAULT_MIRROR_MAX_GAP_M, MAX_BODY_ASYMMETRY_M, TemplateMirror, body_asymmetry_m,
};
use super::sequence::Sequence;
use super::shards::{Frame, write_atomic, write_shards, write_templates};
use super::stats::{Stats, stats};
use crate::error::{Result, file_error};
use crate::geometry::{
    FrameBody, GeometryImage, PosedSurface, RootRemoval, TargetKind, Targets, nearest_body,
};
use crate::model::{BODY_CHANNELS, NEAREST_CHANNELS};

/// How a dataset becomes tensors.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TensorOptions {
    /// Texels per side.
    pub resolution: usize,
    /// What the targets hold.
    pub target: TargetKind,
    /// Earlier frames in each pose window.
    pub window: usize,
    /// Every K-th motion frame of a sequence becomes a sample.
    pub every: usize,
    /// Root rotation removed by the canonical frame.
    pub root: RootRemoval,
    /// Frames per shard.
    pub shard_frames: usize,
    /// Condition layout and scaling.
    pub conditions: ConditionScaling,
    /// Whether the body inputs also hold each texel's offset to the nearest body point and
    /// its normal (`lbs_residual` only).
    #[serde(default)]
    pub nearest: bool,
    /// Held-out splits whose sequences join the train split (indexed as [`Split::ALL`]): the
    /// refit of a chosen recipe on its training and validation data together.
    #[serde(default)]
    pub train_splits: [bool; Split::ALL.len()],
    /// Whether the train split also holds every sequence's mirror image (`mirror.rs`), for
    /// templates symmetric enough.
    #[serde(default)]
    pub mirror: bool,
    /// The largest mean asymmetry (m) of a template that is mirrored.
    #[serde(default = "default_mirror_max_gap")]
    pub mirror_max_gap_m: f64,
}

fn default_mirror_max_gap() -> f64 {
    DEFAULT_MIRROR_MAX_GAP_M
}

impl TensorOptions {
    /// The split a sequence of `split` lands in: the train split where it joins it.
    fn lands_in(&self, split: Split) -> Split {
        let joined = Split::ALL
            .iter()
            .position(|&s| s == split)
            .is_some_and(|i| self.train_splits[i]);
        if joined { Split::Train } else { split }
    }
}

impl Default for TensorOptions {
    fn default() -> Self {
        Self {
            resolution: 64,
            target: TargetKind::Displacement,
            window: 2,
            every: 1,
            root: RootRemoval::Heading,
            shard_frames: 2048,
            conditions: ConditionScaling::Bounded,
            nearest: false,
            train_splits: [false; Split::ALL.len()],
            mirror: false,
            mirror_max_gap_m: DEFAULT_MIRROR_MAX_GAP_M,
        }
    }
}

/// The body inputs of a frame as maps, channels first (m, un-normalized): the template
/// skinned to body `now` and its change since body `before`, both in `now`'s canonical frame
/// (`[6, R, R]`); with `nearest`, `now`'s posed body surface, also each skinned texel's offset
/// to the nearest body point and that point's normal (`[12, R, R]`). Training tensors and
/// prediction both call this, so the two paths give the same inputs.
pub fn body_input_maps(
    targets: &mut Targets,
    image: &GeometryImage,
    model: &BodyModel,
    now: FrameBody,
    before: FrameBody,
    nearest: Option<&MeshSurface>,
) -> Result<Vec<f32>> {
    let (frame, change) = targets.body_inputs(model, now, before)?;
    let mut out = channels_first(&image.encode(frame.base())?);
    out.extend(channels_first(&image.encode(&change)?));
    if let Some(body) = nearest {
        let skinned = frame.decode(&vec![[0.0; 3]; frame.base().len()]);
        for map in nearest_body(&skinned, frame.canonical(), body) {
            out.extend(channels_first(&image.encode(&map)?));
        }
    }
    Ok(out)
}

/// Channels-last `[f64; 3]` texels as channels-first f32 `[3, R, R]`.
pub(crate) fn channels_first(image: &[[f64; 3]]) -> Vec<f32> {
    (0..3)
        .flat_map(|c| image.iter().map(move |t| t[c] as f32))
        .collect()
}

/// Statistics of the body inputs: per channel for the skinned template; one scale for the
/// three channels of its change, mean 0 (their root mean square), so a motion sideways that
/// training rarely saw does not arrive at tens of standard deviations of the sideways channel.
/// The nearest-body offset is scaled the same way (one root mean square, mean 0); its normal
/// is a unit vector and stays as it is.
fn body_stats(sum: &[f64], sum2: &[f64], count: f64) -> Stats {
    let mut s = stats(sum, sum2, count);
    let mut one_scale = |channels: std::ops::Range<usize>, rms: Option<f64>| {
        let rms = rms.unwrap_or_else(|| {
            (sum2[channels.clone()].iter().sum::<f64>() / (3.0 * count.max(1.0))).sqrt()
        });
        for c in channels {
            s.mean[c] = 0.0;
            s.std[c] = if rms > 1e-12 { rms } else { 1.0 };
        }
    };
    one_scale(3..6, None);
    if sum.len() == BODY_CHANNELS + NEAREST_CHANNELS {
        one_scale(6..9, None);
        one_scale(9..12, Some(1.0));
    }
    s
}

/// A finished sequence: its manifest line, its recording's path, the recording parsed.
type Finished = (ManifestRecord, PathBuf, Sequence);

/// The dataset's finished sequences, each read once: checked against its manifest checksum,
/// then parsed.
fn finished(dir: &DatasetDir) -> Result<Vec<Finished>> {
    let path = dir.manifest();
    let mut records: Vec<ManifestRecord> = files::read_json_lines(&path, "dataset manifest")?;
    records.retain(ManifestRecord::ok);
    records
        .into_par_iter()
        .map(|r| {
            r.check_paths().map_err(|e| file_error(&path, e))?;
            let (Some(file), Some(sha)) = (&r.file, &r.sha256) else {
                return Err(file_error(
                    &path,
                    format!("sequence {} has no recording", r.sequence.id),
                ));
            };
            let seq = dir.root.join(file);
            let bytes = files::read_verified(
                &seq,
                files::limits::RECORDING,
                "recording",
                sha,
                "the manifest",
            )?;
            let sequence = Sequence::from_recording(Recording::from_bytes(&bytes, &seq)?, &seq)?;
            Ok((r, seq, sequence))
        })
        .collect()
}

/// The finished sequences of several datasets, and the material ranges their conditions are
/// scaled by: every dataset's spec must give the same ranges (a condition means one material
/// in all of them), and no sequence may come twice (the same dataset given twice).
fn combined(dirs: &[PathBuf]) -> Result<(MaterialRanges, Vec<Finished>)> {
    let Some(first) = dirs.first() else {
        return Err(crate::error::Error::NoDatasets);
    };
    let material = DatasetSpec::load(&DatasetDir::new(first).spec())?.material;
    let mut all: Vec<Finished> = Vec::new();
    for dir in dirs.iter().map(|d| DatasetDir::new(d)) {
        let path = dir.spec();
        let spec = DatasetSpec::load(&path)?;
        if spec.material != material {
            return Err(file_error(
                &path,
                format!(
                    "material ranges {:?} differ from {:?} of {} (datasets combined into one \
                     tensor set must share them)",
                    spec.material,
                    material,
                    first.display()
                ),
            ));
        }
        for found in finished(&dir)? {
            if let Some(seen) = all
                .iter()
                .find(|(r, ..)| r.sequence.id == found.0.sequence.id)
            {
                return Err(file_error(
                    &dir.manifest(),
                    format!(
                        "sequence {} is also in {}",
                        found.0.sequence.id,
                        seen.1.display()
                    ),
                ));
            }
            all.push(found);
        }
    }
    Ok((material, all))
}

/// The templates of the sequences' garments, one per garment name (sorted names give the
/// indices), each with its geometry image; a garment whose vertex count differs between
/// sequences is refused, naming the recording.
#[allow(clippy::type_complexity)]
fn template_images<'a>(
    records: &'a [ManifestRecord],
    sequences: &[(PathBuf, Sequence)],
    resolution: usize,
) -> Result<(Vec<&'a str>, Vec<(TemplateArrays, GeometryImage)>)> {
    let mut names: Vec<&str> = records
        .iter()
        .map(|r| r.sequence.garment.as_str())
        .collect();
    names.sort_unstable();
    names.dedup();
    let mut templates: Vec<Option<(TemplateArrays, GeometryImage)>> = vec![None; names.len()];
    for ((path, s), r) in sequences.iter().zip(records) {
        let g = names
            .binary_search(&r.sequence.garment.as_str())
            .unwrap_or(0);
        match &templates[g] {
            Some((t, _)) if t.positions.len() != s.template.positions.len() => {
                return Err(file_error(
                    path,
                    format!(
                        "garment '{}' has {} vertices here and {} in another sequence",
                        r.sequence.garment,
                        s.template.positions.len(),
                        t.positions.len()
                    ),
                ));
            }
            Some(_) => {}
            None => {
                let t = &s.template;
                let image =
                    GeometryImage::of_template(t, resolution).map_err(|e| file_error(path, e))?;
                templates[g] = Some((t.clone(), image));
            }
        }
    }
    Ok((names, templates.into_iter().flatten().collect()))
}

/// What turns a sequence into frames: the body model, the options, the condition layout, the
/// templates' geometry images and, with `--mirror`, their mirror correspondences.
struct Encoder<'a> {
    model: &'a BodyModel,
    options: &'a TensorOptions,
    layout: ConditionLayout,
    names: &'a [&'a str],
    templates: &'a [(TemplateArrays, GeometryImage)],
    mirrors: Vec<Option<TemplateMirror>>,
    with_bodies: bool,
}

impl Encoder<'_> {
    /// The index of a sequence's template (`template_images` gives every garment one).
    fn template_index(&self, record: &ManifestRecord) -> usize {
        self.names
            .binary_search(&record.sequence.garment.as_str())
            .unwrap_or(0)
    }

    /// The mirror correspondence of template `g`, where its sequences are to be held mirrored
    /// too (`--mirror`, a training template symmetric within the limit).
    fn mirror_of(&self, g: usize) -> Option<&TemplateMirror> {
        self.mirrors[g]
            .as_ref()
            .filter(|m| m.is_symmetric(self.options.mirror_max_gap_m))
    }

    /// The frames of sequence `i`, on template `g` (every `options.every`-th after the blend-in), encoded.
    /// `mirrored`: the sequence is the mirror image of a recorded one, whose cloth is then
    /// measured against the template's own mirror image (`TemplateMirror::template`), so that a
    /// template's asymmetry does not enter the target; the body inputs are the template's, as
    /// prediction gives them.
    fn sequence(
        &self,
        i: usize,
        g: usize,
        path: &Path,
        s: &Sequence,
        mirrored: Option<&TemplateMirror>,
    ) -> Result<Vec<Frame>> {
        let (model, options) = (self.model, self.options);
        let (template, image) = &self.templates[g];
        let targets_of = |positions: &[[f64; 3]]| {
            Targets::new(
                model,
                positions,
                &template.triangles,
                options.target,
                options.root,
            )
        };
        let mut targets = targets_of(&template.positions)?;
        let mut mirrored_targets = match mirrored {
            Some(mirror) => Some(targets_of(&mirror.template(&template.positions))?),
            None => None,
        };
        let motion = s.motion()?;
        let mut surface = PosedSurface::default();
        let mut out = Vec::new();
        for k in (s.first_motion_frame()..s.len()).step_by(options.every.max(1)) {
            let condition = self
                .layout
                .vector(&motion, k, &s.betas[k], &s.meta.material)?;
            let target = mirrored_targets.as_mut().unwrap_or(&mut targets).encode(
                model,
                s.body(k),
                &s.garment[k],
            )?;
            let map = image.encode(&target).map_err(|e| file_error(path, e))?;
            let bodies = if self.with_bodies {
                let before = s.body(k.saturating_sub(1));
                let nearest = match options.nearest {
                    true => Some(surface.at(model, s.body(k))?),
                    false => None,
                };
                body_input_maps(&mut targets, image, model, s.body(k), before, nearest)
                    .map_err(|e| file_error(path, e))?
            } else {
                Vec::new()
            };
            out.push(Frame {
                condition: condition.iter().map(|&x| x as f32).collect(),
                target: channels_first(&map),
                bodies,
                template: g,
                sequence: i,
                frame: k,
            });
        }
        Ok(out)
    }
}

/// With `--mirror`, the mirror correspondence of each template the train split holds (none
/// for the others, whose splits are not mirrored, nor without `--mirror`); a body model that
/// is not symmetric is refused, naming it.
fn mirrors(
    options: &TensorOptions,
    model: &BodyModel,
    names: &[&str],
    templates: &[(TemplateArrays, GeometryImage)],
    records: &[ManifestRecord],
) -> Result<Vec<Option<TemplateMirror>>> {
    if !options.mirror {
        return Ok(vec![None; templates.len()]);
    }
    let gap = body_asymmetry_m(model);
    if gap > MAX_BODY_ASYMMETRY_M {
        return Err(crate::error::Error::File {
            path: model.name().to_string(),
            problem: format!(
                "--mirror needs a body symmetric about x = 0: its mirrored rest vertices lie \
                 {:.1} mm from its own on average (at most {:.1})",
                1e3 * gap,
                1e3 * MAX_BODY_ASYMMETRY_M
            )
            .into(),
        });
    }
    let trained: Vec<&str> = records
        .iter()
        .filter(|r| options.lands_in(r.sequence.split) == Split::Train)
        .map(|r| r.sequence.garment.as_str())
        .collect();
    templates
        .par_iter()
        .zip(names)
        .map(|((t, _), name)| match trained.contains(name) {
            true => TemplateMirror::of_template(t, name).map(Some),
            false => Ok(None),
        })
        .collect()
}

/// The train split's sums over loss-mask texels (targets, body inputs) and frames
/// (conditions), and which templates it holds: the normalization statistics.
struct TrainSums {
    resolution: usize,
    targets: (Vec<f64>, Vec<f64>, f64),
    conditions: (Vec<f64>, Vec<f64>, f64),
    bodies: (Vec<f64>, Vec<f64>),
    templates: Vec<bool>,
}

impl TrainSums {
    fn new(resolution: usize, dim: usize, body_channels: usize, templates: usize) -> Self {
        Self {
            resolution,
            targets: (vec![0.0; 3], vec![0.0; 3], 0.0),
            conditions: (vec![0.0; dim], vec![0.0; dim], 0.0),
            bodies: (vec![0.0; body_channels], vec![0.0; body_channels]),
            templates: vec![false; templates],
        }
    }

    /// Adds a training frame, its targets and body inputs over `mask` (the template's loss
    /// mask).
    fn add(&mut self, f: &Frame, mask: &[bool]) {
        let rr = self.resolution * self.resolution;
        self.templates[f.template] = true;
        let (t_sum, t_sum2, t_count) = &mut self.targets;
        for c in 0..3 {
            for (k, &m) in mask.iter().enumerate() {
                if m {
                    let x = f.target[c * rr + k] as f64;
                    t_sum[c] += x;
                    t_sum2[c] += x * x;
                }
            }
        }
        let (b_sum, b_sum2) = &mut self.bodies;
        for c in 0..f.bodies.len() / rr {
            for (k, &m) in mask.iter().enumerate() {
                if m {
                    let x = f.bodies[c * rr + k] as f64;
                    b_sum[c] += x;
                    b_sum2[c] += x * x;
                }
            }
        }
        *t_count += mask.iter().filter(|&&m| m).count() as f64;
        let (c_sum, c_sum2, c_count) = &mut self.conditions;
        for (d, &x) in f.condition.iter().enumerate() {
            c_sum[d] += x as f64;
            c_sum2[d] += x as f64 * x as f64;
        }
        *c_count += 1.0;
    }

    /// The statistics of every tensor kind, the position maps' given.
    fn normalization(
        &self,
        layout: &ConditionLayout,
        positions: Stats,
        bodies: bool,
    ) -> Normalization {
        let (t_sum, t_sum2, t_count) = &self.targets;
        let (c_sum, c_sum2, c_count) = &self.conditions;
        let (b_sum, b_sum2) = &self.bodies;
        Normalization {
            targets: stats(t_sum, t_sum2, *t_count),
            conditions: layout.statistics(c_sum, c_sum2, *c_count),
            position_maps: positions,
            bodies: bodies.then(|| body_stats(b_sum, b_sum2, *t_count)),
        }
    }
}

/// Frames written per split, and per template and split.
struct SplitFrames {
    splits: BTreeMap<String, SplitInfo>,
    per_template: Vec<BTreeMap<String, usize>>,
}

/// Each split's frames encoded (sequences in parallel) and written as shards of `shape`
/// (`[condition dim, body channels, resolution]`), the train split's sums accumulated.
#[allow(clippy::too_many_arguments)]
fn encode_splits(
    encoder: &Encoder,
    records: &[ManifestRecord],
    sequences: &[(PathBuf, Sequence)],
    sums: &mut TrainSums,
    loss_masks: &[Vec<bool>],
    out: &Path,
    shape: [usize; 3],
    progress: &(impl Fn() + Sync),
) -> Result<SplitFrames> {
    let mut splits = BTreeMap::new();
    let mut per_template = vec![BTreeMap::<String, usize>::new(); loss_masks.len()];
    for split in Split::ALL.map(Split::name) {
        let members: Vec<usize> = (0..records.len())
            .filter(|&i| encoder.options.lands_in(records[i].sequence.split).name() == split)
            .collect();
        if members.is_empty() {
            continue;
        }
        let is_train = split == Split::Train.name();
        let mirrored = match is_train {
            true => members
                .iter()
                .filter(|&&i| {
                    encoder
                        .mirror_of(encoder.template_index(&records[i]))
                        .is_some()
                })
                .count(),
            false => 0,
        };
        let frames: Vec<Vec<Frame>> = members
            .par_iter()
            .map(|&i| {
                let (path, s) = &sequences[i];
                let g = encoder.template_index(&records[i]);
                let mut frames = encoder.sequence(i, g, path, s, None)?;
                if let Some(mirror) = encoder.mirror_of(g).filter(|_| is_train) {
                    let image = mirror.sequence(s);
                    frames.extend(encoder.sequence(i, g, path, &image, Some(mirror))?);
                }
                progress();
                Ok(frames)
            })
            .collect::<Result<_>>()?;
        let frames: Vec<Frame> = frames.into_iter().flatten().collect();
        for f in &frames {
            if is_train {
                sums.add(f, &loss_masks[f.template]);
            }
            *per_template[f.template]
                .entry(split.to_string())
                .or_default() += 1;
        }
        let info = SplitInfo {
            frames: frames.len(),
            sequences: members.len(),
            mirrored,
            shards: write_shards(out, split, &frames, encoder.options.shard_frames, shape)?,
        };
        splits.insert(split.to_string(), info);
    }
    Ok(SplitFrames {
        splits,
        per_template,
    })
}

/// Turns the datasets in `dirs` (one, or several with the same material ranges) into tensors
/// in `out`; `progress` is called once per sequence. Stages: the finished sequences read and
/// checked, the templates' geometry images, each split's frames encoded (sequences in
/// parallel) and written as shards while the train split's sums accumulate, the templates'
/// maps, the manifest.
pub fn write_tensors(
    dirs: &[PathBuf],
    out: &Path,
    model: &BodyModel,
    options: &TensorOptions,
    progress: impl Fn() + Sync,
) -> Result<TensorManifest> {
    let (material, found) = combined(dirs)?;
    let (records, sequences): (Vec<ManifestRecord>, Vec<(PathBuf, Sequence)>) =
        found.into_iter().map(|(r, path, s)| (r, (path, s))).unzip();
    let layout = ConditionLayout {
        betas: model.num_betas(),
        window: options.window,
        material,
        scaling: options.conditions,
    };
    let with_bodies = options.target == TargetKind::LbsResidual;
    if options.nearest && !with_bodies {
        return Err(crate::error::Error::NeedsLbsResidual {
            what: "nearest-body inputs",
        });
    }
    let body_channels = match (with_bodies, options.nearest) {
        (false, _) => 0,
        (true, false) => BODY_CHANNELS,
        (true, true) => BODY_CHANNELS + NEAREST_CHANNELS,
    };
    let (names, templates) = template_images(&records, &sequences, options.resolution)?;
    let loss_masks: Vec<Vec<bool>> = templates.iter().map(|(_, i)| i.loss_mask()).collect();
    let mirrors = mirrors(options, model, &names, &templates, &records)?;
    std::fs::create_dir_all(out).map_err(|e| file_error(out, e))?;
    let (r, dim) = (options.resolution, layout.dim());
    let encoder = Encoder {
        model,
        options,
        layout,
        names: &names,
        templates: &templates,
        mirrors,
        with_bodies,
    };
    let mut sums = TrainSums::new(r, dim, body_channels, templates.len());
    let split_frames = encode_splits(
        &encoder,
        &records,
        &sequences,
        &mut sums,
        &loss_masks,
        out,
        [dim, body_channels, r],
        &progress,
    )?;
    let (templates_sha256, positions) =
        write_templates(out, &templates, &loss_masks, &sums.templates, r)?;
    let manifest = TensorManifest {
        format: TENSORS_FORMAT,
        source: dirs
            .iter()
            .map(|d| d.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        resolution: r,
        target: options.target,
        window: options.window,
        every: options.every,
        root: options.root,
        condition_layout: Some(layout),
        condition: layout.blocks(),
        condition_dim: dim,
        material_ranges: material,
        body_model: model.name().to_string(),
        splits: split_frames.splits,
        joined_to_train: Split::ALL
            .iter()
            .zip(options.train_splits)
            .filter(|(_, joined)| *joined)
            .map(|(s, _)| s.name().to_string())
            .collect(),
        templates: templates
            .iter()
            .enumerate()
            .map(|(i, (t, image))| TemplateInfo {
                name: names[i].to_string(),
                index: i,
                vertices: t.positions.len(),
                coverage: image.atlas().coverage(),
                frames: split_frames.per_template[i].clone(),
                mirror_gap_m: encoder.mirrors[i].as_ref().map(|m| m.mean_gap_m),
            })
            .collect(),
        templates_sha256,
        normalization: sums.normalization(&layout, positions, with_bodies),
    };
    let json = serde_json::to_vec_pretty(&manifest).map_err(|e| file_error(out, e))?;
    write_atomic(&out.join("manifest.json"), &json)?;
    Ok(manifest)
}
