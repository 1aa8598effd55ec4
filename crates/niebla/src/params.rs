//! Reading tagged JSON objects (scene files, integrator settings) with
//! errors that carry the JSON path of the offending value.
//!
//! A tagged object (one with a `type` field) is read into a map, its tag is
//! taken out, and the rest is deserialized into a plain
//! `deny_unknown_fields` struct with its own `serde_path_to_error` tracking.
//! Errors inside carry a path relative to the object ([`Located`]); the
//! path travels out through serde inside the error message
//! ([`Located::into_serde`]) and is joined to the outer path, so that every
//! error names its full path, e.g. `lights[1].intensity[2]`.

use std::fmt;

use serde::de::{self, DeserializeOwned, Deserializer, MapAccess, Visitor};
use serde_json::{Map, Value};

/// Marks a serde error message that carries a path: `"\u{1}PATH\u{1}MESSAGE"`.
const NESTED: char = '\u{1}';

/// An error with a path relative to the object being read.
#[derive(Debug)]
pub struct Located {
    /// Path relative to the object being read; empty for the object itself.
    pub path: String,
    /// What is wrong and what was expected.
    pub message: String,
}

impl Located {
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Located {
        Located { path: path.into(), message: message.into() }
    }

    /// Passes this error out through serde, keeping its path in the message;
    /// [`Located::from_path_error`] unpacks it and joins the outer path.
    pub fn into_serde<E: de::Error>(self) -> E {
        E::custom(format!("{NESTED}{}{NESTED}{}", self.path, self.message))
    }

    /// Converts a `serde_path_to_error` error: its path joined with any path
    /// carried in the message, and serde's wording made friendlier.
    pub fn from_path_error(e: serde_path_to_error::Error<serde_json::Error>) -> Located {
        let outer = path_string(e.path());
        let text = e.into_inner().to_string();
        match text.strip_prefix(NESTED).and_then(|t| t.split_once(NESTED)) {
            Some((inner, message)) => Located::new(join(&outer, inner), message),
            None => normalize(outer, &text),
        }
    }

    /// The same error seen from the parent object, where this value is `key`.
    pub fn under(mut self, key: &str) -> Located {
        self.path = join(key, &self.path);
        self
    }
}

/// Formats a `serde_path_to_error` path as `a.b[2].c`; empty for the root.
fn path_string(path: &serde_path_to_error::Path) -> String {
    let mut out = String::new();
    for segment in path.iter() {
        match segment {
            serde_path_to_error::Segment::Seq { index } => out.push_str(&format!("[{index}]")),
            serde_path_to_error::Segment::Map { key } | serde_path_to_error::Segment::Enum { variant: key } => {
                out = join(&out, key);
            }
            serde_path_to_error::Segment::Unknown => out = join(&out, "?"),
        }
    }
    out
}

/// Joins two relative paths: `join("lights[1]", "intensity[2]")` is
/// `lights[1].intensity[2]`, `join("a", "[0]")` is `a[0]`.
pub fn join(outer: &str, inner: &str) -> String {
    if outer.is_empty() {
        inner.to_string()
    } else if inner.is_empty() {
        outer.to_string()
    } else if inner.starts_with('[') {
        format!("{outer}{inner}")
    } else {
        format!("{outer}.{inner}")
    }
}

/// Rewords a plain serde message: a missing field's path names the field,
/// Rust type names become words, and an unknown string in a closed set (such
/// as `sampling`) is an unknown value rather than a "variant".
fn normalize(path: String, message: &str) -> Located {
    if let Some(field) = message.strip_prefix("missing field `").and_then(|rest| rest.strip_suffix('`')) {
        return Located::new(join(&path, field), format!("missing required field `{field}`"));
    }
    let message = message
        .replace("expected f32", "expected a number")
        .replace("expected u32", "expected a whole number from 0 to 4294967295")
        .replace("expected u64", "expected a whole number >= 0")
        .replace("unknown variant `", "unknown value `")
        .replace(", there are no fields", "; this type has no fields besides `type`");
    Located::new(path, message)
}

/// A JSON object being read field by field.
pub type Object = Map<String, Value>;

/// Reads any JSON object into a map; `expecting` completes "expected ..." when
/// the value is not an object.
pub fn read_object<'de, D: Deserializer<'de>>(deserializer: D, expecting: &'static str) -> Result<Object, D::Error> {
    struct ObjectVisitor(&'static str);
    impl<'de> Visitor<'de> for ObjectVisitor {
        type Value = Object;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str(self.0)
        }
        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Object, A::Error> {
            let mut object = Object::new();
            while let Some((key, value)) = map.next_entry::<String, Value>()? {
                object.insert(key, value);
            }
            Ok(object)
        }
    }
    deserializer.deserialize_map(ObjectVisitor(expecting))
}

/// Takes the `type` tag out of a tagged object. A missing tag is an error
/// unless there is a `default`.
pub fn take_tag(object: &mut Object, kind: &str, types: &[&str], default: Option<&str>) -> Result<String, Located> {
    match object.remove("type") {
        Some(Value::String(tag)) => Ok(tag),
        Some(other) => Err(Located::new(
            "type",
            format!("expected a string naming the {kind} type, one of: {}; got {}", types.join(", "), describe(&other)),
        )),
        None => default.map(str::to_string).ok_or_else(|| {
            Located::new("type", format!("missing required field `type`; expected one of: {}", types.join(", ")))
        }),
    }
}

/// The error for a `type` that names no variant.
pub fn unknown_type(kind: &str, tag: &str, types: &[&str]) -> Located {
    Located::new("type", format!("unknown {kind} type {tag:?}; expected one of: {}", types.join(", ")))
}

/// Takes `key` out of the object and deserializes it, if present.
pub fn take<T: DeserializeOwned>(object: &mut Object, key: &str) -> Result<Option<T>, Located> {
    object
        .remove(key)
        .map(|value| serde_path_to_error::deserialize(value).map_err(|e| Located::from_path_error(e).under(key)))
        .transpose()
}

/// Deserializes what is left of an object (the tag removed) as `T`, usually a
/// `deny_unknown_fields` struct.
pub fn rest<T: DeserializeOwned>(object: Object) -> Result<T, Located> {
    serde_path_to_error::deserialize(Value::Object(object)).map_err(Located::from_path_error)
}

/// A short description of a JSON value's kind, for messages.
pub fn describe(value: &Value) -> &'static str {
    match value {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joined_paths_use_dots_and_brackets() {
        assert_eq!(join("lights[1]", "intensity[2]"), "lights[1].intensity[2]");
        assert_eq!(join("a", "[0]"), "a[0]");
        assert_eq!(join("", "x"), "x");
        assert_eq!(join("x", ""), "x");
    }
}
