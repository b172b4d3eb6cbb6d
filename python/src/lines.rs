//! `pcaline.Lines`: a set of lines as numpy columns, one row per line. The
//! same class carries a scan's detections (sensor frame, with their beams,
//! points and straightness), a map's lines (world frame, with their ids,
//! observations and status) and lines from elsewhere
//! ([`PyLines::from_endpoints`], to score another extractor's output).
//!
//! Columns are built when read, so a detection that is never looked at
//! costs no array.

use crate::convert::{matrices_array, read_points, rows_array, value_error};
use numpy::{PyArray1, PyArray2, PyArray3};
use pcaline::fitting::Straightness;
use pcaline::mapping::{LineStatus, MapLine};
use pcaline::{DetectedLine, LineSegment, Point2};
use pyo3::prelude::*;

/// A map line's bookkeeping.
#[derive(Debug, Clone, Copy)]
pub struct MapInfo {
    id: u64,
    observations: u32,
    status: LineStatus,
}

/// Lines as numpy columns. `alpha` and `d` are the normal form
/// `x cos(alpha) + y sin(alpha) = d` (the paper's eq. 6, `d >= 0`).
#[pyclass(name = "Lines", module = "pcaline", frozen)]
#[derive(Debug, Clone, Default)]
pub struct PyLines {
    pub lines: Vec<LineSegment>,
    detected: Option<Vec<DetectedLine>>,
    map: Option<Vec<MapInfo>>,
}

impl PyLines {
    /// A scan's detected lines (sensor frame).
    pub fn detected(lines: &[DetectedLine]) -> Self {
        PyLines {
            lines: lines.iter().map(|l| l.line).collect(),
            detected: Some(lines.to_vec()),
            map: None,
        }
    }

    /// Plain segments (true walls, lines from elsewhere).
    pub fn segments(lines: Vec<LineSegment>) -> Self {
        PyLines { lines, detected: None, map: None }
    }

    /// A map's lines (world frame).
    pub fn map(lines: &[MapLine]) -> Self {
        PyLines {
            lines: lines.iter().map(|m| m.line).collect(),
            detected: None,
            map: Some(
                lines
                    .iter()
                    .map(|m| MapInfo { id: m.id.0, observations: m.observations, status: m.status })
                    .collect(),
            ),
        }
    }

    fn column<'py>(
        &self,
        py: Python<'py>,
        f: impl Fn(&LineSegment) -> f64,
    ) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_iter(py, self.lines.iter().map(f))
    }

    fn points<'py>(
        &self,
        py: Python<'py>,
        f: impl Fn(&LineSegment) -> Point2<f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let flat = self.lines.iter().flat_map(|l| {
            let p = f(l);
            [p.x, p.y]
        });
        rows_array(py, 2, flat.collect())
    }

    fn detected_column<'py, T: numpy::Element>(
        &self,
        py: Python<'py>,
        f: impl Fn(&DetectedLine) -> T,
    ) -> Option<Bound<'py, PyArray1<T>>> {
        self.detected.as_ref().map(|d| PyArray1::from_iter(py, d.iter().map(f)))
    }

    fn straightness<'py>(
        &self,
        py: Python<'py>,
        f: impl Fn(&Straightness) -> f64,
    ) -> Option<Bound<'py, PyArray1<f64>>> {
        self.detected_column(py, |l| f(&l.straightness))
    }
}

#[pymethods]
impl PyLines {
    /// Lines from their endpoints: `start` and `end` are `(n, 2)` arrays
    /// (or sequences of pairs) of the same length, metres; lines of zero
    /// length are refused. Use it to score another extractor's lines with
    /// `pcaline.eval`.
    #[staticmethod]
    fn from_endpoints(start: &Bound<'_, PyAny>, end: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (a, b) = (read_points(start, "start")?, read_points(end, "end")?);
        if a.len() != b.len() {
            return Err(value_error(format!(
                "start and end: {} and {} points; they must be as many",
                a.len(),
                b.len()
            )));
        }
        let lines = a
            .iter()
            .zip(&b)
            .enumerate()
            .map(|(i, (a, b))| {
                let dir = b - a;
                let norm = dir.norm();
                if !(norm > 0.0 && norm.is_finite()) {
                    return Err(value_error(format!(
                        "line {i}: start {a:?} and end {b:?} do not make a line"
                    )));
                }
                Ok(LineSegment::between(*a, *b))
            })
            .collect::<PyResult<_>>()?;
        Ok(PyLines::segments(lines))
    }

    fn __len__(&self) -> usize {
        self.lines.len()
    }

    fn __repr__(&self) -> String {
        let kind = if self.detected.is_some() {
            "detected"
        } else if self.map.is_some() {
            "map"
        } else {
            "plain"
        };
        format!("Lines({} {kind} lines)", self.lines.len())
    }

    /// Normal angle of each line, radians (eq. 6).
    #[getter]
    fn alpha<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |l| l.alpha())
    }

    /// Distance of each line from the origin, metres (eq. 6, `>= 0`).
    #[getter]
    fn d<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |l| l.d())
    }

    /// First endpoints, `(n, 2)`, metres.
    #[getter]
    fn start<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.points(py, |l| l.start())
    }

    /// Last endpoints, `(n, 2)`, metres.
    #[getter]
    fn end<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.points(py, |l| l.end())
    }

    /// Endpoints as `(n, 2, 2)`: `[line][start|end][x|y]`, what
    /// `matplotlib.collections.LineCollection` takes.
    #[getter]
    fn segments_xy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let flat = self
            .lines
            .iter()
            .flat_map(|l| [l.start().x, l.start().y, l.end().x, l.end().y])
            .collect();
        matrices_array(py, flat)
    }

    /// Centroids of the fitted points, `(n, 2)`, metres.
    #[getter]
    fn centroid<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.points(py, |l| l.centroid())
    }

    /// Unit directions, start to end, `(n, 2)`.
    #[getter]
    fn direction<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.points(py, |l| Point2::from(l.direction()))
    }

    /// Lengths, metres.
    #[getter]
    fn length<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, LineSegment::length)
    }

    /// Points fitted (0 for lines made from endpoints).
    #[getter]
    fn n_points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        PyArray1::from_iter(py, self.lines.iter().map(|l| l.n_points() as u64))
    }

    /// Residual standard deviation of the fitted points, metres.
    #[getter]
    fn residual_std<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |l| l.residual_std())
    }

    /// Covariance of `(alpha, d)` of each line, `(n, 2, 2)` (eq. 7).
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let flat = self
            .lines
            .iter()
            .flat_map(|l| {
                let c = &l.covariance();
                [c[(0, 0)], c[(0, 1)], c[(1, 0)], c[(1, 1)]]
            })
            .collect();
        matrices_array(py, flat)
    }

    /// First beam of each detected line (`None` for other lines).
    #[getter]
    fn first_beam<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<u32>>> {
        self.detected_column(py, |l| l.first_beam)
    }

    /// Last beam of each detected line.
    #[getter]
    fn last_beam<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<u32>>> {
        self.detected_column(py, |l| l.last_beam)
    }

    /// First point (index into `Detection.points`) of each detected line.
    #[getter]
    fn first_point<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<u64>>> {
        self.detected_column(py, |l| l.first_point as u64)
    }

    /// Last point of each detected line (inclusive; it wraps past the end
    /// of the points on a 360° scan's seam).
    #[getter]
    fn last_point<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<u64>>> {
        self.detected_column(py, |l| l.last_point as u64)
    }

    /// Residual over the range noise at the line's range (about 1 on a
    /// straight wall), for detected lines.
    #[getter]
    fn residual_ratio<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.straightness(py, |s| s.residual_ratio)
    }

    /// Runs-test z score of the residual signs (strongly negative on a
    /// curved surface), for detected lines.
    #[getter]
    fn runs_z<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.straightness(py, |s| s.runs_z)
    }

    /// Bow (sagitta of the residuals' parabola), metres, for detected lines.
    #[getter]
    fn bow_m<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.straightness(py, |s| s.bow_m)
    }

    /// Map line ids (`None` for other lines).
    #[getter]
    fn id<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<u64>>> {
        self.map.as_ref().map(|m| PyArray1::from_iter(py, m.iter().map(|i| i.id)))
    }

    /// Scans that refined each map line.
    #[getter]
    fn observations<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<u32>>> {
        self.map.as_ref().map(|m| PyArray1::from_iter(py, m.iter().map(|i| i.observations)))
    }

    /// Each map line's status: `"tentative"`, `"confirmed"` or
    /// `"not-straight"`.
    #[getter]
    fn status(&self) -> Option<Vec<&'static str>> {
        self.map.as_ref().map(|m| {
            m.iter()
                .map(|i| match i.status {
                    LineStatus::Tentative => "tentative",
                    LineStatus::Confirmed => "confirmed",
                    _ => "not-straight",
                })
                .collect()
        })
    }
}
