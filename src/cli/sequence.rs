//! `fitup plan-sequence DOC [--mode mates|geometry] [--base NAME] [--threaded NAME…]
//! [--time-limit-ms MS] [--json]`.

use super::out::{errln as eprintln, outln as println};
use super::Exit;
use crate::document::Document;
use crate::sequence::{plan_sequence, Mode, SequenceOptions};
use crate::workspace::SceneCache;
use std::path::Path;

/// Options of `fitup plan-sequence`.
pub(super) struct Args<'a> {
    pub doc: &'a Path,
    pub mode: &'a str,
    pub base: Option<String>,
    pub threaded: Vec<String>,
    pub time_limit_ms: Option<f64>,
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
    let doc = match Document::open(a.doc) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {}", e.render());
            return Exit::Failure;
        }
    };
    let o = SequenceOptions {
        mode,
        base: a.base,
        threaded: a.threaded,
        time_limit_ms: a.time_limit_ms,
        max_sequences: a.max_sequences,
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
            eprintln!("error: {}: {e}", a.doc.display());
            Exit::Failure
        }
    }
}

fn print(s: &str) {
    let s = crate::diagnostics::printable(s, true);
    super::out::write(super::out::Stream::Stdout, &s);
}
