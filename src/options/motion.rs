//! The vocabularies of robot motions (`move_joint`, `move_line`, `move_circle`,
//! `run_program`) and drilling programs (`drill_program`). Lengths mm, angles and
//! angular speeds in degrees (per second), times in seconds where the key says so;
//! [`Motion::motion_options`] and [`Drill::drill_options`] build the library's
//! radians.

use super::{Key, Kind, Options, Vocabulary};
use crate::kinematics::{DrillOptions, MotionOptions, ToolAxis};
use crate::math::{AngleConvention, Vec3};
use serde::{Deserialize, Serialize};

/// The keys every motion takes (also the tail of [`Drill`]'s).
const MOTION_KEYS: [Key; 5] = [
    Key {
        name: "speed",
        kind: Kind::Number,
        unit: "mm/s",
        meaning: "TCP speed of Cartesian moves (prismatic joints of joint moves too)",
        default: None,
    },
    Key {
        name: "joint_speed",
        kind: Kind::Number,
        unit: "deg/s",
        meaning: "joint speed of joint moves",
        default: None,
    },
    Key {
        name: "angular_speed",
        kind: Kind::Number,
        unit: "deg/s",
        meaning: "TCP reorientation speed of Cartesian moves; the slower of the two decides the duration",
        default: None,
    },
    Key {
        name: "interval",
        kind: Kind::Number,
        unit: "s",
        meaning: "time between output samples",
        default: None,
    },
    Key {
        name: "stream",
        kind: Kind::Bool,
        unit: "",
        meaning: "print every sample `t joints tcp` as it is made (seed 001's live monitor; in `fitup watch` the lines stream to the output)",
        default: None,
    },
];

/// `a` then `b` (a const table from two).
const fn concat<const A: usize, const B: usize, const C: usize>(
    a: [Key; A],
    b: [Key; B],
) -> [Key; C] {
    let mut out = [a[0]; C];
    let mut i = 0;
    while i < A {
        out[i] = a[i];
        i += 1;
    }
    while i < C {
        out[i] = b[i - A];
        i += 1;
    }
    out
}

/// Options of a motion (see the [`VOCABULARY`](Options::VOCABULARY)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Motion {
    /// TCP speed, mm/s.
    pub speed: f64,
    /// Joint speed, deg/s.
    pub joint_speed: f64,
    /// TCP reorientation speed, deg/s.
    pub angular_speed: f64,
    /// Sample interval, s.
    pub interval: f64,
    /// Print every sample as it is made (the face's job).
    pub stream: bool,
}

impl Default for Motion {
    fn default() -> Self {
        Self::of(&MotionOptions::default())
    }
}

impl Motion {
    fn of(o: &MotionOptions) -> Self {
        Self {
            speed: o.linear_speed,
            joint_speed: o.joint_speed.to_degrees(),
            angular_speed: o.angular_speed.to_degrees(),
            interval: o.sample_interval,
            stream: false,
        }
    }

    /// The library's motion options (radians); ranges are its own rule.
    pub fn motion_options(&self) -> MotionOptions {
        MotionOptions {
            linear_speed: self.speed,
            joint_speed: self.joint_speed.to_radians(),
            angular_speed: self.angular_speed.to_radians(),
            sample_interval: self.interval,
            ..MotionOptions::default()
        }
    }
}

impl Options for Motion {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "motion",
        keys: &MOTION_KEYS,
        deprecated: &[],
    };
}

/// Options of a drilling program: its own keys, then the motion keys.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Drill {
    /// The drill axis in the TCP frame: "x", "z" or "-z".
    pub tool_axis: String,
    /// The drill tip in the TCP frame, mm.
    pub compensation: [f64; 3],
    /// Approach distance above the hole, mm.
    pub approach: f64,
    /// Retract distance, mm.
    pub retract: f64,
    /// Spin angles sampled about the drill axis.
    pub spin_samples: u64,
    /// Travel orientation `[a, b, c]`, degrees.
    pub travel: Option<[f64; 3]>,
    /// TCP speed, mm/s.
    pub speed: f64,
    /// Joint speed, deg/s.
    pub joint_speed: f64,
    /// TCP reorientation speed, deg/s.
    pub angular_speed: f64,
    /// Sample interval, s.
    pub interval: f64,
    /// Print every sample as it is made.
    pub stream: bool,
}

impl Default for Drill {
    fn default() -> Self {
        let o = DrillOptions::default();
        let m = Motion::of(&o.motion);
        Self {
            tool_axis: match o.tool_axis {
                ToolAxis::X => "x",
                ToolAxis::Z => "z",
                ToolAxis::NegZ => "-z",
            }
            .into(),
            compensation: o.compensation.into(),
            approach: o.approach,
            retract: o.retract,
            spin_samples: o.spin_samples as u64,
            travel: None,
            speed: m.speed,
            joint_speed: m.joint_speed,
            angular_speed: m.angular_speed,
            interval: m.interval,
            stream: m.stream,
        }
    }
}

impl Drill {
    /// The motion keys of the drilling options.
    pub fn motion(&self) -> Motion {
        Motion {
            speed: self.speed,
            joint_speed: self.joint_speed,
            angular_speed: self.angular_speed,
            interval: self.interval,
            stream: self.stream,
        }
    }

    /// The library's drilling options (radians); ranges are
    /// [`DrillOptions::validate`]'s rule.
    pub fn drill_options(&self) -> DrillOptions {
        DrillOptions {
            tool_axis: self.tool_axis.parse().unwrap_or(ToolAxis::X),
            compensation: Vec3::from(self.compensation),
            approach: self.approach,
            retract: self.retract,
            spin_samples: usize::try_from(self.spin_samples).unwrap_or(usize::MAX),
            travel_orientation: self.travel.map(|[a, b, c]| {
                AngleConvention::default().rotation(a.to_radians(), b.to_radians(), c.to_radians())
            }),
            motion: self.motion().motion_options(),
        }
    }
}

impl Options for Drill {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "drilling",
        keys: &concat::<6, 5, 11>(
            [
                Key {
                    name: "tool_axis",
                    kind: Kind::Choice(&["x", "z", "-z"]),
                    unit: "",
                    meaning: "the drill axis in the TCP frame (`\"x\"`: seed 001; `\"-z\"`: e.g. the MZ07 tool point)",
                    default: None,
                },
                Key {
                    name: "compensation",
                    kind: Kind::Vector,
                    unit: "mm",
                    meaning: "tool offset compensation: the drill tip in the TCP frame (seed 001's X₀ Y₀ Z₀)",
                    default: None,
                },
                Key {
                    name: "approach",
                    kind: Kind::Number,
                    unit: "mm",
                    meaning: "distance above the hole, along the normal, where the tool aligns",
                    default: None,
                },
                Key {
                    name: "retract",
                    kind: Kind::Number,
                    unit: "mm",
                    meaning: "distance along the normal the tool retracts to after drilling",
                    default: None,
                },
                Key {
                    name: "spin_samples",
                    kind: Kind::Count,
                    unit: "",
                    meaning: "spin angles sampled about the drill axis per hole (1 to 3600)",
                    default: None,
                },
                Key {
                    name: "travel",
                    kind: Kind::Vector,
                    unit: "deg",
                    meaning: "travel orientation `[a, b, c]` of steps 1–2 (seed 001: `[0, 180, 0]`)",
                    default: Some("none (the TCP orientation at the start of each hole)"),
                },
            ],
            MOTION_KEYS,
        ),
        deprecated: &[],
    };
}
