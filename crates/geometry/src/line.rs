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
    // Invariants, kept by every constructor: `alpha` wrapped to (-pi, pi],
    // `d >= 0`, `direction` the unit tangent `(-sin alpha, cos alpha)` up to
    // sign, pointing from `start` to `end`, and `centroid`, `start`, `end`
    // on the line (to rounding). Non-finite input gives non-finite fields.
    alpha: f64,
    d: f64,
    centroid: Point2<f64>,
    direction: Vector2<f64>,
    start: Point2<f64>,
    end: Point2<f64>,
    n_points: usize,
    residual_std: f64,
    covariance: Matrix2<f64>,
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

    /// The segment from `start` to `end` (a wall drawn by its ends), through
    /// their midpoint; statistics set to zero. Coincident ends give a
    /// segment whose direction and Hessian form are NaN, as do non-finite
    /// ones.
    ///
    /// ```
    /// use pcaline_geometry::{LineSegment, Point2};
    /// let wall = LineSegment::between(Point2::new(0.0, 1.0), Point2::new(4.0, 1.0));
    /// assert!((wall.d() - 1.0).abs() < 1e-12 && (wall.length() - 4.0).abs() < 1e-12);
    /// assert!(LineSegment::between(Point2::new(1.0, 1.0), Point2::new(1.0, 1.0)).d().is_nan());
    /// ```
    pub fn between(start: Point2<f64>, end: Point2<f64>) -> Self {
        Self::through(Point2::from((start.coords + end.coords) / 2.0), end - start, start, end)
    }

    /// A segment restored from its stored Hessian form (a saved map): the
    /// line `x cos(alpha) + y sin(alpha) = d` through `centroid`, from
    /// `start` to `end`, as given. `alpha` is wrapped; a negative `d` is
    /// made positive by turning the normal half a turn. The points are kept
    /// as given, so they should lie on the line (a record written from a
    /// [`LineSegment`] does); [`LineSegment::through`] projects points that
    /// may not. Statistics are zero, see [`LineSegment::with_statistics`].
    pub fn from_hessian(
        alpha: f64,
        d: f64,
        centroid: Point2<f64>,
        start: Point2<f64>,
        end: Point2<f64>,
    ) -> Self {
        let (alpha, d) =
            if d < 0.0 { (wrap_angle(alpha + PI), -d) } else { (wrap_angle(alpha), d) };
        let mut line =
            LineSegment::through(centroid, Vector2::new(-alpha.sin(), alpha.cos()), start, end);
        line.alpha = alpha;
        line.d = d;
        line.start = start;
        line.end = end;
        line
    }

    /// The same line with its fit statistics: the number of points, the
    /// standard deviation of their orthogonal residuals (metres) and the
    /// covariance of (`alpha`, `d`) (rad², rad·m, m²).
    pub fn with_statistics(
        mut self,
        n_points: usize,
        residual_std_m: f64,
        covariance: Matrix2<f64>,
    ) -> Self {
        self.n_points = n_points;
        self.residual_std = residual_std_m;
        self.covariance = covariance;
        self
    }

    /// The same line with the number of points it was fitted to.
    pub fn with_n_points(mut self, n_points: usize) -> Self {
        self.n_points = n_points;
        self
    }

    /// The same infinite line with its endpoints at `lo_m` and `hi_m` metres
    /// along `direction` from the centroid (`centroid + direction * s`).
    /// `lo_m > hi_m` is read as the interval `[hi_m, lo_m]`, so the direction
    /// still points from `start` to `end`.
    pub fn with_extent(mut self, lo_m: f64, hi_m: f64) -> Self {
        let (lo, hi) = if lo_m > hi_m { (hi_m, lo_m) } else { (lo_m, hi_m) };
        self.start = self.centroid + self.direction * lo;
        self.end = self.centroid + self.direction * hi;
        self
    }

    /// Angle of the normal in radians, in (-pi, pi].
    #[inline]
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Distance of the line from the frame origin in metres, `>= 0`.
    #[inline]
    pub fn d(&self) -> f64 {
        self.d
    }

    /// Centroid of the fitted points (it lies on the line).
    #[inline]
    pub fn centroid(&self) -> Point2<f64> {
        self.centroid
    }

    /// Unit direction along the line, from `start` towards `end`.
    #[inline]
    pub fn direction(&self) -> Vector2<f64> {
        self.direction
    }

    /// First endpoint: the first fitted point projected onto the line.
    #[inline]
    pub fn start(&self) -> Point2<f64> {
        self.start
    }

    /// Last endpoint: the last fitted point projected onto the line.
    #[inline]
    pub fn end(&self) -> Point2<f64> {
        self.end
    }

    /// Number of points the line was fitted to (0 for a line made by
    /// [`LineSegment::through`] alone).
    #[inline]
    pub fn n_points(&self) -> usize {
        self.n_points
    }

    /// Standard deviation of the orthogonal point-to-line residuals, metres.
    #[inline]
    pub fn residual_std(&self) -> f64 {
        self.residual_std
    }

    /// Covariance of (`alpha`, `d`): rad², rad·m, m².
    #[inline]
    pub fn covariance(&self) -> Matrix2<f64> {
        self.covariance
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
        let s = if (wrap_angle(alpha - self.alpha - parent_from_self.heading())).abs() < PI / 2.0 {
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

/// The distance from `p` to the segment from `a` to `b`: to its nearest
/// point, an end when `p` projects beyond it. A segment of zero length is
/// the point `a`.
///
/// ```
/// use pcaline_geometry::{Point2, point_segment_distance};
/// let (a, b) = (Point2::new(0.0, 0.0), Point2::new(2.0, 0.0));
/// assert_eq!(point_segment_distance(&Point2::new(1.0, 0.5), &a, &b), 0.5);
/// assert_eq!(point_segment_distance(&Point2::new(5.0, 4.0), &a, &b), 5.0); // past the end
/// assert_eq!(point_segment_distance(&Point2::new(3.0, 4.0), &a, &a), 5.0);
/// ```
pub fn point_segment_distance(p: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 { ((p - a).dot(&ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p - (a + ab * t)).norm()
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

    #[test]
    fn restored_and_rebuilt_lines_keep_the_invariants() {
        let l = LineSegment::through(
            Point2::new(2.0, 1.0),
            Vector2::new(0.3, 1.0),
            Point2::new(1.0, -2.0),
            Point2::new(3.0, 4.0),
        );
        // A saved line reads back as it was.
        let back = LineSegment::from_hessian(l.alpha(), l.d(), l.centroid(), l.start(), l.end());
        assert_eq!(
            (back.alpha(), back.d(), back.start(), back.end()),
            (l.alpha(), l.d(), l.start(), l.end())
        );
        assert!((back.direction() - l.direction()).norm() < 1e-12);
        // A negative distance turns the normal half a turn; alpha is wrapped.
        let flipped = LineSegment::from_hessian(
            l.alpha() + PI + 4.0 * PI,
            -l.d(),
            l.centroid(),
            l.start(),
            l.end(),
        );
        assert!((flipped.alpha() - l.alpha()).abs() < 1e-12 && flipped.d() == l.d());
        // Endpoints along the line, in either order, keep start -> end along
        // the direction.
        let e = l.with_extent(1.0, -0.5);
        assert!((e.start() - (l.centroid() - l.direction() * 0.5)).norm() < 1e-12);
        assert!((e.end() - (l.centroid() + l.direction())).norm() < 1e-12);
        assert!((e.end() - e.start()).dot(&e.direction()) > 0.0);
        let s = e.with_statistics(12, 0.01, Matrix2::identity()).with_n_points(13);
        assert_eq!(
            (s.n_points(), s.residual_std(), s.covariance()),
            (13, 0.01, Matrix2::identity())
        );
        assert_eq!((s.alpha(), s.d(), s.start(), s.end()), (e.alpha(), e.d(), e.start(), e.end()));
    }
}
