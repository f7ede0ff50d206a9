//! Things that move: keys on objects and lights, through the binary. A frame of an animated
//! scene is the still scene that writes its poses literally; motion blur is the same on any
//! thread count; a changed key makes stale only the frames whose poses it changes; bad keys
//! are refused with their file, line and field.

mod common;

use common::*;
use rayreel::timeline::motion::Thing;
use std::path::Path;

/// A scene where a mesh turns and moves, a sphere travels and grows, a textured plane tilts
/// (its texture's axis turning with it), a point, a spot and a directional light move and
/// change colour, and a rect light moves and turns: every kind of keyed field.
/// `keys` is what follows the sphere's keys (e.g. nothing, or a shutter).
fn animated(render: &str) -> String {
    format!(
        "render: {{ width: 96, height: 64{render} }}
camera: {{ position: [0, 1.2, 4], look_at: [0, 0.4, 0], fov: 55 }}
materials:
  clay: {{ ambient: [0.1, 0.08, 0.06], diffuse: [0.7, 0.55, 0.45], specular: [0.4, 0.4, 0.4], shininess: 60 }}
  red: {{ ambient: [0.1, 0, 0], diffuse: [0.8, 0.1, 0.1], specular: [1, 1, 1], shininess: 80, reflection: 0.2 }}
  grey: {{ diffuse: [0.6, 0.6, 0.6], specular: [0, 0, 0] }}
  wood: {{ diffuse: {{ image: wood.png, scale: [0.5, 0.5] }}, specular: [0, 0, 0] }}
objects:
  - plane: {{ point: [0, 0, 0], normal: [0, 1, 0], u_axis: [1, 0, 0.3], material: wood }}
    keys:
      - {{ time: 0 }}
      - {{ time: 1, normal: [0.1, 1, 0.05], point: [0, -0.1, 0] }}
  - mesh: {{ file: blob.ply, material: clay, scale: 0.5, translate: [0.8, 0.5, 0] }}
    keys:
      - {{ frame: 0, rotate: [0, 0, 0] }}
      - {{ frame: 12, rotate: [10, 200, 0], translate: [0.6, 0.6, 0.3] }}
      - {{ frame: 24, rotate: [0, 360, 30], scale: [0.6, 0.4, 0.5], ease: stop }}
  - sphere: {{ center: [-0.8, 0.4, 0], radius: 0.4, material: red }}
    interpolation: linear
    keys:
      - {{ time: 0, center: [-1.2, 0.4, 0] }}
      - {{ time: 17/24, center: [-0.6, 0.7, 0.5], radius: 0.3 }}
      - {{ time: 1, center: [-0.2, 0.4, 0], radius: 0.45 }}
lights:
  - point: {{ position: [3, 4, 3], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
    keys:
      - {{ time: 0 }}
      - {{ time: 1, position: [-3, 3, 3], diffuse: [0.4, 0.5, 1] }}
  - spot: {{ position: [0, 3, 2], direction: [0, -1, -0.5], inner_angle: 10, outer_angle: 20, diffuse: [0.5, 0.5, 0.5], specular: [0.2, 0.2, 0.2] }}
    keys:
      - {{ time: 0.25 }}
      - {{ time: 0.75, direction: [0.3, -1, -0.4], inner_angle: 15, outer_angle: 35 }}
  - directional: {{ direction: [-1, -1, -1], diffuse: [0.2, 0.2, 0.2], specular: [0, 0, 0] }}
    keys:
      - {{ time: 0, direction: [-1, -1, -1] }}
      - {{ time: 1, direction: [1, -1, -1], specular: [0.3, 0.3, 0.3] }}
  - rect: {{ corner: [-1, 2.5, -0.5], edge_u: [1, 0, 0], edge_v: [0, 0, 1], samples: 4, diffuse: [0.3, 0.3, 0.3], specular: [0.2, 0.2, 0.2] }}
    keys:
      - {{ time: 0 }}
      - {{ time: 1, corner: [-0.5, 2.5, -1], edge_u: [0.8, 0.3, 0], edge_v: [0, 0.2, 1.2] }}
"
    )
}

fn setup(name: &str, yaml: &str) -> Scratch {
    let tmp = scratch(name);
    std::fs::copy(
        repo().join("sequences/models/blob.ply"),
        tmp.join("blob.ply"),
    )
    .unwrap();
    std::fs::copy(
        repo().join("sequences/textures/wood.png"),
        tmp.join("wood.png"),
    )
    .unwrap();
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    tmp
}

fn ok(dir: &Path, args: &[&str]) -> String {
    let out = run_in(dir, args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// `yaml` with every `keys:` block removed and each keyed thing's fields replaced by their
/// values at frame n, as `rayreel camera --object I | --light I --format json` prints them
/// (the shortest decimal that reads back as the same f64).
fn still_at(yaml: &str, seq: &rayreel::sequence::Sequence, dir: &Path, n: u64) -> String {
    let mut poses = seq
        .timeline
        .motion
        .iter()
        .map(|rig| exported(dir, rig.thing, n));
    let lines: Vec<&str> = yaml
        .lines()
        .filter(|l| !l.trim_start().starts_with("interpolation:"))
        .collect();
    let mut out = String::new();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        i += 1;
        let keyed = lines.get(i).is_some_and(|l| l.trim_start() == "keys:");
        if !(line.starts_with("  - ") && keyed) {
            out += line;
            out += "\n";
            continue;
        }
        let mut fields = poses.next().unwrap();
        out += &replace_fields(line, &mut fields);
        out += "\n";
        i += 1;
        while lines.get(i).is_some_and(|l| l.starts_with("      - ")) {
            i += 1;
        }
    }
    out
}

/// The flow mapping of `line` with each field named in `fields` replaced (or added).
fn replace_fields(line: &str, fields: &mut Vec<String>) -> String {
    let open = line.find("{ ").unwrap() + 2;
    let close = line.rfind(" }").unwrap();
    let body = &line[open..close];
    // Split at top-level commas.
    let (mut parts, mut depth, mut start) = (Vec::new(), 0, 0);
    for (i, c) in body.char_indices() {
        match c {
            '[' | '{' => depth += 1,
            ']' | '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(body[start..i].trim().to_string());
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(body[start..].trim().to_string());
    let name = |s: &str| s.split(':').next().unwrap().trim().to_string();
    let given: Vec<String> = fields
        .iter()
        .flat_map(|f| {
            f.split(", ")
                .filter(|p| p.contains(':'))
                .map(name)
                .collect::<Vec<_>>()
        })
        .collect();
    parts.retain(|p| !given.contains(&name(p)));
    parts.append(fields);
    format!("{}{}{}", &line[..open], parts.join(", "), &line[close..])
}

/// The fields `camera --format json` prints for one moving thing at frame n, as YAML.
fn exported(dir: &Path, thing: Thing, n: u64) -> Vec<String> {
    let (flag, i) = match thing {
        Thing::Object(i) => ("--object", i),
        Thing::Light(i) => ("--light", i),
    };
    let (i, n) = (i.to_string(), n.to_string());
    let args = ["camera", "seq.yaml", flag, &i, "--format", "json"];
    let line = ok(dir, &[&args[..], &["--frames", &n]].concat());
    let json: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&line).unwrap();
    json.iter()
        .filter(|(k, _)| !["frame", "time"].contains(&k.as_str()))
        .map(|(k, v)| format!("{k}: {v}"))
        .collect()
}

#[test]
fn a_frame_is_the_still_scene_that_writes_its_poses() {
    let yaml = animated("");
    let tmp = setup("motion-exact", &yaml);
    let seq = rayreel::sequence::load(&tmp.join("seq.yaml")).unwrap();
    assert_eq!(
        seq.timeline.frame_count, 25,
        "the film ends on the last key"
    );
    for n in [0u64, 7, 17, 24] {
        let still = still_at(&yaml, &seq, &tmp, n);
        assert!(!still.contains("keys:"), "{still}");
        let name = format!("still{n}.yaml");
        std::fs::write(tmp.join(&name), &still).unwrap();
        let nth = n.to_string();
        let first = format!("{n}");
        ok(
            &tmp,
            &[
                "render",
                "seq.yaml",
                "--frames",
                &nth,
                "-o",
                "anim/f_####.png",
                "-q",
            ],
        );
        ok(
            &tmp,
            &[
                "render",
                &name,
                "--first-frame",
                &first,
                "-o",
                "still/f_####.png",
                "-q",
            ],
        );
        let file = format!("f_{n:04}.png");
        let a = read_png(&tmp.join("anim").join(&file));
        let b = read_png(&tmp.join("still").join(&file));
        assert!(a == b, "frame {n} differs from the still scene:\n{still}");
    }
    // And the frames differ from each other: things did move.
    let f0 = read_png(&tmp.join("anim/f_0000.png"));
    let f24 = read_png(&tmp.join("anim/f_0024.png"));
    assert!(f0 != f24);
}

#[test]
fn things_hold_before_their_first_key_and_after_their_last() {
    // Without the rect light, whose points are drawn anew each frame.
    let scene = animated("");
    let scene = &scene[..scene.find("  - rect:").unwrap()];
    let yaml = format!(
        "{}timeline:\n  duration: 2\n  keyframes: [ {{ time: 0, position: [0, 1.2, 4], look_at: [0, 0.4, 0], fov: 55 }} ]\n",
        scene
            .replace("{ time: 0, center: [-1.2", "{ time: 0.25, center: [-1.2")
            .replace("{ time: 0 }", "{ time: 0.25 }")
            .replace("{ time: 0, direction", "{ time: 0.25, direction")
            .replace("frame: 0, rotate", "frame: 6, rotate")
    );
    let tmp = setup("motion-hold", &yaml);
    ok(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "--frames",
            "0,3,6,24,30,47",
            "--samples",
            "1",
            "-q",
        ],
    );
    let frame = |n: u32| read_png(&tmp.join(format!("frames/seq/frame_{n:04}.png")));
    assert!(frame(0) == frame(3), "held before the first key");
    assert!(frame(0) == frame(6), "at the first key");
    assert!(
        frame(24) == frame(30) && frame(30) == frame(47),
        "held after the last key"
    );
    assert!(frame(6) != frame(24));
}

#[test]
fn motion_blur_is_the_same_on_any_thread_count() {
    let tmp = setup("motion-blur", &animated(", shutter: 270, samples: 6"));
    for threads in ["1", "2", "3"] {
        let out = format!("j{threads}/f_####.png");
        let args = [
            "render", "seq.yaml", "--frames", "11", "-j", threads, "-o", &out, "-q",
        ];
        ok(&tmp, &args);
    }
    assert_same_files(&tmp.join("j1"), &tmp.join("j2"));
    assert_same_files(&tmp.join("j1"), &tmp.join("j3"));
    // The blur is there: the frame differs from the same frame with the shutter closed.
    let sharp = animated(", samples: 6");
    std::fs::write(tmp.join("sharp.yaml"), sharp).unwrap();
    ok(
        &tmp,
        &[
            "render",
            "sharp.yaml",
            "--frames",
            "11",
            "-o",
            "sharp/f_####.png",
            "-q",
        ],
    );
    assert!(read_png(&tmp.join("j1/f_0011.png")) != read_png(&tmp.join("sharp/f_0011.png")));
}

/// `rayreel status` lines: (state, frames), e.g. ("up to date", "0-12").
fn status(dir: &Path, file: &str, args: &[&str]) -> Vec<(String, String)> {
    let mut all = vec!["status", file];
    all.extend(args);
    let out = run_in(dir, &all);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let l = l.trim();
            let (state, frames) = l.rsplit_once(' ')?;
            (!state.contains(':')).then(|| (state.trim().to_string(), frames.to_string()))
        })
        .collect()
}

/// Keys at frames 0, 12, 24 (linear): moving the last key changes the poses of frames 13 to
/// 24 only; with an open shutter, frame 12 sees past its key too.
fn late_key(last: &str, render: &str) -> String {
    format!(
        "render: {{ width: 32, height: 24{render} }}
camera: {{ position: [0, 1, 4], look_at: [0, 0.4, 0] }}
materials: {{ red: {{ diffuse: [0.8, 0.1, 0.1], specular: [0, 0, 0] }} }}
objects:
  - sphere: {{ center: [0, 0.4, 0], radius: 0.4, material: red }}
    interpolation: linear
    keys:
      - {{ frame: 0, center: [-1, 0.4, 0] }}
      - {{ frame: 12, center: [0, 0.4, 0] }}
      - {{ frame: 24, center: [{last}, 0.4, 0] }}
lights:
  - point: {{ position: [3, 4, 3], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
"
    )
}

#[test]
fn a_changed_late_key_makes_stale_only_the_frames_it_moves() {
    let tmp = scratch("motion-stale");
    for (render, fresh, stale) in [("", "0-12", "13-24"), (", shutter: 180", "0-11", "12-24")] {
        std::fs::write(tmp.join("a.yaml"), late_key("1", render)).unwrap();
        std::fs::write(tmp.join("b.yaml"), late_key("1.5", render)).unwrap();
        let dir = if render.is_empty() {
            "sharp/f_####.png"
        } else {
            "blur/f_####.png"
        };
        ok(&tmp, &["render", "a.yaml", "-o", dir, "-q"]);
        let all_fresh = status(&tmp, "a.yaml", &["-o", dir]);
        assert_eq!(all_fresh, [("up to date".to_string(), "0-24".to_string())]);
        let after = status(&tmp, "b.yaml", &["-o", dir]);
        assert_eq!(
            after,
            [
                ("up to date".to_string(), fresh.to_string()),
                ("stale".to_string(), stale.to_string())
            ],
            "{render}"
        );
        // Re-rendering the edited file redoes exactly those frames.
        let out = run_in(&tmp, &["render", "b.yaml", "-o", dir]);
        assert!(out.status.success(), "{}", stderr(&out));
        assert_eq!(
            status(&tmp, "b.yaml", &["-o", dir]),
            [("up to date".to_string(), "0-24".to_string())]
        );
    }
}

/// The message for `yaml` (with blob.ply beside it): exit 2, naming `seq.yaml:LINE:` and
/// `field`.
fn refused(yaml: &str, line: usize, field: &str) -> String {
    let tmp = setup("motion-bad", yaml);
    let out = run_in(&tmp, &["check", "seq.yaml"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("seq.yaml:{line}:")), "{field}: {err}");
    assert!(err.contains(field), "{field}: {err}");
    err
}

#[test]
fn bad_keys_are_refused_with_file_line_and_field() {
    let base = animated("");
    let line_of = |needle: &str| base.lines().position(|l| l.contains(needle)).unwrap() + 1;
    // A field the thing cannot key.
    let bad = base.replace("{ frame: 12, rotate", "{ frame: 12, radius: 2, rotate");
    let err = refused(
        &bad,
        line_of("frame: 12, rotate"),
        "objects[1].keys[1].radius",
    );
    assert!(err.contains("scale, rotate, translate"), "{err}");
    // A field no key can set.
    let bad = base.replace("{ time: 0.25 }", "{ time: 0.25, material: red }");
    refused(&bad, line_of("{ time: 0.25 }"), "material");
    // Keys out of order.
    let bad = base.replace("{ frame: 24, rotate", "{ frame: 10, rotate");
    let err = refused(
        &bad,
        line_of("frame: 24, rotate"),
        "objects[1].keys[2].frame",
    );
    assert!(err.contains("increase"), "{err}");
    // A non-finite value.
    let bad = base.replace("center: [-0.6, 0.7, 0.5]", "center: [-0.6, .nan, 0.5]");
    refused(
        &bad,
        line_of("center: [-0.6, 0.7"),
        "objects[2].keys[1].center[1]",
    );
    // A scale crossing zero.
    let bad = base.replace("scale: [0.6, 0.4, 0.5]", "scale: [0.6, -0.4, 0.5]");
    let err = refused(
        &bad,
        line_of("scale: [0.6, 0.4"),
        "objects[1].keys[2].scale",
    );
    assert!(err.contains("cross zero"), "{err}");
    // A spot whose inner angle passes its outer one.
    let bad = base.replace(
        "inner_angle: 15, outer_angle: 35",
        "inner_angle: 40, outer_angle: 35",
    );
    refused(
        &bad,
        line_of("inner_angle: 15"),
        "lights[1].keys[1].inner_angle",
    );
    // A direction that turns straight back.
    let bad = base.replace("direction: [1, -1, -1]", "direction: [1, 1, 1]");
    refused(
        &bad,
        line_of("direction: [1, -1, -1]"),
        "lights[2].keys[1].direction",
    );
    // A rect light whose edges turn edge-on at a key, and one that flips between keys.
    let bad = base.replace("edge_v: [0, 0.2, 1.2]", "edge_v: [1.6, 0.6, 0]");
    let err = refused(
        &bad,
        line_of("edge_v: [0, 0.2, 1.2]"),
        "lights[3].keys[1].edge_v",
    );
    assert!(err.contains("parallel"), "{err}");
    let bad = base.replace("edge_v: [0, 0.2, 1.2]", "edge_v: [0, 0.2, -1.2]");
    let err = refused(&bad, line_of("edge_v: [0, 0.2, 1.2]"), "lights[3].keys[1]");
    assert!(err.contains("edge-on or flip"), "{err}");
}

#[test]
fn check_lists_what_moves_and_over_which_frames() {
    let tmp = setup("motion-check", &animated(""));
    // `check` wraps lines past 120 columns under the summary's indent.
    let out = ok(&tmp, &["check", "seq.yaml"]).replace("\n              ", " ");
    let line = "  moving:     objects[0] (point, normal) frames 0-24; objects[1] (scale, rotate, translate) frames 0-24; objects[2] (center, radius) frames 0-24; lights[0] (position, diffuse) frames 0-24, and 3 more\n";
    assert!(out.contains(line), "{out}");
    // A scene without keys says nothing of it.
    let still = std::fs::read_to_string(repo().join("sequences/talk.yaml")).unwrap();
    std::fs::write(tmp.join("still.yaml"), still).unwrap();
    assert!(!ok(&tmp, &["check", "still.yaml"]).contains("moving:"));
}

#[test]
fn camera_exports_the_poses_of_moving_things() {
    let tmp = setup("motion-export", &animated(""));
    // The turntable's chan: the placement's ZXY angles, the pan unwrapped to one full turn.
    let file = repo().join("sequences/turntable.yaml");
    let file = file.to_str().unwrap();
    let chan = ok(&tmp, &["camera", file, "--object", "1", "--format", "chan"]);
    let rows: Vec<Vec<f64>> = chan
        .lines()
        .map(|l| l.split(' ').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 97, "{chan}");
    for (n, row) in rows.iter().enumerate() {
        assert_eq!(row[..4], [n as f64, 0.0, 0.05, 0.0], "{chan}");
        assert!((row[5] - 3.75 * n as f64).abs() < 1e-9, "{chan}");
        assert_eq!((row[4], row[6]), (0.0, 0.0), "{chan}");
    }
    // A spot light looks along its direction; csv names every keyed column.
    let spot = ok(
        &tmp,
        &["camera", "seq.yaml", "--light", "1", "--format", "chan"],
    );
    let first: Vec<f64> = spot
        .lines()
        .next()
        .unwrap()
        .split(' ')
        .map(|x| x.parse().unwrap())
        .collect();
    let tilt = (-1.0f64 / 1.25f64.sqrt()).asin().to_degrees();
    assert!((first[4] - tilt).abs() < 1e-9 && first[5] == 0.0, "{spot}");
    let csv = ok(
        &tmp,
        &["camera", "seq.yaml", "--light", "1", "--frames", "0"],
    );
    assert!(
        csv.starts_with("frame,time,direction_x,direction_y,direction_z,inner_angle,outer_angle\n"),
        "{csv}"
    );
    // A rect light: its corner, looking the way it shines (down), up along edge_v (+z).
    let rect = ok(
        &tmp,
        &[
            "camera", "seq.yaml", "--light", "3", "--format", "chan", "--frames", "0",
        ],
    );
    assert_eq!(rect, "0 -1.0 2.5 -0.5 -90.0 0.0 180.0\n");
    // A plane whose normal is keyed gives its texture's axis too.
    let json = ok(
        &tmp,
        &[
            "camera", "seq.yaml", "--object", "0", "--frames", "0", "--format", "json",
        ],
    );
    assert!(json.contains("\"u_axis\": ["), "{json}");
    // What cannot be exported says why, naming the thing; exit 2.
    let still = animated("").replace("    keys:\n      - { time: 0 }\n      - { time: 1, normal: [0.1, 1, 0.05], point: [0, -0.1, 0] }\n", "");
    std::fs::write(tmp.join("still.yaml"), still).unwrap();
    for (args, says) in [
        (
            &["camera", "still.yaml", "--object", "0"][..],
            "objects[0] has no keys",
        ),
        (
            &["camera", "seq.yaml", "--object", "wheel"],
            "no object is named `wheel`",
        ),
        (
            &["camera", "seq.yaml", "--object", "3"],
            "the sequence has 3 objects",
        ),
        (
            &["camera", "seq.yaml", "--light", "4"],
            "the sequence has 4 lights",
        ),
        (
            &["camera", "seq.yaml", "--object", "0", "--format", "chan"],
            "objects[0] is a plane",
        ),
    ] {
        let out = run_in(&tmp, args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}
