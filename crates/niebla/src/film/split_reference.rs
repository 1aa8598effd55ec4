//! A reference image made of two independent renders ("halves") of the same
//! scene, and the relative MSE of an image against it with the reference's
//! own noise removed.
//!
//! With `R = (n_a A + n_b B) / (n_a + n_b)` the sample-count weighted mean of
//! two independent unbiased renders `A` (`n_a` samples per pixel) and `B`
//! (`n_b`), and `x` an image independent of both, per pixel and channel
//! `E[(x - R)^2] = (x - T)^2 + Var(R)` (`T` the true value). With `s^2` the
//! per-sample variance, `Var(A) = s^2 / n_a`, `Var(B) = s^2 / n_b` and
//! `Var(R) = s^2 / (n_a + n_b)`, so
//! `E[(A - B)^2] = s^2 (n_a + n_b) / (n_a n_b)` and
//! `w (A - B)^2` with `w = n_a n_b / (n_a + n_b)^2` (1/4 for equal halves) is
//! an unbiased estimate of `Var(R)`. Dividing both by the same denominator
//! as [`Image::relative_mse`] against `R` (`R^2 + eps`,
//! `eps = (0.01 mean(R))^2`) gives the reference-noise term of that measure,
//! [`SplitReference::noise`], and the noise-corrected relative MSE
//! `relMSE(x, R) - noise`. (`A - B` is uncorrelated with `R` for equal
//! halves and nearly so otherwise, so the shared denominator does not bias
//! the noise term to first order.)
//!
//! What is left: the denominator uses the noisy `R` instead of `T`. To
//! second order in the reference's relative noise `v = Var(R) / T^2` the
//! corrected measure's expectation per pixel is
//! `r^2 + 4 r v + 3 r^2 v` with `r = (x - T) / T` (for `eps` small against
//! `T^2`), against `r^2 + v + 4 r v + 3 r^2 v` uncorrected: the correction
//! removes the term of order `v`, the rest is of order `|r| v`. So the
//! reference must still be good (`v` small) where the method is far off;
//! heavy-tailed noise (fireflies) makes the one-pair estimate of `Var(R)`
//! itself noisy ([`SplitReference::noise_standard_error`]).

use super::Image;

/// A reference image: one render, or the weighted mean of two independent
/// renders of the same scene and size (which also estimates its own noise).
#[derive(Clone, Debug)]
pub struct SplitReference {
    /// The reference: the one image, or the sample-count weighted mean of
    /// the two halves.
    mean: Image,
    /// The halves and `w = n_a n_b / (n_a + n_b)^2`, when there are two.
    halves: Option<(Image, Image, f64)>,
}

impl SplitReference {
    /// A reference of one image: no noise estimate.
    pub fn single(image: Image) -> SplitReference {
        SplitReference { mean: image, halves: None }
    }

    /// The reference of two independent renders `a` (`spp_a` samples per
    /// pixel) and `b` (`spp_b`) of the same scene: their sample-count
    /// weighted mean. Panics if their sizes differ or a sample count is 0
    /// (callers check files before).
    pub fn halves(a: Image, spp_a: u64, b: Image, spp_b: u64) -> SplitReference {
        assert_eq!((a.width, a.height), (b.width, b.height), "the halves of a reference must be the same size");
        assert!(spp_a > 0 && spp_b > 0, "the halves of a reference need samples");
        let (na, nb) = (spp_a as f64, spp_b as f64);
        let (wa, wb) = (na / (na + nb), nb / (na + nb));
        let mut mean = Image::new(a.width, a.height);
        for ((m, pa), pb) in mean.pixels.iter_mut().zip(&a.pixels).zip(&b.pixels) {
            for c in 0..3 {
                m[c] = (wa * pa[c] as f64 + wb * pb[c] as f64) as f32;
            }
        }
        SplitReference { mean, halves: Some((a, b, wa * wb)) }
    }

    /// The reference image.
    pub fn mean(&self) -> &Image {
        &self.mean
    }

    /// Relative MSE of `image` against the reference
    /// ([`Image::relative_mse`]); its expectation includes the reference's
    /// own noise ([`SplitReference::noise`]).
    pub fn relative_mse(&self, image: &Image) -> f64 {
        image.relative_mse(&self.mean)
    }

    /// The per-pixel, per-channel terms `w (A - B)^2 / (R^2 + eps)` of the
    /// noise estimate (see the module notes), or `None` for a single image.
    fn noise_terms(&self) -> Option<Vec<f64>> {
        let (a, b, w) = self.halves.as_ref()?;
        let mean = self.mean.mean().average() as f64;
        let eps = (0.01 * mean).powi(2).max(f64::MIN_POSITIVE);
        let mut terms = Vec::with_capacity(3 * self.mean.pixels.len());
        for ((r, pa), pb) in self.mean.pixels.iter().zip(&a.pixels).zip(&b.pixels) {
            for c in 0..3 {
                let (r, d) = (r[c] as f64, pa[c] as f64 - pb[c] as f64);
                terms.push(w * d * d / (r * r + eps));
            }
        }
        Some(terms)
    }

    /// The reference's own noise as it enters [`SplitReference::relative_mse`]:
    /// the estimate of the mean over pixels and channels of
    /// `Var(R) / (R^2 + eps)` from the two halves; `None` for a single image.
    pub fn noise(&self) -> Option<f64> {
        let terms = self.noise_terms()?;
        Some(terms.iter().sum::<f64>() / terms.len().max(1) as f64)
    }

    /// Standard error of [`SplitReference::noise`] from the spread of its
    /// per-pixel terms (treated as independent); `None` for a single image.
    pub fn noise_standard_error(&self) -> Option<f64> {
        let terms = self.noise_terms()?;
        let n = terms.len().max(2) as f64;
        let mean = terms.iter().sum::<f64>() / n;
        let variance = terms.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / (n - 1.0);
        Some((variance / n).sqrt())
    }

    /// Relative MSE of `image` with the reference's noise removed:
    /// `relative_mse(image) - noise()`, an estimate of the relative MSE
    /// against the true image (it can come out slightly negative when the
    /// image is closer to the truth than the reference's noise resolves);
    /// `None` for a single image. `image` must be independent of both halves.
    pub fn noise_corrected_relative_mse(&self, image: &Image) -> Option<f64> {
        Some(self.relative_mse(image) - self.noise()?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::sampling::hash_u64;

    /// Uniform and standard normal numbers from a hashed counter.
    struct Numbers(u64);

    impl Numbers {
        fn uniform(&mut self) -> f64 {
            self.0 += 1;
            ((hash_u64(self.0) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        }
    }

    const W: u32 = 192;
    const H: u32 = 128;

    /// A smooth positive truth in [0.2, 2].
    fn truth() -> Vec<[f64; 3]> {
        (0..W * H)
            .map(|i| {
                let (x, y) = ((i % W) as f64 / W as f64, (i / W) as f64 / H as f64);
                let t = 1.1 + 0.9 * (6.0 * x).sin() * (4.0 * y).cos();
                [t, 0.8 * t + 0.2, 2.2 - t]
            })
            .collect()
    }

    fn image(values: &[[f64; 3]]) -> Image {
        let mut im = Image::new(W, H);
        for (p, v) in im.pixels.iter_mut().zip(values) {
            *p = Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32);
        }
        im
    }

    /// Truth plus Gaussian noise of relative standard deviation `rel_sd`.
    fn noisy(truth: &[[f64; 3]], rel_sd: f64, numbers: &mut Numbers) -> Vec<[f64; 3]> {
        truth.iter().map(|t| t.map(|v| v * (1.0 + rel_sd * numbers.normal()))).collect()
    }

    /// The corrected measure's error against the true relative MSE of `x`,
    /// with the standard error of that error from its per-pixel terms.
    fn error_and_se(truth: &[[f64; 3]], x: &Image, reference: &SplitReference) -> (f64, f64, f64) {
        let r_mean = reference.mean().mean().average() as f64;
        let eps = (0.01 * r_mean).powi(2);
        let (a, b, w) = reference.halves.as_ref().unwrap();
        let mut diffs = Vec::new();
        let mut true_sum = 0.0;
        for (i, t) in truth.iter().enumerate() {
            for (c, &tc) in t.iter().enumerate() {
                let (xv, r) = (x.pixels[i][c] as f64, reference.mean().pixels[i][c] as f64);
                let d = a.pixels[i][c] as f64 - b.pixels[i][c] as f64;
                let estimate = ((xv - r).powi(2) - w * d * d) / (r * r + eps);
                let exact = (xv - tc).powi(2) / (tc * tc + eps);
                true_sum += exact;
                diffs.push(estimate - exact);
            }
        }
        let n = diffs.len() as f64;
        let mean = diffs.iter().sum::<f64>() / n;
        let var = diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt(), true_sum / n)
    }

    #[test]
    fn the_noise_of_equal_halves_is_removed_from_an_exact_image() {
        // The image is the truth: its true relative MSE is 0, and against a
        // reference of relative noise 0.02 (v = 4e-4) the plain measure is v.
        let mut numbers = Numbers(1);
        let t = truth();
        let (rel_sd_half, v) = (0.02 * 2f64.sqrt(), 4e-4);
        let a = image(&noisy(&t, rel_sd_half, &mut numbers));
        let b = image(&noisy(&t, rel_sd_half, &mut numbers));
        let reference = SplitReference::halves(a, 64, b, 64);
        let x = image(&t);
        let (error, se, true_mse) = error_and_se(&t, &x, &reference);
        assert!(true_mse < 1e-12);
        let corrected = reference.noise_corrected_relative_mse(&x).unwrap();
        let plain = reference.relative_mse(&x);
        // The test resolves v: 4 standard errors are a small part of it.
        assert!(4.0 * se < 0.05 * v, "se {se}");
        assert!((corrected - true_mse).abs() < 4.0 * se, "corrected {corrected}, error {error}, se {se}");
        // v to second order: |v^2| terms are ~1e-7, far below 4 se.
        assert!((plain - v).abs() < 4.0 * se + 4.0 * v * v, "plain {plain}, v {v}, se {se}");
        let noise = reference.noise().unwrap();
        assert!((noise - v).abs() < 4.0 * reference.noise_standard_error().unwrap() + 4.0 * v * v, "noise {noise}");
    }

    #[test]
    fn unequal_halves_and_a_biased_noisy_method() {
        // Halves of 3:1 samples (relative sd 0.02 of the mean: v = 4e-4);
        // the method is off by +-10% per pixel (random sign) with 5% noise.
        let mut numbers = Numbers(1000);
        let t = truth();
        let v: f64 = 4e-4;
        let (na, nb) = (96u64, 32u64);
        let n = (na + nb) as f64;
        let sd_a = (v * n / na as f64).sqrt();
        let sd_b = (v * n / nb as f64).sqrt();
        let a = image(&noisy(&t, sd_a, &mut numbers));
        let b = image(&noisy(&t, sd_b, &mut numbers));
        let reference = SplitReference::halves(a, na, b, nb);
        let mut rs = Vec::new();
        let x_values: Vec<[f64; 3]> = t
            .iter()
            .map(|p| {
                p.map(|tv| {
                    let sign = if numbers.uniform() < 0.5 { -1.0 } else { 1.0 };
                    let r = 0.1 * sign + 0.05 * numbers.normal();
                    rs.push(r);
                    tv * (1.0 + r)
                })
            })
            .collect();
        let x = image(&x_values);
        let (_, se, true_mse) = error_and_se(&t, &x, &reference);
        // The second-order remainder of the module notes, per pixel
        // 4 r v + 3 r^2 v, averaged (small: the signs of r cancel).
        let remainder = rs.iter().map(|r| 4.0 * r * v + 3.0 * r * r * v).sum::<f64>() / rs.len() as f64;
        assert!(4.0 * se + remainder.abs() < 0.25 * v, "se {se}, remainder {remainder}");
        let corrected = reference.noise_corrected_relative_mse(&x).unwrap();
        let plain = reference.relative_mse(&x);
        assert!(
            (corrected - true_mse).abs() < 4.0 * se + remainder.abs(),
            "corrected {corrected}, true {true_mse}, se {se}, remainder {remainder}"
        );
        // Uncorrected, the reference's noise stays in: about v too high.
        assert!((plain - true_mse - v).abs() < 0.25 * v, "plain {plain}, true {true_mse}");
    }

    #[test]
    fn a_single_image_has_no_noise_estimate() {
        let t = truth();
        let reference = SplitReference::single(image(&t));
        assert_eq!(reference.noise(), None);
        assert_eq!(reference.noise_corrected_relative_mse(&image(&t)), None);
        assert_eq!(reference.relative_mse(&image(&t)), 0.0);
    }
}
