//! How deeply a YAML text nests, found in one linear pass before libyaml sees the text.
//!
//! serde_yaml has libyaml scan a whole document into events before deserializing it, and its
//! own depth limit (128) applies only then. By that time the damage is done: libyaml re-examines
//! every open flow collection at each token, so `[[[[…` costs time quadratic in the depth
//! (100,000 `[` take 15 s), and every open collection, block or flow, holds a few hundred bytes.
//!
//! The scan follows libyaml's scanner (unsafe-libyaml 0.2) closely enough to count no lower
//! than it: flow brackets outside quoted scalars, comments, tags and block scalars, and block
//! collections through libyaml's own indentation stack. Every level counts twice, since one
//! may hold a second collection that opens without a bracket or indentation of its own: a
//! sequence sharing its mapping's column (`key:` then `- item`), or a single-pair mapping in a
//! flow sequence (`[a: [b: 1]]`), and a flow collection counts one more in case it is the key
//! of a block mapping (`[a]: b`). The bound is thus at most twice the real depth plus one. The `fuzz/`
//! target `nesting` checks it against the depth serde_yaml reaches. (libyaml's parser can nest
//! deeper than its scanner: after `?` in a flow sequence it drops the next `]`, so `[?],[?],…`
//! leaves sequences open. That costs memory per event like any other dense YAML, not time,
//! and serde_yaml's recursion limit stops it.)

/// An upper bound on the nesting depth of `text` (at most twice the real depth plus one), and the
/// 1-based line and column where it is first reached; (0, 1, 1) for a text with no collections.
pub fn nesting_depth(text: &str) -> (usize, usize, usize) {
    let mut s = Scanner::new(text, usize::MAX);
    s.run();
    (s.max, s.max_at.0, s.max_at.1)
}

/// Line and column (1-based) of the first point where the bound of `nesting_depth` passes
/// `limit`.
pub(crate) fn first_too_deep(text: &str, limit: usize) -> Option<(usize, usize)> {
    let mut s = Scanner::new(text, limit);
    s.run();
    (s.max > limit).then_some(s.max_at)
}

/// A possible simple key at flow level 0: where a `key:` would open its block mapping.
#[derive(Clone, Copy)]
struct Key {
    line: usize,
    col: usize,
    byte: usize,
}

struct Scanner<'a> {
    /// The text up to the first character libyaml's reader refuses, where it stops.
    text: &'a str,
    /// Byte offset of the next character.
    i: usize,
    line: usize,
    col: usize,
    flow: usize,
    /// libyaml's `indents` plus its current `indent` on top; empty means -1.
    indents: Vec<usize>,
    key: Option<Key>,
    key_allowed: bool,
    limit: usize,
    max: usize,
    max_at: (usize, usize),
}

fn blank(c: Option<char>) -> bool {
    matches!(c, Some(' ' | '\t'))
}

fn brk(c: Option<char>) -> bool {
    matches!(c, Some('\n' | '\r' | '\u{85}' | '\u{2028}' | '\u{2029}'))
}

fn blankz(c: Option<char>) -> bool {
    c.is_none() || blank(c) || brk(c)
}

/// libyaml's reader stops the whole parse at the first character YAML does not allow.
fn allowed(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{7e}' | '\u{85}' | '\u{a0}'..='\u{d7ff}' | '\u{e000}'..='\u{fffd}' | '\u{10000}'..)
}

fn anchor_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || c == '-'
}

fn tag_char(c: char, verbatim: bool) -> bool {
    anchor_char(c) || ";/?:@&=+$.%!~*'()".contains(c) || (verbatim && ",[]".contains(c))
}

impl<'a> Scanner<'a> {
    fn new(text: &'a str, limit: usize) -> Scanner<'a> {
        let end = text
            .char_indices()
            .find(|&(_, c)| !allowed(c))
            .map_or(text.len(), |(i, _)| i);
        Scanner {
            text: &text[..end],
            i: 0,
            line: 1,
            col: 0,
            flow: 0,
            indents: Vec::new(),
            key: None,
            key_allowed: true,
            limit,
            max: 0,
            max_at: (1, 1),
        }
    }

    /// The character `k` characters ahead.
    fn at(&self, k: usize) -> Option<char> {
        self.text[self.i..].chars().nth(k)
    }

    fn done(&self) -> bool {
        self.max > self.limit
    }

    /// Consumes one character; a line break (CR LF counts once) starts a new line.
    fn bump(&mut self) {
        let Some(ch) = self.at(0) else { return };
        if ch == '\r' && self.at(1) == Some('\n') {
            self.i += 1;
        }
        self.i += ch.len_utf8();
        if brk(Some(ch)) {
            self.line += 1;
            self.col = 0;
        } else {
            self.col += 1;
        }
    }

    fn depth(&self) -> usize {
        // Inside a flow collection one more: it may turn out to be the key of a block mapping
        // (`[a: 1]: x`), which libyaml opens before it once the `:` is found.
        2 * (self.indents.len() + self.flow) + usize::from(self.flow > 0)
    }

    fn note_depth(&mut self, line: usize, col: usize) {
        let d = self.depth();
        if d > self.max {
            self.max = d;
            self.max_at = (line, col + 1);
        }
    }

    fn indent(&self) -> isize {
        self.indents.last().map_or(-1, |&i| i as isize)
    }

    fn roll(&mut self, col: usize) {
        if self.flow == 0 && self.indent() < col as isize {
            self.indents.push(col);
            self.note_depth(self.line, col);
        }
    }

    fn unroll(&mut self, col: isize) {
        if self.flow == 0 {
            while self.indent() > col {
                self.indents.pop();
            }
        }
    }

    fn save_key(&mut self) {
        if self.key_allowed && self.flow == 0 {
            self.key = Some(Key {
                line: self.line,
                col: self.col,
                byte: self.i,
            });
        }
    }

    fn remove_key(&mut self) {
        if self.flow == 0 {
            self.key = None;
        }
    }

    fn document_marker(&self) -> bool {
        self.col == 0
            && matches!(
                (self.at(0), self.at(1), self.at(2)),
                (Some('-'), Some('-'), Some('-')) | (Some('.'), Some('.'), Some('.'))
            )
            && blankz(self.at(3))
    }

    fn skip_to_break(&mut self) {
        while self.at(0).is_some() && !brk(self.at(0)) {
            self.bump();
        }
    }

    /// libyaml's `scan_to_next_token`: spaces, comments and line breaks.
    fn skip_to_token(&mut self) {
        loop {
            if self.col == 0 && self.at(0) == Some('\u{feff}') {
                self.bump();
            }
            while self.at(0) == Some(' ')
                || ((self.flow > 0 || !self.key_allowed) && self.at(0) == Some('\t'))
            {
                self.bump();
            }
            if self.at(0) == Some('#') {
                self.skip_to_break();
            }
            if !brk(self.at(0)) {
                return;
            }
            self.bump();
            if self.flow == 0 {
                self.key_allowed = true;
            }
        }
    }

    fn run(&mut self) {
        while !self.done() {
            self.skip_to_token();
            let Some(ch) = self.at(0) else { return };
            let start = self.i;
            if let Some(k) = self.key
                && (k.line < self.line || k.byte + 1024 < self.i)
            {
                self.key = None;
            }
            self.unroll(self.col as isize);
            if !self.document_boundary(ch) {
                self.token(ch);
            }
            if self.i == start {
                self.bump();
            }
        }
    }

    /// A directive (`%YAML`) or a document marker (`---`, `...`) at the start of a line, which
    /// closes every block collection; false for anything else.
    fn document_boundary(&mut self, ch: char) -> bool {
        let directive = self.col == 0 && ch == '%';
        let marker = !directive && self.document_marker();
        if !(directive || marker) {
            return false;
        }
        self.unroll(-1);
        self.remove_key();
        self.key_allowed = false;
        match directive {
            true => self.skip_to_break(),
            false => (0..3).for_each(|_| self.bump()),
        }
        true
    }

    /// One token starting with `ch`, as libyaml's `fetch_next_token` tells them apart.
    fn token(&mut self, ch: char) {
        let (line, col) = (self.line, self.col);
        match ch {
            '[' | '{' => {
                self.save_key();
                self.flow += 1;
                self.key_allowed = true;
                self.bump();
                self.note_depth(line, col);
            }
            ']' | '}' => {
                self.remove_key();
                self.flow = self.flow.saturating_sub(1);
                self.key_allowed = false;
                self.bump();
            }
            ',' => {
                self.remove_key();
                self.key_allowed = true;
                self.bump();
            }
            '-' if blankz(self.at(1)) => {
                self.roll(col);
                self.remove_key();
                self.key_allowed = true;
                self.bump();
            }
            '?' if self.flow > 0 || blankz(self.at(1)) => {
                self.roll(col);
                self.remove_key();
                self.key_allowed = self.flow == 0;
                self.bump();
            }
            ':' if self.flow > 0 || blankz(self.at(1)) => self.value(col),
            '*' | '&' => {
                self.save_key();
                self.key_allowed = false;
                self.bump();
                while self.at(0).is_some_and(anchor_char) {
                    self.bump();
                }
            }
            '!' => self.tag(),
            '|' | '>' if self.flow == 0 => {
                self.remove_key();
                self.key_allowed = true;
                self.block_scalar();
            }
            '\'' | '"' => {
                self.save_key();
                self.key_allowed = false;
                self.quoted(ch);
            }
            _ => {
                self.save_key();
                self.key_allowed = false;
                self.plain();
            }
        }
    }

    /// A `:` value indicator: a block mapping opens at the saved simple key's column, or at
    /// this one's when there is none.
    fn value(&mut self, col: usize) {
        let key = if self.flow == 0 {
            self.key.take()
        } else {
            None
        };
        match key {
            Some(k) => {
                self.roll(k.col);
                self.key_allowed = false;
            }
            None => {
                self.roll(col);
                self.key_allowed = self.flow == 0;
            }
        }
        self.bump();
    }

    /// A tag: `!`, `!!str`, `!local`, or verbatim `!<tag:yaml.org,2002:str>`.
    fn tag(&mut self) {
        self.save_key();
        self.key_allowed = false;
        self.bump();
        let verbatim = self.at(0) == Some('<');
        if verbatim {
            self.bump();
        }
        while self.at(0).is_some_and(|c| tag_char(c, verbatim)) {
            self.bump();
        }
        if verbatim && self.at(0) == Some('>') {
            self.bump();
        }
    }

    fn quoted(&mut self, quote: char) {
        self.bump();
        while let Some(ch) = self.at(0) {
            if self.document_marker() {
                return;
            }
            if quote == '\'' && ch == '\'' {
                if self.at(1) == Some('\'') {
                    self.bump();
                    self.bump();
                    continue;
                }
                self.bump();
                return;
            }
            if quote == '"' && ch == '\\' {
                self.bump();
                self.bump();
                continue;
            }
            self.bump();
            if quote == '"' && ch == '"' {
                return;
            }
        }
    }

    /// libyaml's `scan_plain_scalar`: in block context it runs on over lines indented more
    /// than the enclosing collection.
    fn plain(&mut self) {
        let indent = self.indent() + 1;
        let mut leading_blanks = false;
        loop {
            if self.document_marker() || self.at(0) == Some('#') {
                break;
            }
            while !blankz(self.at(0)) {
                let (ch, next) = (self.at(0), self.at(1));
                if ch == Some(':')
                    && (blankz(next)
                        || (self.flow > 0
                            && matches!(next, Some(',' | '?' | '[' | ']' | '{' | '}'))))
                {
                    break;
                }
                if self.flow > 0 && matches!(ch, Some(',' | '[' | ']' | '{' | '}')) {
                    break;
                }
                self.bump();
            }
            if !(blank(self.at(0)) || brk(self.at(0))) {
                break;
            }
            while blank(self.at(0)) || brk(self.at(0)) {
                leading_blanks |= brk(self.at(0));
                self.bump();
            }
            if self.flow == 0 && (self.col as isize) < indent {
                break;
            }
        }
        if leading_blanks {
            self.key_allowed = true;
        }
    }

    /// libyaml's `scan_block_scalar`: a header line, then every line indented at least as
    /// far as the first non-empty one (or as the explicit indentation indicator says).
    fn block_scalar(&mut self) {
        self.bump();
        let mut increment = 0;
        for _ in 0..2 {
            match self.at(0) {
                Some('+' | '-') => self.bump(),
                Some(d @ '1'..='9') if increment == 0 => {
                    increment = d as usize - '0' as usize;
                    self.bump();
                }
                _ => break,
            }
        }
        self.skip_to_break();
        if self.at(0).is_none() {
            return;
        }
        self.bump();
        let mut indent = if increment == 0 {
            0
        } else {
            (self.indent().max(0) as usize) + increment
        };
        self.block_breaks(&mut indent);
        while self.col == indent && self.at(0).is_some() {
            self.skip_to_break();
            if self.at(0).is_none() {
                return;
            }
            self.bump();
            self.block_breaks(&mut indent);
        }
    }

    fn block_breaks(&mut self, indent: &mut usize) {
        let mut max_indent = 0;
        loop {
            while (*indent == 0 || self.col < *indent) && self.at(0) == Some(' ') {
                self.bump();
            }
            max_indent = max_indent.max(self.col);
            if !brk(self.at(0)) {
                break;
            }
            self.bump();
        }
        if *indent == 0 {
            *indent = max_indent.max((self.indent() + 1) as usize).max(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn depth(text: &str) -> usize {
        nesting_depth(text).0
    }

    #[test]
    fn counts_flow_and_block_levels() {
        assert_eq!(depth(""), 0);
        assert_eq!(depth("a: 1\nb: [1, [2, {c: 3}]]\n"), 2 * (1 + 3) + 1);
        assert_eq!(depth("a:\n  b:\n    - [1]\n"), 2 * (3 + 1) + 1);
        assert_eq!(depth("- - - x\n"), 2 * 3);
        assert_eq!(depth(&"[".repeat(1000)), 2 * 1000 + 1);
    }

    #[test]
    fn ignores_brackets_in_scalars_and_comments() {
        assert_eq!(depth("a: '[[[[' # [[[[\nb: \"[[\\\"[[\"\n"), 2);
        assert_eq!(depth("a: x[[[[\nb: |\n  [[[[\n   [[[\nc: !<a[[[> 1\n"), 2);
        assert_eq!(depth("a: 'it''s [[['\n"), 2);
        assert_eq!(depth("a: [!, 1]\n"), 2 * 2 + 1);
    }

    #[test]
    fn plain_scalars_run_on_over_indented_lines() {
        // ` 'x` continues the plain scalar `it`, so the quote opens nothing and the flow
        // sequence on the next line counts.
        assert_eq!(depth("a: it\n 'x\nb: [[[ ']]]' ]]]\n"), 2 * (1 + 3) + 1);
    }

    #[test]
    fn collections_without_brackets_stay_within_the_bound() {
        // Found by the fuzzer. seq, map, seq, map, seq, map: six levels from three brackets.
        assert!(depth("[a: [b: [c: 1]]]") >= 6);
        assert!(depth("x: [? a : [b: 1]]") > 4);
        // A block mapping whose key is a flow sequence holding a pair: three levels.
        assert!(depth(" [a: 1]: b") >= 3);
    }

    #[test]
    fn reports_where_the_limit_is_passed() {
        let text = format!("render:\n  width: {}\n", "[".repeat(100));
        // Two block levels, then the 30th `[` passes 64.
        assert_eq!(first_too_deep(&text, 64), Some((2, 10 + 29)));
        assert_eq!(first_too_deep("a: [[1]]\n", 64), None);
    }
}
