//! Editing a document from a script or the library, as SolidWorks macros do: mates as
//! objects (add, delete, suppress, flip), suppression and visibility of components,
//! custom properties of parts and components, and adding, renaming and re-pointing
//! components. Every change that can move a component re-solves the mates; a change
//! the mates cannot satisfy is undone and refused.

use super::file::PartFile;
use super::mates::{self, Mate, MateKind};
use super::{
    nfc_name, Component, Document, DocumentError, LinkEdit, MateProblem, Part, PartMeshError,
    Reference, ReferenceProblem,
};
use crate::math::Transform;
use crate::mesh::MeshCache;
use crate::project::Project;
use indexmap::IndexMap;
use std::path::Path;

/// A new mate, as a document file writes one (`component/reference` entities, the
/// value in mm or radians).
#[derive(Debug, Clone, PartialEq)]
pub struct MateSpec {
    /// Unique mate name (a distance or angle mate's dimension is `D1@<name>`).
    pub name: String,
    /// What it constrains.
    pub kind: MateKind,
    /// The two entities, `component/reference`.
    pub entities: [String; 2],
    /// Driving value of a distance (mm) or angle (radians) mate.
    pub value: Option<f64>,
    /// Directions aligned (true) or opposed (false); `None`: the kind's default.
    pub aligned: Option<bool>,
    /// Angle mates: the axis (`component/axis`) the angle is measured about.
    pub about: Option<String>,
}

/// Whose custom properties: a part's (file properties) or a component's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PropertyOwner<'a> {
    /// A part, by name.
    Part(&'a str),
    /// A component, by name.
    Component(&'a str),
}

impl Document {
    /// Whether a mate is solved: neither it nor a component it names is suppressed.
    pub fn mate_active(&self, m: &Mate) -> bool {
        !m.suppressed
            && m.entities
                .iter()
                .chain(m.about.iter())
                .all(|e| !self.components[e.component].is_suppressed())
    }

    /// The index of a mate by name, or an error listing close matches.
    pub fn mate_index(&self, name: &str) -> Result<usize, DocumentError> {
        let name = &*nfc_name(name);
        self.mates
            .iter()
            .position(|m| m.name == name)
            .ok_or_else(|| {
                DocumentError::not_found("mate", name, self.mates.iter().map(|m| m.name.as_str()))
            })
    }

    /// A mate by name.
    pub fn mate(&self, name: &str) -> Result<&Mate, DocumentError> {
        Ok(&self.mates[self.mate_index(name)?])
    }

    /// Whether mate `name`'s directions are aligned, see [`Mate::alignment`].
    pub fn mate_alignment(&self, name: &str) -> Result<Option<bool>, DocumentError> {
        let poses: Vec<Transform> = self.components.iter().map(|c| c.transform).collect();
        Ok(self.mate(name)?.alignment(&poses))
    }

    /// Runs `change`, then re-solves the mates; when they cannot be satisfied, the
    /// mates, poses, flags and parts of the components are put back and the
    /// solver's error returned.
    fn change_and_rebuild(
        &mut self,
        change: impl FnOnce(&mut Self) -> Result<(), DocumentError>,
    ) -> Result<(), DocumentError> {
        let mates = self.mates.clone();
        let flags: Vec<(bool, bool)> = self
            .components
            .iter()
            .map(|c| (c.suppressed, c.hidden))
            .collect();
        let poses: Vec<Transform> = self.components.iter().map(|c| c.transform).collect();
        let parts: Vec<String> = self.components.iter().map(|c| c.part.clone()).collect();
        change(self)?;
        if let Err(e) = self.rebuild() {
            self.mates = mates;
            for (((c, t), (s, h)), p) in self.components.iter_mut().zip(poses).zip(flags).zip(parts)
            {
                c.transform = t;
                c.suppressed = s;
                c.hidden = h;
                c.part = p;
            }
            return Err(e);
        }
        Ok(())
    }

    /// Deletes a mate (SolidWorks' `DeleteSelection` on a mate); nothing moves.
    /// Returns the deleted mate. Refused while an equation uses or sets its
    /// dimension (fitup keeps no broken equation).
    pub fn delete_mate(&mut self, name: &str) -> Result<Mate, DocumentError> {
        let i = self.mate_index(name)?;
        if self.mates[i].kind.has_dimension() {
            let dimension = super::dimension::full_name(&self.mates[i].name);
            if let Some(&e) = self.equations_using(&dimension).first() {
                return Err(DocumentError::DimensionInUse(Box::new(
                    super::DimensionInUse {
                        component: None,
                        mate: name.to_string(),
                        dimension,
                        index: e,
                        equation: super::equations::shown(&self.equations()[e].text()),
                    },
                )));
            }
        }
        self.revision += 1;
        Ok(self.mates.remove(i))
    }

    /// Suppresses or unsuppresses a mate, then re-solves.
    pub fn set_mate_suppressed(
        &mut self,
        name: &str,
        suppressed: bool,
    ) -> Result<(), DocumentError> {
        let i = self.mate_index(name)?;
        self.change_and_rebuild(|d| {
            d.mates[i].suppressed = suppressed;
            Ok(())
        })
    }

    /// Sets a mate's alignment (`Some(true)`: aligned, `Some(false)`: anti-aligned,
    /// `None`: the kind's default), then re-solves (SolidWorks' `MateAlign` and
    /// `EditRebuild3`). Refused for a mate of points.
    pub fn set_mate_aligned(
        &mut self,
        name: &str,
        aligned: Option<bool>,
    ) -> Result<(), DocumentError> {
        let i = self.mate_index(name)?;
        if aligned.is_some() && self.mate_alignment(name)?.is_none() {
            return Err(DocumentError::NoAlignment {
                mate: self.mates[i].name.clone().into(),
                change: "set",
            });
        }
        self.change_and_rebuild(|d| {
            d.mates[i].aligned = aligned;
            Ok(())
        })
    }

    /// Flips a mate between aligned and anti-aligned (SolidWorks' flip mate
    /// alignment), then re-solves.
    pub fn flip_mate(&mut self, name: &str) -> Result<(), DocumentError> {
        let now = self
            .mate_alignment(name)?
            .ok_or_else(|| DocumentError::NoAlignment {
                mate: name.into(),
                change: "flip",
            })?;
        self.set_mate_aligned(name, Some(!now))
    }

    /// Adds a mate (SolidWorks' `AddMate5`) and solves it; refused, with nothing
    /// changed, when the name is taken, an entity is unknown or of the wrong kind, or
    /// the mates cannot be satisfied.
    pub fn add_mate(&mut self, spec: &MateSpec) -> Result<(), DocumentError> {
        let name = super::new_name(&spec.name, "mate name")?;
        if self.mates.iter().any(|m| m.name == name) {
            return Err(DocumentError::NameTaken { what: "mate", name });
        }
        let entry = |e: super::EntryError| DocumentError::MateEntity {
            mate: name.clone().into(),
            source: Box::new(e),
        };
        let bad = |problem| DocumentError::BadMate {
            mate: name.clone().into(),
            problem,
        };
        let ea = self
            .mate_entity(&nfc_name(&spec.entities[0]))
            .map_err(entry)?;
        let eb = self
            .mate_entity(&nfc_name(&spec.entities[1]))
            .map_err(entry)?;
        mates::check_entities(spec.kind, &ea.geometry, &eb.geometry, spec.aligned)
            .map_err(entry)?;
        let about = match &spec.about {
            None => None,
            Some(s) => {
                let e = self.mate_entity(&nfc_name(s)).map_err(entry)?;
                if !matches!(e.geometry, Reference::Axis { .. }) {
                    return Err(bad(MateProblem::AboutNotAnAxis));
                }
                Some(e)
            }
        };
        match (spec.kind.has_dimension(), spec.value) {
            (true, None) => return Err(bad(MateProblem::NeedsValue(spec.kind))),
            (false, Some(_)) => return Err(bad(MateProblem::TakesNoValue(spec.kind))),
            (_, Some(v)) if !v.is_finite() || v.abs() > super::MAX_ABS_VALUE => {
                return Err(bad(MateProblem::ValueOutOfRange(v)))
            }
            (_, Some(v)) if spec.kind == MateKind::Distance && v < 0.0 => {
                return Err(bad(MateProblem::NegativeDistance(v)))
            }
            _ => {}
        }
        if spec.kind.has_dimension() && self.robot_dimension(&name).is_some() {
            return Err(bad(MateProblem::RobotDimension));
        }
        let mate = Mate {
            name,
            kind: spec.kind,
            entities: [ea, eb],
            value: spec.value,
            aligned: spec.aligned,
            about,
            suppressed: false,
        };
        self.change_and_rebuild(|d| {
            d.mates.push(mate);
            Ok(())
        })
    }

    /// Suppresses or unsuppresses a component (SolidWorks' `SetSuppression2`), then
    /// re-solves: a suppressed component's mates are inactive. Unsuppressing a
    /// component whose part is not loaded reads the part's file first
    /// ([`super::Part::is_loaded`]); when it cannot be read, nothing changes
    /// ([`DocumentError::PartUnreadable`]).
    pub fn set_suppressed(&mut self, name: &str, suppressed: bool) -> Result<(), DocumentError> {
        let i = self.component_index(name)?;
        if !suppressed && !self.components[i].held_suppressed {
            self.load_parts_of(&[i])?;
        }
        self.change_and_rebuild(|d| {
            d.components[i].suppressed = suppressed;
            Ok(())
        })
    }

    /// Hides or shows a component (SolidWorks' `Visible`).
    pub fn set_hidden(&mut self, name: &str, hidden: bool) -> Result<(), DocumentError> {
        let i = self.component_index(name)?;
        self.components[i].hidden = hidden;
        self.revision += 1;
        Ok(())
    }

    fn properties_mut(
        &mut self,
        owner: PropertyOwner<'_>,
    ) -> Result<&mut IndexMap<String, String>, DocumentError> {
        Ok(match owner {
            PropertyOwner::Part(p) => {
                let name = self.part(p)?.name.clone();
                &mut self.parts[&name].properties
            }
            PropertyOwner::Component(c) => {
                let i = self.component_index(c)?;
                &mut self.components[i].properties
            }
        })
    }

    /// The custom properties of a part or component, name → text, in order.
    pub fn properties(
        &self,
        owner: PropertyOwner<'_>,
    ) -> Result<&IndexMap<String, String>, DocumentError> {
        Ok(match owner {
            PropertyOwner::Part(p) => &self.part(p)?.properties,
            PropertyOwner::Component(c) => &self.component(c)?.properties,
        })
    }

    /// Sets a custom property (SolidWorks' `ICustomPropertyManager.Add3` with
    /// replace); saved with the document.
    pub fn set_property(
        &mut self,
        owner: PropertyOwner<'_>,
        key: &str,
        value: &str,
    ) -> Result<(), DocumentError> {
        let key = super::new_name(key, "property name")?;
        if key.trim().is_empty() {
            return Err(DocumentError::EmptyName {
                what: "custom property",
            });
        }
        if value
            .chars()
            .any(|c| c.is_control() && c != '\n' && c != '\t')
        {
            return Err(DocumentError::PropertyControl { key: key.into() });
        }
        self.properties_mut(owner)?.insert(key, value.to_string());
        self.revision += 1;
        Ok(())
    }

    /// Deletes a custom property (`ICustomPropertyManager.Delete2`); returns its value,
    /// `None` when there was none.
    pub fn remove_property(
        &mut self,
        owner: PropertyOwner<'_>,
        key: &str,
    ) -> Result<Option<String>, DocumentError> {
        let key = nfc_name(key).into_owned();
        let old = self.properties_mut(owner)?.shift_remove(&key);
        self.revision += 1;
        Ok(old)
    }

    /// Adds a component of an existing part at `transform` (SolidWorks'
    /// `AddComponent5`); returns its index. Not mated: it stays where it is put.
    pub fn add_component(
        &mut self,
        name: &str,
        part: &str,
        transform: Transform,
    ) -> Result<usize, DocumentError> {
        let name = super::new_name(name, "component name")?;
        self.check_parent(&name)?;
        if self.by_name.contains_key(&name) {
            return Err(DocumentError::NameTaken {
                what: "component",
                name,
            });
        }
        let part = self.part(part)?.name.clone();
        super::check_pose(&transform, format_args!("the pose for `{name}`"))?;
        let i = self.components.len();
        // a part not loaded yet is read for the new component (unless it goes into
        // a suppressed sub-assembly); nothing changes when it cannot be
        let before = (!self.parts[&part].loaded).then(|| self.clone());
        self.by_name.insert(name.clone(), i);
        self.numbering.insert(&name);
        self.components
            .push(Component::placed(name, part, transform));
        self.apply_assembly_suppression();
        if let Some(before) = before {
            if !self.components[i].is_suppressed() {
                if let Err(e) = self.load_parts_of(&[i]) {
                    *self = before;
                    return Err(e);
                }
            }
        }
        self.revision += 1;
        Ok(i)
    }

    /// A name for a new component of `part`: `part-N` with the first free N (as
    /// SolidWorks numbers instances).
    pub fn next_instance_name(&self, part: &str) -> String {
        self.numbering.next(&nfc_name(part))
    }

    /// Renames a component (SolidWorks' `IComponent2.Name2 = …`); mates, robots and
    /// the saved file follow.
    pub fn rename_component(&mut self, old: &str, new: &str) -> Result<(), DocumentError> {
        let i = self.component_index(old)?;
        let new = super::new_name(new, "component name")?;
        if new == self.components[i].name {
            return Ok(());
        }
        self.check_parent(&new)?;
        if self.by_name.contains_key(&new) {
            return Err(DocumentError::NameTaken {
                what: "component",
                name: new,
            });
        }
        if self.generated.contains(&self.components[i].part) {
            return Err(DocumentError::UrdfLink {
                component: self.components[i].name.clone().into(),
                edit: LinkEdit::Rename,
            });
        }
        // renamed out of a suppressed sub-assembly, a component whose part is not
        // loaded needs it read; nothing changes when it cannot be
        let before = (!self.part_loaded(i)).then(|| self.clone());
        let old_name = std::mem::replace(&mut self.components[i].name, new.clone());
        self.by_name.remove(&old_name);
        self.numbering.remove(&old_name);
        self.numbering.insert(&new);
        self.by_name.insert(new, i);
        self.apply_assembly_suppression();
        if let Some(before) = before {
            if !self.components[i].is_suppressed() {
                if let Err(e) = self.load_parts_of(&[i]) {
                    *self = before;
                    return Err(e);
                }
            }
        }
        self.revision += 1;
        Ok(())
    }

    /// Makes a component an instance of another part (SolidWorks'
    /// `ReplaceComponents2`): its mates keep their reference names, which the new part
    /// must have; then re-solves.
    pub fn set_component_part(&mut self, name: &str, part: &str) -> Result<(), DocumentError> {
        let i = self.component_index(name)?;
        let part = self.part(part)?.name.clone();
        if self.generated.contains(&self.components[i].part) {
            return Err(DocumentError::UrdfLink {
                component: name.into(),
                edit: LinkEdit::ReplacePart,
            });
        }
        let mut mates = self.mates.clone();
        let new_part = &self.parts[&part];
        for m in &mut mates {
            for e in m.entities.iter_mut().chain(m.about.iter_mut()) {
                if e.component != i {
                    continue;
                }
                e.geometry = new_part.reference(&e.reference).ok_or_else(|| {
                    DocumentError::MissingReference(Box::new(super::MissingReference {
                        mate: m.name.clone(),
                        component: name.to_string(),
                        reference: e.reference.clone(),
                        part: part.clone(),
                    }))
                })?;
            }
            m.check_geometry()?;
        }
        if !self.components[i].is_suppressed() && !self.parts[&part].loaded {
            // the new part is read first (as for the component, the error names it)
            let old = std::mem::replace(&mut self.components[i].part, part.clone());
            let read = self.load_parts_of(&[i]);
            self.components[i].part = old;
            read?;
        }
        self.change_and_rebuild(|d| {
            d.mates = mates;
            d.components[i].part = part;
            Ok(())
        })?;
        if let Ok(mut cache) = self.aabb_cache.0.lock() {
            cache.clear();
        }
        Ok(())
    }

    /// Adds a part whose mesh is `file` (relative to the document's folder, inside
    /// `project`), read through `cache`: a mesh file (STL, OBJ, PLY, glTF), or a STEP
    /// file (`.step`/`.stp`), which makes a `step:` part tessellated with the default
    /// deflection (needs the `step` feature; without it the error says how to add it).
    /// Returns the part's name.
    pub fn add_part(
        &mut self,
        name: &str,
        file: &str,
        project: &Project,
        cache: &mut MeshCache,
    ) -> Result<String, DocumentError> {
        let name = super::new_name(name, "part name")?;
        if name.is_empty() {
            return Err(DocumentError::EmptyName { what: "part" });
        }
        if self.parts.contains_key(&name) {
            return Err(DocumentError::NameTaken { what: "part", name });
        }
        let dir = std::path::absolute(&self.path)
            .ok()
            .and_then(|p| p.parent().map(Path::to_path_buf))
            .and_then(|d| d.canonicalize().ok())
            .unwrap_or_else(|| project.root().to_path_buf());
        let invalid = |source| DocumentError::PartMesh {
            part: name.clone().into(),
            source,
        };
        let mesh_path = project
            .resolve_from(&dir, file)
            .map_err(|e| invalid(PartMeshError::Path(e)))?;
        // A STEP file is a `step:` part (SolidWorks' AddComponent of a STEP file),
        // tessellated as a document's `step:` part with the default deflection and
        // kept in the project's tessellation store.
        let (mesh, mesh_files, step) = if crate::mesh::step::is_step_path(&mesh_path) {
            let pf = PartFile {
                step: Some(file.to_string()),
                ..PartFile::from_stl(String::new())
            };
            let store = project.root().join(crate::mesh::step::STEP_STORE);
            let (mesh, geometry) = super::load::step_mesh(&pf, &mesh_path, project, &store, cache)
                .map_err(|e| invalid(PartMeshError::Step(Box::new(e))))?;
            (mesh, Vec::new(), Some(geometry))
        } else {
            let mesh = cache
                .get_in(project, &mesh_path)
                .map_err(|e| invalid(PartMeshError::Read(e)))?;
            (mesh, cache.files_of(&mesh_path), None)
        };
        self.parts.insert(
            name.clone(),
            Part {
                name: name.clone(),
                stl: file.replace('\\', "/"),
                mesh_path,
                mesh_files,
                step,
                mesh,
                references: IndexMap::new(),
                features: Vec::new(),
                properties: IndexMap::new(),
                loaded: true,
                at: None,
            },
        );
        self.revision += 1;
        Ok(name)
    }

    /// Adds or replaces a named reference (plane, axis or point, part frame, mm) of a
    /// part (SolidWorks' reference geometry); directions are normalised. Mates using
    /// the reference follow it and are re-solved; refused, with nothing changed, when
    /// they cannot be satisfied, for a built-in name (`origin`, `front`, …) or for a
    /// non-finite or zero-length vector.
    pub fn set_reference(
        &mut self,
        part: &str,
        name: &str,
        reference: Reference,
    ) -> Result<(), DocumentError> {
        let part = self.part(part)?.name.clone();
        let name = super::new_name(name, "reference name")?;
        let bad = |problem| DocumentError::BadReference {
            part: part.clone().into(),
            reference: name.clone().into(),
            problem,
        };
        if name.is_empty() || Reference::BUILTIN_NAMES.contains(&name.as_str()) {
            return Err(bad(ReferenceProblem::ReservedName));
        }
        let finite = reference
            .anchor()
            .coords
            .iter()
            .chain(reference.direction().unwrap_or_default().iter())
            .all(|v| v.is_finite() && v.abs() <= super::MAX_ABS_VALUE)
            && reference.coordinate_system().is_none_or(|f| f.is_finite());
        if !finite {
            return Err(bad(ReferenceProblem::NotFinite));
        }
        let reference = match reference {
            Reference::Plane { point, normal } => Reference::Plane {
                point,
                normal: normal
                    .try_normalize(1e-12)
                    .ok_or_else(|| bad(ReferenceProblem::ZeroNormal))?,
            },
            Reference::Axis { point, direction } => Reference::Axis {
                point,
                direction: direction
                    .try_normalize(1e-12)
                    .ok_or_else(|| bad(ReferenceProblem::ZeroDirection))?,
            },
            p @ (Reference::Point(_) | Reference::CoordinateSystem(_)) => p,
        };
        let mut mates = self.mates.clone();
        for m in &mut mates {
            for e in m.entities.iter_mut().chain(m.about.iter_mut()) {
                if self.components[e.component].part == part && e.reference == name {
                    e.geometry = reference;
                }
            }
            m.check_geometry()?;
        }
        let old = self.parts[&part].references.clone();
        let result = self.change_and_rebuild(|d| {
            d.mates = mates;
            d.parts[&part].references.insert(name.clone(), reference);
            Ok(())
        });
        if result.is_err() {
            self.parts[&part].references = old;
        }
        result
    }

    /// [`add_part`](Self::add_part) in the document's own project (the nearest folder
    /// of the document holding `fitup.toml`, else its folder), reading the mesh
    /// afresh.
    pub fn add_part_file(&mut self, name: &str, file: &str) -> Result<String, DocumentError> {
        let project = Project::for_file(&self.path).map_err(|e| DocumentError::PartMesh {
            part: name.into(),
            source: PartMeshError::Project(e.into()),
        })?;
        self.add_part(name, file, &project, &mut MeshCache::new())
    }
}
