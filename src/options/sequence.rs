//! The vocabulary of assembly-sequence planning (`assembly_sequence` in Rhai,
//! `plan_sequence` in Python). Lengths mm, the tilt in degrees; [`Sequence::sequence_options`]
//! builds the library's [`SequenceOptions`] (radians).

use super::{Deprecated, Key, Kind, Options, Vocabulary};
use crate::sequence::{Mode, SequenceOptions, DEFAULT_SEQUENCE_TIME_LIMIT_MS};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Options of a sequence-planning request (see the
/// [`VOCABULARY`](Options::VOCABULARY) for each key).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Sequence {
    /// "mates" or "geometry".
    pub mode: String,
    /// The pinned base component.
    pub base: Option<String>,
    /// The first components after the base, in order.
    pub order: Vec<String>,
    /// How many sequences to return.
    pub max_sequences: u64,
    /// Budget of the whole call, ms.
    pub time_limit_ms: f64,
    /// Seed of the planner fallback.
    pub seed: u64,
    /// Penetration tolerance, mm.
    pub tolerance: f64,
    /// Deepest fit that may slide, mm.
    pub slide_fit_mm: f64,
    /// The product's components.
    pub components: Vec<String>,
    /// Components that are not part of the product.
    pub exclude: Vec<String>,
    /// Threaded components or parts.
    pub threaded: Vec<String>,
    /// Mass per component or part name.
    pub masses: BTreeMap<String, f64>,
    /// Physically plausible sequences.
    pub support: bool,
    /// Largest gap at which two components touch, mm.
    pub contact_gap_mm: f64,
    /// The down direction.
    pub gravity: Option<[f64; 3]>,
    /// Sideways room under which an insertion is difficult, mm.
    pub tight_clearance_mm: f64,
    /// Plan a path when no straight insertion exists.
    pub planner_fallback: bool,
    /// Budget of one planner fallback, ms.
    pub fallback_time_limit_ms: f64,
    /// Largest tilt between mating directions without re-mounting, degrees.
    pub max_tilt_deg: f64,
    /// Directions of the sampled sphere.
    pub sphere_directions: u64,
    /// Separation of a probe along a free direction, mm.
    pub probe_mm: f64,
    /// Step of the safe-length search, mm (0: automatic).
    pub step_mm: f64,
    /// Size ratio under which a base is inactive.
    pub small_base_ratio: f64,
}

impl Default for Sequence {
    fn default() -> Self {
        let o = SequenceOptions::default();
        Self {
            mode: o.mode.name().into(),
            base: o.base,
            order: o.order,
            max_sequences: o.max_sequences as u64,
            time_limit_ms: o.time_limit_ms.unwrap_or(DEFAULT_SEQUENCE_TIME_LIMIT_MS),
            seed: o.seed,
            tolerance: o.tolerance,
            slide_fit_mm: o.slide_fit_mm,
            components: o.components,
            exclude: o.exclude,
            threaded: o.threaded,
            masses: o.masses,
            support: o.support,
            contact_gap_mm: o.contact_gap_mm,
            gravity: o.gravity.map(|g| [g.x, g.y, g.z]),
            tight_clearance_mm: o.tight_clearance_mm,
            planner_fallback: o.planner_fallback,
            fallback_time_limit_ms: o.fallback_time_limit_ms,
            max_tilt_deg: o.max_tilt.to_degrees(),
            sphere_directions: o.sphere_directions as u64,
            probe_mm: o.probe_mm,
            step_mm: o.step_mm,
            small_base_ratio: o.small_base_ratio,
        }
    }
}

impl Sequence {
    /// The library's options (the keys not in the vocabulary keep their defaults).
    /// Ranges are [`SequenceOptions`]' own rule, when planning.
    pub fn sequence_options(&self) -> SequenceOptions {
        let count = |n: u64| usize::try_from(n).unwrap_or(usize::MAX);
        SequenceOptions {
            mode: Mode::parse(&self.mode).unwrap_or_default(),
            base: self.base.clone(),
            order: self.order.clone(),
            max_sequences: count(self.max_sequences),
            time_limit_ms: Some(self.time_limit_ms),
            seed: self.seed,
            tolerance: self.tolerance,
            slide_fit_mm: self.slide_fit_mm,
            components: self.components.clone(),
            exclude: self.exclude.clone(),
            threaded: self.threaded.clone(),
            masses: self.masses.clone(),
            support: self.support,
            contact_gap_mm: self.contact_gap_mm,
            gravity: self.gravity.map(crate::math::Vec3::from),
            tight_clearance_mm: self.tight_clearance_mm,
            planner_fallback: self.planner_fallback,
            fallback_time_limit_ms: self.fallback_time_limit_ms,
            max_tilt: self.max_tilt_deg.to_radians(),
            sphere_directions: count(self.sphere_directions),
            probe_mm: self.probe_mm,
            step_mm: self.step_mm,
            small_base_ratio: self.small_base_ratio,
            ..SequenceOptions::default()
        }
    }
}

impl Options for Sequence {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "sequence",
        keys: &[
            Key {
                name: "mode",
                kind: Kind::Choice(&["mates", "geometry"]),
                unit: "",
                meaning: "`\"mates\"`: seed 003's relation graph from the document's mates (a document without mates is planned by geometry); `\"geometry\"`: meshes only (contacts, a blocking graph, sampled directions)",
                default: None,
            },
            Key {
                name: "base",
                kind: Kind::Text,
                unit: "",
                meaning: "pin the base component",
                default: Some("chosen by size (volume, or `masses`)"),
            },
            Key {
                name: "order",
                kind: Kind::Names,
                unit: "",
                meaning: "pin the first components after the base, in order",
                default: None,
            },
            Key {
                name: "max_sequences",
                kind: Kind::Count,
                unit: "",
                meaning: "how many sequences to return, best first (1 to 1000)",
                default: None,
            },
            Key {
                name: "time_limit_ms",
                kind: Kind::Number,
                unit: "ms",
                meaning: "budget of the whole call",
                default: None,
            },
            Key {
                name: "seed",
                kind: Kind::Count,
                unit: "",
                meaning: "seed of the planner fallback and the sampled sphere (the randomized parts)",
                default: None,
            },
            Key {
                name: "tolerance",
                kind: Kind::Number,
                unit: "mm",
                meaning: "penetration tolerance of every interference check; components that interfere in the assembled pose (press fits, CAD overlaps) are fits, reported with their depth, and the checks between such a pair allow the overlap of the assembled pose and no other",
                default: None,
            },
            Key {
                name: "slide_fit_mm",
                kind: Kind::Number,
                unit: "mm",
                meaning: "fits (components that interfere in the assembled pose) no deeper than this (their reported depth) may also slide along a straight motion from the assembled pose, overlapping the partner along every line of the motion only where and by no more than assembled: a press fit, a card a little wider than its guides; deeper fits (a bolt modelled through a plate without its hole) keep to the overlap of the assembled pose; 0 turns sliding off",
                default: None,
            },
            Key {
                name: "components",
                kind: Kind::Names,
                unit: "",
                meaning: "the product's components: only they are sequenced, the others ignored; empty: every component except robot links, fixtures and `exclude`",
                default: None,
            },
            Key {
                name: "exclude",
                kind: Kind::Names,
                unit: "",
                meaning: "components that are not part of the product (fixtures, the table, pedestals)",
                default: None,
            },
            Key {
                name: "threaded",
                kind: Kind::Names,
                unit: "",
                meaning: "components or parts whose tasks are `screw`",
                default: None,
            },
            Key {
                name: "masses",
                kind: Kind::NumberMap,
                unit: "any",
                meaning: "mass per component or part name, for the base choice (missing: the mesh volume)",
                default: None,
            },
            Key {
                name: "support",
                kind: Kind::Bool,
                unit: "",
                meaning: "physically plausible sequences: every added part touches (within `contact_gap_mm`) a part already placed; parts that touch nothing within the gap are held by their closest neighbour (a clearance joint; reported as support gaps)",
                default: None,
            },
            Key {
                name: "contact_gap_mm",
                kind: Kind::Number,
                unit: "mm",
                meaning: "largest gap at which two components count as touching (support, and the contact graph of geometry mode)",
                default: None,
            },
            Key {
                name: "gravity",
                kind: Kind::Vector,
                unit: "",
                meaning: "the down direction (assembly frame, any length): every part then moves down or sideways into place",
                default: Some("none (any direction)"),
            },
            Key {
                name: "tight_clearance_mm",
                kind: Kind::Number,
                unit: "mm",
                meaning: "an insertion is difficult (ranked after easier orders) when the part cannot move this far sideways in its assembled pose in two directions across its mating direction, or when its path is planned",
                default: None,
            },
            Key {
                name: "planner_fallback",
                kind: Kind::Bool,
                unit: "",
                meaning: "plan a path with fitup's planners (`local_rrt` disassembly) when no straight insertion exists",
                default: None,
            },
            Key {
                name: "fallback_time_limit_ms",
                kind: Kind::Number,
                unit: "ms",
                meaning: "budget of one planner fallback, within the call's budget",
                default: None,
            },
            Key {
                name: "max_tilt_deg",
                kind: Kind::Number,
                unit: "deg",
                meaning: "largest angle between two consecutive mating directions that needs no re-mounting of the base (0: every change re-mounts)",
                default: None,
            },
            Key {
                name: "sphere_directions",
                kind: Kind::Count,
                unit: "",
                meaning: "directions on the sampled sphere (geometry mode, parts no other candidate frees; rotated by `seed`); 0 turns the sphere off",
                default: None,
            },
            Key {
                name: "probe_mm",
                kind: Kind::Number,
                unit: "mm",
                meaning: "how far a part is separated along a free direction to test it (larger than the largest fit clearance)",
                default: None,
            },
            Key {
                name: "step_mm",
                kind: Kind::Number,
                unit: "mm",
                meaning: "step of the safe-length search and the two-segment slide",
                default: Some("0: 1 % of the smallest part's box diagonal, 0.05 to 2 mm"),
            },
            Key {
                name: "small_base_ratio",
                kind: Kind::Number,
                unit: "",
                meaning: "a base is inactive when its size is below this fraction of its largest related part (unless pinned by `base`)",
                default: None,
            },
        ],
        deprecated: &[Deprecated {
            old: "max_tilt",
            new: "max_tilt_deg",
            scale: 180.0 / std::f64::consts::PI,
            until: "fitup 0.2",
        }],
    };
}
