//! What the fuzz targets share: the input written to a file of this
//! process (the readers take paths), and a reader that must not panic.

use pcaline_io::{LogFormat, LogOptions, read_log};
use std::ops::ControlFlow;
use std::path::PathBuf;

/// Writes `data` to this process's file for `name` (e.g. `input.clf`) and
/// returns its path.
pub fn input_file(name: &str, data: &[u8]) -> PathBuf {
    let path = std::env::temp_dir().join(format!("pcaline-fuzz-{}-{name}", std::process::id()));
    std::fs::write(&path, data).expect("the temporary folder is writable");
    path
}

/// Reads `data` as a log of `format`, then with the format detected from
/// the bytes; errors are expected, panics are the bugs.
pub fn read_every_way(name: &str, format: LogFormat, data: &[u8]) {
    let path = input_file(name, data);
    for format in [Some(format), None] {
        let mut options = LogOptions::default();
        options.format = format;
        let _ = read_log(&path, &options, |_| ControlFlow::Continue(()));
    }
}
