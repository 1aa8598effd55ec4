//! Glass and metal surfaces in the integrators: a glass sphere of milk (a
//! scattering, non-absorbing medium inside a dielectric) in a uniform
//! environment is a white furnace (refraction's radiance scaling and total
//! internal reflection must conserve energy exactly); a mirror shows the
//! environment times its Fresnel reflectance; scene files describe both.

mod common;

use common::{scene, Stats};
use niebla::bsdf::{fresnel_complex, Bsdf};
use niebla::color::Rgb;
use niebla::geometry::{Rectangle, Shape, Sphere, Transform};
use niebla::integrator::{Integrator, SingleIntegrator, SingleSampling, VolPathIntegrator};
use niebla::light::{ConstantLight, Light};
use niebla::math::{Ray, Vec3};
use niebla::medium::{HomogeneousMedium, Medium, MediumId};
use niebla::phase::PhaseFunction;
use niebla::sampling::{PixelSampler, SamplerKind};
use niebla::scene::{build_scene, parse_scene_str, SceneObject};
use niebla::tracking::TransmittanceMethod;

fn mean<I: Integrator>(integrator: &I, s: &niebla::scene::Scene, ray: Ray, n: u32) -> [Stats; 3] {
    let mut stats = [Stats::default(); 3];
    for i in 0..n {
        let mut sampler = PixelSampler::for_pixel(SamplerKind::default(), 5, 1, 2, i as u64);
        let l = integrator.radiance(s, ray, None, &mut sampler);
        for c in 0..3 {
            stats[c].add(l[c] as f64);
        }
    }
    stats
}

#[test]
fn glass_of_milk_in_a_uniform_environment_is_a_white_furnace() {
    let milk = Medium::Homogeneous(HomogeneousMedium {
        sigma_a: Rgb::ZERO,
        sigma_s: Rgb::new(4.0, 6.0, 9.0),
        l_ve: Rgb::ZERO,
        phase: PhaseFunction::hg(0.7),
    });
    let glass = SceneObject {
        shape: Shape::Sphere(Sphere::new(Vec3::ZERO, 1.0)),
        bsdf: Bsdf::dielectric(1.5, 1.0),
        interior: Some(MediumId(0)),
        exterior: None,
        bounds_medium: true,
        emitter: None,
        texture: None,
        roughness: None,
        dpdu_frame: false,
    };
    let env = Light::Constant(ConstantLight { radiance: Rgb::splat(0.8) });
    let s = scene(common::camera_along_x(1, 1, 30.0), vec![glass], vec![milk], vec![env], None);
    for target in [Vec3::ZERO, Vec3::new(0.0, 0.7, 0.3)] {
        let stats =
            mean(&VolPathIntegrator::new(100_000), &s, Ray::new(Vec3::new(-4.0, target.y, target.z), Vec3::X), 4_000);
        for (c, st) in stats.iter().enumerate() {
            let z = (st.mean() - 0.8) / (st.standard_error() + 1e-5);
            assert!(z.abs() < 4.0, "channel {c}: {} +- {}", st.mean(), st.standard_error());
        }
    }
}

#[test]
fn mirror_shows_the_environment_times_its_fresnel_reflectance() {
    let (eta, k) = (Rgb::new(0.2, 0.9, 1.4), Rgb::new(3.0, 2.4, 1.8));
    let t = Transform::from_components(Vec3::splat(5.0), Vec3::new(-90.0, 0.0, 0.0), Vec3::ZERO).unwrap();
    let mirror = SceneObject {
        shape: Shape::Rectangle(Rectangle::new(t)),
        bsdf: Bsdf::Conductor { eta, k },
        interior: None,
        exterior: None,
        bounds_medium: false,
        emitter: None,
        texture: None,
        roughness: None,
        dpdu_frame: false,
    };
    let env = Light::Constant(ConstantLight { radiance: Rgb::splat(2.0) });
    let s = scene(common::camera_along_x(1, 1, 30.0), vec![mirror], vec![], vec![env], None);
    let d = Vec3::new(1.0, -1.0, 0.0).normalize();
    let ray = Ray::new(Vec3::new(-1.0, 1.0, 0.0), d);
    let expected = fresnel_complex(d.y.abs(), eta, k) * 2.0;
    let single = SingleIntegrator {
        step: None,
        sampling: SingleSampling::March,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: None,
    };
    for stats in [mean(&VolPathIntegrator::new(8), &s, ray, 16), mean(&single, &s, ray, 16)] {
        for c in 0..3 {
            assert!(
                (stats[c].mean() - expected[c] as f64).abs() < 1e-5,
                "channel {c}: {} vs {}",
                stats[c].mean(),
                expected[c]
            );
        }
    }
}

#[test]
fn scene_files_describe_glass_and_metal_and_reject_bad_values() {
    let text = |bsdf: &str| {
        format!(
            r#"{{"version": 1,
                "camera": {{"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 8, "height": 8}},
                "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "bsdf": {bsdf}}}]}}"#
        )
    };
    let build = |bsdf: &str| {
        let desc = parse_scene_str(&text(bsdf), "s.json").unwrap();
        build_scene(&desc, "s.json", std::path::Path::new(".")).unwrap().scene.objects[0].bsdf
    };
    assert_eq!(build(r#"{"type": "dielectric"}"#), Bsdf::Dielectric { eta: 1.5 });
    assert_eq!(build(r#"{"type": "dielectric", "int_ior": 1.333, "ext_ior": 1.0}"#), Bsdf::Dielectric { eta: 1.333 });
    assert_eq!(build(r#"{"type": "conductor", "material": "Au"}"#), Bsdf::conductor_preset("gold").unwrap());
    assert!(matches!(build(r#"{"type": "conductor", "reflectance": 0.9}"#), Bsdf::Conductor { .. }));
    let errors = [
        (r#"{"type": "dielectric", "int_ior": -1}"#, "shapes[0].bsdf.int_ior"),
        (r#"{"type": "conductor", "material": "unobtainium"}"#, "shapes[0].bsdf.material"),
        (r#"{"type": "conductor", "eta": 1}"#, "shapes[0].bsdf.k"),
        (r#"{"type": "conductor"}"#, "shapes[0].bsdf"),
        (r#"{"type": "conductor", "reflectance": 1.0}"#, "shapes[0].bsdf.reflectance"),
        (r#"{"type": "dielectric", "ior": 1.5}"#, "shapes[0].bsdf.ior"),
    ];
    for (bsdf, path) in errors {
        let err = parse_scene_str(&text(bsdf), "s.json").unwrap_err();
        assert_eq!(err.path, path, "{bsdf}: {err}");
    }
}
