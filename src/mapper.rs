//! [`Mapper`]: the whole loop of the paper's section 2.1: scan and source pose
//! in, corrected pose and updated line map out.

use crate::{Config, LineDetector};
use pcaline_aiding::{Aiding, AidingConfig, SensorLine, StepReport};
use pcaline_geometry::{ConfigError, Pose2, Scan};
use pcaline_mapping::{LineMap, MapConfig};

/// Configuration of a [`Mapper`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapperConfig {
    /// The line detector.
    pub detector: Config,
    /// The line map.
    pub map: MapConfig,
    /// The aiding.
    pub aiding: AidingConfig,
}

impl MapperConfig {
    /// The paper throughout: its detector, its map (eq. 8-10, endpoints
    /// extended only) and its heading aiding (eq. 11-14).
    pub fn paper() -> Self {
        MapperConfig {
            detector: Config::paper(),
            map: MapConfig::paper(),
            aiding: AidingConfig::paper(),
        }
    }
}

impl Default for MapperConfig {
    /// The default detector, a refining map with the line lifecycle, and
    /// the estimator.
    fn default() -> Self {
        MapperConfig {
            detector: Config::default(),
            map: MapConfig::default(),
            aiding: AidingConfig::estimator(),
        }
    }
}

/// What one scan did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapperStep {
    /// The corrected `world_from_sensor`.
    pub pose: Pose2,
    /// Lines detected in the scan.
    pub lines: usize,
    /// The aiding's report.
    pub report: StepReport,
}

/// Detection, mapping and aiding, scan by scan.
///
/// ```
/// use pcaline::{Mapper, MapperConfig, Pose2, Scan};
///
/// let mut mapper = Mapper::new(MapperConfig::default()).unwrap();
/// let angle_min = -30f32.to_radians();
/// let inc = 0.25f32.to_radians();
/// let ranges: Vec<f32> = (0..241).map(|i| 2.0 / (angle_min + i as f32 * inc).cos()).collect();
/// let scan = Scan::new(angle_min, inc, 0.1, 30.0, ranges);
/// let step = mapper.process(&scan, &Pose2::identity());
/// assert_eq!(step.lines, 1);
/// assert_eq!(mapper.map().len(), 1);
/// ```
#[derive(Debug, Clone)]
pub struct Mapper {
    detector: LineDetector,
    aiding: Aiding,
    lines: Vec<SensorLine>,
    /// The last stamped source pose (for the deskew velocity).
    last_source: Option<(f64, Pose2)>,
}

impl Mapper {
    /// A mapper with an empty map.
    pub fn new(config: MapperConfig) -> Result<Self, ConfigError> {
        Ok(Mapper {
            detector: LineDetector::new(config.detector)?,
            aiding: Aiding::new(config.aiding, config.map)?,
            lines: Vec::new(),
            last_source: None,
        })
    }

    /// Processes one scan with the localization source's pose estimate for
    /// it. A stamped scan ([`Scan::stamp_s`]) lets the estimator learn the
    /// source's heading-rate bias, and a stamp going backwards skips it.
    pub fn process(&mut self, scan: &Scan, source_pose: &Pose2) -> MapperStep {
        // Deskew with the source's velocity over the last step, when stamped.
        let velocity = match (self.last_source, scan.stamp_s) {
            (Some((t0, p0)), Some(t)) => p0.velocity_to(source_pose, t - t0),
            _ => None,
        };
        self.last_source = scan.stamp_s.map(|t| (t, *source_pose));
        self.detect(scan, velocity);
        let (pose, report) = match scan.stamp_s {
            Some(t) => self.aiding.step_at(t, source_pose, &self.lines),
            None => self.aiding.step(source_pose, &self.lines),
        };
        MapperStep { pose, lines: self.lines.len(), report }
    }

    /// Processes one scan without a localization source (LIDAR-only mode):
    /// the last estimated motion is the prediction, the line matches
    /// estimate the motion.
    pub fn process_without_source(&mut self, scan: &Scan) -> MapperStep {
        self.detect(scan, self.aiding.velocity());
        let (pose, report) = self.aiding.step_without_source(scan.stamp_s, &self.lines);
        MapperStep { pose, lines: self.lines.len(), report }
    }

    /// Processes one scan with the source's motion since the previous scan.
    pub fn process_increment(&mut self, scan: &Scan, increment: &Pose2) -> MapperStep {
        self.detect(scan, self.aiding.velocity());
        let (pose, report) = self.aiding.step_increment(increment, &self.lines);
        MapperStep { pose, lines: self.lines.len(), report }
    }

    /// Detects the scan's lines, deskewed with `velocity` when the scan
    /// carries its beam timing.
    fn detect(&mut self, scan: &Scan, velocity: Option<Pose2>) {
        self.lines.clear();
        let detection = self.detector.detect_moving(scan, velocity.as_ref());
        self.lines.extend(detection.lines.iter().map(SensorLine::from));
    }

    /// The map built so far.
    pub fn map(&self) -> &LineMap {
        self.aiding.map()
    }

    /// The latest corrected pose.
    pub fn pose(&self) -> Option<Pose2> {
        self.aiding.pose()
    }
}
