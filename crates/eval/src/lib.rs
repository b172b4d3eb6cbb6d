//! Accuracy metrics of pcaline against exact ground truth: localization
//! errors of trajectories, the quality of line maps against the true walls,
//! and the paper's own simulations (Tables 1-3 and the `ETh` experiment).
//!
//! ```
//! use pcaline_eval::trajectory_errors;
//! use pcaline_geometry::Pose2;
//! let truth = [Pose2::identity(), Pose2::new(1.0, 0.0, 0.0)];
//! let estimate = [Pose2::identity(), Pose2::new(1.0, 0.3, 0.1)];
//! let e = trajectory_errors(&estimate, &truth).unwrap();
//! assert!((e.position_final_m - 0.3).abs() < 1e-12);
//! assert!((e.heading_max_rad - 0.1).abs() < 1e-12);
//! ```

mod detection;
mod detection_run;
mod fit_accuracy;
mod localization;
mod loop_check;
mod map_quality;
mod relation_metric;
mod reproduce;
mod scan_agreement;
mod sensitivity;
mod sharpness;
#[cfg(test)]
mod test_scans;
mod trajectory;

pub use detection::{
    DetectionCriteria, DetectionScore, LENGTH_BINS_M, TrueWall, matches, true_walls,
};
pub use detection_run::{
    DetectFn, DetectionEval, DetectorResult, FaultMode, evaluate_detectors, oracle_lines,
    surface_rms_m,
};
pub use fit_accuracy::{FitAccuracy, RangeBearingAccuracy, fit_accuracy, range_bearing_accuracy};
pub use localization::{
    AidedRun, AidedScore, MAP_MAX_ANGLE_DEG, MAP_TOLERANCE_M, ObservedRunError, RunStep,
};
pub use loop_check::{
    LoopCheck, WRONG_LOOP_DEG, WRONG_LOOP_M, reference_by_registration, reference_by_source,
};
pub use map_quality::{MapQuality, VisibleWalls, map_quality};
pub use relation_metric::{RelationErrors, StampedTrajectory, relation_errors};
pub use reproduce::{
    ETH_EXPERIMENTS, EthExperiment, EthResult, FitRow, FitRowResult, TABLE1, TABLE2, TABLE3,
    dataset, run_eth, run_fit_row,
};
pub use scan_agreement::{
    AGREEING_SHARE, CONTRADICTED_SHARE, LinkAgreement, MAX_OUTLIER_STRETCH, ScanAgreement,
    scan_agreement,
};
pub use sensitivity::{SENSITIVITY_PERTURBATION, SENSITIVITY_SEEDS, perturbed};
pub use sharpness::OccupiedCells;
pub use trajectory::{
    TrajectoryErrors, aligned_trajectory_errors, rigid_alignment,
    rigidly_aligned_trajectory_errors, trajectory_errors,
};
