//! Many processes, one sequence: shards, claim files, farm-friendly progress and `status`.
//! Every result is compared byte for byte with a single-process render.

mod common;
use common::*;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

fn seq() -> String {
    sequence(96, 54, &orbit(24, 2.0))
}

fn setup(name: &str) -> Scratch {
    with_clean_render(name, &seq())
}

fn spawn(dir: &Path, args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_rayreel"))
        .args(["render", "seq.yaml", "-o", "out/f_####.png", "-q"])
        .args(args)
        .current_dir(dir)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn assert_complete_and_identical(dir: &Path) {
    assert_same_files(&dir.join("clean"), &dir.join("out"));
    let status = run_in(dir, &["status", "seq.yaml", "-o", "out/f_####.png"]);
    assert_eq!(
        status.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&status.stdout)
    );
}

#[test]
fn two_and_four_shards_compose_into_the_single_render() {
    for n in [2, 4] {
        let tmp = setup(&format!("shards{n}"));
        let before = run_in(&tmp, &["status", "seq.yaml", "-o", "out/f_####.png"]);
        assert_eq!(before.status.code(), Some(1));
        assert!(String::from_utf8_lossy(&before.stdout).contains("missing     0-47"));
        let children: Vec<Child> = (1..=n)
            .map(|k| spawn(&tmp, &["--shard", &format!("{k}/{n}"), "--threads", "1"]))
            .collect();
        for c in children {
            let out = c.wait_with_output().unwrap();
            assert!(out.status.success(), "{}", stderr(&out));
        }
        assert_complete_and_identical(&tmp);
    }
}

#[test]
fn shard_auto_reads_slurm_and_kubernetes_indices() {
    let tmp = setup("auto");
    let dry = |envs: &[(&str, &str)], extra: &[&str]| {
        let mut cmd = bin();
        cmd.args([
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "--dry-run",
            "--shard",
            "auto",
        ])
        .args(extra);
        cmd.env_remove("SLURM_ARRAY_TASK_ID")
            .env_remove("JOB_COMPLETION_INDEX");
        for (k, v) in envs {
            cmd.env(k, v);
        }
        cmd.current_dir(&tmp).output().unwrap()
    };
    let slurm = dry(
        &[
            ("SLURM_ARRAY_TASK_ID", "11"),
            ("SLURM_ARRAY_TASK_MIN", "10"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ],
        &[],
    );
    assert!(
        String::from_utf8_lossy(&slurm.stdout).contains("12 frames: 12 missing"),
        "{}",
        stderr(&slurm)
    );
    let k8s = dry(&[("JOB_COMPLETION_INDEX", "2")], &["--shard-count", "3"]);
    assert!(
        String::from_utf8_lossy(&k8s.stdout).contains("16 frames: 16 missing"),
        "{}",
        stderr(&k8s)
    );
    let none = dry(&[], &[]);
    assert_eq!(none.status.code(), Some(2));
    assert!(
        stderr(&none).contains("neither is set"),
        "{}",
        stderr(&none)
    );
}

#[test]
fn claiming_processes_survive_one_being_killed() {
    let tmp = setup("claim");
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "clean/f_####.png",
            "--size",
            "640x360",
            // The setup's clean frames are of the file's size: only --force replaces them.
            "--force",
            "-q",
        ],
    );
    assert!(out.status.success());
    let mut children: Vec<Child> = (0..3)
        .map(|_| spawn(&tmp, &["--claim", "--threads", "1", "--size", "640x360"]))
        .collect();
    std::thread::sleep(Duration::from_millis(200));
    children[1].kill().unwrap();
    let killed = children[1].wait().unwrap();
    assert!(
        !killed.success(),
        "the process finished before it could be killed"
    );
    for c in [children.remove(2), children.remove(0)] {
        let out = c.wait_with_output().unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let leftovers: Vec<String> = files(&tmp.join("out"))
        .into_iter()
        .filter(|f| f.starts_with('.'))
        .collect();
    // The killed process may leave its claim or temporary; the survivors took its frames over.
    assert!(
        leftovers.iter().all(|f| f.contains(".rayreel-")),
        "{leftovers:?}"
    );
    for f in &leftovers {
        std::fs::remove_file(tmp.join("out").join(f)).unwrap();
    }
    assert_same_files(&tmp.join("clean"), &tmp.join("out"));
}

#[test]
fn json_progress_is_one_object_per_frame_event() {
    let tmp = setup("json");
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "--frames",
            "0-3",
            "--progress",
            "json",
        ],
    );
    assert!(out.status.success());
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "--frames",
            "0-5",
            "--progress",
            "json",
        ],
    );
    let events: Vec<serde_yaml::Value> = stderr(&out)
        .lines()
        .map(|l| serde_yaml::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect();
    let frames: Vec<&serde_yaml::Value> = events.iter().filter(|e| e["event"] == "frame").collect();
    assert_eq!(frames.len(), 6);
    let status = |s: &str| frames.iter().filter(|e| e["status"] == s).count();
    assert_eq!((status("up-to-date"), status("written")), (4, 2));
    assert!(frames.iter().all(
        |e| e["path"].as_str().is_some_and(|p| p.starts_with("out/f_"))
            && e["seconds"].as_f64().is_some()
    ));
    assert!(events.iter().any(|e| e["event"] == "summary"));
}

#[test]
fn status_lists_every_state_as_compact_specs() {
    let tmp = setup("status");
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "--frames",
            "0-11,20",
            "-q",
        ],
    );
    assert!(out.status.success());
    std::fs::write(tmp.join("out/f_0003.png"), b"broken").unwrap();
    image::RgbImage::new(4, 4)
        .save(tmp.join("out/f_0030.png"))
        .unwrap();
    let status = run_in(&tmp, &["status", "seq.yaml", "-o", "out/f_####.png"]);
    let text = String::from_utf8_lossy(&status.stdout);
    assert_eq!(status.status.code(), Some(1), "{text}");
    assert!(
        text.contains("48 frames: 12 up to date, 34 missing, 1 corrupt, 1 foreign"),
        "{text}"
    );
    assert!(text.contains("up to date  0-2,4-11,20"), "{text}");
    assert!(text.contains("missing     12-19,21-29,31-47"), "{text}");
    assert!(
        text.contains("corrupt     3") && text.contains("foreign     30"),
        "{text}"
    );
    // The same override flags as render: frames of another size are kept, never replaced.
    let other = run_in(
        &tmp,
        &[
            "status",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "--size",
            "48x27",
            "--frames",
            "0-2",
        ],
    );
    assert!(String::from_utf8_lossy(&other.stdout).contains("3 frames: 3 kept"));
}
