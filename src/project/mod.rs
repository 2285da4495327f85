//! The project: the one folder that bounds every file a run touches (scripts, imports,
//! documents, meshes, CSV tables, programs, saves), and the rule that finds it.
//! Beside it, the write rule every output goes through and the registry of the files
//! fitup wrote ([`check_output`], [`write_output`], [`OUTPUT_REGISTRY`]).
//!
//! # The path rule
//!
//! - The project root is `--root` when given. Otherwise it is the nearest folder,
//!   starting at the script's (or, for `fitup check`, the document's) own folder and
//!   going up, that holds a [`PROJECT_FILE`] (`fitup.toml`); without one, the
//!   script's (document's) own folder. The folders are searched as the path is
//!   written, each held open from `/` down without following a link: a folder of the
//!   path that is a symbolic link is not looked through (the search goes on above
//!   it; pass `--root` for a project reached only through a link whose parents hold
//!   a `fitup.toml`).
//! - The SCRIPT (or document) argument on the command line is a path like any other
//!   command-line path: relative to the current folder, never to `--root`.
//! - Paths inside a script, and mesh paths inside a document, resolve against the
//!   project root (meshes: against the document's folder) and must stay inside the
//!   root: `..` that leaves it, absolute paths elsewhere and symbolic links that lead
//!   out are refused before anything is opened.

mod output;

pub use output::{
    check_output, is_source, register_output, register_stream, write_checked, write_output,
    OutputError, OutputRule, OUTPUT_REGISTRY, RRD_MAGIC, SQLITE_MAGIC,
};
pub(crate) use output::{check_output_in, write_in};
use std::path::{Component, Path, PathBuf};

/// The file that marks a project root (its content is not read yet).
pub const PROJECT_FILE: &str = "fitup.toml";

/// Why a path was refused or could not be resolved.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PathError {
    /// An empty path.
    #[error("empty path")]
    Empty,
    /// The path leads outside the project folder (by `..`, an absolute path or a
    /// symbolic link).
    #[error("`{path}` is outside the project folder {root}: only files inside it may be used (the project folder is `--root`, else the nearest folder holding fitup.toml, else the script's or document's own folder)")]
    Outside {
        /// The path as written.
        path: PathBuf,
        /// The project root.
        root: PathBuf,
    },
    /// An output refused by the write rule ([`check_output`]).
    #[error("`{path}`: {cause}")]
    Refused {
        /// The path as written.
        path: PathBuf,
        /// Why.
        cause: OutputError,
    },
    /// The path cannot be resolved (an unreadable folder, …).
    #[error("`{path}` cannot be resolved: {cause}")]
    Unresolvable {
        /// The path as written.
        path: PathBuf,
        /// Why.
        #[source]
        cause: Unresolved,
    },
}

/// Why a path cannot be resolved (the cause of a [`PathError::Unresolvable`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Unresolved {
    /// No folder on the way exists (not even a root).
    #[error("no such folder")]
    NoSuchFolder,
    /// The path ends in `..` or is a root: no file name.
    #[error("not a file name")]
    NotAFileName,
    /// The operating system could not resolve the existing part of the path.
    #[error(transparent)]
    Io(crate::fsutil::IoCause),
    /// Its folder could not be made.
    #[error("cannot create its folder: {0}")]
    CreateFolder(#[source] crate::fsutil::IoCause),
    /// Its folder could not be opened.
    #[error("cannot open its folder: {0}")]
    OpenFolder(#[source] crate::fsutil::IoCause),
}

/// The folder a run may read and write in. Relative paths are resolved against it;
/// anything that resolves outside it is refused.
///
/// The root folder is held open ([`crate::fsutil::Dir`]): files are opened and
/// written by walking from that handle without following a symbolic link
/// ([`Project::open_file`], [`Project::write_output`]), so a folder swapped for a link
/// between the path check and the use is refused, never followed outside.
#[derive(Debug, Clone)]
pub struct Project {
    root: PathBuf,
    dir: std::sync::Arc<crate::fsutil::Dir>,
}

impl PartialEq for Project {
    fn eq(&self, other: &Self) -> bool {
        self.root == other.root
    }
}

impl Eq for Project {}

impl Project {
    /// A project rooted at `root` (made absolute and canonical), its folder held open.
    pub fn new(root: &Path) -> std::io::Result<Self> {
        let root = root.canonicalize()?;
        let dir = crate::fsutil::Dir::open(&root)?;
        Ok(Self {
            root,
            dir: std::sync::Arc::new(dir),
        })
    }

    /// The folder `folder` (absolute, inside the root, as [`resolve`](Self::resolve)
    /// returns it) held open, reached from the root's handle one folder at a time
    /// without following a link; with `create`, missing folders are made.
    pub fn folder(&self, folder: &Path, create: bool) -> std::io::Result<crate::fsutil::Dir> {
        let rel = folder.strip_prefix(&self.root).map_err(|_| {
            std::io::Error::other(format!(
                "{} is outside the project folder {}",
                folder.display(),
                self.root.display()
            ))
        })?;
        self.dir.walk(rel, create)
    }

    /// Opens the regular file at `path` (absolute, inside the root, as
    /// [`resolve`](Self::resolve) returns it) for reading, through the root's handle:
    /// a link met on the way or at the file is refused, and a FIFO, device or socket
    /// is refused without blocking.
    pub fn open_file(&self, path: &Path) -> std::io::Result<std::fs::File> {
        let (Some(parent), Some(name)) = (path.parent(), path.file_name()) else {
            return Err(std::io::Error::other(format!(
                "{}: not a file name",
                path.display()
            )));
        };
        self.folder(parent, false)?.open_file(name)
    }

    /// Reads the file at `path` (see [`open_file`](Self::open_file)) whole, within the
    /// cap of `kind`.
    pub fn read_file(
        &self,
        path: &Path,
        kind: crate::fsutil::FileKind,
    ) -> Result<Vec<u8>, crate::fsutil::ReadError> {
        let f = self
            .open_file(path)
            .map_err(|e| crate::fsutil::ReadError::Io(e.into()))?;
        crate::fsutil::read_opened(f, kind)
    }

    /// [`read_file`](Self::read_file) as UTF-8 text.
    pub fn read_text(
        &self,
        path: &Path,
        kind: crate::fsutil::FileKind,
    ) -> Result<String, crate::fsutil::ReadError> {
        String::from_utf8(self.read_file(path, kind)?)
            .map_err(|e| crate::fsutil::ReadError::NotText(e.utf8_error().valid_up_to()))
    }

    /// Reads `path` as text, however the caller spelled it (relative to the working
    /// folder, or through links the caller named). A path that lies inside the project
    /// as written (made absolute against the working folder, without resolving links)
    /// is read through the root's held handle ([`read_text`](Self::read_text)), never
    /// by name: a folder on the way swapped for a link is refused, not followed. Only
    /// when such a read meets a link is the folder resolved, and the file read through
    /// the held handle if it lies inside the project (a link that leads out is
    /// refused). A path outside the project as written and as resolved (a document
    /// given on the command line with another `--root`) is read by its path.
    pub fn read_named_text(
        &self,
        path: &Path,
        kind: crate::fsutil::FileKind,
    ) -> Result<String, crate::fsutil::ReadError> {
        let lexical = lexical_absolute(path).filter(|p| p.starts_with(&self.root));
        if let Some(full) = &lexical {
            match self.read_text(full, kind) {
                Err(crate::fsutil::ReadError::Io(e)) if e.to_string().contains("symbolic link") => {
                }
                other => return other,
            }
        }
        let parent = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let full = match (parent.canonicalize(), path.file_name()) {
            (Ok(dir), Some(name)) => dir.join(name),
            _ if lexical.is_some() => {
                return Err(crate::fsutil::ReadError::FolderUnresolvable(
                    path.to_path_buf(),
                ))
            }
            _ => return crate::fsutil::read_text(path, kind),
        };
        if full.starts_with(&self.root) {
            self.read_text(&full, kind)
        } else if lexical.is_some() {
            Err(crate::fsutil::ReadError::LinkOutside {
                path: path.to_path_buf(),
                root: self.root.clone(),
            })
        } else {
            crate::fsutil::read_text(path, kind)
        }
    }

    /// The project of a script or document at `file` when no `--root` is given: the
    /// nearest folder from the file's own folder upwards holding [`PROJECT_FILE`],
    /// else the file's own folder.
    ///
    /// # Examples
    /// ```
    /// let dir = tempfile::tempdir().unwrap();
    /// std::fs::create_dir(dir.path().join("scripts")).unwrap();
    /// std::fs::write(dir.path().join("fitup.toml"), "").unwrap();
    /// std::fs::write(dir.path().join("scripts/a.rhai"), "").unwrap();
    /// let p = fitup::project::Project::for_file(&dir.path().join("scripts/a.rhai")).unwrap();
    /// assert_eq!(p.root(), dir.path().canonicalize().unwrap());
    /// ```
    ///
    /// The folders above the file are first searched as the path is written (made
    /// absolute against the working folder): every folder from `/` down to the file's
    /// own is opened from its parent's held handle without following a link
    /// ([`held_chain`]), and each is asked for [`PROJECT_FILE`] through its handle, so
    /// a folder of the path swapped for a link (at any depth, to an outside folder
    /// that holds a `fitup.toml`) is never looked through: the search stops above
    /// the link. Only when the written path meets a link and no folder above it
    /// holds a [`PROJECT_FILE`] are links resolved (the caller named them) and the
    /// canonical path walked the same way; a link met on that walk (the path changed
    /// while it was searched) stops it too.
    pub fn for_file(file: &Path) -> std::io::Result<Self> {
        Self::search(file, true)
    }

    /// The project of the folder `folder` (`fitup cache prune DIR`): the nearest
    /// folder from `folder` itself upwards holding [`PROJECT_FILE`], else `folder`,
    /// searched as [`for_file`](Self::for_file) searches (every folder held from `/`
    /// down without following a link; links resolved only when nothing above the
    /// first one holds a [`PROJECT_FILE`]). The root is the folder that was opened,
    /// held: nothing looks it up by name again.
    pub fn for_folder(folder: &Path) -> std::io::Result<Self> {
        Self::search(folder, false)
    }

    /// [`for_file`](Self::for_file) (`of_file`: the search starts at `path`'s folder)
    /// or [`for_folder`](Self::for_folder) (it starts at `path`).
    fn search(path: &Path, of_file: bool) -> std::io::Result<Self> {
        let start = |p: &Path| -> Option<PathBuf> {
            if of_file {
                p.parent().map(Path::to_path_buf)
            } else {
                Some(p.to_path_buf())
            }
        };
        if let Some(abs) = lexical_absolute(path).as_deref().and_then(start) {
            if let Some(p) = Self::in_chain(&abs) {
                return p;
            }
        }
        let canonical = path.canonicalize()?;
        let folder = start(&canonical).unwrap_or_else(|| PathBuf::from("/"));
        if let Some(p) = Self::in_chain(&folder) {
            return p;
        }
        if held_chain(&folder).1 == Walked::Unopenable {
            // A folder that may be searched but not listed (mode 0711): it cannot be
            // held, so it is looked up by name.
            let root = folder
                .ancestors()
                .find(|d| d.join(PROJECT_FILE).is_file())
                .unwrap_or(&folder);
            return Self::new(root);
        }
        Err(std::io::Error::other(format!(
            "{}: a folder on its path changed while its project was searched",
            canonical.display()
        )))
    }

    /// The project of a file in `folder` (absolute) from [`held_chain`] of it: the
    /// deepest held folder holding [`PROJECT_FILE`]; else, when the whole path was
    /// walked, `folder` itself; else `None` (a link on the way).
    fn in_chain(folder: &Path) -> Option<std::io::Result<Self>> {
        let (mut chain, walked) = held_chain(folder);
        let found = chain.iter().rposition(|d| {
            matches!(
                d.stat(std::ffi::OsStr::new(PROJECT_FILE)),
                Ok(Some(crate::fsutil::Kind::File(_)))
            )
        });
        let dir = match found {
            Some(i) => chain.swap_remove(i),
            None if walked == Walked::Whole => chain.pop()?,
            None => return None,
        };
        // The root's canonical name is that of the folder opened (not a second lookup
        // by name).
        let root = dir
            .raw_fd()
            .and_then(|fd| std::fs::read_link(format!("/proc/self/fd/{fd}")).ok())
            .filter(|r| r.is_absolute())
            .unwrap_or_else(|| dir.path().to_path_buf());
        Some(Ok(Self {
            root,
            dir: std::sync::Arc::new(dir),
        }))
    }

    /// The canonical root folder.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The absolute path of `path` (relative to the root), checked to lie inside the
    /// project. `..` components and symbolic links are resolved before the check, so
    /// neither can escape. The file need not exist (for writes).
    pub fn resolve(&self, path: &str) -> Result<PathBuf, PathError> {
        self.resolve_from(&self.root, path)
    }

    /// Like [`resolve`](Self::resolve), with a relative `path` taken relative to the
    /// folder `base` (a document's folder for its mesh paths). The result must still
    /// lie inside the project.
    pub fn resolve_from(&self, base: &Path, path: &str) -> Result<PathBuf, PathError> {
        if path.is_empty() {
            return Err(PathError::Empty);
        }
        let outside = || PathError::Outside {
            path: path.into(),
            root: self.root.clone(),
        };
        let p = Path::new(path);
        let joined = if p.is_absolute() {
            p.to_path_buf()
        } else {
            base.join(p)
        };
        // Canonicalize the deepest existing ancestor, then append the rest lexically
        // (refusing `..` there: its meaning would depend on folders not yet made).
        let mut existing = joined.clone();
        let mut rest = Vec::new();
        while std::fs::symlink_metadata(&existing).is_err() {
            match (existing.file_name(), existing.parent()) {
                (Some(name), Some(parent)) => {
                    rest.push(name.to_os_string());
                    existing = parent.to_path_buf();
                }
                _ => {
                    if existing.ends_with("..") {
                        return Err(outside());
                    }
                    return Err(PathError::Unresolvable {
                        path: path.into(),
                        cause: Unresolved::NoSuchFolder,
                    });
                }
            }
        }
        // A dangling symbolic link: canonicalize fails; refuse rather than guess.
        let mut full =
            existing
                .canonicalize()
                .map_err(|e| match std::fs::read_link(&existing) {
                    Ok(_) => outside(),
                    Err(_) => PathError::Unresolvable {
                        path: path.into(),
                        cause: Unresolved::Io(e.into()),
                    },
                })?;
        for name in rest.iter().rev() {
            if Path::new(name)
                .components()
                .any(|c| matches!(c, Component::ParentDir))
            {
                return Err(outside());
            }
            full.push(name);
        }
        if !full.starts_with(&self.root) {
            return Err(outside());
        }
        Ok(full)
    }

    /// [`resolve`](Self::resolve) for a file about to be written: also creates the
    /// missing folders leading to it (inside the project), so scripts can write to
    /// `out/…` in a fresh clone.
    pub fn resolve_for_write(&self, path: &str) -> Result<PathBuf, PathError> {
        let full = self.resolve(path)?;
        if let Some(parent) = full.parent() {
            // Made by walking from the root's handle: a folder swapped for a link
            // meanwhile is refused, and no folder is ever made outside.
            self.folder(parent, true)
                .map_err(|e| PathError::Unresolvable {
                    path: path.into(),
                    cause: Unresolved::CreateFolder(e.into()),
                })?;
        }
        Ok(full)
    }

    /// [`resolve_for_write`](Self::resolve_for_write) for an output file (CSV logs,
    /// exports, plans, key poses, recordings): the path must also pass the one write
    /// rule, [`check_output`] — never over a file the project uses or
    /// that fitup did not write, unless `rule.force` (`--force`, `overwrite: true`);
    /// never over a folder, FIFO, device or symbolic link. This only checks (for
    /// writers that refuse before working); write with
    /// [`write_output`](Self::write_output), which checks again through the handle
    /// it writes with.
    pub fn resolve_output(&self, path: &str, rule: &OutputRule) -> Result<PathBuf, PathError> {
        let (full, dir) = self.output_folder(path)?;
        let name = full.file_name().unwrap_or_default();
        check_output_in(&dir, name, &full, rule).map_err(|cause| PathError::Refused {
            path: path.into(),
            cause,
        })?;
        Ok(full)
    }

    /// Writes `bytes` as the output `path` (relative to the root): resolved inside the
    /// project, its folder made and held open by walking from the root's handle, the
    /// write rule checked ([`check_output`]) and the file written
    /// atomically and listed in the folder's registry — all through that one handle,
    /// so a folder swapped for a link midway is refused and nothing (the output, its
    /// temporary file, the registry) lands outside. Returns the file's path.
    pub fn write_output(
        &self,
        path: &str,
        bytes: &[u8],
        rule: &OutputRule,
    ) -> Result<PathBuf, PathError> {
        let (full, dir) = self.output_folder(path)?;
        let name = full.file_name().unwrap_or_default();
        let refused = |cause| PathError::Refused {
            path: path.into(),
            cause,
        };
        check_output_in(&dir, name, &full, rule).map_err(refused)?;
        write_in(&dir, name, bytes).map_err(refused)?;
        Ok(full)
    }

    /// The full path of the output `path` and its folder held open (made when
    /// missing); a link at the path itself is refused by name first, since
    /// [`resolve`](Self::resolve) would follow it.
    fn output_folder(&self, path: &str) -> Result<(PathBuf, crate::fsutil::Dir), PathError> {
        let written = Path::new(path);
        let lexical = if written.is_absolute() {
            written.to_path_buf()
        } else {
            self.root.join(written)
        };
        if std::fs::symlink_metadata(&lexical).is_ok_and(|m| m.file_type().is_symlink()) {
            return Err(PathError::Refused {
                path: path.into(),
                cause: OutputError::Symlink,
            });
        }
        let full = self.resolve(path)?;
        let (Some(parent), Some(_)) = (full.parent(), full.file_name()) else {
            return Err(PathError::Unresolvable {
                path: path.into(),
                cause: Unresolved::NotAFileName,
            });
        };
        let dir = self
            .folder(parent, true)
            .map_err(|e| PathError::Unresolvable {
                path: path.into(),
                cause: Unresolved::OpenFolder(e.into()),
            })?;
        Ok((full, dir))
    }

    /// `path` shown relative to the root when inside it.
    pub fn display(&self, path: &Path) -> String {
        path.strip_prefix(&self.root)
            .unwrap_or(path)
            .display()
            .to_string()
    }
}

/// `path` made absolute against the working folder without resolving links, `.`
/// dropped; `None` when it holds `..` (its meaning would depend on links) or the
/// working folder is unknown.
/// The fallback of callers whose file may not exist yet: when [`Project::for_file`]
/// failed because the file is missing (`NotFound`), the project rooted at `folder`;
/// any other failure (a folder on the path changed while it was searched) is kept,
/// never answered by a lookup of `folder` by name.
pub(crate) fn unless_missing(e: std::io::Error, folder: &Path) -> std::io::Result<Project> {
    if e.kind() == std::io::ErrorKind::NotFound {
        Project::new(folder)
    } else {
        Err(e)
    }
}

/// Every folder from `/` down to `folder` (absolute), each opened from the one above
/// it without following a link (one held handle per level), stopping at the first
/// link or folder that cannot be opened; how far it went.
fn held_chain(folder: &Path) -> (Vec<crate::fsutil::Dir>, Walked) {
    let mut chain: Vec<crate::fsutil::Dir> = Vec::new();
    let mut comps = folder.components();
    match comps.next() {
        Some(Component::RootDir) => {}
        _ => return (chain, Walked::Unopenable),
    }
    let Ok(top) = crate::fsutil::Dir::open(Path::new("/")) else {
        return (chain, Walked::Unopenable);
    };
    chain.push(top);
    for c in comps {
        let Component::Normal(name) = c else {
            return (chain, Walked::Unopenable);
        };
        let next = chain.last().map(|d| d.walk(Path::new(name), false));
        match next {
            Some(Ok(d)) => chain.push(d),
            Some(Err(e)) if e.kind() == std::io::ErrorKind::PermissionDenied => {
                return (chain, Walked::Unopenable)
            }
            _ => return (chain, Walked::Link),
        }
    }
    (chain, Walked::Whole)
}

/// How far [`held_chain`] walked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Walked {
    /// Down to the folder asked for.
    Whole,
    /// Up to a link, a missing folder or something not a folder.
    Link,
    /// Up to a folder it may not open (searchable, not readable), or a path it cannot
    /// walk (not absolute).
    Unopenable,
}

fn lexical_absolute(path: &Path) -> Option<PathBuf> {
    let base = if path.is_absolute() {
        PathBuf::new()
    } else {
        std::env::current_dir().ok()?
    };
    let mut out = base;
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => return None,
            other => out.push(other.as_os_str()),
        }
    }
    Some(out)
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
        assert!(matches!(p.resolve("../x"), Err(PathError::Outside { .. })));
        assert!(matches!(
            p.resolve("models/../../x"),
            Err(PathError::Outside { .. })
        ));
        assert!(matches!(
            p.resolve("new/../../x"),
            Err(PathError::Outside { .. })
        ));
        assert!(matches!(
            p.resolve("/etc/passwd"),
            Err(PathError::Outside { .. })
        ));
        assert_eq!(p.resolve(""), Err(PathError::Empty));
        let models = dir.path().canonicalize().unwrap().join("models");
        assert!(p.resolve_from(&models, "../models/a.stl").is_ok());
        assert!(p.resolve_from(&models, "../../a.stl").is_err());
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("/tmp", dir.path().join("escape")).unwrap();
            assert!(p.resolve("escape/x").is_err());
            std::os::unix::fs::symlink("/etc/passwd", dir.path().join("pw.stl")).unwrap();
            assert!(p.resolve("pw.stl").is_err());
            std::os::unix::fs::symlink("/nonexistent/x", dir.path().join("dangling")).unwrap();
            assert!(p.resolve("dangling").is_err());
            assert!(p.resolve_for_write("escape/new/x.csv").is_err());
        }
        let w = p.resolve_for_write("out/sub/x.csv").unwrap();
        assert!(w.parent().unwrap().is_dir());
        let rule = OutputRule::default();
        std::fs::write(dir.path().join("models/cell.yaml"), "parts: {}\n").unwrap();
        assert!(p.resolve_output("models/cell.yaml", &rule).is_err());
        assert!(p.resolve_output("models", &rule).is_err());
        assert!(p.resolve_output("models/new.yaml", &rule).is_ok());
        // A file fitup did not write is kept; one it wrote may be replaced.
        std::fs::write(&w, "a,b\n").unwrap();
        assert!(matches!(
            p.resolve_output("out/sub/x.csv", &rule),
            Err(PathError::Refused {
                cause: OutputError::NotOurs,
                ..
            })
        ));
        write_output(&w, b"c,d\n", &OutputRule::forced(true)).unwrap();
        assert!(p.resolve_output("out/sub/x.csv", &rule).is_ok());
        #[cfg(unix)]
        {
            // A link at the output path itself is refused, even to a file inside.
            std::os::unix::fs::symlink(&w, dir.path().join("link.csv")).unwrap();
            let e = p
                .resolve_output("link.csv", &OutputRule::forced(true))
                .unwrap_err();
            assert!(e.to_string().contains("symbolic link"), "{e}");
        }
    }

    #[test]
    fn the_root_is_the_nearest_folder_with_fitup_toml() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().canonicalize().unwrap();
        std::fs::create_dir_all(d.join("a/b")).unwrap();
        std::fs::write(d.join("a/b/s.rhai"), "").unwrap();
        // No fitup.toml: the script's own folder.
        let p = Project::for_file(&d.join("a/b/s.rhai")).unwrap();
        assert_eq!(p.root(), d.join("a/b"));
        std::fs::write(d.join("a/fitup.toml"), "").unwrap();
        let p = Project::for_file(&d.join("a/b/s.rhai")).unwrap();
        assert_eq!(p.root(), d.join("a"));
    }

    /// A link on the written path, however far above the file, is not looked through:
    /// the search goes on above it (here: `p`, not the `fitup.toml` three levels down
    /// the link), and links are resolved only when nothing above one holds a
    /// `fitup.toml`.
    #[test]
    fn the_search_never_looks_through_a_link_on_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path().canonicalize().unwrap();
        let (p, o) = (d.join("p"), d.join("o"));
        std::fs::create_dir_all(o.join("b/c")).unwrap();
        std::fs::create_dir_all(&p).unwrap();
        for f in ["b/c/s.rhai", "b/c/fitup.toml", "b/fitup.toml"] {
            std::fs::write(o.join(f), "").unwrap();
        }
        std::os::unix::fs::symlink(&o, p.join("a")).unwrap();
        // Nothing above the link holds fitup.toml: the links are resolved.
        let found = Project::for_file(&p.join("a/b/c/s.rhai")).unwrap();
        assert_eq!(found.root(), o.join("b/c"));
        std::fs::write(p.join("fitup.toml"), "").unwrap();
        let found = Project::for_file(&p.join("a/b/c/s.rhai")).unwrap();
        assert_eq!(found.root(), p);
        // Reading the file through that project meets the link: refused, not read.
        let e = found
            .read_named_text(&p.join("a/b/c/s.rhai"), crate::fsutil::FileKind::Script)
            .unwrap_err();
        assert!(e.to_string().contains("outside the project"), "{e}");
    }
}
