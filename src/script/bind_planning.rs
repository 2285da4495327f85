//! Bindings for path planning: `doc.plan_path`, `doc.plan_disassembly`, the Path
//! result, `component.follow` and re-validation.

use super::api::Api;
use super::bind_document::{ComponentHandle, DocHandle};
use super::bind_math::{to_transform, xyzabc_deg};
use super::convert::overwrite_option;
use super::convert::{err, fail, num, read_options};
use super::{Context, ScriptResult};
use crate::math::AngleConvention;
use crate::options::{Narrow, Plan};
use crate::planning::{Control, Phase, PlannedPath, ProblemFile, Progress};
use crate::workspace::{PlanRequest, Revalidation, Workspace};
use rhai::{Array, Dynamic, Map};
use std::sync::Arc;
use std::time::Instant;

/// A planned path (cheap to clone); it keeps the run context so `save_csv` can check
/// and record the file it writes. `revalidate` takes the tolerance rule from the
/// path itself ([`PlannedPath::validator_options`]).
#[derive(Clone)]
pub struct PathHandle(pub(super) Arc<PlannedPath>, pub(super) Arc<Context>);

/// The planning request of the script's options: the library's vocabulary
/// ([`Plan`]), which converts names and units (degrees to radians, `0` = off) and
/// types. Every range is checked once, by the library when it plans (`PlanError`,
/// `CollisionError`, `WorkspaceError`), so a script and a Rust caller get the same
/// rule and the same words.
fn parse(opts: &Map, default_planner: &str, ctx: &Context) -> ScriptResult<PlanRequest> {
    let o: Plan = read_options(opts, &|w| ctx.print(w))?;
    o.request(default_planner).map_err(fail)
}

fn progress_printer<'a>(
    ctx: &'a Arc<Context>,
    planner: &'static str,
) -> impl FnMut(&Progress) -> Control + 'a {
    let mut last = Instant::now();
    move |p: &Progress| {
        if ctx.cancelled() {
            return Control::Cancel;
        }
        if last.elapsed().as_secs_f64() > 1.0 {
            last = Instant::now();
            ctx.print(&match p.phase {
                Phase::Search => format!(
                    "  {planner}: {} iterations, {} nodes, {:.2} mm from the goal, {:.0} ms",
                    p.iterations, p.nodes, p.best_distance, p.elapsed_ms
                ),
                Phase::Smoothing => format!(
                    "  {planner}: smoothing, {} shortcuts tried, {} key poses, {:.1} long, {:.0} ms",
                    p.iterations, p.nodes, p.best_distance, p.elapsed_ms
                ),
            });
        }
        Control::Continue
    }
}

/// Runs `f` on the workspace of the document (the run's scene cache).
pub(super) fn with_workspace<R>(
    d: &DocHandle,
    f: impl FnOnce(&Workspace) -> ScriptResult<R>,
) -> ScriptResult<R> {
    let doc = d.lock()?;
    let ws = Workspace::new(&doc, &mut *d.context().scene_cache()?).map_err(fail)?;
    f(&ws)
}

fn plan(d: &DocHandle, name: &str, goal: &Dynamic, opts: &Map) -> ScriptResult<PathHandle> {
    let goal = to_transform(goal, "goal")?;
    let ctx = d.context().clone();
    let req = parse(opts, "rrt_connect", &ctx)?;
    let mut cb = progress_printer(&ctx, req.planner.name());
    let path = with_workspace(d, |ws| {
        ws.plan_path(name, &goal, &req, Some(&mut cb)).map_err(fail)
    })?;
    if path.failure.is_some() && ctx.cancelled() {
        return err("cancelled");
    }
    Ok(PathHandle(Arc::new(path), ctx.clone()))
}

/// A planning problem read from a `.plan.json` file (cheap to clone).
#[derive(Clone)]
pub struct ProblemHandle(pub(super) Arc<ProblemFile>);

fn load_problem(d: &DocHandle, path: &str) -> ScriptResult<ProblemHandle> {
    let ctx = d.context();
    let full = ctx.project.resolve(path).map_err(fail)?;
    ctx.record_read(&full);
    let p = ProblemFile::read(&full).map_err(fail)?;
    d.lock()?
        .component_index(&p.moving_component)
        .map_err(|e| fail(format!("{path}: {e}")))?;
    Ok(ProblemHandle(Arc::new(p)))
}

fn plan_problem(d: &DocHandle, p: &ProblemHandle, opts: &Map) -> ScriptResult<PathHandle> {
    let ctx = d.context().clone();
    let req = parse(opts, "rrt_connect", &ctx)?;
    let mut cb = progress_printer(&ctx, req.planner.name());
    let path = with_workspace(d, |ws| {
        ws.plan_problem(&p.0, &req, Some(&mut cb)).map_err(fail)
    })?;
    if path.failure.is_some() && ctx.cancelled() {
        return err("cancelled");
    }
    Ok(PathHandle(Arc::new(path), ctx.clone()))
}

fn plan_disassembly(d: &DocHandle, name: &str, opts: &Map) -> ScriptResult<PathHandle> {
    let ctx = d.context().clone();
    let req = parse(opts, "local_rrt", &ctx)?;
    let mut cb = progress_printer(&ctx, req.planner.name());
    let path = with_workspace(d, |ws| {
        ws.plan_disassembly(name, &req, Some(&mut cb)).map_err(fail)
    })?;
    if path.failure.is_some() && ctx.cancelled() {
        return err("cancelled");
    }
    Ok(PathHandle(Arc::new(path), ctx.clone()))
}

fn densify(p: &PlannedPath, step: f64) -> ScriptResult<Vec<crate::math::Transform>> {
    // Rotation steps follow the translation step: 1 mm ~ 1°; the library refuses a bad
    // step and counts the poses against the shared cap before making any.
    p.densify_as(step, step.to_radians(), "step", step)
        .map_err(|e| fail(format!("Path.densify: {e}")))
}

pub(super) fn register(api: &mut Api) {
    api.section("Path planning", "Collision-free paths for one component (position and orientation) among the others, seeds 000 and 002. Planners: `\"greedy_ant\"` (seed 000's single-ant dynamic greedy: options `step` = segments of s→e, `L`, `dis`, `radius`), `\"rrt_floyd\"` (seed 000's random-walk tree + Floyd shortest path), `\"rrt\"`, `\"biased_rrt\"` (seed 002's baselines, `goal_bias` p), `\"local_rrt\"` (seed 002's improved RRT: local discretization — 26 translation neighbours at an edge length adapting to the clearance, then the 6 single-axis rotations), `\"rrt_connect\"` (default; bidirectional, with the local lattice and random coordinated moves when an extension is blocked, within `fallback_share` of the work; it explores lazily with pose checks and returns only a path whose every edge passed the `edge` check). With `disassemble: true`, `rrt`, `biased_rrt` and `local_rrt` search the disassembly, with `rrt_connect` (default) `local_rrt` does; `greedy_ant` and `rrt_floyd` are refused; when both or neither end is inside, there is nothing to disassemble and the call is plain `rrt_connect`. `Path.planner` says what ran, e.g. `\"lazy_disassemble_local_rrt+lazy_rrt_connect\"`, `lazy_` marking a search explored lazily and certified. Progress is printed every second. Fixed components are refused. A path that is not found says why in `reason`. The options maps of `plan_path`, `plan_disassembly` and `plan_problem` take the keys of the tables below (Python's keywords are the same); an unknown key is an error naming the close ones");
    api.options::<Plan>("Options of `plan_path`, `plan_disassembly`, `plan_problem`:");
    api.options::<Narrow>("The map of `narrow`:");
    api.type_::<PathHandle>("Path");
    api.f("Document.plan_path(name: string, goal) -> Path", "Plans a path for the component from its current pose to `goal` (a Transform or a pose `[x,y,z,a,b,c]`) with the default planner (`rrt_connect`).", |d: &mut DocHandle, name: &str, goal: Dynamic| plan(d, name, &goal, &Map::new()));
    api.f(
        "Document.plan_path(name: string, goal, options: map) -> Path",
        "Plans a path with options (the section's table).",
        |d: &mut DocHandle, name: &str, goal: Dynamic, o: Map| plan(d, name, &goal, &o),
    );
    api.f("Document.plan_disassembly(name: string) -> Path", "Seed 002's \"can be disassembled, can be assembled\": plans from the component's (assembled) pose until its box is outside the box of the other components, then reverses the path, so it ends assembled. Default planner `local_rrt`.", |d: &mut DocHandle, name: &str| plan_disassembly(d, name, &Map::new()));
    api.f(
        "Document.plan_disassembly(name: string, options: map) -> Path",
        "As above with options (planner `rrt`, `biased_rrt` or `local_rrt`).",
        |d: &mut DocHandle, name: &str, o: Map| plan_disassembly(d, name, &o),
    );
    api.type_::<ProblemHandle>("Problem");
    api.f("Document.load_problem(file: string) -> Problem", "Reads a planning problem (`.plan.json`, path inside the project: which component moves, start and goal poses, bounds, rotation weight — the files under `models/problems/`) and checks that its component is in this document; errors name the file, line and field.", |d: &mut DocHandle, file: &str| load_problem(d, file));
    api.f(
        "Document.plan_problem(problem: Problem) -> Path",
        "Plans the problem: its component from the file's start to its goal within its bounds, default planner and options.",
        |d: &mut DocHandle, p: ProblemHandle| plan_problem(d, &p, &Map::new()),
    );
    api.f(
        "Document.plan_problem(problem: Problem, options: map) -> Path",
        "As above with the options of `plan_path` (`bounds` and `start` come from the file).",
        |d: &mut DocHandle, p: ProblemHandle, o: Map| plan_problem(d, &p, &o),
    );
    api.get(
        "Problem.name -> string",
        "The problem's name.",
        |p: &mut ProblemHandle| p.0.name.clone(),
    );
    api.get(
        "Problem.component -> string",
        "The component that moves.",
        |p: &mut ProblemHandle| p.0.moving_component.clone(),
    );
    api.get(
        "Problem.start -> Transform",
        "Start pose (mm).",
        |p: &mut ProblemHandle| p.0.start,
    );
    api.get(
        "Problem.goal -> Transform",
        "Goal pose (mm).",
        |p: &mut ProblemHandle| p.0.goal,
    );
    api.get(
        "Path.found -> bool",
        "Whether a path was found.",
        |p: &mut PathHandle| p.0.found(),
    );
    api.get("Path.reason -> string", "Why not (iteration limit, time limit, start/goal in collision or out of bounds, cancelled); empty when found.", |p: &mut PathHandle| p.0.failure.as_ref().map(|f| f.to_string()).unwrap_or_default());
    api.get(
        "Path.poses -> array",
        "The key poses (Transforms), start to end.",
        |p: &mut PathHandle| {
            p.0.poses
                .iter()
                .map(|t| Dynamic::from(*t))
                .collect::<Array>()
        },
    );
    api.get(
        "Path.xyzabc -> array",
        "The key poses as `[x, y, z, a, b, c]` (mm, degrees).",
        |p: &mut PathHandle| {
            p.0.poses
                .iter()
                .map(|t| xyzabc_deg(t, AngleConvention::default()))
                .collect::<Array>()
        },
    );
    api.get(
        "Path.length -> float",
        "Translation length (mm) after smoothing.",
        |p: &mut PathHandle| p.0.length_mm,
    );
    api.get(
        "Path.length_before_smoothing -> float",
        "Translation length (mm) as the planner found it.",
        |p: &mut PathHandle| p.0.raw_length_mm,
    );
    api.get(
        "Path.rotation -> float",
        "Total rotation along the path (degrees).",
        |p: &mut PathHandle| p.0.rotation_rad.to_degrees(),
    );
    api.get(
        "Path.iterations -> int",
        "Planner iterations.",
        |p: &mut PathHandle| p.0.iterations as i64,
    );
    api.get(
        "Path.checks -> int",
        "Collision checks (poses + edges).",
        |p: &mut PathHandle| p.0.collision_checks() as i64,
    );
    api.get(
        "Path.time_ms -> float",
        "Time of the whole call (ms): search and smoothing.",
        |p: &mut PathHandle| p.0.time_ms,
    );
    api.get(
        "Path.search_ms -> float",
        "Of `time_ms`, the search (ms).",
        |p: &mut PathHandle| p.0.search_ms,
    );
    api.get(
        "Path.smoothing_ms -> float",
        "Of `time_ms`, the smoothing (ms).",
        |p: &mut PathHandle| p.0.smoothing_ms,
    );
    api.get(
        "Path.planner -> string",
        "The planner that made it.",
        |p: &mut PathHandle| p.0.planner.to_string(),
    );
    api.get(
        "Path.tolerance -> float",
        "The penetration tolerance (mm) the path was planned with: crossings up to this depth counted as touching.",
        |p: &mut PathHandle| p.0.tolerance_mm,
    );
    api.get(
        "Path.resolution -> string",
        "How edges were validated (continuous, or the stepwise resolution).",
        |p: &mut PathHandle| p.0.resolution.to_string(),
    );
    api.f(
        "Path.densify(step) -> array",
        "Poses along the path no more than `step` mm (and `step` degrees) apart, for animation. More than 1,000,000 poses (the cap of every call, see docs/scripting.md \"Caps\") is an error naming `step`.",
        |p: &mut PathHandle, s: Dynamic| -> ScriptResult<Array> {
            Ok(densify(&p.0, num(&s, "step")?)?
                .into_iter()
                .map(Dynamic::from)
                .collect())
        },
    );
    api.f(
        "Path.to_string() -> string",
        "A one-line summary.",
        |p: &mut PathHandle| {
            let p = &p.0;
            match &p.failure {
                None => format!(
                    "Path({}: {} key poses, {:.1} mm, {:.1}°, {} iterations, {} checks, {:.1} ms)",
                    p.planner,
                    p.poses.len(),
                    p.length_mm,
                    p.rotation_rad.to_degrees(),
                    p.iterations,
                    p.collision_checks(),
                    p.time_ms
                ),
                Some(f) => format!(
                    "Path({}: not found — {f}; {} iterations, {:.1} ms)",
                    p.planner, p.iterations, p.time_ms
                ),
            }
        },
    );
    fn save_path(p: &PathHandle, file: &str, overwrite: bool) -> ScriptResult<()> {
        let mut bytes = Vec::new();
        p.0.write_csv(&mut bytes, AngleConvention::default())
            .map_err(fail)?;
        p.1.write_output(file, &bytes, overwrite)?;
        Ok(())
    }
    api.f("Path.save_csv(file: string)", "Writes the key poses as CSV (`index,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg`) inside the project, atomically. Refuses to replace a file the project uses or one fitup did not write (see \"What a run writes\" in docs/scripting.md); `#{overwrite: true}` replaces it.", |p: &mut PathHandle, file: &str| -> ScriptResult<()> {
        save_path(p, file, false)
    });
    api.f(
        "Path.save_csv(file: string, options: map)",
        "`save_csv(file)` with `#{overwrite}` (bool, default false).",
        |p: &mut PathHandle, file: &str, opts: Map| -> ScriptResult<()> {
            save_path(p, file, overwrite_option(&opts, "save_csv")?)
        },
    );
    api.f("Document.revalidate(name: string, path: Path) -> map", "Checks a path again against the document as it is now, with the tolerance and edge check it was planned with (a path the planner accepted passes while nothing moved): `#{ok, segment, transform}` (the first blocked segment and pose when not ok).", |d: &mut DocHandle, name: &str, p: PathHandle| -> ScriptResult<Map> {
        let r = with_workspace(d, |ws| ws.revalidate(name, &p.0, &p.0.validator_options()).map_err(fail))?;
        let mut m = Map::new();
        match r {
            Revalidation::Valid => {
                m.insert("ok".into(), true.into());
            }
            Revalidation::Blocked { segment, pose } => {
                m.insert("ok".into(), false.into());
                m.insert("segment".into(), Dynamic::from_int(segment as i64));
                m.insert("transform".into(), Dynamic::from(pose));
            }
        }
        Ok(m)
    });
    api.f("Component.follow(path: Path, step) -> int", "Animates the component along the path in steps of at most `step` mm (and degrees), printing each step's pose (mm, degrees) — in watch mode each step shows. Returns the number of steps. More than 1,000,000 steps (the cap of every call, docs/scripting.md \"Caps\") is an error naming `step`, before the component moves.", |c: &mut ComponentHandle, p: PathHandle, s: Dynamic| follow(c, &p, &s, true));
    api.f(
        "Component.follow(path: Path, step, print: bool) -> int",
        "As above; `print: false` moves silently.",
        |c: &mut ComponentHandle, p: PathHandle, s: Dynamic, print: bool| follow(c, &p, &s, print),
    );
}

fn follow(c: &ComponentHandle, p: &PathHandle, step: &Dynamic, print: bool) -> ScriptResult<i64> {
    let step = num(step, "step")?;
    let ctx = c.doc.context().clone();
    let mut doc = c.doc.lock()?;
    let i = c.at(&doc)?;
    let name = doc.components()[i].name.clone();
    let view = ctx.caches.view.clone();
    view.log_path(&name, &p.0.poses);
    let doc_name = crate::viewer::document_name(&doc);
    let n = crate::workspace::follow(&mut doc, &name, &p.0, step, |k, n, t| {
        if view.is_live() {
            view.send(crate::viewer::ViewEvent::Poses {
                doc: doc_name.clone(),
                poses: vec![(name.clone(), *t)],
                advance: true,
            });
        }
        if print {
            ctx.print(&format!("follow {name} {k}/{n}: {t}"));
        }
        if ctx.cancelled() {
            Control::Cancel
        } else {
            Control::Continue
        }
    })
    .map_err(fail)?;
    Ok(n as i64)
}

#[cfg(test)]
mod option_tests {
    use super::*;

    fn request(pairs: &[(&str, Dynamic)], default_planner: &str) -> ScriptResult<PlanRequest> {
        let m: Map = pairs
            .iter()
            .map(|(k, v)| ((*k).into(), v.clone()))
            .collect();
        let o: Plan = read_options(&m, &|w| panic!("{w}"))?;
        o.request(default_planner).map_err(fail)
    }

    fn map(pairs: &[(&str, Dynamic)]) -> Dynamic {
        Dynamic::from_map(
            pairs
                .iter()
                .map(|(k, v)| ((*k).into(), v.clone()))
                .collect(),
        )
    }

    #[test]
    fn narrow_option_converts_degrees_and_switches() {
        use crate::planning::NarrowPassage;
        let narrow = |v: Dynamic| {
            let mut r = request(&[("narrow", v)], "rrt_connect").unwrap();
            *r.planner.narrow_mut().unwrap()
        };
        assert_eq!(narrow(Dynamic::from_bool(false)), NarrowPassage::OFF);
        assert_eq!(narrow(Dynamic::from_bool(true)), NarrowPassage::default());
        let n = narrow(map(&[
            ("max_turn_deg", Dynamic::from_float(10.0)),
            ("dynamic_domain", Dynamic::from_int(0)),
            ("to_contact", Dynamic::from_bool(false)),
            ("axis_moves", Dynamic::from_float(0.0)),
        ]));
        assert!((n.max_turn.unwrap() - 10f64.to_radians()).abs() < 1e-12);
        assert_eq!(n.axis_moves, 0.0);
        assert_eq!(n.dynamic_domain, None);
        assert!(!n.to_contact);
        assert_eq!(n.bridge, NarrowPassage::default().bridge);
        // Not a narrow option, or not a map: refused by the vocabulary, by name.
        for bad in [
            map(&[("max_turn", Dynamic::from_float(5.0))]),
            Dynamic::from_int(3),
        ] {
            let e = request(&[("narrow", bad.clone())], "rrt_connect").unwrap_err();
            assert!(e.to_string().contains("narrow"), "{bad:?}: {e}");
        }
        // Out of range: converted, then refused by the library's one rule.
        for bad in [
            map(&[("bridge", Dynamic::from_float(1.5))]),
            map(&[("max_turn_deg", Dynamic::from_float(-1.0))]),
            map(&[("max_turn_deg", Dynamic::from_float(190.0))]),
            map(&[("dynamic_domain", Dynamic::from_float(-2.0))]),
            map(&[("axis_moves", Dynamic::from_float(1.5))]),
            map(&[("axis_samples", Dynamic::from_float(-0.5))]),
        ] {
            assert!(narrow(bad.clone()).validate().is_err(), "{bad:?}");
        }
        // A planner without the measures refuses the key.
        assert!(request(
            &[("narrow", Dynamic::FALSE), ("planner", "greedy_ant".into())],
            "rrt"
        )
        .is_err());
    }

    #[test]
    fn fallback_share_reaches_the_planner_and_is_range_checked() {
        let share = |x: f64| request(&[("fallback_share", Dynamic::from_float(x))], "rrt_connect");
        assert_eq!(
            share(0.5).unwrap().planner.fallback_share_mut().copied(),
            Some(0.5)
        );
        // A number that is not one is refused by the conversion…
        let e = share(f64::NAN).unwrap_err();
        assert!(e.to_string().contains("fallback_share"), "{e}");
        // …one out of range by the library.
        for bad in [1.5, -0.1] {
            assert!(
                matches!(
                    share(bad).unwrap().planner.validate(),
                    Err(crate::planning::PlanError::InvalidOption {
                        option: "fallback_share",
                        ..
                    })
                ),
                "{bad}"
            );
        }
        assert!(request(
            &[
                ("fallback_share", Dynamic::from_float(0.5)),
                ("planner", "rrt_floyd".into())
            ],
            "rrt_connect"
        )
        .is_err());
    }

    #[test]
    fn poses_and_boxes_convert_as_script_values() {
        let r = request(
            &[
                (
                    "start",
                    Dynamic::from_array(vec![
                        Dynamic::from_int(1),
                        Dynamic::from_int(2),
                        Dynamic::from_int(3),
                        Dynamic::from_int(0),
                        Dynamic::from_int(0),
                        Dynamic::from_int(90),
                    ]),
                ),
                (
                    "bounds",
                    map(&[
                        ("min", Dynamic::from_array(vec![Dynamic::from_int(-1); 3])),
                        (
                            "max",
                            Dynamic::from_array(vec![Dynamic::from_float(5.0); 3]),
                        ),
                    ]),
                ),
            ],
            "rrt_connect",
        )
        .unwrap();
        let t = r.start.unwrap();
        assert!((t.translation() - crate::math::Vec3::new(1.0, 2.0, 3.0)).norm() < 1e-12);
        assert_eq!(r.bounds.unwrap().hi.x, 5.0);
        let e = request(&[("start", Dynamic::from_int(3))], "rrt").unwrap_err();
        assert!(e.to_string().contains("start"), "{e}");
    }
}
