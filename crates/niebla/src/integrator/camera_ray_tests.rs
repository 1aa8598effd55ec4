//! Tests of the camera-ray walk: which medium segments it visits through a
//! known layout of boxes, and how it composes their radiance and
//! transmittance with the environment and opaque surfaces.

use super::*;
use crate::scene::{build_scene, parse_scene_str};

/// A scene of axis-aligned boxes along +z (camera at the origin looking +z,
/// in vacuum): `a` fills z in [2, 4]; `b` fills z in [6, 9] and holds `c`,
/// z in [7, 8] (whose exterior is therefore `b`); `extra_shapes` are
/// appended. A constant environment of radiance 1.
fn boxes_scene(extra_shapes: &str) -> Scene {
    let text = format!(
        r#"{{"version": 1,
        "camera": {{"type": "perspective", "position": [0, 0, 0], "target": [0, 0, 1], "width": 4, "height": 4}},
        "media": {{"a": {{"sigma_a": 1, "sigma_s": 0}}, "b": {{"sigma_a": 1, "sigma_s": 0}},
                  "c": {{"sigma_a": 1, "sigma_s": 0}}}},
        "shapes": [
            {{"type": "box", "min": [-1, -1, 2], "max": [1, 1, 4], "interior": "a"}},
            {{"type": "box", "min": [-1, -1, 6], "max": [1, 1, 9], "interior": "b"}},
            {{"type": "box", "min": [-0.5, -0.5, 7], "max": [0.5, 0.5, 8], "interior": "c"}}{extra_shapes}
        ],
        "lights": [{{"type": "constant", "radiance": 1}}]}}"#
    );
    let desc = parse_scene_str(&text, "boxes.json").unwrap();
    build_scene(&desc, "boxes.json", ".".as_ref()).unwrap().scene
}

/// Records each visited segment as (medium name, z of its start, z of its
/// end) and answers with a fixed radiance and transmittance; records opaque
/// surfaces as (z of the hit, medium of the side seen, `wo`).
#[derive(Default)]
struct Recorder {
    segments: Vec<(String, f32, f32)>,
    surfaces: Vec<(f32, Option<MediumId>, Vec3)>,
}

/// What every segment adds in the recorder: radiance 0.1, transmittance 0.5.
const SEGMENT: SegmentRadiance = SegmentRadiance { radiance: Rgb([0.1; 3]), transmittance: Rgb([0.5; 3]) };
/// What every opaque surface returns in the recorder.
const SURFACE_RADIANCE: f32 = 0.3;

impl CameraRayVisitor for Recorder {
    fn segment(
        &mut self,
        scene: &Scene,
        _m: &Medium,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        _sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        let name = scene.medium_names[id.0 as usize].clone();
        self.segments.push((name, ray.o.z, ray.at(t_end).z));
        SEGMENT
    }

    fn opaque_surface(
        &mut self,
        _scene: &Scene,
        hit: &Hit,
        wo: Vec3,
        medium: Option<MediumId>,
        _sampler: &mut PixelSampler,
    ) -> Rgb {
        self.surfaces.push((hit.surface.p.z, medium, wo));
        Rgb::splat(SURFACE_RADIANCE)
    }
}

/// Positions are f32 coordinates below 10 found by ray-box intersection: a
/// few ulps of 10 (about 1e-6 each).
const Z_TOLERANCE: f32 = 1e-5;

fn assert_segments(found: &[(String, f32, f32)], expected: &[(&str, f32, f32)]) {
    assert_eq!(found.len(), expected.len(), "segments {found:?}, expected {expected:?}");
    for ((name, z0, z1), (e_name, e0, e1)) in found.iter().zip(expected) {
        assert_eq!(name, e_name, "segments {found:?}");
        assert!(
            (z0 - e0).abs() < Z_TOLERANCE && (z1 - e1).abs() < Z_TOLERANCE,
            "segments {found:?}, expected {expected:?}"
        );
    }
}

#[test]
fn walk_crosses_index_matched_boxes_and_nested_media_in_order() {
    let scene = boxes_scene("");
    let mut recorder = Recorder::default();
    let mut sampler = PixelSampler::new(0, 0, 0, 0);
    let l = walk_camera_ray(&scene, Ray::new(Vec3::ZERO, Vec3::Z), None, &mut sampler, &mut recorder);

    // Vacuum gaps (z in [0, 2] and [4, 6]) are no segments; c splits b.
    assert_segments(&recorder.segments, &[("a", 2.0, 4.0), ("b", 6.0, 7.0), ("c", 7.0, 8.0), ("b", 8.0, 9.0)]);
    assert!(recorder.surfaces.is_empty());

    // L = sum_k 0.5^k 0.1 over the four segments + 0.5^4 L_env: 0.1875 + 0.0625.
    // Every factor is a power of two times 0.1, so the f32 result is within
    // a few ulps of 0.25.
    for c in 0..3 {
        assert!((l[c] - 0.25).abs() < 1e-6, "radiance {l:?}");
    }
}

#[test]
fn walk_stops_at_the_first_opaque_surface_and_shades_it_from_its_medium() {
    // An opaque diffuse box at z in [8.5, 8.75] inside b (it bounds no
    // medium): the walk ends there, seeing it from b.
    let wall = r#", {"type": "box", "min": [-1, -1, 8.5], "max": [1, 1, 8.75],
                  "bsdf": {"type": "diffuse", "reflectance": 0.5}}"#;
    let scene = boxes_scene(wall);
    let b = MediumId(scene.medium_names.iter().position(|n| n == "b").unwrap() as u32);
    let mut recorder = Recorder::default();
    let mut sampler = PixelSampler::new(0, 0, 0, 0);
    let l = walk_camera_ray(&scene, Ray::new(Vec3::ZERO, Vec3::Z), None, &mut sampler, &mut recorder);

    assert_segments(&recorder.segments, &[("a", 2.0, 4.0), ("b", 6.0, 7.0), ("c", 7.0, 8.0), ("b", 8.0, 8.5)]);
    assert_eq!(recorder.surfaces.len(), 1, "{:?}", recorder.surfaces);
    let (z, medium, wo) = recorder.surfaces[0];
    assert!((z - 8.5).abs() < Z_TOLERANCE, "hit at z = {z}");
    assert_eq!(medium, Some(b));
    assert_eq!(wo, -Vec3::Z);

    // 0.1875 from the segments + 0.5^4 * 0.3 from the wall; no environment.
    let expected = 0.1875 + 0.0625 * SURFACE_RADIANCE;
    for c in 0..3 {
        assert!((l[c] - expected).abs() < 1e-6, "radiance {l:?}, expected {expected}");
    }
}

#[test]
fn walk_from_inside_a_medium_starts_with_its_segment() {
    // A ray starting at z = 3 inside a: its first segment runs from the
    // origin to a's far face.
    let scene = boxes_scene("");
    let a = MediumId(scene.medium_names.iter().position(|n| n == "a").unwrap() as u32);
    let mut recorder = Recorder::default();
    let mut sampler = PixelSampler::new(0, 0, 0, 0);
    walk_camera_ray(&scene, Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::Z), Some(a), &mut sampler, &mut recorder);
    assert_segments(&recorder.segments, &[("a", 3.0, 4.0), ("b", 6.0, 7.0), ("c", 7.0, 8.0), ("b", 8.0, 9.0)]);
}
