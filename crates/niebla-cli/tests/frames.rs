//! Sequences (`niebla render --frames`): 24 VDB frames written by the
//! reference library (python3-openvdb) render to the images of each frame's
//! scene rendered alone, bit for bit, also when the sequence is killed and
//! started again (finished frames skipped); keyframed cameras and lights
//! take the linear interpolation of their keyframes; missing frames and bad
//! patterns or ranges are refused before anything renders.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use niebla::film::{read_checkpoint, Image};
use niebla::scene::{build_scene_cached, parse_scene_frame, BuildOptions, CameraDesc, LightDesc, SceneCache};

/// Writes `smoke.0001.vdb` .. `smoke.0024.vdb` into the folder argv[1]: a
/// `density` block of 6^3 voxels (voxel 0.1) that moves one voxel along x
/// per frame and whose density grows with the frame.
const GENERATOR: &str = r#"
import os, sys
os.environ.setdefault("OPENVDB_DISABLE_DELAYED_LOAD", "1")
import pyopenvdb as vdb
for f in range(1, 25):
    g = vdb.FloatGrid(0.0); g.name = "density"
    g.transform = vdb.createLinearTransform(voxelSize=0.1)
    x0 = -12 + f
    g.fill((x0, -3, -3), (x0 + 5, 2, 2), 2.0 + 0.25 * f, True)
    vdb.write(os.path.join(sys.argv[1], "smoke.%04d.vdb" % f), grids=[g])
"#;

/// A floor (one quad, OBJ) that no frame changes: read once per sequence.
const FLOOR: &str = "v -3 -0.5 -3\nv 3 -0.5 -3\nv 3 -0.5 3\nv -3 -0.5 3\nf 1 4 3 2\n";

/// The sequence scene: `FILE` is the density file name.
const SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 0.4, 3], "target": [0, 0, 0], "fov_y": 50, "width": 16, "height": 16},
  "render": {"integrator": {"type": "volpath"}, "spp": 2, "seed": 3},
  "media": {"smoke": {"type": "grid", "density": {"type": "vdb", "file": "FILE"}, "sigma_t": 4, "albedo": 0.8}},
  "shapes": [
    {"type": "box", "min": [-1.5, -0.5, -0.5], "max": [1.5, 0.5, 0.5], "interior": "smoke"},
    {"type": "mesh", "file": "floor.obj", "bsdf": {"type": "diffuse", "reflectance": 0.5}}
  ],
  "lights": [{"type": "point", "position": [1, 2, 2], "intensity": 8}, {"type": "constant", "radiance": 0.2}]
}"#;

fn niebla() -> Command {
    Command::new(env!("CARGO_BIN_EXE_niebla"))
}

/// The folder with the 24 frames, generated once per test run.
fn vdb_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("frames_vdbs");
        if dir.join("smoke.0024.vdb").exists() {
            return dir;
        }
        let scratch = dir.with_extension(format!("tmp{}", std::process::id()));
        std::fs::create_dir_all(&scratch).unwrap();
        let out = Command::new("/usr/bin/python3")
            .args(["-c", GENERATOR])
            .arg(&scratch)
            .output()
            .expect("run /usr/bin/python3 (install python3-openvdb)");
        assert!(out.status.success(), "VDB generator failed:\n{}", String::from_utf8_lossy(&out.stderr));
        if std::fs::rename(&scratch, &dir).is_err() {
            assert!(dir.join("smoke.0024.vdb").exists());
            let _ = std::fs::remove_dir_all(&scratch);
        }
        dir
    })
}

/// A fresh folder holding the frames (links), the floor and `seq.json`
/// whose density file is `file`.
fn scene_dir(name: &str, file: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for f in 1..=24 {
        let vdb = format!("smoke.{f:04}.vdb");
        std::fs::copy(vdb_dir().join(&vdb), dir.join(&vdb)).unwrap();
    }
    std::fs::write(dir.join("floor.obj"), FLOOR).unwrap();
    std::fs::write(dir.join("seq.json"), SCENE.replace("FILE", file)).unwrap();
    dir
}

fn run(dir: &Path, args: &[&str]) -> std::process::Output {
    niebla().current_dir(dir).args(args).output().unwrap()
}

fn run_ok(dir: &Path, args: &[&str]) -> String {
    let out = run(dir, args);
    assert!(out.status.success(), "niebla {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn run_err(dir: &Path, args: &[&str]) -> String {
    let out = run(dir, args);
    assert!(!out.status.success(), "niebla {args:?} succeeded:\n{}", String::from_utf8_lossy(&out.stdout));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn bits(path: &Path) -> Vec<[u32; 3]> {
    let (image, _): (Image, _) = read_checkpoint(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image.pixels.iter().map(|p| p.0.map(f32::to_bits)).collect()
}

#[test]
fn killed_vdb_sequence_resumes_to_the_images_of_each_frame_rendered_alone() {
    let dir = scene_dir("frames_sequence", "smoke.####.vdb");
    let args = ["render", "seq.json", "--frames", "1-24", "-o", "out/f.####.exr", "--quiet", "--threads", "2"];
    std::fs::create_dir_all(dir.join("out")).unwrap();

    // Started, and killed once its second frame is finished.
    let mut child = niebla()
        .current_dir(&dir)
        .args(args)
        .args(["--spp", "24"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !dir.join("out/f.0002.exr").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no frame finished within 60 s");
        assert!(child.try_wait().unwrap().is_none(), "the sequence ended before it was killed");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let finished: Vec<u32> = (1..=24).filter(|f| dir.join(format!("out/f.{f:04}.exr")).exists()).collect();
    assert!(finished.len() < 24, "all frames finished before the kill; the test needs slower frames");
    let before: Vec<Vec<u8>> =
        finished.iter().map(|f| std::fs::read(dir.join(format!("out/f.{f:04}.exr"))).unwrap()).collect();

    // Started again: the finished frames are skipped (and left as they were), the rest rendered.
    let stdout = run_ok(&dir, &[&args[..], &["--spp", "24"]].concat());
    for (f, bytes) in finished.iter().zip(&before) {
        assert!(stdout.contains(&format!("frame {f}: skipped, out/f.{f:04}.exr exists")), "{stdout}");
        assert_eq!(&std::fs::read(dir.join(format!("out/f.{f:04}.exr"))).unwrap(), bytes, "frame {f} was rewritten");
    }
    let rendered = 24 - finished.len();
    assert!(stdout.contains(&format!("rendered {rendered} of 24 frames")), "{stdout}");
    assert_eq!(stdout.matches(": rendered 16x16 at 24 spp").count(), rendered, "{stdout}");

    // Each frame's scene alone (the file name written out) gives the same image, bit for bit.
    for f in 1..=24u32 {
        let alone = format!("alone{f}.json");
        std::fs::write(dir.join(&alone), SCENE.replace("FILE", &format!("smoke.{f:04}.vdb"))).unwrap();
        let out = format!("alone{f}.exr");
        run_ok(&dir, &["render", &alone, "-o", &out, "--quiet", "--spp", "24"]);
        assert_eq!(bits(&dir.join(format!("out/f.{f:04}.exr"))), bits(&dir.join(&out)), "frame {f}");
    }
    // The frames differ (the block moves and thickens), so the comparison is not vacuous.
    assert_ne!(bits(&dir.join("out/f.0001.exr")), bits(&dir.join("out/f.0024.exr")));

    // Nothing left to do; --overwrite renders a frame again, to the same image.
    let stdout = run_ok(&dir, &[&args[..], &["--spp", "24"]].concat());
    assert!(stdout.contains("rendered 0 of 24 frames"), "{stdout}");
    let stdout = run_ok(
        &dir,
        &["render", "seq.json", "--frames", "5", "-o", "out/f.####.exr", "--spp", "24", "--overwrite", "--quiet"],
    );
    assert!(stdout.contains("frame 5: rendered 16x16"), "{stdout}");
    assert_eq!(bits(&dir.join("out/f.0005.exr")), bits(&dir.join("alone5.exr")));
}

#[test]
fn a_missing_frame_is_named_before_anything_renders() {
    let dir = scene_dir("frames_missing", "smoke.{frame:04}.vdb");
    std::fs::remove_file(dir.join("smoke.0013.vdb")).unwrap();
    let err = run_err(&dir, &["render", "seq.json", "--frames", "1-24", "-o", "f.####.exr"]);
    assert!(
        err.contains("seq.json: frame 13: media.smoke.density.file:")
            && err.contains("smoke.0013.vdb not found (the first missing file of frames 1-24; nothing was rendered)"),
        "{err}"
    );
    assert!(!dir.join("f.0001.exr").exists(), "a frame was rendered before the check");
    // Beyond the frames on disk: the first missing is the first after them.
    let err = run_err(&dir, &["render", "seq.json", "--frames", "20-30:5", "-o", "f.####.exr"]);
    assert!(err.contains("frame 25: media.smoke.density.file:") && err.contains("smoke.0025.vdb not found"), "{err}");
}

#[test]
fn bad_ranges_and_patterns_are_refused_with_what_was_expected() {
    let dir = scene_dir("frames_bad", "smoke.####.vdb");
    let cases: &[(&[&str], &str)] = &[
        (&["--frames", "5-1", "-o", "f.####.exr"], "--frames: \"5-1\": the first frame (5) is after the last (1)"),
        (&["--frames", "1-4:0", "-o", "f.####.exr"], "--frames: \"1-4:0\": the step must be at least 1"),
        (&["--frames", "one-4", "-o", "f.####.exr"], "the first frame must be a whole number >= 0, got \"one\""),
        (&["--frames", "1-4"], "--frames: needs -o with a frame pattern"),
        (&["--frames", "1-4", "-o", "f.exr"], "-o: f.exr: with --frames the output needs a frame pattern"),
        (&["--frames", "1-4", "-o", "f.{frame:4}.exr"], "-o: `{frame:4}`: expected {frame} or {frame:0N}"),
        (&["--frames", "1-4", "-o", "f.####.jpg"], "f.0001.jpg: output must end in .exr or .png"),
    ];
    for (args, says) in cases {
        let err = run_err(&dir, &[&["render", "seq.json"][..], args].concat());
        assert!(err.contains(says), "{args:?}: {err}");
    }
    let err = run_err(&dir, &["render", "seq.json", "--overwrite", "-o", "f.exr"]);
    assert!(err.contains("--frames"), "{err}");
    // A malformed pattern in the scene names its field.
    std::fs::write(dir.join("bad.json"), SCENE.replace("FILE", "smoke.{frame:4}.vdb")).unwrap();
    let err = run_err(&dir, &["render", "bad.json", "--frames", "1-4", "-o", "f.####.exr"]);
    assert!(
        err.contains("frame 1: bad.json: media.smoke.density.file: `{frame:4}`: expected {frame} or {frame:0N}"),
        "{err}"
    );
    // Without --frames, names are used as written.
    let err = run_err(&dir, &["render", "seq.json", "-o", "still.exr"]);
    assert!(err.contains("media.smoke.density.file") && err.contains("smoke.####.vdb"), "{err}");
    assert!(
        err.contains("note: seq.json: media.smoke.density.file change with the frame; without --frames the scene is rendered as written"),
        "{err}"
    );
}

/// A turntable: the camera circles by keyframes (position, fov_y), a point
/// light moves and brightens, a spot light turns.
const TURNTABLE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 5], "target": [0, 0, 0], "width": 8, "height": 8,
    "keyframes": [
      {"frame": 1, "position": [0, 1, 5], "fov_y": 30},
      {"frame": 13, "position": [5, 1, 0]},
      {"frame": 48, "position": [-5, 2, 0], "fov_y": 60}
    ]},
  "lights": [
    {"type": "point", "position": [0, 3, 0], "intensity": 1,
     "keyframes": [{"frame": 10, "position": [0, 3, 0], "intensity": 1}, {"frame": 20, "position": [2, 3, -4], "intensity": [2, 4, 6]}]},
    {"type": "spot", "position": [0, 3, 0], "direction": [0, -1, 0], "intensity": 5,
     "keyframes": [{"frame": 0, "direction": [0, -1, 0]}, {"frame": 40, "direction": [1, -1, 0]}]}
  ]
}"#;

/// `a + (b - a) t` with `t` the frame's fraction between the keyframes.
fn expected(a: f64, b: f64, fa: f64, fb: f64, frame: f64) -> f32 {
    let t = ((frame - fa) / (fb - fa)).clamp(0.0, 1.0);
    (a + (b - a) * t) as f32
}

fn close(x: f32, y: f32) -> bool {
    (x - y).abs() <= 1e-6 * y.abs().max(1.0)
}

#[test]
fn keyframes_interpolate_linearly_and_hold_outside() {
    for frame in [0u32, 1, 2, 7, 13, 14, 30, 47, 48, 100] {
        let (desc, _) = parse_scene_frame(TURNTABLE, "turntable.json", Some(frame)).unwrap();
        let CameraDesc::Perspective(c) = &desc.camera;
        let f = f64::from(frame);
        let position = if f <= 13.0 {
            [expected(0.0, 5.0, 1.0, 13.0, f), 1.0, expected(5.0, 0.0, 1.0, 13.0, f)]
        } else {
            [expected(5.0, -5.0, 13.0, 48.0, f), expected(1.0, 2.0, 13.0, 48.0, f), 0.0]
        };
        for i in 0..3 {
            assert!(close(c.position[i], position[i]), "frame {frame}: {:?} vs {position:?}", c.position);
        }
        // fov_y is set at frames 1 and 48 only: the keyframe at 13 does not pin it.
        assert!(close(c.fov_y, expected(30.0, 60.0, 1.0, 48.0, f)), "frame {frame}: fov {}", c.fov_y);
        assert_eq!(c.target, [0.0, 0.0, 0.0]);
        let LightDesc::Point(p) = &desc.lights[0] else { panic!() };
        let want = [expected(0.0, 2.0, 10.0, 20.0, f), 3.0, expected(0.0, -4.0, 10.0, 20.0, f)];
        for i in 0..3 {
            assert!(close(p.position[i], want[i]), "frame {frame}: {:?}", p.position);
            let intensity = expected(1.0, [2.0, 4.0, 6.0][i], 10.0, 20.0, f);
            assert!(close(p.intensity.channels()[i], intensity), "frame {frame}: {:?}", p.intensity);
        }
        let LightDesc::Spot(s) = &desc.lights[1] else { panic!() };
        let niebla::scene::SpotAimDesc::Direction(d) = s.aim else { panic!() };
        assert!(close(d[0], expected(0.0, 1.0, 0.0, 40.0, f)) && d[1] == -1.0 && d[2] == 0.0, "{d:?}");
    }
    // At the keyframes themselves the values are the ones written, exactly.
    let (desc, _) = parse_scene_frame(TURNTABLE, "turntable.json", Some(13)).unwrap();
    let CameraDesc::Perspective(c) = &desc.camera;
    assert_eq!(c.position, [5.0, 1.0, 0.0]);
    // Without a frame the object's own values are the scene's.
    let (desc, _) = parse_scene_frame(TURNTABLE, "turntable.json", None).unwrap();
    let CameraDesc::Perspective(c) = &desc.camera;
    assert_eq!((c.position, c.fov_y), ([0.0, 1.0, 5.0], 40.0));
}

#[test]
fn keyframe_errors_name_the_keyframe_field() {
    let with = |from: &str, to: &str| {
        let text = TURNTABLE.replacen(from, to, 1);
        assert_ne!(text, TURNTABLE, "{from}");
        parse_scene_frame(&text, "t.json", Some(3)).unwrap_err().to_string()
    };
    let cases = [
        (r#""fov_y": 60"#, r#""fov_y": 190"#, "t.json: camera.keyframes[2].fov_y: vertical field of view must be in the open interval (0, 180) degrees, got 190"),
        (r#"{"frame": 13, "position""#, r#"{"frame": 13, "positon""#, "t.json: camera.keyframes[1].positon: unknown field `positon`; a perspective camera's keyframes may set: frame, position, target, up, fov_y"),
        (r#"{"frame": 13,"#, r#"{"frame": 1,"#, "t.json: camera.keyframes[1].frame: keyframes must be in increasing frame order, but frame 1 follows frame 1"),
        (r#"{"frame": 13,"#, r#"{"frame": -2,"#, "t.json: camera.keyframes[1].frame: expected a frame number >= 0, got -2"),
        (r#"{"frame": 13,"#, r#"{"#, "t.json: camera.keyframes[1]: missing field `frame`"),
        (r#""position": [5, 1, 0]"#, r#""position": [5, 1]"#, "t.json: camera.keyframes[1].position: expected [x, y, z] (3 finite numbers), got [5,1]"),
        (r#""intensity": [2, 4, 6]"#, r#""intensity": [2, -4, 6]"#, "t.json: lights[0].keyframes[1].intensity[1]: must be >= 0, got -4"),
        (r#"{"frame": 40, "direction""#, r#"{"frame": 40, "target""#, "t.json: lights[1].keyframes[1].target: this spot light aims by `direction`; its keyframes must animate `direction`, not `target`"),
        (r#""keyframes": [{"frame": 10"#, r#""keyframes": {}, "x": [{"frame": 10"#, "t.json: lights[0].keyframes: expected a list of keyframe objects, got an object"),
    ];
    for (from, to, says) in cases {
        let err = with(from, to);
        assert!(err.starts_with(says), "{to}:\n{err}\nnot\n{says}");
    }
}

#[test]
fn unchanged_files_are_read_once_per_sequence() {
    // The mesh is rewritten (invalid) after the first build: the second
    // frame still builds, from the cached mesh; a build that does not use
    // it drops it, and the next reads the file again.
    let dir = scene_dir("frames_cache", "smoke.####.vdb");
    let text = std::fs::read_to_string(dir.join("seq.json")).unwrap();
    let cache = SceneCache::default();
    let options = BuildOptions::default();
    let build = |frame: u32, text: &str| {
        let (desc, _) = parse_scene_frame(text, "seq.json", Some(frame)).unwrap();
        build_scene_cached(&desc, "seq.json", &dir, &options, &cache)
    };
    build(1, &text).unwrap();
    assert_eq!(cache.len(), 1);
    std::fs::write(dir.join("floor.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
    build(2, &text).unwrap();
    let without_floor = text.replace(
        r#"{"type": "mesh", "file": "floor.obj", "bsdf": {"type": "diffuse", "reflectance": 0.5}}"#,
        r#"{"type": "sphere", "center": [0, -3, 0], "radius": 1}"#,
    );
    assert_ne!(without_floor, text);
    build(3, &without_floor).unwrap();
    assert!(cache.is_empty());
    let err = build(4, &text).unwrap_err();
    assert_eq!(err.path, "shapes[1].file", "{err}");
}
