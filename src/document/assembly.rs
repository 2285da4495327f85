//! Sub-assemblies (SolidWorks' `IComponent2` of an assembly): groups of components
//! in this document, nested to any depth, named by full names as SolidWorks' `Name2`
//! writes them (`Cart-1`, `Cart-1/Axle-1`); a component inside one is named
//! `Cart-1/Axle-1/Wheel-2`.
//!
//! In the file (`assemblies:`), a sub-assembly's `transform` and the `transform` of a
//! component inside one are relative to its parent sub-assembly (the assembly frame
//! at the top), so moving a sub-assembly in the file moves what it holds. In the
//! model every pose is composed to the assembly (world) frame, as `Transform2` is: a
//! sub-assembly's children are at `local * parent` (apply the local pose, then the
//! parent's).

use super::{check_pose, new_name, nfc_name, Document, DocumentError};
use crate::math::Transform;

/// A sub-assembly: a named group in this document.
#[derive(Debug, Clone, PartialEq)]
pub struct SubAssembly {
    /// Full name, `Cart-1/Axle-1`.
    pub name: String,
    /// Pose: sub-assembly frame → assembly (world) frame, mm.
    pub transform: Transform,
    /// The document whose content it holds, when it is another file (see
    /// [`super::subdoc`]); `None` for a group of this document.
    pub file: Option<super::SubDocument>,
    /// Suppressed: everything inside is suppressed (saved in the file holding the
    /// sub-assembly's entry).
    pub suppressed: bool,
}

/// The parent's full name of a full name (`Cart-1/Axle-1` of `Cart-1/Axle-1/Wheel-2`),
/// `None` at the top.
pub fn parent_name(full_name: &str) -> Option<&str> {
    full_name.rsplit_once('/').map(|(p, _)| p)
}

/// Whether `full_name` is well formed: no empty level, no surrounding spaces at a
/// level.
pub(crate) fn check_levels(full_name: &str) -> Result<(), super::EntryError> {
    if full_name.split('/').any(|s| s.is_empty() || s.trim() != s) {
        return Err(super::EntryError::FullName(full_name.to_string()));
    }
    Ok(())
}

impl Document {
    /// The sub-assemblies, parents before children, in file order.
    pub fn sub_assemblies(&self) -> &[SubAssembly] {
        &self.assemblies
    }

    /// A sub-assembly by full name.
    pub fn sub_assembly(&self, name: &str) -> Result<&SubAssembly, DocumentError> {
        let name = nfc_name(name);
        self.assemblies
            .iter()
            .find(|a| a.name == *name)
            .ok_or_else(|| {
                DocumentError::not_found(
                    "sub-assembly",
                    &name,
                    self.assemblies.iter().map(|a| a.name.as_str()),
                )
            })
    }

    /// The world pose of sub-assembly `name`, or the assembly frame (identity) for
    /// `None`.
    fn frame_of(&self, parent: Option<&str>) -> Transform {
        parent
            .and_then(|p| self.assemblies.iter().find(|a| a.name == p))
            .map_or(Transform::IDENTITY, |a| a.transform)
    }

    /// The parent sub-assembly of a component or sub-assembly (`IComponent2.GetParent`),
    /// `None` at the top level.
    pub fn parent_of(&self, name: &str) -> Result<Option<String>, DocumentError> {
        let name = nfc_name(name);
        if !self.by_name.contains_key(&*name) && self.sub_assembly(&name).is_err() {
            let names = self
                .components
                .iter()
                .map(|c| c.name.as_str())
                .chain(self.assemblies.iter().map(|a| a.name.as_str()));
            return Err(DocumentError::not_found(
                "component or sub-assembly",
                &name,
                names,
            ));
        }
        Ok(parent_name(&name).map(str::to_string))
    }

    /// The direct children of sub-assembly `name` (`IComponent2.GetChildren`), or of
    /// the assembly for `None`: sub-assemblies first, then components, each in file
    /// order, by full name.
    pub fn children(&self, name: Option<&str>) -> Result<Vec<String>, DocumentError> {
        let name = match name {
            Some(n) => Some(self.sub_assembly(n)?.name.clone()),
            None => None,
        };
        let here = |n: &str| parent_name(n) == name.as_deref();
        Ok(self
            .assemblies
            .iter()
            .map(|a| &a.name)
            .chain(self.components.iter().map(|c| &c.name))
            .filter(|n| here(n))
            .cloned()
            .collect())
    }

    /// A component's or sub-assembly's pose relative to its parent sub-assembly (the
    /// assembly frame at the top level), mm.
    pub fn local_transform(&self, name: &str) -> Result<Transform, DocumentError> {
        let name = nfc_name(name);
        let world = match self.by_name.get(&*name) {
            Some(&i) => self.components[i].transform,
            None => self.sub_assembly(&name)?.transform,
        };
        Ok(world * self.frame_of(parent_name(&name)).inverse())
    }

    /// Moves sub-assembly `name` to `t` (its frame → world, mm), and everything in it
    /// with it, rigidly (the robots inside too: their bases move). Refused when a
    /// component inside is fixed (unless it is fixed in a sub-document moved with it:
    /// fixed in that document's frame) or the link of a robot outside it.
    /// Mates are re-solved at the next rebuild, as for a component's move.
    pub fn set_sub_assembly_transform(
        &mut self,
        name: &str,
        t: Transform,
    ) -> Result<(), DocumentError> {
        let name = self.sub_assembly(name)?.name.clone();
        check_pose(&t, format_args!("the pose for sub-assembly `{name}`"))?;
        let prefix = format!("{name}/");
        let inside = |n: &str| n.starts_with(&prefix);
        for (i, c) in self.components.iter().enumerate() {
            if inside(&c.name) {
                // a component fixed in a sub-document is fixed in that document's
                // frame: it moves with it
                let moves_with_its_file = self
                    .owning_sub_document(&c.name)
                    .is_some_and(|a| a.name == name || a.name.starts_with(&prefix));
                if c.fixed && !moves_with_its_file {
                    return Err(DocumentError::FixedComponent(c.name.clone().into()));
                }
                // a robot inside moves with it (its base in the sub-assembly's frame)
                if let Some(robot) = self.driving_robot(i).filter(|r| !inside(r)) {
                    return Err(DocumentError::RobotLink {
                        component: c.name.clone().into(),
                        robot: robot.into(),
                    });
                }
            }
        }
        let old = self.sub_assembly(&name)?.transform;
        let motion = old.inverse() * t;
        for a in &mut self.assemblies {
            if a.name == name {
                a.transform = t;
            } else if inside(&a.name) {
                a.transform = a.transform * motion;
            }
        }
        for c in &mut self.components {
            if inside(&c.name) {
                c.transform = c.transform * motion;
            }
        }
        self.move_robots_inside(&prefix, motion);
        self.revision += 1;
        Ok(())
    }

    /// Adds an empty sub-assembly `name` (a full name whose parent exists) at `t`
    /// (world, mm).
    pub fn add_sub_assembly(&mut self, name: &str, t: Transform) -> Result<(), DocumentError> {
        let name = new_name(name, "sub-assembly name")?;
        check_levels(&name)?;
        if self.by_name.contains_key(&name) || self.assemblies.iter().any(|a| a.name == name) {
            return Err(DocumentError::NameTaken {
                what: "component or sub-assembly",
                name,
            });
        }
        self.check_parent(&name)?;
        check_pose(&t, format_args!("the pose for sub-assembly `{name}`"))?;
        self.assemblies.push(SubAssembly {
            name,
            transform: t,
            file: None,
            suppressed: false,
        });
        self.revision += 1;
        Ok(())
    }

    /// Suppresses or unsuppresses sub-assembly `name` and so everything it holds, at
    /// every level (SolidWorks' `SetSuppression2` on a sub-assembly component), then
    /// re-solves the mates; on failure nothing changes. A component's own
    /// suppression is kept: unsuppressing the sub-assembly leaves it suppressed.
    /// The parts of the components it unsuppresses are read if they were not loaded
    /// ([`super::Part::is_loaded`]; an unreadable one is
    /// [`DocumentError::PartUnreadable`]).
    pub fn set_sub_assembly_suppressed(
        &mut self,
        name: &str,
        suppressed: bool,
    ) -> Result<(), DocumentError> {
        let name = self.sub_assembly(name)?.name.clone();
        let before = self.clone();
        for a in &mut self.assemblies {
            if a.name == name {
                a.suppressed = suppressed;
            }
        }
        self.apply_assembly_suppression();
        // the parts of the components it unsuppresses, read if they were not
        let unsuppressed: Vec<usize> = (0..self.components.len())
            .filter(|&i| !self.components[i].is_suppressed())
            .collect();
        if let Err(e) = self
            .load_parts_of(&unsuppressed)
            .and_then(|()| self.rebuild())
        {
            *self = before;
            return Err(e);
        }
        Ok(())
    }

    /// Whether sub-assembly `name` is suppressed, by its own flag or a suppressed
    /// sub-assembly holding it.
    pub fn sub_assembly_suppressed(&self, name: &str) -> Result<bool, DocumentError> {
        let name = self.sub_assembly(name)?.name.clone();
        Ok(self
            .assemblies
            .iter()
            .any(|a| a.suppressed && (a.name == name || name.starts_with(&format!("{}/", a.name)))))
    }

    /// Gives every component its `held_suppressed` flag from the suppressed
    /// sub-assemblies holding it.
    pub(crate) fn apply_assembly_suppression(&mut self) {
        let suppressed: std::collections::HashSet<&str> = self
            .assemblies
            .iter()
            .filter(|a| a.suppressed)
            .map(|a| a.name.as_str())
            .collect();
        for c in &mut self.components {
            c.held_suppressed = !suppressed.is_empty()
                && c.name
                    .match_indices('/')
                    .any(|(i, _)| suppressed.contains(&c.name[..i]));
        }
    }

    /// Refuses a full name whose parent is no sub-assembly.
    pub(crate) fn check_parent(&self, name: &str) -> Result<(), DocumentError> {
        check_levels(name)?;
        match parent_name(name) {
            Some(p) if !self.assemblies.iter().any(|a| a.name == p) => {
                Err(DocumentError::NoParentAssembly {
                    name: name.to_string(),
                    parent: p.to_string(),
                    hint: crate::diagnostics::suggestion(
                        p,
                        self.assemblies.iter().map(|a| a.name.as_str()),
                    ),
                })
            }
            _ => Ok(()),
        }
    }
}

/// The sub-assemblies of a file, their poses composed to the world frame: names well
/// formed and unique, each parent listed before its children. `at(key, message)`
/// locates an error at a scan key (`assemblies/3/name`).
pub(super) fn load(
    file: &super::file::DocumentFile,
    at: impl Fn(&str, String) -> DocumentError,
) -> Result<Vec<SubAssembly>, DocumentError> {
    let mut out: Vec<SubAssembly> = Vec::with_capacity(file.assemblies.len());
    // by name: a file of many sub-assemblies is read in linear time
    let mut index: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (i, a) in file.assemblies.iter().enumerate() {
        let name_key = format!("assemblies/{i}/name");
        check_levels(&a.name).map_err(|e| at(&name_key, format!("sub-assembly {e}")))?;
        if index.contains_key(a.name.as_str()) {
            return Err(at(
                &name_key,
                format!("duplicate sub-assembly name `{}`", a.name),
            ));
        }
        let parent = match parent_name(&a.name) {
            None => Transform::IDENTITY,
            Some(p) => match index.get(p) {
                Some(&k) => out[k].transform,
                None => {
                    return Err(at(
                        &name_key,
                        format!(
                            "sub-assembly `{}`: its parent `{p}` must be a sub-assembly listed before it",
                            a.name
                        ),
                    ))
                }
            },
        };
        let local = match &a.transform {
            None => Transform::IDENTITY,
            Some(m) => {
                let key = format!("assemblies/{i}/transform");
                if m.iter()
                    .flatten()
                    .any(|v| !v.is_finite() || v.abs() > super::MAX_ABS_VALUE)
                {
                    return Err(at(&key, format!("sub-assembly `{}`: pose entries must be finite and at most 1e9 in magnitude", a.name)));
                }
                Transform::from_matrix(m)
                    .map_err(|e| at(&key, format!("sub-assembly `{}`: {e}", a.name)))?
            }
        };
        if let Some(p) = parent_name(&a.name) {
            if file.assemblies[index[p]].file.is_some() {
                return Err(at(
                    &name_key,
                    format!(
                        "sub-assembly `{}`: `{p}` is another document; what it holds is written in that file",
                        a.name
                    ),
                ));
            }
        }
        index.insert(&a.name, out.len());
        out.push(SubAssembly {
            name: a.name.clone(),
            transform: local * parent,
            file: None,
            suppressed: a.suppressed,
        });
    }
    Ok(out)
}

/// The sub-assemblies' world poses by full name.
pub(super) fn frames(assemblies: &[SubAssembly]) -> std::collections::HashMap<&str, Transform> {
    assemblies
        .iter()
        .map(|a| (a.name.as_str(), a.transform))
        .collect()
}

/// The world pose of the parent of `name` among `frames` (identity at the top),
/// `None` when the parent is no sub-assembly.
pub(super) fn parent_frame(
    frames: &std::collections::HashMap<&str, Transform>,
    name: &str,
) -> Option<Transform> {
    match parent_name(name) {
        None => Some(Transform::IDENTITY),
        Some(p) => frames.get(p).copied(),
    }
}
