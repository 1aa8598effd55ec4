//! Emissive media as light sources: a distribution over the points of a
//! scene where media emit, for next-event estimation toward emission inside
//! media (the "volume light" strategy; see `volpath`'s `volume_nee`).
//!
//! - A grid medium is covered by light cells: the cells of its majorant
//!   grid, each split into `s^3` equal cells when the majorant grid is
//!   coarse (up to 2^15 light cells; a fire a few majorant cells across
//!   emits unevenly within each). Each light cell whose majorant cell is
//!   positive (free-flight sampling only collects emission where it draws
//!   tentative collisions) gets a weight: its world volume times an
//!   estimate of its emitted radiance per unit length `L_ve` (the mean and
//!   the largest of a 3x3x3 lattice of evaluations), plus a small floor so
//!   that every such cell keeps a positive probability whatever the lattice
//!   missed. A cell is chosen with probability proportional to its weight,
//!   then a uniform point in it.
//! - A homogeneous medium bounded by closed shapes (it is the interior of
//!   each, never an exterior, the ambient medium or bounded by an open
//!   shape) is sampled uniformly in the bounding box of those shapes.
//!   Media without a finite region are left to free-flight sampling.
//!
//! The density of a sampled point `y` is `pdf(y)` per unit volume (world):
//! the medium's probability (by total weight) times the cell's probability
//! over the cell's volume. A point seen from `x` then has density
//! `pdf(y) |x - y|^2` in the solid angle times distance measure of free-flight
//! sampling, which is what the multiple importance sampling against
//! collisions compares.
//!
//! Media whose extinction is zero in every channel never collide, so
//! free-flight sampling never collects their emission; they are left out so
//! that light sampling keeps the image's meaning.

use glam::Affine3A;

use crate::color::Rgb;
use crate::geometry::Shape;
use crate::math::Vec3;
use crate::medium::{GridMedium, Medium, MediumId};
use crate::sampling::Distribution1D;
use crate::world::Scene;

/// Lattice points per axis at which a cell's emission is evaluated.
const LATTICE: usize = 3;

/// Weight floor of a cell with a positive majorant, relative to the largest
/// cell weight of its medium.
const CELL_FLOOR: f32 = 1e-3;

/// Bytes per light cell of an emissive grid medium: the cell's probability
/// (f32) and, for cells with a positive majorant, the cell index (u32) and
/// the cumulative table's entries (two f32).
const BYTES_PER_CELL: u64 = 16;

/// The emissive media of a scene as light sources.
#[derive(Clone, Debug, Default)]
pub struct VolumeLights {
    /// The sampled media, each with its region.
    emitters: Vec<Emitter>,
    /// Choice of an emitter, proportional to its total weight.
    choice: Option<Distribution1D>,
    /// Per medium (indexed by [`MediumId`]): its emitter's index, if sampled.
    emitter_of: Vec<Option<u32>>,
}

/// One emissive medium and where its points are drawn.
#[derive(Clone, Debug)]
struct Emitter {
    medium: MediumId,
    region: Region,
    /// World bounds (min, max) of where it emits: the region's box, or the
    /// cells whose emission estimate exceeds the weight floor.
    bounds: (Vec3, Vec3),
}

/// Where an emitter's points are drawn.
#[derive(Clone, Debug)]
enum Region {
    /// Uniform in an axis-aligned box (world).
    Box { min: Vec3, extent: Vec3, inv_volume: f32 },
    /// The cells of a grid medium's majorant grid.
    Cells(Box<CellDistribution>),
}

/// A distribution over the cells of a majorant grid.
#[derive(Clone, Debug)]
struct CellDistribution {
    world_to_grid: Affine3A,
    grid_to_world: Affine3A,
    /// The majorant grid's box in grid space.
    lo: Vec3,
    hi: Vec3,
    res: [usize; 3],
    /// Probability of each cell (`[z][y][x]`, x fastest), 0 where not sampled.
    cell_pmf: Vec<f32>,
    /// Linear indices of the cells with a positive probability.
    cells: Vec<u32>,
    /// Choice among `cells`.
    dist: Distribution1D,
    /// `1 / (world volume of one cell)`.
    inv_cell_volume: f32,
}

/// A point drawn by [`VolumeLights::sample`].
#[derive(Clone, Copy, Debug)]
pub struct VolumeLightSample {
    /// World position.
    pub p: Vec3,
    /// The medium it was drawn in (light arrives from it only if the point
    /// lies in that medium's region).
    pub medium: MediumId,
    /// Density of `p` per unit world volume (medium choice included).
    pub pdf: f32,
}

impl VolumeLights {
    /// The light distribution over the emissive media of `scene`.
    pub fn new(scene: &Scene) -> VolumeLights {
        let mut emitters = Vec::new();
        let mut weights = Vec::new();
        for (i, medium) in scene.media.iter().enumerate() {
            let id = MediumId(i as u32);
            if !medium.is_emissive() || !(medium.max_sigma_t() > 0.0) {
                continue;
            }
            let found = match medium {
                Medium::Homogeneous(h) => homogeneous_region(scene, id).map(|(min, max)| {
                    let extent = max - min;
                    let volume = extent.x * extent.y * extent.z;
                    (Region::Box { min, extent, inv_volume: 1.0 / volume }, h.l_ve.average() * volume, (min, max))
                }),
                Medium::Grid(g) => {
                    cell_distribution(g).map(|(cells, power, bounds)| (Region::Cells(Box::new(cells)), power, bounds))
                }
            };
            if let Some((region, power, bounds)) = found {
                if power > 0.0 && power.is_finite() {
                    emitters.push(Emitter { medium: id, region, bounds });
                    weights.push(power);
                }
            }
        }
        let mut emitter_of = vec![None; scene.media.len()];
        for (k, e) in emitters.iter().enumerate() {
            emitter_of[e.medium.0 as usize] = Some(k as u32);
        }
        let choice = (!weights.is_empty()).then(|| Distribution1D::new(&weights));
        VolumeLights { emitters, choice, emitter_of }
    }

    /// Upper estimate of the bytes [`VolumeLights::new`] allocates for `scene`.
    pub fn memory_estimate(scene: &Scene) -> u64 {
        scene
            .media
            .iter()
            .map(|m| match m {
                Medium::Grid(g) if m.is_emissive() => {
                    let res = g.majorant.res();
                    let sub = subdivision(res) as u64;
                    res.iter().map(|&r| r as u64 * sub).product::<u64>() * BYTES_PER_CELL
                }
                _ => 0,
            })
            .sum()
    }

    /// Whether no medium is sampled.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// World bounds (min, max) of where each sampled medium emits: its
    /// region's box (homogeneous) or the box of its cells whose emission
    /// estimate is above the weight floor (grids).
    pub fn emitting_bounds(&self) -> impl Iterator<Item = (Vec3, Vec3)> + '_ {
        self.emitters.iter().map(|e| e.bounds)
    }

    /// A point drawn from the distribution with uniform numbers `u` (medium
    /// and cell choice) and `v` (position in the cell), or `None` without
    /// emitters.
    #[inline]
    pub fn sample(&self, u: f32, v: [f32; 3]) -> Option<VolumeLightSample> {
        let choice = self.choice.as_ref()?;
        let (k, pmf, u) = choice.sample_discrete_remapped(u);
        let emitter = &self.emitters[k];
        let (p, pdf) = match &emitter.region {
            Region::Box { min, extent, inv_volume } => (*min + *extent * Vec3::new(v[0], v[1], v[2]), *inv_volume),
            Region::Cells(c) => {
                let (j, cell_pmf) = c.dist.sample_discrete(u);
                let index = c.cells[j] as usize;
                let (x, rest) = (index % c.res[0], index / c.res[0]);
                let (y, z) = (rest % c.res[1], rest / c.res[1]);
                let size = (c.hi - c.lo) / Vec3::new(c.res[0] as f32, c.res[1] as f32, c.res[2] as f32);
                let corner = c.lo + size * Vec3::new(x as f32, y as f32, z as f32);
                let q = corner + size * Vec3::new(v[0], v[1], v[2]);
                (c.grid_to_world.transform_point3(q), cell_pmf * c.inv_cell_volume)
            }
        };
        Some(VolumeLightSample { p, medium: emitter.medium, pdf: pmf * pdf })
    }

    /// Density per unit world volume with which [`VolumeLights::sample`]
    /// draws `p` as a point of `medium` (0 where it never does).
    #[inline]
    pub fn pdf(&self, medium: MediumId, p: Vec3) -> f32 {
        let Some(Some(k)) = self.emitter_of.get(medium.0 as usize) else {
            return 0.0;
        };
        let Some(choice) = &self.choice else {
            return 0.0;
        };
        let emitter = &self.emitters[*k as usize];
        let pmf = choice.pmf(*k as usize);
        match &emitter.region {
            Region::Box { min, extent, inv_volume } => {
                let f = (p - *min) / *extent;
                if f.cmpge(Vec3::ZERO).all() && f.cmple(Vec3::ONE).all() {
                    pmf * inv_volume
                } else {
                    0.0
                }
            }
            Region::Cells(c) => match c.cell_of(p) {
                Some(index) => pmf * c.cell_pmf[index] * c.inv_cell_volume,
                None => 0.0,
            },
        }
    }
}

impl CellDistribution {
    /// Linear index of the cell holding world point `p`, if inside the box.
    #[inline]
    fn cell_of(&self, p: Vec3) -> Option<usize> {
        let q = self.world_to_grid.transform_point3(p);
        let f = (q - self.lo) / (self.hi - self.lo);
        let mut c = [0usize; 3];
        for a in 0..3 {
            let x = f[a] * self.res[a] as f32;
            if !(x >= 0.0 && x <= self.res[a] as f32) {
                return None;
            }
            c[a] = (x as usize).min(self.res[a] - 1);
        }
        Some((c[2] * self.res[1] + c[1]) * self.res[0] + c[0])
    }
}

/// The box of a homogeneous medium's region: the union of the bounds of the
/// closed shapes it is the interior of; `None` when it also lies outside a
/// shape, fills the space around the shapes, or has an open boundary.
fn homogeneous_region(scene: &Scene, id: MediumId) -> Option<(Vec3, Vec3)> {
    if scene.ambient_medium == Some(id) {
        return None;
    }
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for object in &scene.objects {
        if object.exterior == Some(id) {
            return None;
        }
        if object.interior == Some(id) {
            if matches!(object.shape, Shape::Rectangle(_)) || !(object.shape.volume() > 0.0) {
                return None;
            }
            let (a, b) = object.shape.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    let extent = hi - lo;
    (extent.cmpgt(Vec3::ZERO).all() && extent.is_finite()).then_some((lo, hi))
}

/// Most light cells a grid's distribution divides its majorant cells into
/// (the subdivision stops before exceeding it).
const LIGHT_CELLS: usize = 1 << 15;

/// Largest subdivision of a majorant cell per axis.
const MAX_SUBDIVISION: usize = 16;

/// Light cells per majorant cell and axis: the largest `s <=
/// MAX_SUBDIVISION` with `cells * s^3 <= LIGHT_CELLS` (at least 1), so that
/// a coarse majorant grid (a few cells across a fire) still gets cells
/// small enough to follow where it emits.
fn subdivision(res: [usize; 3]) -> usize {
    let n = res.iter().product::<usize>().max(1);
    let mut s = 1;
    while s < MAX_SUBDIVISION && n.saturating_mul((s + 1).pow(3)) <= LIGHT_CELLS {
        s += 1;
    }
    s
}

/// The cell distribution of a grid medium, its total weight and the world
/// bounds of its cells whose emission is above the floor, or `None` when no
/// cell emits.
///
/// The cells are those of the majorant grid, each divided into
/// [`subdivision`]^3 light cells; a light cell inside a majorant cell with a
/// positive majorant is sampled, with a weight: its world volume times its
/// emission estimate (the mean and the largest `L_ve` of a 3x3x3 lattice),
/// at least [`CELL_FLOOR`] times the largest weight. Any positive weights
/// keep the estimator unbiased; these only shape its variance.
fn cell_distribution(g: &GridMedium) -> Option<(CellDistribution, f32, (Vec3, Vec3))> {
    let majorant = &g.majorant;
    let mres = majorant.res();
    let sub = subdivision(mres);
    let res = [mres[0] * sub, mres[1] * sub, mres[2] * sub];
    let (lo, hi) = majorant.bounds();
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let grid_to_world = g.world_to_grid.inverse();
    let size = (hi - lo) / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
    let det = grid_to_world.matrix3.determinant().abs();
    let cell_volume = size.x * size.y * size.z * det;
    if !(cell_volume > 0.0) || !cell_volume.is_finite() {
        return None;
    }
    let values = majorant.values();
    let count = res[0] * res[1] * res[2];
    let mut cells = Vec::new();
    let mut weights = Vec::new();
    for z in 0..res[2] {
        for y in 0..res[1] {
            for x in 0..res[0] {
                let index = (z * res[1] + y) * res[0] + x;
                let major = ((z / sub) * mres[1] + y / sub) * mres[0] + x / sub;
                if !(values[major] > 0.0) {
                    continue;
                }
                let corner = lo + size * Vec3::new(x as f32, y as f32, z as f32);
                let (mut sum, mut max) = (0.0f32, 0.0f32);
                for k in 0..LATTICE * LATTICE * LATTICE {
                    let f = Vec3::new(
                        (k % LATTICE) as f32 + 0.5,
                        ((k / LATTICE) % LATTICE) as f32 + 0.5,
                        (k / (LATTICE * LATTICE)) as f32 + 0.5,
                    ) / LATTICE as f32;
                    let e = emission_estimate(g, grid_to_world.transform_point3(corner + size * f));
                    sum += e;
                    max = max.max(e);
                }
                let mean = sum / (LATTICE * LATTICE * LATTICE) as f32;
                cells.push(index as u32);
                weights.push(0.5 * (mean + max) * cell_volume);
            }
        }
    }
    let largest = weights.iter().copied().fold(0.0f32, f32::max);
    if !(largest > 0.0) || !largest.is_finite() {
        return None;
    }
    // Index bounds of the cells above the floor, then their world box.
    let (mut cmin, mut cmax) = ([usize::MAX; 3], [0usize; 3]);
    for (&index, &w) in cells.iter().zip(&weights) {
        if w > CELL_FLOOR * largest {
            let index = index as usize;
            let c = [index % res[0], (index / res[0]) % res[1], index / (res[0] * res[1])];
            for a in 0..3 {
                cmin[a] = cmin[a].min(c[a]);
                cmax[a] = cmax[a].max(c[a] + 1);
            }
        }
    }
    let (mut wmin, mut wmax) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for k in 0..8 {
        let pick = |a: usize| (if k >> a & 1 == 0 { cmin[a] } else { cmax[a] }) as f32;
        let q = lo + size * Vec3::new(pick(0), pick(1), pick(2));
        let p = grid_to_world.transform_point3(q);
        wmin = wmin.min(p);
        wmax = wmax.max(p);
    }
    for w in &mut weights {
        *w = w.max(CELL_FLOOR * largest);
    }
    let dist = Distribution1D::new(&weights);
    let mut cell_pmf = vec![0.0f32; count];
    for (j, &index) in cells.iter().enumerate() {
        cell_pmf[index as usize] = dist.pmf(j);
    }
    let total = weights.iter().map(|&w| w as f64).sum::<f64>() as f32;
    let c = CellDistribution {
        world_to_grid: g.world_to_grid,
        grid_to_world,
        lo,
        hi,
        res,
        cell_pmf,
        cells,
        dist,
        inv_cell_volume: 1.0 / cell_volume,
    };
    Some((c, total, (wmin, wmax)))
}

/// Emitted radiance per unit length at `p` (channel mean, finite, >= 0).
fn emission_estimate(g: &GridMedium, p: Vec3) -> f32 {
    let e = g.l_ve(p, g.density_at(p)).average();
    if e.is_finite() {
        e.max(0.0)
    } else {
        0.0
    }
}

/// The RGB majorant `sigma_maj` that free-flight sampling uses at world
/// point `p` of `medium` (per unit length): a homogeneous medium's
/// extinction, a grid medium's extinction per density times the majorant of
/// the cell holding `p` (0 outside the grid).
#[inline]
pub fn majorant_at(medium: &Medium, p: Vec3) -> Rgb {
    match medium {
        Medium::Homogeneous(h) => h.sigma_t(),
        Medium::Grid(g) => {
            let m = g.tracking_majorant();
            let res = m.res();
            let (lo, hi) = m.bounds();
            let q = g.world_to_grid.transform_point3(p);
            let mut c = [0usize; 3];
            for a in 0..3 {
                let x = (q[a] - lo[a]) / (hi[a] - lo[a]) * res[a] as f32;
                if !(x >= 0.0 && x <= res[a] as f32) {
                    return Rgb::ZERO;
                }
                c[a] = (x as usize).min(res[a] - 1);
            }
            g.sigma_t() * m.value(c[0], c[1], c[2])
        }
    }
}
