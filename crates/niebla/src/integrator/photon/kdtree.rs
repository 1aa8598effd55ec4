//! A balanced kd-tree over photons (Jensen 2001, chapter 6), stored
//! implicitly: the photons are reordered so that every index range
//! `[lo, hi)` of a subtree holds its node at `(lo + hi) / 2`, split on the
//! axis of the range's largest extent, with the lower half of the range on
//! the lower side. Queries: all photons within a radius, the `k` nearest
//! (with a radius cap), and, once every photon has a radius, all photons
//! whose sphere a ray segment crosses (the beam radiance estimate of Jarosz,
//! Zwicker and Jensen 2008). For that last query the same hierarchy is a
//! bounding volume hierarchy: each node keeps the box of its subtree's
//! spheres.
//!
//! The build is deterministic (a median selection on the input order), so a
//! tree depends only on the photons given, not on the thread count.
//!
//! ```
//! use niebla::color::Rgb;
//! use niebla::integrator::photon::{Photon, PhotonTree};
//! use niebla::math::Vec3;
//! let photons: Vec<Photon> = (0..100)
//!     .map(|i| Photon::in_medium(Vec3::new(i as f32, 0.0, 0.0), Vec3::X, Rgb::ONE, 0))
//!     .collect();
//! let tree = PhotonTree::build(photons);
//! let mut found = 0;
//! tree.for_each_within(Vec3::new(50.2, 0.0, 0.0), 1.5 * 1.5, |_, _| found += 1);
//! assert_eq!(found, 3); // 49, 50, 51
//! ```

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::stored::Photon;
use crate::math::{Ray, Vec3};

/// Subtrees at most this large are scanned linearly.
const LEAF_SIZE: usize = 6;

/// Ranges larger than this are built on two threads.
const PARALLEL_BUILD: usize = 1 << 14;

/// Photons in kd-tree order with the split axis of every node.
#[derive(Clone, Debug, Default)]
pub struct PhotonTree {
    photons: Vec<Photon>,
    /// Split axis of the node at each index (0, 1, 2).
    axes: Vec<u8>,
    /// Radius of each photon's sphere (beam queries), empty until set.
    radii: Vec<f32>,
    /// Box `(min, max)` of the spheres of the subtree whose node is at each
    /// index, empty until radii are set.
    boxes: Vec<(Vec3, Vec3)>,
}

/// One of the `k` nearest photons: squared distance and index in tree order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    /// Squared distance to the query point.
    pub d2: f32,
    /// Index of the photon in [`PhotonTree::photons`].
    pub index: u32,
}

impl Eq for Neighbor {}

impl PartialOrd for Neighbor {
    fn partial_cmp(&self, other: &Neighbor) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Neighbor {
    fn cmp(&self, other: &Neighbor) -> Ordering {
        self.d2.total_cmp(&other.d2).then(self.index.cmp(&other.index))
    }
}

impl PhotonTree {
    /// Build the tree (reorders `photons`).
    pub fn build(mut photons: Vec<Photon>) -> PhotonTree {
        let mut axes = vec![0u8; photons.len()];
        build_range(&mut photons, &mut axes);
        PhotonTree { photons, axes, radii: Vec::new(), boxes: Vec::new() }
    }

    /// The photons, in tree order.
    #[inline]
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// Number of photons.
    #[inline]
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// True when the tree holds no photon.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Call `f(photon, d2)` for every photon within squared distance `r2`
    /// (strictly less) of `x`.
    #[inline]
    pub fn for_each_within(&self, x: Vec3, r2: f32, mut f: impl FnMut(&Photon, f32)) {
        self.within_range(0, self.photons.len(), x, r2, &mut f);
    }

    fn within_range(&self, lo: usize, hi: usize, x: Vec3, r2: f32, f: &mut impl FnMut(&Photon, f32)) {
        if hi - lo <= LEAF_SIZE {
            for photon in &self.photons[lo..hi] {
                let d2 = (photon.p - x).length_squared();
                if d2 < r2 {
                    f(photon, d2);
                }
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let photon = &self.photons[mid];
        let axis = self.axes[mid] as usize;
        let delta = x[axis] - photon.p[axis];
        let (near, far) = if delta <= 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
        self.within_range(near.0, near.1, x, r2, f);
        let d2 = (photon.p - x).length_squared();
        if d2 < r2 {
            f(photon, d2);
        }
        if delta * delta < r2 {
            self.within_range(far.0, far.1, x, r2, f);
        }
    }

    /// The `k` nearest photons to `x` within squared distance `r2_max`
    /// (strictly less) that pass `accept`, into `heap` (cleared first; a
    /// max-heap on distance, reused across calls to avoid allocation).
    /// Returns the squared distance of the farthest one found, or `r2_max`
    /// when fewer than `k` were found.
    pub fn nearest(
        &self,
        x: Vec3,
        k: usize,
        r2_max: f32,
        accept: impl Fn(&Photon) -> bool,
        heap: &mut BinaryHeap<Neighbor>,
    ) -> f32 {
        heap.clear();
        if k == 0 {
            return r2_max;
        }
        let mut r2 = r2_max;
        self.nearest_range(0, self.photons.len(), x, k, &mut r2, &accept, heap);
        if heap.len() == k {
            heap.peek().map_or(r2_max, |n| n.d2)
        } else {
            r2_max
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn nearest_range(
        &self,
        lo: usize,
        hi: usize,
        x: Vec3,
        k: usize,
        r2: &mut f32,
        accept: &impl Fn(&Photon) -> bool,
        heap: &mut BinaryHeap<Neighbor>,
    ) {
        let consider = |index: usize, r2: &mut f32, heap: &mut BinaryHeap<Neighbor>| {
            let photon = &self.photons[index];
            let d2 = (photon.p - x).length_squared();
            if d2 < *r2 && accept(photon) {
                heap.push(Neighbor { d2, index: index as u32 });
                if heap.len() > k {
                    heap.pop();
                }
                if heap.len() == k {
                    // Only photons closer than the current k-th can enter.
                    *r2 = heap.peek().map_or(*r2, |n| n.d2);
                }
            }
        };
        if hi - lo <= LEAF_SIZE {
            for index in lo..hi {
                consider(index, r2, heap);
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let axis = self.axes[mid] as usize;
        let delta = x[axis] - self.photons[mid].p[axis];
        let (near, far) = if delta <= 0.0 { ((lo, mid), (mid + 1, hi)) } else { ((mid + 1, hi), (lo, mid)) };
        self.nearest_range(near.0, near.1, x, k, r2, accept, heap);
        consider(mid, r2, heap);
        if delta * delta < *r2 {
            self.nearest_range(far.0, far.1, x, k, r2, accept, heap);
        }
    }

    /// Give every photon (in tree order) a sphere of radius `radii[i]` and
    /// build the boxes for [`PhotonTree::for_each_crossed`].
    ///
    /// # Panics
    /// When `radii` does not hold one radius per photon.
    pub fn set_radii(&mut self, radii: Vec<f32>) {
        assert_eq!(radii.len(), self.photons.len(), "one radius per photon");
        self.boxes = vec![(Vec3::ZERO, Vec3::ZERO); self.photons.len()];
        self.radii = radii;
        if !self.photons.is_empty() {
            fill_boxes(&self.photons, &self.radii, &mut self.boxes, 0, self.photons.len());
        }
    }

    /// Radius of photon `index` (tree order) after [`PhotonTree::set_radii`].
    #[inline]
    pub fn radius(&self, index: usize) -> f32 {
        self.radii[index]
    }

    /// Call `f(photon, t, d2, r)` for every photon whose sphere (radius `r`)
    /// the line of `ray` crosses with the photon's projection `t` on the ray
    /// in `[t0, t1)` (`ray.d` unit); `d2` is the squared distance from the
    /// photon to the ray. Needs [`PhotonTree::set_radii`] first (otherwise
    /// finds nothing).
    pub fn for_each_crossed(&self, ray: &Ray, t0: f32, t1: f32, mut f: impl FnMut(&Photon, f32, f32, f32)) {
        if self.boxes.is_empty() || !(t1 > t0) {
            return;
        }
        let inv_d = Vec3::ONE / ray.d;
        self.crossed_range(0, self.photons.len(), ray, inv_d, t0, t1, &mut f);
    }

    #[allow(clippy::too_many_arguments)]
    fn crossed_range(
        &self,
        lo: usize,
        hi: usize,
        ray: &Ray,
        inv_d: Vec3,
        t0: f32,
        t1: f32,
        f: &mut impl FnMut(&Photon, f32, f32, f32),
    ) {
        if lo >= hi {
            return;
        }
        let mid = (lo + hi) / 2;
        let (b_min, b_max) = self.boxes[mid];
        // Slab test of the subtree's box against the segment.
        let a = (b_min - ray.o) * inv_d;
        let b = (b_max - ray.o) * inv_d;
        let t_near = a.min(b).max_element().max(t0);
        let t_far = a.max(b).min_element().min(t1);
        if !(t_near <= t_far) {
            // Also rejects NaN from 0 * inf on a box face (then the box is
            // only touched, and any sphere in it has zero chord).
            return;
        }
        let photon = &self.photons[mid];
        let r = self.radii[mid];
        let to = photon.p - ray.o;
        let t = to.dot(ray.d);
        if t >= t0 && t < t1 {
            let d2 = (to - ray.d * t).length_squared();
            if d2 < r * r {
                f(photon, t, d2, r);
            }
        }
        self.crossed_range(lo, mid, ray, inv_d, t0, t1, f);
        self.crossed_range(mid + 1, hi, ray, inv_d, t0, t1, f);
    }
}

/// Median split of `photons` on the axis of largest extent, recursively.
fn build_range(photons: &mut [Photon], axes: &mut [u8]) {
    let n = photons.len();
    if n <= 1 {
        return;
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for photon in photons.iter() {
        lo = lo.min(photon.p);
        hi = hi.max(photon.p);
    }
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = n / 2;
    photons.select_nth_unstable_by(mid, |a, b| a.p[axis].total_cmp(&b.p[axis]));
    axes[mid] = axis as u8;
    let (left, rest) = photons.split_at_mut(mid);
    let right = &mut rest[1..];
    let (left_axes, rest_axes) = axes.split_at_mut(mid);
    let right_axes = &mut rest_axes[1..];
    if n > PARALLEL_BUILD {
        rayon::join(|| build_range(left, left_axes), || build_range(right, right_axes));
    } else {
        build_range(left, left_axes);
        build_range(right, right_axes);
    }
}

/// Boxes of the spheres of every subtree, bottom up; returns the box of `[lo, hi)`.
fn fill_boxes(photons: &[Photon], radii: &[f32], boxes: &mut [(Vec3, Vec3)], lo: usize, hi: usize) -> (Vec3, Vec3) {
    let mid = (lo + hi) / 2;
    let r = Vec3::splat(radii[mid]);
    let mut b = (photons[mid].p - r, photons[mid].p + r);
    if lo < mid {
        let left = fill_boxes(photons, radii, boxes, lo, mid);
        b = (b.0.min(left.0), b.1.max(left.1));
    }
    if mid + 1 < hi {
        let right = fill_boxes(photons, radii, boxes, mid + 1, hi);
        b = (b.0.min(right.0), b.1.max(right.1));
    }
    boxes[mid] = b;
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::sampling::PixelSampler;

    fn random_photons(n: usize, key: u64) -> Vec<Photon> {
        let mut rng = PixelSampler::from_key(key);
        (0..n)
            .map(|i| {
                // Clustered: half uniform in a box, half in a small blob, to
                // exercise unbalanced extents.
                let u = Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d());
                let p = if i % 2 == 0 { u * Vec3::new(4.0, 1.0, 2.0) } else { Vec3::splat(1.0) + 0.05 * u };
                Photon::in_medium(p, Vec3::X, Rgb::ONE, (i % 3) as u32)
            })
            .collect()
    }

    fn random_query(rng: &mut PixelSampler) -> Vec3 {
        Vec3::new(rng.next_1d() * 4.4 - 0.2, rng.next_1d() * 1.4 - 0.2, rng.next_1d() * 2.4 - 0.2)
    }

    #[test]
    fn radius_query_returns_exactly_the_brute_force_set() {
        for n in [0usize, 1, 5, 7, 100, 5000, 40_000] {
            let photons = random_photons(n, n as u64);
            let tree = PhotonTree::build(photons.clone());
            let mut rng = PixelSampler::from_key(11 + n as u64);
            for q in 0..200 {
                let x = if q % 4 == 0 && n > 0 { photons[q % n].p } else { random_query(&mut rng) };
                let r = 0.3 * rng.next_1d().powi(2);
                let r2 = r * r;
                let mut found: Vec<[u32; 3]> = Vec::new();
                tree.for_each_within(x, r2, |p, d2| {
                    assert!((d2 - (p.p - x).length_squared()).abs() <= 1e-6);
                    found.push(p.p.to_array().map(f32::to_bits));
                });
                let mut expected: Vec<[u32; 3]> = photons
                    .iter()
                    .filter(|p| (p.p - x).length_squared() < r2)
                    .map(|p| p.p.to_array().map(f32::to_bits))
                    .collect();
                found.sort_unstable();
                expected.sort_unstable();
                assert_eq!(found, expected, "n {n} query {q}");
            }
        }
    }

    #[test]
    fn nearest_query_returns_exactly_the_brute_force_set() {
        for n in [0usize, 3, 7, 1000, 40_000] {
            let photons = random_photons(n, 100 + n as u64);
            let tree = PhotonTree::build(photons.clone());
            let mut rng = PixelSampler::from_key(7 + n as u64);
            let mut heap = BinaryHeap::new();
            for q in 0..200 {
                let x = random_query(&mut rng);
                let k = 1 + (q % 64);
                // Half the queries capped by a radius, half unbounded; a
                // filter on the tag as the volume estimate uses.
                let r2_max = if q % 2 == 0 { 0.04 } else { f32::INFINITY };
                let tag = (q % 3) as u32;
                let r2 = tree.nearest(x, k, r2_max, |p| p.tag == tag, &mut heap);
                let mut found: Vec<f32> = heap.iter().map(|nb| nb.d2).collect();
                found.sort_by(f32::total_cmp);
                let mut all: Vec<f32> = photons
                    .iter()
                    .filter(|p| p.tag == tag)
                    .map(|p| (p.p - x).length_squared())
                    .filter(|&d2| d2 < r2_max)
                    .collect();
                all.sort_by(f32::total_cmp);
                all.truncate(k);
                assert_eq!(found, all, "n {n} query {q}");
                let expected_r2 = if all.len() == k { all[k - 1] } else { r2_max };
                assert_eq!(r2, expected_r2);
                for nb in heap.iter() {
                    assert_eq!(tree.photons()[nb.index as usize].tag, tag);
                }
            }
        }
    }

    #[test]
    fn beam_query_returns_exactly_the_brute_force_set() {
        let photons = random_photons(20_000, 9);
        let mut tree = PhotonTree::build(photons);
        let mut rng = PixelSampler::from_key(21);
        let radii: Vec<f32> = (0..tree.len()).map(|_| 0.01 + 0.1 * rng.next_1d()).collect();
        tree.set_radii(radii);
        for q in 0..200 {
            let o = random_query(&mut rng);
            let d = crate::sampling::sample_uniform_sphere(rng.next_2d());
            let ray = Ray::new(o, d);
            let (t0, t1) = if q % 2 == 0 { (0.0, f32::INFINITY) } else { (0.1, 0.1 + 2.0 * rng.next_1d()) };
            let mut found: Vec<u32> = Vec::new();
            tree.for_each_crossed(&ray, t0, t1, |p, _, _, _| found.push(p.p.x.to_bits() ^ p.p.y.to_bits()));
            let mut expected: Vec<u32> = (0..tree.len())
                .filter(|&i| {
                    let p = tree.photons()[i].p;
                    let t = (p - o).dot(d);
                    let d2 = (p - o - d * t).length_squared();
                    t >= t0 && t < t1 && d2 < tree.radius(i).powi(2)
                })
                .map(|i| tree.photons()[i].p.x.to_bits() ^ tree.photons()[i].p.y.to_bits())
                .collect();
            found.sort_unstable();
            expected.sort_unstable();
            assert_eq!(found, expected, "query {q}");
        }
    }

    #[test]
    fn build_does_not_depend_on_the_thread_count() {
        let photons = random_photons(100_000, 4);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let a = one.install(|| PhotonTree::build(photons.clone()));
        let b = three.install(|| PhotonTree::build(photons));
        assert_eq!(a.photons(), b.photons());
        assert_eq!(a.axes, b.axes);
    }
}
