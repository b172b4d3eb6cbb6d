//! [`edge_on_ends`]: the ends of a fitted line that lie on another surface
//! seen edge-on, and [`EdgeOnEnds`], its configuration.
//!
//! Beyond the paper. A wall seen head-on and a surface beside it seen
//! edge-on (the 10 cm end face of a maze wall, the side of a recess) meet
//! at a corner. The edge-on surface's returns lie along the beams, across
//! the wall's line: at 30 mm noise the first 5-10 of them stay within 3-4
//! noise sigmas of it, inside every split threshold, and they tilt a short
//! wall's line by 2-3°. What gives them away is where they lie *along* the
//! line. A return on the wall lies where its beam meets the line, give or
//! take the range noise; the returns of a surface seen edge-on all project
//! onto the corner while their beams sweep on along the line. An end run
//! of returns that stalls so, and whose removal lowers the residual sum by
//! more than the noise, is cut off. Comparing each return with its own
//! beam, not with the line's mean spacing, keeps a long wall whose returns
//! crowd near the foot of the perpendicular from looking stalled.

use crate::Moments;
use crate::kink::RunSums;
use pcaline_geometry::{ConfigError, Point2, Vector2};

/// Beams meeting the line at less than this cosine (within 6° of it) make
/// the test unusable: where such a beam meets the line is not known.
const MIN_BEAM_COSINE: f64 = 0.1;

/// When the ends of a fitted line are cut off as another surface seen
/// edge-on ([`edge_on_ends`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct EdgeOnEnds {
    /// Fewest points of an end run that may be cut (at least 3).
    pub min_points: usize,
    /// An end run stalls when its returns advance along the line by less
    /// than half as much as their beams do (the slope of the one against the
    /// other), and by less than the beams by more than this many standard
    /// errors of that slope.
    pub min_stall_z: f64,
    /// ... and is cut when fitting it by a line of its own lowers the sum
    /// of squared orthogonal residuals by more than this many noise
    /// variances.
    pub min_chi2: f64,
}

impl EdgeOnEnds {
    /// End runs of at least `min_points` points, stalled by more than
    /// `min_stall_z` standard errors, lowering the residual sum by more than
    /// `min_chi2` noise variances.
    pub const fn new(min_points: usize, min_stall_z: f64, min_chi2: f64) -> Self {
        EdgeOnEnds { min_points, min_stall_z, min_chi2 }
    }

    /// Runs of 5 points or more, stalled by 3 standard errors, lowering the
    /// residual sum by 4 noise variances. On three generated mazes at 30 mm
    /// noise (`docs/accuracy.md`) it takes the false positives from 7.8% to
    /// 5.0% and recall from 0.819 to 0.841; on the shipped scenes it moves
    /// neither by more than 0.1 point.
    pub const fn standard() -> Self {
        EdgeOnEnds { min_points: 5, min_stall_z: 3.0, min_chi2: 4.0 }
    }

    /// Checks every value: `min_points` at least 3, `min_stall_z` and
    /// `min_chi2` finite and not negative. Errors name `prefix.min_points`
    /// and so on (`fitting.edge_on_ends` in a [`crate::FitConfig`]).
    ///
    /// ```
    /// use pcaline_fitting::EdgeOnEnds;
    /// let e = EdgeOnEnds::new(2, 3.0, 4.0).validate("fitting.edge_on_ends").unwrap_err();
    /// assert!(e.to_string().contains("`fitting.edge_on_ends.min_points`"));
    /// assert!(EdgeOnEnds::standard().validate("x").is_ok());
    /// ```
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let n = self.min_points as f64;
        ConfigError::check_field(self.min_points >= 3, prefix, "min_points", n, "must be >= 3")?;
        for (name, v) in [("min_stall_z", self.min_stall_z), ("min_chi2", self.min_chi2)] {
            let ok = v >= 0.0 && v.is_finite();
            ConfigError::check_field(ok, prefix, name, v, "must be finite and >= 0")?;
        }
        Ok(())
    }
}

/// Least-squares sums of a straight-line fit of `y` against `x`.
#[derive(Debug, Clone, Copy, Default)]
struct Trend {
    n: f64,
    x: f64,
    xx: f64,
    y: f64,
    xy: f64,
}

impl Trend {
    fn add(&mut self, x: f64, y: f64) {
        self.n += 1.0;
        self.x += x;
        self.xx += x * x;
        self.y += y;
        self.xy += x * y;
    }

    /// The slope, and the spread of `x` (its sum of squared deviations).
    fn slope(&self) -> (f64, f64) {
        let sxx = self.xx - self.x * self.x / self.n;
        let sxy = self.xy - self.x * self.y / self.n;
        (sxy / sxx, sxx)
    }
}

/// How many points to cut from the start and from the end of `points` (in
/// scan order, sensor frame: the beams start at the origin), whose moments
/// are `moments`, as another surface seen edge-on, under `test`, with range
/// noise `sigma_m`: at each end, of the runs of `test.min_points` to a
/// third of the points that stall along the line (their slope against
/// their beams, with the standard error the range noise gives along the
/// line at the run's end), the one whose own line lowers the residual sum
/// most, when it lowers it by more than `test.min_chi2` noise variances.
/// Each end is walked inward only until its returns advance with their
/// beams (slope significantly above one half), at most a third of the
/// points: most lines cost a few points at each end.
///
/// Edge cases: fewer than `2 * min_points + 2` points, `moments` of another
/// number of points, a `min_points` below 3, a `sigma_m` that is not
/// positive and finite, non-finite points, or a run's beam within 6° of the
/// line (cosine below 0.1: that end is not searched) cut nothing.
///
/// ```
/// use pcaline_fitting::{EdgeOnEnds, Moments, edge_on_ends};
/// use pcaline_geometry::Point2;
/// use std::f64::consts::FRAC_PI_4;
/// // Beams 0.25° apart (bearing b from the y axis) on a wall along y = 1.5 m
/// // up to its end at x = 1.5 m, then on its 10 cm face towards the sensor
/// // (x = 1.5, y down to 1.4), seen nearly edge-on by the last 7 beams.
/// let pts: Vec<_> = (0..47)
///     .map(|i| FRAC_PI_4 + (i as f64 - 39.0) * 0.25f64.to_radians())
///     .map(|b| {
///         let r = if b <= FRAC_PI_4 + 1e-9 { 1.5 / b.cos() } else { 1.5 / b.sin() };
///         Point2::new(r * b.sin(), r * b.cos())
///     })
///     .collect();
/// let moments = Moments::from_points(&pts);
/// assert_eq!(edge_on_ends(&pts, &moments, 0.01, &EdgeOnEnds::standard()), (0, 7));
/// ```
pub fn edge_on_ends(
    points: &[Point2<f64>],
    moments: &Moments,
    sigma_m: f64,
    test: &EdgeOnEnds,
) -> (usize, usize) {
    let n = points.len();
    if test.min_points < 3
        || n < 2 * test.min_points + 2
        || moments.n != n
        || !(sigma_m > 0.0 && sigma_m.is_finite())
    {
        return (0, 0);
    }
    // (A non-finite point makes every statistic NaN, and NaN passes no test.)
    // The line through the centroid along the major axis, its normal
    // pointing away from the sensor (distance d >= 0).
    let c = moments.mean;
    let u = moments.eigen().major;
    let mut normal = Vector2::new(-u.y, u.x);
    if normal.dot(&c.coords) < 0.0 {
        normal = -normal;
    }
    let d = normal.dot(&c.coords);
    let total = RunSums::about_mean(moments);
    let walk = EndWalk {
        points,
        c: c.coords,
        u,
        normal,
        d,
        total,
        one_line: total.residual_sum(),
        z2: test.min_stall_z * test.min_stall_z,
        sigma2: sigma_m * sigma_m,
        test,
    };
    let start = walk.best_run(|m| m);
    let end = walk.best_run(|m| n - 1 - m);
    if start + end + test.min_points > n {
        return (0, 0);
    }
    (start, end)
}

/// One line's end walked inward by [`edge_on_ends`].
struct EndWalk<'a> {
    points: &'a [Point2<f64>],
    /// The centroid, the line's direction and its normal away from the
    /// sensor, and its distance from the sensor.
    c: Vector2<f64>,
    u: Vector2<f64>,
    normal: Vector2<f64>,
    d: f64,
    /// The sums of all the points about the centroid, and their residual
    /// sum about one line.
    total: RunSums,
    one_line: f64,
    /// `min_stall_z` and `sigma_m`, squared.
    z2: f64,
    sigma2: f64,
    test: &'a EdgeOnEnds,
}

impl EndWalk<'_> {
    /// How many points of the end run whose `m`-th point is `index(m)` (an
    /// end, walked inward) to cut: the stalled run whose own line lowers the
    /// residual sum most ([`edge_on_ends`]), or 0.
    fn best_run(&self, index: impl Fn(usize) -> usize) -> usize {
        let (points, u, test) = (self.points, self.u, self.test);
        let mut trend = Trend::default();
        // The run's sums about the centroid, brought up to date only when
        // a stalled run is weighed (most ends never stall).
        let (mut run, mut run_len) = (RunSums::default(), 0);
        let mut best: Option<(f64, usize)> = None;
        let mut var_along = 0.0;
        for m in 0..points.len() / 3 {
            let p = points[index(m)].coords;
            let n_p = self.normal.dot(&p);
            if n_p * n_p <= MIN_BEAM_COSINE * MIN_BEAM_COSINE * p.norm_squared() {
                return 0;
            }
            if m == 0 {
                // The range noise along the line, at this end: sigma times
                // the sine of the incidence (floored at a tenth of sigma).
                let sine2 = u.dot(&p).powi(2) / p.norm_squared();
                var_along = self.sigma2 * sine2.max(0.01);
            }
            // Where the beam through p meets the line (p d / (n . p)), and
            // where the return lies, both along the line.
            let on_beam = self.d * u.dot(&p) / n_p;
            let v = p - self.c;
            trend.add(on_beam, u.dot(&v));
            if m + 1 < test.min_points {
                continue;
            }
            // Stalled: the slope below one half, and 1 - slope above
            // min_stall_z standard errors, sqrt(var_along / spread).
            let (slope, spread) = trend.slope();
            if slope >= 0.5 {
                // A run well above one half has reached the wall: a longer
                // one, holding more of it, will not stall.
                if (slope - 0.5).powi(2) * spread > self.z2 * var_along {
                    break;
                }
                continue;
            }
            if (1.0 - slope).powi(2) * spread <= self.z2 * var_along {
                continue;
            }
            for k in run_len..=m {
                let w = points[index(k)].coords - self.c;
                run.add(w.x, w.y);
            }
            run_len = m + 1;
            let drop = (self.one_line - run.residual_sum() - self.total.minus(&run).residual_sum())
                / self.sigma2;
            if drop > test.min_chi2 && best.is_none_or(|b| drop > b.0) {
                best = Some((drop, m + 1));
            }
        }
        best.map_or(0, |b| b.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, Normal};

    /// Returns of beams 0.25° apart, range noise `sigma`, on a wall along
    /// y = 1.5 m whose end at x = 1.5 m (bearing 45°) turns into a 10 cm
    /// face towards the sensor (x = 1.5, y from 1.5 down to 1.4): `beams`
    /// returns on the wall, then, with `face`, the 7 beams that hit the
    /// face, seen nearly edge-on.
    fn wall_with_end_face(
        rng: &mut StdRng,
        sigma: f64,
        beams: usize,
        face: bool,
    ) -> Vec<Point2<f64>> {
        let noise = Normal::new(0.0, sigma).unwrap();
        let step = 0.25f64.to_radians();
        let last = std::f64::consts::FRAC_PI_4;
        let mut pts = Vec::new();
        let mut b = last - (beams - 1) as f64 * step;
        loop {
            // Bearing from the y axis: x = r sin b, y = r cos b.
            let r = if b <= last + 1e-9 {
                1.5 / b.cos()
            } else if face && 1.5 / b.tan() >= 1.4 {
                1.5 / b.sin()
            } else {
                break;
            };
            let r = r + noise.sample(rng);
            pts.push(Point2::new(r * b.sin(), r * b.cos()));
            b += step;
        }
        pts
    }

    /// How many of 100 walls with an end face have it cut off (5 to 9
    /// points of its 7), at noise `sigma`; the start is never cut.
    fn cut_of_100(seed: u64, sigma: f64) -> usize {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut cut = 0;
        for _ in 0..100 {
            let pts = wall_with_end_face(&mut rng, sigma, 40, true);
            assert_eq!(pts.len(), 47);
            let moments = Moments::from_points(&pts);
            let (start, end) = edge_on_ends(&pts, &moments, sigma, &EdgeOnEnds::standard());
            assert_eq!(start, 0);
            cut += usize::from((5..=9).contains(&end));
        }
        cut
    }

    #[test]
    fn an_end_face_seen_edge_on_is_cut_off() {
        // At 10 mm the face's returns lie up to 10 sigmas off the wall:
        // measured 98 of 100.
        let at_10mm = cut_of_100(3, 0.01);
        assert!(at_10mm >= 90, "{at_10mm}");
        // At 30 mm they lie within 3.3 sigmas: measured 78 of 100.
        let at_30mm = cut_of_100(3, 0.03);
        assert!(at_30mm >= 60, "{at_30mm}");
    }

    #[test]
    fn a_straight_noisy_wall_keeps_its_ends() {
        let mut rng = StdRng::seed_from_u64(5);
        let mut cut = 0;
        for _ in 0..500 {
            let pts = wall_with_end_face(&mut rng, 0.03, 40, false);
            let moments = Moments::from_points(&pts);
            if edge_on_ends(&pts, &moments, 0.03, &EdgeOnEnds::standard()) != (0, 0) {
                cut += 1;
            }
        }
        // Measured: 10 of 500 (the runs of 5 to 13 points at either end are
        // many tests).
        assert!(cut <= 15, "{cut}");
    }

    #[test]
    fn too_few_points_or_a_bad_sigma_cut_nothing() {
        let test = EdgeOnEnds::standard();
        let few: Vec<_> = (0..11).map(|i| Point2::new(0.02 * i as f64, 2.0)).collect();
        assert_eq!(edge_on_ends(&few, &Moments::from_points(&few), 0.01, &test), (0, 0));
        let pts: Vec<_> = (0..30).map(|i| Point2::new(0.02 * i as f64, 2.0)).collect();
        let m = Moments::from_points(&pts);
        assert_eq!(edge_on_ends(&pts, &m, 0.0, &test), (0, 0));
        assert_eq!(edge_on_ends(&pts, &m, f64::NAN, &test), (0, 0));
        assert_eq!(edge_on_ends(&pts[1..], &m, 0.01, &test), (0, 0));
        let mut bad = pts.clone();
        bad[4].y = f64::INFINITY;
        assert_eq!(edge_on_ends(&bad, &m, 0.01, &test), (0, 0));
        // Every beam along the line: nothing is known of where they meet it.
        let along_beam: Vec<_> = (1..=30).map(|i| Point2::new(0.1 * i as f64, 0.0)).collect();
        let m = Moments::from_points(&along_beam);
        assert_eq!(edge_on_ends(&along_beam, &m, 0.01, &test), (0, 0));
        let still = vec![Point2::new(1.0, 1.0); 30];
        assert_eq!(edge_on_ends(&still, &Moments::from_points(&still), 0.01, &test), (0, 0));
    }
}
