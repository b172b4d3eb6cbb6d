//! [`Config`]: the whole detector's configuration, with named presets.

use pcaline_fitting::FitConfig;
use pcaline_geometry::{ConfigError, RangeNoise};
use pcaline_segmentation::SegmentationConfig;

/// Configuration of [`crate::LineDetector`]: segmentation and fitting.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Config {
    /// Level-1 and level-2 clustering.
    pub segmentation: SegmentationConfig,
    /// PCA fit, elongation test and merge.
    pub fitting: FitConfig,
}

impl Config {
    /// Exactly the paper's detector: `DTh` 0.15 m, clusters under 5 points
    /// dropped, signed derivative peaks (eq. 2a/2b), `ETh` 50, merge by eq. 7
    /// with `alpha_T` 0.05°.
    pub fn paper() -> Self {
        Config { segmentation: SegmentationConfig::paper(), fitting: FitConfig::paper() }
    }

    /// The noise-aware detector for a sensor with range noise `noise`: adaptive
    /// level-1 threshold, recursive split at 4 sigma instead of derivative
    /// peaks, `ETh` 50, and a merge that tests the residual increase of one
    /// line through both pieces against the noise instead of a fixed 0.05° angle.
    pub fn noise_aware(noise: RangeNoise) -> Self {
        Config {
            segmentation: SegmentationConfig::noise_aware(noise),
            fitting: FitConfig::noise_aware(noise),
        }
    }

    /// The established split-and-merge extractors, as a baseline: a fixed
    /// 0.15 m break-point distance, a recursive split at a fixed 5 cm from
    /// the chord, `ETh` 50, and a merge of neighbours within 2° (thresholds
    /// in metres and degrees, not following the noise).
    pub fn split_and_merge() -> Self {
        use pcaline_fitting::MergeRule;
        use pcaline_segmentation::{BreakRule, Level2Rule};
        Config {
            segmentation: SegmentationConfig {
                level1: BreakRule::Fixed { dth_m: 0.15 },
                min_cluster_points: 5,
                level2: Level2Rule::SplitAtFarthest {
                    sigma_factor: 1.0,
                    min_distance_m: 0.05,
                    noise: RangeNoise::constant(0.0),
                },
            },
            fitting: FitConfig {
                eth: 50.0,
                min_points: 5,
                merge: MergeRule::Angles { alpha_t_rad: 2f64.to_radians() },
                corner_window: 0,
                residual_test: None,
                min_line_points: 0,
                min_line_length_m: 0.0,
                orientation_test: None,
            },
        }
    }

    /// Checks every value; an invalid one is a [`ConfigError`] naming the field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.segmentation.validate()?;
        self.fitting.validate()
    }
}

impl Default for Config {
    /// The noise-aware detector for the UTM-30LX-EW (10 mm below 10 m, 30 mm
    /// beyond). It differs from the paper where the paper's fixed thresholds
    /// fail under noise: the fixed `DTh` over-segments far walls, derivative
    /// peaks of noisy points split walls every few points, and eq. 7's 0.05°
    /// never merges noisy pieces.
    fn default() -> Self {
        Config::noise_aware(RangeNoise::utm30lx())
    }
}
