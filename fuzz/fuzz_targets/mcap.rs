//! The Mcap reader on arbitrary bytes: an error or a result, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pcaline_fuzz::read_every_way;
use pcaline_io::LogFormat;

fuzz_target!(|data: &[u8]| {
    read_every_way("input.mcap", LogFormat::Mcap, data);
});
