//! Rhai scripting: the sandboxed engine, the API bindings, and running a script.
//!
//! Bindings are thin: each one converts arguments (numbers, `[x, y, z]` arrays,
//! degrees for user-facing angles), calls the Rust API, and converts the result back.
//! Units: millimetres and radians, except pose triples (`X Y Z A B C`) and joint arrays,
//! which are degrees; a dimension's `system_value` is SI (metres, radians).

mod api;
mod args;
mod assign;
mod bind_assembly;
#[cfg(feature = "db")]
mod bind_db;
mod bind_document;
mod bind_edit;
mod bind_equations;
mod bind_files;
mod bind_interference;
mod bind_mass;
mod bind_math;
mod bind_planning;
mod bind_robot;
mod bind_sequence;
#[cfg(feature = "skills")]
mod bind_skills;
mod bind_view;
mod builders;
mod convert;
pub mod sandbox;

pub use api::{api_reference, ApiEntry};
pub use args::{ArgError, ArgValue, Arguments};
pub use bind_document::{DocHandle, OpenError};
pub use sandbox::{Dispatch, Limits, Project};

use crate::diagnostics::SourceError;
use crate::mesh::MeshCache;
use rhai::{Engine, EvalAltResult, Position, Scope};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::RecvTimeoutError;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub(crate) type ScriptResult<T> = Result<T, Box<EvalAltResult>>;

/// Caches that outlive one run (watch mode keeps them between reruns).
#[derive(Default)]
pub struct Caches {
    /// Meshes by file, re-read only when the file changed.
    pub meshes: Mutex<MeshCache>,
    /// Collision trees and cut cells by mesh.
    pub scene: Mutex<crate::workspace::SceneCache>,
    /// Parsed documents by file, reused while none of their source files changed.
    pub documents: Mutex<DocumentCache>,
    /// The viewer session the runs log to (off unless `--view`/`--record`).
    pub view: crate::viewer::Viewer,
    /// What the runs wrote, as they wrote it: the content hash of each file by path.
    /// Watch mode takes a file whose bytes are what a run wrote there for that run's
    /// own write, not a save (a script that rewrites itself does not cancel itself).
    pub own_writes: Mutex<std::collections::HashMap<PathBuf, u64>>,
    /// Files a run is writing now (marked before the write begins, cleared once its
    /// hash is in [`own_writes`](Self::own_writes)): watch mode holds its verdict on
    /// such a file until the write is recorded, so the rename that lands the run's
    /// own bytes is never taken for a save in the instant before they are recorded.
    pub writing: Mutex<std::collections::HashSet<PathBuf>>,
}

/// The key of [`Caches::own_writes`] and [`Caches::writing`]: the path with its folder
/// canonicalized (the file itself may not exist yet), as watch mode spells event paths.
pub fn write_key(path: &Path) -> PathBuf {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    match (
        abs.parent().and_then(|d| d.canonicalize().ok()),
        abs.file_name(),
    ) {
        (Some(dir), Some(name)) => dir.join(name),
        _ => abs,
    }
}

/// A parsed document and the stamps of its source files when it was loaded.
type CachedDocument = (
    Vec<(PathBuf, crate::fsutil::Stamp)>,
    crate::document::Document,
);

/// Parsed documents kept between reruns: a document whose YAML, meshes and robot
/// files all have the [`Stamp`](crate::fsutil::Stamp) they had when it was loaded is
/// handed out as a copy instead of being parsed and solved again.
#[derive(Default)]
pub struct DocumentCache {
    /// By (project root, document path): the source files' stamps and the document.
    entries: std::collections::HashMap<(PathBuf, PathBuf), CachedDocument>,
}

impl DocumentCache {
    /// The cached copy of the document at `path` opened in `project`, when every
    /// source file is unchanged.
    pub fn get(&self, project: &Path, path: &Path) -> Option<crate::document::Document> {
        let (stamps, doc) = self
            .entries
            .get(&(project.to_path_buf(), path.to_path_buf()))?;
        stamps
            .iter()
            .all(|(f, s)| crate::fsutil::stamp(f).is_ok_and(|now| now == *s))
            .then(|| doc.clone())
    }

    /// Keeps `doc` (just loaded from `path` in `project`) with its files' stamps.
    pub fn insert(&mut self, project: &Path, path: &Path, doc: &crate::document::Document) {
        let stamps: Option<Vec<_>> = doc
            .source_files()
            .into_iter()
            .map(|f| crate::fsutil::stamp(&f).ok().map(|s| (f, s)))
            .collect();
        if let Some(stamps) = stamps {
            self.entries.insert(
                (project.to_path_buf(), path.to_path_buf()),
                (stamps, doc.clone()),
            );
        }
    }
}

/// A document a run opened (held weakly: closed when the script drops its last
/// handle) and its source files as last seen.
type OpenDocument = (
    std::sync::Weak<Mutex<crate::document::Document>>,
    Vec<PathBuf>,
);

/// Where a script's `print` and progress lines go.
pub type OutputSink = Arc<dyn Fn(&str) + Send + Sync>;

/// Shared state of one run, reachable from every binding.
pub struct Context {
    /// The folder that bounds file access.
    pub project: Project,
    /// Caches shared across runs.
    pub caches: Arc<Caches>,
    /// Set to stop the run (a newer save in watch mode).
    pub cancel: Arc<AtomicBool>,
    /// Output lines.
    pub output: OutputSink,
    /// The script's arguments (`fitup run SCRIPT -- key=value …`), the map `args`.
    pub args: Arguments,
    /// Whether skills may be dispatched over TCP (`fitup run --dispatch`).
    pub dispatch: Dispatch,
    /// The run's sandbox limits (the data sizes bindings check a result against
    /// before they build it).
    pub limits: Limits,
    /// The time budget all of this run's `db.query` calls share.
    #[cfg(feature = "db")]
    pub query_budget: crate::db::RunQueryBudget,
    reads: Mutex<BTreeSet<PathBuf>>,
    writes: Mutex<BTreeSet<PathBuf>>,
    /// The documents this run opened (while a handle on them lives) with their source
    /// files as last seen: what no output of the run may replace.
    documents: Mutex<Vec<OpenDocument>>,
    operations: AtomicU64,
    /// Set (with `cancel`) when the run passed its time limit (`Limits::max_seconds`).
    timed_out: AtomicBool,
    /// The properties with a setter (`set_<name>` methods), known once the engine is
    /// built.
    setters: std::sync::OnceLock<std::collections::HashSet<String>>,
}

impl Context {
    /// The run's collision cache (colliders and cut cells by mesh, kept across watch
    /// reruns), locked for the caller.
    pub(crate) fn scene_cache(
        &self,
    ) -> ScriptResult<std::sync::MutexGuard<'_, crate::workspace::SceneCache>> {
        self.caches
            .scene
            .lock()
            .map_err(|_| convert::fail("collision cache poisoned"))
    }

    /// A fresh context for one run.
    pub fn new(
        project: Project,
        caches: Arc<Caches>,
        cancel: Arc<AtomicBool>,
        output: OutputSink,
    ) -> Self {
        Self {
            project,
            caches,
            cancel,
            output,
            args: Arguments::default(),
            dispatch: Dispatch::Never,
            limits: Limits::default(),
            #[cfg(feature = "db")]
            query_budget: crate::db::RunQueryBudget::default(),
            reads: Mutex::default(),
            writes: Mutex::default(),
            documents: Mutex::default(),
            operations: AtomicU64::new(0),
            timed_out: AtomicBool::new(false),
            setters: Default::default(),
        }
    }

    /// The same context with script arguments.
    pub fn with_args(mut self, args: Arguments) -> Self {
        self.args = args;
        self
    }

    /// The same context with the dispatch permission of the command line.
    pub fn with_dispatch(mut self, dispatch: Dispatch) -> Self {
        self.dispatch = dispatch;
        self
    }

    /// The same context with the run's sandbox limits.
    pub fn with_limits(mut self, limits: Limits) -> Self {
        self.limits = limits;
        self
    }

    /// Operations evaluated so far in this run, over the script and all its modules.
    pub fn operations(&self) -> u64 {
        self.operations.load(Ordering::Relaxed)
    }

    /// Records a file the run depends on (watch mode reruns when it changes).
    pub fn record_read(&self, path: &Path) {
        if let Ok(mut r) = self.reads.lock() {
            r.insert(path.to_path_buf());
        }
    }

    /// Records a document this run opened: while a handle on it lives, no output of
    /// the run replaces a file it was read from ([`Self::document_sources`]).
    pub(crate) fn record_document(&self, doc: &Arc<Mutex<crate::document::Document>>) {
        let sources = doc.lock().map(|d| d.source_files()).unwrap_or_default();
        if let Ok(mut open) = self.documents.lock() {
            open.retain(|(d, _)| d.strong_count() > 0);
            open.push((Arc::downgrade(doc), sources));
        }
    }

    /// The files the documents this run has open were read from
    /// ([`crate::document::Document::source_files`]): their YAML, sub-documents,
    /// meshes, STEP files, URDFs, as they are now (a part added since counts; a
    /// document locked by the caller counts with its files as last seen).
    pub fn document_sources(&self) -> Vec<PathBuf> {
        let Ok(mut open) = self.documents.lock() else {
            return Vec::new();
        };
        open.retain(|(d, _)| d.strong_count() > 0);
        let mut all = Vec::new();
        for (doc, seen) in open.iter_mut() {
            if let Some(doc) = doc.upgrade() {
                if let Ok(d) = doc.try_lock() {
                    *seen = d.source_files();
                }
            }
            all.extend(seen.iter().cloned());
        }
        all
    }

    /// Records a file the run wrote, so watch mode does not mistake the run's own
    /// output for a user's save.
    pub fn record_write(&self, path: &Path) {
        self.record_write_unread(path);
        // Seen by watch mode at once, while the run goes on.
        let key = write_key(path);
        // Read back through the project's held root (never through a swapped folder).
        if let Ok(bytes) = self.project.read_file(path, crate::fsutil::FileKind::Mesh) {
            let hash = crate::fsutil::content_hash(&bytes);
            if let Ok(mut own) = self.caches.own_writes.lock() {
                own.insert(key.clone(), hash);
            }
        }
        if let Ok(mut w) = self.caches.writing.lock() {
            w.remove(&key);
        }
    }

    /// The folder of the document file `path` (inside the project) held open, walked
    /// from the project root without following a link; missing folders are made (a
    /// `save_as` into a new folder).
    pub(crate) fn document_folder(&self, path: &Path) -> ScriptResult<crate::fsutil::Dir> {
        let parent = path.parent().unwrap_or(Path::new("."));
        self.project
            .folder(parent, true)
            .map_err(|e| convert::fail(format!("cannot save {}: {e}", self.project.display(path))))
    }

    /// Runs `write`, a write of this run to `path`, with `path` marked as being
    /// written ([`Caches::writing`]) until the write is recorded: watch mode waits for
    /// the mark to go before it judges the file, so the run's own bytes landing are
    /// not a save. The written file is recorded ([`record_write`](Self::record_write))
    /// when `write` succeeds; the mark goes either way.
    pub fn writing<T, E>(&self, path: &Path, write: impl FnOnce() -> Result<T, E>) -> Result<T, E> {
        let key = write_key(path);
        if let Ok(mut w) = self.caches.writing.lock() {
            w.insert(key.clone());
        }
        let result = write();
        if result.is_ok() {
            self.record_write(path);
        }
        if let Ok(mut w) = self.caches.writing.lock() {
            w.remove(&key);
        }
        result
    }

    /// [`record_write`](Self::record_write) without reading the file back: for the
    /// files of an open SQLite database. Opening and closing a descriptor on them in
    /// this process would drop the POSIX locks SQLite holds on them (an `fcntl` lock
    /// belongs to the process and goes with any close of that file), and another
    /// process would then take itself for the only one and truncate the shared-memory
    /// file under this one's mapping (a bus error).
    pub fn record_write_unread(&self, path: &Path) {
        if let Ok(mut w) = self.writes.lock() {
            w.insert(path.to_path_buf());
        }
    }

    /// Writes a script's output file `path` (inside the project) through the one write
    /// rule ([`crate::project::check_output`]): a file a document open in this run was
    /// read from ([`Self::document_sources`]) is never replaced, not even with
    /// `overwrite`; the other files this run read count as files the project uses;
    /// `overwrite` is the script's `overwrite: true`. Atomic, listed in the folder's
    /// output registry, recorded as the run's write. Returns the absolute path.
    pub fn write_output(&self, path: &str, bytes: &[u8], overwrite: bool) -> ScriptResult<PathBuf> {
        let used = |p: &Path| self.reads.lock().map_or(true, |r| r.contains(p));
        let sources = self.document_sources();
        let rule = crate::project::OutputRule {
            force: overwrite,
            used: Some(&used),
            signature: None,
            sources: &sources,
        };
        // Checked and written through one folder handle walked from the project root.
        // Marked as the run's write before it lands (see `writing`); the path is the
        // one the writer resolves (an unresolvable one fails in the writer itself).
        let target = self.project.resolve(path).ok();
        let write = || self.project.write_output(path, bytes, &rule);
        let full = match &target {
            Some(t) => self.writing(t, write),
            None => write(),
        }
        .map_err(convert::fail)?;
        if target.as_deref() != Some(full.as_path()) {
            self.record_write(&full);
        }
        Ok(full)
    }

    /// Sends a line to the output.
    pub fn print(&self, line: &str) {
        (self.output)(line)
    }

    /// A diagnostic (a document warning): to stderr, escaped, never into the script's
    /// own output (a CSV a script prints must start with its own first line).
    pub fn warn(&self, line: &str) {
        use std::io::Write;
        let text = crate::diagnostics::printable(line, false);
        // a closed stderr loses the warning, never the run
        let _ = writeln!(std::io::stderr().lock(), "warning: {text}");
    }

    /// Whether the run was cancelled.
    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// The run's cancellation flag (set by a newer save or Ctrl-C), for a library
    /// loop that stops on it (a skill run's cancel token).
    #[cfg(feature = "skills")]
    pub(crate) fn cancel_flag(&self) -> Arc<AtomicBool> {
        self.cancel.clone()
    }
}

/// What to run.
#[derive(Clone)]
pub struct RunOptions {
    /// The script file.
    pub script: PathBuf,
    /// A document to provide as the variable `doc`.
    pub doc: Option<PathBuf>,
    /// The project root.
    pub project: Project,
    /// Resource limits.
    pub limits: Limits,
    /// Cancellation flag.
    pub cancel: Arc<AtomicBool>,
    /// Output sink.
    pub output: OutputSink,
    /// The script's arguments, the map `args` in the script.
    pub args: Arguments,
}

/// Why a run failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ScriptError {
    /// A syntax error, a runtime error or a failed `assert`, located in a file.
    #[error("{0}")]
    Located(SourceError),
    /// A newer save cancelled the run.
    #[error("cancelled")]
    Cancelled,
}

impl ScriptError {
    /// The message with the source line.
    pub fn render(&self) -> String {
        match self {
            ScriptError::Located(s) => s.render(),
            ScriptError::Cancelled => "cancelled".into(),
        }
    }
}

/// The result of a run.
pub struct RunOutcome {
    /// Success, or the located error.
    pub result: Result<(), ScriptError>,
    /// Every file the run read (script, imports, documents, meshes, CSVs…), for watch.
    pub files_read: Vec<PathBuf>,
    /// Every file the run wrote.
    pub files_written: Vec<PathBuf>,
    /// Wall time of the run.
    pub elapsed: Duration,
    /// Operations the run evaluated (script and modules), to compare with the limit.
    pub operations: u64,
}

/// Stack of the thread a script runs on. Rhai evaluates recursively; the sandbox's
/// depth limits (64 nested calls, expressions 128 deep, 16 nested imports) fit in a
/// fraction of this, which is only reserved address space until used.
pub const SCRIPT_STACK_BYTES: usize = 256 << 20;

/// What `on_progress` returns when the run passes its operation limit (Rhai counts
/// each imported module from zero, so the limit over the whole run is kept here).
const OPERATION_LIMIT: &str = "operation limit";

/// What `on_progress` returns when the run passed its time limit.
const TIME_LIMIT: &str = "time limit";

/// Builds a sandboxed engine with the whole fitup API for the given context.
pub fn engine(ctx: &Arc<Context>, limits: &Limits) -> Engine {
    let mut engine = Engine::new();
    limits.apply(&mut engine);
    builders::register(&mut engine, limits.max_array_size);
    engine.set_strict_variables(true);
    engine.set_fail_on_invalid_map_property(true);
    let c = ctx.clone();
    engine.on_print(move |s| c.print(s));
    let c = ctx.clone();
    engine.on_debug(move |s, _, pos| c.print(&format!("[debug {pos}] {s}")));
    let c = ctx.clone();
    let max_operations = limits.max_operations;
    engine.on_progress(move |_| {
        // A run is evaluated by one thread at a time (the script's; callbacks and
        // modules run on it too), so a plain load and store count the operations:
        // an atomic read-modify-write on every operation cost more than many calls.
        let n = c.operations.load(Ordering::Relaxed) + 1;
        c.operations.store(n, Ordering::Relaxed);
        if c.cancelled() {
            Some(if c.timed_out.load(Ordering::Relaxed) {
                TIME_LIMIT.into()
            } else {
                "cancelled".into()
            })
        } else if max_operations > 0 && n > max_operations {
            Some(OPERATION_LIMIT.into())
        } else {
            None
        }
    });
    engine.set_module_resolver(sandbox::ProjectResolver::new(ctx.clone(), *limits));
    api::register_all(&mut engine, ctx);
    engine
}

/// Runs a script to completion (or cancellation) and reports what it read.
///
/// The script runs on its own thread with a [`SCRIPT_STACK_BYTES`] stack, so deep
/// recursion and deeply nested expressions end with the sandbox's limit message, never
/// with a stack overflow of the caller's thread (watch mode's run threads are small).
pub fn run_script(opts: &RunOptions, caches: &Arc<Caches>) -> RunOutcome {
    let start = Instant::now();
    let ctx = Arc::new(
        Context::new(
            opts.project.clone(),
            caches.clone(),
            opts.cancel.clone(),
            opts.output.clone(),
        )
        .with_args(opts.args.clone())
        .with_dispatch(opts.limits.dispatch)
        .with_limits(opts.limits),
    );
    let result = std::thread::scope(|s| {
        // The run's time limit: a watchdog sets the cancel flag (read at every
        // operation and by the planners and queries) when it passes; it is told the
        // run ended by the channel closing.
        let (done, ended) = std::sync::mpsc::channel::<()>();
        if opts.limits.max_seconds > 0 {
            let limit = Duration::from_secs(opts.limits.max_seconds);
            let ctx = ctx.clone();
            let _ = std::thread::Builder::new()
                .name("fitup-time-limit".into())
                .spawn_scoped(s, move || {
                    if ended.recv_timeout(limit) == Err(RecvTimeoutError::Timeout) {
                        ctx.timed_out.store(true, Ordering::Relaxed);
                        ctx.cancel.store(true, Ordering::Relaxed);
                    }
                });
        }
        let _done = done;
        let run = std::thread::Builder::new()
            .name("fitup-script".into())
            .stack_size(SCRIPT_STACK_BYTES)
            .spawn_scoped(s, || run_inner(opts, &ctx));
        match run {
            Ok(handle) => handle.join().unwrap_or_else(|_| {
                Err(ScriptError::Located(SourceError::new(
                    &opts.script,
                    0,
                    0,
                    "internal error: the script's thread panicked (please report this)",
                )))
            }),
            // No thread to be had (out of memory or threads): run here instead.
            Err(_) => run_inner(opts, &ctx),
        }
    });
    let files_read = ctx
        .reads
        .lock()
        .map(|r| r.iter().cloned().collect())
        .unwrap_or_default();
    let files_written = ctx
        .writes
        .lock()
        .map(|r| r.iter().cloned().collect())
        .unwrap_or_default();
    RunOutcome {
        result,
        files_read,
        files_written,
        elapsed: start.elapsed(),
        operations: ctx.operations(),
    }
}

fn run_inner(opts: &RunOptions, ctx: &Arc<Context>) -> Result<(), ScriptError> {
    let script = opts.script.canonicalize().map_err(|e| {
        ScriptError::Located(SourceError::new(
            &opts.script,
            0,
            0,
            format!("cannot read the script: {e}"),
        ))
    })?;
    ctx.record_read(&script);
    let text = crate::fsutil::read_text(&script, crate::fsutil::FileKind::Script).map_err(|e| {
        ScriptError::Located(SourceError::new(
            &script,
            0,
            0,
            format!("cannot read the script: {e}"),
        ))
    })?;
    let engine = engine(ctx, &opts.limits);
    let mut scope = Scope::new();
    scope.push_constant("args", ctx.args.to_map());
    scope.push_constant("view", bind_view::ViewHandle::new(ctx));
    if let Some(doc_path) = &opts.doc {
        let doc = bind_document::DocHandle::open(ctx, &doc_path.to_string_lossy())
            .map_err(|e| ScriptError::Located(SourceError::new(doc_path, 0, 0, e.to_string())))?;
        scope.push("doc", doc);
    }
    let compiled = engine.compile_with_scope(&scope, &text).or_else(|e| {
        // `doc.component("x").fixed = true`: spelled with the setter method, the way
        // a macro author means it (assign.rs); any other error stays the error
        if !matches!(*e.0, rhai::ParseErrorType::AssignmentToInvalidLHS(..)) {
            return Err(e);
        }
        let setters = ctx.setters.get().cloned().unwrap_or_default();
        match assign::rewrite(&text, &setters) {
            Some(t) => engine.compile_with_scope(&scope, &t).map_err(|_| e),
            None => Err(e),
        }
    });
    let mut ast = compiled.map_err(|e| {
        let (line, col) = (e.1.line().unwrap_or(0), e.1.position().unwrap_or(0));
        let located = SourceError::new(&script, line, col, format!("syntax error: {}", e.0));
        ScriptError::Located(match *e.0 {
            rhai::ParseErrorType::AssignmentToInvalidLHS(..) => located.with_help(
                "only a property of a variable, or of a call's result that has a setter \
                 (`doc.component(\"x\").fixed = true`), can be assigned; for anything else \
                 keep the value in a variable first: `let c = doc.component(\"x\"); c.fixed = true;`",
            ),
            _ => located,
        })
    })?;
    ast.set_source(script.to_string_lossy().as_ref());
    match engine.run_ast_with_scope(&mut scope, &ast) {
        Ok(()) => Ok(()),
        Err(e) => {
            // Whatever error a run stopped by its time limit ends with (the
            // termination, or a planner's or module's error on the way) is the limit,
            // at the line it was reached.
            if ctx.timed_out.load(Ordering::Relaxed) {
                let mut located = locate_error(&e, &script, &opts.limits);
                located.message = time_limit_message(&opts.limits);
                return Err(ScriptError::Located(located));
            }
            // Whatever error a cancelled run ends with (the termination itself, or a
            // module's error wrapping it) is the cancellation.
            if ctx.cancelled() {
                return Err(ScriptError::Cancelled);
            }
            Err(ScriptError::Located(locate_error(
                &e,
                &script,
                &opts.limits,
            )))
        }
    }
}

/// The message of a run stopped by its time limit.
fn time_limit_message(limits: &Limits) -> String {
    format!(
        "the script ran past its time limit of {} s; if it really needs longer, raise it \
         with `--max-seconds N` (from Python: `run_script(..., max_seconds=N)`; 0: no limit)",
        crate::math::format::count(limits.max_seconds)
    )
}

/// Finds the innermost located cause of a Rhai error, in whichever file it happened.
fn locate_error(err: &EvalAltResult, file: &Path, limits: &Limits) -> SourceError {
    let mut calls = Vec::new();
    let mut current = err;
    let mut path = file.to_path_buf();
    let mut pos = err.position();
    loop {
        match current {
            EvalAltResult::ErrorInFunctionCall(name, src, inner, p) => {
                calls.push(name.clone());
                if !src.is_empty() {
                    path = PathBuf::from(src);
                }
                pos = if inner.position().is_none() {
                    *p
                } else {
                    inner.position()
                };
                current = inner;
            }
            EvalAltResult::ErrorInModule(name, inner, p) => {
                if !name.is_empty() && Path::new(name).is_file() {
                    path = PathBuf::from(name);
                }
                pos = if inner.position().is_none() {
                    *p
                } else {
                    inner.position()
                };
                current = inner;
            }
            _ => break,
        }
    }
    let message = describe(current, limits);
    let (line, col) = position(pos);
    let mut e = SourceError::new(&path, line, col, message);
    if !calls.is_empty() {
        e = e.with_help(format!(
            "inside {}",
            calls
                .iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(" → ")
        ));
    }
    e
}

fn position(pos: Position) -> (usize, usize) {
    (pos.line().unwrap_or(0), pos.position().unwrap_or(0))
}

fn describe(err: &EvalAltResult, limits: &Limits) -> String {
    match err {
        EvalAltResult::ErrorRuntime(v, _) => v.to_string(),
        EvalAltResult::ErrorTerminated(token, _)
            if token.clone().into_string().ok().as_deref() == Some(TIME_LIMIT) =>
        {
            time_limit_message(limits)
        }
        EvalAltResult::ErrorTerminated(token, _)
            if token.clone().into_string().ok().as_deref() != Some(OPERATION_LIMIT) =>
        {
            "the script was stopped".into()
        }
        EvalAltResult::ErrorTooManyOperations(_) | EvalAltResult::ErrorTerminated(..) => format!(
            "the script ran past its operation limit of {} operations (an endless loop?); if it really needs more, \
             raise it with `--max-operations N` (e.g. `--max-operations {}`)",
            crate::math::format::count(limits.max_operations),
            limits.max_operations.saturating_mul(10)
        ),
        EvalAltResult::ErrorStackOverflow(_) => format!(
            "more than {} nested function calls (runaway recursion?)",
            limits.max_call_levels
        ),
        EvalAltResult::ErrorTooManyModules(_) => format!(
            "more than {} modules imported in one run",
            limits.max_modules
        ),
        EvalAltResult::ErrorDataTooLarge(what, _) => format!(
            "{what} is larger than the sandbox allows (strings up to {} characters, arrays up to {} elements, maps up to {} properties)",
            crate::math::format::count(limits.max_string_size as u64),
            crate::math::format::count(limits.max_array_size as u64),
            crate::math::format::count(limits.max_map_size as u64)
        ),
        other => {
            let s = other.to_string();
            // Rhai appends " (line x, position y)"; the location is shown separately.
            match s.rfind(" (line ") {
                Some(i) => s[..i].to_string(),
                None => s,
            }
        }
    }
}
