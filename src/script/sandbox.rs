//! The script sandbox: the project folder that bounds file access, resource limits, and
//! the module resolver that keeps `import` inside the project.

use super::{Context, ScriptResult};
use rhai::{Engine, EvalAltResult, Module, Position, Scope, Shared};
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use crate::project::Project;

/// Resource limits of a script run. Every limit is set explicitly on the engine (debug
/// builds of Rhai otherwise default to a call depth of 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Operations (roughly: expression evaluations) per run.
    pub max_operations: u64,
    /// Nested function calls.
    pub max_call_levels: usize,
    /// Nesting depth of expressions, and of expressions inside functions.
    pub max_expr_depth: (usize, usize),
    /// Characters in one string.
    pub max_string_size: usize,
    /// Elements in one array.
    pub max_array_size: usize,
    /// Properties in one object map.
    pub max_map_size: usize,
    /// Modules imported in one run.
    pub max_modules: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_operations: 500_000_000,
            max_call_levels: 64,
            max_expr_depth: (128, 64),
            max_string_size: 16 << 20,
            max_array_size: 4_000_000,
            max_map_size: 2_000_000,
            max_modules: 64,
        }
    }
}

impl Limits {
    /// Applies the limits to an engine.
    pub fn apply(&self, engine: &mut Engine) {
        engine.set_max_operations(self.max_operations);
        engine.set_max_call_levels(self.max_call_levels);
        engine.set_max_expr_depths(self.max_expr_depth.0, self.max_expr_depth.1);
        engine.set_max_string_size(self.max_string_size);
        engine.set_max_array_size(self.max_array_size);
        engine.set_max_map_size(self.max_map_size);
        engine.set_max_modules(self.max_modules);
    }
}

/// Resolves `import "path"` against the importing script's folder, inside the project
/// only; `.rhai` is appended when the path has no extension. Imported files are
/// recorded as dependencies for watch mode.
pub(crate) struct ProjectResolver {
    pub(crate) ctx: Arc<Context>,
}

impl rhai::ModuleResolver for ProjectResolver {
    fn resolve(
        &self,
        engine: &Engine,
        source: Option<&str>,
        path: &str,
        pos: Position,
    ) -> ScriptResult<Shared<Module>> {
        let err = |m: String| Box::new(EvalAltResult::ErrorModuleNotFound(m, pos));
        let mut rel = PathBuf::from(path);
        if rel.extension().is_none() {
            rel.set_extension("rhai");
        }
        let base = source
            .map(Path::new)
            .and_then(Path::parent)
            .map(Path::to_path_buf);
        let candidate = match base {
            Some(b) if rel.is_relative() => b.join(&rel),
            _ => rel,
        };
        // Refusals are runtime errors: Rhai turns a ModuleNotFound into one that shows
        // the bare path only.
        let refuse = |m: String| {
            Box::new(EvalAltResult::ErrorRuntime(
                format!("import \"{path}\": {m}").into(),
                pos,
            ))
        };
        let full = self
            .ctx
            .project
            .resolve(&candidate.to_string_lossy())
            .map_err(|e| refuse(e.to_string()))?;
        if !full.exists() {
            return Err(err(path.to_string()));
        }
        let text = crate::fsutil::read_text(&full, crate::fsutil::FileKind::Script)
            .map_err(|e| refuse(e.to_string()))?;
        self.ctx.record_read(&full);
        let mut ast = engine.compile(&text).map_err(|e| {
            Box::new(EvalAltResult::ErrorInModule(
                full.to_string_lossy().into_owned(),
                Box::new(EvalAltResult::ErrorParsing(*e.0, e.1)),
                pos,
            ))
        })?;
        ast.set_source(full.to_string_lossy().as_ref());
        let module = Module::eval_ast_as_new(Scope::new(), &ast, engine)?;
        Ok(module.into())
    }
}
