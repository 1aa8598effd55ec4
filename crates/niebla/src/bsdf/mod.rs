//! Surface scattering. A closed set: `Null` marks an index-matched medium
//! boundary that light crosses unchanged; `Diffuse` is an opaque Lambertian
//! reflector; `Dielectric` a smooth refractive interface (glass, water, the
//! surface of a glass of milk); `Conductor` a smooth metal mirror. pbrt-v4
//! chapter 9 is the reference design.
//!
//! # Conventions
//! - `wo` and `wi` are unit vectors pointing *away* from the surface point
//!   (as for phase functions). `wo` is the direction toward the camera (the
//!   path's previous vertex), `wi` the direction toward the light.
//! - `n` is the unit *geometric* normal given by the caller
//!   (`hit.surface.n`, which shapes orient outward). `Diffuse` and
//!   `Conductor` are two-sided: they scatter on whichever side `wo` lies, so
//!   either orientation of `n` gives the same result. `Dielectric` is not:
//!   `n` must point to the *outside*, and `eta = ior_inside / ior_outside`;
//!   `wo` may lie on either side. Do not flip `n` toward `wo` for it.
//! - `f` is in 1/sr and excludes the cosine; the scattering integral is
//!   `L_o(wo) = integral f(wo, wi) L_i(wi) |cos(wi, n)| dwi`.
//!
//! # Delta lobes (pbrt-v4 convention)
//! `Null`, `Dielectric` and `Conductor` are specular: their BSDF is a Dirac
//! delta, so [`Bsdf::eval`] and [`Bsdf::pdf`] return 0 for them (a light
//! sample never hits the delta direction) and only [`Bsdf::sample`] sees
//! them. A specular [`BsdfSample`] has `f = F / |cos(wi, n)|`, with `F` the
//! energy fraction of the chosen lobe (Fresnel `R`, `T / etap^2`, or the
//! conductor's `R`), and `pdf` = the *discrete probability of choosing that
//! lobe* (not a density). Then the same throughput update
//! `beta *= f * |cos(wi, n)| / pdf` ([`BsdfSample::weight`]) is right for
//! every variant: it gives `F / pdf` for delta lobes and `f cos / pdf` for
//! `Diffuse`. A path tracer must skip MIS with light sampling after a
//! specular sample (`is_specular`): `pdf` there is not a solid-angle density.
//!
//! # Radiance transport across a dielectric (the `1 / eta^2` factor)
//! Radiance is not invariant under refraction: crossing into a medium of
//! relative index `etap` (transmitted side over incident side) compresses the
//! solid angle by `etap^2`, so `L_t = T etap^2 L_i` (pbrt-v4 section 9.5.2).
//! niebla traces paths from the camera and carries *radiance* back along
//! them, which is pbrt-v4's `TransportMode::Radiance`: the BSDF used is the
//! adjoint of the light's, and on refraction `f` carries a factor
//! `1 / etap^2`, where `etap` = [`BsdfSample::eta`] = index on the side of
//! `wi` over index on the side of `wo`. Example: a camera ray entering glass
//! from air (`etap = 1.5`) is weighted by `T / 2.25`, since radiance inside
//! glass is 2.25 times what it becomes in air. Paths traced from lights
//! (photons) carry importance-like flux instead, which does not scale:
//! [`Bsdf::sample_with_mode`] with [`TransportMode::Importance`] omits the
//! factor. A path that refracts in and out again picks up
//! `1 / etap^2 * etap^2 = 1`. For Russian roulette, pbrt-v4 divides the
//! throughput by the accumulated `product of etap^2` (its `etaScale`).

mod conductor;
mod dielectric;
mod diffuse;
pub mod fresnel;
pub mod microfacet;
mod mitsuba_conductors;
mod plastic;
mod rough_conductor;
mod rough_dielectric;
pub mod rough_plastic;
mod thin_dielectric;
mod two_sided;

pub use conductor::{
    conductor_from_artist, conductor_from_reflectance, conductor_preset, ConductorPreset, CONDUCTOR_PRESETS,
};
pub use fresnel::{fresnel_complex, fresnel_dielectric, reflect, refract};
pub use microfacet::{Microfacet, MicrofacetKind};
pub use mitsuba_conductors::MITSUBA_CONDUCTORS;
pub use plastic::{fresnel_diffuse_reflectance, Plastic};
pub use rough_conductor::RoughConductor;
pub use rough_dielectric::RoughDielectric;
pub use rough_plastic::RoughPlastic;
pub use thin_dielectric::ThinDielectric;
pub use two_sided::{Reflector, TwoSided};

use crate::color::Rgb;
use crate::math::{Frame, Vec2, Vec3};

/// Surface scattering model of a shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Index-matched boundary: no reflection, rays pass (the default for media containers).
    Null,
    /// Opaque, two-sided Lambertian surface with hemispherical `reflectance` in [0, 1].
    Diffuse {
        /// Albedo of the surface.
        reflectance: Rgb,
    },
    /// Smooth dielectric interface: Fresnel-weighted specular reflection and
    /// refraction, no absorption (absorption belongs to the media on either
    /// side). The normal points outside.
    Dielectric {
        /// Relative index of refraction `ior_inside / ior_outside`, > 0
        /// (1.5 for glass in air, 1.333 for water, 1 for index-matched).
        eta: f32,
    },
    /// Smooth conductor (metal mirror), two-sided, with complex index of
    /// refraction `eta + i k` per channel relative to the outside medium.
    Conductor {
        /// Real part of the index per channel, > 0.
        eta: Rgb,
        /// Extinction coefficient per channel, >= 0 (large `k`: a perfect mirror).
        k: Rgb,
    },
    /// Rough conductor (Mitsuba's `roughconductor`), one-sided: black seen
    /// from behind `n`.
    RoughConductor(RoughConductor),
    /// Rough dielectric interface (Mitsuba's `roughdielectric`): microfacet
    /// reflection and refraction, a medium boundary. The normal points outside.
    RoughDielectric(RoughDielectric),
    /// Thin glass sheet (Mitsuba's `thindielectric`): delta reflection and
    /// straight pass-through; rays that pass change medium.
    ThinDielectric(ThinDielectric),
    /// Smooth coated diffuse surface (Mitsuba's `plastic`), one-sided.
    Plastic(Plastic),
    /// Rough coated diffuse surface (Mitsuba's `roughplastic`), one-sided.
    RoughPlastic(RoughPlastic),
    /// Mitsuba's `twosided`: a reflecting model on each side of `n`.
    TwoSided(TwoSided),
}

/// Which quantity a path carries, for the non-symmetric refraction factor
/// (pbrt-v4 `TransportMode`): see the module documentation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TransportMode {
    /// Paths from the camera carrying radiance (path tracers): refraction
    /// scales `f` by `1 / etap^2`.
    #[default]
    Radiance,
    /// Paths from lights carrying flux (photon tracing): no scaling.
    Importance,
}

/// A sampled incident direction with its BSDF value and probability.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled unit direction toward the light, pointing away from the surface.
    pub wi: Vec3,
    /// BSDF value `f(wo, wi)` in 1/sr. For a specular (delta) sample: the
    /// chosen lobe's energy fraction over `|cos(wi, n)|`, including the
    /// `1 / etap^2` radiance factor on refraction.
    pub f: Rgb,
    /// Solid-angle density of `wi` (1/sr) for non-specular samples; for
    /// specular samples, the discrete probability of the chosen lobe.
    pub pdf: f32,
    /// True when `wi` came from a delta lobe (`pdf` is then a probability).
    pub is_specular: bool,
    /// True when `wi` lies on the other side of the surface from `wo`: the
    /// path enters the medium on that side.
    pub is_transmission: bool,
    /// Relative index across this scattering event: index on the side of `wi`
    /// over index on the side of `wo` (pbrt-v4 `etap`); 1 for reflection and
    /// index-matched crossings.
    pub eta: f32,
}

impl BsdfSample {
    /// Throughput factor `f |cos(wi, n)| / pdf` of this sample, the same
    /// update for every variant (`n` is the normal passed to `sample`).
    ///
    /// ```
    /// use niebla::bsdf::Bsdf;
    /// use niebla::math::{Vec2, Vec3};
    /// let mirror = Bsdf::Conductor { eta: niebla::color::Rgb::ONE, k: niebla::color::Rgb::splat(1e4) };
    /// let s = mirror.sample(Vec3::Z, Vec3::new(0.6, 0.0, 0.8), 0.5, Vec2::new(0.3, 0.7)).unwrap();
    /// assert!((s.weight(Vec3::Z).g() - 1.0).abs() < 1e-5);
    /// ```
    #[inline]
    pub fn weight(&self, n: Vec3) -> Rgb {
        self.f * (self.wi.dot(n).abs() / self.pdf)
    }
}

impl Bsdf {
    /// A dielectric interface between an inside of index `ior_inside` and an
    /// outside of index `ior_outside` (both > 0).
    ///
    /// ```
    /// use niebla::bsdf::Bsdf;
    /// assert_eq!(Bsdf::dielectric(1.5, 1.0), Bsdf::Dielectric { eta: 1.5 });
    /// ```
    pub fn dielectric(ior_inside: f32, ior_outside: f32) -> Bsdf {
        debug_assert!(ior_inside > 0.0 && ior_outside > 0.0);
        Bsdf::Dielectric { eta: ior_inside / ior_outside }
    }

    /// A conductor from a named preset (`"gold"`, `"Au"`, `"silver"`,
    /// `"aluminium"`, `"copper"`; see [`CONDUCTOR_PRESETS`]), in vacuum or air.
    ///
    /// ```
    /// use niebla::bsdf::Bsdf;
    /// assert!(matches!(Bsdf::conductor_preset("gold"), Some(Bsdf::Conductor { .. })));
    /// ```
    pub fn conductor_preset(name: &str) -> Option<Bsdf> {
        conductor_preset(name).map(|p| Bsdf::Conductor { eta: p.eta, k: p.k })
    }

    /// A conductor whose normal-incidence reflectance is `reflectance` (pbrt-v4's
    /// mapping: `eta = 1`, `k = 2 sqrt(r) / sqrt(1 - r)`).
    pub fn conductor_from_reflectance(reflectance: Rgb) -> Bsdf {
        let (eta, k) = conductor_from_reflectance(reflectance);
        Bsdf::Conductor { eta, k }
    }

    /// A conductor from reflectance and edge tint (Gulbrandsen 2014).
    pub fn conductor_from_artist(reflectance: Rgb, edge_tint: Rgb) -> Bsdf {
        let (eta, k) = conductor_from_artist(reflectance, edge_tint);
        Bsdf::Conductor { eta, k }
    }

    /// BSDF value f(wo, wi) (1/sr) for unit directions; zero for delta lobes
    /// (`Null`, `Dielectric`, `Conductor`). `Diffuse` is zero when `wi` and
    /// `wo` lie on different sides of `n`.
    #[inline]
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Rgb {
        match *self {
            Bsdf::Diffuse { reflectance } => diffuse::diffuse_eval(reflectance, n, wo, wi),
            Bsdf::Null | Bsdf::Dielectric { .. } | Bsdf::Conductor { .. } | Bsdf::ThinDielectric(_) => Rgb::ZERO,
            Bsdf::RoughConductor(b) => {
                let (wo, wi) = to_local_in(self.frame(n), wo, wi);
                b.eval_local(wo, wi)
            }
            Bsdf::RoughDielectric(b) => {
                let (wo, wi) = to_local_in(self.frame(n), wo, wi);
                b.eval_local(wo, wi)
            }
            Bsdf::Plastic(b) => {
                let (wo, wi) = to_local(n, wo, wi);
                b.eval_local(wo, wi)
            }
            Bsdf::RoughPlastic(b) => {
                let (wo, wi) = to_local(n, wo, wi);
                b.eval_local(wo, wi)
            }
            Bsdf::TwoSided(b) => {
                let (wo, wi) = to_local_in(self.frame(n), wo, wi);
                b.eval_local(wo, wi)
            }
        }
    }

    /// Solid-angle density (1/sr) with which [`Bsdf::sample`] returns `wi`;
    /// zero for delta lobes.
    #[inline]
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Bsdf::Diffuse { .. } => diffuse::diffuse_pdf(n, wo, wi),
            Bsdf::Null | Bsdf::Dielectric { .. } | Bsdf::Conductor { .. } | Bsdf::ThinDielectric(_) => 0.0,
            Bsdf::RoughConductor(b) => {
                let (wo, wi) = to_local_in(self.frame(n), wo, wi);
                b.pdf_local(wo, wi)
            }
            Bsdf::RoughDielectric(b) => {
                let (wo, wi) = to_local_in(self.frame(n), wo, wi);
                b.pdf_local(wo, wi)
            }
            Bsdf::Plastic(b) => {
                let (wo, wi) = to_local(n, wo, wi);
                b.pdf_local(wo, wi)
            }
            Bsdf::RoughPlastic(b) => {
                let (wo, wi) = to_local(n, wo, wi);
                b.pdf_local(wo, wi)
            }
            Bsdf::TwoSided(b) => {
                let (wo, wi) = to_local_in(self.frame(n), wo, wi);
                b.pdf_local(wo, wi)
            }
        }
    }

    /// Sample `wi` for radiance transport (camera paths); see
    /// [`Bsdf::sample_with_mode`].
    ///
    /// ```
    /// use niebla::bsdf::Bsdf;
    /// use niebla::math::{Vec2, Vec3};
    /// let glass = Bsdf::Dielectric { eta: 1.5 };
    /// // u_lobe above R = 0.04: the camera ray refracts into the glass.
    /// let s = glass.sample(Vec3::Z, Vec3::Z, 0.5, Vec2::ZERO).unwrap();
    /// assert!(s.is_transmission && s.is_specular && s.eta == 1.5);
    /// assert!((s.weight(Vec3::Z).r() - 1.0 / 2.25).abs() < 1e-6);
    /// ```
    #[inline]
    pub fn sample(&self, n: Vec3, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        self.sample_with_mode(n, wo, u_lobe, u, TransportMode::Radiance)
    }

    /// Sample `wi` given `wo`, with `u_lobe` in [0, 1) choosing among lobes
    /// (reflection or refraction) and `u` in [0, 1)^2 sampling within a lobe.
    /// `Diffuse` samples cosine-weighted on the side of `wo`; `Null` and an
    /// index-matched dielectric pass straight through (`wi = -wo`, weight 1).
    /// `None` when `wo` is grazing (`n . wo = 0`) or the sample is degenerate.
    #[inline]
    pub fn sample_with_mode(&self, n: Vec3, wo: Vec3, u_lobe: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        match *self {
            Bsdf::Null => {
                let cos_o = n.dot(wo);
                (cos_o != 0.0).then(|| dielectric::pass_through(wo, cos_o))
            }
            Bsdf::Diffuse { reflectance } => diffuse::sample_diffuse(reflectance, n, wo, u),
            Bsdf::Dielectric { eta } => dielectric::sample_dielectric(eta, n, wo, u_lobe, mode),
            Bsdf::Conductor { eta, k } => conductor::sample_conductor(eta, k, n, wo),
            Bsdf::RoughConductor(b) => {
                let frame = self.frame(n);
                let (wi, f, pdf) = b.sample_local(frame.to_local(wo), u)?;
                Some(BsdfSample {
                    wi: frame.to_world(wi),
                    f,
                    pdf,
                    is_specular: false,
                    is_transmission: false,
                    eta: 1.0,
                })
            }
            Bsdf::RoughDielectric(b) => {
                let frame = self.frame(n);
                let s = b.sample_local(frame.to_local(wo), u_lobe, u, mode)?;
                Some(BsdfSample {
                    wi: frame.to_world(s.wi),
                    f: s.f,
                    pdf: s.pdf,
                    is_specular: false,
                    is_transmission: s.transmitted,
                    eta: s.etap,
                })
            }
            Bsdf::ThinDielectric(b) => {
                let frame = Frame::from_z(n);
                let (wi, weight, pdf, transmitted) = b.sample_local(frame.to_local(wo), u_lobe)?;
                let wi = if transmitted { -wo } else { frame.to_world(wi) };
                let cos_i = n.dot(wi).abs();
                if cos_i == 0.0 || !(pdf > 0.0) {
                    return None;
                }
                let f = weight * (pdf / cos_i);
                Some(BsdfSample { wi, f, pdf, is_specular: true, is_transmission: transmitted, eta: 1.0 })
            }
            Bsdf::Plastic(b) => {
                let frame = Frame::from_z(n);
                let s = b.sample_local(frame.to_local(wo), u_lobe, u)?;
                Some(BsdfSample {
                    wi: frame.to_world(s.wi),
                    f: s.f,
                    pdf: s.pdf,
                    is_specular: s.specular,
                    is_transmission: false,
                    eta: 1.0,
                })
            }
            Bsdf::RoughPlastic(b) => {
                let frame = Frame::from_z(n);
                let s = b.sample_local(frame.to_local(wo), u_lobe, u)?;
                Some(BsdfSample {
                    wi: frame.to_world(s.wi),
                    f: s.f,
                    pdf: s.pdf,
                    is_specular: false,
                    is_transmission: false,
                    eta: 1.0,
                })
            }
            Bsdf::TwoSided(b) => {
                let frame = self.frame(n);
                let s = b.sample_local(frame.to_local(wo), u_lobe, u)?;
                Some(BsdfSample {
                    wi: frame.to_world(s.wi),
                    f: s.f,
                    pdf: s.pdf,
                    is_specular: s.specular,
                    is_transmission: false,
                    eta: 1.0,
                })
            }
        }
    }

    /// True for delta (perfectly specular) models, for which `eval` and `pdf`
    /// are zero and light sampling cannot contribute.
    #[inline]
    pub fn is_specular(&self) -> bool {
        match self {
            Bsdf::Null | Bsdf::Dielectric { .. } | Bsdf::Conductor { .. } | Bsdf::ThinDielectric(_) => true,
            Bsdf::Diffuse { .. }
            | Bsdf::RoughConductor(_)
            | Bsdf::RoughDielectric(_)
            | Bsdf::Plastic(_)
            | Bsdf::RoughPlastic(_) => false,
            Bsdf::TwoSided(b) => b.front.is_specular() && b.back.is_specular(),
        }
    }

    /// True for models with a non-delta transmission lobe (`roughdielectric`):
    /// their `eval` and `pdf` are non-zero for `wi` on the other side of the
    /// surface from `wo`.
    #[inline]
    pub fn has_rough_transmission(&self) -> bool {
        matches!(self, Bsdf::RoughDielectric(_))
    }

    /// The model with its textured color set to `color` (clamped to
    /// [0, 1]): a diffuse `reflectance`, a (rough) plastic's `diffuse_reflectance`,
    /// a rough conductor's `specular_reflectance`, or those of the sides of
    /// a `twosided` that [`TwoSided::textured`] marks. Other models are
    /// returned unchanged.
    #[inline]
    pub fn with_texture(self, color: Rgb) -> Bsdf {
        let color = color.map(|c| c.clamp(0.0, 1.0));
        match self {
            Bsdf::Diffuse { .. } => Bsdf::Diffuse { reflectance: color },
            Bsdf::RoughConductor(b) => Bsdf::RoughConductor(RoughConductor { specular_reflectance: color, ..b }),
            Bsdf::Plastic(b) => Bsdf::Plastic(Plastic { diffuse_reflectance: color, ..b }),
            Bsdf::RoughPlastic(b) => Bsdf::RoughPlastic(RoughPlastic { diffuse_reflectance: color, ..b }),
            Bsdf::TwoSided(mut b) => {
                if b.textured & 1 != 0 {
                    b.front = b.front.with_texture(color);
                }
                if b.textured & 2 != 0 {
                    b.back = b.back.with_texture(color);
                }
                Bsdf::TwoSided(b)
            }
            other => other,
        }
    }

    /// The model with its isotropic roughness set to `alpha` (raised to
    /// [`MIN_ALPHA`](microfacet::MIN_ALPHA), as Mitsuba 3 does): a rough
    /// conductor's or rough dielectric's distribution, kind unchanged. Other
    /// models are returned unchanged (the scene builder gives a textured
    /// roughness to no others).
    #[inline]
    pub fn with_alpha(self, alpha: f32) -> Bsdf {
        self.with_alpha_uv(alpha, alpha)
    }

    /// The model with its roughness set to `alpha_u` along the tangent and
    /// `alpha_v` along the bitangent (each raised to
    /// [`MIN_ALPHA`](microfacet::MIN_ALPHA)), as [`Bsdf::with_alpha`].
    #[inline]
    pub fn with_alpha_uv(self, alpha_u: f32, alpha_v: f32) -> Bsdf {
        match self {
            Bsdf::RoughConductor(b) => Bsdf::RoughConductor(RoughConductor {
                microfacet: Microfacet::new(b.microfacet.kind, alpha_u, alpha_v),
                ..b
            }),
            Bsdf::RoughDielectric(b) => Bsdf::RoughDielectric(RoughDielectric {
                microfacet: Microfacet::new(b.microfacet.kind, alpha_u, alpha_v),
                ..b
            }),
            other => other,
        }
    }

    /// True for the models Mitsuba 3 makes one-sided (diffuse, conductors,
    /// plastics: zero where `wo` lies behind the normal they are given);
    /// false for dielectrics, thin panes, `null` and `twosided`.
    #[inline]
    pub fn is_one_sided(&self) -> bool {
        matches!(
            self,
            Bsdf::Diffuse { .. }
                | Bsdf::Conductor { .. }
                | Bsdf::RoughConductor(_)
                | Bsdf::Plastic(_)
                | Bsdf::RoughPlastic(_)
        )
    }

    /// True when a microfacet distribution of the model (a rough
    /// conductor's, a rough dielectric's, a rough-conductor side of a
    /// `twosided`) has `alpha_u != alpha_v`: only then does the tangent
    /// frame's orientation change the result.
    #[inline]
    pub fn is_anisotropic(&self) -> bool {
        match self {
            Bsdf::RoughConductor(b) => b.microfacet.is_anisotropic(),
            Bsdf::RoughDielectric(b) => b.microfacet.is_anisotropic(),
            Bsdf::TwoSided(b) => [b.front, b.back].iter().any(|s| s.microfacet().is_some_and(|m| m.is_anisotropic())),
            _ => false,
        }
    }

    /// The model with the world-space tangent `t` (a shape's `dp/du` at
    /// one hit; any length) set as the x axis (`alpha_u`) of its
    /// microfacet distributions, made orthogonal to the normal each
    /// evaluation uses (see [`RoughConductor::tangent`]). Models without one
    /// are returned unchanged.
    #[inline]
    pub fn with_tangent(self, t: Vec3) -> Bsdf {
        match self {
            Bsdf::RoughConductor(b) => Bsdf::RoughConductor(RoughConductor { tangent: t, ..b }),
            Bsdf::RoughDielectric(b) => Bsdf::RoughDielectric(RoughDielectric { tangent: t, ..b }),
            Bsdf::TwoSided(b) => {
                Bsdf::TwoSided(TwoSided { front: b.front.with_tangent(t), back: b.back.with_tangent(t), ..b })
            }
            other => other,
        }
    }

    /// The shading frame about unit normal `n` (`+z = n`): x along the
    /// microfacet tangent where one is set ([`Bsdf::with_tangent`]), else
    /// [`Frame::from_z`]'s.
    #[inline]
    pub fn frame(&self, n: Vec3) -> Frame {
        let tangent = match self {
            Bsdf::RoughConductor(b) => b.tangent,
            Bsdf::RoughDielectric(b) => b.tangent,
            Bsdf::TwoSided(b) => match (b.front, b.back) {
                (Reflector::RoughConductor(r), _) if r.tangent != Vec3::ZERO => r.tangent,
                (_, Reflector::RoughConductor(r)) => r.tangent,
                _ => Vec3::ZERO,
            },
            _ => Vec3::ZERO,
        };
        if tangent == Vec3::ZERO {
            Frame::from_z(n)
        } else {
            Frame::from_normal_tangent(n, tangent)
        }
    }

    /// The microfacet distribution of a rough conductor or rough
    /// dielectric; `None` for other models.
    #[inline]
    pub fn microfacet(&self) -> Option<Microfacet> {
        match self {
            Bsdf::RoughConductor(b) => Some(b.microfacet),
            Bsdf::RoughDielectric(b) => Some(b.microfacet),
            _ => None,
        }
    }

    /// True for index-matched boundaries that rays cross.
    #[inline]
    pub fn is_null(&self) -> bool {
        matches!(self, Bsdf::Null)
    }

    /// True for surfaces that shadow rays cross instead of being blocked:
    /// index-matched boundaries (`Null`) and thin dielectric panes, whose
    /// straight-through transmission is a null lobe (as in Mitsuba 3), so
    /// light reaches through them weighted by their transmittance.
    #[inline]
    pub fn passes_shadow_rays(&self) -> bool {
        matches!(self, Bsdf::Null | Bsdf::ThinDielectric(_))
    }
}

/// `wo` and `wi` in the local frame of `n` ([`Frame::from_z`]: `+z = n`).
#[inline]
fn to_local(n: Vec3, wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    to_local_in(Frame::from_z(n), wo, wi)
}

/// `wo` and `wi` in `frame`.
#[inline]
fn to_local_in(frame: Frame, wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    (frame.to_local(wo), frame.to_local(wi))
}

/// A sample in a local frame, shared by the reflecting models.
pub(crate) struct LocalSample {
    pub wi: Vec3,
    pub f: Rgb,
    pub pdf: f32,
    pub specular: bool,
}
