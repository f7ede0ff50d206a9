//! Sets of frame numbers as ascending runs with strides (`0-9999999` is one run, `0-100:5`
//! another), so choosing, sharding, planning and reporting frames costs what the selection's
//! description costs, not what its frame count does. Written out (`Display`) a set is a frame
//! spec again: `0-11,14,20-47:3`.

use std::fmt;

/// Frames `first`, `first + step`, …: `count` of them (count ≥ 1, step ≥ 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Run {
    pub(crate) first: u64,
    pub(crate) count: u64,
    pub(crate) step: u64,
}

impl Run {
    /// `first..=last` every `step` (first ≤ last, step ≥ 1).
    pub(crate) fn new(first: u64, last: u64, step: u64) -> Run {
        Run {
            first,
            count: (last - first) / step + 1,
            step,
        }
    }

    pub(crate) fn last(&self) -> u64 {
        self.nth(self.count - 1)
    }

    fn nth(&self, i: u64) -> u64 {
        self.first + i * self.step
    }

    fn contains(&self, n: u64) -> bool {
        n >= self.first && n <= self.last() && (n - self.first).is_multiple_of(self.step)
    }

    /// Every frame of `other` is in `self`.
    fn covers(&self, other: &Run) -> bool {
        self.contains(other.first)
            && other.last() <= self.last()
            && (other.count == 1 || other.step.is_multiple_of(self.step))
    }
}

/// Ascending frame numbers without repeats, as runs each ending before the next begins.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FrameSet {
    runs: Vec<Run>,
    len: u64,
}

impl FrameSet {
    pub(crate) fn new() -> FrameSet {
        FrameSet::default()
    }

    /// `first..=last` every `step`.
    pub(crate) fn range(first: u64, last: u64, step: u64) -> FrameSet {
        FrameSet::from_runs(vec![Run::new(first, last, step)])
    }

    /// The union of any runs, overlapping or not. Runs that repeat, contain or extend one
    /// another are joined as runs; only runs whose frames interleave (`0-9:2` with `1-9:2`)
    /// are merged frame by frame, which costs their span.
    pub(crate) fn from_runs(mut runs: Vec<Run>) -> FrameSet {
        runs.sort_by_key(|r| (r.first, std::cmp::Reverse(r.count)));
        let mut kept: Vec<Run> = Vec::with_capacity(runs.len());
        for r in runs {
            match kept.last_mut() {
                Some(a) if a.covers(&r) => {}
                Some(a) if continues(a, &r) => a.count = (r.last() - a.first) / a.step + 1,
                _ => kept.push(r),
            }
        }
        let mut set = FrameSet::new();
        if kept.windows(2).all(|w| w[0].last() < w[1].first) {
            kept.into_iter().for_each(|r| set.push_run(r));
            return set;
        }
        // A bitset over the span (frame numbers stay below the timeline's 10 million) takes
        // each frame once however often the runs repeat it.
        let base = kept.iter().map(|r| r.first).min().unwrap_or(0);
        let span = kept.iter().map(|r| r.last() - base + 1).max().unwrap_or(0);
        let mut seen = vec![0u64; span.div_ceil(64) as usize];
        for i in kept.iter().flat_map(frames_of).map(|n| n - base) {
            seen[(i / 64) as usize] |= 1 << (i % 64);
        }
        (0..span)
            .filter(|i| seen[(i / 64) as usize] >> (i % 64) & 1 == 1)
            .for_each(|i| set.push(base + i));
        set
    }

    /// The union of several sets.
    pub(crate) fn union(sets: &[&FrameSet]) -> FrameSet {
        FrameSet::from_runs(sets.iter().flat_map(|s| s.runs.iter().copied()).collect())
    }

    pub(crate) fn len(&self) -> u64 {
        self.len
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.len == 0
    }

    #[cfg(test)]
    pub(crate) fn runs(&self) -> &[Run] {
        &self.runs
    }

    pub(crate) fn iter(&self) -> impl Iterator<Item = u64> + '_ {
        self.runs.iter().flat_map(frames_of)
    }

    pub(crate) fn contains(&self, n: u64) -> bool {
        let i = self.runs.partition_point(|r| r.last() < n);
        self.runs.get(i).is_some_and(|r| r.contains(n))
    }

    /// The frame after `n` in the set, `n` being in it.
    pub(crate) fn next_after(&self, n: u64) -> Option<u64> {
        let i = self.runs.partition_point(|r| r.last() < n);
        let r = self.runs.get(i)?;
        match n < r.last() {
            true => Some(n + r.step),
            false => self.runs.get(i + 1).map(|r| r.first),
        }
    }

    pub(crate) fn last(&self) -> Option<u64> {
        self.runs.last().map(Run::last)
    }

    /// Adds `n`, which must exceed every frame in the set, as a run of its own: a set built
    /// from a sparse subset of another should not stride over the frames in between.
    pub(crate) fn push_apart(&mut self, n: u64) {
        debug_assert!(self.runs.last().is_none_or(|r| r.last() < n));
        self.len += 1;
        self.runs.push(Run {
            first: n,
            count: 1,
            step: 1,
        });
    }

    /// Adds `n`, which must exceed every frame in the set.
    pub(crate) fn push(&mut self, n: u64) {
        debug_assert!(self.runs.last().is_none_or(|r| r.last() < n));
        self.len += 1;
        let single = Run {
            first: n,
            count: 1,
            step: 1,
        };
        let Some(r) = self.runs.last_mut() else {
            return self.runs.push(single);
        };
        if r.count == 1 {
            (r.count, r.step) = (2, n - r.first);
        } else if n == r.last() + r.step {
            r.count += 1;
        } else if r.count == 2 && r.step > 1 {
            // Two frames make a run of any step; give the second to the new run instead, so
            // `14, 20, 21, 22` reads `14,20-22` rather than `14,20,21-22`.
            let second = r.last();
            (r.count, r.step) = (1, 1);
            self.runs.push(Run {
                first: second,
                count: 2,
                step: n - second,
            });
        } else {
            self.runs.push(single);
        }
    }

    /// Adds `run`, which must begin after every frame in the set.
    fn push_run(&mut self, run: Run) {
        self.push(run.first);
        if run.count == 1 {
            return;
        }
        self.len += run.count - 1;
        let rest = Run {
            first: run.first + run.step,
            count: run.count - 1,
            step: run.step,
        };
        let last = self.runs.last_mut().expect("just pushed");
        if last.count == 1 {
            last.step = run.step;
        }
        if last.step == run.step {
            last.count += rest.count;
        } else if last.count == 2 && last.step > 1 {
            // As in `push`: the run's first frame leaves the two-frame run it had joined.
            (last.count, last.step) = (1, 1);
            self.runs.push(run);
        } else {
            self.runs.push(rest);
        }
    }

    /// The set without the frames in `sorted` (ascending; frames not in the set are ignored).
    pub(crate) fn without(&self, sorted: &[u64]) -> FrameSet {
        let mut out = FrameSet::new();
        let mut j = 0;
        for r in &self.runs {
            let mut from = 0;
            while let Some(&p) = sorted.get(j).filter(|&&p| p <= r.last()) {
                j += 1;
                if !r.contains(p) {
                    continue;
                }
                let i = (p - r.first) / r.step;
                if i > from {
                    out.push_run(piece(r, from, i));
                }
                from = i + 1;
            }
            if from < r.count {
                out.push_run(piece(r, from, r.count));
            }
        }
        out
    }

    /// Task `k` of `n` (1-based): every n-th frame of the set starting with its k-th.
    pub(crate) fn shard(&self, k: u64, n: u64) -> FrameSet {
        let mut out = FrameSet::new();
        let mut seen = 0u64;
        for r in &self.runs {
            // The first index i in this run with (seen + i) % n == k - 1.
            let i = (k - 1 + n - seen % n) % n;
            if i < r.count {
                let count = (r.count - 1 - i) / n + 1;
                // count > 1 means n < r.count, so the new step cannot overflow.
                let step = if count == 1 { 1 } else { r.step * n };
                out.push_run(Run {
                    first: r.nth(i),
                    count,
                    step,
                });
            }
            seen += r.count;
        }
        out
    }
}

/// `b` (which starts no earlier than `a`) carries on `a`'s progression without a gap.
fn continues(a: &Run, b: &Run) -> bool {
    (b.count == 1 || b.step == a.step)
        && a.count > 1
        && b.first >= a.first
        && (b.first - a.first).is_multiple_of(a.step)
        && b.first <= a.last() + a.step
}

fn frames_of(r: &Run) -> impl Iterator<Item = u64> + '_ {
    (0..r.count).map(move |i| r.nth(i))
}

/// Frames `from..to` (indices) of `r`.
fn piece(r: &Run, from: u64, to: u64) -> Run {
    Run {
        first: r.nth(from),
        count: to - from,
        step: if to - from == 1 { 1 } else { r.step },
    }
}

impl fmt::Display for FrameSet {
    /// `0-11,14,20-47:3`: runs of one step as ranges, two frames of a wider step as a pair.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, r) in self.runs.iter().enumerate() {
            if i > 0 {
                f.write_str(",")?;
            }
            match (r.count, r.step) {
                (1, _) => write!(f, "{}", r.first)?,
                (_, 1) => write!(f, "{}-{}", r.first, r.last())?,
                (2, _) => write!(f, "{},{}", r.first, r.last())?,
                _ => write!(f, "{}-{}:{}", r.first, r.last(), r.step)?,
            }
        }
        Ok(())
    }
}

/// `n` frames spread evenly over `0..frame_count`, first and last included:
/// n_k = round(k·(frame_count − 1)/(n − 1)), ascending and without repeats.
pub fn evenly_spaced(frame_count: u64, n: u64) -> Vec<u64> {
    if frame_count == 0 || n == 0 {
        return Vec::new();
    }
    if n == 1 {
        return vec![0];
    }
    // Steps shorter than one frame round onto every frame: skip building n values.
    if n >= frame_count {
        return (0..frame_count).collect();
    }
    let (last, d) = (u128::from(frame_count - 1), u128::from(n - 1));
    // Integer rounding (half up) so the choice is exact for any frame count.
    let mut out: Vec<u64> = (0..u128::from(n))
        .map(|k| ((2 * k * last + d) / (2 * d)) as u64)
        .collect();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evenly_spaced_hits_both_ends() {
        assert_eq!(evenly_spaced(144, 12).first(), Some(&0));
        assert_eq!(evenly_spaced(144, 12).last(), Some(&143));
        assert_eq!(evenly_spaced(144, 12).len(), 12);
        assert_eq!(evenly_spaced(5, 3), vec![0, 2, 4]);
        assert_eq!(evenly_spaced(4, 12), vec![0, 1, 2, 3]);
        assert_eq!(evenly_spaced(10, 1), vec![0]);
        assert_eq!(evenly_spaced(1, 12), vec![0]);
        // round(k·3/2) for k = 0..2 is 0, 2 (1.5 rounds up), 3.
        assert_eq!(evenly_spaced(4, 3), vec![0, 2, 3]);
    }

    /// A tiny deterministic generator for the comparisons with plain vectors.
    struct Lcg(u64);

    impl Lcg {
        fn below(&mut self, n: u64) -> u64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 33) % n
        }
    }

    fn naive(runs: &[Run]) -> Vec<u64> {
        let mut all: Vec<u64> = runs.iter().flat_map(frames_of).collect();
        all.sort_unstable();
        all.dedup();
        all
    }

    fn random_runs(rng: &mut Lcg) -> Vec<Run> {
        (0..1 + rng.below(5))
            .map(|_| {
                let first = rng.below(60);
                Run::new(first, first + rng.below(40), 1 + rng.below(4))
            })
            .collect()
    }

    #[test]
    fn unions_shards_and_differences_match_plain_vectors() {
        let mut rng = Lcg(7);
        for _ in 0..3000 {
            let runs = random_runs(&mut rng);
            let set = FrameSet::from_runs(runs.clone());
            let want = naive(&runs);
            assert_eq!(set.iter().collect::<Vec<_>>(), want, "{runs:?}");
            assert_eq!(set.len(), want.len() as u64);
            assert!(set.runs.windows(2).all(|w| w[0].last() < w[1].first));
            for n in 0..110 {
                assert_eq!(set.contains(n), want.contains(&n), "{n} in {runs:?}");
            }
            let n = 1 + rng.below(5);
            for k in 1..=n {
                let share: Vec<u64> = want
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i as u64 % n == k - 1)
                    .map(|(_, f)| *f)
                    .collect();
                assert_eq!(set.shard(k, n).iter().collect::<Vec<_>>(), share);
            }
            let gone: Vec<u64> = want.iter().copied().filter(|_| rng.below(3) == 0).collect();
            let rest: Vec<u64> = want.iter().copied().filter(|f| !gone.contains(f)).collect();
            assert_eq!(set.without(&gone).iter().collect::<Vec<_>>(), rest);
            // Written out, a set is a frame spec that selects the same frames.
            let spec = crate::cli::parse_frame_spec(&set.to_string());
            if !set.is_empty() {
                assert_eq!(
                    spec.unwrap()
                        .frames(0, 199)
                        .unwrap()
                        .iter()
                        .collect::<Vec<_>>(),
                    want
                );
            }
        }
    }

    #[test]
    fn written_compactly() {
        let mut s = FrameSet::new();
        for n in [0, 1, 2, 3, 5, 7, 8, 14, 20, 21, 22] {
            s.push(n);
        }
        assert_eq!(s.to_string(), "0-3,5,7-8,14,20-22");
        assert_eq!(FrameSet::range(0, 100, 5).to_string(), "0-100:5");
        assert_eq!(FrameSet::range(4, 9, 5).to_string(), "4,9");
        assert_eq!(FrameSet::new().to_string(), "");
        let big = FrameSet::range(0, 9_999_999, 1);
        assert_eq!((big.len(), big.runs().len()), (10_000_000, 1));
        assert_eq!(big.shard(2, 4).to_string(), "1-9999997:4");
        assert_eq!(big.without(&[5, 9_999_999]).to_string(), "0-4,6-9999998");
        assert_eq!(big.next_after(41), Some(42));
        let spread = FrameSet::range(0, 10, 5);
        assert_eq!(
            (spread.next_after(5), spread.next_after(10)),
            (Some(10), None)
        );
    }
}
