//! [`LineSegment`]: a fitted line in Hessian normal form with its extent and
//! uncertainty; [`SlopeIntercept`], the paper's `y = m x + n` view (eq. 4).

use crate::{Pose2, wrap_angle};
use nalgebra::{Matrix2, Point2, Vector2};
use std::f64::consts::PI;

/// A line segment fitted to points: the infinite line `x cos(alpha) + y sin(alpha) = d`
/// (Hessian normal form, `alpha` in (-pi, pi], `d >= 0`) plus the segment's
/// extent and statistics.
///
/// The Hessian form has no singular orientation, unlike the paper's
/// `y = m x + n` (eq. 4) and the `tan` form of eq. 9, which fail for vertical
/// lines; [`LineSegment::slope_intercept`] gives eq. 4 as a view for output.
/// For a line through the frame origin (`d = 0`) the normal is chosen with
/// `alpha` in (-pi/2, pi/2].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineSegment {
    /// Angle of the normal in radians, in (-pi, pi].
    pub alpha: f64,
    /// Distance of the line from the frame origin in metres, `>= 0`.
    pub d: f64,
    /// Centroid of the fitted points (it lies on the line).
    pub centroid: Point2<f64>,
    /// Unit direction along the line, from `start` towards `end`.
    pub direction: Vector2<f64>,
    /// First endpoint: the first fitted point projected onto the line.
    pub start: Point2<f64>,
    /// Last endpoint: the last fitted point projected onto the line.
    pub end: Point2<f64>,
    /// Number of points the line was fitted to.
    pub n_points: usize,
    /// Standard deviation of the orthogonal point-to-line residuals, metres.
    pub residual_std: f64,
    /// Covariance of (`alpha`, `d`): rad², rad·m, m².
    pub covariance: Matrix2<f64>,
}

/// The paper's `y = m x + n` (eq. 4): slope `m` (eq. 5) and intercept `n` (eq. 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlopeIntercept {
    /// Slope `m = tan(alpha_L)`.
    pub m: f64,
    /// Intercept `n`.
    pub n: f64,
}

impl LineSegment {
    /// The segment through `centroid` with unit `direction`, between the
    /// projections of `first` and `last` onto the line; statistics set to zero.
    /// `direction` is re-oriented to point from the first to the last point.
    pub fn through(
        centroid: Point2<f64>,
        direction: Vector2<f64>,
        first: Point2<f64>,
        last: Point2<f64>,
    ) -> Self {
        let mut dir = direction.normalize();
        if (last - first).dot(&dir) < 0.0 {
            dir = -dir;
        }
        let (alpha, d) = hessian(&centroid, &dir);
        let project = |p: &Point2<f64>| centroid + dir * (p - centroid).dot(&dir);
        LineSegment {
            alpha,
            d,
            centroid,
            direction: dir,
            start: project(&first),
            end: project(&last),
            n_points: 0,
            residual_std: 0.0,
            covariance: Matrix2::zeros(),
        }
    }

    /// Unit normal `(cos alpha, sin alpha)`.
    pub fn normal(&self) -> Vector2<f64> {
        Vector2::new(self.alpha.cos(), self.alpha.sin())
    }

    /// Orientation of the line's direction in radians, in (-pi, pi]
    /// (the paper's `alpha_L` of eq. 5 up to a half turn).
    pub fn direction_angle(&self) -> f64 {
        self.direction.y.atan2(self.direction.x)
    }

    /// Length of the segment in metres.
    pub fn length(&self) -> f64 {
        (self.end - self.start).norm()
    }

    /// Signed distance of `p` from the infinite line (positive on the side the normal points to).
    pub fn signed_distance(&self, p: &Point2<f64>) -> f64 {
        self.normal().dot(&p.coords) - self.d
    }

    /// Orthogonal projection of `p` onto the infinite line.
    pub fn project(&self, p: &Point2<f64>) -> Point2<f64> {
        self.centroid + self.direction * (p - self.centroid).dot(&self.direction)
    }

    /// The paper's `y = m x + n` view (eq. 4-6); `None` for a vertical line,
    /// where the slope is undefined.
    pub fn slope_intercept(&self) -> Option<SlopeIntercept> {
        if self.direction.x.abs() < 1e-12 {
            return None;
        }
        let m = self.direction.y / self.direction.x;
        Some(SlopeIntercept { m, n: self.centroid.y - m * self.centroid.x })
    }

    /// The same segment expressed in the parent frame of `parent_from_self`
    /// (for a line in the sensor frame, pass `world_from_sensor`). The
    /// covariance is propagated for the exact transform (no pose uncertainty).
    pub fn transformed(&self, parent_from_self: &Pose2) -> LineSegment {
        let centroid = parent_from_self.transform_point(&self.centroid);
        let direction = parent_from_self.rotate(&self.direction);
        let (alpha, d) = hessian(&centroid, &direction);
        // d' = d + n'.t  with alpha' = alpha + heading (+pi if flipped): the Jacobian
        // of (alpha', d') w.r.t. (alpha, d) is [[1, 0], [j, s]] with s = +-1.
        let s = if (wrap_angle(alpha - self.alpha - parent_from_self.heading)).abs() < PI / 2.0 {
            1.0
        } else {
            -1.0
        };
        let t = parent_from_self.translation();
        let tangent = Vector2::new(-alpha.sin(), alpha.cos());
        let j = Matrix2::new(1.0, 0.0, tangent.dot(&t), s);
        LineSegment {
            alpha,
            d,
            centroid,
            direction,
            start: parent_from_self.transform_point(&self.start),
            end: parent_from_self.transform_point(&self.end),
            n_points: self.n_points,
            residual_std: self.residual_std,
            covariance: j * self.covariance * j.transpose(),
        }
    }
}

/// Hessian normal form `(alpha, d)` of the line through `p` with direction `dir`.
pub(crate) fn hessian(p: &Point2<f64>, dir: &Vector2<f64>) -> (f64, f64) {
    let mut n = Vector2::new(-dir.y, dir.x);
    let mut d = n.dot(&p.coords);
    if d < 0.0 {
        n = -n;
        d = -d;
    }
    let mut alpha = n.y.atan2(n.x);
    if d <= 1e-12 * (1.0 + p.coords.norm()) {
        // Through the origin: pick the normal with alpha in (-pi/2, pi/2].
        d = 0.0;
        if alpha <= -PI / 2.0 || alpha > PI / 2.0 {
            alpha = wrap_angle(alpha + PI);
        }
    }
    (wrap_angle(alpha), d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertical_line_has_no_slope_but_a_hessian_form() {
        let l = LineSegment::through(
            Point2::new(2.0, 0.0),
            Vector2::new(0.0, 1.0),
            Point2::new(2.0, -1.0),
            Point2::new(2.0, 1.0),
        );
        assert!(l.slope_intercept().is_none());
        assert!(l.alpha.abs() < 1e-12);
        assert!((l.d - 2.0).abs() < 1e-12);
        assert!((l.length() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn horizontal_line_below_origin() {
        let l = LineSegment::through(
            Point2::new(0.0, -3.0),
            Vector2::new(1.0, 0.0),
            Point2::new(-1.0, -3.0),
            Point2::new(1.0, -3.0),
        );
        assert!((l.alpha + PI / 2.0).abs() < 1e-12);
        assert!((l.d - 3.0).abs() < 1e-12);
        let si = l.slope_intercept().unwrap();
        assert!(si.m.abs() < 1e-12 && (si.n + 3.0).abs() < 1e-12);
    }

    #[test]
    fn line_through_origin() {
        let l = LineSegment::through(
            Point2::new(1.0, 1.0),
            Vector2::new(1.0, 1.0),
            Point2::new(0.0, 0.0),
            Point2::new(2.0, 2.0),
        );
        assert_eq!(l.d, 0.0);
        assert!(l.alpha > -PI / 2.0 && l.alpha <= PI / 2.0);
        assert!(l.signed_distance(&Point2::new(3.0, 3.0)).abs() < 1e-12);
    }

    #[test]
    fn transform_keeps_points_on_line() {
        let l = LineSegment::through(
            Point2::new(2.0, 1.0),
            Vector2::new(0.3, 1.0),
            Point2::new(1.0, -2.0),
            Point2::new(3.0, 4.0),
        );
        let pose = Pose2::new(5.0, -3.0, 2.5);
        let w = l.transformed(&pose);
        for p in [l.start, l.end, l.centroid] {
            assert!(w.signed_distance(&pose.transform_point(&p)).abs() < 1e-9);
        }
        assert!(w.d >= 0.0);
    }
}
