//! The manipulator over TCP: ROS-Industrial **simple_message** ([`message`]), a client
//! that streams joint trajectories and reads joint state ([`client`]), and a simulated
//! controller that executes them on a document's robot ([`simulator`]).
//!
//! Ports (REP-I0006 / `industrial_robot_client` defaults): motion **11000**
//! (JOINT_TRAJ_PT requests and replies, FITUP_TOOL requests), state **11002**
//! (JOINT_POSITION and STATUS published by the controller); one rule on both sides
//! puts the state port at the motion port + 2 unless given ([`state_port_for`]).
//! Units inside fitup are
//! millimetres and radians; on the wire prismatic joints are metres (REP-103).
//!
//! Safety: a [`client::Client`] refuses an address that is not loopback unless
//! [`client::ClientOptions::allow_remote`] is set (the command line's
//! `--allow-remote`).

pub mod client;
pub mod message;
pub mod simulator;

use crate::kinematics::JointKind;
use message::MAX_JOINTS;

/// Default motion port (JOINT_TRAJ_PT).
pub const MOTION_PORT: u16 = 11000;
/// Default state port (JOINT_POSITION, STATUS): [`state_port_for`]`(MOTION_PORT)`.
pub const STATE_PORT: u16 = 11002;
/// How far above the motion port the state port is, unless given
/// (industrial_robot_client's 11000 / 11002).
pub const STATE_PORT_OFFSET: u16 = 2;

/// The state port that goes with motion port `motion`: `motion + 2`, and 0 (pick a
/// free port) for 0. The one rule of both sides: `fitup manipulator --port P` listens
/// for state on it and `skills run --target HOST:P` connects to it, unless
/// `--state-port` says otherwise on that side. `None` when `motion + 2` is not a port
/// (above 65535).
pub fn state_port_for(motion: u16) -> Option<u16> {
    match motion {
        0 => Some(0),
        p => p.checked_add(STATE_PORT_OFFSET),
    }
}

/// Why the simulator refused a trajectory point: published as STATUS `error_code`
/// (with `in_error` on) after a FAILURE reply.
///
/// | code | meaning |
/// |---|---|
/// | 1000 + j | joint `j` (0-based) outside its limits |
/// | 2000 | the segment to the point collides with the cell (workspace interference) |
/// | 3000 | out-of-order sequence number |
/// | 4000 | bad point: wrong joint count, non-finite, no usable duration or velocity |
/// | 5000 | bad tool command |
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum RefusalCode {
    /// Joint (0-based) outside its limits.
    JointLimit(usize),
    /// The motion would collide with the cell.
    Collision,
    /// Sequence number out of order.
    OutOfOrder,
    /// A malformed point.
    BadPoint,
    /// A tool command the controller cannot do.
    BadTool,
}

impl RefusalCode {
    /// The STATUS `error_code`.
    pub fn code(self) -> i32 {
        match self {
            Self::JointLimit(j) => 1000 + j as i32,
            Self::Collision => 2000,
            Self::OutOfOrder => 3000,
            Self::BadPoint => 4000,
            Self::BadTool => 5000,
        }
    }

    /// Parses [`code`](Self::code).
    pub fn from_code(code: i32) -> Option<Self> {
        Some(match code {
            1000..=1009 => Self::JointLimit((code - 1000) as usize),
            2000 => Self::Collision,
            3000 => Self::OutOfOrder,
            4000 => Self::BadPoint,
            5000 => Self::BadTool,
            _ => return None,
        })
    }
}

impl std::fmt::Display for RefusalCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::JointLimit(j) => write!(f, "joint {} outside its limits", j + 1),
            Self::Collision => write!(f, "collision with the cell"),
            Self::OutOfOrder => write!(f, "trajectory point out of order"),
            Self::BadPoint => write!(f, "malformed trajectory point"),
            Self::BadTool => write!(f, "tool command refused"),
        }
    }
}

/// Joint values (rad, mm) → wire values (rad, m), padded with zeros to 10.
pub fn joints_to_wire(kinds: &[JointKind], q: &[f64]) -> [f32; MAX_JOINTS] {
    let mut out = [0f32; MAX_JOINTS];
    for (i, (&v, k)) in q.iter().zip(kinds).take(MAX_JOINTS).enumerate() {
        out[i] = match k {
            JointKind::Prismatic => (v / 1000.0) as f32,
            _ => v as f32,
        };
    }
    out
}

/// Wire values (rad, m) → joint values (rad, mm), the first `kinds.len()`.
pub fn joints_from_wire(kinds: &[JointKind], w: &[f32; MAX_JOINTS]) -> Vec<f64> {
    kinds
        .iter()
        .zip(w)
        .map(|(k, &v)| match k {
            JointKind::Prismatic => v as f64 * 1000.0,
            _ => v as f64,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_state_port_rule() {
        assert_eq!(state_port_for(MOTION_PORT), Some(STATE_PORT));
        assert_eq!(state_port_for(12345), Some(12347));
        assert_eq!(state_port_for(0), Some(0));
        assert_eq!(state_port_for(65533), Some(65535));
        assert_eq!(state_port_for(65534), None);
        assert_eq!(state_port_for(65535), None);
    }

    #[test]
    fn refusal_codes_round_trip() {
        for c in [
            RefusalCode::JointLimit(0),
            RefusalCode::JointLimit(9),
            RefusalCode::Collision,
            RefusalCode::OutOfOrder,
            RefusalCode::BadPoint,
            RefusalCode::BadTool,
        ] {
            assert_eq!(RefusalCode::from_code(c.code()), Some(c));
        }
        assert_eq!(RefusalCode::from_code(0), None);
        assert_eq!(RefusalCode::from_code(1010), None);
    }

    #[test]
    fn prismatic_joints_are_metres_on_the_wire() {
        let kinds = [JointKind::Revolute, JointKind::Prismatic];
        let w = joints_to_wire(&kinds, &[0.5, 250.0]);
        assert_eq!(w[0], 0.5);
        assert_eq!(w[1], 0.25);
        assert_eq!(w[2..], [0.0; 8]);
        let back = joints_from_wire(&kinds, &w);
        assert!((back[1] - 250.0).abs() < 1e-4);
    }
}
