//! Scene files rendered: parse, validate and build as the `scene` target
//! does, then render a 3 x 2 crop at 1 sample per pixel with the scene's
//! integrator (path depth capped at 8), and require finite pixels. Build
//! with `cargo fuzz run -a render` so that the render loop's
//! `debug_assert!`s on non-finite samples are on.
#![no_main]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use niebla::integrator::IntegratorSettings;
use niebla::render::{render, RenderOptions};
use niebla::scene::{build_scene_with_options, parse_scene_str, BuildOptions};

const MAX_MEMORY: u64 = 64 << 20;

fn files_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("files"))
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(desc) = parse_scene_str(text, "fuzz.json") else { return };
    let options = BuildOptions { max_memory: MAX_MEMORY };
    let Ok(mut built) = build_scene_with_options(&desc, "fuzz.json", files_dir(), &options) else { return };
    built.scene.camera.width = built.scene.camera.width.min(3);
    built.scene.camera.height = built.scene.camera.height.min(2);
    let mut settings = built.settings.integrator;
    if let IntegratorSettings::VolPath { max_depth, .. } = &mut settings {
        *max_depth = (*max_depth).min(8);
    }
    let options = RenderOptions { spp: 1, seed: 1, first_sample: 0, threads: Some(1) };
    let image = render(&built.scene, &settings, &options, &|_, _| {}, None).unwrap();
    assert!(image.pixels.iter().all(|p| p.is_finite()), "non-finite pixel in {:?}", image.pixels);
});
