//! From description to render-ready scene: names become typed ids, transforms
//! become matrices, phase tables are loaded, and each shape without an explicit
//! `exterior` gets the medium that encloses it.

use std::path::Path;

use glam::{Affine3A, Mat3, Mat4};

use super::desc::*;
use super::{RenderSettings, Scene, SceneError, SceneObject};
use crate::bsdf::Bsdf;
use crate::camera::{CameraMotion, PerspectiveCamera};
use crate::color::Rgb;
use crate::geometry::{
    AxisAlignedBox, Disk, Motion, MotionError, MovingShape, Rectangle, Shape, Sphere, Transform, TransformMotion,
};
use crate::integrator::IntegratorSettings;
use crate::light::{
    AreaLight, AreaMotion, AreaShape, ConstantLight, DirectionalLight, EnvironmentMap, Light, MeshLight, PointLight,
    SpotLight,
};
use crate::math::{Frame, Vec3};
use crate::medium::MediumId;
use crate::phase::{PhaseFunction, Schlick, Tabulated};

/// A scene ready to render and the render settings its file asked for.
#[derive(Clone, Debug)]
pub struct BuiltScene {
    /// The scene.
    pub scene: Scene,
    /// Integrator, spp, seed and exposure from the file.
    pub settings: RenderSettings,
    /// The file's `render.integrator` object as written (for overrides that
    /// change one field of it).
    pub integrator_spec: crate::scene::IntegratorSpec,
    /// Things in the file that are valid but almost surely not what was
    /// meant (a medium nothing refers to), each a whole message naming the
    /// file and the JSON path. Shown by `niebla render` and `niebla info`,
    /// raised as Python warnings.
    pub warnings: Vec<String>,
}

/// Limits of a scene build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// Bytes the scene's large buffers (grids and their majorants, files
    /// read into memory, VDB trees, environment maps) may take together;
    /// a source whose declared size would exceed what is left is refused
    /// before it is allocated, with an error naming its field and the
    /// estimated size. Default: half of the machine's memory
    /// ([`crate::limits::default_memory_limit`]).
    pub max_memory: u64,
}

impl Default for BuildOptions {
    fn default() -> BuildOptions {
        BuildOptions { max_memory: crate::limits::default_memory_limit() }
    }
}

/// Build a validated description. `source` names the file in messages;
/// `base_dir` resolves relative paths (phase tables, grids, environment
/// maps). Uses the default [`BuildOptions`].
pub fn build_scene(desc: &SceneDesc, source: &str, base_dir: &Path) -> Result<BuiltScene, SceneError> {
    build_scene_with_options(desc, source, base_dir, &BuildOptions::default())
}

/// Files read by scene builds and kept for the next build: meshes (with
/// their BVHs), image textures and environment maps, keyed by resolved path
/// and the options that change the data. The frames of a sequence share one
/// cache, so a file whose name has no frame pattern is read once; what a
/// build does not use is dropped at its end. Each build charges its memory
/// budget for what it uses as if it had read it, so limits do not depend on
/// the cache. Grids are not cached.
#[derive(Default)]
pub struct SceneCache {
    meshes: std::sync::Mutex<super::build_mesh::MeshLoader>,
    textures: std::sync::Mutex<super::build_texture::TextureLoader>,
    envmaps: std::sync::Mutex<EnvmapCache>,
}

/// What makes two environment lights share their map: the file, the scale
/// and the rotation (bits of the floats).
type EnvmapKey = (std::path::PathBuf, u32, [u32; 9]);

/// The environment maps of [`SceneCache`].
#[derive(Default)]
struct EnvmapCache {
    maps: std::collections::HashMap<EnvmapKey, std::sync::Arc<EnvironmentMap>>,
    used: std::collections::HashSet<EnvmapKey>,
}

impl SceneCache {
    /// Number of files held (meshes, textures, environment maps).
    pub fn len(&self) -> usize {
        self.meshes.lock().map_or(0, |m| m.len())
            + self.textures.lock().map_or(0, |t| t.len())
            + self.envmaps.lock().map_or(0, |e| e.maps.len())
    }

    /// Whether no file is held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// [`build_scene`] within the limits of `options`.
///
/// ```
/// use niebla::scene::{build_scene_with_options, parse_scene_str, BuildOptions};
/// let text = r#"{"version": 1,
///     "camera": {"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 8, "height": 8},
///     "media": {"cloud": {"type": "grid", "sigma_t": 1, "albedo": 0.9,
///         "density": {"type": "procedural", "shape": "cloud", "resolution": 512}}}}"#;
/// let desc = parse_scene_str(text, "cloud.json").unwrap();
/// let err = build_scene_with_options(&desc, "cloud.json", ".".as_ref(), &BuildOptions { max_memory: 64 << 20 })
///     .unwrap_err();
/// assert_eq!(err.path, "media.cloud.density.resolution");
/// assert!(err.message.contains("512 MiB"), "{err}");
/// ```
pub fn build_scene_with_options(
    desc: &SceneDesc,
    source: &str,
    base_dir: &Path,
    options: &BuildOptions,
) -> Result<BuiltScene, SceneError> {
    build_scene_cached(desc, source, base_dir, options, &SceneCache::default())
}

/// [`build_scene_with_options`] taking meshes, textures and environment
/// maps from `cache` where an earlier build read them (the same file with
/// the same options) and leaving there what this build read. The scene is
/// the same as without the cache.
pub fn build_scene_cached(
    desc: &SceneDesc,
    source: &str,
    base_dir: &Path,
    options: &BuildOptions,
    cache: &SceneCache,
) -> Result<BuiltScene, SceneError> {
    let poisoned = || SceneError::new(source, "", "a previous scene build panicked");
    let mut meshes = cache.meshes.lock().map_err(|_| poisoned())?;
    let mut textures = cache.textures.lock().map_err(|_| poisoned())?;
    let mut envmaps = cache.envmaps.lock().map_err(|_| poisoned())?;
    let built = build_with_loaders(desc, source, base_dir, options, (&mut meshes, &mut textures, &mut envmaps));
    meshes.finish_build();
    textures.finish_build();
    let used = std::mem::take(&mut envmaps.used);
    envmaps.maps.retain(|key, _| used.contains(key));
    built
}

/// The loaders of one build.
type Loaders<'a> =
    (&'a mut super::build_mesh::MeshLoader, &'a mut super::build_texture::TextureLoader, &'a mut EnvmapCache);

/// The body of [`build_scene_cached`].
fn build_with_loaders(
    desc: &SceneDesc,
    source: &str,
    base_dir: &Path,
    options: &BuildOptions,
    (meshes, textures, envmaps): Loaders,
) -> Result<BuiltScene, SceneError> {
    let err = |path: &str, message: String| SceneError::new(source, path, message);
    let mut budget = crate::limits::MemoryBudget::new(options.max_memory);

    // Media, in name order (BTreeMap), so ids are stable.
    let mut media = Vec::new();
    let mut medium_names = Vec::new();
    for (name, m) in &desc.media {
        let path = format!("media.{name}");
        let phase = build_phase(m.phase(), &format!("{path}.phase"), source, base_dir)?;
        let medium = super::build_medium::build_medium(m, &path, source, base_dir, phase, &mut budget)?;
        media.push(medium);
        medium_names.push(name.clone());
    }
    let medium_id = |name: &Option<String>| -> Option<MediumId> {
        name.as_ref().and_then(|n| medium_names.iter().position(|m| m == n)).map(|i| MediumId(i as u32))
    };

    // Shapes. Moving ones are bounded over the camera's shutter.
    let CameraDesc::Perspective(camera_desc) = &desc.camera;
    let shutter = [camera_desc.shutter_open, camera_desc.shutter_close];
    let mut objects = Vec::new();
    let mut explicit_exterior = Vec::new();
    for (i, s) in desc.shapes.iter().enumerate() {
        let path = format!("shapes[{i}]");
        let bounds_medium = s.interior.is_some() || s.exterior.is_some();
        let shape = match &s.geometry {
            GeometryDesc::Sphere(d) => Shape::Sphere(build_sphere(d)),
            GeometryDesc::Box(d) => Shape::Box(AxisAlignedBox { min: Vec3::from(d.min), max: Vec3::from(d.max) }),
            GeometryDesc::Rectangle(d) => {
                let t = build_transform(&d.to_world)
                    .ok_or_else(|| err(&format!("{path}.to_world"), "transform is singular (zero scale?)".into()))?;
                Shape::Rectangle(Rectangle::new(t))
            }
            GeometryDesc::Disk(d) => {
                let t = build_transform(&d.to_world)
                    .ok_or_else(|| err(&format!("{path}.to_world"), "transform is singular (zero scale?)".into()))?;
                Shape::Disk(Disk::new(t))
            }
            GeometryDesc::Mesh(d) => {
                let t = build_transform(&d.to_world)
                    .ok_or_else(|| err(&format!("{path}.to_world"), "transform is singular (zero scale?)".into()))?;
                Shape::Mesh(meshes.instance(d, t, bounds_medium, &path, source, base_dir, &mut budget)?)
            }
        };
        let shape = match &s.motion {
            None => shape,
            Some(m) => moving_shape(&s.geometry, m, shape, shutter, &path, source)?,
        };
        let mut texture = None;
        let mut roughness = None;
        let bsdf = match &s.bsdf {
            BsdfDesc::Null => Bsdf::Null,
            BsdfDesc::Diffuse { reflectance: ReflectanceDesc::Color(c) } => Bsdf::Diffuse { reflectance: c.to_rgb() },
            BsdfDesc::Diffuse { reflectance: ReflectanceDesc::Texture(t) } => {
                let field = format!("{path}.bsdf.reflectance");
                texture = Some(std::sync::Arc::new(textures.texture(t, &field, source, base_dir, &mut budget)?));
                // The constant is unused: every hit looks the texture up.
                Bsdf::Diffuse { reflectance: Rgb::splat(0.5) }
            }
            BsdfDesc::Dielectric { int_ior, ext_ior } => Bsdf::dielectric(*int_ior, *ext_ior),
            BsdfDesc::Conductor(ConductorDesc::Material(name)) => Bsdf::conductor_preset(name)
                .ok_or_else(|| err(&format!("{path}.bsdf.material"), format!("unknown conductor \"{name}\"")))?,
            BsdfDesc::Conductor(ConductorDesc::Index { eta, k }) => {
                Bsdf::Conductor { eta: eta.to_rgb(), k: k.to_rgb() }
            }
            BsdfDesc::Conductor(ConductorDesc::Reflectance(r)) => Bsdf::conductor_from_reflectance(r.to_rgb()),
            other => {
                let mut ctx = super::build_surfaces::TextureContext {
                    loader: &mut *textures,
                    source,
                    base_dir,
                    budget: &mut budget,
                };
                let (bsdf, t) = super::build_surfaces::build_surface(other, &format!("{path}.bsdf"), &mut ctx)?;
                texture = t.color;
                roughness = t.roughness;
                bsdf
            }
        };
        let interior = medium_id(&s.interior);
        let exterior = medium_id(&s.exterior);
        // Only a bsdf that may be anisotropic (a constant pair, or
        // roughness textures) pays for the tangent.
        let dpdu_frame = s.tangent_frame == TangentFrameDesc::Dpdu && (bsdf.is_anisotropic() || roughness.is_some());
        objects.push(SceneObject {
            shape,
            bsdf,
            interior,
            exterior,
            bounds_medium,
            emitter: None,
            texture,
            roughness,
            dpdu_frame,
        });
        explicit_exterior.push(s.exterior.is_some());
    }
    let ambient_medium = medium_id(&desc.ambient_medium);

    // Lights.
    let mut lights = Vec::new();
    for (i, l) in desc.lights.iter().enumerate() {
        let path = format!("lights[{i}]");
        lights.push(match l {
            LightDesc::Point(_) | LightDesc::Spot(_) | LightDesc::Directional(_) | LightDesc::Constant(_) => {
                build_simple_light(l, &path, source)?.expect("a light without a shape or file")
            }
            LightDesc::Area(a) => {
                let shape_path = format!("{path}.shape");
                let area_shape = match &a.shape.geometry {
                    GeometryDesc::Sphere(d) => AreaShape::Sphere(build_sphere(d)),
                    GeometryDesc::Rectangle(d) => {
                        let t = build_transform(&d.to_world).ok_or_else(|| {
                            err(&format!("{shape_path}.to_world"), "transform is singular (zero scale?)".into())
                        })?;
                        AreaShape::Rectangle(Rectangle::new(t))
                    }
                    GeometryDesc::Disk(d) => {
                        let t = build_transform(&d.to_world).ok_or_else(|| {
                            err(&format!("{shape_path}.to_world"), "transform is singular (zero scale?)".into())
                        })?;
                        AreaShape::Disk(Disk::new(t))
                    }
                    GeometryDesc::Mesh(d) => {
                        let t = build_transform(&d.to_world).ok_or_else(|| {
                            err(&format!("{shape_path}.to_world"), "transform is singular (zero scale?)".into())
                        })?;
                        let instance = meshes.instance(d, t, false, &shape_path, source, base_dir, &mut budget)?;
                        let what = d.file.as_ref().map_or(String::new(), |f| format!("{f}: "));
                        let mesh = MeshLight::new(instance).ok_or_else(|| {
                            err(
                                &shape_path,
                                format!("{what}an emitting mesh must have a positive, finite area (all its triangles are degenerate)"),
                            )
                        })?;
                        AreaShape::Mesh(std::sync::Arc::new(mesh))
                    }
                    GeometryDesc::Box(_) => {
                        return Err(err(&shape_path, "an area light is a rectangle, a disk, a sphere or a mesh".into()))
                    }
                };
                let mut light = AreaLight::new(area_shape, a.radiance.to_rgb(), a.two_sided)
                    .map_err(|e| err(&shape_path, e.to_string()))?;
                // The emitter is also a black surface that rays hit.
                let shape = match &light.shape {
                    AreaShape::Sphere(s) => Shape::Sphere(*s),
                    AreaShape::Rectangle(r) => Shape::Rectangle(*r),
                    AreaShape::Disk(d) => Shape::Disk(*d),
                    AreaShape::Mesh(m) => Shape::Mesh(m.instance.clone()),
                };
                // A moving emitter: the surface rays hit and the light
                // sampled move together (the same poses).
                let shape = match &a.shape.motion {
                    None => shape,
                    Some(m) => {
                        let moving = moving_shape(&a.shape.geometry, m, shape, shutter, &shape_path, source)?;
                        if let Shape::Moving(ms) = &moving {
                            light.motion = Some(Box::new(match &ms.motion {
                                Motion::Sphere { end, .. } => AreaMotion::Sphere(*end),
                                Motion::Rectangle(t) | Motion::Disk(t) => AreaMotion::Transform(*t),
                                Motion::Box { .. } | Motion::Mesh(..) => {
                                    unreachable!("area lights are not boxes, and validation refuses moving meshes")
                                }
                            }));
                            // Sampling uses the interpolated pose from time 0.
                            if let Some(still) = ms.still_at(0.0) {
                                light.shape = match still {
                                    Shape::Sphere(s) => AreaShape::Sphere(s),
                                    Shape::Rectangle(r) => AreaShape::Rectangle(r),
                                    Shape::Disk(d) => AreaShape::Disk(d),
                                    _ => light.shape.clone(),
                                };
                            }
                        }
                        moving
                    }
                };
                objects.push(SceneObject {
                    shape,
                    bsdf: Bsdf::Diffuse { reflectance: Rgb::ZERO },
                    interior: None,
                    exterior: None,
                    bounds_medium: false,
                    emitter: Some(i as u32),
                    texture: None,
                    roughness: None,
                    dpdu_frame: false,
                });
                explicit_exterior.push(false);
                Light::Area(light)
            }
            LightDesc::Envmap(e) => {
                let file = base_dir.join(&e.file);
                let t = build_transform(&e.to_world)
                    .ok_or_else(|| err(&format!("{path}.to_world"), "transform is singular".into()))?;
                let rotation = glam::Mat3::from(t.to_world.matrix3);
                charge_envmap(&file, &mut budget).map_err(|message| err(&format!("{path}.file"), message))?;
                let key = (file.clone(), e.scale.to_bits(), rotation.to_cols_array().map(f32::to_bits));
                let map = match envmaps.maps.get(&key) {
                    Some(map) => map.clone(),
                    None => {
                        let map = EnvironmentMap::from_exr(&file, e.scale, rotation)
                            .map_err(|error| err(&format!("{path}.file"), error.to_string()))?;
                        let map = std::sync::Arc::new(map);
                        envmaps.maps.insert(key.clone(), map.clone());
                        map
                    }
                };
                envmaps.used.insert(key);
                Light::Environment(map)
            }
        });
    }

    let camera = build_camera(&desc.camera, source)?;
    // Moving media see the shutter: their majorants grow by the largest
    // displacement over it.
    for m in &mut media {
        if let crate::medium::Medium::Grid(g) = m {
            g.set_shutter(camera.shutter, camera_desc.fps);
        }
    }
    let bounds = scene_bounds(&camera, &objects, &lights, &media);

    let mut scene = Scene {
        camera,
        objects,
        media,
        medium_names,
        lights,
        ambient_medium,
        camera_medium: None,
        bounds,
        accel: Default::default(),
        transparent_background: desc.film.transparent,
    };
    assign_enclosing_exteriors(&mut scene, &explicit_exterior);
    scene.camera_medium = scene.medium_at(scene.camera.position);

    let settings = render_settings(desc);
    Ok(BuiltScene {
        scene,
        settings,
        integrator_spec: desc.render.integrator.clone(),
        warnings: unused_media_warnings(desc, source)
            .into_iter()
            .chain(light_rotation_warnings(desc, source))
            .collect(),
    })
}

/// The shape `still` (built from `geometry`, its pose at time 0) moving to
/// the pose `motion` gives at time 1, seen through `shutter` (errors at
/// `path.motion`).
fn moving_shape(
    geometry: &GeometryDesc,
    motion: &ShapeMotionDesc,
    still: Shape,
    shutter: [f32; 2],
    path: &str,
    source: &str,
) -> Result<Shape, SceneError> {
    let at = format!("{path}.motion");
    let err = |path: &str, message: String| SceneError::new(source, path, message);
    let end_transform = |to_world: &TransformDesc| -> Result<Transform, SceneError> {
        build_transform(motion.to_world.as_ref().unwrap_or(to_world))
            .ok_or_else(|| err(&format!("{at}.to_world"), "transform is singular (zero scale?)".into()))
    };
    let transform_motion = |t0: &Transform, to_world: &TransformDesc| {
        let t1 = end_transform(to_world)?;
        TransformMotion::new(&t0.to_world, &t1.to_world).map_err(|e| {
            let field = if matches!(e, MotionError::NotDecomposable { time } if time == 0.0) {
                format!("{path}.to_world")
            } else {
                format!("{at}.to_world")
            };
            err(&field, e.to_string())
        })
    };
    let kind = match (geometry, still) {
        (GeometryDesc::Sphere(d), Shape::Sphere(start)) => {
            let end = Sphere::new(Vec3::from(motion.center.unwrap_or(d.center)), motion.radius.unwrap_or(d.radius))
                .with_rotation(start.rotation);
            Motion::Sphere { start, end }
        }
        (GeometryDesc::Box(d), Shape::Box(start)) => {
            let end = AxisAlignedBox {
                min: Vec3::from(motion.min.unwrap_or(d.min)),
                max: Vec3::from(motion.max.unwrap_or(d.max)),
            };
            Motion::Box { start, end }
        }
        (GeometryDesc::Rectangle(d), Shape::Rectangle(r)) => {
            Motion::Rectangle(transform_motion(&r.transform, &d.to_world)?)
        }
        (GeometryDesc::Disk(d), Shape::Disk(r)) => Motion::Disk(transform_motion(&r.transform, &d.to_world)?),
        (GeometryDesc::Mesh(d), Shape::Mesh(m)) => {
            let t = transform_motion(&m.transform, &d.to_world)?;
            Motion::Mesh(m, t)
        }
        _ => return Err(err(&at, "the shape and its description disagree (internal)".into())),
    };
    let moving = MovingShape::new(kind, shutter).map_err(|e| err(&at, e.to_string()))?;
    Ok(Shape::Moving(Box::new(moving)))
}

/// A point, spot, directional or constant light (errors at `path`); `None`
/// for an area light or an environment map, which need shapes or files.
pub(super) fn build_simple_light(l: &LightDesc, path: &str, source: &str) -> Result<Option<Light>, SceneError> {
    let err = |path: &str, message: String| SceneError::new(source, path, message);
    Ok(Some(match l {
        LightDesc::Point(p) => {
            Light::Point(PointLight { position: Vec3::from(p.position), intensity: p.intensity.to_rgb() })
        }
        LightDesc::Spot(s) => {
            let position = Vec3::from(s.position);
            let axis = match s.aim {
                SpotAimDesc::Target(t) => Vec3::from(t) - position,
                SpotAimDesc::Direction(d) => Vec3::from(d),
            };
            let axis = axis
                .try_normalize()
                .ok_or_else(|| err(path, "spot light target equals its position (no direction)".into()))?;
            Light::Spot(SpotLight {
                position,
                frame: Frame::from_z(axis),
                intensity: s.intensity.to_rgb(),
                cutoff_angle: s.cutoff_angle.to_radians(),
                beam_width: s.beam_width.to_radians(),
            })
        }
        LightDesc::Directional(d) => Light::Directional(DirectionalLight {
            direction: Vec3::from(d.direction)
                .try_normalize()
                .ok_or_else(|| err(&format!("{path}.direction"), "must be a non-zero vector".into()))?,
            irradiance: d.irradiance.to_rgb(),
        }),
        LightDesc::Constant(c) => Light::Constant(ConstantLight { radiance: c.radiance.to_rgb() }),
        LightDesc::Area(_) | LightDesc::Envmap(_) => return Ok(None),
    }))
}

/// The camera of a scene description (errors at `camera`).
pub(super) fn build_camera(desc: &CameraDesc, source: &str) -> Result<PerspectiveCamera, SceneError> {
    let CameraDesc::Perspective(c) = desc;
    let mut camera = PerspectiveCamera::look_at(
        Vec3::from(c.position),
        Vec3::from(c.target),
        Vec3::from(c.up),
        c.fov_y,
        c.width,
        c.height,
    )
    .ok_or_else(|| {
        SceneError::new(source, "camera", "position, target and up do not define a view (parallel or equal)")
    })?;
    camera.shutter = [c.shutter_open, c.shutter_close];
    camera.motion = c.motion.as_ref().map(|m| {
        let pair = |at0: [f32; 3], at1: Option<[f32; 3]>| [Vec3::from(at0), Vec3::from(at1.unwrap_or(at0))];
        CameraMotion { position: pair(c.position, m.position), target: pair(c.target, m.target), up: pair(c.up, m.up) }
    });
    Ok(camera)
}

/// Bounds of everything positioned: the camera, the shapes, the lights with
/// a position and the grid media's boxes ([`Scene::bounds`]).
pub(super) fn scene_bounds(
    camera: &PerspectiveCamera,
    objects: &[SceneObject],
    lights: &[Light],
    media: &[crate::medium::Medium],
) -> (Vec3, Vec3) {
    let mut lo = camera.position;
    let mut hi = camera.position;
    for o in objects {
        let (a, b) = o.shape.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    for l in lights {
        if let Some(p) = l.point_position() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    for m in media {
        if let crate::medium::Medium::Grid(g) = m {
            lo = lo.min(g.world_bounds.0);
            hi = hi.max(g.world_bounds.1);
        }
    }
    (lo, hi)
}

/// The render settings a description asks for (`render` and `film`).
pub(super) fn render_settings(desc: &SceneDesc) -> RenderSettings {
    RenderSettings {
        integrator: integrator_settings(&desc.render.integrator),
        spp: desc.render.spp,
        seed: desc.render.seed,
        sampler: desc.render.sampler,
        exposure: desc.render.exposure,
        film: crate::scene::FilmSettings::from_desc(&desc.film),
    }
}

/// A warning for each medium that no shape names as `interior` or
/// `exterior` and that is not the `ambient_medium`: it fills no region of
/// space, so the render shows nothing of it.
///
/// ```
/// use niebla::scene::{build_scene, parse_scene_str};
/// let text = r#"{"version": 1,
///     "camera": {"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 8, "height": 8},
///     "media": {"smoke": {"sigma_a": 0.1, "sigma_s": 1}}}"#;
/// let built = build_scene(&parse_scene_str(text, "s.json").unwrap(), "s.json", ".".as_ref()).unwrap();
/// assert_eq!(built.warnings.len(), 1);
/// assert!(built.warnings[0].starts_with("s.json: media.smoke: medium \"smoke\" is not used"));
/// ```
pub fn unused_media_warnings(desc: &SceneDesc, source: &str) -> Vec<String> {
    let used = |name: &str| {
        desc.ambient_medium.as_deref() == Some(name)
            || desc.shapes.iter().any(|s| s.interior.as_deref() == Some(name) || s.exterior.as_deref() == Some(name))
    };
    desc.media
        .keys()
        .filter(|name| !used(name))
        .map(|name| {
            format!(
                "{source}: media.{name}: medium {name:?} is not used: no shape has it as \"interior\" or \"exterior\" \
                 and it is not the \"ambient_medium\", so it fills no space and renders nothing; add a shape around it \
                 with \"interior\": {name:?} (e.g. a box over its bounds) or set \"ambient_medium\": {name:?}"
            )
        })
        .collect()
}

/// Warnings (file, field) for area lights whose sphere has a `"rotation"`:
/// it turns only the sphere's uv frame, which a light's uniform radiance
/// does not use, so it changes nothing in the image.
fn light_rotation_warnings(desc: &SceneDesc, source: &str) -> Vec<String> {
    desc.lights
        .iter()
        .enumerate()
        .filter_map(|(i, l)| match l {
            LightDesc::Area(a) => match &a.shape.geometry {
                GeometryDesc::Sphere(s) if s.rotation.is_some() => Some(format!(
                    "{source}: lights[{i}].shape.rotation: has no effect on an area light (the rotation turns only a \
                     sphere's uv frame, and a light's radiance is uniform); it can be removed"
                )),
                _ => None,
            },
            _ => None,
        })
        .collect()
}

/// Give each medium-bounding shape without an explicit `exterior` the medium
/// of the innermost other closed shape that contains its whole bounding box,
/// else the ambient medium (the same rule that places the camera; see
/// ARCHITECTURE.md, "Which medium").
fn assign_enclosing_exteriors(scene: &mut Scene, explicit: &[bool]) {
    for (i, &is_explicit) in explicit.iter().enumerate() {
        if is_explicit || !scene.objects[i].bounds_medium {
            continue;
        }
        let (lo, hi) = scene.objects[i].shape.bounds();
        let corners = (0..8).map(|k| {
            Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            )
        });
        let corners: Vec<Vec3> = corners.collect();
        let mut best: Option<(f32, MediumId)> = None;
        for (j, other) in scene.objects.iter().enumerate() {
            let Some(id) = other.interior else { continue };
            if j == i || !other.shape.is_closed() {
                continue;
            }
            let v = other.shape.volume();
            if v > scene.objects[i].shape.volume()
                && corners.iter().all(|&p| other.shape.contains(p))
                && best.is_none_or(|(bv, _)| v < bv)
            {
                best = Some((v, id));
            }
        }
        scene.objects[i].exterior = best.map(|(_, id)| id).or(scene.ambient_medium);
    }
}

/// Bytes per texel an environment map takes: its RGB texels and the
/// marginal and conditional distributions that sample it.
const ENVMAP_BYTES_PER_TEXEL: u64 = 12 + 2 * 8;

/// Charges an environment map's declared size (read from the EXR header)
/// before its pixels are read. Unreadable headers are left to the reader,
/// which reports them.
fn charge_envmap(file: &Path, budget: &mut crate::limits::MemoryBudget) -> Result<(), String> {
    let Ok(meta) = exr::meta::MetaData::read_from_file(file, false) else { return Ok(()) };
    let Some(header) = meta.headers.first() else { return Ok(()) };
    let (w, h) = (header.layer_size.width() as u64, header.layer_size.height() as u64);
    budget
        .charge(w.saturating_mul(h).saturating_mul(ENVMAP_BYTES_PER_TEXEL))
        .map_err(|why| format!("{}: the {w} x {h} environment map {why}", file.display()))
}

/// Integrator settings of a scene file's `render.integrator` (read by the
/// integrator registry when the file was parsed).
pub fn integrator_settings(spec: &IntegratorSpec) -> IntegratorSettings {
    spec.settings
}

/// A sphere from its description, turned by its `rotation` if it has one.
fn build_sphere(d: &SphereDesc) -> Sphere {
    Sphere::new(Vec3::from(d.center), d.radius).with_rotation(d.rotation.as_ref().map(build_rotation))
}

/// The local-to-world rotation a sphere's `rotation` describes: about x,
/// then y, then z (degrees, right-handed, as [`Transform::from_components`]),
/// or its row-major matrix as written.
fn build_rotation(desc: &RotationDesc) -> Mat3 {
    match *desc {
        RotationDesc::Angles([x, y, z]) => {
            Mat3::from_rotation_z(z.to_radians())
                * Mat3::from_rotation_y(y.to_radians())
                * Mat3::from_rotation_x(x.to_radians())
        }
        RotationDesc::Matrix(rows) => Mat3::from_cols_array_2d(&rows).transpose(),
    }
}

/// Transform from its description: scale, rotate x, y, z (degrees), translate;
/// or a row-major 4x4 matrix whose last row must be (0, 0, 0, 1).
pub fn build_transform(desc: &TransformDesc) -> Option<Transform> {
    match *desc {
        TransformDesc::Components { scale, rotate_x, rotate_y, rotate_z, translate } => Transform::from_components(
            Vec3::from(scale),
            Vec3::new(rotate_x, rotate_y, rotate_z),
            Vec3::from(translate),
        ),
        TransformDesc::Matrix(rows) => {
            let m = Mat4::from_cols_array_2d(&rows).transpose();
            if rows[3] != [0.0, 0.0, 0.0, 1.0] {
                return None;
            }
            Transform::new(Affine3A::from_mat4(m))
        }
    }
}

pub(super) fn build_phase(
    desc: &PhaseDesc,
    path: &str,
    source: &str,
    base_dir: &Path,
) -> Result<PhaseFunction, SceneError> {
    let err = |e: crate::phase::PhaseError| SceneError::new(source, path, e.to_string());
    Ok(match desc {
        PhaseDesc::Isotropic => PhaseFunction::isotropic(),
        PhaseDesc::HenyeyGreenstein { g } => {
            PhaseFunction::HenyeyGreenstein(crate::phase::HenyeyGreenstein::new(*g).map_err(err)?)
        }
        PhaseDesc::DoubleHenyeyGreenstein { w, g1, g2 } => {
            PhaseFunction::DoubleHg(crate::phase::DoubleHg::new(*w, *g1, *g2).map_err(err)?)
        }
        PhaseDesc::Schlick(SchlickDesc::K(k)) => PhaseFunction::Schlick(Schlick::new(*k).map_err(err)?),
        PhaseDesc::Schlick(SchlickDesc::G(g)) => PhaseFunction::Schlick(Schlick::with_mean_cosine(*g).map_err(err)?),
        PhaseDesc::Rayleigh => PhaseFunction::rayleigh(),
        PhaseDesc::CornetteShanks { g } => {
            PhaseFunction::CornetteShanks(crate::phase::CornetteShanks::new(*g).map_err(err)?)
        }
        PhaseDesc::Tabulated { file, column } => {
            let full = base_dir.join(file);
            let table = Tabulated::from_csv_file(&full, column)
                .map_err(|e| SceneError::new(source, format!("{path}.file"), e.to_string()))?;
            PhaseFunction::tabulated(table)
        }
        PhaseDesc::TabulatedInline { mu, p } => PhaseFunction::tabulated(
            Tabulated::from_cosines(mu, p).map_err(|e| SceneError::new(source, format!("{path}.mu"), e.to_string()))?,
        ),
        PhaseDesc::Fog => PhaseFunction::fog(),
        PhaseDesc::MieFog => PhaseFunction::mie_fog(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::parse_scene_str;

    /// A turned sphere light renders as an unturned one and is named in a
    /// warning; a light without `rotation` gets none.
    #[test]
    fn a_sphere_lights_rotation_is_named_in_a_warning() {
        let scene = |rotation: &str| {
            format!(
                r#"{{"version": 1,
                "camera": {{"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 8, "height": 8}},
                "lights": [{{"type": "area", "radiance": 1,
                             "shape": {{"type": "sphere", "center": [0, 0, 0], "radius": 1{rotation}}}}}]}}"#
            )
        };
        let turned = scene(r#", "rotation": {"rotate_x": 30}"#);
        let built = build_scene(&parse_scene_str(&turned, "s.json").unwrap(), "s.json", ".".as_ref()).unwrap();
        assert_eq!(built.warnings.len(), 1, "{:?}", built.warnings);
        assert!(
            built.warnings[0].starts_with("s.json: lights[0].shape.rotation: has no effect"),
            "{:?}",
            built.warnings
        );
        let plain = build_scene(&parse_scene_str(&scene(""), "s.json").unwrap(), "s.json", ".".as_ref()).unwrap();
        assert!(plain.warnings.is_empty(), "{:?}", plain.warnings);
    }
}
