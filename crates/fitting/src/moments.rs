//! [`Moments`]: the sufficient statistics of a point set for PCA line fitting
//! (count, centroid, centred second moments), built in one pass and merged in O(1).

use crate::SymmetricEigen2;
use pcaline_geometry::{Point2, Vector2};

/// Count, centroid and centred scatter of a point set: everything the paper's
/// covariance `Q` (eq. 3) needs.
///
/// Built in a single pass with sums shifted by the first point (numerically
/// stable far from the origin, unlike raw sums of `x²`), and merged with Chan's
/// parallel formula, so joining two fitted lines (eq. 7) or absorbing a new
/// line into a map line costs O(1), not a refit over the points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moments {
    /// Number of points.
    pub n: usize,
    /// Centroid (mean) of the points.
    pub mean: Point2<f64>,
    /// Sum of squared x deviations from the mean.
    pub sxx: f64,
    /// Sum of products of x and y deviations.
    pub sxy: f64,
    /// Sum of squared y deviations.
    pub syy: f64,
}

impl Moments {
    /// The moments of no points.
    pub const EMPTY: Moments =
        Moments { n: 0, mean: Point2::new(0.0, 0.0), sxx: 0.0, sxy: 0.0, syy: 0.0 };

    /// The moments of `points` in one pass.
    ///
    /// ```
    /// use pcaline_fitting::Moments;
    /// use pcaline_geometry::Point2;
    /// let m = Moments::from_points(&[Point2::new(0.0, 0.0), Point2::new(2.0, 0.0)]);
    /// assert_eq!(m.n, 2);
    /// assert_eq!(m.mean, Point2::new(1.0, 0.0));
    /// assert_eq!(m.sxx, 2.0);
    /// ```
    pub fn from_points(points: &[Point2<f64>]) -> Moments {
        let Some(first) = points.first() else {
            return Moments::EMPTY;
        };
        let (kx, ky) = (first.x, first.y);
        let (mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for p in points {
            let dx = p.x - kx;
            let dy = p.y - ky;
            sx += dx;
            sy += dy;
            sxx += dx * dx;
            sxy += dx * dy;
            syy += dy * dy;
        }
        let n = points.len() as f64;
        let (mx, my) = (sx / n, sy / n);
        Moments {
            n: points.len(),
            mean: Point2::new(kx + mx, ky + my),
            sxx: (sxx - sx * mx).max(0.0),
            sxy: sxy - sx * my,
            syy: (syy - sy * my).max(0.0),
        }
    }

    /// The moments of the union of two point sets (Chan et al.'s pairwise update).
    pub fn merge(&self, other: &Moments) -> Moments {
        if self.n == 0 {
            return *other;
        }
        if other.n == 0 {
            return *self;
        }
        let (na, nb) = (self.n as f64, other.n as f64);
        let n = na + nb;
        let delta = other.mean - self.mean;
        let f = na * nb / n;
        Moments {
            n: self.n + other.n,
            mean: self.mean + delta * (nb / n),
            sxx: self.sxx + other.sxx + delta.x * delta.x * f,
            sxy: self.sxy + other.sxy + delta.x * delta.y * f,
            syy: self.syy + other.syy + delta.y * delta.y * f,
        }
    }

    /// The covariance `Q` of the paper's eq. 3 (normalised by `N_SC`) as
    /// `(q_xx, q_xy, q_yy)`; zeros for an empty set.
    pub fn covariance(&self) -> (f64, f64, f64) {
        if self.n == 0 {
            return (0.0, 0.0, 0.0);
        }
        let n = self.n as f64;
        (self.sxx / n, self.sxy / n, self.syy / n)
    }

    /// Eigen decomposition of `Q` (eq. 3): the major eigenvector is the line
    /// direction (eq. 5), the eigenvalues are the variances along and across it.
    pub fn eigen(&self) -> SymmetricEigen2 {
        let (a, b, c) = self.covariance();
        SymmetricEigen2::of_covariance(a, b, c)
    }

    /// The moments in another frame: `parent_from_self` rotates and translates
    /// the points (the scatter rotates, the centroid moves).
    pub fn transformed(&self, parent_from_self: &pcaline_geometry::Pose2) -> Moments {
        let (s, c) = parent_from_self.heading().sin_cos();
        let (a, b, d) = (self.sxx, self.sxy, self.syy);
        // R S R^T for R = [[c, -s], [s, c]].
        let sxx = c * c * a - 2.0 * c * s * b + s * s * d;
        let syy = s * s * a + 2.0 * c * s * b + c * c * d;
        let sxy = c * s * (a - d) + (c * c - s * s) * b;
        Moments {
            n: self.n,
            mean: parent_from_self.transform_point(&self.mean),
            sxx: sxx.max(0.0),
            sxy,
            syy: syy.max(0.0),
        }
    }

    /// Sum of squared orthogonal distances of the points from the line through
    /// the centroid with unit direction `dir`.
    pub fn orthogonal_scatter(&self, dir: &Vector2<f64>) -> f64 {
        let (nx, ny) = (-dir.y, dir.x);
        (nx * nx * self.sxx + 2.0 * nx * ny * self.sxy + ny * ny * self.syy).max(0.0)
    }
}

impl Default for Moments {
    fn default() -> Self {
        Moments::EMPTY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pts() -> impl Strategy<Value = Vec<Point2<f64>>> {
        prop::collection::vec((-100.0f64..100.0, -100.0f64..100.0), 1..40)
            .prop_map(|v| v.into_iter().map(|(x, y)| Point2::new(x, y)).collect())
    }

    fn close(a: &Moments, b: &Moments) -> bool {
        let tol = 1e-7 * (1.0 + a.sxx.abs() + a.syy.abs());
        a.n == b.n
            && (a.mean - b.mean).norm() < 1e-9
            && (a.sxx - b.sxx).abs() < tol
            && (a.sxy - b.sxy).abs() < tol
            && (a.syy - b.syy).abs() < tol
    }

    proptest! {
        #[test]
        fn merge_equals_union(a in pts(), b in pts()) {
            let all: Vec<_> = a.iter().chain(b.iter()).copied().collect();
            prop_assert!(close(&Moments::from_points(&a).merge(&Moments::from_points(&b)),
                               &Moments::from_points(&all)));
        }

        #[test]
        fn transform_equals_transformed_points(a in pts(), x in -50.0f64..50.0, y in -50.0f64..50.0, h in -4.0f64..4.0) {
            let pose = pcaline_geometry::Pose2::new(x, y, h);
            let moved: Vec<_> = a.iter().map(|p| pose.transform_point(p)).collect();
            prop_assert!(close(&Moments::from_points(&a).transformed(&pose), &Moments::from_points(&moved)));
        }
    }

    #[test]
    fn stable_far_from_origin() {
        // A 1 cm scatter 10 km away: raw sums would lose it entirely.
        let pts: Vec<_> = (0..100)
            .map(|i| {
                Point2::new(1e4 + i as f64 * 0.01, 1e4 + if i % 2 == 0 { 0.01 } else { -0.01 })
            })
            .collect();
        let m = Moments::from_points(&pts);
        assert!((m.syy / 100.0 - 1e-4).abs() < 1e-10);
    }
}
