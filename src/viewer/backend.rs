//! The worker that turns [`ViewEvent`]s into Rerun log calls, on its own thread.

use super::{PairView, PartView, RobotSample, ViewEvent};
use crate::math::Transform;
use crate::mesh::Mesh;
use rerun::{EntityPath, EntityPathPart, RecordingStream};
use std::collections::{HashMap, HashSet};
use std::sync::mpsc::Receiver;
use std::sync::Arc;

/// Where each recording goes: a fresh set of sinks per recording.
pub(crate) type SinkFactory =
    Box<dyn Fn() -> Result<Vec<Box<dyn rerun::sink::LogSink>>, String> + Send>;

/// Application id of every fitup recording.
pub const APP_ID: &str = "fitup";

/// The step timeline's name.
pub const STEP: &str = "step";

/// Default colour of a component without one (light steel).
const DEFAULT_RGB: [f64; 3] = [0.72, 0.76, 0.82];
/// Fixed parts are drawn at this share of their colour.
const FIXED_SHADE: f64 = 0.55;
const RED: [u8; 4] = [230, 40, 40, 255];

struct Worker {
    sinks: SinkFactory,
    rec: Option<RecordingStream>,
    step: i64,
    /// Converted meshes by mesh identity, kept for the whole session (reruns reuse them).
    meshes: HashMap<usize, (Arc<Mesh>, Arc<rerun::Mesh3D>)>,
    /// Entities whose mesh this recording already has.
    sent: HashSet<EntityPath>,
    /// Interference entities shown now (cleared when the pair stops interfering).
    pairs: HashSet<EntityPath>,
    report: Box<dyn Fn(&str) + Send>,
}

/// Runs the worker until every sender is gone. `first` names the first recording.
pub(crate) fn run(
    rx: Receiver<ViewEvent>,
    sinks: SinkFactory,
    first: Option<String>,
    report: Box<dyn Fn(&str) + Send>,
) {
    let mut w = Worker {
        sinks,
        rec: None,
        step: 0,
        meshes: HashMap::new(),
        sent: HashSet::new(),
        pairs: HashSet::new(),
        report,
    };
    if let Some(name) = first {
        w.new_run(&name);
    }
    while let Ok(event) = rx.recv() {
        w.handle(event);
    }
    if let Some(rec) = w.rec.take() {
        let _ = rec.flush_blocking();
    }
}

fn path(parts: &[&str]) -> EntityPath {
    EntityPath::new(parts.iter().map(|p| EntityPathPart::new(*p)).collect())
}

fn f32x3(v: [f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

fn rgba(c: [f64; 3], shade: f64) -> [u8; 4] {
    let b = |x: f64| ((x * shade).clamp(0.0, 1.0) * 255.0).round() as u8;
    [b(c[0]), b(c[1]), b(c[2]), 255]
}

fn transform3d(t: &Transform) -> rerun::Transform3D {
    let p = t.translation();
    let q = t.rotation();
    rerun::Transform3D::from_translation_rotation(
        f32x3([p.x, p.y, p.z]),
        rerun::Quaternion::from_xyzw([q.i as f32, q.j as f32, q.k as f32, q.w as f32]),
    )
}

fn mesh3d(mesh: &Mesh) -> rerun::Mesh3D {
    let positions: Vec<[f32; 3]> = mesh
        .vertices
        .iter()
        .map(|v| f32x3([v.x, v.y, v.z]))
        .collect();
    rerun::Mesh3D::new(positions).with_triangle_indices(
        mesh.triangles
            .iter()
            .map(|t| rerun::datatypes::UVec3D::from(*t)),
    )
}

impl Worker {
    fn new_run(&mut self, name: &str) {
        if let Some(old) = self.rec.take() {
            let _ = old.flush_blocking();
        }
        self.step = 0;
        self.sent.clear();
        self.pairs.clear();
        let sinks = match (self.sinks)() {
            Ok(s) => s,
            Err(e) => {
                (self.report)(&format!("viewer: {e}"));
                return;
            }
        };
        match rerun::RecordingStreamBuilder::new(APP_ID)
            .recording_name(name)
            .set_sinks(sinks)
        {
            Ok(rec) => {
                let _ = rec.log_static(
                    EntityPath::root(),
                    &rerun::ViewCoordinates::RIGHT_HAND_Z_UP(),
                );
                rec.set_time_sequence(STEP, 0);
                self.rec = Some(rec);
            }
            Err(e) => (self.report)(&format!("viewer: cannot start a recording: {e}")),
        }
    }

    fn handle(&mut self, event: ViewEvent) {
        if let ViewEvent::NewRun(name) = &event {
            self.new_run(name);
            return;
        }
        if let ViewEvent::Flush(done) = event {
            if let Some(rec) = &self.rec {
                let _ = rec.flush_blocking();
            }
            let _ = done.send(());
            return;
        }
        if self.rec.is_none() {
            // Logging before any run (a library user who forgot `new_run`): start one.
            self.new_run("fitup");
        }
        match event {
            ViewEvent::Step(n) => self.set_step(n),
            ViewEvent::Document { doc, parts } => self.document(&doc, &parts),
            ViewEvent::Poses {
                doc,
                poses,
                advance,
            } => {
                if advance {
                    self.set_step(self.step + 1);
                }
                for (name, pose) in &poses {
                    self.log(path(&[&doc, name]), &transform3d(pose));
                }
            }
            ViewEvent::Path { name, poses } => self.path(&name, &poses),
            ViewEvent::Trajectory {
                doc,
                robot,
                samples,
            } => self.trajectory(&doc, &robot, &samples),
            ViewEvent::Interference { doc, pairs } => self.interference(&doc, &pairs),
            ViewEvent::Text(line) => self.log(path(&["log"]), &rerun::TextLog::new(line)),
            ViewEvent::Scalar { name, value } => {
                self.log(path(&["plots", &name]), &rerun::Scalars::single(value))
            }
            ViewEvent::NewRun(_) | ViewEvent::Flush(_) => {}
        }
    }

    fn set_step(&mut self, n: i64) {
        self.step = n;
        if let Some(rec) = &self.rec {
            rec.set_time_sequence(STEP, n);
        }
    }

    fn log<A: rerun::AsComponents + ?Sized>(&self, entity: EntityPath, what: &A) {
        if let Some(rec) = &self.rec {
            if let Err(e) = rec.log(entity, what) {
                (self.report)(&format!("viewer: {e}"));
            }
        }
    }

    fn log_static<A: rerun::AsComponents + ?Sized>(&self, entity: EntityPath, what: &A) {
        if let Some(rec) = &self.rec {
            if let Err(e) = rec.log_static(entity, what) {
                (self.report)(&format!("viewer: {e}"));
            }
        }
    }

    fn mesh(&mut self, mesh: &Arc<Mesh>) -> Arc<rerun::Mesh3D> {
        let key = Arc::as_ptr(mesh) as usize;
        if let Some((_, m)) = self.meshes.get(&key) {
            return m.clone();
        }
        let m = Arc::new(mesh3d(mesh));
        // The Arc kept in the entry pins the address the key stands for.
        self.meshes.insert(key, (mesh.clone(), m.clone()));
        m
    }

    fn document(&mut self, doc: &str, parts: &[PartView]) {
        for p in parts {
            let entity = path(&[doc, &p.name]);
            if !self.sent.contains(&entity) {
                let shade = if p.fixed { FIXED_SHADE } else { 1.0 };
                let colour = rgba(p.color.unwrap_or(DEFAULT_RGB), shade);
                let mesh = self.mesh(&p.mesh);
                let styled = (*mesh).clone().with_albedo_factor(colour);
                self.log_static(entity.clone(), &styled);
                self.sent.insert(entity.clone());
            }
            self.log(entity, &transform3d(&p.pose));
        }
    }

    fn path(&self, name: &str, poses: &[Transform]) {
        let points: Vec<[f32; 3]> = poses
            .iter()
            .map(|t| {
                let p = t.translation();
                f32x3([p.x, p.y, p.z])
            })
            .collect();
        self.log(
            path(&["paths", name, "keys"]),
            &rerun::LineStrips3D::new([points.clone()])
                .with_colors([[255u8, 200, 0, 255]])
                .with_labels([name.to_string()]),
        );
        self.log(
            path(&["paths", name, "points"]),
            &rerun::Points3D::new(points.clone()).with_radii([1.5f32]),
        );
        // Frames scaled to the path: a tenth of its extent, at least 5 mm.
        let extent = points
            .iter()
            .flat_map(|a| points.iter().map(move |b| (a, b)))
            .take(10_000)
            .map(|(a, b)| {
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .fold(0.0f32, f32::max);
        let len = (extent / 10.0).max(5.0) as f64;
        let mut origins = Vec::new();
        let mut vectors = Vec::new();
        let mut colours = Vec::new();
        for t in poses {
            let o = t.translation();
            for (axis, colour) in [
                ([len, 0.0, 0.0], [230u8, 40, 40, 255]),
                ([0.0, len, 0.0], [40, 200, 40, 255]),
                ([0.0, 0.0, len], [40, 80, 230, 255]),
            ] {
                let v = t.apply_vector(&crate::math::Vec3::new(axis[0], axis[1], axis[2]));
                origins.push(f32x3([o.x, o.y, o.z]));
                vectors.push(f32x3([v.x, v.y, v.z]));
                colours.push(colour);
            }
        }
        self.log(
            path(&["paths", name, "frames"]),
            &rerun::Arrows3D::from_vectors(vectors)
                .with_origins(origins)
                .with_colors(colours),
        );
    }

    fn trajectory(&mut self, doc: &str, robot: &str, samples: &[RobotSample]) {
        // The whole TCP curve once, from the trajectory's first frame on; the current
        // TCP as a point at every sample.
        let curve: Vec<[f32; 3]> = samples
            .iter()
            .map(|s| {
                let p = s.tcp.translation();
                f32x3([p.x, p.y, p.z])
            })
            .collect();
        for (k, s) in samples.iter().enumerate() {
            self.set_step(self.step + 1);
            if k == 0 {
                self.log(
                    path(&["robots", robot, "tcp_path"]),
                    &rerun::LineStrips3D::new([curve.clone()]).with_colors([[0u8, 180, 220, 255]]),
                );
            }
            for (name, pose) in &s.links {
                self.log(path(&[doc, name]), &transform3d(pose));
            }
            for (i, q) in s.joints.iter().enumerate() {
                let j = format!("j{}", i + 1);
                self.log(
                    path(&["robots", robot, "joints", &j]),
                    &rerun::Scalars::single(*q),
                );
            }
            let p = s.tcp.translation();
            for (axis, v) in [("x", p.x), ("y", p.y), ("z", p.z)] {
                self.log(
                    path(&["robots", robot, "tcp", axis]),
                    &rerun::Scalars::single(v),
                );
            }
            self.log(
                path(&["robots", robot, "time_s"]),
                &rerun::Scalars::single(s.t),
            );
            self.log(
                path(&["robots", robot, "tcp_point"]),
                &rerun::Points3D::new([curve[k]])
                    .with_colors([[0u8, 180, 220, 255]])
                    .with_radii([3.0f32]),
            );
        }
    }

    fn interference(&mut self, doc: &str, pairs: &[PairView]) {
        let mut now = HashSet::new();
        for p in pairs {
            let name = format!("{} × {}", p.a, p.b);
            let entity = path(&[doc, "interference", &name]);
            now.insert(entity.clone());
            let (lo, hi) = p.overlap;
            let centre = [
                (lo[0] + hi[0]) / 2.0,
                (lo[1] + hi[1]) / 2.0,
                (lo[2] + hi[2]) / 2.0,
            ];
            let half = [
                (hi[0] - lo[0]) / 2.0,
                (hi[1] - lo[1]) / 2.0,
                (hi[2] - lo[2]) / 2.0,
            ];
            self.log(
                entity.clone(),
                &rerun::Boxes3D::from_centers_and_half_sizes([f32x3(centre)], [f32x3(half)])
                    .with_colors([RED])
                    .with_labels([format!(
                        "{name}: depth {} mm",
                        crate::math::format::number(p.depth, 3)
                    )]),
            );
            self.log(
                path(&[doc, "interference", &name, "points"]),
                &rerun::Points3D::new(p.points.iter().map(|q| f32x3(*q)))
                    .with_colors([RED])
                    .with_radii([0.8f32]),
            );
        }
        // Pairs that no longer interfere: cleared at this step.
        let gone: Vec<EntityPath> = self.pairs.difference(&now).cloned().collect();
        for g in gone {
            if let Some(rec) = &self.rec {
                let _ = rec.log(g, &rerun::Clear::recursive());
            }
        }
        self.pairs = now;
    }
}
