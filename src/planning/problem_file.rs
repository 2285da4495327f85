//! [`ProblemFile`]: a planning problem stored beside its document
//! (`models/problems/<name>.plan.json`), so scripts and benchmarks run problems by
//! name instead of repeating start, goal and bounds.
//!
//! The format is what `Problem::plan_json` (the generators in `tests/common/problems.rs`)
//! writes: poses as `{"t": [x, y, z], "q": [w, x, y, z]}` (mm; unit quaternion acting
//! on column vectors, `p' = R p + t`), boxes as `*_min` / `*_max` corners (mm), the
//! rotation weight in mm per rad.

use crate::math::Aabb;
use crate::math::{Transform, Vec3};
use nalgebra::{Quaternion, UnitQuaternion};
use serde::Deserialize;
use std::path::Path;

/// Largest problem file read, bytes: a problem is a few hundred bytes.
pub const MAX_PROBLEM_FILE_BYTES: u64 = 1 << 20;

/// Why a problem file could not be used; the message names the file and the field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ProblemFileError {
    /// Reading the file failed (missing, unreadable, too large, not a regular file).
    #[error("{file}: {cause}")]
    Read {
        /// The file.
        file: String,
        /// What went wrong.
        cause: ReadCause,
    },
    /// The text is not the problem format (JSON syntax, a missing or unknown field),
    /// with the line and column serde reports.
    #[error("{file}:{line}:{column}: {source}")]
    Syntax {
        /// The file.
        file: String,
        /// Line (1-based).
        line: usize,
        /// Column (1-based).
        column: usize,
        /// What the parser expected.
        source: serde_json::Error,
    },
    /// A value is out of range (non-finite number, quaternion far from unit length,
    /// inverted box, a pose outside the bounds).
    #[error("{file}: `{field}` {problem}")]
    Value {
        /// The file.
        file: String,
        /// The field.
        field: &'static str,
        /// What is wrong with it.
        problem: ValueProblem,
    },
}

/// Why a problem file could not be read ([`ProblemFileError::Read`]).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReadCause {
    /// The file system refused (missing, no permission…).
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// The path is a folder, a device or a pipe.
    #[error("not a regular file")]
    NotAFile,
    /// Larger than [`MAX_PROBLEM_FILE_BYTES`].
    #[error("{bytes} bytes is too large for a problem file (at most {max})")]
    TooLarge {
        /// The file's size (bytes).
        bytes: u64,
        /// The largest accepted (bytes).
        max: u64,
    },
}

/// What is wrong with a field of a problem file ([`ProblemFileError::Value`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ValueProblem {
    /// A coordinate is NaN or infinite.
    #[error("has a non-finite number")]
    NonFinite,
    /// The rotation quaternion's length is not 1 (± 1e-6).
    #[error("has a rotation quaternion of length {length}, expected 1")]
    QuaternionLength {
        /// Its length.
        length: f64,
    },
    /// A box's minimum is above its maximum on some axis.
    #[error("has a minimum above its maximum")]
    InvertedBox,
    /// An end pose's translation lies outside `bounds_min`..`bounds_max`.
    #[error("lies outside the bounds")]
    OutsideBounds,
    /// A number that must be finite and positive is not (mm/rad for the rotation
    /// weight).
    #[error("must be a finite number > 0, not {value}")]
    NotPositive {
        /// The value given.
        value: f64,
    },
    /// Only one of `product_box_min` / `product_box_max` is given.
    #[error("and `product_box_max` come together")]
    Unpaired,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseJson {
    t: [f64; 3],
    q: [f64; 4],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProblemJson {
    name: String,
    #[serde(default)]
    description: String,
    document: String,
    moving_component: String,
    start: PoseJson,
    goal: PoseJson,
    bounds_min: [f64; 3],
    bounds_max: [f64; 3],
    rotation_weight_mm_per_rad: Option<f64>,
    product_box_min: Option<[f64; 3]>,
    product_box_max: Option<[f64; 3]>,
}

/// A planning problem read from a `.plan.json` file: which component of which
/// document moves from where to where, within which bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct ProblemFile {
    /// The problem's name.
    pub name: String,
    /// One line for people.
    pub description: String,
    /// The document, relative to the problem file's folder.
    pub document: String,
    /// The component that moves.
    pub moving_component: String,
    /// Start pose of the component (assembly frame, mm).
    pub start: Transform,
    /// Goal pose of the component (assembly frame, mm).
    pub goal: Transform,
    /// Bounds of the component's origin (assembly frame, mm).
    pub bounds: Aabb,
    /// Weight of rotation in the metric, mm per rad (`None`: the space's default).
    pub rotation_weight: Option<f64>,
    /// The product's box (assembly frame, mm), when given: disassembly ends when the
    /// component's box leaves it.
    pub product_box: Option<Aabb>,
}

impl ProblemFile {
    /// Reads and checks `path` (at most [`MAX_PROBLEM_FILE_BYTES`]).
    ///
    /// # Examples
    /// ```
    /// use fitup::planning::ProblemFile;
    ///
    /// let p = ProblemFile::read("models/problems/bar_slot.plan.json".as_ref()).unwrap();
    /// assert_eq!(p.moving_component, "moving");
    /// assert_eq!(p.bounds.distance_to_point(&p.start.translation().into()), 0.0);
    /// ```
    ///
    /// # Errors
    /// [`ProblemFileError`] naming the file: unreadable, not JSON, a missing or
    /// unknown field, or a value out of range.
    pub fn read(path: &Path) -> Result<Self, ProblemFileError> {
        let file = path.display().to_string();
        let read = |cause: ReadCause| ProblemFileError::Read {
            file: file.clone(),
            cause,
        };
        let meta = std::fs::metadata(path).map_err(|e| read(e.into()))?;
        if !meta.is_file() {
            return Err(read(ReadCause::NotAFile));
        }
        if meta.len() > MAX_PROBLEM_FILE_BYTES {
            return Err(read(ReadCause::TooLarge {
                bytes: meta.len(),
                max: MAX_PROBLEM_FILE_BYTES,
            }));
        }
        let text = std::fs::read_to_string(path).map_err(|e| read(e.into()))?;
        Self::parse(&text, &file)
    }

    /// Parses and checks the text of a problem file; `file` names it in errors.
    ///
    /// # Errors
    /// As [`read`](Self::read), without the file system ones.
    pub fn parse(text: &str, file: &str) -> Result<Self, ProblemFileError> {
        let j: ProblemJson = serde_json::from_str(text).map_err(|e| ProblemFileError::Syntax {
            file: file.into(),
            line: e.line(),
            column: e.column(),
            source: e,
        })?;
        let value = |field: &'static str, problem: ValueProblem| ProblemFileError::Value {
            file: file.into(),
            field,
            problem,
        };
        let finite3 = |field: &'static str, v: [f64; 3]| {
            if v.iter().all(|x| x.is_finite()) {
                Ok(Vec3::from(v))
            } else {
                Err(value(field, ValueProblem::NonFinite))
            }
        };
        let pose = |field: &'static str, p: &PoseJson| {
            let t = finite3(field, p.t)?;
            let [w, x, y, z] = p.q;
            let q = Quaternion::new(w, x, y, z);
            let n = q.norm();
            if !(n.is_finite() && (n - 1.0).abs() <= 1e-6) {
                return Err(value(field, ValueProblem::QuaternionLength { length: n }));
            }
            Ok(Transform::from_parts(t, UnitQuaternion::new_normalize(q)))
        };
        let boxed = |field: &'static str, lo: [f64; 3], hi: [f64; 3]| {
            let (lo, hi) = (finite3(field, lo)?, finite3(field, hi)?);
            if (0..3).any(|i| lo[i] > hi[i]) {
                return Err(value(field, ValueProblem::InvertedBox));
            }
            Ok(Aabb::new(lo, hi))
        };
        let start = pose("start", &j.start)?;
        let goal = pose("goal", &j.goal)?;
        let bounds = boxed("bounds_min", j.bounds_min, j.bounds_max)?;
        for (field, p) in [("start", &start), ("goal", &goal)] {
            if bounds.distance_to_point(&p.translation().into()) > 0.0 {
                return Err(value(field, ValueProblem::OutsideBounds));
            }
        }
        if let Some(w) = j.rotation_weight_mm_per_rad {
            if !(w.is_finite() && w > 0.0) {
                return Err(value(
                    "rotation_weight_mm_per_rad",
                    ValueProblem::NotPositive { value: w },
                ));
            }
        }
        let product_box = match (j.product_box_min, j.product_box_max) {
            (Some(lo), Some(hi)) => Some(boxed("product_box_min", lo, hi)?),
            (None, None) => None,
            _ => return Err(value("product_box_min", ValueProblem::Unpaired)),
        };
        Ok(Self {
            name: j.name,
            description: j.description,
            document: j.document,
            moving_component: j.moving_component,
            start,
            goal,
            bounds,
            rotation_weight: j.rotation_weight_mm_per_rad,
            product_box,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"{"name": "x", "document": "x.yaml", "moving_component": "m",
        "start": {"t": [0, 0, 0], "q": [1, 0, 0, 0]},
        "goal": {"t": [10, 0, 0], "q": [0, 1, 0, 0]},
        "bounds_min": [-5, -5, -5], "bounds_max": [20, 5, 5]}"#;

    #[test]
    fn a_good_file_parses() {
        let p = ProblemFile::parse(GOOD, "x.plan.json").unwrap();
        assert_eq!(p.moving_component, "m");
        assert!((p.goal.translation().x - 10.0).abs() < 1e-12);
        assert!((p.goal.distance_to(&p.start).0 - std::f64::consts::PI).abs() < 1e-9);
        assert_eq!(p.product_box, None);
    }

    #[test]
    fn bad_files_name_file_and_field() {
        let bad = |text: &str| {
            ProblemFile::parse(text, "bad.plan.json")
                .unwrap_err()
                .to_string()
        };
        let e = bad("{\n\"name\": 3}");
        assert!(e.starts_with("bad.plan.json:2:"), "{e}");
        let e = bad(&GOOD.replace("[20, 5, 5]", "[-20, 5, 5]"));
        assert!(
            e.contains("bounds_min") && e.contains("minimum above"),
            "{e}"
        );
        let e = bad(&GOOD.replace("[0, 1, 0, 0]", "[0, 2, 0, 0]"));
        assert!(e.contains("`goal`") && e.contains("length 2"), "{e}");
        let e = bad(&GOOD.replace("[10, 0, 0]", "[100, 0, 0]"));
        assert!(e.contains("`goal` lies outside the bounds"), "{e}");
        let e = bad(&GOOD.replace("\"name\"", "\"nmae\""));
        assert!(e.contains("unknown field"), "{e}");
        let e = bad(&GOOD.replace("[10, 0, 0]", "[1e999, 0, 0]"));
        assert!(e.starts_with("bad.plan.json:"), "{e}");
    }
}
