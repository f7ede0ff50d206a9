//! Colour encoding, exposure, alpha and the compositing attributes of EXR frames, through the
//! binary: PNG and stream values against the EXR colour of the same frame, the sRGB chunks,
//! exposure in stops, coverage as alpha, camera matrices and finite depth read by oiiotool.

mod common;
use common::*;
use std::path::Path;

/// A red sphere filling the middle of the frame over a bright background, lit from the front,
/// with a mirror sphere that reflects the background.
const SCENE: &str = "
render: { width: 48, height: 32, max_depth: 3, background: [0.2, 0.5, 0.9] }
camera: { position: [0, 0, 3], look_at: [0, 0, 0], fov: 60 }
objects:
  - sphere: { center: [-0.3, 0, 0], radius: 0.8, material: { ambient: [0.05, 0, 0], diffuse: [0.8, 0.1, 0.05], specular: [0.6, 0.6, 0.6], shininess: 40 } }
  - sphere: { center: [0.8, 0.3, 0.5], radius: 0.35, material: { diffuse: [0.1, 0.1, 0.1], reflection: 0.9 } }
lights:
  - point: { position: [2, 3, 4], diffuse: [1.2, 1.2, 1.2], specular: [1, 1, 1] }
  - ambient: { color: [0.3, 0.3, 0.3] }
";

fn setup(name: &str) -> Scratch {
    let tmp = scratch(name);
    std::fs::write(tmp.join("s.yaml"), SCENE).unwrap();
    tmp
}

fn render(dir: &Path, args: &[&str]) -> std::process::Output {
    let out = run_in(dir, &[&["render", "s.yaml", "-q"][..], args].concat());
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    out
}

/// Every channel of an EXR frame by name, as f32.
fn exr_channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    let img = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    img.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| {
            let v = match &c.sample_data {
                exr::image::FlatSamples::F32(v) => v.clone(),
                exr::image::FlatSamples::F16(v) => v.iter().map(|h| h.to_f32()).collect(),
                other => panic!("{other:?}"),
            };
            (c.name.to_string(), v)
        })
        .collect()
}

fn channel(channels: &[(String, Vec<f32>)], name: &str) -> Vec<f32> {
    channels
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no {name}"))
        .1
        .clone()
}

/// The frame's colour as interleaved RGB from a float EXR.
fn exr_rgb(path: &Path) -> Vec<f32> {
    let c = exr_channels(path);
    let (r, g, b) = (channel(&c, "R"), channel(&c, "G"), channel(&c, "B"));
    (0..r.len()).flat_map(|i| [r[i], g[i], b[i]]).collect()
}

fn srgb(x: f64) -> f64 {
    if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// round(max · sRGB(clamp(c · 2^stops))), in f64.
fn encoded(c: f32, stops: f64, max: f64) -> f64 {
    let x = (f64::from(c) * stops.exp2()).clamp(0.0, 1.0);
    (max * srgb(x)).round()
}

/// The chunk types of a PNG file, in order.
fn chunks(path: &Path) -> Vec<String> {
    let bytes = std::fs::read(path).unwrap();
    let mut rest = &bytes[8..];
    let mut out = Vec::new();
    while rest.len() >= 12 {
        let len = u32::from_be_bytes(rest[..4].try_into().unwrap()) as usize;
        out.push(String::from_utf8_lossy(&rest[4..8]).into_owned());
        rest = &rest[12 + len..];
    }
    out
}

#[test]
fn png_and_stream_values_are_the_srgb_of_the_exr_colour() {
    let tmp = setup("srgb");
    render(&tmp, &["-o", "exr/f_####.exr", "--exr-precision", "float"]);
    let linear = exr_rgb(&tmp.join("exr/f_0000.exr"));
    for stops in ["0", "0.5", "-1.25"] {
        let e: f64 = stops.parse().unwrap();
        let png = format!("png{stops}/f_####.png");
        render(&tmp, &["-o", &png, "--exposure", stops]);
        let path = tmp.join(format!("png{stops}/f_0000.png"));
        let names = chunks(&path);
        let at = |c: &str| names.iter().position(|n| n == c).unwrap_or(usize::MAX);
        assert!(at("sRGB") < at("IDAT") && at("gAMA") < at("IDAT") && at("cHRM") < at("IDAT"));
        let (_, _, png) = read_png(&path);
        let raw = render(&tmp, &["--pipe", "raw", "--exposure", stops]).stdout;
        assert_eq!(raw, png, "the raw stream holds the PNG's values");
        let mut exact = 0;
        for (&c, &v) in linear.iter().zip(&png) {
            let want = encoded(c, e, 255.0);
            assert!(
                (f64::from(v) - want).abs() <= 1.0,
                "{c} at {stops}: {v} vs {want}"
            );
            exact += usize::from(f64::from(v) == want);
        }
        assert!(exact * 100 >= 99 * png.len(), "{exact} of {}", png.len());
    }
    let sixteen = render(&tmp, &["--pipe", "raw", "--bit-depth", "16"]).stdout;
    for (i, &c) in linear.iter().enumerate() {
        let v = u16::from_le_bytes([sixteen[2 * i], sixteen[2 * i + 1]]);
        assert!((f64::from(v) - encoded(c, 0.0, 65535.0)).abs() <= 1.0);
    }
}

/// `linear` writes round(255 · clamp(c, 0, 1)) of the f32 colour, halves up: the values every
/// frame had before encodings existed, tagged gamma 1.0.
#[test]
fn linear_encoding_writes_the_old_values() {
    let tmp = setup("linear");
    render(&tmp, &["-o", "exr/f_####.exr", "--exr-precision", "float"]);
    render(&tmp, &["-o", "png/f_####.png", "--encoding", "linear"]);
    let linear = exr_rgb(&tmp.join("exr/f_0000.exr"));
    let path = tmp.join("png/f_0000.png");
    let names = chunks(&path);
    assert!(names.contains(&"gAMA".into()) && !names.contains(&"sRGB".into()));
    let (_, _, png) = read_png(&path);
    for (&c, &v) in linear.iter().zip(&png) {
        let y = c.clamp(0.0, 1.0) * 255.0;
        let w = y.trunc();
        let want = if y - w >= 0.5 { w + 1.0 } else { w };
        assert_eq!(f32::from(v), want, "{c}");
    }
}

#[test]
fn exposure_doubles_every_linear_exr_value_per_stop() {
    let tmp = setup("exposure");
    render(&tmp, &["-o", "a/f_####.exr", "--exr-precision", "float"]);
    render(
        &tmp,
        &[
            "-o",
            "b/f_####.exr",
            "--exr-precision",
            "float",
            "--exposure",
            "1",
        ],
    );
    let (a, b) = (
        exr_rgb(&tmp.join("a/f_0000.exr")),
        exr_rgb(&tmp.join("b/f_0000.exr")),
    );
    assert!(a.iter().any(|&v| v > 0.0));
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(2.0 * x, *y);
    }
}

/// Coverage: 0 where every eye ray misses, 1 where all hit, fractional on antialiased edges;
/// EXR colour premultiplied by it, PNG colour straight; covered pixels keep the colour they
/// have without alpha, mirrored background included.
#[test]
fn alpha_is_the_coverage() {
    let tmp = setup("alpha");
    let float = ["--exr-precision", "float", "--samples", "16"];
    render(&tmp, &[&["-o", "opaque/f_####.exr"][..], &float].concat());
    render(
        &tmp,
        &[&["-o", "alpha/f_####.exr", "--alpha"][..], &float].concat(),
    );
    render(
        &tmp,
        &["-o", "png/f_####.png", "--alpha", "--samples", "16"],
    );
    let c = exr_channels(&tmp.join("alpha/f_0000.exr"));
    let a = channel(&c, "A");
    let (rgb, opaque) = (
        exr_rgb(&tmp.join("alpha/f_0000.exr")),
        exr_rgb(&tmp.join("opaque/f_0000.exr")),
    );
    let (w, h) = (48, 32);
    assert_eq!(a[0], 0.0, "a background corner");
    assert_eq!(a[16 * w + 18], 1.0, "the red sphere's middle");
    let edges = a.iter().filter(|&&v| v > 0.0 && v < 1.0).count();
    assert!(edges > 20, "{edges} fractional pixels");
    for i in 0..w * h {
        let px = &rgb[3 * i..3 * i + 3];
        if a[i] == 0.0 {
            assert_eq!(px, [0.0; 3], "transparent pixels hold nothing");
        }
        if a[i] == 1.0 {
            assert_eq!(px, &opaque[3 * i..3 * i + 3], "pixel {i}");
        }
    }
    let mirror = 11 * w + 35; // on the mirror sphere, reflecting the background
    assert_eq!(a[mirror], 1.0);
    assert!(
        rgb[3 * mirror + 2] > 0.5,
        "the mirror shows the blue background"
    );
    let img = image::open(tmp.join("png/f_0000.png")).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgba8);
    let png = img.to_rgba8().into_raw();
    for i in 0..w * h {
        assert!((f64::from(png[4 * i + 3]) - (255.0 * f64::from(a[i])).round()).abs() <= 1.0);
        if a[i] > 0.05 {
            for k in 0..3 {
                let straight = rgb[3 * i + k] / a[i];
                let want = encoded(straight, 0.0, 255.0);
                assert!((f64::from(png[4 * i + k]) - want).abs() <= 1.0, "pixel {i}");
            }
        }
    }
    let raw = render(&tmp, &["--pipe", "raw", "--alpha", "--samples", "16"]);
    assert_eq!(raw.stdout, png, "the raw stream is the PNG's rgba");
    let printed = run_in(
        &tmp,
        &[
            "render",
            "s.yaml",
            "--pipe",
            "raw",
            "--alpha",
            "--print-ffmpeg",
            "--frames",
            "0",
            "-q",
        ],
    );
    assert!(
        stderr(&printed).contains("-pix_fmt rgba "),
        "{}",
        stderr(&printed)
    );
    if have_tool("oiiotool") {
        for f in ["png/f_0000.png", "alpha/f_0000.exr"] {
            let out = sh(&tmp, &format!("oiiotool --info -v {f}"));
            assert!(
                String::from_utf8_lossy(&out.stdout).contains("R, G, B, A"),
                "{f}"
            );
        }
    }
    if have_tool("ffmpeg") {
        let out = sh(
            &tmp,
            "\"$RAYREEL\" render s.yaml --pipe raw --alpha -q | ffmpeg -v error -f rawvideo -pix_fmt rgba -s 48x32 -i - -c:v prores_ks -profile:v 4444 -pix_fmt yuva444p10le -f null -",
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// worldToNDC sends the red sphere's front point to its pixel, where Z is its planar depth;
/// oiiotool reads both matrices, and no channel holds NaN or Inf even after `--mulc 0`.
#[test]
fn exr_frames_carry_camera_matrices_and_finite_depth() {
    let tmp = setup("matrices");
    render(
        &tmp,
        &[
            "-o",
            "f/f_####.exr",
            "--alpha",
            "--depth",
            "--exr-precision",
            "float",
        ],
    );
    let path = tmp.join("f/f_0000.exr");
    let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
    let attrs = &meta.headers[0].own_attributes;
    let (to_cam, to_ndc) = (
        attrs.world_to_camera.unwrap(),
        attrs.world_to_normalized_device.unwrap(),
    );
    let row = |m: &[f32; 16], p: [f64; 3]| -> [f64; 4] {
        std::array::from_fn(|j| {
            (0..3).map(|i| p[i] * f64::from(m[4 * i + j])).sum::<f64>() + f64::from(m[12 + j])
        })
    };
    let cam = row(&to_cam, [0.0, 0.0, 3.0]);
    assert!(cam[..3].iter().all(|v| v.abs() < 1e-6), "{cam:?}");
    let front = [-0.3, 0.0, 0.8]; // the red sphere's pole facing the camera
    let c = row(&to_cam, front);
    let n = row(&to_ndc, front);
    let (col, line) = ((n[0] / n[3] * 48.0) as usize, (n[1] / n[3] * 32.0) as usize);
    assert_eq!((col, line), (18, 16));
    let channels = exr_channels(&path);
    let z = channel(&channels, "Z")[line * 48 + col];
    assert!(
        (f64::from(z) - c[2]).abs() < 0.02,
        "Z {z} vs camera z {}",
        c[2]
    );
    assert_eq!(channel(&channels, "Z")[0], 1e10, "background");
    if have_tool("oiiotool") {
        let info = sh(&tmp, "oiiotool --info -v f/f_0000.exr");
        let info = String::from_utf8_lossy(&info.stdout);
        assert!(
            info.contains("worldToCamera:") && info.contains("worldToNDC:"),
            "{info}"
        );
        let stats = sh(&tmp, "oiiotool f/f_0000.exr --mulc 0 --printstats");
        let stats = String::from_utf8_lossy(&stats.stdout);
        for line in stats
            .lines()
            .filter(|l| l.contains("NanCount") || l.contains("InfCount"))
        {
            assert!(
                line.split(':')
                    .nth(1)
                    .unwrap()
                    .split_whitespace()
                    .all(|v| v == "0"),
                "{line}"
            );
        }
        assert!(stats.contains("NanCount"), "{stats}");
    }
}

/// A file that sets no sampling gets 2 samples, adaptive up to 8.
#[test]
fn default_sampling_is_adaptive_two_to_eight() {
    let tmp = setup("defaults");
    let explicit = SCENE.replace(
        "max_depth: 3,",
        "max_depth: 3, samples: 2, adaptive: { max_samples: 8 },",
    );
    std::fs::write(tmp.join("e.yaml"), explicit).unwrap();
    render(&tmp, &["-o", "d/f_####.png"]);
    let out = run_in(&tmp, &["render", "e.yaml", "-q", "-o", "e/f_####.png"]);
    assert!(out.status.success());
    let one = render(&tmp, &["--pipe", "raw", "--samples", "1"]).stdout;
    let (_, _, d) = read_png(&tmp.join("d/f_0000.png"));
    let (_, _, e) = read_png(&tmp.join("e/f_0000.png"));
    assert_eq!(d, e);
    assert_ne!(d, one);
}

/// Frames stay up to date while their settings hold, and turn stale when an encoding,
/// exposure or alpha changes their bytes; a PNG's encoding never makes an EXR stale.
#[test]
fn fingerprints_cover_encoding_exposure_and_alpha() {
    let tmp = setup("fingerprints");
    render(&tmp, &["-o", "p/f_####.png"]);
    render(&tmp, &["-o", "x/f_####.exr"]);
    let status = |args: &[&str]| {
        run_in(&tmp, &[&["status", "s.yaml"][..], args].concat())
            .status
            .code()
    };
    assert_eq!(status(&["-o", "p/f_####.png"]), Some(0));
    assert_eq!(
        status(&["-o", "p/f_####.png", "--encoding", "srgb"]),
        Some(0)
    );
    for changed in [
        &["--encoding", "linear"][..],
        &["--exposure", "1"],
        &["--alpha"],
    ] {
        assert_eq!(
            status(&[&["-o", "p/f_####.png"][..], changed].concat()),
            Some(1),
            "{changed:?}"
        );
    }
    assert_eq!(
        status(&["-o", "x/f_####.exr", "--encoding", "linear"]),
        Some(0)
    );
    assert_eq!(status(&["-o", "x/f_####.exr", "--exposure", "1"]), Some(1));
}

#[test]
fn measure_names_the_encoding_of_its_errors() {
    let tmp = setup("measure");
    for (flag, name) in [("srgb", "srgb"), ("linear", "linear")] {
        let out = run_in(
            &tmp,
            &[
                "measure",
                "s.yaml",
                "--size",
                "16x10",
                "--runs",
                "1",
                "--encoding",
                flag,
                "--out",
                "m",
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let table = String::from_utf8_lossy(&out.stdout);
        assert!(
            table.contains(&format!("errors on the 8-bit {name} values")),
            "{table}"
        );
        let json = std::fs::read_to_string(tmp.join("m/measure.json")).unwrap();
        assert!(json.contains(&format!("\"encoding\": \"{name}\"")));
    }
}
