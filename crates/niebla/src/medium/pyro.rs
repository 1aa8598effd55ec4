//! Emission of the pyro medium (Blender's Principled Volume, as Cycles
//! evaluates it): a flame-modulated emission color plus blackbody radiation
//! of a temperature field, radiance per unit length wherever the density is
//! positive.

use std::sync::Arc;

use crate::color::{BlackbodyTable, Rgb};
use crate::math::Vec3;

use super::GridField;

/// Cycles' blackbody radiance factor: the Stefan-Boltzmann constant
/// (5.670373e-8 W m^-2 K^-4) times 1e-6, over pi, so that
/// `factor * T^4` is the emission strength at `T` Kelvin.
pub const PYRO_STEFAN_BOLTZMANN: f32 = 5.670373e-8 * 1e-6 / std::f32::consts::PI;

/// A piecewise linear color ramp over increasing positions, clamped
/// outside (Blender's Color Ramp node in linear mode).
#[derive(Clone, Debug, PartialEq)]
pub struct ColorRamp {
    /// `(position, color)` stops with increasing positions (at least one).
    pub stops: Vec<(f32, Rgb)>,
}

impl ColorRamp {
    /// The ramp's color at `x`.
    pub fn eval(&self, x: f32) -> Rgb {
        let stops = &self.stops;
        let first = stops[0];
        if !(x > first.0) {
            return first.1;
        }
        for w in stops.windows(2) {
            let ((x0, c0), (x1, c1)) = (w[0], w[1]);
            if x <= x1 {
                let f = (x - x0) / (x1 - x0);
                return c0 * (1.0 - f) + c1 * f;
            }
        }
        stops[stops.len() - 1].1
    }
}

/// The temperature of a pyro medium: `T(x) = scale * grid(x) + offset`
/// Kelvin, or the constant `scale + offset` without a grid.
#[derive(Clone, Debug)]
pub struct PyroTemperature {
    /// Temperature grid placed in the world, if any.
    pub field: Option<GridField>,
    /// Multiplier of the grid (Blender's Temperature), Kelvin per grid unit.
    pub scale: f32,
    /// Kelvin added after the multiplication.
    pub offset: f32,
}

impl PyroTemperature {
    /// Kelvin at world point `p`.
    #[inline]
    pub fn kelvin(&self, p: Vec3) -> f32 {
        match &self.field {
            Some(f) => self.scale * f.eval(p) + self.offset,
            None => self.scale + self.offset,
        }
    }
}

/// The emission terms of a pyro medium (see
/// [`PyroMediumDesc`](crate::scene::desc::PyroMediumDesc) for the mapping).
#[derive(Clone, Debug)]
pub struct PyroEmission {
    /// `emission_strength * emission_color` (radiance per unit length).
    pub emission: Rgb,
    /// Flame grid and the ramp its values go through; `None`: the emission
    /// is constant inside the medium.
    pub flame: Option<(GridField, Option<ColorRamp>)>,
    /// Blackbody intensity in [0, 1]; 0 turns the blackbody term off.
    pub blackbody_intensity: f32,
    /// Blackbody tint.
    pub blackbody_tint: Rgb,
    /// The temperature field.
    pub temperature: PyroTemperature,
    /// Unit-luminance blackbody colors.
    pub table: Arc<BlackbodyTable>,
}

impl PyroEmission {
    /// Emitted radiance per unit length at world point `p` where the density
    /// is `density` (zero where the density is not positive).
    #[inline]
    pub fn l_ve(&self, p: Vec3, density: f32) -> Rgb {
        if !(density > 0.0) {
            return Rgb::ZERO;
        }
        let mut l = match &self.flame {
            None => self.emission,
            Some((field, None)) => self.emission * field.eval(p).max(0.0),
            Some((field, Some(ramp))) => self.emission * ramp.eval(field.eval(p)),
        };
        if self.blackbody_intensity > 0.0 {
            l += self.blackbody(self.temperature.kelvin(p));
        }
        l
    }

    /// The blackbody term at `kelvin` (Cycles: zero for `T <= 0`).
    #[inline]
    pub fn blackbody(&self, kelvin: f32) -> Rgb {
        if !(kelvin > 0.0) {
            return Rgb::ZERO;
        }
        let t4 = (kelvin * kelvin) * (kelvin * kelvin);
        let intensity = PYRO_STEFAN_BOLTZMANN * (1.0 + (t4 - 1.0) * self.blackbody_intensity);
        self.blackbody_tint * self.table.rgb(kelvin) * intensity
    }

    /// Whether the medium emits nothing whatever its grids hold.
    pub fn is_black(&self) -> bool {
        self.emission.is_black() && (self.blackbody_intensity == 0.0 || self.blackbody_tint.is_black())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_interpolates_and_clamps() {
        let ramp = ColorRamp { stops: vec![(0.2, Rgb::ZERO), (0.6, Rgb::new(1.0, 0.5, 0.0))] };
        assert_eq!(ramp.eval(0.0), Rgb::ZERO);
        let mid = ramp.eval(0.4);
        let want = [0.5, 0.25, 0.0];
        assert!((0..3).all(|c| (mid.0[c] - want[c]).abs() < 1e-6), "{mid:?}");
        assert_eq!(ramp.eval(2.0), Rgb::new(1.0, 0.5, 0.0));
        assert_eq!(ramp.eval(f32::NAN), Rgb::ZERO);
    }

    #[test]
    fn blackbody_follows_stefan_boltzmann_times_the_unit_luminance_color() {
        let table = Arc::new(BlackbodyTable::new());
        let e = PyroEmission {
            emission: Rgb::ZERO,
            flame: None,
            blackbody_intensity: 1.0,
            blackbody_tint: Rgb::ONE,
            temperature: PyroTemperature { field: None, scale: 1500.0, offset: 0.0 },
            table: table.clone(),
        };
        let got = e.l_ve(Vec3::ZERO, 1.0);
        let t4 = 1500f64.powi(4);
        let exact = crate::color::blackbody_rgb_exact(1500.0);
        for c in 0..3 {
            let want = 5.670373e-14 / std::f64::consts::PI * t4 * exact.0[c] as f64;
            assert!((got.0[c] as f64 - want).abs() <= 2e-3 * want.max(1e-3), "{c}: {} vs {want}", got.0[c]);
        }
        assert_eq!(e.l_ve(Vec3::ZERO, 0.0), Rgb::ZERO);
    }
}
