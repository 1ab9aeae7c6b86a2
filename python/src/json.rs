//! JSON values as Python objects, through Python's own `json` module (one conversion of
//! metadata per recording; not a hot path).

use pyo3::prelude::*;

/// `value` as the dict, list or scalar `json.loads` makes of it.
pub fn to_python(py: Python<'_>, value: &serde_json::Value) -> PyResult<Py<PyAny>> {
    let text = value.to_string();
    Ok(py.import("json")?.call_method1("loads", (text,))?.unbind())
}
