//! Density along one ray inside one medium, with its majorant segments: the
//! concrete view the trackers loop over. The medium is matched once per ray
//! (in `grid_dispatch`, not per lookup) and the trackers are generic over [`DensityAlongRay`],
//! so their inner loops have no type branches.

use std::ops::ControlFlow;

use niebla_volume::{DenseF32Lookup, DenseGrid, DensityBoundGrid, MajorantGrid, SparseAccessor, SparseGrid};

use crate::math::Vec3;
use crate::medium::GridMotion;

/// A piece `[t0, t1]` of a ray with bounds on the density inside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DensitySegment {
    /// Start (ray parameter).
    pub t0: f32,
    /// End (ray parameter, may be infinite for unbounded media).
    pub t1: f32,
    /// Lower bound of the density (0 when unknown).
    pub d_min: f32,
    /// Upper bound of the density (the majorant).
    pub d_max: f32,
}

/// Density (a multiplier of the medium's coefficients) along a ray.
pub trait DensityAlongRay {
    /// Density at ray parameter `t`.
    fn density(&self, t: f32) -> f32;
    /// The ray's majorant segments in increasing `t`, contiguous where the
    /// medium is, except that segments with `d_max == 0` and `d_min == 0`
    /// (no medium: every tracker skips them) may be left out; `f` may stop
    /// the walk.
    fn segments<F: FnMut(DensitySegment) -> ControlFlow<()>>(&self, f: F) -> ControlFlow<()>;
    /// Whether [`DensityAlongRay::density`] is exactly 0 wherever no
    /// segment with `d_max > 0` covers `t` (the density is never negative,
    /// so a zero majorant means zero): a ray march may then skip those
    /// samples without changing its sum. `false` when not known.
    #[inline]
    fn zero_outside_segments(&self) -> bool {
        false
    }
    /// The segments of [`DensityAlongRay::segments`] with `d_max > 0`
    /// (bit-identical), others possibly left out; `f` may stop the walk.
    #[inline]
    fn positive_segments<F: FnMut(DensitySegment) -> ControlFlow<()>>(&self, mut f: F) -> ControlFlow<()> {
        self.segments(|s| if s.d_max > 0.0 { f(s) } else { ControlFlow::Continue(()) })
    }
}

/// Density 1 over `[t0, t1]`: a homogeneous medium.
#[derive(Clone, Copy, Debug)]
pub struct UnitDensity {
    /// Start.
    pub t0: f32,
    /// End.
    pub t1: f32,
}

impl DensityAlongRay for UnitDensity {
    #[inline]
    fn density(&self, _t: f32) -> f32 {
        1.0
    }
    #[inline]
    fn segments<F: FnMut(DensitySegment) -> ControlFlow<()>>(&self, mut f: F) -> ControlFlow<()> {
        f(DensitySegment { t0: self.t0, t1: self.t1, d_min: 1.0, d_max: 1.0 })
    }
}

/// Trilinear lookup in a grid's own space.
pub trait GridLookup {
    /// Value at grid-space point `p`.
    fn lookup_grid(&self, p: Vec3) -> f32;
    /// Whether no value is negative, so that a point whose majorant cell is
    /// 0 reads exactly 0 (a ray march may then skip it). `false` when not
    /// known.
    #[inline]
    fn nonnegative(&self) -> bool {
        false
    }
}

impl GridLookup for DenseGrid {
    #[inline]
    fn lookup_grid(&self, p: Vec3) -> f32 {
        self.lookup(p.to_array())
    }
    #[inline]
    fn nonnegative(&self) -> bool {
        self.min_value() >= 0.0
    }
}

/// A dense f32 grid's unpacked lookup (the same values as the grid's own);
/// the caller tells whether the grid is non-negative.
pub struct DenseF32Along<'a> {
    /// The lookup.
    pub lookup: DenseF32Lookup<'a>,
    /// The grid's smallest value is >= 0.
    pub nonnegative: bool,
}

impl GridLookup for DenseF32Along<'_> {
    #[inline(always)]
    fn lookup_grid(&self, p: Vec3) -> f32 {
        self.lookup.lookup(p.to_array())
    }
    #[inline]
    fn nonnegative(&self) -> bool {
        self.nonnegative
    }
}

impl GridLookup for SparseGrid {
    #[inline]
    fn lookup_grid(&self, p: Vec3) -> f32 {
        self.lookup_index(p.to_array())
    }
}

/// Cached reads of a sparse grid (same values as the grid's own lookup).
impl GridLookup for SparseAccessor<'_> {
    #[inline]
    fn lookup_grid(&self, p: Vec3) -> f32 {
        self.lookup_index(p.to_array())
    }
}

/// A grid seen along a ray given in the grid's space (`o + t d`, `d` not unit,
/// `t` the world ray's parameter), restricted to `[t0, t1]`, at one instant:
/// with `motion`, the density at a point is the grid's at the point the
/// motion brings there ([`GridMotion::source_point`]).
pub struct GridAlongRay<'a, G: GridLookup> {
    /// The voxels.
    pub grid: &'a G,
    /// Per-cell maxima.
    pub majorant: &'a MajorantGrid,
    /// Per-cell minima (same layout), if known.
    pub minorant: Option<&'a DensityBoundGrid>,
    /// Ray origin in grid space.
    pub o: Vec3,
    /// Ray direction in grid space.
    pub d: Vec3,
    /// Start of the range.
    pub t0: f32,
    /// End of the range.
    pub t1: f32,
    /// The medium's motion and the ray's time (frames), if it moves and the
    /// time is not 0; `majorant` then bounds the moving density.
    pub motion: Option<(&'a GridMotion, f32)>,
}

impl<G: GridLookup> DensityAlongRay for GridAlongRay<'_, G> {
    #[inline]
    fn density(&self, t: f32) -> f32 {
        let p = self.o + self.d * t;
        match self.motion {
            None => self.grid.lookup_grid(p),
            Some((m, time)) => self.grid.lookup_grid(m.source_point(p, time)),
        }
    }

    #[inline]
    fn zero_outside_segments(&self) -> bool {
        self.grid.nonnegative()
    }

    #[inline]
    fn positive_segments<F: FnMut(DensitySegment) -> ControlFlow<()>>(&self, mut f: F) -> ControlFlow<()> {
        // Without the minima: empty blocks are crossed in one step.
        let (o, d) = (self.o.to_array(), self.d.to_array());
        let minorant = self.minorant;
        self.majorant.walk_nonzero(o, d, self.t0, self.t1, |cell, s| {
            if s.max_density <= 0.0 {
                return ControlFlow::Continue(());
            }
            let d_min = minorant.map_or(0.0, |m| m.value(cell[0], cell[1], cell[2]));
            f(DensitySegment { t0: s.t0, t1: s.t1, d_min: d_min.min(s.max_density), d_max: s.max_density })
        })
    }

    #[inline]
    fn segments<F: FnMut(DensitySegment) -> ControlFlow<()>>(&self, mut f: F) -> ControlFlow<()> {
        let (o, d) = (self.o.to_array(), self.d.to_array());
        match self.minorant {
            // Without minima, a zero-majorant cell is a segment with
            // `d_min == d_max == 0`: leave those out (runs of empty cells
            // cost a step per 4^3 block, and no tracker's result changes).
            None => self.majorant.walk_nonzero(o, d, self.t0, self.t1, |_, s| {
                f(DensitySegment { t0: s.t0, t1: s.t1, d_min: 0.0f32.min(s.max_density), d_max: s.max_density })
            }),
            // A minorant may be negative where the majorant is 0, so every
            // cell is reported.
            Some(m) => self.majorant.walk_cells(o, d, self.t0, self.t1, |cell, s| {
                let d_min = m.value(cell[0], cell[1], cell[2]);
                f(DensitySegment { t0: s.t0, t1: s.t1, d_min: d_min.min(s.max_density), d_max: s.max_density })
            }),
        }
    }
}
