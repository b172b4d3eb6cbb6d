//! The scene loader on arbitrary bytes, as TOML and as JSON; a scene that
//! loads is validated and, when valid, its simulator built: an error or a
//! result, never a panic or an unbounded allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pcaline_fuzz::input_file;

fuzz_target!(|data: &[u8]| {
    for name in ["input.toml", "input.json"] {
        let path = input_file(name, data);
        if let Ok(scene) = pcaline_io::read_scene(&path) {
            if scene.validate().is_ok() {
                let _ = scene.world();
                let _ = scene.trajectory().duration_s();
            }
        }
    }
});
