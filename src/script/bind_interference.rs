//! Bindings for interference detection: static checks (exact, AABB, cut cells), the
//! cut-cells feature, and sweeps along motions.

use super::api::Api;
use super::bind_document::{ComponentHandle, DocHandle};
use super::bind_math::to_transform;
use super::bind_planning::with_workspace;
use super::convert::{box_value, check_keys, err, fail, floats, num, read_options};
use super::ScriptResult;
use crate::collision::{Contact, CutSpec, SweepOptions};
use crate::document::Feature;
use crate::options::{Check, Sweep};
use crate::workspace::{split_part, CheckOptions, CUT_CELLS_FEATURE};
use rhai::{Array, Dynamic, Map};

/// A part's cut-cells feature, by part and feature name.
#[derive(Clone)]
pub struct FeatureHandle {
    doc: DocHandle,
    part: String,
    name: String,
}

/// The check options of a script's map (the library's [`Check`] vocabulary; the
/// tolerance's range is the library's rule, when checking).
fn options(map: Option<&Map>) -> ScriptResult<CheckOptions> {
    Ok(match map {
        None => CheckOptions::default(),
        Some(m) => read_options::<Check>(m, &|_| {})?.check_options(),
    })
}

fn contact_map(c: &Contact, a: &str, b: &str) -> Map {
    let mut m = Map::new();
    m.insert("a".into(), a.into());
    m.insert("b".into(), b.into());
    m.insert("state".into(), c.state_name().into());
    m.insert("depth".into(), Dynamic::from_float(c.depth()));
    if c.is_interfering() {
        m.insert("kind".into(), c.kind_text(a, b).into());
    }
    m
}

fn pairs(d: &DocHandle, opts: Option<&Map>, want_touching: bool) -> ScriptResult<Array> {
    let o = options(opts)?;
    with_workspace(d, |ws| {
        let found = if want_touching {
            ws.touching(&o)
        } else {
            ws.interferences(&o)
        }
        .map_err(fail)?;
        let view = &d.context().caches.view;
        if view.is_live() && !want_touching {
            let pairs: Vec<_> = found
                .iter()
                .map(|p| (p.a, p.b, p.contact.depth()))
                .collect();
            view.log_interference(ws.document(), &pairs);
        }
        Ok(found
            .into_iter()
            .map(|p| {
                let c = ws.with_separation_depth(p.a, p.b, p.contact);
                Dynamic::from_map(contact_map(&c, ws.name(p.a), ws.name(p.b)))
            })
            .collect())
    })
}

fn pair(d: &DocHandle, a: &str, b: &str, opts: Option<&Map>) -> ScriptResult<Map> {
    let o = options(opts)?;
    with_workspace(d, |ws| {
        let c = ws.contact(a, b, &o).map_err(fail)?;
        let (ia, ib) = (ws.index(a).map_err(fail)?, ws.index(b).map_err(fail)?);
        Ok(contact_map(&ws.with_separation_depth(ia, ib, c), a, b))
    })
}

fn interferes(d: &DocHandle, a: &str, b: &str, opts: Option<&Map>) -> ScriptResult<bool> {
    let o = options(opts)?;
    with_workspace(d, |ws| ws.interferes(a, b, &o).map_err(fail))
}

/// The waypoints of a motion: a Transform or pose, or an array of Transforms.
fn waypoints(motion: &Dynamic) -> ScriptResult<Vec<crate::math::Transform>> {
    if let Some(arr) = motion.read_lock::<Array>() {
        // An array of Transforms (not a 4×4 matrix or a pose): a pose sequence.
        if arr.iter().all(|v| v.is::<crate::math::Transform>()) && !arr.is_empty() {
            return arr
                .iter()
                .enumerate()
                .map(|(i, v)| to_transform(v, &format!("motion[{i}]")))
                .collect();
        }
    }
    Ok(vec![to_transform(motion, "motion")?])
}

fn sweep(d: &DocHandle, name: &str, motion: &Dynamic, opts: Option<&Map>) -> ScriptResult<Map> {
    let o = match opts {
        None => SweepOptions::default(),
        Some(m) => read_options::<Sweep>(m, &|_| {})?.sweep_options(),
    };
    let to = waypoints(motion)?;
    with_workspace(d, |ws| {
        let hit = ws.sweep_through(name, &to, &o).map_err(fail)?;
        let mut m = Map::new();
        m.insert("hit".into(), hit.hit.into());
        m.insert("t".into(), Dynamic::from_float(hit.t));
        m.insert("transform".into(), Dynamic::from(hit.pose));
        m.insert(
            "with".into(),
            hit.with
                .map(|k| Dynamic::from(ws.name(k).to_string()))
                .unwrap_or(Dynamic::UNIT),
        );
        m.insert("checks".into(), Dynamic::from_int(hit.queries as i64));
        Ok(m)
    })
}

fn feature_map(part: &str, f: &Feature) -> Map {
    let mut m = Map::new();
    m.insert("part".into(), part.into());
    m.insert("name".into(), f.name().into());
    match f {
        Feature::CutCells { spec, .. } => {
            m.insert("type".into(), "cut_cells".into());
            match spec {
                CutSpec::Size(s) => {
                    m.insert("cell_size".into(), Dynamic::from_float(*s));
                }
                CutSpec::Planes { x, y, z } => {
                    let mut p = Map::new();
                    p.insert("x".into(), floats(x.iter().copied()));
                    p.insert("y".into(), floats(y.iter().copied()));
                    p.insert("z".into(), floats(z.iter().copied()));
                    m.insert("planes".into(), p.into());
                }
            }
        }
    }
    m
}

fn split(c: &ComponentHandle, spec: CutSpec) -> ScriptResult<FeatureHandle> {
    let mut doc = c.doc.lock()?;
    let i = c.at(&doc)?;
    let mut cache = c.doc.context().scene_cache()?;
    let part = split_part(&mut doc, &mut cache, i, spec).map_err(fail)?;
    Ok(FeatureHandle {
        doc: c.doc.clone(),
        part,
        name: CUT_CELLS_FEATURE.to_string(),
    })
}

fn feature_cells(f: &FeatureHandle) -> ScriptResult<std::sync::Arc<crate::collision::CutCells>> {
    let doc = f.doc.lock()?;
    let mut cache = f.doc.context().scene_cache()?;
    crate::workspace::feature_cells(&doc, &mut cache, &f.part, &f.name).map_err(fail)
}

pub(super) fn register(api: &mut Api) {
    api.section("Interference", "Static interference between components, seed 000 style. Methods: `\"exact\"` (default: solid semantics — surfaces crossing deeper than the tolerance, or one part inside the other), `\"aabb\"` (whole-part world boxes) and `\"cells\"` (whole-part boxes, then the boxes of the parts' cut cells). Parts whose surfaces only meet (a plate on the table, a screw resting in a hole of its diameter) are *touching*, not interfering. The options maps take the keys of the table below (`tolerance`: the penetration tolerance). Results are maps `#{a, b, state, depth, kind}`: `state` is `\"separate\"`, `\"touching\"` or `\"interfering\"`, `depth` the interference depth in mm (for closed solids the shortest translation that separates them, as `overlap` measures it, within 2 s; else the crossing estimate), `kind` `\"surfaces cross\"`, `\"X inside Y\"`, `\"faces overlap\"` (closed solids whose faces overlap in one plane facing the same way: equal walls pushed into each other) or `\"boxes overlap\"`.");
    api.options::<Check>("Options of `interferences`, `touching`, `interferes`, `contact`:");
    api.options::<Sweep>("Options of `sweep`:");
    api.type_::<FeatureHandle>("Feature");
    api.f(
        "Document.interferences() -> array",
        "Every interfering pair (exact method): `#{a, b, state, depth, kind}`.",
        |d: &mut DocHandle| pairs(d, None, false),
    );
    api.f(
        "Document.interferences(options: map) -> array",
        "Every interfering pair by `#{method, tolerance}`.",
        |d: &mut DocHandle, o: Map| pairs(d, Some(&o), false),
    );
    api.f(
        "Document.touching() -> array",
        "Every pair whose surfaces meet without interfering (exact method).",
        |d: &mut DocHandle| pairs(d, None, true),
    );
    api.f(
        "Document.touching(options: map) -> array",
        "Touching pairs by `#{method, tolerance}`.",
        |d: &mut DocHandle, o: Map| pairs(d, Some(&o), true),
    );
    api.f(
        "Document.interferes(a: string, b: string) -> bool",
        "Whether two components interfere (exact method, the default tolerance). The same answer as `contact(a, b).state == \"interfering\"`, but stops at the first crossing deeper than the tolerance instead of measuring the deepest: the cheap check for loops over many poses.",
        |d: &mut DocHandle, a: &str, b: &str| interferes(d, a, b, None),
    );
    api.f(
        "Document.interferes(a: string, b: string, options: map) -> bool",
        "Whether two components interfere by `#{method: \"exact\"|\"aabb\"|\"cells\", tolerance}`.",
        |d: &mut DocHandle, a: &str, b: &str, o: Map| interferes(d, a, b, Some(&o)),
    );
    api.f(
        "Document.contact(a: string, b: string) -> map",
        "The verdict for two components: `#{a, b, state, depth, kind}` (exact method).",
        |d: &mut DocHandle, a: &str, b: &str| pair(d, a, b, None),
    );
    api.f(
        "Document.contact(a: string, b: string, options: map) -> map",
        "The verdict for two components by `#{method, tolerance}`.",
        |d: &mut DocHandle, a: &str, b: &str, o: Map| pair(d, a, b, Some(&o)),
    );
    api.f("Document.clearance(a: string, b: string) -> float", "Distance between the surfaces of two components (mm), 0 when they touch, cross or one is inside the other (agrees with `contact`: not separate ⇒ at most the tolerance); searched up to 1000 mm (1000 when nothing is nearer).", |d: &mut DocHandle, a: &str, b: &str| -> ScriptResult<f64> {
        with_workspace(d, |ws| ws.clearance(a, b, crate::workspace::DEFAULT_CLEARANCE_SEARCH_MM).map_err(fail))
    });
    api.f("Document.sweep(name: string, motion) -> map", "Dynamic interference: moves the component from its pose to `motion` (a Transform, or an array of Transforms visited in order; translation lerp + rotation slerp) and returns the first contact: `#{hit, t, transform, with, checks}` (`t` in 0..1 along the motion, `with` the other component — `with` is a Rhai keyword, read it as `hit[\"with\"]`). Continuous method: never misses a contact.", |d: &mut DocHandle, name: &str, motion: Dynamic| sweep(d, name, &motion, None));
    api.f("Document.sweep(name: string, motion, options: map) -> map", "As above with the options of the section's sweep table (`method`, `step`, `tolerance`, `time_limit_ms`); `\"step\"` is seed 000's static check after every step and can jump over thin features.", |d: &mut DocHandle, name: &str, motion: Dynamic, o: Map| sweep(d, name, &motion, Some(&o)));

    api.section("Cut cells", "Seed 000's finite subdivision: a part cut by arrays of planes into cells, one box per cell, stored as a feature in the part's feature tree (saved with the document, re-derived when the mesh changes). Cells are in the part frame (mm).");
    api.f("Component.split(cell_size) -> Feature", "Cuts the component's part into cubic cells of `cell_size` mm (plane arrays from the part's minimum corner) and stores the feature `CutCells` in the part's tree (replacing an earlier one). Refuses sizes that would make more than 100,000 cells.", |c: &mut ComponentHandle, size: Dynamic| -> ScriptResult<FeatureHandle> {
        let s = num(&size, "cell_size")?;
        if s <= 0.0 {
            return err(format!("cell_size must be > 0 mm, not {s}"));
        }
        split(c, CutSpec::Size(s))
    });
    api.f("Component.split(planes: map) -> Feature", "Cuts the part by explicit planes `#{x: [..], y: [..], z: [..]}` (positions in the part frame, mm).", |c: &mut ComponentHandle, p: Map| -> ScriptResult<FeatureHandle> {
        check_keys(&p, &["x", "y", "z"], "planes")?;
        let axis = |k: &str| -> ScriptResult<Vec<f64>> {
            match p.get(k) {
                None => Ok(vec![]),
                Some(v) => v.read_lock::<Array>().ok_or_else(|| fail(format!("planes.{k} must be an array")))?.iter().map(|x| num(x, k)).collect(),
            }
        };
        split(c, CutSpec::Planes { x: axis("x")?, y: axis("y")?, z: axis("z")? })
    });
    api.f(
        "Document.features(part: string) -> array",
        "The part's feature tree: maps `#{part, name, type, cell_size | planes}`.",
        |d: &mut DocHandle, part: &str| -> ScriptResult<Array> {
            let doc = d.lock()?;
            let p = doc.part(part).map_err(fail)?;
            Ok(p.features
                .iter()
                .map(|f| Dynamic::from_map(feature_map(part, f)))
                .collect())
        },
    );
    api.f(
        "Document.feature(part: string, name: string) -> Feature",
        "A feature of a part by name.",
        |d: &mut DocHandle, part: &str, name: &str| -> ScriptResult<FeatureHandle> {
            let doc = d.lock()?;
            let p = doc.part(part).map_err(fail)?;
            let name = &*crate::document::nfc_name(name);
            if !p.features.iter().any(|f| f.name() == name) {
                return err(format!("part `{part}` has no feature `{name}`"));
            }
            Ok(FeatureHandle {
                doc: d.clone(),
                part: part.into(),
                name: name.into(),
            })
        },
    );
    api.get(
        "Feature.name -> string",
        "The feature name.",
        |f: &mut FeatureHandle| f.name.clone(),
    );
    api.get(
        "Feature.part -> string",
        "The part whose tree holds it.",
        |f: &mut FeatureHandle| f.part.clone(),
    );
    api.f("Feature.cells() -> array", "The cells: a `Box` (`.min`, `.max`) of the part's material in each grid cell, part frame (mm).", |f: &mut FeatureHandle| -> ScriptResult<Array> {
        let cells = feature_cells(f)?;
        Ok(cells.cells.iter().map(|c| box_value(&c.bounds)).collect())
    });
    api.get(
        "Feature.count -> int",
        "How many cells have material.",
        |f: &mut FeatureHandle| -> ScriptResult<i64> { Ok(feature_cells(f)?.cells.len() as i64) },
    );
    api.f(
        "Feature.to_string() -> string",
        "`Feature(part/name)`.",
        |f: &mut FeatureHandle| format!("Feature({}/{})", f.part, f.name),
    );
}
