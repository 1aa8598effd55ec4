//! The scene's acceleration structure: the top level of a two-level
//! hierarchy. Its leaves are the scene's objects (spheres, boxes,
//! rectangles and mesh instances, each mesh with its own hierarchy in object
//! space). Three trees: over every object (nearest hits of paths), over the
//! opaque ones (any-hit queries of shadow rays) and over the surfaces shadow
//! rays cross (index-matched medium boundaries and thin dielectric panes,
//! [`crate::bsdf::Bsdf::passes_shadow_rays`]: the pieces of a shadow ray).

use std::sync::{Arc, OnceLock};

use crate::geometry::{AxisAlignedBox, Bvh, PrimitiveHit};
use crate::math::Ray;

use super::SceneObject;

/// A hierarchy over a subset of the scene's objects.
#[derive(Clone, Debug, Default)]
pub struct ObjectTree {
    /// Object index of each primitive of `bvh`.
    objects: Vec<u32>,
    bvh: Bvh,
}

impl ObjectTree {
    fn build(all: &[SceneObject], keep: impl Fn(&SceneObject) -> bool) -> ObjectTree {
        let objects: Vec<u32> = (0..all.len() as u32).filter(|&i| keep(&all[i as usize])).collect();
        let boxes: Vec<AxisAlignedBox> = objects
            .iter()
            .map(|&i| {
                let (min, max) = all[i as usize].shape.bounds();
                AxisAlignedBox { min, max }
            })
            .collect();
        ObjectTree { bvh: Bvh::build(&boxes), objects }
    }

    /// Nearest hit among the tree's objects with `t` in `(t_min, t_max)`:
    /// the object's index and its hit. Of hits at the same `t`, the object
    /// listed first in the scene wins (as a loop over the objects in order
    /// would choose).
    #[inline]
    pub fn closest(&self, all: &[SceneObject], ray: &Ray, t_min: f32, t_max: f32) -> Option<(u32, PrimitiveHit)> {
        let inv = ray.d.recip();
        let mut best: Option<(u32, PrimitiveHit)> = None;
        if self.objects.len() <= DIRECT_OBJECTS {
            // Objects in ascending index order, each bounded by the nearest
            // hit so far (exclusive): a tie goes to the lower index, as below.
            let mut closest = t_max;
            for &object in &self.objects {
                if let Some(h) = all[object as usize].shape.hit_t(ray, inv, t_min, closest) {
                    closest = h.t;
                    best = Some((object, h));
                }
            }
            return best;
        }
        self.closest_traversed(all, ray, t_min, t_max)
    }

    /// [`Self::closest`] by traversing the hierarchy, whatever its size.
    #[inline]
    fn closest_traversed(&self, all: &[SceneObject], ray: &Ray, t_min: f32, t_max: f32) -> Option<(u32, PrimitiveHit)> {
        let inv = ray.d.recip();
        let mut best: Option<(u32, PrimitiveHit)> = None;
        self.bvh.closest(ray, t_min, t_max, |leaf, t_closest| {
            let object = self.objects[leaf as usize];
            // A tie goes to the lower index: let it hit at exactly t_closest.
            let bound = match best {
                Some((b, _)) if object < b => next_up(t_closest),
                _ => t_closest,
            };
            let h = all[object as usize].shape.hit_t(ray, inv, t_min, bound)?;
            best = Some((object, h));
            Some(h.t)
        });
        best
    }

    /// Whether any of the tree's objects other than `ignore` is hit with `t`
    /// in `(t_min, t_max)`.
    #[inline]
    pub fn any(&self, all: &[SceneObject], ray: &Ray, t_min: f32, t_max: f32, ignore: Option<u32>) -> bool {
        let inv = ray.d.recip();
        if self.objects.len() <= DIRECT_OBJECTS {
            return self
                .objects
                .iter()
                .any(|&object| Some(object) != ignore && all[object as usize].shape.occludes(ray, inv, t_min, t_max));
        }
        self.any_traversed(all, ray, t_min, t_max, ignore)
    }

    /// [`Self::any`] by traversing the hierarchy, whatever its size.
    #[inline]
    fn any_traversed(&self, all: &[SceneObject], ray: &Ray, t_min: f32, t_max: f32, ignore: Option<u32>) -> bool {
        let inv = ray.d.recip();
        self.bvh.any(ray, t_min, t_max, |leaf, t_max| {
            let object = self.objects[leaf as usize];
            Some(object) != ignore && all[object as usize].shape.occludes(ray, inv, t_min, t_max)
        })
    }

    /// The tree's only object, when it holds exactly one.
    #[inline]
    pub fn single(&self) -> Option<u32> {
        match self.objects[..] {
            [object] => Some(object),
            _ => None,
        }
    }

    /// Whether the tree holds no object.
    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.objects.len() * 4 + self.bvh.memory_bytes()
    }
}

/// Trees of up to this many objects are not traversed: each object's own
/// test runs directly (the hierarchy's box tests would only repeat it). A
/// homogeneous slab or a cloud over a floor is a scene of one to a few objects,
/// where the traversal was the largest part of a ray query.
const DIRECT_OBJECTS: usize = 4;

/// The smallest `f32` above a finite non-negative `t` (`t` itself otherwise).
#[inline]
fn next_up(t: f32) -> f32 {
    if t.is_finite() && t >= 0.0 {
        f32::from_bits(t.to_bits() + 1)
    } else {
        t
    }
}

/// The three trees of a scene.
#[derive(Clone, Debug, Default)]
pub struct SceneTrees {
    /// Every object.
    pub all: ObjectTree,
    /// Objects that block shadow rays (neither `null` nor a thin dielectric).
    pub opaque: ObjectTree,
    /// Objects that shadow rays cross: `null` surfaces (index-matched medium
    /// boundaries) and thin dielectric panes.
    pub boundaries: ObjectTree,
}

impl SceneTrees {
    /// Builds the trees over `objects`.
    pub fn build(objects: &[SceneObject]) -> SceneTrees {
        SceneTrees {
            all: ObjectTree::build(objects, |_| true),
            opaque: ObjectTree::build(objects, |o| !o.bsdf.passes_shadow_rays()),
            boundaries: ObjectTree::build(objects, |o| o.bsdf.passes_shadow_rays()),
        }
    }
}

/// The scene's trees, built on first use from the scene's objects (so that
/// scenes assembled field by field, as tests do, need no extra step; the
/// scene builder builds them at once). The objects must not change after
/// the first query. Cloning shares the built trees.
#[derive(Clone, Debug, Default)]
pub struct SceneAccel {
    cell: OnceLock<Arc<SceneTrees>>,
}

impl SceneAccel {
    /// The trees of `objects`, built now if not yet.
    #[inline]
    pub fn get(&self, objects: &[SceneObject]) -> &SceneTrees {
        self.cell.get_or_init(|| Arc::new(SceneTrees::build(objects)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::geometry::{AxisAlignedBox, Shape, Sphere};
    use crate::math::Vec3;
    use crate::sampling::PixelSampler;

    fn object(shape: Shape) -> SceneObject {
        SceneObject {
            shape,
            bsdf: Bsdf::Diffuse { reflectance: crate::color::Rgb::splat(0.5) },
            interior: None,
            exterior: None,
            bounds_medium: false,
            emitter: None,
            texture: None,
            roughness: None,
            dpdu_frame: false,
        }
    }

    /// The direct loop over a small tree's objects returns what the
    /// traversal returns (object and `t`), ties included: the scenes hold a
    /// box twice, so that every ray that hits it hits two objects at the same `t`.
    #[test]
    fn small_trees_answer_as_the_traversal_does() {
        let mut s = PixelSampler::from_key(3);
        let mut rnd = |scale: f32| Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * scale;
        let unit = AxisAlignedBox { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        let mut hits = 0;
        for n in 1..=DIRECT_OBJECTS {
            let mut objects = vec![object(Shape::Box(unit))];
            for k in 1..n {
                objects.push(match k {
                    1 => object(Shape::Box(unit)),
                    2 => object(Shape::Sphere(Sphere::new(Vec3::new(0.5, 0.0, 0.0), 0.8))),
                    _ => object(Shape::Box(AxisAlignedBox { min: Vec3::splat(-0.2), max: Vec3::splat(2.0) })),
                });
            }
            let tree = ObjectTree::build(&objects, |_| true);
            for i in 0..2000 {
                let o = rnd(6.0) - Vec3::splat(3.0);
                let d = (rnd(2.0) - Vec3::ONE).normalize();
                let ray = Ray::new(o, d);
                let t_max = if i % 3 == 0 { f32::INFINITY } else { 1.0 + (i % 7) as f32 };
                let direct = tree.closest(&objects, &ray, 1e-4, t_max);
                let traversed = tree.closest_traversed(&objects, &ray, 1e-4, t_max);
                assert_eq!(direct.map(|(o, h)| (o, h.t)), traversed.map(|(o, h)| (o, h.t)), "n {n} ray {i}");
                hits += direct.is_some() as u32;
                for ignore in [None, Some(0)] {
                    let any = tree.any(&objects, &ray, 1e-4, t_max, ignore);
                    assert_eq!(any, tree.any_traversed(&objects, &ray, 1e-4, t_max, ignore), "n {n} ray {i}");
                }
            }
        }
        assert!(hits > 1000, "{hits}");
    }
}
