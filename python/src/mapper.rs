//! `pcaline.Mapper`: the facade's [`Mapper`] from Python: a scan and the
//! localization source's pose in, the corrected pose, the scan's lines and
//! the growing line map out.

use crate::config;
use crate::convert::{pose_from, pose_tuple, poses_array, value_error};
use crate::lines::PyLines;
use crate::scan::PyScan;
use numpy::{PyArray2, PyArrayMethods};
use pcaline::aiding::{AidingConfig, AidingMode, StepReport};
use pcaline::{Mapper, MapperConfig, MapperStep};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The aiding modes `Mapper` takes, by name.
const AIDING: &str = "estimator, paper, heading, full, none";

/// Line detection, the line map and localization aiding, scan by scan (the
/// paper's section 2.1; the estimator and loop closure beyond it).
#[pyclass(name = "Mapper", module = "pcaline")]
pub struct PyMapper {
    mapper: Mapper,
}

/// A `CamelCase` Rust name as `kebab-case`.
fn kebab(name: &str) -> String {
    let mut s = String::with_capacity(name.len() + 4);
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() && i > 0 {
            s.push('-');
        }
        s.push(c.to_ascii_lowercase());
    }
    s
}

#[pymethods]
impl PyMapper {
    /// A mapper with an empty map. `config` is a preset or a configuration
    /// file, as for `LineDetector`; `aiding` is `"estimator"` (odometry
    /// and line matches fused by their uncertainty, the default),
    /// `"paper"` (the paper's heading aiding, eq. 11-14), `"heading"`,
    /// `"full"` (each scan's correction in full) or `"none"`;
    /// `loop_closure` adds keyframes, loop closure and a pose graph.
    /// `overrides` are field paths of the configuration file's form,
    /// section first: `detector__fitting__eth=30`, `map__max_offset_m=0.2`,
    /// `aiding__estimator__motion__rotation_per_m=0.02`. `mount` is where
    /// the LIDAR sits on the vehicle whose poses `step` is given,
    /// `vehicle_from_sensor` as `(x_m, y_m, heading_rad)`; the poses the
    /// mapper returns are then the vehicle's too. Raises `ValueError`
    /// naming the field for a bad configuration.
    #[new]
    #[pyo3(signature = (config=None, aiding="estimator", loop_closure=true, mount=None, **overrides))]
    fn new(
        config: Option<&Bound<'_, PyAny>>,
        aiding: &str,
        loop_closure: bool,
        mount: Option<(f64, f64, f64)>,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let named = config::resolve(config, None, overrides)?;
        let aiding = match aiding {
            "estimator" => named.aiding_in(AidingMode::Estimator),
            "paper" => AidingConfig::paper(),
            "heading" => named.aiding_in(AidingMode::Heading),
            "full" => named.aiding_in(AidingMode::FullPose),
            "none" => named.aiding_in(AidingMode::None),
            other => {
                return Err(value_error(format!("aiding: {other:?} is not one of {AIDING}")));
            }
        };
        let mount = mount.map(|m| pose_from(m, "mount")).transpose()?.unwrap_or_default();
        let config = MapperConfig::new(named.detector, named.map, aiding)
            .with_loop_closure(loop_closure.then_some(named.loop_closure))
            .with_mount(mount);
        Ok(PyMapper { mapper: Mapper::new(config).map_err(value_error)? })
    }

    /// Processes one scan. `pose` is the localization source's
    /// `world_from_vehicle` for it (`world_from_sensor` without a mount),
    /// `(x_m, y_m, heading_rad)`; without one
    /// the mapper runs on the lines alone (the last estimated motion
    /// predicts). A stamped scan lets the estimator learn the source's
    /// heading-rate bias and deskew the scan. The Python lock is released
    /// while it works.
    #[pyo3(signature = (scan, pose=None))]
    fn step(
        &mut self,
        py: Python<'_>,
        scan: &PyScan,
        pose: Option<(f64, f64, f64)>,
    ) -> PyResult<PyStep> {
        let source = pose.map(|p| pose_from(p, "pose")).transpose()?;
        let mapper = &mut self.mapper;
        let step: MapperStep = py.detach(|| match source {
            Some(p) => mapper.process(&scan.scan, &p),
            None => mapper.process_without_source(&scan.scan),
        });
        Ok(PyStep {
            pose: pose_tuple(&step.pose),
            lines: PyLines::detected(self.mapper.lines()),
            report: step.report,
        })
    }

    /// The map's lines, world frame, with their ids, observations and
    /// status (rebuilt from the keyframes after each loop closure).
    #[getter]
    fn map(&self) -> PyLines {
        PyLines::map(self.mapper.map().lines())
    }

    /// The latest corrected pose `(x_m, y_m, heading_rad)`, `None` before
    /// the first scan.
    #[getter]
    fn pose(&self) -> Option<(f64, f64, f64)> {
        self.mapper.pose().as_ref().map(pose_tuple)
    }

    /// Optimizes the pose graph now (loop closure on) and re-anchors the
    /// map; returns what it did as a dict, `None` without loop closure.
    fn optimize<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(r) = self.mapper.optimize() else { return Ok(None) };
        let d = PyDict::new(py);
        d.set_item("kept", r.kept.map(|k| kebab(&format!("{k:?}"))))?;
        d.set_item("rounds", r.rounds)?;
        d.set_item("switched_off", r.switched_off)?;
        d.set_item("cost_before", r.cost_before)?;
        d.set_item("cost_after", r.cost_after)?;
        d.set_item("max_shift_m", r.max_shift_m)?;
        Ok(Some(d))
    }

    /// Every processed scan's pose as the pose graph now places it, `(n,
    /// 3)` (NaN rows for scans it cannot place); `None` without loop
    /// closure (the poses `step` returned are then final).
    fn trajectory<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.mapper.trajectory().map(|t| poses_array(py, t.into_iter())).transpose()
    }

    fn __repr__(&self) -> String {
        format!("Mapper({} map lines)", self.mapper.map().len())
    }
}

/// What one `Mapper.step` did.
#[pyclass(name = "Step", module = "pcaline", frozen)]
pub struct PyStep {
    pose: (f64, f64, f64),
    lines: PyLines,
    report: StepReport,
}

#[pymethods]
impl PyStep {
    /// The corrected `world_from_sensor`, `(x_m, y_m, heading_rad)`.
    #[getter]
    fn pose(&self) -> (f64, f64, f64) {
        self.pose
    }

    /// The scan's detected lines, sensor frame.
    #[getter]
    fn lines(&self) -> PyLines {
        self.lines.clone()
    }

    /// The aiding's report as a dict: `matches`, `rejected_gate`,
    /// `ambiguous`, `rejected_joint`, `unconfirmed`, `prediction`
    /// (`"source"` or `"constant-velocity"`), `covariance` (3x3, of `(x, y,
    /// heading)`), `correction_distance2`, `motion_noise_scale`,
    /// `measurement_noise_scale`, `heading_correction_rad`,
    /// `translation_correction_m`, `constrained_directions` and `fallback`
    /// (why the correction fell back, e.g. `"no-matches"`, or `None`).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.report;
        let d = PyDict::new(py);
        d.set_item("matches", r.matches)?;
        d.set_item("rejected_gate", r.rejected_gate)?;
        d.set_item("ambiguous", r.ambiguous)?;
        d.set_item("rejected_joint", r.rejected_joint)?;
        d.set_item("unconfirmed", r.unconfirmed)?;
        d.set_item("prediction", kebab(&format!("{:?}", r.prediction)))?;
        let c = &r.covariance;
        let rows: Vec<f64> = (0..3).flat_map(|i| (0..3).map(move |j| c[(i, j)])).collect();
        d.set_item("covariance", numpy::PyArray1::from_vec(py, rows).reshape([3, 3])?)?;
        d.set_item("correction_distance2", r.correction_distance2)?;
        d.set_item("motion_noise_scale", r.motion_noise_scale)?;
        d.set_item("measurement_noise_scale", r.measurement_noise_scale)?;
        d.set_item("heading_correction_rad", r.heading_correction_rad)?;
        let t = r.translation_correction_m;
        d.set_item("translation_correction_m", (t.x, t.y))?;
        d.set_item("constrained_directions", r.constrained_directions)?;
        d.set_item("fallback", r.fallback.map(|f| kebab(&format!("{f:?}"))))?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "Step(pose={:?}, {} lines, {} matches)",
            self.pose,
            self.lines.lines.len(),
            self.report.matches
        )
    }
}
