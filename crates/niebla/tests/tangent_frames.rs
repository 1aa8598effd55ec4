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
    let s = Sphere::new(Vec3::new(0.3, -0.2, 0.5), 1.7);
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
        // Without uvs: the uv is (b1, b2), so dp/du is the edge p1 - p0
        // (Mitsuba 3.9.1; see the flipped case below).
        let (_, dpdu, _) = hit_toward(&bare, p, n);
        assert!((dpdu - (b - a)).length() < 1e-5, "{dpdu} {}", b - a);
        check("mesh without uvs", &bare, p, n, 1e-3);
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

/// Mitsuba's `cube` imported from XML where its surface needs uvs (here
/// anisotropic roughness): at the hits Mitsuba 3.9.1 recorded on a cube
/// placed by a turned, unevenly scaled `to_world` (two points on each face,
/// one per triangle; crates/niebla/tests/data/mitsuba_cube.json, written by
/// `scripts/mitsuba_refs.py --cube`), niebla's hit point, uv and dp/du are
/// Mitsuba's within f32 rounding (1e-5 of the cube's size for points and
/// uv, 1e-4 relative for dp/du, whose entries are differences of f32
/// vertex positions over uv steps of 1), and dp/du is the finite
/// difference of niebla's own uvs (see `check`).
#[test]
fn mitsuba_cube_has_mitsubas_uv_and_dpdu_on_every_face() {
    let table: serde_json::Value =
        serde_json::from_str(include_str!("data/mitsuba_cube.json")).expect("the cube table");
    let v3 = |v: &serde_json::Value| {
        let a: Vec<f32> = v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
        Vec3::new(a[0], a[1], a[2])
    };
    let m = table["to_world"].as_array().unwrap();
    let matrix: Vec<String> =
        m.iter().flat_map(|row| row.as_array().unwrap().iter().map(|x| x.as_f64().unwrap().to_string())).collect();
    let xml = format!(
        r#"<scene version="3.0.0">
             <sensor type="perspective"><float name="fov" value="40"/><transform name="to_world"><lookat origin="0, 0, 6" target="0, 0, 0" up="0, 1, 0"/></transform>
               <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
             <shape type="cube"><transform name="to_world"><matrix value="{}"/></transform>
               <bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.4"/></bsdf>
             </shape>
           </scene>"#,
        matrix.join(" ")
    );
    let imported = niebla::scene::mitsuba::import_mitsuba_str(&xml, "cube.xml", std::path::Path::new("."), &[])
        .unwrap_or_else(|e| panic!("{e}"));
    let built = build(&imported.scene.to_string());
    let shape = &built.scene.objects[0].shape;
    assert!(built.scene.objects[0].dpdu_frame);
    let hits = table["hits"].as_array().unwrap();
    assert_eq!(hits.len(), 12);
    for (i, hit) in hits.iter().enumerate() {
        let ray = Ray::new(v3(&hit["origin"]), v3(&hit["direction"]));
        let h = shape.hit_t(&ray, ray.d.recip(), 0.0, 10.0).unwrap_or_else(|| panic!("hit {i}: no hit"));
        let s = shape.surface_at(&ray, &h);
        let (uv, dpdu) = (shape.uv(&s, &h, 0.0), shape.dpdu(&s, &h, 0.0));
        let (p, n, duv) = (v3(&hit["p"]), v3(&hit["n"]), v3(&hit["dp_du"]));
        let muv = hit["uv"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect::<Vec<_>>();
        assert!((s.p - p).length() < 1e-5, "hit {i}: p {} vs Mitsuba's {p}", s.p);
        assert!((s.n - n).length() < 1e-5, "hit {i}: n {} vs Mitsuba's {n}", s.n);
        assert!((uv - Vec2::new(muv[0], muv[1])).length() < 1e-5, "hit {i}: uv {uv} vs Mitsuba's {muv:?}");
        assert!((dpdu - duv).length() < 1e-4 * duv.length(), "hit {i}: dp/du {dpdu} vs Mitsuba's {duv}");
        check("Mitsuba cube", shape, s.p, s.n, 1e-3);
    }
}

/// A triangle without uvs, as is and with `flip_normals`, at the hit
/// Mitsuba 3.9.1 recorded (crates/niebla/tests/data/mitsuba_cube.json,
/// `bare_hits`): Mitsuba keeps the triangle's corner order when it flips the
/// normal, so its uv stays the barycentric `(b1, b2)` and its dp/du stays
/// `p1 - p0`; niebla, which swaps corners 1 and 2 to flip, gives the same
/// uv and dp/du (within f32 rounding, 1e-5) and the flipped normal.
#[test]
fn mesh_without_uvs_has_mitsubas_uv_and_dpdu_also_flipped() {
    let table: serde_json::Value =
        serde_json::from_str(include_str!("data/mitsuba_cube.json")).expect("the cube table");
    let v3 = |v: &serde_json::Value| {
        let a: Vec<f32> = v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
        Vec3::new(a[0], a[1], a[2])
    };
    for hit in table["bare_hits"].as_array().unwrap() {
        let flip = hit["flip_normals"].as_bool().unwrap();
        let built = build(&scene_json(&format!(
            r#"{{"type": "mesh", "positions": {}, "indices": [[0, 1, 2]], "flip_normals": {flip},
                "tangent_frame": "dpdu", "bsdf": {{"type": "roughconductor", "alpha_u": 0.05, "alpha_v": 0.4}}}}"#,
            table["bare_triangle"]
        )));
        let shape = &built.scene.objects[0].shape;
        let ray = Ray::new(v3(&hit["origin"]), v3(&hit["direction"]));
        let h = shape.hit_t(&ray, ray.d.recip(), 0.0, 10.0).expect("hit");
        let s = shape.surface_at(&ray, &h);
        let (uv, dpdu) = (shape.uv(&s, &h, 0.0), shape.dpdu(&s, &h, 0.0));
        let muv = v3(&serde_json::json!([hit["uv"][0], hit["uv"][1], 0.0]));
        assert!((s.n - v3(&hit["n"])).length() < 1e-5, "flip {flip}: n {} vs Mitsuba's {}", s.n, hit["n"]);
        assert!((uv - Vec2::new(muv.x, muv.y)).length() < 1e-5, "flip {flip}: uv {uv} vs Mitsuba's {}", hit["uv"]);
        assert!((dpdu - v3(&hit["dp_du"])).length() < 1e-5, "flip {flip}: dp/du {dpdu} vs Mitsuba's {}", hit["dp_du"]);
    }
}

/// Spheres turned by their `to_world` (a uniform scale, a rotation about a
/// unit axis and a translation; two rotations and a translation), imported
/// from the XML Mitsuba 3.9.1 read (crates/niebla/tests/data/mitsuba_sphere.json,
/// written by `scripts/mitsuba_refs.py --sphere`) with an anisotropic
/// surface: at 8 hits spread over each sphere (away from the poles and the
/// seam), niebla's hit point and normal are Mitsuba's within 1e-5 (f32
/// rounding of points of size ~1), its uv within 1e-5 (f32 rounding of an
/// atan2 and an acos of unit-size arguments, ~1e-7) and its dp/du within
/// 1e-4 of |dp/du| (Mitsuba turns a local tangent by its f32 to_world,
/// niebla by the f32 rotation the importer wrote: both within a few ulps);
/// and dp/du is the finite difference of niebla's own uvs (see `check`).
#[test]
fn turned_spheres_have_mitsubas_uv_and_dpdu() {
    let table: serde_json::Value =
        serde_json::from_str(include_str!("data/mitsuba_sphere.json")).expect("the sphere table");
    let v3 = |v: &serde_json::Value| {
        let a: Vec<f32> = v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
        Vec3::new(a[0], a[1], a[2])
    };
    let spheres = table["spheres"].as_array().unwrap();
    assert_eq!(spheres.len(), 2);
    // Largest differences seen: uv (absolute), dp/du (relative).
    let (mut worst_uv, mut worst_dpdu) = (0.0f32, 0.0f32);
    for (k, sphere) in spheres.iter().enumerate() {
        let shape_xml = sphere["xml"].as_str().unwrap().replace(
            "</shape>",
            r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.4"/></bsdf></shape>"#,
        );
        let xml = format!(
            r#"<scene version="3.0.0">
                 <sensor type="perspective"><float name="fov" value="40"/><transform name="to_world"><lookat origin="0, 0, 6" target="0, 0, 0" up="0, 1, 0"/></transform>
                   <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
                 {shape_xml}
               </scene>"#
        );
        let imported = niebla::scene::mitsuba::import_mitsuba_str(&xml, "sphere.xml", std::path::Path::new("."), &[])
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(imported.scene["shapes"][0].get("rotation").is_some(), "{}", imported.scene);
        let built = build(&imported.scene.to_string());
        let shape = &built.scene.objects[0].shape;
        assert!(built.scene.objects[0].dpdu_frame);
        let hits = sphere["hits"].as_array().unwrap();
        assert_eq!(hits.len(), 8);
        for (i, hit) in hits.iter().enumerate() {
            let ray = Ray::new(v3(&hit["origin"]), v3(&hit["direction"]));
            let h = shape.hit_t(&ray, ray.d.recip(), 0.0, 10.0).unwrap_or_else(|| panic!("sphere {k} hit {i}: no hit"));
            let s = shape.surface_at(&ray, &h);
            let (uv, dpdu) = (shape.uv(&s, &h, 0.0), shape.dpdu(&s, &h, 0.0));
            let (p, n, duv) = (v3(&hit["p"]), v3(&hit["n"]), v3(&hit["dp_du"]));
            let muv = Vec2::new(hit["uv"][0].as_f64().unwrap() as f32, hit["uv"][1].as_f64().unwrap() as f32);
            assert!((s.p - p).length() < 1e-5, "sphere {k} hit {i}: p {} vs Mitsuba's {p}", s.p);
            assert!((s.n - n).length() < 1e-5, "sphere {k} hit {i}: n {} vs Mitsuba's {n}", s.n);
            worst_uv = worst_uv.max((uv - muv).abs().max_element());
            worst_dpdu = worst_dpdu.max((dpdu - duv).length() / duv.length());
            assert!((uv - muv).abs().max_element() < 1e-5, "sphere {k} hit {i}: uv {uv} vs Mitsuba's {muv}");
            assert!((dpdu - duv).length() < 1e-4 * duv.length(), "sphere {k} hit {i}: dp/du {dpdu} vs Mitsuba's {duv}");
            check("turned sphere", shape, s.p, s.n, 2e-3);
        }
    }
    println!("turned spheres: largest uv difference {worst_uv:e}, largest relative dp/du difference {worst_dpdu:e}");
}
