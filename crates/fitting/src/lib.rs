//! Line fitting for pcaline: the paper's PCA fit (eq. 3, 5, 6) with the
//! eigenvalue-ratio elongation test, the merge of adjacent collinear pieces
//! (eq. 7), and the least-squares baseline (section 3, eq. 16).
//!
//! The entry point is [`fit_lines`] over a [`FitConfig`]: sub-clusters of a
//! segmented scan in, [`DetectedLine`]s out, into reusable [`LineFits`].
//! Everything is pure and allocation-free except [`merge_adjacent`], which
//! edits the caller's vector in place, and the buffers of [`LineFits`],
//! which grow to the largest scan. The geometry ([`ScanPoints`],
//! [`LineSegment`]) is re-exported, so this crate is usable alone.
//!
//! ```
//! use pcaline_fitting::{FitConfig, Moments, elongation_ratio, line_from_moments};
//! use pcaline_geometry::Point2;
//!
//! let pts: Vec<_> = (0..20).map(|i| Point2::new(0.1 * i as f64, 1.0)).collect();
//! let m = Moments::from_points(&pts);
//! let config = FitConfig::paper();
//! assert!(elongation_ratio(&m.eigen()) > config.eth); // a perfect line: r = inf
//! let line = line_from_moments(&m, &pts[0], &pts[19]).unwrap();
//! assert!((line.d() - 1.0).abs() < 1e-12);
//! ```

mod corners;
mod edge_on;
mod eigen;
mod elongation;
mod fit_lines;
mod kink;
mod least_squares;
mod merge;
mod moments;
mod orientation;
mod pca;
mod range_bearing;
mod residual;
mod straightness;

pub use corners::refine_boundaries;
pub use edge_on::{EdgeOnEnds, edge_on_ends};
pub use eigen::SymmetricEigen2;
pub use elongation::{elongation_ratio, is_elongated};
pub use fit_lines::{DetectedLine, LineFits, fit_lines};
pub use kink::{KinkTest, RunSums, best_split};
pub use least_squares::{fit_least_squares, slope_intercept_from_moments, vertical_rms_error};
pub use merge::{MergeRule, Piece, merge_adjacent};
pub use moments::Moments;
pub use orientation::OrientationTest;
pub use pca::{fit_pca, fit_pca_slope_intercept, line_from_eigen, line_from_moments};
pub use pcaline_geometry::{self as geometry, LineSegment, Point2, RangeNoise, ScanPoints};
pub use range_bearing::{fit_weighted, pca_covariance, point_covariance};
pub use residual::ResidualTest;
pub use straightness::{Straightness, StraightnessTest, straightness};

use pcaline_geometry::ConfigError;

/// Configuration of the fitting stage.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct FitConfig {
    /// The eigenvalue-ratio threshold `ETh`: a piece is a line when
    /// `lambda_max / lambda_min > eth` (paper: 50). Must be > 1.
    pub eth: f64,
    /// Fewest points a sub-cluster needs to be fitted. The paper states its
    /// 5-point minimum for level-1 clusters only; for sub-clusters the
    /// `paper` preset uses 3, the fewest for which the eigenvalue ratio means
    /// anything (2 points always have `lambda_min = 0`).
    pub min_points: usize,
    /// When adjacent pieces are merged (paper: eq. 7 with `alpha_T` = 0.05°).
    pub merge: MergeRule,
    /// Points around each level-2 break-point that may move to the
    /// neighbouring piece when they fit its line better
    /// ([`refine_boundaries`]); 0 disables it (paper).
    pub corner_window: usize,
    /// Reject pieces whose residual is inconsistent with the noise
    /// ([`ResidualTest`]); `None` in the paper, whose only test is `ETh`.
    pub residual_test: Option<ResidualTest>,
    /// Final lines with fewer points are not reported (0: all are; paper).
    pub min_line_points: usize,
    /// Final lines shorter than this are not reported, metres (0: all are;
    /// paper). Short lines are mostly real (box faces, recess sides) but
    /// their orientation is barely determined: at 10 mm noise a 10 cm piece
    /// of 5 points points anywhere within several degrees.
    pub min_line_length_m: f64,
    /// Final lines whose orientation the noise leaves too uncertain are not
    /// reported ([`OrientationTest`]); `None` in the paper.
    #[cfg_attr(feature = "serde", serde(default))]
    pub orientation_test: Option<OrientationTest>,
    /// Final lines over a curved surface (a residual above the noise with
    /// residual signs in long runs) are not reported ([`StraightnessTest`]);
    /// `None`: every line is reported with its [`Straightness`].
    #[cfg_attr(feature = "serde", serde(default))]
    pub straightness_test: Option<StraightnessTest>,
    /// Lines whose points two lines fit significantly better than one (a
    /// wall and its end face, a corner the split missed) are cut in two
    /// ([`KinkTest`], [`best_split`]); `None`: no such cut (paper).
    #[cfg_attr(feature = "serde", serde(default))]
    pub kink_test: Option<KinkTest>,
    /// A line's end runs that lie on another surface seen edge-on (the end
    /// face of a wall beside a wall seen head-on) are cut off
    /// ([`EdgeOnEnds`], [`edge_on_ends`]); `None`: no such cut (paper).
    #[cfg_attr(feature = "serde", serde(default))]
    pub edge_on_ends: Option<EdgeOnEnds>,
}

impl FitConfig {
    /// The fitting of the established split-and-merge extractors, as a
    /// baseline: `ETh` 50, sub-clusters of 5 points or more, neighbours
    /// merged within 2°, and no further test.
    pub fn split_and_merge() -> Self {
        FitConfig {
            min_points: 5,
            merge: MergeRule::Angles { alpha_t_rad: 2f64.to_radians() },
            ..FitConfig::paper()
        }
    }

    /// Exactly the paper's values: `ETh` 50, eq. 7 with `alpha_T` 0.05°, and
    /// sub-clusters of 3 points or more fitted.
    pub fn paper() -> Self {
        FitConfig {
            eth: 50.0,
            min_points: 3,
            merge: MergeRule::Angles { alpha_t_rad: 0.05f64.to_radians() },
            corner_window: 0,
            residual_test: None,
            min_line_points: 0,
            min_line_length_m: 0.0,
            orientation_test: None,
            straightness_test: None,
            kink_test: None,
            edge_on_ends: None,
        }
    }

    /// The noise-aware variant: a merge that accepts two pieces when one line
    /// through both is consistent with the sensor noise (residual increase
    /// below the 99.9% point of `chi²(2)`) instead of a 0.05° angle, which
    /// noise alone exceeds on short pieces; corner points assigned to the
    /// line they fit (window of 3 points); pieces whose residual exceeds 3
    /// noise sigmas rejected; only lines of at least 10 points and 0.3 m
    /// reported; and, instead of the paper's `ETh` 50 (kept at 10 as a
    /// sanity check), only lines whose orientation the noise determines to
    /// 2° (one standard deviation, [`OrientationTest`]).
    ///
    /// Measured with `pcaline eval` (docs/accuracy.md): the length and point
    /// minimums cut false positives at 10 mm from 15.7% to 1.2% for 1% of
    /// recall; the orientation test trades recall for false positives at
    /// 30 mm along the frontier a perfect segmentation also obeys.
    pub fn noise_aware(noise: RangeNoise) -> Self {
        FitConfig {
            eth: 10.0,
            min_points: 5,
            merge: MergeRule::ResidualIncrease { max_chi2: 13.8, noise },
            corner_window: 3,
            residual_test: Some(ResidualTest { max_sigmas: 3.0, noise }),
            min_line_points: 10,
            min_line_length_m: 0.3,
            orientation_test: Some(OrientationTest { max_std_rad: 2f64.to_radians(), noise }),
            straightness_test: None,
            kink_test: None,
            edge_on_ends: None,
        }
    }

    /// The range noise of the first rule that uses one (merge, residual
    /// test, orientation test).
    pub fn noise(&self) -> Option<RangeNoise> {
        match self.merge {
            MergeRule::ResidualIncrease { noise, .. } => Some(noise),
            MergeRule::Angles { .. } | MergeRule::Never => {
                self.residual_test.map(|t| t.noise).or(self.orientation_test.map(|t| t.noise))
            }
        }
    }

    /// The same configuration with every noise-aware rule using `noise`.
    pub fn with_noise(mut self, new: RangeNoise) -> Self {
        if let MergeRule::ResidualIncrease { noise, .. } = &mut self.merge {
            *noise = new;
        }
        if let Some(t) = &mut self.residual_test {
            t.noise = new;
        }
        if let Some(t) = &mut self.orientation_test {
            t.noise = new;
        }
        self
    }

    /// Checks every value; an invalid one is a [`ConfigError`].
    pub fn validate(&self) -> Result<(), ConfigError> {
        ConfigError::check(
            self.eth > 1.0 && self.eth.is_finite(),
            "fitting.eth",
            self.eth,
            "must be finite and > 1",
        )?;
        ConfigError::check(
            self.min_points >= 3,
            "fitting.min_points",
            self.min_points as f64,
            "must be >= 3",
        )?;
        match self.merge {
            MergeRule::Angles { alpha_t_rad } => {
                ConfigError::non_negative("fitting.merge.Angles.alpha_t_rad", alpha_t_rad)
            }
            MergeRule::ResidualIncrease { max_chi2, noise } => {
                ConfigError::positive("fitting.merge.ResidualIncrease.max_chi2", max_chi2)?;
                noise.validate("fitting.merge.ResidualIncrease.noise")
            }
            MergeRule::Never => Ok(()),
        }?;
        ConfigError::non_negative("fitting.min_line_length_m", self.min_line_length_m)?;
        if let Some(t) = self.residual_test {
            ConfigError::positive("fitting.residual_test.max_sigmas", t.max_sigmas)?;
            t.noise.validate("fitting.residual_test.noise")?;
        }
        if let Some(t) = self.orientation_test {
            ConfigError::check(
                t.max_std_rad > 0.0 && !t.max_std_rad.is_nan(),
                "fitting.orientation_test.max_std_rad",
                t.max_std_rad,
                "must be > 0",
            )?;
            t.noise.validate("fitting.orientation_test.noise")?;
        }
        if let Some(t) = self.kink_test {
            ConfigError::positive("fitting.kink_test.min_chi2", t.min_chi2)?;
        }
        if let Some(t) = self.edge_on_ends {
            t.validate("fitting.edge_on_ends")?;
        }
        if let Some(t) = self.straightness_test {
            ConfigError::non_negative(
                "fitting.straightness_test.max_bow_sigmas",
                t.max_bow_sigmas,
            )?;
            ConfigError::check(
                t.max_runs_z.is_finite(),
                "fitting.straightness_test.max_runs_z",
                t.max_runs_z,
                "must be finite",
            )?;
        }
        Ok(())
    }
}

impl Default for FitConfig {
    fn default() -> Self {
        FitConfig::noise_aware(RangeNoise::utm30lx())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_configs_are_errors() {
        let mut c = FitConfig::paper();
        assert!(c.validate().is_ok());
        c.eth = 1.0;
        assert!(c.validate().is_err());
        c.eth = f64::NAN;
        assert!(c.validate().is_err());
        let mut c = FitConfig::paper();
        c.merge = MergeRule::Angles { alpha_t_rad: -1.0 };
        assert!(c.validate().is_err());
        let mut c =
            FitConfig { edge_on_ends: Some(EdgeOnEnds::standard()), ..FitConfig::default() };
        assert!(c.validate().is_ok());
        c.edge_on_ends = Some(EdgeOnEnds::new(2, 3.0, 4.0));
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("fitting.edge_on_ends.min_points"), "{e}");
        c.edge_on_ends = Some(EdgeOnEnds::new(5, f64::NAN, 4.0));
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains("fitting.edge_on_ends.min_stall_z"), "{e}");
    }
}
