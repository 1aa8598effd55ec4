//! `niebla render --width` sizes images as `niebla bench interactive` sizes
//! its error images, and `bench interactive --reference-exr` refuses cached
//! references of another size, scene or integrator, or two of one seed,
//! naming the file and the reason (before rendering anything).

use std::path::{Path, PathBuf};
use std::process::Command;

use niebla::film::read_checkpoint_full;

const SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "width": 21, "height": 13},
  "render": {"integrator": {"type": "hegeman"}, "spp": 4, "seed": 11},
  "media": {"fog": {"sigma_a": 0.05, "sigma_s": 1.5, "phase": {"type": "hg", "g": 0.4}}},
  "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "interior": "fog"}],
  "lights": [{"type": "point", "position": [1, 3, 1], "intensity": 10}, {"type": "constant", "radiance": 0.1}]
}"#;

fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    // Another scene: the same but for a brighter light.
    std::fs::write(dir.join("other.json"), SCENE.replace("\"intensity\": 10", "\"intensity\": 20")).unwrap();
    dir
}

fn niebla(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_niebla")).current_dir(dir).args(args).output().unwrap()
}

fn run_ok(dir: &Path, args: &[&str]) {
    let out = niebla(dir, args);
    assert!(out.status.success(), "niebla {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
}

fn run_err(dir: &Path, args: &[&str]) -> String {
    let out = niebla(dir, args);
    assert!(!out.status.success(), "niebla {args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A volpath reference render of `scene` at `width` with `seed`.
fn reference(dir: &Path, scene: &str, width: u32, seed: u64, out: &str) {
    let (width, seed) = (width.to_string(), seed.to_string());
    run_ok(
        dir,
        &[
            "render",
            scene,
            "--width",
            &width,
            "--integrator",
            "volpath",
            "--max-depth",
            "256",
            "--spp",
            "2",
            "--seed",
            &seed,
            "--quiet",
            "-o",
            out,
        ],
    );
}

#[test]
fn render_width_keeps_the_aspect_like_the_bench() {
    let dir = temp_dir("cli_bench_reference_width");
    reference(&dir, "fog.json", 12, 1, "w12.exr");
    let c = read_checkpoint_full(&dir.join("w12.exr")).unwrap();
    // 12 * 13 / 21 = 7.43 -> 7 rows; the header still names the scene file.
    assert_eq!((c.image.width, c.image.height), (12, 7));
    assert_eq!(niebla::render::split_recorded_key(&c.info.integrator).0, "volpath(max_depth=256)");
    let err = run_err(&dir, &["render", "fog.json", "--width", "0", "-o", "x.exr"]);
    assert!(err.contains("--width") && err.contains("between 1 and 16384"), "{err}");
}

#[test]
fn wrong_references_are_refused_with_the_file_and_why() {
    let dir = temp_dir("cli_bench_reference_refused");
    reference(&dir, "fog.json", 12, 101, "a.exr");
    reference(&dir, "fog.json", 12, 101, "same_seed.exr");
    reference(&dir, "fog.json", 10, 102, "small.exr");
    reference(&dir, "other.json", 12, 102, "other.exr");
    run_ok(&dir, &["render", "fog.json", "--width", "12", "--spp", "1", "--quiet", "-o", "hegeman.exr"]);
    let bench = |files: &[&str]| {
        let mut args = vec!["bench", "interactive", "fog.json", "--error-width", "12", "--frames", "1"];
        for f in files {
            args.extend(["--reference-exr", f]);
        }
        run_err(&dir, &args)
    };
    let err = bench(&["small.exr"]);
    assert!(err.contains("small.exr: is 10 x 6 pixels") && err.contains("--width 12"), "{err}");
    let err = bench(&["a.exr", "same_seed.exr"]);
    assert!(err.contains("same seed 101") && err.contains("independent"), "{err}");
    let err = bench(&["other.exr"]);
    assert!(err.contains("other.exr: was rendered from a scene of hash") && err.contains("fog.json ("), "{err}");
    let err = bench(&["hegeman.exr"]);
    assert!(err.contains("hegeman.exr: was rendered with hegeman(") && err.contains("volpath(max_depth=256)"), "{err}");
    let err = bench(&["missing.exr"]);
    assert!(err.contains("--reference-exr") && err.contains("missing.exr"), "{err}");
}
