//! Triangle meshes: the hierarchy against a loop over every triangle,
//! watertightness on closed meshes, meshes bounding media against the
//! analytic box, the white furnace in a closed mesh, one mesh from every
//! file format giving bit-identical images, and bad input.

use std::path::{Path, PathBuf};

use niebla::film::Image;
use niebla::geometry::triangle::{intersect_triangle, WatertightRay};
use niebla::geometry::{PrimitiveHit, TriangleMesh};
use niebla::math::{Ray, Vec2, Vec3};
use niebla::render::{render, RenderOptions};
use niebla::sampling::PixelSampler;
use niebla::scene::{build_scene, parse_scene_str, BuiltScene};
use niebla_mesh::MeshData;

fn mesh_of(data: &MeshData) -> TriangleMesh {
    TriangleMesh::new(
        data.positions.iter().map(|&p| Vec3::from(p)).collect(),
        data.indices.clone(),
        data.normals.as_ref().map(|n| n.iter().map(|&v| Vec3::from(v)).collect()),
        data.uvs.as_ref().map(|u| u.iter().map(|&v| Vec2::from(v)).collect()),
    )
    .unwrap()
}

/// Nearest hit by testing every triangle in order (the first of equal `t` wins).
fn brute_force(mesh: &TriangleMesh, ray: &Ray) -> Option<PrimitiveHit> {
    let w = WatertightRay::new(ray);
    let mut best: Option<PrimitiveHit> = None;
    for prim in 0..mesh.triangle_count() as u32 {
        let [a, b, c] = mesh.corners(prim);
        let t_max = best.map_or(f32::INFINITY, |h| h.t);
        if let Some(h) = intersect_triangle(&w, a, b, c, 0.0, t_max) {
            best = Some(PrimitiveHit { t: h.t, prim, b1: h.b1, b2: h.b2 });
        }
    }
    best
}

fn random_ray(s: &mut PixelSampler, lo: Vec3, hi: Vec3) -> Ray {
    let size = hi - lo;
    let o = lo - 0.25 * size + Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 1.5 * size;
    let d = loop {
        let v = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 2.0 - Vec3::ONE;
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            break v.normalize();
        }
    };
    Ray::new(o, d)
}

/// A mesh shipped with niebla-mesh's tests (from Debian's assimp-testmodels,
/// BSD-3-Clause; see its LICENSE.md).
fn real_mesh_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../niebla-mesh/tests/data").join(name)
}

/// 10^5 random rays on a random soup, a closed sphere and a real mesh
/// (assimp's Wuson, 3,732 triangles): the hierarchy
/// finds the same nearest hit as the loop (parameter, triangle and
/// barycentrics bit for bit; a different triangle only at exactly the same
/// parameter, a tie on a shared edge), and any-hit agrees with closest-hit.
#[test]
fn hierarchy_hits_equal_a_loop_over_all_triangles() {
    let real = niebla_mesh::read_obj(real_mesh_path("wuson.obj"), None).unwrap();
    for (label, data) in [
        ("soup", niebla_mesh::random_soup(2000, 7)),
        ("icosphere", niebla_mesh::icosphere(3, 1.0)),
        ("wuson (real, open)", real),
    ] {
        let mesh = mesh_of(&data);
        let b = mesh.bounds().unwrap();
        let mut s = PixelSampler::from_key(42);
        let (mut hits, mut ties) = (0, 0);
        for _ in 0..100_000 {
            let ray = random_ray(&mut s, b.min, b.max);
            let fast = mesh.intersect(&ray, 0.0, f32::INFINITY);
            let slow = brute_force(&mesh, &ray);
            match (fast, slow) {
                (None, None) => {}
                (Some(f), Some(g)) => {
                    hits += 1;
                    assert_eq!(f.t, g.t, "{label}: {ray:?}");
                    if f.prim == g.prim {
                        assert_eq!((f.b1, f.b2), (g.b1, g.b2), "{label}: {ray:?}");
                    } else {
                        ties += 1;
                    }
                }
                _ => panic!("{label}: hierarchy {fast:?}, loop {slow:?} for {ray:?}"),
            }
            assert_eq!(mesh.occluded(&ray, 0.0, f32::INFINITY), slow.is_some(), "{label}: {ray:?}");
        }
        assert!(hits > 10_000, "{label}: only {hits} rays hit");
        assert!(ties < 10, "{label}: {ties} ties");
    }
}

/// Rays aimed exactly at the vertices and at points of the edges of a closed
/// mesh from outside, entering it there (from directions at least 17
/// degrees above the tangent plane, so that rounding of the direction cannot
/// make them pass beside the silhouette), must hit it no farther than their
/// target: a ray that slips through a shared edge or vertex would first hit
/// the far side. 10^6 rays (10^7 with NIEBLA_SLOW_TESTS), on an icosphere,
/// on the same sphere rotated and stretched by an instance transform, and on
/// a closed real mesh (a cylinder exported by Blender, from assimp's test
/// models).
#[test]
fn no_ray_slips_through_the_edges_and_vertices_of_a_closed_mesh() {
    let rays: u32 = if std::env::var_os("NIEBLA_SLOW_TESTS").is_some() { 10_000_000 } else { 1_000_000 };
    let cylinder = niebla_mesh::read_obj(real_mesh_path("blender_cylinder.obj"), None).unwrap();
    for (label, data) in [("icosphere", niebla_mesh::icosphere(4, 1.0)), ("cylinder", cylinder)] {
        assert!(data.closedness().is_closed(), "{label}");
        slips_through(label, &data, rays);
    }
}

fn slips_through(name: &str, data: &MeshData, rays: u32) {
    let mesh = std::sync::Arc::new(mesh_of(data));
    // The unit normals of the faces around each vertex, vertices welded by
    // position (files split vertices at seams and creases).
    let welded = data.welded_ids();
    let mut around = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|k| mesh.positions[k as usize]);
        let n = (b - a).cross(c - a).normalize();
        for &k in t {
            around[welded[k as usize] as usize].push(n);
        }
    }
    let stretch = glam::Affine3A::from_scale_rotation_translation(
        Vec3::new(1.5, 0.7, 1.1),
        glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 0.7),
        Vec3::new(0.2, -0.4, 3.0),
    );
    for (label, transform) in [
        (name.to_string(), niebla::geometry::Transform::IDENTITY),
        (format!("transformed {name}"), niebla::geometry::Transform::new(stretch).unwrap()),
    ] {
        let instance = niebla::geometry::MeshInstance::new(mesh.clone(), transform, true);
        let mut s = PixelSampler::from_key(5);
        let (mut slipped, mut traced) = (0u64, 0u64);
        for i in 0..rays {
            let tri = mesh.triangles[(i as usize / 4) % mesh.triangle_count()];
            let [a, b, c] = tri.map(|k| mesh.positions[k as usize]);
            let [ka, kb, kc] = tri.map(|k| welded[k as usize] as usize);
            // A vertex, or a point of an edge (an exact float on the segment).
            let u = s.next_1d();
            let (target_local, ends) = match i % 4 {
                0 => (a, [ka, ka]),
                1 => (a + (b - a) * u, [ka, kb]),
                2 => (b + (c - b) * u, [kb, kc]),
                _ => (c + (a - c) * u, [kc, ka]),
            };
            // A direction from outside above every face around the target
            // (so the ray enters the solid there; not a line that only
            // touches a convex corner).
            let faces: Vec<Vec3> = ends.iter().flat_map(|&k| around[k].iter().copied()).collect();
            let away = (0..64).find_map(|_| {
                let v = (Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 2.0 - Vec3::ONE).normalize_or(Vec3::X);
                faces.iter().all(|n| v.dot(*n) > 0.2).then_some(v)
            });
            let Some(away) = away else { continue };
            traced += 1;
            let target = transform.point_to_world(target_local);
            let from = transform.point_to_world(target_local + away * 3.0);
            let dist = (target - from).length();
            let ray = Ray::new(from, (target - from) / dist);
            let hit = instance.hit(&ray, 0.0, f32::INFINITY);
            if hit.is_none_or(|h| h.t > dist * (1.0 + 1e-5)) {
                slipped += 1;
            }
        }
        println!("{label}: {traced} rays at vertices and edges, {slipped} slipped through");
        assert!(traced as f64 > 0.9 * rays as f64, "{label}: only {traced} of {rays} rays found a direction");
        assert_eq!(slipped, 0, "{label}");
    }
}

fn build(text: &str, dir: &Path) -> BuiltScene {
    let desc = parse_scene_str(text, "mesh-test.json").unwrap_or_else(|e| panic!("{e}\n{text}"));
    build_scene(&desc, "mesh-test.json", dir).unwrap_or_else(|e| panic!("{e}"))
}

fn render_scene(built: &BuiltScene, spp: u32, seed: u64) -> Image {
    let options = RenderOptions { spp, seed, first_sample: 0, threads: None, sampler: Default::default() };
    render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap()
}

fn json_array<T: std::fmt::Debug>(items: &[T]) -> String {
    let body: Vec<String> = items.iter().map(|v| format!("{v:?}")).collect();
    format!("[{}]", body.join(", "))
}

/// The axis-aligned box `[lo, hi]` as 12 outward-wound triangles (inline JSON
/// `positions` and `indices`).
fn box_mesh_json(lo: [f32; 3], hi: [f32; 3]) -> String {
    let mut positions = Vec::new();
    for k in 0..8 {
        positions.push([
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        ]);
    }
    let indices: [[u32; 3]; 12] = [
        [0, 2, 3],
        [0, 3, 1], // z = lo (normal -z)
        [4, 5, 7],
        [4, 7, 6], // z = hi
        [0, 1, 5],
        [0, 5, 4], // y = lo
        [2, 6, 7],
        [2, 7, 3], // y = hi
        [0, 4, 6],
        [0, 6, 2], // x = lo
        [1, 3, 7],
        [1, 7, 5], // x = hi
    ];
    format!(r#""type": "mesh", "positions": {}, "indices": {}"#, json_array(&positions), json_array(&indices))
}

fn fog_scene(shape: &str, integrator: &str) -> String {
    format!(
        r#"{{"version": 1,
          "camera": {{"type": "perspective", "position": [0.3, 0.6, 4], "target": [0, 0, 0], "fov_y": 40,
                     "width": 16, "height": 16}},
          "render": {{"integrator": {integrator}}},
          "media": {{"fog": {{"type": "homogeneous", "sigma_t": 1.5, "albedo": 0.8, "phase": {{"type": "hg", "g": 0.4}}}}}},
          "shapes": [
            {{{shape}, "interior": "fog"}},
            {{"type": "rectangle", "to_world": {{"scale": 3, "rotate_x": -90, "translate": [0, -1.01, 0]}},
              "bsdf": {{"type": "diffuse", "reflectance": 0.6}}}}
          ],
          "lights": [{{"type": "point", "position": [0.5, 2.5, 1], "intensity": 6}},
                     {{"type": "constant", "radiance": 0.1}}]}}"#
    )
}

/// Per-pixel means and standard errors of `batches` renders with seeds 1, 2, ...
fn batch_stats(built: &BuiltScene, spp: u32, batches: u64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let images: Vec<Image> = (1..=batches).map(|seed| render_scene(built, spp, seed)).collect();
    let n = batches as f64;
    let pixels = images[0].pixels.len();
    let mut mean = vec![[0.0; 3]; pixels];
    let mut se = vec![[0.0; 3]; pixels];
    for i in 0..pixels {
        for c in 0..3 {
            let m = images.iter().map(|im| im.pixels[i][c] as f64).sum::<f64>() / n;
            let v = images.iter().map(|im| (im.pixels[i][c] as f64 - m).powi(2)).sum::<f64>() / (n - 1.0);
            mean[i][c] = m;
            se[i][c] = (v / n).sqrt();
        }
    }
    (mean, se)
}

/// Fog inside a 12-triangle mesh box equals fog inside `"type": "box"`,
/// pixel by pixel within 4 combined standard errors (8 batches each, the
/// same seeds for both, so the renders differ only where the two
/// intersection routines do), for volpath and for single scattering.
#[test]
fn a_box_medium_bounded_by_a_mesh_equals_the_box_shape() {
    let (lo, hi) = ([-1.0, -1.0, -1.0], [1.0, 0.8, 0.6]);
    let boxed = format!(r#""type": "box", "min": {lo:?}, "max": {hi:?}"#);
    let meshed = box_mesh_json(lo, hi);
    for integrator in [r#"{"type": "volpath"}"#, r#"{"type": "single", "sampling": "mis"}"#] {
        let a = build(&fog_scene(&boxed, integrator), Path::new("."));
        let b = build(&fog_scene(&meshed, integrator), Path::new("."));
        let (ma, sa) = batch_stats(&a, 16, 8);
        let (mb, sb) = batch_stats(&b, 16, 8);
        let (mut sum_a, mut sum_b) = (0.0, 0.0);
        for i in 0..ma.len() {
            for c in 0..3 {
                let se = (sa[i][c].powi(2) + sb[i][c].powi(2)).sqrt();
                let d = (ma[i][c] - mb[i][c]).abs();
                assert!(
                    d <= 4.0 * se + 1e-6,
                    "{integrator} pixel {i} channel {c}: box {} mesh {} (se {se})",
                    ma[i][c],
                    mb[i][c]
                );
                sum_a += ma[i][c];
                sum_b += mb[i][c];
            }
        }
        assert!(sum_a > 0.0 && (sum_a - sum_b).abs() < 1e-3 * sum_a, "{integrator}: means {sum_a} vs {sum_b}");
    }
}

/// A white furnace: a closed mesh (an icosphere, and the same mesh rotated
/// and stretched) filled with a non-absorbing medium in a uniform
/// environment of radiance 0.7 looks exactly like the environment: every
/// path carries weight 1 and escapes, so every pixel is 0.7 to float
/// rounding, whatever the noise.
#[test]
fn white_furnace_inside_a_closed_mesh() {
    let sphere = niebla_mesh::icosphere(3, 1.0);
    let mesh = format!(
        r#""type": "mesh", "positions": {}, "indices": {}"#,
        json_array(&sphere.positions),
        json_array(&sphere.indices)
    );
    for transform in ["{}", r#"{"scale": [1.4, 0.6, 1.0], "rotate_y": 30, "translate": [0.1, 0, 0]}"#] {
        let text = format!(
            r#"{{"version": 1,
              "camera": {{"type": "perspective", "position": [0, 0, 4], "target": [0, 0, 0], "fov_y": 40,
                         "width": 12, "height": 12}},
              "render": {{"integrator": {{"type": "volpath", "max_depth": 100000}}}},
              "media": {{"white": {{"type": "homogeneous", "sigma_a": 0, "sigma_s": 3, "phase": {{"type": "hg", "g": 0.3}}}}}},
              "shapes": [{{{mesh}, "to_world": {transform}, "interior": "white"}}],
              "lights": [{{"type": "constant", "radiance": 0.7}}]}}"#
        );
        let image = render_scene(&build(&text, Path::new(".")), 16, 3);
        for (i, p) in image.pixels.iter().enumerate() {
            for c in 0..3 {
                assert!((p[c] - 0.7).abs() < 1e-4, "{transform}: pixel {i} channel {c} = {}", p[c]);
            }
        }
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("niebla-meshes-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The same mesh (smooth normals and uvs) read from OBJ, binary PLY (both
/// byte orders), ASCII PLY and inline arrays renders bit-identical images:
/// the readers reproduce the numbers exactly and the vertex numbering does
/// not change the hierarchy.
#[test]
fn one_mesh_from_every_format_renders_identically() {
    let mut data = niebla_mesh::icosphere(2, 0.9);
    data.normals = Some(data.positions.iter().map(|p| Vec3::from(*p).normalize().to_array()).collect());
    data.uvs = Some(data.positions.iter().map(|p| [0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1]]).collect());
    let dir = temp_dir("formats");
    niebla_mesh::write_obj(dir.join("m.obj"), &data).unwrap();
    niebla_mesh::write_ply_ascii(dir.join("m_ascii.ply"), &data).unwrap();
    niebla_mesh::write_ply_binary(dir.join("m_le.ply"), &data, niebla_mesh::ByteOrder::LittleEndian).unwrap();
    niebla_mesh::write_ply_binary(dir.join("m_be.ply"), &data, niebla_mesh::ByteOrder::BigEndian).unwrap();
    let inline = format!(
        r#""type": "mesh", "positions": {}, "indices": {}, "normals": {}, "uvs": {}"#,
        json_array(&data.positions),
        json_array(&data.indices),
        json_array(data.normals.as_ref().unwrap()),
        json_array(data.uvs.as_ref().unwrap())
    );
    let scene = |shape: &str| {
        format!(
            r#"{{"version": 1,
              "camera": {{"type": "perspective", "position": [0.5, 1, 3], "target": [0, 0, 0], "fov_y": 40,
                         "width": 24, "height": 24}},
              "render": {{"integrator": {{"type": "volpath"}}}},
              "media": {{"milk": {{"type": "homogeneous", "sigma_t": [4, 5, 6], "albedo": 0.95}}}},
              "shapes": [{{{shape}, "interior": "milk", "bsdf": {{"type": "dielectric", "int_ior": 1.33}}}},
                         {{{shape}, "to_world": {{"translate": [1.5, 0, -1]}}, "bsdf": {{"type": "diffuse"}}}}],
              "lights": [{{"type": "point", "position": [1, 3, 2], "intensity": 10}},
                         {{"type": "constant", "radiance": 0.2}}]}}"#
        )
    };
    let reference = render_scene(&build(&scene(&inline), &dir), 4, 9);
    for file in ["m.obj", "m_ascii.ply", "m_le.ply", "m_be.ply"] {
        let image = render_scene(&build(&scene(&format!(r#""type": "mesh", "file": "{file}""#)), &dir), 4, 9);
        assert!(image.pixels == reference.pixels, "{file} renders differently from the inline arrays");
    }
    std::fs::remove_dir_all(&dir).ok();
}

fn build_error(text: &str, dir: &Path) -> String {
    let desc = match parse_scene_str(text, "bad.json") {
        Ok(d) => d,
        Err(e) => return e.to_string(),
    };
    match build_scene(&desc, "bad.json", dir) {
        Ok(_) => panic!("expected an error for {text}"),
        Err(e) => e.to_string(),
    }
}

/// Bad meshes are errors naming the scene file, the JSON path, the mesh
/// file and what is wrong.
#[test]
fn bad_meshes_are_errors_naming_file_and_fault() {
    let dir = temp_dir("errors");
    let sphere = niebla_mesh::icosphere(1, 1.0);
    let ply = niebla_mesh::ply_binary_bytes(&sphere, niebla_mesh::ByteOrder::LittleEndian);
    std::fs::write(dir.join("truncated.ply"), &ply[..ply.len() - 20]).unwrap();
    let ascii = String::from_utf8_lossy(&niebla_mesh::ply_ascii_bytes(&sphere)).into_owned();
    assert!(ascii.contains("element vertex 42\n"));
    // A count that the memory estimate accepts but the bytes cannot hold, and
    // one too large for the memory limit.
    std::fs::write(dir.join("lying.ply"), ascii.replace("element vertex 42\n", "element vertex 4200000\n")).unwrap();
    std::fs::write(dir.join("huge.ply"), ascii.replace("element vertex 42\n", "element vertex 4200000000\n")).unwrap();
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
    let mut open = sphere.clone();
    open.indices.pop();
    niebla_mesh::write_ply_binary(dir.join("open.ply"), &open, niebla_mesh::ByteOrder::LittleEndian).unwrap();
    let scene = |shape: &str| {
        format!(
            r#"{{"version": 1,
              "camera": {{"type": "perspective", "position": [0, 0, 4], "target": [0, 0, 0], "width": 4, "height": 4}},
              "media": {{"fog": {{"type": "homogeneous", "sigma_t": 1, "albedo": 0.5}}}},
              "shapes": [{shape}]}}"#
        )
    };
    let cases: &[(&str, &str, &[&str])] = &[
        ("missing file", r#"{"type": "mesh", "file": "nowhere.ply"}"#, &["shapes[0].file", "nowhere.ply"]),
        ("truncated PLY", r#"{"type": "mesh", "file": "truncated.ply"}"#, &["shapes[0].file", "truncated.ply"]),
        ("lying counts", r#"{"type": "mesh", "file": "lying.ply"}"#, &["shapes[0].file", "lying.ply", "4200000"]),
        (
            "counts over the memory limit",
            r#"{"type": "mesh", "file": "huge.ply"}"#,
            &["shapes[0].file", "huge.ply", "memory limit"],
        ),
        ("OBJ index out of range", r#"{"type": "mesh", "file": "bad.obj"}"#, &["shapes[0].file", "bad.obj", "line 4"]),
        ("unknown extension", r#"{"type": "mesh", "file": "mesh.stl"}"#, &["shapes[0].file", "stl"]),
        (
            "inline index out of range",
            r#"{"type": "mesh", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2],[0,1,3]]}"#,
            &["shapes[0].indices[1][2]", "out of range"],
        ),
        (
            "inline NaN-like vertex",
            r#"{"type": "mesh", "positions": [[0,0,0],[1,0,0],[0,1,1e39]], "indices": [[0,1,2]]}"#,
            &["shapes[0]", "positions[2][2]"],
        ),
        (
            "open mesh bounding a medium",
            r#"{"type": "mesh", "file": "open.ply", "interior": "fog"}"#,
            &["shapes[0]", "3 open (boundary) edges", "allow_open"],
        ),
        ("neither file nor arrays", r#"{"type": "mesh"}"#, &["shapes[0]", "needs `file`"]),
        (
            "file and arrays",
            r#"{"type": "mesh", "file": "a.ply", "positions": [[0,0,0]], "indices": [[0,0,0]]}"#,
            &["shapes[0].file", "not both"],
        ),
        (
            "all degenerate",
            r#"{"type": "mesh", "positions": [[0,0,0],[1,0,0],[2,0,0]], "indices": [[0,1,2]]}"#,
            &["shapes[0]", "degenerate"],
        ),
    ];
    for (label, shape, expected) in cases {
        let message = build_error(&scene(shape), &dir);
        assert!(message.contains("bad.json"), "{label}: {message}");
        for part in *expected {
            assert!(message.contains(part), "{label}: {message:?} lacks {part:?}");
        }
    }
    // allow_open lets the open mesh bound the medium.
    let ok = scene(r#"{"type": "mesh", "file": "open.ply", "interior": "fog", "allow_open": true}"#);
    build(&ok, &dir);
    std::fs::remove_dir_all(&dir).ok();
}

/// A finely tessellated sphere (an icosphere of 20480 triangles with its
/// exact vertex normals) renders like the analytic sphere: diffuse, glass
/// holding a chromatic medium, and an index-matched boundary of fog. The
/// image means agree within 4 combined standard errors (6 batches each, the
/// same seeds) plus the tessellation's own effect: the faces lie inside the
/// sphere by a mean radial deficit `eps = 1 - (V_mesh / V_sphere)^(1/3)`,
/// which changes the projected area and the optical depths by about
/// `2 eps`; 3 eps of the mean is allowed for it.
#[test]
fn a_tessellated_sphere_renders_like_the_analytic_sphere() {
    let mut data = niebla_mesh::icosphere(5, 1.0);
    data.normals = Some(data.positions.iter().map(|p| Vec3::from(*p).normalize().to_array()).collect());
    let mesh = mesh_of(&data);
    let eps = 1.0 - (mesh.volume() as f64 / (4.0 / 3.0 * std::f64::consts::PI)).cbrt();
    assert!(eps > 0.0 && eps < 1e-3, "radial deficit {eps}");
    let dir = temp_dir("tessellated");
    niebla_mesh::write_ply_binary(dir.join("sphere.ply"), &data, niebla_mesh::ByteOrder::LittleEndian).unwrap();
    let cases = [
        ("diffuse", r#""bsdf": {"type": "diffuse", "reflectance": [0.7, 0.5, 0.3]}"#),
        ("glass of milk", r#""bsdf": {"type": "dielectric", "int_ior": 1.4}, "interior": "milk""#),
        ("fog boundary", r#""interior": "fog""#),
    ];
    for (label, surface) in cases {
        let scene = |shape: &str| {
            format!(
                r#"{{"version": 1,
                  "camera": {{"type": "perspective", "position": [0.4, 0.8, 4], "target": [0, 0, 0], "fov_y": 38,
                             "width": 24, "height": 24}},
                  "render": {{"integrator": {{"type": "volpath"}}}},
                  "media": {{"milk": {{"type": "homogeneous", "sigma_t": [3, 4, 6], "albedo": 0.97}},
                            "fog": {{"type": "homogeneous", "sigma_t": 1.2, "albedo": 0.9, "phase": {{"type": "hg", "g": 0.5}}}}}},
                  "shapes": [{{{shape}, {surface}}},
                             {{"type": "rectangle", "to_world": {{"scale": 4, "rotate_x": -90, "translate": [0, -1.05, 0]}},
                               "bsdf": {{"type": "diffuse", "reflectance": 0.5}}}}],
                  "lights": [{{"type": "point", "position": [1.5, 3, 2], "intensity": 12}},
                             {{"type": "constant", "radiance": 0.15}}]}}"#
            )
        };
        let analytic = build(&scene(r#""type": "sphere", "center": [0, 0, 0], "radius": 1"#), &dir);
        let meshed = build(&scene(r#""type": "mesh", "file": "sphere.ply""#), &dir);
        let (ma, sa) = batch_stats(&analytic, 16, 6);
        let (mb, sb) = batch_stats(&meshed, 16, 6);
        let n = ma.len() as f64;
        for c in 0..3 {
            let mean_a = ma.iter().map(|p| p[c]).sum::<f64>() / n;
            let mean_b = mb.iter().map(|p| p[c]).sum::<f64>() / n;
            // Standard error of the image mean from the per-pixel ones
            // (pixels are independent).
            let se_a = (sa.iter().map(|p| p[c] * p[c]).sum::<f64>()).sqrt() / n;
            let se_b = (sb.iter().map(|p| p[c] * p[c]).sum::<f64>()).sqrt() / n;
            let tolerance = 4.0 * (se_a * se_a + se_b * se_b).sqrt() + 3.0 * eps * mean_a;
            println!("{label} channel {c}: sphere {mean_a:.5}, mesh {mean_b:.5}, tolerance {tolerance:.2e}");
            assert!(
                (mean_a - mean_b).abs() <= tolerance,
                "{label} channel {c}: {mean_a} vs {mean_b} (tol {tolerance})"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
