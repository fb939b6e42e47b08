//! A deterministic value as a study's `[fixed]` table or `simulate --set` gives it: a number,
//! a Boolean or a text. Which FMI type it becomes is decided by the variable it is set on
//! (by the study's interface to the FMU): a Real takes a number, an Integer or Enumeration a whole
//! number, a Boolean `true`/`false` (or 1/0), a String a text; a text given for a Real,
//! Integer, Enumeration or Boolean variable is parsed as such (that is how `--set NAME=VALUE`
//! arrives).

use std::fmt;

use serde::{Deserialize, Serialize};

/// A deterministic value: serialized as the bare TOML/JSON value (a number stays a number, so
/// study hashes and `summary.json` of studies with numbers only are what they were).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum FixedValue {
    /// `true` / `false`.
    Bool(bool),
    /// A number (TOML integers arrive here too).
    Number(f64),
    /// A text (a String variable's value, or a value still to be parsed for its variable).
    Text(String),
}

impl FixedValue {
    /// Whether the value is usable: numbers must be finite.
    pub fn is_finite(&self) -> bool {
        match self {
            FixedValue::Number(v) => v.is_finite(),
            _ => true,
        }
    }

    /// The number, if it is one.
    pub fn as_number(&self) -> Option<f64> {
        match self {
            FixedValue::Number(v) => Some(*v),
            _ => None,
        }
    }
}

impl From<f64> for FixedValue {
    fn from(v: f64) -> Self {
        FixedValue::Number(v)
    }
}

impl From<bool> for FixedValue {
    fn from(v: bool) -> Self {
        FixedValue::Bool(v)
    }
}

impl From<&str> for FixedValue {
    fn from(v: &str) -> Self {
        FixedValue::Text(v.to_owned())
    }
}

impl fmt::Display for FixedValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FixedValue::Bool(b) => write!(f, "{b}"),
            FixedValue::Number(v) => write!(f, "{v}"),
            FixedValue::Text(s) => write!(f, "{s:?}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn toml_values_of_every_kind_deserialize() {
        let m: BTreeMap<String, FixedValue> =
            toml::from_str("a = 1\nb = 2.5\nc = true\nd = \"track.csv\"\n").unwrap();
        assert_eq!(m["a"], FixedValue::Number(1.0));
        assert_eq!(m["b"], FixedValue::Number(2.5));
        assert_eq!(m["c"], FixedValue::Bool(true));
        assert_eq!(m["d"], FixedValue::Text("track.csv".into()));
    }

    #[test]
    fn numbers_serialize_as_bare_numbers() {
        // The study hash of a study with numbers only must not change.
        let mut m = BTreeMap::new();
        m.insert("h", FixedValue::Number(0.001));
        m.insert("n", FixedValue::Number(3.0));
        let plain: BTreeMap<&str, f64> = [("h", 0.001), ("n", 3.0)].into_iter().collect();
        assert_eq!(
            serde_json::to_string(&m).unwrap(),
            serde_json::to_string(&plain).unwrap()
        );
    }
}
