//! The blurred phase function of the multiple-scattering term: a
//! Henyey-Greenstein lobe convolved with an angular blur of per-axis
//! variance `w^2` around the light direction, tabulated over `(w, mu)`.
//!
//! The blur kernel is the heat kernel on the sphere (Legendre coefficients
//! `exp(-l (l + 1) w^2 / 2)`): exactly normalized, positive, and for small
//! `w` a Gaussian of per-axis variance `w^2`, as the small-angle
//! (Fermi-Eyges) theory of the stand-in model asks (see [`super`]); a von
//! Mises-Fisher lobe of `kappa = 1/w^2` would have the same small-angle limit. In Legendre
//! space the convolution is a product (Funk-Hecke), so
//! `P_w(mu) = sum_l (2l + 1)/(4 pi) g^l exp(-l (l + 1) w^2 / 2) P_l(mu)`.

use std::f64::consts::PI;

/// Table resolution in `w` (per-axis angular standard deviation, radians).
const N_W: usize = 96;
/// Largest tabulated `w`; beyond it the blurred phase is isotropic to < 1e-6.
const W_MAX: f64 = 4.0;
/// Table resolution in `mu` on [-1, 1].
const N_MU: usize = 256;

/// `P_w(mu)` for one asymmetry `g`.
#[derive(Clone, Debug)]
pub struct BlurredPhaseTable {
    g: f32,
    values: Vec<f32>,
}

impl BlurredPhaseTable {
    /// Tabulate for HG asymmetry `g` (|g| < 1). The Legendre sum runs until
    /// `|g|^l` falls below 1e-7 (or 2000 terms); the `w = 0` row is the HG
    /// lobe itself, evaluated directly.
    pub fn new(g: f32) -> BlurredPhaseTable {
        let gd = (g as f64).clamp(-0.99, 0.99);
        let l_max =
            if gd.abs() < 1e-6 { 1 } else { ((1e-7f64).ln() / gd.abs().ln()).ceil().clamp(1.0, 2000.0) as usize };
        let values = tabulate(
            l_max,
            |l| gd.powi(l as i32),
            |mu| (1.0 - gd * gd) / (4.0 * PI * (1.0 + gd * gd - 2.0 * gd * mu).powf(1.5)),
        );
        BlurredPhaseTable { g, values }
    }

    /// The irradiance kernel of the blurred light: `eval(w, c)` is
    /// `int max(0, -n . w') K_w(w' . d) dw'`, the irradiance on a surface of
    /// normal `n` from unit fluence whose propagation directions `w'` are
    /// spread around `d` by the heat kernel `K_w` of per-axis width `w`, at
    /// `c = -n . d` (the cosine between the normal and the direction toward
    /// the light). `w = 0` gives `max(0, c)` (a collimated beam), a wide
    /// blur `1/4` (isotropic radiance: irradiance `pi L`, fluence `4 pi L`).
    /// Legendre moments of the clamped cosine, `2 int_0^1 t P_l(t) dt`
    /// (Funk-Hecke), summed until the blur factor falls below 1e-12.
    pub fn irradiance() -> BlurredPhaseTable {
        // Row 1 (w = W_MAX / N_W) has blur factors below 1e-12 from l ~ 180.
        const L_MAX: usize = 400;
        // m_l = 2 int_0^1 t P_l(t) dt: 1, 2/3, 1/4, zero for odd l >= 3,
        // and for even l >= 4 the ratio m_l / m_{l-2} = -(l - 3) / (l + 2).
        let mut moments = vec![0f64; L_MAX + 1];
        moments[0] = 1.0;
        moments[1] = 2.0 / 3.0;
        if L_MAX >= 2 {
            moments[2] = 0.25;
        }
        let mut l = 4;
        while l <= L_MAX {
            moments[l] = -moments[l - 2] * (l as f64 - 3.0) / (l as f64 + 2.0);
            l += 2;
        }
        // The kernel max(0, t) has moments 2 pi int max(0, t) P_l(t) dt = pi m_l.
        let values = tabulate(L_MAX, |l| PI * moments[l], |mu| mu.max(0.0));
        BlurredPhaseTable { g: f32::NAN, values }
    }

    /// Bytes held by the table.
    pub fn memory_bytes(&self) -> usize {
        self.values.len() * 4
    }

    /// Asymmetry the table was built for (NaN for [`BlurredPhaseTable::irradiance`]).
    pub fn g(&self) -> f32 {
        self.g
    }

    /// `P_w(mu)` (1/sr), bilinear; `mu` is the scattering cosine
    /// (`-dot(wo, wi)`, 1 = forward).
    #[inline]
    pub fn eval(&self, w: f32, mu: f32) -> f32 {
        let x = (w.max(0.0) / W_MAX as f32 * N_W as f32).min(N_W as f32);
        let y = ((mu.clamp(-1.0, 1.0) + 1.0) * 0.5 * N_MU as f32).min(N_MU as f32);
        let (i, j) = ((x as usize).min(N_W - 1), (y as usize).min(N_MU - 1));
        let (fx, fy) = (x - i as f32, y - j as f32);
        let at = |i: usize, j: usize| self.values[i * (N_MU + 1) + j];
        let a = at(i, j) * (1.0 - fy) + at(i, j + 1) * fy;
        let b = at(i + 1, j) * (1.0 - fy) + at(i + 1, j + 1) * fy;
        a * (1.0 - fx) + b * fx
    }
}

/// `(N_W + 1) x (N_MU + 1)` values of `sum_l (2l + 1)/(4 pi) m_l
/// exp(-l (l + 1) w^2 / 2) P_l(mu)` (clamped at zero), with `m_l =
/// moment(l)` for `l <= l_max`; the `w = 0` row is `exact(mu)`.
fn tabulate(l_max: usize, moment: impl Fn(usize) -> f64, exact: impl Fn(f64) -> f64) -> Vec<f32> {
    let mut values = vec![0f32; (N_W + 1) * (N_MU + 1)];
    let moments: Vec<f64> = (0..=l_max).map(moment).collect();
    let mut legendre = vec![0f64; l_max + 1];
    for j in 0..=N_MU {
        let mu = -1.0 + 2.0 * j as f64 / N_MU as f64;
        // P_l(mu) by the three-term recurrence.
        legendre[0] = 1.0;
        if l_max >= 1 {
            legendre[1] = mu;
        }
        for l in 2..=l_max {
            legendre[l] = ((2 * l - 1) as f64 * mu * legendre[l - 1] - (l - 1) as f64 * legendre[l - 2]) / l as f64;
        }
        for i in 0..=N_W {
            let w = W_MAX * i as f64 / N_W as f64;
            let value = if i == 0 {
                exact(mu)
            } else {
                let mut sum = 0.0;
                for (l, (p, m)) in legendre.iter().zip(&moments).enumerate() {
                    let lf = l as f64;
                    let blur = (-lf * (lf + 1.0) * w * w * 0.5).exp();
                    if blur < 1e-12 {
                        break;
                    }
                    sum += (2.0 * lf + 1.0) * m * blur * p;
                }
                (sum / (4.0 * PI)).max(0.0)
            };
            values[i * (N_MU + 1) + j] = value as f32;
        }
    }
    values
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row integrates to one over the sphere (the blur conserves energy).
    #[test]
    fn blurred_phase_integrates_to_one() {
        for g in [0.0f32, 0.35, 0.85] {
            let table = BlurredPhaseTable::new(g);
            for w in [0.0f32, 0.05, 0.3, 1.0, 3.0] {
                let n = 4000;
                let mut sum = 0.0f64;
                for k in 0..n {
                    let mu = -1.0 + 2.0 * (k as f64 + 0.5) / n as f64;
                    sum += table.eval(w, mu as f32) as f64 * 2.0 * PI * 2.0 / n as f64;
                }
                // Narrow rows for g = 0.85 (w < 0.1) are sharp peaks: linear
                // interpolation over 256 mu cells misses a few percent of them.
                let tolerance = if w < 0.1 && g > 0.5 { 0.05 } else { 5e-3 };
                assert!((sum - 1.0).abs() < tolerance, "g {g} w {w}: {sum}");
            }
        }
    }

    /// A wide blur tends to isotropic; no blur is the HG lobe.
    #[test]
    fn blurred_phase_limits() {
        let table = BlurredPhaseTable::new(0.6);
        let iso = 1.0 / (4.0 * std::f32::consts::PI);
        assert!((table.eval(3.9, 0.3) - iso).abs() < 1e-4);
        let hg = crate::phase::PhaseFunction::hg(0.6).eval_mu(-0.5);
        assert!((table.eval(0.0, -0.5) - hg).abs() < 1e-3 * hg);
    }

    /// The irradiance table against closed forms: `w = 0` is `max(0, c)`;
    /// `C(w, c) - C(w, -c) = c exp(-w^2)` for every `w` (the clamped cosine
    /// minus its mirror is the cosine, whose heat-kernel moment is
    /// `exp(-l (l + 1) w^2 / 2)` at `l = 1`); a narrow lobe (`w = 0.3`, all
    /// its mass above the horizon to 1e-6) at normal incidence gives the
    /// lobe's mean cosine `exp(-w^2)`; a wide one the isotropic `1/4`.
    #[test]
    fn irradiance_closed_forms() {
        let table = BlurredPhaseTable::irradiance();
        for c in [-1.0f32, -0.4, 0.0, 0.25, 0.7, 1.0] {
            assert!((table.eval(0.0, c) - c.max(0.0)).abs() < 1e-6, "w 0 c {c}");
        }
        for w in [0.125f32, 0.5, 1.0, 2.0] {
            for c in [0.125f32, 0.5, 0.875] {
                let odd = table.eval(w, c) - table.eval(w, -c);
                let exact = c * (-w * w).exp();
                assert!((odd - exact).abs() < 2e-4, "w {w} c {c}: {odd} vs {exact}");
            }
        }
        let narrow = table.eval(0.291_666_66, 1.0);
        assert!((narrow - (-0.291_666_66f32 * 0.291_666_66).exp()).abs() < 2e-3, "{narrow}");
        assert!((table.eval(3.9, 0.3) - 0.25).abs() < 1e-4);
        assert!((table.eval(3.9, -0.8) - 0.25).abs() < 1e-4);
    }
}
