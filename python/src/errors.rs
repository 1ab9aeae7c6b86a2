//! The crates' typed errors as Python exceptions with the command line's one-line messages:
//! `OSError` where a file is unreadable, foreign or in the way, `ValueError` for a bad value,
//! `RuntimeError` where the numbers failed (a blow-up, a diverged prediction).

use pyo3::PyErr;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};

/// Which Python exception an error becomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    File,
    Value,
    Numeric,
}

fn motion_kind(e: &motions::Error) -> Kind {
    use motions::Error as E;
    match e {
        E::File(_)
        | E::Io { .. }
        | E::Pickle { .. }
        | E::BadPickle { .. }
        | E::NotNpz { .. }
        | E::MissingKey { .. }
        | E::BadArray { .. }
        | E::Bvh { .. }
        | E::JointMap { .. } => Kind::File,
        _ => Kind::Value,
    }
}

fn sim_kind(e: &sim::Error) -> Kind {
    use sim::Error as E;
    match e {
        E::File(_) | E::Recording { .. } | E::Config { .. } => Kind::File,
        E::Motion(m) => motion_kind(m),
        E::Factorization { .. } | E::BlowUp { .. } | E::Deadline { .. } => Kind::Numeric,
        _ => Kind::Value,
    }
}

fn dataset_kind(e: &dataset::Error) -> Kind {
    use dataset::Error as E;
    match e {
        E::Sim(s) => sim_kind(s),
        E::Shard(_) => Kind::Value,
        E::File(_) | E::Dataset { .. } | E::Spec { .. } => Kind::File,
    }
}

fn surrogate_kind(e: &surrogate::Error) -> Kind {
    use surrogate::Error as E;
    match e {
        E::Files(_) | E::File { .. } | E::Config { .. } => Kind::File,
        E::Sim(s) => sim_kind(s),
        E::Dataset(d) => dataset_kind(d),
        E::Motion(m) => motion_kind(m),
        E::Diverged { .. } | E::NonFinitePrediction { .. } => Kind::Numeric,
        E::Sequence { source, .. } | E::GarmentInput { source, .. } => surrogate_kind(source),
        _ => Kind::Value,
    }
}

fn exception(kind: Kind, message: String) -> PyErr {
    match kind {
        Kind::File => PyOSError::new_err(message),
        Kind::Value => PyValueError::new_err(message),
        Kind::Numeric => PyRuntimeError::new_err(message),
    }
}

/// An engine error as its exception.
pub fn sim_error(e: sim::Error) -> PyErr {
    exception(sim_kind(&e), e.to_string())
}

/// A dataset error as its exception.
pub fn dataset_error(e: dataset::Error) -> PyErr {
    exception(dataset_kind(&e), e.to_string())
}

/// A surrogate error as its exception.
pub fn surrogate_error(e: surrogate::Error) -> PyErr {
    exception(surrogate_kind(&e), e.to_string())
}

/// A body-model or motion error as its exception.
pub fn motion_error(e: motions::Error) -> PyErr {
    exception(motion_kind(&e), e.to_string())
}

/// A file error (always an `OSError`).
pub fn file_error(e: files::Error) -> PyErr {
    PyOSError::new_err(e.to_string())
}

/// A bad argument, named.
pub fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}
