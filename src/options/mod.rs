//! One vocabulary per request: the keys an options map (Rhai) or keyword arguments
//! (Python) may hold, with their type, unit, default and meaning, and the plain Rust
//! struct they fill.
//!
//! Each request's options are a `serde` struct ([`Plan`], [`Check`], [`Sweep`],
//! [`Sequence`], [`Motion`], [`Drill`]) with `deny_unknown_fields`, a [`Default`] impl that holds every
//! default (taken from the library's own request types) and a [`Vocabulary`]: the one
//! table of its keys. The faces only turn their values into JSON ([`serde_json::Value`];
//! poses and boxes through [`pose_value`] and [`box_value`]) and call
//! [`Options::from_value`], which checks every key against the table — unknown keys
//! with close matches, values against their [`Kind`], deprecated spellings renamed
//! with a warning — and deserializes. `fitup docs` prints the same tables into
//! docs/api.md ([`Vocabulary::markdown`]), as ripgrep generates its help from one flag
//! table. Ranges are not checked here: each request's `validate` (the planners',
//! [`SequenceOptions`](crate::sequence::SequenceOptions)', …) is the one rule.
//!
//! Units: millimetres inside, and the unit of every key is in its table. Angles
//! are **degrees** where the key's name says so (`edge_step_deg`, `max_turn_deg`,
//! `max_tilt_deg`, speeds in deg/s): they are converted to radians when the request
//! is built, so the Rust request types stay in radians.
//!
//! # Examples
//!
//! ```
//! use fitup::options::{Options, Plan};
//! let parsed = Plan::from_value(serde_json::json!({"seed": 3, "tolerance": 0.02})).unwrap();
//! assert_eq!(parsed.options.seed, 3);
//! let e = Plan::from_value(serde_json::json!({"sede": 3})).unwrap_err();
//! assert!(e.to_string().contains("did you mean `seed`"), "{e}");
//! ```

mod check;
#[cfg(feature = "db")]
mod db;
mod mate;
mod motion;
mod plan;
mod sequence;

pub use check::{Check, Sweep};
#[cfg(feature = "db")]
pub use db::{Limits, PathFilter};
pub use mate::AddMate;
pub use motion::{Drill, Motion};
pub use plan::{Narrow, NarrowSwitch, Plan};
pub use sequence::Sequence;

use crate::math::{Aabb, Transform};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::{Map, Value};

/// The values a key takes (what the faces convert to, and what the docs print).
#[derive(Debug, Clone, Copy)]
pub enum Kind {
    /// A finite number (an integer is accepted).
    Number,
    /// A whole number ≥ 0 (a whole float such as `1e5` is accepted).
    Count,
    /// `true` or `false`.
    Bool,
    /// Text.
    Text,
    /// One of the given names.
    Choice(&'static [&'static str]),
    /// An array of names.
    Names,
    /// Three numbers `[x, y, z]`.
    Vector,
    /// A box (faces: a Rhai `Box` or `#{min, max}`, Python `[[min xyz], [max xyz]]`);
    /// inside, [`box_value`]'s form.
    Box,
    /// A pose (faces: a Rhai Transform or `[x, y, z, a, b, c]`, Python a 4×4 array);
    /// inside, [`pose_value`]'s form.
    Pose,
    /// A map of name → number.
    NumberMap,
    /// `true` (the defaults), `false` (off) or a map of the nested vocabulary.
    Switch(&'static Vocabulary),
}

impl Kind {
    /// The kind's name: `number`, `count`, `bool`, `text`, `choice`, `names`,
    /// `vector`, `box`, `pose`, `number_map` or `switch` (for tools and tests that
    /// walk a vocabulary).
    pub fn name(&self) -> &'static str {
        match self {
            Kind::Number => "number",
            Kind::Count => "count",
            Kind::Bool => "bool",
            Kind::Text => "text",
            Kind::Choice(_) => "choice",
            Kind::Names => "names",
            Kind::Vector => "vector",
            Kind::Box => "box",
            Kind::Pose => "pose",
            Kind::NumberMap => "number_map",
            Kind::Switch(_) => "switch",
        }
    }

    /// What a value of this kind is, for messages: "a number", "true or false", ….
    pub fn phrase(&self) -> String {
        match self {
            Kind::Number => "a number".into(),
            Kind::Count => "a whole number ≥ 0".into(),
            Kind::Bool => "true or false".into(),
            Kind::Text => "a string".into(),
            Kind::Choice(names) => format!("one of {}", quoted(names)),
            Kind::Names => "an array of names".into(),
            Kind::Vector => "3 numbers [x, y, z]".into(),
            Kind::Box => "a box (min below max on every axis)".into(),
            Kind::Pose => "a pose".into(),
            Kind::NumberMap => "a map of name: number".into(),
            Kind::Switch(v) => format!(
                "true, false or a map of {}",
                quoted(&v.keys.iter().map(|k| k.name).collect::<Vec<_>>())
            ),
        }
    }

    /// The type column of the reference (the script face's words).
    pub fn type_name(&self) -> String {
        match self {
            Kind::Number => "number".into(),
            Kind::Count => "int ≥ 0".into(),
            Kind::Bool => "bool".into(),
            Kind::Text => "string".into(),
            Kind::Choice(names) => names
                .iter()
                .map(|n| format!("`\"{n}\"`"))
                .collect::<Vec<_>>()
                .join(" or "),
            Kind::Names => "array of names".into(),
            Kind::Vector => "`[x, y, z]`".into(),
            Kind::Box => "`Box` or `#{min, max}`".into(),
            Kind::Pose => "Transform or `[x, y, z, a, b, c]`".into(),
            Kind::NumberMap => "map name: number".into(),
            Kind::Switch(_) => "bool or map (below)".into(),
        }
    }
}

fn quoted(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// One key of a vocabulary.
#[derive(Debug, Clone, Copy)]
pub struct Key {
    /// The key, as scripts and Python keywords spell it (the struct's field name).
    pub name: &'static str,
    /// Its values.
    pub kind: Kind,
    /// Its unit ("mm", "deg", "ms", "mm/s", …; "" for none).
    pub unit: &'static str,
    /// What it does.
    pub meaning: &'static str,
    /// The default in words where the struct's default is not a value (`None`:
    /// "derived from the problem", "the planner's default"); `None` here prints the
    /// `Default` impl's value.
    pub default: Option<&'static str>,
}

/// An old spelling of a key, accepted for one release with a warning.
#[derive(Debug, Clone, Copy)]
pub struct Deprecated {
    /// The old key.
    pub old: &'static str,
    /// The key that replaces it.
    pub new: &'static str,
    /// Factor from the old value to the new one (e.g. radians → degrees); 1 for a
    /// plain rename.
    pub scale: f64,
    /// The release after which the old key is refused.
    pub until: &'static str,
}

/// The keys of one request: the one table the faces, the docs and the tests read.
#[derive(Debug, Clone, Copy)]
pub struct Vocabulary {
    /// The request's name in messages ("planning", "interference", …).
    pub request: &'static str,
    /// Its keys, in the order the reference lists them.
    pub keys: &'static [Key],
    /// Old spellings still accepted.
    pub deprecated: &'static [Deprecated],
}

/// Why an options map is refused. Ranges are the requests' own errors; these are
/// names and types.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OptionError {
    /// A key the request does not take.
    #[error("unknown {request} option `{key}`: {hint}")]
    Unknown {
        /// The request ("planning", …).
        request: &'static str,
        /// The key given (`narrow.max_turn` for a nested one).
        key: String,
        /// Close matches or the keys that exist.
        hint: String,
    },
    /// A command-line option text without `=` (`--option KEY=VALUE`).
    #[error("`{arg}`: expected KEY=VALUE (keys: {})", .keys.join(", "))]
    NotKeyValue {
        /// The text given.
        arg: String,
        /// The keys of the request.
        keys: Vec<&'static str>,
    },
    /// A value that is not of the key's kind.
    #[error("{request} option `{key}` must be {expected}, not {value}")]
    Value {
        /// The request.
        request: &'static str,
        /// The key.
        key: String,
        /// The value given, shortened.
        value: String,
        /// What the key takes, with its unit.
        expected: String,
    },
    /// Options that are not a map.
    #[error("{request} options must be a map of key: value, not {}", shown(.value))]
    NotAMap {
        /// The request.
        request: &'static str,
        /// What was given.
        value: Value,
    },
    /// A deprecated key given with the key that replaces it.
    #[error("{request} options `{old}` and `{new}` are the same option: give only `{new}`")]
    Both {
        /// The request.
        request: &'static str,
        /// The deprecated key.
        old: &'static str,
        /// The key that replaces it.
        new: &'static str,
    },
    /// The checked map still did not fit the struct (a vocabulary that disagrees
    /// with its struct: a bug the vocabulary tests catch).
    #[error("{request} options: {source}")]
    Internal {
        /// The request.
        request: &'static str,
        /// serde's error.
        #[source]
        source: crate::files::JsonError,
    },
}

/// Options read from a map, with the warnings for deprecated keys.
#[derive(Debug, Clone, PartialEq)]
pub struct Parsed<T> {
    /// The options.
    pub options: T,
    /// One line per deprecated key used ("`edge_step_rad` is deprecated: …").
    pub warnings: Vec<String>,
}

/// `text` read as a value of `kind` (see [`Vocabulary::map_from_args`]); `None`
/// when it does not read as one.
fn text_value(kind: &Kind, text: &str) -> Option<Value> {
    let number = |t: &str| t.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    let list = |t: &str| -> Vec<String> {
        t.split(',')
            .map(|x| x.trim().to_string())
            .filter(|x| !x.is_empty())
            .collect()
    };
    Some(match kind {
        Kind::Number => serde_json::json!(number(text)?),
        Kind::Count => {
            let v = number(text)?;
            if v >= 0.0 && v.fract() == 0.0 && v < 9.0e15 {
                serde_json::json!(v as u64)
            } else {
                serde_json::json!(v)
            }
        }
        Kind::Bool => Value::Bool(text.parse().ok()?),
        Kind::Text | Kind::Choice(_) => Value::String(text.to_string()),
        Kind::Names => serde_json::json!(list(text)),
        Kind::Vector => {
            let v = list(text)
                .iter()
                .map(|x| number(x))
                .collect::<Option<Vec<f64>>>()?;
            serde_json::json!(v)
        }
        Kind::NumberMap => {
            let mut m = Map::new();
            for pair in list(text) {
                let (k, v) = pair.split_once('=')?;
                m.insert(k.trim().to_string(), serde_json::json!(number(v)?));
            }
            Value::Object(m)
        }
        Kind::Box | Kind::Pose | Kind::Switch(_) => serde_json::from_str(text).ok()?,
    })
}

/// A value for messages: JSON text, at most 60 characters.
fn shown(v: &Value) -> String {
    crate::diagnostics::shorten(&v.to_string(), 60)
}

impl Vocabulary {
    /// Command-line `KEY=VALUE` texts (`fitup plan-sequence --option …`) as the map
    /// [`Options::from_value`] reads, so that every key of the table is reachable
    /// from the command line as from scripts and Python. Each value is read by its
    /// key's kind: a number, `true`/`false`, names or numbers separated by commas
    /// (`a,b`; `x,y,z`), `name=number` pairs separated by commas, JSON for boxes,
    /// poses and switches; a value that does not read as its kind is passed as text,
    /// and a key outside the table as it is (the check then refuses either by name).
    ///
    /// # Errors
    /// [`OptionError::NotKeyValue`]: a text without `=`.
    pub fn map_from_args(&self, args: &[String]) -> Result<Map<String, Value>, OptionError> {
        let mut map = Map::new();
        for arg in args {
            let Some((key, text)) = arg.split_once('=') else {
                return Err(OptionError::NotKeyValue {
                    arg: arg.clone(),
                    keys: self.keys.iter().map(|k| k.name).collect(),
                });
            };
            let (key, text) = (key.trim(), text.trim());
            let value = self
                .key(key)
                .and_then(|k| text_value(&k.kind, text))
                .unwrap_or_else(|| Value::String(text.to_string()));
            map.insert(key.to_string(), value);
        }
        Ok(map)
    }

    /// The key called `name`.
    pub fn key(&self, name: &str) -> Option<&'static Key> {
        self.keys.iter().find(|k| k.name == name)
    }

    /// The key names, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.keys.iter().map(|k| k.name).collect()
    }

    /// The key a face should convert `name`'s value for: the key itself, or the key a
    /// deprecated spelling stands for.
    pub fn key_for(&self, name: &str) -> Option<&'static Key> {
        self.key(name).or_else(|| {
            self.deprecated
                .iter()
                .find(|d| d.old == name)
                .and_then(|d| self.key(d.new))
        })
    }

    /// Checks `map` against the table and puts it in the struct's form: unknown keys
    /// refused with close matches, null values (Python's `None`, Rhai's `()`)
    /// dropped as absent, deprecated keys renamed (and scaled) with a warning each, every
    /// value checked against its kind (whole floats of count keys made integers).
    /// `prefix` is the path of a nested map (`"narrow."`), empty at the top.
    ///
    /// # Errors
    /// [`OptionError`] naming the first key refused.
    pub fn check(
        &self,
        map: &mut Map<String, Value>,
        prefix: &str,
    ) -> Result<Vec<String>, OptionError> {
        if let Some(name) = map
            .keys()
            .find(|k| self.key(k).is_none() && !self.deprecated.iter().any(|d| d.old == *k))
        {
            let mut known = self.names();
            known.extend(self.deprecated.iter().map(|d| d.old));
            return Err(OptionError::Unknown {
                request: self.request,
                key: format!("{prefix}{name}"),
                hint: crate::diagnostics::suggestion(name, known),
            });
        }
        map.retain(|_, v| !v.is_null());
        let mut warnings = Vec::new();
        for d in self.deprecated {
            let Some(v) = map.remove(d.old) else {
                continue;
            };
            if map.contains_key(d.new) {
                return Err(OptionError::Both {
                    request: self.request,
                    old: d.old,
                    new: d.new,
                });
            }
            let unit = self.key(d.new).map_or("", |k| k.unit);
            warnings.push(format!(
                "{} option `{prefix}{}` is deprecated and will be refused after {}: use `{prefix}{}`{}",
                self.request,
                d.old,
                d.until,
                d.new,
                if d.scale == 1.0 {
                    String::new()
                } else {
                    format!(" ({unit}; the value is converted)")
                }
            ));
            let v = match v.as_f64() {
                Some(x) if d.scale != 1.0 => serde_json::Number::from_f64(x * d.scale)
                    .map(Value::Number)
                    .unwrap_or(v),
                _ => v,
            };
            map.insert(d.new.to_string(), v);
        }
        for (name, value) in map.iter_mut() {
            let Some(key) = self.key(name) else {
                continue; // renamed above: not reached
            };
            let path = format!("{prefix}{name}");
            warnings.extend(check_value(self.request, key, &path, value)?);
        }
        Ok(warnings)
    }

    /// The reference table of the keys (Markdown): key, type, unit, default, meaning.
    /// `defaults` is the struct's [`Default`] as JSON ([`Options::defaults`]).
    pub fn markdown(&self, defaults: &Map<String, Value>) -> String {
        let mut out =
            String::from("| key | type | unit | default | meaning |\n|---|---|---|---|---|\n");
        for k in self.keys {
            let default = match k.default {
                Some(text) => text.to_string(),
                None => default_text(defaults.get(k.name).unwrap_or(&Value::Null)),
            };
            out += &format!(
                "| `{}` | {} | {} | {} | {} |\n",
                k.name,
                k.kind.type_name(),
                k.unit,
                default,
                k.meaning
            );
        }
        for d in self.deprecated {
            out += &format!(
                "| `{}` | deprecated | | | the old spelling of `{}`{}, accepted with a warning until {} |\n",
                d.old,
                d.new,
                if d.scale == 1.0 { "" } else { " (its old unit, converted)" },
                d.until
            );
        }
        out
    }
}

/// A default value as the reference prints it.
fn default_text(v: &Value) -> String {
    match v {
        Value::Null => "none".into(),
        Value::String(s) => format!("`\"{s}\"`"),
        Value::Array(a) if a.is_empty() => "`[]`".into(),
        Value::Object(m) if m.is_empty() => "`#{}`".into(),
        Value::Number(n) => match n.as_f64() {
            // Round-trip noise of unit conversions (0.1° as radians and back).
            Some(x) if n.is_f64() => format!("{}", (x * 1e9).round() / 1e9),
            _ => n.to_string(),
        },
        other => format!("`{other}`"),
    }
}

/// Checks one value against its key's kind (see [`Vocabulary::check`]).
fn check_value(
    request: &'static str,
    key: &Key,
    path: &str,
    value: &mut Value,
) -> Result<Vec<String>, OptionError> {
    let bad = |value: &Value| OptionError::Value {
        request,
        key: path.to_string(),
        value: shown(value),
        expected: if key.unit.is_empty() {
            key.kind.phrase()
        } else {
            format!("{} ({})", key.kind.phrase(), key.unit)
        },
    };
    let numbers = |v: &Value, n: usize| {
        v.as_array()
            .is_some_and(|a| a.len() == n && a.iter().all(Value::is_number))
    };
    let ok = match key.kind {
        Kind::Number => value.is_number(),
        Kind::Count => match value.as_f64() {
            _ if value.is_u64() => true,
            Some(x) if x >= 0.0 && x.fract() == 0.0 && x <= 9.007_199_254_740_992e15 => {
                *value = Value::from(x as u64);
                true
            }
            _ => false,
        },
        Kind::Bool => value.is_boolean(),
        Kind::Text => value.is_string(),
        Kind::Choice(names) => match value.as_str() {
            Some(s) if names.contains(&s) => true,
            Some(s) => {
                return Err(OptionError::Value {
                    request,
                    key: path.to_string(),
                    value: shown(value),
                    expected: format!(
                        "{} ({})",
                        key.kind.phrase(),
                        crate::diagnostics::suggestion(s, names.iter().copied())
                    ),
                })
            }
            None => false,
        },
        Kind::Names => value
            .as_array()
            .is_some_and(|a| a.iter().all(Value::is_string)),
        Kind::Vector => numbers(value, 3),
        Kind::Box => value.as_object().is_some_and(|m| {
            let (Some(lo), Some(hi)) = (m.get("lo"), m.get("hi")) else {
                return false;
            };
            numbers(lo, 3)
                && numbers(hi, 3)
                && (0..3).all(|i| lo[i].as_f64() < hi[i].as_f64())
                && m.len() == 2
        }),
        Kind::Pose => value
            .as_array()
            .is_some_and(|rows| rows.len() == 4 && rows.iter().all(|r| numbers(r, 4))),
        Kind::NumberMap => value
            .as_object()
            .is_some_and(|m| m.values().all(Value::is_number)),
        Kind::Switch(nested) => match value {
            Value::Bool(_) => true,
            Value::Object(m) => return nested.check(m, &format!("{path}.")),
            _ => false,
        },
    };
    if ok {
        Ok(Vec::new())
    } else {
        Err(bad(value))
    }
}

/// A request's options: a `serde` struct with its [`Vocabulary`].
pub trait Options: Default + Serialize + DeserializeOwned {
    /// The table of its keys.
    const VOCABULARY: &'static Vocabulary;

    /// Reads options from a JSON map (what the faces convert their values to).
    ///
    /// # Errors
    /// [`OptionError`]: not a map, an unknown key, a value not of its key's kind.
    fn from_value(value: Value) -> Result<Parsed<Self>, OptionError> {
        let request = Self::VOCABULARY.request;
        let Value::Object(mut map) = value else {
            return Err(OptionError::NotAMap { request, value });
        };
        let warnings = Self::VOCABULARY.check(&mut map, "")?;
        let options =
            serde_json::from_value(Value::Object(map)).map_err(|e| OptionError::Internal {
                request,
                source: e.into(),
            })?;
        Ok(Parsed { options, warnings })
    }

    /// The defaults as JSON (what the reference prints).
    fn defaults() -> Map<String, Value> {
        match serde_json::to_value(Self::default()) {
            Ok(Value::Object(m)) => m,
            _ => Map::new(),
        }
    }

    /// The reference table of the keys ([`Vocabulary::markdown`]).
    fn markdown() -> String {
        Self::VOCABULARY.markdown(&Self::defaults())
    }
}

/// A pose as the options read it: the rows of [`Transform::to_matrix`] (mm).
pub fn pose_value(t: &Transform) -> Value {
    Value::from(
        t.to_matrix()
            .iter()
            .map(|r| Value::from(r.to_vec()))
            .collect::<Vec<_>>(),
    )
}

/// A box as the options read it (the serde form of [`Aabb`], mm).
pub fn box_value(b: &Aabb) -> Value {
    serde_json::to_value(b).unwrap_or(Value::Null)
}

/// `serde` of an optional pose in [`pose_value`]'s form.
pub(crate) mod serde_pose {
    use crate::math::Transform;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(t: &Option<Transform>, s: S) -> Result<S::Ok, S::Error> {
        match t {
            None => s.serialize_none(),
            Some(t) => s.serialize_some(&t.to_matrix()),
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Transform>, D::Error> {
        Option::<[[f64; 4]; 4]>::deserialize(d)?
            .map(|m| Transform::from_matrix(&m).map_err(serde::de::Error::custom))
            .transpose()
    }
}

/// Every vocabulary, for the key-set tests and tools.
pub fn vocabularies() -> Vec<&'static Vocabulary> {
    vec![
        Plan::VOCABULARY,
        Narrow::VOCABULARY,
        Check::VOCABULARY,
        Sweep::VOCABULARY,
        Sequence::VOCABULARY,
        Motion::VOCABULARY,
        Drill::VOCABULARY,
        AddMate::VOCABULARY,
        #[cfg(feature = "db")]
        PathFilter::VOCABULARY,
        #[cfg(feature = "db")]
        Limits::VOCABULARY,
    ]
}

/// The vocabulary of the request called `request` ("planning", "sequence", …).
pub fn vocabulary(request: &str) -> Option<&'static Vocabulary> {
    vocabularies().into_iter().find(|v| v.request == request)
}

/// The field names `T`'s `Deserialize` asks for: read from serde itself, so a test can
/// hold a vocabulary to its struct.
pub fn struct_fields<T: DeserializeOwned>() -> Vec<&'static str> {
    struct Fields(Vec<&'static str>);
    #[derive(Debug)]
    struct Stop;
    impl std::fmt::Display for Stop {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("stop")
        }
    }
    impl std::error::Error for Stop {}
    impl serde::de::Error for Stop {
        fn custom<M: std::fmt::Display>(_: M) -> Self {
            Stop
        }
    }
    impl<'de> serde::Deserializer<'de> for &mut Fields {
        type Error = Stop;
        fn deserialize_any<V: serde::de::Visitor<'de>>(self, _: V) -> Result<V::Value, Stop> {
            Err(Stop)
        }
        fn deserialize_struct<V: serde::de::Visitor<'de>>(
            self,
            _: &'static str,
            fields: &'static [&'static str],
            _: V,
        ) -> Result<V::Value, Stop> {
            self.0 = fields.to_vec();
            Err(Stop)
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
            bytes byte_buf option unit unit_struct newtype_struct seq tuple
            tuple_struct map enum identifier ignored_any
        }
    }
    let mut f = Fields(Vec::new());
    let _ = T::deserialize(&mut f);
    f.0
}

#[cfg(test)]
mod tests;
