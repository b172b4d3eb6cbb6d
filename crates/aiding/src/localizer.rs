//! [`Localizer`]: the aiding alone or with loop closure on top, behind one
//! set of steps, for callers that offer both (the facade's `Mapper`,
//! `pcaline map`, `pcaline eval --real`).

use crate::{Aiding, AidingConfig, LoopClosing, LoopClosureConfig, ObservedLine, StepReport};
use pcaline_geometry::{ConfigError, Pose2, Twist2};
use pcaline_mapping::{LineMap, MapConfig};

/// One localization loop: the aiding alone, or with loop closure on top.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum Localizer {
    /// The aiding alone.
    Plain(Box<Aiding>),
    /// Keyframes, loop closure and a pose graph on top of the aiding.
    Loops(Box<LoopClosing>),
}

impl Localizer {
    /// A loop with an empty map; with loop closure when `loops` is given.
    pub fn new(
        aiding: AidingConfig,
        map: MapConfig,
        loops: Option<LoopClosureConfig>,
    ) -> Result<Self, ConfigError> {
        Ok(match loops {
            None => Localizer::Plain(Box::new(Aiding::new(aiding, map)?)),
            Some(l) => Localizer::Loops(Box::new(LoopClosing::new(aiding, map, l)?)),
        })
    }

    /// The aiding (the estimator under the loop closure).
    pub fn aiding(&self) -> &Aiding {
        match self {
            Localizer::Plain(a) => a,
            Localizer::Loops(l) => l.aiding(),
        }
    }

    /// The loop closure, if on.
    pub fn loop_closing(&self) -> Option<&LoopClosing> {
        match self {
            Localizer::Plain(_) => None,
            Localizer::Loops(l) => Some(l),
        }
    }

    /// The line map.
    pub fn map(&self) -> &LineMap {
        self.aiding().map()
    }

    /// The estimated velocity (for deskew without a source).
    pub fn velocity(&self) -> Option<Twist2> {
        self.aiding().velocity()
    }

    /// The latest corrected pose.
    pub fn pose(&self) -> Option<Pose2> {
        self.aiding().pose()
    }

    /// Optimizes the graph now (with loop closure; `None` without).
    pub fn optimize(&mut self) -> Option<crate::OptimizeReport> {
        match self {
            Localizer::Plain(_) => None,
            Localizer::Loops(l) => Some(l.optimize()),
        }
    }

    /// One scan with the source's pose: [`Aiding::step_at`] when stamped,
    /// [`Aiding::step`] when not (with loop closure on top, if on).
    pub fn step_with(
        &mut self,
        stamp_s: Option<f64>,
        source: &Pose2,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        match (self, stamp_s) {
            (Localizer::Plain(a), Some(t)) => a.step_at(t, source, lines),
            (Localizer::Plain(a), None) => a.step(source, lines),
            (Localizer::Loops(l), Some(t)) => {
                let s = l.step_at(t, source, lines);
                (s.pose, s.report)
            }
            (Localizer::Loops(l), None) => {
                let s = l.step(source, lines);
                (s.pose, s.report)
            }
        }
    }

    /// One scan without a source (LIDAR-only mode).
    pub fn step_without_source(
        &mut self,
        stamp_s: Option<f64>,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        match self {
            Localizer::Plain(a) => a.step_without_source(stamp_s, lines),
            Localizer::Loops(l) => {
                let s = l.step_without_source(stamp_s, lines);
                (s.pose, s.report)
            }
        }
    }

    /// With loop closure: a last optimization, then every stepped scan's
    /// pose as the graph places it (a scan before the first keyframe keeps
    /// `None`). `None` for the aiding alone, whose poses are final as they
    /// come.
    pub fn finish(&mut self) -> Option<Vec<Option<Pose2>>> {
        match self {
            Localizer::Plain(_) => None,
            Localizer::Loops(l) => {
                l.optimize();
                Some(l.trajectory())
            }
        }
    }
}
