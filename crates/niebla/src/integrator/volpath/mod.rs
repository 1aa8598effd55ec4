//! Volumetric path tracing with the null-scattering path integral (Miller,
//! Georgiev, Jarosz 2019), after pbrt-v4's `VolPathIntegrator`: free flight by
//! delta tracking over majorant segments with real, null and absorption
//! events; medium emission at every tentative collision; next-event
//! estimation at every scattering vertex with shadow transmittance by ratio
//! tracking; MIS between phase or BSDF sampling and light sampling; spectral
//! MIS over the RGB channels with a hero channel chosen per path (stratified
//! over the pixel's samples); Russian
//! roulette on throughput.
//!
//! Channels whose medium coefficients differ much are traced by separate
//! paths, one per group of similar channels (`channels`).
//!
//! Path state (pbrt-v4's notation): `beta` is the throughput divided by the
//! hero channel's path pdf; `r_u` and `r_l` are the unidirectional and
//! light-sampling path pdfs of every channel divided by that same hero pdf.
//! A contribution found by phase/BSDF sampling is divided by the channel mean
//! of `r_u + r_l` (or of `r_u` alone where light sampling could not have made
//! it), one found by light sampling by the mean of `r_l + r_u`.
//!
//! Files: `path` (the path loop), `nee` (next-event estimation and shadow
//! rays), `equiangular_nee` (equiangular sampling on medium segments and its
//! MIS), `distance_mixture` (the next vertex's distance by free flight or
//! equiangular sampling), `guiding` and `light_guide` (directions toward
//! lamps inside media, with `lit_guide` toward the diffuse objects they
//! light), `channels` (channel grouping), `volume_nee` (light sampling of
//! emissive media, MIS-weighted against the collision estimator of their
//! emission), `emitter_guide` (directions toward emissive media), `forced`
//! (forced collisions where leaving the medium gathers nothing), `layout`
//! (the Sobol dimension layout), `settings` (the scene keys), and for the
//! unit tests `guide_checks` (Monte Carlo checks of the guides' densities).

mod channels;
mod distance_mixture;
mod emitter_guide;
mod equiangular_nee;
mod forced;
#[cfg(test)]
mod guide_checks;
mod guiding;
mod layout;
mod light_guide;
mod lit_guide;
mod nee;
mod path;
pub(crate) mod settings;
mod volume_nee;

use std::sync::Arc;

use crate::aov::{LayerSplit, RadianceSum};
use crate::color::Rgb;
use crate::math::Ray;
use crate::medium::MediumId;
use crate::sampling::PixelSampler;
use crate::world::Scene;

use super::{Integrator, VolumeLights};
use channels::{channel_groups, Channels};
use emitter_guide::{EmitterGuide, GuideBox};
use guiding::{GuideTarget, Guiding};
use light_guide::LightGuide;
use nee::LightChoice;

/// The volumetric path tracer.
#[derive(Clone, Debug)]
pub struct VolPathIntegrator {
    /// Largest number of scattering events (medium or surface) on a path.
    pub max_depth: u32,
    /// Probability, at a vertex whose next segment runs through a medium,
    /// of drawing the direction toward a point or spot light inside a
    /// medium instead of from the phase function or diffuse BSDF (one-sample
    /// MIS of the two; see `LightGuide`). 0 turns guiding off; it only acts
    /// in scenes with such a light. Values above `MAX_GUIDE_FRACTION` act
    /// as it: phase/BSDF sampling must keep a share, or directions the guide
    /// never draws would be lost. Used when some guided light is a spot
    /// light; see [`VolPathIntegrator::point_guide_fraction`] otherwise.
    pub guide_fraction: f32,
    /// [`VolPathIntegrator::guide_fraction`] for scenes whose guided lights
    /// are all point lights (no spot light inside a medium): a point
    /// light's guide has no spot's apex tail, so a larger share pays there.
    pub point_guide_fraction: f32,
    /// Probability, at a non-specular surface vertex without lamp guiding
    /// when emissive media are sampled as lights, of drawing the direction
    /// toward the emitting region (`EmitterGuide`) instead of from the
    /// BSDF (one-sample MIS). 0 turns it off; values above
    /// `MAX_GUIDE_FRACTION` act as it.
    pub emitter_guide_fraction: f32,
    /// The same at a scattering vertex in a medium without lamp guiding:
    /// probability of drawing the direction toward the emitting region
    /// instead of from the phase function (one-sample MIS). 0 turns it off;
    /// values above `MAX_GUIDE_FRACTION` act as it.
    pub medium_emitter_guide_fraction: f32,
    /// Probability, on a homogeneous medium segment where the path
    /// collides, of placing the next scattering vertex by equiangular
    /// sampling toward a point or spot light inside a medium that passes
    /// within one mean free path of the segment, instead of by free flight
    /// (one-sample MIS of the two distances, `distance_mixture`). 0 turns
    /// it off (free flight alone); it only acts in scenes with such lamps
    /// in fog and at most four lights, and changes noise, never the mean.
    /// Values above 0.9 act as 0.9.
    pub distance_mixture: f32,
    /// What depends only on the scene, when computed once for the scene
    /// being rendered ([`VolPathIntegrator::for_scene`]); else found for
    /// every camera sample (then without light sampling of emissive media,
    /// whose distribution is too costly to build per sample).
    scene_constants: Option<SceneConstants>,
}

/// What a render's paths share: it depends on the scene alone.
#[derive(Clone, Debug)]
struct SceneConstants {
    /// The channel groups traced by separate paths, `groups.0[..groups.1]`.
    groups: ([Channels; 3], usize),
    /// How next-event estimation picks lights.
    lights: LightChoice,
    /// The guide toward the lights inside media.
    guide: LightGuide,
    /// The emissive media as lights, when sampled and some medium emits.
    volume_lights: Option<Arc<VolumeLights>>,
    /// The medium whose free flights are forced to collide (`forced`).
    forced: Option<MediumId>,
    /// The medium inside the scene's lone boundary (`forced`), where
    /// segments and shadow rays need only the distance to the boundary.
    lone: Option<MediumId>,
    /// The guide toward the emissive media at surface vertices (empty
    /// without volume light sampling).
    emitter_guide: EmitterGuide,
}

impl SceneConstants {
    /// The constants; the volume light distribution only with `volume_lights`.
    fn new(scene: &Scene, volume_lights: bool) -> SceneConstants {
        let volume_lights = volume_lights.then(|| VolumeLights::new(scene)).filter(|v| !v.is_empty()).map(Arc::new);
        let emitter_guide = volume_lights.as_ref().map_or_else(EmitterGuide::default, |v| {
            EmitterGuide::new(v.emitting_bounds().filter_map(|(lo, hi)| GuideBox::new(lo, hi)))
        });
        SceneConstants {
            groups: channel_groups(scene),
            lights: LightChoice::new(scene),
            guide: LightGuide::new(scene),
            volume_lights,
            forced: forced::forced_collision_medium(scene),
            lone: forced::lone_boundary_medium(scene),
            emitter_guide,
        }
    }
}

/// [`VolPathIntegrator::guide_fraction`] of [`VolPathIntegrator::new`].
pub const DEFAULT_GUIDE_FRACTION: f32 = 0.25;

/// [`VolPathIntegrator::point_guide_fraction`] of [`VolPathIntegrator::new`].
///
/// Measured on bench/scenes/fog_point.json (48 px wide, 8 renders of 64
/// spp, Sobol, the guide's radius the root mean square distance): relative
/// MSE 3.96e-3 at 0.25, 3.74e-3 at 0.35; at a radius of half the farthest
/// corner's 3.91e-3, 3.71e-3 and 3.91e-3 at 0.25, 0.35 and 0.5. With the
/// guide's share toward lit objects (`LitSurfaces`, share 0.3 unless
/// stated): 3.47e-3 at 0.35 (share 0.1), 3.28e-3 at 0.4, 3.26e-3 at 0.45
/// (share 0.25), 3.61e-3 +- 2.7e-4 (a tail) at 0.5; without it 3.73e-3 at
/// 0.4 and 3.75e-3 at 0.45.
pub const DEFAULT_POINT_GUIDE_FRACTION: f32 = 0.4;

/// [`VolPathIntegrator::emitter_guide_fraction`] of [`VolPathIntegrator::new`].
///
/// Measured on the fire showcase (64x64, the floor's per-pixel relative
/// variance times CPU time): 0.3, 0.5, 0.7 and 0.9 were 2.7x, 3.2-4.0x,
/// 3.9x and 3.0x as efficient as no guiding; 0.5 keeps half of the
/// directions for the BSDF, which bounds the loss (2x) where the light
/// comes from elsewhere.
pub const DEFAULT_EMITTER_GUIDE_FRACTION: f32 = 0.5;

/// [`VolPathIntegrator::medium_emitter_guide_fraction`] of [`VolPathIntegrator::new`].
///
/// Measured on the fire showcase (64x64, the smoke's per-pixel relative
/// variance times CPU time, 16 renders of 32 spp per setting): there most
/// of the smoke's variance came from paths that scatter in the smoke and
/// then find the fire's own scattered light by phase sampling. 0.12, 0.25,
/// 0.4 and 0.5 were 2.6x, 3.0x, 2.3x and 2.1x as efficient as none on the
/// smoke; the floor and the fire gained 1.1-1.2x.
pub const DEFAULT_MEDIUM_EMITTER_GUIDE_FRACTION: f32 = 0.25;

/// [`VolPathIntegrator::distance_mixture`] of [`VolPathIntegrator::new`].
///
/// Measured on bench/scenes/fog_point.json (48 px wide, 8 renders of 64
/// spp, Sobol): relative MSE 5.33e-3 with free flight alone, 4.78e-3 at
/// 0.25, 4.73e-3 at 0.5, 5.24e-3 at 0.75; 0.5 is also Cycles' and Kulla
/// and Fajardo's choice.
pub const DEFAULT_DISTANCE_MIXTURE: f32 = 0.5;

/// Largest guiding probability used.
pub const MAX_GUIDE_FRACTION: f32 = 0.9;

impl VolPathIntegrator {
    /// The path tracer with at most `max_depth` scattering events per path
    /// and the default light guiding, for any scene.
    pub fn new(max_depth: u32) -> VolPathIntegrator {
        VolPathIntegrator {
            max_depth,
            guide_fraction: DEFAULT_GUIDE_FRACTION,
            point_guide_fraction: DEFAULT_POINT_GUIDE_FRACTION,
            emitter_guide_fraction: DEFAULT_EMITTER_GUIDE_FRACTION,
            medium_emitter_guide_fraction: DEFAULT_MEDIUM_EMITTER_GUIDE_FRACTION,
            distance_mixture: DEFAULT_DISTANCE_MIXTURE,
            scene_constants: None,
        }
    }

    /// [`VolPathIntegrator::new`] with what depends on the scene alone
    /// (channel groups, light choice, guide, the light distribution over
    /// emissive media) computed once, for `scene`: render only that scene
    /// (unchanged) with it. Emissive media are sampled as lights.
    pub fn for_scene(scene: &Scene, max_depth: u32) -> VolPathIntegrator {
        VolPathIntegrator::for_scene_with(scene, max_depth, true)
    }

    /// [`VolPathIntegrator::for_scene`] with volume light sampling on or off.
    pub fn for_scene_with(scene: &Scene, max_depth: u32, volume_light_sampling: bool) -> VolPathIntegrator {
        VolPathIntegrator {
            scene_constants: Some(SceneConstants::new(scene, volume_light_sampling)),
            ..VolPathIntegrator::new(max_depth)
        }
    }

    /// The same integrator with guiding probability `fraction` (0: off),
    /// for spot and point lights alike (both
    /// [`VolPathIntegrator::guide_fraction`] and
    /// [`VolPathIntegrator::point_guide_fraction`]).
    pub fn with_guide_fraction(self, fraction: f32) -> VolPathIntegrator {
        VolPathIntegrator { guide_fraction: fraction, point_guide_fraction: fraction, ..self }
    }

    /// The same integrator with guiding probability `fraction` where every
    /// guided light is a point light (0: off there).
    pub fn with_point_guide_fraction(self, fraction: f32) -> VolPathIntegrator {
        VolPathIntegrator { point_guide_fraction: fraction, ..self }
    }

    /// The same integrator with emitter guiding probability `fraction` (0: off).
    pub fn with_emitter_guide_fraction(self, fraction: f32) -> VolPathIntegrator {
        VolPathIntegrator { emitter_guide_fraction: fraction, ..self }
    }

    /// The same integrator with emitter guiding probability `fraction` at
    /// medium vertices (0: off).
    pub fn with_medium_emitter_guide_fraction(self, fraction: f32) -> VolPathIntegrator {
        VolPathIntegrator { medium_emitter_guide_fraction: fraction, ..self }
    }

    /// The same integrator with equiangular distance probability `q` on
    /// homogeneous segments toward point and spot lights (0: free flight
    /// alone, as before the mixture).
    pub fn with_distance_mixture(self, q: f32) -> VolPathIntegrator {
        VolPathIntegrator { distance_mixture: q, ..self }
    }
}

/// How a path samples lights: next-event estimation's choice and direction
/// guiding toward lights inside media.
#[derive(Clone, Copy)]
struct LightSampling<'a> {
    lights: LightChoice,
    guiding: Option<Guiding<'a>>,
    /// Guiding toward the emissive media at surface vertices whose lamp
    /// guiding is off, when volume light sampling is on.
    emitter_guiding: Option<Guiding<'a>>,
    /// Guiding toward the emissive media at medium vertices without lamp
    /// guiding, when volume light sampling is on.
    medium_emitter_guiding: Option<Guiding<'a>>,
    /// The emissive media as lights, if sampled.
    volume: Option<&'a VolumeLights>,
    /// The medium in which free flight is forced to collide: there, because
    /// every light is directional, an escaping path reaches no light.
    forced: Option<MediumId>,
    /// The medium inside the scene's lone convex boundary: there a segment
    /// or shadow ray needs only the distance to the boundary.
    lone: Option<MediumId>,
}

impl Integrator for VolPathIntegrator {
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb {
        self.radiance_sum(scene, ray, medium, sampler)
    }

    fn radiance_split(
        &self,
        scene: &Scene,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> LayerSplit {
        self.radiance_sum(scene, ray, medium, sampler)
    }
}

impl VolPathIntegrator {
    /// The radiance (`Rgb`) or its split by path class (`LayerSplit`).
    #[inline]
    fn radiance_sum<S: RadianceSum>(
        &self,
        scene: &Scene,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> S {
        match &self.scene_constants {
            Some(constants) => self.radiance_with(constants, scene, ray, medium, sampler),
            None => self.radiance_with(&SceneConstants::new(scene, false), scene, ray, medium, sampler),
        }
    }

    /// [`Integrator::radiance`] with the scene's constants: one path per channel group.
    #[inline]
    fn radiance_with<S: RadianceSum>(
        &self,
        constants: &SceneConstants,
        scene: &Scene,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> S {
        let SceneConstants {
            groups: (groups, count),
            lights,
            ref guide,
            ref volume_lights,
            ref emitter_guide,
            forced,
            lone,
        } = *constants;
        let volume = volume_lights.as_deref();
        let guide_fraction = if guide.points_only() { self.point_guide_fraction } else { self.guide_fraction };
        let guiding = (guide_fraction > 0.0 && lights.points > 0 && guide.is_active())
            .then_some(Guiding { target: GuideTarget::Lamps(guide), fraction: guide_fraction.min(MAX_GUIDE_FRACTION) });
        let emitter_fraction = self.emitter_guide_fraction;
        let emitter_guiding =
            (emitter_fraction > 0.0 && volume.is_some() && emitter_guide.is_active()).then_some(Guiding {
                target: GuideTarget::Emitters(emitter_guide),
                fraction: emitter_fraction.min(MAX_GUIDE_FRACTION),
            });
        let medium_fraction = self.medium_emitter_guide_fraction;
        let medium_emitter_guiding = (medium_fraction > 0.0 && volume.is_some() && emitter_guide.is_active())
            .then_some(Guiding {
                target: GuideTarget::Emitters(emitter_guide),
                fraction: medium_fraction.min(MAX_GUIDE_FRACTION),
            });
        let mut l = S::default();
        // Each group's path gives only its channels, so the paths may share
        // their numbers: each starts at the same dimension.
        let first_dimension = sampler.dimension();
        for &group in &groups[..count] {
            sampler.rewind_for_another_estimate(first_dimension);
            l.merge(self.trace(
                scene,
                ray,
                medium,
                group,
                LightSampling { lights, guiding, emitter_guiding, medium_emitter_guiding, volume, forced, lone },
                sampler,
            ));
        }
        l
    }
}
