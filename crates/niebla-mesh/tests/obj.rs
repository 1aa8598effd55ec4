//! The OBJ reader: polygons, objects and groups (merged or selected),
//! partial attributes, and errors with the file and line for bad input.

use std::path::Path;

use niebla_mesh::{parse_obj, read_obj, MeshData, MeshError};

fn obj(text: &str, object: Option<&str>) -> Result<MeshData, MeshError> {
    parse_obj(text.as_bytes(), Path::new("test.obj"), object)
}

fn err(text: &str) -> String {
    obj(text, None).unwrap_err().to_string()
}

const FIVE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0\n";

#[test]
fn quad_and_pentagon_are_fans() {
    let m = obj(&format!("{FIVE}f 1 2 3 4\nf 1 2 3 5 4\n"), None).unwrap();
    assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 4], [0, 4, 3]]);
    assert_eq!(m.positions, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.5, 2.0, 0.0]]);
}

#[test]
fn relative_indices_w_points_lines_and_polylines() {
    let text = format!("{FIVE}v 2 4 6 2\nf -4 -3 -2\np 1\nl 1 2\nl 1 2 3 4\nf 1 2\nf 4 5 6\n");
    let m = obj(&text, None).unwrap();
    // Vertices in order of first use: 3 4 5 (from -4 -3 -2 with 6 so far), then 6.
    assert_eq!(m.positions, vec![[1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.5, 2.0, 0.0], [1.0, 2.0, 3.0]]);
    assert_eq!(m.indices, vec![[0, 1, 2], [1, 2, 3]]);
}

const TWO_OBJECTS: &str = "o left\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n\
o right\nv 5 0 0\nv 6 0 0\nv 5 1 0\nv 5 0 1\nf 4/1 5/2 6/3\nf 4/1 6/3 7/2\ng extra\nf 1/1 3/3 7/2\n";

#[test]
fn objects_are_merged_or_selected() {
    let all = obj(TWO_OBJECTS, None).unwrap();
    assert_eq!(all.triangle_count(), 4);
    assert_eq!(all.vertex_count(), 3 + 4 + 3);
    assert_eq!(all.indices, vec![[0, 1, 2], [3, 4, 5], [3, 5, 6], [7, 8, 9]]);
    assert_eq!(all.uvs.as_ref().unwrap()[6], [1.0, 0.0]);
    let right = obj(TWO_OBJECTS, Some("right")).unwrap();
    assert_eq!(right.positions, vec![[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0], [5.0, 0.0, 1.0]]);
    assert_eq!(right.indices, vec![[0, 1, 2], [0, 2, 3]]);
    let extra = obj(TWO_OBJECTS, Some("extra")).unwrap();
    assert_eq!(extra.positions, vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [5.0, 0.0, 1.0]]);
    let e = obj(TWO_OBJECTS, Some("middle")).unwrap_err().to_string();
    assert_eq!(e, "test.obj: no object named \"middle\" with faces; the file has [\"left\", \"right\", \"extra\"]");
    // Faces before any o/g line belong to tobj's "unnamed_object".
    let e = obj(&format!("{FIVE}f 1 2 3\n"), Some("x")).unwrap_err().to_string();
    assert_eq!(e, "test.obj: no object named \"x\" with faces; the file has [\"unnamed_object\"]");
}

#[test]
fn attributes_missing_on_some_corners_are_dropped_for_the_whole_mesh() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
                f 1/1/1 2/2/1 3/3/1\nf 2/2/1 4//1 3/3/1\n";
    let m = obj(text, None).unwrap();
    assert!(m.uvs.is_none(), "uvs missing at one corner are dropped");
    assert_eq!(m.normals.as_ref().unwrap(), &vec![[0.0, 0.0, 1.0]; 4]);
    assert_eq!(m.indices, vec![[0, 1, 2], [1, 3, 2]]);
    // Between objects: one with normals, one without.
    let text = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\no b\nf 1 2 3\n";
    let m = obj(text, None).unwrap();
    assert!(m.normals.is_none());
    assert_eq!(m.triangle_count(), 2);
    assert!(obj(text, Some("a")).unwrap().normals.is_some());
}

#[test]
fn a_vertex_used_with_two_uvs_becomes_two_vertices() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nf 1/1 2/2 3/3\nf 2/4 4/4 3/3\n";
    let m = obj(text, None).unwrap();
    assert_eq!(m.vertex_count(), 5);
    assert_eq!(m.positions[1], m.positions[3]);
    assert_eq!(m.uvs.unwrap()[3], [1.0, 1.0]);
}

#[test]
fn byte_order_mark_latin1_names_and_unnamed_usemtl_are_accepted() {
    let mut data = b"\xef\xbb\xbf".to_vec();
    data.extend_from_slice(FIVE.as_bytes());
    data.extend_from_slice(b"o caf\xe9\nusemtl\nusemtl Terraind\xe6k\nf 1 2 3\n");
    let m = parse_obj(&data, Path::new("latin1.obj"), Some("caf\u{fffd}")).unwrap();
    assert_eq!(m.positions, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
}

#[test]
fn partial_vertex_colours_are_ignored() {
    let m = obj(&format!("v 0 0 0 1 0 0\n{FIVE}f 2 3 4\n"), None).unwrap();
    assert_eq!(m.positions, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
}

#[test]
fn bad_files_name_the_line() {
    let cases = [
        (
            format!("{FIVE}f 1 2 907\n"),
            "line 6: face vertex \"907\" refers to position 907 but the file has 5 positions",
        ),
        (
            format!("{FIVE}f 1 2 0\n"),
            "line 6: face vertex \"0\": index 0 (OBJ indices start at 1, negative ones count back)",
        ),
        (
            format!("{FIVE}f 1 2 -6\n"),
            "line 6: face vertex \"-6\": relative position index -6 but only 5 positions precede this line",
        ),
        (
            format!("{FIVE}f 1/1 2/1 3/1\n"),
            "line 6: face vertex \"1/1\" refers to texture coordinate 1 but the file has 0 texture coordinates",
        ),
        (
            format!("{FIVE}vn 0 0 1\nf 1//1 2//2 3//1\n"),
            "line 7: face vertex \"2//2\" refers to normal 2 but the file has 1 normal",
        ),
        // Indices whose arithmetic overflows inside tobj 4.0.5 (`vn * 3 + 2`,
        // `vt * 2 + 1` after a relative index wraps): it panics on them.
        (format!("{FIVE}vn 0 0 1\nf 1//6148914691236517206 2//1 3//1\n"), "line 7: face vertex \"1//6148914691236517206\" refers to normal 6148914691236517206 but the file has 1 normal"),
        (format!("{FIVE}vt 0 0\nf 1/-9223372036854775808 2/1 3/1\n"), "line 7: face vertex \"1/-9223372036854775808\": relative texture coordinate index -9223372036854775808 but only 1 texture coordinate precedes this line"),
        (format!("{FIVE}f -9223372036854775808 1 2\n"), "line 6: face vertex \"-9223372036854775808\": relative position index -9223372036854775808 but only 5 positions precede this line"),
        (format!("{FIVE}f 1 2 9223372036854775808\n"), "line 6: face vertex \"9223372036854775808\": \"9223372036854775808\" is not an integer"),
        (format!("{FIVE}f 1 2 x\n"), "line 6: face vertex \"x\": \"x\" is not an integer"),
        (format!("{FIVE}f 1 2 3/4/5/6\n"), "line 6: face vertex \"3/4/5/6\": more than three /-separated indices"),
        (format!("{FIVE}f 1 /2 3\n"), "line 6: face vertex \"/2\": no position index"),
        (format!("{FIVE}f\n"), "line 6: face without vertices"),
        ("v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n".into(), "line 2: vertex position: \"zero\" is not a number"),
        ("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n".into(), "line 2: vertex position: expected 3 numbers, found 2"),
        ("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n".into(), "line 2: vertex position: \"nan\" is not a finite number"),
        ("v 0 0 0\nv 1 0 0 0\nv 0 1 0\nf 1 2 3\n".into(), "line 2: vertex w is 0"),
        (
            "v 0 0 0\nv 1 0 0 1 1\nv 0 1 0\nf 1 2 3\n".into(),
            "line 2: vertex with 5 values; expected x y z, x y z w or x y z r g b",
        ),
        (format!("{FIVE}vt 0.5\nf 1 2 3\n"), "line 6: texture coordinate (u v): expected 2 numbers, found 1"),
        (format!("{FIVE}vn 0 inf 1\nf 1//1 2//1 3//1\n"), "line 6: normal: \"inf\" is not a finite number"),
        (format!("{FIVE}\n"), "no triangles (faces with fewer than 3 vertices are skipped)"),
    ];
    for (text, expected) in cases {
        assert_eq!(err(&text), format!("test.obj: {expected}"), "{text}");
    }
    let e = parse_obj(b"v 0 0 0\nv \xff 0 0\n", Path::new("bin.obj"), None).unwrap_err().to_string();
    assert_eq!(e, "bin.obj: line 2: vertex position: \"\u{fffd}\" is not a number");
    let e = parse_obj(b"\xff\xfe\0v\0 \x000", Path::new("utf16.obj"), None).unwrap_err().to_string();
    assert_eq!(e, "utf16.obj: line 1: UTF-16 text (byte order mark); OBJ files must be ASCII or UTF-8");
    // A position overflowing f32 after the division by w.
    let e = err("v 0 0 0\nv 1e30 0 0 1e-30\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(e, "test.obj: positions[1][0]: inf is not a finite number");
}

#[test]
fn missing_file_is_an_error() {
    let e = read_obj("/nonexistent/x.obj", None).unwrap_err().to_string();
    assert!(e.starts_with("/nonexistent/x.obj: cannot read: "), "{e}");
}
