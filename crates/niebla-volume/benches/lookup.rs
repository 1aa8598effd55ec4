//! Density lookups per second for dense f32, dense f16 and sparse grids at
//! random points inside their bounds and along rays (sparse: the uncached
//! tree lookup and the cached [`SparseAccessor`]), with the sparse grids'
//! memory, at 256^3, 512^3 and 1024^3 procedural blob fields; DDA segments
//! per second, and the time to build majorant and minorant grids and to bake
//! procedural densities.
//!
//! Run: `cargo bench -p niebla-volume --bench lookup`
//! (set `NIEBLA_BENCH_VDB=file.vdb` to also time the `density` grid of a file;
//! `NIEBLA_BENCH_ONLY=scale` runs only the 256^3-1024^3 blob section).

use std::hint::black_box;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use niebla_volume::{
    procedural_density, Affine, DenseGrid, MajorantGrid, ProceduralParams, ProceduralShape, SparseAccessor, SparseGrid,
    SparseGridBuilder, VdbFile,
};

struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn point(&mut self, lo: [f32; 3], hi: [f32; 3]) -> [f32; 3] {
        [0, 1, 2].map(|a| lo[a] + (hi[a] - lo[a]) * self.uniform())
    }
}

/// Smooth bounded test field: a ball with a ripple, zero outside radius 1.
fn field(p: [f32; 3]) -> f32 {
    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    if r < 1.0 {
        (1.0 - r) * (0.75 + 0.25 * (p[0] * 12.0 + p[2] * 3.0).sin())
    } else {
        0.0
    }
}

/// `count` points marched along random chords of [-1, 1]^3 with the given
/// step: the access pattern of a tracker, coherent in memory.
fn ray_march_points(rng: &mut Rng, count: usize, step: f32) -> Vec<[f32; 3]> {
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        let (o, q) = (rng.point([-1.0; 3], [1.0; 3]), rng.point([-1.0; 3], [1.0; 3]));
        let d = [q[0] - o[0], q[1] - o[1], q[2] - o[2]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-6);
        let steps = (len / step) as usize;
        for s in 0..steps.min(count - out.len()) {
            let t = s as f32 / steps as f32;
            out.push([o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]]);
        }
    }
    out
}

/// Runs `f` over `points` repeatedly for about `budget`; returns calls per second.
fn rate(points: &[[f32; 3]], budget: Duration, f: impl Fn([f32; 3]) -> f32) -> f64 {
    let start = Instant::now();
    let mut calls = 0u64;
    let mut sum = 0.0f32;
    while start.elapsed() < budget {
        for &p in points {
            sum += f(p);
        }
        calls += points.len() as u64;
    }
    black_box(sum);
    calls as f64 / start.elapsed().as_secs_f64()
}

fn report(name: &str, per_second: f64) {
    println!("{name:<44} {:>8.1} M lookups/s  ({:.2} ns each)", per_second / 1e6, 1e9 / per_second);
}

fn main() {
    // `cargo test --all-targets` runs bench binaries without `--bench`: print
    // figures only when asked by `cargo bench`.
    if !std::env::args().any(|a| a == "--bench") {
        println!("lookup bench: run with `cargo bench -p niebla-volume --bench lookup`");
        return;
    }
    let budget = Duration::from_millis(1500);
    let mut rng = Rng(42);
    if std::env::var("NIEBLA_BENCH_ONLY").as_deref() == Ok("scale") {
        bench_scale(&mut rng, Duration::from_millis(800));
        return;
    }
    let n = 256;

    // Dense 256^3 over [-1, 1]^3.
    let mut data = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let c = |i: usize| (i as f32 + 0.5) / n as f32 * 2.0 - 1.0;
                data.push(field([c(x), c(y), c(z)]));
            }
        }
    }
    let dense = DenseGrid::new([n; 3], data, [-1.0; 3], [1.0; 3]).unwrap();
    let dense_f16 = dense.to_f16();
    let points: Vec<[f32; 3]> = (0..1 << 20).map(|_| rng.point([-1.0; 3], [1.0; 3])).collect();
    let coherent = ray_march_points(&mut rng, 1 << 20, 0.5 / n as f32 * 2.0);
    let small_data: Vec<f32> = (0..32 * 32 * 32).map(|i| (i % 97) as f32 / 97.0).collect();
    let small = DenseGrid::new([32; 3], small_data, [-1.0; 3], [1.0; 3]).unwrap();
    report("dense f32 32^3 lookup (in cache)", rate(&points, budget, |p| small.lookup(p)));
    report("dense f32 256^3 lookup, random points", rate(&points, budget, |p| dense.lookup(p)));
    report("dense f16 256^3 lookup, random points", rate(&points, budget, |p| dense_f16.lookup(p)));
    report("dense f32 256^3 lookup, along rays", rate(&coherent, budget, |p| dense.lookup(p)));
    report("dense f16 256^3 lookup, along rays", rate(&coherent, budget, |p| dense_f16.lookup(p)));

    // Sparse: the same ball, voxels at index (i, j, k) = world * 128.
    let start = Instant::now();
    let mut b = SparseGridBuilder::new(0.0, Affine::scale_translate([1.0 / 128.0; 3], [0.0; 3]));
    for k in -128..128 {
        for j in -128..128 {
            for i in -128..128 {
                let v = field([i as f32 / 128.0, j as f32 / 128.0, k as f32 / 128.0]);
                if v > 0.0 {
                    b.set_voxel([i, j, k], v, true);
                }
            }
        }
    }
    let sparse = b.build();
    println!(
        "(built sparse ball: {} leaves, {} active voxels in {:.2} s)",
        sparse.leaf_count(),
        sparse.active_voxel_count(),
        start.elapsed().as_secs_f64()
    );
    let index_points: Vec<[f32; 3]> = points.iter().map(|p| p.map(|v| v * 128.0)).collect();
    let index_coherent: Vec<[f32; 3]> = coherent.iter().map(|p| p.map(|v| v * 128.0)).collect();
    report("sparse ball lookup_index, random points", rate(&index_points, budget, |p| sparse.lookup_index(p)));
    report("sparse ball lookup_world, random points", rate(&points, budget, |p| sparse.lookup_world(p)));
    report("sparse ball lookup_index, along rays", rate(&index_coherent, budget, |p| sparse.lookup_index(p)));
    report("sparse ball lookup_world, along rays", rate(&coherent, budget, |p| sparse.lookup_world(p)));
    let acc = sparse.accessor();
    report("sparse ball accessor lookup_index, random", rate(&index_points, budget, |p| acc.lookup_index(p)));
    report("sparse ball accessor lookup_index, along rays", rate(&index_coherent, budget, |p| acc.lookup_index(p)));
    bench_majorant(&dense, &sparse, &mut rng, budget);
    bench_procedural();
    drop((dense, dense_f16, sparse));
    bench_scale(&mut rng, Duration::from_millis(800));

    if let Ok(path) = std::env::var("NIEBLA_BENCH_VDB") {
        let start = Instant::now();
        let grid: SparseGrid = match VdbFile::open(&path).and_then(|f| f.read_float_grid("density")) {
            Ok(g) => g,
            Err(e) => {
                eprintln!("NIEBLA_BENCH_VDB: {e}");
                return;
            }
        };
        println!("(read {path}: {} leaves in {:.2} s)", grid.leaf_count(), start.elapsed().as_secs_f64());
        let (lo, hi) = grid.data_bounds_index().unwrap();
        let (lo, hi) = (lo.map(|v| v as f32), hi.map(|v| v as f32));
        let pts: Vec<[f32; 3]> = (0..1 << 20).map(|_| rng.point(lo, hi)).collect();
        report("VDB file lookup_index", rate(&pts, budget, |p| grid.lookup_index(p)));
    }
}

fn bench_majorant(dense: &DenseGrid, sparse: &SparseGrid, rng: &mut Rng, budget: Duration) {
    let start = Instant::now();
    let m_dense = MajorantGrid::from_dense(dense, MajorantGrid::DEFAULT_RESOLUTION);
    let t_dense = start.elapsed();
    let start = Instant::now();
    let m_sparse = MajorantGrid::from_sparse(sparse, MajorantGrid::DEFAULT_MAX_CELLS);
    let t_sparse = start.elapsed();
    println!(
        "(majorant grids: dense 16^3 in {:.1} ms, sparse {:?} in {:.1} ms)",
        t_dense.as_secs_f64() * 1e3,
        m_sparse.res(),
        t_sparse.as_secs_f64() * 1e3
    );
    let start = Instant::now();
    black_box(MajorantGrid::minorant_from_dense(dense, MajorantGrid::DEFAULT_RESOLUTION));
    let t_dense = start.elapsed();
    let start = Instant::now();
    black_box(MajorantGrid::minorant_from_sparse(sparse, MajorantGrid::DEFAULT_MAX_CELLS));
    let t_sparse = start.elapsed();
    println!(
        "(minorant grids: dense 16^3 in {:.1} ms, sparse in {:.1} ms)",
        t_dense.as_secs_f64() * 1e3,
        t_sparse.as_secs_f64() * 1e3
    );
    for (name, m) in [("DDA walk, dense 16^3 majorants", &m_dense), ("DDA walk, sparse per-leaf majorants", &m_sparse)]
    {
        let (lo, hi) = m.bounds();
        let rays: Vec<([f32; 3], [f32; 3])> = (0..1 << 14)
            .map(|_| {
                let (o, q) = (rng.point(lo, hi), rng.point(lo, hi));
                (o, [q[0] - o[0], q[1] - o[1], q[2] - o[2]])
            })
            .collect();
        let start = Instant::now();
        let (mut segments, mut walks) = (0u64, 0u64);
        while start.elapsed() < budget {
            for (o, d) in &rays {
                let _ = m.walk(*o, *d, 0.0, f32::INFINITY, |s| {
                    black_box(s);
                    segments += 1;
                    ControlFlow::Continue(())
                });
            }
            walks += rays.len() as u64;
        }
        let secs = start.elapsed().as_secs_f64();
        println!(
            "{name:<44} {:>8.1} M segments/s  ({:.1} segments per ray, {:.2} M rays/s)",
            segments as f64 / secs / 1e6,
            segments as f64 / walks as f64,
            walks as f64 / secs / 1e6
        );
    }
}

/// Single-threaded bake time of the procedural densities at default
/// parameters, best of three runs.
fn bench_procedural() {
    for n in [64, 128, 256] {
        for shape in [ProceduralShape::Cloud, ProceduralShape::Plume] {
            let params = ProceduralParams { shape, resolution: [n; 3], ..ProceduralParams::default() };
            let mut best = f64::INFINITY;
            for _ in 0..3 {
                let start = Instant::now();
                black_box(procedural_density(&params).unwrap());
                best = best.min(start.elapsed().as_secs_f64());
            }
            let name = format!("procedural {shape:?} bake {n}^3");
            println!("{name:<44} {:>8.1} ms  ({:.1} ns per voxel)", best * 1e3, best * 1e9 / (n * n * n) as f64);
        }
    }
}

/// A sparse "cloud" in the index box `[0, n)^3`: a dozen seeded noisy balls
/// (radii n/16 to n/6, about 5% of the box), density 1 in their cores (kept
/// as 8^3 tiles, as OpenVDB's pruning would) falling to 0 at their rims,
/// modulated by a ripple; empty elsewhere.
struct Blobs {
    balls: Vec<([f32; 3], f32)>,
}

impl Blobs {
    fn new(n: usize, rng: &mut Rng) -> Blobs {
        let n = n as f32;
        let balls = (0..12)
            .map(|_| {
                let r = n / 16.0 + (n / 6.0 - n / 16.0) * rng.uniform();
                let c = [0, 1, 2].map(|_| r + (n - 2.0 * r) * rng.uniform());
                (c, r)
            })
            .collect();
        Blobs { balls }
    }

    fn value(&self, ijk: [i32; 3]) -> f32 {
        let p = ijk.map(|v| v as f32);
        let ripple = 0.8 + 0.2 * (p[0] * 0.21 + p[1] * 0.13).sin() * (p[2] * 0.17).cos();
        let mut v = 0.0f32;
        for (c, r) in &self.balls {
            let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
            v = v.max(2.5 * (1.0 - d / r) * ripple);
        }
        v.min(1.0)
    }

    /// Whether every voxel of the 8^3 block at `origin` is 1 (within a third
    /// of a radius of some centre, where `2.5 (1 - d/r) 0.6 >= 1`), or 0.
    fn block_state(&self, origin: [i32; 3]) -> Option<f32> {
        let lo = origin.map(|v| v as f32);
        let hi = lo.map(|v| v + 7.0);
        let mut all_zero = true;
        for (c, r) in &self.balls {
            let near: f32 = (0..3).map(|a| (c[a] - c[a].clamp(lo[a], hi[a])).powi(2)).sum::<f32>().sqrt();
            let far: f32 = (0..3).map(|a| (c[a] - lo[a]).abs().max((c[a] - hi[a]).abs()).powi(2)).sum::<f32>().sqrt();
            if far <= r / 3.0 - 0.01 {
                return Some(1.0);
            }
            all_zero &= near >= *r;
        }
        all_zero.then_some(0.0)
    }

    fn build(&self, n: usize) -> SparseGrid {
        let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
        let blocks = (n / 8) as i32;
        for bk in 0..blocks {
            for bj in 0..blocks {
                for bi in 0..blocks {
                    let origin = [bi * 8, bj * 8, bk * 8];
                    match self.block_state(origin) {
                        Some(0.0) => continue,
                        Some(v) => b.fill_tile(2, origin, v, true),
                        None => {
                            for k in 0..8 {
                                for j in 0..8 {
                                    for i in 0..8 {
                                        let ijk = [origin[0] + i, origin[1] + j, origin[2] + k];
                                        let v = self.value(ijk);
                                        if v > 0.0 {
                                            b.set_voxel(ijk, v, true);
                                        }
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        b.build()
    }
}

/// Lookups per second at 256^3, 512^3 and 1024^3 blob fields: sparse tree
/// lookups, sparse accessor lookups and (up to 512^3) a dense grid of the
/// same voxels, at random points of the box and along random chords of it
/// (half-voxel steps), with the sparse grid's memory.
fn bench_scale(rng: &mut Rng, budget: Duration) {
    println!("\nblob fields (index box [0, n)^3, ~5% occupied); memory = heap bytes, payload = leaves + tiles");
    for n in [256usize, 512, 1024] {
        let blobs = Blobs::new(n, rng);
        let start = Instant::now();
        let sparse = blobs.build(n);
        println!(
            "({n}^3: {} leaves, {} 8^3 tiles, {} active voxels, built in {:.1} s; memory {:.1} MiB, payload {:.1} MiB, ratio {:.3})",
            sparse.leaf_count(),
            sparse.tiles().len(),
            sparse.active_voxel_count(),
            start.elapsed().as_secs_f64(),
            sparse.memory_bytes() as f64 / (1u64 << 20) as f64,
            sparse.payload_bytes() as f64 / (1u64 << 20) as f64,
            sparse.memory_bytes() as f64 / sparse.payload_bytes() as f64
        );
        let hi = [n as f32 - 1.0; 3];
        let random: Vec<[f32; 3]> = (0..1 << 20).map(|_| rng.point([0.0; 3], hi)).collect();
        // Chords of [0, n)^3, and chords between points inside two balls
        // (where a tracker's lookups go: the majorants skip empty space),
        // marched in half-voxel steps.
        let unit: Vec<[f32; 3]> = ray_march_points(rng, 1 << 21, 1.0 / n as f32);
        let box_rays: Vec<[f32; 3]> = unit.iter().map(|p| p.map(|v| (v + 1.0) * 0.5 * (n as f32 - 1.0))).collect();
        let mut blob_rays = Vec::with_capacity(1 << 21);
        while blob_rays.len() < 1 << 21 {
            let mut inside = || {
                let (c, r) = blobs.balls[(rng.uniform() * blobs.balls.len() as f32) as usize % blobs.balls.len()];
                [0, 1, 2].map(|a| c[a] + r * 0.6 * (2.0 * rng.uniform() - 1.0))
            };
            let (o, q) = (inside(), inside());
            let len = ((q[0] - o[0]).powi(2) + (q[1] - o[1]).powi(2) + (q[2] - o[2]).powi(2)).sqrt();
            let steps = (2.0 * len) as usize;
            for s in 0..steps.min((1 << 21) - blob_rays.len()) {
                let t = s as f32 / steps as f32;
                blob_rays.push([0, 1, 2].map(|a| o[a] + t * (q[a] - o[a])));
            }
        }
        let inside = |pts: &[[f32; 3]]| {
            100.0 * pts.iter().filter(|&&p| sparse.lookup_index(p) > 0.0).count() as f64 / pts.len() as f64
        };
        println!(
            "({:.0}% of box-chord points and {:.0}% of blob-chord points are inside the blobs)",
            inside(&box_rays),
            inside(&blob_rays)
        );
        let acc = SparseAccessor::new(&sparse);
        // The same voxels dense (up to 512^3): cell (x, y, z) centred at index (x, y, z).
        let dense = (n <= 512).then(|| {
            let mut data = Vec::with_capacity(n * n * n);
            for z in 0..n as i32 {
                for y in 0..n as i32 {
                    for x in 0..n as i32 {
                        data.push(acc.value([x, y, z]));
                    }
                }
            }
            println!("({n}^3 dense f32: {:.1} MiB)", (n * n * n * 4) as f64 / (1u64 << 20) as f64);
            DenseGrid::new([n; 3], data, [-0.5; 3], [n as f32 - 0.5; 3]).unwrap()
        });
        // Three interleaved rounds, best of each (the machine may be busy).
        for (what, points) in
            [("random points", &random), ("along box chords", &box_rays), ("along blob chords", &blob_rays)]
        {
            let (mut tree, mut cached, mut full) = (0.0f64, 0.0f64, 0.0f64);
            for _ in 0..3 {
                tree = tree.max(rate(points, budget / 3, |p| sparse.lookup_index(p)));
                cached = cached.max(rate(points, budget / 3, |p| acc.lookup_index(p)));
                if let Some(d) = &dense {
                    full = full.max(rate(points, budget / 3, |p| d.lookup(p)));
                }
            }
            report(&format!("{n}^3 sparse tree, {what}"), tree);
            report(&format!("{n}^3 sparse accessor, {what}"), cached);
            if dense.is_some() {
                report(&format!("{n}^3 dense f32, {what}"), full);
                println!("{:<44} {:>8.2} (accessor / dense)", format!("{n}^3 ratio, {what}"), cached / full);
            }
        }
    }
}
