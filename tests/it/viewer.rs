//! The live viewer's recordings, read back with Rerun's own `.rrd` reader: the bundled
//! examples run as the user runs them (`fitup run SCRIPT --record FILE.rrd` from the
//! repository root) and the recording holds what docs/viewer.md promises.
#![cfg(feature = "viewer")]

use crate::common;

use common::{repo, run_bounded, short_text};
use fitup::document::Document;
use fitup::viewer::{content_security_policy, read_recording, Row, Session, SessionOptions};
use std::path::PathBuf;
use std::time::Duration;

const BOUND: Duration = Duration::from_secs(300);

/// A recording path under the repository's `out/` (git-ignored), unique to this test.
fn out(name: &str) -> (PathBuf, String) {
    let rel = format!("out/viewer-tests/{name}-{}.rrd", std::process::id());
    (repo().join(&rel), rel)
}

/// Runs `fitup run SCRIPT --record FILE` from the repository root and reads the file.
fn record(script: &str, name: &str) -> (Vec<Row>, String) {
    let (abs, rel) = out(name);
    let o = run_bounded(&repo(), &["run", script, "--record", &rel], BOUND);
    assert_eq!(o.status.code(), Some(0), "{}", short_text(&o));
    let rows = read_recording(&abs).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&abs);
    (rows, String::from_utf8_lossy(&o.stdout).into_owned())
}

fn rows_of<'a>(rows: &'a [Row], entity: &[&str], component: &str) -> Vec<&'a Row> {
    let mut v: Vec<&Row> = rows
        .iter()
        .filter(|r| r.entity == entity && r.component == component)
        .collect();
    v.sort_by_key(|r| r.step);
    v
}

fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

fn number_after(text: &str, before: &str) -> usize {
    let i = text
        .find(before)
        .unwrap_or_else(|| panic!("`{before}` not in {text}"))
        + before.len();
    text[i..]
        .split_whitespace()
        .next()
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no number after `{before}`"))
}

#[test]
fn the_demo_shows_every_component_with_its_mesh_colour_and_pose() {
    let (rows, stdout) = record("scripts/demo.rhai", "demo");
    let doc = Document::open(&repo().join("models/cell.yaml")).unwrap();
    for (i, c) in doc.components().iter().enumerate() {
        let entity = ["cell", c.name.as_str()];
        let mesh = rows_of(&rows, &entity, "Mesh3D:vertex_positions");
        assert_eq!(mesh.len(), 1, "{}: the mesh once", c.name);
        assert_eq!(mesh[0].step, None, "{}: the mesh is static", c.name);
        assert_eq!(
            mesh[0].values.len(),
            3 * doc.mesh_of(i).vertices.len(),
            "{}",
            c.name
        );
        let albedo = rows_of(&rows, &entity, "Mesh3D:albedo_factor");
        assert_eq!(albedo.len(), 1, "{}: a colour", c.name);
        let poses = rows_of(&rows, &entity, "Transform3D:translation");
        assert!(!poses.is_empty(), "{}: a pose", c.name);
        let t = c.transform.translation();
        assert!(
            close(&poses[0].values, &[t.x, t.y, t.z], 1e-3),
            "{}: first pose {:?} is the document's {t:?}",
            c.name,
            poses[0].values
        );
    }
    // Colours from the document; fixed parts at 55 % so they stand apart (packed RGBA).
    let packed = |c: [f64; 3], shade: f64| {
        let b = |x: f64| ((x * shade).clamp(0.0, 1.0) * 255.0).round() as u32;
        f64::from(b(c[0]) << 24 | b(c[1]) << 16 | b(c[2]) << 8 | 255)
    };
    let mut shades = std::collections::BTreeSet::new();
    for c in doc.components() {
        let colour = c.color.expect("the demo colours every component");
        let shade = if c.fixed { 0.55 } else { 1.0 };
        shades.insert(c.fixed);
        let albedo = rows_of(&rows, &["cell", &c.name], "Mesh3D:albedo_factor");
        assert_eq!(albedo[0].values, [packed(colour, shade)], "{}", c.name);
    }
    assert_eq!(shades.len(), 2, "the demo has fixed and loose parts");
    // The screw's 1 mm steps are frames of the animation, one step each.
    let steps = number_after(&stdout, "screw4 moved ");
    let screw = rows_of(&rows, &["cell", "screw4"], "Transform3D:translation");
    assert_eq!(
        screw.len(),
        steps + 2,
        "first pose, {steps} steps, the final set"
    );
    for w in screw.windows(2) {
        assert!(
            w[1].step > w[0].step,
            "{:?} then {:?}",
            w[0].step,
            w[1].step
        );
    }
}

#[test]
fn a_followed_path_is_a_curve_and_its_steps_are_on_the_timeline() {
    let (rows, stdout) = record("scripts/peg_in_hole.rhai", "peg");
    let doc = Document::open(&repo().join("models/problems/peg_in_hole_100.yaml")).unwrap();
    let start = doc.component("moving").unwrap().transform.translation();
    let keys = rows_of(&rows, &["paths", "moving", "keys"], "LineStrips3D:strips");
    assert_eq!(keys.len(), 1, "the path once, at follow");
    let k = &keys[0].values;
    assert!(k.len() >= 6 && k.len().is_multiple_of(3));
    assert!(
        close(&k[..3], &[start.x, start.y, start.z], 1e-3),
        "starts at the peg: {:?}",
        &k[..3]
    );
    assert!(
        close(&k[k.len() - 3..], &[0.0, 0.0, 10.0], 1e-3),
        "ends seated"
    );
    let frames = rows_of(&rows, &["paths", "moving", "frames"], "Arrows3D:vectors");
    assert_eq!(
        frames[0].values.len(),
        3 * k.len(),
        "three axes per key pose"
    );
    // The followed steps: the last `n` poses of the peg, one step apart, ending seated.
    let n = number_after(&stdout, "followed ");
    let poses = rows_of(
        &rows,
        &["peg_in_hole_100", "moving"],
        "Transform3D:translation",
    );
    assert!(poses.len() > n, "{} poses, {n} followed", poses.len());
    let followed = &poses[poses.len() - n..];
    for w in followed.windows(2) {
        assert_eq!(w[1].step.unwrap(), w[0].step.unwrap() + 1);
        let d: f64 = (0..3)
            .map(|i| (w[1].values[i] - w[0].values[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(d <= 5.0 + 1e-3, "steps of at most 5 mm: {d}");
    }
    assert!(close(&followed[n - 1].values, &[0.0, 0.0, 10.0], 1e-3));
}

#[test]
fn a_program_feeds_the_joint_monitor_and_moves_the_links() {
    let (rows, _) = record("scripts/robot_program.rhai", "program");
    let series: Vec<Vec<&Row>> = (1..=6)
        .map(|j| {
            rows_of(
                &rows,
                &["robots", "mz07", "joints", &format!("j{j}")],
                "Scalars:scalars",
            )
        })
        .collect();
    let n = series[0].len();
    assert!(n > 10, "{n} samples");
    for s in &series {
        assert_eq!(s.len(), n, "every joint at every sample");
    }
    for axis in ["x", "y", "z"] {
        assert_eq!(
            rows_of(&rows, &["robots", "mz07", "tcp", axis], "Scalars:scalars").len(),
            n
        );
    }
    // The program ends at `Joint 20 -10 10 0 0 0` (degrees): some sample shows exactly that.
    let end = [20.0, -10.0, 10.0, 0.0, 0.0, 0.0];
    let hit = (0..n).any(|i| (0..6).all(|j| (series[j][i].values[0] - end[j]).abs() < 1e-6));
    assert!(hit, "the program's end joints are in the monitor");
    // The link components move at the samples' steps.
    let link = rows_of(&rows, &["mz07", "mz07_link1"], "Transform3D:translation");
    let quat = rows_of(&rows, &["mz07", "mz07_link1"], "Transform3D:quaternion");
    assert!(
        link.len() >= n && quat.len() >= n,
        "{} / {} link poses",
        link.len(),
        quat.len()
    );
    let steps: std::collections::BTreeSet<_> = quat.iter().map(|r| r.step).collect();
    assert!(series[0].iter().all(|r| steps.contains(&r.step)));
}

#[test]
fn an_interfering_pair_is_highlighted_with_points_where_they_meet() {
    let (abs, rel) = out("interference");
    let script = repo().join(format!(
        "out/viewer-tests/interfere-{}.rhai",
        std::process::id()
    ));
    std::fs::create_dir_all(script.parent().unwrap()).unwrap();
    // The peg 3 mm off the hole's axis, half inside: it cuts the block (0.1 mm clearance).
    std::fs::write(
        &script,
        "let doc = open_doc(\"models/problems/peg_in_hole_100.yaml\");\n\
         doc.set_transform(\"moving\", translation(3, 0, 40));\n\
         let bad = doc.interferences();\n\
         assert(bad.len() == 1, `${bad}`);\n\
         doc.set_transform(\"moving\", translation(0, 0, 200));\n\
         assert(doc.interferences().len() == 0);\n",
    )
    .unwrap();
    let script_rel = script
        .strip_prefix(repo())
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let o = run_bounded(&repo(), &["run", &script_rel, "--record", &rel], BOUND);
    let _ = std::fs::remove_file(&script);
    assert_eq!(o.status.code(), Some(0), "{}", short_text(&o));
    let rows = read_recording(&abs).unwrap();
    let _ = std::fs::remove_file(&abs);
    let pair = ["peg_in_hole_100", "interference", "block × moving"];
    let boxes = rows_of(&rows, &pair, "Boxes3D:half_sizes");
    assert_eq!(boxes.len(), 1, "the pair highlighted once");
    let labels = rows_of(&rows, &pair, "Boxes3D:labels");
    assert!(
        labels[0].texts[0].contains("depth"),
        "{:?}",
        labels[0].texts
    );
    let mut points_entity = pair.to_vec();
    points_entity.push("points");
    let points = rows_of(&rows, &points_entity, "Points3D:positions");
    assert!(!points[0].values.is_empty(), "points where they meet");
    // Every point lies in the overlap: inside the hole's block (|x|,|y| ≤ 40) and the peg.
    for p in points[0].values.chunks(3) {
        assert!(p[2] >= 40.0 - 1e-3 && p[2] <= 140.0 + 1e-3, "{p:?}");
    }
    // Moved apart: the highlight is cleared at a later step.
    let cleared = rows
        .iter()
        .any(|r| r.entity == pair && r.component.starts_with("Clear") && r.step > boxes[0].step);
    assert!(cleared, "cleared when apart");
}

#[test]
fn a_file_that_is_not_a_recording_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("x.rrd");
    std::fs::write(&bad, "not a recording").unwrap();
    let e = read_recording(&bad).unwrap_err().to_string();
    assert!(e.contains("x.rrd"), "{e}");
    let o = run_bounded(dir.path(), &["view", "x.rrd"], BOUND);
    assert_eq!(o.status.code(), Some(1));
    assert!(short_text(&o).contains("x.rrd"), "{}", short_text(&o));
}

/// One GET on the session's web server: the response head and body.
fn get(port: u16, path: &str) -> (String, Vec<u8>) {
    use std::io::{Read, Write};
    let mut c = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
    c.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
    write!(c, "GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n").unwrap();
    let mut all = Vec::new();
    c.read_to_end(&mut all).unwrap();
    let split = all.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    (
        String::from_utf8_lossy(&all[..split]).into_owned(),
        all[split + 4..].to_vec(),
    )
}

/// The served page and the wasm carry a local-only policy that names the session's own
/// gRPC port, and nothing outside the web viewer's files is served.
#[test]
fn the_page_and_the_wasm_carry_a_local_only_policy() {
    let session = Session::start(SessionOptions {
        serve: true,
        ..SessionOptions::default()
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let url = session.url().expect("a serving session has an address");
    let port = |text: Option<&str>| -> u16 {
        text.and_then(|p| p.parse().ok())
            .unwrap_or_else(|| panic!("no port in {url}"))
    };
    let rest = url.strip_prefix("http://127.0.0.1:").unwrap_or(url);
    let (web, page) = rest.split_at(rest.find('/').unwrap_or(rest.len()));
    let web = port(Some(web));
    let grpc = port(
        url.rsplit("127.0.0.1%3A")
            .next()
            .and_then(|p| p.strip_suffix("%2Fproxy")),
    );
    let (head, body) = get(web, page);
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    assert!(
        head.contains(&format!(
            "Content-Security-Policy: {}",
            content_security_policy(grpc)
        )),
        "{head}"
    );
    assert!(
        head.contains("Content-Security-Policy: default-src 'self'"),
        "{head}"
    );
    assert!(
        head.contains(&format!("connect-src 'self' http://127.0.0.1:{grpc} ")),
        "{head}"
    );
    assert!(String::from_utf8_lossy(&body).contains("re_viewer"));
    let (head, body) = get(web, "/re_viewer_bg.wasm");
    assert!(head.contains("application/wasm"), "{head}");
    assert_eq!(&body[..4], b"\0asm");
    let (head, _) = get(web, "/../etc/passwd");
    assert!(head.starts_with("HTTP/1.1 404"), "{head}");
}
