//! Replays what the fuzzers (`fuzz/`, see CONTRIBUTING.md) kept: their minimized corpora in
//! `fuzz/corpus/` and the inputs that once crashed them in `tests/fixtures/fuzz/`. No input
//! may panic or take a second, so a fixed crash stays fixed without libFuzzer or nightly.

use rayreel::cli::parse_frame_spec;
use rayreel::fuzzing;
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
    replay_bytes(dir, min_files, |bytes| {
        if let Ok(text) = std::str::from_utf8(bytes) {
            call(text)
        }
    })
}

/// `replay` on the files' bytes as they are.
fn replay_bytes(dir: &str, min_files: usize, call: impl Fn(&[u8])) {
    let files = inputs(dir);
    assert!(
        files.len() >= min_files,
        "{dir}: {} inputs, expected at least {min_files}",
        files.len()
    );
    let mut failures = Vec::new();
    for file in &files {
        let bytes = std::fs::read(file).unwrap();
        let started = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| call(&bytes)));
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

/// The fuzz targets past parsing (`render`, `frame_files`, `ffmpeg_words`): their seeds and
/// kept inputs against the same checks, in `rayreel::fuzzing`.
#[test]
fn render_corpus() {
    replay("fuzz/corpus/sequence", 50, fuzzing::render_tiny);
}

#[test]
fn ffmpeg_words_corpus() {
    replay("fuzz/corpus/ffmpeg_words", 4, fuzzing::ffmpeg_words);
}

#[test]
fn frame_files_corpus_and_crashes() {
    replay_bytes("fuzz/corpus/frame_files", 5, fuzzing::frame_and_claim_files);
    let before = peak_rss_kb();
    replay_bytes(
        "tests/fixtures/fuzz/frame_files",
        1,
        fuzzing::frame_and_claim_files,
    );
    // A header claiming 2 GB of pixels is judged by its header, never decoded.
    let grew = peak_rss_kb() - before;
    assert!(grew < 200 * 1024, "peak RSS grew by {grew} kB");
}

/// The model and texture readers' targets (`ply`, `obj`, `textures`): their seeds and kept
/// inputs, and what once hung them (a binary PLY element without properties declaring 3e18
/// rows, each read as nothing).
#[test]
fn model_and_texture_corpora() {
    replay_bytes("fuzz/corpus/ply", 4, fuzzing::ply_file);
    replay_bytes("tests/fixtures/fuzz/ply", 1, fuzzing::ply_file);
    replay_bytes("fuzz/corpus/obj", 5, fuzzing::obj_file);
    replay_bytes("fuzz/corpus/textures", 8, fuzzing::texture_file);
}

/// This process's peak resident set, in kB.
fn peak_rss_kb() -> i64 {
    // SAFETY: getrusage writes only the struct it is given.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    usage.ru_maxrss
}
