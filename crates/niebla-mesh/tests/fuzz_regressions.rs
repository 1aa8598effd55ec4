//! Inputs the fuzz targets `ply` and `obj` (`fuzz/`, cargo-fuzz) found or
//! that guard what they check, kept as regression tests on the stable
//! toolchain: every file in `tests/fuzz_regressions/{ply,obj}/` goes
//! through what the target does (parse; if accepted, topology checks and a
//! bit-exact round trip through the writers). Add a crashing input by
//! copying it there from `fuzz/artifacts/<target>/`.

use std::path::{Path, PathBuf};

use niebla_mesh::{obj_bytes, parse_obj, parse_ply, ply_ascii_bytes, ply_binary_bytes, ByteOrder};

fn inputs(kind: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions").join(kind);
    if !dir.exists() {
        return Vec::new();
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

/// What `fuzz/fuzz_targets/ply.rs` does.
fn ply_target(data: &[u8]) {
    let Ok(mesh) = parse_ply(data, Path::new("fuzz.ply")) else { return };
    let _ = mesh.closedness();
    let _ = mesh.degenerate_triangles();
    let binary = parse_ply(&ply_binary_bytes(&mesh, ByteOrder::BigEndian), Path::new("rt.ply")).unwrap();
    assert_eq!(format!("{binary:?}"), format!("{mesh:?}"));
    let ascii = parse_ply(&ply_ascii_bytes(&mesh), Path::new("rt.ply")).unwrap();
    assert_eq!(format!("{ascii:?}"), format!("{mesh:?}"));
}

/// What `fuzz/fuzz_targets/obj.rs` does.
fn obj_target(data: &[u8]) {
    let Some((&select, text)) = data.split_first() else { return };
    let object = if select % 2 == 1 { Some("a") } else { None };
    let Ok(mesh) = parse_obj(text, Path::new("fuzz.obj"), object) else { return };
    let _ = mesh.closedness();
    let _ = mesh.degenerate_triangles();
    let back = parse_obj(&obj_bytes(&mesh), Path::new("rt.obj"), None).unwrap();
    assert_eq!(format!("{back:?}"), format!("{mesh:?}"));
}

#[test]
fn fuzzed_ply_inputs_give_errors_not_panics() {
    for path in inputs("ply") {
        println!("{}", path.display());
        ply_target(&std::fs::read(&path).unwrap());
    }
}

#[test]
fn fuzzed_obj_inputs_give_errors_not_panics() {
    for path in inputs("obj") {
        println!("{}", path.display());
        obj_target(&std::fs::read(&path).unwrap());
    }
}
