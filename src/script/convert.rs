//! Conversions between Rhai values and fitup types, with messages that name the
//! argument. Numbers may be integers or floats everywhere (Rhai does not convert `1`
//! to `1.0` for native functions, so every binding takes numbers through [`num`]).

use super::ScriptResult;
use crate::math::{Point3, Vec3};
use rhai::{Array, Dynamic, EvalAltResult, Map};

/// A runtime error with a message; Rhai fills in the call's position.
pub fn err<T>(message: impl Into<String>) -> ScriptResult<T> {
    Err(Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(message.into()),
        rhai::Position::NONE,
    )))
}

/// Any displayable error as a script error.
pub fn fail<E: std::fmt::Display>(e: E) -> Box<EvalAltResult> {
    Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(e.to_string()),
        rhai::Position::NONE,
    ))
}

/// What a script value holds, counted as Rhai counts it against the sandbox's limits
/// (every array element and map property, nested ones included, and the text of every
/// string), so a binding can refuse a result *before* it builds it: Rhai checks only
/// the built value, after its memory is taken.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Sizes {
    /// Array elements.
    pub arrays: usize,
    /// Map properties.
    pub maps: usize,
    /// Bytes of text.
    pub chars: usize,
}

impl Sizes {
    /// An error naming `what` and the limits when these sizes pass them.
    pub(crate) fn within(self, limits: &super::Limits, what: &str) -> ScriptResult<()> {
        if self.arrays <= limits.max_array_size
            && self.maps <= limits.max_map_size
            && self.chars <= limits.max_string_size
        {
            return Ok(());
        }
        let n = |x: usize| crate::math::format::count(x as u64);
        err(format!(
            "{what} would make {} array elements, {} map properties and {} characters of text: \
             more than a script may hold (arrays up to {} elements, maps up to {} properties, \
             strings up to {} characters, nested values counted); nothing was built",
            n(self.arrays),
            n(self.maps),
            n(self.chars),
            n(limits.max_array_size),
            n(limits.max_map_size),
            n(limits.max_string_size)
        ))
    }
}

/// A finite number from an integer or a float.
pub fn num(v: &Dynamic, what: &str) -> ScriptResult<f64> {
    let x = if let Ok(f) = v.as_float() {
        f
    } else if let Ok(i) = v.as_int() {
        i as f64
    } else {
        return err(format!("{what} must be a number, not {}", v.type_name()));
    };
    if !x.is_finite() {
        return err(format!("{what} must be finite, not {x}"));
    }
    Ok(x)
}

/// A finite number from an integer or a float, with the argument's name built only
/// when the value is refused (hot paths call this per array element).
fn num_at(v: &Dynamic, what: &str, i: usize) -> ScriptResult<f64> {
    let x = match v.as_float() {
        Ok(f) => f,
        Err(_) => match v.as_int() {
            Ok(i) => i as f64,
            Err(_) => return num(v, &format!("{what}[{i}]")),
        },
    };
    if x.is_finite() {
        Ok(x)
    } else {
        num(v, &format!("{what}[{i}]"))
    }
}

/// Fills `out` from an array of exactly `out.len()` numbers (no allocation).
pub fn numbers_into(v: &Dynamic, out: &mut [f64], what: &str) -> ScriptResult<()> {
    let n = out.len();
    let arr = v.read_lock::<Array>().ok_or_else(|| {
        fail(format!(
            "{what} must be an array of {n} numbers, not {}",
            v.type_name()
        ))
    })?;
    if arr.len() != n {
        return err(format!(
            "{what} must have {n} numbers, it has {}",
            arr.len()
        ));
    }
    for (i, (x, o)) in arr.iter().zip(out.iter_mut()).enumerate() {
        *o = num_at(x, what, i)?;
    }
    Ok(())
}

/// A list of `n` numbers.
pub fn numbers(v: &Dynamic, n: usize, what: &str) -> ScriptResult<Vec<f64>> {
    let mut out = vec![0.0; n];
    numbers_into(v, &mut out, what)?;
    Ok(out)
}

/// A vector from `[x, y, z]`.
pub fn vec3(v: &Dynamic, what: &str) -> ScriptResult<Vec3> {
    let mut n = [0.0; 3];
    numbers_into(v, &mut n, what)?;
    Ok(Vec3::new(n[0], n[1], n[2]))
}

/// A point from `[x, y, z]` (mm).
pub fn point3(v: &Dynamic, what: &str) -> ScriptResult<Point3> {
    Ok(vec3(v, what)?.into())
}

/// `[x, y, z]` as a Rhai array.
pub fn array3(v: &Vec3) -> Dynamic {
    floats(v.iter().copied())
}

/// Numbers as a Rhai array of floats.
pub fn floats(v: impl IntoIterator<Item = f64>) -> Dynamic {
    Dynamic::from_array(v.into_iter().map(Dynamic::from_float).collect())
}

/// A box as the script type `Box` (properties `min`, `max`, …; no map allocated).
pub fn box_value(b: &crate::math::Aabb) -> Dynamic {
    Dynamic::from(*b)
}

/// A box from a script value: a `Box`, or a map `#{min: [x,y,z], max: [x,y,z]}` (mm).
pub fn to_box(v: &Dynamic, what: &str) -> ScriptResult<crate::math::Aabb> {
    if let Some(b) = v.clone().try_cast::<crate::math::Aabb>() {
        return Ok(b);
    }
    let m = v.read_lock::<Map>().ok_or_else(|| {
        fail(format!(
            "{what} must be a Box or #{{min: [x,y,z], max: [x,y,z]}}"
        ))
    })?;
    let lo = vec3(
        m.get("min")
            .ok_or_else(|| fail(format!("{what} needs `min`")))?,
        &format!("{what}.min"),
    )?;
    let hi = vec3(
        m.get("max")
            .ok_or_else(|| fail(format!("{what} needs `max`")))?,
        &format!("{what}.max"),
    )?;
    Ok(crate::math::Aabb::new(lo, hi))
}

/// How a `Box` prints: `#{min: [x, y, z], max: [x, y, z]}` with every digit (mm).
pub fn box_text(b: &crate::math::Aabb) -> String {
    let v = |p: &crate::math::Point3| format!("[{:?}, {:?}, {:?}]", p.x, p.y, p.z);
    format!("#{{min: {}, max: {}}}", v(&b.lo), v(&b.hi))
}

/// An optional numeric field of an options map.
pub fn opt_num(map: &Map, key: &str) -> ScriptResult<Option<f64>> {
    map.get(key).map(|v| num(v, key)).transpose()
}

/// An optional string field of an options map.
pub fn opt_str(map: &Map, key: &str) -> ScriptResult<Option<String>> {
    match map.get(key) {
        None => Ok(None),
        Some(v) => v
            .clone()
            .into_string()
            .map(Some)
            .map_err(|t| fail(format!("option `{key}` must be a string, not {t}"))),
    }
}

/// The options map of an output writer (`save_csv(file, #{overwrite: true})`):
/// whether it may replace an existing file (see "What a run writes" in
/// docs/scripting.md).
pub fn overwrite_option(map: &Map, what: &str) -> ScriptResult<bool> {
    check_keys(map, &["overwrite"], what)?;
    match map.get("overwrite") {
        None => Ok(false),
        Some(v) => v
            .as_bool()
            .map_err(|t| fail(format!("option `overwrite` must be true or false, not {t}"))),
    }
}

/// Refuses keys that are not in `known` (a typo in an option name is an error, not a
/// silent default).
pub fn check_keys(map: &Map, known: &[&str], what: &str) -> ScriptResult<()> {
    for k in map.keys() {
        if !known.contains(&k.as_str()) {
            let hint = crate::diagnostics::suggestion(k, known.iter().copied());
            return err(format!("unknown {what} option `{k}`: {hint}"));
        }
    }
    Ok(())
}

/// How [`json_value`] reads a script value and words a refusal.
pub(crate) struct JsonRule<'a> {
    /// Whether a character is a string and a Transform its 4×4 matrix (data files);
    /// otherwise both are refused (option values).
    pub loose: bool,
    /// The message for a number JSON cannot spell, from the value's path and the number.
    pub non_finite: &'a dyn Fn(&str, f64) -> String,
    /// The message for a value of another type, from the path and the type name.
    pub other: &'a dyn Fn(&str, &str) -> String,
}

/// A script value as JSON: `()` is null; booleans, numbers, strings, arrays and maps as
/// themselves (elements at `path[i]`, entries at `path.key`); characters and
/// Transforms as `rule` says; anything else refused with `rule`'s message.
pub(crate) fn json_value(
    v: &Dynamic,
    path: &str,
    rule: &JsonRule,
) -> ScriptResult<serde_json::Value> {
    use serde_json::Value;
    if v.is_unit() {
        return Ok(Value::Null);
    }
    if let Ok(b) = v.as_bool() {
        return Ok(Value::Bool(b));
    }
    if let Ok(i) = v.as_int() {
        return Ok(Value::from(i));
    }
    if let Ok(x) = v.as_float() {
        return serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| fail((rule.non_finite)(path, x)));
    }
    if v.is_string() || (rule.loose && v.is_char()) {
        return Ok(Value::String(v.to_string()));
    }
    if let Some(a) = v.read_lock::<Array>() {
        return a
            .iter()
            .enumerate()
            .map(|(i, x)| json_value(x, &format!("{path}[{i}]"), rule))
            .collect::<ScriptResult<Vec<_>>>()
            .map(Value::Array);
    }
    if let Some(m) = v.read_lock::<Map>() {
        let mut out = serde_json::Map::new();
        for (k, x) in m.iter() {
            out.insert(k.to_string(), json_value(x, &format!("{path}.{k}"), rule)?);
        }
        return Ok(Value::Object(out));
    }
    if let (true, Some(t)) = (rule.loose, v.read_lock::<crate::math::Transform>()) {
        return Ok(Value::Array(
            t.to_matrix()
                .iter()
                .map(|r| Value::Array(r.iter().map(|x| Value::from(*x)).collect()))
                .collect(),
        ));
    }
    err((rule.other)(path, v.type_name()))
}

/// A script value as JSON, for an options vocabulary: numbers, booleans, strings,
/// arrays, maps; `()` is absent (null). `path` names the key in messages.
fn json_of(v: &Dynamic, request: &str, path: &str, kind: &str) -> ScriptResult<serde_json::Value> {
    json_value(
        v,
        path,
        &JsonRule {
            loose: false,
            non_finite: &|path, x| format!("{request} option `{path}` must be finite, not {x}"),
            other: &|path, t| format!("{request} option `{path}` must be {kind}, not {t}"),
        },
    )
}

/// A script options map as the JSON map of `vocabulary`: poses (Transforms,
/// `[x, y, z, a, b, c]`, 4×4 matrices) and boxes (`Box`, `#{min, max}`) converted the
/// way every script argument is, nested switches (`narrow`) recursively, the rest
/// as plain values. Keys are not checked here: the vocabulary does that.
fn options_json(
    map: &Map,
    vocabulary: &crate::options::Vocabulary,
    prefix: &str,
) -> ScriptResult<serde_json::Map<String, serde_json::Value>> {
    use crate::options::{box_value, pose_value, Kind};
    let mut out = serde_json::Map::new();
    for (k, v) in map.iter() {
        let path = format!("{prefix}{k}");
        let key = vocabulary.key_for(k);
        let phrase = key.map_or_else(|| "a value".to_string(), |k| k.kind.phrase());
        let value = match key.map(|k| k.kind) {
            _ if v.is_unit() => serde_json::Value::Null,
            Some(Kind::Pose) => pose_value(&super::bind_math::to_transform(v, &path)?),
            Some(Kind::Box) => box_value(&to_box(v, &path)?),
            Some(Kind::Switch(nested)) if v.is_map() => serde_json::Value::Object(options_json(
                &v.read_lock::<Map>().expect("a map"),
                nested,
                &format!("{path}."),
            )?),
            _ => json_of(v, vocabulary.request, &path, &phrase)?,
        };
        out.insert(k.to_string(), value);
    }
    Ok(out)
}

/// The options `T` of a script's options map, by `T`'s vocabulary (one table for
/// Rhai and Python: unknown keys with close matches, values against their kind);
/// a deprecated key's warning goes to `warn`.
pub fn read_options<T: crate::options::Options>(map: &Map, warn: &dyn Fn(&str)) -> ScriptResult<T> {
    let json = options_json(map, T::VOCABULARY, "")?;
    let parsed = T::from_value(serde_json::Value::Object(json)).map_err(fail)?;
    for w in &parsed.warnings {
        warn(&format!("warning: {w}"));
    }
    Ok(parsed.options)
}
