//! Top-level `<emitter>`: `point`, `spot`, `directional`, `constant` and
//! `envmap` into niebla lights (same radiometry: niebla follows Mitsuba 3's).

use serde_json::{json, Value};

use super::convert::{color_json, Converter};
use super::props::Props;
use super::transform::{is_identity, norm, point, to_json, vector, Form, IDENTITY};
use super::xml::Node;
use crate::scene::SceneError;

/// Converts a top-level `<emitter>` into a niebla light.
pub(super) fn convert_emitter<'a>(c: &mut Converter<'a>, node: &'a Node) -> Result<Value, SceneError> {
    let p = Props::new(node)?;
    let t = p.plugin_type()?;
    let placed = p.transform_form("to_world")?;
    let m = placed.as_ref().map(|(m, _)| *m);
    let out = match t {
        "point" => {
            let position = match (p.vec3("position")?, m) {
                (Some(_), Some(_)) => return Err(p.error("give `position` or `to_world`, not both")),
                (Some(pos), None) => pos,
                (None, m) => point(&m.unwrap_or(IDENTITY), [0.0; 3]),
            };
            let intensity = p.color("intensity")?.unwrap_or([1.0; 3]);
            json!({"type": "point", "position": position, "intensity": color_json(intensity)})
        }
        "spot" => {
            let m = m.unwrap_or(IDENTITY);
            let position = point(&m, [0.0; 3]);
            let axis = vector(&m, [0.0, 0.0, 1.0]);
            if !(norm(axis) > 0.0) {
                return Err(p.error("to_world maps the spot's axis (+z) to zero"));
            }
            let intensity = p.color("intensity")?.unwrap_or([1.0; 3]);
            let cutoff = p.float_or("cutoff_angle", 20.0)?;
            let beam = p.float_or("beam_width", cutoff * 0.75)?;
            if p.plugin_named("texture").is_some() {
                return Err(p.error("a projected `texture` is not supported"));
            }
            let mut out = json!({"type": "spot", "position": position, "direction": axis,
                   "intensity": color_json(intensity), "cutoff_angle": cutoff, "beam_width": beam});
            // A lone <lookat>: its origin and target as written (the same
            // axis; niebla normalizes it in f32 as from a JSON scene).
            if let Some((_, Form::LookAt { origin, target, .. })) = &placed {
                out["position"] = json!(origin);
                out.as_object_mut().unwrap().remove("direction");
                out["target"] = json!(target);
            }
            out
        }
        "directional" => {
            let direction = match (p.vec3("direction")?, m) {
                (Some(_), Some(_)) => return Err(p.error("give `direction` or `to_world`, not both")),
                (Some(d), None) => d,
                (None, m) => vector(&m.unwrap_or(IDENTITY), [0.0, 0.0, 1.0]),
            };
            let irradiance = p.color("irradiance")?.unwrap_or([1.0; 3]);
            json!({"type": "directional", "direction": direction, "irradiance": color_json(irradiance)})
        }
        "constant" => {
            let radiance = p.color("radiance")?.unwrap_or([1.0; 3]);
            json!({"type": "constant", "radiance": color_json(radiance)})
        }
        "envmap" => {
            let (file, _) = c.file(&p, "filename")?;
            let scale = p.float_or("scale", 1.0)?;
            let mut out = json!({"type": "envmap", "file": file, "scale": scale});
            if let Some(m) = m.filter(|m| !is_identity(m)) {
                out["to_world"] = to_json(&m);
            }
            p.harmless(&["filter_type", "wrap_mode", "mis_compensation"], "ignored", &mut c.notes);
            out
        }
        "area" => return Err(p.error("an area emitter belongs inside a <shape>")),
        _ => return Err(p.error("not supported")),
    };
    // An emitter's medium: niebla takes it from the shapes around the light.
    for r in p.plugins("medium").into_iter().chain(p.plugin_named("medium")).chain(p.unnamed_refs()) {
        if c.target_tag(r) != Some("medium") {
            return Err(r.loc.error(format!("{}: not supported inside an emitter", r.describe())));
        }
        let name = c.medium(r)?;
        c.notes.push(format!(
            "{}: {}: medium \"{name}\": niebla takes the medium around a light from the shapes containing it",
            r.loc.at(),
            p.what()
        ));
    }
    p.harmless(&["sampling_weight"], "ignored", &mut c.notes);
    p.finish()?;
    Ok(out)
}
