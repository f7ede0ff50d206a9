//! Triangle meshes end to end: the four shading models, a tessellated sphere against the
//! analytic one, watertightness seen from inside a closed mesh, scale and distance
//! invariance, instancing, the fingerprint, and every bad input through the binary.

mod common;
use common::{read_png, run_in, scratch, stderr, uv_sphere};
use std::fmt::Write;
use std::path::Path;

const LIGHT: &str = "lights:
  - point: { position: [4, 5, 6], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";

fn scene(object: &str, size: &str, camera: &str) -> String {
    format!("render: {{ {size}, samples: 1 }}\n{object}{LIGHT}camera: {camera}\n")
}

const CLAY: &str = "{ ambient: [0.1, 0.06, 0.05], diffuse: [0.7, 0.45, 0.35], specular: [0.6, 0.6, 0.6], shininess: 60 }";

fn render(dir: &Path, yaml: &str, name: &str) -> Vec<u8> {
    std::fs::write(dir.join(format!("{name}.yaml")), yaml).unwrap();
    let out = run_in(
        dir,
        &[
            "render",
            &format!("{name}.yaml"),
            "-q",
            "--force",
            "-o",
            &format!("{name}.png"),
        ],
    );
    assert!(out.status.success(), "{name}: {}", stderr(&out));
    read_png(&dir.join(format!("{name}.png"))).2
}

/// Share of bytes within `tolerance` levels of each other.
fn within(a: &[u8], b: &[u8], tolerance: u8) -> f64 {
    assert_eq!(a.len(), b.len());
    let close = a
        .iter()
        .zip(b)
        .filter(|(x, y)| x.abs_diff(**y) <= tolerance)
        .count();
    close as f64 / a.len() as f64
}

#[test]
fn a_finely_tessellated_sphere_renders_as_the_analytic_one() {
    let tmp = scratch("mesh-analytic");
    std::fs::write(tmp.join("fine.obj"), uv_sphere(512, 256, true, false)).unwrap();
    let camera = "{ position: [0, 0.6, 3.2], look_at: [0, 0, 0], fov: 50 }";
    let size = "width: 160, height: 120";
    let mesh = render(
        &tmp,
        &scene(
            &format!("objects:\n  - mesh: {{ file: fine.obj, material: {CLAY} }}\n"),
            size,
            camera,
        ),
        "mesh",
    );
    let sphere = render(
        &tmp,
        &scene(
            &format!(
                "objects:\n  - sphere: {{ center: [0, 0, 0], radius: 1, material: {CLAY} }}\n"
            ),
            size,
            camera,
        ),
        "sphere",
    );
    let share = within(&mesh, &sphere, 1);
    assert!(
        share >= 0.99,
        "only {:.3}% of values within 1 level",
        100.0 * share
    );
}

#[test]
fn the_four_shading_models_differ_as_the_talk_says() {
    let tmp = scratch("mesh-shading");
    std::fs::write(tmp.join("ball.obj"), uv_sphere(12, 6, true, false)).unwrap();
    let camera = "{ position: [0, 0.5, 3], look_at: [0, 0, 0], fov: 50 }";
    let size = "width: 96, height: 72";
    let shaded = |model: &str| {
        let object = format!(
            "objects:\n  - mesh: {{ file: ball.obj, shading: {model}, material: {CLAY} }}\n"
        );
        render(&tmp, &scene(&object, size, camera), model)
    };
    let (phong, flat, gouraud, constant) = (
        shaded("phong"),
        shaded("flat"),
        shaded("gouraud"),
        shaded("constant"),
    );
    // All four see the same silhouette (the same triangles are hit).
    let lit = |img: &[u8]| {
        img.chunks(3)
            .map(|p| p.iter().any(|&c| c > 0))
            .collect::<Vec<_>>()
    };
    assert_eq!(lit(&phong), lit(&flat));
    assert_eq!(lit(&gouraud), lit(&constant));
    // Each model differs from every other one somewhere.
    for (a, b, what) in [
        (&phong, &flat, "phong/flat"),
        (&phong, &gouraud, "phong/gouraud"),
        (&flat, &constant, "flat/constant"),
        (&gouraud, &constant, "gouraud/constant"),
    ] {
        assert!(a != b, "{what} render the same image");
    }
    // Constant shading takes far fewer distinct colours than Phong: one per triangle.
    let colours = |img: &[u8]| {
        let mut c: Vec<&[u8]> = img.chunks(3).collect();
        c.sort();
        c.dedup();
        c.len()
    };
    assert!(
        colours(&constant) <= 12 * 6 + 1,
        "{} colours",
        colours(&constant)
    );
    assert!(colours(&phong) > 4 * colours(&constant));
}

/// From the centre of a closed mesh every eye ray must hit a triangle: a black mesh on a white
/// background shows any ray that slipped between two triangles as a white pixel.
#[test]
fn no_ray_escapes_a_closed_mesh() {
    let tmp = scratch("mesh-watertight");
    std::fs::write(tmp.join("ball.obj"), uv_sphere(37, 19, false, false)).unwrap();
    let yaml =
        "render: { width: 200, height: 150, samples: 1, background: [1, 1, 1], encoding: linear }
objects:
  - mesh: { file: ball.obj, scale: 3, rotate: [11, 23, 7], material: { diffuse: [0, 0, 0] } }
camera: { position: [0.1, 0.2, -0.05], look_at: [1, 0.3, 0.2], fov: 120 }
";
    let img = render(&tmp, yaml, "inside");
    let white = img.chunks(3).filter(|p| p.iter().any(|&c| c > 0)).count();
    assert_eq!(
        white, 0,
        "{white} pixels saw the background through the mesh"
    );
}

/// A model scaled by 1e-4 or 1e4 and moved 1e5 away, seen by a camera placed the same way,
/// renders as the unscaled original does.
#[test]
fn huge_tiny_and_distant_models_render_as_their_originals() {
    let tmp = scratch("mesh-scale");
    std::fs::write(tmp.join("ball.obj"), uv_sphere(24, 12, true, false)).unwrap();
    let at = |s: f64, far: f64| {
        format!(
            "render: {{ width: 80, height: 60, samples: 1 }}
objects:
  - mesh: {{ file: ball.obj, scale: {s}, translate: [{far}, 0, 0], material: {CLAY} }}
  - plane: {{ point: [0, {floor}, 0], normal: [0, 1, 0], material: {{ diffuse: [0.5, 0.5, 0.5], reflection: 0.3 }} }}
lights:
  - point: {{ position: [{lx}, {ly}, {lz}], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
camera: {{ position: [{cx}, {cy}, {cz}], look_at: [{far}, 0, 0], fov: 50 }}
",
            floor = -s,
            lx = far + 4.0 * s,
            ly = 5.0 * s,
            lz = 6.0 * s,
            cx = far,
            cy = 0.7 * s,
            cz = 3.0 * s
        )
    };
    let original = render(&tmp, &at(1.0, 0.0), "original");
    for (i, (s, far)) in [(1e-4, 0.0), (1e4, 0.0), (1.0, 1e5), (1e-4, 1e5)]
        .iter()
        .enumerate()
    {
        for precision in ["f64", "f32"] {
            let yaml =
                at(*s, *far).replace("samples: 1", &format!("samples: 1, precision: {precision}"));
            let img = render(&tmp, &yaml, &format!("scaled{i}-{precision}"));
            let share = within(&img, &original, 2);
            assert!(
                share >= 0.99,
                "scale {s} at {far} in {precision}: {:.3}% within 2 levels",
                100.0 * share
            );
        }
    }
}

#[test]
fn polygons_fan_and_both_file_formats_agree() {
    let tmp = scratch("mesh-formats");
    // One quad as an OBJ polygon and as a binary big-endian PLY face with 4 corners.
    std::fs::write(
        tmp.join("quad.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n",
    )
    .unwrap();
    let mut ply = b"ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
    for v in [
        [-1.0f64, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        v.iter().for_each(|x| ply.extend(x.to_be_bytes()));
    }
    ply.push(4);
    (0..4u32).for_each(|i| ply.extend(i.to_be_bytes()));
    std::fs::write(tmp.join("quad.ply"), ply).unwrap();
    let yaml = |file: &str| {
        format!(
            "render: {{ width: 40, height: 30, samples: 1 }}\nobjects:\n  - mesh: {{ file: {file}, material: {CLAY} }}\n{LIGHT}camera: {{ position: [0.3, 0.2, 3], look_at: [0, 0, 0] }}\n"
        )
    };
    let a = render(&tmp, &yaml("quad.obj"), "obj");
    let b = render(&tmp, &yaml("quad.ply"), "ply");
    assert_eq!(a, b);
    assert!(a.iter().any(|&c| c > 0));
    let out = run_in(&tmp, &["check", "obj.yaml"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("2 triangles, 4 vertices"), "{text}");
}

#[test]
fn one_file_placed_many_times_is_read_once() {
    let tmp = scratch("mesh-instances");
    std::fs::write(tmp.join("ball.obj"), uv_sphere(16, 8, true, false)).unwrap();
    let mut yaml = String::from("render: { width: 64, height: 48, samples: 1 }\nobjects:\n");
    for i in 0..16 {
        let (x, z) = ((i % 4) as f64 * 2.5 - 3.75, (i / 4) as f64 * -2.5);
        writeln!(
            yaml,
            "  - mesh: {{ file: ball.obj, translate: [{x}, 0, {z}], material: {CLAY} }}"
        )
        .unwrap();
    }
    yaml.push_str(LIGHT);
    yaml.push_str("camera: { position: [0, 4, 6], look_at: [0, 0, -3] }\n");
    std::fs::write(tmp.join("many.yaml"), &yaml).unwrap();
    let out = run_in(&tmp, &["check", "many.yaml"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.matches("  mesh: ").count(), 1, "{text}");
    assert!(text.contains("16 placements"), "{text}");
    let img = render(&tmp, &yaml, "many");
    assert!(img.iter().any(|&c| c > 0));
}

#[test]
fn a_changed_model_makes_its_frames_stale() {
    let tmp = scratch("mesh-stale");
    std::fs::write(tmp.join("ball.obj"), uv_sphere(8, 4, false, false)).unwrap();
    let yaml = format!(
        "render: {{ width: 32, height: 24, samples: 1 }}\nobjects:\n  - mesh: {{ file: ball.obj, material: {CLAY} }}\n{LIGHT}camera: {{ position: [0, 0, 3], look_at: [0, 0, 0] }}\noutput: out/f_####.png\n"
    );
    std::fs::write(tmp.join("s.yaml"), yaml).unwrap();
    assert!(run_in(&tmp, &["render", "s.yaml", "-q"]).status.success());
    assert!(run_in(&tmp, &["status", "s.yaml"]).status.success());
    std::fs::write(tmp.join("ball.obj"), uv_sphere(9, 4, false, false)).unwrap();
    let out = run_in(&tmp, &["status", "s.yaml"]);
    assert!(!out.status.success(), "{}", stderr(&out));
}

/// Every bad mesh input is refused with exit 2 and a message naming the sequence file's line
/// and field and the mesh file's line (OBJ) or element (PLY); nothing hangs.
#[test]
fn bad_meshes_are_refused_with_file_line_and_field() {
    let tmp = scratch("mesh-bad");
    let files: &[(&str, &[u8])] = &[
        ("range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
        ("short.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\n"),
        ("word.obj", b"v 0 0 zero\n"),
        ("empty.obj", b"v 0 0 0\n"),
        ("flat.obj", b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
        ("nofaces.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n"),
        ("trunc.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\0\0\0\0"),
        ("bad.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n"),
        ("model.stl", b"solid x\n"),
    ];
    for (name, bytes) in files {
        std::fs::write(tmp.join(name), bytes).unwrap();
    }
    let fifo = tmp.join("pipe.obj");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    std::fs::create_dir(tmp.join("sub")).unwrap();
    let cases: &[(&str, &str)] = &[
        (
            "range.obj",
            "range.obj: line 4: face corner `4`: vertex index 4 is out of range",
        ),
        (
            "short.obj",
            "short.obj: line 3: the file has no faces of 3 or more corners (1 with fewer)",
        ),
        (
            "word.obj",
            "word.obj: line 1: `v` coordinate 3 is not a number",
        ),
        ("empty.obj", "no faces"),
        ("flat.obj", "all 1 triangles are degenerate"),
        ("nofaces.ply", "no `face` element"),
        ("trunc.ply", "trunc.ply: vertex 0: the file ends early"),
        ("bad.ply", "bad.ply: face 0: vertex index 9 is out of range"),
        ("model.stl", "must end in .obj or .ply"),
        ("missing.obj", "missing.obj: cannot read"),
        ("pipe.obj", "is not a regular file"),
        ("sub", "is not a regular file"),
        (
            "/etc/hostname",
            "relative path below the sequence file's folder",
        ),
        ("../x.obj", "relative path below the sequence file's folder"),
    ];
    for (file, want) in cases {
        let yaml = format!(
            "render: {{ width: 8, height: 8 }}\nobjects:\n  - mesh: {{ file: {file}, material: {CLAY} }}\n{LIGHT}camera: {{ position: [0, 0, 3], look_at: [0, 0, 0] }}\n"
        );
        std::fs::write(tmp.join("bad.yaml"), yaml).unwrap();
        let out = run_in(&tmp, &["check", "bad.yaml"]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{file}: {err}");
        assert!(err.contains("bad.yaml:3:"), "{file}: no line: {err}");
        assert!(
            err.contains("objects[0].mesh.file"),
            "{file}: no field: {err}"
        );
        assert!(err.contains(want), "{file}: wanted `{want}` in {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// tests/reference/mesh_reference.py, an independent float64 implementation written from
/// docs/spec alone, renders its scenes (every shading model, PLY and OBJ, glass, ties, far
/// from the origin) and compares them with rayreel's frames: every byte must agree.
#[test]
fn the_independent_reference_reproduces_mesh_frames() {
    common::independent_reference(&["mesh_reference.py"], "mesh");
}
