//! The vocabularies of static interference checks (`interferences`, `touching`,
//! `interferes`, `contact`, `contacts`) and sweeps (`sweep`). Lengths mm.

use super::{Key, Kind, Options, Vocabulary};
use crate::collision::{Method, SweepMethod, SweepOptions, DEFAULT_SWEEP_TIME_LIMIT_MS};
use crate::workspace::CheckOptions;
use serde::{Deserialize, Serialize};

/// The method names of [`Method`].
const METHODS: [&str; 3] = ["exact", "aabb", "cells"];

/// Options of a static interference check; [`Check::check_options`] is the
/// library's [`CheckOptions`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Check {
    /// Exact, whole-part boxes or cut cells.
    pub method: Method,
    /// Penetration tolerance, mm.
    pub tolerance: f64,
}

impl Default for Check {
    fn default() -> Self {
        let o = CheckOptions::default();
        Self {
            method: o.method,
            tolerance: o.tolerance,
        }
    }
}

impl Check {
    /// The library's request options.
    pub fn check_options(&self) -> CheckOptions {
        CheckOptions {
            method: self.method,
            tolerance: self.tolerance,
        }
    }
}

impl Options for Check {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "interference",
        keys: &[
            Key {
                name: "method",
                kind: Kind::Choice(&METHODS),
                unit: "",
                meaning: "`\"exact\"`: solid semantics (surfaces crossing deeper than the tolerance, or one part inside the other); `\"aabb\"`: whole-part world boxes; `\"cells\"`: whole-part boxes, then the boxes of the parts' cut cells",
                default: None,
            },
            Key {
                name: "tolerance",
                kind: Kind::Number,
                unit: "mm",
                meaning: "penetration tolerance (≥ 0): crossings up to this depth are touching",
                default: None,
            },
        ],
        deprecated: &[],
    };
}

/// Options of a sweep along a motion; [`Sweep::sweep_options`] is the library's
/// [`SweepOptions`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Sweep {
    /// "continuous" or "step".
    pub method: String,
    /// `method: "step"`: largest displacement of any point between checks, mm.
    pub step: f64,
    /// Penetration tolerance, mm.
    pub tolerance: f64,
    /// Budget of the sweep, ms.
    pub time_limit_ms: f64,
}

impl Default for Sweep {
    fn default() -> Self {
        let o = SweepOptions::default();
        Self {
            method: "continuous".into(),
            // Seed 000's static check after every millimetre.
            step: 1.0,
            tolerance: o.tolerance,
            time_limit_ms: o.time_limit_ms.unwrap_or(DEFAULT_SWEEP_TIME_LIMIT_MS),
        }
    }
}

impl Sweep {
    /// The library's sweep options.
    pub fn sweep_options(&self) -> SweepOptions {
        SweepOptions {
            method: if self.method == "step" {
                SweepMethod::displacement_steps(self.step)
            } else {
                SweepMethod::CONTINUOUS_FINE
            },
            tolerance: self.tolerance,
            time_limit_ms: Some(self.time_limit_ms),
        }
    }
}

impl Options for Sweep {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "sweep",
        keys: &[
            Key {
                name: "method",
                kind: Kind::Choice(&["continuous", "step"]),
                unit: "",
                meaning: "`\"continuous\"`: conservative advancement, never misses a contact; `\"step\"`: seed 000's static check after every `step` (can jump over thin features)",
                default: None,
            },
            Key {
                name: "step",
                kind: Kind::Number,
                unit: "mm",
                meaning: "`method: \"step\"`: no point of the part moves more than this between checks",
                default: None,
            },
            Key {
                name: "tolerance",
                kind: Kind::Number,
                unit: "mm",
                meaning: "penetration tolerance of the checks",
                default: None,
            },
            Key {
                name: "time_limit_ms",
                kind: Kind::Number,
                unit: "ms",
                meaning: "budget of the sweep; a sweep that runs out of it fails with an error",
                default: None,
            },
        ],
        deprecated: &[],
    };
}
