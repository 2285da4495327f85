//! Re-validation of a planned sequence after the document changed (seed 003's tasks
//! kept, the geometry edited): which steps still hold and which broke, and why.
//! Units: millimetres, assembly frame.

use super::fit::{FitPairCheck, FitPairValidator};
use super::options::{Sequence, SequenceError};
use super::paths::FitValidator;
use crate::collision::SweepMethod;
use crate::document::Document;
use crate::math::format::length as fmt_mm;
use crate::planning::{MeshValidator, MeshValidatorOptions};
use crate::workspace::{GivenValue, Scene, SceneCache, WorkspaceError};

/// A step of a sequence that no longer holds in the edited document.
#[derive(Debug, Clone, PartialEq)]
pub struct BrokenStep {
    /// The task's index in the sequence.
    pub index: usize,
    /// The component the task inserts.
    pub part: String,
    /// Why, for people: a component gone, the part moved, or the insertion path now
    /// hitting a part assembled before it (named).
    pub reason: String,
}

/// Re-checks every task of `sequence` against `doc` as it is now: the component and
/// those assembled before it still exist, the part's assembled pose is where the task
/// ends (within 1 µm / 1 µrad), and the insertion path is free (continuous check,
/// `tolerance` mm; a component the task records a fit with, its allowance) against
/// exactly the components assembled before it at their current poses. Returns the broken steps, in order (empty: the sequence still holds).
///
/// # Errors
/// The scene cannot be built (unusable meshes); a bad tolerance.
///
/// # Examples
/// ```
/// use fitup::document::Document;
/// use fitup::math::{Transform, Vec3};
/// use fitup::sequence::{plan_sequence, revalidate, SequenceOptions};
/// use fitup::workspace::SceneCache;
///
/// let mut doc = Document::open(std::path::Path::new("models/wheel.yaml")).unwrap();
/// let mut cache = SceneCache::new();
/// let plan = plan_sequence(&doc, &mut cache, &SequenceOptions::default()).unwrap();
/// let tol = fitup::collision::DEFAULT_TOLERANCE;
/// assert!(revalidate(plan.best(), &doc, &mut cache, tol).unwrap().is_empty());
/// // The gear moved 1 mm up: its task no longer ends where the gear is.
/// doc.set_transform("gear", Transform::from_translation(Vec3::new(0.0, 0.0, 2.5))).unwrap();
/// let broken = revalidate(plan.best(), &doc, &mut cache, tol).unwrap();
/// assert_eq!(broken[0].part, "gear");
/// ```
pub fn revalidate(
    sequence: &Sequence,
    doc: &Document,
    cache: &mut SceneCache,
    tolerance: f64,
) -> Result<Vec<BrokenStep>, SequenceError> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(SequenceError::InvalidOption {
            option: "tolerance",
            value: GivenValue::Number(tolerance),
            expected: "a finite number of mm ≥ 0",
        });
    }
    let scene = Scene::new(doc, cache)?;
    let index = |name: &str| doc.component_index(name).ok();
    let mut broken = Vec::new();
    let mut before: Vec<Option<usize>> = vec![index(&sequence.base)];
    for t in &sequence.tasks {
        let mut fail = |reason: String| {
            broken.push(BrokenStep {
                index: t.index,
                part: t.part.clone(),
                reason,
            })
        };
        let missing: Vec<&str> = std::iter::once(&sequence.base)
            .chain(
                sequence.tasks[..t.index.min(sequence.tasks.len())]
                    .iter()
                    .map(|u| &u.part),
            )
            .zip(&before)
            .filter(|(_, i)| i.is_none())
            .map(|(n, _)| n.as_str())
            .collect();
        let Some(p) = index(&t.part) else {
            fail(format!(
                "component `{}` is no longer in the document",
                t.part
            ));
            before.push(None);
            continue;
        };
        before.push(Some(p));
        if !missing.is_empty() {
            fail(format!(
                "assembled before it and gone from the document: {}",
                missing.join(", ")
            ));
            continue;
        }
        let now = scene.poses[p];
        if !now.approx_eq(&t.assembled_pose, 1e-3, 1e-6) {
            let moved = (now.translation() - t.assembled_pose.translation()).norm();
            fail(format!(
                "`{}` moved ({} away from where the task puts it)",
                t.part,
                fmt_mm(moved)
            ));
            continue;
        }
        let assembled: Vec<usize> = before[..before.len() - 1]
            .iter()
            .flatten()
            .copied()
            .collect();
        // The task's fit partners (by name, as recorded when it was planned): the
        // overlap of the assembled pose allowed (see `fit.rs`); every other
        // component the tolerance.
        let fitted = |q: usize| t.fits.contains(&doc.components()[q].name);
        let slides = |q: usize| t.slides.contains(&doc.components()[q].name);
        let validator = |qs: &[usize]| {
            let main = MeshValidator::new(
                scene.colliders[p].clone(),
                qs.iter()
                    .filter(|&&q| !fitted(q))
                    .map(|&q| (scene.colliders[q].clone(), scene.poses[q]))
                    .collect(),
                MeshValidatorOptions {
                    tolerance: Some(tolerance),
                    edge: SweepMethod::CONTINUOUS,
                    ..MeshValidatorOptions::default()
                },
            )
            .map_err(|e| SequenceError::from(WorkspaceError::from(e)))?;
            let pairs: Vec<FitPairCheck> = qs
                .iter()
                .filter(|&&q| fitted(q))
                .map(|&q| {
                    let diag = |i: usize| {
                        let b = scene.colliders[i].bounds();
                        (b.hi - b.lo).norm()
                    };
                    let spacing = (0.005 * diag(p).min(diag(q))).clamp(0.025, 1.0);
                    FitPairCheck {
                        p: scene.colliders[p].clone(),
                        p_home: scene.poses[p],
                        q: scene.colliders[q].clone(),
                        q_pose: scene.poses[q],
                        p_carved: super::context::carved_first(
                            doc.mesh_of(p),
                            doc.mesh_of(q),
                            p < q,
                        ),
                        slides: slides(q),
                        spacing,
                        tolerance,
                    }
                })
                .collect();
            let step = pairs
                .iter()
                .map(|c| c.spacing)
                .fold(f64::INFINITY, f64::min);
            let fits = (!pairs.is_empty()).then(|| FitPairValidator {
                pairs,
                step_mm: step,
                deadline: None,
            });
            Ok::<_, SequenceError>(FitValidator::new(main, fits))
        };
        if t.path.revalidate(&mut validator(&assembled)?).is_ok() {
            continue;
        }
        // Name the parts in the way (only on failure: one check per part).
        let mut hit = Vec::new();
        for &q in &assembled {
            if t.path.revalidate(&mut validator(&[q])?).is_err() {
                hit.push(doc.components()[q].name.as_str());
            }
        }
        fail(format!(
            "its insertion path now hits {}",
            if hit.is_empty() {
                "the parts assembled before it".to_string()
            } else {
                hit.join(", ")
            }
        ));
    }
    Ok(broken)
}
