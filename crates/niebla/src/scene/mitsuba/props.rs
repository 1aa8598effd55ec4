//! The properties of one Mitsuba plugin element (`<float name=... value=...>`,
//! `<rgb>`, `<spectrum>`, `<integer>`, `<boolean>`, `<string>`, `<point>`,
//! `<vector>`, `<transform>`, nested plugins and `<ref>`s): typed getters that
//! mark what they read, so that whatever no converter read is an error (or,
//! for harmless properties, a note) naming its line.

use std::cell::Cell;

use super::transform::{read_transform_form, Form, Mat4};
use super::xml::Node;
use crate::scene::SceneError;

/// Parses numbers separated by commas and/or white space.
pub(super) fn numbers(text: &str) -> Result<Vec<f64>, String> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| format!("\"{s}\" is not a finite number"))
        })
        .collect()
}

/// Tags of the elements that are plugins (objects), not values.
pub(super) const PLUGIN_TAGS: &[&str] = &[
    "bsdf",
    "emitter",
    "shape",
    "medium",
    "phase",
    "volume",
    "texture",
    "sensor",
    "film",
    "rfilter",
    "sampler",
    "integrator",
];

/// A color read from a property: RGB (a gray value repeated).
pub(super) type Rgb3 = [f64; 3];

/// The properties of a plugin element, with a mark per child once read.
pub(super) struct Props<'a> {
    /// The plugin element.
    pub node: &'a Node,
    used: Vec<Cell<bool>>,
}

impl<'a> Props<'a> {
    /// The properties of `node`, checking that its own attributes are `type`, `id` and `name` only.
    pub fn new(node: &'a Node) -> Result<Props<'a>, SceneError> {
        node.check_attrs(&["type", "id", "name"])?;
        Ok(Props { node, used: node.children.iter().map(|_| Cell::new(false)).collect() })
    }

    /// The plugin's `type` attribute.
    pub fn plugin_type(&self) -> Result<&'a str, SceneError> {
        self.node.required("type")
    }

    /// `<tag type="x">` as shown in messages.
    pub fn what(&self) -> String {
        self.node.describe()
    }

    /// An error at the plugin's line, prefixed with the plugin.
    pub fn error(&self, message: impl std::fmt::Display) -> SceneError {
        self.node.loc.error(format!("{}: {message}", self.what()))
    }

    /// The child value element named `name`, marked as read.
    fn named(&self, name: &str) -> Option<&'a Node> {
        let node: &'a Node = self.node;
        let i = node
            .children
            .iter()
            .position(|c| !PLUGIN_TAGS.contains(&c.tag.as_str()) && c.tag != "ref" && c.attr("name") == Some(name))?;
        self.used[i].set(true);
        Some(&node.children[i])
    }

    /// Whether a value element named `name` exists (without marking it).
    pub fn has(&self, name: &str) -> bool {
        self.node.children.iter().any(|c| c.attr("name") == Some(name))
    }

    fn value_of<'n>(&self, node: &'n Node) -> Result<&'n str, SceneError> {
        node.check_attrs(&["name", "value"])?;
        node.required("value")
    }

    fn bad(&self, node: &Node, expected: &str) -> SceneError {
        node.loc.error(format!("{}: property `{}`: expected {expected}", self.what(), node.attr("name").unwrap_or("")))
    }

    /// A `<float>` (or `<integer>`) named `name`.
    pub fn float(&self, name: &str) -> Result<Option<f64>, SceneError> {
        let Some(n) = self.named(name) else { return Ok(None) };
        if n.tag != "float" && n.tag != "integer" {
            return Err(self.bad(n, &format!("<float name=\"{name}\" value=\"...\"/>, found <{}>", n.tag)));
        }
        let v = self.value_of(n)?;
        match numbers(v) {
            Ok(x) if x.len() == 1 => Ok(Some(x[0])),
            _ => Err(self.bad(n, &format!("one number, found \"{v}\""))),
        }
    }

    /// A `<float>` named `name`, or `default`.
    pub fn float_or(&self, name: &str, default: f64) -> Result<f64, SceneError> {
        Ok(self.float(name)?.unwrap_or(default))
    }

    /// An `<integer>` named `name`.
    pub fn integer(&self, name: &str) -> Result<Option<i64>, SceneError> {
        let Some(n) = self.named(name) else { return Ok(None) };
        if n.tag != "integer" {
            return Err(self.bad(n, &format!("<integer name=\"{name}\" value=\"...\"/>, found <{}>", n.tag)));
        }
        let v = self.value_of(n)?;
        v.trim().parse::<i64>().map(Some).map_err(|_| self.bad(n, &format!("a whole number, found \"{v}\"")))
    }

    /// A `<boolean>` named `name`.
    pub fn boolean(&self, name: &str) -> Result<Option<bool>, SceneError> {
        let Some(n) = self.named(name) else { return Ok(None) };
        if n.tag != "boolean" {
            return Err(self.bad(n, &format!("<boolean name=\"{name}\" value=\"true|false\"/>, found <{}>", n.tag)));
        }
        match self.value_of(n)?.trim() {
            "true" => Ok(Some(true)),
            "false" => Ok(Some(false)),
            v => Err(self.bad(n, &format!("true or false, found \"{v}\""))),
        }
    }

    /// A `<string>` named `name`.
    pub fn string(&self, name: &str) -> Result<Option<&'a str>, SceneError> {
        let Some(n) = self.named(name) else { return Ok(None) };
        if n.tag != "string" {
            return Err(self.bad(n, &format!("<string name=\"{name}\" value=\"...\"/>, found <{}>", n.tag)));
        }
        n.check_attrs(&["name", "value"])?;
        n.required("value").map(Some)
    }

    /// A `<point>` or `<vector>` named `name`: `x`, `y`, `z` attributes or `value="x, y, z"`.
    pub fn vec3(&self, name: &str) -> Result<Option<[f64; 3]>, SceneError> {
        let Some(n) = self.named(name) else { return Ok(None) };
        if n.tag != "point" && n.tag != "vector" {
            return Err(self.bad(n, &format!("<point> or <vector>, found <{}>", n.tag)));
        }
        n.check_attrs(&["name", "value", "x", "y", "z"])?;
        if let Some(v) = n.attr("value") {
            return match numbers(v) {
                Ok(x) if x.len() == 3 => Ok(Some([x[0], x[1], x[2]])),
                Ok(x) if x.len() == 1 => Ok(Some([x[0]; 3])),
                _ => Err(self.bad(n, &format!("3 numbers, found \"{v}\""))),
            };
        }
        let mut out = [0.0; 3];
        for (i, a) in ["x", "y", "z"].iter().enumerate() {
            if let Some(v) = n.attr(a) {
                out[i] = match numbers(v) {
                    Ok(x) if x.len() == 1 => x[0],
                    _ => return Err(self.bad(n, &format!("one number in `{a}`, found \"{v}\""))),
                };
            }
        }
        Ok(Some(out))
    }

    /// A color: `<rgb>`, `<spectrum>` (a constant value; wavelength samples
    /// are not converted), or `<float>`/`<integer>` (gray). A `<texture>`
    /// here is an error.
    pub fn color(&self, name: &str) -> Result<Option<Rgb3>, SceneError> {
        if let Some(t) = self.plugin_named(name) {
            return Err(t.loc.error(format!(
                "{}: `{name}` as {}: textures and volumes are not supported here; give a constant <rgb> or <float>",
                self.what(),
                t.describe()
            )));
        }
        let Some(n) = self.named(name) else { return Ok(None) };
        let v = match n.tag.as_str() {
            "rgb" | "spectrum" | "float" | "integer" => self.value_of(n)?,
            other => return Err(self.bad(n, &format!("<rgb>, <spectrum> or <float>, found <{other}>"))),
        };
        if n.tag == "spectrum" && v.contains(':') {
            return Err(self.bad(
                n,
                "a constant <spectrum value=\"v\"/>: spectra sampled at wavelengths are not converted to RGB (give \
                 <rgb>)",
            ));
        }
        match numbers(v) {
            Ok(x) if x.len() == 1 => Ok(Some([x[0]; 3])),
            Ok(x) if x.len() == 3 && n.tag == "rgb" => Ok(Some([x[0], x[1], x[2]])),
            _ => Err(self.bad(n, &format!("one number or (for <rgb>) three, found \"{v}\""))),
        }
    }

    /// A `<transform>` named `name`.
    pub fn transform(&self, name: &str) -> Result<Option<Mat4>, SceneError> {
        Ok(self.transform_form(name)?.map(|(m, _)| m))
    }

    /// Like [`Props::transform`], with the transform's [`Form`] (the numbers
    /// as written, where niebla has a description of its own for them).
    pub fn transform_form(&self, name: &str) -> Result<Option<(Mat4, Form)>, SceneError> {
        let Some(n) = self.named(name) else { return Ok(None) };
        if n.tag != "transform" {
            return Err(self.bad(n, &format!("<transform name=\"{name}\">, found <{}>", n.tag)));
        }
        read_transform_form(n).map(Some)
    }

    /// The nested plugin element or `<ref>` with attribute `name="name"`, marked as read.
    pub fn plugin_named(&self, name: &str) -> Option<&'a Node> {
        let node: &'a Node = self.node;
        let i = node.children.iter().enumerate().position(|(i, c)| {
            !self.used[i].get()
                && (PLUGIN_TAGS.contains(&c.tag.as_str()) || c.tag == "ref")
                && c.attr("name") == Some(name)
        })?;
        self.used[i].set(true);
        Some(&node.children[i])
    }

    /// Every nested plugin element or `<ref>` that has no `name` (or any
    /// name when `any_name`), with tag `tag` (a `<ref>` counts for any tag;
    /// the caller resolves it), marked as read.
    pub fn plugins(&self, tag: &str) -> Vec<&'a Node> {
        let node: &'a Node = self.node;
        let mut out = Vec::new();
        for (i, c) in node.children.iter().enumerate() {
            if self.used[i].get() {
                continue;
            }
            if c.tag == tag {
                self.used[i].set(true);
                out.push(c);
            }
        }
        out
    }

    /// Unread `<ref>` children without a `name`.
    pub fn unnamed_refs(&self) -> Vec<&'a Node> {
        let node: &'a Node = self.node;
        let mut out = Vec::new();
        for (i, c) in node.children.iter().enumerate() {
            if !self.used[i].get() && c.tag == "ref" {
                self.used[i].set(true);
                out.push(c);
            }
        }
        out
    }

    /// Marks the properties `names` as accepted without effect, adding a
    /// note for each that is present.
    pub fn harmless(&self, names: &[&str], why: &str, notes: &mut Vec<String>) {
        for (i, c) in self.node.children.iter().enumerate() {
            if let Some(n) = c.attr("name") {
                if names.contains(&n) && !self.used[i].get() {
                    self.used[i].set(true);
                    notes.push(format!("{}: {} `{n}`: {why}", c.loc.at(), self.what()));
                }
            }
        }
    }

    /// The error for the first child nobody read.
    pub fn finish(&self) -> Result<(), SceneError> {
        for (i, c) in self.node.children.iter().enumerate() {
            if !self.used[i].get() {
                let what = match c.attr("name") {
                    Some(n) => format!("property `{n}` ({})", c.describe()),
                    None => c.describe(),
                };
                return Err(c.loc.error(format!("{}: {what}: not supported", self.what())));
            }
        }
        Ok(())
    }
}
