//! The microfacet and layered surfaces (`roughconductor`, `roughdielectric`,
//! `thindielectric`, `plastic`, `roughplastic`, `twosided`) against Mitsuba 3's own values,
//! their samplers against their densities (chi-square), reciprocity, and
//! energy conservation.

use niebla::bsdf::{Bsdf, TransportMode};
use niebla::math::Vec3;
use niebla::sampling::{PixelSampler, SamplerKind};
use niebla::scene::{build_scene, parse_scene_str};

/// The BSDF a scene file's `bsdf` object describes (on a unit sphere).
fn bsdf_from_json(bsdf: &str) -> Bsdf {
    let text = format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 4, "height": 4}},
            "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "bsdf": {bsdf}}}]}}"#
    );
    let desc = parse_scene_str(&text, "t.json").unwrap_or_else(|e| panic!("{bsdf}: {e}"));
    build_scene(&desc, "t.json", std::path::Path::new(".")).unwrap().scene.objects[0].bsdf
}

fn vec3(v: &serde_json::Value) -> Vec3 {
    let a: Vec<f32> = v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
    Vec3::new(a[0], a[1], a[2])
}

/// Mitsuba 3.9.1's `eval` and `pdf` (scalar_rgb) at fixed local directions,
/// from scripts/mitsuba_bsdf_values.py: 864 rows over 16 BSDFs (rough
/// conductors and dielectrics with both distributions, isotropic and
/// anisotropic, several indices; plastics; rough plastics with both
/// distributions, alpha 0.05 to 0.5, nonlinear, tinted specular, another
/// outside index), 6 incident and 9 outgoing
/// directions on both sides. Mitsuba's `eval` includes |cos(wo)|; niebla's
/// `f` does not. Tolerance: relative 2e-4 plus 2e-6 absolute; both
/// renderers compute the same f32 formulas, and the largest relative
/// difference seen is about 1e-5 (values up to ~100 near the specular
/// peak of alpha = 0.1 lose more digits to the exponential).
#[test]
fn eval_and_pdf_match_mitsuba() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/mitsuba_bsdf_values.txt");
    let text = std::fs::read_to_string(path).unwrap();
    let mut rows = 0;
    let mut cache: Vec<(String, Bsdf)> = Vec::new();
    let mut worst = 0.0f64;
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let row: serde_json::Value = serde_json::from_str(line).unwrap();
        let key = row["bsdf"].to_string();
        let bsdf = match cache.iter().find(|(k, _)| *k == key) {
            Some((_, b)) => *b,
            None => {
                let b = bsdf_from_json(&key);
                cache.push((key.clone(), b));
                b
            }
        };
        // Mitsuba's wi (toward the camera) is niebla's wo.
        let (wo, wi) = (vec3(&row["wi"]), vec3(&row["wo"]));
        let f = bsdf.eval(Vec3::Z, wo, wi) * wi.z.abs();
        let pdf = bsdf.pdf(Vec3::Z, wo, wi);
        let expected = vec3(&row["eval"]);
        let expected_pdf = row["pdf"].as_f64().unwrap() as f32;
        let close = |a: f32, b: f32| (a - b).abs() <= 2e-4 * a.abs().max(b.abs()) + 2e-6;
        for c in 0..3 {
            assert!(
                close(f[c], expected[c]),
                "{key} wo {wo} wi {wi} channel {c}: niebla {} vs Mitsuba {}",
                f[c],
                expected[c]
            );
            if expected[c] > 1e-3 {
                worst = worst.max(((f[c] - expected[c]) / expected[c]).abs() as f64);
            }
        }
        assert!(close(pdf, expected_pdf), "{key} wo {wo} wi {wi}: pdf niebla {pdf} vs Mitsuba {expected_pdf}");
        rows += 1;
    }
    assert_eq!(rows, 864);
    eprintln!("largest relative difference of eval: {worst:.2e}");
}

/// Mitsuba 3.9.1's `eval` and `pdf` of anisotropic BSDFs (rough conductors
/// and dielectrics with both distributions, a `twosided` rough conductor)
/// in a shading frame built from a tilted normal and a `dp_du` neither unit
/// nor orthogonal to it (Mitsuba's `initialize_sh_frame`), at world
/// directions, from `scripts/mitsuba_bsdf_values.py --frames`: 540 rows,
/// 2 frames x 54 direction pairs x 5 BSDFs. niebla gets the world normal,
/// the world directions and `dp_du` as the tangent (`Bsdf::with_tangent`).
/// Tolerance as in `eval_and_pdf_match_mitsuba` (relative 2e-4 plus 2e-6),
/// with 1e-4 more for the two frames' f32 rounding; the old frame
/// (`Frame::from_z`) misses these values by far more (checked below: more
/// than 10% on some rows of every BSDF).
#[test]
fn eval_and_pdf_match_mitsuba_in_a_dpdu_frame() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/mitsuba_bsdf_frames.txt");
    let text = std::fs::read_to_string(path).unwrap();
    let mut rows = 0;
    let mut worst = 0.0f64;
    let mut old_frame_off: std::collections::BTreeMap<String, f32> = Default::default();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let row: serde_json::Value = serde_json::from_str(line).unwrap();
        let key = row["bsdf"].to_string();
        let plain = bsdf_from_json(&key);
        assert!(plain.is_anisotropic(), "{key}");
        let bsdf = plain.with_tangent(vec3(&row["dp_du"]));
        let n = vec3(&row["n"]).normalize();
        let (wo, wi) = (vec3(&row["wi"]), vec3(&row["wo"]));
        let f = bsdf.eval(n, wo, wi) * wi.dot(n).abs();
        let pdf = bsdf.pdf(n, wo, wi);
        let expected = vec3(&row["eval"]);
        let expected_pdf = row["pdf"].as_f64().unwrap() as f32;
        let close = |a: f32, b: f32| (a - b).abs() <= 3e-4 * a.abs().max(b.abs()) + 2e-6;
        for c in 0..3 {
            assert!(
                close(f[c], expected[c]),
                "{key} n {n} wo {wo} wi {wi} channel {c}: niebla {} vs Mitsuba {}",
                f[c],
                expected[c]
            );
            if expected[c] > 1e-3 {
                worst = worst.max(((f[c] - expected[c]) / expected[c]).abs() as f64);
            }
        }
        assert!(close(pdf, expected_pdf), "{key} n {n} wo {wo} wi {wi}: pdf niebla {pdf} vs Mitsuba {expected_pdf}");
        let old = plain.eval(n, wo, wi).g() * wi.dot(n).abs();
        if expected.y > 1e-3 {
            let off = old_frame_off.entry(key).or_default();
            *off = off.max(((old - expected.y) / expected.y).abs());
        }
        rows += 1;
    }
    assert_eq!(rows, 540);
    assert_eq!(old_frame_off.len(), 5);
    for (key, off) in &old_frame_off {
        assert!(*off > 0.1, "{key}: the normal-only frame is within {off} of Mitsuba's dp/du frame");
    }
    eprintln!("largest relative difference of eval: {worst:.2e}; normal-only frame: {old_frame_off:?}");
}

/// Sampling turns with the tangent too: in a dp/du frame, every sample's
/// `f` and `pdf` are `eval` and `pdf` at the sampled direction (relative
/// 1e-3: the same f32 formulas along two paths), and the samples' mean
/// local azimuth of the half vector follows the tangent (the `alpha_u = 0.05,
/// alpha_v = 0.4` lobe spreads along the bitangent: mean |h.y| > 2 mean |h.x|).
#[test]
fn sampling_follows_the_tangent() {
    let plain = bsdf_from_json(r#"{"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.05, "alpha_v": 0.4}"#);
    let n = Vec3::new(0.3, -0.5, 0.8).normalize();
    let t = Vec3::new(1.0, 0.4, -0.7);
    let bsdf = plain.with_tangent(t);
    let frame = niebla::math::Frame::from_normal_tangent(n, t);
    let wo = frame.to_world(Vec3::new(0.3, 0.2, 0.9).normalize());
    let (mut hx, mut hy, mut count) = (0.0f64, 0.0f64, 0);
    for i in 0..64 {
        for j in 0..64 {
            let u = niebla::math::Vec2::new((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0);
            let Some(s) = bsdf.sample(n, wo, 0.5, u) else { continue };
            let (f, pdf) = (bsdf.eval(n, wo, s.wi), bsdf.pdf(n, wo, s.wi));
            assert!((s.pdf - pdf).abs() <= 1e-3 * pdf.max(s.pdf), "pdf {} vs {pdf}", s.pdf);
            assert!((s.f.g() - f.g()).abs() <= 1e-3 * f.g().max(s.f.g()) + 1e-6, "f {} vs {}", s.f.g(), f.g());
            let h = frame.to_local((wo + s.wi).normalize());
            hx += h.x.abs() as f64;
            hy += h.y.abs() as f64;
            count += 1;
        }
    }
    assert!(count > 3000, "{count} samples");
    assert!(hy > 2.0 * hx, "mean |h.x| {} |h.y| {}", hx / count as f64, hy / count as f64);
}

/// The models under test, built from scene-file objects, with the
/// incident angles (degrees from the normal; above 90: from inside/behind).
fn models() -> Vec<(&'static str, Bsdf)> {
    [
        r#"{"type": "roughconductor", "distribution": "beckmann", "alpha": 0.2, "material": "Au"}"#,
        r#"{"type": "roughconductor", "distribution": "ggx", "alpha": 0.5, "material": "Cu"}"#,
        r#"{"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.15, "alpha_v": 0.6}"#,
        r#"{"type": "roughconductor", "distribution": "beckmann", "alpha_u": 0.7, "alpha_v": 0.25}"#,
        r#"{"type": "roughdielectric", "distribution": "beckmann", "alpha": 0.25, "int_ior": 1.5, "ext_ior": 1}"#,
        r#"{"type": "roughdielectric", "distribution": "ggx", "alpha": 0.6, "int_ior": 1.33, "ext_ior": 1}"#,
        r#"{"type": "roughdielectric", "distribution": "ggx", "alpha_u": 0.2, "alpha_v": 0.5}"#,
        r#"{"type": "plastic", "diffuse_reflectance": [0.8, 0.4, 0.1]}"#,
        r#"{"type": "plastic", "diffuse_reflectance": 0.9, "int_ior": 1.8, "nonlinear": true}"#,
        r#"{"type": "twosided", "bsdf": {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3}}"#,
        r#"{"type": "twosided", "bsdf": [{"type": "diffuse", "reflectance": 0.7}, {"type": "plastic"}]}"#,
        r#"{"type": "roughplastic", "distribution": "beckmann", "alpha": 0.2, "diffuse_reflectance": [0.8, 0.4, 0.1]}"#,
        r#"{"type": "roughplastic", "distribution": "ggx", "alpha": 0.6, "diffuse_reflectance": 0.9, "int_ior": 1.8,
            "nonlinear": true}"#,
        r#"{"type": "twosided", "bsdf": {"type": "roughplastic", "distribution": "ggx", "alpha": 0.1}}"#,
    ]
    .into_iter()
    .map(|j| (j, bsdf_from_json(j)))
    .chain(textured_alpha_models())
    .collect()
}

/// A unit sphere at the origin whose `bsdf` has checkerboard roughnesses
/// (four cells over the unit uv square), and the model at its surface
/// point of polar angle `theta` and azimuth `phi` (degrees), found by a ray
/// toward it (from outside: a `twosided`'s front) and
/// `Scene::surface_bsdf`, with the parity of that point's cell: the
/// sphere's uv (`u` the azimuth over 360 degrees, `v` the polar angle over
/// 180) computed here, not by the renderer.
fn textured_alpha_at(bsdf: &str, theta: f32, phi: f32) -> (Bsdf, bool) {
    let text = format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 4, "height": 4}},
            "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "bsdf": {bsdf}}}]}}"#
    );
    let desc = parse_scene_str(&text, "t.json").unwrap_or_else(|e| panic!("{bsdf}: {e}"));
    let scene = build_scene(&desc, "t.json", std::path::Path::new(".")).unwrap().scene;
    let (t, p) = (theta.to_radians(), phi.to_radians());
    let point = Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
    let ray = niebla::math::Ray::new(point * 3.0, -point);
    let hit = scene.intersect(&ray, 0.0, f32::INFINITY).expect("the ray hits the sphere");
    let (u, v) = (phi / 360.0, theta / 180.0);
    let odd = ((2.0 * u).floor() as i64 + (2.0 * v).floor() as i64).rem_euclid(2) == 1;
    (scene.surface_bsdf(&hit), odd)
}

/// A roughness in a template of [`textured_alpha_cases`]: one of two
/// checkerboards or a constant.
#[derive(Clone, Copy)]
enum Rough {
    /// 0.3 on cells of even parity, 0.55 on odd ones.
    CheckerA,
    /// 0.45 on even cells, 0.15 on odd ones.
    CheckerB,
    /// A constant.
    Const(f32),
}

impl Rough {
    /// As written in the textured scene file.
    fn textured(self) -> String {
        match self {
            Rough::CheckerA => r#"{"type": "checkerboard", "color0": 0.3, "color1": 0.55}"#.into(),
            Rough::CheckerB => r#"{"type": "checkerboard", "color0": 0.45, "color1": 0.15}"#.into(),
            Rough::Const(a) => format!("{a}"),
        }
    }

    /// The constant the point's cell should give.
    fn at(self, odd: bool) -> f32 {
        match (self, odd) {
            (Rough::CheckerA, false) => 0.3,
            (Rough::CheckerA, true) => 0.55,
            (Rough::CheckerB, false) => 0.45,
            (Rough::CheckerB, true) => 0.15,
            (Rough::Const(a), _) => a,
        }
    }
}

/// The textured-roughness cases: a name, a `bsdf` template whose `$0`,
/// `$1`, `$2` stand for the roughnesses, those roughnesses, and the point
/// (theta, phi in degrees). Isotropic `alpha` on a rough conductor and
/// dielectric, anisotropic pairs (one or both textured), and `twosided`
/// with its two sides textured differently and with one child.
#[allow(clippy::type_complexity)]
fn textured_alpha_cases() -> Vec<(&'static str, &'static str, Vec<Rough>, f32, f32)> {
    use Rough::*;
    let conductor = r#"{"type": "roughconductor", "distribution": "ggx", "material": "Au", "alpha": $0}"#;
    let dielectric = r#"{"type": "roughdielectric", "distribution": "beckmann", "int_ior": 1.5, "alpha": $0}"#;
    let conductor_uv = r#"{"type": "roughconductor", "distribution": "beckmann", "material": "Cu", "alpha_u": $0,
                           "alpha_v": $1}"#;
    let dielectric_uv = r#"{"type": "roughdielectric", "distribution": "ggx", "int_ior": 1.33, "alpha_u": $0,
                            "alpha_v": $1}"#;
    let two_sides = r#"{"type": "twosided", "bsdf": [
                         {"type": "roughconductor", "distribution": "ggx", "material": "Au", "alpha": $0},
                         {"type": "roughconductor", "distribution": "beckmann", "material": "Cu", "alpha_u": $1,
                          "alpha_v": $2}]}"#;
    let one_child = r#"{"type": "twosided", "bsdf": {"type": "roughconductor", "distribution": "ggx",
                         "alpha_u": $0, "alpha_v": $1}}"#;
    vec![
        ("roughconductor ggx, checkerboard alpha, odd cell", conductor, vec![CheckerA], 60.0, 200.0),
        ("roughconductor ggx, checkerboard alpha, even cell", conductor, vec![CheckerA], 60.0, 30.0),
        ("roughdielectric beckmann, checkerboard alpha, even cell", dielectric, vec![CheckerA], 50.0, 100.0),
        ("roughdielectric beckmann, checkerboard alpha, odd cell", dielectric, vec![CheckerA], 120.0, 30.0),
        (
            "roughconductor beckmann, checkerboard alpha_u, alpha_v 0.2, odd",
            conductor_uv,
            vec![CheckerA, Const(0.2)],
            60.0,
            200.0,
        ),
        (
            "roughconductor beckmann, alpha_u 0.5, checkerboard alpha_v, even",
            conductor_uv,
            vec![Const(0.5), CheckerB],
            60.0,
            30.0,
        ),
        (
            "roughdielectric ggx, checkerboard alpha_u and alpha_v, even",
            dielectric_uv,
            vec![CheckerA, CheckerB],
            50.0,
            100.0,
        ),
        (
            "roughdielectric ggx, checkerboard alpha_u and alpha_v, odd",
            dielectric_uv,
            vec![CheckerB, CheckerA],
            120.0,
            30.0,
        ),
        (
            "twosided, textured alpha front, anisotropic back, odd",
            two_sides,
            vec![CheckerA, Const(0.25), CheckerB],
            60.0,
            200.0,
        ),
        ("twosided, one child, textured alpha_u and alpha_v, even", one_child, vec![CheckerB, CheckerA], 50.0, 100.0),
    ]
}

/// `template` with `$i` replaced by `values[i]`.
fn fill(template: &str, values: &[String]) -> String {
    values.iter().enumerate().fold(template.to_string(), |t, (i, v)| t.replace(&format!("${i}"), v))
}

/// `(alpha_u, alpha_v)` of each microfacet model in `bsdf` (both sides of a
/// `twosided`).
fn roughnesses(bsdf: &Bsdf) -> Vec<(f32, f32)> {
    let m = match bsdf {
        Bsdf::RoughConductor(b) => vec![b.microfacet],
        Bsdf::RoughDielectric(b) => vec![b.microfacet],
        Bsdf::TwoSided(b) => [b.front.microfacet(), b.back.microfacet()].into_iter().flatten().collect(),
        other => panic!("{other:?}"),
    };
    m.iter().map(|m| (m.alpha_u, m.alpha_v)).collect()
}

/// The textured-roughness models added to the chi-square, reciprocity and
/// energy tests, each with the JSON of the same surface with the constant
/// roughnesses its point should have: each point's model must carry
/// exactly its cell's roughnesses (so those tests run at the roughness the
/// textures give).
fn textured_alpha_points() -> Vec<(&'static str, Bsdf, String)> {
    let mut out = Vec::new();
    for (name, template, rough, theta, phi) in textured_alpha_cases() {
        let textured = fill(template, &rough.iter().map(|r| r.textured()).collect::<Vec<_>>());
        let (bsdf, odd) = textured_alpha_at(&textured, theta, phi);
        let constant = fill(template, &rough.iter().map(|r| format!("{}", r.at(odd))).collect::<Vec<_>>());
        let expected = roughnesses(&bsdf_from_json(&constant));
        assert_eq!(roughnesses(&bsdf), expected, "{name}: roughness at the hit");
        out.push((name, bsdf, constant));
    }
    out
}

fn textured_alpha_models() -> Vec<(&'static str, Bsdf)> {
    textured_alpha_points().into_iter().map(|(name, bsdf, _)| (name, bsdf)).collect()
}

/// A textured roughness gives, at a hit, the model the same surface with
/// those constant roughnesses has: `f` and `pdf` equal to the last bit at 6
/// x 6 direction pairs (both sides), for each of the ten textured points.
#[test]
fn textured_alpha_at_a_hit_is_the_constant_model() {
    let points = textured_alpha_points();
    assert_eq!(points.len(), 10);
    for (name, bsdf, constant) in points {
        let reference = bsdf_from_json(&constant);
        let dirs: Vec<Vec3> = [10.0f32, 40.0, 70.0, 100.0, 140.0, 170.0]
            .iter()
            .enumerate()
            .map(|(i, t)| spherical(t.to_radians() as f64, 0.9 * i as f64))
            .collect();
        for wo in &dirs {
            for wi in &dirs {
                let (a, b) = (bsdf.eval(Vec3::Z, *wo, *wi), reference.eval(Vec3::Z, *wo, *wi));
                assert_eq!(a.0.map(f32::to_bits), b.0.map(f32::to_bits), "{name} ({constant}): f");
                let (a, b) = (bsdf.pdf(Vec3::Z, *wo, *wi), reference.pdf(Vec3::Z, *wo, *wi));
                assert_eq!(a.to_bits(), b.to_bits(), "{name} ({constant}): pdf");
            }
        }
    }
}

const ANGLES: [f32; 4] = [10.0, 50.0, 80.0, 135.0];

fn incident(theta_deg: f32) -> Vec3 {
    let t = theta_deg.to_radians();
    Vec3::new(t.sin() * 0.8, t.sin() * 0.6, t.cos())
}

/// Direction of polar angle `theta` and azimuth `phi` about +z.
fn spherical(theta: f64, phi: f64) -> Vec3 {
    Vec3::new((theta.sin() * phi.cos()) as f32, (theta.sin() * phi.sin()) as f32, theta.cos() as f32)
}

/// Regularized upper incomplete gamma function Q(a, x) (Numerical Recipes,
/// series for x < a + 1, Lentz's continued fraction otherwise).
fn gamma_q(a: f64, x: f64) -> f64 {
    let ln_gamma_a = ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - ln_gamma_a).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - ln_gamma_a).exp() * h
    }
}

/// ln Gamma(x) for x > 0 (Lanczos, g = 7, n = 9).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Mitsuba's chi-square test design (its `ChiSquareTest`): the sphere is
/// binned in (theta, phi) (36 x 36 bins), the sampler's histogram (delta-lobe samples
/// left out) is compared to the density integrated over each bin (64 x 16
/// midpoint rule in theta and phi with the sin theta Jacobian: a rough
/// dielectric's transmission density has steep edges in theta, where 16
/// points per 5 degree bin were 13% off), bins with
/// fewer than 5 expected samples are pooled, and the statistic's p-value
/// must exceed 0.01 divided by the number of tests (Bonferroni): the
/// models of [`models`] (both distributions, isotropic and anisotropic, alphas 0.15 to
/// 0.7, indices 1.33 to 1.8, and ten points of textured-roughness surfaces),
/// each at 10, 50, 80 and 135 degrees (the last
/// from behind or inside). `CHI2_SAMPLES` and `CHI2_SEED` override the
/// sample count and seed; `CHI2_DEBUG` prints the worst bins.
#[test]
fn samplers_follow_their_densities_chi_square() {
    const THETA_BINS: usize = 36;
    const PHI_BINS: usize = 36;
    const SUB_T: usize = 64;
    const SUB_P: usize = 12;
    // 300,000 samples per test; 2,000,000 with NIEBLA_SLOW_TESTS (passed too).
    let default_samples = if std::env::var_os("NIEBLA_SLOW_TESTS").is_some() { 2_000_000 } else { 300_000 };
    let samples_env: usize = std::env::var("CHI2_SAMPLES").ok().and_then(|s| s.parse().ok()).unwrap_or(default_samples);
    let seed: u64 = std::env::var("CHI2_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(11);
    #[allow(non_snake_case)]
    let SAMPLES = samples_env;
    let models = models();
    let tests = models.len() * ANGLES.len();
    let threshold = 0.01 / tests as f64;
    for (index, (name, bsdf)) in models.iter().enumerate() {
        for (a, theta_deg) in ANGLES.into_iter().enumerate() {
            let wo = incident(theta_deg).normalize();
            let mut sampler = PixelSampler::for_pixel(SamplerKind::Independent, seed, index as u32, a as u32, 0);
            // Expected counts.
            let (dt, dp) = (std::f64::consts::PI / THETA_BINS as f64, std::f64::consts::TAU / PHI_BINS as f64);
            let mut expected = vec![0.0f64; THETA_BINS * PHI_BINS];
            for i in 0..THETA_BINS {
                for j in 0..PHI_BINS {
                    let mut sum = 0.0;
                    for a in 0..SUB_T {
                        let theta = (i as f64 + (a as f64 + 0.5) / SUB_T as f64) * dt;
                        for b in 0..SUB_P {
                            let phi = (j as f64 + (b as f64 + 0.5) / SUB_P as f64) * dp;
                            sum += bsdf.pdf(Vec3::Z, wo, spherical(theta, phi)) as f64 * theta.sin();
                        }
                    }
                    expected[i * PHI_BINS + j] = sum * dt * dp / (SUB_T * SUB_P) as f64 * SAMPLES as f64;
                }
            }
            // Histogram.
            let mut observed = vec![0.0f64; THETA_BINS * PHI_BINS];
            for _ in 0..SAMPLES {
                let Some(s) =
                    bsdf.sample_with_mode(Vec3::Z, wo, sampler.next_1d(), sampler.next_2d(), TransportMode::Radiance)
                else {
                    continue;
                };
                if s.is_specular {
                    continue;
                }
                let theta = (s.wi.z as f64).clamp(-1.0, 1.0).acos();
                let phi = (s.wi.y as f64).atan2(s.wi.x as f64).rem_euclid(std::f64::consts::TAU);
                let i = ((theta / dt) as usize).min(THETA_BINS - 1);
                let j = ((phi / dp) as usize).min(PHI_BINS - 1);
                observed[i * PHI_BINS + j] += 1.0;
            }
            // One-sided models seen from behind: no density, no samples.
            let total: f64 = expected.iter().sum();
            if total < 1e-9 * SAMPLES as f64 {
                assert_eq!(observed.iter().sum::<f64>(), 0.0, "{name} at {theta_deg} deg: samples where pdf is zero");
                continue;
            }
            // Pool small bins, then the statistic.
            let mut order: Vec<usize> = (0..expected.len()).collect();
            order.sort_by(|a, b| expected[*a].partial_cmp(&expected[*b]).unwrap());
            let (mut chi2, mut dof, mut pooled_e, mut pooled_o) = (0.0, 0usize, 0.0, 0.0);
            for k in order {
                if expected[k] < 5.0 {
                    pooled_e += expected[k];
                    pooled_o += observed[k];
                    if pooled_e >= 5.0 {
                        chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
                        dof += 1;
                        pooled_e = 0.0;
                        pooled_o = 0.0;
                    }
                } else {
                    chi2 += (observed[k] - expected[k]) * (observed[k] - expected[k]) / expected[k];
                    dof += 1;
                }
            }
            if pooled_e > 0.0 {
                chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e.max(1e-3);
                dof += 1;
            }
            assert!(dof > 1, "{name} at {theta_deg} deg: too few bins");
            if std::env::var("CHI2_DEBUG").is_ok() {
                let band_o: f64 = (0..PHI_BINS).map(|j| observed[23 * PHI_BINS + j]).sum();
                let band_e: f64 = (0..PHI_BINS).map(|j| expected[23 * PHI_BINS + j]).sum();
                eprintln!("{name} {theta_deg}: band 23 observed {band_o} expected {band_e:.1} of {SAMPLES}");
                let mut worst: Vec<(f64, usize)> = (0..expected.len())
                    .filter(|k| expected[*k] >= 5.0)
                    .map(|k| ((observed[k] - expected[k]).powi(2) / expected[k], k))
                    .collect();
                worst.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
                for (c, k) in worst.iter().take(6) {
                    eprintln!(
                        "{name} {theta_deg}: bin theta {} phi {}: obs {} exp {:.1} chi {c:.1}",
                        k / PHI_BINS,
                        k % PHI_BINS,
                        observed[*k],
                        expected[*k]
                    );
                }
            }
            let p = gamma_q((dof - 1) as f64 / 2.0, chi2 / 2.0);
            assert!(p > threshold, "{name} at {theta_deg} deg: chi2 {chi2:.1} with {} dof, p = {p:.2e}", dof - 1);
        }
    }
}

/// Reciprocity: `f(wo, wi) = f(wi, wo)` for the reflecting models; for a
/// rough dielectric in radiance transport, `f(wo, wi) / eta_o^2 = f(wi, wo)
/// / eta_i^2` with `eta` the index on each direction's side (Veach 1997,
/// section 5.2, with the `1 / etap^2` radiance factor). Tolerance 1e-3
/// relative: the two orders compute the half vector from different f32
/// sums (`wo + eta wi` against `wi + wo / eta`), and a steep `D` turns its
/// rounding (~1e-7) into ~1e-4 of the value. Pairs whose inside direction
/// lies within 0.002 of the critical cosine to the (generalized) half
/// vector, reflecting inside or refracting, are skipped (the Fresnel term's
/// slope is infinite there).
#[test]
fn reciprocity() {
    let mut sampler = PixelSampler::for_pixel(SamplerKind::Independent, 2, 7, 1, 0);
    for (name, bsdf) in models() {
        let eta = match bsdf {
            Bsdf::RoughDielectric(d) => d.eta,
            _ => 1.0,
        };
        let mut checked = 0;
        for _ in 0..2_000 {
            let a = niebla::sampling::sample_uniform_sphere(sampler.next_2d());
            let b = niebla::sampling::sample_uniform_sphere(sampler.next_2d());
            let index = |w: Vec3| if w.z < 0.0 { eta } else { 1.0 };
            // The inside direction within 0.002 of the critical angle to the
            // (generalized) half vector, in reflection inside or in
            // refraction: F's infinite slope there turns f32 rounding into
            // large differences (a refraction pair at 1e-4 of it differs by
            // 1e-3 even in f64, from the unit vectors' last-bit lengths).
            if eta != 1.0 && (a.z < 0.0 || b.z < 0.0) {
                let m = if a.z * b.z > 0.0 {
                    a + b
                } else if a.z > 0.0 {
                    a + b * eta
                } else {
                    b + a * eta
                };
                let inside = if a.z < 0.0 { a } else { b };
                let c = inside.dot(m.normalize()).abs();
                if (c - (1.0 - 1.0 / (eta * eta)).sqrt()).abs() < 2e-3 {
                    continue;
                }
            }
            let fab = bsdf.eval(Vec3::Z, a, b) / (index(a) * index(a));
            let fba = bsdf.eval(Vec3::Z, b, a) / (index(b) * index(b));
            for c in 0..3 {
                let scale = fab[c].abs().max(fba[c].abs());
                assert!(
                    (fab[c] - fba[c]).abs() <= 1e-3 * scale + 1e-7,
                    "{name}: a {a} b {b}: {} vs {}",
                    fab[c],
                    fba[c]
                );
            }
            checked += usize::from(fab.max_channel() > 0.0);
        }
        assert!(checked > 100, "{name}: only {checked} non-zero pairs");
    }
}

/// Energy: the directional albedo `integral f |cos| dwi` of each model is
/// at most 1, and the sampler's estimate `E[f |cos| / pdf]` (delta lobes
/// included) agrees with quadrature of `eval` plus the delta lobes' known
/// weight: the sample weights are those of `eval`. 200,000 samples; the
/// agreement is asserted within 4 standard errors plus 0.5% for the
/// quadrature (a 256 x 512 midpoint rule in (theta, phi), finer than the
/// narrowest lobe of these roughnesses).
#[test]
fn albedo_is_at_most_one_and_sampling_weights_match_eval() {
    let mut sampler = PixelSampler::for_pixel(SamplerKind::Independent, 5, 5, 9, 0);
    const N: usize = 200_000;
    for (name, bsdf) in models() {
        for theta_deg in ANGLES {
            let wo = incident(theta_deg).normalize();
            let (mut sum, mut sum2, mut delta) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
            for _ in 0..N {
                let Some(s) = bsdf.sample(Vec3::Z, wo, sampler.next_1d(), sampler.next_2d()) else { continue };
                let w = s.weight(Vec3::Z);
                // Radiance mode: undo the 1 / etap^2 of refraction to count energy.
                let w = if s.is_transmission { w * (s.eta * s.eta) } else { w };
                for c in 0..3 {
                    sum[c] += w[c] as f64;
                    sum2[c] += (w[c] as f64).powi(2);
                    if s.is_specular {
                        delta[c] += w[c] as f64;
                    }
                }
            }
            let (nt, np) = (256usize, 512usize);
            let (dt, dp) = (std::f64::consts::PI / nt as f64, std::f64::consts::TAU / np as f64);
            let mut quad = [0.0f64; 3];
            for i in 0..nt {
                let theta = (i as f64 + 0.5) * dt;
                for j in 0..np {
                    let wi = spherical(theta, (j as f64 + 0.5) * dp);
                    let mut f = bsdf.eval(Vec3::Z, wo, wi);
                    if wi.z * wo.z < 0.0 {
                        if let Bsdf::RoughDielectric(d) = bsdf {
                            let etap = if wo.z > 0.0 { d.eta } else { 1.0 / d.eta };
                            f *= etap * etap;
                        }
                    }
                    for c in 0..3 {
                        quad[c] += f[c] as f64 * (wi.z as f64).abs() * theta.sin() * dt * dp;
                    }
                }
            }
            for c in 0..3 {
                let mean = sum[c] / N as f64;
                let se = ((sum2[c] / N as f64 - mean * mean).max(0.0) / N as f64).sqrt();
                let expected = quad[c] + delta[c] / N as f64;
                assert!(mean <= 1.0 + 4.0 * se, "{name} at {theta_deg} deg channel {c}: albedo {mean} +- {se}");
                assert!(
                    (mean - expected).abs() <= 4.0 * se + 5e-3 * expected,
                    "{name} at {theta_deg} deg channel {c}: sampled {mean} +- {se} vs quadrature {expected}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Renders: white furnaces, the smooth limit, frosted glass of milk
// ---------------------------------------------------------------------------

mod common;

use common::Stats;
use niebla::color::Rgb;
use niebla::geometry::{Shape, Sphere};
use niebla::integrator::{Integrator, VolPathIntegrator};
use niebla::light::{ConstantLight, Light};
use niebla::math::Ray;
use niebla::medium::{HomogeneousMedium, Medium, MediumId};
use niebla::phase::PhaseFunction;
use niebla::scene::{surface_epsilon, Scene, SceneObject};

/// A unit sphere at the origin with `bsdf` (and `interior`), in a uniform
/// environment of radiance `env`.
fn sphere_scene(bsdf: Bsdf, interior: Option<Medium>, env: f32) -> Scene {
    let object = SceneObject {
        shape: Shape::Sphere(Sphere::new(Vec3::ZERO, 1.0)),
        bsdf,
        interior: interior.as_ref().map(|_| MediumId(0)),
        exterior: None,
        bounds_medium: interior.is_some(),
        emitter: None,
        texture: None,
        roughness: None,
        dpdu_frame: false,
    };
    let env = Light::Constant(ConstantLight { radiance: Rgb::splat(env) });
    common::scene(common::camera_along_x(1, 1, 30.0), vec![object], interior.into_iter().collect(), vec![env], None)
}

/// Camera rays from x = -4 toward points of the sphere's silhouette side.
fn rays() -> Vec<Ray> {
    [(0.0, 0.0), (0.5, 0.3), (0.0, 0.9), (0.7, -0.6)]
        .into_iter()
        .map(|(y, z)| Ray::new(Vec3::new(-4.0, y, z), Vec3::X))
        .collect()
}

fn estimate(
    scene: &Scene,
    ray: Ray,
    n: u32,
    seed: u64,
    mut f: impl FnMut(&Scene, Ray, &mut PixelSampler) -> Rgb,
) -> [Stats; 3] {
    let mut stats = [Stats::default(); 3];
    for i in 0..n {
        let mut sampler = PixelSampler::for_pixel(SamplerKind::default(), seed, 1, 2, i as u64);
        let l = f(scene, ray, &mut sampler);
        for c in 0..3 {
            stats[c].add(l[c] as f64);
        }
    }
    stats
}

fn volpath(scene: &Scene, ray: Ray, n: u32) -> [Stats; 3] {
    let integrator = VolPathIntegrator::new(1000);
    estimate(scene, ray, n, 3, |s, r, sampler| integrator.radiance(s, r, None, sampler))
}

/// White furnace: a white rough conductor (Mitsuba's default index, eta 0
/// and k 1, reflects everything at every angle) and a rough dielectric
/// without a medium, in a uniform environment of radiance 1: microfacet
/// models without multiple scattering between facets lose energy and
/// never gain it, so every pixel is at most 1 within 4 standard errors
/// (4,000 paths each). They also stay above 0.3: single-scattering
/// microfacets lose energy, 31% here for the conductor (GGX with alpha 0.5
/// has a directional albedo of 0.688 at normal incidence, by an independent
/// quadrature of the same formulas in numpy) and about half for the rough
/// glass sphere (0.49 for GGX 0.4: light crosses two rough interfaces and
/// is reflected inside many times, losing energy at each event).
#[test]
fn white_furnace_pixels_are_at_most_one() {
    for json in [
        r#"{"type": "roughconductor", "distribution": "ggx", "alpha": 0.5}"#,
        r#"{"type": "roughconductor", "distribution": "beckmann", "alpha_u": 0.3, "alpha_v": 0.8}"#,
        r#"{"type": "roughdielectric", "distribution": "ggx", "alpha": 0.4, "int_ior": 1.5, "ext_ior": 1}"#,
        r#"{"type": "roughdielectric", "distribution": "beckmann", "alpha": 0.8, "int_ior": 1.33, "ext_ior": 1}"#,
        r#"{"type": "twosided", "bsdf": {"type": "roughconductor", "distribution": "ggx", "alpha": 0.2}}"#,
        r#"{"type": "roughplastic", "distribution": "ggx", "alpha": 0.3, "diffuse_reflectance": 1}"#,
        r#"{"type": "roughplastic", "distribution": "beckmann", "alpha": 0.6, "diffuse_reflectance": 1,
            "nonlinear": true}"#,
    ] {
        let scene = sphere_scene(bsdf_from_json(json), None, 1.0);
        for ray in rays() {
            let stats = volpath(&scene, ray, 4_000);
            for (c, st) in stats.iter().enumerate() {
                assert!(
                    st.mean() <= 1.0 + 4.0 * st.standard_error(),
                    "{json} channel {c}: {} +- {}",
                    st.mean(),
                    st.standard_error()
                );
                assert!(st.mean() > 0.3, "{json} channel {c}: {} +- {}", st.mean(), st.standard_error());
            }
        }
    }
}

/// The smooth limit: with alpha = 0.001 a rough conductor reflects the
/// environment times the smooth Fresnel reflectance (within 0.2%: the
/// facets tilt by ~0.001 rad), and a rough glass sphere of milk (a
/// non-absorbing medium) in a uniform environment is the smooth one's
/// exact white furnace: 0.8 within 4 standard errors of 4,000 paths.
#[test]
fn small_roughness_reaches_the_smooth_models() {
    let metal =
        bsdf_from_json(r#"{"type": "roughconductor", "distribution": "ggx", "alpha": 0.001, "material": "Cu"}"#);
    let smooth = bsdf_from_json(
        r#"{"type": "conductor", "eta": [0.2010055, 0.9237495, 1.1022154], "k": [3.913262, 2.453045, 2.1420898]}"#,
    );
    let (Bsdf::RoughConductor(m), Bsdf::Conductor { eta, k }) = (metal, smooth) else { panic!() };
    assert!((m.eta - eta).map(f32::abs).max_channel() < 1e-6 && (m.k - k).map(f32::abs).max_channel() < 1e-6);
    let scene = sphere_scene(metal, None, 2.0);
    for ray in rays() {
        let hit = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        let cos = hit.surface.n.dot(-ray.d);
        let expected = niebla::bsdf::fresnel_complex(cos, eta, k) * 2.0;
        let stats = volpath(&scene, ray, 200);
        for c in 0..3 {
            let got = stats[c].mean();
            assert!(
                (got - expected[c] as f64).abs() < 2e-3 * expected[c] as f64,
                "channel {c}: {got} vs {}",
                expected[c]
            );
        }
    }
    let milk = Medium::Homogeneous(HomogeneousMedium {
        sigma_a: Rgb::ZERO,
        sigma_s: Rgb::new(4.0, 6.0, 9.0),
        l_ve: Rgb::ZERO,
        phase: PhaseFunction::hg(0.7),
    });
    let glass = bsdf_from_json(
        r#"{"type": "roughdielectric", "distribution": "ggx", "alpha": 0.001, "int_ior": 1.5, "ext_ior": 1}"#,
    );
    let scene = sphere_scene(glass, Some(milk), 0.8);
    for ray in rays() {
        let stats = volpath(&scene, ray, 4_000);
        for (c, st) in stats.iter().enumerate() {
            let z = (st.mean() - 0.8) / (st.standard_error() + 1e-5);
            assert!(z.abs() < 4.0, "channel {c}: {} +- {}", st.mean(), st.standard_error());
        }
    }
}

/// An estimator independent of volpath: BSDF sampling only (no light
/// sampling, no MIS), analog free-flight sampling in the gray medium inside
/// the sphere (albedo as weight), the environment added when a path escapes.
fn naive_radiance(
    scene: &Scene,
    ray: Ray,
    sigma_s: f32,
    sigma_a: f32,
    phase: &PhaseFunction,
    env: f32,
    sampler: &mut PixelSampler,
) -> Rgb {
    let mut ray = ray;
    let mut t_min = 0.0;
    let mut inside = false;
    let mut beta = Rgb::ONE;
    let sigma_t = sigma_s + sigma_a;
    for _ in 0..10_000 {
        let hit = scene.intersect(&ray, t_min, f32::INFINITY);
        if inside {
            let t = -(1.0 - sampler.next_1d()).ln() / sigma_t;
            if hit.is_none_or(|h| t < h.local.t) {
                beta *= sigma_s / sigma_t;
                let p = ray.at(t);
                let Some(ps) = phase.sample(-ray.d, sampler.next_2d()) else { return Rgb::ZERO };
                beta *= ps.value / ps.pdf;
                ray = Ray::new(p, ps.wi);
                t_min = 0.0;
                continue;
            }
        }
        let Some(hit) = hit else { return beta * env };
        let wo = -ray.d;
        let ns = hit.surface.shading_normal(wo);
        let bsdf = scene.surface_bsdf(&hit);
        let Some(bs) = bsdf.sample(ns, wo, sampler.next_1d(), sampler.next_2d()) else { return Rgb::ZERO };
        beta *= bs.weight(ns);
        if bs.is_transmission {
            inside = !inside;
        }
        ray = Ray::new(hit.surface.p, bs.wi);
        t_min = surface_epsilon(hit.surface.p);
    }
    Rgb::ZERO
}

/// Frosted glass of milk: a rough dielectric sphere (GGX, alpha 0.3, index
/// 1.5) holding an absorbing, scattering medium (sigma_s 3, sigma_a 0.5,
/// HG 0.5) in a uniform environment renders without error, and volpath
/// (light sampling with MIS at the glass, null-scattering tracking) agrees
/// with the naive estimator above within 4 combined standard errors
/// (20,000 paths each, per ray).
#[test]
fn frosted_glass_of_milk_agrees_between_two_estimators() {
    let (sigma_s, sigma_a) = (3.0f32, 0.5f32);
    let phase = PhaseFunction::hg(0.5);
    let milk = Medium::Homogeneous(HomogeneousMedium {
        sigma_a: Rgb::splat(sigma_a),
        sigma_s: Rgb::splat(sigma_s),
        l_ve: Rgb::ZERO,
        phase: phase.clone(),
    });
    let glass = bsdf_from_json(
        r#"{"type": "roughdielectric", "distribution": "ggx", "alpha": 0.3, "int_ior": 1.5, "ext_ior": 1}"#,
    );
    let scene = sphere_scene(glass, Some(milk), 1.0);
    for ray in rays() {
        let a = volpath(&scene, ray, 20_000);
        let b = estimate(&scene, ray, 20_000, 99, |s, r, sampler| {
            naive_radiance(s, r, sigma_s, sigma_a, &phase, 1.0, sampler)
        });
        for c in 0..3 {
            let se = (a[c].standard_error().powi(2) + b[c].standard_error().powi(2)).sqrt();
            assert!(a[c].mean().is_finite() && a[c].mean() > 0.05);
            assert!(
                (a[c].mean() - b[c].mean()).abs() < 4.0 * se,
                "ray {ray:?} channel {c}: volpath {} vs naive {} (se {se})",
                a[c].mean(),
                b[c].mean()
            );
        }
    }
}
