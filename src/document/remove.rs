//! Removing a component from a document (SolidWorks' `DeleteSelection2` on a
//! component), with its mates refused or removed along with it.

use super::{dimension, equations, AabbCache, Document, DocumentError, Mate};

/// What [`Document::remove_component`] does with the mates of the component.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RemoveMates {
    /// Refuse to remove a component that has mates (the error names them).
    Refuse,
    /// Delete its mates with it (as SolidWorks does), unless an equation uses or sets
    /// one of their dimensions.
    Delete,
}

impl Document {
    /// Removes component `name`; its mates (those with an entity or `about` axis on
    /// it) are refused or deleted with it as `mates` says. Returns the deleted mates.
    ///
    /// Refused, with nothing changed, for a robot's link component (remove the robot
    /// instead) and, with [`RemoveMates::Refuse`], for a component with mates. The
    /// indices of the later components shift down by one; [`removals`](Self::removals)
    /// records it for holders of indices.
    pub fn remove_component(
        &mut self,
        name: &str,
        mates: RemoveMates,
    ) -> Result<Vec<Mate>, DocumentError> {
        let i = self.component_index(name)?;
        let name = self.components[i].name.clone();
        if let Some(robot) = self.driving_robot(i) {
            return Err(DocumentError::RobotLinkRemoval {
                component: name.into(),
                robot: robot.into(),
            });
        }
        let touches = |m: &Mate| {
            m.entities.iter().any(|e| e.component == i)
                || m.about.as_ref().is_some_and(|e| e.component == i)
        };
        let own: Vec<&Mate> = self.mates.iter().filter(|m| touches(m)).collect();
        if !own.is_empty() && mates == RemoveMates::Refuse {
            return Err(DocumentError::HasMates {
                component: name.into(),
                mates: own.iter().map(|m| m.name.clone()).collect(),
            });
        }
        for m in own.iter().filter(|m| m.kind.has_dimension()) {
            let d = dimension::full_name(&m.name);
            if let Some(&e) = self.equations_using(&d).first() {
                return Err(DocumentError::DimensionInUse(Box::new(
                    super::DimensionInUse {
                        component: Some(name),
                        mate: m.name.clone(),
                        dimension: d,
                        index: e,
                        equation: equations::shown(&self.equations[e].text()),
                    },
                )));
            }
        }
        let before = self.clone();
        let (deleted, kept): (Vec<Mate>, Vec<Mate>) = std::mem::take(&mut self.mates)
            .into_iter()
            .partition(touches);
        self.mates = kept;
        let shift = |c: &mut usize| {
            if *c > i {
                *c -= 1;
            }
        };
        for m in &mut self.mates {
            m.entities.iter_mut().for_each(|e| shift(&mut e.component));
            if let Some(e) = &mut m.about {
                shift(&mut e.component);
            }
        }
        self.shift_robot_links(i);
        let removed = self.components.remove(i);
        self.generated.remove(&removed.name);
        self.numbering.remove(&removed.name);
        self.by_name = self
            .components
            .iter()
            .enumerate()
            .map(|(k, c)| (c.name.clone(), k))
            .collect();
        // the boxes are cached by index
        self.aabb_cache = AabbCache::default();
        self.removed.push(i);
        if let Err(e) = self.rebuild() {
            *self = before;
            return Err(e);
        }
        Ok(deleted)
    }

    /// The component indices removed from this document so far, in order: an index
    /// taken when `removals().len()` was `n` is mapped to today's by
    /// [`index_since`](Self::index_since).
    pub fn removals(&self) -> &[usize] {
        &self.removed
    }

    /// Today's index of the component that had `index` when `removals().len()` was
    /// `since`; `None` when that component was removed since.
    pub fn index_since(&self, index: usize, since: usize) -> Option<usize> {
        let mut at = index;
        for &r in self.removed.get(since..).unwrap_or(&[]) {
            if at == r {
                return None;
            }
            if at > r {
                at -= 1;
            }
        }
        (at < self.components.len()).then_some(at)
    }
}
