//! pcaline: PCA-based line detection from 2D LIDAR range data, after Opromolla
//! et al., "PCA-Based Line Detection from Range Data for Mapping and
//! Localization-Aiding of UAVs" (2017), and beyond it.
//!
//! This facade ties the layered crates together: [`LineDetector`] runs the
//! whole detection pipeline on a [`Scan`] (eq. 1, level-1 and level-2
//! clustering, PCA fit with the eigenvalue-ratio test, merge of collinear
//! pieces), with [`Config::paper`] reproducing the paper exactly; [`Mapper`]
//! adds the line map and localization aiding of the paper's section 2.1.
//!
//! ```
//! use pcaline::{Config, LineDetector, Scan};
//!
//! // A wall 2 m in front of the sensor, seen over 60° at 0.25°.
//! let n = 241;
//! let angle_min = -30f32.to_radians();
//! let inc = 0.25f32.to_radians();
//! let ranges = (0..n).map(|i| 2.0 / (angle_min + i as f32 * inc).cos()).collect();
//! let scan = Scan::new(angle_min, inc, 0.1, 30.0, ranges);
//!
//! let mut detector = LineDetector::new(Config::paper()).unwrap();
//! let detection = detector.detect(&scan);
//! assert_eq!(detection.lines.len(), 1);
//! let wall = &detection.lines[0].line;
//! assert!((wall.d() - 2.0).abs() < 1e-6 && wall.alpha().abs() < 1e-6);
//! ```

mod config;
mod detector;
mod mapper;

pub use config::{Config, NoisyScanTests};
pub use detector::{Detection, LineDetector};
pub use mapper::{Mapper, MapperConfig, MapperStep};
pub use pcaline_fitting::DetectedLine;

pub use pcaline_aiding as aiding;
pub use pcaline_fitting as fitting;
pub use pcaline_geometry as geometry;
pub use pcaline_mapping as mapping;
pub use pcaline_segmentation as segmentation;

pub use pcaline_geometry::{
    ConfigError, LineSegment, Point2, Pose2, RangeNoise, Scan, Twist2, Vector2,
};

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
