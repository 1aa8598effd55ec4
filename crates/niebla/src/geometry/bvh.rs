//! A bounding volume hierarchy over primitives given by their boxes: a
//! binned surface-area-heuristic build (Wald 2007, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies"; 16 bins on each axis), run in
//! parallel over subtrees and deterministic (the tree depends only on the
//! boxes, never on the thread count), flattened depth first into 32-byte
//! nodes. Used for the triangles of a mesh and for the objects of a scene
//! (the two levels of the scene's acceleration structure).

use glam::Vec3A;

use crate::math::{Ray, Vec3};

use super::AxisAlignedBox;

/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Largest number of primitives in a leaf.
const MAX_LEAF: usize = 8;
/// Subtrees with more primitives than this are built in parallel.
const PARALLEL_THRESHOLD: usize = 4096;
/// Cost of visiting a node relative to one primitive test, in the SAH.
const TRAVERSAL_COST: f32 = 1.0;
/// Depth below which the build stops trusting the SAH and splits at the
/// median, so that no tree gets deeper than `MEDIAN_DEPTH + 32`.
const MEDIAN_DEPTH: usize = 48;
/// Deepest traversal stack: deeper than any tree the build makes.
const STACK_DEPTH: usize = 96;

/// One node of the flattened tree (32 bytes). An interior node's first child
/// follows it; `offset` is the second child's index. A leaf holds `count`
/// primitives from `offset` in [`Bvh::order`].
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub struct BvhNode {
    /// Lower corner of the node's box.
    pub min: [f32; 3],
    /// Upper corner of the node's box.
    pub max: [f32; 3],
    /// Second child (interior) or first primitive slot (leaf).
    pub offset: u32,
    /// Number of primitives (0 for an interior node).
    pub count: u16,
    /// Split axis of an interior node (0, 1, 2): the child on the lower side
    /// comes first.
    pub axis: u16,
}

/// A bounding volume hierarchy: flattened nodes and the primitive order of
/// the leaves.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Nodes, depth first; node 0 is the root (absent for no primitives).
    pub nodes: Vec<BvhNode>,
    /// Primitive indices in leaf order.
    pub order: Vec<u32>,
}

/// A primitive during the build: its box, the box's centroid and its index.
#[derive(Clone, Copy)]
struct PrimRef {
    min: Vec3,
    max: Vec3,
    centroid: Vec3,
    index: u32,
}

/// The build's tree before flattening.
enum BuildNode {
    Leaf { min: Vec3, max: Vec3, first: usize, count: usize },
    Interior { min: Vec3, max: Vec3, axis: usize, children: Box<[BuildNode; 2]> },
}

fn surface_area(min: Vec3, max: Vec3) -> f32 {
    let d = (max - min).max(Vec3::ZERO);
    2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
}

#[derive(Clone, Copy)]
struct Bin {
    min: Vec3,
    max: Vec3,
    count: usize,
}

impl Bin {
    const EMPTY: Bin = Bin { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY), count: 0 };
    fn grow(&mut self, p: &PrimRef) {
        self.min = self.min.min(p.min);
        self.max = self.max.max(p.max);
        self.count += 1;
    }
    fn merge(&self, o: &Bin) -> Bin {
        Bin { min: self.min.min(o.min), max: self.max.max(o.max), count: self.count + o.count }
    }
}

fn bounds_of(prims: &[PrimRef]) -> (Vec3, Vec3, Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut clo = lo;
    let mut chi = hi;
    for p in prims {
        lo = lo.min(p.min);
        hi = hi.max(p.max);
        clo = clo.min(p.centroid);
        chi = chi.max(p.centroid);
    }
    (lo, hi, clo, chi)
}

/// Bin of a centroid coordinate `c` over `[lo, lo + extent]`.
#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

fn build_node(prims: &mut [PrimRef], first: usize, depth: usize) -> BuildNode {
    let (min, max, clo, chi) = bounds_of(prims);
    let n = prims.len();
    if n <= 2 {
        return BuildNode::Leaf { min, max, first, count: n };
    }
    // Best SAH split over the bins of every axis.
    let extent = chi - clo;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, split bin)
    for axis in 0..3 {
        if !(extent[axis] > 0.0) {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let mut bins = [Bin::EMPTY; BINS];
        for p in prims.iter() {
            bins[bin_of(p.centroid[axis], clo[axis], scale)].grow(p);
        }
        // Sweep from the right for the right-hand areas and counts.
        let mut right = [(0.0f32, 0usize); BINS];
        let mut acc = Bin::EMPTY;
        for i in (1..BINS).rev() {
            acc = acc.merge(&bins[i]);
            right[i] = (surface_area(acc.min, acc.max), acc.count);
        }
        let mut left = Bin::EMPTY;
        for i in 1..BINS {
            left = left.merge(&bins[i - 1]);
            let (ra, rc) = right[i];
            if left.count == 0 || rc == 0 {
                continue;
            }
            let cost = surface_area(left.min, left.max) * left.count as f32 + ra * rc as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, i));
            }
        }
    }
    let area = surface_area(min, max).max(f32::MIN_POSITIVE);
    let split = match best {
        Some((_, axis, _)) if depth >= MEDIAN_DEPTH => {
            // Too deep for the SAH's choices (pathological inputs): the median.
            let mid = n / 2;
            prims.select_nth_unstable_by(mid, |a, b| {
                a.centroid[axis].total_cmp(&b.centroid[axis]).then(a.index.cmp(&b.index))
            });
            (axis, mid)
        }
        Some((cost, axis, bin)) => {
            let sah = TRAVERSAL_COST + cost / area;
            if n <= MAX_LEAF && sah >= n as f32 {
                return BuildNode::Leaf { min, max, first, count: n };
            }
            let scale = BINS as f32 / extent[axis];
            let lo = clo[axis];
            let mid = partition(prims, |p| bin_of(p.centroid[axis], lo, scale) < bin);
            (axis, mid)
        }
        None => {
            // All centroids coincide: a leaf if small, else halves in index order.
            if n <= MAX_LEAF {
                return BuildNode::Leaf { min, max, first, count: n };
            }
            let d = max - min;
            let axis = if d.x >= d.y && d.x >= d.z {
                0
            } else if d.y >= d.z {
                1
            } else {
                2
            };
            (axis, n / 2)
        }
    };
    let (axis, mid) = split;
    let (left, right) = prims.split_at_mut(mid);
    let children = if n > PARALLEL_THRESHOLD {
        let (a, b) = rayon::join(|| build_node(left, first, depth + 1), || build_node(right, first + mid, depth + 1));
        [a, b]
    } else {
        [build_node(left, first, depth + 1), build_node(right, first + mid, depth + 1)]
    };
    BuildNode::Interior { min, max, axis, children: Box::new(children) }
}

/// Stable-enough in-place partition: elements satisfying `pred` first;
/// returns their count. Deterministic (depends only on the input order).
fn partition(prims: &mut [PrimRef], pred: impl Fn(&PrimRef) -> bool) -> usize {
    let mut i = 0;
    for j in 0..prims.len() {
        if pred(&prims[j]) {
            prims.swap(i, j);
            i += 1;
        }
    }
    i
}

fn flatten(node: &BuildNode, nodes: &mut Vec<BvhNode>) {
    match node {
        BuildNode::Leaf { min, max, first, count } => nodes.push(BvhNode {
            min: min.to_array(),
            max: max.to_array(),
            offset: *first as u32,
            count: *count as u16,
            axis: 0,
        }),
        BuildNode::Interior { min, max, axis, children } => {
            let me = nodes.len();
            nodes.push(BvhNode { min: min.to_array(), max: max.to_array(), offset: 0, count: 0, axis: *axis as u16 });
            flatten(&children[0], nodes);
            nodes[me].offset = nodes.len() as u32;
            flatten(&children[1], nodes);
        }
    }
}

/// A ray prepared for box tests: origin and reciprocal direction, in SIMD
/// lanes.
#[derive(Clone, Copy, Debug)]
struct BoxRay {
    o: Vec3A,
    inv: Vec3A,
}

impl BoxRay {
    fn new(ray: &Ray) -> BoxRay {
        BoxRay { o: Vec3A::from(ray.o), inv: Vec3A::from(ray.d.recip()) }
    }

    /// Entry parameter of the ray into the node's box within `[t_min, t_max]`,
    /// or `None`. The far parameter is widened by `1 + 2 gamma_3` (pbrt-v4's
    /// conservative bound) so that rounding never culls a box the ray grazes.
    #[inline(always)]
    fn enter(&self, n: &BvhNode, t_min: f32, t_max: f32) -> Option<f32> {
        let lo = (Vec3A::from(n.min) - self.o) * self.inv;
        let hi = (Vec3A::from(n.max) - self.o) * self.inv;
        let near = lo.min(hi);
        let far = lo.max(hi) * GROW;
        // f32::min/max ignore the NaN of 0 * inf (a ray in a slab plane).
        let t0 = t_min.max(near.x).max(near.y).max(near.z);
        let t1 = t_max.min(far.x).min(far.y).min(far.z);
        (t0 <= t1).then_some(t0)
    }
}

/// `1 + 2 gamma_3` with `gamma_n = n eps / (1 - n eps)` for `f32`'s unit roundoff.
const GROW: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

impl Bvh {
    /// Builds the hierarchy over primitives with boxes `boxes` (primitive `i`
    /// has box `boxes[i]`). Boxes with a NaN corner or `min > max` must not
    /// be passed (callers leave such primitives out).
    pub fn build(boxes: &[AxisAlignedBox]) -> Bvh {
        if boxes.is_empty() {
            return Bvh::default();
        }
        let mut prims: Vec<PrimRef> = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| PrimRef { min: b.min, max: b.max, centroid: 0.5 * (b.min + b.max), index: i as u32 })
            .collect();
        let root = build_node(&mut prims, 0, 0);
        let mut nodes = Vec::with_capacity(2 * prims.len() / 2 + 1);
        flatten(&root, &mut nodes);
        drop(root);
        nodes.shrink_to_fit();
        Bvh { nodes, order: prims.iter().map(|p| p.index).collect() }
    }

    /// Bytes held by the nodes and the primitive order.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<BvhNode>() + self.order.len() * 4
    }

    /// Bytes the hierarchy over `n` primitives needs at most (two nodes per
    /// primitive bound, the order, and the build's temporary references).
    pub fn memory_estimate(n: usize) -> usize {
        n * (2 * std::mem::size_of::<BvhNode>() + 4 + std::mem::size_of::<PrimRef>() + 48)
    }

    /// World box of everything in the hierarchy (`None` when empty).
    pub fn bounds(&self) -> Option<AxisAlignedBox> {
        self.nodes.first().map(|n| AxisAlignedBox { min: Vec3::from(n.min), max: Vec3::from(n.max) })
    }

    /// Nearest hit: visits the leaves the ray may reach within `(t_min,
    /// t_max)` in near-to-far order and calls `hit(primitive, t_closest)` for
    /// each primitive there; `hit` returns the parameter of a hit closer than
    /// `t_closest` (and remembers what it needs), or `None`. Returns the
    /// parameter of the nearest hit reported.
    #[inline]
    pub fn closest<F>(&self, ray: &Ray, t_min: f32, t_max: f32, mut hit: F) -> Option<f32>
    where
        F: FnMut(u32, f32) -> Option<f32>,
    {
        if self.nodes.is_empty() {
            return None;
        }
        let r = BoxRay::new(ray);
        let mut closest = t_max;
        let mut found = false;
        let mut stack = [0u32; STACK_DEPTH];
        let mut sp = 0usize;
        let mut index = 0usize;
        r.enter(&self.nodes[0], t_min, closest)?;
        loop {
            let node = &self.nodes[index];
            if node.count > 0 {
                let first = node.offset as usize;
                for &p in &self.order[first..first + node.count as usize] {
                    if let Some(t) = hit(p, closest) {
                        closest = t;
                        found = true;
                    }
                }
            } else {
                let (a, b) = (index + 1, node.offset as usize);
                let ta = r.enter(&self.nodes[a], t_min, closest);
                let tb = r.enter(&self.nodes[b], t_min, closest);
                match (ta, tb) {
                    (Some(x), Some(y)) => {
                        let (near, far) = if y < x { (b, a) } else { (a, b) };
                        if sp < STACK_DEPTH {
                            stack[sp] = far as u32;
                            sp += 1;
                        }
                        index = near;
                        continue;
                    }
                    (Some(_), None) => {
                        index = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        index = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next node still in reach.
            loop {
                if sp == 0 {
                    return found.then_some(closest);
                }
                sp -= 1;
                let candidate = stack[sp] as usize;
                if r.enter(&self.nodes[candidate], t_min, closest).is_some() {
                    index = candidate;
                    break;
                }
            }
        }
    }

    /// Any hit: `true` as soon as `hit(primitive, t_max)` reports a hit for a
    /// primitive of a leaf the ray may reach within `(t_min, t_max)`.
    #[inline]
    pub fn any<F>(&self, ray: &Ray, t_min: f32, t_max: f32, mut hit: F) -> bool
    where
        F: FnMut(u32, f32) -> bool,
    {
        if self.nodes.is_empty() {
            return false;
        }
        let r = BoxRay::new(ray);
        if r.enter(&self.nodes[0], t_min, t_max).is_none() {
            return false;
        }
        let mut stack = [0u32; STACK_DEPTH];
        let mut sp = 0usize;
        let mut index = 0usize;
        loop {
            let node = &self.nodes[index];
            if node.count > 0 {
                let first = node.offset as usize;
                for &p in &self.order[first..first + node.count as usize] {
                    if hit(p, t_max) {
                        return true;
                    }
                }
            } else {
                // Both children's boxes are tested here; only those the ray
                // enters are visited, the nearer first.
                let (a, b) = (index + 1, node.offset as usize);
                match (r.enter(&self.nodes[a], t_min, t_max), r.enter(&self.nodes[b], t_min, t_max)) {
                    (Some(x), Some(y)) => {
                        let (near, far) = if y < x { (b, a) } else { (a, b) };
                        if sp < STACK_DEPTH {
                            stack[sp] = far as u32;
                            sp += 1;
                        }
                        index = near;
                        continue;
                    }
                    (Some(_), None) => {
                        index = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        index = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            index = stack[sp] as usize;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::PixelSampler;

    fn random_boxes(n: usize, seed: u64) -> Vec<AxisAlignedBox> {
        let mut s = PixelSampler::from_key(seed);
        (0..n)
            .map(|_| {
                let c = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 10.0;
                let h = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.3 + Vec3::splat(0.01);
                AxisAlignedBox { min: c - h, max: c + h }
            })
            .collect()
    }

    #[test]
    fn every_primitive_sits_in_one_leaf_and_nodes_bound_their_children() {
        let boxes = random_boxes(5000, 3);
        let bvh = Bvh::build(&boxes);
        let mut seen = bvh.order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..5000u32).collect::<Vec<_>>());
        for (i, n) in bvh.nodes.iter().enumerate() {
            let inside = |m: &BvhNode| (0..3).all(|k| m.min[k] >= n.min[k] && m.max[k] <= n.max[k]);
            if n.count == 0 {
                assert!(inside(&bvh.nodes[i + 1]) && inside(&bvh.nodes[n.offset as usize]));
            } else {
                for &p in &bvh.order[n.offset as usize..(n.offset + n.count as u32) as usize] {
                    let b = &boxes[p as usize];
                    assert!((0..3).all(|k| b.min[k] >= n.min[k] && b.max[k] <= n.max[k]));
                }
            }
        }
        // Deterministic: the same boxes give the same tree.
        let again = Bvh::build(&boxes);
        assert_eq!(again.order, bvh.order);
    }

    #[test]
    fn closest_and_any_agree_with_a_loop_over_all_boxes() {
        let boxes = random_boxes(3000, 9);
        let bvh = Bvh::build(&boxes);
        let mut s = PixelSampler::from_key(11);
        for _ in 0..2000 {
            let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 14.0 - Vec3::splat(2.0);
            let d = (Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) - Vec3::splat(0.5)).normalize();
            let ray = Ray::new(o, d);
            let test = |p: u32, t_max: f32| {
                let (a, b) = boxes[p as usize].slab_range(&ray);
                let t = a.max(0.0);
                (a <= b && t < t_max && b > 0.0).then_some(t)
            };
            let brute = (0..3000u32).filter_map(|p| test(p, f32::INFINITY)).fold(f32::INFINITY, f32::min);
            let got = bvh.closest(&ray, 0.0, f32::INFINITY, test).unwrap_or(f32::INFINITY);
            assert_eq!(got, brute);
            assert_eq!(bvh.any(&ray, 0.0, f32::INFINITY, |p, t| test(p, t).is_some()), brute.is_finite());
        }
    }
}
