//! `niebla convert`, `info` and `render` on Mitsuba 3 XML scenes: `-D`
//! overrides, notes, errors with file:line, and no output left by a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

fn niebla(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_niebla")).args(args).output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/mitsuba").join(name).display().to_string()
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("niebla_mitsuba_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn convert_applies_defines_and_writes_a_niebla_scene() {
    let out = temp("grid.json");
    let (ok, _, err) = niebla(&["convert", &scene("grid_smoke.xml"), "-o", out.to_str().unwrap(), "-D", "spp=8"]);
    assert!(ok, "{err}");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(json["render"]["spp"], 8);
    assert_eq!(json["render"]["integrator"], serde_json::json!({"type": "volpath", "max_depth": 32}));
    // The grid's file is found from the output's folder (absolute here: it lies outside it).
    let file = json["media"]["smoke"]["density"]["file"].as_str().unwrap();
    assert!(Path::new(file).is_file(), "{file}");
    // The written scene renders as a niebla scene.
    let (ok, stdout, err) = niebla(&["info", out.to_str().unwrap()]);
    assert!(ok && stdout.contains("grid medium"), "{err}");
}

#[test]
fn info_lists_what_was_accepted_without_effect() {
    let (ok, stdout, err) = niebla(&["info", &scene("area_fog.xml")]);
    assert!(ok, "{err}");
    assert!(stdout.contains("accepted without effect (1):"), "{stdout}");
    assert!(stdout.contains("area_fog.xml:26: <sensor> medium \"fog\""), "{stdout}");
}

#[test]
fn xml_errors_name_file_and_line_and_leave_no_output() {
    let bad = temp("bad.xml");
    std::fs::write(
        &bad,
        "<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n    <bsdf type=\"hair\"/>\n  </shape>\n</scene>\n",
    )
    .unwrap();
    let out = temp("bad.json");
    let (ok, _, err) = niebla(&["convert", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("bad.xml:3: <bsdf type=\"hair\">: not supported"), "{err}");
    assert!(!out.exists());
    let (ok, _, err) = niebla(&["render", bad.to_str().unwrap(), "-o", temp("bad.exr").to_str().unwrap()]);
    assert!(!ok && err.contains("bad.xml:3:"), "{err}");
    // -D is for XML scenes only.
    let json = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/default.json");
    let (ok, _, err) = niebla(&["info", json.to_str().unwrap(), "-D", "spp=4"]);
    assert!(!ok && err.contains("-D spp=...: parameters apply to Mitsuba XML scenes"), "{err}");
}

#[test]
fn render_reads_xml_directly() {
    let out = temp("mesh.exr");
    let (ok, _, err) =
        niebla(&["render", &scene("mesh_in_fog.xml"), "-D", "spp=1", "--quiet", "-o", out.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.is_file());
}
