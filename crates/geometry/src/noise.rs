//! The range-noise model: standard deviation of a range return as a function of range.

use crate::ConfigError;

/// Standard deviation of the range noise of a LIDAR, piecewise constant in range.
///
/// The Hokuyo UTM-30LX-EW datasheet gives a repeatability of 10 mm below 10 m and
/// 30 mm beyond ([`RangeNoise::utm30lx`]); the paper's simulations use 4 cm
/// everywhere ([`RangeNoise::constant`]). Noise-aware thresholds and the line
/// covariance use this model.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct RangeNoise {
    /// Sigma in metres for ranges below `far_from_m`.
    pub near_sigma_m: f64,
    /// Sigma in metres for ranges at or beyond `far_from_m`.
    pub far_sigma_m: f64,
    /// The range in metres where the far sigma starts; infinite when it
    /// never does (JSON, which has no infinity, writes it `null`, and
    /// `null` reads back as infinite).
    #[cfg_attr(feature = "serde", serde(deserialize_with = "infinite_when_null"))]
    pub far_from_m: f64,
}

/// A number, or `null` for an infinite one (serde_json writes non-finite
/// numbers as `null`).
#[cfg(feature = "serde")]
fn infinite_when_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    use serde::Deserialize;
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

impl RangeNoise {
    /// The UTM-30LX-EW datasheet: 10 mm below 10 m, 30 mm beyond.
    pub const fn utm30lx() -> Self {
        RangeNoise { near_sigma_m: 0.01, far_sigma_m: 0.03, far_from_m: 10.0 }
    }

    /// The same sigma at every range.
    pub const fn constant(sigma_m: f64) -> Self {
        RangeNoise { near_sigma_m: sigma_m, far_sigma_m: sigma_m, far_from_m: f64::INFINITY }
    }

    /// Sigma in metres at `range_m`.
    #[inline]
    pub fn sigma_at(&self, range_m: f64) -> f64 {
        if range_m < self.far_from_m { self.near_sigma_m } else { self.far_sigma_m }
    }

    /// Checks that both sigmas are finite and non-negative and the far
    /// range is not negative; errors name `prefix.near_sigma_m` and so on.
    pub fn validate(&self, prefix: &str) -> Result<(), ConfigError> {
        for (name, s) in [("near_sigma_m", self.near_sigma_m), ("far_sigma_m", self.far_sigma_m)] {
            ConfigError::check_field(
                s >= 0.0 && s.is_finite(),
                prefix,
                name,
                s,
                "must be finite and >= 0",
            )?;
        }
        let far = self.far_from_m;
        ConfigError::check_field(far >= 0.0, prefix, "far_from_m", far, "must be >= 0")
    }
}

impl Default for RangeNoise {
    fn default() -> Self {
        RangeNoise::utm30lx()
    }
}
