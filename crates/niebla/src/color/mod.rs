//! Color: linear RGB with Rec.709 primaries, and the sRGB transfer curve.

mod blackbody;
mod rgb;

pub use blackbody::{blackbody_rgb_exact, blackbody_xyz, cie_1931_table, planck, xyz_to_linear_srgb, BlackbodyTable};
pub use rgb::Rgb;

/// sRGB opto-electronic transfer function (IEC 61966-2-1) of a linear value in [0, 1].
pub fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear RGB to an 8-bit sRGB triple: multiplies by `2^exposure`, applies the
/// sRGB curve and clamps to [0, 255]. NaN maps to 0.
pub fn rgb_to_srgb8(c: Rgb, exposure: f32) -> [u8; 3] {
    let k = exposure.exp2();
    let q = |v: f32| {
        let v = if v.is_nan() { 0.0 } else { v * k };
        (linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8
    };
    [q(c.r()), q(c.g()), q(c.b())]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curve_endpoints_and_continuity() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        let a = 12.92 * 0.003_130_8;
        let b = 1.055 * 0.003_130_8f32.powf(1.0 / 2.4) - 0.055;
        assert!((a - b).abs() < 1e-4);
        assert_eq!(rgb_to_srgb8(Rgb::splat(0.5), 1.0), [255, 255, 255]);
        assert_eq!(rgb_to_srgb8(Rgb::splat(f32::NAN), 0.0), [0, 0, 0]);
    }
}
