//! Where photons come from: the lights (by their power) and emissive media.
//!
//! A medium emits `4 pi L_ve(x)` watts per unit volume (`L_ve` is radiance
//! per unit length, isotropic), `4 pi integral L_ve dV` in all. Its photons
//! start at a point sampled in the box that bounds the medium (the shapes
//! whose interior it is, clipped to a grid's bounds) from a lattice of
//! cells weighted by the largest `L_ve` found at 27 points of each cell,
//! mixed with a uniform choice of cell (10%) so that the density is positive
//! wherever the medium can emit; the photon carries
//! `4 pi L_ve(x) / pdf(x)` when `x` lies in the medium (else nothing), so
//! the estimate is unbiased whatever the lattice misses. Those photons have
//! no direct part that shadow rays compute (`single` sees emission only
//! along the camera ray, not scattered), so their first scattering event is
//! stored too.

use crate::color::Rgb;
use crate::light::SceneSphere;
use crate::math::{Vec2, Vec3, PI};
use crate::medium::{Medium, MediumId};
use crate::sampling::{sample_uniform_sphere, Distribution1D};
use crate::world::Scene;

/// Lattice cells along the longest side of an emitting medium's box.
const LATTICE_CELLS: usize = 32;

/// Share of the uniform cell choice in the mixture.
const UNIFORM_SHARE: f32 = 0.1;

/// The photon sources of a scene: lights and emissive media, chosen in
/// proportion to their (estimated) power. Built once per render.
#[derive(Clone, Debug)]
pub struct Emitters {
    /// Sphere around the scene (directional and environment lights).
    pub(super) sphere: SceneSphere,
    /// Choice over `lights ++ media`, `None` when nothing emits.
    choice: Option<Distribution1D>,
    /// Number of lights (the first entries of the choice).
    lights: usize,
    /// Emissive media (the remaining entries).
    media: Vec<MediumEmitter>,
}

/// One emitted photon's start.
pub(super) enum Source<'a> {
    /// Light `index` of the scene, chosen with probability `pmf`.
    Light { index: usize, pmf: f32 },
    /// An emissive medium, chosen with probability `pmf`.
    Medium { emitter: &'a MediumEmitter, pmf: f32 },
}

impl Emitters {
    /// The lights' powers (average over RGB) and every emissive medium's.
    pub fn new(scene: &Scene) -> Emitters {
        let sphere = SceneSphere::around(scene.bounds);
        let media: Vec<MediumEmitter> = (0..scene.media.len() as u32)
            .map(MediumId)
            .filter(|&id| scene.medium(id).is_emissive())
            .filter_map(|id| MediumEmitter::new(scene, id))
            .collect();
        let powers: Vec<f32> = scene
            .lights
            .iter()
            .map(|l| l.power(&sphere).average())
            .chain(media.iter().map(|m| m.power))
            .map(|p| if p.is_finite() && p > 0.0 { p } else { 0.0 })
            .collect();
        let choice = (powers.iter().any(|&p| p > 0.0)).then(|| Distribution1D::new(&powers));
        Emitters { sphere, choice, lights: scene.lights.len(), media }
    }

    /// True when nothing emits.
    pub fn is_empty(&self) -> bool {
        self.choice.is_none()
    }

    /// Choose a source from `u` in [0, 1).
    pub(super) fn choose(&self, u: f32) -> Option<Source<'_>> {
        let (index, pmf) = self.choice.as_ref()?.sample_discrete(u);
        if index < self.lights {
            Some(Source::Light { index, pmf })
        } else {
            Some(Source::Medium { emitter: self.media.get(index - self.lights)?, pmf })
        }
    }
}

/// Photon emission of one emissive medium.
#[derive(Clone, Debug)]
pub(super) struct MediumEmitter {
    /// The medium.
    pub id: MediumId,
    /// Sampling box (world).
    lo: Vec3,
    hi: Vec3,
    /// Cells along x, y, z.
    n: [usize; 3],
    /// Weights of the cells (x fastest).
    cells: Distribution1D,
    /// Estimated power (average over RGB), W.
    power: f32,
}

impl MediumEmitter {
    fn new(scene: &Scene, id: MediumId) -> Option<MediumEmitter> {
        let medium = scene.medium(id);
        // The box of the shapes whose interior is this medium; the scene's
        // bounds when it is the ambient medium.
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for object in scene.objects.iter().filter(|o| o.interior == Some(id) && o.shape.is_closed()) {
            let (a, b) = object.shape.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
        if scene.ambient_medium == Some(id) {
            lo = lo.min(scene.bounds.0);
            hi = hi.max(scene.bounds.1);
        }
        if let Medium::Grid(g) = medium {
            lo = lo.max(g.world_bounds.0);
            hi = hi.min(g.world_bounds.1);
        }
        let extent = hi - lo;
        if !(extent.min_element() > 0.0 && extent.is_finite()) {
            return None;
        }
        let longest = extent.max_element();
        let n =
            [0, 1, 2].map(|a| ((extent[a] / longest * LATTICE_CELLS as f32).ceil() as usize).clamp(1, LATTICE_CELLS));
        let cell = extent / Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32);
        let mut weights = Vec::with_capacity(n[0] * n[1] * n[2]);
        for z in 0..n[2] {
            for y in 0..n[1] {
                for x in 0..n[0] {
                    let corner = lo + cell * Vec3::new(x as f32, y as f32, z as f32);
                    let mut w = 0.0f32;
                    for k in 0..27 {
                        let f = Vec3::new((k % 3) as f32, ((k / 3) % 3) as f32, (k / 9) as f32) * 0.5;
                        w = w.max(medium.at(corner + cell * f).l_ve.average());
                    }
                    weights.push(if w.is_finite() { w } else { 0.0 });
                }
            }
        }
        let cell_volume = cell.element_product();
        let power = 4.0 * PI * weights.iter().sum::<f32>() * cell_volume;
        (power > 0.0).then(|| MediumEmitter { id, lo, hi, n, cells: Distribution1D::new(&weights), power })
    }

    /// A photon start: position `x`, direction, and the flux
    /// `4 pi L_ve(x) / pdf(x)` (zero when `x` is not in the medium).
    pub(super) fn sample(&self, scene: &Scene, u_cell: f32, u_pos: Vec3, u_dir: Vec2) -> (Vec3, Vec3, Rgb) {
        let count = self.cells.len();
        let index = if u_cell < UNIFORM_SHARE {
            ((u_cell / UNIFORM_SHARE * count as f32) as usize).min(count - 1)
        } else {
            self.cells.sample_discrete((u_cell - UNIFORM_SHARE) / (1.0 - UNIFORM_SHARE)).0
        };
        let (x, y, z) = (index % self.n[0], (index / self.n[0]) % self.n[1], index / (self.n[0] * self.n[1]));
        let cell = (self.hi - self.lo) / Vec3::new(self.n[0] as f32, self.n[1] as f32, self.n[2] as f32);
        let p = self.lo + cell * (Vec3::new(x as f32, y as f32, z as f32) + u_pos);
        let pmf = (1.0 - UNIFORM_SHARE) * self.cells.pmf(index) + UNIFORM_SHARE / count as f32;
        let pdf = pmf / cell.element_product();
        let d = sample_uniform_sphere(u_dir);
        if scene.medium_at(p) != Some(self.id) || !(pdf > 0.0) {
            return (p, d, Rgb::ZERO);
        }
        (p, d, scene.medium(self.id).at(p).l_ve * (4.0 * PI / pdf))
    }
}
