//! [`IoError`]: every reader and writer error names the file, and the line,
//! message or item where it can.

use std::path::PathBuf;

/// An error reading or writing a file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is not in the expected format.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The 1-based line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The file parsed, but an item in it is invalid.
    #[error("{}: {item}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The offending item.
        item: String,
        /// What is wrong with it.
        message: String,
    },
    /// The file's extension names no format this reader knows.
    #[error("{}: unknown format (expected one of: {expected})", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The accepted extensions.
        expected: &'static str,
    },
}

impl IoError {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        IoError::Io { path: path.into(), source }
    }

    /// A parse error in `path`.
    pub fn parse(
        path: impl Into<PathBuf>,
        line: Option<usize>,
        message: impl Into<String>,
    ) -> Self {
        IoError::Parse { path: path.into(), line, message: message.into() }
    }
}
