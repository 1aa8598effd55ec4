//! The pyro medium (`"type": "pyro"`, Blender's Principled Volume
//! parameters over the grids of one VDB file written by the reference
//! library, python3-openvdb): closed forms, agreement with the same scene
//! written with the grid medium's own emission options, and errors that name
//! the file, the grid and the field.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use niebla::color::{blackbody_rgb_exact, Rgb};
use niebla::film::Image;
use niebla::math::Vec3;
use niebla::render::{render, RenderOptions};
use niebla::scene::{build_scene, parse_scene_str, BuiltScene, SceneError};

const FILE: &str = "pyro_test.json";

/// Grids (identity-free transforms): `density` 1 on the world box [-2, 2]^3
/// (voxel 0.05), `flame` 0.8 on the same box (voxel 0.05), `temperature`
/// 1.5 on it at voxel 0.1 (another transform), `vel` a Vec3 grid, and
/// `bad_temp` with one NaN voxel, all as active tiles and voxels.
const GENERATOR: &str = r#"
import os, sys
os.environ.setdefault("OPENVDB_DISABLE_DELAYED_LOAD", "1")
import pyopenvdb as vdb
def grid(cls, bg, name, voxel, lo, hi, value):
    g = cls(bg); g.name = name
    g.transform = vdb.createLinearTransform(voxelSize=voxel)
    g.fill(lo, hi, value, True)
    return g
grids = [
    grid(vdb.FloatGrid, 0.0, "density", 0.05, (-40, -40, -40), (40, 40, 40), 1.0),
    grid(vdb.FloatGrid, 0.0, "flame", 0.05, (-40, -40, -40), (40, 40, 40), 0.8),
    grid(vdb.FloatGrid, 0.0, "temperature", 0.1, (-20, -20, -20), (20, 20, 20), 1.5),
    grid(vdb.Vec3SGrid, (0.0, 0.0, 0.0), "vel", 0.05, (-8, -8, -8), (7, 7, 7), (0.0, 1.0, 0.0)),
    grid(vdb.FloatGrid, 0.0, "bad_temp", 0.1, (-4, -4, -4), (3, 3, 3), 1.0),
]
grids[-1].getAccessor().setValueOn((1, 2, 3), float("nan"))
vdb.write(sys.argv[1], grids=grids)
"#;

fn vdb_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("pyro_vdbs");
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("pyro.vdb");
        if !file.exists() {
            let scratch = dir.join(format!("pyro.vdb.tmp{}", std::process::id()));
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

/// A scene whose camera sits at (0, 0, -0.5) inside the box [-1, 1]^3 that
/// holds medium `fire` (given as JSON text), looking along +z through a
/// 2-degree field of view: each pixel sees 1.5 units of medium (within 2e-4).
fn scene_with(medium: &str, integrator: &str) -> Result<BuiltScene, SceneError> {
    let text = format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [0, 0, -0.5], "target": [0, 0, 1],
                        "fov_y": 2, "width": 8, "height": 8}},
            "render": {{"integrator": {integrator}, "spp": 64, "seed": 5}},
            "media": {{"fire": {medium}}},
            "shapes": [{{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "interior": "fire"}}]}}"#
    );
    let desc = parse_scene_str(&text, FILE)?;
    build_scene(&desc, FILE, vdb_dir())
}

fn build(medium: &str) -> BuiltScene {
    scene_with(medium, r#"{"type": "volpath"}"#).unwrap_or_else(|e| panic!("{e}"))
}

/// [`build`] with `volpath`'s light sampling of emissive media off: its
/// distribution is built from emission found at lattice points, which differ
/// between two descriptions of the same emission where the density is zero
/// (the pyro medium emits nothing there), so only free flight draws the same
/// random numbers for both.
fn build_free_flight(medium: &str) -> BuiltScene {
    scene_with(medium, r#"{"type": "volpath", "volume_light_sampling": false}"#).unwrap_or_else(|e| panic!("{e}"))
}

fn render_image(built: &BuiltScene, spp: u32) -> Image {
    let options = RenderOptions { spp, seed: 5, first_sample: 0, threads: None, sampler: Default::default() };
    render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap()
}

/// Mean over pixels of channel `c` and its standard error (pixels are
/// independent estimates of the same value).
fn mean_and_se(image: &Image, c: usize) -> (f64, f64) {
    let v: Vec<f64> = image.pixels.iter().map(|p| p.0[c] as f64).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn emissive_only_slab_matches_the_closed_form() {
    // color 0: no scattering; absorption_color 0: sigma_a = density = 0.8;
    // L_ve = emission_strength * emission_color = 2 (1, 0.5, 0.25), constant
    // without a flame grid.
    let built = build(
        r#"{"type": "pyro", "file": "pyro.vdb", "density": 0.8, "color": 0,
            "emission_strength": 2, "emission_color": [1, 0.5, 0.25], "flame_attribute": ""}"#,
    );
    let image = render_image(&built, 64);
    let (sigma, d) = (0.8f64, 1.5f64);
    for (c, l_e) in [2.0f64, 1.0, 0.5].into_iter().enumerate() {
        let exact = l_e * (1.0 - (-sigma * d).exp()) / sigma;
        let (mean, se) = mean_and_se(&image, c);
        // 4 standard errors, plus the 2e-4 relative spread of path lengths.
        assert!((mean - exact).abs() <= 4.0 * se + 2e-4 * exact, "channel {c}: {mean} +- {se} vs {exact}");
        // The test has power: the standard error is below 1% of the value.
        assert!(se < 0.01 * exact, "channel {c}: standard error {se} of {exact}");
    }
}

#[test]
fn principled_coefficients_follow_blenders_mapping() {
    let built = build(
        r#"{"type": "pyro", "file": "pyro.vdb", "density": 2, "color": [0.2, 0.5, 0.9],
            "absorption_color": [0.25, 0, 1], "anisotropy": 0.3}"#,
    );
    let point = built.scene.media[0].at(Vec3::new(0.1, 0.2, 0.3));
    // sigma_s = d c; sigma_a = d max(1 - c, 0) max(1 - sqrt(a), 0).
    let expected_s = [0.4, 1.0, 1.8];
    let expected_a = [2.0 * 0.8 * 0.5, 2.0 * 0.5 * 1.0, 0.0];
    for c in 0..3 {
        assert!((point.sigma_s.0[c] - expected_s[c]).abs() < 1e-5, "{:?}", point.sigma_s);
        assert!((point.sigma_a.0[c] - expected_a[c]).abs() < 1e-5, "{:?}", point.sigma_a);
    }
    assert!((built.scene.media[0].phase().mean_cosine() - 0.3).abs() < 1e-6);
}

#[test]
fn blackbody_of_a_constant_temperature_grid_is_the_blackbody_of_that_temperature() {
    // T = temperature x grid = 1000 x 1.5 = 1500 K (the grid on another
    // transform than the density); intensity 1: sigma_SB 1e-6 / pi T^4.
    let built =
        build(r#"{"type": "pyro", "file": "pyro.vdb", "blackbody_intensity": 1, "blackbody_tint": [1, 0.5, 2]}"#);
    let l_ve = built.scene.media[0].at(Vec3::new(0.3, -0.2, 0.1)).l_ve;
    let exact = blackbody_rgb_exact(1500.0);
    let factor = 5.670373e-14 / std::f64::consts::PI * 1500f64.powi(4);
    let tint = [1.0, 0.5, 2.0];
    for (c, t) in tint.iter().enumerate() {
        let want = factor * t * exact.0[c] as f64;
        // The table interpolates in 20 K steps: 1e-3 relative.
        assert!((l_ve.0[c] as f64 - want).abs() <= 1e-3 * want, "{c}: {} vs {want}", l_ve.0[c]);
    }
    // Outside the density (|x| > 2) nothing is emitted.
    assert_eq!(built.scene.media[0].at(Vec3::new(0.0, 2.5, 0.0)).l_ve, Rgb::ZERO);
}

/// Per-pixel relative agreement of two renders with the same random numbers.
fn assert_same_image(a: &Image, b: &Image, what: &str) {
    let mut worst = 0.0f32;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            let d = (p.0[c] - q.0[c]).abs() / p.0[c].abs().max(q.0[c].abs()).max(1e-6);
            worst = worst.max(d);
        }
    }
    assert!(worst <= 1e-4, "{what}: largest relative difference {worst}");
    let mean = |i: &Image| i.pixels.iter().map(|p| p.0[0] as f64).sum::<f64>();
    assert!(mean(a) > 0.0, "{what}: black image");
}

#[test]
fn pyro_renders_as_the_same_scene_written_with_grid_emission_options() {
    // Flame emission through the identity ramp = an emission grid with a color.
    let pyro = build_free_flight(
        r#"{"type": "pyro", "file": "pyro.vdb", "color": 0.5,
            "emission_strength": 3, "emission_color": [1, 0.6, 0.3]}"#,
    );
    let grid = build_free_flight(
        r#"{"type": "grid", "sigma_a": 0.5, "sigma_s": 0.5,
            "density": {"type": "vdb", "file": "pyro.vdb", "grid": "density"},
            "emission": {"grid": {"type": "vdb", "file": "pyro.vdb", "grid": "flame"},
                         "color": [1, 0.6, 0.3], "emission_scale": 3}}"#,
    );
    assert_same_image(&render_image(&pyro, 16), &render_image(&grid, 16), "flame emission");

    // Blackbody of a constant 1500 K = temperature emission scaled by sigma T^4.
    let pyro = build_free_flight(r#"{"type": "pyro", "file": "pyro.vdb", "color": 0.5, "blackbody_intensity": 1}"#);
    let scale = niebla::medium::PYRO_STEFAN_BOLTZMANN * 1500f32.powi(4);
    let grid = build_free_flight(&format!(
        r#"{{"type": "grid", "sigma_a": 0.5, "sigma_s": 0.5,
            "density": {{"type": "vdb", "file": "pyro.vdb", "grid": "density"}},
            "emission": {{"temperature": {{"type": "constant", "value": 1500, "bounds": {{"min": [-3, -3, -3], "max": [3, 3, 3]}}}},
                          "emission_scale": {scale}}}}}"#
    ));
    assert_same_image(&render_image(&pyro, 16), &render_image(&grid, 16), "blackbody emission");
}

#[test]
fn bad_grids_name_the_file_the_grid_and_the_field() {
    let err = |medium: &str| scene_with(medium, r#"{"type": "volpath"}"#).map(|_| ()).unwrap_err();

    // A Vec3 grid where a float is expected.
    let e = err(r#"{"type": "pyro", "file": "pyro.vdb", "blackbody_intensity": 1, "temperature_attribute": "vel"}"#);
    assert_eq!(e.path, "media.fire.temperature_attribute", "{e}");
    assert!(e.message.contains("pyro.vdb") && e.message.contains("\"vel\"") && e.message.contains("Vec3"), "{e}");

    // A grid absent from the file: the message lists the file's grids.
    let e = err(r#"{"type": "pyro", "file": "pyro.vdb", "density_attribute": "smoke"}"#);
    assert_eq!(e.path, "media.fire.density_attribute", "{e}");
    assert!(e.message.contains("no grid named \"smoke\"") && e.message.contains("\"flame\" (float)"), "{e}");

    // No density grid at all.
    let e = err(r#"{"type": "pyro", "file": "pyro.vdb", "density_attribute": ""}"#);
    assert!(e.message.contains("needs a density grid"), "{e}");

    // NaN temperatures: the voxel is named.
    let e =
        err(r#"{"type": "pyro", "file": "pyro.vdb", "blackbody_intensity": 1, "temperature_attribute": "bad_temp"}"#);
    assert!(e.path.starts_with("media.fire.temperature_attribute"), "{e}");
    assert!(e.message.contains("\"bad_temp\"") && e.message.contains("(1, 2, 3)") && e.message.contains("NaN"), "{e}");

    // An absurd remap: 90000 x 1.5 K.
    let e = err(r#"{"type": "pyro", "file": "pyro.vdb", "blackbody_intensity": 1, "temperature": 90000}"#);
    assert_eq!(e.path, "media.fire.temperature_attribute", "{e}");
    assert!(e.message.contains("\"temperature\"") && e.message.contains("135000"), "{e}");
    let e = err(r#"{"type": "pyro", "file": "pyro.vdb", "temperature": -5}"#);
    assert_eq!(e.path, "media.fire.temperature", "{e}");

    // Unknown keys are refused (a typo of a Blender parameter).
    let e = err(r#"{"type": "pyro", "file": "pyro.vdb", "emision_strength": 1}"#);
    assert!(e.message.contains("emision_strength"), "{e}");
}

#[test]
fn mantaflow_style_file_reads_by_default_names_and_renders() {
    // density, flame, temperature (floats), vel and color (Vec3), and the
    // empty heat, fuel, react and velocity_guide grids of a Blender fire.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("pyro_mantaflow");
    if !dir.join("mantaflow_fire.vdb").exists() {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../niebla-volume/tests/oracle/make_vec3_vdbs.py");
        let scratch = dir.with_extension(format!("tmp{}", std::process::id()));
        let out = Command::new("/usr/bin/python3").arg(&script).arg(&scratch).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        if std::fs::rename(&scratch, &dir).is_err() {
            let _ = std::fs::remove_dir_all(&scratch);
        }
    }
    let text = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 1.2, 5], "target": [0, 1.2, 0], "width": 12, "height": 12},
        "render": {"integrator": {"type": "volpath"}, "spp": 8},
        "media": {"fire": {"type": "pyro", "file": "mantaflow_fire.vdb", "density": 10,
                           "emission_strength": 1, "blackbody_intensity": 1}},
        "ambient_medium": "fire"}"#;
    let desc = parse_scene_str(text, FILE).unwrap();
    let built = build_scene(&desc, FILE, &dir).unwrap_or_else(|e| panic!("{e}"));
    let niebla::medium::Medium::Grid(g) = &built.scene.media[0] else { panic!("a grid medium") };
    let niebla::medium::GridEmission::Pyro(e) = &g.emission else { panic!("pyro emission") };
    assert!(e.flame.is_some() && e.temperature.field.is_some(), "flame and temperature found by name");
    let image = render_image(&built, 8);
    assert!(image.pixels.iter().all(|p| p.0.iter().all(|v| v.is_finite() && *v >= 0.0)));
    let center = image.pixels[6 * 12 + 6];
    assert!(center.0[0] > 0.0, "the fire glows: {center:?}");

    // An empty grid as the temperature: T is the offset everywhere.
    let text =
        text.replace("\"blackbody_intensity\": 1", "\"blackbody_intensity\": 1, \"temperature_attribute\": \"heat\"");
    let desc = parse_scene_str(&text, FILE).unwrap();
    let built = build_scene(&desc, FILE, &dir).unwrap_or_else(|e| panic!("{e}"));
    let niebla::medium::Medium::Grid(g) = &built.scene.media[0] else { panic!("a grid medium") };
    let niebla::medium::GridEmission::Pyro(e) = &g.emission else { panic!("pyro emission") };
    assert_eq!(e.temperature.kelvin(Vec3::new(0.0, 1.0, 0.0)), 0.0);
}
