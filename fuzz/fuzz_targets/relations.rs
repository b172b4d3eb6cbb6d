//! The relations reader (`t1 t2 x y z roll pitch yaw`) and the scan-pairs
//! reader on arbitrary bytes: an error or a result, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pcaline_fuzz::input_file;

fuzz_target!(|data: &[u8]| {
    let path = input_file("input.relations", data);
    let _ = pcaline_io::read_relations(&path);
    let _ = pcaline_io::read_scan_pairs(&path);
});
