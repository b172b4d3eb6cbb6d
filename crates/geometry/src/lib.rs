//! Types and frames shared by every pcaline crate: [`Scan`] (ROS `LaserScan`
//! semantics), polar to Cartesian conversion with a cached bearing table (paper
//! eq. 1), [`Pose2`], [`LineSegment`] in Hessian normal form, angle helpers, the
//! range-noise model and the shared configuration error.
//!
//! Conventions: x forward, y left, angles counter-clockwise positive, radians.
//! Ranges are `f32` as drivers publish them; everything derived is `f64`.
//!
//! ```
//! use pcaline_geometry::{BearingTable, Scan, ScanPoints};
//!
//! // Three beams at -10°, 0° and +10°; the middle one is a dropout (+inf).
//! let scan = Scan::new(-10f32.to_radians(), 10f32.to_radians(), 0.1, 30.0,
//!                      vec![2.0, f32::INFINITY, 2.0]);
//! let mut table = BearingTable::default();
//! let mut points = ScanPoints::default();
//! points.fill_from(&scan, &mut table);
//! assert_eq!(points.len(), 2); // the dropout is not a point
//! assert!((points.point(0).x - 2.0 * 10f64.to_radians().cos()).abs() < 1e-6);
//! ```

mod angle;
mod bearings;
mod config_error;
mod line;
mod noise;
mod pose;
mod relation;
mod scan;
mod sensor_profile;
mod twist;

pub use angle::{line_angle_diff, wrap_angle};
pub use bearings::{BearingTable, ScanPoints, polar_to_cartesian};
pub use config_error::ConfigError;
pub use line::{LineSegment, SlopeIntercept, point_segment_distance};
pub use nalgebra::{Matrix2, Matrix3, Point2, Vector2, Vector3};
pub use noise::RangeNoise;
pub use pose::Pose2;
pub use relation::Relation;
pub use scan::Scan;
pub use sensor_profile::SensorProfile;
pub use twist::Twist2;
