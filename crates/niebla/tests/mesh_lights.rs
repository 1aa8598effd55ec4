//! Emitting meshes (`{"type": "area", "shape": {"type": "mesh", ..}}`):
//! light sampling against its own pdf (chi-square, and the pdf integrating
//! to 1), against closed forms and quadrature it does not use, light
//! sampling (NEE) against BSDF sampling through the scene on a non-convex
//! mesh that hides parts of itself, and the errors for bad emitting meshes.

mod common;

use std::f64::consts::PI as PI64;
use std::sync::Arc;

use niebla::color::Rgb;
use niebla::geometry::{MeshInstance, Transform, TriangleMesh};
use niebla::light::{AreaLight, AreaShape, Light, MeshLight};
use niebla::math::{Frame, Vec2, Vec3};
use niebla::sampling::PixelSampler;
use niebla::scene::{build_scene, parse_scene_str};

use common::mean_se;

/// A mesh light from object-space data placed by the identity.
fn mesh_light(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>, normals: Option<Vec<Vec3>>) -> AreaLight {
    let mesh = TriangleMesh::new(positions, triangles, normals, None).unwrap();
    let t = Transform::from_components(Vec3::ONE, Vec3::ZERO, Vec3::ZERO).unwrap();
    let light = MeshLight::new(MeshInstance::new(Arc::new(mesh), t, false)).unwrap();
    AreaLight::new(AreaShape::Mesh(Arc::new(light)), Rgb::ONE, false).unwrap()
}

/// A pyramid roof over the square [-1, 1]^2 at height 2 (apex at height
/// 2.6), wound so that its normals point down (toward the receivers below),
/// with vertex normals tilted away from the winding's where asked. Seen
/// from below, each direction meets at most one triangle.
fn roof(normals: bool) -> AreaLight {
    let positions = vec![
        Vec3::new(-1.0, 2.0, -1.0),
        Vec3::new(1.0, 2.0, -1.0),
        Vec3::new(1.0, 2.0, 1.0),
        Vec3::new(-1.0, 2.0, 1.0),
        Vec3::new(0.0, 2.6, 0.0),
    ];
    // Counter-clockwise seen from below: normals point down.
    let triangles = vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
    let normals = normals.then(|| {
        vec![
            Vec3::new(-0.5, -1.0, -0.5).normalize(),
            Vec3::new(0.5, -1.0, -0.5).normalize(),
            Vec3::new(0.5, -1.0, 0.5).normalize(),
            Vec3::new(-0.5, -1.0, 0.5).normalize(),
            Vec3::new(0.3, -1.0, 0.0).normalize(),
        ]
    });
    mesh_light(positions, triangles, normals)
}

/// Chi-square of `n` directions from `light.sample_li(p, ..)` binned in
/// (cos theta, phi) cells around straight up, against `density.pdf_li`
/// integrated over each cell by a midpoint rule; also returns the integral
/// of that density over the whole upper hemisphere. Every sample of
/// `light` must be kept (it faces `p`) and report its own `pdf_li`.
fn chi_square_up(light: &AreaLight, density: &AreaLight, p: Vec3, n: usize, key: u64) -> (f64, usize, f64) {
    let (n_cos, n_phi) = (16usize, 24usize);
    let cell = |w: Vec3| -> usize {
        let c = ((w.y as f64).clamp(0.0, 1.0 - 1e-12) * n_cos as f64) as usize;
        let phi = (w.z as f64).atan2(w.x as f64).rem_euclid(2.0 * PI64);
        c * n_phi + ((phi / (2.0 * PI64) * n_phi as f64) as usize).min(n_phi - 1)
    };
    let mut observed = vec![0.0; n_cos * n_phi];
    let mut rng = PixelSampler::from_key(key);
    // A point sampled within rounding of an edge may be found on the
    // neighbouring triangle by pdf_li's ray, whose normal differs (face
    // normals jump at edges): allowed for 1 sample in 10^4.
    let mut off = 0;
    for _ in 0..n {
        let s = light.sample_li(p, rng.next_2d()).expect("every point faces p");
        {
            assert!(s.wi.y > 0.0);
            let pdf = light.pdf_li(p, s.wi);
            if (pdf - s.pdf).abs() > 1e-3 * s.pdf {
                off += 1;
            }
            observed[cell(s.wi)] += 1.0;
        }
    }
    eprintln!("{off} of {n} samples with pdf_li off their pdf by more than 0.1%");
    assert!(off <= n / 10_000, "{off} samples with pdf_li off their pdf");
    // Expected counts: pdf_li (a density per steradian whose samples are
    // all kept here: every sampled point faces p) over each cell.
    let q = 24;
    let mut expected = vec![0.0; n_cos * n_phi];
    let mut total = 0.0;
    for (k, e) in expected.iter_mut().enumerate() {
        let (ci, pi) = (k / n_phi, k % n_phi);
        let (c0, dc) = (ci as f64 / n_cos as f64, 1.0 / (n_cos * q) as f64);
        let (p0, dp) = (pi as f64 * 2.0 * PI64 / n_phi as f64, 2.0 * PI64 / (n_phi * q) as f64);
        let mut sum = 0.0;
        for a in 0..q {
            let cos = c0 + (a as f64 + 0.5) * dc;
            let sin = (1.0 - cos * cos).sqrt();
            for b in 0..q {
                let phi = p0 + (b as f64 + 0.5) * dp;
                let w = Vec3::new((sin * phi.cos()) as f32, cos as f32, (sin * phi.sin()) as f32);
                sum += density.pdf_li(p, w) as f64;
            }
        }
        *e = sum * dc * dp * n as f64;
        total += sum * dc * dp;
    }
    let (mut stat, mut cells, mut po, mut pe) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            po += o;
            pe += e;
        } else {
            stat += (o - e).powi(2) / e;
            cells += 1;
        }
    }
    if pe > 0.0 {
        stat += (po - pe).powi(2) / pe;
        cells += 1;
    }
    (stat, cells - 1, total)
}

/// Chi-square quantile at tail probability ~1e-4 (Wilson-Hilferty, z = 3.72).
fn chi2_bound(dof: usize) -> f64 {
    let k = dof as f64;
    let c = 2.0 / (9.0 * k);
    k * (1.0 - c + 3.72 * c.sqrt()).powi(3)
}

#[test]
fn mesh_light_directions_follow_pdf_li_and_it_integrates_to_one() {
    // Without vertex normals pdf_li is the density of the sampled
    // directions: chi-square against it, and (every point of the roof is
    // seen from p, below it and off centre, and faces it) it integrates to
    // 1 over the directions (midpoint rule error well below 0.5%).
    let p = Vec3::new(0.3, 0.2, -0.4);
    let n = 200_000;
    let flat = roof(false);
    let (stat, dof, total) = chi_square_up(&flat, &flat, p, n, 11);
    eprintln!("roof: chi2 {stat:.1}, dof {dof}, bound {:.1}; integral of pdf_li {total:.5}", chi2_bound(dof));
    assert!(stat < chi2_bound(dof), "chi2 {stat} with {dof} dof");
    assert!((total - 1.0).abs() < 5e-3, "integral {total}");
    // With vertex normals the points are drawn the same way (uniform by
    // area), and the reported pdf converts area to solid angle with the
    // geometric cosine, so it is the density of the sampled directions too
    // (Mitsuba 3's `pdf_direction` takes the interpolated normal's cosine,
    // which is not): chi-square against it, against the flat roof's, and it
    // integrates to 1 (every point of this roof faces p by its normals).
    let smooth = roof(true);
    let (stat, dof, total) = chi_square_up(&smooth, &smooth, p, n, 12);
    eprintln!("roof with normals: chi2 {stat:.1}, dof {dof}; integral of pdf_li {total:.5}");
    assert!(stat < chi2_bound(dof), "chi2 {stat} with {dof} dof");
    assert!((total - 1.0).abs() < 5e-3, "integral {total}");
    let (stat, dof, _) = chi_square_up(&smooth, &flat, p, n, 13);
    eprintln!("roof with normals against the flat density: chi2 {stat:.1}, dof {dof}");
    assert!(stat < chi2_bound(dof), "chi2 {stat} with {dof} dof");
}

#[test]
fn planar_mesh_light_irradiance_matches_the_rectangle_closed_form() {
    // A 2 x 2 square at height h as two triangles facing down: irradiance
    // at the point below its centre is 4 corner-rectangle form factors
    // times pi L (the rectangle light's closed form, see light_sampling.rs).
    let h = 1.5f64;
    let corner = |x: f64, y: f64| {
        let (rx, ry) = ((x * x + h * h).sqrt(), (y * y + h * h).sqrt());
        0.5 * (x / rx * (y / rx).atan() + y / ry * (x / ry).atan())
    };
    let exact = 4.0 * corner(1.0, 1.0);
    let y = h as f32;
    let positions =
        vec![Vec3::new(-1.0, y, -1.0), Vec3::new(1.0, y, -1.0), Vec3::new(1.0, y, 1.0), Vec3::new(-1.0, y, 1.0)];
    let light = mesh_light(positions, vec![[0, 1, 2], [0, 2, 3]], None);
    let mut rng = PixelSampler::from_key(21);
    let values: Vec<f64> = (0..100_000)
        .map(|_| match light.sample_li(Vec3::ZERO, rng.next_2d()) {
            Some(s) => s.li.g() as f64 * s.wi.y.max(0.0) as f64 / s.pdf as f64,
            None => 0.0,
        })
        .collect();
    let (mean, se) = mean_se(&values);
    eprintln!("planar mesh: E {mean:.6} +- {se:.2e}, closed form {exact:.6}");
    assert!((mean - exact).abs() < 4.0 * se, "{mean} vs {exact} (se {se})");
    // Turned over (normals up), the receiver below sees its back: nothing.
    let positions =
        vec![Vec3::new(-1.0, y, -1.0), Vec3::new(1.0, y, -1.0), Vec3::new(1.0, y, 1.0), Vec3::new(-1.0, y, 1.0)];
    let up = mesh_light(positions, vec![[0, 2, 1], [0, 3, 2]], None);
    assert!((0..100).all(|i| up.sample_li(Vec3::ZERO, Vec2::new(i as f32 / 100.0, 0.37)).is_none()));
}

#[test]
fn vertex_normal_roof_irradiance_matches_quadrature() {
    // With vertex normals a point emits toward the receiver when the
    // direction is on its interpolated normal's side (Mitsuba 3's rule),
    // and the area-to-solid-angle cosine is the triangle's (geometric), so
    // light sampling estimates E = integral of L cos_r |ng . d| / r^2 over
    // the emitting points: the radiance L over the directions that see an
    // emitting point, what a ray that hits the roof finds. Quadrature: 400 x
    // 400 barycentric midpoints per triangle, normals interpolated here from
    // the table in `roof`. With the interpolated normal's cosine instead
    // (Mitsuba 3's `pdf_direction`), the quadrature is printed too: at these
    // points it differs by more than 10 standard errors of the estimate.
    let light = roof(true);
    let p = Vec3::new(-0.6, 0.0, 0.5);
    let positions = [[-1.0, 2.0, -1.0], [1.0, 2.0, -1.0], [1.0, 2.0, 1.0], [-1.0, 2.0, 1.0], [0.0, 2.6, 0.0]]
        .map(|v: [f64; 3]| glam::DVec3::from(v));
    let normals = [[-0.5, -1.0, -0.5], [0.5, -1.0, -0.5], [0.5, -1.0, 0.5], [-0.5, -1.0, 0.5], [0.3, -1.0, 0.0]]
        .map(|v: [f64; 3]| glam::DVec3::from(v).normalize());
    let pd = glam::DVec3::new(p.x as f64, p.y as f64, p.z as f64);
    let triangles: Vec<_> = [[0usize, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]
        .iter()
        .map(|tri| (tri.map(|i| positions[i]), tri.map(|i| normals[i])))
        .collect();
    let (exact, shading) = common::smooth_mesh_irradiance(&triangles, pd, glam::DVec3::Y, 400);
    let mut rng = PixelSampler::from_key(31);
    let values: Vec<f64> = (0..200_000)
        .map(|_| match light.sample_li(p, rng.next_2d()) {
            Some(s) => s.li.g() as f64 * s.wi.y.max(0.0) as f64 / s.pdf as f64,
            None => 0.0,
        })
        .collect();
    let (mean, se) = mean_se(&values);
    eprintln!(
        "roof with vertex normals: E {mean:.6} +- {se:.2e}, quadrature {exact:.6} (with the shading cosine {shading:.6})"
    );
    assert!((mean - exact).abs() < 4.0 * se + 1e-4 * exact, "{mean} vs {exact} (se {se})");
    assert!((shading - exact).abs() > 10.0 * se, "the test does not tell the two conventions apart");
}

/// A floor and the open roof of scenes/mitsuba/data/tent.obj (inline, two
/// quads meeting at a ridge) turned to emit downward, 1 unit up: the roof is
/// not convex, so from beside it one half hides the other's underside.
const TENT_SCENE: &str = r#"{"version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 0.5, 0], "width": 8, "height": 8},
  "render": {"integrator": {"type": "volpath", "max_depth": 1}},
  "shapes": [{"type": "rectangle", "to_world": {"scale": 4, "rotate_x": -90},
              "bsdf": {"type": "diffuse", "reflectance": 0.5}}],
  "lights": [{"type": "area", "radiance": [3, 2, 1], "shape": {"type": "mesh",
    "positions": [[-0.7, 0, -0.6], [-0.7, 0, 0.6], [0, 0.5, -0.6], [0, 0.5, 0.6], [0.7, 0, -0.6], [0.7, 0, 0.6]],
    "indices": [[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]],
    "flip_normals": true, "to_world": {"translate": [0, 1, 0]}}}]}"#;

#[test]
fn light_sampling_agrees_with_bsdf_sampling_on_a_non_convex_mesh() {
    // Irradiance at floor points (normal +y) two ways through the scene:
    // (a) NEE: Light::sample_li and the shadow ray's transmittance (the
    // mesh itself may block it); (b) cosine-weighted directions traced to
    // the first hit, counting the emitted radiance seen there (pi L_e on
    // average). Floor points under the roof, under its eave and beside it,
    // and a point in the air beside the eaves facing the roof (normal -x),
    // from where the near half hides the far half's underside near the
    // ridge (NEE that let its shadow rays pass through its own mesh would
    // count that part). The roof with face normals, and with Mitsuba's
    // computed vertex normals (`compute_normals`; at the ridge they point
    // straight down, 36 degrees off each half's triangles), where the two
    // strategies agree only if light sampling converts area to solid angle
    // with the geometric cosine (the emitting side follows the vertex
    // normals in both).
    let smooth = TENT_SCENE.replace(r#""flip_normals": true,"#, r#""flip_normals": true, "compute_normals": true,"#);
    assert_ne!(smooth, TENT_SCENE);
    for (text, normals) in [(TENT_SCENE, "face"), (smooth.as_str(), "vertex")] {
        nee_matches_bsdf_sampling(text, normals);
    }
}

/// NEE and BSDF sampling at the points of
/// `light_sampling_agrees_with_bsdf_sampling_on_a_non_convex_mesh` in the
/// tent scene `text`.
fn nee_matches_bsdf_sampling(text: &str, normals: &str) {
    let desc = parse_scene_str(text, "tent.json").unwrap_or_else(|e| panic!("{e}"));
    let built = build_scene(&desc, "tent.json", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let scene = &built.scene;
    let light = &scene.lights[0];
    assert!(matches!(light, Light::Area(a) if a.shape.is_mesh()));
    assert_eq!(scene.light_object(0), None, "a mesh's shadow rays test the mesh itself");
    let points = [
        (Vec3::new(0.0, 0.0, 0.2), Vec3::Y),
        (Vec3::new(0.55, 0.0, 0.2), Vec3::Y),
        (Vec3::new(1.2, 0.0, 0.2), Vec3::Y),
        (Vec3::new(-1.6, 0.0, 0.2), Vec3::Y),
        (Vec3::new(1.5, 0.9, 0.2), -Vec3::X),
    ];
    for (k, (p, n)) in points.into_iter().enumerate() {
        let origin = p + n * 1e-4;
        let mut rng = PixelSampler::from_key(100 + k as u64);
        let count = 100_000;
        let nee: Vec<f64> = (0..count)
            .map(|_| {
                let u = rng.next_2d();
                let Some(s) = light.sample_li(p, Some(n), u, 0.0) else { return 0.0 };
                let cos = s.wi.dot(n);
                if cos <= 0.0 {
                    return 0.0;
                }
                let tr = scene.transmittance(
                    origin,
                    None,
                    s.wi,
                    s.distance,
                    niebla::tracking::TransmittanceMethod::Analytic,
                    &mut rng,
                );
                (s.li * tr).g() as f64 * cos as f64 / s.pdf as f64
            })
            .collect();
        let frame = Frame::from_z(n);
        let bsdf: Vec<f64> = (0..count)
            .map(|_| {
                let local = niebla::sampling::sample_cosine_hemisphere(rng.next_2d());
                let w = frame.to_world(local);
                let ray = niebla::math::Ray::new(origin, w);
                match scene.intersect(&ray, 0.0, f32::INFINITY) {
                    Some(hit) => scene.emitted_radiance(&hit, -w).map_or(0.0, |(le, _)| le.g() as f64 * PI64),
                    None => 0.0,
                }
            })
            .collect();
        let ((a, sa), (b, sb)) = (mean_se(&nee), mean_se(&bsdf));
        let z = (a - b) / (sa * sa + sb * sb).sqrt();
        eprintln!("{normals} normals, p = {p}: NEE {a:.5} +- {sa:.1e}, BSDF {b:.5} +- {sb:.1e}, z {z:.2}");
        assert!(z.abs() < 4.0, "{normals} normals, p = {p}: NEE {a} vs BSDF {b} (z {z:.2})");
        assert!(a > 0.0);
    }
}

#[test]
fn bad_emitting_meshes_are_errors_naming_the_field() {
    // Zero area: every triangle degenerate.
    let zero = TENT_SCENE.replace(
        r#""positions": [[-0.7, 0, -0.6], [-0.7, 0, 0.6], [0, 0.5, -0.6], [0, 0.5, 0.6], [0.7, 0, -0.6], [0.7, 0, 0.6]]"#,
        r#""positions": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [4, 0, 0], [5, 0, 0]]"#,
    );
    assert_ne!(zero, TENT_SCENE);
    let desc = parse_scene_str(&zero, "tent.json").unwrap_or_else(|e| panic!("{e}"));
    let err = build_scene(&desc, "tent.json", std::path::Path::new(".")).unwrap_err().to_string();
    assert!(err.contains("tent.json: lights[0].shape:") && err.contains("degenerate (no area)"), "{err}");
    // A moving emitting mesh.
    let moving = TENT_SCENE.replace(
        r#""to_world": {"translate": [0, 1, 0]}}}]}"#,
        r#""to_world": {"translate": [0, 1, 0]}, "motion": {"to_world": {"translate": [0, 2, 0]}}}}]}"#,
    );
    assert_ne!(moving, TENT_SCENE);
    let err = match parse_scene_str(&moving, "tent.json") {
        Err(e) => e.to_string(),
        Ok(desc) => build_scene(&desc, "tent.json", std::path::Path::new(".")).unwrap_err().to_string(),
    };
    assert!(err.contains("lights[0].shape.motion") && err.contains("cannot move"), "{err}");
}

#[test]
fn hegeman_and_zhou_refuse_an_emitting_mesh() {
    let desc = parse_scene_str(TENT_SCENE, "tent.json").unwrap_or_else(|e| panic!("{e}"));
    let built = build_scene(&desc, "tent.json", std::path::Path::new(".")).unwrap();
    for name in ["hegeman", "zhou"] {
        let settings = niebla::integrator::registry::defaults(name).unwrap();
        let options = niebla::render::RenderOptions {
            spp: 1,
            seed: 0,
            first_sample: 0,
            threads: Some(1),
            sampler: niebla::sampling::SamplerKind::Independent,
        };
        let err = niebla::render::render(&built.scene, &settings, &options, &|_, _| {}, None).unwrap_err().to_string();
        assert!(err.contains(name) && err.contains("lights[0] is an emitting mesh"), "{err}");
    }
}
