//! The tensor files of `dataset tensors`: a split's frames as safetensors shards and the
//! templates' maps as `templates.safetensors`, each written atomically with its SHA-256 for
//! the manifest.

use std::path::Path;

use safetensors::tensor::{Dtype, TensorView};
use sim::recording::TemplateArrays;

use super::manifest::ShardInfo;
use super::stats::{Stats, stats};
use super::tensors::channels_first;
use crate::error::{Result, file_error};
use crate::geometry::GeometryImage;

/// One sample.
pub(super) struct Frame {
    pub(super) condition: Vec<f32>,
    pub(super) target: Vec<f32>,
    /// `[6, R, R]`, empty without body inputs.
    pub(super) bodies: Vec<f32>,
    pub(super) template: usize,
    pub(super) sequence: usize,
    pub(super) frame: usize,
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn i64_bytes(values: impl Iterator<Item = usize>) -> Vec<u8> {
    values.flat_map(|v| (v as i64).to_le_bytes()).collect()
}

/// Writes `bytes` to `path` atomically and returns their SHA-256 for the manifest.
pub(super) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<String> {
    files::write_atomic(path, bytes)?;
    Ok(files::sha256_hex(bytes))
}

/// Serializes named tensors (f32 or i64 little-endian bytes with their shapes).
fn safetensors_bytes(
    tensors: &[(&str, Dtype, Vec<usize>, Vec<u8>)],
    path: &Path,
) -> Result<Vec<u8>> {
    let views = tensors
        .iter()
        .map(|(name, dtype, shape, bytes)| {
            TensorView::new(*dtype, shape.clone(), bytes)
                .map(|v| (name.to_string(), v))
                .map_err(|e| file_error(path, e))
        })
        .collect::<Result<Vec<_>>>()?;
    safetensors::serialize(views, None).map_err(|e| file_error(path, e))
}

/// A split's frames written as shards of at most `shard_frames` frames, `<split>-NNNN`.
pub(super) fn write_shards(
    out: &Path,
    split: &str,
    frames: &[Frame],
    shard_frames: usize,
    [dim, body_channels, r]: [usize; 3],
) -> Result<Vec<ShardInfo>> {
    let mut shards = Vec::new();
    for (n, chunk) in frames.chunks(shard_frames.max(1)).enumerate() {
        let file = format!("{split}-{n:04}.safetensors");
        let path = out.join(&file);
        let count = chunk.len();
        let flat = |part: fn(&Frame) -> &[f32]| -> Vec<f32> {
            chunk.iter().flat_map(|f| part(f).iter().copied()).collect()
        };
        let index = |part: fn(&Frame) -> usize| i64_bytes(chunk.iter().map(part));
        let mut tensors = vec![
            (
                "conditions",
                Dtype::F32,
                vec![count, dim],
                f32_bytes(&flat(|f| &f.condition)),
            ),
            (
                "targets",
                Dtype::F32,
                vec![count, 3, r, r],
                f32_bytes(&flat(|f| &f.target)),
            ),
            (
                "template_index",
                Dtype::I64,
                vec![count],
                index(|f| f.template),
            ),
            (
                "sequence_index",
                Dtype::I64,
                vec![count],
                index(|f| f.sequence),
            ),
            ("frame_index", Dtype::I64, vec![count], index(|f| f.frame)),
        ];
        if body_channels > 0 {
            tensors.push((
                "bodies",
                Dtype::F32,
                vec![count, body_channels, r, r],
                f32_bytes(&flat(|f| &f.bodies)),
            ));
        }
        let bytes = safetensors_bytes(&tensors, &path)?;
        let sha256 = write_atomic(&path, &bytes)?;
        shards.push(ShardInfo {
            file,
            frames: count,
            sha256,
        });
    }
    Ok(shards)
}

/// `templates.safetensors`: position maps, loss masks and inside masks, channels first;
/// returns its SHA-256 and the statistics of the training templates' position maps.
pub(super) fn write_templates(
    out: &Path,
    templates: &[(TemplateArrays, GeometryImage)],
    loss_masks: &[Vec<bool>],
    in_training: &[bool],
    r: usize,
) -> Result<(String, Stats)> {
    let g = templates.len();
    let mut positions = Vec::with_capacity(g * 3 * r * r);
    let mut masks = Vec::with_capacity(g * r * r);
    let mut inside = Vec::with_capacity(g * r * r);
    let (mut p_sum, mut p_sum2, mut p_count) = (vec![0.0; 3], vec![0.0; 3], 0.0);
    for (i, (t, image)) in templates.iter().enumerate() {
        let map = image.encode(&t.positions).map_err(|e| file_error(out, e))?;
        positions.extend(channels_first(&map));
        masks.extend(loss_masks[i].iter().map(|&m| m as u8 as f32));
        inside.extend(image.atlas().inside().iter().map(|&m| m as u8 as f32));
        if in_training[i] {
            for (p, _) in map.iter().zip(image.atlas().inside()).filter(|(_, m)| **m) {
                for c in 0..3 {
                    p_sum[c] += p[c];
                    p_sum2[c] += p[c] * p[c];
                }
                p_count += 1.0;
            }
        }
    }
    let path = out.join("templates.safetensors");
    let bytes = safetensors_bytes(
        &[
            (
                "position_maps",
                Dtype::F32,
                vec![g, 3, r, r],
                f32_bytes(&positions),
            ),
            ("masks", Dtype::F32, vec![g, 1, r, r], f32_bytes(&masks)),
            ("inside", Dtype::F32, vec![g, 1, r, r], f32_bytes(&inside)),
        ],
        &path,
    )?;
    Ok((
        write_atomic(&path, &bytes)?,
        stats(&p_sum, &p_sum2, p_count),
    ))
}
