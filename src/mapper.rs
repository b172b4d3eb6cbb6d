//! [`Mapper`]: the whole loop of the paper's section 2.1: scan and source pose
//! in, corrected pose and updated line map out.

use crate::{Config, DetectedLine, LineDetector};
use pcaline_aiding::{
    AidingConfig, Localizer, LoopClosing, LoopClosureConfig, OptimizeReport, StepReport,
};
use pcaline_geometry::{ConfigError, Pose2, Scan, Twist2};
use pcaline_mapping::{LineMap, MapConfig};

/// Configuration of a [`Mapper`]. With feature `serde` it (de)serializes,
/// as every configuration does (JSON writes an infinite limit as `null`,
/// which reads back as infinite).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct MapperConfig {
    /// The line detector.
    pub detector: Config,
    /// The line map.
    pub map: MapConfig,
    /// The aiding.
    pub aiding: AidingConfig,
    /// Loop closure on top of the aiding (`None`: off).
    pub loop_closure: Option<LoopClosureConfig>,
    /// Where the LIDAR sits on the vehicle (`vehicle_from_sensor`: its
    /// offset forward and left in metres, and its yaw). The localization
    /// source gives `world_from_vehicle` and the mapper returns it; the
    /// map and the aiding work in `world_from_sensor = world_from_vehicle
    /// ∘ vehicle_from_sensor`. Identity (the default): the source gives the
    /// sensor's own pose, as the paper's setup and most logs do.
    #[cfg_attr(feature = "serde", serde(default))]
    pub vehicle_from_sensor: Pose2,
}

impl MapperConfig {
    /// A mapper of `detector`, `map` and `aiding`, without loop closure,
    /// with the sensor at the vehicle's origin ([`MapperConfig::with_loop_closure`],
    /// [`MapperConfig::with_mount`]).
    pub fn new(detector: Config, map: MapConfig, aiding: AidingConfig) -> Self {
        MapperConfig {
            detector,
            map,
            aiding,
            loop_closure: None,
            vehicle_from_sensor: Pose2::identity(),
        }
    }

    /// The same with the aiding `aiding`.
    pub fn with_aiding(self, aiding: AidingConfig) -> Self {
        MapperConfig { aiding, ..self }
    }

    /// The same with loop closure `loop_closure` (`None`: off).
    pub fn with_loop_closure(self, loop_closure: Option<LoopClosureConfig>) -> Self {
        MapperConfig { loop_closure, ..self }
    }

    /// The same with the LIDAR at `vehicle_from_sensor` on the vehicle.
    pub fn with_mount(self, vehicle_from_sensor: Pose2) -> Self {
        MapperConfig { vehicle_from_sensor, ..self }
    }

    /// The paper throughout: its detector, its map (eq. 8-10, endpoints
    /// extended only) and its heading aiding (eq. 11-14).
    pub fn paper() -> Self {
        MapperConfig {
            detector: Config::paper(),
            map: MapConfig::paper(),
            aiding: AidingConfig::paper(),
            loop_closure: None,
            vehicle_from_sensor: Pose2::identity(),
        }
    }
}

impl Default for MapperConfig {
    /// The default detector, a refining map with the line lifecycle, the
    /// estimator, and loop closure (as `pcaline map`).
    fn default() -> Self {
        MapperConfig {
            detector: Config::default(),
            map: MapConfig::default(),
            aiding: AidingConfig::estimator(),
            loop_closure: Some(LoopClosureConfig::standard()),
            vehicle_from_sensor: Pose2::identity(),
        }
    }
}

/// What one scan did.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct MapperStep {
    /// The corrected `world_from_vehicle` (`world_from_sensor` with the
    /// default mount).
    pub pose: Pose2,
    /// The corrected `world_from_sensor`, the pose the scan's lines were
    /// placed with.
    pub world_from_sensor: Pose2,
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
/// assert_eq!(mapper.lines()[0].line.n_points(), 241);
/// assert_eq!(mapper.map().len(), 1);
/// ```
#[derive(Debug, Clone)]
pub struct Mapper {
    detector: LineDetector,
    localizer: Localizer,
    vehicle_from_sensor: Pose2,
    sensor_from_vehicle: Pose2,
    /// The last scan's lines (the localizer takes them as they are).
    detected: Vec<DetectedLine>,
    /// The last stamped source pose (for the deskew velocity).
    last_source: Option<(f64, Pose2)>,
}

impl Mapper {
    /// A mapper with an empty map.
    pub fn new(config: MapperConfig) -> Result<Self, ConfigError> {
        let mount = config.vehicle_from_sensor;
        for (name, v) in [("x", mount.x()), ("y", mount.y()), ("heading", mount.heading())] {
            ConfigError::check_field(
                v.is_finite(),
                "vehicle_from_sensor",
                name,
                v,
                "must be finite",
            )?;
        }
        Ok(Mapper {
            detector: LineDetector::new(config.detector)?,
            localizer: Localizer::new(config.aiding, config.map, config.loop_closure)?,
            vehicle_from_sensor: mount,
            sensor_from_vehicle: mount.inverse(),
            detected: Vec::new(),
            last_source: None,
        })
    }

    /// Processes one scan with the localization source's pose estimate for
    /// it, `world_from_vehicle`. A stamped scan ([`Scan::stamp_s`]) lets the
    /// estimator learn the source's heading-rate bias, and a stamp going
    /// backwards skips it.
    pub fn process(&mut self, scan: &Scan, world_from_vehicle: &Pose2) -> MapperStep {
        let source = world_from_vehicle.compose(&self.vehicle_from_sensor);
        // Deskew with the source's velocity over the last step, when stamped.
        let velocity = match (self.last_source, scan.stamp_s) {
            (Some((t0, p0)), Some(t)) => p0.velocity_to(&source, t - t0),
            _ => None,
        };
        self.last_source = scan.stamp_s.map(|t| (t, source));
        self.detect(scan, velocity);
        let (pose, report) = self.localizer.step_scan(scan, &source, &self.detected);
        self.step(pose, report)
    }

    /// Processes one scan without a localization source (LIDAR-only mode):
    /// the scan registered to the previous one measures the motion, with the
    /// last estimated motion as its prior (the prediction alone when the
    /// registration is off or not trusted), and the line matches correct
    /// it.
    pub fn process_without_source(&mut self, scan: &Scan) -> MapperStep {
        self.last_source = None;
        self.detect(scan, self.localizer.velocity());
        let (pose, report) = self.localizer.step_scan_without_source(scan, &self.detected);
        self.step(pose, report)
    }

    /// The step's record from the corrected `world_from_sensor`.
    fn step(&self, world_from_sensor: Pose2, report: StepReport) -> MapperStep {
        MapperStep {
            pose: world_from_sensor.compose(&self.sensor_from_vehicle),
            world_from_sensor,
            lines: self.detected.len(),
            report,
        }
    }

    /// Detects the scan's lines, deskewed with `velocity` when the scan
    /// carries its beam timing.
    fn detect(&mut self, scan: &Scan, velocity: Option<Twist2>) {
        let detection = self.detector.detect_moving(scan, velocity.as_ref());
        self.detected.clear();
        self.detected.extend_from_slice(detection.lines);
    }

    /// The lines detected in the last processed scan, sensor frame (empty
    /// before the first scan).
    pub fn lines(&self) -> &[DetectedLine] {
        &self.detected
    }

    /// The map built so far (rebuilt from the keyframes after each loop
    /// closure).
    pub fn map(&self) -> &LineMap {
        self.localizer.map()
    }

    /// The latest corrected `world_from_vehicle`.
    pub fn pose(&self) -> Option<Pose2> {
        self.localizer.pose().map(|p| p.compose(&self.sensor_from_vehicle))
    }

    /// The localizer (the aiding, and loop closure when on): its map,
    /// velocity and graph, in the sensor's frame (`world_from_sensor`).
    pub fn localizer(&self) -> &Localizer {
        &self.localizer
    }

    /// The loop closure (its graph, keyframes and loops), when on.
    pub fn loop_closing(&self) -> Option<&LoopClosing> {
        self.localizer.loop_closing()
    }

    /// Optimizes the pose graph now (when loop closure is on); afterwards
    /// [`Mapper::trajectory`] gives the optimized trajectory.
    pub fn optimize(&mut self) -> Option<OptimizeReport> {
        self.localizer.optimize()
    }

    /// Every processed scan's `world_from_vehicle` as the pose graph now
    /// places it (loop closure on), `None` without loop closure: then the
    /// poses the steps returned are final.
    pub fn trajectory(&self) -> Option<Vec<Option<Pose2>>> {
        let to_vehicle = |p: Option<Pose2>| p.map(|p| p.compose(&self.sensor_from_vehicle));
        self.loop_closing().map(|l| l.trajectory().into_iter().map(to_vehicle).collect())
    }
}

#[cfg(all(test, feature = "serde"))]
mod tests {
    use super::*;

    #[test]
    fn every_mapper_preset_round_trips_through_json() {
        let with_paper_aiding =
            MapperConfig { aiding: AidingConfig::paper(), ..Default::default() };
        for config in [MapperConfig::paper(), MapperConfig::default(), with_paper_aiding] {
            let json = serde_json::to_string(&config).unwrap();
            let back: MapperConfig = serde_json::from_str(&json).unwrap();
            assert_eq!(back, config, "{json}");
        }
    }
}

#[cfg(test)]
mod mount_tests {
    use super::*;
    use pcaline_sim::{MazeConfig, Simulator, generate_maze};

    #[test]
    fn a_mounted_sensor_maps_as_the_sensor_itself() {
        let scene = generate_maze(&MazeConfig::small("mount").with_grid(3, 2), 5).unwrap();
        let sim = Simulator::new(&scene, 3).unwrap();
        // 30 cm forward, 10 cm right, turned 0.2 rad to the left.
        let vehicle_from_sensor = Pose2::new(0.3, -0.1, 0.2);
        let sensor_from_vehicle = vehicle_from_sensor.inverse();
        let mut plain = Mapper::new(MapperConfig::default()).unwrap();
        let mut mounted =
            Mapper::new(MapperConfig { vehicle_from_sensor, ..MapperConfig::default() }).unwrap();
        let close = |a: &Pose2, b: &Pose2| {
            (a.x() - b.x()).abs() < 1e-6
                && (a.y() - b.y()).abs() < 1e-6
                && pcaline_geometry::wrap_angle(a.heading() - b.heading()).abs() < 1e-9
        };
        for frame in sim.frames().step_by(4) {
            let world_from_sensor = frame.odometry_pose;
            let world_from_vehicle = world_from_sensor.compose(&sensor_from_vehicle);
            let a = plain.process(&frame.scan, &world_from_sensor);
            let b = mounted.process(&frame.scan, &world_from_vehicle);
            assert!(close(&b.world_from_sensor, &a.pose), "scan {}", frame.index);
            assert!(close(&b.pose, &a.pose.compose(&sensor_from_vehicle)), "scan {}", frame.index);
            assert_eq!(a.lines, b.lines);
        }
        assert!(plain.map().len() > 10);
        assert_eq!(plain.map().len(), mounted.map().len());
        let (p, m) = (plain.pose().unwrap(), mounted.pose().unwrap());
        assert!(close(&m, &p.compose(&sensor_from_vehicle)));
        let bad = Pose2::new(f64::NAN, 0.0, 0.0);
        let e = Mapper::new(MapperConfig { vehicle_from_sensor: bad, ..MapperConfig::default() });
        assert!(e.unwrap_err().to_string().contains("vehicle_from_sensor.x"));
    }
}
