//! `pcaline.read_log`: the scans of any log the command line reads, as a
//! Python iterator that streams.
//!
//! The reader runs on its own thread and hands scans over a bounded
//! channel, so a log of any size takes a bounded amount of memory, and a
//! loop that stops early (or an iterator dropped) stops the reader at its
//! next scan.

use crate::convert::{io_error, value_error};
use crate::scan::PyScan;
use pcaline_io::{CarmenOptions, IoError, LogFormat, LogOptions, LogRecord, read_log};
use pyo3::prelude::*;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, sync_channel};

/// Scans read ahead of the Python loop.
const READ_AHEAD: usize = 64;

/// An iterator over the scans of a log (`for scan in pcaline.read_log(path)`).
#[pyclass(name = "LogReader", module = "pcaline")]
pub struct PyLogReader {
    path: PathBuf,
    scans: Mutex<Receiver<Result<PyScan, IoError>>>,
}

/// Reads the scans of a log: CARMEN, ROS 1 bag, ROS 2 bag (a `.db3` file or
/// a bag folder), MCAP, JSON or CSV. `format` (`"carmen"`, `"ros1"`,
/// `"ros2"`, `"mcap"`, `"json"`, `"csv"`) is detected from the file when
/// `None`; `topic` keeps one topic of a ROS log or MCAP file; `fov` is the
/// field of view of CARMEN `FLASER` lines in degrees, in (0, 360] (needed
/// for beam counts other than 180, 181 and 361); CARMEN ranges at or above
/// `max_range` metres are no return (default 80).
///
/// Each item is a `Scan` with its stamp, the log's own pose and odometry
/// when the log has them, and its position (line or index). Raises
/// `FileNotFoundError` or `OSError` when the file cannot be read, and
/// `FormatError` naming the file and line (or scan) when it is malformed;
/// errors met while iterating are raised by the iteration, after the scans
/// before them.
#[pyfunction]
#[pyo3(signature = (path, format=None, topic=None, fov=None, max_range=None))]
#[pyo3(name = "read_log")]
pub fn read_log_py(
    path: PathBuf,
    format: Option<&str>,
    topic: Option<String>,
    fov: Option<f64>,
    max_range: Option<f64>,
) -> PyResult<PyLogReader> {
    let format = format
        .map(|f| {
            LogFormat::from_name(f).ok_or_else(|| {
                value_error(format!("format: {f:?} is not a format ({})", LogFormat::names()))
            })
        })
        .transpose()?;
    if let Some(fov) = fov
        && !(fov > 0.0 && fov <= 360.0)
    {
        return Err(value_error(format!("fov: {fov} must be in (0, 360] degrees")));
    }
    let defaults = CarmenOptions::default();
    let max_range_m = max_range.unwrap_or(defaults.max_range_m);
    if !(max_range_m > 0.0 && max_range_m.is_finite()) {
        return Err(value_error(format!(
            "max_range: {max_range_m} must be a positive number of metres"
        )));
    }
    if !path.exists() {
        return Err(io_error(IoError::io(&path, std::io::ErrorKind::NotFound.into())));
    }
    let mut carmen = defaults;
    carmen.fov_rad = fov.map(f64::to_radians);
    carmen.max_range_m = max_range_m;
    let mut options = LogOptions::default();
    options.format = format;
    options.topic = topic;
    options.carmen = carmen;
    let (tx, rx) = sync_channel(READ_AHEAD);
    let reader_path = path.clone();
    std::thread::Builder::new()
        .name("pcaline-read-log".into())
        .spawn(move || {
            let read = read_log(&reader_path, &options, |record| match record {
                LogRecord::Scan(s) => {
                    let scan = PyScan {
                        scan: s.scan,
                        pose: s.pose,
                        odometry: s.odometry,
                        sensor: s.sensor,
                        position: s.position,
                    };
                    // A closed channel: the iterator is gone, stop reading.
                    match tx.send(Ok(scan)) {
                        Ok(()) => ControlFlow::Continue(()),
                        Err(_) => ControlFlow::Break(()),
                    }
                }
                // Odometry alone, and records of kinds added later.
                _ => ControlFlow::Continue(()),
            });
            if let Err(e) = read {
                let _ = tx.send(Err(e));
            }
        })
        .map_err(|e| io_error(IoError::io(&path, e)))?;
    Ok(PyLogReader { path, scans: Mutex::new(rx) })
}

#[pymethods]
impl PyLogReader {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&self, py: Python<'_>) -> PyResult<Option<PyScan>> {
        let next = py.detach(|| match self.scans.lock() {
            Ok(rx) => rx.recv().ok(),
            Err(_) => None,
        });
        match next {
            Some(Ok(scan)) => Ok(Some(scan)),
            Some(Err(e)) => Err(io_error(e)),
            None => Ok(None),
        }
    }

    fn __repr__(&self) -> String {
        format!("LogReader({:?})", self.path.display().to_string())
    }
}
