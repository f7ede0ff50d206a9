//! Attacker-written bytes where a frame file or a claim file stands: the frame checks (PNG,
//! EXR) and the claim's owner line must answer, never panic or allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| rayreel::fuzzing::frame_and_claim_files(data));
