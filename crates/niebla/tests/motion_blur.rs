//! Motion blur: a camera shutter with a time per camera sample, a moving
//! camera and Eulerian motion of grid media from a Vec3 velocity grid
//! written by the reference library (python3-openvdb).
//!
//! Each blurred render is compared with something it did not compute
//! itself: the average of static renders at the shutter's sub-times (the
//! blob translated by `to_world`, or the camera placed by hand), strip by
//! strip of the image, within 4 standard errors estimated from independent
//! batches of samples.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use niebla::film::Image;
use niebla::render::{render, RenderOptions};
use niebla::scene::{build_scene, parse_scene_frame, parse_scene_str, BuiltScene, CameraDesc, SceneError};

const FILE: &str = "motion_test.json";

/// `density`: a Gaussian blob (standard deviation 0.15, peak 1) centred at
/// the origin, voxel 0.04, on [-0.6, 0.6]^3; `vel`: the constant velocity
/// (0.6, 0, 0) world units per second on [-1.2, 1.2]^3 (active voxels);
/// `zero`: the velocity 0 on the same voxels.
const GENERATOR: &str = r#"
import os, sys
os.environ.setdefault("OPENVDB_DISABLE_DELAYED_LOAD", "1")
import numpy as np
import pyopenvdb as vdb
voxel = 0.04
n = 15
i = np.arange(-n, n + 1) * voxel
x, y, z = np.meshgrid(i, i, i, indexing="ij")
blob = np.exp(-(x * x + y * y + z * z) / (2 * 0.15 ** 2)).astype(np.float32)
d = vdb.FloatGrid(0.0); d.name = "density"
d.transform = vdb.createLinearTransform(voxelSize=voxel)
d.copyFromArray(blob, ijk=(-n, -n, -n), tolerance=0.0)
def vec(name, value):
    g = vdb.Vec3SGrid((0.0, 0.0, 0.0)); g.name = name
    g.transform = vdb.createLinearTransform(voxelSize=voxel)
    g.fill((-30, -30, -30), (30, 30, 30), value, True)
    return g
vdb.write(sys.argv[1], grids=[d, vec("vel", (0.6, 0.0, 0.0)), vec("zero", (0.0, 0.0, 0.0))])
"#;

fn vdb_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("motion_vdbs");
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("blob.vdb");
        if !file.exists() {
            let scratch = dir.join(format!("blob.vdb.tmp{}", std::process::id()));
            let out = Command::new("/usr/bin/python3")
                .args(["-c", GENERATOR])
                .arg(&scratch)
                .output()
                .expect("run /usr/bin/python3 (install python3-openvdb)");
            assert!(out.status.success(), "VDB generator failed:\n{}", String::from_utf8_lossy(&out.stderr));
            std::fs::rename(&scratch, &file).unwrap();
        }
        dir
    })
}

/// The velocity (world units per second) of `vel` along x.
const SPEED: f32 = 0.6;
/// Frames per second of the blurred scenes.
const FPS: f32 = 2.0;
/// Shutter of the blurred scenes (frames): one-sided, so that a motion of
/// the wrong sign (the blob blurred to the left) would fail.
const SHUTTER: [f32; 2] = [0.0, 1.0];

/// A 16 x 16 view of the blob from (cx, 0, 3) toward (cx, 0, 0) against a
/// white sky; `camera_extra` and `medium_extra` are more JSON keys of the
/// camera and of the medium.
fn scene(camera_extra: &str, medium_extra: &str) -> Result<BuiltScene, SceneError> {
    let text = format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [0, 0, 3], "target": [0, 0, 0],
                        "fov_y": 26, "width": 16, "height": 16 {camera_extra}}},
            "render": {{"integrator": {{"type": "volpath"}}, "spp": 16, "seed": 3}},
            "media": {{"blob": {{"type": "grid", "density": {{"type": "vdb", "file": "blob.vdb"}},
                                 "sigma_t": 8, "albedo": 0.7 {medium_extra}}}}},
            "shapes": [{{"type": "box", "min": [-1.5, -1.5, -1.5], "max": [1.5, 1.5, 1.5], "interior": "blob"}}],
            "lights": [{{"type": "constant", "radiance": 1}}]}}"#
    );
    let desc = parse_scene_str(&text, FILE)?;
    build_scene(&desc, FILE, vdb_dir())
}

fn build(camera_extra: &str, medium_extra: &str) -> BuiltScene {
    scene(camera_extra, medium_extra).unwrap_or_else(|e| panic!("{e}"))
}

fn render_batch(built: &BuiltScene, spp: u32, batch: u64) -> Image {
    let options =
        RenderOptions { spp, seed: 3, first_sample: batch * spp as u64, threads: None, sampler: Default::default() };
    render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap()
}

/// Mean of channel 0 over each of 4 vertical strips (4 columns each) of a
/// 16 x 16 image: the motion is along the image's x axis.
fn strips(image: &Image) -> [f64; 4] {
    let mut s = [0.0; 4];
    for y in 0..image.height {
        for x in 0..image.width {
            s[(x / 4) as usize] += image.get(x, y).0[0] as f64 / (4.0 * image.height as f64);
        }
    }
    s
}

/// Per strip: mean over batches and its standard error.
fn mean_and_se(batches: &[[f64; 4]]) -> [(f64, f64); 4] {
    let k = batches.len() as f64;
    std::array::from_fn(|i| {
        let mean = batches.iter().map(|b| b[i]).sum::<f64>() / k;
        let var = batches.iter().map(|b| (b[i] - mean).powi(2)).sum::<f64>() / (k - 1.0);
        (mean, (var / k).sqrt())
    })
}

/// Compares the blurred strips with the average of static ones within 4
/// combined standard errors, and checks the blur is visible (the static
/// frame at time 0 differs from the blurred one by more than that).
fn assert_blur_matches(blurred: &[[f64; 4]], averaged: &[[f64; 4]], unblurred: &[f64; 4], what: &str) {
    let (b, a) = (mean_and_se(blurred), mean_and_se(averaged));
    let mut visible = false;
    for i in 0..4 {
        let se = (b[i].1.powi(2) + a[i].1.powi(2)).sqrt();
        let diff = (b[i].0 - a[i].0).abs();
        eprintln!(
            "{what}: strip {i}: blurred {:.5} +- {:.5}, average of static {:.5} +- {:.5}, \
             static at time 0 {:.5}, |diff| = {:.2} SE",
            b[i].0,
            b[i].1,
            a[i].0,
            a[i].1,
            unblurred[i],
            diff / se
        );
        assert!(diff < 4.0 * se, "{what}: strip {i}: blurred {} vs averaged {} (SE {se})", b[i].0, a[i].0);
        visible |= (b[i].0 - unblurred[i]).abs() > 8.0 * se;
    }
    assert!(visible, "{what}: the blurred image does not differ from the static one");
}

/// Midpoints of `n` equal parts of the shutter (frames).
fn sub_times(n: usize) -> Vec<f32> {
    (0..n).map(|i| SHUTTER[0] + (SHUTTER[1] - SHUTTER[0]) * (i as f32 + 0.5) / n as f32).collect()
}

const BATCHES: u64 = 16;
const SPP: u32 = 16;
/// Sub-times of the static average. A strip's value as a function of the
/// blob's displacement `s` changes by about 0.1 over the blob's width
/// (sigma 0.15), so `|f''| <~ 0.1 / 0.15^2 = 4.4`; the midpoint rule over
/// the 0.3 world units the blob travels, in 16 parts of h = 0.01875, errs
/// by at most h^2 / 24 |f''| ~ 6e-5, below the standard errors (measured
/// 3e-4 to 1.3e-3 per strip).
const SUB_TIMES: usize = 16;

fn camera_shutter() -> String {
    format!(r#", "shutter_open": {}, "shutter_close": {}, "fps": {FPS}"#, SHUTTER[0], SHUTTER[1])
}

#[test]
fn translating_blob_equals_the_time_average_of_static_renders() {
    // Blurred: the blob moves at 0.6 world units per second, 0.3 per frame
    // at 2 fps, during the shutter [0, 1] frames: density(x, t) =
    // blob(x - (0.3 t, 0, 0)).
    let blurred_scene = build(&camera_shutter(), r#", "velocity": "vel", "velocity_units": "world_per_second""#);
    let blurred: Vec<[f64; 4]> = (0..BATCHES).map(|k| strips(&render_batch(&blurred_scene, SPP, k))).collect();
    // Static: the blob translated by `to_world` to where it is at each sub-time.
    let statics: Vec<BuiltScene> = sub_times(SUB_TIMES)
        .iter()
        .map(|&t| build("", &format!(r#", "to_world": {{"translate": [{}, 0, 0]}}"#, SPEED / FPS * t)))
        .collect();
    let averaged: Vec<[f64; 4]> = (0..BATCHES)
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
    let unblurred =
        mean_and_se(&(0..BATCHES).map(|k| strips(&render_batch(&build("", ""), SPP, k))).collect::<Vec<_>>())
            .map(|(m, _)| m);
    assert_blur_matches(&blurred, &averaged, &unblurred, "translating blob");
}

#[test]
fn velocity_units_convert_to_the_same_motion() {
    // 0.6 world/s at 2 fps = 0.3 world/frame = 7.5 voxels/frame (voxel 0.04):
    // the three descriptions move the blob alike. Displacements are equal up
    // to rounding, so the images agree closely but not bit for bit.
    let a = build(&camera_shutter(), r#", "velocity": "vel", "velocity_units": "world_per_second""#);
    let (sa, _) = (strips(&render_batch(&a, 64, 0)), ());
    for units in ["world_per_frame", "voxel_per_frame"] {
        // Same speed in other units: scale the shutter instead of the grid,
        // so that the product velocity x time is the same.
        let factor = match units {
            "world_per_frame" => 0.5,    // 0.6 world/frame = 2x: half the shutter
            _ => 0.6 / FPS / 0.04 / 0.6, // 0.6 voxel/frame: 12.5x the shutter
        };
        let camera = format!(
            r#", "shutter_open": {}, "shutter_close": {}, "fps": {FPS}"#,
            SHUTTER[0] * factor,
            SHUTTER[1] * factor
        );
        let b = build(&camera, &format!(r#", "velocity": "vel", "velocity_units": "{units}""#));
        let sb = strips(&render_batch(&b, 64, 0));
        for i in 0..4 {
            assert!((sa[i] - sb[i]).abs() < 0.02, "{units}: strip {i}: {} vs {}", sa[i], sb[i]);
        }
    }
}

#[test]
fn zero_velocity_gives_the_static_image_bit_for_bit() {
    let moving = build(&camera_shutter(), r#", "velocity": "zero""#);
    let still = build(&camera_shutter(), "");
    let a = render_batch(&moving, 8, 0);
    let b = render_batch(&still, 8, 0);
    assert!(a.pixels.iter().zip(&b.pixels).all(|(p, q)| p.0.map(f32::to_bits) == q.0.map(f32::to_bits)));
    // A shutter of the single instant 0 keeps a scene's old image.
    let old = render_batch(&build("", ""), 8, 0);
    let closed = render_batch(&build(r#", "shutter_open": 0, "shutter_close": 0"#, r#", "velocity": "vel""#), 8, 0);
    assert!(old.pixels.iter().zip(&closed.pixels).all(|(p, q)| p.0.map(f32::to_bits) == q.0.map(f32::to_bits)));
}

#[test]
fn moving_camera_equals_the_average_of_renders_at_sub_times() {
    // The camera slides along x by 0.3 per frame (target with it); the blob
    // is still.
    let motion = r#", "motion": {"position": [0.3, 0, 3], "target": [0.3, 0, 0]}"#;
    let blurred_scene = build(&format!("{}{motion}", camera_shutter()), "");
    let blurred: Vec<[f64; 4]> = (0..BATCHES).map(|k| strips(&render_batch(&blurred_scene, SPP, k))).collect();
    let statics: Vec<BuiltScene> = sub_times(SUB_TIMES)
        .iter()
        .map(|&t| {
            let x = 0.3 * t;
            // Replaces position and target (later keys are refused as
            // duplicates, so the whole camera is written).
            let text = format!(
                r#"{{"version": 1,
                    "camera": {{"type": "perspective", "position": [{x}, 0, 3], "target": [{x}, 0, 0],
                                "fov_y": 26, "width": 16, "height": 16}},
                    "render": {{"integrator": {{"type": "volpath"}}, "spp": 16, "seed": 3}},
                    "media": {{"blob": {{"type": "grid", "density": {{"type": "vdb", "file": "blob.vdb"}},
                                         "sigma_t": 8, "albedo": 0.7}}}},
                    "shapes": [{{"type": "box", "min": [-1.5, -1.5, -1.5], "max": [1.5, 1.5, 1.5],
                                 "interior": "blob"}}],
                    "lights": [{{"type": "constant", "radiance": 1}}]}}"#
            );
            build_scene(&parse_scene_str(&text, FILE).unwrap(), FILE, vdb_dir()).unwrap()
        })
        .collect();
    let averaged: Vec<[f64; 4]> = (0..BATCHES)
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
    let unblurred =
        mean_and_se(&(0..BATCHES).map(|k| strips(&render_batch(&build("", ""), SPP, k))).collect::<Vec<_>>())
            .map(|(m, _)| m);
    assert_blur_matches(&blurred, &averaged, &unblurred, "moving camera");
}

fn expect_error(built: Result<BuiltScene, SceneError>) -> SceneError {
    match built {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

fn error_of(camera_extra: &str, medium_extra: &str) -> SceneError {
    match scene(camera_extra, medium_extra) {
        Ok(_) => panic!("expected an error for {camera_extra} {medium_extra}"),
        Err(e) => e,
    }
}

#[test]
fn bad_motion_input_names_the_file_and_the_field() {
    let e = error_of("", r#", "velocity": "wind""#);
    assert_eq!(e.path, "media.blob.velocity");
    let text = e.to_string();
    assert!(text.contains(FILE) && text.contains("blob.vdb") && text.contains("\"wind\""), "{text}");
    assert!(text.contains("vel") && text.contains("zero"), "lists the grids: {text}");

    let e = error_of("", r#", "velocity": "density""#);
    assert_eq!(e.path, "media.blob.velocity");
    assert!(e.to_string().contains("not a Vec3 grid"), "{e}");

    let e = error_of(r#", "shutter_open": 0.5, "shutter_close": 0.25"#, "");
    assert_eq!(e.path, "camera.shutter_close");
    assert!(e.to_string().contains(FILE) && e.to_string().contains("close at or after"), "{e}");

    let e = error_of(r#", "fps": 0"#, "");
    assert_eq!(e.path, "camera.fps");

    let e = error_of("", r#", "velocity_units": "furlongs""#);
    assert_eq!(e.path, "media.blob.velocity_units");

    // The camera reaches its target when the shutter closes.
    let e = error_of(r#", "shutter_close": 1, "motion": {"position": [0, 0, 0]}"#, "");
    assert_eq!(e.path, "camera.motion");

    // A velocity needs a VDB density.
    let text = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 0, 3], "target": [0, 0, 0], "width": 4, "height": 4},
        "media": {"fog": {"type": "grid", "density": {"type": "constant"}, "sigma_t": 1, "albedo": 1,
                          "velocity": "vel"}}}"#;
    let e = expect_error(build_scene(&parse_scene_str(text, FILE).unwrap(), FILE, vdb_dir()));
    assert_eq!(e.path, "media.fog.velocity");
    assert!(e.to_string().contains("\"type\": \"vdb\""), "{e}");
}

#[test]
fn keyframed_camera_moves_between_its_poses_at_the_shutter_ends() {
    // Keyframes: x = 0 at frame 1, x = 4 at frame 5 (x = frame - 1 between).
    let text = |shutter: &str| {
        format!(
            r#"{{"version": 1,
                "camera": {{"type": "perspective", "position": [0, 0, 3], "target": [0, 0, 0],
                            "width": 4, "height": 4 {shutter},
                            "keyframes": [{{"frame": 1, "position": [0, 0, 3]}}, {{"frame": 5, "position": [4, 0, 3]}}]}}}}"#
        )
    };
    let camera = |shutter: &str, frame: u32| {
        let (desc, _) = parse_scene_frame(&text(shutter), FILE, Some(frame)).unwrap();
        let CameraDesc::Perspective(c) = desc.camera;
        c
    };
    // Shutter [0, 0.5] at frame 2: poses x = 1 and 1.5, so x = 1 at time 0
    // and 2 at time 1.
    let c = camera(r#", "shutter_open": 0, "shutter_close": 0.5"#, 2);
    assert_eq!(c.position, [1.0, 0.0, 3.0]);
    assert_eq!(c.motion.as_ref().unwrap().position, Some([2.0, 0.0, 3.0]));
    assert_eq!(c.motion.as_ref().unwrap().target, None);
    // Shutter [-0.5, 0.5] at frame 1, where the keyframes start (held
    // before): poses x = 0 at 0.5 and 0.5 at 1.5, the line x = 0.25 + 0.5 t.
    let c = camera(r#", "shutter_open": -0.5, "shutter_close": 0.5"#, 1);
    assert_eq!(c.position, [0.25, 0.0, 3.0]);
    assert_eq!(c.motion.as_ref().unwrap().position, Some([0.75, 0.0, 3.0]));
    // A closed shutter: no motion, the keyframed pose.
    let c = camera("", 2);
    assert_eq!(c.position, [1.0, 0.0, 3.0]);
    assert!(c.motion.is_none());
}

#[test]
fn pyro_medium_moves_by_its_velocity_grid() {
    // An emitting pyro blob (constant emission colour where the density is
    // positive): the zero velocity grid gives the still image bit for bit,
    // `vel` blurs it, and a missing grid is an error at the field.
    let pyro = |extra: &str| {
        let text = format!(
            r#"{{"version": 1,
                "camera": {{"type": "perspective", "position": [0, 0, 3], "target": [0, 0, 0],
                            "fov_y": 26, "width": 16, "height": 16 {}}},
                "render": {{"integrator": {{"type": "volpath"}}, "spp": 8, "seed": 3}},
                "media": {{"fire": {{"type": "pyro", "file": "blob.vdb", "density": 8,
                                     "emission_strength": 2 {extra}}}}},
                "shapes": [{{"type": "box", "min": [-1.5, -1.5, -1.5], "max": [1.5, 1.5, 1.5], "interior": "fire"}}]}}"#,
            camera_shutter()
        );
        build_scene(&parse_scene_str(&text, FILE).unwrap(), FILE, vdb_dir())
    };
    let still = render_batch(&pyro("").unwrap(), 8, 0);
    let zero = render_batch(&pyro(r#", "velocity": "zero""#).unwrap(), 8, 0);
    assert!(still.pixels.iter().zip(&zero.pixels).all(|(p, q)| p.0.map(f32::to_bits) == q.0.map(f32::to_bits)));
    let moving = strips(&render_batch(&pyro(r#", "velocity": "vel""#).unwrap(), 8, 0));
    let still = strips(&still);
    // The blob moves toward +x (strip 3): more light there, less in strip 0.
    assert!(moving[3] > still[3] * 1.05 && moving[0] < still[0], "{moving:?} vs {still:?}");
    let e = expect_error(pyro(r#", "velocity": "velocity""#));
    assert_eq!(e.path, "media.fire.velocity");
}
