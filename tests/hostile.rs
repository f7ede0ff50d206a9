//! Hostile sequence files through the real binary: `rayreel check FILE` must refuse each one
//! (or accept it) in under a second of CPU time and 100 MB, with exit 2 and one clear line on
//! stderr. CPU time, not wall time: a shared machine's load stretches the wall time several-fold
//! (0.17 s became 0.37 s under three busy loops), and the refusals' wall time is only held to
//! a hang guard.
//!
//! Peak memory is the child's `ru_maxrss` from `wait4`. The big files are written in small
//! chunks so that this process stays small: a child spawned with `posix_spawn` (which shares
//! the parent's memory until it execs) inherits the parent's high-water mark.

mod common;
use common::*;

use std::io::Write;
use std::path::Path;
use std::process::Stdio;
use std::time::Instant;

const MAX_CPU_SECONDS: f64 = 1.0;
/// Far above any run's wall time: a hang, not noise.
const MAX_WALL_SECONDS: f64 = 15.0;
const MAX_PEAK_KB: u64 = 100 * 1024;

fn check(dir: &Path, name: &str) -> Run {
    cpu_timed(bin().args(["check", name]).current_dir(dir))
}

/// Writes `name` in `dir` from `head`, `count` copies of `chunk`, then `tail`.
fn write(dir: &Path, name: &str, head: &str, chunk: &str, count: usize, tail: &str) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(dir.join(name)).unwrap());
    f.write_all(head.as_bytes()).unwrap();
    for _ in 0..count {
        f.write_all(chunk.as_bytes()).unwrap();
    }
    f.write_all(tail.as_bytes()).unwrap();
    f.flush().unwrap();
}

/// The run was quick, small, exit 2, and said `needle` on one line that starts `FILE:`.
fn assert_refused(run: &Run, name: &str, needle: &str) {
    let what = format!(
        "{name}: exit {:?}, {:.2} s CPU, {:.2} s wall, {} MB, stderr {:?}",
        run.code,
        run.cpu_seconds,
        run.seconds,
        run.peak_kb / 1024,
        run.stderr.chars().take(600).collect::<String>()
    );
    eprintln!("{what}");
    assert_eq!(run.code, Some(2), "{what}");
    assert!(run.cpu_seconds < MAX_CPU_SECONDS, "too slow: {what}");
    assert!(run.seconds < MAX_WALL_SECONDS, "a hang: {what}");
    assert!(run.peak_kb < MAX_PEAK_KB, "too much memory: {what}");
    assert!(
        run.stderr.starts_with(&format!("rayreel: {name}:")),
        "{what}"
    );
    assert!(run.stderr.contains(needle), "expected {needle:?}: {what}");
    assert_eq!(run.stderr.lines().count(), 1, "{what}");
    assert!(run.stderr.len() < 1000, "message too long: {what}");
}

/// `FILE:LINE:COL: ` at the start of the message.
fn assert_located(run: &Run, name: &str) {
    let rest = &run.stderr[format!("rayreel: {name}:").len()..];
    let mut parts = rest.splitn(3, ':');
    let line = parts.next().unwrap();
    let col = parts.next().unwrap();
    assert!(
        line.parse::<u32>().is_ok() && col.parse::<u32>().is_ok(),
        "no LINE:COL in {:?}",
        run.stderr
    );
}

const HEAD: &str = "render: { width: 64, height: 36 }
camera: { position: [0, 0, 1], look_at: [0, 0, 0] }
lights:
  - point: { position: [5, 5, 5], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";

/// Nine levels of ten aliases each: a billion "lol"s if anything expanded them.
fn laughs(indent: &str) -> String {
    let mut s = format!("{indent}- &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]\n");
    for i in 1..10 {
        let refs = vec![format!("*a{}", i - 1); 10].join(", ");
        s += &format!("{indent}- &a{i} [{refs}]\n");
    }
    s
}

#[test]
fn alias_bombs_are_refused_without_expanding() {
    let dir = scratch("hostile-laughs");
    // The classic: the bomb under a key of its own.
    let top = format!("{HEAD}lol:\n{}", laughs("  "));
    write(&dir, "laughs_key.yaml", &top, "", 0, "");
    let run = check(&dir, "laughs_key.yaml");
    assert_refused(&run, "laughs_key.yaml", "unknown field `lol`");
    assert_located(&run, "laughs_key.yaml");

    // Under keys the file does have, where each alias would be read as an object or a vector.
    let objects = format!("{HEAD}objects:\n{}", laughs("  "));
    write(&dir, "laughs_objects.yaml", &objects, "", 0, "");
    let run = check(&dir, "laughs_objects.yaml");
    assert_refused(&run, "laughs_objects.yaml", "objects[0]");
    assert_located(&run, "laughs_objects.yaml");

    let center = format!(
        "{HEAD}objects:\n  - sphere: {{ center: [0, 0, -1], radius: 1, material: {{ diffuse: [1, 0, 0] }} }}\n  - sphere: {{ center: *a9, radius: 1, material: {{ diffuse: [1, 0, 0] }} }}\nlol:\n{}",
        laughs("  ")
    );
    write(&dir, "laughs_late.yaml", &center, "", 0, "");
    let run = check(&dir, "laughs_late.yaml");
    assert_refused(&run, "laughs_late.yaml", "unknown anchor");
    assert_located(&run, "laughs_late.yaml");

    // An alias may stand for a whole keyframe: each one is read, but only once per alias.
    let keys = format!(
        "{HEAD}timeline:\n  keyframes:\n    - &k {{ time: 0, position: [0, 0, 1], look_at: [0, 0, 0] }}\n    - "
    );
    write(
        &dir,
        "alias_keys.yaml",
        &keys,
        "*k\n    - ",
        100_000,
        "*k\n",
    );
    let run = check(&dir, "alias_keys.yaml");
    assert_refused(
        &run,
        "alias_keys.yaml",
        "timeline.keyframes[1].time: keyframe times must increase strictly",
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn deep_nesting_is_refused_before_parsing() {
    let dir = scratch("hostile-nesting");
    for (name, head, chunk, tail) in [
        ("flow_seq.yaml", "", "[", ""),
        ("flow_map_value.yaml", HEAD, "{a: ", "\n"),
        ("under_output.yaml", HEAD, "[", "\n"),
        ("block_seq.yaml", "", "- ", "x\n"),
    ] {
        let head = if head.is_empty() {
            String::new()
        } else {
            format!("{head}output: ")
        };
        write(&dir, name, &head, chunk, 100_000, tail);
        let run = check(&dir, name);
        assert_refused(&run, name, "collections nested too deeply here");
        assert_located(&run, name);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn huge_numbers_are_refused_with_their_field() {
    let dir = scratch("hostile-numbers");
    let sphere = |radius: &str| {
        format!(
            "{HEAD}objects:\n  - sphere: {{ center: [0, 0, -1], radius: {radius}, material: {{ diffuse: [1, 0, 0] }} }}\n"
        )
    };
    let cases = [
        (
            "radius_1e400.yaml",
            sphere("1e400"),
            "objects[0].sphere.radius: must be within ±1e100 (lengths are squared) (got 1e400)",
        ),
        (
            "radius_minus_1e400.yaml",
            sphere("-1e400"),
            "objects[0].sphere.radius: must be within ±1e100 (lengths are squared) (got -1e400)",
        ),
        (
            "radius_400_digits.yaml",
            sphere(&"9".repeat(400)),
            "objects[0].sphere.radius: must be within ±1e100",
        ),
        (
            "width_huge.yaml",
            HEAD.replace("width: 64", "width: 99999999999999999999999"),
            "render.width: number out of range (got 99999999999999999999999)",
        ),
        (
            "width_negative.yaml",
            HEAD.replace("width: 64", "width: -99999999999999999999999"),
            "render.width: number out of range (got -99999999999999999999999)",
        ),
        (
            "fps_1e308.yaml",
            format!("{HEAD}timeline:\n  fps: 1e308\n  keyframes: [{{ time: 0 }}]\n"),
            "timeline.fps",
        ),
        (
            "duration_1e300.yaml",
            format!("{HEAD}timeline:\n  duration: 1e300\n  keyframes: [{{ time: 0 }}]\n"),
            "timeline.duration",
        ),
    ];
    for (name, text, needle) in cases {
        write(&dir, name, &text, "", 0, "");
        let run = check(&dir, name);
        assert_refused(&run, name, needle);
        assert_located(&run, name);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn enormous_strings_are_refused() {
    let dir = scratch("hostile-strings");
    let mib = "m".repeat(1 << 20);
    // A 50 MB material name: the file is over the size limit and is never read.
    let head = format!("{HEAD}objects:\n  - sphere: {{ center: [0, 0, -1], radius: 1, material: ");
    write(&dir, "name_50mb.yaml", &head, &mib, 50, " }\n");
    let run = check(&dir, "name_50mb.yaml");
    assert_refused(&run, "name_50mb.yaml", "the file is 50.0 MiB (52429");
    assert!(
        run.stderr.contains("sequence files are limited to 16 MiB"),
        "{}",
        run.stderr
    );

    // A 50 MB output pattern.
    write(
        &dir,
        "output_50mb.yaml",
        &format!("{HEAD}output: f"),
        &mib,
        50,
        "_####.png\n",
    );
    let run = check(&dir, "output_50mb.yaml");
    assert_refused(
        &run,
        "output_50mb.yaml",
        "sequence files are limited to 16 MiB",
    );

    // Within the limit, a 4 MB name is read, and the message quotes only its ends.
    write(&dir, "name_4mb.yaml", &head, &mib, 4, " }\n");
    let run = check(&dir, "name_4mb.yaml");
    assert_refused(
        &run,
        "name_4mb.yaml",
        "objects[0].sphere.material: unknown material `mmm",
    );
    assert!(run.stderr.contains(" bytes …] "), "{}", run.stderr);
    assert_located(&run, "name_4mb.yaml");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn files_over_the_limit_are_refused_unread() {
    let dir = scratch("hostile-100mb");
    let comment = format!("#{}\n", "c".repeat(98));
    write(&dir, "comments.yaml", HEAD, &comment, 1 << 20, "");
    let run = check(&dir, "comments.yaml");
    assert_refused(&run, "comments.yaml", "the file is 100.0 MiB");
    std::fs::remove_file(dir.join("comments.yaml")).unwrap();

    let sphere =
        "  - sphere: { center: [0, 0, -1], radius: 0.5, material: { diffuse: [1, 0, 0] } }\n";
    write(
        &dir,
        "objects.yaml",
        &format!("{HEAD}objects:\n"),
        sphere,
        (100 << 20) / sphere.len(),
        "",
    );
    let run = check(&dir, "objects.yaml");
    assert_refused(&run, "objects.yaml", "sequence files are limited to 16 MiB");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_stream_over_the_limit_is_cut_off() {
    // /dev/stdin has no length up front: rayreel stops reading one byte past the limit.
    let started = Instant::now();
    let child = bin()
        .args(["check", "/dev/stdin"])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rayreel runs");
    let run = measure(child, started, |child| {
        let mut stdin = child.stdin.take().unwrap();
        let writer = std::thread::spawn(move || {
            let chunk = format!("#{}\n", "c".repeat(1022)).repeat(64);
            let _ = stdin.write_all(HEAD.as_bytes());
            for _ in 0..(100 << 20) / chunk.len() {
                // rayreel closes the pipe once it has read enough.
                if stdin.write_all(chunk.as_bytes()).is_err() {
                    break;
                }
            }
        });
        writer.join().unwrap();
    });
    assert_refused(
        &run,
        "/dev/stdin",
        "the input goes on past the limit; sequence files are limited to 16 MiB",
    );
}
