//! Datasets from Python: the finished sequences of a `synth` dataset folder (its manifest, read
//! and checked by the engine's own reader) and the training tensors of `dataset tensors`
//! (checked against their checksums, normalized as the trainer sees them).

use std::path::PathBuf;

use dataset::{DatasetDir, Split};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use surrogate::data::TrainingTensors;

use crate::errors::{dataset_error, surrogate_error, value_error};
use crate::json::to_python;

/// The sequences of `split` that passed their gates, in manifest order: a list of dicts with
/// `id`, `file` (absolute), `garment`, `motion`, `betas`, `material`, `frames`, `seed`.
#[pyfunction]
pub fn dataset_sequences<'py>(
    py: Python<'py>,
    folder: PathBuf,
    split: String,
) -> PyResult<Bound<'py, PyList>> {
    let Some(split) = Split::parse(&split) else {
        return Err(value_error(format!(
            "split '{split}': not one of {}",
            Split::names()
        )));
    };
    let dir = DatasetDir::new(&folder);
    let (_, _, records) = py.detach(|| dataset::load(&dir)).map_err(dataset_error)?;
    let out = PyList::empty(py);
    for r in records
        .iter()
        .filter(|r| r.sequence.split == split && r.ok())
    {
        let Some(file) = &r.file else { continue };
        let d = PyDict::new(py);
        d.set_item("id", &r.sequence.id)?;
        d.set_item("file", folder.join(file))?;
        d.set_item("garment", &r.sequence.garment)?;
        d.set_item("motion", &r.sequence.motion)?;
        d.set_item("betas", r.sequence.betas.clone())?;
        let material = PyDict::new(py);
        material.set_item("k_s", r.sequence.material.stretch)?;
        material.set_item("rho", r.sequence.material.density)?;
        material.set_item("k_b", r.sequence.material.bending)?;
        d.set_item("material", material)?;
        d.set_item("frames", r.frames)?;
        d.set_item("seed", r.sequence.seed)?;
        out.append(d)?;
    }
    Ok(out)
}

/// The training tensors `dataset tensors` wrote, read and checked: normalized with the
/// manifest's train statistics, as the trainer batches them.
#[pyclass(frozen, module = "dit_garment")]
pub struct TensorShards {
    tensors: TrainingTensors,
}

#[pymethods]
impl TensorShards {
    /// Opens a tensors folder (its manifest and templates; a split's shards are read when
    /// asked for).
    #[new]
    fn new(py: Python<'_>, folder: PathBuf) -> PyResult<Self> {
        let tensors = py
            .detach(|| TrainingTensors::open(&folder))
            .map_err(surrogate_error)?;
        Ok(Self { tensors })
    }

    /// The folder.
    #[getter]
    fn folder(&self) -> PathBuf {
        self.tensors.dir.clone()
    }

    /// Texels per side of the geometry images.
    #[getter]
    fn resolution(&self) -> usize {
        self.tensors.resolution()
    }

    /// The splits that have frames.
    #[getter]
    fn splits(&self) -> Vec<String> {
        let m = &self.tensors.manifest;
        Split::ALL
            .map(Split::name)
            .into_iter()
            .filter(|s| m.splits.get(*s).is_some_and(|i| !i.shards.is_empty()))
            .map(str::to_string)
            .collect()
    }

    /// `manifest.json` as a dict (normalization statistics, condition layout, templates).
    #[getter]
    fn manifest(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let value =
            serde_json::to_value(&self.tensors.manifest).map_err(|e| value_error(e.to_string()))?;
        to_python(py, &value)
    }

    /// The templates' maps: `position_maps` float32 `(G, 3, R, R)` (normalized), `masks` and
    /// `inside` float32 `(G, 1, R, R)`.
    #[getter]
    fn templates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = &self.tensors;
        let (g, r) = (t.manifest.templates.len(), t.resolution());
        let d = PyDict::new(py);
        let map = |values: &[f32], channels: usize| {
            PyArray1::from_slice(py, values).reshape([g, channels, r, r])
        };
        d.set_item("position_maps", map(&t.position_maps, 3)?)?;
        d.set_item("masks", map(&t.masks, 1)?)?;
        d.set_item("inside", map(&t.inside, 1)?)?;
        Ok(d)
    }

    /// Every frame of `split`, normalized: `conditions` float32 `(N, D)`, `targets` float32
    /// `(N, 3, R, R)`, `bodies` float32 `(N, C, R, R)` where the tensors have body inputs,
    /// and int64 `template_index`, `sequence_index`, `frame_index` `(N,)`.
    fn split<'py>(&self, py: Python<'py>, name: String) -> PyResult<Bound<'py, PyDict>> {
        if Split::parse(&name).is_none() {
            return Err(value_error(format!(
                "split '{name}': not one of {}",
                Split::names()
            )));
        }
        let t = &self.tensors;
        let frames = py.detach(|| t.frames(&name)).map_err(surrogate_error)?;
        let (n, r, dim) = (frames.len(), t.resolution(), t.manifest.condition_dim);
        let d = PyDict::new(py);
        d.set_item(
            "conditions",
            PyArray1::from_vec(py, frames.conditions).reshape([n, dim])?,
        )?;
        d.set_item(
            "targets",
            PyArray1::from_vec(py, frames.targets).reshape([n, 3, r, r])?,
        )?;
        if !frames.bodies.is_empty() {
            let c = t.manifest.body_channels();
            d.set_item(
                "bodies",
                PyArray1::from_vec(py, frames.bodies).reshape([n, c, r, r])?,
            )?;
        }
        let index =
            |v: Vec<usize>| PyArray1::from_vec(py, v.into_iter().map(|i| i as i64).collect());
        d.set_item("template_index", index(frames.template))?;
        d.set_item("sequence_index", index(frames.sequence))?;
        d.set_item("frame_index", index(frames.frame))?;
        Ok(d)
    }

    fn __getitem__<'py>(&self, py: Python<'py>, name: String) -> PyResult<Bound<'py, PyDict>> {
        self.split(py, name)
    }

    fn __repr__(&self) -> String {
        format!(
            "TensorShards({}, resolution {}, splits {})",
            self.tensors.dir.display(),
            self.resolution(),
            self.splits().join(", ")
        )
    }
}
