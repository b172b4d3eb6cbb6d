//! [`LineMap`]: the incremental line map of the paper's section 2.1:
//! matching new lines against map lines (eq. 8-10), endpoint update by
//! projection, and the refined variant that keeps every absorbed point's sums.

use crate::fast_hash::FastMap;
use crate::grid::Grid;
use crate::metrics::{centroid_distance, normal_offset};
use crate::{LineDistance, LineStatus, MapConfig, MergeGate};
use pcaline_fitting::{Moments, line_from_moments};
use pcaline_geometry::{ConfigError, LineSegment, Point2, Pose2, Vector2, line_angle_diff};
use std::collections::VecDeque;

/// A stable identifier of a map line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LineId(pub u64);

/// A line of the map, in the world frame.
#[derive(Debug, Clone, PartialEq)]
pub struct MapLine {
    /// Stable identifier.
    pub id: LineId,
    /// The line and its extent.
    pub line: LineSegment,
    /// Sums of every point absorbed (used when the map refines its lines).
    pub moments: Moments,
    /// Number of detected lines merged into this one (1 when new).
    pub observations: u32,
    /// The most extreme endpoints observed on each side (for the robust extent).
    pub extremes: Extremes,
    /// Unit normal pointing from the line to the side it was first seen
    /// from; `None` when inserted without a viewpoint.
    pub facing: Option<Vector2<f64>>,
    /// What the line may be used for ([`crate::Lifecycle`]).
    pub status: LineStatus,
    /// Distinct scans the line was seen in ([`LineMap::begin_scan`] counts
    /// scans; a map fed without it counts every insertion as a scan).
    pub scans_seen: u32,
    /// The scan the line was first seen in.
    pub first_scan: u64,
    /// The scan the line was last seen in.
    pub last_scan: u64,
    /// Sum over the absorbed observations of `n_points * residual_std²`,
    /// m²: what the points scatter about their own fits (for the
    /// straightness test).
    pub observed_scatter: f64,
}

impl MapLine {
    /// A map line made of one observation, seen in scan `scan`.
    pub fn new(id: LineId, line: LineSegment, moments: Moments, scan: u64) -> Self {
        MapLine {
            id,
            line,
            moments,
            observations: 1,
            extremes: Extremes::of(&line),
            facing: None,
            status: LineStatus::Confirmed,
            scans_seen: 1,
            first_scan: scan,
            last_scan: scan,
            observed_scatter: line.n_points() as f64 * line.residual_std().powi(2),
        }
    }

    /// Rms distance of the absorbed points from the line, metres.
    pub fn rms_m(&self) -> f64 {
        (self.moments.orthogonal_scatter(&self.line.direction()) / self.moments.n.max(1) as f64)
            .sqrt()
    }

    /// Rms residual of the absorbed observations about their own fits, metres.
    pub fn observed_rms_m(&self) -> f64 {
        (self.observed_scatter / self.moments.n.max(1) as f64).sqrt()
    }

    /// True when aiding may correct a pose with the line.
    pub fn is_confirmed(&self) -> bool {
        self.status == LineStatus::Confirmed
    }
}

/// The extent of a map line: the accepted endpoints and, with the robust
/// rule, extensions seen once and waiting for confirmation. Points are in the
/// world frame and re-projected whenever the line is refitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extremes {
    /// Accepted first endpoint.
    pub low: Point2<f64>,
    /// Accepted last endpoint.
    pub high: Point2<f64>,
    /// Unconfirmed extensions beyond `low`.
    pub pending_low: [Option<Point2<f64>>; 2],
    /// Unconfirmed extensions beyond `high`.
    pub pending_high: [Option<Point2<f64>>; 2],
}

/// How close a second observation must come to an extension to confirm it, metres.
const CONFIRM_M: f64 = 0.05;

impl Extremes {
    /// The extent of one observation, nothing pending.
    pub fn of(line: &LineSegment) -> Self {
        Extremes {
            low: line.start(),
            high: line.end(),
            pending_low: [None; 2],
            pending_high: [None; 2],
        }
    }

    /// Adds the endpoints of a new observation. Without `robust`, the extent
    /// grows to any endpoint beyond it (the paper). With `robust`, an endpoint
    /// beyond the extent is accepted only as far as another observation
    /// beyond it (or within 5 cm of it) confirms; otherwise it waits.
    fn add(&mut self, line: &LineSegment, points: [Point2<f64>; 2], robust: bool) {
        let s = |p: &Point2<f64>| (p - line.centroid()).dot(&line.direction());
        let (a, b) = if s(&points[0]) <= s(&points[1]) {
            (points[0], points[1])
        } else {
            (points[1], points[0])
        };
        let (lo, hi) = if s(&self.low) <= s(&self.high) {
            (self.low, self.high)
        } else {
            (self.high, self.low)
        };
        // Work on the low side with s and on the high side with -s.
        let (new_lo, pend_lo) = extend(lo, a, self.pending_low, robust, |p| s(p));
        let (new_hi, pend_hi) = extend(hi, b, self.pending_high, robust, |p| -s(p));
        *self = Extremes { low: new_lo, high: new_hi, pending_low: pend_lo, pending_high: pend_hi };
    }

    /// The accepted extent `(lo, hi)` along `line`.
    fn extent(&self, line: &LineSegment) -> (f64, f64) {
        let s = |p: &Point2<f64>| (p - line.centroid()).dot(&line.direction());
        let (lo, hi) = (s(&self.low), s(&self.high));
        if lo <= hi { (lo, hi) } else { (hi, lo) }
    }
}

/// One side of [`Extremes::add`]; `key` grows towards the inside of the line.
fn extend(
    accepted: Point2<f64>,
    candidate: Point2<f64>,
    mut pending: [Option<Point2<f64>>; 2],
    robust: bool,
    key: impl Fn(&Point2<f64>) -> f64,
) -> (Point2<f64>, [Option<Point2<f64>>; 2]) {
    if key(&candidate) >= key(&accepted) {
        return (accepted, pending);
    }
    if !robust {
        return (candidate, pending);
    }
    // A pending extension reaching as far as the candidate (within the
    // tolerance) confirms it up to the less extreme of the two.
    let mut accepted = accepted;
    let mut confirmed = false;
    for p in pending.iter().flatten() {
        if key(p) <= key(&candidate) + CONFIRM_M {
            let reach = if key(p) >= key(&candidate) { *p } else { candidate };
            if key(&reach) < key(&accepted) {
                accepted = reach;
            }
            confirmed = true;
        }
    }
    if !confirmed {
        // Keep the two most extreme unconfirmed extensions.
        let mut all: Vec<Point2<f64>> =
            pending.iter().flatten().copied().chain([candidate]).collect();
        all.sort_by(|x, y| key(x).total_cmp(&key(y)));
        pending = [all.first().copied(), all.get(1).copied()];
    }
    // Pending points no longer beyond the extent are dropped.
    for p in pending.iter_mut() {
        if p.is_some_and(|q| key(&q) >= key(&accepted)) {
            *p = None;
        }
    }
    (accepted, pending)
}

/// A map line matched by a new line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Match {
    /// Index of the map line in [`LineMap::lines`].
    pub index: usize,
    /// Its identifier.
    pub id: LineId,
    /// The metrics of the match.
    pub distance: LineDistance,
}

/// The gates of a match: what [`LineMap::find_match`] uses from the
/// configuration, or wider ones an estimator derives from its pose
/// uncertainty ([`LineMap::for_each_candidate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct MatchGate {
    /// Largest orientation difference, radians.
    pub max_d_alpha_rad: f64,
    /// Largest `d_rho`, metres.
    pub max_d_rho_m: f64,
    /// Largest distance of the new centroid from the map line, metres.
    pub max_offset_m: Option<f64>,
}

impl MatchGate {
    /// Gates of at most `max_d_alpha_rad` radians of orientation difference,
    /// `max_d_rho_m` metres of `d_rho` and, when given, `max_offset_m` metres
    /// of the new centroid from the map line.
    pub fn new(max_d_alpha_rad: f64, max_d_rho_m: f64, max_offset_m: Option<f64>) -> Self {
        MatchGate { max_d_alpha_rad, max_d_rho_m, max_offset_m }
    }

    /// The gates of a map configuration.
    pub fn of(config: &MapConfig) -> Self {
        MatchGate {
            max_d_alpha_rad: config.max_d_alpha_rad,
            max_d_rho_m: config.max_d_rho_m,
            max_offset_m: config.max_offset_m,
        }
    }
}

/// An incremental map of lines with a spatial index.
///
/// Line indices ([`Match::index`]) are positions in [`LineMap::lines`]: they
/// hold until the next insertion or [`LineMap::begin_scan`], which may remove
/// lines (expiry, duplicates). Ids ([`LineId`]) never change.
#[derive(Debug, Clone)]
pub struct LineMap {
    config: MapConfig,
    lines: Vec<MapLine>,
    grid: Grid,
    next_id: u64,
    /// The current scan ([`LineMap::begin_scan`]).
    scan: u64,
    /// Whether scans are counted by the caller; otherwise every insertion
    /// is a scan of its own.
    counted: bool,
    index_of: FastMap<LineId, usize>,
    /// Tentative lines by first scan, oldest first (may hold lines since
    /// confirmed or removed).
    tentative: VecDeque<(u64, LineId)>,
}

impl LineMap {
    /// An empty map; an invalid configuration is a [`ConfigError`].
    pub fn new(config: MapConfig) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(LineMap {
            grid: Grid::new(config.grid_cell_m),
            config,
            lines: Vec::new(),
            next_id: 0,
            scan: 0,
            counted: false,
            index_of: FastMap::default(),
            tentative: VecDeque::new(),
        })
    }

    /// Starts a new scan: observations inserted from now on count as one
    /// sighting, and tentative lines not confirmed within
    /// [`crate::Lifecycle::expire_after_scans`] are removed. A map that is
    /// never told counts every insertion as a scan of its own.
    pub fn begin_scan(&mut self) {
        self.counted = true;
        self.scan += 1;
        let Some(life) = self.config.lifecycle else { return };
        while let Some(&(first, id)) = self.tentative.front() {
            if first + u64::from(life.expire_after_scans) > self.scan {
                break;
            }
            self.tentative.pop_front();
            if let Some(&i) = self.index_of.get(&id)
                && self.lines[i].status == LineStatus::Tentative
            {
                self.remove_at(i);
            }
        }
    }

    /// The current scan number (0 before the first [`LineMap::begin_scan`]).
    pub fn scan(&self) -> u64 {
        self.scan
    }

    /// The map line with id `id`.
    pub fn get(&self, id: LineId) -> Option<&MapLine> {
        self.index_of.get(&id).map(|&i| &self.lines[i])
    }

    /// Removes the line at `index` (the last line takes its place).
    fn remove_at(&mut self, index: usize) {
        let last = self.lines.len() - 1;
        self.grid.remove(index as u32);
        if index != last {
            self.grid.rename(last as u32, index as u32);
        }
        let removed = self.lines.swap_remove(index);
        self.index_of.remove(&removed.id);
        if index != last {
            self.index_of.insert(self.lines[index].id, index);
        }
    }

    /// The configuration.
    pub fn config(&self) -> &MapConfig {
        &self.config
    }

    /// The map lines, in insertion order.
    pub fn lines(&self) -> &[MapLine] {
        &self.lines
    }

    /// Number of map lines.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// True when the map has no lines.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// The map line that `line` (world frame) matches: among the lines with
    /// `|d_alpha|` and `d_rho` below their thresholds, the one with the
    /// smallest `d_rho` (paper, section 2.1). Only lines near `line`'s
    /// centroid are examined (spatial index). `None` for no match or a
    /// non-finite line.
    pub fn find_match(&self, line: &LineSegment) -> Option<Match> {
        self.find_match_seen_from(line, None)
    }

    /// As [`LineMap::find_match`], for a line seen from `viewpoint` (the
    /// sensor position, world frame): with [`MapConfig::sided`], map lines
    /// seen from the other side are skipped.
    pub fn find_match_seen_from(
        &self,
        line: &LineSegment,
        viewpoint: Option<&Point2<f64>>,
    ) -> Option<Match> {
        self.best_match(line, viewpoint, None)
    }

    /// The best match of `line` under the matching gates and, when `merge`
    /// is set, under the merge gate.
    fn best_match(
        &self,
        line: &LineSegment,
        viewpoint: Option<&Point2<f64>>,
        merge: Option<MergeGate>,
    ) -> Option<Match> {
        let mut best: Option<Match> = None;
        self.visit_candidates(line, viewpoint, &MatchGate::of(&self.config), |index, distance| {
            let m = &self.lines[index];
            if best.is_some_and(|b| b.index == index)
                || merge.is_some_and(|gate| !within_merge_gate(&m.line, line, &gate))
            {
                return;
            }
            if best.is_none_or(|b| distance.d_rho < b.distance.d_rho) {
                best = Some(Match { index, id: m.id, distance });
            }
        });
        best
    }

    /// The indices (into [`LineMap::lines`]) of the map lines that pass
    /// within about `radius_m` of `point` (world frame): every line through
    /// a grid cell that the square of half-side `radius_m` around `point`
    /// touches, so a few lines up to a cell farther are included. Ascending,
    /// each once. Empty for a non-finite point or a radius that is negative
    /// or not finite.
    pub fn lines_near(&self, point: &Point2<f64>, radius_m: f64) -> Vec<usize> {
        if !(radius_m >= 0.0 && radius_m.is_finite()) {
            return Vec::new();
        }
        let mut found: Vec<usize> = Vec::new();
        self.grid.for_each_near(point, radius_m, |id| found.push(id as usize));
        found.sort_unstable();
        found.dedup();
        found
    }

    /// Calls `f` once for every map line that `line` (world frame, seen
    /// from `viewpoint`) matches under `gate` (and the side rule of
    /// [`MapConfig::sided`]), with its metrics. Nothing for a non-finite
    /// line. Only lines near `line`'s centroid are examined.
    pub fn for_each_candidate(
        &self,
        line: &LineSegment,
        viewpoint: Option<&Point2<f64>>,
        gate: &MatchGate,
        mut f: impl FnMut(Match, &MapLine),
    ) {
        let mut seen: Vec<usize> = Vec::new();
        self.visit_candidates(line, viewpoint, gate, |index, distance| {
            if !seen.contains(&index) {
                seen.push(index);
                let m = &self.lines[index];
                f(Match { index, id: m.id, distance }, m);
            }
        });
    }

    /// The grid walk shared by the matchers (a line may be visited twice).
    fn visit_candidates(
        &self,
        line: &LineSegment,
        viewpoint: Option<&Point2<f64>>,
        gate: &MatchGate,
        mut f: impl FnMut(usize, LineDistance),
    ) {
        if !(line.alpha().is_finite()
            && line.d().is_finite()
            && line.centroid().coords.iter().all(|v| v.is_finite()))
        {
            return;
        }
        self.grid.for_each_near(&line.centroid(), gate.max_d_rho_m, |id| {
            let index = id as usize;
            let m = &self.lines[index];
            // The angle first: it rejects most candidates without a sine.
            let d_alpha = line_angle_diff(m.line.alpha(), line.alpha());
            if d_alpha.abs() >= gate.max_d_alpha_rad {
                return;
            }
            let d_d = normal_offset(&m.line, line);
            if gate.max_offset_m.is_some_and(|max| d_d >= max) {
                return;
            }
            let d_rho = d_d + centroid_distance(&m.line, line, self.config.centroid_term);
            if d_rho < gate.max_d_rho_m && (!self.config.sided || same_side(m, viewpoint)) {
                f(index, LineDistance { d_alpha, d_rho });
            }
        });
    }

    /// Adds a line observed by a sensor at `world_from_sensor`: `line` and
    /// the `moments` of its points are in the sensor's frame, as a detector
    /// gives them. Both are placed in the world here, and the sensor's
    /// position is the viewpoint (a new map line remembers the side it was
    /// seen from; with [`MapConfig::sided`] only lines seen from the same
    /// side merge into it). The line is merged into the map line it
    /// matches, or added as a new one; returns the map line's id and the
    /// match, if any. Non-finite lines, and unmatched lines too uncertain to
    /// start a map line ([`MapConfig::max_new_alpha_std_rad`]), are not
    /// added (`None`).
    ///
    /// This is the insertion path of the paper's mapping (section 2.1);
    /// [`LineMap::insert`] takes lines already in the world frame.
    pub fn insert_observed(
        &mut self,
        world_from_sensor: &Pose2,
        line: &LineSegment,
        moments: &Moments,
    ) -> Option<(LineId, Option<Match>)> {
        let viewpoint = Point2::new(world_from_sensor.x(), world_from_sensor.y());
        self.insert_seen_from(
            &line.transformed(world_from_sensor),
            &moments.transformed(world_from_sensor),
            Some(&viewpoint),
        )
    }

    /// Adds a line that is already in the world frame, with the moments of
    /// its points in the world frame (a map built from another source, a
    /// test). It has no viewpoint, so [`MapConfig::sided`] cannot apply to
    /// it: it may merge with a line seen from the other side of a thin wall.
    /// Lines from a sensor go through [`LineMap::insert_observed`].
    pub fn insert(
        &mut self,
        line: &LineSegment,
        moments: &Moments,
    ) -> Option<(LineId, Option<Match>)> {
        self.insert_seen_from(line, moments, None)
    }

    /// The one insertion: `line` and `moments` in the world frame, seen from
    /// `viewpoint` when known.
    fn insert_seen_from(
        &mut self,
        line: &LineSegment,
        moments: &Moments,
        viewpoint: Option<&Point2<f64>>,
    ) -> Option<(LineId, Option<Match>)> {
        if !(line.alpha().is_finite()
            && line.d().is_finite()
            && line.start().coords.iter().chain(line.end().coords.iter()).all(|v| v.is_finite()))
        {
            return None;
        }
        if !self.counted {
            self.scan += 1;
        }
        match self.best_match(line, viewpoint, self.config.merge_gate) {
            Some(m) => {
                self.absorb(m.index, line, moments);
                let merged_into = self.merge_duplicates_of(m.index);
                Some((merged_into.unwrap_or(m.id), Some(m)))
            }
            None => {
                if self.config.max_new_alpha_std_rad.is_some_and(|max| {
                    let std = line.covariance()[(0, 0)].sqrt();
                    std.is_nan() || std > max
                }) {
                    return None;
                }
                let id = LineId(self.next_id);
                self.next_id += 1;
                let index = self.lines.len() as u32;
                self.grid.insert(index, &line.start(), &line.end());
                let mut new = MapLine::new(id, *line, *moments, self.scan);
                new.facing = viewpoint.and_then(|v| facing(line, v));
                if let Some(life) = self.config.lifecycle {
                    new.status = life.status(1, 0.0, 0.0);
                    if new.status == LineStatus::Tentative {
                        self.tentative.push_back((self.scan, id));
                    }
                }
                self.lines.push(new);
                self.index_of.insert(id, index as usize);
                Some((id, None))
            }
        }
    }

    /// Merges `line` into map line `index`: the extent grows to the
    /// projections of the new endpoints (paper); with refinement the line's
    /// parameters are refitted from the merged sums first.
    fn absorb(&mut self, index: usize, line: &LineSegment, moments: &Moments) {
        let refine = self.config.refine;
        let m = &mut self.lines[index];
        let old = m.line;
        let mut base = old;
        if refine {
            let merged = m.moments.merge(moments);
            if let Some(refit) = line_from_moments(&merged, &old.start(), &old.end()) {
                base = refit;
                m.moments = merged;
            }
        } else {
            m.moments = m.moments.merge(moments);
        }
        // Extent: along the (possibly refitted) line, from the accepted
        // endpoint observations.
        m.extremes.add(&base, [line.start(), line.end()], self.config.robust_extent);
        let (lo, hi) = m.extremes.extent(&base);
        base = base.with_extent(lo, hi).with_n_points(m.moments.n);
        m.line = base;
        m.observations += 1;
        m.observed_scatter += line.n_points() as f64 * line.residual_std().powi(2);
        if m.last_scan != self.scan {
            m.last_scan = self.scan;
            m.scans_seen += 1;
        }
        if let Some(life) = self.config.lifecycle {
            m.status = life.status(m.scans_seen, m.rms_m(), m.observed_rms_m());
        }
        let (a, b) = (m.line.start(), m.line.end());
        self.grid.insert(index as u32, &a, &b);
    }

    /// With [`crate::Lifecycle::merge_duplicates`], merges into line `index`
    /// every other line of the same wall: seen from the same side, each
    /// within the merge gate of the other. Returns the id of the surviving
    /// line when a merge happened (the one seen in more scans).
    fn merge_duplicates_of(&mut self, index: usize) -> Option<LineId> {
        let life = self.config.lifecycle?;
        let gate = self.config.merge_gate?;
        if !life.merge_duplicates {
            return None;
        }
        let mut keep = self.lines[index].id;
        loop {
            let i = self.index_of[&keep];
            let me = &self.lines[i];
            let mut other = None;
            let reach = me.line.length() / 2.0 + gate.max_gap_m + self.config.grid_cell_m;
            self.grid.for_each_near(&me.line.centroid(), reach, |id| {
                let j = id as usize;
                if other.is_some() || j == i {
                    return;
                }
                let o = &self.lines[j];
                let facing_ok = match (me.facing, o.facing) {
                    (Some(a), Some(b)) => a.dot(&b) > 0.0,
                    _ => true,
                };
                if facing_ok
                    && line_angle_diff(me.line.alpha(), o.line.alpha()).abs()
                        < self.config.max_d_alpha_rad
                    && within_merge_gate(&me.line, &o.line, &gate)
                    && within_merge_gate(&o.line, &me.line, &gate)
                {
                    other = Some(j);
                }
            });
            let j = other?;
            // The line seen in more scans survives; the other is absorbed.
            let (survivor, absorbed) =
                if self.lines[j].scans_seen > self.lines[i].scans_seen { (j, i) } else { (i, j) };
            let gone = self.lines[absorbed].clone();
            self.absorb_line(survivor, &gone);
            keep = self.lines[survivor].id;
            self.remove_at(absorbed);
        }
    }

    /// Merges map line `other` into line `index`: sums, extents, counts.
    fn absorb_line(&mut self, index: usize, other: &MapLine) {
        let m = &mut self.lines[index];
        let merged = m.moments.merge(&other.moments);
        let (lo_pt, hi_pt) = (m.line.start(), m.line.end());
        if let Some(refit) = line_from_moments(&merged, &lo_pt, &hi_pt) {
            let mut base = refit;
            let s = |p: &Point2<f64>| (p - base.centroid()).dot(&base.direction());
            let along =
                [m.line.start(), m.line.end(), other.line.start(), other.line.end()].map(|p| s(&p));
            let lo = along.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = along.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            base = base.with_extent(lo, hi).with_n_points(merged.n);
            m.line = base;
            m.extremes = Extremes::of(&base);
        }
        m.moments = merged;
        m.observations += other.observations;
        m.observed_scatter += other.observed_scatter;
        m.scans_seen = m.scans_seen.max(other.scans_seen);
        m.first_scan = m.first_scan.min(other.first_scan);
        m.last_scan = m.last_scan.max(other.last_scan);
        if let Some(life) = self.config.lifecycle {
            m.status = life.status(m.scans_seen, m.rms_m(), m.observed_rms_m());
        }
        let (a, b) = (m.line.start(), m.line.end());
        self.grid.insert(index as u32, &a, &b);
    }

    /// Rebuilds a map from saved lines (ids kept; the next id follows the largest).
    pub fn from_lines(config: MapConfig, lines: Vec<MapLine>) -> Result<Self, ConfigError> {
        let mut map = LineMap::new(config)?;
        for (i, l) in lines.iter().enumerate() {
            map.grid.insert(i as u32, &l.line.start(), &l.line.end());
            map.index_of.insert(l.id, i);
            if l.status == LineStatus::Tentative {
                map.tentative.push_back((l.first_scan, l.id));
            }
        }
        map.next_id = lines.iter().map(|l| l.id.0 + 1).max().unwrap_or(0);
        map.scan = lines.iter().map(|l| l.last_scan).max().unwrap_or(0);
        map.lines = lines;
        Ok(map)
    }
}

/// Whether `new` may merge into map line `map`: both endpoints within
/// `gate.max_offset_m` of the line, and its extent within `gate.max_gap_m`
/// of the map line's along the line.
fn within_merge_gate(map: &LineSegment, new: &LineSegment, gate: &MergeGate) -> bool {
    let n = map.normal();
    let offsets_ok = [new.start(), new.end()]
        .iter()
        .all(|p| (n.dot(&p.coords) - map.d()).abs() <= gate.max_offset_m);
    let along = |p: &Point2<f64>| (p - map.start()).dot(&map.direction());
    let (a, b) = (along(&new.start()), along(&new.end()));
    let (lo, hi) = (a.min(b), a.max(b));
    let map_end = along(&map.end());
    let (map_lo, map_hi) = (map_end.min(0.0), map_end.max(0.0));
    let gap = (lo - map_hi).max(map_lo - hi).max(0.0);
    offsets_ok && gap <= gate.max_gap_m
}

/// The unit normal of `line` pointing to `viewpoint`'s side; `None` when
/// the viewpoint lies on the line or is not finite.
fn facing(line: &LineSegment, viewpoint: &Point2<f64>) -> Option<Vector2<f64>> {
    let s = line.normal().dot(&viewpoint.coords) - line.d();
    (s.is_finite() && s != 0.0).then(|| line.normal() * s.signum())
}

/// Whether `viewpoint` is on the side map line `m` was seen from (true when
/// either is unknown).
fn same_side(m: &MapLine, viewpoint: Option<&Point2<f64>>) -> bool {
    let (Some(facing), Some(v)) = (m.facing, viewpoint) else { return true };
    let n = m.line.normal();
    (n.dot(&v.coords) - m.line.d()) * n.dot(&facing) > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CentroidTerm;
    use pcaline_geometry::Vector2;

    fn wall(x: f64, y0: f64, y1: f64) -> (LineSegment, Moments) {
        let pts: Vec<_> =
            (0..=20).map(|i| Point2::new(x, y0 + (y1 - y0) * i as f64 / 20.0)).collect();
        let m = Moments::from_points(&pts);
        (line_from_moments(&m, &pts[0], &pts[20]).unwrap(), m)
    }

    #[test]
    fn paper_map_extends_endpoints_and_keeps_parameters() {
        let mut map = LineMap::new(MapConfig::paper()).unwrap();
        let (a, ma) = wall(3.0, 0.0, 1.0);
        let (id, m) = map.insert(&a, &ma).unwrap();
        assert!(m.is_none());
        let (b, mb) = wall(3.05, 0.5, 1.5);
        let (id2, m2) = map.insert(&b, &mb).unwrap();
        assert_eq!(id, id2);
        assert!(m2.is_some());
        let l = &map.lines()[0].line;
        assert!((l.d() - 3.0).abs() < 1e-12, "paper keeps the map line's parameters");
        assert!((l.length() - 1.5).abs() < 1e-9);
        assert_eq!(map.lines()[0].observations, 2);
    }

    #[test]
    fn lines_near_a_point_come_from_the_grid_each_once() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        for (x, y0, y1) in [(3.0, 0.0, 6.0), (40.0, 0.0, 1.0), (-5.0, -1.0, 1.0)] {
            let (l, m) = wall(x, y0, y1);
            map.insert(&l, &m);
        }
        // The first wall spans three cells of 2 m: still listed once.
        assert_eq!(map.lines_near(&Point2::new(0.0, 0.0), 6.0), vec![0, 2]);
        assert_eq!(map.lines_near(&Point2::new(40.0, 0.5), 1.0), vec![1]);
        assert_eq!(map.lines_near(&Point2::new(0.0, 0.0), 1e9), vec![0, 1, 2]);
        assert!(map.lines_near(&Point2::new(20.0, 20.0), 3.0).is_empty());
        assert!(map.lines_near(&Point2::new(f64::NAN, 0.0), 6.0).is_empty());
        assert!(map.lines_near(&Point2::new(0.0, 0.0), -1.0).is_empty());
        assert!(map.lines_near(&Point2::new(0.0, 0.0), f64::INFINITY).is_empty());
    }

    #[test]
    fn refined_map_refits_from_all_points() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        let (a, ma) = wall(3.0, 0.0, 1.0);
        map.insert(&a, &ma);
        let (b, mb) = wall(3.03, 1.0, 2.0);
        map.insert(&b, &mb);
        // The robust extent waits for a second observation of an extension.
        assert!((map.lines()[0].line.length() - 1.0).abs() < 0.01);
        map.insert(&b, &mb);
        let l = &map.lines()[0].line;
        assert!((l.length() - 2.0).abs() < 0.01, "{l:?}");
        assert_eq!(map.lines()[0].moments.n, 63);
        assert!(l.centroid().x > 3.0 && l.centroid().x < 3.03);
    }

    #[test]
    fn a_single_glitch_does_not_extend_a_robust_extent() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        let (a, ma) = wall(3.0, 0.0, 2.0);
        for _ in 0..5 {
            map.insert(&a, &ma);
        }
        let (glitch, mg) = wall(3.0, 0.5, 2.3);
        map.insert(&glitch, &mg);
        assert!((map.lines()[0].line.length() - 2.0).abs() < 0.01);
        // A second observation reaching 2.1 confirms the extension up to 2.1.
        let (b, mb) = wall(3.0, 0.5, 2.1);
        map.insert(&b, &mb);
        assert!((map.lines()[0].line.length() - 2.1).abs() < 0.01, "{:?}", map.lines()[0].line);
    }

    #[test]
    fn smallest_d_rho_wins_and_far_lines_do_not_match() {
        let mut map = LineMap::new(MapConfig::paper()).unwrap();
        for x in [3.0, 3.6] {
            let (l, m) = wall(x, 0.0, 1.0);
            map.insert(&l, &m);
        }
        let (q, _) = wall(3.5, 0.0, 1.0);
        assert_eq!(map.find_match(&q).unwrap().id, LineId(1));
        let (far, _) = wall(10.0, 0.0, 1.0);
        assert!(map.find_match(&far).is_none());
        // A perpendicular line nearby does not match (d_alpha above 15°).
        let perp = LineSegment::through(
            Point2::new(3.0, 0.5),
            Vector2::new(1.0, 0.0),
            Point2::new(2.5, 0.5),
            Point2::new(3.5, 0.5),
        );
        assert!(map.find_match(&perp).is_none());
    }

    #[test]
    fn long_wall_fragments_with_centroid_term_not_with_segment_gap() {
        for (term, expect) in [(CentroidTerm::Centroid, 2), (CentroidTerm::SegmentGap, 1)] {
            let config = MapConfig { centroid_term: term, ..MapConfig::paper() };
            let mut map = LineMap::new(config).unwrap();
            let (a, ma) = wall(3.0, 0.0, 10.0);
            map.insert(&a, &ma);
            let (b, mb) = wall(3.0, 9.0, 10.0);
            map.insert(&b, &mb);
            assert_eq!(map.len(), expect, "{term:?}");
        }
    }

    #[test]
    fn uncertain_lines_do_not_start_map_lines() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        let (a, ma) = wall(3.0, 0.0, 1.0);
        let with_alpha_std = |deg: f64| {
            let mut c = a.covariance();
            c[(0, 0)] = deg.to_radians().powi(2);
            a.with_statistics(a.n_points(), a.residual_std(), c)
        };
        assert!(map.insert(&with_alpha_std(2.0), &ma).is_none());
        assert!(map.insert(&with_alpha_std(0.5), &ma).is_some());
        // Once the map line exists, an uncertain observation is absorbed.
        assert!(map.insert(&with_alpha_std(2.0), &ma).is_some_and(|(_, m)| m.is_some()));
    }

    #[test]
    fn non_finite_lines_are_ignored() {
        let mut map = LineMap::new(MapConfig::paper()).unwrap();
        let (a, ma) = wall(3.0, 0.0, 1.0);
        let a = LineSegment::from_hessian(f64::NAN, a.d(), a.centroid(), a.start(), a.end());
        assert!(a.alpha().is_nan());
        assert!(map.insert(&a, &ma).is_none());
        assert!(map.find_match(&a).is_none());
        assert!(map.is_empty());
    }

    #[test]
    fn an_observation_is_placed_in_the_world_with_its_moments() {
        // The wall x = 3 (world), 0 <= y <= 1, seen from two sensor poses.
        let (world_wall, world_moments) = wall(3.0, 0.0, 1.0);
        let mut observed = LineMap::new(MapConfig::default()).unwrap();
        let mut by_hand = LineMap::new(MapConfig::default()).unwrap();
        for world_from_sensor in [Pose2::new(1.0, 0.5, 0.3), Pose2::new(0.5, -0.2, -0.4)] {
            let sensor_from_world = world_from_sensor.inverse();
            let line = world_wall.transformed(&sensor_from_world);
            let moments = world_moments.transformed(&sensor_from_world);
            observed.insert_observed(&world_from_sensor, &line, &moments).unwrap();
            let viewpoint = Point2::new(world_from_sensor.x(), world_from_sensor.y());
            by_hand.insert_seen_from(
                &line.transformed(&world_from_sensor),
                &moments.transformed(&world_from_sensor),
                Some(&viewpoint),
            );
        }
        assert_eq!(observed.lines(), by_hand.lines());
        assert_eq!(observed.len(), 1);
        let m = &observed.lines()[0];
        assert!((m.line.d() - 3.0).abs() < 1e-9 && m.line.alpha().abs() < 1e-9, "{:?}", m.line);
        assert!((m.moments.mean - world_moments.mean).norm() < 1e-9);
        // Seen from x < 3: the side is remembered.
        assert!(m.facing.is_some());
    }

    #[test]
    fn the_two_faces_of_a_thin_wall_stay_two_sided_lines() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        let (west, mw) = wall(0.0, 0.0, 3.0);
        let (east, me) = wall(0.04, 0.0, 3.0);
        let (from_west, from_east) = (Point2::new(-2.0, 1.5), Point2::new(2.0, 1.5));
        let (a, _) = map.insert_seen_from(&west, &mw, Some(&from_west)).unwrap();
        let (b, m) = map.insert_seen_from(&east, &me, Some(&from_east)).unwrap();
        assert!(a != b && m.is_none(), "the far face must not merge into the near one");
        // Each face matches only from its own side.
        assert_eq!(map.find_match_seen_from(&west, Some(&from_west)).unwrap().id, a);
        assert_eq!(map.find_match_seen_from(&east, Some(&from_east)).unwrap().id, b);
        // Unsided (the paper), the far face merges into the near one.
        let mut paper = LineMap::new(MapConfig { sided: false, ..MapConfig::default() }).unwrap();
        paper.insert_seen_from(&west, &mw, Some(&from_west));
        assert!(paper.insert_seen_from(&east, &me, Some(&from_east)).unwrap().1.is_some());
    }

    #[test]
    fn the_merge_gate_keeps_doorways_and_end_faces_out_of_a_line() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        let (left, ml) = wall(0.0, 0.0, 2.0);
        let id = map.insert(&left, &ml).unwrap().0;
        // Collinear, across a 0.5 m gap: it matches (the same infinite line,
        // so the aiding may use it) but starts its own map line.
        let (right, mr) = wall(0.0, 2.5, 3.3);
        assert_eq!(map.find_match(&right).unwrap().id, id);
        let (right_id, m) = map.insert(&right, &mr).unwrap();
        assert!(right_id != id && m.is_none());
        // 8 cm in front of the wall (a face of something else): its own line.
        let (front, mf) = wall(0.08, 0.5, 1.0);
        assert!(map.insert(&front, &mf).unwrap().1.is_none());
        // A new observation overlapping the wall, 1 cm off: merged.
        let (again, ma) = wall(0.01, 1.5, 2.2);
        assert_eq!(map.insert(&again, &ma).unwrap().0, id);
        assert_eq!(map.len(), 3);
    }

    #[test]
    fn a_line_is_tentative_until_seen_in_three_scans_and_expires_otherwise() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        let (long, mw) = wall(3.0, 0.0, 2.0);
        let (legs, ml) = wall(1.0, 5.0, 6.0); // seen once: three chair legs
        map.begin_scan();
        let id = map.insert(&long, &mw).unwrap().0;
        let one_off = map.insert(&legs, &ml).unwrap().0;
        // Two pieces of the wall in one scan are one sighting.
        map.insert(&long, &mw);
        assert_eq!(map.get(id).unwrap().status, LineStatus::Tentative);
        for _ in 0..2 {
            map.begin_scan();
            map.insert(&long, &mw);
        }
        assert_eq!(map.get(id).unwrap().status, LineStatus::Confirmed);
        assert_eq!(map.get(id).unwrap().scans_seen, 3);
        for _ in 0..10 {
            map.begin_scan();
        }
        assert!(map.get(one_off).is_none(), "the one-off line expired");
        assert!(map.get(id).is_some(), "a confirmed line never expires");
        assert_eq!(map.len(), 1);
        // The index still finds the survivor after the removal.
        assert_eq!(map.find_match(&long).unwrap().id, id);
    }

    #[test]
    fn duplicates_of_one_wall_merge_into_one_line() {
        let mut map = LineMap::new(MapConfig::default()).unwrap();
        let viewpoint = Point2::new(0.0, 1.0);
        // Two copies 2 cm apart, made while the first was out of the merge
        // gate's reach along the wall (more than 0.3 m away)...
        let (a, ma) = wall(3.0, 0.0, 1.0);
        let (b, mb) = wall(3.02, 1.5, 2.5);
        map.insert_seen_from(&a, &ma, Some(&viewpoint));
        map.insert_seen_from(&b, &mb, Some(&viewpoint));
        assert_eq!(map.len(), 2);
        // ...grow together when a sighting bridges the gap: one line remains.
        let (c, mc) = wall(3.01, 0.5, 2.0);
        for _ in 0..3 {
            map.insert_seen_from(&c, &mc, Some(&viewpoint));
        }
        assert_eq!(map.len(), 1, "{:?}", map.lines());
        let l = &map.lines()[0];
        assert!((l.line.length() - 2.5).abs() < 0.05, "{:?}", l.line);
        assert_eq!(l.moments.n, 21 * 5);
    }

    #[test]
    fn a_curved_surface_is_marked_not_straight() {
        // The rule with a 3 mm allowance for pose errors (the default's 1 cm
        // suits real walls seen from estimated poses).
        let config = MapConfig {
            lifecycle: Some(crate::Lifecycle {
                straightness_floor_m: 0.003,
                ..crate::Lifecycle::standard()
            }),
            ..MapConfig::default()
        };
        let mut map = LineMap::new(config).unwrap();
        // Chords of a circle of radius 2 m, each with a 2 mm residual of its
        // own, seen from viewpoints that slide along it: the merged points
        // scatter about the merged line by more than a centimetre.
        let chord = |t0: f64| {
            let pts: Vec<_> = (0..=20)
                .map(|i| {
                    let t = t0 + 0.01 * i as f64;
                    Point2::new(2.0 * t.cos(), 2.0 * t.sin())
                })
                .collect();
            let m = Moments::from_points(&pts);
            let l = line_from_moments(&m, &pts[0], &pts[20]).unwrap();
            let l = l.with_statistics(l.n_points(), 0.001, l.covariance());
            (l, m)
        };
        for k in 0..6 {
            let (l, m) = chord(-0.1 + 0.04 * k as f64);
            map.insert(&l, &m);
        }
        assert!(
            map.lines().iter().any(|l| l.status == LineStatus::NotStraight),
            "{:?}",
            map.lines()
        );
        // A straight wall seen as often stays confirmed.
        let mut flat = LineMap::new(config).unwrap();
        for k in 0..6 {
            let (l, m) = wall(3.0, 0.1 * k as f64, 1.0 + 0.1 * k as f64);
            let l = l.with_statistics(l.n_points(), 0.002, l.covariance());
            flat.insert(&l, &m);
        }
        assert!(flat.lines().iter().all(|l| l.is_confirmed()), "{:?}", flat.lines());
    }
}
