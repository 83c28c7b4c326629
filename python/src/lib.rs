//! `sitar._sitar`, the extension under the Python package `sitar`: `ape`, `rpe` and `drift`
//! on the sitar-evo library (options by evo's names, the JSON document back as text, which
//! `sitar/__init__.py` turns into the dict), and `main`, the `sitar` command itself.

mod calibrate;
mod estimate;
mod evo_api;
mod matrix;
mod matrix_rows;
mod options;

use std::path::{Path, PathBuf};

use pyo3::create_exception;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sitar_evo::{Collected, FileFormat, Metric};

use crate::options::Options;

create_exception!(
    _sitar,
    SitarError,
    PyValueError,
    "A bad input file (its path, line and column in the message) or option value."
);

/// The library's error as a Python exception: missing files as FileNotFoundError, other
/// reading failures as OSError, everything else as SitarError (a ValueError).
fn to_python(error: sitar_evo::Error) -> PyErr {
    let text = error.chain_text();
    let mut cause: Option<&dyn std::error::Error> = Some(&error);
    while let Some(e) = cause {
        if let Some(io) = e.downcast_ref::<std::io::Error>() {
            return match io.kind() {
                std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(text),
                _ => PyOSError::new_err(text),
            };
        }
        cause = e.source();
    }
    SitarError::new_err(text)
}

/// The files of one call.
fn files<'a>(fmt: &str, estimates: &'a [PathBuf]) -> PyResult<(FileFormat, Vec<&'a Path>)> {
    let format = FileFormat::from_name(fmt).map_err(to_python)?;
    if estimates.is_empty() {
        return Err(PyValueError::new_err("no estimate given"));
    }
    Ok((format, estimates.iter().map(PathBuf::as_path).collect()))
}

/// APE or RPE of each estimate: the JSON document and the warnings.
fn metric(
    py: Python<'_>,
    kind: &'static str,
    fmt: &str,
    reference: PathBuf,
    estimates: Vec<PathBuf>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<(String, Vec<String>)> {
    let (format, estimates) = files(fmt, &estimates)?;
    let parsed = Options::parse(kind, options)?;
    let metric: Metric = parsed.metric()?;
    let messages = Collected::default();
    let outcomes = py
        .allow_threads(|| {
            sitar_evo::compute_files(
                metric,
                format,
                &reference,
                &estimates,
                &parsed.sync,
                &parsed.algorithm,
                &messages,
            )
        })
        .map_err(to_python)?;
    Ok((
        sitar_evo::metric_document(&outcomes).to_string(),
        messages.take(),
    ))
}

/// `sitar.ape`'s core: the JSON text `sitar ape --format json` prints, and the warnings.
#[pyfunction]
#[pyo3(signature = (fmt, reference, estimates, options=None))]
fn ape(
    py: Python<'_>,
    fmt: &str,
    reference: PathBuf,
    estimates: Vec<PathBuf>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<(String, Vec<String>)> {
    metric(py, "ape", fmt, reference, estimates, options)
}

/// `sitar.rpe`'s core: the JSON text `sitar rpe --format json` prints, and the warnings.
#[pyfunction]
#[pyo3(signature = (fmt, reference, estimates, options=None))]
fn rpe(
    py: Python<'_>,
    fmt: &str,
    reference: PathBuf,
    estimates: Vec<PathBuf>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<(String, Vec<String>)> {
    metric(py, "rpe", fmt, reference, estimates, options)
}

/// `sitar.drift`'s core: the JSON text `sitar drift --format json` prints, and the warnings.
#[pyfunction]
#[pyo3(signature = (fmt, reference, estimates, options=None))]
fn drift(
    py: Python<'_>,
    fmt: &str,
    reference: PathBuf,
    estimates: Vec<PathBuf>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<(String, Vec<String>)> {
    let (format, estimates) = files(fmt, &estimates)?;
    let parsed = Options::parse("drift", options)?;
    let settings = parsed.drift()?;
    let messages = Collected::default();
    let (_, document) = py
        .allow_threads(|| {
            sitar_evo::drift_files(
                format,
                &reference,
                &estimates,
                &parsed.sync,
                &settings,
                &messages,
            )
        })
        .map_err(to_python)?;
    Ok((document.to_string(), messages.take()))
}

/// The extension module.
#[pymodule]
fn _sitar(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(ape, m)?)?;
    m.add_function(wrap_pyfunction!(rpe, m)?)?;
    m.add_function(wrap_pyfunction!(drift, m)?)?;
    m.add_function(wrap_pyfunction!(matrix::read_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(matrix::parse_matrix_text, m)?)?;
    m.add_function(wrap_pyfunction!(matrix_rows::read_matrix_rows, m)?)?;
    m.add_function(wrap_pyfunction!(matrix_rows::matrix_rows_of_text, m)?)?;
    m.add_class::<matrix_rows::MatrixRows>()?;
    m.add_function(wrap_pyfunction!(evo_api::ape_errors, m)?)?;
    m.add_function(wrap_pyfunction!(evo_api::read_bag_topic, m)?)?;
    m.add_function(wrap_pyfunction!(evo_api::rpe_errors, m)?)?;
    m.add_function(wrap_pyfunction!(estimate::estimate, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate::calibrate, m)?)?;
    m.add("SitarError", m.py().get_type::<SitarError>())?;
    Ok(())
}
