//! JSON input: a user's JSON document read into serde-derived types (`#[serde(deny_unknown_fields)]`)
//! with errors that name the JSON path of the offending field, say what was expected and what was
//! found, and suggest the closest known name for a misspelt field or type.
//!
//! ```
//! use serde::Deserialize;
//! #[derive(Deserialize)]
//! #[serde(deny_unknown_fields)]
//! struct Axis { direction: [f64; 3] }
//! #[derive(Deserialize)]
//! #[serde(deny_unknown_fields)]
//! struct File { axes: Vec<Axis> }
//!
//! let v = mte_linalg::json::parse(r#"{"axes": [{"direction": [1, 0, 0]}, {"dirction": [0, 1, 0]}]}"#).unwrap();
//! let e = mte_linalg::json::from_value::<File>(&v).err().unwrap();
//! assert_eq!(e.path, "axes[1].dirction");
//! assert!(e.message.contains("did you mean `direction`?"), "{}", e.message);
//! ```

use crate::text::{closest, levenshtein};
use serde::Deserialize;
use serde::de::{DeserializeOwned, Deserializer, Error as _};
use serde_json::Value;

/// A field that does not fit: its JSON path (`bodies[2].joint.direction`, empty for the root)
/// and what was expected and found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldError {
    /// JSON path of the offending field.
    pub path: String,
    /// What was expected and what was found.
    pub message: String,
}

/// Parses JSON text (a leading UTF-8 byte-order mark dropped) into a tree.
///
/// # Errors
/// The parser's error, with line and column, for malformed JSON (including numbers beyond the
/// range of `f64`, which JSON cannot carry as NaN or infinity).
pub fn parse(text: &str) -> Result<Value, serde_json::Error> {
    serde_json::from_str(text.strip_prefix('\u{feff}').unwrap_or(text))
}

/// The root's `format` tag, checked before anything else so that a file of another kind is
/// named as such rather than by its first unknown field.
///
/// # Errors
/// A [`FieldError`] at `format` (or the root when it is not an object).
pub fn check_format(root: &Value, format: &str) -> Result<(), FieldError> {
    let err = |path: &str, message: String| FieldError {
        path: path.into(),
        message,
    };
    match root {
        Value::Object(m) => match m.get("format") {
            Some(Value::String(f)) if f == format => Ok(()),
            Some(v) => Err(err(
                "format",
                format!("unsupported format {v} (expected \"{format}\")"),
            )),
            None => Err(err(
                "format",
                format!("missing field (expected \"{format}\")"),
            )),
        },
        v => Err(err(
            "",
            format!("expected an object, found {}", describe(v)),
        )),
    }
}

/// Deserialises `T` from `value`.
///
/// # Errors
/// A [`FieldError`] naming the path of the first field that does not fit.
pub fn from_value<T: DeserializeOwned>(value: &Value) -> Result<T, FieldError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let mut path = String::new();
        for seg in e.path().iter() {
            match seg {
                serde_path_to_error::Segment::Seq { index } => path += &format!("[{index}]"),
                serde_path_to_error::Segment::Map { key } => join(&mut path, key),
                serde_path_to_error::Segment::Enum { variant } => join(&mut path, variant),
                serde_path_to_error::Segment::Unknown => join(&mut path, "?"),
            }
        }
        let (sub, message) = reword(&e.into_inner().to_string());
        if let Some(sub) = sub {
            join(&mut path, &sub);
        }
        FieldError { path, message }
    })
}

/// An internally tagged object `{"type": "<variant>", …fields}` read as the externally tagged
/// enum `T` (`#[serde(rename_all = "snake_case")]`, one struct per variant), so that an error
/// inside the variant's fields keeps its path (serde's own `#[serde(tag = "type")]` buffers the
/// object and loses it). A variant without fields is written `Name {}`.
#[derive(Debug, Clone, PartialEq)]
pub struct Tagged<T>(pub T);

impl<'de, T: DeserializeOwned> Deserialize<'de> for Tagged<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let mut map = match Value::deserialize(d)? {
            Value::Object(m) => m,
            v => {
                let m = format!("expected an object, found {}", describe(&v));
                return Err(D::Error::custom(embed("", &m)));
            }
        };
        let tag = match map.remove("type") {
            Some(Value::String(s)) => s,
            Some(v) => {
                let m = format!("expected a string, found {}", describe(&v));
                return Err(D::Error::custom(embed("type", &m)));
            }
            None => return Err(D::Error::custom(embed("type", "missing field"))),
        };
        let external = Value::Object([(tag.clone(), Value::Object(map))].into_iter().collect());
        from_value(&external).map(Tagged).map_err(|e| {
            // the path starts with the variant; at the root, the variant is unknown: `type`
            let path = match e.path.strip_prefix(tag.as_str()) {
                _ if e.path.is_empty() => "type",
                Some(rest) => rest.trim_start_matches('.'),
                None => &e.path,
            };
            D::Error::custom(embed(path, &e.message))
        })
    }
}

/// How a JSON value is named in messages.
pub fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => format!("the boolean {b}"),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) => format!("the string {s:?}"),
        Value::Array(_) => "an array".into(),
        Value::Object(_) => "an object".into(),
    }
}

/// `"; did you mean `x`?"` with the known name closest to `name`, when it is close (at most half
/// of `name`'s characters differ), else nothing.
///
/// ```
/// let known = ["direction", "sign"];
/// assert_eq!(mte_linalg::json::did_you_mean("dirction", &known), "; did you mean `direction`?");
/// assert_eq!(mte_linalg::json::did_you_mean("Q", ["A", "C"]), "");
/// ```
pub fn did_you_mean<S: AsRef<str>>(name: &str, known: impl IntoIterator<Item = S>) -> String {
    match closest(name, known, 1).pop() {
        Some(c)
            if levenshtein(&name.to_lowercase(), &c.to_lowercase()) <= name.chars().count() / 2 =>
        {
            format!("; did you mean `{c}`?")
        }
        _ => String::new(),
    }
}

fn join(path: &mut String, seg: &str) {
    if !path.is_empty() && !seg.starts_with('[') && !seg.is_empty() {
        path.push('.');
    }
    path.push_str(seg);
}

/// A path below the failing value travels inside the message of a nested reader (see [`Tagged`]).
const MARK: char = '\u{1}';

fn embed(path: &str, message: &str) -> String {
    format!("{MARK}{path}{MARK}{message}")
}

/// serde's message in our words, and a path below the one serde tracked (a missing field, a path
/// embedded by a nested reader).
fn reword(m: &str) -> (Option<String>, String) {
    if let Some((path, msg)) = m.strip_prefix(MARK).and_then(|r| r.split_once(MARK)) {
        return (Some(path.to_string()), msg.to_string());
    }
    let names = |s: &str| -> Vec<String> {
        s.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    };
    let m = m.replace("expected f64", "expected a finite number");
    if let Some(rest) = m.strip_prefix("missing field ") {
        return (names(rest).into_iter().next(), "missing field".into());
    }
    for (what, kind) in [("unknown field ", "field"), ("unknown variant ", "value")] {
        if let Some(rest) = m.strip_prefix(what) {
            let all = names(rest);
            let (given, known) = all.split_first().map_or(("", &[][..]), |(g, k)| (g, k));
            let msg = if known.is_empty() {
                format!("unknown {kind} `{given}` (no fields are allowed here)")
            } else {
                format!(
                    "unknown {kind} `{given}` (expected one of: {}){}",
                    known.join(", "),
                    did_you_mean(given, known)
                )
            };
            return (None, msg);
        }
    }
    for what in ["invalid type: ", "invalid value: ", "invalid length "] {
        if let Some((found, expected)) = m
            .strip_prefix(what)
            .and_then(|r| r.split_once(", expected "))
        {
            let found = if what == "invalid length " {
                format!("{found} elements")
            } else {
                found.to_string()
            };
            return (None, format!("expected {expected}, found {found}"));
        }
    }
    (None, m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    #[serde(rename_all = "snake_case", deny_unknown_fields)]
    #[allow(dead_code)]
    enum Joint {
        Fixed {},
        Linear { direction: [f64; 3] },
    }

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Body {
        name: String,
        joint: Option<Tagged<Joint>>,
    }

    fn err(json: &str) -> FieldError {
        from_value::<Vec<Body>>(&parse(json).unwrap()).unwrap_err()
    }

    #[test]
    fn paths_and_messages() {
        let e = err(
            r#"[{"name": "a"}, {"name": "b", "joint": {"type": "linear", "direction": [1, "x", 0]}}]"#,
        );
        assert_eq!(e.path, "[1].joint.direction[1]");
        assert_eq!(e.message, "expected a finite number, found string \"x\"");
        let e = err(r#"[{"name": "b", "joint": {"type": "linar"}}]"#);
        assert_eq!(e.path, "[0].joint.type");
        assert!(
            e.message.contains("did you mean `linear`?"),
            "{}",
            e.message
        );
        let e = err(r#"[{"name": "b", "joint": {"type": "fixed", "direction": [1, 0, 0]}}]"#);
        assert_eq!(e.path, "[0].joint.direction");
        assert!(e.message.contains("no fields"), "{}", e.message);
        let e = err(r#"[{"name": "b", "joint": {"type": "linear"}}]"#);
        assert_eq!(
            (e.path.as_str(), e.message.as_str()),
            ("[0].joint.direction", "missing field")
        );
        let e = err(r#"[{"name": "b", "joint": {"direction": [1, 0]}}]"#);
        assert_eq!(e.path, "[0].joint.type");
        let e = err(r#"[{"name": "b", "joint": {"type": "linear", "direction": [1, 0]}}]"#);
        assert_eq!(e.message, "expected an array of length 3, found 2 elements");
        let e = err(r#"[{"nme": "b"}]"#);
        assert_eq!(e.path, "[0].nme");
        assert!(e.message.contains("did you mean `name`?"), "{}", e.message);
        assert!(from_value::<Vec<Body>>(&parse("\u{feff}[]").unwrap()).is_ok());
    }

    #[test]
    fn format_first() {
        let v = parse(r#"{"format": "x/2", "bodies": 1}"#).unwrap();
        let e = check_format(&v, "x/1").unwrap_err();
        assert_eq!(e.path, "format");
        assert!(e.message.contains("\"x/1\""), "{}", e.message);
        assert!(check_format(&parse("[]").unwrap(), "x/1").is_err());
    }
}
