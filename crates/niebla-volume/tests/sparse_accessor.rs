//! The cached accessor returns exactly what the uncached tree lookups
//! return, at random points and at points marched along rays, on a grid
//! shaped like real data: noisy blobs (some across upper-node and
//! negative-coordinate borders), 8^3 and 128^3 tiles beside leaves, a root
//! tile, and empty space, with a non-zero background.

use std::collections::HashMap;

use niebla_volume::{Affine, SparseGrid, SparseGridBuilder};

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        // SplitMix64.
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.uniform()
    }
}

const BACKGROUND: f32 = 0.125;

/// The test grid and, independently, every voxel value it was given.
fn blob_grid() -> (SparseGrid, HashMap<[i32; 3], f32>) {
    let mut rng = Rng(7);
    let mut b = SparseGridBuilder::new(BACKGROUND, Affine::scale_translate([0.01; 3], [0.5, -0.25, 0.0]));
    let mut voxels = HashMap::new();
    // Tiles first (voxels set later split them).
    b.fill_tile(1, [256, 0, 0], 0.75, true); // 128^3 tile [256, 384) x [0, 128) x [0, 128)
    b.fill_tile(2, [48, 0, 0], 2.0, true); // 8^3 tiles beside the first blob
    b.fill_tile(2, [-8, -8, -8], 1.5, true);
    b.fill_tile(2, [4088, 32, 32], 3.0, false);
    b.fill_tile(0, [8192, 0, 0], 0.5, true); // a 4096^3 root tile
                                             // Noisy balls: (center, radius).
    let blobs: [([i32; 3], i32); 5] =
        [([20, 20, 20], 18), ([4096, 70, 70], 14), ([-30, 5, -40], 12), ([300, 60, 60], 10), ([8190, 3, 3], 9)];
    for (c, r) in blobs {
        for k in -r..=r {
            for j in -r..=r {
                for i in -r..=r {
                    if i * i + j * j + k * k > r * r {
                        continue;
                    }
                    let ijk = [c[0] + i, c[1] + j, c[2] + k];
                    let v = rng.range(0.0, 4.0);
                    let active = rng.uniform() < 0.9;
                    b.set_voxel(ijk, v, active);
                    voxels.insert(ijk, v);
                }
            }
        }
    }
    (b.build(), voxels)
}

/// Box enclosing every blob and tile except the far root tile, plus margin.
const LO: [f32; 3] = [-60.0, -20.0, -60.0];
const HI: [f32; 3] = [4120.0, 140.0, 140.0];

#[test]
fn voxel_values_match_the_tree_and_an_independent_table() {
    let (g, voxels) = blob_grid();
    assert!(g.leaf_count() > 20, "{} leaves", g.leaf_count());
    let acc = g.accessor();
    for (&ijk, &v) in &voxels {
        assert_eq!(acc.value(ijk).to_bits(), v.to_bits(), "voxel {ijk:?}");
    }
    // Tiles and background, in an order that hops between nodes.
    let probes: [([i32; 3], f32); 8] = [
        ([300, 100, 5], 0.75),
        ([50, 3, 3], 2.0),
        ([-1, -1, -1], 1.5),
        ([4090, 35, 35], 3.0),
        ([9000, 9, 9], 0.5),
        ([200, 200, 200], BACKGROUND),
        ([-5000, 0, 0], BACKGROUND),
        ([300, 100, 5], 0.75),
    ];
    for (ijk, v) in probes {
        assert_eq!(acc.value(ijk), v, "voxel {ijk:?}");
        assert_eq!(g.value(ijk), v, "voxel {ijk:?}");
    }
}

#[test]
fn random_points_match_the_uncached_lookup_bit_for_bit() {
    let (g, _) = blob_grid();
    let acc = g.accessor();
    let mut rng = Rng(11);
    let mut off_background = 0;
    for n in 0..400_000 {
        // Alternate the whole box with the neighbourhood of the first blob
        // and its tiles, so that leaves, tiles and background all occur.
        let p = if n % 2 == 0 {
            [0, 1, 2].map(|a| rng.range(LO[a], HI[a]))
        } else {
            [0, 1, 2].map(|_| rng.range(-12.0, 60.0))
        };
        let (a, b) = (acc.lookup_index(p), g.lookup_index(p));
        assert_eq!(a.to_bits(), b.to_bits(), "at {p:?}: accessor {a}, tree {b}");
        off_background += (b != BACKGROUND) as usize;
    }
    assert!(off_background > 15_000, "only {off_background} points off the background");
    // Far away and non-finite points give the background, as the tree does.
    for p in [[1e10, 0.0, 0.0], [f32::NAN, 1.0, 1.0], [9000.5, 10.25, 3.0]] {
        assert_eq!(acc.lookup_index(p).to_bits(), g.lookup_index(p).to_bits(), "at {p:?}");
    }
}

#[test]
fn ray_coherent_points_match_the_uncached_lookup_bit_for_bit() {
    let (g, _) = blob_grid();
    let mut rng = Rng(13);
    let mut total = 0usize;
    let mut off_background = 0usize;
    for ray in 0..3000 {
        // One accessor per ray, as the renderer uses it; rays aimed at the
        // blobs and tiles (small boxes) and through the whole box.
        let acc = g.accessor();
        let (lo, hi) = match ray % 3 {
            0 => ([-45.0, -15.0, -55.0], [60.0, 45.0, 45.0]),
            1 => ([240.0, -5.0, -5.0], [400.0, 135.0, 135.0]),
            _ => ([4070.0, 50.0, 50.0], [4115.0, 90.0, 90.0]),
        };
        let o: [f32; 3] = std::array::from_fn(|a| rng.range(lo[a], hi[a]));
        let q: [f32; 3] = std::array::from_fn(|a| rng.range(lo[a], hi[a]));
        let step = rng.range(0.05, 1.5);
        let d = [q[0] - o[0], q[1] - o[1], q[2] - o[2]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-3);
        let steps = (len / step) as usize;
        for s in 0..=steps {
            let t = s as f32 / steps.max(1) as f32;
            let p = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
            let (a, b) = (acc.lookup_index(p), g.lookup_index(p));
            assert_eq!(a.to_bits(), b.to_bits(), "ray {ray} at {p:?}: accessor {a}, tree {b}");
            // World-space lookups go through the same transform.
            let w = g.index_to_world(p);
            assert_eq!(acc.lookup_world(w).to_bits(), g.lookup_world(w).to_bits(), "ray {ray} at world {w:?}");
            total += 1;
            off_background += (b != BACKGROUND) as usize;
        }
    }
    assert!(total > 100_000 && off_background > total / 4, "{off_background} of {total} points off the background");
}

#[test]
fn voxel_walks_across_node_borders_match() {
    // Unit steps along each axis across leaf, lower- and upper-node borders
    // (and negative coordinates), where the cache must be replaced.
    let (g, _) = blob_grid();
    let acc = g.accessor();
    for (start, axis) in [([-60, 20, 20], 0), ([4000, 70, 70], 0), ([20, -40, 20], 1), ([4096, 70, -20], 2)] {
        for s in 0..200 {
            let mut ijk = start;
            ijk[axis] += s;
            assert_eq!(acc.value(ijk).to_bits(), g.value(ijk).to_bits(), "voxel {ijk:?}");
            let p = ijk.map(|v| v as f32 + 0.5);
            assert_eq!(acc.lookup_index(p).to_bits(), g.lookup_index(p).to_bits(), "point {p:?}");
        }
    }
}
