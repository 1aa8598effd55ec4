//! The PLY reader on hand-written files: polygon triangulation, skipped
//! elements and properties, every scalar type, aliases, big-endian bodies,
//! and an error naming the file and the place for every bad input.

use std::path::Path;

use niebla_mesh::{parse_ply, read_mesh, read_ply, MeshError, MeshReadOptions};

fn ply(text: &str) -> Result<niebla_mesh::MeshData, MeshError> {
    parse_ply(text.as_bytes(), Path::new("test.ply"))
}

fn err(text: &str) -> String {
    ply(text).unwrap_err().to_string()
}

const SQUARE_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n\
property float z\n";

#[test]
fn quad_and_pentagon_are_fans() {
    let text = format!(
        "{SQUARE_HEADER}element face 2\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 2 0\n4 0 1 2 3\n5 0 1 2 4 3\n"
    );
    let m = ply(&text).unwrap();
    assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 4], [0, 4, 3]]);
    assert_eq!(m.positions[4], [0.5, 2.0, 0.0]);
    assert!(m.normals.is_none() && m.uvs.is_none());
}

#[test]
fn faces_with_fewer_than_three_vertices_are_skipped() {
    let text = format!(
        "{SQUARE_HEADER}element face 4\nproperty list uchar int vertex_index\nend_header\n\
         0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 2 0\n0\n1 3\n2 0 1\n3 2 3 4\n"
    );
    assert_eq!(ply(&text).unwrap().indices, vec![[2, 3, 4]]);
}

#[test]
fn other_elements_and_properties_are_skipped_including_lists() {
    let text = "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info nothing\r\n\
        element camera 1\r\nproperty list int float params\r\nproperty uchar id\r\n\
        element vertex 3\r\nproperty double confidence\r\nproperty list uchar int links\r\nproperty float z\r\n\
        property float y\r\nproperty float x\r\nproperty uchar red\r\nproperty float s\r\nproperty float t\r\n\
        element face 1\r\nproperty list ushort uint feature_ids\r\nproperty uchar flags\r\n\
        property list uchar int vertex_indices\r\nproperty list int int more\r\n\
        element edge 2\r\nproperty int a\r\nproperty int b\r\nend_header\r\n\
        3 1.5 2.5 3.5 7\r\n\
        0.5 2 9 9 3 2 1 255 0.25 0.75\r\n\
        0.5 0 2 1 0 0 0.5 1\r\n\
        \r\n\
        0.5 1 -4 4 0 0 0 0 0\r\n\
        3 1 2 3 9 3 2 1 0 2 -7 8\r\n\
        0 1\r\n1 2\r\n";
    let m = ply(text).unwrap();
    assert_eq!(m.positions, vec![[1.0, 2.0, 3.0], [0.0, 1.0, 2.0], [0.0, 0.0, 4.0]]);
    assert_eq!(m.uvs, Some(vec![[0.25, 0.75], [0.5, 1.0], [0.0, 0.0]]));
    assert_eq!(m.indices, vec![[2, 1, 0]]);
    assert!(m.normals.is_none());
}

#[test]
fn every_scalar_type_and_alias_is_read() {
    let types = ["char", "uchar", "short", "ushort", "int", "uint", "float", "double"];
    let aliases = ["int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"];
    for names in [types, aliases] {
        for (i, t) in names.iter().enumerate() {
            let index = names[(i + 1) % 8];
            let index = if index.starts_with('f') || index == "double" { "int" } else { index };
            let text = format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty {t} x\nproperty {t} y\nproperty {t} z\n\
                 property {t} nx\nproperty {t} ny\nproperty {t} nz\nproperty {t} texture_u\nproperty {t} texture_v\n\
                 element face 1\nproperty list {index} {index} vertex_indices\nend_header\n\
                 1 2 3 0 0 1 0 1\n4 5 6 0 1 0 1 1\n7 8 9 1 0 0 1 0\n3 0 1 2\n"
            );
            let m = ply(&text).unwrap_or_else(|e| panic!("{t}/{index}: {e}"));
            assert_eq!(m.positions[2], [7.0, 8.0, 9.0], "{t}");
            assert_eq!(m.normals.as_ref().unwrap()[1], [0.0, 1.0, 0.0], "{t}");
            assert_eq!(m.uvs.as_ref().unwrap()[2], [1.0, 0.0], "{t}");
            assert_eq!(m.indices, vec![[0, 1, 2]]);
        }
    }
}

/// A binary file with mixed types: double positions, short normals (so
/// that only whole numbers occur), a uchar/ushort index list, and an extra
/// element with a list, in the given byte order.
fn mixed_binary(big: bool) -> Vec<u8> {
    let format = if big { "binary_big_endian" } else { "binary_little_endian" };
    let mut d = format!(
        "ply\nformat {format} 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
         property short nx\nproperty short ny\nproperty short nz\nproperty list int uchar junk\n\
         element face 1\nproperty list uchar ushort vertex_indices\nelement note 1\nproperty list uint char text\n\
         end_header\n"
    )
    .into_bytes();
    let put = |d: &mut Vec<u8>, le: &[u8], be: &[u8]| d.extend_from_slice(if big { be } else { le });
    for (i, p) in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, -0.5]].iter().enumerate() {
        for x in p {
            put(&mut d, &x.to_le_bytes(), &x.to_be_bytes());
        }
        for n in [0i16, -1, 1] {
            put(&mut d, &n.to_le_bytes(), &n.to_be_bytes());
        }
        let junk = i as i32;
        put(&mut d, &junk.to_le_bytes(), &junk.to_be_bytes());
        d.extend(std::iter::repeat_n(0xAAu8, i));
    }
    d.push(4);
    for i in [3u16, 2, 1, 0] {
        put(&mut d, &i.to_le_bytes(), &i.to_be_bytes());
    }
    put(&mut d, &5u32.to_le_bytes(), &5u32.to_be_bytes());
    d.extend_from_slice(b"hello");
    d
}

#[test]
fn binary_little_and_big_endian_give_the_same_mesh() {
    let le = parse_ply(&mixed_binary(false), Path::new("le.ply")).unwrap();
    let be = parse_ply(&mixed_binary(true), Path::new("be.ply")).unwrap();
    assert_eq!(le, be);
    assert_eq!(le.positions[3], [0.0, 1.0, -0.5]);
    assert_eq!(le.normals.as_ref().unwrap()[0], [0.0, -1.0, 1.0]);
    assert_eq!(le.indices, vec![[3, 2, 1], [3, 1, 0]]);
}

#[test]
fn truncated_and_lying_binary_files_are_errors() {
    let full = mixed_binary(false);
    let header_len = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // The header's minimum (4 vertices of 34 bytes, 1 face of 1, 1 note of 4)
    // is 141 bytes; the lists make the full body 160.
    let e = parse_ply(&full[..header_len + 100], Path::new("short.ply")).unwrap_err().to_string();
    assert_eq!(
        e,
        "short.ply: file too short: the header declares 4 vertices of at least 34 bytes each and 1 faces of at \
         least 1 bytes each and 1 \"note\" elements of at least 4 bytes each but only 100 bytes follow the header"
    );
    // Enough for the minimum, not for the lists: the element and byte are named.
    let e = parse_ply(&full[..full.len() - 3], Path::new("short.ply")).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "short.ply: file too short: note 0 (byte {}): the file ends at byte {} while reading text (5 values of \
             type char)",
            full.len() - 9,
            full.len() - 3
        )
    );
    let e = parse_ply(&full[..full.len() - 14], Path::new("short.ply")).unwrap_err().to_string();
    assert!(e.starts_with("short.ply: file too short: face 0 (byte"), "{e}");
    assert!(e.ends_with("while reading vertex_indices (ushort)"), "{e}");
    // A header declaring 10^9 vertices in front of a kilobyte.
    let mut lying =
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            .to_vec();
    lying.extend(std::iter::repeat_n(0u8, 1000));
    let e = parse_ply(&lying, Path::new("lying.ply")).unwrap_err().to_string();
    assert_eq!(
        e,
        "lying.ply: file too short: the header declares 1000000000 vertices of 12 bytes each and 1 faces of at \
         least 1 bytes each but only 1000 bytes follow the header"
    );
    // Counts whose byte total overflows u64.
    let huge =
        String::from_utf8(lying[..lying.len() - 1000].to_vec()).unwrap().replace("1000000000", "18446744073709551615");
    let e = parse_ply(huge.as_bytes(), Path::new("huge.ply")).unwrap_err().to_string();
    assert!(e.starts_with("huge.ply: file too short: the header declares 18446744073709551615 vertices"), "{e}");
    // A polygon claiming 2^32 - 1 indices in a short file.
    let mut d = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty uchar x\nproperty uchar y\n\
property uchar z\nelement face 1\nproperty list uint uint vertex_indices\nend_header\n"
        .to_vec();
    d.extend_from_slice(&[0, 0, 0, 1, 0, 0, 0, 1, 0, 255, 255, 255, 255, 0, 0, 0, 0]);
    let e = parse_ply(&d, Path::new("list.ply")).unwrap_err().to_string();
    assert_eq!(
        e,
        "list.ply: file too short: face 0 (byte 175): the file ends at byte 183 while reading vertex_indices (uint)"
    );
}

#[test]
fn truncated_and_bad_ascii_files_are_errors() {
    let body = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 2 0\n";
    let head = format!("{SQUARE_HEADER}element face 2\nproperty list uchar int vertex_indices\nend_header\n");
    // Ends inside the face list: the line and face are named.
    let e = err(&format!("{head}{body}3 0 1 2\n4 0 1"));
    assert_eq!(
        e,
        "test.ply: line 16 (face 1): the line ends after 3 values; expected a int for property vertex_indices"
    );
    // Ends before the last face.
    let e = err(&format!("{head}{body}3 0 1 2\n\n\n\n\n\n\n\n"));
    assert_eq!(e, "test.ply: file too short: the file ends after line 22, before face 1 (the header declares 2)");
    // Lying count: 10^9 vertices.
    let e = err(&format!("{}{body}3 0 1 2\n4 0 1 2 3\n", head.replace("vertex 5", "vertex 1000000000")));
    assert!(e.starts_with("test.ply: file too short: the header declares 1000000000 vertices of at least 6 bytes each"));
    // Index out of range, negative index, non-numbers, too many values.
    assert_eq!(
        err(&format!("{head}{body}3 0 1 2\n3 0 1 907\n")),
        "test.ply: line 16 (face 1): vertex_indices[2]: vertex index 907 out of range (the file has 5 vertices)"
    );
    assert_eq!(
        err(&format!("{head}{body}3 0 -1 2\n3 0 1 2\n")),
        "test.ply: line 15 (face 0): vertex_indices[1]: vertex index -1 out of range (the file has 5 vertices)"
    );
    assert_eq!(
        err(&format!("{head}0 0 0\n1 zero 0\n1 1 0\n0 1 0\n0.5 2 0\n3 0 1 2\n3 0 1 2\n")),
        "test.ply: line 11 (vertex 1): property y: \"zero\" is not a number (float)"
    );
    assert_eq!(
        err(&format!("{head}{body}3 0 1 2\n300 0 1 2\n")),
        "test.ply: line 16 (face 1): property vertex_indices: \"300\" is not an integer in 0..=255 (uchar)"
    );
    assert_eq!(
        err(&format!("{head}{body}3 0 1 2 5\n3 0 1 2\n")),
        "test.ply: line 15 (face 0): 5 values on the line but the header's properties take 4"
    );
    assert_eq!(
        err(&format!("{head}{body}3 0 1 2\n4 0 1 2\n")),
        "test.ply: line 16 (face 1): the line ends after 4 values; expected a int for property vertex_indices"
    );
    // NaN and infinite coordinates (double overflowing f32 too).
    assert_eq!(
        err(&format!("{head}0 0 0\n1 0 nan\n1 1 0\n0 1 0\n0.5 2 0\n3 0 1 2\n3 0 1 2\n")),
        "test.ply: positions[1][2]: NaN is not a finite number"
    );
    let doubles = head.replace("float", "double");
    assert_eq!(
        err(&format!("{doubles}0 0 0\n1 0 0\n1 1 0\n0 1e300 0\n0.5 2 0\n3 0 1 2\n3 0 1 2\n")),
        "test.ply: positions[3][1]: inf is not a finite number"
    );
}

#[test]
fn malformed_headers_name_the_line() {
    assert_eq!(err(""), "test.ply: PLY header line 1: empty file; a PLY file starts with the line \"ply\"");
    assert_eq!(
        err("OFF\n3 1 0\n"),
        "test.ply: PLY header line 1: not a PLY file: the first line is \"OFF\", expected \"ply\""
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nelement vertex 3\n"),
        "test.ply: file too short: the header ends after 3 lines without an \"end_header\" line"
    );
    assert_eq!(
        err("ply\nformat binary_middle_endian 1.0\nend_header\n"),
        "test.ply: PLY header line 2: format \"binary_middle_endian\"; expected ascii, binary_little_endian or \
         binary_big_endian"
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nelement vertex 3\nproperty float16 x\nend_header\n"),
        "test.ply: PLY header line 4: unknown type \"float16\"; expected char, uchar, short, ushort, int, uint, \
         float, double or int8, uint8, int16, uint16, int32, uint32, float32, float64"
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nelement vertex -3\nend_header\n"),
        "test.ply: PLY header line 3: element vertex: count \"-3\" is not a non-negative integer"
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nproperty float x\nend_header\n"),
        "test.ply: PLY header line 3: a property before any element"
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nelement face 0\n\
             property list uchar int vertex_indices\nend_header\n"),
        "test.ply: PLY header line 3: element vertex has no property \"z\"; expected x, y and z"
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n\
             end_header\n"),
        "test.ply: PLY header line 7: the header declares no \"face\" element (a point cloud, not a mesh); a mesh \
         needs one"
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n\
             element face 0\nproperty list uchar float vertex_indices\nend_header\n"),
        "test.ply: PLY header line 8: face vertex_indices: index type float is not an integer type"
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n\
             element face 0\nproperty list uchar int vertex_indices\nend_header\n"),
        "test.ply: no triangles (faces with fewer than 3 vertices are skipped)"
    );
    assert_eq!(
        err("ply\nformat ascii 1.0\nCreated by hand\nelement vertex 0\nmaterial red\nend_header\n"),
        "test.ply: PLY header line 5: unknown keyword \"material\"; expected format, comment, obj_info, element, \
         property or end_header"
    );
}

#[test]
fn missing_file_unknown_format_and_object_for_ply_are_errors() {
    let e = read_ply("/nonexistent/dir/mesh.ply").unwrap_err().to_string();
    assert!(e.starts_with("/nonexistent/dir/mesh.ply: cannot read: "), "{e}");
    let e = read_mesh("/nonexistent/dir/mesh.obj", &MeshReadOptions::default()).unwrap_err().to_string();
    assert!(e.starts_with("/nonexistent/dir/mesh.obj: cannot read: "), "{e}");
    let e = read_mesh("scene/mesh.stl", &MeshReadOptions::default()).unwrap_err().to_string();
    assert_eq!(e, "scene/mesh.stl: unknown mesh format \"stl\"; supported: .ply (ASCII or binary) and .obj");
    let e = read_mesh("scene/mesh", &MeshReadOptions::default()).unwrap_err().to_string();
    assert_eq!(e, "scene/mesh: unknown mesh format \"\"; supported: .ply (ASCII or binary) and .obj");
    let e = niebla_mesh::estimate_mesh_bytes("m.off").unwrap_err().to_string();
    assert!(e.starts_with("m.off: unknown mesh format \"off\""), "{e}");
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("object.ply");
    niebla_mesh::write_ply_ascii(&path, &niebla_mesh::icosphere(0, 1.0)).unwrap();
    let options = MeshReadOptions { object: Some("bunny".into()), ..Default::default() };
    let e = read_mesh(&path, &options).unwrap_err().to_string();
    assert!(e.ends_with("object.ply: object \"bunny\" requested, but only OBJ files have named objects"), "{e}");
}

#[test]
fn faces_before_vertices_and_partial_normals() {
    // The face element comes first; indices are checked against the
    // declared vertex count. nx and ny without nz are not normals.
    let text = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n\
                element vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n\
                property float ny\nend_header\n3 2 1 0\n0 0 0 1 1\n1 0 0 1 1\n0 1 0 1 1\n";
    let m = ply(text).unwrap();
    assert_eq!(m.indices, vec![[2, 1, 0]]);
    assert_eq!(m.positions[2], [0.0, 1.0, 0.0]);
    assert!(m.normals.is_none());
    assert_eq!(
        err(&text.replace("3 2 1 0", "3 2 1 3")),
        "test.ply: line 12 (face 0): vertex_indices[2]: vertex index 3 out of range (the file has 3 vertices)"
    );
}
