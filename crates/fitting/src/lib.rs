//! Line fitting for pcaline: the paper's PCA fit (eq. 3, 5, 6) with the
//! eigenvalue-ratio elongation test, the merge of adjacent collinear pieces
//! (eq. 7), and the least-squares baseline (section 3, eq. 16).
//!
//! Everything is pure and allocation-free except [`merge_adjacent`], which
//! edits the caller's vector in place.
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
//! assert!((line.d - 1.0).abs() < 1e-12);
//! ```

mod eigen;
mod elongation;
mod least_squares;
mod merge;
mod moments;
mod pca;

pub use eigen::SymmetricEigen2;
pub use elongation::{elongation_ratio, is_elongated};
pub use least_squares::{fit_least_squares, slope_intercept_from_moments, vertical_rms_error};
pub use merge::{MergeRule, Piece, merge_adjacent};
pub use moments::Moments;
pub use pca::{fit_pca, line_from_eigen, line_from_moments};

use pcaline_geometry::{ConfigError, RangeNoise};

/// Configuration of the fitting stage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitConfig {
    /// The eigenvalue-ratio threshold `ETh`: a piece is a line when
    /// `lambda_max / lambda_min > eth` (paper: 50). Must be > 1.
    pub eth: f64,
    /// Fewest points a piece needs to be fitted (paper: 5, the smallest cluster
    /// it keeps).
    pub min_points: usize,
    /// When adjacent pieces are merged (paper: eq. 7 with `alpha_T` = 0.05°).
    pub merge: MergeRule,
}

impl FitConfig {
    /// Exactly the paper's values: `ETh` 50, 5 points, eq. 7 with `alpha_T` 0.05°.
    pub fn paper() -> Self {
        FitConfig {
            eth: 50.0,
            min_points: 5,
            merge: MergeRule::Angles {
                alpha_t_rad: 0.05f64.to_radians(),
            },
        }
    }

    /// The noise-aware variant: the same elongation test, and a merge that
    /// accepts two pieces when their joint residual is consistent with the
    /// sensor noise (within 2.5 sigma) instead of a 0.05° angle, which noise
    /// alone exceeds on short pieces.
    pub fn noise_aware(noise: RangeNoise) -> Self {
        FitConfig {
            eth: 50.0,
            min_points: 5,
            merge: MergeRule::Residual {
                max_sigma_ratio: 2.5,
                noise,
            },
        }
    }

    /// Checks every value; an invalid one is a [`ConfigError`].
    pub fn validate(&self) -> Result<(), ConfigError> {
        ConfigError::check(self.eth > 1.0, "fitting.eth", self.eth, "must be > 1")?;
        ConfigError::check(
            self.min_points >= 2,
            "fitting.min_points",
            self.min_points as f64,
            "must be >= 2",
        )?;
        match self.merge {
            MergeRule::Angles { alpha_t_rad } => ConfigError::check(
                alpha_t_rad >= 0.0 && alpha_t_rad.is_finite(),
                "fitting.merge.alpha_t",
                alpha_t_rad,
                "must be finite and >= 0",
            ),
            MergeRule::Residual {
                max_sigma_ratio,
                noise,
            } => {
                ConfigError::check(
                    max_sigma_ratio > 0.0 && max_sigma_ratio.is_finite(),
                    "fitting.merge.max_sigma_ratio",
                    max_sigma_ratio,
                    "must be finite and > 0",
                )?;
                noise.validate("fitting.merge.noise")
            }
            MergeRule::Never => Ok(()),
        }
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
    }
}
