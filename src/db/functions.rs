//! The SQL functions of scripts' queries whose SQLite versions cost more than linear
//! time in their arguments, replaced on the query connection by versions that do not,
//! and that look at the query's clock while they work.
//!
//! Why: the progress handler and the interrupt are only looked at between virtual
//! machine steps, and a function call is one step. SQLite's `instr(X, Y)` and
//! `replace(X, Y, Z)` compare `Y` at every position of `X` (16 MiB × 8 MiB is 10^14
//! byte comparisons, one step that never ends), `trim(X, Y)` tests every character
//! of `X` against every character of `Y`, `like` and `glob` backtrack. Here `instr`
//! and `replace` search with `str::find` (two-way: linear), the `trim` family with a
//! set, `like` and `glob` with a matcher that backtracks only to the last wildcard and
//! stops when the query's time is up ([`Clock`]). Every other built-in function is
//! linear in its arguments, which the connection caps at 16 MiB each.

use rusqlite::functions::{Context, FunctionFlags};
use rusqlite::types::ValueRef;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// The current query's deadline and cancel flag, shared with the functions.
#[derive(Debug)]
pub(crate) struct Clock {
    epoch: Instant,
    /// Nanoseconds after `epoch`; `u64::MAX`: no query running.
    deadline_ns: AtomicU64,
    cancel: Mutex<Option<Arc<AtomicBool>>>,
}

impl Clock {
    pub(crate) fn new() -> Clock {
        Clock {
            epoch: Instant::now(),
            deadline_ns: AtomicU64::new(u64::MAX),
            cancel: Mutex::new(None),
        }
    }

    /// A query starts: its deadline and cancel flag.
    pub(crate) fn start(&self, deadline: Instant, cancel: Option<Arc<AtomicBool>>) {
        let ns = deadline.saturating_duration_since(self.epoch).as_nanos();
        self.deadline_ns
            .store(u64::try_from(ns).unwrap_or(u64::MAX - 1), Ordering::Relaxed);
        if let Ok(mut c) = self.cancel.lock() {
            *c = cancel;
        }
    }

    /// The query ended.
    pub(crate) fn stop(&self) {
        self.deadline_ns.store(u64::MAX, Ordering::Relaxed);
        if let Ok(mut c) = self.cancel.lock() {
            *c = None;
        }
    }

    /// Whether the query's time is up or the run was cancelled.
    pub(crate) fn expired(&self) -> bool {
        let d = self.deadline_ns.load(Ordering::Relaxed);
        if d != u64::MAX && self.epoch.elapsed().as_nanos() > u128::from(d) {
            return true;
        }
        self.cancel
            .lock()
            .ok()
            .and_then(|c| c.as_ref().map(|f| f.load(Ordering::Relaxed)))
            .unwrap_or(false)
    }
}

/// Steps between two looks at the clock inside a matcher.
const CHECK_EVERY: u64 = 1 << 16;

/// The error a function stops with when the clock says so (the caller reports the
/// time limit or the cancel).
fn stopped() -> rusqlite::Error {
    rusqlite::Error::UserFunctionError("interrupted: the query's time is up".into())
}

fn too_big() -> rusqlite::Error {
    rusqlite::Error::UserFunctionError("string or blob too big".into())
}

/// A value as text, as SQLite converts it for a text function (`None`: NULL).
fn text<'a>(v: ValueRef<'a>) -> Option<std::borrow::Cow<'a, str>> {
    use std::borrow::Cow;
    match v {
        ValueRef::Null => None,
        ValueRef::Integer(i) => Some(Cow::Owned(i.to_string())),
        ValueRef::Real(r) => Some(Cow::Owned(real_text(r))),
        ValueRef::Text(t) | ValueRef::Blob(t) => Some(String::from_utf8_lossy(t)),
    }
}

/// A real as SQLite prints it (`%!.15g`: `1.0`, `0.1`, `1e+300`).
fn real_text(r: f64) -> String {
    if r.is_finite() && r == r.trunc() && r.abs() < 1e15 {
        format!("{r:.1}")
    } else if r.is_finite() {
        let s = format!("{r:.15e}");
        // Shortest form that reads back the same, as %.15g would print it.
        let short = format!("{r}");
        if short.len() <= 17 {
            short
        } else {
            s
        }
    } else if r.is_nan() {
        "NaN".into()
    } else if r > 0.0 {
        "Inf".into()
    } else {
        "-Inf".into()
    }
}

/// Registers the functions on `conn`, reading `clock`.
pub(crate) fn register(conn: &rusqlite::Connection, clock: &Arc<Clock>) -> rusqlite::Result<()> {
    let flags = FunctionFlags::SQLITE_UTF8 | FunctionFlags::SQLITE_DETERMINISTIC;
    conn.create_scalar_function("instr", 2, flags, instr)?;
    conn.create_scalar_function("replace", 3, flags, replace)?;
    for (name, left, right) in [
        ("trim", true, true),
        ("ltrim", true, false),
        ("rtrim", false, true),
    ] {
        conn.create_scalar_function(name, 2, flags, move |ctx| trim(ctx, left, right))?;
    }
    for (name, n, glob) in [("like", 2, false), ("like", 3, false), ("glob", 2, true)] {
        let c = clock.clone();
        conn.create_scalar_function(name, n, flags, move |ctx| pattern(ctx, glob, &c))?;
    }
    Ok(())
}

/// `instr(X, Y)`: the 1-based position of the first `Y` in `X` (characters; bytes when
/// both are blobs), 0 when none, NULL when either is NULL.
fn instr(ctx: &mut Context<'_>) -> rusqlite::Result<Option<i64>> {
    let (x, y) = (ctx.get_raw(0), ctx.get_raw(1));
    if let (ValueRef::Blob(h), ValueRef::Blob(n)) = (x, y) {
        return Ok(Some(match find_bytes(h, n) {
            Some(i) => i as i64 + 1,
            None => 0,
        }));
    }
    let (Some(h), Some(n)) = (text(x), text(y)) else {
        return Ok(None);
    };
    Ok(Some(match h.find(n.as_ref()) {
        Some(i) => h[..i].chars().count() as i64 + 1,
        None => 0,
    }))
}

/// The first occurrence of `needle` in `hay` (Knuth–Morris–Pratt: linear).
fn find_bytes(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() {
        return Some(0);
    }
    let mut fail = vec![0usize; needle.len()];
    let mut k = 0;
    for i in 1..needle.len() {
        while k > 0 && needle[i] != needle[k] {
            k = fail[k - 1];
        }
        if needle[i] == needle[k] {
            k += 1;
        }
        fail[i] = k;
    }
    let mut k = 0;
    for (i, &b) in hay.iter().enumerate() {
        while k > 0 && b != needle[k] {
            k = fail[k - 1];
        }
        if b == needle[k] {
            k += 1;
            if k == needle.len() {
                return Some(i + 1 - k);
            }
        }
    }
    None
}

/// `replace(X, Y, Z)`: every `Y` in `X` replaced by `Z` (text); `X` when `Y` is
/// empty; NULL when any is NULL. A result past the value cap is an error, found
/// before it is built.
fn replace(ctx: &mut Context<'_>) -> rusqlite::Result<Option<String>> {
    let (Some(x), Some(y), Some(z)) = (
        text(ctx.get_raw(0)),
        text(ctx.get_raw(1)),
        text(ctx.get_raw(2)),
    ) else {
        return Ok(None);
    };
    if y.is_empty() {
        return Ok(Some(x.into_owned()));
    }
    let count = x.matches(y.as_ref()).count();
    let len = x.len() as u128 + count as u128 * z.len() as u128;
    if len.saturating_sub(count as u128 * y.len() as u128) > MAX_VALUE_BYTES as u128 {
        return Err(too_big());
    }
    Ok(Some(x.replace(y.as_ref(), z.as_ref())))
}

/// `trim(X, Y)`, `ltrim(X, Y)`, `rtrim(X, Y)`: the characters of `Y` removed from the
/// ends of `X` (a set lookup per character, not a scan of `Y`).
fn trim(ctx: &mut Context<'_>, left: bool, right: bool) -> rusqlite::Result<Option<String>> {
    let (Some(x), Some(y)) = (text(ctx.get_raw(0)), text(ctx.get_raw(1))) else {
        return Ok(None);
    };
    let set: std::collections::HashSet<char> = y.chars().collect();
    let mut s: &str = x.as_ref();
    if left {
        s = s.trim_start_matches(|c| set.contains(&c));
    }
    if right {
        s = s.trim_end_matches(|c| set.contains(&c));
    }
    Ok(Some(s.to_string()))
}

/// The longest text or blob value a script's SQLite query may build (also bounds
/// `zeroblob`, `printf` and `group_concat` bombs): the script string limit.
pub(crate) const MAX_VALUE_BYTES: i32 = 16 << 20;

/// The longest `like`/`glob` pattern, bytes (SQLite's own limit is 50,000).
pub(crate) const MAX_PATTERN_BYTES: usize = 1000;

/// One element of a pattern.
#[derive(Debug, Clone)]
enum Token {
    /// `%` / `*`: any run of characters.
    Any,
    /// `_` / `?`: one character.
    One,
    /// A character (ASCII case folded for `like`).
    Char(char),
    /// A `glob` class `[...]`: (negated, ranges).
    Class(bool, Vec<(char, char)>),
}

/// `like(P, S[, E])` and `glob(P, S)`: SQLite's semantics (`like` folds ASCII case,
/// `_` and `%`, an optional one-character escape; `glob` is case-sensitive with `?`,
/// `*` and `[...]` classes), matched by backtracking only to the last `%`/`*` (time
/// linear in `S` per pattern element), looking at the clock as it goes.
fn pattern(ctx: &mut Context<'_>, glob: bool, clock: &Clock) -> rusqlite::Result<Option<bool>> {
    let (Some(p), Some(s)) = (text(ctx.get_raw(0)), text(ctx.get_raw(1))) else {
        return Ok(None);
    };
    if p.len() > MAX_PATTERN_BYTES {
        return Err(rusqlite::Error::UserFunctionError(
            format!("LIKE or GLOB pattern too complex (more than {MAX_PATTERN_BYTES} bytes)")
                .into(),
        ));
    }
    let escape = if ctx.len() == 3 {
        match text(ctx.get_raw(2)) {
            None => return Ok(None),
            Some(e) => {
                let mut cs = e.chars();
                match (cs.next(), cs.next()) {
                    (Some(c), None) => Some(c),
                    _ => {
                        return Err(rusqlite::Error::UserFunctionError(
                            "ESCAPE expression must be a single character".into(),
                        ))
                    }
                }
            }
        }
    } else {
        None
    };
    let tokens = if glob {
        glob_tokens(&p)
    } else {
        like_tokens(&p, escape)
    };
    let s: Vec<char> = if glob {
        s.chars().collect()
    } else {
        s.chars().map(|c| c.to_ascii_lowercase()).collect()
    };
    matches(&tokens, &s, clock).map(Some)
}

fn like_tokens(p: &str, escape: Option<char>) -> Vec<Token> {
    let mut out = Vec::new();
    let mut it = p.chars();
    while let Some(c) = it.next() {
        out.push(match c {
            c if Some(c) == escape => match it.next() {
                Some(n) => Token::Char(n.to_ascii_lowercase()),
                None => break,
            },
            '%' => Token::Any,
            '_' => Token::One,
            c => Token::Char(c.to_ascii_lowercase()),
        });
    }
    out
}

fn glob_tokens(p: &str) -> Vec<Token> {
    let cs: Vec<char> = p.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < cs.len() {
        match cs[i] {
            '*' => out.push(Token::Any),
            '?' => out.push(Token::One),
            '[' => {
                let mut j = i + 1;
                let negated = cs.get(j) == Some(&'^');
                if negated {
                    j += 1;
                }
                let mut ranges = Vec::new();
                let mut first = true;
                let mut closed = false;
                while j < cs.len() {
                    let c = cs[j];
                    if c == ']' && !first {
                        closed = true;
                        break;
                    }
                    first = false;
                    if cs.get(j + 1) == Some(&'-') && cs.get(j + 2).is_some_and(|&e| e != ']') {
                        ranges.push((c, cs[j + 2]));
                        j += 3;
                    } else {
                        ranges.push((c, c));
                        j += 1;
                    }
                }
                if !closed {
                    // An unclosed class matches nothing (as SQLite's).
                    out.push(Token::Class(false, Vec::new()));
                    return out;
                }
                out.push(Token::Class(negated, ranges));
                i = j;
            }
            c => out.push(Token::Char(c)),
        }
        i += 1;
    }
    out
}

fn one(t: &Token, c: char) -> bool {
    match t {
        Token::Any | Token::One => true,
        Token::Char(x) => *x == c,
        Token::Class(neg, ranges) => ranges.iter().any(|&(a, b)| a <= c && c <= b) != *neg,
    }
}

/// The wildcard match with backtracking to the last `Any` only: correct for patterns
/// whose other elements each match one character, and at most |S| restarts per `Any`.
fn matches(p: &[Token], s: &[char], clock: &Clock) -> rusqlite::Result<bool> {
    let (mut pi, mut si) = (0usize, 0usize);
    let mut star: Option<(usize, usize)> = None;
    let mut steps = 0u64;
    while si < s.len() {
        steps += 1;
        if steps.is_multiple_of(CHECK_EVERY) && clock.expired() {
            return Err(stopped());
        }
        if pi < p.len() && matches!(p[pi], Token::Any) {
            star = Some((pi, si));
            pi += 1;
        } else if pi < p.len() && one(&p[pi], s[si]) {
            pi += 1;
            si += 1;
        } else if let Some((sp, ss)) = star {
            pi = sp + 1;
            si = ss + 1;
            star = Some((sp, ss + 1));
        } else {
            return Ok(false);
        }
    }
    Ok(p[pi..].iter().all(|t| matches!(t, Token::Any)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn conn() -> rusqlite::Connection {
        let c = rusqlite::Connection::open_in_memory().unwrap();
        register(&c, &Arc::new(Clock::new())).unwrap();
        c
    }

    fn one_value(c: &rusqlite::Connection, sql: &str) -> rusqlite::types::Value {
        c.query_row(sql, [], |r| r.get(0)).unwrap()
    }

    /// The replacements agree with SQLite's own on ordinary arguments.
    #[test]
    fn agrees_with_sqlite() {
        let ours = conn();
        let theirs = rusqlite::Connection::open_in_memory().unwrap();
        for sql in [
            "SELECT instr('hello world', 'o')",
            "SELECT instr('héllo', 'l')",
            "SELECT instr('abc', '')",
            "SELECT instr('abc', 'x')",
            "SELECT instr(NULL, 'x')",
            "SELECT instr(x'0102030405', x'0304')",
            "SELECT instr(12345, 34)",
            "SELECT replace('aaa', 'a', 'bb')",
            "SELECT replace('abc', '', 'x')",
            "SELECT replace('abc', 'b', NULL)",
            "SELECT trim('xxhixx', 'x')",
            "SELECT ltrim('xyhixy', 'yx')",
            "SELECT rtrim('xyhixy', 'yx')",
            "SELECT 'Hello' LIKE 'h%O'",
            "SELECT 'Hello' LIKE 'h_llo'",
            "SELECT 'Hello' LIKE 'h_lo'",
            "SELECT 'a%b' LIKE 'a!%b' ESCAPE '!'",
            "SELECT 'axb' LIKE 'a!%b' ESCAPE '!'",
            "SELECT 'Hello' GLOB 'H*'",
            "SELECT 'Hello' GLOB 'h*'",
            "SELECT 'Hello' GLOB 'H[a-f]llo'",
            "SELECT 'Hello' GLOB 'H[^a-f]llo'",
            "SELECT 'H]llo' GLOB 'H[]]llo'",
            "SELECT 'Hello' GLOB 'H?llo'",
            "SELECT 'abcabc' LIKE '%b%c'",
            "SELECT '' LIKE '%'",
            "SELECT NULL LIKE 'a'",
        ] {
            assert_eq!(one_value(&ours, sql), one_value(&theirs, sql), "{sql}");
        }
    }

    /// What took SQLite's versions hours is linear here.
    #[test]
    fn hostile_arguments_are_linear() {
        let c = conn();
        let start = Instant::now();
        let v = one_value(
            &c,
            "SELECT instr(replace(zeroblob(4000000), x'00', 'a'), replace(zeroblob(2000000), x'00', 'a') || 'b')",
        );
        assert_eq!(v, rusqlite::types::Value::Integer(0));
        let v = one_value(
            &c,
            "SELECT length(trim(replace(zeroblob(2000000), x'00', 'ab'), replace(zeroblob(100000), x'00', 'c') || 'ab'))",
        );
        assert_eq!(v, rusqlite::types::Value::Integer(0));
        let v = one_value(
            &c,
            "SELECT replace(zeroblob(2000000), x'00', 'a') LIKE '%a%a%a%a%a%a%a%a%b'",
        );
        assert_eq!(v, rusqlite::types::Value::Integer(0));
        // A bound on hangs, not a speed claim: these were hours.
        assert!(start.elapsed().as_secs() < 60);
        // A replacement past the value cap is refused before it is built.
        let e = c
            .query_row(
                "SELECT replace(replace(zeroblob(100000), x'00', 'a'), 'a', replace(zeroblob(1000), x'00', 'b'))",
                [],
                |r| r.get::<_, String>(0),
            )
            .unwrap_err();
        assert!(e.to_string().contains("too big"), "{e}");
    }
}
