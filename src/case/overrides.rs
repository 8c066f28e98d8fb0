//! `--set PATH=VALUE`: changes to a case file's text made before it is parsed and
//! validated, so that a bad override gets the same located errors as a bad file.
//!
//! `PATH` is a dotted path into the case as `super::locate` names fields: enum variants
//! and `Some(...)` are transparent (`substrate.width` reaches the `width` of
//! `substrate: Pillars(width: 8.0)`, `active.pac.e` the `e` of `pac: Some((e: 0.7))`), and
//! a number indexes a tuple or list (`active.pac.inner_semi_axes.0`). `VALUE` is one RON
//! value, written as in a case file (`6`, `1e-3`, `Some(0.2)`, `OffAfter(9.0)`,
//! `Pillars(width: 6.0)`).
//!
//! An override is applied to the file's text: a field the file writes gets its value
//! replaced; a field it leaves out is inserted into its section (with the sections on the
//! way, `materials.nucleus.e=900` on a file without `materials` inserts
//! `materials: (nucleus: (e: 900))`); a section written `None` is replaced by one holding
//! the field. The result is then parsed and validated as a file is, and every error is
//! mapped back: to the file's own line and column where the text is the file's, to the
//! `--set` argument where the text is the override's. A field name that the case does not
//! have is refused by the schema with the list of the fields valid at that level.
//!
//! (ron's own [`ron::Value`] cannot carry this: it drops enum variant names, so
//! `Pillars(...)` would not survive a round trip. Splicing the text keeps every comment
//! and position of the file as well.)

use std::fmt;
use std::str::FromStr;

use super::locate::{FieldMap, Position, Tok, Token, tokens};
use super::{Case, CaseError};

/// One `--set PATH=VALUE`: a dotted path into the case and a RON value.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct Override {
    /// Dotted path, e.g. `substrate.spacing`.
    pub path: String,
    /// The value in RON syntax, e.g. `6.0`.
    pub value: String,
    /// Where the override comes from, as an error message names it: `None` for the
    /// command line (`--set PATH=VALUE`), else e.g. "sweep axis `substrate.spacing` =
    /// 10.0" ([`Override::from_source`]). Not serialized.
    pub origin: Option<String>,
}

impl Override {
    /// An override of `path` by `value` (RON text), checked as [`Override::parse`] does.
    pub fn new(path: &str, value: &str) -> Result<Self, OverrideError> {
        Override::parse(&format!("{path}={value}"))
    }

    /// Parses `PATH=VALUE`. The path must be dot-separated field names (identifiers) or
    /// indices; the value must be exactly one RON value. The error says what is wrong.
    pub fn parse(arg: &str) -> Result<Self, OverrideError> {
        let Some((path, value)) = arg.split_once('=') else {
            return Err(OverrideError::NotPathValue(arg.to_string()));
        };
        let (path, value) = (path.trim(), value.trim());
        if path.is_empty() {
            return Err(OverrideError::EmptyPath(arg.to_string()));
        }
        for comp in path.split('.') {
            let ident = comp
                .chars()
                .next()
                .is_some_and(|c| c.is_alphabetic() || c == '_')
                && comp.chars().all(|c| c.is_alphanumeric() || c == '_');
            let index = !comp.is_empty() && comp.chars().all(|c| c.is_ascii_digit());
            if !(ident || index) {
                return Err(OverrideError::NotAFieldName {
                    arg: arg.to_string(),
                    component: comp.to_string(),
                    path: path.to_string(),
                });
            }
        }
        if value.is_empty() {
            return Err(OverrideError::EmptyValue(arg.to_string()));
        }
        if let Err(e) = ron::value::RawValue::from_ron(value) {
            return Err(OverrideError::NotOneValue {
                arg: arg.to_string(),
                value: value.to_string(),
                reason: e.code.to_string(),
                column: e.span.start.col,
            });
        }
        Ok(Override {
            path: path.to_string(),
            value: value.to_string(),
            origin: None,
        })
    }

    /// The same override, named in error messages by `origin` (a sweep file's axis, its
    /// `set` or `derive` entry) instead of `--set PATH=VALUE`.
    pub fn from_source(mut self, origin: impl Into<String>) -> Self {
        self.origin = Some(origin.into());
        self
    }

    /// How an error message names the override: its origin, or `--set PATH=VALUE`.
    pub fn label(&self) -> String {
        match &self.origin {
            Some(o) => o.clone(),
            None => format!("--set {self}"),
        }
    }

    /// The path's components.
    pub fn components(&self) -> Vec<&str> {
        self.path.split('.').collect()
    }
}

impl fmt::Display for Override {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}={}", self.path, self.value)
    }
}

impl FromStr for Override {
    type Err = OverrideError;
    fn from_str(s: &str) -> Result<Self, OverrideError> {
        Override::parse(s)
    }
}

impl TryFrom<String> for Override {
    type Error = OverrideError;
    fn try_from(s: String) -> Result<Self, OverrideError> {
        Override::parse(&s)
    }
}

/// Why a `PATH=VALUE` argument is not an override.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OverrideError {
    /// No `=`.
    #[error("`{0}` is not PATH=VALUE (e.g. substrate.spacing=6.0)")]
    NotPathValue(String),
    /// Nothing before the `=`.
    #[error("`{0}`: the path before `=` is empty (e.g. substrate.spacing=6.0)")]
    EmptyPath(String),
    /// A component of the path is neither a field name nor an index.
    #[error(
        "`{arg}`: `{component}` in the path `{path}` is not a field name (a path is field \
         names joined by dots, e.g. materials.nucleus.e)"
    )]
    NotAFieldName {
        /// The argument.
        arg: String,
        /// The component.
        component: String,
        /// The path.
        path: String,
    },
    /// Nothing after the `=`.
    #[error("`{0}`: the value after `=` is empty")]
    EmptyValue(String),
    /// The value is not exactly one RON value.
    #[error("`{arg}`: the value `{value}` is not one RON value: {reason} (at character {column})")]
    NotOneValue {
        /// The argument.
        arg: String,
        /// The value.
        value: String,
        /// ron's reason.
        reason: String,
        /// Where ron stopped in the value (1-based).
        column: usize,
    },
}

impl From<Override> for String {
    fn from(o: Override) -> String {
        o.to_string()
    }
}

// ---------------------------------------------------------------------------------------
// The value tree of a RON text, with byte spans

/// A value of the text: optional leading words (`Some`, `Pillars`, `-2.0`, `"text"`)
/// and an optional bracketed group after them.
#[derive(Debug)]
struct Node {
    /// Byte span of the whole value in the text.
    start: usize,
    end: usize,
    /// The identifier directly before the group (`Some`, `Pillars`, `OffAfter`), if any.
    ident: Option<String>,
    /// The value is one bare identifier (`None`, `Off`, `true`).
    word: Option<String>,
    group: Option<Group>,
}

#[derive(Debug)]
struct Group {
    /// `(`, `[` or `{`.
    kind: char,
    /// Byte just after the opening bracket.
    open_end: usize,
    elems: Vec<Elem>,
}

#[derive(Debug)]
struct Elem {
    /// `name:` before the value, if any.
    name: Option<String>,
    node: Node,
}

/// Deeper than this the text is taken as malformed (a case needs 4 levels).
const MAX_DEPTH: usize = 64;

struct Parser<'a> {
    text: &'a str,
    toks: Vec<Token>,
    /// Byte offsets of each token's start and end.
    spans: Vec<(usize, usize)>,
    i: usize,
}

impl<'a> Parser<'a> {
    fn new(text: &'a str) -> Self {
        let toks = tokens(text);
        let index = LineIndex::new(text);
        let spans = toks
            .iter()
            .map(|t| (index.byte(text, t.start), index.byte(text, t.end)))
            .collect();
        Parser {
            text,
            toks,
            spans,
            i: 0,
        }
    }

    fn tok(&self, k: usize) -> Option<&Tok> {
        self.toks.get(k).map(|t| &t.tok)
    }

    fn starts_with(&self, k: usize, c: char) -> bool {
        self.spans
            .get(k)
            .is_some_and(|&(s, _)| self.text[s..].starts_with(c))
    }

    /// The whole text: optional `#![...]` attributes, then one value.
    fn root(mut self) -> Option<Node> {
        while matches!(self.tok(self.i), Some(Tok::Other)) && self.starts_with(self.i, '#') {
            self.i += 1;
            if matches!(self.tok(self.i), Some(Tok::Other)) && self.starts_with(self.i, '!') {
                self.i += 1;
            }
            match self.tok(self.i) {
                Some(Tok::Open(c)) => {
                    let c = *c;
                    self.group(c, 1)?;
                }
                _ => return None,
            }
        }
        let node = self.value(0)?;
        (self.i == self.toks.len()).then_some(node)
    }

    fn value(&mut self, depth: usize) -> Option<Node> {
        let first = self.i;
        let mut ident = None;
        let mut group = None;
        loop {
            match self.tok(self.i) {
                Some(Tok::Ident(name)) => {
                    ident = Some(name.clone());
                    self.i += 1;
                }
                Some(Tok::Other) => {
                    ident = None;
                    self.i += 1;
                }
                Some(Tok::Open(c)) => {
                    let c = *c;
                    group = Some(self.group(c, depth + 1)?);
                    break;
                }
                _ => break,
            }
        }
        if self.i == first {
            return None;
        }
        let words = self.i - first - usize::from(group.is_some());
        let word = if group.is_none() && words == 1 {
            ident.clone()
        } else {
            None
        };
        Some(Node {
            start: self.spans[first].0,
            end: self.spans[self.i - 1].1,
            ident: if group.is_some() { ident } else { None },
            word,
            group,
        })
    }

    /// A bracketed group whose opening bracket is the current token.
    fn group(&mut self, kind: char, depth: usize) -> Option<Group> {
        if depth > MAX_DEPTH {
            return None;
        }
        let open_end = self.spans[self.i].1;
        self.i += 1;
        let mut elems = Vec::new();
        loop {
            match self.tok(self.i)? {
                Tok::Close => {
                    self.i += 1;
                    break;
                }
                Tok::Comma => return None,
                _ => {}
            }
            let name = match (self.tok(self.i), self.tok(self.i + 1)) {
                (Some(Tok::Ident(n)), Some(Tok::Colon)) if kind == '(' => {
                    let n = n.clone();
                    self.i += 2;
                    Some(n)
                }
                _ => None,
            };
            let node = self.value(depth)?;
            if matches!(self.tok(self.i), Some(Tok::Colon)) {
                // A map entry `key: value`: keep the value.
                self.i += 1;
                let value = self.value(depth)?;
                elems.push(Elem { name, node: value });
            } else {
                elems.push(Elem { name, node });
            }
            match self.tok(self.i)? {
                Tok::Comma => self.i += 1,
                Tok::Close => {}
                _ => return None,
            }
        }
        Some(Group {
            kind,
            open_end,
            elems,
        })
    }
}

impl Node {
    /// The group holding named fields that this value stands for: its own, or that of
    /// the value inside `Some(...)`.
    fn fields(&self) -> Option<&Group> {
        let g = self.group.as_ref().filter(|g| g.kind == '(')?;
        if self.ident.as_deref() == Some("Some") && g.elems.len() == 1 && g.elems[0].name.is_none()
        {
            return g.elems[0].node.fields();
        }
        g.elems.iter().all(|e| e.name.is_some()).then_some(g)
    }

    /// The elements of a tuple or list value (not named fields).
    fn items(&self) -> Option<&[Elem]> {
        let g = self.group.as_ref()?;
        if self.ident.as_deref() == Some("Some") && g.elems.len() == 1 && g.elems[0].name.is_none()
        {
            if let Some(items) = g.elems[0].node.items() {
                return Some(items);
            }
        }
        g.elems
            .iter()
            .all(|e| e.name.is_none())
            .then_some(g.elems.as_slice())
    }
}

/// `a: (b: (c: value))` for the path `[a, b, c]`.
fn nest(path: &[&str], value: &str) -> String {
    match path {
        [] => value.to_string(),
        [last] => format!("{last}: {value}"),
        [first, rest @ ..] => format!("{first}: ({})", nest(rest, value)),
    }
}

/// Where the text must change to apply an override: replace `start..end` by `text`.
struct Edit {
    start: usize,
    end: usize,
    text: String,
}

impl Edit {
    /// Replaces the text of `node` by `value`.
    fn replace(node: &Node, value: &str) -> Self {
        Edit {
            start: node.start,
            end: node.end,
            text: value.to_string(),
        }
    }
}

/// Why an override cannot be applied to a text.
enum EditError {
    /// The text is not a RON value this module can walk (the parser will say why).
    Malformed,
    /// The path does not lead anywhere; the message says why.
    Path(String),
}

fn snippet(text: &str, node: &Node) -> String {
    let s: String = text[node.start..node.end]
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    if s.chars().count() > 40 {
        format!("{}…", s.chars().take(40).collect::<String>())
    } else {
        s
    }
}

/// The node at `path`, if the text writes it.
fn find<'n>(root: &'n Node, path: &[&str]) -> Option<&'n Node> {
    let mut cur = root;
    for comp in path {
        cur = if let Some(g) = cur.fields() {
            &g.elems
                .iter()
                .find(|e| e.name.as_deref() == Some(comp))?
                .node
        } else {
            let k: usize = comp.parse().ok()?;
            &cur.items()?.get(k)?.node
        };
    }
    Some(cur)
}

fn edit_for(text: &str, path: &[&str], value: &str) -> Result<Edit, EditError> {
    let root = Parser::new(text).root().ok_or(EditError::Malformed)?;
    if root.fields().is_none() {
        return Err(EditError::Malformed);
    }
    let mut cur = &root;
    for (k, comp) in path.iter().enumerate() {
        let last = k + 1 == path.len();
        let here = path[..k].join(".");
        if let Some(g) = cur.fields() {
            match g.elems.iter().find(|e| e.name.as_deref() == Some(comp)) {
                Some(e) if last => return Ok(Edit::replace(&e.node, value)),
                Some(e) => cur = &e.node,
                None => {
                    return Ok(Edit {
                        start: g.open_end,
                        end: g.open_end,
                        text: format!("{}, ", nest(&path[k..], value)),
                    });
                }
            }
        } else if let (Some(items), Ok(index)) = (cur.items(), comp.parse::<usize>()) {
            match items.get(index) {
                Some(e) if last => return Ok(Edit::replace(&e.node, value)),
                Some(e) => cur = &e.node,
                None => {
                    return Err(EditError::Path(format!(
                        "`{here}` has {} elements: no element {index} (they count from 0)",
                        items.len()
                    )));
                }
            }
        } else if cur.word.as_deref() == Some("None") {
            return Ok(Edit {
                start: cur.start,
                end: cur.end,
                text: format!("({})", nest(&path[k..], value)),
            });
        } else {
            return Err(EditError::Path(format!(
                "`{here}` is `{}` in the file, a value without fields: it has no field `{comp}`",
                snippet(text, cur)
            )));
        }
    }
    Err(EditError::Path("empty path".into()))
}

/// The RON text of the value at dotted `path` in `text`, as written, if the text writes
/// it (enum variants and `Some` transparent, as for overrides). Used to read a parameter
/// from a resolved case (`Case::to_ron`).
pub fn value_at(text: &str, path: &str) -> Option<String> {
    let root = Parser::new(text).root()?;
    let comps: Vec<&str> = path.split('.').collect();
    let node = find(&root, &comps)?;
    Some(text[node.start..node.end].to_string())
}

/// The value at `path` in a case as a number, if it is one: a number, or `Some(number)`.
pub fn number_at(case: &Case, path: &str) -> Option<f64> {
    let text = case.to_ron().ok()?;
    parse_number(&value_at(&text, path)?)
}

/// A number from RON text: `1.5`, `Some(1.5)`.
pub fn parse_number(text: &str) -> Option<f64> {
    let t = text.trim();
    let t = t
        .strip_prefix("Some(")
        .and_then(|s| s.strip_suffix(')'))
        .unwrap_or(t);
    t.trim().parse().ok()
}

// ---------------------------------------------------------------------------------------
// Positions and the origin of each piece of the edited text

/// Byte offsets of the starts of the lines of a text.
struct LineIndex {
    starts: Vec<usize>,
}

impl LineIndex {
    fn new(text: &str) -> Self {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        LineIndex { starts }
    }

    /// Byte offset of a (1-based, character-counted) position; clamped to the text.
    fn byte(&self, text: &str, p: Position) -> usize {
        let Some(&line_start) = self.starts.get(p.line.saturating_sub(1)) else {
            return text.len();
        };
        let line = &text[line_start..];
        let line = line.split('\n').next().unwrap_or("");
        let skip = p.col.saturating_sub(1);
        let within = line.char_indices().nth(skip).map_or(line.len(), |(i, _)| i);
        line_start + within
    }

    /// The position of byte `b`.
    fn position(&self, text: &str, b: usize) -> Position {
        let b = b.min(text.len());
        let line = self.starts.partition_point(|&s| s <= b);
        let start = self.starts[line - 1];
        let col = text.get(start..b).map_or(0, |s| s.chars().count()) + 1;
        Position { line, col }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Origin {
    /// Text of the file, from this byte of the original.
    File(usize),
    /// Text written by override `k`.
    Set(usize),
}

#[derive(Debug, Clone, Copy)]
struct Piece {
    origin: Origin,
    len: usize,
}

/// A case text after overrides, knowing which override wrote each piece of it.
#[derive(Debug, Clone)]
pub struct Edited {
    /// The text after the overrides.
    pub text: String,
    original: String,
    pieces: Vec<Piece>,
}

/// Where a position of the edited text came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Source {
    /// The file, at this position of the original text.
    File(Position),
    /// Override number `k`.
    Set(usize),
}

impl Edited {
    fn splice(&mut self, edit: Edit, k: usize) {
        let set = Piece {
            origin: Origin::Set(k),
            len: edit.text.len(),
        };
        let mut pieces = Vec::with_capacity(self.pieces.len() + 2);
        let mut off = 0;
        let mut inserted = false;
        for p in &self.pieces {
            let (a, b) = (off, off + p.len);
            off = b;
            // The part of the piece before the edit, the edit, the part after it.
            if a < edit.start {
                pieces.push(Piece {
                    len: b.min(edit.start) - a,
                    ..*p
                });
            }
            if !inserted && b >= edit.start {
                pieces.push(set);
                inserted = true;
            }
            if b > edit.end {
                let from = a.max(edit.end);
                let origin = match p.origin {
                    Origin::File(o) => Origin::File(o + (from - a)),
                    set => set,
                };
                pieces.push(Piece {
                    origin,
                    len: b - from,
                });
            }
        }
        if !inserted {
            pieces.push(set);
        }
        pieces.retain(|p| p.len > 0);
        self.text.replace_range(edit.start..edit.end, &edit.text);
        self.pieces = pieces;
        debug_assert_eq!(
            self.pieces.iter().map(|p| p.len).sum::<usize>(),
            self.text.len()
        );
    }

    /// The last override that wrote text between positions `from` and `to` of the edited
    /// text (a field's name and value), if any did.
    pub fn set_within(&self, from: Position, to: Position) -> Option<usize> {
        let lines = LineIndex::new(&self.text);
        let (a, b) = (lines.byte(&self.text, from), lines.byte(&self.text, to));
        let mut off = 0;
        let mut last = None;
        for piece in &self.pieces {
            let end = off + piece.len;
            if let Origin::Set(k) = piece.origin {
                if off < b && end > a {
                    last = last.max(Some(k));
                }
            }
            off = end;
        }
        last
    }

    /// Where position `p` of the edited text came from. A position just after an
    /// override's text is the override's: parsers report a value that fell short there.
    pub fn source(&self, p: Position) -> Source {
        let b = LineIndex::new(&self.text).byte(&self.text, p);
        let mut off = 0;
        for piece in &self.pieces {
            let end = off + piece.len;
            match piece.origin {
                Origin::Set(k) if b >= off && b <= end => return Source::Set(k),
                Origin::File(o) if b >= off && b < end => {
                    let ob = o + (b - off);
                    return Source::File(
                        LineIndex::new(&self.original).position(&self.original, ob),
                    );
                }
                _ => {}
            }
            off = end;
        }
        Source::File(LineIndex::new(&self.original).position(&self.original, self.original.len()))
    }
}

/// Applies `overrides`, in order, to the case text `text`. The error message says why an
/// override does not apply; `Err(None)` means the text itself cannot be walked (its own
/// parse error says why).
pub fn apply(text: &str, overrides: &[Override]) -> Result<Edited, (usize, Option<String>)> {
    let mut edited = Edited {
        text: text.to_string(),
        original: text.to_string(),
        pieces: vec![Piece {
            origin: Origin::File(0),
            len: text.len(),
        }],
    };
    for (k, o) in overrides.iter().enumerate() {
        match edit_for(&edited.text, &o.components(), &o.value) {
            Ok(edit) => edited.splice(edit, k),
            Err(EditError::Malformed) => return Err((k, None)),
            Err(EditError::Path(m)) => return Err((k, Some(m))),
        }
    }
    Ok(edited)
}

impl Case {
    /// Reads the case file at `path`, applies `overrides` and validates the result with
    /// the lower layers' checks `layers` ([`Case::load_with_overrides`] gives them).
    pub fn parse_file_with_overrides(
        path: impl AsRef<std::path::Path>,
        overrides: &[Override],
        layers: super::LayerChecks,
    ) -> Result<Case, CaseError> {
        let (label, bytes) = Case::read_file(path.as_ref())?;
        let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
        match std::str::from_utf8(bytes) {
            Ok(text) => Case::parse_str_with_overrides(text, &label, overrides, layers),
            Err(_) => Case::parse_bytes(bytes, &label, layers),
        }
    }

    /// As [`Case::parse_str`], with `overrides` applied to the text first (see
    /// [`Case::load_with_overrides`]).
    pub fn parse_str_with_overrides(
        text: &str,
        file_label: &str,
        overrides: &[Override],
        layers: super::LayerChecks,
    ) -> Result<Case, CaseError> {
        if overrides.is_empty() {
            return Case::parse_str(text, file_label, layers);
        }
        let text = text.strip_prefix('\u{FEFF}').unwrap_or(text);
        let edited = match apply(text, overrides) {
            Ok(e) => e,
            Err((k, message)) => {
                // A file that cannot be walked has a syntax error of its own: report it.
                Case::parse_str(text, file_label, layers)?;
                return Err(CaseError::Override {
                    file: file_label.to_string(),
                    arg: overrides[k].label(),
                    field: Some(overrides[k].path.clone()),
                    message: message.unwrap_or_else(|| "cannot apply to this file".into()),
                });
            }
        };
        Case::parse_str(&edited.text, file_label, layers)
            .map_err(|e| relocate(e, &edited, overrides))
    }
}

/// Maps the positions of an error in the edited text back to the file or to the override
/// that wrote the text there.
fn relocate(e: CaseError, edited: &Edited, overrides: &[Override]) -> CaseError {
    match e {
        CaseError::Parse {
            file,
            position,
            field,
            message,
        } => match edited.source(position) {
            Source::File(position) => CaseError::Parse {
                file,
                position,
                field,
                message,
            },
            Source::Set(k) => CaseError::Override {
                file,
                arg: overrides[k].label(),
                field,
                message,
            },
        },
        CaseError::Invalid { file, problems } => {
            // A problem is the override's when an override wrote any of the field's name
            // or value (a value replaced in place keeps the file's name before it).
            let fields = FieldMap::scan(&edited.text);
            let problems = problems
                .into_iter()
                .map(|mut p| {
                    let by_set = fields
                        .span(&p.violation.field)
                        .and_then(|(a, b)| edited.set_within(a, b));
                    match (by_set, p.position.map(|pos| edited.source(pos))) {
                        (Some(k), _) | (None, Some(Source::Set(k))) => {
                            p.position = None;
                            p.set = Some(overrides[k].label());
                        }
                        (None, Some(Source::File(q))) => p.position = Some(q),
                        (None, None) => {}
                    }
                    p
                })
                .collect();
            CaseError::Invalid { file, problems }
        }
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::Substrate;

    const BASE: &str = "// a comment
(
    name: \"t\",
    substrate: Pillars(width: 8.0, spacing: 8.0, first_center: 0.0),
    adhesion: None,
    active: (pac: Some((e: 0.7))),
    phases: (t_end: 600.0),
    inertia: (mode: OffAfter(0.5)),
)
";

    fn set(args: &[&str]) -> Vec<Override> {
        args.iter().map(|a| Override::parse(a).unwrap()).collect()
    }

    fn load(args: &[&str]) -> Result<Case, CaseError> {
        Case::from_str_with_overrides(BASE, "base.ron", &set(args))
    }

    /// The message refusing `text` (labelled `label`) with `overrides`.
    fn refusal_of(text: &str, label: &str, overrides: &[Override]) -> String {
        Case::from_str_with_overrides(text, label, overrides)
            .unwrap_err()
            .to_string()
    }

    /// The message refusing the base case with the overrides `args`.
    fn refusal(args: &[&str]) -> String {
        refusal_of(BASE, "base.ron", &set(args))
    }

    fn pillars(c: &Case) -> &crate::case::Pillars {
        match &c.substrate {
            Substrate::Pillars(p) => p,
            Substrate::Flat(_) => panic!("flat"),
        }
    }

    #[test]
    fn override_replaces_a_field_inside_an_enum_variant() {
        let c = load(&["substrate.width=6.0", "substrate.spacing=10"]).unwrap();
        assert_eq!(pillars(&c).width, 6.0);
        assert_eq!(pillars(&c).spacing, 10.0);
        assert_eq!(pillars(&c).first_center, 0.0);
    }

    #[test]
    fn override_inserts_fields_and_sections_the_file_leaves_out() {
        let c = load(&[
            "substrate.gap=0.3",
            "materials.nucleus.e=900",
            "solver.rtol=1e-3",
            "output.n_times=500",
        ])
        .unwrap();
        assert_eq!(pillars(&c).gap, 0.3);
        assert_eq!(c.materials.nucleus.e, 900.0);
        assert_eq!(c.solver.rtol, 1e-3);
        assert_eq!(c.output.n_times, 500);
    }

    #[test]
    fn override_reaches_into_options_and_replaces_none() {
        let c = load(&[
            "active.pac.e=0.5",
            "adhesion.e_f=1.5",
            "active.bottom.e=0.6",
        ])
        .unwrap();
        assert_eq!(c.active.pac.as_ref().unwrap().e, 0.5);
        assert_eq!(c.adhesion.as_ref().unwrap().e_f, 1.5);
        assert_eq!(c.active.bottom.as_ref().unwrap().e, 0.6);
        let c = load(&["substrate.y_top=Some(-2.0)"]).unwrap();
        assert_eq!(pillars(&c).y_top, Some(-2.0));
        let c = load(&["adhesion=None", "active.pac=None"]).unwrap();
        assert!(c.adhesion.is_none() && c.active.pac.is_none());
    }

    #[test]
    fn the_readings_of_the_paper_are_reachable_by_overrides() {
        use crate::case::AdhesionDirection;
        // Defaults: MODEL.md's readings.
        let c = load(&["adhesion.e_f=1.5"]).unwrap();
        let a = c.adhesion.as_ref().unwrap();
        assert_eq!(a.direction, AdhesionDirection::Cofactor);
        assert!(!a.jacobian_factor && !a.layer_excludes_substrate);
        assert!(!c.active.pac.as_ref().unwrap().clip_to_cell);
        // Each alone, as a sweep sets it.
        let c = load(&["adhesion.direction=Unit"]).unwrap();
        assert_eq!(c.adhesion.unwrap().direction, AdhesionDirection::Unit);
        let c = load(&["adhesion.jacobian_factor=true"]).unwrap();
        assert!(c.adhesion.unwrap().jacobian_factor);
        let c = load(&["adhesion.layer_excludes_substrate=true"]).unwrap();
        assert!(c.adhesion.unwrap().layer_excludes_substrate);
        // The PAC's semi-axes reading: three fields, or the whole region in one override.
        let c = load(&[
            "active.pac.inner_semi_axes=(10.0, 9.0)",
            "active.pac.outer_semi_axes=(15.0, 14.0)",
            "active.pac.clip_to_cell=true",
        ])
        .unwrap();
        let pac = c.active.pac.unwrap();
        assert_eq!(
            (pac.inner_semi_axes, pac.outer_semi_axes),
            ((10.0, 9.0), (15.0, 14.0))
        );
        assert!(pac.clip_to_cell);
        let c = load(&[
            "active.pac=(inner_semi_axes: (10.0, 9.0), outer_semi_axes: (15.0, 14.0), \
             clip_to_cell: true)",
        ])
        .unwrap();
        assert!(c.active.pac.unwrap().clip_to_cell);
        // Without clip_to_cell those axes leave the cell: refused, pointing at the switch.
        let e = refusal(&[
            "active.pac.inner_semi_axes=(10.0, 9.0)",
            "active.pac.outer_semi_axes=(15.0, 14.0)",
        ]);
        assert!(
            e.contains("outer_semi_axes") && e.contains("clip_to_cell"),
            "{e}"
        );
        // A misspelt reading lists the valid ones.
        let e = refusal(&["adhesion.direction=Normal"]);
        assert!(e.contains("Cofactor") && e.contains("Unit"), "{e}");
    }

    #[test]
    fn override_replaces_whole_enums_and_indexes_tuples() {
        let c = load(&["inertia.mode=On", "substrate=Flat(y_s: -3.0)"]).unwrap();
        assert_eq!(c.inertia.mode, crate::case::InertiaMode::On);
        assert!(matches!(c.substrate, Substrate::Flat(ref f) if f.y_s == -3.0));
        let c = load(&["active.pac.inner_semi_axes=(5.0, 4.0)"]).unwrap();
        assert_eq!(c.active.pac.as_ref().unwrap().inner_semi_axes, (5.0, 4.0));
        let c = load(&[
            "active.pac.inner_semi_axes=(5.0, 4.0)",
            "active.pac.inner_semi_axes.1=4.25",
        ])
        .unwrap();
        assert_eq!(c.active.pac.as_ref().unwrap().inner_semi_axes, (5.0, 4.25));
        // The later of two overrides of one field wins.
        let c = load(&["substrate.width=6.0", "substrate.width=7.0"]).unwrap();
        assert_eq!(pillars(&c).width, 7.0);
    }

    #[test]
    fn a_bad_override_value_names_the_set_argument() {
        let e = load(&["substrate.spacing=abc"]).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.starts_with("--set substrate.spacing=abc: substrate.spacing: "),
            "{msg}"
        );
        assert!(matches!(e, CaseError::Override { .. }));
        let e = refusal(&["output.n_times=4.5"]);
        assert!(e.starts_with("--set output.n_times=4.5: "), "{e}");
        assert!(e.contains("expected an integer"), "{e}");
        // Out of range: the validation rule, attributed to the override.
        let e = refusal(&["materials.nucleus.nu=0.5"]);
        assert_eq!(
            e,
            "--set materials.nucleus.nu=0.5: materials.nucleus.nu = 0.5 is out of range \
             (must satisfy -1 < nu < 0.5)"
        );
    }

    #[test]
    fn errors_in_the_file_keep_their_file_positions() {
        let text = BASE.replace("phases: (t_end: 600.0)", "phases: (t_end: -1.0)");
        let e = refusal_of(&text, "base.ron", &set(&["substrate.width=6.0"]));
        let plain = Case::from_str(&text, "base.ron").unwrap_err().to_string();
        assert_eq!(e, plain);
        assert!(e.starts_with("base.ron:7:"), "{e}");
        // A syntax error in the file is the file's, whatever the overrides.
        let text = BASE.replace("spacing: 8.0,", "spacing: 8.0,,");
        let e = refusal_of(&text, "base.ron", &set(&["substrate.width=6.0"]));
        assert!(e.starts_with("base.ron:4:"), "{e}");
        // A file error after an override on an earlier, longer line.
        let text = BASE.replace("(mode: OffAfter(0.5))", "(mode: OffAfter(0.5), nope: 1)");
        let e = Case::from_str_with_overrides(
            &text,
            "base.ron",
            &set(&["name=\"a much longer name than before\"", "substrate.q=3.0"]),
        )
        .unwrap_err();
        let plain = Case::from_str(&text, "base.ron").unwrap_err();
        assert_eq!(e.position(), plain.position(), "{e}");
        assert_eq!(e.to_string(), plain.to_string());
    }

    #[test]
    fn unknown_fields_list_the_valid_names_at_their_level() {
        let e = refusal(&["substrate.widht=6.0"]);
        assert!(e.starts_with("--set substrate.widht=6.0: "), "{e}");
        assert!(
            e.contains("unknown field `widht`") && e.contains("`width`") && e.contains("`gap`"),
            "{e}"
        );
        let e = refusal(&["solvr.rtol=1e-3"]);
        assert!(
            e.contains("unknown field `solvr`") && e.contains("`solver`"),
            "{e}"
        );
        let e = refusal(&["materials.nucleus.young=1"]);
        assert!(
            e.contains("unknown field `young`") && e.contains("`e`"),
            "{e}"
        );
        // A Flat substrate has no width: its own fields are listed.
        let flat = BASE.replace(
            "Pillars(width: 8.0, spacing: 8.0, first_center: 0.0)",
            "Flat(y_s: -2.0)",
        );
        let e = refusal_of(&flat, "f.ron", &set(&["substrate.width=6.0"]));
        assert!(
            e.contains("unknown field `width`") && e.contains("`y_s`"),
            "{e}"
        );
        // Below a plain value.
        let e = refusal(&["name.first=1"]);
        assert_eq!(
            e,
            "--set name.first=1: name.first: `name` is `\"t\"` in the file, a value without \
             fields: it has no field `first`"
        );
        let e = load(&["active.pac.inner_semi_axes.2=1.0"]);
        assert!(e.is_err());
    }

    #[test]
    fn malformed_arguments_are_refused_with_a_reason() {
        for (arg, needle) in [
            ("substrate.width", "not PATH=VALUE"),
            ("=3", "path before `=` is empty"),
            ("substrate.width=", "value after `=` is empty"),
            ("substrate..width=1", "is not a field name"),
            ("substrate.width=1)", "not one RON value"),
            ("substrate.width=6 7", "not one RON value"),
            ("name=\"open", "not one RON value"),
        ] {
            let e = Override::parse(arg).unwrap_err();
            assert!(e.to_string().contains(needle), "{arg}: {e}");
        }
        let o = Override::parse(" substrate.width = Some(6.0) ").unwrap();
        assert_eq!(o.to_string(), "substrate.width=Some(6.0)");
    }

    #[test]
    fn value_at_reads_a_resolved_case() {
        let c = load(&["substrate.width=6.5"]).unwrap();
        assert_eq!(number_at(&c, "substrate.width"), Some(6.5));
        assert_eq!(
            number_at(&c, "materials.nucleus.e"),
            Some(c.materials.nucleus.e)
        );
        assert_eq!(number_at(&c, "active.pac.e"), Some(0.7));
        assert_eq!(number_at(&c, "substrate.nope"), None);
        assert_eq!(
            value_at(BASE, "inertia.mode").as_deref(),
            Some("OffAfter(0.5)")
        );
    }
}
