//! The live 3D viewer: what a run computes, shown in [Rerun](https://rerun.io) —
//! documents, robots, paths, interference — live in the browser or saved as an `.rrd`
//! recording.
//!
//! A [`Viewer`] is a cheap handle (clones share one session). Every `log_*` call copies
//! what it needs into a [`ViewEvent`] and hands it to the session's worker thread over an
//! unbounded channel, so logging never waits on the network, a file or the browser: the
//! script goes on while the worker converts meshes and sends them. A disabled viewer
//! ([`Viewer::default`]) drops events at once, so code can log unconditionally.
//!
//! What is logged where (entity paths; units mm, as everywhere inside):
//! - `DOC/COMPONENT`: each component's mesh (in its part frame, sent once per
//!   recording and converted once per session: meshes are cached across reruns) and its
//!   pose on the `step` timeline. Colours come from the document; fixed parts are drawn
//!   darker (their colour at 55 %) so they stand apart from the moving ones.
//! - `robots/ROBOT/joints/jN` (degrees, mm for prismatic joints) and
//!   `robots/ROBOT/tcp/x|y|z` (mm): the joint monitor, one point per trajectory sample;
//!   `robots/ROBOT/tcp_path` the TCP's curve (outside `DOC`, whose entities carry the
//!   components' poses). Link components move on the same `step` timeline.
//! - `paths/NAME/keys`: a path's key points as a 3D curve, `paths/NAME/frames` a small
//!   frame (red X, green Y, blue Z) at each key pose.
//! - `DOC/interference/A × B`: an interfering pair: the overlap of their world boxes as a
//!   red wire box labelled with the depth, and the mesh vertices of both parts inside
//!   that overlap as red points (where they meet).
//!
//! The `step` timeline counts animation frames: every followed step and every
//! trajectory sample advances it by one; [`Viewer::step`] sets it.
//!
//! Without the `viewer` cargo feature the module keeps its API (scripts' `view` calls
//! stay valid) but a live session cannot be started.

#[cfg(feature = "viewer")]
mod backend;
pub mod origin;
#[cfg(feature = "viewer")]
mod read;
#[cfg(feature = "viewer")]
mod server;

#[cfg(feature = "viewer")]
pub use read::{read_recording, Row};
#[cfg(feature = "viewer")]
pub use server::{content_security_policy, open_browser, Report, Session, SessionOptions};

use crate::document::Document;
use crate::math::Transform;
use crate::mesh::Mesh;
use std::sync::mpsc::{Sender, SyncSender};
use std::sync::Arc;
use std::time::Duration;

/// Why a viewer session could not start or a recording could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewerError {
    /// The web or gRPC server could not listen.
    #[error("cannot start the viewer server: {0}")]
    Server(String),
    /// The recording file could not be created, written or read.
    #[error("recording {path}: {reason}")]
    Recording {
        /// The `.rrd` file.
        path: std::path::PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// This build has no viewer (the `viewer` feature is opt-in: it adds ≈ 430 crates).
    #[error("this fitup was built without the viewer; to use --view, --record and `fitup view`, rebuild with it: cargo install --path . --features viewer (or cargo run --release --features viewer -- …)")]
    NotBuilt,
}

/// A component as the viewer draws it.
#[derive(Debug, Clone)]
pub struct PartView {
    /// Component name.
    pub name: String,
    /// The part's mesh (part frame, mm), shared with the document.
    pub mesh: Arc<Mesh>,
    /// World pose of the component (mm).
    pub pose: Transform,
    /// RGB colour in 0..1, if the document gives one.
    pub color: Option<[f64; 3]>,
    /// Whether the component is fixed in the assembly.
    pub fixed: bool,
}

/// One sample of a robot trajectory as the viewer shows it.
#[derive(Debug, Clone)]
pub struct RobotSample {
    /// Time from the start of the trajectory (s).
    pub t: f64,
    /// Joint values as the user reads them (degrees, mm for prismatic joints).
    pub joints: Vec<f64>,
    /// World pose of the TCP (mm).
    pub tcp: Transform,
    /// World poses of the link components at this sample: `(component, pose)`.
    pub links: Vec<(String, Transform)>,
}

/// An interfering pair as the viewer highlights it.
#[derive(Debug, Clone)]
pub struct PairView {
    /// First component.
    pub a: String,
    /// Second component.
    pub b: String,
    /// Penetration depth estimate (mm).
    pub depth: f64,
    /// Overlap of the two world boxes: min and max corners (mm).
    pub overlap: ([f64; 3], [f64; 3]),
    /// Mesh vertices of either part inside the overlap (world, mm).
    pub points: Vec<[f64; 3]>,
}

/// What the worker is asked to log. Built by the `log_*` methods of [`Viewer`].
#[derive(Debug)]
pub enum ViewEvent {
    /// Start a new recording (a new run); the open viewer switches to it.
    NewRun(String),
    /// Set the `step` timeline.
    Step(i64),
    /// A whole document: meshes (once per recording) and poses at the current step.
    Document {
        /// Document name (its file stem).
        doc: String,
        /// Its components.
        parts: Vec<PartView>,
    },
    /// New poses of some components; `advance` moves the step forward first.
    Poses {
        /// Document name.
        doc: String,
        /// `(component, world pose)`.
        poses: Vec<(String, Transform)>,
        /// Whether this is a new animation frame.
        advance: bool,
    },
    /// A path's key poses.
    Path {
        /// Name shown in the entity tree.
        name: String,
        /// Key poses, start first (mm).
        poses: Vec<Transform>,
    },
    /// A robot trajectory: link poses animate, joints and TCP feed the monitor.
    Trajectory {
        /// Document name.
        doc: String,
        /// Robot name.
        robot: String,
        /// The samples, in time order.
        samples: Vec<RobotSample>,
    },
    /// The interfering pairs of a document (an empty list clears the highlight).
    Interference {
        /// Document name.
        doc: String,
        /// The pairs.
        pairs: Vec<PairView>,
    },
    /// A line of text in the recording's log.
    Text(String),
    /// A point of the plot `plots/NAME`.
    Scalar {
        /// Plot name.
        name: String,
        /// The value.
        value: f64,
    },
    /// Answer on the channel once everything before has been sent.
    Flush(SyncSender<()>),
}

/// A handle on a viewer session (clones share it). See the [module docs](self).
#[derive(Clone, Default)]
pub struct Viewer {
    tx: Option<Sender<ViewEvent>>,
}

impl std::fmt::Debug for Viewer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.tx.is_some() {
            "Viewer(live)"
        } else {
            "Viewer(off)"
        })
    }
}

/// The name the viewer uses for a document: its file stem.
pub fn document_name(doc: &Document) -> String {
    doc.path()
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "doc".to_string())
}

impl Viewer {
    /// A handle that sends to `tx` (the worker of a [`Session`] owns the receiver).
    #[cfg(any(feature = "viewer", test))]
    pub(crate) fn from_sender(tx: Sender<ViewEvent>) -> Self {
        Self { tx: Some(tx) }
    }

    /// Whether events go anywhere.
    pub fn is_live(&self) -> bool {
        self.tx.is_some()
    }

    /// Hands an event to the worker; never blocks. A session that ended drops it.
    pub fn send(&self, event: ViewEvent) {
        if let Some(tx) = &self.tx {
            let _ = tx.send(event);
        }
    }

    /// Starts a new recording named `name` (watch mode: one per run).
    pub fn new_run(&self, name: &str) {
        self.send(ViewEvent::NewRun(name.to_string()));
    }

    /// Sets the `step` timeline to `n`.
    pub fn step(&self, n: i64) {
        self.send(ViewEvent::Step(n));
    }

    /// Logs a line of text.
    pub fn text(&self, line: &str) {
        self.send(ViewEvent::Text(line.to_string()));
    }

    /// Adds `value` to the plot `plots/NAME` at the current step.
    pub fn scalar(&self, name: &str, value: f64) {
        self.send(ViewEvent::Scalar {
            name: name.to_string(),
            value,
        });
    }

    /// Logs every shown component of `doc` (mesh, pose, colour, fixed) at the current
    /// step: a suppressed or hidden one is not drawn ([`Component::is_shown`]).
    ///
    /// [`Component::is_shown`]: crate::document::Component::is_shown
    pub fn log_document(&self, doc: &Document) {
        if !self.is_live() {
            return;
        }
        let parts = doc
            .components()
            .iter()
            .enumerate()
            .filter(|(_, c)| c.is_shown())
            .map(|(i, c)| PartView {
                name: c.name.clone(),
                mesh: doc.mesh_of(i).clone(),
                pose: c.transform,
                color: c.color,
                fixed: c.fixed,
            })
            .collect();
        self.send(ViewEvent::Document {
            doc: document_name(doc),
            parts,
        });
    }

    /// Logs new poses of components of `doc` (by name); `advance` makes it a new
    /// animation frame (the step moves forward by one first). Poses of suppressed or
    /// hidden components are left out, as their meshes are.
    pub fn log_poses(&self, doc: &Document, mut poses: Vec<(String, Transform)>, advance: bool) {
        if self.is_live() {
            poses.retain(|(name, _)| doc.component(name).map_or(true, |c| c.is_shown()));
            self.send(ViewEvent::Poses {
                doc: document_name(doc),
                poses,
                advance,
            });
        }
    }

    /// Logs a path's key poses (mm) as a curve with a small frame at each.
    pub fn log_path(&self, name: &str, poses: &[Transform]) {
        if self.is_live() {
            self.send(ViewEvent::Path {
                name: name.to_string(),
                poses: poses.to_vec(),
            });
        }
    }

    /// Logs a robot trajectory of `doc`'s robot `robot` (index): every sample advances
    /// the step, moves the link components and adds a point to the joint monitor.
    pub fn log_trajectory(
        &self,
        doc: &Document,
        robot: usize,
        trajectory: &crate::kinematics::Trajectory,
    ) {
        if !self.is_live() {
            return;
        }
        let Ok(instance) = doc.robot_at(robot) else {
            return;
        };
        // the link components drawn (a suppressed or hidden one is not)
        let names: Vec<Option<&str>> = doc
            .components()
            .iter()
            .map(|c| c.is_shown().then_some(c.name.as_str()))
            .collect();
        let samples = trajectory
            .samples
            .iter()
            .map(|s| RobotSample {
                t: s.t,
                joints: crate::document::robot::joints_to_document(instance.robot(), &s.joints),
                tcp: s.tcp,
                links: instance
                    .component_poses(&s.joints)
                    .unwrap_or_default()
                    .into_iter()
                    .filter_map(|(c, p)| {
                        names.get(c).copied().flatten().map(|n| (n.to_string(), p))
                    })
                    .collect(),
            })
            .collect();
        self.send(ViewEvent::Trajectory {
            doc: document_name(doc),
            robot: instance.name().to_string(),
            samples,
        });
    }

    /// Logs the interfering pairs of `doc` (component indices `a`, `b` and depth, mm):
    /// each is highlighted with its overlap box and the vertices inside it.
    pub fn log_interference(&self, doc: &Document, pairs: &[(usize, usize, f64)]) {
        if !self.is_live() {
            return;
        }
        let pairs = pairs
            .iter()
            .filter_map(|&(a, b, depth)| pair_view(doc, a, b, depth))
            .collect();
        self.send(ViewEvent::Interference {
            doc: document_name(doc),
            pairs,
        });
    }

    /// Waits (at most `timeout`) until everything logged so far has been handed to the
    /// sinks (the browser's server, the `.rrd` file). Returns whether it got there.
    pub fn flush(&self, timeout: Duration) -> bool {
        let Some(tx) = &self.tx else {
            return true;
        };
        let (done, wait) = std::sync::mpsc::sync_channel(1);
        if tx.send(ViewEvent::Flush(done)).is_err() {
            return false;
        }
        wait.recv_timeout(timeout).is_ok()
    }
}

/// At most this many highlight points per interfering pair (the rest are dropped).
const MAX_PAIR_POINTS: usize = 2000;

fn pair_view(doc: &Document, a: usize, b: usize, depth: f64) -> Option<PairView> {
    let (ab, bb) = (doc.world_aabb(a)?, doc.world_aabb(b)?);
    let (a_min, a_max, b_min, b_max) = (ab.lo, ab.hi, bb.lo, bb.hi);
    let lo = [
        a_min.x.max(b_min.x),
        a_min.y.max(b_min.y),
        a_min.z.max(b_min.z),
    ];
    let hi = [
        a_max.x.min(b_max.x),
        a_max.y.min(b_max.y),
        a_max.z.min(b_max.z),
    ];
    let inside = |p: &crate::math::Point3| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
    let mut points = Vec::new();
    for i in [a, b] {
        let pose = doc.components()[i].transform;
        for v in &doc.mesh_of(i).vertices {
            let w = pose.apply(v);
            if inside(&w) && points.len() < MAX_PAIR_POINTS {
                points.push([w.x, w.y, w.z]);
            }
        }
    }
    let comps = doc.components();
    Some(PairView {
        a: comps[a].name.clone(),
        b: comps[b].name.clone(),
        depth,
        overlap: (lo, hi),
        points,
    })
}

/// Starts a session (see [`Session::start`]); without the `viewer` feature, an error.
#[cfg(not(feature = "viewer"))]
pub fn not_built() -> ViewerError {
    ViewerError::NotBuilt
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disabled_viewer_drops_everything_at_once() {
        let v = Viewer::default();
        assert!(!v.is_live());
        v.new_run("x");
        v.step(3);
        assert!(v.flush(Duration::from_millis(1)));
    }

    /// Issue 37: a suppressed or hidden component is not drawn (SolidWorks draws
    /// neither): not by `log_document`, nor moved by `log_poses`, nor as a robot link
    /// of `log_trajectory`; the shown ones are.
    #[test]
    fn suppressed_and_hidden_components_are_not_drawn() {
        use crate::kinematics::{Trajectory, TrajectorySample};
        let names =
            |parts: &[PartView]| -> Vec<String> { parts.iter().map(|p| p.name.clone()).collect() };
        let (tx, rx) = std::sync::mpsc::channel();
        let v = Viewer::from_sender(tx);
        let mut doc = Document::open(std::path::Path::new("models/cell.yaml")).unwrap();
        let all = doc.components().len();
        v.log_document(&doc);
        match rx.recv().unwrap() {
            ViewEvent::Document { parts, .. } => assert_eq!(parts.len(), all),
            e => panic!("{e:?}"),
        }
        doc.set_suppressed("screw4", true).unwrap();
        doc.set_hidden("screw5", true).unwrap();
        v.log_document(&doc);
        match rx.recv().unwrap() {
            ViewEvent::Document { parts, .. } => {
                let drawn = names(&parts);
                assert_eq!(drawn.len(), all - 2, "{drawn:?}");
                assert!(
                    !drawn.iter().any(|n| n == "screw4" || n == "screw5"),
                    "{drawn:?}"
                );
            }
            e => panic!("{e:?}"),
        }
        let moved: Vec<(String, Transform)> = ["screw3", "screw4", "screw5"]
            .iter()
            .map(|n| (n.to_string(), Transform::IDENTITY))
            .collect();
        v.log_poses(&doc, moved, true);
        match rx.recv().unwrap() {
            ViewEvent::Poses { poses, .. } => {
                let posed: Vec<&str> = poses.iter().map(|(n, _)| n.as_str()).collect();
                assert_eq!(posed, ["screw3"]);
            }
            e => panic!("{e:?}"),
        }
        // a robot's hidden link is not moved by its trajectory; the others are
        let mut doc = Document::open(std::path::Path::new("models/mz07.yaml")).unwrap();
        doc.set_hidden("mz07_link3", true).unwrap();
        let robot = doc.robot_at(0).unwrap().robot().clone();
        let trajectory = Trajectory {
            samples: vec![TrajectorySample {
                t: 0.0,
                joints: vec![0.0; robot.dof()],
                tcp: Transform::IDENTITY,
            }],
            joint_kinds: robot.joint_kinds(),
        };
        v.log_trajectory(&doc, 0, &trajectory);
        match rx.recv().unwrap() {
            ViewEvent::Trajectory { samples, .. } => {
                let links: Vec<&str> = samples[0].links.iter().map(|(n, _)| n.as_str()).collect();
                assert!(links.contains(&"mz07_link2"), "{links:?}");
                assert!(!links.contains(&"mz07_link3"), "{links:?}");
            }
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn events_reach_the_receiver_in_order() {
        let (tx, rx) = std::sync::mpsc::channel();
        let v = Viewer::from_sender(tx);
        v.new_run("run 1");
        v.step(7);
        v.log_path("p", &[Transform::IDENTITY]);
        match rx.recv().unwrap() {
            ViewEvent::NewRun(n) => assert_eq!(n, "run 1"),
            e => panic!("{e:?}"),
        }
        assert!(matches!(rx.recv().unwrap(), ViewEvent::Step(7)));
        match rx.recv().unwrap() {
            ViewEvent::Path { name, poses } => {
                assert_eq!(name, "p");
                assert_eq!(poses.len(), 1);
            }
            e => panic!("{e:?}"),
        }
    }
}
