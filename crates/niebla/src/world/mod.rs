//! The render-ready scene: typed ids, world-space shapes and lights, no strings
//! on the per-sample path. Immutable and `Sync` while rendering.

mod accel;
mod boundary_walk;

pub use accel::{ObjectTree, SceneAccel, SceneTrees};
pub use boundary_walk::{walk_shadow_ray, PaneCrossing, PathRay, ShadowSegment, MAX_PATH_BOUNDARY_CROSSINGS};

use std::ops::ControlFlow;

use crate::bsdf::Bsdf;
use crate::camera::PerspectiveCamera;
use crate::color::Rgb;
use crate::geometry::{PrimitiveHit, Shape, SurfaceHit};
use crate::light::Light;
use crate::math::{Ray, Vec3};
use crate::medium::{Medium, MediumId};
use crate::sampling::PixelSampler;
use crate::tracking::{segment_transmittance, TransmittanceMethod};

/// A shape with its surface model and the media on its two sides.
#[derive(Clone, Debug)]
pub struct SceneObject {
    /// Geometry (world space).
    pub shape: Shape,
    /// Surface scattering.
    pub bsdf: Bsdf,
    /// Medium inside a closed shape (or behind a rectangle's normal).
    pub interior: Option<MediumId>,
    /// Medium outside (or in front of a rectangle's normal). When the scene file
    /// leaves it out, the builder sets the medium that encloses the shape.
    pub exterior: Option<MediumId>,
    /// True when the shape bounds a medium (a side has a medium).
    pub bounds_medium: bool,
    /// Index in [`Scene::lights`] of the area light this shape emits as.
    pub emitter: Option<u32>,
    /// A texture giving the surface's color at each uv point (a diffuse
    /// reflectance, a plastic's diffuse reflectance, a rough conductor's
    /// specular reflectance), replacing `bsdf`'s constant one; see
    /// [`Scene::surface_bsdf`].
    pub texture: Option<std::sync::Arc<crate::texture::Texture>>,
    /// Textures giving the roughness (`alpha`, or `alpha_u` and `alpha_v`)
    /// of a `roughconductor`, a `roughdielectric` or the rough-conductor
    /// sides of a `twosided` at each uv point (their
    /// [`Texture::scalar`](crate::texture::Texture::scalar)), replacing
    /// `bsdf`'s constants; see [`Scene::surface_bsdf`].
    pub roughness: Option<std::sync::Arc<crate::texture::RoughnessTextures>>,
    /// True when anisotropic roughness on this object is oriented along
    /// the shape's `dp/du` (the scene's `"tangent_frame": "dpdu"`, Mitsuba
    /// 3's frame; see [`Shape::dpdu`]) and `bsdf` may be anisotropic; false:
    /// along the x axis of [`Frame::from_z`](crate::math::Frame::from_z) of
    /// the normal, and no tangent is computed.
    pub dpdu_frame: bool,
}

/// A surface hit with the object it belongs to.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Geometric hit record.
    pub surface: SurfaceHit,
    /// Index into [`Scene::objects`].
    pub object: u32,
    /// The hit on the object's shape (for a mesh: triangle and barycentrics).
    pub local: PrimitiveHit,
    /// The time of the ray that found the hit (frames; moving shapes were
    /// hit in their pose at this instant).
    pub time: f32,
}

/// Maximum number of index-matched boundaries a ray may cross before it is
/// terminated (guards against rays trapped by numerical error).
pub const MAX_BOUNDARY_CROSSINGS: u32 = 256;

/// The scene as the integrators see it.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The camera.
    pub camera: PerspectiveCamera,
    /// Shapes with their surfaces and media.
    pub objects: Vec<SceneObject>,
    /// Media, indexed by [`MediumId`].
    pub media: Vec<Medium>,
    /// Names of the media (same order), for messages and `niebla info`.
    pub medium_names: Vec<String>,
    /// Lights.
    pub lights: Vec<Light>,
    /// The medium that fills space outside every shape (`ambient_medium`).
    pub ambient_medium: Option<MediumId>,
    /// The medium the camera sits in (innermost closed shape containing it, else ambient).
    pub camera_medium: Option<MediumId>,
    /// World bounds of shapes, camera and positioned lights.
    pub bounds: (Vec3, Vec3),
    /// The hierarchy over `objects` (built on first use; see [`SceneAccel`]).
    pub accel: SceneAccel,
    /// The film's `transparent` option: camera rays that reach the
    /// environment without scattering (or a specular bounce) see black; the
    /// alpha layer tells the compositor where the background shows. The
    /// environment still lights the scene.
    pub transparent_background: bool,
}

/// Offset from a surface point along `d` that moves a ray origin off the
/// surface, scaled with the coordinates' magnitude.
#[inline]
pub fn offset_origin(p: Vec3, d: Vec3) -> Vec3 {
    p + d * surface_epsilon(p)
}

/// Smallest ray parameter accepted for a ray that starts on a surface at `p`,
/// so that the surface it leaves is not hit again.
#[inline]
pub fn surface_epsilon(p: Vec3) -> f32 {
    1e-4 * p.abs().max_element().max(1.0)
}

impl Scene {
    /// Nearest surface hit along `ray` with `t` in `(t_min, t_max)`, moving
    /// shapes in their pose at the ray's time.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        // Nearest hit first; the hit record only for the nearest object.
        let (i, h) = self.trees().all.closest(&self.objects, ray, t_min, t_max)?;
        Some(Hit { surface: self.objects[i as usize].shape.surface_at(ray, &h), object: i, local: h, time: ray.time })
    }

    /// Ray parameter of the nearest hit with `t` in `(t_min, t_max)`, the
    /// same as [`Scene::intersect`]'s, without the hit record.
    #[inline]
    pub fn hit_distance(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        self.trees().all.closest(&self.objects, ray, t_min, t_max).map(|(_, h)| h.t)
    }

    /// Nearest hit among the surfaces shadow rays cross (index-matched medium
    /// boundaries and thin dielectric panes) alone.
    #[inline]
    pub fn intersect_boundaries(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let (i, h) = self.trees().boundaries.closest(&self.objects, ray, t_min, t_max)?;
        Some(Hit { surface: self.objects[i as usize].shape.surface_at(ray, &h), object: i, local: h, time: ray.time })
    }

    /// The surface model at `hit`: the object's BSDF, with its textured
    /// color (see [`Bsdf::with_texture`]) and textured roughness (see
    /// [`RoughnessTextures::apply`](crate::texture::RoughnessTextures::apply))
    /// looked up at the hit's uv, and, where [`SceneObject::dpdu_frame`] is
    /// set and the roughness is anisotropic, the shape's `dp/du` as its
    /// tangent ([`Bsdf::with_tangent`]).
    #[inline]
    pub fn surface_bsdf(&self, hit: &Hit) -> Bsdf {
        let object = self.object(hit);
        if hit.surface.backside_ns && object.bsdf.is_one_sided() {
            // Mitsuba 3's rule: a one-sided BSDF seen from behind its
            // shading normal reflects nothing.
            return Bsdf::Diffuse { reflectance: crate::color::Rgb::ZERO };
        }
        if object.texture.is_none() && object.roughness.is_none() && !object.dpdu_frame {
            return object.bsdf;
        }
        let mut bsdf = object.bsdf;
        if object.texture.is_some() || object.roughness.is_some() {
            let uv = object.shape.uv(&hit.surface, &hit.local, hit.time);
            if let Some(texture) = &object.texture {
                bsdf = bsdf.with_texture(texture.eval(uv));
            }
            if let Some(roughness) = &object.roughness {
                bsdf = roughness.apply(bsdf, uv);
            }
        }
        if object.dpdu_frame && bsdf.is_anisotropic() {
            bsdf = bsdf.with_tangent(object.shape.dpdu(&hit.surface, &hit.local, hit.time));
        }
        bsdf
    }

    /// Whether an opaque surface (any object that does not
    /// [`pass shadow rays`](crate::bsdf::Bsdf::passes_shadow_rays))
    /// other than object `ignore` lies along `ray` with `t` in `(t_min, t_max)`:
    /// an any-hit query.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32, ignore: Option<u32>) -> bool {
        self.trees().opaque.any(&self.objects, ray, t_min, t_max, ignore)
    }

    /// The scene's hierarchies (built on the first call).
    #[inline]
    pub fn trees(&self) -> &SceneTrees {
        self.accel.get(&self.objects)
    }

    /// The medium with id `id`.
    #[inline]
    pub fn medium(&self, id: MediumId) -> &Medium {
        &self.media[id.0 as usize]
    }

    /// Whether a path that sampled unit `wi` about the shading normal
    /// `ns_used` at `hit` goes on: where `wi` lies on the same side of
    /// `ns_used` as of the geometric normal ([`SurfaceHit::sides_agree`],
    /// niebla's guard against light leaks), and always on a mesh that keeps
    /// its shading normal ([`crate::geometry::Shape::keeps_shading_normal`]:
    /// Mitsuba 3 evaluates and samples BSDFs in the shading frame alone and
    /// lets a path whose direction crosses the triangle's plane go on).
    #[inline]
    pub fn path_continues(&self, hit: &Hit, ns_used: Vec3, wi: Vec3) -> bool {
        hit.surface.sides_agree(ns_used, wi) || self.object(hit).shape.keeps_shading_normal()
    }

    /// The object hit.
    #[inline]
    pub fn object(&self, hit: &Hit) -> &SceneObject {
        &self.objects[hit.object as usize]
    }

    /// The medium a ray travelling along `d` is in after crossing the
    /// index-matched boundary `hit`, given the medium it was in before.
    #[inline]
    pub fn medium_after_crossing(&self, hit: &Hit, d: Vec3, current: Option<MediumId>) -> Option<MediumId> {
        let object = self.object(hit);
        if !object.bounds_medium {
            return current;
        }
        if d.dot(hit.surface.n) < 0.0 {
            object.interior
        } else {
            object.exterior
        }
    }

    /// The medium at point `p`: the interior of the innermost (smallest) closed
    /// shape with an interior medium that contains `p`, else the ambient medium.
    pub fn medium_at(&self, p: Vec3) -> Option<MediumId> {
        let mut best: Option<(f32, MediumId)> = None;
        for object in &self.objects {
            if let Some(id) = object.interior {
                if object.shape.contains(p) {
                    let v = object.shape.volume();
                    if best.is_none_or(|(bv, _)| v < bv) {
                        best = Some((v, id));
                    }
                }
            }
        }
        best.map(|(_, id)| id).or(self.ambient_medium)
    }

    /// The object that is the surface of area light `light` (an index into
    /// [`Scene::lights`]), which a shadow ray toward a sampled point of that
    /// light may pass through; `None` for other lights and for a mesh light,
    /// whose other parts can hide a sampled point (so its shadow rays test
    /// it like any surface and stop just short of the point).
    #[inline]
    pub fn light_object(&self, light: usize) -> Option<u32> {
        if let Some(crate::light::Light::Area(a)) = self.lights.get(light) {
            if a.shape.is_mesh() {
                return None;
            }
        }
        self.objects.iter().position(|o| o.emitter == Some(light as u32)).map(|i| i as u32)
    }

    /// Transmittance from `p` (inside `medium`) along unit `wi` over `distance`
    /// (may be infinite), crossing index-matched boundaries; zero if an opaque
    /// surface is in the way. Moving shapes are in their pose at the camera
    /// sample's time ([`PixelSampler::time`]).
    pub fn transmittance(
        &self,
        p: Vec3,
        medium: Option<MediumId>,
        wi: Vec3,
        distance: f32,
        method: TransmittanceMethod,
        sampler: &mut PixelSampler,
    ) -> Rgb {
        self.transmittance_ignoring(p, medium, wi, distance, None, method, sampler)
    }

    /// [`Scene::transmittance`] toward a sampled point of a light whose own
    /// surface is object `ignore`: that surface cannot occlude a sample of
    /// itself (rays grazing a sphere light's silhouette would otherwise hit it
    /// through rounding).
    #[allow(clippy::too_many_arguments)]
    pub fn transmittance_ignoring(
        &self,
        p: Vec3,
        medium: Option<MediumId>,
        wi: Vec3,
        distance: f32,
        ignore: Option<u32>,
        method: TransmittanceMethod,
        sampler: &mut PixelSampler,
    ) -> Rgb {
        let mut tr = Rgb::ONE;
        let reached = walk_shadow_ray(self, p, sampler.time(), medium, wi, distance, ignore, |s| {
            if let Some(id) = s.medium {
                tr *= segment_transmittance(self.medium(id), s.ray, 0.0, s.t_end, method, sampler);
            }
            if let Some(pane) = s.pane {
                tr *= pane.weight;
            }
            if tr.is_black() {
                return ControlFlow::Break(());
            }
            ControlFlow::Continue(())
        });
        // A black estimate is returned as it is; a blocked ray is black.
        if reached || tr.is_black() {
            tr
        } else {
            Rgb::ZERO
        }
    }

    /// Radiance emitted by the surface of `hit` toward `w_out` (zero unless the
    /// object is an area light), and the light's index.
    #[inline]
    pub fn emitted_radiance(&self, hit: &Hit, w_out: Vec3) -> Option<(Rgb, u32)> {
        let index = self.object(hit).emitter?;
        match &self.lights[index as usize] {
            crate::light::Light::Area(a) => Some((a.le(a.shape.front_normal(&hit.surface), w_out), index)),
            _ => None,
        }
    }

    /// Radiance of environment lights seen along an escaping direction `d`.
    #[inline]
    pub fn escaped_radiance(&self, d: Vec3) -> Rgb {
        let mut l = Rgb::ZERO;
        for light in &self.lights {
            l += light.le_escaped(d);
        }
        l
    }

    /// Where the first moving shape (one with a `motion`) is in the scene
    /// file: `shapes[i]`, or `lights[k].shape` for an area light (objects
    /// are the file's shapes in order, then the area lights' surfaces);
    /// `None` when nothing moves.
    pub fn moving_shape_name(&self) -> Option<String> {
        let i = self.objects.iter().position(|o| matches!(o.shape, Shape::Moving(_)))?;
        Some(match self.objects[i].emitter {
            Some(light) => format!("lights[{light}].shape"),
            None => format!("shapes[{i}]"),
        })
    }

    /// Length of the diagonal of the scene bounds (a scale for default steps).
    pub fn diagonal(&self) -> f32 {
        (self.bounds.1 - self.bounds.0).length()
    }
}
