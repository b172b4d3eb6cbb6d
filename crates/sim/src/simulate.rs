//! [`Simulator`]: scans of a scene along its trajectory, with per-beam ground
//! truth, odometry, and everything seeded.

use crate::rng::{Stream, stream_rng};
use crate::{OdometryModel, Scene, SceneError, SensorModel, Trajectory, World};
use pcaline_geometry::{ConfigError, Point2, Pose2, Scan, Vector2};
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};

/// What happened to a beam besides range noise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Fault {
    /// A clean return (plus Gaussian noise) or no return because nothing was hit.
    None,
    /// The return was displaced by a random amount.
    Displaced,
    /// The return came from clutter between the sensor and the wall.
    Clutter,
    /// The sensor reported no return although a wall was in range.
    Dropout,
    /// A range between foreground and background at a depth edge.
    MixedPixel,
}

/// Ground truth of one beam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamTruth {
    /// The wall hit (index into [`World::walls`]), `None` when nothing is in range.
    pub wall: Option<u32>,
    /// The true (noise-free) range, metres; +inf when nothing is hit.
    pub range_m: f64,
    /// The true hit point in the world frame.
    pub point: Option<Point2<f64>>,
    /// The fault applied to the beam, if any.
    pub fault: Fault,
}

/// One simulated scan with its ground truth.
#[derive(Debug, Clone, PartialEq)]
pub struct SimFrame {
    /// Index of the scan along the trajectory.
    pub index: usize,
    /// Time of the first beam, seconds from the start.
    pub time_s: f64,
    /// True `world_from_sensor` at the first beam.
    pub true_pose: Pose2,
    /// The odometry's estimate of the same pose.
    pub odometry_pose: Pose2,
    /// The scan, as a driver would publish it.
    pub scan: Scan,
    /// Ground truth per beam.
    pub beams: Vec<BeamTruth>,
}

/// A maximal run of consecutive beams with valid returns that hit the same
/// wall: the unit of the evaluation protocol (a "ground-truth visible wall").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WallRun {
    /// The wall hit.
    pub wall: u32,
    /// First beam of the run.
    pub first_beam: usize,
    /// Last beam of the run, inclusive.
    pub last_beam: usize,
}

impl SimFrame {
    /// The maximal runs of at least `min_beams` consecutive beams whose
    /// returns are valid in the published scan (noise and faults included) and
    /// whose ground truth names the same wall.
    pub fn wall_runs(&self, min_beams: usize) -> Vec<WallRun> {
        self.runs_by(min_beams, |w| w)
    }

    /// As [`SimFrame::wall_runs`], with walls of one surface (`surfaces`,
    /// from [`crate::World::surfaces`]) counted as one: a straight wall drawn
    /// as several segments gives one run, whose `wall` is the surface id.
    pub fn surface_runs(&self, min_beams: usize, surfaces: &[u32]) -> Vec<WallRun> {
        self.runs_by(min_beams, |w| surfaces.get(w as usize).copied().unwrap_or(w))
    }

    fn runs_by(&self, min_beams: usize, id: impl Fn(u32) -> u32) -> Vec<WallRun> {
        let mut runs = Vec::new();
        let mut current: Option<WallRun> = None;
        for (i, beam) in self.beams.iter().enumerate() {
            let wall = beam.wall.filter(|_| {
                beam.fault == Fault::None && self.scan.is_valid_range(self.scan.ranges[i])
            });
            let wall = wall.map(&id);
            match (current.as_mut(), wall) {
                (Some(run), Some(w)) if run.wall == w && run.last_beam + 1 == i => {
                    run.last_beam = i
                }
                (_, w) => {
                    if let Some(run) = current.take()
                        && run.last_beam + 1 - run.first_beam >= min_beams
                    {
                        runs.push(run);
                    }
                    current = w.map(|wall| WallRun { wall, first_beam: i, last_beam: i });
                }
            }
        }
        if let Some(run) = current
            && run.last_beam + 1 - run.first_beam >= min_beams
        {
            runs.push(run);
        }
        runs
    }
}

/// A seeded simulation of one scene: the same scene and seed give the same
/// scans, bit for bit, in any order of access.
#[derive(Debug, Clone)]
pub struct Simulator {
    world: World,
    sensor: SensorModel,
    trajectory: Trajectory,
    true_poses: Vec<Pose2>,
    odometry_poses: Vec<Pose2>,
    /// cos and sin of each beam's bearing in the sensor frame.
    bearings: Vec<(f64, f64)>,
    seed: u64,
}

impl Simulator {
    /// A simulator for a validated scene.
    pub fn new(scene: &Scene, seed: u64) -> Result<Self, SceneError> {
        scene.validate()?;
        Self::from_parts(
            scene.world(),
            scene.sensor_model(),
            scene.trajectory(),
            scene.odometry_model(),
            seed,
        )
        .map_err(|e| SceneError { item: "scene".into(), message: e.to_string() })
    }

    /// A simulator from its parts.
    pub fn from_parts(
        world: World,
        sensor: SensorModel,
        trajectory: Trajectory,
        odometry: OdometryModel,
        seed: u64,
    ) -> Result<Self, ConfigError> {
        sensor.validate()?;
        odometry.validate()?;
        let dt = 1.0 / sensor.rate_hz;
        let count = (trajectory.duration_s() / dt).floor() as usize + 1;
        let true_poses: Vec<_> = (0..count).map(|k| trajectory.pose_at(k as f64 * dt)).collect();
        let odometry_poses = odometry.corrupt(&true_poses, dt, seed);
        let bearings = (0..sensor.beams)
            .map(|i| {
                let (s, c) =
                    (sensor.angle_min_rad + i as f64 * sensor.angle_increment_rad).sin_cos();
                (c, s)
            })
            .collect();
        Ok(Simulator { world, sensor, trajectory, true_poses, odometry_poses, bearings, seed })
    }

    /// Number of scans along the trajectory.
    pub fn len(&self) -> usize {
        self.true_poses.len()
    }

    /// True when there are no scans.
    pub fn is_empty(&self) -> bool {
        self.true_poses.is_empty()
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The sensor model.
    pub fn sensor(&self) -> &SensorModel {
        &self.sensor
    }

    /// True poses of all scans.
    pub fn true_poses(&self) -> &[Pose2] {
        &self.true_poses
    }

    /// Odometry poses of all scans.
    pub fn odometry_poses(&self) -> &[Pose2] {
        &self.odometry_poses
    }

    /// Scan `index` along the trajectory; `None` past the end.
    pub fn frame(&self, index: usize) -> Option<SimFrame> {
        let true_pose = *self.true_poses.get(index)?;
        let time_s = index as f64 / self.sensor.rate_hz;
        let (scan, beams) = self.scan_at(&true_pose, time_s, index as u64);
        Some(SimFrame {
            index,
            time_s,
            true_pose,
            odometry_pose: self.odometry_poses[index],
            scan,
            beams,
        })
    }

    /// All scans in order.
    pub fn frames(&self) -> impl Iterator<Item = SimFrame> + '_ {
        (0..self.len()).filter_map(|k| self.frame(k))
    }

    /// A scan taken at `world_from_sensor` at time `time_s`, with the noise of
    /// stream `scan_index`. With motion skew, each beam uses the trajectory's
    /// pose at its own time instead.
    pub fn scan_at(
        &self,
        world_from_sensor: &Pose2,
        time_s: f64,
        scan_index: u64,
    ) -> (Scan, Vec<BeamTruth>) {
        let s = &self.sensor;
        let mut beams = Vec::with_capacity(s.beams);
        let mut hint = None;
        let (mut sin_h, mut cos_h) = world_from_sensor.heading().sin_cos();
        for i in 0..s.beams {
            let t = time_s + if s.motion_skew { i as f64 * s.beam_period_s() } else { 0.0 };
            let pose = if s.motion_skew { self.trajectory.pose_at(t) } else { *world_from_sensor };
            if s.motion_skew {
                (sin_h, cos_h) = pose.heading().sin_cos();
            }
            // The beam's direction in the sensor frame, then rotated into the world.
            let ((c, sn), horizontal) = match s.tilt {
                None => (self.bearings[i], 1.0),
                Some(_) => {
                    let bearing = s.angle_min_rad + i as f64 * s.angle_increment_rad;
                    let (b, h) = tilted_bearing(s, bearing, t);
                    let (sb, cb) = b.sin_cos();
                    ((cb, sb), h)
                }
            };
            let dir = Vector2::new(cos_h * c - sin_h * sn, sin_h * c + cos_h * sn);
            let origin = Point2::new(pose.x(), pose.y());
            let hit = self.world.cast_hinted(&origin, &dir, s.range_max_m * horizontal, hint);
            hint = hit.map(|h| h.wall).or(hint);
            beams.push(match hit {
                Some(h) => BeamTruth {
                    wall: Some(h.wall),
                    range_m: h.distance_m / horizontal,
                    point: Some(h.point),
                    fault: Fault::None,
                },
                None => BeamTruth {
                    wall: None,
                    range_m: f64::INFINITY,
                    point: None,
                    fault: Fault::None,
                },
            });
        }
        let ranges = self.corrupt(&mut beams, scan_index);
        let scan = Scan::new(
            s.angle_min_rad as f32,
            s.angle_increment_rad as f32,
            s.range_min_m as f32,
            s.range_max_m as f32,
            ranges,
        )
        .with_stamp(time_s);
        // A sweep taken over time says so, as a real driver does; without
        // motion skew every beam is taken at the first beam's pose.
        let scan = if s.motion_skew { scan.with_time_increment(s.beam_period_s()) } else { scan };
        (scan, beams)
    }

    /// Applies faults and noise, in beam order, from the scan's own stream.
    fn corrupt(&self, beams: &mut [BeamTruth], scan_index: u64) -> Vec<f32> {
        let s = &self.sensor;
        let f = &s.faults;
        let mut rng = stream_rng(self.seed, Stream::Scan, scan_index);
        let true_ranges: Vec<f64> = beams.iter().map(|b| b.range_m).collect();
        let mut ranges = Vec::with_capacity(beams.len());
        for (i, beam) in beams.iter_mut().enumerate() {
            let r = beam.range_m;
            if !r.is_finite() {
                ranges.push(f32::INFINITY);
                continue;
            }
            let mut measured = r;
            if f.dropout_probability > 0.0 && rng.random_bool(f.dropout_probability) {
                beam.fault = Fault::Dropout;
                ranges.push(f32::INFINITY);
                continue;
            }
            if f.outlier_probability > 0.0 && rng.random_bool(f.outlier_probability) {
                if rng.random_bool(0.5) {
                    beam.fault = Fault::Displaced;
                    measured = r + rng.random_range(-f.outlier_max_m..=f.outlier_max_m);
                } else {
                    beam.fault = Fault::Clutter;
                    measured = rng.random_range(s.range_min_m..=r.max(s.range_min_m));
                }
            } else if f.mixed_pixel_probability > 0.0 {
                let neighbour = [i.wrapping_sub(1), i + 1]
                    .into_iter()
                    .filter_map(|j| true_ranges.get(j).copied())
                    .find(|q| q.is_finite() && (q - r).abs() > f.mixed_edge_m);
                if let Some(q) = neighbour
                    && rng.random_bool(f.mixed_pixel_probability)
                {
                    beam.fault = Fault::MixedPixel;
                    measured = r + (q - r) * rng.random_range(0.0..1.0);
                }
            }
            let sigma = s.noise.sigma_at(measured);
            let z: f64 = StandardNormal.sample(&mut rng);
            let mut published = measured + sigma * z;
            if s.range_resolution_m > 0.0 {
                published = (published / s.range_resolution_m).round() * s.range_resolution_m;
            }
            ranges.push(published as f32);
        }
        ranges
    }
}

/// The horizontal bearing of a beam in a tilted scan plane and the
/// horizontal fraction of its unit direction (ranges to vertical walls are
/// the horizontal distance divided by it).
fn tilted_bearing(s: &SensorModel, bearing: f64, t: f64) -> (f64, f64) {
    let Some(tilt) = s.tilt else {
        return (bearing, 1.0);
    };
    let phase = 2.0 * std::f64::consts::PI * t / tilt.period_s;
    let (roll, pitch) =
        (tilt.roll_amplitude_rad * phase.sin(), tilt.pitch_amplitude_rad * phase.cos());
    let (sb, cb) = bearing.sin_cos();
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    // R_y(pitch) R_x(roll) (cos b, sin b, 0).
    let x = cb * cp + sb * sr * sp;
    let y = sb * cr;
    (y.atan2(x), x.hypot(y).max(1e-6))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tilt_lengthens_ranges() {
        let mut s = SensorModel::utm30lx_ew();
        assert_eq!(tilted_bearing(&s, 0.3, 1.0), (0.3, 1.0));
        s.tilt =
            Some(crate::Tilt { roll_amplitude_rad: 0.0, pitch_amplitude_rad: 0.1, period_s: 1.0 });
        let (b, h) = tilted_bearing(&s, 0.0, 0.0);
        assert!(b.abs() < 1e-12 && (h - 0.1f64.cos()).abs() < 1e-12);
    }
}
