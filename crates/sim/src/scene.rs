//! [`Scene`]: a simulated environment as read from a scene file (walls,
//! obstacles, sensor, trajectory, odometry errors), and its validation.
//!
//! The types derive serde with unknown keys refused; reading files is the `io`
//! crate's job. See `sim-scenes/README.md` for the schema with an example.

use crate::{OdometryModel, SensorModel, Tilt, Trajectory, Wall, World};
use pcaline_geometry::{Point2, Pose2, RangeNoise, Vector2};
use serde::{Deserialize, Serialize};

/// A scene: the world, the sensor, and how the vehicle moves through it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name.
    pub name: String,
    /// What the scene is for.
    #[serde(default)]
    pub description: String,
    /// The simulated sensor.
    #[serde(default)]
    pub sensor: SensorSpec,
    /// Walls, as polylines or closed polygons.
    #[serde(default)]
    pub walls: Vec<Shape>,
    /// Named obstacles (pillars, furniture, clutter), usually closed polygons.
    #[serde(default)]
    pub obstacles: Vec<Shape>,
    /// The true motion.
    pub trajectory: TrajectorySpec,
    /// Errors of the simulated localization source.
    #[serde(default)]
    pub odometry: OdometrySpec,
}

/// A polyline (or closed polygon) of walls.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shape {
    /// Name, used in error messages and ground truth.
    #[serde(default)]
    pub name: String,
    /// Vertices `[x, y]` in metres, world frame.
    pub points: Vec<[f64; 2]>,
    /// Join the last vertex back to the first.
    #[serde(default)]
    pub closed: bool,
}

/// The sensor of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorSpec {
    /// Base model.
    pub model: SensorKind,
    /// Replaces the model's range noise with a constant sigma, metres.
    pub range_sigma_m: Option<f64>,
    /// Rounds every range to a multiple of this step, metres, instead of
    /// the model's resolution ([`SensorModel::range_resolution_m`]); 0: no
    /// rounding.
    pub range_resolution_m: Option<f64>,
    /// Outlier probability per beam.
    pub outlier_probability: f64,
    /// Dropout probability per beam.
    pub dropout_probability: f64,
    /// Mixed-pixel probability per beam at a depth edge.
    pub mixed_pixel_probability: f64,
    /// Beams taken at their own times within the scan.
    pub motion_skew: bool,
    /// Sway of the scan plane.
    pub tilt: Option<TiltSpec>,
}

impl Default for SensorSpec {
    fn default() -> Self {
        SensorSpec {
            model: SensorKind::Utm30lxEw,
            range_sigma_m: None,
            range_resolution_m: None,
            outlier_probability: 0.0,
            dropout_probability: 0.0,
            mixed_pixel_probability: 0.0,
            motion_skew: false,
            tilt: None,
        }
    }
}

/// The base sensor models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum SensorKind {
    /// [`SensorModel::utm30lx_ew`].
    #[serde(rename = "utm30lx-ew")]
    Utm30lxEw,
    /// [`SensorModel::sick_lms_180`].
    #[serde(rename = "sick-lms-180")]
    SickLms180,
    /// [`SensorModel::urg_04lx`].
    #[serde(rename = "urg-04lx")]
    Urg04lx,
    /// [`SensorModel::rplidar`].
    #[serde(rename = "rplidar")]
    Rplidar,
}

/// Largest tilt amplitude of a scene file, degrees: the simulator's 1.2 rad.
const MAX_TILT_DEG: f64 = 1.2 * 180.0 / std::f64::consts::PI;

/// Sway of the scan plane, in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TiltSpec {
    /// Roll amplitude, degrees.
    pub roll_amplitude_deg: f64,
    /// Pitch amplitude, degrees.
    pub pitch_amplitude_deg: f64,
    /// Period, seconds.
    pub period_s: f64,
}

/// The true motion: start pose and waypoints.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySpec {
    /// Start pose.
    pub start: StartPose,
    /// Waypoints `[x, y]` visited in order.
    pub waypoints: Vec<[f64; 2]>,
    /// Driving speed, m/s.
    #[serde(default = "default_speed")]
    pub speed_m_s: f64,
    /// Turning rate in place, degrees/s.
    #[serde(default = "default_yaw_rate")]
    pub yaw_rate_deg_s: f64,
    /// Times the path is driven (returning to the start in between).
    #[serde(default = "default_laps")]
    pub laps: u32,
    /// Scans per second; the sensor's rate when absent.
    #[serde(default)]
    pub scan_rate_hz: Option<f64>,
}

fn default_speed() -> f64 {
    1.0
}
fn default_yaw_rate() -> f64 {
    90.0
}
fn default_laps() -> u32 {
    1
}

/// A pose with the heading in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartPose {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, degrees counter-clockwise from x.
    #[serde(default)]
    pub heading_deg: f64,
}

/// Odometry errors, in the units people quote them in.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OdometrySpec {
    /// Heading-rate bias, degrees/s.
    pub heading_rate_bias_deg_s: f64,
    /// Heading random walk, degrees/sqrt(s).
    pub heading_random_walk_deg_sqrt_s: f64,
    /// Relative speed error.
    pub speed_scale_error: f64,
    /// Position random walk, m/sqrt(s).
    pub position_random_walk_m_sqrt_s: f64,
}

/// A scene that cannot be simulated, naming the offending item.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{item}: {message}")]
pub struct SceneError {
    /// The item, as a path into the scene (`walls[2] "north"`, `trajectory.speed_m_s`).
    pub item: String,
    /// What is wrong with it.
    pub message: String,
}

/// Vertices farther than this from the origin, metres, are refused: no
/// LIDAR scene needs them, and evaluation bins every wall in 5 cm.
pub const MAX_SCENE_COORDINATE_M: f64 = 1e5;
/// The most wall and obstacle length a scene may hold, metres.
pub const MAX_SCENE_WALL_LENGTH_M: f64 = 1e6;
/// The most scans a scene's run may take (seven hours at 40 Hz).
pub const MAX_SCENE_SCANS: f64 = 1e6;
/// A start or waypoint from which more than this fraction of directions
/// meets no wall lies outside the walls (a door in a room's wall lets
/// through a few directions, the outside of a room at least a quarter).
const MAX_ESCAPING_FRACTION: f64 = 0.25;

fn err(item: impl Into<String>, message: impl Into<String>) -> SceneError {
    SceneError { item: item.into(), message: message.into() }
}

impl Scene {
    /// Checks the scene: every shape has at least 2 finite vertices (3 when
    /// closed) and no zero-length wall; there is at least one wall; the sensor
    /// and odometry values are valid; the trajectory has a positive speed, yaw
    /// rate and scan rate, starts and turns inside the walls (not outside
    /// them, not inside an obstacle) and never passes through a wall or
    /// obstacle. Work is bounded: vertices within [`MAX_SCENE_COORDINATE_M`], at
    /// most [`MAX_SCENE_WALL_LENGTH_M`] of walls and [`MAX_SCENE_SCANS`] scans.
    pub fn validate(&self) -> Result<(), SceneError> {
        for (kind, shapes) in [("walls", &self.walls), ("obstacles", &self.obstacles)] {
            for (i, shape) in shapes.iter().enumerate() {
                let item = shape_item(kind, i, shape);
                let min = if shape.closed { 3 } else { 2 };
                if shape.points.len() < min {
                    return Err(err(
                        item,
                        format!("needs at least {min} vertices, has {}", shape.points.len()),
                    ));
                }
                for (k, p) in shape.points.iter().enumerate() {
                    if !p[0].is_finite() || !p[1].is_finite() {
                        return Err(err(item, format!("vertex {k} is not finite: {p:?}")));
                    }
                    if p[0].abs() > MAX_SCENE_COORDINATE_M || p[1].abs() > MAX_SCENE_COORDINATE_M {
                        return Err(err(
                            item,
                            format!("vertex {k} {p:?} lies beyond ±{MAX_SCENE_COORDINATE_M:e} m"),
                        ));
                    }
                }
                for (k, (a, b)) in segments(shape).enumerate() {
                    if (b - a).norm() < 1e-9 {
                        return Err(err(item, format!("segment {k} has zero length at {a}")));
                    }
                }
            }
        }
        if self.walls.is_empty() && self.obstacles.is_empty() {
            return Err(err("walls", "the scene has no walls"));
        }
        let walls = self.world_walls();
        let length: f64 = walls.iter().map(|w| (w.b - w.a).norm()).sum();
        if length > MAX_SCENE_WALL_LENGTH_M {
            return Err(err(
                "walls",
                format!("{length:.0} m of walls, more than {MAX_SCENE_WALL_LENGTH_M:e} m"),
            ));
        }
        // The file's tilt is in degrees: checked here, so the error names
        // the key the file writes (the model's check is in radians).
        if let Some(t) = &self.sensor.tilt {
            for (item, a) in [
                ("sensor.tilt.roll_amplitude_deg", t.roll_amplitude_deg),
                ("sensor.tilt.pitch_amplitude_deg", t.pitch_amplitude_deg),
            ] {
                if a.is_nan() || a.abs() >= MAX_TILT_DEG {
                    return Err(err(item, format!("must be below {MAX_TILT_DEG:.1}°, is {a}")));
                }
            }
        }
        self.sensor_model().validate().map_err(|e| err("sensor", e.to_string()))?;
        self.odometry_model().validate().map_err(|e| err("odometry", e.to_string()))?;
        let t = &self.trajectory;
        for (item, v) in [
            ("trajectory.speed_m_s", t.speed_m_s),
            ("trajectory.yaw_rate_deg_s", t.yaw_rate_deg_s),
            ("trajectory.scan_rate_hz", t.scan_rate_hz.unwrap_or(1.0)),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(err(item, format!("must be finite and > 0, is {v}")));
            }
        }
        let start = [t.start.x, t.start.y];
        if !start.iter().chain([t.start.heading_deg].iter()).all(|v| v.is_finite()) {
            return Err(err("trajectory.start", "is not finite"));
        }
        let (lo, hi) = self.bounds();
        let mut path = vec![("trajectory.start".to_string(), start)];
        for (i, w) in t.waypoints.iter().enumerate() {
            path.push((format!("trajectory.waypoints[{i}]"), *w));
        }
        for (item, p) in &path {
            if !p[0].is_finite() || !p[1].is_finite() {
                return Err(err(item.clone(), format!("is not finite: {p:?}")));
            }
            if p[0] < lo.x || p[0] > hi.x || p[1] < lo.y || p[1] > hi.y {
                return Err(err(item.clone(), format!("{p:?} lies outside every wall")));
            }
            let at = Point2::new(p[0], p[1]);
            let escaping = escaping_fraction(&at, &walls);
            if escaping > MAX_ESCAPING_FRACTION {
                return Err(err(
                    item.clone(),
                    format!(
                        "{p:?} lies outside the walls ({:.0}% of the directions from it meet no wall)",
                        100.0 * escaping
                    ),
                ));
            }
            for (i, o) in self.obstacles.iter().enumerate() {
                if o.closed && inside_polygon(&at, &o.points) {
                    return Err(err(
                        item.clone(),
                        format!("{p:?} lies inside {}", shape_item("obstacles", i, o)),
                    ));
                }
            }
        }
        let rate_hz = self.sensor_model().rate_hz;
        let one_lap_s = self.trajectory_of_laps(1).duration_s();
        let lap_s = self.trajectory_of_laps(2).duration_s() - one_lap_s;
        let scans = (one_lap_s + f64::from(t.laps.max(1) - 1) * lap_s) * rate_hz;
        if scans.is_nan() || scans > MAX_SCENE_SCANS {
            return Err(err(
                "trajectory",
                format!(
                    "the run would take {scans:.3e} scans, more than {MAX_SCENE_SCANS:e}: shorten the \
                     path, lower laps or scan_rate_hz, or raise speed_m_s"
                ),
            ));
        }
        let mut legs: Vec<_> = path.windows(2).map(|w| (w[1].0.clone(), w[0].1, w[1].1)).collect();
        if t.laps > 1
            && let Some(last) = path.last()
        {
            legs.push(("trajectory (return to start)".into(), last.1, start));
        }
        for (item, a, b) in legs {
            let (a, b) = (Point2::new(a[0], a[1]), Point2::new(b[0], b[1]));
            for w in self.world_walls() {
                if segments_cross(&a, &b, &w.a, &w.b) {
                    let shape = self.shape_label(w.shape);
                    return Err(err(
                        item,
                        format!("the path from {a} to {b} passes through {shape}"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The wall segments of all shapes, walls first, then obstacles.
    pub fn world_walls(&self) -> Vec<Wall> {
        self.walls
            .iter()
            .chain(self.obstacles.iter())
            .enumerate()
            .flat_map(|(shape, s)| segments(s).map(move |(a, b)| Wall { a, b, shape }))
            .filter(|w| (w.b - w.a).norm() >= 1e-9)
            .collect()
    }

    /// The indexed world.
    pub fn world(&self) -> World {
        World::new(self.world_walls())
    }

    /// A label of shape `index` (walls first, then obstacles), for messages and ground truth.
    pub fn shape_label(&self, index: usize) -> String {
        if index < self.walls.len() {
            shape_item("walls", index, &self.walls[index])
        } else {
            let i = index - self.walls.len();
            self.obstacles
                .get(i)
                .map_or_else(|| format!("shape {index}"), |s| shape_item("obstacles", i, s))
        }
    }

    /// Axis-aligned bounds of all vertices.
    pub fn bounds(&self) -> (Point2<f64>, Point2<f64>) {
        let mut lo = Point2::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        for s in self.walls.iter().chain(self.obstacles.iter()) {
            for p in &s.points {
                lo = Point2::new(lo.x.min(p[0]), lo.y.min(p[1]));
                hi = Point2::new(hi.x.max(p[0]), hi.y.max(p[1]));
            }
        }
        (lo, hi)
    }

    /// The sensor model with this scene's overrides.
    pub fn sensor_model(&self) -> SensorModel {
        let s = &self.sensor;
        let mut m = match s.model {
            SensorKind::Utm30lxEw => SensorModel::utm30lx_ew(),
            SensorKind::SickLms180 => SensorModel::sick_lms_180(),
            SensorKind::Urg04lx => SensorModel::urg_04lx(),
            SensorKind::Rplidar => SensorModel::rplidar(),
        };
        if let Some(sigma) = s.range_sigma_m {
            m.noise = RangeNoise::constant(sigma);
        }
        if let Some(step) = s.range_resolution_m {
            m.range_resolution_m = step;
        }
        m.faults.outlier_probability = s.outlier_probability;
        m.faults.dropout_probability = s.dropout_probability;
        m.faults.mixed_pixel_probability = s.mixed_pixel_probability;
        m.motion_skew = s.motion_skew;
        m.tilt = s.tilt.map(|t| Tilt {
            roll_amplitude_rad: t.roll_amplitude_deg.to_radians(),
            pitch_amplitude_rad: t.pitch_amplitude_deg.to_radians(),
            period_s: t.period_s,
        });
        if let Some(rate) = self.trajectory.scan_rate_hz {
            m.rate_hz = rate;
        }
        m
    }

    /// The true motion.
    pub fn trajectory(&self) -> Trajectory {
        self.trajectory_of_laps(self.trajectory.laps)
    }

    /// The true motion driven `laps` times.
    fn trajectory_of_laps(&self, laps: u32) -> Trajectory {
        let t = &self.trajectory;
        let waypoints: Vec<_> = t.waypoints.iter().map(|p| Point2::new(p[0], p[1])).collect();
        Trajectory::new(
            Pose2::new(t.start.x, t.start.y, t.start.heading_deg.to_radians()),
            &waypoints,
            t.speed_m_s,
            t.yaw_rate_deg_s.to_radians(),
            laps,
        )
    }

    /// The odometry error model.
    pub fn odometry_model(&self) -> OdometryModel {
        let o = &self.odometry;
        OdometryModel {
            heading_rate_bias_rad_s: o.heading_rate_bias_deg_s.to_radians(),
            heading_random_walk_rad_sqrt_s: o.heading_random_walk_deg_sqrt_s.to_radians(),
            speed_scale_error: o.speed_scale_error,
            position_random_walk_m_sqrt_s: o.position_random_walk_m_sqrt_s,
        }
    }
}

fn shape_item(kind: &str, i: usize, shape: &Shape) -> String {
    if shape.name.is_empty() {
        format!("{kind}[{i}]")
    } else {
        format!("{kind}[{i}] \"{}\"", shape.name)
    }
}

/// The segments of a shape, closing it when asked.
fn segments(shape: &Shape) -> impl Iterator<Item = (Point2<f64>, Point2<f64>)> + '_ {
    let pts = &shape.points;
    let n = pts.len();
    let count = if shape.closed && n >= 3 { n } else { n.saturating_sub(1) };
    (0..count).map(move |i| {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        (Point2::new(a[0], a[1]), Point2::new(b[0], b[1]))
    })
}

/// The fraction of 72 directions (every 5°) in which a ray from `p` meets
/// no wall.
fn escaping_fraction(p: &Point2<f64>, walls: &[Wall]) -> f64 {
    const RAYS: usize = 72;
    let escaping = (0..RAYS)
        .filter(|k| {
            let angle = (*k as f64 + 0.5) * std::f64::consts::TAU / RAYS as f64;
            let u = Vector2::new(angle.cos(), angle.sin());
            !walls.iter().any(|w| ray_hits(p, &u, &w.a, &w.b))
        })
        .count();
    escaping as f64 / RAYS as f64
}

/// True when the ray from `p` along `u` meets the segment `a-b`.
fn ray_hits(p: &Point2<f64>, u: &Vector2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> bool {
    let (e, f) = (b - a, a - p);
    let den = u.x * e.y - u.y * e.x;
    if den.abs() < 1e-15 {
        return false;
    }
    let t = (f.x * e.y - f.y * e.x) / den;
    let s = (f.x * u.y - f.y * u.x) / den;
    t > 0.0 && (0.0..=1.0).contains(&s)
}

/// Even-odd test of `p` against the closed polygon `points`.
fn inside_polygon(p: &Point2<f64>, points: &[[f64; 2]]) -> bool {
    let n = points.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        if (a[1] > p.y) != (b[1] > p.y) {
            let x = a[0] + (p.y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// True when segments `a-b` and `c-d` properly cross or touch.
fn segments_cross(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>, d: &Point2<f64>) -> bool {
    let cross = |o: &Point2<f64>, p: &Point2<f64>, q: &Point2<f64>| {
        (p.x - o.x) * (q.y - o.y) - (p.y - o.y) * (q.x - o.x)
    };
    let (d1, d2) = (cross(c, d, a), cross(c, d, b));
    let (d3, d4) = (cross(a, b, c), cross(a, b, d));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && (d1 != 0.0 || d2 != 0.0 || d3 != 0.0 || d4 != 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_scene() -> Scene {
        Scene {
            name: "t".into(),
            description: String::new(),
            sensor: SensorSpec::default(),
            walls: vec![Shape {
                name: "outer".into(),
                points: vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]],
                closed: true,
            }],
            obstacles: vec![],
            trajectory: TrajectorySpec {
                start: StartPose { x: 1.0, y: 1.0, heading_deg: 0.0 },
                waypoints: vec![[9.0, 1.0], [9.0, 9.0]],
                speed_m_s: 1.0,
                yaw_rate_deg_s: 90.0,
                laps: 1,
                scan_rate_hz: None,
            },
            odometry: OdometrySpec::default(),
        }
    }

    #[test]
    fn valid_scene() {
        let s = square_scene();
        assert_eq!(s.validate(), Ok(()));
        assert_eq!(s.world_walls().len(), 4);
    }

    /// Scenes that pass a bounding-box test but that a run cannot handle:
    /// huge coordinates, runs of unbounded length, a start outside an
    /// L-shaped room or inside an obstacle.
    #[test]
    fn work_is_bounded_and_the_path_is_inside() {
        let mut s = square_scene();
        s.walls[0].points[2] = [1e20, 1e20];
        assert!(s.validate().unwrap_err().to_string().contains("beyond"));
        for (edit, what) in [
            ((|t: &mut TrajectorySpec| t.laps = 100_000_000) as fn(&mut TrajectorySpec), "scans"),
            (|t| t.speed_m_s = 1e-6, "scans"),
            (|t| t.scan_rate_hz = Some(1e9), "scans"),
        ] {
            let mut s = square_scene();
            edit(&mut s.trajectory);
            let e = s.validate().unwrap_err();
            assert!(e.item == "trajectory" && e.message.contains(what), "{e}");
        }
        let mut s = square_scene();
        s.walls[0].points = vec![[0.0, 0.0], [1e6, 0.0], [1e6, 2.0], [0.0, 2.0]];
        assert!(s.validate().is_err(), "a 10^6 m corridor");
        // An L-shaped room: its bounding box holds the notch, which lies
        // outside the walls.
        let mut s = square_scene();
        s.walls[0].points =
            vec![[0.0, 0.0], [10.0, 0.0], [10.0, 5.0], [5.0, 5.0], [5.0, 10.0], [0.0, 10.0]];
        s.trajectory.waypoints = vec![[4.0, 1.0], [4.0, 4.0]];
        assert_eq!(s.validate(), Ok(()));
        s.trajectory.start = StartPose { x: 8.0, y: 8.0, heading_deg: 0.0 };
        let e = s.validate().unwrap_err();
        assert!(e.item == "trajectory.start" && e.message.contains("outside the walls"), "{e}");
        let mut s = square_scene();
        s.obstacles.push(Shape {
            name: "crate".into(),
            points: vec![[8.0, 8.0], [9.5, 8.0], [9.5, 9.5], [8.0, 9.5]],
            closed: true,
        });
        s.trajectory.waypoints = vec![[9.0, 1.0], [9.0, 5.0]];
        assert_eq!(s.validate(), Ok(()));
        s.trajectory.waypoints.push([8.5, 8.5]);
        let e = s.validate().unwrap_err();
        assert!(e.message.contains("inside obstacles[0]"), "{e}");
    }

    #[test]
    fn a_tilt_too_large_names_the_key_in_degrees() {
        let mut s = square_scene();
        s.sensor.tilt =
            Some(TiltSpec { roll_amplitude_deg: 3.0, pitch_amplitude_deg: 80.0, period_s: 2.0 });
        let e = s.validate().unwrap_err();
        assert_eq!(e.item, "sensor.tilt.pitch_amplitude_deg", "{e}");
        assert!(e.message.contains("68.8°, is 80"), "{e}");
        s.sensor.tilt =
            Some(TiltSpec { roll_amplitude_deg: 3.0, pitch_amplitude_deg: 2.0, period_s: 2.0 });
        assert_eq!(s.validate(), Ok(()));
    }

    #[test]
    fn errors_name_the_item() {
        let mut s = square_scene();
        s.walls[0].points.truncate(1);
        assert!(
            s.validate()
                .unwrap_err()
                .to_string()
                .starts_with("walls[0] \"outer\": needs at least 3")
        );

        let mut s = square_scene();
        s.walls[0].points[1] = [0.0, 0.0];
        assert!(s.validate().unwrap_err().to_string().contains("zero length"));

        let mut s = square_scene();
        s.walls[0].points[2] = [f64::NAN, 1.0];
        assert!(s.validate().unwrap_err().to_string().contains("vertex 2 is not finite"));

        let mut s = square_scene();
        s.trajectory.speed_m_s = -1.0;
        assert_eq!(s.validate().unwrap_err().item, "trajectory.speed_m_s");

        let mut s = square_scene();
        s.trajectory.waypoints.push([20.0, 5.0]);
        let e = s.validate().unwrap_err();
        assert_eq!(e.item, "trajectory.waypoints[2]");
        assert!(e.message.contains("outside every wall"));

        let mut s = square_scene();
        s.obstacles.push(Shape {
            name: "box".into(),
            points: vec![[4.0, 0.5], [5.0, 0.5], [5.0, 1.5], [4.0, 1.5]],
            closed: true,
        });
        let e = s.validate().unwrap_err();
        assert_eq!(e.item, "trajectory.waypoints[0]");
        assert!(e.message.contains("obstacles[0] \"box\""), "{e}");

        let mut s = square_scene();
        s.sensor.outlier_probability = 2.0;
        assert_eq!(s.validate().unwrap_err().item, "sensor");
    }
}
