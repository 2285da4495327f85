//! A STEP assembly as a new document (`fitup import`): one part per distinct solid
//! (meshed once, written as a binary STL under `meshes/`), one component per placed
//! solid, the product tree kept as sub-assemblies (groups in the document: the root
//! assembly is the document, each sub-assembly occurrence an `assemblies:` entry, so
//! full names read `Frame-1/Wheel-2` and poses compose through the levels to the
//! file's placements), names from the tree made unique among their siblings and safe,
//! the tessellation recorded in the document's description.
//!
//! Nothing is half-written: the STEP file is read and every output checked by the
//! write rule ([`crate::project::check_output`]) before the first byte is written. A new
//! project folder is built in a temporary folder beside it and renamed into place; in
//! an existing folder each file is written atomically, the document last, and the
//! meshes written so far are removed when a later write fails.

use super::file::{AssemblyFile, ComponentFile, DocumentFile, PartFile};
use super::{Document, DocumentError};
use crate::mesh::step::{read_step, StepError, StepModel, StepOptions};
use crate::mesh::MeshError;
use crate::project::{OutputError, OutputRule};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

/// How to import.
#[derive(Debug, Clone, Default)]
pub struct ImportOptions {
    /// Reading and tessellation (deflection, time limit, triangle cap).
    pub step: StepOptions,
    /// Replace existing files at the output paths (`--force`), never a folder, FIFO or
    /// symbolic link.
    pub force: bool,
}

/// One part the import wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedPart {
    /// Its name in the document.
    pub name: String,
    /// Its STL, relative to the document's folder.
    pub stl: String,
    /// Triangles of its mesh.
    pub triangles: usize,
    /// Mesh volume over the exact B-rep volume.
    pub volume_ratio: f64,
    /// How many components place it.
    pub instances: usize,
    /// Gaps of Open CASCADE's mesh closed to make it a closed solid
    /// ([`StepPart::mended`](crate::mesh::step::StepPart::mended)).
    pub mended: usize,
}

/// What [`import_step`] wrote.
#[derive(Debug, Clone)]
pub struct ImportReport {
    /// The document.
    pub document: PathBuf,
    /// Whether the folder was created (with a `fitup.toml`).
    pub new_project: bool,
    /// The parts, in document order.
    pub parts: Vec<ImportedPart>,
    /// How many components.
    pub components: usize,
    /// The read itself: units, options, timings.
    pub model: StepModel,
}

/// Why an import wrote nothing (or removed what it had written).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImportError {
    /// The STEP file could not be read (see [`StepError`]).
    #[error(transparent)]
    Step(#[from] StepError),
    /// An output may not be written (the write rule refused it).
    #[error("{}: {source}", path.display())]
    Output {
        /// The output.
        path: PathBuf,
        /// Why.
        source: OutputError,
    },
    /// The operating system refused (creating a folder, renaming, …).
    #[error("{}: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The document could not be written as YAML (a bug: reported, nothing kept).
    #[error("the imported document cannot be written as YAML: {source}")]
    Yaml {
        /// The serializer's error.
        source: serde_yaml::Error,
    },
    /// A mesh could not be written.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The document made would not load again (a bug: reported, nothing kept).
    #[error("the imported document would not load: {0}")]
    Document(#[from] DocumentError),
}

fn io_err(path: &Path, source: std::io::Error) -> ImportError {
    ImportError::Io {
        path: path.into(),
        source,
    }
}

/// What a new project's `fitup.toml` says (the mark of a project root).
const PROJECT_TOML: &str = "# Marks the root of a fitup project (written by `fitup import`): scripts below this\n# folder resolve their paths against it and may use files inside it only (docs/scripting.md).\n";

/// The longest name (characters) the import gives a part or component.
const MAX_NAME_CHARS: usize = 80;

/// A name from the file as a document name: NFC, control and invisible characters
/// ([`crate::diagnostics::hidden_char`]) and `/` (which separates component and
/// reference) replaced by `_`, trimmed, at most [`MAX_NAME_CHARS`]; `fallback` when
/// nothing is left.
pub fn document_name(raw: &str, fallback: &str) -> String {
    let name: String = super::nfc_name(raw)
        .chars()
        .map(|c| {
            if c == '/' || crate::diagnostics::hidden_char(c).is_some() {
                '_'
            } else {
                c
            }
        })
        .take(MAX_NAME_CHARS)
        .collect();
    let name = name.trim();
    if name.is_empty() {
        fallback.to_string()
    } else {
        name.to_string()
    }
}

/// `name`, or `name_2`, `name_3`, … : the first not in `taken` (compared as given,
/// so in NFC), which it joins.
fn unique(name: String, taken: &mut HashSet<String>) -> String {
    let mut candidate = name.clone();
    let mut k = 2;
    while taken.contains(&candidate) {
        candidate = format!("{name}_{k}");
        k += 1;
    }
    taken.insert(candidate.clone());
    candidate
}

/// A file name for a part's STL: letters and digits of any script, `-`, `_` and `.`
/// kept, anything else `_`, no leading `.`; unique ignoring case (`taken` holds
/// lower-case stems), since macOS and Windows file systems ignore it.
fn file_stem(name: &str, taken: &mut HashSet<String>) -> String {
    let stem: String = name
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .take(MAX_NAME_CHARS)
        .collect();
    let stem = stem.trim_start_matches('.');
    let stem = if stem.is_empty() { "part" } else { stem };
    let mut candidate = stem.to_string();
    let mut k = 2;
    while !taken.insert(candidate.to_lowercase()) {
        candidate = format!("{stem}_{k}");
        k += 1;
    }
    candidate
}

/// Whether `name` is an occurrence id an exporter generated (`NAUO12`: SolidWorks names
/// every NEXT_ASSEMBLY_USAGE_OCCURRENCE so) rather than a name a user gave.
fn generated_occurrence_id(name: &str) -> bool {
    let n = name.trim();
    n.get(..4).is_some_and(|p| p.eq_ignore_ascii_case("NAUO"))
        && n.len() > 4
        && n[4..].bytes().all(|b| b.is_ascii_digit())
}

/// `leaf` inside the sub-assembly `parent` (`parent/leaf`), or at the top.
fn within(parent: Option<&str>, leaf: &str) -> String {
    match parent {
        Some(p) => format!("{p}/{leaf}"),
        None => leaf.to_string(),
    }
}

/// How the file's assembly tree maps onto the document's levels.
struct Tree {
    /// The one root assembly that is the document itself (when the file has exactly
    /// one free shape and it is an assembly, as CAD exports have).
    document: Option<usize>,
}

impl Tree {
    fn of(model: &StepModel) -> Tree {
        let roots: Vec<usize> = model
            .assemblies
            .iter()
            .enumerate()
            .filter(|(_, a)| a.parent.is_none())
            .map(|(k, _)| k)
            .collect();
        let free_solids = model.instances.iter().any(|i| i.parent.is_none());
        Tree {
            document: match roots[..] {
                [only] if !free_solids => Some(only),
                _ => None,
            },
        }
    }

    fn is_document(&self, k: usize) -> bool {
        self.document == Some(k)
    }

    /// The document level of something held by the assembly `parent`: the
    /// sub-assembly's index, or `None` at the top.
    fn level(&self, parent: Option<usize>) -> Option<usize> {
        parent.filter(|&p| !self.is_document(p))
    }

    /// The pose of a document level in the file's root frame (the document's frame).
    fn pose(&self, level: Option<usize>, model: &StepModel) -> crate::math::Transform {
        level.map_or(crate::math::Transform::IDENTITY, |k| {
            model.assemblies[k].transform
        })
    }
}

/// The document (not yet written) and the meshes' relative paths for `model`.
fn build(model: &StepModel) -> (DocumentFile, Vec<ImportedPart>) {
    let step_stem = model
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut part_names = HashSet::new();
    let mut stems = HashSet::new();
    let mut parts = Vec::with_capacity(model.parts.len());
    let mut doc = DocumentFile {
        units: "mm".into(),
        description: Some(format!(
            "Imported from {} by `fitup import` (file unit {}; tessellation: linear deflection {} mm, angular deflection {} rad)",
            document_name(
                &model.path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default(),
                "a STEP file"
            ),
            if model.file_unit.is_empty() { "not stated" } else { &model.file_unit },
            model.options.linear_deflection,
            model.options.angular_deflection,
        )),
        mesh_deflection: Some(model.options.linear_deflection),
        ..DocumentFile::default()
    };
    for p in &model.parts {
        let mut base = document_name(&p.product, &document_name(&step_stem, "part"));
        if p.solid.1 > 1 {
            base = format!("{base}-solid{}", p.solid.0);
        }
        let name = unique(base, &mut part_names);
        let stl = format!("meshes/{}.stl", file_stem(&name, &mut stems));
        doc.parts
            .insert(name.clone(), PartFile::from_stl(stl.clone()));
        parts.push(ImportedPart {
            name,
            stl,
            triangles: p.mesh.triangles.len(),
            volume_ratio: p.volume_ratio(),
            instances: 0,
            mended: p.mended,
        });
    }
    // The product tree as sub-assemblies (groups in this document): one root
    // assembly is the document itself; any other assembly occurrence is a
    // sub-assembly named inside its parent (`Frame-1/Wheel-2`), posed relative to it.
    let tree = Tree::of(model);
    let mut taken: HashMap<Option<usize>, HashSet<String>> = HashMap::new();
    let mut counts: HashMap<(Option<usize>, String), usize> = HashMap::new();
    // Each assembly's place in the document: its full name, or `None` for the root
    // that is the document.
    let mut full: Vec<Option<String>> = Vec::with_capacity(model.assemblies.len());
    for (k, a) in model.assemblies.iter().enumerate() {
        if tree.is_document(k) {
            full.push(None);
            continue;
        }
        let level = tree.level(a.parent);
        let product = document_name(&a.product, "assembly");
        let n = counts.entry((level, format!("a:{product}"))).or_insert(0);
        *n += 1;
        let given = if generated_occurrence_id(&a.name) {
            ""
        } else {
            &a.name
        };
        let leaf = unique(
            document_name(given, &format!("{product}-{n}")),
            taken.entry(level).or_default(),
        );
        let name = within(level.and_then(|p| full[p].as_deref()), &leaf);
        let parent_pose = tree.pose(level, model);
        doc.assemblies.push(AssemblyFile {
            name: name.clone(),
            transform: Some(a.transform.then(&parent_pose.inverse()).to_matrix()),
            file: None,
            suppressed: false,
        });
        full.push(Some(name));
    }
    for inst in &model.instances {
        let part = &mut parts[inst.part];
        part.instances += 1;
        let level = tree.level(inst.parent);
        let n = counts.entry((level, part.name.clone())).or_insert(0);
        *n += 1;
        // SolidWorks (and other exporters) name every occurrence `NAUO<n>`, which says
        // nothing; such components are named as SolidWorks' own tree names them.
        let given = if generated_occurrence_id(&inst.name) {
            ""
        } else {
            &inst.name
        };
        let leaf = unique(
            document_name(given, &format!("{}-{n}", part.name)),
            taken.entry(level).or_default(),
        );
        let parent_pose = tree.pose(level, model);
        doc.components.push(ComponentFile::new(
            within(level.and_then(|p| full[p].as_deref()), &leaf),
            part.name.clone(),
            Some(inst.transform.then(&parent_pose.inverse()).to_matrix()),
        ));
    }
    (doc, parts)
}

/// Reads `step` and writes a document for it into `out`: `out/<stem>.yaml` and
/// `out/meshes/*.stl`. A missing or empty `out` becomes a new project (with a
/// `fitup.toml`); in an existing folder the files are added beside what is there, and
/// any existing file at an output path is refused unless `options.force`.
pub fn import_step(
    step: &Path,
    out: &Path,
    options: &ImportOptions,
) -> Result<ImportReport, ImportError> {
    let model = read_step(step, &options.step)?;
    let (doc, mut parts) = build(&model);
    let text = doc
        .to_yaml()
        .map_err(|source| ImportError::Yaml { source })?;
    let stem = document_name(
        &step
            .file_stem()
            .map(|s| s.to_string_lossy())
            .unwrap_or_default(),
        "assembly",
    );
    let doc_name = format!("{}.yaml", file_stem(&stem, &mut HashSet::new()));
    // The text must load as a document before anything is written.
    Document::parse_text(&text, &out.join(&doc_name))?;
    let new_project = match std::fs::read_dir(out) {
        Ok(mut entries) => entries.next().is_none(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => true,
        Err(e) => return Err(io_err(out, e)),
    };
    let meshes: Vec<(PathBuf, &crate::mesh::Mesh)> = parts
        .iter()
        .zip(&model.parts)
        .map(|(p, m)| (PathBuf::from(&p.stl), &m.mesh))
        .collect();
    if new_project {
        write_new(out, &doc_name, &text, &meshes)?;
    } else {
        write_into(out, &doc_name, &text, &meshes, options.force)?;
    }
    let document = out.join(&doc_name);
    // What was written loads as a document (meshes and all).
    let loaded = Document::open(&document)?;
    for p in &mut parts {
        p.triangles = loaded
            .part(&p.name)
            .map_or(p.triangles, |q| q.mesh.triangles.len());
    }
    Ok(ImportReport {
        document,
        new_project,
        components: doc.components.len(),
        parts,
        model,
    })
}

/// A new project: everything in a temporary folder beside `out`, renamed into place.
fn write_new(
    out: &Path,
    doc_name: &str,
    text: &str,
    meshes: &[(PathBuf, &crate::mesh::Mesh)],
) -> Result<(), ImportError> {
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(parent).map_err(|e| io_err(parent, e))?;
    let tmp = tempfile::Builder::new()
        .prefix(".fitup-import-")
        .tempdir_in(parent)
        .map_err(|e| io_err(parent, e))?;
    std::fs::create_dir(tmp.path().join("meshes")).map_err(|e| io_err(tmp.path(), e))?;
    for (rel, mesh) in meshes {
        crate::mesh::write_stl(&tmp.path().join(rel), mesh)?;
    }
    let toml = tmp.path().join("fitup.toml");
    crate::fsutil::write_atomic(&toml, PROJECT_TOML.as_bytes()).map_err(|e| io_err(&toml, e))?;
    let doc = tmp.path().join(doc_name);
    crate::fsutil::write_atomic(&doc, text.as_bytes()).map_err(|e| io_err(&doc, e))?;
    // An empty `out` (checked by the caller) is replaced; rename refuses a non-empty one.
    if out.exists() {
        std::fs::remove_dir(out).map_err(|e| io_err(out, e))?;
    }
    std::fs::rename(tmp.path(), out).map_err(|e| io_err(out, e))?;
    let _ = tmp.keep();
    Ok(())
}

/// An existing folder: every output checked first, then the meshes, then the
/// document; on a failure the meshes this call created are removed again. The folder's
/// project is found through folders held from `/` down ([`Project::for_folder`]) and
/// every check, write and removal goes through its held root, one folder at a time
/// without following a link: a `meshes` folder that is (or is swapped for) a link to
/// a folder outside is refused, never written through.
fn write_into(
    out: &Path,
    doc_name: &str,
    text: &str,
    meshes: &[(PathBuf, &crate::mesh::Mesh)],
    force: bool,
) -> Result<(), ImportError> {
    let rule = OutputRule::forced(force);
    let project = crate::project::Project::for_folder(out).map_err(|e| io_err(out, e))?;
    let base = std::path::absolute(out).map_err(|e| io_err(out, e))?;
    // An output's folder held open (walked from the root without following a link,
    // made when missing) and its name; the write rule checked through that handle.
    // (Not listed in the folder's output registry: an imported file is replaced by a
    // later import only with --force, as before.)
    let held = |rel: &Path| -> Result<(PathBuf, crate::fsutil::Dir), ImportError> {
        let at = out.join(rel);
        let full = project
            .resolve(&base.join(rel).to_string_lossy())
            .map_err(|e| io_err(&at, std::io::Error::other(e.to_string())))?;
        let (Some(parent), Some(name)) = (full.parent(), full.file_name()) else {
            return Err(io_err(&at, std::io::Error::other("not a file name")));
        };
        let dir = project.folder(parent, true).map_err(|e| io_err(&at, e))?;
        crate::project::check_output_in(&dir, name, &full, &rule)
            .map_err(|source| ImportError::Output { path: at, source })?;
        Ok((full, dir))
    };
    let doc = Path::new(doc_name);
    for rel in meshes.iter().map(|(rel, _)| rel.as_path()).chain([doc]) {
        held(rel)?;
    }
    let mut created: Vec<(crate::fsutil::Dir, std::ffi::OsString)> = Vec::new();
    let result = (|| {
        for (rel, mesh) in meshes {
            let (full, dir) = held(rel)?;
            let name = full.file_name().unwrap_or_default().to_os_string();
            // Whether something is there already (a mesh it replaces stays replaced).
            let existed = dir.stat(&name).is_ok_and(|k| k.is_some());
            dir.write_atomic(&name, &crate::mesh::stl_bytes(mesh))
                .map_err(|e| io_err(&full, e))?;
            if !existed {
                created.push((dir, name));
            }
        }
        let (full, dir) = held(doc)?;
        dir.write_atomic(full.file_name().unwrap_or_default(), text.as_bytes())
            .map_err(|e| io_err(&full, e))
    })();
    if result.is_err() {
        // Through the held folders too (never by name).
        for (dir, name) in &created {
            let _ = dir.remove(name);
        }
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_occurrence_ids_are_not_names() {
        for id in ["NAUO1", "nauo12", " NAUO7 "] {
            assert!(generated_occurrence_id(id), "{id}");
        }
        for name in ["NAUO", "NAUO1a", "bracket-1", "NAUÖ1", "", "ÄNAUO1"] {
            assert!(!generated_occurrence_id(name), "{name}");
        }
    }

    #[test]
    fn names_are_safe_and_unique() {
        assert_eq!(document_name("peg/1", "x"), "peg_1");
        assert_eq!(document_name("a\u{1b}[31mb", "x"), "a_[31mb");
        assert_eq!(document_name("  \u{200b} ", "fallback"), "_");
        assert_eq!(document_name("   ", "fallback"), "fallback");
        // NFD in, NFC out.
        assert_eq!(document_name("cafe\u{301}", "x"), "café");
        assert_eq!(document_name("角度", "x"), "角度");
        let mut taken = HashSet::new();
        assert_eq!(unique("peg".into(), &mut taken), "peg");
        assert_eq!(unique("peg".into(), &mut taken), "peg_2");
        assert_eq!(unique("peg".into(), &mut taken), "peg_3");
        let mut stems = HashSet::new();
        assert_eq!(file_stem("Plate", &mut stems), "Plate");
        assert_eq!(file_stem("plate", &mut stems), "plate_2");
        assert_eq!(file_stem("../etc", &mut stems), "_etc");
        assert_eq!(file_stem("角度 1", &mut stems), "角度_1");
    }
}
