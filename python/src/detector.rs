//! `pcaline.LineDetector` and its `Detection`: the facade's
//! [`LineDetector`] from Python, one scan at a time.

use crate::config;
use crate::convert::{read_f32_into, rows_array, value_error};
use crate::lines::PyLines;
use crate::scan::{PyScan, set_header};
use numpy::{PyArray1, PyArray2};
use pcaline::geometry::ScanPoints;
use pcaline::{Config, DetectedLine, Detection, LineDetector, RangeNoise, Scan};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::ops::Range;

/// The line detector of the paper (two-level clustering, PCA fit with the
/// eigenvalue-ratio test, merge of collinear pieces), configured by a
/// preset or a configuration file and keyword overrides.
#[pyclass(name = "LineDetector", module = "pcaline")]
pub struct PyLineDetector {
    detector: LineDetector,
    /// The scan buffer `detect` fills, kept to allocate nothing per scan.
    scan: Scan,
    name: String,
}

#[pymethods]
impl PyLineDetector {
    /// A detector. `config` is a preset (`"default"`, `"paper"`,
    /// `"split-and-merge"`, `"told-sigma"`, `"datasheet"`, `"adaptive"`) or
    /// the path of a TOML or JSON configuration file; `overrides` are its
    /// `detector` fields, as `fitting__eth=30` or `fitting={"eth": 30}`.
    /// Raises `ValueError` naming the field for a bad configuration.
    #[new]
    #[pyo3(signature = (config=None, **overrides))]
    fn new(
        config: Option<&Bound<'_, PyAny>>,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let named = config::resolve(config, Some("detector"), overrides)?;
        let detector = LineDetector::new(named.detector).map_err(value_error)?;
        Ok(PyLineDetector {
            detector,
            scan: Scan::new(0.0, 1.0, 0.0, 1.0, Vec::new()),
            name: named.name,
        })
    }

    /// Detects the lines of one scan. `ranges` is a 1-D float32 or float64
    /// array, or a sequence of numbers (copied once into the detector's
    /// buffer); the bearing of beam `i` is `angle_min + i * angle_increment`
    /// radians. Invalid ranges (NaN, inf, outside `[range_min,
    /// range_max]`) are beams without a return. Raises `ValueError` for an
    /// array that is not 1-D and numeric, or a header that cannot be right.
    /// The Python lock is released while detecting.
    #[pyo3(signature = (ranges, angle_min, angle_increment, range_min=0.0, range_max=f64::INFINITY, stamp=None))]
    #[allow(clippy::too_many_arguments)]
    fn detect(
        &mut self,
        py: Python<'_>,
        ranges: &Bound<'_, PyAny>,
        angle_min: f64,
        angle_increment: f64,
        range_min: f64,
        range_max: f64,
        stamp: Option<f64>,
    ) -> PyResult<PyDetection> {
        read_f32_into(ranges, "ranges", &mut self.scan.ranges)?;
        set_header(&mut self.scan, angle_min, angle_increment, range_min, range_max, stamp)?;
        let (detector, scan) = (&mut self.detector, &self.scan);
        Ok(py.detach(|| PyDetection::from(&detector.detect(scan))))
    }

    /// Detects the lines of a `Scan` (as `read_log` and the simulator give
    /// them).
    fn detect_scan(&mut self, py: Python<'_>, scan: &PyScan) -> PyDetection {
        let detector = &mut self.detector;
        py.detach(|| PyDetection::from(&detector.detect(&scan.scan)))
    }

    /// Detects the lines of `scan` `repeats` times in Rust, without
    /// returning to Python, and returns the seconds per detection: the
    /// baseline `bench/overhead.py` measures Python's calling overhead
    /// against. Not part of the API.
    fn _seconds_per_detection(&mut self, py: Python<'_>, scan: &PyScan, repeats: u32) -> f64 {
        let detector = &mut self.detector;
        py.detach(|| {
            let start = std::time::Instant::now();
            for _ in 0..repeats {
                std::hint::black_box(detector.detect(std::hint::black_box(&scan.scan)).lines.len());
            }
            start.elapsed().as_secs_f64() / f64::from(repeats.max(1))
        })
    }

    /// The configuration in effect, as a dict in the configuration file's
    /// form (the `detector` table).
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        config_dict(py, self.detector.config())
    }

    fn __repr__(&self) -> String {
        format!("LineDetector(config={:?})", self.name)
    }
}

/// `config` as a Python dict, through its JSON form.
fn config_dict<'py>(py: Python<'py>, config: &Config) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(config).map_err(value_error)?;
    let json = py.import("json")?;
    json.call_method1("loads", (PyString::new(py, &text),))
}

/// The result of `LineDetector.detect`: the lines and what led to them
/// (the paper's Figures 1-3: points, break-points, clusters).
#[pyclass(name = "Detection", module = "pcaline", frozen)]
#[derive(Debug, Clone)]
pub struct PyDetection {
    lines: Vec<DetectedLine>,
    points: ScanPoints,
    noise: Option<RangeNoise>,
    range_step_m: Option<f64>,
    level1_breaks: Vec<usize>,
    level2_breaks: Vec<usize>,
    clusters: Vec<Range<usize>>,
    sub_clusters: Vec<Range<usize>>,
}

impl From<&Detection<'_>> for PyDetection {
    fn from(d: &Detection<'_>) -> Self {
        PyDetection {
            lines: d.lines.to_vec(),
            points: d.points.clone(),
            noise: d.noise,
            range_step_m: d.noise_estimate.map(|e| e.range_step_m),
            level1_breaks: d.level1_breaks.to_vec(),
            level2_breaks: d.level2_breaks().collect(),
            clusters: d.clusters.to_vec(),
            sub_clusters: d.sub_clusters.to_vec(),
        }
    }
}

/// Index ranges `[start, end)` as an `(n, 2)` array.
fn ranges_array<'py>(py: Python<'py>, r: &[Range<usize>]) -> PyResult<Bound<'py, PyArray2<u64>>> {
    rows_array(py, 2, r.iter().flat_map(|r| [r.start as u64, r.end as u64]).collect())
}

#[pymethods]
impl PyDetection {
    /// The detected lines, sensor frame, in scan order.
    #[getter]
    fn lines(&self) -> PyLines {
        PyLines::detected(&self.lines)
    }

    /// The valid returns as points in the sensor frame, `(m, 2)`, metres
    /// (eq. 1), in scan order; a 360° scan is rotated to start at a
    /// level-1 break-point.
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows_array(py, 2, self.points.xy.iter().flat_map(|p| [p.x, p.y]).collect())
    }

    /// The beam of each point.
    #[getter]
    fn point_beams<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_slice(py, &self.points.beam)
    }

    /// The range of each point, metres.
    #[getter]
    fn point_ranges<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.points.range_m)
    }

    /// Level-1 break-points: the points that begin a cluster.
    #[getter]
    fn level1_breaks<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        PyArray1::from_iter(py, self.level1_breaks.iter().map(|&i| i as u64))
    }

    /// Level-2 break-points: the first point of every sub-cluster that
    /// does not begin a level-1 cluster.
    #[getter]
    fn level2_breaks<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        PyArray1::from_iter(py, self.level2_breaks.iter().map(|&i| i as u64))
    }

    /// Level-1 clusters kept, `(k, 2)` point ranges `[start, end)`.
    #[getter]
    fn clusters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u64>>> {
        ranges_array(py, &self.clusters)
    }

    /// Level-2 sub-clusters, `(k, 2)` point ranges `[start, end)`.
    #[getter]
    fn sub_clusters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u64>>> {
        ranges_array(py, &self.sub_clusters)
    }

    /// The range noise the thresholds used, `(near_sigma_m, far_sigma_m,
    /// far_from_m)`; `None` when no rule uses noise (the paper's preset).
    #[getter]
    fn noise(&self) -> Option<(f64, f64, f64)> {
        self.noise.map(|n| (n.near_sigma_m, n.far_sigma_m, n.far_from_m))
    }

    /// The range grid step found in the ranges, metres, when the
    /// configuration estimates the noise.
    #[getter]
    fn range_step_m(&self) -> Option<f64> {
        self.range_step_m
    }

    fn __len__(&self) -> usize {
        self.lines.len()
    }

    fn __repr__(&self) -> String {
        format!("Detection({} lines from {} points)", self.lines.len(), self.points.xy.len())
    }
}
