//! Walking a ray across index-matched boundaries (shapes with a `null`
//! BSDF, which only separate media): the one implementation used by paths
//! (`volpath`, photon tracing, the camera-ray walk) and by shadow rays
//! ([`Scene::transmittance`] and `volpath`'s next-event estimation).
//!
//! A crossing continues from the hit point itself, so no path length is lost,
//! and ignores hits closer than [`surface_epsilon`] of it; the medium after it
//! is [`Scene::medium_after_crossing`].

use std::ops::ControlFlow;

use crate::math::{Ray, Vec3};
use crate::medium::MediumId;

use super::render_scene::{surface_epsilon, Hit, Scene, MAX_BOUNDARY_CROSSINGS};

/// Largest number of index-matched boundaries one path (all its segments
/// together) crosses before it is ended: paths bounce, so they get more
/// room than a single shadow ray's [`MAX_BOUNDARY_CROSSINGS`].
pub const MAX_PATH_BOUNDARY_CROSSINGS: u32 = MAX_BOUNDARY_CROSSINGS * 16;

/// Where a path is: its current ray, the medium around the ray's origin,
/// the smallest accepted hit parameter and the boundaries crossed so far.
#[derive(Clone, Copy, Debug)]
pub struct PathRay {
    /// The ray the path travels along.
    pub ray: Ray,
    /// The medium the ray starts in (`None`: vacuum).
    pub medium: Option<MediumId>,
    /// Smallest ray parameter of the next hit (`surface_epsilon` after a surface).
    pub t_min: f32,
    /// Index-matched boundaries crossed so far.
    pub crossings: u32,
}

impl PathRay {
    /// A path starting along `ray` in `medium`, accepting hits beyond `t_min`.
    #[inline]
    pub fn new(ray: Ray, medium: Option<MediumId>, t_min: f32) -> PathRay {
        PathRay { ray, medium, t_min, crossings: 0 }
    }

    /// The nearest surface hit ahead.
    #[inline]
    pub fn intersect(&self, scene: &Scene) -> Option<Hit> {
        scene.intersect(&self.ray, self.t_min, f32::INFINITY)
    }

    /// Cross the index-matched boundary `hit` straight on; `false` (and no
    /// change) once the path has crossed [`MAX_PATH_BOUNDARY_CROSSINGS`].
    #[inline]
    pub fn cross(&mut self, scene: &Scene, hit: &Hit) -> bool {
        self.crossings += 1;
        if self.crossings > MAX_PATH_BOUNDARY_CROSSINGS {
            return false;
        }
        self.medium = scene.medium_after_crossing(hit, self.ray.d, self.medium);
        self.ray = Ray::new(hit.surface.p, self.ray.d);
        self.t_min = surface_epsilon(hit.surface.p);
        true
    }

    /// Leave surface `hit` toward unit `wi` (a sampled reflection or, when
    /// `transmitted`, a refraction into the medium on `wi`'s side).
    #[inline]
    pub fn leave_surface(&mut self, scene: &Scene, hit: &Hit, wi: Vec3, transmitted: bool) {
        if transmitted {
            self.medium = scene.medium_after_crossing(hit, wi, self.medium);
        }
        self.ray = Ray::new(hit.surface.p, wi);
        self.t_min = surface_epsilon(hit.surface.p);
    }

    /// Go on from a scattering point `p` inside the current medium toward unit `wi`.
    #[inline]
    pub fn scatter_in_medium(&mut self, p: Vec3, wi: Vec3) {
        self.ray = Ray::new(p, wi);
        self.t_min = 0.0;
    }
}

/// One piece of a shadow ray between two surfaces, handed to the visitor of
/// [`walk_shadow_ray`].
#[derive(Clone, Copy, Debug)]
pub struct ShadowSegment<'a> {
    /// The medium the piece lies in.
    pub medium: Option<MediumId>,
    /// The ray of the piece; the piece is `[0, t_end)` of it.
    pub ray: &'a Ray,
    /// End of the piece (ray parameter).
    pub t_end: f32,
    /// Whether the piece ends at an opaque surface that blocks the shadow ray
    /// (the walk stops after this piece and reports the ray blocked).
    pub blocked: bool,
}

/// Walk the shadow ray from `p` (inside `medium`) along unit `wi` over
/// `distance` (may be infinite), crossing index-matched boundaries, and hand
/// each piece to `visit` in order. An opaque surface blocks the ray unless it
/// is object `ignore` (the sampled light's own surface, where the ray ends).
/// Returns `true` when the ray reached its end, `false` when it was blocked,
/// `visit` stopped it or it crossed more than [`MAX_BOUNDARY_CROSSINGS`]
/// boundaries.
#[inline]
pub fn walk_shadow_ray<F>(
    scene: &Scene,
    p: Vec3,
    mut medium: Option<MediumId>,
    wi: Vec3,
    distance: f32,
    ignore: Option<u32>,
    mut visit: F,
) -> bool
where
    F: FnMut(ShadowSegment) -> ControlFlow<()>,
{
    let mut ray = Ray::new(p, wi);
    let mut remaining = distance;
    let mut t_min = 0.0;
    for _ in 0..MAX_BOUNDARY_CROSSINGS {
        let hit = scene.intersect(&ray, t_min, remaining);
        let t_end = hit.map_or(remaining, |h| h.surface.t);
        // An opaque surface: the light's own (the ray ends there) or a blocker.
        let opaque = hit.filter(|h| !scene.object(h).bsdf.is_null());
        let blocked = opaque.is_some_and(|h| Some(h.object) != ignore);
        if visit(ShadowSegment { medium, ray: &ray, t_end, blocked }).is_break() || blocked {
            return false;
        }
        let Some(hit) = hit.filter(|_| opaque.is_none()) else {
            return true;
        };
        medium = scene.medium_after_crossing(&hit, wi, medium);
        remaining -= hit.surface.t;
        ray = Ray::new(hit.surface.p, wi);
        t_min = surface_epsilon(hit.surface.p);
        if remaining <= t_min {
            return true;
        }
    }
    false
}
