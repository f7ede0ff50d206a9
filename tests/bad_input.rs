//! Every bad-input fixture is rejected before rendering with the exact message its first line
//! promises (`# expect: LINE:COL: field.path: message`), exit code 2, and no output file.

mod common;
use common::*;

#[test]
fn each_fixture_gives_its_message_and_exit_2() {
    let dir = repo().join("tests/fixtures/bad");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".yaml"))
        .collect();
    names.sort();
    assert!(names.len() >= 25, "fixtures missing: {names:?}");
    for name in names {
        let text = std::fs::read_to_string(dir.join(&name)).unwrap();
        let expect = text
            .lines()
            .next()
            .unwrap()
            .strip_prefix("# expect: ")
            .unwrap();
        let out = run_in(&dir, &["check", &name]);
        assert_eq!(out.status.code(), Some(2), "{name}: {}", stderr(&out));
        assert_eq!(
            stderr(&out),
            format!("rayreel: {name}:{expect}\n"),
            "{name}"
        );
        assert!(out.stdout.is_empty(), "{name}: check printed a summary");

        let scratch = scratch(&format!("bad-{name}"));
        let out = run_in(
            &dir,
            &[
                "render",
                &name,
                "--output",
                scratch.join("f_####.png").to_str().unwrap(),
            ],
        );
        assert_eq!(out.status.code(), Some(2), "{name}");
        assert!(files(&scratch).is_empty(), "{name}: render wrote files");
    }
}

#[test]
fn bad_flags_exit_2_with_the_flag_named() {
    let talk = repo().join("sequences/talk.yaml");
    let talk = talk.to_str().unwrap();
    let tmp = scratch("flags");
    let out_pattern = tmp.join("f_####.png");
    let out_pattern = out_pattern.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["--size", "0x10"],
            "rayreel: invalid value '0x10' for '--size <WxH>': width must be 1 to 16384 pixels (got 0)",
        ),
        (
            vec!["--size", "100000x100000"],
            "'--size <WxH>': width must be 1 to 16384 pixels (got 100000)",
        ),
        (vec!["--size", "64"], "expected WIDTHxHEIGHT"),
        (
            vec!["--max-depth", "0"],
            "rayreel: invalid value '0' for '--max-depth <N>': 0 is not in 1..=10000",
        ),
        (
            vec!["--frames", "3"],
            "--frames: frame 3 is outside the timeline, which has frames 0-0",
        ),
        (vec!["--frames", "x-y"], "frame spec"),
    ] {
        let mut all = vec!["render", talk, "--output", out_pattern];
        all.extend(args.iter());
        let out = run_in(&tmp, &all);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(needle), "{args:?}: {}", stderr(&out));
    }
    assert!(files(&tmp).is_empty());
}

#[test]
fn missing_file_is_named() {
    let out = bin()
        .args(["check", "/nonexistent/seq.yaml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("/nonexistent/seq.yaml: cannot read"),
        "{}",
        stderr(&out)
    );
}
