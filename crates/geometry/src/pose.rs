//! [`Pose2`]: a rigid transform in the plane (position and heading).

use crate::{Twist2, wrap_angle};
use nalgebra::{Point2, Vector2};

/// A 2D rigid transform `parent_from_child`: the child frame's origin at
/// (`x`, `y`) in the parent frame, rotated by `heading` radians
/// (counter-clockwise positive). A vehicle pose is `world_from_body`.
///
/// ```
/// use pcaline_geometry::{Point2, Pose2};
/// let world_from_sensor = Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2);
/// let p = world_from_sensor.transform_point(&Point2::new(1.0, 0.0));
/// assert!((p - Point2::new(1.0, 3.0)).norm() < 1e-12);
/// let back = world_from_sensor.inverse().transform_point(&p);
/// assert!((back - Point2::new(1.0, 0.0)).norm() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
// Read through `Pose2::new`, which wraps the heading.
#[cfg_attr(feature = "serde", serde(from = "PoseFields"))]
pub struct Pose2 {
    x: f64,
    y: f64,
    /// Wrapped to (-pi, pi] by every constructor (or not finite).
    heading: f64,
}

/// A pose as written: read into [`Pose2`] through [`Pose2::new`].
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct PoseFields {
    x: f64,
    y: f64,
    heading: f64,
}

#[cfg(feature = "serde")]
impl From<PoseFields> for Pose2 {
    fn from(p: PoseFields) -> Self {
        Pose2::new(p.x, p.y, p.heading)
    }
}

impl Pose2 {
    /// A pose; the heading is wrapped to (-pi, pi].
    pub fn new(x: f64, y: f64, heading: f64) -> Self {
        Pose2 { x, y, heading: wrap_angle(heading) }
    }

    /// The identity transform.
    pub const fn identity() -> Self {
        Pose2 { x: 0.0, y: 0.0, heading: 0.0 }
    }

    /// Position x in the parent frame, metres.
    #[inline]
    pub const fn x(&self) -> f64 {
        self.x
    }

    /// Position y in the parent frame, metres.
    #[inline]
    pub const fn y(&self) -> f64 {
        self.y
    }

    /// Heading in radians, counter-clockwise from the parent's x axis, in
    /// (-pi, pi] (NaN or infinite only when constructed so).
    #[inline]
    pub const fn heading(&self) -> f64 {
        self.heading
    }

    /// The same heading at another position.
    pub fn with_translation(&self, x: f64, y: f64) -> Pose2 {
        Pose2 { x, y, heading: self.heading }
    }

    /// The same position with another heading (wrapped).
    pub fn with_heading(&self, heading: f64) -> Pose2 {
        Pose2::new(self.x, self.y, heading)
    }

    /// The translation as a vector.
    pub fn translation(&self) -> Vector2<f64> {
        Vector2::new(self.x, self.y)
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.heading.is_finite()
    }

    /// Rotates a vector by the heading.
    #[inline]
    pub fn rotate(&self, v: &Vector2<f64>) -> Vector2<f64> {
        let (s, c) = self.heading.sin_cos();
        Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
    }

    /// Maps a point from the child frame to the parent frame.
    #[inline]
    pub fn transform_point(&self, p: &Point2<f64>) -> Point2<f64> {
        let v = self.rotate(&p.coords);
        Point2::new(v.x + self.x, v.y + self.y)
    }

    /// Composition `self * other`: if `self` is `a_from_b` and `other` is
    /// `b_from_c`, the result is `a_from_c`.
    pub fn compose(&self, other: &Pose2) -> Pose2 {
        let t = self.rotate(&other.translation());
        Pose2::new(self.x + t.x, self.y + t.y, self.heading + other.heading)
    }

    /// The inverse transform (`b_from_a` for `a_from_b`).
    pub fn inverse(&self) -> Pose2 {
        let (s, c) = self.heading.sin_cos();
        Pose2::new(-(c * self.x + s * self.y), s * self.x - c * self.y, -self.heading)
    }

    /// The constant velocity that moves `self` to `other` in `dt_s`
    /// seconds: the increment divided by the time, in `self`'s frame
    /// (metres and radians per second; first order in the turn). `None`
    /// for a time that is not positive and finite.
    pub fn velocity_to(&self, other: &Pose2, dt_s: f64) -> Option<Twist2> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return None;
        }
        let inc = self.between(other);
        let v = Twist2::new(inc.x / dt_s, inc.y / dt_s, inc.heading / dt_s);
        v.is_finite().then_some(v)
    }

    /// The relative pose `self^-1 * other`: `other` expressed in `self`'s frame
    /// (an odometry increment from `self` to `other`).
    pub fn between(&self, other: &Pose2) -> Pose2 {
        self.inverse().compose(other)
    }

    /// The pose a fraction `w` of the way from `self` to `other`: positions
    /// blended linearly, the heading along the shorter arc (wrapped to
    /// (-pi, pi]). `w` 0 gives `self`'s position and heading, 1 `other`'s;
    /// `w` outside [0, 1] extrapolates.
    ///
    /// ```
    /// use pcaline_geometry::Pose2;
    /// let (a, b) = (Pose2::new(0.0, 0.0, 3.0), Pose2::new(2.0, 4.0, -3.0));
    /// let m = a.lerp(&b, 0.5);
    /// assert_eq!((m.x(), m.y()), (1.0, 2.0));
    /// // 3 rad to -3 rad the short way, through pi.
    /// assert!((m.heading().abs() - std::f64::consts::PI).abs() < 1e-9);
    /// ```
    pub fn lerp(&self, other: &Pose2, w: f64) -> Pose2 {
        Pose2::new(
            self.x + w * (other.x - self.x),
            self.y + w * (other.y - self.y),
            crate::wrap_angle(self.heading + w * crate::wrap_angle(other.heading - self.heading)),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pose() -> impl Strategy<Value = Pose2> {
        (-50.0f64..50.0, -50.0f64..50.0, -4.0f64..4.0).prop_map(|(x, y, h)| Pose2::new(x, y, h))
    }

    fn close(a: &Pose2, b: &Pose2) -> bool {
        (a.x - b.x).abs() < 1e-9
            && (a.y - b.y).abs() < 1e-9
            && crate::wrap_angle(a.heading - b.heading).abs() < 1e-9
    }

    proptest! {
        #[test]
        fn inverse_composes_to_identity(p in pose()) {
            prop_assert!(close(&p.compose(&p.inverse()), &Pose2::identity()));
            prop_assert!(close(&p.inverse().compose(&p), &Pose2::identity()));
        }

        #[test]
        fn between_undoes_compose(a in pose(), b in pose()) {
            prop_assert!(close(&a.compose(&a.between(&b)), &b));
        }

        #[test]
        fn compose_matches_point_mapping(a in pose(), b in pose(), x in -5.0f64..5.0, y in -5.0f64..5.0) {
            let p = Point2::new(x, y);
            let lhs = a.compose(&b).transform_point(&p);
            let rhs = a.transform_point(&b.transform_point(&p));
            prop_assert!((lhs - rhs).norm() < 1e-9);
        }
    }
}
