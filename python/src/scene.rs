//! The scene functions: `simulate` and `predict` (a garment through a motion, by the engine or
//! by the surrogate), the body model posed, a garment's template, and one recording scored
//! against another. Each long call releases the GIL.

use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::conversion::FromPyObjectOwned;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::SceneConfig;
use sim::run::Prepared;
use surrogate::burn::prelude::Device;
use surrogate::predict::{SceneInput, SceneRequest, Settings, predict_scene};
use surrogate::run::TrainedModel;

use crate::errors::{file_error, motion_error, sim_error, surrogate_error, value_error};
use crate::recording::{Recording, indices};

/// The writer's name in a simulated recording: the command line's, so the same scene gives
/// the same bytes from either.
fn software() -> String {
    format!("dit-garment {}", env!("CARGO_PKG_VERSION"))
}

/// What a scene is made of, as the keyword arguments of `simulate` and `predict` give it.
#[derive(Debug, Default)]
pub struct SceneInputs {
    pub garment: String,
    pub motion: String,
    pub frames: Option<usize>,
    pub material: Option<Vec<(String, f64)>>,
    pub betas: Option<Vec<f64>>,
    pub body_model: Option<PathBuf>,
    pub blend_frames: Option<usize>,
    pub settle_frames: Option<usize>,
}

impl SceneInputs {
    /// These inputs over `c`.
    fn apply(&self, c: &mut SceneConfig) -> PyResult<()> {
        c.garment = self.garment.clone();
        c.motion = self.motion.clone();
        if let Some(path) = &self.body_model {
            c.model = Some(path.display().to_string());
        }
        if let Some(v) = &self.betas {
            c.betas = v.clone();
        }
        for (key, value) in self.material.iter().flatten() {
            match key.as_str() {
                "k_s" => c.material.stretch = *value,
                "rho" => c.material.density = *value,
                "k_b" => c.material.bending = *value,
                _ => {
                    return Err(value_error(format!(
                        "material: unknown key '{key}' (keys k_s N/m, rho kg/m^2, k_b N m)"
                    )));
                }
            }
        }
        if let Some(v) = self.frames {
            c.frames = Some(v);
        }
        if let Some(v) = self.blend_frames {
            c.blend_frames = v;
        }
        if let Some(v) = self.settle_frames {
            c.settle_frames = v;
        }
        Ok(())
    }
}

/// The solver's keyword arguments over `c`, each named as the command line's flag.
fn apply_solver(c: &mut SceneConfig, solver: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
    let Some(solver) = solver else {
        return Ok(());
    };
    for (key, value) in solver.iter() {
        let key: String = key.extract()?;
        let bad = |e: PyErr| value_error(format!("{key}: {e}"));
        match key.as_str() {
            "friction" => c.friction = value.extract().map_err(bad)?,
            "substeps" => c.solver.substeps = value.extract().map_err(bad)?,
            "iterations" => c.solver.max_iterations = value.extract().map_err(bad)?,
            "acceleration" => c.solver.acceleration = value.extract().map_err(bad)?,
            "self_contact" => c.solver.self_contact = value.extract().map_err(bad)?,
            "self_contact_distance" => {
                c.solver.self_contact_distance = value.extract().map_err(bad)?
            }
            "self_friction" => c.solver.self_friction = value.extract().map_err(bad)?,
            "body_vertices" => c.record.body_vertices = value.extract().map_err(bad)?,
            _ => {
                return Err(value_error(format!(
                    "unknown solver argument '{key}' (friction, substeps, iterations, \
                     acceleration, self_contact, self_contact_distance, self_friction, \
                     body_vertices)"
                )));
            }
        }
    }
    Ok(())
}

/// Loads what the configuration names and builds its scene (a library design's template is
/// made on first use and cached, as on the command line).
fn prepare(config: SceneConfig) -> sim::Result<Prepared> {
    let garment = config.garment.clone();
    Prepared::load(config.validated()?, &sim::templates::cache_dir(), |path| {
        eprintln!(
            "making the template of '{garment}' (first use; cached in {})",
            path.display()
        )
    })
}

/// Simulates a scene; see the Python docstring.
#[pyfunction]
#[pyo3(signature = (inputs, config=None, solver=None))]
pub fn simulate(
    py: Python<'_>,
    inputs: &Bound<'_, PyDict>,
    config: Option<PathBuf>,
    solver: Option<&Bound<'_, PyDict>>,
) -> PyResult<Recording> {
    let mut c = match &config {
        Some(path) => SceneConfig::load(path).map_err(sim_error)?,
        None => SceneConfig::default(),
    };
    SceneInputs::from_dict(inputs)?.apply(&mut c)?;
    apply_solver(&mut c, solver)?;
    c.validate().map_err(sim_error)?;
    let bytes = py
        .detach(|| -> sim::Result<Vec<u8>> {
            let prepared = prepare(c)?;
            let mut out = Cursor::new(Vec::new());
            prepared.record(&mut out, &software(), None, |_| Ok(()))?;
            Ok(out.into_inner())
        })
        .map_err(sim_error)?;
    Recording::from_bytes(py, bytes, "<simulated>")
}

/// Predicts a scene with a trained surrogate; see the Python docstring.
#[pyfunction]
#[pyo3(signature = (inputs, model, guidance, seed, steps=None, body_vertices=false))]
pub fn predict(
    py: Python<'_>,
    inputs: &Bound<'_, PyDict>,
    model: String,
    guidance: f64,
    seed: u64,
    steps: Option<usize>,
    body_vertices: bool,
) -> PyResult<Recording> {
    let dir = crate::models::model_dir(&model)?;
    let mut c = SceneConfig::default();
    SceneInputs::from_dict(inputs)?.apply(&mut c)?;
    c.validate().map_err(sim_error)?;
    let out_dir = tempfile::tempdir().map_err(|e| value_error(e.to_string()))?;
    let out = out_dir.path().join("prediction.mcap");
    py.detach(|| -> surrogate::Result<()> {
        let trained = TrainedModel::load(&dir, &Device::flex())?;
        let mut settings = Settings::for_model(&trained);
        settings.guidance.weight = guidance;
        settings.seed = seed;
        if let Some(steps) = steps {
            settings.steps = steps;
        }
        settings.validate()?;
        let prepared = prepare(c)?;
        let software = format!("dit-garment {} predict", env!("CARGO_PKG_VERSION"));
        let request = SceneRequest {
            trained: &trained,
            model_name: &model,
            settings: &settings,
            out: &out,
            obj_dir: None,
            body_vertices,
        };
        predict_scene(
            &SceneInput::of_scene(&prepared, &software),
            &request,
            &mut || {},
        )?;
        Ok(())
    })
    .map_err(surrogate_error)?;
    let bytes = files::read(&out, files::limits::RECORDING, "recording").map_err(file_error)?;
    Recording::from_bytes(py, bytes, "<predicted>")
}

impl SceneInputs {
    /// The inputs from the dict the Python wrapper passes (its keyword arguments by name;
    /// `None` leaves a value at its default).
    fn from_dict(d: &Bound<'_, PyDict>) -> PyResult<Self> {
        let get = |key: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
            Ok(d.get_item(key)?.filter(|v| !v.is_none()))
        };
        fn take<'py, T: FromPyObjectOwned<'py>>(
            key: &str,
            v: Option<Bound<'py, PyAny>>,
        ) -> PyResult<Option<T>> {
            v.map(|v| {
                v.extract::<T>()
                    .map_err(|e| value_error(format!("{key}: {}", Into::<PyErr>::into(e))))
            })
            .transpose()
        }
        Ok(Self {
            garment: take("garment", get("garment")?)?.unwrap_or_else(|| "skirt".into()),
            motion: take("motion", get("motion")?)?.unwrap_or_else(|| "walk".into()),
            frames: take("frames", get("frames")?)?,
            material: take::<std::collections::BTreeMap<String, f64>>(
                "material",
                get("material")?,
            )?
            .map(|m| m.into_iter().collect()),
            betas: take("betas", get("betas")?)?,
            body_model: take("body_model", get("body_model")?)?,
            blend_frames: take("blend_frames", get("blend_frames")?)?,
            settle_frames: take("settle_frames", get("settle_frames")?)?,
        })
    }
}

/// The body model a path names (the licence-free default body when `None`).
fn body_model(path: Option<&Path>) -> PyResult<motions::BodyModel> {
    sim::sources::body_model(path).map_err(sim_error)
}

/// The body posed: `poses` float64 `(frames, 24, 3)`, `translation` `(frames, 3)`; returns
/// vertices `(frames, V, 3)` and faces.
#[pyfunction]
#[pyo3(signature = (betas, poses, translation, model=None))]
#[allow(clippy::type_complexity)]
pub fn body<'py>(
    py: Python<'py>,
    betas: Vec<f64>,
    poses: PyReadonlyArray3<'py, f64>,
    translation: PyReadonlyArray2<'py, f64>,
    model: Option<PathBuf>,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Py<PyArray2<i64>>)> {
    let model = body_model(model.as_deref())?;
    let (poses, translation) = (poses.as_array(), translation.as_array());
    let frames = poses.shape()[0];
    if poses.shape()[1..] != [24, 3] || translation.shape() != [frames, 3] {
        return Err(value_error(format!(
            "poses must be (frames, 24, 3) and translation (frames, 3); got {:?} and {:?}",
            poses.shape(),
            translation.shape()
        )));
    }
    let frame_poses: Vec<motions::FramePose> = (0..frames)
        .map(|k| motions::FramePose {
            pose: std::array::from_fn(|i| poses[[k, i / 3, i % 3]]),
            transl: std::array::from_fn(|i| translation[[k, i]]),
        })
        .collect();
    let posed = py
        .detach(|| -> motions::Result<Vec<motions::PosedBody>> {
            let shaped = model.shape(&betas)?;
            model.pose_batch(&shaped, &frame_poses)
        })
        .map_err(motion_error)?;
    let vertices = posed
        .first()
        .map_or(model.template().len(), |p| p.vertices.len());
    let flat: Vec<f64> = posed
        .iter()
        .flat_map(|p| p.vertices.iter().flatten().copied())
        .collect();
    let array = PyArray1::from_vec(py, flat).reshape([frames, vertices, 3])?;
    Ok((array, indices(py, model.faces())?))
}

/// A garment's template: rest positions `(V, 3)`, triangles `(T, 3)` and the UV of every
/// triangle corner `(T, 3, 2)`.
#[pyfunction]
#[pyo3(signature = (garment, model=None))]
#[allow(clippy::type_complexity)]
pub fn template<'py>(
    py: Python<'py>,
    garment: String,
    model: Option<PathBuf>,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Py<PyArray2<i64>>,
    Bound<'py, PyArray3<f64>>,
)> {
    let model = Arc::new(body_model(model.as_deref())?);
    let (g, _) = py
        .detach(|| {
            sim::sources::garment(&garment, &model, &sim::templates::cache_dir(), |path| {
                eprintln!(
                    "making the template of '{garment}' (first use; cached in {})",
                    path.display()
                )
            })
        })
        .map_err(sim_error)?;
    let positions: Vec<f64> = g.positions.iter().flatten().copied().collect();
    let corners: Vec<f64> = g
        .uv_triangles
        .iter()
        .flat_map(|t| t.iter().flat_map(|&i| g.uvs[i as usize]))
        .collect();
    Ok((
        PyArray1::from_vec(py, positions).reshape([g.positions.len(), 3])?,
        indices(py, &g.triangles)?,
        PyArray1::from_vec(py, corners).reshape([g.uv_triangles.len(), 3, 2])?,
    ))
}

/// `prediction` scored against `truth` with the paper's metrics; see the Python docstring.
#[pyfunction]
#[pyo3(signature = (truth, prediction, seed=0, model=None))]
pub fn metrics<'py>(
    py: Python<'py>,
    truth: &Recording,
    prediction: &Recording,
    seed: u64,
    model: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = body_model(model.as_deref())?;
    let c = py
        .detach(|| {
            sim::metrics::compare(
                truth.parsed(),
                truth.name(),
                prediction.parsed(),
                prediction.name(),
                &model,
                seed,
            )
        })
        .map_err(sim_error)?;
    let out = PyDict::new(py);
    for ((name, _), v) in sim::metrics::Scores::UNITS.iter().zip(c.mean.values()) {
        out.set_item(*name, v)?;
    }
    out.set_item("frames_scored", c.per_frame.len())?;
    out.set_item("frames", c.frames)?;
    out.set_item("jitter", c.jitter_b)?;
    out.set_item("jitter_truth", c.jitter_a)?;
    Ok(out)
}
