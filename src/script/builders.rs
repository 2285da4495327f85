//! Rhai's string → array builders (`split`, `split_rev`, `to_chars`, `to_blob`),
//! counted before they allocate.
//!
//! Rhai builds the whole array first and compares it with the sandbox's array limit
//! afterwards: `split("")` of a 16 M-character string took 1.08 GB before the
//! refusal. These replacements (registered on the engine, so they take precedence
//! over Rhai's packages, with the same results) count the elements without allocating
//! and refuse past the limit; an array within it takes at most about 64 bytes per
//! element beyond the string's own bytes (a `Dynamic` and one shared string each).

use rhai::{Array, Blob, Dynamic, Engine, EvalAltResult, ImmutableString, Position, INT};

type Built<T> = Result<T, Box<EvalAltResult>>;

/// Refuses an array of `n` elements made by `what` past `max` (0: no limit).
fn within(n: usize, max: usize, what: &str) -> Result<(), Box<EvalAltResult>> {
    if max > 0 && n > max {
        return Err(Box::new(EvalAltResult::ErrorDataTooLarge(
            format!(
                "the array `{what}` would make ({} elements)",
                crate::math::format::count(n as u64)
            ),
            Position::NONE,
        )));
    }
    Ok(())
}

/// The segments `split(delimiter)` makes (Rhai: a string without the delimiter, or an
/// empty one, is one segment; an empty delimiter splits around every character).
fn segments(s: &str, delimiter: &str) -> usize {
    if s.is_empty() {
        1
    } else if delimiter.is_empty() {
        s.chars().count() + 2
    } else {
        s.matches(delimiter).count() + 1
    }
}

/// The most segments `split(…, n)` asks for (Rhai: `n <= 1` keeps the string whole).
fn limit(n: INT) -> usize {
    if n <= 1 {
        1
    } else {
        usize::try_from(n).unwrap_or(usize::MAX)
    }
}

fn segments_char(s: &str, delimiter: char) -> usize {
    if s.is_empty() {
        1
    } else {
        s.matches(delimiter).count() + 1
    }
}

fn segment(s: &str) -> Dynamic {
    s.into()
}

fn one(s: ImmutableString) -> Array {
    vec![s.into()]
}

/// Which end a split starts from: `split` the front, `split_rev` the back.
#[derive(Clone, Copy)]
enum End {
    Front,
    Back,
}

/// `s` split at the string `d` from `end`, into at most `n` segments (`None`: all),
/// as Rhai splits it: an empty string, or one without a non-empty `d`, is one segment.
fn split_str(s: ImmutableString, d: &str, n: Option<usize>, end: End) -> Array {
    if n.is_some_and(|n| n <= 1) || s.is_empty() || (!d.is_empty() && !s.contains(d)) {
        return one(s);
    }
    match (n, end) {
        (None, End::Front) => s.split(d).map(segment).collect(),
        (None, End::Back) => s.rsplit(d).map(segment).collect(),
        (Some(n), End::Front) => s.splitn(n, d).map(segment).collect(),
        (Some(n), End::Back) => s.rsplitn(n, d).map(segment).collect(),
    }
}

/// [`split_str`] at the character `d`.
fn split_char(s: ImmutableString, d: char, n: Option<usize>, end: End) -> Array {
    split_str(s, d.encode_utf8(&mut [0; 4]), n, end)
}

/// Registers the counted builders (`max`: the sandbox's elements per array).
pub(super) fn register(engine: &mut Engine, max: usize) {
    for (name, end) in [("split", End::Front), ("split_rev", End::Back)] {
        engine.register_fn(
            name,
            move |s: ImmutableString, d: ImmutableString| -> Built<Array> {
                within(segments(&s, &d), max, name)?;
                Ok(split_str(s, &d, None, end))
            },
        );
        engine.register_fn(
            name,
            move |s: ImmutableString, d: ImmutableString, n: INT| -> Built<Array> {
                let n = limit(n);
                within(segments(&s, &d).min(n), max, name)?;
                Ok(split_str(s, &d, Some(n), end))
            },
        );
        engine.register_fn(name, move |s: ImmutableString, d: char| -> Built<Array> {
            within(segments_char(&s, d), max, name)?;
            Ok(split_char(s, d, None, end))
        });
        engine.register_fn(
            name,
            move |s: ImmutableString, d: char, n: INT| -> Built<Array> {
                let n = limit(n);
                within(segments_char(&s, d).min(n), max, name)?;
                Ok(split_char(s, d, Some(n), end))
            },
        );
    }
    engine.register_fn("split", move |s: ImmutableString| -> Built<Array> {
        within(s.split_whitespace().count(), max, "split")?;
        let out: Array = if s.is_empty() {
            one(s)
        } else {
            s.split_whitespace().map(segment).collect()
        };
        Ok(out)
    });
    engine.register_fn("to_chars", move |s: ImmutableString| -> Built<Array> {
        within(s.chars().count(), max, "to_chars")?;
        Ok(s.chars().map(Dynamic::from).collect())
    });
    engine.register_fn("to_blob", move |s: ImmutableString| -> Built<Blob> {
        within(s.len(), max, "to_blob")?;
        Ok(s.as_bytes().to_vec())
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn engine(max: usize) -> Engine {
        let mut e = Engine::new();
        e.set_max_array_size(max);
        register(&mut e, max);
        e
    }

    /// The replacements give what Rhai's own functions give.
    #[test]
    fn results_are_rhais() {
        let ours = engine(1000);
        let mut rhai = Engine::new();
        rhai.set_max_array_size(1000);
        let s = r#"let s = "hello, world! hello, foo!"; let t = "é a\tb  c"; let e = "";"#;
        for call in [
            r#"s.split("ll")"#,
            r#"s.split("")"#,
            r#"s.split("zz")"#,
            r#"e.split("")"#,
            r#"e.split("x")"#,
            r#"s.split("ll", 2)"#,
            r#"s.split("", 4)"#,
            r#"s.split("ll", 0)"#,
            r#"s.split("ll", 99)"#,
            "s.split('l')",
            "s.split('z')",
            "e.split('l')",
            "s.split('l', 3)",
            "s.split('l', -1)",
            "s.split()",
            "t.split()",
            "e.split()",
            "s.split(6)",
            "t.split(-2)",
            r#"s.split_rev("ll")"#,
            r#"s.split_rev("")"#,
            r#"s.split_rev("ll", 2)"#,
            "s.split_rev('l')",
            "s.split_rev('l', 3)",
            "s.split_rev('z')",
            r#"s.split_rev("ll", 0)"#,
            r#"e.split_rev("")"#,
            "s.split_rev('l', -1)",
            r#"s.split_rev("zz", 5)"#,
            "t.to_chars()",
            "e.to_chars()",
            "t.to_blob()",
            "e.to_blob()",
            r#""a,b".split(",")"#,
        ] {
            let script = format!("{s} {call}");
            let a = ours.eval::<Dynamic>(&script).unwrap();
            let b = rhai.eval::<Dynamic>(&script).unwrap();
            assert_eq!(a.to_string(), b.to_string(), "{call}");
            assert_eq!(a.type_name(), b.type_name(), "{call}");
        }
        // Called on a constant, as a method.
        let a = ours
            .eval::<Array>(r#"const C = "a,b"; C.split(",")"#)
            .unwrap();
        assert_eq!(a.len(), 2);
    }

    /// Past the limit each builder refuses before building: the count in the message
    /// is the one the array would have had.
    #[test]
    fn past_the_limit_is_refused_with_the_count() {
        let ours = engine(10);
        let s = r#"let s = "abcdefghijkl"; let w = "a b c d e f g h i j k l"; "#;
        for (call, n) in [
            (r#"s.split("")"#, "14"),
            ("w.split(' ')", "12"),
            (r#"w.split(" ", 50)"#, "12"),
            ("w.split()", "12"),
            (r#"s.split_rev("")"#, "14"),
            ("w.split_rev(' ')", "12"),
            ("s.to_chars()", "12"),
            ("s.to_blob()", "12"),
        ] {
            let e = ours.eval::<Dynamic>(&format!("{s}{call}")).unwrap_err();
            let EvalAltResult::ErrorDataTooLarge(what, _) = *e else {
                panic!("{call}: {e}");
            };
            assert!(what.contains(&format!("({n} elements)")), "{call}: {what}");
        }
        assert!(ours
            .eval::<Array>(r#"let s = "abcdefgh"; s.split("")"#)
            .is_ok());
    }
}
