//! The lifecycle of a map line (beyond the paper): a new line is
//! tentative until it is seen in several scans, a tentative line that is
//! not confirmed in time expires, and a line whose observations disagree
//! with a straight line (the chords of a curved surface) is marked so that
//! aiding does not correct a pose with it.
//!
//! Real logs taught why: a line through three chair legs, seen once, stayed
//! in the paper's map for ever, and a curved wall's chords, which shift as
//! the viewpoint moves, pulled the pose by degrees.

use pcaline_geometry::ConfigError;

/// What a map line may be used for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "kebab-case"))]
#[non_exhaustive]
pub enum LineStatus {
    /// Seen in fewer scans than [`Lifecycle::confirm_scans`]: matched and
    /// refined, but not used to correct a pose; expires if not confirmed.
    Tentative,
    /// Seen in enough scans: used for aiding. Maps without a lifecycle hold
    /// only confirmed lines.
    #[default]
    Confirmed,
    /// Its observations scatter about it by more than their own residuals
    /// allow ([`Lifecycle::max_straightness_ratio`]): a curved surface, or
    /// several surfaces. Kept in the map, not used for aiding.
    NotStraight,
}

/// The lifecycle rules of [`crate::LineMap`] lines.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
#[non_exhaustive]
pub struct Lifecycle {
    /// Distinct scans a line must be seen in to be confirmed.
    pub confirm_scans: u32,
    /// A tentative line not confirmed within this many scans of its first
    /// sighting is removed.
    pub expire_after_scans: u32,
    /// A line is not straight when the rms distance of all its absorbed
    /// points from it exceeds this multiple of its observations' own rms
    /// residual, plus [`Lifecycle::straightness_floor_m`].
    pub max_straightness_ratio: f64,
    /// The allowance for pose errors between observations in the
    /// straightness test, metres.
    pub straightness_floor_m: f64,
    /// Two map lines of one wall (same side, within the merge gate of each
    /// other) are merged into one when either is updated.
    pub merge_duplicates: bool,
}

impl Lifecycle {
    /// Confirmed from 3 scans, expired after 10, not straight beyond 2.5
    /// times the observations' residual plus 1 cm, duplicates merged.
    pub const fn standard() -> Self {
        Lifecycle {
            confirm_scans: 3,
            expire_after_scans: 10,
            max_straightness_ratio: 2.5,
            straightness_floor_m: 0.01,
            merge_duplicates: true,
        }
    }

    /// Checks every value; errors name the field as a configuration file
    /// writes it (`map.lifecycle.*`).
    pub fn validate(&self) -> Result<(), ConfigError> {
        ConfigError::check(
            self.confirm_scans >= 1,
            "map.lifecycle.confirm_scans",
            f64::from(self.confirm_scans),
            "must be >= 1",
        )?;
        ConfigError::check(
            self.expire_after_scans >= self.confirm_scans,
            "map.lifecycle.expire_after_scans",
            f64::from(self.expire_after_scans),
            "must be >= map.lifecycle.confirm_scans",
        )?;
        ConfigError::check(
            self.max_straightness_ratio >= 1.0 && self.max_straightness_ratio.is_finite(),
            "map.lifecycle.max_straightness_ratio",
            self.max_straightness_ratio,
            "must be finite and >= 1",
        )?;
        ConfigError::non_negative("map.lifecycle.straightness_floor_m", self.straightness_floor_m)
    }

    /// The status of a line seen in `scans` distinct scans whose absorbed
    /// points lie `rms_m` from it while its observations' own residuals are
    /// `observed_rms_m`. A line is judged not straight only once confirmed
    /// (before that, too few viewpoints have seen it).
    pub fn status(&self, scans: u32, rms_m: f64, observed_rms_m: f64) -> LineStatus {
        if scans < self.confirm_scans {
            LineStatus::Tentative
        } else if rms_m > self.max_straightness_ratio * observed_rms_m + self.straightness_floor_m {
            LineStatus::NotStraight
        } else {
            LineStatus::Confirmed
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_follows_scans_and_scatter() {
        let l = Lifecycle::standard();
        assert_eq!(l.status(1, 0.005, 0.005), LineStatus::Tentative);
        assert_eq!(l.status(3, 0.005, 0.005), LineStatus::Confirmed);
        // A curved wall: 4 cm about the merged line, 5 mm about each chord.
        assert_eq!(l.status(3, 0.04, 0.005), LineStatus::NotStraight);
        // Not judged before confirmation.
        assert_eq!(l.status(2, 0.04, 0.005), LineStatus::Tentative);
    }

    #[test]
    fn invalid_values_name_their_field() {
        let bad = Lifecycle { expire_after_scans: 1, ..Lifecycle::standard() };
        let e = bad.validate().unwrap_err().to_string();
        assert!(e.contains("map.lifecycle.expire_after_scans"), "{e}");
        let bad = Lifecycle { max_straightness_ratio: f64::NAN, ..Lifecycle::standard() };
        assert!(bad.validate().is_err());
    }
}
