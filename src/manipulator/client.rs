//! A simple_message client: streams joint trajectories to the motion port, sends
//! tool commands (fitup's extension) and follows JOINT_POSITION / STATUS from the
//! state port on a background thread.
//!
//! Every wait is bounded ([`ClientOptions`]); a connection that breaks, goes silent
//! or sends garbage gives [`ManipulatorError::Disconnected`], so a caller can
//! reconnect and resume. Replies and state messages may arrive in parts with pauses
//! between them: each connection keeps its partial packet across read timeouts
//! ([`FrameReader`]). A value that does not fit the wire (a 32-bit float, e.g. a
//! joint of 1e39 rad) is refused before anything is sent
//! ([`ManipulatorError::NotOnWire`]).

use super::message::{
    msg_type, special_seq, Body, ByteOrder, CodecError, CommType, FrameReader, JointTrajPt, Packet,
    ReplyCode, Status, ToolAction, ToolCommand, TriState, MAX_JOINTS, TOOL_EXTENSION_VERSION,
};
use super::{joints_from_wire, joints_to_wire, RefusalCode};
use crate::kinematics::JointKind;
use crate::math::Deadline;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use thiserror::Error;

/// Timeouts and safety settings of a [`Client`].
#[derive(Debug, Clone)]
pub struct ClientOptions {
    /// Byte order of the controller (big-endian by default: REP-I0006's examples,
    /// and the order the big-endian controllers' drivers put on the wire).
    pub byte_order: ByteOrder,
    /// Longest wait for a TCP connection.
    pub connect_timeout: Duration,
    /// Longest wait for the reply to a request.
    pub reply_timeout: Duration,
    /// The state port counts as lost after this long without a message.
    pub state_timeout: Duration,
    /// Allow an address that is not loopback (a real controller). Off by default:
    /// nothing moves a real robot unless asked for explicitly.
    pub allow_remote: bool,
}

impl Default for ClientOptions {
    fn default() -> Self {
        Self {
            byte_order: ByteOrder::Big,
            connect_timeout: Duration::from_secs(2),
            reply_timeout: Duration::from_secs(5),
            state_timeout: Duration::from_secs(2),
            allow_remote: false,
        }
    }
}

/// What went wrong talking to a controller.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ManipulatorError {
    /// The address is not loopback and remote dispatch was not allowed.
    #[error("{0} is not the local simulator (127.0.0.1): pass --allow-remote to command a real controller")]
    NotLocal(String),
    /// The address cannot be used.
    #[error("bad address `{addr}`: {cause}")]
    Address {
        /// The address as given (`HOST:PORT`).
        addr: String,
        /// Why it cannot be used.
        #[source]
        cause: AddressError,
    },
    /// No connection.
    #[error("cannot connect to {addr}: {source}")]
    Connect {
        /// The address.
        addr: SocketAddr,
        /// The cause.
        source: std::io::Error,
    },
    /// The connection broke, went silent, or the controller sent garbage.
    #[error("controller disconnected: {port} port: {cause}")]
    Disconnected {
        /// The connection that was lost.
        port: Port,
        /// How it was lost.
        #[source]
        cause: Lost,
    },
    /// The controller dropped the connection every time one command of a skill was
    /// sent ([`crate::skills`]' manager gives up: the controller refuses that command).
    #[error("controller disconnected: {port} port: {cause}; the controller dropped the connection {drops} times at command {command} of this skill: giving up (it refuses that command)")]
    DroppedAt {
        /// The connection lost the last time.
        port: Port,
        /// How it was lost the last time.
        #[source]
        cause: Lost,
        /// How many times in a row.
        drops: usize,
        /// The command of the skill (1-based).
        command: usize,
    },
    /// The controller refused a request (a FAILURE reply).
    #[error("controller refused {request}: {}", refusal_text(*.code, *.error_code))]
    Refused {
        /// What was refused.
        request: Request,
        /// The simple_message type of the refused request ([`msg_type`]).
        msg_type: i32,
        /// The controller's reason, when it is one fitup knows.
        code: Option<RefusalCode>,
        /// The STATUS `error_code` that followed the refusal, when one did.
        error_code: Option<i32>,
    },
    /// The controller did not finish in time.
    #[error("timeout: the controller did not reach the target within {} s", .waited.as_secs_f64())]
    Timeout {
        /// How long it was waited for.
        waited: Duration,
    },
    /// The controller reports an error state.
    #[error("controller in error (code {0})")]
    InError(i32),
    /// A value that the wire format cannot carry (not finite as a 32-bit float, more
    /// joints than simple_message carries); nothing was sent.
    #[error("{request} cannot be sent: {cause}")]
    NotOnWire {
        /// What could not be sent.
        request: Request,
        /// Why.
        #[source]
        cause: WireError,
    },
}

/// The reason text of [`ManipulatorError::Refused`].
fn refusal_text(code: Option<RefusalCode>, error_code: Option<i32>) -> String {
    match (code, error_code) {
        (Some(c), _) => c.to_string(),
        (None, Some(n)) => format!("controller error code {n}"),
        (None, None) => "FAILURE reply without a reason in STATUS".into(),
    }
}

/// Why an address cannot be used ([`ManipulatorError::Address`]).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum AddressError {
    /// `HOST:PORT` does not parse or the host does not resolve.
    #[error("{0}")]
    Resolve(#[source] std::io::Error),
    /// It resolves to no address at all.
    #[error("it resolves to no address")]
    NoAddress,
    /// The state port by the rule (motion port + [`super::STATE_PORT_OFFSET`]) is
    /// beyond 65535.
    #[error(
        "no state port {port} + {}: give the state port",
        super::STATE_PORT_OFFSET
    )]
    NoStatePort {
        /// The motion port.
        port: u16,
    },
}

/// A controller connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Port {
    /// The motion port (requests and their replies).
    Motion,
    /// The state port (JOINT_POSITION and STATUS topics).
    State,
}

impl std::fmt::Display for Port {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Motion => "motion",
            Self::State => "state",
        })
    }
}

/// How a connection was lost ([`ManipulatorError::Disconnected`]). Cheap to clone:
/// the state port's reader keeps it and every later call reports it.
#[derive(Debug, Clone, Error)]
#[non_exhaustive]
pub enum Lost {
    /// The controller closed the connection.
    #[error("connection closed")]
    Closed,
    /// Nothing came within the wait: no reply (motion port), no state message or no
    /// first joint state (state port).
    #[error("no {awaited} within {} s", .waited.as_secs_f64())]
    Silent {
        /// What was awaited (`reply`, `state message`, `joint state`).
        awaited: &'static str,
        /// How long.
        waited: Duration,
    },
    /// A read or write failed, or the controller sent bytes that are not a
    /// simple_message packet.
    #[error("{0}")]
    Codec(#[source] Arc<CodecError>),
}

impl From<CodecError> for Lost {
    /// An end of stream is [`Lost::Closed`]; anything else is kept.
    fn from(e: CodecError) -> Self {
        match e {
            CodecError::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => Self::Closed,
            e => Self::Codec(Arc::new(e)),
        }
    }
}

/// A request to the controller, as errors name it.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum Request {
    /// PING.
    Ping,
    /// One JOINT_TRAJ_PT.
    Point {
        /// Its sequence number.
        sequence: i32,
    },
    /// A tool command of fitup's extension (FITUP_TOOL).
    Tool {
        /// The action as the plan names it (`grasp`, `Touch`…).
        action: String,
    },
    /// The robot itself (its joint count), checked when connecting.
    Robot,
}

impl std::fmt::Display for Request {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Ping => write!(f, "ping"),
            Self::Point { sequence } => write!(f, "trajectory point {sequence}"),
            Self::Tool { action } => write!(f, "tool command {action}"),
            Self::Robot => write!(f, "the robot"),
        }
    }
}

/// Why a value cannot go on the wire ([`ManipulatorError::NotOnWire`], [`wire_point`]).
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum WireError {
    /// More joints than simple_message carries.
    #[error("{joints} joints, simple_message carries at most {MAX_JOINTS}")]
    TooManyJoints {
        /// The robot's joint count.
        joints: usize,
    },
    /// Not one value per joint.
    #[error(
        "{got} joint values for a robot of {joints} joints (at most {MAX_JOINTS} on the wire)"
    )]
    JointCount {
        /// Values given.
        got: usize,
        /// The robot's joint count.
        joints: usize,
    },
    /// A joint value that is not a finite 32-bit float on the wire.
    #[error("joint {} = {value} does not fit the wire's 32-bit float (largest magnitude {:e})", .joint + 1, f32::MAX)]
    Joint {
        /// The joint (0-based; the message counts from 1).
        joint: usize,
        /// Its value (rad or mm).
        value: f64,
    },
    /// A duration that is not a finite 32-bit float ≥ 0.
    #[error("duration {0} s is not a finite 32-bit float ≥ 0")]
    Duration(f64),
    /// A tool value that is not finite.
    #[error("value {0} is not a finite 32-bit float")]
    ToolValue(f32),
    /// A tool action fitup's extension does not have.
    #[error("unknown tool action")]
    UnknownTool,
}

/// How often a blocked read wakes up to check its deadline and the stop flag.
const READ_SLICE: Duration = Duration::from_millis(100);

/// Whether an I/O error is a read timeout (retryable with a [`FrameReader`]).
fn timed_out(e: &CodecError) -> bool {
    matches!(e, CodecError::Io(io) if matches!(
        io.kind(),
        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
    ))
}

/// Joint state and status as last published by the controller.
#[derive(Debug, Clone)]
pub struct RobotState {
    /// Joints (rad, mm).
    pub joints: Vec<f64>,
    /// The last STATUS, if one arrived.
    pub status: Option<Status>,
}

#[derive(Debug, Default)]
struct Shared {
    joints: Option<Vec<f64>>,
    status: Option<Status>,
    /// When the last STATUS arrived.
    status_at: Option<Instant>,
    last_rx: Option<Instant>,
    broken: Option<Lost>,
}

/// A connection to a controller's motion and state ports.
pub struct Client {
    motion: TcpStream,
    /// The motion port's partial reply, kept across read timeouts.
    frames: FrameReader,
    options: ClientOptions,
    kinds: Vec<JointKind>,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    reader: Option<std::thread::JoinHandle<()>>,
}

/// Resolves `HOST:PORT` and applies the loopback rule.
///
/// # Errors
/// An unresolvable address, or one that is not loopback without `allow_remote`.
pub fn resolve(addr: &str, allow_remote: bool) -> Result<SocketAddr, ManipulatorError> {
    let a = addr
        .to_socket_addrs()
        .map_err(|e| ManipulatorError::Address {
            addr: addr.into(),
            cause: AddressError::Resolve(e),
        })?
        .next()
        .ok_or_else(|| ManipulatorError::Address {
            addr: addr.into(),
            cause: AddressError::NoAddress,
        })?;
    if !allow_remote && !a.ip().is_loopback() {
        return Err(ManipulatorError::NotLocal(addr.into()));
    }
    Ok(a)
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Client {
    /// Connects to the motion and state ports of a controller whose robot has joints
    /// of `kinds`, and waits for the first joint state. A PING goes out on the
    /// motion port before the state port is opened (its reply is awaited for at most
    /// a second and not required), so that a controller which detects the byte order
    /// from a client's first frame publishes state in the client's order.
    ///
    /// # Errors
    /// Not loopback (see [`ClientOptions::allow_remote`]), no connection, no state.
    pub fn connect(
        motion: SocketAddr,
        state: SocketAddr,
        kinds: Vec<JointKind>,
        options: &ClientOptions,
    ) -> Result<Self, ManipulatorError> {
        for a in [motion, state] {
            if !options.allow_remote && !a.ip().is_loopback() {
                return Err(ManipulatorError::NotLocal(a.to_string()));
            }
        }
        if kinds.len() > MAX_JOINTS {
            return Err(ManipulatorError::NotOnWire {
                request: Request::Robot,
                cause: WireError::TooManyJoints {
                    joints: kinds.len(),
                },
            });
        }
        let open = |addr: SocketAddr| {
            let s = TcpStream::connect_timeout(&addr, options.connect_timeout)
                .map_err(|source| ManipulatorError::Connect { addr, source })?;
            let _ = s.set_nodelay(true);
            let _ = s.set_read_timeout(Some(READ_SLICE));
            let _ = s.set_write_timeout(Some(options.reply_timeout));
            Ok::<_, ManipulatorError>(s)
        };
        let mut motion = open(motion)?;
        let mut frames = FrameReader::new(options.byte_order);
        // A PING first, so that a controller which detects the byte order from a
        // client's first frame (`fitup manipulator`) knows it before the state
        // connection opens: state clients never send. Its answer is not required
        // (a controller may not serve PING); a broken connection shows at the first
        // request.
        let _ = exchange(
            &mut motion,
            &mut frames,
            options.byte_order,
            &Packet::request(msg_type::PING, Body::Ping),
            options.reply_timeout.min(ANNOUNCE_TIMEOUT),
        );
        let mut state_stream = open(state)?;
        let state_timeout = options.state_timeout;
        let shared = Arc::new(Mutex::new(Shared::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let reader = {
            let (shared, stop, kinds, order) = (
                shared.clone(),
                stop.clone(),
                kinds.clone(),
                options.byte_order,
            );
            let mut frames = FrameReader::new(order);
            // Silence on the state port longer than `state_timeout` breaks it.
            let mut quiet_until = Deadline::after(state_timeout);
            std::thread::spawn(move || loop {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                let packet = frames.read_frame(&mut state_stream).and_then(|f| {
                    let h = f.header();
                    if !matches!(h.msg_type, msg_type::JOINT_POSITION | msg_type::STATUS) {
                        // REP-I0006: topics one does not know are ignored
                        // (JOINT_FEEDBACK, vendor messages…); the stream is in step.
                        return Ok(None);
                    }
                    f.decode().map(Some)
                });
                match packet {
                    Err(e) if timed_out(&e) && !quiet_until.passed() => continue,
                    Ok(None) => quiet_until = Deadline::after(state_timeout),
                    Ok(Some(p)) => {
                        quiet_until = Deadline::after(state_timeout);
                        let mut s = lock(&shared);
                        s.last_rx = Some(Instant::now());
                        match p.body {
                            Body::JointPosition(jp) => {
                                s.joints = Some(joints_from_wire(&kinds, &jp.joints))
                            }
                            Body::Status(st) => {
                                s.status = Some(st);
                                s.status_at = Some(Instant::now());
                            }
                            // REP-I0006: topics one does not know are ignored.
                            _ => {}
                        }
                    }
                    Err(e) => {
                        let why = if timed_out(&e) {
                            Lost::Silent {
                                awaited: "state message",
                                waited: state_timeout,
                            }
                        } else {
                            Lost::from(e)
                        };
                        lock(&shared).broken = Some(why);
                        return;
                    }
                }
            })
        };
        let client = Self {
            motion,
            frames,
            options: options.clone(),
            kinds,
            shared,
            stop,
            reader: Some(reader),
        };
        let deadline = Deadline::after(options.state_timeout);
        loop {
            {
                let s = lock(&client.shared);
                if s.joints.is_some() && s.status.is_some() {
                    break;
                }
                if let Some(b) = &s.broken {
                    return Err(state_lost(b.clone()));
                }
            }
            if deadline.passed() {
                return Err(state_lost(Lost::Silent {
                    awaited: "joint state",
                    waited: options.state_timeout,
                }));
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(client)
    }

    /// The joint kinds the client converts units for.
    pub fn joint_kinds(&self) -> &[JointKind] {
        &self.kinds
    }

    /// The latest state.
    ///
    /// # Errors
    /// `Disconnected` when the state connection broke or went silent.
    pub fn state(&self) -> Result<RobotState, ManipulatorError> {
        let s = lock(&self.shared);
        if let Some(b) = &s.broken {
            return Err(state_lost(b.clone()));
        }
        if s.last_rx
            .is_none_or(|t| t.elapsed() > self.options.state_timeout)
        {
            return Err(state_lost(Lost::Silent {
                awaited: "state message",
                waited: self.options.state_timeout,
            }));
        }
        Ok(RobotState {
            joints: s.joints.clone().unwrap_or_default(),
            status: s.status,
        })
    }

    fn request(&mut self, p: &Packet) -> Result<Packet, ManipulatorError> {
        exchange(
            &mut self.motion,
            &mut self.frames,
            self.options.byte_order,
            p,
            self.options.reply_timeout,
        )
    }

    /// Sends PING and waits for the reply.
    ///
    /// # Errors
    /// A broken connection or a FAILURE reply.
    pub fn ping(&mut self) -> Result<(), ManipulatorError> {
        let r = self.request(&Packet::request(msg_type::PING, Body::Ping))?;
        if r.reply_code != ReplyCode::Success {
            return Err(ManipulatorError::Refused {
                request: Request::Ping,
                msg_type: msg_type::PING,
                code: None,
                error_code: None,
            });
        }
        Ok(())
    }

    /// The reason of a refusal: the error code of the next STATUS after `since` with
    /// `in_error`, and the code fitup knows it as.
    fn refusal_reason(&self, since: Instant) -> (Option<RefusalCode>, Option<i32>) {
        let deadline = Deadline::after(self.options.reply_timeout.min(Duration::from_secs(2)));
        while !deadline.passed() {
            {
                let s = lock(&self.shared);
                if let (Some(st), Some(at)) = (s.status, s.status_at) {
                    if at >= since && st.in_error == TriState::On {
                        return (RefusalCode::from_code(st.error_code), Some(st.error_code));
                    }
                }
                if s.broken.is_some() {
                    break;
                }
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        (None, None)
    }

    /// Sends one JOINT_TRAJ_PT (joints rad/mm, duration s).
    ///
    /// # Errors
    /// `Refused` with the controller's reason, `Disconnected`.
    pub fn send_point(
        &mut self,
        sequence: i32,
        joints: &[f64],
        duration: f64,
    ) -> Result<(), ManipulatorError> {
        let request = || Request::Point { sequence };
        let pt = wire_point(&self.kinds, sequence, joints, duration).map_err(|cause| {
            ManipulatorError::NotOnWire {
                request: request(),
                cause,
            }
        })?;
        let sent = Instant::now();
        let r = self.request(&Packet::request(
            msg_type::JOINT_TRAJ_PT,
            Body::JointTrajPt(pt),
        ))?;
        if r.reply_code == ReplyCode::Success {
            return Ok(());
        }
        let (code, error_code) = self.refusal_reason(sent);
        Err(ManipulatorError::Refused {
            request: request(),
            msg_type: msg_type::JOINT_TRAJ_PT,
            code,
            error_code,
        })
    }

    /// Streams a trajectory: `(joints, duration from the previous point)`, sequence
    /// numbers from 0 (which starts a new trajectory on the controller).
    ///
    /// # Errors
    /// As [`send_point`](Self::send_point).
    pub fn stream(&mut self, points: &[(Vec<f64>, f64)]) -> Result<(), ManipulatorError> {
        for (i, (q, d)) in points.iter().enumerate() {
            self.send_point(i as i32, q, *d)?;
        }
        Ok(())
    }

    /// Stops any motion now (STOP_TRAJECTORY).
    ///
    /// # Errors
    /// As [`send_point`](Self::send_point).
    pub fn stop_motion(&mut self) -> Result<(), ManipulatorError> {
        let q = vec![0.0; self.kinds.len()];
        self.send_point(special_seq::STOP_TRAJECTORY, &q, 0.0)
    }

    /// Sends a tool command of fitup's extension; returns the reply's value.
    ///
    /// # Errors
    /// `Refused`, `Disconnected`.
    pub fn tool(
        &mut self,
        action: ToolAction,
        index: i32,
        value: f32,
    ) -> Result<f32, ManipulatorError> {
        let request = || Request::Tool {
            action: format!("{action:?}"),
        };
        if !value.is_finite() {
            return Err(ManipulatorError::NotOnWire {
                request: request(),
                cause: WireError::ToolValue(value),
            });
        }
        let r = self.request(&Packet::request(
            msg_type::FITUP_TOOL,
            Body::Tool(ToolCommand {
                version: TOOL_EXTENSION_VERSION,
                action,
                index,
                value,
            }),
        ))?;
        match (r.reply_code, r.body) {
            (ReplyCode::Success, Body::Tool(t)) => Ok(t.value),
            _ => Err(ManipulatorError::Refused {
                request: request(),
                msg_type: msg_type::FITUP_TOOL,
                code: Some(RefusalCode::BadTool),
                error_code: None,
            }),
        }
    }

    /// Waits until the controller is not moving and its joints are within `tol`
    /// (rad / mm) of `target`, checking `cancel` between polls.
    ///
    /// Returns `Ok(false)` when `cancel` returned true first.
    ///
    /// # Errors
    /// `Timeout` after `timeout`, `InError`, `Disconnected`.
    pub fn wait_until_at(
        &self,
        target: &[f64],
        tol: f64,
        timeout: Duration,
        cancel: &dyn Fn() -> bool,
    ) -> Result<bool, ManipulatorError> {
        let since = Instant::now();
        let deadline = Deadline::from_start(since, timeout);
        loop {
            let st = self.state()?;
            // Only a STATUS published after the wait began says anything about the
            // motion just sent (an older one may still carry a cleared error).
            let fresh = lock(&self.shared).status_at.is_some_and(|t| t > since);
            if let Some(status) = st.status.filter(|_| fresh) {
                if status.in_error == TriState::On {
                    return Err(ManipulatorError::InError(status.error_code));
                }
                let close = st.joints.len() == target.len()
                    && st
                        .joints
                        .iter()
                        .zip(target)
                        .all(|(a, b)| (a - b).abs() <= tol);
                if close && status.in_motion == TriState::Off {
                    return Ok(true);
                }
            }
            if cancel() {
                return Ok(false);
            }
            if deadline.passed() {
                return Err(ManipulatorError::Timeout { waited: timeout });
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

/// The state port lost, `cause` how.
fn state_lost(cause: Lost) -> ManipulatorError {
    ManipulatorError::Disconnected {
        port: Port::State,
        cause,
    }
}

/// Longest wait for the reply to the PING a client sends when it connects.
const ANNOUNCE_TIMEOUT: Duration = Duration::from_secs(1);

/// Sends request `p` on `motion` and waits up to `timeout` for its reply.
/// REP-I0006: replies nobody asked for and topics (of any type, even unknown ones)
/// are skipped without being decoded.
fn exchange(
    motion: &mut TcpStream,
    frames: &mut FrameReader,
    order: ByteOrder,
    p: &Packet,
    timeout: Duration,
) -> Result<Packet, ManipulatorError> {
    let lost = |e: CodecError| ManipulatorError::Disconnected {
        port: Port::Motion,
        cause: Lost::from(e),
    };
    p.write_to(motion, order).map_err(lost)?;
    let deadline = Deadline::after(timeout);
    loop {
        let f = match frames.read_frame(motion) {
            Ok(f) => f,
            Err(e) if timed_out(&e) => {
                if deadline.passed() {
                    return Err(ManipulatorError::Disconnected {
                        port: Port::Motion,
                        cause: Lost::Silent {
                            awaited: "reply",
                            waited: timeout,
                        },
                    });
                }
                continue;
            }
            Err(e) => return Err(lost(e)),
        };
        let h = f.header();
        if h.comm_type == CommType::ServiceReply as i32 && h.msg_type == p.msg_type {
            return f.decode().map_err(lost);
        }
    }
}

/// The JOINT_TRAJ_PT of one point (joints rad/mm, duration s), or why the wire cannot
/// carry it: every value must be a finite 32-bit float after the unit conversion
/// (prismatic joints in metres), and there must be exactly one value per joint.
///
/// # Errors
/// [`WireError`]: the joint count, the joint (with its value) or the duration.
pub fn wire_point(
    kinds: &[JointKind],
    sequence: i32,
    joints: &[f64],
    duration: f64,
) -> Result<JointTrajPt, WireError> {
    if joints.len() != kinds.len() || kinds.len() > MAX_JOINTS {
        return Err(WireError::JointCount {
            got: joints.len(),
            joints: kinds.len(),
        });
    }
    let wire = joints_to_wire(kinds, joints);
    if let Some(j) = wire.iter().position(|v| !v.is_finite()) {
        return Err(WireError::Joint {
            joint: j,
            value: joints[j],
        });
    }
    let d = duration as f32;
    if !(d.is_finite() && d >= 0.0) {
        return Err(WireError::Duration(duration));
    }
    Ok(JointTrajPt {
        sequence,
        joints: wire,
        velocity: 1.0,
        duration: d,
    })
}

impl Drop for Client {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        let _ = self.motion.shutdown(std::net::Shutdown::Both);
        // The reader ends at its next message or timeout; do not wait for it.
        drop(self.reader.take());
    }
}
