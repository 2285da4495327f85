//! `fitup plan-sequence DOC [--mode mates|geometry] [--base NAME] [--threaded NAME…]
//! [--time-limit-ms MS] [--exclude NAME…] [--component NAME…] [--no-support]
//! [--gravity X,Y,Z] [--json]`.

use super::out::{errln as eprintln, outln as println};
use super::Exit;
use crate::document::Document;
use crate::sequence::{
    plan_sequence, Mode, SequenceError, SequenceOptions, DEFAULT_SEQUENCE_TIME_LIMIT_MS,
};
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
    pub json: bool,
}

pub(super) fn plan(a: Args<'_>) -> Exit {
    let Some(mode) = Mode::parse(a.mode) else {
        eprintln!(
            "error: --mode must be `mates` or `geometry`, not `{}`",
            a.mode
        );
        return Exit::Usage;
    };
    let gravity = match a.gravity.as_deref().map(parse_vec3) {
        None => None,
        Some(Some(g)) => Some(g),
        Some(None) => {
            eprintln!(
                "error: --gravity must be three numbers `x,y,z`, not `{}`",
                a.gravity.unwrap_or_default()
            );
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
    let limit = a.time_limit_ms.unwrap_or(DEFAULT_SEQUENCE_TIME_LIMIT_MS);
    let mut left = a.time_limit_ms;
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
        left = Some(limit - spent);
    }
    let o = SequenceOptions {
        mode,
        base: a.base,
        threaded: a.threaded,
        time_limit_ms: left,
        max_sequences: a.max_sequences,
        exclude: a.exclude,
        components: a.components,
        support: a.support,
        gravity,
        ..SequenceOptions::default()
    };
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
