//! Heterogeneous media: optical coefficients per unit density times a voxel
//! density (dense or sparse grid from `niebla-volume`), placed in the world
//! by an affine map, with a majorant grid for tracking.

use std::sync::{Arc, OnceLock};

use glam::{Affine3A, Mat3};
use niebla_volume::{
    DenseF32Lookup, DenseGrid, DenseRgbGrid, DensityBoundGrid, MajorantGrid, SparseGrid, SparseVec3Grid,
};

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

/// The voxels of an albedo field: one channel (grey) or three (RGB).
#[derive(Clone, Debug)]
pub enum AlbedoGrid {
    /// One channel, the same albedo in R, G and B.
    Grey(Arc<DenseGrid>),
    /// Three channels.
    Rgb(Arc<DenseRgbGrid>),
}

/// A spatially varying single-scattering albedo: `albedo(x) = scale *
/// grid(x)`, looked up trilinearly (values at cell centers) at the world
/// point placed in the grid's box, which is clamped to the box first: outside
/// its box the field takes the value of the nearest point of the box
/// (Mitsuba 3's `gridvolume` with `wrap_mode` `clamp`). It does not change
/// the extinction, so majorants and trackers are unaffected.
#[derive(Clone, Debug)]
pub struct AlbedoField {
    /// The voxels.
    pub grid: AlbedoGrid,
    /// World space to the grid's local box space.
    pub world_to_grid: Affine3A,
    /// The grid's local box (lowest corner).
    pub lo: Vec3,
    /// The grid's local box (highest corner).
    pub hi: Vec3,
    /// Multiplies the grid's values (the medium's `albedo` color).
    pub scale: Rgb,
}

impl AlbedoField {
    /// A field over `grid`'s box placed in the world by the inverse of
    /// `world_to_grid`, its values times `scale`.
    pub fn new(grid: AlbedoGrid, world_to_grid: Affine3A, scale: Rgb) -> AlbedoField {
        let (lo, hi) = match &grid {
            AlbedoGrid::Grey(g) => g.bounds(),
            AlbedoGrid::Rgb(g) => g.bounds(),
        };
        AlbedoField { grid, world_to_grid, lo: Vec3::from(lo), hi: Vec3::from(hi), scale }
    }

    /// Albedo at world point `p` (each channel in [0, 1] for valid data).
    #[inline]
    pub fn eval(&self, p: Vec3) -> Rgb {
        let q = self.world_to_grid.transform_point3(p).clamp(self.lo, self.hi).to_array();
        let v = match &self.grid {
            AlbedoGrid::Grey(g) => Rgb::splat(g.lookup(q)),
            AlbedoGrid::Rgb(g) => Rgb(g.lookup(q)),
        };
        v * self.scale
    }

    /// Per-channel largest value the field takes.
    pub fn max_value(&self) -> Rgb {
        let v = match &self.grid {
            AlbedoGrid::Grey(g) => Rgb::splat(g.max_value()),
            AlbedoGrid::Rgb(g) => Rgb(g.max_value()),
        };
        v * self.scale
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

/// Eulerian motion of a grid medium from a velocity grid: at time `t`
/// (frames relative to the rendered frame) the fields at a point `x` are
/// those of the stored grids at `x - v(x) t` (semi-Lagrangian advection by
/// one step, as production renderers blur smoke caches). The displacement
/// is computed in the density grid's space, so a zero velocity leaves every
/// lookup bit-identical.
#[derive(Clone, Debug)]
pub struct GridMotion {
    /// The velocity grid, looked up trilinearly in its index space (zero,
    /// its background, outside its data).
    pub velocity: Arc<SparseVec3Grid>,
    /// The density grid's space to the velocity grid's index space.
    pub grid_to_velocity: Affine3A,
    /// A stored velocity to its displacement per frame in the density grid's
    /// space (units, the medium's `to_world` and the frame rate applied).
    pub to_grid_per_frame: Mat3,
    /// The same displacement in the world (for emission fields, which have
    /// their own spaces).
    pub to_world_per_frame: Mat3,
    /// The largest absolute value of each stored velocity component
    /// (background, tiles and voxels).
    pub max_abs_velocity: [f32; 3],
    /// Whether the stored values are per second (else per frame): until
    /// [`GridMedium::set_shutter`], the matrices above map to displacements
    /// per second.
    pub per_second: bool,
    /// The majorant grid of the moving density over the shutter: the static
    /// one dilated by the largest displacement ([`GridMedium::set_shutter`]).
    pub majorant: MajorantGrid,
}

impl GridMotion {
    /// The density grid's point whose stored values are seen at grid point
    /// `p` at `time` (frames): `p - v(p) time`.
    #[inline]
    pub fn source_point(&self, p: Vec3, time: f32) -> Vec3 {
        let v = self.velocity.lookup_index(self.grid_to_velocity.transform_point3(p).to_array());
        p - self.to_grid_per_frame * Vec3::from(v) * time
    }

    /// The world point whose stored values are seen at world point `p_world`
    /// (density grid point `p_grid`) at `time`.
    #[inline]
    pub fn source_world_point(&self, p_world: Vec3, p_grid: Vec3, time: f32) -> Vec3 {
        let v = self.velocity.lookup_index(self.grid_to_velocity.transform_point3(p_grid).to_array());
        p_world - self.to_world_per_frame * Vec3::from(v) * time
    }

    /// The largest displacement along each axis of the density grid's space
    /// over times of absolute value at most `max_abs_time` (frames).
    pub fn max_displacement(&self, max_abs_time: f32) -> [f32; 3] {
        let m = self.to_grid_per_frame;
        let rows = [m.row(0), m.row(1), m.row(2)];
        let v = Vec3::from(self.max_abs_velocity);
        rows.map(|r| r.abs().dot(v) * max_abs_time)
    }
}

/// How a minorant grid is made from a density grid: the parameters of the
/// majorant grid it pairs with (so both have the same cells).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MinorantRecipe {
    /// [`DensityBoundGrid::minorant_from_dense`] with this resolution.
    Dense([usize; 3]),
    /// [`DensityBoundGrid::minorant_from_sparse_with_min_cell`] with this
    /// cell budget and smallest cell side (voxels).
    Sparse {
        /// Cell budget.
        max_cells: usize,
        /// Smallest cell side, voxels.
        min_cell: usize,
    },
}

/// A grid medium's minorant grid, built at most once, on first use: only
/// residual ratio tracking reads it, so a render that never runs that
/// tracker never builds it (on a 512^3 sparse grid that build is about as
/// costly as the majorant grid's). Threads asking at the same time wait for
/// one build; the grid is the same whenever it is built.
#[derive(Clone, Debug)]
pub struct LazyMinorant {
    grid: OnceLock<Option<DensityBoundGrid>>,
    recipe: Option<MinorantRecipe>,
}

impl LazyMinorant {
    /// An already built minorant grid (or none).
    pub fn built(grid: Option<DensityBoundGrid>) -> LazyMinorant {
        LazyMinorant { grid: OnceLock::from(grid), recipe: None }
    }

    /// A minorant grid built by `recipe` from the medium's density grid on
    /// first use (none if the recipe's storage is not the grid's).
    pub fn on_demand(recipe: MinorantRecipe) -> LazyMinorant {
        LazyMinorant { grid: OnceLock::new(), recipe: Some(recipe) }
    }

    /// Whether the grid has been built (or given).
    pub fn is_built(&self) -> bool {
        self.grid.get().is_some()
    }

    /// The grid, built from `density` by the recipe if not yet built.
    pub fn get(&self, density: &DensityGrid) -> Option<&DensityBoundGrid> {
        self.grid
            .get_or_init(|| match (self.recipe, density) {
                (Some(MinorantRecipe::Dense(res)), DensityGrid::Dense(g)) => {
                    Some(DensityBoundGrid::minorant_from_dense(g, res))
                }
                (Some(MinorantRecipe::Sparse { max_cells, min_cell }), DensityGrid::Sparse(g)) => {
                    Some(DensityBoundGrid::minorant_from_sparse_with_min_cell(g, max_cells, min_cell))
                }
                _ => None,
            })
            .as_ref()
    }
}

/// A heterogeneous medium: `sigma_x(p) = density(p) * sigma_x`, or with an
/// albedo field `sigma_s(p) = density(p) sigma_t albedo(p)` and `sigma_a(p) =
/// density(p) sigma_t - sigma_s(p)`.
#[derive(Clone, Debug)]
pub struct GridMedium {
    /// Absorption per unit density (1/length); with an albedo field,
    /// `sigma_t - sigma_s` (the field decides the split at each point).
    pub sigma_a: Rgb,
    /// Scattering per unit density (1/length); with an albedo field, its
    /// largest value `sigma_t * albedo.scale` (the field is at most 1).
    pub sigma_s: Rgb,
    /// Density voxels (dimensionless multiplier of the coefficients).
    pub density: DensityGrid,
    /// World space to the density grid's space.
    pub world_to_grid: Affine3A,
    /// Per coarse cell, the largest density trilinear interpolation reaches.
    pub majorant: MajorantGrid,
    /// Per coarse cell (same layout), the smallest density interpolation
    /// reaches: the control of residual ratio tracking, built on first use
    /// (read it with [`GridMedium::minorant`]).
    pub minorant: LazyMinorant,
    /// Emission.
    pub emission: GridEmission,
    /// Phase function.
    pub phase: PhaseFunction,
    /// World-space bounding box of the majorant grid (outside: no medium);
    /// with motion, of the dilated majorant grid.
    pub world_bounds: (Vec3, Vec3),
    /// Eulerian motion blur from a velocity grid, if the medium moves.
    pub motion: Option<GridMotion>,
    /// Spatially varying single-scattering albedo; `None`: `sigma_s /
    /// sigma_t` everywhere.
    pub albedo: Option<AlbedoField>,
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
        let world_bounds = world_box(&world_to_grid, &majorant);
        GridMedium {
            sigma_a,
            sigma_s,
            density,
            world_to_grid,
            majorant,
            minorant: LazyMinorant::built(minorant),
            emission,
            phase,
            world_bounds,
            motion: None,
            albedo: None,
        }
    }

    /// Sets the exposure of a moving medium: its motion scaled to frames
    /// (`per_second` values divided by `fps`) and its majorant dilated by
    /// the largest displacement over the `shutter` (frames) plus one cell
    /// for rounding, its world bounds grown to match. Without motion, or
    /// with a shutter of the single instant 0, the medium stays static
    /// (and renders as without a velocity grid).
    pub fn set_shutter(&mut self, shutter: [f32; 2], fps: f32) {
        let Some(mut motion) = self.motion.take() else { return };
        let max_abs_time = shutter[0].abs().max(shutter[1].abs());
        if max_abs_time == 0.0 {
            return;
        }
        if motion.per_second {
            motion.per_second = false;
            motion.to_grid_per_frame *= 1.0 / fps;
            motion.to_world_per_frame *= 1.0 / fps;
        }
        let d = motion.max_displacement(max_abs_time);
        let h = self.majorant.cell_size();
        // No displacement along an axis: no growth (a zero velocity keeps
        // the static majorant, so the image is the static one bit for bit);
        // else one cell more than the displacement covers, for rounding.
        // A displacement beyond the grid's own size is cut there (the box
        // grows by at most its size on each side; the max filter then spans
        // the whole axis, so inside the grown box the bound holds).
        let res = self.majorant.res();
        let radius: [usize; 3] = std::array::from_fn(|a| {
            let cells = (d[a] / h[a]).ceil();
            if d[a] == 0.0 {
                0
            } else if cells.is_finite() && cells < res[a] as f32 {
                cells as usize + 1
            } else {
                res[a]
            }
        });
        if radius != [0; 3] {
            // The minima no longer bound the moving density from below.
            self.minorant = LazyMinorant::built(None);
        }
        motion.majorant = self.majorant.dilated(radius);
        self.world_bounds = world_box(&self.world_to_grid, &motion.majorant);
        self.motion = Some(motion);
    }

    /// The minorant grid (the majorant grid's cells), built from the density
    /// grid on the first call when the medium was given a recipe
    /// ([`LazyMinorant::on_demand`]); `None` when the medium has none (a
    /// moving medium, or none given).
    #[inline]
    pub fn minorant(&self) -> Option<&DensityBoundGrid> {
        self.minorant.get(&self.density)
    }

    /// The majorant grid trackers use: the dilated one of a moving medium.
    #[inline]
    pub fn tracking_majorant(&self) -> &MajorantGrid {
        self.motion.as_ref().map_or(&self.majorant, |m| &m.majorant)
    }

    /// Density at world point `p` at `time` (frames; 0 for a static view).
    #[inline]
    pub fn density_at_time(&self, p: Vec3, time: f32) -> f32 {
        let g = self.world_to_grid.transform_point3(p);
        match &self.motion {
            Some(m) if time != 0.0 => self.density.lookup(m.source_point(g, time)),
            _ => self.density.lookup(g),
        }
    }

    /// Emitted radiance per unit length at world point `p` at `time` with
    /// density `density` (already looked up at `time`): emission fields are
    /// read at the point the motion brings to `p`.
    #[inline]
    pub fn l_ve_at_time(&self, p: Vec3, density: f32, time: f32) -> Rgb {
        match (&self.motion, &self.emission) {
            (Some(m), GridEmission::Field { .. } | GridEmission::Temperature { .. } | GridEmission::Pyro(_))
                if time != 0.0 =>
            {
                let g = self.world_to_grid.transform_point3(p);
                self.l_ve(m.source_world_point(p, g, time), density)
            }
            _ => self.l_ve(p, density),
        }
    }

    /// Coefficients at world point `p` at `time` (frames).
    #[inline]
    pub fn point_at_time(&self, p: Vec3, time: f32) -> MediumPoint {
        let d = self.density_at_time(p, time);
        self.point_with_density(p, d, time)
    }

    /// `(sigma_a, sigma_s)` at world point `p` at `time` (frames) where the
    /// density (looked up at `time`) is `density`: an albedo field is read at
    /// the point the motion brings to `p`, like emission fields.
    #[inline]
    pub fn absorption_scattering(&self, p: Vec3, density: f32, time: f32) -> (Rgb, Rgb) {
        match &self.albedo {
            None => (self.sigma_a * density, self.sigma_s * density),
            Some(field) => {
                let source = match &self.motion {
                    Some(m) if time != 0.0 => m.source_world_point(p, self.world_to_grid.transform_point3(p), time),
                    _ => p,
                };
                let sigma_t = self.sigma_t() * density;
                let sigma_s = sigma_t * field.eval(source);
                ((sigma_t - sigma_s).map(|x| x.max(0.0)), sigma_s)
            }
        }
    }

    /// Coefficients at world point `p` at `time` (frames) where the density
    /// (looked up at `time`) is `density`.
    #[inline]
    pub fn point_with_density(&self, p: Vec3, density: f32, time: f32) -> MediumPoint {
        let (sigma_a, sigma_s) = self.absorption_scattering(p, density, time);
        MediumPoint { sigma_a, sigma_s, l_ve: self.l_ve_at_time(p, density, time) }
    }
}

/// Density of a grid medium at rest at world points
/// ([`GridMedium::density_reader`]): a dense f32 grid's lookup unpacked once
/// per march, or the medium's own [`GridMedium::density_at`].
#[derive(Clone, Copy, Debug)]
pub enum DensityReader<'a> {
    /// A dense f32 grid and the world-to-grid map.
    DenseF32 {
        /// The grid's lookup.
        grid: DenseF32Lookup<'a>,
        /// World space to the grid's local box.
        world_to_grid: &'a Affine3A,
    },
    /// Any other grid: the medium's lookup.
    Any(&'a GridMedium),
}

impl DensityReader<'_> {
    /// Density at world point `p`, bit for bit [`GridMedium::density_at`].
    #[inline(always)]
    pub fn at(&self, p: Vec3) -> f32 {
        match self {
            DensityReader::DenseF32 { grid, world_to_grid } => {
                grid.lookup(world_to_grid.transform_point3(p).to_array())
            }
            DensityReader::Any(g) => g.density_at(p),
        }
    }
}

/// The world-space bounding box of a bound grid's box placed by the inverse
/// of `world_to_grid`.
fn world_box(world_to_grid: &Affine3A, majorant: &MajorantGrid) -> (Vec3, Vec3) {
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
    (wlo, whi)
}

impl GridMedium {
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

    /// A reader of [`GridMedium::density_at`] for the many lookups of a ray
    /// march: the same bits, with a dense f32 grid read without dispatch.
    #[inline]
    pub fn density_reader(&self) -> DensityReader<'_> {
        match &self.density {
            DensityGrid::Dense(g) => match g.f32_lookup() {
                Some(grid) => DensityReader::DenseF32 { grid, world_to_grid: &self.world_to_grid },
                None => DensityReader::Any(self),
            },
            DensityGrid::Sparse(_) => DensityReader::Any(self),
        }
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
        let (sigma_a, sigma_s) = self.absorption_scattering(p, d, 0.0);
        MediumPoint { sigma_a, sigma_s, l_ve: self.l_ve(p, d) }
    }

    /// Largest extinction anywhere (max over channels).
    pub fn max_sigma_t(&self) -> f32 {
        self.tracking_majorant().max_value() * self.sigma_t().max_channel()
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
