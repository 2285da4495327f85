//! The STEP tessellations a project's documents ask for, and pruning the project's
//! tessellation store ([`crate::mesh::step::STEP_STORE`]) by them: what
//! `fitup cache prune` does (library: [`prune_project_store`]).

use super::file::{DocumentFile, PartFile};
use crate::mesh::step::{
    prune_held, PruneOptions, PruneReport, StoreError, Tessellation, DEFAULT_ANGULAR_DEFLECTION,
    DEFAULT_LINEAR_DEFLECTION, STEP_STORE,
};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// A `step:` part's tessellation: its linear deflection (mm) and angular deflection
/// (radians), from its `deflection:` (mm) and `angle:` (degrees) or the defaults —
/// the one place both the loader and the pruner take them from, so they agree bit for
/// bit.
pub fn of_part(pf: &PartFile) -> (f64, f64) {
    (
        pf.deflection.unwrap_or(DEFAULT_LINEAR_DEFLECTION),
        pf.angle.map_or(DEFAULT_ANGULAR_DEFLECTION, f64::to_radians),
    )
}

/// The most files [`in_use`] looks at, and how deep it goes: a project is a folder of
/// documents, not a disk.
const MAX_FILES: usize = 100_000;
const MAX_DEPTH: usize = 16;

/// What the documents of a project ask for.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InUse {
    /// Every `step:` part's file (canonical) and tessellation.
    pub tessellations: HashSet<Tessellation>,
    /// How many documents name a `step:` part.
    pub documents: usize,
    /// YAML files that name `step:` but could not be read as documents, and why: while
    /// there is one, what they ask for is not known.
    pub unreadable: Vec<(PathBuf, String)>,
}

/// The tessellations the documents under `root` ask for: every `.yaml`/`.yml` file
/// below it (not in hidden folders such as `.fitup-cache` or `.git`, nor `target`)
/// that mentions `step:` is read as a document, and each `step:` part's file is
/// resolved from the document's folder.
pub fn in_use(project: &crate::project::Project) -> InUse {
    let mut found = InUse::default();
    // Walked from the root's held handle without following a link (a folder swapped
    // for a link to an outside folder while this runs is skipped, never listed or
    // read), each document read through the folder handle it was listed in.
    let Ok(top) = project.folder(project.root(), false) else {
        return found;
    };
    let mut stack = vec![(project.root().to_path_buf(), top, 0)];
    let mut seen = 0;
    while let Some((dir, handle, depth)) = stack.pop() {
        let Ok(entries) = handle.entries() else {
            continue;
        };
        for (name_os, kind) in entries {
            seen += 1;
            if seen > MAX_FILES {
                return found;
            }
            let name = name_os.to_string_lossy().into_owned();
            if kind == crate::fsutil::Kind::Dir {
                if depth < MAX_DEPTH && !name.starts_with('.') && name != "target" {
                    if let Ok(sub) = handle.walk(Path::new(&name_os), false) {
                        stack.push((dir.join(&name_os), sub, depth + 1));
                    }
                }
                continue;
            }
            let yaml = name.ends_with(".yaml") || name.ends_with(".yml");
            if !matches!(kind, crate::fsutil::Kind::File(_)) || !yaml {
                continue;
            }
            let path = dir.join(&name_os);
            let Ok(text) = handle
                .open_file(&name_os)
                .map_err(|e| crate::fsutil::ReadError::Io(e.into()))
                .and_then(|f| crate::fsutil::read_opened(f, crate::fsutil::FileKind::Document))
                .and_then(|b| {
                    String::from_utf8(b).map_err(|e| {
                        crate::fsutil::ReadError::NotText(e.utf8_error().valid_up_to())
                    })
                })
            else {
                continue;
            };
            if !text.contains("step:") {
                continue;
            }
            match super::scan::from_yaml::<DocumentFile>(&text, &path, "document", "") {
                Err(e) => found.unreadable.push((path, e.to_string())),
                Ok((doc, _)) => {
                    let mut any = false;
                    for pf in doc.parts.values() {
                        let Some(step) = &pf.step else { continue };
                        any = true;
                        let Ok(file) = project.resolve_from(&dir, step) else {
                            continue;
                        };
                        let (linear, angular) = of_part(pf);
                        if let Some(t) = Tessellation::new(&file, linear, angular) {
                            found.tessellations.insert(t);
                        }
                    }
                    found.documents += usize::from(any);
                }
            }
        }
    }
    found
}

/// Prunes the tessellation store of `project` ([`prune_store`](crate::mesh::step::prune_store)): entries whose STEP
/// file is gone or changed, of an old format or damaged, whose tessellation no
/// document asks for (only while every document that names `step:` could be read),
/// dead writers' temporary files, then the least recently used down to `max_bytes`.
/// Nothing outside `.fitup-cache/step` of the project is touched; a store reached
/// through a symbolic link is refused. The documents, the store and the sources its
/// entries name are all reached from the project's held root folder, never by name:
/// the root's path renamed or swapped for a link meanwhile changes nothing. Returns
/// what was (or, with `dry_run`, would be) removed and what the documents ask for.
pub fn prune_project_store(
    project: &crate::project::Project,
    dry_run: bool,
    max_bytes: u64,
) -> Result<(PruneReport, InUse), StoreError> {
    let root = project.root();
    let io = |path: &Path, e: std::io::Error| StoreError::Io {
        path: path.to_path_buf(),
        kind: e.kind(),
    };
    let top = project.folder(root, false).map_err(|e| io(root, e))?;
    let cache = root.join(".fitup-cache");
    match top.stat(std::ffi::OsStr::new(".fitup-cache")) {
        Ok(None | Some(crate::fsutil::Kind::Dir)) => {}
        Ok(Some(_)) => return Err(StoreError::NotAFolder { path: cache }),
        Err(e) => return Err(io(&cache, e)),
    }
    let used = in_use(project);
    let options = PruneOptions {
        dry_run,
        max_bytes,
        in_use: used
            .unreadable
            .is_empty()
            .then(|| used.tessellations.clone()),
    };
    let store = root.join(STEP_STORE);
    let dir = match top.walk(Path::new(STEP_STORE), false) {
        Ok(d) => d,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok((PruneReport::default(), used))
        }
        Err(e) if e.kind() == std::io::ErrorKind::Other => {
            return Err(StoreError::NotAFolder { path: store })
        }
        Err(e) => return Err(io(&store, e)),
    };
    let report = prune_held(&store, dir, Some((root.to_path_buf(), top)), &options)?;
    Ok((report, used))
}
