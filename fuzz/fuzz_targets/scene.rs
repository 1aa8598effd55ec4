//! Scene files: JSON parsing, validation (with the JSON-path scanner on
//! errors) and the build into a render-ready scene, under a memory limit.
//! Relative file names resolve against `fuzz/files/` (small valid `.npy`,
//! `.vol`, `.vdb`, `.csv` and `.exr` files written by `seed_corpus.py`).
#![no_main]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use niebla::scene::{build_scene_with_options, parse_scene_str, BuildOptions};

/// Memory a fuzzed scene may ask for: enough for every valid small scene,
/// little enough that a refused one is found fast.
const MAX_MEMORY: u64 = 64 << 20;

fn files_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("files"))
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(desc) = parse_scene_str(text, "fuzz.json") else { return };
    let _ = build_scene_with_options(&desc, "fuzz.json", files_dir(), &BuildOptions { max_memory: MAX_MEMORY });
});
