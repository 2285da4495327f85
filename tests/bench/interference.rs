//! `cargo bench --bench interference`: exact pair queries per second on ~10k-triangle
//! parts (colliding, 1 mm near miss, far apart) against python-fcl and coal measured
//! in the same run (interleaved), cells vs exact (time and disagreement per cell
//! size), and continuous vs stepwise sweeps. Figures go to docs/interference.md.
//!
//! The peers run from `.venv/bin/python` when it exists (`pip install python-fcl coal
//! numpy` in `.venv`); without it only fitup is timed. parry3d-f64 (a dev-dependency
//! used only here) runs in this process on the same pairs: mesh–mesh intersection,
//! contact and distance against fitup's own queries, and ray casts (fitup has none).

use fitup::collision::{
    check, contact, interferes, method_disagreement, surface_distance, sweep, Collider, CutCells,
    CutSpec, Method, Motion, Obstacle, PosedPart, SweepMethod, SweepOptions, DEFAULT_TOLERANCE,
};
use fitup::document::file::{ComponentFile, DocumentFile, PartFile};
use fitup::math::{Point3, Rng, Transform, Vec3};
use fitup::mesh::{write_stl, Mesh};
use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

#[path = "../common/fixtures.rs"]
mod fixtures;
#[path = "rhai_timing.rs"]
mod rhai_timing;

const PAIRS: usize = 1000;
const ROUNDS: usize = 5;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn line(p: &Transform) -> String {
    let t = p.translation();
    let q = p.rotation();
    format!("{} {} {} {} {} {} {}", t.x, t.y, t.z, q.w, q.i, q.j, q.k)
}

fn random_pose(rng: &mut Rng, spread: f64) -> Transform {
    let t = Vec3::new(
        rng.range(-spread, spread),
        rng.range(-spread, spread),
        rng.range(-spread, spread),
    );
    Transform::from_parts(t, rng.rotation())
}

fn main() {
    // `FITUP_BENCH_AREA_ONLY=1`: the sliding-contact rows only
    if std::env::var_os("FITUP_BENCH_AREA_ONLY").is_some() {
        area_contacts();
        return;
    }
    script_rows();
    if std::env::var_os("FITUP_BENCH_SCRIPT_ONLY").is_some() {
        return;
    }
    let a_mesh = fixtures::torus(30.0, 10.0, 100, 50); // 10,000 triangles
    let b_mesh = fixtures::sphere(20.0, 100, 51); // 10,000 triangles
    let a = Collider::new(Arc::new(a_mesh.clone())).unwrap();
    let b = Collider::new(Arc::new(b_mesh.clone())).unwrap();
    println!(
        "# parts: torus {} triangles, sphere {} triangles",
        a.triangle_count(),
        b.triangle_count()
    );

    // pose pairs by category
    let mut rng = Rng::new(2024);
    let mut cats: Vec<(&str, Vec<(Transform, Transform)>)> = Vec::new();
    let mut colliding = Vec::new();
    while colliding.len() < PAIRS {
        let (pa, pb) = (random_pose(&mut rng, 5.0), random_pose(&mut rng, 30.0));
        if interferes(&a, &pa, &b, &pb, DEFAULT_TOLERANCE).unwrap() {
            colliding.push((pa, pb));
        }
    }
    cats.push(("colliding", colliding));
    let mut near = Vec::new();
    while near.len() < PAIRS {
        let pa = random_pose(&mut rng, 5.0);
        let rb = rng.rotation();
        let dir = Vec3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
        // place b along dir so that the surfaces are 1 mm apart (bisection)
        let (mut lo, mut hi) = (0.0, 200.0);
        let pose = |s: f64| Transform::from_parts(pa.translation() + dir * s, rb);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            let p = pose(mid);
            let d = surface_distance(&a, &pa, &b, &p, 1.0).unwrap();
            if d < 1.0 || interferes(&a, &pa, &b, &p, 0.0).unwrap() {
                lo = mid
            } else {
                hi = mid
            }
        }
        let p = pose(hi);
        if !interferes(&a, &pa, &b, &p, 0.0).unwrap() {
            near.push((pa, p));
        }
    }
    cats.push(("near_miss_1mm", near));
    let far: Vec<_> = (0..PAIRS)
        .map(|_| {
            let pa = random_pose(&mut rng, 5.0);
            let pb = Transform::from_parts(
                Vec3::new(300.0, rng.range(-50.0, 50.0), 0.0),
                rng.rotation(),
            );
            (pa, pb)
        })
        .collect();
    cats.push(("far", far));

    let dir = tempfile::tempdir().unwrap();
    write_stl(&dir.path().join("a.stl"), &a_mesh).unwrap();
    write_stl(&dir.path().join("b.stl"), &b_mesh).unwrap();
    let mut f = std::fs::File::create(dir.path().join("poses.txt")).unwrap();
    for (cat, pairs) in &cats {
        for (pa, pb) in pairs {
            writeln!(f, "{cat} {} {}", line(pa), line(pb)).unwrap();
        }
    }
    drop(f);
    let python = std::path::Path::new(".venv/bin/python");
    let script = "tests/bench/interference_peers.py";

    let mut ours: Vec<Vec<f64>> = vec![Vec::new(); cats.len()];
    let mut hits = vec![0usize; cats.len()];
    let mut peers: std::collections::BTreeMap<(String, String), (Vec<f64>, String)> =
        Default::default();
    for round in 0..ROUNDS {
        for (k, (_, pairs)) in cats.iter().enumerate() {
            let t0 = Instant::now();
            let mut n = 0;
            for (pa, pb) in pairs {
                n += interferes(&a, pa, &b, pb, DEFAULT_TOLERANCE).unwrap() as usize;
            }
            ours[k].push(t0.elapsed().as_secs_f64() / pairs.len() as f64 * 1e6);
            hits[k] = n;
        }
        if python.exists() {
            let out = std::process::Command::new(python)
                .arg(script)
                .arg(dir.path())
                .output()
                .unwrap();
            for l in String::from_utf8_lossy(&out.stdout).lines() {
                let w: Vec<&str> = l.split_whitespace().collect();
                if w.len() == 4 && !l.starts_with('#') {
                    let e = peers
                        .entry((w[0].to_string(), w[1].to_string()))
                        .or_default();
                    e.0.push(w[2].parse().unwrap_or(f64::NAN));
                    e.1 = w[3].to_string();
                } else if round == 0 {
                    println!("{l}");
                }
            }
        }
        let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
        println!("# round {round} loadavg {}", load.trim());
    }
    println!(
        "\n## exact pair query (interferes), median of {ROUNDS} rounds x {PAIRS} pairs, µs/query"
    );
    println!("| poses | fitup µs | fitup hits | fcl µs | fcl hits | coal µs | coal hits | fcl/fitup | coal/fitup |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for (k, (cat, _)) in cats.iter().enumerate() {
        let o = median(ours[k].clone());
        let get = |p: &str| {
            peers
                .get(&(p.to_string(), cat.to_string()))
                .map(|(v, h)| (median(v.clone()), h.clone()))
        };
        let (f, fh) = get("fcl").unwrap_or((f64::NAN, "-".into()));
        let (c, ch) = get("coal").unwrap_or((f64::NAN, "-".into()));
        println!(
            "| {cat} | {o:.2} | {} | {f:.2} | {fh} | {c:.2} | {ch} | {:.2} | {:.2} |",
            hits[k],
            f / o,
            c / o
        );
    }

    parry_rows(&a_mesh, &b_mesh, &a, &b, &cats);

    area_contacts();
    // `FITUP_BENCH_EXACT_ONLY=1`: the exact pair rows only (the other tables take minutes)
    if std::env::var_os("FITUP_BENCH_EXACT_ONLY").is_none() {
        cells_vs_exact();
        sweeps();
    }
}

/// A screw's shank in a hole of its own diameter meshed with other facets (as two
/// CAD parts meshed apart are): every facet of the shank crosses the hole's by less
/// than the tolerance, so each query climbs from hundreds of shallow crossings to
/// learn that no surface reaches deeper (`interferes`' depth walk). The screw is
/// drawn out 0–4 mm and turned about its axis; every pose is free (asserted).
fn area_contacts() {
    println!("\n## sliding area contact (interferes), median of {ROUNDS} rounds, µs/query");
    println!("| shank / hole facets | triangles | poses | fitup µs |");
    println!("|---|---|---|---|");
    for (ns, nh) in [(48, 64), (192, 256), (768, 1024)] {
        let plate = Collider::new(Arc::new(fixtures::plate_with_hole(20.0, 4.0, 3.0, nh))).unwrap();
        let screw = Collider::new(Arc::new(fixtures::screw(3.0, 4.0, 5.0, 2.0, ns))).unwrap();
        let poses: Vec<Transform> = (0..40)
            .map(|k| {
                let k = f64::from(k);
                let turn = nalgebra::UnitQuaternion::from_axis_angle(&Vec3::z_axis(), 0.037 * k);
                Transform::from_parts(Vec3::new(0.0, 0.0, 0.1 * k), turn)
            })
            .collect();
        let mut times = Vec::new();
        for _ in 0..ROUNDS {
            let t0 = Instant::now();
            for p in &poses {
                let hit =
                    interferes(&screw, p, &plate, &Transform::IDENTITY, DEFAULT_TOLERANCE).unwrap();
                assert!(!hit, "{ns}/{nh} facets: a line-to-line pose interferes");
            }
            times.push(t0.elapsed().as_secs_f64() / poses.len() as f64 * 1e6);
        }
        println!(
            "| {ns} / {nh} | {} + {} | {} | {:.1} |",
            screw.triangle_count(),
            plate.triangle_count(),
            poses.len(),
            median(times)
        );
    }
}

fn cells_vs_exact() {
    println!("\n## cells vs exact: disagreement and time per check");
    // perforated plate with pins near the holes
    let plate = Collider::new(Arc::new(fixtures::perforated_plate(
        (10, 10),
        4.0,
        8.0,
        4.0,
        3.0,
    )))
    .unwrap();
    let pin = Collider::new(Arc::new(Mesh::cylinder(1.5, 12.0, 32))).unwrap();
    let pin_sampler = |r: &mut Rng| {
        let c = |r: &mut Rng| 6.0 + 8.0 * r.below(10) as f64 + r.range(-0.8, 0.8);
        let tilt = fitup::math::AngleConvention::XyzFixed.rotation(
            r.range(-0.05, 0.05),
            r.range(-0.05, 0.05),
            r.range(0.0, 6.3),
        );
        Transform::from_parts(Vec3::new(c(r), c(r), r.range(-8.0, 2.0)), tilt)
    };
    // table + two plates + a screw dropped near a hole
    let table = Collider::new(Arc::new(Mesh::cuboid(
        [-100.0, -100.0, -30.0].into(),
        [100.0, 100.0, 0.0].into(),
    )))
    .unwrap();
    let plate2 = Collider::new(Arc::new(fixtures::plate_with_hole(30.0, 5.0, 3.0, 32))).unwrap();
    let screw = Collider::new(Arc::new(fixtures::screw(2.9, 12.0, 5.0, 3.0, 32))).unwrap();
    let screw_sampler = |r: &mut Rng| {
        let tilt = fitup::math::AngleConvention::XyzFixed.rotation(
            r.range(-0.1, 0.1),
            r.range(-0.1, 0.1),
            r.range(0.0, 6.3),
        );
        Transform::from_parts(
            Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-6.0, 2.0)),
            tilt,
        )
    };
    println!("| scene | cell mm | cells (fixed, moving) | exact hits | cells hits | cells false +/- | aabb false +/- | exact µs | cells µs |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for size in [0.5, 1.0, 2.0, 4.0, 8.0] {
        let pc = match CutCells::derive(&plate, CutSpec::Size(size)) {
            Ok(c) => c,
            Err(e) => {
                println!("| perforated plate + pin | {size} | refused: {e} | | | | | | |");
                continue;
            }
        };
        let nc = CutCells::derive(&pin, CutSpec::Size(size)).unwrap();
        let fixed = [PosedPart {
            collider: &plate,
            cells: Some(&pc),
            pose: Transform::IDENTITY,
        }];
        report(
            "perforated plate + pin",
            size,
            &fixed,
            (&pin, &nc),
            pin_sampler,
            (pc.cells.len(), nc.cells.len()),
        );
        let tc = CutCells::derive(&table, CutSpec::Size(size.max(4.0))).unwrap();
        let p2c = CutCells::derive(&plate2, CutSpec::Size(size)).unwrap();
        let sc = CutCells::derive(&screw, CutSpec::Size(size)).unwrap();
        let fixed = [
            PosedPart {
                collider: &table,
                cells: Some(&tc),
                pose: Transform::from_translation(Vec3::new(0.0, 0.0, -5.0)),
            },
            PosedPart {
                collider: &plate2,
                cells: Some(&p2c),
                pose: Transform::from_translation(Vec3::new(0.0, 0.0, -5.0)),
            },
            PosedPart {
                collider: &plate2,
                cells: Some(&p2c),
                pose: Transform::IDENTITY,
            },
        ];
        report(
            "table + 2 plates + screw",
            size,
            &fixed,
            (&screw, &sc),
            screw_sampler,
            (p2c.cells.len(), sc.cells.len()),
        );
    }
}

fn report(
    name: &str,
    size: f64,
    fixed: &[PosedPart],
    moving: (&Collider, &CutCells),
    sampler: impl Fn(&mut Rng) -> Transform + Copy,
    counts: (usize, usize),
) {
    const N: usize = 2000;
    let d = method_disagreement(
        fixed,
        (moving.0, Some(moving.1)),
        sampler,
        N,
        7,
        DEFAULT_TOLERANCE,
    )
    .unwrap();
    let time = |method: Method| {
        let mut rng = Rng::new(7);
        let t0 = Instant::now();
        for _ in 0..N {
            let m = PosedPart {
                collider: moving.0,
                cells: Some(moving.1),
                pose: sampler(&mut rng),
            };
            for f in fixed {
                std::hint::black_box(check(method, f, &m, DEFAULT_TOLERANCE).unwrap());
            }
        }
        t0.elapsed().as_secs_f64() / N as f64 * 1e6
    };
    let (te, tc) = (time(Method::Exact), time(Method::Cells));
    println!(
        "| {name} | {size} | {} , {} | {} | {} | {} / {} | {} / {} | {te:.1} | {tc:.1} |",
        counts.0,
        counts.1,
        d.exact_interfering,
        d.cells_interfering,
        d.cells_false_positives,
        d.cells_false_negatives,
        d.aabb_false_positives,
        d.aabb_false_negatives
    );
}

fn sweeps() {
    println!("\n## sweeps: thin wall (0.2 mm) crossed by a 1 mm plate moving 20 mm, 200 random wall positions");
    let mover = Collider::new(Arc::new(Mesh::cuboid(
        [0.0, -5.0, -5.0].into(),
        [1.0, 5.0, 5.0].into(),
    )))
    .unwrap();
    let wall = Collider::new(Arc::new(Mesh::cuboid(
        [0.0, -20.0, -20.0].into(),
        [0.2, 20.0, 20.0].into(),
    )))
    .unwrap();
    let ball = Collider::new(Arc::new(fixtures::sphere(5.0, 100, 51))).unwrap();
    let motion = Motion::Translation {
        start: Transform::IDENTITY,
        offset: Vec3::new(20.0, 0.0, 0.0),
    };
    println!("| mover | method | missed | mean t error | µs/sweep |");
    println!("|---|---|---|---|---|");
    for (mname, m) in [("box 12 tris", &mover), ("sphere 10k tris", &ball)] {
        for (name, method) in [
            ("step 5 mm", SweepMethod::displacement_steps(5.0)),
            ("step 1 mm", SweepMethod::displacement_steps(1.0)),
            ("step 0.1 mm", SweepMethod::displacement_steps(0.1)),
            ("continuous", SweepMethod::CONTINUOUS_FINE),
        ] {
            let mut rng = Rng::new(11);
            let (mut missed, mut err, mut n) = (0, 0.0, 0);
            let t0 = Instant::now();
            const RUNS: usize = 200;
            for _ in 0..RUNS {
                let x = rng.range(8.0, 15.0);
                let obstacles = [Obstacle {
                    collider: &wall,
                    pose: Transform::from_translation(Vec3::new(x, 0.0, 0.0)),
                }];
                let h = sweep(
                    m,
                    &motion,
                    &obstacles,
                    &SweepOptions {
                        method,
                        tolerance: DEFAULT_TOLERANCE,
                        ..Default::default()
                    },
                )
                .unwrap();
                // exact first contact: the part's +X extent reaches the wall
                let reach = m.bounds().hi.x;
                let t_true = (x - reach) / 20.0;
                if !h.hit {
                    missed += 1;
                } else {
                    err += (h.t - t_true).abs() * 20.0;
                    n += 1;
                }
            }
            let us = t0.elapsed().as_secs_f64() / RUNS as f64 * 1e6;
            println!(
                "| {mname} | {name} | {missed}/{RUNS} | {:.3} mm | {us:.0} |",
                err / n.max(1) as f64
            );
        }
    }
}

/// Pairs per pose category for the parry comparison, and rounds (median taken).
const PARRY_PAIRS: usize = 200;
const PARRY_ROUNDS: usize = 3;

/// parry3d-f64 against fitup on the same pairs in this process: build, intersection
/// (yes/no), contact, distance, and ray casts (which fitup lacks).
fn parry_rows(
    a_mesh: &Mesh,
    b_mesh: &Mesh,
    a: &Collider,
    b: &Collider,
    cats: &[(&str, Vec<(Transform, Transform)>)],
) {
    use parry3d_f64::math::{Pose, Rot3, Vector};
    use parry3d_f64::query::{self, Ray, RayCast};
    use parry3d_f64::shape::TriMesh;
    let trimesh = |m: &Mesh| {
        let v = m
            .vertices
            .iter()
            .map(|p| Vector::new(p.x, p.y, p.z))
            .collect();
        TriMesh::new(v, m.triangles.clone()).unwrap()
    };
    let ms = |f: &mut dyn FnMut()| {
        let t0 = Instant::now();
        for _ in 0..5 {
            f();
        }
        t0.elapsed().as_secs_f64() / 5.0 * 1e3
    };
    let fitup_build = ms(&mut || {
        std::hint::black_box(Collider::new(Arc::new(a_mesh.clone())).unwrap());
    });
    let parry_build = ms(&mut || {
        std::hint::black_box(trimesh(a_mesh));
    });
    let (sa, sb) = (trimesh(a_mesh), trimesh(b_mesh));
    let pose = |p: &Transform| {
        let t = p.translation();
        let q = p.rotation();
        Pose::from_parts(
            Vector::new(t.x, t.y, t.z),
            Rot3::from_xyzw(q.i, q.j, q.k, q.w),
        )
    };
    println!(
        "\n## parry3d-f64 on the same pairs, in this process: median of {PARRY_ROUNDS} rounds x {PARRY_PAIRS} pairs, µs/query"
    );
    println!(
        "build of the torus (10k triangles): fitup Collider {fitup_build:.2} ms, parry TriMesh {parry_build:.2} ms"
    );
    println!("| poses | query | fitup µs | parry µs | parry/fitup | answers agree |");
    println!("|---|---|---|---|---|---|");
    for (cat, pairs) in cats {
        let pairs = &pairs[..PARRY_PAIRS.min(pairs.len())];
        let pp: Vec<(Pose, Pose)> = pairs.iter().map(|(x, y)| (pose(x), pose(y))).collect();
        // parry's mesh–mesh distance takes 0.1–0.3 s a pair: 10 pairs, one round
        let time = |n: usize, f: &mut dyn FnMut(usize) -> f64| -> (f64, Vec<f64>) {
            let (n, rounds) = if n < pairs.len() {
                (n, 1)
            } else {
                (pairs.len(), PARRY_ROUNDS)
            };
            let mut per = Vec::new();
            let mut out = Vec::new();
            for _ in 0..rounds {
                out.clear();
                let t0 = Instant::now();
                for k in 0..n {
                    out.push(f(k));
                }
                per.push(t0.elapsed().as_secs_f64() / n as f64 * 1e6);
            }
            (median(per), out)
        };
        // (query, fitup (µs, answers), parry (µs, answers), agreement threshold)
        type Timed = (f64, Vec<f64>);
        let rows: [(&str, Timed, Timed, f64); 3] = [
            (
                "intersection yes/no",
                time(usize::MAX, &mut |k| {
                    let (x, y) = &pairs[k];
                    interferes(a, x, b, y, DEFAULT_TOLERANCE).unwrap() as u8 as f64
                }),
                time(usize::MAX, &mut |k| {
                    let (x, y) = &pp[k];
                    query::intersection_test(x, &sa, y, &sb)
                        .unwrap()
                        .intersecting as u8 as f64
                }),
                0.5,
            ),
            (
                "contact (fitup: verdict + depth; parry: deepest point pair)",
                time(usize::MAX, &mut |k| {
                    let (x, y) = &pairs[k];
                    (contact(a, x, b, y, DEFAULT_TOLERANCE).unwrap()
                        != fitup::collision::Contact::Separate) as u8 as f64
                }),
                time(usize::MAX, &mut |k| {
                    let (x, y) = &pp[k];
                    query::contact(x, &sa, y, &sb, 0.0).unwrap().is_some() as u8 as f64
                }),
                0.5,
            ),
            (
                "distance",
                time(10, &mut |k| {
                    let (x, y) = &pairs[k];
                    surface_distance(a, x, b, y, 0.0).unwrap()
                }),
                time(10, &mut |k| {
                    let (x, y) = &pp[k];
                    query::distance(x, &sa, y, &sb).unwrap().distance
                }),
                1e-6,
            ),
        ];
        for (name, (tf, af), (tp, ap), within) in rows {
            let agree = af
                .iter()
                .zip(&ap)
                .filter(|(x, y)| (*x - *y).abs() < within)
                .count();
            println!(
                "| {cat} | {name} | {tf:.2} | {tp:.2} | {:.2} | {agree}/{} |",
                tp / tf,
                af.len()
            );
        }
    }
    // rays from a sphere of radius 150 mm at points near the torus (picking)
    let mut rng = Rng::new(5);
    let rays: Vec<Ray> = (0..10_000)
        .map(|_| {
            let o = Vec3::new(rng.normal(), rng.normal(), rng.normal()).normalize() * 150.0;
            let t = Vec3::new(
                rng.range(-40.0, 40.0),
                rng.range(-40.0, 40.0),
                rng.range(-10.0, 10.0),
            );
            let d = (t - o).normalize();
            Ray::new(Vector::new(o.x, o.y, o.z), Vector::new(d.x, d.y, d.z))
        })
        .collect();
    let at = Pose::from_translation(Vector::new(0.0, 0.0, 0.0));
    let t0 = Instant::now();
    let hits = rays
        .iter()
        .filter(|r| sa.cast_ray(&at, r, f64::MAX, true).is_some())
        .count();
    let us = t0.elapsed().as_secs_f64() / rays.len() as f64 * 1e6;
    println!(
        "ray casts at the torus (fitup has no ray query): parry {us:.2} µs/ray, {hits}/{} hit",
        rays.len()
    );
}

/// Rounds over the script case's poses per timed script run.
const SCRIPT_ROUNDS: usize = 20;

/// Issue 12's case from a script: a 6000-triangle torus against a 12-triangle box
/// at 600 seeded random poses, split into separated and interfering poses:
/// `doc.interferes` (the yes/no query, stops at the first crossing deeper than the
/// tolerance) and `doc.contact` (the full verdict with the deepest crossing) from
/// Rhai, the same two queries in Rust, and python-fcl / coal `collide` from Python
/// on the same meshes and poses, in the same run.
fn script_rows() {
    let torus = fixtures::torus(20.0, 5.0, 100, 30); // 6000 triangles
    let cube = Mesh::cuboid(
        Point3::new(-15.0, -15.0, -15.0),
        Point3::new(15.0, 15.0, 15.0),
    );
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    std::fs::create_dir_all(root.join("models/meshes")).unwrap();
    std::fs::create_dir_all(root.join("scripts")).unwrap();
    write_stl(&root.join("models/meshes/torus.stl"), &torus).unwrap();
    write_stl(&root.join("models/meshes/box.stl"), &cube).unwrap();
    let mut file = DocumentFile {
        units: "mm".into(),
        ..Default::default()
    };
    for name in ["torus", "box"] {
        file.parts.insert(
            name.into(),
            PartFile::from_stl(format!("meshes/{name}.stl")),
        );
        file.components.push(ComponentFile::new(name, name, None));
    }
    std::fs::write(root.join("models/pair.yaml"), file.to_yaml().unwrap()).unwrap();

    // the meshes as the document has them (read back from the STL files: f32
    // coordinates, welded), so the Rust rows query the same trees as the script
    let read = |name: &str| {
        let path = root.join(format!("models/meshes/{name}.stl"));
        Collider::new(Arc::new(fitup::mesh::read_stl(&path).unwrap())).unwrap()
    };
    let (a, b) = (read("torus"), read("box"));
    let id = Transform::IDENTITY;
    let mut rng = Rng::new(12);
    let (mut apart, mut crossing) = (Vec::new(), Vec::new());
    for _ in 0..600 {
        let p = random_pose(&mut rng, 40.0);
        if interferes(&a, &p, &b, &id, DEFAULT_TOLERANCE).unwrap() {
            crossing.push(p);
        } else {
            apart.push(p);
        }
    }
    println!(
        "# script case: torus {} triangles, box {} triangles, 600 poses: {} separated, {} interfering",
        a.triangle_count(),
        b.triangle_count(),
        apart.len(),
        crossing.len()
    );
    let peers_dir = root.join("peers");
    std::fs::create_dir_all(&peers_dir).unwrap();
    write_stl(&peers_dir.join("a.stl"), &torus).unwrap();
    write_stl(&peers_dir.join("b.stl"), &cube).unwrap();
    let mut f = std::fs::File::create(peers_dir.join("poses.txt")).unwrap();
    for (cat, poses) in [("separated", &apart), ("interfering", &crossing)] {
        for p in poses {
            writeln!(f, "{cat} {} {}", line(p), line(&id)).unwrap();
        }
    }
    drop(f);

    let rhai_seconds = |body: &str| rhai_timing::rhai_seconds(root, body);
    let script_for = |poses: &[Transform], call: &str| {
        let list: Vec<String> = poses
            .iter()
            .map(|p| {
                let rows: Vec<String> = p
                    .to_matrix()
                    .iter()
                    .map(|r| {
                        let v: Vec<String> = r.iter().map(|x| format!("{x:.15}")).collect();
                        format!("[{}]", v.join(", "))
                    })
                    .collect();
                format!("[{}]", rows.join(", "))
            })
            .collect();
        format!(
            "let d = open_doc(\"models/pair.yaml\");\n\
             let ts = []; for m in [{}] {{ ts.push(transform(m)); }}\n\
             let w = d.contact(\"torus\", \"box\");\n\
             for r in 0..{SCRIPT_ROUNDS} {{ for t in ts {{ d.set_transform(\"torus\", t); {call} }} }}\n",
            list.join(", ")
        )
    };
    let python = std::path::Path::new(".venv/bin/python");
    let mut rows: std::collections::BTreeMap<(&str, String), Vec<f64>> = Default::default();
    let mut peer_hits: std::collections::BTreeMap<(String, String), String> = Default::default();
    for round in 0..ROUNDS {
        for (cat, poses) in [("separated", &apart), ("interfering", &crossing)] {
            let calls = (poses.len() * SCRIPT_ROUNDS) as f64;
            let base = rhai_seconds(&script_for(poses, ""));
            for (label, call) in [
                (
                    "script doc.interferes",
                    "let x = d.interferes(\"torus\", \"box\");",
                ),
                (
                    "script doc.contact",
                    "let x = d.contact(\"torus\", \"box\");",
                ),
            ] {
                let t = rhai_seconds(&script_for(poses, call));
                rows.entry((cat, label.into()))
                    .or_default()
                    .push((t - base) / calls * 1e6);
            }
            let t0 = Instant::now();
            let mut n = 0;
            for p in poses.iter() {
                n += interferes(&a, p, &b, &id, DEFAULT_TOLERANCE).unwrap() as usize;
            }
            rows.entry((cat, "Rust collision::interferes".into()))
                .or_default()
                .push(t0.elapsed().as_secs_f64() / poses.len() as f64 * 1e6);
            assert_eq!(n, if cat == "separated" { 0 } else { poses.len() });
            let t0 = Instant::now();
            for p in poses.iter() {
                let c = contact(&a, p, &b, &id, DEFAULT_TOLERANCE).unwrap();
                assert_eq!(c.is_interfering(), cat == "interfering");
            }
            rows.entry((cat, "Rust collision::contact".into()))
                .or_default()
                .push(t0.elapsed().as_secs_f64() / poses.len() as f64 * 1e6);
        }
        if python.exists() {
            let out = std::process::Command::new(python)
                .arg("tests/bench/interference_peers.py")
                .arg(&peers_dir)
                .output()
                .unwrap();
            for l in String::from_utf8_lossy(&out.stdout).lines() {
                let w: Vec<&str> = l.split_whitespace().collect();
                if w.len() == 4 && !l.starts_with('#') {
                    let cat = if w[1] == "separated" {
                        "separated"
                    } else {
                        "interfering"
                    };
                    rows.entry((cat, format!("Python {} collide", w[0])))
                        .or_default()
                        .push(w[2].parse().unwrap_or(f64::NAN));
                    peer_hits.insert((w[0].to_string(), cat.to_string()), w[3].to_string());
                } else if round == 0 {
                    println!("{l}");
                }
            }
        }
        let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
        println!("# script case round {round} loadavg {}", load.trim());
    }
    println!("\n## issue 12 script case, median of {ROUNDS} rounds, µs per pose");
    println!("| query | separated µs | interfering µs |");
    println!("|---|---:|---:|");
    let labels: std::collections::BTreeSet<String> = rows.keys().map(|(_, l)| l.clone()).collect();
    for label in labels {
        let get = |cat: &str| {
            rows.get(&(cat, label.clone()))
                .map_or(f64::NAN, |v| median(v.clone()))
        };
        println!(
            "| {label} | {:.2} | {:.2} |",
            get("separated"),
            get("interfering")
        );
    }
    for ((peer, cat), hits) in &peer_hits {
        println!("# {peer} {cat}: {hits} collisions reported");
    }
}
