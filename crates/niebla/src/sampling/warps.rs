//! Warps from uniform numbers to distributions, each with its pdf
//! and a test of the two together.

use crate::math::{safe_sqrt, Vec2, Vec3, INV_4PI, PI};

/// Uniform direction on the unit sphere; pdf `1 / (4 pi)` per steradian.
#[inline]
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = safe_sqrt(1.0 - z * z);
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`sample_uniform_sphere`], per steradian.
#[inline]
pub fn uniform_sphere_pdf() -> f32 {
    INV_4PI
}

/// Cosine-weighted direction on the hemisphere around +z (Malley's method);
/// pdf `cos(theta) / pi` per steradian.
#[inline]
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), safe_sqrt(1.0 - u.x))
}

/// Density of [`sample_cosine_hemisphere`] for a direction with `cos_theta` to +z.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * crate::math::INV_PI
}

/// Uniform direction inside the cone of half-angle `acos(cos_max)` around +z;
/// pdf `1 / (2 pi (1 - cos_max))`.
#[inline]
pub fn sample_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_theta = 1.0 - u.x * (1.0 - cos_max);
    let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
    crate::math::spherical_direction(sin_theta, cos_theta, 2.0 * PI * u.y)
}

/// Density of [`sample_uniform_cone`], per steradian.
#[inline]
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Distance in [0, t_max) with density proportional to `sigma exp(-sigma t)`
/// (free flight in a homogeneous medium truncated to a segment). `sigma = 0`
/// or `t_max = inf` handled: with sigma = 0 the distance is uniform.
#[inline]
pub fn sample_truncated_exponential(u: f32, sigma: f32, t_max: f32) -> f32 {
    if sigma <= 0.0 {
        return u * t_max;
    }
    // 1 - exp(-sigma t_max), computed stably.
    let mass = -(-sigma * t_max).exp_m1();
    let t = -(-u * mass).ln_1p() / sigma;
    t.min(t_max)
}

/// Density of [`sample_truncated_exponential`] at `t` in [0, t_max].
#[inline]
pub fn truncated_exponential_pdf(t: f32, sigma: f32, t_max: f32) -> f32 {
    if sigma <= 0.0 {
        return 1.0 / t_max;
    }
    let mass = -(-sigma * t_max).exp_m1();
    sigma * (-sigma * t).exp() / mass
}

/// Equiangular sampling (Kulla and Fajardo 2012) of a distance `t` in
/// `[t_a, t_b]` along a ray toward a point at distance `h > 0` from the ray's
/// line whose closest approach is at ray parameter `t_c`. Density is
/// proportional to `1 / (h^2 + (t - t_c)^2)`.
#[inline]
pub fn sample_equiangular(u: f32, t_a: f32, t_b: f32, t_c: f32, h: f32) -> f32 {
    sample_equiangular_at_angles(u, t_a, t_b, t_c, h, equiangular_angles(t_a, t_b, t_c, h))
}

/// Density of [`sample_equiangular`] at `t`.
#[inline]
pub fn equiangular_pdf(t: f32, t_a: f32, t_b: f32, t_c: f32, h: f32) -> f32 {
    equiangular_pdf_at_angles(t, t_c, h, equiangular_angles(t_a, t_b, t_c, h))
}

/// The angles (radians, in `(-pi/2, pi/2)`) under which the ends `t_a` and
/// `t_b` are seen from the point of [`sample_equiangular`], measured from
/// the perpendicular: what its sampling and density share (two `atan`s),
/// to be computed once per interval.
#[inline]
pub fn equiangular_angles(t_a: f32, t_b: f32, t_c: f32, h: f32) -> (f32, f32) {
    (((t_a - t_c) / h).atan(), ((t_b - t_c) / h).atan())
}

/// [`sample_equiangular`] with the interval's [`equiangular_angles`] given
/// (the same bits).
#[inline]
pub fn sample_equiangular_at_angles(u: f32, t_a: f32, t_b: f32, t_c: f32, h: f32, angles: (f32, f32)) -> f32 {
    let (theta_a, theta_b) = angles;
    let theta = theta_a + u * (theta_b - theta_a);
    (t_c + h * theta.tan()).clamp(t_a, t_b)
}

/// [`equiangular_pdf`] with the interval's [`equiangular_angles`] given
/// (the same bits).
#[inline]
pub fn equiangular_pdf_at_angles(t: f32, t_c: f32, h: f32, angles: (f32, f32)) -> f32 {
    let (theta_a, theta_b) = angles;
    let d = t - t_c;
    h / ((theta_b - theta_a) * (h * h + d * d))
}

/// Shirley and Chiu's concentric map of `u` in [0, 1)^2 onto the unit disk:
/// uniform by area (density `1 / pi`), low distortion.
pub fn sample_uniform_disk_concentric(u: Vec2) -> Vec2 {
    let x = 2.0 * u.x - 1.0;
    let y = 2.0 * u.y - 1.0;
    if x == 0.0 && y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if x * x > y * y { (x, (PI / 4.0) * (y / x)) } else { (y, PI / 2.0 - (PI / 4.0) * (x / y)) };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::PixelSampler;

    /// Chi-square statistic of `n` samples `x` binned on [a, b] against the pdf
    /// integrated per bin by the midpoint rule on 64 sub-steps.
    fn chi2_1d(samples: &[f32], a: f32, b: f32, bins: usize, pdf: impl Fn(f32) -> f32) -> (f64, usize) {
        let mut observed = vec![0f64; bins];
        for &x in samples {
            let i = (((x - a) / (b - a)) * bins as f32) as usize;
            observed[i.min(bins - 1)] += 1.0;
        }
        let n = samples.len() as f64;
        let mut chi2 = 0.0;
        for (i, obs) in observed.iter().enumerate() {
            let (lo, hi) = (
                a as f64 + (b - a) as f64 * i as f64 / bins as f64,
                a as f64 + (b - a) as f64 * (i + 1) as f64 / bins as f64,
            );
            let sub = 64;
            let mut p = 0.0;
            for k in 0..sub {
                let x = lo + (hi - lo) * (k as f64 + 0.5) / sub as f64;
                p += pdf(x as f32) as f64 * (hi - lo) / sub as f64;
            }
            let expected = n * p;
            chi2 += (obs - expected).powi(2) / expected;
        }
        (chi2, bins - 1)
    }

    #[test]
    fn equiangular_sampler_matches_its_pdf() {
        // 50 bins: chi-square with 49 dof has mean 49, sd 9.9; 99.9% quantile ~ 86.
        let (t_a, t_b, t_c, h) = (0.0, 4.0, 1.3, 0.2);
        let mut s = PixelSampler::from_key(11);
        let xs: Vec<f32> = (0..200_000).map(|_| sample_equiangular(s.next_1d(), t_a, t_b, t_c, h)).collect();
        let (chi2, _dof) = chi2_1d(&xs, t_a, t_b, 50, |t| equiangular_pdf(t, t_a, t_b, t_c, h));
        assert!(chi2 < 86.0, "chi2 = {chi2}");
    }

    #[test]
    fn truncated_exponential_sampler_matches_its_pdf() {
        let (sigma, t_max) = (1.7, 2.5);
        let mut s = PixelSampler::from_key(12);
        let xs: Vec<f32> = (0..200_000).map(|_| sample_truncated_exponential(s.next_1d(), sigma, t_max)).collect();
        let (chi2, _) = chi2_1d(&xs, 0.0, t_max, 50, |t| truncated_exponential_pdf(t, sigma, t_max));
        assert!(chi2 < 86.0, "chi2 = {chi2}");
    }

    #[test]
    fn uniform_sphere_and_cone_are_unit_and_within_bounds() {
        let mut s = PixelSampler::from_key(3);
        let mut mean_z = 0.0;
        for _ in 0..100_000 {
            let d = sample_uniform_sphere(s.next_2d());
            assert!((d.length() - 1.0).abs() < 1e-5);
            mean_z += d.z as f64;
            let c = sample_uniform_cone(s.next_2d(), 0.9);
            assert!(c.z >= 0.9 - 1e-6);
        }
        // E[z] = 0, sd of mean = sqrt(1/3 / 1e5) = 1.8e-3.
        assert!((mean_z / 100_000.0).abs() < 5.0 * 1.83e-3);
    }
}
