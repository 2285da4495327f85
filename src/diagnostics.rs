//! Error reports with source snippets: one renderer for documents, scripts, programs
//! and CSV files, so every message names file, line and column the same way.

use std::fmt;
use std::path::{Path, PathBuf};

/// An error located in a user's text file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SourceError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// 1-based column, when known.
    pub column: Option<usize>,
    /// What is wrong.
    pub message: String,
    /// How to fix it, when we can tell.
    pub help: Option<String>,
}

impl SourceError {
    /// An error in `path` at `line:column` (1-based; 0 = unknown).
    pub fn new(path: &Path, line: usize, column: usize, message: impl Into<String>) -> Self {
        Self {
            path: path.to_path_buf(),
            line: (line > 0).then_some(line),
            column: (column > 0).then_some(column),
            message: message.into(),
            help: None,
        }
    }

    /// Adds a hint.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// `file:line:col: message` followed by the source line and a caret, and the hint.
    /// Reads the file again to show the line; falls back to the one-line form.
    pub fn render(&self) -> String {
        let mut out = self.to_string();
        if let Some((line, text)) = self.line.and_then(|l| Some((l, source_text(&self.path)?))) {
            if let Some(full) = text.lines().nth(line - 1) {
                let (src, column) = excerpt(full, self.column);
                let src = src.as_str();
                let gutter = line.to_string();
                out += &format!("\n {} |\n {} | {}\n", " ".repeat(gutter.len()), gutter, src);
                if let Some(col) = column {
                    let pad: String = src
                        .chars()
                        .take(col.saturating_sub(1))
                        .map(|c| if c == '\t' { '\t' } else { ' ' })
                        .collect();
                    out += &format!(" {} | {}^", " ".repeat(gutter.len()), pad);
                } else {
                    out.pop();
                }
            }
        }
        if let Some(h) = &self.help {
            out += &format!("\n help: {h}");
        }
        out
    }
}

impl fmt::Display for SourceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        write!(f, ": {}", self.message)
    }
}

/// The text of a file to quote from: a regular file of at most 16 MiB only (the error
/// may be about a FIFO, a device or a huge file, which must not be read again).
fn source_text(path: &Path) -> Option<String> {
    crate::fsutil::read_text(path, crate::fsutil::FileKind::Document).ok()
}

/// Characters of a source line shown around the error column; a longer line (a
/// generated or minified file) is cut to a window with `…` on the cut sides.
const MAX_SHOWN_LINE: usize = 120;

/// The part of `line` to show and the column within it.
fn excerpt(line: &str, column: Option<usize>) -> (String, Option<usize>) {
    let n = line.chars().count();
    if n <= MAX_SHOWN_LINE {
        return (line.to_string(), column);
    }
    let col = column.unwrap_or(1).clamp(1, n);
    let start = col
        .saturating_sub(MAX_SHOWN_LINE / 2)
        .min(n - MAX_SHOWN_LINE);
    let end = start + MAX_SHOWN_LINE;
    let mut shown: String = line.chars().skip(start).take(MAX_SHOWN_LINE).collect();
    let mut col_in = column.map(|c| c.saturating_sub(start));
    if start > 0 {
        shown.insert(0, '…');
        col_in = col_in.map(|c| c + 1);
    }
    if end < n {
        shown.push('…');
    }
    (shown, col_in)
}

/// `text` cut to at most `max` characters, with `…` where it was cut: for quoting a
/// user's value (which may be megabytes long) in an error message.
pub fn shorten(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        None => text.to_string(),
        Some((byte, _)) => format!("{}…", &text[..byte]),
    }
}

/// The 1-based line and column of the first occurrence of `needle` in `text` at or
/// after line `from_line`, for errors found after parsing (an unknown part name, a
/// duplicate component) that serde could not locate.
pub fn locate(text: &str, needle: &str, from_line: usize) -> Option<(usize, usize)> {
    text.lines()
        .enumerate()
        .skip(from_line.saturating_sub(1))
        .find_map(|(i, l)| {
            l.find(needle)
                .map(|byte| (i + 1, l[..byte].chars().count() + 1))
        })
}

/// Close matches for `name` among `candidates`, best first (for "did you mean").
pub fn close_matches<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let mut scored: Vec<(f64, &str)> = candidates
        .into_iter()
        .map(|c| {
            (
                strsim::jaro_winkler(&name.to_lowercase(), &c.to_lowercase()),
                c,
            )
        })
        .filter(|(s, _)| *s > 0.7)
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    scored
        .into_iter()
        .take(3)
        .map(|(_, c)| c.to_string())
        .collect()
}

/// "did you mean `a`, `b`?" or a list of what exists, for a missing name.
pub fn suggestion<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str> + Clone) -> String {
    let close = close_matches(name, candidates.clone());
    if !close.is_empty() {
        let list: Vec<String> = close.iter().map(|c| format!("`{c}`")).collect();
        return format!("did you mean {}?", list.join(", "));
    }
    let all: Vec<&str> = candidates.into_iter().collect();
    if all.is_empty() {
        "there are none".into()
    } else if all.len() <= 12 {
        format!(
            "known: {}",
            all.iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    } else {
        format!("{} known, e.g. `{}`", all.len(), all[0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_and_suggest() {
        let text = "a: 1\nparts:\n  角度1: x\n";
        assert_eq!(locate(text, "角度1", 1), Some((3, 3)));
        assert_eq!(locate(text, "角度1", 4), None);
        assert!(suggestion("plate_a", ["plate_a1", "table"]).contains("plate_a1"));
        assert!(suggestion("zzz", ["table"]).contains("known"));
    }

    #[test]
    fn long_lines_are_cut_around_the_column() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("long.rhai");
        let line = format!("{}X{}", "(".repeat(5000), ")".repeat(5000));
        std::fs::write(&p, &line).unwrap();
        let r = SourceError::new(&p, 1, 5001, "deep").render();
        assert!(r.len() < 600, "{r}");
        let shown = r.lines().nth(2).unwrap();
        let caret = r.lines().nth(3).unwrap();
        assert!(shown.contains('…') && shown.contains('X'), "{r}");
        // The caret still points at the X.
        let x = shown.chars().position(|c| c == 'X').unwrap();
        assert_eq!(caret.chars().position(|c| c == '^'), Some(x), "{r}");
    }

    #[test]
    fn render_shows_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.yaml");
        std::fs::write(&p, "one\ntwo three\n").unwrap();
        let r = SourceError::new(&p, 2, 5, "bad").with_help("fix").render();
        assert!(
            r.contains(":2:5: bad")
                && r.contains("two three")
                && r.contains("    ^")
                && r.contains("help: fix"),
            "{r}"
        );
    }
}
