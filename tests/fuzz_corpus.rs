//! Replays what the fuzzers (`fuzz/`, see CONTRIBUTING.md) kept: their minimized corpora in
//! `fuzz/corpus/` and the inputs that once crashed them in `tests/fixtures/fuzz/`. No input
//! may panic or take a second, so a fixed crash stays fixed without libFuzzer or nightly.

use rayreel::cli::parse_frame_spec;
use rayreel::sequence;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn inputs(dir: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

/// Runs `call` on every file of `dir` (as UTF-8 text, like the fuzz targets), collecting every
/// panic and every call that takes a second or more.
fn replay(dir: &str, min_files: usize, call: impl Fn(&str)) {
    let files = inputs(dir);
    assert!(
        files.len() >= min_files,
        "{dir}: {} inputs, expected at least {min_files}",
        files.len()
    );
    let mut failures = Vec::new();
    for file in &files {
        let bytes = std::fs::read(file).unwrap();
        let Ok(text) = std::str::from_utf8(&bytes) else {
            continue;
        };
        let started = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| call(text)));
        let took = started.elapsed();
        if result.is_err() {
            failures.push(format!("{}: panicked", file.display()));
        } else if took >= Duration::from_secs(1) {
            failures.push(format!("{}: took {took:?}", file.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn parse_sequence(text: &str) {
    let _ = sequence::parse(Path::new("fuzz.yaml"), text);
}

#[test]
fn sequence_corpus() {
    replay("fuzz/corpus/sequence", 50, parse_sequence);
}

#[test]
fn sequence_crashes() {
    replay("tests/fixtures/fuzz", 1, parse_sequence);
}

#[test]
fn frame_spec_corpus() {
    replay("fuzz/corpus/frame_spec", 50, |s| {
        let _ = parse_frame_spec(s).and_then(|spec| spec.frames(0, 999));
    });
}
