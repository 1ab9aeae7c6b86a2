//! `reference.safetensors`: a fixed input and the model's output on it, which
//! `tools/dit_reference.py` recomputes in NumPy.

use std::path::Path;

use burn::prelude::*;
use safetensors::tensor::{Dtype, TensorView};

use super::batch::Batch;
use crate::error::{Result, file_error};
use crate::model::Dit;

/// Writes the batch's inputs and `model`'s output on them (run on `device`) to `path`.
pub fn save_reference(model: &Dit, batch: &Batch, path: &Path, device: &Device) -> Result<()> {
    let (noisy, position, mask, time, conditions) = batch.inputs(device);
    let output = model.forward(
        noisy.clone(),
        position.clone(),
        mask.clone(),
        time.clone(),
        conditions.clone(),
    );
    let named: Vec<(&str, Tensor<4>)> = vec![
        ("noisy", noisy),
        ("position", position),
        ("mask", mask),
        ("output", output),
    ];
    let mut arrays: Vec<(String, Vec<usize>, Vec<u8>)> = named
        .into_iter()
        .map(|(name, t)| {
            (
                name.to_string(),
                t.dims().to_vec(),
                bytes(t.try_into_vec_as::<f32>()),
            )
        })
        .collect();
    arrays.push((
        "timestep".into(),
        time.dims().to_vec(),
        bytes(time.try_into_vec_as::<f32>()),
    ));
    arrays.push((
        "conditions".into(),
        conditions.dims().to_vec(),
        bytes(conditions.try_into_vec_as::<f32>()),
    ));
    let views = arrays
        .iter()
        .map(|(name, shape, data)| {
            TensorView::new(Dtype::F32, shape.clone(), data)
                .map(|v| (name.clone(), v))
                .map_err(|e| file_error(path, e))
        })
        .collect::<Result<Vec<_>>>()?;
    let serialized = safetensors::serialize(views, None).map_err(|e| file_error(path, e))?;
    Ok(files::write_atomic(path, &serialized)?)
}

fn bytes<E: std::fmt::Debug>(values: std::result::Result<Vec<f32>, E>) -> Vec<u8> {
    values
        .expect("f32 tensors read back as f32")
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}
