//! The house keeps its floors: every `crate::MODULE` path in the library's code points
//! to a module on a lower layer than its own, so there is no arrow back up and no circle
//! across modules, and docs/architecture.md shows the same layers as the code.
//!
//! Read from the source text (comments, `tests.rs`, `test_*.rs` and `#[cfg(test)] mod`
//! blocks left out: test scaffolding may reach any layer).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The library's top-level modules, lowest layer first. A module may use only modules
/// of earlier rows. A new module must be placed here (the test says so).
const LAYERS: &[&[&str]] = &[
    &["math", "fsutil"],
    &["project"],
    &["diagnostics", "mesh"],
    &["collision", "kinematics", "files"],
    &["planning", "document"],
    &["workspace", "db", "viewer", "demo"],
    &["sequence", "manipulator"],
    &["skills"],
    &["options"],
    &["script"],
    &["watch"],
    &["cli"],
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|row| row.contains(&module))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// `crate::NAME` paths in the non-test code of one file, with their lines.
fn crate_paths(text: &str) -> Vec<(usize, String)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let next = lines.get(i + 1).map(|l| l.trim_start()).unwrap_or("");
        if line.trim() == "#[cfg(test)]"
            && (next.starts_with("mod ") || next.starts_with("pub(crate) mod "))
        {
            break;
        }
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(at) = rest.find("crate::") {
            let tail = &rest[at + "crate::".len()..];
            let name: String = tail
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            out.push((i + 1, name));
            rest = tail;
        }
    }
    out
}

#[test]
fn every_import_points_down_the_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut modules = BTreeMap::new();
    let mut wrong = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&src).unwrap();
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        if ["lib", "main", "test_support"].contains(&top.as_str()) {
            continue;
        }
        let file_name = rel.file_name().unwrap().to_string_lossy();
        if file_name == "tests.rs" || file_name.starts_with("test_") {
            continue;
        }
        let Some(own) = layer_of(&top) else {
            wrong.push(format!(
                "src/{}: module `{top}` is on no layer of LAYERS",
                rel.display()
            ));
            continue;
        };
        modules.insert(top.clone(), own);
        let text = std::fs::read_to_string(f).unwrap();
        for (line, name) in crate_paths(&text) {
            if name == top {
                continue;
            }
            match layer_of(&name) {
                Some(l) if l < own => {}
                Some(l) => wrong.push(format!(
                    "src/{}:{line}: `{top}` (layer {}) uses `crate::{name}` (layer {})",
                    rel.display(),
                    own + 1,
                    l + 1
                )),
                None => {} // a macro or an item of lib.rs, not a module
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "arrows that run up or sideways:\n{}",
        wrong.join("\n")
    );
    // Every layer's module exists: LAYERS is the house, not a wish list.
    for row in LAYERS {
        for m in *row {
            assert!(
                modules.contains_key(*m),
                "LAYERS names `{m}`, which src/ does not have"
            );
        }
    }
}

#[test]
fn architecture_doc_shows_the_layers_of_the_code() {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/architecture.md"))
            .unwrap();
    let mut table = String::from("| layer | modules |\n|---|---|\n");
    for (i, row) in LAYERS.iter().enumerate() {
        let names: Vec<String> = row.iter().map(|m| format!("`{m}`")).collect();
        table.push_str(&format!("| {} | {} |\n", i + 1, names.join(", ")));
    }
    assert!(
        doc.contains(&table),
        "docs/architecture.md should hold the layer table of tests/it/layers.rs:\n{table}"
    );
}
