//! The vocabulary of a new mate (`add_mate`): its driving value and alignment.
//! Lengths mm, angles degrees (as the document file writes mate values).

use super::{Key, Kind, Options, Vocabulary};
use crate::document::{DocumentError, MateKind, MateSpec};
use serde::{Deserialize, Serialize};

/// Options of a new mate; [`AddMate::spec`] is the library's [`MateSpec`].
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AddMate {
    /// Distance (mm) or angle (degrees) of a distance or angle mate.
    pub value: Option<f64>,
    /// Aligned (true) or anti-aligned (false); none: the kind's default.
    pub aligned: Option<bool>,
    /// Angle mates: the axis `component/axis` the angle is measured about.
    pub about: Option<String>,
}

impl AddMate {
    /// The mate `name` of `kind` (`coincident`, `concentric`, `parallel`,
    /// `perpendicular`, `distance`, `angle`) between entities `a` and `b`
    /// (`component/reference`), the value in the library's units (mm, radians).
    ///
    /// # Errors
    /// An unknown kind.
    pub fn spec(
        &self,
        name: &str,
        kind: &str,
        a: &str,
        b: &str,
    ) -> Result<MateSpec, DocumentError> {
        let kind = MateKind::parse(kind)
            .ok_or_else(|| DocumentError::UnknownMateKind(kind.to_string()))?;
        Ok(MateSpec {
            name: name.to_string(),
            kind,
            entities: [a.to_string(), b.to_string()],
            value: self.value.map(|v| {
                if kind == MateKind::Angle {
                    v.to_radians()
                } else {
                    v
                }
            }),
            aligned: self.aligned,
            about: self.about.clone(),
        })
    }
}

impl Options for AddMate {
    const VOCABULARY: &'static Vocabulary = &Vocabulary {
        request: "mate",
        keys: &[
            Key {
                name: "value",
                kind: Kind::Number,
                unit: "mm or deg",
                meaning: "the driving value of a `distance` (mm) or `angle` (degrees) mate, its dimension `D1@<name>`; other mates take none",
                default: Some("none"),
            },
            Key {
                name: "aligned",
                kind: Kind::Bool,
                unit: "",
                meaning: "directions aligned (`true`) or opposed (`false`); coincident and distance planes default to opposed, other mates to the nearer one",
                default: Some("the kind's"),
            },
            Key {
                name: "about",
                kind: Kind::Text,
                unit: "",
                meaning: "`angle` mates: the axis `component/axis` the angle is measured about (a signed angle over the full turn)",
                default: Some("none"),
            },
        ],
        deprecated: &[],
    };
}
