//! Tests of direct lighting against closed forms: a Lambertian surface
//! under a point and a directional light, in-scattering in a homogeneous
//! medium with exact transmittance, and shadows. Point and directional
//! lights are sampled deterministically (one direction, pdf 1), so every
//! expected value is exact up to f32 rounding.

use super::*;
use crate::scene::{build_scene, parse_scene_str};

/// A floor (a diffuse rectangle at y = 0, normal +y) under a point light of
/// 8 W/sr at height 2 and a directional light of 3 W/m^2 at 60 degrees from
/// the vertical (toward -z); a fog box (sigma_t 0.5, isotropic, y from 0.5
/// to 4, |x|, |z| <= 3) holds the point light; a small opaque ceiling
/// (|x|, |z| <= 1 at y = 5) hides a point light above it.
const SCENE: &str = r#"{"version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "width": 4, "height": 4},
  "media": {"fog": {"sigma_a": 0.2, "sigma_s": 0.3, "phase": {"type": "isotropic"}}},
  "shapes": [
    {"type": "rectangle", "to_world": {"scale": 10, "rotate_x": -90}, "bsdf": {"type": "diffuse", "reflectance": 0.5}},
    {"type": "box", "min": [-3, 0.5, -3], "max": [3, 4, 3], "interior": "fog"},
    {"type": "rectangle", "to_world": {"scale": 1, "rotate_x": 90, "translate": [0, 5, 0]},
     "bsdf": {"type": "diffuse", "reflectance": 0.5}}
  ],
  "lights": [
    {"type": "point", "position": [0, 2, 0], "intensity": 8},
    {"type": "directional", "direction": [0, -0.5, -0.8660254], "irradiance": 3},
    {"type": "point", "position": [0, 7, 0], "intensity": 100}
  ]}"#;

fn scene() -> Scene {
    let desc = parse_scene_str(SCENE, "direct.json").unwrap();
    build_scene(&desc, "direct.json", ".".as_ref()).unwrap().scene
}

/// Relative tolerance of a shadow ray leaving a surface at `p` at cosine
/// `cos` to the normal through fog of `sigma_t` 0.5: the ray starts
/// `surface_epsilon(p)` off the surface and runs the full distance to the
/// light, so its fog path may be longer by up to `epsilon / cos` (a
/// transmittance factor `exp(-0.5 epsilon / cos)`), plus f32 rounding.
fn offset_tolerance(p: Vec3, cos: f32) -> f32 {
    1e-5 + 0.5 * crate::world::surface_epsilon(p) / cos
}

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-30)
}

#[test]
fn lambertian_floor_sees_both_lights_through_fog_and_not_the_hidden_one() {
    let scene = scene();
    let bsdf = crate::bsdf::Bsdf::Diffuse { reflectance: Rgb::splat(0.5) };
    let mut sampler = PixelSampler::new(1, 0, 0, 0);
    // At the origin, seen from above: the point light 2 above (the last 1.5
    // through fog, from y = 0.5), the sun at cos 0.5 (its ray through fog
    // from y = 0.5, t = 1, to the face z = 3, t = 3 / cos 30), the light
    // above the ceiling shadowed.
    let p = Vec3::ZERO;
    let surface = SurfaceHit { t: 0.0, p, n: Vec3::Y, ns: Vec3::Y, backside_ns: false };
    let l =
        direct_surface_radiance(&scene, &surface, Vec3::Y, &bsdf, None, TransmittanceMethod::Analytic, &mut sampler);
    let point = 0.5 / std::f32::consts::PI * 8.0 / 4.0 * (-0.5f32 * 1.5).exp();
    let sun = 0.5 / std::f32::consts::PI * 3.0 * 0.5 * (-0.5f32 * (3.0 / 0.8660254 - 1.0)).exp();
    for c in 0..3 {
        assert!(close(l[c], point + sun, offset_tolerance(p, 0.5)), "channel {c}: {} vs {}", l[c], point + sun);
    }
}

#[test]
fn in_scattering_is_phase_times_attenuated_intensity_over_distance_squared() {
    let scene = scene();
    let fog = scene.medium_names.iter().position(|n| n == "fog").map(|i| MediumId(i as u32));
    let phase = PhaseFunction::Isotropic;
    let mut sampler = PixelSampler::new(2, 0, 0, 0);
    // At (1, 2, 0) inside the fog: the point light 1 away through fog, the
    // sun through fog up to the face z = 3 (t = 3 / cos 30), the light
    // above the ceiling shadowed.
    let p = Vec3::new(1.0, 2.0, 0.0);
    let wo = Vec3::Z;
    let l = in_scattered_radiance(&scene, p, wo, &phase, fog, TransmittanceMethod::Analytic, &mut sampler);
    let iso = 0.25 / std::f32::consts::PI;
    let point = iso * 8.0 * (-0.5f32).exp();
    let sun = iso * 3.0 * (-0.5f32 * (3.0 / 0.8660254)).exp();
    for c in 0..3 {
        assert!(close(l[c], point + sun, 1e-5), "channel {c}: {} vs {}", l[c], point + sun);
    }
    // One light alone is its share.
    let only_point =
        light_in_scattered_radiance(&scene, 0, p, wo, &phase, fog, TransmittanceMethod::Analytic, &mut sampler);
    assert!(close(only_point[0], point, 1e-5), "{} vs {point}", only_point[0]);
    let shadowed =
        light_in_scattered_radiance(&scene, 2, p, wo, &phase, fog, TransmittanceMethod::Analytic, &mut sampler);
    assert_eq!(shadowed, Rgb::ZERO);
}

#[test]
fn a_surface_lit_from_behind_receives_nothing() {
    let scene = scene();
    let bsdf = crate::bsdf::Bsdf::Diffuse { reflectance: Rgb::splat(0.5) };
    let mut sampler = PixelSampler::new(3, 0, 0, 0);
    // The ceiling's underside at (0, 5, 0) seen from below faces the point
    // light inside the fog box; the light above the ceiling is behind it,
    // and the sun shines on its top.
    let l = direct_surface_radiance(
        &scene,
        &SurfaceHit { t: 0.0, p: Vec3::new(0.0, 5.0, 0.0), n: -Vec3::Y, ns: -Vec3::Y, backside_ns: false },
        -Vec3::Y,
        &bsdf,
        None,
        TransmittanceMethod::Analytic,
        &mut sampler,
    );
    // The light at y = 2 is 3 away: 1 of vacuum (5 -> 4), 2 of fog (4 -> 2).
    let expected = 0.5 / std::f32::consts::PI * 8.0 / 9.0 * (-0.5f32 * 2.0).exp();
    assert!(close(l[0], expected, offset_tolerance(Vec3::new(0.0, 5.0, 0.0), 1.0)), "{} vs {expected}", l[0]);
}
