//! Training tensors read back (`dataset tensors` output): the manifest, the templates' maps and
//! a split's frames, checked against their checksums and shapes and normalized with the
//! manifest's train statistics, as flat `f32` arrays a trainer batches from.

use std::path::{Path, PathBuf};

use safetensors::SafeTensors;
use safetensors::tensor::Dtype;

use super::manifest::TensorManifest;
use crate::error::{Result, file_error};

/// A tensors folder: its manifest and its templates, normalized.
#[derive(Debug, Clone)]
pub struct TrainingTensors {
    /// The folder.
    pub dir: PathBuf,
    /// `manifest.json`.
    pub manifest: TensorManifest,
    /// Normalized position maps, `[G, 3, R, R]` flat.
    pub position_maps: Vec<f32>,
    /// Loss masks (inside or read back), `[G, 1, R, R]` flat, 0 or 1.
    pub masks: Vec<f32>,
    /// Inside-a-chart masks, `[G, 1, R, R]` flat, 0 or 1.
    pub inside: Vec<f32>,
}

/// The frames of one split, normalized.
#[derive(Debug, Clone, Default)]
pub struct Frames {
    /// `[N, D]` flat.
    pub conditions: Vec<f32>,
    /// `[N, 3, R, R]` flat.
    pub targets: Vec<f32>,
    /// Body inputs `[N, 6, R, R]` flat (empty where the tensors have none).
    pub bodies: Vec<f32>,
    /// Template of every frame.
    pub template: Vec<usize>,
    /// Manifest line of every frame's sequence.
    pub sequence: Vec<usize>,
    /// Recording frame of every frame.
    pub frame: Vec<usize>,
}

impl Frames {
    /// Frames held.
    pub fn len(&self) -> usize {
        self.template.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.template.is_empty()
    }

    /// The frame just before frame `f` of the same sequence, if it is held: shards keep a
    /// sequence's frames in order, so it is the one stored before `f` (the first frame of a
    /// sequence, and every frame of tensors made with `--every` above 1, have none).
    pub fn previous(&self, f: usize) -> Option<usize> {
        let p = f.checked_sub(1)?;
        (self.sequence[p] == self.sequence[f] && self.frame[p] + 1 == self.frame[f]).then_some(p)
    }
}

/// Reads a tensor file and checks it against `sha256` (hex), the manifest's.
fn read_checked(path: &Path, sha256: &str) -> Result<Vec<u8>> {
    let limit = files::limits::TENSORS;
    Ok(files::read_verified(
        path,
        limit,
        "tensor file",
        sha256,
        "the manifest",
    )?)
}

/// A named tensor of the given dtype and shape as little-endian values.
fn tensor_bytes<'a>(
    file: &'a SafeTensors<'a>,
    name: &str,
    dtype: Dtype,
    shape: &[usize],
    path: &Path,
) -> Result<&'a [u8]> {
    let view = file
        .tensor(name)
        .map_err(|e| file_error(path, format!("tensor '{name}': {e}")))?;
    if view.dtype() != dtype || view.shape() != shape {
        return Err(file_error(
            path,
            format!(
                "tensor '{name}' is {:?} {:?}, expected {dtype:?} {shape:?}",
                view.dtype(),
                view.shape()
            ),
        ));
    }
    Ok(view.data())
}

fn f32s(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

fn indices(bytes: &[u8], bound: usize, name: &str, path: &Path) -> Result<Vec<usize>> {
    bytes
        .chunks_exact(8)
        .map(|b| {
            let v = i64::from_le_bytes(b.try_into().expect("8 bytes"));
            usize::try_from(v)
                .ok()
                .filter(|&v| v < bound)
                .ok_or_else(|| file_error(path, format!("'{name}' holds {v}, out of 0..{bound}")))
        })
        .collect()
}

impl TrainingTensors {
    /// Opens a tensors folder: reads and checks the manifest and `templates.safetensors`.
    pub fn open(dir: &Path) -> Result<Self> {
        let path = dir.join("manifest.json");
        let text = files::read_to_string(&path, files::limits::TEXT, "tensors manifest")?;
        let manifest: TensorManifest =
            serde_json::from_str(&text).map_err(|e| file_error(&path, e))?;
        let n = &manifest.normalization;
        if !manifest.normalization_fits() {
            return Err(file_error(
                &path,
                "normalization statistics of the wrong length",
            ));
        }
        if let Some(problem) = manifest.statistics_problem() {
            return Err(file_error(&path, problem));
        }
        let r = manifest.resolution;
        let g = manifest.templates.len();
        let path = dir.join("templates.safetensors");
        let bytes = read_checked(&path, &manifest.templates_sha256)?;
        let file = SafeTensors::deserialize(&bytes).map_err(|e| file_error(&path, e))?;
        let mut position_maps = f32s(tensor_bytes(
            &file,
            "position_maps",
            Dtype::F32,
            &[g, 3, r, r],
            &path,
        )?);
        n.position_maps.normalize(&mut position_maps, r * r);
        let masks = f32s(tensor_bytes(
            &file,
            "masks",
            Dtype::F32,
            &[g, 1, r, r],
            &path,
        )?);
        let inside = f32s(tensor_bytes(
            &file,
            "inside",
            Dtype::F32,
            &[g, 1, r, r],
            &path,
        )?);
        Ok(Self {
            dir: dir.to_path_buf(),
            manifest,
            position_maps,
            masks,
            inside,
        })
    }

    /// Reads every shard of `split` (no frames if the split has none), checked and
    /// normalized.
    pub fn frames(&self, split: &str) -> Result<Frames> {
        let m = &self.manifest;
        let (r, d, g) = (m.resolution, m.condition_dim, m.templates.len());
        let mut out = Frames::default();
        let Some(info) = m.splits.get(split) else {
            return Ok(out);
        };
        for shard in &info.shards {
            let path = self.dir.join(&shard.file);
            let bytes = read_checked(&path, &shard.sha256)?;
            let file = SafeTensors::deserialize(&bytes).map_err(|e| file_error(&path, e))?;
            let f = shard.frames;
            let mut conditions = f32s(tensor_bytes(
                &file,
                "conditions",
                Dtype::F32,
                &[f, d],
                &path,
            )?);
            m.normalization.conditions.normalize(&mut conditions, 1);
            let mut targets = f32s(tensor_bytes(
                &file,
                "targets",
                Dtype::F32,
                &[f, 3, r, r],
                &path,
            )?);
            m.normalization.targets.normalize(&mut targets, r * r);
            if let Some(stats) = &m.normalization.bodies {
                let mut bodies = f32s(tensor_bytes(
                    &file,
                    "bodies",
                    Dtype::F32,
                    &[f, m.body_channels(), r, r],
                    &path,
                )?);
                stats.normalize(&mut bodies, r * r);
                out.bodies.extend(bodies);
            }
            let index = |name: &str, bound: usize| {
                tensor_bytes(&file, name, Dtype::I64, &[f], &path)
                    .and_then(|b| indices(b, bound, name, &path))
            };
            out.template.extend(index("template_index", g)?);
            out.sequence.extend(index("sequence_index", usize::MAX)?);
            out.frame.extend(index("frame_index", usize::MAX)?);
            out.conditions.extend(conditions);
            out.targets.extend(targets);
        }
        Ok(out)
    }

    /// Texels per side.
    pub fn resolution(&self) -> usize {
        self.manifest.resolution
    }
}
