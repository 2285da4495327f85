//! Keyword arguments → the library's request types (`PlanRequest`,
//! `SequenceOptions`, check and sweep options). Only conversion: the library checks the
//! values it is given (time budgets, probabilities, tolerances) and names what it
//! refuses.

use crate::convert;
use crate::error::{Error, Result};
use fitup::collision::{Aabb, Method, SweepMethod, SweepOptions};
use fitup::planning::{Planner, RotationFreedom};
use fitup::sequence::{Mode, SequenceOptions};
use fitup::workspace::{CheckOptions, PlanRequest, WorkspaceError};
use numpy::{AllowTypeChange, PyArrayLike1, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Keyword arguments, checked against the names a call accepts.
pub struct Keywords<'py> {
    items: Vec<(String, Bound<'py, PyAny>)>,
}

impl<'py> Keywords<'py> {
    /// The keywords of `d`; a name not in `allowed` is an `InputError` with close
    /// matches.
    pub fn new(d: Option<&Bound<'py, PyDict>>, allowed: &[&'static str]) -> Result<Self> {
        let mut items = Vec::new();
        if let Some(d) = d {
            for (k, v) in d.iter() {
                let k: String = k.extract().unwrap_or_else(|_| k.to_string());
                if !allowed.contains(&k.as_str()) {
                    return Err(Error::Unknown {
                        what: "keyword argument",
                        hint: fitup::diagnostics::suggestion(&k, allowed.iter().copied()),
                        name: k,
                    });
                }
                if !v.is_none() {
                    items.push((k, v));
                }
            }
        }
        Ok(Self { items })
    }

    fn get(&self, key: &str) -> Option<&Bound<'py, PyAny>> {
        self.items.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    fn bad(key: &'static str, v: &Bound<'py, PyAny>, expected: &'static str) -> Error {
        Error::Option {
            option: key,
            value: v
                .repr()
                .map(|r| r.to_string())
                .unwrap_or_else(|_| "?".into()),
            expected,
        }
    }

    /// The value of `key` as a `T`, None when it is absent (or None); a value that
    /// is not a `T` is an `OptionError` saying it expected `expected`. Every typed
    /// reader below is this with its type and words.
    fn value<T: FromPyObjectOwned<'py>>(
        &self,
        key: &'static str,
        expected: &'static str,
    ) -> Result<Option<T>> {
        self.get(key)
            .map(|v| Self::value_of(v, key, expected))
            .transpose()
    }

    /// `v`, the value of `key`, as a `T` (see [`Keywords::value`]).
    fn value_of<T: FromPyObjectOwned<'py>>(
        v: &Bound<'py, PyAny>,
        key: &'static str,
        expected: &'static str,
    ) -> Result<T> {
        v.extract::<T>().map_err(|_| Self::bad(key, v, expected))
    }

    /// A number (ints are accepted).
    pub fn f64(&self, key: &'static str) -> Result<Option<f64>> {
        self.value(key, "a number")
    }

    /// A whole number ≥ 0.
    pub fn u64(&self, key: &'static str) -> Result<Option<u64>> {
        self.value(key, "a whole number >= 0")
    }

    /// True or False.
    pub fn bool(&self, key: &'static str) -> Result<Option<bool>> {
        self.value(key, "True or False")
    }

    /// Text.
    pub fn str(&self, key: &'static str) -> Result<Option<String>> {
        self.value(key, "a str")
    }

    /// A list of names (none when absent).
    pub fn names(&self, key: &'static str) -> Result<Vec<String>> {
        Ok(self.value(key, "a list of names")?.unwrap_or_default())
    }

    /// A pose: a 4×4 array-like (column-vector matrix, mm).
    pub fn pose(&self, key: &'static str) -> Result<Option<fitup::math::Transform>> {
        self.value::<PyArrayLike2<'py, f64, AllowTypeChange>>(key, "a 4x4 array of numbers")?
            .map(|a| convert::pose_of(a.as_array(), key))
            .transpose()
    }

    /// A box `[[xmin, ymin, zmin], [xmax, ymax, zmax]]` (mm, world).
    pub fn bounds(&self, key: &'static str) -> Result<Option<Aabb>> {
        const BOX: &str = "[[xmin, ymin, zmin], [xmax, ymax, zmax]] in mm";
        let Some(v) = self.get(key) else {
            return Ok(None);
        };
        let a: PyArrayLike2<'py, f64, AllowTypeChange> = Self::value_of(v, key, BOX)?;
        if a.shape() != [2, 3] {
            return Err(Error::Shape {
                argument: key,
                expected: "(2, 3)",
                shape: a.shape().to_vec(),
            });
        }
        let a = a.as_array();
        let lo = fitup::math::Point3::new(a[[0, 0]], a[[0, 1]], a[[0, 2]]);
        let hi = fitup::math::Point3::new(a[[1, 0]], a[[1, 1]], a[[1, 2]]);
        // NaN compares as neither below nor above: refused as well.
        if (0..3).any(|i| lo[i].partial_cmp(&hi[i]) != Some(std::cmp::Ordering::Less)) {
            return Err(Self::bad(
                key,
                v,
                "a box whose min is below its max on every axis",
            ));
        }
        Ok(Some(Aabb::new(lo, hi)))
    }

    /// A 3-vector (mm or a direction).
    pub fn vec3(&self, key: &'static str) -> Result<Option<fitup::math::Vec3>> {
        self.value::<PyArrayLike1<'py, f64, AllowTypeChange>>(key, "3 numbers")?
            .map(|a| convert::vec3_of(a.as_array(), key))
            .transpose()
    }

    /// The keywords as JSON (numbers, booleans, text; anything else as its repr), as
    /// they are stored with a path.
    pub fn to_json(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        for (k, v) in &self.items {
            let j = if let Ok(b) = v.extract::<bool>() {
                serde_json::Value::Bool(b)
            } else if let Ok(i) = v.extract::<i64>() {
                serde_json::Value::from(i)
            } else if let Ok(x) = v.extract::<f64>() {
                serde_json::Number::from_f64(x)
                    .map(serde_json::Value::Number)
                    .unwrap_or(serde_json::Value::Null)
            } else if let Ok(s) = v.extract::<String>() {
                serde_json::Value::String(s)
            } else {
                serde_json::Value::String(v.repr().map(|r| r.to_string()).unwrap_or_default())
            };
            m.insert(k.clone(), j);
        }
        serde_json::Value::Object(m)
    }
}

/// The keywords of `plan_path`, `plan_insertion` and `plan_disassembly`.
pub const PLAN_KEYS: [&str; 18] = [
    "planner",
    "seed",
    "time_limit_ms",
    "max_iterations",
    "step",
    "goal_bias",
    "smoothing",
    "tolerance",
    "edge",
    "contact_step",
    "edge_step",
    "edge_step_rad",
    "bounds",
    "margin",
    "rotation",
    "rotation_weight",
    "fallback_share",
    "start",
];

/// A planning request from keywords; `planner` defaults to `default_planner`.
/// Returns the request and its seed.
pub fn plan_request(kw: &Keywords<'_>, default_planner: &str) -> Result<(PlanRequest, u64)> {
    let name = kw.str("planner")?.unwrap_or_else(|| default_planner.into());
    // Names, option ranges and which planner has which option are the library's
    // rules (`PlanError`), the same words a script gets.
    let refused = |e: fitup::planning::PlanError| Error::Workspace(WorkspaceError::Plan(e));
    let mut planner: Planner = name.parse().map_err(refused)?;
    let seed = kw.u64("seed")?.unwrap_or(0);
    {
        let limits = planner.limits_mut();
        limits.seed = seed;
        if let Some(n) = kw.u64("max_iterations")? {
            limits.max_iterations = n as usize;
        }
        limits.time_limit_ms = kw.f64("time_limit_ms")?;
    }
    if let Some(s) = kw.f64("step")? {
        planner.set_step(s);
    }
    if let Some(p) = kw.f64("goal_bias")? {
        planner.set_goal_bias(p).map_err(refused)?;
    }
    if let Some(on) = kw.bool("smoothing")? {
        planner.set_smoothing(on);
    }
    if let Some(f) = kw.f64("fallback_share")? {
        planner.set_fallback_share(f).map_err(refused)?;
    }
    let mut request = PlanRequest {
        planner,
        ..PlanRequest::default()
    };
    if let Some(t) = kw.f64("tolerance")? {
        request.validator.tolerance = t;
    }
    request.validator.edge = match kw.str("edge")?.as_deref() {
        None | Some("continuous") => SweepMethod::Continuous {
            contact_step_mm: kw
                .f64("contact_step")?
                .unwrap_or(SweepMethod::DEFAULT_CONTACT_STEP_MM),
        },
        Some("step") => SweepMethod::Stepwise {
            step_mm: kw.f64("edge_step")?.unwrap_or(0.1),
            step_rad: kw.f64("edge_step_rad")?.unwrap_or(0.1f64.to_radians()),
        },
        Some(other) => {
            return Err(Error::Option {
                option: "edge",
                value: format!("{other:?}"),
                expected: "\"continuous\" or \"step\"",
            })
        }
    };
    request.bounds = kw.bounds("bounds")?;
    if let Some(m) = kw.f64("margin")? {
        request.margin_mm = Some(m);
    }
    if kw.bool("rotation")? == Some(false) {
        request.rotation = RotationFreedom::Fixed;
    }
    request.rotation_weight = kw.f64("rotation_weight")?;
    request.start = kw.pose("start")?;
    Ok((request, seed))
}

/// The keywords of the static checks.
pub fn check_options(method: &str, tolerance: Option<f64>) -> Result<CheckOptions> {
    let method: Method = method
        .parse()
        .map_err(|e| Error::Workspace(fitup::workspace::WorkspaceError::Collision(e)))?;
    Ok(CheckOptions {
        method,
        tolerance: tolerance.unwrap_or(fitup::collision::DEFAULT_TOLERANCE),
    })
}

/// The keywords of a sweep.
pub fn sweep_options(tolerance: Option<f64>, time_limit_ms: Option<f64>) -> SweepOptions {
    SweepOptions {
        tolerance: tolerance.unwrap_or(fitup::collision::DEFAULT_TOLERANCE),
        time_limit_ms,
        ..SweepOptions::default()
    }
}

/// The keywords of `plan_sequence`.
pub const SEQUENCE_KEYS: [&str; 16] = [
    "mode",
    "base",
    "order",
    "max_sequences",
    "time_limit_ms",
    "seed",
    "tolerance",
    "components",
    "exclude",
    "threaded",
    "support",
    "gravity",
    "planner_fallback",
    "fallback_time_limit_ms",
    "max_tilt",
    "sphere_directions",
];

/// Sequence options from keywords.
pub fn sequence_options(kw: &Keywords<'_>) -> Result<SequenceOptions> {
    let mut o = SequenceOptions::default();
    if let Some(m) = kw.str("mode")? {
        o.mode = Mode::parse(&m).ok_or_else(|| Error::Option {
            option: "mode",
            value: format!("{m:?}"),
            expected: "\"mates\" or \"geometry\"",
        })?;
    }
    o.base = kw.str("base")?;
    o.order = kw.names("order")?;
    if let Some(n) = kw.u64("max_sequences")? {
        o.max_sequences = n as usize;
    }
    o.time_limit_ms = kw.f64("time_limit_ms")?;
    if let Some(s) = kw.u64("seed")? {
        o.seed = s;
    }
    if let Some(t) = kw.f64("tolerance")? {
        o.tolerance = t;
    }
    o.components = kw.names("components")?;
    o.exclude = kw.names("exclude")?;
    o.threaded = kw.names("threaded")?;
    if let Some(s) = kw.bool("support")? {
        o.support = s;
    }
    o.gravity = kw.vec3("gravity")?;
    if let Some(p) = kw.bool("planner_fallback")? {
        o.planner_fallback = p;
    }
    if let Some(t) = kw.f64("fallback_time_limit_ms")? {
        o.fallback_time_limit_ms = t;
    }
    if let Some(t) = kw.f64("max_tilt")? {
        o.max_tilt = t;
    }
    if let Some(n) = kw.u64("sphere_directions")? {
        o.sphere_directions = n as usize;
    }
    Ok(o)
}
