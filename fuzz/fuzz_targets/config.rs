//! The configuration-file parser on arbitrary text, as TOML and as JSON:
//! an error naming the file, or a valid configuration; never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pcaline_cli::config_file::parse;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    for name in ["fuzz.toml", "fuzz.json"] {
        if let Ok(config) = parse(Path::new(name), text, 0.01) {
            assert!(config.detector.validate().is_ok(), "a parsed configuration is valid");
        }
    }
});
