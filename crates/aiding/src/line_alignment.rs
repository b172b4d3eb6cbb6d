//! [`align_lines`]: the rigid transform between two sets of line segments,
//! found without a good prior. Loop closure verifies a candidate keyframe
//! with it.
//!
//! Hypotheses come from pairs of non-parallel lines: two lines in one set
//! matched to two lines in the other fix a rotation (from their directions)
//! and a translation (from their intersections, a corner or a virtual one).
//! Each hypothesis is scored by the length of wall it lays over the other
//! set; the best is refined by iterated least squares over the
//! endpoint-to-line distances of its matches. The result carries what a
//! consistency test needs: the matched length, the weakest constrained
//! direction, the rms residual and the information of the estimate.

use pcaline_geometry::{
    ConfigError, LineSegment, Matrix2, Matrix3, Point2, Pose2, Vector2, Vector3, wrap_angle,
};

/// Walls shorter than this do not block a ray in [`see_through_fraction`].
const SEE_THROUGH_MIN_WALL_M: f64 = 1.0;

/// Tuning of [`align_lines`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct AlignmentConfig {
    /// Two lines form a hypothesis pair when their directions differ by at
    /// least this, radians.
    pub min_pair_angle_rad: f64,
    /// Pair angles in the two sets must agree within this, radians.
    pub pair_angle_tolerance_rad: f64,
    /// A transformed line matches a line of the other set within this
    /// direction difference, radians...
    pub match_angle_rad: f64,
    /// ... with both endpoints within this distance of its infinite line,
    /// metres ...
    pub match_distance_m: f64,
    /// ... and overlapping it along the line by at least this, metres.
    pub min_overlap_m: f64,
    /// The longest lines of each set that form hypothesis pairs (bounds the
    /// work at `n²(n-1)²/2` hypotheses).
    pub hypothesis_lines: usize,
    /// A hypothesis pair's intersection must lie within this of both
    /// segments, metres (a corner, or the meeting point of two walls in view).
    pub max_corner_distance_m: f64,
    /// Gauss-Newton rounds of the refinement.
    pub refine_iterations: usize,
    /// Whether a line matches lines facing either way, or only the same way.
    /// A configuration file that leaves it out gets [`Facing::Either`].
    #[cfg_attr(feature = "serde", serde(default))]
    pub facing: Facing,
}

/// Which lines of the other set a line may match in [`align_lines`]. The
/// default is [`Facing::Either`], which asks nothing of the sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum Facing {
    /// Any line along it, whichever way either is directed: for sets whose
    /// line directions mean nothing (walls drawn by hand, merged map lines).
    #[default]
    Either,
    /// Only a line directed the same way (their directions less than 90°
    /// apart). Both sets must be directed with the sensor that saw each
    /// line on its left, as the detector's lines are (scan order, bearings
    /// increasing counter-clockwise) and as [`crate::LoopClosing`] orients
    /// its keyframes' lines. The two faces of a wall, seen from either
    /// side, then never match: in a building of 10 cm walls, the least
    /// squares otherwise pulls an alignment up to a wall's thickness
    /// towards the far face (`docs/accuracy.md`).
    Same,
}

impl AlignmentConfig {
    /// Defaults for indoor scans: pairs at least 30° apart, matches within 3°
    /// and 10 cm overlapping 20 cm, the 12 longest lines, corners within 2 m,
    /// lines facing either way.
    pub const fn standard() -> Self {
        AlignmentConfig {
            min_pair_angle_rad: 30f64.to_radians(),
            pair_angle_tolerance_rad: 3f64.to_radians(),
            match_angle_rad: 3f64.to_radians(),
            match_distance_m: 0.10,
            min_overlap_m: 0.2,
            hypothesis_lines: 12,
            max_corner_distance_m: 2.0,
            refine_iterations: 5,
            facing: Facing::Either,
        }
    }

    /// [`AlignmentConfig::standard`] for sets directed with their sensor on
    /// the left ([`Facing::Same`]): loop closure's keyframe lines.
    pub const fn sided() -> Self {
        AlignmentConfig { facing: Facing::Same, ..Self::standard() }
    }

    /// Checks every field; errors name `prefix.field`.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        let angles = [
            ("min_pair_angle_rad", self.min_pair_angle_rad),
            ("pair_angle_tolerance_rad", self.pair_angle_tolerance_rad),
            ("match_angle_rad", self.match_angle_rad),
        ];
        for (name, v) in angles {
            ConfigError::check_field(
                v > 0.0 && v < std::f64::consts::FRAC_PI_2,
                prefix,
                name,
                v,
                "must be in (0, pi/2)",
            )?;
        }
        ConfigError::positive_fields(
            prefix,
            &[
                ("match_distance_m", self.match_distance_m),
                ("min_overlap_m", self.min_overlap_m),
                ("max_corner_distance_m", self.max_corner_distance_m),
            ],
        )?;
        ConfigError::check_field(
            (2..=64).contains(&self.hypothesis_lines),
            prefix,
            "hypothesis_lines",
            self.hypothesis_lines as f64,
            "must be in 2..=64",
        )?;
        ConfigError::check_field(
            (1..=50).contains(&self.refine_iterations),
            prefix,
            "refine_iterations",
            self.refine_iterations as f64,
            "must be in 1..=50",
        )
    }
}

impl Default for AlignmentConfig {
    fn default() -> Self {
        Self::standard()
    }
}

/// A bound on the transform, from what the caller already knows: hypotheses
/// outside it are not scored, and its own transform is scored as one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignmentPrior {
    /// The expected `candidate_from_current`.
    pub candidate_from_current: Pose2,
    /// The translation may differ from the expected by at most this, metres.
    pub radius_m: f64,
    /// The rotation may differ from the expected by at most this, radians
    /// (`>= pi` leaves it free).
    pub max_rotation_rad: f64,
}

/// The transform [`align_lines`] found, with what a consistency test needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alignment {
    /// Maps the current set's frame into the candidate set's frame.
    pub candidate_from_current: Pose2,
    /// Matched lines.
    pub matches: usize,
    /// Length of the current set's walls laid over the candidate's, metres.
    pub matched_length_m: f64,
    /// Total length of the current set's lines, metres.
    pub current_length_m: f64,
    /// The smallest eigenvalue of `sum(len * n n^T)` over the matches, metres:
    /// the matched wall length that constrains the weakest direction (about
    /// zero in a corridor).
    pub weakest_direction_m: f64,
    /// Rms endpoint-to-line distance of the matches, metres.
    pub rms_m: f64,
    /// Information of the estimate in `(x, y, heading)`, for an endpoint
    /// noise of `max(rms_m, noise_floor)`.
    pub information: Matrix3<f64>,
    /// The matched length of the best hypothesis that places the current set
    /// at least 0.5 m or 5° from this one, metres (0 if none): close to
    /// `matched_length_m` when the structure repeats and the alignment is
    /// ambiguous.
    pub runner_up_length_m: f64,
}

/// One line in a form the alignment reuses: its infinite line and extent.
#[derive(Debug, Clone, Copy)]
struct Seg {
    start: Point2<f64>,
    end: Point2<f64>,
    /// Unit direction from start to end.
    dir: Vector2<f64>,
    /// Unit normal.
    n: Vector2<f64>,
    /// `n . p` for points on the line.
    d: f64,
    len: f64,
}

impl Seg {
    fn of(l: &LineSegment) -> Option<Seg> {
        let v = l.end() - l.start();
        let len = v.norm();
        if len.is_nan() || len <= 1e-6 || !len.is_finite() {
            return None;
        }
        let dir = v / len;
        let n = Vector2::new(-dir.y, dir.x);
        Some(Seg { start: l.start(), end: l.end(), dir, n, d: n.dot(&l.start().coords), len })
    }

    fn moved(&self, t: &Pose2) -> Seg {
        let start = t.transform_point(&self.start);
        let end = t.transform_point(&self.end);
        let dir = t.rotate(&self.dir);
        let n = Vector2::new(-dir.y, dir.x);
        Seg { start, end, dir, n, d: n.dot(&start.coords), len: self.len }
    }

    fn angle(&self) -> f64 {
        self.dir.y.atan2(self.dir.x)
    }

    /// Distance from `p` to the segment (not the infinite line).
    fn distance_to(&self, p: &Point2<f64>) -> f64 {
        let s = (p - self.start).dot(&self.dir).clamp(0.0, self.len);
        (p - (self.start + self.dir * s)).norm()
    }
}

/// Direction difference of two undirected lines, in `[0, pi/2]`.
fn undirected_difference(a: f64, b: f64) -> f64 {
    let d = wrap_angle(a - b).abs();
    d.min(std::f64::consts::PI - d)
}

/// The intersection of two infinite lines, if they are not parallel.
fn intersection(a: &Seg, b: &Seg) -> Option<Point2<f64>> {
    let m = Matrix2::new(a.n.x, a.n.y, b.n.x, b.n.y);
    let p = m.try_inverse()? * Vector2::new(a.d, b.d);
    p.iter().all(|v| v.is_finite()).then(|| Point2::from(p))
}

/// A match of a (transformed) current line with a candidate line: the
/// overlap length, if they match.
fn overlap(c: &Seg, k: &Seg, max_sin: f64, config: &AlignmentConfig) -> Option<f64> {
    // The undirected angle between the lines, compared by its sine (no
    // atan2 in the inner loop): `max_sin` is `sin(match_angle_rad)`.
    if c.dir.perp(&k.dir).abs() > max_sin
        || (config.facing == Facing::Same && c.dir.dot(&k.dir) <= 0.0)
    {
        return None;
    }
    let ds = (k.n.dot(&c.start.coords) - k.d).abs();
    let de = (k.n.dot(&c.end.coords) - k.d).abs();
    if ds > config.match_distance_m || de > config.match_distance_m {
        return None;
    }
    let a = (c.start - k.start).dot(&k.dir);
    let b = (c.end - k.start).dot(&k.dir);
    let lo = a.min(b).max(0.0);
    let hi = a.max(b).min(k.len);
    let o = hi - lo;
    (o >= config.min_overlap_m).then_some(o)
}

/// The sine of an undirected angle bound: two lines are within `angle_rad`
/// of each other when the sine of their angle is at most this (any pair
/// when the bound is 90° or more).
fn max_sine(angle_rad: f64) -> f64 {
    if angle_rad >= std::f64::consts::FRAC_PI_2 { f64::INFINITY } else { angle_rad.sin() }
}

/// For each current line, its best match in the candidate set under `t`:
/// `(current index, candidate index, overlap)`.
fn matches(
    current: &[Seg],
    candidate: &[Seg],
    t: &Pose2,
    config: &AlignmentConfig,
    out: &mut Vec<(usize, usize, f64)>,
) -> f64 {
    out.clear();
    let max_sin = max_sine(config.match_angle_rad);
    let mut total = 0.0;
    for (i, c) in current.iter().enumerate() {
        let moved = c.moved(t);
        let best = candidate
            .iter()
            .enumerate()
            .filter_map(|(j, k)| overlap(&moved, k, max_sin, config).map(|o| (j, o)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((j, o)) = best {
            let o = o.min(c.len);
            out.push((i, j, o));
            total += o;
        }
    }
    total
}

/// Aligns the `current` lines to the `candidate` lines: the transform
/// `candidate_from_current` that lays the most wall of one set over the
/// other, refined by least squares.
///
/// Hypotheses come from pairs of lines that meet at a corner, matched
/// between the sets; with a `prior`, the prior's own transform is one more
/// (where the caller's chain places the current set), so a repeated
/// structure that the corner pairs only catch one period away shows up as a
/// close runner-up instead of a confident wrong fit.
///
/// Edge cases: fewer than two usable lines in either set, or no hypothesis
/// with a match, gives `None`. Degenerate lines (zero length, non-finite)
/// are ignored. Without a prior, a parallel-only set (a corridor) yields no
/// hypothesis: its along-corridor offset is unobservable; with one, its fit
/// reports that direction as unconstrained
/// ([`Alignment::weakest_direction_m`] near zero) or fails (`None`).
///
/// ```
/// use pcaline_aiding::{AlignmentConfig, align_lines};
/// use pcaline_geometry::{LineSegment, Point2, Pose2};
///
/// let room = [
///     LineSegment::between(Point2::new(0.0, 0.0), Point2::new(4.0, 0.0)),
///     LineSegment::between(Point2::new(4.0, 0.0), Point2::new(4.0, 3.0)),
///     LineSegment::between(Point2::new(4.0, 3.0), Point2::new(1.0, 3.0)),
/// ];
/// let shift = Pose2::new(0.5, -0.2, 0.1);
/// let seen: Vec<_> = room.iter().map(|l| l.transformed(&shift.inverse())).collect();
/// let a = align_lines(&seen, &room, None, &AlignmentConfig::standard()).unwrap();
/// assert!((a.candidate_from_current.x() - 0.5).abs() < 1e-6);
/// assert!((a.candidate_from_current.heading() - 0.1).abs() < 1e-6);
/// ```
pub fn align_lines(
    current: &[LineSegment],
    candidate: &[LineSegment],
    prior: Option<&AlignmentPrior>,
    config: &AlignmentConfig,
) -> Option<Alignment> {
    let cur: Vec<Seg> = current.iter().filter_map(Seg::of).collect();
    let cand: Vec<Seg> = candidate.iter().filter_map(Seg::of).collect();
    if cur.len() < 2 || cand.len() < 2 {
        return None;
    }
    // The longest lines, one of each wall: a local set holds the same wall
    // seen from several keyframes, and copies make no hypothesis pair.
    let longest = |s: &[Seg]| {
        let mut idx: Vec<usize> = (0..s.len()).collect();
        idx.sort_by(|a, b| s[*b].len.total_cmp(&s[*a].len));
        let mut kept: Vec<usize> = Vec::with_capacity(config.hypothesis_lines);
        for i in idx {
            if kept.len() == config.hypothesis_lines {
                break;
            }
            let copy = kept.iter().any(|&k| {
                undirected_difference(s[i].angle(), s[k].angle()) < config.match_angle_rad
                    && (s[k].n.dot(&s[i].start.coords) - s[k].d).abs() < config.match_distance_m
                    && (s[k].n.dot(&s[i].end.coords) - s[k].d).abs() < config.match_distance_m
            });
            if !copy {
                kept.push(i);
            }
        }
        kept
    };
    let pairs = |s: &[Seg], idx: &[usize]| {
        let mut out = Vec::new();
        for (n, &a) in idx.iter().enumerate() {
            for &b in &idx[n + 1..] {
                let angle = undirected_difference(s[a].angle(), s[b].angle());
                if angle < config.min_pair_angle_rad {
                    continue;
                }
                let Some(p) = intersection(&s[a], &s[b]) else { continue };
                if s[a].distance_to(&p) > config.max_corner_distance_m
                    || s[b].distance_to(&p) > config.max_corner_distance_m
                {
                    continue;
                }
                out.push((a, b, angle, p));
            }
        }
        out
    };
    let cur_pairs = pairs(&cur, &longest(&cur));
    let cand_pairs = pairs(&cand, &longest(&cand));
    let mut scratch = Vec::new();
    let mut best: Option<(f64, Pose2)> = None;
    // Every hypothesis's score, for the runner-up distinct from the best.
    let mut scored: Vec<(f64, Pose2)> = Vec::new();
    let mut consider = |t: Pose2| {
        let score = matches(&cur, &cand, &t, config, &mut scratch);
        if score > 0.0 {
            scored.push((score, t));
        }
        if best.is_none_or(|(s, _)| score > s) {
            best = Some((score, t));
        }
    };
    for &(a, b, angle, p) in &cur_pairs {
        for &(c, d, angle_k, q) in &cand_pairs {
            if (angle - angle_k).abs() > config.pair_angle_tolerance_rad {
                continue;
            }
            // a with c and b with d, or a with d and b with c; each line
            // direction is known up to pi.
            for (k1, k2) in [(c, d), (d, c)] {
                for flip in [0.0, std::f64::consts::PI] {
                    let rotation = wrap_angle(cand[k1].angle() - cur[a].angle() + flip);
                    let rotated_b = cur[b].angle() + rotation;
                    if undirected_difference(rotated_b, cand[k2].angle())
                        > config.pair_angle_tolerance_rad
                    {
                        continue;
                    }
                    let r = Pose2::new(0.0, 0.0, rotation);
                    let moved = r.transform_point(&p);
                    let t = Pose2::new(q.x - moved.x, q.y - moved.y, rotation);
                    if let Some(prior) = prior {
                        let e = prior.candidate_from_current;
                        if (t.x() - e.x()).hypot(t.y() - e.y()) > prior.radius_m
                            || wrap_angle(t.heading() - e.heading()).abs() > prior.max_rotation_rad
                        {
                            continue;
                        }
                    }
                    consider(t);
                }
            }
        }
    }
    // The prior itself is a hypothesis too: where the chain places the
    // current set. In a corridor with a repeated structure the corner pairs
    // may only produce an alignment one period away; scored here, the
    // prior's own overlap makes such an alignment ambiguous (the runner-up
    // below) instead of a confident false loop.
    if let Some(prior) = prior {
        consider(prior.candidate_from_current);
    }
    let (score, t) = best?;
    if score.is_nan() || score <= 0.0 {
        return None;
    }
    let mut a = refine(&cur, &cand, t, config)?;
    // The best hypothesis placing the current set at least 0.5 m or 5° away
    // from the refined one: repeated structure (a grid of identical rooms,
    // a row of doors) scores almost as well one period away.
    let t = a.candidate_from_current;
    a.runner_up_length_m = scored
        .iter()
        .filter(|(_, h)| {
            (h.x() - t.x()).hypot(h.y() - t.y()) > DISTINCT_M
                || wrap_angle(h.heading() - t.heading()).abs() > DISTINCT_RAD
        })
        .map(|(s, _)| *s)
        .fold(0.0, f64::max);
    Some(a)
}

/// The length of `current`'s walls that `candidate_from_current` lays over
/// `candidate`'s under the matching rule of `config` (each current line's
/// best overlap, at most its own length), metres: the score
/// [`align_lines`] gives a hypothesis. Degenerate lines count nothing.
pub fn laid_length(
    current: &[LineSegment],
    candidate: &[LineSegment],
    candidate_from_current: &Pose2,
    config: &AlignmentConfig,
) -> f64 {
    let cur: Vec<Seg> = current.iter().filter_map(Seg::of).collect();
    let cand: Vec<Seg> = candidate.iter().filter_map(Seg::of).collect();
    matches(&cur, &cand, candidate_from_current, config, &mut Vec::new())
}

/// Two hypotheses are distinct beyond this distance, metres ...
const DISTINCT_M: f64 = 0.5;
/// ... or this rotation, radians (5°).
const DISTINCT_RAD: f64 = 0.0873;

/// Iterated least squares from the hypothesis `t`: the matches are found
/// again after each Gauss-Newton step, [`AlignmentConfig::refine_iterations`]
/// times at most; then the matches at the result are held, and the result is
/// their least-squares solution.
///
/// Re-matching alone need not settle: where a line's best match flips
/// between two candidates from one step to the next, the steps go round a
/// cycle. Over `pcaline eval --real` (the real logs' loop candidates), 1656
/// refinements still moved by more than 1 mm at their 20th step, 881 by more
/// than 1 cm. Held matches make the result a definite optimum, whatever the
/// cycle.
fn refine(cur: &[Seg], cand: &[Seg], mut t: Pose2, config: &AlignmentConfig) -> Option<Alignment> {
    let mut found = Vec::new();
    for _ in 0..config.refine_iterations {
        matches(cur, cand, &t, config, &mut found);
        let step;
        (t, step) = gauss_newton_step(cur, cand, &t, &found)?;
        if step < CONVERGED {
            break;
        }
    }
    let matched_length_m = matches(cur, cand, &t, config, &mut found);
    if found.is_empty() {
        return None;
    }
    for _ in 0..HELD_ITERATIONS {
        let step;
        (t, step) = gauss_newton_step(cur, cand, &t, &found)?;
        if step < CONVERGED {
            break;
        }
    }
    let (h, _, sum_w, sum_wr2) = normal_equations(cur, cand, &t, &found);
    let mut directions = Matrix2::zeros();
    for &(_, j, o) in &found {
        let n = cand[j].n;
        directions += n * n.transpose() * o;
    }
    let weakest = directions.symmetric_eigenvalues().min();
    let rms_m = if sum_w > 0.0 { (sum_wr2 / sum_w).sqrt() } else { 0.0 };
    Some(Alignment {
        candidate_from_current: t,
        matches: found.len(),
        matched_length_m,
        current_length_m: cur.iter().map(|s| s.len).sum(),
        weakest_direction_m: weakest.max(0.0),
        rms_m,
        // Unit endpoint noise; the caller scales it by its noise.
        information: h,
        runner_up_length_m: 0.0,
    })
}

/// A Gauss-Newton step smaller than this has converged (metres and radians).
const CONVERGED: f64 = 1e-9;
/// Gauss-Newton steps over the held matches at most: with the matches fixed
/// the problem is nearly linear and converges in two or three.
const HELD_ITERATIONS: usize = 10;

/// One Gauss-Newton step of the matches `found` from `t`: the new transform
/// and the step's size. `None` when the system is singular or the step is
/// not finite.
fn gauss_newton_step(
    cur: &[Seg],
    cand: &[Seg],
    t: &Pose2,
    found: &[(usize, usize, f64)],
) -> Option<(Pose2, f64)> {
    let (h, g, _, _) = normal_equations(cur, cand, t, found);
    let step = h.try_inverse().map(|inv| inv * g)?;
    if !step.iter().all(|v| v.is_finite()) {
        return None;
    }
    let moved = Pose2::new(t.x() + step.x, t.y() + step.y, wrap_angle(t.heading() + step.z));
    Some((moved, step.norm()))
}

/// The Gauss-Newton system of the matches' endpoint-to-line distances, each
/// endpoint weighted by half its match's overlap (metres of wall), so that a
/// long wall counts more than a short one. Returns `(J^T W J, -J^T W r,
/// sum w, sum w r^2)`.
fn normal_equations(
    cur: &[Seg],
    cand: &[Seg],
    t: &Pose2,
    found: &[(usize, usize, f64)],
) -> (Matrix3<f64>, Vector3<f64>, f64, f64) {
    let mut h = Matrix3::zeros();
    let mut g = Vector3::zeros();
    let (mut sum_w, mut sum_wr2) = (0.0, 0.0);
    for &(i, j, o) in found {
        let k = &cand[j];
        for p in [cur[i].start, cur[i].end] {
            let rp = t.rotate(&p.coords);
            let world = rp + t.translation();
            let r = k.n.dot(&world) - k.d;
            let jac = Vector3::new(k.n.x, k.n.y, k.n.dot(&Vector2::new(-rp.y, rp.x)));
            let w = 0.5 * o;
            h += jac * jac.transpose() * w;
            g -= jac * (w * r);
            sum_w += w;
            sum_wr2 += w * r * r;
        }
    }
    (h, g, sum_w, sum_wr2)
}

/// The fraction of `observed` wall that `walls` contradict: sample points
/// every 0.2 m along each observed segment, and count those whose ray from
/// the segment's viewpoint crosses a wall more than `margin_m` before the
/// point (the sensor saw through where `walls` has a wall). Both sets are in
/// one frame. Loop closure uses it both ways on an alignment: a symmetric
/// corridor or a twin room lines up its matched walls, but the rest of what
/// one keyframe saw runs through the other's walls.
///
/// Only walls of at least 1 m count: short lines are clutter that moves
/// (chairs, people) or is seen from one side only.
///
/// Edge cases: no usable observed segment gives 0; degenerate segments are
/// skipped.
pub fn see_through_fraction(
    observed: &[(LineSegment, Point2<f64>)],
    walls: &[LineSegment],
    margin_m: f64,
) -> f64 {
    let walls: Vec<Seg> =
        walls.iter().filter_map(Seg::of).filter(|w| w.len >= SEE_THROUGH_MIN_WALL_M).collect();
    let (mut samples, mut through) = (0usize, 0usize);
    for (line, viewpoint) in observed {
        let Some(s) = Seg::of(line) else { continue };
        let n = ((s.len / 0.2).ceil() as usize).clamp(1, 50);
        for k in 0..n {
            let p = s.start + s.dir * (s.len * (k as f64 + 0.5) / n as f64);
            let ray = p - viewpoint;
            let range = ray.norm();
            if range.is_nan() || range <= margin_m {
                continue;
            }
            samples += 1;
            let limit = 1.0 - margin_m / range;
            let crosses = walls.iter().any(|w| {
                // Solve viewpoint + t ray = w.start + u (w.end - w.start).
                let e = w.end - w.start;
                let m = Matrix2::new(ray.x, -e.x, ray.y, -e.y);
                m.try_inverse().is_some_and(|inv| {
                    let tu = inv * (w.start - viewpoint);
                    tu.x > 0.0 && tu.x < limit && (0.0..=1.0).contains(&tu.y)
                })
            });
            through += usize::from(crosses);
        }
    }
    if samples == 0 { 0.0 } else { through as f64 / samples as f64 }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(a: (f64, f64), b: (f64, f64)) -> LineSegment {
        LineSegment::between(Point2::new(a.0, a.1), Point2::new(b.0, b.1))
    }

    /// An L-shaped room with a pillar.
    fn room() -> Vec<LineSegment> {
        vec![
            seg((0.0, 0.0), (6.0, 0.0)),
            seg((6.0, 0.0), (6.0, 3.0)),
            seg((6.0, 3.0), (3.0, 3.0)),
            seg((3.0, 3.0), (3.0, 5.0)),
            seg((3.0, 5.0), (0.0, 5.0)),
            seg((0.0, 5.0), (0.0, 0.0)),
            seg((1.0, 1.0), (1.5, 1.0)),
            seg((1.5, 1.0), (1.5, 1.6)),
        ]
    }

    #[test]
    fn recovers_a_large_transform() {
        let truth = Pose2::new(2.5, -1.5, 2.0);
        let seen: Vec<_> = room().iter().map(|l| l.transformed(&truth.inverse())).collect();
        let a = align_lines(&seen, &room(), None, &AlignmentConfig::standard()).unwrap();
        let e = a.candidate_from_current.between(&truth);
        assert!(e.x().hypot(e.y()) < 1e-6 && e.heading().abs() < 1e-6, "{e:?}");
        assert_eq!(a.matches, 8);
        assert!(a.weakest_direction_m > 5.0);
        assert!(a.rms_m < 1e-6);
        // The room has one fit; any other places at most a wall or two.
        assert!(a.runner_up_length_m < 0.6 * a.matched_length_m, "{a:?}");
    }

    /// A wall 8 cm thick: the candidate set saw its north face whole (from
    /// the north) and its south face in part (from the south), the current
    /// set its south face whole, between two cross walls. Facing either
    /// way, the current south face lays more wall over the north face and
    /// the fit lands on it; facing the same way, it can only match the
    /// south face. Lines are directed with their sensor on the left.
    #[test]
    fn the_two_faces_of_a_wall_match_only_the_same_way() {
        let candidate = vec![
            seg((0.0, 0.04), (6.0, 0.04)),
            seg((4.0, -0.04), (2.0, -0.04)),
            seg((1.0, -0.04), (1.0, -3.0)),
            seg((5.0, -3.0), (5.0, -0.04)),
        ];
        let seen_from_south = [
            seg((5.0, -0.04), (1.0, -0.04)),
            seg((1.0, -0.04), (1.0, -3.0)),
            seg((5.0, -3.0), (5.0, -0.04)),
        ];
        let truth = Pose2::new(0.4, -0.3, 0.1);
        let seen: Vec<_> =
            seen_from_south.iter().map(|l| l.transformed(&truth.inverse())).collect();
        let same = align_lines(&seen, &candidate, None, &AlignmentConfig::sided()).unwrap();
        let e = same.candidate_from_current.between(&truth);
        assert!(e.x().hypot(e.y()) < 1e-6 && e.heading().abs() < 1e-6, "{e:?}");
        assert!(same.rms_m < 1e-6, "{same:?}");
        let either = align_lines(&seen, &candidate, None, &AlignmentConfig::standard()).unwrap();
        let e = either.candidate_from_current.between(&truth);
        assert!(e.x().hypot(e.y()) > 0.03, "the far face pulls: {e:?}");
    }

    /// A corridor whose only cross wall meets no other line within
    /// `max_corner_distance_m`: no corner pair, so no hypothesis without a
    /// prior; the prior's own transform is scored and refined.
    #[test]
    fn the_prior_is_a_hypothesis_when_no_corner_pair_is() {
        let corridor = vec![
            seg((0.0, 0.0), (10.0, 0.0)),
            seg((0.0, 2.0), (10.0, 2.0)),
            seg((14.0, 0.5), (14.0, 1.5)),
        ];
        let truth = Pose2::new(0.3, 0.05, 0.02);
        let seen: Vec<_> = corridor.iter().map(|l| l.transformed(&truth.inverse())).collect();
        let config = AlignmentConfig::standard();
        assert!(align_lines(&seen, &corridor, None, &config).is_none());
        let near = Pose2::new(0.33, 0.03, 0.025);
        let prior =
            AlignmentPrior { candidate_from_current: near, radius_m: 1.0, max_rotation_rad: 0.1 };
        let a = align_lines(&seen, &corridor, Some(&prior), &config).unwrap();
        let e = a.candidate_from_current.between(&truth);
        assert!(e.x().hypot(e.y()) < 1e-6 && e.heading().abs() < 1e-6, "{e:?}");
        // Without the cross wall the along-corridor offset is unobservable.
        let walls = &corridor[..2];
        let seen: Vec<_> = walls.iter().map(|l| l.transformed(&truth.inverse())).collect();
        if let Some(a) = align_lines(&seen, walls, Some(&prior), &config) {
            assert!(a.weakest_direction_m < 0.1, "{a:?}");
        }
    }

    #[test]
    fn a_repeated_structure_has_a_close_runner_up() {
        // A row of identical 3 m cells: one period away fits almost as well.
        let mut row = Vec::new();
        for k in 0..6 {
            let x = 3.0 * k as f64;
            row.push(seg((x, 0.0), (x + 3.0, 0.0)));
            row.push(seg((x, 3.0), (x + 3.0, 3.0)));
            row.push(seg((x, 0.0), (x, 2.0)));
        }
        let seen: Vec<_> =
            row[3..12].iter().map(|l| l.transformed(&Pose2::new(-0.2, 0.0, 0.0))).collect();
        let a = align_lines(&seen, &row, None, &AlignmentConfig::standard()).unwrap();
        assert!(a.runner_up_length_m > 0.8 * a.matched_length_m, "{a:?}");
    }

    #[test]
    fn a_prior_excludes_hypotheses_outside_it() {
        let truth = Pose2::new(2.5, -1.5, 2.0);
        let seen: Vec<_> = room().iter().map(|l| l.transformed(&truth.inverse())).collect();
        let prior = AlignmentPrior {
            candidate_from_current: Pose2::new(-3.0, 4.0, 0.0),
            radius_m: 1.0,
            max_rotation_rad: 0.2,
        };
        assert!(align_lines(&seen, &room(), Some(&prior), &AlignmentConfig::standard()).is_none());
    }

    #[test]
    fn a_corridor_gives_no_alignment() {
        let corridor = vec![seg((0.0, 0.0), (10.0, 0.0)), seg((0.0, 2.0), (10.0, 2.0))];
        let seen: Vec<_> =
            corridor.iter().map(|l| l.transformed(&Pose2::new(1.0, 0.0, 0.0))).collect();
        assert!(align_lines(&seen, &corridor, None, &AlignmentConfig::standard()).is_none());
    }

    #[test]
    fn too_few_or_degenerate_lines_give_none() {
        let config = AlignmentConfig::standard();
        assert!(align_lines(&[], &room(), None, &config).is_none());
        assert!(align_lines(&room()[..1], &room(), None, &config).is_none());
        let bad = room()[0].with_extent(0.0, 0.0);
        assert_eq!(bad.length(), 0.0);
        assert!(align_lines(&[bad, bad], &room(), None, &config).is_none());
    }

    #[test]
    fn seeing_through_a_wall_is_counted() {
        let wall = seg((2.0, -1.0), (2.0, 1.0));
        let behind = seg((4.0, -1.0), (4.0, 1.0));
        let origin = Point2::new(0.0, 0.0);
        assert_eq!(see_through_fraction(&[(behind, origin)], &[wall], 0.15), 1.0);
        assert_eq!(see_through_fraction(&[(wall, origin)], &[wall], 0.15), 0.0);
        assert_eq!(see_through_fraction(&[(wall, origin)], &[behind], 0.15), 0.0);
        assert_eq!(see_through_fraction(&[], &[wall], 0.15), 0.0);
    }

    #[test]
    fn validation_names_the_field() {
        let mut c = AlignmentConfig::standard();
        c.match_distance_m = f64::NAN;
        let e = c.validate("loops.alignment").unwrap_err().to_string();
        assert!(e.contains("loops.alignment.match_distance_m"), "{e}");
    }
}
