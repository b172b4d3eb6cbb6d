//! [`LineDetector`]: the detection pipeline of the paper's section 2 on one
//! scan, with reusable buffers and the intermediate results exposed.

use crate::Config;
use pcaline_fitting::{
    Moments, Piece, Straightness, is_elongated, line_from_eigen, merge_adjacent, refine_boundaries,
    straightness,
};
use pcaline_geometry::{
    BearingTable, ConfigError, LineSegment, Pose2, RangeNoise, Scan, ScanPoints,
};
use pcaline_segmentation::{
    Level2Rule, NoiseEstimate, NoiseScratch, RangeGrid, derivative_peak_split, detect_range_step,
    estimate_range_noise, level1_clusters, seam_start, split_at_farthest,
};
use std::ops::Range;

/// A detected line and the points it was fitted from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectedLine {
    /// The line in the sensor frame.
    pub line: LineSegment,
    /// Moments of the fitted points, sensor frame (for maps that refine lines).
    pub moments: Moments,
    /// Index of the first point (in [`Detection::points`]).
    pub first_point: usize,
    /// Index of the last point, inclusive. Smaller than `first_point` only for
    /// a line that wraps around the end of a closed 360° scan.
    pub last_point: usize,
    /// Beam index of the first point.
    pub first_beam: u32,
    /// Beam index of the last point.
    pub last_beam: u32,
    /// How straight the points under the line are: residual against the
    /// noise the thresholds used (the UTM-30LX-EW datasheet for the paper's
    /// detector, which uses none) and the runs test of the residual signs.
    pub straightness: Straightness,
}

impl From<&DetectedLine> for pcaline_aiding::SensorLine {
    /// The line and its moments, as the aiding takes them.
    fn from(l: &DetectedLine) -> Self {
        pcaline_aiding::SensorLine { line: l.line, moments: l.moments }
    }
}

impl DetectedLine {
    /// Indices of the line's points in [`Detection::points`], in scan order
    /// (wrapping for a line across the seam of a closed scan). Includes points
    /// of rejected pieces lying between merged pieces.
    pub fn point_indices(&self, n_points: usize) -> impl Iterator<Item = usize> + use<> {
        wrapping_range(self.first_point, self.last_point, n_points)
    }
}

/// The indices `first..=last` of a ring of `n_points`, wrapping past the end
/// when `last < first`.
fn wrapping_range(first: usize, last: usize, n_points: usize) -> impl Iterator<Item = usize> {
    let len = if last >= first { last - first + 1 } else { n_points - first + last + 1 };
    (0..len).map(move |k| (first + k) % n_points.max(1))
}

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
    level1_breaks: Vec<usize>,
    clusters: Vec<Range<usize>>,
    sub_clusters: Vec<Range<usize>>,
    pieces: Vec<Piece>,
    lines: Vec<DetectedLine>,
    derivative_scratch: Vec<[f64; 2]>,
    split_stack: Vec<Range<usize>>,
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
            level1_breaks: Vec::new(),
            clusters: Vec::new(),
            sub_clusters: Vec::new(),
            pieces: Vec::new(),
            lines: Vec::new(),
            derivative_scratch: Vec::new(),
            split_stack: Vec::new(),
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
    pub fn detect_moving(&mut self, scan: &Scan, velocity: Option<&Pose2>) -> Detection<'_> {
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
            config = config.with_noise(found.noise);
            self.noise_estimate = Some(found);
        }
        let noise = config.nominal_noise();
        let seg = config.segmentation;
        let fit = config.fitting;

        // A closed scan is a ring: start reading it at a break-point so no
        // cluster crosses the seam; with no break at all, the merge bridges it.
        let mut ring_without_break = false;
        if scan.is_closed() {
            match seam_start(&self.points, &seg.level1) {
                Some(start) => {
                    let turn = std::f64::consts::TAU * f64::from(scan.angle_increment).signum();
                    self.points.rotate_start(start, turn);
                }
                None => ring_without_break = self.points.len() >= seg.min_cluster_points,
            }
        }

        level1_clusters(
            &self.points,
            &seg.level1,
            seg.min_cluster_points,
            &mut self.level1_breaks,
            &mut self.clusters,
        );

        self.sub_clusters.clear();
        for cluster in &self.clusters {
            let first_sub = self.sub_clusters.len();
            match seg.level2 {
                Level2Rule::DerivativePeaks { sign } => derivative_peak_split(
                    &self.points,
                    cluster.clone(),
                    sign,
                    &mut self.derivative_scratch,
                    &mut self.sub_clusters,
                ),
                Level2Rule::SplitAtFarthest { sigma_factor, min_distance_m, noise } => {
                    split_at_farthest(
                        &self.points,
                        cluster.clone(),
                        &noise,
                        sigma_factor,
                        min_distance_m,
                        &mut self.split_stack,
                        &mut self.sub_clusters,
                    )
                }
                Level2Rule::None => self.sub_clusters.push(cluster.clone()),
            }
            refine_boundaries(
                &self.points.xy,
                &mut self.sub_clusters[first_sub..],
                fit.corner_window,
            );
        }

        self.pieces.clear();
        let mut cluster_id = 0;
        for sub in &self.sub_clusters {
            while self.clusters[cluster_id].end < sub.end {
                cluster_id += 1;
            }
            if sub.len() < fit.min_points {
                continue;
            }
            let moments = Moments::from_points(&self.points.xy[sub.clone()]);
            let eigen = moments.eigen();
            if is_elongated(&eigen, fit.eth)
                && fit.residual_test.is_none_or(|t| t.accepts(&moments, &eigen))
            {
                self.pieces.push(Piece {
                    moments,
                    first: sub.start,
                    last: sub.end - 1,
                    cluster: cluster_id,
                });
            }
        }

        merge_adjacent(&mut self.pieces, &fit.merge, ring_without_break);

        self.lines.clear();
        let reference_noise = noise.unwrap_or(RangeNoise::utm30lx());
        for piece in &self.pieces {
            let first = self.points.xy[piece.first];
            let last = self.points.xy[piece.last];
            // One eigen decomposition serves the fit and the orientation test.
            let eigen = piece.moments.eigen();
            if let Some(line) = line_from_eigen(&piece.moments, &eigen, &first, &last)
                && line.n_points >= fit.min_line_points
                && line.length() >= fit.min_line_length_m
                && fit.orientation_test.is_none_or(|t| t.accepts(&piece.moments, &eigen))
            {
                // The line's points in scan order, wrapping past the end of a
                // closed scan.
                let xy = &self.points.xy;
                let straightness = if piece.last >= piece.first {
                    straightness(&xy[piece.first..=piece.last], &line, &reference_noise)
                } else {
                    let wrapped = xy[piece.first..].iter().chain(&xy[..=piece.last]);
                    straightness(wrapped, &line, &reference_noise)
                };
                let sigma = reference_noise.sigma_at(line.centroid.coords.norm());
                if fit.straightness_test.is_some_and(|t| !t.accepts(&straightness, sigma)) {
                    continue;
                }
                self.lines.push(DetectedLine {
                    line,
                    moments: piece.moments,
                    first_point: piece.first,
                    last_point: piece.last,
                    first_beam: self.points.beam[piece.first],
                    last_beam: self.points.beam[piece.last],
                    straightness,
                });
            }
        }

        Detection {
            lines: &self.lines,
            points: &self.points,
            level1_breaks: &self.level1_breaks,
            clusters: &self.clusters,
            sub_clusters: &self.sub_clusters,
            noise,
            noise_estimate: self.noise_estimate,
        }
    }
}
