//! Hostile names, driven through the real binary in temporary projects: names that
//! differ only by Unicode normalisation (NFC/NFD), by case, or by an invisible
//! character; bidi overrides and terminal escape sequences in names; an NFD name
//! looked up by its NFC spelling from a script.
//!
//! Every case ends within the bound (30 s, a hang bound, not a speed assertion);
//! refused documents are refused with file, line and column and the character as
//! `U+XXXX`; nothing fitup prints holds a raw control or invisible character; and
//! every user file keeps its exact bytes (compared in full, stronger than a hash).

use crate::common;
use common::{snapshot, Snapshot};

use common::{project, spawn};
use std::path::Path;
use std::time::Duration;

const HANG: Duration = Duration::from_secs(30);

/// Exit code and combined output of `fitup ARGS` in `dir`; fails when it hangs.
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let o = common::finish(spawn(dir, args), &args.join(" "), HANG);
    (o.status.code().unwrap_or(-1), common::text(&o))
}

fn unchanged(before: &Snapshot, dir: &Path) {
    common::assert_kept(before, &snapshot(dir));
}

/// No raw control character (other than newline and tab) and no invisible / bidi
/// character in what fitup printed.
fn nothing_raw(out: &str) {
    for c in out.chars() {
        if c == '\n' || c == '\t' {
            continue;
        }
        assert!(
            fitup::diagnostics::hidden_char(c).is_none(),
            "raw U+{:04X} printed: {out:?}",
            c as u32
        );
    }
}

/// A document of `components` (name, part) over the demo's `plate_a` and `screw`
/// meshes, with `extra` appended (mates, …).
fn doc(components: &[(&str, &str)], extra: &str) -> String {
    let mut t = String::from(
        "parts:\n  plate:\n    stl: meshes/plate_a.stl\n  screw:\n    stl: meshes/screw.stl\ncomponents:\n",
    );
    for (i, (name, part)) in components.iter().enumerate() {
        t += &format!(
            "  - name: {name}\n    part: {part}\n    transform: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [{}, 0, 0, 1]]\n",
            300 * i
        );
    }
    t + extra
}

/// The 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

const NFC_E: &str = "caf\u{e9}"; // café, composed
const NFD_E: &str = "cafe\u{301}"; // café, e + combining acute

#[test]
fn nfc_and_nfd_spellings_are_one_name() {
    let dir = project();
    let p = dir.path();
    // two components spelled NFC and NFD: a duplicate, located at the second
    let text = doc(&[(NFC_E, "plate"), (NFD_E, "screw")], "");
    std::fs::write(p.join("models/dup.yaml"), &text).unwrap();
    // two parts whose keys differ only by normalisation: a duplicate key
    let parts = format!(
        "parts:\n  {NFC_E}:\n    stl: meshes/plate_a.stl\n  {NFD_E}:\n    stl: meshes/screw.stl\ncomponents:\n  - name: a\n    part: {NFC_E}\n"
    );
    std::fs::write(p.join("models/dup_parts.yaml"), &parts).unwrap();
    let before = snapshot(p);
    let (code, out) = run(p, &["check", "models/dup.yaml"]);
    assert_ne!(code, 0, "{out}");
    let line = line_of(&text, NFD_E);
    assert!(
        out.contains(&format!("models/dup.yaml:{line}:"))
            && out.contains("duplicate component name"),
        "{out}"
    );
    nothing_raw(&out);
    let (code, out) = run(p, &["check", "models/dup_parts.yaml"]);
    assert_ne!(code, 0, "{out}");
    assert!(
        out.contains("dup_parts.yaml:4:") && out.contains("duplicate key") && out.contains("NFC"),
        "{out}"
    );
    unchanged(&before, p);
}

#[test]
fn an_nfd_name_is_found_by_its_nfc_spelling_from_a_script() {
    let dir = project();
    let p = dir.path();
    // written decomposed in the file, with an NFD mate dimension and a CJK one
    let text = doc(&[(NFD_E, "plate"), ("ねじ", "screw")], "");
    std::fs::write(p.join("models/nfd.yaml"), &text).unwrap();
    std::fs::write(
        p.join("scripts/find.rhai"),
        format!(
            "let d = open_doc(\"models/nfd.yaml\");\n\
             print(\"composed: \" + d.component(\"{NFC_E}\").name);\n\
             print(\"decomposed: \" + d.component(\"{NFD_E}\").name);\n\
             print(\"cjk: \" + d.component(\"ねじ\").name);\n\
             d.component(\"{NFC_E}\").translate(0, 0, 1);\n\
             print(\"moved\");\n"
        ),
    )
    .unwrap();
    let before = snapshot(p);
    let (code, out) = run(p, &["run", "scripts/find.rhai"]);
    assert_eq!(code, 0, "{out}");
    // the name is kept in NFC: both spellings find it, and it prints composed
    assert!(out.contains(&format!("composed: {NFC_E}")), "{out}");
    assert!(out.contains(&format!("decomposed: {NFC_E}")), "{out}");
    assert!(out.contains("cjk: ねじ") && out.contains("moved"), "{out}");
    unchanged(&before, p);
    // the demo's `D1@角度1`-style dimension lookups keep working
    std::fs::write(
        p.join("scripts/dim.rhai"),
        "let d = open_doc(\"models/cell.yaml\");\nlet n = d.dimensions();\nprint(`dims ${n.len()}`);\nfor x in n { print(x); d.dimension(x); }\n",
    )
    .unwrap();
    let (code, out) = run(p, &["run", "scripts/dim.rhai"]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("dims"), "{out}");
}

#[test]
fn case_only_collisions_are_warned_by_check_and_run() {
    let dir = project();
    let p = dir.path();
    let text = doc(&[("Plate", "plate"), ("plate", "screw")], "");
    std::fs::write(p.join("models/case.yaml"), &text).unwrap();
    std::fs::write(
        p.join("scripts/case.rhai"),
        "let d = open_doc(\"models/case.yaml\");\nprint(d.component(\"plate\").part);\n",
    )
    .unwrap();
    let before = snapshot(p);
    let (code, out) = run(p, &["check", "models/case.yaml"]);
    assert_eq!(code, 0, "{out}");
    let second = line_of(&text, "name: plate");
    assert!(
        out.contains(&format!("warning: models/case.yaml:{second}:"))
            && out.contains("`Plate`")
            && out.contains("differ only by case"),
        "{out}"
    );
    assert!(out.contains("1 warning(s)"), "{out}");
    let (code, out) = run(p, &["run", "scripts/case.rhai"]);
    assert_eq!(code, 0, "{out}");
    // still two names: `plate` is the screw
    assert!(
        out.contains("differ only by case") && out.contains("screw"),
        "{out}"
    );
    unchanged(&before, p);
}

#[test]
fn invisible_and_bidi_characters_in_names_are_refused_with_their_place() {
    let dir = project();
    let p = dir.path();
    let cases: &[(&str, &str, &str)] = &[
        ("zwsp", "plate\u{200b}", "U+200B"),
        ("zwj", "pla\u{200d}te", "U+200D"),
        ("rlo", "evil\u{202e}gpj.exe", "U+202E"),
        ("isolate", "a\u{2066}b\u{2069}", "U+2066"),
        ("bom", "\u{feff}plate", "U+FEFF"),
        ("soft_hyphen", "pla\u{ad}te", "U+00AD"),
        ("tag", "x\u{e0041}", "U+E0041"),
    ];
    for (file, name, code_point) in cases {
        // once as a component name, once as a part key, once in a mate name
        for (kind, text) in [
            ("component", doc(&[("ok", "plate"), (name, "screw")], "")),
            (
                "part",
                format!("parts:\n  {name}:\n    stl: meshes/plate_a.stl\ncomponents: []\n"),
            ),
            (
                "mate",
                doc(
                    &[("a", "plate"), ("b", "screw")],
                    &format!("mates:\n  - name: {name}\n    type: coincident\n    entities: [a/origin, b/origin]\n"),
                ),
            ),
        ] {
            let rel = format!("models/{file}_{kind}.yaml");
            std::fs::write(p.join(&rel), &text).unwrap();
            let before = snapshot(p);
            let (code, out) = run(p, &["check", &rel]);
            assert_ne!(code, 0, "{rel}: {out}");
            let line = line_of(&text, name);
            let col = text.lines().nth(line - 1).unwrap()
                .chars()
                .position(|c| fitup::diagnostics::hidden_char(c).is_some())
                .unwrap()
                + 1;
            assert!(
                out.contains(&format!("{rel}:{line}:{col}: {code_point}")),
                "{rel} (expected line {line} column {col}): {out}"
            );
            nothing_raw(&out);
            unchanged(&before, p);
        }
    }
}

#[test]
fn escape_sequences_are_refused_and_never_printed_raw() {
    let dir = project();
    let p = dir.path();
    // raw ESC and BEL in a plain name; an escape written as a YAML escape in a quoted
    // name (`"\e[2J"`, no raw byte in the file); an OSC title sequence in a part key
    let raw = doc(&[("ok", "plate"), ("x\u{1b}[31mred\u{7}", "screw")], "");
    let quoted = doc(&[("ok", "plate"), ("\"clear\\e[2J\\e[H\"", "screw")], "");
    let osc =
        "parts:\n  \"t\\e]0;pwned\\a\":\n    stl: meshes/plate_a.stl\ncomponents: []\n".to_string();
    let cases = [("raw", raw), ("quoted", quoted), ("osc", osc)];
    for (file, text) in &cases {
        let rel = format!("models/esc_{file}.yaml");
        std::fs::write(p.join(&rel), text).unwrap();
        let before = snapshot(p);
        let (code, out) = run(p, &["check", &rel]);
        assert_ne!(code, 0, "{rel}: {out}");
        assert!(out.contains(&format!("{rel}:")), "{rel}: {out}");
        assert!(
            out.contains("U+001B") || out.contains("U+0007"),
            "{rel}: {out}"
        );
        nothing_raw(&out);
        unchanged(&before, p);
    }
    // a script that prints escapes and bidi overrides, and asks for such a name:
    // the output and the not-found error are escaped
    std::fs::write(
        p.join("scripts/esc.rhai"),
        "print(\"a\\x1b[2Jb\\u202ec\");\nlet d = open_doc(\"models/cell.yaml\");\nd.component(\"zz\\x1b]0;t\\x07\");\n",
    )
    .unwrap();
    let before = snapshot(p);
    let (code, out) = run(p, &["run", "scripts/esc.rhai"]);
    assert_ne!(code, 0, "{out}");
    assert!(out.contains("a<U+001B>[2Jb<U+202E>c"), "{out}");
    assert!(out.contains("zz<U+001B>]0;t<U+0007>"), "{out}");
    nothing_raw(&out);
    unchanged(&before, p);
}
