//! The minorant is never above the interpolated density: at random points
//! of random dense and sparse grids and at points sampled along DDA
//! segments of the paired majorant grid, whose cells it shares. Constant
//! grids have equal minorants and majorants, and a cell whose interpolation
//! support holds a zero voxel has minorant zero (and only such cells).

mod common;

use std::ops::ControlFlow;

use common::Rng;
use niebla_volume::{Affine, DenseGrid, MajorantGrid, SparseGrid, SparseGridBuilder};

/// `value >= bound`, allowing the rounding of a lerp between values of
/// magnitude up to `scale`.
fn above(value: f32, bound: f32, scale: f32) -> bool {
    value >= bound - 4.0 * f32::EPSILON * scale.abs().max(bound.abs())
}

/// The cells whose closed box contains `p` (several on shared faces).
fn cells_containing(m: &MajorantGrid, p: [f32; 3]) -> Vec<[usize; 3]> {
    let res = m.res();
    let axis = |a: usize| -> Vec<usize> {
        (0..res[a])
            .filter(|&c| {
                let mut idx = [0; 3];
                idx[a] = c;
                let (lo, hi) = m.cell_bounds(idx[0], idx[1], idx[2]);
                lo[a] <= p[a] && p[a] <= hi[a]
            })
            .collect()
    };
    let mut out = Vec::new();
    for z in axis(2) {
        for y in axis(1) {
            for x in axis(0) {
                out.push([x, y, z]);
            }
        }
    }
    out
}

/// Every cell of `min` is at most the same cell of `max`, and both have
/// the same cells.
fn assert_paired(min: &MajorantGrid, max: &MajorantGrid) {
    assert!(min.same_layout(max));
    assert_eq!((min.res(), min.bounds()), (max.res(), max.bounds()));
    for (i, (lo, hi)) in min.values().iter().zip(max.values()).enumerate() {
        assert!(lo <= hi, "cell {i}: minorant {lo} > majorant {hi}");
    }
}

fn random_dense(rng: &mut Rng) -> DenseGrid {
    let dims = [1 + rng.below(12), 1 + rng.below(12), 1 + rng.below(12)];
    let n = dims[0] * dims[1] * dims[2];
    // Mostly dense with holes, so that a loose or shifted minorant shows.
    let data = (0..n)
        .map(|_| match rng.below(6) {
            0 => 0.0,
            1 => rng.range(0.0, 0.5),
            _ => rng.range(2.0, 10.0),
        })
        .collect();
    let lo = [0, 1, 2].map(|_| rng.range(-2.0, 2.0));
    let hi = [0, 1, 2].map(|a| lo[a] + rng.range(0.1, 5.0));
    DenseGrid::new(dims, data, lo, hi).unwrap()
}

/// A sparse grid with leaves, 8^3 and 128^3 tiles (some split by voxels
/// set inside them) over a background of 0 or 0.25.
fn random_sparse(rng: &mut Rng) -> SparseGrid {
    let background = if rng.below(2) == 0 { 0.0 } else { 0.25 };
    let mut b = SparseGridBuilder::new(background, Affine::IDENTITY);
    let c = [0, 1, 2].map(|_| rng.below(64) as i32 - 32);
    if rng.below(3) == 0 {
        b.fill_tile(1, c, rng.range(1.0, 3.0), true);
    }
    for _ in 0..rng.below(4) {
        let ijk = [0, 1, 2].map(|a| c[a] + rng.below(60) as i32 - 30);
        b.fill_tile(2, ijk, rng.range(0.5, 2.0), true);
    }
    for _ in 0..rng.below(300) {
        let ijk = [0, 1, 2].map(|a| c[a] + rng.below(40) as i32 - 20);
        b.set_voxel(ijk, rng.range(0.0, 5.0), true);
    }
    b.build()
}

/// Walks random rays through the majorant grid `max` and checks, at points
/// sampled in every segment (ends included), that `density` is at least the
/// minorant of the segment's cell. Points for which `inside` is false are
/// skipped and counted.
fn check_segments(
    rng: &mut Rng,
    max: &MajorantGrid,
    min: &MajorantGrid,
    density: &dyn Fn([f32; 3]) -> f32,
    inside: &dyn Fn([f32; 3]) -> bool,
) -> (usize, usize) {
    let (lo, hi) = max.bounds();
    let (mut checked, mut skipped) = (0, 0);
    for _ in 0..60 {
        let pick = |rng: &mut Rng| [0, 1, 2].map(|a| rng.range(lo[a] - 1.0, hi[a] + 1.0));
        let (o, target) = (pick(rng), pick(rng));
        let d = [0, 1, 2].map(|a| target[a] - o[a]);
        let _ = max.walk_cells(o, d, 0.0, 2.0, |c, s| {
            let minorant = min.value(c[0], c[1], c[2]);
            for k in 0..=8 {
                let t = match k {
                    0 => s.t0,
                    8 => s.t1,
                    _ => s.t0 + (s.t1 - s.t0) * rng.uniform(),
                };
                let p = [0, 1, 2].map(|a| o[a] + t * d[a]);
                if !inside(p) {
                    skipped += 1;
                    continue;
                }
                let v = density(p);
                assert!(
                    above(v, minorant, s.max_density),
                    "density {v} < minorant {minorant} of cell {c:?} at t {t} in {s:?}"
                );
                checked += 1;
            }
            ControlFlow::Continue(())
        });
    }
    (checked, skipped)
}

#[test]
fn dense_minorant_is_below_trilinear_density_everywhere() {
    let mut rng = Rng::new(21);
    let (mut checked, mut skipped) = (0, 0);
    for case in 0..200 {
        let g = random_dense(&mut rng);
        let g = if case % 3 == 0 { g.to_f16() } else { g };
        let res = [1 + rng.below(9), 1 + rng.below(9), 1 + rng.below(9)];
        let min = MajorantGrid::minorant_from_dense(&g, res);
        let max = MajorantGrid::from_dense(&g, res);
        assert_paired(&min, &max);
        assert_eq!(min.bounds(), g.bounds());
        let (lo, hi) = g.bounds();
        for k in 0..400 {
            // Random points, and points snapped to cell faces.
            let mut p = [0, 1, 2].map(|a| rng.range(lo[a], hi[a]));
            if k % 4 == 0 {
                let a = rng.below(3);
                let c = rng.below(res[a] + 1);
                let mut idx = [0usize; 3];
                idx[a] = c.min(res[a] - 1);
                let (clo, chi) = min.cell_bounds(idx[0], idx[1], idx[2]);
                p[a] = if c == res[a] { chi[a] } else { clo[a] };
            }
            let v = g.lookup(p);
            for c in cells_containing(&min, p) {
                let (lower, upper) = (min.value(c[0], c[1], c[2]), max.value(c[0], c[1], c[2]));
                assert!(above(v, lower, upper), "cell {c:?}: minorant {lower} > {v} at {p:?}");
            }
        }
        // The dense grid reads zero outside its closed box: rounding can
        // put a segment's end there (see the minorant module docs).
        let inside = |p: [f32; 3]| (0..3).all(|a| lo[a] <= p[a] && p[a] <= hi[a]);
        let (c, s) = check_segments(&mut rng, &max, &min, &|p| g.lookup(p), &inside);
        checked += c;
        skipped += s;
    }
    assert!(skipped * 100 < checked, "{skipped} of {checked} segment points outside the box");
}

#[test]
fn sparse_minorant_is_below_trilinear_density_everywhere() {
    let mut rng = Rng::new(22);
    let mut above_background = 0;
    for case in 0..120 {
        let g = random_sparse(&mut rng);
        let max_cells = if case % 2 == 0 { MajorantGrid::DEFAULT_MAX_CELLS } else { 1 + rng.below(20) };
        let min = MajorantGrid::minorant_from_sparse(&g, max_cells);
        let max = MajorantGrid::from_sparse(&g, max_cells);
        assert_paired(&min, &max);
        above_background += min.values().iter().filter(|&&v| v > g.background()).count();
        let (lo, hi) = min.bounds();
        for _ in 0..2000 {
            let p = [0, 1, 2].map(|a| rng.range(lo[a] - 3.0, hi[a] + 3.0));
            let v = g.lookup_index(p);
            let cells = cells_containing(&min, p);
            if cells.is_empty() {
                assert_eq!(v, g.background(), "outside the minorant box at {p:?}");
            }
            for c in cells {
                let (lower, upper) = (min.value(c[0], c[1], c[2]), max.value(c[0], c[1], c[2]));
                assert!(above(v, lower, upper), "cell {c:?}: minorant {lower} > {v} at {p:?}");
            }
        }
        // The sparse field is the background outside the box: nothing to skip.
        let (_, skipped) = check_segments(&mut rng, &max, &min, &|p| g.lookup_index(p), &|_| true);
        assert_eq!(skipped, 0);
    }
    // Tiles make the bound useful, not just the background everywhere.
    assert!(above_background > 1000, "{above_background} useful cells");
}

#[test]
fn minorants_bound_grids_read_from_vdb_files() {
    let mut rng = Rng::new(23);
    for name in ["tiles_internal.vdb", "density_half_zip.vdb", "big_shell.vdb"] {
        let file = niebla_volume::VdbFile::open(common::vdb_dir().join(name)).unwrap();
        let g = file.read_float_grid("density").unwrap();
        let min = MajorantGrid::minorant_from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
        let max = MajorantGrid::from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
        assert_paired(&min, &max);
        check_segments(&mut rng, &max, &min, &|p| g.lookup_index(p), &|_| true);
        for leaf in g.leaves().iter().take(500) {
            let p = [0, 1, 2].map(|a| leaf.origin[a] as f32 + rng.range(-1.5, 9.5));
            let v = g.lookup_index(p);
            for c in cells_containing(&min, p) {
                let (lower, upper) = (min.value(c[0], c[1], c[2]), max.value(c[0], c[1], c[2]));
                assert!(above(v, lower, upper), "{name}: {v} < {lower} at {p:?}");
            }
        }
    }
}

#[test]
fn constant_grids_have_equal_minorants_and_majorants() {
    for (dims, res) in [([5, 7, 3], [2, 3, 4]), ([1, 1, 1], [4, 4, 4]), ([16; 3], [16; 3])] {
        let n = dims[0] * dims[1] * dims[2];
        let g = DenseGrid::new(dims, vec![0.75; n], [-1.0; 3], [2.0, 1.0, 3.0]).unwrap();
        for g in [g.to_f16(), g] {
            let min = MajorantGrid::minorant_from_dense(&g, res);
            let max = MajorantGrid::from_dense(&g, res);
            assert!(min.values().iter().all(|&v| v == 0.75), "{dims:?}");
            assert_eq!(min, max);
        }
    }
    // Sparse: a 128^3 tile holding the background value, and leaves too.
    let mut b = SparseGridBuilder::new(0.5, Affine::IDENTITY);
    b.fill_tile(1, [0, 0, 0], 0.5, true);
    b.set_voxel([300, 3, 3], 0.5, true);
    let g = b.build();
    for max_cells in [MajorantGrid::DEFAULT_MAX_CELLS, 8] {
        let min = MajorantGrid::minorant_from_sparse(&g, max_cells);
        let max = MajorantGrid::from_sparse(&g, max_cells);
        assert!(min.values().iter().all(|&v| v == 0.5));
        assert_eq!(min, max);
    }
}

#[test]
fn dense_cells_whose_support_holds_a_zero_have_minorant_zero() {
    let mut rng = Rng::new(24);
    for _ in 0..100 {
        let dims = [0, 1, 2].map(|_| 1 + rng.below(10));
        let n = dims[0] * dims[1] * dims[2];
        let zero = dims.map(|d| rng.below(d));
        let mut data = vec![1.0; n];
        data[(zero[2] * dims[1] + zero[1]) * dims[0] + zero[0]] = 0.0;
        let lo = [0, 1, 2].map(|_| rng.range(-2.0, 2.0));
        let hi = [0, 1, 2].map(|a| lo[a] + rng.range(0.1, 5.0));
        let g = DenseGrid::new(dims, data, lo, hi).unwrap();
        let res = [0, 1, 2].map(|_| 1 + rng.below(8));
        let min = MajorantGrid::minorant_from_dense(&g, res);
        let h = g.cell_size();
        // Interpolation reads the zero voxel on the open interval within
        // one voxel of its center, extended to the face for a face voxel.
        let reach: [(f32, f32); 3] = std::array::from_fn(|a| {
            let center = lo[a] + (zero[a] as f32 + 0.5) * h[a];
            let r0 = if zero[a] == 0 { f32::NEG_INFINITY } else { center - h[a] };
            let r1 = if zero[a] + 1 == dims[a] { f32::INFINITY } else { center + h[a] };
            (r0, r1)
        });
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    let (clo, chi) = min.cell_bounds(x, y, z);
                    let overlaps = (0..3).all(|a| clo[a] < reach[a].1 && chi[a] > reach[a].0);
                    let apart = (0..3).any(|a| chi[a] < reach[a].0 - 0.01 * h[a] || clo[a] > reach[a].1 + 0.01 * h[a]);
                    let v = min.value(x, y, z);
                    if overlaps {
                        assert_eq!(v, 0.0, "cell ({x}, {y}, {z}) reads the zero");
                    } else if apart {
                        assert_eq!(v, 1.0, "cell ({x}, {y}, {z}) is clear of the zero");
                    }
                }
            }
        }
    }
}

#[test]
fn sparse_cells_whose_support_holds_a_zero_or_background_have_it_as_minorant() {
    // Background 0.5, a 128^3 tile of 1 over voxels 0..=127, one zero voxel.
    let mut rng = Rng::new(25);
    for _ in 0..20 {
        let zero = [0, 1, 2].map(|_| rng.below(128) as i32);
        let mut b = SparseGridBuilder::new(0.5, Affine::IDENTITY);
        b.fill_tile(1, [0, 0, 0], 1.0, true);
        b.set_voxel(zero, 0.0, true);
        let g = b.build();
        let max_cells = [MajorantGrid::DEFAULT_MAX_CELLS, 64, 8][rng.below(3)];
        let min = MajorantGrid::minorant_from_sparse(&g, max_cells);
        let res = min.res();
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    let (clo, chi) = min.cell_bounds(x, y, z);
                    // Interpolation in the closed cell reads voxels lo ..= hi + 1
                    // (lo - 1 too, an ulp outside the cell).
                    let reads = |v: i32, a: usize| clo[a] <= v as f32 && v as f32 <= chi[a] + 1.0;
                    let clear = |v: i32, a: usize| (v as f32) < clo[a] - 1.0 || (v as f32) > chi[a] + 1.0;
                    let leaves_tile = (0..3).any(|a| clo[a] - 1.0 < 0.0 || chi[a] + 1.0 > 127.0);
                    let value = min.value(x, y, z);
                    if (0..3).all(|a| reads(zero[a], a)) {
                        assert_eq!(value, 0.0, "cell ({x}, {y}, {z}) reads the zero");
                    } else if (0..3).any(|a| clear(zero[a], a)) {
                        let expected = if leaves_tile { 0.5 } else { 1.0 };
                        assert_eq!(value, expected, "cell ({x}, {y}, {z})");
                    }
                }
            }
        }
    }
}
