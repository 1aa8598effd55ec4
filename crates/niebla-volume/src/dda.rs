//! A 3D DDA over a [`MajorantGrid`] (Amanatides and Woo 1987; pbrt-v4
//! section 11.4.3, `DDAMajorantIterator`): the ray's pieces inside each
//! cell, in order, each with the cell's majorant.
//!
//! The ray is `o + t d` in the majorant grid's space (local space of a
//! dense grid, index space of a sparse grid), `d` need not be normalized,
//! and `t` is restricted to `[t_min, t_max]`. Segments are contiguous
//! (each starts where the previous ended) and cover exactly
//! `[t_min, t_max]` intersected with the grid's box; pieces of zero length
//! (a ray through an edge or corner, or grazing a face) are not reported.
//! Cells with a zero majorant are reported like the others, so a tracker
//! sees every `t` it crosses; [`MajorantGrid::walk_merged`] merges runs of
//! equal majorant (empty space then costs one callback).

use std::ops::ControlFlow;

use crate::MajorantGrid;

/// A piece `[t0, t1]` of a ray in which the density is at most
/// `max_density`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Ray parameter where the piece starts.
    pub t0: f32,
    /// Ray parameter where the piece ends (`t1 > t0`).
    pub t1: f32,
    /// Majorant of the density over the piece (>= 0).
    pub max_density: f32,
}

impl MajorantGrid {
    /// Walks the cells the ray `o + t d`, `t in [t_min, t_max]`, passes
    /// through, calling `f` with each cell `[x, y, z]` and its segment, in
    /// order of increasing `t`. Returns `Break` if `f` did.
    ///
    /// ```
    /// use std::ops::ControlFlow;
    /// use niebla_volume::MajorantGrid;
    /// let m = MajorantGrid::new([2, 1, 1], [0.0; 3], [2.0, 1.0, 1.0], vec![1.0, 3.0]).unwrap();
    /// let mut cells = Vec::new();
    /// let _ = m.walk_cells([-1.0, 0.5, 0.5], [1.0, 0.0, 0.0], 0.0, 10.0, |c, s| {
    ///     cells.push((c, s.t0, s.t1, s.max_density));
    ///     ControlFlow::Continue(())
    /// });
    /// assert_eq!(cells, [([0, 0, 0], 1.0, 2.0, 1.0), ([1, 0, 0], 2.0, 3.0, 3.0)]);
    /// ```
    pub fn walk_cells<F>(&self, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32, mut f: F) -> ControlFlow<()>
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
                if !(o[a] >= self.bounds_min[a] && o[a] <= self.bounds_max[a]) {
                    return ControlFlow::Continue(());
                }
                continue;
            }
            let inv = 1.0 / d[a];
            let (mut near, mut far) = ((self.bounds_min[a] - o[a]) * inv, (self.bounds_max[a] - o[a]) * inv);
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
        let width: [f32; 3] = std::array::from_fn(|a| (self.bounds_max[a] - self.bounds_min[a]) / self.res[a] as f32);
        let inv_d: [f32; 3] = std::array::from_fn(|a| if d[a] != 0.0 { 1.0 / d[a] } else { 0.0 });
        let crossing = |a: usize, c: usize| -> f32 {
            let plane = |k: usize| {
                if k >= self.res[a] {
                    self.bounds_max[a]
                } else {
                    self.bounds_min[a] + k as f32 * width[a]
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
            let extent = self.bounds_max[a] - self.bounds_min[a];
            let u = ((p - self.bounds_min[a]) / extent * self.res[a] as f32).floor();
            cell[a] = (u.max(0.0) as usize).min(self.res[a] - 1);
            // Rounding may put p just across a plane: settle on the cell that
            // the ray is entering (or, moving along -axis, leaving).
            if d[a] > 0.0 && cell[a] + 1 < self.res[a] && self.plane(a, cell[a] + 1) <= p {
                cell[a] += 1;
            } else if d[a] < 0.0 && cell[a] > 0 && self.plane(a, cell[a]) >= p {
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
                let max_density = self.values[(cell[2] * self.res[1] + cell[1]) * self.res[0] + cell[0]];
                f(cell, Segment { t0: t, t1: t_end, max_density })?;
                t = t_end;
            }
            if next[axis] >= t1 {
                return ControlFlow::Continue(());
            }
            // Step into the neighbour across the plane.
            if d[axis] > 0.0 {
                cell[axis] += 1;
                if cell[axis] == self.res[axis] {
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

    /// Like [`MajorantGrid::walk_cells`] without the cell indices: one
    /// [`Segment`] per cell crossed, zero majorants included.
    pub fn walk<F>(&self, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32, mut f: F) -> ControlFlow<()>
    where
        F: FnMut(Segment) -> ControlFlow<()>,
    {
        self.walk_cells(o, d, t_min, t_max, |_, s| f(s))
    }

    /// Like [`MajorantGrid::walk`], but consecutive cells with the same
    /// majorant are reported as one segment (runs of empty cells become a
    /// single segment with `max_density == 0`).
    pub fn walk_merged<F>(&self, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32, mut f: F) -> ControlFlow<()>
    where
        F: FnMut(Segment) -> ControlFlow<()>,
    {
        let mut pending: Option<Segment> = None;
        self.walk(o, d, t_min, t_max, |s| {
            match &mut pending {
                Some(p) if p.max_density == s.max_density => p.t1 = s.t1,
                Some(p) => {
                    let done = *p;
                    *p = s;
                    f(done)?;
                }
                None => pending = Some(s),
            }
            ControlFlow::Continue(())
        })?;
        match pending {
            Some(p) => f(p),
            None => ControlFlow::Continue(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collect(m: &MajorantGrid, o: [f32; 3], d: [f32; 3], t0: f32, t1: f32) -> Vec<([usize; 3], Segment)> {
        let mut out = Vec::new();
        let _ = m.walk_cells(o, d, t0, t1, |c, s| {
            out.push((c, s));
            ControlFlow::Continue(())
        });
        out
    }

    #[test]
    fn diagonal_through_corners_skips_zero_length_pieces() {
        let m = MajorantGrid::new([2, 2, 2], [0.0; 3], [2.0; 3], (0..8).map(|v| v as f32).collect()).unwrap();
        let segs = collect(&m, [0.0; 3], [1.0; 3], 0.0, 10.0);
        assert_eq!(segs.len(), 2);
        assert_eq!(segs[0].0, [0, 0, 0]);
        assert_eq!(segs[1].0, [1, 1, 1]);
        assert_eq!((segs[0].1.t0, segs[0].1.t1, segs[1].1.t1), (0.0, 1.0, 2.0));
    }

    #[test]
    fn ray_starting_inside_and_leaving_backwards() {
        let m = MajorantGrid::new([4, 1, 1], [0.0; 3], [4.0, 1.0, 1.0], vec![1.0, 2.0, 3.0, 4.0]).unwrap();
        let segs = collect(&m, [2.5, 0.5, 0.5], [-2.0, 0.0, 0.0], 0.0, 1.0);
        let cells: Vec<_> = segs.iter().map(|s| s.0[0]).collect();
        assert_eq!(cells, [2, 1, 0]);
        assert_eq!((segs[0].1.t1, segs[1].1.t1, segs[2].1.t1), (0.25, 0.75, 1.0));
    }

    #[test]
    fn missing_rays_and_empty_ranges_report_nothing() {
        let m = MajorantGrid::new([2, 2, 2], [0.0; 3], [1.0; 3], vec![1.0; 8]).unwrap();
        assert!(collect(&m, [2.0, 0.5, 0.5], [0.0, 1.0, 0.0], 0.0, 10.0).is_empty());
        assert!(collect(&m, [0.5, 0.5, 0.5], [1.0, 0.0, 0.0], 0.3, 0.3).is_empty());
        assert!(collect(&m, [0.5, 0.5, 0.5], [f32::NAN, 0.0, 0.0], 0.0, 1.0).is_empty());
    }

    #[test]
    fn merged_walk_joins_equal_majorants_and_stops_on_break() {
        let m = MajorantGrid::new([4, 1, 1], [0.0; 3], [4.0, 1.0, 1.0], vec![0.0, 0.0, 2.0, 2.0]).unwrap();
        let mut segs = Vec::new();
        let _ = m.walk_merged([-1.0, 0.5, 0.5], [1.0, 0.0, 0.0], 0.0, 100.0, |s| {
            segs.push(s);
            ControlFlow::Continue(())
        });
        assert_eq!(
            segs,
            [Segment { t0: 1.0, t1: 3.0, max_density: 0.0 }, Segment { t0: 3.0, t1: 5.0, max_density: 2.0 }]
        );
        let mut calls = 0;
        let flow = m.walk([-1.0, 0.5, 0.5], [1.0, 0.0, 0.0], 0.0, 100.0, |_| {
            calls += 1;
            ControlFlow::Break(())
        });
        assert_eq!((flow, calls), (ControlFlow::Break(()), 1));
    }
}
