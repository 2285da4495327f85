//! The registry of script functions: every binding is registered through [`Api`] with
//! its signature and doc text, so `fitup docs` generates `docs/api.md` from exactly what
//! the engine knows and the reference never drifts from the code.

use super::Context;
use rhai::{Engine, FuncRegistration, RhaiNativeFunc};
use std::sync::Arc;

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
        }
    }

    /// Starts a section of the reference.
    pub fn section(&mut self, title: &str, intro: &str) {
        self.sections.push((title.to_string(), intro.to_string()));
    }

    /// Registers a custom type under its script name.
    pub fn type_<T: Clone + Send + Sync + 'static>(&mut self, name: &str) {
        self.engine.register_type_with_name::<T>(name);
    }

    fn add<
        A: 'static,
        const N: usize,
        const X: bool,
        R: Clone + Send + Sync + 'static,
        const F: bool,
    >(
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
    pub fn f<
        A: 'static,
        const N: usize,
        const X: bool,
        R: Clone + Send + Sync + 'static,
        const F: bool,
    >(
        &mut self,
        signature: &str,
        doc: &str,
        func: impl RhaiNativeFunc<A, N, X, R, F> + Send + Sync + 'static,
    ) {
        self.add(rhai_name(signature, None), signature, doc, func);
    }

    /// Registers a property getter (`Type.prop -> R`).
    pub fn get<
        A: 'static,
        const N: usize,
        const X: bool,
        R: Clone + Send + Sync + 'static,
        const F: bool,
    >(
        &mut self,
        signature: &str,
        doc: &str,
        func: impl RhaiNativeFunc<A, N, X, R, F> + Send + Sync + 'static,
    ) {
        self.add(rhai_name(signature, Some("get")), signature, doc, func);
    }

    /// Registers a property setter (`Type.prop = value`), documented with its getter.
    pub fn set<A: 'static, const N: usize, const X: bool, const F: bool>(
        &mut self,
        signature: &str,
        func: impl RhaiNativeFunc<A, N, X, (), F> + Send + Sync + 'static,
    ) {
        let name = rhai_name(signature, Some("set"));
        let comments = vec![format!("/// Sets `{signature}`.")];
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

/// Registers the whole fitup API for a run.
pub(crate) fn register_all(
    engine: &mut Engine,
    ctx: &Arc<Context>,
) -> (Vec<(String, String)>, Vec<ApiEntry>) {
    let mut api = Api::new(engine);
    super::bind_math::register(&mut api);
    super::bind_document::register(&mut api, ctx);
    super::bind_interference::register(&mut api);
    super::bind_planning::register(&mut api);
    super::bind_robot::register(&mut api, ctx);
    super::bind_db::register(&mut api, ctx);
    super::bind_view::register(&mut api);
    (api.sections, api.entries)
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
    let (sections, entries) = register_all(&mut engine, &ctx);
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
        let (_, entries) = register_all(&mut engine, &ctx);
        let setters = entries
            .iter()
            .filter(|e| e.signature.ends_with("(get/set)"))
            .count();
        assert_eq!(
            engine.gen_fn_signatures(false).len(),
            entries.len() + setters
        );
    }
}
