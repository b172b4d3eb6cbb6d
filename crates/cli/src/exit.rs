//! Exit codes: bad input is 2, everything else that fails is 1.

use pcaline_io::IoError;
use std::process::ExitCode;

/// Marks an error as the user's input being wrong (exit code 2).
#[derive(Debug)]
pub struct BadInput(pub String);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// The exit code for `err`: 2 when any cause is bad input (a reader's error
/// about the input file, or a [`BadInput`]), 1 otherwise.
pub fn code_for(err: &anyhow::Error) -> ExitCode {
    for cause in err.chain() {
        if cause.is::<BadInput>() {
            return ExitCode::from(2);
        }
        if let Some(io) = cause.downcast_ref::<IoError>() {
            return match io {
                IoError::Io { source, .. }
                    if source.kind() != std::io::ErrorKind::NotFound
                        && source.kind() != std::io::ErrorKind::InvalidData =>
                {
                    ExitCode::from(1)
                }
                _ => ExitCode::from(2),
            };
        }
    }
    ExitCode::from(1)
}
