//! A phase function tabulated over the scattering angle (measured or Mie),
//! interpolated linearly in `mu = cos(theta)` and sampled exactly by inverting
//! the CDF of that interpolant; cf. the tabulated phase functions of Mitsuba 3
//! (`tabphase`, also linear in `mu`) and pbrt-v4 section 11.3.

use super::error::PhaseError;
use super::tabulated_csv::{parse_csv, RowFault};
use super::ScatteringCosine;
use std::path::Path;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// Phase function given by a table `p(theta_i)` (theta in degrees from 0 =
/// forward to 180, p in 1/sr).
///
/// - **Interpolation**: linear in `mu = cos(theta)` between the rows (exact at
///   the table angles). Linear in `mu` makes the density in `mu` piecewise
///   linear, so its CDF is piecewise quadratic and is inverted exactly per
///   interval; it also matches Mitsuba 3's `tabphase`.
/// - **Normalization**: the interpolant is divided by its exact integral over
///   the sphere, [`Tabulated::normalization`] (`2 pi sum h_i (p_i + p_i+1) / 2`
///   with `h_i` the width in mu), so it integrates to 1 exactly; for a table
///   already normalized (like the Mie fog table) that factor is close to 1.
/// - **Sampling**: exact inversion of the CDF of the interpolant, so
///   `pdf == eval`. Everything is computed in f64; `eval` rounds to f32 last.
///
/// ```
/// use niebla::phase::Tabulated;
/// // A constant table is the isotropic function (normalization 4 pi).
/// let t = Tabulated::from_table(&[0.0, 90.0, 180.0], &[1.0, 1.0, 1.0]).unwrap();
/// assert!((t.eval_mu(0.2) - 0.25 / std::f32::consts::PI).abs() < 1e-7);
/// assert!((t.normalization() - 4.0 * std::f64::consts::PI).abs() < 1e-12);
/// ```
#[derive(Clone, Debug)]
pub struct Tabulated {
    /// Table angles in degrees as given, ascending from 0 to 180.
    theta_deg: Vec<f64>,
    /// Node cosines, ascending from -1 to 1 (the rows in reverse order).
    mu: Vec<f64>,
    /// Normalized p at the nodes, 1/sr, in the order of `mu`.
    p: Vec<f64>,
    /// CDF over mu at the nodes: 0 at mu = -1, 1 at mu = +1.
    cdf: Vec<f64>,
    /// Integral of the given interpolant over the sphere (divided out).
    normalization: f64,
    /// Exact mean cosine of the normalized interpolant.
    mean_cosine: f64,
}

impl Tabulated {
    /// Build from angles `theta_deg` (degrees, strictly increasing from
    /// exactly 0 to exactly 180) and values `p >= 0` (1/sr, any scale: the
    /// interpolant is renormalized). Errors name the 1-based row.
    pub fn from_table(theta_deg: &[f64], p: &[f64]) -> Result<Tabulated, PhaseError> {
        if theta_deg.len() != p.len() {
            return Err(PhaseError::Table {
                row: theta_deg.len().min(p.len()) + 1,
                what: format!("theta has {} values but p has {}: expected one p per angle", theta_deg.len(), p.len()),
            });
        }
        Tabulated::build(theta_deg, p, "theta", "p").map_err(|fault| PhaseError::Table {
            row: fault.index.map_or(theta_deg.len(), |i| i + 1),
            what: fault.what,
        })
    }

    /// Load column `column` (p in 1/sr) of a CSV file: lines starting with
    /// `#` are comments, the first other line is the header, and the angle
    /// column is named `theta_deg` (or `theta`), in degrees. Errors name the
    /// file, the line and what was expected.
    pub fn from_csv_file(path: &Path, column: &str) -> Result<Tabulated, PhaseError> {
        let text =
            std::fs::read_to_string(path).map_err(|source| PhaseError::Io { path: path.to_path_buf(), source })?;
        Tabulated::from_csv_str(&text, column, &path.display().to_string())
    }

    /// Like [`Tabulated::from_csv_file`] for text already in memory;
    /// `source_name` names it in errors.
    pub fn from_csv_str(text: &str, column: &str, source_name: &str) -> Result<Tabulated, PhaseError> {
        let csv = parse_csv(text, column, source_name)?;
        Tabulated::build(&csv.theta_deg, &csv.p, csv.theta_name, column).map_err(|fault| PhaseError::Csv {
            source_name: source_name.to_string(),
            line: fault.index.map_or(csv.last_line, |i| csv.lines[i]),
            what: fault.what,
        })
    }

    /// Validate the rows, then build nodes, normalization, CDF and mean cosine.
    fn build(theta_deg: &[f64], p: &[f64], theta_name: &str, p_name: &str) -> Result<Tabulated, RowFault> {
        let n = theta_deg.len();
        if n < 2 {
            return Err(RowFault {
                index: None,
                what: format!("found {n} data rows: expected at least 2 (theta = 0 and 180 deg)"),
            });
        }
        for (i, (&theta, &value)) in theta_deg.iter().zip(p).enumerate() {
            let fault = |what: String| Err(RowFault { index: Some(i), what });
            if !theta.is_finite() {
                return fault(format!("{theta_name} = {theta}: expected a finite angle in degrees"));
            }
            if !value.is_finite() {
                return fault(format!("{p_name} = {value}: expected a finite value in 1/sr"));
            }
            if value < 0.0 {
                return fault(format!("{p_name} = {value} is negative: expected p >= 0 (1/sr)"));
            }
            if i > 0 && theta <= theta_deg[i - 1] {
                return fault(format!(
                    "{theta_name} = {theta} deg does not increase (previous row {} deg): \
                     expected rows sorted by strictly increasing angle",
                    theta_deg[i - 1]
                ));
            }
        }
        if theta_deg[0] != 0.0 {
            return Err(RowFault {
                index: Some(0),
                what: format!(
                    "table starts at {theta_name} = {} deg: expected the first row at 0 deg \
                     (theta must span 0..180)",
                    theta_deg[0]
                ),
            });
        }
        if theta_deg[n - 1] != 180.0 {
            return Err(RowFault {
                index: Some(n - 1),
                what: format!(
                    "table ends at {theta_name} = {} deg: expected the last row at 180 deg \
                     (theta must span 0..180)",
                    theta_deg[n - 1]
                ),
            });
        }

        // Nodes in ascending mu (rows reversed); endpoints exact.
        let cos_deg = |t: f64| {
            if t == 0.0 {
                1.0
            } else if t == 180.0 {
                -1.0
            } else {
                t.to_radians().cos()
            }
        };
        let mu: Vec<f64> = theta_deg.iter().rev().map(|&t| cos_deg(t)).collect();
        let values: Vec<f64> = p.iter().rev().copied().collect();
        for j in 1..n {
            if mu[j] <= mu[j - 1] {
                let row = n - 1 - j;
                return Err(RowFault {
                    index: Some(row),
                    what: format!(
                        "{theta_name} = {} deg has the same cosine in double precision as the \
                         next row: expected rows farther apart",
                        theta_deg[row]
                    ),
                });
            }
        }
        Tabulated::from_nodes(theta_deg.to_vec(), mu, values, p_name)
    }

    /// Build from nodes in cosine: `mu` strictly increasing from exactly -1
    /// (backward) to exactly 1 (forward) and values `p >= 0` (1/sr, any
    /// scale: renormalized), interpolated linearly in `mu` like Mitsuba 3's
    /// `tabphase` (whose regularly spaced table is `mu_i = -1 + 2 i / (n - 1)`).
    /// Errors name the 1-based node.
    ///
    /// ```
    /// use niebla::phase::Tabulated;
    /// // p = 1 + mu: normalization 4 pi, mean cosine 1/3.
    /// let t = Tabulated::from_cosines(&[-1.0, 1.0], &[0.0, 2.0]).unwrap();
    /// assert!((t.mean_cosine_f64() - 1.0 / 3.0).abs() < 1e-12);
    /// ```
    pub fn from_cosines(mu: &[f64], p: &[f64]) -> Result<Tabulated, PhaseError> {
        let fault = |index: usize, what: String| PhaseError::Table { row: index + 1, what };
        let n = mu.len();
        if n != p.len() {
            return Err(fault(
                n.min(p.len()),
                format!("mu has {n} values but p has {}: expected one p per cosine", p.len()),
            ));
        }
        if n < 2 {
            return Err(fault(n, format!("found {n} nodes: expected at least 2 (mu = -1 and 1)")));
        }
        for (i, (&m, &value)) in mu.iter().zip(p).enumerate() {
            if !m.is_finite() || !(-1.0..=1.0).contains(&m) {
                return Err(fault(i, format!("mu = {m}: expected a cosine in [-1, 1]")));
            }
            if !value.is_finite() || value < 0.0 {
                return Err(fault(i, format!("p = {value}: expected a finite value >= 0 (1/sr)")));
            }
            if i > 0 && m <= mu[i - 1] {
                return Err(fault(
                    i,
                    format!(
                        "mu = {m} does not increase (previous node {}): expected strictly increasing cosines",
                        mu[i - 1]
                    ),
                ));
            }
        }
        if mu[0] != -1.0 {
            return Err(fault(0, format!("the first node is mu = {}: expected -1 (mu must span -1..1)", mu[0])));
        }
        if mu[n - 1] != 1.0 {
            return Err(fault(n - 1, format!("the last node is mu = {}: expected 1 (mu must span -1..1)", mu[n - 1])));
        }
        let theta_deg: Vec<f64> = mu.iter().rev().map(|&m| m.acos().to_degrees()).collect();
        Tabulated::from_nodes(theta_deg, mu.to_vec(), p.to_vec(), "p")
            .map_err(|f| PhaseError::Table { row: f.index.map_or(n, |i| i + 1), what: f.what })
    }

    /// Normalization, CDF and mean cosine of checked nodes (`mu` ascending,
    /// `values` at the nodes, `theta_deg` the same nodes in degrees ascending).
    fn from_nodes(
        theta_deg: Vec<f64>,
        mu: Vec<f64>,
        mut values: Vec<f64>,
        p_name: &str,
    ) -> Result<Tabulated, RowFault> {
        let n = mu.len();

        // Normalization: exact integral of the interpolant over the sphere.
        let interval_mass = |j: usize, v: &[f64]| std::f64::consts::PI * (mu[j + 1] - mu[j]) * (v[j] + v[j + 1]);
        let normalization: f64 = (0..n - 1).map(|j| interval_mass(j, &values)).sum();
        if normalization <= 0.0 {
            return Err(RowFault {
                index: None,
                what: format!("all {p_name} values are zero: expected a positive integral over the sphere"),
            });
        }
        for v in &mut values {
            *v /= normalization;
        }

        // CDF in mu and mean cosine (exact for the piecewise linear density).
        let mut cdf = Vec::with_capacity(n);
        cdf.push(0.0);
        let mut mean_cosine = 0.0;
        for j in 0..n - 1 {
            cdf.push(cdf[j] + interval_mass(j, &values));
            let (m0, m1, p0, p1) = (mu[j], mu[j + 1], values[j], values[j + 1]);
            mean_cosine += TWO_PI * (m1 - m0) / 6.0 * (p0 * (2.0 * m0 + m1) + p1 * (m0 + 2.0 * m1));
        }
        let total = cdf[n - 1];
        for c in &mut cdf {
            *c = (*c / total).min(1.0);
        }
        cdf[n - 1] = 1.0;

        Ok(Tabulated { theta_deg, mu, p: values, cdf, normalization, mean_cosine })
    }

    /// The table angles in degrees, ascending.
    pub fn theta_deg(&self) -> &[f64] {
        &self.theta_deg
    }

    /// Integral over the sphere of the interpolant of the table as given
    /// (1/sr times sr, dimensionless); the table was divided by it.
    pub fn normalization(&self) -> f64 {
        self.normalization
    }

    /// `p(mu)` of the normalized interpolant, 1/sr.
    #[inline]
    pub fn eval_mu(&self, mu: f32) -> f32 {
        self.eval_mu_f64(mu as f64) as f32
    }

    /// `p` of a scattering cosine, 1/sr (looked up in double precision).
    #[inline]
    pub fn eval_cosine(&self, c: ScatteringCosine) -> f32 {
        self.eval_mu_f64(c.mu_f64()) as f32
    }

    /// `p(mu)` in double precision, 1/sr.
    pub fn eval_mu_f64(&self, mu: f64) -> f64 {
        let n = self.mu.len();
        let mu = mu.clamp(-1.0, 1.0);
        let j = self.mu.partition_point(|&m| m <= mu).clamp(1, n - 1) - 1;
        let t = ((mu - self.mu[j]) / (self.mu[j + 1] - self.mu[j])).clamp(0.0, 1.0);
        self.p[j] * (1.0 - t) + self.p[j + 1] * t
    }

    /// Scattering cosine by exact inversion of the CDF (u = 0 backward,
    /// u -> 1 forward).
    #[inline]
    pub fn sample_mu(&self, u: f32) -> f32 {
        self.sample_cosine(u).mu
    }

    /// Exact inversion: find the interval `j` with `cdf_j <= u < cdf_j+1`,
    /// then solve `2 pi h (p0 t + (p1 - p0) t^2 / 2) = u - cdf_j` for the
    /// fraction `t` of the interval, as `t = 2c / (p0 + sqrt(p0^2 + 2 (p1 - p0) c))`
    /// with `c = (u - cdf_j) / (2 pi h)` (no cancellation when `p1 ~ p0`).
    #[inline]
    pub fn sample_cosine(&self, u: f32) -> ScatteringCosine {
        let n = self.mu.len();
        let xi = u as f64;
        let j = self.cdf.partition_point(|&c| c <= xi).clamp(1, n - 1) - 1;
        let (m0, m1, p0, p1) = (self.mu[j], self.mu[j + 1], self.p[j], self.p[j + 1]);
        let h = m1 - m0;
        let c = (xi - self.cdf[j]).max(0.0) / (TWO_PI * h);
        let denom = p0 + (p0 * p0 + 2.0 * (p1 - p0) * c).max(0.0).sqrt();
        let t = if denom > 0.0 { (2.0 * c / denom).clamp(0.0, 1.0) } else { 0.0 };
        // 1 - mu and 1 + mu as sums of non-negative terms.
        let one_minus_mu = (1.0 - m1) + (1.0 - t) * h;
        let one_plus_mu = (1.0 + m0) + t * h;
        ScatteringCosine::from_complements(one_minus_mu as f32, one_plus_mu as f32)
    }

    /// Exact mean cosine of the normalized interpolant.
    pub fn mean_cosine(&self) -> f32 {
        self.mean_cosine as f32
    }

    /// Mean cosine in double precision.
    pub fn mean_cosine_f64(&self) -> f64 {
        self.mean_cosine
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tabulated_linear_in_mu_has_closed_form_normalization_and_mean() {
        // p = a + b mu with mu nodes at 0, 90, 180 deg: exactly linear, so the
        // interpolant is the function itself; integral 4 pi a, mean cosine b / (3 a).
        let (a, b) = (2.0, 1.5);
        let t = Tabulated::from_table(&[0.0, 90.0, 180.0], &[a + b, a, a - b]).unwrap();
        assert!((t.normalization() - 4.0 * std::f64::consts::PI * a).abs() < 1e-12);
        assert!((t.mean_cosine_f64() - b / (3.0 * a)).abs() < 1e-12);
    }

    #[test]
    fn tabulated_sample_inverts_piecewise_quadratic_cdf() {
        let t = Tabulated::from_table(&[0.0, 30.0, 100.0, 180.0], &[5.0, 0.0, 2.0, 0.5]).unwrap();
        // Numerical CDF of eval by fine midpoint quadrature in mu.
        for u in [0.05f32, 0.3, 0.6, 0.9, 0.99] {
            let mu = t.sample_cosine(u).mu_f64();
            let steps = 200_000;
            let h = (mu + 1.0) / steps as f64;
            let cdf: f64 = (0..steps).map(|i| TWO_PI * t.eval_mu_f64(-1.0 + (i as f64 + 0.5) * h) * h).sum();
            assert!((cdf - u as f64).abs() < 1e-6, "u {u}: F = {cdf}");
        }
    }

    #[test]
    fn tabulated_zero_interval_is_never_sampled() {
        // p = 0 on 30..100 deg: no sample may land strictly inside.
        let t = Tabulated::from_table(&[0.0, 30.0, 100.0, 180.0], &[1.0, 0.0, 0.0, 1.0]).unwrap();
        let (lo, hi) = (100f64.to_radians().cos(), 30f64.to_radians().cos());
        for i in 0..10_000 {
            let mu = t.sample_cosine(i as f32 / 10_000.0).mu_f64();
            assert!(mu <= lo + 1e-6 || mu >= hi - 1e-6, "mu {mu}");
        }
    }
}
