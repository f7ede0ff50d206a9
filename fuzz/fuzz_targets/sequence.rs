//! A sequence file: any text must give a `Sequence` or a `LoadError`, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rayreel::sequence::parse;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse(Path::new("fuzz.yaml"), text);
    }
});
