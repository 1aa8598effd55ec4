//! The event choice at a tentative collision of free-flight sampling and the
//! weights that go with it, in the null-scattering path integral (Miller,
//! Georgiev, Jarosz 2019, "A null-scattering path integral formulation of
//! light transport"; pbrt-v4's `VolPathIntegrator::Li` and `TraceTransmittance`).
//!
//! Conventions: coefficients are per unit length (1/m, world units), RGB per
//! channel; `hero` is the channel whose majorant drew the collision (see
//! [`sample_t_maj`](super::sample_t_maj)), so every pdf below is the hero
//! channel's and every weight is "per-channel value over hero pdf". A
//! collision's `t_maj` is the majorant transmittance since the previous
//! collision, `sigma_maj` the RGB majorant there; the null coefficient is
//! `sigma_n = max(sigma_maj - sigma_a - sigma_s, 0)`.

use crate::color::Rgb;

use super::MajorantCollision;

/// What happens at a tentative collision, chosen with the hero channel's
/// probabilities `sigma_a / sigma_maj`, `sigma_s / sigma_maj` and the rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CollisionEvent {
    /// Absorption: the path ends.
    Absorb,
    /// Real scattering.
    Scatter,
    /// Null collision: the path goes on unchanged in direction.
    Null,
}

/// Per-channel weights of a null collision (each over the hero's pdf).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NullWeights {
    /// Factor of the path throughput: `T_maj sigma_n / pdf`.
    pub throughput: Rgb,
    /// Factor of a light-sampling (ratio-tracking) path pdf: `T_maj sigma_maj / pdf`.
    pub majorant: Rgb,
}

impl MajorantCollision {
    /// The null coefficient `max(sigma_maj - sigma_a - sigma_s, 0)` per channel.
    #[inline]
    pub fn sigma_n(&self) -> Rgb {
        (self.sigma_maj - self.point.sigma_a - self.point.sigma_s).map(|x| x.max(0.0))
    }

    /// The event for uniform `u` in [0, 1): absorption below
    /// `sigma_a / sigma_maj`, scattering below `(sigma_a + sigma_s) / sigma_maj`
    /// (hero channel), null collision above.
    #[inline]
    pub fn event(&self, hero: usize, u: f32) -> CollisionEvent {
        let p_absorb = self.point.sigma_a[hero] / self.sigma_maj[hero];
        let p_scatter = self.point.sigma_s[hero] / self.sigma_maj[hero];
        if u < p_absorb {
            CollisionEvent::Absorb
        } else if u < p_absorb + p_scatter {
            CollisionEvent::Scatter
        } else {
            CollisionEvent::Null
        }
    }

    /// Whether the collision is real (absorption or scattering, probability
    /// `sigma_t / sigma_maj` of the hero channel) rather than null.
    #[inline]
    pub fn is_real(&self, hero: usize, u: f32) -> bool {
        u * self.sigma_maj[hero] < self.point.sigma_a[hero] + self.point.sigma_s[hero]
    }

    /// Weights of a real collision chosen by [`Self::is_real`] and turned
    /// into scattering with the albedo as weight (no absorption event): the
    /// throughput factor `T_maj sigma_s / (T_maj sigma_t)[hero]` and the
    /// unidirectional path pdf factor `T_maj sigma_t / (T_maj sigma_t)[hero]`.
    #[inline]
    pub fn real_scatter_weights(&self, hero: usize) -> Option<NullWeights> {
        let sigma_t = self.point.sigma_a + self.point.sigma_s;
        let pdf = self.t_maj[hero] * sigma_t[hero];
        if !(pdf > 0.0) {
            return None;
        }
        Some(NullWeights { throughput: self.t_maj * self.point.sigma_s / pdf, majorant: self.t_maj * sigma_t / pdf })
    }

    /// Throughput factor of a real scattering chosen by [`Self::event`]:
    /// `T_maj sigma_s / (T_maj sigma_s)[hero]` (the hero channel's is 1).
    #[inline]
    pub fn scatter_weight(&self, hero: usize) -> Rgb {
        let sigma_s = self.point.sigma_s;
        let pdf = self.t_maj[hero] * sigma_s[hero];
        self.t_maj * sigma_s / pdf
    }

    /// Weights of a null collision chosen by [`Self::event`] (pdf
    /// `(T_maj sigma_n)[hero]`); `None` when that pdf is not positive (the
    /// hero cannot have chosen it: the path ends).
    #[inline]
    pub fn null_weights(&self, hero: usize) -> Option<NullWeights> {
        let sigma_n = self.sigma_n();
        let pdf = self.t_maj[hero] * sigma_n[hero];
        if !(pdf > 0.0) {
            return None;
        }
        Some(NullWeights { throughput: self.t_maj * sigma_n / pdf, majorant: self.t_maj * self.sigma_maj / pdf })
    }

    /// Weights of ratio tracking, which passes every collision as null
    /// (pdf `(T_maj sigma_maj)[hero]`): `throughput = T_maj sigma_n / pdf`
    /// multiplies the transmittance estimate and the unidirectional path pdf,
    /// `majorant = T_maj sigma_maj / pdf` the light-sampling path pdf.
    #[inline]
    pub fn ratio_tracking_weights(&self, hero: usize) -> NullWeights {
        let sigma_n = self.sigma_n();
        let pdf = self.t_maj[hero] * self.sigma_maj[hero];
        NullWeights { throughput: self.t_maj * sigma_n / pdf, majorant: self.t_maj * self.sigma_maj / pdf }
    }
}

/// Weight of passing the end of a free-flight range without a collision:
/// `T_maj / T_maj[hero]`, the hero's majorant transmittance being the
/// probability of getting there; `None` when that probability is not positive.
#[inline]
pub fn pass_through_weight(t_maj: Rgb, hero: usize) -> Option<Rgb> {
    let h = t_maj[hero];
    (h > 0.0).then(|| t_maj / h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::medium::MediumPoint;
    use crate::sampling::PixelSampler;

    const SIGMA_A: Rgb = Rgb::new(0.2, 0.1, 0.4);
    const SIGMA_S: Rgb = Rgb::new(0.6, 0.3, 0.2);

    fn collision(dt: f32, sigma_maj: Rgb) -> MajorantCollision {
        let point = MediumPoint { sigma_a: SIGMA_A, sigma_s: SIGMA_S, l_ve: Rgb::ZERO };
        MajorantCollision { t: dt, p: Vec3::ZERO, point, sigma_maj, t_maj: (sigma_maj * dt).exp_neg() }
    }

    #[test]
    fn event_probabilities_and_hero_weights_are_exact() {
        let sigma_maj = Rgb::new(1.6, 0.8, 1.2);
        let c = collision(0.5, sigma_maj);
        // Hero 0: p_absorb = 0.2/1.6 = 0.125, p_scatter = 0.375.
        assert_eq!(c.event(0, 0.1), CollisionEvent::Absorb);
        assert_eq!(c.event(0, 0.3), CollisionEvent::Scatter);
        assert_eq!(c.event(0, 0.6), CollisionEvent::Null);
        for hero in 0..3 {
            // The hero's own factors are value/pdf of the same number: 1 up to rounding.
            assert!((c.scatter_weight(hero)[hero] - 1.0).abs() < 1e-6);
            let w = c.null_weights(hero).unwrap();
            assert!((w.throughput[hero] - 1.0).abs() < 1e-6);
            // Null over ratio tracking: sigma_maj / sigma_n for the hero.
            let sigma_n = sigma_maj - SIGMA_A - SIGMA_S;
            let r = c.ratio_tracking_weights(hero);
            assert!((r.throughput[hero] - sigma_n[hero] / sigma_maj[hero]).abs() < 1e-6);
            assert!((r.majorant[hero] - 1.0).abs() < 1e-6);
        }
        // A majorant that equals sigma_t leaves no null collision to choose.
        assert_eq!(collision(0.5, SIGMA_A + SIGMA_S).null_weights(1), None);
        assert_eq!(pass_through_weight(Rgb::new(0.5, 0.0, 0.25), 1), None);
        assert_eq!(pass_through_weight(Rgb::new(0.5, 0.0, 0.25), 0), Some(Rgb::new(1.0, 0.0, 0.5)));
    }

    /// Monte Carlo over a homogeneous slab of thickness `d` with a majorant
    /// above `sigma_t`: the estimators built from these weights must average
    /// to `exp(-sigma_t d)` in every channel, whatever the hero.
    #[test]
    fn null_collision_weights_estimate_beer_lambert_transmittance() {
        let sigma_t = SIGMA_A + SIGMA_S;
        let sigma_maj = Rgb::new(1.6, 0.8, 1.2);
        let d = 2.0f32;
        let n = 200_000;
        let mut s = PixelSampler::from_key(7);
        for hero in 0..3 {
            let (mut free_flight, mut ratio) = ([0f64; 3], [0f64; 3]);
            let (mut free_flight_sq, mut ratio_sq) = ([0f64; 3], [0f64; 3]);
            for _ in 0..n {
                // Free flight (delta tracking with null-collision weights) and
                // ratio tracking through the same Poisson process of collisions.
                let (mut beta, mut tr) = (Some(Rgb::ONE), Rgb::ONE);
                let mut t = 0.0f32;
                loop {
                    let dt = -(1.0 - s.next_1d()).ln() / sigma_maj[hero];
                    if t + dt >= d {
                        let end = (sigma_maj * (d - t)).exp_neg();
                        let w = pass_through_weight(end, hero).unwrap();
                        beta = beta.map(|b| b * w);
                        tr *= w;
                        break;
                    }
                    t += dt;
                    let c = collision(dt, sigma_maj);
                    tr *= c.ratio_tracking_weights(hero).throughput;
                    if let Some(b) = beta {
                        beta = match c.event(hero, s.next_1d()) {
                            CollisionEvent::Null => c.null_weights(hero).map(|w| b * w.throughput),
                            _ => None,
                        };
                    }
                }
                let b = beta.unwrap_or(Rgb::ZERO);
                for ch in 0..3 {
                    free_flight[ch] += b[ch] as f64;
                    free_flight_sq[ch] += (b[ch] as f64).powi(2);
                    ratio[ch] += tr[ch] as f64;
                    ratio_sq[ch] += (tr[ch] as f64).powi(2);
                }
            }
            for ch in 0..3 {
                let exact = (-(sigma_t[ch] as f64) * d as f64).exp();
                for (sum, sq) in [(free_flight[ch], free_flight_sq[ch]), (ratio[ch], ratio_sq[ch])] {
                    let mean = sum / n as f64;
                    let stderr = ((sq / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
                    // Five standard errors: a false failure about once in 10^6 runs
                    // (the sampler is seeded, so the outcome is fixed anyway).
                    assert!((mean - exact).abs() < 5.0 * stderr + 1e-6, "hero {hero} ch {ch}: {mean} vs {exact}");
                }
            }
        }
    }
}
