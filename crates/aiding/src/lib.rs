//! Localization aiding from line matches (paper, section 2.1, and beyond).
//!
//! A localization source (odometry, inertial, a log's poses) drifts. Each
//! scan's lines, placed in the world with the current estimate, are matched
//! against the line map; the matches correct the heading by the weighted mean
//! of their orientation offsets (eq. 11-13) and rotate the position step
//! accordingly (eq. 14). Beyond the paper, [`AidingMode::FullPose`] then
//! solves the translation from the matched lines' normal offsets (robust
//! weighted least squares, only along directions the matches constrain) and
//! iterates match and solve.
//!
//! ```
//! use pcaline_aiding::{Aiding, AidingConfig, SensorLine};
//! use pcaline_fitting::{Moments, line_from_moments};
//! use pcaline_geometry::{Point2, Pose2};
//! use pcaline_mapping::MapConfig;
//!
//! // A wall 3 m ahead, seen from the origin.
//! let pts: Vec<_> = (0..=20).map(|i| Point2::new(3.0, -1.0 + 0.1 * i as f64)).collect();
//! let moments = Moments::from_points(&pts);
//! let wall = SensorLine { line: line_from_moments(&moments, &pts[0], &pts[20]).unwrap(), moments };
//!
//! let mut aiding = Aiding::new(AidingConfig::paper(), MapConfig::paper()).unwrap();
//! aiding.step(&Pose2::identity(), &[wall]);
//! // The source claims the sensor turned by 0.05 rad; the wall says it did not.
//! let (pose, report) = aiding.step(&Pose2::new(0.0, 0.0, 0.05), &[wall]);
//! assert!(pose.heading.abs() < 1e-9);
//! assert_eq!(report.matches, 1);
//! ```

mod aiding;
mod heading;
mod translation;

pub use aiding::{Aiding, SensorLine};
pub use heading::{MIN_D_RHO_M, heading_correction, rotate_step, weighted_offset};
pub use translation::{NormalConstraint, TranslationFix, solve_translation};

use pcaline_geometry::{ConfigError, Vector2};

/// Which corrections are applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AidingMode {
    /// No correction: the map is built with the source's poses (for comparison).
    None,
    /// The paper: heading from eq. 11-13, position step rotated by eq. 14.
    Heading,
    /// Heading as the paper, then the translation from the matched lines,
    /// iterated.
    FullPose,
}

/// How the orientation offsets of the matches are weighted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HeadingWeights {
    /// Eq. 13: `1 / d_rho²`.
    InverseDRhoSquared,
    /// `1 / (var(alpha_new) + var(alpha_map) + floor²)` from the lines'
    /// covariances: long, well-fitted lines count most.
    InverseVariance {
        /// Floor of the orientation standard deviation, radians (model and
        /// pose errors the covariances do not hold).
        floor_rad: f64,
    },
}

/// Configuration of [`Aiding`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AidingConfig {
    /// Which corrections are applied.
    pub mode: AidingMode,
    /// Weights of the heading correction.
    pub heading_weights: HeadingWeights,
    /// Match/solve rounds in [`AidingMode::FullPose`].
    pub iterations: usize,
    /// Residual scale of the Cauchy robust weights, metres.
    pub robust_scale_m: f64,
    /// Smallest information along a direction, relative to the best
    /// direction, for the translation to be corrected along it.
    pub min_information_ratio: f64,
    /// Floor of a constraint's standard deviation, metres (map and model errors).
    pub offset_floor_m: f64,
    /// Largest heading correction of one step, radians (the matching
    /// threshold already bounds it).
    pub max_heading_step_rad: f64,
    /// Largest translation correction of one round, metres.
    pub max_translation_step_m: f64,
}

impl AidingConfig {
    /// The paper's heading aiding: eq. 11-14 with eq. 13's weights.
    pub fn paper() -> Self {
        AidingConfig {
            mode: AidingMode::Heading,
            heading_weights: HeadingWeights::InverseDRhoSquared,
            ..Self::full_pose()
        }
    }

    /// Heading aiding as the paper (eq. 11, 12, 14) with inverse-variance
    /// weights instead of eq. 13.
    pub fn heading() -> Self {
        AidingConfig { mode: AidingMode::Heading, ..Self::full_pose() }
    }

    /// Full-pose aiding: heading with inverse-variance weights, then
    /// translation, 3 rounds.
    pub fn full_pose() -> Self {
        AidingConfig {
            mode: AidingMode::FullPose,
            heading_weights: HeadingWeights::InverseVariance { floor_rad: 0.1f64.to_radians() },
            iterations: 3,
            robust_scale_m: 0.05,
            min_information_ratio: 0.05,
            offset_floor_m: 0.01,
            max_heading_step_rad: 15f64.to_radians(),
            max_translation_step_m: 0.5,
        }
    }

    /// No aiding (the map is still built).
    pub fn none() -> Self {
        AidingConfig { mode: AidingMode::None, ..Self::full_pose() }
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<(), ConfigError> {
        for (field, v) in [
            ("aiding.robust_scale_m", self.robust_scale_m),
            ("aiding.offset_floor_m", self.offset_floor_m),
            ("aiding.max_heading_step", self.max_heading_step_rad),
            ("aiding.max_translation_step_m", self.max_translation_step_m),
        ] {
            ConfigError::check(v > 0.0 && v.is_finite(), field, v, "must be finite and > 0")?;
        }
        if let HeadingWeights::InverseVariance { floor_rad } = self.heading_weights {
            ConfigError::check(
                floor_rad > 0.0 && floor_rad.is_finite(),
                "aiding.heading_weights.floor",
                floor_rad,
                "must be finite and > 0",
            )?;
        }
        ConfigError::check(
            (0.0..=1.0).contains(&self.min_information_ratio),
            "aiding.min_information_ratio",
            self.min_information_ratio,
            "must be in [0, 1]",
        )
    }
}

/// Why a step kept the uncorrected estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fallback {
    /// No new line matched the map.
    NoMatches,
    /// The source pose or increment was not finite; the last corrected pose was kept.
    NonFiniteSource,
    /// The correction was not finite; the prediction was kept.
    NonFiniteCorrection,
}

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Matches used (in the last round).
    pub matches: usize,
    /// Total heading correction applied, radians.
    pub heading_correction_rad: f64,
    /// Total translation correction applied, metres.
    pub translation_correction_m: Vector2<f64>,
    /// Directions the translation was corrected along (0, 1 or 2).
    pub constrained_directions: usize,
    /// Why the correction fell back, if it did.
    pub fallback: Option<Fallback>,
}
