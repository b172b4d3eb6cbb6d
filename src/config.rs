//! [`Config`]: the whole detector's configuration, with named presets.

use pcaline_fitting::FitConfig;
use pcaline_geometry::{ConfigError, RangeNoise, SensorProfile};
use pcaline_segmentation::{NoiseEstimation, SegmentationConfig};

/// Configuration of [`crate::LineDetector`]: segmentation and fitting.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct Config {
    /// Level-1 and level-2 clustering.
    pub segmentation: SegmentationConfig,
    /// PCA fit, elongation test and merge.
    pub fitting: FitConfig,
    /// Estimate the range noise from each scan and use it, instead of the
    /// noise the rules were built with, in every noise-aware threshold
    /// ([`pcaline_segmentation::estimate_range_noise`]). `None`: the rules'
    /// own noise (the paper's rules have none).
    #[cfg_attr(feature = "serde", serde(default))]
    pub noise_estimation: Option<NoiseEstimation>,
}

impl Config {
    /// Exactly the paper's detector: `DTh` 0.15 m, clusters under 5 points
    /// dropped, signed derivative peaks (eq. 2a/2b), `ETh` 50, merge by eq. 7
    /// with `alpha_T` 0.05°.
    pub fn paper() -> Self {
        Config {
            segmentation: SegmentationConfig::paper(),
            fitting: FitConfig::paper(),
            noise_estimation: None,
        }
    }

    /// The noise-aware detector told that the sensor's range noise is
    /// `noise`: adaptive level-1 threshold (with grazing walls kept whole),
    /// recursive split at 4 sigma instead of derivative peaks, a merge that
    /// tests the residual increase of one line through both pieces against
    /// the noise instead of a fixed 0.05° angle, a residual test, and only
    /// lines whose orientation the noise determines to 2°
    /// ([`FitConfig::noise_aware`]).
    pub fn noise_aware(noise: RangeNoise) -> Self {
        Config {
            segmentation: SegmentationConfig::noise_aware(noise),
            fitting: FitConfig::noise_aware(noise),
            noise_estimation: None,
        }
    }

    /// The default detector for `sensor`: the noise-aware rules on its
    /// datasheet noise ([`SensorProfile::range_noise`]) as the nominal,
    /// estimated from each scan ([`NoiseEstimation::standard`]).
    /// `Config::for_sensor(SensorProfile::Utm30lxEw)` is `Config::default()`.
    ///
    /// ```
    /// use pcaline::{Config, geometry::SensorProfile};
    /// assert_eq!(Config::for_sensor(SensorProfile::Utm30lxEw), Config::default());
    /// let sick = Config::for_sensor(SensorProfile::SickLms);
    /// assert_eq!(sick.nominal_noise(), Some(SensorProfile::SickLms.range_noise()));
    /// assert!(sick.noise_estimation.is_some());
    /// ```
    pub fn for_sensor(sensor: SensorProfile) -> Self {
        Config::datasheet(sensor).with_noise_estimation(NoiseEstimation::standard())
    }

    /// The noise-aware rules on `sensor`'s datasheet noise, not estimated
    /// from the scans: the default detector before 2026-12-05. Where the
    /// actual noise is the datasheet's it finds the same lines as
    /// [`Config::for_sensor`]; at three times it (30 mm on a 10 mm
    /// sensor) it shreds walls (docs/accuracy.md).
    pub fn datasheet(sensor: SensorProfile) -> Self {
        Config::noise_aware(sensor.range_noise())
    }

    /// The detector that adapts further to the scene: the default
    /// (estimating the range noise and range grid from each scan,
    /// [`NoiseEstimation::standard`]), refusing lines over curved
    /// surfaces ([`pcaline_fitting::StraightnessTest::standard`]), and
    /// cutting lines whose points two lines fit far better, such as a wall
    /// and its end face ([`pcaline_fitting::KinkTest::standard`]), and
    /// cutting off the ends of a line that lie on a surface seen edge-on
    /// ([`pcaline_fitting::EdgeOnEnds::standard`]). The three tests take
    /// the false positives of generated mazes at 30 mm from 9.7% to 5%, but
    /// they change the lines real logs map enough to move MIT CSAIL's and
    /// Intel's own good poses more than 0.10 m (docs/accuracy.md).
    pub fn adaptive() -> Self {
        let mut c = Config::default();
        c.fitting.straightness_test = Some(pcaline_fitting::StraightnessTest::standard());
        c.fitting.kink_test = Some(pcaline_fitting::KinkTest::standard());
        c.fitting.edge_on_ends = Some(pcaline_fitting::EdgeOnEnds::standard());
        c
    }

    /// The same configuration, estimating the range noise from each scan
    /// (the rules' noise becomes the nominal the estimate starts from).
    pub fn with_noise_estimation(self, estimation: NoiseEstimation) -> Self {
        Config { noise_estimation: Some(estimation), ..self }
    }

    /// The range noise the rules were built with: that of the first
    /// noise-aware rule (level 1, level 2, merge, residual test, orientation
    /// test); `None` when no rule uses noise (the paper).
    pub fn nominal_noise(&self) -> Option<RangeNoise> {
        self.segmentation.noise().or_else(|| self.fitting.noise())
    }

    /// The same configuration with every noise-aware rule using `noise`.
    pub fn with_noise(self, noise: RangeNoise) -> Self {
        Config {
            segmentation: self.segmentation.with_noise(noise),
            fitting: self.fitting.with_noise(noise),
            ..self
        }
    }

    /// The established split-and-merge extractors, as a baseline: a fixed
    /// 0.15 m break-point distance, a recursive split at a fixed 5 cm from
    /// the chord, `ETh` 50, and a merge of neighbours within 2° (thresholds
    /// in metres and degrees, not following the noise).
    pub fn split_and_merge() -> Self {
        Config {
            segmentation: SegmentationConfig::split_and_merge(),
            fitting: FitConfig::split_and_merge(),
            noise_estimation: None,
        }
    }

    /// Checks every value; an invalid one is a [`ConfigError`] naming the field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.segmentation.validate()?;
        if let Some(e) = self.noise_estimation {
            e.validate()?;
        }
        self.fitting.validate()
    }
}

impl Default for Config {
    /// The noise-aware detector with the UTM-30LX-EW datasheet (10 mm below
    /// 10 m, 30 mm beyond) as its nominal noise, estimated from each scan
    /// ([`NoiseEstimation::standard`]): told nothing, it finds the walls of
    /// a 30 mm sensor as well as the detector told 30 mm, and ranges
    /// rounded to 5 cm do not shred its walls; where the noise is the
    /// nominal's (within 1.5 times it) it is the datasheet detector
    /// ([`Config::datasheet`]). It differs from the paper where the paper's
    /// fixed thresholds fail under noise: the fixed `DTh` over-segments far
    /// walls, derivative peaks of noisy points split walls every few
    /// points, and eq. 7's 0.05° never merges noisy pieces. It does not
    /// refuse bowed lines ([`Config::adaptive`]): those tests change the
    /// lines real logs map enough to move their own good poses more than
    /// 0.10 m (docs/accuracy.md).
    fn default() -> Self {
        Config::for_sensor(SensorProfile::Utm30lxEw)
    }
}
