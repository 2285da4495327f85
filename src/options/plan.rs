//! The planning vocabulary: `plan_path`, `plan_disassembly`, `plan_problem` (Rhai) and
//! `plan_path`, `plan_insertion`, `plan_disassembly` (Python). Lengths mm, angles in
//! degrees where the key says `_deg`; [`Plan::request`] builds the library's
//! [`PlanRequest`] (radians).
//!
//! Lengths whose default is `None` are derived from the problem (its bounds, the
//! moving part's size, the clearance found; docs/planning.md): the planner's own
//! defaults decide them, not this table.

use super::{Deprecated, Key, Kind, Options, Vocabulary};
use crate::collision::SweepMethod;
use crate::math::{Aabb, Transform};
use crate::planning::{
    MeshValidatorOptions, NarrowPassage, PlanError, PlanLimits, Planner, RotationFreedom,
    DEFAULT_TIME_LIMIT_MS, PLANNER_NAMES,
};
use crate::workspace::PlanRequest;
use serde::{Deserialize, Serialize};

/// The stepwise edge check's translation step while none is given (mm); the lead's
/// derivation from the problem replaces it.
const STEPWISE_EDGE_STEP_MM: f64 = 0.1;
/// The stepwise edge check's rotation step, degrees.
const STEPWISE_EDGE_STEP_DEG: f64 = 0.1;

const DERIVED: Option<&str> = Some("derived from the problem, see docs/planning.md");
const PLANNERS_OWN: Option<&str> = Some("the planner's own (docs/planning.md)");

/// Options of a path-planning request (see the [`VOCABULARY`](Options::VOCABULARY)
/// for each key's meaning). `None`: the default in the table's words.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
#[allow(non_snake_case)]
pub struct Plan {
    /// Planner name ([`PLANNER_NAMES`]); `None`: the call's default.
    pub planner: Option<String>,
    /// Seed of the run.
    pub seed: u64,
    /// Iteration limit.
    pub max_iterations: u64,
    /// Budget of the whole call, ms.
    pub time_limit_ms: f64,
    /// Extension step, mm (`greedy_ant`: segments of s → e).
    pub step: Option<f64>,
    /// Goal bias, a probability.
    pub goal_bias: Option<f64>,
    /// Path shortcutting.
    pub smoothing: Option<bool>,
    /// Narrow-passage measures.
    pub narrow: Option<NarrowSwitch>,
    /// Share of the search the fallbacks may take, 0..1.
    pub fallback_share: Option<f64>,
    /// `greedy_ant`'s shortest length L, mm.
    pub L: Option<f64>,
    /// `greedy_ant`'s dis, mm.
    pub dis: Option<f64>,
    /// `greedy_ant`'s radius, mm.
    pub radius: Option<f64>,
    /// Penetration tolerance, mm.
    pub tolerance: Option<f64>,
    /// Edge check: "continuous" or "step".
    pub edge: String,
    /// Contact step of the continuous edge check, mm.
    pub contact_step: Option<f64>,
    /// Translation step of the stepwise edge check, mm.
    pub edge_step: Option<f64>,
    /// Rotation step of the stepwise edge check, degrees.
    pub edge_step_deg: f64,
    /// Bounds of the part origin (world, mm).
    pub bounds: Option<Aabb>,
    /// Growth of the default bounds, mm.
    pub margin: Option<f64>,
    /// Whether the part may turn.
    pub rotation: bool,
    /// Weight of rotation in the metric, mm per rad.
    pub rotation_weight: Option<f64>,
    /// Seed 002's disassembly first.
    pub disassemble: bool,
    /// Start pose (world, mm); `None`: the component's pose.
    #[serde(with = "super::serde_pose")]
    pub start: Option<Transform>,
}

impl Default for Plan {
    fn default() -> Self {
        let limits = PlanLimits::default();
        Self {
            planner: None,
            seed: limits.seed,
            max_iterations: limits.max_iterations as u64,
            time_limit_ms: limits.time_limit_ms.unwrap_or(DEFAULT_TIME_LIMIT_MS),
            step: None,
            goal_bias: None,
            smoothing: None,
            narrow: None,
            fallback_share: None,
            L: None,
            dis: None,
            radius: None,
            tolerance: None,
            edge: "continuous".into(),
            contact_step: None,
            edge_step: None,
            edge_step_deg: STEPWISE_EDGE_STEP_DEG,
            bounds: None,
            margin: None,
            rotation: true,
            rotation_weight: None,
            disassemble: false,
            start: None,
        }
    }
}

/// `narrow`: `true` (fitup's measures), `false` (all off) or some of them changed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum NarrowSwitch {
    /// On (the defaults) or off ([`NarrowPassage::OFF`]).
    On(bool),
    /// The defaults with these changed.
    Set(Narrow),
}

/// The narrow-passage measures of the tree planners ([`NarrowPassage`]), angles in
/// degrees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Narrow {
    /// Largest turn of a retried blocked extension, degrees; 0: none.
    pub max_turn_deg: f64,
    /// Dynamic-domain radius, mm of the metric; 0: off.
    pub dynamic_domain: Option<f64>,
    /// Probability of a bridge-test sample.
    pub bridge: f64,
    /// Bridge width, mm.
    pub bridge_width: Option<f64>,
    /// A blocked extension keeps its farthest free pose.
    pub to_contact: bool,
    /// Share of `rrt_connect`'s work for the axis-move search, 0..1.
    pub axis_moves: f64,
    /// Probability of an axis-aligned sample, 0..1.
    pub axis_samples: f64,
}

impl Default for Narrow {
    fn default() -> Self {
        let n = NarrowPassage::default();
        Self {
            max_turn_deg: n.max_turn.map_or(0.0, f64::to_degrees),
            dynamic_domain: None,
            bridge: n.bridge,
            bridge_width: None,
            to_contact: n.to_contact,
            axis_moves: n.axis_moves,
            axis_samples: n.axis_samples,
        }
    }
}

impl Narrow {
    /// The measures in the planner's units (0 = off where the key says so).
    pub fn passage(&self) -> NarrowPassage {
        let d = NarrowPassage::default();
        NarrowPassage {
            max_turn: (self.max_turn_deg != 0.0).then(|| self.max_turn_deg.to_radians()),
            dynamic_domain: match self.dynamic_domain {
                None => d.dynamic_domain,
                Some(r) => (r != 0.0).then_some(r),
            },
            bridge: self.bridge,
            bridge_width: self.bridge_width.unwrap_or(d.bridge_width),
            to_contact: self.to_contact,
            axis_moves: self.axis_moves,
            axis_samples: self.axis_samples,
        }
    }
}

impl NarrowSwitch {
    /// The measures this switch stands for.
    pub fn passage(&self) -> NarrowPassage {
        match self {
            NarrowSwitch::On(true) => NarrowPassage::default(),
            NarrowSwitch::On(false) => NarrowPassage::OFF,
            NarrowSwitch::Set(n) => n.passage(),
        }
    }
}

impl Options for Narrow {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "narrow",
        keys: &[
            Key {
                name: "max_turn_deg",
                kind: Kind::Number,
                unit: "deg",
                meaning: "a blocked extension is retried turning at most this much; 0 = no limit",
                default: None,
            },
            Key {
                name: "dynamic_domain",
                kind: Kind::Number,
                unit: "mm",
                meaning: "dynamic-domain radius in the metric; 0 = off",
                default: DERIVED,
            },
            Key {
                name: "bridge",
                kind: Kind::Number,
                unit: "",
                meaning: "probability of a bridge-test sample (0..1)",
                default: None,
            },
            Key {
                name: "bridge_width",
                kind: Kind::Number,
                unit: "mm",
                meaning: "width of the bridge test",
                default: DERIVED,
            },
            Key {
                name: "to_contact",
                kind: Kind::Bool,
                unit: "",
                meaning: "a blocked extension keeps its farthest free pose",
                default: None,
            },
            Key {
                name: "axis_moves",
                kind: Kind::Number,
                unit: "",
                meaning: "the share of `rrt_connect`'s work for its axis-move search (0..1): quarter and eighth turns about the part's own axes and slides along them to contact, what finds slots aligned with the part; 0 = off",
                default: None,
            },
            Key {
                name: "axis_samples",
                kind: Kind::Number,
                unit: "",
                meaning: "the probability (0..1) that a sample keeps the tree root's orientation turned about one axis of the assembly frame, for parts moving in a flat corridor",
                default: None,
            },
        ],
        deprecated: &[],
    };
}

impl Options for Plan {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "planning",
        keys: &[
            Key {
                name: "planner",
                kind: Kind::Choice(&PLANNER_NAMES),
                unit: "",
                meaning: "the planner (see the section)",
                default: Some("`\"rrt_connect\"`; `\"local_rrt\"` for `plan_disassembly`"),
            },
            Key {
                name: "seed",
                kind: Kind::Count,
                unit: "",
                meaning: "seed of the run: same seed, same path (when the iteration limit, not the time, ends the search)",
                default: None,
            },
            Key {
                name: "max_iterations",
                kind: Kind::Count,
                unit: "",
                meaning: "iteration limit (tree extensions, or layers for `greedy_ant`)",
                default: None,
            },
            Key {
                name: "time_limit_ms",
                kind: Kind::Number,
                unit: "ms",
                meaning: "budget of the whole call, search and smoothing; smoothing stops when it is spent and keeps the best path so far",
                default: None,
            },
            Key {
                name: "step",
                kind: Kind::Number,
                unit: "mm",
                meaning: "extension step of the tree planners in the metric; for `greedy_ant` the number of segments of s → e",
                default: DERIVED,
            },
            Key {
                name: "goal_bias",
                kind: Kind::Number,
                unit: "",
                meaning: "probability of sampling the goal (`rrt_floyd`, `rrt`, `biased_rrt`, `local_rrt`)",
                default: PLANNERS_OWN,
            },
            Key {
                name: "smoothing",
                kind: Kind::Bool,
                unit: "",
                meaning: "shortcut the path found",
                default: Some("on"),
            },
            Key {
                name: "narrow",
                kind: Kind::Switch(Narrow::VOCABULARY),
                unit: "",
                meaning: "the narrow-passage measures of the tree planners: `false` (all off), `true` (the defaults) or a map changing some (the `narrow` table)",
                default: Some("on for `rrt_connect` and `disassemble: true`, off for `rrt`, `biased_rrt`, `local_rrt`"),
            },
            Key {
                name: "fallback_share",
                kind: Kind::Number,
                unit: "",
                meaning: "the largest share (0..1) of the search's checks that the lattice, extension to contact, bridge test and dynamic-domain redraws may take, the rest being plain RRT-Connect iterations (tree planners)",
                default: Some("0.1 for `rrt_connect` and `disassemble: true`, 1 for `rrt`, `biased_rrt`, `local_rrt`"),
            },
            Key {
                name: "L",
                kind: Kind::Number,
                unit: "mm",
                meaning: "`greedy_ant`'s shortest length L (seed 000)",
                default: PLANNERS_OWN,
            },
            Key {
                name: "dis",
                kind: Kind::Number,
                unit: "mm",
                meaning: "`greedy_ant`'s dis (seed 000)",
                default: PLANNERS_OWN,
            },
            Key {
                name: "radius",
                kind: Kind::Number,
                unit: "mm",
                meaning: "`greedy_ant`'s radius (seed 000)",
                default: PLANNERS_OWN,
            },
            Key {
                name: "tolerance",
                kind: Kind::Number,
                unit: "mm",
                meaning: "penetration tolerance: crossings up to this depth count as touching, which is allowed",
                default: DERIVED,
            },
            Key {
                name: "edge",
                kind: Kind::Choice(&["continuous", "step"]),
                unit: "",
                meaning: "how edges are checked: `\"continuous\"` (conservative advancement, which cannot jump over an obstacle; static checks every `contact_step` while the part touches one) or `\"step\"` (static checks `edge_step` and `edge_step_deg` apart; thin features can be missed)",
                default: None,
            },
            Key {
                name: "contact_step",
                kind: Kind::Number,
                unit: "mm",
                meaning: "`edge: \"continuous\"`: checks this far apart while the part touches an obstacle",
                default: DERIVED,
            },
            Key {
                name: "edge_step",
                kind: Kind::Number,
                unit: "mm",
                meaning: "`edge: \"step\"`: largest translation between two checks (at least 0.0001)",
                default: DERIVED,
            },
            Key {
                name: "edge_step_deg",
                kind: Kind::Number,
                unit: "deg",
                meaning: "`edge: \"step\"`: largest rotation between two checks",
                default: None,
            },
            Key {
                name: "bounds",
                kind: Kind::Box,
                unit: "mm",
                meaning: "bounds of the part origin (world)",
                default: Some("the assembly box with start and goal, grown by `margin`"),
            },
            Key {
                name: "margin",
                kind: Kind::Number,
                unit: "mm",
                meaning: "growth of the default bounds",
                default: DERIVED,
            },
            Key {
                name: "rotation",
                kind: Kind::Bool,
                unit: "",
                meaning: "whether the part may turn",
                default: None,
            },
            Key {
                name: "rotation_weight",
                kind: Kind::Number,
                unit: "mm/rad",
                meaning: "weight of rotation in the metric",
                default: DERIVED,
            },
            Key {
                name: "disassemble",
                kind: Kind::Bool,
                unit: "",
                meaning: "seed 002: the end (start or goal) whose box overlaps the box of the other components is the assembled one; plan the disassembly from it until the part leaves that box and join the other end with `rrt_connect` — the way into tight clearances (Python: `plan_insertion`)",
                default: None,
            },
            Key {
                name: "start",
                kind: Kind::Pose,
                unit: "mm, deg",
                meaning: "where the path starts (world); `plan_problem` takes it from the file",
                default: Some("the component's pose"),
            },
        ],
        deprecated: &[Deprecated {
            old: "edge_step_rad",
            new: "edge_step_deg",
            scale: 180.0 / std::f64::consts::PI,
            until: "fitup 0.2",
        }],
    };
}

impl Plan {
    /// The library's request: the planner called `planner` (else `default_planner`)
    /// with these options, the validator, bounds and freedoms. Only converts (units,
    /// `0` = off); the ranges are checked when planning.
    ///
    /// # Errors
    /// An unknown planner, or an option the chosen planner does not have
    /// ([`PlanError::NotAnOption`]).
    pub fn request(&self, default_planner: &str) -> Result<PlanRequest, PlanError> {
        let mut planner: Planner = self.planner.as_deref().unwrap_or(default_planner).parse()?;
        {
            let limits = planner.limits_mut();
            limits.seed = self.seed;
            limits.max_iterations = usize::try_from(self.max_iterations).unwrap_or(usize::MAX);
            limits.time_limit_ms = Some(self.time_limit_ms);
        }
        if let Some(s) = self.step {
            planner.set_step(s);
        }
        if let Some(p) = self.goal_bias {
            planner.set_goal_bias(p)?;
        }
        if let Some(on) = self.smoothing {
            planner.set_smoothing(on);
        }
        if let Some(n) = &self.narrow {
            planner.set_narrow(n.passage())?;
        }
        if let Some(f) = self.fallback_share {
            planner.set_fallback_share(f)?;
        }
        if self.L.is_some() || self.dis.is_some() || self.radius.is_some() {
            planner.set_greedy_ant(self.L, self.dis, self.radius)?;
        }
        let mut validator = MeshValidatorOptions::default();
        if let Some(t) = self.tolerance {
            validator.tolerance = Some(t);
        }
        validator.edge = if self.edge == "step" {
            SweepMethod::Stepwise {
                step_mm: self.edge_step.unwrap_or(STEPWISE_EDGE_STEP_MM),
                step_rad: self.edge_step_deg.to_radians(),
            }
        } else {
            SweepMethod::Continuous {
                contact_step_mm: self
                    .contact_step
                    .unwrap_or(SweepMethod::DEFAULT_CONTACT_STEP_MM),
            }
        };
        Ok(PlanRequest {
            planner,
            validator,
            bounds: self.bounds,
            margin_mm: self.margin,
            rotation: if self.rotation {
                RotationFreedom::Free
            } else {
                RotationFreedom::Fixed
            },
            rotation_weight: self.rotation_weight,
            disassemble: self.disassemble,
            start: self.start,
        })
    }
}
