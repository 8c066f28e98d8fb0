//! A small, tolerant scanner that maps dotted field paths of a RON case file to their
//! positions in the text, and positions back to field paths.
//!
//! ron reports *where* a parse error happened but not *which field* it belongs to, and a
//! validation error knows the field but not where it was written. This scanner closes both
//! gaps. It reads the text once into tokens and walks the bracket structure with an explicit
//! stack (no recursion, so no stack overflow on deeply nested malformed input), recording
//! every `name: value` pair as a [`Record`] with its dotted path and its span.
//!
//! Paths follow the case schema, not the RON syntax: an identifier directly before a bracket
//! (`Some(...)`, an enum variant such as `Pillars(...)` or `OffAfter(...)`, an explicit
//! struct name such as `Case(...)`) is transparent, so `substrate: Pillars(width: 8)` records
//! `substrate.width`, and `pac: Some((e: 0.7))` records `active.pac.e`. Elements of a bare
//! tuple get their index (`active.pac.inner_semi_axes.0`) only if they are containers.
//!
//! It never fails: on malformed text it records what it can.

use std::fmt;

/// A position in a text: 1-based line and column. Columns count characters (not bytes),
/// the same convention as ron's error positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Position {
    /// Line, from 1.
    pub line: usize,
    /// Column in characters, from 1.
    pub col: usize,
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.col)
    }
}

impl From<ron::error::Position> for Position {
    fn from(p: ron::error::Position) -> Self {
        Position {
            line: p.line,
            col: p.col,
        }
    }
}

/// One `name: value` pair of the text.
#[derive(Debug, Clone)]
struct Record {
    /// Dotted path, e.g. `materials.nucleus.nu`.
    path: String,
    /// Position of the first character of the field name.
    start: Position,
    /// Position just after the last character of the value (exclusive).
    end: Position,
}

/// The fields written in a RON text, with their positions.
#[derive(Debug, Clone, Default)]
pub struct FieldMap {
    records: Vec<Record>,
    /// The text holds nothing but whitespace and comments.
    blank: bool,
}

/// A token of the scanner (also walked by [`super::overrides`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Tok {
    Ident(String),
    Open(char),
    Close,
    Comma,
    Colon,
    /// Numbers, strings, chars, and any other punctuation.
    Other,
}

/// A token with its span (`end` exclusive).
#[derive(Debug, Clone)]
pub(crate) struct Token {
    pub(crate) tok: Tok,
    pub(crate) start: Position,
    pub(crate) end: Position,
}

/// The tokens of `text` (comments and whitespace skipped). Never fails.
pub(crate) fn tokens(text: &str) -> Vec<Token> {
    let mut lexer = Lexer::new(text);
    let mut tokens = Vec::new();
    while let Some(t) = lexer.next_token() {
        tokens.push(t);
    }
    tokens
}

/// Character cursor with line/column bookkeeping.
struct Lexer {
    chars: Vec<char>,
    i: usize,
    pos: Position,
}

impl Lexer {
    fn new(text: &str) -> Self {
        Lexer {
            chars: text.chars().collect(),
            i: 0,
            pos: Position { line: 1, col: 1 },
        }
    }

    fn peek(&self, k: usize) -> Option<char> {
        self.chars.get(self.i + k).copied()
    }

    fn bump(&mut self) -> Option<char> {
        let c = self.peek(0)?;
        self.i += 1;
        if c == '\n' {
            self.pos.line += 1;
            self.pos.col = 1;
        } else {
            self.pos.col += 1;
        }
        Some(c)
    }

    /// Skips whitespace and comments (line comments and nested block comments).
    fn skip_trivia(&mut self) {
        loop {
            match (self.peek(0), self.peek(1)) {
                (Some(c), _) if c.is_whitespace() => {
                    self.bump();
                }
                (Some('/'), Some('/')) => {
                    while let Some(c) = self.bump() {
                        if c == '\n' {
                            break;
                        }
                    }
                }
                (Some('/'), Some('*')) => {
                    self.bump();
                    self.bump();
                    let mut depth = 1usize;
                    while depth > 0 {
                        match (self.peek(0), self.peek(1)) {
                            (None, _) => return,
                            (Some('*'), Some('/')) => {
                                self.bump();
                                self.bump();
                                depth -= 1;
                            }
                            (Some('/'), Some('*')) => {
                                self.bump();
                                self.bump();
                                depth += 1;
                            }
                            _ => {
                                self.bump();
                            }
                        }
                    }
                }
                _ => return,
            }
        }
    }

    /// Consumes a quoted string whose opening `"` is the next character.
    fn string(&mut self) {
        self.bump();
        while let Some(c) = self.bump() {
            match c {
                '\\' => {
                    self.bump();
                }
                '"' => return,
                _ => {}
            }
        }
    }

    /// Consumes a raw string `r#"..."#` whose `r` has already been consumed.
    fn raw_string(&mut self) {
        let mut hashes = 0usize;
        while self.peek(0) == Some('#') {
            self.bump();
            hashes += 1;
        }
        self.bump(); // the opening quote
        while let Some(c) = self.bump() {
            if c == '"' && (0..hashes).all(|k| self.peek(k) == Some('#')) {
                for _ in 0..hashes {
                    self.bump();
                }
                return;
            }
        }
    }

    /// Is the text at offset `k` a raw-string opening `#*"`?
    fn raw_string_ahead(&self, k: usize) -> bool {
        let mut k = k;
        while self.peek(k) == Some('#') {
            k += 1;
        }
        self.peek(k) == Some('"')
    }

    fn ident_char(c: char) -> bool {
        c.is_alphanumeric() || c == '_'
    }

    fn next_token(&mut self) -> Option<Token> {
        self.skip_trivia();
        let start = self.pos;
        let c = self.peek(0)?;
        let tok = match c {
            '(' | '[' | '{' => {
                self.bump();
                Tok::Open(c)
            }
            ')' | ']' | '}' => {
                self.bump();
                Tok::Close
            }
            ',' => {
                self.bump();
                Tok::Comma
            }
            ':' => {
                self.bump();
                Tok::Colon
            }
            '"' => {
                self.string();
                Tok::Other
            }
            '\'' => {
                self.bump();
                if self.peek(0) == Some('\\') {
                    self.bump();
                    self.bump();
                    // \u{...} escapes: skip to the closing quote, at most a few characters.
                    let mut n = 0;
                    while n < 10 && self.peek(0).is_some_and(|c| c != '\'') {
                        self.bump();
                        n += 1;
                    }
                } else {
                    self.bump();
                }
                if self.peek(0) == Some('\'') {
                    self.bump();
                }
                Tok::Other
            }
            'b' if self.peek(1) == Some('"') => {
                self.bump();
                self.string();
                Tok::Other
            }
            'b' if self.peek(1) == Some('r') && self.raw_string_ahead(2) => {
                self.bump();
                self.bump();
                self.raw_string();
                Tok::Other
            }
            'r' if self.raw_string_ahead(1) => {
                self.bump();
                self.raw_string();
                Tok::Other
            }
            'r' if self.peek(1) == Some('#') && self.peek(2).is_some_and(Self::ident_char) => {
                // Raw identifier r#name: the name is what a field is called.
                self.bump();
                self.bump();
                let mut name = String::new();
                while let Some(c) = self.peek(0).filter(|&c| Self::ident_char(c)) {
                    name.push(c);
                    self.bump();
                }
                Tok::Ident(name)
            }
            c if c.is_alphabetic() || c == '_' => {
                let mut name = String::new();
                while let Some(c) = self.peek(0).filter(|&c| Self::ident_char(c)) {
                    name.push(c);
                    self.bump();
                }
                Tok::Ident(name)
            }
            c if c.is_ascii_digit() || c == '-' || c == '+' || c == '.' => {
                let mut prev = ' ';
                while let Some(c) = self.peek(0) {
                    let exponent_sign = (c == '-' || c == '+') && (prev == 'e' || prev == 'E');
                    let first = self.pos == start;
                    if Self::ident_char(c) || c == '.' || exponent_sign || first {
                        prev = c;
                        self.bump();
                    } else {
                        break;
                    }
                }
                Tok::Other
            }
            _ => {
                self.bump();
                Tok::Other
            }
        };
        Some(Token {
            tok,
            start,
            end: self.pos,
        })
    }
}

/// Brackets nested deeper than this are walked but their fields are not recorded: paths
/// stay short and the scan stays linear in the text on pathological input. (ron itself
/// refuses nesting deeper than 128; a case file needs 4.)
const MAX_DEPTH: usize = 64;

/// One open bracket while walking the text.
struct Frame {
    /// Dotted path of the value this bracket belongs to ("" for the root).
    path: String,
    /// `(`: may hold `name: value` fields; `[` and `{` never do.
    parens: bool,
    /// Opened directly after an identifier (`Some(`, `Pillars(`, `Case(`): its unnamed
    /// elements keep the frame's path instead of getting an index.
    transparent: bool,
    /// Index of the current element.
    index: usize,
    /// No token of the current element has been seen yet.
    at_element_start: bool,
    /// The record of the current element, if it is a `name: value` field.
    field: Option<usize>,
    /// Fields are recorded (false beyond [`MAX_DEPTH`]).
    live: bool,
}

impl Frame {
    fn new(path: String, parens: bool, transparent: bool) -> Self {
        Frame {
            path,
            parens,
            transparent,
            index: 0,
            at_element_start: true,
            field: None,
            live: true,
        }
    }

    /// A frame too deep to record.
    fn dead() -> Self {
        Frame {
            live: false,
            ..Frame::new(String::new(), false, false)
        }
    }

    /// Path of the current element.
    fn element_path(&self, records: &[Record]) -> String {
        match self.field {
            Some(r) => records[r].path.clone(),
            None if self.transparent => self.path.clone(),
            None => join(&self.path, &self.index.to_string()),
        }
    }
}

fn join(base: &str, name: &str) -> String {
    if base.is_empty() {
        name.to_string()
    } else {
        format!("{base}.{name}")
    }
}

impl FieldMap {
    /// Scans `text` and records every `name: value` field. Never fails.
    pub fn scan(text: &str) -> FieldMap {
        let tokens = tokens(text);

        let mut records: Vec<Record> = Vec::new();
        // The root is transparent: the top-level value has path "".
        let mut stack = vec![Frame::new(String::new(), false, true)];
        let mut last_end = Position { line: 1, col: 1 };
        let mut prev_was_ident = false;

        let mut i = 0;
        while i < tokens.len() {
            let t = &tokens[i];
            let next_is_colon = tokens.get(i + 1).is_some_and(|n| n.tok == Tok::Colon);
            let depth = stack.len();
            let Some(frame) = stack.last_mut() else {
                break;
            };
            match &t.tok {
                Tok::Ident(name)
                    if frame.live
                        && frame.parens
                        && frame.at_element_start
                        && next_is_colon
                        && depth > 1 =>
                {
                    records.push(Record {
                        path: join(&frame.path, name),
                        start: t.start,
                        end: tokens[i + 1].end,
                    });
                    frame.field = Some(records.len() - 1);
                    frame.at_element_start = false;
                    last_end = tokens[i + 1].end;
                    prev_was_ident = false;
                    i += 2;
                    continue;
                }
                Tok::Open(c) => {
                    frame.at_element_start = false;
                    if frame.live && depth < MAX_DEPTH {
                        let path = frame.element_path(&records);
                        stack.push(Frame::new(path, *c == '(', prev_was_ident));
                    } else {
                        stack.push(Frame::dead());
                    }
                }
                Tok::Close => {
                    if let Some(r) = frame.field {
                        records[r].end = last_end;
                    }
                    if depth > 1 {
                        stack.pop();
                    }
                }
                Tok::Comma => {
                    if let Some(r) = frame.field.take() {
                        records[r].end = last_end;
                    }
                    frame.index += 1;
                    frame.at_element_start = true;
                }
                Tok::Ident(_) | Tok::Colon | Tok::Other => {
                    frame.at_element_start = false;
                }
            }
            prev_was_ident = matches!(t.tok, Tok::Ident(_));
            last_end = t.end;
            i += 1;
        }
        // Unclosed brackets at the end of a truncated text: close what is open.
        for frame in &stack {
            if let Some(r) = frame.field {
                records[r].end = last_end;
            }
        }
        FieldMap {
            records,
            blank: tokens.is_empty(),
        }
    }

    /// Does the text hold nothing but whitespace and comments?
    pub fn is_blank(&self) -> bool {
        self.blank
    }

    /// Position of the name of the field at dotted `path`, if the text writes it.
    pub fn locate(&self, path: &str) -> Option<Position> {
        self.records
            .iter()
            .find(|r| r.path == path)
            .map(|r| r.start)
    }

    /// Where the text writes the field at dotted `path`: from the start of its name to
    /// the end of its value.
    pub fn span(&self, path: &str) -> Option<(Position, Position)> {
        self.records
            .iter()
            .find(|r| r.path == path)
            .map(|r| (r.start, r.end))
    }

    /// Does the text write the field at dotted `path`?
    pub fn contains(&self, path: &str) -> bool {
        self.locate(path).is_some()
    }

    /// Dotted path of the innermost field whose name or value contains `pos`.
    pub fn path_at(&self, pos: Position) -> Option<&str> {
        self.records
            .iter()
            .filter(|r| r.start <= pos && pos < r.end)
            .max_by_key(|r| r.start)
            .map(|r| r.path.as_str())
    }

    /// Like [`FieldMap::path_at`], but if no field contains `pos`, the innermost field
    /// ending exactly at `pos`: ron reports "expected ..." errors just after the value
    /// that fell short.
    pub fn path_at_or_before(&self, pos: Position) -> Option<&str> {
        self.path_at(pos).or_else(|| {
            self.records
                .iter()
                .filter(|r| r.end == pos)
                .max_by_key(|r| r.start)
                .map(|r| r.path.as_str())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r###"#![enable(implicit_some)]
// a comment with (unbalanced [ brackets and "quotes
Case(
    name: "a (tricky), string: with \" quote",
    geometry: (r_n: 5.0, /* block /* nested */ comment */ r_cp: 9.75),
    substrate: Pillars(width: 8, y_top: Some(-0.3)),
    active: (pac: Some((e: 0.7, inner_semi_axes: (5, 4.5))), bottom: None),
    inertia: (mode: OffAfter(1e+4)),
    r#raw: r##"raw "# string"##,
)
"###;

    #[test]
    fn case_locator_finds_nested_fields() {
        let m = FieldMap::scan(TEXT);
        let at = |p: &str| m.locate(p).map(|p| (p.line, p.col));
        assert_eq!(at("name"), Some((4, 5)));
        assert_eq!(at("geometry"), Some((5, 5)));
        assert_eq!(at("geometry.r_n"), Some((5, 16)));
        assert_eq!(at("geometry.r_cp"), Some((5, 59)));
        assert_eq!(at("substrate.width"), Some((6, 24)));
        assert_eq!(at("substrate.y_top"), Some((6, 34)));
        assert_eq!(at("active.pac.e"), Some((7, 25)));
        assert_eq!(at("active.pac.inner_semi_axes"), Some((7, 33)));
        assert_eq!(at("active.bottom"), Some((7, 62)));
        assert_eq!(at("inertia.mode"), Some((8, 15)));
        assert_eq!(at("raw"), Some((9, 5)));
        assert_eq!(at("string"), None);
        assert_eq!(at("enable"), None);
    }

    #[test]
    fn case_locator_maps_positions_to_paths() {
        let m = FieldMap::scan(TEXT);
        let path = |line, col| m.path_at(Position { line, col });
        assert_eq!(path(5, 21), Some("geometry.r_n")); // inside "5.0"
        assert_eq!(path(5, 30), Some("geometry")); // inside the comment, between fields
        assert_eq!(path(7, 28), Some("active.pac.e"));
        assert_eq!(path(8, 30), Some("inertia.mode")); // inside OffAfter(1e+4)
        assert_eq!(path(10, 1), None); // the closing bracket of the root
        // Just after a value: the field it belongs to.
        assert_eq!(
            m.path_at_or_before(Position { line: 4, col: 46 }),
            Some("name")
        );
        assert!(!m.is_blank());
        assert!(FieldMap::scan("  // only a comment\n /* and another */ ").is_blank());
    }

    #[test]
    fn case_locator_survives_malformed_text() {
        for text in [
            "",
            "(",
            ")))",
            "(a: (b: (c: ",
            "(a: \"unterminated",
            "(a: r#\"unterminated",
            "(a: 'x",
            "/* unterminated",
            "(a: 1, : : , b c: (",
            "r#",
            "'\\u{1234567890123",
        ] {
            let m = FieldMap::scan(text);
            let _ = m.path_at(Position { line: 1, col: 3 });
        }
        // Deep nesting is walked in linear time; only the first levels are recorded.
        let deep = "(a: ".repeat(1_000_000);
        let m = FieldMap::scan(&deep);
        assert!(m.contains("a.a.a"));
        assert!(m.records.len() < MAX_DEPTH);
        let m = FieldMap::scan("(a: (b: (c: 1");
        assert_eq!(m.path_at(Position { line: 1, col: 13 }), Some("a.b.c"));
    }
}
