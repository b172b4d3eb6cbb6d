//! The least-squares baseline the paper compares PCA with (section 3): ordinary
//! regression `y = m x + n` and the error measure of eq. 16.

use crate::Moments;
use pcaline_geometry::{Point2, SlopeIntercept};

/// Ordinary least-squares fit of `y = m x + n` (vertical residuals), the
/// paper's baseline.
///
/// Returns `None` for fewer than 2 points or when all x are equal: the model
/// cannot express a vertical line, which is why pcaline's detector uses PCA.
///
/// ```
/// use pcaline_fitting::fit_least_squares;
/// use pcaline_geometry::Point2;
/// let pts = [Point2::new(0.0, 1.0), Point2::new(1.0, 3.0), Point2::new(2.0, 5.0)];
/// let f = fit_least_squares(&pts).unwrap();
/// assert!((f.m - 2.0).abs() < 1e-12 && (f.n - 1.0).abs() < 1e-12);
/// assert!(fit_least_squares(&[Point2::new(1.0, 0.0), Point2::new(1.0, 1.0)]).is_none());
/// ```
pub fn fit_least_squares(points: &[Point2<f64>]) -> Option<SlopeIntercept> {
    if points.len() < 2 {
        return None;
    }
    slope_intercept_from_moments(&Moments::from_points(points))
}

/// The least-squares `y = m x + n` from precomputed [`Moments`].
pub fn slope_intercept_from_moments(m: &Moments) -> Option<SlopeIntercept> {
    if m.n < 2 || m.sxx <= 0.0 || !m.sxx.is_finite() {
        return None;
    }
    let slope = m.sxy / m.sxx;
    let fit = SlopeIntercept { m: slope, n: m.mean.y - slope * m.mean.x };
    (fit.m.is_finite() && fit.n.is_finite()).then_some(fit)
}

/// The paper's error measure (eq. 16): the rms of the vertical residuals
/// `y_i - m x_i - n`. Zero for an empty set.
pub fn vertical_rms_error(points: &[Point2<f64>], fit: &SlopeIntercept) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let sum: f64 = points.iter().map(|p| (p.y - fit.m * p.x - fit.n).powi(2)).sum();
    (sum / points.len() as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit_pca;

    #[test]
    fn ls_and_pca_agree_on_exact_line() {
        let pts: Vec<_> =
            (0..50).map(|i| Point2::new(i as f64 * 0.1, 0.5 * i as f64 * 0.1 - 2.0)).collect();
        let ls = fit_least_squares(&pts).unwrap();
        let pca = fit_pca(&pts).unwrap().slope_intercept().unwrap();
        assert!((ls.m - pca.m).abs() < 1e-9 && (ls.n - pca.n).abs() < 1e-9);
        assert!(vertical_rms_error(&pts, &ls) < 1e-9);
    }
}
