//! Surface textures against closed forms: a diffuse plane under a uniform
//! environment of radiance `L` (and nothing else) reflects exactly
//! `R(uv) L` toward the camera, since every path bounces once and escapes;
//! so each pixel inside one texture cell equals that cell's reflectance
//! times `L` to float rounding, with any noise.

use std::path::Path;

use niebla::film::Image;
use niebla::render::{render, RenderOptions};
use niebla::scene::{build_scene, parse_scene_str};

const L: f32 = 0.8;

/// A 2 x 2 square in the xz plane, facing +y, seen from straight above.
fn render_plane(shape: &str, reflectance: &str, dir: &Path) -> Image {
    let text = format!(
        r#"{{"version": 1,
          "camera": {{"type": "perspective", "position": [0, 4, 0], "target": [0, 0, 0], "up": [0, 0, -1],
                     "fov_y": 26, "width": 32, "height": 32}},
          "render": {{"integrator": {{"type": "volpath"}}}},
          "shapes": [{{{shape}, "bsdf": {{"type": "diffuse", "reflectance": {reflectance}}}}}],
          "lights": [{{"type": "constant", "radiance": {L}}}]}}"#
    );
    let desc = parse_scene_str(&text, "texture.json").unwrap_or_else(|e| panic!("{e}"));
    let built = build_scene(&desc, "texture.json", dir).unwrap_or_else(|e| panic!("{e}"));
    let options = RenderOptions { spp: 4, seed: 1, first_sample: 0, threads: None, sampler: Default::default() };
    render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap()
}

const RECTANGLE: &str = r#""type": "rectangle", "to_world": {"rotate_x": -90}"#;

/// The rectangle's uv: local (x, y) in [-1, 1]^2 to [0, 1]^2; `rotate_x: -90`
/// takes local +y to world -z, so u grows with world x and v toward -z (the
/// top of the image, as `up` is -z).
#[test]
fn checkerboard_cells_reflect_their_color() {
    let checker = r#"{"type": "checkerboard", "color0": [0.9, 0.5, 0.1], "color1": 0.25, "scale": [2, 2]}"#;
    let image = render_plane(RECTANGLE, checker, Path::new("."));
    let at = |x: u32, y: u32| image.pixels[(y * image.width + x) as usize];
    let c0 = [0.9 * L, 0.5 * L, 0.1 * L];
    let c1 = [0.25 * L; 3];
    let close = |p: niebla::color::Rgb, c: [f32; 3]| (0..3).all(|k| (p[k] - c[k]).abs() < 1e-5);
    // Pixel centers well inside each quadrant of the 2 x 2 square: cell
    // (0, 0) (u < 1/2, v < 1/2) is at the bottom left of the image.
    assert!(close(at(8, 24), c0), "bottom left {:?}", at(8, 24));
    assert!(close(at(24, 8), c0), "top right {:?}", at(24, 8));
    assert!(close(at(24, 24), c1), "bottom right {:?}", at(24, 24));
    assert!(close(at(8, 8), c1), "top left {:?}", at(8, 8));
    // Every pixel lies between the two colors' values (mixed at cell borders).
    for p in &image.pixels {
        for k in 0..3 {
            assert!(p[k] >= c0[k].min(c1[k]) - 1e-5 && p[k] <= c0[k].max(c1[k]) + 1e-5, "{p:?}");
        }
    }
    // A mesh square with the same uvs renders the same cells.
    let quad = r#""type": "mesh", "positions": [[-1,0,1],[1,0,1],[1,0,-1],[-1,0,-1]],
                  "indices": [[0,1,2],[0,2,3]], "uvs": [[0,0],[1,0],[1,1],[0,1]]"#;
    let meshed = render_plane(quad, checker, Path::new("."));
    for (x, y) in [(8, 24), (24, 8), (24, 24), (8, 8)] {
        let (a, b) = (at(x, y), meshed.pixels[(y * 32 + x) as usize]);
        assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-5), "mesh pixel ({x}, {y}): {b:?} vs {a:?}");
    }
}

/// PNG texels are decoded from sRGB (8 bits: 128 is 0.2158 linear), EXR
/// texels are linear, `raw` keeps 8-bit values as they are.
#[test]
fn bitmap_texels_are_decoded_from_srgb_or_kept_linear() {
    let dir = std::env::temp_dir().join(format!("niebla-textures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A uniform 4 x 3 PNG of sRGB (128, 64, 255).
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, 4, 3);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&[128u8, 64, 255].repeat(12)).unwrap();
    }
    std::fs::write(dir.join("uniform.png"), &bytes).unwrap();
    let srgb = |v: f32| if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) };
    let expected = [srgb(128.0 / 255.0), srgb(64.0 / 255.0), srgb(1.0)];
    let image = render_plane(RECTANGLE, r#"{"type": "bitmap", "file": "uniform.png"}"#, &dir);
    let p = image.pixels[16 * 32 + 16];
    for k in 0..3 {
        assert!((p[k] - expected[k] * L).abs() < 1e-5, "channel {k}: {} vs {}", p[k], expected[k] * L);
    }
    let raw = render_plane(RECTANGLE, r#"{"type": "bitmap", "file": "uniform.png", "raw": true}"#, &dir);
    assert!((raw.pixels[16 * 32 + 16][0] - 128.0 / 255.0 * L).abs() < 1e-5);
    // A linear EXR.
    let mut exr_image = Image::new(2, 2);
    for p in &mut exr_image.pixels {
        *p = niebla::color::Rgb::new(0.3, 0.6, 0.05);
    }
    niebla::film::write_exr(&exr_image, &dir.join("linear.exr")).unwrap();
    let image = render_plane(RECTANGLE, r#"{"type": "bitmap", "file": "linear.exr"}"#, &dir);
    let p = image.pixels[16 * 32 + 16];
    for (k, v) in [0.3, 0.6, 0.05].iter().enumerate() {
        assert!((p[k] - v * L).abs() < 1e-5, "channel {k}: {}", p[k]);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad textures are errors naming the file, the JSON path and the fault.
#[test]
fn bad_textures_are_errors() {
    let dir = std::env::temp_dir().join(format!("niebla-textures-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("broken.png"), b"not a png at all").unwrap();
    let cases = [
        (r#"{"type": "bitmap", "file": "missing.png"}"#, vec!["shapes[0].bsdf.reflectance.file", "missing.png"]),
        (r#"{"type": "bitmap", "file": "broken.png"}"#, vec!["shapes[0].bsdf.reflectance.file", "broken.png", "PNG"]),
        (r#"{"type": "bitmap", "file": "a.tga"}"#, vec!["shapes[0].bsdf.reflectance.file", "tga"]),
        (r#"{"type": "bitmap", "file": "a.png", "wrap": "tile"}"#, vec!["shapes[0].bsdf.reflectance.wrap", "tile"]),
        (
            r#"{"type": "bitmap", "file": "a.png", "filter": "cubic"}"#,
            vec!["shapes[0].bsdf.reflectance.filter", "cubic"],
        ),
        (
            r#"{"type": "bitmap", "file": "a.png", "to_uv": [[1, 0, 1e39], [0, 1, 0]]}"#,
            vec!["shapes[0].bsdf.reflectance.to_uv[0][2]", "finite"],
        ),
        (r#"{"type": "checkerboard", "to_uv": [[1, 0], [0, 1]]}"#, vec!["shapes[0].bsdf.reflectance.to_uv"]),
        (r#"{"type": "checkerboard", "color0": 1.5}"#, vec!["shapes[0].bsdf.reflectance.color0"]),
        (r#"{"type": "checkerboard", "scale": [0, 1]}"#, vec!["shapes[0].bsdf.reflectance.scale[0]"]),
        (r#"{"type": "marble"}"#, vec!["shapes[0].bsdf.reflectance", "marble"]),
        (r#""red""#, vec!["shapes[0].bsdf.reflectance", "texture"]),
    ];
    for (reflectance, expected) in cases {
        let text = format!(
            r#"{{"version": 1,
              "camera": {{"type": "perspective", "position": [0, 4, 0], "target": [0, 0, 0], "up": [0, 0, -1],
                         "width": 4, "height": 4}},
              "shapes": [{{{RECTANGLE}, "bsdf": {{"type": "diffuse", "reflectance": {reflectance}}}}}]}}"#
        );
        let message = match parse_scene_str(&text, "bad.json") {
            Err(e) => e.to_string(),
            Ok(desc) => match build_scene(&desc, "bad.json", &dir) {
                Err(e) => e.to_string(),
                Ok(_) => panic!("{reflectance}: accepted"),
            },
        };
        for part in expected {
            assert!(message.contains(part), "{reflectance}: {message:?} lacks {part:?}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A textured roughness where niebla takes only a constant one is an error
/// naming the field: roughplastic (its coating tables are precomputed per
/// roughness; Mitsuba 3 refuses it too), alone or inside a twosided, with
/// `alpha` or an anisotropic pair; a bad texture in `alpha`, `alpha_u` or
/// `alpha_v` (also of a twosided's side) is checked like a color texture.
#[test]
fn unsupported_textured_roughness_is_an_error() {
    let checker = r#"{"type": "checkerboard", "color0": 0.1, "color1": 0.4}"#;
    let cases = [
        (format!(r#"{{"type": "roughplastic", "alpha": {checker}}}"#), vec!["shapes[0].bsdf.alpha", "roughplastic"]),
        (
            format!(r#"{{"type": "twosided", "bsdf": {{"type": "roughplastic", "alpha": {checker}}}}}"#),
            vec!["shapes[0].bsdf.bsdf.alpha", "roughplastic", "Mitsuba 3 refuses"],
        ),
        (
            format!(r#"{{"type": "roughplastic", "alpha_u": {checker}, "alpha_v": 0.2}}"#),
            vec!["shapes[0].bsdf.alpha_u", "roughplastic is isotropic"],
        ),
        (
            format!(r#"{{"type": "roughconductor", "alpha": {checker}, "alpha_v": 0.2}}"#),
            vec!["shapes[0].bsdf.alpha", "not both"],
        ),
        (
            r#"{"type": "roughconductor", "alpha_u": 0.1, "alpha_v": "rough"}"#.to_string(),
            vec!["shapes[0].bsdf.alpha_v", "a number in (0, 1] or a texture"],
        ),
        (
            format!(r#"{{"type": "roughconductor", "alpha_u": {checker}, "alpha_v": 1.5}}"#),
            vec!["shapes[0].bsdf.alpha_v", "(0, 1]"],
        ),
        (
            r#"{"type": "roughdielectric", "alpha": {"type": "checkerboard", "scale": [0, 1]}}"#.to_string(),
            vec!["shapes[0].bsdf.alpha.scale[0]"],
        ),
        (
            r#"{"type": "roughdielectric", "alpha_u": 0.2, "alpha_v": {"type": "checkerboard", "scale": [0, 1]}}"#
                .to_string(),
            vec!["shapes[0].bsdf.alpha_v.scale[0]"],
        ),
        (
            r#"{"type": "roughdielectric", "alpha": {"type": "bitmap", "file": "missing.png"}}"#.to_string(),
            vec!["shapes[0].bsdf.alpha.file", "missing.png"],
        ),
        (
            r#"{"type": "twosided", "bsdf": [{"type": "diffuse"}, {"type": "roughconductor",
                "alpha_u": {"type": "bitmap", "file": "missing.png"}, "alpha_v": 0.3}]}"#
                .to_string(),
            vec!["shapes[0].bsdf.bsdf[1].alpha_u.file", "missing.png"],
        ),
    ];
    for (bsdf, expected) in cases {
        let text = format!(
            r#"{{"version": 1,
              "camera": {{"type": "perspective", "position": [0, 4, 0], "target": [0, 0, 0], "up": [0, 0, -1],
                         "width": 4, "height": 4}},
              "shapes": [{{{RECTANGLE}, "bsdf": {bsdf}}}]}}"#
        );
        let message = match parse_scene_str(&text, "bad.json") {
            Err(e) => e.to_string(),
            Ok(desc) => match build_scene(&desc, "bad.json", Path::new(".")) {
                Err(e) => e.to_string(),
                Ok(_) => panic!("{bsdf}: accepted"),
            },
        };
        for part in expected {
            assert!(message.contains(part), "{bsdf}: {message:?} lacks {part:?}");
        }
    }
}

/// JPEG texels are decoded from sRGB: a uniform image encoded at quality
/// 100 (a uniform color survives JPEG's DCT and quantization to within 2
/// levels of 255) reflects `srgb_to_linear(c) L` within that tolerance.
#[test]
fn jpeg_texels_are_decoded_from_srgb() {
    let dir = std::env::temp_dir().join(format!("niebla-textures-jpeg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("uniform.jpg");
    let pixels = [200u8, 120, 40].repeat(16 * 16);
    jpeg_encoder::Encoder::new_file(&path, 100).unwrap().encode(&pixels, 16, 16, jpeg_encoder::ColorType::Rgb).unwrap();
    let image = render_plane(RECTANGLE, r#"{"type": "bitmap", "file": "uniform.jpg"}"#, &dir);
    let p = image.pixels[16 * 32 + 16];
    let srgb = |v: f32| if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) };
    for (k, v) in [200.0f32, 120.0, 40.0].iter().enumerate() {
        let (lo, hi) = (srgb((v - 2.0) / 255.0) * L, srgb((v + 2.0) / 255.0) * L);
        assert!(p[k] >= lo && p[k] <= hi, "channel {k}: {} not in [{lo}, {hi}]", p[k]);
    }
    std::fs::remove_dir_all(&dir).ok();
}
