//! `niebla info FILE.vdb` on a Mantaflow-style fire file written by the
//! reference library (`crates/niebla-volume/tests/oracle/make_vec3_vdbs.py`,
//! run with Debian's python3-openvdb): one line per grid with the type,
//! class, active voxel count and value range the library reports.

use std::path::{Path, PathBuf};
use std::process::Command;

fn generated_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("info_vdb_files");
    if dir.join("expected.json").exists() {
        return dir;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../niebla-volume/tests/oracle/make_vec3_vdbs.py");
    let scratch = dir.with_extension(format!("tmp{}", std::process::id()));
    let out = Command::new("/usr/bin/python3")
        .arg(&script)
        .arg(&scratch)
        .env("OPENVDB_DISABLE_DELAYED_LOAD", "1")
        .output()
        .expect("run /usr/bin/python3 (install python3-openvdb and libopenvdb-tools)");
    assert!(out.status.success(), "make_vec3_vdbs.py failed:\n{}", String::from_utf8_lossy(&out.stderr));
    if std::fs::rename(&scratch, &dir).is_err() {
        assert!(dir.join("expected.json").exists());
        let _ = std::fs::remove_dir_all(&scratch);
    }
    dir
}

#[test]
fn info_lists_every_grid_of_a_bare_vdb_file() {
    let dir = generated_dir();
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_niebla"))
        .args(["info", dir.join("mantaflow_fire.vdb").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("9 grids"), "{stdout}");
    for g in expected["files"]["mantaflow_fire.vdb"].as_array().unwrap() {
        let name = g["name"].as_str().unwrap();
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{name}:")))
            .unwrap_or_else(|| panic!("no line for {name}:\n{stdout}"));
        let kind = if g["vector"].as_bool().unwrap() { "vec3s" } else { "float" };
        assert!(line.contains(&format!(": {kind},")), "{line}");
        assert!(line.contains(&format!("class {}", g["class"].as_str().unwrap())), "{line}");
        let count = g["active_voxel_count"].as_u64().unwrap();
        if count == 0 {
            assert!(line.contains("empty (0 active voxels)"), "{line}");
            continue;
        }
        assert!(line.contains(&format!("{count} active voxels")), "{line}");
        // The range printed (f32 shortest form) equals the library's within f32 rounding.
        let range = &g["value_range"];
        let printed: Vec<f64> = line
            .rsplit(' ')
            .next()
            .unwrap()
            .split("..")
            .map(|v| v.parse().unwrap_or_else(|_| panic!("{line}")))
            .collect();
        for (p, want) in printed.iter().zip(range.as_array().unwrap()) {
            let want = want.as_f64().unwrap();
            assert!((p - want).abs() <= 1e-6 * want.abs().max(1.0), "{line}: {p} vs {want}");
        }
    }
}

#[test]
fn info_on_a_corrupt_vdb_names_the_file() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("info_vdb_bad");
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.vdb");
    std::fs::write(&bad, b"not a vdb file at all").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_niebla")).args(["info", bad.to_str().unwrap()]).output().unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("bad.vdb") && stderr.contains("not an OpenVDB file"), "{stderr}");
}
