//! The same mesh written as ASCII PLY, binary PLY (both byte orders) and
//! OBJ reads back bit for bit, through the byte parsers and through files
//! with `read_mesh`; generators give the documented counts.

use std::path::{Path, PathBuf};

use niebla_mesh::{
    estimate_mesh_bytes, icosphere, obj_bytes, parse_obj, parse_ply, ply_ascii_bytes, ply_binary_bytes, random_soup,
    read_mesh, uv_sphere, write_obj, write_ply_ascii, write_ply_binary, ByteOrder, MeshData, MeshFormat,
    MeshReadOptions,
};

fn tmp(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("niebla_mesh_roundtrip");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// The bits of positions, normals, uvs, and the indices.
type Bits = (Vec<u32>, Option<Vec<u32>>, Option<Vec<u32>>, Vec<[u32; 3]>);

/// Bitwise equality, so that -0.0 != 0.0 and NaN patterns would count.
fn bits(m: &MeshData) -> Bits {
    (
        m.positions.iter().flatten().map(|x| x.to_bits()).collect(),
        m.normals.as_ref().map(|n| n.iter().flatten().map(|x| x.to_bits()).collect()),
        m.uvs.as_ref().map(|n| n.iter().flatten().map(|x| x.to_bits()).collect()),
        m.indices.clone(),
    )
}

/// Every combination of the optional attributes of `mesh`.
fn variants(mesh: &MeshData) -> Vec<MeshData> {
    let mut out = Vec::new();
    for normals in [false, true] {
        for uvs in [false, true] {
            let mut m = mesh.clone();
            if !normals {
                m.normals = None;
            }
            if !uvs {
                m.uvs = None;
            }
            out.push(m);
        }
    }
    out
}

fn check_all_formats(mesh: &MeshData) {
    let p = Path::new("m.ply");
    let o = Path::new("m.obj");
    let expect = bits(mesh);
    assert_eq!(bits(&parse_ply(&ply_ascii_bytes(mesh), p).unwrap()), expect, "ascii PLY");
    assert_eq!(bits(&parse_ply(&ply_binary_bytes(mesh, ByteOrder::LittleEndian), p).unwrap()), expect, "binary LE");
    assert_eq!(bits(&parse_ply(&ply_binary_bytes(mesh, ByteOrder::BigEndian), p).unwrap()), expect, "binary BE");
    assert_eq!(bits(&parse_obj(&obj_bytes(mesh), o, None).unwrap()), expect, "OBJ");
}

#[test]
fn generated_meshes_round_trip_bit_for_bit_in_every_format() {
    for mesh in [icosphere(3, 2.5), uv_sphere(7, 11, 0.75), random_soup(500, 42)] {
        for m in variants(&mesh) {
            check_all_formats(&m);
        }
    }
}

#[test]
fn awkward_values_round_trip_bit_for_bit() {
    // Negative zero, subnormals, extremes, values whose shortest decimal is long.
    let values = [-0.0f32, 1e-45, -f32::MIN_POSITIVE, f32::MAX, f32::MIN, 0.1, 1.0 / 3.0, 16777215.0, -123456.79];
    let positions: Vec<[f32; 3]> =
        (0..values.len()).map(|i| [values[i], values[(i + 1) % 9], values[(i + 4) % 9]]).collect();
    let normals = positions.iter().map(|p| [p[2], p[0], p[1]]).collect();
    let uvs = positions.iter().map(|p| [p[1], p[2]]).collect();
    let indices = vec![[0, 1, 2], [3, 4, 5], [6, 7, 8]];
    let mesh = MeshData::from_arrays(positions, indices, Some(normals), Some(uvs)).unwrap();
    assert_eq!(mesh, mesh.renumbered_by_first_use());
    for m in variants(&mesh) {
        check_all_formats(&m);
    }
}

#[test]
fn files_read_back_through_read_mesh_with_any_case_extension() {
    let mesh = uv_sphere(5, 8, 1.0);
    type Writer = fn(&Path, &MeshData);
    let cases: [(&str, Writer); 4] = [
        ("a.ply", |p, m| write_ply_ascii(p, m).unwrap()),
        ("le.PLY", |p, m| write_ply_binary(p, m, ByteOrder::LittleEndian).unwrap()),
        ("be.Ply", |p, m| write_ply_binary(p, m, ByteOrder::BigEndian).unwrap()),
        ("m.OBJ", |p, m| write_obj(p, m).unwrap()),
    ];
    for (name, write) in cases {
        let path = tmp(name);
        write(&path, &mesh);
        let back = read_mesh(&path, &MeshReadOptions::default()).unwrap();
        assert_eq!(bits(&back), bits(&mesh), "{name}");
    }
    assert_eq!(MeshFormat::from_path(Path::new("x.Obj")).unwrap(), MeshFormat::Obj);
}

#[test]
fn generators_have_the_documented_counts() {
    for s in 0..4 {
        let m = icosphere(s, 1.0);
        assert_eq!(m.triangle_count(), 20 * 4usize.pow(s));
        assert_eq!(m.vertex_count(), 10 * 4usize.pow(s) + 2);
        assert_eq!(m.degenerate_triangles(), 0);
        for p in &m.positions {
            let r = (p[0] as f64).hypot(p[1] as f64).hypot(p[2] as f64);
            assert!((r - 1.0).abs() < 1e-6, "{r}");
        }
    }
    // uv sphere: (n_theta + 1) rows of n_phi + 1 vertices minus the unused
    // last vertex of each pole row; 2 triangles per quad except at the poles.
    let m = uv_sphere(6, 10, 1.0);
    assert_eq!(m.triangle_count(), 2 * 6 * 10 - 2 * 10);
    assert_eq!(m.vertex_count(), 7 * 11 - 2);
    assert_eq!(m.degenerate_triangles(), 0);
    let soup = random_soup(100, 7);
    assert_eq!((soup.vertex_count(), soup.triangle_count()), (300, 100));
    assert_eq!(soup, random_soup(100, 7));
    assert_ne!(soup, random_soup(100, 8));
    assert!(soup.positions.iter().flatten().all(|&x| (0.0..1.0).contains(&x)));
    assert!(soup.normals.as_ref().unwrap().iter().all(|n| {
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        (l - 1.0).abs() < 1e-5
    }));
}

/// Signed volume by the divergence theorem: positive when every triangle is
/// wound counter-clockwise seen from outside.
fn signed_volume(m: &MeshData) -> f64 {
    m.indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].map(f64::from));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

#[test]
fn spheres_are_wound_outward() {
    let v = signed_volume(&icosphere(4, 2.0));
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 8.0;
    assert!(v > 0.0 && (v - exact).abs() / exact < 0.01, "{v} vs {exact}");
    let v = signed_volume(&uv_sphere(32, 64, 1.0));
    assert!(v > 0.0 && (v - 4.18879).abs() < 0.05, "{v}");
}

#[test]
fn memory_estimate_matches_the_formula() {
    let mesh = icosphere(3, 1.0); // 642 vertices with normals, 1280 triangles
    let le = tmp("estimate.ply");
    write_ply_binary(&le, &mesh, ByteOrder::LittleEndian).unwrap();
    let size = std::fs::metadata(&le).unwrap().len();
    let arrays = 642 * 24 + 1280 * 12;
    assert_eq!(mesh.memory_bytes(), arrays);
    assert_eq!(estimate_mesh_bytes(&le).unwrap(), size + arrays);
    let ascii = tmp("estimate_ascii.ply");
    write_ply_ascii(&ascii, &mesh).unwrap();
    let size = std::fs::metadata(&ascii).unwrap().len();
    assert_eq!(estimate_mesh_bytes(&ascii).unwrap(), size + arrays);
    // A binary file of quads: 2 triangles per face from the index bytes.
    let quads = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
    let mut data = quads.to_vec();
    data.extend(std::iter::repeat_n(0u8, 48));
    let quad: Vec<u8> = std::iter::once(4u8).chain([0i32, 1, 2, 3].iter().flat_map(|i| i.to_le_bytes())).collect();
    data.extend_from_slice(&quad);
    data.extend_from_slice(&quad);
    let q = tmp("quads.ply");
    std::fs::write(&q, &data).unwrap();
    assert_eq!(estimate_mesh_bytes(&q).unwrap(), data.len() as u64 + 4 * 12 + 4 * 12);
    let obj = tmp("estimate.obj");
    write_obj(&obj, &mesh).unwrap();
    let size = std::fs::metadata(&obj).unwrap().len();
    assert_eq!(estimate_mesh_bytes(&obj).unwrap(), size * niebla_mesh::OBJ_BYTES_PER_FILE_BYTE);
    let options = MeshReadOptions { max_bytes: Some(size), ..Default::default() };
    let err = read_mesh(&obj, &options).unwrap_err().to_string();
    assert!(err.contains("estimate.obj: reading this mesh would take about") && err.contains("more than the limit"));
}
