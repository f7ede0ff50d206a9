//! What the command line says in small languages of its own: frame specs (`7`, `0-23`,
//! `0-100:5`, `1-100x2`, `1,3,7-9`, Blender's `1..10`, open `5-`, `last`), shards (`2/4`,
//! `auto`) and sizes (`640x360`).

use crate::frameset::{FrameSet, Run};
use crate::sequence::{MAX_DIMENSION, MAX_PIXELS};

/// Most comma-separated entries a frame spec may have: farm managers hand out one range or a
/// few, and a bound keeps expansion time bounded too.
const MAX_ENTRIES: usize = 64;

/// How frames are numbered, for a frame spec that missed: Blender starts at 1, rayreel at
/// `timeline.first_frame` (0 unless set).
fn numbering(first: u64) -> String {
    match first {
        0 => "; frames are numbered from 0 (set `timeline.first_frame: 1` or --first-frame 1 to number them from 1, as Blender does)".into(),
        _ => format!("; frames are numbered from timeline.first_frame ({first})"),
    }
}

/// What is wrong with a frame spec, a shard or a size (clap shows it after the flag).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SpecError {
    #[error("expected K/N with 1 ≤ K ≤ N, such as 2/4, or `auto` (got `{0}`)")]
    Shard(String),
    #[error("{name}={value} is not a whole number")]
    NotANumber { name: &'static str, value: String },
    #[error("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")]
    NoSlurmCount,
    #[error(
        "SLURM_ARRAY_TASK_ID={id} is outside MIN={min}, COUNT={count} (use a contiguous array such as --array=0-3)"
    )]
    OutsideSlurmArray { id: u64, min: u64, count: u64 },
    #[error("JOB_COMPLETION_INDEX is set: give --shard-count N (the job's completions)")]
    NoShardCount,
    #[error("JOB_COMPLETION_INDEX={index} is not below --shard-count {count}")]
    OutsideShardCount { index: u64, count: u64 },
    #[error(
        "--shard auto needs SLURM_ARRAY_TASK_ID (a Slurm job array) or JOB_COMPLETION_INDEX with --shard-count (a Kubernetes Indexed Job); neither is set"
    )]
    NoScheduler,
    #[error("frame {frame} is outside the timeline, which has frames {first}-{last}{}", numbering(*.first))]
    OutsideTimeline { frame: u64, first: u64, last: u64 },
    #[error("the range {0}-{1} runs backwards")]
    Backwards(u64, u64),
    #[error("frame spec has more than {MAX_ENTRIES} comma-separated entries")]
    TooManyEntries,
    #[error(
        "`{part}` in frame spec `{spec}`: {why}; use forms like 7, 0-23, 1..10, 5-, last, 0-100:5, 1-100x2, 1,3,10-12"
    )]
    Entry {
        part: String,
        spec: String,
        why: &'static str,
    },
    #[error("expected WIDTHxHEIGHT such as 640x360 (got `{0}`)")]
    Size(String),
    #[error("expected WIDTHxHEIGHT with whole numbers such as 640x360 (got `{0}`)")]
    SizeNotWhole(String),
    #[error("{what} must be 1 to {MAX_DIMENSION} pixels (got {got})")]
    Dimension { what: &'static str, got: u64 },
    #[error(
        "{width}x{height} is {pixels} pixels; a frame may have at most {MAX_PIXELS} (e.g. 8192x8192)"
    )]
    Pixels {
        width: u32,
        height: u32,
        pixels: u64,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ShardSpec {
    /// 1-based task number and task count.
    Fixed(u64, u64),
    Auto,
}

pub(crate) fn parse_shard(s: &str) -> Result<ShardSpec, SpecError> {
    if s == "auto" {
        return Ok(ShardSpec::Auto);
    }
    let bad = || SpecError::Shard(s.to_string());
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n): (u64, u64) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok(ShardSpec::Fixed(k, n))
}

/// Turns `--shard auto` into K/N from the scheduler's environment.
pub(crate) fn resolve_shard(
    spec: ShardSpec,
    shard_count: Option<u64>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(u64, u64), SpecError> {
    if let ShardSpec::Fixed(k, n) = spec {
        return Ok((k, n));
    }
    let num = |name: &'static str| -> Result<Option<u64>, SpecError> {
        env(name)
            .map(|value| {
                value
                    .trim()
                    .parse::<u64>()
                    .map_err(|_| SpecError::NotANumber { name, value })
            })
            .transpose()
    };
    if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
        let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let count = num("SLURM_ARRAY_TASK_COUNT")?.ok_or(SpecError::NoSlurmCount)?;
        if id < min || id - min >= count {
            return Err(SpecError::OutsideSlurmArray { id, min, count });
        }
        return Ok((id - min + 1, count));
    }
    if let Some(index) = num("JOB_COMPLETION_INDEX")? {
        let count = shard_count.ok_or(SpecError::NoShardCount)?;
        if index >= count {
            return Err(SpecError::OutsideShardCount { index, count });
        }
        return Ok((index + 1, count));
    }
    Err(SpecError::NoScheduler)
}

/// One end of a range in a frame spec: a number, or the timeline's first or last frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum End {
    At(u64),
    First,
    Last,
}

impl End {
    fn resolve(self, first: u64, last: u64) -> u64 {
        match self {
            End::At(n) => n,
            End::First => first,
            End::Last => last,
        }
    }
}

/// A union of inclusive ranges with steps, kept unexpanded until the timeline is known.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameSpec {
    ranges: Vec<(End, End, u64)>,
}

impl FrameSpec {
    /// The selected frames of a timeline numbered `first`…`last`, or the first one out of
    /// range. Repeated and overlapping ranges are joined as ranges, so `0-9999999` costs one
    /// run, however often it is repeated.
    pub fn frames(&self, first: u64, last: u64) -> Result<FrameSet, SpecError> {
        let mut runs = Vec::with_capacity(self.ranges.len());
        for &(a, b, step) in &self.ranges {
            let (a, b) = (a.resolve(first, last), b.resolve(first, last));
            if let Some(frame) = [a, b].into_iter().find(|n| !(first..=last).contains(n)) {
                return Err(SpecError::OutsideTimeline { frame, first, last });
            }
            if a > b {
                return Err(SpecError::Backwards(a, b));
            }
            runs.push(Run::new(a, b, step));
        }
        Ok(FrameSet::from_runs(runs))
    }
}

/// Parses a frame spec: comma-separated entries `N`, `A-B`, `A..B`, `A-` (to the last frame),
/// `first`, `last`, each range with an optional step `:S` or `xS`.
pub fn parse_frame_spec(s: &str) -> Result<FrameSpec, SpecError> {
    if s.split(',').count() > MAX_ENTRIES {
        return Err(SpecError::TooManyEntries);
    }
    let ranges = s.split(',').map(|part| entry(s, part.trim()));
    Ok(FrameSpec {
        ranges: ranges.collect::<Result<_, _>>()?,
    })
}

/// One entry of a frame spec.
fn entry(spec: &str, part: &str) -> Result<(End, End, u64), SpecError> {
    let bad = |why| SpecError::Entry {
        part: part.to_string(),
        spec: spec.to_string(),
        why,
    };
    if part.is_empty() {
        return Err(bad("empty entry"));
    }
    let (range, step) = match part.split_once([':', 'x']) {
        Some((r, st)) => (r, Some(st)),
        None => (part, None),
    };
    let end = |t: &str, open: End| match t.trim() {
        "" => Ok(open),
        "first" => Ok(End::First),
        "last" => Ok(End::Last),
        t => t
            .parse()
            .map(End::At)
            .map_err(|_| bad("not a whole number")),
    };
    let (start, stop) = match range.split_once("..").or_else(|| range.split_once('-')) {
        Some((a, _)) if a.trim().is_empty() => return Err(bad("the range has no start")),
        Some((a, b)) => (end(a, End::First)?, end(b, End::Last)?),
        None if range.trim().is_empty() => return Err(bad("no frame before the step")),
        None => {
            let n = end(range, End::First)?;
            (n, n)
        }
    };
    if let (End::At(a), End::At(b)) = (start, stop)
        && a > b
    {
        return Err(bad("the range runs backwards"));
    }
    let step = match step {
        Some(st) => st
            .trim()
            .parse::<u64>()
            .map_err(|_| bad("not a whole number"))?,
        None => 1,
    };
    if step == 0 || step > usize::MAX as u64 {
        return Err(bad("the step must be at least 1"));
    }
    Ok((start, stop, step))
}

/// `WxH` with both parts whole numbers of pixels within the limits a frame may have.
pub fn parse_size(s: &str) -> Result<(u32, u32), SpecError> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| SpecError::Size(s.to_string()))?;
    let num = |p: &str, what| {
        let got = (p.trim().parse::<u64>()).map_err(|_| SpecError::SizeNotWhole(s.to_string()))?;
        match (1..=MAX_DIMENSION).contains(&got) {
            true => Ok(got as u32),
            false => Err(SpecError::Dimension { what, got }),
        }
    };
    let (width, height) = (num(w, "width")?, num(h, "height")?);
    let pixels = u64::from(width) * u64::from(height);
    if pixels > MAX_PIXELS {
        return Err(SpecError::Pixels {
            width,
            height,
            pixels,
        });
    }
    Ok((width, height))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(s: &str, count: u64) -> Result<Vec<u64>, String> {
        let spec = parse_frame_spec(s).map_err(|e| e.to_string())?;
        let set = spec.frames(0, count - 1).map_err(|e| e.to_string())?;
        Ok(set.iter().collect())
    }

    #[test]
    fn specs_expand() {
        assert_eq!(frames("7", 10).unwrap(), vec![7]);
        assert_eq!(frames("0-3", 10).unwrap(), vec![0, 1, 2, 3]);
        assert_eq!(frames("0-10:5", 11).unwrap(), vec![0, 5, 10]);
        assert_eq!(frames("1-9x4", 11).unwrap(), vec![1, 5, 9]);
        assert_eq!(frames("1,3,10-12", 13).unwrap(), vec![1, 3, 10, 11, 12]);
        assert_eq!(frames("3,1-3", 13).unwrap(), vec![1, 2, 3]);
    }

    #[test]
    fn garbage_is_rejected_clearly() {
        for bad in ["", "a", "-3", "5-2", "1-9:0", "1,,2", "1.5", "0-3:x", ":2"] {
            let err = frames(bad, 100).unwrap_err();
            assert!(
                err.contains("frame spec") || err.contains("outside"),
                "{bad}: {err}"
            );
        }
        let err = frames("0-100", 48).unwrap_err();
        assert!(
            err.contains("frame 100 is outside the timeline, which has frames 0-47"),
            "{err}"
        );
        // A huge range is refused before anything is expanded.
        assert!(frames("0-18446744073709551615", 48).is_err());
        // Repeated ranges are joined as ranges (this once took 80 MB a copy).
        let spec = vec!["4-8888885"; 16].join(",");
        let set = parse_frame_spec(&spec)
            .unwrap()
            .frames(0, 9_999_999)
            .unwrap();
        assert_eq!((set.len(), set.runs().len()), (8_888_882, 1));
        assert!(
            frames(&vec!["1"; 65].join(","), 10)
                .unwrap_err()
                .contains("more than 64")
        );
    }

    #[test]
    fn shards_parse_and_resolve() {
        assert_eq!(parse_shard("2/4"), Ok(ShardSpec::Fixed(2, 4)));
        for bad in ["0/4", "5/4", "2", "a/b", "1/0"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
        let slurm = |name: &str| match name {
            "SLURM_ARRAY_TASK_ID" => Some("7".to_string()),
            "SLURM_ARRAY_TASK_MIN" => Some("5".to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("4".to_string()),
            _ => None,
        };
        assert_eq!(resolve_shard(ShardSpec::Auto, None, &slurm), Ok((3, 4)));
        let k8s = |name: &str| (name == "JOB_COMPLETION_INDEX").then(|| "0".to_string());
        assert_eq!(resolve_shard(ShardSpec::Auto, Some(3), &k8s), Ok((1, 3)));
        assert!(
            resolve_shard(ShardSpec::Auto, None, &k8s)
                .unwrap_err()
                .to_string()
                .contains("--shard-count")
        );
        assert!(
            resolve_shard(ShardSpec::Auto, None, &|_| None)
                .unwrap_err()
                .to_string()
                .contains("neither is set")
        );
    }

    #[test]
    fn blender_open_and_named_ends() {
        assert_eq!(frames("1..3", 10).unwrap(), vec![1, 2, 3]);
        assert_eq!(frames("7-", 10).unwrap(), vec![7, 8, 9]);
        assert_eq!(frames("7..", 10).unwrap(), vec![7, 8, 9]);
        assert_eq!(frames("last", 10).unwrap(), vec![9]);
        assert_eq!(frames("first,last", 10).unwrap(), vec![0, 9]);
        assert_eq!(frames("0-:4", 10).unwrap(), vec![0, 4, 8]);
        let offset = parse_frame_spec("1001-")
            .unwrap()
            .frames(1001, 1003)
            .unwrap();
        assert_eq!(offset.iter().collect::<Vec<_>>(), vec![1001, 1002, 1003]);
        let below = parse_frame_spec("0")
            .unwrap()
            .frames(1001, 1003)
            .unwrap_err()
            .to_string();
        assert!(below.contains("frames 1001-1003"), "{below}");
    }

    #[test]
    fn sizes() {
        assert_eq!(parse_size("640x360"), Ok((640, 360)));
        assert!(parse_size("640").is_err());
        assert!(parse_size("-1x3").is_err());
        let err = parse_size("70000x70000").unwrap_err().to_string();
        assert!(err.contains("16384"), "{err}");
    }
}
