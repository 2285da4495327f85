//! The ROS-Industrial **simple_message** codec (REP-I0006), plus fitup's tool extension.
//!
//! A packet on the wire is
//!
//! ```text
//! prefix  length      shared_int   bytes of header + body (the prefix itself excluded)
//! header  msg_type    shared_int   1 PING, 10 JOINT_POSITION, 11 JOINT_TRAJ_PT, 13 STATUS,
//!                                  65001 FITUP_TOOL (extension, freely assignable range)
//!         comm_type   shared_int   1 TOPIC, 2 SERVICE_REQUEST, 3 SERVICE_REPLY
//!         reply_code  shared_int   0 INVALID (unused), 1 SUCCESS, 2 FAILURE
//! body    message specific (see [`Body`])
//! ```
//!
//! `shared_int` is a 32-bit two's-complement integer and `shared_real` a 32-bit IEEE
//! float (the 4/4 variant of REP-I0006). The byte order is a property of the
//! connection ([`ByteOrder`]): REP-I0006 lets a driver use either ("swap" or
//! "non-swap" client nodes). A client chooses one (fitup's default is big-endian,
//! network order, the order in which REP-I0006 prints its byte-stream examples); a
//! server can detect it from the first length prefix ([`ByteOrder::detect`],
//! [`FrameReader::detecting`]).
//!
//! Framing ([`FrameReader::read_frame`]) is separate from decoding
//! ([`Frame::decode`]): a whole frame whose content is bad leaves the stream in step,
//! so a receiver can answer it (FAILURE to a request) or ignore it (a topic) and go
//! on, as REP-I0006 asks.
//!
//! Units on the wire follow REP-103: radians for revolute joints, **metres** for
//! prismatic joints, seconds for durations. fitup works in millimetres: the
//! conversion happens in the client and simulator, not here.
//!
//! Decoding never panics and never allocates more than [`MAX_LENGTH`] bytes: a bad
//! length, an unknown type, a body of the wrong size or a non-finite number is a
//! typed [`CodecError`].

use std::io::{Read, Write};
use thiserror::Error;

/// Bytes of the length prefix.
pub const PREFIX_SIZE: usize = 4;
/// Bytes of the header (msg_type, comm_type, reply_code).
pub const HEADER_SIZE: usize = 12;
/// Largest accepted `length` (header + body, bytes). The largest standard message
/// (JOINT_TRAJ_PT_FULL) is 148 bytes; anything far beyond is garbage or an attack.
pub const MAX_LENGTH: usize = 1024;
/// Joint values carried by JOINT_POSITION and JOINT_TRAJ_PT (unused ones are 0).
pub const MAX_JOINTS: usize = 10;

/// Message type identifiers (REP-I0004).
pub mod msg_type {
    /// PING (synchronous service, 10 dummy ints each way).
    pub const PING: i32 = 1;
    /// JOINT_POSITION (published joint state).
    pub const JOINT_POSITION: i32 = 10;
    /// JOINT_TRAJ_PT (enqueue one trajectory point).
    pub const JOINT_TRAJ_PT: i32 = 11;
    /// STATUS (published controller status).
    pub const STATUS: i32 = 13;
    /// fitup's tool extension (grasp, release, touch, tool output), in the freely
    /// assignable range 65001–65535 of REP-I0004.
    pub const FITUP_TOOL: i32 = 65001;
}

/// Special sequence numbers of JOINT_TRAJ_PT (REP-I0006).
pub mod special_seq {
    /// Downloading drivers only: start of a trajectory.
    pub const START_TRAJECTORY_DOWNLOAD: i32 = -1;
    /// Start of a streamed trajectory.
    pub const START_TRAJECTORY_STREAMING: i32 = -2;
    /// Downloading drivers only: end of a trajectory.
    pub const END_TRAJECTORY: i32 = -3;
    /// Abort any motion now.
    pub const STOP_TRAJECTORY: i32 = -4;
}

/// Version of fitup's tool extension carried in every FITUP_TOOL body.
pub const TOOL_EXTENSION_VERSION: i32 = 1;

/// Byte order of every `shared_int` / `shared_real` on a connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum ByteOrder {
    /// Network order (most significant byte first): fitup's default, and what the
    /// big-endian controllers speak (the Fanuc and Motoman drivers run
    /// industrial_core's *swap* nodes on x86 for them).
    #[default]
    Big,
    /// Least significant byte first: industrial_core's default ("non-swap") build
    /// on an x86 host.
    Little,
}

impl ByteOrder {
    /// The byte order in which the 4-byte length prefix `prefix` reads as a sane
    /// length (`HEADER_SIZE..=MAX_LENGTH`), or `None` when it is sane in neither.
    ///
    /// A sane length is sane in one order only: its two high bytes are 0 and its low
    /// byte pair is not (a length ≥ 12), so the byte-reversed value, read unsigned, is
    /// at least 2^16 (negative when read signed): far outside the sane range. This is how a server detects a client's order from its
    /// first frame.
    pub fn detect(prefix: [u8; PREFIX_SIZE]) -> Option<Self> {
        let sane = |v: i32| (HEADER_SIZE as i32..=MAX_LENGTH as i32).contains(&v);
        if sane(i32::from_be_bytes(prefix)) {
            Some(Self::Big)
        } else if sane(i32::from_le_bytes(prefix)) {
            Some(Self::Little)
        } else {
            None
        }
    }

    /// `big` or `little` (as the command line and scripts spell it).
    pub fn name(self) -> &'static str {
        match self {
            Self::Big => "big",
            Self::Little => "little",
        }
    }

    /// Parses [`name`](Self::name).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "big" => Some(Self::Big),
            "little" => Some(Self::Little),
            _ => None,
        }
    }
}

impl std::fmt::Display for ByteOrder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Big => "big-endian",
            Self::Little => "little-endian",
        })
    }
}

/// The header's communication type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum CommType {
    /// Needs no acknowledgement (published state).
    Topic = 1,
    /// The sender waits for a reply.
    ServiceRequest = 2,
    /// The reply to a request.
    ServiceReply = 3,
}

/// The header's reply code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ReplyCode {
    /// Unused (topics and requests).
    Invalid = 0,
    /// The receiver accepted the request.
    Success = 1,
    /// The receiver refused the request (the reason is in the next STATUS).
    Failure = 2,
}

/// A STATUS tri-state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum TriState {
    /// Cannot be determined.
    Unknown = -1,
    /// False / off / disabled.
    Off = 0,
    /// True / on / enabled.
    On = 1,
}

impl TriState {
    /// `On` for true, `Off` for false.
    pub fn from_bool(b: bool) -> Self {
        if b {
            Self::On
        } else {
            Self::Off
        }
    }
}

/// Controller mode of STATUS (ISO 10218-1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum RobotMode {
    /// Cannot be determined.
    Unknown = -1,
    /// Manual mode.
    Manual = 1,
    /// Automatic mode.
    Auto = 2,
}

/// The body of JOINT_TRAJ_PT: one trajectory point (radians / metres, seconds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointTrajPt {
    /// Index into the trajectory (0 starts a new one), or a [`special_seq`] value.
    pub sequence: i32,
    /// Joint positions (rad, m); unused entries 0.
    pub joints: [f32; MAX_JOINTS],
    /// Fraction (0, 1] of the maximum joint speed.
    pub velocity: f32,
    /// Time to reach this point from the previous one (s).
    pub duration: f32,
}

/// The body of JOINT_POSITION: the joint state (rad, m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointPosition {
    /// Unused when reporting state (0).
    pub sequence: i32,
    /// Joint positions (rad, m); unused entries 0.
    pub joints: [f32; MAX_JOINTS],
}

/// The body of STATUS.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Status {
    /// Servo power.
    pub drives_powered: TriState,
    /// Emergency stop engaged.
    pub e_stopped: TriState,
    /// Code of the error that put the controller in error (see
    /// [`crate::manipulator::RefusalCode`] for the simulator's codes).
    pub error_code: i32,
    /// In error.
    pub in_error: TriState,
    /// Moving.
    pub in_motion: TriState,
    /// Controller mode.
    pub mode: RobotMode,
    /// A new trajectory would run now.
    pub motion_possible: TriState,
}

/// A tool action of fitup's extension (FITUP_TOOL, version 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ToolAction {
    /// Close the gripper to `value` (opening, m).
    Grasp = 1,
    /// Open the gripper to `value` (opening, m).
    Release = 2,
    /// Guarded move: the tool moves straight, at most `value` (m), along the tool
    /// axis `index` names (0 +z, the default, 1 −z, 2 +x, 3 −x, 4 +y, 5 −y) and stops
    /// at the first contact; the reply's value is the distance travelled (m).
    Touch = 3,
    /// Set digital output `index` to `value` (0 or 1).
    SetOutput = 4,
}

/// The body of FITUP_TOOL (request and reply have the same layout):
/// `version, action, index: shared_int; value: shared_real` (16 bytes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolCommand {
    /// The extension's version ([`TOOL_EXTENSION_VERSION`]).
    pub version: i32,
    /// What to do.
    pub action: ToolAction,
    /// Output index ([`ToolAction::SetOutput`]), the tool axis of a
    /// [`ToolAction::Touch`], else 0.
    pub index: i32,
    /// The action's value (see [`ToolAction`]); in a reply, the measured value.
    pub value: f32,
}

/// The body of a packet.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Body {
    /// Nothing after the header (an acknowledgement, the *alternative* replies).
    Empty,
    /// PING's 10 zero ints (request and reply).
    Ping,
    /// JOINT_TRAJ_PT request.
    JointTrajPt(JointTrajPt),
    /// 10 zero reals: the full reply of JOINT_TRAJ_PT.
    DummyReals,
    /// JOINT_POSITION.
    JointPosition(JointPosition),
    /// STATUS.
    Status(Status),
    /// FITUP_TOOL.
    Tool(ToolCommand),
}

/// One simple_message packet.
#[derive(Debug, Clone, PartialEq)]
pub struct Packet {
    /// Message type ([`msg_type`]).
    pub msg_type: i32,
    /// Communication type.
    pub comm_type: CommType,
    /// Reply code ([`ReplyCode::Invalid`] unless a reply).
    pub reply_code: ReplyCode,
    /// The body, matching `msg_type` and `comm_type`.
    pub body: Body,
}

/// A packet that cannot be decoded (or a connection that broke while reading one).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CodecError {
    /// The length prefix is negative, smaller than the header or above [`MAX_LENGTH`].
    #[error("bad length prefix {0} (must be {HEADER_SIZE}..={MAX_LENGTH} bytes)")]
    BadLength(i64),
    /// The stream ended inside a packet.
    #[error("truncated packet: {got} of {expected} bytes")]
    Truncated {
        /// Bytes expected.
        expected: usize,
        /// Bytes received.
        got: usize,
    },
    /// The message type is not one fitup speaks.
    #[error("unknown message type {0}")]
    UnknownType(i32),
    /// The communication type is not 1, 2 or 3.
    #[error("bad comm_type {0}")]
    BadCommType(i32),
    /// The reply code is not 0, 1 or 2, or does not fit the comm_type.
    #[error("bad reply_code {0} for this comm_type")]
    BadReplyCode(i32),
    /// The body has the wrong size for its type.
    #[error("message type {msg_type}: body of {got} bytes, expected {expected}")]
    BadBodySize {
        /// Message type.
        msg_type: i32,
        /// Expected body size(s), for people (`40, 52 or 0`).
        expected: &'static str,
        /// Body bytes received.
        got: usize,
    },
    /// A field holds a value outside its domain (a non-finite real, a bad tri-state…).
    #[error("message type {msg_type}: bad field `{field}`: {value}")]
    BadField {
        /// Message type.
        msg_type: i32,
        /// Field name.
        field: &'static str,
        /// The value.
        value: FieldValue,
    },
    /// The connection failed or timed out.
    #[error("connection: {0}")]
    Io(#[from] std::io::Error),
}

/// A field's value outside its domain ([`CodecError::BadField`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum FieldValue {
    /// A code no value of the field has (a tri-state, a tool action).
    Code(i32),
    /// A real that is not finite.
    Real(f32),
    /// A tool extension version this build does not speak
    /// ([`TOOL_EXTENSION_VERSION`]).
    Version(i32),
}

impl std::fmt::Display for FieldValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FieldValue::Code(v) => write!(f, "{v}"),
            FieldValue::Real(v) => write!(f, "{v}"),
            FieldValue::Version(v) => {
                write!(f, "{v} (this build speaks {TOOL_EXTENSION_VERSION})")
            }
        }
    }
}

impl ByteOrder {
    fn put_i32(self, out: &mut Vec<u8>, v: i32) {
        out.extend_from_slice(&match self {
            Self::Big => v.to_be_bytes(),
            Self::Little => v.to_le_bytes(),
        });
    }
    fn put_f32(self, out: &mut Vec<u8>, v: f32) {
        out.extend_from_slice(&match self {
            Self::Big => v.to_be_bytes(),
            Self::Little => v.to_le_bytes(),
        });
    }
    fn i32_at(self, b: &[u8], at: usize) -> i32 {
        let w = [b[at], b[at + 1], b[at + 2], b[at + 3]];
        match self {
            Self::Big => i32::from_be_bytes(w),
            Self::Little => i32::from_le_bytes(w),
        }
    }
    fn f32_at(self, b: &[u8], at: usize) -> f32 {
        let w = [b[at], b[at + 1], b[at + 2], b[at + 3]];
        match self {
            Self::Big => f32::from_be_bytes(w),
            Self::Little => f32::from_le_bytes(w),
        }
    }
}

impl Packet {
    /// A TOPIC packet.
    pub fn topic(msg_type: i32, body: Body) -> Self {
        Self {
            msg_type,
            comm_type: CommType::Topic,
            reply_code: ReplyCode::Invalid,
            body,
        }
    }

    /// A SERVICE_REQUEST packet.
    pub fn request(msg_type: i32, body: Body) -> Self {
        Self {
            msg_type,
            comm_type: CommType::ServiceRequest,
            reply_code: ReplyCode::Invalid,
            body,
        }
    }

    /// A SERVICE_REPLY packet.
    pub fn reply(msg_type: i32, reply_code: ReplyCode, body: Body) -> Self {
        Self {
            msg_type,
            comm_type: CommType::ServiceReply,
            reply_code,
            body,
        }
    }

    /// The packet as bytes, prefix included.
    ///
    /// # Examples
    /// ```
    /// use fitup::manipulator::message::{msg_type, Body, ByteOrder, Packet};
    ///
    /// let ping = Packet::request(msg_type::PING, Body::Ping);
    /// let bytes = ping.encode(ByteOrder::Big);
    /// // length 52 (header 12 + ten zero ints), type 1, SERVICE_REQUEST, INVALID.
    /// assert_eq!(&bytes[..16], &[0, 0, 0, 52, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 0]);
    /// assert_eq!(Packet::decode(&bytes, ByteOrder::Big).unwrap(), ping);
    /// ```
    pub fn encode(&self, order: ByteOrder) -> Vec<u8> {
        let mut body = Vec::with_capacity(64);
        match &self.body {
            Body::Empty => {}
            Body::Ping => (0..10).for_each(|_| order.put_i32(&mut body, 0)),
            Body::DummyReals => (0..10).for_each(|_| order.put_f32(&mut body, 0.0)),
            Body::JointTrajPt(p) => {
                order.put_i32(&mut body, p.sequence);
                p.joints.iter().for_each(|&j| order.put_f32(&mut body, j));
                order.put_f32(&mut body, p.velocity);
                order.put_f32(&mut body, p.duration);
            }
            Body::JointPosition(p) => {
                order.put_i32(&mut body, p.sequence);
                p.joints.iter().for_each(|&j| order.put_f32(&mut body, j));
            }
            Body::Status(s) => {
                for v in [
                    s.drives_powered as i32,
                    s.e_stopped as i32,
                    s.error_code,
                    s.in_error as i32,
                    s.in_motion as i32,
                    s.mode as i32,
                    s.motion_possible as i32,
                ] {
                    order.put_i32(&mut body, v);
                }
            }
            Body::Tool(t) => {
                order.put_i32(&mut body, t.version);
                order.put_i32(&mut body, t.action as i32);
                order.put_i32(&mut body, t.index);
                order.put_f32(&mut body, t.value);
            }
        }
        let mut out = Vec::with_capacity(PREFIX_SIZE + HEADER_SIZE + body.len());
        order.put_i32(&mut out, (HEADER_SIZE + body.len()) as i32);
        order.put_i32(&mut out, self.msg_type);
        order.put_i32(&mut out, self.comm_type as i32);
        order.put_i32(&mut out, self.reply_code as i32);
        out.extend_from_slice(&body);
        out
    }

    /// Decodes one whole packet (prefix included) from `bytes`; extra bytes after it
    /// are an error.
    ///
    /// # Errors
    /// Any [`CodecError`] but `Io`.
    pub fn decode(bytes: &[u8], order: ByteOrder) -> Result<Self, CodecError> {
        if bytes.len() < PREFIX_SIZE {
            return Err(CodecError::Truncated {
                expected: PREFIX_SIZE,
                got: bytes.len(),
            });
        }
        let length = check_length(order.i32_at(bytes, 0))?;
        let rest = &bytes[PREFIX_SIZE..];
        if rest.len() < length {
            return Err(CodecError::Truncated {
                expected: PREFIX_SIZE + length,
                got: bytes.len(),
            });
        }
        if rest.len() > length {
            return Err(CodecError::BadLength(length as i64));
        }
        Self::decode_message(rest, order)
    }

    /// Decodes header + body (the bytes the length prefix counts).
    fn decode_message(m: &[u8], order: ByteOrder) -> Result<Self, CodecError> {
        let msg_type = order.i32_at(m, 0);
        let comm = order.i32_at(m, 4);
        let reply = order.i32_at(m, 8);
        let comm_type = match comm {
            1 => CommType::Topic,
            2 => CommType::ServiceRequest,
            3 => CommType::ServiceReply,
            c => return Err(CodecError::BadCommType(c)),
        };
        let reply_code = match (reply, comm_type) {
            (0, CommType::Topic | CommType::ServiceRequest) => ReplyCode::Invalid,
            (1, CommType::ServiceReply) => ReplyCode::Success,
            (2, CommType::ServiceReply) => ReplyCode::Failure,
            (r, _) => return Err(CodecError::BadReplyCode(r)),
        };
        let b = &m[HEADER_SIZE..];
        let size = |expected: &'static str| CodecError::BadBodySize {
            msg_type,
            expected,
            got: b.len(),
        };
        let real = |at: usize, field: &'static str| -> Result<f32, CodecError> {
            let v = order.f32_at(b, at);
            if v.is_finite() {
                Ok(v)
            } else {
                Err(CodecError::BadField {
                    msg_type,
                    field,
                    value: FieldValue::Real(v),
                })
            }
        };
        let joints = |from: usize| -> Result<[f32; MAX_JOINTS], CodecError> {
            let mut j = [0f32; MAX_JOINTS];
            for (i, v) in j.iter_mut().enumerate() {
                *v = real(from + 4 * i, "joint_data")?;
            }
            Ok(j)
        };
        // A reply may be header only (REP-I0006's *alternative* reply), whatever its
        // type; after FAILURE "any payload must be considered invalid" (it may be
        // uninitialised), so it is not decoded at all.
        if comm_type == CommType::ServiceReply && (b.is_empty() || reply_code == ReplyCode::Failure)
        {
            if !matches!(
                msg_type,
                msg_type::PING
                    | msg_type::JOINT_POSITION
                    | msg_type::JOINT_TRAJ_PT
                    | msg_type::STATUS
                    | msg_type::FITUP_TOOL
            ) {
                return Err(CodecError::UnknownType(msg_type));
            }
            return Ok(Self {
                msg_type,
                comm_type,
                reply_code,
                body: Body::Empty,
            });
        }
        let body = match msg_type {
            msg_type::PING => match b.len() {
                40 => Body::Ping,
                0 => Body::Empty,
                _ => return Err(size("40 (or 0)")),
            },
            msg_type::JOINT_TRAJ_PT => match comm_type {
                CommType::ServiceReply if b.len() != 52 => match b.len() {
                    40 => Body::DummyReals,
                    0 => Body::Empty,
                    _ => return Err(size("40, 52 or 0")),
                },
                // A request, or a reply that echoes the point (industrial_core's
                // typed messages reply with their own body).
                _ => {
                    if b.len() != 52 {
                        return Err(size("52"));
                    }
                    Body::JointTrajPt(JointTrajPt {
                        sequence: order.i32_at(b, 0),
                        joints: joints(4)?,
                        velocity: real(44, "velocity")?,
                        duration: real(48, "duration")?,
                    })
                }
            },
            msg_type::JOINT_POSITION => {
                if b.len() != 44 {
                    return Err(size("44"));
                }
                Body::JointPosition(JointPosition {
                    sequence: order.i32_at(b, 0),
                    joints: joints(4)?,
                })
            }
            msg_type::STATUS => {
                if b.len() != 28 {
                    return Err(size("28"));
                }
                let tri = |at: usize, field: &'static str| match order.i32_at(b, at) {
                    -1 => Ok(TriState::Unknown),
                    0 => Ok(TriState::Off),
                    1 => Ok(TriState::On),
                    v => Err(CodecError::BadField {
                        msg_type,
                        field,
                        value: FieldValue::Code(v),
                    }),
                };
                let mode = match order.i32_at(b, 20) {
                    1 => RobotMode::Manual,
                    2 => RobotMode::Auto,
                    // Other values are reserved; REP-I0006 says report them as unknown.
                    _ => RobotMode::Unknown,
                };
                Body::Status(Status {
                    drives_powered: tri(0, "drives_powered")?,
                    e_stopped: tri(4, "e_stopped")?,
                    error_code: order.i32_at(b, 8),
                    in_error: tri(12, "in_error")?,
                    in_motion: tri(16, "in_motion")?,
                    mode,
                    motion_possible: tri(24, "motion_possible")?,
                })
            }
            msg_type::FITUP_TOOL => {
                if b.len() != 16 {
                    return Err(size("16"));
                }
                let version = order.i32_at(b, 0);
                if version != TOOL_EXTENSION_VERSION {
                    return Err(CodecError::BadField {
                        msg_type,
                        field: "version",
                        value: FieldValue::Version(version),
                    });
                }
                let action = match order.i32_at(b, 4) {
                    1 => ToolAction::Grasp,
                    2 => ToolAction::Release,
                    3 => ToolAction::Touch,
                    4 => ToolAction::SetOutput,
                    v => {
                        return Err(CodecError::BadField {
                            msg_type,
                            field: "action",
                            value: FieldValue::Code(v),
                        })
                    }
                };
                Body::Tool(ToolCommand {
                    version,
                    action,
                    index: order.i32_at(b, 8),
                    value: real(12, "value")?,
                })
            }
            t => return Err(CodecError::UnknownType(t)),
        };
        Ok(Self {
            msg_type,
            comm_type,
            reply_code,
            body,
        })
    }

    /// Reads exactly one packet from a blocking stream (a fresh [`FrameReader`]: bytes
    /// of a packet cut short by a timeout are lost; keep a [`FrameReader`] for streams
    /// with read timeouts). The read is bounded: the length is checked before anything
    /// is read past the prefix. A stream that ends between packets gives
    /// `Io(UnexpectedEof)`; one that ends inside a packet gives `Truncated`.
    ///
    /// # Errors
    /// Any [`CodecError`].
    pub fn read_from(stream: &mut impl Read, order: ByteOrder) -> Result<Self, CodecError> {
        FrameReader::new(order).read_packet(stream)
    }

    /// Writes the packet to a stream.
    ///
    /// # Errors
    /// The stream's error.
    pub fn write_to(&self, stream: &mut impl Write, order: ByteOrder) -> Result<(), CodecError> {
        stream.write_all(&self.encode(order))?;
        stream.flush()?;
        Ok(())
    }
}

fn check_length(length: i32) -> Result<usize, CodecError> {
    if length < HEADER_SIZE as i32 || length as usize > MAX_LENGTH {
        return Err(CodecError::BadLength(length as i64));
    }
    Ok(length as usize)
}

/// The three header fields of a frame as received, before any validation: what a
/// receiver needs to answer (or ignore) a message it cannot decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawHeader {
    /// `msg_type`, any value.
    pub msg_type: i32,
    /// `comm_type`, any value (valid ones are [`CommType`]'s).
    pub comm_type: i32,
    /// `reply_code`, any value.
    pub reply_code: i32,
}

impl RawHeader {
    /// A SERVICE_REQUEST: the sender waits for a reply, even one saying FAILURE.
    pub fn is_request(&self) -> bool {
        self.comm_type == CommType::ServiceRequest as i32
    }
}

/// One whole frame as received: its length prefix was sane, so the stream is still
/// in step after it, whether or not its content decodes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame {
    order: ByteOrder,
    /// Header and body (the bytes the length prefix counts, at least [`HEADER_SIZE`]).
    message: Vec<u8>,
}

impl Frame {
    /// The header, undecoded.
    pub fn header(&self) -> RawHeader {
        RawHeader {
            msg_type: self.order.i32_at(&self.message, 0),
            comm_type: self.order.i32_at(&self.message, 4),
            reply_code: self.order.i32_at(&self.message, 8),
        }
    }

    /// The byte order the frame was read in.
    pub fn order(&self) -> ByteOrder {
        self.order
    }

    /// Bytes of header and body (the length prefix's value).
    pub fn len(&self) -> usize {
        self.message.len()
    }

    /// Never true: a frame holds at least a header.
    pub fn is_empty(&self) -> bool {
        self.message.is_empty()
    }

    /// The packet.
    ///
    /// # Errors
    /// Any [`CodecError`] of the content (unknown type, bad comm type or reply code,
    /// body size, a non-finite real…); the connection stays usable.
    pub fn decode(&self) -> Result<Packet, CodecError> {
        Packet::decode_message(&self.message, self.order)
    }
}

/// The framing of one connection: reads frames from a stream whose reads may time
/// out (`WouldBlock` / `TimedOut`) and keeps the bytes of a frame received so far
/// across those timeouts, so a packet that arrives in parts, with pauses, is decoded
/// whole. It never holds more than one frame ([`PREFIX_SIZE`] + [`MAX_LENGTH`]
/// bytes): it reads only the bytes the current frame still needs.
///
/// The byte order is fixed ([`new`](Self::new)) or detected from the first length
/// prefix ([`detecting`](Self::detecting), see [`ByteOrder::detect`]) and then kept
/// for the connection.
///
/// After a framing error (a bad length prefix, a stream that ends inside a frame, an
/// I/O error other than a timeout) the stream cannot be re-synchronised
/// (simple_message has only byte counting): the connection should be closed. A frame
/// whose content does not decode ([`Frame::decode`]) leaves the stream in step.
#[derive(Debug)]
pub struct FrameReader {
    order: Option<ByteOrder>,
    buf: Vec<u8>,
}

impl FrameReader {
    /// An empty framing buffer for a connection of byte order `order`.
    pub fn new(order: ByteOrder) -> Self {
        Self {
            order: Some(order),
            buf: Vec::with_capacity(PREFIX_SIZE + HEADER_SIZE + 52),
        }
    }

    /// An empty framing buffer that takes the byte order from the first length
    /// prefix it reads.
    pub fn detecting() -> Self {
        Self {
            order: None,
            buf: Vec::with_capacity(PREFIX_SIZE + HEADER_SIZE + 52),
        }
    }

    /// The connection's byte order: fixed, or detected (`None` before the first
    /// prefix of a detecting reader).
    pub fn order(&self) -> Option<ByteOrder> {
        self.order
    }

    /// Bytes of an incomplete packet held (0 between packets).
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// Reads the next packet: [`read_frame`](Self::read_frame), then
    /// [`Frame::decode`].
    ///
    /// # Errors
    /// As [`read_frame`](Self::read_frame), or a frame that does not decode (its
    /// bytes are consumed).
    pub fn read_packet(&mut self, stream: &mut impl Read) -> Result<Packet, CodecError> {
        self.read_frame(stream)?.decode()
    }

    /// Reads the next whole frame. A read timeout returns `Io(WouldBlock | TimedOut)`
    /// and keeps the bytes read so far: call again to continue the same frame.
    ///
    /// # Errors
    /// A timeout (retryable, see above), `Io(UnexpectedEof)` when the stream ends
    /// between frames, `Truncated` when it ends inside one, a bad length prefix
    /// (in the fixed order, or in both orders when detecting; before anything past
    /// the prefix is read).
    pub fn read_frame(&mut self, stream: &mut impl Read) -> Result<Frame, CodecError> {
        loop {
            let want = if self.buf.len() < PREFIX_SIZE {
                PREFIX_SIZE
            } else {
                let order = match self.order {
                    Some(o) => o,
                    None => {
                        let prefix = [self.buf[0], self.buf[1], self.buf[2], self.buf[3]];
                        let Some(o) = ByteOrder::detect(prefix) else {
                            return Err(CodecError::BadLength(i32::from_be_bytes(prefix) as i64));
                        };
                        self.order = Some(o);
                        o
                    }
                };
                let length = check_length(order.i32_at(&self.buf, 0))?;
                PREFIX_SIZE + length
            };
            if self.buf.len() == want && want > PREFIX_SIZE {
                let frame = Frame {
                    order: self.order.expect("set with the prefix"),
                    message: self.buf[PREFIX_SIZE..].to_vec(),
                };
                self.buf.clear();
                return Ok(frame);
            }
            let mut chunk = [0u8; PREFIX_SIZE + MAX_LENGTH];
            let need = want - self.buf.len();
            match stream.read(&mut chunk[..need]) {
                Ok(0) => {
                    let got = std::mem::take(&mut self.buf).len();
                    if got == 0 {
                        return Err(CodecError::Io(std::io::ErrorKind::UnexpectedEof.into()));
                    }
                    return Err(CodecError::Truncated {
                        expected: want,
                        got,
                    });
                }
                Ok(n) => self.buf.extend_from_slice(&chunk[..n.min(need)]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(CodecError::Io(e)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(s: &str) -> Vec<u8> {
        let s: String = s.split_whitespace().collect();
        (0..s.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
            .collect()
    }

    // The three byte streams of REP-I0006 appendix A (printed big-endian).
    const JOINT_POSITION_EXAMPLE: &str = "00000038 0000000A 00000001 00000000 00000000 B81AD9FA
        B6836312 B7C043F5 B8B81516 B865D055 B8B6365E 00000000 00000000 00000000 00000000";
    const JOINT_TRAJ_PT_EXAMPLE: &str = "00000040 0000000B 00000002 00000000 00000001 A7600000
        3EA7CDE8 BF5D9E57 C0490FDB 3F34815F C0490FDB 00000000 00000000 00000000 00000000
        3DCCCCCD 40A00000";
    const STATUS_EXAMPLE: &str = "00000028 0000000D 00000001 00000000 00000001 FFFFFFFF
        00000000 00000000 00000000 00000002 00000001";

    #[test]
    fn rep_i0006_joint_position_example() {
        let bytes = hex(JOINT_POSITION_EXAMPLE);
        let p = Packet::decode(&bytes, ByteOrder::Big).unwrap();
        assert_eq!(p.msg_type, msg_type::JOINT_POSITION);
        assert_eq!(p.comm_type, CommType::Topic);
        let Body::JointPosition(jp) = &p.body else {
            panic!("{p:?}")
        };
        assert_eq!(jp.sequence, 0);
        assert!((jp.joints[0] - -0.000036919).abs() < 1e-9);
        assert!((jp.joints[5] - -0.000086886).abs() < 1e-9);
        assert_eq!(jp.joints[6..], [0.0; 4]);
        assert_eq!(p.encode(ByteOrder::Big), bytes);
    }

    #[test]
    fn rep_i0006_joint_traj_pt_example() {
        let bytes = hex(JOINT_TRAJ_PT_EXAMPLE);
        let p = Packet::decode(&bytes, ByteOrder::Big).unwrap();
        assert_eq!(p.comm_type, CommType::ServiceRequest);
        assert_eq!(p.reply_code, ReplyCode::Invalid);
        let Body::JointTrajPt(pt) = &p.body else {
            panic!("{p:?}")
        };
        assert_eq!(pt.sequence, 1);
        assert!((pt.joints[1] - 0.327_742_8).abs() < 1e-6);
        assert!((pt.joints[3] - -std::f32::consts::PI).abs() < 1e-6);
        assert_eq!(pt.velocity, 0.1);
        assert_eq!(pt.duration, 5.0);
        assert_eq!(p.encode(ByteOrder::Big), bytes);
    }

    #[test]
    fn rep_i0006_status_example() {
        let bytes = hex(STATUS_EXAMPLE);
        let p = Packet::decode(&bytes, ByteOrder::Big).unwrap();
        assert_eq!(
            p.body,
            Body::Status(Status {
                drives_powered: TriState::On,
                e_stopped: TriState::Unknown,
                error_code: 0,
                in_error: TriState::Off,
                in_motion: TriState::Off,
                mode: RobotMode::Auto,
                motion_possible: TriState::On,
            })
        );
        assert_eq!(p.encode(ByteOrder::Big), bytes);
    }

    #[test]
    fn little_endian_is_the_byte_reverse_of_each_field() {
        let big = hex(STATUS_EXAMPLE);
        let p = Packet::decode(&big, ByteOrder::Big).unwrap();
        let little = p.encode(ByteOrder::Little);
        assert_eq!(little.len(), big.len());
        for (b, l) in big.chunks(4).zip(little.chunks(4)) {
            let mut r = b.to_vec();
            r.reverse();
            assert_eq!(r, l);
        }
        assert_eq!(Packet::decode(&little, ByteOrder::Little).unwrap(), p);
    }

    #[test]
    fn ping_and_replies_layouts() {
        let ping = Packet::request(msg_type::PING, Body::Ping).encode(ByteOrder::Big);
        assert_eq!(ping.len(), 4 + 12 + 40);
        assert_eq!(&ping[..16], &hex("00000034 00000001 00000002 00000000")[..]);
        assert!(ping[16..].iter().all(|&b| b == 0));
        let reply = Packet::reply(msg_type::JOINT_TRAJ_PT, ReplyCode::Failure, Body::Empty);
        assert_eq!(
            reply.encode(ByteOrder::Big),
            hex("0000000C 0000000B 00000003 00000002")
        );
        let full = Packet::reply(
            msg_type::JOINT_TRAJ_PT,
            ReplyCode::Success,
            Body::DummyReals,
        );
        let bytes = full.encode(ByteOrder::Big);
        assert_eq!(bytes.len(), 56);
        assert_eq!(Packet::decode(&bytes, ByteOrder::Big).unwrap(), full);
    }

    #[test]
    fn tool_extension_layout() {
        let t = Packet::request(
            msg_type::FITUP_TOOL,
            Body::Tool(ToolCommand {
                version: 1,
                action: ToolAction::Grasp,
                index: 0,
                value: 0.5,
            }),
        );
        let bytes = t.encode(ByteOrder::Big);
        assert_eq!(
            bytes,
            hex("0000001C 0000FDE9 00000002 00000000 00000001 00000001 00000000 3F000000")
        );
        assert_eq!(Packet::decode(&bytes, ByteOrder::Big).unwrap(), t);
        let mut v2 = bytes.clone();
        v2[19] = 2;
        assert!(matches!(
            Packet::decode(&v2, ByteOrder::Big),
            Err(CodecError::BadField {
                field: "version",
                value: FieldValue::Version(2),
                ..
            })
        ));
        assert_eq!(
            Packet::decode(&v2, ByteOrder::Big).unwrap_err().to_string(),
            "message type 65001: bad field `version`: 2 (this build speaks 1)"
        );
    }

    #[test]
    fn malformed_packets_are_typed_errors() {
        let good = hex(JOINT_TRAJ_PT_EXAMPLE);
        // Every truncation.
        for n in 0..good.len() {
            let e = Packet::decode(&good[..n], ByteOrder::Big).unwrap_err();
            assert!(matches!(e, CodecError::Truncated { .. }), "{n}: {e}");
            let e = Packet::read_from(&mut &good[..n], ByteOrder::Big).unwrap_err();
            if n == 0 {
                assert!(matches!(e, CodecError::Io(_)), "{e}");
            } else {
                assert!(matches!(e, CodecError::Truncated { .. }), "{n}: {e}");
            }
        }
        // Lengths: negative, too small, huge (nothing allocated: read_from fails first).
        for len in [-1i32, 0, 11, 1025, i32::MAX] {
            let mut b = good.clone();
            b[..4].copy_from_slice(&len.to_be_bytes());
            assert!(matches!(
                Packet::read_from(&mut &b[..], ByteOrder::Big),
                Err(CodecError::BadLength(_))
            ));
        }
        // Wrong byte order reads a huge length.
        assert!(matches!(
            Packet::decode(&good, ByteOrder::Little),
            Err(CodecError::BadLength(_))
        ));
        // Unknown type, bad comm type, reply code on a request, body size, NaN.
        let mut b = good.clone();
        b[7] = 99;
        assert!(matches!(
            Packet::decode(&b, ByteOrder::Big),
            Err(CodecError::UnknownType(99))
        ));
        let mut b = good.clone();
        b[11] = 7;
        assert!(matches!(
            Packet::decode(&b, ByteOrder::Big),
            Err(CodecError::BadCommType(7))
        ));
        let mut b = good.clone();
        b[15] = 1;
        assert!(matches!(
            Packet::decode(&b, ByteOrder::Big),
            Err(CodecError::BadReplyCode(1))
        ));
        let mut b = good.clone();
        b.truncate(b.len() - 4);
        b[3] = 60;
        assert!(matches!(
            Packet::decode(&b, ByteOrder::Big),
            Err(CodecError::BadBodySize { .. })
        ));
        let mut b = good.clone();
        b[20..24].copy_from_slice(&f32::NAN.to_be_bytes());
        assert!(matches!(
            Packet::decode(&b, ByteOrder::Big),
            Err(CodecError::BadField {
                field: "joint_data",
                value: FieldValue::Real(v),
                ..
            }) if v.is_nan()
        ));
        assert_eq!(
            Packet::decode(&b, ByteOrder::Big).unwrap_err().to_string(),
            "message type 11: bad field `joint_data`: NaN"
        );
        let mut b = hex(STATUS_EXAMPLE);
        b[19] = 5;
        assert!(matches!(
            Packet::decode(&b, ByteOrder::Big),
            Err(CodecError::BadField {
                field: "drives_powered",
                value: FieldValue::Code(5),
                ..
            })
        ));
        assert_eq!(
            Packet::decode(&b, ByteOrder::Big).unwrap_err().to_string(),
            "message type 13: bad field `drives_powered`: 5"
        );
    }

    #[test]
    fn arbitrary_bytes_never_panic() {
        let mut rng = crate::math::Rng::new(7);
        for _ in 0..20_000 {
            let n = (rng.next_u64() % 80) as usize;
            let mut b: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
            if n >= 4 && rng.next_u64().is_multiple_of(2) {
                b[..4].copy_from_slice(&((n as i32) - 4).to_be_bytes());
            }
            let _ = Packet::decode(&b, ByteOrder::Big);
            let _ = Packet::read_from(&mut &b[..], ByteOrder::Big);
        }
    }

    /// A stream that hands out `data` in the given chunks, with a timeout
    /// (`WouldBlock` or `TimedOut`, alternately) between two chunks: a peer that
    /// pauses mid-packet behind a socket read timeout.
    struct Paused {
        chunks: std::collections::VecDeque<Vec<u8>>,
        pause_next: bool,
        pauses: usize,
    }

    impl Paused {
        fn new(data: &[u8], cuts: &[usize]) -> Self {
            let mut chunks = std::collections::VecDeque::new();
            let mut from = 0;
            for &c in cuts.iter().chain([&data.len()]) {
                let c = c.clamp(from, data.len());
                if c > from {
                    chunks.push_back(data[from..c].to_vec());
                }
                from = c;
            }
            Self {
                chunks,
                pause_next: false,
                pauses: 0,
            }
        }
    }

    impl Read for Paused {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.pause_next && !self.chunks.is_empty() {
                self.pause_next = false;
                self.pauses += 1;
                let kind = if self.pauses.is_multiple_of(2) {
                    std::io::ErrorKind::TimedOut
                } else {
                    std::io::ErrorKind::WouldBlock
                };
                return Err(kind.into());
            }
            let Some(front) = self.chunks.front_mut() else {
                return Ok(0);
            };
            let n = buf.len().min(front.len());
            buf[..n].copy_from_slice(&front[..n]);
            front.drain(..n);
            if front.is_empty() {
                self.chunks.pop_front();
                self.pause_next = true;
            }
            Ok(n)
        }
    }

    /// Every packet of `stream`, retrying after each timeout (as the simulator and
    /// the client do), until the stream ends.
    fn read_all(r: &mut impl Read, order: ByteOrder) -> (Vec<Packet>, Option<CodecError>) {
        let mut frames = FrameReader::new(order);
        let mut out = Vec::new();
        loop {
            match frames.read_packet(r) {
                Ok(p) => out.push(p),
                Err(CodecError::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(CodecError::Io(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                    return (out, None)
                }
                Err(e) => return (out, Some(e)),
            }
        }
    }

    fn sample_packets() -> Vec<Packet> {
        let mut v = vec![
            Packet::decode(&hex(JOINT_POSITION_EXAMPLE), ByteOrder::Big).unwrap(),
            Packet::decode(&hex(JOINT_TRAJ_PT_EXAMPLE), ByteOrder::Big).unwrap(),
            Packet::decode(&hex(STATUS_EXAMPLE), ByteOrder::Big).unwrap(),
            Packet::request(msg_type::PING, Body::Ping),
            Packet::reply(msg_type::JOINT_TRAJ_PT, ReplyCode::Failure, Body::Empty),
        ];
        v.push(Packet::request(
            msg_type::FITUP_TOOL,
            Body::Tool(ToolCommand {
                version: 1,
                action: ToolAction::Touch,
                index: 0,
                value: 0.01,
            }),
        ));
        v
    }

    #[test]
    fn a_stream_split_at_every_byte_with_pauses_decodes_the_same() {
        for order in [ByteOrder::Big, ByteOrder::Little] {
            let packets = sample_packets();
            let bytes: Vec<u8> = packets.iter().flat_map(|p| p.encode(order)).collect();
            // One cut at every boundary, and every byte on its own.
            for cut in 0..=bytes.len() {
                let (got, err) = read_all(&mut Paused::new(&bytes, &[cut]), order);
                assert!(err.is_none(), "cut {cut}: {err:?}");
                assert_eq!(got, packets, "cut {cut}");
            }
            let every: Vec<usize> = (1..bytes.len()).collect();
            let mut r = Paused::new(&bytes, &every);
            let (got, err) = read_all(&mut r, order);
            assert!(err.is_none(), "{err:?}");
            assert_eq!(got, packets);
            assert_eq!(r.pauses, bytes.len() - 1);
        }
    }

    #[test]
    fn a_stream_that_ends_mid_packet_is_truncated_not_lost_silently() {
        let bytes = hex(JOINT_TRAJ_PT_EXAMPLE);
        for end in 1..bytes.len() {
            let cuts: Vec<usize> = (1..end).collect();
            let (got, err) = read_all(&mut Paused::new(&bytes[..end], &cuts), ByteOrder::Big);
            assert!(got.is_empty());
            assert!(
                matches!(err, Some(CodecError::Truncated { .. })),
                "{end}: {err:?}"
            );
        }
    }

    /// `bytes` with every 4-byte word reversed: the little-endian form of a
    /// big-endian stream (every field of simple_message is 4 bytes).
    fn swap_words(bytes: &[u8]) -> Vec<u8> {
        bytes
            .chunks(4)
            .flat_map(|w| w.iter().rev().copied().collect::<Vec<_>>())
            .collect()
    }

    #[test]
    fn a_sane_length_reads_sanely_in_one_order_only() {
        for len in HEADER_SIZE as i32..=MAX_LENGTH as i32 {
            assert_eq!(ByteOrder::detect(len.to_be_bytes()), Some(ByteOrder::Big));
            assert_eq!(
                ByteOrder::detect(len.to_le_bytes()),
                Some(ByteOrder::Little)
            );
            // The other reading is far out of range (≥ 2^16 unsigned).
            assert!(u32::from_le_bytes(len.to_be_bytes()) >= 1 << 16);
        }
        for bad in [0i32, 11, 1025, -1, i32::MAX, 0x4745_5420] {
            assert_eq!(ByteOrder::detect(bad.to_be_bytes()), None, "{bad}");
        }
        assert_eq!(ByteOrder::detect(*b"GET "), None);
    }

    #[test]
    fn the_appendix_streams_in_little_endian_decode_the_same() {
        for example in [
            JOINT_POSITION_EXAMPLE,
            JOINT_TRAJ_PT_EXAMPLE,
            STATUS_EXAMPLE,
        ] {
            let big = hex(example);
            let little = swap_words(&big);
            let p = Packet::decode(&big, ByteOrder::Big).unwrap();
            assert_eq!(Packet::decode(&little, ByteOrder::Little).unwrap(), p);
            assert_eq!(p.encode(ByteOrder::Little), little);
            for (bytes, order) in [(&big, ByteOrder::Big), (&little, ByteOrder::Little)] {
                let mut frames = FrameReader::detecting();
                assert_eq!(frames.order(), None);
                assert_eq!(frames.read_packet(&mut &bytes[..]).unwrap(), p);
                assert_eq!(frames.order(), Some(order));
            }
        }
    }

    #[test]
    fn a_detecting_reader_keeps_the_first_order_and_refuses_garbage() {
        let big = hex(STATUS_EXAMPLE);
        let little = swap_words(&big);
        // Little first: the big-endian frame after it is a bad length.
        let mut stream = little.clone();
        stream.extend(&big);
        let mut frames = FrameReader::detecting();
        let mut r = &stream[..];
        frames.read_packet(&mut r).unwrap();
        assert!(matches!(
            frames.read_packet(&mut r),
            Err(CodecError::BadLength(_))
        ));
        // A prefix sane in neither order (an HTTP request).
        let mut frames = FrameReader::detecting();
        assert!(matches!(
            frames.read_packet(&mut &b"GET / HTTP/1.1\r\n"[..]),
            Err(CodecError::BadLength(_))
        ));
        assert_eq!(frames.order(), None);
    }

    #[test]
    fn a_frame_that_does_not_decode_leaves_the_stream_in_step() {
        for order in [ByteOrder::Big, ByteOrder::Little] {
            // GET_VERSION (2), header only; a JOINT_TRAJ_PT with a NaN joint; a
            // topic of an unknown type with a body; then a PING.
            let get_version = Packet::request(2, Body::Empty).encode(order);
            let mut nan = Packet::decode(&hex(JOINT_TRAJ_PT_EXAMPLE), ByteOrder::Big)
                .unwrap()
                .encode(order);
            let at = PREFIX_SIZE + HEADER_SIZE + 4;
            nan[at..at + 4].copy_from_slice(&match order {
                ByteOrder::Big => f32::NAN.to_be_bytes(),
                ByteOrder::Little => f32::NAN.to_le_bytes(),
            });
            let mut unknown_topic = Packet::topic(15, Body::Ping).encode(order);
            unknown_topic.extend(Packet::request(msg_type::PING, Body::Ping).encode(order));
            let mut stream = get_version;
            stream.extend(&nan);
            stream.extend(&unknown_topic);
            let mut frames = FrameReader::detecting();
            let mut r = &stream[..];
            let f = frames.read_frame(&mut r).unwrap();
            assert_eq!(
                f.header(),
                RawHeader {
                    msg_type: 2,
                    comm_type: 2,
                    reply_code: 0
                }
            );
            assert!(f.header().is_request());
            assert!(matches!(f.decode(), Err(CodecError::UnknownType(2))));
            let f = frames.read_frame(&mut r).unwrap();
            assert_eq!(f.header().msg_type, msg_type::JOINT_TRAJ_PT);
            assert!(matches!(
                f.decode(),
                Err(CodecError::BadField {
                    field: "joint_data",
                    ..
                })
            ));
            let f = frames.read_frame(&mut r).unwrap();
            assert!(!f.header().is_request());
            assert!(matches!(f.decode(), Err(CodecError::UnknownType(15))));
            let p = frames.read_packet(&mut r).unwrap();
            assert_eq!(p, Packet::request(msg_type::PING, Body::Ping));
            assert_eq!(frames.order(), Some(order));
        }
    }

    #[test]
    fn header_only_ping_and_lenient_replies() {
        // industrial_core's PingMessage: length 12, PING, SERVICE_REQUEST, INVALID.
        let ping = hex("0000000C 00000001 00000002 00000000");
        let p = Packet::decode(&ping, ByteOrder::Big).unwrap();
        assert_eq!(p, Packet::request(msg_type::PING, Body::Empty));
        // After FAILURE the payload is invalid: not decoded (here: a NaN).
        let mut fail = Packet::reply(
            msg_type::JOINT_TRAJ_PT,
            ReplyCode::Failure,
            Body::DummyReals,
        )
        .encode(ByteOrder::Big);
        fail[16..20].copy_from_slice(&f32::NAN.to_be_bytes());
        let p = Packet::decode(&fail, ByteOrder::Big).unwrap();
        assert_eq!(p.reply_code, ReplyCode::Failure);
        assert_eq!(p.body, Body::Empty);
        // A reply that echoes the point (industrial_core's typed messages).
        let pt = Packet::decode(&hex(JOINT_TRAJ_PT_EXAMPLE), ByteOrder::Big).unwrap();
        let echo = Packet::reply(msg_type::JOINT_TRAJ_PT, ReplyCode::Success, pt.body.clone());
        let bytes = echo.encode(ByteOrder::Big);
        assert_eq!(bytes.len(), 68);
        assert_eq!(Packet::decode(&bytes, ByteOrder::Big).unwrap(), echo);
    }

    proptest::proptest! {
        #![proptest_config(crate::test_support::proptest_config(256))]

        /// Random chunkings of a random sequence of valid packets decode to the same
        /// packets, whatever the pauses between chunks.
        #[test]
        fn random_chunkings_decode_to_the_same_packets(
            picks in proptest::collection::vec(0usize..6, 1..12),
            cuts in proptest::collection::vec(0usize..700, 0..40),
            little in proptest::bool::ANY,
        ) {
            let order = if little { ByteOrder::Little } else { ByteOrder::Big };
            let all = sample_packets();
            let packets: Vec<Packet> = picks.iter().map(|&i| all[i].clone()).collect();
            let bytes: Vec<u8> = packets.iter().flat_map(|p| p.encode(order)).collect();
            let mut cuts = cuts;
            cuts.sort_unstable();
            let (got, err) = read_all(&mut Paused::new(&bytes, &cuts), order);
            proptest::prop_assert!(err.is_none(), "{:?}", err);
            proptest::prop_assert_eq!(got, packets);
        }

        /// Garbage, and any length prefix, give errors, never a panic, and nothing
        /// past a bad prefix is read.
        #[test]
        fn garbage_and_bad_prefixes_are_errors(
            prefix in proptest::num::i32::ANY,
            tail in proptest::collection::vec(proptest::num::u8::ANY, 0..200),
            cuts in proptest::collection::vec(0usize..210, 0..10),
        ) {
            let mut bytes = prefix.to_be_bytes().to_vec();
            bytes.extend(&tail);
            let mut cuts = cuts;
            cuts.sort_unstable();
            let (_, err) = read_all(&mut Paused::new(&bytes, &cuts), ByteOrder::Big);
            if !(HEADER_SIZE as i32..=MAX_LENGTH as i32).contains(&prefix) {
                proptest::prop_assert!(
                    matches!(err, Some(CodecError::BadLength(_))),
                    "{:?}",
                    err
                );
            }
        }
    }
}
