//! Texture maps end to end: the exact coordinate rules of every object kind, image decoding
//! and mip levels, the footprint filter that keeps a checker to the horizon free of moiré at
//! one sample, the fingerprint, and bad input.

mod common;

use common::{read_png, run_in, scratch, stderr};
use glam::DVec3;
use rayreel::scene::Texture;
use rayreel::sequence::{self, Sequence};
use rayreel::shutter::Exposure;
use rayreel::tracer::intersect::Ray;
use rayreel::tracer::{self, World, path};
use std::path::Path;

/// A 2×2 RGB PNG, 8 bits, texels row by row from the top.
fn png_2x2(path: &Path, texels: [[u8; 3]; 4]) {
    let file = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(file, 2, 2);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&texels.concat()).unwrap();
}

const TEXELS: [[u8; 3]; 4] = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 0]];

/// The texel's linear value as the spec decodes sRGB.
fn linear(v: u8) -> f64 {
    let x = f64::from(v) / 255.0;
    let y = if x <= 0.04045 {
        x / 12.92
    } else {
        libm::pow((x + 0.055) / 1.055, 2.4)
    };
    f64::from(y as f32)
}

/// Texture coordinates of the four texel centres, in the order of `TEXELS`.
const CENTRES: [(f64, f64); 4] = [(0.25, 0.75), (0.75, 0.75), (0.25, 0.25), (0.75, 0.25)];

fn texel(i: usize) -> DVec3 {
    DVec3::from_array(TEXELS[i].map(linear))
}

/// A scene lit only by an ambient light of 1, whose material's ambient is the map: a ray's
/// colour is the texture's value.
fn ambient_scene(dir: &Path, object: &str, map: &str) -> Sequence {
    let yaml = format!(
        "camera: {{ position: [0, 0, 10], look_at: [0, 0, 0] }}
materials:
  m: {{ ambient: {map}, diffuse: [0, 0, 0] }}
objects:
  - {object}
lights:
  - ambient: {{ color: [1, 1, 1] }}
"
    );
    std::fs::write(dir.join("seq.yaml"), yaml).unwrap();
    sequence::load(&dir.join("seq.yaml")).unwrap()
}

fn ray_colour(seq: &Sequence, origin: DVec3, towards: DVec3) -> DVec3 {
    let world = World::new(seq.scene.clone());
    let ray = Ray {
        origin,
        dir: (towards - origin).normalize(),
        leaving: None,
    };
    path::trace(&world, ray, 1)
}

fn close(a: DVec3, b: DVec3, what: &str) {
    assert!((a - b).abs().max_element() < 1e-6, "{what}: {a} vs {b}");
}

/// Texel centres of a 2×2 image on a floor: u along +x, v along −z, row 0 at v = 1.
#[test]
fn a_floor_maps_u_along_x_and_v_along_minus_z() {
    let tmp = scratch("tex-plane");
    png_2x2(&tmp.join("t.png"), TEXELS);
    let seq = ambient_scene(
        &tmp,
        "plane: { point: [0, 0, 0], normal: [0, 1, 0], material: m }",
        "{ image: t.png }",
    );
    for (i, (u, v)) in CENTRES.into_iter().enumerate() {
        let p = DVec3::new(u, 0.0, -v);
        close(
            ray_colour(&seq, p + DVec3::Y, p),
            texel(i),
            &format!("texel {i}"),
        );
    }
    // `scale: [2, 2]` repeats twice per unit; `u_axis` turns the map.
    let seq = ambient_scene(
        &tmp,
        "plane: { point: [0, 0, 0], normal: [0, 1, 0], u_axis: [0, 0, -1], material: m }",
        "{ image: t.png, scale: [2, 2] }",
    );
    // u along −z, v = N × U = y × (−z) = −x.
    let p = DVec3::new(-0.375, 0.0, -0.125);
    close(
        ray_colour(&seq, p + DVec3::Y, p),
        texel(0),
        "u_axis and scale",
    );
}

/// A sphere: u = 0.5 − atan2(q.z, q.x)/2π, v = 1 − acos(q.y)/π.
#[test]
fn a_sphere_maps_longitude_and_latitude_with_north_at_the_top() {
    let tmp = scratch("tex-sphere");
    png_2x2(&tmp.join("t.png"), TEXELS);
    let seq = ambient_scene(
        &tmp,
        "sphere: { center: [1, 2, 3], radius: 2, material: m }",
        "{ image: t.png }",
    );
    let centre = DVec3::new(1.0, 2.0, 3.0);
    let pi = std::f64::consts::PI;
    for (i, (u, v)) in CENTRES.into_iter().enumerate() {
        let (phi, theta) = ((0.5 - u) * 2.0 * pi, (1.0 - v) * pi);
        let q = DVec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        );
        let hit = ray_colour(&seq, centre + q * 5.0, centre);
        close(hit, texel(i), &format!("texel {i}"));
    }
}

/// A mesh takes its file's texture coordinates, blended by the hit's barycentrics.
#[test]
fn a_mesh_takes_its_file_uvs() {
    let tmp = scratch("tex-mesh");
    png_2x2(&tmp.join("t.png"), TEXELS);
    std::fs::write(
        tmp.join("quad.obj"),
        "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
    let seq = ambient_scene(
        &tmp,
        "mesh: { file: quad.obj, material: m }",
        "{ image: t.png }",
    );
    for (i, (u, v)) in CENTRES.into_iter().enumerate() {
        let p = DVec3::new(4.0 * u, 4.0 * v, 0.0);
        close(
            ray_colour(&seq, p + DVec3::Z, p),
            texel(i),
            &format!("texel {i}"),
        );
    }
}

/// Point samples of the checker (a single ray has no footprint): even cell sums give the
/// first colour; a floor at y = 0 sits on a cell boundary and takes the cell above it.
#[test]
fn the_checker_takes_the_first_colour_on_even_cells() {
    let tmp = scratch("tex-checker");
    let seq = ambient_scene(
        &tmp,
        "plane: { point: [0, 0, 0], normal: [0, 1, 0], material: m }",
        "{ checker: { size: 0.5, colors: [[1, 1, 1], [0, 0, 0]] } }",
    );
    for (x, z, even) in [
        (0.1, 0.1, true),
        (0.6, 0.1, false),
        (0.6, -0.1, true),
        (-0.3, 7.3, false),
        (-0.3, 7.6, true),
    ] {
        let p = DVec3::new(x, 0.0, z);
        let c = ray_colour(&seq, p + DVec3::new(0.3, 1.0, 0.2), p);
        let want = if even { DVec3::ONE } else { DVec3::ZERO };
        assert_eq!(c, want, "({x}, {z})");
    }
}

/// Mip levels halve (rounding up) down to 1×1, each texel the mean of four, wrapping; 8-bit
/// codes decode through the exact sRGB curve.
#[test]
fn images_decode_to_linear_and_build_their_pyramid() {
    let tmp = scratch("tex-mip");
    png_2x2(&tmp.join("t.png"), TEXELS);
    let seq = ambient_scene(
        &tmp,
        "plane: { point: [0, 0, 0], normal: [0, 1, 0], material: m }",
        "{ image: t.png }",
    );
    let Some(Texture::Image { image, .. }) = &seq.scene.materials[0].ambient_map else {
        panic!("an image map");
    };
    assert_eq!(image.levels.len(), 2);
    assert_eq!((image.levels[1].width, image.levels[1].height), (1, 1));
    let t = |i: usize| image.levels[0].texels[i];
    for (i, want) in (0..4).map(|i| (i, texel(i))) {
        assert_eq!(DVec3::from_array(t(i).map(f64::from)), want, "texel {i}");
    }
    let mean: [f32; 3] =
        std::array::from_fn(|c| ((t(0)[c] + t(1)[c]) + (t(2)[c] + t(3)[c])) * 0.25);
    assert_eq!(image.levels[1].texels[0], mean);
    // `encoding: linear` takes the codes as they are; an odd width wraps.
    let file = std::fs::File::create(tmp.join("odd.png")).unwrap();
    let mut enc = png::Encoder::new(file, 3, 1);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&[0, 0, 0x80, 0x00, 0xff, 0xff]).unwrap();
    drop(w);
    let seq = ambient_scene(
        &tmp,
        "plane: { point: [0, 0, 0], normal: [0, 1, 0], material: m }",
        "{ image: odd.png, encoding: linear }",
    );
    let Some(Texture::Image { image, .. }) = &seq.scene.materials[0].ambient_map else {
        panic!("an image map");
    };
    let widths: Vec<u32> = image.levels.iter().map(|l| l.width).collect();
    assert_eq!(widths, [3, 2, 1]);
    let v = |l: usize, i: usize| image.levels[l].texels[i][0];
    assert_eq!(v(0, 1), (32768.0 / 65535.0) as f32);
    // Level 1 texel 1 averages columns 2 and 0 (wrapped), each counted twice (height 1).
    assert_eq!(v(1, 1), ((v(0, 2) + v(0, 0)) + (v(0, 2) + v(0, 0))) * 0.25);
}

const FLOOR: &str = "render: { width: 240, height: 136, max_depth: 1, samples: 1, encoding: linear, background: [0.5, 0.5, 0.5] }
camera: { position: [0.3, 1, 0], look_at: [0.3, 0.6, -10], fov: 90 }
materials:
  tiles: { ambient: { checker: { size: 1, colors: [[1, 1, 1], [0, 0, 0]] } }, diffuse: [0, 0, 0] }
objects:
  - plane: { point: [0, 0, 0], normal: [0, 1, 0], material: tiles }
lights:
  - ambient: { color: [1, 1, 1] }
";

fn frame(seq: &Sequence, world: &World, samples: u32) -> Vec<f32> {
    let settings = tracer::Settings {
        samples,
        adaptive: None,
        ..seq.settings
    };
    let exposure = Exposure::of_frame(&seq.timeline, None, 0).unwrap();
    tracer::render(world, &exposure, &settings, 0).rgb
}

fn psnr(a: &[f32], b: &[f32]) -> f64 {
    let mse = a
        .iter()
        .zip(b)
        .map(|(x, y)| f64::from(x.clamp(0.0, 1.0) - y.clamp(0.0, 1.0)).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    10.0 * (1.0 / mse).log10()
}

/// The classic test: a checker floor to the horizon at one sample per pixel. Filtered over
/// each ray's pixel it is close to a reference of 256 point samples a pixel (the pixel's true
/// mean, which no filter of rayreel's shapes); point-sampled it is not.
#[test]
fn one_sample_of_a_checker_to_the_horizon_shows_no_moire() {
    let tmp = scratch("tex-moire");
    std::fs::write(tmp.join("seq.yaml"), FLOOR).unwrap();
    let seq = sequence::load(&tmp.join("seq.yaml")).unwrap();
    let world = World::new(seq.scene.clone());
    let reference = frame(&seq, &world.clone().point_sampled(), 256);
    let filtered = frame(&seq, &world, 1);
    let point = frame(&seq, &world.clone().point_sampled(), 1);
    let (f, p) = (psnr(&filtered, &reference), psnr(&point, &reference));
    eprintln!("1 sample against 256: filtered {f:.1} dB, point-sampled {p:.1} dB");
    assert!(f >= 30.0, "filtered {f:.1} dB");
    assert!(f > p + 6.0, "filtered {f:.1} dB, point-sampled {p:.1} dB");
    // Far rows, just below the horizon, take the pixels' means (grey, or the moiré a box
    // filter itself shows) instead of aliasing into black and white as point samples do.
    let w = 240;
    let horizon = (0..136)
        .find(|&r| (0..w).any(|c| filtered[3 * (r * w + c)] != 0.5))
        .unwrap();
    let far = |frame: &[f32]| {
        (horizon..horizon + 4)
            .flat_map(|r| (0..w).map(move |c| 3 * (r * w + c)))
            .map(|i| (frame[i] - reference[i]).abs())
            .fold(0.0, f32::max)
    };
    let (f, p) = (far(&filtered), far(&point));
    // (The parallelogram is a first-order pixel there, and beyond 32 rows of cells the taps'
    // grey takes over.)
    assert!(f < 0.3, "filtered far rows up to {f} from the reference");
    assert!(
        p > f + 0.15,
        "point-sampled far rows up to {p}, filtered {f}"
    );
}

/// A checker at an eye ray's first hit reads the mean over the ray's pixel (docs/spec/texture.md,
/// **The pixel**): every sample of a pixel on a flat floor reads the same value, so a pixel's
/// colour does not depend on how many samples it takes, cell edges included; and that value
/// is the pixel's box-filtered checker, which many point samples approach.
#[test]
fn a_checker_at_the_eye_is_averaged_over_the_whole_pixel() {
    let tmp = scratch("tex-pixel");
    let down = FLOOR
        .replace("look_at: [0.3, 0.6, -10]", "look_at: [0.3, -2, -2]")
        .replace("size: 1,", "size: 0.1,");
    std::fs::write(tmp.join("seq.yaml"), &down).unwrap();
    let seq = sequence::load(&tmp.join("seq.yaml")).unwrap();
    let world = World::new(seq.scene.clone());
    let one = frame(&seq, &world, 1);
    let sixteen = frame(&seq, &world, 16);
    let edges = one.iter().filter(|&&v| v > 0.05 && v < 0.95).count();
    assert!(edges * 20 > one.len(), "{edges} pixels on cell edges");
    let most = one
        .iter()
        .zip(&sixteen)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    assert!(most < 1e-5, "1 and 16 samples differ by {most}");
    // Point samples converge on the same box filter.
    let point = frame(&seq, &world.clone().point_sampled(), 256);
    let p = psnr(&one, &point);
    assert!(p > 40.0, "one sample against 256 point samples: {p:.1} dB");
}

/// Through the binary: a textured frame renders, `check` lists the texture, a changed
/// texture file makes the frame stale, and the same frame comes out of any thread count.
#[test]
fn textured_frames_render_check_and_go_stale_with_their_file() {
    let tmp = scratch("tex-binary");
    png_2x2(&tmp.join("t.png"), TEXELS);
    let yaml = "render: { width: 64, height: 36 }
camera: { position: [0, 1, 3], look_at: [0, 0, 0] }
materials:
  globe: { diffuse: { image: t.png }, specular: [0.3, 0.3, 0.3] }
  tiles: { diffuse: { checker: { size: 0.5, colors: [[0.9, 0.9, 0.9], [0.1, 0.1, 0.1]] } }, reflection: 0.3 }
objects:
  - sphere: { center: [0, 0.5, 0], radius: 0.5, material: globe }
  - plane: { point: [0, 0, 0], normal: [0, 1, 0], material: tiles }
lights:
  - point: { position: [3, 4, 5], ambient: [0.2, 0.2, 0.2], diffuse: [1, 1, 1], specular: [1, 1, 1] }
output: out/f_####.png
";
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    let out = run_in(&tmp, &["check", "seq.yaml"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(text.contains("t.png 2x2, 2 mip levels"), "{text}");
    assert!(text.contains("1 checker map"), "{text}");
    let out = run_in(&tmp, &["render", "seq.yaml", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let one = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-q",
            "--threads",
            "1",
            "-o",
            "one/f_####.png",
        ],
    );
    assert!(one.status.success(), "{}", stderr(&one));
    let (a, b) = (
        read_png(&tmp.join("out/f_0000.png")),
        read_png(&tmp.join("one/f_0000.png")),
    );
    assert_eq!(a.2, b.2, "one thread and many");
    let status = run_in(&tmp, &["status", "seq.yaml"]);
    assert!(
        String::from_utf8_lossy(&status.stdout).contains("1 up to date"),
        "{}",
        String::from_utf8_lossy(&status.stdout)
    );
    png_2x2(
        &tmp.join("t.png"),
        [[1, 2, 3], [4, 5, 6], [7, 8, 9], [10, 11, 12]],
    );
    let status = run_in(&tmp, &["status", "seq.yaml"]);
    assert!(
        String::from_utf8_lossy(&status.stdout).contains("1 stale"),
        "{}",
        String::from_utf8_lossy(&status.stdout)
    );
}

/// Bad texture input: a clear message naming the file, the line and the field; exit 2.
#[test]
fn bad_textures_are_refused_with_file_line_and_field() {
    let tmp = scratch("tex-bad");
    png_2x2(&tmp.join("t.png"), TEXELS);
    std::fs::write(tmp.join("junk.png"), b"not a png at all").unwrap();
    std::fs::write(tmp.join("quad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    // A PNG whose header claims 20000×20000 pixels: refused before any decoding.
    let mut huge = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut huge, 20000, 1);
        enc.set_color(png::ColorType::Grayscale);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&vec![0; 20000]).unwrap();
    }
    std::fs::write(tmp.join("wide.png"), huge).unwrap();
    // A FIFO at a texture's name is refused without blocking the load.
    let fifo = std::ffi::CString::new(tmp.join("pipe.png").to_str().unwrap()).unwrap();
    // SAFETY: mkfifo reads a valid NUL-terminated path and nothing else.
    assert_eq!(unsafe { libc::mkfifo(fifo.as_ptr(), 0o644) }, 0);
    let plane = |map: &str| {
        format!(
            "camera: {{ position: [0, 1, 3], look_at: [0, 0, 0] }}\nobjects:\n  - plane: {{ point: [0, 0, 0], normal: [0, 1, 0], material: {{ diffuse: {map} }} }}\n"
        )
    };
    let cases = [
        (plane("{ image: missing.png }"), "objects[0].plane.material.diffuse.image", "cannot read"),
        (plane("{ image: junk.png }"), "objects[0].plane.material.diffuse.image", "unreadable PNG"),
        (plane("{ image: wide.png }"), "objects[0].plane.material.diffuse.image", "16384 pixels a side"),
        (plane("{ image: pipe.png }"), "objects[0].plane.material.diffuse.image", "a FIFO"),
        (plane("{ image: t.bmp }"), "objects[0].plane.material.diffuse.image", ".png or .exr"),
        (plane("{ image: ../t.png }"), "objects[0].plane.material.diffuse.image", "relative path below"),
        (plane("{ checker: { size: 0, colors: [[1, 1, 1], [0, 0, 0]] } }"), "objects[0].plane.material.diffuse.checker.size", "positive"),
        (plane("{ checker: { colors: [[1, 1, 1], [0, 0, 0]] }, image: t.png }"), "objects[0].plane.material.diffuse", "not both"),
        (plane("{ checker: { colors: [[1, 1, 1], [0, 0, 0]] }, scale: [2, 2] }"), "objects[0].plane.material.diffuse", "belong to image maps"),
        (plane("{ image: t.png, scale: [0, 1] }"), "objects[0].plane.material.diffuse.scale", "non-zero"),
        (plane("{ image: t.png, filter: none }"), "objects[0].plane.material.diffuse", "unknown field"),
        (
            "camera: { position: [0, 1, 3], look_at: [0, 0, 0] }\nobjects:\n  - plane: { point: [0, 0, 0], normal: [0, 1, 0], u_axis: [0, 2, 0], material: { diffuse: [1, 1, 1] } }\n".to_string(),
            "objects[0].plane.u_axis",
            "parallel",
        ),
        (
            "camera: { position: [0, 1, 3], look_at: [0, 0, 0] }\nobjects:\n  - mesh: { file: quad.obj, material: { diffuse: { image: t.png } } }\n".to_string(),
            "objects[0].mesh.material",
            "texture coordinates",
        ),
    ];
    for (yaml, field, words) in cases {
        std::fs::write(tmp.join("seq.yaml"), &yaml).unwrap();
        let out = run_in(&tmp, &["check", "seq.yaml"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{yaml}: {err}");
        assert!(
            err.contains("seq.yaml:") && err.contains(field),
            "{yaml}: {err}"
        );
        assert!(err.contains(words), "{yaml}: {err}");
    }
}

/// An EXR whose first part holds only Y (and is larger) and whose second holds R, G and B:
/// the texture is the second part, sized as it is.
#[test]
fn an_exr_texture_is_its_first_part_with_r_g_and_b() {
    use exr::prelude::*;
    let tmp = scratch("tex-exr-parts");
    let channel = |name: &str, v: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(v));
    let luma = Layer::new(
        (8, 8),
        LayerAttributes::named("luma"),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(vec![channel("Y", vec![0.5; 64])].into()),
    );
    let colour = Layer::new(
        (2, 2),
        LayerAttributes::named("colour"),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(
            vec![
                channel("R", vec![1.0, 0.0, 0.0, 0.25]),
                channel("G", vec![0.0, 1.0, 0.0, 0.25]),
                channel("B", vec![0.0, 0.0, 1.0, 0.25]),
            ]
            .into(),
        ),
    );
    let image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions((8, 8))),
        vec![luma, colour],
    );
    image.write().to_file(tmp.join("parts.exr")).unwrap();
    let seq = ambient_scene(
        &tmp,
        "plane: { point: [0, 0, 0], normal: [0, 1, 0], material: m }",
        "{ image: parts.exr }",
    );
    let Some(Texture::Image { image, .. }) = &seq.scene.materials[0].ambient_map else {
        panic!("an image map");
    };
    let l0 = &image.levels[0];
    assert_eq!((l0.width, l0.height), (2, 2));
    assert_eq!(
        l0.texels,
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.25; 3]]
    );
}
