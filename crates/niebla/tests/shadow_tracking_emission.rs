//! `sample_t_maj_without_emission` (what `volpath`'s shadow rays track
//! with) draws the same tentative collisions as `sample_t_maj`, with the same
//! random numbers, coefficients and majorants, and only leaves out the
//! emission: so shadow rays' ratio tracking gives the same transmittance,
//! bit for bit, without the emission lookups.

use niebla::color::Rgb;
use niebla::math::{Ray, Vec3};
use niebla::sampling::PixelSampler;
use niebla::scene::{build_scene, parse_scene_str};
use niebla::tracking::{sample_t_maj, sample_t_maj_without_emission, MajorantCollision};

/// An emissive procedural cloud with chromatic extinction in the box
/// [-1, 1]^3 (a dense grid; emission proportional to the density).
const SCENE: &str = r#"{"version": 1,
    "camera": {"type": "perspective", "position": [0, 0, -3], "target": [0, 0, 0],
               "fov_y": 30, "width": 4, "height": 4},
    "render": {"integrator": {"type": "volpath"}, "spp": 1, "seed": 1},
    "media": {"fire": {"type": "grid",
        "density": {"type": "procedural", "shape": "cloud", "seed": 4, "resolution": 24},
        "sigma_t": [6, 9, 12], "albedo": 0.6,
        "emission": {"L_ve": [3, 1, 0.2]},
        "to_world": {"scale": 2, "translate": [-1, -1, -1]}}},
    "shapes": [{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "interior": "fire"}]}"#;

/// One collision's bits: `t`, `sigma_a`, `sigma_s`, `sigma_maj`, `t_maj`.
fn bits(c: &MajorantCollision) -> Vec<u32> {
    let rgb = |x: Rgb| (0..3).map(move |i| x[i].to_bits());
    std::iter::once(c.t.to_bits())
        .chain(rgb(c.point.sigma_a))
        .chain(rgb(c.point.sigma_s))
        .chain(rgb(c.sigma_maj))
        .chain(rgb(c.t_maj))
        .collect()
}

#[test]
fn shadow_tracking_sees_the_same_collisions_without_emission() {
    let desc = parse_scene_str(SCENE, "shadow_tracking_emission.json").unwrap();
    let built = build_scene(&desc, "shadow_tracking_emission.json", std::path::Path::new(".")).unwrap();
    let medium = &built.scene.media[0];
    let (mut collisions, mut emitting) = (0usize, 0usize);
    for i in 0..400u32 {
        // Rays from a sphere of radius 3 toward points inside the box.
        let mut s = PixelSampler::new(9, i, 0, 0);
        let (a, b, c) = (s.next_1d(), s.next_1d(), s.next_1d());
        let dir = Vec3::new(2.0 * a - 1.0, 2.0 * b - 1.0, 2.0 * c - 1.0).normalize_or(Vec3::Z);
        let target = Vec3::new(s.next_1d() - 0.5, s.next_1d() - 0.5, s.next_1d() - 0.5);
        let ray = Ray::new(target - dir * 3.0, dir);
        let hero = (i % 3) as usize;
        let run = |without: bool| {
            let mut sampler = PixelSampler::new(17, i, 1, 0);
            let mut seen: Vec<(Vec<u32>, Rgb)> = Vec::new();
            // Stop at about one collision in ten, as a tracker's roulette does.
            let mut callback = |c: MajorantCollision, sampler: &mut PixelSampler| {
                seen.push((bits(&c), c.point.l_ve));
                sampler.next_1d() > 0.1
            };
            let end = if without {
                sample_t_maj_without_emission(medium, &ray, 6.0, hero, &mut sampler, &mut callback)
            } else {
                sample_t_maj(medium, &ray, 6.0, hero, &mut sampler, &mut callback)
            };
            (seen, end.0.map(f32::to_bits))
        };
        let (with, end_with) = run(false);
        let (without, end_without) = run(true);
        assert_eq!(end_with, end_without, "ray {i}: majorant transmittance to the end");
        assert_eq!(with.len(), without.len(), "ray {i}: collision count");
        for (k, ((a, l_a), (b, l_b))) in with.iter().zip(&without).enumerate() {
            assert_eq!(a, b, "ray {i}, collision {k}");
            assert_eq!(*l_b, Rgb::ZERO, "ray {i}, collision {k}: emission left out");
            emitting += (!l_a.is_black()) as usize;
        }
        collisions += with.len();
    }
    // The emission the shadow path skips is there in the full version.
    assert!(collisions > 400 && emitting > collisions / 10, "{collisions} collisions, {emitting} emitting");
}
