//! Part features that need the collision layer: cutting a component's part into
//! cells (seed 000's finite subdivision), validated before it is stored, and reading a
//! stored cut back as cells through the [`SceneCache`].

use super::{SceneCache, WorkspaceError};
use crate::collision::{CutCells, CutSpec};
use crate::document::{Document, DocumentError, Feature};
use std::sync::Arc;

/// The name under which [`split_part`] stores a part's cut.
pub const CUT_CELLS_FEATURE: &str = "CutCells";

/// Cuts the part of component `component` (an index of `doc`) by `spec` and stores
/// the feature [`CUT_CELLS_FEATURE`] in the part's tree, replacing an earlier cut.
/// The cells are derived first (and kept in `cache`), so a spec that cannot be cut
/// (too many cells, a bad size) is refused with nothing stored. Returns the part's
/// name. Cells are in the part frame (mm).
///
/// # Errors
/// A spec the collision layer refuses, or one the document refuses to store.
pub fn split_part(
    doc: &mut Document,
    cache: &mut SceneCache,
    component: usize,
    spec: CutSpec,
) -> Result<String, WorkspaceError> {
    let part = doc.components()[component].part.clone();
    let mesh = doc.loaded_mesh_of(component)?.clone();
    cache.cells(&mesh, &spec)?;
    doc.set_feature(
        &part,
        Feature::CutCells {
            name: CUT_CELLS_FEATURE.to_string(),
            spec,
        },
    )?;
    Ok(part)
}

/// The cells of feature `feature` of part `part` (part frame, mm), derived once per
/// mesh and spec through `cache`.
///
/// # Errors
/// An unknown part, a part without that feature (it may have been replaced since),
/// or a cut the collision layer refuses.
pub fn feature_cells(
    doc: &Document,
    cache: &mut SceneCache,
    part: &str,
    feature: &str,
) -> Result<Arc<CutCells>, WorkspaceError> {
    let p = doc.part(part)?;
    let spec = p
        .features
        .iter()
        .find_map(|f| match f {
            Feature::CutCells { name, spec } if name == feature => Some(spec),
            _ => None,
        })
        .ok_or_else(|| DocumentError::NotFound {
            what: "feature",
            name: feature.into(),
            hint: format!(
                "part `{part}` has {}",
                crate::diagnostics::suggestion(feature, p.features.iter().map(|f| f.name()))
            ),
        })?;
    if !p.is_loaded() {
        let user = doc.components().iter().find(|c| c.part == p.name);
        return Err(DocumentError::NotLoaded {
            component: user.map_or_else(Default::default, |c| c.name.clone().into()),
            part: p.name.clone().into(),
        }
        .into());
    }
    Ok(cache.cells(&p.mesh, spec)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cut is stored only when it can be derived; the stored cut reads back as the
    /// same cells, and a feature that is not there is a typed `NotFound`.
    #[test]
    fn split_parts_store_derivable_cuts_only() {
        let mut doc = Document::open(std::path::Path::new("models/cell.yaml")).unwrap();
        let mut cache = SceneCache::new();
        let i = doc.component_index("plate_a").unwrap();
        let features_before = doc
            .part(&doc.components()[i].part.clone())
            .unwrap()
            .features
            .len();
        // Far too many cells: refused, nothing stored.
        assert!(split_part(&mut doc, &mut cache, i, CutSpec::Size(1e-3)).is_err());
        let part = doc.components()[i].part.clone();
        assert_eq!(doc.part(&part).unwrap().features.len(), features_before);
        let stored = split_part(&mut doc, &mut cache, i, CutSpec::Size(10.0)).unwrap();
        assert_eq!(stored, part);
        let cells = feature_cells(&doc, &mut cache, &part, CUT_CELLS_FEATURE).unwrap();
        assert!(!cells.cells.is_empty());
        let direct = cache.cells(doc.mesh_of(i), &CutSpec::Size(10.0)).unwrap();
        assert_eq!(cells.cells.len(), direct.cells.len());
        assert!(matches!(
            feature_cells(&doc, &mut cache, &part, "NoSuchCut"),
            Err(WorkspaceError::Document(DocumentError::NotFound {
                what: "feature",
                ..
            }))
        ));
    }
}
