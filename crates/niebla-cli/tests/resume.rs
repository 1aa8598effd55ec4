//! Crash-safe output and `--resume`, with real child processes: a render
//! killed with SIGKILL leaves a complete checkpoint EXR (or none), and
//! resuming it gives the image of a render that was never stopped, bit for
//! bit. Also: memory limits refuse a scene before rendering, naming the
//! field and the estimated size.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use niebla::film::{read_checkpoint, Image};

const SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "width": 40, "height": 30},
  "render": {"integrator": {"type": "volpath"}, "spp": 4, "seed": 11},
  "media": {"fog": {"sigma_a": 0.05, "sigma_s": 1.5, "phase": {"type": "hg", "g": 0.4}}},
  "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "interior": "fog"}],
  "lights": [{"type": "point", "position": [1, 3, 1], "intensity": 10}, {"type": "constant", "radiance": 0.1}]
}"#;

fn niebla() -> Command {
    Command::new(env!("CARGO_BIN_EXE_niebla"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run_ok(dir: &Path, args: &[&str]) -> String {
    let out = niebla().current_dir(dir).args(args).output().unwrap();
    assert!(out.status.success(), "niebla {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn run_err(dir: &Path, args: &[&str]) -> String {
    let out = niebla().current_dir(dir).args(args).output().unwrap();
    assert!(!out.status.success(), "niebla {args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().map(|p| p.0.map(f32::to_bits)).collect()
}

#[test]
fn killed_render_resumes_to_the_uninterrupted_image() {
    let dir = temp_dir("cli_resume");
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();

    // A long render, killed as soon as its first checkpoint is in place.
    let mut child = niebla()
        .current_dir(&dir)
        .args(["render", "fog.json", "-o", "killed.exr", "--spp", "1000000", "--quiet", "--threads", "2"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let checkpoint = dir.join("killed.exr");
    let start = Instant::now();
    while !checkpoint.exists() {
        assert!(start.elapsed() < Duration::from_secs(120), "no checkpoint after 120 s");
        assert!(child.try_wait().unwrap().is_none(), "the render ended before it was killed");
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap(); // SIGKILL on Unix
    child.wait().unwrap();

    // The checkpoint is a complete EXR with its metadata.
    let (image, info) = read_checkpoint(&checkpoint).expect("the killed render's checkpoint decodes");
    assert_eq!((image.width, image.height), (40, 30));
    assert!(info.spp >= 1 && info.spp.is_power_of_two(), "checkpoint at {} spp", info.spp);
    assert_eq!(info.seed, 11);
    assert!(image.pixels.iter().all(|p| p.is_finite()));

    // Resume to a few passes more, and render the same count in one go with
    // another thread count.
    let target = (info.spp * 4).to_string();
    let resumed = run_ok(
        &dir,
        &["render", "fog.json", "-o", "killed.exr", "--spp", &target, "--resume", "killed.exr", "--quiet"],
    );
    assert!(resumed.contains(&format!("at {target} spp")), "{resumed}");
    run_ok(&dir, &["render", "fog.json", "-o", "straight.exr", "--spp", &target, "--quiet", "--threads", "1"]);
    let (a, a_info) = read_checkpoint(&checkpoint).unwrap();
    let (b, b_info) = read_checkpoint(&dir.join("straight.exr")).unwrap();
    assert_eq!(a_info, b_info);
    assert_eq!(a_info.spp.to_string(), target);
    assert!(bits(&a) == bits(&b), "resumed image differs from the uninterrupted one");
    assert!(a.mean().max_channel() > 0.0);

    // A checkpoint of another scene, seed or integrator is refused.
    std::fs::write(dir.join("other.json"), SCENE.replace("\"seed\": 11", "\"seed\": 12")).unwrap();
    let err = run_err(&dir, &["render", "other.json", "-o", "x.exr", "--spp", "64", "--resume", "killed.exr"]);
    assert!(err.contains("was rendered from another scene"), "{err}");
    let err =
        run_err(&dir, &["render", "fog.json", "-o", "x.exr", "--spp", "64", "--resume", "killed.exr", "--seed", "3"]);
    assert!(err.contains("seed 11, not --seed 3"), "{err}");
    let err = run_err(
        &dir,
        &["render", "fog.json", "-o", "x.exr", "--spp", "64", "--resume", "killed.exr", "--integrator", "single"],
    );
    assert!(err.contains("was rendered with volpath(max_depth=1024), not single("), "{err}");
    // ... and so is one of the other sampler.
    let other = if read_checkpoint(&dir.join("killed.exr")).unwrap().1.integrator.contains("; sampler=sobol") {
        ["independent", "the sobol sampler, not independent"]
    } else {
        ["sobol", "the independent sampler, not sobol"]
    };
    let err = run_err(
        &dir,
        &["render", "fog.json", "-o", "x.exr", "--spp", "64", "--resume", "killed.exr", "--sampler", other[0]],
    );
    assert!(err.contains(&format!("was rendered with {}", other[1])), "{err}");
    // Nothing but the outputs is left behind (no temporary files).
    let mut names: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.retain(|n| !n.starts_with(".killed.exr.")); // the killed process's own temporary file, if any
    names.sort();
    assert_eq!(names, ["fog.json", "killed.exr", "other.json", "straight.exr"]);
}

/// `--no-checkpoints` (the benchmarks' way of timing a render without its
/// image writes) gives the same bits as a render that checkpoints, writes
/// the one output file and nothing beside it, and reports the process CPU
/// seconds before the final write.
#[test]
fn render_without_checkpoints_gives_the_same_image() {
    let dir = temp_dir("cli_no_checkpoints");
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    let line =
        run_ok(&dir, &["render", "fog.json", "-o", "once.exr", "--spp", "16", "--no-checkpoints", "--threads", "2"]);
    assert!(line.contains("at 16 spp") && line.contains(", process CPU "), "{line}");
    run_ok(&dir, &["render", "fog.json", "-o", "checkpointed.exr", "--spp", "16", "--quiet", "--threads", "1"]);
    let (a, a_info) = read_checkpoint(&dir.join("once.exr")).unwrap();
    let (b, b_info) = read_checkpoint(&dir.join("checkpointed.exr")).unwrap();
    assert_eq!(a_info, b_info);
    assert!(bits(&a) == bits(&b), "the image without checkpoints differs");
    let mut files: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    files.sort();
    assert_eq!(files, ["checkpointed.exr", "fog.json", "once.exr"]);
}

#[test]
fn memory_limit_refuses_large_images_and_grids_before_rendering() {
    let dir = temp_dir("cli_max_memory");
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    // 40 x 30 pixels need about 338 KiB of image, exact sums and output buffers.
    let err = run_err(&dir, &["render", "fog.json", "-o", "x.exr", "--max-memory", "64K"]);
    assert!(err.contains("camera.width, camera.height: rendering 40 x 30 pixels would need about 338 KiB"), "{err}");
    assert!(err.contains("memory limit of 64 KiB"), "{err}");
    run_ok(&dir, &["render", "fog.json", "-o", "x.exr", "--max-memory", "1M", "--spp", "1", "--quiet"]);

    let cloud = SCENE.replace(
        r#""fog": {"sigma_a": 0.05, "sigma_s": 1.5, "phase": {"type": "hg", "g": 0.4}}"#,
        r#""fog": {"type": "grid", "sigma_t": 1, "albedo": 0.9,
                   "density": {"type": "procedural", "shape": "cloud", "resolution": 256}}"#,
    );
    std::fs::write(dir.join("cloud.json"), cloud).unwrap();
    let err = run_err(&dir, &["render", "cloud.json", "-o", "x.exr", "--max-memory", "32M"]);
    assert!(err.contains("media.fog.density.resolution: the procedural density of 256 x 256 x 256 voxels"), "{err}");
    assert!(err.contains("would need about 64 MiB"), "{err}");
    assert!(err.contains("--max-memory"), "{err}");
    let err = run_err(&dir, &["render", "fog.json", "--max-memory", "lots"]);
    assert!(err.contains("expected a size such as 8G"), "{err}");
    assert!(!dir.join("x.exr").exists() || dir.join("x.exr").metadata().unwrap().len() > 0);
}

#[test]
fn memory_limit_refuses_large_photon_maps_and_lattices_before_precomputing() {
    let dir = temp_dir("cli_precompute_memory");
    // A photon count whose map cannot fit: refused at once, nothing written.
    let photons = SCENE.replace(r#""type": "volpath""#, r#""type": "photon", "photons": 4000000000"#);
    std::fs::write(dir.join("photons.json"), photons).unwrap();
    let err = run_err(&dir, &["render", "photons.json", "-o", "x.exr", "--max-memory", "1G"]);
    assert!(err.contains("photons.json: render.integrator.photons: the photon map: 4000000000 photons"), "{err}");
    assert!(err.contains("raise --max-memory"), "{err}");
    assert!(!dir.join("x.exr").exists());
    // The same photon count per ppm pass.
    let ppm = SCENE.replace(r#""type": "volpath""#, r#""type": "ppm", "photons": 4000000000"#);
    std::fs::write(dir.join("ppm.json"), ppm).unwrap();
    let err = run_err(&dir, &["render", "ppm.json", "-o", "x.exr", "--max-memory", "1G"]);
    assert!(err.contains("render.integrator.photons: each pass's photon map"), "{err}");
    // A Hegeman lattice of 512^3 nodes per light (2 lights): 3 GiB.
    let cloud = SCENE
        .replace(
            r#""fog": {"sigma_a": 0.05, "sigma_s": 1.5, "phase": {"type": "hg", "g": 0.4}}"#,
            r#""fog": {"type": "grid", "sigma_t": 1, "albedo": 0.9,
                       "density": {"type": "procedural", "shape": "cloud", "resolution": 16}}"#,
        )
        .replace(r#""type": "volpath""#, r#""type": "hegeman", "resolution": 512"#);
    std::fs::write(dir.join("cloud.json"), cloud).unwrap();
    let err = run_err(&dir, &["render", "cloud.json", "-o", "x.exr", "--max-memory", "1G"]);
    assert!(err.contains("cloud.json: render.integrator.resolution: 2 light volume(s) of up to 512^3 nodes"), "{err}");
    assert!(err.contains("would need about 3 GiB"), "{err}");
    let err =
        run_err(&dir, &["preview", "cloud.json", "--integrator", "hegeman", "--frames", "1", "--max-memory", "1G"]);
    assert!(err.contains("render.integrator.resolution"), "{err}");
    // Within the limit the render runs.
    let small =
        std::fs::read_to_string(dir.join("cloud.json")).unwrap().replace(r#""resolution": 512"#, r#""resolution": 16"#);
    std::fs::write(dir.join("small.json"), small).unwrap();
    run_ok(&dir, &["render", "small.json", "-o", "x.exr", "--max-memory", "1G", "--spp", "1", "--quiet"]);
    assert!(dir.join("x.exr").exists());
}
