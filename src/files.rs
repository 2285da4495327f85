//! Data files a script reads and writes inside the project: CSV tables, JSON and
//! plain text (a macro's spreadsheets, lookup tables, reports).
//!
//! Reading goes through the project's path rule ([`Project::resolve`]: nothing
//! outside the project folder, regular files only) and the table cap
//! ([`FileKind::Table`], 64 MiB); the text must be UTF-8 (a byte order mark is
//! skipped). Every parse error names the file, the line and the cause. Writing is
//! the caller's: text goes through the output rule (`project::check_output`, the
//! project's output registry), see [`csv_text`] for the CSV spelling.
//!
//! # Examples
//!
//! ```
//! use fitup::files::{parse_csv, Cell, CsvOptions};
//!
//! let table = parse_csv("name,x,y\nbolt-1,10,2.5\n\"a, b\",-3,\n", &CsvOptions::default())?;
//! assert_eq!(table.columns, ["name", "x", "y"]);
//! assert_eq!(table.rows[0], [Cell::Text("bolt-1".into()), Cell::Int(10), Cell::Float(2.5)]);
//! assert_eq!(table.rows[1][0], Cell::Text("a, b".into()));
//! assert_eq!(table.rows[1][2], Cell::Empty);
//! # Ok::<(), fitup::files::DataError>(())
//! ```

use crate::fsutil::{FileKind, ReadError};
use crate::project::Project;
use std::path::{Path, PathBuf};

/// A data file that cannot be read, located where possible.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DataError {
    /// The path is outside the project or unusable.
    #[error("`{path}`: {cause}")]
    Path {
        /// The path as given.
        path: PathBuf,
        /// Why.
        #[source]
        cause: crate::project::PathError,
    },
    /// The file cannot be read (missing, a folder, too large, not UTF-8).
    #[error("{}: {cause}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        cause: ReadError,
    },
    /// The content is malformed at `line` (1-based; 0 when unknown).
    #[error("{}:{line}: {cause}", path.display())]
    Parse {
        /// The file (empty for text parsed from memory).
        path: PathBuf,
        /// The line, 1-based.
        line: usize,
        /// What is wrong there.
        #[source]
        cause: DataProblem,
    },
    /// A CSV delimiter that cannot separate fields (a double quote or a line break).
    #[error("`delimiter` cannot be {0:?}")]
    Delimiter(char),
}

impl DataError {
    fn at(self, file: &Path) -> Self {
        match self {
            DataError::Parse { line, cause, .. } => DataError::Parse {
                path: file.to_path_buf(),
                line,
                cause,
            },
            e => e,
        }
    }
}

/// What is wrong at a line of a CSV or JSON text (the cause of a [`DataError::Parse`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DataProblem {
    /// The table passed [`MAX_CSV_FIELDS`] at this line.
    #[error("more than {} fields: the most a table may hold (split the file)", crate::math::format::count(*.max as u64))]
    TooManyFields {
        /// The cap.
        max: usize,
    },
    /// A quoted field opened at this line is never closed.
    #[error("a quoted field is never closed (a `\"` without its closing `\"`)")]
    UnclosedQuote,
    /// Something other than the delimiter or the line end after a closing quote.
    #[error("{found:?} after a closing quote: a quoted field ends at the delimiter {delimiter:?} or the line end")]
    AfterClosingQuote {
        /// The character found.
        found: char,
        /// The table's delimiter.
        delimiter: char,
    },
    /// A double quote inside a field that does not start with one.
    #[error("a `\"` inside an unquoted field: quote the whole field and double the inner quotes")]
    QuoteInField,
    /// The header names a column twice.
    #[error("the header names column `{column}` twice")]
    DuplicateColumn {
        /// The column's name.
        column: String,
    },
    /// A row whose field count differs from the header's.
    #[error("{fields} fields, but the header has {columns} columns")]
    FieldCount {
        /// The row's fields.
        fields: usize,
        /// The header's columns.
        columns: usize,
    },
    /// JSON that does not parse, or passes [`MAX_JSON_VALUES`] values.
    #[error("column {}: {source}", .source.column())]
    Json {
        /// The parser's error (its line is the [`DataError::Parse`]'s).
        #[source]
        source: JsonError,
    },
}

/// A JSON parser's error kept shareable (a [`DataError`] is `Clone`); two compare
/// equal when their line, column and message do.
#[derive(Debug, Clone, thiserror::Error)]
#[error(transparent)]
pub struct JsonError(std::sync::Arc<serde_json::Error>);

impl JsonError {
    /// The 1-based line.
    pub fn line(&self) -> usize {
        self.0.line()
    }

    /// The 1-based column.
    pub fn column(&self) -> usize {
        self.0.column()
    }
}

impl From<serde_json::Error> for JsonError {
    fn from(e: serde_json::Error) -> Self {
        JsonError(std::sync::Arc::new(e))
    }
}

impl PartialEq for JsonError {
    fn eq(&self, other: &Self) -> bool {
        (self.0.line(), self.0.column(), self.0.to_string())
            == (other.0.line(), other.0.column(), other.0.to_string())
    }
}

/// One CSV field, typed from its text when [`CsvOptions::typed`]: whole numbers are
/// `Int`, other numbers `Float`, `true`/`false` `Bool`, an empty unquoted field
/// `Empty`, anything else (and every quoted field) `Text`.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// An empty unquoted field.
    Empty,
    /// A whole number.
    Int(i64),
    /// A number with a fraction or exponent (finite).
    Float(f64),
    /// `true` or `false`.
    Bool(bool),
    /// Text.
    Text(String),
}

impl Cell {
    /// The number in the field, if it is one.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Cell::Int(i) => Some(*i as f64),
            Cell::Float(f) => Some(*f),
            _ => None,
        }
    }

    fn from_field(text: String, quoted: bool, typed: bool) -> Cell {
        if quoted || !typed {
            return Cell::Text(text);
        }
        let t = text.trim();
        if t.is_empty() {
            return Cell::Empty;
        }
        if let Ok(i) = t.parse::<i64>() {
            return Cell::Int(i);
        }
        if t.bytes().any(|b| b.is_ascii_digit()) && !t.contains(['x', 'X']) {
            if let Ok(f) = t.parse::<f64>() {
                if f.is_finite() {
                    return Cell::Float(f);
                }
            }
        }
        match t {
            "true" => Cell::Bool(true),
            "false" => Cell::Bool(false),
            _ => Cell::Text(text),
        }
    }
}

/// How to read a CSV table (the options map of `read_csv`).
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CsvOptions {
    /// The first row names the columns (default true).
    pub header: bool,
    /// The field separator, one character (default `,`; `;` and tab are common).
    pub delimiter: char,
    /// Lines starting with this character are skipped (default none).
    pub comment: Option<char>,
    /// Type unquoted fields as numbers and booleans (default true).
    pub typed: bool,
}

impl Default for CsvOptions {
    fn default() -> Self {
        CsvOptions {
            header: true,
            delimiter: ',',
            comment: None,
            typed: true,
        }
    }
}

/// A CSV table: the column names (empty without a header) and the rows.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// The header's names, in order.
    pub columns: Vec<String>,
    /// The rows, each with the 1-based line it starts on.
    pub rows: Vec<Vec<Cell>>,
    /// The line each row starts on (1-based), for messages.
    pub lines: Vec<usize>,
}

/// The most fields a CSV table may hold (every row's, the header's included),
/// counted as they are read: a 64 MiB file of `1,2` lines is 33 million fields, which
/// took 11.5 GB as a script's rows. At the cap a table takes about 32 bytes a field
/// besides its text (≈ 130 MB, twice while the rows are typed).
pub const MAX_CSV_FIELDS: usize = 4_000_000;

/// Parses CSV text (RFC 4180: fields in double quotes may hold the delimiter, line
/// breaks and doubled quotes; `\r\n` or `\n` line ends). Empty lines are skipped.
/// With a header every row must have as many fields as the header. A table of more
/// than [`MAX_CSV_FIELDS`] fields is refused at the line that passes it, before the
/// field is kept.
pub fn parse_csv(text: &str, options: &CsvOptions) -> Result<Table, DataError> {
    let d = options.delimiter;
    if d == '"' || d == '\n' || d == '\r' {
        return Err(DataError::Delimiter(d));
    }
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let bad = |line: usize, cause: DataProblem| DataError::Parse {
        path: PathBuf::new(),
        line,
        cause,
    };
    // Rows are typed as they end (never all kept as raw fields first): the header
    // (when the options say there is one) is the first row that is not empty.
    let mut table = Table::default();
    let mut header_seen = !options.header;
    let mut chars = text.chars().peekable();
    let mut line = 1usize;
    let mut kept = 0usize;
    // One more field counted, refused past the cap at `line` before it is kept.
    let count = |kept: &mut usize, line: usize| {
        *kept += 1;
        if *kept > MAX_CSV_FIELDS {
            return Err(bad(
                line,
                DataProblem::TooManyFields {
                    max: MAX_CSV_FIELDS,
                },
            ));
        }
        Ok(())
    };
    while chars.peek().is_some() {
        let start = line;
        // a comment or empty line
        if options.comment.is_some() && chars.peek() == options.comment.as_ref() {
            for c in chars.by_ref() {
                if c == '\n' {
                    break;
                }
            }
            line += 1;
            continue;
        }
        let mut fields: Vec<(String, bool)> = Vec::new();
        let mut field = String::new();
        let mut quoted = false;
        let mut at_start = true;
        loop {
            match chars.next() {
                None => {
                    count(&mut kept, line)?;
                    fields.push((std::mem::take(&mut field), quoted));
                    break;
                }
                Some('"') if at_start => {
                    quoted = true;
                    at_start = false;
                    let opened = line;
                    loop {
                        match chars.next() {
                            None => return Err(bad(opened, DataProblem::UnclosedQuote)),
                            Some('"') if chars.peek() == Some(&'"') => {
                                chars.next();
                                field.push('"');
                            }
                            Some('"') => break,
                            Some('\n') => {
                                line += 1;
                                field.push('\n');
                            }
                            Some(c) => field.push(c),
                        }
                    }
                    // only the delimiter or the line end may follow the closing quote
                    match chars.peek() {
                        None | Some('\n') | Some('\r') => {}
                        Some(&c) if c == d => {}
                        Some(&c) => {
                            return Err(bad(
                                line,
                                DataProblem::AfterClosingQuote {
                                    found: c,
                                    delimiter: d,
                                },
                            ))
                        }
                    }
                }
                Some(c) if c == d => {
                    count(&mut kept, line)?;
                    fields.push((std::mem::take(&mut field), quoted));
                    quoted = false;
                    at_start = true;
                }
                Some('\r') if chars.peek() == Some(&'\n') => {}
                Some('\n') => {
                    count(&mut kept, line)?;
                    line += 1;
                    fields.push((std::mem::take(&mut field), quoted));
                    break;
                }
                Some(c) => {
                    if c == '"' {
                        return Err(bad(line, DataProblem::QuoteInField));
                    }
                    at_start = false;
                    field.push(c);
                }
            }
        }
        let empty = fields.len() == 1 && !fields[0].1 && fields[0].0.trim().is_empty();
        if empty {
            kept -= 1;
            continue;
        }
        if !header_seen {
            header_seen = true;
            table.columns = header_columns(fields).map_err(|cause| bad(1, cause))?;
            continue;
        }
        if options.header && fields.len() != table.columns.len() {
            return Err(bad(
                start,
                DataProblem::FieldCount {
                    fields: fields.len(),
                    columns: table.columns.len(),
                },
            ));
        }
        table.rows.push(
            fields
                .into_iter()
                .map(|(t, q)| Cell::from_field(t, q, options.typed))
                .collect(),
        );
        table.lines.push(start);
    }
    Ok(table)
}

/// A header row's column names (each field trimmed), refusing a name given twice.
fn header_columns(fields: Vec<(String, bool)>) -> Result<Vec<String>, DataProblem> {
    let columns: Vec<String> = fields
        .into_iter()
        .map(|(t, _)| t.trim().to_string())
        .collect();
    for (i, name) in columns.iter().enumerate() {
        if columns[..i].contains(name) {
            return Err(DataProblem::DuplicateColumn {
                column: name.clone(),
            });
        }
    }
    Ok(columns)
}

/// Reads a text file inside the project: the resolved path and its text.
pub fn read_text(project: &Project, path: &str) -> Result<(PathBuf, String), DataError> {
    let full = project.resolve(path).map_err(|cause| DataError::Path {
        path: path.into(),
        cause,
    })?;
    // Read through the project's held root: a folder swapped for a link after the
    // path check is refused, never followed outside.
    let text = project
        .read_file(&full, FileKind::Table)
        .and_then(|b| {
            String::from_utf8(b).map_err(|e| ReadError::NotText(e.utf8_error().valid_up_to()))
        })
        .map_err(|cause| DataError::Read {
            path: PathBuf::from(path),
            cause,
        })?;
    let text = match text.strip_prefix('\u{feff}') {
        Some(t) => t.to_string(),
        None => text,
    };
    Ok((full, text))
}

/// Reads a CSV table inside the project ([`parse_csv`]).
pub fn read_csv(
    project: &Project,
    path: &str,
    options: &CsvOptions,
) -> Result<(PathBuf, Table), DataError> {
    let (full, text) = read_text(project, path)?;
    let table = parse_csv(&text, options).map_err(|e| e.at(Path::new(path)))?;
    Ok((full, table))
}

/// The deepest nesting a JSON file may have (serde_json's own recursion limit).
pub const MAX_JSON_DEPTH: usize = 128;

/// The most values a JSON file may hold (every scalar, array and object, nested
/// ones included), counted by a first pass that keeps nothing: a 64 MiB file of
/// `[1,2]` is 33 million values, which took 2.9 GB as a script's value. At the cap the
/// parsed value takes 32 bytes a value in arrays and about 200 bytes a value in
/// objects besides its text (900,000 objects of 3 numbers, 3.6 million values, took
/// 734 MB): at most ≈ 400 MB.
pub const MAX_JSON_VALUES: usize = 2_000_000;

/// Counts the values of a JSON document without keeping any, failing past `max`.
struct CountValues<'a> {
    count: &'a std::cell::Cell<usize>,
    max: usize,
}

impl CountValues<'_> {
    fn one<E: serde::de::Error>(&self) -> Result<(), E> {
        let n = self.count.get() + 1;
        self.count.set(n);
        if n > self.max {
            return Err(E::custom(format!(
                "more than {} values: the most a JSON file may hold",
                crate::math::format::count(self.max as u64)
            )));
        }
        Ok(())
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for CountValues<'_> {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for CountValues<'_> {
    type Value = ();
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_bool<E: serde::de::Error>(self, _: bool) -> Result<(), E> {
        self.one()
    }
    fn visit_i64<E: serde::de::Error>(self, _: i64) -> Result<(), E> {
        self.one()
    }
    fn visit_u64<E: serde::de::Error>(self, _: u64) -> Result<(), E> {
        self.one()
    }
    fn visit_f64<E: serde::de::Error>(self, _: f64) -> Result<(), E> {
        self.one()
    }
    fn visit_str<E: serde::de::Error>(self, _: &str) -> Result<(), E> {
        self.one()
    }
    fn visit_unit<E: serde::de::Error>(self) -> Result<(), E> {
        self.one()
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> Result<(), A::Error> {
        self.one()?;
        let (count, max) = (self.count, self.max);
        while a.next_element_seed(CountValues { count, max })?.is_some() {}
        Ok(())
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut a: A) -> Result<(), A::Error> {
        self.one()?;
        let (count, max) = (self.count, self.max);
        while a.next_key::<serde::de::IgnoredAny>()?.is_some() {
            a.next_value_seed(CountValues { count, max })?;
        }
        Ok(())
    }
}

/// Parses JSON text; an error names the line and column. A document of more than
/// [`MAX_JSON_VALUES`] values is refused by a first pass that keeps nothing, at the
/// line and column of the value past the cap, before anything is parsed into memory.
pub fn parse_json(text: &str) -> Result<serde_json::Value, DataError> {
    use serde::de::DeserializeSeed;
    let located = |e: serde_json::Error| DataError::Parse {
        path: PathBuf::new(),
        line: e.line(),
        cause: DataProblem::Json { source: e.into() },
    };
    let count = std::cell::Cell::new(0);
    let mut d = serde_json::Deserializer::from_str(text);
    CountValues {
        count: &count,
        max: MAX_JSON_VALUES,
    }
    .deserialize(&mut d)
    .and_then(|()| d.end())
    .map_err(located)?;
    serde_json::from_str(text).map_err(located)
}

/// Reads a JSON file inside the project ([`parse_json`]).
pub fn read_json(project: &Project, path: &str) -> Result<(PathBuf, serde_json::Value), DataError> {
    let (full, text) = read_text(project, path)?;
    let v = parse_json(&text).map_err(|e| e.at(Path::new(path)))?;
    Ok((full, v))
}

/// One field as CSV text: quoted when it holds the delimiter, a quote, a line break
/// or leading/trailing spaces (inner quotes doubled).
pub fn csv_field(text: &str, delimiter: char) -> String {
    let needs =
        text.contains([delimiter, '"', '\n', '\r']) || text.starts_with(' ') || text.ends_with(' ');
    if needs {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// Rows of fields as CSV text (`\n` line ends), each field through [`csv_field`].
pub fn csv_text<R: AsRef<[String]>>(rows: &[R], delimiter: char) -> String {
    let mut out = String::new();
    for r in rows {
        let line: Vec<String> = r.as_ref().iter().map(|f| csv_field(f, delimiter)).collect();
        out.push_str(&line.join(&delimiter.to_string()));
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_typing_and_line_ends() {
        let t = parse_csv(
            "a;b;c\r\n1;\"x;y\";true\r\n\r\n\"multi\nline\";-2e3;\" 7\"\n",
            &CsvOptions {
                delimiter: ';',
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(t.columns, ["a", "b", "c"]);
        assert_eq!(
            t.rows[0],
            [Cell::Int(1), Cell::Text("x;y".into()), Cell::Bool(true)]
        );
        assert_eq!(
            t.rows[1],
            [
                Cell::Text("multi\nline".into()),
                Cell::Float(-2000.0),
                Cell::Text(" 7".into())
            ]
        );
        assert_eq!(t.lines, [2, 4]);
        // no header, ragged rows, comments
        let t = parse_csv(
            "# holes\n1,2\n3\n",
            &CsvOptions {
                header: false,
                comment: Some('#'),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(
            t.rows,
            [vec![Cell::Int(1), Cell::Int(2)], vec![Cell::Int(3)]]
        );
        // untyped keeps the text; inf, nan and hex stay text
        let t = parse_csv("x\ninf\nNaN\n0x10\n1e999\n", &CsvOptions::default()).unwrap();
        assert!(t.rows.iter().all(|r| matches!(r[0], Cell::Text(_))));
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse_csv("a,b\n1,2\n3\n", &CsvOptions::default()).unwrap_err();
        assert_eq!(e.to_string(), ":3: 1 fields, but the header has 2 columns");
        let e = parse_csv("a\n\"open\n\n", &CsvOptions::default()).unwrap_err();
        assert!(matches!(e, DataError::Parse { line: 2, .. }), "{e}");
        let e = parse_csv("a\nx\"y\n", &CsvOptions::default()).unwrap_err();
        assert!(matches!(e, DataError::Parse { line: 2, .. }), "{e}");
        let e = parse_csv("a,a\n", &CsvOptions::default()).unwrap_err();
        assert!(e.to_string().contains("twice"));
        let e = parse_json("{\n  \"a\": [1,\n}").unwrap_err();
        assert!(matches!(e, DataError::Parse { line: 3, .. }), "{e}");
    }

    #[test]
    fn written_csv_reads_back() {
        let rows = vec![
            vec!["name".to_string(), "note".to_string()],
            vec!["a,b".to_string(), "say \"hi\"\nbye".to_string()],
        ];
        let text = csv_text(&rows, ',');
        let t = parse_csv(&text, &CsvOptions::default()).unwrap();
        assert_eq!(
            t.rows[0],
            [
                Cell::Text("a,b".into()),
                Cell::Text("say \"hi\"\nbye".into())
            ]
        );
    }
}
