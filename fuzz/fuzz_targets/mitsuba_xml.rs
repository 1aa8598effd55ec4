//! Mitsuba 3 XML scenes: XML syntax, `<default>`/`$name` substitution,
//! includes, properties, transforms and the conversion to niebla's scene
//! description, then niebla's parser and validation of the result. Relative
//! file names (meshes, `.vol` grids, included XML) resolve against
//! `fuzz/files/`. Good seeds: `scenes/mitsuba/*.xml`.
#![no_main]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use niebla::scene::mitsuba::import_mitsuba_str;
use niebla::scene::parse_scene_str;

fn files_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("files"))
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let defines = [("spp".to_string(), "4".to_string())];
    let Ok(import) = import_mitsuba_str(text, "fuzz.xml", files_dir(), &defines) else { return };
    let _ = parse_scene_str(&import.scene.to_string(), "fuzz.xml (converted)");
});
