//! Bindings for sub-assemblies (SolidWorks' `IComponent2.GetChildren`, `GetParent`,
//! full names `Cart-1/Axle-1/Wheel-2`). The library keeps the tree
//! (`crate::document::assembly`); these only convert names and poses.

use super::api::Api;
use super::bind_document::{ComponentHandle, DocHandle};
use super::bind_math::to_transform;
use super::convert::fail;
use super::ScriptResult;
use crate::math::Transform;
use rhai::{Array, Dynamic};

fn names(v: Vec<String>) -> Array {
    v.into_iter().map(Dynamic::from).collect()
}

pub(super) fn register(api: &mut Api) {
    api.section("Sub-assemblies", "Groups of components in the document, nested to any depth (SolidWorks' sub-assembly components). Names are full names as `IComponent2.Name2` gives them: `Cart-1`, `Cart-1/Axle-1`, and a component inside is `Cart-1/Axle-1/Wheel-2` (`doc.component(full_name)` finds it). Poses are in the assembly (world) frame, composed through the levels; `local_transform` is relative to the parent. In the file (`assemblies:`) a sub-assembly's and its components' `transform` are relative to the parent.");
    api.f(
        "Document.sub_assemblies() -> array",
        "Every sub-assembly's full name, parents before children.",
        |d: &mut DocHandle| -> ScriptResult<Array> {
            Ok(names(
                d.lock()?
                    .sub_assemblies()
                    .iter()
                    .map(|a| a.name.clone())
                    .collect(),
            ))
        },
    );
    api.f(
        "Document.is_sub_assembly(name: string) -> bool",
        "Whether `name` is a sub-assembly's full name.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<bool> {
            Ok(d.lock()?.sub_assembly(name).is_ok())
        },
    );
    api.f(
        "Document.children() -> array",
        "The top level's children: sub-assemblies, then components, by full name (`IAssemblyDoc.GetComponents(True)`).",
        |d: &mut DocHandle| -> ScriptResult<Array> {
            Ok(names(d.lock()?.children(None).map_err(fail)?))
        },
    );
    api.f(
        "Document.children(name: string) -> array",
        "A sub-assembly's direct children by full name (`IComponent2.GetChildren`).",
        |d: &mut DocHandle, name: &str| -> ScriptResult<Array> {
            Ok(names(d.lock()?.children(Some(name)).map_err(fail)?))
        },
    );
    api.f(
        "Document.parent(name: string) -> string",
        "The parent sub-assembly of a component or sub-assembly (`IComponent2.GetParent`); `\"\"` at the top level.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<String> {
            Ok(d.lock()?.parent_of(name).map_err(fail)?.unwrap_or_default())
        },
    );
    api.get(
        "Component.parent -> string",
        "The parent sub-assembly's full name, `\"\"` at the top level.",
        |c: &mut ComponentHandle| -> ScriptResult<String> {
            c.with_component(|c| {
                crate::document::assembly::parent_name(&c.name)
                    .unwrap_or_default()
                    .to_string()
            })
        },
    );
    api.get(
        "Component.local_transform -> Transform",
        "The pose relative to the parent sub-assembly (the assembly at the top level), mm.",
        |c: &mut ComponentHandle| -> ScriptResult<Transform> {
            let (doc, i) = c.locked()?;
            let name = doc.components()[i].name.clone();
            doc.local_transform(&name).map_err(fail)
        },
    );
    api.f(
        "Document.sub_assembly_transform(name: string) -> Transform",
        "A sub-assembly's pose in the assembly frame (its `Transform2`), mm.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<Transform> {
            Ok(d.lock()?.sub_assembly(name).map_err(fail)?.transform)
        },
    );
    api.f(
        "Document.set_sub_assembly_transform(name: string, pose)",
        "Moves a sub-assembly, and everything in it rigidly, to `pose` (a Transform, 4×4 matrix or `[x, y, z, a, b, c]`, mm and degrees; assembly frame). Refused when a component inside is fixed.",
        |d: &mut DocHandle, name: &str, pose: Dynamic| -> ScriptResult<()> {
            let t = to_transform(&pose, "pose")?;
            d.lock()?.set_sub_assembly_transform(name, t).map_err(fail)
        },
    );
    api.f(
        "Document.add_sub_assembly(name: string, pose)",
        "Adds an empty sub-assembly `name` (a full name whose parent exists) at `pose` (assembly frame); then `add_component(\"Sub-1/Part-1\", part, pose)` fills it.",
        |d: &mut DocHandle, name: &str, pose: Dynamic| -> ScriptResult<()> {
            let t = if pose.is_unit() {
                Transform::IDENTITY
            } else {
                to_transform(&pose, "pose")?
            };
            d.lock()?.add_sub_assembly(name, t).map_err(fail)
        },
    );
    api.f(
        "Document.sub_assembly_file(name: string) -> string",
        "The document file a sub-assembly holds (SolidWorks' `IComponent2.GetPathName` of a sub-assembly), as written in its `file:` key (relative to the document holding the entry); `\"\"` for a group of this document. Components, sub-assemblies and mates loaded from it are named inside it (`Cart-1/Wheel-2`) and saved back to that file, which a save rewrites only when a script changed what it holds.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<String> {
            Ok(d
                .lock()?
                .sub_assembly(name)
                .map_err(fail)?
                .file
                .as_ref()
                .map(|f| f.file.clone())
                .unwrap_or_default())
        },
    );
    api.f(
        "Document.sub_assembly_suppressed(name: string) -> bool",
        "Whether a sub-assembly is suppressed, itself or by a suppressed sub-assembly holding it (`IComponent2.IsSuppressed`).",
        |d: &mut DocHandle, name: &str| -> ScriptResult<bool> {
            d.lock()?.sub_assembly_suppressed(name).map_err(fail)
        },
    );
    api.f(
        "Document.set_sub_assembly_suppressed(name: string, suppressed: bool)",
        "Suppresses (or unsuppresses) a sub-assembly and so everything it holds at every level (`IComponent2.SetSuppression2` on a sub-assembly), then re-solves; saved. A component suppressed on its own stays suppressed when its sub-assembly is unsuppressed.",
        |d: &mut DocHandle, name: &str, suppressed: bool| -> ScriptResult<()> {
            d.lock()?
                .set_sub_assembly_suppressed(name, suppressed)
                .map_err(fail)
        },
    );
}
