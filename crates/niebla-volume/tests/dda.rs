//! The DDA visits exactly the cells a brute-force slab test of every cell
//! finds, in order, with contiguous segments covering the ray's part inside
//! the grid, for random rays and for the degenerate ones (starting inside,
//! parallel to axes, through edges and corners, along faces).

mod common;

use std::ops::ControlFlow;

use common::Rng;
use niebla_volume::{MajorantGrid, Segment};

/// The exact (f64) parameter interval of the ray inside a closed box,
/// clipped to `[t_min, t_max]`; `None` if empty or a single point.
fn slab(o: [f32; 3], d: [f32; 3], lo: [f32; 3], hi: [f32; 3], t_min: f32, t_max: f32) -> Option<(f64, f64)> {
    slab_with(o, d, lo, hi, t_min, t_max, false)
}

/// Like [`slab`], but a ray lying in a face of the box (parallel to an axis
/// and exactly on its boundary plane) misses it: such a ray runs between two
/// cells and either one may report it.
fn slab_interior(o: [f32; 3], d: [f32; 3], lo: [f32; 3], hi: [f32; 3], t_min: f32, t_max: f32) -> Option<(f64, f64)> {
    slab_with(o, d, lo, hi, t_min, t_max, true)
}

fn slab_with(
    o: [f32; 3],
    d: [f32; 3],
    lo: [f32; 3],
    hi: [f32; 3],
    t_min: f32,
    t_max: f32,
    open_faces: bool,
) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (t_min as f64, t_max as f64);
    for a in 0..3 {
        let (o, d, lo, hi) = (o[a] as f64, d[a] as f64, lo[a] as f64, hi[a] as f64);
        if d == 0.0 {
            if o < lo || o > hi || (open_faces && (o == lo || o == hi)) {
                return None;
            }
            continue;
        }
        let (mut n, mut f) = ((lo - o) / d, (hi - o) / d);
        if n > f {
            std::mem::swap(&mut n, &mut f);
        }
        t0 = t0.max(n);
        t1 = t1.min(f);
    }
    (t0 < t1).then_some((t0, t1))
}

fn walk(m: &MajorantGrid, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32) -> Vec<([usize; 3], Segment)> {
    let mut out = Vec::new();
    let _ = m.walk_cells(o, d, t_min, t_max, |c, s| {
        out.push((c, s));
        ControlFlow::Continue(())
    });
    out
}

/// Checks one ray against the brute-force answer; `scale` is the size of
/// the ray's `t` range used for tolerances.
fn check_ray(m: &MajorantGrid, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32) {
    let segs = walk(m, o, d, t_min, t_max);
    let [rx, ry, rz] = m.res();
    let dlen = (d[0] as f64).hypot(d[1] as f64).hypot(d[2] as f64);
    // Parameter tolerance: a few ulps of the coordinates, divided by speed.
    let coord = o.iter().chain(&m.bounds().0).chain(&m.bounds().1).fold(1.0f64, |a, &v| a.max(v.abs() as f64));
    let tol = 1e-5 * coord / dlen.max(1e-30) + 1e-6 * (t_max as f64).abs().min(1e6);
    let context = format!("o {o:?} d {d:?} t [{t_min}, {t_max}]");

    // Segments are ordered, non-empty and contiguous.
    for w in segs.windows(2) {
        assert_eq!(w[0].1.t1, w[1].1.t0, "gap or overlap: {context}");
    }
    for (c, s) in &segs {
        assert!(s.t1 > s.t0, "empty segment {s:?}: {context}");
        assert_eq!(s.max_density, m.value(c[0], c[1], c[2]), "{context}");
        // Each segment is that cell's exact interval.
        let (lo, hi) = m.cell_bounds(c[0], c[1], c[2]);
        match slab(o, d, lo, hi, t_min, t_max) {
            Some((a, b)) => assert!(
                (s.t0 as f64 - a).abs() <= tol && (s.t1 as f64 - b).abs() <= tol,
                "cell {c:?}: segment [{}, {}] vs exact [{a}, {b}]: {context}",
                s.t0,
                s.t1
            ),
            None => assert!(((s.t1 - s.t0) as f64) <= tol, "cell {c:?} not on the ray: {s:?}, {context}"),
        }
    }
    // Coverage: [t_min, t_max] intersected with the grid.
    let (glo, ghi) = m.bounds();
    match slab(o, d, glo, ghi, t_min, t_max) {
        Some((a, b)) if b - a > tol => {
            assert!(!segs.is_empty(), "no segments for [{a}, {b}]: {context}");
            assert!((segs[0].1.t0 as f64 - a).abs() <= tol, "starts at {} not {a}: {context}", segs[0].1.t0);
            let end = segs.last().unwrap().1.t1 as f64;
            assert!((end - b).abs() <= tol, "ends at {end} not {b}: {context}");
        }
        _ => assert!(segs.iter().all(|(_, s)| ((s.t1 - s.t0) as f64) <= tol), "{context}"),
    }
    // Brute force: every cell crossed over more than the tolerance is visited.
    for z in 0..rz {
        for y in 0..ry {
            for x in 0..rx {
                let (lo, hi) = m.cell_bounds(x, y, z);
                if let Some((a, b)) = slab_interior(o, d, lo, hi, t_min, t_max) {
                    if b - a > 4.0 * tol {
                        assert!(
                            segs.iter().any(|(c, _)| *c == [x, y, z]),
                            "cell [{x}, {y}, {z}] crossed over [{a}, {b}] but not visited: {context}"
                        );
                    }
                }
            }
        }
    }
    // And no cell twice.
    let mut cells: Vec<_> = segs.iter().map(|(c, _)| *c).collect();
    cells.sort();
    cells.dedup();
    assert_eq!(cells.len(), segs.len(), "a cell visited twice: {context}");
}

fn grid(res: [usize; 3], lo: [f32; 3], hi: [f32; 3]) -> MajorantGrid {
    let n = res[0] * res[1] * res[2];
    MajorantGrid::new(res, lo, hi, (0..n).map(|i| (i % 7) as f32).collect()).unwrap()
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
fn random_rays_visit_exactly_the_brute_force_cells() {
    let mut rng = Rng::new(1);
    for case in 0..400 {
        let res = [1 + rng.below(9), 1 + rng.below(9), 1 + rng.below(9)];
        let lo = [rng.range(-3.0, 1.0), rng.range(-3.0, 1.0), rng.range(-3.0, 1.0)];
        let hi = [lo[0] + rng.range(0.5, 4.0), lo[1] + rng.range(0.5, 4.0), lo[2] + rng.range(0.5, 4.0)];
        let m = grid(res, lo, hi);
        // Origins outside and inside the box, random speeds (d unnormalized).
        let o = [rng.range(-6.0, 6.0), rng.range(-6.0, 6.0), rng.range(-6.0, 6.0)];
        let d = random_dir(&mut rng).map(|v| v * rng.range(0.2, 3.0));
        let (t_min, t_max) =
            if case % 3 == 0 { (0.0, f32::INFINITY) } else { (rng.range(-2.0, 2.0), rng.range(2.0, 20.0)) };
        check_ray(&m, o, d, t_min, t_max);
    }
}

#[test]
fn rays_starting_inside_cover_from_t_min() {
    let mut rng = Rng::new(2);
    let m = grid([5, 4, 3], [0.0; 3], [5.0, 4.0, 3.0]);
    for _ in 0..300 {
        let o = [rng.range(0.0, 5.0), rng.range(0.0, 4.0), rng.range(0.0, 3.0)];
        let d = random_dir(&mut rng);
        check_ray(&m, o, d, 0.0, rng.range(0.0, 10.0));
        let segs = walk(&m, o, d, 0.0, 1e9);
        assert_eq!(segs[0].1.t0, 0.0);
    }
}

#[test]
fn axis_parallel_rays_and_rays_along_faces() {
    let mut rng = Rng::new(3);
    let m = grid([4, 4, 4], [-2.0; 3], [2.0; 3]);
    for _ in 0..300 {
        let axis = rng.below(3);
        let mut d = [0.0f32; 3];
        d[axis] = if rng.below(2) == 0 { 1.0 } else { -1.0 };
        // Other coordinates: random, or exactly on a cell face (-2, -1, .. 2).
        let mut o = [0f32; 3];
        for (a, v) in o.iter_mut().enumerate() {
            *v = if a == axis {
                rng.range(-4.0, 4.0)
            } else if rng.below(2) == 0 {
                rng.below(5) as f32 - 2.0
            } else {
                rng.range(-2.5, 2.5)
            };
        }
        check_ray(&m, o, d, 0.0, 100.0);
    }
}

#[test]
fn rays_through_cell_edges_and_corners() {
    let mut rng = Rng::new(4);
    let m = grid([8, 8, 8], [0.0; 3], [8.0; 3]);
    for _ in 0..300 {
        // Start on a lattice point, move along a lattice diagonal.
        let o = [rng.below(9) as f32, rng.below(9) as f32, rng.below(9) as f32];
        let mut d = [0f32; 3];
        for v in d.iter_mut() {
            *v = rng.below(3) as f32 - 1.0;
        }
        if d == [0.0; 3] {
            d[rng.below(3)] = 1.0;
        }
        let back = rng.range(0.0, 3.0);
        check_ray(&m, [o[0] - back * d[0], o[1] - back * d[1], o[2] - back * d[2]], d, 0.0, 30.0);
    }
}

#[test]
fn majorants_of_segments_are_the_cells_values_and_walk_matches_walk_cells() {
    let m = grid([3, 3, 3], [0.0; 3], [3.0; 3]);
    let (o, d) = ([-1.0, 0.3, 0.7], [1.0, 0.4, 0.3]);
    let mut a = Vec::new();
    let _ = m.walk(o, d, 0.0, 100.0, |s| {
        a.push(s);
        ControlFlow::Continue(())
    });
    let b: Vec<Segment> = walk(&m, o, d, 0.0, 100.0).into_iter().map(|(_, s)| s).collect();
    assert_eq!(a, b);
    // Merged segments cover the same range with no equal neighbours.
    let mut merged = Vec::new();
    let _ = m.walk_merged(o, d, 0.0, 100.0, |s| {
        merged.push(s);
        ControlFlow::Continue(())
    });
    assert_eq!(merged.first().unwrap().t0, a.first().unwrap().t0);
    assert_eq!(merged.last().unwrap().t1, a.last().unwrap().t1);
    assert!(merged.windows(2).all(|w| w[0].t1 == w[1].t0 && w[0].max_density != w[1].max_density));
}
