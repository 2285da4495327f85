//! Scale: a generated cell of N distinct parts of ~10k triangles each (solids of
//! revolution on a grid, neighbours overlapping), measured as a user opens and checks
//! it: open the document (YAML + STL), the first full interference pass (every
//! collider built), a repeat pass (nothing moved: colliders and pair verdicts
//! reused), a pass after every component moved (trees reused, every pair
//! rechecked), the CPU time of open + first pass (all threads: comparable under
//! load, unlike the wall times) and the resident memory.
//!
//! `cargo bench --bench scale` prints the table for 10 → 200 parts, each row in a
//! fresh process (so resident memory is that row's); `-- --parts 100` runs one row.
//! Figures and goals are in docs/performance.md.

use fitup::collision::{Method, DEFAULT_TOLERANCE};
use fitup::document::file::{ComponentFile, DocumentFile, PartFile};
use fitup::document::Document;
use fitup::math::{Transform, Vec3};
use fitup::mesh::{write_stl, Mesh};
use fitup::workspace::{Scene, SceneCache};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// Facets around each part.
const SEGMENTS: usize = 100;
/// Profile points of each part (≈ 2 · SEGMENTS · PROFILE triangles = 10k).
const PROFILE: usize = 50;
/// Grid pitch (mm): parts are ~52 mm across, so grid neighbours overlap.
const PITCH: f64 = 48.0;

/// Part `i`: a bulging solid of revolution whose profile depends on `i`, so no two
/// parts share a mesh.
fn part_mesh(i: usize) -> Mesh {
    let h = 60.0 + (i % 17) as f64;
    let r = 24.0 + (i % 7) as f64 * 0.3;
    let mut profile = vec![(0.0, 0.0)];
    for k in 0..PROFILE {
        let s = (k as f64 + 0.5) / PROFILE as f64;
        let bulge = 1.0 + 0.08 * (std::f64::consts::TAU * s * (1.0 + (i % 5) as f64)).sin();
        profile.push((r * bulge, h * s));
    }
    profile.push((0.0, h));
    Mesh::lathe(&profile, SEGMENTS).expect("lathe profile")
}

fn write_cell(dir: &Path, parts: usize) -> (std::path::PathBuf, usize) {
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    let mut file = DocumentFile {
        units: "mm".into(),
        description: Some(format!("scale bench: {parts} distinct parts")),
        ..Default::default()
    };
    let side = (parts as f64).sqrt().ceil() as usize;
    let mut triangles = 0;
    for i in 0..parts {
        let mesh = part_mesh(i);
        triangles += mesh.triangles.len();
        let name = format!("p{i:03}");
        write_stl(&dir.join(format!("meshes/{name}.stl")), &mesh).unwrap();
        file.parts.insert(
            name.clone(),
            PartFile::from_stl(format!("meshes/{name}.stl")),
        );
        let at = Vec3::new((i % side) as f64 * PITCH, (i / side) as f64 * PITCH, 0.0);
        file.components.push(ComponentFile::new(
            name.clone(),
            name,
            Some(Transform::from_translation(at).to_matrix()),
        ));
    }
    let path = dir.join("cell.yaml");
    std::fs::write(&path, file.to_yaml().unwrap()).unwrap();
    (path, triangles)
}

/// `VmRSS` and `VmHWM` (peak) of this process, MB.
fn resident_mb() -> (f64, f64) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let field = |key: &str| {
        status
            .lines()
            .find(|l| l.starts_with(key))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<f64>().ok())
            .map_or(f64::NAN, |kb| kb / 1024.0)
    };
    (field("VmRSS:"), field("VmHWM:"))
}

/// CPU time this process has used so far (all threads, user + system), s: with the
/// machine shared, the load-independent companion of the wall times.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // fields after the command name, which is in parentheses and may hold spaces
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse().ok())
        .collect();
    // USER_HZ is 100 on Linux
    f.iter().sum::<f64>() / 100.0
}

fn row(parts: usize) {
    let dir = tempfile::tempdir().unwrap();
    let (path, triangles) = write_cell(dir.path(), parts);
    let (base, _) = resident_mb();
    let cpu0 = cpu_seconds();
    let t0 = Instant::now();
    let doc = Document::open(&path).unwrap();
    let open = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let mut cache = SceneCache::new();
    let scene = Scene::new(&doc, &mut cache).unwrap();
    let found = scene.contacts(Method::Exact, DEFAULT_TOLERANCE).unwrap();
    let first = t1.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu0;
    drop(scene);
    let mut repeat = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        let scene = Scene::new(&doc, &mut cache).unwrap();
        let again = scene.contacts(Method::Exact, DEFAULT_TOLERANCE).unwrap();
        repeat = repeat.min(t.elapsed().as_secs_f64());
        assert_eq!(again, found, "the repeat pass must find the same pairs");
    }
    // every component moved by the same 1 mm: the same pairs, but no verdict can be
    // reused, so this is the full recheck with the trees already built
    let mut doc = doc;
    let shift = Transform::from_translation(Vec3::new(1.0, 0.0, 0.0));
    for i in 0..doc.components().len() {
        let t = doc.components()[i].transform;
        doc.set_transform_at(i, shift * t).unwrap();
    }
    let t = Instant::now();
    let scene = Scene::new(&doc, &mut cache).unwrap();
    let moved = scene.contacts(Method::Exact, DEFAULT_TOLERANCE).unwrap();
    let recheck = t.elapsed().as_secs_f64();
    assert_eq!(moved.len(), found.len(), "a common shift keeps every pair");
    let (rss, peak) = resident_mb();
    println!(
        "| {parts:>5} | {:>9} | {:>7.0} | {:>10.0} | {:>9.0} | {:>7.0} | {:>10.1} | {:>10.0} | {:>6} | {:>8.0} | {:>8.0} | {} |",
        triangles,
        open * 1e3,
        first * 1e3,
        (open + first) * 1e3,
        cpu * 1e3,
        repeat * 1e3,
        recheck * 1e3,
        found.len(),
        rss - base,
        peak,
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .split_whitespace()
            .next()
            .unwrap_or("?"),
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--parts") {
        let n = args.get(i + 1).and_then(|v| v.parse().ok()).unwrap_or(100);
        row(n);
        return;
    }
    println!(
        "# {} threads (rayon); part = lathe solid, {SEGMENTS} × {PROFILE} facets",
        rayon_threads()
    );
    println!(
        "| parts | triangles | open ms | 1st pass ms | open+1st ms | CPU ms | repeat ms | moved ms | pairs | ΔRSS MB | peak MB | load |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let me = std::env::current_exe().unwrap();
    for n in [10, 25, 50, 100, 200] {
        let status = Command::new(&me)
            .args(["--parts", &n.to_string()])
            .status()
            .unwrap();
        assert!(status.success(), "row {n} failed");
    }
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
