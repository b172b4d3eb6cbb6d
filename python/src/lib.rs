//! The `pcaline` Python package's native module (`pcaline._pcaline`): line
//! detection, log reading, mapping and localization aiding, simulation and
//! evaluation, from numpy arrays. The Python package (`python/pcaline/`)
//! re-exports it: `pcaline.LineDetector`, `pcaline.read_log`,
//! `pcaline.Mapper`, `pcaline.sim`, `pcaline.eval`.
//!
//! No Rust panic reaches Python: every argument is checked at the boundary
//! (`convert.rs`) and the algorithm crates do not panic on data.

mod config;
mod convert;
mod detector;
mod eval;
mod lines;
mod log;
mod mapper;
mod scan;
mod sim;

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

create_exception!(
    pcaline,
    FormatError,
    PyValueError,
    "A malformed log, scene or configuration file; the message names the file and the line, scan or item."
);

/// The native module.
#[pymodule]
fn _pcaline(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("FormatError", m.py().get_type::<FormatError>())?;
    m.add_class::<scan::PyScan>()?;
    m.add_class::<lines::PyLines>()?;
    m.add_class::<detector::PyLineDetector>()?;
    m.add_class::<detector::PyDetection>()?;
    m.add_class::<log::PyLogReader>()?;
    m.add_function(wrap_pyfunction!(log::read_log_py, m)?)?;
    m.add_class::<mapper::PyMapper>()?;
    m.add_class::<mapper::PyStep>()?;
    m.add_class::<sim::PyScene>()?;
    m.add_class::<sim::PySimulator>()?;
    m.add_class::<sim::PyFrame>()?;
    m.add_function(wrap_pyfunction!(sim::generate_maze_py, m)?)?;
    m.add_class::<eval::PyDetectionScore>()?;
    m.add_function(wrap_pyfunction!(eval::true_walls, m)?)?;
    m.add_function(wrap_pyfunction!(eval::trajectory_errors_py, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
