//! The DDA's fast paths against references: [`MajorantGrid::walk_cells`]
//! equals, bit for bit, the straightforward Amanatides-Woo loop it
//! replaced (kept here as the reference), and [`MajorantGrid::walk_nonzero`]
//! equals `walk_cells` with the zero cells dropped, bit for bit, on grids
//! with empty blocks, for random and degenerate rays (axis-parallel, on
//! faces, through edges and corners, starting inside, clipped by `t`).

mod common;

use std::ops::ControlFlow;

use common::Rng;
use niebla_volume::{Affine, MajorantGrid, Segment, SparseGridBuilder};

/// Boundary plane `k` of axis `a`, as the grid defines it (`cell_bounds`).
fn plane(m: &MajorantGrid, a: usize, k: usize) -> f32 {
    let res = m.res();
    if k >= res[a] {
        return m.bounds().1[a];
    }
    let mut c = [0usize; 3];
    c[a] = k;
    m.cell_bounds(c[0], c[1], c[2]).0[a]
}

/// The cell walk as it was before the incremental-index loop (one array of
/// next crossings indexed by axis, the cell's index recomputed per step).
#[allow(clippy::needless_range_loop)]
fn reference_walk_cells<F>(
    m: &MajorantGrid,
    o: [f32; 3],
    d: [f32; 3],
    t_min: f32,
    t_max: f32,
    mut f: F,
) -> ControlFlow<()>
where
    F: FnMut([usize; 3], Segment) -> ControlFlow<()>,
{
    // Clip the ray to the grid's box (slab test).
    let (mut t0, mut t1) = (t_min, t_max);
    if o.iter().chain(&d).any(|v| !v.is_finite()) {
        return ControlFlow::Continue(());
    }
    for a in 0..3 {
        if d[a] == 0.0 {
            if !(o[a] >= m.bounds().0[a] && o[a] <= m.bounds().1[a]) {
                return ControlFlow::Continue(());
            }
            continue;
        }
        let inv = 1.0 / d[a];
        let (mut near, mut far) = ((m.bounds().0[a] - o[a]) * inv, (m.bounds().1[a] - o[a]) * inv);
        if near > far {
            std::mem::swap(&mut near, &mut far);
        }
        t0 = t0.max(near);
        t1 = t1.min(far);
    }
    // Empty, a single point, or NaN limits.
    if t0.partial_cmp(&t1) != Some(std::cmp::Ordering::Less) {
        return ControlFlow::Continue(());
    }

    // Cell widths and reciprocal directions, so that stepping needs no division.
    let width: [f32; 3] = std::array::from_fn(|a| (m.bounds().1[a] - m.bounds().0[a]) / m.res()[a] as f32);
    let inv_d: [f32; 3] = std::array::from_fn(|a| if d[a] != 0.0 { 1.0 / d[a] } else { 0.0 });
    let crossing = |a: usize, c: usize| -> f32 {
        let plane = |k: usize| {
            if k >= m.res()[a] {
                m.bounds().1[a]
            } else {
                m.bounds().0[a] + k as f32 * width[a]
            }
        };
        if d[a] > 0.0 {
            (plane(c + 1) - o[a]) * inv_d[a]
        } else if d[a] < 0.0 {
            (plane(c) - o[a]) * inv_d[a]
        } else {
            f32::INFINITY
        }
    };
    // Starting cell and the t of the next boundary plane along each axis.
    let mut cell = [0usize; 3];
    let mut next = [f32::INFINITY; 3];
    for a in 0..3 {
        let p = o[a] + d[a] * t0;
        let extent = m.bounds().1[a] - m.bounds().0[a];
        let u = ((p - m.bounds().0[a]) / extent * m.res()[a] as f32).floor();
        cell[a] = (u.max(0.0) as usize).min(m.res()[a] - 1);
        // Rounding may put p just across a plane: settle on the cell that
        // the ray is entering (or, moving along -axis, leaving).
        if d[a] > 0.0 && cell[a] + 1 < m.res()[a] && plane(m, a, cell[a] + 1) <= p {
            cell[a] += 1;
        } else if d[a] < 0.0 && cell[a] > 0 && plane(m, a, cell[a]) >= p {
            cell[a] -= 1;
        }
        next[a] = crossing(a, cell[a]);
    }

    let mut t = t0;
    loop {
        let axis = if next[0] <= next[1] && next[0] <= next[2] {
            0
        } else if next[1] <= next[2] {
            1
        } else {
            2
        };
        let t_end = next[axis].min(t1);
        if t_end > t {
            let max_density = m.value(cell[0], cell[1], cell[2]);
            f(cell, Segment { t0: t, t1: t_end, max_density })?;
            t = t_end;
        }
        if next[axis] >= t1 {
            return ControlFlow::Continue(());
        }
        // Step into the neighbour across the plane.
        if d[axis] > 0.0 {
            cell[axis] += 1;
            if cell[axis] == m.res()[axis] {
                return ControlFlow::Continue(());
            }
        } else {
            if cell[axis] == 0 {
                return ControlFlow::Continue(());
            }
            cell[axis] -= 1;
        }
        next[axis] = crossing(axis, cell[axis]);
    }
}

type Visit = ([usize; 3], [u32; 3]);

fn bits(c: [usize; 3], s: Segment) -> Visit {
    (c, [s.t0.to_bits(), s.t1.to_bits(), s.max_density.to_bits()])
}

fn reference(m: &MajorantGrid, o: [f32; 3], d: [f32; 3], t0: f32, t1: f32) -> Vec<Visit> {
    let mut out = Vec::new();
    let _ = reference_walk_cells(m, o, d, t0, t1, |c, s| {
        out.push(bits(c, s));
        ControlFlow::Continue(())
    });
    out
}

fn cells(m: &MajorantGrid, o: [f32; 3], d: [f32; 3], t0: f32, t1: f32) -> Vec<Visit> {
    let mut out = Vec::new();
    let _ = m.walk_cells(o, d, t0, t1, |c, s| {
        out.push(bits(c, s));
        ControlFlow::Continue(())
    });
    out
}

fn nonzero(m: &MajorantGrid, o: [f32; 3], d: [f32; 3], t0: f32, t1: f32) -> Vec<Visit> {
    let mut out = Vec::new();
    let _ = m.walk_nonzero(o, d, t0, t1, |c, s| {
        out.push(bits(c, s));
        ControlFlow::Continue(())
    });
    out
}

/// Checks both walks on one ray; returns (cells visited, zero cells among them).
fn check(m: &MajorantGrid, o: [f32; 3], d: [f32; 3], t0: f32, t1: f32) -> (usize, usize) {
    let all = cells(m, o, d, t0, t1);
    assert_eq!(all, reference(m, o, d, t0, t1), "walk_cells vs reference: o {o:?} d {d:?} t [{t0}, {t1}]");
    let kept: Vec<Visit> = all.iter().copied().filter(|v| f32::from_bits(v.1[2]) != 0.0).collect();
    assert_eq!(nonzero(m, o, d, t0, t1), kept, "walk_nonzero: o {o:?} d {d:?} t [{t0}, {t1}]");
    // Stopping after the k-th call stops both at the same visit.
    if !kept.is_empty() {
        let k = kept.len() / 2;
        let mut seen = Vec::new();
        let flow = m.walk_nonzero(o, d, t0, t1, |c, s| {
            seen.push(bits(c, s));
            if seen.len() > k {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        assert_eq!(flow, ControlFlow::Break(()));
        assert_eq!(seen, kept[..=k]);
    }
    (all.len(), all.len() - kept.len())
}

/// A grid whose values are zero except in a few random boxes of cells, so
/// that it has empty 4^3 blocks, partly empty blocks and full ones.
fn sparse_values(rng: &mut Rng, res: [usize; 3]) -> Vec<f32> {
    let mut v = vec![0.0f32; res[0] * res[1] * res[2]];
    for _ in 0..1 + rng.below(4) {
        let lo: [usize; 3] = std::array::from_fn(|a| rng.below(res[a]));
        let hi: [usize; 3] = std::array::from_fn(|a| (lo[a] + 1 + rng.below(4)).min(res[a]));
        for z in lo[2]..hi[2] {
            for y in lo[1]..hi[1] {
                for x in lo[0]..hi[0] {
                    // Some zeros inside the boxes too (partly empty blocks).
                    v[(z * res[1] + y) * res[0] + x] = if rng.below(5) == 0 { 0.0 } else { 0.5 + rng.uniform() };
                }
            }
        }
    }
    v
}

fn random_dir(rng: &mut Rng) -> [f32; 3] {
    loop {
        let d = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if l > 0.1 && l <= 1.0 {
            return d.map(|v| v / l);
        }
    }
}

#[test]
fn random_rays_through_grids_with_empty_blocks() {
    let mut rng = Rng::new(11);
    let (mut visited, mut zeros) = (0, 0);
    for case in 0..10000 {
        let res = [1 + rng.below(19), 1 + rng.below(19), 1 + rng.below(19)];
        let lo = [rng.range(-3.0, 1.0), rng.range(-3.0, 1.0), rng.range(-3.0, 1.0)];
        let hi = [lo[0] + rng.range(0.5, 4.0), lo[1] + rng.range(0.5, 4.0), lo[2] + rng.range(0.5, 4.0)];
        let m = MajorantGrid::new(res, lo, hi, sparse_values(&mut rng, res)).unwrap();
        let o = if case % 2 == 0 {
            [rng.range(-6.0, 6.0), rng.range(-6.0, 6.0), rng.range(-6.0, 6.0)]
        } else {
            std::array::from_fn(|a| rng.range(lo[a], hi[a]))
        };
        let d = random_dir(&mut rng).map(|v| v * rng.range(0.2, 3.0));
        let (t0, t1) = match case % 3 {
            0 => (0.0, f32::INFINITY),
            1 => (rng.range(-2.0, 2.0), rng.range(2.0, 20.0)),
            _ => (0.0, rng.range(0.0, 3.0)),
        };
        let (v, z) = check(&m, o, d, t0, t1);
        visited += v;
        zeros += z;
    }
    // The rays do cross zero cells (so the block skip is exercised).
    assert!(zeros > visited / 4, "{zeros} zero cells of {visited}");
}

#[test]
fn lattice_rays_axis_parallel_rays_and_rays_on_faces() {
    let mut rng = Rng::new(12);
    for _ in 0..10000 {
        let n = 4 + rng.below(13);
        let res = [n, 1 + rng.below(16), n];
        let hi = [res[0] as f32, res[1] as f32, res[2] as f32];
        let m = MajorantGrid::new(res, [0.0; 3], hi, sparse_values(&mut rng, res)).unwrap();
        // Start on a lattice point (block corners included), move along a
        // lattice direction with components in {-1, 0, 1} (axis-parallel,
        // face and space diagonals), from outside or inside.
        let o: [f32; 3] = std::array::from_fn(|a| rng.below(res[a] + 1) as f32);
        let mut d: [f32; 3] = std::array::from_fn(|_| rng.below(3) as f32 - 1.0);
        if d == [0.0; 3] {
            d[rng.below(3)] = 1.0;
        }
        let back = if rng.below(2) == 0 { rng.below(4) as f32 } else { rng.range(0.0, 3.0) };
        let o = [o[0] - back * d[0], o[1] - back * d[1], o[2] - back * d[2]];
        check(&m, o, d, 0.0, if rng.below(2) == 0 { 100.0 } else { rng.below(20) as f32 });
        // A random ray through the same lattice point.
        let d = random_dir(&mut rng);
        check(&m, o, d, -50.0, 50.0);
    }
}

#[test]
fn sparse_grid_majorants_walk_the_same() {
    // Majorants of a sparse grid (cells of one leaf): two blobs far apart,
    // so most of the majorant grid's blocks are empty.
    let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
    let mut rng = Rng::new(13);
    for centre in [[10, 12, 9], [100, 90, 110]] {
        for _ in 0..400 {
            let p: [i32; 3] = std::array::from_fn(|a| centre[a] + rng.below(12) as i32 - 6);
            b.set_voxel(p, 0.2 + rng.uniform(), true);
        }
    }
    let g = b.build();
    let m = MajorantGrid::from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
    let (lo, hi) = m.bounds();
    let (mut visited, mut zeros) = (0, 0);
    for _ in 0..2000 {
        let o: [f32; 3] = std::array::from_fn(|a| rng.range(lo[a] - 10.0, hi[a] + 10.0));
        let target: [f32; 3] = if rng.below(2) == 0 { [10.0, 12.0, 9.0] } else { [100.0, 90.0, 110.0] };
        let d: [f32; 3] = std::array::from_fn(|a| target[a] + rng.range(-8.0, 8.0) - o[a]);
        let (v, z) = check(&m, o, d, 0.0, 2.0);
        visited += v;
        zeros += z;
    }
    assert!(zeros > visited / 2, "{zeros} zero cells of {visited}");
}
