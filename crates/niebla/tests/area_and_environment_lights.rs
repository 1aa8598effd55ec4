//! Area lights and environment maps in the integrators, against closed forms:
//! a Lambertian floor under a sphere light shows `rho L (R/d)^2`; a medium in
//! a uniform environment map is a white furnace; an environment seen directly
//! is its own radiance. Both `single` and `volpath` (whose BSDF-sampled hits
//! on the light are MIS-weighted against light sampling) must agree.

mod common;

use std::sync::Arc;

use common::{scene, Stats};
use niebla::bsdf::Bsdf;
use niebla::camera::PerspectiveCamera;
use niebla::color::Rgb;
use niebla::geometry::{Rectangle, Shape, Sphere, Transform};
use niebla::integrator::{Integrator, SingleIntegrator, SingleSampling, VolPathIntegrator};
use niebla::light::{AreaLight, AreaShape, EnvironmentMap, Light};
use niebla::math::{Ray, Vec3};
use niebla::medium::{HomogeneousMedium, Medium, MediumId};
use niebla::phase::PhaseFunction;
use niebla::sampling::{PixelSampler, SamplerKind};
use niebla::scene::{build_scene, parse_scene_str, Scene, SceneObject};
use niebla::tracking::TransmittanceMethod;

fn floor(reflectance: f32) -> SceneObject {
    let t = Transform::from_components(Vec3::splat(50.0), Vec3::new(-90.0, 0.0, 0.0), Vec3::ZERO).unwrap();
    SceneObject {
        shape: Shape::Rectangle(Rectangle::new(t)),
        bsdf: Bsdf::Diffuse { reflectance: Rgb::splat(reflectance) },
        interior: None,
        exterior: None,
        bounds_medium: false,
        emitter: None,
        texture: None,
        roughness: None,
        dpdu_frame: false,
    }
}

fn mean_radiance<I: Integrator>(integrator: &I, s: &Scene, ray: Ray, medium: Option<MediumId>, n: u32) -> Stats {
    let mut stats = Stats::default();
    for i in 0..n {
        let mut sampler = PixelSampler::for_pixel(SamplerKind::default(), 9, 0, 0, i as u64);
        stats.add(integrator.radiance(s, ray, medium, &mut sampler).g() as f64);
    }
    stats
}

#[test]
fn floor_under_a_sphere_light_shows_the_closed_form_radiance() {
    let (radius, height, radiance, rho) = (0.5f32, 3.0f32, 4.0f32, 0.7f32);
    let light = AreaLight::new(
        AreaShape::Sphere(Sphere::new(Vec3::new(0.0, height, 0.0), radius)),
        Rgb::splat(radiance),
        false,
    )
    .unwrap();
    let emitter = SceneObject {
        shape: Shape::Sphere(Sphere::new(Vec3::new(0.0, height, 0.0), radius)),
        bsdf: Bsdf::Diffuse { reflectance: Rgb::ZERO },
        interior: None,
        exterior: None,
        bounds_medium: false,
        emitter: Some(0),
        texture: None,
        roughness: None,
        dpdu_frame: false,
    };
    let camera = PerspectiveCamera::look_at(Vec3::new(3.0, 1.0, 0.0), Vec3::ZERO, Vec3::Y, 10.0, 1, 1).unwrap();
    let s = scene(camera, vec![emitter, floor(rho)], vec![], vec![Light::Area(light)], None);
    // Lambertian radiance rho/pi * E with E = pi L (R/d)^2 for a sphere on the normal.
    let expected = (rho * radiance * (radius / height).powi(2)) as f64;
    let ray = Ray::new(camera.position, (Vec3::ZERO - camera.position).normalize());
    let single = SingleIntegrator {
        step: None,
        sampling: SingleSampling::Mis,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: None,
    };
    for (name, stats) in [
        ("single", mean_radiance(&single, &s, ray, None, 4_000)),
        ("volpath", mean_radiance(&VolPathIntegrator::new(8), &s, ray, None, 40_000)),
    ] {
        let z = (stats.mean() - expected) / (stats.standard_error() + 1e-6 * expected);
        assert!(z.abs() < 4.0, "{name}: {} +- {} vs {expected}", stats.mean(), stats.standard_error());
    }
    // Looking at the light itself shows its radiance.
    let at_light = Ray::new(Vec3::new(0.0, height, 5.0), -Vec3::Z);
    let direct = mean_radiance(&VolPathIntegrator::new(8), &s, at_light, None, 16);
    assert!((direct.mean() - radiance as f64).abs() < 1e-5);
}

/// A disk light of radius `R` facing a Lambertian floor from height `h`:
/// the point below its centre receives `E = pi L R^2 / (h^2 + R^2)` and shows
/// `rho L R^2 / (h^2 + R^2)` (the disk is read from a scene file, so the
/// parser and builder are covered too).
#[test]
fn floor_under_a_disk_light_shows_the_closed_form_radiance() {
    let (radius, height, radiance, rho) = (1.5f32, 2.0f32, 3.0f32, 0.6f32);
    let text = format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [3, 1, 0], "target": [0, 0, 0], "width": 1, "height": 1}},
            "shapes": [{{"type": "rectangle", "to_world": {{"scale": 50, "rotate_x": -90}},
                         "bsdf": {{"type": "diffuse", "reflectance": {rho}}}}}],
            "lights": [{{"type": "area", "radiance": {radiance},
                         "shape": {{"type": "disk", "to_world": {{"scale": {radius}, "rotate_x": 90,
                                    "translate": [0, {height}, 0]}}}}}}]}}"#
    );
    let desc = parse_scene_str(&text, "disk.json").unwrap();
    let built = build_scene(&desc, "disk.json", std::path::Path::new(".")).unwrap();
    let s = &built.scene;
    let Light::Area(light) = &s.lights[0] else { panic!("an area light") };
    assert!((light.area() - std::f32::consts::PI * radius * radius).abs() < 1e-4);
    let expected = (rho * radiance * radius * radius / (height * height + radius * radius)) as f64;
    let camera = Vec3::new(3.0, 1.0, 0.0);
    let ray = Ray::new(camera, (Vec3::ZERO - camera).normalize());
    let single = SingleIntegrator {
        step: None,
        sampling: SingleSampling::Mis,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: None,
    };
    for (name, stats) in [
        ("single", mean_radiance(&single, s, ray, None, 4_000)),
        ("volpath", mean_radiance(&VolPathIntegrator::new(8), s, ray, None, 40_000)),
    ] {
        let z = (stats.mean() - expected) / (stats.standard_error() + 1e-6 * expected);
        assert!(z.abs() < 4.0, "{name}: {} +- {} vs {expected}", stats.mean(), stats.standard_error());
    }
    // Looking up at the disk inside its rim shows its radiance; just outside the rim, the black ceiling.
    let up = |x: f32| mean_radiance(&VolPathIntegrator::new(8), s, Ray::new(Vec3::new(x, 0.5, 0.0), Vec3::Y), None, 4);
    assert!((up(0.98 * radius).mean() - radiance as f64).abs() < 1e-5);
    assert_eq!(up(1.02 * radius).mean(), 0.0);
}

#[test]
fn uniform_environment_map_is_a_white_furnace_for_volpath() {
    // A 16 x 8 map of radiance 0.5 everywhere, rotated: every direction sees 0.5.
    let map =
        EnvironmentMap::from_pixels(16, 8, vec![Rgb::splat(0.5); 128], 1.0, glam::Mat3::from_rotation_y(0.7)).unwrap();
    let env = Light::Environment(Arc::new(map));
    let medium = Medium::Homogeneous(HomogeneousMedium {
        sigma_a: Rgb::ZERO,
        sigma_s: Rgb::new(3.0, 1.0, 6.0),
        l_ve: Rgb::ZERO,
        phase: PhaseFunction::hg(0.5),
    });
    let sphere = SceneObject {
        shape: Shape::Sphere(Sphere::new(Vec3::ZERO, 1.0)),
        bsdf: Bsdf::Null,
        interior: Some(MediumId(0)),
        exterior: None,
        bounds_medium: true,
        emitter: None,
        texture: None,
        roughness: None,
        dpdu_frame: false,
    };
    let s = scene(common::camera_along_x(1, 1, 30.0), vec![sphere], vec![medium], vec![env], None);
    let stats =
        mean_radiance(&VolPathIntegrator::new(1000), &s, Ray::new(Vec3::new(-3.0, 0.2, 0.1), Vec3::X), None, 4_000);
    let z = (stats.mean() - 0.5) / (stats.standard_error() + 1e-5);
    assert!(z.abs() < 4.0, "{} +- {}", stats.mean(), stats.standard_error());
}

#[test]
fn environment_map_seen_directly_is_its_radiance_and_lights_a_floor() {
    // Bright band around the horizon, dark poles: a floor (facing up) sees the
    // upper hemisphere only; single and volpath must agree on its radiance.
    let (w, h) = (32usize, 16usize);
    let pixels: Vec<Rgb> = (0..w * h).map(|i| Rgb::splat(if (i / w) == 6 { 8.0 } else { 0.2 })).collect();
    let map = Arc::new(EnvironmentMap::from_pixels(w, h, pixels, 1.0, glam::Mat3::IDENTITY).unwrap());
    let env = Light::Environment(map.clone());
    let camera = PerspectiveCamera::look_at(Vec3::new(2.0, 2.0, 0.0), Vec3::ZERO, Vec3::Y, 10.0, 1, 1).unwrap();
    let s = scene(camera, vec![floor(0.5)], vec![], vec![env], None);
    let up = Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.3, 0.8, 0.1).normalize());
    let seen = mean_radiance(&VolPathIntegrator::new(4), &s, up, None, 8);
    assert!((seen.mean() - map.le(up.d).g() as f64).abs() < 1e-6);
    let ray = Ray::new(camera.position, (Vec3::ZERO - camera.position).normalize());
    let single = SingleIntegrator {
        step: None,
        sampling: SingleSampling::Mis,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: None,
    };
    let a = mean_radiance(&single, &s, ray, None, 20_000);
    let b = mean_radiance(&VolPathIntegrator::new(4), &s, ray, None, 20_000);
    // Irradiance from the upper hemisphere by direct quadrature over pixels.
    let mut e = 0.0f64;
    for y in 0..h {
        for x in 0..w {
            let d = map.pixel_direction(x, y);
            if d.y > 0.0 {
                e += map.pixel(x, y).g() as f64 * d.y as f64 * map.pixel_solid_angle(y) as f64;
            }
        }
    }
    let expected = 0.5 / std::f64::consts::PI * e;
    for (name, st) in [("single", a), ("volpath", b)] {
        // The quadrature puts each pixel's radiance at its center direction:
        // allow 2% for that, plus 4 standard errors.
        let tol = 4.0 * st.standard_error() + 0.02 * expected;
        assert!((st.mean() - expected).abs() < tol, "{name}: {} +- {} vs {expected}", st.mean(), st.standard_error());
    }
}

#[test]
fn scene_files_describe_area_lights_and_environment_maps() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("envmap_scene");
    std::fs::create_dir_all(&dir).unwrap();
    let mut sky = niebla::film::Image::new(8, 4);
    for (i, p) in sky.pixels.iter_mut().enumerate() {
        *p = Rgb::splat(0.1 + i as f32 * 0.01);
    }
    niebla::film::write_exr(&sky, &dir.join("sky.exr")).unwrap();
    let text = |lights: &str| {
        format!(
            r#"{{"version": 1,
                "camera": {{"type": "perspective", "position": [0, 1, 5], "target": [0, 0, 0], "width": 8, "height": 8}},
                "shapes": [{{"type": "rectangle", "to_world": {{"scale": 4, "rotate_x": -90}},
                             "bsdf": {{"type": "diffuse"}}}}],
                "lights": {lights}}}"#
        )
    };
    let good = text(
        r#"[{"type": "area", "shape": {"type": "rectangle", "to_world": {"translate": [0, 2, 0], "rotate_x": 90}},
             "radiance": [5, 4, 3]},
            {"type": "area", "shape": {"type": "sphere", "center": [1, 1, 0], "radius": 0.2}, "radiance": 10},
            {"type": "envmap", "file": "sky.exr", "scale": 2, "to_world": {"rotate_y": 90}}]"#,
    );
    let desc = parse_scene_str(&good, "lights.json").unwrap();
    let built = build_scene(&desc, "lights.json", &dir).unwrap();
    let s = &built.scene;
    assert_eq!(s.lights.len(), 3);
    assert_eq!(s.objects.len(), 3, "each area light is also a surface");
    assert_eq!(s.light_object(0), Some(1));
    assert_eq!(s.light_object(1), Some(2));
    assert!(matches!(s.lights[2], Light::Environment(_)));
    // The rectangle light faces down (rotate_x 90 turns +z to -y): the floor sees it.
    let image = niebla::render::render(
        s,
        &niebla::integrator::IntegratorSettings::VolPath {
            max_depth: 4,
            volume_light_sampling: true,
            emitter_guiding: true,
        },
        &niebla::render::RenderOptions {
            spp: 4,
            seed: 0,
            first_sample: 0,
            threads: Some(1),
            sampler: Default::default(),
        },
        &|_, _| {},
        None,
    )
    .unwrap();
    assert!(image.mean().max_channel() > 0.0 && image.pixels.iter().all(|p| p.is_finite()));
    let errors = [
        (
            r#"[{"type": "area", "shape": {"type": "box", "min": [0, 0, 0], "max": [1, 1, 1]}, "radiance": 1}]"#,
            "lights[0].shape.type",
        ),
        (r#"[{"type": "area", "radiance": 1}]"#, "lights[0].shape"),
        (
            r#"[{"type": "area", "shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "radiance": -1}]"#,
            "lights[0].radiance",
        ),
        (r#"[{"type": "envmap", "file": "missing.exr"}]"#, "lights[0].file"),
        (r#"[{"type": "envmap", "file": "sky.exr", "scale": -1}]"#, "lights[0].scale"),
    ];
    for (lights, path) in errors {
        let err = parse_scene_str(&text(lights), "lights.json")
            .and_then(|d| build_scene(&d, "lights.json", &dir).map(|_| ()));
        let err = err.unwrap_err();
        assert_eq!(err.path, path, "{lights}: {err}");
    }
}
