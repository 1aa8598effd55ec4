//! A bounding volume hierarchy over primitives given by their boxes: a
//! binned surface-area-heuristic build (Wald 2007, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies"; 16 bins on each axis), run in
//! parallel over subtrees and deterministic (the tree depends only on the
//! boxes, never on the thread count), then collapsed into a 4-wide tree
//! whose nodes hold their children's boxes side by side, so that one node
//! visit tests four boxes in SIMD lanes (the layout of Wald, Benthin and
//! Boulos 2008, "Getting rid of packets", and of Embree's BVH4). Used for
//! the triangles of a mesh and for the objects of a scene (the two levels of
//! the scene's acceleration structure).

use glam::{Vec3A, Vec4};

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
/// Deepest traversal stack: a 4-wide node pushes at most three entries more
/// than it pops, and the tree is at most `MEDIAN_DEPTH + 32` levels deep.
const STACK_DEPTH: usize = 3 * (MEDIAN_DEPTH + 32) + 16;
/// Stack of the traversals of trees of up to 5 levels (scenes of a few
/// dozen objects, small meshes).
const SMALL_STACK: usize = 16;
/// Stack of the traversals of trees of up to 21 levels.
const MEDIUM_STACK: usize = 64;

/// Number of levels of inner nodes of a flattened tree (0 without nodes):
/// the traversal stack holds at most `3 * levels + 1` entries, as a node
/// pushes at most three more than it pops.
fn inner_levels(nodes: &[BvhNode]) -> usize {
    let mut deepest = 0;
    let mut todo = Vec::new();
    if !nodes.is_empty() {
        todo.push((0u32, 1usize));
    }
    while let Some((i, level)) = todo.pop() {
        deepest = deepest.max(level);
        let node = &nodes[i as usize];
        for &child in &node.child[..node.count as usize] {
            if child & LEAF == 0 {
                todo.push((child, level + 1));
            }
        }
    }
    deepest
}

/// One node of the 4-wide tree (112 bytes): the boxes of up to four
/// children, coordinate by coordinate, and what each child is.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct BvhNode {
    /// Lower x of each child's box.
    pub min_x: [f32; 4],
    /// Lower y of each child's box.
    pub min_y: [f32; 4],
    /// Lower z of each child's box.
    pub min_z: [f32; 4],
    /// Upper x of each child's box.
    pub max_x: [f32; 4],
    /// Upper y of each child's box.
    pub max_y: [f32; 4],
    /// Upper z of each child's box.
    pub max_z: [f32; 4],
    /// Each child: an inner node's index, or with [`LEAF`] set a leaf of
    /// `child & 15` primitives from slot `(child & !LEAF) >> 4` of
    /// [`Bvh::order`]. Children past `count` are unused.
    pub child: [u32; 4],
    /// Number of children in use (2 to 4; 1 only for a root that is a leaf).
    pub count: u32,
}

/// Flag of a leaf child in [`BvhNode::child`].
pub const LEAF: u32 = 1 << 31;

/// Most primitives a hierarchy holds (a leaf's first slot has 27 bits).
pub const MAX_PRIMITIVES: usize = 1 << 27;

/// A bounding volume hierarchy: 4-wide nodes and the primitive order of the
/// leaves.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// Nodes, depth first; node 0 is the root (absent for no primitives).
    pub nodes: Vec<BvhNode>,
    /// Box of everything (meaningless without nodes).
    root_box: AxisAlignedBox,
    /// Primitive indices in leaf order.
    pub order: Vec<u32>,
    /// Most entries a traversal stack of this tree can hold (`3 * levels +
    /// 1`): the traversals use the smallest fixed stack that fits, so that
    /// shallow trees (a scene of a few objects) do not clear a stack sized
    /// for the deepest tree on every ray.
    stack_need: usize,
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
    Interior { min: Vec3, max: Vec3, children: Box<[BuildNode; 2]> },
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
    let (_, mid) = split;
    let (left, right) = prims.split_at_mut(mid);
    let children = if n > PARALLEL_THRESHOLD {
        let (a, b) = rayon::join(|| build_node(left, first, depth + 1), || build_node(right, first + mid, depth + 1));
        [a, b]
    } else {
        [build_node(left, first, depth + 1), build_node(right, first + mid, depth + 1)]
    };
    BuildNode::Interior { min, max, children: Box::new(children) }
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

impl BuildNode {
    fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            BuildNode::Leaf { min, max, .. } | BuildNode::Interior { min, max, .. } => (*min, *max),
        }
    }
}

/// The up to four subtrees a 4-wide node over `node` holds: its two
/// children, the inner one of largest surface area replaced by its own two
/// children while there is room.
fn collapse(node: &BuildNode) -> Vec<&BuildNode> {
    let BuildNode::Interior { children, .. } = node else { return vec![node] };
    let mut kids: Vec<&BuildNode> = vec![&children[0], &children[1]];
    while kids.len() < 4 {
        let widest = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| matches!(k, BuildNode::Interior { .. }))
            .max_by(|a, b| {
                let area = |k: &BuildNode| {
                    let (lo, hi) = k.bounds();
                    surface_area(lo, hi)
                };
                area(a.1).total_cmp(&area(b.1)).then(b.0.cmp(&a.0))
            })
            .map(|(i, _)| i);
        let Some(i) = widest else { break };
        let BuildNode::Interior { children, .. } = kids[i] else { break };
        kids[i] = &children[0];
        kids.insert(i + 1, &children[1]);
    }
    kids
}

/// Appends the 4-wide node over `node` and its subtrees depth first;
/// returns its index.
fn flatten(node: &BuildNode, nodes: &mut Vec<BvhNode>) -> u32 {
    let me = nodes.len();
    let empty = [0.0f32; 4];
    nodes.push(BvhNode {
        min_x: empty,
        min_y: empty,
        min_z: empty,
        max_x: empty,
        max_y: empty,
        max_z: empty,
        child: [0; 4],
        count: 0,
    });
    let kids = collapse(node);
    let mut out = nodes[me];
    out.count = kids.len() as u32;
    for (k, kid) in kids.iter().enumerate() {
        let (lo, hi) = kid.bounds();
        out.min_x[k] = lo.x;
        out.min_y[k] = lo.y;
        out.min_z[k] = lo.z;
        out.max_x[k] = hi.x;
        out.max_y[k] = hi.y;
        out.max_z[k] = hi.z;
        out.child[k] = match kid {
            BuildNode::Leaf { first, count, .. } => LEAF | ((*first as u32) << 4) | *count as u32,
            BuildNode::Interior { .. } => 0, // set below, after the earlier siblings' subtrees
        };
    }
    nodes[me] = out;
    for (k, kid) in kids.iter().enumerate() {
        if let BuildNode::Interior { .. } = kid {
            let index = flatten(kid, nodes);
            nodes[me].child[k] = index;
        }
    }
    me as u32
}

/// A ray prepared for box tests: origin and reciprocal direction, each
/// coordinate in all four SIMD lanes.
#[derive(Clone, Copy, Debug)]
struct BoxRay {
    ox: Vec4,
    oy: Vec4,
    oz: Vec4,
    ix: Vec4,
    iy: Vec4,
    iz: Vec4,
}

impl BoxRay {
    fn new(ray: &Ray) -> BoxRay {
        let inv = ray.d.recip();
        BoxRay {
            ox: Vec4::splat(ray.o.x),
            oy: Vec4::splat(ray.o.y),
            oz: Vec4::splat(ray.o.z),
            ix: Vec4::splat(inv.x),
            iy: Vec4::splat(inv.y),
            iz: Vec4::splat(inv.z),
        }
    }

    /// Entry parameters of the ray into the node's four child boxes within
    /// `[t_min, t_max]`, and the bit mask of the children it enters. The far
    /// parameter is widened by `1 + 2 gamma_3` (pbrt-v4's conservative
    /// bound) so that rounding never culls a box the ray grazes.
    #[inline(always)]
    fn enter4(&self, n: &BvhNode, t_min: f32, t_max: f32) -> (Vec4, u32) {
        let x0 = (Vec4::from_array(n.min_x) - self.ox) * self.ix;
        let x1 = (Vec4::from_array(n.max_x) - self.ox) * self.ix;
        let y0 = (Vec4::from_array(n.min_y) - self.oy) * self.iy;
        let y1 = (Vec4::from_array(n.max_y) - self.oy) * self.iy;
        let z0 = (Vec4::from_array(n.min_z) - self.oz) * self.iz;
        let z1 = (Vec4::from_array(n.max_z) - self.oz) * self.iz;
        // A NaN (0 * inf: a ray in a slab plane) makes min/max return their
        // other operand, as the scalar test's f32::min/max did.
        let near = x0.min(x1).max(y0.min(y1)).max(z0.min(z1)).max(Vec4::splat(t_min));
        let far = (x0.max(x1).min(y0.max(y1)).min(z0.max(z1)) * GROW).min(Vec4::splat(t_max));
        let used = (1u32 << n.count) - 1;
        (near, near.cmple(far).bitmask() & used)
    }
}

/// Whether the ray's segment `[t_min, t_max]` meets `b` (for the root box).
#[inline]
fn enters_box(ray: &Ray, b: &AxisAlignedBox, t_min: f32, t_max: f32) -> bool {
    let inv = Vec3A::from(ray.d.recip());
    let o = Vec3A::from(ray.o);
    let lo = (Vec3A::from(b.min) - o) * inv;
    let hi = (Vec3A::from(b.max) - o) * inv;
    let near = lo.min(hi);
    let far = lo.max(hi) * GROW;
    let t0 = t_min.max(near.x).max(near.y).max(near.z);
    let t1 = t_max.min(far.x).min(far.y).min(far.z);
    t0 <= t1
}

/// `1 + 2 gamma_3` with `gamma_n = n eps / (1 - n eps)` for `f32`'s unit roundoff.
const GROW: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

impl Bvh {
    /// Builds the hierarchy over primitives with boxes `boxes` (primitive `i`
    /// has box `boxes[i]`), at most [`MAX_PRIMITIVES`] of them (callers
    /// refuse more). Boxes with a NaN corner or `min > max` must not be
    /// passed (callers leave such primitives out).
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
        let (lo, hi) = root.bounds();
        // A lone leaf becomes a root node with one child.
        let mut nodes = Vec::with_capacity(prims.len() / 2 + 1);
        flatten(&root, &mut nodes);
        drop(root);
        nodes.shrink_to_fit();
        let stack_need = 3 * inner_levels(&nodes) + 1;
        debug_assert!(stack_need <= STACK_DEPTH);
        Bvh {
            nodes,
            root_box: AxisAlignedBox { min: lo, max: hi },
            order: prims.iter().map(|p| p.index).collect(),
            stack_need,
        }
    }

    /// Bytes held by the nodes and the primitive order.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<BvhNode>() + self.order.len() * 4
    }

    /// Bytes the hierarchy over `n` primitives needs at most (two nodes per
    /// primitive bound, the order, and the build's temporary references).
    pub fn memory_estimate(n: usize) -> usize {
        n * (std::mem::size_of::<BvhNode>() + 4 + std::mem::size_of::<PrimRef>() + 48 + 64)
    }

    /// World box of everything in the hierarchy (`None` when empty).
    pub fn bounds(&self) -> Option<AxisAlignedBox> {
        (!self.nodes.is_empty()).then_some(self.root_box)
    }

    /// Nearest hit: visits the leaves the ray may reach within `(t_min,
    /// t_max)`, nearer boxes first, and calls `hit(primitive, t_closest)` for
    /// each primitive there; `hit` returns the parameter of a hit closer than
    /// `t_closest` (and remembers what it needs), or `None`. Returns the
    /// parameter of the nearest hit reported.
    #[inline]
    pub fn closest<F>(&self, ray: &Ray, t_min: f32, t_max: f32, hit: F) -> Option<f32>
    where
        F: FnMut(u32, f32) -> Option<f32>,
    {
        if self.nodes.is_empty() || !enters_box(ray, &self.root_box, t_min, t_max) {
            return None;
        }
        if self.stack_need <= SMALL_STACK {
            self.closest_with::<SMALL_STACK, F>(ray, t_min, t_max, hit)
        } else if self.stack_need <= MEDIUM_STACK {
            self.closest_with::<MEDIUM_STACK, F>(ray, t_min, t_max, hit)
        } else {
            self.closest_with::<STACK_DEPTH, F>(ray, t_min, t_max, hit)
        }
    }

    /// [`Self::closest`] with a stack of `N >= self.stack_need` entries.
    #[inline]
    fn closest_with<const N: usize, F>(&self, ray: &Ray, t_min: f32, t_max: f32, mut hit: F) -> Option<f32>
    where
        F: FnMut(u32, f32) -> Option<f32>,
    {
        let r = BoxRay::new(ray);
        let mut closest = t_max;
        let mut found = false;
        // Entries: a child word (inner node or leaf) and its entry parameter.
        let mut stack = [(0u32, 0f32); N];
        let mut sp = 1usize;
        stack[0] = (0, t_min);
        while sp > 0 {
            sp -= 1;
            let (child, t_enter) = stack[sp];
            if t_enter > closest {
                continue;
            }
            if child & LEAF != 0 {
                let first = ((child & !LEAF) >> 4) as usize;
                for &p in &self.order[first..first + (child & 15) as usize] {
                    if let Some(t) = hit(p, closest) {
                        closest = t;
                        found = true;
                    }
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let (near, mut mask) = r.enter4(node, t_min, closest);
            // Push the entered children farthest first, so the nearest pops next.
            let base = sp;
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let entry = (node.child[k], near[k]);
                let mut j = sp;
                while j > base && stack[j - 1].1 < entry.1 {
                    stack[j] = stack[j - 1];
                    j -= 1;
                }
                stack[j] = entry;
                sp += 1;
            }
        }
        found.then_some(closest)
    }

    /// Any hit: `true` as soon as `hit(primitive, t_max)` reports a hit for a
    /// primitive of a leaf the ray may reach within `(t_min, t_max)`.
    #[inline]
    pub fn any<F>(&self, ray: &Ray, t_min: f32, t_max: f32, hit: F) -> bool
    where
        F: FnMut(u32, f32) -> bool,
    {
        if self.nodes.is_empty() || !enters_box(ray, &self.root_box, t_min, t_max) {
            return false;
        }
        if self.stack_need <= SMALL_STACK {
            self.any_with::<SMALL_STACK, F>(ray, t_min, t_max, hit)
        } else if self.stack_need <= MEDIUM_STACK {
            self.any_with::<MEDIUM_STACK, F>(ray, t_min, t_max, hit)
        } else {
            self.any_with::<STACK_DEPTH, F>(ray, t_min, t_max, hit)
        }
    }

    /// [`Self::any`] with a stack of `N >= self.stack_need` entries.
    #[inline]
    fn any_with<const N: usize, F>(&self, ray: &Ray, t_min: f32, t_max: f32, mut hit: F) -> bool
    where
        F: FnMut(u32, f32) -> bool,
    {
        let r = BoxRay::new(ray);
        let mut stack = [0u32; N];
        let mut sp = 1usize;
        stack[0] = 0;
        while sp > 0 {
            sp -= 1;
            let child = stack[sp];
            if child & LEAF != 0 {
                let first = ((child & !LEAF) >> 4) as usize;
                for &p in &self.order[first..first + (child & 15) as usize] {
                    if hit(p, t_max) {
                        return true;
                    }
                }
                continue;
            }
            let node = &self.nodes[child as usize];
            let (_, mut mask) = r.enter4(node, t_min, t_max);
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                stack[sp] = node.child[k];
                sp += 1;
            }
        }
        false
    }
}

impl Default for Bvh {
    fn default() -> Bvh {
        Bvh {
            nodes: Vec::new(),
            root_box: AxisAlignedBox { min: Vec3::ZERO, max: Vec3::ZERO },
            order: Vec::new(),
            stack_need: 0,
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
        // Every child box holds what is below it.
        fn check(bvh: &Bvh, boxes: &[AxisAlignedBox], node: usize) {
            let n = &bvh.nodes[node];
            assert!((1..=4).contains(&n.count));
            for k in 0..n.count as usize {
                let (lo, hi) =
                    (Vec3::new(n.min_x[k], n.min_y[k], n.min_z[k]), Vec3::new(n.max_x[k], n.max_y[k], n.max_z[k]));
                let child = n.child[k];
                if child & LEAF != 0 {
                    let first = ((child & !LEAF) >> 4) as usize;
                    for &p in &bvh.order[first..first + (child & 15) as usize] {
                        let b = &boxes[p as usize];
                        assert!(b.min.cmpge(lo).all() && b.max.cmple(hi).all());
                    }
                } else {
                    let c = &bvh.nodes[child as usize];
                    for j in 0..c.count as usize {
                        assert!(c.min_x[j] >= lo.x && c.min_y[j] >= lo.y && c.min_z[j] >= lo.z);
                        assert!(c.max_x[j] <= hi.x && c.max_y[j] <= hi.y && c.max_z[j] <= hi.z);
                    }
                    check(bvh, boxes, child as usize);
                }
            }
        }
        check(&bvh, &boxes, 0);
        // Deterministic: the same boxes give the same tree.
        let again = Bvh::build(&boxes);
        assert_eq!(again.order, bvh.order);
    }

    #[test]
    fn closest_and_any_agree_with_a_loop_over_all_boxes() {
        check_against_loop(3000, 9, 2000);
    }

    /// Trees of every stack size class (a lone box, a few, hundreds,
    /// thousands) traverse correctly with the stack their depth needs; a
    /// stack too small would panic on an index.
    #[test]
    fn each_stack_size_class_traverses_correctly() {
        let mut classes = Vec::new();
        for (n, rays) in [(1, 300), (2, 300), (5, 300), (40, 500), (600, 1000), (20_000, 300)] {
            let bvh = Bvh::build(&random_boxes(n, 5));
            assert_eq!(bvh.stack_need, 3 * inner_levels(&bvh.nodes) + 1);
            assert!(bvh.stack_need <= STACK_DEPTH);
            classes.push(if bvh.stack_need <= SMALL_STACK { 0 } else { 1 });
            check_against_loop(n, 5, rays);
        }
        // A lone box: one root node.
        assert_eq!(Bvh::build(&random_boxes(1, 5)).stack_need, 4);
        assert!(classes.contains(&0) && classes.contains(&1), "{classes:?}");
    }

    fn check_against_loop(n: usize, seed: u64, rays: usize) {
        let boxes = random_boxes(n, seed);
        let bvh = Bvh::build(&boxes);
        let mut s = PixelSampler::from_key(11);
        for _ in 0..rays {
            let o = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 14.0 - Vec3::splat(2.0);
            let d = (Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) - Vec3::splat(0.5)).normalize();
            let ray = Ray::new(o, d);
            let test = |p: u32, t_max: f32| {
                let (a, b) = boxes[p as usize].slab_range(&ray);
                let t = a.max(0.0);
                (a <= b && t < t_max && b > 0.0).then_some(t)
            };
            let brute = (0..n as u32).filter_map(|p| test(p, f32::INFINITY)).fold(f32::INFINITY, f32::min);
            let got = bvh.closest(&ray, 0.0, f32::INFINITY, test).unwrap_or(f32::INFINITY);
            assert_eq!(got, brute);
            assert_eq!(bvh.any(&ray, 0.0, f32::INFINITY, |p, t| test(p, t).is_some()), brute.is_finite());
        }
    }
}
