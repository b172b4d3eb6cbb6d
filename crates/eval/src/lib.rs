//! Accuracy metrics of pcaline against exact ground truth: localization
//! errors of trajectories, and the quality of line maps against the true walls.
//! (Detection metrics and the paper's tables follow the protocol of the
//! design document, section 5.)
//!
//! ```
//! use pcaline_eval::trajectory_errors;
//! use pcaline_geometry::Pose2;
//! let truth = [Pose2::identity(), Pose2::new(1.0, 0.0, 0.0)];
//! let estimate = [Pose2::identity(), Pose2::new(1.0, 0.3, 0.1)];
//! let e = trajectory_errors(&estimate, &truth).unwrap();
//! assert!((e.position_final_m - 0.3).abs() < 1e-12);
//! assert!((e.heading_max_rad - 0.1).abs() < 1e-12);
//! ```

mod map_quality;
mod trajectory;

pub use map_quality::{MapQuality, VisibleWalls, map_quality};
pub use trajectory::{TrajectoryErrors, trajectory_errors};
