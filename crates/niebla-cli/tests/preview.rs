//! `niebla preview`: writes the requested number of frames (one rewritten
//! image or a numbered sequence), reports frames per second, and starts over
//! (precomputation included) when the scene file changes.

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn niebla() -> Command {
    Command::new(env!("CARGO_BIN_EXE_niebla"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("niebla-preview-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn fog_scene(dir: &std::path::Path) -> PathBuf {
    let source = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/fog.json");
    let path = dir.join("fog.json");
    std::fs::copy(source, &path).unwrap();
    path
}

#[test]
fn preview_writes_a_numbered_sequence_and_reports_fps() {
    let dir = temp_dir("sequence");
    let scene = fog_scene(&dir);
    let frames = dir.join("frames");
    let out = niebla()
        .args(["preview", scene.to_str().unwrap(), "--width", "24", "--height", "16", "--frames", "3"])
        .args(["--sequence", frames.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut names: Vec<String> =
        std::fs::read_dir(&frames).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    assert_eq!(names, ["frame_00000.png", "frame_00001.png", "frame_00002.png"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("frames/s"));
}

#[test]
fn preview_rerenders_after_the_scene_file_changes() {
    let dir = temp_dir("reload");
    let scene = fog_scene(&dir);
    let image = dir.join("frame.png");
    let mut child = niebla()
        .args(["preview", scene.to_str().unwrap(), "--width", "8", "--height", "8", "--frames", "100000"])
        .args(["--output", image.to_str().unwrap(), "--integrator", "single", "--threads", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first frame, then change the file (a brighter lamp) and
    // give the poll time to see a new modification time.
    let start = Instant::now();
    while !image.exists() && start.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(1100));
    let text = std::fs::read_to_string(&scene).unwrap().replace("[6.0, 5.0, 3.6]", "[12.0, 10.0, 7.2]");
    std::fs::write(&scene, text).unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    child.kill().unwrap();
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.matches("precomputed in").count(), 2, "{stderr}");
}
