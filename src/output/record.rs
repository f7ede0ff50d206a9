//! A frame's settings record: what produced it, as `name=value` lines stored beside its
//! fingerprint (PNG `tEXt` / EXR attribute `rayreel:settings`), so a rerun can say which
//! setting differs from the frame it finds, and whether only the quality does.
//!
//! Settings a person reads (size, samples, depth…) are written as values; the scene's parts
//! (background, objects, lights, meshes, each named material) and the frame's camera as a
//! 64-bit hash each, which says *what* changed without spelling out a whole scene.

use super::fingerprint::{self, Canon, Hasher};
use super::format::{ExrPrecision, FileFormat};
use crate::scene::{Material, Scene};
use crate::sequence::Sequence;
use crate::settings::{Aovs, Precision, Sampler, Settings};
use crate::shutter::FrameView;
use crate::transfer::Encoding;

/// Key of the PNG text chunk and the EXR attribute that hold the record.
pub(crate) const KEY: &str = "rayreel:settings";

/// Fields whose difference changes only how well a frame is sampled, not what it shows.
const QUALITY: [&str; 7] = [
    "samples",
    "max_samples",
    "threshold",
    "max_depth",
    "sampler",
    "precision",
    "denoise",
];

/// Named materials beyond this many are recorded as one hash (`materials`), so the record of
/// a scene with thousands of materials stays small.
const MAX_NAMED: usize = 32;

/// The lines every frame of a run shares (all but `camera`).
pub(crate) fn of_run(seq: &Sequence, format: &FileFormat, fps: Option<(i32, u32)>) -> String {
    let mut lines = settings(&seq.settings, format);
    if let Some((num, den)) = fps {
        lines.push(("fps".into(), format!("{num}/{den}")));
    }
    lines.extend(scene(&seq.scene, &seq.material_names));
    lines.iter().map(|(k, v)| format!("{k}={v}\n")).collect()
}

/// The run's lines and, last, the hash of what the fingerprint adds for the frame `view`
/// shows (its number, camera, exposure and time).
pub(crate) fn of_frame(run: &str, view: &FrameView) -> String {
    let Some(m) = fingerprint::motion(view) else {
        let camera = fingerprint::of_frame(&Hasher::new(), view);
        return format!("{run}camera={}", &camera[..16]);
    };
    // Where objects or lights move, their poses are a line of their own, so that a changed
    // key is named as such rather than as the camera.
    let mut still = view.clone();
    if let Ok(e) = &mut still.exposure {
        e.motion = None;
    }
    let camera = fingerprint::of_frame(&Hasher::new(), &still);
    let mut h = Hasher::new();
    fingerprint::poses(&mut h, m);
    format!("{run}camera={}\nposes={}", &camera[..16], &h.hex()[..16])
}

fn settings(s: &Settings, format: &FileFormat) -> Vec<(String, String)> {
    let exr = matches!(format, FileFormat::Exr { .. });
    let (max, threshold) = match s.adaptive {
        Some(a) => (a.max_samples, a.threshold.to_string()),
        None => (s.samples, "none".into()),
    };
    let yes = |b: bool| if b { "yes" } else { "no" };
    let fields = [
        ("rayreel", env!("CARGO_PKG_VERSION").to_string()),
        ("size", format!("{}x{}", s.width, s.height)),
        ("samples", s.samples.to_string()),
        ("max_samples", max.to_string()),
        ("threshold", threshold),
        ("max_depth", s.max_depth.to_string()),
        ("sampler", sampler(s.sampler).into()),
        ("precision", s.precision.name().into()),
        ("depth", yes(s.depth).into()),
        ("alpha", yes(s.alpha).into()),
        ("exposure", s.exposure.to_string()),
        ("encoding", encoding(s.encoding, exr).into()),
        ("format", format_name(format).into()),
        ("aov", aovs(s.aov)),
        ("denoise", yes(s.denoise).into()),
    ];
    fields.map(|(k, v)| (k.to_string(), v)).into()
}

/// The compositing passes, comma-separated in `Aov::ALL`'s order, or `none`.
fn aovs(a: Aovs) -> String {
    match a.is_empty() {
        true => "none".into(),
        false => a.iter().map(|p| p.name()).collect::<Vec<_>>().join(","),
    }
}

fn sampler(s: Sampler) -> &'static str {
    match s {
        Sampler::Stratified => "stratified",
        Sampler::Random => "random",
    }
}

/// EXR frames are linear whatever the encoding (as in the fingerprint).
fn encoding(e: Encoding, exr: bool) -> &'static str {
    match (e, exr) {
        (Encoding::Srgb, false) => "srgb",
        _ => "linear",
    }
}

fn format_name(f: &FileFormat) -> &'static str {
    match f {
        FileFormat::Png {
            sixteen_bit: false, ..
        } => "png 8-bit",
        FileFormat::Png { .. } => "png 16-bit",
        FileFormat::Exr {
            precision: ExrPrecision::Half,
        } => "exr half",
        FileFormat::Exr { .. } => "exr float",
    }
}

/// A hash of each part of the scene; named materials one by one (they come first in
/// `Scene::materials`), materials written inline in objects together.
fn scene(scene: &Scene, names: &[String]) -> Vec<(String, String)> {
    let hash = |part: &dyn Canon| {
        let mut h = Hasher::new();
        part.canon(&mut h);
        h.hex()[..16].to_string()
    };
    let digests: Vec<u64> = scene.meshes.iter().map(|m| m.digest).collect();
    let mut lines = vec![
        ("background".to_string(), background(scene)),
        ("objects".into(), hash(&scene.objects)),
        ("lights".into(), hash(&scene.lights)),
        ("meshes".into(), hash(&digests)),
    ];
    let (named, inline) = scene
        .materials
        .split_at(names.len().min(scene.materials.len()));
    match names.len() <= MAX_NAMED {
        true => lines.extend(names.iter().zip(named).map(|(name, m)| {
            let name = format!("materials.{}", escape(name));
            (name, format!("{} {}", hash(m), material_fields(m)))
        })),
        false => lines.push(("materials".into(), hash(&named.to_vec()))),
    }
    lines.push(("materials.inline".into(), hash(&inline.to_vec())));
    lines
}

/// The hash of the background: its colour, then (only with one) the sky, as the fingerprint
/// encodes them.
fn background(scene: &Scene) -> String {
    let mut h = Hasher::new();
    scene.background.canon(&mut h);
    if let Some(sky) = &scene.sky {
        h.write(b"sky");
        sky.canon(&mut h);
    }
    h.hex()[..16].to_string()
}

/// A short hash of each of a material's fields, by their YAML names (`ambient:1a2b3c4d
/// diffuse:…`): what a stale frame's reason names when a material changed. Only the hash in
/// front decides whether the material differs (records written before these existed have it
/// alone).
fn material_fields(m: &Material) -> String {
    let short = |parts: &[&dyn Canon]| {
        let mut h = Hasher::new();
        parts.iter().for_each(|p| p.canon(&mut h));
        h.hex()[..8].to_string()
    };
    let fields: [(&str, String); 8] = [
        ("ambient", short(&[&m.ambient, &m.ambient_map])),
        ("diffuse", short(&[&m.diffuse, &m.diffuse_map])),
        ("specular", short(&[&m.specular])),
        ("shininess", short(&[&m.exponent, &m.specular_floor])),
        ("reflection", short(&[&m.reflection])),
        ("transmission", short(&[&m.transmission])),
        ("ior", short(&[&m.ior])),
        ("fresnel", short(&[&m.fresnel])),
    ];
    let fields: Vec<String> = fields.iter().map(|(k, v)| format!("{k}:{v}")).collect();
    fields.join(" ")
}

/// The material fields whose hashes differ between two `materials.NAME` values, or None
/// when either value has none (an older record).
fn material_change(old: &str, new: &str) -> Option<String> {
    let fields = |v: &str| -> Vec<(String, String)> {
        v.split(' ')
            .skip(1)
            .filter_map(|f| f.split_once(':'))
            .map(|(k, h)| (k.to_string(), h.to_string()))
            .collect()
    };
    let (old, new) = (fields(old), fields(new));
    if old.is_empty() || new.is_empty() {
        return None;
    }
    let changed: Vec<&str> = new
        .iter()
        .filter(|(k, h)| old.iter().find(|(o, _)| o == k).is_none_or(|(_, g)| g != h))
        .map(|(k, _)| k.as_str())
        .collect();
    (!changed.is_empty()).then(|| changed.join(", "))
}

/// The part of a record's value that says whether it differs: a material's hash without its
/// fields' hashes (see `material_fields`), any other value whole.
fn deciding<'a>(key: &str, value: Option<&'a str>) -> Option<&'a str> {
    match key.starts_with("materials.") {
        true => value.map(|v| v.split(' ').next().unwrap_or(v)),
        false => value,
    }
}

/// A material's name as record text: ASCII letters, digits, `_` and `-` as they are, any
/// other byte as `%XX`, so no name can break a line or leave Latin-1.
fn escape(name: &str) -> String {
    name.bytes()
        .map(|b| match b {
            b'a'..=b'z' | b'A'..=b'Z' | b'0'..=b'9' | b'_' | b'-' => (b as char).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// How an existing frame's record compares with the one this job would write.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Difference {
    /// No record (written before records existed), or none of its fields differ though the
    /// fingerprint does: re-render.
    Unknown,
    /// Only quality fields differ; `raise` when this job's settings are at least as high in
    /// every one of them (a re-render improves the frame).
    Quality { what: String, raise: bool },
    /// The size differs, and apart from it only quality fields: a finished frame of another
    /// size is never replaced unforced.
    Resized(String),
    /// What the frame shows differs.
    Content(String),
}

/// The fields of a record, in order.
fn fields(record: &str) -> Vec<(&str, &str)> {
    record.lines().filter_map(|l| l.split_once('=')).collect()
}

/// Compares the record an existing frame carries (`None` without one) with this job's.
pub(crate) fn compare(old: Option<&str>, new: &str) -> Difference {
    let Some(old) = old else {
        return Difference::Unknown;
    };
    let (old, new) = (fields(old), fields(new));
    fn get<'a>(list: &[(&str, &'a str)], k: &str) -> Option<&'a str> {
        list.iter().find(|(n, _)| *n == k).map(|f| f.1)
    }
    let mut names: Vec<&str> = new.iter().map(|f| f.0).collect();
    names.extend(old.iter().map(|f| f.0).filter(|k| get(&new, k).is_none()));
    let changed: Vec<&str> = names
        .into_iter()
        .filter(|k| deciding(k, get(&old, k)) != deciding(k, get(&new, k)))
        .collect();
    if changed.is_empty() {
        return Difference::Unknown;
    }
    let what = describe(&changed, |k| (get(&old, k), get(&new, k)));
    // Names come from the file too.
    let what = crate::console::printable(&what).into_owned();
    let quality = |k: &&str| QUALITY.contains(k);
    match changed.iter().all(quality) {
        true => Difference::Quality {
            what,
            raise: raises(&|k| (get(&old, k), get(&new, k))),
        },
        false if changed.iter().all(|k| quality(k) || *k == "size") => Difference::Resized(what),
        false => Difference::Content(what),
    }
}

type Pair<'a> = (Option<&'a str>, Option<&'a str>);

/// `samples: adaptive 4–64 → 2, max_depth: 5 → 3, materials.red`: values for settings,
/// names alone for hashed parts; the three sampling fields as one (the threshold only when
/// it differs).
fn describe<'a>(changed: &[&str], pair: impl Fn(&str) -> Pair<'a>) -> String {
    let sampling = ["samples", "max_samples", "threshold"];
    let mut parts = Vec::new();
    if changed.iter().any(|k| sampling.contains(k)) {
        let side = |i: usize| {
            let v = sampling.map(|k| {
                let p = pair(k);
                [p.0, p.1][i].unwrap_or("?")
            });
            let v = v.map(shown);
            match v[2].as_str() {
                "none" => v[0].clone(),
                t if changed.contains(&"threshold") => {
                    format!("adaptive {}–{} (threshold {t})", v[0], v[1])
                }
                _ => format!("adaptive {}–{}", v[0], v[1]),
            }
        };
        parts.push(format!("samples: {} → {}", side(0), side(1)));
    }
    for k in changed.iter().filter(|k| !sampling.contains(k)) {
        let (old, new) = pair(k);
        let hashed = matches!(
            *k,
            "background" | "objects" | "lights" | "meshes" | "camera" | "poses"
        ) || k.starts_with("materials");
        parts.push(match (hashed, old, new) {
            (true, Some(o), Some(n)) => match material_change(o, n) {
                Some(fields) => format!("{k} ({fields})"),
                None => k.to_string(),
            },
            _ => {
                let [old, new] = [old, new].map(|v| shown(v.unwrap_or("none")));
                format!("{k}: {old} → {new}")
            }
        });
    }
    parts.join(", ")
}

/// A value as it is shown: a frame's record is a file's text, which may hold anything, so
/// what reaches a terminal is escaped and cut short.
fn shown(v: &str) -> String {
    const LONGEST: usize = 40;
    let cut: String = v.chars().take(LONGEST).collect();
    let more = if v.chars().count() > LONGEST {
        "…"
    } else {
        ""
    };
    format!("{}{more}", crate::console::printable(&cut))
}

/// Whether the new quality settings are at least as high as the old in every field: as many
/// samples or more (a uniform count is threshold 0), a threshold as low or lower, as deep or
/// deeper, f64 over f32, the same sampler.
fn raises<'a>(pair: &dyn Fn(&str) -> Pair<'a>) -> bool {
    let number = |v: Option<&str>| match v {
        Some("none") => Some(0.0),
        Some(v) => v.parse::<f64>().ok(),
        None => None,
    };
    let not_lower = |k: &str, higher_is_better: bool| {
        let (old, new) = pair(k);
        match (number(old), number(new)) {
            (Some(o), Some(n)) if higher_is_better => n >= o,
            (Some(o), Some(n)) => n <= o,
            _ => false,
        }
    };
    let precision = pair("precision");
    not_lower("samples", true)
        && not_lower("max_samples", true)
        && not_lower("threshold", false)
        && not_lower("max_depth", true)
        && pair("sampler").0 == pair("sampler").1
        && pair("denoise").0.unwrap_or("no") == pair("denoise").1.unwrap_or("no")
        && (precision.0 == precision.1 || precision.1 == Some(Precision::F64.name()))
}

#[cfg(test)]
mod tests {
    use super::*;

    const OLD: &str = "rayreel=1\nsamples=4\nmax_samples=64\nthreshold=0.02\nmax_depth=5\nsampler=stratified\nprecision=f64\nsize=8x8\nmaterials.red=aa\ncamera=11";

    #[test]
    fn quality_and_content_are_told_apart() {
        let lower = OLD
            .replace("max_samples=64", "max_samples=8")
            .replace("samples=4", "samples=2");
        let d = compare(Some(OLD), &lower);
        assert_eq!(
            d,
            Difference::Quality {
                what: "samples: adaptive 4–64 → adaptive 2–8".into(),
                raise: false
            }
        );
        let deeper = OLD.replace("max_depth=5", "max_depth=6");
        assert!(matches!(
            compare(Some(OLD), &deeper),
            Difference::Quality { raise: true, .. }
        ));
        let f32 = OLD.replace("f64", "f32");
        assert!(matches!(
            compare(Some(OLD), &f32),
            Difference::Quality { raise: false, .. }
        ));
        assert!(matches!(
            compare(Some(&f32), OLD),
            Difference::Quality { raise: true, .. }
        ));
        let red = OLD
            .replace("red=aa", "red=ab")
            .replace("size=8x8", "size=4x4");
        assert_eq!(
            compare(Some(OLD), &red),
            Difference::Content("size: 8x8 → 4x4, materials.red".into())
        );
        assert_eq!(compare(None, OLD), Difference::Unknown);
        assert_eq!(compare(Some(OLD), OLD), Difference::Unknown);
    }

    #[test]
    fn a_hostile_record_prints_escaped_and_short() {
        let evil = OLD.replace("size=8x8", &format!("size=\x1b[2J{}", "9".repeat(99)));
        let Difference::Resized(what) = compare(Some(&evil), OLD) else {
            panic!("only the size differs")
        };
        assert_eq!(what, format!("size: \\u{{1b}}[2J{}… → 8x8", "9".repeat(36)));
    }

    #[test]
    fn a_changed_material_names_its_field() {
        let old = OLD.replace("red=aa", "red=aa ambient:1 diffuse:2 specular:3");
        let new = OLD.replace("red=aa", "red=ab ambient:1 diffuse:5 specular:3");
        assert_eq!(
            compare(Some(&old), &new),
            Difference::Content("materials.red (diffuse)".into())
        );
        // A record without field hashes (an older rayreel's) differs by the hash alone.
        let same = OLD.replace("samples=4", "samples=2");
        let same = same.replace("red=aa", "red=aa ambient:1");
        assert!(matches!(
            compare(Some(OLD), &same),
            Difference::Quality { .. }
        ));
    }

    #[test]
    fn names_stay_on_their_line() {
        assert_eq!(escape("rouge vif=\n"), "rouge%20vif%3D%0A");
    }
}
