//! `niebla bench geometry`: figures, not tests. Builds the hierarchy of
//! generated meshes of 10^4 to 10^7 triangles (icospheres, optionally
//! displaced into a rough, non-convex surface) and reports build time,
//! memory, and closest-hit and any-hit rays per second for primary rays (a
//! pinhole camera looking at the mesh: coherent) and random rays (origins in
//! the mesh's box, uniform directions: incoherent). `--export DIR` writes
//! each mesh as binary PLY and its rays as raw little-endian `f32` so that
//! `bench/geometry.py` can trace the same rays with Mitsuba 3.

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use clap::Args;
use niebla::geometry::{MeshInstance, Transform, TriangleMesh};
use niebla::math::{Ray, Vec2, Vec3};
use niebla::sampling::PixelSampler;
use rayon::prelude::*;

use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla bench geometry`.
#[derive(Args, Debug)]
pub struct GeometryBenchArgs {
    /// Icosphere subdivision levels to measure (20 * 4^k triangles each;
    /// 5..=10 spans 2.0e4 to 2.1e7).
    #[arg(long, value_delimiter = ',', default_values_t = vec![5u32, 6, 7, 8, 9])]
    pub levels: Vec<u32>,
    /// Rays per measurement.
    #[arg(long, default_value_t = 1_000_000)]
    pub rays: usize,
    /// Displace the sphere's vertices by seeded noise (a rough, non-convex
    /// surface, closer to scanned meshes than a perfect sphere).
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub rough: bool,
    /// Write `mesh_K.ply`, `primary_K.f32` and `random_K.f32` (rays as
    /// origin xyz, direction xyz) and `niebla_K.txt` (hit counts and the sum
    /// of hit distances) for each level here.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

/// The measured mesh: an icosphere of level `level`, displaced into a bumpy
/// blob (amplitude 8% of the radius) when `rough`.
fn generate(level: u32, rough: bool) -> niebla_mesh::MeshData {
    if rough {
        niebla_mesh::blob(level, 0.08)
    } else {
        niebla_mesh::icosphere(level, 1.0)
    }
}

fn primary_rays(n: usize, lo: Vec3, hi: Vec3) -> Vec<Ray> {
    let center = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let eye = center + Vec3::new(0.3, 0.4, 1.0).normalize() * (2.5 * radius);
    let forward = (center - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let side = (n as f64).sqrt().ceil() as usize;
    let half = (25f32).to_radians().tan();
    (0..n)
        .map(|i| {
            let (x, y) = (i % side, i / side);
            let u = ((x as f32 + 0.5) / side as f32 * 2.0 - 1.0) * half;
            let v = ((y as f32 + 0.5) / side as f32 * 2.0 - 1.0) * half;
            Ray::new(eye, (forward + right * u + up * v).normalize())
        })
        .collect()
}

fn random_rays(n: usize, lo: Vec3, hi: Vec3) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let mut s = PixelSampler::from_key(0x6e6f_6973 ^ i as u64);
            let o = lo + Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * (hi - lo);
            let d = niebla::sampling::sample_uniform_sphere(Vec2::new(s.next_1d(), s.next_1d()));
            Ray::new(o, d)
        })
        .collect()
}

/// Closest-hit: (rays per second, hits, sum of hit distances).
fn time_closest(mesh: &MeshInstance, rays: &[Ray]) -> (f64, usize, f64) {
    let start = Instant::now();
    let (hits, sum) = rays
        .par_chunks(4096)
        .map(|chunk| {
            let mut hits = 0usize;
            let mut sum = 0f64;
            for r in chunk {
                if let Some(h) = mesh.hit(r, 0.0, f32::INFINITY) {
                    hits += 1;
                    sum += h.t as f64;
                }
            }
            (hits, sum)
        })
        .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    (rays.len() as f64 / start.elapsed().as_secs_f64(), hits, sum)
}

/// Any-hit: (rays per second, rays blocked).
fn time_any(mesh: &MeshInstance, rays: &[Ray]) -> (f64, usize) {
    let start = Instant::now();
    let hits: usize =
        rays.par_chunks(4096).map(|chunk| chunk.iter().filter(|r| mesh.occluded(r, 0.0, f32::INFINITY)).count()).sum();
    (rays.len() as f64 / start.elapsed().as_secs_f64(), hits)
}

fn write_rays(path: &std::path::Path, rays: &[Ray]) -> Result<(), CliError> {
    let mut bytes = Vec::with_capacity(rays.len() * 24);
    for r in rays {
        for v in [r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).map_err(|e| CliError::Io { path: path.to_path_buf(), error: e })
}

/// `niebla bench geometry`.
pub fn run(args: &GeometryBenchArgs) -> Result<(), CliError> {
    let threads = args.threads.get()?;
    if let Some(&bad) = args.levels.iter().find(|&&k| k > niebla_mesh::MAX_ICOSPHERE_SUBDIVISIONS) {
        return Err(CliError::invalid_option(
            "--levels",
            format!("{bad} is above the largest level {}", niebla_mesh::MAX_ICOSPHERE_SUBDIVISIONS),
        ));
    }
    if args.rays == 0 {
        return Err(CliError::invalid_option("--rays", "must be at least 1"));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| CliError::invalid_option("--threads", e.to_string()))?;
    if let Some(dir) = &args.export {
        std::fs::create_dir_all(dir).map_err(|e| CliError::Io { path: dir.clone(), error: e })?;
    }
    println!(
        "bench geometry: {} rays per measurement, threads {}, {} icospheres",
        args.rays,
        pool.current_num_threads(),
        if args.rough { "displaced" } else { "smooth" }
    );
    println!(
        "{:>10} {:>9} {:>12} {:>10} {:>14} {:>14} {:>14} {:>14}",
        "triangles", "build s", "s/Mtri", "memory", "primary Mray/s", "any prim.", "random Mray/s", "any random"
    );
    for &level in &args.levels {
        let data = generate(level, args.rough);
        if let Some(dir) = &args.export {
            let path = dir.join(format!("mesh_{level}.ply"));
            niebla_mesh::write_ply_binary(&path, &data, niebla_mesh::ByteOrder::LittleEndian)
                .map_err(|e| CliError::Io { path: path.clone(), error: std::io::Error::other(e.to_string()) })?;
        }
        let positions: Vec<Vec3> = data.positions.iter().map(|&p| Vec3::from(p)).collect();
        let indices = data.indices;
        let start = Instant::now();
        let mesh = pool
            .install(|| TriangleMesh::new(positions, indices, None, None))
            .map_err(|e| CliError::invalid_option("--levels", format!("level {level} made an invalid mesh: {e}")))?;
        let build = start.elapsed().as_secs_f64();
        let triangles = mesh.triangle_count();
        let memory = mesh.memory_bytes();
        let bounds = mesh.bounds().expect("a generated mesh has triangles");
        let instance = MeshInstance::new(Arc::new(mesh), Transform::IDENTITY, true);
        let primary = primary_rays(args.rays, bounds.min, bounds.max);
        let random = random_rays(args.rays, bounds.min, bounds.max);
        // One untimed pass warms the caches.
        pool.install(|| time_closest(&instance, &primary[..primary.len().min(10_000)]));
        let (p_closest, p_hits, p_sum) = pool.install(|| time_closest(&instance, &primary));
        let (p_any, p_blocked) = pool.install(|| time_any(&instance, &primary));
        let (r_closest, r_hits, r_sum) = pool.install(|| time_closest(&instance, &random));
        let (r_any, r_blocked) = pool.install(|| time_any(&instance, &random));
        println!(
            "{:>10} {:>9.3} {:>12.3} {:>10} {:>14.2} {:>14.2} {:>14.2} {:>14.2}",
            triangles,
            build,
            build / (triangles as f64 / 1e6),
            niebla::limits::format_bytes(memory as u64),
            p_closest / 1e6,
            p_any / 1e6,
            r_closest / 1e6,
            r_any / 1e6
        );
        if p_hits != p_blocked || r_hits != r_blocked {
            eprintln!("warning: any-hit and closest-hit disagree ({p_hits}/{p_blocked}, {r_hits}/{r_blocked})");
        }
        if let Some(dir) = &args.export {
            write_rays(&dir.join(format!("primary_{level}.f32")), &primary)?;
            write_rays(&dir.join(format!("random_{level}.f32")), &random)?;
            let path = dir.join(format!("niebla_{level}.txt"));
            let mut f = std::fs::File::create(&path).map_err(|e| CliError::Io { path: path.clone(), error: e })?;
            writeln!(
                f,
                "triangles {triangles}\nbuild_s {build}\nmemory {memory}\nprimary_closest {p_closest}\nprimary_any \
                 {p_any}\nprimary_hits {p_hits}\nprimary_tsum {p_sum}\nrandom_closest {r_closest}\nrandom_any \
                 {r_any}\nrandom_hits {r_hits}\nrandom_tsum {r_sum}"
            )
            .map_err(|e| CliError::Io { path: path.clone(), error: e })?;
        }
    }
    Ok(())
}
