//! [`Trajectory`]: the true motion of the vehicle: turn in place towards the
//! next waypoint at a yaw rate, then drive straight to it at a speed.

use pcaline_geometry::{Point2, Pose2, wrap_angle};

/// One piece of the motion.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Leg {
    Turn { at: Point2<f64>, from: f64, delta: f64 },
    Drive { from: Point2<f64>, to: Point2<f64>, heading: f64 },
}

/// A piecewise motion through waypoints, evaluated at any time.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    legs: Vec<(f64, f64, Leg)>, // (start time, duration, leg)
    end_pose: Pose2,
}

impl Trajectory {
    /// The motion from `start` through `waypoints` at `speed_m_s`, turning at
    /// `yaw_rate_rad_s`; with `laps > 1` the path returns to the start and is
    /// driven again. Speeds and rates must be positive (validated by the scene).
    pub fn new(
        start: Pose2,
        waypoints: &[Point2<f64>],
        speed_m_s: f64,
        yaw_rate_rad_s: f64,
        laps: u32,
    ) -> Self {
        let mut legs = Vec::new();
        let mut t = 0.0;
        let mut pose = start;
        let start_point = Point2::new(start.x(), start.y());
        let mut targets: Vec<Point2<f64>> = Vec::new();
        for lap in 0..laps.max(1) {
            if lap > 0 {
                targets.push(start_point);
            }
            targets.extend_from_slice(waypoints);
        }
        for target in targets {
            let here = Point2::new(pose.x(), pose.y());
            let d = target - here;
            let dist = d.norm();
            if dist < 1e-9 {
                continue;
            }
            let heading = d.y.atan2(d.x);
            let delta = wrap_angle(heading - pose.heading());
            if delta.abs() > 1e-12 {
                let dur = delta.abs() / yaw_rate_rad_s;
                legs.push((t, dur, Leg::Turn { at: here, from: pose.heading(), delta }));
                t += dur;
            }
            let dur = dist / speed_m_s;
            legs.push((t, dur, Leg::Drive { from: here, to: target, heading }));
            t += dur;
            pose = Pose2::new(target.x, target.y, heading);
        }
        Trajectory { legs, end_pose: pose }
    }

    /// Total duration in seconds.
    pub fn duration_s(&self) -> f64 {
        self.legs.last().map_or(0.0, |(t, d, _)| t + d)
    }

    /// The true pose (`world_from_body`) at time `t_s`; before the start the
    /// start pose, after the end the end pose.
    pub fn pose_at(&self, t_s: f64) -> Pose2 {
        let Some(first) = self.legs.first() else {
            return self.end_pose;
        };
        if t_s <= 0.0 || !t_s.is_finite() {
            return Self::eval(&first.2, 0.0);
        }
        let i = self.legs.partition_point(|(start, _, _)| *start <= t_s).saturating_sub(1);
        let (start, dur, leg) = self.legs[i];
        if t_s >= start + dur {
            return if i + 1 == self.legs.len() { self.end_pose } else { Self::eval(&leg, 1.0) };
        }
        Self::eval(&leg, if dur > 0.0 { (t_s - start) / dur } else { 1.0 })
    }

    fn eval(leg: &Leg, f: f64) -> Pose2 {
        match *leg {
            Leg::Turn { at, from, delta } => Pose2::new(at.x, at.y, from + f * delta),
            Leg::Drive { from, to, heading } => {
                let p = from + (to - from) * f;
                Pose2::new(p.x, p.y, heading)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_path() {
        let t = Trajectory::new(
            Pose2::new(0.0, 0.0, 0.0),
            &[Point2::new(2.0, 0.0), Point2::new(2.0, 2.0)],
            1.0,
            std::f64::consts::FRAC_PI_2,
            1,
        );
        // 2 s drive, 1 s turn of 90°, 2 s drive.
        assert!((t.duration_s() - 5.0).abs() < 1e-12);
        let p = t.pose_at(1.0);
        assert!((p.x() - 1.0).abs() < 1e-12 && p.heading().abs() < 1e-12);
        let p = t.pose_at(2.5);
        assert!(
            (p.x() - 2.0).abs() < 1e-12
                && (p.heading() - std::f64::consts::FRAC_PI_4).abs() < 1e-12
        );
        let p = t.pose_at(100.0);
        assert!((p.y() - 2.0).abs() < 1e-12);
        assert_eq!(t.pose_at(f64::NAN), t.pose_at(0.0));
    }
}
