//! Sparse grids of 3-vectors (OpenVDB `Vec3SGrid` / `Vec3DGrid`: velocity,
//! color), stored as three [`SparseGrid`]s, one per component, with the same
//! leaves and internal nodes.
//!
//! Keeping one scalar grid per component reuses the scalar grid's storage,
//! lookup and statistics unchanged; a lookup walks the tree three times,
//! which is cheap next to the rendering work done per lookup.

use crate::{Affine, SparseGrid};

/// A sparse grid of 3-vectors in index space with an index-to-world map.
///
/// Component `c` of the value at voxel `ijk` is `component(c).value(ijk)`;
/// interpolation is trilinear per component (OpenVDB's `BoxSampler`).
#[derive(Clone, Debug)]
pub struct SparseVec3Grid {
    pub(crate) components: [SparseGrid; 3],
}

impl SparseVec3Grid {
    /// A grid from its three component grids; `None` unless they share
    /// their transform and their leaf layout (as grids read from one VDB
    /// vector grid do).
    pub fn from_components(components: [SparseGrid; 3]) -> Option<SparseVec3Grid> {
        let [x, y, z] = &components;
        let same = |g: &SparseGrid| {
            g.transform() == x.transform()
                && g.leaves.len() == x.leaves.len()
                && g.leaves.iter().zip(&x.leaves).all(|(a, b)| a.origin == b.origin && a.active == b.active)
        };
        (same(y) && same(z)).then_some(SparseVec3Grid { components })
    }

    /// The grid's name (from its file).
    pub fn name(&self) -> &str {
        self.components[0].name()
    }

    /// The OpenVDB map type of the transform.
    pub fn map_type(&self) -> &str {
        self.components[0].map_type()
    }

    /// The index-to-world map.
    pub fn transform(&self) -> &Affine {
        self.components[0].transform()
    }

    /// The scalar grid of component `c` (0 = x, 1 = y, 2 = z); panics for
    /// `c > 2`.
    pub fn component(&self, c: usize) -> &SparseGrid {
        &self.components[c]
    }

    /// The three component grids.
    pub fn into_components(self) -> [SparseGrid; 3] {
        self.components
    }

    /// The value where nothing is stored.
    pub fn background(&self) -> [f32; 3] {
        self.components.each_ref().map(|g| g.background())
    }

    /// The value of voxel `ijk`.
    pub fn value(&self, ijk: [i32; 3]) -> [f32; 3] {
        self.components.each_ref().map(|g| g.value(ijk))
    }

    /// The value and active state of voxel `ijk`.
    pub fn probe(&self, ijk: [i32; 3]) -> ([f32; 3], bool) {
        let (x, active) = self.components[0].probe(ijk);
        ([x, self.components[1].value(ijk), self.components[2].value(ijk)], active)
    }

    /// Trilinear interpolation of each component at index-space point `p`.
    pub fn lookup_index(&self, p: [f32; 3]) -> [f32; 3] {
        self.components.each_ref().map(|g| g.lookup_index(p))
    }

    /// Trilinear interpolation of each component at world-space point `p`.
    pub fn lookup_world(&self, p: [f32; 3]) -> [f32; 3] {
        self.lookup_index(self.components[0].world_to_index(p))
    }

    /// Number of active voxels (leaf voxels plus the volume of active tiles).
    pub fn active_voxel_count(&self) -> u64 {
        self.components[0].active_voxel_count()
    }

    /// Number of stored 8^3 leaves.
    pub fn leaf_count(&self) -> usize {
        self.components[0].leaf_count()
    }

    /// Inclusive index-space bounds of the active voxels, `None` if none.
    pub fn active_bounds_index(&self) -> Option<([i32; 3], [i32; 3])> {
        self.components[0].active_bounds_index()
    }

    /// Number of active tiles at tree depth 0, 1 and 2.
    pub fn active_tile_counts(&self) -> [usize; 3] {
        self.components[0].active_tile_counts()
    }

    /// World-space box outside which every component is its background
    /// (the union of the components' [`SparseGrid::world_bounds`]).
    pub fn world_bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let mut out: Option<([f32; 3], [f32; 3])> = None;
        for g in &self.components {
            if let Some((lo, hi)) = g.world_bounds() {
                out = Some(match out {
                    None => (lo, hi),
                    Some((a, b)) => {
                        (std::array::from_fn(|i| a[i].min(lo[i])), std::array::from_fn(|i| b[i].max(hi[i])))
                    }
                });
            }
        }
        out
    }

    /// Smallest and largest Euclidean length of the active values (voxels
    /// and active tiles), `None` if none is active.
    pub fn active_length_range(&self) -> Option<(f32, f32)> {
        let [x, y, z] = &self.components;
        let mut range: Option<(f32, f32)> = None;
        let mut add = |v: [f32; 3]| {
            let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            range = Some(match range {
                None => (len, len),
                Some((lo, hi)) => (lo.min(len), hi.max(len)),
            });
        };
        for (l, leaf) in x.leaves.iter().enumerate() {
            for n in 0..leaf.values.len() {
                if leaf.is_active(n) {
                    add([leaf.values[n], y.leaves[l].values[n], z.leaves[l].values[n]]);
                }
            }
        }
        for t in x.tiles.iter().filter(|t| t.active) {
            add([t.value, y.value(t.origin), z.value(t.origin)]);
        }
        range
    }
}
