//! `pcaline.sim`: scenes (loaded or generated mazes) and the simulated
//! Hokuyo UTM-30LX-EW with exact ground truth per beam.

use crate::convert::{io_error, matrices_array, pose_tuple, poses_array, rows_array, value_error};
use crate::scan::PyScan;
use numpy::{PyArray1, PyArray2, PyArray3};
use pcaline_sim::{Fault, MazeConfig, Scene, SimFrame, Simulator, generate_maze};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

/// A scene: walls, obstacles, the sensor, the trajectory and the odometry
/// model (the scene files of `sim-scenes/`).
#[pyclass(name = "Scene", module = "pcaline.sim", frozen)]
#[derive(Debug, Clone)]
pub struct PyScene {
    pub scene: Scene,
}

#[pymethods]
impl PyScene {
    /// Loads a scene file (TOML, or JSON by extension). Raises
    /// `FileNotFoundError`/`OSError` when it cannot be read and
    /// `FormatError` naming the file and item when it is malformed or
    /// invalid.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let scene = pcaline_io::read_scene(&path).map_err(io_error)?;
        Ok(PyScene { scene })
    }

    /// Writes the scene (TOML, or JSON by extension), atomically.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        pcaline_io::write_scene(&path, &self.scene).map_err(io_error)
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> &str {
        &self.scene.name
    }

    /// The scene's description.
    #[getter]
    fn description(&self) -> &str {
        &self.scene.description
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}: {} walls, {} obstacles)",
            self.scene.name,
            self.scene.walls.len(),
            self.scene.obstacles.len()
        )
    }
}

/// Generates a maze scene (as `pcaline scene generate`): `cols` x `rows`
/// cells of `cell_m` metres with double walls, doorways, loops, rooms and
/// `clutter` boxes, and a tour through every cell. The same seed gives the
/// same maze. Raises `ValueError` naming the field for a bad size.
#[pyfunction]
#[pyo3(signature = (seed, cols=5, rows=4, cell_m=2.5, clutter=6, name="maze"))]
#[pyo3(name = "generate_maze")]
pub fn generate_maze_py(
    seed: u64,
    cols: usize,
    rows: usize,
    cell_m: f64,
    clutter: usize,
    name: &str,
) -> PyResult<PyScene> {
    let mut config = MazeConfig::small(name);
    (config.cols, config.rows, config.cell_m, config.clutter) = (cols, rows, cell_m, clutter);
    Ok(PyScene { scene: generate_maze(&config, seed).map_err(value_error)? })
}

/// The simulated scans of a scene along its trajectory, with exact ground
/// truth. Everything is seeded: the same scene and seed give the same
/// scans, bit for bit, in any order of access.
#[pyclass(name = "Simulator", module = "pcaline.sim", frozen)]
pub struct PySimulator {
    pub sim: Arc<Simulator>,
}

#[pymethods]
impl PySimulator {
    /// A simulator of `scene` with noise stream `seed`. Raises `ValueError`
    /// for a scene that cannot be simulated.
    #[new]
    #[pyo3(signature = (scene, seed=1))]
    fn new(scene: &PyScene, seed: u64) -> PyResult<Self> {
        let sim = Simulator::new(&scene.scene, seed).map_err(value_error)?;
        Ok(PySimulator { sim: Arc::new(sim) })
    }

    fn __len__(&self) -> usize {
        self.sim.len()
    }

    /// Scan `index` with its ground truth; negative indices count from the
    /// end. Raises `IndexError` past either end.
    fn __getitem__(&self, index: isize) -> PyResult<PyFrame> {
        let n = self.sim.len() as isize;
        let k = if index < 0 { index + n } else { index };
        let frame =
            (0..n).contains(&k).then(|| self.sim.frame(k as usize)).flatten().ok_or_else(|| {
                pyo3::exceptions::PyIndexError::new_err(format!("frame {index} of {n}"))
            })?;
        Ok(PyFrame { frame, sim: Arc::clone(&self.sim) })
    }

    /// The world's walls (obstacles included), `(n, 2, 2)`: `[wall][a|b][x|y]`.
    #[getter]
    fn walls<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let flat = self.sim.world().walls().iter().flat_map(|w| [w.a.x, w.a.y, w.b.x, w.b.y]);
        matrices_array(py, flat.collect())
    }

    /// The true `world_from_sensor` of every scan, `(n, 3)`.
    #[getter]
    fn true_poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        poses_array(py, self.sim.true_poses().iter().map(|p| Some(*p)))
    }

    /// The odometry's estimate of every scan's pose, `(n, 3)`.
    #[getter]
    fn odometry_poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        poses_array(py, self.sim.odometry_poses().iter().map(|p| Some(*p)))
    }

    fn __repr__(&self) -> String {
        format!("Simulator({} scans, {} walls)", self.sim.len(), self.sim.world().walls().len())
    }
}

/// One simulated scan and its ground truth.
#[pyclass(name = "Frame", module = "pcaline.sim", frozen)]
pub struct PyFrame {
    pub frame: SimFrame,
    pub sim: Arc<Simulator>,
}

#[pymethods]
impl PyFrame {
    /// Index along the trajectory.
    #[getter]
    fn index(&self) -> usize {
        self.frame.index
    }

    /// Time of the first beam, seconds from the start (also the scan's stamp).
    #[getter]
    fn time(&self) -> f64 {
        self.frame.time_s
    }

    /// True `world_from_sensor`, `(x_m, y_m, heading_rad)`.
    #[getter]
    fn true_pose(&self) -> (f64, f64, f64) {
        pose_tuple(&self.frame.true_pose)
    }

    /// The odometry's estimate of the same pose.
    #[getter]
    fn odometry_pose(&self) -> (f64, f64, f64) {
        pose_tuple(&self.frame.odometry_pose)
    }

    /// The scan, as a driver would publish it (stamped, with the odometry
    /// pose as its `odometry`).
    #[getter]
    fn scan(&self) -> PyScan {
        PyScan {
            scan: self.frame.scan.clone(),
            pose: None,
            odometry: Some(self.frame.odometry_pose),
            sensor: None,
            position: self.frame.index,
        }
    }

    /// The wall each beam hit (an index into `Simulator.walls`), -1 where
    /// nothing is in range.
    #[getter]
    fn beam_wall<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_iter(py, self.frame.beams.iter().map(|b| b.wall.map_or(-1, i64::from)))
    }

    /// The true (noise-free) range of each beam, metres; inf where nothing
    /// is hit.
    #[getter]
    fn beam_true_range<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_iter(py, self.frame.beams.iter().map(|b| b.range_m))
    }

    /// The true hit point of each beam, world frame, `(n, 2)`; NaN rows
    /// where nothing is hit.
    #[getter]
    fn beam_point<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let flat =
            self.frame.beams.iter().flat_map(|b| b.point.map_or([f64::NAN; 2], |p| [p.x, p.y]));
        rows_array(py, 2, flat.collect())
    }

    /// The fault of each beam: 0 none, 1 displaced, 2 clutter, 3 dropout,
    /// 4 mixed pixel (255: a kind of fault newer than this package).
    #[getter]
    fn beam_fault<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u8>> {
        PyArray1::from_iter(
            py,
            self.frame.beams.iter().map(|b| match b.fault {
                Fault::None => 0,
                Fault::Displaced => 1,
                Fault::Clutter => 2,
                Fault::Dropout => 3,
                Fault::MixedPixel => 4,
                _ => u8::MAX,
            }),
        )
    }

    fn __repr__(&self) -> String {
        format!("Frame({} at {:.3} s)", self.frame.index, self.frame.time_s)
    }
}
