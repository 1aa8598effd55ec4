//! Heterogeneous media: optical coefficients per unit density times a voxel
//! density (dense or sparse grid from `niebla-volume`), placed in the world
//! by an affine map, with a majorant grid for tracking.

use std::sync::Arc;

use glam::Affine3A;
use niebla_volume::{DenseGrid, DensityBoundGrid, MajorantGrid, SparseGrid};

use crate::color::{BlackbodyTable, Rgb};
use crate::math::{Ray, Vec3};
use crate::phase::PhaseFunction;

use super::MediumPoint;

/// Voxel data of a field, in its own grid space: a dense grid's local box
/// coordinates, or a sparse (VDB) grid's index space.
#[derive(Clone, Debug)]
pub enum DensityGrid {
    /// Dense grid (trilinear, zero outside its box).
    Dense(Arc<DenseGrid>),
    /// Sparse grid (trilinear in index space; zero outside its data bounds).
    Sparse(Arc<SparseGrid>),
}

impl DensityGrid {
    /// Trilinear value at grid-space point `p`.
    #[inline]
    pub fn lookup(&self, p: Vec3) -> f32 {
        match self {
            DensityGrid::Dense(g) => g.lookup(p.to_array()),
            DensityGrid::Sparse(g) => g.lookup_index(p.to_array()),
        }
    }

    /// Largest value stored.
    pub fn max_value(&self) -> f32 {
        match self {
            DensityGrid::Dense(g) => g.max_value(),
            DensityGrid::Sparse(g) => g.max_value(),
        }
    }
}

/// A voxel field placed in the world: value at a world point.
#[derive(Clone, Debug)]
pub struct GridField {
    /// The voxels.
    pub grid: DensityGrid,
    /// World space to the grid's space (dense: local box; sparse: index space).
    pub world_to_grid: Affine3A,
}

impl GridField {
    /// Value at world point `p`.
    #[inline]
    pub fn eval(&self, p: Vec3) -> f32 {
        self.grid.lookup(self.world_to_grid.transform_point3(p))
    }
}

/// Emission of a grid medium, as radiance per unit length `L_ve` (the
/// lecture's convention).
#[derive(Clone, Debug)]
pub enum GridEmission {
    /// No emission.
    None,
    /// `L_ve(x) = L_ve * density(x)`: emission proportional to the density.
    ProportionalToDensity(Rgb),
    /// `L_ve(x) = scale * field(x)` from an emission grid.
    Field {
        /// Emission grid placed in the world.
        field: GridField,
        /// Color and scale (radiance per unit length per unit grid value).
        scale: Rgb,
    },
    /// `L_ve(x) = scale * blackbody(T(x))`, the blackbody color of unit
    /// luminance at temperature `T` (Kelvin) read from a grid.
    Temperature {
        /// Temperature grid (Kelvin) placed in the world.
        field: GridField,
        /// `emission_scale` (radiance per unit length at unit luminance).
        scale: f32,
        /// Tabulated blackbody colors.
        table: Arc<BlackbodyTable>,
    },
    /// The pyro medium's emission (flame and blackbody terms, zero where the
    /// density is not positive).
    Pyro(Box<super::PyroEmission>),
}

/// A heterogeneous medium: `sigma_x(p) = density(p) * sigma_x`.
#[derive(Clone, Debug)]
pub struct GridMedium {
    /// Absorption per unit density (1/length).
    pub sigma_a: Rgb,
    /// Scattering per unit density (1/length).
    pub sigma_s: Rgb,
    /// Density voxels (dimensionless multiplier of the coefficients).
    pub density: DensityGrid,
    /// World space to the density grid's space.
    pub world_to_grid: Affine3A,
    /// Per coarse cell, the largest density trilinear interpolation reaches.
    pub majorant: MajorantGrid,
    /// Per coarse cell (same layout), the smallest density interpolation reaches;
    /// the control of residual ratio tracking. `None`: zero.
    pub minorant: Option<DensityBoundGrid>,
    /// Emission.
    pub emission: GridEmission,
    /// Phase function.
    pub phase: PhaseFunction,
    /// World-space bounding box of the majorant grid (outside: no medium).
    pub world_bounds: (Vec3, Vec3),
}

impl GridMedium {
    /// A grid medium; computes its world bounds from the majorant grid's box.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        sigma_a: Rgb,
        sigma_s: Rgb,
        density: DensityGrid,
        world_to_grid: Affine3A,
        majorant: MajorantGrid,
        minorant: Option<DensityBoundGrid>,
        emission: GridEmission,
        phase: PhaseFunction,
    ) -> GridMedium {
        let grid_to_world = world_to_grid.inverse();
        let (lo, hi) = majorant.bounds();
        let mut wlo = Vec3::splat(f32::INFINITY);
        let mut whi = Vec3::splat(f32::NEG_INFINITY);
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { lo[0] } else { hi[0] },
                if k & 2 == 0 { lo[1] } else { hi[1] },
                if k & 4 == 0 { lo[2] } else { hi[2] },
            );
            let w = grid_to_world.transform_point3(c);
            wlo = wlo.min(w);
            whi = whi.max(w);
        }
        GridMedium {
            sigma_a,
            sigma_s,
            density,
            world_to_grid,
            majorant,
            minorant,
            emission,
            phase,
            world_bounds: (wlo, whi),
        }
    }

    /// Extinction per unit density.
    #[inline]
    pub fn sigma_t(&self) -> Rgb {
        self.sigma_a + self.sigma_s
    }

    /// Density at world point `p`.
    #[inline]
    pub fn density_at(&self, p: Vec3) -> f32 {
        self.density.lookup(self.world_to_grid.transform_point3(p))
    }

    /// The ray in grid space (same parameter `t`; the direction is not unit).
    #[inline]
    pub fn ray_to_grid(&self, ray: &Ray) -> (Vec3, Vec3) {
        (self.world_to_grid.transform_point3(ray.o), self.world_to_grid.transform_vector3(ray.d))
    }

    /// Emitted radiance per unit length at world point `p` with density `density`.
    #[inline]
    pub fn l_ve(&self, p: Vec3, density: f32) -> Rgb {
        match &self.emission {
            GridEmission::None => Rgb::ZERO,
            GridEmission::ProportionalToDensity(l) => *l * density,
            GridEmission::Field { field, scale } => *scale * field.eval(p).max(0.0),
            GridEmission::Temperature { field, scale, table } => table.rgb(field.eval(p)) * *scale,
            GridEmission::Pyro(e) => e.l_ve(p, density),
        }
    }

    /// Coefficients at world point `p`.
    #[inline]
    pub fn point(&self, p: Vec3) -> MediumPoint {
        let d = self.density_at(p);
        MediumPoint { sigma_a: self.sigma_a * d, sigma_s: self.sigma_s * d, l_ve: self.l_ve(p, d) }
    }

    /// Largest extinction anywhere (max over channels).
    pub fn max_sigma_t(&self) -> f32 {
        self.majorant.max_value() * self.sigma_t().max_channel()
    }

    /// Parameter range `[t0, t1]` of `ray` within `[t_min, t_max]` inside the
    /// world bounds, if any.
    #[inline]
    pub fn clip(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        let b = crate::geometry::AxisAlignedBox { min: self.world_bounds.0, max: self.world_bounds.1 };
        let (near, far) = b.slab_range(ray);
        let (t0, t1) = (near.max(t_min), far.min(t_max));
        (t0 < t1).then_some((t0, t1))
    }
}
