//! Robot calls from scripts against the same calls in Rust, in one run: FK
//! (`arm.fk(q)` vs `Robot::tcp_pose`), nearest IK (`arm.ik_near(t, q)` vs
//! `Robot::inverse_nearest`) and the batch forms (`fk_many`, `ik_many`), on the demo
//! MZ07 document. Script figures subtract an empty loop of the same shape.
//!
//! Run: `cargo bench --bench robot_script`

use fitup::kinematics::IkOptions;
#[path = "demo_mz07.rs"]
mod demo_mz07;
#[path = "rhai_timing.rs"]
mod rhai_timing;

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

const N: usize = 20_000;
const ROUNDS: usize = 7;
const BATCH: usize = 10;

const SETUP: &str = r#"let d = open_doc("models/mz07.yaml");
let arm = d.robot("mz07");
let q = [10.0, -20.0, 30.0, 40.0, -50.0, 60.0];
let t = arm.fk(q);
"#;

/// The script `body` after [`SETUP`].
fn rhai_seconds(dir: &Path, body: &str) -> f64 {
    rhai_timing::rhai_seconds(dir, &format!("{SETUP}{body}\n"))
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let (dir, robot, q, target) = demo_mz07::demo_mz07();
    let opts = IkOptions::default();
    let empty = format!("for i in 0..{N} {{ let x = q; }}");
    let fk = format!("for i in 0..{N} {{ let x = arm.fk(q); }}");
    let ik = format!("for i in 0..{N} {{ let x = arm.ik_near(t, q); }}");
    // Batch forms: one array of N entries, the batch call repeated BATCH times, minus
    // the same script without the calls.
    let fk_many = format!(
        "let qs = []; for i in 0..{N} {{ qs.push(q); }}\nfor k in 0..{BATCH} {{ let x = arm.fk_many(qs); }}"
    );
    let fk_many_empty = format!(
        "let qs = []; for i in 0..{N} {{ qs.push(q); }}\nfor k in 0..{BATCH} {{ let x = 0; }}"
    );
    let ik_many = format!(
        "let ts = []; for i in 0..{N} {{ ts.push(t); }}\nfor k in 0..{BATCH} {{ let x = arm.ik_many(ts); }}"
    );
    let ik_many_empty = format!(
        "let ts = []; for i in 0..{N} {{ ts.push(t); }}\nfor k in 0..{BATCH} {{ let x = 0; }}"
    );
    let (mut r_fk, mut r_ik, mut s_fk, mut s_ik, mut s_fkm, mut s_ikm) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    for _ in 0..ROUNDS {
        let t0 = Instant::now();
        for _ in 0..N {
            black_box(robot.tcp_pose(black_box(&q)).unwrap());
        }
        r_fk.push(t0.elapsed().as_secs_f64() / N as f64 * 1e9);
        let t0 = Instant::now();
        for _ in 0..N {
            black_box(
                robot
                    .inverse_nearest(black_box(&target), &q, &opts)
                    .unwrap(),
            );
        }
        r_ik.push(t0.elapsed().as_secs_f64() / N as f64 * 1e9);
        let e = rhai_seconds(dir.path(), &empty);
        s_fk.push((rhai_seconds(dir.path(), &fk) - e) / N as f64 * 1e9);
        s_ik.push((rhai_seconds(dir.path(), &ik) - e) / N as f64 * 1e9);
        let e = rhai_seconds(dir.path(), &fk_many_empty);
        s_fkm.push((rhai_seconds(dir.path(), &fk_many) - e) / (N * BATCH) as f64 * 1e9);
        let e = rhai_seconds(dir.path(), &ik_many_empty);
        s_ikm.push((rhai_seconds(dir.path(), &ik_many) - e) / (N * BATCH) as f64 * 1e9);
    }
    let (rf, ri) = (median(&mut r_fk), median(&mut r_ik));
    let (sf, si) = (median(&mut s_fk), median(&mut s_ik));
    let (sfm, sim) = (median(&mut s_fkm), median(&mut s_ikm));
    println!("medians over {ROUNDS} rounds, {N} calls each (ns per call, wall clock):");
    println!("| call | Rust | script | script / Rust |");
    println!("|---|---|---|---|");
    println!(
        "| FK `arm.fk(q)` vs `Robot::tcp_pose` | {rf:.0} | {sf:.0} | {:.2} |",
        sf / rf
    );
    println!(
        "| FK `arm.fk_many(qs)` per pose | {rf:.0} | {sfm:.0} | {:.2} |",
        sfm / rf
    );
    println!(
        "| IK `arm.ik_near(t, q)` vs `Robot::inverse_nearest` | {ri:.0} | {si:.0} | {:.2} |",
        si / ri
    );
    println!(
        "| IK `arm.ik_many(ts)` per pose | {ri:.0} | {sim:.0} | {:.2} |",
        sim / ri
    );
    println!(
        "loadavg: {}",
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}
