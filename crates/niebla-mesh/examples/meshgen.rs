//! Writes a generated mesh, for benchmarks and for trying readers:
//! `meshgen icosphere SUBDIVISIONS OUT`, `meshgen uvsphere N_THETA N_PHI OUT`,
//! `meshgen blob SUBDIVISIONS AMPLITUDE_PERCENT OUT` or
//! `meshgen soup TRIANGLES SEED OUT`, where OUT ends in `.obj` or `.ply`
//! (binary little-endian; `--ascii` or `--big-endian` before the kind
//! change that; `--positions-only` drops normals and uvs). Radius 1 for the
//! spheres.

use niebla_mesh::{blob, icosphere, random_soup, uv_sphere, write_obj, write_ply_ascii, write_ply_binary, ByteOrder};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let ascii = take_flag(&mut args, "--ascii");
    let big = take_flag(&mut args, "--big-endian");
    let bare = take_flag(&mut args, "--positions-only");
    let n = |i: usize| -> u64 { args.get(i).and_then(|a| a.parse().ok()).unwrap_or_else(|| usage()) };
    let (mut mesh, out) = match args.first().map(String::as_str) {
        Some("icosphere") => (icosphere(n(1) as u32, 1.0), args.get(2)),
        Some("uvsphere") => (uv_sphere(n(1) as u32, n(2) as u32, 1.0), args.get(3)),
        Some("soup") => (random_soup(n(1) as u32, n(2)), args.get(3)),
        Some("blob") => (blob(n(1) as u32, n(2) as f32 / 100.0), args.get(3)),
        _ => usage(),
    };
    let out = out.unwrap_or_else(|| usage()).clone();
    if bare {
        mesh.normals = None;
        mesh.uvs = None;
    }
    let out = &out;
    let result = if out.to_ascii_lowercase().ends_with(".obj") {
        write_obj(out, &mesh)
    } else if ascii {
        write_ply_ascii(out, &mesh)
    } else {
        write_ply_binary(out, &mesh, if big { ByteOrder::BigEndian } else { ByteOrder::LittleEndian })
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
    println!("{out}: {} vertices, {} triangles", mesh.vertex_count(), mesh.triangle_count());
}

fn take_flag(args: &mut Vec<String>, flag: &str) -> bool {
    let found = args.iter().any(|a| a == flag);
    args.retain(|a| a != flag);
    found
}

fn usage() -> ! {
    eprintln!("usage: meshgen [--ascii] [--big-endian] [--positions-only] icosphere S OUT | uvsphere NT NP OUT | blob S PERCENT OUT | soup N SEED OUT");
    std::process::exit(2);
}
