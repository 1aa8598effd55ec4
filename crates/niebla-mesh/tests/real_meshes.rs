//! Real exported meshes (tests/data, BSD-3-clause, see LICENSE.md there):
//! counts, closedness, and the same mesh read back from every format.

use std::path::{Path, PathBuf};

use niebla_mesh::{
    obj_bytes, parse_obj, parse_ply, ply_ascii_bytes, ply_binary_bytes, read_obj, ByteOrder, Closedness,
};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

#[test]
fn blender_cylinder_is_closed() {
    let m = read_obj(data("blender_cylinder.obj"), None).unwrap();
    // 130 positions split by face normals into 450 vertices.
    assert_eq!((m.vertex_count(), m.triangle_count()), (450, 256));
    assert!(m.normals.is_some() && m.uvs.is_none());
    assert_eq!(m.closedness(), Closedness::default());
    let welded: std::collections::HashSet<u32> = m.welded_ids().into_iter().collect();
    assert_eq!(welded.len(), 130);
    assert_eq!(read_obj(data("blender_cylinder.obj"), Some("Cylinder")).unwrap(), m);
}

#[test]
fn wuson_reads_the_same_from_every_format() {
    let m = read_obj(data("wuson.obj"), None).unwrap();
    assert_eq!((m.vertex_count(), m.triangle_count()), (2117, 3732));
    assert!(m.normals.is_some() && m.uvs.is_some());
    assert_eq!(m.degenerate_triangles(), 0);
    assert_eq!(m.closedness(), Closedness { boundary_edges: 412, ..Closedness::default() });
    let p = Path::new("wuson.ply");
    assert_eq!(parse_ply(&ply_binary_bytes(&m, ByteOrder::LittleEndian), p).unwrap(), m);
    assert_eq!(parse_ply(&ply_binary_bytes(&m, ByteOrder::BigEndian), p).unwrap(), m);
    assert_eq!(parse_ply(&ply_ascii_bytes(&m), p).unwrap(), m);
    assert_eq!(parse_obj(&obj_bytes(&m), Path::new("wuson.obj"), None).unwrap(), m);
}
