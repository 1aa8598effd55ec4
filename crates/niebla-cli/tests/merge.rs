//! `niebla render --first-sample N --spp M` and `niebla merge`: renders of
//! disjoint sample ranges merge to the image (and sums) of one render of
//! all the samples, bit for bit; overlapping ranges and renders of another
//! scene, seed or integrator are refused with the file and the reason.

use std::path::{Path, PathBuf};
use std::process::Command;

use niebla::film::{read_checkpoint_full, Checkpoint, Image};

const SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "width": 21, "height": 13},
  "render": {"integrator": {"type": "volpath"}, "spp": 4, "seed": 11},
  "media": {"fog": {"sigma_a": 0.05, "sigma_s": 1.5, "phase": {"type": "hg", "g": 0.4}}},
  "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "interior": "fog"}],
  "lights": [{"type": "point", "position": [1, 3, 1], "intensity": 10}, {"type": "constant", "radiance": 0.1}]
}"#;

fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    dir
}

fn niebla(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_niebla")).current_dir(dir).args(args).output().unwrap()
}

fn run_ok(dir: &Path, args: &[&str]) -> String {
    let out = niebla(dir, args);
    assert!(out.status.success(), "niebla {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn run_err(dir: &Path, args: &[&str]) -> String {
    let out = niebla(dir, args);
    assert!(!out.status.success(), "niebla {args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().map(|p| p.0.map(f32::to_bits)).collect()
}

fn read(dir: &Path, name: &str) -> Checkpoint {
    read_checkpoint_full(&dir.join(name)).unwrap()
}

#[test]
fn halves_merge_to_the_whole_render_bit_for_bit() {
    let dir = temp_dir("cli_merge_halves");
    run_ok(&dir, &["render", "fog.json", "--spp", "10", "-o", "whole.exr", "--quiet"]);
    // Halves that do not split at a pass boundary, on other thread counts,
    // given to merge in reverse order.
    run_ok(&dir, &["render", "fog.json", "--spp", "3", "-o", "a.exr", "--quiet", "--threads", "1"]);
    run_ok(&dir, &["render", "fog.json", "--first-sample", "3", "--spp", "7", "-o", "b.exr", "--quiet"]);
    let b = read(&dir, "b.exr");
    assert_eq!((b.info.spp, b.info.ranges.clone()), (7, vec![(3, 10)]));
    let printed = run_ok(&dir, &["merge", "b.exr", "a.exr", "-o", "merged.exr"]);
    assert!(printed.contains("10 spp (samples 0..10)"), "{printed}");

    let (whole, merged) = (read(&dir, "whole.exr"), read(&dir, "merged.exr"));
    assert_eq!(merged.info, whole.info);
    assert!(bits(&merged.image) == bits(&whole.image), "merged image differs from the whole render");
    assert_eq!(merged.sums, whole.sums);
    assert!(whole.image.mean().max_channel() > 0.0);
    // The halves' means differ from the whole's: the test compares real data.
    assert_ne!(bits(&read(&dir, "a.exr").image), bits(&whole.image));

    // The merged file continues like the whole render does.
    run_ok(&dir, &["render", "fog.json", "--resume", "merged.exr", "--spp", "16", "-o", "more.exr", "--quiet"]);
    run_ok(&dir, &["render", "fog.json", "--spp", "16", "-o", "straight16.exr", "--quiet"]);
    assert!(bits(&read(&dir, "more.exr").image) == bits(&read(&dir, "straight16.exr").image));
}

#[test]
fn mismatched_or_overlapping_inputs_are_refused_with_the_file_and_why() {
    let dir = temp_dir("cli_merge_refused");
    run_ok(&dir, &["render", "fog.json", "--spp", "4", "-o", "a.exr", "--quiet"]);
    run_ok(&dir, &["render", "fog.json", "--first-sample", "2", "--spp", "4", "-o", "over.exr", "--quiet"]);
    run_ok(
        &dir,
        &["render", "fog.json", "--first-sample", "4", "--spp", "4", "--seed", "3", "-o", "seed.exr", "--quiet"],
    );
    let other = SCENE.replace("\"intensity\": 10", "\"intensity\": 12");
    std::fs::write(dir.join("other.json"), other).unwrap();
    run_ok(&dir, &["render", "other.json", "--first-sample", "4", "--spp", "4", "-o", "scene.exr", "--quiet"]);
    run_ok(
        &dir,
        &["render", "fog.json", "--first-sample", "4", "--spp", "4", "--integrator", "single", "-o", "single.exr"],
    );

    let err = run_err(&dir, &["merge", "a.exr", "over.exr", "-o", "out.exr"]);
    assert!(err.contains("over.exr: its samples 2..6 overlap samples 0..4 of a.exr"), "{err}");
    let err = run_err(&dir, &["merge", "a.exr", "seed.exr", "-o", "out.exr"]);
    assert!(err.contains("seed.exr: was rendered with seed 3, a.exr with seed 11"), "{err}");
    let err = run_err(&dir, &["merge", "a.exr", "scene.exr", "-o", "out.exr"]);
    assert!(err.contains("scene.exr: was rendered from another scene"), "{err}");
    let err = run_err(&dir, &["merge", "a.exr", "single.exr", "-o", "out.exr"]);
    assert!(err.contains("single.exr: was rendered with integrator single"), "{err}");
    let err = run_err(&dir, &["merge", "a.exr", "missing.exr", "-o", "out.exr"]);
    assert!(err.contains("missing.exr") && err.contains("not found"), "{err}");
    // Nothing was written by the refused merges.
    assert!(!dir.join("out.exr").exists());
}
