//! A sequence file that loads renders its first frame (8×8 at most, few samples) in f64 and in
//! f32 with every pixel finite: fuzzing past parsing, into the camera and the tracer.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        rayreel::fuzzing::render_tiny(text);
    }
});
