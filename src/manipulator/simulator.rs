//! A simulated manipulator controller that speaks simple_message on 127.0.0.1.
//!
//! It moves one robot of a document in real time (or `speed` times faster): points
//! streamed with JOINT_TRAJ_PT on the motion port are checked and queued, the motion
//! thread interpolates joint-linearly between them, and every state client gets
//! JOINT_POSITION and STATUS each [`SimulatorOptions::publish_interval`].
//!
//! A point is **refused** (FAILURE reply, then STATUS `in_error` with a
//! [`RefusalCode`] as `error_code`, and any motion stopped) when a joint leaves its
//! limits, the segment from the previous point makes the robot's link components
//! interfere with any other component of the cell (pairs that already interfere at
//! start-up are ignored), the sequence number is out of order, or the point is
//! malformed. A new trajectory (sequence 0) clears the error.
//!
//! A request it does not serve, or one whose content does not decode (a NaN joint,
//! an unknown type), gets a SERVICE_REPLY with FAILURE and the connection stays open
//! (REP-I0006); topics it does not act on are ignored. Only framing garbage (a bad
//! length prefix, a stream cut inside a frame) closes a connection. The byte order is
//! detected per motion connection unless [`SimulatorOptions::byte_order`] forces one.
//!
//! Clients that disconnect or send garbage only lose their own connection: the
//! simulator logs the cause to standard error and keeps serving.
//!
//! Connections are bounded so that idle or hostile clients cannot starve a real
//! one: at most [`MAX_CONNECTIONS`] per port. When a port is full, a new connection
//! takes the place of the oldest motion connection that has not yet sent a whole
//! packet (an idle one); when there is none (or on the state port, whose clients
//! never send) the oldest connection is closed. A motion connection is closed when its first
//! packet does not arrive within [`FIRST_PACKET_TIMEOUT`], when a packet it started
//! is not complete within [`PARTIAL_PACKET_TIMEOUT`], and after [`IDLE_TIMEOUT`]
//! without a packet. A packet may arrive in any number of parts with pauses between
//! them (the bytes read so far are kept across read timeouts).

use super::message::{
    msg_type, special_seq, Body, ByteOrder, CodecError, Frame, FrameReader, JointTrajPt, Packet,
    ReplyCode, RobotMode, Status, ToolAction, TriState, MAX_JOINTS,
};
use super::{joints_from_wire, joints_to_wire, RefusalCode};
use crate::document::Document;
use crate::kinematics::{IkOptions, JointKind};
use crate::math::{Deadline, Transform};
use crate::workspace::{CheckOptions, SceneCache, Workspace};
use nalgebra::Vector3;
use std::collections::{HashSet, VecDeque};
use std::io::Write;
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use thiserror::Error;

/// Most connections served at once on each port (motion, state).
pub const MAX_CONNECTIONS: usize = 32;
/// A motion connection that sends no whole packet this long after it opened is
/// closed (a connection that never speaks holds a slot for nothing).
pub const FIRST_PACKET_TIMEOUT: Duration = Duration::from_secs(10);
/// A packet whose first bytes arrived must be complete within this time.
pub const PARTIAL_PACKET_TIMEOUT: Duration = Duration::from_secs(10);
/// A motion connection silent this long after its last packet is closed.
pub const IDLE_TIMEOUT: Duration = Duration::from_secs(300);
/// Messages a motion connection sends that are answered FAILURE or ignored and
/// logged; beyond this many per connection they are no longer logged (a flood of
/// them cannot flood standard error).
pub const MAX_LOGGED_PER_CONNECTION: usize = 8;

/// Longest guarded move a TOUCH may ask for (mm).
pub const MAX_TOUCH_MM: f64 = 1000.0;

/// The tool-frame direction of FITUP_TOOL TOUCH's `index`: 0 +z (the default: the
/// tool's approach), 1 −z, 2 +x, 3 −x, 4 +y, 5 −y; `None` for any other index.
pub fn touch_direction(index: i32) -> Option<Vector3<f64>> {
    Some(match index {
        0 => Vector3::z(),
        1 => -Vector3::z(),
        2 => Vector3::x(),
        3 => -Vector3::x(),
        4 => Vector3::y(),
        5 => -Vector3::y(),
        _ => return None,
    })
}

/// Settings of a [`Simulator`].
#[derive(Debug, Clone)]
pub struct SimulatorOptions {
    /// Motion port on 127.0.0.1 (0 picks a free one).
    pub motion_port: u16,
    /// State port on 127.0.0.1 (0 picks a free one).
    pub state_port: u16,
    /// Time scale: 1 is real time, 10 runs motions ten times faster.
    pub speed: f64,
    /// Byte order: `Some` forces one on every connection; `None` (the default)
    /// detects it per motion connection from its first length prefix
    /// ([`ByteOrder::detect`]). State clients never send, so a state connection
    /// speaks the forced order, else the order of the last motion connection that
    /// sent a frame before it connected (fitup's client pings first for this), else
    /// big-endian.
    pub byte_order: Option<ByteOrder>,
    /// Time between two JOINT_POSITION + STATUS publications (wall clock).
    pub publish_interval: Duration,
    /// Joint speed used when a point gives only a velocity fraction (rad/s at 1.0;
    /// prismatic joints: this × 1000 mm/s per rad/s).
    pub max_joint_speed: f64,
    /// Largest joint step between two interference checks of a segment (rad / mm).
    pub check_step: f64,
}

impl Default for SimulatorOptions {
    fn default() -> Self {
        Self {
            motion_port: super::MOTION_PORT,
            state_port: super::STATE_PORT,
            speed: 1.0,
            byte_order: None,
            publish_interval: Duration::from_millis(50),
            max_joint_speed: 1.0,
            check_step: 2f64.to_radians(),
        }
    }
}

/// A simulator that cannot start.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SimulatorError {
    /// No such robot in the document.
    #[error(transparent)]
    Robot(#[from] crate::document::DocumentError),
    /// A robot with more joints than simple_message carries.
    #[error("robot `{robot}` has {joints} joints: simple_message (JOINT_TRAJ_PT, JOINT_POSITION) carries at most {max}", max = MAX_JOINTS)]
    TooManyJoints {
        /// The robot.
        robot: String,
        /// Its joint count.
        joints: usize,
    },
    /// The cell cannot be checked at the robot's start pose.
    #[error("the cell cannot be checked at the robot's start pose: {0}")]
    Cell(#[source] CellError),
    /// A port cannot be bound.
    #[error("cannot listen on 127.0.0.1:{port}: {source}")]
    Bind {
        /// The port.
        port: u16,
        /// The cause.
        source: std::io::Error,
    },
}

/// Why the simulator cannot check its cell at some joints.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CellError {
    /// The joints cannot be set (count, limits, non-finite).
    #[error(transparent)]
    Joints(#[from] crate::document::DocumentError),
    /// The collision check failed (a mesh, a tolerance).
    #[error(transparent)]
    Check(#[from] crate::workspace::WorkspaceError),
}

/// Why a TOUCH (guarded move) was refused.
#[derive(Debug, Error)]
#[non_exhaustive]
enum TouchError {
    /// The tool pose at the start joints cannot be computed.
    #[error(transparent)]
    Start(#[from] crate::kinematics::KinematicsError),
    /// No IK solution `at` mm along the tool's axis.
    #[error("the tool cannot go {at:.3} mm along its axis: {source}")]
    Ik {
        /// Distance along the axis (mm).
        at: f64,
        /// The IK error.
        #[source]
        source: crate::kinematics::IkError,
    },
    /// A joint (0-based) leaves its limits `at` mm along the axis.
    #[error("joint {} leaves its limits {at:.3} mm along the touch", .joint + 1)]
    Limit {
        /// The joint (0-based).
        joint: usize,
        /// Distance along the axis (mm).
        at: f64,
    },
    /// The cell cannot be checked.
    #[error(transparent)]
    Cell(#[from] CellError),
}

/// The cell as the simulator checks it: the document, the robot and the pairs that
/// already interfere at start-up.
struct Cell {
    doc: Document,
    robot: usize,
    kinds: Vec<JointKind>,
    links: HashSet<usize>,
    baseline: HashSet<(usize, usize)>,
    cache: SceneCache,
    check_step: f64,
}

impl Cell {
    /// Robot-vs-cell interfering pairs at joints `q` (component indices).
    fn pairs(&mut self, q: &[f64]) -> Result<Vec<(usize, usize)>, CellError> {
        self.doc.set_robot_joints(self.robot, q)?;
        let ws = Workspace::new(&self.doc, &mut self.cache)?;
        let all = ws.interferences(&CheckOptions::default())?;
        Ok(all
            .into_iter()
            .filter(|p| self.links.contains(&p.a) != self.links.contains(&p.b))
            .map(|p| (p.a, p.b))
            .collect())
    }

    /// Robot-vs-cell pairs in contact (touching or interfering) at joints `q`.
    fn contacts(&mut self, q: &[f64]) -> Result<Vec<(usize, usize)>, CellError> {
        self.doc.set_robot_joints(self.robot, q)?;
        let ws = Workspace::new(&self.doc, &mut self.cache)?;
        let all = ws.contacts(&CheckOptions::default())?;
        Ok(all
            .into_iter()
            .filter(|p| self.links.contains(&p.a) != self.links.contains(&p.b))
            .map(|p| (p.a, p.b))
            .collect())
    }

    /// The guarded move of TOUCH: from joints `q0` the tool moves straight along
    /// `direction` (tool frame, unit) for at most `distance` mm and stops at the
    /// first contact of a link with another component of the cell (pairs already
    /// in contact at `q0` are ignored). Returns the distance travelled (mm), the
    /// joints there and the component touched (`None`: no contact, the whole
    /// distance). The contact is found in steps of at most 0.2 mm, then bisected to
    /// 1e-4 mm: the tool stops with the surfaces within the collision tolerance.
    fn touch(
        &mut self,
        q0: &[f64],
        direction: Vector3<f64>,
        distance: f64,
    ) -> Result<(f64, Vec<f64>, Option<String>), TouchError> {
        let robot = self.doc.robots()[self.robot].shared_robot();
        let tcp0 = robot.tcp_pose(q0)?;
        let ik = IkOptions::default();
        let at = |s: f64, near: &[f64]| -> Result<Vec<f64>, TouchError> {
            let target = Transform::from_translation(direction * s).then(&tcp0);
            let sol = robot
                .inverse_nearest(&target, near, &ik)
                .map_err(|source| TouchError::Ik { at: s, source })?;
            if let Some(joint) = robot.limit_violation(&sol.joints) {
                return Err(TouchError::Limit { joint, at: s });
            }
            Ok(sol.joints)
        };
        let baseline: HashSet<(usize, usize)> = self.contacts(q0)?.into_iter().collect();
        let n = ((distance / 0.2).ceil() as usize).clamp(1, 100_000);
        let (mut free_s, mut free_q) = (0.0, q0.to_vec());
        for k in 1..=n {
            let s = distance * k as f64 / n as f64;
            let q = at(s, &free_q)?;
            let hit: Vec<_> = self
                .contacts(&q)?
                .into_iter()
                .filter(|p| !baseline.contains(p))
                .collect();
            if let Some(&(a, b)) = hit.first() {
                // Bisect between the last free step and this one.
                let (mut lo, mut hi, mut with) = (free_s, s, (a, b));
                while hi - lo > 1e-4 {
                    let mid = 0.5 * (lo + hi);
                    let qm = at(mid, &free_q)?;
                    let hit: Vec<_> = self
                        .contacts(&qm)?
                        .into_iter()
                        .filter(|p| !baseline.contains(p))
                        .collect();
                    match hit.first() {
                        Some(&p) => {
                            hi = mid;
                            with = p;
                        }
                        None => {
                            lo = mid;
                            free_q = qm;
                        }
                    }
                }
                let c = self.doc.components();
                let other = if self.links.contains(&with.0) {
                    with.1
                } else {
                    with.0
                };
                return Ok((lo, free_q, Some(c[other].name.clone())));
            }
            free_s = s;
            free_q = q;
        }
        Ok((free_s, free_q, None))
    }

    /// Checks limits at `to` and interference along `from → to`. A joint that
    /// passes a limit by no more than the wire's rounding of that limit is put at
    /// the limit first ([`snap_to_limits`]).
    fn check(&mut self, from: &[f64], to: &mut [f64]) -> Result<(), (RefusalCode, String)> {
        let robot = self.doc.robots()[self.robot].shared_robot();
        snap_to_limits(
            &self.kinds,
            &robot
                .joint_limits()
                .iter()
                .map(|l| l.map(|l| (l.min, l.max)))
                .collect::<Vec<_>>(),
            to,
        );
        let to = &*to;
        if let Some(j) = robot.limit_violation(to) {
            let lim = robot.joint_limits()[j];
            return Err((
                RefusalCode::JointLimit(j),
                format!(
                    "joint {} = {} is outside its limits {:?}",
                    j + 1,
                    to[j],
                    lim.map(|l| (l.min, l.max))
                ),
            ));
        }
        let step = from
            .iter()
            .zip(to)
            .zip(&self.kinds)
            .map(|((a, b), k)| {
                let d = (b - a).abs();
                match k {
                    // Prismatic joints are checked every 2 mm.
                    JointKind::Prismatic => d / 2.0 * self.check_step,
                    _ => d,
                }
            })
            .fold(0.0, f64::max);
        let n = ((step / self.check_step).ceil() as usize).clamp(1, 500);
        for i in 1..=n {
            let s = i as f64 / n as f64;
            let q: Vec<f64> = from.iter().zip(to).map(|(a, b)| a + (b - a) * s).collect();
            let pairs = self
                .pairs(&q)
                .map_err(|e| (RefusalCode::BadPoint, e.to_string()))?;
            if let Some(&(a, b)) = pairs.iter().find(|p| !self.baseline.contains(p)) {
                let c = self.doc.components();
                return Err((
                    RefusalCode::Collision,
                    format!(
                        "`{}` would interfere with `{}` at {:.0}% of the segment",
                        c[a].name,
                        c[b].name,
                        s * 100.0
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// One queued segment: target joints (rad/mm) and duration (s, simulated time).
#[derive(Debug, Clone)]
struct Segment {
    to: Vec<f64>,
    duration: f64,
}

#[derive(Debug)]
struct State {
    joints: Vec<f64>,
    /// The current segment's start joints and elapsed time.
    current: Option<(Vec<f64>, Segment, f64)>,
    queue: VecDeque<Segment>,
    /// Joints at the end of the last queued point (where the next segment starts).
    last_target: Vec<f64>,
    last_seq: Option<i32>,
    error: Option<RefusalCode>,
    gripper: f32,
    outputs: [bool; 32],
}

impl State {
    fn in_motion(&self) -> bool {
        self.current.is_some() || !self.queue.is_empty()
    }

    fn stop(&mut self) {
        self.current = None;
        self.queue.clear();
        self.last_target = self.joints.clone();
    }

    fn status(&self) -> Status {
        Status {
            drives_powered: TriState::On,
            e_stopped: TriState::Off,
            error_code: self.error.map_or(0, RefusalCode::code),
            in_error: TriState::from_bool(self.error.is_some()),
            in_motion: TriState::from_bool(self.in_motion()),
            mode: RobotMode::Auto,
            motion_possible: TriState::from_bool(self.error.is_none()),
        }
    }

    /// Advances the motion by `dt` seconds of simulated time.
    fn advance(&mut self, mut dt: f64) {
        while dt > 0.0 {
            if self.current.is_none() {
                match self.queue.pop_front() {
                    Some(seg) => self.current = Some((self.joints.clone(), seg, 0.0)),
                    None => return,
                }
            }
            let (from, seg, elapsed) = self.current.as_mut().expect("set above");
            let left = seg.duration - *elapsed;
            if dt >= left {
                dt -= left.max(0.0);
                self.joints = seg.to.clone();
                self.current = None;
            } else {
                *elapsed += dt;
                let s = *elapsed / seg.duration;
                self.joints = from
                    .iter()
                    .zip(&seg.to)
                    .map(|(a, b)| a + (b - a) * s)
                    .collect();
                dt = 0.0;
            }
        }
    }
}

/// A running simulator; dropping it (or [`Simulator::shutdown`]) stops its threads.
pub struct Simulator {
    motion_addr: SocketAddr,
    state_addr: SocketAddr,
    stop: Arc<AtomicBool>,
    state: Arc<Mutex<State>>,
    threads: Vec<std::thread::JoinHandle<()>>,
}

impl Simulator {
    /// Starts the simulator for robot `robot` of `doc` (at its saved joints) on
    /// 127.0.0.1.
    ///
    /// # Errors
    /// An unknown robot, a cell that cannot be checked, a port in use.
    pub fn start(
        doc: &Document,
        robot: &str,
        options: &SimulatorOptions,
    ) -> Result<Self, SimulatorError> {
        let index = doc.robot_index(robot).map_err(SimulatorError::Robot)?;
        let inst = &doc.robots()[index];
        let kinds = inst.robot().joint_kinds();
        if kinds.len() > MAX_JOINTS {
            return Err(SimulatorError::TooManyJoints {
                robot: robot.to_string(),
                joints: kinds.len(),
            });
        }
        let links: HashSet<usize> = inst.links().iter().filter_map(|l| l.component).collect();
        let joints = inst.joints().to_vec();
        let mut cell = Cell {
            doc: doc.clone(),
            robot: index,
            kinds: kinds.clone(),
            links,
            baseline: HashSet::new(),
            cache: SceneCache::new(),
            check_step: options.check_step.max(1e-3),
        };
        cell.baseline = cell
            .pairs(&joints)
            .map_err(SimulatorError::Cell)?
            .into_iter()
            .collect();
        let bind = |port: u16| {
            TcpListener::bind((Ipv4Addr::LOCALHOST, port))
                .map_err(|source| SimulatorError::Bind { port, source })
        };
        let motion = bind(options.motion_port)?;
        let state_l = bind(options.state_port)?;
        let motion_addr = motion.local_addr().expect("bound");
        let state_addr = state_l.local_addr().expect("bound");
        for l in [&motion, &state_l] {
            l.set_nonblocking(true).expect("nonblocking listener");
        }
        let stop = Arc::new(AtomicBool::new(false));
        let heard: Heard = Arc::new(Mutex::new(None));
        let state = Arc::new(Mutex::new(State {
            last_target: joints.clone(),
            joints,
            current: None,
            queue: VecDeque::new(),
            last_seq: None,
            error: None,
            gripper: 0.0,
            outputs: [false; 32],
        }));
        let cell = Arc::new(Mutex::new(cell));
        let mut threads = Vec::new();
        // Motion clock.
        {
            let (stop, state, speed) = (stop.clone(), state.clone(), options.speed.max(1e-3));
            threads.push(std::thread::spawn(move || {
                let mut last = Instant::now();
                while !stop.load(Ordering::Relaxed) {
                    std::thread::sleep(Duration::from_millis(5));
                    let now = Instant::now();
                    let dt = (now - last).as_secs_f64() * speed;
                    last = now;
                    lock(&state).advance(dt);
                }
            }));
        }
        // Motion port.
        {
            let (stop, state, opts) = (stop.clone(), state.clone(), options.clone());
            let (kinds, heard) = (kinds.clone(), heard.clone());
            threads.push(std::thread::spawn(move || {
                accept_loop(motion, "motion", &stop, |stream, conn| {
                    let (stop, state, cell, kinds, opts, heard) = (
                        stop.clone(),
                        state.clone(),
                        cell.clone(),
                        kinds.clone(),
                        opts.clone(),
                        heard.clone(),
                    );
                    std::thread::spawn(move || {
                        let ctx = Ctx {
                            state: &state,
                            cell: &cell,
                            kinds: &kinds,
                            opts: &opts,
                            heard: &heard,
                        };
                        serve_motion(stream, &conn, &stop, &ctx)
                    });
                })
            }));
        }
        // State port.
        {
            let (stop, state, opts) = (stop.clone(), state.clone(), options.clone());
            threads.push(std::thread::spawn(move || {
                accept_loop(state_l, "state", &stop, |stream, conn| {
                    let (stop, state, kinds, opts) =
                        (stop.clone(), state.clone(), kinds.clone(), opts.clone());
                    // Fixed when the client connects: one stream, one order.
                    let order = opts.byte_order.or(*lock(&heard)).unwrap_or(ByteOrder::Big);
                    std::thread::spawn(move || {
                        serve_state(stream, &conn, &stop, &state, &kinds, &opts, order)
                    });
                })
            }));
        }
        Ok(Self {
            motion_addr,
            state_addr,
            stop,
            state,
            threads,
        })
    }

    /// The motion port's address.
    pub fn motion_addr(&self) -> SocketAddr {
        self.motion_addr
    }

    /// The state port's address.
    pub fn state_addr(&self) -> SocketAddr {
        self.state_addr
    }

    /// Current joints (rad, mm).
    pub fn joints(&self) -> Vec<f64> {
        lock(&self.state).joints.clone()
    }

    /// Current gripper opening (m, as last commanded).
    pub fn gripper(&self) -> f32 {
        lock(&self.state).gripper
    }

    /// Stops every thread and closes the ports.
    pub fn shutdown(mut self) {
        self.stop_threads();
    }

    fn stop_threads(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl Drop for Simulator {
    fn drop(&mut self) {
        self.stop_threads();
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // A panicked connection thread must not take the controller down.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// One served connection, as the accept loop sees it.
struct Conn {
    /// Set by the accept loop to make the serving thread close the connection.
    closed: AtomicBool,
    /// The connection sent a whole packet (it is a client, not an idle socket).
    spoke: AtomicBool,
    /// The serving thread ended.
    ended: AtomicBool,
    /// A handle to shut the socket down from the accept loop.
    stream: Option<TcpStream>,
    opened: Instant,
}

impl Conn {
    fn close(&self) {
        self.closed.store(true, Ordering::Relaxed);
        if let Some(s) = &self.stream {
            let _ = s.shutdown(std::net::Shutdown::Both);
        }
    }
    fn open(&self, stop: &AtomicBool) -> bool {
        !stop.load(Ordering::Relaxed) && !self.closed.load(Ordering::Relaxed)
    }
}

/// Accepts connections, at most [`MAX_CONNECTIONS`] served at once (see the module
/// documentation for which one gives way when the port is full).
fn accept_loop(
    listener: TcpListener,
    port: &str,
    stop: &AtomicBool,
    mut serve: impl FnMut(TcpStream, Arc<Conn>),
) {
    let mut conns: Vec<Arc<Conn>> = Vec::new();
    let mut warned = false;
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => {
                let _ = stream.set_nonblocking(false);
                let _ = stream.set_nodelay(true);
                conns.retain(|c| !c.ended.load(Ordering::Relaxed));
                if conns.len() >= MAX_CONNECTIONS {
                    let victim = conns
                        .iter()
                        .position(|c| !c.spoke.load(Ordering::Relaxed))
                        .unwrap_or(0);
                    conns.remove(victim).close();
                    if !warned {
                        eprintln!(
                            "manipulator: {port} port full ({MAX_CONNECTIONS} connections): closing the oldest idle one for each new one"
                        );
                        warned = true;
                    }
                }
                let conn = Arc::new(Conn {
                    closed: AtomicBool::new(false),
                    spoke: AtomicBool::new(false),
                    ended: AtomicBool::new(false),
                    stream: stream.try_clone().ok(),
                    opened: Instant::now(),
                });
                conns.push(conn.clone());
                serve(stream, conn);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                // Ended connections give their socket back now, not at the next accept.
                conns.retain(|c| !c.ended.load(Ordering::Relaxed));
                std::thread::sleep(Duration::from_millis(10));
            }
            Err(e) => {
                eprintln!("manipulator: accept failed: {e}");
                std::thread::sleep(Duration::from_millis(100));
            }
        }
    }
    for c in conns {
        c.close();
    }
}

/// The byte order of the last motion connection that sent a frame (what a state
/// connection speaks when no order is forced).
type Heard = Arc<Mutex<Option<ByteOrder>>>;

/// What a motion connection's thread works on.
struct Ctx<'a> {
    state: &'a Mutex<State>,
    cell: &'a Mutex<Cell>,
    kinds: &'a [JointKind],
    opts: &'a SimulatorOptions,
    heard: &'a Mutex<Option<ByteOrder>>,
}

fn serve_state(
    mut stream: TcpStream,
    conn: &Conn,
    stop: &AtomicBool,
    state: &Mutex<State>,
    kinds: &[JointKind],
    opts: &SimulatorOptions,
    order: ByteOrder,
) {
    let _ = stream.set_write_timeout(Some(Duration::from_secs(2)));
    while conn.open(stop) {
        let (joints, status) = {
            let s = lock(state);
            (joints_to_wire(kinds, &s.joints), s.status())
        };
        let mut bytes = Packet::topic(
            msg_type::JOINT_POSITION,
            Body::JointPosition(super::message::JointPosition {
                sequence: 0,
                joints,
            }),
        )
        .encode(order);
        bytes.extend(Packet::topic(msg_type::STATUS, Body::Status(status)).encode(order));
        if stream.write_all(&bytes).is_err() {
            break; // the client left, or reads nothing
        }
        std::thread::sleep(opts.publish_interval);
    }
    let _ = stream.shutdown(std::net::Shutdown::Both);
    conn.ended.store(true, Ordering::Relaxed);
}

fn serve_motion(mut stream: TcpStream, conn: &Conn, stop: &AtomicBool, ctx: &Ctx<'_>) {
    let peer = stream
        .peer_addr()
        .map_or_else(|_| "?".to_string(), |a| a.to_string());
    if let Some(why) = serve_motion_packets(&mut stream, &peer, conn, stop, ctx) {
        eprintln!("manipulator: {peer}: {why}; closing the connection");
    }
    // Closed now, whoever else holds the socket (the accept loop keeps a clone to
    // close it from outside): the peer reads EOF at once, not when the slot is
    // reused by a later connection.
    let _ = stream.shutdown(std::net::Shutdown::Both);
    conn.ended.store(true, Ordering::Relaxed);
}

/// Serves one motion connection until it ends; returns why it was closed when that
/// is worth a log line.
fn serve_motion_packets(
    stream: &mut TcpStream,
    peer: &str,
    conn: &Conn,
    stop: &AtomicBool,
    ctx: &Ctx<'_>,
) -> Option<String> {
    // Short read timeouts so that shutdown and the idle limits are noticed; the
    // framing buffer keeps a packet's first bytes across them.
    let _ = stream.set_read_timeout(Some(Duration::from_millis(200)));
    let _ = stream.set_write_timeout(Some(Duration::from_secs(2)));
    let mut frames = ctx
        .opts
        .byte_order
        .map_or_else(FrameReader::detecting, FrameReader::new);
    // Its first packet, the rest of a packet begun, the next packet (re-armed by each).
    let first_packet = Deadline::from_start(conn.opened, FIRST_PACKET_TIMEOUT);
    let mut next_packet = Deadline::from_start(conn.opened, IDLE_TIMEOUT);
    let mut packet_end: Option<Deadline> = None;
    let mut logged = 0usize;
    let mut log = |line: String| {
        logged += 1;
        if logged <= MAX_LOGGED_PER_CONNECTION {
            eprintln!("manipulator: {peer}: {line}");
        }
        if logged == MAX_LOGGED_PER_CONNECTION {
            eprintln!("manipulator: {peer}: further refused or ignored messages of this connection are not logged");
        }
    };
    while conn.open(stop) {
        let frame = match frames.read_frame(stream) {
            Ok(f) => f,
            Err(CodecError::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                if frames.pending() > 0 {
                    let end =
                        *packet_end.get_or_insert_with(|| Deadline::after(PARTIAL_PACKET_TIMEOUT));
                    if end.passed() {
                        return Some(format!(
                            "a packet started {} s ago is still incomplete ({} bytes)",
                            PARTIAL_PACKET_TIMEOUT.as_secs(),
                            frames.pending()
                        ));
                    }
                } else if !conn.spoke.load(Ordering::Relaxed) && first_packet.passed() {
                    return Some(format!(
                        "no packet within {} s of connecting",
                        FIRST_PACKET_TIMEOUT.as_secs()
                    ));
                } else if next_packet.passed() {
                    return Some(format!("idle for {} s", IDLE_TIMEOUT.as_secs()));
                }
                continue;
            }
            Err(CodecError::Io(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof => return None,
            Err(_) if !conn.open(stop) => return None,
            // A bad length prefix or a stream cut inside a frame: byte counting is
            // all simple_message has, so the stream cannot be re-synchronised and
            // this connection ends.
            Err(e) => return Some(e.to_string()),
        };
        packet_end = None;
        next_packet = Deadline::after(IDLE_TIMEOUT);
        if !conn.spoke.swap(true, Ordering::Relaxed) {
            // The first frame fixed this connection's order: later state clients
            // speak it too (unless an order is forced).
            *lock(ctx.heard) = Some(frame.order());
        }
        let reply = match frame.decode() {
            Ok(packet) => handle(&packet, ctx, &mut log),
            Err(e) => undecodable(&frame, &e, ctx, &mut log),
        };
        if let Some(r) = reply {
            if let Err(e) = r.write_to(stream, frame.order()) {
                return Some(e.to_string());
            }
        }
    }
    None
}

/// The answer to a whole frame whose content does not decode (REP-I0006, header
/// notes): a SERVICE_REQUEST gets a SERVICE_REPLY with FAILURE, header only, and the
/// connection stays open; anything else (a topic of a type it does not know, a reply
/// nobody asked for, a bad comm type) is ignored, with a log line. A JOINT_TRAJ_PT
/// request is refused as a bad point (code 4000 in STATUS, motion stopped), as a
/// point that decodes but cannot be executed is.
fn undecodable(
    frame: &Frame,
    e: &CodecError,
    ctx: &Ctx<'_>,
    log: &mut impl FnMut(String),
) -> Option<Packet> {
    let h = frame.header();
    if !h.is_request() {
        let what = match h.comm_type {
            1 => "topic",
            3 => "reply",
            _ => "message with an invalid comm_type",
        };
        log(format!("ignored a {what} of type {}: {e}", h.msg_type));
        return None;
    }
    if h.msg_type == msg_type::JOINT_TRAJ_PT {
        refuse_point(ctx.state, RefusalCode::BadPoint);
        log(format!(
            "refused a trajectory point: {}: {e}",
            RefusalCode::BadPoint.code()
        ));
    } else {
        log(format!(
            "replied FAILURE to a request of type {}: {e}",
            h.msg_type
        ));
    }
    Some(Packet::reply(h.msg_type, ReplyCode::Failure, Body::Empty))
}

/// Puts every joint of `q` (rad, mm) that passes one of its `limits` by no more than
/// the wire's rounding of that limit at the limit. simple_message carries joints as
/// f32 (rad, m): a controller at a limit reports the f32 nearest to it, which can be
/// a hair past it (3 mm is 0.003000000026 m), and a client that sends that state
/// back as the first point of a new trajectory (the rule that clears an error) must
/// not be refused for the rounding — that left a controller in error for good.
pub(crate) fn snap_to_limits(kinds: &[JointKind], limits: &[Option<(f64, f64)>], q: &mut [f64]) {
    for ((v, k), lim) in q.iter_mut().zip(kinds).zip(limits) {
        let Some((lo, hi)) = *lim else { continue };
        let scale = match k {
            JointKind::Prismatic => 1000.0,
            _ => 1.0,
        };
        // The rounding of a limit on the wire, in joint units: the distance to its
        // f32, plus one f32 step there (the value may have been rounded once more).
        let slack = |l: f64| {
            let w = l / scale;
            ((f64::from(w as f32) - w).abs() + w.abs() * f64::from(f32::EPSILON)) * scale
        };
        if *v > hi && *v - hi <= slack(hi) {
            *v = hi;
        } else if *v < lo && lo - *v <= slack(lo) {
            *v = lo;
        }
    }
}

/// Puts the controller in error with `code` and stops any motion (a refused point).
fn refuse_point(state: &Mutex<State>, code: RefusalCode) {
    let mut s = lock(state);
    s.stop();
    s.error = Some(code);
    s.last_seq = None;
}

/// The reply to one request (None for topics, which need none).
fn handle(p: &Packet, ctx: &Ctx<'_>, log: &mut impl FnMut(String)) -> Option<Packet> {
    use super::message::CommType;
    let state = ctx.state;
    match p.comm_type {
        CommType::ServiceRequest => {}
        CommType::Topic => {
            // REP-I0006: receivers ignore topics they do not act on.
            log(format!("ignored a topic of type {}", p.msg_type));
            return None;
        }
        CommType::ServiceReply => return None,
    }
    let ok = |t| Some(Packet::reply(t, ReplyCode::Success, Body::Empty));
    let fail = |t| Some(Packet::reply(t, ReplyCode::Failure, Body::Empty));
    match (p.msg_type, &p.body) {
        // Either form: ten zero ints (REP-I0006) or header only (what
        // industrial_core's PingMessage sends); the reply has the request's form.
        (msg_type::PING, Body::Ping | Body::Empty) => Some(Packet::reply(
            msg_type::PING,
            ReplyCode::Success,
            p.body.clone(),
        )),
        (_, Body::JointTrajPt(pt)) => match enqueue(pt, state, ctx.cell, ctx.kinds, ctx.opts) {
            Ok(()) => ok(msg_type::JOINT_TRAJ_PT),
            Err((code, why)) => {
                eprintln!("manipulator: refused point {}: {code}: {why}", pt.sequence);
                refuse_point(state, code);
                fail(msg_type::JOINT_TRAJ_PT)
            }
        },
        (_, Body::Tool(t)) if t.action == ToolAction::Touch => {
            let Some(direction) = touch_direction(t.index) else {
                log(format!(
                    "refused TOUCH along axis index {} (0..=5)",
                    t.index
                ));
                return fail(msg_type::FITUP_TOOL);
            };
            let distance = f64::from(t.value) * 1000.0;
            if !(distance.is_finite() && (0.0..=MAX_TOUCH_MM).contains(&distance)) {
                log(format!(
                    "refused TOUCH of {distance} mm (0 to {MAX_TOUCH_MM} mm)"
                ));
                return fail(msg_type::FITUP_TOOL);
            }
            let q0 = {
                let s = lock(state);
                if s.in_motion() || s.error.is_some() {
                    log("refused TOUCH while moving or in error".into());
                    return fail(msg_type::FITUP_TOOL);
                }
                s.joints.clone()
            };
            let result = lock(ctx.cell).touch(&q0, direction, distance);
            match result {
                Ok((travelled, q, with)) => {
                    match &with {
                        Some(c) => eprintln!(
                            "manipulator: touch: contact with `{c}` after {travelled:.4} mm"
                        ),
                        None => eprintln!("manipulator: touch: no contact within {distance} mm"),
                    }
                    let mut s = lock(state);
                    s.joints.clone_from(&q);
                    s.stop();
                    let mut reply = *t;
                    reply.value = (travelled / 1000.0) as f32;
                    Some(Packet::reply(
                        msg_type::FITUP_TOOL,
                        ReplyCode::Success,
                        Body::Tool(reply),
                    ))
                }
                Err(why) => {
                    eprintln!("manipulator: touch refused: {why}");
                    fail(msg_type::FITUP_TOOL)
                }
            }
        }
        (_, Body::Tool(t)) => {
            let mut s = lock(state);
            let reply = *t;
            match t.action {
                ToolAction::Grasp | ToolAction::Release => {
                    if !(0.0..=1.0).contains(&t.value) {
                        return fail(msg_type::FITUP_TOOL);
                    }
                    s.gripper = t.value;
                }
                // Served above (the guarded move).
                ToolAction::Touch => return fail(msg_type::FITUP_TOOL),
                ToolAction::SetOutput => {
                    let Some(o) = usize::try_from(t.index)
                        .ok()
                        .and_then(|i| s.outputs.get_mut(i))
                    else {
                        return fail(msg_type::FITUP_TOOL);
                    };
                    *o = t.value != 0.0;
                }
            }
            Some(Packet::reply(
                msg_type::FITUP_TOOL,
                ReplyCode::Success,
                Body::Tool(reply),
            ))
        }
        // REP-I0006: a request for an unsupported service gets FAILURE.
        _ => {
            log(format!(
                "replied FAILURE to a request of type {} (not a service it offers)",
                p.msg_type
            ));
            fail(p.msg_type)
        }
    }
}

fn enqueue(
    pt: &JointTrajPt,
    state: &Mutex<State>,
    cell: &Mutex<Cell>,
    kinds: &[JointKind],
    opts: &SimulatorOptions,
) -> Result<(), (RefusalCode, String)> {
    match pt.sequence {
        special_seq::STOP_TRAJECTORY => {
            let mut s = lock(state);
            s.stop();
            s.last_seq = None;
            return Ok(());
        }
        special_seq::START_TRAJECTORY_STREAMING
        | special_seq::START_TRAJECTORY_DOWNLOAD
        | special_seq::END_TRAJECTORY => return Ok(()),
        n if n < 0 => return Err((RefusalCode::BadPoint, format!("sequence {n} is reserved"))),
        _ => {}
    }
    if pt.joints[kinds.len()..].iter().any(|&v| v != 0.0) {
        return Err((
            RefusalCode::BadPoint,
            format!("this robot has {} joints; the rest must be 0", kinds.len()),
        ));
    }
    let target = joints_from_wire(kinds, &pt.joints);
    let from = {
        let mut s = lock(state);
        if pt.sequence == 0 {
            // A new trajectory: stop whatever runs and start from where the arm is.
            s.stop();
            s.error = None;
        } else if s.last_seq != Some(pt.sequence - 1) {
            return Err((
                RefusalCode::OutOfOrder,
                format!(
                    "point {} after {}",
                    pt.sequence,
                    s.last_seq.map_or("nothing".into(), |v| v.to_string())
                ),
            ));
        }
        s.last_target.clone()
    };
    let travel = from
        .iter()
        .zip(&target)
        .zip(kinds)
        .map(|((a, b), k)| match k {
            JointKind::Prismatic => (b - a).abs() / 1000.0,
            _ => (b - a).abs(),
        })
        .fold(0.0, f64::max);
    // REP-I0006: durations or velocities outside the controller's bounds are an
    // error. The codec already refused non-finite ones.
    if pt.duration < 0.0 || !(0.0..=1.0).contains(&pt.velocity) {
        return Err((
            RefusalCode::BadPoint,
            format!(
                "duration {} s (must be ≥ 0) or velocity {} (must be in [0, 1])",
                pt.duration, pt.velocity
            ),
        ));
    }
    let duration = if pt.duration > 0.0 {
        pt.duration as f64
    } else if pt.velocity > 0.0 && pt.velocity <= 1.0 {
        travel / (opts.max_joint_speed * pt.velocity as f64)
    } else if travel == 0.0 {
        0.0
    } else {
        return Err((
            RefusalCode::BadPoint,
            format!(
                "no duration ({}) and velocity {} outside (0, 1]",
                pt.duration, pt.velocity
            ),
        ));
    };
    let mut target = target;
    lock(cell).check(&from, &mut target)?;
    let mut s = lock(state);
    s.last_seq = Some(pt.sequence);
    s.last_target = target.clone();
    s.queue.push_back(Segment {
        to: target,
        duration,
    });
    Ok(())
}
