//! A simulated 2D LIDAR with exact ground truth: the Hokuyo UTM-30LX-EW of the
//! paper (and a SICK LMS-style scanner), ray-cast with parry2d against the
//! walls of a [`Scene`], with range noise, outliers, dropouts, mixed pixels,
//! motion skew and a tilting scan plane, along a trajectory, with a corrupted
//! odometry standing in for the paper's localization algorithm.
//!
//! Everything is seeded: the same scene and seed give the same scans, bit for
//! bit, whatever the order in which frames are requested.
//!
//! ```
//! use pcaline_sim::{MazeConfig, Simulator, generate_maze};
//!
//! let scene = generate_maze(&MazeConfig::small("demo"), 7).unwrap();
//! let sim = Simulator::new(&scene, 1).unwrap();
//! let frame = sim.frame(0).unwrap();
//! assert_eq!(frame.scan.len(), 1081);
//! // Every beam that hit a wall knows which one, and where.
//! let hit = frame.beams.iter().find(|b| b.wall.is_some()).unwrap();
//! assert!(hit.range_m > 0.0 && hit.point.is_some());
//! ```

mod maze;
mod odometry;
mod rng;
mod scene;
mod sensor;
mod simulate;
mod surfaces;
mod trajectory;
mod wall_grid;
mod world;

pub use maze::{MazeConfig, WallStyle, generate_maze};
pub use odometry::OdometryModel;
pub use scene::{
    MAX_SCENE_COORDINATE_M, MAX_SCENE_SCANS, MAX_SCENE_WALL_LENGTH_M, OdometrySpec, Scene,
    SceneError, SensorKind, SensorSpec, Shape, StartPose, TiltSpec, TrajectorySpec,
};
pub use sensor::{Faults, SensorModel, Tilt};
pub use simulate::{BeamTruth, Fault, SimFrame, Simulator, WallRun};
pub use surfaces::collinear_surfaces;
pub use trajectory::Trajectory;
pub use world::{Hit, Wall, World};
