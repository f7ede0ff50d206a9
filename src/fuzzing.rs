//! The properties the fuzz targets (`fuzz/`, CONTRIBUTING.md#fuzzing) check, each a function
//! that panics when its property fails. They live here, not in the targets, so that
//! `tests/fuzz_corpus.rs` replays a kept input against exactly the check that found it, on
//! stable Rust and without libFuzzer; and so they may reach the crate-private parts they test.
//! Nothing in the pipeline calls them.

use crate::claim;
use crate::output::stream::{Source, ffmpeg_command};
use crate::output::{Compression, Existing, Expected, ExrPrecision, FileFormat, exr, png};
use crate::pattern::Pattern;
use crate::sequence;
use crate::settings::Precision;
use crate::shutter::Exposure;
use crate::tracer::{self, World};
use std::path::Path;

/// The largest frame a fuzzed sequence is rendered at, its samples and bounces: enough for
/// every stage to run, small enough for thousands of inputs a second.
const SIDE: u32 = 8;
const SAMPLES: u32 = 2;
const DEPTH: u32 = 6;

/// A sequence that loads renders its first frame, shrunk to at most 8×8 with few samples, in
/// f64 and in f32, with every pixel finite and no non-finite sample counted.
pub fn render_tiny(text: &str) {
    let Ok(seq) = sequence::parse(Path::new("fuzz.yaml"), text) else {
        return;
    };
    let first = seq.timeline.first_frame();
    let Ok(exposure) = Exposure::of_frame(&seq.timeline, seq.settings.shutter, first) else {
        return;
    };
    let world = World::new(seq.scene.clone());
    for precision in [Precision::F64, Precision::F32] {
        let settings = crate::settings::Settings {
            width: seq.settings.width.min(SIDE),
            height: seq.settings.height.min(SIDE),
            samples: seq.settings.samples.min(SAMPLES),
            adaptive: None,
            max_depth: seq.settings.max_depth.min(DEPTH),
            precision,
            ..seq.settings
        };
        let frame = tracer::render(&world, &exposure, &settings, first);
        assert_eq!(frame.non_finite, 0, "{precision:?}: non-finite samples");
        let bad = frame.rgb.iter().position(|v| !v.is_finite() || *v < 0.0);
        assert!(
            bad.is_none(),
            "{precision:?}: pixel value {bad:?} not finite"
        );
    }
}

/// Attacker-written bytes at a frame's name, read as each format's frame check reads them,
/// and at a claim's name, read as a waiting or taking-over process reads them: an answer,
/// never a panic.
pub fn frame_and_claim_files(bytes: &[u8]) {
    let formats = [
        FileFormat::Png {
            sixteen_bit: bytes.len().is_multiple_of(2),
            compression: Compression::Fast,
        },
        FileFormat::Exr {
            precision: ExrPrecision::Half,
        },
    ];
    for format in formats {
        let expected = Expected {
            width: 4,
            height: 3,
            format,
            alpha: bytes.len().is_multiple_of(3),
        };
        // Any answer will do. (A file whose fingerprint text is empty is ours and stale: it
        // carries our key, and rayreel never writes an empty one, so it is re-rendered.)
        let _: Existing = match format {
            FileFormat::Png { .. } => png::inspect(bytes, &expected),
            FileFormat::Exr { .. } => exr::inspect(bytes, &expected),
        };
        for key in [crate::output::fingerprint::KEY, crate::output::record::KEY] {
            let _ = png::header_text(bytes, key);
            let _ = exr::header_text(bytes, key);
        }
    }
    claim::judge_owner_line(&String::from_utf8_lossy(bytes));
}

/// Any bytes as a PLY file: a refusal, or a mesh whose arrays agree (`mesh_agrees`).
pub fn ply_file(bytes: &[u8]) {
    mesh_file(bytes, true)
}

/// Any bytes as an OBJ file: a refusal, or a mesh whose arrays agree (`mesh_agrees`).
pub fn obj_file(bytes: &[u8]) {
    mesh_file(bytes, false)
}

/// A refusal, or a mesh whose arrays agree (one normal, and texture coordinates if any, per
/// position; every index in range; the tracer indexes them without checks), whose normals are
/// unit length, and whose used positions are finite-or-skipped, within [−1, 1] when brought
/// to other units. Never a panic.
fn mesh_file(bytes: &[u8], ply: bool) {
    {
        let Ok(loaded) = sequence::mesh::read_bytes(bytes, ply) else {
            return;
        };
        let m = &loaded.mesh;
        let n = m.positions.len();
        assert_eq!(m.normals.len(), n);
        assert!(m.uvs.as_ref().is_none_or(|u| u.len() == n));
        assert!(!m.triangles.is_empty());
        for t in &m.triangles {
            assert!(t.iter().all(|&i| (i as usize) < n), "{t:?} of {n}");
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!(a.is_finite() && b.is_finite() && c.is_finite());
            if loaded.exponent != 0 {
                assert!(a.abs().max(b.abs()).max(c.abs()).max_element() < 1.0);
            }
        }
        for v in &m.normals {
            assert!((v.length() - 1.0).abs() < 1e-9, "normal {v}");
        }
    }
}

/// Any bytes as a PNG and an EXR texture (where the header's size is small: a large one is a
/// question of memory, which the budget answers, not of decoding): a refusal or a pyramid down
/// to 1×1 of finite, non-negative texels.
pub fn texture_file(bytes: &[u8]) {
    use image::ImageDecoder;
    const MOST: u64 = 1 << 20;
    let png = image::codecs::png::PngDecoder::new(std::io::Cursor::new(bytes))
        .map(|d| d.dimensions())
        .is_ok_and(|(w, h)| u64::from(w) * u64::from(h) <= MOST);
    let exr = ::exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .is_ok_and(|m| {
            m.headers
                .iter()
                .all(|h| (h.layer_size.width() as u64) * (h.layer_size.height() as u64) <= MOST)
        });
    for (is_png, small) in [(true, png), (false, exr)] {
        if !small {
            continue;
        }
        for linear in [false, true] {
            let Ok(levels) = sequence::decode_texture(bytes, is_png, linear, "fuzz") else {
                continue;
            };
            let last = levels.last().expect("a level");
            assert_eq!((last.width, last.height), (1, 1));
            for l in &levels {
                assert_eq!(l.texels.len(), (l.width * l.height) as usize);
                assert!(
                    l.texels
                        .iter()
                        .flatten()
                        .all(|v| v.is_finite() && *v >= 0.0)
                );
            }
        }
    }
}

/// An output pattern, as `--print-ffmpeg` prints it in a command: lexed back by a POSIX shell
/// (with bash's `$'…'`, which the quoting uses for control characters), the input and output
/// words are exactly the image2 pattern and the file name given to the command.
pub fn ffmpeg_words(text: &str) {
    // A file name never holds NUL, and a shell word cannot.
    let Some((pattern, out)) = text.split_once('\n') else {
        return;
    };
    if text.contains('\0') {
        return;
    }
    let Ok(pattern) = Pattern::new(pattern, 99) else {
        return;
    };
    let image2 = pattern.ffmpeg();
    for alpha in [false, true] {
        let source = Source::Files {
            pattern: &image2,
            first: 1,
        };
        let line = ffmpeg_command(source, alpha, (3, 5), "24000/1001", out);
        let words = shell_words(&line).unwrap_or_else(|e| panic!("{line:?}: {e}"));
        let input = words.iter().position(|w| w == "-i").map(|i| &words[i + 1]);
        assert_eq!(input, Some(&image2), "{line:?}");
        let expected_out = match alpha {
            false => out.to_string(),
            true => format!("{}.mov", out.strip_suffix(".mp4").unwrap_or(out)),
        };
        assert_eq!(words.last(), Some(&expected_out), "{line:?}");
    }
}

/// The words a POSIX shell makes of `line` (blanks separate words; `'…'` is literal, `"…"` and
/// a backslash as POSIX says, with no expansion checked: the quoting never leaves a `$` or a
/// backquote unquoted), plus bash's `$'…'` with the escapes `shell_quote` writes.
pub fn shell_words(line: &str) -> Result<Vec<String>, String> {
    let mut words = Vec::new();
    let mut chars = line.chars().peekable();
    let mut word: Option<String> = None;
    while let Some(c) = chars.next() {
        match c {
            ' ' | '\t' => words.extend(word.take()),
            '\n' => return Err("an unquoted newline ends the command".into()),
            '\'' => {
                let w = word.get_or_insert_with(String::new);
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(c) => w.push(c),
                        None => return Err("unterminated '".into()),
                    }
                }
            }
            '$' if chars.peek() == Some(&'\'') => {
                chars.next();
                dollar_quoted(&mut chars, word.get_or_insert_with(String::new))?;
            }
            '\\' => match chars.next() {
                Some('\n') => {}
                Some(c) => word.get_or_insert_with(String::new).push(c),
                None => return Err("a trailing backslash".into()),
            },
            c if "\"`$;&|<>()*?[#~{}!".contains(c) => {
                return Err(format!("an unquoted {c:?} the shell would act on"));
            }
            c => word.get_or_insert_with(String::new).push(c),
        }
    }
    words.extend(word);
    Ok(words)
}

/// The rest of a `$'…'` word, its escapes decoded as bash decodes them.
fn dollar_quoted(
    chars: &mut std::iter::Peekable<std::str::Chars>,
    w: &mut String,
) -> Result<(), String> {
    loop {
        let c = chars.next().ok_or("unterminated $'")?;
        if c == '\'' {
            return Ok(());
        }
        if c != '\\' {
            w.push(c);
            continue;
        }
        let e = chars.next().ok_or("unterminated $'")?;
        let simple = [
            ('\\', '\\'),
            ('\'', '\''),
            ('n', '\n'),
            ('t', '\t'),
            ('r', '\r'),
        ];
        if let Some(&(_, v)) = simple.iter().find(|(k, _)| *k == e) {
            w.push(v);
            continue;
        }
        // bash reads at most 2 hex digits after \x and 4 after \u.
        let most = match e {
            'x' => 2,
            'u' => 4,
            other => return Err(format!("an escape \\{other} shell_quote never writes")),
        };
        let mut hex = String::new();
        while hex.len() < most && chars.peek().is_some_and(char::is_ascii_hexdigit) {
            hex.extend(chars.next());
        }
        let v = u32::from_str_radix(&hex, 16).map_err(|_| format!("\\{e} without digits"))?;
        w.push(char::from_u32(v).ok_or("an escape that is no character")?);
    }
}
