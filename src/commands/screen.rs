//! What keeps `check` on one screen for any scene: every list it prints (mesh files, their
//! placements, textures, area lights' notes, warnings) shows its first few items and counts
//! the rest, saying that `rayreel check --full` lists them all; lists of numbers are grouped
//! (`1000 sphere (16 samples)`); mesh files and texture images past the first few are summed
//! up, with the largest. Long file names are cut (`short_name`), lines wrapped at `WIDTH`.
//! Text quoted from model files is cut short where it is read (`sequence::mesh::quoted`).

/// Items a list shows before it counts the rest.
pub(crate) const SHOWN: usize = 4;

/// How much `check` prints: a screen, or everything (`--full`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Screen {
    pub(crate) full: bool,
}

impl Screen {
    /// How many of `total` items a list shows: all of them, or `SHOWN − 1` and a line that
    /// counts the rest.
    pub(crate) fn keep(self, total: usize) -> usize {
        match self.full || total <= SHOWN {
            true => total,
            false => SHOWN - 1,
        }
    }

    /// The first `keep(total)` of `items` as lines, then, when some of the `total` were left
    /// out, `indent… and N more NOUN (rayreel check --full lists them)`. `items` may hold
    /// only those shown, so that the others are never made.
    pub(crate) fn lines(self, items: &[String], total: usize, indent: &str, noun: &str) -> String {
        let keep = self.keep(total).min(items.len());
        let mut out = String::new();
        for item in &items[..keep] {
            out.push_str(item);
            if !item.ends_with('\n') {
                out.push('\n');
            }
        }
        if keep < total {
            out.push_str(&format!(
                "{indent}… and {} more {noun} (`rayreel check --full` lists them)\n",
                total - keep
            ));
        }
        out
    }
}

/// Columns a summary line takes at most: `wrap` breaks longer ones.
pub(crate) const WIDTH: usize = 120;
/// Characters a file name takes at most in a summary line: a longer one keeps its tail.
pub(crate) const NAME: usize = 56;

/// `name` made printable and, past `NAME` characters, cut: its folders first (`…/`), then
/// the middle of the file's own name, whose start and end are what tell files apart
/// (`…/model_number_000_expo…_with_a_long_name.obj`).
pub(crate) fn short_name(name: &str) -> String {
    let name = crate::console::printable(name);
    let chars: Vec<char> = name.chars().collect();
    if chars.len() <= NAME {
        return name.into_owned();
    }
    let own = chars.iter().rposition(|&c| c == '/').map_or(0, |i| i + 1);
    let file = &chars[own..];
    let prefix = if own > 0 { "…/" } else { "" };
    let room = NAME - prefix.chars().count();
    if file.len() <= room {
        return format!("{prefix}{}", file.iter().collect::<String>());
    }
    let head = (room - 1) / 2;
    let tail = room - 1 - head;
    let start: String = file[..head].iter().collect();
    let end: String = file[file.len() - tail..].iter().collect();
    format!("{prefix}{start}…{end}")
}

/// `text` with every line longer than `WIDTH` columns broken at its last space that fits,
/// the rest going on under `indent` (a word longer than a line stays whole).
pub(crate) fn wrap(text: &str, indent: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut rest = line.to_string();
        while rest.chars().count() > WIDTH {
            let fits: String = rest.chars().take(WIDTH + 1).collect();
            let floor = indent.len() + 1;
            let Some(at) = fits.rfind(' ').filter(|&at| at > floor) else {
                break;
            };
            out.push_str(rest[..at].trim_end());
            out.push('\n');
            rest = format!("{indent}{}", rest[at + 1..].trim_start());
        }
        out.push_str(&rest);
        out.push('\n');
    }
    out
}

/// Counts of equal values, in order of first appearance: `[16, 16, 64]` → `[(16, 2), (64, 1)]`.
pub(crate) fn grouped<T: PartialEq + Copy>(values: impl IntoIterator<Item = T>) -> Vec<(T, usize)> {
    let mut groups: Vec<(T, usize)> = Vec::new();
    for v in values {
        match groups.iter_mut().find(|(g, _)| *g == v) {
            Some((_, n)) => *n += 1,
            None => groups.push((v, 1)),
        }
    }
    groups
}

/// Indices as runs: `0-999`, `1, 3 and 7-9`; past `SHOWN` runs, the count of the others.
pub(crate) fn runs(indices: &[usize]) -> String {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for &i in indices {
        match runs.last_mut() {
            Some((_, last)) if *last + 1 == i => *last = i,
            _ => runs.push((i, i)),
        }
    }
    let text = |&(a, b): &(usize, usize)| match a == b {
        true => a.to_string(),
        false => format!("{a}-{b}"),
    };
    let shown: Vec<String> = runs.iter().take(SHOWN).map(text).collect();
    match runs.len() > SHOWN {
        true => {
            let others: usize = runs[SHOWN..].iter().map(|(a, b)| b - a + 1).sum();
            format!("{} and {others} others", shown.join(", "))
        }
        false => match shown.as_slice() {
            [rest @ .., last] if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
            _ => shown.join(""),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_lists_are_cut_and_counted() {
        let items: Vec<String> = (0..10).map(|i| format!("  item {i}")).collect();
        let short = Screen { full: false }.lines(&items, 10, "  ", "items");
        assert_eq!(short.lines().count(), SHOWN);
        assert!(short.ends_with("… and 7 more items (`rayreel check --full` lists them)\n"));
        let full = Screen { full: true };
        assert_eq!(full.lines(&items, 10, "  ", "items").lines().count(), 10);
        let four = Screen { full: false }.lines(&items[..4], 4, "  ", "items");
        assert_eq!(four.lines().count(), 4);
        let made = Screen { full: false }.lines(&items[..3], 10, "  ", "items");
        assert_eq!(made, short);
    }

    #[test]
    fn long_lines_wrap_and_long_names_keep_their_tail() {
        let long = format!("  note: {}", "word ".repeat(60));
        let wrapped = wrap(&long, "        ");
        assert!(
            wrapped.lines().all(|l| l.chars().count() <= WIDTH),
            "{wrapped}"
        );
        assert_eq!(wrapped.split_whitespace().count(), 61);
        assert!(
            wrapped
                .lines()
                .skip(1)
                .all(|l| l.starts_with("        word"))
        );
        assert_eq!(wrap("short\n", "  "), "short\n");
        let name = format!("{}/model.obj", "d".repeat(100));
        assert_eq!(short_name(&name), "…/model.obj");
        let name = format!("models/model_007_{}_long_name.obj", "x".repeat(100));
        let cut = short_name(&name);
        assert_eq!(cut.chars().count(), NAME);
        assert!(
            cut.starts_with("…/model_007_x") && cut.ends_with("x_long_name.obj"),
            "{cut}"
        );
        assert_eq!(short_name("a.obj"), "a.obj");
    }

    #[test]
    fn indices_read_as_runs() {
        assert_eq!(runs(&(0..1000).collect::<Vec<_>>()), "0-999");
        assert_eq!(runs(&[1, 3, 7, 8, 9]), "1, 3 and 7-9");
        assert_eq!(runs(&[0, 2, 4, 6, 8, 10, 11]), "0, 2, 4, 6 and 3 others");
        assert_eq!(grouped([16, 16, 64, 16]), vec![(16, 3), (64, 1)]);
    }
}
