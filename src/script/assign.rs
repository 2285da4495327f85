//! `doc.component("x").fixed = true`: Rhai cannot assign to a property of a call's
//! result (a parse error), while a macro author writes exactly that
//! (`swAssy.GetComponentByName("x").Fixed = True` has no VBA equivalent problem).
//! fitup's handles share their document, so setting the property on the call's
//! result is what the user means: such an assignment is spelled as a call of the
//! property's setter method, `doc.component("x").set_fixed(true)` (every property
//! setter is also registered as `set_<name>`).
//!
//! Only an assignment `… ) . name = value` or `… ] . name = value` whose `name` has a
//! setter is rewritten, and only when Rhai refused the script for it; the line count
//! is unchanged, so errors keep their lines.

use std::collections::HashSet;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Tok {
    /// An identifier at `start..end`.
    Ident(usize, usize),
    /// A punctuation character at the offset.
    Punct(char, usize),
    /// A single `=` (assignment) at the offset.
    Assign(usize),
    /// Anything else (operators of several characters, numbers, strings).
    Other,
}

/// The script's tokens, enough to find assignments: strings, characters and comments
/// are skipped as one token.
fn tokens(text: &str) -> Vec<Tok> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        match c {
            b' ' | b'\t' | b'\r' | b'\n' => i += 1,
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                // Rhai block comments nest
                i = crate::diagnostics::nested_comment_end(b, i);
                out.push(Tok::Other);
            }
            b'"' | b'`' | b'\'' => {
                let q = c;
                i += 1;
                while i < b.len() && b[i] != q {
                    if b[i] == b'\\' && q != b'`' {
                        i += 1;
                    }
                    i += 1;
                }
                i += 1;
                out.push(Tok::Other);
            }
            b'=' => {
                let next = b.get(i + 1).copied();
                let prev = i.checked_sub(1).map(|p| b[p]);
                let compound = matches!(
                    prev,
                    Some(
                        b'=' | b'!'
                            | b'<'
                            | b'>'
                            | b'+'
                            | b'-'
                            | b'*'
                            | b'/'
                            | b'%'
                            | b'&'
                            | b'|'
                            | b'^'
                    )
                );
                if next == Some(b'=') || next == Some(b'>') {
                    out.push(Tok::Other);
                    i += 2;
                } else {
                    out.push(if compound { Tok::Other } else { Tok::Assign(i) });
                    i += 1;
                }
            }
            c if c == b'_' || c.is_ascii_alphabetic() || c >= 0x80 => {
                let s = i;
                while i < b.len() && (b[i] == b'_' || b[i].is_ascii_alphanumeric() || b[i] >= 0x80)
                {
                    i += 1;
                }
                out.push(Tok::Ident(s, i));
            }
            b'(' | b')' | b'[' | b']' | b'{' | b'}' | b';' | b'.' | b',' => {
                out.push(Tok::Punct(c as char, i));
                i += 1;
            }
            _ => {
                out.push(Tok::Other);
                i += 1;
            }
        }
    }
    out
}

/// The script with every `call(…).name = value` (and `x[i].name = value`) whose
/// `name` is in `setters` spelled `call(…).set_name(value)`; `None` when there is
/// none.
pub(crate) fn rewrite(text: &str, setters: &HashSet<String>) -> Option<String> {
    let toks = tokens(text);
    // (offset, text to insert, bytes to remove)
    let mut edits: Vec<(usize, String, usize)> = Vec::new();
    for k in 0..toks.len() {
        let Tok::Assign(eq) = toks[k] else { continue };
        let (Some(Tok::Ident(s, e)), Some(Tok::Punct('.', _)), Some(Tok::Punct(')' | ']', _))) = (
            k.checked_sub(1).map(|j| toks[j]),
            k.checked_sub(2).map(|j| toks[j]),
            k.checked_sub(3).map(|j| toks[j]),
        ) else {
            continue;
        };
        let name = &text[s..e];
        if !setters.contains(name) {
            continue;
        }
        // the value ends at `;`, `,` or a closer at its own depth, or the end
        let mut depth = 0i32;
        let mut end = text.len();
        for t in &toks[k + 1..] {
            match *t {
                Tok::Punct('(' | '[' | '{', _) => depth += 1,
                Tok::Punct(')' | ']' | '}', at) => {
                    if depth == 0 {
                        end = at;
                        break;
                    }
                    depth -= 1;
                }
                Tok::Punct(';' | ',', at) if depth == 0 => {
                    end = at;
                    break;
                }
                _ => {}
            }
        }
        let value_end = text[..end].trim_end().len();
        if value_end <= eq + 1 {
            continue;
        }
        // `name =` → `set_name(`, and `)` after the value
        edits.push((s, format!("set_{name}("), eq + 1 - s));
        edits.push((value_end, ")".to_string(), 0));
    }
    if edits.is_empty() {
        return None;
    }
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = text.to_string();
    for (at, insert, remove) in edits {
        out.replace_range(at..at + remove, &insert);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn setters() -> HashSet<String> {
        ["fixed", "transform"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    #[test]
    fn call_results_get_their_setter() {
        let s = setters();
        assert_eq!(
            rewrite("doc.component(\"a\").fixed = true;\nlet x = 1;", &s).unwrap(),
            "doc.component(\"a\").set_fixed( true);\nlet x = 1;"
        );
        assert_eq!(
            rewrite(
                "for c in doc.components() { doc.component(c.name).fixed = f(1, [2]) }",
                &s
            )
            .unwrap(),
            "for c in doc.components() { doc.component(c.name).set_fixed( f(1, [2])) }"
        );
        assert_eq!(
            rewrite("cs[0].transform = pose(1,2,3,0,0,0)", &s).unwrap(),
            "cs[0].set_transform( pose(1,2,3,0,0,0))"
        );
    }

    #[test]
    fn everything_else_stays() {
        let s = setters();
        for text in [
            "let c = doc.component(\"a\"); c.fixed = true;",
            "doc.component(\"a\").fixed == true;",
            "doc.component(\"a\").color = 1;",
            "doc.component(\"a\").fixed += 1;",
            "let s = \"x).fixed = 1\";",
            "// f(x).fixed = 1\n",
        ] {
            assert_eq!(rewrite(text, &s), None, "{text}");
        }
    }
}
