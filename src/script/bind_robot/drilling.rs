//! Drilling from scripts: `drill_program` over a hole list, with its options and
//! each hole's outcome as a map (mm, degrees).

use super::*;

/// A hole from a `load_holes` map (`position`, `normal`, optional `id`).
fn hole_arg(v: &Dynamic, i: usize) -> ScriptResult<Hole> {
    let m = v
        .read_lock::<Map>()
        .ok_or_else(|| fail(format!("hole {i} must be a map #{{position, normal}}")))?;
    let get = |k: &str| {
        m.get(k)
            .ok_or_else(|| fail(format!("hole {i} has no `{k}`")))
    };
    let position = vec3(get("position")?, &format!("hole {i} position"))?;
    let normal = vec3(get("normal")?, &format!("hole {i} normal"))?;
    let id = m.get("id").map(|v| v.to_string()).filter(|s| !s.is_empty());
    let line = m
        .get("line")
        .and_then(|v| v.as_int().ok())
        .unwrap_or(0)
        .max(0) as usize;
    Hole::new(id, position.into(), normal, line)
        .ok_or_else(|| fail(format!("hole {i}: the normal is zero")))
}

fn hole_map(h: &Hole) -> Map {
    let mut m = Map::new();
    m.insert(
        "id".into(),
        h.id.clone()
            .map(Dynamic::from)
            .unwrap_or(Dynamic::from(String::new())),
    );
    m.insert("position".into(), array3(&h.position.coords));
    m.insert("normal".into(), array3(&h.normal));
    m.insert("line".into(), Dynamic::from_int(h.line as i64));
    m
}

/// Drilling options from a map (the library's [`Drill`] vocabulary), checked by the
/// library's rule before anything runs; with the `stream` flag.
fn drill_options(m: &Map) -> ScriptResult<(DrillOptions, bool)> {
    let o: Drill = read_options(m, &|_| {})?;
    let d = o.drill_options();
    d.validate().map_err(fail)?;
    Ok((d, o.stream))
}

/// Drilling programs and hole tables (seed 001).
pub(super) fn register_drilling(api: &mut Api, ctx: &Arc<Context>) {
    let dp = |r: &mut RobotHandle, holes: Array, o: Option<&Dynamic>| -> ScriptResult<Map> {
        let m = match o {
            Some(v) => options_map(v, "drilling")?,
            None => Map::new(),
        };
        let (opts, stream) = drill_options(&m)?;
        let holes: Vec<Hole> = holes
            .iter()
            .enumerate()
            .map(|(i, h)| hole_arg(h, i))
            .collect::<ScriptResult<_>>()?;
        let (robot, q) = r.snapshot()?;
        let report = drill_program(&robot, &q, &holes, &opts)
            .map_err(|e| fail(format!("robot `{}`: drill_program: {e}", robot.name())))?;
        let mut rows = Array::new();
        let mut drilled = 0;
        for (h, rep) in holes.iter().zip(&report.holes) {
            let mut row = hole_map(h);
            row.insert("index".into(), Dynamic::from_int(rep.index as i64));
            match &rep.outcome {
                HoleOutcome::Drilled { spin, joints } => {
                    drilled += 1;
                    row.insert("reachable".into(), Dynamic::TRUE);
                    row.insert("reason".into(), Dynamic::from(String::new()));
                    row.insert("spin".into(), Dynamic::from_float(spin.to_degrees()));
                    row.insert("joints".into(), joints_out(&robot, joints));
                }
                HoleOutcome::Unreachable(why) => {
                    row.insert("reachable".into(), Dynamic::FALSE);
                    row.insert("reason".into(), Dynamic::from(why.to_string()));
                }
            }
            rows.push(Dynamic::from_map(row));
        }
        let n = rows.len();
        let t = r.finish(&robot, report.trajectory, stream)?;
        let mut out = Map::new();
        out.insert("trajectory".into(), Dynamic::from(t));
        out.insert("holes".into(), Dynamic::from_array(rows));
        out.insert("drilled".into(), Dynamic::from_int(drilled));
        out.insert("unreachable".into(), Dynamic::from_int(n as i64 - drilled));
        Ok(out)
    };
    api.f("Robot.drill_program(holes: array) -> map", "Drills the holes (from `load_holes`) in order (seed 001 §2.2: travel posture, line to the approach point, align, drill, retract). Returns `#{trajectory, holes, drilled, unreachable}`; each hole row is the hole map plus `index`, `reachable`, `reason` (which step failed and why), and for drilled holes `spin` (degrees) and `joints` at the hole. Unreachable holes are reported, not errors.", move |r: &mut RobotHandle, h: Array| dp(r, h, None));
    api.f(
        "Robot.drill_program(holes: array, options: map) -> map",
        "Drilling with the options of the drilling table below (its own keys and the motion keys).",
        move |r: &mut RobotHandle, h: Array, o: Dynamic| dp(r, h, Some(&o)),
    );
    api.f(
        "Robot.to_string() -> string",
        "`Robot(name: joints …)`.",
        |r: &mut RobotHandle| -> ScriptResult<String> {
            let (robot, q) = r.snapshot()?;
            let j = joints_to_document(&robot, &q)
                .iter()
                .map(|v| format!("{v:.3}"))
                .collect::<Vec<_>>()
                .join(", ");
            Ok(format!("Robot({}: [{j}])", robot.name()))
        },
    );

    let c = ctx.clone();
    api.f("load_holes(path: string) -> array", "Reads a hole table (CSV `id,x,y,z,nx,ny,nz` or `x y z nx ny nz`, mm, `#` comments) inside the project: an array of `#{id, position, normal, line}` (normals unit). The file is a dependency of the run; a bad line is an error naming it.", move |path: &str| -> ScriptResult<Array> {
        let full = c.project.resolve(path).map_err(fail)?;
        c.record_read(&full);
        let text = c.project.read_text(&full, crate::fsutil::FileKind::Table).map_err(|e| fail(format!("{path}: {e}")))?;
        let holes = parse_holes(&c.project.display(&full), &text).map_err(fail)?;
        // Each hole is a map of 4 properties holding two arrays of 3 (`hole_map`).
        crate::script::convert::Sizes {
            arrays: holes.len() * 7,
            maps: holes.len() * 4,
            chars: holes.iter().map(|h| h.id.as_ref().map_or(0, String::len)).sum(),
        }
        .within(&c.limits, &format!("load_holes(\"{path}\") of {} holes", crate::math::format::count(holes.len() as u64)))?;
        Ok(holes.iter().map(|h| Dynamic::from_map(hole_map(h))).collect())
    });
}
