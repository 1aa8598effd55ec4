//! Piecewise-constant distributions over [0, 1) and [0, 1)^2, sampled by
//! inverting their cumulative distribution (pbrt-v4 section A.4.2,
//! `PiecewiseConstant1D` and `PiecewiseConstant2D`).
//!
//! A function given as `n` non-negative values is the step function that takes
//! value `f[i]` on the bin `[i / n, (i + 1) / n)`. Sums run in `f64`; the
//! cumulative table is stored in `f32` (as pbrt does) with its last entry
//! exactly 1, so a bin of zero value has zero width and is never sampled.
//!
//! Index convention, shared by sampling and evaluation so that the pdf a
//! sampler returns always equals the pdf evaluated at the point it returned:
//! `x` lies in bin `min(floor(x n), n - 1)`.

use crate::math::Vec2;

/// A piecewise-constant density on [0, 1) built from `n >= 1` non-negative
/// values, one per bin of width `1 / n`; also a discrete distribution over
/// the `n` bins with probabilities proportional to the values.
///
/// An input that sums to zero falls back to the uniform distribution (pdf 1,
/// pmf `1 / n`); [`Distribution1D::integral`] still reports 0 so callers can
/// tell.
///
/// ```
/// use niebla::sampling::Distribution1D;
/// let d = Distribution1D::new(&[1.0, 3.0]);
/// assert_eq!(d.integral(), 2.0); // (1 + 3) / 2 bins
/// let (x, pdf, index) = d.sample_continuous(0.5);
/// assert_eq!(index, 1);
/// assert_eq!(pdf, 1.5); // 3 / 2
/// assert_eq!(pdf, d.pdf(x));
/// ```
#[derive(Clone, Debug)]
pub struct Distribution1D {
    /// The step function's values, clamped to be non-negative; all ones for
    /// the uniform fallback.
    func: Vec<f32>,
    /// Cumulative distribution at the bin edges, `n + 1` entries from 0 to 1.
    cdf: Vec<f32>,
    /// Integral of the input over [0, 1]: `sum(values) / n`.
    integral: f64,
    /// Normalization of `func` actually used: its sum over bins, `f64`.
    func_sum: f64,
}

impl Distribution1D {
    /// Build from `values` (one per bin, each finite and non-negative;
    /// negative or NaN entries are a precondition violation, checked by
    /// `debug_assert!` and treated as 0 in release builds).
    ///
    /// # Panics
    /// When `values` is empty.
    pub fn new(values: &[f32]) -> Distribution1D {
        assert!(!values.is_empty(), "Distribution1D needs at least one value");
        debug_assert!(
            values.iter().all(|v| *v >= 0.0 && v.is_finite()),
            "Distribution1D values must be finite and non-negative"
        );
        let n = values.len();
        // `!(v > 0)` also maps NaN to 0.
        let mut func: Vec<f32> = values.iter().map(|&v| if !(v > 0.0) || !v.is_finite() { 0.0 } else { v }).collect();
        let sum: f64 = func.iter().map(|&v| v as f64).sum();
        let integral = sum / n as f64;
        let func_sum = if sum > 0.0 {
            sum
        } else {
            // Uniform fallback.
            func.iter_mut().for_each(|v| *v = 1.0);
            n as f64
        };
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0f32);
        let mut running = 0.0f64;
        for &v in &func {
            running += v as f64;
            cdf.push((running / func_sum) as f32);
        }
        cdf[n] = 1.0;
        Distribution1D { func, cdf, integral, func_sum }
    }

    /// Number of bins `n`.
    #[inline]
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Always false: a distribution has at least one bin.
    #[inline]
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Integral of the input step function over [0, 1], i.e. the mean of the
    /// values (0 when they were all zero, even though sampling is then uniform).
    #[inline]
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// Bin index of `x` in [0, 1]: `min(floor(x n), n - 1)`, 0 for `x < 0`.
    #[inline]
    pub fn bin(&self, x: f32) -> usize {
        let n = self.func.len();
        ((x * n as f32).max(0.0) as usize).min(n - 1)
    }

    /// Sample a point `x` in [0, 1) from `u` in [0, 1). Returns `(x, pdf,
    /// index)`: the density of `x` on [0, 1] (equal to [`Distribution1D::pdf`]
    /// at `x`) and the bin it lies in. The map is monotonic in `u` and linear
    /// inside each bin, so stratified `u` gives stratified `x`.
    #[inline]
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let n = self.func.len();
        let index = self.find_interval(u);
        let (c0, c1) = (self.cdf[index], self.cdf[index + 1]);
        let du = if c1 > c0 { ((u - c0) / (c1 - c0)).clamp(0.0, 1.0) } else { 0.0 };
        let x = self.clamp_to_bin((index as f32 + du) / n as f32, index);
        (x, self.pdf_of_bin(index), index)
    }

    /// Density on [0, 1] of [`Distribution1D::sample_continuous`] at `x`
    /// (0 outside [0, 1]).
    #[inline]
    pub fn pdf(&self, x: f32) -> f32 {
        if !(0.0..=1.0).contains(&x) {
            return 0.0;
        }
        self.pdf_of_bin(self.bin(x))
    }

    /// Choose a bin with probability proportional to its value from `u` in
    /// [0, 1). Returns `(index, pmf)`, with `pmf` equal to
    /// [`Distribution1D::pmf`] of `index`.
    #[inline]
    pub fn sample_discrete(&self, u: f32) -> (usize, f32) {
        let index = self.find_interval(u);
        (index, self.pmf(index))
    }

    /// Like [`Distribution1D::sample_discrete`], also returning `u` remapped
    /// to a fresh uniform number in [0, 1) (its position inside the chosen
    /// bin's cdf interval), so one random number can serve two decisions.
    #[inline]
    pub fn sample_discrete_remapped(&self, u: f32) -> (usize, f32, f32) {
        let index = self.find_interval(u);
        let (c0, c1) = (self.cdf[index], self.cdf[index + 1]);
        let u_remapped = if c1 > c0 { ((u - c0) / (c1 - c0)).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 };
        (index, self.pmf(index), u_remapped)
    }

    /// Probability of bin `index` under [`Distribution1D::sample_discrete`]
    /// (0 for an index out of range).
    #[inline]
    pub fn pmf(&self, index: usize) -> f32 {
        match self.func.get(index) {
            Some(&v) => (v as f64 / self.func_sum) as f32,
            None => 0.0,
        }
    }

    /// Density of bin `index` on [0, 1]: `n` times its pmf.
    #[inline]
    fn pdf_of_bin(&self, index: usize) -> f32 {
        (self.func[index] as f64 * self.func.len() as f64 / self.func_sum) as f32
    }

    /// Largest `i < n` with `cdf[i] <= u` (binary search). Zero-width bins are
    /// skipped because the search takes the last of equal cdf entries.
    #[inline]
    fn find_interval(&self, u: f32) -> usize {
        let n = self.func.len();
        // partition_point: first entry with cdf > u; the bin starts one before.
        let first_greater = self.cdf.partition_point(|&c| c <= u);
        first_greater.saturating_sub(1).min(n - 1)
    }

    /// Nudge `x` by ulps so that [`Distribution1D::bin`] of it is `index`:
    /// `(index + du) / n` may round across a bin edge.
    #[inline]
    fn clamp_to_bin(&self, mut x: f32, index: usize) -> f32 {
        for _ in 0..4 {
            let b = self.bin(x);
            if b < index {
                x = next_up(x);
            } else if b > index {
                x = next_down(x);
            } else {
                break;
            }
        }
        x.min(ONE_MINUS_EPSILON)
    }
}

/// The largest `f32` below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Next representable `f32` above a non-negative finite `x`.
#[inline]
fn next_up(x: f32) -> f32 {
    if x == 0.0 {
        f32::from_bits(1)
    } else {
        f32::from_bits(x.to_bits() + 1)
    }
}

/// Next representable `f32` below a positive finite `x` (0 stays 0).
#[inline]
fn next_down(x: f32) -> f32 {
    if x <= 0.0 {
        0.0
    } else {
        f32::from_bits(x.to_bits() - 1)
    }
}

/// A piecewise-constant density on [0, 1)^2 built from a `width x height`
/// grid of non-negative values stored row-major (`values[row * width +
/// column]`); column `i` covers `u.x` in `[i / width, (i + 1) / width)` and row
/// `j` covers `u.y` in `[j / height, (j + 1) / height)`.
///
/// Sampling picks a row from the marginal distribution (row sums) with `u.y`,
/// then a column from that row's conditional distribution with `u.x`
/// (pbrt-v4 `PiecewiseConstant2D`). The density of a point is
/// `value / mean(values)`. An all-zero grid falls back to uniform.
///
/// ```
/// use niebla::math::Vec2;
/// use niebla::sampling::Distribution2D;
/// // 2 x 1 grid: the right half holds 3/4 of the mass.
/// let d = Distribution2D::new(&[1.0, 3.0], 2, 1);
/// let (p, pdf) = d.sample(Vec2::new(0.9, 0.5));
/// assert!(p.x >= 0.5);
/// assert_eq!(pdf, 1.5);
/// assert_eq!(d.pdf(p), pdf);
/// ```
#[derive(Clone, Debug)]
pub struct Distribution2D {
    /// One distribution over columns per row.
    conditional: Vec<Distribution1D>,
    /// Distribution over rows, from the rows' integrals.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// Build from `values.len() == width * height` values, row-major.
    ///
    /// # Panics
    /// When `width` or `height` is 0 or the length does not match.
    pub fn new(values: &[f32], width: usize, height: usize) -> Distribution2D {
        assert!(width > 0 && height > 0, "Distribution2D needs a non-empty grid");
        assert_eq!(values.len(), width * height, "Distribution2D: values.len() != width * height");
        let conditional: Vec<Distribution1D> = values.chunks_exact(width).map(Distribution1D::new).collect();
        let row_integrals: Vec<f32> = conditional.iter().map(|c| c.integral() as f32).collect();
        let marginal = Distribution1D::new(&row_integrals);
        Distribution2D { conditional, marginal }
    }

    /// Grid width (columns, along `u.x`).
    #[inline]
    pub fn width(&self) -> usize {
        self.conditional[0].len()
    }

    /// Grid height (rows, along `u.y`).
    #[inline]
    pub fn height(&self) -> usize {
        self.conditional.len()
    }

    /// Integral of the step function over [0, 1]^2: the mean of the values.
    #[inline]
    pub fn integral(&self) -> f64 {
        self.marginal.integral()
    }

    /// Sample a point in [0, 1)^2 from `u` in [0, 1)^2; returns it with its
    /// density on the unit square (equal to [`Distribution2D::pdf`] there).
    /// The point's cell is `(bin(x), bin(y))` of the conditional and marginal.
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (y, pdf_y, row) = self.marginal.sample_continuous(u.y);
        let (x, pdf_x, _) = self.conditional[row].sample_continuous(u.x);
        (Vec2::new(x, y), pdf_x * pdf_y)
    }

    /// Density on [0, 1]^2 of [`Distribution2D::sample`] at `p` (0 outside).
    #[inline]
    pub fn pdf(&self, p: Vec2) -> f32 {
        if !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
            return 0.0;
        }
        let row = self.marginal.bin(p.y);
        self.marginal.pdf_of_bin(row) * self.conditional[row].pdf(p.x)
    }

    /// Cell `(column, row)` containing `p` in [0, 1]^2, by the same rule the
    /// sampler and [`Distribution2D::pdf`] use.
    #[inline]
    pub fn cell(&self, p: Vec2) -> (usize, usize) {
        let row = self.marginal.bin(p.y);
        (self.conditional[row].bin(p.x), row)
    }

    /// Probability of cell `(column, row)`: its density times its area
    /// `1 / (width height)`.
    #[inline]
    pub fn pmf(&self, column: usize, row: usize) -> f32 {
        self.marginal.pmf(row) * self.conditional.get(row).map_or(0.0, |c| c.pmf(column))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::PixelSampler;

    /// Pearson chi-square of observed counts against expected counts, cells
    /// with expected < 5 pooled into one (Mitsuba 3's `ChiSquareTest` does
    /// the same). Returns (statistic, degrees of freedom).
    fn chi2(observed: &[f64], expected: &[f64]) -> (f64, usize) {
        let (mut stat, mut cells) = (0.0, 0usize);
        let (mut pooled_obs, mut pooled_exp) = (0.0, 0.0);
        for (o, e) in observed.iter().zip(expected) {
            if *e < 5.0 {
                pooled_obs += o;
                pooled_exp += e;
            } else {
                stat += (o - e).powi(2) / e;
                cells += 1;
            }
        }
        if pooled_exp > 0.0 {
            stat += (pooled_obs - pooled_exp).powi(2) / pooled_exp;
            cells += 1;
        }
        (stat, cells - 1)
    }

    /// Upper bound of a chi-square with `dof` degrees of freedom at tail
    /// probability ~1e-4 (Wilson-Hilferty: z = 3.72).
    fn chi2_bound(dof: usize) -> f64 {
        let k = dof as f64;
        let c = 2.0 / (9.0 * k);
        k * (1.0 - c + 3.72 * c.sqrt()).powi(3)
    }

    /// Values with zeros, a spike and a smooth part, to exercise every path.
    fn test_values(n: usize) -> Vec<f32> {
        (0..n)
            .map(|i| match i % 7 {
                0 => 0.0,
                3 => 5.0,
                _ => 1.0 + (i as f32 * 0.37).sin().abs(),
            })
            .collect()
    }

    #[test]
    fn continuous_samples_match_pdf_chi_square() {
        // 1e5 samples into 40 histogram bins that do not align with the 13
        // distribution bins; expected counts integrate the step pdf exactly.
        let d = Distribution1D::new(&test_values(13));
        let (n, bins) = (100_000usize, 40usize);
        let mut s = PixelSampler::from_key(101);
        let mut observed = vec![0f64; bins];
        for _ in 0..n {
            let (x, _, _) = d.sample_continuous(s.next_1d());
            observed[((x * bins as f32) as usize).min(bins - 1)] += 1.0;
        }
        let expected: Vec<f64> = (0..bins)
            .map(|k| {
                let (a, b) = (k as f64 / bins as f64, (k + 1) as f64 / bins as f64);
                // Exact integral of the step pdf over [a, b].
                let m = d.len();
                (0..m)
                    .map(|i| {
                        let (lo, hi) = ((i as f64 / m as f64).max(a), ((i + 1) as f64 / m as f64).min(b));
                        if hi > lo {
                            (hi - lo) * d.pdf_of_bin(i) as f64
                        } else {
                            0.0
                        }
                    })
                    .sum::<f64>()
                    * n as f64
            })
            .collect();
        let (stat, dof) = chi2(&observed, &expected);
        eprintln!("chi2 = {stat:.1}, dof = {dof}, bound = {:.1}", chi2_bound(dof));
        assert!(stat < chi2_bound(dof), "chi2 = {stat} with {dof} dof (bound {})", chi2_bound(dof));
    }

    #[test]
    fn pdf_integrates_to_one_and_matches_sample() {
        let d = Distribution1D::new(&test_values(29));
        // Midpoint rule on 29 * 64 points is exact for a step function on this grid.
        let m = 29 * 64;
        let integral: f64 = (0..m).map(|k| d.pdf((k as f32 + 0.5) / m as f32) as f64 / m as f64).sum();
        assert!((integral - 1.0).abs() < 1e-5, "integral = {integral}");
        let mut s = PixelSampler::from_key(102);
        for _ in 0..100_000 {
            let (x, pdf, index) = d.sample_continuous(s.next_1d());
            assert!((0.0..1.0).contains(&x));
            assert_eq!(d.bin(x), index);
            assert_eq!(pdf, d.pdf(x), "x = {x}");
            assert!(pdf > 0.0, "sampled a zero bin at x = {x}");
        }
        // Edges of u: 0 and the largest u below 1.
        for u in [0.0, ONE_MINUS_EPSILON] {
            let (x, pdf, _) = d.sample_continuous(u);
            assert!((0.0..1.0).contains(&x) && pdf == d.pdf(x) && pdf > 0.0);
        }
    }

    #[test]
    fn discrete_pmf_sums_to_one_and_matches_frequencies() {
        let values = test_values(11);
        let d = Distribution1D::new(&values);
        let total: f64 = (0..11).map(|i| d.pmf(i) as f64).sum();
        assert!((total - 1.0).abs() < 1e-6);
        let sum: f32 = values.iter().sum();
        for (i, v) in values.iter().enumerate() {
            assert!((d.pmf(i) - v / sum).abs() < 1e-6);
        }
        // Frequencies: each count is binomial; 5 standard deviations.
        let n = 200_000usize;
        let mut counts = [0usize; 11];
        let mut s = PixelSampler::from_key(103);
        for _ in 0..n {
            let (i, pmf) = d.sample_discrete(s.next_1d());
            assert_eq!(pmf, d.pmf(i));
            counts[i] += 1;
        }
        for (i, c) in counts.iter().enumerate() {
            let p = d.pmf(i) as f64;
            let sd = (n as f64 * p * (1.0 - p)).sqrt();
            assert!((*c as f64 - n as f64 * p).abs() <= 5.0 * sd + 1e-9, "bin {i}: {c} vs {}", n as f64 * p);
        }
    }

    #[test]
    fn all_zero_input_falls_back_to_uniform() {
        let d = Distribution1D::new(&[0.0; 4]);
        assert_eq!(d.integral(), 0.0);
        assert_eq!(d.pmf(2), 0.25);
        assert_eq!(d.pdf(0.6), 1.0);
        let (x, pdf, index) = d.sample_continuous(0.6);
        assert!((x - 0.6).abs() < 1e-6 && pdf == 1.0 && index == 2);
        let d2 = Distribution2D::new(&[0.0; 6], 3, 2);
        let (p, pdf) = d2.sample(Vec2::new(0.5, 0.7));
        assert!((p - Vec2::new(0.5, 0.7)).length() < 1e-6 && pdf == 1.0);
    }

    #[test]
    fn remapped_discrete_sample_is_uniform_within_bin() {
        // E[u'] = 1/2 and Var = 1/12 for a fresh uniform; 5 standard errors.
        let d = Distribution1D::new(&test_values(9));
        let n = 100_000;
        let mut s = PixelSampler::from_key(104);
        let mean = (0..n).map(|_| d.sample_discrete_remapped(s.next_1d()).2 as f64).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 5.0 * (1.0 / 12.0 / n as f64).sqrt(), "mean = {mean}");
    }

    #[test]
    fn two_d_samples_match_pdf_chi_square() {
        // 7 x 5 grid with zero cells; 2e5 samples into a 16 x 12 histogram
        // that does not align with the grid; expected counts integrate the
        // step pdf exactly over cell overlaps.
        let (w, h) = (7usize, 5usize);
        let values: Vec<f32> = test_values(w * h).iter().enumerate().map(|(i, v)| v * (1 + i % 3) as f32).collect();
        let d = Distribution2D::new(&values, w, h);
        let (n, bx, by) = (200_000usize, 16usize, 12usize);
        let mut s = PixelSampler::from_key(105);
        let mut observed = vec![0f64; bx * by];
        for _ in 0..n {
            let (p, pdf) = d.sample(s.next_2d());
            assert!(p.x < 1.0 && p.y < 1.0 && pdf > 0.0);
            assert_eq!(pdf, d.pdf(p));
            let (i, j) = (((p.x * bx as f32) as usize).min(bx - 1), ((p.y * by as f32) as usize).min(by - 1));
            observed[j * bx + i] += 1.0;
        }
        let overlap = |a0: f64, a1: f64, b0: f64, b1: f64| (a1.min(b1) - a0.max(b0)).max(0.0);
        let mut expected = vec![0f64; bx * by];
        for (k, e) in expected.iter_mut().enumerate() {
            let (i, j) = ((k % bx) as f64, (k / bx) as f64);
            for row in 0..h {
                for col in 0..w {
                    let ax = overlap(
                        i / bx as f64,
                        (i + 1.0) / bx as f64,
                        col as f64 / w as f64,
                        (col + 1) as f64 / w as f64,
                    );
                    let ay = overlap(
                        j / by as f64,
                        (j + 1.0) / by as f64,
                        row as f64 / h as f64,
                        (row + 1) as f64 / h as f64,
                    );
                    let center = Vec2::new((col as f32 + 0.5) / w as f32, (row as f32 + 0.5) / h as f32);
                    *e += ax * ay * d.pdf(center) as f64 * n as f64;
                }
            }
        }
        let (stat, dof) = chi2(&observed, &expected);
        eprintln!("chi2 = {stat:.1}, dof = {dof}, bound = {:.1}", chi2_bound(dof));
        assert!(stat < chi2_bound(dof), "chi2 = {stat} with {dof} dof (bound {})", chi2_bound(dof));
    }

    #[test]
    fn two_d_pdf_integrates_to_one_and_cell_pmfs_sum_to_one() {
        let (w, h) = (6usize, 4usize);
        let d = Distribution2D::new(&test_values(w * h), w, h);
        let (mx, my) = (w * 16, h * 16);
        let mut integral = 0.0f64;
        for j in 0..my {
            for i in 0..mx {
                let p = Vec2::new((i as f32 + 0.5) / mx as f32, (j as f32 + 0.5) / my as f32);
                integral += d.pdf(p) as f64 / (mx * my) as f64;
            }
        }
        assert!((integral - 1.0).abs() < 1e-5, "integral = {integral}");
        let total: f64 = (0..h).flat_map(|r| (0..w).map(move |c| (c, r))).map(|(c, r)| d.pmf(c, r) as f64).sum();
        assert!((total - 1.0).abs() < 1e-5, "sum of pmfs = {total}");
        assert!((d.pmf(3, 2) - d.pdf(Vec2::new(3.5 / 6.0, 2.5 / 4.0)) / 24.0).abs() < 1e-6);
    }
}
