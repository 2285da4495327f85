//! Keyword arguments → the library's option vocabularies (`fitup::options`: `Plan`,
//! `Check`, `Sweep`, …), the same tables a script's options map goes through. Only
//! conversion: Python values become JSON (4×4 arrays through the one pose transpose
//! of `convert`, `(2, 3)` boxes), and the library checks the keys, kinds and ranges
//! and names what it refuses.

use crate::convert;
use crate::error::{Error, Result};
use fitup::math::Aabb;
use fitup::options::{box_value, pose_value, Kind, Options, Vocabulary};
use numpy::{AllowTypeChange, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::Value;

/// The options `T` of a call's keyword arguments, and the keywords given as JSON
/// (stored with a path). A deprecated keyword warns (`DeprecationWarning`).
pub fn read<T: Options>(py: Python<'_>, kwargs: Option<&Bound<'_, PyDict>>) -> Result<(T, Value)> {
    let given = match kwargs {
        Some(d) => keywords_json(d, T::VOCABULARY)?,
        None => serde_json::Map::new(),
    };
    let parsed = T::from_value(Value::Object(given.clone()))?;
    if !parsed.warnings.is_empty() {
        let warnings = py.import("warnings")?;
        let category = py.get_type::<pyo3::exceptions::PyDeprecationWarning>();
        for w in &parsed.warnings {
            warnings.call_method1("warn", (w.as_str(), &category, 3))?;
        }
    }
    Ok((parsed.options, Value::Object(given)))
}

/// The keywords of `d` as the JSON map of `vocabulary` (see [`read`]).
fn keywords_json(
    d: &Bound<'_, PyDict>,
    vocabulary: &Vocabulary,
) -> Result<serde_json::Map<String, Value>> {
    let mut out = serde_json::Map::new();
    for (k, v) in d.iter() {
        let name: String = k.extract().unwrap_or_else(|_| k.to_string());
        let value = match vocabulary.key_for(&name) {
            _ if v.is_none() => Value::Null,
            Some(key) => match key.kind {
                Kind::Pose => {
                    let a: PyArrayLike2<'_, f64, AllowTypeChange> = v
                        .extract()
                        .map_err(|_| refused(vocabulary, key.name, &v, "a 4x4 array of numbers"))?;
                    pose_value(&convert::pose_of(a.as_array(), key.name)?)
                }
                Kind::Box => box_json(vocabulary, key.name, &v)?,
                Kind::Switch(nested) if v.is_instance_of::<PyDict>() => Value::Object(
                    keywords_json(v.cast::<PyDict>().map_err(PyErr::from)?, nested)?,
                ),
                _ => json_of(vocabulary, &name, &v)?,
            },
            // Unknown: the vocabulary names it with close matches.
            None => Value::Null,
        };
        out.insert(name, value);
    }
    Ok(out)
}

/// A value refused before the vocabulary sees it, in the vocabulary's words.
fn refused(vocabulary: &Vocabulary, key: &str, v: &Bound<'_, PyAny>, expected: &str) -> Error {
    Error::Options(fitup::options::OptionError::Value {
        request: vocabulary.request,
        key: key.to_string(),
        value: v
            .repr()
            .map(|r| fitup::diagnostics::shorten(&r.to_string(), 60))
            .unwrap_or_else(|_| "?".into()),
        expected: expected.to_string(),
    })
}

/// A box keyword: `[[xmin, ymin, zmin], [xmax, ymax, zmax]]` (mm, world).
fn box_json(vocabulary: &Vocabulary, key: &'static str, v: &Bound<'_, PyAny>) -> Result<Value> {
    const BOX: &str = "[[xmin, ymin, zmin], [xmax, ymax, zmax]] in mm";
    let a: PyArrayLike2<'_, f64, AllowTypeChange> =
        v.extract().map_err(|_| refused(vocabulary, key, v, BOX))?;
    if a.shape() != [2, 3] {
        return Err(Error::Shape {
            argument: key,
            expected: "(2, 3)",
            shape: a.shape().to_vec(),
        });
    }
    let a = a.as_array();
    Ok(box_value(&Aabb::new(
        [a[[0, 0]], a[[0, 1]], a[[0, 2]]],
        [a[[1, 0]], a[[1, 1]], a[[1, 2]]],
    )))
}

/// A plain keyword value as JSON: bool, int, float (finite), str, list, tuple, dict
/// and numpy arrays and scalars (through `tolist`).
fn json_of(vocabulary: &Vocabulary, key: &str, v: &Bound<'_, PyAny>) -> Result<Value> {
    if v.is_none() {
        return Ok(Value::Null);
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        if let Ok(i) = v.extract::<i64>() {
            return Ok(Value::from(i));
        }
        if let Ok(u) = v.extract::<u64>() {
            return Ok(Value::from(u));
        }
        return Err(refused(vocabulary, key, v, "a number in range"));
    }
    if v.is_instance_of::<PyFloat>() {
        let x: f64 = v.extract()?;
        return serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| refused(vocabulary, key, v, "a finite number"));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut out = serde_json::Map::new();
        for (k, x) in d.iter() {
            let k: String = k.extract().unwrap_or_else(|_| k.to_string());
            let value = json_of(vocabulary, &format!("{key}.{k}"), &x)?;
            out.insert(k, value);
        }
        return Ok(Value::Object(out));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut out = Vec::new();
        for (i, x) in v.try_iter()?.enumerate() {
            out.push(json_of(vocabulary, &format!("{key}[{i}]"), &x?)?);
        }
        return Ok(Value::Array(out));
    }
    // numpy arrays and scalars (np.float32, np.int64, np.bool_).
    if v.hasattr("tolist")? {
        let plain = v.call_method0("tolist")?;
        if !plain.is(v) {
            return json_of(vocabulary, key, &plain);
        }
    }
    Err(refused(
        vocabulary,
        key,
        v,
        "a number, bool, str, list or dict",
    ))
}

/// The keys of a request's options — the table every keyword argument of it is
/// checked against, and that ``docs/api.md`` prints: a list of dicts ``key``,
/// ``kind`` (``"number"``, ``"count"``, ``"bool"``, ``"text"``, ``"choice"``,
/// ``"names"``, ``"vector"``, ``"box"``, ``"pose"``, ``"number_map"``,
/// ``"switch"``), ``choices`` (the names of a choice, else None), ``unit`` and
/// ``meaning``. ``request``: ``"planning"``, ``"narrow"``, ``"interference"``,
/// ``"sweep"``, ``"sequence"``, ``"motion"`` or ``"drilling"``.
#[pyfunction]
pub fn option_keys<'py>(py: Python<'py>, request: &str) -> Result<Vec<Bound<'py, PyDict>>> {
    let names: Vec<&str> = fitup::options::vocabularies()
        .iter()
        .map(|v| v.request)
        .collect();
    let v = fitup::options::vocabulary(request).ok_or_else(|| Error::Unknown {
        what: "option vocabulary",
        name: request.to_string(),
        hint: fitup::diagnostics::suggestion(request, names.iter().copied()),
    })?;
    v.keys
        .iter()
        .map(|k| {
            let d = PyDict::new(py);
            d.set_item("key", k.name)?;
            d.set_item("kind", k.kind.name())?;
            d.set_item(
                "choices",
                match k.kind {
                    Kind::Choice(names) => Some(names.to_vec()),
                    _ => None,
                },
            )?;
            d.set_item("unit", k.unit)?;
            d.set_item("meaning", k.meaning)?;
            Ok(d)
        })
        .collect::<PyResult<_>>()
        .map_err(Error::from)
}
