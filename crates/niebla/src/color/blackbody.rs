//! Blackbody color: Planck's law integrated against the CIE 1931 2-degree
//! color matching functions, converted to linear Rec.709 RGB and normalized
//! to unit luminance (a medium's `temperature` in Kelvin maps to this
//! normalized color times its `emission_scale`).
//!
//! The color matching functions are the CIE 1931 2-degree standard observer
//! tabulated at 5 nm from 380 to 780 nm (CIE 15, `data/cie1931_2deg_5nm.csv`),
//! integrated with the trapezoid rule.

use super::Rgb;

/// The CIE 1931 2-degree table shipped with niebla: `lambda_nm,x_bar,y_bar,z_bar`.
pub const CIE_1931_CSV: &str = include_str!("../../data/cie1931_2deg_5nm.csv");

/// The CIE 1931 table as (wavelength in nm, [x_bar, y_bar, z_bar]) rows.
pub fn cie_1931_table() -> Vec<(f64, [f64; 3])> {
    CIE_1931_CSV
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("lambda"))
        .filter_map(|l| {
            let v: Vec<f64> = l.split(',').filter_map(|x| x.trim().parse().ok()).collect();
            (v.len() == 4).then(|| (v[0], [v[1], v[2], v[3]]))
        })
        .collect()
}

/// Spectral radiance of a blackbody at `kelvin`, per meter of wavelength, at
/// wavelength `lambda_nm` (Planck's law), in W/(sr m^2 m).
pub fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    const H: f64 = 6.626_070_15e-34;
    const C: f64 = 299_792_458.0;
    const K_B: f64 = 1.380_649e-23;
    let l = lambda_nm * 1e-9;
    2.0 * H * C * C / (l.powi(5) * ((H * C / (l * K_B * kelvin)).exp_m1()))
}

/// CIE XYZ of a blackbody at `kelvin`, scaled to Y = 1 (trapezoid rule over
/// the 5 nm CIE 1931 table).
pub fn blackbody_xyz(kelvin: f64) -> [f64; 3] {
    blackbody_xyz_with(&cie_1931_table(), kelvin)
}

fn blackbody_xyz_with(table: &[(f64, [f64; 3])], kelvin: f64) -> [f64; 3] {
    let mut xyz = [0.0f64; 3];
    for (i, (lambda, cmf)) in table.iter().enumerate() {
        let weight = if i == 0 || i + 1 == table.len() { 0.5 } else { 1.0 };
        let b = planck(*lambda, kelvin) * weight;
        for c in 0..3 {
            xyz[c] += b * cmf[c];
        }
    }
    let y = xyz[1];
    if y > 0.0 && y.is_finite() {
        xyz.map(|v| v / y)
    } else {
        [0.0; 3]
    }
}

/// CIE XYZ (D65 white) to linear Rec.709/sRGB primaries.
pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = xyz;
    [
        3.240_454_2 * x - 1.537_138_5 * y - 0.498_531_4 * z,
        -0.969_266_0 * x + 1.876_010_8 * y + 0.041_556_0 * z,
        0.055_643_4 * x - 0.204_025_9 * y + 1.057_225_2 * z,
    ]
}

/// Lowest temperature with a color, in Kelvin; colder is black.
pub const BLACKBODY_MIN_KELVIN: f32 = 400.0;
/// Highest tabulated temperature, in Kelvin; hotter uses this color.
pub const BLACKBODY_MAX_KELVIN: f32 = 40_000.0;
const TABLE_STEP_KELVIN: f32 = 20.0;

/// Linear Rec.709 RGB of a blackbody at `kelvin`, with unit luminance.
/// Channels outside the RGB gamut (blue below about 1900 K) are clipped at 0
/// and the color renormalized to luminance 1.
pub fn blackbody_rgb_exact(kelvin: f64) -> Rgb {
    rgb_from_xyz(blackbody_xyz(kelvin))
}

fn rgb_from_xyz(xyz: [f64; 3]) -> Rgb {
    let rgb = xyz_to_linear_srgb(xyz).map(|v| v.max(0.0));
    let lum = 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
    if lum > 0.0 {
        Rgb::new((rgb[0] / lum) as f32, (rgb[1] / lum) as f32, (rgb[2] / lum) as f32)
    } else {
        Rgb::ZERO
    }
}

/// A table of [`blackbody_rgb_exact`] from 400 K to 40000 K in 20 K steps,
/// interpolated linearly: cheap enough to evaluate per voxel lookup.
#[derive(Clone, Debug)]
pub struct BlackbodyTable {
    rgb: Vec<Rgb>,
}

impl Default for BlackbodyTable {
    fn default() -> Self {
        Self::new()
    }
}

impl BlackbodyTable {
    /// Build the table (about 2000 entries, each an 81-point integral).
    pub fn new() -> BlackbodyTable {
        let cie = cie_1931_table();
        let n = ((BLACKBODY_MAX_KELVIN - BLACKBODY_MIN_KELVIN) / TABLE_STEP_KELVIN) as usize + 1;
        let rgb = (0..n)
            .map(|i| {
                let kelvin = (BLACKBODY_MIN_KELVIN + i as f32 * TABLE_STEP_KELVIN) as f64;
                rgb_from_xyz(blackbody_xyz_with(&cie, kelvin))
            })
            .collect();
        BlackbodyTable { rgb }
    }

    /// Unit-luminance color at `kelvin`: black below 400 K (and for NaN), the
    /// 40000 K color above the table.
    #[inline]
    pub fn rgb(&self, kelvin: f32) -> Rgb {
        if !(kelvin >= BLACKBODY_MIN_KELVIN) {
            return Rgb::ZERO;
        }
        let x = ((kelvin - BLACKBODY_MIN_KELVIN) / TABLE_STEP_KELVIN).min((self.rgb.len() - 1) as f32);
        let i = (x as usize).min(self.rgb.len() - 2);
        let f = x - i as f32;
        self.rgb[i] * (1.0 - f) + self.rgb[i + 1] * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// CIE 1931 chromaticities of Planckian radiators, as published in
    /// Planckian-locus tables (e.g. Wyszecki and Stiles; Wikipedia's
    /// "Planckian locus" lists 6500 K at (0.3135, 0.3236)), to their 4
    /// digits; the 5 nm table truncated at 780 nm is good to a few 1e-4.
    #[test]
    fn blackbody_chromaticity_matches_published_planckian_locus() {
        let published = [
            (1000.0, 0.6528, 0.3444),
            (2000.0, 0.5267, 0.4133),
            (3000.0, 0.4369, 0.4041),
            (4000.0, 0.3805, 0.3768),
            (5000.0, 0.3451, 0.3516),
            (6500.0, 0.3135, 0.3236),
            (10000.0, 0.2807, 0.2884),
        ];
        for (kelvin, x_ref, y_ref) in published {
            let [x, y, z] = blackbody_xyz(kelvin);
            let (cx, cy) = (x / (x + y + z), y / (x + y + z));
            assert!(
                (cx - x_ref).abs() < 1e-3 && (cy - y_ref).abs() < 1e-3,
                "{kelvin} K: ({cx:.4}, {cy:.4}) vs ({x_ref}, {y_ref})"
            );
        }
    }

    #[test]
    fn cie_table_is_complete_and_peaks_at_555_nm() {
        let t = cie_1931_table();
        assert_eq!(t.len(), 81);
        assert_eq!(t[35], (555.0, [0.51205, 1.0, 0.00575]));
    }

    #[test]
    fn blackbody_rgb_has_unit_luminance_and_reddens_as_it_cools() {
        let table = BlackbodyTable::new();
        for k in [1000.0, 1500.0, 3000.0, 6500.0, 12000.0] {
            let c = table.rgb(k);
            assert!((c.luminance() - 1.0).abs() < 2e-3, "{k}: {c:?}");
            let exact = blackbody_rgb_exact(k as f64);
            for ch in 0..3 {
                assert!((c[ch] - exact[ch]).abs() < 1e-2 * exact.max_channel(), "{k}: table {c:?} vs {exact:?}");
            }
        }
        let (warm, white, cool) = (table.rgb(1000.0), table.rgb(6500.0), table.rgb(12000.0));
        assert!(warm.r() > warm.g() && warm.g() > warm.b());
        assert!(cool.b() > cool.r());
        // 6500 K is close to (but not exactly) the D65 white of sRGB.
        assert!((white.r() / white.b() - 1.0).abs() < 0.15, "{white:?}");
        assert_eq!(table.rgb(100.0), Rgb::ZERO);
        assert_eq!(table.rgb(f32::NAN), Rgb::ZERO);
        assert_eq!(table.rgb(1e9), table.rgb(40_000.0));
    }
}
