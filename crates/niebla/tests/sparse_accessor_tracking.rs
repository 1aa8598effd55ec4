//! The trackers read sparse grids through a cached `SparseAccessor` (made
//! per ray in `with_grid_along_ray`); their estimates must be bit-identical
//! to the same trackers reading the grid's uncached tree lookup, with the
//! same random numbers, on a blob-shaped sparse grid with tiles, empty
//! space and rays crossing leaf and internal-node borders.

use niebla::color::Rgb;
use niebla::math::Vec3;
use niebla::sampling::PixelSampler;
use niebla::tracking::{delta_tracking, ratio_tracking, residual_ratio_tracking, GridAlongRay, GridLookup};
use niebla_volume::{Affine, DensityBoundGrid, MajorantGrid, SparseGrid, SparseGridBuilder};

fn blob_grid() -> SparseGrid {
    let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
    b.fill_tile(2, [120, 8, 8], 0.9, true);
    b.fill_tile(2, [128, 8, 8], 0.6, true); // across the 128-voxel lower-node border
    for (c, r) in [([30.0f32, 30.0, 30.0], 22.0f32), ([110.0, 20.0, 20.0], 16.0), ([60.0, 70.0, 40.0], 12.0)] {
        let lo = c.map(|v| (v - r) as i32);
        for k in lo[2]..lo[2] + 2 * r as i32 + 1 {
            for j in lo[1]..lo[1] + 2 * r as i32 + 1 {
                for i in lo[0]..lo[0] + 2 * r as i32 + 1 {
                    let d = [i as f32 - c[0], j as f32 - c[1], k as f32 - c[2]];
                    let d = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    if d < r {
                        let ripple = 0.75 + 0.25 * (i as f32 * 0.7).sin() * (k as f32 * 0.4).cos();
                        b.set_voxel([i, j, k], (1.0 - d / r) * ripple, true);
                    }
                }
            }
        }
    }
    b.build()
}

fn run<G: GridLookup>(
    grid: &G,
    majorant: &MajorantGrid,
    minorant: &DensityBoundGrid,
    o: Vec3,
    d: Vec3,
    key: u64,
) -> [Rgb; 3] {
    let r = GridAlongRay { grid, majorant, minorant: Some(minorant), o, d, t0: 0.0, t1: 1.0, motion: None };
    let sigma_t = Rgb::new(3.5, 5.0, 8.0);
    let mut s = PixelSampler::from_key(key);
    [
        ratio_tracking(&r, sigma_t, &mut s),
        delta_tracking(&r, sigma_t, &mut s),
        residual_ratio_tracking(&r, sigma_t, &mut s),
    ]
}

#[test]
fn trackers_read_the_same_densities_through_the_accessor() {
    let g = blob_grid();
    let majorant = MajorantGrid::from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
    let minorant = MajorantGrid::minorant_from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
    let mut not_one = 0;
    for n in 0..2000u64 {
        // Chords between seeded points of the box [0, 140] x [0, 90] x [0, 60].
        let h = |k: u64| ((n * 0x9e37_79b9 + k * 0x85eb_ca6b) % 1000) as f32 / 1000.0;
        let o = Vec3::new(140.0 * h(1), 90.0 * h(2), 60.0 * h(3));
        let q = Vec3::new(140.0 * h(4), 90.0 * h(5), 60.0 * h(6));
        let tree = run(&g, &majorant, &minorant, o, q - o, n);
        let acc = g.accessor();
        let cached = run(&acc, &majorant, &minorant, o, q - o, n);
        for (a, b) in tree.iter().zip(&cached) {
            for c in 0..3 {
                assert_eq!(a[c].to_bits(), b[c].to_bits(), "ray {n}: tree {a:?}, accessor {b:?}");
            }
        }
        not_one += (tree[0][2] < 0.999) as usize;
    }
    // Many chords cross the blobs (the test compares real work).
    assert!(not_one > 200, "only {not_one} of 2000 rays were attenuated");
}
