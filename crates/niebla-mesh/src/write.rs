//! Writers for PLY (ASCII, binary little- and big-endian) and OBJ, so that
//! tests can produce the same mesh in every format the readers take.
//!
//! Values are written so that reading them back gives the same bits:
//! binary PLY stores `float`s, and text formats print each `f32` with the
//! shortest decimal that parses back to it (Rust's `Display`), which
//! `f32` parsing (this crate's PLY reader, tobj) restores exactly.
//! Negative zero stays negative zero.

use std::fmt::Write as _;
use std::path::Path;

use crate::{MeshData, MeshError};

/// Byte order of a binary PLY body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ByteOrder {
    /// `binary_little_endian`, the common one.
    LittleEndian,
    /// `binary_big_endian`.
    BigEndian,
}

/// The PLY header this crate writes: `float` x y z, then nx ny nz and u v
/// when the mesh has them, and faces as `list uchar uint vertex_indices`.
fn ply_header(mesh: &MeshData, format: &str) -> String {
    let mut h = format!(
        "ply\nformat {format} 1.0\ncomment written by niebla-mesh\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n",
        mesh.positions.len()
    );
    if mesh.normals.is_some() {
        h.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if mesh.uvs.is_some() {
        h.push_str("property float u\nproperty float v\n");
    }
    let _ = write!(h, "element face {}\nproperty list uchar uint vertex_indices\nend_header\n", mesh.indices.len());
    h
}

/// The values of vertex `i` in header order.
fn vertex_values(mesh: &MeshData, i: usize) -> impl Iterator<Item = f32> + '_ {
    let n = mesh.normals.as_ref().map(|n| n[i]);
    let uv = mesh.uvs.as_ref().map(|uv| uv[i]);
    mesh.positions[i].into_iter().chain(n.into_iter().flatten()).chain(uv.into_iter().flatten())
}

/// The mesh as an ASCII PLY file.
pub fn ply_ascii_bytes(mesh: &MeshData) -> Vec<u8> {
    let mut s = ply_header(mesh, "ascii");
    for i in 0..mesh.positions.len() {
        let mut first = true;
        for x in vertex_values(mesh, i) {
            let sep = if first { "" } else { " " };
            let _ = write!(s, "{sep}{x}");
            first = false;
        }
        s.push('\n');
    }
    for [a, b, c] in &mesh.indices {
        let _ = writeln!(s, "3 {a} {b} {c}");
    }
    s.into_bytes()
}

/// The mesh as a binary PLY file in the given byte order.
pub fn ply_binary_bytes(mesh: &MeshData, order: ByteOrder) -> Vec<u8> {
    let format = match order {
        ByteOrder::LittleEndian => "binary_little_endian",
        ByteOrder::BigEndian => "binary_big_endian",
    };
    let mut out = ply_header(mesh, format).into_bytes();
    let big = order == ByteOrder::BigEndian;
    let f = |x: f32| if big { x.to_be_bytes() } else { x.to_le_bytes() };
    let u = |x: u32| if big { x.to_be_bytes() } else { x.to_le_bytes() };
    for i in 0..mesh.positions.len() {
        for x in vertex_values(mesh, i) {
            out.extend_from_slice(&f(x));
        }
    }
    for tri in &mesh.indices {
        out.push(3);
        for &i in tri {
            out.extend_from_slice(&u(i));
        }
    }
    out
}

/// The mesh as an OBJ file: `v`, then `vt` and `vn` when present (one per
/// vertex, same numbering), and one `f` per triangle with the same 1-based
/// index for position, uv and normal (`f a/a/a`, `f a/a`, `f a//a` or
/// `f a`). The OBJ reader returns vertices in order of first use, so a mesh
/// reads back identical when its vertices already are in that order
/// ([`MeshData::renumbered_by_first_use`]).
pub fn obj_bytes(mesh: &MeshData) -> Vec<u8> {
    let mut s = String::from("# written by niebla-mesh\n");
    for [x, y, z] in &mesh.positions {
        let _ = writeln!(s, "v {x} {y} {z}");
    }
    for [u, v] in mesh.uvs.iter().flatten() {
        let _ = writeln!(s, "vt {u} {v}");
    }
    for [x, y, z] in mesh.normals.iter().flatten() {
        let _ = writeln!(s, "vn {x} {y} {z}");
    }
    let corner = |i: u32| {
        let i = i + 1;
        match (mesh.uvs.is_some(), mesh.normals.is_some()) {
            (true, true) => format!("{i}/{i}/{i}"),
            (true, false) => format!("{i}/{i}"),
            (false, true) => format!("{i}//{i}"),
            (false, false) => format!("{i}"),
        }
    };
    for [a, b, c] in &mesh.indices {
        let _ = writeln!(s, "f {} {} {}", corner(*a), corner(*b), corner(*c));
    }
    s.into_bytes()
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
    std::fs::write(path, bytes).map_err(|source| MeshError::Io { path: path.to_path_buf(), action: "write", source })
}

/// Writes the mesh as an ASCII PLY file ([`ply_ascii_bytes`]).
pub fn write_ply_ascii(path: impl AsRef<Path>, mesh: &MeshData) -> Result<(), MeshError> {
    write_file(path.as_ref(), &ply_ascii_bytes(mesh))
}

/// Writes the mesh as a binary PLY file in the given byte order
/// ([`ply_binary_bytes`]).
pub fn write_ply_binary(path: impl AsRef<Path>, mesh: &MeshData, order: ByteOrder) -> Result<(), MeshError> {
    write_file(path.as_ref(), &ply_binary_bytes(mesh, order))
}

/// Writes the mesh as an OBJ file ([`obj_bytes`]).
pub fn write_obj(path: impl AsRef<Path>, mesh: &MeshData) -> Result<(), MeshError> {
    write_file(path.as_ref(), &obj_bytes(mesh))
}
