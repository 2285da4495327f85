//! Writing a document: its YAML schema, and the checked atomic save.

use super::file::{
    AssemblyFile, AxisFile, ComponentFile, CoordinateSystemFile, DocumentFile, FeatureFile,
    MateFile, PartFile, PlaneFile, PlanesFile,
};
use super::{Color, Document, DocumentError, Feature, MateKind, Reference, WriteProblem};
use crate::collision::CutSpec;
use crate::fsutil::{content_hash, relative_path, FileKind};
use crate::math::Vec3;
use std::path::{Path, PathBuf};

impl Document {
    /// The document as its YAML schema (what `save` writes).
    pub fn to_file(&self) -> DocumentFile {
        let frames = super::assembly::frames(&self.assemblies);
        // what sub-documents hold is written in their files
        let held = super::subdoc::HeldBy::new(&self.assemblies);
        let parts = self
            .parts
            .values()
            .filter(|p| !self.generated.contains(&p.name) && !held.inside(&p.name))
            .map(|p| {
                let mut pf = PartFile {
                    features: p.features.iter().map(Feature::to_file).collect(),
                    properties: property_values(&p.properties),
                    ..PartFile::from_stl(p.stl.clone())
                };
                if let Some(step) = &p.step {
                    pf.step = Some(std::mem::take(&mut pf.stl));
                    pf.deflection = step.deflection;
                    pf.angle = step.angle;
                }
                for (n, r) in &p.references {
                    let a = |v: Vec3| [v.x, v.y, v.z];
                    match *r {
                        Reference::Plane { point, normal } => {
                            pf.planes.insert(
                                n.clone(),
                                PlaneFile {
                                    point: a(point.coords),
                                    normal: a(normal),
                                },
                            );
                        }
                        Reference::Axis { point, direction } => {
                            pf.axes.insert(
                                n.clone(),
                                AxisFile {
                                    point: a(point.coords),
                                    direction: a(direction),
                                },
                            );
                        }
                        Reference::Point(point) => {
                            pf.points.insert(n.clone(), a(point.coords));
                        }
                        Reference::CoordinateSystem(f) => {
                            pf.coordinate_systems.insert(
                                n.clone(),
                                CoordinateSystemFile {
                                    origin: a(f.translation()),
                                    x: a(f.apply_vector(&Vec3::x())),
                                    y: a(f.apply_vector(&Vec3::y())),
                                },
                            );
                        }
                    }
                }
                (p.name.clone(), pf)
            })
            .collect();
        let components = self
            .components
            .iter()
            .filter(|c| !self.generated.contains(&c.part) && !held.inside(&c.name))
            .map(|c| ComponentFile {
                name: c.name.clone(),
                part: c.part.clone(),
                fixed: c.fixed,
                color: c.color.as_ref().map(color_value),
                transform: Some(Self::local_pose(&frames, &c.name, c.transform)),
                mass: c.mass,
                threaded: c.threaded,
                fixture: c.fixture,
                suppressed: c.suppressed,
                hidden: c.hidden,
                properties: property_values(&c.properties),
            })
            .collect();
        let mates = self
            .mates
            .iter()
            .filter(|m| !held.inside(&m.name))
            .map(|m| MateFile {
                name: m.name.clone(),
                kind: m.kind.name().into(),
                entities: m
                    .entities
                    .clone()
                    .map(|e| format!("{}/{}", self.components[e.component].name, e.reference)),
                value: m.value.map(|v| {
                    if m.kind == MateKind::Angle {
                        tidy(v.to_degrees())
                    } else {
                        tidy(v)
                    }
                }),
                aligned: m.aligned,
                about: m
                    .about
                    .as_ref()
                    .map(|e| format!("{}/{}", self.components[e.component].name, e.reference)),
                suppressed: m.suppressed,
            })
            .collect();
        let assemblies = self
            .assemblies
            .iter()
            .filter(|a| !held.inside(&a.name))
            .map(|a| AssemblyFile {
                name: a.name.clone(),
                transform: Some(Self::local_pose(&frames, &a.name, a.transform)),
                file: a.file.as_ref().map(|f| f.file.clone()),
                suppressed: a.suppressed,
            })
            .collect();
        DocumentFile {
            units: "mm".into(),
            description: self.description.clone(),
            mesh_deflection: self.mesh_deflection,
            parts,
            assemblies,
            components,
            mates,
            robots: self
                .robots
                .iter()
                .filter(|r| !held.inside(r.name()))
                .map(|r| r.to_file_named(|c| self.components[c].name.clone()))
                .collect(),
            // A sub-document's equations are written in its own file.
            equations: self
                .equations
                .iter()
                .filter(|e| e.scope.is_none())
                .map(|e| e.text())
                .collect(),
        }
    }

    /// `world` (the pose of `name`) relative to its parent sub-assembly, as the file
    /// writes it (mm, tidied).
    fn local_pose(
        frames: &std::collections::HashMap<&str, crate::math::Transform>,
        name: &str,
        world: crate::math::Transform,
    ) -> [[f64; 4]; 4] {
        let frame =
            super::assembly::parent_frame(frames, name).unwrap_or(crate::math::Transform::IDENTITY);
        let local = if frame == crate::math::Transform::IDENTITY {
            world
        } else {
            world * frame.inverse()
        };
        if frame == crate::math::Transform::IDENTITY {
            return local.to_matrix().map(|row| row.map(tidy));
        }
        // composing and decomposing leaves float noise (`180.00000000000003`,
        // `-5.7e-14`): snapped to the nearest 1e-9 when within 1e-12 of it (relative)
        local
            .to_matrix()
            .map(|row| row.map(|x| tidy(super::snap(x))))
    }

    /// The document as YAML text.
    pub fn to_yaml(&self) -> String {
        self.to_file().to_yaml().unwrap_or_default()
    }

    /// Writes the document back to its file atomically.
    ///
    /// Refused, with nothing written, when the text would not load again (a value out
    /// of range, …) or when the file changed on disk since the document was loaded or
    /// last saved (another writer's edits are never overwritten silently: reopen the
    /// document and apply the change again).
    pub fn save(&mut self) -> Result<(), DocumentError> {
        let path = self.path.clone();
        let expected = self.disk_hash;
        let mut written = Vec::new();
        let r = self.write_checked(&path, expected, None, &mut written);
        self.saved(written);
        r
    }

    /// [`save`](Self::save) through `folder`, the document's folder already held open
    /// (a project's writer walks it from the project root without following a link,
    /// [`crate::project::Project::folder`]): the check of what is on disk and the
    /// write go through that handle, so a folder swapped for a link to somewhere else
    /// cannot redirect either.
    pub fn save_in(&mut self, folder: crate::fsutil::Dir) -> Result<(), DocumentError> {
        let path = self.path.clone();
        let expected = self.disk_hash;
        let mut written = Vec::new();
        let r = self.write_checked(&path, expected, Some(folder), &mut written);
        self.saved(written);
        r
    }

    /// Writes the document to `path` atomically and makes it the document's file.
    /// Relative mesh paths are rewritten so they still point at the same meshes.
    ///
    /// Refuses to overwrite a file this document was read from
    /// ([`source_files`](Self::source_files): a mesh, [`DocumentError::OverMesh`]; a
    /// sub-document, STEP file, URDF, [`crate::project::OutputError::Source`]) and any
    /// existing file that is not a fitup document; over its own file it behaves as
    /// [`save`](Self::save).
    pub fn save_as(&mut self, path: &Path) -> Result<(), DocumentError> {
        self.save_as_through(path, None)
    }

    /// [`save_as`](Self::save_as) through `folder`, the target's folder already held
    /// open (see [`save_in`](Self::save_in)).
    pub fn save_as_in(
        &mut self,
        path: &Path,
        folder: crate::fsutil::Dir,
    ) -> Result<(), DocumentError> {
        self.save_as_through(path, Some(folder))
    }

    fn save_as_through(
        &mut self,
        path: &Path,
        folder: Option<crate::fsutil::Dir>,
    ) -> Result<(), DocumentError> {
        let target = crate::fsutil::resolved_path(path);
        if let Some(p) = self
            .parts
            .values()
            .find(|p| crate::fsutil::resolved_path(&p.mesh_path) == target)
        {
            return Err(DocumentError::OverMesh {
                path: path.to_path_buf(),
                part: p.name.clone().into(),
            });
        }
        // Its other sources (sub-documents, URDFs, a mesh's buffers); its own file is
        // its save.
        let others: Vec<PathBuf> = self
            .source_files()
            .into_iter()
            .filter(|s| *s != self.path)
            .collect();
        if target != crate::fsutil::resolved_path(&self.path)
            && crate::project::is_source(path, &others)
        {
            return Err(DocumentError::Write {
                path: path.to_path_buf(),
                cause: WriteProblem::Output(crate::project::OutputError::Source {
                    path: path.to_path_buf(),
                }),
            });
        }
        let expected = (target == crate::fsutil::resolved_path(&self.path))
            .then_some(self.disk_hash)
            .flatten();
        let new_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let old = self.parts.clone();
        let old_robots = self.robots.clone();
        let old_assemblies = self.assemblies.clone();
        let held = super::subdoc::HeldBy::new(&self.assemblies);
        // a sub-document's parts name their meshes from its own folder
        let own_parts: Vec<bool> = self.parts.values().map(|p| !held.inside(&p.name)).collect();
        // a sub-document's robots name their URDF from its own folder
        let own_robots: Vec<bool> = self.robots.iter().map(|r| !held.inside(r.name())).collect();
        let nested: Vec<bool> = self
            .assemblies
            .iter()
            .map(|a| held.inside(&a.name))
            .collect();
        drop(held);
        for (p, own) in self.parts.values_mut().zip(own_parts) {
            if let Some(rel) = relative_path(&p.mesh_path, &new_dir).filter(|_| own) {
                p.stl = rel;
            }
        }
        for (r, own) in self.robots.iter_mut().zip(own_robots) {
            if own {
                r.rebase_urdf(|f| relative_path(f, &new_dir));
            }
        }
        for (a, nested) in self.assemblies.iter_mut().zip(nested) {
            if let (Some(f), false) = (&mut a.file, nested) {
                if let Some(rel) = relative_path(&f.path, &new_dir) {
                    f.file = rel;
                }
            }
        }
        let mut written = Vec::new();
        let r = self.write_checked(path, expected, folder, &mut written);
        self.saved(written);
        if let Err(e) = r {
            self.parts = old;
            self.robots = old_robots;
            self.assemblies = old_assemblies;
            return Err(e);
        }
        self.path = path.to_path_buf();
        Ok(())
    }

    /// Validates the text, then, holding a lock on the folder (so concurrent fitup
    /// writers take turns), checks what is on disk — the bytes hashed to `expected`, or
    /// else no file or a fitup document — and replaces it atomically.
    pub(super) fn write_checked(
        &mut self,
        path: &Path,
        expected: Option<u64>,
        folder: Option<crate::fsutil::Dir>,
        written: &mut Vec<super::subdoc::Written>,
    ) -> Result<(), DocumentError> {
        let write_err = |cause: WriteProblem| DocumentError::Write {
            path: path.into(),
            cause,
        };
        // A save solves what loading solves (SolidWorks rebuilds on save): the file
        // holds the poses the mates give, and a document whose mates cannot be
        // satisfied (a mated component moved, then fixed) is refused, not written.
        let mut solved = self.clone();
        solved
            .solve_mates()
            .map_err(|e| write_err(WriteProblem::Unsolvable(e)))?;
        let text = solved
            .to_file()
            .to_yaml()
            .map_err(|e| write_err(WriteProblem::Serialize(e.into())))?;
        if let Err(e) = Self::parse_text(&text, path) {
            return Err(write_err(WriteProblem::WouldNotReload(Box::new(e))));
        }
        // The sub-documents changed from a script first (each through the same checked
        // write), so the document is written last, over sub-documents that hold
        // what it names.
        solved.save_sub_documents(written)?;
        // The folder is opened once: the lock, the check of what is on disk and the
        // write all go through that handle (never a second lookup by name).
        let dir = match folder {
            Some(d) => d,
            None => {
                let parent = match path.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                crate::fsutil::Dir::open(parent)
                    .map_err(|e| write_err(WriteProblem::Io(e.into())))?
            }
        };
        let Some(name) = path.file_name() else {
            return Err(write_err(WriteProblem::NotAFileName));
        };
        let _lock = dir.lock();
        let on_disk = match dir.stat(name) {
            Ok(None) => None,
            Ok(Some(crate::fsutil::Kind::File(size))) => {
                match dir.read_capped(name, FileKind::Document.max_bytes()) {
                    Ok(Some(bytes)) => Some(Ok(bytes)),
                    Ok(None) => Some(Err(crate::fsutil::ReadError::TooLarge {
                        size,
                        cap: FileKind::Document.max_bytes() >> 20,
                        what: FileKind::Document.name(),
                    })),
                    Err(e) => Some(Err(crate::fsutil::ReadError::Io(e.into()))),
                }
            }
            Ok(Some(crate::fsutil::Kind::Symlink)) => {
                Some(Err(crate::fsutil::ReadError::NotRegular("a symbolic link")))
            }
            Ok(Some(crate::fsutil::Kind::Dir)) => {
                Some(Err(crate::fsutil::ReadError::NotRegular("a folder")))
            }
            Ok(Some(crate::fsutil::Kind::Special(what))) => {
                Some(Err(crate::fsutil::ReadError::NotRegular(what)))
            }
            Err(e) => Some(Err(crate::fsutil::ReadError::Io(e.into()))),
        };
        match on_disk {
            None => {}
            Some(Ok(bytes)) => match expected {
                Some(h) if content_hash(&bytes) != h => {
                    return Err(write_err(WriteProblem::ChangedOnDisk))
                }
                Some(_) => {}
                None => {
                    let is_document = std::str::from_utf8(&bytes)
                        .ok()
                        .is_some_and(|t| Self::parse_text(t, path).is_ok());
                    if !is_document {
                        return Err(write_err(WriteProblem::NotADocument));
                    }
                }
            },
            Some(Err(e)) => return Err(write_err(WriteProblem::Unreadable(e))),
        }
        dir.write_atomic(name, text.as_bytes())
            .map_err(|e| write_err(WriteProblem::Io(e.into())))?;
        self.disk_hash = Some(content_hash(text.as_bytes()));
        let mut moved = false;
        for (c, s) in self.components.iter_mut().zip(&solved.components) {
            moved |= c.transform != s.transform;
            c.transform = s.transform;
        }
        if moved {
            self.revision += 1;
        }
        Ok(())
    }
}

fn property_values(
    p: &indexmap::IndexMap<String, String>,
) -> indexmap::IndexMap<String, serde_yaml::Value> {
    p.iter()
        .map(|(k, v)| (k.clone(), serde_yaml::Value::String(v.clone())))
        .collect()
}

fn color_value(c: &Color) -> serde_yaml::Value {
    let h = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    serde_yaml::Value::String(format!("#{:02x}{:02x}{:02x}", h(c[0]), h(c[1]), h(c[2])))
}

/// Snaps round-off (|x| < 1e-14 → 0) so saved matrices read cleanly; idempotent.
fn tidy(x: f64) -> f64 {
    if x.abs() < 1e-14 {
        0.0
    } else {
        x
    }
}

impl Feature {
    fn to_file(&self) -> FeatureFile {
        match self {
            Feature::CutCells {
                name,
                spec: CutSpec::Size(s),
            } => FeatureFile::CutCells {
                name: name.clone(),
                cell_size: Some(*s),
                planes: None,
            },
            Feature::CutCells {
                name,
                spec: CutSpec::Planes { x, y, z },
            } => FeatureFile::CutCells {
                name: name.clone(),
                cell_size: None,
                planes: Some(PlanesFile {
                    x: x.clone(),
                    y: y.clone(),
                    z: z.clone(),
                }),
            },
        }
    }
}
