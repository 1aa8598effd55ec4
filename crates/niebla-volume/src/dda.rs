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

use crate::majorant::ZERO_BLOCK;
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
    // Kept out of line (the callback is inlined into it): inlined into a
    // caller, the walk's size changes how the caller's other paths compile.
    #[inline(never)]
    pub fn walk_cells<F>(&self, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32, f: F) -> ControlFlow<()>
    where
        F: FnMut([usize; 3], Segment) -> ControlFlow<()>,
    {
        self.walk_impl::<false, F>(o, d, t_min, t_max, f)
    }

    /// Like [`MajorantGrid::walk_cells`], but cells whose value is exactly
    /// zero are not reported: the calls are those of `walk_cells` without
    /// the zero cells, with the same cells and bit-identical segments (a
    /// reported segment starts where the previous reported one ended only
    /// if no zero cell lies between them). Blocks of 4^3 cells that are
    /// all zero are crossed in one step (Amanatides and Woo's DDA run on
    /// the block grid, with the cell-level state at the block's exit
    /// recovered exactly), so empty space costs a step per block instead
    /// of per cell.
    ///
    /// ```
    /// use std::ops::ControlFlow;
    /// use niebla_volume::MajorantGrid;
    /// let mut v = vec![0.0; 12];
    /// v[10] = 2.0;
    /// let m = MajorantGrid::new([12, 1, 1], [0.0; 3], [12.0, 1.0, 1.0], v).unwrap();
    /// let mut cells = Vec::new();
    /// let _ = m.walk_nonzero([-1.0, 0.5, 0.5], [1.0, 0.0, 0.0], 0.0, 100.0, |c, s| {
    ///     cells.push((c, s.t0, s.t1, s.max_density));
    ///     ControlFlow::Continue(())
    /// });
    /// assert_eq!(cells, [([10, 0, 0], 11.0, 12.0, 2.0)]);
    /// ```
    // Kept out of line (the callback is inlined into it): inlined into a
    // caller, the walk's size changes how the caller's other paths compile.
    #[inline(never)]
    pub fn walk_nonzero<F>(&self, o: [f32; 3], d: [f32; 3], t_min: f32, t_max: f32, f: F) -> ControlFlow<()>
    where
        F: FnMut([usize; 3], Segment) -> ControlFlow<()>,
    {
        self.walk_impl::<true, F>(o, d, t_min, t_max, f)
    }

    /// The DDA of [`MajorantGrid::walk_cells`]; with `SKIP_ZEROS`, that of
    /// [`MajorantGrid::walk_nonzero`].
    #[inline(always)]
    fn walk_impl<const SKIP_ZEROS: bool, F>(
        &self,
        o: [f32; 3],
        d: [f32; 3],
        t_min: f32,
        t_max: f32,
        mut f: F,
    ) -> ControlFlow<()>
    where
        F: FnMut([usize; 3], Segment) -> ControlFlow<()>,
    {
        // Clip the ray to the grid's box (slab test), keeping the reciprocal
        // directions (0 for a zero component) so that stepping needs no
        // division.
        let (mut t0, mut t1) = (t_min, t_max);
        if o.iter().chain(&d).any(|v| !v.is_finite()) {
            return ControlFlow::Continue(());
        }
        let mut inv_d = [0.0f32; 3];
        for a in 0..3 {
            if d[a] == 0.0 {
                if !(o[a] >= self.bounds_min[a] && o[a] <= self.bounds_max[a]) {
                    return ControlFlow::Continue(());
                }
                continue;
            }
            let inv = 1.0 / d[a];
            inv_d[a] = inv;
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

        // The grid's constants (the same expressions the walk once
        // evaluated here, evaluated when the grid was built).
        let w = &self.walk;
        // The ray parameter where it crosses the boundary plane at index `i`
        // of `w.crossing` (plane `i - w.offset[a]` of axis `a`).
        let crossing_plane = |a: usize, i: usize| -> f32 { (w.crossing[i] - o[a]) * inv_d[a] };
        // Starting cell and the t of the next boundary plane along each axis.
        let mut cell = [0usize; 3];
        let mut next = [f32::INFINITY; 3];
        // Per axis: the next plane's index in `w.crossing`, the cell step
        // (+1 or -1 as a wrapping usize), the steps left before the ray
        // leaves the grid, and the step of the linear cell index.
        let mut plane_i = [0usize; 3];
        let mut step = [0usize; 3];
        let mut left = [0usize; 3];
        let mut index_step = [0usize; 3];
        for a in 0..3 {
            let p = o[a] + d[a] * t0;
            // The cell `floor(u)` clamped to the grid; for `u >= 0` the
            // truncating conversion is the floor, and a negative `u` (or
            // NaN) clamps to 0 either way, so no `floor` call is needed.
            let u = (p - self.bounds_min[a]) / w.extent[a] * w.res_f32[a];
            cell[a] = (u.max(0.0) as usize).min(self.res[a] - 1);
            // Rounding may put p just across a plane: settle on the cell that
            // the ray is entering (or, moving along -axis, leaving).
            let first = w.offset[a];
            if d[a] > 0.0 && cell[a] + 1 < self.res[a] && w.start[first + cell[a] + 1] <= p {
                cell[a] += 1;
            } else if d[a] < 0.0 && cell[a] > 0 && w.start[first + cell[a]] >= p {
                cell[a] -= 1;
            }
            if d[a] > 0.0 {
                plane_i[a] = first + cell[a] + 1;
                step[a] = 1;
                left[a] = self.res[a] - 1 - cell[a];
                index_step[a] = w.stride[a];
                next[a] = crossing_plane(a, plane_i[a]);
            } else if d[a] < 0.0 {
                plane_i[a] = first + cell[a];
                step[a] = usize::MAX;
                left[a] = cell[a];
                index_step[a] = w.stride[a].wrapping_neg();
                next[a] = crossing_plane(a, plane_i[a]);
            }
        }

        // The walk keeps each axis' next crossing in its own variable and
        // the cell's linear index up to date, so that a step is a compare,
        // an integer add and one plane crossing read from the grid's table
        // (no division, no conversion, no index recomputation). The axis
        // is chosen by branches: a branch-free choice through an array of
        // crossings measured slower (examples/walk_cost.rs).
        let [mut next_x, mut next_y, mut next_z] = next;
        let mut index = self.cell_index(cell);
        let values = &self.values[..];
        let mut t = t0;
        loop {
            if SKIP_ZEROS && values[index] == 0.0 && self.zero_blocks[self.zero_block_index(cell)] {
                // The cell's block is all zero: go to the cell where the ray
                // leaves it. The cell walk takes plane crossings in
                // increasing t, ties in axis order, and every crossing
                // inside the block is between zero cells, so only the state
                // after the block's first exit crossing matters.
                let exit_plane: [usize; 3] = std::array::from_fn(|a| {
                    let first = cell[a] / ZERO_BLOCK * ZERO_BLOCK;
                    if d[a] > 0.0 {
                        (first + ZERO_BLOCK).min(self.res[a])
                    } else {
                        first
                    }
                });
                let exit_t: [f32; 3] = std::array::from_fn(|a| {
                    if d[a] != 0.0 {
                        crossing_plane(a, w.offset[a] + exit_plane[a])
                    } else {
                        f32::INFINITY
                    }
                });
                let axis = first_axis(exit_t);
                let t_exit = exit_t[axis];
                // The walk ends at t1 before leaving the block.
                if t_exit >= t1 {
                    return ControlFlow::Continue(());
                }
                // The cell walk keeps the first of equal crossings as the
                // next segment's start; equal values with different bits
                // are +0 and -0, so an exit at t = 0 takes the cell steps.
                if t_exit != 0.0 {
                    next = [next_x, next_y, next_z];
                    // Crossings of the other axes that come first: before
                    // t_exit, or at it for an axis earlier in the tie order.
                    for b in 0..3 {
                        if b == axis || d[b] == 0.0 {
                            continue;
                        }
                        while left[b] > 0 && (next[b] < t_exit || (next[b] == t_exit && b < axis)) {
                            left[b] -= 1;
                            cell[b] = cell[b].wrapping_add(step[b]);
                            plane_i[b] = plane_i[b].wrapping_add(step[b]);
                            next[b] = crossing_plane(b, plane_i[b]);
                        }
                    }
                    // The exit crossing itself, into the next block (or out
                    // of the grid).
                    if d[axis] > 0.0 {
                        if exit_plane[axis] == self.res[axis] {
                            return ControlFlow::Continue(());
                        }
                        cell[axis] = exit_plane[axis];
                        left[axis] = self.res[axis] - 1 - cell[axis];
                    } else {
                        if exit_plane[axis] == 0 {
                            return ControlFlow::Continue(());
                        }
                        cell[axis] = exit_plane[axis] - 1;
                        left[axis] = cell[axis];
                    }
                    plane_i[axis] = (w.offset[axis] + exit_plane[axis]).wrapping_add(step[axis]);
                    next[axis] = crossing_plane(axis, plane_i[axis]);
                    [next_x, next_y, next_z] = next;
                    index = self.cell_index(cell);
                    if t_exit > t {
                        t = t_exit;
                    }
                    continue;
                }
            }
            // The axis whose plane comes first (ties: x, then y, then z).
            let (axis, t_next) = if next_x <= next_y && next_x <= next_z {
                (0, next_x)
            } else if next_y <= next_z {
                (1, next_y)
            } else {
                (2, next_z)
            };
            let t_end = t_next.min(t1);
            if t_end > t {
                let max_density = values[index];
                if !(SKIP_ZEROS && max_density == 0.0) {
                    f(cell, Segment { t0: t, t1: t_end, max_density })?;
                }
                t = t_end;
            }
            if t_next >= t1 || left[axis] == 0 {
                return ControlFlow::Continue(());
            }
            // Step into the neighbour across the plane.
            left[axis] -= 1;
            cell[axis] = cell[axis].wrapping_add(step[axis]);
            plane_i[axis] = plane_i[axis].wrapping_add(step[axis]);
            index = index.wrapping_add(index_step[axis]);
            let crossed = crossing_plane(axis, plane_i[axis]);
            match axis {
                0 => next_x = crossed,
                1 => next_y = crossed,
                _ => next_z = crossed,
            }
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

/// The axis whose value in `t` is smallest, ties to the lower axis (x, then
/// y, then z; with a NaN, the choice of `x <= y && x <= z`, else `y <= z`),
/// computed without branches.
// The negated comparisons are the point: a NaN must choose as the chain did.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
#[inline(always)]
fn first_axis(t: [f32; 3]) -> usize {
    let not_x = !((t[0] <= t[1]) & (t[0] <= t[2])) as usize;
    let z_over_y = !(t[1] <= t[2]) as usize;
    not_x * (1 + z_over_y)
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

    /// The branch-free axis choice equals the comparison chain it replaced
    /// on every triple of values with ties, signed zeros, infinities and NaN.
    #[test]
    fn first_axis_equals_the_comparison_chain() {
        let vals = [-f32::INFINITY, -1.0, -0.0, 0.0, 0.5, 1.0, f32::INFINITY, f32::NAN];
        let mut n = 0;
        for x in vals {
            for y in vals {
                for z in vals {
                    let chain = if x <= y && x <= z {
                        0
                    } else if y <= z {
                        1
                    } else {
                        2
                    };
                    assert_eq!(first_axis([x, y, z]), chain, "{x} {y} {z}");
                    n += 1;
                }
            }
        }
        assert_eq!(n, 512);
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
