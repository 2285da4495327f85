//! `fitup plan-sequence DOC [--mode mates|geometry] [--base NAME] [--threaded NAME…]
//! [--time-limit-ms MS] [--exclude NAME…] [--component NAME…] [--no-support]
//! [--gravity X,Y,Z] [--option KEY=VALUE…] [--json]`: the flags and `--option`s fill
//! the one table of sequence options (`fitup::options::Sequence`), as a script's map
//! and Python's keywords do.

use super::out::{errln as eprintln, outln as println};
use super::Exit;
use crate::document::Document;
use crate::options::{Options, Sequence};
use crate::sequence::{plan_sequence, SequenceError};
use crate::workspace::SceneCache;
use std::path::Path;

/// Options of `fitup plan-sequence`.
pub(super) struct Args<'a> {
    pub doc: &'a Path,
    pub mode: &'a str,
    pub base: Option<String>,
    pub threaded: Vec<String>,
    pub time_limit_ms: Option<f64>,
    pub exclude: Vec<String>,
    pub components: Vec<String>,
    pub support: bool,
    pub gravity: Option<String>,
    pub max_sequences: usize,
    /// `KEY=VALUE` of the sequence options table.
    pub options: Vec<String>,
    pub json: bool,
}

/// The request the flags and `--option`s make (flags first, `--option`s over them),
/// read through the vocabulary like a script's map.
fn request(a: &Args<'_>) -> Result<Sequence, super::CliError> {
    use serde_json::{json, Value};
    let mut map = serde_json::Map::new();
    map.insert("mode".into(), json!(a.mode));
    if let Some(b) = &a.base {
        map.insert("base".into(), json!(b));
    }
    for (key, list) in [
        ("threaded", &a.threaded),
        ("exclude", &a.exclude),
        ("components", &a.components),
    ] {
        if !list.is_empty() {
            map.insert(key.into(), json!(list));
        }
    }
    if let Some(t) = a.time_limit_ms {
        map.insert("time_limit_ms".into(), json!(t));
    }
    map.insert("support".into(), json!(a.support));
    if let Some(g) = &a.gravity {
        let v = parse_vec3(g).ok_or_else(|| super::CliError::Gravity(g.clone()))?;
        map.insert("gravity".into(), json!([v.x, v.y, v.z]));
    }
    map.insert("max_sequences".into(), json!(a.max_sequences));
    map.extend(Sequence::VOCABULARY.map_from_args(&a.options)?);
    let parsed = Sequence::from_value(Value::Object(map))?;
    for w in &parsed.warnings {
        eprintln!("warning: {w}");
    }
    Ok(parsed.options)
}

pub(super) fn plan(a: Args<'_>) -> Exit {
    let req = match request(&a) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return Exit::Usage;
        }
    };
    // The limit covers reading the document and its meshes too (a 500k-triangle
    // product takes a second or more to read): the planner gets what is left.
    let started = std::time::Instant::now();
    let doc = match Document::open(a.doc) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {}", e.render());
            return Exit::Failure;
        }
    };
    let limit = req.time_limit_ms;
    let mut o = req.sequence_options();
    if limit.is_finite() && limit > 0.0 {
        let spent = started.elapsed().as_secs_f64() * 1e3;
        if spent >= limit {
            eprintln!(
                "error: {}: {}",
                a.doc.display(),
                SequenceError::TimeLimit(limit)
            );
            return Exit::Failure;
        }
        o.time_limit_ms = Some(limit - spent);
    }
    match plan_sequence(&doc, &mut SceneCache::new(), &o) {
        Ok(p) => {
            if a.json {
                println!("{}", p.to_json());
            } else {
                print(&p.summary());
            }
            Exit::Ok
        }
        Err(e) => {
            // The user's limit, not what was left of it after reading.
            let e = match e {
                SequenceError::TimeLimit(_) => SequenceError::TimeLimit(limit),
                e => e,
            };
            eprintln!("error: {}: {e}", a.doc.display());
            Exit::Failure
        }
    }
}

fn print(s: &str) {
    let s = crate::diagnostics::printable(s, true);
    super::out::write(super::out::Stream::Stdout, &s);
}

/// `x,y,z` → a vector (finite numbers; the library checks it is non-zero).
fn parse_vec3(s: &str) -> Option<crate::math::Vec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()?;
    (v.len() == 3).then(|| crate::math::Vec3::new(v[0], v[1], v[2]))
}
