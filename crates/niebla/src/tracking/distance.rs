//! Distance sampling with a piecewise-exponential density built from a ray's
//! majorant segments: `pdf(t) = s(t) exp(-integral_0^t s) / (1 - exp(-S))`
//! on the ray's medium range, where `s` is constant per segment (e.g. the
//! segment's density bound times the channel-averaged extinction) and `S` its
//! total. It is exactly computable, so it can be combined by MIS with
//! equiangular sampling in heterogeneous media too.

use std::ops::ControlFlow;

use super::along_ray::DensityAlongRay;

/// The piecewise-constant sampling rate along one ray range.
#[derive(Clone, Debug, Default)]
pub struct MajorantProfile {
    /// `(t0, t1, rate)` pieces in increasing `t`, rate > 0.
    pieces: Vec<(f32, f32, f32)>,
    /// Integral of the rate over all pieces (may be infinite).
    total: f32,
}

impl MajorantProfile {
    /// Profile of `r` with rate `d_max * rate_per_density` per segment.
    pub fn new<R: DensityAlongRay>(r: &R, rate_per_density: f32) -> MajorantProfile {
        let mut pieces = Vec::new();
        let mut total = 0.0f32;
        let _ = r.segments(|s| {
            let rate = s.d_max * rate_per_density;
            if rate > 0.0 && s.t1 > s.t0 {
                pieces.push((s.t0, s.t1, rate));
                total += rate * (s.t1 - s.t0);
            }
            ControlFlow::Continue(())
        });
        MajorantProfile { pieces, total }
    }

    /// True when no distance can be sampled (no medium with a positive rate).
    pub fn is_empty(&self) -> bool {
        self.pieces.is_empty()
    }

    /// `1 - exp(-S)`: probability mass of the range, computed stably.
    #[inline]
    fn mass(&self) -> f32 {
        -(-self.total).exp_m1()
    }

    /// A distance with the profile's density, from `u` in [0, 1).
    pub fn sample(&self, u: f32) -> Option<f32> {
        if self.pieces.is_empty() {
            return None;
        }
        // Target optical depth: F(t) = (1 - exp(-M(t))) / mass = u.
        let target = -(-u * self.mass()).ln_1p();
        let mut acc = 0.0f32;
        for &(t0, t1, rate) in &self.pieces {
            let depth = rate * (t1 - t0);
            if acc + depth >= target {
                return Some((t0 + (target - acc) / rate).min(t1));
            }
            acc += depth;
        }
        self.pieces.last().map(|p| p.1)
    }

    /// `exp(-integral_0^t rate)`: the profile's transmittance up to `t`.
    pub fn transmittance(&self, t: f32) -> f32 {
        let mut acc = 0.0f32;
        for &(t0, t1, rate) in &self.pieces {
            if t <= t0 {
                break;
            }
            acc += rate * (t.min(t1) - t0);
        }
        (-acc).exp()
    }

    /// Density of [`MajorantProfile::sample`] at `t` (0 outside the pieces).
    pub fn pdf(&self, t: f32) -> f32 {
        let mut acc = 0.0f32;
        for &(t0, t1, rate) in &self.pieces {
            if t < t0 {
                return 0.0;
            }
            if t <= t1 {
                return rate * (-(acc + rate * (t - t0))).exp() / self.mass();
            }
            acc += rate * (t1 - t0);
        }
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::PixelSampler;
    use crate::tracking::{DensitySegment, UnitDensity};

    struct Steps(Vec<DensitySegment>);
    impl DensityAlongRay for Steps {
        fn density(&self, _t: f32) -> f32 {
            unreachable!()
        }
        fn segments<F: FnMut(DensitySegment) -> ControlFlow<()>>(&self, mut f: F) -> ControlFlow<()> {
            for s in &self.0 {
                f(*s)?;
            }
            ControlFlow::Continue(())
        }
    }

    #[test]
    fn profile_sampler_matches_its_pdf_and_integrates_to_one() {
        let seg = |t0, t1, d| DensitySegment { t0, t1, d_min: 0.0, d_max: d };
        let r = Steps(vec![seg(0.5, 1.0, 2.0), seg(1.0, 1.5, 0.0), seg(1.5, 3.0, 0.7), seg(3.0, 3.2, 5.0)]);
        let p = MajorantProfile::new(&r, 1.3);
        // pdf integrates to 1 (midpoint rule).
        let n = 200_000;
        let integral: f64 = (0..n).map(|i| p.pdf(3.5 * (i as f32 + 0.5) / n as f32) as f64 * 3.5 / n as f64).sum();
        assert!((integral - 1.0).abs() < 1e-3, "{integral}");
        // Histogram of samples against the pdf: 35 bins over [0, 3.5].
        let mut hist = [0u32; 35];
        let mut s = PixelSampler::from_key(5);
        let m = 200_000;
        for _ in 0..m {
            let t = p.sample(s.next_1d()).unwrap();
            assert!(p.pdf(t) > 0.0);
            hist[((t / 0.1) as usize).min(34)] += 1;
        }
        let mut chi2 = 0.0;
        let mut dof = 0;
        for (i, &h) in hist.iter().enumerate() {
            let e: f64 = (0..100).map(|k| p.pdf(0.1 * i as f32 + 0.001 * (k as f32 + 0.5)) as f64 * 0.001).sum::<f64>()
                * m as f64;
            if e > 5.0 {
                chi2 += (h as f64 - e).powi(2) / e;
                dof += 1;
            } else {
                assert!(h < 20, "bin {i}: {h} samples where {e} expected");
            }
        }
        // 99.9% quantile of chi-square with ~25 dof is about 52.6.
        assert!(chi2 < 52.6 + 2.0 * (dof as f64 - 25.0).max(0.0), "chi2 {chi2} dof {dof}");
        // Unbounded homogeneous: plain exponential.
        let u = MajorantProfile::new(&UnitDensity { t0: 0.0, t1: f32::INFINITY }, 2.0);
        assert!((u.pdf(0.5) - 2.0 * (-1.0f32).exp()).abs() < 1e-6);
        assert!((u.sample(1.0 - (-1.0f32).exp()).unwrap() - 0.5).abs() < 1e-5);
    }
}
