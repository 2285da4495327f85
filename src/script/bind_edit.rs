//! Bindings for editing a document as SolidWorks macros do: mates as objects,
//! suppression and visibility, custom properties, adding, renaming and replacing
//! components. The library does the work (`crate::document`'s edit calls); these
//! only convert values.

use super::api::Api;
use super::bind_document::{ComponentHandle, DocHandle};
use super::bind_math::to_transform;
use super::convert::{fail, point3, read_options, vec3};
use super::{Context, ScriptResult};
use crate::document::{coordinate_system, Document, PropertyOwner, Reference, RemoveMates};
use crate::math::Transform;
use crate::options::AddMate;
use rhai::{Array, Dynamic, Map};
use std::sync::Arc;

/// A mate of a document, by name.
#[derive(Clone)]
pub struct MateHandle {
    doc: DocHandle,
    name: String,
}

impl MateHandle {
    fn with<R>(&self, f: impl FnOnce(&Document, &crate::document::Mate) -> R) -> ScriptResult<R> {
        let doc = self.doc.lock()?;
        let m = doc.mate(&self.name).map_err(fail)?;
        Ok(f(&doc, m))
    }
}

/// A custom property value as the document keeps it: text (numbers and booleans in
/// their written form).
fn property_text(v: &Dynamic, key: &str) -> ScriptResult<String> {
    if let Some(s) = v.clone().try_cast::<rhai::ImmutableString>() {
        return Ok(s.to_string());
    }
    if v.is_int() || v.is_float() || v.is_bool() || v.is_char() {
        return Ok(v.to_string());
    }
    Err(fail(format!(
        "custom property `{key}`: a value is a string, number or bool, not {}",
        v.type_name()
    )))
}

fn properties_map(p: &indexmap::IndexMap<String, String>) -> Map {
    p.iter()
        .map(|(k, v)| (k.as_str().into(), Dynamic::from(v.clone())))
        .collect()
}

fn component_name(c: &ComponentHandle) -> ScriptResult<String> {
    c.with_component(|c| c.name.clone())
}

fn mate_handles(d: &DocHandle, names: Vec<String>) -> Array {
    names
        .into_iter()
        .map(|name| {
            Dynamic::from(MateHandle {
                doc: d.clone(),
                name,
            })
        })
        .collect()
}

/// The part's file as the project shows it (relative to the project folder).
fn part_file(d: &DocHandle, part: &str) -> ScriptResult<String> {
    let path = d.lock()?.part(part).map_err(fail)?.mesh_path.clone();
    Ok(d.context().project.display(&path))
}

/// A reference from its script map `#{type, point, normal | direction}` (mm), or a
/// coordinate system `#{type: "coordinate_system", point, x, y}` or `#{type:
/// "coordinate_system", transform}`.
fn reference_of(m: &Map) -> ScriptResult<Reference> {
    let get = |k: &str| {
        m.get(k)
            .cloned()
            .ok_or_else(|| fail(format!("a reference needs `{k}`")))
    };
    let kind = get("type")?
        .into_string()
        .map_err(|t| fail(format!("`type` must be a string, not {t}")))?;
    if kind == "coordinate_system" {
        if !m.contains_key("point") {
            if let Some(t) = m.get("transform") {
                let t = t
                    .clone()
                    .try_cast::<Transform>()
                    .ok_or_else(|| fail("`transform` must be a Transform"))?;
                return Ok(Reference::CoordinateSystem(t));
            }
        }
        let f = coordinate_system(
            vec3(&get("point")?, "point")?,
            vec3(&get("x")?, "x")?,
            vec3(&get("y")?, "y")?,
        )
        .map_err(|e| fail(format!("coordinate system: {e}")))?;
        return Ok(Reference::CoordinateSystem(f));
    }
    let point = point3(&get("point")?, "point")?;
    Ok(match kind.as_str() {
        "plane" => Reference::Plane {
            point,
            normal: vec3(&get("normal")?, "normal")?,
        },
        "axis" => Reference::Axis {
            point,
            direction: vec3(&get("direction")?, "direction")?,
        },
        "point" => Reference::Point(point),
        other => {
            return Err(fail(format!(
                "reference type `{other}`: plane, axis, point or coordinate_system"
            )))
        }
    })
}

pub(super) fn register(api: &mut Api, ctx: &Arc<Context>) {
    register_document_mates(api, ctx);
    register_mate(api);
    register_suppression(api);
    register_properties(api);
    register_components(api, ctx);
}

/// Mates: listing, adding and deleting them on a document.
fn register_document_mates(api: &mut Api, ctx: &Arc<Context>) {
    api.section("Mates", "Mates as objects (SolidWorks' `IMate2` features): list, add, delete, suppress, flip. Every change re-solves the mates; one they cannot satisfy is undone and refused. A mate is suppressed with its own flag or when a component it joins is suppressed.");
    api.type_::<MateHandle>("Mate");
    api.f(
        "Document.mates() -> array",
        "Every mate, in document order (`IFeature` of type `MateGroup` children).",
        |d: &mut DocHandle| -> ScriptResult<Array> {
            let names = d.lock()?.mates().iter().map(|m| m.name.clone()).collect();
            Ok(mate_handles(d, names))
        },
    );
    api.f(
        "Document.mate(name: string) -> Mate",
        "A mate by name; a missing name lists close matches.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<MateHandle> {
            let name = d.lock()?.mate(name).map_err(fail)?.name.clone();
            Ok(MateHandle {
                doc: d.clone(),
                name,
            })
        },
    );
    fn add_mate(
        d: &DocHandle,
        name: &str,
        kind: &str,
        a: &str,
        b: &str,
        o: &AddMate,
    ) -> ScriptResult<MateHandle> {
        let spec = o.spec(name, kind, a, b).map_err(fail)?;
        let mut doc = d.lock()?;
        doc.add_mate(&spec).map_err(fail)?;
        let name = doc
            .mates()
            .last()
            .map(|m| m.name.clone())
            .unwrap_or_default();
        Ok(MateHandle {
            doc: d.clone(),
            name,
        })
    }
    api.f(
        "Document.add_mate(name: string, type: string, a: string, b: string) -> Mate",
        "Adds a mate (SolidWorks' `AddMate5`) of `type` `coincident`, `concentric`, `parallel` or `perpendicular` between the entities `a` and `b` (`component/reference`: a plane, axis or point of the part, or `origin`, `front`, `top`, `right`, `x_axis`…), and solves it: the second component moves unless it is fixed.",
        |d: &mut DocHandle, name: &str, kind: &str, a: &str, b: &str| add_mate(d, name, kind, a, b, &AddMate::default()),
    );
    let c = ctx.clone();
    api.f(
        "Document.add_mate(name: string, type: string, a: string, b: string, options: map) -> Mate",
        "As above with the options of the table below (`value` of `distance` and `angle` mates, `aligned`, `about`).",
        move |d: &mut DocHandle, name: &str, kind: &str, a: &str, b: &str, o: Map| -> ScriptResult<MateHandle> {
            let o: AddMate = read_options(&o, &|w| c.print(w))?;
            add_mate(d, name, kind, a, b, &o)
        },
    );
    api.options::<AddMate>("The options of `add_mate` (Python: keywords of `Document.add_mate`):");
    api.f(
        "Document.delete_mate(name: string)",
        "Deletes a mate; nothing moves.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<()> {
            d.lock()?.delete_mate(name).map_err(fail).map(|_| ())
        },
    );
}

/// A mate object: its properties, flip, suppress, delete; a component's mates.
fn register_mate(api: &mut Api) {
    api.get(
        "Mate.name -> string",
        "The mate's name (its dimension, if any, is `D1@<name>`).",
        |m: &mut MateHandle| m.name.clone(),
    );
    api.get("Mate.type -> string", "`coincident`, `concentric`, `parallel`, `perpendicular`, `distance` or `angle` (`IMate2.Type`).", |m: &mut MateHandle| m.with(|_, m| m.kind.name().to_string()));
    api.get(
        "Mate.entities -> array",
        "The two entities, `component/reference` (`IMate2.MateEntity(i)`).",
        |m: &mut MateHandle| {
            m.with(|d, m| {
                m.entities
                    .iter()
                    .map(|e| {
                        Dynamic::from(format!(
                            "{}/{}",
                            d.components()[e.component].name,
                            e.reference
                        ))
                    })
                    .collect::<Array>()
            })
        },
    );
    api.get(
        "Mate.components -> array",
        "The names of the two components it joins.",
        |m: &mut MateHandle| {
            m.with(|d, m| {
                m.entities
                    .iter()
                    .map(|e| Dynamic::from(d.components()[e.component].name.clone()))
                    .collect::<Array>()
            })
        },
    );
    api.get(
        "Mate.value -> float",
        "The driving value in document units (mm for `distance`, degrees for `angle`), `()` for mates without one; set it through `doc.dimension(\"D1@<name>\")`.",
        |m: &mut MateHandle| {
            m.with(|_, m| match m.value {
                Some(v) if m.kind == crate::document::MateKind::Angle => Dynamic::from(v.to_degrees()),
                Some(v) => Dynamic::from(v),
                None => Dynamic::UNIT,
            })
        },
    );
    api.get(
        "Mate.aligned -> bool",
        "Whether the directions are aligned (`IMate2.Alignment`): as set, else the kind's default (coincident planes: anti-aligned), else as the poses are; `()` for mates of points. Setting it re-solves.",
        |m: &mut MateHandle| -> ScriptResult<Dynamic> {
            let a = m.doc.lock()?.mate_alignment(&m.name).map_err(fail)?;
            Ok(a.map_or(Dynamic::UNIT, Dynamic::from))
        },
    );
    api.set(
        "Mate.aligned",
        |m: &mut MateHandle, v: bool| -> ScriptResult<()> {
            m.doc
                .lock()?
                .set_mate_aligned(&m.name, Some(v))
                .map_err(fail)
        },
    );
    api.f(
        "Mate.flip()",
        "Flips aligned ↔ anti-aligned and re-solves (SolidWorks' flip mate alignment).",
        |m: &mut MateHandle| -> ScriptResult<()> { m.doc.lock()?.flip_mate(&m.name).map_err(fail) },
    );
    api.get(
        "Mate.suppressed -> bool",
        "Whether the mate itself is suppressed (`IFeature.IsSuppressed`); setting it re-solves.",
        |m: &mut MateHandle| m.with(|_, m| m.suppressed),
    );
    api.set(
        "Mate.suppressed",
        |m: &mut MateHandle, v: bool| -> ScriptResult<()> {
            m.doc.lock()?.set_mate_suppressed(&m.name, v).map_err(fail)
        },
    );
    api.get(
        "Mate.active -> bool",
        "Whether the mate is solved: neither it nor a component it joins is suppressed.",
        |m: &mut MateHandle| m.with(|d, m| d.mate_active(m)),
    );
    api.f(
        "Mate.delete()",
        "Deletes the mate (`doc.delete_mate(name)`).",
        |m: &mut MateHandle| -> ScriptResult<()> {
            m.doc.lock()?.delete_mate(&m.name).map_err(fail).map(|_| ())
        },
    );
    api.f(
        "Mate.to_string() -> string",
        "`Mate(name: type a b)`.",
        |m: &mut MateHandle| {
            m.with(|d, m| {
                let [a, b] = &m.entities;
                let e = |e: &crate::document::MateEntity| {
                    format!("{}/{}", d.components()[e.component].name, e.reference)
                };
                format!("Mate({}: {} {} {})", m.name, m.kind.name(), e(a), e(b))
            })
        },
    );
    api.f(
        "Component.mates() -> array",
        "The mates that join this component (`IComponent2.GetMates`), in document order.",
        |c: &mut ComponentHandle| -> ScriptResult<Array> {
            let names = {
                let (doc, i) = c.locked()?;
                doc.mates()
                    .iter()
                    .filter(|m| m.entities.iter().any(|e| e.component == i))
                    .map(|m| m.name.clone())
                    .collect()
            };
            Ok(mate_handles(&c.doc, names))
        },
    );
}

/// Suppression and visibility of components.
fn register_suppression(api: &mut Api) {
    api.section("Suppression and visibility", "A suppressed component (`IComponent2.SetSuppression2`) stays in the document but is not checked for interference, planned around, sequenced, weighed by `doc.mass_properties()`, bounded by `doc.aabb()` or exported, and its mates are inactive; asking to check or plan it is an error. A part only suppressed components use is not loaded when the document opens (its file may be missing): `c.suppressed = false` reads it first, and when it cannot be read the assignment fails naming the file, the document's line and the cause, and nothing changes; until then its world mesh, mass, box and export are refused. A hidden one (`IComponent2.Visible = false`) is checked like the others but left out of exports. Both are saved.");
    api.get(
        "Component.suppressed -> bool",
        "Whether the component is suppressed; setting it re-solves the mates.",
        |c: &mut ComponentHandle| -> ScriptResult<bool> { c.with_component(|c| c.is_suppressed()) },
    );
    api.set(
        "Component.suppressed",
        |c: &mut ComponentHandle, v: bool| -> ScriptResult<()> {
            let name = component_name(c)?;
            c.doc.lock()?.set_suppressed(&name, v).map_err(fail)
        },
    );
    api.get(
        "Component.visible -> bool",
        "Whether the component is shown (not hidden); `visible = false` hides it.",
        |c: &mut ComponentHandle| -> ScriptResult<bool> { c.with_component(|c| !c.hidden) },
    );
    api.set(
        "Component.visible",
        |c: &mut ComponentHandle, v: bool| -> ScriptResult<()> {
            let name = component_name(c)?;
            c.doc.lock()?.set_hidden(&name, !v).map_err(fail)
        },
    );
}

/// Custom properties of parts and components.
fn register_properties(api: &mut Api) {
    api.section("Custom properties", "Name → text properties of parts (SolidWorks' file properties: `Description`, `Price`, `Material`…) and of components (component-level properties), from the document's `properties:` and set by scripts; saved with the document. Numbers and booleans are kept as their text, as `ICustomPropertyManager` keeps them.");
    api.get(
        "Component.properties -> map",
        "The component's own properties.",
        |c: &mut ComponentHandle| -> ScriptResult<Map> {
            c.with_component(|c| properties_map(&c.properties))
        },
    );
    api.f("Component.property_names() -> array", "The names of the component's own properties in document order (a map's keys are sorted by name).", |c: &mut ComponentHandle| -> ScriptResult<Array> {
        c.with_component(|c| c.properties.keys().map(|k| Dynamic::from(k.clone())).collect())
    });
    api.f(
        "Component.property(name: string) -> string",
        "A property of the component, else of its part (how a BOM reads it), else `()`.",
        |c: &mut ComponentHandle, key: &str| -> ScriptResult<Dynamic> {
            let (doc, i) = c.locked()?;
            let comp = &doc.components()[i];
            let own = comp.properties.get(key).cloned();
            let v = match own {
                Some(v) => Some(v),
                None => doc
                    .part(&comp.part)
                    .map_err(fail)?
                    .properties
                    .get(key)
                    .cloned(),
            };
            Ok(v.map_or(Dynamic::UNIT, Dynamic::from))
        },
    );
    api.f(
        "Component.set_property(name: string, value)",
        "Sets a property of the component (a string, number or bool, kept as text).",
        |c: &mut ComponentHandle, key: &str, v: Dynamic| -> ScriptResult<()> {
            let name = component_name(c)?;
            let text = property_text(&v, key)?;
            c.doc
                .lock()?
                .set_property(PropertyOwner::Component(&name), key, &text)
                .map_err(fail)
        },
    );
    api.f(
        "Component.remove_property(name: string) -> bool",
        "Deletes a property of the component; whether it had one.",
        |c: &mut ComponentHandle, key: &str| -> ScriptResult<bool> {
            let name = component_name(c)?;
            Ok(c.doc
                .lock()?
                .remove_property(PropertyOwner::Component(&name), key)
                .map_err(fail)?
                .is_some())
        },
    );
    api.f(
        "Document.part_properties(part: string) -> map",
        "The properties of a part.",
        |d: &mut DocHandle, part: &str| -> ScriptResult<Map> {
            Ok(properties_map(
                d.lock()?
                    .properties(PropertyOwner::Part(part))
                    .map_err(fail)?,
            ))
        },
    );
    api.f(
        "Document.part_property_names(part: string) -> array",
        "The names of a part's properties in document order (a map's keys are sorted by name).",
        |d: &mut DocHandle, part: &str| -> ScriptResult<Array> {
            Ok(d.lock()?
                .properties(PropertyOwner::Part(part))
                .map_err(fail)?
                .keys()
                .map(|k| Dynamic::from(k.clone()))
                .collect())
        },
    );
    api.f(
        "Document.set_part_property(part: string, name: string, value)",
        "Sets a property of a part (a string, number or bool, kept as text).",
        |d: &mut DocHandle, part: &str, key: &str, v: Dynamic| -> ScriptResult<()> {
            let text = property_text(&v, key)?;
            d.lock()?
                .set_property(PropertyOwner::Part(part), key, &text)
                .map_err(fail)
        },
    );
    api.f(
        "Document.remove_part_property(part: string, name: string) -> bool",
        "Deletes a property of a part; whether it had one.",
        |d: &mut DocHandle, part: &str, key: &str| -> ScriptResult<bool> {
            Ok(d.lock()?
                .remove_property(PropertyOwner::Part(part), key)
                .map_err(fail)?
                .is_some())
        },
    );
    api.f("Document.part_coordinate_system(part: string, name: string) -> Transform", "A coordinate system of a part in the part frame (SolidWorks' `CoordinateSystemFeatureData.Transform` of a `CoordSys` feature; mm, `.array_data` in metres).", |d: &mut DocHandle, part: &str, name: &str| -> ScriptResult<Transform> {
        d.lock()?.part_coordinate_system(part, name).map_err(fail)
    });
    api.f("Document.part_file(part: string) -> string", "The part's geometry file (its mesh or STEP file) relative to the project folder (`IModelDoc2.GetPathName` of the part).", |d: &mut DocHandle, part: &str| part_file(d, part));
    api.get(
        "Component.part_file -> string",
        "The component's part file relative to the project folder (`IComponent2.GetPathName`).",
        |c: &mut ComponentHandle| -> ScriptResult<String> {
            let part = c.with_component(|c| c.part.clone())?;
            part_file(&c.doc, &part)
        },
    );
}

/// Adding, renaming and re-pointing components.
fn register_components(api: &mut Api, ctx: &Arc<Context>) {
    api.section("Adding and replacing components", "Components added, renamed and re-pointed from a script (`IAssemblyDoc.AddComponent5`, `IComponent2.Name2`, `ReplaceComponents2`); saved with the document.");
    fn add(
        d: &DocHandle,
        name: Option<&str>,
        part: &str,
        pose: &Dynamic,
    ) -> ScriptResult<ComponentHandle> {
        let t = if pose.is_unit() {
            Transform::IDENTITY
        } else {
            to_transform(pose, "pose")?
        };
        let mut doc = d.lock()?;
        let part = doc.part(part).map_err(fail)?.name.clone();
        let name = name.map_or_else(|| doc.next_instance_name(&part), str::to_string);
        let index = doc.add_component(&name, &part, t).map_err(fail)?;
        Ok(ComponentHandle::new(d, &doc, index))
    }
    api.f("Document.add_component(part: string, pose) -> Component", "Adds a component of `part` at `pose` (a Transform, 4×4 matrix or `[x, y, z, a, b, c]`, mm and degrees), named `part-N` with the first free N.", |d: &mut DocHandle, part: &str, pose: Dynamic| add(d, None, part, &pose));
    api.f(
        "Document.add_component(name: string, part: string, pose) -> Component",
        "Adds a component named `name`.",
        |d: &mut DocHandle, name: &str, part: &str, pose: Dynamic| add(d, Some(name), part, &pose),
    );
    fn remove(d: &DocHandle, name: &str, mates: RemoveMates) -> ScriptResult<Array> {
        let deleted = d.lock()?.remove_component(name, mates).map_err(fail)?;
        Ok(deleted.into_iter().map(|m| Dynamic::from(m.name)).collect())
    }
    api.f(
        "Document.remove_component(name: string)",
        "Removes a component (SolidWorks' `DeleteSelection2` on it). Refused while it has mates (the error names them) and for a robot's link. Handles of the other components stay valid; a handle of the removed one is an error when used.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<()> {
            remove(d, name, RemoveMates::Refuse).map(|_| ())
        },
    );
    api.f(
        "Document.remove_component(name: string, with_mates: bool) -> array",
        "As above; `with_mates: true` deletes its mates with it (as SolidWorks does) and returns their names, unless an equation uses one of their dimensions.",
        |d: &mut DocHandle, name: &str, with_mates: bool| -> ScriptResult<Array> {
            let mates = if with_mates { RemoveMates::Delete } else { RemoveMates::Refuse };
            remove(d, name, mates)
        },
    );
    let c = ctx.clone();
    api.f("Document.add_part(name: string, file: string) -> string", "Adds a part whose geometry is `file` (relative to the document's folder, inside the project): a mesh (STL, OBJ, PLY or glTF), or a STEP file (`.step`/`.stp`), which becomes a `step:` part tessellated with the default deflection and kept in the project's tessellation store (needs a build with `--features step`; without it the error says how to add it). Returns its name. Its file becomes a dependency of the run.", move |d: &mut DocHandle, name: &str, file: &str| -> ScriptResult<String> {
        let mut doc = d.lock()?;
        let mut cache = c.caches.meshes.lock().map_err(|_| fail("mesh cache poisoned"))?;
        let name = doc.add_part(name, file, &c.project, &mut cache).map_err(fail)?;
        let part = doc.part(&name).map_err(fail)?;
        c.record_read(&part.mesh_path);
        Ok(name)
    });
    api.f("Document.set_reference(part: string, name: string, reference: map)", "Adds or replaces a reference of a part, in the part frame (mm): `#{type: \"plane\", point, normal}`, `#{type: \"axis\", point, direction}`, `#{type: \"point\", point}`, `#{type: \"coordinate_system\", point, x, y}` (Z = X × Y) or `#{type: \"coordinate_system\", transform}` (what `Component.reference` gives, in world coordinates). Mates using it follow and are re-solved.", |d: &mut DocHandle, part: &str, name: &str, r: Map| -> ScriptResult<()> {
        let r = reference_of(&r)?;
        d.lock()?.set_reference(part, name, r).map_err(fail)
    });
    api.set(
        "Component.name",
        |c: &mut ComponentHandle, v: &str| -> ScriptResult<()> {
            let name = component_name(c)?;
            c.doc.lock()?.rename_component(&name, v).map_err(fail)
        },
    );
    api.set(
        "Component.part",
        |c: &mut ComponentHandle, v: &str| -> ScriptResult<()> {
            let name = component_name(c)?;
            c.doc.lock()?.set_component_part(&name, v).map_err(fail)
        },
    );
}
