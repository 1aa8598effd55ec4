//! The one place where a grid medium's density storage (dense or sparse) is
//! matched: [`with_grid_along_ray`] builds the concrete [`GridAlongRay`] view
//! of a ray and hands it to a [`GridRayVisitor`], whose generic method is
//! monomorphized per storage type. Trackers, free-flight sampling and
//! majorant profiles are written once against [`DensityAlongRay`] and reach
//! the grid through here, so their inner loops carry no type branch. Sparse
//! grids are read through a [`niebla_volume::SparseAccessor`] made here per
//! ray, which caches the last leaf visited (bit-identical values).

use crate::math::Vec3;
use crate::medium::{DensityGrid, GridMedium};

use super::along_ray::{DenseF32Along, GridAlongRay, GridLookup};

/// Work done on a grid seen along a ray, generic over the voxel storage.
pub trait GridRayVisitor {
    /// What the work returns.
    type Output;
    /// Run on the concrete view `r` of the grid along the ray.
    fn visit<G: GridLookup>(self, r: &GridAlongRay<'_, G>) -> Self::Output;
}

/// Run `visitor` on the grid of `g` along the grid-space ray `o + t d`
/// (`t` the world ray's parameter, see [`GridMedium::ray_to_grid`]) over the
/// parameter range `[t0, t1]` (already clipped to the grid box) at `time`
/// (frames, the camera sample's [`crate::sampling::PixelSampler::time`]):
/// a moving medium is seen at that instant, bounded by its dilated majorant.
/// Per-cell minima are passed along when `with_minorant` is set and the
/// medium has them (built then on first use, see [`GridMedium::minorant`]):
/// only residual ratio tracking reads them, and without them the walk skips
/// empty cells.
#[inline]
pub fn with_grid_along_ray<V: GridRayVisitor>(
    g: &GridMedium,
    (o, d): (Vec3, Vec3),
    (t0, t1): (f32, f32),
    time: f32,
    with_minorant: bool,
    visitor: V,
) -> V::Output {
    let majorant = g.tracking_majorant();
    let minorant = if with_minorant { g.minorant() } else { None };
    let motion = g.motion.as_ref().filter(|_| time != 0.0).map(|m| (m, time));
    match &g.density {
        DensityGrid::Dense(grid) => match grid.f32_lookup() {
            // f32 storage: the lookup unpacked once per ray (same values).
            Some(lookup) => {
                let grid = DenseF32Along { lookup, nonnegative: grid.min_value() >= 0.0 };
                visitor.visit(&GridAlongRay { grid: &grid, majorant, minorant, o, d, t0, t1, motion })
            }
            None => visitor.visit(&GridAlongRay { grid: grid.as_ref(), majorant, minorant, o, d, t0, t1, motion }),
        },
        DensityGrid::Sparse(grid) => {
            // One cached accessor per ray: consecutive lookups along the ray
            // mostly stay in one leaf and skip the tree descent.
            let accessor = grid.accessor();
            visitor.visit(&GridAlongRay { grid: &accessor, majorant, minorant, o, d, t0, t1, motion })
        }
    }
}
