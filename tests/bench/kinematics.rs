//! Benchmark: forward kinematics and all-branch inverse kinematics of the NACHI MZ07
//! (flange as TCP), fitup against the `rs-opw-kinematics` crate, interleaved in one
//! run (A, B, A, B…), CPU time per call from /proc/thread-self/schedstat, medians.
//!
//! With `FITUP_OPW_KIN_SRC` naming the C++ opw_kinematics include folder, its
//! `inverse()` joins the MZ07 rounds (compiled at bench time, timed inside its driver).
//!
//! Then the UR5e (UR closed form, offset wrist): with `FITUP_UR_KIN_SRC` naming the
//! universal_robot checkout (tests/bench/ur_reference.sh), against ROS-Industrial's
//! `ur_kin.cpp` `inverse()` (compiled at bench time with -O2 for `UR5e_PARAMS`,
//! timed inside its driver) interleaved in the same run, each solving poses made by
//! its own FK; then against fitup's numeric solver on the same targets: CPU time per
//! call and how many of the 8 branches each finds. Neither reference is committed.
//!
//! Run: `FITUP_UR_KIN_SRC=… FITUP_OPW_KIN_SRC=… cargo bench --no-default-features --bench kinematics`

use fitup::kinematics::{Catalog, ClosedFormIk, IkOptions, NumericIk, Robot};
use fitup::math::{Rng, Transform};
use rs_opw_kinematics::kinematic_traits::Kinematics;
use rs_opw_kinematics::kinematics_impl::OPWKinematics;
use rs_opw_kinematics::parameters::opw_kinematics::Parameters;
use std::hint::black_box;

#[path = "../common/kin_driver.rs"]
mod kin_driver;
#[path = "../common/opw_kin.rs"]
mod opw_kin;
#[path = "../common/ur_kin.rs"]
mod ur_kin;

const CALLS: usize = 20_000;
const ROUNDS: usize = 15;
const IK_REPS: usize = 10;
const FK_REPS: usize = 50;
/// Targets handed to a C++ peer's driver, and its passes over them per measurement.
const PEER_CALLS: usize = 2_000;
const PEER_REPS: usize = 100;

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
    // `FITUP_KIN_BENCH=ur`: only the UR5e against ur_kin.cpp (for profiling).
    if std::env::var("FITUP_KIN_BENCH").is_ok_and(|v| v == "ur") {
        let out_dir = std::env::temp_dir().join(format!("fitup-kin-bench-{}", std::process::id()));
        ur_against_ur_kin(&out_dir);
        let _ = std::fs::remove_dir_all(&out_dir);
        return;
    }
    // `FITUP_KIN_BENCH=opw`: only the MZ07 IK against C++ opw_kinematics (for profiling
    // and before/after runs).
    let opw_only = std::env::var("FITUP_KIN_BENCH").is_ok_and(|v| v == "opw");
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

    // The C++ opw_kinematics, when its include folder is named: the same parameters,
    // poses from its own FK (the first PEER_CALLS joint vectors), timed in its driver.
    let out_dir = std::env::temp_dir().join(format!("fitup-kin-bench-{}", std::process::id()));
    let mut opw_cpp = opw_kin::source().and_then(|src| {
        opw_kin::build(
            &src,
            [50.0, -45.0, 0.0, 340.0, 330.0, 340.0, 80.0],
            &out_dir,
        )
        .map_err(|e| eprintln!("opw_kinematics: {e}"))
        .ok()
    });
    let cpp_targets: Vec<[f64; 16]> = match &mut opw_cpp {
        Some(p) => joints.iter().take(PEER_CALLS).map(|q| p.fk(q)).collect(),
        None => Vec::new(),
    };
    if let Some(p) = &mut opw_cpp {
        let n: usize = cpp_targets.iter().take(1000).map(|t| p.ik(t).len()).sum();
        println!(
            "branches per pose (first 1000): C++ opw_kinematics {:.2}",
            n as f64 / 1000.0
        );
    }
    let mut ik_cpp: Vec<f64> = Vec::new();

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
        if opw_only {
            if let Some(p) = &mut opw_cpp {
                ik_cpp.push(p.bench(PEER_REPS, &cpp_targets).0);
            }
            println!(
                "round {round:2}: IK fitup {:7.1} ns, C++ opw_kinematics {:7.1} ns | loadavg {}",
                ik_a[round],
                ik_cpp.last().copied().unwrap_or(f64::NAN),
                loadavg()
            );
            continue;
        }
        ik_b.push(per_call(IK_REPS, &mut || {
            for t in &theirs {
                black_box(peer.inverse(black_box(t)));
            }
        }));
        if let Some(p) = &mut opw_cpp {
            ik_cpp.push(p.bench(PEER_REPS, &cpp_targets).0);
        }
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
    if opw_only {
        if ik_cpp.is_empty() {
            ik_cpp.push(f64::NAN); // no peer
        }
        let ic = median(&mut ik_cpp);
        let ia = median(&mut ik_a);
        let (lo, hi) = (ik_a[0], ik_a[ROUNDS - 1]);
        println!(
            "\nMZ07 all-branch IK, medians over {ROUNDS} rounds: fitup {ia:.1} ns (rounds {lo:.1}–{hi:.1}), C++ opw_kinematics {ic:.1} ns ({:.1}–{:.1}): peer / fitup {:.3}; loadavg at end: {}",
            ik_cpp[0],
            ik_cpp[ik_cpp.len() - 1],
            ic / ia,
            loadavg()
        );
        drop(opw_cpp);
        let _ = std::fs::remove_dir_all(&out_dir);
        return;
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
    if !ik_cpp.is_empty() {
        let ic = median(&mut ik_cpp);
        println!(
            "| all-branch IK, C++ opw_kinematics (same rounds) | {ia:.1} ns | {ic:.1} ns | {:.2} |",
            ic / ia
        );
    }
    println!("| FK (generic tree walk, Robot::tcp_pose) | {ft:.1} ns | – | – |");
    println!("| Robot::inverse (limits, ±360° variants, sorted Vec) | {ifull:.1} ns | – | – |");
    println!("loadavg at end: {}", loadavg());
    drop(opw_cpp);
    ur_against_ur_kin(&out_dir);
    let _ = std::fs::remove_dir_all(&out_dir);
    ur_against_numeric();
}

/// UR5e: fitup's all-branch closed form (`UrSolver::branches`) against ROS-Industrial's
/// `ur_kin.cpp` `inverse()` (every solution in [0, 2π)), interleaved rounds, each on
/// poses made by its own FK from the same joint vectors; skipped without
/// `FITUP_UR_KIN_SRC`.
fn ur_against_ur_kin(out_dir: &std::path::Path) {
    let mut peer = ur_kin::source().and_then(|src| {
        ur_kin::build(&src, "UR5e", out_dir)
            .map_err(|e| eprintln!("ur_kin.cpp: {e}"))
            .ok()
    });
    let ur5e = Catalog::Ur5e.robot();
    let solver = ur5e.ur_solver().expect("UR5e uses the UR solver").clone();
    let mut rng = Rng::new(44);
    let joints: Vec<[f64; 6]> = (0..PEER_CALLS)
        .map(|_| {
            let mut q = [0.0; 6];
            for v in &mut q {
                *v = rng.range(-std::f64::consts::PI, std::f64::consts::PI);
            }
            q
        })
        .collect();
    let ours: Vec<_> = joints.iter().map(|q| solver.forward(q)).collect();
    let theirs: Vec<[f64; 16]> = match &mut peer {
        Some(p) => joints.iter().map(|q| p.fk(q)).collect(),
        None => Vec::new(),
    };
    let n_ours: usize = ours.iter().map(|t| solver.branches(t, 1e-9).len()).sum();
    // Each solves its own poses: the generating joints must be among the answers.
    let wrap = |a: f64| {
        let r = a.rem_euclid(std::f64::consts::TAU);
        r.min(std::f64::consts::TAU - r)
    };
    let found = |sols: &[[f64; 6]], q: &[f64; 6]| {
        sols.iter()
            .any(|s| s.iter().zip(q).all(|(a, b)| wrap(a - b) < 1e-6))
    };
    let gen_ours = joints
        .iter()
        .zip(&ours)
        .filter(|(q, t)| {
            let br = solver.branches(t, 1e-9);
            let sols: Vec<[f64; 6]> = br.as_slice().iter().map(|b| b.joints).collect();
            found(&sols, q)
        })
        .count();
    println!(
        "\nUR5e, {PEER_CALLS} poses: fitup {:.2} solutions per pose, generating joints found {gen_ours}",
        n_ours as f64 / PEER_CALLS as f64
    );
    if let Some(p) = &mut peer {
        let n_theirs: usize = theirs.iter().map(|t| p.ik(t).len()).sum();
        let gen_theirs = joints
            .iter()
            .zip(&theirs)
            .filter(|(q, t)| found(&p.ik(t), q))
            .count();
        println!(
            "ur_kin.cpp {:.2} solutions per pose, generating joints found {gen_theirs}",
            n_theirs as f64 / PEER_CALLS as f64
        );
    }
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for round in 0..ROUNDS {
        let t0 = cpu_ns();
        for _ in 0..PEER_REPS {
            for t in &ours {
                black_box(solver.branches(black_box(t), 1e-9));
            }
        }
        a.push((cpu_ns() - t0) as f64 / (PEER_REPS * PEER_CALLS) as f64);
        if let Some(p) = &mut peer {
            b.push(p.bench(PEER_REPS, &theirs).0);
        }
        println!(
            "UR round {round:2}: UrSolver::branches {:7.1} ns | ur_kin.cpp inverse() {:7.1} ns | loadavg {}",
            a[round],
            b.last().copied().unwrap_or(f64::NAN),
            loadavg()
        );
    }
    let ma = median(&mut a);
    let mb = if b.is_empty() {
        f64::NAN
    } else {
        median(&mut b)
    };
    let (lo, hi) = (a[0], a[ROUNDS - 1]);
    println!(
        "\nUR5e, medians over {ROUNDS} rounds of {} calls (CPU time per call, one core):",
        PEER_REPS * PEER_CALLS
    );
    println!("| operation | fitup | ur_kin.cpp | ratio (peer / fitup) |");
    println!("|---|---|---|---|");
    println!(
        "| all-branch IK, UR closed form | {ma:.1} ns (rounds {lo:.1}–{hi:.1}) | {mb:.1} ns | {:.2} |",
        mb / ma
    );
    println!("loadavg at end: {}", loadavg());
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
