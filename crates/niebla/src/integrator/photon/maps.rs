//! The photon maps of one pass: kd-trees over the volume and surface
//! photons, their gather radii, and the tracing bookkeeping.

use std::collections::BinaryHeap;

use super::emitters::Emitters;
use super::kdtree::PhotonTree;
use super::trace::{trace_photons_with, TraceSettings, TraceStats};
use super::{PhotonGather, PhotonSettings, VolumeQuery};
use crate::world::Scene;

/// Neighbours behind the automatic radius.
const AUTO_K: usize = 50;

/// Photons sampled to measure the automatic radius.
const AUTO_SAMPLES: usize = 256;

/// Volume and surface photon maps with the radii their estimates use.
#[derive(Clone, Debug, Default)]
pub struct PhotonMaps {
    /// Photons stored at real scattering events in media.
    pub volume: PhotonTree,
    /// Photons stored at diffuse surfaces.
    pub surface: PhotonTree,
    /// Bookkeeping of the tracing pass.
    pub stats: TraceStats,
}

impl PhotonMaps {
    /// Trace and build the maps of one pass (stream from
    /// [`super::photon_stream`]) from `emitters` on the current rayon pool.
    pub fn trace(scene: &Scene, emitters: &Emitters, settings: &PhotonSettings, stream: u64) -> PhotonMaps {
        let trace = TraceSettings {
            photons: settings.photons.max(1) as u64,
            max_depth: settings.max_depth,
            store_direct: settings.store_direct,
        };
        let traced = trace_photons_with(scene, emitters, &trace, stream);
        let (volume, surface) = rayon::join(|| PhotonTree::build(traced.volume), || PhotonTree::build(traced.surface));
        PhotonMaps { volume, surface, stats: traced.stats }
    }

    /// Give every volume photon the radius of its beam-query sphere: `radius`
    /// for fixed-radius gathering, else the distance to its k-th nearest
    /// neighbour in the same medium, capped at `radius` (Jarosz et al. 2008).
    pub fn set_beam_radii(&mut self, gather: PhotonGather, radius: f32) {
        use rayon::prelude::*;
        let radii: Vec<f32> = match gather {
            PhotonGather::Radius => vec![radius; self.volume.len()],
            PhotonGather::Nearest(k) => {
                let tree = &self.volume;
                tree.photons()
                    .par_iter()
                    .map_init(BinaryHeap::new, |heap, photon| {
                        let tag = photon.tag;
                        // The photon itself is among its nearest; k + 1 counts the others.
                        let r2 = tree.nearest(photon.p, k as usize + 1, radius * radius, |p| p.tag == tag, heap);
                        r2.sqrt().min(radius)
                    })
                    .collect()
            }
        };
        self.volume.set_radii(radii);
    }

    /// Prepare for `settings.query`: beam queries need photon radii.
    pub fn prepare(&mut self, settings: &PhotonSettings, volume_radius: f32) {
        if settings.query == VolumeQuery::Beam {
            self.set_beam_radii(settings.gather, volume_radius);
        }
    }
}

/// Median over up to 256 stored photons (evenly spaced in tree order) of the
/// distance to their 50th nearest neighbour with the same tag (medium); 0
/// for an empty map. A density-adapted default gather radius.
pub fn auto_radius(tree: &PhotonTree, same_tag: bool) -> f32 {
    let n = tree.len();
    if n == 0 {
        return 0.0;
    }
    let stride = n.div_ceil(AUTO_SAMPLES).max(1);
    let mut heap = BinaryHeap::new();
    let mut distances: Vec<f32> = tree
        .photons()
        .iter()
        .step_by(stride)
        .map(|photon| {
            let tag = photon.tag;
            let r2 = tree.nearest(photon.p, AUTO_K + 1, f32::INFINITY, |p| !same_tag || p.tag == tag, &mut heap);
            // Fewer neighbours than asked: the farthest one found.
            let r2 = if r2.is_finite() { r2 } else { heap.iter().map(|nb| nb.d2).fold(0.0, f32::max) };
            r2.sqrt()
        })
        .collect();
    distances.sort_by(f32::total_cmp);
    distances[distances.len() / 2]
}
