//! [`Twist2`]: a planar velocity (linear and angular), the rate of change
//! of a [`Pose2`].

use crate::Pose2;
use nalgebra::Vector2;

/// A constant planar velocity in the moving body's own frame: linear
/// velocity (`vx_mps`, `vy_mps`) in metres per second and turn rate
/// `yaw_rate_radps` in radians per second (counter-clockwise positive).
///
/// Unlike a [`Pose2`] heading, the turn rate is not wrapped: 4 rad/s is a
/// rate, not an angle. Any value is allowed; [`Twist2::is_finite`] tells the
/// usable ones.
///
/// ```
/// use pcaline_geometry::{Pose2, Twist2};
/// let a = Pose2::new(1.0, 0.0, 0.0);
/// let b = Pose2::new(1.5, 0.0, 0.1);
/// let v = a.velocity_to(&b, 0.25).unwrap();
/// assert!((v.vx_mps - 2.0).abs() < 1e-12 && (v.yaw_rate_radps - 0.4).abs() < 1e-12);
/// // Half a second of that velocity, as a motion of the body:
/// let moved = v.motion_over(0.5);
/// assert!((moved.heading() - 0.2).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Twist2 {
    /// Velocity along the body's x axis, metres per second.
    pub vx_mps: f64,
    /// Velocity along the body's y axis, metres per second.
    pub vy_mps: f64,
    /// Turn rate, radians per second, counter-clockwise positive; not wrapped.
    pub yaw_rate_radps: f64,
}

impl Twist2 {
    /// A velocity from its three components.
    pub const fn new(vx_mps: f64, vy_mps: f64, yaw_rate_radps: f64) -> Self {
        Twist2 { vx_mps, vy_mps, yaw_rate_radps }
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.vx_mps.is_finite() && self.vy_mps.is_finite() && self.yaw_rate_radps.is_finite()
    }

    /// The linear velocity as a vector, metres per second.
    pub fn linear_mps(&self) -> Vector2<f64> {
        Vector2::new(self.vx_mps, self.vy_mps)
    }

    /// `self * (1 - t) + other * t`, component by component (`t = 0.25`
    /// moves a running average a quarter of the way to a new sample).
    pub fn lerp(&self, other: &Twist2, t: f64) -> Twist2 {
        let s = 1.0 - t;
        Twist2 {
            vx_mps: s * self.vx_mps + t * other.vx_mps,
            vy_mps: s * self.vy_mps + t * other.vy_mps,
            yaw_rate_radps: s * self.yaw_rate_radps + t * other.yaw_rate_radps,
        }
    }

    /// The body's motion after `t_s` seconds at this constant velocity,
    /// `start_from_now = exp(twist * t_s)`: the exact constant-twist motion
    /// (an arc when turning, a straight line when not; turn rates below
    /// 1e-9 rad per step are treated as straight). The heading is wrapped.
    pub fn motion_over(&self, t_s: f64) -> Pose2 {
        let theta = self.yaw_rate_radps * t_s;
        let (s, c) = theta.sin_cos();
        // V(theta) = [[a, -b], [b, a]] with a = sin/theta, b = (1 - cos)/theta.
        let (a, b) = if theta.abs() < 1e-9 { (1.0, 0.0) } else { (s / theta, (1.0 - c) / theta) };
        let vt = self.linear_mps() * t_s;
        Pose2::new(a * vt.x - b * vt.y, b * vt.x + a * vt.y, theta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_circle_returns_to_the_start() {
        // 1 m/s forward while turning 2 pi rad in one second: a circle.
        let v = Twist2::new(1.0, 0.0, std::f64::consts::TAU);
        let p = v.motion_over(1.0);
        assert!(p.translation().norm() < 1e-12 && p.heading().abs() < 1e-9, "{p:?}");
        // A quarter of it: the point at radius 1/(2 pi), 90 degrees on.
        let r = 1.0 / std::f64::consts::TAU;
        let q = v.motion_over(0.25);
        assert!((q.x() - r).abs() < 1e-12 && (q.y() - r).abs() < 1e-12, "{q:?}");
    }

    #[test]
    fn no_turn_is_a_straight_line_and_lerp_ends_at_its_inputs() {
        let v = Twist2::new(1.0, -2.0, 0.0);
        assert_eq!(v.motion_over(0.5), Pose2::new(0.5, -1.0, 0.0));
        let w = Twist2::new(3.0, 0.0, 8.0);
        assert_eq!(v.lerp(&w, 0.0), v);
        assert_eq!(v.lerp(&w, 1.0), w);
        assert!(!Twist2::new(f64::NAN, 0.0, 0.0).is_finite());
    }
}
