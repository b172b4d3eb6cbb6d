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

/// Standard output was closed by its reader (`pcaline detect log | head`):
/// the command stops and exits 0 without a message, like ripgrep.
#[derive(Debug)]
pub struct StdoutClosed;

impl std::fmt::Display for StdoutClosed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("stdout closed")
    }
}

impl std::error::Error for StdoutClosed {}

/// A failed write to standard output: [`StdoutClosed`] for a broken pipe,
/// else an error that names stdout (exit 1).
pub fn stdout_error(e: std::io::Error) -> anyhow::Error {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        StdoutClosed.into()
    } else {
        anyhow::anyhow!("writing to stdout: {e}")
    }
}

/// The exit code for `err`: 2 when any cause is bad input (a reader's error
/// about the input file, or a [`BadInput`]), 1 otherwise.
pub fn code_for(err: &anyhow::Error) -> ExitCode {
    for cause in err.chain() {
        if cause.is::<BadInput>() {
            return ExitCode::from(2);
        }
        if let Some(io) = cause.downcast_ref::<IoError>() {
            return match io {
                // A missing, unreadable or malformed file is the user's input
                // (exit 2); a full disk or a failing device is not.
                IoError::Io { source, .. }
                    if !matches!(
                        source.kind(),
                        std::io::ErrorKind::NotFound
                            | std::io::ErrorKind::InvalidData
                            | std::io::ErrorKind::PermissionDenied
                            | std::io::ErrorKind::IsADirectory
                            | std::io::ErrorKind::NotADirectory
                    ) =>
                {
                    ExitCode::from(1)
                }
                _ => ExitCode::from(2),
            };
        }
    }
    ExitCode::from(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unreadable_or_missing_input_is_bad_input_and_a_full_disk_is_not() {
        let code = |kind: std::io::ErrorKind| {
            let e = anyhow::Error::from(IoError::io("f.json", std::io::Error::from(kind)));
            format!("{:?}", code_for(&e))
        };
        let two = format!("{:?}", ExitCode::from(2));
        let one = format!("{:?}", ExitCode::from(1));
        for kind in [std::io::ErrorKind::NotFound, std::io::ErrorKind::PermissionDenied] {
            assert_eq!(code(kind), two, "{kind:?}");
        }
        assert_eq!(code(std::io::ErrorKind::StorageFull), one);
    }
}
