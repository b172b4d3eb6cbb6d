//! [`SensorModel`]: the simulated LIDAR's geometry, timing, noise and faults.

use pcaline_geometry::{ConfigError, RangeNoise, SensorProfile};
use std::f64::consts::PI;

/// Fault probabilities, per beam.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Faults {
    /// A return displaced by up to ±`outlier_max_m`, or replaced by clutter
    /// between the sensor and the wall (half of the outliers each).
    pub outlier_probability: f64,
    /// Largest displacement of a displaced outlier, metres.
    pub outlier_max_m: f64,
    /// No return at all (reported as +inf).
    pub dropout_probability: f64,
    /// At a depth edge (a neighbour's true range differs by more than
    /// `mixed_edge_m`), a range between foreground and background.
    pub mixed_pixel_probability: f64,
    /// Smallest range difference between neighbours that makes a depth edge.
    pub mixed_edge_m: f64,
}

/// A tilting scan plane: a hand-held or flying sensor rolls and pitches.
/// Roll is `roll_amplitude sin(2 pi t / period)`, pitch
/// `pitch_amplitude cos(2 pi t / period)`. Walls are vertical, so a tilted
/// beam measures a longer range along a slightly different bearing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tilt {
    /// Roll amplitude, radians.
    pub roll_amplitude_rad: f64,
    /// Pitch amplitude, radians.
    pub pitch_amplitude_rad: f64,
    /// Period of the sway, seconds.
    pub period_s: f64,
}

/// A simulated 2D LIDAR.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorModel {
    /// Number of beams per scan.
    pub beams: usize,
    /// Bearing of the first beam, radians.
    pub angle_min_rad: f64,
    /// Angle between beams, radians.
    pub angle_increment_rad: f64,
    /// Smallest valid range, metres.
    pub range_min_m: f64,
    /// Largest range, metres: nothing beyond is returned.
    pub range_max_m: f64,
    /// Scans per second.
    pub rate_hz: f64,
    /// Range noise (Gaussian).
    pub noise: RangeNoise,
    /// Range resolution, metres: every published range is rounded to a
    /// multiple of it after the noise, as sensors that report centimetres
    /// (or 5 cm steps) do. 0: ranges are not rounded.
    pub range_resolution_m: f64,
    /// Fault probabilities.
    pub faults: Faults,
    /// Each beam is taken at its own time within the scan (the mirror turns
    /// once per scan period), so a moving sensor skews the scan.
    pub motion_skew: bool,
    /// Optional sway of the scan plane.
    pub tilt: Option<Tilt>,
}

impl SensorModel {
    /// Hokuyo UTM-30LX-EW: 1081 beams from -135° to +135° in 0.25°, 0.1-30 m,
    /// 40 Hz, range noise 10 mm below 10 m and 30 mm beyond (datasheet), no faults.
    pub fn utm30lx_ew() -> Self {
        SensorModel {
            beams: 1081,
            angle_min_rad: -135.0 * PI / 180.0,
            angle_increment_rad: 0.25 * PI / 180.0,
            range_min_m: 0.1,
            range_max_m: 30.0,
            rate_hz: 40.0,
            noise: RangeNoise::utm30lx(),
            range_resolution_m: 0.0,
            faults: Faults { outlier_max_m: 1.0, mixed_edge_m: 0.3, ..Faults::default() },
            motion_skew: false,
            tilt: None,
        }
    }

    /// A SICK LMS-style scanner: 180 beams of 1° from -90°, 0.1-80 m, 75 Hz,
    /// 1 cm noise (the Intel dataset's geometry).
    pub fn sick_lms_180() -> Self {
        SensorModel {
            beams: 180,
            angle_min_rad: -PI / 2.0,
            angle_increment_rad: PI / 180.0,
            range_min_m: 0.1,
            range_max_m: 80.0,
            rate_hz: 75.0,
            noise: RangeNoise::constant(0.01),
            ..Self::utm30lx_ew()
        }
    }

    /// A Hokuyo URG-04LX: 683 beams of 360°/1024 from -120°, 0.02-5.6 m,
    /// 10 Hz, the datasheet's noise ([`SensorProfile::Urg04lx`]: 10 mm below
    /// 2 m, 20 mm beyond), ranges in millimetres.
    pub fn urg_04lx() -> Self {
        SensorModel {
            beams: 683,
            angle_min_rad: -120.0 * PI / 180.0,
            angle_increment_rad: 2.0 * PI / 1024.0,
            range_min_m: 0.02,
            range_max_m: 5.6,
            rate_hz: 10.0,
            noise: SensorProfile::Urg04lx.range_noise(),
            range_resolution_m: SensorProfile::Urg04lx.range_resolution_m(),
            ..Self::utm30lx_ew()
        }
    }

    /// A low-cost 360° scanner (RPLIDAR A2 class): 400 beams of 0.9° all
    /// round from -180°, 0.15-12 m, 10 Hz, the class's noise
    /// ([`SensorProfile::Rplidar`]: 15 mm below 3 m, 50 mm beyond).
    pub fn rplidar() -> Self {
        SensorModel {
            beams: 400,
            angle_min_rad: -PI,
            angle_increment_rad: 2.0 * PI / 400.0,
            range_min_m: 0.15,
            range_max_m: 12.0,
            rate_hz: 10.0,
            noise: SensorProfile::Rplidar.range_noise(),
            range_resolution_m: SensorProfile::Rplidar.range_resolution_m(),
            ..Self::utm30lx_ew()
        }
    }

    /// The UTM-30LX-EW geometry with the paper's simulated noise, 4 cm everywhere.
    pub fn paper_simulation() -> Self {
        SensorModel { noise: RangeNoise::constant(0.04), ..Self::utm30lx_ew() }
    }

    /// Time between two beams, seconds: the mirror turns once per scan period.
    pub fn beam_period_s(&self) -> f64 {
        self.angle_increment_rad.abs() / (2.0 * PI) / self.rate_hz
    }

    /// Checks every value.
    pub fn validate(&self) -> Result<(), ConfigError> {
        ConfigError::check(self.beams >= 1, "sensor.beams", self.beams as f64, "must be >= 1")?;
        ConfigError::check(
            self.angle_increment_rad.is_finite() && self.angle_increment_rad != 0.0,
            "sensor.angle_increment_rad",
            self.angle_increment_rad,
            "must be finite and non-zero",
        )?;
        ConfigError::check(
            self.angle_min_rad.is_finite(),
            "sensor.angle_min_rad",
            self.angle_min_rad,
            "must be finite",
        )?;
        ConfigError::check(
            self.range_min_m >= 0.0 && self.range_min_m < self.range_max_m,
            "sensor.range_min_m",
            self.range_min_m,
            "must be >= 0 and below range_max_m",
        )?;
        ConfigError::check(
            self.range_max_m.is_finite(),
            "sensor.range_max_m",
            self.range_max_m,
            "must be finite",
        )?;
        ConfigError::positive("sensor.rate_hz", self.rate_hz)?;
        self.noise.validate("sensor.noise")?;
        ConfigError::check(
            self.range_resolution_m >= 0.0 && self.range_resolution_m <= 1.0,
            "sensor.range_resolution_m",
            self.range_resolution_m,
            "must be in [0, 1]",
        )?;
        for (field, p) in [
            ("sensor.outlier_probability", self.faults.outlier_probability),
            ("sensor.dropout_probability", self.faults.dropout_probability),
            ("sensor.mixed_pixel_probability", self.faults.mixed_pixel_probability),
        ] {
            ConfigError::unit_interval(field, p)?;
        }
        ConfigError::non_negative("sensor.outlier_max_m", self.faults.outlier_max_m)?;
        if let Some(t) = self.tilt {
            ConfigError::positive("sensor.tilt.period_s", t.period_s)?;
            for (field, a) in [
                ("sensor.tilt.roll_amplitude_rad", t.roll_amplitude_rad),
                ("sensor.tilt.pitch_amplitude_rad", t.pitch_amplitude_rad),
            ] {
                ConfigError::check(a.abs() < 1.2, field, a, "must be below 1.2 rad")?;
            }
        }
        Ok(())
    }
}

impl Default for SensorModel {
    fn default() -> Self {
        Self::utm30lx_ew()
    }
}
