//! Rebuilding a built scene after an edit, reusing what the edit left
//! alone: a live viewer changes the camera or a medium's coefficients many
//! times a second, and loading grids (files, procedural noise) and their
//! majorants again each time is what makes an edit slow.
//!
//! [`rebuild_scene`] accepts edits of the camera, of `render`, of the
//! scalar fields of media (coefficients, `scale`, phase function, emission
//! color and scale) and of point, spot, directional and constant lights
//! that keep their kind (intensity, color, position, direction, cone);
//! anything else needs [`super::build_scene`]. The result
//! is equal, field for field, to building the edited description from
//! scratch: density grids and their majorant grids are in density units
//! (the coefficients multiply them at render time), so they do not change
//! with the scalars, and the camera enters only the camera, the scene
//! bounds and the medium the camera sits in, which are recomputed with the
//! builder's own functions.

use std::path::Path;

use super::build::{build_camera, build_phase, build_simple_light, render_settings, scene_bounds};
use super::desc::*;
use super::{unused_media_warnings, BuiltScene, SceneError};
use crate::color::Rgb;
use crate::medium::{GridEmission, HomogeneousMedium, Medium};

/// What [`rebuild_scene`] changed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneEdit {
    /// The camera differs (position, orientation, field of view or size).
    pub camera: bool,
    /// Per medium (indexed like [`crate::world::Scene::media`]): its
    /// coefficients, phase function or emission scalars differ.
    pub media: Vec<bool>,
    /// Per light (indexed like [`crate::world::Scene::lights`]): its
    /// intensity, color, position or direction differs (the kind is the same).
    pub lights: Vec<bool>,
    /// The `render` block differs (integrator, samples, seed, sampler, exposure).
    pub render: bool,
}

impl SceneEdit {
    /// Whether some medium changed.
    pub fn any_medium(&self) -> bool {
        self.media.iter().any(|&m| m)
    }

    /// Whether some light changed.
    pub fn any_light(&self) -> bool {
        self.lights.iter().any(|&l| l)
    }

    /// Whether nothing but the camera (and possibly `render`) changed.
    pub fn camera_only(&self) -> bool {
        !self.any_medium() && !self.any_light()
    }
}

/// Copy the fields of `old` that [`rebuild_scene`] may change into `new`,
/// so that the two compare equal when nothing else differs; `false` when a
/// field of `new` that needs loading differs in kind (the medium changed
/// type, or an emission changed to or from a grid).
fn copy_scalars(new: &mut MediumDesc, old: &MediumDesc) -> bool {
    match (new, old) {
        (MediumDesc::Homogeneous(n), MediumDesc::Homogeneous(o)) => {
            *n = o.clone();
            true
        }
        (MediumDesc::Grid(n), MediumDesc::Grid(o)) => {
            n.coefficients = o.coefficients;
            n.scale = o.scale;
            n.phase = o.phase.clone();
            match (&mut n.emission, &o.emission) {
                (
                    None | Some(GridEmissionDesc::ProportionalToDensity { .. }),
                    None | Some(GridEmissionDesc::ProportionalToDensity { .. }),
                ) => n.emission = o.emission.clone(),
                (
                    Some(GridEmissionDesc::Field { color, emission_scale, .. }),
                    Some(GridEmissionDesc::Field { color: oc, emission_scale: os, .. }),
                ) => {
                    *color = *oc;
                    *emission_scale = *os;
                }
                (
                    Some(GridEmissionDesc::Temperature { emission_scale, .. }),
                    Some(GridEmissionDesc::Temperature { emission_scale: os, .. }),
                ) => *emission_scale = *os,
                _ => return false,
            }
            true
        }
        _ => false,
    }
}

/// The kind of a light [`rebuild_scene`] rebuilds in place (one without a
/// shape or a file); `None` for area lights and environment maps.
fn simple_light_kind(l: &LightDesc) -> Option<u8> {
    match l {
        LightDesc::Point(_) => Some(0),
        LightDesc::Spot(_) => Some(1),
        LightDesc::Directional(_) => Some(2),
        LightDesc::Constant(_) => Some(3),
        LightDesc::Area(_) | LightDesc::Envmap(_) => None,
    }
}

/// `old`, built from `old_desc`, rebuilt for `desc` when the two differ
/// only in the camera, `render`, the scalar fields of media and lights
/// without shapes or files that keep their kind (see the module); `None` when something else differs (build `desc` from scratch
/// then). Phase tables are read again (`base_dir` resolves them); grids are
/// reused. Errors are the builder's, at the same JSON paths.
///
/// ```
/// use niebla::scene::{build_scene, parse_scene_str, rebuild_scene, DEFAULT_SCENE};
/// let base = std::path::Path::new(".");
/// let desc = parse_scene_str(DEFAULT_SCENE, "<default>").unwrap();
/// let built = build_scene(&desc, "<default>", base).unwrap();
/// let mut moved = desc.clone();
/// let niebla::scene::CameraDesc::Perspective(c) = &mut moved.camera;
/// c.position[0] += 0.5;
/// let (rebuilt, edit) = rebuild_scene(&built, &desc, &moved, "<default>", base).unwrap().unwrap();
/// assert!(edit.camera && edit.camera_only());
/// let fresh = build_scene(&moved, "<default>", base).unwrap();
/// assert_eq!(rebuilt.scene.camera, fresh.scene.camera);
/// assert_eq!(rebuilt.scene.bounds, fresh.scene.bounds);
/// let mut shapes = desc.clone();
/// shapes.shapes.pop();
/// assert!(rebuild_scene(&built, &desc, &shapes, "<default>", base).is_none());
/// ```
pub fn rebuild_scene(
    old: &BuiltScene,
    old_desc: &SceneDesc,
    desc: &SceneDesc,
    source: &str,
    base_dir: &Path,
) -> Option<Result<(BuiltScene, SceneEdit), SceneError>> {
    // A moving medium's majorant and a moving shape's box depend on the
    // shutter: build afresh.
    let (CameraDesc::Perspective(a), CameraDesc::Perspective(b)) = (&old_desc.camera, &desc.camera);
    let moving = desc.media.values().any(|m| matches!(m, MediumDesc::Grid(g) if g.velocity.is_some()))
        || desc.shapes.iter().any(|s| s.motion.is_some())
        || desc.lights.iter().any(|l| matches!(l, LightDesc::Area(a) if a.shape.motion.is_some()));
    if moving && (a.shutter_open != b.shutter_open || a.shutter_close != b.shutter_close || a.fps != b.fps) {
        return None;
    }
    let mut probe = desc.clone();
    probe.camera = old_desc.camera.clone();
    probe.render = old_desc.render.clone();
    for (name, medium) in probe.media.iter_mut() {
        let old_medium = old_desc.media.get(name)?;
        if !copy_scalars(medium, old_medium) {
            return None;
        }
    }
    if probe.lights.len() != old_desc.lights.len() {
        return None;
    }
    for (light, old_light) in probe.lights.iter_mut().zip(&old_desc.lights) {
        if simple_light_kind(light).is_some() && simple_light_kind(light) == simple_light_kind(old_light) {
            *light = old_light.clone();
        }
    }
    if probe != *old_desc || old.scene.media.len() != desc.media.len() {
        return None;
    }
    Some(rebuild(old, old_desc, desc, source, base_dir))
}

fn rebuild(
    old: &BuiltScene,
    old_desc: &SceneDesc,
    desc: &SceneDesc,
    source: &str,
    base_dir: &Path,
) -> Result<(BuiltScene, SceneEdit), SceneError> {
    let mut scene = old.scene.clone();
    let mut edit = SceneEdit {
        camera: desc.camera != old_desc.camera,
        media: Vec::new(),
        lights: Vec::new(),
        render: desc.render != old_desc.render,
    };
    for (index, (l, old_l)) in desc.lights.iter().zip(&old_desc.lights).enumerate() {
        let changed = l != old_l;
        edit.lights.push(changed);
        if changed {
            scene.lights[index] = build_simple_light(l, &format!("lights[{index}]"), source)?
                .expect("rebuild_scene checked that only shapeless, fileless lights changed");
        }
    }
    // Media are in name order (BTreeMap) in both descriptions and the scene.
    for (index, ((name, m), old_m)) in desc.media.iter().zip(old_desc.media.values()).enumerate() {
        let changed = m != old_m;
        edit.media.push(changed);
        if !changed {
            continue;
        }
        let path = format!("media.{name}");
        let phase = build_phase(m.phase(), &format!("{path}.phase"), source, base_dir)?;
        scene.media[index] = match (m, &scene.media[index]) {
            (MediumDesc::Homogeneous(h), _) => {
                let (sigma_a, sigma_s) = h.sigma_a_sigma_s();
                let l_ve = h.emission.map_or(Rgb::ZERO, |e| e.l_ve.to_rgb());
                Medium::Homogeneous(HomogeneousMedium { sigma_a, sigma_s, l_ve, phase })
            }
            (MediumDesc::Grid(g), Medium::Grid(built)) => {
                let mut grid = built.clone();
                (grid.sigma_a, grid.sigma_s) = g.sigma_a_sigma_s();
                if let Some(albedo) = &mut grid.albedo {
                    albedo.scale = g.albedo_grid_scale();
                }
                grid.phase = phase;
                grid.emission = match (&g.emission, &built.emission) {
                    (None, _) => GridEmission::None,
                    (Some(GridEmissionDesc::ProportionalToDensity { l_ve }), _) => {
                        GridEmission::ProportionalToDensity(l_ve.to_rgb())
                    }
                    (
                        Some(GridEmissionDesc::Field { color, emission_scale, .. }),
                        GridEmission::Field { field, .. },
                    ) => GridEmission::Field { field: field.clone(), scale: color.to_rgb() * *emission_scale },
                    (
                        Some(GridEmissionDesc::Temperature { emission_scale, .. }),
                        GridEmission::Temperature { field, table, .. },
                    ) => {
                        GridEmission::Temperature { field: field.clone(), scale: *emission_scale, table: table.clone() }
                    }
                    _ => unreachable!("rebuild_scene checked that the emission keeps its kind"),
                };
                Medium::Grid(grid)
            }
            _ => unreachable!("rebuild_scene checked that the medium keeps its type"),
        };
    }
    if edit.camera {
        scene.camera = build_camera(&desc.camera, source)?;
    }
    if edit.camera || edit.any_light() {
        scene.bounds = scene_bounds(&scene.camera, &scene.objects, &scene.lights, &scene.media);
        scene.camera_medium = scene.medium_at(scene.camera.position);
    }
    let built = BuiltScene {
        scene,
        settings: render_settings(desc),
        integrator_spec: desc.render.integrator.clone(),
        warnings: unused_media_warnings(desc, source),
    };
    Ok((built, edit))
}
