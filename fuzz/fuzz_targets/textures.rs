//! Any bytes as a PNG and an EXR texture: a refusal or a finite pyramid down to 1×1.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| rayreel::fuzzing::texture_file(data));
