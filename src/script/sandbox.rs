//! The script sandbox: the project folder that bounds file access, resource limits, and
//! the module resolver that keeps `import` inside the project.

use super::{Context, ScriptResult};
use rhai::{Engine, EvalAltResult, Module, Position, Scope, Shared};
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

/// The folder a script may read and write in. Relative paths in scripts are
/// resolved against it; anything that resolves outside it is refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Project {
    root: PathBuf,
}

impl Project {
    /// A project rooted at `root` (made absolute and canonical).
    pub fn new(root: &Path) -> std::io::Result<Self> {
        Ok(Self {
            root: root.canonicalize()?,
        })
    }

    /// The canonical root folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The absolute path of `path` (relative to the root), checked to lie inside the
    /// project. `..` components and symbolic links are resolved before the check, so
    /// neither can escape. The file need not exist (for writes); its folder must.
    pub fn resolve(&self, path: &str) -> Result<PathBuf, String> {
        if path.is_empty() {
            return Err("empty path".into());
        }
        let p = Path::new(path);
        let joined = if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.root.join(p)
        };
        // Canonicalize the deepest existing ancestor, then append the rest lexically.
        let mut existing = joined.clone();
        let mut rest = Vec::new();
        while !existing.exists() {
            match (existing.file_name(), existing.parent()) {
                (Some(name), Some(parent)) => {
                    rest.push(name.to_os_string());
                    existing = parent.to_path_buf();
                }
                _ => return Err(format!("`{path}` cannot be resolved")),
            }
        }
        let mut full = existing
            .canonicalize()
            .map_err(|e| format!("`{path}`: {e}"))?;
        for name in rest.iter().rev() {
            if Path::new(name)
                .components()
                .any(|c| matches!(c, Component::ParentDir))
            {
                return Err(format!("`{path}` leaves the project folder"));
            }
            full.push(name);
        }
        if !full.starts_with(&self.root) {
            return Err(format!(
                "`{path}` is outside the project folder {}: scripts may only use files inside it",
                self.root.display()
            ));
        }
        Ok(full)
    }

    /// `path` shown relative to the root when inside it.
    pub fn display(&self, path: &Path) -> String {
        path.strip_prefix(&self.root)
            .unwrap_or(path)
            .display()
            .to_string()
    }
}

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
            .map_err(refuse)?;
        if !full.is_file() {
            return Err(err(path.to_string()));
        }
        let text = std::fs::read_to_string(&full).map_err(|e| refuse(e.to_string()))?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_outside_the_project_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("models")).unwrap();
        let p = Project::new(dir.path()).unwrap();
        assert!(p.resolve("models/x.yaml").is_ok());
        assert!(p.resolve("new/deeper/file.csv").is_ok());
        assert!(p.resolve("../x").is_err());
        assert!(p.resolve("models/../../x").is_err());
        assert!(p.resolve("/etc/passwd").is_err());
        assert!(p.resolve("").is_err());
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("/tmp", dir.path().join("escape")).unwrap();
            assert!(p.resolve("escape/x").is_err());
        }
    }
}
