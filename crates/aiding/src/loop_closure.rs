//! [`LoopClosing`]: the estimator ([`Aiding`]) with keyframes, loop closure
//! from lines alone and a pose graph, so that drift accumulated away from a
//! mapped area is undone when the vehicle comes back.
//!
//! Scan by scan, the estimator corrects the source's pose against the line
//! map. Every [`LoopClosureConfig::keyframe_distance_m`] of travel (or
//! [`LoopClosureConfig::keyframe_turn_rad`] of turn) the scan becomes a
//! keyframe: its lines are kept in its own frame, and a sequential edge with
//! the motion model's covariance joins it to the previous keyframe. A new
//! keyframe looks for loops:
//!
//! 1. **Candidates**: older keyframes at least
//!    [`LoopClosureConfig::min_loop_path_m`] of travel back, within the
//!    relative pose's uncertainty: the sequential edges' covariances summed
//!    along the chain between them, heading error times the travel for the
//!    position, [`LoopClosureConfig::search_sigmas`] standard deviations
//!    (bounded by [`LoopClosureConfig::max_search_radius_m`]). Where that
//!    uncertainty reaches beyond the bound, place recognition
//!    ([`LoopClosureConfig::place_recognition`]) adds the older keyframes
//!    beyond it, within the uncertainty, whose local line sets look alike
//!    ([`PlaceDescriptor`]).
//! 2. **Verification**: the lines of the last keyframes, in the current
//!    keyframe's frame, are aligned to the lines around the candidate
//!    ([`align_lines`]: RANSAC over line pairs, then least squares), and the
//!    alignment must pass a consistency test: enough wall matched, in two
//!    directions, with a small residual. The winner must also be the only
//!    place that fits: the current lines are aligned with the
//!    older keyframes, one stretch per place, within
//!    [`LoopClosureConfig::place_search_scale`] times the search radius,
//!    and another place matching almost as much wall refuses the loop (a
//!    look-alike place that the drifted estimate happens to lie near).
//! 3. **Optimization** ([`PoseGraph::optimize`]): loop edges carry a Cauchy
//!    kernel and are switched off when the optimum disagrees with them, so a
//!    false loop does not survive. The map is then rebuilt from the keyframes
//!    at their optimized poses (re-anchored) and the estimator carried over.
//!
//! The optimization runs after each accepted loop by default
//! ([`OptimizeSchedule::AfterLoop`]); with [`OptimizeSchedule::Manual`] the
//! caller schedules [`LoopClosing::optimize`] itself (for example on another
//! thread's budget).

use crate::{
    Aiding, AidingConfig, Alignment, AlignmentConfig, AlignmentPrior, EdgeKind, Fallback,
    ObservedLine, OptimizeReport, OptimizerConfig, PlaceDescriptor, PlaceRecognitionConfig,
    PoseGraph, SensorLine, StepReport, align_lines, see_through_fraction,
};

/// A sample closer than this to a crossing wall is not seeing through it
/// (the wall it lies on, seen again with noise), metres.
const SEE_THROUGH_MARGIN_M: f64 = 0.15;

/// Two placements of the current keyframe are the same place within this
/// distance, metres ...
const SAME_PLACE_M: f64 = 1.0;
/// ... and this rotation, radians (5°).
const SAME_PLACE_RAD: f64 = 0.0873;
/// The look-alike search aligns one stretch of keyframes per place: a
/// keyframe closer than this to one already searched, metres ...
const PLACE_SPACING_M: f64 = 1.5;
/// ... and turned by less than this, radians (45°), is skipped.
const PLACE_SPACING_RAD: f64 = 0.785;

use pcaline_geometry::{ConfigError, LineSegment, Matrix3, Point2, Pose2, Vector3, wrap_angle};
use pcaline_mapping::{LineMap, MapConfig};

/// When [`LoopClosing`] optimizes its graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum OptimizeSchedule {
    /// Right after a scan that added a loop edge.
    AfterLoop,
    /// Only when the caller calls [`LoopClosing::optimize`].
    Manual,
}

/// Configuration of [`LoopClosing`]. Errors name fields under
/// `loop_closure.`, as a configuration file writes them.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct LoopClosureConfig {
    /// A scan becomes a keyframe after this much travel since the last one,
    /// metres ...
    pub keyframe_distance_m: f64,
    /// ... or this much turn, radians.
    pub keyframe_turn_rad: f64,
    /// Keyframes on each side whose lines form the local line set of a
    /// keyframe (the current keyframe uses this many before it).
    pub submap_keyframes: usize,
    /// A candidate lies at least this much travel back, metres.
    pub min_loop_path_m: f64,
    /// Search radius around the predicted relative pose: this, metres ...
    pub search_radius_m: f64,
    /// ... plus this many standard deviations of the chain's position
    /// uncertainty (and the same for the rotation) ...
    pub search_sigmas: f64,
    /// ... at most this, metres.
    pub max_search_radius_m: f64,
    /// Rotation search: this, radians, plus `search_sigmas` standard
    /// deviations of the chain's heading uncertainty (at most pi).
    pub search_rotation_rad: f64,
    /// Candidates verified per keyframe, nearest first.
    pub max_candidates: usize,
    /// After an accepted loop, this many keyframes look for none.
    ///
    /// 8 by default (4 m at the default keyframe spacing; 5 before
    /// 2026-12-05). Loops found a few keyframes apart align nearly the same
    /// local lines, so they are not independent measurements, yet the graph
    /// counts each in full. Measured with `pcaline eval --real --drift-grid
    /// --sensitivity-seeds 96` at 3, 5, 6, 7, 8, 10 and 12: from 6 up,
    /// Intel's own poses come out no worse than the source on its relation
    /// metric (0.0689 m at 8, against the source's 0.0692 m; 0.0696 m at 5).
    /// At 8 no CSAIL sensitivity run of 96 keeps a loop 0.5 m off (3 at 5).
    /// CSAIL's own poses move more (0.094 m against 0.074 m, still under
    /// the 0.10 m target; `docs/accuracy.md`).
    pub loop_spacing_keyframes: usize,
    /// A verified loop is added once another, from a keyframe at most this
    /// many keyframes later, closes the same cycle (the two loops and the
    /// chain pieces between their keyframes and between their candidates
    /// compose to the identity; 0: no confirmation) ...
    pub confirm_keyframes: usize,
    /// ... but a loop whose prior does not vouch for the place
    /// ([`LoopRecord::weak_prior`]: found by place recognition, or where
    /// the relative pose's uncertainty reaches beyond
    /// `max_search_radius_m`) only by, or with, a loop from a keyframe
    /// whose local line set shares none of its keyframes: more than
    /// `submap_keyframes` and at most this many keyframes later (0: such
    /// loops confirm as the others do).
    ///
    /// 16 by default. Two loops from adjacent keyframes align local sets
    /// that share all keyframes but one with nearly the same candidate
    /// lines: they agree with each other whether the place is right or
    /// not, so their agreement says little where nothing else does. Over
    /// 96 sensitivity runs of MIT CSAIL's raw odometry (`pcaline eval
    /// --real --drift-grid --sensitivity-seeds 96`), with adjacent
    /// confirmations one run kept a loop 34 m and 62° off (two loops from
    /// keyframes one apart, 8 m search radius against a 54 m uncertainty,
    /// each with 60-66% of its wall matched by another alignment or place)
    /// and ended 30° off; with this rule none keeps a loop 0.5 m off, and
    /// the mean heading rms is 9.4° instead of 9.9°. The cost is on
    /// Intel's synthetic drift: fewer loops stand (92 against 110), and
    /// the relation metric is 0.061 m instead of 0.057 m
    /// (`docs/accuracy.md`). At 11 (6 keyframes of window after the
    /// shared ones) Intel's figure is 0.064 m.
    #[cfg_attr(feature = "serde", serde(default = "default_independent_confirm_keyframes"))]
    pub independent_confirm_keyframes: usize,
    /// ... within this distance, metres ...
    pub confirm_distance_m: f64,
    /// ... and this rotation, radians.
    pub confirm_rotation_rad: f64,
    /// Consistency test: matched wall length at least this, metres ...
    pub min_matched_length_m: f64,
    /// ... and at least this fraction of the current lines' length ...
    pub min_matched_fraction: f64,
    /// ... with at least this much wall constraining the weakest direction,
    /// metres ...
    pub min_weakest_direction_m: f64,
    /// ... and an rms endpoint residual of at most this, metres ...
    pub max_rms_m: f64,
    /// ... and no distinct alignment matching more than this fraction of
    /// the best one's length ([`Alignment::runner_up_length_m`]: repeated
    /// structure) ...
    pub max_runner_up: f64,
    /// ... and neither keyframe's local lines may see through the other's
    /// walls over more than this fraction of their length
    /// ([`see_through_fraction`](crate::see_through_fraction)) ...
    pub max_see_through: f64,
    /// ... and, when this is above 0, no other place may match more than
    /// `max_runner_up` of the loop's matched length
    /// ([`LoopRecord::other_place_length_m`]): the older keyframes whose
    /// graph pose lies within this many times the loop's search radius of
    /// the current one's, one per place, each aligned with the current
    /// lines anywhere in that distance and at any rotation.
    /// It catches what the prior-bounded runner-up cannot: a place
    /// repeated further along the building, where drift has put the
    /// estimate near the copy and the true place outside the search.
    ///
    /// 1 by default: the other places are looked for within the loop's own
    /// search radius, the uncertainty in which it was itself looked for.
    /// Over 96 sensitivity runs of MIT CSAIL's raw odometry (`pcaline eval
    /// --real --drift-grid --sensitivity-seeds 96`), a loop 0.5 m or more
    /// off stands in 3 runs instead of 29, and the rigid heading rms with
    /// loops averages 9.7° instead of 10.9°; the logs' own poses and the
    /// drift grid move as little as without it, and `pcaline map` takes 2-3x
    /// as long. In the shipped large building (identical 3 m cells, a path
    /// that never comes back to a place) it refuses every loop found, each
    /// a twin cell 3-4 m off, before any reaches the graph. Larger
    /// scales refuse right loops too (at 4 CSAIL keeps 3 loops, and with a
    /// heading bias on Intel the first right loops into the start room are
    /// refused because its twin is down the corridor); 0 turns the search
    /// off (`docs/accuracy.md`).
    pub place_search_scale: f64,
    /// Place recognition ([`PlaceRecognitionConfig`]): where the relative
    /// pose's uncertainty reaches beyond `max_search_radius_m`, older
    /// keyframes beyond it but within the uncertainty whose local line sets
    /// look alike ([`PlaceDescriptor`]) are verified too, aligned anywhere
    /// within the uncertainty; and a loop is refused when two verified
    /// candidates place the current keyframe in different places
    /// ([`LoopOutcome::LookAlikePlace`]). On by default: on MIT CSAIL's raw
    /// odometry the heading over the whole log is about 2° better on
    /// average and the position two to three times (`docs/accuracy.md`);
    /// `None` turns it off.
    #[cfg_attr(feature = "serde", serde(default))]
    pub place_recognition: Option<PlaceRecognitionConfig>,
    /// The sequential edges' covariance: the estimator's motion model over
    /// the motion between the keyframes, at the noise scale the estimator
    /// adapted to the source ([`StepReport::motion_noise_scale`]), times this.
    pub sequential_variance_scale: f64,
    /// Floors of a loop edge's standard deviations: position, metres ...
    pub loop_floor_m: f64,
    /// ... and heading, radians.
    pub loop_floor_rad: f64,
    /// The line-set alignment.
    pub alignment: AlignmentConfig,
    /// The graph optimizer.
    pub optimizer: OptimizerConfig,
    /// When to optimize.
    pub schedule: OptimizeSchedule,
}

/// [`LoopClosureConfig::independent_confirm_keyframes`] of
/// [`LoopClosureConfig::standard`], for configuration files written before
/// the field.
#[cfg(feature = "serde")]
fn default_independent_confirm_keyframes() -> usize {
    LoopClosureConfig::standard().independent_confirm_keyframes
}

impl LoopClosureConfig {
    /// Defaults for indoor logs: a keyframe each 0.5 m or 15°, local sets of
    /// 5 keyframes, loops at least 8 m of travel back within 1 m and 10° plus
    /// 3 sigmas of the chain's uncertainty (at most 8 m; beyond, by place
    /// recognition, [`PlaceRecognitionConfig::standard`]), a consistency test of 3 m of
    /// wall, 40% of the current lines, 1 m in the weakest direction and 4 cm
    /// rms, no other place within the search radius that fits almost as
    /// well; no loop search for 8 keyframes after a loop; loop edges no
    /// tighter than 5 cm and 0.5°.
    pub fn standard() -> Self {
        LoopClosureConfig {
            keyframe_distance_m: 0.5,
            keyframe_turn_rad: 15f64.to_radians(),
            submap_keyframes: 5,
            min_loop_path_m: 8.0,
            search_radius_m: 1.0,
            search_sigmas: 3.0,
            max_search_radius_m: 8.0,
            search_rotation_rad: 10f64.to_radians(),
            max_candidates: 4,
            loop_spacing_keyframes: 8,
            confirm_keyframes: 6,
            independent_confirm_keyframes: 16,
            confirm_distance_m: 0.3,
            confirm_rotation_rad: 3f64.to_radians(),
            min_matched_length_m: 3.0,
            min_matched_fraction: 0.4,
            min_weakest_direction_m: 1.0,
            max_rms_m: 0.04,
            max_runner_up: 0.7,
            max_see_through: 0.5,
            place_search_scale: 1.0,
            place_recognition: Some(PlaceRecognitionConfig::standard()),
            sequential_variance_scale: 1.0,
            loop_floor_m: 0.05,
            loop_floor_rad: 0.5f64.to_radians(),
            alignment: AlignmentConfig::sided(),
            optimizer: OptimizerConfig::standard(),
            schedule: OptimizeSchedule::AfterLoop,
        }
    }

    /// Checks every value; errors name `loop_closure.<field>`.
    pub fn validate(&self) -> Result<(), ConfigError> {
        const P: &str = "loop_closure";
        ConfigError::positive_fields(
            P,
            &[
                ("keyframe_distance_m", self.keyframe_distance_m),
                ("keyframe_turn_rad", self.keyframe_turn_rad),
                ("min_loop_path_m", self.min_loop_path_m),
                ("search_radius_m", self.search_radius_m),
                ("max_search_radius_m", self.max_search_radius_m),
                ("search_rotation_rad", self.search_rotation_rad),
                ("min_matched_length_m", self.min_matched_length_m),
                ("min_weakest_direction_m", self.min_weakest_direction_m),
                ("max_rms_m", self.max_rms_m),
                ("loop_floor_m", self.loop_floor_m),
                ("loop_floor_rad", self.loop_floor_rad),
                ("sequential_variance_scale", self.sequential_variance_scale),
                ("confirm_distance_m", self.confirm_distance_m),
                ("confirm_rotation_rad", self.confirm_rotation_rad),
            ],
        )?;
        ConfigError::check_field(
            self.search_sigmas >= 0.0 && self.search_sigmas.is_finite(),
            P,
            "search_sigmas",
            self.search_sigmas,
            "must be finite and >= 0",
        )?;
        ConfigError::check_field(
            self.place_search_scale >= 0.0 && self.place_search_scale.is_finite(),
            P,
            "place_search_scale",
            self.place_search_scale,
            "must be finite and >= 0",
        )?;
        ConfigError::check_field(
            (0.0..=1.0).contains(&self.max_runner_up),
            P,
            "max_runner_up",
            self.max_runner_up,
            "must be in [0, 1]",
        )?;
        ConfigError::check_field(
            (0.0..=1.0).contains(&self.max_see_through),
            P,
            "max_see_through",
            self.max_see_through,
            "must be in [0, 1]",
        )?;
        ConfigError::check_field(
            self.min_matched_fraction > 0.0 && self.min_matched_fraction <= 1.0,
            P,
            "min_matched_fraction",
            self.min_matched_fraction,
            "must be in (0, 1]",
        )?;
        for (name, v, max) in [
            ("submap_keyframes", self.submap_keyframes, 100),
            ("max_candidates", self.max_candidates, 100),
            ("loop_spacing_keyframes", self.loop_spacing_keyframes, 10_000),
            ("confirm_keyframes", self.confirm_keyframes, 100),
            ("independent_confirm_keyframes", self.independent_confirm_keyframes, 100),
        ] {
            ConfigError::check_field(v <= max, P, name, v as f64, "is too large")?;
        }
        ConfigError::check_field(
            self.max_candidates >= 1,
            P,
            "max_candidates",
            0.0,
            "must be >= 1",
        )?;
        ConfigError::check_field(
            self.independent_confirm_keyframes == 0
                || self.independent_confirm_keyframes > self.submap_keyframes,
            P,
            "independent_confirm_keyframes",
            self.independent_confirm_keyframes as f64,
            "must be 0 or more than submap_keyframes (no loop could confirm a weak-prior one)",
        )?;
        if let Some(p) = &self.place_recognition {
            p.validate("loop_closure.place_recognition")?;
        }
        self.alignment.validate("loop_closure.alignment")?;
        self.optimizer.validate("loop_closure.optimizer")
    }
}

impl Default for LoopClosureConfig {
    fn default() -> Self {
        Self::standard()
    }
}

/// A keyframe: a scan whose lines the graph keeps, in its own frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Keyframe {
    /// Index of the scan (counted from 0 by [`LoopClosing`]).
    pub scan: usize,
    /// The scan's stamp, if it had one.
    pub stamp_s: Option<f64>,
    /// Travel from the first keyframe along the estimated path, metres.
    pub path_m: f64,
    /// The sequential edges' heading variances summed from the first
    /// keyframe, rad².
    pub chain_heading_var: f64,
    /// The same for the position (the mean of x and y), m².
    pub chain_position_var: f64,
    /// The scan's lines, sensor frame.
    pub lines: Vec<SensorLine>,
    /// The descriptor of its local line set (this keyframe's lines and the
    /// `submap_keyframes` before it, in its frame), with place recognition
    /// on and enough lines.
    pub descriptor: Option<PlaceDescriptor>,
}

/// How a loop candidate was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum LoopSearch {
    /// Within the local search radius around the predicted relative pose.
    Local,
    /// Beyond it, within the relative pose's uncertainty, by the likeness
    /// of the two local line sets ([`PlaceRecognitionConfig`]).
    PlaceRecognition,
}

/// A keyframe to verify as a loop, and the bounds of its alignment.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    keyframe: usize,
    /// Place recognition's, or the uncertainty reaches beyond the local
    /// search ([`LoopRecord::weak_prior`]).
    weak_prior: bool,
    radius_m: f64,
    rotation_rad: f64,
    search: LoopSearch,
}

/// Why a verified candidate was not used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum LoopOutcome {
    /// Accepted: the graph has an edge for it.
    Accepted,
    /// Accepted, later switched off by the optimizer's chi-square test.
    SwitchedOff,
    /// Too little wall matched.
    TooLittleMatched,
    /// The matches leave a direction unconstrained (a corridor).
    Unconstrained,
    /// The matched lines lie too far apart after the alignment.
    LargeResidual,
    /// One keyframe's lines see through the other's walls.
    SeesThroughWalls,
    /// Another alignment, at least 0.5 m or 5° away, matches almost as
    /// much wall: the structure repeats.
    Ambiguous,
    /// Verified, but another place within
    /// [`LoopClosureConfig::place_search_scale`] times the search radius
    /// fits the current lines almost as well, or, with place recognition,
    /// another verified candidate places the current keyframe elsewhere:
    /// the place repeats.
    LookAlikePlace,
    /// Verified, but no second loop from the next keyframes closed the
    /// same cycle ([`LoopClosureConfig::confirm_keyframes`]; with a weak
    /// prior, from independent lines:
    /// [`LoopClosureConfig::independent_confirm_keyframes`]).
    Unconfirmed,
}

/// A loop candidate that [`align_lines`] aligned, and what came of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopRecord {
    /// The current keyframe.
    pub keyframe: usize,
    /// The older keyframe it was aligned with.
    pub candidate: usize,
    /// The graph edge, when accepted.
    pub edge: Option<usize>,
    /// `candidate_from_current` the alignment found.
    pub candidate_from_current: Pose2,
    /// Matched wall length, metres.
    pub matched_length_m: f64,
    /// Wall length in the weakest direction, metres.
    pub weakest_direction_m: f64,
    /// Matched length of the best distinct alignment, metres
    /// ([`Alignment::runner_up_length_m`]).
    pub runner_up_length_m: f64,
    /// Rms endpoint residual, metres.
    pub rms_m: f64,
    /// The larger see-through fraction of the two directions.
    pub see_through: f64,
    /// Matched length of the best alignment with another place within
    /// [`LoopClosureConfig::place_search_scale`] times the search radius,
    /// metres (0 when no other place fits, or the loop was refused before
    /// the search).
    pub other_place_length_m: f64,
    /// The alignment's information, unit endpoint noise
    /// ([`Alignment::information`]).
    pub information: Matrix3<f64>,
    /// How the candidate was found.
    pub search: LoopSearch,
    /// The prior did not vouch for the place: the candidate came from place
    /// recognition, or the relative pose's uncertainty (its search radius
    /// before the cap) reached beyond
    /// [`LoopClosureConfig::max_search_radius_m`]. Such a loop is
    /// confirmed only with a loop from independent local lines
    /// ([`LoopClosureConfig::independent_confirm_keyframes`]).
    pub weak_prior: bool,
    /// The loop of the pair that confirmed this one (an index in
    /// [`LoopClosing::loops`]), once confirmed; `None` without confirmation
    /// ([`LoopClosureConfig::confirm_keyframes`] 0) or before it.
    pub confirmed_with: Option<usize>,
    /// What came of it.
    pub outcome: LoopOutcome,
}

/// What one scan did in [`LoopClosing`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct LoopStep {
    /// The corrected `world_from_sensor` (after the optimization, if one ran).
    pub pose: Pose2,
    /// The estimator's report.
    pub report: StepReport,
    /// The keyframe the scan became, if it did.
    pub keyframe: Option<usize>,
    /// Loop edges the scan added.
    pub loops_added: usize,
    /// The optimization the scan triggered ([`OptimizeSchedule::AfterLoop`]).
    pub optimized: Option<OptimizeReport>,
}

/// The estimator with keyframes, loop closure and a pose graph; see the
/// module documentation.
///
/// ```
/// use pcaline_aiding::{AidingConfig, LoopClosing, LoopClosureConfig, SensorLine};
/// use pcaline_geometry::Pose2;
/// use pcaline_mapping::MapConfig;
///
/// let mut slam =
///     LoopClosing::new(AidingConfig::estimator(), MapConfig::default(), LoopClosureConfig::standard())
///         .unwrap();
/// let lines: Vec<SensorLine> = Vec::new();
/// let step = slam.step_at(0.0, &Pose2::identity(), &lines);
/// assert_eq!(step.keyframe, Some(0));
/// assert_eq!(slam.graph().nodes.len(), 1);
/// ```
#[derive(Debug, Clone)]
pub struct LoopClosing {
    aiding: Aiding,
    config: LoopClosureConfig,
    graph: PoseGraph,
    keyframes: Vec<Keyframe>,
    loops: Vec<LoopRecord>,
    /// Each scan's keyframe and its pose in that keyframe's frame (`None`
    /// for a scan before the first keyframe).
    scans: Vec<Option<(usize, Pose2)>>,
    /// The keyframe after which loop search resumes.
    quiet_until: usize,
    optimizations: usize,
    last_optimization: Option<OptimizeReport>,
    /// Verified loops of the last keyframes, waiting for confirmation.
    pending: Vec<PendingLoop>,
}

impl LoopClosing {
    /// An empty graph and map.
    pub fn new(
        aiding: AidingConfig,
        map: MapConfig,
        config: LoopClosureConfig,
    ) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(LoopClosing {
            aiding: Aiding::new(aiding, map)?,
            config,
            graph: PoseGraph::new(),
            keyframes: Vec::new(),
            loops: Vec::new(),
            scans: Vec::new(),
            quiet_until: 0,
            optimizations: 0,
            last_optimization: None,
            pending: Vec::new(),
        })
    }

    /// One scan with the source's pose, stamped ([`Aiding::step_at`]).
    pub fn step_at(
        &mut self,
        stamp_s: f64,
        source: &Pose2,
        lines: &[impl ObservedLine],
    ) -> LoopStep {
        let (pose, report) = self.aiding.step_at(stamp_s, source, lines);
        self.after_step(pose, report, Some(stamp_s), lines)
    }

    /// The next scan's registration to the previous one, for the estimator
    /// ([`Aiding::set_registration`]).
    pub fn set_registration(&mut self, registration: Option<crate::Registration>) {
        self.aiding.set_registration(registration);
    }

    /// One scan with the source's pose, unstamped ([`Aiding::step`]).
    pub fn step(&mut self, source: &Pose2, lines: &[impl ObservedLine]) -> LoopStep {
        let (pose, report) = self.aiding.step(source, lines);
        self.after_step(pose, report, None, lines)
    }

    /// One scan without a source ([`Aiding::step_without_source`]).
    pub fn step_without_source(
        &mut self,
        stamp_s: Option<f64>,
        lines: &[impl ObservedLine],
    ) -> LoopStep {
        let (pose, report) = self.aiding.step_without_source(stamp_s, lines);
        self.after_step(pose, report, stamp_s, lines)
    }

    /// The estimator (its map, pose, covariance and calibration).
    pub fn aiding(&self) -> &Aiding {
        &self.aiding
    }

    /// The line map (rebuilt from the keyframes after each optimization).
    pub fn map(&self) -> &LineMap {
        self.aiding.map()
    }

    /// The latest corrected pose.
    pub fn pose(&self) -> Option<Pose2> {
        self.aiding.pose()
    }

    /// The pose graph: one node per keyframe.
    pub fn graph(&self) -> &PoseGraph {
        &self.graph
    }

    /// The keyframes, in the graph's node order.
    pub fn keyframes(&self) -> &[Keyframe] {
        &self.keyframes
    }

    /// Every aligned loop candidate, accepted or not.
    pub fn loops(&self) -> &[LoopRecord] {
        &self.loops
    }

    /// Optimizations run so far.
    pub fn optimizations(&self) -> usize {
        self.optimizations
    }

    /// The report of the last optimization, if one ran.
    pub fn last_optimization(&self) -> Option<&OptimizeReport> {
        self.last_optimization.as_ref()
    }

    /// The configuration.
    pub fn config(&self) -> &LoopClosureConfig {
        &self.config
    }

    /// Every scan's `world_from_sensor` as the graph now places it. After a
    /// final [`LoopClosing::optimize`], this is the optimized trajectory.
    ///
    /// A scan between keyframes `k` and `k + 1` is placed from both: its
    /// keyframe's node composed with the scan's pose relative to it, and the
    /// next node composed back along the sequential edge between them; the
    /// two are blended by the scan's place between the keyframes (its index),
    /// so that the optimization's correction changes smoothly along the path
    /// instead of jumping at each keyframe. When the optimized nodes agree
    /// with the edge, both placements are the same. A scan after the last
    /// keyframe, or whose keyframe has no sequential edge to the next (the
    /// source jumped), is placed from its keyframe alone. A scan before the
    /// first keyframe (its pose was not finite) has none.
    pub fn trajectory(&self) -> Vec<Option<Pose2>> {
        let nodes = &self.graph.nodes;
        // The measured `k_from_next` of each keyframe's sequential edge.
        let mut to_next: Vec<Option<Pose2>> = vec![None; nodes.len()];
        for e in &self.graph.edges {
            if e.kind == EdgeKind::Sequential && e.to == e.from + 1 {
                to_next[e.from] = Some(e.from_from_to);
            }
        }
        self.scans
            .iter()
            .enumerate()
            .map(|(scan, s)| {
                let (k, rel) = (*s)?;
                let from_keyframe = nodes.get(k)?.compose(&rel);
                let next = to_next[k].zip(nodes.get(k + 1)).zip(self.keyframes.get(k + 1));
                let Some(((k_from_next, next_node), next_keyframe)) = next else {
                    return Some(from_keyframe);
                };
                let first = self.keyframes[k].scan;
                let w = (scan - first) as f64 / (next_keyframe.scan - first).max(1) as f64;
                let from_next = next_node.compose(&k_from_next.inverse().compose(&rel));
                Some(from_keyframe.lerp(&from_next, w))
            })
            .collect()
    }

    fn after_step(
        &mut self,
        pose: Pose2,
        report: StepReport,
        stamp_s: Option<f64>,
        lines: &[impl ObservedLine],
    ) -> LoopStep {
        let scan = self.scans.len();
        let mut step = LoopStep { pose, report, keyframe: None, loops_added: 0, optimized: None };
        let last = self.graph.nodes.last().copied();
        let is_keyframe = match last {
            None => true,
            Some(k) => {
                let rel = k.between(&pose);
                rel.x().hypot(rel.y()) >= self.config.keyframe_distance_m
                    || wrap_angle(rel.heading()).abs() >= self.config.keyframe_turn_rad
            }
        };
        // A scan the estimator skipped (its stamp went backwards, its source
        // was not finite) has a guessed pose and put nothing in the map: it
        // is no keyframe, and no loop or optimization starts from it.
        let skipped = matches!(
            step.report.fallback,
            Some(Fallback::StampBackwards | Fallback::NonFiniteSource)
        );
        if !is_keyframe || skipped || !pose.is_finite() {
            let k = self.graph.nodes.len().saturating_sub(1);
            let rel = last.map(|n| n.between(&pose)).filter(Pose2::is_finite);
            self.scans.push(last.map(|_| (k, rel.unwrap_or_default())));
            return step;
        }
        let node = self.graph.add_node(pose);
        let (path_m, chain_heading_var, chain_position_var) = match (last, self.keyframes.last()) {
            (Some(k), Some(prev)) => {
                let rel = k.between(&pose);
                // The motion model at the scale the estimator has learnt
                // for this source (`NoiseAdaptation`, whose own floor is the
                // only one): a good source's chain is tight, and so is the
                // loop search around it, and a loop the chain contradicts is
                // switched off instead of bending it. (A second floor, a
                // quarter of the model, let Intel's loops move its good
                // poses 0.18 m; docs/accuracy.md.)
                let cov = self.aiding.config().estimator.motion.covariance(&rel)
                    * (step.report.motion_noise_scale * self.config.sequential_variance_scale);
                self.graph.add_edge(node - 1, node, rel, cov, EdgeKind::Sequential);
                (
                    prev.path_m + rel.x().hypot(rel.y()),
                    prev.chain_heading_var + cov[(2, 2)],
                    prev.chain_position_var + 0.5 * (cov[(0, 0)] + cov[(1, 1)]),
                )
            }
            _ => (0.0, 0.0, 0.0),
        };
        self.keyframes.push(Keyframe {
            scan,
            stamp_s,
            path_m,
            chain_heading_var,
            chain_position_var,
            lines: lines
                .iter()
                .map(|l| SensorLine { line: *l.line(), moments: *l.moments() })
                .collect(),
            descriptor: None,
        });
        if let Some(p) = self.config.place_recognition {
            let first = node.saturating_sub(self.config.submap_keyframes);
            let local: Vec<LineSegment> =
                self.local_lines(node, first..=node).into_iter().map(|(l, _)| l).collect();
            self.keyframes[node].descriptor = PlaceDescriptor::of(&local, p.min_line_m);
        }
        self.scans.push(Some((node, Pose2::identity())));
        step.keyframe = Some(node);
        if node >= self.quiet_until {
            step.loops_added = self.close_loops(node);
        }
        if step.loops_added > 0 {
            self.quiet_until = node + 1 + self.config.loop_spacing_keyframes;
            if self.config.schedule == OptimizeSchedule::AfterLoop {
                let report = self.optimize();
                step.pose = self.aiding.pose().unwrap_or(step.pose);
                step.optimized = Some(report);
            }
        }
        step
    }

    /// The lines of keyframes `range` in the frame of keyframe `frame`, each
    /// with the position it was seen from.
    fn local_lines(
        &self,
        frame: usize,
        range: std::ops::RangeInclusive<usize>,
    ) -> Vec<(LineSegment, Point2<f64>)> {
        let origin = self.graph.nodes[frame];
        let mut out = Vec::new();
        for k in range {
            let t = origin.between(&self.graph.nodes[k]);
            let viewpoint = Point2::new(t.x(), t.y());
            out.extend(self.keyframes[k].lines.iter().map(|l| (l.line.transformed(&t), viewpoint)));
        }
        out
    }

    /// Looks for loops from keyframe `current`; returns the edges added.
    fn close_loops(&mut self, current: usize) -> usize {
        let chosen = self.loop_candidates(current);
        if chosen.is_empty() {
            return 0;
        }
        let Some(verified) = self.verify_candidates(current, chosen) else { return 0 };
        let other = self.other_place_length(current, &verified);
        if other > self.config.max_runner_up * verified.alignment.matched_length_m {
            let mut r = verified.record(current, LoopOutcome::LookAlikePlace);
            r.other_place_length_m = other;
            self.loops.push(r);
            return 0;
        }
        self.confirm_loop(current, &verified, other)
    }

    /// Step 1 of loop closing: keyframes at least
    /// [`LoopClosureConfig::min_loop_path_m`] of travel back whose graph
    /// pose lies within the search radius (the relative pose's uncertainty
    /// along the chain, at most `max_search_radius_m`), nearest first, one
    /// per stretch of `submap_keyframes`, at most `max_candidates`; then,
    /// with place recognition, the most similar of those beyond the radius
    /// but within the uncertainty ([`LoopClosing::place_candidates`]).
    fn loop_candidates(&self, current: usize) -> Vec<Candidate> {
        let c = self.config;
        let here = self.graph.nodes[current];
        let path_here = self.keyframes[current].path_m;
        let kf = &self.keyframes[current];
        // (distance, keyframe, uncapped radius, uncapped rotation)
        let reachable: Vec<(f64, usize, f64, f64)> = (0..current)
            .filter_map(|j| {
                let old = &self.keyframes[j];
                let travel = path_here - old.path_m;
                if travel < c.min_loop_path_m {
                    return None;
                }
                // The relative pose's uncertainty along the chain: the
                // edges' variances, and the heading error's lever arm.
                let var_heading = (kf.chain_heading_var - old.chain_heading_var).max(0.0);
                let var_position = (kf.chain_position_var - old.chain_position_var).max(0.0)
                    + var_heading * travel * travel / 3.0;
                let radius = c.search_radius_m + c.search_sigmas * var_position.sqrt();
                let rotation = c.search_rotation_rad + c.search_sigmas * var_heading.sqrt();
                let n = self.graph.nodes[j];
                let distance = (n.x() - here.x()).hypot(n.y() - here.y());
                (distance <= radius).then_some((distance, j, radius, rotation))
            })
            .collect();
        let mut local: Vec<(f64, usize, f64, f64)> = reachable
            .iter()
            .filter(|(d, _, r, _)| *d <= r.min(c.max_search_radius_m))
            .copied()
            .collect();
        local.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut chosen: Vec<Candidate> = Vec::new();
        for (_, j, radius, rotation) in local {
            if chosen.len() >= c.max_candidates {
                break;
            }
            if chosen.iter().all(|k| k.keyframe.abs_diff(j) > c.submap_keyframes) {
                chosen.push(Candidate {
                    keyframe: j,
                    weak_prior: radius > c.max_search_radius_m,
                    radius_m: radius.min(c.max_search_radius_m),
                    rotation_rad: rotation.min(std::f64::consts::PI),
                    search: LoopSearch::Local,
                });
            }
        }
        if let Some(p) = c.place_recognition {
            let far = reachable.into_iter().filter(|(d, _, _, _)| *d > c.max_search_radius_m);
            self.place_candidates(current, far, &p, &mut chosen);
        }
        chosen
    }

    /// Place recognition's candidates, added to `chosen`: of the keyframes
    /// `far` (beyond the local search, within the relative pose's
    /// uncertainty: `(distance, keyframe, radius, rotation)`), those whose
    /// descriptor is at least `min_similarity` like the current one's, the
    /// most similar first, one per stretch, at most `max_candidates`. Each
    /// is aligned within its whole uncertainty.
    fn place_candidates(
        &self,
        current: usize,
        far: impl Iterator<Item = (f64, usize, f64, f64)>,
        p: &PlaceRecognitionConfig,
        chosen: &mut Vec<Candidate>,
    ) {
        let Some(here) = &self.keyframes[current].descriptor else { return };
        let mut similar: Vec<(f64, usize, f64, f64)> = far
            .filter_map(|(_, j, radius, rotation)| {
                let s = here.similarity(self.keyframes[j].descriptor.as_ref()?);
                (s >= p.min_similarity).then_some((s, j, radius, rotation))
            })
            .collect();
        similar.sort_by(|a, b| b.0.total_cmp(&a.0));
        let n = self.config.submap_keyframes;
        let mut added = 0;
        for (_, j, radius, rotation) in similar {
            if added >= p.max_candidates {
                break;
            }
            if chosen.iter().all(|k| k.keyframe.abs_diff(j) > n) {
                chosen.push(Candidate {
                    keyframe: j,
                    weak_prior: true,
                    radius_m: radius,
                    rotation_rad: rotation.min(std::f64::consts::PI),
                    search: LoopSearch::PlaceRecognition,
                });
                added += 1;
            }
        }
    }

    /// Step 2: each candidate's local lines aligned with the current
    /// keyframe's (within the search prior) and tested (matched length,
    /// constrained directions, residual, ambiguity, walls seen through);
    /// the refused ones recorded. Returns the accepted alignment with the
    /// longest matched length. With place recognition, when a candidate it
    /// found is accepted and another accepted one places the current
    /// keyframe elsewhere (beyond [`SAME_PLACE_M`] or [`SAME_PLACE_RAD`]),
    /// none is: the longest is recorded as [`LoopOutcome::LookAlikePlace`].
    fn verify_candidates(
        &mut self,
        current: usize,
        chosen: Vec<Candidate>,
    ) -> Option<VerifiedLoop> {
        let c = self.config;
        let here = self.graph.nodes[current];
        let first = current.saturating_sub(c.submap_keyframes);
        let current_seen = self.local_lines(current, first..=current);
        let current_lines: Vec<LineSegment> = facing_left(&current_seen);
        let mut accepted: Vec<VerifiedLoop> = Vec::new();
        for candidate in chosen {
            let j = candidate.keyframe;
            let candidate_seen = self.local_lines(j, self.candidate_stretch(j, first));
            let candidate_lines: Vec<LineSegment> = facing_left(&candidate_seen);
            let prior = AlignmentPrior {
                candidate_from_current: self.graph.nodes[j].between(&here),
                radius_m: candidate.radius_m,
                max_rotation_rad: candidate.rotation_rad,
            };
            let Some(a) = align_lines(&current_lines, &candidate_lines, Some(&prior), &c.alignment)
            else {
                continue;
            };
            let see_through = {
                let t = a.candidate_from_current;
                let in_candidate: Vec<(LineSegment, Point2<f64>)> = current_seen
                    .iter()
                    .map(|(l, v)| (l.transformed(&t), t.transform_point(v)))
                    .collect();
                let t_inv = t.inverse();
                let in_current: Vec<(LineSegment, Point2<f64>)> = candidate_seen
                    .iter()
                    .map(|(l, v)| (l.transformed(&t_inv), t_inv.transform_point(v)))
                    .collect();
                see_through_fraction(&in_candidate, &candidate_lines, SEE_THROUGH_MARGIN_M)
                    .max(see_through_fraction(&in_current, &current_lines, SEE_THROUGH_MARGIN_M))
            };
            let outcome = if a.matched_length_m < c.min_matched_length_m
                || a.matched_length_m < c.min_matched_fraction * a.current_length_m
            {
                LoopOutcome::TooLittleMatched
            } else if a.weakest_direction_m < c.min_weakest_direction_m {
                LoopOutcome::Unconstrained
            } else if a.rms_m > c.max_rms_m {
                LoopOutcome::LargeResidual
            } else if a.runner_up_length_m > c.max_runner_up * a.matched_length_m {
                LoopOutcome::Ambiguous
            } else if see_through > c.max_see_through {
                LoopOutcome::SeesThroughWalls
            } else {
                LoopOutcome::Accepted
            };
            if outcome != LoopOutcome::Accepted {
                let mut r = record(current, j, &a, see_through, outcome);
                r.search = candidate.search;
                r.weak_prior = candidate.weak_prior;
                self.loops.push(r);
                continue;
            }
            accepted.push(VerifiedLoop {
                candidate: j,
                alignment: a,
                see_through,
                radius_m: candidate.radius_m,
                current_lines: current_lines.clone(),
                search: candidate.search,
                weak_prior: candidate.weak_prior,
            });
        }
        let best = accepted
            .iter()
            .enumerate()
            .max_by(|(i, a), (k, b)| {
                // The longest; the first of equals.
                a.alignment.matched_length_m.total_cmp(&b.alignment.matched_length_m).then(k.cmp(i))
            })
            .map(|(i, _)| i)?;
        let best = accepted.swap_remove(best);
        let recognised = best.search == LoopSearch::PlaceRecognition
            || accepted.iter().any(|v| v.search == LoopSearch::PlaceRecognition);
        if recognised {
            let placed = |v: &VerifiedLoop| {
                self.graph.nodes[v.candidate].compose(&v.alignment.candidate_from_current)
            };
            let other_place_m = accepted
                .iter()
                .filter(|v| elsewhere(&placed(&best), &placed(v)))
                .map(|v| v.alignment.matched_length_m)
                .fold(0.0f64, f64::max);
            if other_place_m > 0.0 {
                let mut r = best.record(current, LoopOutcome::LookAlikePlace);
                r.other_place_length_m = other_place_m;
                self.loops.push(r);
                return None;
            }
        }
        Some(best)
    }

    /// The keyframes whose lines form the local set around candidate `j`:
    /// `submap_keyframes` on each side, none from `first` on (the current
    /// keyframe's own local set).
    fn candidate_stretch(&self, j: usize, first: usize) -> std::ops::RangeInclusive<usize> {
        let n = self.config.submap_keyframes;
        j.saturating_sub(n)..=(j + n).min(first.saturating_sub(1)).max(j)
    }

    /// Step 2b: the longest wall matched when the current keyframe's local
    /// lines are aligned with the local lines around older keyframes (one
    /// per place: [`PLACE_SPACING_M`], [`PLACE_SPACING_RAD`]; at least
    /// `min_loop_path_m` of travel back; graph pose within
    /// `place_search_scale` times the loop's search radius, the alignment
    /// anywhere in that distance, at any rotation) that place the current
    /// keyframe elsewhere than the loop does (beyond 1 m or 5°). Alignments
    /// that fail the residual or weakest-direction test do not count.
    fn other_place_length(&self, current: usize, verified: &VerifiedLoop) -> f64 {
        let c = self.config;
        let search_m = c.place_search_scale * verified.radius_m;
        if search_m <= 0.0 {
            return 0.0;
        }
        let nodes = &self.graph.nodes;
        let here = nodes[current];
        let placed = nodes[verified.candidate].compose(&verified.alignment.candidate_from_current);
        let first = current.saturating_sub(c.submap_keyframes);
        let path_here = self.keyframes[current].path_m;
        // One stretch per place: a keyframe close to one searched shortly
        // before it sees the same walls. Only keyframes of the same stretch
        // of travel are compared: across passes the graph may have drifted,
        // and one graph position may hold two places.
        let mut searched: Vec<(usize, Pose2)> = Vec::new();
        let mut longest = 0.0f64;
        for (k, (&node, keyframe)) in nodes.iter().zip(&self.keyframes).enumerate().take(first) {
            let d = here.between(&node);
            if d.x().hypot(d.y()) > search_m
                || path_here - keyframe.path_m < c.min_loop_path_m
                || searched.iter().rev().take_while(|(i, _)| k - i <= 2 * c.submap_keyframes).any(
                    |(_, s)| {
                        (s.x() - node.x()).hypot(s.y() - node.y()) < PLACE_SPACING_M
                            && wrap_angle(s.heading() - node.heading()).abs() < PLACE_SPACING_RAD
                    },
                )
            {
                continue;
            }
            searched.push((k, node));
            let lines: Vec<LineSegment> =
                facing_left(&self.local_lines(k, self.candidate_stretch(k, first)));
            let prior = AlignmentPrior {
                candidate_from_current: node.between(&here),
                radius_m: search_m,
                // Any rotation: where the chain's heading is wrong enough
                // for the place to be capped, a copy may lie turned.
                max_rotation_rad: std::f64::consts::PI,
            };
            let Some(b) = align_lines(&verified.current_lines, &lines, Some(&prior), &c.alignment)
            else {
                continue;
            };
            if b.rms_m > c.max_rms_m || b.weakest_direction_m < c.min_weakest_direction_m {
                continue;
            }
            if elsewhere(&placed, &node.compose(&b.candidate_from_current)) {
                longest = longest.max(b.matched_length_m);
            }
        }
        longest
    }

    /// Step 3: the verified loop waits for a second, from another of the
    /// last keyframes, that closes the same cycle; once confirmed, both
    /// become edges of the graph. Returns the edges added.
    fn confirm_loop(
        &mut self,
        current: usize,
        verified: &VerifiedLoop,
        other_place_length_m: f64,
    ) -> usize {
        let c = self.config;
        let (j, a) = (verified.candidate, &verified.alignment);
        let mut r = verified.record(current, LoopOutcome::Unconfirmed);
        r.other_place_length_m = other_place_length_m;
        self.loops.push(r);
        let index = self.loops.len() - 1;
        // Confirmation: a loop stands once a second one, from another of
        // the last keyframes, closes the same cycle: the first loop, the
        // chain from its keyframe to this one, and this loop back along the
        // chain between the candidates, compose to the identity. Only the
        // short chain pieces enter the test, not the drift the loops
        // correct, so a large correction confirms as readily as a small
        // one. A false loop from aliasing (a repeated door, a symmetric
        // junction) rarely repeats. Where the prior does not vouch for the
        // place, the two loops must align local sets with no keyframe in
        // common: adjacent keyframes see nearly the same lines, and agree
        // on a wrong place as readily as on the right one.
        let independent = c.independent_confirm_keyframes > 0;
        let nodes = &self.graph.nodes;
        let loops = &self.loops;
        let window = |p: &PendingLoop| {
            if independent && loops[p.record].weak_prior {
                c.confirm_keyframes.max(c.independent_confirm_keyframes)
            } else {
                c.confirm_keyframes
            }
        };
        self.pending.retain(|p| current - p.keyframe <= window(p));
        let agrees = |p: &PendingLoop| {
            let earlier = &loops[p.record];
            let (kp, jp) = (earlier.keyframe, earlier.candidate);
            if independent
                && (earlier.weak_prior || verified.weak_prior)
                && current - kp <= c.submap_keyframes
            {
                return false;
            }
            // The earlier candidate's frame to this keyframe, both ways.
            let via_earlier =
                earlier.candidate_from_current.compose(&nodes[kp].between(&nodes[current]));
            let via_this = nodes[jp].between(&nodes[j]).compose(&a.candidate_from_current);
            let d = via_earlier.between(&via_this);
            d.x().hypot(d.y()) <= c.confirm_distance_m
                && wrap_angle(d.heading()).abs() <= c.confirm_rotation_rad
        };
        let confirmed: Vec<usize> =
            self.pending.iter().filter(|p| agrees(p)).map(|p| p.record).collect();
        if c.confirm_keyframes > 0 && confirmed.is_empty() {
            self.pending.push(PendingLoop { keyframe: current, record: index });
            return 0;
        }
        if let Some(&first) = confirmed.first() {
            self.loops[index].confirmed_with = Some(first);
        }
        for &r in &confirmed {
            if self.loops[r].confirmed_with.is_none() {
                self.loops[r].confirmed_with = Some(index);
            }
        }
        let mut added = 0;
        for r in confirmed.into_iter().chain(std::iter::once(index)) {
            if self.loops[r].edge.is_some() {
                continue;
            }
            let l = self.loops[r];
            let covariance =
                loop_covariance(l.information, l.rms_m, c.loop_floor_m, c.loop_floor_rad);
            let edge = self.graph.add_edge(
                l.candidate,
                l.keyframe,
                l.candidate_from_current,
                covariance,
                EdgeKind::Loop,
            );
            self.loops[r].edge = Some(edge);
            self.loops[r].outcome = LoopOutcome::Accepted;
            added += 1;
        }
        self.pending.push(PendingLoop { keyframe: current, record: index });
        added
    }

    /// Optimizes the graph, marks the loops it switched off, rebuilds the
    /// map from the keyframes at their optimized poses and carries the
    /// estimator over. The report says why the poses were kept, if they were
    /// ([`crate::NotOptimized`]); the map is then left as it is.
    pub fn optimize(&mut self) -> OptimizeReport {
        let Some(old_last) = self.graph.nodes.last().copied() else {
            return self.graph.optimize(&self.config.optimizer);
        };
        let report = self.graph.optimize(&self.config.optimizer);
        self.optimizations += 1;
        // Pending loops were checked against the poses before.
        self.pending.clear();
        self.last_optimization = Some(report.clone());
        for e in &report.switched_off {
            if let Some(r) = self.loops.iter_mut().find(|r| r.edge == Some(*e)) {
                r.outcome = LoopOutcome::SwitchedOff;
            }
        }
        if report.kept.is_some() {
            return report;
        }
        let new_last = *self.graph.nodes.last().unwrap_or(&old_last);
        let new_from_old = new_last.compose(&old_last.inverse());
        let map = self.rebuilt_map();
        self.aiding.reanchor(map, &new_from_old);
        report
    }

    /// The line map built again from every keyframe's lines at its node's
    /// pose, in keyframe order.
    fn rebuilt_map(&self) -> LineMap {
        let config = *self.aiding.map().config();
        // The configuration was validated when the map was first built.
        let mut map = match LineMap::new(config) {
            Ok(m) => m,
            Err(_) => return self.aiding.map().clone(),
        };
        for (k, node) in self.keyframes.iter().zip(&self.graph.nodes) {
            map.begin_scan();
            for l in &k.lines {
                map.insert_observed(node, &l.line, &l.moments);
            }
        }
        map
    }
}

/// Whether two placements of one keyframe are different places: farther
/// apart than [`SAME_PLACE_M`] or turned by more than [`SAME_PLACE_RAD`].
fn elsewhere(a: &Pose2, b: &Pose2) -> bool {
    let d = a.between(b);
    d.x().hypot(d.y()) > SAME_PLACE_M || wrap_angle(d.heading()).abs() > SAME_PLACE_RAD
}

fn record(
    keyframe: usize,
    candidate: usize,
    a: &Alignment,
    see_through: f64,
    outcome: LoopOutcome,
) -> LoopRecord {
    LoopRecord {
        keyframe,
        candidate,
        edge: None,
        candidate_from_current: a.candidate_from_current,
        matched_length_m: a.matched_length_m,
        weakest_direction_m: a.weakest_direction_m,
        runner_up_length_m: a.runner_up_length_m,
        rms_m: a.rms_m,
        see_through,
        other_place_length_m: 0.0,
        information: a.information,
        search: LoopSearch::Local,
        weak_prior: false,
        confirmed_with: None,
        outcome,
    }
}

/// The candidate that passed verification, with what the later steps need.
#[derive(Debug, Clone)]
struct VerifiedLoop {
    candidate: usize,
    alignment: Alignment,
    see_through: f64,
    /// The candidate's search radius, metres.
    radius_m: f64,
    /// The current keyframe's local lines, its own frame.
    current_lines: Vec<LineSegment>,
    /// How the candidate was found.
    search: LoopSearch,
    /// [`LoopRecord::weak_prior`].
    weak_prior: bool,
}

impl VerifiedLoop {
    fn record(&self, keyframe: usize, outcome: LoopOutcome) -> LoopRecord {
        let mut r = record(keyframe, self.candidate, &self.alignment, self.see_through, outcome);
        r.search = self.search;
        r.weak_prior = self.weak_prior;
        r
    }
}

/// A verified loop waiting for a second to confirm it.
#[derive(Debug, Clone, Copy)]
struct PendingLoop {
    keyframe: usize,
    /// Its index in the loop records.
    record: usize,
}

/// Each line directed with its viewpoint on its left, so that the two faces
/// of a wall, seen from either side, point opposite ways
/// ([`crate::Facing::Same`]). A reversed line keeps only its ends, all
/// that [`align_lines`] reads.
fn facing_left(seen: &[(LineSegment, Point2<f64>)]) -> Vec<LineSegment> {
    seen.iter()
        .map(|(l, v)| {
            if (l.end() - l.start()).perp(&(v - l.start())) < 0.0 {
                LineSegment::between(l.end(), l.start())
            } else {
                *l
            }
        })
        .collect()
}

/// A loop edge's covariance: the alignment's least-squares covariance for
/// its residual, per endpoint of unit weight, with the floors added.
fn loop_covariance(
    information: Matrix3<f64>,
    rms_m: f64,
    floor_m: f64,
    floor_rad: f64,
) -> Matrix3<f64> {
    let floors =
        Matrix3::from_diagonal(&Vector3::new(floor_m.powi(2), floor_m.powi(2), floor_rad.powi(2)));
    // The information is in metres of wall; one endpoint per half metre.
    let info = information * 2.0 / rms_m.max(0.01).powi(2);
    match info.try_inverse() {
        Some(c) if c.iter().all(|v| v.is_finite()) => c + floors,
        _ => floors * 100.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_fitting::Moments;

    /// The walls of a 6 m x 4 m room with a pillar, centred at `(cx, 0)`.
    fn room(cx: f64) -> Vec<(Point2<f64>, Point2<f64>)> {
        let p = |x: f64, y: f64| Point2::new(cx + x, y);
        vec![
            (p(-3.0, -2.0), p(3.0, -2.0)),
            (p(3.0, -2.0), p(3.0, 2.0)),
            (p(3.0, 2.0), p(-3.0, 2.0)),
            (p(-3.0, 2.0), p(-3.0, -2.0)),
            (p(1.0, 0.0), p(1.6, 0.0)),
            (p(1.6, 0.0), p(1.6, 0.8)),
        ]
    }

    /// The walls seen from `pose` (all of them: no occlusion), sensor frame.
    fn seen(walls: &[(Point2<f64>, Point2<f64>)], pose: &Pose2) -> Vec<SensorLine> {
        let inv = pose.inverse();
        walls
            .iter()
            .map(|(a, b)| {
                let (a, b) = (inv.transform_point(a), inv.transform_point(b));
                let points: Vec<Point2<f64>> =
                    (0..=20).map(|k| a + (b - a) * (k as f64 / 20.0)).collect();
                SensorLine {
                    line: LineSegment::between(a, b),
                    moments: Moments::from_points(&points),
                }
            })
            .collect()
    }

    /// Loop closing with the standard configuration over the estimator.
    fn standard_slam() -> LoopClosing {
        LoopClosing::new(
            AidingConfig::estimator(),
            MapConfig::default(),
            LoopClosureConfig::standard(),
        )
        .unwrap()
    }

    /// Laps around a room centred at `(cx, 0)`, 0.25 m per scan.
    fn laps(cx: f64, laps: usize) -> Vec<Pose2> {
        let n = 60;
        (0..laps * n)
            .map(|k| {
                let a = k as f64 / n as f64 * std::f64::consts::TAU;
                Pose2::new(cx + 1.5 * a.cos(), 1.0 * a.sin(), a + std::f64::consts::FRAC_PI_2)
            })
            .collect()
    }

    #[test]
    fn twin_rooms_do_not_close_a_false_loop() {
        let (a, b) = (room(0.0), room(20.0));
        let mut slam = standard_slam();
        // Three laps in room A, a corridor walk with no walls in view, three laps
        // in room B, with a slow heading drift in the source.
        let mut truth = laps(0.0, 3);
        let from = *truth.last().unwrap();
        for k in 1..=40 {
            let f = k as f64 / 40.0;
            truth.push(Pose2::new(from.x() + f * 18.5, from.y() * (1.0 - f), 0.0));
        }
        truth.extend(laps(20.0, 3));
        let mut source = Pose2::identity();
        let mut previous = truth[0];
        for (k, pose) in truth.iter().enumerate() {
            let step = previous.between(pose);
            source = source.compose(&Pose2::new(step.x(), step.y(), step.heading() + 0.001));
            previous = *pose;
            let walls = if pose.x() < 5.0 {
                &a
            } else if pose.x() > 15.0 {
                &b
            } else {
                &Vec::new()
            };
            slam.step_at(k as f64 * 0.1, &source, &seen(walls, pose));
        }
        slam.optimize();
        let in_room_a = |node: usize| slam.graph().nodes[node].x() < 10.0;
        let false_loops = slam
            .graph()
            .edges
            .iter()
            .filter(|e| e.kind == EdgeKind::Loop && e.active)
            .filter(|e| in_room_a(e.from) != in_room_a(e.to))
            .count();
        assert_eq!(false_loops, 0);
        // The true loops in each room were found.
        let accepted = slam.loops().iter().filter(|r| r.outcome == LoopOutcome::Accepted).count();
        assert!(
            accepted >= 2,
            "{} keyframes, path {:?}",
            slam.keyframes().len(),
            slam.keyframes().last().map(|k| k.path_m)
        );
    }

    /// Laps of one room with a source that slips 0.8 m sideways half-way
    /// round the second lap, the map built from the source as it is (no
    /// aiding), and the local search capped at 0.3 m: after the slip the
    /// first lap lies 0.8 m from where the graph puts it, beyond the cap but
    /// within the chain's uncertainty. Place recognition finds the loops
    /// there, the right ones, and the optimization undoes the slip; with it
    /// off, no loop stands.
    #[test]
    fn place_recognition_finds_loops_beyond_the_local_search() {
        let walls = room(0.0);
        let truth = laps(0.0, 3);
        let run = |place_recognition: Option<PlaceRecognitionConfig>| {
            let mut config = LoopClosureConfig::standard();
            config.search_radius_m = 0.2;
            config.max_search_radius_m = 0.3;
            config.place_recognition = place_recognition;
            let mut slam =
                LoopClosing::new(AidingConfig::none(), MapConfig::default(), config).unwrap();
            for (k, pose) in truth.iter().enumerate() {
                let slip = if k >= 90 { 0.8 } else { 0.0 };
                let source = Pose2::new(slip, 0.0, 0.0).compose(pose);
                slam.step_at(k as f64 * 0.1, &source, &seen(&walls, pose));
            }
            slam.optimize();
            slam
        };
        let truth_of = |slam: &LoopClosing, r: &LoopRecord| {
            let k = |i: usize| truth[slam.keyframes()[i].scan];
            k(r.candidate).between(&k(r.keyframe))
        };
        let off = run(None);
        let standing = |slam: &LoopClosing| -> Vec<LoopRecord> {
            slam.loops().iter().filter(|r| r.outcome == LoopOutcome::Accepted).copied().collect()
        };
        for r in standing(&off) {
            // Any loop without place recognition lies before the slip.
            assert!(off.keyframes()[r.keyframe].scan < 90, "{r:?}");
        }
        let on = run(Some(PlaceRecognitionConfig::standard()));
        let recognised: Vec<LoopRecord> = standing(&on)
            .into_iter()
            .filter(|r| r.search == LoopSearch::PlaceRecognition)
            .collect();
        assert!(!recognised.is_empty(), "{:#?}", on.loops());
        for r in &recognised {
            let error = truth_of(&on, r).between(&r.candidate_from_current);
            assert!(error.x().hypot(error.y()) < 0.05, "{r:?}");
        }
        // The last pose, 0.8 m off in the source, is brought back; without
        // place recognition it stays off.
        let last_error = |slam: &LoopClosing| {
            let last = slam.trajectory().last().copied().flatten().unwrap();
            let truth_last = truth.last().unwrap();
            (last.x() - truth_last.x()).hypot(last.y() - truth_last.y())
        };
        assert!(last_error(&on) < 0.1, "{} m", last_error(&on));
        assert!(last_error(&off) > 0.7, "{} m", last_error(&off));
    }

    /// Laps in room A, then laps in its twin B, 8 m along: with the place
    /// search on and reaching A, the loops inside B are refused as a
    /// look-alike place (A fits them as well); with it off they stand.
    #[test]
    fn the_place_search_refuses_loops_that_a_twin_place_fits() {
        let (a, b) = (room(0.0), room(8.0));
        let run = |scale: f64| {
            let mut config = LoopClosureConfig::standard();
            config.place_search_scale = scale;
            let mut slam =
                LoopClosing::new(AidingConfig::estimator(), MapConfig::default(), config).unwrap();
            let mut truth = laps(0.0, 3);
            let from = *truth.last().unwrap();
            for k in 1..=20 {
                let f = k as f64 / 20.0;
                truth.push(Pose2::new(from.x() + f * 6.5, from.y() * (1.0 - f), 0.0));
            }
            truth.extend(laps(8.0, 3));
            for (k, pose) in truth.iter().enumerate() {
                let walls = if pose.x() < 3.0 { &a } else { &b };
                slam.step_at(k as f64 * 0.1, pose, &seen(walls, pose));
            }
            slam
        };
        let in_b = |slam: &LoopClosing, r: &LoopRecord| {
            slam.graph().nodes[r.keyframe].x() > 4.0 && slam.graph().nodes[r.candidate].x() > 4.0
        };
        let off = run(0.0);
        assert!(
            off.loops().iter().any(|r| in_b(&off, r) && r.outcome == LoopOutcome::Accepted),
            "{:?}",
            off.loops()
        );
        let on = run(10.0);
        let refused: Vec<&LoopRecord> = on
            .loops()
            .iter()
            .filter(|r| in_b(&on, r) && r.outcome == LoopOutcome::LookAlikePlace)
            .collect();
        assert!(!refused.is_empty(), "{:?}", on.loops());
        for r in refused {
            assert!(r.other_place_length_m > 0.7 * r.matched_length_m, "{r:?}");
        }
        assert!(!on.loops().iter().any(|r| in_b(&on, r) && r.outcome == LoopOutcome::Accepted));
    }

    /// A scan whose stamp goes backwards is skipped by the estimator: its
    /// pose is the last one moved by the source, and it makes no keyframe
    /// (no loop or optimization may start from a guessed pose).
    #[test]
    fn a_skipped_scan_makes_no_keyframe() {
        let walls = room(0.0);
        let mut slam = standard_slam();
        let first = Pose2::new(1.0, 1.0, 0.0);
        slam.step_at(1.0, &first, &seen(&walls, &first));
        assert_eq!(slam.keyframes().len(), 1);
        // Turned by 30° (a keyframe's worth), but stamped before the first.
        let turned = Pose2::new(1.0, 1.0, 0.5);
        let step = slam.step_at(0.5, &turned, &seen(&walls, &turned));
        assert_eq!(step.report.fallback, Some(Fallback::StampBackwards));
        assert_eq!(step.keyframe, None);
        assert_eq!(slam.keyframes().len(), 1);
        assert!((step.pose.heading() - 0.5).abs() < 1e-9, "{:?}", step.pose);
        // The next scan in order is processed and becomes a keyframe.
        let step = slam.step_at(2.0, &turned, &seen(&walls, &turned));
        assert_eq!(step.keyframe, Some(1));
    }

    /// Scans between two keyframes take the optimization's correction in
    /// proportion to their place between them: the trajectory does not jump
    /// at the next keyframe, and agrees with the old placement when the
    /// nodes agree with their edge.
    #[test]
    fn scans_between_keyframes_blend_the_two_corrections() {
        let walls = room(0.0);
        let mut slam = standard_slam();
        // A keyframe each 0.5 m: scans at 0, 0.1, ..., 0.5 m along x.
        for k in 0..=5 {
            let p = Pose2::new(-1.0 + 0.1 * k as f64, 0.5, 0.0);
            slam.step_at(k as f64, &p, &seen(&walls, &p));
        }
        assert_eq!(slam.keyframes().iter().map(|k| k.scan).collect::<Vec<_>>(), [0, 5]);
        let before = slam.trajectory();
        // Nodes that agree with their edge: the same placement as before.
        let moved = Pose2::new(0.3, -0.2, 0.1);
        slam.graph.nodes = slam.graph.nodes.iter().map(|n| moved.compose(n)).collect();
        for (b, a) in before.iter().zip(slam.trajectory()) {
            let (b, a) = (moved.compose(&b.unwrap()), a.unwrap());
            assert!((b.x() - a.x()).abs() < 1e-9 && (b.y() - a.y()).abs() < 1e-9, "{a:?} {b:?}");
        }
        // The second keyframe moved 10 cm and 0.02 rad against its edge: the
        // scans between take 0, 1/5, ..., 4/5 of that move.
        let shift = Pose2::new(0.0, 0.1, 0.02);
        slam.graph.nodes[1] = slam.graph.nodes[1].compose(&shift);
        let after = slam.trajectory();
        let base: Vec<Pose2> = before.iter().map(|p| moved.compose(&p.unwrap())).collect();
        for (k, (a, b)) in after.iter().zip(&base).enumerate().take(5) {
            let turn = wrap_angle(a.unwrap().heading() - b.heading());
            assert!((turn - 0.02 * k as f64 / 5.0).abs() < 1e-9, "scan {k}: {turn}");
        }
        let (last, next) = (after[4].unwrap(), after[5].unwrap());
        assert!(last.between(&next).x().hypot(last.between(&next).y()) < 0.12, "{last:?} {next:?}");
    }

    /// A verified loop at `current` to `candidate`, where the graph already
    /// places them: the alignment agrees with the chain.
    fn agreeing_loop(
        slam: &LoopClosing,
        current: usize,
        candidate: usize,
        weak_prior: bool,
    ) -> VerifiedLoop {
        let nodes = &slam.graph().nodes;
        VerifiedLoop {
            candidate,
            alignment: Alignment {
                candidate_from_current: nodes[candidate].between(&nodes[current]),
                matches: 6,
                matched_length_m: 10.0,
                current_length_m: 12.0,
                weakest_direction_m: 2.0,
                rms_m: 0.01,
                information: Matrix3::identity() * 100.0,
                runner_up_length_m: 0.0,
            },
            see_through: 0.0,
            radius_m: 8.0,
            current_lines: Vec::new(),
            search: LoopSearch::Local,
            weak_prior,
        }
    }

    /// Two loops from adjacent keyframes confirm each other when the prior
    /// vouches for the place; when it does not, only a loop from a keyframe
    /// whose local set shares none of the first's keyframes does, and the
    /// pair is recorded.
    #[test]
    fn a_weak_prior_loop_needs_a_confirmation_from_independent_lines() {
        let walls = room(0.0);
        let mut config = LoopClosureConfig::standard();
        // No loop of its own: the test adds them.
        config.min_loop_path_m = 1e6;
        let make = |config: LoopClosureConfig| {
            let mut slam =
                LoopClosing::new(AidingConfig::none(), MapConfig::default(), config).unwrap();
            for (k, pose) in laps(0.0, 2).iter().enumerate() {
                slam.step_at(k as f64 * 0.1, pose, &seen(&walls, pose));
            }
            assert!(slam.keyframes().len() > 30, "{}", slam.keyframes().len());
            slam
        };
        let n = config.submap_keyframes;
        // Vouched for: the next keyframe confirms.
        let mut slam = make(config);
        assert_eq!(slam.confirm_loop(20, &agreeing_loop(&slam, 20, 2, false), 0.0), 0);
        assert_eq!(slam.confirm_loop(21, &agreeing_loop(&slam, 21, 3, false), 0.0), 2);
        // Not vouched for: the adjacent loops wait, the first independent
        // one confirms the loops it shares no keyframe with.
        let mut slam = make(config);
        assert_eq!(slam.confirm_loop(20, &agreeing_loop(&slam, 20, 2, true), 0.0), 0);
        assert_eq!(slam.confirm_loop(21, &agreeing_loop(&slam, 21, 3, true), 0.0), 0);
        let later = 20 + n + 1;
        assert_eq!(slam.confirm_loop(later, &agreeing_loop(&slam, later, 8, true), 0.0), 2);
        let loops = slam.loops();
        assert_eq!(loops[0].outcome, LoopOutcome::Accepted);
        assert_eq!(loops[1].outcome, LoopOutcome::Unconfirmed);
        assert_eq!(loops[2].outcome, LoopOutcome::Accepted);
        assert_eq!((loops[0].confirmed_with, loops[2].confirmed_with), (Some(2), Some(0)));
        assert!(loops.iter().all(|r| r.weak_prior));
        // Switched off, adjacent loops confirm each other again.
        config.independent_confirm_keyframes = 0;
        let mut slam = make(config);
        assert_eq!(slam.confirm_loop(20, &agreeing_loop(&slam, 20, 2, true), 0.0), 0);
        assert_eq!(slam.confirm_loop(21, &agreeing_loop(&slam, 21, 3, true), 0.0), 2);
    }

    #[test]
    fn validation_names_the_field_path() {
        let mut c = LoopClosureConfig::standard();
        c.max_search_radius_m = -1.0;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("loop_closure.max_search_radius_m"), "{e}");
        let mut c = LoopClosureConfig::standard();
        c.optimizer.rounds = 0;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("loop_closure.optimizer.rounds"), "{e}");
        let mut c = LoopClosureConfig::standard();
        c.place_search_scale = f64::NAN;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("loop_closure.place_search_scale"), "{e}");
        let mut c = LoopClosureConfig::standard();
        c.independent_confirm_keyframes = c.submap_keyframes;
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("loop_closure.independent_confirm_keyframes"), "{e}");
    }
}
