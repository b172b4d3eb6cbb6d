//! End-to-end tests of the line detector on hand-made scenes: the cases the
//! established extractors' bug trackers are full of, and bad input.

mod support;

use pcaline::segmentation::{DerivativeSign, Level2Rule};
use pcaline::{Config, LineDetector, Point2, Scan, geometry::SensorProfile, geometry::wrap_angle};
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};
use support::*;

fn presets() -> [(&'static str, Config); 2] {
    [("paper", Config::paper()), ("default", Config::default())]
}

fn p(x: f64, y: f64) -> Point2<f64> {
    Point2::new(x, y)
}

#[test]
fn corner_gives_two_lines_with_exact_parameters() {
    // Walls x = 3 (y from -4 to 2) and y = 2 (x from -1 to 3), noise-free.
    let walls = [(p(3.0, -4.0), p(3.0, 2.0)), (p(3.0, 2.0), p(-1.0, 2.0))];
    let scan = utm_scan(&walls, 0.0, 1);
    for (name, config) in presets() {
        let mut det = LineDetector::new(config).unwrap();
        let lines: Vec<_> = det.detect(&scan).lines.iter().map(|l| l.line).collect();
        let vertical = lines.iter().find(|l| l.alpha().abs() < 1e-3 && (l.d() - 3.0).abs() < 1e-3);
        let horizontal = lines
            .iter()
            .find(|l| (l.alpha() - FRAC_PI_2).abs() < 1e-3 && (l.d() - 2.0).abs() < 1e-3);
        assert!(vertical.is_some() && horizontal.is_some(), "{name}: {lines:#?}");
        let v = vertical.unwrap();
        assert!(v.length() > 5.0, "{name}: vertical wall only {} m", v.length());
    }
}

#[test]
fn parallel_walls_at_a_depth_jump_stay_apart() {
    // Two walls facing the sensor, at 2 m and at 3 m, side by side.
    let walls = [(p(2.0, -2.0), p(2.0, 0.0)), (p(3.0, 0.0), p(3.0, 3.0))];
    let scan = utm_scan(&walls, 0.0, 2);
    for (name, config) in presets() {
        let mut det = LineDetector::new(config).unwrap();
        let d = det.detect(&scan);
        let mut ds: Vec<f64> = d.lines.iter().map(|l| l.line.d()).collect();
        ds.sort_by(f64::total_cmp);
        assert_eq!(ds.len(), 2, "{name}: {:#?}", d.lines);
        assert!((ds[0] - 2.0).abs() < 1e-6 && (ds[1] - 3.0).abs() < 1e-6, "{name}: {ds:?}");
        assert!(d.level1_breaks.len() >= 2, "{name}: the depth jump is a level-1 break");
    }
}

#[test]
fn vertical_and_horizontal_walls_and_a_wall_through_the_x_axis() {
    for (walls, alpha, d) in [
        (vec![(p(4.0, -3.0), p(4.0, 3.0))], 0.0, 4.0),
        (vec![(p(-3.0, 1.5), p(3.0, 1.5))], FRAC_PI_2, 1.5),
        (vec![(p(-3.0, -1.5), p(3.0, -1.5))], -FRAC_PI_2, 1.5),
    ] {
        let scan = utm_scan(&walls, 0.0, 3);
        for (name, config) in presets() {
            let mut det = LineDetector::new(config).unwrap();
            let d_ = det.detect(&scan);
            assert_eq!(d_.lines.len(), 1, "{name}: {:#?}", d_.lines);
            let l = d_.lines[0].line;
            assert!((l.alpha() - alpha).abs() < 1e-6 && (l.d() - d).abs() < 1e-6, "{name}: {l:?}");
        }
    }
    // A wall crossing the x axis ahead (the line x = 5 crosses the sensor's
    // x axis) and a wall along a ray through the sensor (seen edge-on: no line).
    let scan = utm_scan(&[(p(5.0, -1.0), p(5.0, 1.0)), (p(1.0, 0.0), p(4.0, 0.0))], 0.0, 4);
    let mut det = LineDetector::new(Config::default()).unwrap();
    let d_ = det.detect(&scan);
    assert_eq!(d_.lines.len(), 1, "{:#?}", d_.lines);
}

#[test]
fn endpoints_reach_the_wall_ends() {
    // No point dropped at splits: the segment spans the first to the last beam
    // on the wall. The paper's rule may still drop a sub-cluster of under 3
    // points at each end (its derivative peaks fire on f32 rounding noise).
    let scan = utm_scan(&[(p(2.0, -1.0), p(2.0, 1.0))], 0.0, 5);
    let spacing = 2.0 * 0.25f64.to_radians();
    for (name, config, allowance) in
        [("paper", Config::paper(), 6.0 * spacing), ("default", Config::default(), 2.0 * spacing)]
    {
        let mut det = LineDetector::new(config).unwrap();
        let d = det.detect(&scan);
        assert_eq!(d.lines.len(), 1, "{name}: {:#?}", d.lines);
        let l = d.lines[0].line;
        assert!(l.length() > 2.0 - allowance, "{name}: length {}", l.length());
    }
}

#[test]
fn wall_across_the_seam_of_a_360_scan_is_one_line() {
    let n = 1440;
    let inc = 2.0 * PI / n as f64;
    // Behind the sensor: a wall x = -3 spanning y in [-2, 2] crosses the ±180° seam.
    // Case 1: with another wall elsewhere (level-1 breaks exist).
    let walls = vec![(p(-3.0, -2.0), p(-3.0, 2.0)), (p(4.0, -1.0), p(4.0, 1.0))];
    // Case 2: a closed room (no level-1 break anywhere).
    let room = rectangle(-3.0, -2.0, 4.0, 2.5);
    let mut paper_absolute = Config::paper();
    paper_absolute.segmentation.level2 =
        Level2Rule::DerivativePeaks { sign: DerivativeSign::Absolute };
    // The paper's signed peaks miss the room's corner at (-3, 2.5), where the
    // derivative drops instead of peaking ,
    // so the closed room is checked with the rules that find corners.
    let cases = [
        (walls, vec![("paper", Config::paper()), ("default", Config::default())]),
        (room, vec![("paper+absolute", paper_absolute), ("default", Config::default())]),
    ];
    for (walls, configs) in cases {
        let scan = scan_of(&walls, -PI, inc, n, 0.0, 6);
        assert!(scan.is_closed());
        for (name, config) in configs {
            let mut det = LineDetector::new(config).unwrap();
            let d = det.detect(&scan);
            let behind: Vec<_> =
                d.lines.iter().filter(|l| (l.line.alpha().abs() - PI).abs() < 1e-3).collect();
            assert_eq!(behind.len(), 1, "{name}: {:#?}", d.lines);
            assert!(behind[0].line.length() > 3.9, "{name}: {:?}", behind[0].line);
            assert!(behind[0].first_beam > behind[0].last_beam, "{name}: crosses the seam");
        }
    }
}

#[test]
fn absolute_peaks_find_a_corner() {
    // A corner where both derivatives fall: the absolute-value variant of
    // eq. 2a/2b splits it into its two walls.
    let walls = [(p(-3.0, -3.0), p(-3.0, 2.5)), (p(-3.0, 2.5), p(4.0, 2.5))];
    let scan = scan_of(&walls, 20f64.to_radians(), 0.25f64.to_radians(), 600, 0.0, 1);
    let mut config = Config::paper();
    config.segmentation.level2 = Level2Rule::DerivativePeaks { sign: DerivativeSign::Absolute };
    let mut det = LineDetector::new(config).unwrap();
    let d = det.detect(&scan);
    assert_eq!(d.lines.len(), 2, "{:#?}", d.lines);
}

#[test]
fn max_range_and_invalid_returns_are_not_walls() {
    // Half the beams see nothing (reported at range_max, NaN, or inf): no phantom arc.
    let mut scan = utm_scan(&[(p(2.0, -1.0), p(2.0, 1.0))], 0.0, 7);
    for (i, r) in scan.ranges.iter_mut().enumerate() {
        if !r.is_finite() {
            *r = match i % 3 {
                0 => 30.0,
                1 => f32::NAN,
                _ => f32::NEG_INFINITY,
            };
        }
    }
    for (name, config) in presets() {
        let mut det = LineDetector::new(config).unwrap();
        let d = det.detect(&scan);
        assert_eq!(d.lines.len(), 1, "{name}: {:#?}", d.lines);
        assert!(d.points.range_m.iter().all(|r| *r < 30.0));
    }
}

#[test]
fn negative_increment_scan() {
    // A sensor mounted upside down: same wall, beams in the opposite order.
    let walls = [(p(3.0, -2.0), p(3.0, 2.0)), (p(3.0, 2.0), p(0.0, 2.0))];
    let scan = scan_of(&walls, 135f64.to_radians(), -0.25f64.to_radians(), 1081, 0.0, 8);
    let mut det = LineDetector::new(Config::default()).unwrap();
    let d = det.detect(&scan);
    assert_eq!(d.lines.len(), 2, "{:#?}", d.lines);
}

#[test]
fn bad_scans_give_no_lines_and_no_panic() {
    let inc = 0.25f32.to_radians();
    let cases = vec![
        Scan::new(0.0, inc, 0.1, 30.0, vec![]),
        Scan::new(0.0, inc, 0.1, 30.0, vec![f32::NAN; 1081]),
        Scan::new(0.0, inc, 0.1, 30.0, vec![5.0]),
        Scan::new(0.0, inc, 0.1, 30.0, vec![5.0; 3]),
        Scan::new(0.0, 0.0, 0.1, 30.0, vec![5.0; 100]), // duplicated points
        Scan::new(0.0, f32::NAN, 0.1, 30.0, vec![5.0; 100]),
        Scan::new(f32::INFINITY, inc, 0.1, 30.0, vec![5.0; 100]),
        Scan::new(0.0, inc, 0.0, f32::MAX, vec![f32::MAX / 2.0; 100]),
        Scan::new(0.0, inc, 0.0, 30.0, vec![1e-30; 100]),
        Scan::new(0.0, 1e-30, 0.0, 30.0, vec![5.0; 100]),
        Scan::new(0.0, 1e30, 0.0, 30.0, vec![5.0; 100]),
    ];
    // The default finds no line in any of them. The paper's detector has no
    // minimum length: from points 1e-30 m apart (ranges of 1e-30 m, or an
    // increment of 1e-30 rad) it fits sub-millimetre "lines", never a real one.
    let mut det = LineDetector::new(Config::default()).unwrap();
    for scan in &cases {
        let lines = det.detect(scan).lines;
        assert!(lines.is_empty(), "{} lines from {scan:?}", lines.len());
    }
    let mut det = LineDetector::new(Config::paper()).unwrap();
    for scan in &cases {
        for l in det.detect(scan).lines {
            assert!(l.line.alpha().is_finite() && l.line.d().is_finite(), "{scan:?}");
            assert!(l.line.length() < 1e-3, "a {} m line from {scan:?}", l.line.length());
        }
    }
    // Identical ranges over an arc form a circle: no straight wall.
    let arc = Scan::new(-2.0, inc, 0.1, 30.0, vec![5.0; 900]);
    let mut det = LineDetector::new(Config::default()).unwrap();
    assert!(det.detect(&arc).lines.iter().all(|l| l.line.length() < 2.0));
}

#[test]
fn invalid_configurations_are_typed_errors() {
    let mut c = Config::paper();
    c.fitting.eth = 0.5;
    let err = LineDetector::new(c).unwrap_err();
    assert!(err.to_string().contains("fitting.eth"), "{err}");
    let mut c = Config::paper();
    c.segmentation.level1 = pcaline::segmentation::BreakRule::Fixed { dth_m: -1.0 };
    assert!(LineDetector::new(c).is_err());
    let mut c = Config::paper();
    c.fitting.eth = 1.0;
    assert!(LineDetector::new(c).is_err());
}

#[test]
fn intermediate_results_are_consistent() {
    let walls = rectangle(-2.0, -3.0, 5.0, 4.0);
    let scan = utm_scan(&walls, 0.01, 9);
    let mut det = LineDetector::new(Config::paper()).unwrap();
    let d = det.detect(&scan);
    // Sub-clusters tile the kept clusters.
    for c in d.clusters {
        let subs: Vec<_> =
            d.sub_clusters.iter().filter(|s| s.start >= c.start && s.end <= c.end).collect();
        assert_eq!(subs.first().unwrap().start, c.start);
        assert_eq!(subs.last().unwrap().end, c.end);
        assert!(subs.windows(2).all(|w| w[0].end == w[1].start));
    }
    assert!(d.level2_breaks().count() + d.clusters.len() == d.sub_clusters.len());
}

#[test]
fn noisy_room_default_finds_the_walls() {
    // A 7 x 7 m room, sigma 1 cm: the default detector finds each visible run
    // of wall once. The wall behind (x = -2) is seen twice, at both ends of the
    // 270° field of view.
    let walls = rectangle(-2.0, -3.0, 5.0, 4.0);
    let scan = utm_scan(&walls, 0.01, 10);
    let mut det = LineDetector::new(Config::default()).unwrap();
    let d = det.detect(&scan);
    assert_eq!(d.lines.len(), 5, "{:#?}", d.lines);
    for (alpha, dist, runs) in
        [(0.0, 5.0, 1), (FRAC_PI_2, 4.0, 1), (-FRAC_PI_2, 3.0, 1), (PI, 2.0, 2)]
    {
        let hits: Vec<_> = d
            .lines
            .iter()
            .filter(|l| {
                wrap_angle(l.line.alpha() - alpha).abs() < 1f64.to_radians()
                    && (l.line.d() - dist).abs() < 0.02
            })
            .collect();
        assert_eq!(hits.len(), runs, "wall ({alpha}, {dist}): {:#?}", d.lines);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_ranges_never_panic(ranges in prop::collection::vec(any_range(), 0..1200),
                                    angle_min in -4.0f32..4.0, inc in -0.02f32..0.02) {
        let scan = Scan::new(angle_min, inc, 0.1, 30.0, ranges);
        let estimated = Config::default()
            .with_noise_estimation(pcaline::segmentation::NoiseEstimation::standard());
        for config in [Config::paper(), Config::default(), estimated] {
            let mut det = LineDetector::new(config).unwrap();
            let d = det.detect(&scan);
            for l in d.lines {
                prop_assert!(l.line.alpha().is_finite() && l.line.d().is_finite() && l.line.d() >= 0.0);
            }
        }
    }

    #[test]
    fn room_with_corrupted_beams_never_panics(walls in room(), seed in 0u64..1000,
                                               corrupt in prop::collection::vec((0usize..1081, any_range()), 0..200)) {
        let mut scan = utm_scan(&walls, 0.01, seed);
        for (i, r) in corrupt {
            scan.ranges[i] = r;
        }
        let estimated = Config::default()
            .with_noise_estimation(pcaline::segmentation::NoiseEstimation::standard());
        for config in [Config::default(), estimated] {
            let mut det = LineDetector::new(config).unwrap();
            let d = det.detect(&scan);
            // An estimate, when made, stays within its bounds of the nominal.
            if let Some(n) = d.noise {
                prop_assert!(n.near_sigma_m >= 0.01 && n.near_sigma_m <= 0.04, "{n:?}");
            }
        }
    }

    #[test]
    fn every_line_lies_near_its_points(walls in room(), seed in 0u64..1000, sigma in 0.0f64..0.03) {
        let scan = utm_scan(&walls, sigma, seed);
        // Default: the split leaves every point within 4 model sigmas of its
        // piece's chord and a merge keeps the joint residual within 2.5 model
        // sigmas, so no point strays more than 8 model sigmas plus the noise.
        let mut det = LineDetector::new(Config::default()).unwrap();
        let d = det.detect(&scan);
        let noise = pcaline::RangeNoise::utm30lx();
        for l in d.lines {
            for i in l.point_indices(d.points.len()) {
                let bound = 8.0 * noise.sigma_at(d.points.range_m[i]) + 6.0 * sigma + 1e-3;
                let dist = l.line.signed_distance(&d.points.point(i)).abs();
                prop_assert!(dist < bound, "point {i} at {dist} m from its line (bound {bound})");
            }
        }
        // Paper: the only test is the eigenvalue ratio, which bounds the
        // residual by the spread along the line: lambda_min < lambda_max / ETh,
        // residual² = lambda_min n / (n - 2) (unbiased), and lambda_max is at
        // most (length / 2)² for points spread over the segment (plus noise).
        let mut det = LineDetector::new(Config::paper()).unwrap();
        let d = det.detect(&scan);
        for l in d.lines {
            let n = l.line.n_points() as f64;
            let bound = (n / (n - 2.0) / 50.0).sqrt() * l.line.length() / 2.0;
            prop_assert!(l.line.residual_std() < bound + 6.0 * sigma + 1e-3,
                "residual {} for a {} m line", l.line.residual_std(), l.line.length());
        }
    }
}

/// The default detector says which noise it used: the profile's (widened by
/// the range grid) when a scan has too few triples to estimate from, the
/// scan's own when a clearly noisier sensor took it.
#[test]
fn the_default_detector_reports_the_noise_it_used() {
    let mut det = LineDetector::new(Config::default()).unwrap();
    // 12 beams on a wall: too few triples (30 a band) to estimate.
    let few = Scan::new(-0.05, 0.25f32.to_radians(), 0.1, 30.0, vec![2.0; 12]);
    let d = det.detect(&few);
    let e = d.noise_estimate.unwrap();
    assert!(e.samples[0] < 30, "{e:?}");
    assert_eq!(d.noise.unwrap().near_sigma_m, pcaline::RangeNoise::utm30lx().near_sigma_m);
    // A 40 mm sensor on the walls of a room: the estimate follows it.
    let walls = [(p(3.0, -4.0), p(3.0, 2.0)), (p(3.0, 2.0), p(-1.0, 2.0))];
    let noisy = utm_scan(&walls, 0.04, 7);
    let d = det.detect(&noisy);
    let sigma = d.noise.unwrap().near_sigma_m;
    assert!((sigma / 0.04 - 1.0).abs() < 0.25, "{sigma}");
    assert!(d.noise_estimate.unwrap().samples[0] >= 30);
    // The adaptive detector estimates as the default does.
    let mut adaptive = LineDetector::new(Config::adaptive()).unwrap();
    assert_eq!(adaptive.detect(&noisy).noise.unwrap().near_sigma_m, sigma);
    // The datasheet detector is told the datasheet and estimates nothing.
    let mut datasheet = LineDetector::new(Config::datasheet(SensorProfile::Utm30lxEw)).unwrap();
    let d = datasheet.detect(&noisy);
    assert!(d.noise_estimate.is_none());
    assert_eq!(d.noise, Some(pcaline::RangeNoise::utm30lx()));
}

#[test]
fn the_default_cuts_edge_on_ends_on_noisy_scans_only() {
    // A room with a 10 cm and a 40 cm thick wall whose end face the sensor
    // sees nearly edge-on, beside the wall's long face.
    let room_with = |wall: Vec<_>| [rectangle(-5.0, -3.0, 5.0, 4.5), wall].concat();
    let scenes =
        [room_with(rectangle(-3.0, 1.4, -0.5, 1.5)), room_with(rectangle(-4.0, 1.0, -1.0, 1.4))];
    let lines = |config: &Config, scan: &Scan| {
        let mut det = LineDetector::new(*config).unwrap();
        det.detect(scan).lines.iter().map(|l| (l.first_point, l.last_point)).collect::<Vec<_>>()
    };
    let default = Config::default();
    let mut never = default;
    never.noisy_scan_tests = None;
    let mut always = never;
    always.fitting.edge_on_ends = Some(pcaline::fitting::EdgeOnEnds::standard());
    let datasheet = Config::datasheet(SensorProfile::Utm30lxEw);
    let (mut cut_at_10mm, mut cut_at_30mm) = (false, false);
    for (walls, seed) in scenes.iter().flat_map(|w| (0..8).map(move |s| (w, s))) {
        // At the datasheet's noise the default is the datasheet detector,
        // where a cut on every scan would change a line.
        let scan = utm_scan(walls, 0.01, seed);
        assert_eq!(lines(&default, &scan), lines(&datasheet, &scan), "seed {seed}");
        cut_at_10mm |= lines(&always, &scan) != lines(&never, &scan);
        // At 30 mm the estimate is raised, and the default cuts as a
        // detector that cuts on every scan.
        let scan = utm_scan(walls, 0.03, seed);
        assert_eq!(lines(&default, &scan), lines(&always, &scan), "seed {seed}");
        cut_at_30mm |= lines(&default, &scan) != lines(&never, &scan);
    }
    assert!(cut_at_10mm && cut_at_30mm, "the cut changed no line: {cut_at_10mm} {cut_at_30mm}");
}
