//! What an adversarial pass over the output directory, claims, signals and input found (issue
//! 14), each through the real binary: nothing the user has is lost or overwritten, nothing is
//! written outside where it should be, broken frames do not pass as done, and nothing hangs.

mod common;
use common::*;
use std::path::Path;

fn small() -> String {
    sequence(32, 18, &orbit(24, 1.0))
}

#[test]
fn exr_frames_are_byte_identical_across_processes() {
    let tmp = scratch("exr-determinism");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    // The header's custom attributes used to follow a per-process hash order: eight separate
    // renders all agreeing would have had a chance of about 1 in 6^7.
    let renders: Vec<Vec<u8>> = (0..8)
        .map(|i| {
            let pattern = format!("e{i}/f_####.exr");
            let out = run_in(
                &tmp,
                &["render", "seq.yaml", "-o", &pattern, "--frames", "1"],
            );
            assert!(out.status.success(), "{}", stderr(&out));
            std::fs::read(tmp.join(format!("e{i}/f_0001.exr"))).unwrap()
        })
        .collect();
    for (i, bytes) in renders.iter().enumerate() {
        assert!(bytes == &renders[0], "render {i} differs from render 0");
    }
    let again = run_in(
        &tmp,
        &["status", "seq.yaml", "-o", "e3/f_####.exr", "--frames", "1"],
    );
    assert_eq!(again.status.code(), Some(0), "{}", stderr(&again));
}

/// Runs rayreel in `dir` with a stdout whose reader has already gone.
fn with_closed_stdout(dir: &Path, args: &[&str]) -> std::process::Output {
    use std::os::fd::FromRawFd;
    let mut fds = [0; 2];
    // SAFETY: pipe fills both descriptors; we own them from here on.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    // SAFETY: the read end is ours and is closed once, here.
    unsafe { libc::close(fds[0]) };
    // SAFETY: the write end is ours; the Stdio takes it over.
    let write_end = unsafe { std::process::Stdio::from_raw_fd(fds[1]) };
    bin()
        .args(args)
        .current_dir(dir)
        .stdout(write_end)
        .output()
        .expect("rayreel runs")
}

#[test]
fn a_closed_stdout_is_a_normal_end() {
    let tmp = scratch("closed-stdout");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let out = run_in(&tmp, &["render", "seq.yaml", "-o", "f/f_####.png", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    for (args, code) in [
        (vec!["check", "seq.yaml"], 0),
        (vec!["status", "seq.yaml", "-o", "f/f_####.png"], 0),
        // The listing ends; the verdict (frames missing) still decides the exit code.
        (vec!["status", "seq.yaml", "-o", "g/f_####.png"], 1),
        (
            vec!["render", "seq.yaml", "-o", "g/f_####.png", "--dry-run"],
            0,
        ),
        (vec!["render", "seq.yaml", "--pipe", "raw", "--dry-run"], 0),
        (vec!["preview", "seq.yaml", "--out", "p", "--tiles", "2"], 0),
    ] {
        let out = with_closed_stdout(&tmp, &args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

const STILL: &str = "render: { width: 32, height: 18 }
camera: { position: [0, 0, 1], look_at: [0, 0, 0] }
objects:
  - sphere: { center: [0, 0, -1], radius: 0.5, material: { diffuse: [1, 0, 0] } }
lights:
  - point: { position: [5, 5, 5], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";

/// `check` on `yaml` written to `name` in `dir`.
fn check(dir: &Path, name: &str, yaml: &str) -> std::process::Output {
    std::fs::write(dir.join(name), yaml).unwrap();
    run_in(dir, &["check", name])
}

/// Numbers serde_yaml takes as another type (issue 29): a negative sample count, a hexadecimal
/// or octal radius were once told to drop a tag and quotes they never had; a value just over
/// a limit is shown as written, not rounded onto the limit.
#[test]
fn numbers_of_the_wrong_kind_are_named_as_written() {
    let tmp = scratch("number-kinds");
    let keys = "timeline:\n  keyframes:\n    - { time: 0 }\n";
    let cases = [
        (
            ("width: 32,", "width: 32, samples: -1,"),
            "render.samples: must be 1 to 4096 samples per pixel (got -1)",
        ),
        (
            ("radius: 0.5", "radius: 0x10"),
            "radius: hexadecimal numbers are not accepted, write 16 (got 0x10)",
        ),
        (
            ("radius: 0.5", "radius: 0o17"),
            "radius: octal numbers are not accepted, write 15 (got 0o17)",
        ),
        (
            (
                "look_at: [0, 0, 0] }",
                "look_at: [0, 0, 0], fov: 360.0001 }",
            ),
            "(got 360.0001)",
        ),
    ];
    for (i, ((from, to), needle)) in cases.into_iter().enumerate() {
        let yaml = format!("{}{keys}", STILL.replacen(from, to, 1));
        let out = check(&tmp, &format!("n{i}.yaml"), &yaml);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        let said = stderr(&out);
        assert!(
            said.contains(needle) && !said.contains("tagged"),
            "{needle}: {said}"
        );
    }
}

#[test]
fn messages_read_well_whatever_the_file_holds() {
    let tmp = scratch("messages");
    let out = check(&tmp, "bom.yaml", &format!("\u{feff}{STILL}"));
    assert!(out.status.success(), "a byte-order mark: {}", stderr(&out));

    let keys = "  keyframes:\n    - { time: 0 }\n";
    let tagged = format!("{STILL}timeline:\n  fps: 24\n  duration: !!float \"1\"\n{keys}");
    let out = check(&tmp, "tagged.yaml", &tagged);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("tagged.yaml:9:13: timeline.duration:")
            && stderr(&out).contains("write it plainly, without tag or quotes: `duration: 1`"),
        "{}",
        stderr(&out)
    );

    let tiny = format!("{STILL}timeline:\n  duration: 1e-300\n{keys}");
    let out = check(&tmp, "tiny.yaml", &tiny);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        stderr(&out),
        "rayreel: tiny.yaml:8:13: timeline.duration: duration × fps must give 1 to 10000000 frames (got 1e-300 s × 24 fps = 0 frames)\n"
    );
}

#[test]
fn control_characters_from_a_file_never_reach_the_terminal() {
    let tmp = scratch("escapes");
    let hostile = "\\e[31mred/\\e]0;owned\\a\\e[2Jf_####";
    let yaml = format!("{STILL}output: \"{hostile}.png\"\n");
    let clean = |o: &std::process::Output| {
        for bytes in [&o.stdout, &o.stderr] {
            assert!(
                !bytes.iter().any(|&b| b == 0x1b || b == 0x07),
                "{}",
                String::from_utf8_lossy(bytes)
            );
        }
    };
    let out = check(&tmp, "esc.yaml", &yaml);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("\\u{1b}[31mred/"));
    clean(&out);
    for args in [
        vec!["render", "esc.yaml"],
        vec!["render", "esc.yaml", "--dry-run"],
        vec!["status", "esc.yaml"],
    ] {
        let out = run_in(&tmp, &args);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        clean(&out);
    }
    let bad = format!("{STILL}output: \"{hostile}.txt\"\n");
    let out = check(&tmp, "bad.yaml", &bad);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("(got `\\u{1b}[31mred/"),
        "{}",
        stderr(&out)
    );
    clean(&out);
}

/// `png` with each chunk's data passed through `edit` (by chunk type; `None` drops the chunk)
/// and its CRC recomputed: a file whose checksums are all valid.
fn edit_chunks(png: &[u8], edit: Edit) -> Vec<u8> {
    let mut out = png[..8].to_vec();
    let mut rest = &png[8..];
    while rest.len() >= 12 {
        let len = u32::from_be_bytes(rest[..4].try_into().unwrap()) as usize;
        let kind = &rest[4..8];
        if let Some(data) = edit(kind, rest[8..8 + len].to_vec()) {
            let mut crc = crc32fast::Hasher::new();
            crc.update(kind);
            crc.update(&data);
            out.extend((data.len() as u32).to_be_bytes());
            out.extend(kind);
            out.extend(&data);
            out.extend(crc.finalize().to_be_bytes());
        }
        rest = &rest[12 + len..];
    }
    out
}

type Edit = fn(&[u8], Vec<u8>) -> Option<Vec<u8>>;

/// Ways to break a frame that keep its fingerprint and every checksum valid.
const BREAKS: [(&str, Edit); 5] = [
    ("half the rows", |kind, data| match kind {
        b"IDAT" => {
            let pixels = fdeflate::decompress_to_vec(&data).unwrap();
            Some(fdeflate::compress_to_vec(&pixels[..pixels.len() / 2]))
        }
        _ => Some(data),
    }),
    ("garbage data", |kind, data| match kind {
        b"IDAT" => Some(data.iter().map(|b| b.wrapping_mul(31) ^ 0x5a).collect()),
        _ => Some(data),
    }),
    ("no data", |kind, data| (kind != b"IDAT").then_some(data)),
    ("1x1 header", |kind, mut data| {
        if kind == b"IHDR" {
            data[..8].copy_from_slice(&[0, 0, 0, 1, 0, 0, 0, 1]);
        }
        Some(data)
    }),
    ("RGBA header", |kind, mut data| {
        if kind == b"IHDR" {
            data[9] = 6;
        }
        Some(data)
    }),
];

#[test]
fn broken_frames_with_valid_checksums_are_not_up_to_date() {
    let tmp = with_clean_render("broken-frames", &small());
    let out = run_in(&tmp, &["render", "seq.yaml", "-o", "out/f_####.png", "-q"]);
    assert!(out.status.success());
    for (n, (what, edit)) in BREAKS.iter().enumerate() {
        let path = tmp.join(format!("out/f_{n:04}.png"));
        let broken = edit_chunks(&std::fs::read(&path).unwrap(), *edit);
        std::fs::write(&path, broken).unwrap();
        let status = run_in(&tmp, &["status", "seq.yaml", "-o", "out/f_####.png"]);
        let text = String::from_utf8_lossy(&status.stdout);
        assert_eq!(status.status.code(), Some(1), "{what}: {text}");
        assert!(
            text.contains(&format!(
                "corrupt     {}",
                if n == 0 {
                    "0".to_string()
                } else {
                    format!("0-{n}")
                }
            )),
            "{what}: {text}"
        );
    }
    let out = run_in(&tmp, &["render", "seq.yaml", "-o", "out/f_####.png"]);
    assert!(
        stderr(&out).contains("24 frames: 19 up to date, 5 corrupt → rendering 5"),
        "{}",
        stderr(&out)
    );
    assert_same_files(&tmp.join("clean"), &tmp.join("out"));
}

/// Runs rayreel in `dir` and measures it (exit code, stderr, time, peak memory).
fn measured(dir: &Path, args: &[&str]) -> (Run, String) {
    use std::process::Stdio;
    let started = std::time::Instant::now();
    let mut child = bin()
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut stdout, &mut s).unwrap();
        s
    });
    let run = measure(child, started, |_| {});
    (run, reader.join().unwrap())
}

#[test]
fn ten_million_frames_cost_what_their_selection_costs() {
    let tmp = scratch("ten-million");
    let yaml = format!(
        "{STILL}timeline:\n  fps: 1000\n  duration: 10000\n  keyframes:\n    - {{ time: 0 }}\n    - {{ time: 10000, position: [1, 0, 1] }}\n"
    );
    std::fs::write(tmp.join("ten.yaml"), yaml).unwrap();
    let out = run_in(&tmp, &["render", "ten.yaml", "-q", "--frames", "5,9999999"]);
    assert!(out.status.success(), "{}", stderr(&out));
    for (args, code, needle) in [
        (
            vec!["status", "ten.yaml"],
            Some(1),
            "10000000 frames: 2 up to date, 9999998 missing\n  up to date  5,9999999\n  missing     0-4,6-9999998\n",
        ),
        (
            vec![
                "render",
                "ten.yaml",
                "--dry-run",
                "--frames",
                "0-9999999:3",
                "--shard",
                "2/4",
            ],
            Some(0),
            "833334 frames: 1 up to date, 833333 missing → rendering 833333\nwould render: 3-9999987:12\n",
        ),
    ] {
        let (run, stdout) = measured(&tmp, &args);
        let what = format!(
            "{args:?}: exit {:?}, {:.2} s, {} MB: {stdout}{}",
            run.code,
            run.seconds,
            run.peak_kb / 1024,
            run.stderr
        );
        eprintln!("{what}");
        assert_eq!(run.code, code, "{what}");
        assert!(stdout.contains(needle), "{what}");
        // Once 473 MB: a vector of every frame number and a state for each.
        assert!(run.peak_kb < 64 * 1024, "{what}");
    }
}

fn alive(pid: i32) -> bool {
    // SAFETY: signal 0 only checks that the process exists.
    unsafe { libc::kill(pid, 0) == 0 }
}

/// Renders frames 0-3 of seq.yaml to out/, quietly.
const FIRST_FOUR: [&str; 7] = [
    "render",
    "seq.yaml",
    "-o",
    "out/f_####.png",
    "--frames",
    "0-3",
    "-q",
];

#[test]
fn a_link_planted_under_a_temporary_name_is_never_followed() {
    let tmp = with_clean_render("planted-links", &small());
    let victim = tmp.join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).unwrap();
    // The old names were `.NAME.rayreel-tmp-HOST-PID`: plant links for the pids to come.
    let last: i32 = std::fs::read_to_string("/proc/sys/kernel/ns_last_pid")
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let planted = last + 1..last + 300;
    for pid in planted.clone() {
        for n in 0..4 {
            let link = out.join(format!(".f_{n:04}.png.rayreel-tmp-{}-{pid}", host()));
            std::os::unix::fs::symlink(&victim, link).unwrap();
        }
    }
    let child = bin().args(FIRST_FOUR).current_dir(&tmp).spawn().unwrap();
    let pid = child.id() as i32;
    let status = child.wait_with_output().unwrap().status;
    assert!(status.success());
    assert!(
        planted.contains(&pid),
        "pid {pid} was not among the planted ones"
    );
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    for n in 0..4 {
        let name = format!("f_{n:04}.png");
        let meta = std::fs::symlink_metadata(out.join(&name)).unwrap();
        assert!(meta.file_type().is_file(), "{name} is not a plain file");
        assert_eq!(
            std::fs::read(out.join(&name)).unwrap(),
            std::fs::read(tmp.join("clean").join(&name)).unwrap()
        );
    }
}

#[test]
fn cleanup_removes_only_temporaries_of_this_jobs_frames() {
    let tmp = scratch("cleanup");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let dead = 3_999_998;
    assert!(!alive(dead));
    let me = std::process::id();
    let h = host();
    let keep = [
        format!("notes.rayreel-tmp-{h}-{dead}"),
        format!(".notes.rayreel-tmp-{h}-{dead}"),
        format!(".f_9999.png.rayreel-tmp-{h}-{dead}"),
        format!(".g_0001.png.rayreel-tmp-{h}-{dead}-0123456789abcdef"),
        format!(".f_0003.png.rayreel-tmp-{h}-{me}-0123456789abcdef"),
        format!(".f_0001.png.rayreel-tmp-{h}-{dead}-extra"),
    ];
    let remove = [
        format!(".f_0001.png.rayreel-tmp-{h}-{dead}-0123456789abcdef"),
        format!(".f_0002.png.rayreel-tmp-{h}-{dead}"),
    ];
    for name in keep.iter().chain(&remove) {
        std::fs::write(out.join(name), "mine").unwrap();
    }
    let run = run_in(&tmp, &FIRST_FOUR);
    assert!(run.status.success(), "{}", stderr(&run));
    for name in &keep {
        assert!(out.join(name).exists(), "{name} was removed");
    }
    for name in &remove {
        assert!(!out.join(name).exists(), "{name} was left");
    }
}

#[test]
fn a_sequence_file_cannot_write_through_a_linked_directory() {
    let tmp = scratch("escape");
    let (work, elsewhere) = (tmp.join("work"), tmp.join("elsewhere"));
    std::fs::create_dir_all(work.join("inside")).unwrap();
    std::fs::create_dir_all(&elsewhere).unwrap();
    std::os::unix::fs::symlink("../elsewhere", work.join("outlink")).unwrap();
    std::os::unix::fs::symlink("../nowhere", work.join("dangling")).unwrap();
    std::os::unix::fs::symlink("inside", work.join("inlink")).unwrap();
    for output in [
        "outlink/f_####.png",
        "outlink/new/deeper/f_####.png",
        "dangling/f_####.png",
    ] {
        let yaml = format!("{}output: {output}\n", small());
        std::fs::write(work.join("seq.yaml"), yaml).unwrap();
        let out = run_in(&work, &["render", "seq.yaml", "--frames", "0"]);
        assert_eq!(out.status.code(), Some(2), "{output}: {}", stderr(&out));
        assert!(
            stderr(&out).contains(&format!(
                "output: `{output}` leads outside the current directory"
            )),
            "{}",
            stderr(&out)
        );
        assert_eq!(run_in(&work, &["check", "seq.yaml"]).status.code(), Some(2));
    }
    assert!(files(&elsewhere).is_empty());
    // A link that stays inside is fine, and the command line may point anywhere.
    std::fs::write(
        work.join("seq.yaml"),
        format!("{}output: inlink/f_####.png\n", small()),
    )
    .unwrap();
    let out = run_in(&work, &["render", "seq.yaml", "--frames", "0", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(files(&work.join("inside")), ["f_0000.png"]);
    let out = run_in(
        &work,
        &[
            "render",
            "seq.yaml",
            "--frames",
            "0",
            "-q",
            "-o",
            "outlink/f_####.png",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(files(&elsewhere), ["f_0000.png"]);
}

#[test]
fn long_names_render_and_impossible_ones_are_refused_at_load() {
    let tmp = scratch("names");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    // The longest legal frame name: 254 bytes once `####` is a number.
    let name = format!("{}_####.png", "n".repeat(254 - 9));
    for (dir, extra) in [("a", vec![]), ("b", vec!["--claim"])] {
        let pattern = format!("{dir}/{name}");
        let mut args = vec![
            "render", "seq.yaml", "--frames", "0-1", "-q", "-o", &pattern,
        ];
        args.extend(extra);
        let out = run_in(&tmp, &args);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        assert_eq!(files(&tmp.join(dir)).len(), 2, "{args:?}");
    }
    let status = run_in(
        &tmp,
        &[
            "status",
            "seq.yaml",
            "--frames",
            "0-1",
            "-o",
            &format!("a/{name}"),
        ],
    );
    assert_eq!(status.status.code(), Some(0));
    let yaml = format!("{}output: c/{name}\n", small());
    std::fs::write(tmp.join("long.yaml"), yaml).unwrap();
    let out = run_in(&tmp, &["render", "long.yaml", "--frames", "0", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));

    let too_long = format!("{}_####.png", "n".repeat(256 - 9));
    let out = run_in(
        &tmp,
        &["render", "seq.yaml", "-o", &format!("d/{too_long}")],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("--output: the name `nnnnnnnnnnnnnnnnnnnnnnnn…nnnnnnnnnnn_0023.png` is 256 bytes; a file or directory name may have at most 255"),
        "{}",
        stderr(&out)
    );
    for (file, output, message) in [
        ("toolong.yaml", format!("e/{too_long}"), "is 256 bytes"),
        (
            "nul.yaml",
            "\"f/n\\0_####.png\"".to_string(),
            "contains a NUL byte",
        ),
    ] {
        std::fs::write(tmp.join(file), format!("{}output: {output}\n", small())).unwrap();
        let out = run_in(&tmp, &["render", file]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        let prefix = format!("rayreel: {file}:");
        assert!(
            stderr(&out).starts_with(&prefix)
                && stderr(&out).contains(": output: ")
                && stderr(&out).contains(message),
            "{}",
            stderr(&out)
        );
    }
    // Refused before anything was created.
    for dir in ["d", "e", "f"] {
        assert!(!tmp.join(dir).exists(), "{dir} was created");
    }
}

/// Starts a `--claim` render of frames 0-3 into out/ with `extra` flags, stderr piped.
fn claiming(dir: &Path, extra: &[&str]) -> std::process::Child {
    bin()
        .args(&FIRST_FOUR[..6])
        .args(["--claim", "--threads", "1"])
        .args(extra)
        .current_dir(dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

/// Two facing mirrors around the camera at 4096x4096, 4096 samples, depth 10000: every path
/// visits 10000 surfaces, so this one frame would take days.
const MONSTROUS: &str = "render: { width: 4096, height: 4096, samples: 4096, max_depth: 10000 }
camera: { position: [0, 0, 0], look_at: [0, 0, -1] }
materials:
  mirror: { diffuse: [0.5, 0.5, 0.5], reflection: 1 }
objects:
  - plane: { point: [0, 0, -1], normal: [0, 0, 1], material: mirror }
  - plane: { point: [0, 0, 1], normal: [0, 0, -1], material: mirror }
lights:
  - point: { position: [0, 0.5, 0], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";

/// Glass balls nested five deep: each glass surface reflects and transmits, so an eye sample
/// traces a tree, not a path. The bound once counted max_depth rays a sample (1.33e11 for the
/// job, no warning) while the tree holds up to 2^20 − 1, cut at the tracer's budget of 1024:
/// 140× the time the bound implied. Now the bound counts the tree and the warning fires.
#[test]
fn check_counts_a_glass_tree_in_the_cost() {
    let tmp = scratch("glass-cost");
    let balls: String = (1..=5)
        .map(|i| {
            format!(
                "  - sphere: {{ center: [0, 0, -3], radius: {}, material: glass }}\n",
                6 - i
            )
        })
        .collect();
    let yaml = format!(
        "render: {{ width: 640, height: 360, samples: 4, max_depth: 20 }}
camera: {{ position: [0, 0, 6], look_at: [0, 0, -3] }}
materials:
  glass: {{ diffuse: [0, 0, 0], transmission: [0.9, 0.9, 0.9], ior: 1.5, reflection: 0.1 }}
objects:
{balls}lights:
  - point: {{ position: [5, 5, 5], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
timeline: {{ fps: 24, keyframes: [ {{ time: 0 }}, {{ time: 30 }} ] }}
"
    );
    std::fs::write(tmp.join("nested.yaml"), yaml).unwrap();
    let check = run_in(&tmp, &["check", "nested.yaml"]);
    assert!(check.status.success(), "{}", stderr(&check));
    // `check` wraps lines past 120 columns under the summary's indent.
    let summary = String::from_utf8_lossy(&check.stdout).replace("\n              ", " ");
    // 640×360 pixels × 4 samples × (1 + 1 light) × 1024 surfaces, for 721 frames: the bound
    // beside the measured estimate.
    let frame = 640.0 * 360.0 * 4.0 * 2.0 * 1024.0;
    let bound = format!(
        "at most {:.2e} rays (an upper bound: pixels × samples × (1 + lights) × the surfaces of a glass or Fresnel tree: up to 2^max_depth − 1)",
        frame * 721.0
    );
    assert!(summary.contains(&bound), "{summary}");
    assert!(summary.contains(" for 721 frames (measured: "), "{summary}");
}

#[test]
fn one_sigterm_stops_a_monstrous_frame_within_seconds() {
    let tmp = scratch("monstrous");
    std::fs::write(tmp.join("huge.yaml"), MONSTROUS).unwrap();
    let check = run_in(&tmp, &["check", "huge.yaml"]);
    assert!(check.status.success(), "{}", stderr(&check));
    // The probe gives up after a few seconds: the estimate is a lower bound, beside the
    // ray count's upper one.
    let summary = String::from_utf8_lossy(&check.stdout).into_owned();
    assert!(summary.contains("cost:       at least "), "{summary}");
    assert!(
        summary.contains("at most 1.37e15 rays (an upper bound"),
        "{summary}"
    );
    assert!(stderr(&check).contains("warning: this job may take at least"));
    let dry = run_in(&tmp, &["render", "huge.yaml", "--dry-run"]);
    assert!(String::from_utf8_lossy(&dry.stdout).contains("at most 1.37e15 rays"));
    assert!(stderr(&dry).contains("warning: this job may take at least"));

    let mut child = bin()
        .args(["render", "huge.yaml", "-o", "out/f.png", "--threads", "2"])
        .current_dir(&tmp)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut first = String::new();
    std::io::BufRead::read_line(&mut err, &mut first).unwrap();
    assert!(first.contains("rendering 1"), "{first}");
    std::thread::sleep(std::time::Duration::from_millis(500));
    let sent = std::time::Instant::now();
    signal(&child, libc::SIGTERM);
    let out = ends_within(child, 20.0, "after SIGTERM");
    let seconds = sent.elapsed().as_secs_f64();
    let mut log = String::new();
    std::io::Read::read_to_string(&mut err, &mut log).unwrap();
    assert_eq!(out.status.code(), Some(143), "{log}");
    assert!(seconds < 5.0, "{seconds:.2} s to stop: {log}");
    assert!(
        log.contains("stopping on SIGTERM: the frame in flight is cancelled at the next pixel"),
        "{log}"
    );
    assert!(
        log.contains("interrupted: 0 frames written in this run"),
        "{log}"
    );
    assert!(
        files(&tmp.join("out")).is_empty(),
        "{:?}",
        files(&tmp.join("out"))
    );
}

#[test]
fn one_sigint_ends_a_stream_whose_reader_stalled() {
    let tmp = scratch("stalled");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let mut child = bin()
        .args([
            "render",
            "seq.yaml",
            "--pipe",
            "raw",
            "--size",
            "320x180",
            "--threads",
            "1",
        ])
        .current_dir(&tmp)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Read 14 frames, then stop reading with the pipe still open: a frame (172 800 bytes) is
    // more than a pipe holds, so the 15th is stuck half-written.
    let mut stdout = child.stdout.take().unwrap();
    let mut frames = vec![0u8; 14 * 320 * 180 * 3];
    std::io::Read::read_exact(&mut stdout, &mut frames).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    signal(&child, libc::SIGINT);
    let out = ends_within(child, 5.0, "after one SIGINT");
    drop(stdout);
    let log = stderr(&out);
    assert_eq!(out.status.code(), Some(130), "{log}");
    assert!(
        log.contains("interrupted: 14 frames streamed to stdout in this run"),
        "{log}"
    );
}

#[test]
fn thread_counts_the_machine_cannot_start_are_refused_at_once() {
    let tmp = scratch("threads");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let started = std::time::Instant::now();
    let child = bin()
        .args([
            "render",
            "seq.yaml",
            "-o",
            "a/f_####.png",
            "--threads",
            "65535",
        ])
        .current_dir(&tmp)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Once: "cannot start worker threads", then 9 minutes at 500 MB, deaf to SIGTERM.
    let out = ends_within(child, 10.0, "--threads 65535");
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("65535 is not in 1..=1024"),
        "{}",
        stderr(&out)
    );
    // 1000 threads under a 200 MB address space: the machine cannot start them.
    let limited = sh(
        &tmp,
        "ulimit -v 200000; $RAYREEL render seq.yaml -o b/f_####.png --threads 1000",
    );
    assert_eq!(limited.status.code(), Some(2), "{}", stderr(&limited));
    assert!(
        stderr(&limited).contains("--threads 1000: cannot start 1000 worker threads"),
        "{}",
        stderr(&limited)
    );
    assert!(started.elapsed().as_secs_f64() < 10.0);
    assert!(
        files(&tmp).iter().all(|f| f == "seq.yaml"),
        "{:?}",
        files(&tmp)
    );
}

/// out/ holds frames 0-3 as the clean render has them, and nothing else.
fn assert_first_four_clean(tmp: &Path) {
    let names = files(&tmp.join("out"));
    assert_eq!(names.len(), 4, "{names:?}");
    for name in names {
        let (a, b) = (tmp.join("out").join(&name), tmp.join("clean").join(&name));
        assert!(
            std::fs::read(a).unwrap() == std::fs::read(b).unwrap(),
            "{name}"
        );
    }
}

#[test]
fn claims_of_processes_that_are_gone_are_taken_over() {
    let tmp = with_clean_render("claims-gone", &small());
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let me = my_claim_owner();
    // A live pid (this test) that is not the process which wrote the claim: after pid reuse
    // or a container restart the start time differs, or the boot id does.
    let reused = me.replace(" start=", " start=1");
    let rebooted = me.replace(" boot=", " boot=0");
    std::fs::write(out.join(".f_0000.png.rayreel-claim"), &reused).unwrap();
    std::fs::write(out.join(".f_0001.png.rayreel-claim"), &rebooted).unwrap();
    // This very process, alive, but silent for an hour.
    let silent = out.join(".f_0002.png.rayreel-claim");
    std::fs::write(&silent, &me).unwrap();
    let hour_ago = std::time::SystemTime::now() - std::time::Duration::from_secs(3600);
    std::fs::File::options()
        .append(true)
        .open(&silent)
        .unwrap()
        .set_modified(hour_ago)
        .unwrap();
    finishes_within(
        claiming(&tmp, &["--claim-timeout", "60"]),
        30,
        "gone claims",
    );
    assert_first_four_clean(&tmp);
}

#[test]
fn a_worker_says_what_it_waits_for_and_goes_on_when_the_claim_goes() {
    let tmp = with_clean_render("claims-wait", &small());
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let claim = out.join(".f_0002.png.rayreel-claim");
    std::fs::write(&claim, my_claim_owner()).unwrap();
    let mut child = claiming(&tmp, &["--progress", "json"]);
    let err = std::io::BufReader::new(child.stderr.take().unwrap());
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufRead::lines(err) {
            let _ = tx.send(line.unwrap());
        }
    });
    let line = loop {
        match rx.recv_timeout(std::time::Duration::from_secs(20)) {
            Ok(line) if line.contains("\"event\": \"waiting\"") => break line,
            Ok(_) => {}
            Err(e) => {
                child.kill().unwrap();
                panic!("the worker did not say what it waits for: {e}");
            }
        }
    };
    let event: serde_yaml::Value = serde_yaml::from_str(&line).unwrap();
    assert_eq!(event["frames"], "2", "{line}");
    let held = &event["claims"][0];
    assert_eq!(held["path"], "out/.f_0002.png.rayreel-claim", "{line}");
    assert_eq!(
        held["owner"].as_str(),
        Some(my_claim_owner().as_str()),
        "{line}"
    );
    // The holder goes away without writing the frame: the worker renders it.
    std::fs::remove_file(&claim).unwrap();
    finishes_within(child, 30, "waiting worker");
    assert_first_four_clean(&tmp);
}
