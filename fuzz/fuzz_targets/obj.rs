//! OBJ reader (pre-scan + tobj) on arbitrary bytes. The first byte picks
//! the object: all merged (even), or the object named `a` (odd). A mesh it
//! accepts must read back identical from the OBJ writer, and the topology
//! checks must run on it.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use niebla_mesh::{obj_bytes, parse_obj};

fuzz_target!(|data: &[u8]| {
    let Some((&select, text)) = data.split_first() else { return };
    let object = if select % 2 == 1 { Some("a") } else { None };
    let Ok(mesh) = parse_obj(text, Path::new("fuzz.obj"), object) else { return };
    let _ = mesh.closedness();
    let _ = mesh.degenerate_triangles();
    let back = parse_obj(&obj_bytes(&mesh), Path::new("rt.obj"), None).unwrap();
    assert_eq!(format!("{back:?}"), format!("{mesh:?}"));
});
