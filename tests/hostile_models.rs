//! A third adversarial pass, through the real binary, on what users bring: model files from
//! other programs' test suites and from attackers, textures that declare gigabytes, models in
//! any units, and the memory a limit leaves. Each test failed before the readers were made to
//! read by grammar, the memory budget to count everything, and placements to be exact.

mod common;
use common::*;
use std::path::Path;

const LIGHT: &str = "lights:
  - point: { position: [4, 5, 6], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";

/// A sequence placing `file` (with `extra` placement fields), seen from the front.
fn placing(file: &str, extra: &str) -> String {
    format!(
        "render: {{ width: 40, height: 30, samples: 1 }}
objects:
  - mesh: {{ file: {file}, {extra}material: {{ diffuse: [0.7, 0.5, 0.4], reflection: 0.2 }} }}
  - plane: {{ point: [0, -1, 0], normal: [0, 1, 0], material: {{ diffuse: [0.5, 0.5, 0.5] }} }}
{LIGHT}camera: {{ position: [0.4, 0.7, 3.5], look_at: [0.2, 0.2, 0], fov: 50 }}
"
    )
}

/// `check` on a sequence placing `file` (written with `bytes`): exit code, stdout, stderr.
fn check_model(dir: &Path, file: &str, bytes: &[u8]) -> (Option<i32>, String, String) {
    std::fs::write(dir.join(file), bytes).unwrap();
    std::fs::write(dir.join("seq.yaml"), placing(file, "")).unwrap();
    let out = run_in(dir, &["check", "seq.yaml"]);
    let said = String::from_utf8_lossy(&out.stdout).into_owned();
    (out.status.code(), said, stderr(&out))
}

/// A PLY with two `vertex` elements, the second with normals and texture coordinates: `check`
/// accepted it and `render` panicked in the polygon shading (exit 134), positions of both
/// elements kept but normals and texture coordinates of one. It is refused, naming the line.
#[test]
fn a_ply_with_two_vertex_elements_is_refused_not_a_crash() {
    let tmp = scratch("ply-two-vertex");
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1 0 0 1 0 0\n1 0 1 0 0 1 1 0\n0 1 1 0 0 1 0 1\n3 3 4 5\n";
    let (code, _, err) = check_model(&tmp, "two.ply", ply.as_bytes());
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("seq.yaml:3:")
            && err.contains(
                "objects[0].mesh.file: two.ply: header line 7: a second `vertex` element"
            ),
        "{err}"
    );
    let out = run_in(&tmp, &["render", "seq.yaml", "-q", "-o", "f.png"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(!stderr(&out).contains("panicked"));
}

/// Legal files other readers' test suites hold, refused before: a PLY whose `face` element
/// comes before `vertex`, an OBJ whose face continues after a `\`, Latin-1 bytes in lines the
/// reader ignores, a UTF-16 OBJ, a Blender 2.47 header line without `comment`, and what
/// lenient readers accept with data dropped (undefined `vt`/`vn`, a two-corner face). Each
/// loads, with a `check` note where something was dropped or read as a comment.
#[test]
fn legal_models_from_other_readers_load_with_notes() {
    let tmp = scratch("legal-models");
    let faces_first = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n";
    let blender = "ply\nformat ascii 1.0\nCreated by Blender3D 247 - www.blender.org, source file: \nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n0 0 0 0 0 \n1 0 0 1 0 \n0 1 0 0 1 \n3 0 1 2\n";
    let plain = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let mut utf16 = vec![0xff, 0xfe];
    utf16.extend(plain.encode_utf16().flat_map(u16::to_le_bytes));
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("faces_first.ply", faces_first.into(), "1 triangles"),
        (
            "blender.ply",
            blender.into(),
            "note: header line 3 starts with no PLY keyword and was read as a comment",
        ),
        (
            "continued.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n  2 3\n".to_vec(),
            "1 triangles",
        ),
        (
            "latin1.obj",
            b"# caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\ng gr\xfcn\nusemtl r\xf6d\nf 1 2 3\n".to_vec(),
            "note: ignored statements: usemtl",
        ),
        ("utf16.obj", utf16, "note: read as UTF-16 text"),
        (
            "undefined.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1 2/2/2 3/3/3\n".to_vec(),
            "note: 3 face corners refer to texture coordinates (`vt`) the file has not defined (the first on line 4); those were dropped",
        ),
        (
            "twocorner.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1 2 3\n".to_vec(),
            "note: 1 face with fewer than 3 corners skipped (the first on line 4)",
        ),
    ];
    for (file, bytes, want) in cases {
        let (code, said, err) = check_model(&tmp, file, &bytes);
        assert_eq!(code, Some(0), "{file}: {err}");
        // `check` wraps lines past 120 columns under the summary's indent.
        let said = said.replace("\n              ", " ");
        assert!(said.contains(want), "{file}: wanted `{want}` in\n{said}");
        let out = run_in(
            &tmp,
            &["render", "seq.yaml", "-q", "--force", "-o", "f.png"],
        );
        assert!(out.status.success(), "{file}: {}", stderr(&out));
    }
}

/// What was misread or refused by substring: `end_header` inside a comment or a property
/// name, spaces after `end_header`, a header over 64 KiB. And rows that are wrong are named
/// themselves: an ASCII row with a value too many (the next element was blamed), a list
/// length of 3.5 (read as 3).
#[test]
fn ply_headers_are_read_by_grammar_and_rows_name_themselves() {
    let tmp = scratch("ply-grammar");
    let ply = |extra: &str, end: &str, body: &str| {
        format!(
            "ply\nformat ascii 1.0\n{extra}element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n{end}\n{body}"
        )
    };
    let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let long = "comment a scanner's settings, line after line\n".repeat(2000);
    for (name, text) in [
        (
            "comment",
            ply("comment the end_header line follows\n", "end_header", body),
        ),
        (
            "property",
            ply(
                "element extra 0\nproperty float end_header\n",
                "end_header",
                body,
            ),
        ),
        ("spaces", ply("", "end_header  \t", body)),
        ("long", ply(&long, "end_header", body)),
    ] {
        assert!(text.len() > 100);
        let (code, said, err) = check_model(&tmp, &format!("{name}.ply"), text.as_bytes());
        assert_eq!(code, Some(0), "{name}: {err}");
        assert!(said.contains("1 triangles, 3 vertices"), "{name}: {said}");
    }
    let bad = [
        (
            "extra",
            "0 0 0 7\n1 0 0\n0 1 0\n3 0 1 2\n",
            "vertex 0: the row has 4 values, 1 more",
        ),
        (
            "count",
            "0 0 0\n1 0 0\n0 1 0\n3.5 0 1 2\n",
            "face 0: a list's length must be a whole number",
        ),
    ];
    for (name, rows, want) in bad {
        let (code, _, err) = check_model(
            &tmp,
            &format!("{name}.ply"),
            ply("", "end_header", rows).as_bytes(),
        );
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(err.contains(want), "{name}: wanted `{want}` in {err}");
    }
}

/// A sparse 1 GiB OBJ (zeros) was read whole before being refused; the read now stops at the
/// first NUL byte. A sparse 1 GiB texture is refused by its first 8 bytes (under a 400 MB
/// address-space limit, where reading it whole aborted). Non-text bytes inside a statement
/// that is read are refused with the line.
#[test]
fn a_sparse_gigabyte_model_is_refused_at_its_first_block() {
    let tmp = scratch("sparse-obj");
    let f = std::fs::File::create(tmp.join("sparse.obj")).unwrap();
    f.set_len(1 << 30).unwrap();
    std::fs::write(tmp.join("seq.yaml"), placing("sparse.obj", "")).unwrap();
    let run = cpu_timed(bin().args(["check", "seq.yaml"]).current_dir(&tmp));
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    assert!(
        run.stderr.contains("sparse.obj: line 1: a NUL byte"),
        "{}",
        run.stderr
    );
    assert!(run.cpu_seconds < 0.5, "{:.2} s CPU", run.cpu_seconds);
    // A sparse 1 GiB texture: refused by its first bytes, not read into memory first.
    let f = std::fs::File::create(tmp.join("sparse.png")).unwrap();
    f.set_len(1 << 30).unwrap();
    let textured = placing("t.obj", "").replace(
        "material: { diffuse: [0.7, 0.5, 0.4], reflection: 0.2 }",
        "material: { diffuse: { image: sparse.png } }",
    );
    std::fs::write(
        tmp.join("t.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n",
    )
    .unwrap();
    std::fs::write(tmp.join("seq.yaml"), textured).unwrap();
    // prlimit execs rayreel in its own process: the child measured is rayreel.
    let run = cpu_timed(
        std::process::Command::new("prlimit")
            .args([
                "--as=400000000",
                env!("CARGO_BIN_EXE_rayreel"),
                "check",
                "seq.yaml",
            ])
            .current_dir(&tmp),
    );
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    assert!(
        run.stderr
            .contains("sparse.png does not start as a PNG file does"),
        "{}",
        run.stderr
    );
    assert!(run.cpu_seconds < 0.5, "{:.2} s CPU", run.cpu_seconds);
    let (code, _, err) = check_model(&tmp, "word.obj", b"v 0 0 0\nv 1 \xe9 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(code, Some(2));
    assert!(
        err.contains("word.obj: line 2: `\\u{e9}`") || err.contains("word.obj: line 2:"),
        "{err}"
    );
}

/// The same model in other units with a compensating scale: identical up to 1e±30 before,
/// then black (1e55) or wrong everywhere (1e80, 1e-95), with exit 0. Every pixel now matches
/// the model in units of 1, up to 1e±300; a scale that would make the placed model smaller
/// than f64 can trace is refused, naming the file, the line and the field.
#[test]
fn models_in_any_units_render_the_same_pixels() {
    let tmp = scratch("mesh-units");
    let corners = [
        [-1.0, -0.8, 0.0],
        [1.2, -0.6, -0.3],
        [0.1, 1.1, 0.2],
        [-0.5, 0.2, 0.9],
    ];
    let write = |exp: i32| {
        let f: f64 = format!("1e{exp}").parse().unwrap();
        let mut text = String::new();
        for c in corners {
            text += &format!("v {:?} {:?} {:?}\n", c[0] * f, c[1] * f, c[2] * f);
        }
        text += "f 1 2 3\nf 1 3 4\nf 2 3 4\n";
        let name = format!("m{exp}.obj");
        std::fs::write(tmp.join(&name), text).unwrap();
        name
    };
    let render = |exp: i32| {
        let yaml = placing(&write(exp), &format!("scale: 1e{}, ", -exp));
        std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
        let png = format!("u{exp}.png");
        let out = run_in(&tmp, &["render", "seq.yaml", "-q", "--force", "-o", &png]);
        assert!(out.status.success(), "1e{exp}: {}", stderr(&out));
        read_png(&tmp.join(png)).2
    };
    let unit = render(0);
    for exp in [55, 80, -95, 150, -150, 300, -300] {
        assert!(
            render(exp) == unit,
            "1e{exp}: pixels differ from units of 1"
        );
    }
    // File coordinates of 1e-95 and a scale of 1e-55: a model 1e-150 across.
    let yaml = placing(&write(-95), "scale: 1e-55, ");
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    let out = run_in(&tmp, &["check", "seq.yaml"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("seq.yaml:3:")
            && err.contains("objects[0].mesh.scale: ")
            && err.contains("m-95.obj's coordinates reach 1.20e-95")
            && err.contains("at least 1e-100 across"),
        "{err}"
    );
    // With `fit` the fitted size is what must hold: a model 1e-150 (or 1e150) across with
    // `scale: 1, fit: 2.2` is 2.2 across, as the model in units of 1 is (it was refused:
    // "this scale makes the placed model about 2.20e-150 across").
    let fitted = |exp: i32| {
        let yaml = placing(&write(exp), "scale: 1, fit: 2.2, ");
        std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
        let png = format!("f{exp}.png");
        let out = run_in(&tmp, &["render", "seq.yaml", "-q", "--force", "-o", &png]);
        assert!(out.status.success(), "1e{exp} fitted: {}", stderr(&out));
        read_png(&tmp.join(png)).2
    };
    let unit_fitted = fitted(0);
    for exp in [-150, 150] {
        let image = fitted(exp);
        let differ = (image.chunks(3).zip(unit_fitted.chunks(3)))
            .filter(|(a, b)| a != b)
            .count();
        assert!(differ <= 12, "1e{exp} fitted: {differ} pixels differ");
    }
}

/// A PNG of `side`×`side` black pixels, written fast (it compresses to almost nothing).
fn black_png(path: &Path, side: u32) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut enc = png::Encoder::new(file, side, side);
    enc.set_color(png::ColorType::Rgb);
    enc.set_compression(png::Compression::Fast);
    let mut w = enc.write_header().unwrap().into_stream_writer().unwrap();
    let row = vec![0u8; 3 * side as usize];
    for _ in 0..side {
        std::io::Write::write_all(&mut w, &row).unwrap();
    }
    w.finish().unwrap();
}

/// Under a 3 GB address-space limit (prlimit --as=3000000000): four small PNGs declaring
/// 8192×8192 (each within the per-image limit) took 4.3 GB and `check` aborted in an
/// allocation (exit 134). The third is now refused before it is decoded, with the figures in
/// GB and what the first two hold, and exit 1; so is `render`.
#[test]
fn textures_beyond_the_memory_limit_are_refused_with_the_figures() {
    if !have_tool("prlimit") {
        return;
    }
    let tmp = scratch("texture-memory");
    black_png(&tmp.join("a.png"), 8192);
    for n in ["b", "c", "d"] {
        std::fs::copy(tmp.join("a.png"), tmp.join(format!("{n}.png"))).unwrap();
    }
    let mut yaml = String::from("render: { width: 32, height: 24, samples: 1 }\nmaterials:\n");
    for n in ["a", "b", "c", "d"] {
        yaml += &format!("  {n}: {{ diffuse: {{ image: {n}.png }} }}\n");
    }
    yaml += "objects:\n";
    for (i, n) in ["a", "b", "c", "d"].iter().enumerate() {
        yaml += &format!(
            "  - sphere: {{ center: [{}, 0, 0], radius: 1, material: {n} }}\n",
            2 * i
        );
    }
    yaml += &format!("{LIGHT}camera: {{ position: [3, 0, 8], look_at: [3, 0, 0] }}\n");
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    for command in ["check seq.yaml", "render seq.yaml -q -o f.png"] {
        let out = sh(
            &tmp,
            &format!("prlimit --as=3000000000 \"$RAYREEL\" {command}"),
        );
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{command}: {err}");
        assert!(
            err.contains("seq.yaml:5:")
                && err.contains("materials.c.diffuse.image: not enough memory for decoding c.png (8192x8192): it needs about 1.01 GB")
                && err.contains("under RLIMIT_AS (ulimit -v) of 3.00 GB (the textures read before it hold 2.15 GB)"),
            "{command}: {err}"
        );
        assert!(
            !err.contains("memory allocation") && !err.contains("0.00"),
            "{err}"
        );
    }
}

/// A 12 MB OBJ whose one face has 6 million corners aborted `check` under 150 and 300 MB of
/// address space (exit 134). Every array the reader grows, and the hierarchy a mesh will need,
/// is now admitted first: refused with the figures and exit 1, never an abort; with room
/// enough it loads.
#[test]
fn a_model_beyond_the_memory_limit_is_refused_with_the_figures() {
    if !have_tool("prlimit") {
        return;
    }
    let tmp = scratch("mesh-memory");
    let face = " 1 2 3".repeat(2_000_000);
    std::fs::write(
        tmp.join("big.obj"),
        format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nf{face}\n"),
    )
    .unwrap();
    std::fs::write(tmp.join("seq.yaml"), placing("big.obj", "")).unwrap();
    for mb in [150, 300] {
        let out = sh(
            &tmp,
            &format!("prlimit --as={mb}000000 \"$RAYREEL\" check seq.yaml"),
        );
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{mb} MB: {err}");
        assert!(
            err.contains("objects[0].mesh.file: big.obj: not enough memory for ")
                && err.contains(&format!("under RLIMIT_AS (ulimit -v) of {mb}.0 MB")),
            "{mb} MB: {err}"
        );
        assert!(
            !err.contains("memory allocation") && !err.contains("panicked"),
            "{err}"
        );
    }
}

/// `samples: -1` on an area light said "0 or more" though 0 is refused; rect edges of 1e100
/// that are perpendicular were refused as parallel (their cross product overflowed);
/// `rotate: [1e300, 0, 0]` was refused with a message about squared lengths (any finite
/// angle reduces exactly).
#[test]
fn small_refusals_say_what_is_true() {
    let tmp = scratch("small-refusals");
    std::fs::write(tmp.join("t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let scene = |light: &str, object: &str| {
        format!(
            "render: {{ width: 16, height: 12, samples: 1 }}\nobjects:\n  - {object}\nlights:\n  - {light}\ncamera: {{ position: [0, 0, 5], look_at: [0, 0, 0] }}\n"
        )
    };
    let sphere = "sphere: { center: [0, 0, 0], radius: 1, material: { diffuse: [0.5, 0.5, 0.5] } }";
    let cases = [
        (
            scene(
                "sphere: { center: [0, 5, 0], radius: 1, samples: -1, diffuse: [1, 1, 1], specular: [1, 1, 1] }",
                sphere,
            ),
            Some(
                "lights[0].sphere.samples: must be 1 to 4096 points on the light per eye sample (got -1)",
            ),
        ),
        (
            scene(
                "point: { position: [0, 5, 5], diffuse: [1, 1, 1], specular: [1, 1, 1] }",
                sphere,
            )
            .replace("samples: 1", "samples: -1"),
            Some("render.samples: must be 1 to "),
        ),
        (
            scene(
                "rect: { corner: [0, 1e99, 0], edge_u: [1e100, 0, 0], edge_v: [0, 0, 1e100], diffuse: [1, 1, 1], specular: [1, 1, 1] }",
                sphere,
            ),
            None,
        ),
        (
            scene(
                "point: { position: [0, 5, 5], diffuse: [1, 1, 1], specular: [1, 1, 1] }",
                "mesh: { file: t.obj, rotate: [1e300, 0, 0], material: { diffuse: [0.5, 0.5, 0.5] } }",
            ),
            None,
        ),
    ];
    for (yaml, want) in cases {
        std::fs::write(tmp.join("seq.yaml"), &yaml).unwrap();
        let out = run_in(
            &tmp,
            &["render", "seq.yaml", "-q", "--force", "-o", "f.png"],
        );
        let err = stderr(&out);
        match want {
            Some(want) => {
                assert_eq!(out.status.code(), Some(2), "{yaml}: {err}");
                assert!(err.contains(want), "wanted `{want}` in {err}");
            }
            None => assert!(out.status.success(), "{yaml}: {err}"),
        }
    }
}

/// An OBJ comment ending in `\` (`# exported to C:\models\`) swallowed the next line, here
/// the first vertex, so `f 1 2 4` named a fourth vertex the file did not have. A comment now
/// ends at its line, as other OBJ readers have it; a `\` outside a comment still continues.
#[test]
fn an_obj_comment_ending_in_a_backslash_ends_at_its_line() {
    let tmp = scratch("obj-comment-backslash");
    let obj = b"# exported to C:\\models\\\nv 5 5 5\nv 1 -1 0\nv 1 \\\n 1 0\nv -1 1 0\nf 1 2 4\nf 2 3 4\n";
    let (code, said, err) = check_model(&tmp, "path.obj", obj);
    assert_eq!(code, Some(0), "{said}{err}");
    assert!(!said.contains("degenerate"), "{said}");
}

/// A binary PLY grid of `side`×`side` vertices (2·(side−1)² triangles).
fn ply_grid(path: &Path, side: u32) {
    let quads = (side - 1) * (side - 1);
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        side * side,
        2 * quads
    )
    .into_bytes();
    for y in 0..side {
        for x in 0..side {
            let at = |i: u32| 2.0 * i as f32 / (side - 1) as f32 - 1.0;
            for c in [at(x), at(y), 0.0] {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    for y in 0..side - 1 {
        for x in 0..side - 1 {
            let i = y * side + x;
            for t in [[i, i + 1, i + side], [i + 1, i + side + 1, i + side]] {
                bytes.push(3);
                t.iter()
                    .for_each(|v| bytes.extend_from_slice(&v.to_le_bytes()));
            }
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// `check` of a 2M-triangle grid under `prlimit --as=500000000` loaded it and then aborted
/// (exit 134, "memory allocation of 207584208 bytes failed"): its cost probe builds the
/// hierarchy and the f64 copy of the triangles, which no check counted, and the copy was
/// gathered in pieces and then copied, holding it twice. The hierarchies and copies are now
/// admitted before the probe, beside the probe's threads' arenas: raising the limit, each run
/// is refused with the figures (exit 1) until one measures the job, never an abort.
#[test]
fn a_model_whose_hierarchy_cannot_fit_is_refused_before_the_probe() {
    if !have_tool("prlimit") {
        return;
    }
    let tmp = scratch("hierarchy-memory");
    ply_grid(&tmp.join("grid.ply"), 708);
    std::fs::write(tmp.join("seq.yaml"), placing("grid.ply", "")).unwrap();
    until_it_fits(
        &tmp,
        (200..=2000).step_by(50),
        |mb| format!("prlimit --as={mb}000000 \"$RAYREEL\" check seq.yaml"),
        "not enough memory for the meshes' hierarchies and triangle copies (999698 triangles): they need about 160.0 MB",
    );
}

/// Runs `command(mb)` at each limit in `limits` (MB) until it succeeds: every run before
/// ends with exit 1 and "not enough memory", never an abort or a panic, and one of them said
/// `wanted`. Returns the limit that let it succeed.
fn until_it_fits(
    dir: &Path,
    limits: impl Iterator<Item = u64>,
    command: impl Fn(u64) -> String,
    wanted: &str,
) -> u64 {
    let mut said_wanted = false;
    for mb in limits {
        let out = sh(dir, &command(mb));
        let err = stderr(&out);
        assert!(
            !err.contains("memory allocation") && !err.contains("panicked"),
            "{mb} MB: {err}"
        );
        match out.status.code() {
            Some(0) => {
                assert!(said_wanted, "{mb} MB: never refused with `{wanted}`");
                return mb;
            }
            Some(1) => assert!(err.contains("not enough memory"), "{mb} MB: {err}"),
            code => panic!("{mb} MB: exit {code:?}: {err}"),
        }
        said_wanted |= err.contains(wanted);
    }
    panic!("no limit let `{}` succeed", command(0));
}

/// An f32 job whose compositing passes are traced in f64 builds both copies of a mesh's
/// triangles, where only one was counted, and both copies and the hierarchy were allocated
/// without a way to fail. Both are now counted (212 bytes a triangle: hierarchy, f64 and f32
/// copies) and allocated fallibly: raising the limit, each run is refused with the figures
/// (exit 1) until one renders, never an abort.
#[test]
fn an_f32_job_counts_both_triangle_copies_and_never_aborts() {
    if !have_tool("prlimit") {
        return;
    }
    let tmp = scratch("hierarchy-both-copies");
    ply_grid(&tmp.join("grid.ply"), 301);
    let yaml = placing("grid.ply", "").replace("samples: 1 }", "samples: 1, precision: f32 }");
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    // 180000 triangles × 212 bytes.
    let mb = until_it_fits(
        &tmp,
        (150..=2000).step_by(25),
        |mb| {
            format!(
                "prlimit --as={mb}000000 \"$RAYREEL\" render seq.yaml -q --threads 2 --aov normal -o f{mb}.exr"
            )
        },
        "beside 38.2 MB for the meshes' hierarchies",
    );
    assert!(files(&tmp).contains(&format!("f{mb}.exr")));
}

/// A PLY face index of `1.5` was reported "out of range"; a second `format` line replaced
/// the first; OBJ numbers `nan`, `inf` and `1e999` were taken (a NaN texture coordinate
/// rendered with exit 0, a NaN normal silently became the face's). Each is now refused with
/// the file, the line or row, and the field.
#[test]
fn non_integer_indices_second_formats_and_non_finite_numbers_are_refused() {
    let tmp = scratch("model-messages");
    let ply = |extra: &str, face: &str| {
        format!(
            "ply\nformat ascii 1.0\n{extra}element vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 {face}\n"
        )
    };
    let cases: [(&str, String, &str); 7] = [
        (
            "index.ply",
            ply("", "1\n3 0 1.5 2"),
            "index.ply: face 0: vertex index 1.5 is not a whole number",
        ),
        (
            "format.ply",
            ply("format binary_little_endian 1.0\n", "1\n3 0 1 2"),
            "format.ply: header line 3: a second `format` line (the first is header line 2)",
        ),
        (
            "normal.ply",
            ply("", "nan\n3 0 1 2"),
            "normal.ply: vertex 2: `nz` is not a finite number (got NaN)",
        ),
        (
            "v.obj",
            "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n".into(),
            "v.obj: line 3: `v` coordinate 2 is not a finite number (got `nan`)",
        ),
        (
            "vn.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 inf\nf 1//1 2//1 3//1\n".into(),
            "vn.obj: line 4: `vn` coordinate 3 is not a finite number (got `inf`)",
        ),
        (
            "vt.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 1e999 0\nf 1/1 2/1 3/1\n".into(),
            "vt.obj: line 4: `vt` coordinate 1 is not a finite number (got `1e999`)",
        ),
        (
            "big.ply",
            ply("", "1\n3 0 1 4294967296"),
            "big.ply: face 0: vertex index 4294967296 is out of range (3 vertices)",
        ),
    ];
    for (file, text, said) in cases {
        let (code, _, err) = check_model(&tmp, file, text.as_bytes());
        assert_eq!(code, Some(2), "{file}: {err}");
        assert!(err.contains(said), "{file}: {err}");
        assert!(err.contains("objects[0].mesh.file"), "{file}: {err}");
    }
}
