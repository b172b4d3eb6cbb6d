//! `pcaline.eval`: detections scored against the simulator's ground truth
//! with the project's protocol (`pcaline eval`; design section 5), and
//! trajectories against true poses.

use crate::convert::{pose_from, value_error};
use crate::lines::PyLines;
use crate::sim::PyFrame;
use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pcaline::Pose2;
use pcaline_eval::{DetectionCriteria, DetectionScore, trajectory_errors};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The matching rule from keyword arguments, checked.
fn criteria(
    min_beams: usize,
    min_extent_m: f64,
    max_angle_deg: f64,
    max_endpoint_m: f64,
    min_overlap: f64,
) -> PyResult<DetectionCriteria> {
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(value_error(format!("{name}: {v} must be a finite number >= 0")))
        }
    };
    positive("min_extent_m", min_extent_m)?;
    positive("max_angle_deg", max_angle_deg)?;
    positive("max_endpoint_m", max_endpoint_m)?;
    if !(0.0..=1.0).contains(&min_overlap) {
        return Err(value_error(format!("min_overlap: {min_overlap} must be in [0, 1]")));
    }
    let mut criteria = DetectionCriteria::default();
    criteria.min_beams = min_beams;
    criteria.min_extent_m = min_extent_m;
    criteria.max_angle_rad = max_angle_deg.to_radians();
    criteria.max_endpoint_m = max_endpoint_m;
    criteria.min_overlap = min_overlap;
    Ok(criteria)
}

/// The true visible walls of a simulated frame, sensor frame: maximal runs
/// of at least `min_beams` consecutive valid beams on one surface (collinear
/// walls drawn end to end are one surface), at least `min_extent_m` long.
#[pyfunction]
#[pyo3(signature = (frame, min_beams=10, min_extent_m=0.3))]
pub fn true_walls(frame: &PyFrame, min_beams: usize, min_extent_m: f64) -> PyResult<PyLines> {
    let c = criteria(min_beams, min_extent_m, 2.0, 0.1, 0.5)?;
    let walls = pcaline_eval::true_walls(&frame.frame, frame.sim.world(), &c);
    Ok(PyLines::segments(walls.into_iter().map(|w| w.line).collect()))
}

/// Recall, false positives, fragmentation and errors of detections over
/// any number of simulated scans. A detected line matches a true visible
/// wall when their orientations differ by at most `max_angle_deg`, both
/// detected endpoints lie within `max_endpoint_m` of the wall's line, and
/// they overlap by at least `min_overlap` of the shorter.
#[pyclass(name = "DetectionScore", module = "pcaline.eval")]
pub struct PyDetectionScore {
    criteria: DetectionCriteria,
    score: DetectionScore,
}

#[pymethods]
impl PyDetectionScore {
    /// An empty score with the protocol's matching rule (the defaults are
    /// `pcaline eval`'s).
    #[new]
    #[pyo3(signature = (min_beams=10, min_extent_m=0.3, max_angle_deg=2.0, max_endpoint_m=0.10, min_overlap=0.5))]
    fn new(
        min_beams: usize,
        min_extent_m: f64,
        max_angle_deg: f64,
        max_endpoint_m: f64,
        min_overlap: f64,
    ) -> PyResult<Self> {
        Ok(PyDetectionScore {
            criteria: criteria(
                min_beams,
                min_extent_m,
                max_angle_deg,
                max_endpoint_m,
                min_overlap,
            )?,
            score: DetectionScore::default(),
        })
    }

    /// Scores one frame's detected lines (sensor frame: a `Detection`'s
    /// `lines`, or `Lines.from_endpoints` of another extractor's output)
    /// against the frame's true visible walls.
    fn add(&mut self, frame: &PyFrame, lines: &PyLines) {
        let truth = pcaline_eval::true_walls(&frame.frame, frame.sim.world(), &self.criteria);
        self.score.add_scan(&truth, &lines.lines, &self.criteria);
    }

    /// Matched true walls over true walls (1 with none).
    #[getter]
    fn recall(&self) -> f64 {
        self.score.recall()
    }

    /// Detections matching no true wall over detections (0 with none).
    #[getter]
    fn false_positive_fraction(&self) -> f64 {
        self.score.false_positive_fraction()
    }

    /// Matching detections per matched wall (1: no fragmentation).
    #[getter]
    fn fragmentation(&self) -> f64 {
        self.score.fragmentation()
    }

    /// Median and rms of the orientation errors, radians (NaN without a match).
    #[getter]
    fn alpha_error(&self) -> (f64, f64) {
        self.score.alpha_error()
    }

    /// Median and rms of the centroids' offsets from the true lines, metres.
    #[getter]
    fn d_error(&self) -> (f64, f64) {
        self.score.d_error()
    }

    /// Median and rms of the endpoint errors, metres.
    #[getter]
    fn endpoint_error(&self) -> (f64, f64) {
        self.score.endpoint_error()
    }

    /// Recall by true wall length: under 0.5 m, 0.5-1 m, 1-2 m, 2 m and more
    /// (NaN for an empty bin).
    #[getter]
    fn recall_by_length(&self) -> [f64; 4] {
        self.score.recall_by_length()
    }

    /// The counts as a dict: `scans`, `true_walls`, `matched_walls`,
    /// `detections`, `false_positives`, `matching_detections`.
    #[getter]
    fn counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.score;
        let d = PyDict::new(py);
        d.set_item("scans", s.scans)?;
        d.set_item("true_walls", s.true_walls)?;
        d.set_item("matched_walls", s.matched_walls)?;
        d.set_item("detections", s.detections)?;
        d.set_item("false_positives", s.false_positives)?;
        d.set_item("matching_detections", s.matching_detections)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "DetectionScore(recall={:.3}, false_positives={:.3}, {} scans)",
            self.score.recall(),
            self.score.false_positive_fraction(),
            self.score.scans
        )
    }
}

/// `(n, 3)` poses from a numpy array or a sequence of triples.
fn read_poses(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<Pose2>> {
    let rows: Vec<(f64, f64, f64)> = if let Ok(a) = obj.cast::<PyArray2<f64>>() {
        if a.shape()[1] != 3 {
            return Err(value_error(format!("{name}: expected shape (n, 3), got {:?}", a.shape())));
        }
        let a = a.readonly();
        a.as_array().rows().into_iter().map(|r| (r[0], r[1], r[2])).collect()
    } else {
        obj.extract().map_err(|_| {
            value_error(format!("{name}: expected an (n, 3) array of (x_m, y_m, heading_rad)"))
        })?
    };
    rows.into_iter().enumerate().map(|(i, p)| pose_from(p, &format!("{name}[{i}]"))).collect()
}

/// Errors of a trajectory against the true one, pose by pose (`(n, 3)`
/// arrays of `(x_m, y_m, heading_rad)`, as many rows each): a dict of
/// `heading_rms_rad`, `heading_max_rad`, `position_rms_m`,
/// `position_final_m`. Raises `ValueError` for empty or mismatched inputs.
#[pyfunction]
#[pyo3(name = "trajectory_errors")]
pub fn trajectory_errors_py<'py>(
    py: Python<'py>,
    estimate: &Bound<'py, PyAny>,
    truth: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let (e, t) = (read_poses(estimate, "estimate")?, read_poses(truth, "truth")?);
    if e.len() != t.len() || e.is_empty() {
        return Err(value_error(format!(
            "estimate and truth: {} and {} poses; they must be as many, and not none",
            e.len(),
            t.len()
        )));
    }
    let r = trajectory_errors(&e, &t)
        .ok_or_else(|| value_error("estimate and truth: nothing to compare"))?;
    let d = PyDict::new(py);
    d.set_item("heading_rms_rad", r.heading_rms_rad)?;
    d.set_item("heading_max_rad", r.heading_max_rad)?;
    d.set_item("position_rms_m", r.position_rms_m)?;
    d.set_item("position_final_m", r.position_final_m)?;
    Ok(d)
}
