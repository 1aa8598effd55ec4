//! The one error type of scene loading, [`SceneError`]: where (file and JSON
//! path) and what, and a scanner that maps a position in the text to its
//! JSON path (for syntax errors and duplicate keys). Errors with paths
//! relative to a nested object are [`crate::params::Located`].

use std::collections::HashSet;
use std::fmt;

use crate::params::join;

/// An error in a scene file: the file, the JSON path inside it and what was
/// expected there.
///
/// Paths use dots for object keys and brackets for array indices, relative to
/// the top-level object: `media.fog.sigma_s[2]`, `shapes[3].interior`,
/// `lights[1].intensity`. The path is empty for errors about the file as a
/// whole (it cannot be read, or it is not valid JSON; the message then carries
/// the line and column).
///
/// Displays as `"{file}: {path}: {message}"`, or `"{file}: {message}"` when the
/// path is empty.
///
/// ```
/// use niebla::scene::SceneError;
/// let e = SceneError::new("fog.json", "media.fog.sigma_s[2]", "must be >= 0, got -1");
/// assert_eq!(e.to_string(), "fog.json: media.fog.sigma_s[2]: must be >= 0, got -1");
/// let e = SceneError::new("fog.json", "", "invalid JSON: EOF while parsing a value at line 1 column 0");
/// assert_eq!(e.to_string(), "fog.json: invalid JSON: EOF while parsing a value at line 1 column 0");
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// The scene file as given by the caller (a path or a name such as `<stdin>`).
    pub file: String,
    /// JSON path of the offending value, e.g. `shapes[3].interior`; empty for
    /// whole-file errors.
    pub path: String,
    /// What is wrong and what was expected, e.g. `unknown medium "fgo"; known
    /// media: fog, smoke`.
    pub message: String,
}

impl SceneError {
    /// An error at `path` (may be empty) in `file`.
    pub fn new(file: impl Into<String>, path: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError { file: file.into(), path: path.into(), message: message.into() }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: {}: {}", self.file, self.path, self.message)
        }
    }
}

impl std::error::Error for SceneError {}

// ---------------------------------------------------------------------------
// Text scanner: JSON paths of text positions, duplicate keys
// ---------------------------------------------------------------------------

/// An open container while scanning JSON text.
enum Frame {
    /// An object, with the key whose value comes next (if read) and the keys
    /// seen so far.
    Object { key: Option<String>, seen: HashSet<String> },
    /// An array, with the index of the current element.
    Array { index: usize },
}

/// Result of [`scan`]: the path of the value at the stop position and the
/// first duplicate key, as (path of the duplicate, key).
struct Scan {
    path: String,
    duplicate: Option<(String, String)>,
}

/// Walks JSON text up to byte `stop`, tracking the containers and keys.
/// Tolerates any input (it is also run on text that failed to parse) and
/// never panics.
fn scan(text: &str, stop: usize) -> Scan {
    let bytes = text.as_bytes();
    let stop = stop.min(bytes.len());
    let mut stack: Vec<Frame> = Vec::new();
    let mut duplicate = None;
    let mut i = 0;
    while i < stop {
        match bytes.get(i).copied().unwrap_or(b' ') {
            b'{' => stack.push(Frame::Object { key: None, seen: HashSet::new() }),
            b'[' => stack.push(Frame::Array { index: 0 }),
            b'}' | b']' => {
                stack.pop();
            }
            b',' => match stack.last_mut() {
                Some(Frame::Array { index }) => *index += 1,
                Some(Frame::Object { key, .. }) => *key = None,
                None => {}
            },
            b'"' => {
                let end = string_end(bytes, i);
                if let Some(Frame::Object { key: key @ None, seen }) = stack.last_mut() {
                    // A string where a key is expected: the key.
                    let raw = text.get(i..end).unwrap_or("");
                    let name =
                        serde_json::from_str::<String>(raw).unwrap_or_else(|_| raw.trim_matches('"').to_string());
                    let is_duplicate = !seen.insert(name.clone());
                    *key = Some(name.clone());
                    if is_duplicate && duplicate.is_none() {
                        duplicate = Some((path_of(&stack), name));
                    }
                }
                i = end;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    Scan { path: path_of(&stack), duplicate }
}

/// Index just past the string starting at the quote at `start`.
fn string_end(bytes: &[u8], start: usize) -> usize {
    let mut j = start + 1;
    while let Some(&b) = bytes.get(j) {
        match b {
            b'\\' => j += 2,
            b'"' => return j + 1,
            _ => j += 1,
        }
    }
    bytes.len()
}

fn path_of(stack: &[Frame]) -> String {
    let mut path = String::new();
    for frame in stack {
        match frame {
            Frame::Object { key: Some(key), .. } => path = join(&path, key),
            Frame::Object { key: None, .. } => break,
            Frame::Array { index } => path.push_str(&format!("[{index}]")),
        }
    }
    path
}

/// JSON path of the value at byte `offset` of `text`.
pub(super) fn path_at(text: &str, offset: usize) -> String {
    scan(text, offset).path
}

/// The first key that appears twice in one object, as (path, key).
pub(super) fn find_duplicate_key(text: &str) -> Option<(String, String)> {
    scan(text, text.len()).duplicate
}

/// Byte offset of serde_json's 1-based `line` and `column` (columns count
/// bytes; the column of an error is that of its last byte read).
pub(super) fn byte_offset(text: &str, line: usize, column: usize) -> usize {
    let line_start: usize = text.split_inclusive('\n').take(line.saturating_sub(1)).map(str::len).sum();
    (line_start + column.saturating_sub(1)).min(text.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scanner_finds_paths_of_positions() {
        let text = r#"{"a": {"b": [1, 2, {"c": 3}]}, "d": 4}"#;
        let at = |needle: &str| path_at(text, text.find(needle).unwrap());
        assert_eq!(at("2,"), "a.b[1]");
        assert_eq!(at("3}"), "a.b[2].c");
        assert_eq!(at("4}"), "d");
    }

    #[test]
    fn scanner_finds_duplicate_keys_with_their_path() {
        let text = r#"{"m": {"x": 1, "s": "\"x\"", "x": 2}, "x": 0}"#;
        assert_eq!(find_duplicate_key(text), Some(("m.x".to_string(), "x".to_string())));
        assert_eq!(find_duplicate_key(r#"{"a": [{"x": 1}, {"x": 2}]}"#), None);
    }

    #[test]
    fn scanner_survives_garbage() {
        for text in ["", "\"", "{\"", "}}]]", "{\"a\\", "[[[,,,", "{\"é\": \"\\é"] {
            let _ = scan(text, text.len());
            let _ = scan(text, usize::MAX);
        }
    }

    #[test]
    fn scanner_walks_nesting_ten_thousand_deep_without_recursion() {
        // serde_json stops at 128 levels; the scanner keeps its own stack,
        // so any depth is fine (run on a small stack to prove it).
        let deep = format!("{}{{\"k\": 1, \"k\": 2}}{}", "[{\"a\": ".repeat(10_000), "}]".repeat(10_000));
        let (duplicate, path) = std::thread::Builder::new()
            .stack_size(256 << 10)
            .spawn(move || (find_duplicate_key(&deep), path_at(&deep, deep.len() / 2)))
            .unwrap()
            .join()
            .unwrap();
        let (at, key) = duplicate.unwrap();
        assert_eq!(key, "k");
        assert!(at.starts_with("[0].a[0].a") && at.len() > 50_000, "{}", &at[..40]);
        assert!(path.starts_with("[0].a[0].a"));
    }
}
