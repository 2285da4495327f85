//! Bindings for the assembly document: `open_doc`, components, dimensions, save.

use super::api::Api;
use super::bind_math::to_transform;
use super::convert::{array3, box_value, err, fail, floats, num, point3, vec3};
use super::{Context, ScriptResult};
use crate::document::{DimensionKind, Document, Reference};
use crate::math::{Transform, Vec3};
use rhai::{Array, Dynamic, Map};
use std::sync::{Arc, Mutex, MutexGuard};

/// Why [`DocHandle::open`] could not open a script's document.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OpenError {
    /// The path is refused by the project's path rule (outside the project, …).
    #[error(transparent)]
    Path(#[from] crate::project::PathError),
    /// No file at the path.
    #[error("`{}` does not exist in the project folder {} (the project folder is `--root`, else the nearest folder of the script holding fitup.toml, else the script's folder)", .path.display(), .root.display())]
    Missing {
        /// The path as the script gave it (relative to the project folder).
        path: std::path::PathBuf,
        /// The project folder.
        root: std::path::PathBuf,
    },
    /// A shared cache is unusable after a panic in another run.
    #[error("{0} cache poisoned")]
    Poisoned(&'static str),
    /// The document does not load; the message is located with its source line.
    #[error("{}", .0.render())]
    Document(#[source] crate::document::DocumentError),
}

/// A script's handle on an open document (cheap to clone; clones share the document).
#[derive(Clone)]
pub struct DocHandle {
    inner: Arc<Mutex<Document>>,
    ctx: Arc<Context>,
}

/// A component of a document, by index.
#[derive(Clone)]
pub struct ComponentHandle {
    pub(crate) doc: DocHandle,
    /// Its index when the handle was made …
    index: usize,
    /// … and the document's number of removals then (see [`Document::index_since`]).
    since: usize,
}

/// A driving dimension of a document, by full name (`D1@角度1`).
#[derive(Clone)]
pub struct DimensionHandle {
    doc: DocHandle,
    name: String,
}

impl DocHandle {
    /// Opens a document (path relative to the project root) through the shared mesh
    /// cache and records its files as dependencies of the run.
    pub fn open(ctx: &Arc<Context>, path: &str) -> Result<Self, OpenError> {
        let full = ctx.project.resolve(path)?;
        ctx.record_read(&full);
        if !full.exists() {
            // The usual cause is a project root other than the user expects.
            return Err(OpenError::Missing {
                path: path.into(),
                root: ctx.project.root().to_path_buf(),
            });
        }
        let root = ctx.project.root().to_path_buf();
        let cached = ctx
            .caches
            .documents
            .lock()
            .map_err(|_| OpenError::Poisoned("document"))?
            .get(&root, &full);
        let doc = match cached {
            Some(doc) => doc,
            None => {
                let doc = {
                    let mut cache = ctx
                        .caches
                        .meshes
                        .lock()
                        .map_err(|_| OpenError::Poisoned("mesh"))?;
                    Document::load_in(&full, &ctx.project, &mut cache)
                        .map_err(OpenError::Document)?
                };
                ctx.caches
                    .documents
                    .lock()
                    .map_err(|_| OpenError::Poisoned("document"))?
                    .insert(&root, &full, &doc);
                doc
            }
        };
        for f in doc.source_files() {
            ctx.record_read(&f);
        }
        for w in doc.warnings() {
            ctx.warn(w);
        }
        ctx.caches.view.log_document(&doc);
        let inner = Arc::new(Mutex::new(doc));
        ctx.record_document(&inner);
        Ok(Self {
            inner,
            ctx: ctx.clone(),
        })
    }

    /// Locks the document.
    pub fn lock(&self) -> ScriptResult<MutexGuard<'_, Document>> {
        self.inner
            .lock()
            .map_err(|_| fail("the document is unusable after an earlier panic"))
    }

    /// The run context.
    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    pub(crate) fn component(&self, name: &str) -> ScriptResult<ComponentHandle> {
        let doc = self.lock()?;
        let index = doc.component_index(name).map_err(fail)?;
        Ok(ComponentHandle::new(self, &doc, index))
    }
}

impl ComponentHandle {
    /// A handle on component `index` of `doc` (the document of `handle`, locked).
    pub(crate) fn new(handle: &DocHandle, doc: &Document, index: usize) -> Self {
        ComponentHandle {
            doc: handle.clone(),
            index,
            since: doc.removals().len(),
        }
    }

    /// The component's index in `doc` (its document, locked) today: components
    /// removed since the handle was made shift it; its own removal is an error.
    pub(crate) fn at(&self, doc: &Document) -> ScriptResult<usize> {
        doc.index_since(self.index, self.since)
            .ok_or_else(|| fail("this component was removed from the document"))
    }

    /// The component's index today (locks the document for the lookup only).
    pub(crate) fn index(&self) -> ScriptResult<usize> {
        self.locked().map(|(_, i)| i)
    }

    /// The document locked, and the component's index in it.
    pub(crate) fn locked(&self) -> ScriptResult<(MutexGuard<'_, Document>, usize)> {
        let doc = self.doc.lock()?;
        let i = self.at(&doc)?;
        Ok((doc, i))
    }

    fn with<R>(
        &self,
        f: impl FnOnce(&Document, &crate::document::Component) -> R,
    ) -> ScriptResult<R> {
        let (doc, i) = self.locked()?;
        Ok(f(&doc, &doc.components()[i]))
    }

    /// `f` of the component.
    pub(crate) fn with_component<R>(
        &self,
        f: impl FnOnce(&crate::document::Component) -> R,
    ) -> ScriptResult<R> {
        self.with(|_, c| f(c))
    }

    fn set_transform(&self, t: Transform) -> ScriptResult<()> {
        let (mut doc, i) = self.locked()?;
        doc.set_transform_at(i, t).map_err(fail)?;
        self.show_pose(&doc, i);
        Ok(())
    }

    /// Shows the new pose in the viewer as a new animation frame.
    fn show_pose(&self, doc: &Document, i: usize) {
        let view = &self.doc.context().caches.view;
        if view.is_live() {
            let c = &doc.components()[i];
            view.log_poses(doc, vec![(c.name.clone(), c.transform)], true);
        }
    }

    /// Moves the component by `motion` applied after its pose (world frame), under one lock.
    fn move_by(&self, motion: Transform) -> ScriptResult<()> {
        let (mut doc, i) = self.locked()?;
        doc.move_component_at(i, &motion).map_err(fail)?;
        self.show_pose(&doc, i);
        Ok(())
    }

    fn transform(&self) -> ScriptResult<Transform> {
        self.with(|_, c| c.transform)
    }
}

fn reference_map(r: &Reference) -> Map {
    let mut m = Map::new();
    m.insert("type".into(), r.kind_name().into());
    m.insert("point".into(), array3(&r.anchor().coords));
    match r {
        Reference::Plane { normal, .. } => {
            m.insert("normal".into(), array3(normal));
        }
        Reference::Axis { direction, .. } => {
            m.insert("direction".into(), array3(direction));
        }
        Reference::Point(_) => {}
        Reference::CoordinateSystem(f) => {
            m.insert("x".into(), array3(&f.apply_vector(&Vec3::x())));
            m.insert("y".into(), array3(&f.apply_vector(&Vec3::y())));
            m.insert("z".into(), array3(&f.apply_vector(&Vec3::z())));
            m.insert("transform".into(), Dynamic::from(*f));
        }
    }
    m
}

pub(super) fn register(api: &mut Api, ctx: &Arc<Context>) {
    api.section("Document", "An assembly document (YAML + STL). Lengths in mm, angles in radians unless a name says degrees. Components are part instances with a pose (`transform`, part frame → world).");
    api.type_::<DocHandle>("Document");
    api.type_::<ComponentHandle>("Component");
    api.type_::<DimensionHandle>("Dimension");
    let c = ctx.clone();
    api.f("open_doc(path: string) -> Document", "Opens a document (path relative to the project folder); its file and meshes become dependencies of the run, so `fitup watch` reruns when they change.", move |path: &str| -> ScriptResult<DocHandle> {
        DocHandle::open(&c, path).map_err(fail)
    });
    api.get(
        "Document.path -> string",
        "The document's file, relative to the project folder.",
        |d: &mut DocHandle| -> ScriptResult<String> {
            let p = d.lock()?.path().to_path_buf();
            Ok(d.ctx.project.display(&p))
        },
    );
    api.f(
        "Document.component(name: string) -> Component",
        "A component by name; a missing name is an error that lists close matches.",
        |d: &mut DocHandle, name: &str| d.component(name),
    );
    api.f(
        "Document.set_transform(name: string, pose)",
        "Sets the pose of component `name` (part frame → world, mm): a Transform, a 4×4 matrix or `[x, y, z, a, b, c]` (mm, degrees). Same as `doc.component(name).set_transform(pose)`; fixed components refuse.",
        |d: &mut DocHandle, name: &str, v: Dynamic| -> ScriptResult<()> {
            let t = to_transform(&v, "pose")?;
            d.component(name)?.set_transform(t)
        },
    );
    api.f(
        "Document.components() -> array",
        "Every component, in document order.",
        |d: &mut DocHandle| -> ScriptResult<Array> {
            let doc = d.lock()?;
            Ok((0..doc.components().len())
                .map(|index| Dynamic::from(ComponentHandle::new(d, &doc, index)))
                .collect())
        },
    );
    api.f(
        "Document.parts() -> array",
        "Part names, in document order.",
        |d: &mut DocHandle| -> ScriptResult<Array> {
            Ok(d.lock()?
                .parts()
                .map(|p| Dynamic::from(p.name.clone()))
                .collect())
        },
    );
    api.f(
        "Document.dimensions() -> array",
        "Full names of the driving dimensions (`D1@<mate>`), in document order.",
        |d: &mut DocHandle| -> ScriptResult<Array> {
            Ok(d.lock()?
                .dimensions()
                .into_iter()
                .map(Dynamic::from)
                .collect())
        },
    );
    api.f(
        "Document.dimension(full_name: string) -> Dimension",
        "A driving dimension by full name, e.g. `D1@角度1`.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<DimensionHandle> {
            d.lock()?.dimension(name).map_err(fail)?;
            Ok(DimensionHandle {
                doc: d.clone(),
                name: name.to_string(),
            })
        },
    );
    api.f(
        "Document.rebuild()",
        "Re-solves the mates (SolidWorks' rebuild): components follow what they are mated to.",
        |d: &mut DocHandle| -> ScriptResult<()> { d.lock()?.rebuild().map_err(fail) },
    );
    api.f(
        "Document.aabb() -> Box",
        "The world box around every component (mm): a `Box` (`.min`, `.max`).",
        |d: &mut DocHandle| -> ScriptResult<Dynamic> {
            match d.lock()?.assembly_aabb() {
                Some(b) => Ok(box_value(&b)),
                None => err("the document has no components"),
            }
        },
    );
    api.f(
        "Document.save()",
        "Writes the document back to its file atomically (temporary file, then rename). Refused, with nothing written, when the file changed on disk since it was opened or last saved (another writer's edits are kept), or when a value would make the document unloadable.",
        |d: &mut DocHandle| -> ScriptResult<()> {
            let mut doc = d.lock()?;
            let path = doc.path().to_path_buf();
            // Through the document's folder walked from the project root without
            // following a link (a folder swapped for a link cannot redirect the save).
            let folder = d.ctx.document_folder(&path)?;
            d.ctx.writing(&path, || doc.save_in(folder)).map_err(fail)?;
            // sub-documents a script changed were written too
            for p in doc.saved_sub_documents() {
                d.ctx.record_write(p);
            }
            Ok(())
        },
    );
    let c = ctx.clone();
    api.f("Document.save_as(path: string)", "Writes the document to a new file (inside the project; missing folders are created) atomically and makes it the document's file; mesh paths are rewritten relative to it. Refuses to overwrite a file a document open in the run was read from (its meshes, STEP files, sub-documents, URDFs; another open document's file) and any file that is not a fitup document.", move |d: &mut DocHandle, path: &str| -> ScriptResult<()> {
        let full = c.project.resolve_for_write(path).map_err(fail)?;
        let mut doc = d.lock()?;
        // Another open document's files (its own are checked by `save_as`; its own
        // file is its save).
        let own = [doc.path().to_path_buf()];
        let others: Vec<std::path::PathBuf> = c
            .document_sources()
            .into_iter()
            .filter(|s| !crate::project::is_source(s, &own))
            .collect();
        if !crate::project::is_source(&full, &own) && crate::project::is_source(&full, &others) {
            return Err(fail(crate::document::DocumentError::Write {
                path: full.clone(),
                cause: crate::document::WriteProblem::Output(crate::project::OutputError::Source {
                    path: full,
                }),
            }));
        }
        let folder = c.document_folder(&full)?;
        c.writing(&full, || doc.save_as_in(&full, folder)).map_err(fail)?;
        for p in doc.saved_sub_documents() {
            c.record_write(p);
        }
        Ok(())
    });
    fn export_glb(d: &DocHandle, file: &str, overwrite: bool) -> ScriptResult<()> {
        let bytes = d.lock()?.glb_bytes().map_err(fail)?;
        d.ctx.write_output(file, &bytes, overwrite)?;
        Ok(())
    }
    api.f("Document.export_glb(file: string)", "Writes the document as binary glTF (one node per component, named as it, at its pose; metres and +Y up as glTF wants, see docs/document.md) inside the project, atomically. Never replaces a file a document open in the run was read from (its YAML, sub-documents, meshes, STEP files, URDFs), not even with `#{overwrite: true}`; refuses another file the project uses or one fitup did not write, which `#{overwrite: true}` replaces.", |d: &mut DocHandle, file: &str| -> ScriptResult<()> {
        export_glb(d, file, false)
    });
    api.f(
        "Document.export_glb(file: string, options: map)",
        "`export_glb(file)` with `#{overwrite}` (bool, default false). With `components` (names) or `frame` (a pose in the world), those components (default: every one neither suppressed nor hidden) are written as `c.export_glb` writes one: each mesh with its pose baked in, in the coordinates of `frame` (default the world), one node per component without a matrix of its own; a suppressed one is refused.",
        |d: &mut DocHandle, file: &str, opts: Map| -> ScriptResult<()> {
            if !(opts.contains_key("components") || opts.contains_key("frame")) {
                let overwrite = super::convert::overwrite_option(&opts, "export_glb")?;
                return export_glb(d, file, overwrite);
            }
            let shown = super::bind_mass::shown_components(d)?;
            let (which, frame, overwrite) =
                super::bind_mass::export_options(d, &opts, shown, "export_glb")?;
            let format = super::bind_mass::ExportFormat::Glb;
            super::bind_mass::export_components(d, file, &which, frame.as_ref(), overwrite, format)
        },
    );
    api.f(
        "Document.to_string() -> string",
        "A one-line summary.",
        |d: &mut DocHandle| -> ScriptResult<String> {
            let doc = d.lock()?;
            Ok(format!(
                "Document({}: {} parts, {} components, {} mates)",
                d.ctx.project.display(doc.path()),
                doc.parts().count(),
                doc.components().len(),
                doc.mates().len()
            ))
        },
    );

    api.section("Component", "A part instance. `transform` maps the part frame to the world (mm). Fixed components refuse to move.");
    api.get(
        "Component.name -> string",
        "The component name.",
        |c: &mut ComponentHandle| c.with(|_, c| c.name.clone()),
    );
    api.get(
        "Component.part -> string",
        "The part it instantiates.",
        |c: &mut ComponentHandle| c.with(|_, c| c.part.clone()),
    );
    api.get(
        "Component.fixed -> bool",
        "Whether the component is fixed (never moved by mates, moves or planners).",
        |c: &mut ComponentHandle| c.with(|_, c| c.fixed),
    );
    api.set(
        "Component.fixed",
        |c: &mut ComponentHandle, v: bool| -> ScriptResult<()> {
            let (mut doc, i) = c.locked()?;
            let name = doc.components()[i].name.clone();
            doc.set_fixed(&name, v).map_err(fail)
        },
    );
    api.get(
        "Component.transform -> Transform",
        "The pose, part frame → world (mm).",
        |c: &mut ComponentHandle| c.transform(),
    );
    api.set(
        "Component.transform",
        |c: &mut ComponentHandle, v: Dynamic| -> ScriptResult<()> {
            let t = to_transform(&v, "transform")?;
            c.set_transform(t)
        },
    );
    // Rhai refuses `doc.component("x").transform = m` (a property set on a call's
    // result is a syntax error), so setting a pose has a one-call spelling too.
    api.f(
        "Component.set_transform(pose)",
        "Sets the pose (part frame → world, mm): a Transform, a 4×4 matrix or `[x, y, z, a, b, c]` (mm, degrees). The one-call spelling of `c.transform = pose` that also works on a call's result: `doc.component(\"x\").set_transform(pose)`.",
        |c: &mut ComponentHandle, v: Dynamic| -> ScriptResult<()> {
            c.set_transform(to_transform(&v, "pose")?)
        },
    );
    api.get(
        "Component.color -> array",
        "`[r, g, b]` in 0..1, or an empty array when unset.",
        |c: &mut ComponentHandle| {
            c.with(|_, c| {
                c.color
                    .map(floats)
                    .unwrap_or_else(|| Dynamic::from_array(Array::new()))
            })
        },
    );
    api.f(
        "Component.translate(dx, dy, dz)",
        "Moves the component by (dx, dy, dz) mm in the world frame.",
        |c: &mut ComponentHandle, x: Dynamic, y: Dynamic, z: Dynamic| -> ScriptResult<()> {
            let d = Vec3::new(num(&x, "dx")?, num(&y, "dy")?, num(&z, "dz")?);
            c.move_by(Transform::from_translation(d))
        },
    );
    // typed fast paths of the form above (all floats, all integers): no Dynamic
    // conversions on the hot path of animation loops
    api.overload(
        "Component.translate(dx, dy, dz)",
        |c: &mut ComponentHandle, x: f64, y: f64, z: f64| -> ScriptResult<()> {
            c.move_by(Transform::from_translation(Vec3::new(x, y, z)))
        },
    );
    api.overload(
        "Component.translate(dx, dy, dz)",
        |c: &mut ComponentHandle, x: i64, y: i64, z: i64| -> ScriptResult<()> {
            c.move_by(Transform::from_translation(Vec3::new(
                x as f64, y as f64, z as f64,
            )))
        },
    );
    api.f(
        "Component.translate(v: array)",
        "Moves the component by `[dx, dy, dz]` mm in the world frame.",
        |c: &mut ComponentHandle, v: Dynamic| -> ScriptResult<()> {
            let d = vec3(&v, "translation")?;
            c.move_by(Transform::from_translation(d))
        },
    );
    api.f("Component.rotate(point: array, axis: array, angle_rad)", "Rotates the component by `angle_rad` **radians** about the world line through `point` (mm) along `axis`.", |c: &mut ComponentHandle, p: Dynamic, a: Dynamic, ang: Dynamic| -> ScriptResult<()> {
        let r = Transform::from_rotation_about(point3(&p, "point")?, vec3(&a, "axis")?, num(&ang, "angle")?).map_err(fail)?;
        c.move_by(r)
    });
    api.f(
        "Component.aabb() -> Box",
        "World axis-aligned box (mm) of the posed mesh: a `Box` (`.min`, `.max`).",
        |c: &mut ComponentHandle| -> ScriptResult<Dynamic> {
            let (doc, i) = c.locked()?;
            doc.loaded_mesh_of(i).map_err(fail)?;
            match doc.world_aabb(i) {
                Some(b) => Ok(box_value(&b)),
                None => err("the component's mesh is empty"),
            }
        },
    );
    api.f("Component.reference(name: string) -> map", "A reference of the part in world coordinates: `#{type, point, normal}` for planes, `#{type, point, direction}` for axes, `#{type, point}` for points, `#{type: \"coordinate_system\", point, x, y, z, transform}` for coordinate systems (mm).", |c: &mut ComponentHandle, name: &str| -> ScriptResult<Map> {
        let (doc, i) = c.locked()?;
        let r = doc.world_reference(i, name).map_err(fail)?;
        Ok(reference_map(&r))
    });
    api.f("Component.coordinate_system(name: string) -> Transform", "A coordinate system of the part in world coordinates: the pose that maps the system's coordinates to the world (mm; `.array_data` gives SolidWorks' `CoordinateSystemFeatureData.Transform.ArrayData` times `Transform2`, in metres).", |c: &mut ComponentHandle, name: &str| -> ScriptResult<Transform> {
        let (doc, i) = c.locked()?;
        doc.coordinate_system(i, name).map_err(fail)
    });
    api.f(
        "Component.to_string() -> string",
        "`Component(name)`.",
        |c: &mut ComponentHandle| c.with(|_, c| format!("Component({})", c.name)),
    );

    api.section("Dimension", "A driving dimension `D1@<mate>` of a distance or angle mate. `value` is in document units (mm, degrees); `system_value` mirrors SolidWorks' `SystemValue` (metres, radians): `system_value = ang * PI / 180`. Setting either re-solves the mates before anything else reads the document.");
    api.get(
        "Dimension.name -> string",
        "The full name, e.g. `D1@角度1`.",
        |d: &mut DimensionHandle| d.name.clone(),
    );
    api.get(
        "Dimension.kind -> string",
        "`\"angle\"` or `\"length\"`.",
        |d: &mut DimensionHandle| -> ScriptResult<String> {
            let dim = d.doc.lock()?.dimension(&d.name).map_err(fail)?;
            Ok(if dim.kind == DimensionKind::Angle {
                "angle"
            } else {
                "length"
            }
            .into())
        },
    );
    api.get(
        "Dimension.value -> float",
        "The value in document units: mm or degrees.",
        |d: &mut DimensionHandle| -> ScriptResult<f64> {
            Ok(d.doc
                .lock()?
                .dimension(&d.name)
                .map_err(fail)?
                .document_value())
        },
    );
    api.set(
        "Dimension.value",
        |d: &mut DimensionHandle, v: Dynamic| -> ScriptResult<()> {
            let v = num(&v, "value")?;
            let mut doc = d.doc.lock()?;
            let kind = doc.dimension(&d.name).map_err(fail)?.kind;
            doc.set_dimension(&d.name, crate::document::Dimension::from_document(kind, v))
                .map_err(fail)
        },
    );
    api.get(
        "Dimension.system_value -> float",
        "The value in SI units (metres or radians), as SolidWorks' `SystemValue`.",
        |d: &mut DimensionHandle| -> ScriptResult<f64> {
            Ok(d.doc
                .lock()?
                .dimension(&d.name)
                .map_err(fail)?
                .system_value())
        },
    );
    api.set(
        "Dimension.system_value",
        |d: &mut DimensionHandle, v: Dynamic| -> ScriptResult<()> {
            let v = num(&v, "system_value")?;
            let mut doc = d.doc.lock()?;
            let kind = doc.dimension(&d.name).map_err(fail)?.kind;
            doc.set_dimension(&d.name, crate::document::Dimension::from_system(kind, v))
                .map_err(fail)
        },
    );
    api.f(
        "Dimension.to_string() -> string",
        "`D1@name = value unit`.",
        |d: &mut DimensionHandle| -> ScriptResult<String> {
            let dim = d.doc.lock()?.dimension(&d.name).map_err(fail)?;
            Ok(format!(
                "{} = {} {}",
                dim.name,
                dim.document_value(),
                if dim.kind == DimensionKind::Angle {
                    "deg"
                } else {
                    "mm"
                }
            ))
        },
    );

    api.section("Checks", "Assertions and output.");
    api.f("assert(condition: bool, message: string)", "Stops the script with `assertion failed: message` (and its line) when `condition` is false.", |c: bool, m: &str| -> ScriptResult<()> {
        if c { Ok(()) } else { err(format!("assertion failed: {m}")) }
    });
    api.f(
        "assert(condition: bool)",
        "Stops the script with `assertion failed` when `condition` is false.",
        |c: bool| -> ScriptResult<()> {
            if c {
                Ok(())
            } else {
                err("assertion failed")
            }
        },
    );
    api.f(
        "assert_near(a, b, tolerance)",
        "Stops the script unless |a − b| ≤ tolerance; the message shows both values.",
        |a: Dynamic, b: Dynamic, t: Dynamic| -> ScriptResult<()> {
            let (a, b, t) = (num(&a, "a")?, num(&b, "b")?, num(&t, "tolerance")?);
            if (a - b).abs() <= t {
                Ok(())
            } else {
                err(format!(
                    "assertion failed: {a} and {b} differ by {} > {t}",
                    (a - b).abs()
                ))
            }
        },
    );
}
