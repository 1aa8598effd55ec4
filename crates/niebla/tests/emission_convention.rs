//! Emission follows the lecture's convention: `L_ve` is radiance emitted per
//! unit length (pbrt-v2's convention, not pbrt-v4's `sigma_a L_e`). A deep purely absorbing emitting medium
//! looks like `L_ve / sigma_a`; a slab of thickness d like
//! `L_ve (1 - exp(-sigma_a d)) / sigma_a`.

mod common;

use common::{homogeneous, scene};
use niebla::bsdf::Bsdf;
use niebla::camera::PerspectiveCamera;
use niebla::color::Rgb;
use niebla::geometry::{AxisAlignedBox, Shape};
use niebla::integrator::{IntegratorSettings, SingleSampling};
use niebla::math::Vec3;
use niebla::medium::MediumId;
use niebla::phase::PhaseFunction;
use niebla::render::{render, RenderOptions};
use niebla::scene::SceneObject;
use niebla::tracking::{MarchStep, TransmittanceMethod};

fn settings() -> Vec<IntegratorSettings> {
    let mut v = Vec::new();
    for transmittance in [TransmittanceMethod::Analytic, TransmittanceMethod::RayMarch(MarchStep::Length(0.01))] {
        v.push(IntegratorSettings::Emission { step: Some(MarchStep::Length(0.01)), transmittance });
        for sampling in [SingleSampling::March, SingleSampling::Mis] {
            v.push(IntegratorSettings::Single {
                step: Some(MarchStep::Length(0.01)),
                sampling,
                transmittance,
                volume_lights: false,
            });
        }
    }
    v
}

/// Relative tolerance: closed forms are exact up to f32 rounding (and the
/// 1e-6 transmittance cut of unbounded segments); a ray march of the emission
/// integral with one jittered offset u is a shifted rectangle rule whose ratio
/// to the exact integral lies in [x e^-x / (1 - e^-x), x / (1 - e^-x)] with
/// x = sigma_t dt, i.e. within about sigma_t dt / 2.
fn tolerance(settings: &IntegratorSettings, sigma_t: f32) -> f32 {
    let marched = matches!(
        settings,
        IntegratorSettings::Emission { transmittance: TransmittanceMethod::RayMarch(_), .. }
            | IntegratorSettings::Single { transmittance: TransmittanceMethod::RayMarch(_), .. }
    );
    if marched {
        0.5 * sigma_t * 0.01 + 1e-5
    } else {
        2e-5
    }
}

fn options() -> RenderOptions {
    RenderOptions { spp: 4, seed: 3, first_sample: 0, threads: Some(1), sampler: Default::default() }
}

#[test]
fn deep_absorbing_emitting_medium_shows_l_ve_over_sigma_a() {
    let l_ve = Rgb::new(0.3, 0.6, 1.2);
    let sigma_a = 1.5;
    let medium = homogeneous(sigma_a, 0.0, l_ve, PhaseFunction::isotropic());
    let s = scene(common::camera_along_x(4, 4, 20.0), vec![], vec![medium], vec![], Some(MediumId(0)));
    for st in settings() {
        let image = render(&s, &st, &options(), &|_, _| {}, None).unwrap();
        for p in &image.pixels {
            for c in 0..3 {
                let expected = l_ve[c] / sigma_a;
                assert!(
                    (p[c] - expected).abs() <= tolerance(&st, sigma_a) * expected,
                    "{st:?}: {} vs {expected}",
                    p[c]
                );
            }
        }
    }
}

#[test]
fn emitting_slab_shows_closed_form_radiance() {
    let l_ve = Rgb::new(2.0, 1.0, 0.5);
    let (sigma_a, d) = (0.8f32, 1.7f32);
    let medium = homogeneous(sigma_a, 0.0, l_ve, PhaseFunction::isotropic());
    // A slab [2, 2 + d] along x, huge in y and z, seen by a narrow camera along +x.
    let slab = SceneObject {
        shape: Shape::Box(AxisAlignedBox {
            min: Vec3::new(2.0, -100.0, -100.0),
            max: Vec3::new(2.0 + d, 100.0, 100.0),
        }),
        bsdf: Bsdf::Null,
        interior: Some(MediumId(0)),
        exterior: None,
        bounds_medium: true,
        emitter: None,
        texture: None,
        roughness: None,
        dpdu_frame: false,
    };
    let camera = PerspectiveCamera::look_at(Vec3::ZERO, Vec3::X, Vec3::Y, 0.01, 4, 4).unwrap();
    let s = scene(camera, vec![slab], vec![medium], vec![], None);
    assert_eq!(s.camera_medium, None);
    for st in settings() {
        let image = render(&s, &st, &options(), &|_, _| {}, None).unwrap();
        for p in &image.pixels {
            for c in 0..3 {
                let expected = l_ve[c] * (1.0 - (-sigma_a * d).exp()) / sigma_a;
                assert!(
                    (p[c] - expected).abs() <= tolerance(&st, sigma_a) * expected,
                    "{st:?}: {} vs {expected}",
                    p[c]
                );
            }
        }
    }
}
