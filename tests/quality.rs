//! Speed versus accuracy: stratified sampling converges faster than random on edges, adaptive
//! sampling matches uniform 16 spp with fewer than half the samples, presets are ordered, and
//! `measure` writes parsable results.

mod common;
use clap::Parser;
use common::*;
use rayreel::cli::{Cli, Command, job::Job};
use rayreel::sequence::{self, Quality, Sequence};
use rayreel::tools::measure::{self, compare};
use rayreel::tracer::{Adaptive, Precision, Sampler, Settings};

/// The orbit sequence as `rayreel render sequences/orbit.yaml ARGS` sees it.
fn job(args: &[&str]) -> Sequence {
    let file = repo().join("sequences/orbit.yaml");
    let file = file.to_str().unwrap();
    let line: Vec<&str> = ["rayreel", "render", file]
        .into_iter()
        .chain(args.iter().copied())
        .collect();
    match Cli::try_parse_from(line).unwrap().command {
        Command::Render(r) => Job::new(&r.job).unwrap().seq,
        _ => unreachable!(),
    }
}

/// Frame 0 of orbit.yaml without its shutter: these tests measure how samples resolve the
/// edges of one instant, which motion blur would smear.
fn orbit((w, h): (u64, u64)) -> Sequence {
    // One uniform sample to start from: each test sets the sampling it measures.
    let mut seq = job(&["--size", &format!("{w}x{h}"), "--samples", "1"]);
    seq.settings.shutter = None;
    seq
}

fn floats(seq: &rayreel::sequence::Sequence, s: &Settings) -> (Vec<f32>, u64) {
    let f = measure::render(seq, 0, s).unwrap();
    (f.rgb, f.samples)
}

fn rmse(a: &[f32], b: &[f32], pixels: &[usize]) -> f64 {
    let sum: f64 = pixels
        .iter()
        .flat_map(|&p| (0..3).map(move |c| 3 * p + c))
        .map(|i| {
            let d = f64::from(a[i].clamp(0.0, 1.0) - b[i].clamp(0.0, 1.0));
            d * d
        })
        .sum();
    (sum / (3 * pixels.len()) as f64).sqrt()
}

/// Least-squares slope of log(y) against log(x).
fn slope(xs: &[f64], ys: &[f64]) -> f64 {
    let (lx, ly): (Vec<f64>, Vec<f64>) = (
        xs.iter().map(|x| x.ln()).collect(),
        ys.iter().map(|y| y.ln()).collect(),
    );
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let cov: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let var: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    cov / var
}

#[test]
fn jittered_sampling_converges_faster_than_random_on_edges() {
    let seq = orbit((128, 72));
    let base = seq.settings;
    let reference = Settings {
        samples: 1024,
        ..base
    };
    let (truth, _) = floats(&seq, &reference);
    let (one, _) = floats(&seq, &Settings { samples: 1, ..base });
    // Edge pixels: where one centred sample is visibly wrong.
    let edges: Vec<usize> = (0..truth.len() / 3)
        .filter(|&p| (0..3).any(|c| (one[3 * p + c] - truth[3 * p + c]).abs() > 0.05))
        .collect();
    assert!(edges.len() > 100, "too few edge pixels ({})", edges.len());
    let counts = [1.0, 4.0, 16.0, 64.0];
    let mut slopes = Vec::new();
    for sampler in [Sampler::Stratified, Sampler::Random] {
        let errors: Vec<f64> = counts
            .iter()
            .map(|&n| {
                rmse(
                    &floats(
                        &seq,
                        &Settings {
                            samples: n as u32,
                            sampler,
                            ..base
                        },
                    )
                    .0,
                    &truth,
                    &edges,
                )
            })
            .collect();
        eprintln!("{sampler:?}: edge RMSE {errors:?}");
        assert!(
            errors.windows(2).all(|w| w[1] < w[0]),
            "{sampler:?} error must fall: {errors:?}"
        );
        slopes.push(slope(&counts, &errors));
    }
    eprintln!(
        "slopes: stratified {:.3}, random {:.3}",
        slopes[0], slopes[1]
    );
    assert!(slopes[0] <= -0.7, "stratified slope {}", slopes[0]);
    assert!(
        (-0.65..=-0.35).contains(&slopes[1]),
        "random slope {}",
        slopes[1]
    );
}

#[test]
fn adaptive_matches_uniform_16_with_less_than_half_the_samples() {
    let seq = orbit((320, 180));
    let base = seq.settings;
    let all: Vec<usize> = (0..(320 * 180) as usize).collect();
    let (truth, _) = floats(
        &seq,
        &Settings {
            samples: 1024,
            ..base
        },
    );
    let (uniform, uniform_samples) = floats(
        &seq,
        &Settings {
            samples: 16,
            ..base
        },
    );
    let adaptive = Settings {
        samples: 4,
        adaptive: Some(Adaptive {
            threshold: sequence::DEFAULT_THRESHOLD as f32,
            max_samples: sequence::DEFAULT_MAX_SAMPLES as u32,
        }),
        ..base
    };
    let (adapt, adaptive_samples) = floats(&seq, &adaptive);
    let (eu, ea) = (rmse(&uniform, &truth, &all), rmse(&adapt, &truth, &all));
    eprintln!(
        "uniform 16: rmse {eu:.5}, {uniform_samples} samples; adaptive: rmse {ea:.5}, {adaptive_samples} samples"
    );
    assert!(ea <= eu, "adaptive error {ea} exceeds uniform 16's {eu}");
    assert!(
        adaptive_samples * 2 < uniform_samples,
        "{adaptive_samples} samples is not under half of {uniform_samples}"
    );
}

#[test]
fn presets_trade_cost_for_accuracy_in_order() {
    let seq = orbit((160, 90));
    let truth = measure::render(&seq, 0, &measure::reference_settings(&seq.settings, false))
        .unwrap()
        .to_rgb8();
    let mut last: Option<(u64, f64)> = None;
    for q in [Quality::Draft, Quality::Preview, Quality::Final] {
        let name = format!("{q:?}").to_lowercase();
        let mut seq = job(&["--size", "160x90", "--quality", &name]);
        if q == Quality::Draft {
            // Draft halves the resolution unless a size is given; measure it at half size.
            seq.settings.width = 80;
            seq.settings.height = 45;
        }
        let frame = measure::render(&seq, 0, &seq.settings).unwrap();
        let cost = frame.samples * u64::from(seq.settings.max_depth);
        let image = if q == Quality::Draft {
            upscale(&frame.to_rgb8(), 80, 160, 90)
        } else {
            frame.to_rgb8()
        };
        let error = compare(&image, &truth).rmse;
        eprintln!("{q:?}: cost {cost}, rmse {error:.3}");
        if let Some((c, e)) = last {
            assert!(
                cost > c && error < e,
                "{q:?} must cost more and err less than the preset before"
            );
        }
        last = Some((cost, error));
    }
}

fn upscale(rgb: &[u8], hw: u32, w: u32, h: u32) -> Vec<u8> {
    let mut out = Vec::new();
    for r in 0..h {
        for c in 0..w {
            let i = 3 * ((r / 2) * hw + c / 2) as usize;
            out.extend_from_slice(&rgb[i..i + 3]);
        }
    }
    out
}

#[test]
fn the_reference_is_f64_whatever_the_file_says() {
    let f32_file = job(&["--precision", "f32"]).settings;
    assert_eq!(f32_file.precision, Precision::F32);
    for trees in [false, true] {
        let r = measure::reference_settings(&f32_file, trees);
        assert_eq!(r.precision, Precision::F64);
    }
}

#[test]
fn draft_halves_the_size_unless_a_size_is_given() {
    // orbit.yaml sets `max_depth: 3` itself, which no preset replaces.
    let s = job(&["--quality", "draft"]).settings;
    assert_eq!(
        (s.width, s.height, s.samples, s.max_depth),
        (640, 360, 1, 3)
    );
    let s = job(&["--quality", "draft", "--size", "100x50", "--max-depth", "4"]).settings;
    assert_eq!((s.width, s.height, s.max_depth), (100, 50, 4));
    let s = job(&["--quality", "final", "--samples", "9"]).settings;
    assert_eq!((s.samples, s.adaptive, s.max_depth), (9, None, 3));
}

#[test]
fn measure_writes_csv_json_and_a_plot() {
    let tmp = scratch("measure");
    let out = run_in(
        &tmp,
        &[
            "measure",
            repo().join("sequences/orbit.yaml").to_str().unwrap(),
            "--size",
            "32x18",
            "--runs",
            "1",
            "--out",
            "m",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        table.contains("256 spp") && table.contains("final"),
        "{table}"
    );
    let csv = std::fs::read_to_string(tmp.join("m/measure.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    let columns = lines[0].split(',').count();
    assert_eq!(columns, 22);
    assert!(
        lines[0].ends_with(",precision,encoding") && lines[1].ends_with(",f64,srgb"),
        "{csv}"
    );
    // orbit.yaml is film (its camera moves while the shutter is open): the rows with the
    // film filter off come too.
    let film = job(&["--size", "32x18"]);
    assert_eq!(lines.len(), 1 + measure::ladder(&film).len() + 2);
    assert!(csv.contains("\ndenoise,default (denoise off),"), "{csv}");
    for line in &lines[1..] {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), columns, "{line}");
        // The columns against f64 are empty outside the precision rows.
        let precision = cells[0] == "precision";
        assert!(
            cells[2..columns - 2]
                .iter()
                .all(|c| c.parse::<f64>().is_ok() || (!precision && c.is_empty())),
            "{line}"
        );
    }
    let json: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(tmp.join("m/measure.json")).unwrap())
            .unwrap();
    assert_eq!(json["rows"].as_sequence().unwrap().len(), lines.len() - 1);
    assert!(json["reference"]["samples_per_pixel"].as_u64() == Some(1024));
    let svg = std::fs::read_to_string(tmp.join("m/measure.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
    assert!(svg.contains(">final</text>") && svg.contains("<polyline"));
    assert!(svg.contains(">f64</text>") && svg.contains(">f32</text>"));
}

/// `measure` on a file that says f32: the ladder in f32, the reference and the first precision
/// row in f64, the second in f32; every column of the precision rows parses, in the table,
/// the CSV and the JSON (counted and parsed, not timed).
#[test]
fn measure_lists_f64_and_f32_rows_for_an_f32_file() {
    let tmp = scratch("measure_f32");
    let yaml = std::fs::read_to_string(repo().join("sequences/orbit.yaml")).unwrap();
    let yaml = yaml.replacen("render:\n", "render:\n  precision: f32\n", 1);
    std::fs::write(tmp.join("f32.yaml"), yaml).unwrap();
    let out = run_in(
        &tmp,
        &[
            "measure", "f32.yaml", "--size", "16x9", "--runs", "2", "--out", "m",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("the ladder in f32"), "{table}");
    let block = table.split("against the f64 image\n").nth(1).expect(&table);
    let rows: Vec<Vec<&str>> = block
        .lines()
        .filter(|l| l.starts_with("precision "))
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(rows.len(), 2, "{table}");
    for (row, name) in rows.iter().zip(["f64", "f32"]) {
        assert_eq!(row[..2], ["precision", name], "{table}");
        assert!(row[2].trim_end_matches('x').parse::<f64>().unwrap() > 0.0);
        for cell in &row[3..] {
            assert!(cell.trim_end_matches('%').parse::<f64>().is_ok(), "{table}");
        }
    }
    // The f64 row against itself: the same image.
    assert_eq!(
        rows[0][2..],
        ["1.00x", "0.000", "inf", "0", "0.000%", "0.000%"]
    );
    assert!(block.contains("target: f32 at most 0.05% of pixels off by more than 2/255: "));
    let json: serde_yaml::Value =
        serde_yaml::from_str(&std::fs::read_to_string(tmp.join("m/measure.json")).unwrap())
            .unwrap();
    assert_eq!(json["reference"]["precision"].as_str(), Some("f64"));
    let rows = json["rows"].as_sequence().unwrap();
    assert!(rows[0]["precision"].as_str() == Some("f32") && rows[0]["rmse_vs_f64"].is_null());
    let precision: Vec<_> = rows.iter().filter(|r| r["group"] == "precision").collect();
    assert_eq!(precision.len(), 2);
    for (r, name) in precision.iter().zip(["f64", "f32"]) {
        assert_eq!(r["precision"].as_str(), Some(name));
        for key in [
            "speedup_vs_f64",
            "rmse_vs_f64",
            "psnr_db_vs_f64",
            "share_off_2_vs_f64",
        ] {
            assert!(r[key].as_f64().is_some(), "{key} of {r:?}");
        }
    }
    assert_eq!(precision[0]["share_off_2_vs_f64"].as_f64(), Some(0.0));
}

#[test]
fn share_off_by_more_than_two_levels() {
    let a = [10u8, 10, 10, 10, 10, 10, 10, 10, 10, 10, 10, 10];
    let b = [11u8, 10, 10, 12, 10, 10, 10, 13, 10, 10, 10, 10];
    let e = compare(&a, &b);
    assert_eq!((e.max, e.off, e.off2), (3, 0.5, 0.25));
}

/// With area lights, `measure` adds the light-sample trade (1, 4, 16 and 64 points per eye
/// sample at the file's pixel sampling) next to the pixel-sample ladder; more light samples
/// come closer to the reference. Lights with keys take the rows' counts too (they are posed
/// from their own copy, which the rows once left at the file's count: four equal rows).
#[test]
fn measure_shows_light_samples_beside_pixel_samples() {
    let tmp = scratch("measure_lights");
    let still = std::fs::read_to_string(repo().join("sequences/soft-shadows.yaml")).unwrap();
    let keyed = still
        .replace(
            "ambient: [1, 1, 1], diffuse: [0.85, 0.82, 0.75], specular: [1, 1, 1], samples: 16 }",
            "ambient: [1, 1, 1], diffuse: [0.85, 0.82, 0.75], specular: [1, 1, 1], samples: 16 }\n    \
             keys: [ { time: 0, center: [-0.2, 3.2, 0.6] }, { time: 9, center: [0.2, 3.2, 0.6] } ]",
        )
        .replace(
            "specular: [0.5, 0.5, 0.5], samples: 16 }",
            "specular: [0.5, 0.5, 0.5], samples: 16 }\n    \
             keys: [ { time: 0, corner: [3, 0.3, -1] }, { time: 9, corner: [3, 0.5, -1] } ]",
        );
    assert_eq!(keyed.matches("keys:").count(), 2, "both area lights keyed");
    for (name, yaml) in [("still", &still), ("keyed", &keyed)] {
        let file = tmp.join(format!("{name}.yaml"));
        std::fs::write(&file, yaml).unwrap();
        let out = run_in(
            &tmp,
            &[
                "measure",
                file.to_str().unwrap(),
                "--size",
                "48x27",
                "--runs",
                "1",
                "--out",
                name,
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let csv = std::fs::read_to_string(tmp.join(name).join("measure.csv")).unwrap();
        let rmse: Vec<f64> = csv
            .lines()
            .filter(|l| l.starts_with("lights,"))
            .map(|l| l.split(',').nth(8).unwrap().parse().unwrap())
            .collect();
        assert_eq!(rmse.len(), 4, "{name}: {csv}");
        assert!(rmse[3] < rmse[0], "{name}: {csv}");
        let svg = std::fs::read_to_string(tmp.join(name).join("measure.svg")).unwrap();
        assert!(svg.contains("#ff7f0e"), "the lights line");
    }
}

/// `render --dry-run`'s effective settings line for `yaml` with `args`.
fn dry_settings(tmp: &std::path::Path, yaml: &str, args: &[&str]) -> String {
    let file = tmp.join("s.yaml");
    std::fs::write(&file, yaml).unwrap();
    let mut line = vec![
        "render",
        file.to_str().unwrap(),
        "--dry-run",
        "-o",
        "f_####.png",
    ];
    line.extend_from_slice(args);
    let out = run_in(tmp, &line);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let settings = text.lines().find(|l| l.starts_with("settings: "));
    settings
        .unwrap_or_else(|| panic!("no settings line in {text}"))
        .to_string()
}

#[test]
fn presets_never_replace_what_the_file_sets() {
    let tmp = scratch("preset_word");
    let scene = "camera: { position: [0, 1, 5], look_at: [0, 0, 0] }\n\
        materials: { m: { diffuse: [0.8, 0.2, 0.2] } }\n\
        objects: [ { sphere: { center: [0, 0, 0], radius: 1, material: m } } ]\n";
    // The file's depth and sampling survive `--quality`; what it leaves unset, the preset fills.
    let own = format!("render: {{ width: 64, height: 36, max_depth: 6, samples: 16 }}\n{scene}");
    // As with the file's own preset, its `samples` is the first pass of final's adaptivity.
    let s = dry_settings(&tmp, &own, &["--quality", "final"]);
    assert!(s.contains("max_depth 6, 16 to 64 samples (adaptive"), "{s}");
    let s = dry_settings(&tmp, &own, &["--quality", "draft"]);
    assert!(
        s.starts_with("settings: 32x18, max_depth 6, 16 samples"),
        "{s}"
    );
    let unset = format!("render: {{ width: 64, height: 36 }}\n{scene}");
    let s = dry_settings(&tmp, &unset, &["--quality", "final"]);
    assert!(s.contains("max_depth 5, 4 to 64 samples (adaptive"), "{s}");
    // Flags that set a value still win over the file.
    let s = dry_settings(&tmp, &own, &["--quality", "final", "--max-depth", "2"]);
    assert!(s.contains("max_depth 2"), "{s}");
    // Draft keeps glass legible: in, out and what is behind it.
    let glass = unset.replace(
        "diffuse: [0.8, 0.2, 0.2]",
        "diffuse: [0, 0, 0], transmission: [0.9, 0.9, 0.9], ior: 1.5",
    );
    let s = dry_settings(&tmp, &glass, &["--quality", "draft"]);
    assert!(s.contains("max_depth 3, 1 sample"), "{s}");
    let s = dry_settings(&tmp, &unset, &["--quality", "draft"]);
    assert!(s.contains("max_depth 2, 1 sample"), "{s}");
    // The same rule for the file's own preset.
    let file_glass = glass.replace("height: 36 }", "height: 36, quality: draft }");
    let s = dry_settings(&tmp, &file_glass, &[]);
    assert!(s.contains("max_depth 3"), "{s}");
}

#[test]
fn check_warns_about_grain_where_the_film_blurs_with_few_samples() {
    let check = |file: &std::path::Path| {
        let out = run_in(&repo(), &["check", file.to_str().unwrap()]);
        assert!(out.status.success(), "{}", stderr(&out));
        stderr(&out)
    };
    let tmp = scratch("grain");
    let text = std::fs::read_to_string(repo().join("sequences/flyby.yaml")).unwrap();
    // The sampling that was the default before film got its own: 2 to 8 samples.
    let grainy = text.replacen(
        "render:\n",
        "render:\n  samples: 2\n  adaptive: { max_samples: 8 }\n",
        1,
    );
    assert_ne!(grainy, text);
    std::fs::write(tmp.join("grainy.yaml"), grainy).unwrap();
    let flyby = check(&tmp.join("grainy.yaml"));
    assert!(
        flyby.contains("frames 0 to 144 may look grainy")
            && flyby.contains("the shutter smears up to")
            && flyby.contains("the lens blurs up to")
            && flyby.contains("--quality final"),
        "{flyby}"
    );
    let talk = check(&repo().join("sequences/talk.yaml"));
    assert!(!talk.contains("grainy"), "{talk}");
    // Film's default sampling reaches 64 samples where the grain is: no warning.
    let out = check(&repo().join("sequences/flyby.yaml"));
    assert!(!out.contains("grainy"), "{out}");
}

/// Frame 60 of flyby.yaml (a 180° shutter and an open lens) at `w`×`h`.
fn flyby((w, h): (u64, u64)) -> Sequence {
    let file = repo().join("sequences/flyby.yaml");
    let size = format!("{w}x{h}");
    let line = ["rayreel", "render", file.to_str().unwrap(), "--size", &size];
    match Cli::try_parse_from(line).unwrap().command {
        Command::Render(r) => Job::new(&r.job).unwrap().seq,
        _ => unreachable!(),
    }
}

#[test]
fn film_samples_converge_faster_than_random_and_rounds_spend_where_the_grain_is() {
    let seq = flyby((160, 90));
    let base = seq.settings;
    let all: Vec<usize> = (0..(160 * 90) as usize).collect();
    let render = |s: Settings| measure::render(&seq, 60, &s).unwrap();
    let uniform = |n: u32, sampler| Settings {
        samples: n,
        adaptive: None,
        sampler,
        ..base
    };
    let truth = render(uniform(1024, Sampler::Stratified)).rgb;
    let error = |n, sampler| rmse(&render(uniform(n, sampler)).rgb, &truth, &all);
    // Sobol' points: at least the Monte Carlo rate, and well ahead of independent samples.
    let counts = [4.0, 16.0, 64.0];
    let sobol: Vec<f64> = [4, 16, 64].map(|n| error(n, Sampler::Stratified)).to_vec();
    let random: Vec<f64> = [4, 16, 64].map(|n| error(n, Sampler::Random)).to_vec();
    let (rate, random_rate) = (slope(&counts, &sobol), slope(&counts, &random));
    eprintln!("sobol {sobol:?} slope {rate:.2}; random {random:?} slope {random_rate:.2}");
    assert!(rate < -0.5, "Sobol' error slope {rate}");
    assert!(
        (0..3).all(|i| sobol[i] < random[i]),
        "{sobol:?} vs {random:?}"
    );
    // The file sets no sampling: film's default, in rounds.
    assert_eq!(
        (base.samples, base.adaptive.map(|a| a.max_samples)),
        (sequence::LENS_SAMPLES, Some(sequence::FILM_SAMPLING_MAX))
    );
    // A shutter alone (the orbit) starts rounds from 2 samples, a lens from 4.
    let shutter = job(&[]).settings;
    assert_eq!(
        (shutter.samples, shutter.adaptive.map(|a| a.max_samples)),
        (sequence::SHUTTER_SAMPLES, Some(sequence::FILM_SAMPLING_MAX))
    );
    let rounds = render(base);
    let pixels = all.len() as u64;
    let spent = rounds.samples as f64 / pixels as f64;
    let e = rmse(&rounds.rgb, &truth, &all);
    eprintln!("rounds: {spent:.2} samples a pixel, rmse {e:.5}");
    // Flat pixels stop at 4, grainy ones go on: far under 64 everywhere, well over 4, and
    // as clean as 16 uniform samples at fewer samples.
    assert!(spent > 5.0 && spent < 16.0, "{spent} samples a pixel");
    assert!(e < sobol[1], "rounds {e} vs 16 uniform {}", sobol[1]);
    // The same bytes whatever the thread count (and so the order of work).
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let again = one.install(|| render(base));
    assert_eq!(again.rgb, rounds.rgb);
}
