//! `<bsdf>` into niebla surfaces: `diffuse`, `dielectric`, `conductor` and
//! `null` map to niebla's own; `roughconductor`, `roughdielectric`,
//! `thindielectric`, `plastic`, `roughplastic` and `twosided` are written
//! with Mitsuba's names and defaults (named indices of refraction replaced by
//! their numbers). A diffuse `reflectance`, a plastic's
//! `diffuse_reflectance` and a rough conductor's `specular_reflectance` may
//! be textures (`textures`); other parameters take constants.

use serde_json::{json, Map, Value};

use super::convert::{color_json, Converter};
use super::props::Props;
use super::textures::{color_or_texture, has_texture};
use super::xml::Node;
use crate::scene::SceneError;

/// Mitsuba 3's named indices of refraction (`ior.h`: Hecht, Optics, 4th
/// edition; 0 to 20 degrees Celsius, about 589 nm).
pub(super) const NAMED_IORS: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// An index of refraction: a `<float>` or a named material (`<string>`).
fn ior(p: &Props, name: &str, default: &str) -> Result<f64, SceneError> {
    if let Some(node) = p.node.children.iter().find(|c| c.attr("name") == Some(name)) {
        if node.tag == "string" {
            let s = p.string(name)?.unwrap_or(default);
            return lookup(p, name, s);
        }
        return Ok(p.float(name)?.unwrap_or(0.0));
    }
    lookup(p, name, default)
}

fn lookup(p: &Props, name: &str, material: &str) -> Result<f64, SceneError> {
    let lower = material.to_ascii_lowercase();
    NAMED_IORS.iter().find(|(n, _)| *n == lower).map(|(_, v)| *v).ok_or_else(|| {
        let names: Vec<&str> = NAMED_IORS.iter().map(|(n, _)| *n).collect();
        p.error(format!("`{name}`: unknown material \"{material}\"; expected a number or one of: {}", names.join(", ")))
    })
}

/// `specular_reflectance` and the like: accepted only as 1 for niebla's own BSDFs.
fn unit_only(p: &Props, name: &str) -> Result<(), SceneError> {
    match p.color(name)? {
        None => Ok(()),
        Some(c) if c == [1.0; 3] => Ok(()),
        Some(c) => Err(p.error(format!("`{name}` {c:?}: only 1 is supported for this bsdf"))),
    }
}

/// Microfacet keys: `distribution` (default beckmann) and `alpha` or
/// `alpha_u` + `alpha_v`. When `textured_alpha` (roughconductor,
/// roughdielectric), each may be a `<texture>` (or a `<ref>` to one); a
/// texture elsewhere (roughplastic) is an error at its line.
fn microfacet<'a>(
    c: &mut Converter<'a>,
    p: &Props<'a>,
    out: &mut Map<String, Value>,
    textured_alpha: bool,
) -> Result<(), SceneError> {
    let d = p.string("distribution")?.unwrap_or("beckmann");
    if d != "beckmann" && d != "ggx" {
        return Err(p.error(format!("`distribution` \"{d}\": expected beckmann or ggx")));
    }
    out.insert("distribution".into(), json!(d));
    let mut values = Vec::new();
    for name in ["alpha", "alpha_u", "alpha_v"] {
        let value = match p.plugin_named(name) {
            Some(t) if !textured_alpha => {
                return Err(t.loc.error(format!(
                    "{}: `{name}` as {}: a textured roughness is not supported for roughplastic (its coating \
                     tables are precomputed for one roughness, and Mitsuba 3 refuses a texture there too; give a \
                     <float>)",
                    p.what(),
                    t.describe()
                )));
            }
            Some(t) => Some(alpha_texture(c, t)?),
            None => p.float(name)?.map(|a| json!(a)),
        };
        values.push(value);
    }
    let mut values = values.into_iter();
    let (a, au, av) = (values.next().flatten(), values.next().flatten(), values.next().flatten());
    match (a, au, av) {
        (a, None, None) => {
            out.insert("alpha".into(), a.unwrap_or(json!(0.1)));
        }
        (None, Some(u), Some(v)) => {
            out.insert("alpha_u".into(), u);
            out.insert("alpha_v".into(), v);
        }
        _ => return Err(p.error("give `alpha`, or both `alpha_u` and `alpha_v`")),
    }
    Ok(())
}

/// A roughness `<texture>` (or `<ref>` to one) as niebla's texture object.
fn alpha_texture<'a>(c: &mut Converter<'a>, t: &'a Node) -> Result<Value, SceneError> {
    let node = c.resolve(t, "texture")?;
    let mut alpha = super::textures::convert_texture(c, node)?;
    if alpha["type"] == "checkerboard" {
        // Mitsuba 3's checkerboard gives its scalar value (`eval_1`, what a
        // roughness reads) from the other color than its color (`eval`):
        // color1 where `eval` gives color0 (checked against Mitsuba 3.9.1).
        // niebla's checkerboard has one rule, so the colors are swapped here.
        let (c0, c1) = (alpha["color0"].take(), alpha["color1"].take());
        alpha["color0"] = c1;
        alpha["color1"] = c0;
    }
    Ok(alpha)
}

/// True when a converted bsdf has a textured color (a textured roughness,
/// `alpha...`, does not count: each side of a `twosided` may have its own).
fn has_color_texture(bsdf: &Value) -> bool {
    bsdf.as_object().is_some_and(|o| o.iter().any(|(k, v)| !k.starts_with("alpha") && has_texture(v)))
}

/// Copies color `name` into `out` when given.
fn copy_color(p: &Props, name: &str, out: &mut Map<String, Value>) -> Result<(), SceneError> {
    if let Some(c) = p.color(name)? {
        out.insert(name.into(), color_json(c));
    }
    Ok(())
}

/// Conductor keys: `material`, or `eta` and `k`. Without `material` (or
/// with `material` "none"), Mitsuba 3 reads `eta` and `k` with the defaults
/// 0 and 1 (its `conductor.cpp` and `roughconductor.cpp`), a Fresnel
/// reflectance of exactly 1 at every angle (a purely imaginary index).
/// niebla's `roughconductor` JSON takes absent keys with the same defaults;
/// for the smooth `conductor` (whose JSON needs both) the importer writes
/// both, a missing one at its default.
fn conductor_index(p: &Props, out: &mut Map<String, Value>, rough: bool) -> Result<(), SceneError> {
    let material = p.string("material")?;
    let (eta, k) = (p.color("eta")?, p.color("k")?);
    match (material, eta, k) {
        (Some(m), None, None) if m != "none" => {
            out.insert("material".into(), json!(m));
        }
        (None | Some("none"), e, k) if rough => {
            if let Some(e) = e {
                out.insert("eta".into(), color_json(e));
            }
            if let Some(k) = k {
                out.insert("k".into(), color_json(k));
            }
        }
        (None | Some("none"), e, k) => {
            out.insert("eta".into(), color_json(e.unwrap_or([0.0; 3])));
            out.insert("k".into(), color_json(k.unwrap_or([1.0; 3])));
        }
        _ => return Err(p.error("give `material`, or `eta` and `k`, not both")),
    }
    Ok(())
}

/// The niebla JSON of a `<bsdf>` element.
pub(super) fn convert_bsdf<'a>(c: &mut Converter<'a>, node: &'a Node) -> Result<Value, SceneError> {
    let p = Props::new(node)?;
    let t = p.plugin_type()?;
    let mut out = Map::new();
    out.insert("type".into(), json!(t));
    match t {
        "null" => {}
        "diffuse" => {
            let r = color_or_texture(c, &p, "reflectance")?.unwrap_or_else(|| json!(0.5));
            out.insert("reflectance".into(), r);
        }
        "dielectric" => {
            out.insert("int_ior".into(), json!(ior(&p, "int_ior", "bk7")?));
            out.insert("ext_ior".into(), json!(ior(&p, "ext_ior", "air")?));
            unit_only(&p, "specular_reflectance")?;
            unit_only(&p, "specular_transmittance")?;
        }
        "conductor" => {
            conductor_index(&p, &mut out, false)?;
            if let Some(Value::String(m)) = out.get("material") {
                if crate::bsdf::conductor_preset(m).is_none() {
                    let names: Vec<&str> = crate::bsdf::CONDUCTOR_PRESETS.iter().map(|p| p.symbol).collect();
                    return Err(p.error(format!("material \"{m}\": niebla's conductors know {}", names.join(", "))));
                }
            }
            unit_only(&p, "specular_reflectance")?;
        }
        "roughconductor" => {
            microfacet(c, &p, &mut out, true)?;
            conductor_index(&p, &mut out, true)?;
            if let Some(r) = color_or_texture(c, &p, "specular_reflectance")? {
                out.insert("specular_reflectance".into(), r);
            }
        }
        "roughdielectric" | "thindielectric" => {
            if t == "roughdielectric" {
                microfacet(c, &p, &mut out, true)?;
            }
            out.insert("int_ior".into(), json!(ior(&p, "int_ior", "bk7")?));
            out.insert("ext_ior".into(), json!(ior(&p, "ext_ior", "air")?));
            copy_color(&p, "specular_reflectance", &mut out)?;
            copy_color(&p, "specular_transmittance", &mut out)?;
        }
        "plastic" | "roughplastic" => {
            if t == "roughplastic" {
                microfacet(c, &p, &mut out, false)?;
                if out.contains_key("alpha_u") {
                    return Err(p.error("roughplastic is isotropic: give `alpha`"));
                }
            }
            let d = color_or_texture(c, &p, "diffuse_reflectance")?.unwrap_or_else(|| json!(0.5));
            out.insert("diffuse_reflectance".into(), d);
            out.insert("specular_reflectance".into(), color_json(p.color("specular_reflectance")?.unwrap_or([1.0; 3])));
            out.insert("int_ior".into(), json!(ior(&p, "int_ior", "polypropylene")?));
            out.insert("ext_ior".into(), json!(ior(&p, "ext_ior", "air")?));
            out.insert("nonlinear".into(), json!(p.boolean("nonlinear")?.unwrap_or(false)));
        }
        "twosided" => {
            let mut inner = p.plugins("bsdf");
            inner.extend(p.unnamed_refs());
            let sides = inner
                .iter()
                .map(|n| {
                    let n = c.resolve(n, "bsdf")?;
                    convert_bsdf(c, n)
                })
                .collect::<Result<Vec<_>, _>>()?;
            if sides.len() == 2 && sides[0] != sides[1] && has_color_texture(&sides[0]) && has_color_texture(&sides[1])
            {
                return Err(p.error("textures on both sides are not supported (niebla textures one color per surface)"));
            }
            match sides.len() {
                1 => out.insert("bsdf".into(), sides.into_iter().next().unwrap_or(Value::Null)),
                2 => out.insert("bsdf".into(), Value::Array(sides)),
                n => return Err(p.error(format!("expected one or two nested bsdfs, found {n}"))),
            };
        }
        _ => return Err(p.error("not supported")),
    }
    p.harmless(&["sample_visible"], "ignored (niebla always samples visible normals)", &mut c.notes);
    p.finish()?;
    Ok(Value::Object(out))
}
