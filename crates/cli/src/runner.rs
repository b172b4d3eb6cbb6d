//! [`Runner`]: the estimator alone or with loop closure, behind one set of
//! steps, for the commands that offer both (`map`, `eval --real`).

use anyhow::Result;
use pcaline::Pose2;
use pcaline::aiding::{
    Aiding, AidingConfig, LoopClosing, LoopClosureConfig, SensorLine, StepReport,
};
use pcaline::mapping::{LineMap, MapConfig};

/// One aiding loop: the aiding alone, or with loop closure on top.
pub enum Runner {
    /// The aiding alone.
    Plain(Box<Aiding>),
    /// Keyframes, loop closure and a pose graph on top of the aiding.
    Loops(Box<LoopClosing>),
}

impl Runner {
    /// A loop with an empty map; with loop closure when `loops` is given.
    pub fn new(
        aiding: AidingConfig,
        map: MapConfig,
        loops: Option<LoopClosureConfig>,
    ) -> Result<Self> {
        Ok(match loops {
            None => Runner::Plain(Box::new(Aiding::new(aiding, map)?)),
            Some(l) => Runner::Loops(Box::new(LoopClosing::new(aiding, map, l)?)),
        })
    }

    /// The aiding (the estimator under the loop closure).
    pub fn aiding(&self) -> &Aiding {
        match self {
            Runner::Plain(a) => a,
            Runner::Loops(l) => l.aiding(),
        }
    }

    /// The loop closure, if on.
    pub fn loop_closing(&self) -> Option<&LoopClosing> {
        match self {
            Runner::Plain(_) => None,
            Runner::Loops(l) => Some(l),
        }
    }

    /// The line map.
    pub fn map(&self) -> &LineMap {
        self.aiding().map()
    }

    /// The estimated velocity (for deskew without a source).
    pub fn velocity(&self) -> Option<Pose2> {
        self.aiding().velocity()
    }

    /// One scan with the source's pose, stamped or not.
    pub fn step(
        &mut self,
        stamp_s: Option<f64>,
        source: &Pose2,
        lines: &[SensorLine],
    ) -> (Pose2, StepReport) {
        match (self, stamp_s) {
            (Runner::Plain(a), Some(t)) => a.step_at(t, source, lines),
            (Runner::Plain(a), None) => a.step(source, lines),
            (Runner::Loops(l), Some(t)) => {
                let s = l.step_at(t, source, lines);
                (s.pose, s.report)
            }
            (Runner::Loops(l), None) => {
                let s = l.step(source, lines);
                (s.pose, s.report)
            }
        }
    }

    /// One scan without a source (LIDAR-only mode).
    pub fn step_without_source(
        &mut self,
        stamp_s: Option<f64>,
        lines: &[SensorLine],
    ) -> (Pose2, StepReport) {
        match self {
            Runner::Plain(a) => a.step_without_source(stamp_s, lines),
            Runner::Loops(l) => {
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
            Runner::Plain(_) => None,
            Runner::Loops(l) => {
                l.optimize();
                Some(l.trajectory())
            }
        }
    }
}
