//! [`Config`]: the whole detector's configuration, with named presets.

use pcaline_fitting::{EdgeOnEnds, FitConfig};
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
    /// Fitting tests added on a scan whose estimated noise is above the
    /// nominal ([`NoisyScanTests`]); `None`, or a configuration that does
    /// not estimate the noise: every scan gets `fitting` as it is.
    #[cfg_attr(feature = "serde", serde(default))]
    pub noisy_scan_tests: Option<NoisyScanTests>,
}

/// Fitting tests that run only on the scans whose estimated range noise is
/// above the nominal ([`Config::noisy_scan_tests`]), in addition to
/// [`Config::fitting`]'s own. Beyond the paper.
///
/// A scan is noisy when the estimate ([`Config::noise_estimation`]) raised
/// the sigma of either range band above the nominal's
/// ([`Config::nominal_noise`]). The estimate keeps the nominal wherever the
/// scan is consistent with it (up to
/// [`NoiseEstimation::consistent_scale`] times it, and a range grid whose
/// share stays within that), so a scan at the datasheet's noise is not
/// noisy, and is detected exactly as by [`Config::datasheet`] unless its far
/// returns are clearly quieter than the datasheet's far figure
/// ([`pcaline_segmentation::FarBandFloor`]). Thresholds
/// that follow a raised noise let more through: at 30 mm on a 10 mm sensor
/// the first 5-10 returns of a surface seen edge-on stay inside every
/// split threshold and tilt a short wall's line. A test that refuses
/// what those looser thresholds let in runs on the scans where they were
/// loosened; where they were not, it would only change lines that the
/// nominal thresholds already hold (on MIT CSAIL's log, the edge-on cut on
/// every scan moves the log's own good poses from 0.092 to 0.104 m,
/// docs/accuracy.md).
///
/// ```
/// use pcaline::{Config, NoisyScanTests};
/// let tests = Config::default().noisy_scan_tests.unwrap();
/// assert_eq!(tests, NoisyScanTests::standard());
/// assert!(tests.edge_on_ends.is_some());
/// assert_eq!(Config::datasheet(pcaline::geometry::SensorProfile::Utm30lxEw).noisy_scan_tests, None);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct NoisyScanTests {
    /// The edge-on cut ([`EdgeOnEnds`], [`pcaline_fitting::edge_on_ends`])
    /// on noisy scans, unless [`Config::fitting`] already has one (which
    /// runs on every scan); `None`: not added.
    #[cfg_attr(feature = "serde", serde(default))]
    pub edge_on_ends: Option<EdgeOnEnds>,
}

impl NoisyScanTests {
    /// The edge-on cut ([`EdgeOnEnds::standard`]): on three generated mazes
    /// at 30 mm it takes the default's false positives from 9.7% to 5.4%,
    /// and recall from 0.803 to 0.838 (docs/accuracy.md).
    pub const fn standard() -> Self {
        NoisyScanTests { edge_on_ends: Some(EdgeOnEnds::standard()) }
    }

    /// `fitting` with these tests added where it has none of its own.
    pub fn added_to(&self, mut fitting: FitConfig) -> FitConfig {
        fitting.edge_on_ends = fitting.edge_on_ends.or(self.edge_on_ends);
        fitting
    }

    /// Checks every value; errors name `noisy_scan_tests.edge_on_ends.min_points`
    /// and so on.
    pub fn validate(&self) -> Result<(), ConfigError> {
        match self.edge_on_ends {
            Some(t) => t.validate("noisy_scan_tests.edge_on_ends"),
            None => Ok(()),
        }
    }
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
            noisy_scan_tests: None,
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
            noisy_scan_tests: None,
        }
    }

    /// The default detector for `sensor`: the noise-aware rules on its
    /// datasheet noise ([`SensorProfile::range_noise`]) as the nominal,
    /// estimated from each scan ([`NoiseEstimation::standard`]), with the
    /// edge-on cut on the scans whose estimate is raised above it
    /// ([`NoisyScanTests::standard`]).
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
        Config {
            noisy_scan_tests: Some(NoisyScanTests::standard()),
            ..Config::datasheet(sensor).with_noise_estimation(NoiseEstimation::standard())
        }
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
    /// ([`pcaline_fitting::EdgeOnEnds::standard`]) on every scan, not only
    /// on the noisy ones as the default does. On scans at the nominal noise
    /// the three tests change the lines real logs map enough to move MIT
    /// CSAIL's and Intel's own good poses more than 0.10 m; on noisy
    /// scans they add little to the default's cut (generated mazes at 30
    /// mm: 5.3% false positives, the default 5.4%; docs/accuracy.md). The
    /// straightness test refuses the chords of a curved wall at the
    /// nominal noise, which the default keeps.
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
            noisy_scan_tests: None,
        }
    }

    /// Checks every value; an invalid one is a [`ConfigError`] naming the field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.segmentation.validate()?;
        if let Some(e) = self.noise_estimation {
            e.validate()?;
        }
        if let Some(t) = self.noisy_scan_tests {
            t.validate()?;
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
    /// ([`Config::datasheet`]), except that far returns clearly quieter
    /// than the datasheet's far figure set the far band, down to the near
    /// figure ([`pcaline_segmentation::FarBandFloor`]); on a noisier scan it also cuts off line
    /// ends on a surface seen edge-on ([`NoisyScanTests`]). It differs from the paper where the paper's
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
