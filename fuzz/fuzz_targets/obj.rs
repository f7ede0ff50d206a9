//! Any bytes as an OBJ model: a refusal or a mesh whose arrays agree (the tracer indexes them
//! without checks), never a panic, a hang or unbounded memory.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| rayreel::fuzzing::obj_file(data));
