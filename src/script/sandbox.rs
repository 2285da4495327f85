//! The script sandbox: the project folder that bounds file access, resource limits, and
//! the module resolver that keeps `import` inside the project.

use super::{Context, ScriptResult};
use rhai::{Engine, EvalAltResult, Module, Position, Scope, Shared};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

pub use crate::project::Project;

/// Resource limits of a script run. Every limit is set explicitly on the engine (debug
/// builds of Rhai otherwise default to a call depth of 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Operations (roughly: expression evaluations) per run, counted over the script
    /// and every module it imports. The default stops a runaway loop within about two
    /// seconds; raise it with `--max-operations`.
    pub max_operations: u64,
    /// Wall time of a run, seconds (0: none). The operation limit does not bound time:
    /// Rhai measures an array after every native call on its variable (`a.len()` of a
    /// 4-million-element array: about 10 ms for one operation), so a loop of such calls
    /// within 50 million operations would run for days. Raise it with `--max-seconds`.
    pub max_seconds: u64,
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
    /// Modules imported in one run (every `import` executed counts, nested ones too).
    pub max_modules: usize,
    /// Depth of nested imports (a module importing a module importing …).
    pub max_import_depth: usize,
    /// Whether the script may dispatch skills to a manipulator over TCP
    /// (`fitup run --dispatch [--allow-remote]`); the in-process simulator needs none.
    pub dispatch: Dispatch,
}

/// Permission to command a manipulator over TCP from a script.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Dispatch {
    /// Never (the default, and `fitup watch` without `--dispatch`).
    #[default]
    Never,
    /// To a controller on this machine (loopback) only: `--dispatch`.
    Loopback,
    /// To any address: `--dispatch --allow-remote`.
    Remote,
}

/// The default operation limit: a tight loop (`while true { x += 1 }`) reaches it in
/// about two seconds on a 2-core VM (about 28 million operations per second), while the
/// bundled examples need far less (the largest, `planners.rhai`, about 100,000: the
/// heavy work happens in Rust, which does not count).
pub const DEFAULT_MAX_OPERATIONS: u64 = 50_000_000;

/// The default time limit of a run (`--max-seconds`), seconds: one hour.
pub const DEFAULT_MAX_SECONDS: u64 = 3600;

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_operations: DEFAULT_MAX_OPERATIONS,
            max_seconds: DEFAULT_MAX_SECONDS,
            max_call_levels: 64,
            max_expr_depth: (128, 64),
            max_string_size: 16 << 20,
            max_array_size: 4_000_000,
            max_map_size: 2_000_000,
            max_modules: 64,
            max_import_depth: 16,
            dispatch: Dispatch::Never,
        }
    }
}

impl Limits {
    /// Applies the limits to an engine. The module count and import depth are enforced
    /// by [`ProjectResolver`]: Rhai evaluates each imported module with fresh counters,
    /// so its own module limit never sees nested imports.
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

/// One import being evaluated: `importer` line `line` imports `module`.
struct ImportFrame {
    importer: PathBuf,
    line: usize,
    module: PathBuf,
}

/// Resolves `import "path"` against the importing script's folder, inside the project
/// only; `.rhai` is appended when the path has no extension. Imported files are
/// recorded as dependencies for watch mode.
///
/// It keeps the chain of imports being evaluated, so a cycle (a script importing
/// itself, `a` → `b` → `a`) is reported with every `file:line` of the chain instead of
/// recursing until the stack overflows, and it counts modules over the whole run.
pub(crate) struct ProjectResolver {
    ctx: Arc<Context>,
    limits: Limits,
    chain: Mutex<Vec<ImportFrame>>,
    loaded: AtomicUsize,
}

impl ProjectResolver {
    pub(crate) fn new(ctx: Arc<Context>, limits: Limits) -> Self {
        Self {
            ctx,
            limits,
            chain: Mutex::default(),
            loaded: AtomicUsize::new(0),
        }
    }

    fn chain(&self) -> MutexGuard<'_, Vec<ImportFrame>> {
        // A panic while the lock is held cannot leave the chain half-updated.
        self.chain.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Pops the import chain when a module's evaluation ends, however it ends.
struct PopOnDrop<'a>(&'a ProjectResolver);

impl Drop for PopOnDrop<'_> {
    fn drop(&mut self) {
        self.0.chain().pop();
    }
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
        let importer = source.map(PathBuf::from).unwrap_or_default();
        {
            let mut chain = self.chain();
            let project = &self.ctx.project;
            // `a.rhai:3 → b.rhai:1 → a.rhai`: each importing line, relative to the project.
            let describe = |frames: &[ImportFrame], last: &ImportFrame, end: &Path| {
                let mut parts: Vec<String> = frames
                    .iter()
                    .chain(std::iter::once(last))
                    .map(|f| format!("{}:{}", project.display(&f.importer), f.line))
                    .collect();
                parts.push(project.display(end));
                parts.join(" → ")
            };
            let frame = ImportFrame {
                importer: importer.clone(),
                line: pos.line().unwrap_or(0),
                module: full.clone(),
            };
            // Files being evaluated: the main script and every module on the chain.
            let in_chain =
                importer == full || chain.iter().any(|f| f.importer == full || f.module == full);
            if in_chain {
                // Show the chain from where this file first imports.
                let start = chain
                    .iter()
                    .position(|f| f.importer == full)
                    .unwrap_or(chain.len());
                let text = describe(&chain[start..], &frame, &full);
                return Err(refuse(format!(
                    "import cycle: {text}; a module cannot import itself, directly or through others"
                )));
            }
            if chain.len() >= self.limits.max_import_depth {
                let text = describe(&chain, &frame, &full);
                return Err(refuse(format!(
                    "imports are nested more than {} deep: {text}",
                    self.limits.max_import_depth
                )));
            }
            if self.loaded.fetch_add(1, Ordering::Relaxed) >= self.limits.max_modules {
                return Err(refuse(format!(
                    "more than {} modules imported in one run (each `import` executed counts)",
                    self.limits.max_modules
                )));
            }
            chain.push(frame);
        }
        let _pop = PopOnDrop(self);
        let text = self
            .ctx
            .project
            .read_text(&full, crate::fsutil::FileKind::Script)
            .map_err(|e| refuse(e.to_string()))?;
        self.ctx.record_read(&full);
        let in_module = |e: Box<EvalAltResult>| {
            Box::new(EvalAltResult::ErrorInModule(
                full.to_string_lossy().into_owned(),
                e,
                pos,
            ))
        };
        let mut ast = engine
            .compile(&text)
            .map_err(|e| in_module(Box::new(EvalAltResult::ErrorParsing(*e.0, e.1))))?;
        ast.set_source(full.to_string_lossy().as_ref());
        let module = Module::eval_ast_as_new(Scope::new(), &ast, engine).map_err(in_module)?;
        Ok(module.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::script::{run_script, Caches, RunOptions, ScriptError};

    /// Runs `main.rhai` of a folder holding `files`; the error message, if any.
    fn run_files(files: &[(&str, &str)], limits: Limits) -> Option<String> {
        let dir = tempfile::tempdir().unwrap();
        for (name, text) in files {
            std::fs::write(dir.path().join(name), text).unwrap();
        }
        let opts = RunOptions {
            script: dir.path().join("main.rhai"),
            doc: None,
            project: Project::new(dir.path()).unwrap(),
            limits,
            cancel: Default::default(),
            output: Arc::new(|_| {}),
            args: Default::default(),
        };
        match run_script(&opts, &Arc::new(Caches::default())).result {
            Ok(()) => None,
            Err(ScriptError::Located(e)) => Some(e.to_string()),
            Err(e) => Some(e.to_string()),
        }
    }

    #[test]
    fn import_cycles_are_errors_with_the_chain() {
        let e = run_files(&[("main.rhai", "import \"main\" as m;")], Limits::default()).unwrap();
        assert!(
            e.contains("main.rhai:1:") && e.contains("import cycle: main.rhai:1 → main.rhai"),
            "{e}"
        );
        let e = run_files(
            &[
                ("main.rhai", "import \"a\" as a;"),
                ("a.rhai", "\nimport \"b\" as b;"),
                ("b.rhai", "import \"a\" as a;"),
            ],
            Limits::default(),
        )
        .unwrap();
        assert!(
            e.contains("b.rhai:1:") && e.contains("import cycle: a.rhai:2 → b.rhai:1 → a.rhai"),
            "{e}"
        );
    }

    #[test]
    fn module_limits_fire() {
        let chain: Vec<(String, String)> = (0..5)
            .map(|i| (format!("m{i}.rhai"), format!("import \"m{}\" as n;", i + 1)))
            .chain(std::iter::once(("m5.rhai".into(), "fn x() { 1 }".into())))
            .collect();
        let mut files: Vec<(&str, &str)> = chain
            .iter()
            .map(|(a, b)| (a.as_str(), b.as_str()))
            .collect();
        files.push(("main.rhai", "import \"m0\" as m;"));
        let tight = Limits {
            max_import_depth: 3,
            ..Limits::default()
        };
        let e = run_files(&files, tight).unwrap();
        assert!(e.contains("nested more than 3 deep"), "{e}");
        assert_eq!(run_files(&files, Limits::default()), None);
        let few = Limits {
            max_modules: 4,
            ..Limits::default()
        };
        let e = run_files(&files, few).unwrap();
        assert!(e.contains("more than 4 modules"), "{e}");
    }

    #[test]
    fn scripts_do_not_use_the_callers_stack() {
        // A caller with a small stack (watch mode's threads, an embedding application)
        // still gets the limit messages, not a stack overflow.
        let deep = format!("let x = {}1{};", "[".repeat(30), "]".repeat(30));
        let recursion = "fn f(n) { if n == 0 { 0 } else { 1 + f(n - 1) } } f(60);";
        let errors = std::thread::Builder::new()
            .stack_size(256 << 10)
            .spawn(move || {
                (
                    run_files(&[("main.rhai", &deep)], Limits::default()),
                    run_files(&[("main.rhai", recursion)], Limits::default()),
                    run_files(
                        &[("main.rhai", "fn f(n) { f(n + 1) } f(0);")],
                        Limits::default(),
                    ),
                )
            })
            .unwrap()
            .join()
            .unwrap();
        assert_eq!(errors.0, None);
        assert_eq!(errors.1, None);
        assert!(
            errors
                .2
                .as_deref()
                .unwrap_or("")
                .contains("nested function calls"),
            "{errors:?}"
        );
    }
}
