//! Memory an integrator's precomputation will take on a scene, estimated
//! before it runs, so that a scene asking for an absurd photon count or
//! lattice resolution is refused with the field to lower instead of running
//! out of memory.

use super::photon::{photon_stream, trace_beams_with, trace_photons, Beam, Emitters, Photon, TraceSettings};
use super::{HegemanSettings, IntegratorSettings, ZhouSettings};
use crate::medium::Medium;
use crate::world::Scene;

/// Photons traced to measure how many get stored per emitted photon.
const PILOT_PHOTONS: u32 = 256;

/// Bytes per lattice node of the `zhou` model per SH coefficient: RGB f32
/// source coefficients, with room for the lighting pass's temporaries (the
/// measured peak was about 0.5 KiB per node at SH order 4, 16 coefficients).
const ZHOU_BYTES_PER_NODE_AND_COEFFICIENT: u64 = 3 * 4 * 3;

/// Bytes per lattice node of the `zhou` model besides its SH coefficients.
const ZHOU_BYTES_PER_NODE: u64 = 64;

/// An integrator's precomputed data on a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct PrecomputeMemory {
    /// Estimated peak bytes (an upper estimate).
    pub bytes: u64,
    /// The scene-file field (under `render.integrator`) that sets the size.
    pub field: &'static str,
    /// What takes the memory, in words.
    pub what: String,
}

/// Upper estimate of the memory the precomputation of `settings` takes on
/// `scene`: photon maps (`photon`: the whole map; `ppm`: one pass's map),
/// per-light lattices (`hegeman`) or the SH lattice (`zhou`). `None` for
/// integrators without precomputation. Photon counts are measured by tracing
/// a few hundred photons (stored photons per emitted one) and scaled.
///
/// ```
/// use niebla::integrator::{precompute_memory, HegemanSettings, IntegratorSettings};
/// use niebla::scene::{build_scene, parse_scene_str};
/// let text = r#"{"version": 1,
///     "camera": {"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 8, "height": 8},
///     "media": {"cloud": {"type": "grid", "sigma_t": 1, "albedo": 0.9,
///         "density": {"type": "procedural", "shape": "cloud", "resolution": 16}}},
///     "lights": [{"type": "point", "position": [0, 2, 0], "intensity": 1}]}"#;
/// let scene = build_scene(&parse_scene_str(text, "c.json").unwrap(), "c.json", ".".as_ref()).unwrap().scene;
/// let settings = IntegratorSettings::Hegeman(HegemanSettings { resolution: 512, ..Default::default() });
/// let m = precompute_memory(&settings, &scene).unwrap();
/// assert_eq!(m.field, "resolution");
/// assert!(m.bytes >= 512u64.pow(3) * 12);
/// ```
pub fn precompute_memory(settings: &IntegratorSettings, scene: &Scene) -> Option<PrecomputeMemory> {
    settings.precompute_memory(scene)
}

/// Grid media of `scene` (the interactive methods precompute per grid medium).
fn grid_media(scene: &Scene) -> u64 {
    scene.media.iter().filter(|m| matches!(m, Medium::Grid(_))).count() as u64
}

/// `hegeman`: one (D0, D1, D2) f32 lattice per light and grid medium, the
/// longest side `resolution` nodes.
pub(crate) fn hegeman_memory(h: &HegemanSettings, scene: &Scene) -> PrecomputeMemory {
    let grid_media = grid_media(scene);
    let nodes = (h.resolution as u64).pow(3);
    let lights = scene.lights.len().max(1) as u64;
    PrecomputeMemory {
        bytes: grid_media * lights * nodes * 12,
        field: "resolution",
        what: format!(
            "{lights} light volume(s) of up to {r}^3 nodes for each of {grid_media} grid medium(s)",
            r = h.resolution
        ),
    }
}

/// `zhou`: the SH lattice of each grid medium.
pub(crate) fn zhou_memory(z: &ZhouSettings, scene: &Scene) -> PrecomputeMemory {
    let grid_media = grid_media(scene);
    let nodes = (z.resolution as u64).pow(3);
    let coefficients = (z.sh_order as u64).pow(2);
    let per_node = coefficients * ZHOU_BYTES_PER_NODE_AND_COEFFICIENT + ZHOU_BYTES_PER_NODE;
    PrecomputeMemory {
        bytes: grid_media * nodes * per_node,
        field: "resolution",
        what: format!(
            "an SH lattice (order {}) of up to {r}^3 nodes for each of {grid_media} grid medium(s)",
            z.sh_order,
            r = z.resolution
        ),
    }
}

/// Stored photons (volume and surface maps) for `photons` emitted, scaled
/// from a pilot run; twice the photon size for the per-thread chunks
/// concatenated and the kd-tree's build.
pub(crate) fn photon_map_memory(scene: &Scene, photons: u32, max_depth: u32, what: &str) -> PrecomputeMemory {
    let pilot = PILOT_PHOTONS.min(photons.max(1));
    let traced = trace_photons(
        scene,
        &TraceSettings { photons: pilot as u64, max_depth, store_direct: false },
        photon_stream(0x5eed, 0),
    );
    let stored_per_photon = (traced.volume.len() + traced.surface.len()) as f64 / pilot as f64;
    let stored = (stored_per_photon * photons as f64).ceil();
    let bytes = stored * (2 * std::mem::size_of::<Photon>()) as f64;
    PrecomputeMemory {
        bytes: bytes.min(u64::MAX as f64) as u64,
        field: "photons",
        what: format!(
            "{what}: {photons} photons, about {stored_per_photon:.1} stored per photon (measured on {pilot})"
        ),
    }
}

/// `ppb`: one pass's beams and surface photons for `photons` emitted,
/// scaled from a pilot run; beams counted three times (the beams, the BVH's
/// pieces and nodes), photons twice.
pub(crate) fn beam_map_memory(scene: &Scene, photons: u32, max_depth: u32) -> PrecomputeMemory {
    let pilot = PILOT_PHOTONS.min(photons.max(1));
    let traced = trace_beams_with(
        scene,
        &Emitters::new(scene),
        &TraceSettings { photons: pilot as u64, max_depth, store_direct: false },
        photon_stream(0x5eed, 0),
    );
    let beams_per_photon = traced.beams.len() as f64 / pilot as f64;
    let surface_per_photon = traced.surface.len() as f64 / pilot as f64;
    let bytes = photons as f64
        * (beams_per_photon * (3 * std::mem::size_of::<Beam>()) as f64
            + surface_per_photon * (2 * std::mem::size_of::<Photon>()) as f64);
    PrecomputeMemory {
        bytes: bytes.min(u64::MAX as f64) as u64,
        field: "photons",
        what: format!(
            "each pass's beams: {photons} photons, about {beams_per_photon:.1} beams and {surface_per_photon:.1} \
             surface photons per photon (measured on {pilot})"
        ),
    }
}
