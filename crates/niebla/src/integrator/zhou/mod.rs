//! The `zhou` integrator: compensated ray marching after Zhou, Ren, Lin,
//! Bao, Guo and Shum 2008 ("Real-time smoke rendering using compensated ray
//! marching", SIGGRAPH 2008), on the CPU.
//!
//! Only the paper's abstract and a prose paraphrase of its sections 3-5
//! (equations missing) were available when this was written; this is a
//! reconstruction of its method, with the deviations marked "ours" in each
//! module:
//! 1. **Density decomposition** ([`fit`]): the density, sampled on a lattice
//!    over each grid medium, is approximated by Gaussian RBFs
//!    `D~ = sum w_l exp(-|x - c_l|^2 / r_l^2)` (projected L-BFGS with
//!    analytic gradients and teleportation); the residual `R = D - D~` is the
//!    full grid minus `D~` (on the CPU no hash is needed). Fits are cached on
//!    disk per density ([`cache`]).
//! 2. **Source radiance at the centres** ([`lighting`]): transmittance of
//!    `D~` toward the environment in SH (a zonal table rotated per RBF pair,
//!    exponentiated on a sphere quadrature), times the SH environment
//!    (constant and lat-long maps), convolved with the phase function
//!    (`a_l`, `g^l` for Henyey-Greenstein). Ours: point, spot and directional
//!    lights are added with their transmittance from `D~` at each centre and
//!    the exact phase function at render time.
//! 3. **Multiple scattering** ([`diffusion`]): the diffusion equation driven
//!    by the band-0/1 moments of the single-scattering source, solved on the
//!    lattice with Marshak boundaries (ours; the paper collocates at the
//!    centres), giving an order-2 SH source `J_ms`.
//! 4. **Interpolation and compensated ray march**: `J~(x) = sum w_l B_l(x)
//!    J(c_l) / sum w_l B_l(x)` (Eq. 7) is stored per lattice node as SH; a
//!    per-view pass turns it into RGB toward the camera (the paper's volume
//!    pass), and each view ray marches the *full* density `D = D~ + R` with
//!    that source (variant A: the residual is
//!    compensated back into both the source and the attenuation along view
//!    rays), or `D~` for attenuation only (variant B), or `D~` everywhere
//!    (compensation off).
//!
//! 5. **Local lights** (ours; the paper has environment light only): with
//!    [`LocalLights::Hegeman`] (the default) point and spot lights are
//!    left out of steps 2-4 and lit by the calibrated `hegeman` model
//!    instead: single scattering with the transmittance of the full density
//!    along the straight line to the light (a line-integral lattice), plus
//!    its Monte Carlo calibrated multiple-scattering term. With
//!    [`LocalLights::Rbf`] they go through steps 2-4 like distant lights
//!    (their `D~` transmittance at each centre, their band-0/1 source in the
//!    diffusion), which overestimates badly when a light sits inside the
//!    medium (diffusion from a point source is singular there and the
//!    smooth `D~` shadows poorly).
//!
//! Scope: grid media (homogeneous media use the `analytic` integrator),
//! environment (constant, map), point, spot and directional lights; area
//! lights light the model only through [`LocalLights::Hegeman`] (as points). Surfaces are lit directly with ray-marched
//! shadow rays. The per-frame insertion scheme for animations and the
//! perfect spatial hash of the residual are not implemented (niebla renders
//! one density per scene, and the CPU reads the full grid directly).

// SH bands, channels and lattice axes index several parallel arrays at once;
// index loops say that more plainly than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod cache;
pub mod diffusion;
pub mod fit;
pub mod lattice;
pub mod lighting;
pub mod rbf;
pub(crate) mod settings;
pub mod sh;

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use crate::color::Rgb;
use crate::math::{Ray, Vec3};
use crate::medium::{GridMedium, Medium, MediumId};
use crate::sampling::PixelSampler;
use crate::world::Scene;

use super::hegeman::{Calibration, HegemanIntegrator, HegemanSettings, SurfaceScattering};
use super::surface_shadows::{shadowed_surface_radiance, ShadowLattices, SurfaceShadows};
use super::{walk_camera_ray, AnalyticIntegrator, CameraRayVisitor, Integrator, JitteredSteps, SegmentRadiance};
use fit::{FitReport, FitSettings};
use lattice::Lattice;
use lighting::{CentreDepth, ModelLight, ZonalDepthTable};
use rbf::Rbf;
use sh::SphereQuadrature;

/// How the residual `R = D - D~` enters the view-ray march.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compensation {
    /// Variant A: the full density `D` for the source and the attenuation.
    Full,
    /// Variant B: `D` for the source, `D~` for the attenuation (literal Eq. 8).
    SourceOnly,
    /// No compensation: `D~` everywhere (the low-frequency smoke alone).
    Off,
}

impl Compensation {
    /// Name in scene files and on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Compensation::Full => "full",
            Compensation::SourceOnly => "source",
            Compensation::Off => "off",
        }
    }
}

/// How point and spot lights (local lights, which the paper does not treat)
/// light the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocalLights {
    /// Like distant lights: their transmittance from the RBF density at the
    /// centres, interpolated, and their band-0/1 source in the diffusion.
    Rbf,
    /// Through the calibrated `hegeman` model instead (ours): single
    /// scattering with the transmittance of the full density along the line
    /// to the light (a line-integral lattice), plus its Monte Carlo
    /// calibrated multiple-scattering term; the RBF model, diffusion
    /// included, then handles only the environment and directional lights.
    Hegeman,
}

impl LocalLights {
    /// Name in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            LocalLights::Rbf => "rbf",
            LocalLights::Hegeman => "hegeman",
        }
    }
}

/// Parameters of the `zhou` integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZhouSettings {
    /// Number of RBFs per grid medium (the paper uses 300-1200).
    pub rbf_count: u32,
    /// L-BFGS iterations of the fit.
    pub fit_iterations: u32,
    /// Lattice nodes along the longest side of a grid medium's box (fit,
    /// diffusion and per-view source), >= 4.
    pub resolution: u32,
    /// SH order (bands `0..order`) of lighting, transmittance and source, 1-6.
    pub sh_order: u32,
    /// Include the diffusion (multiple-scattering) source.
    pub multiple_scattering: bool,
    /// How the residual enters the view-ray march.
    pub compensation: Compensation,
    /// Transmittance toward the environment evaluated in closed form per
    /// quadrature direction (the oracle) instead of the rotated zonal table.
    pub exact_transmittance: bool,
    /// View-ray march step in lattice cells (> 0).
    pub step_cells: f32,
    /// Read and write fits in the cache folder ([`cache::cache_dir`]).
    pub cache: bool,
    /// Point and spot lights.
    pub local_lights: LocalLights,
    /// Where the direct light's shadows on opaque surfaces inside grid
    /// media come from for point, spot and directional lights
    /// ([`SurfaceShadows`]; ours, not in Zhou et al. 2008): line-integral
    /// lattices of the full density toward each light and the environment's
    /// eight octant directions (default; the RBF density's transmittance
    /// would blur the shadows), toward the lights only, or a ray march per
    /// shadow ray.
    pub surface_shadows: SurfaceShadows,
}

impl Default for ZhouSettings {
    fn default() -> ZhouSettings {
        ZhouSettings {
            rbf_count: 600,
            fit_iterations: 60,
            resolution: 48,
            sh_order: 4,
            multiple_scattering: true,
            compensation: Compensation::Full,
            exact_transmittance: false,
            step_cells: 1.0,
            cache: true,
            local_lights: LocalLights::Hegeman,
            surface_shadows: SurfaceShadows::LatticeEnvironment,
        }
    }
}

/// Per grid medium: the lattice fields the view rays read.
#[derive(Clone, Debug)]
struct GridModel {
    lattice: Lattice,
    /// `D~` per node.
    smooth: Vec<f32>,
    /// Source radiance `J~` per node as SH, `3 x order^2` per node.
    source_sh: Vec<f32>,
    /// `J~` toward the current camera per node (RGB).
    view: Vec<f32>,
    /// Transmittance (RGB) of `D~` toward each model light, interpolated from the centres.
    light_transmittance: Vec<f32>,
    albedo: Rgb,
    step: f32,
    /// RBFs in world units.
    rbfs: Vec<Rbf>,
    fit: FitReport,
    /// Lit on the coarser preview lattice ([`ZhouIntegrator::update_media_preview`]).
    preview: bool,
    /// The optical depths of `D~` from the centres, kept for the next relight.
    depths: CentreDepths,
}

/// Optical depths (density x length) of `D~` seen from the RBF centres:
/// toward the environment ([`lighting::centre_depth_sh`], or the exact one
/// per quadrature direction) and toward each model light
/// ([`lighting::centre_light_depths`]). They depend on the fit and on the
/// lights' positions or directions only, not on the medium's coefficients,
/// so a medium edit (a density-scale drag) reuses them unchanged and a light
/// edit recomputes only the light depths, when a light moved.
#[derive(Clone, Debug, Default)]
struct CentreDepths {
    /// Whether computed exactly (`exact_transmittance`), with the values:
    /// `N x order^2` SH coefficients, or `N x directions` exact depths.
    environment: Option<(bool, Vec<f64>)>,
    /// The lights' geometry ([`light_geometry`]) and `N x lights` depths.
    lights: Option<(Vec<[f32; 4]>, Vec<f64>)>,
}

/// What a model light's depths depend on: its position (tag 0) or its
/// direction toward the light (tag 1).
fn light_geometry(light: &ModelLight) -> [f32; 4] {
    match *light {
        ModelLight::Point { position, .. } => [0.0, position.x, position.y, position.z],
        ModelLight::Directional { toward, .. } => [1.0, toward.x, toward.y, toward.z],
    }
}

/// A preview relight ([`ZhouIntegrator::update_media_preview`]) lights a
/// lattice with `resolution / PREVIEW_DIVISOR` cells along the longest
/// side (at least 8): about `PREVIEW_DIVISOR^3` times fewer nodes to
/// interpolate the source to, to solve the diffusion on and to run the
/// per-view pass over (16^3 instead of 48^3 at the default resolution).
pub const PREVIEW_DIVISOR: usize = 3;

/// The integrator with its precomputation.
#[derive(Clone, Debug)]
pub struct ZhouIntegrator {
    settings: ZhouSettings,
    lights: Vec<ModelLight>,
    models: Vec<Option<GridModel>>,
    analytic: AnalyticIntegrator,
    /// The light model of point and spot lights ([`LocalLights::Hegeman`]).
    local: Option<HegemanIntegrator>,
    /// Line integrals toward the point, spot and directional lights for
    /// the shadows on surfaces ([`SurfaceShadows::Lattice`]; empty otherwise).
    shadows: ShadowLattices,
    /// Multiplies every grid model's view-ray march step: 1 (the
    /// settings' step), or [`super::DRAG_STEP_FACTOR`] for a viewer's drag
    /// frames ([`ZhouIntegrator::set_drag_march`]).
    march_scale: f32,
    /// Seconds spent fitting RBFs (0 when every fit came from the cache).
    pub fit_seconds: f64,
    /// Seconds spent on lighting, diffusion and the view pass.
    pub lighting_seconds: f64,
}

impl ZhouIntegrator {
    /// Precompute for `scene`: fit (or load) the RBFs of every grid medium,
    /// compute the source radiance and the view pass for the scene's camera.
    pub fn new(scene: &Scene, settings: ZhouSettings) -> ZhouIntegrator {
        ZhouIntegrator::new_cancellable(scene, settings, None).expect("no cancel flag")
    }

    /// [`ZhouIntegrator::new`], giving up (`None`, no partial result) as
    /// soon as the fit, the lighting or the diffusion finds `cancel` set.
    pub fn new_cancellable(
        scene: &Scene,
        settings: ZhouSettings,
        cancel: Option<&AtomicBool>,
    ) -> Option<ZhouIntegrator> {
        let mut lights = ModelLight::from_scene(&scene.lights);
        let start = Instant::now();
        let local = match settings.local_lights {
            LocalLights::Rbf => None,
            LocalLights::Hegeman => {
                lights.retain(|l| matches!(l, ModelLight::Directional { .. }));
                let local = HegemanIntegrator::local_lights_only(
                    scene,
                    HegemanSettings {
                        multiple_scattering: settings.multiple_scattering,
                        calibration: Calibration::McTables,
                        // zhou lights surfaces itself: no cone integrals.
                        surface_scattering: SurfaceScattering::Off,
                        ..HegemanSettings::default()
                    },
                );
                local.has_lights().then_some(local)
            }
        };
        let shadows = match settings.surface_shadows {
            SurfaceShadows::Lattice => ShadowLattices::new(scene, settings.resolution.max(4) as usize, false),
            SurfaceShadows::LatticeEnvironment => ShadowLattices::new(scene, settings.resolution.max(4) as usize, true),
            SurfaceShadows::March => ShadowLattices::default(),
        };
        let local_seconds = start.elapsed().as_secs_f64();
        let mut fit_seconds = 0.0;
        let mut lighting_seconds = 0.0;
        let mut models = Vec::with_capacity(scene.media.len());
        for m in &scene.media {
            models.push(match m {
                Medium::Grid(g) => {
                    let start = Instant::now();
                    let (lattice, rbfs, smooth, fit) = decompose(g, &settings, cancel)?;
                    fit_seconds += start.elapsed().as_secs_f64();
                    let start = Instant::now();
                    let depths = CentreDepths::default();
                    let mut model =
                        light_model(scene, g, &settings, &lights, lattice, rbfs, smooth, fit, depths, cancel)?;
                    model.set_view(scene.camera.position, settings.sh_order as usize);
                    lighting_seconds += start.elapsed().as_secs_f64();
                    Some(model)
                }
                Medium::Homogeneous(_) => None,
            });
        }
        Some(ZhouIntegrator {
            settings,
            lights,
            models,
            analytic: AnalyticIntegrator::new(),
            local,
            shadows,
            march_scale: 1.0,
            fit_seconds,
            lighting_seconds: lighting_seconds + local_seconds,
        })
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

    /// Recompute the per-view source for a camera at `eye` (cheap: no fit,
    /// no lighting).
    pub fn set_view(&mut self, eye: Vec3) {
        let order = self.settings.sh_order as usize;
        for model in self.models.iter_mut().flatten() {
            model.set_view(eye, order);
        }
    }

    /// Bring the precomputation up to date after the coefficients, phase
    /// function or emission of the grid media flagged in `changed` (indexed
    /// like `scene.media`) were edited in `scene`, the scene it was built
    /// for otherwise unchanged (the camera may have moved): the density
    /// lattice and its RBF fit depend on the density alone and are kept;
    /// the lighting, the diffusion and the view pass run again as in
    /// [`ZhouIntegrator::new`], so the result renders identically to a new
    /// precomputation. `false` when `cancel` stopped it: the integrator is
    /// then half updated and must be dropped.
    /// A medium lit on the preview lattice ([`Self::update_media_preview`])
    /// is lit again on the full one here even when not flagged in `changed`.
    pub fn update_media(&mut self, scene: &Scene, changed: &[bool], cancel: Option<&AtomicBool>) -> bool {
        self.update_media_with(scene, changed, false, cancel)
    }

    /// [`Self::update_media`] for an interactive frame: the lighting and
    /// diffusion of the flagged media run on a lattice `PREVIEW_DIVISOR`
    /// times coarser along each axis, built over the same box from the
    /// same RBFs (world units, so no new fit), and the view pass on it. The
    /// image approximates the full precomputation's (the view rays still
    /// march the real density); [`Self::is_preview`] is then true until a
    /// full update ([`Self::update_media`] or [`Self::update_lights`])
    /// lights those media on the full lattice again, which renders
    /// identically to a new precomputation.
    pub fn update_media_preview(&mut self, scene: &Scene, changed: &[bool], cancel: Option<&AtomicBool>) -> bool {
        self.update_media_with(scene, changed, true, cancel)
    }

    /// True when some medium is lit on the preview lattice.
    pub fn is_preview(&self) -> bool {
        self.models.iter().flatten().any(|m| m.preview)
    }

    fn update_media_with(
        &mut self,
        scene: &Scene,
        changed: &[bool],
        preview: bool,
        cancel: Option<&AtomicBool>,
    ) -> bool {
        let start = Instant::now();
        if let Some(local) = &mut self.local {
            local.update_media(scene, changed);
        }
        let done = self.relight(scene, |index| changed.get(index) == Some(&true), preview, cancel);
        self.lighting_seconds = start.elapsed().as_secs_f64();
        done
    }

    /// Bring the precomputation up to date after the lights of `scene` were
    /// edited (intensity, color, position, direction; the same lights of
    /// the same kinds), the scene it was built for otherwise unchanged (the
    /// camera may have moved, and the scalars of the media flagged in
    /// `changed_media`, as in [`ZhouIntegrator::update_media`]): the fits
    /// are kept; the local-light model is updated ([`HegemanIntegrator::update_lights`]) and the lighting, the
    /// diffusion and the view pass of every grid medium run again, so the
    /// result renders identically to a new precomputation. `false` when
    /// `cancel` stopped it: the integrator is then half updated and must be
    /// dropped.
    pub fn update_lights(&mut self, scene: &Scene, changed_media: &[bool], cancel: Option<&AtomicBool>) -> bool {
        self.update_lights_with(scene, changed_media, false, cancel)
    }

    /// [`Self::update_lights`] for an interactive frame: every grid medium
    /// is lit on the preview lattice, as in [`Self::update_media_preview`].
    pub fn update_lights_preview(
        &mut self,
        scene: &Scene,
        changed_media: &[bool],
        cancel: Option<&AtomicBool>,
    ) -> bool {
        self.update_lights_with(scene, changed_media, true, cancel)
    }

    fn update_lights_with(
        &mut self,
        scene: &Scene,
        changed_media: &[bool],
        preview: bool,
        cancel: Option<&AtomicBool>,
    ) -> bool {
        let start = Instant::now();
        self.lights = ModelLight::from_scene(&scene.lights);
        if self.settings.local_lights == LocalLights::Hegeman {
            self.lights.retain(|l| matches!(l, ModelLight::Directional { .. }));
        }
        if let Some(local) = &mut self.local {
            local.update_media(scene, changed_media);
            local.update_lights(scene);
        }
        if self.settings.surface_shadows != SurfaceShadows::March {
            self.shadows.update_lights(scene);
        }
        let done = self.relight(scene, |_| true, preview, cancel);
        self.lighting_seconds = start.elapsed().as_secs_f64();
        done
    }

    /// Run the lighting, diffusion and view pass again for the grid media
    /// whose index `redo` accepts (and, unless `preview`, for those lit on
    /// the preview lattice), keeping their fits: on the full lattice, or on
    /// the preview lattice when `preview` (`D~` evaluated on it from the
    /// same RBFs); `false` when `cancel` stopped it (some models are then
    /// left empty).
    fn relight(
        &mut self,
        scene: &Scene,
        redo: impl Fn(usize) -> bool,
        preview: bool,
        cancel: Option<&AtomicBool>,
    ) -> bool {
        let order = self.settings.sh_order as usize;
        let full = self.settings.resolution.max(4) as usize;
        let resolution = if preview { (full / PREVIEW_DIVISOR).max(8).min(full) } else { full };
        for (index, (model, medium)) in self.models.iter_mut().zip(&scene.media).enumerate() {
            let (Some(model), Medium::Grid(g)) = (model.as_mut(), medium) else {
                continue;
            };
            if !(redo(index) || (model.preview && !preview)) {
                // Kept lighting; the camera may have moved.
                model.set_view(scene.camera.position, order);
                continue;
            }
            let (lo, hi) = g.world_bounds;
            // The lattice `decompose` makes (full), or the coarser preview one.
            let lattice = Lattice::over_box(lo, hi, resolution);
            let rbfs = std::mem::take(&mut model.rbfs);
            let smooth = if lattice == model.lattice {
                std::mem::take(&mut model.smooth)
            } else {
                rbf::evaluate_at_nodes(&lattice, &rbfs)
            };
            let fit = std::mem::replace(
                &mut model.fit,
                FitReport { relative_error: 0.0, history: Vec::new(), teleports_kept: 0 },
            );
            let depths = std::mem::take(&mut model.depths);
            let Some(relit) =
                light_model(scene, g, &self.settings, &self.lights, lattice, rbfs, smooth, fit, depths, cancel)
            else {
                return false;
            };
            *model = relit;
            model.preview = resolution != full;
            model.set_view(scene.camera.position, order);
        }
        self.fit_seconds = 0.0;
        true
    }

    /// Relative L2 error `||D - D~|| / ||D||` of each grid medium's fit.
    pub fn fit_errors(&self) -> Vec<f64> {
        self.models.iter().flatten().map(|m| m.fit.relative_error).collect()
    }

    /// The fitted RBFs (world units) of each grid medium.
    pub fn rbfs(&self) -> Vec<&[Rbf]> {
        self.models.iter().flatten().map(|m| m.rbfs.as_slice()).collect()
    }

    /// Bytes held by the precomputation.
    pub fn memory_bytes(&self) -> usize {
        self.models
            .iter()
            .flatten()
            .map(|m| {
                4 * (m.smooth.len() + m.source_sh.len() + m.view.len() + m.light_transmittance.len())
                    + m.rbfs.len() * std::mem::size_of::<Rbf>()
            })
            .sum::<usize>()
            + self.local.as_ref().map_or(0, HegemanIntegrator::memory_bytes)
            + self.shadows.memory_bytes()
    }

    /// March a grid segment with the interpolated source, compositing front
    /// to back with per-step opacity `1 - exp(-sigma_t D_att dt)`.
    fn grid_segment(
        &self,
        g: &GridMedium,
        id: MediumId,
        model: &GridModel,
        ray: &Ray,
        t_end: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        let Some(steps) = JitteredSteps::new(g, ray, t_end, model.step * self.march_scale, sampler) else {
            return SegmentRadiance { radiance: Rgb::ZERO, transmittance: Rgb::ONE };
        };
        let dt = steps.dt;
        let sigma_t = g.sigma_t();
        let wo = -ray.d;
        let lattice = &model.lattice;
        let nl = self.lights.len();
        let mut tr = Rgb::ONE;
        let mut l = Rgb::ZERO;
        let density = g.density_reader();
        // With full compensation, steps of zero density add nothing: only
        // those near occupied majorant cells are visited (the same bits as
        // visiting all). The other modes attenuate or shine with `D~`,
        // which is not zero there.
        let mut march = |range: std::ops::Range<usize>| {
            for k in range {
                let x = ray.at(steps.t(k));
                let (d_att, d_src) = match self.settings.compensation {
                    Compensation::Full => {
                        let d = density.at(x);
                        (d, d)
                    }
                    Compensation::SourceOnly => (lattice.interpolate(&model.smooth, x), density.at(x)),
                    Compensation::Off => {
                        let d = lattice.interpolate(&model.smooth, x);
                        (d, d)
                    }
                };
                if d_att <= 0.0 && d_src <= 0.0 {
                    continue;
                }
                let (base, weights) = lattice.corners(x);
                let mut j = Rgb::ZERO;
                for (&node, w) in base.iter().zip(weights) {
                    j += Rgb::new(model.view[3 * node], model.view[3 * node + 1], model.view[3 * node + 2]) * w;
                }
                for (index, light) in self.lights.iter().enumerate() {
                    let Some((wi, _, e)) = light.toward(x) else { continue };
                    if e.is_black() {
                        continue;
                    }
                    let mut t = Rgb::ZERO;
                    for (&node, w) in base.iter().zip(weights) {
                        let o = 3 * (node * nl + index);
                        t += Rgb::new(
                            model.light_transmittance[o],
                            model.light_transmittance[o + 1],
                            model.light_transmittance[o + 2],
                        ) * w;
                    }
                    j += model.albedo * e * t * g.phase.eval(wo, wi);
                }
                if let Some(local) = &self.local {
                    j += model.albedo * local.in_scattered_at(id, &g.phase, x, wo);
                }
                let st_att = sigma_t * d_att.max(0.0);
                let source = sigma_t * j * d_src.max(0.0) + g.l_ve(x, d_src.max(0.0));
                let att = (st_att * dt).exp_neg();
                let mut weight = Rgb::ZERO;
                for c in 0..3 {
                    weight[c] = if st_att[c] * dt > 1e-6 { (1.0 - att[c]) / st_att[c] } else { dt };
                }
                l += tr * source * weight;
                tr *= att;
                if tr.max_channel() < 1e-4 {
                    tr = Rgb::ZERO;
                    return ControlFlow::Break(());
                }
            }
            ControlFlow::Continue(())
        };
        let _ = match self.settings.compensation {
            Compensation::Full => steps.occupied(g, ray, march),
            Compensation::SourceOnly | Compensation::Off => march(0..steps.n),
        };
        SegmentRadiance { radiance: l, transmittance: tr }
    }
}

/// Sample the medium's density on a lattice (2x2x2 supersampled cell
/// averages), fit RBFs (or load them from the cache) and evaluate `D~` on the lattice.
fn decompose(
    g: &GridMedium,
    settings: &ZhouSettings,
    cancel: Option<&AtomicBool>,
) -> Option<(Lattice, Vec<Rbf>, Vec<f32>, FitReport)> {
    let (lo, hi) = g.world_bounds;
    let lattice = Lattice::over_box(lo, hi, settings.resolution.max(4) as usize);
    let density: Vec<f32> = (0..lattice.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|node| {
            let p = lattice.position_of(node);
            let mut sum = 0.0;
            for k in 0..8 {
                let o = Vec3::new(
                    if k & 1 == 0 { -0.25 } else { 0.25 },
                    if k & 2 == 0 { -0.25 } else { 0.25 },
                    if k & 4 == 0 { -0.25 } else { 0.25 },
                );
                sum += g.density_at(p + o * lattice.h).max(0.0);
            }
            sum / 8.0
        })
        .collect();
    let fit_settings = FitSettings {
        count: settings.rbf_count as usize,
        iterations: settings.fit_iterations as usize,
        teleport_every: 20,
        seed: 1,
    };
    let key = cache::fit_key(lattice.n, &density, &fit_settings);
    let cached = if settings.cache { cache::load(key) } else { None };
    let (local, fit) = match cached {
        Some((rbfs, error)) => (rbfs, FitReport { relative_error: error, history: Vec::new(), teleports_kept: 0 }),
        None => {
            let (rbfs, report) = fit::fit_rbfs_cancellable(&lattice, &density, &fit_settings, cancel)?;
            if settings.cache {
                cache::store(key, &rbfs, report.relative_error);
            }
            (rbfs, report)
        }
    };
    let rbfs: Vec<Rbf> = local.iter().map(|r| lattice.rbf_to_world(r)).collect();
    let smooth = rbf::evaluate_at_nodes(&lattice, &rbfs);
    Some((lattice, rbfs, smooth, fit))
}

/// Source radiance at the centres (single scattering, plus diffusion),
/// interpolated to the lattice as SH, and the light transmittances;
/// `None` when `cancel` is found set between its steps.
#[allow(clippy::too_many_arguments)]
fn light_model(
    scene: &Scene,
    g: &GridMedium,
    settings: &ZhouSettings,
    lights: &[ModelLight],
    lattice: Lattice,
    rbfs: Vec<Rbf>,
    smooth: Vec<f32>,
    fit: FitReport,
    mut depths: CentreDepths,
    cancel: Option<&AtomicBool>,
) -> Option<GridModel> {
    let cancelled = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
    let order = (settings.sh_order as usize).clamp(1, sh::MAX_ORDER);
    let nc = order * order;
    let sigma_t = g.sigma_t();
    let albedo = g.sigma_s.safe_div(sigma_t);
    let convolution = sh::phase_convolution(&g.phase, order.max(2));
    let quadrature = SphereQuadrature::new(order);
    let environment = lighting::environment_sh(&scene.lights, order);
    let n = rbfs.len();
    let j_ss = if environment.iter().any(|e| e.iter().any(|v| *v != 0.0)) && n > 0 {
        let exact = settings.exact_transmittance;
        let depth = match depths.environment.take() {
            // Kept from the last relight (same fit, order and method).
            Some((kept_exact, depth)) if kept_exact == exact => depth,
            _ if exact => lighting::centre_depth_exact(&rbfs, &quadrature),
            _ => lighting::centre_depth_sh(&rbfs, &ZonalDepthTable::new(order)),
        };
        let j_ss = lighting::single_scattering_sh(
            n,
            &quadrature,
            &environment,
            if exact { CentreDepth::Exact(&depth) } else { CentreDepth::Sh(&depth) },
            sigma_t,
            albedo,
            &convolution,
        );
        depths.environment = Some((exact, depth));
        j_ss
    } else {
        vec![0.0; n * 3 * nc]
    };
    if cancelled() {
        return None;
    }
    // Per centre: J_ss SH (3 nc), light transmittances (3 per light), and
    // the band-0/1 source of the lights (3 x 4) for the diffusion.
    let nl = lights.len();
    let stride = 3 * nc + 3 * nl + 12;
    let geometry: Vec<[f32; 4]> = lights.iter().map(light_geometry).collect();
    let light_depth = match depths.lights.take() {
        Some((kept, depth)) if kept == geometry => depth,
        _ => lighting::centre_light_depths(&rbfs, lights),
    };
    let mut per_centre = vec![0.0f64; n * stride];
    for (l, row) in per_centre.chunks_mut(stride).enumerate() {
        row[..3 * nc].copy_from_slice(&j_ss[l * 3 * nc..(l + 1) * 3 * nc]);
        let mut y = [0f64; 4];
        for (k, light) in lights.iter().enumerate() {
            let t = (sigma_t * -(light_depth[l * nl + k] as f32)).map(f32::exp);
            for c in 0..3 {
                row[3 * nc + 3 * k + c] = t[c] as f64;
            }
            if let Some((wi, _, e)) = light.toward(rbfs[l].center) {
                sh::eval_basis(2, sh::dir64(wi), &mut y);
                for c in 0..3 {
                    let f = (albedo[c] * e[c] * t[c]) as f64;
                    for b in 0..4 {
                        let band = if b == 0 { 0 } else { 1 };
                        row[3 * nc + 3 * nl + 4 * c + b] += f * convolution[band] * y[b];
                    }
                }
            }
        }
    }
    let nodes_values = if n > 0 {
        rbf::interpolate_at_nodes(&lattice, &rbfs, &per_centre, stride)
    } else {
        vec![0.0; lattice.len() * stride]
    };
    if cancelled() {
        return None;
    }
    let nodes = lattice.len();
    let mut source_sh = vec![0f32; nodes * 3 * nc];
    let mut light_transmittance = vec![0f32; nodes * 3 * nl];
    for node in 0..nodes {
        let v = &nodes_values[node * stride..(node + 1) * stride];
        source_sh[node * 3 * nc..(node + 1) * 3 * nc].copy_from_slice(&v[..3 * nc]);
        light_transmittance[node * 3 * nl..(node + 1) * 3 * nl].copy_from_slice(&v[3 * nc..3 * nc + 3 * nl]);
    }
    if settings.multiple_scattering && n > 0 {
        let g_mean = convolution[1];
        let k0 = (4.0 * std::f64::consts::PI).sqrt();
        let k1 = (3.0 / (4.0 * std::f64::consts::PI)).sqrt();
        for c in 0..3 {
            if cancelled() {
                return None;
            }
            let sigma: Vec<f64> = smooth.iter().map(|d| (sigma_t[c] * d.max(0.0)) as f64).collect();
            let mut j0 = vec![0.0; nodes];
            let mut j1 = vec![0.0; 3 * nodes];
            for node in 0..nodes {
                let v = &nodes_values[node * stride..(node + 1) * stride];
                let lights_low = &v[3 * nc + 3 * nl + 4 * c..3 * nc + 3 * nl + 4 * c + 4];
                let mut low = [0f64; 4];
                for b in 0..4.min(nc) {
                    low[b] = v[c * nc + b] as f64;
                }
                for b in 0..4 {
                    low[b] += lights_low[b] as f64;
                }
                j0[node] = low[0] / k0;
                // Arriving -> propagation convention: the first moment flips sign.
                j1[3 * node] = -k1 * low[3];
                j1[3 * node + 1] = -k1 * low[1];
                j1[3 * node + 2] = -k1 * low[2];
            }
            let solution = diffusion::solve(
                &lattice,
                &sigma,
                albedo[c] as f64,
                g_mean,
                &diffusion::DiffusionSource { j0: &j0, j1: &j1 },
            );
            let m1 = (4.0 * std::f64::consts::PI / 3.0).sqrt();
            let a = albedo[c] as f64;
            for node in 0..nodes {
                let o = node * 3 * nc + c * nc;
                let (l0, l1) = (solution.l0[node], &solution.l1[3 * node..3 * node + 3]);
                source_sh[o] += (a * k0 * l0) as f32;
                if nc >= 4 {
                    source_sh[o + 1] += (-a * g_mean * m1 * l1[1]) as f32;
                    source_sh[o + 2] += (-a * g_mean * m1 * l1[2]) as f32;
                    source_sh[o + 3] += (-a * g_mean * m1 * l1[0]) as f32;
                }
            }
        }
    }
    let longest = lattice.h * *lattice.n.iter().max().unwrap() as f32;
    let step = settings.step_cells.max(0.05) * longest / settings.resolution.max(4) as f32;
    Some(GridModel {
        lattice,
        smooth,
        source_sh,
        view: vec![0.0; nodes * 3],
        light_transmittance,
        albedo,
        step,
        rbfs,
        fit,
        preview: false,
        depths: CentreDepths { lights: Some((geometry, light_depth)), ..depths },
    })
}

impl GridModel {
    /// The per-view pass: `J~(x, w_o)` RGB at every node for `w_o` from the
    /// eye through the node (Zhou's convention: `w_o` points from the camera
    /// into the scene; forward scattering is `w_o = w_i`).
    fn set_view(&mut self, eye: Vec3, order: usize) {
        let order = order.clamp(1, sh::MAX_ORDER);
        let nc = order * order;
        let lattice = self.lattice;
        let source = &self.source_sh;
        self.view.par_chunks_mut(3).enumerate().with_min_len(256).for_each(|(node, out)| {
            let p = lattice.position_of(node);
            let w = (p - eye).normalize_or_zero();
            let mut y = [0f64; sh::MAX_ORDER * sh::MAX_ORDER];
            sh::eval_basis(order, sh::dir64(w), &mut y);
            for c in 0..3 {
                let s = &source[node * 3 * nc + c * nc..node * 3 * nc + (c + 1) * nc];
                out[c] = s.iter().zip(&y).map(|(a, b)| *a as f64 * b).sum::<f64>().max(0.0) as f32;
            }
        });
    }
}

/// The camera-ray walk of [`ZhouIntegrator`]: grid segments by the model,
/// surfaces lit directly with the shadows of [`ZhouSettings::surface_shadows`].
struct ZhouWalk<'a> {
    integrator: &'a ZhouIntegrator,
}

impl CameraRayVisitor for ZhouWalk<'_> {
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
        let z = self.integrator;
        match m {
            Medium::Grid(g) => match &z.models[id.0 as usize] {
                Some(model) => z.grid_segment(g, id, model, ray, t_end, sampler),
                None => z.analytic.segment(scene, id, ray, t_end, sampler),
            },
            Medium::Homogeneous(_) => z.analytic.segment(scene, id, ray, t_end, sampler),
        }
    }

    #[inline]
    fn opaque_surface(
        &mut self,
        scene: &Scene,
        hit: &crate::world::Hit,
        wo: Vec3,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> Rgb {
        let bsdf = &scene.surface_bsdf(hit);
        let shadows = &self.integrator.shadows;
        shadowed_surface_radiance(
            self.integrator.settings.surface_shadows,
            scene,
            &hit.surface,
            wo,
            bsdf,
            medium,
            sampler,
            |light, id, ray, t| {
                let Medium::Grid(g) = scene.medium(id) else { return None };
                shadows.transmittance(g, id.0 as usize, light, ray, t)
            },
        )
    }
}

impl Integrator for ZhouIntegrator {
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb {
        walk_camera_ray(scene, ray, medium, sampler, &mut ZhouWalk { integrator: self })
    }
}
