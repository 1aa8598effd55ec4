//! Prints, for each mesh file given, its counts, attributes, bounds,
//! degenerate triangles, closedness, memory estimate and read time, or the
//! error. `cargo run --release -p niebla-mesh --example meshinfo -- FILE...`
//! (`--object NAME` before the files selects an OBJ object; `--read-only`
//! skips the topology check, to measure reading alone).

use std::time::Instant;

use niebla_mesh::{estimate_mesh_bytes, read_mesh, MeshReadOptions};

fn main() {
    let mut options = MeshReadOptions::default();
    let mut args = std::env::args().skip(1);
    let mut status = 0;
    let mut read_only = false;
    while let Some(arg) = args.next() {
        if arg == "--object" {
            options.object = args.next();
            continue;
        }
        if arg == "--read-only" {
            read_only = true;
            continue;
        }
        let estimate = estimate_mesh_bytes(&arg);
        let start = Instant::now();
        match read_mesh(&arg, &options) {
            Ok(m) if read_only => {
                let seconds = start.elapsed().as_secs_f64();
                println!(
                    "{arg}: {} vertices, {} triangles, arrays {} bytes, estimate {} bytes, read in {seconds:.3} s",
                    m.vertex_count(),
                    m.triangle_count(),
                    m.memory_bytes(),
                    estimate.map_or_else(|e| e.to_string(), |b| b.to_string()),
                );
            }
            Ok(m) => {
                let seconds = start.elapsed().as_secs_f64();
                let c = m.closedness();
                println!(
                    "{arg}: {} vertices, {} triangles, normals {}, uvs {}, bounds {:?}, degenerate {}, \
                     boundary edges {}, non-manifold {}, inconsistent {}, closed {}, arrays {} bytes, \
                     estimate {} bytes, read in {:.3} s",
                    m.vertex_count(),
                    m.triangle_count(),
                    m.normals.is_some(),
                    m.uvs.is_some(),
                    m.bounds(),
                    c.degenerate_triangles,
                    c.boundary_edges,
                    c.non_manifold_edges,
                    c.inconsistent_edges,
                    c.is_closed(),
                    m.memory_bytes(),
                    estimate.map_or_else(|e| e.to_string(), |b| b.to_string()),
                    seconds
                );
            }
            Err(e) => {
                println!("error: {e}");
                status = 1;
            }
        }
    }
    std::process::exit(status);
}
