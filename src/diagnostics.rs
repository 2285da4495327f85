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

    /// [`SourceError::new`] with the message of `cause`, boxed: where an error that
    /// carries its cause beside it is written in a file.
    pub(crate) fn at(
        path: &Path,
        (line, column): (usize, usize),
        cause: &impl std::fmt::Display,
    ) -> Option<Box<Self>> {
        Some(Box::new(Self::new(path, line, column, cause.to_string())))
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
                // The quoted line may hold what the error is about (an escape
                // sequence, a bidi override): escaped, with the caret moved by the
                // characters the escapes add before it.
                let column = column.map(|c| {
                    let before: String = src.chars().take(c.saturating_sub(1)).collect();
                    printable(&before, false).chars().count() + 1
                });
                let src = printable(&src, false).into_owned();
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
///
/// The file is opened again by its name only to quote a line, so no link is followed
/// anywhere along that name (Linux `openat2` with `RESOLVE_NO_SYMLINKS`): a folder of
/// the path swapped for a link to an outside folder since the file was read gives no
/// quote, never a line of the outside file. (Elsewhere: by name.)
fn source_text(path: &Path) -> Option<String> {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{openat2, Mode, OFlags, ResolveFlags, CWD};
        let fd = openat2(
            CWD,
            path,
            OFlags::RDONLY | OFlags::NOFOLLOW | OFlags::NONBLOCK | OFlags::NOCTTY | OFlags::CLOEXEC,
            Mode::empty(),
            ResolveFlags::NO_SYMLINKS | ResolveFlags::NO_MAGICLINKS,
        )
        .ok()?;
        let bytes =
            crate::fsutil::read_opened(std::fs::File::from(fd), crate::fsutil::FileKind::Document)
                .ok()?;
        String::from_utf8(bytes).ok()
    }
    #[cfg(not(target_os = "linux"))]
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

/// A name an error carries: a component's, a mate's, a part's, a robot's, a key's, as
/// the user wrote it. Shown as written (`Display` and `Debug` are the text's own, so a
/// message reads the same as with a plain `String`); compared with text.
#[derive(Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Name(String);

impl Name {
    /// The name as text.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

impl fmt::Debug for Name {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&self.0, f)
    }
}

impl std::ops::Deref for Name {
    type Target = str;
    fn deref(&self) -> &str {
        &self.0
    }
}

impl AsRef<str> for Name {
    fn as_ref(&self) -> &str {
        &self.0
    }
}

impl From<String> for Name {
    fn from(s: String) -> Self {
        Name(s)
    }
}

impl From<&str> for Name {
    fn from(s: &str) -> Self {
        Name(s.to_string())
    }
}

impl From<&String> for Name {
    fn from(s: &String) -> Self {
        Name(s.clone())
    }
}

impl From<Name> for String {
    fn from(n: Name) -> Self {
        n.0
    }
}

impl PartialEq<str> for Name {
    fn eq(&self, other: &str) -> bool {
        self.0 == other
    }
}

impl PartialEq<&str> for Name {
    fn eq(&self, other: &&str) -> bool {
        self.0 == *other
    }
}

impl PartialEq<String> for Name {
    fn eq(&self, other: &String) -> bool {
        &self.0 == other
    }
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

/// `name` in Unicode NFC (borrowed when it already is): how fitup keeps and compares
/// every name, so a composed and a decomposed `café` are one name.
pub fn nfc(name: &str) -> std::borrow::Cow<'_, str> {
    use unicode_normalization::UnicodeNormalization;
    if unicode_normalization::is_nfc_quick(name.chars()) == unicode_normalization::IsNormalized::Yes
    {
        std::borrow::Cow::Borrowed(name)
    } else {
        std::borrow::Cow::Owned(name.nfc().collect())
    }
}

/// The one rule for names, whatever their source (a document's keys, URDF links and
/// joints, names given through the API): a name may not hold a control or invisible
/// character ([`hidden_char`]; `Err` is the first one), and it is kept and compared in
/// NFC ([`nfc`]).
pub fn checked_name(name: &str) -> Result<std::borrow::Cow<'_, str>, char> {
    match name.chars().find(|&c| hidden_char(c).is_some()) {
        Some(c) => Err(c),
        None => Ok(nfc(name)),
    }
}

/// Why a character may not appear in a name: a control character (C0, DEL, C1,
/// including ESC, which starts terminal escape sequences) or an invisible / format
/// character (zero-width space, joiners, bidi embeddings, overrides and isolates,
/// BOM, soft hyphen, variation selectors, tags, …) that makes two different names
/// look the same or reorders the text around it on screen. `None` for every other
/// character (letters of any script, CJK, digits, punctuation, ordinary spaces).
pub fn hidden_char(c: char) -> Option<&'static str> {
    let u = c as u32;
    let name = match u {
        0x1B => "ESCAPE",
        0x09 => "TAB",
        0x0A => "LINE FEED",
        0x0D => "CARRIAGE RETURN",
        0x00..=0x1F | 0x7F => "a control character",
        0x80..=0x9F => "a C1 control character",
        0x00AD => "SOFT HYPHEN",
        0x034F => "COMBINING GRAPHEME JOINER",
        0x061C => "ARABIC LETTER MARK",
        0x115F | 0x1160 | 0x3164 | 0xFFA0 => "a HANGUL FILLER",
        0x17B4 | 0x17B5 => "a KHMER INHERENT VOWEL",
        0x180B..=0x180F => "a MONGOLIAN FREE VARIATION SELECTOR or VOWEL SEPARATOR",
        0x200B => "ZERO WIDTH SPACE",
        0x200C => "ZERO WIDTH NON-JOINER",
        0x200D => "ZERO WIDTH JOINER",
        0x200E => "LEFT-TO-RIGHT MARK",
        0x200F => "RIGHT-TO-LEFT MARK",
        0x2028 => "LINE SEPARATOR",
        0x2029 => "PARAGRAPH SEPARATOR",
        0x202A => "LEFT-TO-RIGHT EMBEDDING",
        0x202B => "RIGHT-TO-LEFT EMBEDDING",
        0x202C => "POP DIRECTIONAL FORMATTING",
        0x202D => "LEFT-TO-RIGHT OVERRIDE",
        0x202E => "RIGHT-TO-LEFT OVERRIDE",
        0x2060 => "WORD JOINER",
        0x2066 => "LEFT-TO-RIGHT ISOLATE",
        0x2067 => "RIGHT-TO-LEFT ISOLATE",
        0x2068 => "FIRST STRONG ISOLATE",
        0x2069 => "POP DIRECTIONAL ISOLATE",
        0x2061..=0x206F => "an invisible format character",
        0xFE00..=0xFE0F | 0xE0100..=0xE01EF => "a VARIATION SELECTOR",
        0xFEFF => "ZERO WIDTH NO-BREAK SPACE (byte order mark)",
        0xFFF0..=0xFFFB => "an interlinear annotation or special character",
        0xFFFE | 0xFFFF => "a noncharacter",
        0x1D173..=0x1D17A => "a MUSICAL SYMBOL format character",
        0xE0000..=0xE007F => "a TAG character",
        _ => return None,
    };
    Some(name)
}

/// `U+XXXX (NAME)` for a message about a refused character.
pub fn describe_char(c: char) -> String {
    match hidden_char(c) {
        Some(name) => format!("U+{:04X} ({name})", c as u32),
        None => format!("U+{:04X}", c as u32),
    }
}

/// `text` safe to print on a terminal: every character [`hidden_char`] refuses in
/// names (control characters such as ESC, bidi overrides, zero-width characters) is
/// written as `<U+XXXX>`, except newline and tab when `keep_lines`. The one
/// escaping rule of every printer of user strings (the CLI writer, error snippets),
/// so a name, a path or a script's message can neither move the cursor, recolour
/// the terminal nor reorder what follows it. Borrows when nothing needs escaping.
pub fn printable(text: &str, keep_lines: bool) -> std::borrow::Cow<'_, str> {
    let escape = |c: char| hidden_char(c).is_some() && !(keep_lines && matches!(c, '\n' | '\t'));
    if !text.chars().any(escape) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        if escape(c) {
            out.push_str(&format!("<U+{:04X}>", c as u32));
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// A connection URL as fitup shows it: the password of `user:password@` is dropped
/// and the value of every `password=` (or other `…pass…=`) parameter becomes `***`.
/// `postgres://u:secret@h:5/d?password=x&sslmode=disable` →
/// `postgres://u@h:5/d?password=***&sslmode=disable`. Every message, listing and
/// `Debug` output that names a PostgreSQL database goes through here.
pub fn redact_url(url: &str) -> String {
    let Some(scheme_end) = url.find("://").map(|s| s + 3) else {
        return url.to_string();
    };
    let (main, query) = match url[scheme_end..].find('?') {
        Some(q) => url.split_at(scheme_end + q),
        None => (url, ""),
    };
    let mut out = String::with_capacity(url.len());
    // userinfo ends at the last '@' before the path (a password may hold '@').
    let path_start = main[scheme_end..]
        .rfind('@')
        .map(|at| scheme_end + at)
        .and_then(|at| main[at..].find('/').map(|p| at + p))
        .or_else(|| main[scheme_end..].find('/').map(|p| scheme_end + p))
        .unwrap_or(main.len());
    match main[scheme_end..path_start].rfind('@') {
        Some(at) => {
            let userinfo = &main[scheme_end..scheme_end + at];
            let user = userinfo.split(':').next().unwrap_or("");
            out.push_str(&main[..scheme_end]);
            out.push_str(user);
            out.push_str(&main[scheme_end + at..]);
        }
        None => out.push_str(main),
    }
    if let Some(params) = query.strip_prefix('?') {
        out.push('?');
        let shown: Vec<String> = params
            .split('&')
            .map(|kv| match kv.split_once('=') {
                Some((k, _)) if k.to_ascii_lowercase().contains("pass") => format!("{k}=***"),
                _ => kv.to_string(),
            })
            .collect();
        out.push_str(&shown.join("&"));
    }
    out
}

/// `text` with the credentials of every `postgres://` or `postgresql://` URL in it
/// removed ([`redact_url`]): the one guard on everything fitup prints, so a password
/// never reaches the terminal even where the text quotes a user's own line (a script
/// line with `open_db("postgres://u:secret@…")` shown under its error).
pub fn redact_credentials(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.contains("postgres") {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = ["postgres://", "postgresql://"]
        .iter()
        .filter_map(|s| rest.find(s))
        .min()
    {
        out.push_str(&rest[..at]);
        let url_len = rest[at..]
            .find(|c: char| {
                c.is_whitespace() || matches!(c, '"' | '\'' | '`' | ')' | '>' | ',' | ';')
            })
            .unwrap_or(rest.len() - at);
        out.push_str(&redact_url(&rest[at..at + url_len]));
        rest = &rest[at + url_len..];
    }
    out.push_str(rest);
    std::borrow::Cow::Owned(out)
}

/// Where the block comment that opens at `b[start]` (`/*`) ends: the index just past
/// its `*/`, comments nesting (`/* a /* b */ c */`, as in PostgreSQL and Rhai), or
/// `b.len()` when it is not closed.
// Its callers are the Rhai assignment scan and the PostgreSQL statement check.
#[cfg_attr(not(any(feature = "script", feature = "postgres")), allow(dead_code))]
pub(crate) fn nested_comment_end(b: &[u8], start: usize) -> usize {
    let (mut i, mut depth) = (start, 0usize);
    while i < b.len() {
        if b[i..].starts_with(b"/*") {
            depth += 1;
            i += 2;
        } else if b[i..].starts_with(b"*/") {
            depth -= 1;
            i += 2;
            if depth == 0 {
                break;
            }
        } else {
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_name_reads_as_its_text() {
        let n = Name::from("plate-1");
        assert_eq!(n.to_string(), "plate-1");
        assert_eq!(format!("{n:?}"), format!("{:?}", "plate-1"));
        assert_eq!(format!("`{n:>9}`"), "`  plate-1`");
        assert_eq!(n, "plate-1");
        assert_ne!(n, "plate-2");
        assert_eq!(String::from(n.clone()), "plate-1");
        assert!(n.starts_with("plate"));
    }

    #[test]
    fn nested_comments_end_after_their_last_close() {
        let end = |t: &str| nested_comment_end(t.as_bytes(), 0);
        assert_eq!(end("/* a */ b"), 7);
        assert_eq!(end("/* a /* b */ c */ d"), 17);
        assert_eq!(end("/* open /* */"), 13);
        assert_eq!(end("/*/ x */"), 8);
        assert_eq!(nested_comment_end(b"x /* y */", 2), 9);
    }

    #[test]
    fn printed_text_never_carries_a_database_password() {
        let line =
            r#"3 | let db = open_db("postgres://u:s3cret@h:5/d?password=x2&sslmode=disable");"#;
        let shown = redact_credentials(line);
        assert!(
            !shown.contains("s3cret") && !shown.contains("x2"),
            "{shown}"
        );
        assert!(
            shown.contains(r#"open_db("postgres://u@h:5/d?password=***&sslmode=disable");"#),
            "{shown}"
        );
        assert_eq!(redact_credentials("no url here"), "no url here");
        let two = redact_credentials("a postgresql://a:b@h/d and postgres://c:d@h/e");
        assert_eq!(two, "a postgresql://a@h/d and postgres://c@h/e");
    }

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
    fn printable_escapes_controls_and_invisible_characters_only() {
        assert!(matches!(
            printable("角度1 plate_a", false),
            std::borrow::Cow::Borrowed(_)
        ));
        assert_eq!(printable("a\u{1b}[31mb", false), "a<U+001B>[31mb");
        assert_eq!(printable("x\u{202e}y\u{200b}", false), "x<U+202E>y<U+200B>");
        assert_eq!(printable("l1\n\tl2\u{7}", true), "l1\n\tl2<U+0007>");
        assert_eq!(printable("l1\n", false), "l1<U+000A>");
        assert_eq!(hidden_char('é'), None);
        assert_eq!(
            hidden_char('\u{feff}'),
            Some("ZERO WIDTH NO-BREAK SPACE (byte order mark)")
        );
        assert_eq!(describe_char('\u{2066}'), "U+2066 (LEFT-TO-RIGHT ISOLATE)");
    }

    #[test]
    fn render_escapes_the_quoted_line_and_keeps_the_caret() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.yaml");
        std::fs::write(&p, "- name: \u{1b}[2Jab\u{202e}X\n").unwrap();
        // column of the X: `- name: ` is 8, then ESC [ 2 J a b RLO, X at 16
        let r = SourceError::new(&p, 1, 16, "bad").render();
        assert!(!r.contains('\u{1b}') && !r.contains('\u{202e}'), "{r:?}");
        let shown = r.lines().nth(2).unwrap();
        let caret = r.lines().nth(3).unwrap();
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
