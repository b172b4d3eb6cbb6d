//! One line match as a measurement of the pose (beyond the paper): the
//! residual of a sensor line placed with a pose against its map line, its
//! Jacobian in the pose, and its covariance from both lines' uncertainties.
//!
//! The paper's eq. 11-12 use the orientation offset only; the translation
//! solve of the full-pose mode adds the normal offset. Here both are one
//! two-row measurement with a covariance, so an estimator can weigh them
//! against the source's motion noise.

use pcaline_geometry::{LineSegment, Matrix2, Point2, Pose2, Vector2, line_angle_diff};
use pcaline_mapping::MapLine;

/// The two rows of one match at a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineMeasurement {
    /// `[orientation offset (map minus placed line, wrapped to (-90°, 90°]),
    /// normal offset (map line's d minus the placed centroid's distance along
    /// the map normal)]`: radians, metres.
    pub residual: Vector2<f64>,
    /// Jacobian of the *placed line* (not the residual) in the pose
    /// `(x, y, heading)`: the residual changes by `-H dx`.
    pub jacobian: nalgebra::Matrix2x3<f64>,
    /// Covariance of the residual from both lines and the floors.
    pub covariance: Matrix2<f64>,
}

/// The floors added to a match's covariance: what the lines' own
/// covariances do not hold (walls that are not flat, map lines built from
/// poses that were themselves uncertain, segmentation that differs between
/// viewpoints).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct MeasurementNoise {
    /// Floor of the orientation offset's standard deviation, radians.
    pub alpha_floor_rad: f64,
    /// Floor of the normal offset's standard deviation, metres.
    pub offset_floor_m: f64,
    /// Factor on both lines' own (alpha, d) variances: a fit's covariance
    /// holds only the white range noise, not the texture of real walls or
    /// segmentation that differs between viewpoints.
    pub line_variance_scale: f64,
}

impl MeasurementNoise {
    /// 0.5° and 2 cm floors, the lines' own variances times 4.
    ///
    /// Measured on the real logs with their own corrected poses (matches
    /// against the map those poses build; `docs/accuracy.md`): the
    /// orientation offsets' 68% quantile is 0.87° on Intel and CSAIL alike,
    /// twice what the fits' covariances say (variance factor 4); the normal
    /// offsets' is 1.9 cm. One setting for every log.
    pub const fn standard() -> Self {
        MeasurementNoise {
            alpha_floor_rad: 0.008_727, // 0.5°
            offset_floor_m: 0.02,
            line_variance_scale: 4.0,
        }
    }
}

/// The measurement of map line `map` by `sensor` (a line in the sensor
/// frame) placed with `world_from_sensor`.
///
/// The covariance is diagonal: the orientation offset's variance is the sum
/// of both lines' orientation variances and the floor; the normal offset's
/// is the sensor centroid's (`residual_std² / n`), the map line's at that
/// centroid (its own centroid's plus the lever arm along the line times its
/// orientation variance), and the floor. A line without points gets the
/// floors only.
pub fn measure(
    sensor: &LineSegment,
    map: &MapLine,
    world_from_sensor: &Pose2,
    noise: &MeasurementNoise,
) -> LineMeasurement {
    let m = &map.line;
    let n = m.normal();
    let centroid = world_from_sensor.transform_point(&sensor.centroid());
    let lever = centroid - Point2::new(world_from_sensor.x(), world_from_sensor.y());
    let alpha_placed = sensor.alpha() + world_from_sensor.heading();
    let residual =
        Vector2::new(line_angle_diff(m.alpha(), alpha_placed), m.d() - n.dot(&centroid.coords));
    let dn_dheading = n.x * -lever.y + n.y * lever.x;
    #[rustfmt::skip]
    let jacobian = nalgebra::Matrix2x3::new(
        0.0, 0.0, 1.0,
        n.x, n.y, dn_dheading,
    );
    let var = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.0 };
    let along = (centroid - m.centroid()).dot(&m.direction());
    let k = noise.line_variance_scale;
    let var_alpha = k * (var(sensor.covariance()[(0, 0)]) + var(m.covariance()[(0, 0)]))
        + noise.alpha_floor_rad.powi(2);
    let var_offset = k
        * (var(sensor.residual_std().powi(2) / sensor.n_points().max(1) as f64)
            + var(map.rms_m().powi(2) / map.moments.n.max(1) as f64)
            + var(along * along * m.covariance()[(0, 0)]))
        + noise.offset_floor_m.powi(2);
    LineMeasurement {
        residual,
        jacobian,
        covariance: Matrix2::new(var_alpha, 0.0, 0.0, var_offset),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_fitting::{Moments, line_from_moments};
    use pcaline_mapping::LineId;

    fn wall_points(a: (f64, f64), b: (f64, f64)) -> Vec<Point2<f64>> {
        (0..=20)
            .map(|i| {
                let t = i as f64 / 20.0;
                Point2::new(a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t)
            })
            .collect()
    }

    fn line(a: (f64, f64), b: (f64, f64)) -> (LineSegment, Moments) {
        let p = wall_points(a, b);
        let m = Moments::from_points(&p);
        (line_from_moments(&m, &p[0], &p[20]).unwrap(), m)
    }

    /// The Jacobian agrees with finite differences of the placed line.
    #[test]
    fn jacobian_matches_finite_differences() {
        let (map_line, mm) = line((3.0, -1.0), (3.5, 2.0));
        let map = MapLine::new(LineId(0), map_line, mm, 0);
        let (sensor, _) = line((2.8, -0.5), (3.2, 1.5));
        let pose = Pose2::new(0.3, -0.2, 0.1);
        let noise = MeasurementNoise::standard();
        let m0 = measure(&sensor, &map, &pose, &noise);
        let h = 1e-6;
        for k in 0..3 {
            let mut d = [pose.x(), pose.y(), pose.heading()];
            d[k] += h;
            let m1 = measure(&sensor, &map, &Pose2::new(d[0], d[1], d[2]), &noise);
            let numeric = -(m1.residual - m0.residual) / h;
            for row in 0..2 {
                assert!(
                    (numeric[row] - m0.jacobian[(row, k)]).abs() < 1e-5,
                    "row {row} col {k}: {} vs {}",
                    numeric[row],
                    m0.jacobian[(row, k)]
                );
            }
        }
        assert!(m0.covariance[(0, 0)] >= noise.alpha_floor_rad.powi(2));
        assert!(m0.covariance[(1, 1)] >= noise.offset_floor_m.powi(2));
    }

    #[test]
    fn a_line_placed_on_its_map_line_has_no_residual() {
        let (l, m) = line((2.0, -1.0), (2.0, 1.0));
        let map = MapLine::new(LineId(0), l, m, 0);
        let r = measure(&l, &map, &Pose2::identity(), &MeasurementNoise::standard()).residual;
        assert!(r.norm() < 1e-12, "{r}");
        // Near the sensor the normal flips sides: a line 1 mm on the other
        // side of the origin has its alpha half a turn away, yet it is the
        // same undirected line 2 mm off.
        let (near, nm) = line((-1.0, 0.001), (1.0, 0.001));
        let map = MapLine::new(LineId(1), near, nm, 0);
        let (other, _) = line((1.0, -0.001), (-1.0, -0.001));
        let turn = pcaline_geometry::wrap_angle(other.alpha() - near.alpha());
        assert!((turn.abs() - std::f64::consts::PI).abs() < 1e-9, "{turn}");
        let r = measure(&other, &map, &Pose2::identity(), &MeasurementNoise::standard());
        assert!((r.residual[1].abs() - 0.002).abs() < 1e-9, "{:?}", r.residual);
        assert!(r.residual[0].abs() < 1e-12, "{:?}", r.residual);
    }
}
