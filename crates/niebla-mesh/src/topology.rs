//! Topology check for meshes that bound a medium: is the surface closed,
//! manifold and consistently oriented?

use std::collections::HashMap;

use crate::MeshData;

/// Edge counts of a triangle mesh after welding vertices at equal positions.
///
/// An *edge* is an unordered pair of welded vertices used by at least one
/// non-degenerate triangle. A mesh that bounds a volume (a closed, oriented
/// 2-manifold) has all three counts zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Closedness {
    /// Edges used by exactly one triangle (holes, open borders).
    pub boundary_edges: usize,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Edges used by exactly two triangles that traverse it in the same
    /// direction (one of the two is wound the wrong way).
    pub inconsistent_edges: usize,
    /// Degenerate triangles skipped by the check ([`MeshData::is_degenerate`]).
    pub degenerate_triangles: usize,
}

impl Closedness {
    /// Whether the mesh bounds a volume: no boundary, non-manifold or
    /// inconsistently oriented edge.
    pub fn is_closed(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.inconsistent_edges == 0
    }
}

/// Uses of one undirected edge `(lo, hi)`: how many triangles traverse it
/// from `lo` to `hi` and how many from `hi` to `lo`.
#[derive(Default, Clone, Copy)]
struct EdgeUses {
    forward: u32,
    backward: u32,
}

impl MeshData {
    /// Welded vertex ids: vertices at exactly the same position (`-0.0` and
    /// `0.0` equal) share the id of the first of them. OBJ and PLY files
    /// split vertices along uv seams and at normal creases; without welding
    /// a closed sphere with a seam would report open edges.
    pub fn welded_ids(&self) -> Vec<u32> {
        let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(self.positions.len());
        self.positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                // Adding +0.0 turns -0.0 into +0.0 and leaves everything else.
                let key = p.map(|c| (c + 0.0).to_bits());
                *first.entry(key).or_insert(i as u32)
            })
            .collect()
    }

    /// Counts boundary, non-manifold and inconsistently oriented edges after
    /// welding vertices by exact position ([`MeshData::welded_ids`]),
    /// ignoring degenerate triangles. A closed, consistently wound mesh
    /// (e.g. [`crate::icosphere`]) gives all zeros; removing one triangle
    /// gives 3 boundary edges; flipping one gives 3 inconsistent edges.
    pub fn closedness(&self) -> Closedness {
        let weld = self.welded_ids();
        let mut edges: HashMap<(u32, u32), EdgeUses> = HashMap::with_capacity(self.indices.len() * 3 / 2);
        let mut degenerate = 0;
        for (t, tri) in self.indices.iter().enumerate() {
            let w = tri.map(|i| weld[i as usize]);
            if self.is_degenerate(t) || w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
                degenerate += 1;
                continue;
            }
            for k in 0..3 {
                let (a, b) = (w[k], w[(k + 1) % 3]);
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                if a < b {
                    e.forward += 1;
                } else {
                    e.backward += 1;
                }
            }
        }
        let mut c = Closedness { degenerate_triangles: degenerate, ..Closedness::default() };
        for uses in edges.values() {
            match uses.forward + uses.backward {
                1 => c.boundary_edges += 1,
                2 if uses.forward != 1 => c.inconsistent_edges += 1,
                2 => {}
                _ => c.non_manifold_edges += 1,
            }
        }
        c
    }
}
