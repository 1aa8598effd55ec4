//! Scene inputs the `scene` fuzz target (`fuzz/`, cargo-fuzz) found or that
//! guard what it checks, kept as regression tests on the stable toolchain:
//! every file in `tests/fuzz_regressions/` is parsed, validated and built
//! (under the fuzz target's memory limit, with its files folder replaced by
//! a scratch folder) without a panic, hang or unbounded allocation; deep
//! nesting gives an error, not a stack overflow; declared sizes over the
//! memory limit are refused before anything is allocated, naming the field
//! and the estimated size.

use std::path::{Path, PathBuf};

use niebla::scene::{build_scene_with_options, parse_scene_str, BuildOptions, SceneError};

/// The fuzz target's memory limit (`fuzz/fuzz_targets/scene.rs`).
const FUZZ_MAX_MEMORY: u64 = 64 << 20;

fn regression_inputs() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.file_name().is_some_and(|n| n != "README.md"))
        .collect();
    files.sort();
    files
}

/// What the fuzz target does with one input.
fn parse_and_build(text: &str, max_memory: u64) -> Result<(), SceneError> {
    let desc = parse_scene_str(text, "fuzz.json")?;
    let base = Path::new(env!("CARGO_TARGET_TMPDIR"));
    build_scene_with_options(&desc, "fuzz.json", base, &BuildOptions { max_memory }).map(|_| ())
}

/// Runs `f` on a thread with a 512 KiB stack, so that deep recursion would
/// show as a stack overflow (an abort) rather than pass on a big stack.
fn on_small_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new().stack_size(512 << 10).spawn(f).unwrap().join().unwrap()
}

#[test]
fn fuzzed_scene_inputs_give_errors_not_panics() {
    let inputs = regression_inputs();
    for path in inputs {
        let bytes = std::fs::read(&path).unwrap();
        let Ok(text) = String::from_utf8(bytes) else { continue };
        let name = path.display().to_string();
        on_small_stack(move || {
            if let Err(e) = parse_and_build(&text, FUZZ_MAX_MEMORY) {
                assert!(!e.to_string().is_empty(), "{name}: empty error");
            }
        });
    }
}

const CAMERA: &str =
    r#""camera": {"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 8, "height": 8}"#;

#[test]
fn nesting_ten_thousand_deep_is_an_error_not_a_stack_overflow() {
    let depth = 10_000;
    let arrays = format!("{}{}", "[".repeat(depth), "]".repeat(depth));
    let objects = format!("{}1{}", r#"{"a": "#.repeat(depth), "}".repeat(depth));
    let cases = [
        // At the top level.
        arrays.clone(),
        objects.clone(),
        // Where a scene value is expected, and under an unknown key.
        format!(r#"{{"version": 1, {CAMERA}, "media": {{"fog": {{"sigma_t": {arrays}, "albedo": 0.5}}}}}}"#),
        format!(r#"{{"version": 1, {CAMERA}, "extra": {objects}}}"#),
        // Unclosed, with a number out of range at the bottom (the scanner
        // that finds JSON paths walks the whole text).
        format!(r#"{{"version": 1, {CAMERA}, "media": {}1e999"#, "[{\"x\": ".repeat(depth)),
        // Duplicate keys deep down (the duplicate-key scanner).
        format!(r#"{{"version": 1, {CAMERA}, "x": {}{{"k": 1, "k": 2}}{}}}"#, "[".repeat(depth), "]".repeat(depth)),
    ];
    for text in cases {
        let err = on_small_stack(move || parse_scene_str(&text, "deep.json").unwrap_err());
        assert!(err.to_string().starts_with("deep.json: "), "{err}");
        assert!(err.message.contains("recursion limit exceeded"), "{err}");
    }
    // Just within serde_json's limit of 128 levels: the error is about the
    // value, with its path.
    let shallow = format!(
        r#"{{"version": 1, {CAMERA}, "media": {{"fog": {{"sigma_t": {}1e999{}, "albedo": 0.5}}}}}}"#,
        "[".repeat(100),
        "]".repeat(100)
    );
    let err = on_small_stack(move || parse_scene_str(&shallow, "deep.json").unwrap_err());
    assert!(err.path.starts_with("media.fog.sigma_t[0][0]"), "{err}");
    assert!(err.message.starts_with("number out of range"), "{err}");
}

/// A scene with one grid medium whose density is `density` and whose
/// majorant grid is `majorant` (a JSON fragment, possibly empty).
fn grid_scene(density: &str, extra: &str) -> String {
    format!(
        r#"{{"version": 1, {CAMERA},
            "media": {{"cloud": {{"type": "grid", "sigma_t": 1, "albedo": 0.9, "density": {density}{extra}}}}}}}"#
    )
}

fn build_error(text: &str, max_memory: u64) -> SceneError {
    parse_and_build(text, max_memory).unwrap_err()
}

#[test]
fn declared_sizes_over_the_memory_limit_are_refused_with_field_and_size() {
    // A procedural density of 2^27 voxels (512 MiB of f32).
    let text = grid_scene(r#"{"type": "procedural", "shape": "plume", "resolution": [1024, 512, 256]}"#, "");
    let err = build_error(&text, 256 << 20);
    assert_eq!(err.path, "media.cloud.density.resolution");
    assert_eq!(
        err.message,
        "the procedural density of 1024 x 512 x 256 voxels would need about 512 MiB, over the memory limit of 256 MiB"
    );
    // An inline grid (its values are already in memory; the grid copy counts).
    let text = grid_scene(
        r#"{"type": "grid", "dims": [4, 4, 4], "data": [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1]}"#,
        "",
    );
    let err = build_error(&text, 100);
    assert_eq!(err.path, "media.cloud.density.dims");
    assert!(err.message.starts_with("the 4 x 4 x 4 density grid would need about 256 B"), "{err}");
    // A majorant grid at the largest resolution the validator allows.
    let text = grid_scene(r#"{"type": "constant"}"#, r#", "majorant_resolution": 256"#);
    let err = build_error(&text, 64 << 20);
    assert_eq!(err.path, "media.cloud.majorant_resolution");
    assert!(err.message.contains("16777216 cells would need about 128 MiB"), "{err}");
    assert!(parse_and_build(&text, 256 << 20).is_ok());
}

#[test]
fn grid_files_are_checked_before_they_are_read() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz_regressions_files");
    std::fs::create_dir_all(&dir).unwrap();
    // A valid 64^3 float32 .npy (1 MiB of values).
    let header = b"{'descr': '<f4', 'fortran_order': False, 'shape': (64, 64, 64), }";
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    let pad = 64 - (10 + header.len() + 1) % 64;
    npy.extend(((header.len() + pad + 1) as u16).to_le_bytes());
    npy.extend(header);
    npy.extend(std::iter::repeat_n(b' ', pad));
    npy.push(b'\n');
    npy.extend(std::iter::repeat_n(0u8, 64 * 64 * 64 * 4));
    std::fs::write(dir.join("big.npy"), &npy).unwrap();
    let text = grid_scene(r#"{"type": "npy", "file": "big.npy"}"#, "");
    let build = |max_memory: u64| {
        let desc = parse_scene_str(&text, "npy.json").unwrap();
        build_scene_with_options(&desc, "npy.json", &dir, &BuildOptions { max_memory }).map(|_| ())
    };
    let err = build(1 << 20).unwrap_err();
    assert_eq!(err.path, "media.cloud.density.file");
    assert!(err.message.contains("big.npy: reading the 1 MiB file would need about 2 MiB"), "{err}");
    build(4 << 20).unwrap();

    // Devices and folders are not grid files (/dev/zero would never end).
    for (file, kind) in [("/dev/zero", "npy"), ("/dev/zero", "vdb"), (".", "vol")] {
        let text = grid_scene(&format!(r#"{{"type": "{kind}", "file": "{file}"}}"#), "");
        let desc = parse_scene_str(&text, "dev.json").unwrap();
        let err = build_scene_with_options(&desc, "dev.json", &dir, &BuildOptions::default()).unwrap_err();
        assert_eq!(err.path, "media.cloud.density.file", "{err}");
        assert!(err.message.ends_with("not a regular file"), "{err}");
    }
}

/// Not a regression test: sorts a fuzz corpus by what each input is (for
/// the fuzzing report). Run with
/// `NIEBLA_FUZZ_CORPUS=fuzz/corpus/scene cargo test -p niebla --test fuzz_regressions -- --ignored --nocapture`.
#[test]
#[ignore]
fn classify_scene_corpus() {
    let Ok(dir) = std::env::var("NIEBLA_FUZZ_CORPUS") else { return };
    let mut counts = std::collections::BTreeMap::<&str, usize>::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        let class = match String::from_utf8(bytes) {
            Err(_) => "not UTF-8",
            Ok(text) => match parse_scene_str(&text, "c.json") {
                Err(e) if e.message.starts_with("invalid JSON") => "malformed JSON",
                Err(e) if e.message.contains("invalid type") || e.message.contains("expected a JSON object") => {
                    "wrong types"
                }
                Err(e)
                    if e.message.contains("unknown")
                        || e.message.contains("missing field")
                        || e.message.contains("duplicate key") =>
                {
                    "unknown, missing or duplicate keys"
                }
                Err(_) => "bad numbers and values",
                Ok(desc) => {
                    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/files");
                    let options = BuildOptions { max_memory: FUZZ_MAX_MEMORY };
                    match build_scene_with_options(&desc, "c.json", &base, &options) {
                        Ok(_) => "valid (built)",
                        Err(e) if e.message.contains("memory limit") => "huge sizes",
                        Err(e) if e.path.ends_with(".file") || e.path.ends_with(".grid") => "bad files",
                        Err(_) => "other build errors",
                    }
                }
            },
        };
        *counts.entry(class).or_default() += 1;
    }
    println!("{dir}: {counts:#?}");
}
