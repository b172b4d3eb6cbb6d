//! [`Localizer`]: the aiding alone or with loop closure on top, behind one
//! set of steps, for callers that offer both (the facade's `Mapper`,
//! `pcaline map`, `pcaline eval --real`), each scan registered to the
//! previous one for the estimator ([`ScanRegistrar`]) when the
//! configuration asks for it.

use crate::{
    Aiding, AidingConfig, AidingMode, LoopClosing, LoopClosureConfig, ObservedLine, ScanRegistrar,
    StepReport,
};
use pcaline_geometry::{ConfigError, Pose2, Scan, Twist2};
use pcaline_mapping::{LineMap, MapConfig};

/// One localization loop: the aiding alone, or with loop closure on top.
#[derive(Debug, Clone)]
pub struct Localizer {
    runner: Runner,
    registrar: Option<ScanRegistrar>,
}

#[derive(Debug, Clone)]
enum Runner {
    /// The aiding alone.
    Plain(Box<Aiding>),
    /// Keyframes, loop closure and a pose graph on top of the aiding.
    Loops(Box<LoopClosing>),
}

use Runner as R;

impl Localizer {
    /// A loop with an empty map; with loop closure when `loops` is given,
    /// and with each scan registered to the previous one in
    /// [`Self::step_scan`] when `aiding` is the estimator and its
    /// `scan_matching` is set.
    pub fn new(
        aiding: AidingConfig,
        map: MapConfig,
        loops: Option<LoopClosureConfig>,
    ) -> Result<Self, ConfigError> {
        let registrar = match (aiding.mode, aiding.estimator.scan_matching) {
            (AidingMode::Estimator, Some(c)) => Some(ScanRegistrar::new(c)?),
            _ => None,
        };
        let runner = match loops {
            None => R::Plain(Box::new(Aiding::new(aiding, map)?)),
            Some(l) => R::Loops(Box::new(LoopClosing::new(aiding, map, l)?)),
        };
        Ok(Localizer { runner, registrar })
    }

    /// One scan `scan` (its stamp, if any, is the step's) with the source's
    /// pose `source` and the scan's lines: [`Self::step_with`], the scan
    /// first registered to the previous one and the registration handed to
    /// the estimator ([`Aiding::set_registration`]) when the configuration
    /// asks for it. Returns the pose and the step's report.
    pub fn step_scan(
        &mut self,
        scan: &Scan,
        source: &Pose2,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        if let Some(registrar) = &mut self.registrar {
            let registration = registrar.next(source, scan);
            self.hand_over(registration);
        }
        self.step_with(scan.stamp_s, source, lines)
    }

    /// The aiding (the estimator under the loop closure).
    pub fn aiding(&self) -> &Aiding {
        match &self.runner {
            R::Plain(a) => a,
            R::Loops(l) => l.aiding(),
        }
    }

    /// The loop closure, if on.
    pub fn loop_closing(&self) -> Option<&LoopClosing> {
        match &self.runner {
            R::Plain(_) => None,
            R::Loops(l) => Some(l),
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
        match &mut self.runner {
            R::Plain(_) => None,
            R::Loops(l) => Some(l.optimize()),
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
        match (&mut self.runner, stamp_s) {
            (R::Plain(a), Some(t)) => a.step_at(t, source, lines),
            (R::Plain(a), None) => a.step(source, lines),
            (R::Loops(l), Some(t)) => {
                let s = l.step_at(t, source, lines);
                (s.pose, s.report)
            }
            (R::Loops(l), None) => {
                let s = l.step(source, lines);
                (s.pose, s.report)
            }
        }
    }

    /// One scan `scan` without a source (LIDAR-only mode) and the scan's
    /// lines: [`Self::step_without_source`], the scan first registered to
    /// the previous one ([`ScanRegistrar::next_without_source`]) and the
    /// registration handed to the estimator when the configuration asks for
    /// it, where it measures the step the constant-velocity model only
    /// guesses.
    pub fn step_scan_without_source(
        &mut self,
        scan: &Scan,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        if let Some(registrar) = &mut self.registrar {
            let registration = registrar.next_without_source(scan);
            self.hand_over(registration);
        }
        self.step_without_source(scan.stamp_s, lines)
    }

    /// Hands the next step's registration to the estimator.
    fn hand_over(&mut self, registration: Option<crate::Registration>) {
        match &mut self.runner {
            R::Plain(a) => a.set_registration(registration),
            R::Loops(l) => l.set_registration(registration),
        }
    }

    /// One scan without a source (LIDAR-only mode).
    pub fn step_without_source(
        &mut self,
        stamp_s: Option<f64>,
        lines: &[impl ObservedLine],
    ) -> (Pose2, StepReport) {
        match &mut self.runner {
            R::Plain(a) => a.step_without_source(stamp_s, lines),
            R::Loops(l) => {
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
        match &mut self.runner {
            R::Plain(_) => None,
            R::Loops(l) => {
                l.optimize();
                Some(l.trajectory())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scan_registration::tests::room_scan;
    use crate::{ScanMatchConfig, SensorLine};

    /// The worst position error over a LIDAR-only run in a room without
    /// lines to match (only a registration sees the motion): still for 10
    /// scans at 40 Hz, then moving and turning for 20, then still again.
    fn lidar_only_worst_error_m(scan_matching: Option<ScanMatchConfig>) -> f64 {
        let mut aiding = AidingConfig::estimator();
        aiding.estimator.scan_matching = scan_matching;
        let mut localizer = Localizer::new(aiding, MapConfig::default(), None).unwrap();
        let no_lines: [SensorLine; 0] = [];
        let mut worst = 0f64;
        for k in 0..40 {
            let s = (k as f64 - 10.0).clamp(0.0, 20.0);
            let truth = Pose2::new(0.02 * s, 0.01 * s, 0.01 * s);
            let scan = room_scan(&truth).with_stamp(0.025 * k as f64);
            let (pose, _) = localizer.step_scan_without_source(&scan, &no_lines);
            let e = truth.between(&pose);
            worst = worst.max(e.x().hypot(e.y()));
        }
        worst
    }

    #[test]
    fn lidar_only_mode_registers_the_motion_the_constant_velocity_model_misses() {
        let registered = lidar_only_worst_error_m(Some(ScanMatchConfig::standard()));
        assert!(registered < 0.005, "{registered} m");
        // Without the registration nothing sees the motion: the pose stays.
        let not_registered = lidar_only_worst_error_m(None);
        assert!(not_registered > 0.4, "{not_registered} m");
    }
}
