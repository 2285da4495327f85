//! Bindings for assembly sequence planning (seed 003's task layer): the relation
//! graph, mating directions, grasp planes, safe length and `doc.assembly_sequence`,
//! whose Sequence result saves as CSV or JSON inside the project. Values are only
//! converted here; the work is `crate::sequence`.

use super::api::Api;
use super::bind_document::DocHandle;
use super::bind_math::xyzabc_deg;
use super::convert::overwrite_option;
use super::convert::{array3, fail, num, read_options, vec3};
use super::{Context, ScriptResult};
use crate::math::AngleConvention;
use crate::options::Sequence;
use crate::sequence::{self, SequenceOptions, SequencePlan};
use rhai::{Array, Dynamic, Map};
use std::sync::Arc;

/// The result of `doc.assembly_sequence` (cheap to clone); it keeps the run context
/// so `save_csv` can check and record the file it writes, and the penetration
/// tolerance (mm) it was planned with, which `revalidate` re-checks with.
#[derive(Clone)]
pub struct SequenceHandle(pub(super) Arc<SequencePlan>, Arc<Context>, f64);

/// The sequence options of a script's map (the library's [`Sequence`] vocabulary;
/// ranges are `SequenceOptions`' own rule, when planning).
fn options(m: Option<&Map>, ctx: &Context) -> ScriptResult<SequenceOptions> {
    Ok(match m {
        None => SequenceOptions::default(),
        Some(m) => read_options::<Sequence>(m, &|w| ctx.print(w))?.sequence_options(),
    })
}

fn run<R>(
    d: &DocHandle,
    f: impl FnOnce(&crate::document::Document, &mut crate::workspace::SceneCache) -> R,
) -> ScriptResult<R> {
    let doc = d.lock()?;
    let mut cache = d.context().scene_cache()?;
    Ok(f(&doc, &mut cache))
}

/// A direction for people: no `-0`.
fn dir(v: &crate::math::Vec3) -> Dynamic {
    array3(&v.map(|x| x + 0.0))
}

fn dir_array(v: &[crate::math::Vec3]) -> Array {
    v.iter().map(dir).collect()
}

fn sequence_map(s: &sequence::Sequence) -> Map {
    let mut m = Map::new();
    m.insert("base".into(), s.base.clone().into());
    m.insert(
        "order".into(),
        s.order()
            .into_iter()
            .map(Dynamic::from)
            .collect::<Array>()
            .into(),
    );
    m.insert("mounts".into(), (s.mounts as i64).into());
    m.insert(
        "direction_changes".into(),
        (s.direction_changes as i64).into(),
    );
    m.insert("path_length".into(), Dynamic::from_float(s.path_length_mm));
    m.insert("difficult".into(), (s.difficult as i64).into());
    m
}

fn task_maps(s: &sequence::Sequence) -> Array {
    let conv = AngleConvention::default();
    s.tasks
        .iter()
        .zip(&s.steps)
        .map(|(t, st)| {
            let mut m = Map::new();
            m.insert("index".into(), (t.index as i64).into());
            m.insert("base".into(), t.base.clone().into());
            m.insert("part".into(), t.part.clone().into());
            m.insert("operation".into(), t.operation.name().into());
            m.insert("mating_direction".into(), dir(&t.mating_direction));
            m.insert(
                "mating_directions".into(),
                dir_array(&st.mating_directions).into(),
            );
            m.insert(
                "receivers".into(),
                st.receivers
                    .iter()
                    .cloned()
                    .map(Dynamic::from)
                    .collect::<Array>()
                    .into(),
            );
            m.insert("safe_length".into(), Dynamic::from_float(t.safe_length));
            m.insert("mount".into(), t.mount.into());
            m.insert("planned".into(), st.planned.into());
            m.insert("path_length".into(), Dynamic::from_float(t.path.length_mm));
            m.insert(
                "path".into(),
                t.path
                    .poses
                    .iter()
                    .map(|p| xyzabc_deg(p, conv))
                    .collect::<Array>()
                    .into(),
            );
            m.insert("assembled".into(), xyzabc_deg(&t.assembled_pose, conv));
            m.insert(
                "grasp".into(),
                match &t.grasp {
                    Some(g) => {
                        let mut gm = Map::new();
                        gm.insert(
                            "faces".into(),
                            g.faces
                                .iter()
                                .cloned()
                                .map(Dynamic::from)
                                .collect::<Array>()
                                .into(),
                        );
                        gm.insert("normal".into(), array3(&g.normal));
                        gm.insert("width".into(), Dynamic::from_float(g.width));
                        gm.insert("depth".into(), Dynamic::from_float(g.depth));
                        gm.insert("point".into(), array3(&g.point));
                        gm.into()
                    }
                    None => Dynamic::UNIT,
                },
            );
            Dynamic::from_map(m)
        })
        .collect()
}

pub(super) fn register(api: &mut Api) {
    api.section("Assembly sequences", "Seed 003's task layer (see `docs/assembly.md`): the relation graph from mates, mating directions, grasp planes, safe lengths and the assembly sequence — tasks `(base, part, operation)` with checked insertion paths. Directions are `[x, y, z]` unit vectors in the assembly frame (mm); poses `[X, Y, Z, A, B, C]` in degrees.");
    api.type_::<SequenceHandle>("Sequence");
    api.f(
        "Document.relation_graph() -> map",
        "The relation graph from the mates: `#{relations: [#{a, b, mates, freedom, ones}], composites: [[names…]], loops}` — `freedom` is the seed's 6-vector `(x, y, z, Rotx, Roty, Rotz)` of the pair's remaining degrees of freedom (intersection of its mates'), `ones` their count; loops are broken into composite nodes (members in their implied order).",
        |d: &mut DocHandle| -> ScriptResult<Map> {
            let g = run(d, |doc, _| sequence::relation_graph(doc))?;
            let mut m = Map::new();
            let rel: Array = g
                .relations
                .iter()
                .map(|r| {
                    let mut x = Map::new();
                    x.insert("a".into(), g.components[r.a].clone().into());
                    x.insert("b".into(), g.components[r.b].clone().into());
                    x.insert("mates".into(), (r.mates.len() as i64).into());
                    x.insert(
                        "freedom".into(),
                        r.freedom
                            .vector()
                            .iter()
                            .map(|&v| Dynamic::from(v as i64))
                            .collect::<Array>()
                            .into(),
                    );
                    x.insert("ones".into(), (r.freedom.count() as i64).into());
                    Dynamic::from_map(x)
                })
                .collect();
            m.insert("relations".into(), rel.into());
            let comp: Array = g
                .nodes
                .iter()
                .filter(|n| n.is_composite())
                .map(|n| {
                    n.members
                        .iter()
                        .map(|&i| Dynamic::from(g.components[i].clone()))
                        .collect::<Array>()
                        .into()
                })
                .collect();
            m.insert("composites".into(), comp.into());
            m.insert("loops".into(), (g.loops.len() as i64).into());
            Ok(m)
        },
    );
    api.f(
        "Document.mating_directions(name: string) -> array",
        "The mating directions of a component (unit `[x, y, z]`, the way it moves while joined): its free separations from the parts it is related to by mates, negated. Empty when it cannot leave them straight.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<Array> {
            let o = SequenceOptions::default();
            let v = run(d, |doc, c| sequence::mating_directions(doc, c, name, &o))?.map_err(fail)?;
            Ok(dir_array(&v))
        },
    );
    api.f(
        "Document.grasp_planes(name: string) -> array",
        "The parallel face pairs a two-finger gripper can hold the component by across all its mating directions (the seed's G1 ∩ G2 ∩ …): `#{faces, normal, width}` in the part frame (mm); named planes first, faces found on the mesh (`mesh_face_k`) otherwise.",
        |d: &mut DocHandle, name: &str| -> ScriptResult<Array> {
            let o = SequenceOptions::default();
            let v = run(d, |doc, c| sequence::grasp_planes(doc, c, name, &o))?.map_err(fail)?;
            Ok(v.iter()
                .map(|f| {
                    let mut m = Map::new();
                    m.insert(
                        "faces".into(),
                        f.faces
                            .iter()
                            .cloned()
                            .map(Dynamic::from)
                            .collect::<Array>()
                            .into(),
                    );
                    m.insert("normal".into(), array3(&f.normal));
                    m.insert("width".into(), Dynamic::from_float(f.width));
                    Dynamic::from_map(m)
                })
                .collect())
        },
    );
    api.f(
        "Document.safe_length(name: string, direction: array) -> float",
        "How far (mm) the component must move out along `direction` (`[x, y, z]`, assembly frame) before it is free to move in every other direction among the parts it is related to.",
        |d: &mut DocHandle, name: &str, dir: Dynamic| -> ScriptResult<f64> {
            let v = vec3(&dir, "direction")?;
            let o = SequenceOptions::default();
            run(d, |doc, c| sequence::safe_length(doc, c, name, &v, &o))?.map_err(fail)
        },
    );
    api.options::<Sequence>("Options of `assembly_sequence` (Python: `plan_sequence`):");
    api.f(
        "Document.assembly_sequence() -> Sequence",
        "Plans the assembly sequence from the mates with the defaults (see the map form).",
        |d: &mut DocHandle| plan(d, None),
    );
    api.f(
        "Document.assembly_sequence(options: map) -> Sequence",
        "Plans the assembly sequence with the options of the section's table (the whole call within `time_limit_ms`, 5 %). A document without mates is planned from the geometry. Fewest re-mountings of the base wins, then fewest direction changes, then fewest difficult insertions (tight fits, planned paths), then the shortest insertion paths (`ranking` says why); every task's path is collision-free against the parts assembled before it.",
        |d: &mut DocHandle, o: Map| plan(d, Some(&o)),
    );
    api.get(
        "Sequence.tasks -> array",
        "The best sequence's tasks: `#{index, base, part, operation, mating_direction, mating_directions, receivers, safe_length, mount, planned, path_length, path, assembled, grasp}`.",
        |s: &mut SequenceHandle| task_maps(s.0.best()),
    );
    api.get(
        "Sequence.order -> array",
        "The best sequence's component names, base first.",
        |s: &mut SequenceHandle| -> Array {
            s.0.best().order().into_iter().map(Dynamic::from).collect()
        },
    );
    api.get(
        "Sequence.base -> string",
        "The base component of the best sequence.",
        |s: &mut SequenceHandle| s.0.best().base.clone(),
    );
    api.get(
        "Sequence.mounts -> int",
        "Re-mountings of the base in the best sequence.",
        |s: &mut SequenceHandle| s.0.best().mounts as i64,
    );
    api.get(
        "Sequence.ranking -> string",
        "Why the best sequence ranked first: its costs against the runner-up's.",
        |s: &mut SequenceHandle| s.0.ranking.clone(),
    );
    api.get(
        "Sequence.complete -> bool",
        "Whether the search ended by itself (false: the time limit or the expansion cap cut it; the sequences are the best found in time).",
        |s: &mut SequenceHandle| s.0.complete,
    );
    api.get(
        "Sequence.sequences -> array",
        "Every sequence found, best first: `#{base, order, mounts, direction_changes, difficult, path_length}`.",
        |s: &mut SequenceHandle| -> Array {
            s.0.sequences
                .iter()
                .map(|q| Dynamic::from_map(sequence_map(q)))
                .collect()
        },
    );
    api.get(
        "Sequence.precedence -> array",
        "`[a, b]` pairs: `a` goes before `b` in every sequence found.",
        |s: &mut SequenceHandle| -> Array {
            s.0.precedence
                .iter()
                .map(|(a, b)| {
                    Dynamic::from_array(vec![Dynamic::from(a.clone()), Dynamic::from(b.clone())])
                })
                .collect()
        },
    );
    api.get(
        "Sequence.fits -> array",
        "Interferences of the assembled pose taken as fits (press fits, CAD overlaps): `#{a, b, depth, contained}` (mm); the removal checks between `a` and `b` allow the overlap of the assembled pose and no other, every other pair `tolerance`.",
        |s: &mut SequenceHandle| -> Array {
            s.0.fits
                .iter()
                .map(|f| {
                    let mut m = Map::new();
                    m.insert("a".into(), f.a.clone().into());
                    m.insert("b".into(), f.b.clone().into());
                    m.insert("depth".into(), f.depth.into());
                    m.insert("contained".into(), f.contained.into());
                    Dynamic::from_map(m)
                })
                .collect()
        },
    );
    api.get(
        "Sequence.support_gaps -> array",
        "Pairs the support rule takes as holding each other across a gap wider than `contact_gap_mm` (a clearance joint; the closest links that connect the product): `#{a, b, gap}` (mm; `()` for a mated pair).",
        |s: &mut SequenceHandle| -> Array {
            s.0.support_gaps
                .iter()
                .map(|g| {
                    let mut m = Map::new();
                    m.insert("a".into(), g.a.clone().into());
                    m.insert("b".into(), g.b.clone().into());
                    m.insert("gap".into(), g.gap_mm.map_or(Dynamic::UNIT, Dynamic::from));
                    Dynamic::from_map(m)
                })
                .collect()
        },
    );
    api.get(
        "Sequence.separate_groups -> array",
        "Groups of the product's parts that touch nothing of one another in the finished product (within `contact_gap_mm`, across the support gaps), when there is more than one: arrays of component names; the first part placed of each group needs no support. Empty when the product holds together.",
        |s: &mut SequenceHandle| -> Array {
            s.0.separate_groups
                .iter()
                .map(|g| Dynamic::from_array(g.iter().map(|n| n.clone().into()).collect()))
                .collect()
        },
    );
    api.get(
        "Sequence.rejected -> array",
        "Orders that failed and why: `#{order, reason}`.",
        |s: &mut SequenceHandle| -> Array {
            s.0.rejected
                .iter()
                .map(|r| {
                    let mut m = Map::new();
                    m.insert(
                        "order".into(),
                        r.order
                            .iter()
                            .cloned()
                            .map(Dynamic::from)
                            .collect::<Array>()
                            .into(),
                    );
                    m.insert("reason".into(), r.reason.to_string().into());
                    Dynamic::from_map(m)
                })
                .collect()
        },
    );
    api.f(
        "Sequence.to_json() -> string",
        "The whole plan as JSON (sequences, rejected, precedence, relations).",
        |s: &mut SequenceHandle| s.0.to_json(),
    );
    api.f(
        "Sequence.to_string() -> string",
        "A report for people.",
        |s: &mut SequenceHandle| s.0.summary(),
    );
    api.f(
        "Sequence.revalidate(doc: Document) -> array",
        "Re-checks the best sequence against `doc` as it is now (after a part moved, a mate or a mesh changed), with the tolerance it was planned with: the broken steps in task order as `#{index, part, reason}` — a component gone, the part moved from where its task ends, or its insertion path now hitting a part assembled before it (named). Empty: every step still holds.",
        |s: &mut SequenceHandle, d: DocHandle| {
            let tol = s.2;
            revalidate(s, &d, tol)
        },
    );
    api.f(
        "Sequence.revalidate(doc: Document, tolerance: float) -> array",
        "`revalidate` with another penetration tolerance (mm, ≥ 0).",
        |s: &mut SequenceHandle, d: DocHandle, tolerance: Dynamic| {
            let tol = num(&tolerance, "tolerance")?;
            revalidate(s, &d, tol)
        },
    );
    fn save_sequence(s: &SequenceHandle, file: &str, overwrite: bool) -> ScriptResult<()> {
        let mut bytes = Vec::new();
        s.0.best().write_csv(&mut bytes).map_err(fail)?;
        s.1.write_output(file, &bytes, overwrite)?;
        Ok(())
    }
    api.f(
        "Sequence.save_csv(file: string)",
        "Writes the best sequence's tasks as CSV inside the project, atomically: `index,base,part,operation,mate_x,mate_y,mate_z,safe_length_mm,mount,planned,path_length_mm,receivers,grasp_faces`. Refuses to replace a file the project uses or one fitup did not write (see \"What a run writes\" in docs/scripting.md); `#{overwrite: true}` replaces it.",
        |s: &mut SequenceHandle, file: &str| -> ScriptResult<()> { save_sequence(s, file, false) },
    );
    api.f(
        "Sequence.save_csv(file: string, options: map)",
        "`save_csv(file)` with `#{overwrite}` (bool, default false).",
        |s: &mut SequenceHandle, file: &str, opts: Map| -> ScriptResult<()> {
            save_sequence(s, file, overwrite_option(&opts, "save_csv")?)
        },
    );
}

fn plan(d: &DocHandle, opts: Option<&Map>) -> ScriptResult<SequenceHandle> {
    let ctx = d.context().clone();
    let o = options(opts, &ctx)?;
    let p = run(d, |doc, c| sequence::plan_sequence(doc, c, &o))?.map_err(fail)?;
    let tolerance = p.tolerance;
    Ok(SequenceHandle(Arc::new(p), ctx, tolerance))
}

/// `Sequence.revalidate`: the broken steps of the best sequence in `d` as it is now.
fn revalidate(s: &SequenceHandle, d: &DocHandle, tolerance: f64) -> ScriptResult<Array> {
    let broken = run(d, |doc, c| {
        sequence::revalidate(s.0.best(), doc, c, tolerance)
    })?
    .map_err(fail)?;
    Ok(broken
        .into_iter()
        .map(|b| {
            let mut m = Map::new();
            m.insert("index".into(), (b.index as i64).into());
            m.insert("part".into(), b.part.into());
            m.insert("reason".into(), b.reason.into());
            Dynamic::from_map(m)
        })
        .collect())
}
