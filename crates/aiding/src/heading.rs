//! Heading correction (paper eq. 11-13) and the rotation of the position step
//! (eq. 14), from matches between new lines and map lines.

use pcaline_geometry::{Point2, Pose2};

/// The smallest `d_rho` used in a weight `1 / d_rho²`: a perfect match
/// (`d_rho = 0`) would otherwise have an infinite weight.
pub const MIN_D_RHO_M: f64 = 1e-3;

/// The heading correction `dgamma` of eq. 12: the weighted mean of the
/// orientation offsets `d_alpha` (map minus new, wrapped to (-90°, 90°]) with
/// weights `1 / d_rho²` (eq. 13), `d_rho` floored at [`MIN_D_RHO_M`].
///
/// Returns `None` with no usable pair (empty, or only non-finite values).
///
/// ```
/// use pcaline_aiding::heading_correction;
/// // Two matches: offsets 0.01 and 0.03 rad at d_rho 0.1 m and 0.2 m.
/// let g = heading_correction([(0.01, 0.1), (0.03, 0.2)]).unwrap();
/// assert!((g - (0.01 / 0.01 + 0.03 / 0.04) / (1.0 / 0.01 + 1.0 / 0.04)).abs() < 1e-12);
/// assert_eq!(heading_correction([]), None);
/// ```
pub fn heading_correction(pairs: impl IntoIterator<Item = (f64, f64)>) -> Option<f64> {
    weighted_offset(
        pairs.into_iter().map(|(d_alpha, d_rho)| (d_alpha, 1.0 / d_rho.max(MIN_D_RHO_M).powi(2))),
    )
}

/// The weighted mean of orientation offsets `(d_alpha, weight)`; pairs with a
/// non-finite value or a weight that is not positive are skipped. `None`
/// when nothing is left.
///
/// With weights `1 / var(d_alpha)` (the variances of both lines' orientations)
/// this is the minimum-variance estimate of the heading offset, which eq. 13's
/// `1 / d_rho²` is not: it lets the closest match dominate however short and
/// noisy its lines are.
pub fn weighted_offset(pairs: impl IntoIterator<Item = (f64, f64)>) -> Option<f64> {
    let (mut num, mut den) = (0.0, 0.0);
    for (d_alpha, w) in pairs {
        if !(d_alpha.is_finite() && w.is_finite() && w > 0.0) {
            continue;
        }
        num += w * d_alpha;
        den += w;
    }
    (den > 0.0).then(|| num / den)
}

/// Eq. 14 in pcaline's counter-clockwise frame: the position step from the
/// previous corrected position `previous` to the predicted position
/// `predicted`, rotated by `+dgamma` about `previous`.
///
/// (The paper writes the rotation for a clockwise heading; in a
/// counter-clockwise frame a heading too small by `dgamma` bends the step by
/// `-dgamma`, which `R(+dgamma)` undoes.)
pub fn rotate_step(previous: &Point2<f64>, predicted: &Point2<f64>, dgamma: f64) -> Point2<f64> {
    previous + Pose2::new(0.0, 0.0, dgamma).rotate(&(predicted - previous))
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::Vector2;

    #[test]
    fn zero_d_rho_is_guarded() {
        let g = heading_correction([(0.02, 0.0), (0.0, 1.0)]).unwrap();
        assert!(g.is_finite() && (g - 0.02).abs() < 1e-5);
        assert_eq!(heading_correction([(f64::NAN, 0.1)]), None);
    }

    #[test]
    fn step_rotation_sign() {
        // Heading too small by 0.1 rad: the predicted step went 0.1 rad clockwise of the truth.
        let prev = Point2::new(1.0, 1.0);
        let truth_step = Vector2::new(0.0, 1.0);
        let (s, c) = (-0.1f64).sin_cos();
        let predicted = prev
            + Vector2::new(
                c * truth_step.x - s * truth_step.y,
                s * truth_step.x + c * truth_step.y,
            );
        let fixed = rotate_step(&prev, &predicted, 0.1);
        assert!((fixed - (prev + truth_step)).norm() < 1e-12);
    }
}
