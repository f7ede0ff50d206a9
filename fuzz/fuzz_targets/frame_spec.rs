//! `--frames SPEC`: parsing any string, then expanding it against a few frame counts, must
//! never panic, hang or allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rayreel::cli::parse_frame_spec;

fuzz_target!(|data: &[u8]| {
    let Ok(s) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(spec) = parse_frame_spec(s) {
        // `frames` joins repeated ranges as ranges and merges interleaved ones in a bitset over
        // their span, so no spec costs memory beyond the frame count (once 80 MB a range:
        // `4-8888885,4-8888885,2`).
        for (first, last) in [(0, 0), (0, 999), (1001, 2000), (0, 9_999_999)] {
            let _ = spec.frames(first, last);
        }
    }
});
