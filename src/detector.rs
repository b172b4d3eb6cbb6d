//! [`LineDetector`]: the detection pipeline of the paper's section 2 on one
//! scan, with reusable buffers and the intermediate results exposed.

use crate::Config;
use pcaline_fitting::{DetectedLine, LineFits, fit_lines};
use pcaline_geometry::{BearingTable, ConfigError, RangeNoise, Scan, ScanPoints, Twist2};
use pcaline_segmentation::{
    NoiseEstimate, NoiseScratch, RangeGrid, Segments, detect_range_step, estimate_range_noise,
    segment,
};
use std::ops::Range;

/// The result of [`LineDetector::detect`], borrowing the detector's buffers.
#[derive(Debug, Clone, Copy)]
pub struct Detection<'a> {
    /// The detected lines, in scan order.
    pub lines: &'a [DetectedLine],
    /// The range noise the thresholds used: the scan's estimate when the
    /// configuration estimates it ([`Config::noise_estimation`]), else the
    /// configuration's own; `None` when no rule uses noise (the paper).
    pub noise: Option<RangeNoise>,
    /// What the estimation found (triples per band, the range grid), when
    /// the configuration estimates the noise.
    pub noise_estimate: Option<NoiseEstimate>,
    /// The valid returns as points in the sensor frame (eq. 1), in scan order;
    /// for a closed scan rotated to start at a level-1 break-point.
    pub points: &'a ScanPoints,
    /// Level-1 break-points: indices of the points that begin a cluster.
    pub level1_breaks: &'a [usize],
    /// Level-1 clusters kept (at least the minimum size).
    pub clusters: &'a [Range<usize>],
    /// Level-2 sub-clusters of the kept clusters.
    pub sub_clusters: &'a [Range<usize>],
}

/// Whether the estimate `found` raised either range band's sigma above the
/// `nominal` model's: a noisy scan ([`crate::NoisyScanTests`]).
fn is_raised(found: &RangeNoise, nominal: &RangeNoise) -> bool {
    found.near_sigma_m > nominal.near_sigma_m || found.far_sigma_m > nominal.far_sigma_m
}

impl Detection<'_> {
    /// Level-2 break-points: the first point of every sub-cluster that does not
    /// begin a level-1 cluster.
    pub fn level2_breaks(&self) -> impl Iterator<Item = usize> + '_ {
        self.sub_clusters
            .iter()
            .map(|r| r.start)
            .filter(|s| self.clusters.iter().all(|c| c.start != *s))
    }
}

/// The line detector. It owns its scratch buffers, so detecting a stream of
/// scans allocates only while a scan is larger than any before it.
///
/// Any [`Scan`] gives lines or no lines: invalid returns are skipped, a scan
/// with unusable geometry gives nothing, and nothing panics on data.
#[derive(Debug, Clone)]
pub struct LineDetector {
    config: Config,
    table: BearingTable,
    points: ScanPoints,
    segments: Segments,
    fits: LineFits,
    noise_estimate: Option<NoiseEstimate>,
    noise_scratch: NoiseScratch,
}

impl LineDetector {
    /// A detector for `config`; an invalid configuration is a [`ConfigError`].
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(LineDetector {
            config,
            table: BearingTable::default(),
            points: ScanPoints::default(),
            segments: Segments::default(),
            fits: LineFits::default(),
            noise_estimate: None,
            noise_scratch: NoiseScratch::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Detects the lines of one scan (paper section 2).
    pub fn detect(&mut self, scan: &Scan) -> Detection<'_> {
        self.detect_moving(scan, None)
    }

    /// As [`LineDetector::detect`], for a scan taken while the sensor moved
    /// with `velocity` (metres and radians per second, in the sensor frame):
    /// with the scan's beam period ([`Scan::beam_period_s`]) known, every
    /// point is first placed in the frame of the first beam
    /// ([`ScanPoints::deskew`]). Without a velocity or a beam period, the
    /// same as [`LineDetector::detect`].
    pub fn detect_moving(&mut self, scan: &Scan, velocity: Option<&Twist2>) -> Detection<'_> {
        self.points.fill_from(scan, &mut self.table);
        if let (Some(v), Some(dt)) = (velocity, scan.beam_period_s()) {
            self.points.deskew(v, dt);
        }
        let mut config = self.config;
        self.noise_estimate = None;
        if let (Some(estimation), Some(nominal)) =
            (self.config.noise_estimation, self.config.nominal_noise())
        {
            let step = match estimation.range_grid {
                RangeGrid::Known { step_m } => step_m,
                _ => detect_range_step(&scan.ranges),
            };
            let found = estimate_range_noise(
                &self.points,
                &nominal,
                &estimation,
                step,
                &mut self.noise_scratch,
            );
            if let Some(tests) = self.config.noisy_scan_tests
                && is_raised(&found.noise, &nominal)
            {
                config.fitting = tests.added_to(config.fitting);
            }
            config = config.with_noise(found.noise);
            self.noise_estimate = Some(found);
        }
        let noise = config.nominal_noise();
        segment(scan, &mut self.points, &config.segmentation, &mut self.segments);
        let s = &mut self.segments;
        fit_lines(
            &self.points,
            &s.clusters,
            &mut s.sub_clusters,
            s.ring_without_break,
            &config.fitting,
            noise.as_ref(),
            &mut self.fits,
        );

        Detection {
            lines: &self.fits.lines,
            points: &self.points,
            level1_breaks: &self.segments.level1_breaks,
            clusters: &self.segments.clusters,
            sub_clusters: &self.segments.sub_clusters,
            noise,
            noise_estimate: self.noise_estimate,
        }
    }
}
