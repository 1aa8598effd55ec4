//! Photon tracing (Jensen and Christensen 1998): photons leave the lights
//! (chosen in proportion to their power, then [`Light::sample_le`]) or
//! emissive media (see [`Emitters`]) and
//! travel through media and surfaces with the free-flight and event code of
//! `volpath` (null-scattering delta tracking over majorant segments with the
//! hero channel, spectral MIS on the photon's power), scattering by the phase
//! function in media and by the BSDF in [`TransportMode::Importance`] at
//! surfaces.
//!
//! # Storage rule
//! - Volume photons are stored at *real scattering* events (after the event
//!   choice picked scattering, before the phase function is sampled): their
//!   power density is `sigma_s * integral L dw`, so the in-scattering
//!   estimate `sum p Phi / V` needs no albedo factor (the stored flux
//!   already went through the choice of scattering over absorption).
//! - Surface photons are stored on arrival at diffuse surfaces, before the
//!   BSDF is sampled (density: incident flux per area).
//! - *Direct* photons are not stored: those whose path from the light has
//!   crossed only media (without a real scattering) and index-matched
//!   boundaries. That light is what shadow rays from the camera side compute
//!   (single scattering in media, direct lighting at surfaces), so storing it
//!   would count it twice (Jensen and Christensen 1998 leave direct light to
//!   ray tracing the same way). Photons that passed a
//!   specular surface (a volume caustic behind glass) are stored, and so
//!   are all events of photons emitted by media.
//!   [`TraceSettings::store_direct`] stores them too (for tests).
//!
//! # Determinism
//! Photon `i` of a pass draws its numbers from
//! `PixelSampler::from_key(stream ^ i)`; photons are traced in chunks on
//! rayon and the chunks' photons are concatenated in chunk order, so the
//! maps depend only on the scene, the seed, the pass and the photon count,
//! never on the thread count.

use crate::bsdf::TransportMode;
use crate::color::Rgb;
use crate::light::Light;
use crate::math::{Ray, Vec3};
use crate::sampling::{hash_u64, PixelSampler};
use crate::tracking::{medium_range, pass_through_weight, sample_t_maj, CollisionEvent};
use crate::world::{surface_epsilon, PathRay, Scene};

use super::beams::Beam;
use super::emitters::{Emitters, Source};
use super::stored::Photon;

/// Photons traced per chunk (one rayon task).
const CHUNK: u64 = 2048;

/// What photon tracing needs to know.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceSettings {
    /// Photons emitted (>= 1).
    pub photons: u64,
    /// Largest number of scattering events (medium or surface) on a path.
    pub max_depth: u32,
    /// Store direct photons too (first scattering in a medium, first diffuse
    /// surface reached straight from a light). For tests only: the photon
    /// integrators then count direct light twice.
    pub store_direct: bool,
}

/// Energy bookkeeping of one tracing pass, W per channel (f64 sums).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TraceStats {
    /// Photons emitted (including those whose emission sample was empty).
    pub emitted: u64,
    /// Total flux emitted.
    pub emitted_power: [f64; 3],
    /// Flux of photons that left the scene (no surface hit, no collision).
    pub escaped_power: [f64; 3],
    /// Flux absorbed by area lights' surfaces.
    pub light_absorbed_power: [f64; 3],
    /// Flux of photons cut off by `max_depth`, the boundary-crossing limit or
    /// an unbounded homogeneous medium around a distant light.
    pub lost_power: [f64; 3],
    /// Real scattering events in media, stored or not.
    pub volume_events: u64,
    /// Flux of all real scattering events in media, stored or not.
    pub volume_event_power: [f64; 3],
    /// Flux of all arrivals at diffuse surfaces, stored or not.
    pub surface_event_power: [f64; 3],
}

impl TraceStats {
    fn merge(&mut self, o: &TraceStats) {
        self.emitted += o.emitted;
        self.volume_events += o.volume_events;
        for c in 0..3 {
            self.emitted_power[c] += o.emitted_power[c];
            self.escaped_power[c] += o.escaped_power[c];
            self.light_absorbed_power[c] += o.light_absorbed_power[c];
            self.lost_power[c] += o.lost_power[c];
            self.volume_event_power[c] += o.volume_event_power[c];
            self.surface_event_power[c] += o.surface_event_power[c];
        }
    }
}

#[inline]
fn add(sum: &mut [f64; 3], x: Rgb) {
    for (s, v) in sum.iter_mut().zip(x.0) {
        *s += v as f64;
    }
}

/// Photons of one pass: volume and surface photons (unordered) and the bookkeeping.
#[derive(Clone, Debug, Default)]
pub struct TracedPhotons {
    /// Photons stored at real scattering events in media.
    pub volume: Vec<Photon>,
    /// Photons stored at diffuse surfaces.
    pub surface: Vec<Photon>,
    /// Photon beams (free flights in media; only from [`trace_beams_with`],
    /// which stores no volume photons).
    pub beams: Vec<Beam>,
    /// Energy bookkeeping.
    pub stats: TraceStats,
}

/// The random stream of pass `pass` of a render seeded with `seed`.
#[inline]
pub fn photon_stream(seed: u64, pass: u64) -> u64 {
    hash_u64(hash_u64(seed ^ 0x5048_4f54_4f4e_5321) ^ pass.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// Trace `settings.photons` photons from the lights and emissive media of
/// `scene` with random stream `stream` (see [`photon_stream`]), on the
/// current rayon pool. Builds the [`Emitters`] each call; renders with many
/// passes use [`trace_photons_with`].
pub fn trace_photons(scene: &Scene, settings: &TraceSettings, stream: u64) -> TracedPhotons {
    trace_photons_with(scene, &Emitters::new(scene), settings, stream)
}

/// [`trace_photons`] with the photon sources built beforehand.
pub fn trace_photons_with(scene: &Scene, emitters: &Emitters, settings: &TraceSettings, stream: u64) -> TracedPhotons {
    trace_with(scene, emitters, settings, stream, false)
}

/// Trace photons as [`trace_photons_with`] does (the same paths for the same
/// stream) but store photon beams instead of volume photons: every free
/// flight through a medium that a volume photon's storage rule would count
/// (not direct unless `store_direct`) becomes a [`Beam`] from its start to
/// the collision or surface that ended it, carrying the power at its start.
/// Flights that leave the scene without a collision store nothing. Surface
/// photons are stored as before.
pub fn trace_beams_with(scene: &Scene, emitters: &Emitters, settings: &TraceSettings, stream: u64) -> TracedPhotons {
    trace_with(scene, emitters, settings, stream, true)
}

fn trace_with(scene: &Scene, emitters: &Emitters, settings: &TraceSettings, stream: u64, beams: bool) -> TracedPhotons {
    use rayon::prelude::*;
    if emitters.is_empty() {
        return TracedPhotons::default();
    }
    let n = settings.photons.max(1);
    let tracer = Tracer { scene, settings, emitters, scale: 1.0 / n as f32, beams };
    let chunks: Vec<TracedPhotons> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|chunk| {
            let mut out = TracedPhotons::default();
            for index in chunk * CHUNK..((chunk + 1) * CHUNK).min(n) {
                let mut sampler = PixelSampler::from_key(stream ^ index);
                tracer.trace(index, &mut sampler, &mut out);
            }
            out
        })
        .collect();
    let mut all = TracedPhotons {
        volume: Vec::with_capacity(chunks.iter().map(|c| c.volume.len()).sum()),
        surface: Vec::with_capacity(chunks.iter().map(|c| c.surface.len()).sum()),
        beams: Vec::with_capacity(chunks.iter().map(|c| c.beams.len()).sum()),
        stats: TraceStats::default(),
    };
    for c in chunks {
        all.volume.extend_from_slice(&c.volume);
        all.surface.extend_from_slice(&c.surface);
        all.beams.extend_from_slice(&c.beams);
        all.stats.merge(&c.stats);
    }
    all
}

struct Tracer<'a> {
    scene: &'a Scene,
    settings: &'a TraceSettings,
    emitters: &'a Emitters,
    /// `1 / photons`.
    scale: f32,
    /// Store beams (and no volume photons).
    beams: bool,
}

impl Tracer<'_> {
    /// Trace photon `index` and store what it leaves behind into `out`.
    fn trace(&self, index: u64, sampler: &mut PixelSampler, out: &mut TracedPhotons) {
        let scene = self.scene;
        out.stats.emitted += 1;
        // Emission: a light or an emissive medium by power, then a ray from it.
        let u_choice = sampler.next_1d();
        let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
        let (ray, mut beta, t_min, medium, from_medium) = match self.emitters.choose(u_choice) {
            None => return,
            Some(Source::Light { index, pmf }) => {
                let light = &scene.lights[index];
                let Some(emission) = light.sample_le(u_pos, u_dir, &self.emitters.sphere) else {
                    return;
                };
                let beta = emission.flux() * (self.scale / pmf);
                let ray = emission.ray;
                let on_surface = matches!(light, Light::Area(_));
                let t_min = if on_surface { surface_epsilon(ray.o) } else { 0.0 };
                let medium = scene.medium_at(if on_surface { ray.at(t_min) } else { ray.o });
                if matches!(light, Light::Directional(_) | Light::Constant(_) | Light::Environment(_)) {
                    // Light from infinity through an unbounded homogeneous medium is
                    // extinguished before it arrives (as shadow rays find).
                    if let Some(h) = medium.and_then(|id| scene.medium(id).as_homogeneous()) {
                        if h.sigma_t().max_channel() > 0.0 && beta.is_finite() {
                            add(&mut out.stats.emitted_power, beta);
                            add(&mut out.stats.lost_power, beta);
                            return;
                        }
                    }
                }
                (ray, beta, t_min, medium, false)
            }
            Some(Source::Medium { emitter, pmf }) => {
                let u_z = sampler.next_1d();
                let u_pos = Vec3::new(u_pos.x, u_pos.y, u_z);
                let (p, d, flux) = emitter.sample(scene, sampler.next_1d(), u_pos, u_dir);
                (Ray::new(p, d), flux * (self.scale / pmf), 0.0, Some(emitter.id), true)
            }
        };
        if !beta.is_finite() || beta.is_black() {
            return;
        }
        add(&mut out.stats.emitted_power, beta);

        // The hero channel of free-flight sampling cycles over photons.
        let hero = (index % 3) as usize;
        let mut r_u = Rgb::ONE;
        let mut depth = 0u32;
        // Photons from emissive media have no part that shadow rays compute.
        let mut direct = !from_medium;
        let mut path = PathRay::new(ray, medium, t_min);
        let store_direct = self.settings.store_direct;
        let max_depth = self.settings.max_depth;

        loop {
            let hit = path.intersect(scene);
            let t_end = hit.map_or(f32::INFINITY, |h| h.surface.t);

            // Free flight through the medium up to the surface.
            if let Some(id) = path.medium {
                let ray = path.ray;
                let m = scene.medium(id);
                let mut scattered: Option<(Vec3, Vec3)> = None;
                let mut ended = false;
                let mut cut = false;
                // The flight's power at its start, for its beam.
                let start_power = beta / r_u.average();
                let store_beam = self.beams && (!direct || store_direct) && start_power.is_finite();
                // Where a real collision ended the flight (ray parameter).
                let mut collision_t: Option<f32> = None;
                // Tracking stopped at a null collision (a zero weight): the
                // flight's end is unknown and its beam is not stored.
                let mut stopped_at_null = false;
                let t_maj = sample_t_maj(m, &ray, t_end, hero, sampler, |c, sampler| {
                    match c.event(hero, sampler.next_1d()) {
                        CollisionEvent::Absorb => {
                            // Absorption: the photon ends.
                            collision_t = Some(c.t);
                            ended = true;
                            false
                        }
                        CollisionEvent::Scatter => {
                            // Real scattering: store, then sample the phase function.
                            collision_t = Some(c.t);
                            let w = c.scatter_weight(hero);
                            beta *= w;
                            r_u *= w;
                            let power = beta / r_u.average();
                            if !power.is_finite() || power.is_black() {
                                ended = true;
                                return false;
                            }
                            out.stats.volume_events += 1;
                            add(&mut out.stats.volume_event_power, power);
                            if (!direct || store_direct) && !self.beams {
                                out.volume.push(Photon::in_medium(c.p, -ray.d, power, id.0));
                            }
                            if depth >= max_depth {
                                add(&mut out.stats.lost_power, power);
                                cut = true;
                                return false;
                            }
                            depth += 1;
                            let Some(ps) = m.phase().sample(-ray.d, sampler.next_2d()) else {
                                ended = true;
                                return false;
                            };
                            beta *= ps.value / ps.pdf;
                            direct = false;
                            scattered = Some((c.p, ps.wi));
                            false
                        }
                        CollisionEvent::Null => {
                            // Null collision: continue with the null-scattering weights.
                            let Some(w) = c.null_weights(hero) else {
                                ended = true;
                                stopped_at_null = true;
                                return false;
                            };
                            beta *= w.throughput;
                            r_u *= w.throughput;
                            let go_on = !(beta.is_black() || r_u.is_black());
                            stopped_at_null = !go_on;
                            go_on
                        }
                    }
                });
                if store_beam {
                    let length = match collision_t {
                        Some(t) => Some(t),
                        // No surface ahead: a grid's beam ends where its box does.
                        None if !stopped_at_null && !t_end.is_finite() => {
                            medium_range(m, &ray, 0.0, t_end).map(|(_, b)| b)
                        }
                        None if !stopped_at_null => Some(t_end),
                        None => None,
                    };
                    if let Some(length) = length.filter(|l| l.is_finite() && *l > 0.0) {
                        out.beams.push(Beam {
                            o: ray.o,
                            d: ray.d,
                            length,
                            power: start_power,
                            medium: id.0,
                            hero: hero as u8,
                        });
                    }
                }
                if ended || cut || beta.is_black() || r_u.is_black() || !beta.is_finite() {
                    return;
                }
                if let Some((p, wi)) = scattered {
                    path.scatter_in_medium(p, wi);
                    continue;
                }
                // Passed through: the hero's majorant transmittance was the
                // probability of reaching the surface.
                let Some(w) = pass_through_weight(t_maj, hero) else {
                    return;
                };
                beta *= w;
                r_u *= w;
            }

            let power = beta / r_u.average();
            // Escaped.
            let Some(hit) = hit else {
                add(&mut out.stats.escaped_power, power);
                return;
            };

            // Index-matched boundary: cross it without counting a bounce.
            let object = scene.object(&hit);
            if object.bsdf.is_null() {
                if !path.cross(scene, &hit) {
                    add(&mut out.stats.lost_power, power);
                    return;
                }
                continue;
            }

            // An area light's surface absorbs.
            if object.emitter.is_some() {
                add(&mut out.stats.light_absorbed_power, power);
                return;
            }

            // Diffuse surface: store on arrival.
            let wo = -path.ray.d;
            if !object.bsdf.is_specular() && !object.bsdf.has_rough_transmission() {
                add(&mut out.stats.surface_event_power, power);
                if !direct || store_direct {
                    let n = if hit.surface.n.dot(wo) < 0.0 { -hit.surface.n } else { hit.surface.n };
                    out.surface.push(Photon::on_surface(hit.surface.p, wo, power, n));
                }
            }
            if depth >= max_depth {
                add(&mut out.stats.lost_power, power);
                return;
            }
            depth += 1;

            // Scatter by the BSDF (flux is not scaled by refraction).
            let u_lobe = sampler.next_1d();
            let u_bsdf = sampler.next_2d();
            let u_rr = sampler.next_1d();
            let ns = hit.surface.shading_normal(wo);
            let bsdf = scene.surface_bsdf(&hit);
            let Some(bs) = bsdf.sample_with_mode(ns, wo, u_lobe, u_bsdf, TransportMode::Importance) else {
                return;
            };
            if !(bs.pdf > 0.0) || !scene.path_continues(&hit, ns, bs.wi) {
                return;
            }
            // Importance transport over shading normals: Veach's (1997, eq.
            // 5.17) factor |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|) applied to
            // f |wi.ns| / pdf leaves f |wo.ns| |wi.ng| / (|wo.ng| pdf); 1 for
            // flat surfaces.
            beta *= bs.weight(ns) * shading_adjoint_factor(hit.surface.n, ns, wo, bs.wi);
            direct = false;
            path.leave_surface(scene, &hit, bs.wi, bs.is_transmission);

            // Russian roulette keeps the photon's power: survive with the
            // ratio of new to old power (the albedo for grey surfaces).
            let before = power.max_channel();
            let after = (beta / r_u.average()).max_channel();
            if after < before {
                let q = after / before;
                if !(u_rr < q) {
                    return;
                }
                beta /= q;
            }
        }
    }
}

/// Veach's (1997, eq. 5.17) correction of the adjoint BSDF for shading
/// normals: `|wo.ns| |wi.ng| / (|wo.ng| |wi.ns|)`, exactly 1 where the
/// shading and geometric normals coincide.
#[inline]
fn shading_adjoint_factor(ng: Vec3, ns: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    if ns == ng {
        return 1.0;
    }
    let den = wo.dot(ng).abs() * wi.dot(ns).abs();
    if den > 0.0 {
        wo.dot(ns).abs() * wi.dot(ng).abs() / den
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photon_streams_differ_per_seed_and_pass_and_are_stable() {
        let streams: Vec<u64> = (0..4).flat_map(|seed| (0..4).map(move |pass| photon_stream(seed, pass))).collect();
        for (i, a) in streams.iter().enumerate() {
            for b in &streams[i + 1..] {
                assert_ne!(a, b);
            }
        }
        // A pure function of (seed, pass): maps are reproducible across runs.
        assert_eq!(photon_stream(3, 7), photon_stream(3, 7));
    }

    #[test]
    fn stats_merge_sums_every_field_in_f64() {
        let mut a = TraceStats::default();
        add(&mut a.emitted_power, Rgb::new(1.0, 2.0, 3.0));
        a.emitted = 2;
        a.volume_events = 5;
        let mut b = a;
        add(&mut b.escaped_power, Rgb::new(0.5, 0.25, 0.125));
        add(&mut b.lost_power, Rgb::splat(1e-8));
        a.merge(&b);
        assert_eq!(a.emitted, 4);
        assert_eq!(a.volume_events, 10);
        assert_eq!(a.emitted_power, [2.0, 4.0, 6.0]);
        assert_eq!(a.escaped_power, [0.5, 0.25, 0.125]);
        // f64 sums keep a 1e-8 increment that an f32 sum of order 1 would round away.
        let mut sum = [1.0f64; 3];
        add(&mut sum, Rgb::splat(1e-8));
        assert!(sum[0] > 1.0);
        assert_eq!(a.lost_power[0], 1e-8f32 as f64);
    }
}
