//! EXR frames, 16-bit PNGs and frame streams, checked with the exr crate and with the real
//! tools (ffmpeg, ffprobe, oiiotool) where installed; CI sets RAYREEL_REQUIRE_TOOLS=1.

mod common;
use common::*;
use rayreel::sequence;

fn orbit() -> String {
    repo()
        .join("sequences/orbit.yaml")
        .to_str()
        .unwrap()
        .to_string()
}

fn read_exr(path: &std::path::Path) -> exr::image::FlatImage {
    exr::prelude::read_all_flat_layers_from_file(path).unwrap()
}

fn channel<'a>(img: &'a exr::image::FlatImage, name: &str) -> &'a exr::image::FlatSamples {
    let layer = &img.layer_data[0];
    let c = layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .unwrap_or_else(|| panic!("no {name}"));
    &c.sample_data
}

#[test]
fn exr_round_trip_keeps_the_tracers_floats_and_depth() {
    let tmp = scratch("exr");
    let yaml = "
render: { width: 9, height: 5, max_depth: 2 }
camera: { position: [0, 0, 3], look_at: [0, 0, 0] }
objects:
  - sphere: { center: [0, 0, -2], radius: 1, material: { diffuse: [0.9, 0.5, 0.1], specular: [3, 3, 3], shininess: 20, reflection: 0.2 } }
lights:
  - point: { position: [0, 0, 5], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";
    std::fs::write(tmp.join("s.yaml"), yaml).unwrap();
    for (flag, float) in [("float", true), ("half", false)] {
        let pattern = format!("{flag}/f_####.exr");
        let out = run_in(
            &tmp,
            &[
                "render",
                "s.yaml",
                "-o",
                &pattern,
                "--depth",
                "--exr-precision",
                flag,
                "-q",
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let img = read_exr(&tmp.join(format!("{flag}/f_0000.exr")));
        let names: Vec<String> = img.layer_data[0]
            .channel_data
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect();
        assert_eq!(names, ["B", "G", "R", "Z"]);
        assert_eq!(img.layer_data[0].size, exr::math::Vec2(9, 5));

        let mut seq = sequence::parse(&tmp.join("s.yaml"), yaml).unwrap();
        seq.settings.depth = true;
        let frame = rayreel::schedule::render_frame(&seq, 0).unwrap();
        let centre = 2 * 9 + 4;
        let want = frame.pixel(2, 4)[0];
        assert!(
            want > 1.0,
            "the highlight must exceed 1 to test unclamped output ({want})"
        );
        let got = channel(&img, "R").value_by_flat_index(centre).to_f32();
        if float {
            assert_eq!(got, want);
        } else {
            assert_eq!(got, half::f16::from_f32(want).to_f32());
        }
        // The centre pixel's eye ray runs straight from z = 3 to the sphere's front at z = −1;
        // background is far but finite.
        let z = channel(&img, "Z").value_by_flat_index(centre).to_f32();
        assert!((z - 4.0).abs() < 1e-6, "{z}");
        assert_eq!(channel(&img, "Z").value_by_flat_index(0).to_f32(), 1e10);
    }
}

/// Renders frame 0 of orbit.yaml at 64x36 to `pattern` with `extra` flags, quietly.
fn frame_zero(dir: &std::path::Path, pattern: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "render", "ORBIT", "--size", "64x36", "--frames", "0", "-o", pattern, "-q",
    ];
    args.extend(extra);
    let orbit = orbit();
    args[1] = &orbit;
    run_in(dir, &args)
}

#[test]
fn sixteen_bit_png_holds_the_finer_values() {
    let tmp = scratch("png16");
    let out = frame_zero(&tmp, "a/f_####.png", &[]);
    assert!(out.status.success());
    let out = frame_zero(&tmp, "b/f_####.png", &["--bit-depth", "16"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let img8 = image::open(tmp.join("a/f_0000.png")).unwrap().to_rgb8();
    let img16 = image::open(tmp.join("b/f_0000.png")).unwrap();
    assert_eq!(img16.color(), image::ColorType::Rgb16);
    let img16 = img16.to_rgb16();
    for (a, b) in img8.as_raw().iter().zip(img16.as_raw()) {
        assert!((f64::from(*a) - f64::from(*b) / 257.0).abs() <= 0.5 + 1e-9);
    }
}

#[test]
fn raw_stream_is_frames_in_order_and_nothing_else() {
    let tmp = scratch("raw");
    let out = run_in(
        &tmp,
        &[
            "render",
            &orbit(),
            "--size",
            "32x18",
            "--frames",
            "0-11",
            "--pipe",
            "raw",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(out.stdout.len(), 12 * 32 * 18 * 3);
    assert!(files(&tmp).is_empty(), "--pipe alone writes no files");
    // Frame 5 of the stream equals frame 5 rendered to a file.
    let out2 = run_in(
        &tmp,
        &[
            "render",
            &orbit(),
            "--size",
            "32x18",
            "--frames",
            "5",
            "-o",
            "f_####.png",
            "-q",
        ],
    );
    assert!(out2.status.success());
    let (_, _, png) = read_png(&tmp.join("f_0005.png"));
    assert_eq!(&out.stdout[5 * 1728..6 * 1728], &png[..]);
    // Files and a stream in one run.
    let out3 = run_in(
        &tmp,
        &[
            "render",
            &orbit(),
            "--size",
            "32x18",
            "--frames",
            "0-2",
            "--pipe",
            "png",
            "-o",
            "both/f_####.png",
            "-q",
        ],
    );
    assert!(out3.status.success());
    assert_eq!(files(&tmp.join("both")).len(), 3);
    assert_eq!(
        out3.stdout
            .windows(8)
            .filter(|w| *w == b"\x89PNG\r\n\x1a\n")
            .count(),
        3
    );
}

#[test]
fn ffmpeg_reads_the_raw_stream_losslessly() {
    if !have_tool("ffmpeg") || !have_tool("ffprobe") {
        return;
    }
    let tmp = scratch("ffmpeg");
    let script = r#"
$RAYREEL render "$1" --size 64x36 --frames 0-47 --pipe raw --quiet | ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgb24 -s 64x36 -r 24 -i - -c:v ffv1 out.mkv
ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 out.mkv
ffmpeg -loglevel error -y -i out.mkv -frames:v 1 -f rawvideo -pix_fmt rgb24 first.rgb
$RAYREEL render "$1" --size 64x36 --frames 0 -o f_####.png --quiet
"#;
    let out = sh(&tmp, &format!("set -- {}; {script}", orbit()));
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "48");
    let first = std::fs::read(tmp.join("first.rgb")).unwrap();
    assert_eq!(first, read_png(&tmp.join("f_0000.png")).2);
}

#[test]
fn a_reader_that_stops_early_ends_the_run_cleanly() {
    if !have_tool("ffmpeg") {
        return;
    }
    let tmp = scratch("early");
    for reader in [
        "head -c 10000 > /dev/null",
        "ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgb24 -s 320x180 -r 24 -i - -frames:v 10 -c:v ffv1 out.mkv",
    ] {
        let script = format!(
            "$RAYREEL render {} --size 320x180 --pipe raw 2>err.txt | {reader}; echo ${{PIPESTATUS[0]}}",
            orbit()
        );
        let out = sh(&tmp, &script);
        let err = std::fs::read_to_string(tmp.join("err.txt")).unwrap();
        assert_eq!(
            String::from_utf8_lossy(&out.stdout).trim(),
            "0",
            "{reader}: {err}"
        );
        assert!(
            err.contains("the reader closed the stream"),
            "{reader}: {err}"
        );
        assert!(
            !err.contains("panicked") && !err.contains("backtrace"),
            "{err}"
        );
    }
}

#[test]
fn oiiotool_reads_exr_with_depth_and_no_nan() {
    if !have_tool("oiiotool") {
        return;
    }
    let tmp = scratch("oiio");
    let out = frame_zero(&tmp, "e/f_####.exr", &["--depth"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = frame_zero(&tmp, "p/f_####.png", &["--encoding", "linear"]);
    assert!(out.status.success());
    let stats = sh(&tmp, "oiiotool --stats e/f_0000.exr");
    let text = String::from_utf8_lossy(&stats.stdout);
    assert!(
        stats.status.success() && text.contains("4 channel"),
        "{text}"
    );
    let nan = text.lines().find(|l| l.contains("NanCount")).unwrap();
    assert_eq!(
        nan.split_whitespace().skip(2).collect::<Vec<_>>(),
        ["0", "0", "0", "0"],
        "{text}"
    );
    let info = sh(&tmp, "oiiotool --info -v e/f_0000.exr");
    assert!(
        String::from_utf8_lossy(&info.stdout).contains("R (half), G (half), B (half), Z (float)")
    );
    // An 8-bit clamp of the EXR matches the linear PNG of the same frame within 1/255.
    let conv = sh(
        &tmp,
        "oiiotool e/f_0000.exr --ch R,G,B --clamp:min=0:max=1 -d uint8 -o clamped.png",
    );
    assert!(conv.status.success(), "{}", stderr(&conv));
    let (_, _, a) = read_png(&tmp.join("clamped.png"));
    let (_, _, b) = read_png(&tmp.join("p/f_0000.png"));
    assert!(a.iter().zip(&b).all(|(x, y)| x.abs_diff(*y) <= 1));
}

/// Peak resident memory (VmHWM) of a raw stream of `frames` frames read by a reader that
/// sleeps between frames.
fn peak_kb_with_slow_reader(frames: u64) -> u64 {
    use std::io::Read;
    let spec = format!("0-{}", frames - 1);
    let mut child = bin()
        .args([
            "render",
            &orbit(),
            "--size",
            "640x360",
            "--pipe",
            "raw",
            "-q",
            "--frames",
            &spec,
        ])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    let mut out = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut buf = vec![0u8; 640 * 360 * 3];
        let mut n = 0;
        while out.read_exact(&mut buf).is_ok() {
            n += 1;
            std::thread::sleep(std::time::Duration::from_millis(15));
        }
        n
    });
    let mut peak = 0;
    while let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) {
        if let Some(kb) = status.lines().find_map(|l| l.strip_prefix("VmHWM:")) {
            peak = peak.max(
                kb.trim()
                    .trim_end_matches(" kB")
                    .trim()
                    .parse()
                    .unwrap_or(0),
            );
        }
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    assert!(child.wait().unwrap().success());
    assert_eq!(reader.join().unwrap(), frames);
    peak
}

#[test]
fn a_slow_reader_does_not_grow_memory() {
    // Both runs long enough to fill the window of frames in flight (threads + 2).
    let (short, long) = (peak_kb_with_slow_reader(24), peak_kb_with_slow_reader(72));
    // 640x360 frames: 2.7 MB as floats, 0.7 MB as rgb24. Growth with the length would be
    // 0.7 MB a frame held for the reader (34 MB more for 48 more frames); the allowance is
    // 10% and one frame's float planes, which a run may or may not hold at its peak
    // depending on how rendering and encoding overlap on a loaded machine.
    const FRAME_KB: u64 = 640 * 360 * 12 / 1024;
    assert!(long < 40_000, "peak {long} kB");
    assert!(
        long * 10 < short * 11 + 10 * FRAME_KB,
        "peak grew from {short} kB to {long} kB"
    );
}
