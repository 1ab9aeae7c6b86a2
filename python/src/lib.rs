//! `dit_garment._native`: the project's crates as a Python extension module (PyO3). The
//! user-facing names, their docstrings and argument handling live in `dit_garment/__init__.py`;
//! this module does the work: the engine (`simulate`), the surrogate (`predict`), the body
//! model, templates, metrics and datasets, each long call with the GIL released, arrays handed
//! to NumPy without copying, errors raised as `OSError` (files), `ValueError` (values) or
//! `RuntimeError` (numerical failure) with the command line's messages.

mod data;
mod errors;
mod json;
mod models;
mod recording;
mod scene;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("COMMIT", surrogate::run::COMMIT)?;
    m.add_class::<recording::Recording>()?;
    m.add_class::<data::TensorShards>()?;
    m.add_function(wrap_pyfunction!(recording::read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(scene::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(scene::predict, m)?)?;
    m.add_function(wrap_pyfunction!(scene::body, m)?)?;
    m.add_function(wrap_pyfunction!(scene::template, m)?)?;
    m.add_function(wrap_pyfunction!(scene::metrics, m)?)?;
    m.add_function(wrap_pyfunction!(data::dataset_sequences, m)?)?;
    m.add_function(wrap_pyfunction!(garment_names, m)?)?;
    Ok(())
}

/// The design library's garments (each also takes variants `NAME~K`, `NAME~wK`, `NAME~dK`),
/// and the built-in skirt.
#[pyfunction]
fn garment_names() -> Vec<String> {
    let mut names = vec!["skirt".to_string()];
    names.extend(
        garments::library::design_names()
            .into_iter()
            .map(String::from),
    );
    names
}
