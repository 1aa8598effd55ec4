//! PLY reader on arbitrary bytes; a mesh it accepts must survive a round
//! trip through the binary and ASCII writers bit for bit, and the topology
//! checks must run on it.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use niebla_mesh::{parse_ply, ply_ascii_bytes, ply_binary_bytes, ByteOrder};

fuzz_target!(|data: &[u8]| {
    let Ok(mesh) = parse_ply(data, Path::new("fuzz.ply")) else { return };
    let _ = mesh.closedness();
    let _ = mesh.degenerate_triangles();
    let binary = parse_ply(&ply_binary_bytes(&mesh, ByteOrder::BigEndian), Path::new("rt.ply")).unwrap();
    assert_eq!(format!("{binary:?}"), format!("{mesh:?}"));
    let ascii = parse_ply(&ply_ascii_bytes(&mesh), Path::new("rt.ply")).unwrap();
    assert_eq!(format!("{ascii:?}"), format!("{mesh:?}"));
});
