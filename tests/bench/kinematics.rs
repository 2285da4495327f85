//! Benchmark: forward kinematics and all-branch inverse kinematics of the NACHI MZ07
//! (flange as TCP), fitup against the `rs-opw-kinematics` crate, interleaved in one
//! run (A, B, A, B…), CPU time per call from /proc/thread-self/schedstat, medians.
//!
//! Then the UR5e (UR closed form, offset wrist) against fitup's numeric solver on the
//! same targets: CPU time per call and how many of the 8 branches each finds.
//!
//! Run: `cargo bench --bench kinematics`

use fitup::kinematics::{Catalog, ClosedFormIk, IkOptions, NumericIk, Robot};
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
    ur_against_numeric();
}

/// UR5e: all-branch closed form (`UrSolver::branches`, `Robot::inverse`) against the
/// numeric solver (`NumericIk` with its default 24 restarts and 8 solutions wanted)
/// on the same targets; branch coverage counted modulo 2π.
fn ur_against_numeric() {
    const UR_CALLS: usize = 2_000;
    const NUM_CALLS: usize = 50;
    let ur5e = Catalog::Ur5e.robot();
    let solver = ur5e.ur_solver().expect("UR5e uses the UR solver").clone();
    let mut rng = Rng::new(43);
    let joints: Vec<Vec<f64>> = (0..UR_CALLS)
        .map(|_| (0..6).map(|_| rng.range(-3.0, 3.0)).collect())
        .collect();
    let targets: Vec<Transform> = joints.iter().map(|q| ur5e.tcp_pose(q).unwrap()).collect();
    let opts = IkOptions::default();
    let numeric = NumericIk::from_options(&IkOptions {
        max_solutions: 8,
        ..IkOptions::default()
    });
    let wrap = |a: f64| (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU);
    let same = |a: &[f64], b: &[f64]| {
        a.iter().zip(b).all(|(x, y)| {
            let d = (wrap(*x) - wrap(*y)).abs();
            d.min(std::f64::consts::TAU - d) < 1e-6
        })
    };
    // Coverage on the first NUM_CALLS targets.
    let (mut ur_found, mut num_found, mut num_gen) = (0usize, 0usize, 0usize);
    for (q, t) in joints.iter().zip(&targets).take(NUM_CALLS) {
        let br = solver.branches(t.isometry(), 1e-9);
        ur_found += br.len();
        let sols = numeric.solve(&ur5e, t, &[0.0; 6]).unwrap_or_default();
        let mut distinct: Vec<&[f64]> = Vec::new();
        for s in &sols {
            if !distinct.iter().any(|d| same(d, &s.joints)) {
                distinct.push(&s.joints);
            }
        }
        num_found += distinct.len();
        if distinct.iter().any(|d| same(d, q)) {
            num_gen += 1;
        }
    }
    let (mut br_t, mut inv_t, mut num_t) = (Vec::new(), Vec::new(), Vec::new());
    for round in 0..7 {
        let t0 = cpu_ns();
        for _ in 0..50 {
            for t in &targets {
                black_box(solver.branches(black_box(t.isometry()), 1e-9));
            }
        }
        br_t.push((cpu_ns() - t0) as f64 / (50 * UR_CALLS) as f64);
        let t0 = cpu_ns();
        for _ in 0..10 {
            for (q, t) in joints.iter().zip(&targets) {
                let _ = black_box(ur5e.inverse(black_box(t), q, &opts));
            }
        }
        inv_t.push((cpu_ns() - t0) as f64 / (10 * UR_CALLS) as f64);
        let t0 = cpu_ns();
        for t in targets.iter().take(NUM_CALLS) {
            let _ = black_box(numeric.solve(&ur5e, black_box(t), &[0.0; 6]));
        }
        num_t.push((cpu_ns() - t0) as f64 / NUM_CALLS as f64);
        println!(
            "UR round {round}: branches {:7.1} ns | Robot::inverse {:8.1} ns | numeric {:10.0} ns | loadavg {}",
            br_t[round], inv_t[round], num_t[round], loadavg()
        );
    }
    let (b, i, n) = (median(&mut br_t), median(&mut inv_t), median(&mut num_t));
    println!("\nUR5e, medians over 7 rounds (CPU time per call, one core):");
    println!("| operation | time | branches found (of 8 per target, {NUM_CALLS} targets) |");
    println!("|---|---|---|");
    println!(
        "| UR closed form, all branches (`UrSolver::branches`) | {b:.1} ns | {:.2} |",
        ur_found as f64 / NUM_CALLS as f64
    );
    println!("| `Robot::inverse` (UR, limits ±360°: 512 solutions, sorted) | {i:.1} ns | – |");
    println!(
        "| numeric (`NumericIk`, 24 restarts, up to 8 solutions) | {n:.0} ns | {:.2} (generating config found {num_gen}/{NUM_CALLS}) |",
        num_found as f64 / NUM_CALLS as f64
    );
    println!("loadavg at end: {}", loadavg());
}
