//! The pre-flight check of a document's YAML text, before it is deserialized: one
//! pass over the parser's events, in time and memory linear in the text.
//!
//! [`from_yaml`] is the one entry point for every YAML file fitup reads (documents,
//! task templates): the same pre-scan and budget for all, then serde, with errors
//! located in the file and quoting at most [`MAX_QUOTE`] characters of a value.
//!
//! It refuses what the deserializer would accept silently or expand without bound —
//! anchors and aliases (an "alias bomb" of a few hundred KB expands to gigabytes),
//! duplicate keys anywhere (the last one would win), numbers that are not finite or
//! beyond [`MAX_ABS_VALUE`], nesting deeper than [`MAX_DEPTH`], an empty file — each
//! with its line and column. It also records where every key's value starts, so later
//! errors (a bad mesh path, a bad pose) can point at their own line.
//!
//! Names are compared as Unicode NFC (two spellings of `é`, composed and decomposed,
//! are one key, so a duplicate), and no key or value may hold a control or invisible
//! character ([`crate::diagnostics::hidden_char`]: ESC, zero-width characters, bidi
//! overrides and isolates, BOM, …; only `description` may hold newlines and tabs):
//! the error names the character as `U+XXXX` at its own line and column.

use crate::diagnostics::{describe_char, hidden_char};
use std::collections::HashMap;
use unicode_normalization::UnicodeNormalization;
use yaml_rust2::parser::{Event, Parser};
use yaml_rust2::scanner::TScalarStyle;

pub use crate::math::MAX_ABS_VALUE;

/// The deepest nesting of mappings and sequences a document may have.
pub const MAX_DEPTH: usize = 64;

/// A problem found by [`scan`], at a 1-based line and column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanIssue {
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

/// Where each value of the document starts: by key path such as `parts/screw/stl` or
/// `components/2/transform` (sequence items by 0-based index).
#[derive(Debug, Clone, Default)]
pub struct Positions(HashMap<String, (usize, usize)>);

impl Positions {
    /// Records where the value at `path` (with or without its leading `/`) starts.
    fn record(&mut self, mut path: String, at: (usize, usize)) {
        if path.starts_with('/') {
            path.remove(0);
        }
        self.0.insert(path, at);
    }

    /// The 1-based line and column of the value at `path`.
    pub fn get(&self, path: &str) -> Option<(usize, usize)> {
        self.0.get(path).copied()
    }
}

/// Keys whose values are text even when they look like numbers.
const TEXT_KEYS: &[&str] = &[
    "name",
    "part",
    "stl",
    "step",
    "description",
    "units",
    "type",
    "about",
    "flange",
    "tip",
    "parent",
    "joint",
    "dimension",
    "catalog",
    "convention",
    "component",
    "entities",
    "color",
    "equations",
];

enum Frame {
    Map {
        path: String,
        /// Keys seen, in NFC: the line and the spelling of the first.
        keys: HashMap<String, (usize, String)>,
        key: Option<String>,
    },
    Seq {
        path: String,
        next: usize,
    },
}

/// Why a plain scalar that YAML reads as a number is refused.
#[derive(Debug, thiserror::Error)]
enum BadNumber {
    /// `.inf`, `.nan` and their signed forms.
    #[error("`{text}` is not a finite number")]
    NotFinite {
        /// The scalar as written.
        text: String,
    },
    /// Past [`MAX_ABS_VALUE`] (or an overflow to infinity).
    #[error("number out of range: `{text}` (fitup accepts magnitudes up to {max:e}: mm, degrees)", max = MAX_ABS_VALUE)]
    OutOfRange {
        /// The scalar as written.
        text: String,
    },
}

/// A plain scalar that YAML reads as a number: its value, or why it is refused.
fn plain_number(s: &str) -> Option<Result<f64, BadNumber>> {
    let lower = s.to_ascii_lowercase();
    if matches!(lower.as_str(), ".inf" | "+.inf" | "-.inf" | ".nan") {
        return Some(Err(BadNumber::NotFinite {
            text: s.to_string(),
        }));
    }
    let numeric = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_digit() || matches!(c, '+' | '-' | '.' | 'e' | 'E' | '_'))
        && s.chars().any(|c| c.is_ascii_digit());
    if !numeric {
        return None;
    }
    let v: f64 = s.replace('_', "").parse().ok()?;
    if !v.is_finite() || v.abs() > MAX_ABS_VALUE {
        return Some(Err(BadNumber::OutOfRange {
            text: s.to_string(),
        }));
    }
    Some(Ok(v))
}

/// The longest excerpt of a user's value quoted in an error (characters; longer
/// values are cut with `…`).
pub const MAX_QUOTE: usize = 80;

/// The message for an empty document file.
pub const DOCUMENT_EMPTY: &str =
    "the document is empty: a fitup document is a YAML mapping with `parts:` and `components:`";

/// Reads a fitup YAML file's text into `T`: [`scan`]'s checks first (aliases, anchors,
/// duplicate keys, number ranges, nesting, an empty file: `empty` is the message for
/// that), then the schema. Errors are located in `path` (line and column); serde's
/// message is prefixed with `what` (`invalid document`, `invalid template`) and
/// quotes of the text are cut to [`MAX_QUOTE`] characters.
///
/// # Errors
/// The first problem found, as a located [`SourceError`].
pub fn from_yaml<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &std::path::Path,
    what: &str,
    empty: &str,
) -> Result<(T, Positions), crate::diagnostics::SourceError> {
    use crate::diagnostics::SourceError;
    let positions = scan_with(text, what, empty)
        .map_err(|i| SourceError::new(path, i.line, i.column, i.message))?;
    let value: T = serde_yaml::from_str(text).map_err(|e| {
        let (line, col) = e
            .location()
            .map(|l| (l.line(), l.column()))
            .unwrap_or((0, 0));
        SourceError::new(
            path,
            line,
            col,
            format!("{what}: {}", quote_cut(&e.to_string())),
        )
    })?;
    Ok((value, positions))
}

/// A serde message with every quoted value (between backticks or double quotes) cut
/// to [`MAX_QUOTE`] characters, and the whole to a few lines' worth.
fn quote_cut(message: &str) -> String {
    let mut out = String::new();
    let mut rest = message;
    while let Some(open) = rest.find(['`', '"']) {
        let q = &rest[open..open + 1];
        out += &rest[..=open];
        rest = &rest[open + 1..];
        let close = rest.find(q).unwrap_or(rest.len());
        out += &crate::diagnostics::shorten(&rest[..close], MAX_QUOTE);
        rest = &rest[close..];
        if let Some(r) = rest.strip_prefix(q) {
            out += q;
            rest = r;
        }
    }
    out += rest;
    crate::diagnostics::shorten(&out, 4 * MAX_QUOTE)
}

/// Checks the YAML text of a document; see the module documentation.
pub fn scan(text: &str) -> Result<Positions, ScanIssue> {
    scan_with(text, "invalid document", DOCUMENT_EMPTY)
}

/// [`scan`] with `what` naming the kind of file in syntax errors and `empty` as the
/// message for a file without content.
fn scan_with(text: &str, what: &str, empty: &str) -> Result<Positions, ScanIssue> {
    let mut parser = Parser::new_from_str(text);
    let mut stack: Vec<Frame> = Vec::new();
    let mut positions = Positions::default();
    let mut content = false;
    let mut documents = 0;
    loop {
        let (event, mark) = parser.next_token().map_err(|e| ScanIssue {
            line: e.marker().line(),
            column: e.marker().col() + 1,
            message: format!("{what}: YAML syntax: {}", e.info()),
        })?;
        let (line, column) = (mark.line(), mark.col() + 1);
        let issue = |message: String| ScanIssue {
            line,
            column,
            message,
        };
        no_alias_or_anchor(&event, text, mark.index(), (line, column))?;
        match event {
            Event::StreamEnd => break,
            Event::DocumentStart => {
                documents += 1;
                if documents > 1 {
                    return Err(issue(
                        "a second YAML document (`---`): a fitup document file holds one".into(),
                    ));
                }
            }
            Event::Scalar(value, style, _, _) => {
                let at = (line, column, mark.index());
                if stack.is_empty() {
                    // A bare scalar at the top: empty (`~`, nothing) or not a mapping.
                    check_characters(&value, false, text, at)?;
                    if !(value.is_empty() || value == "~" || value == "null") {
                        content = true;
                    }
                    continue;
                }
                scalar(&mut stack, &mut positions, value, style, text, at)?;
            }
            Event::MappingStart(..) | Event::SequenceStart(..) => {
                content = true;
                if stack.len() >= MAX_DEPTH {
                    return Err(issue(format!("nesting deeper than {MAX_DEPTH} levels")));
                }
                let path = match stack.last_mut() {
                    None => String::new(),
                    Some(Frame::Map { key: None, .. }) => {
                        return Err(issue(
                            "a mapping or list used as a key: keys must be plain text".into(),
                        ))
                    }
                    Some(Frame::Map { path, key, .. }) => {
                        format!("{path}/{}", key.as_deref().unwrap_or_default())
                    }
                    Some(Frame::Seq { path, next }) => {
                        *next += 1;
                        format!("{path}/{}", *next - 1)
                    }
                };
                positions.record(path.clone(), (line, column));
                stack.push(if matches!(event, Event::MappingStart(..)) {
                    Frame::Map {
                        path,
                        keys: HashMap::new(),
                        key: None,
                    }
                } else {
                    Frame::Seq { path, next: 0 }
                });
            }
            Event::MappingEnd | Event::SequenceEnd => {
                stack.pop();
                if let Some(Frame::Map { key, .. }) = stack.last_mut() {
                    *key = None;
                }
            }
            _ => {}
        }
    }
    if !content {
        return Err(ScanIssue {
            line: 1,
            column: 1,
            message: empty.into(),
        });
    }
    Ok(positions)
}

/// Refuses YAML aliases and anchors (they expand without bound): `index` is the
/// event's byte offset, `at` its line and column.
fn no_alias_or_anchor(
    event: &Event,
    text: &str,
    index: usize,
    at: (usize, usize),
) -> Result<(), ScanIssue> {
    let anchor = match event {
        Event::Alias(_) => return Err(ScanIssue {
            line: at.0,
            column: at.1,
            message:
                "YAML aliases (`*name`) are not allowed in fitup YAML files: write the value out"
                    .into(),
        }),
        Event::Scalar(_, _, a, _) | Event::MappingStart(a, _) | Event::SequenceStart(a, _) => *a,
        _ => 0,
    };
    if anchor > 0 {
        // The parser marks the node, which may start on a later line than its
        // `&name`: point at the `&`.
        let (line, column) = anchor_position(text, index).unwrap_or(at);
        return Err(ScanIssue {
            line,
            column,
            message:
                "YAML anchors (`&name`) are not allowed in fitup YAML files: write the value out"
                    .into(),
        });
    }
    Ok(())
}

/// Refuses a scalar holding a control or invisible character (a `description`'s
/// text may hold line breaks and tabs). `at`: line, column and byte offset.
fn check_characters(
    value: &str,
    in_description: bool,
    text: &str,
    at: (usize, usize, usize),
) -> Result<(), ScanIssue> {
    let (line, column, index) = at;
    if let Some(c) = value
        .chars()
        .find(|&c| hidden_char(c).is_some() && !(in_description && matches!(c, '\n' | '\t' | '\r')))
    {
        let (line, column) = char_position(text, index, c, value.len()).unwrap_or((line, column));
        return Err(ScanIssue {
            line,
            column,
            message: format!(
                "{} in `{}`: control and invisible characters are not allowed in a fitup document's names and text (they hide or reorder what is shown); remove it",
                describe_char(c),
                short(value)
            ),
        });
    }
    Ok(())
}

/// A scalar inside a mapping or list (`stack` not empty): a key (unique in NFC) or a
/// value (a plain number in range), its position recorded. `at`: line, column and
/// byte offset.
fn scalar(
    stack: &mut [Frame],
    positions: &mut Positions,
    value: String,
    style: TScalarStyle,
    text: &str,
    at: (usize, usize, usize),
) -> Result<(), ScanIssue> {
    let (line, column, _) = at;
    let issue = |message: String| ScanIssue {
        line,
        column,
        message,
    };
    let in_description = matches!(
        stack.last(),
        Some(Frame::Map { key: Some(k), .. }) if k == "description"
    );
    check_characters(&value, in_description, text, at)?;
    let Some(top) = stack.last_mut() else {
        return Ok(());
    };
    match top {
        Frame::Map { path, keys, key } if key.is_none() => {
            // Names are NFC: `é` composed and decomposed is one key.
            let raw = value;
            let value = nfc(&raw);
            if let Some((first, spelling)) = keys.get(&value) {
                let same = if *spelling == raw {
                    ""
                } else {
                    " — the same name in another Unicode spelling (names are compared in NFC)"
                };
                return Err(issue(format!(
                    "duplicate key `{value}` (first at line {first}){same}: each key may appear once"
                )));
            }
            keys.insert(value.clone(), (line, raw));
            positions.record(format!("{path}/{value}"), (line, column));
            *key = Some(value);
        }
        Frame::Map { path, key, .. } => {
            let k = key.take().unwrap_or_default();
            if style == TScalarStyle::Plain && !TEXT_KEYS.contains(&k.as_str()) {
                if let Some(Err(m)) = plain_number(&value) {
                    return Err(issue(format!("`{}`: {m}", &path_key(path, &k))));
                }
            }
            positions.record(format!("{path}/{k}"), (line, column));
        }
        Frame::Seq { path, next } => {
            let p = format!("{path}/{next}");
            *next += 1;
            let text_list = path
                .rsplit('/')
                .next()
                .is_some_and(|k| TEXT_KEYS.contains(&k));
            if style == TScalarStyle::Plain && !text_list {
                if let Some(Err(m)) = plain_number(&value) {
                    return Err(issue(format!("`{}`: {m}", p.trim_start_matches('/'))));
                }
            }
            positions.record(p, (line, column));
        }
    }
    Ok(())
}

/// The start of `value`, escaped, for a message (the value may be megabytes).
fn short(value: &str) -> String {
    let mut out: String = value.chars().take(60).collect();
    if out.len() < value.len() {
        out.push('…');
    }
    crate::diagnostics::printable(&out, false).into_owned()
}

/// `name` in Unicode NFC, the form fitup keeps and compares names in.
pub fn nfc(name: &str) -> String {
    if unicode_normalization::is_nfc(name) {
        name.to_string()
    } else {
        name.nfc().collect()
    }
}

/// The 1-based line and column of the first `c` in `text` at or after character
/// `from` and within the `span` characters a scalar of `span` bytes can take in the
/// text (quotes and escapes included); `None` when it is not there (written as an
/// escape such as `"\e"`).
fn char_position(text: &str, from: usize, c: char, span: usize) -> Option<(usize, usize)> {
    let limit = from + 8 * span + 16;
    let (mut line, mut column) = (1, 1);
    for (i, ch) in text.chars().enumerate() {
        if i > limit {
            return None;
        }
        if i >= from && ch == c {
            return Some((line, column));
        }
        if ch == '\n' {
            line += 1;
            column = 1;
        } else {
            column += 1;
        }
    }
    None
}

/// The line and column of the last `&` before character `index` of `text`.
fn anchor_position(text: &str, index: usize) -> Option<(usize, usize)> {
    let before: Vec<char> = text.chars().take(index + 1).collect();
    let at = before.iter().rposition(|&c| c == '&')?;
    let line = before[..at].iter().filter(|&&c| c == '\n').count() + 1;
    let column = at
        - before[..at]
            .iter()
            .rposition(|&c| c == '\n')
            .map_or(0, |i| i + 1)
        + 1;
    Some((line, column))
}

fn path_key(path: &str, key: &str) -> String {
    format!("{path}/{key}").trim_start_matches('/').to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn issue(text: &str) -> ScanIssue {
        scan(text).unwrap_err()
    }

    #[test]
    fn refuses_aliases_duplicates_and_out_of_range_numbers_with_lines() {
        let e = issue(
            "parts:\n  a:\n    stl: a.stl\n    points:\n      p: &p [1, 2, 3]\n      q: *p\n",
        );
        assert_eq!(e.line, 5, "{e:?}");
        assert!(e.message.contains("anchors"), "{e:?}");
        let e = issue("parts:\n  a:\n    stl: a.stl\n  a:\n    stl: b.stl\ncomponents: []\n");
        assert_eq!(e.line, 4);
        assert!(
            e.message.contains("duplicate key `a` (first at line 2)"),
            "{e:?}"
        );
        let e = issue("components:\n  - name: x\n    transform: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [1e400, 0, 0, 1]]\n");
        assert_eq!(e.line, 3);
        assert!(e.message.contains("number out of range"), "{e:?}");
        let e = issue("mates:\n  - name: m\n    value: .nan\n");
        assert!(e.message.contains("not a finite number"), "{e:?}");
        assert!(issue("").message.contains("empty"));
        assert!(issue("# only a comment\n").message.contains("empty"));
        assert!(issue("a: [").message.contains("YAML syntax"));
        // Text fields may look like numbers.
        let p = scan("parts:\n  '1':\n    stl: 1e400\ncomponents:\n  - name: 12345678901234\n")
            .unwrap();
        assert_eq!(p.get("parts/1/stl"), Some((3, 10)));
        assert_eq!(p.get("components/0/name"), Some((5, 11)));
    }

    #[test]
    fn deep_nesting_is_refused() {
        let text = format!("{}{}", "[".repeat(200), "]".repeat(200));
        assert!(issue(&text).message.contains("nesting"));
    }
}
