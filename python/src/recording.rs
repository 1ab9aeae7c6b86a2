//! `Recording`: a garment recording (simulated or predicted) as NumPy arrays, made once when
//! it is read and handed out without copying; its MCAP bytes are kept, so `write` gives the
//! file the engine wrote.

use std::path::{Path, PathBuf};

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::recording::Recording as SimRecording;

use crate::errors::{file_error, sim_error};
use crate::json::to_python;

/// A garment recording as NumPy arrays (metres, seconds, radians; y up, body facing +z).
#[pyclass(frozen, module = "dit_garment")]
pub struct Recording {
    /// Garment vertices per frame, float32 `(frames, vertices, 3)`.
    #[pyo3(get)]
    garment: Py<PyArray3<f32>>,
    /// Garment triangles, int64 `(triangles, 3)`.
    #[pyo3(get)]
    faces: Py<PyArray2<i64>>,
    /// The template's rest positions on the canonical body, float64 `(vertices, 3)`.
    #[pyo3(get)]
    template: Py<PyArray2<f64>>,
    /// UV coordinates, float64 `(uv_vertices, 2)`; `uv_faces` indexes them per triangle.
    #[pyo3(get)]
    uv: Py<PyArray2<f64>>,
    /// UV triangles, int64 `(triangles, 3)` (one per garment triangle).
    #[pyo3(get)]
    uv_faces: Py<PyArray2<i64>>,
    /// Body vertices per frame, float32 `(frames, body_vertices, 3)`, or `None` where the
    /// recording has no body channel (simulate with `body_vertices=True`).
    #[pyo3(get)]
    body: Option<Py<PyArray3<f32>>>,
    /// Body triangles, int64 `(triangles, 3)`, or `None` with no body channel.
    #[pyo3(get)]
    body_faces: Option<Py<PyArray2<i64>>>,
    /// SMPL axis-angle pose per frame, float64 `(frames, 24, 3)`.
    #[pyo3(get)]
    poses: Py<PyArray3<f64>>,
    /// Root translation per frame, float64 `(frames, 3)`.
    #[pyo3(get)]
    translation: Py<PyArray2<f64>>,
    /// The sequence's shape coefficients, float64 `(betas,)`.
    #[pyo3(get)]
    betas: Py<PyArray1<f64>>,
    /// Shape per frame (ramped in during the blend-in), float64 `(frames, betas)`.
    #[pyo3(get)]
    frame_betas: Py<PyArray2<f64>>,
    /// Frames per second.
    #[pyo3(get)]
    fps: f64,
    /// `{"k_s": N/m, "rho": kg/m^2, "k_b": N m}`.
    #[pyo3(get)]
    material: Py<PyDict>,
    /// The scene configuration the sequence was simulated (or predicted) from, as a dict;
    /// `None` in recordings made before configurations were recorded.
    #[pyo3(get)]
    config: Option<Py<PyAny>>,
    /// The whole metadata, as a dict (a prediction's has `predicted`: the model and the
    /// sampler's settings).
    #[pyo3(get)]
    meta: Option<Py<PyAny>>,
    /// Solver statistics per frame, as a list of dicts (empty for a prediction).
    #[pyo3(get)]
    stats: Py<PyAny>,
    /// Where it was read from (or `<simulated>`, `<predicted>`).
    #[pyo3(get)]
    path: String,
    parsed: SimRecording,
    bytes: Vec<u8>,
}

impl Recording {
    /// The recording in `bytes` (MCAP), named `name` in errors.
    pub fn from_bytes(py: Python<'_>, bytes: Vec<u8>, name: &str) -> PyResult<Self> {
        let parsed = SimRecording::from_bytes(&bytes, Path::new(name)).map_err(sim_error)?;
        Self::new(py, parsed, bytes, name)
    }

    /// The parsed recording, for the metrics.
    pub fn parsed(&self) -> &SimRecording {
        &self.parsed
    }

    /// Where it was read from, naming it in errors.
    pub fn name(&self) -> &Path {
        Path::new(&self.path)
    }

    fn new(py: Python<'_>, parsed: SimRecording, bytes: Vec<u8>, name: &str) -> PyResult<Self> {
        let fail = |message: String| {
            sim_error(sim::Error::Recording {
                path: name.to_string(),
                message,
            })
        };
        let frames = parsed.garment.len();
        let vertices = parsed.template.positions.len();
        if let Some(k) = parsed.garment.iter().position(|f| f.len() != vertices) {
            return Err(fail(format!(
                "frame {k} has {} garment vertices, the template {vertices}",
                parsed.garment[k].len()
            )));
        }
        let meta = parsed.meta.as_ref();
        let betas = meta.map(|m| m.betas.clone()).unwrap_or_default();
        let nb = parsed
            .poses
            .iter()
            .map(|p| p.betas.len())
            .max()
            .unwrap_or(betas.len());
        if let Some(k) = parsed.poses.iter().position(|p| p.pose.len() != 72) {
            return Err(fail(format!(
                "frame {k} has {} pose values, not 72",
                parsed.poses[k].pose.len()
            )));
        }
        let flat32 = |frames: &[Vec<[f32; 3]>]| -> Vec<f32> {
            frames.iter().flatten().flatten().copied().collect()
        };
        let garment = array3(py, flat32(&parsed.garment), [frames, vertices, 3])?;
        let body = if parsed.body.is_empty() {
            None
        } else {
            let bv = parsed.body[0].len();
            if let Some(k) = parsed.body.iter().position(|f| f.len() != bv) {
                return Err(fail(format!("body frame {k} has another vertex count")));
            }
            Some(array3(
                py,
                flat32(&parsed.body),
                [parsed.body.len(), bv, 3],
            )?)
        };
        let body_faces = (!parsed.body_faces.is_empty())
            .then(|| indices(py, &parsed.body_faces))
            .transpose()?;
        let poses: Vec<f64> = parsed.poses.iter().flat_map(|p| p.pose.clone()).collect();
        let translation: Vec<f64> = parsed.poses.iter().flat_map(|p| p.transl).collect();
        let frame_betas: Vec<f64> = parsed
            .poses
            .iter()
            .flat_map(|p| (0..nb).map(|i| p.betas.get(i).copied().unwrap_or(0.0)))
            .collect();
        let pose_frames = parsed.poses.len();
        let material = PyDict::new(py);
        if let Some(m) = meta {
            material.set_item("k_s", m.material.stretch)?;
            material.set_item("rho", m.material.density)?;
            material.set_item("k_b", m.material.bending)?;
        }
        let json_of = |value: serde_json::Value| to_python(py, &value);
        let config = match meta.and_then(|m| m.scene_config()) {
            Some(c) => Some(json_of(serde_json::to_value(&c).map_err(value)?)?),
            None => None,
        };
        let meta_dict = match &parsed.meta_json {
            Some(m) => Some(json_of(m.clone())?),
            None => None,
        };
        let stats = json_of(serde_json::to_value(&parsed.stats).map_err(value)?)?;
        Ok(Self {
            garment,
            faces: indices(py, &parsed.template.triangles)?,
            template: array2(py, &parsed.template.positions)?,
            uv: array2(py, &parsed.template.uvs)?,
            uv_faces: indices(py, &parsed.template.uv_triangles)?,
            body,
            body_faces,
            poses: array3(py, poses, [pose_frames, 24, 3])?,
            translation: PyArray1::from_vec(py, translation)
                .reshape([pose_frames, 3])?
                .unbind(),
            betas: PyArray1::from_vec(py, betas).unbind(),
            frame_betas: PyArray1::from_vec(py, frame_betas)
                .reshape([pose_frames, nb])?
                .unbind(),
            fps: meta.map_or(sim::scene::FPS, |m| m.fps),
            material: material.unbind(),
            config,
            meta: meta_dict,
            stats,
            path: name.to_string(),
            parsed,
            bytes,
        })
    }
}

fn value(e: serde_json::Error) -> PyErr {
    crate::errors::value_error(e.to_string())
}

/// A flat vector as a `shape` array, without copying.
fn array3<T: numpy::Element>(
    py: Python<'_>,
    flat: Vec<T>,
    shape: [usize; 3],
) -> PyResult<Py<PyArray3<T>>> {
    Ok(numpy::PyArray1::from_vec(py, flat).reshape(shape)?.unbind())
}

/// Rows of `N` values as an `(rows, N)` array.
fn array2<const N: usize>(py: Python<'_>, rows: &[[f64; N]]) -> PyResult<Py<PyArray2<f64>>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Ok(PyArray1::from_vec(py, flat)
        .reshape([rows.len(), N])?
        .unbind())
}

/// Triangles as an int64 `(triangles, 3)` array.
pub fn indices(py: Python<'_>, triangles: &[[u32; 3]]) -> PyResult<Py<PyArray2<i64>>> {
    let flat: Vec<i64> = triangles.iter().flatten().map(|&i| i64::from(i)).collect();
    Ok(PyArray1::from_vec(py, flat)
        .reshape([triangles.len(), 3])?
        .unbind())
}

#[pymethods]
impl Recording {
    /// Frames recorded.
    #[getter]
    fn frames(&self) -> usize {
        self.parsed.garment.len()
    }

    /// Writes the recording (the engine's MCAP bytes) to `path`, atomically: nothing is
    /// there unless the write finishes.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| files::write_atomic(&path, &self.bytes))
            .map_err(file_error)
    }

    /// The body of every frame: the recorded vertices where the recording has them, else
    /// `model` (default: the licence-free body) posed with each frame's recorded pose,
    /// translation and shape, as the metrics pose it. Returns float32 `(frames, V, 3)` and
    /// int64 faces `(T, 3)`.
    #[pyo3(signature = (model=None))]
    #[allow(clippy::type_complexity)]
    fn posed_body<'py>(
        &self,
        py: Python<'py>,
        model: Option<PathBuf>,
    ) -> PyResult<(Bound<'py, PyArray3<f32>>, Py<PyArray2<i64>>)> {
        let model = sim::sources::body_model(model.as_deref()).map_err(sim_error)?;
        let frames = self.parsed.garment.len().max(self.parsed.poses.len());
        let path = Path::new(&self.path);
        let bodies = py
            .detach(|| {
                (0..frames)
                    .map(|k| self.parsed.body_at(&model, k, path))
                    .collect::<sim::Result<Vec<_>>>()
            })
            .map_err(sim_error)?;
        let vertices = bodies.first().map_or(0, |b| b.vertices.len());
        let faces = bodies
            .first()
            .map_or_else(|| model.faces().to_vec(), |b| b.faces.clone());
        let flat: Vec<f32> = bodies
            .iter()
            .flat_map(|b| b.vertices.iter().flatten().map(|&c| c as f32))
            .collect();
        Ok((
            PyArray1::from_vec(py, flat).reshape([frames, vertices, 3])?,
            indices(py, &faces)?,
        ))
    }

    /// The MCAP bytes.
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, pyo3::types::PyBytes> {
        pyo3::types::PyBytes::new(py, &self.bytes)
    }

    fn __len__(&self) -> usize {
        self.frames()
    }

    fn __repr__(&self) -> String {
        let name = |m: &sim::recording::SequenceMeta| format!("{} through {}", m.garment, m.motion);
        format!(
            "Recording({}, {} frames, {} vertices, {})",
            self.parsed.meta.as_ref().map_or("no metadata".into(), name),
            self.frames(),
            self.parsed.template.positions.len(),
            self.path
        )
    }
}

/// Reads a recording the project wrote (simulated, predicted or a dataset's).
#[pyfunction]
pub fn read_recording(py: Python<'_>, path: PathBuf) -> PyResult<Recording> {
    let bytes = py
        .detach(|| files::read(&path, files::limits::RECORDING, "recording"))
        .map_err(file_error)?;
    Recording::from_bytes(py, bytes, &path.display().to_string())
}
