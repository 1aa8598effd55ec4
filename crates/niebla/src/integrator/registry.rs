//! The one list of integrators and the one `match` over their kinds.
//!
//! A scene file's `render.integrator` object (a `type` and that
//! integrator's fields) is turned into [`IntegratorSettings`] by [`parse`];
//! each integrator's fields, defaults and checks live beside it (its
//! `settings` module). [`PreparedIntegrator`] runs an integrator's per-scene
//! precomputation once and renders with the concrete integrator type, so the
//! render loop is monomorphized per integrator and no sample goes through a
//! virtual call.
//!
//! Adding an integrator: its folder (the integrator, its `settings.rs`), a
//! variant of [`IntegratorSettings`], an entry of [`INTEGRATORS`] and the
//! arms of the matches below.

use std::sync::atomic::AtomicBool;

use serde_json::Value;

use super::precompute_memory::{beam_map_memory, hegeman_memory, photon_map_memory, zhou_memory};
use super::{
    analytic, emission_absorption, hegeman, photon, single, volpath, zhou, AnalyticIntegrator, EmissionIntegrator,
    HegemanIntegrator, PrecomputeMemory, SingleIntegrator, SingleSampling, VolPathIntegrator, ZhouIntegrator,
};
use crate::film::{Image, SampleSums};
use crate::params::{describe, Located, Object};
use crate::render::{render_sums_with, ProgressFn, RenderError, RenderOptions};
use crate::tracking::{MarchStep, TransmittanceMethod};
use crate::world::Scene;

/// Which integrator to run and its parameters (from a scene file's
/// `render.integrator` through [`parse`], or built in code).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IntegratorSettings {
    /// Emission and absorption only (no in-scattering); surfaces lit directly.
    Emission {
        /// Ray-march step for the emission integral; `None` picks a default per medium.
        step: Option<MarchStep>,
        /// Transmittance estimator.
        transmittance: TransmittanceMethod,
    },
    /// Single scattering with shadow rays to every light; surfaces lit directly.
    Single {
        /// Ray-march step along the camera ray; `None` picks a default per medium.
        step: Option<MarchStep>,
        /// How scattering points along the camera ray are chosen.
        sampling: SingleSampling,
        /// Transmittance estimator.
        transmittance: TransmittanceMethod,
        /// Whether emissive media light scattering points and surfaces
        /// (`volume_lights`, default false).
        volume_lights: bool,
    },
    /// Unbiased volumetric path tracing (multiple scattering).
    VolPath {
        /// Largest number of scattering events on a path.
        max_depth: u32,
        /// Whether next-event estimation samples emissive media as lights
        /// (`volume_light_sampling`, default true).
        volume_light_sampling: bool,
        /// Whether surface vertices mix BSDF sampling, and medium vertices
        /// phase sampling, with directions toward the emitting region when
        /// emissive media are sampled as lights
        /// (`emitter_guiding`, default true; the mean is the same either way).
        emitter_guiding: bool,
    },
    /// Closed-form single scattering (Sun et al. 2005) in homogeneous media
    /// from point and spot lights; surfaces lit directly.
    Analytic,
    /// Single scattering plus the blurred multiple-scattering approximation
    /// of Hegeman et al. 2005 (reconstructed), with per-light precomputed
    /// volumes; interactive.
    Hegeman(hegeman::HegemanSettings),
    /// Compensated ray marching (Zhou et al. 2008, reconstructed): RBF
    /// density fit, SH environment lighting, diffusion, residual compensated
    /// along view rays; interactive.
    Zhou(zhou::ZhouSettings),
    /// Volumetric photon mapping (Jensen and Christensen 1998): one photon
    /// map per render, single scattering by shadow rays.
    Photon(photon::PhotonSettings),
    /// Progressive photon mapping (Knaus and Zwicker 2011): one photon map
    /// and a smaller radius per sample index; converges to `volpath`.
    Ppm(photon::PpmSettings),
    /// Progressive photon beams (Jarosz et al. 2011): beams of photon free
    /// flights, the beam x beam 1D estimate and a shrinking radius per
    /// sample index; converges to `volpath`.
    Ppb(photon::PpbSettings),
}

/// One integrator as the user selects it: its name (the `type` in a scene
/// file, the value of `--integrator`), a one-line summary, and whether it
/// is fast enough for `niebla preview`.
#[derive(Clone, Copy, Debug)]
pub struct IntegratorEntry {
    /// The `type` name.
    pub name: &'static str,
    /// What it computes, in one line (command-line help).
    pub summary: &'static str,
    /// Renders a frame in well under a second after its precomputation.
    pub interactive: bool,
    /// Its settings from the object's fields (the `type` taken out).
    parse: fn(Object) -> Result<IntegratorSettings, Located>,
}

/// Every integrator, in the order they are listed to users. The default
/// (`render.integrator` absent) is the first, `single`.
pub const INTEGRATORS: &[IntegratorEntry] = &[
    IntegratorEntry {
        name: "single",
        summary: "Single scattering with shadow rays (march, equiangular or MIS sampling)",
        interactive: true,
        parse: |o| {
            single::settings::parse(o).map(|(step, sampling, transmittance, volume_lights)| {
                IntegratorSettings::Single { step, sampling, transmittance, volume_lights }
            })
        },
    },
    IntegratorEntry {
        name: "emission",
        summary: "Emission and absorption only",
        interactive: false,
        parse: |o| {
            emission_absorption::settings::parse(o)
                .map(|(step, transmittance)| IntegratorSettings::Emission { step, transmittance })
        },
    },
    IntegratorEntry {
        name: "volpath",
        summary: "Volumetric path tracing (multiple scattering, unbiased)",
        interactive: false,
        parse: |o| {
            volpath::settings::parse(o).map(|p| IntegratorSettings::VolPath {
                max_depth: p.max_depth,
                volume_light_sampling: p.volume_light_sampling,
                emitter_guiding: p.emitter_guiding,
            })
        },
    },
    IntegratorEntry {
        name: "analytic",
        summary: "Closed-form single scattering (Sun et al. 2005) in homogeneous media",
        interactive: true,
        parse: |o| analytic::settings::parse(o).map(|()| IntegratorSettings::Analytic),
    },
    IntegratorEntry {
        name: "hegeman",
        summary: "Single + approximate multiple scattering (Hegeman et al. 2005), interactive",
        interactive: true,
        parse: |o| hegeman::settings::parse(o).map(IntegratorSettings::Hegeman),
    },
    IntegratorEntry {
        name: "zhou",
        summary: "Compensated ray marching (Zhou et al. 2008): RBF fit, SH lighting, diffusion; interactive",
        interactive: true,
        parse: |o| zhou::settings::parse(o).map(IntegratorSettings::Zhou),
    },
    IntegratorEntry {
        name: "photon",
        summary: "Volumetric photon mapping (one photon map per render)",
        interactive: false,
        parse: |o| photon::settings::parse_photon(o).map(IntegratorSettings::Photon),
    },
    IntegratorEntry {
        name: "ppm",
        summary: "Progressive photon mapping (converges to volpath)",
        interactive: false,
        parse: |o| photon::settings::parse_ppm(o).map(IntegratorSettings::Ppm),
    },
    IntegratorEntry {
        name: "ppb",
        summary: "Progressive photon beams (beam x beam 1D estimate; converges to volpath)",
        interactive: false,
        parse: |o| photon::settings::parse_ppb(o).map(IntegratorSettings::Ppb),
    },
];

/// The names of [`INTEGRATORS`], in their order.
pub const NAMES: [&str; INTEGRATORS.len()] = {
    let mut names = [""; INTEGRATORS.len()];
    let mut i = 0;
    while i < names.len() {
        names[i] = INTEGRATORS[i].name;
        i += 1;
    }
    names
};

/// The entry named `name`.
pub fn entry(name: &str) -> Option<&'static IntegratorEntry> {
    INTEGRATORS.iter().find(|e| e.name == name)
}

/// Settings from a `render.integrator` object: its `type` (one of
/// [`NAMES`]) and that integrator's fields, defaults filled in and every
/// value checked. Errors carry the path relative to the object (`type`,
/// `max_depth`, `steps`, ...).
///
/// ```
/// use niebla::integrator::{registry, IntegratorSettings};
/// let object = serde_json::json!({"type": "volpath", "max_depth": 64});
/// let settings = registry::parse(object.as_object().unwrap()).unwrap();
/// assert_eq!(settings, IntegratorSettings::VolPath { max_depth: 64, volume_light_sampling: true, emitter_guiding: true });
/// let object = serde_json::json!({"type": "volpath", "max_depth": 0});
/// let e = registry::parse(object.as_object().unwrap()).unwrap_err();
/// assert_eq!((e.path.as_str(), e.message.as_str()), ("max_depth", "must be at least 1, got 0"));
/// ```
pub fn parse(object: &Object) -> Result<IntegratorSettings, Located> {
    let mut object = object.clone();
    let list = NAMES.join(", ");
    let name = match object.remove("type") {
        Some(Value::String(name)) => name,
        Some(other) => {
            return Err(Located::new(
                "type",
                format!("expected a string naming the integrator type, one of: {list}; got {}", describe(&other)),
            ))
        }
        None => return Err(Located::new("type", format!("missing required field `type`; expected one of: {list}"))),
    };
    match entry(&name) {
        Some(entry) => (entry.parse)(object),
        None => Err(Located::new("type", format!("unknown integrator type {name:?}; expected one of: {list}"))),
    }
}

/// Settings from `object` (a `render.integrator` object) changed by the
/// command line: `name`, when it differs from the object's `type`, replaces
/// the whole object (its fields take their defaults, since they belong to
/// another integrator); then each `(field, value)` of `fields` is set.
/// Errors carry the path relative to the object, as [`parse`]'s.
///
/// ```
/// use niebla::integrator::{registry, IntegratorSettings};
/// let object = serde_json::json!({"type": "volpath", "max_depth": 64});
/// let object = object.as_object().unwrap();
/// let same = registry::parse_with_overrides(object, Some("volpath"), &[]).unwrap();
/// assert_eq!(same, IntegratorSettings::VolPath { max_depth: 64, volume_light_sampling: true, emitter_guiding: true });
/// let deeper = registry::parse_with_overrides(object, None, &[("max_depth", 8.into())]).unwrap();
/// assert_eq!(deeper, IntegratorSettings::VolPath { max_depth: 8, volume_light_sampling: true, emitter_guiding: true });
/// let other = registry::parse_with_overrides(object, Some("single"), &[]).unwrap();
/// assert_eq!(Some(other), registry::defaults("single"));
/// ```
pub fn parse_with_overrides(
    object: &Object,
    name: Option<&str>,
    fields: &[(&str, Value)],
) -> Result<IntegratorSettings, Located> {
    let mut object = match name {
        Some(name) if object.get("type").and_then(Value::as_str) != Some(name) => {
            let mut fresh = Object::new();
            fresh.insert("type".into(), Value::String(name.to_string()));
            fresh
        }
        _ => object.clone(),
    };
    for (field, value) in fields {
        object.insert(field.to_string(), value.clone());
    }
    parse(&object)
}

/// The settings of integrator `name` with every field at its default
/// (`None` for an unknown name).
///
/// ```
/// use niebla::integrator::{registry, IntegratorSettings};
/// assert_eq!(registry::defaults("volpath"), Some(IntegratorSettings::VolPath { max_depth: 1024, volume_light_sampling: true, emitter_guiding: true }));
/// ```
pub fn defaults(name: &str) -> Option<IntegratorSettings> {
    entry(name).map(|e| (e.parse)(Object::new()).expect("every integrator has valid defaults"))
}

impl IntegratorSettings {
    /// Default path depth of `volpath`: deep enough for dense albedo-0.99 media.
    pub const DEFAULT_MAX_DEPTH: u32 = volpath::settings::DEFAULT_MAX_DEPTH;

    /// Names of all integrators that can be selected ([`NAMES`]).
    pub const NAMES: &'static [&'static str] = &NAMES;

    /// The name used on the command line and in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorSettings::Emission { .. } => "emission",
            IntegratorSettings::Single { .. } => "single",
            IntegratorSettings::VolPath { .. } => "volpath",
            IntegratorSettings::Analytic => "analytic",
            IntegratorSettings::Hegeman(_) => "hegeman",
            IntegratorSettings::Zhou(_) => "zhou",
            IntegratorSettings::Photon(_) => "photon",
            IntegratorSettings::Ppm(_) => "ppm",
            IntegratorSettings::Ppb(_) => "ppb",
        }
    }

    /// A stable text naming the integrator and every setting, e.g.
    /// `volpath(max_depth=1024)`: equal keys mean equal settings. Checkpoints
    /// record it, so it does not depend on how Rust formats the types.
    ///
    /// ```
    /// use niebla::integrator::registry;
    /// assert_eq!(
    ///     registry::defaults("single").unwrap().key(),
    ///     "single(step=auto, sampling=march, transmittance=analytic)"
    /// );
    /// ```
    pub fn key(&self) -> String {
        match self {
            IntegratorSettings::Emission { step, transmittance } => {
                emission_absorption::settings::key(*step, *transmittance)
            }
            IntegratorSettings::Single { step, sampling, transmittance, volume_lights } => {
                single::settings::key(*step, *sampling, *transmittance, *volume_lights)
            }
            IntegratorSettings::VolPath { max_depth, volume_light_sampling, emitter_guiding } => {
                volpath::settings::key(*max_depth, *volume_light_sampling, *emitter_guiding)
            }
            IntegratorSettings::Analytic => "analytic".to_string(),
            IntegratorSettings::Hegeman(h) => hegeman::settings::key(h),
            IntegratorSettings::Zhou(z) => zhou::settings::key(z),
            IntegratorSettings::Photon(p) => photon::settings::photon_key(p),
            IntegratorSettings::Ppm(p) => photon::settings::ppm_key(p),
            IntegratorSettings::Ppb(p) => photon::settings::ppb_key(p),
        }
    }

    /// Upper estimate of the memory this integrator's precomputation takes
    /// on `scene` (photon maps, light volumes, SH lattices); `None` for
    /// integrators without one.
    pub fn precompute_memory(&self, scene: &Scene) -> Option<PrecomputeMemory> {
        match self {
            IntegratorSettings::Hegeman(h) => Some(hegeman_memory(h, scene)),
            IntegratorSettings::Zhou(z) => Some(zhou_memory(z, scene)),
            IntegratorSettings::Photon(p) => Some(photon_map_memory(scene, p.photons, p.max_depth, "the photon map")),
            IntegratorSettings::Ppb(p) => Some(beam_map_memory(scene, p.photons, p.max_depth)),
            IntegratorSettings::Ppm(p) => {
                Some(photon_map_memory(scene, p.photon.photons, p.photon.max_depth, "each pass's photon map"))
            }
            IntegratorSettings::VolPath { volume_light_sampling: true, .. } => {
                volume_lights_memory(scene, "volume_light_sampling")
            }
            IntegratorSettings::Single { volume_lights: true, .. } => volume_lights_memory(scene, "volume_lights"),
            IntegratorSettings::Emission { .. }
            | IntegratorSettings::Single { .. }
            | IntegratorSettings::VolPath { .. }
            | IntegratorSettings::Analytic => None,
        }
    }
}

/// The memory of [`super::VolumeLights`] for `scene`, reported under the
/// setting `field` that turns it on; `None` without emissive grid media.
fn volume_lights_memory(scene: &Scene, field: &'static str) -> Option<PrecomputeMemory> {
    let bytes = super::VolumeLights::memory_estimate(scene);
    (bytes > 0).then(|| PrecomputeMemory {
        bytes,
        field,
        what: "the light distribution over the majorant cells of the emissive grid media".to_string(),
    })
}

/// An integrator with its per-scene work done (the interactive methods'
/// volumes and fits, volpath's light guide), so that progressive passes and
/// preview frames reuse it.
pub enum PreparedIntegrator {
    /// `emission`.
    Emission(EmissionIntegrator),
    /// `single`.
    Single(SingleIntegrator),
    /// `volpath` with its per-scene constants.
    VolPath(Box<VolPathIntegrator>),
    /// `analytic` with its airlight table.
    Analytic(AnalyticIntegrator),
    /// `hegeman` with its light volumes.
    Hegeman(Box<HegemanIntegrator>),
    /// `zhou` with its RBF fit and source radiance.
    Zhou(Box<ZhouIntegrator>),
    /// `photon` (its photon map is traced per pass).
    Photon(photon::PhotonSettings),
    /// `ppm` (a photon map per pass).
    Ppm(photon::PpmSettings),
    /// `ppb` (beams per pass).
    Ppb(photon::PpbSettings),
}

impl PreparedIntegrator {
    /// Run the precomputation of `settings` for `scene`.
    pub fn new(scene: &Scene, settings: &IntegratorSettings) -> PreparedIntegrator {
        match *settings {
            IntegratorSettings::Emission { step, transmittance } => {
                PreparedIntegrator::Emission(EmissionIntegrator { step, transmittance })
            }
            IntegratorSettings::Single { step, sampling, transmittance, volume_lights } => PreparedIntegrator::Single(
                SingleIntegrator::for_scene(scene, step, sampling, transmittance, volume_lights),
            ),
            IntegratorSettings::VolPath { max_depth, volume_light_sampling, emitter_guiding } => {
                let integrator = VolPathIntegrator::for_scene_with(scene, max_depth, volume_light_sampling);
                PreparedIntegrator::VolPath(Box::new(if emitter_guiding {
                    integrator
                } else {
                    integrator.with_emitter_guide_fraction(0.0).with_medium_emitter_guide_fraction(0.0)
                }))
            }
            IntegratorSettings::Analytic => PreparedIntegrator::Analytic(AnalyticIntegrator::new()),
            IntegratorSettings::Hegeman(h) => PreparedIntegrator::Hegeman(Box::new(HegemanIntegrator::new(scene, h))),
            IntegratorSettings::Zhou(z) => PreparedIntegrator::Zhou(Box::new(ZhouIntegrator::new(scene, z))),
            IntegratorSettings::Photon(p) => PreparedIntegrator::Photon(p),
            IntegratorSettings::Ppm(p) => PreparedIntegrator::Ppm(p),
            IntegratorSettings::Ppb(p) => PreparedIntegrator::Ppb(p),
        }
    }

    /// Bring an integrator prepared with `settings` for a scene up to date
    /// with `scene`, that scene after `edit` ([`crate::scene::rebuild_scene`]),
    /// reusing what the edit left valid: `zhou` keeps its fit (and, when
    /// only the camera moved, its lighting: the view pass runs again),
    /// `hegeman` keeps its line integrals except those of lights that moved
    /// (and everything when only the camera moved); the others, whose preparation is cheap or depends on
    /// the scene bounds (which include the camera), are prepared again.
    /// Renders with the result are identical to those of
    /// `PreparedIntegrator::new(scene, settings)`.
    pub fn update(&mut self, scene: &Scene, settings: &IntegratorSettings, edit: &crate::scene::SceneEdit) {
        let done = self.update_cancellable(scene, settings, edit, None);
        debug_assert!(done, "no cancel flag");
    }

    /// [`Self::new`], giving up (`None`, no partial result) when `cancel`
    /// is set during `zhou`'s fit, lighting or diffusion (the other
    /// integrators' preparations run to the end).
    pub fn new_cancellable(scene: &Scene, settings: &IntegratorSettings, cancel: &AtomicBool) -> Option<Self> {
        match *settings {
            IntegratorSettings::Zhou(z) => {
                ZhouIntegrator::new_cancellable(scene, z, Some(cancel)).map(|z| PreparedIntegrator::Zhou(Box::new(z)))
            }
            _ => Some(PreparedIntegrator::new(scene, settings)),
        }
    }

    /// [`Self::update`], giving up when `cancel` is set during `zhou`'s
    /// lighting or diffusion: `false` then, and the integrator is half
    /// updated and must be dropped (never rendered with).
    pub fn update_cancellable(
        &mut self,
        scene: &Scene,
        settings: &IntegratorSettings,
        edit: &crate::scene::SceneEdit,
        cancel: Option<&AtomicBool>,
    ) -> bool {
        self.update_with(scene, settings, edit, false, cancel)
    }

    /// [`Self::update_cancellable`] for an interactive (drag) frame: `zhou`
    /// lights the edited media on its coarser preview lattice
    /// ([`ZhouIntegrator::update_media_preview`]), and `zhou` and `hegeman`
    /// march camera rays with the coarser drag step
    /// ([`Self::set_drag_march`]), so the image approximates that of a new
    /// precomputation; the next [`Self::update_cancellable`] (any edit, a
    /// camera move included) lights on the full lattice and marches the
    /// settings' step again. The other integrators update as in
    /// [`Self::update`].
    pub fn update_preview_cancellable(
        &mut self,
        scene: &Scene,
        settings: &IntegratorSettings,
        edit: &crate::scene::SceneEdit,
        cancel: Option<&AtomicBool>,
    ) -> bool {
        self.update_with(scene, settings, edit, true, cancel)
    }

    /// True when a preview update ([`Self::update_preview_cancellable`]) or
    /// [`Self::set_drag_march`] left an approximate precomputation or march
    /// (renders then differ from those of `PreparedIntegrator::new`).
    pub fn is_preview(&self) -> bool {
        match self {
            PreparedIntegrator::Zhou(z) => z.is_preview() || z.is_drag_march(),
            PreparedIntegrator::Hegeman(h) => h.is_drag_march(),
            _ => false,
        }
    }

    /// For a live viewer's drag frames (`coarse`): `zhou` and `hegeman`
    /// march camera rays with a step [`crate::integrator::DRAG_STEP_FACTOR`]
    /// times their settings' (an approximate image, about that many times
    /// fewer density lookups per ray); `false` restores the settings' step.
    /// The other integrators do not change.
    pub fn set_drag_march(&mut self, coarse: bool) {
        match self {
            PreparedIntegrator::Zhou(z) => z.set_drag_march(coarse),
            PreparedIntegrator::Hegeman(h) => h.set_drag_march(coarse),
            _ => {}
        }
    }

    fn update_with(
        &mut self,
        scene: &Scene,
        settings: &IntegratorSettings,
        edit: &crate::scene::SceneEdit,
        preview: bool,
        cancel: Option<&AtomicBool>,
    ) -> bool {
        let done = match self {
            PreparedIntegrator::Zhou(z) => {
                if edit.any_light() {
                    match preview {
                        true => z.update_lights_preview(scene, &edit.media, cancel),
                        false => z.update_lights(scene, &edit.media, cancel),
                    }
                } else if edit.any_medium() || (!preview && z.is_preview()) {
                    match preview {
                        true => z.update_media_preview(scene, &edit.media, cancel),
                        false => z.update_media(scene, &edit.media, cancel),
                    }
                } else {
                    if edit.camera {
                        z.set_view(scene.camera.position);
                    }
                    true
                }
            }
            PreparedIntegrator::Hegeman(h) => {
                if edit.any_medium() {
                    h.update_media(scene, &edit.media);
                }
                if edit.any_light() {
                    h.update_lights(scene);
                }
                true
            }
            _ => {
                *self = PreparedIntegrator::new(scene, settings);
                true
            }
        };
        self.set_drag_march(preview);
        done
    }

    /// An error when `scene` has a moving medium (a velocity grid seen
    /// through an open shutter) and this integrator does not see media at
    /// each camera sample's time: those that precompute the media (hegeman,
    /// zhou), trace photons (photon, ppm, ppb) or use closed forms
    /// (analytic). Emission, single and volpath track at the sample's time.
    ///
    /// Likewise for a moving shape or area light (a shape with `motion`):
    /// emission, single and volpath intersect each ray at its time. And an
    /// error for an emitting mesh under hegeman or zhou, whose light models
    /// hold rectangles, disks and spheres only.
    fn check_motion(&self, scene: &Scene) -> Result<(), RenderError> {
        let name = match self {
            PreparedIntegrator::Emission(_) | PreparedIntegrator::Single(_) | PreparedIntegrator::VolPath(_) => {
                return Ok(())
            }
            PreparedIntegrator::Analytic(_) => "analytic",
            PreparedIntegrator::Hegeman(_) => "hegeman",
            PreparedIntegrator::Zhou(_) => "zhou",
            PreparedIntegrator::Photon(_) => "photon",
            PreparedIntegrator::Ppm(_) => "ppm",
            PreparedIntegrator::Ppb(_) => "ppb",
        };
        if matches!(self, PreparedIntegrator::Hegeman(_) | PreparedIntegrator::Zhou(_)) {
            let mesh = scene.lights.iter().position(|l| matches!(l, crate::light::Light::Area(a) if a.shape.is_mesh()));
            if let Some(index) = mesh {
                return Err(RenderError::Unsupported {
                    integrator: name,
                    reason: format!(
                        "lights[{index}] is an emitting mesh, which its light model does not hold (area lights \
                         there are rectangles, disks and spheres); render it with volpath, single, emission, \
                         analytic or photon"
                    ),
                });
            }
        }
        if let Some(shape) = scene.moving_shape_name() {
            return Err(RenderError::Unsupported {
                integrator: name,
                reason: format!(
                    "{shape} moves during the shutter (its `motion`); motion blur of shapes and area lights is \
                     rendered by volpath, single and emission"
                ),
            });
        }
        let moving = scene.media.iter().position(|m| matches!(m, crate::medium::Medium::Grid(g) if g.motion.is_some()));
        match moving {
            None => Ok(()),
            Some(index) => {
                let medium = scene.medium_names.get(index).cloned().unwrap_or_else(|| format!("#{index}"));
                Err(RenderError::Unsupported {
                    integrator: name,
                    reason: format!(
                        "medium {medium:?} moves during the shutter (its `velocity` grid); motion blur of media \
                         is rendered by volpath, single and emission"
                    ),
                })
            }
        }
    }

    /// Render `options.spp` samples per pixel of `scene` (the scene the
    /// integrator was prepared for): the mean of [`Self::render_sums`].
    pub fn render(
        &self,
        scene: &Scene,
        options: &RenderOptions,
        progress: ProgressFn,
        cancel: Option<&AtomicBool>,
    ) -> Result<Image, RenderError> {
        Ok(self.render_sums(scene, options, progress, cancel)?.mean(options.spp as u64))
    }

    /// The per-pixel fixed-point sums (`film::SampleSums`) of samples
    /// `options.first_sample .. options.first_sample + options.spp`.
    pub fn render_sums(
        &self,
        scene: &Scene,
        options: &RenderOptions,
        progress: ProgressFn,
        cancel: Option<&AtomicBool>,
    ) -> Result<SampleSums, RenderError> {
        self.check_motion(scene)?;
        match self {
            PreparedIntegrator::Emission(i) => render_sums_with(scene, i, options, progress, cancel),
            PreparedIntegrator::Single(i) => render_sums_with(scene, i, options, progress, cancel),
            PreparedIntegrator::VolPath(i) => render_sums_with(scene, i.as_ref(), options, progress, cancel),
            PreparedIntegrator::Analytic(i) => render_sums_with(scene, i, options, progress, cancel),
            PreparedIntegrator::Hegeman(i) => render_sums_with(scene, i.as_ref(), options, progress, cancel),
            PreparedIntegrator::Zhou(i) => render_sums_with(scene, i.as_ref(), options, progress, cancel),
            PreparedIntegrator::Photon(p) => photon::render_photon(scene, p, options, progress, cancel),
            PreparedIntegrator::Ppm(p) => photon::render_ppm(scene, p, options, progress, cancel),
            PreparedIntegrator::Ppb(p) => photon::render_ppb(scene, p, options, progress, cancel),
        }
    }

    /// The beauty sums (equal to [`Self::render_sums`]'s) and the sums of
    /// the layers `set` (`crate::aov`). `photon` and `ppm` write no layers:
    /// check [`crate::aov::unsupported_reason`] first (they panic here).
    pub fn render_aov_sums(
        &self,
        scene: &Scene,
        options: &RenderOptions,
        set: crate::aov::AovSet,
        progress: ProgressFn,
        cancel: Option<&AtomicBool>,
    ) -> Result<(SampleSums, crate::aov::AovSums), RenderError> {
        self.render_aov_sums_masked(scene, options, set, None, progress, cancel)
    }

    /// [`Self::render_aov_sums`] of the pixels whose `active` flag is set
    /// (all when `None`; the others take no sample and have zero sums).
    pub fn render_aov_sums_masked(
        &self,
        scene: &Scene,
        options: &RenderOptions,
        set: crate::aov::AovSet,
        active: Option<&[bool]>,
        progress: ProgressFn,
        cancel: Option<&AtomicBool>,
    ) -> Result<(SampleSums, crate::aov::AovSums), RenderError> {
        use crate::aov::render_aov_sums_masked_with as with;
        self.check_motion(scene)?;
        match self {
            PreparedIntegrator::Emission(i) => with(scene, i, options, set, active, progress, cancel),
            PreparedIntegrator::Single(i) => with(scene, i, options, set, active, progress, cancel),
            PreparedIntegrator::VolPath(i) => with(scene, i.as_ref(), options, set, active, progress, cancel),
            PreparedIntegrator::Analytic(i) => with(scene, i, options, set, active, progress, cancel),
            PreparedIntegrator::Hegeman(i) => with(scene, i.as_ref(), options, set, active, progress, cancel),
            PreparedIntegrator::Zhou(i) => with(scene, i.as_ref(), options, set, active, progress, cancel),
            PreparedIntegrator::Photon(_) | PreparedIntegrator::Ppm(_) | PreparedIntegrator::Ppb(_) => {
                panic!("photon, ppm and ppb write no layers (aov::unsupported_reason says so)")
            }
        }
    }

    /// The sums of sample ranges of some pixels for adaptive rendering
    /// ([`crate::aov::render_segment_sums_with`]); on the current rayon pool.
    /// `photon`, `ppm` and `ppb` have no per-pixel samples (they panic here).
    pub fn render_segment_sums(
        &self,
        scene: &Scene,
        seed: u64,
        set: crate::aov::AovSet,
        pixels: &[u32],
        segments: &[(u64, u64)],
        cancel: Option<&AtomicBool>,
    ) -> Result<Vec<i128>, RenderError> {
        use crate::aov::render_segment_sums_with as with;
        self.check_motion(scene)?;
        match self {
            PreparedIntegrator::Emission(i) => with(scene, i, seed, set, pixels, segments, cancel),
            PreparedIntegrator::Single(i) => with(scene, i, seed, set, pixels, segments, cancel),
            PreparedIntegrator::VolPath(i) => with(scene, i.as_ref(), seed, set, pixels, segments, cancel),
            PreparedIntegrator::Analytic(i) => with(scene, i, seed, set, pixels, segments, cancel),
            PreparedIntegrator::Hegeman(i) => with(scene, i.as_ref(), seed, set, pixels, segments, cancel),
            PreparedIntegrator::Zhou(i) => with(scene, i.as_ref(), seed, set, pixels, segments, cancel),
            PreparedIntegrator::Photon(_) | PreparedIntegrator::Ppm(_) | PreparedIntegrator::Ppb(_) => {
                panic!("photon, ppm and ppb have no per-pixel samples (the adaptive command refuses them)")
            }
        }
    }

    /// One range of sample indices per pixel, drawn by sampler `kind`
    /// ([`crate::aov::render_range_sums_with`]); on the current rayon pool.
    /// `photon`, `ppm` and `ppb` have no per-pixel samples (they panic here).
    #[allow(clippy::too_many_arguments)]
    pub fn render_range_sums(
        &self,
        scene: &Scene,
        kind: crate::sampling::SamplerKind,
        seed: u64,
        set: crate::aov::AovSet,
        pixels: &[u32],
        ranges: &[(u64, u64)],
        cancel: Option<&AtomicBool>,
    ) -> Result<Vec<i128>, RenderError> {
        use crate::aov::render_range_sums_with as with;
        self.check_motion(scene)?;
        match self {
            PreparedIntegrator::Emission(i) => with(scene, i, kind, seed, set, pixels, ranges, cancel),
            PreparedIntegrator::Single(i) => with(scene, i, kind, seed, set, pixels, ranges, cancel),
            PreparedIntegrator::VolPath(i) => with(scene, i.as_ref(), kind, seed, set, pixels, ranges, cancel),
            PreparedIntegrator::Analytic(i) => with(scene, i, kind, seed, set, pixels, ranges, cancel),
            PreparedIntegrator::Hegeman(i) => with(scene, i.as_ref(), kind, seed, set, pixels, ranges, cancel),
            PreparedIntegrator::Zhou(i) => with(scene, i.as_ref(), kind, seed, set, pixels, ranges, cancel),
            PreparedIntegrator::Photon(_) | PreparedIntegrator::Ppm(_) | PreparedIntegrator::Ppb(_) => {
                panic!("photon, ppm and ppb have no per-pixel samples (the adaptive command refuses them)")
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_equal_the_integrators_own_defaults() {
        use crate::integrator::photon::{PhotonSettings, PpmSettings};
        use crate::integrator::{HegemanSettings, ZhouSettings};
        assert_eq!(
            defaults("single"),
            Some(IntegratorSettings::Single {
                step: None,
                sampling: SingleSampling::March,
                transmittance: TransmittanceMethod::Analytic,
                volume_lights: false
            })
        );
        assert_eq!(
            defaults("emission"),
            Some(IntegratorSettings::Emission { step: None, transmittance: TransmittanceMethod::Analytic })
        );
        assert_eq!(
            defaults("volpath"),
            Some(IntegratorSettings::VolPath { max_depth: 1024, volume_light_sampling: true, emitter_guiding: true })
        );
        assert_eq!(defaults("analytic"), Some(IntegratorSettings::Analytic));
        assert_eq!(defaults("hegeman"), Some(IntegratorSettings::Hegeman(HegemanSettings::default())));
        assert_eq!(defaults("zhou"), Some(IntegratorSettings::Zhou(ZhouSettings::default())));
        assert_eq!(defaults("photon"), Some(IntegratorSettings::Photon(PhotonSettings::photon())));
        assert_eq!(defaults("ppm"), Some(IntegratorSettings::Ppm(PpmSettings::default())));
        assert_eq!(defaults("ppb"), Some(IntegratorSettings::Ppb(crate::integrator::photon::PpbSettings::default())));
        assert_eq!(defaults("bidirectional"), None);
    }

    #[test]
    fn every_entry_parses_its_own_name_and_keys_are_distinct() {
        let mut keys = std::collections::HashSet::new();
        for name in NAMES {
            let settings = defaults(name).unwrap();
            assert_eq!(settings.name(), name);
            assert!(keys.insert(settings.key()), "{name}: key {} repeated", settings.key());
        }
        assert_eq!(NAMES.len(), 9);
    }

    #[test]
    fn keys_name_every_setting() {
        let a = IntegratorSettings::Single {
            step: Some(MarchStep::Count(32)),
            sampling: SingleSampling::Mis,
            transmittance: TransmittanceMethod::RayMarch(MarchStep::Length(0.25)),
            volume_lights: false,
        };
        assert_eq!(a.key(), "single(steps=32, sampling=mis, transmittance=ray_march(step=0.25))");
        let lit = IntegratorSettings::Single {
            step: Some(MarchStep::Count(32)),
            sampling: SingleSampling::Mis,
            transmittance: TransmittanceMethod::RayMarch(MarchStep::Length(0.25)),
            volume_lights: true,
        };
        assert_eq!(lit.key(), "single(steps=32, sampling=mis, transmittance=ray_march(step=0.25), volume_lights=true)");
        let b = IntegratorSettings::Single {
            step: Some(MarchStep::Count(33)),
            sampling: SingleSampling::Mis,
            transmittance: TransmittanceMethod::RayMarch(MarchStep::Length(0.25)),
            volume_lights: false,
        };
        assert_ne!(a.key(), b.key());
    }
}
