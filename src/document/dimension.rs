//! Driving dimensions: `D1@<mate name>`, the names SolidWorks gives the value of a
//! distance or angle mate.

/// What a dimension measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DimensionKind {
    /// Millimetres in the document, metres as `system_value`.
    Length,
    /// Degrees in the document, radians as `system_value`.
    Angle,
}

/// A snapshot of a dimension.
#[derive(Debug, Clone, PartialEq)]
pub struct Dimension {
    /// Full name, `D1@角度1`.
    pub name: String,
    /// Length or angle.
    pub kind: DimensionKind,
    /// Internal value: mm or radians.
    pub value: f64,
}

impl Dimension {
    /// The value in document units: mm for lengths, degrees for angles.
    pub fn document_value(&self) -> f64 {
        match self.kind {
            DimensionKind::Length => self.value,
            DimensionKind::Angle => self.value.to_degrees(),
        }
    }

    /// The value in SolidWorks' `SystemValue` units: metres or radians.
    pub fn system_value(&self) -> f64 {
        match self.kind {
            DimensionKind::Length => self.value / 1000.0,
            DimensionKind::Angle => self.value,
        }
    }

    /// Internal value (mm or rad) from document units.
    pub fn from_document(kind: DimensionKind, v: f64) -> f64 {
        match kind {
            DimensionKind::Length => v,
            DimensionKind::Angle => v.to_radians(),
        }
    }

    /// Internal value (mm or rad) from SI units.
    pub fn from_system(kind: DimensionKind, v: f64) -> f64 {
        match kind {
            DimensionKind::Length => v * 1000.0,
            DimensionKind::Angle => v,
        }
    }
}

/// `D1@<mate>`.
pub fn full_name(mate: &str) -> String {
    format!("D1@{mate}")
}

/// The mate of `D1@<mate>`.
pub fn mate_of(full_name: &str) -> Option<&str> {
    full_name.strip_prefix("D1@").filter(|m| !m.is_empty())
}

/// What a driving dimension drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DimensionTarget {
    /// The value of a distance or angle mate (index into the document's mates).
    Mate(usize),
    /// A joint of a robot (indices of the robot and of the joint, in joint order).
    Joint {
        /// Robot index in the document.
        robot: usize,
        /// 0-based joint index.
        joint: usize,
    },
}
