//! Source radiance at the RBF centres (Zhou et al. 2008, Section 5.3):
//! transmittance toward the environment from the RBF approximation `D~`
//! only, its product with the SH environment and the convolution with the
//! phase function; and transmittance toward point, spot and directional
//! lights (ours: the paper has environment lighting only).
//!
//! Optical depth in SH: each RBF `h` seen from centre `c_l` is a zonal
//! function of the direction with zonal coefficients depending only on
//! `delta = |c_h - c_l| / r_h` ([`ZonalDepthTable`], 256 samples of the
//! half-angle `beta` in [0, pi], the paper's table size), rotated to the axis
//! `c_l -> c_h` and scaled by `w_h r_h`. Exponentiation: the band-limited
//! optical depth is evaluated at the nodes of a sphere quadrature,
//! exponentiated there and multiplied by the environment before projecting
//! back (ours: exact exponentiation of the band-limited log, the lower bound
//! of every SH-exponentiation scheme's error, instead of Ren et al.'s
//! tabulated approximation; the `exact` mode evaluates the optical depth per
//! quadrature direction in closed form instead).

use rayon::prelude::*;

use super::rbf::{unit_half_line_depth, Rbf};
use super::sh::{self, eval_basis, gauss_legendre, SphereQuadrature};
use crate::color::Rgb;
use crate::light::Light;
use crate::math::Vec3;

/// Samples of `beta` in the zonal optical-depth table.
pub const BETA_SAMPLES: usize = 256;

/// Zonal SH coefficients `T_l(beta) = 2 pi int tau_u(delta(beta), mu) y_l0(mu) dmu`
/// of the optical depth of a unit Gaussian, with `delta = 1/sin(beta)` for
/// `beta <= pi/2` and `delta = sin(beta)` beyond (`beta = pi` at the centre).
#[derive(Clone, Debug)]
pub struct ZonalDepthTable {
    order: usize,
    values: Vec<f64>,
}

impl ZonalDepthTable {
    /// The table for SH order `order`.
    pub fn new(order: usize) -> ZonalDepthTable {
        let mut values = vec![0.0; BETA_SAMPLES * order];
        for (i, row) in values.chunks_mut(order).enumerate() {
            let beta = std::f64::consts::PI * i as f64 / (BETA_SAMPLES - 1) as f64;
            if i == 0 {
                continue; // infinitely far: no optical depth
            }
            row.copy_from_slice(&zonal_depth(delta_of_beta(beta), order));
        }
        ZonalDepthTable { order, values }
    }

    /// Linearly interpolated zonal coefficients at `delta = d / r`.
    pub fn lookup(&self, delta: f64, out: &mut [f64]) {
        let beta = beta_of_delta(delta);
        let f = beta / std::f64::consts::PI * (BETA_SAMPLES - 1) as f64;
        let i = (f as usize).min(BETA_SAMPLES - 2);
        let t = f - i as f64;
        for l in 0..self.order {
            out[l] = (1.0 - t) * self.values[i * self.order + l] + t * self.values[(i + 1) * self.order + l];
        }
    }
}

/// `delta(beta)` of the table (see [`ZonalDepthTable`]).
pub fn delta_of_beta(beta: f64) -> f64 {
    if beta <= std::f64::consts::FRAC_PI_2 {
        1.0 / beta.sin()
    } else {
        beta.sin()
    }
}

/// Inverse of [`delta_of_beta`].
pub fn beta_of_delta(delta: f64) -> f64 {
    if delta >= 1.0 {
        (1.0 / delta).asin()
    } else {
        std::f64::consts::PI - delta.asin()
    }
}

/// Zonal coefficients of `tau_u(delta, mu)` by Gauss-Legendre in the angle
/// to the axis, refined near the axis where the Gaussian's shadow is narrow.
pub fn zonal_depth(delta: f64, order: usize) -> Vec<f64> {
    let (xs, ws) = gauss_legendre(64);
    let split = if delta > 1.0 { (12.0 / delta).min(std::f64::consts::PI) } else { std::f64::consts::PI };
    let mut out = vec![0.0; order];
    let mut y = [0f64; sh::MAX_ORDER * sh::MAX_ORDER];
    for (a, b) in [(0.0, split), (split, std::f64::consts::PI)] {
        if b <= a {
            continue;
        }
        for (x, w) in xs.iter().zip(&ws) {
            let theta = a + 0.5 * (b - a) * (x + 1.0);
            let mu = theta.cos();
            let weight = 0.5 * (b - a) * w * theta.sin() * 2.0 * std::f64::consts::PI;
            let tau = unit_half_line_depth(delta, mu);
            eval_basis(order, [0.0, 0.0, mu], &mut y);
            for l in 0..order {
                out[l] += weight * tau * y[l * l + l];
            }
        }
    }
    out
}

/// SH coefficients (order of `table`) of the optical depth of `D~` seen from
/// each centre, `N x order^2`, density units times length.
pub fn centre_depth_sh(rbfs: &[Rbf], table: &ZonalDepthTable) -> Vec<f64> {
    let order = table.order;
    let nc = order * order;
    let mut out = vec![0.0; rbfs.len() * nc];
    out.par_chunks_mut(nc).enumerate().for_each(|(l, o)| {
        let c = rbfs[l].center;
        let mut zonal = [0f64; sh::MAX_ORDER];
        for h in rbfs {
            let v = h.center - c;
            let d = v.length() as f64;
            let delta = d / h.radius as f64;
            table.lookup(delta, &mut zonal);
            let axis = if d > 0.0 { sh::dir64(v / d as f32) } else { [0.0, 0.0, 1.0] };
            sh::add_rotated_zonal(order, &zonal, axis, h.weight as f64 * h.radius as f64, o);
        }
    });
    out
}

/// Optical depth (density x length) of `D~` from each centre toward each
/// quadrature direction, in closed form: the oracle for [`centre_depth_sh`].
pub fn centre_depth_exact(rbfs: &[Rbf], quadrature: &SphereQuadrature) -> Vec<f64> {
    let nd = quadrature.directions.len();
    let mut out = vec![0.0; rbfs.len() * nd];
    out.par_chunks_mut(nd).enumerate().for_each(|(l, o)| {
        let c = rbfs[l].center;
        for (v, d) in o.iter_mut().zip(&quadrature.directions) {
            let w = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32);
            *v = rbfs.iter().map(|h| h.optical_depth(c, w, f32::INFINITY)).sum();
        }
    });
    out
}

/// SH coefficients (per channel, order `order`) of the radiance arriving
/// from the scene's constant and map environments.
pub fn environment_sh(lights: &[Light], order: usize) -> [Vec<f64>; 3] {
    let nc = order * order;
    let mut out = [vec![0.0; nc], vec![0.0; nc], vec![0.0; nc]];
    let mut y = [0f64; sh::MAX_ORDER * sh::MAX_ORDER];
    for light in lights {
        match light {
            Light::Constant(c) => {
                for ch in 0..3 {
                    out[ch][0] += c.radiance[ch] as f64 * (4.0 * std::f64::consts::PI).sqrt();
                }
            }
            Light::Environment(map) => {
                for py in 0..map.height() {
                    let omega = map.pixel_solid_angle(py) as f64;
                    for px in 0..map.width() {
                        let l = map.pixel(px, py);
                        if l.is_black() {
                            continue;
                        }
                        eval_basis(order, sh::dir64(map.pixel_direction(px, py)), &mut y);
                        for ch in 0..3 {
                            let f = l[ch] as f64 * omega;
                            for k in 0..nc {
                                out[ch][k] += f * y[k];
                            }
                        }
                    }
                }
            }
            _ => {}
        }
    }
    out
}

/// Single-scattering source radiance at each centre as SH, `N x 3 x order^2`
/// (`J_ss,lm = albedo a_l (L_in tau)_lm`), from per-centre optical depths
/// either as SH (`depth_sh`) or per quadrature direction (`depth_exact`).
pub fn single_scattering_sh(
    count: usize,
    quadrature: &SphereQuadrature,
    environment: &[Vec<f64>; 3],
    depth: CentreDepth,
    sigma_t: Rgb,
    albedo: Rgb,
    convolution: &[f64],
) -> Vec<f64> {
    let nc = quadrature.coefficients();
    let nd = quadrature.directions.len();
    let env_values: Vec<Vec<f64>> = environment
        .iter()
        .map(|e| {
            let mut v = vec![0.0; nd];
            quadrature.synthesize(e, &mut v);
            v
        })
        .collect();
    let mut out = vec![0.0; count * 3 * nc];
    out.par_chunks_mut(3 * nc).enumerate().for_each(|(l, o)| {
        let mut tau = vec![0.0; nd];
        match depth {
            CentreDepth::Sh(sh) => quadrature.synthesize(&sh[l * nc..(l + 1) * nc], &mut tau),
            CentreDepth::Exact(e) => tau.copy_from_slice(&e[l * nd..(l + 1) * nd]),
        }
        let mut product = vec![0.0; nd];
        for ch in 0..3 {
            for k in 0..nd {
                product[k] = env_values[ch][k] * (-(sigma_t[ch] as f64) * tau[k]).exp();
            }
            let coeffs = &mut o[ch * nc..(ch + 1) * nc];
            quadrature.project(&product, coeffs);
            for band in 0..quadrature.order {
                for c in &mut coeffs[band * band..(band + 1) * (band + 1)] {
                    *c *= albedo[ch] as f64 * convolution[band];
                }
            }
        }
    });
    out
}

/// Per-centre optical depths toward the environment.
#[derive(Clone, Copy, Debug)]
pub enum CentreDepth<'a> {
    /// SH coefficients per centre (`N x order^2`).
    Sh(&'a [f64]),
    /// Values per centre and quadrature direction (`N x directions`).
    Exact(&'a [f64]),
}

/// A point-like or distant light as the model uses it.
#[derive(Clone, Copy, Debug)]
pub enum ModelLight {
    /// Point light at a position with intensity (W/sr); spot lights carry their cone.
    Point {
        /// World position.
        position: Vec3,
        /// Intensity (W/sr).
        intensity: Rgb,
        /// Spot cone, if any.
        spot: Option<crate::light::SpotLight>,
    },
    /// Directional light: unit direction toward the light and irradiance (W/m^2).
    Directional {
        /// Unit direction from the scene toward the light.
        toward: Vec3,
        /// Irradiance on a perpendicular surface.
        irradiance: Rgb,
    },
}

impl ModelLight {
    /// The scene's point, spot and directional lights.
    pub fn from_scene(lights: &[Light]) -> Vec<ModelLight> {
        lights
            .iter()
            .filter_map(|l| match l {
                Light::Point(p) => Some(ModelLight::Point { position: p.position, intensity: p.intensity, spot: None }),
                Light::Spot(s) => {
                    Some(ModelLight::Point { position: s.position, intensity: s.intensity, spot: Some(*s) })
                }
                Light::Directional(d) => {
                    Some(ModelLight::Directional { toward: -d.direction, irradiance: d.irradiance })
                }
                _ => None,
            })
            .collect()
    }

    /// Unit direction toward the light from `x`, distance (infinite for a
    /// directional light) and the irradiance arriving unattenuated.
    #[inline]
    pub fn toward(&self, x: Vec3) -> Option<(Vec3, f32, Rgb)> {
        match *self {
            ModelLight::Point { position, intensity, spot } => {
                let v = position - x;
                let d2 = v.length_squared();
                if d2 <= 0.0 {
                    return None;
                }
                let d = d2.sqrt();
                let wi = v / d;
                let falloff = spot.map_or(1.0, |s| s.falloff(-wi));
                Some((wi, d, intensity * (falloff / d2)))
            }
            ModelLight::Directional { toward, irradiance } => Some((toward, f32::INFINITY, irradiance)),
        }
    }
}

/// Density integral of `D~` from each centre toward each light (`N x lights`).
pub fn centre_light_depths(rbfs: &[Rbf], lights: &[ModelLight]) -> Vec<f64> {
    let nl = lights.len();
    let mut out = vec![0.0; rbfs.len() * nl];
    if nl == 0 {
        return out;
    }
    out.par_chunks_mut(nl).enumerate().for_each(|(l, o)| {
        let c = rbfs[l].center;
        for (v, light) in o.iter_mut().zip(lights) {
            if let Some((w, d, _)) = light.toward(c) {
                *v = rbfs.iter().map(|h| h.optical_depth(c, w, d)).sum();
            }
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// T2: summed rotated zonal vectors equal a direct SH projection of the
    /// summed optical depth (1e-3 with the 256-sample beta table).
    #[test]
    fn rotated_zonal_depths_match_direct_projection() {
        let order = 4;
        let table = ZonalDepthTable::new(order);
        let mut state = 7u64;
        let mut rand = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut rbfs = vec![Rbf { center: Vec3::ZERO, radius: 0.2, weight: 1.0 }];
        for _ in 0..60 {
            rbfs.push(Rbf {
                center: Vec3::new(rand() - 0.5, rand() - 0.5, rand() - 0.5) * 1.6,
                radius: 0.05 + 0.2 * rand(),
                weight: 0.2 + rand(),
            });
        }
        let shs = centre_depth_sh(&rbfs, &table);
        // A fine quadrature projects the exact optical depth from centre 0.
        let quadrature = SphereQuadrature::with_nodes(order, 128, 256);
        let exact: Vec<f64> = quadrature
            .directions
            .iter()
            .map(|d| {
                let w = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32);
                rbfs.iter().map(|h| h.optical_depth(Vec3::ZERO, w, f32::INFINITY)).sum()
            })
            .collect();
        let mut full = vec![0.0; 16];
        quadrature.project(&exact, &mut full);
        let err: f64 = (0..16).map(|k| (full[k] - shs[k]).powi(2)).sum::<f64>().sqrt();
        let norm: f64 = (0..16).map(|k| full[k].powi(2)).sum::<f64>().sqrt();
        assert!(err / norm < 1e-3, "relative L2 error {}", err / norm);
        // The centre's own RBF is isotropic: sqrt(pi)/2 r w along every direction.
        let own = zonal_depth(0.0, order);
        assert!((own[0] - 0.5 * std::f64::consts::PI.sqrt() * (4.0 * std::f64::consts::PI).sqrt()).abs() < 1e-9);
        assert!(own[1..].iter().all(|v| v.abs() < 1e-9));
    }

    #[test]
    fn beta_map_is_continuous_and_inverts() {
        for delta in [0.0, 0.3, 0.999, 1.0, 1.001, 4.0, 100.0] {
            assert!((delta_of_beta(beta_of_delta(delta)) - delta).abs() < 1e-9 * (1.0 + delta));
        }
        assert!((beta_of_delta(1.0 - 1e-9) - beta_of_delta(1.0 + 1e-9)).abs() < 1e-4);
    }
}
