//! Walking a ray across index-matched boundaries (shapes with a `null`
//! BSDF, which only separate media): the one implementation used by paths
//! (`volpath`, photon tracing, the camera-ray walk) and by shadow rays
//! ([`Scene::transmittance`] and `volpath`'s next-event estimation).
//!
//! A crossing continues from the hit point itself, so no path length is lost,
//! and ignores hits closer than [`surface_epsilon`] of it; the medium after it
//! is [`Scene::medium_after_crossing`].

use std::ops::ControlFlow;

use crate::bsdf::Bsdf;
use crate::color::Rgb;
use crate::math::{Ray, Vec3};
use crate::medium::MediumId;

use super::{surface_epsilon, Hit, Scene, MAX_BOUNDARY_CROSSINGS};

/// Largest number of index-matched boundaries one path (all its segments
/// together) crosses before it is ended: paths bounce, so they get more
/// room than a single shadow ray's [`MAX_BOUNDARY_CROSSINGS`].
pub const MAX_PATH_BOUNDARY_CROSSINGS: u32 = MAX_BOUNDARY_CROSSINGS * 16;

/// Where a path is: its current ray, the medium around the ray's origin,
/// the smallest accepted hit parameter and the boundaries crossed so far.
#[derive(Clone, Copy, Debug)]
pub struct PathRay {
    /// The ray the path travels along.
    pub ray: Ray,
    /// The medium the ray starts in (`None`: vacuum).
    pub medium: Option<MediumId>,
    /// Smallest ray parameter of the next hit (`surface_epsilon` after a surface).
    pub t_min: f32,
    /// Index-matched boundaries crossed so far.
    pub crossings: u32,
}

impl PathRay {
    /// A path starting along `ray` in `medium`, accepting hits beyond
    /// `t_min`. Every ray the path continues along keeps `ray`'s time.
    #[inline]
    pub fn new(ray: Ray, medium: Option<MediumId>, t_min: f32) -> PathRay {
        PathRay { ray, medium, t_min, crossings: 0 }
    }

    /// The nearest surface hit ahead.
    #[inline]
    pub fn intersect(&self, scene: &Scene) -> Option<Hit> {
        scene.intersect(&self.ray, self.t_min, f32::INFINITY)
    }

    /// Cross the index-matched boundary `hit` straight on; `false` (and no
    /// change) once the path has crossed [`MAX_PATH_BOUNDARY_CROSSINGS`].
    #[inline]
    pub fn cross(&mut self, scene: &Scene, hit: &Hit) -> bool {
        self.crossings += 1;
        if self.crossings > MAX_PATH_BOUNDARY_CROSSINGS {
            return false;
        }
        self.medium = scene.medium_after_crossing(hit, self.ray.d, self.medium);
        self.ray = Ray::at_time(hit.surface.p, self.ray.d, self.ray.time);
        self.t_min = surface_epsilon(hit.surface.p);
        true
    }

    /// Leave surface `hit` toward unit `wi` (a sampled reflection or, when
    /// `transmitted`, a refraction into the medium on `wi`'s side). On a
    /// mesh that keeps its shading normal
    /// ([`crate::geometry::Shape::keeps_shading_normal`]) the medium is the
    /// one on `wi`'s geometric side whatever the lobe (Mitsuba 3's
    /// `target_medium`), since there a reflection may cross the triangle's
    /// plane and a transmission may stay on its side.
    #[inline]
    pub fn leave_surface(&mut self, scene: &Scene, hit: &Hit, wi: Vec3, transmitted: bool) {
        if transmitted || scene.object(hit).shape.keeps_shading_normal() {
            self.medium = scene.medium_after_crossing(hit, wi, self.medium);
        }
        self.ray = Ray::at_time(hit.surface.p, wi, self.ray.time);
        self.t_min = surface_epsilon(hit.surface.p);
    }

    /// Go on from a scattering point `p` inside the current medium toward unit `wi`.
    #[inline]
    pub fn scatter_in_medium(&mut self, p: Vec3, wi: Vec3) {
        self.ray = Ray::at_time(p, wi, self.ray.time);
        self.t_min = 0.0;
    }
}

/// One piece of a shadow ray between two surfaces, handed to the visitor of
/// [`walk_shadow_ray`].
#[derive(Clone, Copy, Debug)]
pub struct ShadowSegment<'a> {
    /// The medium the piece lies in.
    pub medium: Option<MediumId>,
    /// The ray of the piece; the piece is `[0, t_end)` of it.
    pub ray: &'a Ray,
    /// End of the piece (ray parameter).
    pub t_end: f32,
    /// The thin dielectric pane the piece ends at, which the ray passes
    /// (`None` at an index-matched boundary or the ray's end). Every visitor
    /// must apply its weight.
    pub pane: Option<PaneCrossing>,
}

/// A thin dielectric pane crossed by a shadow ray (Mitsuba 3's
/// `thindielectric`: its straight-through transmission is a null lobe).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaneCrossing {
    /// Probability `1 - R'` with which a path sampling the pane passes it
    /// (`R' = 2R / (1 + R)`, the sheet's reflectance at the ray's incidence).
    pub pass_probability: f32,
    /// Factor on the light carried through: `specular_transmittance * (1 - R')`.
    pub weight: Rgb,
}

/// Walk the shadow ray from `p` (inside `medium`) along unit `wi` over
/// `distance` (may be infinite), crossing index-matched boundaries and thin
/// dielectric panes, and hand each piece to `visit` in order (a piece ending
/// at a pane carries the pane's [`PaneCrossing`]). An opaque surface blocks
/// the ray unless it is object `ignore` (the sampled light's own surface,
/// where the ray ends): an any-hit query over the opaque surfaces first, so
/// a blocked ray visits nothing, then nearest hits among the crossed
/// surfaces alone. Moving shapes are in their pose at `time` (frames).
/// Returns `true` when the ray reached its end, `false` when it was blocked,
/// `visit` stopped it or it crossed more than [`MAX_BOUNDARY_CROSSINGS`]
/// boundaries.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn walk_shadow_ray<F>(
    scene: &Scene,
    p: Vec3,
    time: f32,
    mut medium: Option<MediumId>,
    wi: Vec3,
    distance: f32,
    ignore: Option<u32>,
    mut visit: F,
) -> bool
where
    F: FnMut(ShadowSegment) -> ControlFlow<()>,
{
    let mut ray = Ray::at_time(p, wi, time);
    if scene.occluded(&ray, 0.0, distance, ignore) {
        return false;
    }
    let mut remaining = distance;
    let mut t_min = 0.0;
    let only_boundary = scene.trees().boundaries.single();
    for _ in 0..MAX_BOUNDARY_CROSSINGS {
        let hit = scene.intersect_boundaries(&ray, t_min, remaining);
        let t_end = hit.map_or(remaining, |h| h.surface.t);
        let pane = hit.and_then(|h| match scene.object(&h).bsdf {
            Bsdf::ThinDielectric(pane) => {
                let cos = h.surface.shading_normal(-wi).dot(wi);
                let pass_probability = pane.pass_probability(cos);
                Some(PaneCrossing { pass_probability, weight: pane.specular_transmittance * pass_probability })
            }
            _ => None,
        });
        if visit(ShadowSegment { medium, ray: &ray, t_end, pane }).is_break() {
            return false;
        }
        let Some(hit) = hit else {
            return true;
        };
        medium = scene.medium_after_crossing(&hit, wi, medium);
        remaining -= hit.surface.t;
        ray = Ray::at_time(hit.surface.p, wi, time);
        t_min = surface_epsilon(hit.surface.p);
        if remaining <= t_min {
            return true;
        }
        // The scene's only crossed surface, left for good (out of a convex
        // medium boundary, e.g. a slab's box): nothing more to cross, the
        // last piece runs to the end in the medium outside.
        if only_boundary == Some(hit.object) && scene.object(&hit).shape.is_left_for_good(hit.surface.n, wi) {
            return visit(ShadowSegment { medium, ray: &ray, t_end: remaining, pane: None }).is_continue();
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::PixelSampler;
    use crate::scene::{build_scene, parse_scene_str};
    use crate::tracking::TransmittanceMethod;

    /// Two nested index-matched boxes along +x from the origin (`inner` to
    /// x = 1, `outer` to x = 2, vacuum beyond), a grey diffuse wall at x = 3.
    fn nested_boxes() -> Scene {
        let json = r#"{
          "version": 1,
          "camera": {"type": "perspective", "position": [0, 0, 10], "target": [0, 0, 0], "fov_y": 40,
                     "width": 4, "height": 4},
          "media": {
            "inner": {"type": "homogeneous", "sigma_a": 0.5, "sigma_s": 0.0},
            "outer": {"type": "homogeneous", "sigma_a": 0.25, "sigma_s": 0.0}
          },
          "shapes": [
            {"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "interior": "inner", "bsdf": {"type": "null"}},
            {"type": "box", "min": [-2, -2, -2], "max": [2, 2, 2], "interior": "outer", "bsdf": {"type": "null"}},
            {"type": "rectangle", "to_world": {"rotate_y": -90, "translate": [3, 0, 0]},
             "bsdf": {"type": "diffuse", "reflectance": 0.5}}
          ]
        }"#;
        let desc = parse_scene_str(json, "<test>").unwrap();
        build_scene(&desc, "<test>", std::path::Path::new(".")).unwrap().scene
    }

    #[test]
    fn shadow_walk_visits_each_medium_piece_and_stops_at_blockers() {
        let scene = nested_boxes();
        let start = scene.medium_at(Vec3::ZERO);
        assert!(start.is_some());
        let mut pieces = Vec::new();
        let reached = walk_shadow_ray(&scene, Vec3::ZERO, 0.0, start, Vec3::X, 2.5, None, |s| {
            pieces.push((s.medium, s.ray.o.x, s.t_end));
            ControlFlow::Continue(())
        });
        // Two boundaries crossed, three pieces: [0, 1] inner, [1, 2] outer, [2, 2.5] vacuum.
        assert!(reached);
        assert_eq!(pieces.len(), 3);
        let (inner, outer) = (pieces[0].0, pieces[1].0);
        assert!(inner.is_some() && outer.is_some() && inner != outer);
        assert_eq!(pieces[2].0, None);
        for (k, &(o, t_end)) in [(0.0, 1.0), (1.0, 1.0), (2.0, 0.5)].iter().enumerate() {
            // Origins are hit points: box faces are exact in f32; a tolerance for the ray-box slab test.
            assert!((pieces[k].1 - o).abs() < 1e-5 && (pieces[k].2 - t_end).abs() < 1e-5, "{pieces:?}");
        }

        // Past the wall at x = 3: blocked before any piece is visited (the
        // any-hit query over opaque surfaces comes first), unless the wall is
        // the ignored object (the light's own surface).
        let mut visited = 0;
        assert!(!walk_shadow_ray(&scene, Vec3::ZERO, 0.0, start, Vec3::X, 10.0, None, |_| {
            visited += 1;
            ControlFlow::Continue(())
        }));
        assert_eq!(visited, 0);
        assert!(walk_shadow_ray(&scene, Vec3::ZERO, 0.0, start, Vec3::X, 10.0, Some(2), |_| ControlFlow::Continue(())));

        // Scene::transmittance over the walk: exp(-(0.5 * 1 + 0.25 * 1)).
        let mut s = PixelSampler::from_key(1);
        let tr = scene.transmittance(Vec3::ZERO, start, Vec3::X, 2.5, TransmittanceMethod::Analytic, &mut s);
        assert!((tr[0] - (-0.75f32).exp()).abs() < 1e-5, "{tr:?}");
    }

    /// A scene whose only crossed surface is one box: the walk stops
    /// querying once the ray has left the box (it cannot meet it again), and
    /// its pieces are those of the general walk: inside, then outside to the end.
    #[test]
    fn shadow_walk_out_of_a_lone_box_ends_after_leaving_it() {
        let json = r#"{
          "version": 1,
          "camera": {"type": "perspective", "position": [0, 0, 10], "target": [0, 0, 0], "fov_y": 40,
                     "width": 4, "height": 4},
          "media": {"slab": {"type": "homogeneous", "sigma_a": 0.5, "sigma_s": 0.0}},
          "shapes": [{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "interior": "slab", "bsdf": {"type": "null"}}]
        }"#;
        let desc = parse_scene_str(json, "<test>").unwrap();
        let scene = build_scene(&desc, "<test>", std::path::Path::new(".")).unwrap().scene;
        assert!(scene.trees().boundaries.single().is_some());
        let inside = scene.medium_at(Vec3::ZERO);
        assert!(inside.is_some());
        for (from, medium, distance, expected) in [
            // From inside, to infinity: [0, 1] inside, [1, inf) outside.
            (Vec3::ZERO, inside, f32::INFINITY, vec![(inside, 0.0, 1.0), (None, 1.0, f32::INFINITY)]),
            // From outside, through the box: [-3, -1] outside, [-1, 1] inside, [1, 4] outside.
            (Vec3::new(-3.0, 0.0, 0.0), None, 7.0, vec![(None, -3.0, 2.0), (inside, -1.0, 2.0), (None, 1.0, 3.0)]),
        ] {
            let mut pieces = Vec::new();
            assert!(walk_shadow_ray(&scene, from, 0.0, medium, Vec3::X, distance, None, |s| {
                pieces.push((s.medium, s.ray.o.x, s.t_end));
                ControlFlow::Continue(())
            }));
            assert_eq!(pieces.len(), expected.len(), "{pieces:?}");
            for (got, want) in pieces.iter().zip(&expected) {
                assert_eq!(got.0, want.0, "{pieces:?}");
                assert!((got.1 - want.1).abs() < 1e-5, "{pieces:?}");
                assert!(got.2 == want.2 || (got.2 - want.2).abs() < 1e-5, "{pieces:?}");
            }
        }
    }

    #[test]
    fn shadow_rays_pass_thin_panes_weighted_by_their_transmittance() {
        // A thin pane (index 1.5 in vacuum, transmission multiplier 0.5) at x = 1.
        let json = r#"{
          "version": 1,
          "camera": {"type": "perspective", "position": [0, 0, 10], "target": [0, 0, 0], "fov_y": 40,
                     "width": 4, "height": 4},
          "shapes": [
            {"type": "rectangle", "to_world": {"rotate_y": -90, "translate": [1, 0, 0]},
             "bsdf": {"type": "thindielectric", "int_ior": 1.5, "ext_ior": 1.0, "specular_transmittance": 0.5}}
          ]
        }"#;
        let desc = parse_scene_str(json, "<test>").unwrap();
        let scene = build_scene(&desc, "<test>", std::path::Path::new(".")).unwrap().scene;
        assert!(!scene.occluded(&Ray::new(Vec3::ZERO, Vec3::X), 0.0, 2.0, None));
        // Normal incidence: R = ((1.5 - 1) / 2.5)^2 = 0.04, the sheet's R' = 2R / (1 + R).
        let r = 0.08 / 1.04;
        let mut panes = Vec::new();
        assert!(walk_shadow_ray(&scene, Vec3::ZERO, 0.0, None, Vec3::X, 2.0, None, |s| {
            panes.push(s.pane);
            ControlFlow::Continue(())
        }));
        assert_eq!(panes.len(), 2);
        let pane = panes[0].expect("the first piece ends at the pane");
        assert!(panes[1].is_none());
        assert!((pane.pass_probability - (1.0 - r)).abs() < 1e-6, "{pane:?}");
        assert!((pane.weight[0] - 0.5 * (1.0 - r)).abs() < 1e-6, "{pane:?}");
        let mut s = PixelSampler::from_key(1);
        let tr = scene.transmittance(Vec3::ZERO, None, Vec3::X, 2.0, TransmittanceMethod::Analytic, &mut s);
        assert!((tr[1] - 0.5 * (1.0 - r)).abs() < 1e-6, "{tr:?}");
        // Short of the pane nothing is crossed.
        let tr = scene.transmittance(Vec3::ZERO, None, Vec3::X, 0.5, TransmittanceMethod::Analytic, &mut s);
        assert_eq!(tr, Rgb::ONE);
    }

    #[test]
    fn path_ray_counts_crossings_and_tracks_the_medium() {
        let scene = nested_boxes();
        let start = scene.medium_at(Vec3::ZERO);
        let mut path = PathRay::new(Ray::new(Vec3::ZERO, Vec3::X), start, 0.0);
        let mut media = vec![path.medium];
        let wall = loop {
            let hit = path.intersect(&scene).unwrap();
            if !scene.object(&hit).bsdf.is_null() {
                break hit;
            }
            assert!(path.cross(&scene, &hit));
            media.push(path.medium);
        };
        assert_eq!(path.crossings, 2);
        assert_eq!(media.len(), 3);
        assert_eq!(media[2], None);
        assert!((wall.surface.p.x - 3.0).abs() < 1e-5);
        // Leaving the wall by reflection keeps the medium and starts past epsilon.
        path.leave_surface(&scene, &wall, -Vec3::X, false);
        assert_eq!(path.medium, None);
        assert_eq!(path.t_min, surface_epsilon(wall.surface.p));
        // The limit: a path that has used up its crossings is refused one more.
        let hit = path.intersect(&scene).unwrap();
        path.crossings = MAX_PATH_BOUNDARY_CROSSINGS;
        assert!(!path.cross(&scene, &hit));
        assert_eq!(path.medium, None);
    }

    /// A glass triangle in z = 0 (geometric normal +z) with medium `fog`
    /// behind it and vertex normals tilted 60 degrees toward +y, under the
    /// given `"shading_normal_backside"` rule.
    fn tilted_glass(rule: &str) -> Scene {
        let json = format!(
            r#"{{
          "version": 1,
          "camera": {{"type": "perspective", "position": [0, 0, 10], "target": [0, 0, 0], "fov_y": 40,
                     "width": 4, "height": 4}},
          "media": {{"fog": {{"type": "homogeneous", "sigma_a": 0.5, "sigma_s": 0.0}}}},
          "shapes": [{{"type": "mesh", "positions": [[-4, -4, 0], [4, -4, 0], [0, 4, 0]], "indices": [[0, 1, 2]],
             "normals": [[0, 0.866025, 0.5], [0, 0.866025, 0.5], [0, 0.866025, 0.5]],
             "interior": "fog", "allow_open": true, "shading_normal_backside": "{rule}",
             "bsdf": {{"type": "dielectric", "int_ior": 1.5}}}}]
        }}"#
        );
        let desc = parse_scene_str(&json, "<test>").unwrap();
        build_scene(&desc, "<test>", std::path::Path::new(".")).unwrap().scene
    }

    /// Mitsuba 3's rule: a direction sampled about the shading normal goes
    /// on even where it crosses the triangle's plane against its lobe, and
    /// the medium after the surface is the one on its geometric side; the
    /// default rule refuses such a direction and keeps the medium of a
    /// reflection.
    #[test]
    fn mitsubas_rule_follows_the_geometric_side_after_a_surface() {
        let fog = Some(crate::medium::MediumId(0));
        // From inside (below z = 0), a "reflection" about the tilted normal
        // that leaves through the plane: below ns, above n.
        let wi = Vec3::new(0.0, -0.9, 0.3).normalize();
        for (rule, continues, medium) in [("mitsuba", true, None), ("geometric", false, fog)] {
            let scene = tilted_glass(rule);
            let mut path = PathRay::new(Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z), fog, 0.0);
            let hit = path.intersect(&scene).unwrap();
            let ns = hit.surface.shading_normal(-path.ray.d);
            assert!(wi.dot(ns) < 0.0 && wi.dot(hit.surface.n) > 0.0);
            assert_eq!(scene.path_continues(&hit, ns, wi), continues, "{rule}");
            path.leave_surface(&scene, &hit, wi, false);
            assert_eq!(path.medium, medium, "{rule}");
            // A transmission about ns that stays below the plane stays in the fog.
            let mut path = PathRay::new(Ray::new(Vec3::new(0.0, 0.0, -1.0), Vec3::Z), fog, 0.0);
            path.leave_surface(&scene, &hit, Vec3::new(0.0, 0.9, -0.3).normalize(), true);
            assert_eq!(path.medium, fog, "{rule}");
        }
    }
}
