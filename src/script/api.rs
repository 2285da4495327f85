//! The registry of script functions: every binding is registered through [`Api`] with
//! its signature and doc text, so `fitup docs` generates `docs/api.md` from exactly what
//! the engine knows and the reference never drifts from the code.

use super::Context;
use rhai::{Engine, FuncRegistration, RhaiNativeFunc};
use std::sync::Arc;

/// What a registered function may return: what Rhai keeps in a `Dynamic` (with its
/// `sync` feature: cloneable, shared between threads, no borrowed data).
pub trait Returned: Clone + Send + Sync + 'static {}

impl<T: Clone + Send + Sync + 'static> Returned for T {}

/// One documented script function or property.
#[derive(Debug, Clone, PartialEq)]
pub struct ApiEntry {
    /// Section title (Transform, Document, …).
    pub section: String,
    /// Signature as users write it.
    pub signature: String,
    /// What it does, with units and frames.
    pub doc: String,
}

/// Registers functions into an engine and keeps their documentation.
pub struct Api<'e> {
    engine: &'e mut Engine,
    entries: Vec<ApiEntry>,
    sections: Vec<(String, String)>,
    /// The option tables of each section: (section, heading, Markdown table).
    options: Vec<(String, String, String)>,
    /// Typed overloads registered without an entry of their own.
    overloads: usize,
    /// Names of the properties that have a setter.
    setters: std::collections::HashSet<String>,
    /// The `Type.set_prop` method aliases registered (an entry of the same name
    /// registered later replaces the alias).
    aliases: std::collections::HashSet<String>,
}

/// The Rhai function name for a signature: `name(..)`, `Type.name(..)`, `Type.prop`
/// (getter/setter) or an operator `A op B`.
fn rhai_name(signature: &str, property: Option<&str>) -> String {
    let head = signature.split(" -> ").next().unwrap_or(signature).trim();
    if let Some(prefix) = property {
        let prop = head
            .rsplit('.')
            .next()
            .unwrap_or(head)
            .split_whitespace()
            .next()
            .unwrap_or(head);
        return format!("{prefix}${prop}");
    }
    match head.find('(') {
        Some(i) => head[..i]
            .rsplit('.')
            .next()
            .unwrap_or(&head[..i])
            .to_string(),
        None => head.split_whitespace().nth(1).unwrap_or(head).to_string(),
    }
}

impl<'e> Api<'e> {
    fn new(engine: &'e mut Engine) -> Self {
        Self {
            engine,
            entries: Vec::new(),
            sections: Vec::new(),
            options: Vec::new(),
            overloads: 0,
            setters: Default::default(),
            aliases: Default::default(),
        }
    }

    /// Starts a section of the reference.
    pub fn section(&mut self, title: &str, intro: &str) {
        self.sections.push((title.to_string(), intro.to_string()));
    }

    /// Documents the options map of the section's requests: the table of `T`'s
    /// vocabulary (key, type, unit, default, meaning), printed after the section's
    /// functions under `heading`. The bindings read the map with
    /// [`read_options`](super::convert::read_options), so the table is what they take.
    pub fn options<T: crate::options::Options>(&mut self, heading: &str) {
        let section = self
            .sections
            .last()
            .map(|s| s.0.clone())
            .unwrap_or_default();
        self.options
            .push((section, heading.to_string(), T::markdown()));
    }

    /// Registers a custom type under its script name.
    pub fn type_<T: Clone + Send + Sync + 'static>(&mut self, name: &str) {
        self.engine.register_type_with_name::<T>(name);
    }

    /// Makes a custom type iterable (`for x in value`), each item what its
    /// `IntoIterator` gives; documented by the type's own entries.
    pub fn iterable<T>(&mut self)
    where
        T: Clone + Send + Sync + 'static + IntoIterator,
        <T as IntoIterator>::Item: Clone + Send + Sync + 'static,
    {
        self.engine.register_iterator::<T>();
    }

    /// Registers an index getter (`Type[i]`) of a custom type.
    pub fn index_get<A: 'static, const N: usize, const X: bool, R: Returned, const F: bool>(
        &mut self,
        signature: &str,
        doc: &str,
        func: impl RhaiNativeFunc<A, N, X, R, F> + Send + Sync + 'static,
    ) {
        // Rhai's name of an index getter (`Engine::register_indexer_get`).
        self.add("index$get$".to_string(), signature, doc, func);
    }

    fn add<A: 'static, const N: usize, const X: bool, R: Returned, const F: bool>(
        &mut self,
        name: String,
        signature: &str,
        doc: &str,
        func: impl RhaiNativeFunc<A, N, X, R, F> + Send + Sync + 'static,
    ) {
        let section = self
            .sections
            .last()
            .map(|s| s.0.clone())
            .unwrap_or_default();
        let comments: Vec<String> = doc.lines().map(|l| format!("/// {l}")).collect();
        if let Some(head) = signature.split('(').next() {
            if self.aliases.remove(head) {
                // this entry replaces the setter's alias of the same name
                self.overloads -= 1;
            }
        }
        FuncRegistration::new(name)
            .with_comments([comments.join("\n")])
            .register_into_engine(self.engine, func);
        self.entries.push(ApiEntry {
            section,
            signature: signature.to_string(),
            doc: doc.to_string(),
        });
    }

    /// Registers a function or operator.
    pub fn f<A: 'static, const N: usize, const X: bool, R: Returned, const F: bool>(
        &mut self,
        signature: &str,
        doc: &str,
        func: impl RhaiNativeFunc<A, N, X, R, F> + Send + Sync + 'static,
    ) {
        self.add(rhai_name(signature, None), signature, doc, func);
    }

    /// Registers a typed overload of a function documented with [`Api::f`] under the
    /// same `signature` (no entry of its own in the reference): Rhai picks it when
    /// the argument types match exactly, skipping the `Dynamic` conversions of the
    /// general form.
    pub fn overload<A: 'static, const N: usize, const X: bool, R: Returned, const F: bool>(
        &mut self,
        signature: &str,
        func: impl RhaiNativeFunc<A, N, X, R, F> + Send + Sync + 'static,
    ) {
        FuncRegistration::new(rhai_name(signature, None)).register_into_engine(self.engine, func);
        self.overloads += 1;
    }

    /// Registers a property getter (`Type.prop -> R`).
    pub fn get<A: 'static, const N: usize, const X: bool, R: Returned, const F: bool>(
        &mut self,
        signature: &str,
        doc: &str,
        func: impl RhaiNativeFunc<A, N, X, R, F> + Send + Sync + 'static,
    ) {
        self.add(rhai_name(signature, Some("get")), signature, doc, func);
    }

    /// Registers a property setter (`Type.prop = value`), documented with its getter,
    /// and the same setter as the method `set_prop(value)` (unless the type has its
    /// own `set_prop`): what `call().prop = value` is spelled as (see `assign.rs`).
    pub fn set<A: 'static, const N: usize, const X: bool, const F: bool>(
        &mut self,
        signature: &str,
        func: impl RhaiNativeFunc<A, N, X, (), F> + Clone + Send + Sync + 'static,
    ) {
        let name = rhai_name(signature, Some("set"));
        let comments = vec![format!("/// Sets `{signature}`.")];
        let prop = name.trim_start_matches("set$").to_string();
        let ty = signature.split('.').next().unwrap_or("");
        let own = format!("{ty}.set_{prop}(");
        if !self.entries.iter().any(|e| e.signature.starts_with(&own)) {
            FuncRegistration::new(format!("set_{prop}"))
                .with_comments([format!(
                    "/// Sets `{signature}` (the method form of the setter)."
                )])
                .register_into_engine(self.engine, func.clone());
            self.overloads += 1;
            self.aliases.insert(format!("{ty}.set_{prop}"));
        }
        self.setters.insert(prop);
        FuncRegistration::new(name)
            .with_comments(comments)
            .register_into_engine(self.engine, func);
        if let Some(e) = self
            .entries
            .iter_mut()
            .rev()
            .find(|e| e.signature.starts_with(signature))
        {
            if !e.signature.contains("(get/set)") {
                e.signature += " (get/set)";
            }
        }
    }
}

/// What [`register_all`] registered: the reference's sections, entries and option
/// tables, and how many undocumented typed overloads of documented functions were
/// added.
pub(crate) struct Registered {
    /// (title, intro) of each section, in order.
    pub sections: Vec<(String, String)>,
    /// Every documented function and property.
    pub entries: Vec<ApiEntry>,
    /// (section, heading, table) of each options map.
    pub options: Vec<(String, String, String)>,
    /// Typed overloads without an entry of their own (the registry test counts them).
    #[cfg_attr(not(test), allow(dead_code))]
    pub overloads: usize,
}

/// Registers the whole fitup API for a run (see [`Registered`]).
pub(crate) fn register_all(engine: &mut Engine, ctx: &Arc<Context>) -> Registered {
    let mut api = Api::new(engine);
    super::bind_math::register(&mut api);
    super::bind_document::register(&mut api, ctx);
    super::bind_edit::register(&mut api, ctx);
    super::bind_equations::register(&mut api);
    super::bind_assembly::register(&mut api);
    super::bind_files::register(&mut api, ctx);
    super::bind_interference::register(&mut api);
    super::bind_mass::register(&mut api);
    super::bind_mass::register_export(&mut api);
    super::bind_planning::register(&mut api);
    super::bind_robot::register(&mut api, ctx);
    #[cfg(feature = "db")]
    super::bind_db::register(&mut api, ctx);
    super::bind_sequence::register(&mut api);
    #[cfg(feature = "skills")]
    super::bind_skills::register(&mut api, ctx);
    super::bind_view::register(&mut api);
    let _ = ctx.setters.set(api.setters.clone());
    Registered {
        sections: api.sections,
        entries: api.entries,
        options: api.options,
        overloads: api.overloads,
    }
}

/// The scripting API reference as Markdown (what `fitup docs` writes to docs/api.md).
pub fn api_reference() -> String {
    let dir = std::env::temp_dir();
    let project = super::Project::new(&dir)
        .unwrap_or_else(|_| super::Project::new(std::path::Path::new("/")).expect("root"));
    let ctx = Arc::new(Context::new(
        project,
        Default::default(),
        Default::default(),
        Arc::new(|_| {}),
    ));
    let mut engine = Engine::new();
    let Registered {
        sections,
        entries,
        options,
        ..
    } = register_all(&mut engine, &ctx);
    let mut out = String::from(
        "# fitup scripting API\n\n\
         Generated by `fitup docs` from the functions registered in the engine; do not edit.\n\n\
         Units: **millimetres and radians** inside. Pose triples `X Y Z A B C` and joint arrays are \
         **degrees**; a dimension's `system_value` is SI (metres, radians) like the SolidWorks API. \
         Numbers may be written as integers or floats everywhere. Points and vectors are arrays `[x, y, z]`.\n\n\
         Files: paths are relative to the project folder (`--root`, else the nearest folder of the script holding `fitup.toml`, else the script's folder; see docs/scripting.md); a script \
         can only read and write inside it.\n",
    );
    for (title, intro) in &sections {
        out += &format!("\n## {title}\n\n{intro}\n\n| function | description |\n|---|---|\n");
        for e in entries.iter().filter(|e| &e.section == title) {
            out += &format!(
                "| `{}` | {} |\n",
                e.signature.replace('|', "\\|"),
                e.doc.replace('\n', " ").replace('|', "\\|")
            );
        }
        for (_, heading, table) in options.iter().filter(|o| &o.0 == title) {
            out += &format!("\n{heading}\n\n{table}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_from_signatures() {
        assert_eq!(rhai_name("pose(x, y) -> Transform", None), "pose");
        assert_eq!(
            rhai_name("Transform.inverse() -> Transform", None),
            "inverse"
        );
        assert_eq!(rhai_name("Transform * Transform -> Transform", None), "*");
        assert_eq!(
            rhai_name("Component.transform -> Transform", Some("get")),
            "get$transform"
        );
    }

    #[test]
    fn every_registered_function_is_documented() {
        let r = api_reference();
        for needle in [
            "open_doc",
            "translation",
            "Component.transform",
            "system_value",
            "D1@",
        ] {
            assert!(r.contains(needle), "{needle} missing from the reference");
        }
        // The engine's own list of global functions equals our documented entries.
        let ctx = Arc::new(Context::new(
            crate::script::Project::new(&std::env::temp_dir()).unwrap(),
            Default::default(),
            Default::default(),
            Arc::new(|_| {}),
        ));
        let mut engine = Engine::new_raw();
        let Registered {
            entries, overloads, ..
        } = register_all(&mut engine, &ctx);
        let setters = entries
            .iter()
            .filter(|e| e.signature.ends_with("(get/set)"))
            .count();
        assert_eq!(
            engine.gen_fn_signatures(false).len(),
            entries.len() + setters + overloads
        );
    }
}

#[cfg(test)]
mod box_tests {
    use crate::script::{run_script, Caches, Limits, Project, RunOptions};
    use std::sync::{Arc, Mutex};

    /// Runs `body` after opening the demo cell as `d`; the printed lines, or the error.
    fn run(body: &str) -> Result<Vec<String>, String> {
        let dir = tempfile::tempdir().unwrap();
        crate::demo::write_cell(&dir.path().join("models")).unwrap();
        let script = dir.path().join("main.rhai");
        std::fs::write(
            &script,
            format!("let d = open_doc(\"models/cell.yaml\");\n{body}\n"),
        )
        .unwrap();
        let lines = Arc::new(Mutex::new(Vec::new()));
        let sink = lines.clone();
        let opts = RunOptions {
            script,
            doc: None,
            project: Project::new(dir.path()).unwrap(),
            limits: Limits::default(),
            cancel: Default::default(),
            output: Arc::new(move |l: &str| sink.lock().unwrap().push(l.to_string())),
            args: Default::default(),
        };
        let out = run_script(&opts, &Arc::new(Caches::default()));
        out.result.map_err(|e| e.to_string())?;
        let lines = lines.lock().unwrap().clone();
        Ok(lines)
    }

    /// `aabb()` is a `Box` whose corners follow the component through the typed
    /// (float and integer) and general `translate` forms alike.
    #[test]
    fn boxes_follow_every_translate_form() {
        let lines = run("let s = d.component(\"screw4\");\n\
             let a = s.aabb();\n\
             s.translate(1.5, 0.0, 0.0);\n\
             s.translate(0, 2, 0);\n\
             s.translate(0, 0.0, 3);\n\
             s.translate([1, 1, 1]);\n\
             let b = s.aabb();\n\
             print(fmt([b.min[0] - a.min[0], b.max[1] - a.max[1], b.min[2] - a.min[2]]));\n\
             print(`${fmt(b.size[0] - a.size[0])} ${type_of(b)}`);\n\
             print(fmt(b.centre[0] - a.centre[0]));")
        .unwrap();
        assert_eq!(lines, ["[2.5, 3, 4]", "0 Box", "2.5"]);
    }

    /// A box prints with its corners; a non-number argument of `translate` is an
    /// error naming it.
    #[test]
    fn boxes_print_and_bad_translations_fail() {
        let lines = run("let b = d.aabb();\n\
             print(`${b}`);\n\
             print(`${b.min == d.aabb().min}`);")
        .unwrap();
        assert!(
            lines[0].starts_with("#{min: [") && lines[0].contains("max: ["),
            "{lines:?}"
        );
        assert_eq!(lines[1], "true");
        let e = run("d.component(\"screw4\").translate(\"x\", 0, 0);").unwrap_err();
        assert!(e.contains("dx"), "{e}");
    }
}

#[cfg(test)]
mod document_cache_tests {
    use crate::document::Document;
    use crate::script::DocumentCache;

    /// A cached document is handed out only while its YAML and meshes are unchanged.
    #[test]
    fn cached_documents_follow_their_files() {
        let dir = tempfile::tempdir().unwrap();
        crate::demo::write_cell(&dir.path().join("models")).unwrap();
        let path = dir.path().join("models/cell.yaml");
        let doc = Document::open(&path).unwrap();
        let mut cache = DocumentCache::default();
        assert!(cache.get(dir.path(), &path).is_none());
        cache.insert(dir.path(), &path, &doc);
        let copy = cache.get(dir.path(), &path).expect("unchanged files");
        assert_eq!(copy.components().len(), doc.components().len());
        // a mesh replaced by another writer (new inode) invalidates the copy
        let mesh = dir.path().join("models/meshes/table.stl");
        let bytes = std::fs::read(&mesh).unwrap();
        std::fs::remove_file(&mesh).unwrap();
        std::fs::write(&mesh, &bytes).unwrap();
        assert!(cache.get(dir.path(), &path).is_none());
        cache.insert(dir.path(), &path, &doc);
        assert!(cache.get(dir.path(), &path).is_some());
        // so does an edited YAML
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, format!("{text}\n# edited\n")).unwrap();
        assert!(cache.get(dir.path(), &path).is_none());
    }
}
