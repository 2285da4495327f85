//! Script arguments: `fitup run SCRIPT -- key=value …` becomes the map `args` in the
//! script, so one script serves many problems.

use rhai::{Dynamic, Map};

/// The longest argument value accepted, in bytes (the sandbox's string limit is larger;
/// this keeps a pasted file out of the command line's purpose).
pub const MAX_ARGUMENT_BYTES: usize = 64 << 10;

/// One argument value, typed the way a user would expect from the text.
#[derive(Debug, Clone, PartialEq)]
pub enum ArgValue {
    /// A whole number (`n=3`).
    Int(i64),
    /// A finite decimal number (`clearance=0.1`, `x=1e-3`).
    Float(f64),
    /// `true` or `false`.
    Bool(bool),
    /// Anything else, as written (`part=screw4`, `name=角度1`).
    Text(String),
}

impl ArgValue {
    /// Types the value of `key`: integers, finite floats, `true`/`false`, else text.
    fn parse(key: &str, text: &str) -> Result<Self, ArgError> {
        if let Ok(i) = text.parse::<i64>() {
            return Ok(Self::Int(i));
        }
        match text {
            "true" => return Ok(Self::Bool(true)),
            "false" => return Ok(Self::Bool(false)),
            _ => {}
        }
        // Words Rust would read as floats ("inf", "NaN", "infinity") stay text; a
        // numeric literal out of range is an error, not a silent infinity or text.
        let numeric = text.bytes().any(|b| b.is_ascii_digit())
            && text
                .bytes()
                .all(|b| b.is_ascii_digit() || matches!(b, b'.' | b'e' | b'E' | b'+' | b'-'));
        match text.parse::<f64>() {
            Ok(x) if x.is_finite() && numeric => Ok(Self::Float(x)),
            Ok(_) if numeric => Err(ArgError::OutOfRange {
                key: shorten(key),
                value: shorten(text),
            }),
            _ => Ok(Self::Text(text.to_string())),
        }
    }

    fn to_dynamic(&self) -> Dynamic {
        match self {
            Self::Int(i) => Dynamic::from_int(*i),
            Self::Float(x) => Dynamic::from_float(*x),
            Self::Bool(b) => Dynamic::from_bool(*b),
            Self::Text(s) => s.clone().into(),
        }
    }
}

/// Why the script arguments are refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ArgError {
    /// An argument without `=`.
    #[error("script argument `{0}` is not `key=value` (e.g. `fast=true`)")]
    NotKeyValue(String),
    /// `=value` with nothing before it.
    #[error("script argument `{0}` has an empty key")]
    EmptyKey(String),
    /// The same key twice.
    #[error("script argument `{0}` is given twice")]
    Duplicate(String),
    /// A numeric value beyond the range of a number (`x=1e999`).
    #[error("script argument `{key}`: `{value}` is out of range for a number")]
    OutOfRange {
        /// The key.
        key: String,
        /// The value as written (shortened).
        value: String,
    },
    /// An argument longer than [`MAX_ARGUMENT_BYTES`].
    #[error(
        "script argument `{key}`: {bytes} bytes is longer than the {MAX_ARGUMENT_BYTES} allowed"
    )]
    TooLong {
        /// The key.
        key: String,
        /// The argument's length in bytes.
        bytes: usize,
    },
}

/// The arguments of one run, in the order given.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Arguments(Vec<(String, ArgValue)>);

impl Arguments {
    /// Parses `key=value` words (what follows `--` on the command line). Keys may be
    /// any non-empty text (use `args["my-key"]` for keys that are not identifiers);
    /// values are typed by [`ArgValue`]. Refuses words without `=`, empty keys,
    /// duplicate keys, out-of-range numbers and values over [`MAX_ARGUMENT_BYTES`].
    ///
    /// # Examples
    ///
    /// ```
    /// use fitup::script::{ArgValue, Arguments};
    /// let a = Arguments::parse(&["n=3", "gap=0.5", "part=screw4", "fast=true"]).unwrap();
    /// assert_eq!(a.get("n"), Some(&ArgValue::Int(3)));
    /// assert_eq!(a.get("gap"), Some(&ArgValue::Float(0.5)));
    /// assert!(Arguments::parse(&["n"]).is_err());
    /// ```
    pub fn parse<S: AsRef<str>>(words: &[S]) -> Result<Self, ArgError> {
        let mut out: Vec<(String, ArgValue)> = Vec::with_capacity(words.len());
        for word in words {
            let word = word.as_ref();
            let (key, value) = word
                .split_once('=')
                .ok_or_else(|| ArgError::NotKeyValue(shorten(word)))?;
            if key.trim().is_empty() {
                return Err(ArgError::EmptyKey(shorten(word)));
            }
            if out.iter().any(|(k, _)| k == key) {
                return Err(ArgError::Duplicate(shorten(key)));
            }
            if word.len() > MAX_ARGUMENT_BYTES {
                return Err(ArgError::TooLong {
                    key: shorten(key),
                    bytes: word.len(),
                });
            }
            out.push((key.to_string(), ArgValue::parse(key, value)?));
        }
        Ok(Self(out))
    }

    /// The value of `key`.
    pub fn get(&self, key: &str) -> Option<&ArgValue> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    /// Whether there are no arguments.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The map `args` a script sees.
    pub fn to_map(&self) -> Map {
        self.0
            .iter()
            .map(|(k, v)| (k.as_str().into(), v.to_dynamic()))
            .collect()
    }
}

/// A word cut to a readable length for messages.
fn shorten(s: &str) -> String {
    const MAX: usize = 60;
    if s.chars().count() <= MAX {
        s.to_string()
    } else {
        let head: String = s.chars().take(MAX).collect();
        format!("{head}… ({} characters)", s.chars().count())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_typed() {
        let a = Arguments::parse(&[
            "n=-3",
            "x=1e-3",
            "on=false",
            "s=screw4",
            "角度=30",
            "empty=",
            "eq=a=b",
            "w=inf",
            "v=1.2.3",
        ])
        .unwrap();
        assert_eq!(a.get("n"), Some(&ArgValue::Int(-3)));
        assert_eq!(a.get("x"), Some(&ArgValue::Float(1e-3)));
        assert_eq!(a.get("on"), Some(&ArgValue::Bool(false)));
        assert_eq!(a.get("s"), Some(&ArgValue::Text("screw4".into())));
        assert_eq!(a.get("角度"), Some(&ArgValue::Int(30)));
        assert_eq!(a.get("empty"), Some(&ArgValue::Text(String::new())));
        assert_eq!(a.get("eq"), Some(&ArgValue::Text("a=b".into())));
        assert_eq!(a.get("w"), Some(&ArgValue::Text("inf".into())));
        assert_eq!(a.get("v"), Some(&ArgValue::Text("1.2.3".into())));
        assert_eq!(a.to_map().len(), 9);
    }

    #[test]
    fn bad_arguments_are_refused_by_name() {
        assert_eq!(
            Arguments::parse(&["verbose"]),
            Err(ArgError::NotKeyValue("verbose".into()))
        );
        assert!(matches!(
            Arguments::parse(&["=1"]),
            Err(ArgError::EmptyKey(_))
        ));
        assert_eq!(
            Arguments::parse(&["n=1", "n=2"]),
            Err(ArgError::Duplicate("n".into()))
        );
        let e = Arguments::parse(&["x=1e400"]).unwrap_err().to_string();
        assert!(e.contains("`x`") && e.contains("out of range"), "{e}");
        assert!(Arguments::parse(&["y=-1e999"]).is_err());
        // Past i64, a whole number is still a number.
        assert_eq!(
            Arguments::parse(&["n=99999999999999999999999"])
                .unwrap()
                .get("n"),
            Some(&ArgValue::Float(1e23))
        );
        let long = format!("k={}", "x".repeat(MAX_ARGUMENT_BYTES));
        let e = Arguments::parse(&[long]).unwrap_err().to_string();
        assert!(e.contains("longer than"), "{e}");
        let long_key = format!("{}=1", "k".repeat(1000));
        let e = Arguments::parse(&[long_key.clone(), long_key])
            .unwrap_err()
            .to_string();
        assert!(
            e.len() < 200 && e.contains("1000 characters") && e.contains("twice"),
            "{e}"
        );
    }
}
