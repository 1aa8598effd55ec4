//! The cost of the majorant DDA walk alone, in walks per CPU second of this
//! thread, on three workloads that bracket what the trackers ask of it:
//!
//! - `short`: free flights in a dense medium, where a flight ends about
//!   1.5 cells after it starts (the walk's setup dominates);
//! - `through`: rays through a 32^3 grid whose blocks are half empty, as a
//!   shadow ray through a sparse cloud (the steps and the empty-block
//!   skips dominate);
//! - `cells`: the same rays through every cell ([`MajorantGrid::walk_cells`]).
//!
//! Each workload runs `ROUNDS` times, interleaved, and the median rate is
//! printed with the sum of the segments' majorants (equal between two
//! builds whose walks agree). CPU time is read from
//! `/proc/thread-self/schedstat` (Linux; wall time elsewhere).
//!
//! ```text
//! cargo run --release -p niebla-volume --example walk_cost
//! ```

use std::hint::black_box;
use std::ops::ControlFlow;
use std::time::Instant;

use niebla_volume::MajorantGrid;

const ROUNDS: usize = 7;
const RAYS: usize = 1 << 15;

/// xorshift64 in [0, 1).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn point(&mut self, lo: [f32; 3], hi: [f32; 3]) -> [f32; 3] {
        std::array::from_fn(|a| lo[a] + (hi[a] - lo[a]) * self.uniform())
    }
    fn direction(&mut self) -> [f32; 3] {
        let z = 2.0 * self.uniform() - 1.0;
        let phi = std::f32::consts::TAU * self.uniform();
        let r = (1.0 - z * z).max(0.0).sqrt();
        [r * phi.cos(), r * phi.sin(), z]
    }
}

/// CPU seconds of this thread so far (wall seconds if unavailable).
fn cpu_seconds(wall: Instant) -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map_or_else(|| wall.elapsed().as_secs_f64(), |ns| ns as f64 * 1e-9)
}

/// One workload: rays `(o, d, t_max)` through `m`.
struct Workload {
    name: &'static str,
    m: MajorantGrid,
    rays: Vec<([f32; 3], [f32; 3], f32)>,
    every_cell: bool,
}

impl Workload {
    /// Walks every ray once: (walks, sum of majorant times length).
    fn run(&self) -> (usize, f64) {
        let mut sum = 0.0f64;
        for &(o, d, t_max) in &self.rays {
            let mut f = |_: [usize; 3], s: niebla_volume::Segment| {
                sum += f64::from(s.max_density) * f64::from(s.t1 - s.t0);
                ControlFlow::Continue(())
            };
            let _ = if self.every_cell {
                self.m.walk_cells(black_box(o), black_box(d), 0.0, t_max, &mut f)
            } else {
                self.m.walk_nonzero(black_box(o), black_box(d), 0.0, t_max, &mut f)
            };
        }
        (self.rays.len(), sum)
    }
}

fn main() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    // A dense medium's majorants: 16^3 cells over a box that does not
    // round to powers of two, all non-zero.
    let (lo, hi) = ([-1.2f32, -0.75, -1.2], [1.2f32, 0.75, 1.2]);
    let dense: Vec<f32> = (0..16 * 16 * 16).map(|_| 0.2 + rng.uniform()).collect();
    let dense = MajorantGrid::new([16; 3], lo, hi, dense).unwrap();
    let cell = (hi[0] - lo[0]) / 16.0;
    let short = (0..RAYS)
        .map(|_| {
            let o = rng.point(lo, hi);
            (o, rng.direction(), cell * (0.5 + 2.0 * rng.uniform()))
        })
        .collect();
    // A sparse cloud's majorants: 32^3 cells of 16 voxels in index space,
    // each 4^3 block empty with probability 1/2.
    let n = 32usize;
    let empty: Vec<bool> = (0..8 * 8 * 8).map(|_| rng.uniform() < 0.5).collect();
    let sparse: Vec<f32> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, i / n % n, i / (n * n));
            if empty[(z / 4 * 8 + y / 4) * 8 + x / 4] {
                0.0
            } else {
                0.1 + rng.uniform()
            }
        })
        .collect();
    let (slo, shi) = ([16.0f32, -48.0, 32.0], [528.0f32, 464.0, 544.0]);
    let sparse = MajorantGrid::new([n; 3], slo, shi, sparse).unwrap();
    let through: Vec<_> = (0..RAYS)
        .map(|_| {
            let o = rng.point(slo, shi);
            (o, rng.direction(), f32::INFINITY)
        })
        .collect();
    let workloads = [
        Workload { name: "short (dense 16^3, ~1.5 cells)", m: dense, rays: short, every_cell: false },
        Workload {
            name: "through (sparse 32^3, nonzero)",
            m: sparse.clone(),
            rays: through.clone(),
            every_cell: false,
        },
        Workload { name: "cells (sparse 32^3, every cell)", m: sparse, rays: through, every_cell: true },
    ];
    let wall = Instant::now();
    let mut rates = vec![Vec::new(); workloads.len()];
    let mut sums = vec![0.0; workloads.len()];
    for _ in 0..ROUNDS {
        for (i, w) in workloads.iter().enumerate() {
            let (mut walks, t0) = (0usize, cpu_seconds(wall));
            while cpu_seconds(wall) - t0 < 0.4 {
                let (k, s) = w.run();
                walks += k;
                sums[i] = s;
            }
            rates[i].push(walks as f64 / (cpu_seconds(wall) - t0));
        }
    }
    for (i, w) in workloads.iter().enumerate() {
        rates[i].sort_by(f64::total_cmp);
        let r = &rates[i];
        println!(
            "{:<34} median {:>6.2} M walks/CPU s (min {:.2}, max {:.2})  sum {:.6e}",
            w.name,
            r[r.len() / 2] * 1e-6,
            r[0] * 1e-6,
            r[r.len() - 1] * 1e-6,
            sums[i]
        );
    }
}
