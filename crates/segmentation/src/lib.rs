//! Segmentation of 2D LIDAR scans for pcaline: the paper's two-level
//! clusterization (section 2) and noise-aware variants.
//!
//! - Level 1 ([`level1_clusters`]): break-points where consecutive valid points
//!   are farther apart than a threshold: the paper's fixed `DTh`, or an adaptive
//!   threshold that follows range, beam spacing and noise ([`BreakRule`]).
//! - Level 2 ([`Level2Rule`]): the paper's derivative peaks (eq. 2a/2b,
//!   [`derivative_peak_split`]), or the noise-aware recursive split
//!   ([`split_at_farthest`]), which is also the split-and-merge baseline.
//! - Closed 360° scans: [`seam_start`] finds where to start reading the ring so
//!   that no wall is cut at the ±180° seam.
//! - All of it in one call: [`segment`] over a [`SegmentationConfig`], into
//!   reusable [`Segments`]. The geometry it works on ([`Scan`],
//!   [`ScanPoints`], [`BearingTable`]) is re-exported, so this crate is
//!   usable alone.
//!
//! ```
//! use pcaline_geometry::{BearingTable, Scan, ScanPoints};
//! use pcaline_segmentation::{BreakRule, level1_clusters};
//!
//! // Two walls at different depths: 8 beams at 2 m, 8 beams at 3 m.
//! let mut ranges = vec![2.0f32; 8];
//! ranges.extend([3.0f32; 8]);
//! let scan = Scan::new(0.0, 0.25f32.to_radians(), 0.1, 30.0, ranges);
//! let mut points = ScanPoints::default();
//! points.fill_from(&scan, &mut BearingTable::default());
//! let (mut breaks, mut clusters) = (Vec::new(), Vec::new());
//! level1_clusters(&points, &BreakRule::paper(), 5, &mut breaks, &mut clusters);
//! assert_eq!(clusters, vec![0..8, 8..16]);
//! ```

mod level1;
mod level2;
mod noise_estimate;
mod segment;
mod split;

pub use level1::{continues_line, is_break, level1_clusters, seam_start};
pub use level2::{DerivativeSign, derivative_peak_split};
pub use noise_estimate::{
    FarBandFloor, NoiseEstimate, NoiseEstimation, NoiseScratch, RangeGrid, detect_range_step,
    estimate_range_noise,
};
pub use pcaline_geometry::{self as geometry, BearingTable, RangeNoise, Scan, ScanPoints};
pub use segment::{Segments, segment};
pub use split::split_at_farthest;

use pcaline_geometry::ConfigError;

/// The level-1 break-point threshold between consecutive points.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum BreakRule {
    /// The paper's fixed threshold `DTh` in metres (0.15 m for the UTM-30LX-EW:
    /// the largest spacing at 30 m and 0.25° is 13.1 cm).
    Fixed {
        /// The threshold `DTh` in metres.
        dth_m: f64,
    },
    /// The adaptive break-point detector of Borges and Aldon: the largest
    /// spacing of two points on a wall seen at incidence `lambda` or steeper,
    /// `r sin(dtheta) / sin(lambda - dtheta)`, plus `sigma_factor` range sigmas.
    /// It follows range and beam spacing: a fixed threshold over-segments far
    /// walls and under-segments near ones. `r` is the nearer range; a gap of
    /// invalid beams enlarges `dtheta`, and a gap wider than `lambda / 2`
    /// always breaks the cluster (bridging it would draw lines across
    /// windows, doorways seen edge-on and dropouts).
    Adaptive {
        /// The shallowest incidence angle of a wall still kept whole, radians.
        lambda_rad: f64,
        /// Multiple of the range sigma added to the threshold.
        sigma_factor: f64,
        /// The sensor's range noise.
        noise: RangeNoise,
        /// Keep a wall seen at grazing incidence (shallower than `lambda`)
        /// whole: a point farther than the threshold still joins the cluster
        /// when it continues the line of the two points before it, within
        /// `sigma_factor` of the noise across that line, and with a spacing
        /// that grows smoothly ([`continues_line`]). Without it a corridor
        /// wall seen far ahead breaks into single points.
        #[cfg_attr(feature = "serde", serde(default))]
        grazing: bool,
    },
}

impl BreakRule {
    /// The paper's `DTh` = 0.15 m.
    pub const fn paper() -> Self {
        BreakRule::Fixed { dth_m: 0.15 }
    }

    /// The adaptive rule for a sensor with range noise `noise`: incidence
    /// down to 10°, 3 sigma, grazing walls followed.
    pub const fn adaptive(noise: RangeNoise) -> Self {
        BreakRule::Adaptive {
            lambda_rad: 10.0 * std::f64::consts::PI / 180.0,
            sigma_factor: 3.0,
            noise,
            grazing: true,
        }
    }

    /// [`BreakRule::adaptive`] for a UTM-30LX-EW's datasheet noise.
    pub const fn adaptive_utm30lx() -> Self {
        Self::adaptive(RangeNoise::utm30lx())
    }

    /// The threshold in metres between points at ranges `r_i` and `r_j`
    /// separated by `delta_angle_rad`.
    #[inline]
    pub fn threshold_m(&self, r_i: f64, r_j: f64, delta_angle_rad: f64) -> f64 {
        self.threshold_with_factor(r_i, r_j, self.angular_factor(delta_angle_rad))
    }

    /// The angular part of the adaptive threshold,
    /// `sin(dtheta) / sin(lambda - dtheta)` (0 for the fixed rule). It depends
    /// only on the bearing step, so callers cache it across beams.
    #[inline]
    pub fn angular_factor(&self, delta_angle_rad: f64) -> f64 {
        match *self {
            BreakRule::Fixed { .. } => 0.0,
            BreakRule::Adaptive { lambda_rad, .. } => {
                if delta_angle_rad.is_nan() || delta_angle_rad > 0.5 * lambda_rad {
                    return -f64::INFINITY; // a wide gap: always a break
                }
                delta_angle_rad.sin() / (lambda_rad - delta_angle_rad).sin()
            }
        }
    }

    /// The threshold given the cached [`BreakRule::angular_factor`].
    #[inline]
    pub fn threshold_with_factor(&self, r_i: f64, r_j: f64, factor: f64) -> f64 {
        match *self {
            BreakRule::Fixed { dth_m } => dth_m,
            BreakRule::Adaptive { sigma_factor, noise, .. } => {
                if factor == f64::NEG_INFINITY {
                    return 0.0;
                }
                r_i.min(r_j) * factor + sigma_factor * noise.sigma_at(r_i.max(r_j))
            }
        }
    }

    fn validate(&self) -> Result<(), ConfigError> {
        match *self {
            BreakRule::Fixed { dth_m } => {
                ConfigError::positive("segmentation.level1.Fixed.dth_m", dth_m)
            }
            BreakRule::Adaptive { lambda_rad, sigma_factor, noise, .. } => {
                ConfigError::check(
                    lambda_rad > 0.0 && lambda_rad < std::f64::consts::FRAC_PI_2,
                    "segmentation.level1.Adaptive.lambda_rad",
                    lambda_rad,
                    "must be in (0, pi/2)",
                )?;
                ConfigError::non_negative(
                    "segmentation.level1.Adaptive.sigma_factor",
                    sigma_factor,
                )?;
                noise.validate("segmentation.level1.Adaptive.noise")
            }
        }
    }
}

/// How a level-1 cluster is split into sub-clusters (level 2).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Level2Rule {
    /// The paper's derivative peaks (eq. 2a/2b).
    DerivativePeaks {
        /// Signed values as printed, or absolute values.
        sign: DerivativeSign,
    },
    /// Recursive split at the farthest point from the chord while it exceeds
    /// `sigma_factor` range sigmas (and `min_distance_m`).
    SplitAtFarthest {
        /// Multiple of the range sigma a point must exceed to split.
        sigma_factor: f64,
        /// Smallest distance in metres that splits, whatever the noise.
        min_distance_m: f64,
        /// The sensor's range noise.
        noise: RangeNoise,
    },
    /// No level-2 split.
    None,
}

/// Configuration of the segmentation stage.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct SegmentationConfig {
    /// Level-1 break-point rule.
    pub level1: BreakRule,
    /// Level-1 clusters with fewer points are dropped (paper: 5).
    pub min_cluster_points: usize,
    /// Level-2 rule.
    pub level2: Level2Rule,
}

impl SegmentationConfig {
    /// Exactly the paper: `DTh` 0.15 m, clusters under 5 points dropped,
    /// derivative peaks compared with their signs as printed in eq. 2a/2b.
    pub const fn paper() -> Self {
        SegmentationConfig {
            level1: BreakRule::paper(),
            min_cluster_points: 5,
            level2: Level2Rule::DerivativePeaks { sign: DerivativeSign::Signed },
        }
    }

    /// Noise-aware segmentation for a sensor with range noise `noise`: the
    /// adaptive level-1 threshold and the recursive split at 4 sigma.
    pub const fn noise_aware(noise: RangeNoise) -> Self {
        SegmentationConfig {
            level1: BreakRule::adaptive(noise),
            min_cluster_points: 5,
            level2: Level2Rule::SplitAtFarthest { sigma_factor: 4.0, min_distance_m: 0.0, noise },
        }
    }

    /// The segmentation of the established split-and-merge extractors, as a
    /// baseline: a fixed 0.15 m break-point distance, clusters under 5
    /// points dropped, and a recursive split at a fixed 5 cm from the chord
    /// (thresholds in metres, not following the noise).
    pub const fn split_and_merge() -> Self {
        SegmentationConfig {
            level1: BreakRule::Fixed { dth_m: 0.15 },
            min_cluster_points: 5,
            level2: Level2Rule::SplitAtFarthest {
                sigma_factor: 1.0,
                min_distance_m: 0.05,
                noise: RangeNoise::constant(0.0),
            },
        }
    }

    /// The range noise of the first rule that uses one (level 1, then level 2).
    pub fn noise(&self) -> Option<RangeNoise> {
        match (self.level1, self.level2) {
            (BreakRule::Adaptive { noise, .. }, _) => Some(noise),
            (_, Level2Rule::SplitAtFarthest { noise, .. }) => Some(noise),
            _ => None,
        }
    }

    /// The same configuration with every noise-aware rule using `noise`.
    pub fn with_noise(mut self, new: RangeNoise) -> Self {
        if let BreakRule::Adaptive { noise, .. } = &mut self.level1 {
            *noise = new;
        }
        if let Level2Rule::SplitAtFarthest { noise, .. } = &mut self.level2 {
            *noise = new;
        }
        self
    }

    /// Checks every value; an invalid one is a [`ConfigError`].
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.level1.validate()?;
        ConfigError::check(
            self.min_cluster_points >= 2,
            "segmentation.min_cluster_points",
            self.min_cluster_points as f64,
            "must be >= 2",
        )?;
        if let Level2Rule::SplitAtFarthest { sigma_factor, min_distance_m, noise } = self.level2 {
            ConfigError::positive(
                "segmentation.level2.SplitAtFarthest.sigma_factor",
                sigma_factor,
            )?;
            ConfigError::non_negative(
                "segmentation.level2.SplitAtFarthest.min_distance_m",
                min_distance_m,
            )?;
            noise.validate("segmentation.level2.SplitAtFarthest.noise")?;
        }
        Ok(())
    }
}

impl Default for SegmentationConfig {
    fn default() -> Self {
        SegmentationConfig::noise_aware(RangeNoise::utm30lx())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_configs_are_errors() {
        assert!(SegmentationConfig::paper().validate().is_ok());
        assert!(SegmentationConfig::default().validate().is_ok());
        let mut c = SegmentationConfig::paper();
        c.level1 = BreakRule::Fixed { dth_m: -0.1 };
        assert!(c.validate().is_err());
        let mut c = SegmentationConfig::paper();
        c.min_cluster_points = 1;
        assert!(c.validate().is_err());
    }
}
