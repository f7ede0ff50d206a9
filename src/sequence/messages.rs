//! How load errors read: serde_yaml's messages made plain, long ones clipped, numbers short.

use super::*;

pub(super) fn yaml_error(file: &Path, source: &str, e: &serde_yaml::Error) -> LoadError {
    let (line, col) = e.location().map_or((1, 1), |l| (l.line(), l.column()));
    let text = e.to_string();
    // serde_yaml appends " at line L column C" (and libyaml "..., while parsing ... at ...");
    // the position is already in front, so keep only the first clause.
    let message = match text.find(" at line ") {
        Some(i) => text[..i].to_string(),
        None => text,
    };
    // serde_yaml's two guards against hostile documents say little on their own.
    let message = match message.as_str() {
        "" => "invalid YAML".into(),
        "recursion limit exceeded" => {
            "nested too deeply, counting what aliases repeat (recursion limit exceeded)".into()
        }
        "repetition limit exceeded" => {
            "aliases repeat too many nodes (repetition limit exceeded)".into()
        }
        _ => out_of_range(&message)
            .or_else(|| {
                let written = e.location().map_or("", |l| scalar_at(source, l.index()));
                tagged_number(&message, written)
            })
            .unwrap_or_else(|| did_you_mean(&rust_types_in_words(&message))),
    };
    LoadError::Invalid {
        file: file.to_owned(),
        line,
        col,
        message: clip(message),
    }
}

/// serde's `expected f64` and `expected u32` in the words of the README.
fn rust_types_in_words(message: &str) -> String {
    let words = [
        ("expected f64", "expected a number"),
        ("expected u64", "expected a whole number (0 or more)"),
        ("expected u32", "expected a whole number (0 or more)"),
        ("expected i64", "expected a whole number"),
        ("expected a boolean", "expected true or false"),
    ];
    let mut message = message.to_string();
    for (rust, plain) in words {
        if let Some(rest) = message.strip_suffix(rust) {
            message = format!("{rest}{plain}");
        }
    }
    message
}

/// serde's `unknown field `radus`, expected one of `center`, `radius`, …` (or `unknown
/// variant`) with `; did you mean `radius`?` appended when one expected name is close: the
/// nearest by edit distance, at most a third of its length away (at least 1), or equal but
/// for case.
pub(super) fn did_you_mean(message: &str) -> String {
    let Some(given) = ["unknown field `", "unknown variant `"]
        .iter()
        .find_map(|p| message.split_once(p).map(|(_, rest)| rest))
        .and_then(|rest| rest.split_once('`'))
        .map(|(given, _)| given)
    else {
        return message.to_string();
    };
    let Some((_, expected)) = message.split_once(", expected ") else {
        return message.to_string();
    };
    let names = expected.split('`').skip(1).step_by(2);
    let best = names
        .map(|name| (edits(&given.to_lowercase(), &name.to_lowercase()), name))
        .filter(|(d, name)| *d <= (name.chars().count() / 3).max(1))
        .min_by_key(|(d, _)| *d);
    match best {
        Some((_, name)) => format!("{message}; did you mean `{name}`?"),
        None => message.to_string(),
    }
}

/// The Levenshtein distance between `a` and `b`, in characters.
fn edits(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// serde_yaml reads a number beyond f64 (`1e400`) as a string and one beyond 64 bits as an
/// i128/u128, then reports a type error; say instead that the number is out of range.
pub(super) fn out_of_range(message: &str) -> Option<String> {
    let (field, rest) = match message.split_once(": invalid type: ") {
        Some((field, rest)) => (format!("{field}: "), rest),
        None => (String::new(), message.strip_prefix("invalid type: ")?),
    };
    if let Some(s) = rest.strip_prefix("string \"") {
        let s = s.strip_suffix("\", expected f64")?;
        let digits = s
            .bytes()
            .all(|b| b.is_ascii_digit() || b"+-.eE".contains(&b));
        s.parse::<f64>()
            .ok()
            .filter(|v| digits && v.is_infinite())?;
        return Some(format!(
            "{field}must be within ±{MAX_MAGNITUDE:e} (lengths are squared) (got {s})"
        ));
    }
    let s = rest.strip_prefix("integer `")?;
    let s = ["u128", "i128"]
        .iter()
        .flat_map(|t| ["u64", "i64"].map(|e| format!("` as {t}, expected {e}")))
        .find_map(|suffix| s.strip_suffix(suffix.as_str()))?;
    Some(format!("{field}number out of range (got {s})"))
}

/// The plain scalar that starts at byte `index` of `text`, as written: up to the end of the
/// line, a comment, or the `,` `]` `}` that ends it in a flow collection.
fn scalar_at(text: &str, index: usize) -> &str {
    let Some(rest) = text.get(index..) else {
        return "";
    };
    let end = rest.find([',', ']', '}', '\n', '#']).unwrap_or(rest.len());
    rest[..end].trim()
}

/// serde_yaml reads some numbers as another type than the field takes and then refuses them
/// for the very type they are (`invalid type: floating point `24.0`, expected f64`): a tagged,
/// quoted number (`fps: !!float "24"`), a hexadecimal or octal one (`0x10`, which YAML 1.1
/// reads as 16), or a negative one where only 0 or more fits. Say which, from `written`, the
/// value as the file has it.
pub(super) fn tagged_number(message: &str, written: &str) -> Option<String> {
    let (field, rest) = message.split_once(": invalid type: ")?;
    let (value, expected) = match rest.strip_prefix("floating point `") {
        Some(r) => (r.strip_suffix("`, expected f64")?, "f64"),
        None => {
            let (value, expected) = rest.strip_prefix("integer `")?.split_once("`, expected ")?;
            (
                ["f64", "u64", "i64"].contains(&expected).then_some(value)?,
                expected,
            )
        }
    };
    let value = value.parse::<f64>().map_or(value.to_string(), num);
    let digits = written.trim_start_matches(['-', '+']).to_ascii_lowercase();
    let base = [("0x", "hexadecimal"), ("0o", "octal"), ("0b", "binary")]
        .into_iter()
        .find(|(prefix, _)| digits.starts_with(prefix));
    if let Some((_, base)) = base {
        return Some(format!(
            "{field}: {base} numbers are not accepted, write {value} (got {written})"
        ));
    }
    if !written.starts_with(['!', '"', '\'']) {
        let what = match expected {
            "u64" => "a whole number, 0 or more",
            "i64" => "a whole number",
            _ => "a number",
        };
        return Some(format!("{field}: must be {what}, got {written}"));
    }
    // `timeline.fps` → `fps: 24`; a list element (`center[1]`) → `0`.
    let plain = match field.ends_with(']') {
        true => value.clone(),
        false => format!("{}: {value}", field.rsplit('.').next().unwrap_or(field)),
    };
    Some(format!(
        "{field}: a tagged, quoted number such as `!!float \"{value}\"` is not read as a number; write it plainly, without tag or quotes: `{plain}`"
    ))
}

/// Longest error message shown whole; longer ones quote some huge value from the file.
pub(super) const MAX_MESSAGE: usize = 400;

/// `message`, cut in the middle when it is too long to read.
pub(super) fn clip(message: String) -> String {
    if message.len() <= MAX_MESSAGE {
        return message;
    }
    let mut head = MAX_MESSAGE / 2;
    while !message.is_char_boundary(head) {
        head -= 1;
    }
    let mut tail = message.len() - MAX_MESSAGE / 4;
    while !message.is_char_boundary(tail) {
        tail += 1;
    }
    format!(
        "{} [… {} bytes …] {}",
        &message[..head],
        tail - head,
        &message[tail..]
    )
}

pub(super) fn got(v: impl Display) -> String {
    format!("(got {v})")
}

/// `(got X)` for a number, short (see `num`).
pub(super) fn got_num(v: f64) -> String {
    got(num(v))
}

pub(crate) use crate::console::num;

/// `[x, y, z]` with each number short (see `num`).
pub(super) fn num3(v: DVec3) -> String {
    format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z))
}

pub(super) fn fmt3(v: raw::V3) -> String {
    num3(DVec3::from(v))
}

/// `s` cut in the middle when long: `aaaaaaaaaaaaaaaaaaaa…aaaaaaaa_0001.png`.
pub(super) fn abbreviated(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    if chars.len() <= 48 {
        return s.to_string();
    }
    let head: String = chars[..24].iter().collect();
    let tail: String = chars[chars.len() - 20..].iter().collect();
    format!("{head}…{tail}")
}
