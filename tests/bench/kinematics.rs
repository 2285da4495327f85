//! Benchmark: forward kinematics and all-branch inverse kinematics of the NACHI MZ07
//! (flange as TCP), fitup against the `rs-opw-kinematics` crate, interleaved in one
//! run (A, B, A, B…), CPU time per call from /proc/thread-self/schedstat, medians.
//!
//! Run: `cargo bench --bench kinematics`

use fitup::kinematics::{Catalog, IkOptions, Robot};
use fitup::math::{Rng, Transform};
use rs_opw_kinematics::kinematic_traits::Kinematics;
use rs_opw_kinematics::kinematics_impl::OPWKinematics;
use rs_opw_kinematics::parameters::opw_kinematics::Parameters;
use std::hint::black_box;

const CALLS: usize = 20_000;
const ROUNDS: usize = 15;
const IK_REPS: usize = 10;
const FK_REPS: usize = 50;

/// CPU time of this thread (ns), wall time as a fallback.
fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse().ok()))
        .unwrap_or_else(|| {
            use std::time::{SystemTime, UNIX_EPOCH};
            SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map(|d| d.as_nanos() as u64)
                .unwrap_or(0)
        })
}

/// CPU time per call of `reps` passes over the `CALLS` inputs. The kernel accounts
/// CPU time in scheduler ticks (4 ms here), so each measurement runs ≥ 0.1 s.
fn per_call(reps: usize, f: &mut dyn FnMut()) -> f64 {
    let t0 = cpu_ns();
    for _ in 0..reps {
        f();
    }
    (cpu_ns() - t0) as f64 / (CALLS * reps) as f64
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .unwrap_or_default()
        .trim()
        .to_string()
}

fn main() {
    // fitup: the catalog MZ07 with the tool at the flange (80 mm from the wrist centre).
    let mz07 = Catalog::NachiMz07.robot().with_tool(Transform::IDENTITY);
    let solver = mz07
        .analytic()
        .expect("MZ07 qualifies for the closed form")
        .clone();
    // rs-opw-kinematics: the same geometry in its parameter form (mm).
    let peer = OPWKinematics::new(Parameters {
        a1: 50.0,
        a2: -45.0,
        b: 0.0,
        c1: 340.0,
        c2: 330.0,
        c3: 340.0,
        c4: 80.0,
        offsets: [0.0; 6],
        sign_corrections: [1; 6],
        dof: 6,
    });

    let mut rng = Rng::new(42);
    let joints: Vec<[f64; 6]> = (0..CALLS)
        .map(|_| {
            let mut q = [0.0; 6];
            for v in &mut q {
                *v = rng.range(-1.5, 1.5);
            }
            q
        })
        .collect();
    let ours: Vec<_> = joints.iter().map(|q| solver.forward(q)).collect();
    let theirs: Vec<_> = joints.iter().map(|q| peer.forward(q)).collect();

    // Sanity: both solvers return branches for their own poses.
    let n_ours: usize = ours
        .iter()
        .take(1000)
        .map(|t| solver.branches(t, 1e-9).len())
        .sum();
    let n_theirs: usize = theirs
        .iter()
        .take(1000)
        .map(|t| peer.inverse(t).len())
        .sum();
    println!(
        "branches per pose (first 1000): fitup {:.2}, rs-opw-kinematics {:.2}",
        n_ours as f64 / 1000.0,
        n_theirs as f64 / 1000.0
    );

    let mut ik_a: Vec<f64> = Vec::with_capacity(ROUNDS);
    let (mut ik_b, mut fk_a, mut fk_b, mut fk_tree, mut ik_full) = (
        ik_a.clone(),
        ik_a.clone(),
        ik_a.clone(),
        ik_a.clone(),
        ik_a.clone(),
    );
    let opts = IkOptions::default();
    let robot: &Robot = &mz07;
    for round in 0..ROUNDS {
        ik_a.push(per_call(IK_REPS, &mut || {
            for t in &ours {
                black_box(solver.branches(black_box(t), 1e-9));
            }
        }));
        ik_b.push(per_call(IK_REPS, &mut || {
            for t in &theirs {
                black_box(peer.inverse(black_box(t)));
            }
        }));
        fk_a.push(per_call(FK_REPS, &mut || {
            for q in &joints {
                black_box(solver.forward(black_box(q)));
            }
        }));
        fk_b.push(per_call(FK_REPS, &mut || {
            for q in &joints {
                black_box(peer.forward(black_box(q)));
            }
        }));
        fk_tree.push(per_call(FK_REPS, &mut || {
            for q in &joints {
                let _ = black_box(robot.tcp_pose(black_box(q)));
            }
        }));
        ik_full.push(per_call(IK_REPS, &mut || {
            for (q, t) in joints.iter().zip(&ours) {
                let _ = black_box(robot.inverse(&Transform::from_isometry(*t), q, &opts));
            }
        }));
        println!(
            "round {round:2}: IK fitup {:7.1} ns, peer {:7.1} ns | FK fitup {:6.1} ns, peer {:6.1} ns | tree FK {:6.1} ns | Robot::inverse {:7.1} ns | loadavg {}",
            ik_a[round], ik_b[round], fk_a[round], fk_b[round], fk_tree[round], ik_full[round], loadavg()
        );
    }
    let (ia, ib, fa, fb) = (
        median(&mut ik_a),
        median(&mut ik_b),
        median(&mut fk_a),
        median(&mut fk_b),
    );
    let (ft, ifull) = (median(&mut fk_tree), median(&mut ik_full));
    println!("\nmedians over {ROUNDS} rounds (IK {} calls, FK {} calls per measurement) (CPU time per call, one core):", CALLS * IK_REPS, CALLS * FK_REPS);
    println!("| operation | fitup | rs-opw-kinematics | ratio (peer / fitup) |");
    println!("|---|---|---|---|");
    println!(
        "| all-branch IK (closed form, up to 8 branches) | {ia:.1} ns | {ib:.1} ns | {:.2} |",
        ib / ia
    );
    println!(
        "| FK (closed form) | {fa:.1} ns | {fb:.1} ns | {:.2} |",
        fb / fa
    );
    println!("| FK (generic tree walk, Robot::tcp_pose) | {ft:.1} ns | – | – |");
    println!("| Robot::inverse (limits, ±360° variants, sorted Vec) | {ifull:.1} ns | – | – |");
    println!("loadavg at end: {}", loadavg());
}
