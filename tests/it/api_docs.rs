//! docs/api.md is exactly what `fitup docs` generates from the registered functions
//! (regenerate with `cargo run -- docs` or `FITUP_BLESS=1 cargo test --test api_docs`).

#[test]
fn committed_api_reference_is_current() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/api.md");
    let generated = fitup::script::api_reference();
    if std::env::var_os("FITUP_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "docs/api.md is stale: run `cargo run -- docs`"
    );
}

/// The Python stubs' docstrings (`python/fitup/_fitup.pyi`, what editors show) are
/// the doc comments of `python/src` (what PyO3 gives the module as `__doc__`), for
/// every class, module function and public member the stubs declare, both cleaned
/// as `inspect.cleandoc` cleans them. pytest's `test_the_stub_docstrings_are_the_modules`
/// checks the same on the built module; this one runs in the default `cargo test`,
/// without Python, so a stale stub fails in minutes rather than at CI's last stage.
#[test]
fn python_stub_docstrings_are_the_doc_comments_of_python_src() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut docs = std::collections::BTreeMap::new();
    let mut sources: Vec<_> = std::fs::read_dir(root.join("python/src"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    sources.sort();
    for file in &sources {
        rust_docs(&std::fs::read_to_string(file).unwrap(), &mut docs);
    }
    let stubs = std::fs::read_to_string(root.join("python/fitup/_fitup.pyi")).unwrap();
    let mut seen = 0;
    for (item, stub) in stub_docs(&stubs) {
        let name = match &item {
            (Some(class), Some(member)) => format!("{class}.{member}"),
            (Some(class), None) => class.clone(),
            (None, Some(function)) => function.clone(),
            (None, None) => unreachable!(),
        };
        let Some(rust) = docs.get(&item) else {
            panic!("`{name}` is in python/fitup/_fitup.pyi but no documented #[pyclass], #[pyfunction] or #[pymethods] member of python/src has that name")
        };
        let want = cleandoc(rust);
        let got = stub.as_deref().map(cleandoc);
        if got.as_deref() != Some(want.as_str()) {
            let line = |s: &str, i: usize| s.lines().nth(i).unwrap_or("(none)").to_string();
            let got = got.unwrap_or_default();
            let first = (0..)
                .find(|&i| line(&got, i) != line(&want, i))
                .unwrap_or(0);
            panic!(
                "`{name}`: the stub's docstring in python/fitup/_fitup.pyi differs from its doc comment in python/src \
                 (line {}: stub {:?}, doc comment {:?}); run `python python/tools/stub_docs.py` with the package installed",
                first + 1,
                line(&got, first),
                line(&want, first)
            );
        }
        seen += 1;
    }
    assert!(seen > 50, "only {seen} stub items read");
}

/// A stub item: (class, member) — (None, Some(f)) a module function, (Some(c), None)
/// a class.
type Item = (Option<String>, Option<String>);

/// `inspect.cleandoc`: tabs expanded, the first line's leading whitespace and the
/// other lines' common indentation removed, leading and trailing empty lines dropped.
fn cleandoc(doc: &str) -> String {
    let doc = doc.replace('\t', "        ");
    let mut lines: Vec<String> = doc.split('\n').map(str::to_string).collect();
    let margin = lines[1..]
        .iter()
        .filter(|l| !l.trim_start().is_empty())
        .map(|l| l.chars().count() - l.trim_start().chars().count())
        .min();
    lines[0] = lines[0].trim_start().to_string();
    if let Some(m) = margin {
        for l in &mut lines[1..] {
            *l = l.chars().skip(m).collect();
        }
    }
    while lines.last().is_some_and(String::is_empty) {
        lines.pop();
    }
    while lines.first().is_some_and(String::is_empty) {
        lines.remove(0);
    }
    lines.join("\n")
}

/// The value of `key = "…"` in an attribute, if any.
fn attr_value<'a>(attr: &'a str, key: &str) -> Option<&'a str> {
    let at = attr.find(&format!("{key} = \""))? + key.len() + 4;
    Some(&attr[at..at + attr[at..].find('"')?])
}

/// The doc comments (`///` lines joined, as PyO3 joins them) of a python/src file's
/// `#[pyclass]` structs (under their Python name), `#[pyfunction]`s and the
/// functions of its `#[pymethods]` blocks (under `#[pyo3(name)]` or `#[getter(name)]`
/// when given). Relies on rustfmt's layout: an impl block ends at a `}` in column 0.
fn rust_docs(text: &str, out: &mut std::collections::BTreeMap<Item, String>) {
    let mut doc: Vec<&str> = Vec::new();
    let mut attrs: Vec<&str> = Vec::new();
    let mut classes: std::collections::HashMap<String, String> = Default::default();
    let mut methods_of: Option<String> = None;
    let mut in_attr = false;
    for line in text.lines() {
        let t = line.trim_start();
        if in_attr {
            attrs.push(t);
            in_attr = !t.ends_with(']');
            continue;
        }
        if let Some(d) = t.strip_prefix("///") {
            doc.push(d);
            continue;
        }
        if t.starts_with("//") {
            continue; // a plain comment between the doc and the item
        }
        if t.starts_with("#[") {
            attrs.push(t);
            in_attr = !t.ends_with(']');
            continue;
        }
        if line == "}" {
            methods_of = None;
        }
        let rust_name = |rest: &str| -> String {
            rest.chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect()
        };
        let has = |a: &str| attrs.iter().any(|x| x.starts_with(a));
        let item = t.strip_prefix("pub ").unwrap_or(t);
        let item = item.strip_prefix("pub(crate) ").unwrap_or(item);
        if let Some(rest) = item.strip_prefix("struct ") {
            if let Some(attr) = attrs.iter().find(|a| a.starts_with("#[pyclass")) {
                let rust = rust_name(rest);
                let py = attr_value(attr, "name").map_or(rust.clone(), str::to_string);
                classes.insert(rust, py.clone());
                out.insert((Some(py), None), doc.join("\n"));
            }
        } else if let Some(rest) = item.strip_prefix("impl ") {
            if has("#[pymethods") {
                let rust = rust_name(rest);
                methods_of = Some(classes.get(&rust).cloned().unwrap_or(rust));
            }
        } else if let Some(rest) = item.strip_prefix("fn ") {
            let rust = rust_name(rest);
            let renamed = attrs.iter().find_map(|a| {
                let pyo3_name = a.strip_prefix("#[pyo3(").filter(|r| r.starts_with("name"));
                pyo3_name.and_then(|r| attr_value(r, "name")).or_else(|| {
                    let g = a.strip_prefix("#[getter(")?;
                    Some(&g[..g.find(')')?])
                })
            });
            let py = renamed.map_or(rust, str::to_string);
            match (&methods_of, has("#[pyfunction")) {
                (Some(class), _)
                    if line.starts_with("    fn ") || line.starts_with("    pub fn ") =>
                {
                    out.insert((Some(class.clone()), Some(py)), doc.join("\n"));
                }
                (None, true) => {
                    out.insert((None, Some(py)), doc.join("\n"));
                }
                _ => {}
            }
        }
        doc.clear();
        attrs.clear();
    }
}

/// Every class, module function and public member (not `_…`) the stubs declare, with
/// its docstring's text as written (None: no docstring).
fn stub_docs(text: &str) -> Vec<(Item, Option<String>)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut class: Option<String> = None;
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let t = line.trim_start();
        let indent = line.len() - t.len();
        let name = |rest: &str| -> String {
            rest.chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect()
        };
        let item = if let Some(rest) = t.strip_prefix("class ").filter(|_| indent == 0) {
            class = Some(name(rest));
            Some((class.clone(), None))
        } else if let Some(rest) = t.strip_prefix("def ") {
            if indent == 0 {
                class = None;
            }
            let n = name(rest);
            (!n.starts_with('_')).then(|| (class.clone().filter(|_| indent > 0), Some(n)))
        } else {
            None
        };
        i += 1;
        let Some(item) = item else {
            // A docstring not after a header (the module's) is skipped whole.
            if let Some(q) = t
                .strip_prefix("r\"\"\"")
                .or_else(|| t.strip_prefix("\"\"\""))
            {
                if !q.contains("\"\"\"") {
                    while i < lines.len() && !lines[i].contains("\"\"\"") {
                        i += 1;
                    }
                    i += 1;
                }
            }
            continue;
        };
        // The header may run over several lines: it ends at a line whose code ends
        // with `:` (or `: ...`) with its brackets closed.
        let mut depth = 0i32;
        let mut header_end = i - 1;
        loop {
            let l = lines[header_end];
            depth += l.matches(['(', '[']).count() as i32 - l.matches([')', ']']).count() as i32;
            let code = l.trim_end();
            if depth <= 0 && (code.ends_with(':') || code.ends_with(": ..."))
                || header_end + 1 >= lines.len()
            {
                break;
            }
            header_end += 1;
        }
        i = header_end + 1;
        let next = lines.get(i).map_or("", |l| l.trim_start());
        let open = next
            .strip_prefix("r\"\"\"")
            .or_else(|| next.strip_prefix("\"\"\""));
        let doc = open.map(|first| {
            if let Some(end) = first.find("\"\"\"") {
                i += 1;
                return first[..end].to_string();
            }
            let mut text = vec![first.to_string()];
            i += 1;
            while i < lines.len() {
                let l = lines[i];
                i += 1;
                if let Some(end) = l.find("\"\"\"") {
                    text.push(l[..end].to_string());
                    break;
                }
                text.push(l.to_string());
            }
            text.join("\n")
        });
        out.push((item, doc));
    }
    out
}
