//! The conversion driver: ids and `<ref>`s, the top-level elements in file
//! order, media by name, and the niebla scene JSON they add up to.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

use super::props::{Props, Rgb3, PLUGIN_TAGS};
use super::xml::{Node, SceneXml};
use crate::scene::SceneError;

/// The state of one conversion.
pub(super) struct Converter<'a> {
    /// The scene read from XML.
    pub xml: &'a SceneXml,
    /// Every element with an `id`, by id.
    ids: HashMap<&'a str, &'a Node>,
    /// Accepted-but-ignored elements, `file:line: what`.
    pub notes: Vec<String>,
    /// niebla media by name.
    pub media: Map<String, Value>,
    /// Names given to medium elements already converted (by address).
    medium_names: HashMap<*const Node, String>,
    /// niebla shapes, in file order.
    pub shapes: Vec<Value>,
    /// niebla lights, in file order.
    pub lights: Vec<Value>,
    /// The folder that file names in the output are relative to.
    out_base: PathBuf,
}

/// The color as niebla JSON: a number when gray, else `[r, g, b]`.
pub(super) fn color_json(c: Rgb3) -> Value {
    if c[0] == c[1] && c[1] == c[2] {
        json!(c[0])
    } else {
        json!(c)
    }
}

impl<'a> Converter<'a> {
    /// A converter for `xml`, writing file names relative to `out_base`.
    pub fn new(xml: &'a SceneXml, out_base: &Path) -> Result<Converter<'a>, SceneError> {
        let mut ids = HashMap::new();
        fn collect<'n>(n: &'n Node, ids: &mut HashMap<&'n str, &'n Node>) -> Result<(), SceneError> {
            if PLUGIN_TAGS.contains(&n.tag.as_str()) {
                if let Some(id) = n.attr("id") {
                    if let Some(prev) = ids.insert(id, n) {
                        return Err(n.loc.error(format!(
                            "{}: id \"{id}\" is already used at {}",
                            n.describe(),
                            prev.loc.at()
                        )));
                    }
                }
            }
            n.children.iter().try_for_each(|c| collect(c, ids))
        }
        for n in &xml.elements {
            collect(n, &mut ids)?;
        }
        let out_base = std::fs::canonicalize(out_base).unwrap_or_else(|_| out_base.to_path_buf());
        Ok(Converter {
            xml,
            ids,
            notes: Vec::new(),
            media: Map::new(),
            medium_names: HashMap::new(),
            shapes: Vec::new(),
            lights: Vec::new(),
            out_base,
        })
    }

    /// `node` itself, or for a `<ref id>` the element it names, which must be a `<tag>`.
    pub fn resolve(&self, node: &'a Node, tag: &str) -> Result<&'a Node, SceneError> {
        if node.tag != "ref" {
            if node.tag != tag {
                return Err(node.loc.error(format!("{}: expected a <{tag}> here", node.describe())));
            }
            return Ok(node);
        }
        node.check_attrs(&["id", "name"])?;
        let id = node.required("id")?;
        let target =
            self.ids.get(id).ok_or_else(|| node.loc.error(format!("<ref id=\"{id}\">: no element has id \"{id}\"")))?;
        if target.tag != tag {
            return Err(node.loc.error(format!(
                "<ref id=\"{id}\">: expected a <{tag}>, but \"{id}\" is {} at {}",
                target.describe(),
                target.loc.at()
            )));
        }
        Ok(target)
    }

    /// The tag a `<ref>` points to (or the element's own tag).
    pub fn target_tag(&self, node: &'a Node) -> Option<&'a str> {
        if node.tag == "ref" {
            node.attr("id").and_then(|id| self.ids.get(id)).map(|t| t.tag.as_str())
        } else {
            Some(node.tag.as_str())
        }
    }

    /// A file named in the scene: found through the search folders and
    /// written relative to the output folder (absolute when outside it).
    pub fn file(&self, props: &Props, name: &str) -> Result<(String, PathBuf), SceneError> {
        let given = props.string(name)?.ok_or_else(|| props.error(format!("missing <string name=\"{name}\">")))?;
        let found = self.xml.resolve(given).ok_or_else(|| {
            let searched: Vec<String> = self.xml.search.iter().map(|p| p.display().to_string()).collect();
            props.error(format!("file \"{given}\" not found (searched {})", searched.join(", ")))
        })?;
        let full = std::fs::canonicalize(&found).unwrap_or(found);
        let shown = match full.strip_prefix(&self.out_base) {
            Ok(rel) => rel.to_string_lossy().replace('\\', "/"),
            Err(_) => full.to_string_lossy().into_owned(),
        };
        Ok((shown, full))
    }

    /// The niebla name of a `<medium>` (or a `<ref>` to one), converting it on first use.
    pub fn medium(&mut self, node: &'a Node) -> Result<String, SceneError> {
        let node = self.resolve(node, "medium")?;
        if let Some(name) = self.medium_names.get(&(node as *const Node)) {
            return Ok(name.clone());
        }
        let mut name = match node.attr("id") {
            Some(id) => id.to_string(),
            None => format!("medium_line{}", node.loc.line),
        };
        while self.media.contains_key(&name) {
            name.push('_');
        }
        let value = super::media::convert_medium(self, node)?;
        self.media.insert(name.clone(), value);
        self.medium_names.insert(node as *const Node, name.clone());
        Ok(name)
    }

    /// Runs the conversion of every top-level element; returns the scene JSON.
    pub fn run(mut self) -> Result<(Value, Vec<String>), SceneError> {
        let mut sensor = None;
        let mut integrator = None;
        for n in &self.xml.elements {
            match n.tag.as_str() {
                "sensor" => {
                    if let Some(prev) = sensor.replace(n) {
                        let prev: &Node = prev;
                        return Err(n.loc.error(format!(
                            "{}: a second sensor (the first is at {}); niebla renders one camera",
                            n.describe(),
                            prev.loc.at()
                        )));
                    }
                }
                "integrator" => {
                    if let Some(prev) = integrator.replace(n) {
                        let prev: &Node = prev;
                        return Err(n
                            .loc
                            .error(format!("<integrator>: a second one (the first is at {})", prev.loc.at())));
                    }
                }
                "shape" => super::shapes::convert_shape(&mut self, n)?,
                "emitter" => {
                    let light = super::emitters::convert_emitter(&mut self, n)?;
                    self.lights.push(light);
                }
                "medium" => {
                    if n.attr("id").is_none() {
                        return Err(n.loc.error(format!("{}: a top-level medium needs an id", n.describe())));
                    }
                    self.medium(n)?;
                }
                // Declarations used through <ref>; checked where they are used.
                "bsdf" | "phase" | "volume" | "texture" if n.attr("id").is_some() => {}
                _ => return Err(n.loc.error(format!("{}: not supported at the top level of a scene", n.describe()))),
            }
        }
        let sensor = sensor.ok_or_else(|| self.xml.loc.error("<scene>: no <sensor>; niebla needs a camera"))?;
        let (camera, mut render, camera_medium) = super::sensor::convert_sensor(&mut self, sensor)?;
        render.insert("integrator".into(), super::sensor::convert_integrator(&mut self, integrator)?);
        let mut scene = Map::new();
        scene.insert("version".into(), json!(1));
        scene.insert("camera".into(), camera);
        scene.insert("render".into(), Value::Object(render));
        if let Some((medium, loc)) = camera_medium {
            let bounded =
                self.shapes.iter().any(|s| s.get("interior").and_then(Value::as_str) == Some(medium.as_str()));
            if bounded {
                self.notes.push(format!(
                    "{loc}: <sensor> medium \"{medium}\": niebla finds the camera's medium itself (the innermost \
                     shape with an interior that contains the camera)"
                ));
            } else {
                scene.insert("ambient_medium".into(), json!(medium));
            }
        }
        scene.insert("media".into(), Value::Object(std::mem::take(&mut self.media)));
        scene.insert("shapes".into(), Value::Array(std::mem::take(&mut self.shapes)));
        scene.insert("lights".into(), Value::Array(std::mem::take(&mut self.lights)));
        Ok((Value::Object(scene), self.notes))
    }
}
