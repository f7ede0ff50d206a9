//! Output patterns: the last run of `#` in the file name (or an ffmpeg-style `%04d`) becomes
//! the zero-padded frame number, widened when the frame numbers need more digits
//! (`frame_####.png` → `frame_0012.png`); `%d` writes numbers without padding; a name with
//! neither names the one frame a job selects (`still.png`).

use std::path::PathBuf;

/// The longest file name (one path component) Linux file systems take, in bytes.
pub(crate) const NAME_MAX: usize = 255;

/// Why text is not an output pattern.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum PatternError {
    #[error("the output pattern is empty")]
    Empty,
    #[error(
        "output pattern `{0}`: the frame number (`#` or `%04d`) must be in the file name, not a directory"
    )]
    NumberInDirectory(String),
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Pattern {
    prefix: String,
    suffix: String,
    /// Width of the number; 0 for a pattern that names one file.
    digits: usize,
    /// Zero-padded to `digits` (`#`, `%04d`) rather than written as it is (`%d`).
    padded: bool,
    /// The frame a one-file pattern holds.
    only: u64,
}

impl Pattern {
    /// `last_frame` (the largest frame number) decides the minimum width.
    pub(crate) fn new(pattern: &str, last_frame: u64) -> Result<Pattern, PatternError> {
        if pattern.trim().is_empty() {
            return Err(PatternError::Empty);
        }
        let name_start = pattern
            .rfind(['/', std::path::MAIN_SEPARATOR])
            .map_or(0, |i| i + 1);
        let needed = last_frame.max(1).ilog10() as usize + 1;
        let pattern_in = |i: usize| i >= name_start;
        let (prefix, suffix, digits, padded) = match (printf(pattern), pattern.rfind('#')) {
            (Some((start, end, width)), _) if pattern_in(start) => (
                &pattern[..start],
                &pattern[end..],
                width.map_or(1, |w| w.max(needed)),
                width.is_some(),
            ),
            (None, Some(end)) if pattern_in(end) => {
                let start = pattern[..end].trim_end_matches('#').len();
                (
                    &pattern[..start],
                    &pattern[end + 1..],
                    (end + 1 - start).max(needed),
                    true,
                )
            }
            (Some(_), _) | (None, Some(_)) => {
                return Err(PatternError::NumberInDirectory(pattern.to_string()));
            }
            (None, None) => (pattern, "", 0, true),
        };
        Ok(Pattern {
            prefix: prefix.to_string(),
            suffix: suffix.to_string(),
            digits,
            padded,
            only: 0,
        })
    }

    /// Whether the pattern names one file rather than numbered frames.
    pub(crate) fn is_single(&self) -> bool {
        self.digits == 0
    }

    /// A one-file pattern holding frame `n`.
    pub(crate) fn holding(mut self, n: u64) -> Pattern {
        self.only = n;
        self
    }

    pub(crate) fn frame_path(&self, n: u64) -> PathBuf {
        match (self.digits, self.padded) {
            (0, _) => PathBuf::from(&self.prefix),
            (width, true) => PathBuf::from(format!("{}{n:0width$}{}", self.prefix, self.suffix)),
            (_, false) => PathBuf::from(format!("{}{n}{}", self.prefix, self.suffix)),
        }
    }

    /// The frame number whose file name (last path component) is `name`, if any.
    pub(crate) fn frame_number(&self, name: &str) -> Option<u64> {
        let head = self.prefix.rsplit('/').next().unwrap_or_default();
        if self.is_single() {
            return (name == head).then_some(self.only);
        }
        let digits = name
            .strip_prefix(head)?
            .strip_suffix(self.suffix.as_str())?;
        let canonical = match self.padded {
            true => digits.len() == self.digits,
            false => !digits.starts_with('0') || digits == "0",
        };
        if !canonical || digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        digits.parse().ok()
    }

    /// The pattern as ffmpeg's image2 reads it: `frames/orbit/frame_%04d.png`.
    pub(crate) fn ffmpeg(&self) -> String {
        let escape = |s: &str| s.replace('%', "%%");
        match (self.digits, self.padded) {
            (0, _) => self.prefix.clone(),
            (width, true) => format!("{}%0{width}d{}", escape(&self.prefix), escape(&self.suffix)),
            (_, false) => format!("{}%d{}", escape(&self.prefix), escape(&self.suffix)),
        }
    }

    /// The file extension, lower-cased (`png`, `exr`).
    pub(crate) fn extension(&self) -> String {
        self.frame_path(0)
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default()
    }
}

/// The last `%0Nd` or `%d` in `pattern`: (start, end, N) with N `None` for `%d`.
fn printf(pattern: &str) -> Option<(usize, usize, Option<usize>)> {
    let start = pattern.rfind('%')?;
    let spec = pattern[start + 1..].split_once('d')?.0;
    let end = start + 1 + spec.len() + 1;
    match spec {
        "" => Some((start, end, None)),
        _ if spec.starts_with('0') && spec.len() <= 3 => spec
            .parse()
            .ok()
            .filter(|&w| w > 0)
            .map(|w| (start, end, Some(w))),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_become_padded_numbers() {
        let p = Pattern::new("frames/talk/frame_####.png", 47).unwrap();
        assert_eq!(p.frame_path(7), PathBuf::from("frames/talk/frame_0007.png"));
        let p = Pattern::new("f_##.png", 12344).unwrap();
        assert_eq!(p.frame_path(12), PathBuf::from("f_00012.png"));
        assert_eq!(p.frame_path(12344), PathBuf::from("f_12344.png"));
        let p = Pattern::new("out.png", 0).unwrap();
        assert_eq!(p.frame_path(0), PathBuf::from("out.png"));
        assert_eq!(p.extension(), "png");
    }

    #[test]
    fn printf_patterns() {
        let p = Pattern::new("dir/f_%04d.png", 47).unwrap();
        assert_eq!(p, Pattern::new("dir/f_####.png", 47).unwrap());
        assert_eq!(p.ffmpeg(), "dir/f_%04d.png");
        let p = Pattern::new("f%d.exr", 1200).unwrap();
        assert_eq!(p.frame_path(7), PathBuf::from("f7.exr"));
        assert_eq!(p.frame_number("f7.exr"), Some(7));
        assert_eq!(p.frame_number("f07.exr"), None);
        assert_eq!(p.ffmpeg(), "f%d.exr");
        assert_eq!(
            Pattern::new("100%_###.png", 9).unwrap().ffmpeg(),
            "100%%_%03d.png"
        );
    }

    #[test]
    fn file_names_give_back_their_frame_numbers() {
        let p = Pattern::new("frames/talk/frame_####.png", 47).unwrap();
        assert_eq!(p.frame_number("frame_0012.png"), Some(12));
        for other in [
            "frame_012.png",
            "frame_00012.png",
            "frame_0012.exr",
            "frame_+012.png",
        ] {
            assert_eq!(p.frame_number(other), None, "{other}");
        }
        let single = Pattern::new("dir/still.png", 30).unwrap().holding(24);
        assert!(single.is_single());
        assert_eq!(single.frame_number("still.png"), Some(24));
    }

    #[test]
    fn bad_patterns() {
        assert!(Pattern::new("dir_##/f.png", 2).is_err());
        assert!(Pattern::new("dir_%02d/f.png", 2).is_err());
    }
}
