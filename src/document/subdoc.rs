//! Sub-assemblies that are other documents (SolidWorks' `.sldasm` inside an
//! assembly): an `assemblies:` entry with `file: cart.yaml` holds that document's
//! parts, components, sub-assemblies and mates, loaded under its full name
//! (`Cart-1/Wheel-2`, `Cart-1/Axle-2/Wheel-2` through more levels), poses composed
//! with its pose.
//!
//! Everything loaded from the file is named inside the sub-assembly (`Cart-1/…`:
//! components, sub-assemblies, mates, parts, robots and their joint dimensions) and is written back to that file,
//! never into the assembly's: a save rewrites the sub-document only when its content
//! changed (a script moved, added, suppressed … something inside), through the same
//! checked write as the document's own file (refused when the file changed on disk
//! since it was read).
//!
//! Bounds, checked on the files' text before any mesh is read: at most
//! [`MAX_DEPTH`] levels of files, at most [`MAX_TOTAL_COMPONENTS`] components over
//! every level and instance; a file that includes itself (directly or through
//! others) is refused at the `file:` line that closes the circle.

use super::file::DocumentFile;
use super::{Document, DocumentError, OutsideItem, SubAssembly, WriteProblem};
use crate::diagnostics::SourceError;
use crate::fsutil::{content_hash, FileKind};
use crate::project::Project;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// At most this many levels of documents inside documents.
pub const MAX_DEPTH: usize = 16;

/// At most this many components over the whole tree of documents (each instance of a
/// sub-document counted again).
pub const MAX_TOTAL_COMPONENTS: usize = 200_000;

/// The file of a sub-assembly that is another document.
#[derive(Debug, Clone, PartialEq)]
pub struct SubDocument {
    /// The path as written in the `file:` key (relative to the document holding it).
    pub file: String,
    /// The file on disk (canonical).
    pub path: PathBuf,
    /// The sub-document as loaded or last saved, to tell whether a save must rewrite
    /// it.
    pub(super) as_loaded: Box<DocumentFile>,
    /// Hash of its bytes when loaded or last saved.
    pub(super) disk_hash: Option<u64>,
}

/// The state of one load through the levels of documents.
pub(super) struct Nesting {
    /// Canonical paths of the documents being loaded, outermost first.
    pub stack: Vec<PathBuf>,
    /// The sub-documents read in this load, by canonical path (each read once).
    loaded: HashMap<PathBuf, (Document, String)>,
    /// Whether the whole tree was counted already (done once, at the top).
    counted: bool,
}

impl Nesting {
    /// The state of loading the document at `path` at the top.
    pub fn root(path: &Path) -> Self {
        Nesting {
            stack: vec![canonical(path)],
            loaded: HashMap::new(),
            counted: false,
        }
    }
}

fn canonical(p: &Path) -> PathBuf {
    p.canonicalize()
        .or_else(|_| std::path::absolute(p))
        .unwrap_or_else(|_| p.to_path_buf())
}

/// A located error at `key` of the file `path` (whose text's key positions are
/// `positions`).
fn at_key(path: &Path, positions: &super::scan::Positions, key: &str, m: String) -> DocumentError {
    let (line, col) = positions.get(key).unwrap_or((0, 0));
    SourceError::new(path, line, col, m).into()
}

/// What the counting pass needs of one file.
struct Counted<'a> {
    file: &'a DocumentFile,
    path: &'a Path,
    dir: &'a Path,
    positions: &'a super::scan::Positions,
}

/// Counts the components of the tree below `doc` (its own and every sub-document's,
/// each instance again), reading only the files' text: refuses a circle, more than
/// [`MAX_DEPTH`] levels and more than [`MAX_TOTAL_COMPONENTS`] components, each at
/// the `file:` line where it happens.
fn count(
    doc: &Counted,
    project: &Project,
    stack: &mut Vec<PathBuf>,
    memo: &mut HashMap<PathBuf, usize>,
) -> Result<usize, DocumentError> {
    let mut total = doc.file.components.len();
    for (i, a) in doc.file.assemblies.iter().enumerate() {
        let Some(f) = &a.file else { continue };
        let key = format!("assemblies/{i}/file");
        let err = |m: String| {
            at_key(
                doc.path,
                doc.positions,
                &key,
                format!("sub-assembly `{}`: {m}", a.name),
            )
        };
        let sub = project
            .resolve_from(doc.dir, f)
            .map_err(|e| err(format!("document {e}")))?;
        let sub = canonical(&sub);
        if let Some(k) = stack.iter().position(|p| *p == sub) {
            let circle: Vec<String> = stack[k..]
                .iter()
                .chain(std::iter::once(&sub))
                .map(|p| project.display(p))
                .collect();
            return Err(err(format!(
                "`{f}` holds itself: {} (a document cannot be its own sub-assembly)",
                circle.join(" → ")
            )));
        }
        if stack.len() >= MAX_DEPTH {
            return Err(err(format!(
                "`{f}` is more than {MAX_DEPTH} levels of documents deep (MAX_DEPTH)"
            )));
        }
        let n = match memo.get(&sub) {
            Some(&n) => n,
            None => {
                let text = project
                    .read_named_text(&sub, FileKind::Document)
                    .map_err(|e| err(format!("cannot read `{f}`: {e}")))?;
                let (file, positions) = Document::parse_text(&text, &sub)?;
                let dir = sub.parent().unwrap_or(project.root()).to_path_buf();
                stack.push(sub.clone());
                let n = count(
                    &Counted {
                        file: &file,
                        path: &sub,
                        dir: &dir,
                        positions: &positions,
                    },
                    project,
                    stack,
                    memo,
                )?;
                stack.pop();
                memo.insert(sub.clone(), n);
                n
            }
        };
        total = total.saturating_add(n);
        if total > MAX_TOTAL_COMPONENTS {
            return Err(err(format!(
                "with `{f}` the assembly holds more than {MAX_TOTAL_COMPONENTS} components over its levels (MAX_TOTAL_COMPONENTS)"
            )));
        }
    }
    Ok(total)
}

/// Whether a name is inside `prefix/`.
fn inside<'a>(name: &'a str, at: &str) -> Option<&'a str> {
    name.strip_prefix(at)?.strip_prefix('/')
}

/// An equation's name `n` of a sub-document as named inside the sub-assembly `at`:
/// a dimension `D1@Gap` is `D1@Cart-1/Gap`, a global variable `Factor` `Cart-1/Factor`.
fn scoped(at: &str, n: &str) -> String {
    match n.strip_prefix("D1@") {
        Some(m) => format!("D1@{at}/{m}"),
        None => format!("{at}/{n}"),
    }
}

/// [`scoped`] undone: `n` as the sub-document itself names it, `None` when `n` is not
/// inside `at`.
fn unscoped(n: &str, at: &str) -> Option<String> {
    match n.strip_prefix("D1@") {
        Some(m) => inside(m, at).map(|r| format!("D1@{r}")),
        None => inside(n, at).map(str::to_string),
    }
}

impl Document {
    /// Loads the sub-documents of `file` (this document's parsed file) and adds what
    /// they hold under their sub-assemblies' names. `dir` is this document's folder.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn load_sub_documents(
        &mut self,
        file: &DocumentFile,
        path: &Path,
        dir: &Path,
        project: &Project,
        positions: &super::scan::Positions,
        nesting: &mut Nesting,
        cache: &mut crate::mesh::MeshCache,
    ) -> Result<(), DocumentError> {
        if !file.assemblies.iter().any(|a| a.file.is_some()) {
            return Ok(());
        }
        if !nesting.counted {
            let mut stack = nesting.stack.clone();
            count(
                &Counted {
                    file,
                    path,
                    dir,
                    positions,
                },
                project,
                &mut stack,
                &mut HashMap::new(),
            )?;
            nesting.counted = true;
        }
        for (i, a) in file.assemblies.iter().enumerate() {
            let Some(f) = &a.file else { continue };
            let key = format!("assemblies/{i}/file");
            let err = |m: String| {
                at_key(
                    path,
                    positions,
                    &key,
                    format!("sub-assembly `{}`: {m}", a.name),
                )
            };
            let sub = canonical(
                &project
                    .resolve_from(dir, f)
                    .map_err(|e| err(format!("document {e}")))?,
            );
            if nesting.stack.contains(&sub) || nesting.stack.len() >= MAX_DEPTH {
                // counted above; a file changed since the count
                return Err(err(format!(
                    "`{f}` holds itself or is too deep (changed while loading?)"
                )));
            }
            if !nesting.loaded.contains_key(&sub) {
                let text = project
                    .read_named_text(&sub, FileKind::Document)
                    .map_err(|e| err(format!("cannot read `{f}`: {e}")))?;
                nesting.stack.push(sub.clone());
                let loaded = Document::from_yaml_nested(&text, &sub, project, cache, nesting);
                nesting.stack.pop();
                let mut loaded = loaded?;
                loaded.disk_hash = Some(content_hash(text.as_bytes()));
                nesting.loaded.insert(sub.clone(), (loaded, text));
            }
            let (sub_doc, _) = &nesting.loaded[&sub];
            let as_loaded = Box::new(sub_doc.to_file());
            let record = SubDocument {
                file: f.clone(),
                path: sub.clone(),
                as_loaded,
                disk_hash: sub_doc.disk_hash,
            };
            self.import(&a.name, record, sub_doc)
                .map_err(|e| err(e.to_string()))?;
        }
        Ok(())
    }

    /// Adds the content of `sub` (a loaded sub-document) inside the sub-assembly
    /// `at` (which exists, and becomes the sub-document's `record`).
    fn import(
        &mut self,
        at: &str,
        record: SubDocument,
        sub: &Document,
    ) -> Result<(), DocumentError> {
        let k = self
            .assemblies
            .iter()
            .position(|a| a.name == at)
            .ok_or_else(|| DocumentError::NoSubAssembly(at.to_string()))?;
        let taken = |what, name| DocumentError::NameTaken { what, name };
        let frame = self.assemblies[k].transform;
        self.assemblies[k].file = Some(record);
        let name = |n: &str| format!("{at}/{n}");
        for p in sub.parts.values() {
            let n = name(&p.name);
            if self.parts.contains_key(&n) {
                return Err(taken("part", n));
            }
            let mut p = p.clone();
            p.name = n.clone();
            self.parts.insert(n, p);
        }
        for a in &sub.assemblies {
            let n = name(&a.name);
            if self.assemblies.iter().any(|b| b.name == n) || self.by_name.contains_key(&n) {
                return Err(taken("sub-assembly", n));
            }
            self.assemblies.push(SubAssembly {
                name: n,
                transform: a.transform * frame,
                ..a.clone()
            });
        }
        let offset = self.components.len();
        self.components.reserve(sub.components.len());
        for c in &sub.components {
            let n = name(&c.name);
            if self
                .by_name
                .insert(n.clone(), self.components.len())
                .is_some()
            {
                return Err(taken("component", n));
            }
            self.numbering.insert(&n);
            let mut c = c.clone();
            c.name = n;
            c.part = name(&c.part);
            c.transform = c.transform * frame;
            self.components.push(c);
        }
        for m in &sub.mates {
            let n = name(&m.name);
            if self.mates.iter().any(|o| o.name == n) {
                return Err(taken("mate", n));
            }
            let mut m = m.clone();
            m.name = n;
            for e in m.entities.iter_mut().chain(m.about.as_mut()) {
                e.component += offset;
            }
            self.mates.push(m);
        }
        // Its robots, named inside the sub-assembly (`Cart-1/Arm`, dimensions
        // `D1@Cart-1/角度1@Arm`), their bases placed by the sub-assembly's frame; the
        // parts and components made for `urdf:` links stay generated.
        for r in &sub.robots {
            let r = r.nested(at, offset, frame);
            if self.robots.iter().any(|o| o.name() == r.name()) {
                return Err(taken("robot", r.name().to_string()));
            }
            self.robots.push(r);
        }
        self.generated.extend(sub.generated.iter().map(|g| name(g)));
        // Its equations, every name inside the sub-assembly (`"Cart-1/Factor"`,
        // `"D1@Cart-1/Gap"`), kept as the sub-document's for a save.
        for e in &sub.equations {
            let mut e = e.renamed(self.equations.len(), &mut |n| Ok(scoped(at, n)))?;
            e.scope = Some(match &e.scope {
                Some(s) => format!("{at}/{s}"),
                None => at.to_string(),
            });
            self.equations.push(e);
        }
        self.apply_assembly_suppression();
        Ok(())
    }

    /// The sub-assembly holding `name` whose content is another document's, the
    /// innermost, if any (full name).
    pub fn owning_sub_document(&self, name: &str) -> Option<&SubAssembly> {
        let mut best: Option<&SubAssembly> = None;
        for a in &self.assemblies {
            if a.file.is_some()
                && inside(name, &a.name).is_some()
                && best.is_none_or(|b| a.name.len() > b.name.len())
            {
                best = Some(a);
            }
        }
        best
    }

    /// The sub-document of the sub-assembly `at` as a document of its own: what it
    /// holds, named without the `at/` prefix, poses relative to `at`.
    fn extract(&self, at: &SubAssembly) -> Result<Document, DocumentError> {
        let record = at
            .file
            .as_ref()
            .ok_or_else(|| DocumentError::NotASubDocument(at.name.clone()))?;
        let inv = at.transform.inverse();
        let strip = |n: &str| inside(n, &at.name).map(str::to_string);
        let mut parts = indexmap::IndexMap::new();
        let mut components = Vec::new();
        let mut by_name = HashMap::new();
        let mut index = HashMap::new();
        let sub_dir = record.path.parent().unwrap_or(Path::new("."));
        for (i, c) in self.components.iter().enumerate() {
            let Some(n) = strip(&c.name) else { continue };
            let part = match strip(&c.part) {
                Some(p) => p,
                None => {
                    // a part of the assembly used inside (a script's add_component)
                    // goes with the sub-document, its file relative to it
                    let mut p = self.parts[&c.part].clone();
                    if let Some(rel) = crate::fsutil::relative_path(&p.mesh_path, sub_dir) {
                        p.stl = rel;
                    }
                    if !parts.contains_key(&p.name) {
                        parts.insert(p.name.clone(), p);
                    }
                    c.part.clone()
                }
            };
            index.insert(i, components.len());
            by_name.insert(n.clone(), components.len());
            let mut c = c.clone();
            c.name = n;
            c.part = part;
            c.transform = super::snapped(c.transform * inv);
            components.push(c);
        }
        for p in self.parts.values() {
            if let Some(n) = strip(&p.name) {
                let mut p = p.clone();
                p.name = n.clone();
                parts.insert(n, p);
            }
        }
        let assemblies = self
            .assemblies
            .iter()
            .filter_map(|a| {
                Some(SubAssembly {
                    name: strip(&a.name)?,
                    transform: super::snapped(a.transform * inv),
                    ..a.clone()
                })
            })
            .collect();
        let mut mates = Vec::new();
        for m in &self.mates {
            let Some(n) = strip(&m.name) else { continue };
            let mut m = m.clone();
            m.name = n;
            for e in m.entities.iter_mut().chain(m.about.as_mut()) {
                e.component = *index.get(&e.component).ok_or_else(|| {
                    DocumentError::OutsideSubDocument(Box::new(super::OutsideSubDocument {
                        file: record.file.clone(),
                        at: at.name.clone(),
                        item: OutsideItem::Mate {
                            mate: m.name.clone(),
                            component: self.components[e.component].name.clone(),
                        },
                    }))
                })?;
            }
            mates.push(m);
        }
        let mut equations = Vec::new();
        for e in &self.equations {
            let Some(scope) = &e.scope else { continue };
            let inner = if *scope == at.name {
                None
            } else if let Some(rest) = inside(scope, &at.name) {
                Some(rest.to_string())
            } else {
                continue;
            };
            let mut e = e.renamed(equations.len(), &mut |n| {
                unscoped(n, &at.name).ok_or_else(|| {
                    DocumentError::OutsideSubDocument(Box::new(super::OutsideSubDocument {
                        file: record.file.clone(),
                        at: at.name.clone(),
                        item: OutsideItem::Equation {
                            name: n.to_string(),
                        },
                    }))
                })
            })?;
            e.scope = inner;
            equations.push(e);
        }
        let mut robots = Vec::new();
        for r in &self.robots {
            if strip(r.name()).is_none() {
                continue;
            }
            robots.push(r.extracted(&at.name, &index, inv).map_err(|c| {
                DocumentError::OutsideSubDocument(Box::new(super::OutsideSubDocument {
                    file: record.file.clone(),
                    at: at.name.clone(),
                    item: OutsideItem::RobotLink {
                        robot: r.name().to_string(),
                        component: self.components[c].name.clone(),
                    },
                }))
            })?);
        }
        let generated = self.generated.iter().filter_map(|g| strip(g)).collect();
        let parts: indexmap::IndexMap<String, super::Part> = parts;
        Ok(Document {
            path: record.path.clone(),
            project: self.project.clone(),
            description: record.as_loaded.description.clone(),
            mesh_deflection: record.as_loaded.mesh_deflection,
            parts,
            components,
            numbering: super::numbering::Numbering::of(by_name.keys()),
            by_name,
            mates,
            equations,
            assemblies,
            robots,
            generated,
            revision: 0,
            aabb_cache: Default::default(),
            disk_hash: record.disk_hash,
            warnings: Vec::new(),
            removed: Vec::new(),
            saved_sub_documents: Vec::new(),
        })
    }

    /// The sub-assemblies whose content is another document, directly in this one
    /// (not inside another such), grouped by file.
    fn direct_sub_documents(&self) -> Vec<Vec<&SubAssembly>> {
        let mut groups: Vec<Vec<&SubAssembly>> = Vec::new();
        let held = HeldBy::new(&self.assemblies);
        for a in &self.assemblies {
            let Some(r) = &a.file else { continue };
            if held.inside(&a.name) {
                continue;
            }
            match groups
                .iter_mut()
                .find(|g| g[0].file.as_ref().is_some_and(|f| f.path == r.path))
            {
                Some(g) => g.push(a),
                None => groups.push(vec![a]),
            }
        }
        groups
    }

    /// Writes the sub-documents whose content changed (this document solved), deepest
    /// first; what was written is added to `written` (path, new hash, content).
    pub(super) fn save_sub_documents(
        &self,
        written: &mut Vec<Written>,
    ) -> Result<(), DocumentError> {
        for group in self.direct_sub_documents() {
            let docs = group
                .iter()
                .map(|a| self.extract(a))
                .collect::<Result<Vec<_>, _>>()?;
            let files: Vec<DocumentFile> = docs.iter().map(Document::to_file).collect();
            let record = |i: usize| group[i].file.as_ref().expect("grouped by file");
            let changed: Vec<usize> = (0..docs.len())
                .filter(|&i| !same_file(&files[i], &record(i).as_loaded))
                .collect();
            if changed.is_empty() {
                for d in &docs {
                    d.save_sub_documents(written)?;
                }
                continue;
            }
            if let Some(j) = (1..docs.len()).find(|&j| !same_file(&files[0], &files[j])) {
                return Err(DocumentError::Write {
                    path: record(0).path.clone(),
                    cause: WriteProblem::ChangedTwice {
                        first: group[0].name.clone(),
                        second: group[j].name.clone(),
                    },
                });
            }
            let mut doc = docs.into_iter().nth(changed[0]).expect("index in range");
            let r = record(changed[0]);
            let folder = match &self.project {
                Some(p) => Some(
                    p.folder(r.path.parent().unwrap_or(p.root()), false)
                        .map_err(|e| DocumentError::Write {
                            path: r.path.clone(),
                            cause: WriteProblem::Io(e.into()),
                        })?,
                ),
                None => None,
            };
            let hash = doc.disk_hash;
            doc.write_checked(&r.path.clone(), hash, folder, written)?;
            written.push(Written {
                path: r.path.clone(),
                hash: doc.disk_hash,
                file: Box::new(doc.to_file()),
            });
        }
        Ok(())
    }

    /// After a save: the records of the sub-documents written take their new content
    /// and hash.
    pub(super) fn saved(&mut self, written: Vec<Written>) {
        for w in &written {
            for a in &mut self.assemblies {
                if let Some(r) = &mut a.file {
                    if r.path == w.path {
                        r.disk_hash = w.hash;
                        r.as_loaded = w.file.clone();
                    }
                }
            }
        }
        self.saved_sub_documents = written.into_iter().map(|w| w.path).collect();
    }

    /// The sub-document files the last save wrote (besides the document's own), for
    /// callers that record their writes (watch mode).
    pub fn saved_sub_documents(&self) -> &[PathBuf] {
        &self.saved_sub_documents
    }
}

/// The names of the sub-assemblies that are other documents, to tell what they
/// hold.
pub(super) struct HeldBy<'a>(std::collections::HashSet<&'a str>);

impl<'a> HeldBy<'a> {
    pub fn new(assemblies: &'a [SubAssembly]) -> Self {
        HeldBy(
            assemblies
                .iter()
                .filter(|a| a.file.is_some())
                .map(|a| a.name.as_str())
                .collect(),
        )
    }

    /// Whether `name` (a component, sub-assembly, mate or part) is inside one (and so
    /// written in its file).
    pub fn inside(&self, name: &str) -> bool {
        !self.0.is_empty()
            && name
                .match_indices('/')
                .any(|(i, _)| self.0.contains(&name[..i]))
    }
}

/// A sub-document a save wrote.
pub(super) struct Written {
    path: PathBuf,
    hash: Option<u64>,
    file: Box<DocumentFile>,
}

/// Whether two document files hold the same content, numbers equal to 1e-9
/// (relative, at least absolute): poses composed and taken apart again differ from
/// the written ones in the last bits.
fn same_file(a: &DocumentFile, b: &DocumentFile) -> bool {
    fn same(a: &serde_yaml::Value, b: &serde_yaml::Value) -> bool {
        use serde_yaml::Value;
        match (a, b) {
            (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
                (Some(x), Some(y)) => (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0),
                _ => x == y,
            },
            (Value::Sequence(x), Value::Sequence(y)) => {
                x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same(a, b))
            }
            (Value::Mapping(x), Value::Mapping(y)) => {
                x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
            }
            _ => a == b,
        }
    }
    match (serde_yaml::to_value(a), serde_yaml::to_value(b)) {
        (Ok(x), Ok(y)) => same(&x, &y),
        _ => false,
    }
}
