//! Reading Mitsuba 3 XML into an owned element tree: syntax (through
//! `roxmltree`, which keeps text positions), `<default>` values and `$name`
//! substitution, `<include>` and `<path>`. Every element keeps its file and
//! line for error messages.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::scene::SceneError;

/// Largest nesting of `<include>` files (a cycle stops here with an error).
const MAX_INCLUDE_DEPTH: usize = 16;
/// Largest XML file read (bytes); a scene description is small, meshes and
/// grids live in their own files.
pub(super) const MAX_XML_BYTES: u64 = 64 << 20;

/// Where an element starts: its file (as named to the user) and 1-based line.
#[derive(Clone, Debug)]
pub(super) struct Loc {
    /// The file, as shown in messages.
    pub file: Arc<str>,
    /// 1-based line of the element's start tag.
    pub line: u32,
}

impl Loc {
    /// An error `file:line: message`.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError::new(format!("{}:{}", self.file, self.line), "", message)
    }

    /// `file:line`, for notes.
    pub fn at(&self) -> String {
        format!("{}:{}", self.file, self.line)
    }
}

/// One XML element, attributes substituted, includes spliced in.
#[derive(Clone, Debug)]
pub(super) struct Node {
    /// Tag name (`shape`, `float`, `transform`, ...).
    pub tag: String,
    /// Attributes in file order, `$name` references replaced.
    pub attrs: Vec<(String, String)>,
    /// Child elements in file order (text and comments dropped).
    pub children: Vec<Node>,
    /// Where the start tag is.
    pub loc: Loc,
}

impl Node {
    /// The value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    /// The value of attribute `name`, or an error naming the element.
    pub fn required(&self, name: &str) -> Result<&str, SceneError> {
        self.attr(name).ok_or_else(|| self.loc.error(format!("{}: missing attribute `{name}`", self.describe())))
    }

    /// `<tag type="...">` or `<tag name="...">` as the element is shown in messages.
    pub fn describe(&self) -> String {
        match (self.attr("type"), self.attr("name")) {
            (Some(t), _) => format!("<{} type=\"{t}\">", self.tag),
            (None, Some(n)) => format!("<{} name=\"{n}\">", self.tag),
            (None, None) => format!("<{}>", self.tag),
        }
    }

    /// Error: attribute(s) other than `allowed`.
    pub fn check_attrs(&self, allowed: &[&str]) -> Result<(), SceneError> {
        for (k, _) in &self.attrs {
            if !allowed.contains(&k.as_str()) {
                return Err(self.loc.error(format!(
                    "{}: unexpected attribute `{k}` (expected {})",
                    self.describe(),
                    allowed.join(", ")
                )));
            }
        }
        Ok(())
    }
}

/// The top-level content of a scene: its elements (defaults, paths and
/// includes resolved) and the folders searched for files.
#[derive(Debug)]
pub(super) struct SceneXml {
    /// The children of `<scene>` and of every included scene, in order.
    pub elements: Vec<Node>,
    /// Folders searched for relative file names: the main file's folder,
    /// then every `<path>` in order.
    pub search: Vec<PathBuf>,
    /// Where the `<scene>` element is.
    pub loc: Loc,
}

impl SceneXml {
    /// Finds a file named in the scene: as given if absolute, else the first
    /// search folder that has it.
    pub fn resolve(&self, name: &str) -> Option<PathBuf> {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.exists().then(|| p.to_path_buf());
        }
        self.search.iter().map(|d| d.join(p)).find(|f| f.exists())
    }
}

/// Reads the XML file `path` with `defines` (command-line `-D name=value`,
/// which win over the file's `<default>`s).
pub(super) fn read_scene_file(path: &Path, defines: &[(String, String)]) -> Result<SceneXml, SceneError> {
    let shown = path.display().to_string();
    let text = read_text(path, &shown)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    read_scene_str(&text, &shown, &dir, defines)
}

/// Reads scene XML from `text`; `file` names it in messages, `dir` is its folder.
pub(super) fn read_scene_str(
    text: &str,
    file: &str,
    dir: &Path,
    defines: &[(String, String)],
) -> Result<SceneXml, SceneError> {
    let mut reader = Reader { search: vec![dir.to_path_buf()], params: HashMap::new(), overrides: HashMap::new() };
    for (k, v) in defines {
        reader.overrides.insert(k.clone(), v.clone());
        reader.params.insert(k.clone(), v.clone());
    }
    let (elements, loc) = reader.read_text(text, file, 0)?;
    Ok(SceneXml { elements, search: reader.search, loc })
}

fn read_text(path: &Path, shown: &str) -> Result<String, SceneError> {
    let meta =
        std::fs::metadata(path).map_err(|e| SceneError::new(shown, "", format!("cannot read scene file: {e}")))?;
    if meta.len() > MAX_XML_BYTES {
        return Err(SceneError::new(
            shown,
            "",
            format!("{} bytes: larger than the {} MiB an XML scene may have", meta.len(), MAX_XML_BYTES >> 20),
        ));
    }
    std::fs::read_to_string(path).map_err(|e| SceneError::new(shown, "", format!("cannot read scene file: {e}")))
}

struct Reader {
    search: Vec<PathBuf>,
    /// Parameters known so far (defaults and overrides).
    params: HashMap<String, String>,
    /// Command-line values: a `<default>` of the same name does not replace them.
    overrides: HashMap<String, String>,
}

impl Reader {
    /// Parses one file's text; returns its content and where `<scene>` is.
    fn read_text(&mut self, text: &str, file: &str, depth: usize) -> Result<(Vec<Node>, Loc), SceneError> {
        let file: Arc<str> = Arc::from(file);
        let options = roxmltree::ParsingOptions { allow_dtd: false, nodes_limit: 1 << 22 };
        let doc = roxmltree::Document::parse_with_options(text, options).map_err(|e| {
            let pos = e.pos();
            SceneError::new(format!("{file}:{}", pos.row), "", format!("malformed XML: {e}"))
        })?;
        let root = doc.root_element();
        let loc = Loc { file: file.clone(), line: doc.text_pos_at(root.range().start).row };
        if root.tag_name().name() != "scene" {
            return Err(loc.error(format!("expected a <scene> element at the top, found <{}>", root.tag_name().name())));
        }
        let version = root
            .attribute("version")
            .ok_or_else(|| loc.error("<scene>: missing attribute `version` (e.g. version=\"3.0.0\")"))?
            .to_string();
        let major = version.split('.').next().unwrap_or("");
        if major != "2" && major != "3" {
            return Err(loc.error(format!(
                "<scene version=\"{version}\">: only Mitsuba 2 and 3 scenes are read (older versions name \
                 properties differently)"
            )));
        }
        let mut out = Vec::new();
        for child in root.children().filter(|n| n.is_element()) {
            let line = doc.text_pos_at(child.range().start).row;
            let here = Loc { file: file.clone(), line };
            match child.tag_name().name() {
                "default" => {
                    let node = self.element(&doc, child, &file)?;
                    node.check_attrs(&["name", "value"])?;
                    let name = node.required("name")?.to_string();
                    let value = node.required("value")?.to_string();
                    if !valid_param_name(&name) {
                        return Err(here.error(format!("<default name=\"{name}\">: a name is letters, digits and _")));
                    }
                    if !self.overrides.contains_key(&name) {
                        self.params.insert(name, value);
                    }
                }
                "path" => {
                    let node = self.element(&doc, child, &file)?;
                    node.check_attrs(&["value"])?;
                    let value = node.required("value")?;
                    let base = self.search[0].clone();
                    self.search.push(base.join(value));
                }
                "include" => {
                    let node = self.element(&doc, child, &file)?;
                    node.check_attrs(&["filename"])?;
                    if depth + 1 >= MAX_INCLUDE_DEPTH {
                        return Err(here.error(format!(
                            "<include>: more than {MAX_INCLUDE_DEPTH} nested includes (does a file include itself?)"
                        )));
                    }
                    let name = node.required("filename")?;
                    let found = self.find(name).ok_or_else(|| {
                        here.error(format!(
                            "<include filename=\"{name}\">: file not found (searched {})",
                            self.searched()
                        ))
                    })?;
                    let shown = found.display().to_string();
                    let text = read_text(&found, &shown).map_err(|e| here.error(format!("<include>: {e}")))?;
                    let (nodes, _) = self.read_text(&text, &shown, depth + 1)?;
                    out.extend(nodes);
                }
                _ => out.push(self.element(&doc, child, &file)?),
            }
        }
        Ok((out, loc))
    }

    fn find(&self, name: &str) -> Option<PathBuf> {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.exists().then(|| p.to_path_buf());
        }
        self.search.iter().map(|d| d.join(p)).find(|f| f.is_file())
    }

    fn searched(&self) -> String {
        self.search.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    }

    /// Copies `n` and its descendants, substituting parameters in attribute values.
    fn element(&self, doc: &roxmltree::Document, n: roxmltree::Node, file: &Arc<str>) -> Result<Node, SceneError> {
        let loc = Loc { file: file.clone(), line: doc.text_pos_at(n.range().start).row };
        let mut attrs = Vec::new();
        for a in n.attributes() {
            let value = self.substitute(a.value()).map_err(|m| loc.error(format!("<{}>: {m}", n.tag_name().name())))?;
            attrs.push((a.name().to_string(), value));
        }
        let mut children = Vec::new();
        for c in n.children().filter(|c| c.is_element()) {
            children.push(self.element(doc, c, file)?);
        }
        Ok(Node { tag: n.tag_name().name().to_string(), attrs, children, loc })
    }

    /// Replaces every `$name` by its parameter's value; an unknown name is an error.
    fn substitute(&self, value: &str) -> Result<String, String> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut out = String::with_capacity(value.len());
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let name = &after[..len];
            if name.is_empty() {
                return Err(format!("`$` not followed by a parameter name in \"{value}\""));
            }
            match self.params.get(name) {
                Some(v) => out.push_str(v),
                None => {
                    return Err(format!(
                        "undefined parameter `${name}` (declare <default name=\"{name}\" value=\"...\"/> or pass -D \
                         {name}=...)"
                    ))
                }
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

fn valid_param_name(name: &str) -> bool {
    !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, defines: &[(&str, &str)]) -> Result<SceneXml, SceneError> {
        let d: Vec<(String, String)> = defines.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        read_scene_str(text, "s.xml", Path::new("/nonexistent"), &d)
    }

    #[test]
    fn defaults_are_substituted_and_overridden() {
        let text = "<scene version=\"3.0.0\">\n<default name=\"spp\" value=\"4\"/>\n\
                    <integer name=\"x\" value=\"$spp\"/>\n<string name=\"y\" value=\"a$spp-$spp\"/></scene>";
        let s = read(text, &[]).unwrap();
        assert_eq!(s.elements[0].attr("value"), Some("4"));
        assert_eq!(s.elements[1].attr("value"), Some("a4-4"));
        assert_eq!(s.elements[1].loc.line, 4);
        let s = read(text, &[("spp", "64")]).unwrap();
        assert_eq!(s.elements[0].attr("value"), Some("64"));
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = read("<scene version=\"3.0.0\">\n\n<float name=\"x\" value=\"$nope\"/></scene>", &[]).unwrap_err();
        assert!(e.to_string().starts_with("s.xml:3: <float>: undefined parameter `$nope`"), "{e}");
        let e = read("<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n</scene>", &[]).unwrap_err();
        assert!(e.to_string().starts_with("s.xml:3: malformed XML"), "{e}");
        let e = read("<scene version=\"0.6.0\"/>", &[]).unwrap_err();
        assert!(e.to_string().starts_with("s.xml:1: <scene version=\"0.6.0\">"), "{e}");
        let e = read("<scene version=\"3.0.0\">\n<include filename=\"missing.xml\"/></scene>", &[]).unwrap_err();
        assert!(e.to_string().starts_with("s.xml:2: <include filename=\"missing.xml\">: file not found"), "{e}");
    }
}
