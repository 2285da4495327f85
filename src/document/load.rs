//! Loading a document: YAML text checked and located, meshes read, references,
//! components, URDF robots and mates built, the mates solved.

use super::file::{ComponentFile, DocumentFile, FeatureFile, MateFile, PartFile};
use super::{
    mates, robot, scan, tessellations, AabbCache, Color, Component, Document, DocumentError,
    Feature, GeometryAt, Mate, MateEntity, MateKind, Part, Reference, StepGeometry, MAX_ABS_VALUE,
};
use super::{EntryError, UrdfRobotError};
use crate::collision::CutSpec;
use crate::diagnostics::{locate, suggestion, SourceError};
use crate::fsutil::{content_hash, FileKind};
use crate::math::{Transform, Vec3};
use crate::mesh::{Mesh, MeshCache};
use crate::project::Project;
use indexmap::IndexMap;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

impl Document {
    /// Loads a document and its meshes (through `cache`, so unchanged meshes are not
    /// re-read), validates it and solves its mates.
    ///
    /// The project (which bounds its mesh paths) is found by the path rule of
    /// [`Project::for_file`]: the nearest folder holding `fitup.toml`, else the
    /// document's folder.
    pub fn load(path: &Path, cache: &mut MeshCache) -> Result<Self, DocumentError> {
        let project = Project::for_file(path)
            .map_err(|e| SourceError::new(path, 0, 0, format!("cannot read the document: {e}")))?;
        Self::load_in(path, &project, cache)
    }

    /// Loads a document whose meshes must lie inside `project` (a mesh path leading
    /// outside it is refused at its `stl:` line, and the outside file is never opened).
    pub fn load_in(
        path: &Path,
        project: &Project,
        cache: &mut MeshCache,
    ) -> Result<Self, DocumentError> {
        // Through the project's held root: a folder swapped for a link meanwhile is
        // refused, never followed.
        let text = project
            .read_named_text(path, FileKind::Document)
            .map_err(|e| SourceError::new(path, 0, 0, format!("cannot read the document: {e}")))?;
        let mut doc = Self::from_yaml_in(&text, path, project, cache)?;
        doc.disk_hash = Some(content_hash(text.as_bytes()));
        Ok(doc)
    }

    /// Loads a document with a private mesh cache.
    ///
    /// # Examples
    /// Drive a mate's dimension (internal units: radians) and read the driven pose
    /// (world frame, mm):
    /// ```
    /// use fitup::document::Document;
    ///
    /// let mut doc = Document::open(std::path::Path::new("models/cell.yaml")).unwrap();
    /// doc.set_dimension("D1@角度1", 30f64.to_radians()).unwrap();
    /// let angle = doc.dimension("D1@角度1").unwrap();
    /// assert!((angle.document_value() - 30.0).abs() < 1e-9); // degrees in the file
    /// let plate = doc.component("plate_b").unwrap();
    /// assert!(plate.transform.translation().z > 700.0); // on the table, mm
    /// ```
    ///
    /// # Errors
    /// The file cannot be read, is not a valid document (located [`SourceError`]),
    /// or its mates cannot be solved.
    pub fn open(path: &Path) -> Result<Self, DocumentError> {
        Self::load(path, &mut MeshCache::new())
    }

    /// Builds a document from YAML text; `path` names the file in messages and anchors
    /// relative mesh paths (which must stay inside the folder [`Project::for_file`]
    /// finds for `path`, or `path`'s folder when `path` does not exist).
    pub fn from_yaml(
        text: &str,
        path: &Path,
        cache: &mut MeshCache,
    ) -> Result<Self, DocumentError> {
        let project = Project::for_file(path)
            .or_else(|e| crate::project::unless_missing(e, path.parent().unwrap_or(Path::new("."))))
            .map_err(|e| SourceError::new(path, 0, 0, format!("cannot resolve its folder: {e}")))?;
        Self::from_yaml_in(text, path, &project, cache)
    }

    /// Parses and checks document text without loading meshes: the checks of
    /// [`scan`] (aliases, duplicate keys, number ranges, empty files), then the schema.
    /// Errors are located in `path`.
    pub fn parse_text(
        text: &str,
        path: &Path,
    ) -> Result<(DocumentFile, scan::Positions), DocumentError> {
        let (file, positions): (DocumentFile, scan::Positions) =
            scan::from_yaml(text, path, "invalid document", scan::DOCUMENT_EMPTY)?;
        let file = if unicode_normalization::is_nfc(text) {
            file
        } else {
            super::names::nfc_file(file).map_err(|e| {
                SourceError::new(path, 0, 0, format!("invalid document after NFC: {e}"))
            })?
        };
        Ok((file, positions))
    }

    /// [`from_yaml`](Self::from_yaml) with meshes bounded by `project`.
    pub fn from_yaml_in(
        text: &str,
        path: &Path,
        project: &Project,
        cache: &mut MeshCache,
    ) -> Result<Self, DocumentError> {
        Self::from_yaml_nested(
            text,
            path,
            project,
            cache,
            &mut super::subdoc::Nesting::root(path),
        )
    }

    /// [`from_yaml_in`](Self::from_yaml_in) at a level of a tree of documents
    /// (`nesting`: the documents being loaded around it).
    pub(super) fn from_yaml_nested(
        text: &str,
        path: &Path,
        project: &Project,
        cache: &mut MeshCache,
        nesting: &mut super::subdoc::Nesting,
    ) -> Result<Self, DocumentError> {
        let (file, positions) = Self::parse_text(text, path)?;
        Self::from_file(file, text, path, project, &positions, cache, nesting)
    }

    /// Builds the document of a parsed file: its parts (meshes read), components, the
    /// parts of its URDF robots, its mates and robots, then solves the mates. Errors
    /// are located in `text` (the file's text) by `positions` (the scan's).
    fn from_file(
        file: DocumentFile,
        text: &str,
        path: &Path,
        project: &Project,
        positions: &scan::Positions,
        cache: &mut MeshCache,
        nesting: &mut super::subdoc::Nesting,
    ) -> Result<Self, DocumentError> {
        let load = Loader {
            text,
            path,
            project,
            positions,
            dir: std::path::absolute(path)
                .ok()
                .and_then(|p| p.parent().and_then(|d| d.canonicalize().ok()))
                .unwrap_or_else(|| project.root().to_path_buf()),
        };
        if file.units != "mm" {
            return Err(load.at(
                "units",
                "units",
                format!(
                    "units `{}` are not supported: fitup documents are in mm",
                    file.units
                ),
            ));
        }
        if let Some(d) = file.mesh_deflection {
            if !(d.is_finite() && d >= 0.0) {
                return Err(load.at(
                    "mesh_deflection",
                    "mesh_deflection",
                    format!("mesh_deflection {d} is not a finite number of mm ≥ 0"),
                ));
            }
        }
        let parts = load.parts(&file)?;
        let assemblies = super::assembly::load(&file, |key, m| load.at_key(&[key], m))?;
        let (components, by_name) = load.components(&file, &parts, &assemblies)?;
        let mut doc = Document {
            path: path.to_path_buf(),
            project: Some(project.clone()),
            saved_sub_documents: Vec::new(),
            generated: Default::default(),
            description: file.description.clone(),
            mesh_deflection: file.mesh_deflection,
            parts,
            components,
            numbering: super::numbering::Numbering::of(by_name.keys()),
            by_name,
            mates: Vec::new(),
            equations: Vec::new(),
            assemblies,
            robots: Vec::new(),
            revision: 0,
            aabb_cache: AabbCache::default(),
            disk_hash: None,
            warnings: Vec::new(),
            removed: Vec::new(),
        };
        doc.load_sub_documents(&file, path, &load.dir, project, positions, nesting, cache)?;
        doc.apply_assembly_suppression();
        // The top document reads the files of the parts its unsuppressed components
        // use, its sub-documents' too (a part only suppressed components use is not
        // read, as SolidWorks opens an assembly without its suppressed components).
        let mut step_warnings = Vec::new();
        if nesting.stack.len() == 1 {
            let needed: Vec<usize> = (0..doc.components.len())
                .filter(|&i| !doc.components[i].is_suppressed())
                .collect();
            let read = doc
                .read_parts_of(&needed, project, cache)
                .map_err(|(_, e)| DocumentError::from(e))?;
            step_warnings = doc.take_read_parts(read);
        }
        let backed = file_backed_set(&file);
        for (i, r) in file.robots.iter().enumerate() {
            if let Some(a) = file_backed(&backed, &r.name) {
                return Err(load.at_key(
                    &[&format!("robots/{i}/name")],
                    format!(
                        "robot `{}`: names inside `{a}/` are the sub-document's own robots; name it otherwise",
                        r.name
                    ),
                ));
            }
        }
        let urdf = load.urdf_robots(&file, &mut doc, cache)?;
        // the file's own mates first, then the sub-documents' (already in `doc`)
        let own = load.mates(&file, &doc)?;
        doc.mates.splice(0..0, own);
        let mate_dimensions = doc
            .mates
            .iter()
            .filter(|m| m.kind.has_dimension())
            .map(|m| m.name.clone())
            .collect();
        // the file's own robots first, then the sub-documents' (already in `doc`)
        let own = robot::load(
            &file.robots,
            &doc.by_name,
            &urdf.loaded,
            &mate_dimensions,
            &doc.robots,
            text,
            path,
        )?;
        doc.robots.splice(0..0, own);
        super::equation_mgr::load(&file.equations, &mut doc, positions, path)?;
        doc.solve_mates().map_err(|source| {
            let at = load.locate(&format!("name: {}", source.mate), "mates");
            DocumentError::Mates {
                at: SourceError::at(path, at, &source),
                source,
            }
        })?;
        doc.warnings = super::names::case_warnings(&file, path, positions);
        doc.warnings.extend(urdf.warnings);
        doc.warnings.extend(step_warnings);
        Ok(doc)
    }

    pub(super) fn mate_entity(&self, spec: &str) -> Result<MateEntity, EntryError> {
        let (comp, reference) = spec
            .rsplit_once('/')
            .ok_or_else(|| EntryError::EntitySyntax(spec.to_string()))?;
        let &component = self
            .by_name
            .get(comp)
            .ok_or_else(|| EntryError::NoComponent {
                name: comp.to_string(),
                hint: suggestion(comp, self.by_name.keys().map(String::as_str)),
            })?;
        let part = &self.parts[&self.components[component].part];
        let geometry = part.reference(reference).ok_or_else(|| {
            let names = part
                .references
                .keys()
                .map(String::as_str)
                .chain(Reference::BUILTIN_NAMES);
            EntryError::NoReference {
                part: part.name.clone(),
                reference: reference.to_string(),
                hint: suggestion(reference, names),
            }
        })?;
        Ok(MateEntity {
            component,
            reference: reference.to_string(),
            geometry,
        })
    }
}

/// What one load reads from: the file's text (to locate errors), its path, the
/// project that bounds its files and the scan's positions of its keys.
struct Loader<'a> {
    text: &'a str,
    path: &'a Path,
    project: &'a Project,
    positions: &'a scan::Positions,
    /// The document's folder (canonical), where relative file names start.
    dir: PathBuf,
}

/// The mesh parts of one load: file names resolved, each once.
#[derive(Default)]
struct PartMemo {
    resolved: HashMap<String, PathBuf>,
}

/// The URDF robots of a document, loaded: by robot name, with their warnings.
struct UrdfRobots {
    loaded: HashMap<String, robot::UrdfLoaded>,
    warnings: Vec<String>,
}

impl Loader<'_> {
    /// Line and column of the first `needle` at or after the line of `section:`
    /// (0, 0 when not found).
    fn locate(&self, needle: &str, section: &str) -> (usize, usize) {
        self.after(&format!("{section}:"), needle)
    }

    /// Line and column of the first `needle` at or after the first line holding
    /// `anchor` (the whole text when there is none; 0, 0 when not found).
    fn after(&self, anchor: &str, needle: &str) -> (usize, usize) {
        let from = locate(self.text, anchor, 1).map(|l| l.0).unwrap_or(1);
        locate(self.text, needle, from).unwrap_or((0, 0))
    }

    /// An error at the first `needle` at or after the line of `section:`.
    fn at(&self, needle: &str, section: &str, message: String) -> DocumentError {
        let (line, col) = self.locate(needle, section);
        SourceError::new(self.path, line, col, message).into()
    }

    /// An error at the first of `keys` the scan placed (unplaced: no line).
    fn at_key(&self, keys: &[&str], message: String) -> DocumentError {
        let (line, col) = keys
            .iter()
            .find_map(|k| self.positions.get(k))
            .unwrap_or((0, 0));
        SourceError::new(self.path, line, col, message).into()
    }

    /// Every part, its entry checked and its file name resolved, not read yet
    /// ([`Part::is_loaded`] false).
    fn parts(&self, file: &DocumentFile) -> Result<IndexMap<String, Part>, DocumentError> {
        // every part's mesh read and parsed at once, in parallel (the cost of opening
        // a cell of many distinct parts); errors are reported by the loop below. Each
        // distinct file name is resolved once and each mesh taken once per load: a
        // document of 400,000 parts naming one mesh resolved and stat-ed it 400,000
        // times over.
        // Each distinct file name is resolved once per load: a document of 400,000
        // parts naming one mesh resolved and stat-ed it 400,000 times over. The files
        // are read later, only for the parts an unsuppressed component uses
        // ([`Document::read_parts_of`]).
        let mut memo = PartMemo::default();
        let mut parts = IndexMap::new();
        let backed = file_backed_set(file);
        for (name, pf) in &file.parts {
            if let Some(a) = file_backed(&backed, name) {
                return Err(self.at_key(
                    &[&format!("parts/{name}")],
                    format!("part `{name}`: names inside `{a}/` are the sub-document's own parts; name it otherwise"),
                ));
            }
            parts.insert(name.clone(), self.part(name, pf, &mut memo)?);
        }
        Ok(parts)
    }

    /// One part: its geometry file (resolved, not read), references and features.
    fn part(&self, name: &str, pf: &PartFile, memo: &mut PartMemo) -> Result<Part, DocumentError> {
        let key = if pf.step.is_some() { "step" } else { "stl" };
        // The `stl:` (or `step:`) value's own line, from the scan.
        let (line, column) = [format!("parts/{name}/{key}"), format!("parts/{name}")]
            .iter()
            .find_map(|k| self.positions.get(k))
            .unwrap_or((0, 0));
        let stl_at = |message: String| -> DocumentError {
            SourceError::new(self.path, line, column, message).into()
        };
        let source = match (&pf.step, pf.stl.is_empty()) {
            (Some(step), true) => step,
            (None, false) => &pf.stl,
            (Some(_), false) => {
                return Err(stl_at(format!(
                    "part `{name}`: give either `stl:` (a mesh file) or `step:` (a STEP file), not both"
                )))
            }
            (None, true) => {
                return Err(stl_at(format!(
                    "part `{name}` has no geometry: give `stl:` (a mesh file) or `step:` (a STEP file)"
                )))
            }
        };
        if pf.step.is_none() && (pf.deflection.is_some() || pf.angle.is_some()) {
            return Err(stl_at(format!(
                "part `{name}`: `deflection:` and `angle:` tessellate a `step:` part; an `stl:` mesh is used as it is"
            )));
        }
        if pf.step.is_some() {
            check_step_settings(pf).map_err(|m| stl_at(format!("part `{name}`: {m}")))?;
        }
        let resolved = match memo.resolved.get(source) {
            Some(p) if pf.step.is_none() => Ok(p.clone()),
            _ => self.project.resolve_from(&self.dir, source),
        };
        let mesh_path = resolved.map_err(|e| {
            let what = if pf.step.is_some() {
                "STEP file"
            } else {
                "mesh"
            };
            stl_at(format!("part `{name}`: {what} {e}"))
        })?;
        if pf.step.is_none() {
            memo.resolved.insert(source.clone(), mesh_path.clone());
        }
        let step = pf.step.as_ref().map(|_| StepGeometry {
            deflection: pf.deflection,
            angle: pf.angle,
            volume_ratio: f64::NAN,
            from_store: false,
        });
        let references = self.references(name, pf)?;
        let features = self.features(name, pf)?;
        for (rname, r) in &references {
            let finite = r
                .anchor()
                .coords
                .iter()
                .chain(r.direction().unwrap_or_default().iter())
                .all(|v| v.is_finite());
            if !finite {
                return Err(self.at(
                    rname,
                    "parts",
                    format!("reference `{rname}` of part `{name}` is not finite"),
                ));
            }
        }
        let properties = properties(&pf.properties).map_err(|m| {
            self.at_key(
                &[
                    &format!("parts/{name}/properties"),
                    &format!("parts/{name}"),
                ],
                format!("part `{name}`: {m}"),
            )
        })?;
        Ok(Part {
            name: name.to_string(),
            stl: source.clone(),
            mesh_path,
            mesh_files: Vec::new(),
            step,
            mesh: super::unloaded_mesh(),
            references,
            features,
            properties,
            loaded: false,
            at: Some(GeometryAt {
                file: self.path.to_path_buf(),
                line,
                column,
            }),
        })
    }

    /// A part's named planes, axes and points (part frame, mm), in that order.
    fn references(
        &self,
        name: &str,
        pf: &PartFile,
    ) -> Result<IndexMap<String, Reference>, DocumentError> {
        let mut references = IndexMap::new();
        for (rname, p) in &pf.planes {
            let normal = vec3(p.normal).try_normalize(1e-12).ok_or_else(|| {
                self.at(
                    rname,
                    "parts",
                    format!("plane `{rname}` of part `{name}` has a zero normal"),
                )
            })?;
            references.insert(
                rname.clone(),
                Reference::Plane {
                    point: vec3(p.point).into(),
                    normal,
                },
            );
        }
        for (rname, a) in &pf.axes {
            let direction = vec3(a.direction).try_normalize(1e-12).ok_or_else(|| {
                self.at(
                    rname,
                    "parts",
                    format!("axis `{rname}` of part `{name}` has a zero direction"),
                )
            })?;
            references.insert(
                rname.clone(),
                Reference::Axis {
                    point: vec3(a.point).into(),
                    direction,
                },
            );
        }
        for (rname, p) in &pf.points {
            references.insert(rname.clone(), Reference::Point(vec3(*p).into()));
        }
        for (rname, cs) in &pf.coordinate_systems {
            let f =
                super::coordinate_system(vec3(cs.origin), vec3(cs.x), vec3(cs.y)).map_err(|e| {
                    self.at(
                        rname,
                        "parts",
                        format!("coordinate system `{rname}` of part `{name}`: {e}"),
                    )
                })?;
            references.insert(rname.clone(), Reference::CoordinateSystem(f));
        }
        Ok(references)
    }

    /// A part's feature tree, names unique.
    fn features(&self, name: &str, pf: &PartFile) -> Result<Vec<Feature>, DocumentError> {
        let mut features: Vec<Feature> = Vec::new();
        for f in &pf.features {
            let feature = Feature::from_file(f).map_err(|m| {
                self.at(
                    &format!("name: {}", f.name()),
                    "parts",
                    format!("part `{name}`: {m}"),
                )
            })?;
            if features.iter().any(|g| g.name() == feature.name()) {
                return Err(self.at(
                    &format!("name: {}", feature.name()),
                    "parts",
                    format!("part `{name}`: duplicate feature name `{}`", feature.name()),
                ));
            }
            features.push(feature);
        }
        Ok(features)
    }

    /// The components, names unique, and their indices by name.
    fn components(
        &self,
        file: &DocumentFile,
        parts: &IndexMap<String, Part>,
        assemblies: &[super::SubAssembly],
    ) -> Result<(Vec<Component>, HashMap<String, usize>), DocumentError> {
        let mut components = Vec::with_capacity(file.components.len());
        let mut by_name = HashMap::new();
        let frames = super::assembly::frames(assemblies);
        let backed = file_backed_set(file);
        for (ci, c) in file.components.iter().enumerate() {
            // The name's own line from the scan (the text may spell it in NFD).
            let name_at =
                |message: String| self.at_key(&[&format!("components/{ci}/name")], message);
            if c.name.is_empty() {
                return Err(name_at("a component name must be non-empty".into()));
            }
            super::assembly::check_levels(&c.name)
                .map_err(|e| name_at(format!("component {e}")))?;
            if let Some(a) = file_backed(&backed, &c.name) {
                return Err(name_at(format!(
                    "component `{}`: `{a}` is the document `{}`; its components are written in that file",
                    c.name,
                    file.assemblies.iter().find(|b| b.name == a).and_then(|b| b.file.as_deref()).unwrap_or_default()
                )));
            }
            let Some(frame) = super::assembly::parent_frame(&frames, &c.name) else {
                return Err(name_at(format!(
                    "component `{}`: its parent `{}` is no sub-assembly of `assemblies:`",
                    c.name,
                    super::assembly::parent_name(&c.name).unwrap_or_default()
                )));
            };
            if let Some(first) = by_name.insert(c.name.clone(), components.len()) {
                let first_line = self
                    .positions
                    .get(&format!("components/{first}/name"))
                    .map_or(String::new(), |(l, _)| format!(" (first at line {l})"));
                return Err(name_at(format!(
                    "duplicate component name `{}`{first_line}; names are compared in Unicode NFC, so two spellings of one name are the same",
                    c.name
                )));
            }
            let mut component = self.component(c, parts)?;
            component.transform = component.transform * frame;
            components.push(component);
        }
        Ok((components, by_name))
    }

    /// One component: its part, pose, colour and mass checked.
    fn component(
        &self,
        c: &ComponentFile,
        parts: &IndexMap<String, Part>,
    ) -> Result<Component, DocumentError> {
        let needle = format!("name: {}", c.name);
        if !parts.contains_key(&c.part) {
            return Err(self
                .at(
                    &format!("part: {}", c.part),
                    &needle,
                    format!("component `{}` uses unknown part `{}`", c.name, c.part),
                )
                .with_help(suggestion(&c.part, parts.keys().map(String::as_str))));
        }
        // A key of this component's entry, located after its name.
        let key_at = |key: &str, message: String| -> DocumentError {
            let (line, col) = self.after(&needle, key);
            SourceError::new(self.path, line, col, message).into()
        };
        let transform = match &c.transform {
            None => Transform::IDENTITY,
            Some(m) if m.iter().flatten().any(|v| !v.is_finite() || v.abs() > MAX_ABS_VALUE) => {
                return Err(self.at(
                    "transform",
                    &needle,
                    format!("component `{}`: pose entries must be finite and at most {MAX_ABS_VALUE:e} in magnitude", c.name),
                ))
            }
            Some(m) => Transform::from_matrix(m)
                .map_err(|e| key_at("transform", format!("component `{}`: {e}", c.name)))?,
        };
        let color = match &c.color {
            None => None,
            Some(v) => Some(parse_color(v).ok_or_else(|| {
                self.at(
                    &needle,
                    "components",
                    format!(
                        "component `{}`: colour must be [r, g, b] in 0..1 or \"#rrggbb\"",
                        c.name
                    ),
                )
            })?),
        };
        if let Some(m) = c.mass {
            if !(m.is_finite() && m > 0.0 && m <= MAX_ABS_VALUE) {
                return Err(key_at(
                    "mass",
                    format!(
                        "component `{}`: mass must be a finite number of kg > 0, not {m}",
                        c.name
                    ),
                ));
            }
        }
        let properties = properties(&c.properties)
            .map_err(|m| key_at("properties", format!("component `{}`: {m}", c.name)))?;
        Ok(Component {
            name: c.name.clone(),
            part: c.part.clone(),
            fixed: c.fixed,
            color,
            transform,
            mass: c.mass,
            threaded: c.threaded,
            fixture: c.fixture,
            suppressed: c.suppressed,
            hidden: c.hidden,
            properties,
            held_suppressed: false,
        })
    }

    /// The `urdf:` robots: read, their links' meshes added to `doc` as generated
    /// parts and components.
    fn urdf_robots(
        &self,
        file: &DocumentFile,
        doc: &mut Document,
        cache: &mut MeshCache,
    ) -> Result<UrdfRobots, DocumentError> {
        let mut out = UrdfRobots {
            loaded: HashMap::new(),
            warnings: Vec::new(),
        };
        // One count for every URDF robot of the document (MAX_URDF_TRIANGLES).
        let mut left = robot::MAX_URDF_TRIANGLES;
        for rf in &file.robots {
            let Some(u) = &rf.urdf else { continue };
            let robot_at = |e: UrdfRobotError| -> DocumentError {
                let (line, col) = self.after(&format!("name: {}", rf.name), "urdf:");
                SourceError::new(self.path, line, col, format!("robot `{}`: {e}", rf.name)).into()
            };
            let loaded = robot::read_urdf_robot(
                self.project,
                &self.dir,
                u,
                &rf.package_path,
                rf.tip.as_deref(),
                cache,
                &mut left,
            )
            .map_err(robot_at)?;
            out.warnings.extend(loaded.warnings.iter().cloned());
            doc.add_urdf_parts(&rf.name, u, &loaded).map_err(robot_at)?;
            out.loaded.insert(rf.name.clone(), loaded);
        }
        Ok(out)
    }

    /// The mates, names unique, their entities found in `doc`'s components.
    fn mates(&self, file: &DocumentFile, doc: &Document) -> Result<Vec<Mate>, DocumentError> {
        let mut mates = Vec::with_capacity(file.mates.len());
        let mut names = std::collections::HashSet::new();
        let backed = file_backed_set(file);
        for (mi, m) in file.mates.iter().enumerate() {
            if !names.insert(m.name.clone()) {
                return Err(self.at_key(
                    &[&format!("mates/{mi}/name")],
                    format!(
                        "duplicate mate name `{}` (names are compared in Unicode NFC)",
                        m.name
                    ),
                ));
            }
            if let Some(a) = file_backed(&backed, &m.name) {
                return Err(self.at_key(
                    &[&format!("mates/{mi}/name")],
                    format!(
                        "mate `{}`: names inside `{a}/` are the sub-document's own mates; name it otherwise",
                        m.name
                    ),
                ));
            }
            mates.push(self.mate(m, doc)?);
        }
        Ok(mates)
    }

    /// One mate: its kind, entities, `about` axis and value (radians or mm) checked.
    fn mate(&self, m: &MateFile, doc: &Document) -> Result<Mate, DocumentError> {
        let needle = format!("name: {}", m.name);
        let err = |msg: String| self.at(&needle, "mates", msg);
        let entity = |spec: &str| {
            doc.mate_entity(spec)
                .map_err(|e| err(format!("mate `{}`: {e}", m.name)))
        };
        let kind = MateKind::parse(&m.kind).ok_or_else(|| {
            err(format!(
                "mate `{}`: unknown type `{}` (coincident, concentric, parallel, perpendicular, distance, angle)",
                m.name, m.kind
            ))
        })?;
        let ea = entity(&m.entities[0])?;
        let eb = entity(&m.entities[1])?;
        mates::check_entities(kind, &ea.geometry, &eb.geometry, m.aligned)
            .map_err(|e| err(format!("mate `{}`: {e}", m.name)))?;
        let about = match &m.about {
            None => None,
            Some(s) => {
                let e = entity(s)?;
                if !matches!(e.geometry, Reference::Axis { .. }) {
                    return Err(err(format!("mate `{}`: `about` must name an axis", m.name)));
                }
                Some(e)
            }
        };
        let value = match (kind, m.value) {
            (MateKind::Angle, Some(v)) => Some(v.to_radians()),
            (MateKind::Distance, Some(v)) => Some(v),
            (k, None) if k.has_dimension() => {
                return Err(err(format!(
                    "{} mate `{}` needs a `value`",
                    k.name(),
                    m.name
                )))
            }
            (_, None) => None,
            (k, Some(_)) => return Err(err(format!("a {} mate takes no `value`", k.name()))),
        };
        if value.is_some_and(|v| !v.is_finite()) {
            return Err(err(format!("mate `{}`: value is not finite", m.name)));
        }
        Ok(Mate {
            name: m.name.clone(),
            kind,
            entities: [ea, eb],
            value,
            aligned: m.aligned,
            about,
            suppressed: m.suppressed,
        })
    }
}

impl Feature {
    fn from_file(f: &FeatureFile) -> Result<Feature, EntryError> {
        match f {
            FeatureFile::CutCells {
                name,
                cell_size,
                planes,
            } => {
                let spec = match (cell_size, planes) {
                    (Some(s), None) if s.is_finite() && *s > 0.0 => CutSpec::Size(*s),
                    (Some(s), None) => {
                        return Err(EntryError::CellSize {
                            name: name.clone(),
                            value: *s,
                        })
                    }
                    (None, Some(p)) => {
                        if p.x.iter().chain(&p.y).chain(&p.z).any(|v| !v.is_finite()) {
                            return Err(EntryError::CutPlanes(name.clone()));
                        }
                        CutSpec::Planes {
                            x: p.x.clone(),
                            y: p.y.clone(),
                            z: p.z.clone(),
                        }
                    }
                    _ => return Err(EntryError::CutSpec(name.clone())),
                };
                Ok(Feature::CutCells {
                    name: name.clone(),
                    spec,
                })
            }
        }
    }
}

/// Custom properties as the document keeps them: every value a text (a number
/// becomes its decimal text, `42.50` → `42.5`; true/false their words).
pub(super) fn properties(
    file: &IndexMap<String, serde_yaml::Value>,
) -> Result<IndexMap<String, String>, EntryError> {
    let mut out = IndexMap::with_capacity(file.len());
    for (k, v) in file {
        if k.trim().is_empty() {
            return Err(EntryError::PropertyName);
        }
        let text = match v {
            serde_yaml::Value::String(s) => s.clone(),
            serde_yaml::Value::Number(n) => n.to_string(),
            serde_yaml::Value::Bool(b) => b.to_string(),
            serde_yaml::Value::Null => String::new(),
            _ => return Err(EntryError::PropertyValue(k.clone())),
        };
        out.insert(k.clone(), text);
    }
    Ok(out)
}

/// The sub-assemblies of `file` whose content is another document, by name.
fn file_backed_set(file: &DocumentFile) -> std::collections::HashSet<&str> {
    file.assemblies
        .iter()
        .filter(|a| a.file.is_some())
        .map(|a| a.name.as_str())
        .collect()
}

/// The sub-assembly among `backed` holding `name` (a level above it), if any.
fn file_backed<'a>(backed: &std::collections::HashSet<&'a str>, name: &str) -> Option<&'a str> {
    if backed.is_empty() {
        return None;
    }
    name.match_indices('/')
        .find_map(|(i, _)| backed.get(&name[..i]).copied())
}

fn vec3(v: [f64; 3]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

fn parse_color(v: &serde_yaml::Value) -> Option<Color> {
    match v {
        serde_yaml::Value::String(s) => {
            let h = s.strip_prefix('#')?;
            if h.len() != 6 {
                return None;
            }
            let c = |i: usize| {
                u8::from_str_radix(&h[i..i + 2], 16)
                    .ok()
                    .map(|x| x as f64 / 255.0)
            };
            Some([c(0)?, c(2)?, c(4)?])
        }
        serde_yaml::Value::Sequence(s) if s.len() == 3 => {
            let mut out = [0.0; 3];
            for (o, x) in out.iter_mut().zip(s) {
                *o = x.as_f64()?;
                if !(0.0..=1.0).contains(o) {
                    return None;
                }
            }
            Some(out)
        }
        _ => None,
    }
}

/// A `step:` part's mesh through the mesh cache and the project's tessellation store
/// `store`, with the part's `deflection:` (mm) and `angle:` (degrees); the message of
/// an error names the file (and, without the `step` feature, the rebuild command).
fn step_part(
    pf: &PartFile,
    file: &Path,
    project: &Project,
    store: &Path,
    cache: &mut MeshCache,
) -> Result<(Arc<Mesh>, StepGeometry), EntryError> {
    check_step_settings(pf)?;
    Ok(step_mesh(pf, file, project, store, cache)?)
}

/// A `step:` part's `deflection:` (mm) and `angle:` (degrees) checked.
fn check_step_settings(pf: &PartFile) -> Result<(), EntryError> {
    for (key, v) in [("deflection", pf.deflection), ("angle", pf.angle)] {
        if v.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
            return Err(EntryError::StepSetting(key));
        }
    }
    if pf.angle.is_some_and(|a| a >= 180.0) {
        return Err(EntryError::StepAngle);
    }
    Ok(())
}

/// [`step_part`] once its `deflection:` and `angle:` are checked: the mesh of STEP
/// file `file` and what was measured of it (also a part a script adds from a STEP
/// file, with the default tessellation).
pub(super) fn step_mesh(
    pf: &PartFile,
    file: &Path,
    project: &Project,
    store: &Path,
    cache: &mut MeshCache,
) -> Result<(Arc<Mesh>, StepGeometry), crate::mesh::step::StepError> {
    use crate::mesh::step::StepOptions;
    let (linear_deflection, angular_deflection) = tessellations::of_part(pf);
    let options = StepOptions {
        linear_deflection,
        angular_deflection,
        ..StepOptions::default()
    };
    let got = cache.get_step(file, Some(project), &options, Some(store))?;
    let geometry = StepGeometry {
        deflection: pf.deflection,
        angle: pf.angle,
        volume_ratio: got.mesh.signed_volume() / got.exact_volume,
        from_store: got.from_store,
    };
    Ok((got.mesh, geometry))
}

/// A part's geometry as read: its name, mesh, the files the mesh was read from and,
/// for a `step:` part, how it was tessellated.
type ReadPart = (String, Arc<Mesh>, Vec<PathBuf>, Option<StepGeometry>);

/// The geometry files read for parts that were not loaded, by part name, and the
/// warnings of reading them.
pub(super) struct ReadParts {
    parts: Vec<ReadPart>,
    warnings: Vec<String>,
}

impl Document {
    /// Reads the geometry files of the parts of `components` (indices) that are not
    /// loaded, each once, without changing the document (see
    /// [`take_read_parts`](Self::take_read_parts)). An error names the first
    /// component whose part cannot be read, located where the document names the
    /// file (as opening the document reports it).
    pub(super) fn read_parts_of(
        &self,
        components: &[usize],
        project: &Project,
        cache: &mut MeshCache,
    ) -> Result<ReadParts, (usize, SourceError)> {
        let mut seen = std::collections::HashSet::new();
        let needed: Vec<(usize, &Part)> = components
            .iter()
            .map(|&i| (i, &self.parts[&self.components[i].part]))
            .filter(|(_, p)| !p.loaded && seen.insert(p.name.as_str()))
            .collect();
        let mut out = ReadParts {
            parts: Vec::with_capacity(needed.len()),
            warnings: Vec::new(),
        };
        if needed.is_empty() {
            return Ok(out);
        }
        // every mesh read and parsed at once, in parallel (the cost of opening a cell
        // of many distinct parts); errors are reported by the loop below
        let mut distinct: Vec<&Path> = needed
            .iter()
            .filter(|(_, p)| p.step.is_none())
            .map(|(_, p)| p.mesh_path.as_path())
            .collect();
        distinct.sort();
        distinct.dedup();
        cache.prefetch_in(project, &distinct);
        let store = project.root().join(crate::mesh::step::STEP_STORE);
        let mut meshes: HashMap<&Path, (Arc<Mesh>, Vec<PathBuf>)> = HashMap::new();
        for (i, p) in needed {
            let (file, line, column) = match &p.at {
                Some(a) => (a.file.as_path(), a.line, a.column),
                None => (self.path.as_path(), 0, 0),
            };
            let name = &p.name;
            let at = |m: String| {
                (
                    i,
                    SourceError::new(file, line, column, format!("part `{name}`: {m}")),
                )
            };
            let read = if let Some(g) = &p.step {
                let pf = PartFile {
                    step: Some(p.stl.clone()),
                    deflection: g.deflection,
                    angle: g.angle,
                    ..PartFile::from_stl(String::new())
                };
                let (mesh, geometry) = step_part(&pf, &p.mesh_path, project, &store, cache)
                    .map_err(|e| at(e.to_string()))?;
                if (geometry.volume_ratio - 1.0).abs() > 0.015 {
                    out.warnings.push(format!(
                        "{}:{line}:{column}: part `{name}`: its mesh is {:.4} of the exact volume (more than 1.5 % off): set a smaller `deflection:`",
                        file.display(),
                        geometry.volume_ratio
                    ));
                }
                (mesh, Vec::new(), Some(geometry))
            } else if let Some((mesh, files)) = meshes.get(p.mesh_path.as_path()) {
                (mesh.clone(), files.clone(), None)
            } else {
                let mesh = cache
                    .get_in(project, &p.mesh_path)
                    .map_err(|e| at(e.to_string()))?;
                let files = cache.files_of(&p.mesh_path);
                meshes.insert(&p.mesh_path, (mesh.clone(), files.clone()));
                (mesh, files, None)
            };
            out.parts.push((name.clone(), read.0, read.1, read.2));
        }
        Ok(out)
    }

    /// Gives the parts what [`read_parts_of`](Self::read_parts_of) read (they are
    /// loaded from now on); returns its warnings.
    pub(super) fn take_read_parts(&mut self, read: ReadParts) -> Vec<String> {
        for (name, mesh, files, step) in read.parts {
            let p = &mut self.parts[&name];
            p.mesh = mesh;
            p.mesh_files = files;
            p.step = step;
            p.loaded = true;
        }
        if let Ok(mut cache) = self.aabb_cache.0.lock() {
            cache.clear();
        }
        read.warnings
    }

    /// Reads the parts of `components` that are not loaded (components about to be
    /// unsuppressed, added or re-pointed): all or nothing, through the document's
    /// project. Their warnings join [`warnings`](Self::warnings).
    ///
    /// # Errors
    /// [`DocumentError::PartUnreadable`] naming the component, the part and, located
    /// in the document, why its file cannot be read; the document is unchanged.
    pub(super) fn load_parts_of(&mut self, components: &[usize]) -> Result<(), DocumentError> {
        if components
            .iter()
            .all(|&i| self.parts[&self.components[i].part].loaded)
        {
            return Ok(());
        }
        let project = match &self.project {
            Some(p) => p.clone(),
            None => Project::for_file(&self.path).map_err(|e| {
                SourceError::new(&self.path, 0, 0, format!("cannot resolve its folder: {e}"))
            })?,
        };
        let read = self
            .read_parts_of(components, &project, &mut MeshCache::new())
            .map_err(|(i, at)| DocumentError::PartUnreadable {
                component: self.components[i].name.clone().into(),
                part: self.components[i].part.clone().into(),
                at: Box::new(at),
            })?;
        let warnings = self.take_read_parts(read);
        self.warnings.extend(warnings);
        self.revision += 1;
        Ok(())
    }
}
