//! The motion-check vocabulary: how a moving part is checked along a motion, shared
//! by [`sweep`](super::sweep) and planner edges ([`edge_interferes`](super::edge_interferes),
//! `planning::MotionValidator`). Lengths in mm, angles in radians.

/// How a moving part is checked along a motion: at discrete poses (stepwise) or by
/// conservative advancement (continuous). The one type for sweeps
/// ([`SweepOptions::method`](super::SweepOptions::method)), mesh validators
/// (`planning::MeshValidatorOptions::edge`) and what a planned path reports
/// (`planning::PlannedPath::resolution`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SweepMethod {
    /// Static checks at poses at most `step_mm` and `step_rad` apart; a feature
    /// thinner than one step can be jumped over.
    ///
    /// For a planner edge `step_mm` bounds the translation of the part origin; for
    /// [`sweep`](super::sweep) it bounds the displacement of every point of the part
    /// (so rotations are stepped by it too), and `step_rad` may be infinite there
    /// (no separate rotation bound).
    Stepwise {
        /// Largest displacement between two checked poses, mm (> 0).
        step_mm: f64,
        /// Largest rotation between two checked poses, rad (> 0).
        step_rad: f64,
    },
    /// Conservative advancement: while the part is clear of every obstacle, each
    /// advance is shorter than the distance to the nearest one, so nothing is jumped
    /// over; within the contact gap ([`contact_gap`]) poses are checked every contact
    /// step ([`contact_step`]: `contact_step_mm`, at least half the tolerance) and
    /// never more than the room left under the tolerance (at least 0.0005 mm), so a
    /// crossing deeper than the tolerance is not stepped over.
    Continuous {
        /// Largest displacement of any point of the part between two checks while it
        /// touches an obstacle, mm (> 0; raised to half the tolerance).
        contact_step_mm: f64,
    },
}

impl std::fmt::Display for SweepMethod {
    /// `continuous (0.05 mm steps in contact)` or `stepwise 0.1 mm / 0.1146°`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SweepMethod::Continuous { contact_step_mm } => {
                write!(f, "continuous ({contact_step_mm} mm steps in contact)")
            }
            SweepMethod::Stepwise { step_mm, step_rad } => {
                write!(f, "stepwise {step_mm} mm / {:.4}°", step_rad.to_degrees())
            }
        }
    }
}

impl SweepMethod {
    /// The contact step of [`SweepMethod::CONTINUOUS`], mm.
    pub const DEFAULT_CONTACT_STEP_MM: f64 = 0.05;

    /// The continuous check with the default contact step (0.05 mm): the mesh
    /// validator's default for planner edges.
    pub const CONTINUOUS: Self = Self::Continuous {
        contact_step_mm: Self::DEFAULT_CONTACT_STEP_MM,
    };

    /// The continuous check whose contact step is the contact gap itself
    /// ([`MIN_CONTACT_GAP_MM`], raised to half the tolerance): the default of
    /// [`sweep`](super::sweep), which reports where a contact first deepens.
    pub const CONTINUOUS_FINE: Self = Self::Continuous {
        contact_step_mm: MIN_CONTACT_GAP_MM,
    };

    /// The stepwise check used by validators that do not state one: 0.1 mm,
    /// 0.002 rad.
    pub const DEFAULT: Self = Self::Stepwise {
        step_mm: Self::DEFAULT_STEP_MM,
        step_rad: Self::DEFAULT_STEP_RAD,
    };

    /// The translation step of [`SweepMethod::DEFAULT`], mm.
    pub const DEFAULT_STEP_MM: f64 = 0.1;

    /// The rotation step of [`SweepMethod::DEFAULT`], rad.
    pub const DEFAULT_STEP_RAD: f64 = 0.002;

    /// Stepwise with no rotation bound of its own (`step_rad` infinite): for
    /// [`sweep`](super::sweep), where `step_mm` (mm) bounds the displacement of every
    /// point of the part and so steps rotations too.
    pub const fn displacement_steps(step_mm: f64) -> Self {
        Self::Stepwise {
            step_mm,
            step_rad: f64::INFINITY,
        }
    }
}

/// The smallest contact gap, mm (0.5 µm): even at a zero tolerance, surfaces this
/// close count as in contact.
pub const MIN_CONTACT_GAP_MM: f64 = 5e-4;

/// The contact gap of a continuous check at penetration `tolerance` (mm): surfaces
/// closer than this count as in contact, and the check switches from distance-sized
/// advances to contact steps. Half the tolerance, at least [`MIN_CONTACT_GAP_MM`].
pub fn contact_gap(tolerance: f64) -> f64 {
    (tolerance / 2.0).max(MIN_CONTACT_GAP_MM)
}

/// The contact step actually used by a continuous check, mm: `contact_step_mm`, at
/// least half the penetration `tolerance` (mm) — a finer step cannot see a crossing
/// the tolerance does not forgive anyway. The one place this clamp is written.
pub fn contact_step(contact_step_mm: f64, tolerance: f64) -> f64 {
    contact_step_mm.max(tolerance / 2.0)
}
