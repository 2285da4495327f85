//! The project: the one folder that bounds every file a run touches (scripts, imports,
//! documents, meshes, CSV tables, programs, saves), and the rule that finds it.
//!
//! # The path rule
//!
//! - The project root is `--root` when given. Otherwise it is the nearest folder,
//!   starting at the script's (or, for `fitup check`, the document's) own folder and
//!   going up, that holds a [`PROJECT_FILE`] (`fitup.toml`); without one, the
//!   script's (document's) own folder.
//! - The SCRIPT (or document) argument on the command line is a path like any other
//!   command-line path: relative to the current folder, never to `--root`.
//! - Paths inside a script, and mesh paths inside a document, resolve against the
//!   project root (meshes: against the document's folder) and must stay inside the
//!   root: `..` that leaves it, absolute paths elsewhere and symbolic links that lead
//!   out are refused before anything is opened.

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
        path: String,
        /// The project root.
        root: PathBuf,
    },
    /// An output refused by the write rule ([`crate::fsutil::check_output`]).
    #[error("`{path}`: {cause}")]
    Refused {
        /// The path as written.
        path: String,
        /// Why.
        cause: crate::fsutil::OutputError,
    },
    /// The path cannot be resolved (an unreadable folder, …).
    #[error("`{path}` cannot be resolved: {message}")]
    Unresolvable {
        /// The path as written.
        path: String,
        /// Why.
        message: String,
    },
}

/// The folder a run may read and write in. Relative paths are resolved against it;
/// anything that resolves outside it is refused.
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
    pub fn for_file(file: &Path) -> std::io::Result<Self> {
        let file = file.canonicalize()?;
        let folder = file.parent().unwrap_or(Path::new("/"));
        if let Some(root) = folder.ancestors().find(|d| d.join(PROJECT_FILE).is_file()) {
            return Self::new(root);
        }
        Self::new(folder)
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
            path: path.to_string(),
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
                        path: path.to_string(),
                        message: "no such folder".into(),
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
                        path: path.to_string(),
                        message: e.to_string(),
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
            std::fs::create_dir_all(parent).map_err(|e| PathError::Unresolvable {
                path: path.to_string(),
                message: format!("cannot create its folder: {e}"),
            })?;
            // A folder created through a link planted meanwhile would be outside.
            let canon = parent.canonicalize().map_err(|e| PathError::Unresolvable {
                path: path.to_string(),
                message: e.to_string(),
            })?;
            if !canon.starts_with(&self.root) {
                return Err(PathError::Outside {
                    path: path.to_string(),
                    root: self.root.clone(),
                });
            }
        }
        Ok(full)
    }

    /// [`resolve_for_write`](Self::resolve_for_write) for an output file (CSV logs,
    /// exports, plans, key poses, recordings): the path must also pass the one write
    /// rule, [`crate::fsutil::check_output`] — never over a file the project uses or
    /// that fitup did not write, unless `rule.force` (`--force`, `overwrite: true`);
    /// never over a folder, FIFO, device or symbolic link. Write the output with
    /// [`crate::fsutil::write_output`] (or register it with
    /// [`crate::fsutil::register_output`]) so a later run may replace it.
    pub fn resolve_output(
        &self,
        path: &str,
        rule: &crate::fsutil::OutputRule,
    ) -> Result<PathBuf, PathError> {
        // `resolve` follows a symbolic link at the path itself; the rule must see it.
        let written = Path::new(path);
        let lexical = if written.is_absolute() {
            written.to_path_buf()
        } else {
            self.root.join(written)
        };
        let refused = |cause| PathError::Refused {
            path: path.to_string(),
            cause,
        };
        if std::fs::symlink_metadata(&lexical).is_ok_and(|m| m.file_type().is_symlink()) {
            return Err(refused(crate::fsutil::OutputError::Symlink));
        }
        let full = self.resolve_for_write(path)?;
        crate::fsutil::check_output(&full, rule).map_err(refused)?;
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
        let rule = crate::fsutil::OutputRule::default();
        std::fs::write(dir.path().join("models/cell.yaml"), "parts: {}\n").unwrap();
        assert!(p.resolve_output("models/cell.yaml", &rule).is_err());
        assert!(p.resolve_output("models", &rule).is_err());
        assert!(p.resolve_output("models/new.yaml", &rule).is_ok());
        // A file fitup did not write is kept; one it wrote may be replaced.
        std::fs::write(&w, "a,b\n").unwrap();
        assert!(matches!(
            p.resolve_output("out/sub/x.csv", &rule),
            Err(PathError::Refused {
                cause: crate::fsutil::OutputError::NotOurs,
                ..
            })
        ));
        crate::fsutil::write_output(&w, b"c,d\n", &crate::fsutil::OutputRule::forced(true))
            .unwrap();
        assert!(p.resolve_output("out/sub/x.csv", &rule).is_ok());
        #[cfg(unix)]
        {
            // A link at the output path itself is refused, even to a file inside.
            std::os::unix::fs::symlink(&w, dir.path().join("link.csv")).unwrap();
            let e = p
                .resolve_output("link.csv", &crate::fsutil::OutputRule::forced(true))
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
}
