//! `Shape::dpdu`, the tangent of anisotropic roughness under
//! `"tangent_frame": "dpdu"`, checked against a finite difference of each
//! shape's own uv parameterization (`Shape::uv`): around a hit, rays hit
//! the surface at `p +- h t1` and `p +- h t2` (`t1`, `t2` spanning the
//! tangent plane, `h` = 1e-3 of the shape's size); central differences give
//! the 2x2 Jacobian of (u, v) and the 3x2 one of the position over those
//! offsets, and `dp/du` is the position's Jacobian times the first column
//! of the inverse of uv's. Truncation error is O(h^2) ~ 1e-6 relative; f32
//! rounding of uv (~1e-7 absolute) over 2h gives ~1e-4 relative, so the
//! tolerance is 1e-3 of |dp/du|.

use std::sync::Arc;

use niebla::geometry::{AxisAlignedBox, Disk, MeshInstance, Rectangle, Shape, Sphere, Transform, TriangleMesh};
use niebla::math::{Frame, Ray, Vec2, Vec3};

/// The hit of a ray toward `p` coming from outside along `n` (unit), with
/// the shape's dp/du and uv there.
fn hit_toward(shape: &Shape, p: Vec3, n: Vec3) -> (Vec3, Vec3, Vec2) {
    let ray = Ray::new(p + n * 0.5, -n);
    let inv = ray.d.recip();
    let h = shape.hit_t(&ray, inv, 0.0, 1.0).unwrap_or_else(|| panic!("no hit toward {p}"));
    let s = shape.surface_at(&ray, &h);
    (s.p, shape.dpdu(&s, &h, 0.0), shape.uv(&s, &h, 0.0))
}

/// Finite-difference dp/du at `p` (on the surface, outward normal `n`).
fn fd_dpdu(shape: &Shape, p: Vec3, n: Vec3, h: f32) -> Vec3 {
    let f = Frame::from_z(n);
    let at = |d: Vec3| {
        let (q, _, uv) = hit_toward(shape, p + d, n);
        (q, uv)
    };
    let ((p1p, uv1p), (p1m, uv1m)) = (at(f.x * h), at(-f.x * h));
    let ((p2p, uv2p), (p2m, uv2m)) = (at(f.y * h), at(-f.y * h));
    let (dp1, dp2) = ((p1p - p1m) / (2.0 * h), (p2p - p2m) / (2.0 * h));
    let (duv1, duv2) = ((uv1p - uv1m) / (2.0 * h), (uv2p - uv2m) / (2.0 * h));
    // [duv1 duv2] (a, b) = (1, 0): the offset along which u grows by 1 and v stays.
    let det = duv1.x * duv2.y - duv2.x * duv1.y;
    let (a, b) = (duv2.y / det, -duv1.y / det);
    dp1 * a + dp2 * b
}

fn check(name: &str, shape: &Shape, p: Vec3, n: Vec3, h: f32) {
    let (_, dpdu, _) = hit_toward(shape, p, n);
    let fd = fd_dpdu(shape, p, n, h);
    let err = (dpdu - fd).length() / fd.length();
    assert!(err < 1e-3, "{name} at {p}: dp/du {dpdu}, finite difference {fd} (relative error {err:e})");
}

fn placement() -> Transform {
    Transform::from_components(Vec3::new(2.0, 0.5, 1.0), Vec3::new(30.0, 50.0, 10.0), Vec3::new(1.0, 2.0, 3.0)).unwrap()
}

#[test]
fn sphere_dpdu_is_the_azimuth_derivative() {
    let s = Sphere { center: Vec3::new(0.3, -0.2, 0.5), radius: 1.7 };
    let shape = Shape::Sphere(s);
    for (theta, phi) in [(0.4f32, 0.7f32), (1.3, 2.0), (2.1, 4.0), (2.8, 5.5)] {
        let n = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        check("sphere", &shape, s.center + n * s.radius, n, 2e-3);
    }
}

#[test]
fn rectangle_and_disk_dpdu_follow_their_placement() {
    let t = placement();
    let rect = Shape::Rectangle(Rectangle::new(t));
    let disk = Shape::Disk(Disk::new(t));
    let n = t.normal_to_world(Vec3::Z);
    for (x, y) in [(0.3f32, -0.6f32), (-0.7, 0.2), (0.1, 0.8)] {
        let p = t.point_to_world(Vec3::new(x, y, 0.0));
        check("rectangle", &rect, p, n, 1e-3);
        // The disk's v (azimuth) jumps at phi = 0: these points lie away from it.
        check("disk", &disk, p, n, 1e-3);
    }
}

#[test]
fn box_dpdu_is_each_faces_u_axis() {
    let b = AxisAlignedBox { min: Vec3::new(-1.0, -0.5, 0.2), max: Vec3::new(2.0, 1.5, 1.0) };
    let shape = Shape::Box(b);
    let c = (b.min + b.max) * 0.5;
    let e = b.max - b.min;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            // A point off the face's center, inside the face.
            let p = c + n * (e * 0.5) + (Vec3::ONE - n.abs()) * e * Vec3::new(0.13, -0.21, 0.17);
            check("box", &shape, p, n, 1e-3);
        }
    }
}

#[test]
fn mesh_dpdu_comes_from_the_triangles_uvs() {
    let positions =
        vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.1, 0.0), Vec3::new(0.2, 1.0, 0.3), Vec3::new(1.2, 1.1, 0.5)];
    let triangles = vec![[0, 1, 2], [1, 3, 2]];
    // A sheared, mirrored-in-places uv layout.
    let uvs = vec![Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.4), Vec2::new(0.3, 0.7), Vec2::new(0.6, 1.5)];
    let mesh = Arc::new(TriangleMesh::new(positions.clone(), triangles.clone(), None, Some(uvs)).unwrap());
    let shape = Shape::Mesh(MeshInstance::new(mesh, placement(), false));
    let bare = Arc::new(TriangleMesh::new(positions.clone(), triangles.clone(), None, None).unwrap());
    let bare = Shape::Mesh(MeshInstance::new(bare, placement(), false));
    let t = placement();
    for tri in &triangles {
        let [a, b, c] = tri.map(|i| t.point_to_world(positions[i as usize]));
        let p = (a + b + c) / 3.0;
        let n = (b - a).cross(c - a).normalize();
        check("mesh", &shape, p, n, 1e-3);
        // Without uvs: Mitsuba's coordinate_system of the geometric normal.
        let (_, dpdu, _) = hit_toward(&bare, p, n);
        assert!((dpdu - Frame::from_z(n).x).length() < 1e-5, "{dpdu} {}", Frame::from_z(n).x);
    }
}

fn build(json: &str) -> niebla::scene::BuiltScene {
    let desc = niebla::scene::parse_scene_str(json, "t.json").unwrap_or_else(|e| panic!("{e}"));
    niebla::scene::build_scene(&desc, "t.json", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

fn scene_json(shape: &str) -> String {
    format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [0, 0.5, 4], "target": [0, 0, 0], "width": 8, "height": 6,
                        "shutter_open": 0, "shutter_close": 1}},
            "shapes": [{shape}],
            "lights": [{{"type": "constant", "radiance": 0.5}}, {{"type": "point", "position": [1, 3, 2], "intensity": 5}}],
            "render": {{"spp": 4, "integrator": {{"type": "volpath"}}}}}}"#
    )
}

fn render_bits(json: &str) -> Vec<u32> {
    use niebla::render::{render, RenderOptions};
    let built = build(json);
    let options = RenderOptions {
        spp: 4,
        seed: 3,
        first_sample: 0,
        threads: Some(1),
        sampler: niebla::sampling::SamplerKind::Independent,
    };
    let image = render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap();
    let (w, h) = (built.scene.camera.width, built.scene.camera.height);
    (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).flat_map(|(x, y)| image.get(x, y).0.map(f32::to_bits)).collect()
}

/// Isotropic roughness ignores `"tangent_frame": "dpdu"`: no tangent is
/// computed (`dpdu_frame` stays false) and the image is bit-identical to the
/// default frame's; anisotropic roughness on the same sphere changes it.
#[test]
fn isotropic_roughness_ignores_the_tangent_frame() {
    let sphere = |frame: &str, alpha: &str| {
        scene_json(&format!(
            r#"{{"type": "sphere", "center": [0, 0, 0], "radius": 1{frame},
                "bsdf": {{"type": "roughconductor", "distribution": "ggx", "material": "Al", {alpha}}}}}"#
        ))
    };
    let iso = r#""alpha": 0.2"#;
    let aniso = r#""alpha_u": 0.05, "alpha_v": 0.4"#;
    let dpdu = r#", "tangent_frame": "dpdu""#;
    assert!(!build(&sphere(dpdu, iso)).scene.objects[0].dpdu_frame);
    assert!(build(&sphere(dpdu, aniso)).scene.objects[0].dpdu_frame);
    assert_eq!(render_bits(&sphere("", iso)), render_bits(&sphere(dpdu, iso)));
    assert_ne!(render_bits(&sphere("", aniso)), render_bits(&sphere(dpdu, aniso)));
}

/// A moving rectangle's dp/du is taken in its pose at the hit's time: a
/// quarter turn about its normal (z) between time 0 and 1 turns dp/du from
/// +x (times 2 s, the scale s = 0.5) to +y.
#[test]
fn moving_shapes_take_dpdu_in_their_pose_at_the_hit_time() {
    let built = build(&scene_json(
        r#"{"type": "rectangle", "to_world": {"scale": 0.5}, "tangent_frame": "dpdu",
            "motion": {"to_world": {"scale": 0.5, "rotate_z": 90}},
            "bsdf": {"type": "roughconductor", "alpha_u": 0.05, "alpha_v": 0.4}}"#,
    ));
    let shape = &built.scene.objects[0].shape;
    assert!(matches!(shape, Shape::Moving(_)));
    for (time, expected) in [(0.0f32, Vec3::X), (1.0, Vec3::Y), (0.5, Vec3::new(1.0, 1.0, 0.0).normalize())] {
        let mut ray = Ray::new(Vec3::new(0.1, 0.05, 1.0), -Vec3::Z);
        ray.time = time;
        let h = shape.hit_t(&ray, ray.d.recip(), 0.0, 10.0).expect("hit");
        let s = shape.surface_at(&ray, &h);
        let dpdu = shape.dpdu(&s, &h, time);
        assert!((dpdu - expected).length() < 1e-5, "time {time}: dp/du {dpdu}, expected {expected}");
    }
}
