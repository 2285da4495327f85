//! Bindings for data files: `read_text`, `read_csv`, `read_json` inside the project,
//! and `write_text`, `write_csv`, `write_json` through the output rule.

use super::api::Api;
use super::convert::{err, fail, Sizes};
use super::{Context, ScriptResult};
use crate::files::{self, Cell, CsvOptions};
use rhai::{Array, Dynamic, Map};
use std::sync::Arc;

/// A Rhai options map as a library options struct (the struct's serde names and
/// defaults; an unknown key is an error naming the known ones).
pub(crate) fn options<T: serde::de::DeserializeOwned>(map: &Map, what: &str) -> ScriptResult<T> {
    let v = to_json(&Dynamic::from_map(map.clone()), what)?;
    serde_json::from_value(v).map_err(|e| fail(format!("{what} options: {e}")))
}

/// A script value as JSON: `()` is null; numbers, strings, booleans, arrays and maps
/// as themselves; a Transform as its 4×4 matrix; anything else is refused.
pub(crate) fn to_json(v: &Dynamic, what: &str) -> ScriptResult<serde_json::Value> {
    super::convert::json_value(
        v,
        "",
        &super::convert::JsonRule {
            loose: true,
            non_finite: &|_, f| {
                format!("{what}: {f} has no JSON spelling (JSON numbers are finite)")
            },
            other: &|_, t| {
                format!("{what}: a {t} cannot be written as JSON (numbers, strings, booleans, arrays, maps and Transforms can)")
            },
        },
    )
}

/// JSON as a script value: null is `()`, whole numbers that fit are integers, other
/// numbers floats, objects maps.
pub(crate) fn from_json(v: &serde_json::Value) -> Dynamic {
    use serde_json::Value;
    match v {
        Value::Null => Dynamic::UNIT,
        Value::Bool(b) => Dynamic::from_bool(*b),
        Value::Number(n) => match n.as_i64() {
            Some(i) => Dynamic::from_int(i),
            None => Dynamic::from_float(n.as_f64().unwrap_or(f64::NAN)),
        },
        Value::String(s) => Dynamic::from(s.clone()),
        Value::Array(a) => Dynamic::from_array(a.iter().map(from_json).collect()),
        Value::Object(o) => {
            let mut m = Map::new();
            for (k, x) in o {
                m.insert(k.as_str().into(), from_json(x));
            }
            Dynamic::from_map(m)
        }
    }
}

fn cell(c: &Cell) -> Dynamic {
    match c {
        Cell::Empty => Dynamic::UNIT,
        Cell::Int(i) => Dynamic::from_int(*i),
        Cell::Float(f) => Dynamic::from_float(*f),
        Cell::Bool(b) => Dynamic::from_bool(*b),
        Cell::Text(t) => Dynamic::from(t.clone()),
    }
}

/// A value as one CSV field's text: numbers with every digit, `()` empty.
fn field_text(v: &Dynamic) -> String {
    if v.is_unit() {
        return String::new();
    }
    if let Ok(f) = v.as_float() {
        return format!("{f:?}");
    }
    if let Some(s) = v.read_lock::<rhai::ImmutableString>() {
        return s.to_string();
    }
    v.to_string()
}

/// Options of `write_csv`.
#[derive(Debug, Clone, Default, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
struct WriteCsvOptions {
    overwrite: bool,
    delimiter: Option<char>,
    /// Column order for rows given as maps (default: the first row's keys).
    columns: Option<Vec<String>>,
}

/// Options of `write_text` and `write_json`.
#[derive(Debug, Clone, Default, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
struct WriteOptions {
    overwrite: bool,
}

/// What the script value of `v` ([`from_json`]) would hold.
fn json_sizes(v: &serde_json::Value, s: &mut Sizes) {
    use serde_json::Value;
    match v {
        Value::Array(a) => {
            s.arrays += a.len();
            a.iter().for_each(|x| json_sizes(x, s));
        }
        Value::Object(o) => {
            s.maps += o.len();
            o.values().for_each(|x| json_sizes(x, s));
        }
        Value::String(t) => s.chars += t.len(),
        _ => {}
    }
}

fn read_csv(c: &Context, path: &str, options: &CsvOptions) -> ScriptResult<Array> {
    let (full, table) = files::read_csv(&c.project, path, options).map_err(fail)?;
    c.record_read(&full);
    let fields: usize = table.rows.iter().map(Vec::len).sum();
    let chars = table
        .rows
        .iter()
        .flatten()
        .map(|v| match v {
            Cell::Text(t) => t.len(),
            _ => 0,
        })
        .sum();
    let sizes = if options.header {
        Sizes {
            arrays: table.rows.len(),
            maps: fields,
            chars,
        }
    } else {
        Sizes {
            arrays: table.rows.len() + fields,
            maps: 0,
            chars,
        }
    };
    sizes.within(
        &c.limits,
        &format!(
            "read_csv(\"{path}\") of {} rows",
            crate::math::format::count(table.rows.len() as u64)
        ),
    )?;
    Ok(table
        .rows
        .iter()
        .map(|r| {
            if options.header {
                let mut m = Map::new();
                for (k, v) in table.columns.iter().zip(r) {
                    m.insert(k.as_str().into(), cell(v));
                }
                Dynamic::from_map(m)
            } else {
                Dynamic::from_array(r.iter().map(cell).collect())
            }
        })
        .collect())
}

fn write_csv(c: &Context, path: &str, rows: &Array, o: &WriteCsvOptions) -> ScriptResult<()> {
    let d = o.delimiter.unwrap_or(',');
    let mut lines: Vec<Vec<String>> = Vec::with_capacity(rows.len() + 1);
    let maps = rows.first().is_some_and(|r| r.is_map());
    let columns: Vec<String> = match (&o.columns, maps) {
        (Some(c), _) => c.clone(),
        (None, true) => rows[0]
            .read_lock::<Map>()
            .map(|m| m.keys().map(|k| k.to_string()).collect())
            .unwrap_or_default(),
        (None, false) => Vec::new(),
    };
    if maps {
        lines.push(columns.clone());
    }
    for (i, r) in rows.iter().enumerate() {
        if let Some(m) = r.read_lock::<Map>() {
            if !maps {
                return err(format!("write_csv: row {i} is a map but row 0 is not: give every row as an array or every row as a map"));
            }
            lines.push(
                columns
                    .iter()
                    .map(|k| m.get(k.as_str()).map(field_text).unwrap_or_default())
                    .collect(),
            );
        } else if let Some(a) = r.read_lock::<Array>() {
            if maps {
                return err(format!("write_csv: row {i} is an array but row 0 is a map"));
            }
            lines.push(a.iter().map(field_text).collect());
        } else {
            return err(format!(
                "write_csv: row {i} must be an array of values or a map, not {}",
                r.type_name()
            ));
        }
    }
    if !maps {
        if let Some(c) = &o.columns {
            lines.insert(0, c.clone());
        }
    }
    c.write_output(path, files::csv_text(&lines, d).as_bytes(), o.overwrite)?;
    Ok(())
}

pub(super) fn register(api: &mut Api, ctx: &Arc<Context>) {
    api.section("Files", "Data files inside the project: CSV tables, JSON and text (UTF-8; at most 64 MiB). A file read is a dependency of the run (`fitup watch` reruns when it changes); a parse error names the file and line. Writers go through the write rule (see \"What a run writes\" in docs/scripting.md): a new file is written, an existing one replaced only when fitup wrote it, or with `#{overwrite: true}`; atomic. Diagnostics (document warnings) go to stderr, so a script's `print` output is its own.");
    let c = ctx.clone();
    api.f(
        "read_text(path: string) -> string",
        "The whole text of a file inside the project.",
        move |path: &str| -> ScriptResult<String> {
            let (full, text) = files::read_text(&c.project, path).map_err(fail)?;
            c.record_read(&full);
            Ok(text)
        },
    );
    let c = ctx.clone();
    api.f("read_csv(path: string) -> array", "A CSV table (RFC 4180 quoting; `,` separated; the first row names the columns): one map per row, column name → value. Unquoted fields are typed: whole numbers integers, other numbers floats, `true`/`false` booleans, empty fields `()`; quoted fields stay text. A row with another number of fields than the header is an error naming its line.", move |path: &str| -> ScriptResult<Array> {
        read_csv(&c, path, &CsvOptions::default())
    });
    let c = ctx.clone();
    api.f("read_csv(path: string, options: map) -> array", "`read_csv(path)` with `#{header: bool (default true; false: one array per row), delimiter: \";\" (one character, default \",\"), comment: \"#\" (lines starting with it are skipped), typed: bool (default true; false keeps every field as text)}`.", move |path: &str, o: Map| -> ScriptResult<Array> {
        let options: CsvOptions = options(&o, "read_csv")?;
        read_csv(&c, path, &options)
    });
    let c = ctx.clone();
    api.f("read_json(path: string) -> any", "A JSON file as script values: objects as maps, arrays as arrays, whole numbers as integers, other numbers as floats, null as `()`.", move |path: &str| -> ScriptResult<Dynamic> {
        let (full, v) = files::read_json(&c.project, path).map_err(fail)?;
        c.record_read(&full);
        let mut sizes = Sizes::default();
        json_sizes(&v, &mut sizes);
        sizes.within(&c.limits, &format!("read_json(\"{path}\")"))?;
        Ok(from_json(&v))
    });
    let c = ctx.clone();
    api.f("write_text(path: string, text: string)", "Writes `text` to a file inside the project (UTF-8, as given; missing folders are created).", move |path: &str, text: &str| -> ScriptResult<()> {
        c.write_output(path, text.as_bytes(), false).map(|_| ())
    });
    let c = ctx.clone();
    api.f(
        "write_text(path: string, text: string, options: map)",
        "`write_text` with `#{overwrite: bool}`.",
        move |path: &str, text: &str, o: Map| -> ScriptResult<()> {
            let o: WriteOptions = options(&o, "write_text")?;
            c.write_output(path, text.as_bytes(), o.overwrite)
                .map(|_| ())
        },
    );
    let c = ctx.clone();
    api.f("write_csv(path: string, rows: array)", "Writes rows as CSV: each row an array of values, or each a map (then the first row's keys, in order, are the header). Fields holding the delimiter, quotes or line breaks are quoted; floats keep every digit; `()` is an empty field.", move |path: &str, rows: Array| -> ScriptResult<()> {
        write_csv(&c, path, &rows, &WriteCsvOptions::default())
    });
    let c = ctx.clone();
    api.f("write_csv(path: string, rows: array, options: map)", "`write_csv` with `#{overwrite: bool, delimiter: \";\", columns: [names]}` (`columns`: the header and, for map rows, their order).", move |path: &str, rows: Array, o: Map| -> ScriptResult<()> {
        let o: WriteCsvOptions = options(&o, "write_csv")?;
        write_csv(&c, path, &rows, &o)
    });
    let c = ctx.clone();
    api.f("write_json(path: string, value)", "Writes a value as pretty-printed JSON (maps as objects, `()` as null, a Transform as its 4×4 matrix in mm).", move |path: &str, v: Dynamic| -> ScriptResult<()> {
        let j = to_json(&v, "write_json")?;
        let text = serde_json::to_string_pretty(&j).map_err(fail)? + "\n";
        c.write_output(path, text.as_bytes(), false).map(|_| ())
    });
    let c = ctx.clone();
    api.f(
        "write_json(path: string, value, options: map)",
        "`write_json` with `#{overwrite: bool}`.",
        move |path: &str, v: Dynamic, o: Map| -> ScriptResult<()> {
            let o: WriteOptions = options(&o, "write_json")?;
            let j = to_json(&v, "write_json")?;
            let text = serde_json::to_string_pretty(&j).map_err(fail)? + "\n";
            c.write_output(path, text.as_bytes(), o.overwrite)
                .map(|_| ())
        },
    );
}
