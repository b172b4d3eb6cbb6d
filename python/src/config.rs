//! Configurations from Python: a preset name or a configuration file (as the
//! command line takes them, `pcaline eval --show-config NAME` shows the
//! form), then keyword overrides written as field paths with `__` between
//! the parts (`fitting__eth=30`) or as nested dicts (`fitting={"eth": 30}`).

use crate::convert::value_error;
use pcaline_cli::config_file::{NamedConfig, resolve_with_overrides};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::PathBuf;
use toml::{Table, Value};

/// The range noise the `told-sigma` preset is told, metres (the
/// datasheet's 10 mm, as `pcaline run` tells it).
const TOLD_SIGMA_M: f64 = 0.01;

/// Resolves `config` (a preset name or a file path; `None` is `"default"`) with `overrides`
/// placed under `section` of the file's form (`detector` for a line
/// detector; none for a mapper, whose overrides name their section).
pub fn resolve(
    config: Option<&Bound<'_, PyAny>>,
    section: Option<&str>,
    overrides: Option<&Bound<'_, PyDict>>,
) -> PyResult<NamedConfig> {
    let spec: PathBuf = match config {
        None => PathBuf::from("default"),
        Some(c) => c.extract().map_err(|_| {
            PyValueError::new_err("config: expected a preset name or a configuration file path")
        })?,
    };
    let mut table = Table::new();
    if let Some(kwargs) = overrides {
        for (key, value) in kwargs.iter() {
            let key: String = key.extract()?;
            let mut path: Vec<&str> = section.into_iter().collect();
            path.extend(key.split("__"));
            insert(&mut table, &path, to_toml(&value, &key)?, &key)?;
        }
    }
    resolve_with_overrides(
        &spec.to_string_lossy(),
        TOLD_SIGMA_M,
        &Value::Table(table),
        "keyword arguments",
    )
    .map_err(|e| value_error(format!("{e:#}")))
}

/// Writes `value` at `path` in `table`, merging tables an earlier keyword
/// made (`fitting__eth` and `fitting__min_line_points` both go to `fitting`).
fn insert(table: &mut Table, path: &[&str], value: Value, key: &str) -> PyResult<()> {
    let Some((last, parents)) = path.split_last() else { return Ok(()) };
    let mut here = table;
    for part in parents {
        let slot = here.entry((*part).to_string()).or_insert_with(|| Value::Table(Table::new()));
        here = slot.as_table_mut().ok_or_else(|| {
            PyValueError::new_err(format!("{key}: `{part}` is given both as a value and a table"))
        })?;
    }
    match (here.get_mut(*last), value) {
        (Some(Value::Table(old)), Value::Table(new)) => old.extend(new),
        (_, value) => {
            here.insert((*last).to_string(), value);
        }
    }
    Ok(())
}

/// A Python value as a configuration value: bools, numbers, strings,
/// dicts and lists; `None` is `false` (turns an optional rule off).
fn to_toml(value: &Bound<'_, PyAny>, key: &str) -> PyResult<Value> {
    if value.is_none() {
        return Ok(Value::Boolean(false));
    }
    if let Ok(b) = value.cast::<PyBool>() {
        return Ok(Value::Boolean(b.is_true()));
    }
    if value.cast::<PyInt>().is_ok() {
        return Ok(Value::Integer(
            value
                .extract()
                .map_err(|_| PyValueError::new_err(format!("{key}: integer out of range")))?,
        ));
    }
    if let Ok(f) = value.cast::<PyFloat>() {
        return Ok(Value::Float(f.value()));
    }
    if let Ok(s) = value.cast::<PyString>() {
        return Ok(Value::String(s.extract()?));
    }
    if let Ok(d) = value.cast::<PyDict>() {
        let mut t = Table::new();
        for (k, v) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| PyValueError::new_err(format!("{key}: dict keys must be strings")))?;
            let v = to_toml(&v, &format!("{key}.{k}"))?;
            t.insert(k, v);
        }
        return Ok(Value::Table(t));
    }
    if value.cast::<PyList>().is_ok() || value.cast::<PyTuple>().is_ok() {
        let items: Vec<Bound<'_, PyAny>> = value.extract()?;
        return items.iter().map(|v| to_toml(v, key)).collect::<PyResult<_>>().map(Value::Array);
    }
    // numpy scalars and other numbers: integers first (`__index__`).
    if let Ok(i) = value.extract::<i64>() {
        return Ok(Value::Integer(i));
    }
    if let Ok(f) = value.extract::<f64>() {
        return Ok(Value::Float(f));
    }
    let kind = value.get_type().name().map(|n| n.to_string()).unwrap_or_default();
    Err(PyValueError::new_err(format!("{key}: a {kind} is not a configuration value")))
}
