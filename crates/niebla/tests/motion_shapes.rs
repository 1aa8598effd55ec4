//! Motion blur of shapes and area lights given a second pose by `motion`.
//!
//! A shape's pose is linear (or slerped) in time, so a blurred render is the
//! time average over the shutter of still renders. Each test compares a
//! blurred render against the mean of `SUB_TIMES` still renders whose poses
//! are written by hand (independently of the interpolation code) at the
//! midpoints of equal sub-intervals of the shutter, strip by strip, within
//! 4 standard errors estimated from 16 independent batches. The midpoint
//! rule's own error is O(h^2) with h = 1/16 for a strip value that is a
//! continuous, piecewise smooth function of time (a kink where an edge
//! enters or leaves a strip adds O(h^2 |jump of the slope|) too), about
//! `h^2 max|f''| / 24`: with strips changing by up to about 0.25 within a
//! tenth of a frame (the light tests) that is of order 1e-4 to 1e-3, as
//! large as some standard errors printed, so a bias of that size would go
//! unnoticed; the tests catch gross errors of timing, not subtle ones. Sampling a moving light at time 0
//! instead of the sample's time fails these tests by 30 to 190 SE.

use niebla::film::Image;
use niebla::render::{render, RenderOptions};
use niebla::scene::{build_scene, parse_scene_str, BuiltScene, SceneError};

const FILE: &str = "moving_shapes.json";
const BATCHES: u64 = 16;
const SPP: u32 = 16;
const SUB_TIMES: usize = 16;

fn try_build(body: &str) -> Result<BuiltScene, SceneError> {
    let desc = parse_scene_str(&format!("{{\"version\": 1, {body}}}"), FILE)?;
    build_scene(&desc, FILE, std::path::Path::new("."))
}

fn build(body: &str) -> BuiltScene {
    try_build(body).unwrap_or_else(|e| panic!("{e}"))
}

fn render_batch(built: &BuiltScene, spp: u32, batch: u64) -> Image {
    let options =
        RenderOptions { spp, seed: 5, first_sample: batch * spp as u64, threads: None, sampler: Default::default() };
    render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap()
}

/// Mean of the red channel over four column strips.
fn strips(image: &Image) -> [f64; 4] {
    let mut s = [0.0; 4];
    let w = image.width / 4;
    for y in 0..image.height {
        for x in 0..image.width {
            s[(x / w) as usize] += image.get(x, y).0[0] as f64 / (w * image.height) as f64;
        }
    }
    s
}

fn mean_and_se(batches: &[[f64; 4]]) -> [(f64, f64); 4] {
    let k = batches.len() as f64;
    std::array::from_fn(|i| {
        let mean = batches.iter().map(|b| b[i]).sum::<f64>() / k;
        let var = batches.iter().map(|b| (b[i] - mean).powi(2)).sum::<f64>() / (k - 1.0);
        (mean, (var / k).sqrt())
    })
}

/// Midpoints of `SUB_TIMES` equal parts of the shutter [0, 1].
fn sub_times() -> Vec<f32> {
    (0..SUB_TIMES).map(|i| (i as f32 + 0.5) / SUB_TIMES as f32).collect()
}

/// The blurred scene's strips (16 batches) against the average of the still
/// scenes `still(t)` at the sub-times (16 batches each): within 4 SE on
/// every strip, and visibly different (over 8 SE on some strip) from the
/// still scene at time 0.
fn assert_blur_matches(blurred: &BuiltScene, still: impl Fn(f32) -> BuiltScene, what: &str) {
    let b: Vec<[f64; 4]> = (0..BATCHES).map(|k| strips(&render_batch(blurred, SPP, k))).collect();
    let statics: Vec<BuiltScene> = sub_times().into_iter().map(&still).collect();
    let a: Vec<[f64; 4]> = (0..BATCHES)
        .map(|k| {
            let mut sum = [0.0; 4];
            for s in &statics {
                let v = strips(&render_batch(s, SPP, k));
                for i in 0..4 {
                    sum[i] += v[i] / SUB_TIMES as f64;
                }
            }
            sum
        })
        .collect();
    let at_zero = strips(&render_batch(&still(0.0), SPP * 16, 0));
    let (b, a) = (mean_and_se(&b), mean_and_se(&a));
    let mut visible = false;
    for i in 0..4 {
        let se = (b[i].1.powi(2) + a[i].1.powi(2)).sqrt();
        let diff = (b[i].0 - a[i].0).abs();
        eprintln!(
            "{what}: strip {i}: blurred {:.5} +- {:.5}, average of stills {:.5} +- {:.5}, still at 0 {:.5}, \
             |diff| = {:.2} SE",
            b[i].0,
            b[i].1,
            a[i].0,
            a[i].1,
            at_zero[i],
            diff / se
        );
        assert!(diff < 4.0 * se, "{what}: strip {i}: blurred {} vs averaged {} (SE {se})", b[i].0, a[i].0);
        visible |= (b[i].0 - at_zero[i]).abs() > 8.0 * se;
    }
    assert!(visible, "{what}: the blurred image does not differ from the still one");
}

const SHUTTER: &str = r#", "shutter_open": 0, "shutter_close": 1"#;

/// A camera looking at the origin from +z over a grey diffuse scene under a
/// white sky.
fn sky_scene(camera_extra: &str, shapes: &str) -> String {
    format!(
        r#""camera": {{"type": "perspective", "position": [0, 0, 6], "target": [0, 0, 0], "fov_y": 30,
                       "width": 16, "height": 16 {camera_extra}}},
            "render": {{"integrator": {{"type": "volpath", "max_depth": 3}}, "spp": 16, "seed": 5}},
            "shapes": [{shapes}],
            "lights": [{{"type": "constant", "radiance": 1}}]"#
    )
}

const GREY: &str = r#""bsdf": {"type": "diffuse", "reflectance": 0.5}"#;

fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

#[test]
fn moving_sphere_and_box_equal_the_average_of_still_renders() {
    // The sphere slides +1 in x and grows from 0.35 to 0.5; the box slides
    // +0.8 in x and shrinks in y.
    let shapes = format!(
        r#"{{"type": "sphere", "center": [-0.6, 0.45, 0], "radius": 0.35, {GREY},
             "motion": {{"center": [0.4, 0.45, 0], "radius": 0.5}}}},
           {{"type": "box", "min": [-1, -1, -0.3], "max": [-0.3, -0.2, 0.3], {GREY},
             "motion": {{"min": [-0.2, -1, -0.3], "max": [0.5, -0.5, 0.3]}}}}"#
    );
    let blurred = build(&sky_scene(SHUTTER, &shapes));
    let still = |t: f32| {
        let shapes = format!(
            r#"{{"type": "sphere", "center": [{}, 0.45, 0], "radius": {}, {GREY}}},
               {{"type": "box", "min": [{}, -1, -0.3], "max": [{}, {}, 0.3], {GREY}}}"#,
            lerp(-0.6, 0.4, t),
            lerp(0.35, 0.5, t),
            lerp(-1.0, -0.2, t),
            lerp(-0.3, 0.5, t),
            lerp(-0.2, -0.5, t),
        );
        build(&sky_scene("", &shapes))
    };
    assert_blur_matches(&blurred, still, "sphere and box");
}

/// A cube mesh (inline, 12 triangles) tipped 30 degrees about x turns 90
/// degrees about z (the view axis) while sliding in x: the slerped rotation
/// equals `rotate_z = 90 t` applied after the fixed tilt.
#[test]
fn turning_mesh_equals_the_average_of_still_renders() {
    let cube = r#""positions": [[-1,-1,-1],[1,-1,-1],[1,1,-1],[-1,1,-1],[-1,-1,1],[1,-1,1],[1,1,1],[-1,1,1]],
        "indices": [[0,2,1],[0,3,2],[4,5,6],[4,6,7],[0,1,5],[0,5,4],[2,3,7],[2,7,6],[1,2,6],[1,6,5],[0,4,7],[0,7,3]]"#;
    let shapes = format!(
        r#"{{"type": "mesh", {cube}, {GREY},
             "to_world": {{"scale": [0.9, 0.3, 0.3], "rotate_x": 30, "translate": [-0.5, 0, 0]}},
             "motion": {{"to_world": {{"scale": [0.9, 0.3, 0.3], "rotate_x": 30, "rotate_z": 90,
                                       "translate": [0.5, 0, 0]}}}}}}"#
    );
    let blurred = build(&sky_scene(SHUTTER, &shapes));
    let still = |t: f32| {
        let shapes = format!(
            r#"{{"type": "mesh", {cube}, {GREY},
                 "to_world": {{"scale": [0.9, 0.3, 0.3], "rotate_x": 30, "rotate_z": {},
                               "translate": [{}, 0, 0]}}}}"#,
            90.0 * t,
            lerp(-0.5, 0.5, t)
        );
        build(&sky_scene("", &shapes))
    };
    assert_blur_matches(&blurred, still, "turning mesh");
}

/// A small one-sided rectangle light facing down slides 2 units in x over
/// a diffuse floor, with no other light: the floor's lighting (next-event
/// samples of the light and BSDF-sampled hits of it, combined by MIS) must
/// be the light's at each sample's time.
#[test]
fn moving_area_light_lights_the_floor_as_the_average_of_still_renders() {
    let scene = |light_to_world: &str, motion: &str, camera_extra: &str| {
        format!(
            r#""camera": {{"type": "perspective", "position": [0, 4, 4], "target": [0, 0, 0], "fov_y": 45,
                           "width": 16, "height": 16 {camera_extra}}},
                "render": {{"integrator": {{"type": "volpath", "max_depth": 2}}, "spp": 16, "seed": 5}},
                "shapes": [{{"type": "rectangle", "to_world": {{"scale": 3, "rotate_x": -90}},
                             "bsdf": {{"type": "diffuse", "reflectance": 0.8}}}}],
                "lights": [{{"type": "area", "radiance": 20,
                             "shape": {{"type": "rectangle", "to_world": {light_to_world} {motion}}}}}]"#
        )
    };
    let at = |x: f32| format!(r#"{{"scale": 0.25, "rotate_x": 90, "translate": [{x}, 0.6, 0]}}"#);
    let blurred = build(&scene(&at(-1.0), &format!(r#", "motion": {{"to_world": {}}}"#, at(1.0)), SHUTTER));
    let still = |t: f32| build(&scene(&at(lerp(-1.0, 1.0, t)), "", ""));
    assert_blur_matches(&blurred, still, "moving area light");
}

/// A moving sphere light: the same check for a sphere emitter, whose cone
/// sampling depends on the center's position at the sample's time; with
/// volpath and with single (its direct lighting of surfaces).
#[test]
fn moving_sphere_light_lights_the_floor_as_the_average_of_still_renders() {
    for integrator in ["volpath", "single"] {
        sphere_light_floor(integrator);
    }
}

fn sphere_light_floor(integrator: &str) {
    let scene = |center: f32, motion: &str, camera_extra: &str| {
        format!(
            r#""camera": {{"type": "perspective", "position": [0, 4, 4], "target": [0, 0, 0], "fov_y": 45,
                           "width": 16, "height": 16 {camera_extra}}},
                "render": {{"integrator": {{"type": "{integrator}"}}, "spp": 16, "seed": 5}},
                "shapes": [{{"type": "rectangle", "to_world": {{"scale": 3, "rotate_x": -90}},
                             "bsdf": {{"type": "diffuse", "reflectance": 0.8}}}}],
                "lights": [{{"type": "area", "radiance": 10,
                             "shape": {{"type": "sphere", "center": [{center}, 0.7, 0], "radius": 0.2 {motion}}}}}]"#
        )
    };
    let blurred = build(&scene(-1.0, r#", "motion": {"center": [1, 0.7, 0]}"#, SHUTTER));
    let still = |t: f32| build(&scene(lerp(-1.0, 1.0, t), "", ""));
    assert_blur_matches(&blurred, still, &format!("moving sphere light ({integrator})"));
}

fn same_bits(a: &Image, b: &Image) -> bool {
    a.pixels.iter().zip(&b.pixels).all(|(p, q)| p.0.map(f32::to_bits) == q.0.map(f32::to_bits))
}

/// A motion to the shape's own pose, and a closed shutter at time 0 with a
/// real motion, both give the still scene's image bit for bit.
#[test]
fn motion_to_the_same_pose_or_a_closed_shutter_is_bit_identical() {
    let still =
        build(&sky_scene(SHUTTER, &format!(r#"{{"type": "sphere", "center": [0, 0, 0], "radius": 1, {GREY}}}"#)));
    let same = build(&sky_scene(
        SHUTTER,
        &format!(
            r#"{{"type": "sphere", "center": [0, 0, 0], "radius": 1, {GREY}, "motion": {{"center": [0, 0, 0]}}}}"#
        ),
    ));
    assert!(same_bits(&render_batch(&still, 4, 0), &render_batch(&same, 4, 0)));
    let old = build(&sky_scene("", &format!(r#"{{"type": "sphere", "center": [0, 0, 0], "radius": 1, {GREY}}}"#)));
    let closed = build(&sky_scene(
        "",
        &format!(
            r#"{{"type": "sphere", "center": [0, 0, 0], "radius": 1, {GREY}, "motion": {{"center": [2, 0, 0]}}}}"#
        ),
    ));
    assert!(same_bits(&render_batch(&old, 4, 0), &render_batch(&closed, 4, 0)));
}

fn error_of(body: &str) -> SceneError {
    match try_build(body) {
        Ok(_) => panic!("expected an error for {body}"),
        Err(e) => e,
    }
}

#[test]
fn bad_motions_are_errors_naming_the_field() {
    let sphere = |motion: &str, camera: &str| {
        sky_scene(camera, &format!(r#"{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "motion": {motion}}}"#))
    };
    // The radius reaches zero inside the shutter (extrapolated before time 0).
    let e = error_of(&sphere(r#"{"radius": 3}"#, r#", "shutter_open": -1, "shutter_close": 0.5"#));
    assert_eq!(e.path, "shapes[0].motion", "{e}");
    assert!(e.message.contains("degenerate at time -1"), "{e}");
    // A key of another shape.
    let e = error_of(&sphere(r#"{"to_world": {"translate": [1, 0, 0]}}"#, SHUTTER));
    assert_eq!(e.path, "shapes[0].motion.to_world", "{e}");
    assert!(e.message.contains("`center` and `radius`"), "{e}");
    // Nothing given.
    let e = error_of(&sphere("{}", SHUTTER));
    assert_eq!(e.path, "shapes[0].motion", "{e}");
    // Non-finite and non-positive values.
    let e = error_of(&sphere(r#"{"center": [0, 1e39, 0]}"#, SHUTTER));
    assert!(e.path.starts_with("shapes[0].motion.center"), "{e}");
    let e = error_of(&sphere(r#"{"radius": 0}"#, SHUTTER));
    assert_eq!(e.path, "shapes[0].motion.radius", "{e}");
    // An unknown key.
    let e = error_of(&sphere(r#"{"velocity": [1, 0, 0]}"#, SHUTTER));
    assert!(e.path.starts_with("shapes[0].motion"), "{e}");
    // A box whose corners cross at time 1.
    let e = error_of(&sky_scene(
        SHUTTER,
        r#"{"type": "box", "min": [0, 0, 0], "max": [1, 1, 1], "motion": {"max": [1, -1, 1]}}"#,
    ));
    assert_eq!(e.path, "shapes[0].motion.max[1]", "{e}");
    // A rectangle mirrored by time 1: its scale passes through zero.
    let e = error_of(&sky_scene(SHUTTER, r#"{"type": "rectangle", "motion": {"to_world": {"scale": [-1, 1, 1]}}}"#));
    assert_eq!(e.path, "shapes[0].motion", "{e}");
    assert!(e.message.contains("degenerate"), "{e}");
    // A sheared pose cannot be interpolated.
    let e = error_of(&sky_scene(
        SHUTTER,
        r#"{"type": "disk", "motion": {"to_world": {"matrix": [[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}}"#,
    ));
    assert_eq!(e.path, "shapes[0].motion.to_world", "{e}");
    assert!(e.message.contains("sheared"), "{e}");
    // A moving medium boundary.
    let body = r#""camera": {"type": "perspective", "position": [0, 0, 6], "target": [0, 0, 0], "width": 4, "height": 4},
        "media": {"fog": {"type": "homogeneous", "sigma_a": 0.1, "sigma_s": 0.1}},
        "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog",
                    "motion": {"center": [1, 0, 0]}}]"#;
    let e = error_of(body);
    assert_eq!(e.path, "shapes[0].motion", "{e}");
    assert!(e.message.contains("cannot bound a medium"), "{e}");
    // A moving area light's bad motion is reported under its shape.
    let e = error_of(&sky_scene(SHUTTER, "").replace(
        r#""lights": [{"type": "constant", "radiance": 1}]"#,
        r#""lights": [{"type": "area", "radiance": 1, "shape": {"type": "sphere", "center": [0, 0, 0], "radius": 1,
                       "motion": {"min": [0, 0, 0]}}}]"#,
    ));
    assert_eq!(e.path, "lights[0].shape.motion.min", "{e}");
}

/// Integrators that precompute lighting or trace photons at time 0 refuse
/// a scene with a moving shape, naming it.
#[test]
fn integrators_without_shape_motion_refuse_naming_the_shape() {
    for integrator in ["photon", "hegeman", "zhou"] {
        let body = format!(
            r#""camera": {{"type": "perspective", "position": [0, 0, 6], "target": [0, 0, 0], "width": 4, "height": 4,
                          "shutter_open": 0, "shutter_close": 1}},
                "render": {{"integrator": {{"type": "{integrator}"}}, "spp": 1}},
                "media": {{"fog": {{"type": "homogeneous", "sigma_a": 0.1, "sigma_s": 0.1}}}},
                "shapes": [{{"type": "box", "min": [-3, -3, -3], "max": [3, 3, 3], "interior": "fog"}},
                           {{"type": "sphere", "center": [0, 0, 0], "radius": 1, "bsdf": {{"type": "diffuse"}},
                             "motion": {{"center": [1, 0, 0]}}}}],
                "lights": [{{"type": "point", "position": [0, 2, 0], "intensity": 1}}]"#
        );
        let built = build(&body);
        let options = RenderOptions { spp: 1, seed: 1, first_sample: 0, threads: None, sampler: Default::default() };
        let e = render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None)
            .expect_err(&format!("{integrator} rendered a moving shape"));
        let message = e.to_string();
        assert!(message.contains("shapes[1]") && message.contains("motion"), "{integrator}: {message}");
    }
}
