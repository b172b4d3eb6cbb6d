//! The typed error every algorithm crate returns for an invalid configuration.

/// An invalid configuration value, found when a configuration is validated
/// (at construction of a detector, map or aiding filter). Data never produces
/// this error: bad data gives "no result", not an error.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// A value is outside its allowed range.
    #[error("invalid configuration: `{field}` = {value} {requirement}")]
    OutOfRange {
        /// The configuration field, as a dotted path (`fitting.eth`).
        field: std::borrow::Cow<'static, str>,
        /// The offending value.
        value: f64,
        /// What the value must satisfy ("must be > 1").
        requirement: &'static str,
    },
}

impl ConfigError {
    /// Checks `ok` and otherwise builds an [`ConfigError::OutOfRange`].
    pub fn check(
        ok: bool,
        field: &'static str,
        value: f64,
        requirement: &'static str,
    ) -> Result<(), ConfigError> {
        Self::check_path(ok, || field.into(), value, requirement)
    }

    /// As [`ConfigError::check`], for the field `name` of a section whose
    /// path is `prefix` (the error names `prefix.name`): a type used in
    /// several places names the place it was used.
    pub fn check_field(
        ok: bool,
        prefix: &str,
        name: &str,
        value: f64,
        requirement: &'static str,
    ) -> Result<(), ConfigError> {
        Self::check_path(ok, || format!("{prefix}.{name}").into(), value, requirement)
    }

    /// `value` must be finite and > 0 (the most common requirement).
    pub fn positive(field: &'static str, value: f64) -> Result<(), ConfigError> {
        Self::check(value > 0.0 && value.is_finite(), field, value, "must be finite and > 0")
    }

    /// Each `(name, value)` of `fields` must be finite and > 0; the first
    /// that is not gives the error, naming `prefix.name`.
    ///
    /// ```
    /// use pcaline_geometry::ConfigError;
    /// let fields = [("radius_m", 1.0), ("max_rms_m", f64::NAN), ("min_gain_m", -1.0)];
    /// let e = ConfigError::positive_fields("recovery", &fields).unwrap_err();
    /// assert!(e.to_string().contains("`recovery.max_rms_m`"));
    /// assert!(ConfigError::positive_fields("recovery", &fields[..1]).is_ok());
    /// ```
    pub fn positive_fields(prefix: &str, fields: &[(&str, f64)]) -> Result<(), ConfigError> {
        fields.iter().try_for_each(|&(name, v)| {
            Self::check_field(v > 0.0 && v.is_finite(), prefix, name, v, "must be finite and > 0")
        })
    }

    /// `value` must be finite and >= 0.
    pub fn non_negative(field: &'static str, value: f64) -> Result<(), ConfigError> {
        Self::check(value >= 0.0 && value.is_finite(), field, value, "must be finite and >= 0")
    }

    /// `value` must lie in [0, 1].
    pub fn unit_interval(field: &'static str, value: f64) -> Result<(), ConfigError> {
        Self::check((0.0..=1.0).contains(&value), field, value, "must be in [0, 1]")
    }

    /// The same error for a configuration nested under `prefix`: the field
    /// `fitting.eth` of a detector read from a file's `[detector]` section
    /// becomes `detector.fitting.eth`, the path the file writes.
    ///
    /// ```
    /// use pcaline_geometry::ConfigError;
    /// let e = ConfigError::positive("fitting.eth", -1.0).unwrap_err();
    /// assert!(e.within("detector").to_string().contains("`detector.fitting.eth`"));
    /// ```
    #[must_use]
    pub fn within(self, prefix: &str) -> Self {
        match self {
            ConfigError::OutOfRange { field, value, requirement } => ConfigError::OutOfRange {
                field: format!("{prefix}.{field}").into(),
                value,
                requirement,
            },
        }
    }

    /// The check both share; a NaN value always fails.
    fn check_path(
        ok: bool,
        field: impl FnOnce() -> std::borrow::Cow<'static, str>,
        value: f64,
        requirement: &'static str,
    ) -> Result<(), ConfigError> {
        if ok && !value.is_nan() {
            Ok(())
        } else {
            Err(ConfigError::OutOfRange { field: field(), value, requirement })
        }
    }
}
