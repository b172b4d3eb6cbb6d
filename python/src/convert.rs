//! Conversions at the Python boundary: arrays and sequences in (checked,
//! copied once into buffers the caller keeps), numpy arrays out, poses as
//! `(x_m, y_m, heading_rad)` tuples, and Rust errors as Python exceptions.
//!
//! Nothing here panics on what Python passes: a wrong dtype, a 2-D array, a
//! non-numeric sequence or a mismatched length is a `ValueError` naming the
//! argument.

use crate::FormatError;
use numpy::{PyArray1, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pcaline::{Point2, Pose2};
use pcaline_io::IoError;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;

/// Copies `obj` (a 1-D float32 or float64 numpy array, or a sequence of
/// numbers) into `out` as `f32`, replacing its content. `name` names the
/// argument in errors.
pub fn read_f32_into(obj: &Bound<'_, PyAny>, name: &str, out: &mut Vec<f32>) -> PyResult<()> {
    out.clear();
    if let Ok(a) = obj.cast::<PyArray1<f32>>() {
        let a = a.readonly();
        match a.as_slice() {
            Ok(s) => out.extend_from_slice(s),
            Err(_) => out.extend(a.as_array().iter().copied()),
        }
        return Ok(());
    }
    if let Ok(a) = obj.cast::<PyArray1<f64>>() {
        let a = a.readonly();
        // Ranges are f32 in a scan, as drivers publish them.
        out.extend(a.as_array().iter().map(|&r| r as f32));
        return Ok(());
    }
    let values = read_f64_sequence(obj, name)?;
    out.extend(values.iter().map(|&r| r as f32));
    Ok(())
}

/// `obj` (a 1-D numeric numpy array or a sequence of numbers) as `f64`s.
pub fn read_f64_sequence(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    if let Ok(a) = obj.cast::<PyArray1<f64>>() {
        return Ok(a.readonly().as_array().to_vec());
    }
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        let dtype = a.dtype();
        if a.ndim() != 1 {
            return Err(PyValueError::new_err(format!(
                "{name}: expected a 1-D array, got a {}-D array of shape {:?}",
                a.ndim(),
                a.shape()
            )));
        }
        // Integer and other float widths are numbers; anything else is not.
        if !(dtype.is_equiv_to(&numpy::dtype::<f32>(obj.py()))
            || "iuf".contains(dtype.kind() as char))
        {
            return Err(PyValueError::new_err(format!(
                "{name}: expected a numeric array (float32 or float64), got dtype {}",
                dtype.str()?
            )));
        }
    }
    obj.extract::<Vec<f64>>().map_err(|_| {
        let kind = obj.get_type().name().map(|n| n.to_string()).unwrap_or_default();
        PyValueError::new_err(format!(
            "{name}: expected a 1-D array or sequence of numbers, got {kind}"
        ))
    })
}

/// `obj` as an `(n, 2)` array of points (a numpy array or a sequence of
/// pairs), row by row.
pub fn read_points(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<Point2<f64>>> {
    let rows: Vec<[f64; 2]> = if let Ok(a) = obj.cast::<numpy::PyArray2<f64>>() {
        let a = a.readonly();
        let v = a.as_array();
        if v.ncols() != 2 {
            return Err(PyValueError::new_err(format!(
                "{name}: expected shape (n, 2), got {:?}",
                v.shape()
            )));
        }
        v.rows().into_iter().map(|r| [r[0], r[1]]).collect()
    } else {
        obj.extract::<Vec<[f64; 2]>>().map_err(|_| {
            PyValueError::new_err(format!("{name}: expected an (n, 2) array of float64 points"))
        })?
    };
    Ok(rows.into_iter().map(|[x, y]| Point2::new(x, y)).collect())
}

/// A pose from `(x_m, y_m, heading_rad)`; the heading is wrapped.
pub fn pose_from(t: (f64, f64, f64), name: &str) -> PyResult<Pose2> {
    if !(t.0.is_finite() && t.1.is_finite() && t.2.is_finite()) {
        return Err(PyValueError::new_err(format!("{name}: {t:?} is not finite")));
    }
    Ok(Pose2::new(t.0, t.1, t.2))
}

/// A pose as `(x_m, y_m, heading_rad)`.
pub fn pose_tuple(p: &Pose2) -> (f64, f64, f64) {
    (p.x(), p.y(), p.heading())
}

/// Poses as an `(n, 3)` array; `None` rows are NaN.
pub fn poses_array<'py>(
    py: Python<'py>,
    poses: impl Iterator<Item = Option<Pose2>>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let flat: Vec<f64> =
        poses.flat_map(|p| p.map_or([f64::NAN; 3], |p| [p.x(), p.y(), p.heading()])).collect();
    rows_array(py, 3, flat)
}

/// A flat row-major vector as an `(n, cols)` array.
pub fn rows_array<T: numpy::Element>(
    py: Python<'_>,
    cols: usize,
    flat: Vec<T>,
) -> PyResult<Bound<'_, numpy::PyArray2<T>>> {
    let n = flat.len() / cols;
    PyArray1::from_vec(py, flat).reshape([n, cols])
}

/// A flat row-major vector as an `(n, 2, 2)` array (covariances).
pub fn matrices_array(py: Python<'_>, flat: Vec<f64>) -> PyResult<Bound<'_, numpy::PyArray3<f64>>> {
    let n = flat.len() / 4;
    PyArray1::from_vec(py, flat).reshape([n, 2, 2])
}

/// A reader's error as Python sees it: `FileNotFoundError` or `OSError` for
/// the operating system's errors, [`FormatError`] for a malformed file.
pub fn io_error(e: IoError) -> PyErr {
    match &e {
        IoError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(e.to_string())
        }
        IoError::Io { .. } => PyOSError::new_err(e.to_string()),
        _ => FormatError::new_err(e.to_string()),
    }
}

/// A configuration error (anything `config_file` or a `validate` reports)
/// as a `ValueError` with the message, cause included.
pub fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}
