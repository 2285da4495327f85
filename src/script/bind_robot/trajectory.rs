//! The `Trajectory` type of scripts: a sampled motion, its samples' joints
//! (degrees / mm) and TCP poses.

use super::*;

/// Trajectories: samples, joints and TCP poses over time, CSV logs.
pub(super) fn register_trajectory(api: &mut Api) {
    api.section("Trajectory", "A sampled motion: `len` samples at times `0 … duration` (s), each with joint values (degrees / mm) and the TCP pose. Sample indices may be negative (−1 = last).");
    fn sample(t: &TrajectoryHandle, i: i64) -> ScriptResult<&crate::kinematics::TrajectorySample> {
        let n = t.trajectory.samples.len() as i64;
        let k = if i < 0 { n + i } else { i };
        if k < 0 || k >= n {
            return err(format!(
                "sample {i} is out of range: the trajectory has {n} samples"
            ));
        }
        Ok(&t.trajectory.samples[k as usize])
    }
    let deg = |t: &TrajectoryHandle, q: &[f64]| -> Dynamic {
        floats(
            q.iter()
                .zip(
                    t.trajectory
                        .joint_kinds
                        .iter()
                        .map(Some)
                        .chain(std::iter::repeat(None)),
                )
                .map(|(v, k)| {
                    if k == Some(&crate::kinematics::JointKind::Prismatic) {
                        *v
                    } else {
                        v.to_degrees()
                    }
                }),
        )
    };
    api.get(
        "Trajectory.len -> int",
        "Number of samples.",
        |t: &mut TrajectoryHandle| t.trajectory.samples.len() as i64,
    );
    api.get(
        "Trajectory.duration -> float",
        "Duration (s).",
        |t: &mut TrajectoryHandle| t.trajectory.duration(),
    );
    api.f(
        "Trajectory.time(i: int) -> float",
        "Time of sample `i` (s).",
        |t: &mut TrajectoryHandle, i: i64| -> ScriptResult<f64> { Ok(sample(t, i)?.t) },
    );
    api.f(
        "Trajectory.joints(i: int) -> array",
        "Joint values of sample `i` (degrees / mm).",
        move |t: &mut TrajectoryHandle, i: i64| -> ScriptResult<Dynamic> {
            Ok(deg(t, &sample(t, i)?.joints))
        },
    );
    api.f(
        "Trajectory.tcp(i: int) -> Transform",
        "TCP world pose of sample `i` (mm).",
        |t: &mut TrajectoryHandle, i: i64| -> ScriptResult<Transform> { Ok(sample(t, i)?.tcp) },
    );
    api.f(
        "Trajectory.tcp_xyzabc(i: int) -> array",
        "TCP of sample `i` as `[x, y, z, a, b, c]` (mm, degrees, convention `xyz`).",
        |t: &mut TrajectoryHandle, i: i64| -> ScriptResult<Dynamic> {
            Ok(xyzabc_deg(&sample(t, i)?.tcp, AngleConvention::default()))
        },
    );
    fn save_trajectory(t: &TrajectoryHandle, path: &str, overwrite: bool) -> ScriptResult<()> {
        let csv = t.trajectory.to_csv(AngleConvention::default());
        t.ctx.write_output(path, csv.as_bytes(), overwrite)?;
        Ok(())
    }
    api.f("Trajectory.save_csv(path: string)", "Writes the joint/TCP log as CSV inside the project, atomically: `t_s,j1_deg,…,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg`. Refuses to replace a file the project uses or one fitup did not write (see \"What a run writes\" in docs/scripting.md); `#{overwrite: true}` replaces it.", |t: &mut TrajectoryHandle, path: &str| -> ScriptResult<()> {
        save_trajectory(t, path, false)
    });
    api.f(
        "Trajectory.save_csv(path: string, options: map)",
        "`save_csv(path)` with `#{overwrite}` (bool, default false).",
        |t: &mut TrajectoryHandle, path: &str, opts: Map| -> ScriptResult<()> {
            save_trajectory(t, path, overwrite_option(&opts, "save_csv")?)
        },
    );
    api.f(
        "Trajectory.to_string() -> string",
        "`Trajectory(n samples, d s)`.",
        |t: &mut TrajectoryHandle| {
            format!(
                "Trajectory({} samples, {:.3} s)",
                t.trajectory.samples.len(),
                t.trajectory.duration()
            )
        },
    );
}
