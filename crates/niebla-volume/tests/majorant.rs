//! The majorant is never below the interpolated density: at random points
//! of random dense and sparse grids, and at every point a tracker can reach
//! by sampling `t` inside a DDA segment (cell borders included).

mod common;

use std::ops::ControlFlow;

use common::Rng;
use niebla_volume::{Affine, DenseGrid, MajorantGrid, SparseGrid, SparseGridBuilder};

/// `value <= bound`, allowing the one-ulp overshoot of a lerp.
fn bounded(value: f32, bound: f32) -> bool {
    value <= bound + bound.abs() * 1e-6
}

/// The cells whose closed box contains `p` (several on shared faces).
fn cells_containing(m: &MajorantGrid, p: [f32; 3]) -> Vec<[usize; 3]> {
    let [rx, ry, rz] = m.res();
    let mut out = Vec::new();
    let axis = |a: usize, n: usize| -> Vec<usize> {
        (0..n)
            .filter(|&c| {
                let (lo, hi) =
                    m.cell_bounds(if a == 0 { c } else { 0 }, if a == 1 { c } else { 0 }, if a == 2 { c } else { 0 });
                lo[a] <= p[a] && p[a] <= hi[a]
            })
            .collect()
    };
    for z in axis(2, rz) {
        for y in axis(1, ry) {
            for x in axis(0, rx) {
                out.push([x, y, z]);
            }
        }
    }
    out
}

fn random_dense(rng: &mut Rng) -> DenseGrid {
    let dims = [1 + rng.below(12), 1 + rng.below(12), 1 + rng.below(12)];
    let n = dims[0] * dims[1] * dims[2];
    // Mostly empty with spikes, so that a loose or shifted majorant shows.
    let data = (0..n).map(|_| if rng.below(4) == 0 { rng.range(0.0, 10.0) } else { 0.0 }).collect();
    let lo = [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)];
    let hi = [lo[0] + rng.range(0.1, 5.0), lo[1] + rng.range(0.1, 5.0), lo[2] + rng.range(0.1, 5.0)];
    DenseGrid::new(dims, data, lo, hi).unwrap()
}

fn random_sparse(rng: &mut Rng) -> SparseGrid {
    let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
    let c = [rng.below(64) as i32 - 32, rng.below(64) as i32 - 32, rng.below(64) as i32 - 32];
    for _ in 0..rng.below(300) {
        let ijk = [0, 1, 2].map(|a| c[a] + rng.below(40) as i32 - 20);
        b.set_voxel(ijk, rng.range(0.0, 5.0), true);
    }
    for _ in 0..rng.below(4) {
        let ijk = [0, 1, 2].map(|a| c[a] + rng.below(60) as i32 - 30);
        b.fill_tile(2, ijk, rng.range(0.0, 2.0), true);
    }
    b.build()
}

/// Walks random rays through `m` and checks `density` at sampled points of
/// every segment, endpoints included.
fn check_segments(rng: &mut Rng, m: &MajorantGrid, density: &dyn Fn([f32; 3]) -> f32) {
    let (lo, hi) = m.bounds();
    for _ in 0..60 {
        let pick = |rng: &mut Rng| [0, 1, 2].map(|a| rng.range(lo[a] - 1.0, hi[a] + 1.0));
        let (o, target) = (pick(rng), pick(rng));
        let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
        let _ = m.walk(o, d, 0.0, 2.0, |s| {
            for k in 0..=8 {
                let t = if k == 8 { s.t1 } else { s.t0 + (s.t1 - s.t0) * rng.uniform() * (k as f32 / 8.0).max(0.0) };
                let p = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
                let v = density(p);
                assert!(bounded(v, s.max_density), "density {v} > majorant {} at t {t} in {s:?}", s.max_density);
            }
            ControlFlow::Continue(())
        });
    }
}

#[test]
fn dense_majorant_bounds_trilinear_density_everywhere() {
    let mut rng = Rng::new(11);
    for _ in 0..200 {
        let g = random_dense(&mut rng);
        let res = [1 + rng.below(9), 1 + rng.below(9), 1 + rng.below(9)];
        let m = MajorantGrid::from_dense(&g, res);
        assert_eq!(m.bounds(), g.bounds());
        let (lo, hi) = g.bounds();
        for k in 0..400 {
            // Random points, and points snapped to majorant cell faces.
            let mut p = [0, 1, 2].map(|a| rng.range(lo[a], hi[a]));
            if k % 4 == 0 {
                let a = rng.below(3);
                let c = rng.below(res[a] + 1);
                let mut idx = [0usize; 3];
                idx[a] = c.min(res[a] - 1);
                let (clo, chi) = m.cell_bounds(idx[0], idx[1], idx[2]);
                p[a] = if c == res[a] { chi[a] } else { clo[a] };
            }
            let v = g.lookup(p);
            for c in cells_containing(&m, p) {
                assert!(
                    bounded(v, m.value(c[0], c[1], c[2])),
                    "cell {c:?} bound {} < {v} at {p:?}",
                    m.value(c[0], c[1], c[2])
                );
            }
        }
        check_segments(&mut rng, &m, &|p| g.lookup(p));
        let h = g.to_f16();
        let mh = MajorantGrid::from_dense(&h, res);
        check_segments(&mut rng, &mh, &|p| h.lookup(p));
    }
}

#[test]
fn dense_majorant_is_tight_around_a_single_voxel() {
    // 32^3 grid, one voxel at (20, 5, 9); 8^3 majorant cells of 4 voxels.
    let mut data = vec![0.0; 32 * 32 * 32];
    data[(9 * 32 + 5) * 32 + 20] = 2.0;
    let g = DenseGrid::new([32; 3], data, [0.0; 3], [1.0; 3]).unwrap();
    let m = MajorantGrid::from_dense(&g, [8; 3]);
    let nonzero: Vec<usize> = (0..512).filter(|&i| m.values()[i] > 0.0).collect();
    // Voxel 20 lies strictly inside cell 5 in x (voxels 20..24 with support
    // reaching 19.5..24.5), voxel 5 in cell 1 in y, voxel 9 in cell 2 in z;
    // the support of its neighbours' cells reaches it along x (cell 4 reads
    // voxels up to 20) and y (cell 1 only: cell 0 reads up to voxel 4), z (cell 2 only).
    assert_eq!(m.value(5, 1, 2), 2.0);
    assert_eq!(m.value(4, 1, 2), 2.0);
    assert!(nonzero.len() <= 4, "{} nonzero cells", nonzero.len());
    assert_eq!(m.max_value(), 2.0);
}

#[test]
fn sparse_majorant_bounds_trilinear_density_everywhere() {
    let mut rng = Rng::new(12);
    for case in 0..120 {
        let g = random_sparse(&mut rng);
        let max_cells = if case % 2 == 0 { MajorantGrid::DEFAULT_MAX_CELLS } else { 1 + rng.below(20) };
        let m = MajorantGrid::from_sparse(&g, max_cells);
        // Aligned cells: a region straddling a cell boundary needs 2 per axis.
        assert!(m.values().len() <= max_cells.max(8), "{:?} for {max_cells}", m.res());
        let (lo, hi) = m.bounds();
        for _ in 0..2000 {
            let p = [0, 1, 2].map(|a| rng.range(lo[a] - 3.0, hi[a] + 3.0));
            let v = g.lookup_index(p);
            let cells = cells_containing(&m, p);
            if cells.is_empty() {
                assert_eq!(v, g.background(), "outside the majorant box at {p:?}");
            }
            for c in cells {
                assert!(
                    bounded(v, m.value(c[0], c[1], c[2])),
                    "cell {c:?}: {} < {v} at {p:?}",
                    m.value(c[0], c[1], c[2])
                );
            }
        }
        check_segments(&mut rng, &m, &|p| g.lookup_index(p));
    }
}

#[test]
fn sparse_majorant_uses_one_cell_per_leaf_when_it_fits() {
    let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
    b.set_voxel([3, 3, 3], 1.0, true);
    b.set_voxel([100, 3, 3], 4.0, true);
    let g = b.build();
    let m = MajorantGrid::from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
    let (lo, hi) = m.bounds();
    let size: Vec<f32> = (0..3).map(|a| (hi[a] - lo[a]) / m.res()[a] as f32).collect();
    assert_eq!(size, [8.0, 8.0, 8.0]);
    assert_eq!(m.max_value(), 4.0);
    // Far from both voxels the majorant is zero.
    let empty = m.values().iter().filter(|&&v| v == 0.0).count();
    assert!(empty > m.values().len() / 2);
    // A tiny budget doubles the cell size until it fits.
    let coarse = MajorantGrid::from_sparse(&g, 8);
    assert!(coarse.values().len() <= 8, "{:?}", coarse.res());
    assert!(bounded(g.lookup_index([100.0, 3.0, 3.0]), coarse.max_value()));
}

#[test]
fn majorants_bound_grids_read_from_vdb_files() {
    let mut rng = Rng::new(13);
    for name in ["big_shell.vdb", "tiles_internal.vdb", "inactive_values.vdb", "density_half_zip.vdb"] {
        let file = niebla_volume::VdbFile::open(common::vdb_dir().join(name)).unwrap();
        let g = file.read_float_grid("density").unwrap();
        let m = MajorantGrid::from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
        assert!(m.values().len() <= MajorantGrid::DEFAULT_MAX_CELLS, "{name}: {:?}", m.res());
        check_segments(&mut rng, &m, &|p| g.lookup_index(p));
        // Points near stored leaves, where the density is non-zero.
        for leaf in g.leaves().iter().take(500) {
            let p = [0, 1, 2].map(|a| leaf.origin[a] as f32 + rng.range(-1.5, 9.5));
            let v = g.lookup_index(p);
            for c in cells_containing(&m, p) {
                assert!(bounded(v, m.value(c[0], c[1], c[2])), "{name}: {v} at {p:?}");
            }
        }
    }
}

/// A cloud shaped like the production frame's (bench/make_big_vdb.py): noisy
/// balls, density `2.5 (1 - d / r)` times a ripple, clamped to 1, stored
/// only where positive, in a 96^3 index box.
fn noisy_balls(rng: &mut Rng) -> SparseGrid {
    let n = 96.0f32;
    let balls: Vec<([f32; 3], f32)> =
        (0..4).map(|_| ([0, 1, 2].map(|_| rng.range(0.3 * n, 0.7 * n)), rng.range(n / 8.0, n / 4.0))).collect();
    let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
    for z in 0..96 {
        for y in 0..96 {
            for x in 0..96 {
                let p = [x as f32, y as f32, z as f32];
                let mut v = 0.0f32;
                for (c, r) in &balls {
                    let d = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
                    let ripple = 0.75 + 0.25 * (0.7 * p[0]).sin() * (0.5 * p[1]).cos() * (0.9 * p[2]).sin();
                    v = v.max((2.5 * (1.0 - d / r)).min(1.0) * ripple);
                }
                if v > 0.0 {
                    b.set_voxel([x, y, z], v, true);
                }
            }
        }
    }
    b.build()
}

/// Coarser-than-leaf cells (the scene default for sparse grids, cells of 16
/// voxels) bound the density of a generated cloud at random points and along
/// DDA segments, and the minorant grid built with the same minimum has the
/// same cells.
#[test]
fn coarse_sparse_cells_bound_a_generated_cloud() {
    let mut rng = Rng::new(14);
    for case in 0..2 {
        let g = noisy_balls(&mut rng);
        for min_cell in [MajorantGrid::DEFAULT_SPARSE_MIN_CELL, 12, 32] {
            let m = MajorantGrid::from_sparse_with_min_cell(&g, MajorantGrid::DEFAULT_MAX_CELLS, min_cell);
            let side = min_cell.next_power_of_two().max(8) as f32;
            assert_eq!(m.cell_size(), [side; 3], "min_cell {min_cell}");
            let min = MajorantGrid::minorant_from_sparse_with_min_cell(&g, MajorantGrid::DEFAULT_MAX_CELLS, min_cell);
            assert!(min.same_layout(&m));
            assert!(min.values().iter().zip(m.values()).all(|(lo, hi)| lo <= hi));
            let (lo, hi) = m.bounds();
            for _ in 0..8000 {
                let p = [0, 1, 2].map(|a| rng.range(lo[a] - 2.0, hi[a] + 2.0));
                let v = g.lookup_index(p);
                let cells = cells_containing(&m, p);
                if cells.is_empty() {
                    assert_eq!(v, g.background(), "case {case}: outside the majorant box at {p:?}");
                }
                for c in cells {
                    let (upper, lower) = (m.value(c[0], c[1], c[2]), min.value(c[0], c[1], c[2]));
                    assert!(bounded(v, upper), "case {case} cell {c:?}: majorant {upper} < {v} at {p:?}");
                    assert!(v >= lower - lower.abs() * 1e-6, "case {case} cell {c:?}: minorant {lower} > {v}");
                }
            }
            check_segments(&mut rng, &m, &|p| g.lookup_index(p));
        }
    }
}
