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
    /// The address cannot be resolved.
    #[error("bad address `{0}`: {1}")]
    Address(String, String),
    /// No connection.
    #[error("cannot connect to {addr}: {source}")]
    Connect {
        /// The address.
        addr: SocketAddr,
        /// The cause.
        source: std::io::Error,
    },
    /// The connection broke, went silent, or the controller sent garbage.
    #[error("controller disconnected: {0}")]
    Disconnected(String),
    /// The controller refused a request, with its reason.
    #[error("controller refused {what}: {reason}")]
    Refused {
        /// What was refused (e.g. `trajectory point 3`).
        what: String,
        /// The controller's reason, when it reported one.
        code: Option<RefusalCode>,
        /// The reason, for people.
        reason: String,
    },
    /// The controller did not finish in time.
    #[error("timeout: {0}")]
    Timeout(String),
    /// The controller reports an error state.
    #[error("controller in error (code {0})")]
    InError(i32),
    /// A value that the wire format cannot carry (not finite as a 32-bit float, more
    /// joints than simple_message carries); nothing was sent.
    #[error("{what} cannot be sent: {reason}")]
    NotOnWire {
        /// What (e.g. `trajectory point 3`).
        what: String,
        /// Why, for people.
        reason: String,
    },
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
    broken: Option<String>,
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
        .map_err(|e| ManipulatorError::Address(addr.into(), e.to_string()))?
        .next()
        .ok_or_else(|| ManipulatorError::Address(addr.into(), "no address".into()))?;
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
                what: "the robot".into(),
                reason: format!(
                    "{} joints, simple_message carries at most {MAX_JOINTS}",
                    kinds.len()
                ),
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
            let mut last = Instant::now();
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
                    Err(e) if timed_out(&e) && last.elapsed() <= state_timeout => continue,
                    Ok(None) => last = Instant::now(),
                    Ok(Some(p)) => {
                        last = Instant::now();
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
                        let why = match e {
                            CodecError::Io(io)
                                if matches!(
                                    io.kind(),
                                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                                ) =>
                            {
                                "no state message within the state timeout".to_string()
                            }
                            CodecError::Io(io)
                                if io.kind() == std::io::ErrorKind::UnexpectedEof =>
                            {
                                "state connection closed".to_string()
                            }
                            e => format!("state port: {e}"),
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
        let deadline = Instant::now() + options.state_timeout;
        loop {
            {
                let s = lock(&client.shared);
                if s.joints.is_some() && s.status.is_some() {
                    break;
                }
                if let Some(b) = &s.broken {
                    return Err(ManipulatorError::Disconnected(b.clone()));
                }
            }
            if Instant::now() > deadline {
                return Err(ManipulatorError::Disconnected(
                    "no joint state from the state port".into(),
                ));
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
            return Err(ManipulatorError::Disconnected(b.clone()));
        }
        if s.last_rx
            .is_none_or(|t| t.elapsed() > self.options.state_timeout)
        {
            return Err(ManipulatorError::Disconnected(
                "no state message within the state timeout".into(),
            ));
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
                what: "ping".into(),
                code: None,
                reason: "FAILURE reply".into(),
            });
        }
        Ok(())
    }

    /// The reason of a refusal: the next STATUS after `since` with `in_error`.
    fn refusal_reason(&self, since: Instant) -> (Option<RefusalCode>, String) {
        let deadline = Instant::now() + self.options.reply_timeout.min(Duration::from_secs(2));
        while Instant::now() < deadline {
            {
                let s = lock(&self.shared);
                if let (Some(st), Some(at)) = (s.status, s.status_at) {
                    if at >= since && st.in_error == TriState::On {
                        let code = RefusalCode::from_code(st.error_code);
                        let text = code.map_or_else(
                            || format!("controller error code {}", st.error_code),
                            |c| c.to_string(),
                        );
                        return (code, text);
                    }
                }
                if s.broken.is_some() {
                    break;
                }
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        (None, "FAILURE reply without a reason in STATUS".into())
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
        let what = || format!("trajectory point {sequence}");
        let pt = wire_point(&self.kinds, sequence, joints, duration).map_err(|reason| {
            ManipulatorError::NotOnWire {
                what: what(),
                reason,
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
        let (code, reason) = self.refusal_reason(sent);
        Err(ManipulatorError::Refused {
            what: what(),
            code,
            reason,
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
        if !value.is_finite() {
            return Err(ManipulatorError::NotOnWire {
                what: format!("tool command {action:?}"),
                reason: format!("value {value} is not a finite 32-bit float"),
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
                what: format!("tool command {action:?}"),
                code: Some(RefusalCode::BadTool),
                reason: "the controller cannot do it".into(),
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
        let deadline = since + timeout;
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
            if Instant::now() > deadline {
                return Err(ManipulatorError::Timeout(format!(
                    "the controller did not reach the target within {} s",
                    timeout.as_secs_f64()
                )));
            }
            std::thread::sleep(Duration::from_millis(10));
        }
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
    let lost = |e: CodecError| ManipulatorError::Disconnected(format!("motion port: {e}"));
    p.write_to(motion, order).map_err(lost)?;
    let deadline = Instant::now() + timeout;
    loop {
        let f = match frames.read_frame(motion) {
            Ok(f) => f,
            Err(e) if timed_out(&e) => {
                if Instant::now() > deadline {
                    return Err(ManipulatorError::Disconnected(format!(
                        "motion port: no reply within {} s",
                        timeout.as_secs_f64()
                    )));
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
/// The reason, naming the joint (1-based) and its value.
pub fn wire_point(
    kinds: &[JointKind],
    sequence: i32,
    joints: &[f64],
    duration: f64,
) -> Result<JointTrajPt, String> {
    if joints.len() != kinds.len() || kinds.len() > MAX_JOINTS {
        return Err(format!(
            "{} joint values for a robot of {} joints (at most {MAX_JOINTS} on the wire)",
            joints.len(),
            kinds.len()
        ));
    }
    let wire = joints_to_wire(kinds, joints);
    if let Some(j) = wire.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "joint {} = {} does not fit the wire's 32-bit float (largest magnitude {:e})",
            j + 1,
            joints[j],
            f32::MAX
        ));
    }
    let d = duration as f32;
    if !(d.is_finite() && d >= 0.0) {
        return Err(format!(
            "duration {duration} s is not a finite 32-bit float ≥ 0"
        ));
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
