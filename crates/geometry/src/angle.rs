//! Angle wrapping: directed angles to (-pi, pi], undirected line angles to
//! (-pi/2, pi/2].

use std::f64::consts::{FRAC_PI_2, PI};

/// Wraps an angle in radians to (-pi, pi].
///
/// Non-finite input is returned unchanged (NaN stays NaN), so callers can detect it.
///
/// ```
/// use pcaline_geometry::wrap_angle;
/// use std::f64::consts::PI;
/// assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-12);
/// assert!((wrap_angle(-PI) - PI).abs() < 1e-12);
/// assert!((wrap_angle(0.5) - 0.5).abs() < 1e-12);
/// ```
pub fn wrap_angle(angle: f64) -> f64 {
    if !angle.is_finite() {
        return angle;
    }
    if angle > -PI && angle <= PI {
        return angle;
    }
    let mut a = angle.rem_euclid(2.0 * PI); // [0, 2pi)
    if a > PI {
        a -= 2.0 * PI;
    }
    a
}

/// Difference `a - b` between two *undirected* line orientations, wrapped to
/// (-pi/2, pi/2]: lines at 0 and at pi are the same line, so their difference is 0.
///
/// This is how the paper's angle comparisons (eq. 7, and `d_alpha` of section
/// 2.1) must be read: orientations of lines are defined modulo 180°.
///
/// ```
/// use pcaline_geometry::line_angle_diff;
/// use std::f64::consts::PI;
/// assert!(line_angle_diff(PI - 0.01, 0.01).abs() - 0.02 < 1e-12);
/// assert!((line_angle_diff(0.3, 0.1) - 0.2).abs() < 1e-12);
/// ```
pub fn line_angle_diff(a: f64, b: f64) -> f64 {
    let d = a - b;
    if !d.is_finite() {
        return d;
    }
    let mut r = d.rem_euclid(PI); // [0, pi)
    if r > FRAC_PI_2 {
        r -= PI;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn wrap_edges() {
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI - 1e-9) - (PI - 1e-9)).abs() < 1e-12);
        assert!(wrap_angle(f64::NAN).is_nan());
        assert!((wrap_angle(7.0 * PI / 2.0) + FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn line_diff_is_modulo_half_turn() {
        assert!(line_angle_diff(FRAC_PI_2, -FRAC_PI_2).abs() < 1e-12);
        assert!((line_angle_diff(0.0, FRAC_PI_2) - FRAC_PI_2).abs() < 1e-12);
        assert!(
            (line_angle_diff(179f64.to_radians(), 1f64.to_radians()) + 2f64.to_radians()).abs()
                < 1e-12
        );
    }

    proptest! {
        #[test]
        fn wrap_range(a in -1e4f64..1e4) {
            let w = wrap_angle(a);
            prop_assert!(w > -PI && w <= PI);
            prop_assert!((w - a).rem_euclid(2.0 * PI) < 1e-9 || (w - a).rem_euclid(2.0 * PI) > 2.0 * PI - 1e-9);
        }

        #[test]
        fn line_diff_range(a in -100f64..100.0, b in -100f64..100.0) {
            let d = line_angle_diff(a, b);
            prop_assert!(d > -FRAC_PI_2 - 1e-12 && d <= FRAC_PI_2 + 1e-12);
            prop_assert!((line_angle_diff(a + PI, b) - d).abs() < 1e-9
                || (line_angle_diff(a + PI, b) - d).abs() > PI - 1e-9);
        }
    }
}
