//! Keeps the front door honest: README.md stays at most 15 KB and indexes every reference page;
//! every relative link in README.md, ARCHITECTURE.md, CONTRIBUTING.md and docs/ resolves
//! (anchors included); every `rayreel …` command shown in the README's code blocks and the
//! docs' shell blocks parses, each of its flags appearing in its subcommand's `--help`; the
//! README's two commands (render the default sequence, run the tests) are there and work; its
//! sequence files load; and no page cites issue numbers.

mod common;
use common::*;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Largest README.md, in bytes.
const README_MAX_BYTES: usize = 15 * 1024;

const SUBCOMMANDS: [&str; 7] = [
    "render", "status", "check", "preview", "camera", "measure", "bench",
];

/// README.md, ARCHITECTURE.md, CONTRIBUTING.md and every Markdown page under docs/.
fn pages() -> Vec<PathBuf> {
    let root = repo();
    let mut pages: Vec<PathBuf> = ["README.md", "ARCHITECTURE.md", "CONTRIBUTING.md"]
        .iter()
        .map(|p| root.join(p))
        .collect();
    pages.extend(docs_pages());
    pages
}

/// Every `.md` file below docs/, sorted.
fn docs_pages() -> Vec<PathBuf> {
    let docs = repo().join("docs");
    let mut out: Vec<PathBuf> = files(&docs)
        .into_iter()
        .filter(|f| f.ends_with(".md"))
        .map(|f| docs.join(f))
        .collect();
    out.sort();
    out
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn name(path: &Path) -> String {
    path.strip_prefix(repo())
        .unwrap_or(path)
        .display()
        .to_string()
}

/// A fenced code block: its info string (`sh`, `yaml`, or empty) and its lines.
struct Block {
    info: String,
    lines: Vec<String>,
}

/// The fenced code blocks of a page, and its prose (every line outside them).
fn split(text: &str) -> (Vec<Block>, Vec<String>) {
    let (mut blocks, mut prose) = (Vec::new(), Vec::new());
    let mut open: Option<Block> = None;
    for line in text.lines() {
        let fence = line.trim_start().starts_with("```");
        match (&mut open, fence) {
            (None, true) => {
                let info = line.trim_start().trim_start_matches('`').trim().to_string();
                open = Some(Block {
                    info,
                    lines: Vec::new(),
                })
            }
            (None, false) => prose.push(line.to_string()),
            (Some(_), true) => blocks.push(open.take().unwrap()),
            (Some(b), false) => b.lines.push(line.to_string()),
        }
    }
    assert!(open.is_none(), "a code block is never closed");
    (blocks, prose)
}

/// Removes inline code spans (`…`), so that text shown as code is not read as a link.
fn without_code_spans(line: &str) -> String {
    let mut out = String::new();
    let mut in_code = false;
    for c in line.chars() {
        if c == '`' {
            in_code = !in_code;
        } else if !in_code {
            out.push(c);
        }
    }
    out
}

/// The targets of the Markdown links and images in `prose`: `[text](target)`.
fn link_targets(prose: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    for line in prose {
        let line = without_code_spans(line);
        let mut rest = line.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let end = after
                .find(')')
                .expect("a link target is closed on its line");
            out.push(after[..end].trim().to_string());
            rest = &after[end..];
        }
    }
    out
}

/// GitHub's anchor for a heading: code marks dropped, lower case, punctuation dropped, spaces
/// to hyphens.
fn slug(heading: &str) -> String {
    heading
        .replace('`', "")
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors a page's headings get, with GitHub's `-1`, `-2` suffixes for repeated headings.
fn anchors(text: &str) -> BTreeSet<String> {
    let (_, prose) = split(text);
    let mut seen = BTreeSet::new();
    for line in prose {
        let Some(heading) = line.strip_prefix('#') else {
            continue;
        };
        let base = slug(heading.trim_start_matches('#').trim());
        let mut anchor = base.clone();
        let mut n = 1;
        while seen.contains(&anchor) {
            anchor = format!("{base}-{n}");
            n += 1;
        }
        seen.insert(anchor);
    }
    seen
}

#[test]
fn readme_is_a_front_door_of_at_most_15_kb() {
    let size = std::fs::metadata(repo().join("README.md")).unwrap().len() as usize;
    assert!(
        size <= README_MAX_BYTES,
        "README.md is {size} bytes, more than {README_MAX_BYTES}: move reference material to docs/"
    );
}

#[test]
fn every_relative_link_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = read(&page);
        let (_, prose) = split(&text);
        for target in link_targets(&prose) {
            if target.starts_with("http://")
                || target.starts_with("https://")
                || target.starts_with("mailto:")
            {
                continue;
            }
            checked += 1;
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let file = if path.is_empty() {
                page.clone()
            } else {
                page.parent().unwrap().join(path)
            };
            if !file.exists() {
                broken.push(format!("{}: {target}: no such file", name(&page)));
                continue;
            }
            let Some(anchor) = anchor else { continue };
            if file.extension().is_some_and(|e| e == "md")
                && !anchors(&read(&file)).contains(anchor)
            {
                broken.push(format!("{}: {target}: no such heading", name(&page)));
            }
        }
    }
    assert!(
        checked > 50,
        "only {checked} links found: is the parser right?"
    );
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn the_slug_is_githubs() {
    assert_eq!(slug("f32, exactly"), "f32-exactly");
    assert_eq!(
        slug("`ease` values of older files"),
        "ease-values-of-older-files"
    );
    let text = "# A\n## Frames\n```\n# not a heading\n```\n## Frames\n";
    let found: Vec<String> = anchors(text).into_iter().collect();
    assert_eq!(found, ["a", "frames", "frames-1"]);
}

#[test]
fn readme_indexes_every_reference_page() {
    let (_, prose) = split(&read(&repo().join("README.md")));
    let linked: BTreeSet<String> = link_targets(&prose)
        .into_iter()
        .map(|t| t.split('#').next().unwrap().to_string())
        .collect();
    let missing: Vec<String> = docs_pages()
        .iter()
        .map(|p| name(p))
        .chain(["ARCHITECTURE.md".into(), "CONTRIBUTING.md".into()])
        .filter(|p| !linked.contains(p))
        .collect();
    assert!(
        missing.is_empty(),
        "README.md does not link to: {missing:?}"
    );
}

/// Splits a shell line into words, keeping quoted strings whole (quotes removed).
fn words(line: &str) -> Vec<String> {
    let (mut out, mut word, mut quote) = (Vec::new(), String::new(), None);
    let mut started = false;
    for c in line.chars() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => word.push(c),
            None if c == '\'' || c == '"' => {
                quote = Some(c);
                started = true;
            }
            None if c.is_whitespace() => {
                if started || !word.is_empty() {
                    out.push(std::mem::take(&mut word));
                }
                started = false;
            }
            None => {
                word.push(c);
                started = true;
            }
        }
    }
    if started || !word.is_empty() {
        out.push(word);
    }
    out
}

/// The `rayreel` command lines in a block's lines: continuation lines joined, a `$ ` prompt
/// removed, then each pipeline stage whose program is rayreel (or `cargo run --release --`,
/// or the Slurm script, whose arguments go to `rayreel render`), as its arguments, up to a
/// comment, a redirection or GNU parallel's `:::`. `{}` (parallel's placeholder) becomes 1.
fn commands(lines: &[String], only_prompts: bool) -> Vec<Vec<String>> {
    let mut joined = Vec::new();
    let mut current = String::new();
    for line in lines {
        match line.strip_suffix('\\') {
            Some(head) => current.push_str(head),
            None => {
                current.push_str(line);
                joined.push(std::mem::take(&mut current));
            }
        }
    }
    let mut out = Vec::new();
    for line in joined {
        let line = line.trim();
        let line = match line.strip_prefix("$ ") {
            Some(rest) => rest,
            None if only_prompts => continue,
            None => line,
        };
        let words = words(line);
        for stage in words.split(|w| w == "|" || w == "&&" || w == ";" || w == "||") {
            let stage: Vec<&str> = stage
                .iter()
                .map(String::as_str)
                .take_while(|w| !w.starts_with('#'))
                .collect();
            let start = if let Some(i) = stage.iter().position(|w| *w == "rayreel") {
                i + 1
            } else if let Some(i) = stage
                .windows(4)
                .position(|w| w == ["cargo", "run", "--release", "--"])
            {
                i + 4
            } else if let Some(i) = stage.iter().position(|w| w.ends_with("render.sbatch")) {
                out.push(render_args(&stage[i + 1..], Some("render")));
                continue;
            } else {
                continue;
            };
            out.push(render_args(&stage[start..], None));
        }
    }
    out
}

/// The arguments of one rayreel invocation, stopped at a redirection or `:::`.
fn render_args(words: &[&str], subcommand: Option<&str>) -> Vec<String> {
    subcommand
        .into_iter()
        .chain(
            words
                .iter()
                .copied()
                .take_while(|w| *w != ":::" && !w.starts_with('>') && !w.starts_with("2>")),
        )
        .map(|w| w.replace("{}", "1"))
        .collect()
}

/// Every rayreel command shown: all of the README's code blocks, and the shell blocks and
/// `$ ` prompts of the other pages.
fn shown_commands() -> Vec<(String, Vec<String>)> {
    let mut out = Vec::new();
    for page in pages() {
        let readme = page.ends_with("README.md") && page.parent() == Some(repo().as_path());
        let (blocks, _) = split(&read(&page));
        for block in blocks {
            if block.info == "yaml" {
                continue;
            }
            let shell = readme || block.info == "sh";
            for args in commands(&block.lines, !shell) {
                out.push((name(&page), args));
            }
        }
    }
    out
}

#[test]
fn command_lines_are_found_as_a_shell_reads_them() {
    let lines: Vec<String> = [
        "$ rayreel camera seq.yaml --format json --frames 72",
        "rayreel render a.yaml --pipe raw --quiet \\",
        "  | ffmpeg -f rawvideo -i - out.mp4",
        "parallel -j4 rayreel render a.yaml --shard {}/4 ::: 1 2 3 4   # comment --bogus",
        "sbatch --array=0-3 examples/slurm/render.sbatch a.yaml --size 640x360",
        "cargo run --release -- bench --only kernels > /dev/null",
        "ffmpeg -framerate 24 -i frames/orbit/frame_%04d.png orbit.mp4",
        "rayreel render 'a b.yaml' -o out/f_####.png",
    ]
    .map(String::from)
    .to_vec();
    let found = commands(&lines, false);
    let want: Vec<Vec<&str>> = vec![
        vec!["camera", "seq.yaml", "--format", "json", "--frames", "72"],
        vec!["render", "a.yaml", "--pipe", "raw", "--quiet"],
        vec!["render", "a.yaml", "--shard", "1/4"],
        vec!["render", "a.yaml", "--size", "640x360"],
        vec!["bench", "--only", "kernels"],
        vec!["render", "a b.yaml", "-o", "out/f_####.png"],
    ];
    assert_eq!(found, want);
    assert_eq!(commands(&lines, true), want[..1].to_vec());
}

/// `rayreel SUBCOMMAND --help`.
fn help(subcommand: &str) -> String {
    let out = bin().args([subcommand, "--help"]).output().unwrap();
    assert!(
        out.status.success(),
        "{subcommand} --help: {}",
        stderr(&out)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Whether `flag` (`--size`, `-o`) is listed in a `--help` text.
fn listed(help: &str, flag: &str) -> bool {
    help.split(|c: char| c.is_whitespace() || c == ',' || c == '[' || c == ']')
        .any(|w| w == flag || w.split_once('=').is_some_and(|(f, _)| f == flag))
}

#[test]
fn every_command_shown_parses() {
    let shown = shown_commands();
    let in_readme = shown.iter().filter(|(p, _)| p == "README.md").count();
    assert!(
        in_readme >= 15,
        "only {in_readme} commands found in README.md"
    );
    let helps: Vec<(&str, String)> = SUBCOMMANDS.iter().map(|s| (*s, help(s))).collect();
    let mut wrong = Vec::new();
    for (page, args) in &shown {
        let line = args.join(" ");
        let Some((_, help)) = helps
            .iter()
            .find(|(s, _)| Some(*s) == args.first().map(|a| a.as_str()))
        else {
            wrong.push(format!("{page}: rayreel {line}: no such subcommand"));
            continue;
        };
        for flag in args[1..]
            .iter()
            .filter(|a| a.starts_with('-') && a.len() > 1)
        {
            let flag = flag.split_once('=').map_or(flag.as_str(), |(f, _)| f);
            if !listed(help, flag) {
                wrong.push(format!(
                    "{page}: rayreel {line}: {flag} is not in `rayreel {} --help`",
                    args[0]
                ));
            }
        }
        // clap reads every flag and value before it acts on --help: a flag that does not
        // exist, or a value it refuses, fails here.
        let out = bin().args(args).arg("--help").output().unwrap();
        if !out.status.success() {
            wrong.push(format!("{page}: rayreel {line}: {}", stderr(&out).trim()));
        }
    }
    assert!(
        wrong.is_empty(),
        "commands that do not parse:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn readme_gives_the_two_commands_and_they_work() {
    let readme = read(&repo().join("README.md"));
    let (blocks, _) = split(&readme);
    let shell: Vec<&String> = blocks
        .iter()
        .filter(|b| b.info == "sh")
        .flat_map(|b| &b.lines)
        .collect();
    let has = |command: &str| {
        shell
            .iter()
            .any(|l| l.split('#').next().unwrap().trim() == command)
    };
    assert!(
        has("rayreel render sequences/orbit.yaml"),
        "the render command"
    );
    assert!(has("cargo test --release"), "the test command");
    // CI runs the same test command.
    let ci = read(&repo().join(".ci/run"));
    assert!(
        ci.lines()
            .any(|l| l.trim().ends_with("cargo test --release")),
        ".ci/run no longer runs `cargo test --release`"
    );
    // The default job is valid and would render its 144 frames (a dry run creates nothing).
    let tmp = scratch("readme-default-job");
    let orbit = repo().join("sequences/orbit.yaml");
    let out = run_in(&tmp, &["render", orbit.to_str().unwrap(), "--dry-run"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let plan = String::from_utf8_lossy(&out.stdout);
    assert!(plan.contains("144 frames"), "{plan}");
    assert!(files(&tmp).is_empty(), "a dry run created files");
}

#[test]
fn sequence_files_shown_load() {
    let mut checked = 0;
    for page in pages() {
        let (blocks, _) = split(&read(&page));
        for block in blocks.iter().filter(|b| b.info == "yaml") {
            let text = block.lines.join("\n") + "\n";
            // Whole files only: fragments (a timeline, a material, a block that says it is an
            // excerpt) cannot load alone.
            let excerpt = block
                .lines
                .first()
                .is_some_and(|l| l.starts_with("# excerpt"));
            let whole = !excerpt
                && text.contains("objects:")
                && (text.contains("camera:") || text.contains("timeline:"));
            if !whole {
                continue;
            }
            checked += 1;
            let tmp = scratch("readme-yaml");
            std::fs::write(tmp.join("shown.yaml"), &text).unwrap();
            let out = run_in(&tmp, &["check", "shown.yaml"]);
            assert!(
                out.status.success(),
                "{}: a sequence file shown does not load: {}",
                name(&page),
                stderr(&out)
            );
        }
    }
    assert!(checked >= 2, "only {checked} sequence files found");
}

#[test]
fn no_page_cites_issue_numbers() {
    let mut found = Vec::new();
    for page in pages() {
        for (i, line) in read(&page).lines().enumerate() {
            let lower = line.to_lowercase();
            let cites = lower.match_indices("issue").any(|(at, _)| {
                let rest = lower[at + 5..].trim_start_matches([' ', '#', 's']);
                rest.starts_with(|c: char| c.is_ascii_digit())
            }) || line.match_indices('#').any(|(at, _)| {
                let before = line[..at].chars().last();
                let after = line[at + 1..].chars().next();
                !before.is_some_and(|c| c.is_alphanumeric() || c == '#' || c == '&')
                    && after.is_some_and(|c| c.is_ascii_digit())
            });
            if cites {
                found.push(format!("{}:{}: {line}", name(&page), i + 1));
            }
        }
    }
    assert!(found.is_empty(), "issue numbers:\n{}", found.join("\n"));
}

/// The examples of `rayreel --help` (the same list ends `render --help`): its indented
/// `rayreel …` lines after `Examples:`.
fn help_examples() -> Vec<Vec<String>> {
    let out = bin().arg("--help").output().unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<String> = text
        .lines()
        .skip_while(|l| !l.starts_with("Examples:"))
        .map(|l| l.trim().to_string())
        .filter(|l| l.starts_with("rayreel "))
        .collect();
    commands(&lines, false)
}

/// `args` made small enough to run in a test: renders become dry runs (the job is still built
/// and checked whole), the tools get their smallest settings, and `/tmp/…` lands in `dir`.
fn small_run(args: &[String], dir: &Path) -> Vec<String> {
    let mut args: Vec<String> = args
        .iter()
        .map(|a| match a.strip_prefix("/tmp/") {
            Some(rest) => dir.join(rest).to_string_lossy().into_owned(),
            None => a.clone(),
        })
        .collect();
    let has = |args: &[String], flag: &str| args.iter().any(|a| a == flag);
    let extra: &[&str] = match args[0].as_str() {
        "render" if !has(&args, "--dry-run") => &["--dry-run"],
        "preview" if !has(&args, "--tiles") => &["--tiles", "1"],
        "measure" if !has(&args, "--size") => &["--size", "16x9", "--runs", "1"],
        "bench" if !has(&args, "--only") => &["--quick", "--runs", "1", "--only", "kernels"],
        "bench" => &["--quick", "--runs", "1"],
        _ => &[],
    };
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

#[test]
fn every_example_in_help_and_the_readme_runs() {
    let tmp = scratch("examples-run");
    std::os::unix::fs::symlink(repo().join("sequences"), tmp.join("sequences")).unwrap();
    // The README's first sequence file, saved as it says.
    let (blocks, _) = split(&read(&repo().join("README.md")));
    let first = blocks
        .iter()
        .find(|b| b.info == "yaml" && b.lines.iter().any(|l| l.contains("frames/first")))
        .expect("the README's first sequence file");
    std::fs::write(tmp.join("first.yaml"), first.lines.join("\n") + "\n").unwrap();
    let mut shown: Vec<(String, Vec<String>)> = help_examples()
        .into_iter()
        .map(|a| ("rayreel --help".to_string(), a))
        .collect();
    shown.extend(
        shown_commands()
            .into_iter()
            .filter(|(p, _)| p == "README.md"),
    );
    assert!(shown.len() >= 30, "only {} examples found", shown.len());
    let mut failed = Vec::new();
    for (page, args) in &shown {
        let run = small_run(args, &tmp);
        let out = run_in(&tmp, &run.iter().map(String::as_str).collect::<Vec<_>>());
        // `status` exits 1 when frames are missing, which they are here.
        let fine = out.status.success() || (args[0] == "status" && out.status.code() == Some(1));
        if !fine {
            failed.push(format!(
                "{page}: rayreel {}: {}",
                run.join(" "),
                stderr(&out).trim()
            ));
        }
    }
    assert!(
        failed.is_empty(),
        "examples that fail:\n{}",
        failed.join("\n")
    );
}
