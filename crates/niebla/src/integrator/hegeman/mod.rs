//! The `hegeman` integrator: single scattering plus an approximation of
//! multiple scattering around lights in inhomogeneous media, after Hegeman,
//! Ashikhmin and Premoze 2005 ("A lighting model for general participating
//! media", I3D 2005).
//!
//! **Reconstruction, not the paper's equations.** Only the paper's abstract
//! was available when this was written; this is a physically grounded
//! stand-in with the structure the abstract and its lineage describe
//! (Premoze, Ashikhmin, Ramamoorthi and Nayar 2004, "Practical rendering of
//! multiple scattering effects in participating media": a point spread
//! function along the most probable path, here the straight line from the
//! light, in small-angle transport theory): light arriving at a
//! point `u` of a view ray from each light is split into
//! - an unscattered beam, `E_0 = E exp(-tau_t)` from the light direction, and
//! - a scattered part `E_ms`, spread in angle around the light direction.
//!   Calibrated ([`Calibration::McTables`]): `E_ms = E F(tau_t)`
//!   and the angular spread convolved with the phase function `P(tau, mu)`
//!   both come from Monte Carlo tables of a homogeneous medium with the
//!   medium's `g` and albedo ([`calibration`]: a point source in an infinite
//!   medium for point lights, a plane wave into a half-space for directions),
//!   looked up at the line-integrated optical depth `tau_t`; for point
//!   lights the shape is taken at the depth `tau_t 3 M2 / (s^2 D0)` whose
//!   homogeneous width moment `M2 = int z^2 sigma_s (1 - g) dz` equals the
//!   actual one (z from the light). Uncalibrated ([`Calibration::None`],
//!   the default, which measures better on the test scenes):
//!   `E_ms = E exp(-tau_a) (1 - exp(-tau_s))` (`k_loss = 1`) blurred by a
//!   Gaussian of per-axis variance `w^2 = M2 / s^2` from small-angle
//!   (Fermi-Eyges) theory (for a directional light `w^2 = int sigma_s (1 - g)
//!   dz`), convolved with the phase function in [`blur`].
//!
//! The in-scattered radiance is `sigma_s [E_0 p(mu) + E_ms P(mu)]`, with the
//! convolved phase tabulated once per `g` (the "simple precomputation"),
//! and it is composited along the view
//! ray by ray marching. The line integrals toward each light are precomputed
//! on a lattice over each grid medium ([`line_integrals`]) and turned into the
//! per-node factors `exp(-tau_t)`, `exp(-tau_a)(1 - exp(-tau_s))` and `w`
//! whenever coefficients change (cheap); a view ray only fetches them.
//!
//! Scope: point, spot and directional lights; area lights as a few
//! Lambertian points ([`AREA_PATCHES`]^2 per rectangle or disk, one isotropic point
//! per sphere); a constant environment or an environment map is
//! approximated by [`ENVIRONMENT_DIRECTIONS`] directional lights (the cube's
//! diagonals, each carrying the radiance integral of its octant as
//! irradiance, with the phase function taken as isotropic for them, so that
//! their sum is one view-independent ambient term per lattice node). Volumetric shadows come from the
//! grid media only (surfaces do not shadow the medium). The blur uses a
//! Henyey-Greenstein lobe with the phase function's mean cosine; the sharp
//! term uses the true phase function. Homogeneous media segments use the
//! `analytic` integrator (single scattering only). Surfaces are lit directly,
//! their shadow rays' transmittance read from the line-integral lattices
//! (point, spot and directional lights on their own line, environments
//! through their octant directions; [`super::surface_shadows`]) or
//! ray-marched (`surface_shadows: "march"`, and area lights).

pub mod blur;
pub mod calibration;
pub mod cone;
pub mod line_integrals;
pub(crate) mod settings;

use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use crate::color::Rgb;
use crate::light::{AreaShape, Light, SpotLight};
use crate::math::{Ray, Vec3};
use crate::medium::{GridMedium, Medium, MediumId};
use crate::phase::PhaseFunction;
use crate::sampling::PixelSampler;
use crate::world::{Hit, Scene};

use super::surface_shadows::{
    lattice_transmittance, octant_diagonal, octant_transmittance, shadowed_surface_radiance, SurfaceShadows,
};
use super::{walk_camera_ray, AnalyticIntegrator, CameraRayVisitor, Integrator, JitteredSteps, SegmentRadiance};
use blur::BlurredPhaseTable;
use calibration::{CalibrationTable, Geometry};
use line_integrals::{LightSource, LineIntegralLattice};

/// Directional lights standing in for a constant environment.
pub const ENVIRONMENT_DIRECTIONS: usize = 8;

/// How the multiple-scattering term's energy and angular spread are set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Calibration {
    /// Monte Carlo tables ([`calibration`], first-crossing estimator): the
    /// scattered power `F(tau)`
    /// and the convolved phase `P(tau, mu)` of a homogeneous medium with the
    /// medium's `g` and albedo, looked up at the line-integrated optical
    /// depth; the angular profile at the depth whose homogeneous width moment
    /// equals the actual one (`M2` correction for inhomogeneous media).
    McTables,
    /// As `McTables`, with the tables of the scattered fluence (light coming
    /// back from beyond the receiver included: exact for an infinite
    /// medium, too bright in bounded ones).
    McFluence,
    /// The uncalibrated small-angle model (the default: it measures best
    /// against volpath on the smoke and cloud scenes, and ties with
    /// `McTables` on the point-lit fog): `k_loss = 1` and a Gaussian
    /// (heat-kernel) blur of the Fermi-Eyges width.
    None,
}

impl Calibration {
    /// Name in scene files (`"mc_tables"`, `"none"`).
    pub fn name(self) -> &'static str {
        match self {
            Calibration::McTables => "mc_tables",
            Calibration::McFluence => "mc_fluence",
            Calibration::None => "none",
        }
    }
}

/// How opaque surfaces inside a grid medium are lit besides the direct
/// light (ours, not in Hegeman et al. 2005).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceScattering {
    /// Direct light only (shadow rays), as before surfaces were lit by the model.
    Off,
    /// The scattered fluence of the medium's lattice at the surface point
    /// (`k_loss = 1` along the line toward the light: exact in a laterally
    /// unbounded medium, too bright in the shadow of a localized plume).
    Line,
    /// As `Line`, with the scattered term's optical depth averaged over the
    /// cone of single-scattering deflections around the line ([`cone`]): the
    /// same in an unbounded homogeneous medium, less light where the medium
    /// around the line is thinner than on it (the default).
    Cone,
}

impl SurfaceScattering {
    /// Name in scene files (`"off"`, `"line"`, `"cone"`).
    pub fn name(self) -> &'static str {
        match self {
            SurfaceScattering::Off => "off",
            SurfaceScattering::Line => "line",
            SurfaceScattering::Cone => "cone",
        }
    }
}

/// Parameters of the `hegeman` integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HegemanSettings {
    /// Calibration of the multiple-scattering term.
    pub calibration: Calibration,
    /// Photons per Monte Carlo table (tables are built once per process for
    /// each `g`, albedo and photon count).
    pub calibration_photons: u32,
    /// Include the multiple-scattering (blurred) term; `false` gives single
    /// scattering with precomputed shadow volumes.
    pub multiple_scattering: bool,
    /// Lattice nodes along the longest side of a grid medium's box (>= 2).
    pub resolution: u32,
    /// View-ray march step in lattice cells (> 0).
    pub step_cells: f32,
    /// How opaque surfaces inside a grid medium receive the model's
    /// multiply scattered light (`HegemanIntegrator::surface_scattered`;
    /// ours, not in Hegeman et al. 2005); default [`SurfaceScattering::Cone`].
    /// `Line` lights the fog's floor right on average but over-fills the
    /// smoke plume's shadow (all scattered light reaching the receiver, as
    /// in a laterally unbounded medium); `Off` is direct light only.
    pub surface_scattering: SurfaceScattering,
    /// Where the direct light's shadows on those surfaces come from: the
    /// lights' line-integral lattices, the environment's through its eight
    /// directions (default), or a ray march per shadow ray ([`SurfaceShadows`]).
    /// Ours, not in Hegeman et al. 2005.
    pub surface_shadows: SurfaceShadows,
}

impl Default for HegemanSettings {
    fn default() -> HegemanSettings {
        HegemanSettings {
            calibration: Calibration::None,
            calibration_photons: calibration::DEFAULT_PHOTONS,
            multiple_scattering: true,
            resolution: 48,
            step_cells: 1.0,
            surface_scattering: SurfaceScattering::Cone,
            surface_shadows: SurfaceShadows::LatticeEnvironment,
        }
    }
}

/// One light as the model sees it.
#[derive(Clone, Copy, Debug)]
struct ModelLight {
    source: LightSource,
    /// Intensity (W/sr) of a point or spot light, irradiance (W/m^2) of a direction.
    power: Rgb,
    emission: Emission,
    /// One of the directions standing in for a constant environment: folded
    /// into the per-node ambient term.
    ambient: bool,
    /// Index of the scene light this stands for (in `scene.lights`).
    scene_light: usize,
}

/// Angular distribution of a point source's intensity.
#[derive(Clone, Copy, Debug)]
enum Emission {
    /// The same in every direction.
    Isotropic,
    /// A spot light's falloff.
    Spot(SpotLight),
    /// A patch of an area light: `cos` to its front normal (both sides when
    /// two-sided).
    Lambert { normal: Vec3, two_sided: bool },
}

impl Emission {
    /// Intensity factor toward unit direction `w` (from the light).
    #[inline]
    fn factor(&self, w: Vec3) -> f32 {
        match self {
            Emission::Isotropic => 1.0,
            Emission::Spot(spot) => spot.falloff(w),
            Emission::Lambert { normal, two_sided } => {
                let c = normal.dot(w);
                if *two_sided {
                    c.abs()
                } else {
                    c.max(0.0)
                }
            }
        }
    }
}

/// The calibration tables of one grid medium (point and collimated geometry).
#[derive(Clone, Debug)]
struct Tables {
    point: Arc<CalibrationTable>,
    collimated: Arc<CalibrationTable>,
}

/// Floats per lattice node before the per-light factors: the ambient
/// in-scattered radiance (RGB).
const AMBIENT: usize = 3;

/// Factors per lattice node and light: `exp(-tau_t)` (3), the scattered
/// fluence ratio (3: `exp(-tau_a)(1 - exp(-tau_s))` uncalibrated, `F(tau_t)`
/// calibrated) and the blur coordinate (1: the width `w` uncalibrated, the
/// table row of the shape depth calibrated).
const FACTORS: usize = 7;

/// A grid medium's precomputation.
#[derive(Clone, Debug)]
struct GridModel {
    volumes: Vec<LineIntegralLattice>,
    lo: Vec3,
    hi: Vec3,
    n: [usize; 3],
    /// `stride` floats per node: ambient RGB, then `FACTORS` per non-ambient light.
    factors: Vec<f32>,
    stride: usize,
    blur: BlurredPhaseTable,
    tables: Option<Tables>,
    step: f32,
    /// Cone-averaged density integrals ([`cone::cone_depth`]) per node and
    /// non-ambient light (node-major), for [`SurfaceScattering::Cone`];
    /// empty otherwise.
    cone: Vec<f32>,
    /// The deflection `cone` was integrated with (NaN: not yet).
    cone_spread: f32,
}

/// The integrator with its precomputation (shadow/blur volumes per light and
/// grid medium, blurred-phase tables).
#[derive(Clone, Debug)]
pub struct HegemanIntegrator {
    settings: HegemanSettings,
    lights: Vec<ModelLight>,
    models: Vec<Option<GridModel>>,
    analytic: AnalyticIntegrator,
    /// The clamped cosine convolved with the blur (uncalibrated surface irradiance).
    irradiance: BlurredPhaseTable,
    /// Whether only point, spot and area lights are modelled
    /// ([`HegemanIntegrator::local_lights_only`]).
    local_only: bool,
    /// Multiplies every grid model's view-ray march step: 1 (the
    /// settings' step), or [`super::DRAG_STEP_FACTOR`] for a viewer's drag
    /// frames ([`HegemanIntegrator::set_drag_march`]).
    march_scale: f32,
    /// Per scene light, the index in `lights` (and in each model's
    /// `volumes`) of its lattice for surface shadows: point, spot and
    /// directional lights that the model holds; `None` for the others.
    shadow_slots: Vec<ShadowSlot>,
    /// Seconds spent in the precomputation.
    pub precompute_seconds: f64,
}

impl HegemanIntegrator {
    /// Precompute for `scene`: the line-integral lattices (per grid medium
    /// and light) and the per-node factors.
    pub fn new(scene: &Scene, settings: HegemanSettings) -> HegemanIntegrator {
        HegemanIntegrator::with_lights(scene, settings, model_lights(scene), false)
    }

    /// The model of the scene's point, spot and area lights only (for the
    /// `zhou` integrator's local lights).
    pub fn local_lights_only(scene: &Scene, settings: HegemanSettings) -> HegemanIntegrator {
        HegemanIntegrator::with_lights(scene, settings, local_model_lights(scene), true)
    }

    /// Whether any light lights the model.
    pub fn has_lights(&self) -> bool {
        !self.lights.is_empty()
    }

    /// Radiance scattered toward `wo` at `x` per unit `sigma_s` inside grid
    /// medium `id` (zero for other media).
    #[inline]
    pub fn in_scattered_at(&self, id: MediumId, phase: &PhaseFunction, x: Vec3, wo: Vec3) -> Rgb {
        match self.models.get(id.0 as usize) {
            Some(Some(model)) => self.in_scattered(model, phase, x, wo),
            _ => Rgb::ZERO,
        }
    }

    fn with_lights(
        scene: &Scene,
        settings: HegemanSettings,
        lights: Vec<ModelLight>,
        local_only: bool,
    ) -> HegemanIntegrator {
        let start = Instant::now();
        let resolution = settings.resolution.max(2) as usize;
        let models = scene
            .media
            .iter()
            .map(|m| match m {
                Medium::Grid(g) => {
                    let volumes: Vec<LineIntegralLattice> =
                        lights.iter().map(|l| LineIntegralLattice::new(g, l.source, resolution)).collect();
                    let (lo, hi) = g.world_bounds;
                    let longest = (hi - lo).max_element();
                    let step = settings.step_cells.max(0.05) * longest / resolution as f32;
                    let n = volumes.first().map_or([2, 2, 2], |v| v.dims());
                    let mut model = GridModel {
                        volumes,
                        lo,
                        hi,
                        n,
                        factors: Vec::new(),
                        stride: 0,
                        blur: BlurredPhaseTable::new(g.phase.mean_cosine()),
                        tables: calibration_tables(g, &settings),
                        step,
                        cone: Vec::new(),
                        cone_spread: f32::NAN,
                    };
                    model.update_factors(g, &lights, settings.multiple_scattering);
                    model.update_cone(g, &lights, &settings, false);
                    Some(model)
                }
                Medium::Homogeneous(_) => None,
            })
            .collect();
        HegemanIntegrator {
            shadow_slots: shadow_slots(scene, &lights),
            settings,
            lights,
            models,
            analytic: AnalyticIntegrator::new(),
            irradiance: BlurredPhaseTable::irradiance(),
            local_only,
            march_scale: 1.0,
            precompute_seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// March camera rays with a step [`super::DRAG_STEP_FACTOR`] times the
    /// settings' (`coarse`: a live viewer's drag frame; about that many
    /// times fewer density lookups, an approximate image) or with the
    /// settings' step (renders then equal a new precomputation's).
    pub fn set_drag_march(&mut self, coarse: bool) {
        self.march_scale = if coarse { super::DRAG_STEP_FACTOR } else { 1.0 };
    }

    /// Whether camera rays march the coarser drag step ([`Self::set_drag_march`]).
    pub fn is_drag_march(&self) -> bool {
        self.march_scale != 1.0
    }

    /// Bring the model up to date after the lights of `scene` were edited
    /// (intensity, color, position, direction; the same lights of the same
    /// kinds), the scene it was built for otherwise unchanged: a light's
    /// line-integral lattice depends only on the density and the light's
    /// position or direction, so lattices whose light did not move are
    /// kept and the others integrated again; the per-node factors are
    /// recomputed, so the result renders identically to a new precomputation.
    pub fn update_lights(&mut self, scene: &Scene) {
        let start = Instant::now();
        let lights = if self.local_only { local_model_lights(scene) } else { model_lights(scene) };
        let resolution = self.settings.resolution.max(2) as usize;
        for (model, medium) in self.models.iter_mut().zip(&scene.media) {
            let (Some(model), Medium::Grid(g)) = (model, medium) else { continue };
            let old = std::mem::take(&mut model.volumes);
            let mut old = old.into_iter();
            model.volumes = lights
                .iter()
                .map(|l| match old.next() {
                    Some(v) if v.source == l.source => v,
                    _ => LineIntegralLattice::new(g, l.source, resolution),
                })
                .collect();
            model.update_factors(g, &lights, self.settings.multiple_scattering);
            model.update_cone(g, &lights, &self.settings, true);
        }
        self.shadow_slots = shadow_slots(scene, &lights);
        self.lights = lights;
        self.precompute_seconds = start.elapsed().as_secs_f64();
    }

    /// Bring the model up to date after the coefficients, phase function or
    /// emission of the grid media flagged in `changed` (indexed like
    /// `scene.media`) were edited in `scene`, the scene it was built for
    /// otherwise unchanged: the line integrals are of the density alone and
    /// are kept; the blurred-phase and calibration tables and the per-node
    /// factors are recomputed as [`HegemanIntegrator::new`] computes them,
    /// so the result renders identically to a new precomputation.
    pub fn update_media(&mut self, scene: &Scene, changed: &[bool]) {
        let start = Instant::now();
        for (index, (model, medium)) in self.models.iter_mut().zip(&scene.media).enumerate() {
            let (Some(model), Medium::Grid(g), true) = (model, medium, changed.get(index) == Some(&true)) else {
                continue;
            };
            // The table depends on `g` alone: a drag of the density scale or
            // the albedo keeps it (the same values a new table would hold).
            let asymmetry = g.phase.mean_cosine();
            if model.blur.g().to_bits() != asymmetry.to_bits() {
                model.blur = BlurredPhaseTable::new(asymmetry);
            }
            model.tables = calibration_tables(g, &self.settings);
            model.update_factors(g, &self.lights, self.settings.multiple_scattering);
            model.update_cone(g, &self.lights, &self.settings, false);
        }
        self.precompute_seconds = start.elapsed().as_secs_f64();
    }

    /// Bytes held by the precomputation.
    pub fn memory_bytes(&self) -> usize {
        self.models
            .iter()
            .flatten()
            .map(|m| {
                m.volumes.iter().map(LineIntegralLattice::memory_bytes).sum::<usize>()
                    + m.factors.len() * 4
                    + m.cone.len() * 4
                    + m.blur.memory_bytes()
                    + m.tables.as_ref().map_or(0, |t| t.point.memory_bytes() + t.collimated.memory_bytes())
            })
            .sum()
    }

    /// Radiance scattered toward `wo` at `x` per unit `sigma_s` (the
    /// in-scattering integral `int p L_i`), from the lattice factors.
    #[inline]
    fn in_scattered(&self, model: &GridModel, phase: &PhaseFunction, x: Vec3, wo: Vec3) -> Rgb {
        let (base, weights) = model.corners(x);
        let stride = model.stride;
        let mut l = Rgb::ZERO;
        for (corner, w) in base.iter().zip(weights) {
            let o = corner * stride;
            l += Rgb::new(model.factors[o], model.factors[o + 1], model.factors[o + 2]) * w;
        }
        for (index, light) in self.lights.iter().filter(|l| !l.ambient).enumerate() {
            let mut f = [0f32; FACTORS];
            for (corner, w) in base.iter().zip(weights) {
                let o = corner * stride + AMBIENT + index * FACTORS;
                for (k, v) in f.iter_mut().enumerate() {
                    *v += w * model.factors[o + k];
                }
            }
            let (wi, mut e) = match light.source {
                LightSource::Point(p) => {
                    let v = p - x;
                    let d2 = v.length_squared();
                    if d2 == 0.0 {
                        continue;
                    }
                    let wi = v / d2.sqrt();
                    (wi, light.power / d2)
                }
                LightSource::Direction(w) => (w, light.power),
            };
            e *= light.emission.factor(-wi);
            if e.is_black() {
                continue;
            }
            let mu = -wo.dot(wi);
            let sharp = phase.eval(wo, wi);
            let mut s = Rgb::new(f[0], f[1], f[2]) * sharp;
            if self.settings.multiple_scattering {
                let scattered = Rgb::new(f[3], f[4], f[5]);
                s += match &model.tables {
                    Some(t) => {
                        let table = match light.source {
                            LightSource::Point(_) => &t.point,
                            LightSource::Direction(_) => &t.collimated,
                        };
                        scattered * table.phase(f[6], mu)
                    }
                    None => scattered * model.blur.eval(f[6], mu),
                };
            }
            l += e * s;
        }
        l
    }

    /// Transmittance of the segment `[0, t_end]` of a shadow ray toward
    /// scene light `light` inside medium `id` from the model's
    /// line-integral lattice toward that light
    /// ([`lattice_transmittance`]); `None` (march it) when the medium has
    /// no model or the light no lattice of its own (area and environment
    /// lights, whose shadow rays go elsewhere than the model's points).
    #[inline]
    fn shadow_transmittance(&self, scene: &Scene, light: usize, id: MediumId, ray: &Ray, t_end: f32) -> Option<Rgb> {
        let Some(Some(model)) = self.models.get(id.0 as usize) else { return None };
        if self.settings.surface_shadows == SurfaceShadows::Lattice
            && matches!(self.shadow_slots.get(light), Some(ShadowSlot::Octants(_)))
        {
            return None;
        }
        let Medium::Grid(g) = scene.medium(id) else { return None };
        match *self.shadow_slots.get(light)? {
            ShadowSlot::Line(slot) => Some(lattice_transmittance(g, model.volumes.get(slot)?, ray, t_end)),
            ShadowSlot::Octants(first) if t_end == f32::INFINITY => {
                Some(octant_transmittance(g, model.volumes.get(first..first + 8)?, ray.o, ray.d))
            }
            _ => None,
        }
    }

    /// Radiance leaving an opaque surface toward `wo` from the model's
    /// multiply scattered light (ours, not in Hegeman et al. 2005): at the
    /// surface point `p` (shading normal) inside grid medium `id`'s box, each
    /// light's scattered fluence ratio `F` (the lattice factor, as for the
    /// medium) times the irradiance of its blurred angular distribution on
    /// the surface, `E_ms C(w, n . wi)` ([`BlurredPhaseTable::irradiance`],
    /// or the calibration table's [`CalibrationTable::irradiance`]), times
    /// the BSDF at the light direction (at the normal where the light lies
    /// below the surface: exact for Lambertian surfaces, an approximation
    /// for glossy ones, whose lobe the blurred light does not resolve).
    /// Visibility of the light is the line integral's; surfaces do not
    /// shadow the medium's scattered light.
    fn surface_scattered(
        &self,
        id: MediumId,
        g: &GridMedium,
        surface: &crate::geometry::SurfaceHit,
        wo: Vec3,
        bsdf: &crate::bsdf::Bsdf,
    ) -> Rgb {
        let Some(Some(model)) = self.models.get(id.0 as usize) else { return Rgb::ZERO };
        let p = surface.p;
        // The lattice covers the medium's box only (its lookups clamp to the
        // box): surfaces outside it get no scattered light from the model.
        let margin = (model.hi - model.lo) * 1e-3;
        if p.cmplt(model.lo - margin).any() || p.cmpgt(model.hi + margin).any() {
            return Rgb::ZERO;
        }
        let ns = surface.shading_normal(wo);
        let n = if ns.dot(wo) < 0.0 { -ns } else { ns };
        let (base, weights) = model.corners(p);
        let stride = model.stride;
        let mut l = Rgb::ZERO;
        for (index, light) in self.lights.iter().filter(|l| !l.ambient).enumerate() {
            let mut f = [0f32; FACTORS];
            for (corner, w) in base.iter().zip(weights) {
                let o = corner * stride + AMBIENT + index * FACTORS;
                for (k, v) in f.iter_mut().enumerate() {
                    *v += w * model.factors[o + k];
                }
            }
            let scattered = match self.settings.surface_scattering {
                SurfaceScattering::Cone if !model.cone.is_empty() => {
                    let lights = model.cone.len() / (model.n[0] * model.n[1] * model.n[2]);
                    let depth: f32 = base.iter().zip(weights).map(|(c, w)| w * model.cone[c * lights + index]).sum();
                    model.scattered_ratio(g, light.source, depth)
                }
                _ => Rgb::new(f[3], f[4], f[5]),
            };
            if scattered.is_black() {
                continue;
            }
            let (wi, mut e) = match light.source {
                LightSource::Point(c) => {
                    let v = c - p;
                    let d2 = v.length_squared();
                    if d2 == 0.0 {
                        continue;
                    }
                    (v / d2.sqrt(), light.power / d2)
                }
                LightSource::Direction(w) => (w, light.power),
            };
            e *= light.emission.factor(-wi);
            let c = n.dot(wi);
            let cosine = match &model.tables {
                Some(t) => {
                    let table = match light.source {
                        LightSource::Point(_) => &t.point,
                        LightSource::Direction(_) => &t.collimated,
                    };
                    table.irradiance(f[6], c)
                }
                None => Rgb::splat(self.irradiance.eval(f[6], c)),
            };
            let toward = if c > 1e-3 { wi } else { n };
            let response = bsdf.eval(ns, wo, toward);
            l += response * e * scattered * cosine;
        }
        l
    }

    /// March a grid segment: front-to-back compositing with per-step opacity
    /// `1 - exp(-sigma_t dt)` (exact for a source constant over the step).
    fn grid_segment(
        &self,
        g: &GridMedium,
        model: &GridModel,
        ray: &Ray,
        t_end: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        let Some(steps) = JitteredSteps::new(g, ray, t_end, model.step * self.march_scale, sampler) else {
            return SegmentRadiance { radiance: Rgb::ZERO, transmittance: Rgb::ONE };
        };
        let dt = steps.dt;
        let (sigma_t, sigma_s) = (g.sigma_t(), g.sigma_s);
        let wo = -ray.d;
        let mut tr = Rgb::ONE;
        let mut l = Rgb::ZERO;
        let density = g.density_reader();
        // Steps of zero density add nothing: only those near occupied
        // majorant cells are visited (the same bits as visiting all).
        let _ = steps.occupied(g, ray, |range| {
            for k in range {
                let x = ray.at(steps.t(k));
                let d = density.at(x);
                if d <= 0.0 {
                    continue;
                }
                let st = sigma_t * d;
                let opacity = Rgb::ONE - (st * dt).exp_neg();
                let mut source = match g.albedo {
                    None => self.in_scattered(model, &g.phase, x, wo) * sigma_s * d,
                    // The model's factors use the field's largest albedo; the march
                    // scatters with the albedo at `x`.
                    Some(_) => self.in_scattered(model, &g.phase, x, wo) * g.absorption_scattering(x, d, 0.0).1,
                };
                source += g.l_ve(x, d);
                l += tr * source.safe_div(st) * opacity;
                tr *= Rgb::ONE - opacity;
                if tr.max_channel() < 1e-4 {
                    tr = Rgb::ZERO;
                    return ControlFlow::Break(());
                }
            }
            ControlFlow::Continue(())
        });
        SegmentRadiance { radiance: l, transmittance: tr }
    }
}

impl GridModel {
    /// Recompute the per-node factors from the line integrals for the
    /// medium's current coefficients (no marching: interactive editing of
    /// `sigma_t`, albedo and `g`). Nodes are independent, so they are
    /// computed in parallel with the same values as one thread would give.
    fn update_factors(&mut self, g: &GridMedium, lights: &[ModelLight], multiple: bool) {
        let nodes = self.n[0] * self.n[1] * self.n[2];
        let extent = self.hi - self.lo;
        let (sigma_t, sigma_s) = (g.sigma_t(), g.sigma_s);
        let sigma_a = g.sigma_a;
        let power = sigma_s.average() * (1.0 - g.phase.mean_cosine()).max(0.0);
        let stride = AMBIENT + FACTORS * lights.iter().filter(|l| !l.ambient).count();
        let mut factors = vec![0f32; nodes * stride];
        let model = &*self;
        factors.par_chunks_mut(stride).enumerate().with_min_len(512).for_each(|(node, chunk)| {
            let (x, y, z) = (node % model.n[0], (node / model.n[0]) % model.n[1], node / (model.n[0] * model.n[1]));
            let f = Vec3::new(
                x as f32 / (model.n[0] - 1) as f32,
                y as f32 / (model.n[1] - 1) as f32,
                z as f32 / (model.n[2] - 1) as f32,
            );
            let p = model.lo + extent * f;
            let mut slot = 0;
            for (index, light) in lights.iter().enumerate() {
                let [d0, d1, d2] = model.volumes[index].node(node);
                let sharp = (sigma_t * d0).exp_neg();
                let tau = sigma_t * d0;
                let table = model.tables.as_ref().map(|t| match light.source {
                    LightSource::Point(_) => &t.point,
                    LightSource::Direction(_) => &t.collimated,
                });
                let scattered = match (multiple, table) {
                    (false, _) => Rgb::ZERO,
                    (true, Some(table)) => table.fluence(tau),
                    (true, None) => (sigma_a * d0).exp_neg() * (Rgb::ONE - (sigma_s * d0).exp_neg()),
                };
                if light.ambient {
                    // Environment directions: phase taken as isotropic (a
                    // constant environment seen through no medium scatters
                    // isotropically for any phase function).
                    let ambient = light.power * (sharp + scattered) * (0.25 / std::f32::consts::PI);
                    for c in 0..3 {
                        chunk[c] += ambient[c];
                    }
                    continue;
                }
                let out = &mut chunk[AMBIENT + slot * FACTORS..AMBIENT + (slot + 1) * FACTORS];
                slot += 1;
                // Second moment of the density along the line, z from the
                // light: int z^2 d dz = s^2 D0 - 2 s D1 + D2 (D_n measured from p).
                let (m2, s2) = match light.source {
                    LightSource::Point(c) => {
                        let s = (c - p).length().max(1e-6);
                        ((s * s * d0 - 2.0 * s * d1 + d2).max(0.0), s * s)
                    }
                    LightSource::Direction(_) => (0.0, 0.0),
                };
                out[..3].copy_from_slice(&sharp.0);
                out[3..6].copy_from_slice(&scattered.0);
                out[6] = if model.tables.is_some() {
                    // M2 correction: the shape of a homogeneous medium whose
                    // width moment M2 = T s^3 / 3 equals the actual one,
                    // i.e. at depth tau * 3 M2 / (s^2 D0) (1 for a plane wave,
                    // whose angular spread does not depend on where it scattered).
                    let ratio = match light.source {
                        LightSource::Point(_) if d0 > 0.0 => (3.0 * m2 / (s2 * d0)).clamp(0.0, 3.0),
                        _ => 1.0,
                    };
                    calibration::row_of_tau(tau.average() * ratio)
                } else {
                    let w2 = match light.source {
                        LightSource::Point(_) => power * m2 / s2,
                        LightSource::Direction(_) => power * d0,
                    };
                    w2.max(0.0).sqrt()
                };
            }
        });
        self.factors = factors;
        self.stride = stride;
    }

    /// Integrate [`GridModel::cone`] for [`SurfaceScattering::Cone`] (and
    /// multiple scattering on; otherwise leave it empty): again when `moved`
    /// (the lights changed) or when the medium's mean cosine changed the
    /// deflection, else kept (it holds density only). One cone integral per
    /// node and non-ambient light, with the line integrals' step.
    fn update_cone(&mut self, g: &GridMedium, lights: &[ModelLight], settings: &HegemanSettings, moved: bool) {
        if settings.surface_scattering != SurfaceScattering::Cone || !settings.multiple_scattering {
            self.cone = Vec::new();
            return;
        }
        let spread = cone::deflection(g.phase.mean_cosine());
        if !moved && spread.to_bits() == self.cone_spread.to_bits() {
            return;
        }
        let sources: Vec<LightSource> = lights.iter().filter(|l| !l.ambient).map(|l| l.source).collect();
        let extent = self.hi - self.lo;
        let step = extent.max_element().max(1e-6) / settings.resolution.max(2) as f32;
        let (n, lo) = (self.n, self.lo);
        let mut cone = vec![0f32; n[0] * n[1] * n[2] * sources.len()];
        if !sources.is_empty() {
            // Base cells of the lattice's spacing (nodes - 1 cells per side).
            let pyramid = cone::DensityPyramid::new(g, n.map(|v| v.saturating_sub(1).max(1)));
            cone.par_chunks_mut(sources.len()).enumerate().with_min_len(64).for_each(|(node, out)| {
                let (x, y, z) = (node % n[0], (node / n[0]) % n[1], node / (n[0] * n[1]));
                let f =
                    Vec3::new(x as f32 / (n[0] - 1) as f32, y as f32 / (n[1] - 1) as f32, z as f32 / (n[2] - 1) as f32);
                for (o, source) in out.iter_mut().zip(&sources) {
                    *o = cone::cone_depth(g, &pyramid, lo + extent * f, *source, step, spread);
                }
            });
        }
        self.cone = cone;
        self.cone_spread = spread;
    }

    /// The scattered fluence ratio of the model for density integral
    /// `depth` toward a light of kind `source`: `exp(-tau_a) (1 - exp(-tau_s))`
    /// uncalibrated, the table's `F(tau_t)` calibrated (as the per-node factor).
    #[inline]
    fn scattered_ratio(&self, g: &GridMedium, source: LightSource, depth: f32) -> Rgb {
        match &self.tables {
            Some(t) => match source {
                LightSource::Point(_) => t.point.fluence(g.sigma_t() * depth),
                LightSource::Direction(_) => t.collimated.fluence(g.sigma_t() * depth),
            },
            None => (g.sigma_a * depth).exp_neg() * (Rgb::ONE - (g.sigma_s * depth).exp_neg()),
        }
    }

    /// Flat indices of the 8 lattice nodes around `x` and their trilinear weights.
    #[inline]
    fn corners(&self, x: Vec3) -> ([usize; 8], [f32; 8]) {
        let f = ((x - self.lo) / (self.hi - self.lo)).clamp(Vec3::ZERO, Vec3::ONE);
        let g = [f.x * (self.n[0] - 1) as f32, f.y * (self.n[1] - 1) as f32, f.z * (self.n[2] - 1) as f32];
        let i = [0, 1, 2].map(|a| (g[a] as usize).min(self.n[a] - 2));
        let t = [0, 1, 2].map(|a| g[a] - i[a] as f32);
        let mut base = [0usize; 8];
        let mut weights = [0f32; 8];
        for corner in 0..8 {
            let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            weights[corner] = (if dx == 1 { t[0] } else { 1.0 - t[0] })
                * (if dy == 1 { t[1] } else { 1.0 - t[1] })
                * (if dz == 1 { t[2] } else { 1.0 - t[2] });
            base[corner] = (i[0] + dx) + self.n[0] * ((i[1] + dy) + self.n[1] * (i[2] + dz));
        }
        (base, weights)
    }
}

/// Which of the model's lattices shadow surfaces from a scene light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ShadowSlot {
    /// None: shadow rays are marched.
    None,
    /// The model light standing for a point, spot or directional light, on
    /// the same line.
    Line(usize),
    /// The first of the eight environment directions standing for a
    /// constant or map environment, in octant order.
    Octants(usize),
}

/// Per scene light, the model lights whose line-integral lattices shadow
/// surfaces from it ([`HegemanIntegrator::shadow_slots`]).
fn shadow_slots(scene: &Scene, lights: &[ModelLight]) -> Vec<ShadowSlot> {
    scene
        .lights
        .iter()
        .enumerate()
        .map(|(index, light)| match super::surface_shadows::lattice_source(light) {
            Some(source) => lights
                .iter()
                .position(|l| l.scene_light == index && !l.ambient && l.source == source)
                .map_or(ShadowSlot::None, ShadowSlot::Line),
            None if light.is_infinite() => {
                let first = lights.iter().position(|l| l.scene_light == index && l.ambient);
                match first {
                    Some(first)
                        if lights.len() >= first + 8
                            && (0..8).all(|k| {
                                lights[first + k].scene_light == index
                                    && lights[first + k].source == LightSource::Direction(octant_diagonal(k))
                            }) =>
                    {
                        ShadowSlot::Octants(first)
                    }
                    _ => ShadowSlot::None,
                }
            }
            None => ShadowSlot::None,
        })
        .collect()
}

/// Points per side of the grid that stands in for a rectangular area light.
pub const AREA_PATCHES: usize = 2;

/// The calibration tables for a grid medium, or `None` when uncalibrated.
fn calibration_tables(g: &GridMedium, settings: &HegemanSettings) -> Option<Tables> {
    let estimator = match settings.calibration {
        _ if !settings.multiple_scattering => return None,
        Calibration::None => return None,
        Calibration::McTables => calibration::Estimator::FirstCrossing,
        Calibration::McFluence => calibration::Estimator::Fluence,
    };
    let albedo = g.sigma_s.safe_div(g.sigma_t());
    let asymmetry = g.phase.mean_cosine();
    let photons = settings.calibration_photons.max(1);
    Some(Tables {
        point: calibration::cached(Geometry::Point, estimator, asymmetry, albedo, photons),
        collimated: calibration::cached(Geometry::Collimated, estimator, asymmetry, albedo, photons),
    })
}

/// The scene's lights in the model: point, spot, directional; area lights
/// as points ([`AREA_PATCHES`]^2 Lambertian points per rectangle or disk, one
/// isotropic point per sphere); a constant environment or an environment
/// map as [`ENVIRONMENT_DIRECTIONS`] ambient directions.
/// [`model_lights`] that are points (point, spot and area lights).
fn local_model_lights(scene: &Scene) -> Vec<ModelLight> {
    let mut lights = model_lights(scene);
    lights.retain(|l| matches!(l.source, LightSource::Point(_)));
    lights
}

fn model_lights(scene: &Scene) -> Vec<ModelLight> {
    let mut lights = Vec::new();
    for (scene_light, light) in scene.lights.iter().enumerate() {
        match light {
            Light::Point(l) => lights.push(ModelLight {
                source: LightSource::Point(l.position),
                power: l.intensity,
                emission: Emission::Isotropic,
                ambient: false,
                scene_light,
            }),
            Light::Spot(l) => lights.push(ModelLight {
                source: LightSource::Point(l.position),
                power: l.intensity,
                emission: Emission::Spot(*l),
                ambient: false,
                scene_light,
            }),
            Light::Directional(l) => lights.push(ModelLight {
                source: LightSource::Direction(-l.direction),
                power: l.irradiance,
                emission: Emission::Isotropic,
                ambient: false,
                scene_light,
            }),
            Light::Constant(c) => {
                let share = 4.0 * std::f32::consts::PI / ENVIRONMENT_DIRECTIONS as f32;
                for k in 0..ENVIRONMENT_DIRECTIONS {
                    let s = |bit: usize| if k & bit == 0 { 1.0 } else { -1.0 };
                    let w = Vec3::new(s(1), s(2), s(4)).normalize();
                    lights.push(ModelLight {
                        source: LightSource::Direction(w),
                        power: c.radiance * share,
                        emission: Emission::Isotropic,
                        ambient: true,
                        scene_light,
                    });
                }
            }
            Light::Environment(map) => {
                // Each octant's radiance integral on its diagonal, as for a
                // constant environment (a uniform map gives the same lights).
                let mut octants = [Rgb::ZERO; ENVIRONMENT_DIRECTIONS];
                for y in 0..map.height() {
                    let omega = map.pixel_solid_angle(y);
                    for x in 0..map.width() {
                        let d = map.pixel_direction(x, y);
                        let k = usize::from(d.x < 0.0) | (usize::from(d.y < 0.0) << 1) | (usize::from(d.z < 0.0) << 2);
                        octants[k] += map.pixel(x, y) * omega;
                    }
                }
                for (k, power) in octants.into_iter().enumerate() {
                    let s = |bit: usize| if k & bit == 0 { 1.0 } else { -1.0 };
                    let w = Vec3::new(s(1), s(2), s(4)).normalize();
                    lights.push(ModelLight {
                        source: LightSource::Direction(w),
                        power,
                        emission: Emission::Isotropic,
                        ambient: true,
                        scene_light,
                    });
                }
            }
            Light::Area(area) => match &area.shape {
                // Seen from outside, a sphere of radiance L is a disk of
                // radiance L: intensity L pi r^2 in every direction.
                AreaShape::Sphere(sphere) => lights.push(ModelLight {
                    source: LightSource::Point(sphere.center),
                    power: area.radiance * (std::f32::consts::PI * sphere.radius * sphere.radius),
                    emission: Emission::Isotropic,
                    ambient: false,
                    scene_light,
                }),
                // A rectangle as AREA_PATCHES x AREA_PATCHES Lambertian
                // points at its cell centres, each of intensity L A_cell cos.
                AreaShape::Rectangle(rect) => {
                    let n = AREA_PATCHES;
                    let share = area.area() / (n * n) as f32;
                    for i in 0..n {
                        for j in 0..n {
                            let u = -1.0 + (2 * i + 1) as f32 / n as f32;
                            let v = -1.0 + (2 * j + 1) as f32 / n as f32;
                            lights.push(ModelLight {
                                source: LightSource::Point(rect.transform.point_to_world(Vec3::new(u, v, 0.0))),
                                power: area.radiance * share,
                                emission: Emission::Lambert { normal: rect.normal, two_sided: area.two_sided },
                                ambient: false,
                                scene_light,
                            });
                        }
                    }
                }
                // A disk as AREA_PATCHES rings x AREA_PATCHES sectors of
                // equal area, a Lambertian point at each cell's centre.
                AreaShape::Disk(disk) => {
                    let n = AREA_PATCHES;
                    let share = area.area() / (n * n) as f32;
                    for i in 0..n {
                        let r = ((i as f32 + 0.5) / n as f32).sqrt();
                        for j in 0..n {
                            let phi = 2.0 * std::f32::consts::PI * (j as f32 + 0.5) / n as f32;
                            let local = Vec3::new(r * phi.cos(), r * phi.sin(), 0.0);
                            lights.push(ModelLight {
                                source: LightSource::Point(disk.transform.point_to_world(local)),
                                power: area.radiance * share,
                                emission: Emission::Lambert { normal: disk.normal, two_sided: area.two_sided },
                                ambient: false,
                                scene_light,
                            });
                        }
                    }
                }
                // Not modelled: rendering refuses a scene with an emitting
                // mesh under hegeman and zhou (`PreparedIntegrator`'s scene
                // check names the light).
                AreaShape::Mesh(_) => {}
            },
        }
    }
    lights
}

/// The camera-ray walk of [`HegemanIntegrator`]: grid segments by the
/// model, surfaces lit directly and, with `surface_scattering`, by the
/// model's scattered light.
struct HegemanWalk<'a> {
    integrator: &'a HegemanIntegrator,
}

impl CameraRayVisitor for HegemanWalk<'_> {
    #[inline]
    fn segment(
        &mut self,
        scene: &Scene,
        m: &Medium,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        let h = self.integrator;
        match m {
            Medium::Grid(g) => match &h.models[id.0 as usize] {
                Some(model) => h.grid_segment(g, model, ray, t_end, sampler),
                None => h.analytic.segment(scene, id, ray, t_end, sampler),
            },
            Medium::Homogeneous(_) => h.analytic.segment(scene, id, ray, t_end, sampler),
        }
    }

    #[inline]
    fn opaque_surface(
        &mut self,
        scene: &Scene,
        hit: &Hit,
        wo: Vec3,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> Rgb {
        let bsdf = &scene.surface_bsdf(hit);
        let h = self.integrator;
        let mut l = shadowed_surface_radiance(
            h.settings.surface_shadows,
            scene,
            &hit.surface,
            wo,
            bsdf,
            medium,
            sampler,
            |light, id, ray, t| h.shadow_transmittance(scene, light, id, ray, t),
        );
        let lit = h.settings.surface_scattering != SurfaceScattering::Off && h.settings.multiple_scattering;
        if let (Some(id), true) = (medium, lit) {
            if let Some(Medium::Grid(g)) = scene.media.get(id.0 as usize) {
                l += h.surface_scattered(id, g, &hit.surface, wo, bsdf);
            }
        }
        l
    }
}

impl Integrator for HegemanIntegrator {
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb {
        walk_camera_ray(scene, ray, medium, sampler, &mut HegemanWalk { integrator: self })
    }
}
