//! Output patterns: the last run of `#` in the file name becomes the zero-padded frame number,
//! widened when the frame count needs more digits (`frame_####.png` → `frame_0012.png`).

use std::path::PathBuf;

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pattern {
    prefix: String,
    suffix: String,
    digits: usize,
}

impl Pattern {
    /// `frame_count` decides the minimum width; a pattern without `#` only suits one frame.
    pub fn new(pattern: &str, frame_count: u64) -> Result<Pattern, String> {
        if pattern.trim().is_empty() {
            return Err("the output pattern is empty".into());
        }
        let Some(end) = pattern.rfind('#') else {
            if frame_count > 1 {
                return Err(format!(
                    "output pattern `{pattern}` has no `#` run for the frame number, but the sequence has {frame_count} frames (e.g. frame_####.png)"
                ));
            }
            return Ok(Pattern {
                prefix: pattern.to_string(),
                suffix: String::new(),
                digits: 0,
            });
        };
        let start = pattern[..end].trim_end_matches('#').len();
        if pattern[end + 1..].contains(['/', std::path::MAIN_SEPARATOR]) {
            return Err(format!(
                "output pattern `{pattern}`: the `#` run must be in the file name, not a directory"
            ));
        }
        let needed = frame_count.saturating_sub(1).max(1).ilog10() as usize + 1;
        Ok(Pattern {
            prefix: pattern[..start].to_string(),
            suffix: pattern[end + 1..].to_string(),
            digits: (end + 1 - start).max(needed),
        })
    }

    pub fn frame_path(&self, n: u64) -> PathBuf {
        if self.digits == 0 {
            return PathBuf::from(&self.prefix);
        }
        PathBuf::from(format!(
            "{}{:0width$}{}",
            self.prefix,
            n,
            self.suffix,
            width = self.digits
        ))
    }

    /// The frame number whose file name (last path component) is `name`, if any.
    pub fn frame_number(&self, name: &str) -> Option<u64> {
        let head = self.prefix.rsplit('/').next().unwrap_or_default();
        if self.digits == 0 {
            return (name == head).then_some(0);
        }
        let digits = name
            .strip_prefix(head)?
            .strip_suffix(self.suffix.as_str())?;
        if digits.len() != self.digits || !digits.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        digits.parse().ok()
    }

    /// The file extension, lower-cased (`png`, `exr`).
    pub fn extension(&self) -> String {
        self.frame_path(0)
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_become_padded_numbers() {
        let p = Pattern::new("frames/talk/frame_####.png", 48).unwrap();
        assert_eq!(p.frame_path(7), PathBuf::from("frames/talk/frame_0007.png"));
        let p = Pattern::new("f_##.png", 12345).unwrap();
        assert_eq!(p.frame_path(12), PathBuf::from("f_00012.png"));
        assert_eq!(p.frame_path(12344), PathBuf::from("f_12344.png"));
        let p = Pattern::new("out.png", 1).unwrap();
        assert_eq!(p.frame_path(0), PathBuf::from("out.png"));
        assert_eq!(p.extension(), "png");
    }

    #[test]
    fn file_names_give_back_their_frame_numbers() {
        let p = Pattern::new("frames/talk/frame_####.png", 48).unwrap();
        assert_eq!(p.frame_number("frame_0012.png"), Some(12));
        for other in [
            "frame_012.png",
            "frame_00012.png",
            "frame_0012.exr",
            "frame_+012.png",
        ] {
            assert_eq!(p.frame_number(other), None, "{other}");
        }
        let single = Pattern::new("dir/still.png", 1).unwrap();
        assert_eq!(single.frame_number("still.png"), Some(0));
    }

    #[test]
    fn bad_patterns() {
        assert!(Pattern::new("out.png", 2).unwrap_err().contains("no `#`"));
        assert!(Pattern::new("dir_##/f.png", 2).is_err());
    }
}
