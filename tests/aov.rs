//! Compositing passes (`--aov`, `render.aov`) through the binary: the channels compositors
//! look for, their values on known geometry, motion against known camera moves, the same bytes
//! from every kernel and thread count, the refusals, resume, and `camera --format chan`.

mod common;
use common::*;

/// A red sphere standing on a grey floor, seen level from (0, 1, 5); 33×25, so the centre
/// pixel's ray is the view axis.
const SCENE: &str = "
render: { width: 33, height: 25, max_depth: 2, samples: 4 }
camera: { position: [0, 1, 5], look_at: [0, 1, 0] }
objects:
  - sphere: { center: [0, 1, 0], radius: 1, material: { diffuse: [0.8, 0.2, 0.1] } }
  - plane: { point: [0, 0, 0], normal: [0, 1, 0], material: { diffuse: [0.5, 0.5, 0.5], reflection: 0.3 } }
lights:
  - point: { position: [2, 5, 5], diffuse: [1, 1, 1], specular: [0.5, 0.5, 0.5] }
";

const ALL: &str = "normal,albedo,id,motion,position";

fn read_exr(path: &std::path::Path) -> exr::image::FlatImage {
    exr::prelude::read_all_flat_layers_from_file(path).unwrap()
}

/// Channel `name` of the first layer as f32 values, row-major.
fn channel(img: &exr::image::FlatImage, name: &str) -> Vec<f32> {
    let layer = &img.layer_data[0];
    let c = (layer.channel_data.list.iter())
        .find(|c| c.name.to_string() == name)
        .unwrap_or_else(|| panic!("no channel {name}"));
    c.sample_data.values_as_f32().collect()
}

fn render_ok(dir: &std::path::Path, args: &[&str]) {
    let mut all = vec!["render", "s.yaml", "-q"];
    all.extend(args);
    let out = run_in(dir, &all);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
}

fn scene(name: &str, yaml: &str) -> Scratch {
    let tmp = scratch(name);
    std::fs::write(tmp.join("s.yaml"), yaml).unwrap();
    tmp
}

#[test]
fn passes_have_the_names_compositors_expect_and_the_values_of_the_scene() {
    let tmp = scene("aov-values", SCENE);
    render_ok(&tmp, &["-o", "f.exr", "--aov", ALL]);
    let img = read_exr(&tmp.join("f.exr"));
    let mut names: Vec<String> = (img.layer_data[0].channel_data.list.iter())
        .map(|c| c.name.to_string())
        .collect();
    names.sort();
    let want = [
        "B",
        "G",
        "N.X",
        "N.Y",
        "N.Z",
        "P.X",
        "P.Y",
        "P.Z",
        "R",
        "albedo.B",
        "albedo.G",
        "albedo.R",
        "forward.u",
        "forward.v",
        "objectId",
    ];
    assert_eq!(names, want);
    for c in &img.layer_data[0].channel_data.list {
        let float = matches!(c.sample_data, exr::image::FlatSamples::F32(_));
        let colour = ["R", "G", "B"].contains(&c.name.to_string().as_str());
        assert_eq!(float, !colour, "{}: passes are 32-bit, colour half", c.name);
    }
    let table = (img.layer_data[0].attributes.other)
        .get(&exr::meta::attribute::Text::from("rayreel:objectIds"));
    match table {
        Some(exr::meta::attribute::AttributeValue::Text(t)) => {
            assert_eq!(t.to_string(), "0 sphere\n1 plane")
        }
        other => panic!("no id table: {other:?}"),
    }

    let at = |name: &str, row: usize, col: usize| channel(&img, name)[row * 33 + col];
    let v3 = |layer: &str, (x, y, z): (&str, &str, &str), row, col| {
        [x, y, z].map(|c| at(&format!("{layer}.{c}"), row, col))
    };
    let xyz = ("X", "Y", "Z");
    // The centre pixel looks along the axis at the sphere's nearest point, (0, 1, 1).
    assert_eq!(v3("N", xyz, 12, 16), [0.0, 0.0, 1.0]);
    assert_eq!(v3("P", xyz, 12, 16), [0.0, 1.0, 1.0]);
    assert_eq!(v3("albedo", ("R", "G", "B"), 12, 16), [0.8, 0.2, 0.1]);
    assert_eq!(at("objectId", 12, 16), 0.0);
    // The bottom row sees the floor (not its reflection: the first surface).
    for col in [0, 16, 32] {
        let [px, py, pz] = v3("P", xyz, 24, col);
        assert!(py.abs() < 1e-6 && pz > 1.0, "floor at ({px}, {py}, {pz})");
        assert_eq!(v3("N", xyz, 24, col), [0.0, 1.0, 0.0]);
        assert_eq!(at("objectId", 24, col), 1.0);
        assert_eq!(v3("albedo", ("R", "G", "B"), 24, col), [0.5; 3]);
    }
    // The top corner sees the sky: id -1, everything else 0.
    assert_eq!(at("objectId", 0, 0), -1.0);
    assert_eq!(v3("N", xyz, 0, 0), [0.0; 3]);
    assert_eq!(v3("P", xyz, 0, 0), [0.0; 3]);
    // A still camera: no motion anywhere.
    for name in ["forward.u", "forward.v"] {
        assert!(channel(&img, name).iter().all(|&v| v == 0.0), "{name}");
    }

    if !have_tool("oiiotool") {
        return;
    }
    let out = std::process::Command::new("oiiotool")
        .args(["--info", "-v", "f.exr"])
        .current_dir(&tmp)
        .output()
        .unwrap();
    let info = String::from_utf8_lossy(&out.stdout);
    for c in &want[..] {
        let kind = if ["R", "G", "B"].contains(c) {
            "half"
        } else {
            "float"
        };
        assert!(info.contains(&format!("{c} ({kind})")), "{c}:\n{info}");
    }
    assert!(
        info.contains("rayreel:objectIds: \"0 sphere\n1 plane\""),
        "{info}"
    );
}

/// A wall at z = 0 facing the camera 5 units away, fov 90, the camera moving by `keys`.
fn wall(keys: &str) -> String {
    format!(
        "
render: {{ width: 33, height: 25, max_depth: 1, samples: 1 }}
camera: {{ position: [0, 1, 5], look_at: [0, 1, 0], fov: 90 }}
objects:
  - plane: {{ point: [0, 0, 0], normal: [0, 0, 1], material: {{ diffuse: [0.5, 0.5, 0.5] }} }}
lights:
  - ambient: {{ color: [1, 1, 1] }}
timeline:
  fps: 24
  interpolation: linear
  keyframes:
{keys}
"
    )
}

#[test]
fn motion_is_the_known_move_of_the_camera_in_pixels_per_frame() {
    // A truck: 2.4 units right in 24 frames, 0.1 a frame. The wall moves left by
    // 0.1/5 of the half width (16.5 pixels at fov 90) a frame, everywhere.
    let truck = wall(
        "    - { time: 0, position: [0, 1, 5], look_at: [0, 1, 0] }
    - { time: 1, position: [2.4, 1, 5], look_at: [2.4, 1, 0] }",
    );
    let tmp = scene("aov-truck", &truck);
    render_ok(
        &tmp,
        &["-o", "f_##.exr", "--aov", "motion", "--frames", "0,12,24"],
    );
    for n in ["00", "12"] {
        let img = read_exr(&tmp.join(format!("f_{n}.exr")));
        let (u, v) = (channel(&img, "forward.u"), channel(&img, "forward.v"));
        for (&u, &v) in u.iter().zip(&v) {
            assert!(
                (u - -0.33).abs() < 1e-4 && v.abs() < 1e-4,
                "frame {n}: ({u}, {v})"
            );
        }
    }
    // The last frame: keys hold still after the last one, so nothing moves.
    let img = read_exr(&tmp.join("f_24.exr"));
    assert!(channel(&img, "forward.u").iter().all(|&u| u == 0.0));

    // A pan: the camera turns right by atan(0.1/5) in frame 0. A point the centre row sees at
    // angle a off the axis is then seen at a − θ: x = tan(a) becomes tan(a − θ), in units of
    // the half width.
    let pan = wall(
        "    - { time: 0, position: [0, 1, 5], look_at: [0, 1, 0] }
    - { time: 1, position: [0, 1, 5], look_at: [2.4, 1, 0] }",
    );
    let tmp = scene("aov-pan", &pan);
    render_ok(
        &tmp,
        &[
            "-o",
            "f_##.exr",
            "--aov",
            "motion,position",
            "--frames",
            "0",
        ],
    );
    let img = read_exr(&tmp.join("f_00.exr"));
    let (u, v) = (channel(&img, "forward.u"), channel(&img, "forward.v"));
    let theta = (0.1f64 / 5.0).atan();
    for col in [0, 8, 16, 24, 32] {
        let x = -1.0 + 2.0 * (col as f64 + 0.5) / 33.0;
        let want = ((x.atan() - theta).tan() - x) * 16.5;
        let i = 12 * 33 + col;
        assert!(
            (f64::from(u[i]) - want).abs() < 1e-4,
            "column {col}: {} vs {want}",
            u[i]
        );
        assert!(v[i].abs() < 1e-4, "column {col}: v {}", v[i]);
    }
    // Up is up: tilting the camera up moves the picture down (v < 0).
    let tilt = wall(
        "    - { time: 0, position: [0, 1, 5], look_at: [0, 1, 0] }
    - { time: 1, position: [0, 1, 5], look_at: [0, 3.4, 0] }",
    );
    let tmp = scene("aov-tilt", &tilt);
    render_ok(
        &tmp,
        &["-o", "f_##.exr", "--aov", "motion", "--frames", "0"],
    );
    let v = channel(&read_exr(&tmp.join("f_00.exr")), "forward.v");
    assert!(
        (f64::from(v[12 * 33 + 16]) - -0.33).abs() < 1e-4,
        "{}",
        v[12 * 33 + 16]
    );
}

#[test]
fn passes_are_the_same_bytes_from_every_kernel_and_thread_count() {
    let moving = SCENE.to_string()
        + "timeline:
  keyframes:
    - { time: 0, position: [0, 1, 5], look_at: [0, 1, 0] }
    - { time: 0.5, position: [1, 1.5, 4], look_at: [0, 0.8, 0] }
";
    let tmp = scene("aov-kernels", &moving);
    let mut files = Vec::new();
    for (kernel, threads) in [("scalar", "1"), ("avx2", "3"), ("avx512", "2")] {
        let out = bin()
            .args(["render", "s.yaml", "-q", "--frames", "5", "-j", threads])
            .args(["-o", &format!("{kernel}_####.exr"), "--aov", ALL])
            .env("RAYREEL_KERNEL", kernel)
            .current_dir(&tmp)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        files.push(std::fs::read(tmp.join(format!("{kernel}_0005.exr"))).unwrap());
    }
    assert!(files.iter().all(|f| *f == files[0]));
    // f32 arithmetic changes the colour, never the passes (traced in f64).
    render_ok(
        &tmp,
        &[
            "--frames",
            "5",
            "-o",
            "p_####.exr",
            "--aov",
            ALL,
            "--precision",
            "f32",
        ],
    );
    let (a, b) = (
        read_exr(&tmp.join("scalar_0005.exr")),
        read_exr(&tmp.join("p_0005.exr")),
    );
    for name in [
        "N.X",
        "P.Z",
        "albedo.G",
        "objectId",
        "forward.u",
        "forward.v",
    ] {
        assert_eq!(channel(&a, name), channel(&b, name), "{name}");
    }
}

#[test]
fn passes_need_exr_files() {
    let tmp = scene("aov-refused", SCENE);
    let refused = |args: &[&str], says: &str| {
        let mut all = vec!["render", "s.yaml", "-q"];
        all.extend(args);
        let out = run_in(&tmp, &all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
    };
    refused(&["-o", "f.png", "--aov", "normal"], "`f.png` is not .exr");
    refused(
        &["--pipe", "raw", "--aov", "id"],
        "the --pipe stream cannot carry",
    );
    refused(
        &["--pipe", "png", "--aov", "id"],
        "the --pipe stream cannot carry",
    );
    let out = run_in(&tmp, &["render", "s.yaml", "--aov", "normals"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("normal, albedo, id, motion, position"),
        "{}",
        stderr(&out)
    );
    // In the file too, named as the file names it.
    let yaml = SCENE.replace("samples: 4 }", "samples: 4, aov: [normal, id] }");
    std::fs::write(tmp.join("s.yaml"), &yaml).unwrap();
    refused(&["-o", "f.png"], "render.aov");
    let out = run_in(&tmp, &["check", "s.yaml"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains(", passes normal,id\n"));
    // EXR files beside a stream carry them.
    let out = run_in(
        &tmp,
        &["render", "s.yaml", "-q", "--pipe", "raw", "-o", "f.exr"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let img = read_exr(&tmp.join("f.exr"));
    assert_eq!(channel(&img, "objectId")[12 * 33 + 16], 0.0);
}

#[test]
fn a_change_of_passes_makes_frames_stale_and_the_same_passes_keep_them() {
    let tmp = scene("aov-resume", SCENE);
    render_ok(&tmp, &["-o", "f.exr", "--aov", "motion,normal"]);
    let status = |aov: &[&str]| {
        let mut args = vec!["status", "s.yaml", "-o", "f.exr"];
        args.extend(aov);
        run_in(&tmp, &args).status.code()
    };
    assert_eq!(status(&["--aov", "normal,motion"]), Some(0));
    assert_eq!(status(&["--aov", "normal"]), Some(1));
    assert_eq!(status(&[]), Some(1));
    // Without passes the fingerprint is the one it always was.
    render_ok(&tmp, &["-o", "plain.exr"]);
    let out = run_in(&tmp, &["status", "s.yaml", "-o", "plain.exr"]);
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn chan_files_hold_nukes_columns() {
    let yaml = wall(
        "    - { time: 0, position: [0, 1, 5], look_at: [0, 1, 0] }
    - { time: 1, position: [0, 1, 5], look_at: [-5, 1, 5] }",
    );
    let tmp = scene("aov-chan", &yaml);
    let out = run_in(&tmp, &["camera", "s.yaml", "--format", "chan"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<Vec<f64>> = (text.lines())
        .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(lines.len(), 25);
    assert!(lines.iter().all(|l| l.len() == 8));
    let vfov = 2.0 * (25.0f64 / 33.0).atan().to_degrees();
    let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9);
    // Looking down -z: no rotation. Looking down -x: a pan of +90 degrees about y.
    assert!(
        close(&lines[0], &[0.0, 0.0, 1.0, 5.0, 0.0, 0.0, 0.0, vfov]),
        "{:?}",
        lines[0]
    );
    assert!(
        close(&lines[24], &[24.0, 0.0, 1.0, 5.0, 0.0, 90.0, 0.0, vfov]),
        "{:?}",
        lines[24]
    );
}

#[test]
fn meshes_and_textures_give_their_own_normals_and_colours() {
    let tmp = scratch("aov-examples");
    let repo = repo();
    for name in ["mesh", "checker"] {
        let file = repo.join(format!("sequences/{name}.yaml"));
        let pattern = format!("{name}_####.exr");
        let out = run_in(
            &tmp,
            &[
                "render",
                file.to_str().unwrap(),
                "-q",
                "--frames",
                "0",
                "--size",
                "48x27",
                "-o",
                &pattern,
                "--aov",
                ALL,
            ],
        );
        assert!(out.status.success(), "{name}: {}", stderr(&out));
    }
    // Mesh normals are unit length where something is hit, 0 elsewhere.
    let img = read_exr(&tmp.join("mesh_0000.exr"));
    let ids = channel(&img, "objectId");
    let n = ["N.X", "N.Y", "N.Z"].map(|c| channel(&img, c));
    assert!(ids.contains(&0.0), "the mesh is in view");
    for (i, &id) in ids.iter().enumerate() {
        let len = n
            .iter()
            .map(|c| f64::from(c[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        match id {
            -1.0 => assert_eq!(len, 0.0),
            _ => assert!((len - 1.0).abs() < 1e-6, "pixel {i}: |N| = {len}"),
        }
    }
    // A checker texture's albedo takes both its colours.
    let red = channel(&read_exr(&tmp.join("checker_0000.exr")), "albedo.R");
    let (lo, hi) = red
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    assert!(hi - lo > 0.5, "albedo.R from {lo} to {hi}");
}

#[test]
fn motion_carries_moving_objects_with_them() {
    // A still camera at (0, 1, 5), fov 90 (32.5 pixels per unit of x/z): a sphere sliding
    // 0.1 a frame to the right, a blob turning 5° a frame about its vertical axis, and a
    // still floor. Each pixel's point P (the position pass) is carried with its object and
    // projected again; the floor gives 0.
    let yaml = "
render: { width: 65, height: 49, max_depth: 1, samples: 1 }
camera: { position: [0, 1, 5], look_at: [0, 1, 0], fov: 90 }
objects:
  - plane: { point: [0, 0, 0], normal: [0, 1, 0], material: { diffuse: [0.5, 0.5, 0.5] } }
  - sphere: { center: [-1, 1, 0], radius: 0.6, material: { diffuse: [0.8, 0.2, 0.1] } }
    interpolation: linear
    keys:
      - { frame: 0, center: [-1, 1, 0] }
      - { frame: 24, center: [1.4, 1, 0] }
  - mesh: { file: blob.ply, scale: 0.6, translate: [1.2, 1.3, 0], material: { diffuse: [0.7, 0.6, 0.5] } }
    interpolation: linear
    keys:
      - { frame: 0, rotate: [0, 0, 0] }
      - { frame: 24, rotate: [0, 120, 0] }
lights:
  - ambient: { color: [1, 1, 1] }
";
    let tmp = scene("aov-objects", yaml);
    std::fs::copy(
        repo().join("sequences/models/blob.ply"),
        tmp.join("blob.ply"),
    )
    .unwrap();
    render_ok(
        &tmp,
        &[
            "-o",
            "f_##.exr",
            "--aov",
            "id,motion,position",
            "--frames",
            "6",
        ],
    );
    let img = read_exr(&tmp.join("f_06.exr"));
    let (u, v) = (channel(&img, "forward.u"), channel(&img, "forward.v"));
    let id = channel(&img, "objectId");
    let (px, py, pz) = (
        channel(&img, "P.X"),
        channel(&img, "P.Y"),
        channel(&img, "P.Z"),
    );
    // Where a point is in the image: column and row, as the spec's projection (v up).
    let project = |p: glam::DVec3| {
        let e = p - glam::DVec3::new(0.0, 1.0, 5.0);
        let z = -e.z;
        (32.5 * (e.x / z + 1.0), 24.5 - 32.5 * e.y / z)
    };
    let (mut sphere, mut blob) = (0, 0);
    for i in 0..u.len() {
        let p = glam::DVec3::new(px[i].into(), py[i].into(), pz[i].into());
        let q = match id[i] as i32 {
            1 => {
                sphere += 1;
                p + glam::DVec3::new(0.1, 0.0, 0.0)
            }
            2 => {
                blob += 1;
                // 5° more about the y axis through the blob's translate.
                let c = glam::DVec3::new(1.2, 1.3, 0.0);
                c + glam::DQuat::from_rotation_y(5f64.to_radians()) * (p - c)
            }
            _ => {
                assert_eq!((u[i], v[i]), (0.0, 0.0), "pixel {i} of the still floor");
                continue;
            }
        };
        let ((c0, r0), (c1, r1)) = (project(p), project(q));
        // P is rounded to f32 in the file: allow for that.
        assert!(
            (f64::from(u[i]) - (c1 - c0)).abs() < 2e-3,
            "pixel {i}: u {} vs {}",
            u[i],
            c1 - c0
        );
        assert!(
            (f64::from(v[i]) - (r0 - r1)).abs() < 2e-3,
            "pixel {i}: v {} vs {}",
            v[i],
            r0 - r1
        );
    }
    assert!(
        sphere > 40 && blob > 40,
        "{sphere} sphere and {blob} blob pixels"
    );
    // Nothing moves on frame 24 and after (the last keys hold), so there vectors are 0.
    render_ok(
        &tmp,
        &["-o", "g_##.exr", "--aov", "motion", "--frames", "24"],
    );
    let u = channel(&read_exr(&tmp.join("g_24.exr")), "forward.u");
    assert!(u.iter().all(|&u| u == 0.0));
}
